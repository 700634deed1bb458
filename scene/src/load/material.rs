//! Textures and materials: samplers, texture references (with KHR_texture_transform),
//! metallic-roughness factors and the supported extensions, a warning for each ignored feature.

use super::context::Ctx;
use crate::material::{AlphaMode, Material};
use crate::texture::{ColorSpace, Texture, TextureRef, TextureTransform, WrapMode};
use glam::{Vec2, Vec3, Vec4};

/// Marks a texture whose image is missing.
const NO_IMAGE: u32 = u32::MAX;

/// The textures (glTF `textures`, same indices); one without an image source is kept, marked
/// [`NO_IMAGE`], with a warning.
pub(super) fn read_textures(ctx: &mut Ctx<'_>, doc: &gltf::Document) -> Vec<Texture> {
    let mut textures = Vec::new();
    for (t, tj) in doc.textures().zip(&doc.as_json().textures) {
        // The JSON `source` (not `Texture::source()`, which unwraps a missing one), or the image
        // an image-format extension names.
        let image = super::texture_source::choose(ctx, doc, t.index(), tj).unwrap_or_else(|| {
            ctx.warn(format!("textures[{}]", t.index()), "no image source: texture ignored");
            NO_IMAGE
        });
        let s = t.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        };
        textures.push(Texture { image, wrap_s: wrap(s.wrap_s()), wrap_t: wrap(s.wrap_t()) });
    }
    textures
}

/// The file's materials, then glTF's default material (the last one: primitives without a
/// material use it).
pub(super) fn read_materials(ctx: &mut Ctx<'_>, doc: &gltf::Document) -> Vec<Material> {
    let mut materials: Vec<Material> = doc.materials().map(|m| read_material(ctx, &m)).collect();
    materials.push(Material::default());
    materials
}

fn texture_ref(
    ctx: &mut Ctx<'_>,
    info: Option<gltf::texture::Info<'_>>,
    space: ColorSpace,
    path: String,
) -> Option<TextureRef> {
    let info = info?;
    let transform = info.texture_transform().map(|t| TextureTransform {
        offset: Vec2::from(t.offset()),
        rotation: t.rotation(),
        scale: Vec2::from(t.scale()),
    });
    let tex_coord = info.texture_transform().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
    let tex_coord = if (tex_coord as usize) < crate::MAX_UV_SETS {
        tex_coord
    } else {
        ctx.warn(
            path,
            format!(
                "uses TEXCOORD_{tex_coord}; sets up to TEXCOORD_{} are read: TEXCOORD_0 used",
                crate::MAX_UV_SETS - 1
            ),
        );
        0
    };
    Some(TextureRef { texture: info.texture().index() as u32, tex_coord, color_space: space, transform })
}

fn read_material(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>) -> Material {
    let i = m.index().unwrap_or(0);
    let p = format!("materials[{i}]");
    let pbr = m.pbr_metallic_roughness();
    let base_color_texture = texture_ref(
        ctx,
        pbr.base_color_texture(),
        ColorSpace::Srgb,
        format!("{p}.pbrMetallicRoughness.baseColorTexture"),
    );
    let metallic_roughness_texture = texture_ref(
        ctx,
        pbr.metallic_roughness_texture(),
        ColorSpace::Linear,
        format!("{p}.pbrMetallicRoughness.metallicRoughnessTexture"),
    );
    let (normal_texture, normal_scale) = normal_texture(m);
    let emissive_texture =
        texture_ref(ctx, m.emissive_texture(), ColorSpace::Srgb, format!("{p}.emissiveTexture"));
    let emissive = emissive(ctx, m, &p);
    let alpha_mode = alpha_mode(ctx, m, &p);
    let (specular_factor, mut specular_color_factor) = specular(ctx, m, &p);
    let ior = ior(ctx, m, &p);
    if ior != 1.5 {
        // The opaque BSDF's dielectric F0 is 0.04·specularColor; KHR_materials_ior sets it to
        // ((ior − 1)/(ior + 1))² (1.5 gives 0.04: left exactly as it was).
        let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2);
        specular_color_factor *= f0 / 0.04;
    }
    let transmission = transmission(ctx, m, &p);
    warn_ignored(ctx, m);
    let clamp01 = |x: f32| if x.is_nan() { 1.0 } else { x.clamp(0.0, 1.0) };
    let roughness_factor = clamp01(pbr.roughness_factor());
    let transmissive = transmission.factor > 0.0;
    if transmissive && !transmission.volume && roughness_factor > 0.0 {
        ctx.warn(
            format!("{p}.extensions.KHR_materials_transmission"),
            "rough thin-walled transmission is not supported: the sheet is rendered smooth",
        );
    }
    Material {
        name: m.name().map(str::to_string),
        base_color_factor: Vec4::from(pbr.base_color_factor()),
        base_color_texture,
        metallic_factor: clamp01(pbr.metallic_factor()),
        roughness_factor,
        metallic_roughness_texture,
        normal_texture,
        normal_scale,
        emissive,
        emissive_texture,
        alpha_mode,
        // A solid's surface is one interface whatever doubleSided says (KHR_materials_volume),
        // and a sheet is seen from both sides: transmissive surfaces are two-sided.
        double_sided: m.double_sided() || transmissive,
        specular_factor,
        specular_color_factor,
        transmission_factor: transmission.factor,
        transmission_texture: transmission.texture,
        ior,
        volume: transmissive && transmission.volume,
        absorption: transmission.absorption,
    }
}

/// KHR_materials_ior's `ior` (1.5 without it). glTF allows 0 (meaning "very large", a
/// metal-like Fresnel) and values ≥ 1; others are invalid.
fn ior(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> f32 {
    let Some(ior) = m.ior() else { return 1.5 };
    if ior == 0.0 {
        ctx.warn(format!("{p}.extensions.KHR_materials_ior.ior"), "0 (infinite index) is rendered as 100");
        return 100.0;
    }
    if !(ior.is_finite() && ior >= 1.0) {
        ctx.warn(format!("{p}.extensions.KHR_materials_ior.ior"), format!("{ior} is not ≥ 1: 1.5 used"));
        return 1.5;
    }
    ior.min(100.0)
}

/// What KHR_materials_transmission and KHR_materials_volume say.
struct TransmissionExt {
    factor: f32,
    texture: Option<TextureRef>,
    volume: bool,
    absorption: Vec3,
}

fn transmission(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> TransmissionExt {
    let mut t = TransmissionExt { factor: 0.0, texture: None, volume: false, absorption: Vec3::ZERO };
    if let Some(tr) = m.transmission() {
        let f = tr.transmission_factor();
        t.factor = if f.is_nan() { 0.0 } else { f.clamp(0.0, 1.0) };
        t.texture = texture_ref(
            ctx,
            tr.transmission_texture(),
            ColorSpace::Linear,
            format!("{p}.extensions.KHR_materials_transmission.transmissionTexture"),
        );
    }
    if let Some(v) = m.volume() {
        let path = format!("{p}.extensions.KHR_materials_volume");
        if m.transmission().is_none() {
            ctx.warn(path.clone(), "a volume without KHR_materials_transmission is opaque: ignored");
        }
        t.volume = v.thickness_factor() > 0.0;
        if v.thickness_texture().is_some() {
            ctx.warn(path.clone(), "thicknessTexture ignored (thickness is ray-traced)");
        }
        let d = v.attenuation_distance();
        let c = Vec3::from(v.attenuation_color());
        if !(d > 0.0) || !(c.min_element() >= 0.0) || !c.is_finite() {
            ctx.warn(path, "attenuationDistance must be > 0 and attenuationColor in [0, 1]: no absorption");
        } else if d.is_finite() {
            // σ_a = −ln(c)/d; a black channel absorbs everything (+∞).
            let sigma = |c: f32| {
                if c >= 1.0 {
                    0.0
                } else if c > 0.0 {
                    -c.ln() / d
                } else {
                    f32::INFINITY
                }
            };
            t.absorption = Vec3::new(sigma(c.x), sigma(c.y), sigma(c.z));
        }
    }
    t
}

/// The normal map and its scale (1 without one).
fn normal_texture(m: &gltf::Material<'_>) -> (Option<TextureRef>, f32) {
    match m.normal_texture() {
        Some(n) => {
            let r = TextureRef {
                texture: n.texture().index() as u32,
                tex_coord: n.tex_coord(),
                color_space: ColorSpace::Linear,
                transform: None,
            };
            (Some(r), n.scale())
        }
        None => (None, 1.0),
    }
}

/// The emitted radiance factor: `emissiveFactor` × KHR_materials_emissive_strength.
fn emissive(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> Vec3 {
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emissive = Vec3::from(m.emissive_factor()) * strength;
    if !(emissive.is_finite() && emissive.min_element() >= 0.0) {
        // A NaN or infinite radiance would make NaN pixels; a negative one is not light.
        ctx.warn(
            format!("{p}.emissiveFactor"),
            "negative or non-finite emission (emissiveFactor × emissiveStrength): those channels are 0",
        );
        let clean = |x: f32| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        return Vec3::new(clean(emissive.x), clean(emissive.y), clean(emissive.z));
    }
    if m.emissive_factor().iter().any(|&x| x > 1.0) {
        ctx.warn(
            format!("{p}.emissiveFactor"),
            "exceeds 1 (the spec's limit; use KHR_materials_emissive_strength): used as given",
        );
    }
    emissive
}

fn alpha_mode(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> AlphaMode {
    match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
        gltf::material::AlphaMode::Blend => {
            ctx.warn(format!("{p}.alphaMode"), "BLEND is rendered opaque");
            AlphaMode::Blend
        }
    }
}

/// KHR_materials_specular's factors (its textures are not supported).
fn specular(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>, p: &str) -> (f32, Vec3) {
    match m.specular() {
        Some(s) => {
            if s.specular_texture().is_some() || s.specular_color_texture().is_some() {
                ctx.warn(
                    format!("{p}.extensions.KHR_materials_specular"),
                    "specular textures are not supported: factors only",
                );
            }
            (s.specular_factor(), Vec3::from(s.specular_color_factor()))
        }
        None => (1.0, Vec3::ONE),
    }
}

/// Warns about the occlusion texture and the material extensions furnace ignores.
fn warn_ignored(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>) {
    if m.occlusion_texture().is_some() {
        ctx.warn("", "occlusionTexture ignored (a path tracer computes occlusion)");
    }
    for (present, name) in [
        (m.unlit(), "KHR_materials_unlit"),
        (m.pbr_specular_glossiness().is_some(), "KHR_materials_pbrSpecularGlossiness"),
    ] {
        if present {
            ctx.warn("", format!("{name} is not supported: ignored"));
        }
    }
}
