//! Materials: glTF 2.0 metallic-roughness with KHR_materials_specular,
//! KHR_materials_emissive_strength, KHR_materials_transmission, KHR_materials_ior,
//! KHR_materials_volume, KHR_materials_clearcoat, KHR_materials_sheen and
//! KHR_materials_iridescence and KHR_materials_diffuse_transmission, as factors and texture
//! references. Textures are sampled by
//! [`Material::evaluate`] into the per-shading-point values the integrator feeds to
//! `furnace_brdf::MetallicRoughnessParams`.

use crate::VertexAttributes;
use crate::texture::{Image, Texture, TextureRef};
use glam::{Vec3, Vec4};

/// How alpha is interpreted (glTF `alphaMode`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AlphaMode {
    /// Alpha ignored (glTF's default).
    #[default]
    Opaque,
    /// Alpha-tested: the surface exists where `alpha ≥ cutoff` (glTF default cutoff 0.5).
    Mask {
        /// `alphaCutoff`.
        cutoff: f32,
    },
    /// Alpha-blended, rendered as stochastic transparency: a ray stops at the surface with
    /// probability α (its coverage, [`crate::Scene::coverage`]) and else passes straight on;
    /// a shadow ray carries 1 − α of its light through it.
    Blend,
}

/// A glTF metallic-roughness material. Factor defaults are glTF's.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// `name`, when the file gives one.
    pub name: Option<String>,
    /// `baseColorFactor`, linear RGBA.
    pub base_color_factor: Vec4,
    /// `baseColorTexture` (sRGB).
    pub base_color_texture: Option<TextureRef>,
    /// `metallicFactor`.
    pub metallic_factor: f32,
    /// `roughnessFactor` (perceptual; α = roughness²).
    pub roughness_factor: f32,
    /// `metallicRoughnessTexture` (linear; roughness in G, metallic in B).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// `normalTexture` (linear, tangent space).
    pub normal_texture: Option<TextureRef>,
    /// `normalTexture.scale`.
    pub normal_scale: f32,
    /// `emissiveFactor × KHR_materials_emissive_strength.emissiveStrength` (linear RGB radiance).
    pub emissive: Vec3,
    /// `emissiveTexture` (sRGB), multiplied with [`Material::emissive`].
    pub emissive_texture: Option<TextureRef>,
    /// `alphaMode` and `alphaCutoff`.
    pub alpha_mode: AlphaMode,
    /// `doubleSided`.
    pub double_sided: bool,
    /// KHR_materials_specular `specularFactor` (default 1).
    pub specular_factor: f32,
    /// KHR_materials_specular `specularColorFactor` (default 1; may exceed 1). The loader folds
    /// KHR_materials_ior into it for the opaque BSDF's Fresnel: `F0 = ((ior − 1)/(ior + 1))²`
    /// is `0.04 × specularColor` there.
    pub specular_color_factor: Vec3,
    /// KHR_materials_specular `specularTexture` (linear, A channel) and `specularColorTexture`
    /// (sRGB, RGB), multiplying the two factors. The content hash leaves them out where both
    /// are absent.
    pub specular_textures: SpecularTextures,
    /// KHR_materials_transmission `transmissionFactor` (default 0: opaque).
    pub transmission_factor: f32,
    /// KHR_materials_transmission `transmissionTexture` (linear, R channel).
    pub transmission_texture: Option<TextureRef>,
    /// KHR_materials_ior `ior` (default 1.5): the index of the transmissive solid or sheet.
    pub ior: f32,
    /// KHR_materials_volume: the surface bounds a solid (`thicknessFactor` > 0, a flag only:
    /// distances are ray-traced); otherwise a transmissive (or diffusely transmissive) surface
    /// is thin-walled.
    pub volume: bool,
    /// The volume's absorption coefficient σ_a = −ln(attenuationColor)/attenuationDistance per
    /// channel, in 1/m (0: clear; +∞ where a channel is black).
    pub absorption: Vec3,
    /// KHR_materials_diffuse_transmission (a `diffuseTransmissionFactor` above 0). The content
    /// hash leaves it out where it is `None`, so other files hash as before.
    pub diffuse_transmission: Option<DiffuseTransmissionFactors>,
    /// The layers above the material (KHR_materials_clearcoat, KHR_materials_sheen). The
    /// content hash leaves them out where there are none, so other files hash as before.
    pub layers: MaterialLayers,
    /// KHR_materials_iridescence (an `iridescenceFactor` above 0). The content hash leaves it
    /// out where it is `None`.
    pub iridescence: Option<Iridescence>,
    /// KHR_materials_anisotropy (an `anisotropyStrength` above 0). The content hash leaves it
    /// out where it is `None`.
    pub anisotropy: Option<Anisotropy>,
    /// KHR_materials_dispersion's `dispersion` = 20/V_d (V_d the Abbe number): the index of a
    /// transmissive solid varies with wavelength (`furnace_brdf::spectrum`). 0: none, and 0
    /// wherever it could have no effect (no volume, no transmission, an index of 1). The
    /// content hash leaves it out where it is 0.
    pub dispersion: f32,
    /// KHR_materials_unlit: the surface shows its base colour (× texture × vertex colour) as
    /// is, to every ray and from either side, reflects nothing and is not a light source (the
    /// loader leaves it no emission, transmission or normal map). Kept last: the content hash
    /// leaves it out where it is false, so other files hash as before.
    pub unlit: bool,
}

impl Default for Material {
    /// glTF's default material: white, metallic 1, roughness 1, single-sided.
    fn default() -> Self {
        Self {
            name: None,
            base_color_factor: Vec4::ONE,
            base_color_texture: None,
            metallic_factor: 1.0,
            roughness_factor: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            specular_factor: 1.0,
            specular_color_factor: Vec3::ONE,
            specular_textures: SpecularTextures::default(),
            transmission_factor: 0.0,
            transmission_texture: None,
            ior: 1.5,
            volume: false,
            absorption: Vec3::ZERO,
            diffuse_transmission: None,
            layers: MaterialLayers::default(),
            iridescence: None,
            anisotropy: None,
            dispersion: 0.0,
            unlit: false,
        }
    }
}

/// The layers above a material, each present only where the file gives it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MaterialLayers {
    /// KHR_materials_clearcoat (a `clearcoatFactor` above 0).
    pub clearcoat: Option<ClearcoatLayer>,
    /// KHR_materials_sheen (a `sheenColorFactor` other than black).
    pub sheen: Option<SheenLayer>,
}

impl MaterialLayers {
    /// No layer.
    pub fn is_empty(&self) -> bool {
        self.clearcoat.is_none() && self.sheen.is_none()
    }
}

/// KHR_materials_clearcoat's factors and textures.
#[derive(Debug, Clone, PartialEq)]
pub struct ClearcoatLayer {
    /// `clearcoatFactor`.
    pub factor: f32,
    /// `clearcoatTexture` (linear, R channel).
    pub texture: Option<TextureRef>,
    /// `clearcoatRoughnessFactor` (perceptual).
    pub roughness: f32,
    /// `clearcoatRoughnessTexture` (linear, G channel).
    pub roughness_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture` (linear, tangent space): the coat's own normal map (without
    /// it the coat takes the interpolated normal, not the base's normal map).
    pub normal_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture.scale`.
    pub normal_scale: f32,
}

/// KHR_materials_sheen's factors and textures.
#[derive(Debug, Clone, PartialEq)]
pub struct SheenLayer {
    /// `sheenColorFactor` (linear RGB).
    pub color: Vec3,
    /// `sheenColorTexture` (sRGB, RGB channels).
    pub color_texture: Option<TextureRef>,
    /// `sheenRoughnessFactor`.
    pub roughness: f32,
    /// `sheenRoughnessTexture` (linear, A channel).
    pub roughness_texture: Option<TextureRef>,
}

/// KHR_materials_specular's textures.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpecularTextures {
    /// `specularTexture` (linear, A channel): multiplies `specularFactor`.
    pub specular: Option<TextureRef>,
    /// `specularColorTexture` (sRGB, RGB): multiplies `specularColorFactor`.
    pub color: Option<TextureRef>,
}

impl SpecularTextures {
    /// Neither texture.
    pub fn is_empty(&self) -> bool {
        self.specular.is_none() && self.color.is_none()
    }
}

/// KHR_materials_anisotropy's factors and texture: the base's specular lobe stretched along a
/// direction in the tangent plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Anisotropy {
    /// `anisotropyStrength` in `[0, 1]`: `αt = mix(α, 1, strength²)` along the direction.
    pub strength: f32,
    /// `anisotropyRotation` (radians): the direction's angle from the tangent towards the
    /// bitangent (counter-clockwise in the tangent plane).
    pub rotation: f32,
    /// `anisotropyTexture` (linear): RG the direction in tangent space (`2·rg − 1`, rotated by
    /// `rotation`), B a factor on the strength.
    pub texture: Option<TextureRef>,
}

/// KHR_materials_iridescence's factors and textures: a thin film on the material.
#[derive(Debug, Clone, PartialEq)]
pub struct Iridescence {
    /// `iridescenceFactor`.
    pub factor: f32,
    /// `iridescenceTexture` (linear, R channel).
    pub texture: Option<TextureRef>,
    /// `iridescenceIor`, the film's index of refraction.
    pub ior: f32,
    /// `iridescenceThicknessMinimum` (nm).
    pub thickness_minimum: f32,
    /// `iridescenceThicknessMaximum` (nm).
    pub thickness_maximum: f32,
    /// `iridescenceThicknessTexture` (linear, G channel): the thickness is
    /// `mix(minimum, maximum, g)`; without it, the maximum.
    pub thickness_texture: Option<TextureRef>,
}

/// KHR_materials_diffuse_transmission's factors and textures.
#[derive(Debug, Clone, PartialEq)]
pub struct DiffuseTransmissionFactors {
    /// `diffuseTransmissionFactor`: the share of the diffuse base that is transmitted.
    pub factor: f32,
    /// `diffuseTransmissionTexture` (linear, A channel).
    pub texture: Option<TextureRef>,
    /// `diffuseTransmissionColorFactor` (linear RGB).
    pub color: Vec3,
    /// `diffuseTransmissionColorTexture` (sRGB, RGB channels).
    pub color_texture: Option<TextureRef>,
}

/// A material evaluated at one shading point: every factor multiplied by its texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialSample {
    /// Linear base colour (RGB).
    pub base_color: Vec3,
    /// Alpha (base colour factor × texture alpha × vertex alpha).
    pub alpha: f32,
    /// `metallicFactor × texture.b`.
    pub metallic: f32,
    /// `roughnessFactor × texture.g`.
    pub roughness: f32,
    /// Emitted radiance, linear RGB.
    pub emission: Vec3,
    /// KHR_materials_specular `specularFactor`.
    pub specular_factor: f32,
    /// KHR_materials_specular `specularColorFactor`.
    pub specular_color: Vec3,
    /// `transmissionFactor × texture.r`: the share of the dielectric part that is transmissive.
    pub transmission: f32,
    /// `clearcoatFactor × texture.r` (0 without a coat).
    pub clearcoat: f32,
    /// `clearcoatRoughnessFactor × texture.g`.
    pub clearcoat_roughness: f32,
    /// `sheenColorFactor × texture.rgb` (black without a sheen).
    pub sheen_color: Vec3,
    /// `sheenRoughnessFactor × texture.a`.
    pub sheen_roughness: f32,
    /// `iridescenceFactor × texture.r` (0 without a film).
    pub iridescence: f32,
    /// `iridescenceIor`.
    pub iridescence_ior: f32,
    /// The film's thickness in nm, `mix(minimum, maximum, texture.g)`.
    pub iridescence_thickness: f32,
    /// `diffuseTransmissionFactor × texture.a` (0 without diffuse transmission).
    pub diffuse_transmission: f32,
    /// `diffuseTransmissionColorFactor × texture.rgb`.
    pub diffuse_transmission_color: Vec3,
    /// `anisotropyStrength × texture.b` (0 without anisotropy). Its direction is the
    /// surface's ([`crate::SurfacePoint::anisotropy`]).
    pub anisotropy: f32,
}

impl Material {
    /// True when any slot uses a texture (the scene then stores UVs).
    pub fn uses_textures(&self) -> bool {
        self.texture_refs().next().is_some()
    }

    /// The slots' textures.
    pub fn texture_refs(&self) -> impl Iterator<Item = &TextureRef> {
        [
            &self.base_color_texture,
            &self.metallic_roughness_texture,
            &self.normal_texture,
            &self.emissive_texture,
            &self.transmission_texture,
            &self.specular_textures.specular,
            &self.specular_textures.color,
        ]
        .into_iter()
        .chain(
            self.layers.clearcoat.iter().flat_map(|c| [&c.texture, &c.roughness_texture, &c.normal_texture]),
        )
        .chain(self.layers.sheen.iter().flat_map(|s| [&s.color_texture, &s.roughness_texture]))
        .chain(self.iridescence.iter().flat_map(|i| [&i.texture, &i.thickness_texture]))
        .chain(self.anisotropy.iter().map(|a| &a.texture))
        .chain(self.diffuse_transmission.iter().flat_map(|d| [&d.texture, &d.color_texture]))
        .flatten()
    }

    /// Whether light can pass through the surface (`transmissionFactor` > 0): rendered as a
    /// dielectric interface (a solid's surface with [`Material::volume`], else a thin sheet).
    pub fn is_transmissive(&self) -> bool {
        self.transmission_factor > 0.0
    }

    /// Whether the surface is a thin-walled transmissive sheet.
    pub fn is_thin_walled(&self) -> bool {
        self.is_transmissive() && !self.volume
    }

    /// Whether shadow rays cross the surface (multiplied by what it transmits): a thin-walled
    /// sheet, or the invisible interface of a solid of index 1. Other solids block them.
    pub fn passes_shadow_rays(&self) -> bool {
        self.is_transmissive() && (!self.volume || self.ior == 1.0)
    }

    /// Evaluates factors × textures at a shading point `at` (each texture at its UV set), the
    /// base colour and alpha multiplied by the vertex colour.
    pub fn evaluate(&self, at: &VertexAttributes, textures: &[Texture], images: &[Image]) -> MaterialSample {
        let sample =
            |t: &Option<TextureRef>| t.as_ref().map_or(Vec4::ONE, |t| t.sample(at, textures, images));
        let base = self.base_color_factor * sample(&self.base_color_texture) * at.color;
        let mr = sample(&self.metallic_roughness_texture);
        let emission = self.emissive * sample(&self.emissive_texture).truncate();
        let transmission = match &self.transmission_texture {
            Some(t) => self.transmission_factor * t.sample(at, textures, images).x,
            None => self.transmission_factor,
        };
        let (clearcoat, clearcoat_roughness) = match &self.layers.clearcoat {
            Some(c) => (c.factor * sample(&c.texture).x, c.roughness * sample(&c.roughness_texture).y),
            None => (0.0, 0.0),
        };
        let (sheen_color, sheen_roughness) = match &self.layers.sheen {
            Some(s) => {
                (s.color * sample(&s.color_texture).truncate(), s.roughness * sample(&s.roughness_texture).w)
            }
            None => (Vec3::ZERO, 0.0),
        };
        let (iridescence, iridescence_ior, iridescence_thickness) = match &self.iridescence {
            Some(i) => {
                let t = match &i.thickness_texture {
                    Some(t) => t.sample(at, textures, images).y,
                    None => 1.0,
                };
                let thickness = i.thickness_minimum * (1.0 - t) + i.thickness_maximum * t;
                (i.factor * sample(&i.texture).x, i.ior, thickness)
            }
            None => (0.0, 1.3, 0.0),
        };
        let (diffuse_transmission, diffuse_transmission_color) = match &self.diffuse_transmission {
            Some(d) => (d.factor * sample(&d.texture).w, d.color * sample(&d.color_texture).truncate()),
            None => (0.0, Vec3::ONE),
        };
        let anisotropy = self.anisotropy.as_ref().map_or(0.0, |a| a.strength * sample(&a.texture).z);
        MaterialSample {
            base_color: base.truncate(),
            alpha: base.w,
            metallic: self.metallic_factor * mr.z,
            roughness: self.roughness_factor * mr.y,
            emission,
            specular_factor: self.specular_factor * sample(&self.specular_textures.specular).w,
            specular_color: self.specular_color_factor * sample(&self.specular_textures.color).truncate(),
            transmission,
            clearcoat,
            clearcoat_roughness,
            sheen_color,
            sheen_roughness,
            iridescence,
            iridescence_ior,
            iridescence_thickness,
            diffuse_transmission,
            diffuse_transmission_color,
            anisotropy,
        }
    }

    /// Whether the alpha test keeps a hit with this `alpha` (always true unless `Mask`).
    pub fn alpha_test(&self, alpha: f32) -> bool {
        match self.alpha_mode {
            AlphaMode::Mask { cutoff } => alpha >= cutoff,
            _ => true,
        }
    }
}
