//! Parity of the WGSL BSDF (`src/wgsl/brdf.wgsl`) with `furnace-brdf`'s `MetallicRoughness`:
//! eval, pdf and sample on the same inputs, for every row of the table of lobes [`LOBES`]
//! (`furnace_tests::lobes`, shared with the chi-square, consistency and white-furnace tests; a
//! new lobe adds a row there) and each of its `SpecularOptions` combinations, plus the WGSL
//! constructor, the Turquin lookup, the constants and the record layout.
//!
//! The WGSL evaluates every lobe inside the glTF record `BsdfParams`, so a row's records are
//! materials drawn by the row with only its lobe on (Lambert: metallic 0, specularFactor 0; GGX:
//! metallic 1), and the glTF material's row draws the whole mixture with its edges; each group
//! (row × options) is checked and reported on its own, each row's counts bounded on their own.
//!
//! `cargo test -p furnace-tests --test all brdf_parity:: -- --nocapture` prints the table of maximum
//! errors per function and configuration.
//!
//! eval and pdf get identical inputs on both sides and are compared directly (relative 1e-5,
//! eval per channel relative to the value plus the lobes at full Fresnel — Fresnel errors are
//! absolute).
//! A sample is compared in three ways (see `check`): the lobe must be the same (a flip is
//! allowed only where `uc` sits within 1e-6 of the specular probability; counted and bounded);
//! wi within 1e-5 of the Rust's; pdf and weight within 1e-5 of the Rust sample's or of the Rust
//! evaluated at the GPU's wi (what the Rust mixture computes once it has a direction). Where
//! the Rust itself moves by more than the tolerance within one sampler step of `u` (the warps'
//! singular edges, grazing reflections) the sample is accepted within a multiple of that
//! movement, and where rounding alone decides the direction (Heitz VNDF at the rim of its disk)
//! only its pdf and weight at its own wi are checked; both are counted and bounded.

use furnace_tests::Rng;

use furnace_brdf::ggx::ALPHA_MIN;
use furnace_brdf::iridescence::ThinFilm;
use furnace_brdf::{
    Bsdf, Masking, MetallicRoughness, MetallicRoughnessParams, SpecularOptions, SpecularSampling,
};
use furnace_gpu::brdf::{self, BsdfParams};
use furnace_gpu::wgsl;
use furnace_tests::gpu::{self as kernel, test_context};
use furnace_tests::lobes::{LOBES, all_options, anisotropy_strength, film_params, gltf_params};
use glam::{Vec2, Vec3};
use std::f64::consts::TAU;
use std::fmt::Write as _;

/// Relative tolerance of every floating-point comparison (the issue's bar). The GPU evaluates
/// the same formulas in the same order; what differs is the rounding of `sqrt`, division,
/// `sin`/`cos`, `exp2`/`log2` (cbrt) and possible fused multiply-adds, a few ulp (≈ 1e-7) each,
/// so 1e-5 leaves two orders of magnitude for error growth through a dozen operations.
const REL_TOL: f32 = 1e-5;

/// Absolute floor below which values count as equal: far below any radiance, pdf or weight
/// that matters, and above what flushing subnormal intermediates to zero (allowed in WGSL) or
/// a Fresnel term (1 − cos θd)⁵ of a vanishing 1 − cos θd (1e-7⁵ = 1e-35) can change.
const ABS_FLOOR: f32 = 1e-20;

/// Weight channels are compared relative to themselves or, below it, to this absolute floor
/// (weights are O(0.01…20)): Schlick's F = F0 + (F90 − F0)(1 − cos θd)⁵ in a channel with
/// F0 ≈ 0 near normal incidence is ≈ F90·(1 − cos θd)⁵, relatively ill-conditioned
/// (5·δ/(1 − cos θd), with δ ~ 1e-7 from the sampled normal's rounding) but tiny; an absolute
/// error of 1e-11 in a path weight changes no radiance a renderer resolves.
const WEIGHT_FLOOR: f32 = 1e-6;

/// Materials per group (row × options; records pick one at random). Each record runs eval,
/// pdf and sample, so every function sees a row's `records_per_option` inputs per group.
const MATERIALS_PER_CONFIG: usize = 2048;

/// Words per input record: material index, wo (3), wi (3), uc, u (2).
const IN_WORDS: usize = 10;
/// Words per output record: eval (3), pdf, sample wi (3), pdf, weight (3), lobe.
const OUT_WORDS: usize = 12;

fn config_name(o: SpecularOptions) -> String {
    let m = match o.masking {
        Masking::Separable => "sep",
        Masking::HeightCorrelated => "hc",
    };
    let s = match o.sampling {
        SpecularSampling::Ndf => "ndf",
        SpecularSampling::Vndf => "vndf",
        SpecularSampling::SphericalCaps => "caps",
    };
    format!("{m}/{s}/{}", if o.compensation { "comp" } else { "nocomp" })
}

/// A direction with cosine `z` and azimuth `phi` (f64, rounded once).
fn dir(z: f64, phi: f64) -> Vec3 {
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32)
}

/// A cosine with the edges: grazing 1e-4…1e-7 and around MIN_COS, normal incidence, 0, below.
fn random_cos(rng: &mut Rng) -> f64 {
    match rng.next_u64() % 20 {
        0 => rng.pick(&[1e-4, 1e-5, 1e-6, 1e-7]),
        1 => 10f64.powf(-7.0 + 5.0 * rng.f64()), // log-uniform in [1e-7, 1e-2]
        2 => 1.0,
        3 => rng.pick(&[0.0, 1e-15, 2e-15, 5e-16, -1e-7]),
        4 | 5 => -rng.f64(), // below the horizon
        _ => rng.f64().max(1e-12),
    }
}

/// `wi` for `wo`: independent, near the mirror direction (inside the lobe of α), the exact
/// mirror, `wi = wo`, `wi = −wo`, or an independent edge cosine.
fn random_wi(rng: &mut Rng, wo: Vec3, alpha: f32) -> Vec3 {
    match rng.next_u64() % 20 {
        0..=5 => {
            // Reflect about a microfacet normal a few α from the pole: where D is large.
            let spread = alpha as f64 * 10f64.powf(-1.0 + 2.0 * rng.f64());
            let (a, b) = (spread * (rng.f64() - 0.5), spread * (rng.f64() - 0.5));
            let n = glam::DVec3::new(a, b, 1.0).normalize();
            let o = wo.as_dvec3();
            (2.0 * o.dot(n) * n - o).normalize().as_vec3()
        }
        6 => Vec3::new(-wo.x, -wo.y, wo.z),
        7 => wo,
        8 => -wo,
        9 => Vec3::Z,
        _ => dir(random_cos(rng), TAU * rng.f64()),
    }
}

/// A uniform number with the edges 0, 2⁻²⁴, ½ and 1 − 2⁻²⁴.
fn random_u(rng: &mut Rng) -> f32 {
    if rng.chance(0.05) {
        rng.pick(&[0.0, 1.0 / 16_777_216.0, 0.5, 1.0 - 1.0 / 16_777_216.0])
    } else {
        rng.f32()
    }
}

/// One group of records: a row of [`LOBES`] and one option combination.
struct Group {
    /// The row's index in [`LOBES`].
    row: usize,
    options: SpecularOptions,
}

impl Group {
    fn name(&self) -> String {
        format!("{} {}", LOBES[self.row].name, config_name(self.options))
    }
}

struct Record {
    group: usize,
    material: u32,
    wo: Vec3,
    wi: Vec3,
    uc: f32,
    u: Vec2,
}

/// The WGSL side: one invocation per record runs all three functions.
fn parity_kernel() -> String {
    let body = r#"
@group(0) @binding(3) var<storage, read> materials: array<BsdfParams>;
@group(0) @binding(4) var<storage, read> turquin_table: array<f32>;

fn in_f32(k: u32) -> f32 { return bitcast<f32>(input[k]); }
fn in_vec3(k: u32) -> vec3<f32> { return vec3<f32>(in_f32(k), in_f32(k + 1u), in_f32(k + 2u)); }
fn out_vec3(k: u32, v: vec3<f32>) {
    output[k] = bitcast<u32>(v.x);
    output[k + 1u] = bitcast<u32>(v.y);
    output[k + 2u] = bitcast<u32>(v.z);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let b = i * 10u;
    let m = materials[input[b]];
    let wo = in_vec3(b + 1u);
    let wi = in_vec3(b + 4u);
    let e = bsdf_eval(m, wo, wi);
    let p = bsdf_pdf(m, wo, wi);
    let s = bsdf_sample(m, wo, in_f32(b + 7u), vec2<f32>(in_f32(b + 8u), in_f32(b + 9u)));
    let o = i * 12u;
    out_vec3(o, e);
    output[o + 3u] = bitcast<u32>(p);
    out_vec3(o + 4u, s.wi);
    output[o + 7u] = bitcast<u32>(s.pdf);
    out_vec3(o + 8u, s.weight);
    output[o + 11u] = s.lobe;
}
"#;
    kernel::brdf_kernel(body)
}

fn words<T: bytemuck::Pod>(v: &[T]) -> Vec<u32> {
    bytemuck::cast_slice(v).to_vec()
}

fn v3(w: &[u32]) -> Vec3 {
    Vec3::new(f32::from_bits(w[0]), f32::from_bits(w[1]), f32::from_bits(w[2]))
}

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

/// The largest error of one quantity and the input where it occurred.
#[derive(Default, Clone)]
struct Worst {
    err: f32,
    at: Option<usize>,
    n: usize,
}

impl Worst {
    fn add(&mut self, err: f32, k: usize) {
        self.n += 1;
        if err > self.err || self.at.is_none() {
            self.err = self.err.max(err);
            if err >= self.err {
                self.at = Some(k);
            }
        }
    }
}

/// The Rust twin's outputs, for a failure report.
fn describe(
    k: usize,
    rec: &Record,
    p: &MetallicRoughnessParams,
    bsdf: &MetallicRoughness,
    out: &[u32],
) -> String {
    let s = bsdf.sample(rec.wo, rec.uc, rec.u);
    format!(
        "record {k}: params {p:?} film {:?}\n  wo {:?} wi {:?} uc {:e} u {:?}\n  \
         Rust eval {:?} pdf {:e} sample {:?} (p_spec {})\n  \
         WGSL eval {:?} pdf {:e} sample wi {:?} pdf {:e} weight {:?} lobe {}",
        bsdf.specular.iridescence,
        rec.wo,
        rec.wi,
        rec.uc,
        rec.u,
        bsdf.eval(rec.wo, rec.wi),
        bsdf.pdf(rec.wo, rec.wi),
        s,
        bsdf.specular_probability(rec.wo),
        v3(&out[0..3]),
        f32::from_bits(out[3]),
        v3(&out[4..7]),
        f32::from_bits(out[7]),
        v3(&out[8..11]),
        out[11]
    )
}

#[test]
fn eval_pdf_sample_match_furnace_brdf() {
    let Some(ctx) = test_context() else { return };
    eprintln!("adapter: {}", ctx.describe());
    // Per row: MATERIALS_PER_CONFIG materials per option combination (the Rust records built by
    // BsdfParams::new), then the row's records, all from the row's generator.
    let mut groups = Vec::new();
    let mut params = Vec::new();
    let mut records_gpu = Vec::new();
    let mut bsdfs = Vec::new();
    let total: usize =
        LOBES.iter().map(|row| (row.parity.options)().len() * row.parity.records_per_option).sum();
    let mut records = Vec::with_capacity(total);
    let mut input = Vec::with_capacity(total * IN_WORDS);
    for (r, row) in LOBES.iter().enumerate() {
        let parity = &row.parity;
        let mut rng = Rng(parity.seed);
        let options = (parity.options)();
        let (first_group, first_material) = (groups.len(), params.len());
        for &o in &options {
            groups.push(Group { row: r, options: o });
            for _ in 0..MATERIALS_PER_CONFIG {
                let p = (parity.params)(&mut rng);
                let film = parity.film.map(|f| f(&mut rng));
                let mut bsdf = match film {
                    Some((factor, film)) => MetallicRoughness::new_iridescent(p, o, factor, film),
                    None => MetallicRoughness::new(p, o),
                };
                if let Some(strength) = parity.anisotropy.map(|f| f(&mut rng)) {
                    bsdf = bsdf.with_anisotropy(strength);
                }
                records_gpu.push(BsdfParams::of(&bsdf));
                params.push((p, o));
                bsdfs.push(bsdf);
            }
        }
        for c in 0..options.len() {
            for _ in 0..parity.records_per_option {
                let material = (first_material + c * MATERIALS_PER_CONFIG) as u32
                    + (rng.next_u64() % MATERIALS_PER_CONFIG as u64) as u32;
                let wo = dir(random_cos(&mut rng), TAU * rng.f64());
                let wi = random_wi(&mut rng, wo, records_gpu[material as usize].alpha);
                let rec = Record {
                    group: first_group + c,
                    material,
                    wo,
                    wi,
                    uc: random_u(&mut rng),
                    u: Vec2::new(random_u(&mut rng), random_u(&mut rng)),
                };
                input.push(material);
                for x in [wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, rec.uc, rec.u.x, rec.u.y] {
                    input.push(x.to_bits());
                }
                records.push(rec);
            }
        }
    }
    let n = records.len();

    let table = brdf::turquin_table();
    let t0 = std::time::Instant::now();
    let out = kernel::run_with(
        &ctx,
        &parity_kernel(),
        &input,
        &[&words(&records_gpu), &words(&table)],
        n * OUT_WORDS,
        n as u32,
    )
    .unwrap();
    eprintln!("GPU: {} records in {:.2?}", n, t0.elapsed());

    check(&groups, &params, &bsdfs, &records, &out);
}

/// One sampler step: `to_unit_f32` resolves `u` to 2⁻²⁴.
const U_STEP: f32 = 1.0 / 16_777_216.0;

/// The GPU's sample of one record.
struct GpuSample {
    wi: Vec3,
    pdf: f32,
    weight: Vec3,
    lobe: u32,
}

fn gpu_sample(o: &[u32]) -> GpuSample {
    GpuSample { wi: v3(&o[4..7]), pdf: f32::from_bits(o[7]), weight: v3(&o[8..11]), lobe: o[11] }
}

/// The Rust samples for `u` moved by one sampler step (`u ± 2⁻²⁴` per coordinate, within the
/// closed square `[0, 1]²`, where the warps' formulas are still defined), not `u` itself.
fn neighbours(bsdf: &MetallicRoughness, rec: &Record) -> Vec<Option<furnace_brdf::Sample>> {
    let mut v = Vec::with_capacity(8);
    for dx in [-1.0f32, 0.0, 1.0] {
        for dy in [-1.0f32, 0.0, 1.0] {
            let u = rec.u + U_STEP * Vec2::new(dx, dy);
            if (dx, dy) != (0.0, 0.0) && u.x >= 0.0 && u.x <= 1.0 && u.y >= 0.0 && u.y <= 1.0 {
                v.push(bsdf.sample(rec.wo, rec.uc, u));
            }
        }
    }
    v
}

/// How much the Rust sample moves within one sampler step of `u`: the largest `metric` between
/// its value at `u` and at the neighbours with the same lobe.
fn spread<T>(
    here: &furnace_brdf::Sample,
    near: &[Option<furnace_brdf::Sample>],
    value: impl Fn(&furnace_brdf::Sample) -> T,
    metric: impl Fn(T, T) -> f32,
) -> f32 {
    near.iter()
        .flatten()
        .filter(|s| s.lobe == here.lobe)
        .map(|s| metric(value(s), value(here)))
        .fold(0.0, f32::max)
}

/// Where the Rust sample is ill-conditioned — where one sampler step (the finest change of `u`
/// a sampler can make) moves it by more than the tolerance, so `u` does not determine it to
/// 1e-5 — a GPU value is accepted within the tolerance plus this many times that movement.
/// This happens at the warps' singular edges (`u` = 2⁻²⁴ or 1 − 2⁻²⁴, where Dupuy–Benyoub's
/// `√(1 − z²)` or Heitz's `√(1 − p₁² − p₂²)` turn one ulp of sin/cos into 1e-4…1e-1) and at
/// reflections that graze the horizon.
const SPREAD_FACTOR: f32 = 4.0;

/// Error table columns.
const FUNCS: [&str; 5] = ["eval", "pdf", "sample wi", "sample pdf", "sample weight"];

/// Per configuration: the worst error per function, and the counts of special cases.
#[derive(Default, Clone)]
struct ConfigStats {
    worst: [Worst; 5],
    /// Largest direct difference of the sample pdf from the Rust's (informational).
    pdf_direct: Worst,
    /// Samples accepted as ill-conditioned ([`SPREAD_FACTOR`]), and how many of those have a
    /// coordinate of u at an edge value.
    ill: usize,
    ill_at_edge_u: usize,
    /// `None` on one side and a sample on the other, where a neighbour of u (one sampler step)
    /// gives the GPU's outcome: a reflection on the horizon or a back-facing microfacet within
    /// rounding.
    validity_flips: usize,
    /// Samples whose direction rounding decides (VNDF/caps rim, the pole, grazing views; see
    /// check).
    rim: usize,
    /// Lobe choices that differ because uc sits within 1e-6 of the specular probability.
    boundary: usize,
    /// Records that fail, and why.
    failures: Vec<(usize, String)>,
}

/// A sample where rounding alone decides the microfacet (see `check`): Heitz's VNDF at the
/// rim of its disk (u.x → 1), or Dupuy–Benyoub's spherical caps at the cap's far end (u.y → 1:
/// z = (1 − u.y)(1 + zo) − zo → −zo, so the stretched normal's z, z + zo, is a rounding
/// residue, and unstretching by a small α turns it into any tilt).
fn is_rim(options: SpecularOptions, rec: &Record) -> bool {
    match options.sampling {
        SpecularSampling::Vndf => rec.u.x >= 1.0 - 2.0 * U_STEP,
        SpecularSampling::SphericalCaps => rec.u.y >= 1.0 - 2.0 * U_STEP,
        SpecularSampling::Ndf => false,
    }
}

/// Direction tolerance at the pole: √(2·2⁻²⁴·2) ≈ 4.9e-4 (two ulps of z under the square root),
/// doubled; also for views grazing the horizon (see `check`).
const POLE_DIR_TOL: f32 = 1e-3;

/// How far `f` moves (by `metric`) when one component of `wo` or `wi` moves by one ulp up or
/// down: the conditioning of `f` at the input, i.e. what rounding of the inputs alone can do.
fn ulp_spread<T: Copy>(wo: Vec3, wi: Vec3, f: impl Fn(Vec3, Vec3) -> T, metric: impl Fn(T, T) -> f32) -> f32 {
    let here = f(wo, wi);
    let mut worst = 0.0f32;
    for which in 0..2 {
        for axis in 0..3 {
            for up in [false, true] {
                let (mut a, mut b) = (wo, wi);
                let v = if which == 0 { &mut a } else { &mut b };
                v[axis] = if up { v[axis].next_up() } else { v[axis].next_down() };
                worst = worst.max(metric(f(a, b), here));
            }
        }
    }
    worst
}

/// Absolute rounding bound of a reflected direction's z: `ωi = 2(ωo·ωm)ωm − ωo` from unit
/// vectors, terms of magnitude ≤ 2, so f32 with or without fused multiply-adds (a GPU
/// compiler may contract where the Rust does not) gives z within a few ulps of 2 (2.4e-7 each);
/// 1e-6 is ≈ 4 of them. Measured: the flips it admits have |ωi.z| ≈ 1e-7.
const HORIZON_ROUNDING: f32 = 1e-6;

/// A `None`/sample flip decided by rounding at the horizon: the side that sampled produced a
/// direction whose height above the horizon is within [`HORIZON_ROUNDING`], so the other side's
/// rounding legitimately put it at or below (`above` is `z > 1e-15`).
fn grazes_within_rounding(rust_wi: Option<Vec3>, g: &GpuSample) -> bool {
    let gpu_wi = (g.lobe != brdf::LOBE_NONE).then_some(g.wi);
    rust_wi.or(gpu_wi).is_some_and(|wi| wi.z.abs() <= HORIZON_ROUNDING)
}

fn is_edge(u: f32) -> bool {
    u == 0.0 || u == U_STEP || u == 0.5 || u == 1.0 - U_STEP
}

/// Direction error: the largest component difference (of unit vectors: relative to their norm).
fn dir_err(a: Vec3, b: Vec3) -> f32 {
    let e = (a - b).abs().max_element();
    if e.is_nan() { f32::INFINITY } else { e }
}

fn check(
    groups: &[Group],
    params: &[(MetallicRoughnessParams, SpecularOptions)],
    bsdfs: &[MetallicRoughness],
    records: &[Record],
    out: &[u32],
) {
    let mut stats = vec![ConfigStats::default(); groups.len()];
    for (k, rec) in records.iter().enumerate() {
        let st = &mut stats[rec.group];
        let bsdf = &bsdfs[rec.material as usize];
        let o = &out[k * OUT_WORDS..(k + 1) * OUT_WORDS];

        // eval: per channel, relative to the value plus the unattenuated diffuse term
        // albedo·cos θi/π: the diffuse attenuation 1 − sF·max(F) cancels towards 0 at grazing
        // half angles, so its rounding is absolute on the scale of that term.
        let e = bsdf.eval(rec.wo, rec.wi);
        let scale = diffuse_scale_at(bsdf, rec.wo, rec.wi) + specular_scale_at(bsdf, rec.wo, rec.wi);
        st.worst[0].add(rel3(v3(&o[0..3]), e, scale), k);
        st.worst[1].add(rel(f32::from_bits(o[3]), bsdf.pdf(rec.wo, rec.wi), 0.0), k);

        // sample
        let g = gpu_sample(o);
        let rust = bsdf.sample(rec.wo, rec.uc, rec.u);
        let p = bsdf.specular_probability(rec.wo);
        let specular_alone = p >= 1.0;
        let rust_lobe = brdf::lobe_code(rust.map(|s| s.lobe));
        if rust_lobe != g.lobe {
            if rust_lobe != brdf::LOBE_NONE && g.lobe != brdf::LOBE_NONE {
                // Different lobes: legitimate only when uc sits on the float boundary p.
                if (rec.uc - p).abs() <= 1e-6 {
                    st.boundary += 1;
                } else {
                    st.failures.push((k, "different lobe".into()));
                }
            } else if neighbours(bsdf, rec).iter().any(|s| brdf::lobe_code(s.map(|s| s.lobe)) == g.lobe)
                || grazes_within_rounding(rust.map(|s| s.wi), &g)
            {
                st.validity_flips += 1;
            } else if is_rim(groups[rec.group].options, rec) {
                st.rim += 1; // the direction rounding decides may be valid on one side only
            } else {
                st.failures.push((k, "None on one side only, also one sampler step away".into()));
            }
            continue;
        }
        let Some(s) = rust else { continue };

        // pdf and weight: compared with the Rust sample, and with the Rust evaluated at the
        // GPU's own wi; the smaller difference counts. The Rust mixture computes exactly
        // pdf = p·pdf_spec(wo, wi) + (1 − p)·pdf_diffuse(wo, wi) and weight = eval/pdf at the wi
        // it sampled, so the second is the same computation for the GPU's direction: for a sharp
        // lobe (α → 1e-4) D changes by ~4δ/α relative when wi moves by δ, so the GPU's wi
        // (within ~1e-7 of the Rust's) alone moves the mixture pdf by up to ~1e-3 (the direct
        // difference, reported as "pdf direct"), and a weight ∝ G1(wi) of a reflection grazing
        // the horizon moves with wi.z. The specular lobe alone returns the closed forms F·G2/G1
        // (VNDF) or F·G2·(ωo·ωm)/(cos θo cos θm) (NDF), equal to its own eval/pdf at its wi.
        let r: &dyn Bsdf = if specular_alone { &bsdf.specular } else { bsdf };
        let rpdf = r.pdf(rec.wo, g.wi);
        let rweight = r.eval(rec.wo, g.wi) / rpdf;
        let direct_pdf = rel(g.pdf, s.pdf, 0.0);
        st.pdf_direct.add(direct_pdf, k);
        let pdf_err = direct_pdf.min(rel(g.pdf, rpdf, 0.0));
        let floor = Vec3::splat(WEIGHT_FLOOR);
        // A film's reflectance comes from cosines of phases up to ~100 rad: its rounding is
        // absolute (~1e-6 of a reflectance of 1), so under a film a weight channel is compared
        // relative to the lobe at full reflectance, as `eval` is.
        let film_scale = |wi: Vec3, pdf: f32| {
            if bsdf.specular.iridescence.is_some() {
                specular_scale_at(bsdf, rec.wo, wi) / pdf
            } else {
                Vec3::ZERO
            }
        };
        let direct_scale =
            (diffuse_scale_at(bsdf, rec.wo, s.wi) / s.pdf + film_scale(s.wi, s.pdf)).max(floor);
        let at_wi_scale = (diffuse_scale_at(bsdf, rec.wo, g.wi) / rpdf + film_scale(g.wi, rpdf)).max(floor);
        let weight_err = rel3(g.weight, s.weight, direct_scale).min(rel3(g.weight, rweight, at_wi_scale));
        let wi_err = dir_err(g.wi, s.wi);
        if wi_err <= REL_TOL && pdf_err <= REL_TOL && weight_err <= REL_TOL {
            st.worst[2].add(wi_err, k);
            st.worst[3].add(pdf_err, k);
            st.worst[4].add(weight_err, k);
            continue;
        }
        // Ill-conditioned at u? Each quantity within the tolerance plus SPREAD_FACTOR times
        // how much the Rust moves within one sampler step.
        let near = neighbours(bsdf, rec);
        let wi_spread = spread(&s, &near, |s| s.wi, dir_err);
        // The pdf and weight also as functions of the GPU's wi, one ulp around it (the Rust at
        // the GPU's direction: see above).
        let pdf_spread = spread(&s, &near, |s| s.pdf, |a, b| rel(a, b, 0.0)).max(ulp_spread(
            rec.wo,
            g.wi,
            |a, b| r.pdf(a, b),
            |x, y| rel(x, y, 0.0),
        ));
        let weight_spread = spread(&s, &near, |s| s.weight, |a, b| rel3(a, b, Vec3::ZERO)).max(ulp_spread(
            rec.wo,
            g.wi,
            |a, b| r.eval(a, b) / r.pdf(a, b),
            |x, y| rel3(x, y, floor),
        ));
        let ok = |err: f32, spread: f32| err <= REL_TOL + SPREAD_FACTOR * spread;
        // Heitz's VNDF at the rim of its disk (u.x ≥ 1 − 2⁻²³, so r = √u.x rounds to 1 or
        // 1 − 2⁻²⁴): the normal's component along the stretched view, √(1 − p₁² − p₂²), is
        // the square root of a rounding residue (c² + s² ≠ 1 by an ulp: 0…3.5e-4), and
        // unstretching by α ≤ 1e-3 magnifies it into a direction anywhere on the lobe's
        // silhouette. Where rounding alone decides the direction, the GPU's wi is not compared;
        // its pdf and weight still must match the Rust's at that wi.
        let rim = is_rim(groups[rec.group].options, rec);
        // At the pole (a reflection straight up): sin θ = √(1 − z²) of a z rounded to 1 or to
        // 1 − 2⁻²⁴ is 0 or 3.45e-4, so directions within POLE_DIR_TOL are the same sample.
        let pole = s.wi.z >= 1.0 - 1e-6 && wi_err <= POLE_DIR_TOL;
        // A view within 1e-4 of the horizon: VNDF's stretched view has z = cos θo/α, and its
        // frame and projection divide by it, so a few ulps of rounding move the direction by up
        // to ~ulp·α/cos θo (measured on hardware: 3.7e-5 at cos θo = 3e-7, pdf and weight
        // identical).
        let grazing = rec.wo.z < 1e-4 && wi_err <= POLE_DIR_TOL;
        if ok(wi_err, wi_spread) && ok(pdf_err, pdf_spread) && ok(weight_err, weight_spread) {
            st.ill += 1;
            st.ill_at_edge_u += usize::from(is_edge(rec.u.x) || is_edge(rec.u.y));
        } else if (rim || pole || grazing) && ok(pdf_err, pdf_spread) && ok(weight_err, weight_spread) {
            st.rim += 1;
        } else {
            st.failures.push((
                k,
                format!(
                    "sample differs: wi {wi_err:e} (one-step spread {wi_spread:e}), pdf {pdf_err:e} \
                     ({pdf_spread:e}), weight {weight_err:e} ({weight_spread:e})"
                ),
            ));
        }
    }

    // The table.
    let mut table = String::new();
    let _ = write!(table, "| config |");
    for f in FUNCS {
        let _ = write!(table, " {f} |");
    }
    let _ = writeln!(
        table,
        " pdf direct | ill-conditioned samples (edge u) | rim/pole | None/Some flips | lobe on boundary | failures |"
    );
    let _ = writeln!(table, "|---|{}---|---|---|---|---|---|", "---|".repeat(FUNCS.len()));
    for (st, g) in stats.iter().zip(groups) {
        let _ = write!(table, "| {} ({} records) |", g.name(), LOBES[g.row].parity.records_per_option);
        for f in &st.worst {
            let _ = write!(table, " {:.1e} |", f.err);
        }
        let _ = writeln!(
            table,
            " {:.1e} | {} ({}) | {} | {} | {} | {} |",
            st.pdf_direct.err,
            st.ill,
            st.ill_at_edge_u,
            st.rim,
            st.validity_flips,
            st.boundary,
            st.failures.len()
        );
    }
    eprintln!(
        "max relative error per function, WGSL vs furnace-brdf, per row and option combination \
         (sample columns: over the well-conditioned samples; counts of the others):\n{table}"
    );

    let show = |k: usize| {
        let rec = &records[k];
        describe(
            k,
            rec,
            &params[rec.material as usize].0,
            &bsdfs[rec.material as usize],
            &out[k * OUT_WORDS..],
        )
    };
    // Per row: its groups' failures and its counts against bounds from its own records.
    let mut failures = String::new();
    let mut counts = vec![(0usize, 0usize, 0usize, 0usize); LOBES.len()];
    for (st, g) in stats.iter().zip(groups) {
        let (n, ill, flips, boundary) = &mut counts[g.row];
        *n += LOBES[g.row].parity.records_per_option;
        *ill += st.ill + st.rim;
        *flips += st.validity_flips;
        *boundary += st.boundary;
        for (f, name) in FUNCS.iter().enumerate() {
            let w = &st.worst[f];
            if !(w.err <= REL_TOL) {
                let _ =
                    writeln!(failures, "{} {name}: error {:e}\n{}", g.name(), w.err, show(w.at.unwrap_or(0)));
            }
        }
        for (k, why) in st.failures.iter().take(3) {
            let _ = writeln!(failures, "{} sample: {why}\n{}", g.name(), show(*k));
        }
    }
    for (row, &(n, ill, flips, boundary)) in LOBES.iter().zip(&counts) {
        // uc within 1e-6 of p: expected ~1e-7 of the samples (p differs by an ulp or so); allow
        // 1e-5.
        let boundary_bound = (n as f64 * 1e-5).ceil() as usize;
        // Ill-conditioned samples and validity flips: edge u values (5% of each coordinate) and
        // grazing reflections; allow 0.5% of the records each.
        let ill_bound = n / 200;
        if !(boundary <= boundary_bound && ill <= ill_bound && flips <= ill_bound) {
            let _ = writeln!(
                failures,
                "{}: lobe flips on the boundary {boundary}, bound {boundary_bound}; ill-conditioned samples \
                 {ill}, None/Some flips {flips}, bound {ill_bound} ({n} records)",
                row.name
            );
        }
    }
    assert!(failures.is_empty(), "WGSL BSDF differs from furnace-brdf:\n{failures}");
}

/// The specular lobe's value with its Fresnel factor at its largest reflectance in every
/// channel (the absolute scale of the Fresnel rounding): Schlick's F = F0 + (F90 − F0)(1 − cos θd)⁵
/// in a channel with F0 = 0 near normal incidence is ~1e-15…1e-20 and relatively
/// ill-conditioned (5·δ/(1 − cos θd) for a rounding δ of cos θd, a few ulps on the GPU), but its
/// absolute error is ≤ 5δ ≈ 1e-6: eval errors are measured against the lobe at full Fresnel,
/// i.e. as absolute errors of F (≤ 1e-5 of the channel's possible reflectance).
fn specular_scale_at(bsdf: &MetallicRoughness, wo: Vec3, wi: Vec3) -> Vec3 {
    let s = bsdf.specular;
    // A film reflects up to 1 whatever F0 and F90 are.
    let full = if s.iridescence.is_some() { 1.0 } else { s.f0.max_element().max(s.f90.max_element()) };
    furnace_brdf::GgxSpecular { f0: Vec3::splat(full), f90: Vec3::splat(full), iridescence: None, ..s }
        .eval(wo, wi)
}

/// The unattenuated diffuse term albedo·cos θi/π (the absolute scale of the diffuse rounding).
fn diffuse_scale_at(bsdf: &MetallicRoughness, wo: Vec3, wi: Vec3) -> Vec3 {
    if wo.z > furnace_brdf::MIN_COS && wi.z > furnace_brdf::MIN_COS {
        bsdf.diffuse.albedo * (wi.z / std::f32::consts::PI)
    } else {
        Vec3::ZERO
    }
}

/// The BRDF module with what a composing shader adds: the sampling module before it and the
/// Turquin table binding.
fn module_source() -> String {
    wgsl::compose(&[
        wgsl::SAMPLING,
        &brdf::declarations(),
        &wgsl::select(wgsl::BRDF, |_| true),
        "@group(0) @binding(0) var<storage, read> turquin_table: array<f32>;",
    ])
}

/// The generated `struct BsdfParams` has the Rust layout, by naga reflection.
#[test]
fn bsdf_params_layout_matches_rust() {
    furnace_tests::layout::assert_gpu_struct::<BsdfParams>(&module_source());
}

#[test]
fn constants_and_bindings_match_rust() {
    let src = module_source();
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let constant = |name: &str| -> naga::Literal {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no const {name} in brdf.wgsl"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(l) => l,
            ref e => panic!("const {name} is not a literal: {e:?}"),
        }
    };
    let u = |name: &str, want: u32| assert_eq!(constant(name), naga::Literal::U32(want), "{name}");
    // Hand-kept in brdf.wgsl (the generated flag and lobe codes need no check).
    u("BSDF_TABLE_SIZE", furnace_brdf::turquin::TABLE_SIZE as u32);
    // Floats bit for bit.
    let f = |name: &str, want: f32| match constant(name) {
        naga::Literal::F32(v) => assert_eq!(v.to_bits(), want.to_bits(), "{name}: {v:e} vs {want:e}"),
        l => panic!("{name} is not f32: {l:?}"),
    };
    f("BSDF_MIN_COS", furnace_brdf::MIN_COS);
    f("BSDF_ALPHA_MIN", ALPHA_MIN);
    f("BRDF_PI", std::f32::consts::PI);
    f("BRDF_TAU", std::f32::consts::TAU);
    f("BRDF_FRAC_1_PI", std::f32::consts::FRAC_1_PI);
    f("BRDF_F32_MAX", f32::MAX);
    // The generated luminance weights are `furnace_sampling::LUMINANCE` bit for bit.
    let (_, luminance) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some("BSDF_LUMINANCE"))
        .expect("no const BSDF_LUMINANCE");
    let naga::Expression::Compose { ref components, .. } = module.global_expressions[luminance.init] else {
        panic!("BSDF_LUMINANCE is not a vector: {:?}", module.global_expressions[luminance.init]);
    };
    let weights: Vec<u32> = components
        .iter()
        .map(|&h| match module.global_expressions[h] {
            naga::Expression::Literal(naga::Literal::F32(v)) => v.to_bits(),
            ref e => panic!("BSDF_LUMINANCE component {e:?}"),
        })
        .collect();
    assert_eq!(weights, furnace_sampling::LUMINANCE.map(f32::to_bits));
    // The flags encode every option distinctly.
    let flags: std::collections::HashSet<u32> = all_options().into_iter().map(brdf::options_flags).collect();
    assert_eq!(flags.len(), 12);
    // The module declares no bindings: the only global is the table the composing shader adds.
    let globals: Vec<_> = module.global_variables.iter().filter_map(|(_, g)| g.name.clone()).collect();
    assert_eq!(globals, ["turquin_table"], "brdf.wgsl must not declare bindings");
    assert!(!wgsl::BRDF.contains("@binding") && !wgsl::BRDF.contains("@group"));
    // The table is the Rust crate's data, in the documented order.
    let table = brdf::turquin_table();
    assert_eq!(table.len(), brdf::TURQUIN_TABLE_LEN);
    let n = furnace_brdf::turquin::TABLE_SIZE;
    for (j, i) in [(0, 0), (5, 17), (63, 63)] {
        assert_eq!(table[j * n + i], furnace_brdf::turquin::E_SS_SEPARABLE[j][i]);
        assert_eq!(table[(n + j) * n + i], furnace_brdf::turquin::E_SS_HEIGHT_CORRELATED[j][i]);
    }
}

/// `bsdf_params` and `bsdf_with_film` (the WGSL constructors, for materials evaluated on the
/// GPU) build the record that `BsdfParams::of(MetallicRoughness::new_iridescent(…))` builds
/// (and `bsdf_with_anisotropy` that of `with_anisotropy`),
/// including the clamping of out-of-range, infinite and NaN inputs.
#[test]
fn wgsl_constructor_matches_rust() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(0xc0ff_ee00);
    let odd = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.5, -0.0, 1.5, 1e30, f32::MAX, 0.0, 1.0];
    let configs = all_options();
    let mut cases = Vec::new();
    for k in 0..100_000 {
        let mut p = gltf_params(&mut rng);
        // Half the cases under a film (weight 0: none).
        let (mut factor, mut film) =
            if k % 2 == 0 { (0.0, ThinFilm { ior: 1.3, thickness: 400.0 }) } else { film_params(&mut rng) };
        // A third anisotropic.
        let mut strength = if k % 3 == 0 { anisotropy_strength(&mut rng) } else { 0.0 };
        if k % 4 < 2 {
            // One odd value in one field.
            let x = rng.pick(&odd);
            match rng.next_u64() % 13 {
                11 => strength = x,
                0 => p.base_color.x = x,
                1 => p.base_color.z = x,
                2 => p.metallic = x,
                3 => p.roughness = x,
                4 => p.specular_factor = x,
                5 => p.specular_color.x = x,
                6 => p.specular_color.y = x,
                7 => p.specular_color = Vec3::splat(x),
                8 => factor = x,
                9 => film.ior = x,
                10 => film.thickness = x,
                _ => p.base_color = Vec3::splat(x),
            }
        }
        cases.push((p, rng.pick(&configs), factor, film, strength));
    }
    const IN: usize = 14;
    const OUT: usize = 24;
    let mut input = Vec::with_capacity(cases.len() * IN);
    for (p, o, factor, film, strength) in &cases {
        let b = p.base_color;
        let c = p.specular_color;
        for x in [b.x, b.y, b.z, p.metallic, p.roughness, p.specular_factor, c.x, c.y, c.z] {
            input.push(x.to_bits());
        }
        input.push(brdf::options_flags(*o));
        input.extend([factor.to_bits(), film.ior.to_bits(), film.thickness.to_bits(), strength.to_bits()]);
    }
    let body = r#"
@group(0) @binding(3) var<storage, read> turquin_table: array<f32>;
fn in_f32(k: u32) -> f32 { return bitcast<f32>(input[k]); }

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let b = i * 14u;
    let base = vec3<f32>(in_f32(b), in_f32(b + 1u), in_f32(b + 2u));
    var m = bsdf_params(base, in_f32(b + 3u), in_f32(b + 4u),
                        in_f32(b + 5u), vec3<f32>(in_f32(b + 6u), in_f32(b + 7u), in_f32(b + 8u)), input[b + 9u]);
    m = bsdf_with_film(m, base, in_f32(b + 3u), in_f32(b + 10u), in_f32(b + 11u), in_f32(b + 12u));
    m = bsdf_with_anisotropy(m, in_f32(b + 13u));
    var w = array<f32, 24>(m.diffuse.x, m.diffuse.y, m.diffuse.z, m.alpha, m.f0.x, m.f0.y, m.f0.z, m.f90,
                           m.f0_dielectric.x, m.f0_dielectric.y, m.f0_dielectric.z, m.specular_factor,
                           bitcast<f32>(m.flags), m.film_factor, m.film_ior, m.film_thickness,
                           m.film_f0_metal.x, m.film_f0_metal.y, m.film_f0_metal.z, m.film_metallic,
                           m.film_f0.x, m.film_f0.y, m.film_f0.z, m.alpha_y);
    for (var k = 0u; k < 24u; k++) {
        output[i * 24u + k] = bitcast<u32>(w[k]);
    }
}
"#;
    let src = kernel::brdf_kernel(body);
    let table = brdf::turquin_table();
    let out = kernel::run_with(&ctx, &src, &input, &[&words(&table)], cases.len() * OUT, cases.len() as u32)
        .unwrap();
    let mut worst = 0.0f32;
    let mut bad = Vec::new();
    for (k, (p, o, factor, film, strength)) in cases.iter().enumerate() {
        let rust = MetallicRoughness::new_iridescent(*p, *o, *factor, *film).with_anisotropy(*strength);
        let want: [u32; OUT] = bytemuck::cast(BsdfParams::of(&rust));
        let got = &out[k * OUT..k * OUT + OUT];
        // Flags exact; the floats within the tolerance (the same operations: clamps, a lerp, a
        // square; the film's F0 a film reflectance, absolute to 1e-5 of 1 (see the sample
        // weights' film scale)).
        let mut err = 0.0f32;
        for w in 0..OUT {
            err = err.max(if w == 12 {
                if got[w] == want[w] { 0.0 } else { f32::INFINITY }
            } else if (20..23).contains(&w) {
                rel(f32::from_bits(got[w]), f32::from_bits(want[w]), 1.0)
            } else {
                rel(f32::from_bits(got[w]), f32::from_bits(want[w]), 0.0)
            });
        }
        worst = worst.max(err);
        if !(err <= REL_TOL) && bad.len() < 5 {
            bad.push(format!(
                "{p:?} {o:?} film {factor} {film:?} anisotropy {strength}:\n  Rust {:?}\n  WGSL {:?}",
                &want[..],
                got
            ));
        }
    }
    eprintln!(
        "bsdf_params, bsdf_with_film, bsdf_with_anisotropy: {} inputs, max relative error {worst:e}",
        cases.len()
    );
    assert!(bad.is_empty(), "bsdf_params / bsdf_with_film differ from BsdfParams::of:\n{}", bad.join("\n"));
}

/// `bsdf_e_ss` (WGSL) against `turquin::e_ss`: the table lookup, with a cube root that WGSL
/// lacks (exp2/log2 and a Newton step), at the grid points (where the cube root decides the
/// cell) and between them.
#[test]
fn turquin_lookup_matches_rust() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(0x7ab1e);
    let n = furnace_brdf::turquin::TABLE_SIZE;
    let mut cases = Vec::new();
    for k in 0..100_000 {
        let mu = match k % 5 {
            0 => furnace_brdf::turquin::table_mu((rng.next_u64() % n as u64) as usize),
            1 => rng.pick(&[0.0, 1.0, 1e-7, 1e-4, -0.5, 1.5]),
            _ => rng.f32(),
        };
        let alpha = match (k / 5) % 5 {
            0 => furnace_brdf::turquin::table_alpha((rng.next_u64() % n as u64) as usize),
            1 => rng.pick(&[0.0, 1.0, ALPHA_MIN, 1e-6, -0.5, 1.5]),
            2 => rng.f32().powi(3),
            _ => rng.f32(),
        };
        let masking = if rng.chance(0.5) { Masking::Separable } else { Masking::HeightCorrelated };
        cases.push((mu, alpha, masking));
    }
    let input: Vec<u32> = cases
        .iter()
        .flat_map(|&(mu, a, m)| [mu.to_bits(), a.to_bits(), u32::from(m == Masking::HeightCorrelated)])
        .collect();
    let body = r#"
@group(0) @binding(3) var<storage, read> turquin_table: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let e = bsdf_e_ss(bitcast<f32>(input[3u * i]), bitcast<f32>(input[3u * i + 1u]), input[3u * i + 2u] != 0u);
    output[i] = bitcast<u32>(e);
}
"#;
    let src = kernel::brdf_kernel(body);
    let table = brdf::turquin_table();
    let out =
        kernel::run_with(&ctx, &src, &input, &[&words(&table)], cases.len(), cases.len() as u32).unwrap();
    let mut worst = (0.0f32, 0);
    for (k, &(mu, a, m)) in cases.iter().enumerate() {
        let err = rel(f32::from_bits(out[k]), furnace_brdf::turquin::e_ss(mu, a, m), 0.0);
        if !(err <= worst.0) {
            worst = (err, k);
        }
    }
    let (mu, a, m) = cases[worst.1];
    eprintln!(
        "bsdf_e_ss: {} inputs, max relative error {:e} (μ {mu:e}, α {a:e}, {m:?})",
        cases.len(),
        worst.0
    );
    assert!(
        worst.0 <= REL_TOL,
        "bsdf_e_ss({mu:e}, {a:e}, {m:?}) = {:e}, Rust {:e}",
        f32::from_bits(out[worst.1]),
        furnace_brdf::turquin::e_ss(mu, a, m)
    );
}
