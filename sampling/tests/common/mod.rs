//! Shared helpers for the statistical tests: integrands, error measurement, slope fits and
//! the tables a human needs to see when a test fails.
#![allow(dead_code)] // each test file uses a different subset

use furnace_sampling::Sampler;
use std::fmt::Write as _;
use std::path::PathBuf;

/// A smooth integrand on [0,1)²: exp(−x² − y²). Integral (∫₀¹ e^(−t²) dt)², with
/// ∫₀¹ e^(−t²) dt = √π/2 · erf(1) = 0.746824132812427.
pub fn smooth(x: f64, y: f64) -> f64 {
    (-x * x - y * y).exp()
}
/// Exact integral of [`smooth`].
pub const SMOOTH_INTEGRAL: f64 = 0.746_824_132_812_427 * 0.746_824_132_812_427;

/// A discontinuous integrand: the quarter disk x² + y² < 2/π, of area exactly 1/2
/// (Christensen et al. 2018's "disk" test function).
pub fn disk(x: f64, y: f64) -> f64 {
    if x * x + y * y < 2.0 / std::f64::consts::PI { 1.0 } else { 0.0 }
}
/// Exact integral of [`disk`].
pub const DISK_INTEGRAL: f64 = 0.5;

/// Per-pixel estimates of the integral of `f` with samples `first .. first + count` of
/// dimensions `(dim, dim+1)`, for `pixels` pixels.
pub fn estimates(
    sampler: &dyn Sampler,
    f: fn(f64, f64) -> f64,
    pixels: u32,
    first: u32,
    count: u32,
    dim: u32,
) -> Vec<f64> {
    (0..pixels)
        .map(|p| {
            let sum: f64 = (first..first + count)
                .map(|i| {
                    let [x, y] = sampler.value_2d(p, i, dim);
                    f(x as f64, y as f64)
                })
                .sum();
            sum / count as f64
        })
        .collect()
}

/// Root-mean-square error of `estimates` against `exact`.
pub fn rmse(estimates: &[f64], exact: f64) -> f64 {
    (estimates.iter().map(|e| (e - exact).powi(2)).sum::<f64>() / estimates.len() as f64).sqrt()
}

/// Least-squares slope of log(y) against log(x).
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let lx: Vec<f64> = x.iter().map(|v| v.ln()).collect();
    let ly: Vec<f64> = y.iter().map(|v| v.ln()).collect();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// Writes `text` to `target/test-output/<name>` (created if needed) and returns the path, so
/// that a failing test can point a human at its table.
pub fn write_output(name: &str, text: &str) -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = manifest.parent().unwrap_or(&manifest).join("target/test-output/sampling");
    std::fs::create_dir_all(&dir).expect("create target/test-output/sampling");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test output");
    path
}

/// Formats rows of numbers as a Markdown table.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}
