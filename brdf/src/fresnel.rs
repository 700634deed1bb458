//! Schlick's Fresnel approximation.

use crate::Rgb;

/// Schlick's approximation with an explicit grazing value (as glTF's KHR_materials_specular
/// needs): `F = F0 + (F90 − F0)(1 − cos θd)^5`, `cos θd` clamped to `[0, 1]`.
///
/// Schlick, "An Inexpensive BRDF Model for Physically-based Rendering", CGF 13(3), 1994.
#[inline]
pub fn schlick(f0: Rgb, f90: Rgb, cos_theta_d: f32) -> Rgb {
    let m = (1.0 - cos_theta_d.clamp(0.0, 1.0)).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (f90 - f0) * (m2 * m2 * m)
}

/// Scalar Schlick, `F0 + (F90 − F0)(1 − cos θd)^5`.
#[inline]
pub fn schlick_scalar(f0: f32, f90: f32, cos_theta_d: f32) -> f32 {
    let m = (1.0 - cos_theta_d.clamp(0.0, 1.0)).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (f90 - f0) * (m2 * m2 * m)
}
