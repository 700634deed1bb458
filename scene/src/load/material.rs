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
        // The JSON `source`, not `Texture::source()`, which unwraps a missing one.
        let image = tj.source.value();
        let image = if image < doc.images().len() {
            image as u32
        } else {
            ctx.warn(format!("textures[{}]", t.index()), "no image source: texture ignored");
            NO_IMAGE
        };
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
    if tex_coord != 0 {
        ctx.warn(path, format!("uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is stored: UV0 used"));
    }
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
    let (specular_factor, specular_color_factor) = specular(ctx, m, &p);
    warn_ignored(ctx, m);
    let clamp01 = |x: f32| if x.is_nan() { 1.0 } else { x.clamp(0.0, 1.0) };
    Material {
        name: m.name().map(str::to_string),
        base_color_factor: Vec4::from(pbr.base_color_factor()),
        base_color_texture,
        metallic_factor: clamp01(pbr.metallic_factor()),
        roughness_factor: clamp01(pbr.roughness_factor()),
        metallic_roughness_texture,
        normal_texture,
        normal_scale,
        emissive,
        emissive_texture,
        alpha_mode,
        double_sided: m.double_sided(),
        specular_factor,
        specular_color_factor,
    }
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
        (m.transmission().is_some(), "KHR_materials_transmission"),
        (m.volume().is_some(), "KHR_materials_volume"),
        (m.ior().is_some(), "KHR_materials_ior"),
        (m.unlit(), "KHR_materials_unlit"),
        (m.pbr_specular_glossiness().is_some(), "KHR_materials_pbrSpecularGlossiness"),
    ] {
        if present {
            ctx.warn("", format!("{name} is not supported: ignored"));
        }
    }
}
