// furnace-gpu: the mean of an f64 film's pixel for present.wgsl and noise.wgsl
// (`film_sum: array<vec4<f64>>`, `film_count: array<vec2<u32>>`), as the host's
// `Film::to_rgb_f32`: f32(sum / count), 0 without samples.
fn film_mean(pixel: u32) -> vec3<f32> {
    let n = film_count[pixel].x;
    if n == 0u {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(film_sum[pixel].xyz / f64(n));
}
