//! The one table of lobes, [`LOBES`], that every per-lobe test iterates: one row ([`Lobe`]) per
//! lobe of `furnace-brdf` that implements [`Bsdf`] (Lambert, the GGX specular lobe, the glTF
//! metallic-roughness material that mixes them, that material under a thin film,
//! KHR_materials_iridescence, and with an anisotropic specular lobe, KHR_materials_anisotropy),
//! holding the configurations each test runs. A
//! new lobe adds a row here; no test file changes.
//!
//! | row field | test | file |
//! |---|---|---|
//! | [`Lobe::chi2`] | chi-square of `sample` against `pdf` (one Šidák family over all rows) | `brdf/tests/chi2.rs` |
//! | [`Lobe::consistency`] | `sample` against `eval` and `pdf`, grazing views, the horizon, `∫ pdf` against the accepted fraction, reciprocity | `brdf/tests/consistency.rs` |
//! | [`Lobe::white_furnace`] | the GPU's white furnace against the CPU and the analytic albedo | `tests/tests/white_furnace.rs` |
//! | [`Lobe::parity`] | WGSL against Rust, eval, pdf and sample on random inputs | `tests/tests/brdf_parity.rs` |
//!
//! The tolerances, seeds derived from a row's first seed, harnesses and failure reports stay in
//! the test files; a row says *what* is tested (parameters, views, seeds), the file *how*.
//!
//! **The GPU twin.** The WGSL evaluates every lobe inside the glTF material record
//! (`furnace_gpu::brdf::BsdfParams`, built by `BsdfParams::new(params, options)` from the same
//! [`MetallicRoughnessParams`] and [`SpecularOptions`] as [`MetallicRoughness::new`]); it has no
//! entry point per lobe. So a row's GPU configurations are glTF parameters with only that lobe
//! on: Lambert is metallic 0 with `specularFactor` 0 (no specular lobe), the GGX lobe is
//! metallic 1 (no diffuse lobe, F0 = base colour, F90 = 1).
//!
//! **Not a row: the dielectric** (`Dielectric`, `Transmissive`). It is not a [`Bsdf`]: it
//! scatters into both hemispheres, has delta events and returns a `ScatterSample`, so its
//! chi-square runs over the whole sphere (with a change of variable that puts the refraction
//! cutoff on a cell edge, a family of its own), its bookkeeping checks delta and transmitted
//! samples, and its WGSL twin is a module of its own with its own record. Its tests are
//! `brdf/tests/dielectric.rs` and `tests/tests/glass_cases/dielectric_parity.rs`.

use crate::Rng;
use furnace_brdf::ggx::ALPHA_MIN;
use furnace_brdf::iridescence::ThinFilm;
use furnace_brdf::turquin::{self, directional_albedo};
use furnace_brdf::{
    Bsdf, GgxSpecular, Lambert, Masking, MetallicRoughness, MetallicRoughnessParams, Rgb, SpecularOptions,
    SpecularSampling,
};
use glam::Vec3;

/// A BSDF under test, shareable with the thread that tests it.
pub type BoxedBsdf = Box<dyn Bsdf + Send + Sync>;

/// One configuration of a lobe.
pub struct Config {
    /// Its name in every report.
    pub label: String,
    /// The BSDF.
    pub bsdf: BoxedBsdf,
    /// The smallest GGX α among its microfacet lobes (`None`: none, Lambert), on which the
    /// consistency tests' `f32` error model and quadrature tolerance depend.
    pub alpha: Option<f32>,
}

impl Config {
    fn new(label: impl Into<String>, bsdf: impl Bsdf + Send + Sync + 'static, alpha: Option<f32>) -> Self {
        Self { label: label.into(), bsdf: Box::new(bsdf), alpha }
    }
}

/// One row of [`LOBES`]: a lobe and the configurations of each test.
pub struct Lobe {
    /// The lobe's name in reports.
    pub name: &'static str,
    /// The chi-square test (`brdf/tests/chi2.rs`).
    pub chi2: Chi2,
    /// The consistency tests (`brdf/tests/consistency.rs`).
    pub consistency: Consistency,
    /// The GPU white furnace (`tests/tests/white_furnace.rs`): the white configurations at a
    /// view cosine μo, or `None` for a lobe without a closed-form albedo.
    pub white_furnace: Option<fn(f32) -> Vec<WhiteConfig>>,
    /// The GPU parity test (`tests/tests/brdf_parity.rs`).
    pub parity: Parity,
}

/// The chi-square configurations of a lobe.
pub struct Chi2 {
    /// Its configurations, each tested at every view angle of [`Chi2::thetas`];
    /// configuration `(g, t)` is labelled `<label>_theta<θo>`.
    pub configs: fn() -> Vec<Config>,
    /// The view angles θo (degrees).
    pub thetas: &'static [f32],
    /// The seed of the first configuration; configuration `(g, t)` gets
    /// `seed + g·thetas.len() + t`.
    pub seed: u32,
}

/// The consistency configurations of a lobe.
pub struct Consistency {
    /// The configurations of the sample checks (strict views, grazing views, the horizon).
    pub configs: fn() -> Vec<Config>,
    /// The seed of the strict sample checks: configuration `i` gets `seed + i`.
    pub seed: u32,
    /// Groups of `∫ pdf` checks, one thread each.
    pub integrals: &'static [Integrals],
    /// The configurations of the reciprocity check: compensation off (Turquin's factor
    /// depends on `cos θo` alone and is not reciprocal).
    pub reciprocal: fn() -> Vec<Config>,
}

/// A group of `∫ pdf` checks: its configurations and the seed of the first; configuration `i`
/// at view `t` gets `seed + 8i + t`.
pub struct Integrals {
    /// The configurations.
    pub configs: fn() -> Vec<IntegralConfig>,
    /// The seed of the first.
    pub seed: u32,
}

/// A configuration of the `∫ pdf` check and the view angles (degrees) it is integrated at.
pub struct IntegralConfig {
    /// The configuration.
    pub config: Config,
    /// Its view angles θo (degrees).
    pub thetas: &'static [f32],
}

/// A white configuration of the GPU white furnace: the glTF parameters with only the lobe on
/// (the GPU's record of them is `BsdfParams::new(params, options)`), the view cosine, and the
/// analytic albedo with the error of that reference.
pub struct WhiteConfig {
    /// Its name in the report (the view cosine is added).
    pub name: String,
    /// The glTF parameters.
    pub params: MetallicRoughnessParams,
    /// The specular options.
    pub options: SpecularOptions,
    /// The view cosine μo.
    pub mu: f32,
    /// The analytic directional albedo `E(μo)`.
    pub analytic: f64,
    /// The error of [`WhiteConfig::analytic`] itself (the compensation table's, when
    /// compensated; 0 for an exact value).
    pub analytic_error: f64,
}

/// How the GPU parity test draws a lobe's materials: one group of records per option
/// combination, each record on a material drawn by `params`.
pub struct Parity {
    /// The option combinations.
    pub options: fn() -> Vec<SpecularOptions>,
    /// Draws the glTF parameters of one material, with the lobe's edges and every other lobe
    /// off.
    pub params: fn(&mut Rng) -> MetallicRoughnessParams,
    /// Draws the thin film over it (KHR_materials_iridescence: its weight and the film), after
    /// the parameters; `None` for a row without one (its generator then draws nothing more).
    pub film: Option<DrawFilm>,
    /// Draws the anisotropy strength (KHR_materials_anisotropy, `with_anisotropy`), after the
    /// film; `None` for an isotropic row.
    pub anisotropy: Option<fn(&mut Rng) -> f32>,
    /// The seed of the row's generator (materials first, then the records).
    pub seed: u64,
    /// Records per option combination.
    pub records_per_option: usize,
}

/// Draws a thin film: its weight and the film ([`film_params`]).
pub type DrawFilm = fn(&mut Rng) -> (f32, ThinFilm);

/// The lobes. A new lobe adds a row.
pub static LOBES: [Lobe; 5] = [
    Lobe {
        name: "lambert",
        chi2: Chi2 { configs: || vec![lambert()], thetas: &CHI2_THETAS, seed: 100 },
        consistency: Consistency {
            configs: || vec![lambert()],
            seed: 1,
            integrals: &[Integrals { configs: lambert_integrals, seed: 20_000 }],
            reciprocal: || vec![lambert()],
        },
        white_furnace: Some(white_lambert),
        parity: Parity {
            options: all_options,
            params: lambert_params,
            film: None,
            anisotropy: None,
            seed: 0x1a3b_e127,
            records_per_option: 20_000,
        },
    },
    Lobe {
        name: "ggx",
        chi2: Chi2 { configs: ggx_chi2, thetas: &CHI2_THETAS, seed: 1000 },
        consistency: Consistency {
            configs: ggx_consistency,
            seed: 100,
            integrals: &[
                Integrals { configs: || ggx_integrals(SpecularSampling::Ndf), seed: 21_000 },
                Integrals { configs: || ggx_integrals(SpecularSampling::Vndf), seed: 22_000 },
                Integrals { configs: || ggx_integrals(SpecularSampling::SphericalCaps), seed: 23_000 },
            ],
            reciprocal: ggx_reciprocal,
        },
        white_furnace: Some(white_metal),
        parity: Parity {
            options: all_options,
            params: metal_params,
            film: None,
            anisotropy: None,
            seed: 0x0066_e75e,
            records_per_option: 20_000,
        },
    },
    Lobe {
        name: "metallic_roughness",
        chi2: Chi2 { configs: material_chi2, thetas: &MATERIAL_CHI2_THETAS, seed: 2000 },
        consistency: Consistency {
            configs: material_consistency,
            seed: 1000,
            integrals: &[
                Integrals { configs: || material_integrals(false, 0..4), seed: 24_000 },
                Integrals { configs: || material_integrals(true, 0..4), seed: 25_000 },
                Integrals { configs: || material_integrals(false, 4..7), seed: 26_000 },
                Integrals { configs: || material_integrals(true, 4..7), seed: 27_000 },
            ],
            reciprocal: material_reciprocal,
        },
        // A mixture of the two lobes above: its albedo has no closed form.
        white_furnace: None,
        parity: Parity {
            options: all_options,
            params: gltf_params,
            film: None,
            anisotropy: None,
            seed: 0x5eed_b5df,
            records_per_option: 100_000,
        },
    },
    Lobe {
        name: "iridescent",
        chi2: Chi2 { configs: iridescent_chi2, thetas: &MATERIAL_CHI2_THETAS, seed: 3000 },
        consistency: Consistency {
            configs: iridescent_consistency,
            seed: 2000,
            integrals: &[Integrals { configs: iridescent_integrals, seed: 28_000 }],
            reciprocal: iridescent_reciprocal,
        },
        // The film's reflectance has no closed-form albedo.
        white_furnace: None,
        parity: Parity {
            options: all_options,
            params: gltf_params,
            film: Some(film_params),
            anisotropy: None,
            seed: 0x1a7e_f11d,
            records_per_option: 40_000,
        },
    },
    Lobe {
        name: "anisotropic",
        chi2: Chi2 { configs: anisotropic_chi2, thetas: &MATERIAL_CHI2_THETAS, seed: 4000 },
        consistency: Consistency {
            configs: anisotropic_consistency,
            seed: 3000,
            integrals: &[Integrals { configs: anisotropic_integrals, seed: 29_000 }],
            reciprocal: anisotropic_reciprocal,
        },
        // Uncompensated, a mixture: no closed-form albedo.
        white_furnace: None,
        parity: Parity {
            options: all_options,
            params: gltf_params,
            film: None,
            anisotropy: Some(anisotropy_strength),
            seed: 0xa115_0770,
            records_per_option: 40_000,
        },
    },
];

// --- the parameters shared by the rows -------------------------------------------------------

/// All 12 [`SpecularOptions`] combinations: masking × sampling × compensation.
pub fn all_options() -> Vec<SpecularOptions> {
    let mut v = Vec::new();
    for masking in MASKINGS {
        for sampling in SAMPLINGS {
            for compensation in [false, true] {
                v.push(SpecularOptions { masking, sampling, compensation });
            }
        }
    }
    v
}

/// The sampling methods of the specular lobe.
const SAMPLINGS: [SpecularSampling; 3] =
    [SpecularSampling::Ndf, SpecularSampling::Vndf, SpecularSampling::SphericalCaps];

/// The masking forms of the specular lobe.
const MASKINGS: [Masking; 2] = [Masking::Separable, Masking::HeightCorrelated];

/// A Lambert lobe of a coloured albedo, so that the channels differ.
fn lambert() -> Config {
    Config::new("lambert", Lambert::new(Vec3::new(0.8, 0.5, 0.2)), None)
}

// --- chi-square ------------------------------------------------------------------------------

/// View angles θo in degrees of the Lambert and GGX chi-square tests. 0° is exactly `+z`.
const CHI2_THETAS: [f32; 5] = [0.0, 30.0, 60.0, 80.0, 89.0];

/// GGX roughness α (not the glTF perceptual roughness) of the chi-square tests.
const CHI2_ALPHAS: [f32; 5] = [0.02, 0.1, 0.3, 0.6, 1.0];

/// View angles θo in degrees of the metallic-roughness chi-square tests.
const MATERIAL_CHI2_THETAS: [f32; 4] = [0.0, 45.0, 80.0, 89.0];

/// The GGX lobe for every sampling method and α, F0 = 1, compensation off. Neither F0,
/// compensation nor masking changes how the lobe samples or its pdf; masking is the default,
/// height-correlated.
fn ggx_chi2() -> Vec<Config> {
    let mut configs = Vec::new();
    for method in SAMPLINGS {
        for alpha in CHI2_ALPHAS {
            let options =
                SpecularOptions { masking: Masking::HeightCorrelated, sampling: method, compensation: false };
            let bsdf = GgxSpecular::new(alpha, Vec3::ONE, options);
            configs.push(Config::new(format!("ggx_{method:?}_alpha{alpha}"), bsdf, Some(alpha)));
        }
    }
    configs
}

/// A glossy blue dielectric (α = 0.0225) with a tinted KHR_materials_specular: a sharp lobe
/// over the diffuse one.
fn glossy_tinted() -> MetallicRoughnessParams {
    MetallicRoughnessParams {
        base_color: Vec3::new(0.2, 0.4, 0.8),
        metallic: 0.0,
        roughness: 0.15,
        specular_factor: 0.7,
        specular_color: Vec3::new(1.0, 0.8, 0.6),
    }
}

/// Four metallic-roughness materials (the one-sample mixture of the diffuse and specular
/// lobes), one configuration each.
fn material_chi2() -> Vec<Config> {
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
            glossy_tinted(),
            SpecularOptions { sampling: SpecularSampling::Ndf, ..SpecularOptions::mitsuba() },
        ),
    ]
    .into_iter()
    .map(|(name, params, options)| {
        let bsdf = MetallicRoughness::new(params, options);
        let alpha = bsdf.specular.ggx.alpha();
        Config::new(format!("metallic_roughness_{name}"), bsdf, Some(alpha))
    })
    .collect()
}

// --- consistency -----------------------------------------------------------------------------

/// GGX roughnesses of the consistency checks: the clamp `ALPHA_MIN` (= 1e-4), sharp, medium,
/// rough.
const CONSISTENCY_ALPHAS: [f32; 6] = [1e-4, 0.02, 0.1, 0.3, 0.6, 1.0];

/// A coloured specular F0, so that the channels differ.
const F0: Vec3 = Vec3::new(0.9, 0.6, 0.3);

/// Every GGX lobe configuration: α × sampling × masking × compensation.
fn ggx_consistency() -> Vec<Config> {
    let mut configs = Vec::new();
    for alpha in CONSISTENCY_ALPHAS {
        for sampling in SAMPLINGS {
            for masking in MASKINGS {
                for compensation in [false, true] {
                    let options = SpecularOptions { masking, sampling, compensation };
                    configs.push(Config::new(
                        format!("ggx a={alpha} {sampling:?} {masking:?} comp={compensation}"),
                        GgxSpecular::new(alpha, F0, options),
                        Some(alpha),
                    ));
                }
            }
        }
    }
    configs
}

/// Representative metallic-roughness materials of the consistency checks: (name, parameters).
/// The first four are common, the last three extreme (mirrors, black).
fn materials() -> Vec<(&'static str, MetallicRoughnessParams)> {
    let p = |base: Vec3, metallic: f32, roughness: f32| MetallicRoughnessParams {
        base_color: base,
        metallic,
        roughness,
        ..Default::default()
    };
    vec![
        ("dielectric", p(Vec3::splat(0.8), 0.0, 0.5)),
        ("half_metallic", p(Vec3::new(0.9, 0.6, 0.3), 0.5, 0.3)),
        ("rough_metal", p(Vec3::new(0.95, 0.64, 0.54), 1.0, 1.0)),
        ("glossy_tinted_specular", glossy_tinted()),
        ("mirror_metal", p(Vec3::new(1.0, 0.78, 0.34), 1.0, 0.0)),
        ("mirror_dielectric", p(Vec3::new(0.1, 0.5, 0.1), 0.0, 0.0)),
        ("black_dielectric", p(Vec3::ZERO, 0.0, 0.4)),
    ]
}

/// Every material × sampling × masking × compensation.
fn material_consistency() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params) in materials() {
        for sampling in SAMPLINGS {
            for masking in MASKINGS {
                for compensation in [false, true] {
                    let options = SpecularOptions { masking, sampling, compensation };
                    let bsdf = MetallicRoughness::new(params, options);
                    let alpha = bsdf.specular.ggx.alpha();
                    configs.push(Config::new(
                        format!("material {name} {sampling:?} {masking:?} comp={compensation}"),
                        bsdf,
                        Some(alpha),
                    ));
                }
            }
        }
    }
    configs
}

/// The view angles of the `∫ pdf` checks for a lobe of roughness α. For α = 1e-4 (the clamp)
/// two views are left out, because the pdf cannot be integrated over `(cos θ, φ)` cells
/// there: at normal incidence the lobe is a ring of `1 − cos θ ≈ 2α² = 2·10⁻⁸` around the pole,
/// narrower than the harness's finest interval (2⁻²³); at 89° the pdf's own `f32` noise
/// (about `(2/α)·u/cos θo` ≈ 7% relative, the error model of `brdf/tests/consistency.rs`)
/// exceeds any useful quadrature tolerance. 0.5° replaces 0°.
fn integral_thetas(alpha: f32) -> &'static [f32] {
    if alpha < 0.01 { &[0.5, 30.0, 60.0, 80.0] } else { &[0.0, 30.0, 60.0, 80.0, 89.0] }
}

fn lambert_integrals() -> Vec<IntegralConfig> {
    vec![IntegralConfig { config: lambert(), thetas: integral_thetas(1.0) }]
}

/// The GGX lobe with one sampling method (masking and compensation do not change the pdf),
/// at every α of [`CONSISTENCY_ALPHAS`].
fn ggx_integrals(sampling: SpecularSampling) -> Vec<IntegralConfig> {
    CONSISTENCY_ALPHAS
        .iter()
        .map(|&alpha| {
            let options = SpecularOptions { sampling, ..SpecularOptions::default() };
            let bsdf = GgxSpecular::new(alpha, F0, options);
            IntegralConfig {
                config: Config::new(format!("ggx a={alpha} {sampling:?}"), bsdf, Some(alpha)),
                thetas: integral_thetas(alpha),
            }
        })
        .collect()
}

/// The materials `range` of [`materials`] with the default switches, or with the Mitsuba ones
/// (separable, no compensation — the lobe choice then uses `E_ss`) sampled by the NDF.
///
/// The near-mirror materials (α = 1e-4) are not checked near the pole: there a lobe 10⁻⁴ wide
/// on top of a diffuse background is a needle the quadrature never sees — near the pole its
/// nodes are ~0.03 rad apart in θ, and the GGX tails that would reveal the lobe are below the
/// background's tolerance — so coarse and fine estimates agree without it (the integral came
/// out 0.90 for a sampler that accepts everything). Without the background (the plain GGX lobe
/// above, or the mirror metal) the tails alone drive the refinement and 0.5° integrates fine.
fn material_integrals(mitsuba: bool, range: std::ops::Range<usize>) -> Vec<IntegralConfig> {
    let options = if mitsuba {
        SpecularOptions { sampling: SpecularSampling::Ndf, ..SpecularOptions::mitsuba() }
    } else {
        SpecularOptions::default()
    };
    let label = if mitsuba { "mitsuba_ndf" } else { "default" };
    materials()[range]
        .iter()
        .map(|&(name, params)| {
            let bsdf = MetallicRoughness::new(params, options);
            let alpha = bsdf.specular.ggx.alpha();
            let has_diffuse = bsdf.diffuse.albedo != Vec3::ZERO;
            let thetas: &'static [f32] =
                if alpha < 0.01 && has_diffuse { &[30.0, 60.0, 80.0] } else { integral_thetas(alpha) };
            IntegralConfig {
                config: Config::new(format!("material {name} {label}"), bsdf, Some(alpha)),
                thetas,
            }
        })
        .collect()
}

/// GGX at every α with both maskings, compensation off.
fn ggx_reciprocal() -> Vec<Config> {
    let mut configs = Vec::new();
    for alpha in CONSISTENCY_ALPHAS {
        for masking in MASKINGS {
            let options = SpecularOptions { masking, compensation: false, ..SpecularOptions::default() };
            configs.push(Config::new(
                format!("ggx a={alpha} {masking:?}"),
                GgxSpecular::new(alpha, F0, options),
                Some(alpha),
            ));
        }
    }
    configs
}

/// Every material of [`materials`] with both maskings, compensation off.
fn material_reciprocal() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params) in materials() {
        for masking in MASKINGS {
            let options = SpecularOptions { masking, compensation: false, ..SpecularOptions::default() };
            let bsdf = MetallicRoughness::new(params, options);
            let alpha = bsdf.specular.ggx.alpha();
            configs.push(Config::new(format!("material {name} {masking:?}"), bsdf, Some(alpha)));
        }
    }
    configs
}

// --- the iridescent material -----------------------------------------------------------------

/// Iridescent materials (KHR_materials_iridescence over the metallic-roughness material): the
/// film changes the Fresnel weights and so the lobe choice, not the lobes' directions.
fn iridescent_materials() -> Vec<(&'static str, MetallicRoughnessParams, f32, ThinFilm)> {
    let p = |base: Vec3, metallic: f32, roughness: f32| MetallicRoughnessParams {
        base_color: base,
        metallic,
        roughness,
        ..Default::default()
    };
    vec![
        (
            "film_dielectric",
            p(Vec3::new(0.04, 0.04, 0.06), 0.0, 0.3),
            1.0,
            ThinFilm { ior: 1.3, thickness: 400.0 },
        ),
        (
            "film_half_metallic",
            p(Vec3::new(0.9, 0.6, 0.3), 0.5, 0.5),
            0.7,
            ThinFilm { ior: 1.8, thickness: 1200.0 },
        ),
        (
            "film_copper",
            p(Vec3::new(0.95, 0.64, 0.54), 1.0, 0.2),
            1.0,
            ThinFilm { ior: 1.3, thickness: 300.0 },
        ),
    ]
}

/// Each iridescent material with the default switches.
fn iridescent_chi2() -> Vec<Config> {
    iridescent_materials()
        .into_iter()
        .map(|(name, params, factor, film)| {
            let bsdf = MetallicRoughness::new_iridescent(params, SpecularOptions::default(), factor, film);
            let alpha = bsdf.specular.ggx.alpha();
            Config::new(name, bsdf, Some(alpha))
        })
        .collect()
}

/// Every iridescent material × sampling × masking × compensation.
fn iridescent_consistency() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params, factor, film) in iridescent_materials() {
        for o in all_options() {
            let bsdf = MetallicRoughness::new_iridescent(params, o, factor, film);
            let alpha = bsdf.specular.ggx.alpha();
            configs.push(Config::new(
                format!("{name} {:?} {:?} comp={}", o.sampling, o.masking, o.compensation),
                bsdf,
                Some(alpha),
            ));
        }
    }
    configs
}

/// Each iridescent material with the default switches.
fn iridescent_integrals() -> Vec<IntegralConfig> {
    iridescent_chi2()
        .into_iter()
        .map(|config| {
            let thetas = integral_thetas(config.alpha.unwrap_or(1.0));
            IntegralConfig { config, thetas }
        })
        .collect()
}

/// Every iridescent material with both maskings, compensation off (the film at `ωo·ωm` is
/// reciprocal).
fn iridescent_reciprocal() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params, factor, film) in iridescent_materials() {
        for masking in MASKINGS {
            let options = SpecularOptions { masking, compensation: false, ..SpecularOptions::default() };
            let bsdf = MetallicRoughness::new_iridescent(params, options, factor, film);
            let alpha = bsdf.specular.ggx.alpha();
            configs.push(Config::new(format!("{name} {masking:?}"), bsdf, Some(alpha)));
        }
    }
    configs
}

/// A thin film with the edges: weight 1 or partial, index 1 (no first interface) to 3,
/// thickness 0 (still not plain Fresnel in the text's formula) to 2000 nm.
pub fn film_params(rng: &mut Rng) -> (f32, ThinFilm) {
    let factor = if rng.next_u64().is_multiple_of(2) { 1.0 } else { 0.05 + 0.95 * rng.f32() };
    let ior = match rng.next_u64() % 5 {
        0 => 1.0,
        1 => 1.3,
        _ => 1.0 + 2.0 * rng.f32(),
    };
    let thickness = match rng.next_u64() % 10 {
        0 => 0.0,
        1 => 2000.0,
        _ => 1200.0 * rng.f32(),
    };
    (factor, ThinFilm { ior, thickness })
}

// --- the anisotropic material ----------------------------------------------------------------

/// Anisotropic materials (KHR_materials_anisotropy: the specular lobe stretched to
/// `αx = mix(α, 1, s²)` along the frame's x axis): a metal, a dielectric and a half-metal whose
/// lobe at full strength is a ridge (αx 1, αy 0.0225; at αy 0.0025 the adaptive quadrature of
/// the tests no longer converges in the ridge's cells), (name, parameters, strength).
fn anisotropic_materials() -> Vec<(&'static str, MetallicRoughnessParams, f32)> {
    let p = |base: Vec3, metallic: f32, roughness: f32| MetallicRoughnessParams {
        base_color: base,
        metallic,
        roughness,
        ..Default::default()
    };
    vec![
        ("aniso_metal", p(Vec3::new(0.95, 0.93, 0.88), 1.0, 0.3), 0.6),
        ("aniso_dielectric", p(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.5), 0.9),
        ("aniso_ridge_half_metal", p(Vec3::new(0.3, 0.6, 0.9), 0.5, 0.15), 1.0),
    ]
}

/// One anisotropic material with `options`, and its [`Config::alpha`] (αy, the smaller).
fn anisotropic(
    params: MetallicRoughnessParams,
    options: SpecularOptions,
    strength: f32,
) -> (MetallicRoughness, f32) {
    let bsdf = MetallicRoughness::new(params, options).with_anisotropy(strength);
    let alpha = bsdf.specular.ggx.alphas().1;
    (bsdf, alpha)
}

/// Each anisotropic material with the default switches.
fn anisotropic_chi2() -> Vec<Config> {
    anisotropic_materials()
        .into_iter()
        .map(|(name, params, strength)| {
            let (bsdf, alpha) = anisotropic(params, SpecularOptions::default(), strength);
            Config::new(name, bsdf, Some(alpha))
        })
        .collect()
}

/// Every anisotropic material × sampling × masking × compensation (which an anisotropic lobe
/// ignores: the option must change nothing).
fn anisotropic_consistency() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params, strength) in anisotropic_materials() {
        for o in all_options() {
            let (bsdf, alpha) = anisotropic(params, o, strength);
            configs.push(Config::new(
                format!("{name} {:?} {:?} comp={}", o.sampling, o.masking, o.compensation),
                bsdf,
                Some(alpha),
            ));
        }
    }
    configs
}

/// Each anisotropic material with the default switches.
fn anisotropic_integrals() -> Vec<IntegralConfig> {
    anisotropic_chi2()
        .into_iter()
        .map(|config| {
            let thetas = integral_thetas(config.alpha.unwrap_or(1.0));
            IntegralConfig { config, thetas }
        })
        .collect()
}

/// Every anisotropic material with both maskings, compensation off.
fn anisotropic_reciprocal() -> Vec<Config> {
    let mut configs = Vec::new();
    for (name, params, strength) in anisotropic_materials() {
        for masking in MASKINGS {
            let options = SpecularOptions { masking, compensation: false, ..SpecularOptions::default() };
            let (bsdf, alpha) = anisotropic(params, options, strength);
            configs.push(Config::new(format!("{name} {masking:?}"), bsdf, Some(alpha)));
        }
    }
    configs
}

/// An anisotropy strength with the edges: 0 (isotropic), 1, a sliver, and at random.
pub fn anisotropy_strength(rng: &mut Rng) -> f32 {
    match rng.next_u64() % 8 {
        0 => 0.0,
        1 | 2 => 1.0,
        3 => 1e-3,
        _ => rng.f32(),
    }
}

// --- the GPU white furnace -------------------------------------------------------------------

/// GGX roughness α of the white furnace: from the clamp to 1.
const WHITE_ALPHAS: [f32; 6] = [1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0];

/// The GGX lobe alone, white: a white metal (base colour 1, metallic 1: F = 1) at every α of
/// [`WHITE_ALPHAS`] and every option combination, against `directional_albedo` (quadrature of
/// order 128; times Turquin's factor when compensated, whose table is within 0.5% for
/// μo ≥ 1e-3 and 3.5% below: `furnace-brdf`'s `tests/stability.rs::white_furnace_full_range`).
fn white_metal(mu: f32) -> Vec<WhiteConfig> {
    let table_error = |mu: f32| if mu >= 1e-3 { 0.005 } else { 0.035 };
    let mut configs = vec![];
    for alpha in WHITE_ALPHAS {
        for o in all_options() {
            let params = MetallicRoughnessParams {
                base_color: Rgb::ONE,
                metallic: 1.0,
                roughness: alpha.sqrt(),
                ..Default::default()
            };
            // The lobe's own α (roughness² of the rounded square root).
            let a = MetallicRoughness::new(params, o).specular.ggx.alpha();
            let e = directional_albedo(mu, a, o.masking, 128);
            let comp =
                if o.compensation { turquin::compensation(Rgb::ONE, mu, a, o.masking).x as f64 } else { 1.0 };
            configs.push(WhiteConfig {
                name: format!("metal α {alpha:e} {:?}/{:?}/comp {}", o.masking, o.sampling, o.compensation),
                params,
                options: o,
                mu,
                analytic: comp * e,
                analytic_error: if o.compensation { table_error(mu) } else { 0.0 },
            });
        }
    }
    configs
}

/// The Lambert lobe alone, white: a glTF Lambert (metallic 0, specularFactor 0), albedo 1,
/// whose albedo is exactly 1.
fn white_lambert(mu: f32) -> Vec<WhiteConfig> {
    let params = MetallicRoughnessParams {
        base_color: Rgb::ONE,
        metallic: 0.0,
        specular_factor: 0.0,
        ..Default::default()
    };
    vec![WhiteConfig {
        name: "Lambert".into(),
        params,
        options: SpecularOptions::default(),
        mu,
        analytic: 1.0,
        analytic_error: 0.0,
    }]
}

// --- the GPU parity test ---------------------------------------------------------------------

/// glTF metallic-roughness parameters with the edges: metallic 0/1, α at ALPHA_MIN (roughness
/// 0 and below √ALPHA_MIN) and 1, specular factor 0/1, specular colours that saturate F0, black
/// and white. Also the inputs of the GPU constructor's test (`brdf_parity.rs`).
pub fn gltf_params(rng: &mut Rng) -> MetallicRoughnessParams {
    let colour = |rng: &mut Rng| match rng.next_u64() % 10 {
        0 => Vec3::ONE,
        1 => Vec3::ZERO,
        2 => Vec3::new(1.0, 0.5 * rng.f32(), 0.0),
        _ => Vec3::new(rng.f32(), rng.f32(), rng.f32()),
    };
    let base_color = colour(rng);
    let metallic = match rng.next_u64() % 10 {
        0..=2 => 0.0,
        3..=5 => 1.0,
        _ => rng.f32(),
    };
    let roughness = match rng.next_u64() % 20 {
        0..=2 => 0.0,          // α = 0 → ALPHA_MIN
        3 => ALPHA_MIN.sqrt(), // α = ALPHA_MIN
        4 => 1e-3,             // α = 1e-6 → ALPHA_MIN
        5 => 1.0,              // α = 1
        6 => 0.03 * rng.f32(), // α < 1e-3: sharp lobes
        _ => rng.f32(),
    };
    let specular_factor = match rng.next_u64() % 5 {
        0 => 0.0,
        1 | 2 => 1.0,
        _ => rng.f32(),
    };
    let specular_color = match rng.next_u64() % 10 {
        0..=4 => Vec3::ONE,
        5 => Vec3::splat(30.0), // 0.04·30 > 1: F0 saturates
        _ => 2.0 * colour(rng),
    };
    MetallicRoughnessParams { base_color, metallic, roughness, specular_factor, specular_color }
}

/// [`gltf_params`] with only the Lambert lobe on: metallic 0, specularFactor 0 (F0 = F90 = 0).
fn lambert_params(rng: &mut Rng) -> MetallicRoughnessParams {
    MetallicRoughnessParams { metallic: 0.0, specular_factor: 0.0, ..gltf_params(rng) }
}

/// [`gltf_params`] with only the GGX lobe on: metallic 1 (no diffuse lobe; F0 = base colour,
/// F90 = 1).
fn metal_params(rng: &mut Rng) -> MetallicRoughnessParams {
    MetallicRoughnessParams { metallic: 1.0, ..gltf_params(rng) }
}
