// furnace-gpu: Schlick's Fresnel, the twin of `furnace-brdf`'s src/fresnel.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after brdf.wgsl.

// `schlick`: F0 + (F90 − F0)(1 − cos θd)^5, cos θd clamped to [0, 1].
fn brdf_schlick(f0: vec3<f32>, f90: vec3<f32>, cos_theta_d: f32) -> vec3<f32> {
    let m = brdf_clamp(1.0 - brdf_clamp(cos_theta_d, 0.0, 1.0), 0.0, 1.0);
    let m2 = m * m;
    return f0 + (f90 - f0) * (m2 * m2 * m);
}
