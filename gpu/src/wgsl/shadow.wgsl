// furnace-gpu: the integrator's shadow rays, twins of furnace-cpu's Vertex::origin_towards and
// CpuRenderer::transmittance: the traversal's hit filter (alpha masks, blended surfaces, and the
// blended surfaces and thin-walled sheets a shadow ray crosses, multiplying what it carries by
// what they let through), the origin of a shadow ray, the
// absorption of the volume a vertex is in, and the queue of the shadow rays a scattering event
// takes, traced by the path loop of integrator.wgsl.
//
// Composed by furnace_gpu::integrator::shader_source after material.wgsl, before lights.wgsl and
// integrator.wgsl.

// #if SHADOW_FILTER
// A shadow ray is being traced (`shadow`): thin-walled sheets and blended surfaces are crossed,
// not hits, and the light it carries is multiplied by what they let through in `shadow_carried`.
var<private> shadow_query: bool = false;
var<private> shadow_carried: vec3<f32>;
// #endif

// #if BLEND
// The blend seed of the path ray being traced (`blend_seed_of` its origin and direction).
var<private> blend_seed: u32;

// furnace_scene::blend_seed: a hash of a ray's origin's and direction's bits.
fn blend_seed_of(origin: vec3<f32>, direction: vec3<f32>) -> u32 {
    let o = bitcast<vec3<u32>>(origin);
    let d = bitcast<vec3<u32>>(direction);
    return smp_hash2(smp_hash3(o.x, o.y, o.z), smp_hash3(d.x, d.y, d.z));
}

// furnace_scene::blend_keeps: whether a ray of `seed` stops at triangle `t` of `coverage`.
fn blend_keeps(seed: u32, t: u32, coverage: f32) -> bool {
    let u = f32(smp_hash2(seed, t) >> 8u) * (1.0 / 16777216.0);
    return u < coverage;
}
// #endif

// The alpha callback of traverse.wgsl: masked materials' cut-outs are not hits, a path ray stops
// at a blended surface with probability equal to its coverage, and a shadow ray crosses blended
// surfaces and thin-walled sheets (CpuRenderer::stops and CpuRenderer::transmittance).
fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool {
    if (params.flags & FRAME_ANY_MASKED) != 0u && !scene_alpha_passes(triangle_id, u, v) {
        return false;
    }
    // #if BLEND
    var coverage = 1.0;
    let mi = scene_triangles[triangle_id].material;
    if (scene_materials[mi].flags & SCENE_ALPHA_MODE_BITS) == SCENE_ALPHA_BLEND {
        coverage = scene_blend_coverage(mi, triangle_id, u, v);
        if !shadow_query {
            // #if INSTANCES
            // Each instance of a triangle decides on its own (CpuRenderer::stops).
            return blend_keeps(blend_seed ^ instances[trv_instance].seed_mix, triangle_id, coverage);
            // #else
            return blend_keeps(blend_seed, triangle_id, coverage);
            // #endif
        }
    }
    // #endif
    // #if THIN_WALLED
    if shadow_query {
        let material = scene_triangles[triangle_id].material;
        let tr = scene_transmission[material];
        // Material::passes_shadow_rays: a sheet, or a solid of index 1.
        if (tr.flags & SCENE_TRANSMISSIVE) != 0u && ((tr.flags & SCENE_VOLUME) == 0u || tr.ior == 1.0) {
            let at = hit_attributes(material, triangle_id, u, v);
            let b = hit_bsdf(hit_material(material, at), material, at, tr.ior);
            // CpuRenderer::transmittance: T′ at the angle to the sheet's shading normal.
            var n = scene_shading_normal(triangle_id, u, v);
            let cos = scene_dot(shadow_direction, n);
            var through = b.t.weight * dielectric_shadow_transmittance(b.t.d, cos);
            // #if LAYERS
            // HitBsdf::sheet_transmittance: through the layers at that direction.
            if b.layered {
                through *= layers_below(b.l, vec3<f32>(0.0, 0.0, abs(cos)), vec3<f32>(0.0, 0.0, -abs(cos)));
            }
            // #endif
            // #if BLEND
            if coverage < 1.0 {
                shadow_carried *= (1.0 - coverage) + coverage * through;
                return all(shadow_carried == vec3<f32>(0.0));
            }
            // #endif
            shadow_carried *= through;
            return all(shadow_carried == vec3<f32>(0.0));
        }
    }
    // #endif
    // #if BLEND
    if shadow_query && coverage < 1.0 {
        shadow_carried *= 1.0 - coverage;
        return all(shadow_carried == vec3<f32>(0.0));
    }
    // #endif
    return true;
}

// Vertex::origin_towards: the origin of a shadow ray along wi (xyz) and whether there is one (w).
fn shadow_origin(b: HitBsdf, surface: SceneSurfacePoint, leave: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    let side = scene_dot(wi, surface.geometric);
    if side > 0.0 {
        return vec4<f32>(leave, 1.0);
    }
    // #if TRANSMISSION
    if side < 0.0 && b.two_sided {
        return vec4<f32>(b.behind, 1.0);
    }
    // #endif
    return vec4<f32>(0.0);
}

// Vertex::receiver_normal: the receiving side for the light BVH (zero: both sides).
fn receiver_normal(b: HitBsdf, surface: SceneSurfacePoint) -> vec3<f32> {
    // #if TRANSMISSION
    if b.two_sided {
        return vec3<f32>(0.0);
    }
    // #endif
    return surface.geometric;
}

// #if TRANSMISSION
// furnace-cpu's absorption: exp(−σ·t) per channel, 1 where σ is 0.
fn absorption(sigma: vec3<f32>, t: f32) -> vec3<f32> {
    return select(vec3<f32>(1.0), exp(-sigma * t), sigma > vec3<f32>(0.0));
}
// #endif

// #if THIN_WALLED
var<private> shadow_direction: vec3<f32>;
// #endif

// The absorption of the volume the vertex is in over a shadow ray's t_max (1 in air).
fn vertex_absorption(b: HitBsdf, t_max: f32) -> vec3<f32> {
    // #if TRANSMISSION
    if any(b.medium != vec3<f32>(0.0)) {
        return absorption(b.medium, t_max);
    }
    // #endif
    return vec3<f32>(1.0);
}

// #if HAS_POINT_LIGHTS
// #if !QUEUED_POINT_LIGHTS
// CpuRenderer::transmittance: what a shadow ray from `origin` along `dir` carries over t_max
// (0 where blocked; the sheets' T′ and the vertex's volume absorption otherwise). Traced here,
// through a second traversal call: for more point lights than the queue holds.
fn shadow(b: HitBsdf, origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> vec3<f32> {
    // #if TRACE_COUNTERS
    rays_traced += 1u;
    // #endif
    let carried = vertex_absorption(b, t_max);
    // #if SHADOW_FILTER
    shadow_carried = carried;
    shadow_query = true;
    // #endif
    // #if THIN_WALLED
    shadow_direction = dir;
    // #endif
    // #if SHADOW_FILTER
    let blocked = trace_any(origin, dir, t_max);
    shadow_query = false;
    if blocked {
        return vec3<f32>(0.0);
    }
    return shadow_carried;
    // #else
    if trace_any(origin, dir, t_max) {
        return vec3<f32>(0.0);
    }
    return carried;
    // #endif
}
// #endif
// #endif

// The shadow rays of the light samples taken at a scattering event (one per light kind the
// scene samples, furnace_gpu's SceneFeatures::shadow_kinds), traced later by the path loop
// itself, before the path's next ray and through the same `trace_query` call: the driver
// inlines the traversal once instead of once more for the shadow rays. `value` is what the
// light adds if the ray is not blocked (throughput, BSDF, light and MIS weight, the vertex's
// volume absorption). SHADOW_KINDS (generated) is that number of kinds, plus one per point light
// where the scene has few of them (QUEUED_POINT_LIGHTS), SHADOW_SLOTS the same but at least 1.
// More point lights keep `shadow`.
struct ShadowRay {
    origin: vec3<f32>,
    t_max: f32,
    dir: vec3<f32>,
    value: vec3<f32>,
}

var<private> shadow_rays: array<ShadowRay, SHADOW_SLOTS>;
var<private> shadow_queued: u32 = 0u;

// Queues a shadow ray from `origin` along `dir` over t_max carrying `value` if unblocked.
fn defer_shadow(b: HitBsdf, origin: vec3<f32>, dir: vec3<f32>, t_max: f32, value: vec3<f32>) {
    shadow_rays[shadow_queued] = ShadowRay(origin, t_max, dir, value * vertex_absorption(b, t_max));
    shadow_queued += 1u;
}
