// furnace-gpu: film accumulation in f32 per pass, folded into f64 sums on the host (adapters
// without SHADER_F64). See furnace_gpu::film::GpuFilm::fold.
//
// Plain f32 additions only, on purpose: compensated (Kahan/Neumaier) f32 summation is not safe
// here — a GPU compiler may simplify its error term away (NVIDIA's Vulkan compiler does, even
// through opaque bit operations), leaving a plain f32 sum that drifts. Instead the GPU sums at most one
// pass of samples per pixel in f32 (a bounded, small error relative to that pass), and the host
// adds each pass into f64 and clears the GPU sums.
//
// Requires the composing shader to declare (see furnace_gpu::film::FilmPrecision::bindings):
//   film_sum:   array<vec4<f32>>  per pixel: this pass's sum of accepted samples (rgb), and in w
//               the sum of their squared luminances (adaptive sampling's noise, folded on the host)
//   film_count: array<vec2<u32>>  per pixel: (accepted, rejected) this pass
// A pixel must be owned by one invocation per dispatch (no atomics).

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
        let l = dot(value, FILM_LUMINANCE);
        film_sum[pixel] = film_sum[pixel] + vec4<f32>(value, l * l);
        film_count[pixel].x = film_count[pixel].x + 1u;
    } else {
        film_count[pixel].y = film_count[pixel].y + 1u;
    }
}
