// furnace-gpu: the glTF material's layering, the twin of `furnace-brdf`'s src/layered.rs
// (`HitBsdf`): which lobes a hit has and their weights. Composed after the generated bindings
// and before integrator.wgsl, with the TRANSMISSION (and DIFFUSE_TRANSMISSION, which implies
// it) parts only when a scene has them.

// What a hit's material reads of its vertices (Geometry::attributes): its UV sets and vertex
// colour where the scene has any (the VERTEX_ATTRIBUTES kernels), else nothing, a constant.
fn hit_attributes(material: u32, triangle: u32, b1: f32, b2: f32) -> SceneAttributes {
    // #if VERTEX_ATTRIBUTES
    return scene_hit_attributes(material, triangle, b1, b2);
    // #else
    return scene_attributes_of_uv(vec2<f32>(0.0));
    // #endif
}

// Material::evaluate at a hit. A kernel without VERTEX_ATTRIBUTES has no texture and no vertex
// colour to read, so it evaluates the factors alone and composes no texture code (the same
// values: every lookup would be opaque white).
fn hit_material(material: u32, at: SceneAttributes) -> MaterialSample {
    // #if VERTEX_ATTRIBUTES
    return scene_material_evaluate(material, at);
    // #else
    return scene_material_factors(material);
    // #endif
}

// The BSDF at a hit and what light samples need of it besides (furnace_brdf::HitBsdf and
// furnace-cpu's Vertex): the opaque record, or with TRANSMISSION the transmissive mixture.
struct HitBsdf {
    m: BsdfParams,
    // #if TRANSMISSION
    t: Transmissive,
    // SCENE_TRANSMISSIVE | SCENE_VOLUME bits (0: opaque).
    kind: u32,
    // Light samples may also arrive from behind (a rough solid interface), leaving from `behind`.
    two_sided: bool,
    behind: vec3<f32>,
    // The absorption coefficient of the volume the vertex is in (0: air).
    medium: vec3<f32>,
    // #endif
    // #if DIFFUSE_TRANSMISSION
    // The diffuse transmission lobe's colour (black: none) and whether a ray it transmits
    // enters or leaves a solid (KHR_materials_volume).
    dt: vec3<f32>,
    dt_volume: bool,
    // #endif
    // #if LAYERS
    // The coat and sheen above the material, and whether there are any at this hit.
    l: Layers,
    layered: bool,
    // #endif
}

// #if IRIDESCENCE
// Material::evaluate's film: (iridescenceFactor × texture.r, iridescenceIor, the thickness
// mix(minimum, maximum, texture.g) in nm).
fn hit_film(material: u32, at: SceneAttributes) -> vec3<f32> {
    let r = scene_iridescence[material];
    if !(r.factor > 0.0) { return vec3<f32>(0.0, 1.3, 0.0); }
    // #if VERTEX_ATTRIBUTES
    let factor = r.factor * scene_texture_sample_at(r.texture, at).x;
    var t = 1.0;
    if (r.thickness_texture.flags & SCENE_TEXTURE_PRESENT) != 0u {
        t = scene_texture_sample_at(r.thickness_texture, at).y;
    }
    // #else
    let factor = r.factor;
    let t = 1.0;
    // #endif
    return vec3<f32>(factor, r.ior, r.thickness_minimum * (1.0 - t) + r.thickness_maximum * t);
}
// #endif

// #if SPECULAR_TEXTURES
// Material::evaluate's KHR_materials_specular textures: the factors times specularTexture.a and
// specularColorTexture.rgb.
fn hit_specular(material: u32, at: SceneAttributes, ms: MaterialSample) -> MaterialSample {
    var r = ms;
    let t = scene_specular[material];
    r.specular_factor *= scene_texture_sample_at(t.specular, at).w;
    r.specular_color *= scene_texture_sample_at(t.color, at).xyz;
    return r;
}
// #endif

// #if ANISOTROPY
// KHR_materials_anisotropy at a hit: xyz its direction (Scene::surface_point's `anisotropy`,
// zero where there is none), w its strength (MaterialSample::anisotropy). `normal` is the
// shading normal before a back face's flip: the back of a double-sided surface has the front's
// direction.
fn hit_anisotropy(material: u32, triangle: u32, b1: f32, b2: f32, at: SceneAttributes,
                  normal: vec3<f32>) -> vec4<f32> {
    let r = scene_anisotropy[material];
    // #if VERTEX_ATTRIBUTES
    let texel = scene_texture_sample_at(r.texture, at);
    // #else
    let texel = vec4<f32>(1.0);
    // #endif
    let strength = r.strength * texel.z;
    if r.directed == 0u {
        return vec4<f32>(0.0, 0.0, 0.0, strength);
    }
    // (cos r, sin r), or the texture's 2·rg − 1 rotated by r, in the tangent frame (T, w·N×T).
    var d = vec2<f32>(1.0, 0.0);
    if (r.texture.flags & SCENE_TEXTURE_PRESENT) != 0u {
        d = vec2<f32>(2.0 * texel.x - 1.0, 2.0 * texel.y - 1.0);
    }
    let c = r.cos_rotation;
    let s = r.sin_rotation;
    let e = vec2<f32>(c * d.x - s * d.y, s * d.x + c * d.y);
    let tangent = scene_tangent(triangle, b1, b2);
    let bn = tangent.w * scene_cross(normal, tangent.xyz);
    let dir = e.x * tangent.xyz + e.y * bn;
    return vec4<f32>(scene_normalize_or_zero(dir - normal * scene_dot(normal, dir)), strength);
}

// MetallicRoughness::with_anisotropy on the hit's metallic-roughness records (HitBsdf::new's
// last step for each).
fn hit_with_anisotropy(bsdf: HitBsdf, strength: f32) -> HitBsdf {
    var b = bsdf;
    b.m = bsdf_with_anisotropy(b.m, strength);
    // #if TRANSMISSION
    b.t.opaque = bsdf_with_anisotropy(b.t.opaque, strength);
    // #endif
    return b;
}
// #endif

// `HitBsdf::new`: the material's BSDF at a hit, a transmissive material's interface of index
// `ior` (the material's, or a dispersive solid's index for the path: spectrum.wgsl).
fn hit_bsdf(material_sample: MaterialSample, material: u32, at: SceneAttributes, ior: f32) -> HitBsdf {
    // #if SPECULAR_TEXTURES
    let ms = hit_specular(material, at, material_sample);
    // #else
    let ms = material_sample;
    // #endif
    var b: HitBsdf;
    b.m = bsdf_params(ms.base_color, ms.metallic, ms.roughness, ms.specular_factor, ms.specular_color,
                      params.bsdf_flags);
    // #if IRIDESCENCE
    let film = hit_film(material, at);
    b.m = bsdf_with_film(b.m, ms.base_color, ms.metallic, film.x, film.y, film.z);
    // #endif
    // #if TRANSMISSION
    let tr = scene_transmission[material];
    // #if VERTEX_ATTRIBUTES
    let transmission = tr.transmission_factor * scene_texture_sample_at(tr.transmission_texture, at).x;
    // #else
    let transmission = tr.transmission_factor;
    // #endif
    let metallic = brdf_clamp(ms.metallic, 0.0, 1.0);
    let g = brdf_clamp(transmission, 0.0, 1.0) * (1.0 - metallic);
    // #if DIFFUSE_TRANSMISSION
    let dr = scene_diffuse_transmission[material];
    // #if VERTEX_ATTRIBUTES
    let dt = brdf_sanitize(dr.factor * scene_texture_sample_at(dr.texture, at).w, 0.0, 1.0, 0.0);
    let dt_color = dr.color * scene_texture_sample_at(dr.color_texture, at).xyz;
    // #else
    let dt = brdf_sanitize(dr.factor, 0.0, 1.0, 0.0);
    let dt_color = dr.color;
    // #endif
    if dt > 0.0 {
        // The Lambert base keeps 1 − dt of its albedo; the lobe takes dt of the opaque
        // dielectric's share (1 − m)(1 − T), coloured dtColor.
        b.m.diffuse = b.m.diffuse * (1.0 - dt);
        let dielectric = (1.0 - brdf_sanitize(ms.metallic, 0.0, 1.0, 1.0))
            * (1.0 - brdf_sanitize(transmission, 0.0, 1.0, 0.0));
        b.dt = brdf_clamp_rgb(dt_color, 1.0) * (dielectric * dt);
        b.dt_volume = (tr.flags & SCENE_VOLUME) != 0u;
    }
    // #endif
    if g > 0.0 {
        let rough = brdf_clamp(ms.roughness, 0.0, 1.0);
        var d = dielectric_new(ior, rough * rough, (tr.flags & SCENE_VOLUME) == 0u,
                               brdf_height_correlated(b.m), ms.base_color);
        // #if IRIDESCENCE
        d = dielectric_with_film(d, film.x, film.y, film.z);
        // #endif
        var m_opaque = 0.0;
        if g < 1.0 {
            m_opaque = min(metallic / (1.0 - g), 1.0);
        }
        var opaque = bsdf_params(ms.base_color, m_opaque, ms.roughness, ms.specular_factor, ms.specular_color,
                                 params.bsdf_flags);
        // #if IRIDESCENCE
        opaque = bsdf_with_film(opaque, ms.base_color, m_opaque, film.x, film.y, film.z);
        // #endif
        // #if DIFFUSE_TRANSMISSION
        if dt > 0.0 {
            opaque.diffuse = opaque.diffuse * (1.0 - dt);
        }
        // #endif
        b.t = Transmissive(d, opaque, min(g, 1.0));
        b.kind = tr.flags;
    }
    // #endif
    // #if LAYERS
    b.l = layers_new(material, at);
    b.layered = layers_present(b.l);
    // #endif
    return b;
}

// Core::eval: the material beneath the layers.
fn hit_core_eval(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    // #if TRANSMISSION
    if b.kind != 0u {
        return transmissive_eval(b.t, wo, wi);
    }
    // #endif
    return bsdf_eval(b.m, wo, wi);
}

// Core::pdf.
fn hit_core_pdf(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    // #if TRANSMISSION
    if b.kind != 0u {
        return transmissive_pdf(b.t, wo, wi);
    }
    // #endif
    return bsdf_pdf(b.m, wo, wi);
}

// #if DIFFUSE_TRANSMISSION
// Core::opaque: the opaque metallic-roughness part, whose Fresnel weight the diffuse
// transmission shares.
fn hit_opaque(b: HitBsdf) -> BsdfParams {
    if b.kind != 0u {
        return b.t.opaque;
    }
    return b.m;
}

// HitBsdf::lobe_side: `w` in the frame the diffuse transmission lobe is defined in, mirrored
// where a solid's interface is seen from inside (ωo below its outward frame).
fn hit_dt_side(b: HitBsdf, wo: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    if wo.z < 0.0 && (b.kind & SCENE_VOLUME) != 0u {
        return vec3<f32>(w.x, w.y, -w.z);
    }
    return w;
}

// HitBsdf::transmission_probability: the lobe against the core by their albedo estimates,
// each at least DT_MIN_PROBABILITY.
fn hit_dt_probability(b: HitBsdf, wo: vec3<f32>) -> f32 {
    let t = dt_estimate(b.dt, hit_opaque(b), hit_dt_side(b, wo, wo));
    var q = t / (t + hit_core_estimate(b, wo));
    if !(abs(q) <= BRDF_F32_MAX) {
        q = 0.5;
    }
    return brdf_clamp(q, DT_MIN_PROBABILITY, 1.0 - DT_MIN_PROBABILITY);
}
// #endif

// HitBsdf::material_eval: the core plus its diffuse transmission.
fn hit_material_eval(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let core = hit_core_eval(b, wo, wi);
    // #if DIFFUSE_TRANSMISSION
    if any(b.dt != vec3<f32>(0.0)) {
        return core + dt_eval(b.dt, hit_opaque(b), hit_dt_side(b, wo, wo), hit_dt_side(b, wo, wi));
    }
    // #endif
    return core;
}

// #if DIFFUSE_TRANSMISSION
// HitBsdf::mixture_pdf: (1 − q)·core + q·transmission, q given.
fn hit_dt_mixture_pdf(b: HitBsdf, q: f32, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    return (1.0 - q) * hit_core_pdf(b, wo, wi) + q * dt_pdf(hit_dt_side(b, wo, wo), hit_dt_side(b, wo, wi));
}
// #endif

// HitBsdf::material_pdf: (1 − q)·core + q·transmission, q the lobe's probability.
fn hit_material_pdf(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    // #if DIFFUSE_TRANSMISSION
    if any(b.dt != vec3<f32>(0.0)) {
        return hit_dt_mixture_pdf(b, hit_dt_probability(b, wo), wo, wi);
    }
    // #endif
    return hit_core_pdf(b, wo, wi);
}

// HitBsdf::eval.
fn hit_eval(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let core = hit_material_eval(b, wo, wi);
    // #if LAYERS
    if b.layered {
        return layers_eval(b.l, wo, wi, core);
    }
    // #endif
    return core;
}

// HitBsdf::pdf.
fn hit_pdf(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    // #if LAYERS
    if b.layered {
        let p = layers_probabilities(b.l, wo, hit_material_estimate(b, wo));
        return layers_pdf(b.l, wo, wi, p) + p.z * hit_material_pdf(b, wo, wi);
    }
    // #endif
    return hit_material_pdf(b, wo, wi);
}

// #if TRANSMISSION
// Core::sample in a kernel with transmission: the transmissive mixture, or the opaque
// material's sample as a ScatterSample.
fn hit_core_scatter(b: HitBsdf, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    if b.kind != 0u {
        return transmissive_sample(b.t, wo, uc, u);
    }
    let o = bsdf_sample(b.m, wo, uc, u);
    return ScatterSample(o.wi, o.pdf, o.weight, 0.0, false, false, o.lobe != BSDF_LOBE_NONE);
}

// HitBsdf::material_sample: the diffuse transmission lobe or the core by uc, then the
// mixture's pdf and weight; a delta event of the core keeps its direction with the choice
// divided out.
fn hit_material_scatter(b: HitBsdf, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    // #if DIFFUSE_TRANSMISSION
    if any(b.dt != vec3<f32>(0.0)) {
        let q = hit_dt_probability(b, wo);
        var wi: vec3<f32>;
        if uc < q {
            let d = dt_sample_direction(hit_dt_side(b, wo, wo), u);
            if d.w == 0.0 {
                return scatter_none();
            }
            wi = hit_dt_side(b, wo, d.xyz);
        } else {
            var s = hit_core_scatter(b, wo, dielectric_rescale(uc, q, false), u);
            if !s.valid {
                return s;
            }
            if s.delta {
                s.weight = s.weight / (1.0 - q);
                return s;
            }
            wi = s.wi;
        }
        let pdf = hit_dt_mixture_pdf(b, q, wo, wi);
        if !brdf_positive_finite(pdf) {
            return scatter_none();
        }
        return ScatterSample(wi, pdf, hit_material_eval(b, wo, wi) / pdf, 0.0, false,
                             (wi.z < 0.0) != (wo.z < 0.0), true);
    }
    // #endif
    return hit_core_scatter(b, wo, uc, u);
}
// #endif

// #if LOBE_ESTIMATES
// MetallicRoughness::albedo_estimates, summed: the opaque material's estimate at ωo.
fn hit_opaque_estimate(m: BsdfParams, wo: vec3<f32>) -> f32 {
    let mu = brdf_clamp(wo.z, 0.0, 1.0);
    return brdf_specular_estimate(m, mu) + brdf_luminance(m.diffuse) * brdf_diffuse_scale(m, mu);
}

// Core::albedo_estimate: a transmissive material's dielectric counts 1.
fn hit_core_estimate(b: HitBsdf, wo: vec3<f32>) -> f32 {
    // #if TRANSMISSION
    if b.kind != 0u {
        return b.t.weight + (1.0 - b.t.weight) * hit_opaque_estimate(b.t.opaque, wo);
    }
    // #endif
    return hit_opaque_estimate(b.m, wo);
}

// HitBsdf::material_estimate: the core's plus the diffuse transmission's.
fn hit_material_estimate(b: HitBsdf, wo: vec3<f32>) -> f32 {
    let core = hit_core_estimate(b, wo);
    // #if DIFFUSE_TRANSMISSION
    if any(b.dt != vec3<f32>(0.0)) {
        return core + dt_estimate(b.dt, hit_opaque(b), hit_dt_side(b, wo, wo));
    }
    // #endif
    return core;
}
// #endif

// #if LAYERS

// HitBsdf::sample for an opaque material under its layers: a lobe by uc, then the mixture's
// pdf and eval/pdf.
fn hit_sample_layered(b: HitBsdf, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> BsdfSample {
    let p = layers_probabilities(b.l, wo, hit_material_estimate(b, wo));
    var wi: vec3<f32>;
    var lobe = BSDF_LOBE_SHEEN;
    if uc < p.x + p.y {
        let d = layers_sample_direction(b.l, wo, uc, u, p);
        if !d.valid {
            return brdf_no_sample();
        }
        wi = d.wi;
        lobe = select(BSDF_LOBE_SHEEN, BSDF_LOBE_CLEARCOAT, uc < p.x);
    } else {
        let s = bsdf_sample(b.m, wo, layers_core_uc(uc, p), u);
        if s.lobe == BSDF_LOBE_NONE {
            return brdf_no_sample();
        }
        wi = s.wi;
        lobe = s.lobe;
    }
    let pdf = layers_pdf(b.l, wo, wi, p) + p.z * bsdf_pdf(b.m, wo, wi);
    if !brdf_positive_finite(pdf) {
        return brdf_no_sample();
    }
    return BsdfSample(wi, pdf, hit_eval(b, wo, wi) / pdf, lobe);
}

// #if TRANSMISSION
// HitBsdf::sample under the layers with a transmissive material: a delta event of the material
// keeps its direction, weighted through the layers with the choice of the material divided out.
fn hit_scatter_layered(b: HitBsdf, wo: vec3<f32>, uc: f32, u: vec2<f32>) -> ScatterSample {
    let p = layers_probabilities(b.l, wo, hit_material_estimate(b, wo));
    var wi: vec3<f32>;
    if uc < p.x + p.y {
        let d = layers_sample_direction(b.l, wo, uc, u, p);
        if !d.valid {
            return scatter_none();
        }
        wi = d.wi;
    } else {
        var s = hit_material_scatter(b, wo, layers_core_uc(uc, p), u);
        if !s.valid {
            return s;
        }
        if s.delta {
            s.weight *= layers_below(b.l, wo, s.wi) / p.z;
            return s;
        }
        wi = s.wi;
    }
    let pdf = layers_pdf(b.l, wo, wi, p) + p.z * hit_material_pdf(b, wo, wi);
    if !brdf_positive_finite(pdf) {
        return scatter_none();
    }
    return ScatterSample(wi, pdf, hit_eval(b, wo, wi) / pdf, 0.0, false, wi.z < 0.0, true);
}
// #endif
// #endif
