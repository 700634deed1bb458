// furnace-gpu: film accumulation in compensated f32 (adapters without SHADER_F64).
//
// Neumaier's variant of Kahan summation: each channel keeps a sum s and a compensation c that
// collects the low-order bits every addition loses; the value is s + c (formed in f64 on the
// CPU when read back). The error of n additions stays ~2·2⁻²⁴·|sum| instead of growing with n.
// No multiplications are involved, so FMA contraction cannot disturb it.
//
// Requires the composing shader to declare (see furnace_gpu::film::bindings):
//   film_sum:   array<vec4<f32>>  2 per pixel: [2p] the sums s (rgb), [2p + 1] the compensations c
//   film_count: array<vec2<u32>>  per pixel: (accepted, rejected)
// A pixel must be owned by one invocation per dispatch (no atomics).

fn film_is_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

fn film_add(pixel: u32, value: vec3<f32>) {
    if film_is_finite(value) {
        let s = film_sum[2u * pixel].xyz;
        let c = film_sum[2u * pixel + 1u].xyz;
        let t = s + value;
        // Neumaier: the rounding error of s + value, from whichever operand is larger.
        let big_s = abs(s) >= abs(value);
        let err = select((value - t) + s, (s - t) + value, big_s);
        film_sum[2u * pixel] = vec4<f32>(t, 0.0);
        film_sum[2u * pixel + 1u] = vec4<f32>(c + err, 0.0);
        film_count[pixel].x = film_count[pixel].x + 1u;
    } else {
        film_count[pixel].y = film_count[pixel].y + 1u;
    }
}
