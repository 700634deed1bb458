//! # furnace-brdf
//!
//! The reflection models of furnace, in a local shading frame (z = normal), with explicit
//! uniform numbers — no random number generator inside — as pbrt-v4 and Mitsuba 3 do:
//!
//! * [`Lambert`] — `albedo/π`, cosine-hemisphere sampling.
//! * [`GgxSpecular`] — GGX microfacet reflection (Walter et al. 2007) with Smith masking,
//!   separable or height-correlated ([`Masking`]; Heitz 2014), Schlick Fresnel (1994), sampled
//!   by the NDF (the thesis §3.2), by visible normals (Heitz 2018) or by spherical caps (Dupuy
//!   & Benyoub 2023) ([`SpecularSampling`]), with optional Turquin 2019 energy compensation
//!   ([`turquin`]) from tables this crate computes itself.
//! * [`MetallicRoughness`] — the glTF 2.0 metallic-roughness material with
//!   KHR_materials_specular, one Lambert and one merged GGX lobe.
//! * [`Dielectric`] — glass: smooth, rough (Walter et al. 2007) or thin-walled, with the exact
//!   unpolarised Fresnel reflectance; [`Transmissive`] mixes one with the opaque material
//!   (KHR_materials_transmission). Dielectrics see both hemispheres ([`dielectric`]).
//! * [`iridescence`] — KHR_materials_iridescence's thin-film Fresnel, mixed into the
//!   material's specular lobe ([`MetallicRoughness::new_iridescent`]).
//! * [`DiffuseTransmission`] — KHR_materials_diffuse_transmission's Lambertian transmission
//!   lobe, the part of the diffuse base that leaves on the other side.
//! * [`spectrum`] — KHR_materials_dispersion: the index per wavelength from the Abbe number,
//!   and the wavelength (with its RGB weight) a path is traced at past a dispersive solid.
//! * [`Clearcoat`] and [`Sheen`] — KHR_materials_clearcoat's white GGX coat and
//!   KHR_materials_sheen's Charlie lobe, the layers above the material.
//! * [`HitBsdf`] — the glTF material at a hit as one layered BSDF: the lobes above, their
//!   weights and albedo scaling, built from [`LayeredParams`] ([`layered`]: the table of
//!   lobes and the layering rule).
//!
//! ## Conventions ([`Bsdf`])
//!
//! * Directions `wo` (towards the viewer) and `wi` (towards the light) are unit vectors
//!   pointing away from the surface; reflection only, so both must be above the horizon
//!   (`z > MIN_COS` = 1e-15, see [`above`]), otherwise `eval` and `pdf` return 0 and `sample`
//!   returns `None`.
//! * [`Bsdf::eval`] returns the BRDF **times** `cos θi` (Mitsuba's convention).
//! * [`Bsdf::sample`] returns `wi`, `weight = eval(wo, wi)/pdf` and `pdf`.
//! * [`Bsdf::pdf`] is the solid-angle density of `sample` (equal to what `sample` reports).
//! * Colours are linear RGB ([`Rgb`] = `glam::Vec3`).
//!
//! No input produces NaN, infinity or a negative value: roughness is clamped to
//! `[ALPHA_MIN, 1]` (`ggx::ALPHA_MIN` = 1e-4, see its docs), colours given to the constructors
//! are clamped to be finite and non-negative (NaN → 0), directions within [`MIN_COS`] of the
//! horizon count as below it, and grazing angles use forms that tend to 0 rather than 0/0
//! (tested in `tests/stability.rs`). Fields set directly bypass the constructors' clamping.
//!
//! ## Example
//!
//! ```
//! use furnace_brdf::{Bsdf, MetallicRoughness, MetallicRoughnessParams, SpecularOptions};
//! use glam::{Vec2, Vec3};
//!
//! let gold = MetallicRoughness::new(
//!     MetallicRoughnessParams {
//!         base_color: Vec3::new(1.0, 0.78, 0.34),
//!         metallic: 1.0,
//!         roughness: 0.4,
//!         ..Default::default()
//!     },
//!     SpecularOptions::default(),
//! );
//! let wo = Vec3::new(0.6, 0.0, 0.8);
//! let s = gold.sample(wo, 0.5, Vec2::new(0.3, 0.7)).expect("a reflection");
//! assert!(s.wi.z > 0.0);
//! // The weight is eval/pdf, and pdf is what `pdf` says.
//! let eval = gold.eval(wo, s.wi);
//! assert!((s.weight - eval / s.pdf).abs().max_element() < 1e-3 * s.weight.max_element());
//! assert!((gold.pdf(wo, s.wi) - s.pdf).abs() < 1e-3 * s.pdf);
//! ```

pub mod clearcoat;
pub mod dielectric;
pub mod diffuse_transmission;
mod frame;
pub mod fresnel;
pub mod ggx;
pub mod iridescence;
mod lambert;
pub mod layered;
mod metallic_roughness;
pub mod sheen;
pub mod spectrum;
mod specular;
#[rustfmt::skip]
mod tables;
pub mod turquin;

pub use clearcoat::Clearcoat;
pub use dielectric::{Dielectric, Fresnel, Interface, ScatterSample, Transmissive, fresnel_dielectric};
pub use diffuse_transmission::DiffuseTransmission;
pub use frame::Frame;
pub use ggx::{Ggx, Masking, SpecularSampling};
pub use lambert::Lambert;
pub use layered::{HitBsdf, LayeredParams, LobeSelection};
pub use metallic_roughness::{MetallicRoughness, MetallicRoughnessParams, luminance};
pub use sheen::Sheen;
pub use specular::{GgxSpecular, SpecularOptions};

use glam::{Vec2, Vec3};

/// Linear RGB.
pub type Rgb = Vec3;

/// Directions closer to the horizon than this cosine count as below it.
///
/// Their contribution is below `f32` resolution (G1 ≤ 2·10⁻¹⁵/α), and the cutoff keeps every
/// product of two cosines a normal `f32` (≥ 10⁻³⁰): below ~10⁻³⁰ half vectors, G2 and the NDF
/// weight underflow to 0/0 or overflow to ∞ (found by `tests/stability.rs`).
pub const MIN_COS: f32 = 1e-15;

/// Clamps each channel to `[0, hi]`, NaN to 0: what the constructors do to colours.
#[inline]
pub(crate) fn clamp_rgb(c: Rgb, hi: f32) -> Rgb {
    let f = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, hi) };
    Rgb::new(f(c.x), f(c.y), f(c.z))
}

/// Whether `w` is above the horizon by more than [`MIN_COS`] (false for NaN).
#[inline]
pub fn above(w: Vec3) -> bool {
    w.z > MIN_COS
}

/// Which lobe produced a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Lobe {
    /// The Lambertian lobe.
    Diffuse,
    /// The GGX lobe.
    Specular,
    /// The clear coat's GGX lobe ([`Clearcoat`]).
    Clearcoat,
    /// The sheen lobe ([`Sheen`]).
    Sheen,
}

/// A sampled direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The sampled incident direction (towards the light), unit length, `z > 0`.
    pub wi: Vec3,
    /// `eval(wo, wi)/pdf`: the BRDF times `cos θi` over the pdf, per channel.
    pub weight: Rgb,
    /// The solid-angle pdf of `wi`, equal to [`Bsdf::pdf`]`(wo, wi)`.
    pub pdf: f32,
    /// The lobe that was sampled.
    pub lobe: Lobe,
}

/// A reflection model in the local shading frame (z = normal). See the crate docs for the
/// conventions.
pub trait Bsdf {
    /// The BRDF times `cos θi` (cosine **included**), per channel; 0 unless both directions are
    /// above the horizon.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb;

    /// Samples `wi` for `wo` from one uniform number `uc` (lobe choice) and two `u` (the
    /// direction), all in `[0, 1)`. `None` when no valid direction results (wo below the
    /// horizon, or a microfacet reflection that lands below it).
    fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<Sample>;

    /// The solid-angle density with which [`Bsdf::sample`] produces `wi`.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32;
}
