//! Chi-square tests of the warps through the public API: each hemisphere warp against its own
//! pdf, and the concentric disk lifted to the hemisphere by Malley's method.
//!
//! Every test draws 10⁶ samples from a fixed seed, at a family-wise significance of 1% with
//! the Šidák correction over the [`TESTS`] tests of this file. On failure the report is printed
//! and the tables are written to `target/test-output/chi2/<name>.{txt,csv,ppm}`.

use furnace_sampling::warp::{
    concentric_disk_pdf, cosine_hemisphere_pdf, square_to_concentric_disk, square_to_cosine_hemisphere,
    square_to_uniform_hemisphere, uniform_hemisphere_pdf,
};
use furnace_tests::chi2::{ChiSquareResult, ChiSquareTest};
use glam::{Vec2, Vec3};
use std::path::PathBuf;

/// Number of chi-square tests in this file (the Šidák family).
const TESTS: usize = 4;

/// The harness as every test here uses it; only the seed differs.
fn harness(seed: u32) -> ChiSquareTest {
    ChiSquareTest {
        sample_count: 1_000_000,
        significance: 0.01,
        test_count: TESTS,
        seed,
        ..ChiSquareTest::default()
    }
}

/// `target/test-output/chi2` of the workspace.
fn output_dir() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(&manifest).join("target/test-output/chi2")
}

/// Passes, or writes the tables and fails with the report.
fn check(name: &str, result: &ChiSquareResult) {
    result.assert_passed(name, &output_dir());
}

/// Malley's method: a point of the unit disk lifted to the hemisphere, `z = √(1 − x² − y²)`.
fn lift(p: Vec2) -> Vec3 {
    Vec3::new(p.x, p.y, (1.0 - p.length_squared()).max(0.0).sqrt())
}

#[test]
fn chi2_uniform_hemisphere() {
    let result = harness(11).run(|u, _| Some(square_to_uniform_hemisphere(u)), uniform_hemisphere_pdf);
    check("uniform_hemisphere", &result);
}

#[test]
fn chi2_cosine_hemisphere() {
    let result = harness(12).run(|u, _| Some(square_to_cosine_hemisphere(u)), cosine_hemisphere_pdf);
    check("cosine_hemisphere", &result);
}

/// A uniform disk lifted to the hemisphere is cosine-distributed (Malley), so the concentric
/// disk is tested against [`cosine_hemisphere_pdf`].
#[test]
fn chi2_concentric_disk_lifted_against_cosine_pdf() {
    let result = harness(13).run(|u, _| Some(lift(square_to_concentric_disk(u))), cosine_hemisphere_pdf);
    check("concentric_disk_malley", &result);
}

/// The same lifted samples against the disk's own area pdf, converted to solid angle: the
/// projection `ω ↦ (x, y)` has `dA = cos θ dω`, so `p_ω(ω) = p_A(x, y) · cos θ`. This checks
/// [`concentric_disk_pdf`] itself, not just the sampler.
#[test]
fn chi2_concentric_disk_lifted_against_disk_pdf() {
    let result = harness(14).run(
        |u, _| Some(lift(square_to_concentric_disk(u))),
        |w| {
            if w.z > 0.0 { concentric_disk_pdf(Vec2::new(w.x, w.y)) * w.z } else { 0.0 }
        },
    );
    check("concentric_disk_area_pdf", &result);
}
