// furnace-gpu: the path tracer, twin of furnace-cpu's CpuRenderer::sample / trace.
//
// Requires (composed before it by furnace_gpu::integrator::shader_source): sampling.wgsl,
// brdf.wgsl, scene.wgsl, traverse.wgsl, a film module, path.wgsl, material.wgsl, shadow.wgsl,
// lights.wgsl, and the bindings of the params uniform, the film, the BVH, the scene, the Turquin
// table and the ray counter.
//
// A sample's path runs in stages, a function each: the camera (`start_path`); the intersection
// (the loop's one `trace_query` call, which the shadow rays share); then at a surface
// (`shade_hit`) its emission (`add_emission`), the light samples (lights.wgsl's
// `sample_lights`) and the BSDF sample that continues the path (`scatter`), or, for a ray that
// leaves the scene, what is at infinity (`escape`). Each pixel's samples are added to the film in
// index order, as the CPU adds them (see `main`).

// Sampler dimensions: DIM_PIXEL, DIM_FIRST_BOUNCE, DIMS_PER_BOUNCE and BOUNCE_* are declared by
// the composing shader from furnace_render::layout.

// FRAME_* flags, FrameParams and the bindings are declared by the composing shader, generated
// from furnace_gpu::integrator (frame_flags_wgsl, FrameParams, binding_table).

// #if TRACE_COUNTERS
// Rays this invocation traced (closest-hit and shadow); added to `ray_counter` at its end (the
// counting kernel only).
var<private> rays_traced: u32 = 0u;
// #endif

// #if AOVS
// What the current sample's camera ray hit first (furnace_render::AovSample), as the two vectors
// of its sums (AovSum's layout): albedo and depth, shading normal and hit (1, or 0 for a miss).
var<private> aov_albedo_depth: vec4<f32>;
var<private> aov_normal_hit: vec4<f32>;
// #endif

// The state of a sample's path between its rays (Renderer::trace's locals), set where the
// sample starts (`start_path`).
struct Path {
    origin: vec3<f32>,
    direction: vec3<f32>,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    // Scattering events so far.
    event: u32,
    // #if SAMPLES_LIGHTS
    // The pdf of the BSDF sample that made the ray (−1: the camera's or a delta event's), for
    // MIS weights.
    ray_pdf: f32,
    // #endif
    // #if HAS_EMITTERS
    // The receiving side (geometric normal) of the vertex the ray left, for the light BVH.
    normal: vec3<f32>,
    // #endif
    // #if TRANSMISSION
    // Where that vertex took its light samples (when the ray has since crossed a surface).
    mis_origin: vec3<f32>,
    mis_moved: bool,
    // The absorption coefficient of the volume the ray travels in (0: air), and the surface
    // point the ray left (its offset origin would shorten the path by the offset).
    medium: vec3<f32>,
    left_from: vec3<f32>,
    // Passes through sheets since the last event, and the lobe number they left (< 0: none).
    passes: u32,
    carried_uc: f32,
    // #endif
    // #if DISPERSION
    // The wavelength (nm) the path is traced at since its first dispersive solid (0: RGB).
    wavelength: f32,
    // #endif
}

// The camera stage: sample `index` of pixel (x, y) starts with a camera ray jittered inside the
// pixel, nothing gathered yet (with AOVs: nothing hit yet, AovSample::MISS).
fn start_path(path: ptr<function, Path>, x: u32, y: u32, pixel: u32, index: u32) {
    let u = sampler_value_2d(params.sampler, pixel, index, DIM_PIXEL);
    let ray = camera_ray(vec2<f32>(f32(x) + u.x, f32(y) + u.y));
    path.origin = ray.origin;
    path.direction = ray.direction;
    path.radiance = vec3<f32>(0.0);
    path.throughput = vec3<f32>(1.0);
    path.event = 0u;
    // #if SAMPLES_LIGHTS
    path.ray_pdf = -1.0;
    // #endif
    // #if HAS_EMITTERS
    path.normal = vec3<f32>(0.0);
    // #endif
    // #if TRANSMISSION
    path.mis_origin = vec3<f32>(0.0);
    path.mis_moved = false;
    path.medium = vec3<f32>(0.0);
    path.left_from = ray.origin;
    path.passes = 0u;
    path.carried_uc = -1.0;
    // #endif
    // #if DISPERSION
    path.wavelength = 0.0;
    // #endif
    // #if AOVS
    // AovSample::MISS: albedo 1, no normal, no depth.
    aov_albedo_depth = vec4<f32>(1.0, 1.0, 1.0, 0.0);
    aov_normal_hit = vec4<f32>(0.0);
    // #endif
}

// The ray left the scene: the sky and, where the scene has them, the lights at infinity,
// weighted against their light samples.
fn escape(path: ptr<function, Path>) {
    // #if TRANSMISSION
    if any(path.medium != vec3<f32>(0.0)) {
        path.throughput *= absorption(path.medium, bitcast<f32>(0x7f800000u));
    }
    // #endif
    path.radiance += path.throughput * params.sky.xyz;
    // #if HAS_ENVIRONMENT
    // CpuRenderer::environment_seen: a camera ray (no event yet) sees it only if visible; a BSDF
    // ray is weighted against the environment's light samples.
    if path.event > 0u || (params.env_flags & ENV_VISIBLE) != 0u {
        var w = 1.0;
        // #if SAMPLES_ENVIRONMENT
        if path.ray_pdf >= 0.0 {
            w = bsdf_weight(path.ray_pdf, env_pdf(frame_env(), path.direction));
        }
        // #endif
        if w != 0.0 {
            path.radiance += path.throughput * (env_radiance(frame_env(), path.direction) * w);
        }
    }
    // #endif
    // #if HAS_SUN_DISC
    path.radiance += path.throughput * sun_disc_seen(path.direction, path.ray_pdf);
    // #endif
}

// #if AOVS
// Records the camera ray's hit as the sample's AOVs: the material's base colour (an emitter's
// front: albedo 1, its colour is its light, like the sky's), the depth and the shading normal
// (none on the back of a single-sided surface, which is black).
fn record_first_hit(ms: MaterialSample, surface: SceneSurfacePoint, t: f32) {
    let n = select(vec3<f32>(0.0), surface.shading, surface.valid != 0u);
    let emits = any(ms.emission != vec3<f32>(0.0)) && surface.valid != 0u && surface.back_face == 0u;
    aov_albedo_depth = vec4<f32>(select(ms.base_color, vec3<f32>(1.0), emits), t);
    aov_normal_hit = vec4<f32>(n, 1.0);
}
// #endif

// The emission the ray reached on the front of a surface (throughput included); where emissive
// triangles are light-sampled, weighted against those samples (CpuRenderer::emission_weight)
// taken where the ray's vertex was.
fn add_emission(path: ptr<function, Path>, emission: vec3<f32>, material: u32, hit: Hit,
                surface: SceneSurfacePoint) {
    // #if HAS_EMITTERS
    if any(emission != vec3<f32>(0.0)) {
        let cos_light = -scene_dot(surface.geometric, path.direction);
        var mis_from = path.origin;
        var distance = hit.t;
        // #if TRANSMISSION
        if path.mis_moved {
            mis_from = path.mis_origin;
            distance = length(surface.position - path.mis_origin);
        }
        // #endif
        let w = emission_weight(path.ray_pdf, mis_from, path.normal, material, hit.triangle, distance,
                                cos_light);
        path.radiance += path.throughput * emission * w;
    }
    // #else
    path.radiance += path.throughput * emission;
    // #endif
}

// The event just sampled is counted; from the third on, Russian roulette (with its flag): the
// path ends, or its throughput is divided by the survival probability. Returns whether the path
// goes on.
fn count_event(path: ptr<function, Path>, pixel: u32, index: u32, dim: u32) -> bool {
    path.event += 1u;
    if (params.flags & FRAME_RUSSIAN_ROULETTE) != 0u && path.event >= 3u {
        let survive = russian_roulette_survival(path.throughput);
        if !(sampler_value(params.sampler, pixel, index, dim + BOUNCE_RUSSIAN_ROULETTE) < survive) {
            return false;
        }
        path.throughput /= survive;
    }
    return true;
}

// #if !TRANSMISSION
// The scattering stage at an opaque surface: the BSDF sample that continues the path (its
// direction, the throughput's weight), Russian roulette, the next ray from `leave`. Returns
// whether the path goes on.
fn scatter(path: ptr<function, Path>, pixel: u32, index: u32, bsdf: HitBsdf, wo: vec3<f32>,
           frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) -> bool {
    let dim = DIM_FIRST_BOUNCE + DIMS_PER_BOUNCE * path.event;
    let u = sampler_value_2d(params.sampler, pixel, index, dim + BOUNCE_BSDF_DIRECTION);
    let uc = sampler_value(params.sampler, pixel, index, dim + BOUNCE_BSDF_LOBE);
    // #if LAYERS
    var s: BsdfSample;
    if bsdf.layered {
        s = hit_sample_layered(bsdf, wo, uc, u);
    } else {
        s = bsdf_sample(bsdf.m, wo, uc, u);
    }
    // #else
    let s = bsdf_sample(bsdf.m, wo, uc, u);
    // #endif
    if s.lobe == BSDF_LOBE_NONE {
        return false;
    }
    let wi = frame_to_world(frame, s.wi);
    if !(dot(wi, surface.geometric) > 0.0) {
        // Above the shading normal's horizon but below the surface: the path ends.
        return false;
    }
    path.throughput *= s.weight;
    // #if SAMPLES_LIGHTS
    path.ray_pdf = s.pdf;
    // #endif
    if !count_event(path, pixel, index, dim) {
        return false;
    }
    // #if HAS_EMITTERS
    path.normal = receiver_normal(bsdf, surface);
    // #endif
    path.origin = leave;
    path.direction = wi;
    return true;
}
// #else
// The scattering stage with transmissive materials: the BSDF sample (the lobe number carried
// through sheets), straight through a sheet or an invisible interface without an event (up to
// MAX_SHEET_PASSES), else an event: Russian roulette, the medium the ray enters, the next ray
// from `leave` or, crossing, from `behind`. `last`: the event at the bounce limit, which only a
// straight pass survives. Returns whether the path goes on.
fn scatter_transmissive(path: ptr<function, Path>, pixel: u32, index: u32, bsdf: HitBsdf,
                        wo: vec3<f32>, frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>,
                        behind: vec3<f32>, material: u32, last: bool, volume: bool,
                        straight: bool) -> bool {
    let dim = DIM_FIRST_BOUNCE + DIMS_PER_BOUNCE * path.event;
    let u = sampler_value_2d(params.sampler, pixel, index, dim + BOUNCE_BSDF_DIRECTION);
    var uc: f32;
    if path.carried_uc >= 0.0 {
        uc = path.carried_uc;
    } else {
        uc = sampler_value(params.sampler, pixel, index, dim + BOUNCE_BSDF_LOBE);
    }
    // #if LAYERS
    var s: ScatterSample;
    if bsdf.layered {
        s = hit_scatter_layered(bsdf, wo, uc, u);
    } else {
        s = hit_material_scatter(bsdf, wo, uc, u);
    }
    // #else
    let s = hit_material_scatter(bsdf, wo, uc, u);
    // #endif
    if !s.valid {
        return false;
    }
    let wi = frame_to_world(frame, s.wi);
    // Reflections leave on the side the ray came from, transmissions on the other (at a
    // solid's interface, whichever side the ray points to).
    let side = dot(wi, surface.geometric);
    let crosses = select(s.transmitted, side < 0.0, volume);
    if !select(side > 0.0, side < 0.0, crosses) {
        return false;
    }
    if s.delta && s.transmitted && straight {
        // Straight through a sheet or an invisible interface: no event, the MIS state of the
        // last one kept (a solid's medium changes).
        if volume {
            path.medium = select(scene_transmission[material].absorption, vec3<f32>(0.0), surface.back_face != 0u);
        }
        path.passes += 1u;
        if path.passes > MAX_SHEET_PASSES {
            return false;
        }
        path.throughput *= s.weight;
        path.carried_uc = s.rest;
        if !path.mis_moved {
            path.mis_origin = path.origin;
            path.mis_moved = true;
        }
        path.origin = behind;
        path.left_from = surface.position;
        return true;
    }
    if last {
        return false;
    }
    path.throughput *= s.weight;
    // #if SAMPLES_LIGHTS
    path.ray_pdf = select(s.pdf, -1.0, s.delta);
    // #endif
    path.passes = 0u;
    path.carried_uc = -1.0;
    // HitBsdf::bounds_medium: a solid's interface, refracting or diffusely transmitting.
    var bounds_medium = volume;
    // #if DIFFUSE_TRANSMISSION
    bounds_medium = bounds_medium || (bsdf.dt_volume && any(bsdf.dt != vec3<f32>(0.0)));
    // #endif
    if crosses && bounds_medium {
        // Into the solid from outside, or out of it.
        path.medium = select(scene_transmission[material].absorption, vec3<f32>(0.0), surface.back_face != 0u);
    }
    if !count_event(path, pixel, index, dim) {
        return false;
    }
    // #if HAS_EMITTERS
    path.normal = receiver_normal(bsdf, surface);
    // #endif
    path.left_from = surface.position;
    if crosses {
        path.origin = behind;
        path.mis_origin = leave;
        path.mis_moved = true;
    } else {
        path.origin = leave;
        path.mis_moved = false;
    }
    path.direction = wi;
    return true;
}
// #endif

// The surface stage at the triangle the path's ray hit: its material and shading point (with
// AOVs, the camera ray's hit recorded), the volume's absorption up to it, its emission; then,
// where the path may go on, its BSDF, the light samples (`sample_lights`) and the BSDF sample
// that continues the path (`scatter`). Returns whether the path goes on.
fn shade_hit(path: ptr<function, Path>, hit: Hit, pixel: u32, index: u32) -> bool {
    // #if INSTANCES
    trv_instance = hit.instance;
    // #endif
    let material = scene_triangle_material(hit.triangle);
    let at = hit_attributes(material, hit.triangle, hit.u, hit.v);
    let ms = hit_material(material, at);
    let surface = scene_surface_point(hit.triangle, hit.u, hit.v, at, path.direction);
    // #if AOVS
    if path.event == 0u {
        record_first_hit(ms, surface, hit.t);
    }
    // #endif
    if surface.valid == 0u {
        // The back of a single-sided surface: black.
        return false;
    }
    // #if TRANSMISSION
    if any(path.medium != vec3<f32>(0.0)) {
        // Beer–Lambert over the segment inside the volume, surface to surface.
        path.throughput *= absorption(path.medium, length(surface.position - path.left_from));
    }
    // #endif
    // #if UNLIT
    if (scene_materials[material].flags & SCENE_MATERIAL_UNLIT) != 0u {
        // KHR_materials_unlit: the colour as is, from either side; nothing reflected.
        path.radiance += path.throughput * ms.base_color;
        return false;
    }
    // #endif
    // Emission is one-sided: the back of a double-sided emitter does not emit.
    if surface.back_face == 0u {
        add_emission(path, ms.emission, material, hit, surface);
    }
    let last = path.event == params.bounces;
    // #if !TRANSMISSION
    if last {
        return false;
    }
    // #endif
    // The index of a transmissive material's interface (read only with TRANSMISSION).
    var ior = 1.5;
    // #if TRANSMISSION
    ior = scene_transmission[material].ior;
    // #endif
    // #if DISPERSION
    let dispersion = scene_transmission[material].dispersion;
    if dispersion > 0.0 {
        // A dispersive solid: its index at the path's wavelength, drawn here if this is the
        // first (the throughput takes the wavelength's RGB weight).
        if path.wavelength == 0.0 {
            let dim = 4u * (params.bounces + 1u) + LIGHT_DIMS_PER_EVENT * params.bounces + params.bounces;
            let s = spectrum_sample(sampler_value(params.sampler, pixel, index, dim));
            path.throughput *= s.weight;
            path.wavelength = s.lambda;
        }
        ior = spectrum_dispersed_ior(ior, dispersion, path.wavelength);
    }
    // #endif
    var bsdf = hit_bsdf(ms, material, at, ior);
    // #if ANISOTROPY
    let facing = select(surface.shading, -surface.shading, surface.back_face != 0u);
    let anisotropy = hit_anisotropy(material, hit.triangle, hit.u, hit.v, at, facing);
    bsdf = hit_with_anisotropy(bsdf, anisotropy.w);
    // #endif
    var shading = surface.shading;
    var delta = false;
    // #if TRANSMISSION
    let volume = (bsdf.kind & SCENE_VOLUME) != 0u;
    let straight = bsdf.kind != 0u && dielectric_is_straight(bsdf.t.d);
    if last && !straight {
        return false;
    }
    // A solid's interface is shaded in its outward frame (wo may be inside).
    if volume && surface.back_face != 0u {
        shading = -shading;
    }
    delta = bsdf.kind != 0u && transmissive_is_delta(bsdf.t);
    // #if LAYERS
    // HitBsdf::is_delta: layers above a smooth dielectric reflect light samples.
    delta = delta && !bsdf.layered;
    // #endif
    // #endif
    // #if ANISOTROPY
    // The BSDF's frame: x along the anisotropy direction where there is one.
    let frame = frame_with_tangent(shading, anisotropy.xyz);
    // #else
    let frame = frame_new(shading);
    // #endif
    // #if CLEARCOAT
    // The coat's own normal (Clearcoat::with_normal), in the frame the BSDF is shaded in.
    if bsdf.layered && bsdf.l.coat_factor > 0.0 {
        let coat = layers_coat_normal(material, hit.triangle, hit.u, hit.v, at, surface);
        if any(coat != surface.shading) {
            var sign = 1.0;
            // #if TRANSMISSION
            if volume && surface.back_face != 0u {
                sign = -1.0;
            }
            // #endif
            bsdf.l = layers_with_coat_normal(bsdf.l, frame_to_local(frame, sign * coat));
        }
    }
    // #endif
    let wo = frame_to_local(frame, -path.direction);
    let leave = offset_ray_origin_scaled(surface.position, surface.geometric, params.offset_scale);
    // #if TRANSMISSION
    let behind = offset_ray_origin_scaled(surface.position, -surface.geometric, params.offset_scale);
    // HitBsdf::transmits_light_samples: a rough solid interface or a rough sheet.
    bsdf.two_sided = (volume && bsdf.t.d.iface == DIELECTRIC_ROUGH) || bsdf.t.d.iface == DIELECTRIC_ROUGH_THIN;
    // #if DIFFUSE_TRANSMISSION
    // HitBsdf::transmits_light_samples: diffuse transmission is lit from behind too.
    bsdf.two_sided = bsdf.two_sided || any(bsdf.dt != vec3<f32>(0.0));
    // #endif
    bsdf.behind = behind;
    bsdf.medium = path.medium;
    // #endif
    if !last && !delta {
        sample_lights(path, pixel, index, bsdf, wo, frame, surface, leave);
    }
    // #if TRANSMISSION
    return scatter_transmissive(path, pixel, index, bsdf, wo, frame, surface, leave, behind, material,
                                last, volume, straight);
    // #else
    return scatter(path, pixel, index, bsdf, wo, frame, surface, leave);
    // #endif
}

// Renderer::trace for `count` samples of `pixel` at (x, y) from sample `first` on: with
// `to_film`, each sample is added to the film as it ends (in index order); the last sample's
// value is returned. The samples run in one loop: a lane whose path ends starts its next sample
// in the next iteration instead of waiting for the warp's other paths to end (path
// regeneration), and no two copies of the path's code are composed.
fn trace_samples(x: u32, y: u32, pixel: u32, first: u32, count: u32, to_film: bool) -> vec3<f32> {
    var index = first;
    var started = 0u;
    // The current sample's path (zero until the first starts: an invocation with no samples
    // returns a zero radiance).
    var path: Path;
    let inf = bitcast<f32>(0x7f800000u);
    // The loop traces one ray per iteration: a path's next ray, or one of the shadow rays
    // queued at its last scattering event (`defer_shadow`). Every path ray is followed by
    // SHADOW_KINDS shadow iterations, empty ones for light samples not taken (none taken when
    // the path ended there), so that the lanes of a warp stay in step, each iteration running
    // the same kind of work in all of them, also across the start of a lane's next sample.
    // `shadow_next`: the next shadow iteration.
    var shadow_runs = 0u;
    var shadow_next = 0u;
    // Whether the current sample's path goes on (false before the first sample).
    var alive = false;
    loop {
        var query_origin = path.origin;
        var query_dir = path.direction;
        var query_t = inf;
        let shadowing = shadow_next < shadow_runs;
        let queued = shadow_next < shadow_queued;
        if shadowing {
            if queued {
                let q = shadow_rays[shadow_next];
                query_origin = q.origin;
                query_dir = q.dir;
                query_t = q.t_max;
                // #if SHADOW_FILTER
                shadow_carried = q.value;
                shadow_query = true;
                // #endif
                // #if THIN_WALLED
                shadow_direction = q.dir;
                // #endif
            } else {
                // An empty iteration: t_max 0 traces nothing.
                query_t = 0.0;
            }
        } else if !alive {
            // The sample ended (or none started yet): add it, start the next one.
            if started > 0u && to_film {
                film_add_sample(pixel, clamp_sample(path.radiance));
            }
            if started == count {
                break;
            }
            index = first + started;
            started += 1u;
            start_path(&path, x, y, pixel, index);
            alive = true;
            query_origin = path.origin;
            query_dir = path.direction;
        }
        // #if TRACE_COUNTERS
        rays_traced += select(0u, 1u, query_t > 0.0);
        // #endif
        // #if BLEND
        if !shadowing {
            blend_seed = blend_seed_of(query_origin, query_dir);
        }
        // #endif
        // The intersection stage: the kernel's one traversal call, for path and shadow rays.
        let hit = trace_query(query_origin, query_dir, query_t, shadowing);
        if shadowing {
            if queued {
                var carried = shadow_rays[shadow_next].value;
                // #if SHADOW_FILTER
                shadow_query = false;
                carried = shadow_carried;
                // #endif
                if !hit.hit {
                    path.radiance += carried;
                }
            }
            shadow_next += 1u;
            continue;
        }
        shadow_queued = 0u;
        shadow_next = 0u;
        shadow_runs = SHADOW_KINDS;
        // The path's next stage: the surface it hit, or what is at infinity. The two forms below
        // are the same branch; the GPU's compiler schedules them differently, and each is the one
        // that runs faster for its kernels in the before/after speed runs of BENCHMARKS.md (with
        // transmission, if/else; without, an early continue).
        // #if TRANSMISSION
        if hit.hit {
            alive = shade_hit(&path, hit, pixel, index);
        } else {
            escape(&path);
            alive = false;
        }
        // #else
        if !hit.hit {
            escape(&path);
            alive = false;
            continue;
        }
        alive = shade_hit(&path, hit, pixel, index);
        // #endif
    }
    return path.radiance;
}

// #if TRACE_COUNTERS
// Adds `v` to the 64-bit counter in words `k`, `k + 1` (the carry goes to word k + 1).
fn counter_add(k: u32, v: u32) {
    if v == 0u {
        return;
    }
    let old = atomicAdd(&ray_counter[k], v);
    if old > 0xffffffffu - v {
        atomicAdd(&ray_counter[k + 1u], 1u);
    }
}
// #endif

// Invocations of a workgroup (FrameParams.group_samples × pixels of a tile); furnace_gpu::integrator's
// GROUP_SIZE (checked by its tests).
const GROUP_SIZE: u32 = 256u;

// One sample per invocation when a workgroup shares its pixels' samples (group_samples > 1).
var<workgroup> group_values: array<vec4<f32>, GROUP_SIZE>;
// #if AOVS
// And its AOVs.
var<workgroup> group_aov_albedo_depth: array<vec4<f32>, GROUP_SIZE>;
var<workgroup> group_aov_normal_hit: array<vec4<f32>, GROUP_SIZE>;
// #endif

// Film::add_sample_with_aovs: the sample, and, with AOVs, its camera ray's first hit when the
// sample is accepted (the same test as film_add's).
fn film_add_sample(pixel: u32, value: vec3<f32>) {
    // #if AOVS
    if film_is_finite(value) {
        film_aov[2u * pixel] = film_aov[2u * pixel] + aov_sum_t(aov_albedo_depth);
        film_aov[2u * pixel + 1u] = film_aov[2u * pixel + 1u] + aov_sum_t(aov_normal_hit);
    }
    // #endif
    film_add(pixel, value);
}

// Twin of furnace_render::clamp_sample: the sample scaled so that its largest channel is at most
// `params.sample_clamp` (0: off); non-finite samples unchanged (the film rejects them).
fn clamp_sample(v: vec3<f32>) -> vec3<f32> {
    let max_value = params.sample_clamp;
    let m = max(v.x, max(v.y, v.z));
    if max_value > 0.0 && film_is_finite(v) && m > max_value {
        return v * (max_value / m);
    }
    return v;
}

// A workgroup covers a tile of (GROUP_SIZE / group_samples) pixels, tile_width wide; each pixel's
// group_samples invocations are consecutive. With group_samples = 1 an invocation owns its pixel
// and adds `samples` samples in index order; with more, invocation `sub` computes sample
// first_sample + sub and the pixel's first invocation adds the group's values in index order
// after a barrier — the same additions in the same order either way, so the film does not
// depend on the grouping (tests/integrator.rs); grouping only spreads a small image over more
// of the GPU.
@compute @workgroup_size(GROUP_SIZE)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) l: u32) {
    let sg = params.group_samples;
    let tw = params.tile_width;
    let th = (GROUP_SIZE / sg) / tw;
    let p = l / sg;
    let sub = l % sg;
    let x = wg.x * tw + p % tw;
    let y = params.row_offset + wg.y * th + p / tw;
    let pixel = y * params.width + x;
    var inside = x < params.width && y < params.height;
    // #if ADAPTIVE
    // A converged pixel takes no more samples (adaptive sampling).
    if inside {
        inside = film_converged[pixel] == 0u;
    }
    // #endif
    // One call of the path code (the driver inlines each call site): with one invocation per
    // pixel, all of the pixel's samples, added to the film as they end; with several, sample
    // `sub` alone, added below.
    let solo = sg == 1u;
    var first = params.first_sample;
    var count = params.samples;
    if !solo {
        first += sub;
        count = select(0u, 1u, sub < params.samples);
    }
    if !inside {
        count = 0u;
    }
    let sample_value = trace_samples(x, y, pixel, first, count, solo);
    if !solo {
        let value = vec4<f32>(sample_value, 0.0);
        group_values[l] = value;
        // #if AOVS
        group_aov_albedo_depth[l] = aov_albedo_depth;
        group_aov_normal_hit[l] = aov_normal_hit;
        // #endif
        workgroupBarrier();
        if inside && sub == 0u {
            for (var k = 0u; k < params.samples; k++) {
                // #if AOVS
                aov_albedo_depth = group_aov_albedo_depth[l + k];
                aov_normal_hit = group_aov_normal_hit[l + k];
                // #endif
                film_add_sample(pixel, clamp_sample(group_values[l + k].xyz));
            }
        }
    }
    // #if TRACE_COUNTERS
    counter_add(0u, rays_traced);
    counter_add(2u, trace_stats.nodes);
    counter_add(4u, trace_stats.triangles);
    atomicAdd(&ray_counter[6], trace_stats.fallbacks);
    atomicMax(&ray_counter[7], trace_stats.max_depth);
    // #endif
}

// #if ADAPTIVE_ON_GPU
// Twin of furnace_render::AdaptiveSampling::converged over the f64 film: the relative standard
// error of the pixel's luminance below params.noise_threshold, compared squared (no f64 sqrt).
fn adaptive_converged(pixel: u32) -> bool {
    let count = film_count[pixel].x;
    if count < 2u {
        return false;
    }
    let s = film_sum[pixel];
    let n = f64(count);
    let w = vec3<f64>(FILM_LUMINANCE);
    let mean = (s.x * w.x + s.y * w.y + s.z * w.z) / n;
    let v = (s.w - n * mean * mean) / (n - 1.0);
    if v <= 0.0 {
        return true;
    }
    let t = f64(params.noise_threshold);
    return mean > 0.0 && v < t * t * n * mean * mean;
}

// Adaptive sampling's test (furnace_render::Film::test_convergence): marks the pixels that have
// converged and adds the newly converged to the running count. A 2-D grid of workgroups over the
// pixels in order.
@compute @workgroup_size(GROUP_SIZE)
fn converge(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
            @builtin(local_invocation_index) l: u32) {
    let pixel = (wg.y * groups.x + wg.x) * GROUP_SIZE + l;
    if pixel >= params.width * params.height {
        return;
    }
    if film_converged[pixel] == 0u && adaptive_converged(pixel) {
        film_converged[pixel] = 1u;
        atomicAdd(&converged_counter[0], 1u);
    }
}
// #endif
