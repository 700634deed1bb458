// furnace-gpu: Turquin 2019 energy compensation: the E_ss table lookup, the twin of `furnace-brdf`'s src/turquin.rs.
// Part of the brdf module (`furnace_gpu::wgsl::BRDF`), composed after ggx.wgsl.

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
