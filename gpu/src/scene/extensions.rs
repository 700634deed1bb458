//! The per-material records of the material extensions, each in a buffer of its own that a
//! scene without the extension neither fills nor binds: `scene_transmission`
//! (KHR_materials_transmission, _ior, _volume), `scene_layers` (KHR_materials_clearcoat,
//! KHR_materials_sheen), `scene_iridescence` (KHR_materials_iridescence), `scene_specular`
//! (KHR_materials_specular's textures), `scene_diffuse_transmission`
//! (KHR_materials_diffuse_transmission) and `scene_anisotropy` (KHR_materials_anisotropy).

use super::{GpuTextureRef, Kept, TRANSMISSIVE, VOLUME};
use crate::shared::WgslType;
use bytemuck::Zeroable;
use furnace_scene::TextureRef;

crate::gpu_struct! {
    /// A material's transmission (WGSL `SceneTransmission`): KHR_materials_transmission, _ior
    /// and _volume. One per material in `scene_transmission`, bound only for a scene with a
    /// transmissive material. 80 bytes.
    pub struct GpuTransmission as "SceneTransmission" {
        /// `transmissionTexture` (R channel).
        pub transmission_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// σ_a per channel (1/m), `Material::absorption`.
        pub absorption: [f32; 3] => WgslType::VEC3_F32,
        /// `ior`.
        pub ior: f32 => WgslType::F32,
        /// `transmissionFactor`.
        pub transmission_factor: f32 => WgslType::F32,
        /// [`TRANSMISSIVE`], [`VOLUME`].
        pub flags: u32 => WgslType::U32,
        /// KHR_materials_dispersion's `dispersion` = 20/V_d (0: none).
        pub dispersion: f32 => WgslType::F32,
        /// Rust-only zeros up to 80 bytes (WGSL pads by itself).
        pub pad: [u32; 1] => WgslType::PAD,
    }
}

crate::gpu_struct! {
    /// A material's layers (WGSL `SceneLayers`): KHR_materials_clearcoat and
    /// KHR_materials_sheen. One per material in `scene_layers`, bound only for a scene with a
    /// coat or a sheen (zeros for a material without). 272 bytes.
    pub struct GpuLayers as "SceneLayers" {
        /// `clearcoatTexture` (R channel).
        pub clearcoat_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `clearcoatRoughnessTexture` (G channel).
        pub clearcoat_roughness_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `sheenColorTexture` (RGB).
        pub sheen_color_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `sheenRoughnessTexture` (A channel).
        pub sheen_roughness_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `clearcoatNormalTexture` (absent when the scene stores no tangents, as the base's).
        pub clearcoat_normal_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `sheenColorFactor` (black: no sheen).
        pub sheen_color: [f32; 3] => WgslType::VEC3_F32,
        /// `sheenRoughnessFactor`.
        pub sheen_roughness: f32 => WgslType::F32,
        /// `clearcoatFactor` (0: no coat).
        pub clearcoat: f32 => WgslType::F32,
        /// `clearcoatRoughnessFactor`.
        pub clearcoat_roughness: f32 => WgslType::F32,
        /// `clearcoatNormalTexture.scale`.
        pub clearcoat_normal_scale: f32 => WgslType::F32,
        /// Rust-only zeros up to 272 bytes (WGSL pads by itself).
        pub pad: [u32; 1] => WgslType::PAD,
    }
}

crate::gpu_struct! {
    /// A material's thin film (WGSL `SceneIridescence`): KHR_materials_iridescence. One per
    /// material in `scene_iridescence`, bound only for a scene with an iridescent material
    /// (zeros for a material without). 112 bytes.
    pub struct GpuIridescence as "SceneIridescence" {
        /// `iridescenceTexture` (R channel).
        pub texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `iridescenceThicknessTexture` (G channel).
        pub thickness_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `iridescenceFactor` (0: no film).
        pub factor: f32 => WgslType::F32,
        /// `iridescenceIor`.
        pub ior: f32 => WgslType::F32,
        /// `iridescenceThicknessMinimum` (nm).
        pub thickness_minimum: f32 => WgslType::F32,
        /// `iridescenceThicknessMaximum` (nm).
        pub thickness_maximum: f32 => WgslType::F32,
    }
}

crate::gpu_struct! {
    /// A material's KHR_materials_specular textures (WGSL `SceneSpecular`). One per material in
    /// `scene_specular`, bound only for a scene where some material has one (absent slots for a
    /// material without). 96 bytes.
    pub struct GpuSpecularTextures as "SceneSpecular" {
        /// `specularTexture` (A channel).
        pub specular: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `specularColorTexture` (RGB, sRGB).
        pub color: GpuTextureRef => GpuTextureRef::wgsl_type(),
    }
}

crate::gpu_struct! {
    /// A material's diffuse transmission (WGSL `SceneDiffuseTransmission`):
    /// KHR_materials_diffuse_transmission. One per material in `scene_diffuse_transmission`,
    /// bound only for a scene with diffuse transmission (zeros for a material without). 112
    /// bytes.
    pub struct GpuDiffuseTransmission as "SceneDiffuseTransmission" {
        /// `diffuseTransmissionTexture` (A channel).
        pub texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `diffuseTransmissionColorTexture` (RGB, sRGB).
        pub color_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `diffuseTransmissionColorFactor`.
        pub color: [f32; 3] => WgslType::VEC3_F32,
        /// `diffuseTransmissionFactor` (0: none).
        pub factor: f32 => WgslType::F32,
    }
}

const _: () = assert!(size_of::<GpuDiffuseTransmission>() == 112);
crate::gpu_struct! {
    /// A material's anisotropy (WGSL `SceneAnisotropy`): KHR_materials_anisotropy. One per
    /// material in `scene_anisotropy`, bound only for a scene with an anisotropic material
    /// (strength 0 for a material without). 64 bytes.
    pub struct GpuAnisotropy as "SceneAnisotropy" {
        /// `anisotropyTexture` (RG the direction in tangent space, B a factor on the strength).
        pub texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `anisotropyStrength` (0: isotropic).
        pub strength: f32 => WgslType::F32,
        /// `cos(anisotropyRotation)`, by Rust's `sin_cos` (the CPU's own values).
        pub cos_rotation: f32 => WgslType::F32,
        /// `sin(anisotropyRotation)`.
        pub sin_rotation: f32 => WgslType::F32,
        /// 1 where the scene keeps tangents to place the direction by, 0 where it has none
        /// (the CPU's `Geometry::tangent` is then `None`: the lobe keeps the plain frame).
        pub directed: u32 => WgslType::U32,
    }
}

const _: () = assert!(size_of::<GpuLayers>() == 272);
const _: () = assert!(size_of::<GpuAnisotropy>() == 64);
const _: () = assert!(size_of::<GpuSpecularTextures>() == 96);
const _: () = assert!(size_of::<GpuIridescence>() == 112);
const _: () = assert!(size_of::<GpuTransmission>() == 80);

/// A material's transmission record, its texture slot through `texture_ref`.
pub(super) fn transmission_record(
    m: &furnace_scene::Material,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuTransmission {
    GpuTransmission {
        transmission_texture: texture_ref(&m.transmission_texture),
        absorption: m.absorption.to_array(),
        ior: m.ior,
        transmission_factor: m.transmission_factor,
        flags: if m.is_transmissive() { TRANSMISSIVE } else { 0 } | if m.volume { VOLUME } else { 0 },
        dispersion: m.dispersion,
        pad: [0; 1],
    }
}

/// A material's layers record, its texture slots through `texture_ref` (zeros without layers).
pub(super) fn layers_record(
    m: &furnace_scene::Material,
    kept: Kept,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuLayers {
    let mut r = GpuLayers::zeroed();
    if let Some(c) = &m.layers.clearcoat {
        r.clearcoat = c.factor;
        r.clearcoat_roughness = c.roughness;
        r.clearcoat_texture = texture_ref(&c.texture);
        r.clearcoat_roughness_texture = texture_ref(&c.roughness_texture);
        if kept.tangents {
            r.clearcoat_normal_texture = texture_ref(&c.normal_texture);
            r.clearcoat_normal_scale = c.normal_scale;
        }
    }
    if let Some(s) = &m.layers.sheen {
        r.sheen_color = s.color.to_array();
        r.sheen_roughness = s.roughness;
        r.sheen_color_texture = texture_ref(&s.color_texture);
        r.sheen_roughness_texture = texture_ref(&s.roughness_texture);
    }
    r
}

/// A material's iridescence record, its texture slots through `texture_ref` (zeros without a
/// film).
pub(super) fn iridescence_record(
    m: &furnace_scene::Material,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuIridescence {
    let mut r = GpuIridescence::zeroed();
    if let Some(i) = &m.iridescence {
        r.factor = i.factor;
        r.ior = i.ior;
        r.thickness_minimum = i.thickness_minimum;
        r.thickness_maximum = i.thickness_maximum;
        r.texture = texture_ref(&i.texture);
        r.thickness_texture = texture_ref(&i.thickness_texture);
    }
    r
}

/// A material's specular textures record, through `texture_ref`.
pub(super) fn specular_record(
    m: &furnace_scene::Material,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuSpecularTextures {
    GpuSpecularTextures {
        specular: texture_ref(&m.specular_textures.specular),
        color: texture_ref(&m.specular_textures.color),
    }
}

/// A material's diffuse transmission record, its texture slots through `texture_ref` (zeros
/// without it).
pub(super) fn diffuse_transmission_record(
    m: &furnace_scene::Material,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuDiffuseTransmission {
    let mut r = GpuDiffuseTransmission::zeroed();
    if let Some(d) = &m.diffuse_transmission {
        r.texture = texture_ref(&d.texture);
        r.color_texture = texture_ref(&d.color_texture);
        r.color = d.color.to_array();
        r.factor = d.factor;
    }
    r
}

/// A material's anisotropy record, its texture slot through `texture_ref` (zeros without
/// anisotropy).
pub(super) fn anisotropy_record(
    m: &furnace_scene::Material,
    kept: Kept,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuAnisotropy {
    let mut r = GpuAnisotropy::zeroed();
    if let Some(a) = &m.anisotropy {
        let (sin, cos) = a.rotation.sin_cos();
        r.texture = texture_ref(&a.texture);
        r.strength = a.strength;
        r.cos_rotation = cos;
        r.sin_rotation = sin;
        r.directed = u32::from(kept.tangents);
    }
    r
}
