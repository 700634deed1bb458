// furnace-gpu: KHR_materials_iridescence's thin-film Fresnel, the twin of `furnace-brdf`'s
// src/iridescence.rs. Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after
// fresnel.wgsl, and only for scenes with an iridescent material (IRIDESCENCE): the film's fields
// of BsdfParams are read nowhere else.
// #if IRIDESCENCE

// `iridescence::sensitivity`: the CIE sensitivities' Fourier transform at `opd` nm, shifted.
fn brdf_film_sensitivity(opd: f32, shift: vec3<f32>) -> vec3<f32> {
    let phase = 2.0 * BRDF_PI * opd * 1.0e-9;
    let val = vec3<f32>(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = vec3<f32>(1.6810e+06, 1.7953e+06, 2.2084e+06);
    let v = vec3<f32>(4.3278e+09, 9.3046e+09, 6.6121e+09);
    let gauss = exp(-(phase * phase) * v);
    var xyz = val * sqrt(2.0 * BRDF_PI * v) * cos(pos * phase + shift) * gauss;
    xyz.x += 9.7470e-14 * sqrt(2.0 * BRDF_PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x)
        * exp(-4.5282e+09 * phase * phase);
    xyz /= 1.0685e-7;
    return vec3<f32>(
        dot(vec3<f32>(3.2404542, -1.5371385, -0.4985314), xyz),
        dot(vec3<f32>(-0.969266, 1.8760108, 0.041556), xyz),
        dot(vec3<f32>(0.0556434, -0.2040259, 1.0572252), xyz));
}

// `iridescence::fresnel`: the film's reflectance over a base of F0 `base_f0`, from air, in [0, 1].
fn brdf_film_fresnel(ior: f32, thickness: f32, base_f0: vec3<f32>, cos_theta1: f32) -> vec3<f32> {
    let c1 = min(abs(cos_theta1), 1.0);
    let sin2_sq = (1.0 / ior) * (1.0 / ior) * (1.0 - c1 * c1);
    let cos2_sq = 1.0 - sin2_sq;
    if !(cos2_sq >= 0.0) { return vec3<f32>(1.0); }
    let c2 = sqrt(cos2_sq);
    let r0 = ((ior - 1.0) / (ior + 1.0)) * ((ior - 1.0) / (ior + 1.0));
    let r12 = brdf_schlick(vec3<f32>(r0), vec3<f32>(1.0), c1).x;
    let t121 = 1.0 - r12;
    let phi12 = select(0.0, BRDF_PI, ior < 1.0);
    let phi21 = BRDF_PI - phi12;
    let s = sqrt(base_f0 + 1.0e-4);
    let m = brdf_clamp(1.0 - c2, 0.0, 1.0);
    let m2 = m * m;
    let m5 = m2 * m2 * m;
    let a = 1.0 + s;
    let b = ior * (1.0 - s);
    let r = (a - b) / (a + b);
    let r1 = r * r;
    let r23 = r1 + (1.0 - r1) * m5;
    // η3 < ηf: a < b below s = 1, η3 negative above.
    let below = select(s > vec3<f32>(1.0), a < b, s < vec3<f32>(1.0));
    let phi = phi21 + select(vec3<f32>(0.0), vec3<f32>(BRDF_PI), below);
    let opd = 2.0 * ior * thickness * c2;
    let r123 = clamp(r12 * r23, vec3<f32>(1.0e-5), vec3<f32>(0.9999));
    let sqrt_r123 = sqrt(r123);
    let rs = t121 * t121 * r23 / (1.0 - r123);
    var i = r12 + rs;
    var cm = rs - t121;
    for (var k = 1u; k <= 2u; k++) {
        cm *= sqrt_r123;
        let sm = 2.0 * brdf_film_sensitivity(f32(k) * opd, f32(k) * phi);
        i += cm * sm;
    }
    return clamp(i, vec3<f32>(0.0), vec3<f32>(1.0));
}

// `Iridescence::dielectric`: the film over the dielectric's F0 `sF·f0d`.
fn brdf_film_dielectric(m: BsdfParams, cos: f32) -> vec3<f32> {
    return brdf_film_fresnel(m.film_ior, m.film_thickness, m.f0_dielectric * m.specular_factor, cos);
}

// `Iridescence::mix`: (1 − i)·plain + i·mix(film over the dielectric, over the metal, metallic).
fn brdf_film_mix(m: BsdfParams, plain: vec3<f32>, cos: f32) -> vec3<f32> {
    var film = vec3<f32>(0.0);
    if m.film_metallic < 1.0 {
        film += (1.0 - m.film_metallic) * brdf_film_dielectric(m, cos);
    }
    if m.film_metallic > 0.0 {
        film += m.film_metallic * brdf_film_fresnel(m.film_ior, m.film_thickness, m.film_f0_metal, cos);
    }
    return (1.0 - m.film_factor) * plain + m.film_factor * film;
}
// #endif
