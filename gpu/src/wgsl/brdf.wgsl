// furnace-gpu: brdf module (see src/wgsl.rs), the twin of `furnace-brdf`.
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
// bits 1–2, compensation bit 3) and of BsdfSample.lobe (BSDF_LOBE_*) are declared before this
// module, generated from furnace_gpu::brdf.

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

// `sanitize` of material.rs: NaN → default, else clamp to [lo, hi].
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

// `furnace_brdf::luminance` (Rec. 709).
fn brdf_luminance(c: vec3<f32>) -> f32 {
    return brdf_dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// ---- fresnel.rs ----

// `schlick`: F0 + (F90 − F0)(1 − cos θd)^5, cos θd clamped to [0, 1].
fn brdf_schlick(f0: vec3<f32>, f90: vec3<f32>, cos_theta_d: f32) -> vec3<f32> {
    let m = brdf_clamp(1.0 - brdf_clamp(cos_theta_d, 0.0, 1.0), 0.0, 1.0);
    let m2 = m * m;
    return f0 + (f90 - f0) * (m2 * m2 * m);
}

// ---- ggx.rs (the distribution; α already clamped) ----

// `Ggx::a`: √(z² + α²(x² + y²)).
fn brdf_ggx_a(alpha: f32, w: vec3<f32>) -> f32 {
    let a2 = alpha * alpha;
    return sqrt(w.z * w.z + a2 * (w.x * w.x + w.y * w.y));
}

// `Ggx::d`: 1/(π α² ((x² + y²)/α² + z²)²), 0 below the horizon.
fn brdf_ggx_d(alpha: f32, wm: vec3<f32>) -> f32 {
    if !(wm.z > 0.0) { return 0.0; }
    let a2 = alpha * alpha;
    let t = (wm.x * wm.x + wm.y * wm.y) / a2 + wm.z * wm.z;
    return 1.0 / (BRDF_PI * a2 * t * t);
}

// `Ggx::g1`: 2|z|/(|z| + a), 0 at the horizon.
fn brdf_ggx_g1(alpha: f32, w: vec3<f32>) -> f32 {
    let z = abs(w.z);
    let den = z + brdf_ggx_a(alpha, w);
    if den > 0.0 { return 2.0 * z / den; }
    return 0.0;
}

// `Ggx::g2`: separable G1·G1 or height-correlated 2 zo zi/(ao zi + ai zo).
fn brdf_ggx_g2(alpha: f32, wo: vec3<f32>, wi: vec3<f32>, height_correlated: bool) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) { return 0.0; }
    if height_correlated {
        let ao = brdf_ggx_a(alpha, wo);
        let ai = brdf_ggx_a(alpha, wi);
        return 2.0 * wo.z * wi.z / (ao * wi.z + ai * wo.z);
    }
    return brdf_ggx_g1(alpha, wo) * brdf_ggx_g1(alpha, wi);
}

// `Ggx::eval_cos`: D·G2/(4 zo) without the 1/zo singularity.
fn brdf_ggx_eval_cos(alpha: f32, wo: vec3<f32>, wi: vec3<f32>, wm: vec3<f32>, height_correlated: bool) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) { return 0.0; }
    let ao = brdf_ggx_a(alpha, wo);
    let ai = brdf_ggx_a(alpha, wi);
    var den: f32;
    if height_correlated {
        den = 2.0 * (ao * wi.z + ai * wo.z);
    } else {
        den = (wo.z + ao) * (wi.z + ai);
    }
    return brdf_ggx_d(alpha, wm) * wi.z / den;
}

// `Ggx::sample_ndf`: tan²θm = α²u₀/(1 − u₀), φ = 2πu₁.
fn brdf_ggx_sample_ndf(alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let tan2 = alpha * alpha * u.x / (1.0 - u.x);
    let cos_theta = 1.0 / sqrt(1.0 + tan2);
    let sin_theta = sqrt(tan2) * cos_theta;
    let phi = BRDF_TAU * u.y;
    let s = sin(phi);
    let c = cos(phi);
    return vec3<f32>(sin_theta * c, sin_theta * s, cos_theta);
}

// `Ggx::sample_vndf_heitz`: Heitz 2018, listing 1.
fn brdf_ggx_sample_vndf_heitz(alpha: f32, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let vh = brdf_normalize_or(vec3<f32>(alpha * wo.x, alpha * wo.y, wo.z), vec3<f32>(0.0, 0.0, 1.0));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    // glam's cross: (y·z' − z·y', z·x' − x·z', x·y' − y·x').
    let t2 = vec3<f32>(vh.y * t1.z - vh.z * t1.y, vh.z * t1.x - vh.x * t1.z, vh.x * t1.y - vh.y * t1.x);
    let r = sqrt(u.x);
    let phi = BRDF_TAU * u.y;
    let s = sin(phi);
    let c = cos(phi);
    let p1 = r * c;
    var p2 = r * s;
    let h = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - h) * sqrt(brdf_max0(1.0 - p1 * p1)) + h * p2;
    let nh = p1 * t1 + p2 * t2 + sqrt(brdf_max0(1.0 - p1 * p1 - p2 * p2)) * vh;
    return brdf_normalize_or(vec3<f32>(alpha * nh.x, alpha * nh.y, brdf_max0(nh.z)), vec3<f32>(0.0, 0.0, 1.0));
}

// `Ggx::sample_vndf_caps`: Dupuy & Benyoub 2023, listing 3.
fn brdf_ggx_sample_vndf_caps(alpha: f32, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let wi_std = brdf_normalize_or(vec3<f32>(alpha * wo.x, alpha * wo.y, wo.z), vec3<f32>(0.0, 0.0, 1.0));
    let phi = BRDF_TAU * u.x;
    let s = sin(phi);
    let c = cos(phi);
    // Rust: (1 − u.y).mul_add(1 + z, −z).
    let z = fma(1.0 - u.y, 1.0 + wi_std.z, -wi_std.z);
    let sin_theta = sqrt(brdf_clamp(1.0 - z * z, 0.0, 1.0));
    let wm_std = vec3<f32>(sin_theta * c, sin_theta * s, z) + wi_std;
    return brdf_normalize_or(vec3<f32>(alpha * wm_std.x, alpha * wm_std.y, wm_std.z), vec3<f32>(0.0, 0.0, 1.0));
}

// `Ggx::sample_wm`.
fn brdf_ggx_sample_wm(alpha: f32, wo: vec3<f32>, u: vec2<f32>, method: u32) -> vec3<f32> {
    if method == BSDF_SAMPLING_NDF { return brdf_ggx_sample_ndf(alpha, u); }
    if method == BSDF_SAMPLING_VNDF { return brdf_ggx_sample_vndf_heitz(alpha, wo, u); }
    return brdf_ggx_sample_vndf_caps(alpha, wo, u);
}

// `Ggx::pdf_reflected`: NDF D·cos θm/(4 cos_om); VNDF D/(2(cos θo + a(ωo))).
fn brdf_ggx_pdf_reflected(alpha: f32, wo: vec3<f32>, wm: vec3<f32>, cos_om: f32, method: u32) -> f32 {
    if !(brdf_above(wo) && cos_om > 0.0) { return 0.0; }
    if method == BSDF_SAMPLING_NDF {
        return brdf_ggx_d(alpha, wm) * brdf_max0(wm.z) / (4.0 * cos_om);
    }
    return brdf_ggx_d(alpha, wm) / (2.0 * (wo.z + brdf_ggx_a(alpha, wo)));
}

// `ggx::reflect`: 2(ωo·ωm)ωm − ωo.
fn brdf_reflect(wo: vec3<f32>, wm: vec3<f32>) -> vec3<f32> {
    return 2.0 * brdf_dot(wo, wm) * wm - wo;
}

// ---- turquin.rs ----

// `turquin::e_ss`: bilinear lookup of E_ss(μ, α), μ = x², α = y³ on the 64² grid.
fn bsdf_e_ss(mu: f32, alpha: f32, height_correlated: bool) -> f32 {
    let n = f32(BSDF_TABLE_SIZE - 1u);
    let x = sqrt(brdf_clamp(mu, 0.0, 1.0)) * n;
    let y = brdf_cbrt(brdf_clamp(alpha, 0.0, 1.0)) * n;
    let i = min(u32(x), BSDF_TABLE_SIZE - 2u);
    let j = min(u32(y), BSDF_TABLE_SIZE - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    var base = 0u;
    if height_correlated { base = BSDF_TABLE_SIZE * BSDF_TABLE_SIZE; }
    let r0 = base + j * BSDF_TABLE_SIZE + i;
    let r1 = r0 + BSDF_TABLE_SIZE;
    let top = turquin_table[r0] * (1.0 - fx) + turquin_table[r0 + 1u] * fx;
    let bottom = turquin_table[r1] * (1.0 - fx) + turquin_table[r1 + 1u] * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// `turquin::compensation`: 1 + F0·(1/E_ss − 1).
fn brdf_turquin_compensation(f0: vec3<f32>, mu_o: f32, alpha: f32, height_correlated: bool) -> vec3<f32> {
    var e = bsdf_e_ss(mu_o, alpha, height_correlated);
    if !(e > 1e-3) { e = 1e-3; }
    return vec3<f32>(1.0) + f0 * (1.0 / e - 1.0);
}

// ---- specular.rs (GgxSpecular) ----

fn brdf_height_correlated(m: BsdfParams) -> bool {
    return (m.flags & BSDF_FLAG_HEIGHT_CORRELATED) != 0u;
}

fn brdf_sampling(m: BsdfParams) -> u32 {
    return (m.flags >> BSDF_SAMPLING_SHIFT) & BSDF_SAMPLING_MASK;
}

// `GgxSpecular::compensation`: the Turquin factor, 1 when compensation is off.
fn brdf_specular_compensation(m: BsdfParams, mu_o: f32) -> vec3<f32> {
    if (m.flags & BSDF_FLAG_COMPENSATION) != 0u {
        return brdf_turquin_compensation(m.f0, mu_o, m.alpha, brdf_height_correlated(m));
    }
    return vec3<f32>(1.0);
}

// `half_vector`: (ωm, ωo·ωm = |ωo + ωi|/2) in xyz/w; w = 0 when the sum vanishes (`None`).
fn brdf_half_vector(wo: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    let h = wo + wi;
    let len = sqrt(brdf_dot(h, h));
    if !(len > 0.0) { return vec4<f32>(0.0); }
    return vec4<f32>(h / len, 0.5 * len);
}

// `GgxSpecular::eval`.
fn brdf_specular_eval(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if !(brdf_above(wo) && brdf_above(wi)) { return vec3<f32>(0.0); }
    let hv = brdf_half_vector(wo, wi);
    if !(hv.w > 0.0) { return vec3<f32>(0.0); }
    let f = brdf_schlick(m.f0, vec3<f32>(m.f90), hv.w);
    let d = brdf_ggx_eval_cos(m.alpha, wo, wi, hv.xyz, brdf_height_correlated(m));
    return f * d * brdf_specular_compensation(m, wo.z);
}

// `GgxSpecular::sample` (uc unused, as in the Rust).
fn brdf_specular_sample(m: BsdfParams, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if !brdf_above(wo) { return brdf_no_sample(); }
    let method = brdf_sampling(m);
    let wm = brdf_ggx_sample_wm(m.alpha, wo, u, method);
    let cos_om = brdf_dot(wo, wm);
    if !(cos_om > 0.0) { return brdf_no_sample(); } // NDF sampled a back-facing microfacet
    let wi = brdf_reflect(wo, wm);
    if !brdf_above(wi) { return brdf_no_sample(); } // reflected below the horizon
    let pdf = brdf_ggx_pdf_reflected(m.alpha, wo, wm, cos_om, method);
    if !brdf_positive_finite(pdf) { return brdf_no_sample(); }
    let g2 = brdf_ggx_g2(m.alpha, wo, wi, brdf_height_correlated(m));
    var throughput: f32;
    if method == BSDF_SAMPLING_NDF {
        throughput = g2 * cos_om / (wo.z * wm.z);
    } else {
        throughput = g2 / brdf_ggx_g1(m.alpha, wo);
    }
    let weight = brdf_schlick(m.f0, vec3<f32>(m.f90), cos_om) * throughput * brdf_specular_compensation(m, wo.z);
    return BsdfSample(wi, pdf, weight, BSDF_LOBE_SPECULAR);
}

// `GgxSpecular::pdf`.
fn brdf_specular_pdf(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) { return 0.0; }
    let hv = brdf_half_vector(wo, wi);
    if !(hv.w > 0.0) { return 0.0; }
    return brdf_ggx_pdf_reflected(m.alpha, wo, hv.xyz, hv.w, brdf_sampling(m));
}

// ---- lambert.rs ----

// `Lambert::sample`: cosine hemisphere, weight = albedo (uc unused).
fn brdf_lambert_sample(m: BsdfParams, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if !brdf_above(wo) { return brdf_no_sample(); }
    let wi = warp_cosine_hemisphere(u);
    let pdf = cosine_hemisphere_pdf(wi.z);
    if !(pdf > 0.0) { return brdf_no_sample(); }
    return BsdfSample(wi, pdf, m.diffuse, BSDF_LOBE_DIFFUSE);
}

// `Lambert::pdf`.
fn brdf_lambert_pdf(wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !brdf_above(wo) { return 0.0; }
    return cosine_hemisphere_pdf(wi.z);
}

// ---- material.rs (MetallicRoughness) ----

// `MetallicRoughness::new`: the record from glTF metallic-roughness + KHR_materials_specular
// parameters (after texture lookups) and the SpecularOptions flags; out-of-range and NaN inputs
// are clamped / replaced as the Rust does.
fn bsdf_params(base_color: vec3<f32>, metallic: f32, roughness: f32, specular_factor: f32,
               specular_color: vec3<f32>, flags: u32) -> BsdfParams {
    let base = brdf_clamp_rgb(base_color, 1.0);
    let metal = brdf_sanitize(metallic, 0.0, 1.0, 1.0);
    let rough = brdf_sanitize(roughness, 0.0, 1.0, 1.0);
    let sf = brdf_sanitize(specular_factor, 0.0, 1.0, 1.0);
    let sc = brdf_clamp_rgb(specular_color, BRDF_F32_MAX);
    // glam's min: per channel `if a < b { a } else { b }`.
    let f0d = select(vec3<f32>(1.0), 0.04 * sc, 0.04 * sc < vec3<f32>(1.0));
    // glam's lerp: a·(1 − s) + b·s.
    let f0 = brdf_clamp_rgb((f0d * sf) * (1.0 - metal) + base * metal, 1.0);
    let f90 = sf + (1.0 - sf) * metal;
    // Ggx::new: α = roughness² clamped to [ALPHA_MIN, 1].
    let alpha = brdf_sanitize(rough * rough, BSDF_ALPHA_MIN, 1.0, 1.0);
    let diffuse = brdf_clamp_rgb(base * (1.0 - metal), 1.0);
    return BsdfParams(diffuse, alpha, f0, f90, f0d, sf, flags);
}

// `MetallicRoughness::diffuse_scale`: 1 − sF·max(fr(cos θd)).
fn brdf_diffuse_scale(m: BsdfParams, cos_theta_d: f32) -> f32 {
    let fr = brdf_schlick(m.f0_dielectric, vec3<f32>(1.0), cos_theta_d);
    return 1.0 - m.specular_factor * brdf_max_element(fr);
}

// `MetallicRoughness::specular_probability`: Fresnel-weighted albedo estimates at μo, clamped
// to [0.05, 0.95] when both lobes are present.
fn bsdf_specular_probability(m: BsdfParams, wo: vec3<f32>) -> f32 {
    let mu = brdf_clamp(wo.z, 0.0, 1.0);
    var spec = brdf_luminance(brdf_schlick(m.f0, vec3<f32>(m.f90), mu));
    if (m.flags & BSDF_FLAG_COMPENSATION) == 0u {
        spec *= bsdf_e_ss(mu, m.alpha, brdf_height_correlated(m));
    }
    let diff = brdf_luminance(m.diffuse) * brdf_diffuse_scale(m, mu);
    // Only a diffuse lobe that is zero everywhere may go unsampled (see the Rust).
    if !(diff > 0.0) { return select(0.95, 1.0, all(m.diffuse == vec3<f32>(0.0))); }
    if !(spec > 0.0) { return 0.0; }
    return brdf_clamp(spec / (spec + diff), 0.05, 0.95);
}

// `MetallicRoughness::eval_diffuse`.
fn brdf_eval_diffuse(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if all(m.diffuse == vec3<f32>(0.0)) || !(brdf_above(wo) && brdf_above(wi)) {
        return vec3<f32>(0.0);
    }
    let wm = brdf_normalize_or(wo + wi, vec3<f32>(0.0, 0.0, 1.0));
    return m.diffuse * (BRDF_FRAC_1_PI * wi.z * brdf_diffuse_scale(m, brdf_dot(wo, wm)));
}

// `MetallicRoughness::eval`: (diffuse + specular)·cos θi.
fn bsdf_eval(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    return brdf_eval_diffuse(m, wo, wi) + brdf_specular_eval(m, wo, wi);
}

// `MetallicRoughness::pdf`: p·pdf_specular + (1 − p)·pdf_diffuse (the specular pdf alone when
// p = 1).
fn bsdf_pdf(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let p = bsdf_specular_probability(m, wo);
    if p >= 1.0 {
        return brdf_specular_pdf(m, wo, wi);
    }
    return p * brdf_specular_pdf(m, wo, wi) + (1.0 - p) * brdf_lambert_pdf(wo, wi);
}

// `MetallicRoughness::sample(wo, uc, u)`: u_lobe (= uc) picks the specular lobe when below p,
// u the direction; the pdf is the mixture and the weight eval/pdf.
fn bsdf_sample(m: BsdfParams, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if !brdf_above(wo) { return brdf_no_sample(); }
    let p = bsdf_specular_probability(m, wo);
    if p >= 1.0 {
        return brdf_specular_sample(m, wo, u);
    }
    var s: BsdfSample;
    if u_lobe < p {
        s = brdf_specular_sample(m, wo, u);
    } else {
        s = brdf_lambert_sample(m, wo, u);
    }
    if s.lobe == BSDF_LOBE_NONE { return brdf_no_sample(); }
    let wi = s.wi;
    let pdf = p * brdf_specular_pdf(m, wo, wi) + (1.0 - p) * brdf_lambert_pdf(wo, wi);
    if !brdf_positive_finite(pdf) { return brdf_no_sample(); }
    return BsdfSample(wi, pdf, bsdf_eval(m, wo, wi) / pdf, s.lobe);
}
