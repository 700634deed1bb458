// furnace-gpu: film accumulation in f64 (adapters with SHADER_F64). Twin of furnace-cpu's Film.
//
// Requires the composing shader to declare (see furnace_gpu::film::bindings):
//   film_sum:   array<vec4<f64>>  per pixel: sum of accepted samples (rgb), and in w the sum of
//               their squared luminances (for the viewer's noise estimate; not read back)
//   film_count: array<vec2<u32>>  per pixel: (accepted, rejected)
// A pixel must be owned by one invocation per dispatch (no atomics): samples are added in the
// order they are computed, as the CPU adds them.

// True when every channel is finite (exponent bits not all ones). Bit test, not `x != x`:
// a shader compiler may assume no NaNs and fold comparisons.
fn film_is_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// FILM_LUMINANCE (Rec. 709) is generated before this module from furnace_sampling::LUMINANCE.

// Adds one sample to `pixel`; a non-finite sample is rejected: not added, counted apart.
fn film_add(pixel: u32, value: vec3<f32>) {
    if film_is_finite(value) {
        let l = f64(dot(value, FILM_LUMINANCE));
        film_sum[pixel] = film_sum[pixel] + vec4<f64>(vec3<f64>(value), l * l);
        film_count[pixel].x = film_count[pixel].x + 1u;
    } else {
        film_count[pixel].y = film_count[pixel].y + 1u;
    }
}
