// furnace-gpu: the path tracer, twin of furnace-cpu's CpuRenderer::sample / trace.
//
// Requires (composed before it by furnace_gpu::integrator): sampling.wgsl, brdf.wgsl,
// scene.wgsl, traverse.wgsl, a film module, and the bindings of the params uniform, the film,
// the BVH, the scene, the Turquin table and the ray counter.
//
// Each pixel's samples are added to the film in index order, as the CPU adds them (see `main`).

// Sampler dimensions: DIM_PIXEL, DIM_FIRST_BOUNCE, DIMS_PER_BOUNCE and BOUNCE_* are declared by
// the composing shader from furnace_render::layout.

// FRAME_* flags, FrameParams and the bindings are declared by the composing shader, generated
// from furnace_gpu::integrator (frame_flags_wgsl, FrameParams, binding_table).

// #if TRACE_COUNTERS
// Rays this invocation traced (closest-hit and shadow); added to `ray_counter` at its end (the
// counting kernel only).
var<private> rays_traced: u32 = 0u;
// #endif


// #if THIN_WALLED
// A shadow ray is being traced (`shadow`): thin-walled sheets are crossed, not hits, and the
// light it carries is multiplied by their T′ in `shadow_carried`.
var<private> shadow_query: bool = false;
var<private> shadow_carried: vec3<f32>;
// #endif

// The alpha-mask callback of traverse.wgsl: masked materials' cut-outs are not hits (and, for a
// shadow ray, thin-walled sheets are crossed).
fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool {
    if (params.flags & FRAME_ANY_MASKED) != 0u && !scene_alpha_passes(triangle_id, u, v) {
        return false;
    }
    // #if THIN_WALLED
    if shadow_query {
        let material = scene_triangles[triangle_id].material;
        let tr = scene_transmission[material];
        // Material::passes_shadow_rays: a sheet, or a solid of index 1.
        if (tr.flags & SCENE_TRANSMISSIVE) != 0u && ((tr.flags & SCENE_VOLUME) == 0u || tr.ior == 1.0) {
            var uv = vec2<f32>(0.0);
            if scene_material_is_textured(material) {
                uv = scene_uv(triangle_id, u, v);
            }
            let b = hit_bsdf(scene_material_evaluate(material, uv), material, uv);
            // CpuRenderer::transmittance: T′ at the angle to the sheet's shading normal.
            var n = scene_shading_normal(triangle_id, u, v);
            let cos = scene_dot(shadow_direction, n);
            shadow_carried *= b.t.weight * dielectric_shadow_transmittance(b.t.d, cos);
            return all(shadow_carried == vec3<f32>(0.0));
        }
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
    // #if THIN_WALLED
    shadow_carried = carried;
    shadow_direction = dir;
    shadow_query = true;
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

// #if HAS_POINT_LIGHTS
// furnace_scene::PointLight::intensity_towards: the intensity sent along unit `direction` (from
// the light) to a point at `distance`, the spot cone and the range window applied.
fn point_light_intensity(light: PointLight, direction: vec3<f32>, distance: f32) -> vec3<f32> {
    var k = 1.0;
    if (light.flags & POINT_LIGHT_SPOT) != 0u {
        let cos = dot(direction, light.spot_direction);
        let t = clamp((cos - light.cos_outer) / (light.cos_inner - light.cos_outer), 0.0, 1.0);
        k = t * t;
    }
    if (light.flags & POINT_LIGHT_RANGE) != 0u {
        let r = distance / light.range;
        k *= clamp(1.0 - (r * r) * (r * r), 0.0, 1.0);
    }
    return light.intensity * k;
}

// furnace-cpu's gathering of the point and spot lights at a scattering event: what they add to
// the path's radiance (throughput included); with QUEUED_POINT_LIGHTS nothing here, their
// shadow rays queued with what each adds. With ONE_POINT_LIGHT one light, chosen by power with
// the event's dimension furnace_render::layout::point_light, its share divided by the choice's
// probability; else every light.
fn gather_point_lights(pixel: u32, index: u32, event: u32, throughput: vec3<f32>, bsdf: HitBsdf,
                       wo: vec3<f32>, frame: Frame, surface: SceneSurfacePoint,
                       leave: vec3<f32>) -> vec3<f32> {
    // #if ONE_POINT_LIGHT
    let dim = 4u * (params.bounces + 1u) + LIGHT_DIMS_PER_EVENT * params.bounces + event;
    let choice = choose_point_light(sampler_value(params.sampler, pixel, index, dim));
    if !(choice.pmf > 0.0) {
        return vec3<f32>(0.0);
    }
    return point_light_share(point_lights[choice.index], throughput / choice.pmf, bsdf, wo, frame,
                             surface, leave);
    // #else
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < params.point_light_count; i++) {
        sum += point_light_share(point_lights[i], throughput, bsdf, wo, frame, surface, leave);
    }
    return sum;
    // #endif
}

// #if ONE_POINT_LIGHT
struct PointLightChoice {
    index: u32,
    pmf: f32,
}

// furnace_scene::PointLightDistribution::sample: the first light with u < its cdf (bisection,
// the same comparisons), and its probability (0 where no light has power: every cdf is 0).
fn choose_point_light(u: f32) -> PointLightChoice {
    var lo = 0u;
    var hi = params.point_light_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < point_lights[mid].choice_cdf {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return PointLightChoice(lo, point_lights[lo].choice_pmf);
}
// #endif

// CpuRenderer::point_light: what `light` adds (`throughput` included) if its shadow ray, queued
// (QUEUED_POINT_LIGHTS) or traced here, is not blocked. A light on the surface (d → 0) would add
// ∞: it adds nothing instead.
fn point_light_share(light: PointLight, throughput: vec3<f32>, bsdf: HitBsdf, wo: vec3<f32>,
                     frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) -> vec3<f32> {
    let to_light = light.position - surface.position;
    let d2 = dot(to_light, to_light);
    if !(d2 > 0.0) {
        return vec3<f32>(0.0);
    }
    let d = sqrt(d2);
    let wi = to_light / d;
    let o = shadow_origin(bsdf, surface, leave, wi);
    if o.w != 0.0 {
        let li = point_light_intensity(light, -wi, d);
        if any(li != vec3<f32>(0.0)) {
            let f = hit_eval(bsdf, wo, frame_to_local(frame, wi));
            let contribution = throughput * f * li / d2;
            if any(f != vec3<f32>(0.0)) && film_is_finite(contribution) {
                // #if QUEUED_POINT_LIGHTS
                defer_shadow(bsdf, o.xyz, wi, d * (1.0 - SHADOW_EPSILON), contribution);
                // #else
                return contribution * shadow(bsdf, o.xyz, wi, d * (1.0 - SHADOW_EPSILON));
                // #endif
            }
        }
    }
    return vec3<f32>(0.0);
}
// #endif

// #if SAMPLES_LIGHTS
// furnace_render::power_heuristic: a² / (a² + b²) as 1 / (1 + (b/a)²); 0 for a <= 0 or NaN.
fn power_heuristic(a: f32, b: f32) -> f32 {
    if !(a > 0.0) {
        return 0.0;
    }
    let r = b / a;
    let w = 1.0 / (1.0 + r * r);
    if w != w {
        return 0.0;
    }
    return w;
}

// LightSampling::light_weight (FRAME_NO_LIGHT_SAMPLES never reaches here).
fn light_weight(light: f32, bsdf: f32) -> f32 {
    if (params.flags & FRAME_NO_BSDF_LIGHT) != 0u {
        return 1.0;
    }
    return power_heuristic(light, bsdf);
}

// LightSampling::bsdf_weight.
fn bsdf_weight(bsdf: f32, light: f32) -> f32 {
    if (params.flags & FRAME_NO_LIGHT_SAMPLES) != 0u {
        return 1.0;
    }
    if (params.flags & FRAME_NO_BSDF_LIGHT) != 0u {
        return 0.0;
    }
    return power_heuristic(bsdf, light);
}

// #endif

// #if HAS_EMITTERS
// furnace_scene::triangle_area.
fn triangle_area(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> f32 {
    let c = scene_cross(v1 - v0, v2 - v0);
    return 0.5 * sqrt(scene_dot(c, c));
}

// #if !LIGHT_BVH
// Emitters::selection_pdf: the probability of choosing a triangle of `material` and `area`.
fn emitter_selection_pdf(material: u32, area: f32) -> f32 {
    let w = bitcast<f32>(emitters[3u * params.emitter_count + material]);
    return w * area / params.emitter_total;
}

// Emitters::select: the alias table's item for the bin-choosing bits and the coin.
fn emitter_select(bits: u32, coin: f32) -> u32 {
    let bin = smp_mul_hi(bits, params.emitter_count);
    var item = bin;
    if !(coin < bitcast<f32>(emitters[3u * bin + 2u])) {
        item = emitters[3u * bin + 1u];
    }
    return emitters[3u * item];
}
// #else
// Emitters::index_of: the emitter whose triangle is `triangle` (a binary search of the ordered
// triangles), or 0xffffffff.
fn emitter_index_of(triangle: u32) -> u32 {
    var lo = 0u;
    var hi = params.emitter_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].x < triangle {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < params.emitter_count && emitters[lo].x == triangle {
        return lo;
    }
    return 0xffffffffu;
}
// #endif

// CpuRenderer::sample_emitter: one light sample of an emissive triangle (throughput included).
// TriangleSampling::solid_angle: the solid angle of the triangle a, b, c (relative to the
// shading point) when it is sampled by solid angle from there, else −1 (sampled by area).
fn triangle_solid_angle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    // #if !SOLID_ANGLE_TRIANGLES
    return -1.0;
    // #else
    let omega = spherical_triangle_solid_angle(a, b, c);
    if omega >= SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE && omega <= SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE {
        return omega;
    }
    return -1.0;
    // #endif
}

fn sample_emitter(pixel: u32, index: u32, event: u32, throughput: vec3<f32>, bsdf: HitBsdf,
                  wo: vec3<f32>, frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) {
    let dim = 4u * (params.bounces + 1u) + LIGHT_DIMS_PER_EVENT * event;
    // The bin's bits and the coin: one pair (LIGHT_EMITTER_COIN = LIGHT_EMITTER_BIN + 1).
    let bin_coin = sampler_bits_2d(params.sampler, pixel, index, dim + LIGHT_EMITTER_BIN);
    // #if LIGHT_BVH
    // The light BVH descends by the bits alone; its nodes follow the emitters' records.
    let choice = light_bvh_sample(params.emitter_count, leave, receiver_normal(bsdf, surface),
                                  to_unit_f32(bin_coin.x));
    if !(choice.pmf > 0.0) {
        return;
    }
    let t = emitters[choice.item].x;
    // #else
    let t = emitter_select(bin_coin.x, to_unit_f32(bin_coin.y));
    // #endif
    let tri = scene_triangles[t];
    let v0 = scene_vertices[tri.i0].position;
    let v1 = scene_vertices[tri.i1].position;
    let v2 = scene_vertices[tri.i2].position;
    // Seen from the offset origin the shadow ray starts at (CpuRenderer::sample_emitter); a
    // point behind the one-sided emitter's plane sees none of it.
    let a = v0 - leave;
    let b_rel = v1 - leave;
    let c = v2 - leave;
    if !(scene_dot(a, scene_cross(v1 - v0, v2 - v0)) < 0.0) {
        return;
    }
    let u = sampler_value_2d(params.sampler, pixel, index, dim + LIGHT_EMITTER_POINT);
    let omega = triangle_solid_angle(a, b_rel, c);
    var b: vec2<f32>;
    if omega > 0.0 {
        let st = warp_spherical_triangle(u, a, b_rel, c, omega);
        if !st.valid {
            return;
        }
        b = st.bary;
    } else {
        b = warp_uniform_triangle(u);
    }
    let y = scene_interpolate3(v0, v1, v2, b.x, b.y);
    let to_light = y - leave;
    let d2 = scene_dot(to_light, to_light);
    if !(d2 > 0.0) {
        return;
    }
    let d = sqrt(d2);
    let wi = to_light / d;
    let cos_light = -scene_dot(scene_geometric_normal(v0, v1, v2), wi);
    let o = shadow_origin(bsdf, surface, leave, wi);
    if !(cos_light > 0.0 && o.w != 0.0) {
        return;
    }
    if (params.flags & FRAME_ANY_MASKED) != 0u && !scene_alpha_passes(t, b.x, b.y) {
        return;
    }
    let material = scene_triangle_material(t);
    var uv = vec2<f32>(0.0);
    if scene_material_is_textured(material) {
        uv = scene_uv(t, b.x, b.y);
    }
    let emission = scene_material_evaluate(material, uv).emission;
    let wi_local = frame_to_local(frame, wi);
    let f = hit_eval(bsdf, wo, wi_local);
    if all(emission == vec3<f32>(0.0)) || all(f == vec3<f32>(0.0)) {
        return;
    }
    let area = triangle_area(v0, v1, v2);
    // #if LIGHT_BVH
    let selection = choice.pmf;
    // #else
    let selection = emitter_selection_pdf(material, area);
    // #endif
    var pdf: f32;
    if omega > 0.0 {
        pdf = selection / omega;
    } else {
        pdf = selection * d2 / (area * cos_light);
    }
    let w = light_weight(pdf, hit_pdf(bsdf, wo, wi_local));
    let contribution = throughput * f * emission * (w / pdf);
    if !(film_is_finite(contribution) && any(contribution != vec3<f32>(0.0))) {
        return;
    }
    defer_shadow(bsdf, o.xyz, wi, d * (1.0 - SHADOW_EPSILON), contribution);
}

// CpuRenderer::emission_weight: the MIS weight of emission reached by a BSDF sample of pdf
// `bsdf_pdf_value` (< 0: a camera ray) from `origin` (whose receiving side was `normal`), at
// distance `t` on the front of `triangle`.
fn emission_weight(bsdf_pdf_value: f32, origin: vec3<f32>, normal: vec3<f32>, material: u32,
                   triangle: u32, t: f32, cos_light: f32) -> f32 {
    if bsdf_pdf_value < 0.0 {
        return 1.0;
    }
    let tri = scene_triangles[triangle];
    let v0 = scene_vertices[tri.i0].position;
    let v1 = scene_vertices[tri.i1].position;
    let v2 = scene_vertices[tri.i2].position;
    let area = triangle_area(v0, v1, v2);
    // #if LIGHT_BVH
    var selection = 0.0;
    let item = emitter_index_of(triangle);
    if item != 0xffffffffu {
        selection = light_bvh_pmf(params.emitter_count, emitters[item].yz, origin, normal);
    }
    // #else
    let selection = emitter_selection_pdf(material, area);
    // #endif
    if !(selection > 0.0) {
        return 1.0;
    }
    let omega = triangle_solid_angle(v0 - origin, v1 - origin, v2 - origin);
    var light: f32;
    if omega > 0.0 {
        light = selection / omega;
    } else {
        light = selection * (t * t) / (area * cos_light);
    }
    return bsdf_weight(bsdf_pdf_value, light);
}

// #endif

// #if HAS_SUN_DISC
// CpuRenderer::sample_sun_discs for the one sun: a direction uniform in its cone, a shadow ray.
fn sample_sun_disc(pixel: u32, index: u32, event: u32, throughput: vec3<f32>, bsdf: HitBsdf,
                   wo: vec3<f32>, frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) {
    let dim = 4u * (params.bounces + 1u) + LIGHT_DIMS_PER_EVENT * event + LIGHT_SUN_DISC;
    let u = sampler_value_2d(params.sampler, pixel, index, dim);
    let t = params.sun_direction.w;
    let wi = frame_to_world(frame_new(-params.sun_direction.xyz), warp_uniform_cone(u, t));
    let o = shadow_origin(bsdf, surface, leave, wi);
    if o.w == 0.0 {
        return;
    }
    let wi_local = frame_to_local(frame, wi);
    let f = hit_eval(bsdf, wo, wi_local);
    if all(f == vec3<f32>(0.0)) {
        return;
    }
    let w = light_weight(uniform_cone_pdf(t), hit_pdf(bsdf, wo, wi_local));
    // Sun::cone_estimate: E · 2 / (2 − t).
    let estimate = params.sun_irradiance.xyz * (2.0 / (2.0 - t));
    let contribution = throughput * f * estimate * w;
    if all(contribution == vec3<f32>(0.0)) {
        return;
    }
    defer_shadow(bsdf, o.xyz, wi, bitcast<f32>(0x7f800000u), contribution);
}

// CpuRenderer::sun_discs_seen for the one sun: its radiance along an escaping ray.
fn sun_disc_seen(direction: vec3<f32>, bsdf_pdf_value: f32) -> vec3<f32> {
    let t = params.sun_direction.w;
    if !in_cone(direction, -params.sun_direction.xyz, t) {
        return vec3<f32>(0.0);
    }
    var w = 1.0;
    if bsdf_pdf_value >= 0.0 {
        w = bsdf_weight(bsdf_pdf_value, uniform_cone_pdf(t));
    }
    return (params.sun_irradiance.xyz * params.sun_irradiance.w) * w;
}

// #endif

// #if HAS_ENVIRONMENT
// The environment of this frame (FrameParams' env_* fields).
fn frame_env() -> EnvMap {
    return EnvMap(params.env_width, params.env_height, params.env_intensity, params.env_cos, params.env_sin);
}

// #if SAMPLES_ENVIRONMENT
// CpuRenderer::sample_environment: one light sample of the environment map (throughput
// included): a direction from its importance distribution, a shadow ray to infinity.
fn sample_environment(pixel: u32, index: u32, event: u32, throughput: vec3<f32>, bsdf: HitBsdf,
                      wo: vec3<f32>, frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) {
    let dim = 4u * (params.bounces + 1u) + LIGHT_DIMS_PER_EVENT * event + LIGHT_ENVIRONMENT;
    let u = sampler_value_2d(params.sampler, pixel, index, dim);
    let s = env_sample(frame_env(), u);
    let o = shadow_origin(bsdf, surface, leave, s.direction);
    if !(s.pdf > 0.0) || o.w == 0.0 || all(s.radiance == vec3<f32>(0.0)) {
        return;
    }
    let wi_local = frame_to_local(frame, s.direction);
    let f = hit_eval(bsdf, wo, wi_local);
    if all(f == vec3<f32>(0.0)) {
        return;
    }
    let w = light_weight(s.pdf, hit_pdf(bsdf, wo, wi_local));
    let contribution = throughput * f * s.radiance * (w / s.pdf);
    if !(film_is_finite(contribution) && any(contribution != vec3<f32>(0.0))) {
        return;
    }
    defer_shadow(bsdf, o.xyz, s.direction, bitcast<f32>(0x7f800000u), contribution);
}
// #endif
// #endif

// #if AOVS
// What the current sample's camera ray hit first (furnace_render::AovSample), as the two vectors
// of its sums (AovSum's layout): albedo and depth, shading normal and hit (1, or 0 for a miss).
var<private> aov_albedo_depth: vec4<f32>;
var<private> aov_normal_hit: vec4<f32>;
// #endif

// Renderer::trace for `count` samples of `pixel` at (x, y) from sample `first` on, each a camera
// ray jittered inside the pixel: with `to_film`, each sample is added to the film as it ends
// (in index order); the last sample's value is returned. The samples run in one loop: a lane
// whose path ends starts its next sample in the next iteration instead of waiting for the
// warp's other paths to end (path regeneration), and no two copies of the path's code are
// composed.
fn trace_samples(x: u32, y: u32, pixel: u32, first: u32, count: u32, to_film: bool) -> vec3<f32> {
    var index = first;
    var started = 0u;
    // The path's state, set where each sample starts (zero until then: an invocation with no
    // samples returns a zero radiance).
    var origin: vec3<f32>;
    var direction: vec3<f32>;
    var radiance: vec3<f32>;
    var throughput: vec3<f32>;
    var event: u32;
    // #if SAMPLES_LIGHTS
    // The pdf of the BSDF sample that made the ray (−1: the camera's or a delta event's), for
    // MIS weights.
    var ray_pdf: f32;
    // #endif
    // #if HAS_EMITTERS
    // The receiving side (geometric normal) of the vertex the ray left, for the light BVH.
    var normal: vec3<f32>;
    // #endif
    // #if TRANSMISSION
    // Where that vertex took its light samples (when the ray has since crossed a surface).
    var mis_origin: vec3<f32>;
    var mis_moved: bool;
    // The absorption coefficient of the volume the ray travels in (0: air), and the surface
    // point the ray left (its offset origin would shorten the path by the offset).
    var medium: vec3<f32>;
    var left_from: vec3<f32>;
    // Passes through sheets since the last event, and the lobe number they left (< 0: none).
    var passes: u32;
    var carried_uc: f32;
    // #endif
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
        var query_origin = origin;
        var query_dir = direction;
        var query_t = inf;
        let shadowing = shadow_next < shadow_runs;
        let queued = shadow_next < shadow_queued;
        if shadowing {
            if queued {
                let q = shadow_rays[shadow_next];
                query_origin = q.origin;
                query_dir = q.dir;
                query_t = q.t_max;
                // #if THIN_WALLED
                shadow_carried = q.value;
                shadow_direction = q.dir;
                shadow_query = true;
                // #endif
            } else {
                // An empty iteration: t_max 0 traces nothing.
                query_t = 0.0;
            }
        } else if !alive {
            // The sample ended (or none started yet): add it, start the next one.
            if started > 0u && to_film {
                film_add_sample(pixel, clamp_sample(radiance));
            }
            if started == count {
                break;
            }
            index = first + started;
            started += 1u;
            let u = sampler_value_2d(params.sampler, pixel, index, DIM_PIXEL);
            let ray = camera_ray(vec2<f32>(f32(x) + u.x, f32(y) + u.y));
            origin = ray.origin;
            direction = ray.direction;
            radiance = vec3<f32>(0.0);
            throughput = vec3<f32>(1.0);
            event = 0u;
            // #if SAMPLES_LIGHTS
            ray_pdf = -1.0;
            // #endif
            // #if HAS_EMITTERS
            normal = vec3<f32>(0.0);
            // #endif
            // #if TRANSMISSION
            mis_origin = vec3<f32>(0.0);
            mis_moved = false;
            medium = vec3<f32>(0.0);
            left_from = ray.origin;
            passes = 0u;
            carried_uc = -1.0;
            // #endif
            // #if AOVS
            // AovSample::MISS: albedo 1, no normal, no depth.
            aov_albedo_depth = vec4<f32>(1.0, 1.0, 1.0, 0.0);
            aov_normal_hit = vec4<f32>(0.0);
            // #endif
            alive = true;
            query_origin = origin;
            query_dir = direction;
        }
        // #if TRACE_COUNTERS
        rays_traced += select(0u, 1u, query_t > 0.0);
        // #endif
        let hit = trace_query(query_origin, query_dir, query_t, shadowing);
        if shadowing {
            if queued {
                var carried = shadow_rays[shadow_next].value;
                // #if THIN_WALLED
                shadow_query = false;
                carried = shadow_carried;
                // #endif
                if !hit.hit {
                    radiance += carried;
                }
            }
            shadow_next += 1u;
            continue;
        }
        shadow_queued = 0u;
        shadow_next = 0u;
        shadow_runs = SHADOW_KINDS;
        if !hit.hit {
            // #if TRANSMISSION
            if any(medium != vec3<f32>(0.0)) {
                throughput *= absorption(medium, inf);
            }
            // #endif
            // The ray leaves the scene: the sky and what else is at infinity.
            radiance += throughput * params.sky.xyz;
            // #if HAS_ENVIRONMENT
            // CpuRenderer::environment_seen: a camera ray (no event yet) sees it only if visible;
            // a BSDF ray is weighted against the environment's light samples.
            if event > 0u || (params.env_flags & ENV_VISIBLE) != 0u {
                var w = 1.0;
                // #if SAMPLES_ENVIRONMENT
                if ray_pdf >= 0.0 {
                    w = bsdf_weight(ray_pdf, env_pdf(frame_env(), direction));
                }
                // #endif
                if w != 0.0 {
                    radiance += throughput * (env_radiance(frame_env(), direction) * w);
                }
            }
            // #endif
            // #if HAS_SUN_DISC
            radiance += throughput * sun_disc_seen(direction, ray_pdf);
            // #endif
            alive = false;
            continue;
        }
        let material = scene_triangle_material(hit.triangle);
        var uv = vec2<f32>(0.0);
        if scene_material_is_textured(material) {
            uv = scene_uv(hit.triangle, hit.u, hit.v);
        }
        let ms = scene_material_evaluate(material, uv);
        let surface = scene_surface_point(hit.triangle, hit.u, hit.v, uv, direction);
        // #if AOVS
        if event == 0u {
            // The back of a single-sided surface (black) has no shading normal.
            let n = select(vec3<f32>(0.0), surface.shading, surface.valid != 0u);
            // The front of an emitter: its colour is its light, like the sky's (albedo 1).
            let emits = any(ms.emission != vec3<f32>(0.0)) && surface.valid != 0u && surface.back_face == 0u;
            aov_albedo_depth = vec4<f32>(select(ms.base_color, vec3<f32>(1.0), emits), hit.t);
            aov_normal_hit = vec4<f32>(n, 1.0);
        }
        // #endif
        if surface.valid == 0u {
            // The back of a single-sided surface: black.
            alive = false;
            continue;
        }
        // #if TRANSMISSION
        if any(medium != vec3<f32>(0.0)) {
            // Beer–Lambert over the segment inside the volume, surface to surface.
            throughput *= absorption(medium, length(surface.position - left_from));
        }
        // #endif
        // Emission is one-sided: the back of a double-sided emitter does not emit.
        if surface.back_face == 0u {
            // #if HAS_EMITTERS
            if any(ms.emission != vec3<f32>(0.0)) {
                let cos_light = -scene_dot(surface.geometric, direction);
                var mis_from = origin;
                var distance = hit.t;
                // #if TRANSMISSION
                if mis_moved {
                    mis_from = mis_origin;
                    distance = length(surface.position - mis_origin);
                }
                // #endif
                let w = emission_weight(ray_pdf, mis_from, normal, material, hit.triangle, distance, cos_light);
                radiance += throughput * ms.emission * w;
            }
            // #else
            radiance += throughput * ms.emission;
            // #endif
        }
        let last = event == params.bounces;
        // #if !TRANSMISSION
        if last {
            alive = false;
            continue;
        }
        // #endif
        var bsdf = hit_bsdf(ms, material, uv);
        var shading = surface.shading;
        var delta = false;
        // #if TRANSMISSION
        let volume = (bsdf.kind & SCENE_VOLUME) != 0u;
        let straight = bsdf.kind != 0u && dielectric_is_straight(bsdf.t.d);
        if last && !straight {
            alive = false;
            continue;
        }
        // A solid's interface is shaded in its outward frame (wo may be inside).
        if volume && surface.back_face != 0u {
            shading = -shading;
        }
        delta = bsdf.kind != 0u && transmissive_is_delta(bsdf.t);
        // #endif
        let frame = frame_new(shading);
        let wo = frame_to_local(frame, -direction);
        let leave = offset_ray_origin_scaled(surface.position, surface.geometric, params.offset_scale);
        // #if TRANSMISSION
        let behind = offset_ray_origin_scaled(surface.position, -surface.geometric, params.offset_scale);
        bsdf.two_sided = volume && bsdf.t.d.iface == DIELECTRIC_ROUGH;
        bsdf.behind = behind;
        bsdf.medium = medium;
        // #endif

        if !last && !delta {
            // #if HAS_DELTA_SUN
            // The sun, a delta light: gathered by a shadow ray only.
            if (params.flags & FRAME_HAS_SUN) != 0u {
                let to_sun = -params.sun_direction.xyz;
                let o = shadow_origin(bsdf, surface, leave, to_sun);
                if o.w != 0.0 {
                    let f = hit_eval(bsdf, wo, frame_to_local(frame, to_sun));
                    if any(f != vec3<f32>(0.0)) {
                        defer_shadow(bsdf, o.xyz, to_sun, inf, throughput * f * params.sun_irradiance.xyz);
                    }
                }
            }
            // #endif

            // #if HAS_POINT_LIGHTS
            // Point and spot lights, delta lights too: a shadow ray to each, or to one chosen by
            // power (composed only for a scene that has them).
            radiance += gather_point_lights(pixel, index, event, throughput, bsdf, wo, frame, surface,
                                            leave);
            // #endif

            // #if SAMPLES_LIGHTS
            // Emitters and the sun disc: one light sample each (next-event estimation).
            if (params.flags & FRAME_NO_LIGHT_SAMPLES) == 0u {
                // #if HAS_EMITTERS
                sample_emitter(pixel, index, event, throughput, bsdf, wo, frame, surface, leave);
                // #endif
                // #if HAS_SUN_DISC
                sample_sun_disc(pixel, index, event, throughput, bsdf, wo, frame, surface, leave);
                // #endif
                // #if SAMPLES_ENVIRONMENT
                sample_environment(pixel, index, event, throughput, bsdf, wo, frame, surface, leave);
                // #endif
            }
            // #endif
        }

        // Continue the path by sampling the BSDF.
        let dim = DIM_FIRST_BOUNCE + DIMS_PER_BOUNCE * event;
        let u = sampler_value_2d(params.sampler, pixel, index, dim + BOUNCE_BSDF_DIRECTION);
        var uc: f32;
        // #if TRANSMISSION
        if carried_uc >= 0.0 {
            uc = carried_uc;
        } else {
            uc = sampler_value(params.sampler, pixel, index, dim + BOUNCE_BSDF_LOBE);
        }
        var s: ScatterSample;
        if bsdf.kind != 0u {
            s = transmissive_sample(bsdf.t, wo, uc, u);
        } else {
            let o = bsdf_sample(bsdf.m, wo, uc, u);
            s = ScatterSample(o.wi, o.pdf, o.weight, 0.0, false, false, o.lobe != BSDF_LOBE_NONE);
        }
        if !s.valid {
            alive = false;
            continue;
        }
        let wi = frame_to_world(frame, s.wi);
        // Reflections leave on the side the ray came from, transmissions on the other (at a
        // solid's interface, whichever side the ray points to).
        let side = dot(wi, surface.geometric);
        let crosses = select(s.transmitted, side < 0.0, volume);
        if !select(side > 0.0, side < 0.0, crosses) {
            alive = false;
            continue;
        }
        if s.delta && s.transmitted && straight {
            // Straight through a sheet or an invisible interface: no event, the MIS state of the
            // last one kept (a solid's medium changes).
            if volume {
                medium = select(scene_transmission[material].absorption, vec3<f32>(0.0), surface.back_face != 0u);
            }
            passes += 1u;
            if passes > MAX_SHEET_PASSES {
                alive = false;
                continue;
            }
            throughput *= s.weight;
            carried_uc = s.rest;
            if !mis_moved {
                mis_origin = origin;
                mis_moved = true;
            }
            origin = behind;
            left_from = surface.position;
            continue;
        }
        if last {
            alive = false;
            continue;
        }
        throughput *= s.weight;
        // #if SAMPLES_LIGHTS
        ray_pdf = select(s.pdf, -1.0, s.delta);
        // #endif
        passes = 0u;
        carried_uc = -1.0;
        if crosses && volume {
            // Into the solid from outside, or out of it.
            medium = select(scene_transmission[material].absorption, vec3<f32>(0.0), surface.back_face != 0u);
        }
        // #else
        uc = sampler_value(params.sampler, pixel, index, dim + BOUNCE_BSDF_LOBE);
        let s = bsdf_sample(bsdf.m, wo, uc, u);
        if s.lobe == BSDF_LOBE_NONE {
            alive = false;
            continue;
        }
        let wi = frame_to_world(frame, s.wi);
        if !(dot(wi, surface.geometric) > 0.0) {
            // Above the shading normal's horizon but below the surface: the path ends.
            alive = false;
            continue;
        }
        throughput *= s.weight;
        // #if SAMPLES_LIGHTS
        ray_pdf = s.pdf;
        // #endif
        // #endif
        event += 1u;
        if (params.flags & FRAME_RUSSIAN_ROULETTE) != 0u && event >= 3u {
            let survive = russian_roulette_survival(throughput);
            if !(sampler_value(params.sampler, pixel, index, dim + BOUNCE_RUSSIAN_ROULETTE) < survive) {
                alive = false;
                continue;
            }
            throughput /= survive;
        }
        // #if HAS_EMITTERS
        normal = receiver_normal(bsdf, surface);
        // #endif
        // #if TRANSMISSION
        left_from = surface.position;
        if crosses {
            origin = behind;
            mis_origin = leave;
            mis_moved = true;
        } else {
            origin = leave;
            mis_moved = false;
        }
        // #else
        origin = leave;
        // #endif
        direction = wi;
    }
    return radiance;
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

// Invocations of a workgroup (FrameParams.group_samples × pixels of a tile); integrator.rs's
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
