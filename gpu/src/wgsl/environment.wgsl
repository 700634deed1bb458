// furnace-gpu: environment maps, twin of furnace-scene's environment.rs (the texel-centred
// lat-long lookup, the rotation about +Y, EnvironmentSampler) and of furnace-sampling's
// Distribution2D (CDF inversion).
//
// Requires a binding `environment: array<f32>` of the map's texels (RGB, row-major, row 0 at the
// top) and, only when it is light-sampled (SAMPLES_ENVIRONMENT), `environment_cdf: array<f32>`
// of its conditional CDFs (W per row, the end of each cell) then its marginal CDF (H), the same
// f32 values the CPU samples with (furnace_gpu::integrator::environment_words).

// An environment as the integrator places it: the map's size, its intensity and the cosine and
// sine of its rotation (furnace_scene::Environment::rotation_cos_sin).
struct EnvMap {
    width: u32,
    height: u32,
    intensity: f32,
    cos_r: f32,
    sin_r: f32,
}

const ENV_FRAC_1_PI: f32 = 0.31830988618379067;
const ENV_PI: f32 = 3.14159265358979323846;

// furnace_scene::direction_to_uv: u = atan2(x, −z)/2π in [0, 1), v = acos(y)/π.
fn env_direction_to_uv(d: vec3<f32>) -> vec2<f32> {
    var u = atan2(d.x, -d.z) * (0.5 * ENV_FRAC_1_PI);
    u -= floor(u);
    let v = acos(clamp(d.y, -1.0, 1.0)) * ENV_FRAC_1_PI;
    return vec2<f32>(u, v);
}

// furnace_scene::uv_to_direction: (sin φ sin θ, cos θ, −cos φ sin θ), φ = 2πu, θ = πv.
fn env_uv_to_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = 2.0 * ENV_PI * uv.x;
    let theta = ENV_PI * uv.y;
    let st = sin(theta);
    return vec3<f32>(sin(phi) * st, cos(theta), -cos(phi) * st);
}

// Environment::to_map: world direction → the map's frame (R⁻¹ d).
fn env_to_map(env: EnvMap, d: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(env.cos_r * d.x - env.sin_r * d.z, d.y, env.sin_r * d.x + env.cos_r * d.z);
}

// Environment::to_world: the map's frame → world direction (R m).
fn env_to_world(env: EnvMap, m: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(env.cos_r * m.x + env.sin_r * m.z, m.y, -env.sin_r * m.x + env.cos_r * m.z);
}

// EnvironmentMap::texel: column i wrapping, row j clamped.
fn env_texel(env: EnvMap, i: i32, j: i32) -> vec3<f32> {
    let w = i32(env.width);
    let ii = ((i % w) + w) % w;
    let jj = clamp(j, 0, i32(env.height) - 1);
    let k = 3u * (u32(jj) * env.width + u32(ii));
    return vec3<f32>(environment[k], environment[k + 1u], environment[k + 2u]);
}

// EnvironmentMap::lookup_uv: the bilinear, texel-centred lookup.
fn env_lookup_uv(env: EnvMap, uv: vec2<f32>) -> vec3<f32> {
    let x = uv.x * f32(env.width) - 0.5;
    let y = uv.y * f32(env.height) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i0 = i32(x0);
    let j0 = i32(y0);
    let top = (1.0 - fx) * env_texel(env, i0, j0) + fx * env_texel(env, i0 + 1, j0);
    let bottom = (1.0 - fx) * env_texel(env, i0, j0 + 1) + fx * env_texel(env, i0 + 1, j0 + 1);
    return (1.0 - fy) * top + fy * bottom;
}

// Environment::radiance: what a ray leaving the scene along world direction d sees.
fn env_radiance(env: EnvMap, d: vec3<f32>) -> vec3<f32> {
    return env.intensity * env_lookup_uv(env, env_direction_to_uv(env_to_map(env, d)));
}

// #if SAMPLES_ENVIRONMENT
// 2π², the Jacobian's factor (furnace-scene's TWO_PI_SQUARED, the same f32).
const ENV_TWO_PI_SQUARED: f32 = 19.739208802178716;
// The largest f32 below 1.
const ENV_ONE_MINUS_EPSILON: f32 = 0.99999994;

// Distribution2D's `find`: the first of the n CDF values from word `start` above u (n − 1 at
// most), by binary search.
fn env_find(start: u32, n: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = n;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if environment_cdf[start + mid] <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return min(lo, n - 1u);
}

// The CDF value at the start of cell k of the CDF from word `start`.
fn env_cdf_start(start: u32, k: u32) -> f32 {
    if k == 0u {
        return 0.0;
    }
    return environment_cdf[start + k - 1u];
}

// furnace_scene::EnvironmentSample; pdf 0: no sample (a pole).
struct EnvSample {
    direction: vec3<f32>,
    pdf: f32,
    radiance: vec3<f32>,
}

// EnvironmentSampler::sample (Distribution2D::sample, then the sphere; the pdf is the sampled
// cell's density over the Jacobian).
fn env_sample(env: EnvMap, u: vec2<f32>) -> EnvSample {
    let w = env.width;
    let h = env.height;
    // The conditional CDFs start at word 0, the marginal CDF after them.
    let marginal = w * h;
    let j = env_find(marginal, h, u.y);
    let m0 = env_cdf_start(marginal, j);
    let m1 = environment_cdf[marginal + j];
    let dv = clamp((u.y - m0) / (m1 - m0), 0.0, ENV_ONE_MINUS_EPSILON);
    let row = j * w;
    let i = env_find(row, w, u.x);
    let c0 = env_cdf_start(row, i);
    let c1 = environment_cdf[row + i];
    let du = clamp((u.x - c0) / (c1 - c0), 0.0, ENV_ONE_MINUS_EPSILON);
    let uv = vec2<f32>((f32(i) + du) / f32(w), (f32(j) + dv) / f32(h));
    let pdf_uv = (m1 - m0) * (c1 - c0) * (f32(w) * f32(h));
    let m = env_uv_to_direction(uv);
    let sin_theta = sqrt(m.x * m.x + m.z * m.z);
    if !(sin_theta > 0.0 && pdf_uv > 0.0) {
        return EnvSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0));
    }
    return EnvSample(env_to_world(env, m), pdf_uv / (ENV_TWO_PI_SQUARED * sin_theta),
                     env.intensity * env_lookup_uv(env, uv));
}

// EnvironmentSampler::pdf: the solid-angle pdf of sampling world direction d.
fn env_pdf(env: EnvMap, d: vec3<f32>) -> f32 {
    let m = env_to_map(env, d);
    let sin_theta = sqrt(m.x * m.x + m.z * m.z);
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    let uv = env_direction_to_uv(m);
    let w = env.width;
    let h = env.height;
    let i = min(u32(uv.x * f32(w)), w - 1u);
    let j = min(u32(uv.y * f32(h)), h - 1u);
    let marginal = w * h;
    let row = j * w;
    let pm = environment_cdf[marginal + j] - env_cdf_start(marginal, j);
    let pc = environment_cdf[row + i] - env_cdf_start(row, i);
    return pm * pc * (f32(w) * f32(h)) / (ENV_TWO_PI_SQUARED * sin_theta);
}
// #endif
