// furnace-gpu: the data of the viewer's noise estimate, reduced on the GPU from an f64 film
// whose sums carry the squared luminances in w (film_f64.wgsl).
//
// Per pixel with n >= 2 samples: luminance mean m = S1 / n, sample variance
// v = (S2 - S1² / n) / (n - 1), squared standard error of the mean v / n. Each workgroup writes
// (Σ v / n over pixels with n >= 2, Σ m over pixels with n >= 1, their two counts) to
// `noise_partial[workgroup]`; the host adds the workgroups in f64.
//
// Composed after the generated `NoiseParams` struct and bindings (params, film_sum, film_count,
// noise_partial).

const NOISE_GROUP: u32 = 256u;
// NOISE_LUMINANCE, the f32 weights of film_f64.wgsl's squares (S1 and S2 weigh alike), is
// generated before this module from furnace_sampling::LUMINANCE.

var<workgroup> noise_acc: array<vec4<f32>, NOISE_GROUP>;

@compute @workgroup_size(256)
fn noise_main(
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let stride = groups.x * NOISE_GROUP;
    var acc = vec4<f32>(0.0);
    for (var p = group.x * NOISE_GROUP + local; p < noise.pixels; p += stride) {
        let n = film_count[p].x;
        if n == 0u {
            continue;
        }
        let s = film_sum[p];
        let nf = f64(n);
        let s1 = dot(s.xyz, vec3<f64>(NOISE_LUMINANCE));
        acc.y += f32(s1 / nf);
        acc.w += 1.0;
        if n >= 2u {
            let v = max(s.w - s1 * s1 / nf, f64(0.0)) / (nf - f64(1.0));
            acc.x += f32(v / nf);
            acc.z += 1.0;
        }
    }
    noise_acc[local] = acc;
    workgroupBarrier();
    for (var half = NOISE_GROUP / 2u; half > 0u; half /= 2u) {
        if local < half {
            noise_acc[local] += noise_acc[local + half];
        }
        workgroupBarrier();
    }
    if local == 0u {
        noise_partial[group.x] = noise_acc[0];
    }
}
