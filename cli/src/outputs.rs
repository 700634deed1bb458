//! What `render`, `view` and `merge` write: the output paths of `--out`, checked before
//! rendering; the EXR (image, metadata, resume state) and PNG written together; denoising.

use crate::args::RenderArgs;
use furnace_post::{ExtraChannel, Metadata, Tonemap, stage_exr_with_state_and, stage_png, to_srgb8};
use furnace_render::Film;
use glam::Vec3;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// How [`write_outputs`] writes a film: the PNG's look, and whether to denoise.
pub(crate) struct Look {
    /// Exposure in stops.
    pub exposure: f32,
    /// The PNG's tone map.
    pub tonemap: Tonemap,
    /// Open Image Denoise's options when the image is denoised too (`PATH.denoised.png` and the
    /// EXR's `denoised.*` layer).
    pub denoise: Option<furnace_denoise::Options>,
    /// No messages but warnings.
    pub quiet: bool,
}

impl Look {
    /// What `render`'s arguments ask for.
    pub(crate) fn of(a: &RenderArgs) -> Self {
        Self {
            exposure: a.exposure,
            tonemap: a.tonemap,
            denoise: a.denoise.then(|| denoise_options(a.denoise_device, a.denoise_prefilter)),
            quiet: a.quiet,
        }
    }
}

/// Open Image Denoise's options for `--denoise-device` and `--denoise-prefilter`.
pub(crate) fn denoise_options(
    device: furnace_denoise::DeviceKind,
    prefilter_guides: bool,
) -> furnace_denoise::Options {
    furnace_denoise::Options { device, prefilter_guides, ..furnace_denoise::Options::default() }
}

/// Writes the EXR (RGB, metadata and the resume state) and the tone-mapped PNG, each atomically.
pub(crate) fn write_outputs(
    film: &Film,
    metadata: &Metadata,
    a: &Look,
    exr_path: &Path,
    png_path: &Path,
) -> Result<(), String> {
    let (width, height) = (film.width(), film.height());
    let radiance: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
    let denoised = match &a.denoise {
        Some(options) => Some(denoise(film, &radiance, options, a.quiet)?),
        None => None,
    };
    let extra: Vec<ExtraChannel> = denoised
        .iter()
        .flat_map(|d| {
            (0..3).map(|c| ExtraChannel {
                name: format!("denoised.{}", ["R", "G", "B"][c]),
                values: d.iter().map(|p| p[c]).collect(),
            })
        })
        .collect();
    // Every file is written to its temporary name first and renamed into place only once all
    // were written: a failure leaves every earlier output as it was (a failed PNG does not leave
    // a new EXR beside the old PNG). The EXR, the render's record, is renamed last.
    let exr = stage_exr_with_state_and(exr_path, film, metadata, &extra).map_err(|e| e.to_string())?;
    let srgb = to_srgb8(&radiance, a.exposure, a.tonemap);
    let png = stage_png(png_path, width, height, &srgb).map_err(|e| e.to_string())?;
    let denoised_png = match &denoised {
        Some(d) => {
            let path = denoised_png_path(png_path);
            Some(
                stage_png(&path, width, height, &to_srgb8(d, a.exposure, a.tonemap))
                    .map_err(|e| e.to_string())?,
            )
        }
        None => None,
    };
    png.commit().map_err(|e| e.to_string())?;
    if let Some(staged) = denoised_png {
        let path = staged.target().to_path_buf();
        staged.commit().map_err(|e| e.to_string())?;
        if !a.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    exr.commit().map_err(|e| e.to_string())
}

/// Checks, before anything is rendered, that `--out PATH` (`out`) names files that can be
/// written: `PATH` must end in a file name (not a separator, `.` or `..`, and not only an
/// extension such as `.exr`) and not be a directory, the outputs must not be directories, and
/// their directory must take a new file (one is created there and removed). Removes the
/// temporary files that a furnace killed while writing these outputs left behind, with a note.
/// `denoise`: the denoised PNG is an output too. Returns the PNG and EXR paths
/// ([`output_paths`]).
///
/// `--out DIR/` is refused rather than read as `DIR/furnace`: a trailing separator is easy to
/// type by accident (shell completion adds it), and a file name made up by furnace is one the
/// user would then have to find; the message says what to give.
pub(crate) fn check_outputs(out: &Path, denoise: bool) -> Result<(PathBuf, PathBuf), String> {
    let text = out.as_os_str().to_string_lossy();
    let last = text.rsplit(['/', std::path::MAIN_SEPARATOR]).next().unwrap_or_default();
    let example = || {
        let dir = out.to_string_lossy();
        let dir = dir.trim_end_matches(['/', std::path::MAIN_SEPARATOR]);
        if dir.is_empty() { "furnace".to_string() } else { format!("{dir}/furnace") }
    };
    let why = if text.is_empty() {
        Some("is empty")
    } else if matches!(last, "" | "." | "..") {
        Some("names a directory, not a file")
    } else if out.is_dir() {
        Some("is a directory")
    } else if matches!(last.to_ascii_lowercase().as_str(), ".png" | ".exr") {
        Some("has no file name before its extension")
    } else {
        None
    };
    if let Some(why) = why {
        let example = example();
        return Err(format!(
            "--out '{}' {why}: give a file path without extension, such as --out {example} (writes \
             {example}.exr and {example}.png)",
            out.display()
        ));
    }
    let (png_path, exr_path) = output_paths(out);
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        return Err(format!(
            "{}: the directory {} does not exist (--out '{}')",
            exr_path.display(),
            dir.display(),
            out.display()
        ));
    }
    let mut outputs = vec![exr_path.clone(), png_path.clone()];
    if denoise {
        outputs.push(denoised_png_path(&png_path));
    }
    for path in &outputs {
        if path.is_dir() {
            return Err(format!("{}: an output of --out '{}' is a directory", path.display(), out.display()));
        }
        for stale in furnace_post::remove_stale_temporaries(path).map_err(|e| e.to_string())? {
            eprintln!(
                "note: removed {}, a temporary file left by a furnace that was stopped while writing {}",
                stale.display(),
                path.display()
            );
        }
    }
    // A file created and removed beside the outputs: the directory exists and takes new files.
    drop(
        furnace_post::stage(&exr_path, |_| Ok(()))
            .map_err(|e| format!("cannot write the outputs of --out '{}': {e}", out.display()))?,
    );
    Ok((png_path, exr_path))
}

/// `PATH.png` → `PATH.denoised.png`.
pub(crate) fn denoised_png_path(png: &Path) -> PathBuf {
    png.with_extension("denoised.png")
}

/// The film's image (`radiance`, its means) denoised by Open Image Denoise, with the film's
/// albedo and normal as guides when it has AOVs, the colour alone otherwise: what `render
/// --denoise` and `chart --denoise` run.
pub(crate) fn denoise_film(
    film: &Film,
    radiance: &[Vec3],
    options: &furnace_denoise::Options,
) -> Result<furnace_denoise::Denoised, furnace_denoise::DenoiseError> {
    let images = film.aov_images();
    let guides = furnace_denoise::Guides {
        albedo: images.as_ref().map(|i| i.albedo.as_slice()),
        normal: images.as_ref().map(|i| i.normal.as_slice()),
    };
    furnace_denoise::denoise(film.width(), film.height(), radiance, guides, options)
}

/// [`denoise_film`] with messages (a film without AOVs is denoised without guides, said in a
/// note).
fn denoise(
    film: &Film,
    radiance: &[Vec3],
    options: &furnace_denoise::Options,
    quiet: bool,
) -> Result<Vec<Vec3>, String> {
    if !film.has_aovs() {
        eprintln!("note: the film has no AOVs (it was rendered without them): denoising without guides");
    }
    let d = denoise_film(film, radiance, options).map_err(|e| format!("denoising: {e}"))?;
    if !quiet {
        eprintln!("denoised on {} in {:.2} s", d.device, d.seconds);
    }
    if d.non_finite.total() > 0 {
        eprintln!(
            "warning: denoising: {} non-finite input values replaced by their neighbours' mean",
            d.non_finite.total()
        );
    }
    Ok(d.pixels)
}

/// `--out PATH`: `PATH.png` and `PATH.exr`; a `.png` / `.exr` extension (any case) is dropped
/// first, any other is kept (`render.v2` → `render.v2.png`).
pub fn output_paths(out: &Path) -> (PathBuf, PathBuf) {
    let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let base = match ext.as_deref() {
        Some("png" | "exr") => out.with_extension(""),
        _ => out.to_path_buf(),
    };
    let with = |e: &str| {
        let mut s: OsString = base.clone().into_os_string();
        s.push(e);
        PathBuf::from(s)
    };
    (with(".png"), with(".exr"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_paths_derive_both_files() {
        let p = |s: &str| {
            let (png, exr) = output_paths(Path::new(s));
            (png.display().to_string(), exr.display().to_string())
        };
        assert_eq!(p("furnace"), ("furnace.png".into(), "furnace.exr".into()));
        assert_eq!(p("out/x.png"), ("out/x.png".into(), "out/x.exr".into()));
        assert_eq!(p("x.EXR"), ("x.png".into(), "x.exr".into()));
        assert_eq!(p("render.v2"), ("render.v2.png".into(), "render.v2.exr".into()));
    }
}
