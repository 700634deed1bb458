//! `furnace compare`: score a candidate render against a reference with the metrics of
//! `furnace_post::metrics` (RMSE, relative MSE with ε = 1e-2, mean ratio, z-scores — the
//! statistics of the comparison script that scored the Mitsuba references), print them, and
//! write an error map.

use crate::args::CompareArgs;
use furnace_post::metrics::{Scores, error_map, score};
use furnace_post::{Tonemap, read_exr, to_srgb8, write_png};
use glam::Vec3;
use std::path::Path;

/// The report printed by `furnace compare`.
pub fn report(s: &Scores, z_with_candidate: bool) -> String {
    let mut out = String::new();
    let mut line = |k: &str, v: String| out.push_str(&format!("{k:<16}{v}\n"));
    line("RMSE", format!("{:.6e}", s.rmse));
    line("relative MSE", format!("{:.6e}", s.rel_mse));
    let [r, g, b] = s.mean_ratio;
    line("mean ratio", format!("R {r:.6}  G {g:.6}  B {b:.6}  (candidate / reference)"));
    line("nonfinite", format!("{} candidate values", s.nonfinite));
    if let Some(z) = s.z {
        let with = if z_with_candidate {
            "reference and candidate stderr"
        } else {
            "reference stderr only: right when the candidate has far more samples"
        };
        line("z mean", format!("{:.6}  ({with})", z.mean));
        line("z std", format!("{:.6}", z.std));
        line("|z| > 3", format!("{:.6}  (Gaussian: 0.0027)", z.frac_gt3));
        line("|z| > 4", format!("{:.6}  (Gaussian: 0.000063)", z.frac_gt4));
    }
    out
}

fn load(path: &Path) -> Result<(u32, u32, Vec<Vec3>), String> {
    let (w, h, px, _) = read_exr(path).map_err(|e| e.to_string())?;
    Ok((w, h, px))
}

/// Loads `path` and checks that it is `w`×`h` like `like`.
fn load_same_size(path: &Path, like: &Path, (w, h): (u32, u32)) -> Result<Vec<Vec3>, String> {
    let (pw, ph, px) = load(path)?;
    if (pw, ph) != (w, h) {
        return Err(format!(
            "size mismatch: {} is {pw}×{ph} but {} is {w}×{h}",
            path.display(),
            like.display()
        ));
    }
    Ok(px)
}

pub fn run(a: &CompareArgs) -> Result<(), String> {
    let (w, h, cand) = load(&a.candidate)?;
    let reference = load_same_size(&a.reference, &a.candidate, (w, h))?;
    let sref = a.stderr.as_deref().map(|p| load_same_size(p, &a.reference, (w, h))).transpose()?;
    let scand = a.candidate_stderr.as_deref().map(|p| load_same_size(p, &a.candidate, (w, h))).transpose()?;
    let scores = score(&cand, &reference, sref.as_deref(), scand.as_deref()).map_err(|e| e.to_string())?;
    let mut text = format!(
        "candidate       {} ({w}×{h})\nreference       {}\n{}",
        a.candidate.display(),
        a.reference.display(),
        report(&scores, scand.is_some())
    );
    if let Some(path) = &a.error_map {
        let map = to_srgb8(&error_map(&cand, &reference), 0.0, Tonemap::Clamp);
        write_png(path, w, h, &map).map_err(|e| e.to_string())?;
        text.push_str(&format!("wrote           {}\n", path.display()));
    }
    emit(&text)
}

/// Writes `text` to stdout; a reader that closed the pipe early (`furnace compare … | head`) is
/// not an error (`println!` would panic there).
fn emit(text: &str) -> Result<(), String> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("writing the report: {e}")),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_names_every_statistic() {
        let s = score(&[Vec3::ONE], &[Vec3::ONE], Some(&[Vec3::ONE]), None).unwrap();
        let text = report(&s, false);
        for key in ["RMSE", "relative MSE", "mean ratio", "nonfinite", "z mean", "z std", "|z| > 3"] {
            assert!(text.contains(key), "{key}: {text}");
        }
    }
}
