// furnace-gpu: the glTF material's layering, the twin of `furnace-brdf`'s src/layered.rs
// (`HitBsdf`): which lobes a hit has and their weights. Composed after the generated bindings
// and before integrator.wgsl, with the TRANSMISSION parts only when a scene has them.

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
}

// `HitBsdf::new`: the material's BSDF at a hit.
fn hit_bsdf(ms: MaterialSample, material: u32, at: SceneAttributes) -> HitBsdf {
    var b: HitBsdf;
    b.m = bsdf_params(ms.base_color, ms.metallic, ms.roughness, ms.specular_factor, ms.specular_color,
                      params.bsdf_flags);
    // #if TRANSMISSION
    let tr = scene_transmission[material];
    // #if VERTEX_ATTRIBUTES
    let transmission = tr.transmission_factor * scene_texture_sample_at(tr.transmission_texture, at).x;
    // #else
    let transmission = tr.transmission_factor;
    // #endif
    let metallic = brdf_clamp(ms.metallic, 0.0, 1.0);
    let g = brdf_clamp(transmission, 0.0, 1.0) * (1.0 - metallic);
    if g > 0.0 {
        let rough = brdf_clamp(ms.roughness, 0.0, 1.0);
        let d = dielectric_new(tr.ior, rough * rough, (tr.flags & SCENE_VOLUME) == 0u,
                               brdf_height_correlated(b.m), ms.base_color);
        var m_opaque = 0.0;
        if g < 1.0 {
            m_opaque = min(metallic / (1.0 - g), 1.0);
        }
        let opaque = bsdf_params(ms.base_color, m_opaque, ms.roughness, ms.specular_factor, ms.specular_color,
                                 params.bsdf_flags);
        b.t = Transmissive(d, opaque, min(g, 1.0));
        b.kind = tr.flags;
    }
    // #endif
    return b;
}

// HitBsdf::eval.
fn hit_eval(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    // #if TRANSMISSION
    if b.kind != 0u {
        return transmissive_eval(b.t, wo, wi);
    }
    // #endif
    return bsdf_eval(b.m, wo, wi);
}

// HitBsdf::pdf.
fn hit_pdf(b: HitBsdf, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    // #if TRANSMISSION
    if b.kind != 0u {
        return transmissive_pdf(b.t, wo, wi);
    }
    // #endif
    return bsdf_pdf(b.m, wo, wi);
}
