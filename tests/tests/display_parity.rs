//! Parity of `tonemap.wgsl` (`furnace_gpu::display`) with `furnace-post`'s display maths:
//! exposure, `Tonemap::apply`, `linear_to_srgb` and `quantize_unorm8`, on the same inputs, for
//! every tone map and exposures of −4, −1.5, 0 and +2.5 EV; plus the module's constants, names
//! and the kernel's layout.
//!
//! `cargo test -p furnace-tests --test all display_parity:: -- --nocapture` prints the largest float
//! difference per tone map and exposure and the number of 8-bit codes that differ.
//!
//! The inputs: a log-spaced sweep of radiance over 1e-6 … 1e6 (grey and coloured triples, so
//! that PBR Neutral's min / max logic sees every channel order), random colours over 1e-7 … 1e7,
//! the knees (PBR Neutral's toe end 0.08 and compression start 0.76, ACES's root 7.24 and its
//! early-out at 8, the clamp at 1, the sRGB breakpoint 0.0031308 after each tone map) a few ulp
//! either side at each exposure, and 0, −0, negatives, NaNs, ±∞, ±f32::MAX and subnormals in
//! every channel and combination.
//!
//! Floats are compared within [`TOL`]; channels that post sends to a constant (non-finite or
//! non-positive input) exactly. The 8-bit codes — quantised on the host from the GPU floats,
//! and by `post_quantize_unorm8` on the GPU — must equal `furnace_post::pixel_to_srgb8` except
//! where post's exact value lies within [`TOL`] of a rounding boundary; those are counted and
//! bounded by [`BOUNDARY_FRACTION`].

use furnace_gpu::display::{self, DisplayParams, display_on_gpu, tonemap_code};
use furnace_post::{Tonemap, exposure_scale, linear_to_srgb, pixel_to_srgb8, quantize_unorm8};
use furnace_tests::Rng;
use furnace_tests::gpu::{self as kernel, test_context};
use glam::Vec3;
use std::fmt::Write as _;

/// Absolute tolerance on display values (all in [0, 1]). The WGSL evaluates the same
/// operations in the same order, but not all of them correctly rounded: `/` may be off by 2.5
/// ulp, `pow(x, y)` is `exp2(y·log2 x)` whose `log2` may be off by 2⁻²¹ absolute for x in
/// [0.5, 2] and whose `exp2` by (3 + 2|y·log2 x|) ulp, a compiler may fuse a·b + c, and
/// subnormals may be flushed; each a few ulp, ≲ 2.5e-7 below 1 (the ACES, clamp and sRGB paths
/// stay there: measured 2.4e-7 on lavapipe). The worst case is PBR Neutral's desaturation
/// `g = 1 − 1/(0.15·(peak − newPeak) + 1)`: when the peak is just past the compression start,
/// the quotient is ≈ 1 and g small, so the division's 2.5 ulp(1) ≈ 1.5e-7 becomes an absolute
/// error of g and of `newPeak·g`, the whole value of a dark channel; the sRGB OETF's slope at
/// the dark end, 12.92, makes it 12.92 · 1.5e-7 ≈ 1.9e-6 (measured on lavapipe: 1.27e-6). 4e-6
/// is twice that bound, and still 1000× below an 8-bit step (1/255 ≈ 3.9e-3).
const TOL: f32 = 4e-6;

/// At most this fraction of the 8-bit codes may differ from post's (each by one, and only
/// where post's value lies within [`TOL`] of a rounding boundary, which is checked per code).
/// A value spread over a code's width of 1/255 lies within the GPU's actual error e of a
/// boundary with probability 2·e·255: ≈ 1e-4 for ulp-level errors (e ≈ 2e-7, almost every
/// channel), and the GPU crosses the boundary in only part of those; most codes here are
/// saturated (0 or 255) or exact besides. Measured on lavapipe: 58 of 1.1·10⁷ codes, 5e-6.
/// 2e-4 is twice the ulp-level estimate: a hardware GPU with a few ulp more error passes, a
/// systematic difference (halves rounded to even, a constant off by an ulp) does not.
const BOUNDARY_FRACTION: f64 = 2e-4;

/// The exposures of the test, in EV.
const EVS: [f32; 4] = [-4.0, -1.5, 0.0, 2.5];

/// Rows of the worst-case table printed on failure.
const SHOW: usize = 20;

/// post's display value of one colour: `Tonemap::apply(c · scale)`, then `linear_to_srgb`.
fn post_display(c: Vec3, scale: f32, t: Tonemap) -> [f32; 3] {
    t.apply(c * scale).to_array().map(linear_to_srgb)
}

/// Odd values: zeros, negatives, NaNs (quiet, negative, with payloads), ±∞, ±f32::MAX, the
/// smallest normal and subnormals.
fn specials() -> Vec<f32> {
    vec![
        0.0,
        -0.0,
        -1e-6,
        -0.5,
        -1.0,
        -1e30,
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7f80_0001),
        f32::from_bits(0x7fc0_0001),
        f32::from_bits(0xffff_ffff),
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        -f32::MAX,
        f32::MIN_POSITIVE,
        f32::MIN_POSITIVE / 2.0,
        f32::from_bits(1),
        f32::from_bits(0x007f_ffff),
        -f32::from_bits(1),
        1e-40,
    ]
}

/// The f32 `n` steps (ulp) away from `x ≥ 0` (towards +∞ for n > 0).
fn step(x: f32, n: i32) -> f32 {
    f32::from_bits(x.to_bits().saturating_add_signed(n))
}

/// The least x in [0, 8] (as a float, by bisection over bit patterns) with `f(x) ≥ target`,
/// `f` non-decreasing.
fn crossing(f: impl Fn(f32) -> f32, target: f32) -> f32 {
    let (mut lo, mut hi) = (0u32, 8.0f32.to_bits());
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if f(f32::from_bits(mid)) >= target {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    f32::from_bits(lo)
}

/// Every input colour of the test (the same for each tone map and exposure).
fn inputs() -> Vec<Vec3> {
    let mut v = Vec::new();
    // The sweep: 2000 values per decade over 1e-6 … 1e6, grey and in coloured triples (the
    // swept channel first, middle and last; ratios that put the others below, above, and far
    // from it).
    let per_decade = 2000;
    let patterns = [
        Vec3::ONE,
        Vec3::new(1.0, 0.5, 0.1),
        Vec3::new(0.02, 1.0, 0.3),
        Vec3::new(0.7, 0.05, 1.0),
        Vec3::new(1e-3, 1.0, 30.0),
    ];
    for k in 0..=12 * per_decade {
        let x = 10f64.powf(-6.0 + f64::from(k) / f64::from(per_decade)) as f32;
        v.extend(patterns.iter().map(|&p| p * x));
    }
    // Random colours, each channel log-uniform over 1e-7 … 1e7 or (one in ten) zero.
    let mut rng = Rng::new(0x70e_3a9);
    for _ in 0..30_000 {
        let mut channel = || if rng.chance(0.1) { 0.0 } else { rng.range(-23.3, 23.3).exp2() };
        v.push(Vec3::new(channel(), channel(), channel()));
    }
    // The knees, a few ulp either side, at each exposure (divided by its scale).
    let offset = |m: f32| if m < 0.08 { m - 6.25 * m * m } else { 0.04 };
    let mut knees: Vec<Vec3> = Vec::new();
    for k in [0.08f32, 0.76, 0.8, 1.0, 7.2417, 8.0, 0.003_130_8, 0.040_45] {
        knees.push(Vec3::splat(k));
        knees.push(Vec3::new(k, 0.5, 0.3)); // PBR Neutral's toe: min at the knee
        knees.push(Vec3::new(0.2, k, 0.1)); // its peak at the knee, min ≥ 0.08 … or not
    }
    for m in [0.0f32, 0.01, 0.04, 0.079_999, 0.08] {
        // PBR Neutral's compression start: peak − offset(min) = 0.76.
        knees.push(Vec3::new(0.76 + offset(m), m, 0.3));
        knees.push(Vec3::new(m, 0.3, 0.76 + offset(m)));
    }
    // Where each tone map's grey output crosses the sRGB breakpoint, and where ACES reaches 1.
    for t in Tonemap::ALL {
        let x = crossing(|x| t.apply(Vec3::splat(x)).x, 0.003_130_8);
        knees.push(Vec3::splat(x));
        knees.push(Vec3::new(x, 1e-3, 0.5));
    }
    knees.push(Vec3::splat(crossing(furnace_post::aces_filmic, 1.0)));
    for ev in EVS {
        let s = exposure_scale(ev);
        for &k in &knees {
            for n in -4..=4 {
                // The first or the last channel steps: each knee row holds its knee in one of
                // them.
                let c = k / s;
                v.push(Vec3::new(step(c.x, n), c.y, c.z));
                v.push(Vec3::new(c.x, c.y, step(c.z, n)));
            }
        }
    }
    // The odd values: alone, in every channel of a few colours, and in pairs.
    let odd = specials();
    for &a in &odd {
        v.push(Vec3::splat(a));
        for base in [Vec3::ZERO, Vec3::splat(0.18), Vec3::new(0.5, 2.0, 10.0)] {
            for ch in 0..3 {
                let mut c = base;
                c[ch] = a;
                v.push(c);
            }
        }
        for &b in &odd {
            v.push(Vec3::new(a, b, 0.3));
            v.push(Vec3::new(0.05, a, b));
        }
    }
    v
}

/// Which channels of `c` post sends to a constant the GPU must reproduce exactly: for the
/// per-channel maps, non-finite and non-positive inputs (→ 0, or 1 for +∞); for PBR Neutral
/// (which mixes channels) every channel when one is +∞ (white) or all are non-finite or ≤ 0
/// (black).
fn exact_channels(c: Vec3, t: Tonemap) -> [bool; 3] {
    let constant = |x: f32| !x.is_finite() || x <= 0.0;
    match t {
        Tonemap::Aces | Tonemap::Clamp => c.to_array().map(constant),
        Tonemap::PbrNeutral => {
            let all = c.to_array().contains(&f32::INFINITY) || c.to_array().iter().all(|&x| constant(x));
            [all; 3]
        }
    }
}

/// Whether post's value `v` lies within [`TOL`] (and the f32 rounding of `v · 255`) of a
/// rounding boundary of `quantize_unorm8`, (k + ½)/255.
fn near_boundary(v: f32) -> bool {
    let t = f64::from(v) * 255.0;
    let distance = (t - (t.floor() + 0.5)).abs();
    distance <= 255.0 * (f64::from(TOL) + f64::from(f32::EPSILON))
}

/// One compared value that failed, for the table.
struct Failure {
    input: Vec3,
    ev: f32,
    tonemap: Tonemap,
    channel: usize,
    what: &'static str,
    cpu: String,
    gpu: String,
    err: f64,
}

fn table(failures: &mut [Failure]) -> String {
    failures.sort_by(|a, b| b.err.total_cmp(&a.err));
    let mut s = String::from(
        "| input | ev | tonemap | ch | what | cpu | gpu | error |\n|---|---|---|---|---|---|---|---|\n",
    );
    for f in failures.iter().take(SHOW) {
        let _ = writeln!(
            s,
            "| ({:e}, {:e}, {:e}) | {} | {} | {} | {} | {} | {} | {:.2e} |",
            f.input.x, f.input.y, f.input.z, f.ev, f.tonemap, f.channel, f.what, f.cpu, f.gpu, f.err
        );
    }
    s
}

/// The kernel of the code comparison: `post_display` and `post_quantize_unorm8` of each case
/// (in: r, g, b, scale, tonemap code; out: the three display values' bits, the three codes).
fn codes_kernel() -> String {
    wgsl_compose(
        r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let c = vec3<f32>(bitcast<f32>(input[5u * i]), bitcast<f32>(input[5u * i + 1u]), bitcast<f32>(input[5u * i + 2u]));
    let v = post_display(c, bitcast<f32>(input[5u * i + 3u]), input[5u * i + 4u]);
    output[6u * i] = bitcast<u32>(v.x);
    output[6u * i + 1u] = bitcast<u32>(v.y);
    output[6u * i + 2u] = bitcast<u32>(v.z);
    output[6u * i + 3u] = post_quantize_unorm8(v.x);
    output[6u * i + 4u] = post_quantize_unorm8(v.y);
    output[6u * i + 5u] = post_quantize_unorm8(v.z);
}
"#,
    )
}

/// The kernel harness's preamble, the display module, and `main`.
fn wgsl_compose(main: &str) -> String {
    furnace_gpu::wgsl::compose(&[kernel::PREAMBLE, &display::wgsl(), main])
}

/// `display_on_gpu` and `post_display` + `post_quantize_unorm8` against post, for every tone
/// map and exposure.
#[test]
fn display_matches_post() {
    let Some(ctx) = test_context() else { return };
    let colours = inputs();
    let n = colours.len();

    // The GPU codes, every (tone map, ev) in one dispatch.
    let mut words = Vec::with_capacity(5 * n * 12);
    for t in Tonemap::ALL {
        for ev in EVS {
            for c in &colours {
                words.extend(c.to_array().map(f32::to_bits));
                words.extend([exposure_scale(ev).to_bits(), tonemap_code(t)]);
            }
        }
    }
    let cases = words.len() / 5;
    let coded = kernel::run(&ctx, &codes_kernel(), &words, 6 * cases, cases as u32).unwrap();

    let mut failures = Vec::new();
    let mut summary = String::from(
        "| tonemap | ev | max |gpu − cpu| (display_on_gpu) | (kernel) | codes ≠ post (host-quantised) | (GPU-quantised) |\n|---|---|---|---|---|---|\n",
    );
    let (mut boundary_total, mut max_err_total) = (0usize, 0f64);
    let mut case = 0;
    for t in Tonemap::ALL {
        for ev in EVS {
            let scale = exposure_scale(ev);
            let gpu = display_on_gpu(&ctx, &colours, ev, t).unwrap();
            assert_eq!(gpu.len(), n);
            let (mut max_err, mut max_err_kernel) = (0f64, 0f64);
            let (mut host_mismatch, mut gpu_mismatch) = (0usize, 0usize);
            for (k, &c) in colours.iter().enumerate() {
                let cpu = post_display(c, scale, t);
                let codes = pixel_to_srgb8(c, scale, t);
                let exact = exact_channels(c, t);
                let out = &coded[6 * case..6 * case + 6];
                case += 1;
                for ch in 0..3 {
                    let mut fail = |what: &'static str, cpu: String, gpu: String, err: f64| {
                        failures.push(Failure { input: c, ev, tonemap: t, channel: ch, what, cpu, gpu, err })
                    };
                    let kernel_value = f32::from_bits(out[ch]);
                    // The floats: in [0, 1], within TOL, exact where post's value is a constant.
                    for (what, g, max) in [
                        ("display_on_gpu", gpu[k][ch], &mut max_err),
                        ("kernel post_display", kernel_value, &mut max_err_kernel),
                    ] {
                        let err = f64::from((g - cpu[ch]).abs());
                        let ok = if exact[ch] { g == cpu[ch] } else { err <= f64::from(TOL) };
                        if !(ok && (0.0..=1.0).contains(&g)) {
                            fail(
                                what,
                                format!("{:e}", cpu[ch]),
                                format!("{g:e}"),
                                if err.is_nan() { f64::INFINITY } else { err },
                            );
                        }
                        if err.is_finite() {
                            *max = max.max(err);
                        }
                    }
                    // GPU quantisation is post's quantize_unorm8 bit for bit on the same float.
                    let gpu_code = out[3 + ch];
                    if gpu_code != u32::from(quantize_unorm8(kernel_value)) {
                        fail(
                            "post_quantize_unorm8",
                            format!(
                                "{} (quantize_unorm8 of the GPU float {kernel_value:e})",
                                quantize_unorm8(kernel_value)
                            ),
                            gpu_code.to_string(),
                            f64::INFINITY,
                        );
                    }
                    // The codes: post's, except by one where its value is on a boundary.
                    let want = u32::from(codes[ch]);
                    for (what, got, count) in [
                        ("host code", u32::from(quantize_unorm8(gpu[k][ch])), &mut host_mismatch),
                        ("GPU code", gpu_code, &mut gpu_mismatch),
                    ] {
                        if got != want {
                            *count += 1;
                            if !(got.abs_diff(want) == 1 && near_boundary(cpu[ch]) && !exact[ch]) {
                                fail(what, format!("{want} ({:e})", cpu[ch]), got.to_string(), f64::INFINITY);
                            }
                        }
                    }
                }
            }
            boundary_total += host_mismatch + gpu_mismatch;
            max_err_total = max_err_total.max(max_err).max(max_err_kernel);
            let _ = writeln!(
                summary,
                "| {t} | {ev} | {max_err:.2e} | {max_err_kernel:.2e} | {host_mismatch} | {gpu_mismatch} |"
            );
        }
    }
    let codes = 2 * 3 * n * Tonemap::ALL.len() * EVS.len();
    let bound = (codes as f64 * BOUNDARY_FRACTION).ceil() as usize;
    eprintln!(
        "display parity on {}: {n} colours × {} tone maps × {} exposures; tolerance {TOL:e}, largest \
         difference {max_err_total:.2e}; codes off by one on a boundary: {boundary_total} of {codes} \
         (bound {bound})\n{summary}",
        ctx.describe(),
        Tonemap::ALL.len(),
        EVS.len()
    );
    let count = failures.len();
    assert!(
        failures.is_empty() && boundary_total <= bound,
        "WGSL display differs from furnace-post: {count} failures, {boundary_total} boundary codes (bound \
         {bound}); worst:\n{}",
        table(&mut failures)
    );
}

/// The scalar functions alone, on raw inputs (not sanitised first): `post_aces_filmic` as
/// `aces_filmic` (exact on its early-outs: x ≤ 0, NaN, x ≥ 8, ±∞), `post_linear_to_srgb` as
/// `linear_to_srgb` on [0, 1] (its linear branch is one correctly rounded product: exact for
/// normal x), `post_sanitize` as `Tonemap::Clamp` before its clamp (exact), and
/// `post_quantize_unorm8` as `quantize_unorm8` bit for bit on every input, including values
/// whose ·255 is a half (Rust rounds halves away from zero, WGSL's `round` to even).
#[test]
fn scalar_functions_match_post() {
    let Some(ctx) = test_context() else { return };
    let mut xs = specials();
    xs.extend([1.0, 1.5, 7.2417, 8.0, 1e30, 2.0, 255.0, 0.5, 0.999_999_9]);
    xs.extend([step(8.0, -1), step(8.0, 1), step(0.003_130_8, -1), step(0.003_130_8, 1)]);
    // Every 1021st float in [0, 1] (1.04·10⁶ of them, all exponents).
    xs.extend((0..=1.0f32.to_bits()).step_by(1021).map(f32::from_bits));
    // Around each code's boundary (k + ½)/255 and each exact code k/255.
    for k in 0..=255u32 {
        for centre in [(k as f32 + 0.5) / 255.0, k as f32 / 255.0] {
            xs.extend((-8..=8).map(|n| step(centre, n)));
        }
    }
    // A sweep of ACES's domain.
    xs.extend((0..=80_000).map(|k| k as f32 * 1e-4));
    let src = wgsl_compose(
        r#"
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = invocation_index(gid, groups);
    if i >= params.x { return; }
    let x = bitcast<f32>(input[i]);
    output[4u * i] = bitcast<u32>(post_aces_filmic(x));
    output[4u * i + 1u] = bitcast<u32>(post_linear_to_srgb(clamp(x, 0.0, 1.0)));
    output[4u * i + 2u] = bitcast<u32>(post_sanitize(vec3<f32>(x, 0.0, 0.0)).x);
    output[4u * i + 3u] = post_quantize_unorm8(x);
}
"#,
    );
    let words: Vec<u32> = xs.iter().map(|x| x.to_bits()).collect();
    let out = kernel::run(&ctx, &src, &words, 4 * xs.len(), xs.len() as u32).unwrap();
    let mut failures = Vec::new();
    let (mut aces_err, mut srgb_err) = (0f64, 0f64);
    for (k, &x) in xs.iter().enumerate() {
        let o = &out[4 * k..4 * k + 4];
        // (The table's ev, tone map and channel columns do not apply: 0, clamp, 0.)
        let mut fail = |what: &'static str, cpu: String, gpu: String, err: f64| {
            failures.push(Failure {
                input: Vec3::splat(x),
                ev: 0.0,
                tonemap: Tonemap::Clamp,
                channel: 0,
                what,
                cpu,
                gpu,
                err,
            })
        };
        // aces_filmic: exact on the early-outs, within TOL elsewhere.
        let (cpu, gpu) = (furnace_post::aces_filmic(x), f32::from_bits(o[0]));
        let err = f64::from((gpu - cpu).abs());
        let early = !(x > 0.0) || x >= 8.0;
        if !(if early { gpu == cpu } else { err <= f64::from(TOL) }) {
            fail(
                "post_aces_filmic",
                format!("{cpu:e}"),
                format!("{gpu:e}"),
                if err.is_nan() { f64::INFINITY } else { err },
            );
        }
        if !early {
            aces_err = aces_err.max(err);
        }
        // linear_to_srgb on [0, 1]: the linear branch exact for normal x, the power branch
        // within TOL. (NaN clamps to either bound on the GPU; skipped.)
        if !x.is_nan() {
            let c = x.clamp(0.0, 1.0);
            let (cpu, gpu) = (linear_to_srgb(c), f32::from_bits(o[1]));
            let err = f64::from((gpu - cpu).abs());
            let linear_branch = c <= 0.003_130_8 && (c == 0.0 || c.is_normal());
            if !(if linear_branch { gpu == cpu } else { err <= f64::from(TOL) }) {
                fail(
                    "post_linear_to_srgb",
                    format!("{cpu:e}"),
                    format!("{gpu:e}"),
                    if err.is_nan() { f64::INFINITY } else { err },
                );
            }
            srgb_err = srgb_err.max(err);
        }
        // sanitize: Tonemap::Clamp is sanitize then a clamp to [0, 1]; compare before the clamp
        // through its definition (NaN → 0, clamp to [0, f32::MAX]). A positive subnormal may
        // come back flushed to 0 (WGSL allows it).
        let cpu = if x.is_nan() { 0.0 } else { x.clamp(0.0, f32::MAX) };
        let gpu = f32::from_bits(o[2]);
        let flushed = x.is_subnormal() && x > 0.0 && gpu == 0.0;
        if !(gpu == cpu || flushed) {
            fail("post_sanitize", format!("{cpu:e}"), format!("{gpu:e}"), f64::INFINITY);
        }
        // quantize_unorm8: bit for bit.
        if o[3] != u32::from(quantize_unorm8(x)) {
            fail("post_quantize_unorm8", quantize_unorm8(x).to_string(), o[3].to_string(), f64::INFINITY);
        }
    }
    eprintln!(
        "scalar functions on {} inputs: largest |gpu − cpu| aces_filmic {aces_err:.2e}, linear_to_srgb \
         {srgb_err:.2e} (tolerance {TOL:e}); sanitize and quantize_unorm8 exact",
        xs.len()
    );
    let count = failures.len();
    assert!(failures.is_empty(), "{count} failures; worst:\n{}", table(&mut failures));
}

/// The module parses alone (with its generated constants), declares no bindings, names its
/// private items `post_` / `POST_`, takes the `TONEMAP_*` codes from the Rust (it declares none
/// itself), and its f32 constants are Rust's bit for bit; the kernel of `display_on_gpu`
/// parses and its `DisplayParams` has the Rust layout.
#[test]
fn module_constants_and_names_match_post() {
    let src = display::wgsl();
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let constant = |name: &str| -> naga::Literal {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no const {name} in tonemap.wgsl"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(l) => l,
            ref e => panic!("const {name} is not a literal: {e:?}"),
        }
    };
    for t in Tonemap::ALL {
        let name = format!("TONEMAP_{}", t.name().to_uppercase().replace('-', "_"));
        assert_eq!(constant(&name), naga::Literal::U32(tonemap_code(t)), "{name}");
        let declared = display::TONEMAP_WGSL
            .lines()
            .any(|l| !l.trim_start().starts_with("//") && l.contains(&format!("const {name}")));
        assert!(!declared, "{name} is generated from the Rust, not kept in tonemap.wgsl");
    }
    let distinct: std::collections::HashSet<u32> = Tonemap::ALL.into_iter().map(tonemap_code).collect();
    assert_eq!(distinct.len(), Tonemap::ALL.len());
    // post's constants (function-local there, so spelt again here, as post spells them; Rust
    // evaluates `0.8 - 0.04` and `1.0 / 2.4` in f32).
    const START_COMPRESSION: f32 = 0.8 - 0.04;
    let floats: [(&str, f32); 17] = [
        ("POST_F32_MAX", f32::MAX),
        ("POST_ACES_A", 2.51),
        ("POST_ACES_B", 0.03),
        ("POST_ACES_C", 2.43),
        ("POST_ACES_D", 0.59),
        ("POST_ACES_E", 0.14),
        ("POST_PBR_START_COMPRESSION", START_COMPRESSION),
        ("POST_PBR_DESATURATION", 0.15),
        ("POST_PBR_D", 1.0 - START_COMPRESSION),
        ("POST_PBR_TOE_END", 0.08),
        ("POST_PBR_TOE_SCALE", 6.25),
        ("POST_PBR_OFFSET", 0.04),
        ("POST_SRGB_BREAK", 0.003_130_8),
        ("POST_SRGB_SLOPE", 12.92),
        ("POST_SRGB_INV_GAMMA", 1.0 / 2.4),
        ("POST_SRGB_SCALE", 1.055),
        ("POST_SRGB_OFFSET", 0.055),
    ];
    for (name, want) in floats {
        match constant(name) {
            naga::Literal::F32(v) => assert_eq!(v.to_bits(), want.to_bits(), "{name}: {v:e} vs {want:e}"),
            l => panic!("{name} is not f32: {l:?}"),
        }
    }
    let globals: Vec<_> = module.global_variables.iter().filter_map(|(_, g)| g.name.clone()).collect();
    assert!(globals.is_empty(), "tonemap.wgsl must not declare bindings: {globals:?}");
    let mut names: Vec<String> = module.functions.iter().filter_map(|(_, f)| f.name.clone()).collect();
    names.extend(module.constants.iter().filter_map(|(_, c)| c.name.clone()));
    names.extend(module.types.iter().filter_map(|(_, t)| t.name.clone()));
    for name in &names {
        assert!(
            name.starts_with("post_") || name.starts_with("POST_") || name.starts_with("TONEMAP_"),
            "tonemap.wgsl: `{name}` is not prefixed post_ / POST_ / TONEMAP_"
        );
    }
    for api in [
        "post_sanitize",
        "post_aces_filmic",
        "post_pbr_neutral",
        "post_tonemap",
        "post_linear_to_srgb",
        "post_display",
        "post_quantize_unorm8",
    ] {
        assert!(names.iter().any(|n| n == api), "tonemap.wgsl lacks `{api}`");
    }
    furnace_tests::layout::assert_gpu_struct::<DisplayParams>(&display::kernel_source());
}

/// No colours: no dispatch, an empty result.
#[test]
fn display_on_gpu_of_nothing_is_empty() {
    let Some(ctx) = test_context() else { return };
    assert!(display_on_gpu(&ctx, &[], 0.0, Tonemap::Aces).unwrap().is_empty());
}
