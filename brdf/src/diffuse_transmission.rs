//! KHR_materials_diffuse_transmission's Lambertian transmission lobe: the part of the
//! dielectric's diffuse base that leaves on the other side of the surface.
//!
//! The extension replaces the base of glTF's `fresnel_mix` by
//! `mix(diffuse_brdf(baseColor), diffuse_btdf(diffuseTransmissionColor), diffuseTransmission)`,
//! so that, with `dt = diffuseTransmission`,
//!
//! ```text
//! base = (1 − dt)·baseColor/π   (ωi on ωo's side)
//!      +       dt·dtColor/π     (ωi on the other side)
//! ```
//!
//! under the same Fresnel weight `1 − sF·max(fr(cos θd))` as the diffuse reflection. For ωi
//! on the other side the half vector of ωo and ωi is not defined by the text; the weight is
//! taken at the half vector of ωo and ωi mirrored to ωo's side (the references' choice
//! `transmission_half = "mirror"`), which keeps the lobe reciprocal.
//!
//! As the reflection models, the lobe is defined for ωo above the surface (z > 0) and is 0
//! otherwise (a solid's interface seen from inside is mirrored by [`crate::HitBsdf`]). `eval`
//! includes `|cos θi|`; `sample_direction` draws a cosine-weighted direction below the
//! surface; the pdf is per solid angle.

use crate::metallic_roughness::MetallicRoughness;
use crate::{Rgb, above, clamp_rgb};
use furnace_sampling::warp::square_to_cosine_hemisphere;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// The diffuse transmission lobe of a material at one shading point. Its Fresnel weight is
/// the opaque material's ([`MetallicRoughness`]'s diffuse attenuation), passed to each call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffuseTransmission {
    /// The lobe's albedo before the Fresnel weight: `(1 − metallic)(1 − transmission)·dt·
    /// dtColor`, each channel in `[0, 1]`.
    pub color: Rgb,
    /// The surface bounds a solid (KHR_materials_volume): a transmitted ray enters or leaves
    /// its medium; otherwise it is a thin sheet.
    pub volume: bool,
}

/// `w` mirrored to the other side of the surface.
#[inline]
fn mirror(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

impl DiffuseTransmission {
    /// The lobe of albedo `color` (clamped to `[0, 1]`, NaN → 0).
    pub fn new(color: Rgb, volume: bool) -> Self {
        Self { color: clamp_rgb(color, 1.0), volume }
    }

    /// `color/π · |cos θi| · (1 − sF·max(fr(ωo·h)))` for ωo above and ωi below the surface
    /// (each more than [`MIN_COS`](crate::MIN_COS) from it), `h` the half vector of ωo and ωi mirrored above;
    /// else 0. `opaque` gives the Fresnel weight.
    #[inline]
    pub fn eval(&self, opaque: &MetallicRoughness, wo: Vec3, wi: Vec3) -> Rgb {
        if !across(wo, wi) {
            return Rgb::ZERO;
        }
        let wm = (wo + mirror(wi)).normalize_or(Vec3::Z);
        self.color * (FRAC_1_PI * wi.z.abs() * opaque.diffuse_scale(wo.dot(wm)))
    }

    /// A cosine-weighted direction below the surface (`u` through the cosine-hemisphere warp,
    /// mirrored), or `None` for ωo not above it.
    #[inline]
    pub fn sample_direction(&self, wo: Vec3, u: Vec2) -> Option<Vec3> {
        if !above(wo) {
            return None;
        }
        let wi = mirror(square_to_cosine_hemisphere(u));
        across(wo, wi).then_some(wi)
    }

    /// `|cos θi|/π` for ωo above and ωi below the surface, else 0.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if across(wo, wi) { FRAC_1_PI * -wi.z } else { 0.0 }
    }

    /// The lobe's albedo estimate (luminance) at ωo for lobe selection:
    /// `lum(color)·(1 − sF·max(fr(μo)))`.
    #[inline]
    pub fn albedo_estimate(&self, opaque: &MetallicRoughness, wo: Vec3) -> f32 {
        crate::luminance(self.color) * opaque.diffuse_scale(wo.z.clamp(0.0, 1.0))
    }
}

/// ωo above and ωi below the surface, each more than [`MIN_COS`](crate::MIN_COS) from it (false for NaN).
#[inline]
fn across(wo: Vec3, wi: Vec3) -> bool {
    above(wo) && above(mirror(wi))
}
