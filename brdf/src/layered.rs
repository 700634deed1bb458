//! The glTF material as one layered BSDF: which lobes a shading point has, with which weights,
//! built from the material's parameters there. The CPU integrator calls [`HitBsdf::new`] at
//! every hit; `furnace-gpu`'s `layered.wgsl` (`hit_bsdf`, `hit_eval`, `hit_pdf`) is its twin.
//!
//! ## The lobes and the layering rule
//!
//! | lobe | Rust file | weight in the mixture | albedo |
//! |---|---|---|---|
//! | [`Lambert`](crate::Lambert) diffuse base | `lambert.rs` | `(1 − g)·(1 − m′)`, under the specular layer: `1 − sF·max(fr)` at the half vector | `baseColor` |
//! | [`GgxSpecular`](crate::GgxSpecular) (with [`turquin`](crate::turquin) compensation) | `specular.rs`, `ggx.rs`, `turquin.rs` | `1 − g`, merged: F0 `mix(0.04·sF·sC, baseColor, m′)`, F90 `mix(sF, 1, m′)` | Fresnel |
//! | [`Dielectric`] interface (smooth, rough or thin-walled) | `dielectric.rs` | `g` | tint `baseColor` |
//!
//! with `m = clamp(metallic)`, `g = clamp(transmission)·(1 − m)` (KHR_materials_transmission:
//! only the dielectric part transmits) and the opaque rest's metallic `m′ = min(m/(1 − g), 1)`
//! (`metallic` itself when `g = 0`): glTF's `mix(dielectric(mix(diffuse, transmission, T)),
//! metal, metallic)` regrouped as `g·dielectric + (1 − g)·opaque`. The first two rows are
//! [`MetallicRoughness`] (`metallic_roughness.rs`), the mixture with the third
//! [`Transmissive`].
//!
//! A new lobe is one more Rust file (its `eval`, `sample`, `pdf`), its parameters in
//! [`LayeredParams`], its weight in [`HitBsdf::new`] and its row above.

use crate::dielectric::{Dielectric, Interface, ScatterSample, Transmissive};
use crate::metallic_roughness::{MetallicRoughness, MetallicRoughnessParams};
use crate::specular::SpecularOptions;
use crate::{Bsdf, Rgb};
use glam::{Vec2, Vec3};

/// The glTF material's parameters at one shading point (after texture lookups): what
/// [`HitBsdf::new`] builds the BSDF from. Out-of-range and NaN inputs are clamped or replaced
/// there, as [`MetallicRoughness::new`] and [`Dielectric::new`] do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayeredParams {
    /// `baseColorFactor × baseColorTexture`, linear RGB: the diffuse albedo, the metal's F0
    /// and the dielectric's tint.
    pub base_color: Rgb,
    /// `metallicFactor × texture.b`.
    pub metallic: f32,
    /// Perceptual roughness `roughnessFactor × texture.g`; α = roughness².
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor`.
    pub specular_factor: f32,
    /// KHR_materials_specular `specularColorFactor`.
    pub specular_color: Rgb,
    /// KHR_materials_transmission `transmissionFactor × texture.r` (0: opaque).
    pub transmission: f32,
    /// KHR_materials_ior `ior`: the dielectric's relative index of refraction.
    pub ior: f32,
    /// KHR_materials_volume: the surface bounds a solid (otherwise a thin-walled sheet).
    pub volume: bool,
}

/// The BSDF at a hit: the opaque glTF material, or one that transmits
/// (KHR_materials_transmission). See the [module docs](self) for the layering.
#[derive(Debug, Clone, Copy)]
pub enum HitBsdf {
    /// Lambert under a merged GGX lobe ([`MetallicRoughness`]).
    Opaque(MetallicRoughness),
    /// The mixture with a dielectric, and whether it bounds a solid (KHR_materials_volume).
    Transmissive(Transmissive, bool),
}

impl HitBsdf {
    /// The BSDF of evaluated material parameters: the glTF metallic-roughness material, mixed
    /// with a dielectric interface where it transmits.
    #[inline]
    pub fn new(params: &LayeredParams, specular: SpecularOptions) -> Self {
        let mr = |metallic: f32| {
            MetallicRoughness::new(
                MetallicRoughnessParams {
                    base_color: params.base_color,
                    metallic,
                    roughness: params.roughness,
                    specular_factor: params.specular_factor,
                    specular_color: params.specular_color,
                },
                specular,
            )
        };
        let metallic = params.metallic.clamp(0.0, 1.0);
        let g = params.transmission.clamp(0.0, 1.0) * (1.0 - metallic);
        if !(g > 0.0) {
            return Self::Opaque(mr(params.metallic));
        }
        let roughness = params.roughness.clamp(0.0, 1.0);
        // Sheets are smooth (the loader warns about rough ones).
        let dielectric = Dielectric::new(
            params.ior,
            roughness * roughness,
            !params.volume,
            specular.masking,
            params.base_color,
        );
        // The opaque rest: metal m and the untransmitted dielectric (1 − m)(1 − T), renormalised.
        let opaque = mr(if g < 1.0 { (metallic / (1.0 - g)).min(1.0) } else { 0.0 });
        Self::Transmissive(Transmissive { dielectric, opaque, weight: g.min(1.0) }, params.volume)
    }

    /// The BSDF times `|cos θi|`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Self::Opaque(b) => b.eval(wo, wi),
            Self::Transmissive(b, _) => b.eval(wo, wi),
        }
    }

    /// The density of the non-delta part of `sample`.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Self::Opaque(b) => b.pdf(wo, wi),
            Self::Transmissive(b, _) => b.pdf(wo, wi),
        }
    }

    /// Samples a direction; the lobe number `uc` is drawn only where it decides something
    /// ([`MetallicRoughness::sample_lazy`]).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2, uc: impl FnOnce() -> f32) -> Option<ScatterSample> {
        match self {
            Self::Opaque(b) => b.sample_lazy(wo, u, uc).map(ScatterSample::from),
            Self::Transmissive(b, _) => b.sample(wo, uc(), u),
        }
    }

    /// Only delta lobes: no light sample can reach a direction.
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Self::Transmissive(b, _) if b.is_delta())
    }

    /// A thin-walled sheet or an η = 1 interface: straight passes are no events.
    #[inline]
    pub fn is_straight(&self) -> bool {
        matches!(self, Self::Transmissive(b, _) if b.dielectric.is_straight())
    }

    /// The interface of a solid.
    #[inline]
    pub fn is_volume(&self) -> bool {
        matches!(self, Self::Transmissive(_, true))
    }

    /// Light samples may arrive from behind the surface (a rough solid interface).
    #[inline]
    pub fn transmits_light_samples(&self) -> bool {
        matches!(self, Self::Transmissive(b, true) if b.dielectric.interface == Interface::Rough)
    }

    /// What a shadow ray crossing a sheet (or an η = 1 interface) at cosine `cos` keeps:
    /// `g·T′·tint + (1 − g)·0`.
    pub fn sheet_transmittance(&self, cos: f32) -> Rgb {
        match self {
            Self::Transmissive(b, _) => b.weight * b.dielectric.shadow_transmittance(cos),
            _ => Vec3::ZERO,
        }
    }
}
