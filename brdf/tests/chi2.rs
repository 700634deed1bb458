//! Chi-square tests of every sampling routine of `furnace-brdf` against its own pdf: does
//! `Bsdf::sample` draw directions with the density that `Bsdf::pdf` claims?
//!
//! This is the BSDF test of Mitsuba 3 and pbrt-v4, run by the shared harness
//! [`furnace_tests::chi2`]: 10⁶ samples per configuration are histogrammed on the harness's
//! 64 (cos θ) × 128 (φ) grid and compared with the pdf integrated over every cell; cells
//! expecting fewer than 5 samples are pooled; rejected samples (`None`, a microfacet reflection
//! below the horizon or a back-facing NDF normal) go to the harness's rejection cell, which
//! expects the pdf mass missing from the sphere; a sample where the pdf is 0 fails outright.
//!
//! The matrix is the table of lobes [`LOBES`] (`furnace_tests::lobes`), which the consistency,
//! white-furnace and GPU parity tests iterate too: each row's `chi2` gives its configurations
//! (Lambert; GGX for every sampling method and α from 0.02 to 1; four glTF materials), their
//! view angles (down to 89°) and its first seed, so a new lobe adds a row there.
//!
//! **Significance.** Every configuration is one test of the family ([`family_size`]); each must
//! reach the Šidák-corrected p-value `1 − 0.99^(1/N)` for a family of N, so the chance that any of them fails
//! for a correct sampler is 1%. Seeds are fixed, so the outcome is deterministic.
//!
//! **Sharp lobes.** At α = 0.02 the GGX lobe (≈ 2° wide, and at normal incidence a ring of
//! `1 − cos θ ≈ 10⁻³` inside the top row of cells) is far narrower than a cell; the old fixed
//! 5 × 5 Gauss–Legendre rule per cell integrates the lobe at 89° to 0.27 (0.57 when the lobe
//! happens to straddle a cell edge) instead of 0.97. The harness integrates every cell
//! adaptively, to its default relative tolerance of 10⁻⁴ (see `furnace_tests::chi2`,
//! "Adaptive quadrature": this biases χ² by about 0.01), and these tests additionally require
//! that every cell converged, so the expected counts are as good as the tolerance says for
//! every configuration here. (At 89° the pdf's own `f32` rounding is a few 10⁻⁵, so a much
//! tighter tolerance could not converge.)
//!
//! One test runs every configuration of every row, the configurations in parallel.
//! On failure every failing configuration's report is printed and its tables are written to
//! `target/test-output/chi2-brdf/<name>.{txt,csv,ppm}`. Run with `--nocapture` to see the
//! p-value of every configuration.

use furnace_brdf::{Bsdf, GgxSpecular, SpecularOptions, SpecularSampling};
use furnace_tests::chi2::{ChiSquareResult, ChiSquareTest};
use furnace_tests::lobes::LOBES;
use glam::Vec3;
use std::path::PathBuf;

/// Number of chi-square tests of the table: the Šidák family.
fn family_size() -> usize {
    LOBES.iter().map(|row| (row.chi2.configs)().len() * row.chi2.thetas.len()).sum()
}

/// The azimuth of every `wo` that is not the normal: an arbitrary angle, so that the lobe is
/// not symmetric about a grid line (a sign error in `y` would be invisible at φo = 0).
const PHI_O: f32 = 1.0;

/// The harness as every test here uses it: 10⁶ samples, 1% over the family; only the seed
/// differs between configurations.
fn harness(seed: u32) -> ChiSquareTest {
    ChiSquareTest {
        sample_count: 1_000_000,
        significance: 0.01,
        test_count: family_size(),
        seed,
        ..ChiSquareTest::default()
    }
}

/// The view direction at `theta_deg` from the normal, azimuth [`PHI_O`]; exactly `+z` at 0°.
fn view(theta_deg: f32) -> Vec3 {
    if theta_deg == 0.0 {
        return Vec3::Z;
    }
    let (st, ct) = theta_deg.to_radians().sin_cos();
    let (sp, cp) = PHI_O.sin_cos();
    Vec3::new(st * cp, st * sp, ct)
}

/// `target/test-output/chi2-brdf` of the workspace.
fn output_dir() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(&manifest).join("target/test-output/chi2-brdf")
}

/// Runs the chi-square test of `bsdf` seen from `wo`.
fn run(bsdf: &dyn Bsdf, wo: Vec3, seed: u32) -> ChiSquareResult {
    harness(seed).run(|u, uc| bsdf.sample(wo, uc, u).map(|s| s.wi), |wi| bsdf.pdf(wo, wi))
}

/// Prints one line per configuration, then fails with the report of every configuration that
/// failed (its tables written to [`output_dir`]) or whose quadrature did not converge.
fn check_all(results: &[(String, ChiSquareResult)]) {
    let mut failures = Vec::new();
    for (name, r) in results {
        println!(
            "{name:<40} p = {:.3e} (threshold {:.2e}), chi2/dof = {:.1}/{}, rejected {:.4}, \
             integral {:.6}, {} pooled, {} pdf evaluations",
            r.p_value,
            r.threshold,
            r.chi2,
            r.dof,
            r.rejected_observed as f64 / r.sample_count as f64,
            r.pdf_integral,
            r.pooled_cells,
            r.pdf_evaluations,
        );
        if let Err(message) = r.check(name, &output_dir()) {
            failures.push(message);
        } else if r.unconverged_cells > 0 {
            failures.push(format!(
                "{name}: the pdf integral of {} cells did not converge, the expected counts are not \
                 trustworthy\n{r}",
                r.unconverged_cells
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} configurations failed:\n{}",
        failures.len(),
        results.len(),
        failures.join("\n")
    );
}

/// Every configuration of every row of [`LOBES`] at every θo of its row, the configurations
/// in parallel; one report for all.
#[test]
fn chi2_every_lobe() {
    let results: Vec<(String, ChiSquareResult)> = std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for row in &LOBES {
            let chi2 = &row.chi2;
            for (g, config) in (chi2.configs)().into_iter().enumerate() {
                handles.push(scope.spawn(move || {
                    chi2.thetas
                        .iter()
                        .enumerate()
                        .map(|(t, &theta)| {
                            let seed = chi2.seed + (g * chi2.thetas.len() + t) as u32;
                            let bsdf = config.bsdf.as_ref();
                            (format!("{}_theta{theta}", config.label), run(bsdf, view(theta), seed))
                        })
                        .collect::<Vec<_>>()
                }));
            }
        }
        handles.into_iter().flat_map(|h| h.join().expect("a chi-square thread panicked")).collect()
    });
    check_all(&results);
}

/// The test has power: visible-normal samples of α = 0.3 against the pdf of α = 0.31 (a
/// roughness 3% off, as from a slip in the α = roughness² remapping) must fail at 60°. Not
/// part of the Šidák family (it is expected to fail).
#[test]
fn chi2_detects_a_slightly_wrong_roughness() {
    let options = SpecularOptions { sampling: SpecularSampling::Vndf, ..SpecularOptions::default() };
    let sampler = GgxSpecular::new(0.3, Vec3::ONE, options);
    let claimed = GgxSpecular::new(0.31, Vec3::ONE, options);
    let wo = view(60.0);
    let result = harness(3000).run(|u, uc| sampler.sample(wo, uc, u).map(|s| s.wi), |wi| claimed.pdf(wo, wi));
    println!("wrong roughness: p = {:e}, chi2/dof = {:.1}/{}", result.p_value, result.chi2, result.dof);
    assert!(!result.passed && result.p_value < 1e-6, "{result}");
}
