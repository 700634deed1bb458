//! Parity of `sampling.wgsl` with `furnace-sampling`: the five samplers, their helpers and
//! `to_unit_f32` bit for bit, the warps within a stated tolerance, the generated tables, the
//! layout of `SamplerParams`, and the module's hygiene (no bindings, private names `smp_`).
//!
//! Each GPU test runs one kernel over all its cases (a dispatch per test, not per case) and
//! compares with the Rust on the CPU; a mismatch prints the first rows and the count.

use furnace_tests::Rng;

use furnace_gpu::sampling::{SamplerParams, kind_code, wgsl_generated};
use furnace_gpu::wgsl;
use furnace_sampling::fixed::{div_frac, div_frac_bitwise, isqrt};
use furnace_sampling::hash::{
    hash2, hash3, hash4, kensler_hash, kensler_permute, laine_karras, owen_scramble, owen_shuffle_index,
    pcg_hash,
};
use furnace_sampling::warp::{
    concentric_disk_pdf, cosine_hemisphere_pdf, in_cone, spherical_triangle_solid_angle,
    square_to_concentric_disk, square_to_cosine_hemisphere, square_to_spherical_triangle,
    square_to_uniform_cone, square_to_uniform_hemisphere, square_to_uniform_triangle, uniform_cone_pdf,
    uniform_hemisphere_pdf,
};
use furnace_sampling::{
    AnySampler, PMJ02_XORS, Sampler, SamplerKind, pmj02_coordinate, sobol_bits, to_unit_f32,
};
use furnace_tests::gpu::{self as kernel, test_context};
use glam::{Vec2, Vec3};
use std::fmt::Write as _;

/// Cases per sampler kind from the random mixture (plus a systematic grid of
/// [`GRID_DIMS`] × [`GRID_INDICES`] per kind and setting).
const RANDOM_CASES_PER_KIND: usize = 100_000;
/// Dimensions of the systematic grid: 0..66 (pixel, then 16 bounces of four).
const GRID_DIMS: u32 = 66;
/// Indices of the systematic grid: 0..40, covering the first 2^k boundaries.
const GRID_INDICES: u32 = 40;
/// Mismatch rows printed before the count.
const SHOW: usize = 8;

// Helpers on the shared generator (`furnace_tests::layout::Rng`, SplitMix64).

/// Indices on both sides of every power of two, and the extremes.
fn edge_indices() -> Vec<u32> {
    let mut v = vec![0, 1, 2, 3, u32::MAX, u32::MAX - 1];
    for k in 1..32 {
        let p = 1u32 << k;
        v.extend([p - 1, p, p + 1]);
    }
    v
}

const EDGE_PIXELS: [u32; 9] = [0, 1, 2, 511, 512 * 512 - 1, 1 << 24, 1 << 31, u32::MAX - 1, u32::MAX];
const EDGE_SEEDS: [u32; 4] = [0, 1, 0x9e37_79b9, u32::MAX];
/// Sample counts of the fixed-N samplers: 1, squares and non-squares, both sides of 2^16 (the
/// two paths of `div_frac`), up to the maximum 2^30.
const EDGE_COUNTS: [u32; 17] =
    [1, 2, 3, 5, 16, 17, 64, 100, 255, 256, 1000, 4096, 65_535, 65_536, 65_537, 1_000_003, 1 << 30];

/// One `(sampler, pixel, index, dimension)` to compare.
#[derive(Debug, Clone, Copy)]
struct Case {
    kind: SamplerKind,
    seed: u32,
    /// N for the fixed-N kinds, else `None`.
    count: Option<u32>,
    pixel: u32,
    index: u32,
    dim: u32,
}

/// The cases of one kind: a systematic grid (dimensions 0..66 × indices 0..40, and for the
/// fixed-N kinds the indices around N, 2N) for a few settings, then a random mixture of edge
/// and random seeds, counts, pixels, indices and dimensions.
fn cases(kind: SamplerKind, rng: &mut Rng) -> Vec<Case> {
    let fixed = kind.needs_sample_count();
    let mut out = Vec::new();
    let settings: Vec<(u32, Option<u32>)> = if fixed {
        vec![(0, Some(16)), (u32::MAX, Some(17)), (7, Some(1)), (0x9e37_79b9, Some(65_537))]
    } else {
        vec![(0, None), (u32::MAX, None)]
    };
    for &(seed, count) in &settings {
        for (pixel_i, pixel) in [0u32, u32::MAX].into_iter().enumerate() {
            let mut indices: Vec<u32> = (0..GRID_INDICES).collect();
            if let Some(n) = count {
                indices.extend([n - 1, n, n + 1, 2 * n - 1, 2 * n, 5 * n + 3]);
            }
            for &index in &indices {
                for dim in 0..GRID_DIMS {
                    // The second pixel only on every other dimension: enough, and faster.
                    if pixel_i == 1 && dim % 2 == 1 {
                        continue;
                    }
                    out.push(Case { kind, seed, count, pixel, index, dim });
                }
            }
        }
    }
    let edges = edge_indices();
    for _ in 0..RANDOM_CASES_PER_KIND {
        let seed = if rng.below(2) == 0 { rng.pick(&EDGE_SEEDS) } else { rng.u32() };
        let count = fixed.then(|| {
            if rng.below(2) == 0 {
                rng.pick(&EDGE_COUNTS)
            } else {
                let bits = rng.below(31);
                1 + rng.below(1 << bits)
            }
        });
        let pixel = match rng.below(10) {
            0..=2 => rng.pick(&EDGE_PIXELS),
            _ => rng.scaled(),
        };
        let index = match (rng.below(10), count) {
            (0..=2, _) => rng.pick(&edges),
            // Around and past N: N − 1, N, N + 1, multiples of N plus a bit, the largest index.
            (3..=5, Some(n)) => match rng.below(5) {
                0 => n - 1,
                1 => n,
                2 => n + 1,
                3 => n.saturating_mul(1 + rng.below(64)).saturating_add(rng.below(n)),
                _ => u32::MAX - rng.below(n),
            },
            _ => rng.scaled(),
        };
        let dim = match rng.below(10) {
            0..=7 => rng.below(GRID_DIMS),
            // Huge dimensions. Sobol's `bits_2d` adds 1 without wrapping at 4k + 3 (an overflow
            // panic at u32::MAX with overflow checks on), so it stops at u32::MAX − 1.
            8 => {
                let top = if kind == SamplerKind::Sobol { u32::MAX - 1 } else { u32::MAX };
                rng.pick(&[1 << 16, (1 << 31) - 1, 1 << 31, u32::MAX - 3, top - 1, top])
            }
            _ => rng.u32().min(u32::MAX - 1),
        };
        out.push(Case { kind, seed, count, pixel, index, dim });
    }
    out
}

/// Words per case in the sampler kernel's input and output.
const CASE_WORDS: usize = 6;

/// Input `[kind, seed, N, pixel, index, dim]` (the params from [`SamplerParams::new`]); output
/// `[bits, bits_2d.x, bits_2d.y, value, value_2d.x, value_2d.y]` (floats as bits).
const SAMPLER_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let r = 6u * i;
    let p = SamplerParams(input[r], input[r + 1u], input[r + 2u], 0u);
    let pixel = input[r + 3u];
    let index = input[r + 4u];
    let dim = input[r + 5u];
    let b2 = sampler_bits_2d(p, pixel, index, dim);
    let v2 = sampler_value_2d(p, pixel, index, dim);
    output[r] = sampler_bits(p, pixel, index, dim);
    output[r + 1u] = b2.x;
    output[r + 2u] = b2.y;
    output[r + 3u] = bitcast<u32>(sampler_value(p, pixel, index, dim));
    output[r + 4u] = bitcast<u32>(v2.x);
    output[r + 5u] = bitcast<u32>(v2.y);
}
"#;

fn shader(kernel_body: &str) -> String {
    wgsl::compose(&[kernel::PREAMBLE, wgsl::SAMPLING, kernel_body])
}

const FIELDS: [&str; CASE_WORDS] = ["bits", "bits_2d.x", "bits_2d.y", "value", "value_2d.x", "value_2d.y"];

/// Every sampler, bit for bit: `bits`, `bits_2d`, `value`, `value_2d` on > 10^5 cases each.
#[test]
fn samplers_are_bit_identical() {
    let Some(ctx) = test_context() else { return };
    eprintln!("adapter: {}", ctx.describe());
    let mut rng = Rng(0x5eed_0006);
    let all: Vec<Case> = SamplerKind::ALL.into_iter().flat_map(|k| cases(k, &mut rng)).collect();
    let mut input = Vec::with_capacity(all.len() * CASE_WORDS);
    let mut want = Vec::with_capacity(all.len() * CASE_WORDS);
    for c in &all {
        let p = SamplerParams::new(c.kind, c.seed, c.count).unwrap();
        input.extend([p.kind, p.seed, p.sample_count, c.pixel, c.index, c.dim]);
        // The Rust side is built directly, not through SamplerParams.
        let s = AnySampler::new(c.kind, c.seed, c.count).unwrap();
        let [x, y] = s.bits_2d(c.pixel, c.index, c.dim);
        let [vx, vy] = s.value_2d(c.pixel, c.index, c.dim);
        want.extend([
            s.bits(c.pixel, c.index, c.dim),
            x,
            y,
            s.value(c.pixel, c.index, c.dim).to_bits(),
            vx.to_bits(),
            vy.to_bits(),
        ]);
    }
    let t = std::time::Instant::now();
    let got = kernel::run(&ctx, &shader(SAMPLER_KERNEL), &input, want.len(), all.len() as u32).unwrap();
    eprintln!("{} cases on the GPU in {:.2} s", all.len(), t.elapsed().as_secs_f64());

    let mut report = String::new();
    let mut failed = false;
    for kind in SamplerKind::ALL {
        let mut rows = Vec::new();
        let mut cases_of_kind = 0;
        for (i, c) in all.iter().enumerate().filter(|(_, c)| c.kind == kind) {
            cases_of_kind += 1;
            for f in 0..CASE_WORDS {
                let (w, g) = (want[i * CASE_WORDS + f], got[i * CASE_WORDS + f]);
                if w != g {
                    rows.push(format!(
                        "  seed {:#010x} N {:?} pixel {} index {} dim {} {}: rust {w:#010x} wgsl {g:#010x}",
                        c.seed, c.count, c.pixel, c.index, c.dim, FIELDS[f]
                    ));
                }
            }
        }
        let _ = writeln!(report, "{kind}: {cases_of_kind} cases, {} mismatching words", rows.len());
        assert!(cases_of_kind >= 100_000, "{kind}: only {cases_of_kind} cases");
        for r in rows.iter().take(SHOW) {
            let _ = writeln!(report, "{r}");
        }
        failed |= !rows.is_empty();
    }
    eprint!("{report}");
    assert!(!failed, "WGSL samplers differ from furnace-sampling:\n{report}");
}

/// The helpers one by one (so that a sampler mismatch can be traced to its cause): op code,
/// four arguments, one result word.
const PRIMITIVE_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let r = 5u * i;
    let a = input[r + 1u];
    let b = input[r + 2u];
    let c = input[r + 3u];
    let d = input[r + 4u];
    var y = 0u;
    switch input[r] {
        case 0u: { y = smp_pcg_hash(a); }
        case 1u: { y = smp_hash2(a, b); }
        case 2u: { y = smp_hash3(a, b, c); }
        case 3u: { y = smp_hash4(a, b, c, d); }
        case 4u: { y = smp_div_frac(a, b, c); }
        case 5u: { y = smp_div_frac_bitwise(a, b, c); }
        case 6u: { y = smp_isqrt(a); }
        case 7u: { y = smp_kensler_permute(a, b, c); }
        case 8u: { y = smp_kensler_hash(a, b); }
        case 9u: { y = smp_laine_karras(a, b); }
        case 10u: { y = smp_owen_scramble(a, b); }
        case 11u: { y = smp_owen_shuffle_index(a, b); }
        case 12u: { y = smp_sobol_bits(a, b); }
        case 13u: { y = smp_pmj02_coordinate(a, b, c); }
        case 14u: { y = bitcast<u32>(to_unit_f32(a)); }
        default: { y = 0xdeadbeefu; }
    }
    output[i] = y;
}
"#;

const PRIMITIVES: [&str; 15] = [
    "pcg_hash",
    "hash2",
    "hash3",
    "hash4",
    "div_frac",
    "div_frac_bitwise",
    "isqrt",
    "kensler_permute",
    "kensler_hash",
    "laine_karras",
    "owen_scramble",
    "owen_shuffle_index",
    "sobol_bits",
    "pmj02_coordinate",
    "to_unit_f32",
];

/// Arguments for op `op` that satisfy its preconditions (`hi < d`, `i < l`, `dim < 4`,
/// `axis < 2`), with extremes mixed in.
fn primitive_args(op: u32, rng: &mut Rng) -> [u32; 4] {
    let mut w = || if rng.below(4) == 0 { rng.pick(&[0, 1, 0x8000_0000, u32::MAX]) } else { rng.scaled() };
    let [a, b, c, d] = [w(), w(), w(), w()];
    match op {
        // div_frac(hi, lo, d): hi < d; divisors on both sides of 2^16 (its two paths).
        4 | 5 => {
            let d = match rng.below(4) {
                0 => rng.pick(&[1, 2, 3, 0xFFFF, 0x1_0000, 0x1_0001, 1 << 31, u32::MAX]),
                1 => 1 + rng.below(0xFFFF),
                _ => c.max(1),
            };
            let hi = if rng.below(4) == 0 { d - 1 } else { a % d };
            [hi, b, d, 0]
        }
        // kensler_permute(i, l, p): i < l, l ≥ 1 (l up to 2^32 − 1).
        7 => {
            let l =
                if rng.below(4) == 0 { rng.pick(&[1, 2, 3, 16, 17, 1 << 30, u32::MAX]) } else { b.max(1) };
            [a % l, l, c, 0]
        }
        12 => [a, rng.below(4), 0, 0],
        13 => [a, rng.below(2), c, 0],
        _ => [a, b, c, d],
    }
}

fn primitive_rust(op: u32, [a, b, c, d]: [u32; 4]) -> u32 {
    match op {
        0 => pcg_hash(a),
        1 => hash2(a, b),
        2 => hash3(a, b, c),
        3 => hash4(a, b, c, d),
        4 => div_frac(a, b, c),
        5 => div_frac_bitwise(a, b, c),
        6 => isqrt(a),
        7 => kensler_permute(a, b, c),
        8 => kensler_hash(a, b),
        9 => laine_karras(a, b),
        10 => owen_scramble(a, b),
        11 => owen_shuffle_index(a, b),
        12 => sobol_bits(a, b as usize),
        13 => pmj02_coordinate(a, &PMJ02_XORS[b as usize], c),
        14 => to_unit_f32(a).to_bits(),
        _ => unreachable!(),
    }
}

/// Each helper bit for bit on 8000 argument sets (random of every bit length, and extremes).
#[test]
fn helpers_are_bit_identical() {
    let Some(ctx) = test_context() else { return };
    let per_op = 8000;
    let mut rng = Rng(0x0d1f_f00d);
    let mut input = Vec::new();
    let mut cases = Vec::new();
    for op in 0..PRIMITIVES.len() as u32 {
        for _ in 0..per_op {
            let args = primitive_args(op, &mut rng);
            input.push(op);
            input.extend(args);
            cases.push((op, args));
        }
    }
    let got = kernel::run(&ctx, &shader(PRIMITIVE_KERNEL), &input, cases.len(), cases.len() as u32).unwrap();
    let mut rows = Vec::new();
    for (&(op, args), &g) in cases.iter().zip(&got) {
        let w = primitive_rust(op, args);
        if w != g {
            rows.push(format!("  {}{args:?}: rust {w:#010x} wgsl {g:#010x}", PRIMITIVES[op as usize]));
        }
    }
    assert!(
        rows.is_empty(),
        "{} of {} helper results differ:\n{}",
        rows.len(),
        cases.len(),
        rows[..rows.len().min(SHOW)].join("\n")
    );
}

/// Input `[u.x, u.y, c, p.x, p.y]`; output: concentric disk (2), uniform hemisphere (3), cosine
/// hemisphere (3), then `concentric_disk_pdf(p)`, `uniform_hemisphere_pdf(c)`,
/// `cosine_hemisphere_pdf(c)`.
const WARP_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let r = 5u * i;
    let u = vec2<f32>(bitcast<f32>(input[r]), bitcast<f32>(input[r + 1u]));
    let c = bitcast<f32>(input[r + 2u]);
    let p = vec2<f32>(bitcast<f32>(input[r + 3u]), bitcast<f32>(input[r + 4u]));
    let o = 11u * i;
    let disk = warp_concentric_disk(u);
    let uh = warp_uniform_hemisphere(u);
    let ch = warp_cosine_hemisphere(u);
    output[o] = bitcast<u32>(disk.x);
    output[o + 1u] = bitcast<u32>(disk.y);
    output[o + 2u] = bitcast<u32>(uh.x);
    output[o + 3u] = bitcast<u32>(uh.y);
    output[o + 4u] = bitcast<u32>(uh.z);
    output[o + 5u] = bitcast<u32>(ch.x);
    output[o + 6u] = bitcast<u32>(ch.y);
    output[o + 7u] = bitcast<u32>(ch.z);
    output[o + 8u] = bitcast<u32>(concentric_disk_pdf(p));
    output[o + 9u] = bitcast<u32>(uniform_hemisphere_pdf(c));
    output[o + 10u] = bitcast<u32>(cosine_hemisphere_pdf(c));
}
"#;

/// Largest absolute difference allowed between a WGSL warp and its Rust twin, per component
/// (all components lie in [−1, 1]).
///
/// Why not bit-exact: WGSL (like Vulkan's SPIR-V) does not require `sin`, `cos`, `sqrt` or `/`
/// to be correctly rounded, and compilers may fuse `a·b + c`. Why 2⁻¹⁶ ≈ 1.5e-5: the formulas
/// are the same, so the difference is the functions' error, carried through at most one
/// multiply; the WGSL spec only bounds `sin`/`cos` by 2⁻¹¹ absolute on [−π, π], but every
/// adapter we know does far better (lavapipe's measured maximum is printed by the test), and
/// 2⁻¹⁶ is ~100× an f32 ulp at 1 yet 1000× below a wrong branch or a swapped coordinate.
const WARP_TOLERANCE: f32 = 1.0 / 65_536.0;

/// The warps to [`WARP_TOLERANCE`]; the pdfs bit for bit on the same input (a compare and a
/// multiply, both exact in WGSL), except concentric-disk points within a few ulp of the rim.
#[test]
fn warps_match_to_float_rounding() {
    let Some(ctx) = test_context() else { return };
    let one_minus = 1.0 - f32::EPSILON / 2.0;
    let edges = [0.0, 2f32.powi(-24), 0.25, 0.5 - 2f32.powi(-25), 0.5, 0.5 + 2f32.powi(-24), 0.75, one_minus];
    let mut us: Vec<Vec2> = Vec::new();
    for &x in &edges {
        for &y in &edges {
            us.push(Vec2::new(x, y));
        }
    }
    let n = 256;
    for i in 0..n {
        for j in 0..n {
            us.push(Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32));
        }
    }
    let mut rng = Rng(0x000a_11ce);
    for _ in 0..20_000 {
        us.push(Vec2::new(to_unit_f32(rng.u32()), to_unit_f32(rng.u32())));
    }
    let mut input = Vec::new();
    let mut pdf_args = Vec::new();
    for (k, u) in us.iter().enumerate() {
        // c covers [−1, 1) with ±0; p covers [−1.25, 1.25)², across the rim.
        let c = match k % 7 {
            0 => 0.0,
            1 => -0.0,
            _ => 2.0 * u.x - 1.0,
        };
        let p = 2.5 * *u - Vec2::splat(1.25);
        input.extend([u.x.to_bits(), u.y.to_bits(), f32::to_bits(c), p.x.to_bits(), p.y.to_bits()]);
        pdf_args.push((c, p));
    }
    let got = kernel::run(&ctx, &shader(WARP_KERNEL), &input, 11 * us.len(), us.len() as u32).unwrap();
    let names = ["disk", "uniform hemisphere", "cosine hemisphere"];
    let mut max_err = [0f32; 3];
    let mut rows = Vec::new();
    let mut pdf_rows = Vec::new();
    for (k, (u, &(c, p))) in us.iter().zip(&pdf_args).enumerate() {
        let g: Vec<f32> = got[11 * k..11 * k + 11].iter().map(|&w| f32::from_bits(w)).collect();
        let d = square_to_concentric_disk(*u);
        let uh = square_to_uniform_hemisphere(*u);
        let ch = square_to_cosine_hemisphere(*u);
        let pairs: [(&[f32], &[f32]); 3] =
            [(&d.to_array(), &g[0..2]), (&uh.to_array(), &g[2..5]), (&ch.to_array(), &g[5..8])];
        for (w, (rust, wgsl)) in pairs.iter().enumerate() {
            let err = rust.iter().zip(wgsl.iter()).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
            let err = if err.is_nan() || wgsl.iter().any(|v| !v.is_finite()) { f32::INFINITY } else { err };
            max_err[w] = max_err[w].max(err);
            if err > WARP_TOLERANCE {
                rows.push(format!("  {} u = {u:?}: rust {rust:?} wgsl {wgsl:?}", names[w]));
            }
        }
        let near_rim = (p.length_squared() - 1.000_001).abs() <= 4.0 * f32::EPSILON;
        let w = Vec3::new(0.0, 0.0, c);
        let pdfs = [
            ("concentric_disk_pdf", concentric_disk_pdf(p), g[8], !near_rim),
            ("uniform_hemisphere_pdf", uniform_hemisphere_pdf(w), g[9], true),
            ("cosine_hemisphere_pdf", cosine_hemisphere_pdf(w), g[10], true),
        ];
        for (name, rust, wgsl, exact) in pdfs {
            if exact && rust.to_bits() != wgsl.to_bits() {
                pdf_rows.push(format!("  {name} (c = {c:?}, p = {p:?}): rust {rust:?} wgsl {wgsl:?}"));
            }
        }
    }
    eprintln!(
        "{} inputs; largest |WGSL − Rust| per component: disk {:.2e}, uniform hemisphere {:.2e}, cosine \
         hemisphere {:.2e} (tolerance {WARP_TOLERANCE:.2e})",
        us.len(),
        max_err[0],
        max_err[1],
        max_err[2]
    );
    assert!(
        rows.is_empty(),
        "{} warp results beyond {WARP_TOLERANCE:e}:\n{}",
        rows.len(),
        rows[..rows.len().min(SHOW)].join("\n")
    );
    assert!(
        pdf_rows.is_empty(),
        "{} pdfs differ:\n{}",
        pdf_rows.len(),
        pdf_rows[..pdf_rows.len().min(SHOW)].join("\n")
    );
}

/// Input `[u.x, u.y, t, a, b]`; output: uniform triangle (2), uniform cone of `1 − cos = t` (3),
/// `uniform_cone_pdf(t)`, `in_cone` of the cone sample against +z (as 0/1), `smp_mul_hi(a, b)`.
const LIGHT_WARP_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let r = 5u * i;
    let u = vec2<f32>(bitcast<f32>(input[r]), bitcast<f32>(input[r + 1u]));
    let t = bitcast<f32>(input[r + 2u]);
    let o = 8u * i;
    let b = warp_uniform_triangle(u);
    let w = warp_uniform_cone(u, t);
    output[o] = bitcast<u32>(b.x);
    output[o + 1u] = bitcast<u32>(b.y);
    output[o + 2u] = bitcast<u32>(w.x);
    output[o + 3u] = bitcast<u32>(w.y);
    output[o + 4u] = bitcast<u32>(w.z);
    output[o + 5u] = bitcast<u32>(uniform_cone_pdf(t));
    output[o + 6u] = select(0u, 1u, in_cone(w, vec3<f32>(0.0, 0.0, 1.0), t));
    output[o + 7u] = smp_mul_hi(input[r + 3u], input[r + 4u]);
}
"#;

/// The light-sampling warps (triangle, cone) to [`WARP_TOLERANCE`] relative to the cone's size
/// (a 0.001° cone's directions differ from +z by 10⁻⁵), the cone pdf bit for bit, `in_cone` on
/// every sample (away from the rim), and the alias table's 64-bit bin product exactly: cones
/// from 1 − cos = 2 (the sphere) down to 3.8·10⁻¹¹ (a 0.001° sun).
#[test]
fn light_warps_match_and_the_bin_product_is_exact() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(0x0001_1647);
    let cones = [2.0f32, 1.0, 0.1339746, 2.1e-5, 3.8e-11];
    let mut input = Vec::new();
    let mut cases = Vec::new();
    for k in 0..20_000 {
        let u = Vec2::new(to_unit_f32(rng.u32()), to_unit_f32(rng.u32()));
        let t = cones[k % cones.len()];
        // Products at the edges too: 0, 1, u32::MAX.
        let (a, b) = match k % 5 {
            0 => (u32::MAX, u32::MAX),
            1 => (rng.u32(), 1),
            _ => (rng.u32(), rng.u32() >> (k % 17)),
        };
        input.extend([u.x.to_bits(), u.y.to_bits(), t.to_bits(), a, b]);
        cases.push((u, t, a, b));
    }
    let got =
        kernel::run(&ctx, &shader(LIGHT_WARP_KERNEL), &input, 8 * cases.len(), cases.len() as u32).unwrap();
    let mut rows = Vec::new();
    let (mut tri_err, mut cone_err) = (0f32, 0f32);
    for (k, &(u, t, a, b)) in cases.iter().enumerate() {
        let g = &got[8 * k..8 * k + 8];
        let f = |i: usize| f32::from_bits(g[i]);
        let bary = square_to_uniform_triangle(u);
        let w = square_to_uniform_cone(u, t);
        let e_tri = (bary.x - f(0)).abs().max((bary.y - f(1)).abs());
        // The cone's directions are compared in units of its size, sin θmax ≈ √(2t).
        let scale = (2.0 * t).sqrt().min(1.0);
        let e_cone = ((w.x - f(2)).abs().max((w.y - f(3)).abs()) / scale).max((w.z - f(4)).abs());
        tri_err = tri_err.max(e_tri);
        cone_err = cone_err.max(e_cone);
        if !(e_tri <= WARP_TOLERANCE && e_cone <= WARP_TOLERANCE) {
            rows.push(format!(
                "  u = {u:?}, t = {t:e}: triangle {bary:?} vs ({}, {}), cone {w:?} vs ({}, {}, {})",
                f(0),
                f(1),
                f(2),
                f(3),
                f(4)
            ));
        }
        if uniform_cone_pdf(t).to_bits() != g[5] {
            rows.push(format!("  uniform_cone_pdf({t:e}): rust {} wgsl {}", uniform_cone_pdf(t), f(5)));
        }
        // Samples strictly inside (u.x < 1 − 1e-3) are in the cone on both sides.
        if u.x < 0.999 && (g[6] != 1 || !in_cone(w, Vec3::Z, t)) {
            rows.push(format!(
                "  in_cone(u = {u:?}, t = {t:e}): rust {} wgsl {}",
                in_cone(w, Vec3::Z, t),
                g[6]
            ));
        }
        let hi = ((u64::from(a) * u64::from(b)) >> 32) as u32;
        if hi != g[7] {
            rows.push(format!("  mul_hi({a}, {b}): rust {hi} wgsl {}", g[7]));
        }
    }
    eprintln!(
        "{} inputs; largest |WGSL − Rust|: triangle {tri_err:.2e}, cone {cone_err:.2e} (relative to its size)",
        cases.len()
    );
    assert!(rows.is_empty(), "{} mismatches:\n{}", rows.len(), rows[..rows.len().min(SHOW)].join("\n"));
}

/// Per case: `u` (2 words) and the three vertices relative to the viewpoint (9 words) in;
/// `spherical_triangle_solid_angle`, then `warp_spherical_triangle`'s direction (3), barycentrics
/// (2) and validity (0/1) out.
const SPHERICAL_TRIANGLE_KERNEL: &str = r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let r = 11u * i;
    let u = vec2<f32>(bitcast<f32>(input[r]), bitcast<f32>(input[r + 1u]));
    let a = vec3<f32>(bitcast<f32>(input[r + 2u]), bitcast<f32>(input[r + 3u]), bitcast<f32>(input[r + 4u]));
    let b = vec3<f32>(bitcast<f32>(input[r + 5u]), bitcast<f32>(input[r + 6u]), bitcast<f32>(input[r + 7u]));
    let c = vec3<f32>(bitcast<f32>(input[r + 8u]), bitcast<f32>(input[r + 9u]), bitcast<f32>(input[r + 10u]));
    let o = 7u * i;
    let omega = spherical_triangle_solid_angle(a, b, c);
    output[o] = bitcast<u32>(omega);
    let s = warp_spherical_triangle(u, a, b, c, omega);
    output[o + 1u] = bitcast<u32>(s.w.x);
    output[o + 2u] = bitcast<u32>(s.w.y);
    output[o + 3u] = bitcast<u32>(s.w.z);
    output[o + 4u] = bitcast<u32>(s.bary.x);
    output[o + 5u] = bitcast<u32>(s.bary.y);
    output[o + 6u] = select(0u, 1u, s.valid);
}
"#;

/// Largest relative difference of the WGSL solid angle from Rust's: the same formula in `f32`,
/// with sampling.wgsl's own `atan2` (WGSL's is bound only to 4096 ulp; lavapipe's was off by
/// 2·10⁻⁵); lavapipe's worst: 2.8·10⁻⁶. An MIS weight or a light sample's pdf off by 10⁻⁵ is
/// far below any image's noise.
const SOLID_ANGLE_TOLERANCE: f32 = 1e-5;

/// Largest difference of the WGSL sample's direction and barycentrics from Rust's (unit
/// vectors and barycentrics, so absolute): the same construction, but the drivers round
/// `normalize` and `length` their own way. lavapipe's worst is 4.9·10⁻⁴, a direction of a
/// triangle of 6.19 sr (nearly a hemisphere) at the horizon, where the construction is
/// ill-conditioned; 2× that keeps the check meaningful.
const SPHERICAL_SAMPLE_TOLERANCE: f32 = 1e-3;

/// The spherical triangle warp and its solid angle against Rust on triangles of 3·10⁻⁴ sr (the
/// smallest ever sampled this way) to 6 sr (nearly a hemisphere), at random `u`.
#[test]
fn spherical_triangle_warp_matches() {
    let Some(ctx) = test_context() else { return };
    let mut rng = Rng(0x5e_7a11);
    let mut input = Vec::new();
    let mut cases = Vec::new();
    while cases.len() < 20_000 {
        let u = Vec2::new(to_unit_f32(rng.u32()), to_unit_f32(rng.u32()));
        // A triangle around a random direction, at a random distance and size.
        let centre = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() + 0.05).normalize()
            * (0.1 + 10.0 * rng.f32());
        let size = centre.length() * 10f32.powf(-2.0 + 3.0 * rng.f32());
        let v =
            [0, 1, 2].map(|_| centre + size * Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5));
        let omega = spherical_triangle_solid_angle(v[0], v[1], v[2]);
        if !(3e-4..=6.22).contains(&omega) {
            continue;
        }
        input.extend(
            u.to_array()
                .iter()
                .chain(v.iter().flat_map(|p| p.to_array().to_vec()).collect::<Vec<_>>().iter())
                .map(|x| x.to_bits()),
        );
        cases.push((u, v, omega));
    }
    let got =
        kernel::run(&ctx, &shader(SPHERICAL_TRIANGLE_KERNEL), &input, 7 * cases.len(), cases.len() as u32)
            .unwrap();
    let mut rows = Vec::new();
    let (mut omega_err, mut sample_err) = (0f32, 0f32);
    let mut worst = String::new();
    for (k, &(u, v, omega)) in cases.iter().enumerate() {
        let g = &got[7 * k..7 * k + 7];
        let f = |i: usize| f32::from_bits(g[i]);
        let e_omega = (f(0) - omega).abs() / omega;
        omega_err = omega_err.max(e_omega);
        if !(e_omega <= SOLID_ANGLE_TOLERANCE) {
            rows.push(format!("  solid angle of {v:?}: rust {omega:e} wgsl {:e}", f(0)));
        }
        match (square_to_spherical_triangle(u, v[0], v[1], v[2], omega), g[6]) {
            (Some((w, b)), 1) => {
                let e = (w - Vec3::new(f(1), f(2), f(3)))
                    .abs()
                    .max_element()
                    .max((b - Vec2::new(f(4), f(5))).abs().max_element());
                if e > sample_err {
                    worst = format!(
                        "u = {u:?}, {v:?} ({omega:e} sr): rust w {w:?} b {b:?}, wgsl w ({}, {}, {}) b ({}, {})",
                        f(1),
                        f(2),
                        f(3),
                        f(4),
                        f(5)
                    );
                }
                sample_err = sample_err.max(e);
                if !(e <= SPHERICAL_SAMPLE_TOLERANCE) {
                    rows.push(format!("  u = {u:?}, {v:?} ({omega:e} sr): rust w {w:?} b {b:?}, wgsl w ({}, {}, {}) b ({}, {})", f(1), f(2), f(3), f(4), f(5)));
                }
            }
            (r, valid) => {
                rows.push(format!("  u = {u:?}, {v:?} ({omega:e} sr): rust {r:?}, wgsl valid {valid}"))
            }
        }
    }
    eprintln!(
        "{} triangles of 3e-4 to 6.22 sr; largest |WGSL − Rust|: solid angle {omega_err:.2e} (relative), sample {sample_err:.2e}, at\n  {worst}",
        cases.len()
    );
    assert!(rows.is_empty(), "{} mismatches:\n{}", rows.len(), rows[..rows.len().min(SHOW)].join("\n"));
}

/// The block between `BEGIN GENERATED` and `END GENERATED` is what `wgsl_generated()` emits from
/// the Rust constants (PMJ02 xors, Sobol directions, kind codes, f32 constants).
#[test]
fn generated_block_matches_the_rust_constants() {
    let src = wgsl::SAMPLING;
    let begin = src.find("// BEGIN GENERATED").expect("sampling.wgsl has no BEGIN GENERATED line");
    let body_start = begin + src[begin..].find('\n').expect("line end") + 1;
    let end = src.find("// END GENERATED").expect("sampling.wgsl has no END GENERATED line");
    let want = wgsl_generated();
    if src[body_start..end] != want {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/gpu");
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join("sampling_generated.wgsl");
        let _ = std::fs::write(&path, &want);
        panic!(
            "the generated block of gpu/src/wgsl/sampling.wgsl is stale; replace it with (also in {}):\n{want}",
            path.display()
        );
    }
    // The codes in the block are those SamplerParams carries.
    for kind in SamplerKind::ALL {
        let line = format!("const SAMPLER_KIND_{}: u32 = {}u;", kind.name().to_uppercase(), kind_code(kind));
        assert!(src.contains(&line), "{line}");
    }
}

/// `SamplerParams` has the same layout in WGSL as in Rust.
#[test]
fn sampler_params_layout_matches() {
    furnace_tests::layout::assert_gpu_struct::<SamplerParams>(wgsl::SAMPLING);
}

/// The module parses alone, declares no bindings (no globals at all), and names everything that
/// is not API with the `smp_` / `SMP_` prefix (modules are concatenated: no clashes).
#[test]
fn module_declares_no_bindings_and_prefixes_private_names() {
    let src = wgsl::SAMPLING;
    let module = naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)));
    let globals: Vec<_> = module.global_variables.iter().map(|(_, g)| g.name.clone()).collect();
    assert!(globals.is_empty(), "sampling.wgsl must not declare global variables or bindings: {globals:?}");
    const API: [&str; 19] = [
        "sampler_bits",
        "sampler_bits_2d",
        "sampler_value",
        "sampler_value_2d",
        "to_unit_f32",
        "warp_concentric_disk",
        "concentric_disk_pdf",
        "warp_uniform_hemisphere",
        "uniform_hemisphere_pdf",
        "warp_cosine_hemisphere",
        "cosine_hemisphere_pdf",
        "warp_uniform_triangle",
        "warp_uniform_cone",
        "uniform_cone_pdf",
        "in_cone",
        "spherical_triangle_solid_angle",
        "warp_spherical_triangle",
        "SphericalTriangleSample",
        "SamplerParams",
    ];
    let mut names: Vec<String> = module.functions.iter().filter_map(|(_, f)| f.name.clone()).collect();
    names.extend(module.constants.iter().filter_map(|(_, c)| c.name.clone()));
    names.extend(module.types.iter().filter_map(|(_, t)| t.name.clone()));
    for name in &names {
        let ok = API.contains(&name.as_str())
            || name.starts_with("SAMPLER_KIND_")
            || name.starts_with("smp_")
            || name.starts_with("SMP_");
        assert!(ok, "sampling.wgsl: `{name}` is neither API nor prefixed smp_ / SMP_");
    }
    for api in API {
        assert!(names.iter().any(|n| n == api), "sampling.wgsl lacks `{api}`");
    }
}
