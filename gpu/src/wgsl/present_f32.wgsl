// furnace-gpu: the mean of a pixel of an f32-pass film for present.wgsl: the means of the passes
// folded on the host, uploaded after each fold (`film_means: array<vec4<f32>>`, count in w).
fn film_mean(pixel: u32) -> vec3<f32> {
    return film_means[pixel].xyz;
}
