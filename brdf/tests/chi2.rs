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
//! The matrix:
//!
//! * [`Lambert`] × θo ∈ {0°, 30°, 60°, 80°, 89°};
//! * [`GgxSpecular`] × every [`SpecularSampling`] × α ∈ {0.02, 0.1, 0.3, 0.6, 1} × the same
//!   θo, with F0 = 1 and compensation off. Neither F0, compensation nor masking changes how
//!   the lobe samples or its pdf; masking is the default, height-correlated;
//! * [`MetallicRoughness`] (one-sample mixture of its diffuse and specular lobes) for four
//!   materials × θo ∈ {0°, 45°, 80°, 89°}.
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
//! The matrix is a table, [`LOBES`]: one row per lobe (its groups of configurations built from
//! the lobe's parameters, its view angles, its first seed), so a new lobe adds a row. One test
//! runs every group in parallel.
//! On failure every failing configuration's report is printed and its tables are written to
//! `target/test-output/chi2-brdf/<name>.{txt,csv,ppm}`. Run with `--nocapture` to see the
//! p-value of every configuration.

use furnace_brdf::{
    Bsdf, GgxSpecular, Lambert, Masking, MetallicRoughness, MetallicRoughnessParams, SpecularOptions,
    SpecularSampling,
};
use furnace_tests::chi2::{ChiSquareResult, ChiSquareTest};
use glam::Vec3;
use std::path::PathBuf;

/// View angles θo in degrees for Lambert and GGX. 0° is exactly `+z`.
const THETAS: [f32; 5] = [0.0, 30.0, 60.0, 80.0, 89.0];

/// GGX roughness α (not the glTF perceptual roughness).
const ALPHAS: [f32; 5] = [0.02, 0.1, 0.3, 0.6, 1.0];

/// The sampling methods of the specular lobe.
const METHODS: [SpecularSampling; 3] =
    [SpecularSampling::Ndf, SpecularSampling::Vndf, SpecularSampling::SphericalCaps];

/// View angles θo in degrees for the metallic-roughness materials.
const MATERIAL_THETAS: [f32; 4] = [0.0, 45.0, 80.0, 89.0];

/// A BSDF under test, shared with the thread that tests it.
type BoxedBsdf = Box<dyn Bsdf + Send + Sync>;

/// One row of the table of lobes: the chi-square family is every configuration of every row.
struct LobeRow {
    /// Its groups of configurations: a label and the BSDF, built from the lobe's parameters.
    groups: fn() -> Vec<(String, BoxedBsdf)>,
    /// The view angles θo (degrees) every group is tested at; configuration `(g, t)` is
    /// labelled `<group label>_theta<θo>`.
    thetas: &'static [f32],
    /// The seed of the first configuration; configuration `(g, t)` gets
    /// `seed + g·thetas.len() + t`.
    seed: u32,
}

/// The lobes of `furnace-brdf` and the glTF material that mixes them. A new lobe adds a row.
static LOBES: [LobeRow; 3] = [
    LobeRow { groups: lambert_groups, thetas: &THETAS, seed: 100 },
    LobeRow { groups: ggx_groups, thetas: &THETAS, seed: 1000 },
    LobeRow { groups: metallic_roughness_groups, thetas: &MATERIAL_THETAS, seed: 2000 },
];

/// Number of chi-square tests of the table: the Šidák family.
fn family_size() -> usize {
    LOBES.iter().map(|row| (row.groups)().len() * row.thetas.len()).sum()
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

/// A Lambert lobe of a coloured albedo.
fn lambert_groups() -> Vec<(String, BoxedBsdf)> {
    vec![("lambert".to_string(), Box::new(Lambert::new(Vec3::new(0.8, 0.5, 0.2))))]
}

/// The GGX lobe for every sampling method and α, F0 = 1, compensation off.
fn ggx_groups() -> Vec<(String, BoxedBsdf)> {
    let mut groups: Vec<(String, BoxedBsdf)> = Vec::new();
    for method in METHODS {
        for alpha in ALPHAS {
            let options =
                SpecularOptions { masking: Masking::HeightCorrelated, sampling: method, compensation: false };
            let bsdf = GgxSpecular::new(alpha, Vec3::ONE, options);
            groups.push((format!("ggx_{method:?}_alpha{alpha}"), Box::new(bsdf)));
        }
    }
    groups
}

/// The metallic-roughness materials, one group each.
fn metallic_roughness_groups() -> Vec<(String, BoxedBsdf)> {
    [
        // A plain dielectric (glTF's common case): grey base, α = 0.25, defaults (spherical
        // caps, height-correlated, compensation on).
        (
            "dielectric",
            MetallicRoughnessParams {
                base_color: Vec3::splat(0.8),
                metallic: 0.0,
                roughness: 0.5,
                ..Default::default()
            },
            SpecularOptions::default(),
        ),
        // Half metallic, coloured, α = 0.09, Heitz VNDF.
        (
            "half_metallic",
            MetallicRoughnessParams {
                base_color: Vec3::new(0.9, 0.6, 0.3),
                metallic: 0.5,
                roughness: 0.3,
                ..Default::default()
            },
            SpecularOptions { sampling: SpecularSampling::Vndf, ..SpecularOptions::default() },
        ),
        // A rough metal (copper, α = 1): no diffuse lobe, so the specular lobe alone.
        (
            "rough_metal",
            MetallicRoughnessParams {
                base_color: Vec3::new(0.95, 0.64, 0.54),
                metallic: 1.0,
                roughness: 1.0,
                ..Default::default()
            },
            SpecularOptions::default(),
        ),
        // A glossy blue dielectric (α = 0.0225, a sharp lobe over the diffuse one) sampled by
        // the NDF, which also rejects, with the Mitsuba switches (separable, no compensation:
        // the lobe choice then uses E_ss) and a tinted KHR_materials_specular.
        (
            "glossy_dielectric_ndf",
            MetallicRoughnessParams {
                base_color: Vec3::new(0.2, 0.4, 0.8),
                metallic: 0.0,
                roughness: 0.15,
                specular_factor: 0.7,
                specular_color: Vec3::new(1.0, 0.8, 0.6),
            },
            SpecularOptions { sampling: SpecularSampling::Ndf, ..SpecularOptions::mitsuba() },
        ),
    ]
    .into_iter()
    .map(|(name, params, options)| {
        let bsdf: BoxedBsdf = Box::new(MetallicRoughness::new(params, options));
        (format!("metallic_roughness_{name}"), bsdf)
    })
    .collect()
}

/// Every group of every row of [`LOBES`] at every θo of its row, the groups in parallel; one
/// report for all.
#[test]
fn chi2_every_lobe() {
    let results: Vec<(String, ChiSquareResult)> = std::thread::scope(|scope| {
        let mut handles = Vec::new();
        for row in &LOBES {
            for (g, (label, bsdf)) in (row.groups)().into_iter().enumerate() {
                handles.push(scope.spawn(move || {
                    row.thetas
                        .iter()
                        .enumerate()
                        .map(|(t, &theta)| {
                            let seed = row.seed + (g * row.thetas.len() + t) as u32;
                            (format!("{label}_theta{theta}"), run(bsdf.as_ref(), view(theta), seed))
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
