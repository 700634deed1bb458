// furnace-gpu: the glTF metallic-roughness material (`MetallicRoughness`: Lambert + one merged
// GGX lobe), the twin of `furnace-brdf`'s src/metallic_roughness.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after lambert.wgsl.

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
    return BsdfParams(diffuse, alpha, f0, f90, f0d, sf, flags, 0.0, 0.0, 0.0, vec3<f32>(0.0), 0.0, vec3<f32>(0.0),
                      alpha);
}

// #if ANISOTROPY
// `MetallicRoughness::with_anisotropy`: the specular lobe of strength `strength` (clamped to
// [0, 1], NaN → 0: isotropic) stretched to αx = mix(α, 1, s²) along the frame's x axis.
fn bsdf_with_anisotropy(params: BsdfParams, strength: f32) -> BsdfParams {
    var m = params;
    let s = brdf_sanitize(strength, 0.0, 1.0, 0.0);
    if s > 0.0 {
        let s2 = s * s;
        m.alpha = brdf_sanitize(params.alpha * (1.0 - s2) + s2, BSDF_ALPHA_MIN, 1.0, 1.0);
    }
    return m;
}
// #endif

// #if IRIDESCENCE
// `MetallicRoughness::new_iridescent`: the record under a film of weight `factor`, index `ior`
// and thickness `thickness` nm, clamped as the Rust does (`base_color`, `metallic` as given to
// `bsdf_params`).
fn bsdf_with_film(params: BsdfParams, base_color: vec3<f32>, metallic: f32, factor: f32, ior: f32,
                  thickness: f32) -> BsdfParams {
    var m = params;
    let i = brdf_sanitize(factor, 0.0, 1.0, 0.0);
    if i > 0.0 {
        m.film_factor = i;
        m.film_ior = brdf_sanitize(ior, 0.01, 100.0, 1.3);
        m.film_thickness = brdf_sanitize(thickness, 0.0, 1.0e6, 0.0);
        m.film_f0_metal = brdf_clamp_rgb(base_color, 1.0);
        m.film_metallic = brdf_sanitize(metallic, 0.0, 1.0, 1.0);
        m.film_f0 = brdf_film_mix(m, brdf_schlick(m.f0, vec3<f32>(m.f90), 1.0), 1.0);
    }
    return m;
}
// #endif

// `MetallicRoughness::diffuse_scale`: 1 − sF·max(fr(cos θd)); under a film
// 1 − max((1 − i)·sF·fr + i·film(cos θd)).
fn brdf_diffuse_scale(m: BsdfParams, cos_theta_d: f32) -> f32 {
    let fr = brdf_schlick(m.f0_dielectric, vec3<f32>(1.0), cos_theta_d);
    // #if IRIDESCENCE
    if m.film_factor > 0.0 {
        let fw = (1.0 - m.film_factor) * (fr * m.specular_factor) + m.film_factor * brdf_film_dielectric(m, cos_theta_d);
        return 1.0 - brdf_max_element(fw);
    }
    // #endif
    return 1.0 - m.specular_factor * brdf_max_element(fr);
}

// `MetallicRoughness::albedo_estimates`' specular half at μo: lum(F(μo)), times E_ss where the
// lobe is not compensated (an anisotropic lobe's at `Ggx::alpha_effective`).
fn brdf_specular_estimate(m: BsdfParams, mu: f32) -> f32 {
    var spec = brdf_luminance(brdf_specular_fresnel(m, mu));
    if !brdf_specular_compensated(m) {
        spec *= bsdf_e_ss(mu, brdf_ggx_alpha_effective(brdf_specular_ggx(m)), brdf_height_correlated(m));
    }
    return spec;
}

// `MetallicRoughness::specular_probability`: Fresnel-weighted albedo estimates at μo, clamped
// to [0.05, 0.95] when both lobes are present.
fn bsdf_specular_probability(m: BsdfParams, wo: vec3<f32>) -> f32 {
    let mu = brdf_clamp(wo.z, 0.0, 1.0);
    let spec = brdf_specular_estimate(m, mu);
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
