// furnace-gpu: the GGX specular lobe (`GgxSpecular`), the twin of `furnace-brdf`'s src/specular.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after turquin.wgsl.

fn brdf_height_correlated(m: BsdfParams) -> bool {
    return (m.flags & BSDF_FLAG_HEIGHT_CORRELATED) != 0u;
}

fn brdf_sampling(m: BsdfParams) -> u32 {
    return (m.flags >> BSDF_SAMPLING_SHIFT) & BSDF_SAMPLING_MASK;
}

// The lobe's distribution (`GgxSpecular::ggx`): α, with ANISOTROPY (αx, αy).
fn brdf_specular_ggx(m: BsdfParams) -> GgxAlpha {
    // #if ANISOTROPY
    return vec2<f32>(m.alpha, m.alpha_y);
    // #else
    return m.alpha;
    // #endif
}

// Whether the lobe is Turquin-compensated: with the option, and not anisotropic (no isotropic
// table bounds an anisotropic lobe's loss).
fn brdf_specular_compensated(m: BsdfParams) -> bool {
    // #if ANISOTROPY
    if m.alpha != m.alpha_y { return false; }
    // #endif
    return (m.flags & BSDF_FLAG_COMPENSATION) != 0u;
}

// `GgxSpecular::fresnel`: Schlick's, with the thin film's mixed in (IRIDESCENCE).
fn brdf_specular_fresnel(m: BsdfParams, cos_om: f32) -> vec3<f32> {
    let f = brdf_schlick(m.f0, vec3<f32>(m.f90), cos_om);
    // #if IRIDESCENCE
    if m.film_factor > 0.0 { return brdf_film_mix(m, f, cos_om); }
    // #endif
    return f;
}

// `GgxSpecular::compensation`: the Turquin factor, 1 when compensation is off or the lobe
// anisotropic.
fn brdf_specular_compensation(m: BsdfParams, mu_o: f32) -> vec3<f32> {
    if brdf_specular_compensated(m) {
        var f0 = m.f0;
        // #if IRIDESCENCE
        if m.film_factor > 0.0 { f0 = m.film_f0; }
        // #endif
        return brdf_turquin_compensation(f0, mu_o, m.alpha, brdf_height_correlated(m));
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
    let f = brdf_specular_fresnel(m, hv.w);
    let d = brdf_ggx_eval_cos(brdf_specular_ggx(m), wo, wi, hv.xyz, brdf_height_correlated(m));
    return f * d * brdf_specular_compensation(m, wo.z);
}

// `GgxSpecular::sample` (uc unused, as in the Rust).
fn brdf_specular_sample(m: BsdfParams, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if !brdf_above(wo) { return brdf_no_sample(); }
    let method = brdf_sampling(m);
    let ggx = brdf_specular_ggx(m);
    let wm = brdf_ggx_sample_wm(ggx, wo, u, method);
    let cos_om = brdf_dot(wo, wm);
    if !(cos_om > 0.0) { return brdf_no_sample(); } // NDF sampled a back-facing microfacet
    let wi = brdf_reflect(wo, wm);
    if !brdf_above(wi) { return brdf_no_sample(); } // reflected below the horizon
    let pdf = brdf_ggx_pdf_reflected(ggx, wo, wm, cos_om, method);
    if !brdf_positive_finite(pdf) { return brdf_no_sample(); }
    let g2 = brdf_ggx_g2(ggx, wo, wi, brdf_height_correlated(m));
    var throughput: f32;
    if method == BSDF_SAMPLING_NDF {
        throughput = g2 * cos_om / (wo.z * wm.z);
    } else {
        throughput = g2 / brdf_ggx_g1(ggx, wo);
    }
    let weight = brdf_specular_fresnel(m, cos_om) * throughput * brdf_specular_compensation(m, wo.z);
    return BsdfSample(wi, pdf, weight, BSDF_LOBE_SPECULAR);
}

// `GgxSpecular::pdf`.
fn brdf_specular_pdf(m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) { return 0.0; }
    let hv = brdf_half_vector(wo, wi);
    if !(hv.w > 0.0) { return 0.0; }
    return brdf_ggx_pdf_reflected(brdf_specular_ggx(m), wo, hv.xyz, hv.w, brdf_sampling(m));
}
