// furnace-gpu: the light samples of a scattering event, twins of furnace-cpu's: one function per
// light kind, each composed only for a scene that has that kind (furnace_gpu::wgsl::select), the
// MIS weights between light and BSDF samples, and the path's light-sampling stage that calls them
// (`sample_lights`).
//
// Composed by furnace_gpu::integrator::shader_source after shadow.wgsl (the shadow rays these
// queue or trace) and before integrator.wgsl (the path's state).

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

// CpuRenderer::sample_emitter: one light sample of an emissive triangle (throughput included),
// its shadow ray queued.
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
    var emission = hit_material(material, hit_attributes(material, t, b.x, b.y)).emission;
    // #if BLEND
    // A blended emitter emits in proportion to its coverage (a path ray sees it that often).
    if (scene_materials[material].flags & SCENE_ALPHA_MODE_BITS) == SCENE_ALPHA_BLEND {
        let coverage = scene_blend_coverage(material, t, b.x, b.y);
        if coverage < 1.0 {
            emission *= coverage;
        }
    }
    // #endif
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

// #if HAS_DELTA_SUN
// The sun without a disc, a delta light: gathered by a shadow ray only (CpuRenderer::sun).
fn sample_delta_sun(throughput: vec3<f32>, bsdf: HitBsdf, wo: vec3<f32>, frame: Frame,
                    surface: SceneSurfacePoint, leave: vec3<f32>) {
    if (params.flags & FRAME_HAS_SUN) != 0u {
        let to_sun = -params.sun_direction.xyz;
        let o = shadow_origin(bsdf, surface, leave, to_sun);
        if o.w != 0.0 {
            let f = hit_eval(bsdf, wo, frame_to_local(frame, to_sun));
            if any(f != vec3<f32>(0.0)) {
                defer_shadow(bsdf, o.xyz, to_sun, bitcast<f32>(0x7f800000u), throughput * f * params.sun_irradiance.xyz);
            }
        }
    }
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

// The light-sampling stage of a path at a scattering event that neither ends the path nor is a
// delta event: shadow rays to the delta lights (each point light, or one chosen by power; what
// those traced here add goes to the path's radiance), then one light sample of each light kind
// that is light-sampled (next-event estimation), in furnace-cpu's order.
fn sample_lights(path: ptr<function, Path>, pixel: u32, index: u32, bsdf: HitBsdf, wo: vec3<f32>,
                 frame: Frame, surface: SceneSurfacePoint, leave: vec3<f32>) {
    // #if HAS_DELTA_SUN
    sample_delta_sun(path.throughput, bsdf, wo, frame, surface, leave);
    // #endif
    // #if HAS_POINT_LIGHTS
    path.radiance += gather_point_lights(pixel, index, path.event, path.throughput, bsdf, wo, frame,
                                         surface, leave);
    // #endif
    // #if SAMPLES_LIGHTS
    if (params.flags & FRAME_NO_LIGHT_SAMPLES) == 0u {
        // #if HAS_EMITTERS
        sample_emitter(pixel, index, path.event, path.throughput, bsdf, wo, frame, surface, leave);
        // #endif
        // #if HAS_SUN_DISC
        sample_sun_disc(pixel, index, path.event, path.throughput, bsdf, wo, frame, surface, leave);
        // #endif
        // #if SAMPLES_ENVIRONMENT
        sample_environment(pixel, index, path.event, path.throughput, bsdf, wo, frame, surface, leave);
        // #endif
    }
    // #endif
}
