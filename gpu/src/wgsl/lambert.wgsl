// furnace-gpu: the Lambertian lobe, the twin of `furnace-brdf`'s src/lambert.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after specular.wgsl.

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
