// furnace-gpu: a film on screen. A full-window triangle whose fragments look up the film pixel
// under them (nearest, `PresentParams.origin` / `step`) and write its mean, exposed, tone-mapped
// and sRGB-encoded by tonemap.wgsl (the maths of furnace-post), straight from the film's buffers.
//
// Composed after tonemap.wgsl, the generated `PresentParams` struct and the bindings of
// furnace_gpu::present (params, and the film: `film_sum` + `film_count` for an f64 film,
// `film_means` for an f32 one), with `film_mean(pixel)` from present_f64.wgsl or present_f32.wgsl.

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // (0,0), (2,0), (0,2) in units of the window: one triangle covering it.
    let x = f32((i << 1u) & 2u);
    let y = f32(i & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    // `position.xy` is the fragment's centre in window pixels (x + 0.5, y + 0.5).
    let f = (position.xy - vec2<f32>(present.origin_x, present.origin_y)) * present.step;
    let size = vec2<f32>(f32(present.film_width), f32(present.film_height));
    if f.x < 0.0 || f.y < 0.0 || f.x >= size.x || f.y >= size.y {
        return present.background;
    }
    let pixel = u32(f.y) * present.film_width + u32(f.x);
    let mean = film_mean(pixel);
    if present.target_srgb != 0u {
        // The target encodes sRGB itself: hand it the tone-mapped linear value.
        return vec4<f32>(post_tonemap(mean * present.exposure_scale, present.tonemap), 1.0);
    }
    return vec4<f32>(post_display(mean, present.exposure_scale, present.tonemap), 1.0);
}
