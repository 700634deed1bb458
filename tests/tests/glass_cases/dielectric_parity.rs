//! Parity of the WGSL dielectric (`gpu/src/wgsl/dielectric.wgsl`, `furnace_gpu::wgsl::DIELECTRIC`)
//! with its Rust twin `furnace_brdf::dielectric`, on the same inputs, in one kernel (one
//! dispatch: a shader compile on a software adapter costs seconds):
//!
//! * `fresnel_dielectric(cos_i, η)` (all four fields) and `thin_reflectance` over a grid of
//!   `cos_i ∈ [−1, 1]` with 0, −0, ±1, tiny and subnormal cosines and cosines within a few ulps
//!   and relative 1e-1…1e-7 of the critical angle, for η ∈ {1, 1 ± 1e-6, 1.33, 1.5, 1/1.5, 2.4,
//!   ETA_MIN, ETA_MAX}; the same records run smooth, thin and rough (α 0.3) interfaces with
//!   `wo.z` = that cosine, so Fresnel's edges are also sampled through.
//! * `dielectric_new` against `Dielectric::new`: η, α, the interface kind (`iface` 0/1/2/3 =
//!   Smooth/Rough/ThinWalled), the masking form and the tint, bit for bit, including NaN,
//!   ±∞, negative, zero and out-of-range η, α and tint, α at ALPHA_MIN ± 1 ulp and η = 1 (smooth
//!   whatever α).
//! * `dielectric_eval` and `dielectric_pdf` at (wo, wi) pairs on both sides (near the reflection
//!   and refraction peaks, the exact mirror and Snell directions, wo, −wo, the poles, random and
//!   grazing directions down to 1e-7 and 0), for α ∈ {1e-4, 0.01, 0.1, 0.3, 1} ×
//!   η ∈ {1.5, 1/1.5, 1.33} × separable / height-correlated masking.
//! * `dielectric_sample` against `Dielectric::sample`: `valid` against `Some`, wi, weight, pdf,
//!   delta, transmitted and rest, for smooth, rough and thin interfaces, wo on both sides
//!   (total internal reflection from inside included), η ∈ {1, 1.33, 1.5, 1/1.5, 2.4}.
//! * `dielectric_shadow_transmittance` against `shadow_transmittance`.
//! * The glTF mixture `Transmissive` (`transmissive_eval/pdf/sample/is_delta`), its opaque part
//!   built on the GPU by `bsdf_params` from the parameters `MetallicRoughness::new` gets (all 12
//!   `SpecularOptions`), weight g ∈ {0.3, 0.7, 1}, over smooth, rough and thin interfaces.
//!
//! * The choice itself: the kernel also returns the probability and uniform number the module
//!   compares (R, R′ or R at its sampled normal; `uc` rescaled in a mixture); the GPU's sample
//!   must follow them exactly (transmitted iff `!(uc < p)`, rest = `rescale(uc, p)` in
//!   `[0, 1)`), and 16 000 records put `uc` on a threshold (= p, ± 1 ulp; also = g and on the
//!   opaque part's specular probability) so that a `<` turned `<=` fails. A degenerate `wo`
//!   (z = 0, not finite) must give no sample on both sides; `uc` = 1 and |cos| > 1 (outside the
//!   domain, clamped) are included.
//!
//! Tolerances (see the constants): every value within 1e-5 relative (Fresnel probabilities R,
//! R′, T′ and a delta event's R or 1 − R: also absolutely within 1e-6), or — where the Rust
//! itself is ill-conditioned, i.e. moves by more than that when one input moves by one ulp or
//! `u` by one sampler step — within 1e-5 plus 4 times that movement ("ill"). Discrete decisions
//! must agree except where they are explained by rounding: the dielectric's choice where `uc`
//! lies between the GPU's and the Rust's probability (which must agree, see above), the opaque
//! part's lobe where `uc` is within 1e-6 of its probability ("boundary"); a None/sample flip
//! where one sampler step or one ulp of `wo` of the Rust gives the GPU's outcome or the
//! direction grazes the interface within rounding ("flips"); where rounding alone decides a
//! rough direction (the spherical cap's far end, `u.y → 1`; Heitz VNDF's rim for the opaque
//! part) only the GPU's pdf and weight at its own direction ("rim"). Every count is bounded.
//!
//! The errors the tolerances allow for, measured on a software adapter (llvmpipe, x86-64) over
//! 508 991 records; `cargo test -p furnace-tests --test all dielectric_parity:: -- --nocapture`
//! prints the table per group:
//! * bit-identical: every Fresnel field, R′, the shadow transmittance, `dielectric_new`, and the
//!   dielectric's eval and pdf (the same operations, correctly rounded on both sides); the
//!   mixture's eval and pdf within 1.5e-7 and 2.2e-7 (its opaque part);
//! * samples, well-conditioned: wi within 9.5e-6 (the GPU's `sin`/`cos` in the spherical-cap
//!   warp), pdf 3.2e-7, weight 4.0e-7, rest 1.0e-5 absolute and the reflection probability at
//!   the sampled normal 1.0e-5 (both follow the normal's rounding);
//! * ≈ 1 030 ill-conditioned values (0.2 %, at most 0.53 of their tolerance; the largest raw
//!   errors wi 0.6 at the opaque part's Heitz rim, p 2.8e-2, rest 6.6e-3), all at `u` on an edge
//!   (u.y = 2⁻²⁴, where the cap's `√(1 − z²)` moves the normal by 3.5e-4 per step; u.x or u.y =
//!   1 − 2⁻²⁴) or at grazing angles; 221 boundary choices, all in the threshold group's rough
//!   records (R at a normal that differs by the warp's rounding); 10 flips; no rim cases.
//!
//! A failure prints the worst mismatches with their inputs and the GPU's and the Rust's values.

use std::f64::consts::TAU;
use std::fmt::Write as _;

use furnace_brdf::dielectric::{
    Dielectric, ETA_MAX, ETA_MIN, Interface, ONE_BELOW, ScatterSample, Transmissive, fresnel_dielectric,
    rescale, thin_reflectance,
};
use furnace_brdf::ggx::ALPHA_MIN;
use furnace_brdf::{
    Bsdf, GgxSpecular, Masking, MetallicRoughness, MetallicRoughnessParams, SpecularOptions, SpecularSampling,
};
use furnace_gpu::brdf;
use furnace_gpu::wgsl;
use furnace_tests::Rng;
use furnace_tests::gpu::{self as kernel, test_context};
use furnace_tests::lobes::all_options;
use glam::{DVec3, Vec2, Vec3};

/// Relative tolerance of every floating-point comparison (as `brdf_parity`). Both sides evaluate
/// the same formulas in the same order; what differs is the rounding of `sqrt`, division,
/// `sin`/`cos` (the spherical-cap warp) and possible fused multiply-adds, a few ulp (≈ 1e-7)
/// each, so 1e-5 leaves two orders of magnitude for error growth through a dozen operations.
const REL_TOL: f32 = 1e-5;

/// Absolute floor of relative comparisons: far below any radiance, pdf or weight that matters,
/// above what flushing subnormal intermediates to zero (allowed in WGSL) can change.
const ABS_FLOOR: f32 = 1e-20;

/// The scale of Fresnel probabilities (R, R′ = 2R/(1 + R), T′ = 1 − R′, a delta event's
/// probability R or 1 − R): compared as `|Δ| ≤ REL_TOL·(value + FRESNEL_SCALE)`, i.e. also within
/// 1e-6 absolutely. R is the mean of two squares of quotients of O(1) terms (a dozen roundings
/// of ≤ 6e-8 each, absolute), so where R → 0 (η → 1: R ~ 1e-13 from a cancelling difference
/// `cos θi − η cos θt`) or 1 − R → 0 (grazing) its relative error is unbounded while its absolute
/// error stays ~1e-7; an error of 1e-6 in a probability changes no image.
const FRESNEL_SCALE: f32 = 0.1;

/// Sample weights are compared relative to themselves or, below it, to this absolute floor
/// (weights are O(0.01…10)), plus the opaque part's diffuse term (see [`opaque_scale`]).
const WEIGHT_FLOOR: f32 = 1e-6;

/// Where the Rust is ill-conditioned at an input — one ulp of an input (or one sampler step of
/// `u`) moves its value by more than [`REL_TOL`] — the GPU value is accepted within `REL_TOL`
/// plus this many times that movement: the GPU's own rounding is equivalent to moving the
/// inputs by a few ulps (the critical angle, where `cos θt = √(1 − η²sin²θi)` is the root of a
/// cancelling difference; sharp lobes α → 1e-4, where D changes by ~4δ/α for a normal moved
/// by δ; a microfacet seen edge-on; the warp's `√(1 − z²)` at u.y → 0).
const SPREAD_FACTOR: f32 = 4.0;

/// A discrete choice `uc < p` may go either way when `uc` is this close to `p` (p differs by
/// an ulp or so; `uc` rescaled by a division may too).
const BOUNDARY: f32 = 1e-6;

/// One sampler step: `to_unit_f32` resolves `u` to 2⁻²⁴.
const U_STEP: f32 = 1.0 / 16_777_216.0;

/// A `None`/sample flip where the sampled direction grazes the interface within rounding: a
/// reflected or refracted `ωi = 2(ωo·ωm)ωm − ωo` (or Walter's refraction) from unit vectors has
/// z within a few ulps of 2 (2.4e-7 each) of the exact value.
const HORIZON_ROUNDING: f32 = 1e-6;

/// Words per input record: flags (thin 1, height-correlated 2, transmissive 4), η, α, tint (3),
/// wo (3), wi (3), uc, u (2), cos, η of the Fresnel call, g, base colour (3), metallic,
/// roughness, specular factor, specular colour (3), BSDF flags.
const IN_WORDS: usize = 28;
/// Words per output record: Fresnel (4), thin R′, the dielectric's η, α, iface, height_correlated,
/// tint (3), eval (3), pdf, sample wi (3), pdf, weight (3), rest, bits (valid 1, delta 2,
/// transmitted 4, transmissive_is_delta 8), shadow transmittance (3), the dielectric's
/// reflection probability and uniform number for the sample, 2 words of padding.
const OUT_WORDS: usize = 32;

/// Records per rough configuration (α × η × masking: 30 configurations).
const ROUGH_RECORDS: usize = 10_000;
/// Records per smooth / thin configuration.
const DELTA_RECORDS: usize = 5000;
/// Records with odd constructor inputs (NaN, ±∞, out of range).
const ODD_RECORDS: usize = 30_000;
/// Records per transmissive configuration (g × interface kind: 9 configurations).
const TRANSMISSIVE_RECORDS: usize = 10_000;
/// Records with `uc` on a choice's threshold.
const THRESHOLD_RECORDS: usize = 16_000;

/// The η of the Fresnel grid.
fn fresnel_etas() -> [f32; 9] {
    [1.0, 1.0 + 1e-6, 1.0 - 1e-6, 1.33, 1.5, 1.0 / 1.5, 2.4, ETA_MIN, ETA_MAX]
}

/// The opaque part of a transmissive record.
#[derive(Clone, Copy, Debug)]
struct Opaque {
    params: MetallicRoughnessParams,
    options: SpecularOptions,
    weight: f32,
}

/// One input record: a dielectric (or mixture), the directions and numbers of eval/pdf/sample,
/// and the `(cos, η)` of the Fresnel and shadow calls.
#[derive(Clone, Copy, Debug)]
struct Case {
    group: usize,
    eta: f32,
    alpha: f32,
    thin: bool,
    masking: Masking,
    tint: Vec3,
    opaque: Option<Opaque>,
    wo: Vec3,
    wi: Vec3,
    uc: f32,
    u: Vec2,
    cos: f32,
    f_eta: f32,
}

/// The Rust BSDF of a record.
#[derive(Clone, Copy)]
enum Model {
    Dielectric(Dielectric),
    Transmissive(Transmissive),
}

impl Case {
    fn dielectric(&self) -> Dielectric {
        Dielectric::new(self.eta, self.alpha, self.thin, self.masking, self.tint)
    }

    fn model(&self) -> Model {
        let d = self.dielectric();
        match self.opaque {
            None => Model::Dielectric(d),
            Some(o) => Model::Transmissive(Transmissive {
                dielectric: d,
                opaque: MetallicRoughness::new(o.params, o.options),
                weight: o.weight,
            }),
        }
    }

    fn encode(&self, out: &mut Vec<u32>) {
        let flags = u32::from(self.thin)
            | (u32::from(self.masking == Masking::HeightCorrelated) << 1)
            | (u32::from(self.opaque.is_some()) << 2);
        let o = self.opaque.unwrap_or(Opaque {
            params: MetallicRoughnessParams {
                base_color: Vec3::ZERO,
                metallic: 0.0,
                roughness: 0.0,
                specular_factor: 0.0,
                specular_color: Vec3::ZERO,
            },
            options: SpecularOptions::default(),
            weight: 1.0,
        });
        let p = o.params;
        out.push(flags);
        for x in [
            self.eta,
            self.alpha,
            self.tint.x,
            self.tint.y,
            self.tint.z,
            self.wo.x,
            self.wo.y,
            self.wo.z,
            self.wi.x,
            self.wi.y,
            self.wi.z,
            self.uc,
            self.u.x,
            self.u.y,
            self.cos,
            self.f_eta,
            o.weight,
            p.base_color.x,
            p.base_color.y,
            p.base_color.z,
            p.metallic,
            p.roughness,
            p.specular_factor,
            p.specular_color.x,
            p.specular_color.y,
            p.specular_color.z,
        ] {
            out.push(x.to_bits());
        }
        out.push(brdf::options_flags(o.options));
    }
}

impl Model {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Model::Dielectric(d) => d.eval(wo, wi),
            Model::Transmissive(t) => t.eval(wo, wi),
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Model::Dielectric(d) => d.pdf(wo, wi),
            Model::Transmissive(t) => t.pdf(wo, wi),
        }
    }

    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<ScatterSample> {
        match self {
            Model::Dielectric(d) => d.sample(wo, uc, u),
            Model::Transmissive(t) => t.sample(wo, uc, u),
        }
    }

    fn dielectric(&self) -> &Dielectric {
        match self {
            Model::Dielectric(d) => d,
            Model::Transmissive(t) => &t.dielectric,
        }
    }

    /// The opaque part and its weight 1 − g, where it takes part.
    fn opaque(&self) -> Option<(&MetallicRoughness, f32)> {
        match self {
            Model::Transmissive(t) if t.weight < 1.0 => Some((&t.opaque, 1.0 - t.weight)),
            _ => None,
        }
    }

    /// Whether some part samples directions that rounding can decide (a rough dielectric or
    /// the opaque part).
    fn has_rough_part(&self) -> bool {
        matches!(self.dielectric().interface, Interface::Rough | Interface::RoughThinWalled)
            || self.opaque().is_some()
    }
}

/// The WGSL `iface` code of a Rust interface kind.
fn interface_code(i: Interface) -> u32 {
    match i {
        Interface::Smooth => 0,
        Interface::Rough => 1,
        Interface::ThinWalled => 2,
        Interface::RoughThinWalled => 3,
    }
}

// ---------------------------------------------------------------------------------------------
// Inputs.

/// A direction with cosine `z` and azimuth `phi` (f64, rounded once).
fn dir(z: f64, phi: f64) -> Vec3 {
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32)
}

/// A cosine on either side with the edges: grazing 1e-4…1e-7 (and log-uniform down to 1e-7),
/// 1e-15, 1e-30, 0, ±1.
fn signed_cos(rng: &mut Rng) -> f64 {
    let m = match rng.below(20) {
        0 => rng.pick(&[1e-4, 1e-5, 1e-6, 1e-7]),
        1 => 10f64.powf(-7.0 + 5.0 * rng.f64()),
        2 => 1.0,
        3 => rng.pick(&[0.0, 1e-15, 1e-30]),
        _ => rng.f64().max(1e-12),
    };
    if rng.chance(0.5) { -m } else { m }
}

/// A microfacet normal a few α from the pole (where D is large).
fn tilted_normal(rng: &mut Rng, alpha: f32) -> DVec3 {
    let spread = f64::from(alpha) * 10f64.powf(-1.0 + 2.0 * rng.f64());
    DVec3::new(spread * (rng.f64() - 0.5), spread * (rng.f64() - 0.5), 1.0).normalize()
}

/// Snell refraction of `o` through the normal `m` of an interface of relative index `eta`
/// (inside over outside; `o.z > 0` is outside), `None` under total internal reflection.
fn refract(o: DVec3, m: DVec3, eta: f64) -> Option<DVec3> {
    let m = if o.dot(m) < 0.0 { -m } else { m };
    let eta_ti = if o.z > 0.0 { 1.0 / eta } else { eta };
    let c = o.dot(m);
    let t2 = 1.0 - eta_ti * eta_ti * (1.0 - c * c);
    (t2 > 0.0).then(|| (-eta_ti * o + (eta_ti * c - t2.sqrt()) * m).normalize())
}

/// `wi` for `wo`: near the reflection or refraction peak of a lobe of width α, the exact
/// mirror and Snell directions, wo, −wo, the poles, or an independent edge direction.
fn random_wi(rng: &mut Rng, wo: Vec3, alpha: f32, eta: f32) -> Vec3 {
    let o = wo.as_dvec3();
    match rng.below(20) {
        0..=4 => {
            let m = tilted_normal(rng, alpha);
            (2.0 * o.dot(m) * m - o).normalize().as_vec3()
        }
        5..=10 => {
            let m = tilted_normal(rng, alpha);
            refract(o, m, f64::from(eta)).unwrap_or(2.0 * o.dot(m) * m - o).normalize().as_vec3()
        }
        11 => Vec3::new(-wo.x, -wo.y, wo.z),
        12 => refract(o, DVec3::Z, f64::from(eta)).map_or(-wo, |v| v.as_vec3()),
        13 => wo,
        14 => -wo,
        15 => rng.pick(&[Vec3::Z, -Vec3::Z]),
        _ => dir(signed_cos(rng), TAU * rng.f64()),
    }
}

/// A uniform number with the edges 0, 2⁻²⁴, ½ and 1 − 2⁻²⁴.
fn random_u(rng: &mut Rng) -> f32 {
    if rng.chance(0.05) { rng.pick(&[0.0, U_STEP, 0.5, 1.0 - U_STEP]) } else { rng.f32() }
}

/// A tint with black, white and saturated channels.
fn random_tint(rng: &mut Rng) -> Vec3 {
    match rng.below(6) {
        0 => Vec3::ONE,
        1 => Vec3::new(1.0, 0.0, 0.5),
        _ => Vec3::new(rng.f32(), rng.f32(), rng.f32()),
    }
}

/// Opaque metallic-roughness parameters with the edges (as `furnace_tests::lobes::gltf_params`):
/// metallic 0/1, roughness 0, √ALPHA_MIN, 1, specular factor 0/1, saturating specular colours.
fn random_params(rng: &mut Rng) -> MetallicRoughnessParams {
    let colour = |rng: &mut Rng| match rng.below(10) {
        0 => Vec3::ONE,
        1 => Vec3::ZERO,
        _ => Vec3::new(rng.f32(), rng.f32(), rng.f32()),
    };
    let base_color = colour(rng);
    let metallic = match rng.below(10) {
        0..=3 => 0.0,
        4 | 5 => 1.0,
        _ => rng.f32(),
    };
    let roughness = match rng.below(10) {
        0 => 0.0,
        1 => ALPHA_MIN.sqrt(),
        2 => 1.0,
        _ => rng.f32(),
    };
    let specular_factor = match rng.below(5) {
        0 => 0.0,
        1 | 2 => 1.0,
        _ => rng.f32(),
    };
    let specular_color = match rng.below(10) {
        0..=5 => Vec3::ONE,
        6 => Vec3::splat(30.0),
        _ => 2.0 * colour(rng),
    };
    MetallicRoughnessParams { base_color, metallic, roughness, specular_factor, specular_color }
}

/// The Fresnel grid's cosines for `eta`: a uniform grid of [−1, 1], the edges (also beyond ±1),
/// and cosines around the critical angle (a few ulps and relative 1e-1…1e-7 away) on the side where it exists.
fn fresnel_cosines(rng: &mut Rng, eta: f32) -> Vec<f32> {
    let mut v: Vec<f32> = (-1000..=1000).map(|k| k as f32 / 1000.0).collect();
    // |cos| > 1 (a direction a rounding longer than unit): clamped to 1.
    for x in [
        0.0,
        1.0,
        1e-7,
        1e-20,
        1e-38,
        1e-40,
        f32::EPSILON,
        ONE_BELOW,
        1.0 - f32::EPSILON,
        0.5,
        1.0f32.next_up(),
        1.5,
        2.0,
    ] {
        v.push(x);
        v.push(-x);
    }
    let e = f64::from(eta);
    // Inside with η > 1 (η_ti = η), or outside with η < 1 (η_ti = 1/η).
    let critical = if eta > 1.0 {
        Some(-(1.0 - 1.0 / (e * e)).sqrt())
    } else if eta < 1.0 {
        Some((1.0 - e * e).sqrt())
    } else {
        None
    };
    if let Some(c) = critical {
        let cf = c as f32;
        let mut x = cf;
        let mut y = cf;
        for _ in 0..8 {
            x = x.next_up();
            y = y.next_down();
            v.push(x);
            v.push(y);
        }
        v.push(cf);
        for k in 1..=7 {
            let r = 10f64.powi(-k);
            v.push((c * (1.0 + r)).clamp(-1.0, 1.0) as f32);
            v.push((c * (1.0 - r)) as f32);
        }
    }
    for _ in 0..500 {
        v.push(rng.range(-1.0, 1.0));
    }
    v
}

/// The records and the group labels.
fn cases() -> (Vec<Case>, Vec<String>) {
    let mut rng = Rng(0xd1e1_ec7c);
    let mut labels = Vec::new();
    let mut cases = Vec::new();
    let mut group = |name: String| {
        labels.push(name);
        labels.len() - 1
    };

    // 1. The Fresnel grid, through smooth, thin and rough (α 0.3) interfaces with wo.z = cos.
    for eta in fresnel_etas() {
        let g = group(format!("fresnel η={eta}"));
        for (k, cos) in fresnel_cosines(&mut rng, eta).into_iter().enumerate() {
            let s = (1.0 - f64::from(cos).powi(2)).max(0.0).sqrt();
            let phi = TAU * rng.f64();
            let wo = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, cos);
            let alpha = if k % 3 == 2 { 0.3 } else { 0.0 };
            cases.push(Case {
                group: g,
                eta,
                alpha,
                thin: k % 3 == 1,
                masking: if rng.chance(0.5) { Masking::Separable } else { Masking::HeightCorrelated },
                tint: random_tint(&mut rng),
                opaque: None,
                wo,
                wi: random_wi(&mut rng, wo, alpha.max(0.01), eta),
                uc: random_u(&mut rng),
                u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
                cos,
                f_eta: eta,
            });
        }
    }

    // 2. Odd constructor inputs.
    let g = group("odd η/α/tint".into());
    let odd_eta = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.5,
        1e-3,
        ETA_MIN,
        ETA_MIN.next_down(),
        1.0,
        1.0 + 1e-6,
        1.0 - 1e-6,
        1.5,
        ETA_MAX,
        ETA_MAX.next_up(),
        1e3,
        f32::MAX,
        f32::MIN_POSITIVE,
    ];
    let odd_alpha = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        -1.0,
        -0.0,
        0.0,
        1e-6,
        ALPHA_MIN.next_down(),
        ALPHA_MIN,
        ALPHA_MIN.next_up(),
        0.5,
        1.0,
        1.0f32.next_up(),
        2.0,
        f32::MAX,
    ];
    let odd_tint =
        [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, -0.0, 0.0, 0.5, 1.0, 1.0f32.next_up(), 2.0];
    for _ in 0..ODD_RECORDS {
        let eta = if rng.chance(0.8) { rng.pick(&odd_eta) } else { rng.range(0.5, 3.0) };
        let alpha = if rng.chance(0.8) { rng.pick(&odd_alpha) } else { rng.f32() };
        let mut tint = random_tint(&mut rng);
        for c in 0..3 {
            if rng.chance(0.3) {
                tint[c] = rng.pick(&odd_tint);
            }
        }
        let d = Dielectric::new(eta, alpha, false, Masking::Separable, Vec3::ONE);
        let mut wo = dir(signed_cos(&mut rng), TAU * rng.f64());
        if rng.chance(0.03) {
            // Not finite: no sample, eval and pdf 0.
            wo[rng.index(3)] = rng.pick(&[f32::NAN, f32::INFINITY, f32::NEG_INFINITY]);
        }
        cases.push(Case {
            group: g,
            eta,
            alpha,
            thin: rng.chance(0.25),
            masking: if rng.chance(0.5) { Masking::Separable } else { Masking::HeightCorrelated },
            tint,
            opaque: None,
            wo,
            wi: random_wi(&mut rng, wo, d.ggx.alpha(), d.eta),
            uc: if rng.chance(0.03) { 1.0 } else { random_u(&mut rng) }, // 1: outside [0, 1), rest clamped
            u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
            cos: signed_cos(&mut rng) as f32,
            f_eta: d.eta,
        });
    }

    // 3. Rough interfaces and rough sheets: α × η × masking.
    for (alpha, thin) in [1e-4f32, 0.01, 0.1, 0.3, 1.0].into_iter().flat_map(|a| [(a, false), (a, true)]) {
        for eta in [1.5f32, 1.0 / 1.5, 1.33] {
            for masking in [Masking::Separable, Masking::HeightCorrelated] {
                let m = if masking == Masking::Separable { "sep" } else { "hc" };
                let kind = if thin { "rough sheet" } else { "rough" };
                let g = group(format!("{kind} α={alpha} η={eta:.4} {m}"));
                for _ in 0..ROUGH_RECORDS / if thin { 2 } else { 1 } {
                    let wo = dir(signed_cos(&mut rng), TAU * rng.f64());
                    cases.push(Case {
                        group: g,
                        eta,
                        alpha,
                        thin,
                        masking,
                        tint: random_tint(&mut rng),
                        opaque: None,
                        wo,
                        wi: random_wi(&mut rng, wo, alpha, eta),
                        uc: random_u(&mut rng),
                        u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
                        cos: signed_cos(&mut rng) as f32,
                        f_eta: eta,
                    });
                }
            }
        }
    }

    // 4. Smooth (α below ALPHA_MIN, or any α at η = 1) and thin-walled interfaces (smooth ones:
    // α below ALPHA_MIN, or any α at η = 1; rough sheets are in 3).
    for eta in [1.5f32, 1.0 / 1.5, 1.33, 2.4, 1.0] {
        for thin in [false, true] {
            let g = group(format!("{} η={eta:.4}", if thin { "thin" } else { "smooth" }));
            for _ in 0..DELTA_RECORDS {
                let alpha = if eta == 1.0 {
                    rng.pick(&[0.0, 0.01, 0.5, 1.0])
                } else {
                    rng.pick(&[0.0, 1e-5, ALPHA_MIN.next_down(), f32::NAN])
                };
                let wo = dir(signed_cos(&mut rng), TAU * rng.f64());
                cases.push(Case {
                    group: g,
                    eta,
                    alpha,
                    thin,
                    masking: Masking::HeightCorrelated,
                    tint: random_tint(&mut rng),
                    opaque: None,
                    wo,
                    wi: random_wi(&mut rng, wo, 0.01, eta),
                    uc: random_u(&mut rng),
                    u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
                    cos: signed_cos(&mut rng) as f32,
                    f_eta: eta,
                });
            }
        }
    }

    // 5. The transmissive mixture: g × interface kind, the opaque part's options all 12.
    let options = all_options();
    for weight in [0.3f32, 0.7, 1.0] {
        for kind in ["smooth", "rough", "thin", "rough sheet"] {
            let g = group(format!("transmissive g={weight} {kind}"));
            for _ in 0..TRANSMISSIVE_RECORDS {
                let eta = rng.pick(&[1.5f32, 1.33, 1.0 / 1.5]);
                let alpha = match kind {
                    "rough" | "rough sheet" => rng.pick(&[0.01f32, 0.1, 0.3, 1.0]),
                    _ => 0.0,
                };
                let wo = dir(signed_cos(&mut rng), TAU * rng.f64());
                let params = random_params(&mut rng);
                let opts = rng.pick(&options);
                let lobe_alpha = (params.roughness * params.roughness).max(alpha).max(1e-3);
                cases.push(Case {
                    group: g,
                    eta,
                    alpha,
                    thin: kind == "thin" || kind == "rough sheet",
                    masking: if rng.chance(0.5) { Masking::Separable } else { Masking::HeightCorrelated },
                    tint: random_tint(&mut rng),
                    opaque: Some(Opaque { params, options: opts, weight }),
                    wo,
                    wi: random_wi(&mut rng, wo, lobe_alpha, eta),
                    uc: random_u(&mut rng),
                    u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
                    cos: signed_cos(&mut rng) as f32,
                    f_eta: eta,
                });
            }
        }
    }
    // 6. uc on a choice's threshold (p, one ulp below, one above) for every kind of choice:
    // the dielectric's R or R′ (smooth, thin, rough at the sampled normal), the mixture's g, and
    // the opaque part's specular probability (uc rescaled onto it).
    let g = group("uc at a threshold".into());
    for k in 0..THRESHOLD_RECORDS {
        let eta = rng.pick(&[1.5f32, 1.33, 1.0 / 1.5, 2.4]);
        let (thin, alpha) = match k % 5 {
            0 => (false, 0.0),
            1 => (true, 0.0),
            2 => (true, rng.pick(&[0.01f32, 0.1, 0.3, 1.0])),
            _ => (false, rng.pick(&[1e-4f32, 0.01, 0.1, 0.3, 1.0])),
        };
        let opaque = rng.chance(0.4).then(|| Opaque {
            params: random_params(&mut rng),
            options: rng.pick(&options),
            weight: rng.pick(&[0.3f32, 0.7, 1.0]),
        });
        let wo = dir(signed_cos(&mut rng), TAU * rng.f64());
        let mut c = Case {
            group: g,
            eta,
            alpha,
            thin,
            masking: if rng.chance(0.5) { Masking::Separable } else { Masking::HeightCorrelated },
            tint: random_tint(&mut rng),
            opaque,
            wo,
            wi: random_wi(&mut rng, wo, alpha.max(0.01), eta),
            uc: 0.0,
            u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
            cos: wo.z,
            f_eta: eta,
        };
        let m = c.model();
        let p_d = reflection_probability(m.dielectric(), wo, c.u);
        let near = |rng: &mut Rng, p: f32| rng.pick(&[p, p.next_down(), p.next_up()]).clamp(0.0, ONE_BELOW);
        c.uc = match c.opaque {
            Some(o) if o.weight < 1.0 => {
                let g = o.weight;
                match rng.below(3) {
                    0 => near(&mut rng, g),
                    1 => solve(near(&mut rng, p_d), |uc| rescale(uc, g, true), p_d * g),
                    _ => {
                        let p_o = MetallicRoughness::new(o.params, o.options).specular_probability(wo);
                        solve(near(&mut rng, p_o), |uc| rescale(uc, g, false), g + p_o * (1.0 - g))
                    }
                }
            }
            _ => near(&mut rng, p_d),
        };
        cases.push(c);
    }
    (cases, labels)
}

/// A `uc` near `guess` (within 16 ulps) with `f(uc) == target`, else `guess`; in `[0, 1)`.
fn solve(target: f32, f: impl Fn(f32) -> f32, guess: f32) -> f32 {
    let mut lo = guess;
    let mut hi = guess;
    for _ in 0..16 {
        for x in [lo, hi] {
            if (0.0..1.0).contains(&x) && f(x) == target {
                return x;
            }
        }
        lo = lo.next_down();
        hi = hi.next_up();
    }
    guess.clamp(0.0, ONE_BELOW)
}

// ---------------------------------------------------------------------------------------------
// The kernel.

/// One invocation per record runs every function of the record; the WGSL module with what a
/// composing shader adds (the sampling and BRDF modules before it, the Turquin table binding).
fn kernel_source() -> String {
    let body = r#"
@group(0) @binding(3) var<storage, read> turquin_table: array<f32>;

fn in_f32(k: u32) -> f32 { return bitcast<f32>(input[k]); }
fn in_vec3(k: u32) -> vec3<f32> { return vec3<f32>(in_f32(k), in_f32(k + 1u), in_f32(k + 2u)); }
fn out_f32(k: u32, x: f32) { output[k] = bitcast<u32>(x); }
fn out_vec3(k: u32, v: vec3<f32>) {
    out_f32(k, v.x);
    out_f32(k + 1u, v.y);
    out_f32(k + 2u, v.z);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let b = i * 28u;  // IN_WORDS
    let flags = input[b];
    let d = dielectric_new(in_f32(b + 1u), in_f32(b + 2u), (flags & 1u) != 0u, (flags & 2u) != 0u,
                           in_vec3(b + 3u));
    let wo = in_vec3(b + 6u);
    let wi = in_vec3(b + 9u);
    let uc = in_f32(b + 12u);
    let u = vec2<f32>(in_f32(b + 13u), in_f32(b + 14u));
    let c = in_f32(b + 15u);
    let f_eta = in_f32(b + 16u);
    let o = i * 32u;  // OUT_WORDS
    let fr = fresnel_dielectric(c, f_eta);
    out_f32(o, fr.reflectance);
    out_f32(o + 1u, fr.cos_t);
    out_f32(o + 2u, fr.eta_it);
    out_f32(o + 3u, fr.eta_ti);
    out_f32(o + 4u, thin_reflectance(c, f_eta));
    out_f32(o + 5u, d.eta);
    out_f32(o + 6u, d.alpha);
    output[o + 7u] = d.iface;
    output[o + 8u] = d.height_correlated;
    out_vec3(o + 9u, d.tint);
    var e: vec3<f32>;
    var p: f32;
    var s: ScatterSample;
    var all_delta = false;
    if (flags & 4u) != 0u {
        let m = bsdf_params(in_vec3(b + 18u), in_f32(b + 21u), in_f32(b + 22u), in_f32(b + 23u),
                            in_vec3(b + 24u), input[b + 27u]);
        let t = Transmissive(d, m, in_f32(b + 17u));
        e = transmissive_eval(t, wo, wi);
        p = transmissive_pdf(t, wo, wi);
        s = transmissive_sample(t, wo, uc, u);
        all_delta = transmissive_is_delta(t);
    } else {
        e = dielectric_eval(d, wo, wi);
        p = dielectric_pdf(d, wo, wi);
        s = dielectric_sample(d, wo, uc, u);
    }
    out_vec3(o + 12u, e);
    out_f32(o + 15u, p);
    out_vec3(o + 16u, s.wi);
    out_f32(o + 19u, s.pdf);
    out_vec3(o + 20u, s.weight);
    out_f32(o + 23u, s.rest);
    output[o + 24u] = select(0u, 1u, s.valid) | select(0u, 2u, s.delta) | select(0u, 4u, s.transmitted)
        | select(0u, 8u, all_delta);
    out_vec3(o + 25u, dielectric_shadow_transmittance(d, c));
    // The dielectric's choice as dielectric_sample and transmissive_sample make it: its uniform
    // number (rescaled in a mixture, where the dielectric is chosen) and reflection probability
    // (R, R′, or R at the sampled microfacet normal: the module's own three lines).
    var uc_d = uc;
    let g = in_f32(b + 17u);
    if (flags & 4u) != 0u && g < 1.0 {
        uc_d = dielectric_rescale(uc, g, true);
    }
    var p_d: f32;
    if d.iface == DIELECTRIC_SMOOTH {
        p_d = fresnel_dielectric(wo.z, d.eta).reflectance;
    } else if d.iface == DIELECTRIC_THIN {
        p_d = thin_reflectance(wo.z, d.eta);
    } else if d.iface == DIELECTRIC_ROUGH_THIN {
        let flip = select(-1.0, 1.0, wo.z > 0.0);
        let h = brdf_ggx_sample_vndf_caps(brdf_ggx_isotropic(d.alpha), wo * flip, u) * flip;
        p_d = thin_reflectance(brdf_dot(wo, h), d.eta);
    } else {
        let flip = select(-1.0, 1.0, wo.z > 0.0);
        let h = brdf_ggx_sample_vndf_caps(brdf_ggx_isotropic(d.alpha), wo * flip, u);
        p_d = fresnel_dielectric(brdf_dot(wo, h), d.eta).reflectance;
    }
    out_f32(o + 28u, p_d);
    out_f32(o + 29u, uc_d);
}
"#;
    wgsl::compose(&[
        kernel::PREAMBLE,
        wgsl::SAMPLING,
        &brdf::declarations(),
        &wgsl::select(wgsl::BRDF, |_| true),
        wgsl::DIELECTRIC,
        body,
    ])
}

/// The GPU's outputs of one record.
#[derive(Debug)]
struct Gpu {
    reflectance: f32,
    cos_t: f32,
    eta_it: f32,
    eta_ti: f32,
    thin: f32,
    eta: f32,
    alpha: f32,
    iface: u32,
    height_correlated: u32,
    tint: Vec3,
    eval: Vec3,
    pdf: f32,
    wi: Vec3,
    s_pdf: f32,
    weight: Vec3,
    rest: f32,
    valid: bool,
    delta: bool,
    transmitted: bool,
    all_delta: bool,
    shadow: Vec3,
    p_d: f32,
    uc_d: f32,
}

fn v3(w: &[u32]) -> Vec3 {
    Vec3::new(f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2]))
}

fn decode(o: &[u32]) -> Gpu {
    let f = |k: usize| f32::from_bits(o[k]);
    Gpu {
        reflectance: f(0),
        cos_t: f(1),
        eta_it: f(2),
        eta_ti: f(3),
        thin: f(4),
        eta: f(5),
        alpha: f(6),
        iface: o[7],
        height_correlated: o[8],
        tint: v3(&o[9..]),
        eval: v3(&o[12..]),
        pdf: f(15),
        wi: v3(&o[16..]),
        s_pdf: f(19),
        weight: v3(&o[20..]),
        rest: f(23),
        valid: o[24] & 1 != 0,
        delta: o[24] & 2 != 0,
        transmitted: o[24] & 4 != 0,
        all_delta: o[24] & 8 != 0,
        shadow: v3(&o[25..]),
        p_d: f(28),
        uc_d: f(29),
    }
}

// ---------------------------------------------------------------------------------------------
// Comparison.

/// Relative error of `got` against `want` with a scale below which errors are absolute.
fn rel(got: f32, want: f32, scale: f32) -> f32 {
    if got == want {
        return 0.0;
    }
    let e = (got - want).abs() / (want.abs() + scale.max(ABS_FLOOR));
    if e.is_nan() { f32::INFINITY } else { e }
}

/// Per-channel [`rel`], the worst channel.
fn rel3(got: Vec3, want: Vec3, scale: Vec3) -> f32 {
    rel(got.x, want.x, scale.x).max(rel(got.y, want.y, scale.y)).max(rel(got.z, want.z, scale.z))
}

/// Direction error: the largest component difference (of unit vectors: relative to their norm).
fn dir_err(a: Vec3, b: Vec3) -> f32 {
    let e = (a - b).abs().max_element();
    if e.is_nan() { f32::INFINITY } else { e }
}

/// The absolute error of a number in `[0, 1)`.
fn abs_err(a: f32, b: f32) -> f32 {
    let e = (a - b).abs();
    if e.is_nan() { f32::INFINITY } else { e }
}

/// `x` one ulp down and up.
fn ulps(x: f32) -> [f32; 2] {
    [x.next_down(), x.next_up()]
}

/// `v` with one component moved by one ulp (6 vectors).
fn vec_ulps(v: Vec3) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(6);
    for axis in 0..3 {
        for x in ulps(v[axis]) {
            let mut w = v;
            w[axis] = x;
            out.push(w);
        }
    }
    out
}

/// How far `f` moves (by `metric`) when `wo` or `wi` moves by one ulp in one component.
fn dir_spread<T: Copy>(wo: Vec3, wi: Vec3, f: impl Fn(Vec3, Vec3) -> T, metric: impl Fn(T, T) -> f32) -> f32 {
    let here = f(wo, wi);
    let a = vec_ulps(wo).into_iter().map(|w| metric(f(w, wi), here));
    let b = vec_ulps(wi).into_iter().map(|w| metric(f(wo, w), here));
    a.chain(b).fold(0.0, f32::max)
}

/// How far `f` moves when `cos` or `eta` moves by one ulp.
fn scalar_spread(cos: f32, eta: f32, f: impl Fn(f32, f32) -> f32, metric: impl Fn(f32, f32) -> f32) -> f32 {
    let here = f(cos, eta);
    let a = ulps(cos).map(|c| metric(f(c, eta), here));
    let b = ulps(eta).map(|e| metric(f(cos, e), here));
    a.into_iter().chain(b).fold(0.0, f32::max)
}

/// The sample inputs one step away: `wo` moved by one ulp in a component, `u` by one sampler
/// step (within the closed square, where the warp is still defined).
fn sample_neighbours(c: &Case) -> Vec<(Vec3, Vec2)> {
    let mut v: Vec<(Vec3, Vec2)> = vec_ulps(c.wo).into_iter().map(|wo| (wo, c.u)).collect();
    for dx in [-1.0f32, 0.0, 1.0] {
        for dy in [-1.0f32, 0.0, 1.0] {
            let u = c.u + U_STEP * Vec2::new(dx, dy);
            if (dx, dy) != (0.0, 0.0) && u.cmpge(Vec2::ZERO).all() && u.cmple(Vec2::ONE).all() {
                v.push((c.wo, u));
            }
        }
    }
    v
}

/// The probability with which a dielectric reflects `wo` for `u`: R (smooth), R′ (thin), or R at
/// the sampled microfacet normal (rough), as its `sample` computes it.
fn reflection_probability(d: &Dielectric, wo: Vec3, u: Vec2) -> f32 {
    match d.interface {
        Interface::Smooth => fresnel_dielectric(wo.z, d.eta).reflectance,
        Interface::ThinWalled => thin_reflectance(wo.z, d.eta),
        Interface::Rough => {
            let flip = if wo.z > 0.0 { 1.0 } else { -1.0 };
            let h = d.ggx.sample_wm(wo * flip, u, SpecularSampling::SphericalCaps);
            fresnel_dielectric(wo.dot(h), d.eta).reflectance
        }
        Interface::RoughThinWalled => {
            let flip = if wo.z > 0.0 { 1.0 } else { -1.0 };
            let h = d.ggx.sample_wm(wo * flip, u, SpecularSampling::SphericalCaps) * flip;
            thin_reflectance(wo.dot(h), d.eta)
        }
    }
}

/// The dielectric's choice in the Rust's sample — (its uniform number, its reflection
/// probability): reflection iff `uc < p` — where the dielectric chooses (not where the mixture
/// takes the opaque part, nor for a degenerate `wo`).
fn dielectric_choice(m: &Model, wo: Vec3, uc: f32, u: Vec2) -> Option<(f32, f32)> {
    let (d, uc) = match m {
        Model::Dielectric(d) => (d, uc),
        Model::Transmissive(t) if t.weight >= 1.0 => (&t.dielectric, uc),
        Model::Transmissive(t) if uc < t.weight => (&t.dielectric, rescale(uc, t.weight, true)),
        Model::Transmissive(_) => return None,
    };
    (wo.z != 0.0 && wo.is_finite()).then(|| (uc, reflection_probability(d, wo, u)))
}

/// The opaque part's lobe choice — (its uniform number, the specular probability) — where the
/// mixture takes the opaque part.
fn opaque_choice(m: &Model, wo: Vec3, uc: f32) -> Option<(f32, f32)> {
    match m {
        Model::Transmissive(t) if t.weight < 1.0 && uc >= t.weight => {
            Some((rescale(uc, t.weight, false), t.opaque.specular_probability(wo)))
        }
        _ => None,
    }
}

/// Whether the opaque part's lobe choice sits on its boundary: its uniform number (one rounded
/// division from `uc`) within [`BOUNDARY`] of the specular probability, plus [`SPREAD_FACTOR`]
/// times how much that probability moves when `wo` moves by one ulp (the flip is not visible
/// in the outcome bits: it shows as a different direction).
fn opaque_on_boundary(m: &Model, c: &Case) -> bool {
    let Some((x, p)) = opaque_choice(m, c.wo, c.uc) else { return false };
    let spread = vec_ulps(c.wo)
        .into_iter()
        .filter_map(|wo| opaque_choice(m, wo, c.uc))
        .map(|(_, q)| abs_err(q, p))
        .fold(0.0, f32::max);
    abs_err(x, p) <= BOUNDARY + SPREAD_FACTOR * spread
}

/// (valid, delta, transmitted) of a sample.
fn outcome(s: Option<ScatterSample>) -> (bool, bool, bool) {
    s.map_or((false, false, false), |s| (true, s.delta, s.transmitted))
}

/// Where rounding alone decides a rough direction: the spherical cap's far end (`u.y → 1`: the
/// stretched normal's z is the residue `(1 − u.y)(1 + zo) − zo + zo`, and unstretching by a
/// small α turns it into any tilt), and for the opaque part with Heitz VNDF the rim of its disk
/// (`u.x → 1`; see `brdf_parity`).
fn is_rim(m: &Model, c: &Case) -> bool {
    let vndf = c.opaque.is_some_and(|o| o.options.sampling == SpecularSampling::Vndf);
    m.has_rough_part() && (c.u.y >= 1.0 - 2.0 * U_STEP || (vndf && c.u.x >= 1.0 - 2.0 * U_STEP))
}

/// The opaque part's absolute rounding scale at (wo, wi), times its weight: the unattenuated
/// diffuse term albedo·cos θi/π (its attenuation 1 − sF·max F cancels towards 0) plus the
/// specular lobe at full Fresnel (Schlick's (1 − cos θd)⁵ in a channel with F0 ≈ 0 is relatively
/// ill-conditioned, absolutely tiny); as in `brdf_parity`.
fn opaque_scale(m: &Model, wo: Vec3, wi: Vec3) -> Vec3 {
    let Some((bsdf, w)) = m.opaque() else { return Vec3::ZERO };
    let diffuse = if wo.z > furnace_brdf::MIN_COS && wi.z > furnace_brdf::MIN_COS {
        bsdf.diffuse.albedo * (wi.z / std::f32::consts::PI)
    } else {
        Vec3::ZERO
    };
    let s = bsdf.specular;
    let full = Vec3::splat(s.f0.max_element().max(s.f90.max_element()));
    w * (diffuse + GgxSpecular { f0: full, f90: full, ..s }.eval(wo, wi))
}

/// Compared quantities (the table's columns).
const COLS: [&str; 15] = [
    "R", "cos_t", "eta_it", "eta_ti", "thin R'", "new", "eval", "pdf", "s.wi", "s.pdf", "s.weight", "s.rest",
    "shadow", "p", "choice",
];
/// The GPU's reflection probability for its sample against the Rust's.
const P_COL: usize = 13;
/// The GPU's choice against its own uniform number and probability (strict) and its uniform
/// number against the Rust's.
const CHOICE_COL: usize = 14;

/// The largest error of one quantity and the record where it occurred.
#[derive(Default, Clone, Copy)]
struct Worst {
    err: f32,
    at: Option<usize>,
}

impl Worst {
    fn add(&mut self, err: f32, k: usize) {
        if self.at.is_none() || err > self.err {
            self.err = err;
            self.at = Some(k);
        }
    }
}

/// Per group: the worst well-conditioned error per column and the counts of special cases.
#[derive(Default, Clone)]
struct Stats {
    n: usize,
    worst: [Worst; COLS.len()],
    /// The largest error per column including the ill-conditioned values accepted.
    raw: [f32; COLS.len()],
    /// Values accepted as ill-conditioned, and the largest error / (REL_TOL + 4·spread) among them.
    ill: usize,
    ill_ratio: f32,
    /// Choices that differ with uc within the boundary margin.
    boundary: usize,
    /// None/sample or outcome flips that one input ulp / sampler step of the Rust reproduces,
    /// or whose direction grazes the interface within rounding.
    flips: usize,
    /// Samples whose direction rounding decides (only pdf/weight at the GPU's wi checked).
    rim: usize,
}

/// A record that fails: the column, how far beyond its tolerance (err/tol), why.
struct Failure {
    k: usize,
    col: &'static str,
    ratio: f32,
    why: String,
}

/// Judges one value: within [`REL_TOL`] (its error goes into the table), else ill-conditioned
/// within `REL_TOL + SPREAD_FACTOR·spread()` (counted), else a failure.
fn judge(
    st: &mut Stats,
    fails: &mut Vec<Failure>,
    k: usize,
    col: usize,
    err: f32,
    spread: impl FnOnce() -> f32,
) {
    if err <= REL_TOL {
        st.worst[col].add(err, k);
        st.raw[col] = st.raw[col].max(err);
        return;
    }
    let spread = spread();
    let tol = REL_TOL + SPREAD_FACTOR * spread;
    if err <= tol {
        st.raw[col] = st.raw[col].max(err);
        st.ill += 1;
        st.ill_ratio = st.ill_ratio.max(err / tol);
    } else {
        fails.push(Failure {
            k,
            col: COLS[col],
            ratio: err / tol,
            why: format!("error {err:e}, tolerance {tol:e} (one-step spread {spread:e})"),
        });
    }
}

/// The GPU's dielectric choice against its own uniform number and probability, and those
/// against the Rust's: `p` within Fresnel's tolerance (or its one-step spread), the uniform
/// number (one division from `uc` in a mixture) within [`REL_TOL`], and — strictly — the GPU's
/// sample consistent with them: transmitted iff `!(uc < p)`, rest = `rescale(uc, p, taken)`
/// (within [`REL_TOL`]: one division) and in `[0, 1)` (also for `uc` = 1, outside the domain). The strict part catches a `<` turned `<=` where `uc` is
/// exactly `p` (the threshold group puts it there); it assumes the kernel's copy of the three
/// lines that compute `p` (see [`kernel_source`]) rounds as the module's own, true of any
/// compiler that does not reassociate.
fn check_choice(c: &Case, m: &Model, g: &Gpu, k: usize, st: &mut Stats, fails: &mut Vec<Failure>) {
    let Some((x, p)) = dielectric_choice(m, c.wo, c.uc, c.u) else { return };
    let near = sample_neighbours(c);
    judge(st, fails, k, P_COL, rel(g.p_d, p, FRESNEL_SCALE), || {
        near.iter()
            .filter_map(|&(wo, u)| dielectric_choice(m, wo, c.uc, u))
            .map(|(_, q)| rel(q, p, FRESNEL_SCALE))
            .fold(0.0, f32::max)
    });
    let uc_err = rel(g.uc_d, x, 0.0);
    let mut why = String::new();
    if !(uc_err <= REL_TOL) {
        why = format!("the dielectric's uc {:e} vs Rust {x:e}", g.uc_d);
    }
    let mut rest_err = 0.0;
    if g.valid {
        let taken = g.uc_d < g.p_d;
        rest_err = abs_err(g.rest, rescale(g.uc_d, g.p_d, taken));
        if !(0.0..1.0).contains(&g.rest) {
            why = format!("rest {:e} outside [0, 1)", g.rest);
        } else if g.transmitted == taken {
            why = format!("transmitted {} but uc {:e} < p {:e} is {taken}", g.transmitted, g.uc_d, g.p_d);
        } else if !(rest_err <= REL_TOL) {
            why = format!("rest {:e} vs rescale(uc, p) {:e}", g.rest, rescale(g.uc_d, g.p_d, taken));
        }
    }
    if why.is_empty() {
        st.worst[CHOICE_COL].add(uc_err.max(rest_err), k);
    } else {
        fails.push(Failure { k, col: "choice", ratio: f32::INFINITY, why });
    }
}

/// The Rust's sample of a record, its pdf/weight evaluated at another direction, and the
/// value comparisons of one sample.
fn check_sample(c: &Case, m: &Model, g: &Gpu, k: usize, st: &mut Stats, fails: &mut Vec<Failure>) {
    check_choice(c, m, g, k, st, fails);
    let rust = m.sample(c.wo, c.uc, c.u);
    let gpu_out = (g.valid, g.valid && g.delta, g.valid && g.transmitted);
    let near = sample_neighbours(c);
    let rim = is_rim(m, c);
    // Where the dielectric chooses, the two sides chose differently: the uniform number lies
    // between the two probabilities (each side's consistency and p's closeness are checked
    // in check_choice).
    let dielectric_flip =
        dielectric_choice(m, c.wo, c.uc, c.u).is_some_and(|(x, p)| (x < p) != (g.uc_d < g.p_d));
    if outcome(rust) != gpu_out {
        // A degenerate wo (in the plane, not finite) gives None exactly; otherwise the choice,
        // or the validity, differs legitimately on a choice's boundary, where a neighbouring
        // input of the Rust gives the GPU's outcome, at the horizon, or at the rim.
        let degenerate = !(c.wo.z != 0.0 && c.wo.is_finite());
        if degenerate {
        } else if dielectric_flip || opaque_on_boundary(m, c) {
            st.boundary += 1;
            return;
        } else if near.iter().any(|&(wo, u)| outcome(m.sample(wo, c.uc, u)) == gpu_out)
            || rust.map(|s| s.wi).or(g.valid.then_some(g.wi)).is_some_and(|wi| wi.z.abs() <= HORIZON_ROUNDING)
        {
            st.flips += 1;
            return;
        } else if rim {
            st.rim += 1;
            return;
        }
        fails.push(Failure {
            k,
            col: "s.outcome",
            ratio: f32::INFINITY,
            why: format!(
                "valid/delta/transmitted: GPU {gpu_out:?}, Rust {:?}; not a choice on its boundary, nor one step \
                 away",
                outcome(rust)
            ),
        });
        return;
    }
    let Some(s) = rust else { return };

    // Against the Rust sample, and for a non-delta sample also against the Rust's pdf and
    // eval/pdf at the GPU's own wi (what the Rust computes once it has a direction: for a sharp
    // lobe the GPU's direction, ~1e-7 from the Rust's, alone moves D by ~4δ/α); the smaller
    // difference counts.
    let at_gpu = (!s.delta).then(|| {
        let pdf = m.pdf(c.wo, g.wi);
        (pdf, m.eval(c.wo, g.wi) / pdf)
    });
    let pdf_scale = if s.delta { FRESNEL_SCALE } else { 0.0 };
    let w_scale = |wi: Vec3, pdf: f32| (opaque_scale(m, c.wo, wi) / pdf).max(Vec3::splat(WEIGHT_FLOOR));
    let mut pdf_err = rel(g.s_pdf, s.pdf, pdf_scale);
    let mut weight_err = rel3(g.weight, s.weight, w_scale(s.wi, s.pdf));
    if let Some((pdf, weight)) = at_gpu {
        pdf_err = pdf_err.min(rel(g.s_pdf, pdf, 0.0));
        weight_err = weight_err.min(rel3(g.weight, weight, w_scale(g.wi, pdf)));
    }
    let wi_err = dir_err(g.wi, s.wi);
    let rest_err = abs_err(g.rest, s.rest);
    let errs = [(8, wi_err), (9, pdf_err), (10, weight_err), (11, rest_err)];
    if errs.iter().all(|&(_, e)| e <= REL_TOL) {
        for (col, e) in errs {
            st.worst[col].add(e, k);
            st.raw[col] = st.raw[col].max(e);
        }
        return;
    }
    // A lobe of the opaque part chosen differently (not visible in the outcome bits).
    if wi_err > 1e-3 && opaque_on_boundary(m, c) {
        st.boundary += 1;
        return;
    }
    // Spreads: the Rust sample one step away with the same outcome; pdf and weight also as
    // functions of the GPU's wi one ulp around it.
    let same: Vec<ScatterSample> = near
        .iter()
        .filter_map(|&(wo, u)| m.sample(wo, c.uc, u))
        .filter(|n| (n.delta, n.transmitted) == (s.delta, s.transmitted))
        .collect();
    let wi_spread = same.iter().map(|n| dir_err(n.wi, s.wi)).fold(0.0, f32::max);
    let mut pdf_spread = same.iter().map(|n| rel(n.pdf, s.pdf, pdf_scale)).fold(0.0, f32::max);
    let mut weight_spread =
        same.iter().map(|n| rel3(n.weight, s.weight, Vec3::splat(WEIGHT_FLOOR))).fold(0.0, f32::max);
    if at_gpu.is_some() {
        pdf_spread = pdf_spread.max(dir_spread(c.wo, g.wi, |a, b| m.pdf(a, b), |x, y| rel(x, y, 0.0)));
        weight_spread = weight_spread.max(dir_spread(
            c.wo,
            g.wi,
            |a, b| m.eval(a, b) / m.pdf(a, b),
            |x, y| rel3(x, y, Vec3::splat(WEIGHT_FLOOR)),
        ));
    }
    // rest = rescale(uc, p): a function of the probability, whose difference check_choice
    // checks (and the GPU's rest against its own p, strictly); here its one-step movement and
    // the movement that the GPU's p accounts for.
    let mut rest_spread = same.iter().map(|n| abs_err(n.rest, s.rest)).fold(0.0, f32::max);
    if dielectric_choice(m, c.wo, c.uc, c.u).is_some() && g.valid {
        rest_spread = rest_spread.max(abs_err(rescale(g.uc_d, g.p_d, !s.transmitted), s.rest));
    }
    let ok = |err: f32, spread: f32| err <= REL_TOL + SPREAD_FACTOR * spread;
    let values_ok = ok(pdf_err, pdf_spread) && ok(weight_err, weight_spread) && ok(rest_err, rest_spread);
    let ratio = errs
        .iter()
        .zip([wi_spread, pdf_spread, weight_spread, rest_spread])
        .map(|(&(_, e), sp)| e / (REL_TOL + SPREAD_FACTOR * sp))
        .fold(0.0, f32::max);
    if ok(wi_err, wi_spread) && values_ok {
        for (col, e) in errs {
            st.raw[col] = st.raw[col].max(e);
        }
        st.ill += 1;
        st.ill_ratio = st.ill_ratio.max(ratio);
    } else if rim && values_ok {
        st.rim += 1;
    } else {
        fails.push(Failure {
            k,
            col: "sample",
            ratio,
            why: format!(
                "wi {wi_err:e} (one-step spread {wi_spread:e}), pdf {pdf_err:e} ({pdf_spread:e}), weight \
                 {weight_err:e} ({weight_spread:e}), rest {rest_err:e} ({rest_spread:e})"
            ),
        });
    }
}

/// A Rust function of (cos, η), to measure its one-ulp spread.
type ScalarFn = fn(f32, f32) -> f32;

/// Checks one record: every column.
fn check_record(c: &Case, g: &Gpu, k: usize, st: &mut Stats, fails: &mut Vec<Failure>) {
    st.n += 1;
    // Fresnel: R and R′ absolutely within 1e-6 (FRESNEL_SCALE), cos θt and the index ratios
    // relatively; spread over one ulp of cos and η.
    let (cos, eta) = (c.cos, c.f_eta);
    let fr = fresnel_dielectric(cos, eta);
    let fields: [(f32, f32, f32, ScalarFn); 5] = [
        (g.reflectance, fr.reflectance, FRESNEL_SCALE, |c, e| fresnel_dielectric(c, e).reflectance),
        (g.cos_t, fr.cos_t, 0.0, |c, e| fresnel_dielectric(c, e).cos_t),
        (g.eta_it, fr.eta_it, 0.0, |c, e| fresnel_dielectric(c, e).eta_it),
        (g.eta_ti, fr.eta_ti, 0.0, |c, e| fresnel_dielectric(c, e).eta_ti),
        (g.thin, thin_reflectance(cos, eta), FRESNEL_SCALE, thin_reflectance),
    ];
    for (col, (got, want, scale, f)) in fields.into_iter().enumerate() {
        judge(st, fails, k, col, rel(got, want, scale), || {
            scalar_spread(cos, eta, f, |x, y| rel(x, y, scale))
        });
    }

    // The constructor: bit for bit (clamps and selects only; -0 == 0).
    let m = c.model();
    let d = m.dielectric();
    let new_ok = g.eta == d.eta
        && g.alpha == d.ggx.alpha()
        && g.iface == interface_code(d.interface)
        && g.height_correlated == u32::from(d.masking == Masking::HeightCorrelated)
        && g.tint == d.tint;
    if new_ok {
        st.worst[5].add(0.0, k);
    } else {
        fails.push(Failure {
            k,
            col: "new",
            ratio: f32::INFINITY,
            why: format!(
                "dielectric_new: GPU η {:e} α {:e} iface {} hc {} tint {:?}; Rust η {:e} α {:e} {:?} {:?} tint {:?}",
                g.eta,
                g.alpha,
                g.iface,
                g.height_correlated,
                g.tint,
                d.eta,
                d.ggx.alpha(),
                d.interface,
                d.masking,
                d.tint
            ),
        });
    }
    if let Model::Transmissive(t) = &m
        && g.all_delta != t.is_delta()
    {
        fails.push(Failure {
            k,
            col: "is_delta",
            ratio: f32::INFINITY,
            why: format!("transmissive_is_delta {} vs Rust {}", g.all_delta, t.is_delta()),
        });
    }

    // eval and pdf: relative (eval per channel, plus the opaque part's absolute scale); spread
    // over one ulp of each component of wo and wi.
    let (wo, wi) = (c.wo, c.wi);
    let e = m.eval(wo, wi);
    let scale = opaque_scale(&m, wo, wi);
    judge(st, fails, k, 6, rel3(g.eval, e, scale), || {
        dir_spread(wo, wi, |a, b| m.eval(a, b), |x, y| rel3(x, y, scale))
    });
    judge(st, fails, k, 7, rel(g.pdf, m.pdf(wo, wi), 0.0), || {
        dir_spread(wo, wi, |a, b| m.pdf(a, b), |x, y| rel(x, y, 0.0))
    });

    check_sample(c, &m, g, k, st, fails);

    // Shadow transmittance: T′·tint, absolutely within 1e-6 of the tint (T′ = 1 − R′ cancels).
    let tint_scale = d.tint * FRESNEL_SCALE;
    judge(st, fails, k, 12, rel3(g.shadow, d.shadow_transmittance(cos), tint_scale), || {
        ulps(cos)
            .into_iter()
            .map(|x| rel3(d.shadow_transmittance(x), d.shadow_transmittance(cos), tint_scale))
            .fold(0.0, f32::max)
    });
}

/// A record's inputs, the GPU's and the Rust's outputs, for a failure report.
fn describe(k: usize, c: &Case, label: &str, g: &Gpu) -> String {
    let m = c.model();
    let fr = fresnel_dielectric(c.cos, c.f_eta);
    format!(
        "record {k} ({label}): η {:e} α {:e} thin {} {:?} tint {:?}{}\n  wo {:?} wi {:?} uc {:e} u {:?} cos {:e} \
         fresnel η {:e}\n  Rust: fresnel {fr:?} thin {:e} eval {:?} pdf {:e} sample {:?} shadow {:?} choice \
         (uc, p) {:?} opaque choice {:?}\n  GPU:  {g:?}",
        c.eta,
        c.alpha,
        c.thin,
        c.masking,
        c.tint,
        c.opaque.map_or(String::new(), |o| format!(" opaque {o:?}")),
        c.wo,
        c.wi,
        c.uc,
        c.u,
        c.cos,
        c.f_eta,
        thin_reflectance(c.cos, c.f_eta),
        m.eval(c.wo, c.wi),
        m.pdf(c.wo, c.wi),
        m.sample(c.wo, c.uc, c.u),
        m.dielectric().shadow_transmittance(c.cos),
        dielectric_choice(&m, c.wo, c.uc, c.u),
        opaque_choice(&m, c.wo, c.uc),
    )
}

#[test]
fn dielectric_matches_furnace_brdf() {
    let Some(ctx) = test_context() else { return };
    eprintln!("adapter: {}", ctx.describe());
    let t0 = std::time::Instant::now();
    let (cases, labels) = cases();
    let mut input = Vec::with_capacity(cases.len() * IN_WORDS);
    for c in &cases {
        c.encode(&mut input);
    }
    assert_eq!(input.len(), cases.len() * IN_WORDS);
    let table = brdf::turquin_table();
    let t1 = std::time::Instant::now();
    let out = kernel::run_with(
        &ctx,
        &kernel_source(),
        &input,
        &[bytemuck::cast_slice(&table)],
        cases.len() * OUT_WORDS,
        cases.len() as u32,
    )
    .unwrap();
    let gpu_time = t1.elapsed();

    let mut stats = vec![Stats::default(); labels.len()];
    let mut fails = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let g = decode(&out[k * OUT_WORDS..(k + 1) * OUT_WORDS]);
        check_record(c, &g, k, &mut stats[c.group], &mut fails);
    }

    let mut table = String::new();
    let _ = write!(table, "| group | n |");
    for col in COLS {
        let _ = write!(table, " {col} |");
    }
    let _ = writeln!(table, " ill (worst err/tol) | boundary | flips | rim |");
    let _ = writeln!(table, "|---|---|{}---|---|---|---|", "---|".repeat(COLS.len()));
    for (st, label) in stats.iter().zip(&labels) {
        let _ = write!(table, "| {label} | {} |", st.n);
        for w in &st.worst {
            let _ = write!(table, " {:.1e} |", w.err);
        }
        let _ = writeln!(
            table,
            " {} ({:.2}) | {} | {} | {} |",
            st.ill, st.ill_ratio, st.boundary, st.flips, st.rim
        );
    }
    let _ = write!(table, "| all, ill-conditioned included | {} |", cases.len());
    for col in 0..COLS.len() {
        let _ = write!(table, " {:.1e} |", stats.iter().map(|s| s.raw[col]).fold(0.0, f32::max));
    }
    let _ = writeln!(table, " | | | |");
    eprintln!(
        "{} records; GPU {gpu_time:.2?} (compile and dispatch), total {:.2?}\nmax relative error per \
         column over the well-conditioned values (R, R', shadow: relative to value + {FRESNEL_SCALE}; s.wi: \
         component difference; s.rest: absolute); counts of the others:\n{table}",
        cases.len(),
        t0.elapsed()
    );

    let n = cases.len();
    let total = |f: fn(&Stats) -> usize| stats.iter().map(f).sum::<usize>();
    let (ill, boundary, flips, rim) =
        (total(|s| s.ill), total(|s| s.boundary), total(|s| s.flips), total(|s| s.rim));
    // uc within the margin of p: ~1e-6 of the random samples plus the near-critical Fresnel
    // records, 1e-4 of them; any of the records put on a threshold on purpose.
    let boundary_bound = THRESHOLD_RECORDS + ((n - THRESHOLD_RECORDS) as f64 * 1e-4).ceil() as usize;
    // Ill-conditioned values, flips and rim cases: edge u (5% of each coordinate), the critical
    // angle grid, grazing directions, sharp lobes; 2% of the records each.
    let bound = n / 50;
    fails.sort_by(|a, b| b.ratio.total_cmp(&a.ratio));
    let mut report = String::new();
    for f in fails.iter().take(20) {
        let c = &cases[f.k];
        let g = decode(&out[f.k * OUT_WORDS..(f.k + 1) * OUT_WORDS]);
        let _ = writeln!(
            report,
            "{} (err/tol {:.3e}): {}\n{}\n",
            f.col,
            f.ratio,
            f.why,
            describe(f.k, c, &labels[c.group], &g)
        );
    }
    let mut per_col = std::collections::BTreeMap::<&str, usize>::new();
    for f in &fails {
        *per_col.entry(f.col).or_default() += 1;
    }
    assert!(
        fails.is_empty() && boundary <= boundary_bound && ill <= bound && flips <= bound && rim <= bound,
        "WGSL dielectric differs from furnace-brdf: {} failures {per_col:?}; boundary choices {boundary} (bound \
         {boundary_bound}), ill-conditioned {ill}, flips {flips}, rim {rim} (bound {bound} each). The worst:\n{report}",
        fails.len()
    );
}

/// The module's hand-kept constants equal the Rust's, bit for bit, and it declares no bindings.
#[test]
fn constants_match_rust() {
    let src = wgsl::compose(&[
        wgsl::SAMPLING,
        &brdf::declarations(),
        &wgsl::select(wgsl::BRDF, |_| true),
        wgsl::DIELECTRIC,
        "@group(0) @binding(0) var<storage, read> turquin_table: array<f32>;",
    ]);
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let constant = |name: &str| -> naga::Literal {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no const {name} in dielectric.wgsl"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(l) => l,
            ref e => panic!("const {name} is not a literal: {e:?}"),
        }
    };
    let f = |name: &str, want: f32| match constant(name) {
        naga::Literal::F32(v) => assert_eq!(v.to_bits(), want.to_bits(), "{name}: {v:e} vs {want:e}"),
        l => panic!("{name} is not f32: {l:?}"),
    };
    f("DIELECTRIC_ETA_MIN", ETA_MIN);
    f("DIELECTRIC_ETA_MAX", ETA_MAX);
    f("DIELECTRIC_ONE_BELOW", ONE_BELOW);
    for (name, i) in [
        ("DIELECTRIC_SMOOTH", Interface::Smooth),
        ("DIELECTRIC_ROUGH", Interface::Rough),
        ("DIELECTRIC_THIN", Interface::ThinWalled),
        ("DIELECTRIC_ROUGH_THIN", Interface::RoughThinWalled),
    ] {
        assert_eq!(constant(name), naga::Literal::U32(interface_code(i)), "{name}");
    }
    let globals: Vec<_> = module.global_variables.iter().filter_map(|(_, g)| g.name.clone()).collect();
    assert_eq!(globals, ["turquin_table"], "dielectric.wgsl must not declare bindings");
    assert!(!wgsl::DIELECTRIC.contains("@binding") && !wgsl::DIELECTRIC.contains("@group"));
}
