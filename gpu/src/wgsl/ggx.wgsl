// furnace-gpu: the GGX distribution (D, Smith G1/G2, NDF / VNDF / spherical-cap sampling; α
// already clamped), the twin of `furnace-brdf`'s src/ggx.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after fresnel.wgsl.
//
// A distribution is a `GgxAlpha`: α, or with ANISOTROPY (αx, αy). Each function keeps the
// Rust's isotropic arithmetic as is and, like the Rust, branches to the stretched forms only
// where αx ≠ αy, so a kernel without anisotropy composes none of them.

// #if ANISOTROPY
alias GgxAlpha = vec2<f32>;

// The isotropic distribution of α.
fn brdf_ggx_isotropic(alpha: f32) -> GgxAlpha {
    return vec2<f32>(alpha);
}

// α along x (all of it when isotropic).
fn brdf_ggx_alpha_x(alpha: GgxAlpha) -> f32 {
    return alpha.x;
}

// The stretch (αx, αy) of the samplers.
fn brdf_ggx_stretch(alpha: GgxAlpha) -> vec2<f32> {
    return alpha;
}

// `Ggx::is_anisotropic`.
fn brdf_ggx_is_anisotropic(alpha: GgxAlpha) -> bool {
    return alpha.x != alpha.y;
}

// `Ggx::alpha_effective`: α, or √((αx² + αy²)/2) when anisotropic.
fn brdf_ggx_alpha_effective(alpha: GgxAlpha) -> f32 {
    if !brdf_ggx_is_anisotropic(alpha) { return alpha.x; }
    return sqrt(0.5 * (alpha.x * alpha.x + alpha.y * alpha.y));
}
// #else
alias GgxAlpha = f32;

fn brdf_ggx_isotropic(alpha: f32) -> GgxAlpha {
    return alpha;
}

fn brdf_ggx_alpha_x(alpha: GgxAlpha) -> f32 {
    return alpha;
}

fn brdf_ggx_stretch(alpha: GgxAlpha) -> vec2<f32> {
    return vec2<f32>(alpha);
}

fn brdf_ggx_alpha_effective(alpha: GgxAlpha) -> f32 {
    return alpha;
}
// #endif

// `Ggx::a`: √(z² + α²(x² + y²)).
fn brdf_ggx_a(alpha: GgxAlpha, w: vec3<f32>) -> f32 {
    // #if ANISOTROPY
    if brdf_ggx_is_anisotropic(alpha) {
        let ax = alpha.x * w.x;
        let ay = alpha.y * w.y;
        return sqrt(w.z * w.z + ax * ax + ay * ay);
    }
    // #endif
    let a = brdf_ggx_alpha_x(alpha);
    let a2 = a * a;
    return sqrt(w.z * w.z + a2 * (w.x * w.x + w.y * w.y));
}

// `Ggx::d`: 1/(π α² ((x² + y²)/α² + z²)²), anisotropic 1/(π αx αy (x²/αx² + y²/αy² + z²)²);
// 0 below the horizon.
fn brdf_ggx_d(alpha: GgxAlpha, wm: vec3<f32>) -> f32 {
    if !(wm.z > 0.0) { return 0.0; }
    // #if ANISOTROPY
    if brdf_ggx_is_anisotropic(alpha) {
        let x = wm.x / alpha.x;
        let y = wm.y / alpha.y;
        let ta = x * x + y * y + wm.z * wm.z;
        return 1.0 / (BRDF_PI * alpha.x * alpha.y * ta * ta);
    }
    // #endif
    let a = brdf_ggx_alpha_x(alpha);
    let a2 = a * a;
    let t = (wm.x * wm.x + wm.y * wm.y) / a2 + wm.z * wm.z;
    return 1.0 / (BRDF_PI * a2 * t * t);
}

// `Ggx::g1`: 2|z|/(|z| + a), 0 at the horizon.
fn brdf_ggx_g1(alpha: GgxAlpha, w: vec3<f32>) -> f32 {
    let z = abs(w.z);
    let den = z + brdf_ggx_a(alpha, w);
    if den > 0.0 { return 2.0 * z / den; }
    return 0.0;
}

// `Ggx::g2`: separable G1·G1 or height-correlated 2 zo zi/(ao zi + ai zo).
fn brdf_ggx_g2(alpha: GgxAlpha, wo: vec3<f32>, wi: vec3<f32>, height_correlated: bool) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) { return 0.0; }
    if height_correlated {
        let ao = brdf_ggx_a(alpha, wo);
        let ai = brdf_ggx_a(alpha, wi);
        return 2.0 * wo.z * wi.z / (ao * wi.z + ai * wo.z);
    }
    return brdf_ggx_g1(alpha, wo) * brdf_ggx_g1(alpha, wi);
}

// `Ggx::eval_cos`: D·G2/(4 zo) without the 1/zo singularity.
fn brdf_ggx_eval_cos(alpha: GgxAlpha, wo: vec3<f32>, wi: vec3<f32>, wm: vec3<f32>, height_correlated: bool) -> f32 {
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

// `Ggx::sample_ndf`: tan²θm = α²u₀/(1 − u₀), φ = 2πu₁; anisotropic, the α = 1 normal so drawn
// stretched by (αx, αy).
fn brdf_ggx_sample_ndf(alpha: GgxAlpha, u: vec2<f32>) -> vec3<f32> {
    let a = brdf_ggx_alpha_x(alpha);
    var a2 = a * a;
    // #if ANISOTROPY
    if brdf_ggx_is_anisotropic(alpha) { a2 = 1.0; }
    // #endif
    let tan2 = a2 * u.x / (1.0 - u.x);
    let cos_theta = 1.0 / sqrt(1.0 + tan2);
    let sin_theta = sqrt(tan2) * cos_theta;
    let phi = BRDF_TAU * u.y;
    let s = sin(phi);
    let c = cos(phi);
    let wm = vec3<f32>(sin_theta * c, sin_theta * s, cos_theta);
    // #if ANISOTROPY
    if brdf_ggx_is_anisotropic(alpha) {
        return brdf_normalize_or(vec3<f32>(alpha.x * wm.x, alpha.y * wm.y, wm.z), vec3<f32>(0.0, 0.0, 1.0));
    }
    // #endif
    return wm;
}

// `Ggx::sample_vndf_heitz`: Heitz 2018, listing 1.
fn brdf_ggx_sample_vndf_heitz(alpha: GgxAlpha, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let st = brdf_ggx_stretch(alpha);
    let vh = brdf_normalize_or(vec3<f32>(st.x * wo.x, st.y * wo.y, wo.z), vec3<f32>(0.0, 0.0, 1.0));
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
    return brdf_normalize_or(vec3<f32>(st.x * nh.x, st.y * nh.y, brdf_max0(nh.z)), vec3<f32>(0.0, 0.0, 1.0));
}

// `Ggx::sample_vndf_caps`: Dupuy & Benyoub 2023, listing 3.
fn brdf_ggx_sample_vndf_caps(alpha: GgxAlpha, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let st = brdf_ggx_stretch(alpha);
    let wi_std = brdf_normalize_or(vec3<f32>(st.x * wo.x, st.y * wo.y, wo.z), vec3<f32>(0.0, 0.0, 1.0));
    let phi = BRDF_TAU * u.x;
    let s = sin(phi);
    let c = cos(phi);
    // Rust: (1 − u.y).mul_add(1 + z, −z).
    let z = fma(1.0 - u.y, 1.0 + wi_std.z, -wi_std.z);
    let sin_theta = sqrt(brdf_clamp(1.0 - z * z, 0.0, 1.0));
    let wm_std = vec3<f32>(sin_theta * c, sin_theta * s, z) + wi_std;
    return brdf_normalize_or(vec3<f32>(st.x * wm_std.x, st.y * wm_std.y, wm_std.z), vec3<f32>(0.0, 0.0, 1.0));
}

// `Ggx::sample_wm`.
fn brdf_ggx_sample_wm(alpha: GgxAlpha, wo: vec3<f32>, u: vec2<f32>, method: u32) -> vec3<f32> {
    if method == BSDF_SAMPLING_NDF { return brdf_ggx_sample_ndf(alpha, u); }
    if method == BSDF_SAMPLING_VNDF { return brdf_ggx_sample_vndf_heitz(alpha, wo, u); }
    return brdf_ggx_sample_vndf_caps(alpha, wo, u);
}

// `Ggx::pdf_reflected`: NDF D·cos θm/(4 cos_om); VNDF D/(2(cos θo + a(ωo))).
fn brdf_ggx_pdf_reflected(alpha: GgxAlpha, wo: vec3<f32>, wm: vec3<f32>, cos_om: f32, method: u32) -> f32 {
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
