// furnace-gpu: brdf module (see src/wgsl.rs), the twin of `furnace-brdf`: this file (the
// constants, records and scalar helpers of its lib.rs) followed by one file per Rust file, in
// dependency order: fresnel, ggx, turquin, specular, lambert, metallic_roughness.
//
// The glTF metallic-roughness BSDF (`furnace_brdf::MetallicRoughness`: a Lambert lobe and one
// merged GGX lobe with Schlick Fresnel, separable or height-correlated Smith masking, NDF /
// VNDF (Heitz 2018) / spherical-cap (Dupuy & Benyoub 2023) sampling, Turquin 2019 energy
// compensation), function for function, branch for branch, with the same operation order.
// Everything is in the local shading frame, z = normal, like the Rust. Conventions (as
// `furnace_brdf::Bsdf`): `bsdf_eval` includes cos θi; `bsdf_sample` returns
// weight = eval/pdf and the solid-angle pdf; directions within BSDF_MIN_COS of the horizon count
// as below it.
//
// Public API (what an integrator calls):
//   struct BsdfParams                        the per-hit material record (Rust twin:
//                                            `furnace_gpu::brdf::BsdfParams`, layout checked)
//   fn bsdf_params(base_color, metallic, roughness, specular_factor, specular_color, flags)
//                                            = `MetallicRoughness::new` (textures evaluated on the GPU)
//   fn bsdf_eval(m, wo, wi) -> vec3<f32>     = `Bsdf::eval`
//   fn bsdf_pdf(m, wo, wi) -> f32            = `Bsdf::pdf`
//   fn bsdf_sample(m, wo, u_lobe, u) -> BsdfSample
//                                            = `Bsdf::sample(wo, uc, u)`: the same three numbers
//                                            in the same roles; `None` is lobe == BSDF_LOBE_NONE
//   fn bsdf_specular_probability(m, wo) -> f32
//   fn bsdf_e_ss(mu, alpha, height_correlated) -> f32   = `turquin::e_ss`
// Private helpers are prefixed `brdf_`.
//
// Requires, declared by the composing shader (this module declares no bindings): the generated
// `furnace_gpu::brdf::declarations()` (flag and lobe codes, `struct BsdfParams`), and
//   var<storage, read> turquin_table: array<f32>;
// holding `furnace_gpu::brdf::turquin_table()`: 2 × 64 × 64 floats, E_ss(μ, α) of
// `furnace_brdf::turquin`, index (m·64 + j)·64 + i with m = 0 for the separable table
// (E_SS_SEPARABLE), 1 for the height-correlated one (E_SS_HEIGHT_CORRELATED), j the α row
// (α = (j/63)³) and i the μ column (μ = (i/63)²).
//
// NaN: WGSL lets a compiler assume that floats are not NaN, so the guards that the Rust writes
// as `!(x > 0.0)` (which reject NaN) are written here with an explicit bit test where a NaN can
// arrive (material inputs, computed pdfs).
//
// Requires the sampling module (`furnace_gpu::wgsl::SAMPLING`) before it: Lambert sampling uses
// its `warp_cosine_hemisphere` and `cosine_hemisphere_pdf`, twins of furnace-sampling's warps.

// ---- constants (Rust twins in `furnace_gpu::brdf`, checked by furnace-tests' brdf_parity.rs) ----

// `furnace_brdf::MIN_COS`.
const BSDF_MIN_COS: f32 = 1e-15;
// `furnace_brdf::ggx::ALPHA_MIN`.
const BSDF_ALPHA_MIN: f32 = 1e-4;
// `furnace_brdf::turquin::TABLE_SIZE`.
const BSDF_TABLE_SIZE: u32 = 64u;

// The codes of BsdfParams.flags (BSDF_FLAG_*, BSDF_SAMPLING_*: masking bit 0, sampling method
// bits 1–2, compensation bit 3), of BsdfSample.lobe (BSDF_LOBE_*) and the luminance weights
// (BSDF_LUMINANCE) are declared before this module, generated from furnace_gpu::brdf.

// std::f32::consts.
const BRDF_PI: f32 = 3.14159265358979323846264338327950288;
const BRDF_TAU: f32 = 6.28318530717958647692528676655900577;
const BRDF_FRAC_1_PI: f32 = 0.318309886183790671537767526745028724;
// f32::MAX.
const BRDF_F32_MAX: f32 = 3.40282347e38;

// ---- records ----

// The per-hit material `BsdfParams` (`MetallicRoughness` after its constructor, in the form the
// lobes use) is declared before this module, generated from furnace_gpu::brdf::BsdfParams.

// A sampled direction (`Option<furnace_brdf::Sample>`): lobe == BSDF_LOBE_NONE (with everything
// else 0) is `None`.
struct BsdfSample {
    // Towards the light, unit length, z > 0.
    wi: vec3<f32>,
    // The solid-angle pdf, equal to bsdf_pdf(m, wo, wi).
    pdf: f32,
    // eval/pdf per channel.
    weight: vec3<f32>,
    // BSDF_LOBE_*.
    lobe: u32,
}

fn brdf_no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), BSDF_LOBE_NONE);
}

// ---- scalar helpers ----

// x is NaN (bit test: survives compilers that assume no NaN).
fn brdf_is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// x is finite (not NaN, not ±∞), by its bits.
fn brdf_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) < 0x7f800000u;
}

// `x > 0.0 && x.is_finite()`.
fn brdf_positive_finite(x: f32) -> bool {
    return brdf_is_finite(x) && x > 0.0;
}

// `f32::clamp` for lo ≤ hi with a non-NaN x.
fn brdf_clamp(x: f32, lo: f32, hi: f32) -> f32 {
    var r = x;
    if r < lo { r = lo; }
    if r > hi { r = hi; }
    return r;
}

// `f32::max(x, 0.0)` (NaN → 0, as Rust's max ignores NaN).
fn brdf_max0(x: f32) -> f32 {
    if x > 0.0 { return x; }
    return 0.0;
}

// `sanitize` of metallic_roughness.rs: NaN → default, else clamp to [lo, hi].
fn brdf_sanitize(x: f32, lo: f32, hi: f32, default_value: f32) -> f32 {
    if brdf_is_nan(x) { return default_value; }
    return brdf_clamp(x, lo, hi);
}

// `clamp_rgb` of lib.rs: each channel clamped to [0, hi], NaN → 0.
fn brdf_clamp_rgb(c: vec3<f32>, hi: f32) -> vec3<f32> {
    return vec3<f32>(brdf_sanitize(c.x, 0.0, hi, 0.0), brdf_sanitize(c.y, 0.0, hi, 0.0),
                     brdf_sanitize(c.z, 0.0, hi, 0.0));
}

// glam's `Vec3::max_element`.
fn brdf_max_element(c: vec3<f32>) -> f32 {
    var m = c.z;
    if c.y > m { m = c.y; }
    if c.x > m { m = c.x; }
    return m;
}

// glam's `dot`: (x·x') + (y·y') + (z·z'), in that order.
fn brdf_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

// glam's `normalize_or`: v·(1/|v|) if that reciprocal is finite and positive, else fallback.
fn brdf_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / sqrt(brdf_dot(v, v));
    if brdf_positive_finite(rcp) {
        return v * rcp;
    }
    return fallback;
}

// `f32::cbrt` for x ≥ 0: exp2(log2(x)/3), refined by one Newton step (to within an ulp or so).
fn brdf_cbrt(x: f32) -> f32 {
    if !(x > 0.0) { return 0.0; }
    let y = exp2(log2(x) / 3.0);
    return y - (y * y * y - x) / (3.0 * y * y);
}

// `furnace_brdf::above`: above the horizon by more than MIN_COS (false for NaN).
fn brdf_above(w: vec3<f32>) -> bool {
    return w.z > BSDF_MIN_COS;
}

// `furnace_brdf::luminance` (Rec. 709; BSDF_LUMINANCE is generated from
// `furnace_sampling::LUMINANCE`).
fn brdf_luminance(c: vec3<f32>) -> f32 {
    return brdf_dot(c, BSDF_LUMINANCE);
}
