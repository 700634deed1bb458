// furnace-gpu: KHR_materials_diffuse_transmission's Lambertian transmission lobe, the twin of
// `furnace-brdf`'s src/diffuse_transmission.rs. Composed after the brdf module (it weighs the
// lobe by the opaque material's `brdf_diffuse_scale`) for scenes with diffuse transmission
// only (`DIFFUSE_TRANSMISSION`).

// ωo above and ωi below the surface, each more than BSDF_MIN_COS from it.
fn dt_across(wo: vec3<f32>, wi: vec3<f32>) -> bool {
    return brdf_above(wo) && brdf_above(vec3<f32>(wi.x, wi.y, -wi.z));
}

// `DiffuseTransmission::eval`: color/π·|cos θi|·(1 − sF·max(fr(ωo·h))), h the half vector of ωo
// and ωi mirrored above.
fn dt_eval(color: vec3<f32>, m: BsdfParams, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if !dt_across(wo, wi) {
        return vec3<f32>(0.0);
    }
    let wm = brdf_normalize_or(wo + vec3<f32>(wi.x, wi.y, -wi.z), vec3<f32>(0.0, 0.0, 1.0));
    return color * (BRDF_FRAC_1_PI * abs(wi.z) * brdf_diffuse_scale(m, brdf_dot(wo, wm)));
}

// `DiffuseTransmission::pdf`: |cos θi|/π below the surface.
fn dt_pdf(wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if dt_across(wo, wi) {
        return BRDF_FRAC_1_PI * -wi.z;
    }
    return 0.0;
}

// `DiffuseTransmission::sample_direction`: the cosine warp mirrored below (w = 0: none).
fn dt_sample_direction(wo: vec3<f32>, u: vec2<f32>) -> vec4<f32> {
    if !brdf_above(wo) {
        return vec4<f32>(0.0);
    }
    let w = warp_cosine_hemisphere(u);
    let wi = vec3<f32>(w.x, w.y, -w.z);
    return vec4<f32>(wi, select(0.0, 1.0, dt_across(wo, wi)));
}

// `DiffuseTransmission::albedo_estimate`: lum(color)·(1 − sF·max(fr(μo))).
fn dt_estimate(color: vec3<f32>, m: BsdfParams, wo: vec3<f32>) -> f32 {
    return brdf_luminance(color) * brdf_diffuse_scale(m, brdf_clamp(wo.z, 0.0, 1.0));
}
