// furnace-gpu: the display maths of furnace-post (post/src/tonemap.rs, post/src/srgb.rs), for a
// viewer that tone-maps the film on the GPU: exposure scale, `Tonemap::apply`, the exact sRGB
// OETF and 8-bit quantisation, line by line, with the same constants and branches.
//
// Requires the composing shader to declare before it (generated from the Rust:
// furnace_gpu::display::consts_wgsl):
//   const TONEMAP_ACES: u32; const TONEMAP_PBR_NEUTRAL: u32; const TONEMAP_CLAMP: u32;
// Declares no bindings. Names that are not API start with `post_` / `POST_` (modules are
// concatenated: no clashes).
//
// NaN and +∞ are recognised by their bits, not by comparisons (`x != x`, `x > MAX`): WGSL lets
// an implementation assume that no NaN or infinity occurs at run time, and a compiler may fold
// such comparisons away. The exposed film can hold both (a +∞ sample, MAX · scale overflowing).

// The f32 constants that are not exact small binary fractions (0.5, 1, 255 stay literals), each
// rounded as Rust rounds it: an `f` suffix makes them f32 literals and their arithmetic f32, as
// in the Rust, rather than abstract floats rounded to f32 once at the end (or twice: decimal →
// f64 → f32). tests/display_parity.rs compares them with Rust's bit for bit.
const POST_F32_MAX: f32 = 3.40282347e38f;
// aces_filmic's A … E.
const POST_ACES_A: f32 = 2.51f;
const POST_ACES_B: f32 = 0.03f;
const POST_ACES_C: f32 = 2.43f;
const POST_ACES_D: f32 = 0.59f;
const POST_ACES_E: f32 = 0.14f;
// pbr_neutral's START_COMPRESSION, DESATURATION and D.
const POST_PBR_START_COMPRESSION: f32 = 0.8f - 0.04f;
const POST_PBR_DESATURATION: f32 = 0.15f;
const POST_PBR_D: f32 = 1.0f - POST_PBR_START_COMPRESSION;
// pbr_neutral's toe: offset x − 6.25x² below x = 0.08, else 0.04.
const POST_PBR_TOE_END: f32 = 0.08f;
const POST_PBR_TOE_SCALE: f32 = 6.25f;
const POST_PBR_OFFSET: f32 = 0.04f;
// linear_to_srgb's breakpoint, slope, exponent 1/2.4 and the power branch's 1.055 and 0.055.
const POST_SRGB_BREAK: f32 = 0.0031308f;
const POST_SRGB_SLOPE: f32 = 12.92f;
const POST_SRGB_INV_GAMMA: f32 = 1.0f / 2.4f;
const POST_SRGB_SCALE: f32 = 1.055f;
const POST_SRGB_OFFSET: f32 = 0.055f;

// True for a NaN (exponent all ones, mantissa not zero), whatever the sign.
fn post_is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// post's `sanitize` of one channel: NaN → 0; everything else clamped to [0, f32::MAX] (so
// −∞ → 0, +∞ → f32::MAX). Negatives (−0 and −∞ included) are told by the sign bit and +∞ by its
// bits, so no comparison sees a NaN or an infinity; the clamp of a finite non-negative value is
// the value itself.
fn post_sanitize_channel(x: f32) -> f32 {
    let bits = bitcast<u32>(x);
    if post_is_nan(x) {
        return 0.0;
    }
    if (bits & 0x80000000u) != 0u {
        return 0.0;
    }
    if bits == 0x7f800000u {
        return POST_F32_MAX;
    }
    return x;
}

// post's `sanitize` of each channel (Tonemap::apply's first step).
fn post_sanitize(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(post_sanitize_channel(c.x), post_sanitize_channel(c.y), post_sanitize_channel(c.z));
}

// furnace_post::aces_filmic: Narkowicz's fit saturate(x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)),
// with its early-outs: x ≤ 0 and NaN → 0, x ≥ 8 and +∞ → 1.
fn post_aces_filmic(x: f32) -> f32 {
    // Rust's `!(x > 0.0)` (NaN, negatives, −∞, ±0) as bits: the floats > 0 and not NaN are
    // exactly the bit patterns 1 ..= 0x7f800000 (+∞ included); the sign bit puts every negative
    // (and −NaN) above 0x7f800000, positive NaNs are above it too.
    let bits = bitcast<u32>(x);
    if bits == 0u || bits > 0x7f800000u {
        return 0.0;
    }
    // f(8) > 1: saturated already; avoids ∞/∞ for huge x. For positive non-NaN floats the bit
    // order is the value order, so this is Rust's `x >= 8.0` with +∞ kept in it.
    if bits >= bitcast<u32>(8.0f) {
        return 1.0;
    }
    let y = (x * (POST_ACES_A * x + POST_ACES_B)) / (x * (POST_ACES_C * x + POST_ACES_D) + POST_ACES_E);
    return clamp(y, 0.0, 1.0);
}

// furnace_post::pbr_neutral: Khronos PBR Neutral on the whole colour. The input must be finite
// and non-negative (post_tonemap sanitises it first).
fn post_pbr_neutral(color: vec3<f32>) -> vec3<f32> {
    // glam's min_element / max_element: x against (y against z); no NaN here, so the order of
    // the comparisons cannot matter.
    let x = min(color.x, min(color.y, color.z));
    var offset = POST_PBR_OFFSET;
    if x < POST_PBR_TOE_END {
        offset = x - POST_PBR_TOE_SCALE * x * x;
    }
    let c = color - vec3<f32>(offset);
    let peak = max(c.x, max(c.y, c.z));
    if peak < POST_PBR_START_COMPRESSION {
        return c;
    }
    let new_peak = 1.0 - POST_PBR_D * POST_PBR_D / (peak + POST_PBR_D - POST_PBR_START_COMPRESSION);
    let compressed = c * (new_peak / peak);
    let g = 1.0 - 1.0 / (POST_PBR_DESATURATION * (peak - new_peak) + 1.0);
    // GLSL mix(a, b, t) = a·(1 − t) + b·t, spelt out as the Rust does: exactly b at t = 1.
    return compressed * (1.0 - g) + vec3<f32>(new_peak) * g;
}

// furnace_post::Tonemap::apply of one exposed linear colour (`tonemap`: a TONEMAP_* code; an
// unknown code clamps). Sanitise, tone-map, clamp to [0, 1]. Never NaN.
fn post_tonemap(c: vec3<f32>, tonemap: u32) -> vec3<f32> {
    let s = post_sanitize(c);
    var mapped = s;
    if tonemap == TONEMAP_ACES {
        mapped = vec3<f32>(post_aces_filmic(s.x), post_aces_filmic(s.y), post_aces_filmic(s.z));
    } else if tonemap == TONEMAP_PBR_NEUTRAL {
        mapped = post_pbr_neutral(s);
    }
    return clamp(mapped, vec3<f32>(0.0), vec3<f32>(1.0));
}

// furnace_post::linear_to_srgb: the exact piecewise sRGB OETF (IEC 61966-2-1), 12.92·x up to
// 0.0031308, else 1.055·x^(1/2.4) − 0.055. NaN takes the power branch and stays NaN, as in the
// Rust; `pow` only ever sees x > 0.0031308 (WGSL's pow is undefined for x < 0).
fn post_linear_to_srgb(x: f32) -> f32 {
    if x <= POST_SRGB_BREAK {
        return POST_SRGB_SLOPE * x;
    }
    return POST_SRGB_SCALE * pow(x, POST_SRGB_INV_GAMMA) - POST_SRGB_OFFSET;
}

// The display value of one linear colour: exposure `scale` (furnace_post::exposure_scale(ev),
// computed on the host), post_tonemap, post_linear_to_srgb per channel. sRGB-encoded, in
// [0, 1]: what furnace_post::pixel_to_srgb8 quantises, and what a fragment shader writes to a
// non-sRGB 8-bit target (or post_quantize_unorm8 turns into the 8-bit code).
fn post_display(linear: vec3<f32>, scale: f32, tonemap: u32) -> vec3<f32> {
    let mapped = post_tonemap(linear * scale, tonemap);
    return vec3<f32>(post_linear_to_srgb(mapped.x), post_linear_to_srgb(mapped.y), post_linear_to_srgb(mapped.z));
}

// furnace_post::quantize_unorm8: round(clamp(v, 0, 1) · 255) with halves away from zero (Rust's
// f32::round, not WGSL's round, which takes halves to even); NaN → 0.
fn post_quantize_unorm8(v: f32) -> u32 {
    if post_is_nan(v) {
        return 0u;
    }
    let t = clamp(v, 0.0, 1.0) * 255.0;
    let f = floor(t);
    // t ≥ 0 and t − floor(t) is exact, so this is the Rust rounding bit for bit (t + 0.5 would
    // round up below 0.5, at t = 0.5 − 2⁻²⁵).
    return u32(f) + select(0u, 1u, t - f >= 0.5);
}
