//! `furnace render`: load, render in passes with a progress bar, write EXR + PNG.

use crate::args::{MAX_SIDE, RenderArgs, Switch};
use furnace_brdf::SpecularOptions;
use furnace_cpu::{RenderSettings, Renderer};
use furnace_post::{Metadata, to_srgb8, write_exr, write_png};
use furnace_scene::{Projection, Scene, builtin};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Default image width (and height for a square camera such as the built-in Cornell box's).
pub const DEFAULT_WIDTH: u32 = 512;

/// Largest number of pixels accepted (8192² — 2 GiB of `f64` film).
const MAX_PIXELS: u64 = 1 << 26;

/// Samples per pixel per pass: at most 4, and about 2¹⁸ samples per pass (a fifth of a second
/// on two cores), so the progress bar moves and `--time-limit` stops promptly.
fn pass_spp(pixels: u64) -> u32 {
    (262_144 / pixels.max(1)).clamp(1, 4) as u32
}

pub fn run(a: &RenderArgs) -> Result<(), String> {
    let (png_path, exr_path) = output_paths(&a.out);
    let scene = load_scene(a.scene.as_deref())?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    let (width, height) = image_size(&scene, a.width, a.height)?;
    let settings = RenderSettings {
        width,
        height,
        bounces: a.bounces,
        sampler: a.sampler,
        seed: a.seed,
        sample_count: a.sampler.needs_sample_count().then_some(a.spp),
        specular: SpecularOptions {
            masking: a.masking.into(),
            sampling: a.specular_sampling.into(),
            compensation: a.compensation == Switch::On,
        },
        russian_roulette: false,
    };
    if a.sampler.needs_sample_count() && a.time_limit.is_some() {
        eprintln!(
            "warning: the {} sampler builds one pattern of N = {} samples per pixel; if --time-limit \
             stops the render before N, the partial pattern is poorly stratified (prefer sobol or pmj02)",
            a.sampler, a.spp
        );
    }
    let scene_name = scene.name.clone();
    let renderer = Renderer::new(scene, settings).map_err(|e| e.to_string())?;

    let pixels = u64::from(width) * u64::from(height);
    let progress = progress_bar(a.quiet, a.spp);
    let start = Instant::now();
    let mut film = renderer.new_film();
    let mut done = 0u32;
    while done < a.spp {
        if let Some(limit) = a.time_limit
            && done > 0
        {
            // Stop before a pass that would, at the mean pass time so far, end past the limit.
            let elapsed = start.elapsed().as_secs_f64();
            let passes = f64::from(done) / f64::from(pass_spp(pixels));
            if elapsed + elapsed / passes.max(1.0) > limit {
                break;
            }
        }
        let n = pass_spp(pixels).min(a.spp - done);
        renderer.render_pass(&mut film, done, n).map_err(|e| e.to_string())?;
        done += n;
        progress.set_position(u64::from(done));
        let rate = (pixels * u64::from(done)) as f64 / start.elapsed().as_secs_f64().max(1e-9);
        progress.set_message(format!("{:.2} Msamples/s", rate / 1e6));
    }
    let seconds = start.elapsed().as_secs_f64();
    progress.finish_and_clear();

    let radiance: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
    let metadata = Metadata {
        spp: Some(done),
        sampler: Some(a.sampler.to_string()),
        bounces: Some(a.bounces),
        seed: Some(u64::from(a.seed)),
        scene: Some(scene_name.clone()),
        render_time_s: Some(seconds),
        rejected_samples: Some(film.rejected()),
        extra: [
            ("furnace.tonemap", a.tonemap.to_string()),
            ("furnace.exposure_ev", a.exposure.to_string()),
            ("furnace.masking", format!("{:?}", settings.specular.masking)),
            ("furnace.specular_sampling", format!("{:?}", settings.specular.sampling)),
            ("furnace.compensation", settings.specular.compensation.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
    };
    write_exr(&exr_path, width, height, &radiance, &metadata).map_err(|e| e.to_string())?;
    let srgb = to_srgb8(&radiance, a.exposure, a.tonemap);
    write_png(&png_path, width, height, &srgb).map_err(|e| e.to_string())?;

    if !a.quiet {
        let rate = (pixels * u64::from(done)) as f64 / seconds.max(1e-9) / 1e6;
        let stopped =
            if done < a.spp { format!(" (stopped by --time-limit; asked {})", a.spp) } else { String::new() };
        eprintln!(
            "{scene_name}: {width}×{height}, {done} spp{stopped}, {} bounces, {} sampler: {seconds:.2} s ({rate:.2} Msamples/s)",
            a.bounces, a.sampler
        );
        if film.rejected() > 0 {
            eprintln!("warning: {} non-finite samples rejected", film.rejected());
        }
        eprintln!("wrote {} and {}", exr_path.display(), png_path.display());
    }
    Ok(())
}

fn load_scene(path: Option<&Path>) -> Result<Scene, String> {
    match path {
        Some(p) => Scene::load(p).map_err(|e| e.to_string()),
        None => builtin::cornell_box().map_err(|e| e.to_string()),
    }
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

/// The image size: given sides win; a missing side follows the camera's aspect ratio (the
/// file's `aspectRatio`, or `xmag/ymag` of an orthographic camera; square without one).
fn image_size(scene: &Scene, width: Option<u32>, height: Option<u32>) -> Result<(u32, u32), String> {
    let aspect = match scene.default_camera().projection {
        Projection::Perspective { aspect_ratio, .. } => aspect_ratio.unwrap_or(1.0),
        Projection::Orthographic { xmag, ymag } => xmag / ymag,
    };
    let aspect = if aspect.is_finite() && aspect > 0.0 { f64::from(aspect) } else { 1.0 };
    let side = |x: f64| x.round().clamp(1.0, f64::from(MAX_SIDE)) as u32;
    let (w, h) = match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, side(f64::from(w) / aspect)),
        (None, Some(h)) => (side(f64::from(h) * aspect), h),
        (None, None) => (DEFAULT_WIDTH, side(f64::from(DEFAULT_WIDTH) / aspect)),
    };
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(format!("a {w}×{h} image is too large (at most {MAX_PIXELS} pixels)"));
    }
    Ok((w, h))
}

fn progress_bar(quiet: bool, spp: u32) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(u64::from(spp));
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:40.cyan/blue}] {pos}/{len} spp  {msg}  ETA {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
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

    #[test]
    fn passes_are_one_to_four_spp() {
        assert_eq!(pass_spp(512 * 512), 1);
        assert_eq!(pass_spp(32 * 32), 4);
        assert_eq!(pass_spp(0), 4);
    }

    #[test]
    fn cornell_box_defaults_to_512_square() {
        let scene = builtin::cornell_box().unwrap();
        assert_eq!(image_size(&scene, None, None).unwrap(), (512, 512));
        assert_eq!(image_size(&scene, Some(64), None).unwrap(), (64, 64));
        assert!(image_size(&scene, Some(16_384), Some(16_384)).is_err());
    }
}
