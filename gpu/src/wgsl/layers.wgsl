// furnace-gpu: the layers above the glTF material (KHR_materials_clearcoat, KHR_materials_sheen),
// the twin of `furnace-brdf`'s src/clearcoat.rs, src/sheen.rs and the `Layers` of
// src/layered.rs: `coat + (1 − c·Fc)·(sheen + s·material)`. Composed before layered.wgsl for
// scenes with a coat or a sheen, with the CLEARCOAT and SHEEN parts only where a scene has them.
// The coat's lobe is a BsdfParams record of a white metal of the coat's roughness (F = 1, no
// compensation), evaluated and sampled by the brdf module as the Rust's `GgxSpecular` is.

// The layers at a hit. A coat of factor 0 or a black sheen is absent.
struct Layers {
    // #if CLEARCOAT
    coat: BsdfParams,
    coat_factor: f32,
    // The coat's normal is not the shading normal (its own normal map, or the base's map that
    // the coat does not take): its frame in the shading frame.
    coat_tilted: bool,
    coat_frame: Frame,
    // #endif
    // #if SHEEN
    sheen_color: vec3<f32>,
    sheen_roughness: f32,
    sheen_alpha: f32,
    // #endif
}

// #if CLEARCOAT
// `clearcoat::fresnel`: Schlick with F0 0.04, F90 1 at |cos|.
fn layers_coat_fresnel(cos_o: f32) -> f32 {
    let m = max(1.0 - min(abs(cos_o), 1.0), 0.0);
    let m2 = m * m;
    return 0.04 + 0.96 * (m2 * m2 * m);
}

// ωo·n_c, the cosine the coat's Fresnel weight and albedo estimate take.
fn layers_coat_cos(l: Layers, wo: vec3<f32>) -> f32 {
    if l.coat_tilted {
        return dot(wo, l.coat_frame.z);
    }
    return wo.z;
}

// `Clearcoat::with_normal`: the layers with the coat's normal at `n` (unit, in the shading
// frame).
fn layers_with_coat_normal(l: Layers, n: vec3<f32>) -> Layers {
    var r = l;
    let len2 = dot(n, n);
    if any(n != vec3<f32>(0.0, 0.0, 1.0)) && len2 > 0.0 && brdf_is_finite(len2) {
        r.coat_tilted = true;
        r.coat_frame = frame_new(normalize(n));
    }
    return r;
}

// `Clearcoat::lobe_eval` (D·V·cos θi in the coat's frame), 0 below the base's horizon.
fn layers_coat_lobe_eval(l: Layers, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) {
        return 0.0;
    }
    if l.coat_tilted {
        return bsdf_eval(l.coat, frame_to_local(l.coat_frame, wo), frame_to_local(l.coat_frame, wi)).x;
    }
    return bsdf_eval(l.coat, wo, wi).x;
}

// `Clearcoat::pdf`.
fn layers_coat_pdf(l: Layers, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !(brdf_above(wo) && brdf_above(wi)) {
        return 0.0;
    }
    if l.coat_tilted {
        return bsdf_pdf(l.coat, frame_to_local(l.coat_frame, wo), frame_to_local(l.coat_frame, wi));
    }
    return bsdf_pdf(l.coat, wo, wi);
}

// The clear coat's normal at a hit (Scene::surface_point's `coat`): the interpolated normal
// with the coat's own normal map, turned as the shading normal is.
fn layers_coat_normal(material: u32, triangle: u32, b1: f32, b2: f32, at: SceneAttributes,
                      surface: SceneSurfacePoint) -> vec3<f32> {
    let r = scene_layers[material];
    var base = scene_shading_normal(triangle, b1, b2);
    if all(base == vec3<f32>(0.0)) {
        base = select(surface.geometric, -surface.geometric, surface.back_face != 0u);
    }
    let coat = scene_normal_mapped(triangle, b1, b2, base, r.clearcoat_normal_texture, r.clearcoat_normal_scale, at);
    return select(coat, -coat, surface.back_face != 0u);
}
// #endif

// #if SHEEN
// `sheen::d`: the Charlie distribution.
fn sheen_d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) * (0.5 * BRDF_FRAC_1_PI);
}

// `sheen::l`: the extension's fit of Λ.
fn sheen_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = 21.5473 * (1.0 - t) + 25.3245 * t;
    let b = 3.82987 * (1.0 - t) + 3.32435 * t;
    let c = 0.19823 * (1.0 - t) + 0.16801 * t;
    let d = -1.97760 * (1.0 - t) + -1.27393 * t;
    let e = -4.32054 * (1.0 - t) + -4.85967 * t;
    return a / (1.0 + b * pow(max(x, 0.0), c)) + d * x + e;
}

// `sheen::lambda`.
fn sheen_lambda(cos: f32, alpha: f32) -> f32 {
    let c = abs(cos);
    if c < 0.5 {
        return exp(sheen_l(c, alpha));
    }
    return exp(2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - c, alpha));
}

// `sheen::albedo`: exp of the bilinear lookup of ln E over (√μ, √roughness), the table after
// the Turquin tables in `turquin_table`.
fn sheen_albedo(mu: f32, roughness: f32) -> f32 {
    let n = f32(SHEEN_TABLE_SIZE - 1u);
    let x = sqrt(brdf_clamp(mu, 0.0, 1.0)) * n;
    let y = sqrt(brdf_sanitize(roughness, 0.0, 1.0, 0.0)) * n;
    let i = min(u32(x), SHEEN_TABLE_SIZE - 2u);
    let j = min(u32(y), SHEEN_TABLE_SIZE - 2u);
    let fx = x - f32(i);
    let fy = y - f32(j);
    let r0 = SHEEN_TABLE_OFFSET + j * SHEEN_TABLE_SIZE + i;
    let r1 = r0 + SHEEN_TABLE_SIZE;
    let top = turquin_table[r0] * (1.0 - fx) + turquin_table[r0 + 1u] * fx;
    let bottom = turquin_table[r1] * (1.0 - fx) + turquin_table[r1 + 1u] * fx;
    return exp(top * (1.0 - fy) + bottom * fy);
}

// `Sheen::eval`: sheenColor·D·V·cos θi.
fn sheen_eval(l: Layers, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if !(brdf_above(wo) && brdf_above(wi)) {
        return vec3<f32>(0.0);
    }
    let h = brdf_normalize_or(wo + wi, vec3<f32>(0.0, 0.0, 1.0));
    let den = (1.0 + sheen_lambda(wo.z, l.sheen_alpha) + sheen_lambda(wi.z, l.sheen_alpha)) * 4.0 * wo.z;
    let v = sheen_d(h.z, l.sheen_alpha) / den;
    return l.sheen_color * select(0.0, v, brdf_is_finite(v));
}

// `Sheen::base_scale`: 1 − max(sheenColor)·max(E(μo), E(μi)), not below 0.
fn sheen_base_scale(l: Layers, mu_o: f32, mu_i: f32) -> f32 {
    let e = max(sheen_albedo(abs(mu_o), l.sheen_roughness), sheen_albedo(abs(mu_i), l.sheen_roughness));
    return max(1.0 - brdf_max_element(l.sheen_color) * e, 0.0);
}

// `Sheen::pdf`: uniform over the hemisphere.
fn sheen_pdf(wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return select(0.0, 0.5 * BRDF_FRAC_1_PI, brdf_above(wo) && brdf_above(wi));
}
// #endif

// `HitBsdf::new`'s layers: the material's coat and sheen at the hit (factors × textures).
fn layers_new(material: u32, at: SceneAttributes) -> Layers {
    var l: Layers;
    let r = scene_layers[material];
    // #if CLEARCOAT
    var coat = r.clearcoat;
    var coat_roughness = r.clearcoat_roughness;
    // #if VERTEX_ATTRIBUTES
    coat *= scene_texture_sample_at(r.clearcoat_texture, at).x;
    coat_roughness *= scene_texture_sample_at(r.clearcoat_roughness_texture, at).y;
    // #endif
    l.coat_factor = brdf_sanitize(coat, 0.0, 1.0, 0.0);
    l.coat = bsdf_params(vec3<f32>(1.0), 1.0, brdf_sanitize(coat_roughness, 0.0, 1.0, 0.0), 1.0, vec3<f32>(1.0),
                         params.bsdf_flags & ~BSDF_FLAG_COMPENSATION);
    l.coat_tilted = false;
    // #endif
    // #if SHEEN
    var color = r.sheen_color;
    var roughness = r.sheen_roughness;
    // #if VERTEX_ATTRIBUTES
    color *= scene_texture_sample_at(r.sheen_color_texture, at).xyz;
    roughness *= scene_texture_sample_at(r.sheen_roughness_texture, at).w;
    // #endif
    l.sheen_color = brdf_clamp_rgb(color, 1.0);
    l.sheen_roughness = brdf_sanitize(roughness, 0.0, 1.0, 0.0);
    l.sheen_alpha = max(l.sheen_roughness * l.sheen_roughness, SHEEN_ALPHA_MIN);
    // #endif
    return l;
}

// Whether a hit has any layer (the Rust's `layers.is_some()`).
fn layers_present(l: Layers) -> bool {
    var any = false;
    // #if CLEARCOAT
    any = any || l.coat_factor > 0.0;
    // #endif
    // #if SHEEN
    any = any || brdf_max_element(l.sheen_color) > 0.0;
    // #endif
    return any;
}

// `Layers::coat_rest`: 1 − c·Fc(ωo).
fn layers_coat_rest(l: Layers, wo: vec3<f32>) -> f32 {
    // #if CLEARCOAT
    if l.coat_factor > 0.0 {
        return 1.0 - l.coat_factor * layers_coat_fresnel(layers_coat_cos(l, wo));
    }
    // #endif
    return 1.0;
}

// `Layers::below_weight`: (1 − c·Fc(ωo))·s(μo, μi).
fn layers_below(l: Layers, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    var s = 1.0;
    // #if SHEEN
    if brdf_max_element(l.sheen_color) > 0.0 {
        s = sheen_base_scale(l, wo.z, wi.z);
    }
    // #endif
    return layers_coat_rest(l, wo) * s;
}

// `Layers::eval`: coat + (1 − c·Fc)·(sheen + s·material), given the material's eval `core`.
fn layers_eval(l: Layers, wo: vec3<f32>, wi: vec3<f32>, core: vec3<f32>) -> vec3<f32> {
    var below = core;
    // #if SHEEN
    if brdf_max_element(l.sheen_color) > 0.0 {
        below = core * sheen_base_scale(l, wo.z, wi.z) + sheen_eval(l, wo, wi);
    }
    // #endif
    var f = below * layers_coat_rest(l, wo);
    // #if CLEARCOAT
    if l.coat_factor > 0.0 {
        f += vec3<f32>(l.coat_factor * layers_coat_fresnel(layers_coat_cos(l, wo)) * layers_coat_lobe_eval(l, wo, wi));
    }
    // #endif
    return f;
}

// `Layers::probabilities`: (coat, sheen, material) in proportion to the albedo estimates at ωo,
// each present layer at least LAYER_MIN_PROBABILITY, the material at least that too.
fn layers_probabilities(l: Layers, wo: vec3<f32>, core_estimate: f32) -> vec3<f32> {
    let rest = layers_coat_rest(l, wo);
    var c = 0.0;
    var coat = false;
    // #if CLEARCOAT
    coat = l.coat_factor > 0.0;
    let mu = layers_coat_cos(l, wo);
    if coat && mu > 0.0 {
        c = l.coat_factor * layers_coat_fresnel(mu) * bsdf_e_ss(mu, l.coat.alpha, brdf_height_correlated(l.coat));
    }
    // #endif
    var s = 0.0;
    var scale = 1.0;
    var sheen = false;
    // #if SHEEN
    sheen = brdf_max_element(l.sheen_color) > 0.0;
    if sheen {
        s = rest * (brdf_luminance(l.sheen_color) * sheen_albedo(wo.z, l.sheen_roughness));
        scale = sheen_base_scale(l, wo.z, wo.z);
    }
    // #endif
    let m = rest * scale * core_estimate;
    let total = c + s + m;
    if total > 0.0 && brdf_is_finite(total) {
        c = c / total;
        s = s / total;
    } else {
        c = 0.0;
        s = 0.0;
    }
    c = select(0.0, max(c, LAYER_MIN_PROBABILITY), coat);
    s = select(0.0, max(s, LAYER_MIN_PROBABILITY), sheen);
    let layers = min(c + s, 1.0 - LAYER_MIN_PROBABILITY);
    var k = 0.0;
    if c + s > 0.0 {
        k = layers / (c + s);
    }
    return vec3<f32>(c * k, s * k, 1.0 - layers);
}

// `Layers::pdf`: the layers' part of the mixture pdf.
fn layers_pdf(l: Layers, wo: vec3<f32>, wi: vec3<f32>, p: vec3<f32>) -> f32 {
    var pdf = 0.0;
    // #if CLEARCOAT
    if l.coat_factor > 0.0 {
        pdf += p.x * layers_coat_pdf(l, wo, wi);
    }
    // #endif
    // #if SHEEN
    if brdf_max_element(l.sheen_color) > 0.0 {
        pdf += p.y * sheen_pdf(wo, wi);
    }
    // #endif
    return pdf;
}

// A direction from the coat (uc < p.x) or the sheen (p.x ≤ uc < p.x + p.y); `valid` false when
// the lobe gives none.
struct LayerDirection {
    wi: vec3<f32>,
    valid: bool,
}

fn layers_sample_direction(l: Layers, wo: vec3<f32>, uc: f32, u: vec2<f32>, p: vec3<f32>) -> LayerDirection {
    // #if CLEARCOAT
    if uc < p.x {
        if l.coat_tilted {
            let s = bsdf_sample(l.coat, frame_to_local(l.coat_frame, wo), 0.0, u);
            return LayerDirection(frame_to_world(l.coat_frame, s.wi), s.lobe != BSDF_LOBE_NONE);
        }
        let s = bsdf_sample(l.coat, wo, 0.0, u);
        return LayerDirection(s.wi, s.lobe != BSDF_LOBE_NONE);
    }
    // #endif
    // `Sheen::sample`: uniform over the hemisphere.
    let z = 1.0 - u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = BRDF_TAU * u.y;
    let wi = vec3<f32>(r * cos(phi), r * sin(phi), z);
    return LayerDirection(wi, brdf_above(wo) && brdf_above(wi));
}

// The rest of uc for the material once the layers are passed: (uc − p.x − p.y)/p.z, below 1.
fn layers_core_uc(uc: f32, p: vec3<f32>) -> f32 {
    return min((uc - p.x - p.y) / p.z, LAYER_ONE_BELOW);
}
