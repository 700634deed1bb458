//! The exact sRGB transfer functions (IEC 61966-2-1:1999) and 8-bit quantisation.

use crate::{Tonemap, exposure_scale};
use glam::Vec3;

/// Linear → sRGB-encoded, the exact piecewise OETF of IEC 61966-2-1 (the thesis, §4.3):
/// `12.92·x` for `x ≤ 0.0031308`, else `1.055·x^(1/2.4) − 0.055`.
///
/// Meant for x ∈ [0, 1]; outside it the formula is simply extended (negative values take the
/// linear branch, values above 1 the power branch), and NaN stays NaN — [`quantize_unorm8`]
/// sends it to 0.
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// sRGB-encoded → linear, the exact inverse EOTF: `v / 12.92` for `v ≤ 0.04045`, else
/// `((v + 0.055) / 1.055)^2.4`.
///
/// The two breakpoints (0.0031308 and 0.04045) are the standard's; they differ from each other's
/// image by < 1e-7 (12.92 · 0.0031308 = 0.040449936), the standard's known tiny discontinuity.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// Quantises a value in [0, 1] to 8 bits: `round(clamp(v, 0, 1) · 255)`, halves away from zero.
/// NaN → 0, values below 0 → 0, above 1 → 255. Never panics.
pub fn quantize_unorm8(v: f32) -> u8 {
    if v.is_nan() {
        return 0;
    }
    // In [0, 255.0] after the clamp, so the cast is exact after rounding.
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// The linear value of an 8-bit sRGB code: `srgb_to_linear(v / 255)`.
pub fn srgb8_to_linear(v: u8) -> f32 {
    srgb_to_linear(f32::from(v) / 255.0)
}

/// One linear pixel → 8-bit sRGB: exposure `scale` (see [`exposure_scale`]), then `tonemap`
/// ([`Tonemap::apply`]: NaN → 0, +∞ → 1), then [`linear_to_srgb`] and [`quantize_unorm8`].
pub fn pixel_to_srgb8(linear: Vec3, scale: f32, tonemap: Tonemap) -> [u8; 3] {
    let mapped = tonemap.apply(linear * scale);
    mapped.to_array().map(|c| quantize_unorm8(linear_to_srgb(c)))
}

/// A linear radiance image → 8-bit sRGB for display or PNG: for each pixel, ×2^`ev`, tone map,
/// sRGB OETF, round to nearest. Defined for every input (NaN → 0, +∞ → 255 in that channel).
///
/// ```
/// use furnace_post::{Tonemap, to_srgb8};
/// use glam::Vec3;
/// let px = to_srgb8(&[Vec3::ZERO, Vec3::ONE, Vec3::splat(f32::NAN)], 0.0, Tonemap::Clamp);
/// assert_eq!(px, vec![[0, 0, 0], [255, 255, 255], [0, 0, 0]]);
/// ```
pub fn to_srgb8(linear: &[Vec3], ev: f32, tonemap: Tonemap) -> Vec<[u8; 3]> {
    let scale = exposure_scale(ev);
    linear.iter().map(|&c| pixel_to_srgb8(c, scale, tonemap)).collect()
}
