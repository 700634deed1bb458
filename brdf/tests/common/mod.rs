//! Shared helpers of the brdf integration tests (each test binary uses some of them).
#![allow(dead_code)]

use std::path::PathBuf;

/// Writes `text` to `target/test-output/brdf/<name>` (created if needed) and returns the path,
/// so that a test can point a human at its table.
pub fn write_output(name: &str, text: &str) -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = manifest.parent().unwrap_or(&manifest).join("target/test-output/brdf");
    std::fs::create_dir_all(&dir).expect("create target/test-output/brdf");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test output");
    path
}

/// The worst `error / tolerance` seen in a group, with the input that produced it.
#[derive(Default)]
pub struct Worst {
    pub ratio: f32,
    pub what: String,
}

impl Worst {
    /// Records `error / tolerance` (NaN counts as the worst).
    pub fn record(&mut self, error: f32, tolerance: f32, what: impl FnOnce() -> String) {
        let ratio = error / tolerance;
        if ratio > self.ratio || ratio.is_nan() {
            self.ratio = ratio;
            self.what = what();
        }
    }

    /// Appends a failure to `failures` if the worst ratio exceeds 1 (or is NaN).
    pub fn check(&self, label: &str, failures: &mut Vec<String>) {
        if !(self.ratio <= 1.0) {
            failures.push(format!("{label}: error {:.3}x its tolerance at {}", self.ratio, self.what));
        }
    }
}

/// The unit direction of polar angle `theta_deg` and azimuth `phi_deg` (degrees) in the
/// shading frame.
pub fn dir(theta_deg: f32, phi_deg: f32) -> glam::Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    glam::Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// Whether a sample's bookkeeping holds: its pdf is what `pdf` gives for its direction and its
/// weight times its pdf is `eval` (where `eval` is not 0), each within `tolerance` relative.
pub fn sample_is_consistent(
    sample_pdf: f32,
    weight: glam::Vec3,
    pdf: f32,
    eval: glam::Vec3,
    tolerance: f32,
) -> bool {
    let rel = |a: f32, b: f32| (a - b).abs() / b.abs().max(1e-20);
    let w_err = (0..3).map(|c| rel(weight[c] * sample_pdf, eval[c])).fold(0.0, f32::max);
    rel(sample_pdf, pdf) < tolerance && (eval.max_element() == 0.0 || w_err < tolerance)
}

/// A direction pair ((θo, φo), (θi, φi)) in degrees.
pub type DirectionPair = ((f32, f32), (f32, f32));

/// `HitBsdf::eval` of each of `materials` at each of `pairs` ((θo, φo), (θi, φi) in degrees)
/// against `oracle`'s values (the same order): the worst relative error over the channels,
/// and a Markdown table of every value for a human.
pub fn eval_against_oracle(
    materials: &[(&str, furnace_brdf::LayeredParams)],
    pairs: &[DirectionPair],
    oracle: &[&[[f64; 3]]],
    options: furnace_brdf::SpecularOptions,
) -> (f64, String) {
    use std::fmt::Write as _;
    let mut report =
        String::from("| material | pair | furnace | oracle | relative error |\n|---|---|---|---|---|\n");
    let mut worst = 0.0f64;
    for ((name, params), expected) in materials.iter().zip(oracle) {
        let bsdf = furnace_brdf::HitBsdf::new(params, options);
        for (&(o, i), want) in pairs.iter().zip(expected.iter()) {
            let got = bsdf.eval(dir(o.0, o.1), dir(i.0, i.1));
            let err = (0..3)
                .map(|c| (got[c] as f64 - want[c]).abs() / want[c].abs().max(1e-12))
                .fold(0.0, f64::max);
            worst = worst.max(err);
            let _ = writeln!(report, "| {name} | {o:?} → {i:?} | {got:?} | {want:?} | {err:.2e} |");
        }
    }
    (worst, report)
}

/// The directional albedo of `bsdf` at `wo` by `n` samples (the largest channel of each
/// weight; a failed sample weighs 0) drawn from `rng` (u, then uc), and the standard error of
/// that mean.
pub fn sampled_albedo(
    bsdf: &furnace_brdf::HitBsdf,
    wo: glam::Vec3,
    rng: &mut furnace_tests::Rng,
    n: usize,
) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let u = glam::Vec2::new(rng.f32(), rng.f32());
        let uc = rng.f32();
        let w = bsdf.sample(wo, u, || uc).map_or(0.0, |s| f64::from(s.weight.max_element()));
        sum += w;
        sum2 += w * w;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}
