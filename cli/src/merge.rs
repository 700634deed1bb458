//! `furnace merge`: adds the films of the parts of a split render into the film of one run.
//!
//! Every part is an EXR written by `furnace render` (`--samples A..B`, or a whole render, or an
//! earlier merge) with its film's exact state (`f64` sums and counts). The merge checks that the
//! parts are of one render — the same identity (`resume::identity`: scene and its content hash,
//! size, sampler, seed, bounces, every option that decides a path) and the same sampler layout —
//! and that they hold disjoint sample ranges; lists the ranges of `0..N` that no part holds
//! (refused unless `--allow-gaps`); then sums the films in order of their first sample and writes
//! the EXR and PNG as `furnace render` does (atomically; nothing is written when a check fails).
//!
//! The merged film is the single run's to the rounding of the `f64` additions
//! (`furnace_render::split::merge_bound`); the counts, the rejected samples and, for a part that
//! starts at sample 0, its sums enter bit for bit. A merge that holds `0..M` of an N-sample render
//! is an ordinary render at M samples per pixel: `furnace render --resume` continues it.

use crate::args::MergeArgs;
use crate::outputs::{Look, check_outputs, denoise_options, write_outputs};
use crate::render::restore;
use crate::resume::{self, SAMPLE_RANGE, SAMPLES, TARGET_SPP};
use furnace_post::{Metadata, read_exr_metadata, read_exr_with_state};
use furnace_render::Film;
use furnace_render::resume::ResumeError;
use furnace_render::split::{Coverage, SampleRange, format_ranges, parse_ranges};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How many parts a merged file was added up from.
pub const PARTS: &str = "furnace.merged_parts";

/// Separates the backends of the parts of a merge in its `furnace.backend` record.
const BACKENDS_SEPARATOR: &str = " + ";

/// One part, from its EXR header.
struct Part {
    path: PathBuf,
    metadata: Metadata,
    width: u32,
    height: u32,
    held: Vec<SampleRange>,
    /// The `--samples` range it was asked to render (`None`: a whole render or a merge).
    requested: Option<SampleRange>,
    /// The whole render's sample count N (`furnace.target_spp`).
    total: u32,
}

impl Part {
    fn read(path: &Path) -> Result<Self, String> {
        let p = path.display();
        let (width, height, metadata) = read_exr_metadata(path).map_err(|e| e.to_string())?;
        let spp = metadata.spp.ok_or_else(|| {
            format!("{p}: no 'furnace.spp' attribute: only EXRs written by `furnace render` can be merged")
        })?;
        let invalid = |key: &str, v: &str| {
            format!("{p}: attribute '{key}' = {} is not a valid value", furnace_post::printable_excerpt(v))
        };
        let total = metadata
            .extra
            .get(TARGET_SPP)
            .ok_or_else(|| format!("{p}: no '{TARGET_SPP}' attribute: not a render furnace can merge"))?;
        let total: u32 = total.parse().ok().filter(|&n| n > 0).ok_or_else(|| invalid(TARGET_SPP, total))?;
        let requested = match metadata.extra.get(SAMPLE_RANGE) {
            Some(v) => Some(v.parse::<SampleRange>().map_err(|_| invalid(SAMPLE_RANGE, v))?),
            None => None,
        };
        let held = match (metadata.extra.get(SAMPLES), requested) {
            (Some(v), _) => {
                let ranges = parse_ranges(v).map_err(|_| invalid(SAMPLES, v))?;
                if ranges.iter().map(|r| u64::from(r.len())).sum::<u64>() != u64::from(spp) {
                    return Err(format!(
                        "{p}: it lists samples {} but says {spp} samples per pixel; it was modified",
                        format_ranges(&ranges)
                    ));
                }
                ranges
            }
            (None, Some(r)) => {
                if spp > r.len() {
                    return Err(format!("{p}: {} samples per pixel in part {r}; it was modified", spp));
                }
                SampleRange::new(r.start, r.start + spp).into_iter().collect()
            }
            (None, None) => SampleRange::new(0, spp).into_iter().collect(),
        };
        if metadata.extra.contains_key(resume::key("noise-threshold")) {
            return Err(format!(
                "{p}: rendered with adaptive sampling (--noise-threshold), whose pixels stop by the samples \
                 before: such a render cannot be split or merged"
            ));
        }
        Ok(Self { path: path.to_path_buf(), metadata, width, height, held, requested, total })
    }

    /// The part's film, checked against its image (`render::restore`) and its header.
    fn film(&self) -> Result<Film, String> {
        let p = self.path.display();
        let file = read_exr_with_state(&self.path).map_err(|e| e.to_string())?;
        if file.state.is_none() {
            return Err(format!(
                "{p}: no furnace film state (furnace.resume.* channels): only EXRs written by `furnace render` \
                 can be merged"
            ));
        }
        if file.metadata != self.metadata {
            return Err(format!("{p}: the file changed while it was being merged"));
        }
        Ok(restore(&self.path, file)?.film)
    }
}

/// Merges `a.parts` into `a.out`.
pub fn run(a: &MergeArgs) -> Result<(), String> {
    if a.denoise && !furnace_denoise::available() {
        // Before any reading: the one line that says how to get it.
        return Err(furnace_denoise::DenoiseError::NotBuilt.to_string());
    }
    let start = Instant::now();
    let (png_path, exr_path) = check_outputs(&a.out, a.denoise)?;
    for part in &a.parts {
        if same_file(part, &exr_path) {
            return Err(format!(
                "{}: the output would replace this part; give another --out",
                part.display()
            ));
        }
    }
    let parts: Vec<Part> = a.parts.iter().map(|p| Part::read(p)).collect::<Result<_, _>>()?;
    check_one_render(&parts)?;

    let total = parts.iter().map(|p| p.total).max().unwrap_or(0);
    let held: Vec<(usize, SampleRange)> =
        parts.iter().enumerate().flat_map(|(i, p)| p.held.iter().map(move |&r| (i, r))).collect();
    let coverage = Coverage::of(&held, total);
    if !coverage.overlaps.is_empty() {
        let list: Vec<String> = coverage
            .overlaps
            .iter()
            .map(|&(i, j, r)| {
                format!("{} and {} both hold samples {r}", parts[i].path.display(), parts[j].path.display())
            })
            .collect();
        return Err(format!("overlapping parts (their samples would count twice): {}", list.join("; ")));
    }
    if coverage.union.is_empty() {
        return Err("the parts hold no samples".into());
    }
    let missing = describe_missing(&parts, &coverage.missing);
    if !missing.is_empty() && !a.allow_gaps {
        return Err(format!(
            "samples missing from the {total}-sample render: {} (--allow-gaps merges what is there)",
            missing.join("; ")
        ));
    }

    // Sum in order of first sample, one part in memory at a time: a part from sample 0 enters
    // the empty film exactly. AOVs only if every part has them (they must average the image's
    // samples).
    let (width, height) = (parts[0].width, parts[0].height);
    let mut order: Vec<&Part> = parts.iter().collect();
    order.sort_by_key(|p| p.held.first().map(|r| r.start));
    let mut film: Option<Film> = None;
    let mut render_time = 0.0;
    for p in &order {
        let part = p.film()?;
        render_time += p.metadata.render_time_s.unwrap_or(0.0);
        let sum = film.get_or_insert_with(|| {
            if part.has_aovs() { Film::with_aovs(width, height) } else { Film::new(width, height) }
        });
        if sum.has_aovs() && !part.has_aovs() {
            if !a.quiet {
                eprintln!("note: {} has no AOVs, so the merge has none", p.path.display());
            }
            let mut plain = Film::new(width, height);
            plain.add_film(sum).map_err(|e| e.to_string())?;
            *sum = plain;
        }
        sum.add_film(&part).map_err(|e| format!("{}: {e}", p.path.display()))?;
    }
    let film = film.ok_or("no part to merge")?;

    let mut metadata = merged_metadata(&parts, &coverage, total);
    metadata.render_time_s = Some(render_time);
    metadata.rejected_samples = Some(film.rejected());
    let tonemap = match a.tonemap {
        Some(t) => t,
        None => parts[0].metadata.extra.get(resume::TONEMAP).and_then(|v| v.parse().ok()).unwrap_or_default(),
    };
    let exposure = match a.exposure {
        Some(x) => x,
        None => parts[0].metadata.extra.get(resume::EXPOSURE).and_then(|v| v.parse().ok()).unwrap_or(0.0),
    };
    // The look recorded is the look written (a resumed merge keeps it).
    metadata.extra.insert(resume::TONEMAP.into(), tonemap.to_string());
    metadata.extra.insert(resume::EXPOSURE.into(), exposure.to_string());
    let look = Look {
        exposure,
        tonemap,
        denoise: a.denoise.then(|| denoise_options(a.denoise_device, false)),
        quiet: a.quiet,
    };
    write_outputs(&film, &metadata, &look, &exr_path, &png_path)?;
    if !a.quiet {
        let held = format_ranges(&coverage.union);
        let per_pixel = coverage.samples();
        eprintln!(
            "merged {} part{}: samples {held} of {total} ({per_pixel} per pixel), {width}×{height}, in {:.2} s",
            parts.len(),
            if parts.len() == 1 { "" } else { "s" },
            start.elapsed().as_secs_f64()
        );
        if !missing.is_empty() {
            eprintln!("warning: missing {}", missing.join("; "));
        }
        if film.rejected() > 0 {
            eprintln!("warning: {} non-finite samples rejected", film.rejected());
        }
        eprintln!("wrote {} and {}", exr_path.display(), png_path.display());
    }
    Ok(())
}

/// `Err` unless every part has the first part's identity and sampler layout.
fn check_one_render(parts: &[Part]) -> Result<(), String> {
    // The resume identity, and the sampler layout the paths were drawn with.
    let identity = |p: &Part| {
        let mut id = resume::identity(&p.metadata, p.width, p.height);
        id.push(("sampler layout", p.metadata.extra.get(resume::SAMPLER_LAYOUT).cloned()));
        id
    };
    let first = &parts[0];
    let id = identity(first);
    for p in &parts[1..] {
        if let Err(ResumeError::Different(differences)) =
            furnace_render::resume::check_same(&id, &identity(p))
        {
            let show = |v: &Option<String>| v.clone().unwrap_or_else(|| "(not recorded)".into());
            let list: Vec<String> = differences
                .iter()
                .map(|d| format!("{} is {} there but {} here", d.setting, show(&d.recorded), show(&d.now)))
                .collect();
            return Err(format!(
                "{}: not a part of the render of {}: {}",
                p.path.display(),
                first.path.display(),
                list.join("; ")
            ));
        }
    }
    Ok(())
}

/// Each missing range, with the part that should hold it (stopped early: how to continue it),
/// if any.
fn describe_missing(parts: &[Part], missing: &[SampleRange]) -> Vec<String> {
    missing
        .iter()
        .map(|m| {
            let owners: Vec<String> = parts
                .iter()
                .filter_map(|p| p.requested.filter(|r| r.overlaps(m)).map(|r| (p, r)))
                .map(|(p, r)| {
                    let at = p.held.last().map_or(r.start, |h| h.end);
                    format!(
                        "part {} ({r}) stopped at sample {at}: continue it with `furnace render --resume {}`",
                        p.path.display(),
                        p.path.display()
                    )
                })
                .collect();
            if owners.is_empty() {
                format!("samples {m} (no part renders them)")
            } else {
                format!("samples {m} ({})", owners.join(", "))
            }
        })
        .collect()
}

/// The merged file's record: the first part's settings, with the samples held and every
/// part's backend.
fn merged_metadata(parts: &[Part], coverage: &Coverage, total: u32) -> Metadata {
    let mut m = parts[0].metadata.clone();
    let held = coverage.samples();
    m.spp = Some(u32::try_from(held).unwrap_or(u32::MAX));
    m.extra.remove(SAMPLE_RANGE);
    m.extra.remove(SAMPLES);
    m.extra.insert(TARGET_SPP.into(), total.to_string());
    m.extra.insert(PARTS.into(), parts.len().to_string());
    let mut backends: Vec<String> = Vec::new();
    for b in parts.iter().filter_map(|p| p.metadata.extra.get(resume::BACKEND)) {
        for one in b.split(BACKENDS_SEPARATOR) {
            if !backends.iter().any(|x| x == one) {
                backends.push(one.to_string());
            }
        }
    }
    if !backends.is_empty() {
        m.extra.insert(resume::BACKEND.into(), backends.join(BACKENDS_SEPARATOR));
    }
    // One range from 0: an ordinary render of `held` samples (resumable up to N). One range from
    // the start of the parts' requested ranges, if they form one range: a part of that range
    // (resumable up to its end). Otherwise the list of what it holds.
    let requested: Vec<(usize, SampleRange)> =
        parts.iter().enumerate().filter_map(|(i, p)| p.requested.map(|r| (i, r))).collect();
    let requested_union = Coverage::of(&requested, 0).union;
    match (coverage.union.as_slice(), requested_union.as_slice()) {
        ([one], _) if one.start == 0 => {}
        ([one], [asked]) if asked.start == one.start && asked.end >= one.end => {
            m.extra.insert(SAMPLE_RANGE.into(), asked.to_string());
        }
        _ => {
            m.extra.insert(SAMPLES.into(), format_ranges(&coverage.union));
        }
    }
    m
}

/// Whether `a` and `b` name the same file (both existing and the same inode, or the same path).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}
