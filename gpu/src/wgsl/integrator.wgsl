// furnace-gpu: the path tracer, twin of furnace-cpu's Renderer::sample / trace.
//
// Requires (composed before it by furnace_gpu::integrator): sampling.wgsl, brdf.wgsl,
// scene.wgsl, traverse.wgsl, a film module, and the bindings of the params uniform, the film,
// the BVH, the scene, the Turquin table and the ray counter.
//
// One invocation per pixel of a tile of rows; it adds `samples` consecutive samples of its pixel
// to the film in index order, as the CPU does, so pixel sums follow the same order.

// Sampler dimensions: furnace_cpu::{DIM_PIXEL, DIM_FIRST_BOUNCE, DIMS_PER_BOUNCE}.
const DIM_PIXEL: u32 = 0u;
const DIM_FIRST_BOUNCE: u32 = 2u;
const DIMS_PER_BOUNCE: u32 = 4u;

// FrameParams.flags.
const FRAME_RUSSIAN_ROULETTE: u32 = 1u;
const FRAME_ORTHOGRAPHIC: u32 = 2u;
const FRAME_ANY_MASKED: u32 = 4u;
const FRAME_HAS_SUN: u32 = 8u;
const FRAME_COUNT_RAYS: u32 = 16u;

// Rays this invocation traced (closest-hit and shadow); added to `ray_counter` at its end when
// FRAME_COUNT_RAYS is set.
var<private> rays_traced: u32 = 0u;

// gpu/src/integrator.rs `FrameParams` (checked by naga reflection in tests/integrator.rs).
struct FrameParams {
    // Camera: world_from_camera's columns (xyz) and translation.
    cam_x: vec4<f32>,
    cam_y: vec4<f32>,
    cam_z: vec4<f32>,
    cam_t: vec4<f32>,
    // Direction the sunlight travels (xyz); irradiance (rgb); sky radiance (rgb).
    sun_direction: vec4<f32>,
    sun_irradiance: vec4<f32>,
    sky: vec4<f32>,
    sampler: SamplerParams,
    width: u32,
    height: u32,
    first_sample: u32,
    samples: u32,
    bounces: u32,
    flags: u32,
    bsdf_flags: u32,
    row_offset: u32,
    // tan(yfov/2) (perspective) or ymag (orthographic), and the image aspect ratio w/h, both
    // computed on the CPU exactly as furnace-scene's Camera::generate_ray does.
    fov_scale: f32,
    aspect: f32,
    pad0: u32,
    pad1: u32,
}

// The alpha-mask callback of traverse.wgsl: masked materials' cut-outs are not hits.
fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool {
    if (params.flags & FRAME_ANY_MASKED) == 0u {
        return true;
    }
    return scene_alpha_passes(triangle_id, u, v);
}

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

fn frame_to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.x), dot(v, f.y), dot(v, f.z));
}

fn frame_to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return v.x * f.x + v.y * f.y + v.z * f.z;
}


// Renderer::trace: radiance arriving at `origin` from −`direction`.
fn trace_path(pixel: u32, index: u32, origin_in: vec3<f32>, direction_in: vec3<f32>) -> vec3<f32> {
    var origin = origin_in;
    var direction = direction_in;
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var event = 0u;
    let inf = bitcast<f32>(0x7f800000u);
    loop {
        rays_traced += 1u;
        let hit = trace_closest(origin, direction, inf);
        if !hit.hit {
            // The ray leaves the scene: the sky is gathered here and only here.
            radiance += throughput * params.sky.xyz;
            break;
        }
        let material = scene_triangle_material(hit.triangle);
        var uv = vec2<f32>(0.0);
        if scene_material_is_textured(material) {
            uv = scene_uv(hit.triangle, hit.u, hit.v);
        }
        let ms = scene_material_evaluate(material, uv);
        let surface = scene_surface_point(hit.triangle, hit.u, hit.v, uv, direction);
        if surface.valid == 0u {
            // The back of a single-sided surface: black.
            break;
        }
        radiance += throughput * ms.emission;
        if event == params.bounces {
            break;
        }
        let bsdf = bsdf_params(ms.base_color, ms.metallic, ms.roughness, ms.specular_factor,
                               ms.specular_color, params.bsdf_flags);
        let frame = frame_new(surface.shading);
        let wo = frame_to_local(frame, -direction);
        let leave = offset_ray_origin(surface.position, surface.geometric);

        // The sun, a delta light: gathered by a shadow ray only.
        if (params.flags & FRAME_HAS_SUN) != 0u {
            let to_sun = -params.sun_direction.xyz;
            if dot(to_sun, surface.geometric) > 0.0 {
                let f = bsdf_eval(bsdf, wo, frame_to_local(frame, to_sun));
                if any(f != vec3<f32>(0.0)) {
                    rays_traced += 1u;
                    if !trace_any(leave, to_sun, inf) {
                        radiance += throughput * f * params.sun_irradiance.xyz;
                    }
                }
            }
        }

        // Continue the path by sampling the BSDF.
        let dim = DIM_FIRST_BOUNCE + DIMS_PER_BOUNCE * event;
        let u = sampler_value_2d(params.sampler, pixel, index, dim);
        let uc = sampler_value(params.sampler, pixel, index, dim + 2u);
        let s = bsdf_sample(bsdf, wo, uc, u);
        if s.lobe == BSDF_LOBE_NONE {
            break;
        }
        let wi = frame_to_world(frame, s.wi);
        if !(dot(wi, surface.geometric) > 0.0) {
            // Above the shading normal's horizon but below the surface: the path ends.
            break;
        }
        throughput *= s.weight;
        event += 1u;
        if (params.flags & FRAME_RUSSIAN_ROULETTE) != 0u && event >= 3u {
            let survive = min(max(max(throughput.x, throughput.y), throughput.z), 1.0);
            if !(sampler_value(params.sampler, pixel, index, dim + 3u) < survive) {
                break;
            }
            throughput /= survive;
        }
        origin = leave;
        direction = wi;
    }
    return radiance;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = gid.x;
    let y = params.row_offset + gid.y;
    if x >= params.width || y >= params.height {
        return;
    }
    let pixel = y * params.width + x;
    for (var k = 0u; k < params.samples; k++) {
        let index = params.first_sample + k;
        let u = sampler_value_2d(params.sampler, pixel, index, DIM_PIXEL);
        let ray = camera_ray(vec2<f32>(f32(x) + u.x, f32(y) + u.y));
        film_add(pixel, trace_path(pixel, index, ray.origin, ray.direction));
    }
    if (params.flags & FRAME_COUNT_RAYS) != 0u {
        // A 64-bit sum in two words: the carry goes to word 1.
        let old = atomicAdd(&ray_counter[0], rays_traced);
        if old > 0xffffffffu - rays_traced {
            atomicAdd(&ray_counter[1], 1u);
        }
    }
}
