// The per-path pieces of the integrator with Rust twins, parity-tested on their own
// (furnace-tests' path_parity.rs): the camera ray (furnace-scene's Camera::generate_ray), the
// shading frame (furnace-brdf's Frame) and Russian roulette's survival probability
// (furnace-render's russian_roulette_survival). They read the uniform `params: FrameParams`.

struct Ray {
    origin: vec3<f32>,
    direction: vec3<f32>,
}

// glam's Affine3A::transform_vector3: x·X + y·Y + z·Z in that order.
fn camera_vector(d: vec3<f32>) -> vec3<f32> {
    return params.cam_x.xyz * d.x + params.cam_y.xyz * d.y + params.cam_z.xyz * d.z;
}

// Camera::generate_ray: film point in pixels (row 0 at the top) → world ray.
fn camera_ray(film: vec2<f32>) -> Ray {
    let w = f32(max(params.width, 1u));
    let h = f32(max(params.height, 1u));
    let x = 2.0 * film.x / w - 1.0;
    let y = 1.0 - 2.0 * film.y / h;
    var o = vec3<f32>(0.0);
    var d: vec3<f32>;
    if (params.flags & FRAME_ORTHOGRAPHIC) != 0u {
        o = vec3<f32>(x * params.fov_scale * params.aspect, y * params.fov_scale, 0.0);
        d = vec3<f32>(0.0, 0.0, -1.0);
    } else {
        d = vec3<f32>(x * params.fov_scale * params.aspect, y * params.fov_scale, -1.0);
    }
    return Ray(camera_vector(o) + params.cam_t.xyz, normalize(camera_vector(d)));
}

// furnace-cpu's Frame (Duff et al. 2017): z = n.
struct Frame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
}

fn frame_new(n: vec3<f32>) -> Frame {
    // 1.0.copysign(n.z), on the sign bit (−0.0 gives −1, as in Rust).
    let sign = bitcast<f32>(0x3f800000u | (bitcast<u32>(n.z) & 0x80000000u));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let x = vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let y = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return Frame(x, y, n);
}

// #if ANISOTROPY
// Frame::with_tangent: x along `tangent` made orthogonal to `n`, y = n × x; frame_new(n) where
// that part is within rounding of zero (a tangent along n, zero, or not finite).
fn frame_with_tangent(n: vec3<f32>, tangent: vec3<f32>) -> Frame {
    let across = tangent - n * dot(n, tangent);
    if !(dot(across, across) > 1e-6 * dot(tangent, tangent)) {
        return frame_new(n);
    }
    // Projected twice, as the Rust (orthogonal to rounding for a tangent near n).
    let a2 = across - n * dot(n, across);
    let x = a2 * (1.0 / sqrt(dot(a2, a2)));
    return Frame(x, cross(n, x), n);
}
// #endif

fn frame_to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.x), dot(v, f.y), dot(v, f.z));
}

fn frame_to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return v.x * f.x + v.y * f.y + v.z * f.z;
}

// furnace_render::russian_roulette_survival: the largest throughput channel, at most 1.
fn russian_roulette_survival(throughput: vec3<f32>) -> f32 {
    return min(max(max(throughput.x, throughput.y), throughput.z), 1.0);
}
