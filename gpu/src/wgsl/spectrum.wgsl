// furnace-gpu: twin of furnace-brdf's `spectrum` module (KHR_materials_dispersion): the
// wavelength a path is traced at past its first dispersive solid, and the index there.
// Composed only for scenes with a dispersive material, after the tables of
// `furnace_brdf::spectrum::wgsl` (SPECTRUM_CDF, SPECTRUM_WEIGHT: the same f32 values).

// `spectrum::WavelengthSample`.
struct WavelengthSample {
    lambda: f32,
    weight: vec3<f32>,
}

// `spectrum::sample_wavelength`: a bin by the CDF (binary search), uniform within it.
fn spectrum_sample(u_in: f32) -> WavelengthSample {
    var u = 0.0;
    if u_in == u_in && abs(u_in) <= 3.4e38 {
        u = clamp(u_in, 0.0, DIELECTRIC_ONE_BELOW);
    }
    var lo = 0u;
    var hi = SPECTRUM_BINS;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if SPECTRUM_CDF[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    var t = clamp((u - SPECTRUM_CDF[lo]) / (SPECTRUM_CDF[lo + 1u] - SPECTRUM_CDF[lo]), 0.0, DIELECTRIC_ONE_BELOW);
    if !(t == t) {
        t = 0.0;
    }
    return WavelengthSample(SPECTRUM_LAMBDA_MIN + SPECTRUM_BIN_WIDTH * (f32(lo) + t), SPECTRUM_WEIGHT[lo]);
}

// `spectrum::dispersed_ior`: Cauchy's two terms from the Abbe number (dispersion = 20/V_d).
fn spectrum_dispersed_ior(ior: f32, dispersion: f32, lambda: f32) -> f32 {
    if !(dispersion > 0.0) {
        return ior;
    }
    let n = ior + (ior - 1.0) * (dispersion / 20.0) * (523655.0 / (lambda * lambda) - 1.5168);
    if !(n == n) {
        return ior;
    }
    return max(n, 1.0);
}
