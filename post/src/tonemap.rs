//! Exposure and tone mapping: linear radiance → display-referred values in [0, 1].

use crate::PostError;
use core::fmt;
use core::str::FromStr;
use glam::Vec3;

/// The linear scale of an exposure of `ev` stops: `2^ev`.
///
/// EV 0 leaves radiance unchanged (scale 1); each +1 doubles it, each −1 halves it. This is the
/// thesis' §4.1 `color · 2^x / scale` without its fixed `scale = 2^−10`, which only compensated
/// for the thesis' FP16 render target (deviation from the thesis, deliberate: our radiance is
/// stored in f32 at its physical magnitude, so EV 0 is the neutral exposure). A NaN `ev` gives
/// NaN, which the tone maps then send to black.
///
/// ```
/// assert_eq!(furnace_post::exposure_scale(0.0), 1.0);
/// assert_eq!(furnace_post::exposure_scale(-2.0), 0.25);
/// ```
pub fn exposure_scale(ev: f32) -> f32 {
    ev.exp2()
}

/// ACES filmic tone curve, Narkowicz's 2015 fit (the thesis, listing 4.1):
/// `saturate(x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14))`.
///
/// The curve reaches 1 at x = (0.56 + √0.3584)/0.16 ≈ 7.2417 (root of 0.08x² − 0.56x − 0.14) and
/// would tend to 2.51/2.43 ≈ 1.0329 unclamped; everything above the root is 1. Defined for every
/// input: NaN → 0 (as HLSL `saturate`), +∞ and any x ≥ 8 → exactly 1 (so that `x·x` cannot
/// overflow into ∞/∞), and x ≤ 0 → 0. The last is a deliberate deviation from the bare fit,
/// whose rational function turns positive again for x < −0.012 (it gives 1 at x = −0.5):
/// negative radiance is not light, so it maps to black.
pub fn aces_filmic(x: f32) -> f32 {
    const A: f32 = 2.51;
    const B: f32 = 0.03;
    const C: f32 = 2.43;
    const D: f32 = 0.59;
    const E: f32 = 0.14;
    if !(x > 0.0) {
        // NaN, negatives, −∞ and 0 (f(0) = 0 exactly anyway).
        return 0.0;
    }
    if x >= 8.0 {
        // f(8) = 160.88 / 160.38 > 1: saturated already; avoids ∞/∞ for huge x.
        return 1.0;
    }
    let y = (x * (A * x + B)) / (x * (C * x + D) + E);
    y.clamp(0.0, 1.0)
}

/// Khronos PBR Neutral tone mapping (Khronos 3D Commerce, "PBR Neutral" specification, 2024),
/// exactly the reference GLSL:
///
/// ```text
/// startCompression = 0.8 − 0.04;  desaturation = 0.15
/// x = min(r, g, b);  offset = x < 0.08 ? x − 6.25x² : 0.04;  color −= offset
/// peak = max(r, g, b);  if peak < startCompression: return color
/// d = 1 − startCompression;  newPeak = 1 − d² / (peak + d − startCompression)
/// color *= newPeak / peak
/// g = 1 − 1 / (desaturation · (peak − newPeak) + 1);  return mix(color, newPeak, g)
/// ```
///
/// It acts on the whole colour (hue-preserving), not per channel. Below the compression start
/// (peak < 0.76 after the toe) it is the identity minus the toe offset (0.04 for min ≥ 0.08).
/// The input must be finite and non-negative; [`Tonemap::apply`] ensures that.
pub fn pbr_neutral(color: Vec3) -> Vec3 {
    const START_COMPRESSION: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let x = color.min_element();
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let color = color - Vec3::splat(offset);
    let peak = color.max_element();
    if peak < START_COMPRESSION {
        return color;
    }
    const D: f32 = 1.0 - START_COMPRESSION;
    let new_peak = 1.0 - D * D / (peak + D - START_COMPRESSION);
    let color = color * (new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    // GLSL mix(a, b, t) = a·(1 − t) + b·t: exactly b at t = 1.
    color * (1.0 - g) + Vec3::splat(new_peak) * g
}

/// The tone maps, by the names the CLI uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Tonemap {
    /// [`aces_filmic`] per channel (the thesis' choice, and the default).
    #[default]
    Aces,
    /// [`pbr_neutral`] on the whole colour.
    PbrNeutral,
    /// Clamp each channel to [0, 1].
    Clamp,
}

impl Tonemap {
    /// Every tone map, in documentation order.
    pub const ALL: [Tonemap; 3] = [Self::Aces, Self::PbrNeutral, Self::Clamp];

    /// The CLI name (`aces`, `pbr-neutral`, `clamp`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Aces => "aces",
            Self::PbrNeutral => "pbr-neutral",
            Self::Clamp => "clamp",
        }
    }

    /// Tone-maps one exposed linear colour into [0, 1]³. Never panics, never returns NaN.
    ///
    /// Each channel is first made finite and non-negative: NaN → 0, negative (and −∞) → 0,
    /// +∞ → `f32::MAX`; so after tone mapping NaN is 0 and +∞ is 1 for every curve (with PBR
    /// Neutral, whose compression desaturates towards white, a +∞ channel turns the whole pixel
    /// white). The result is clamped to [0, 1] (a no-op for ACES and PBR Neutral on valid input).
    pub fn apply(self, color: Vec3) -> Vec3 {
        let c = Vec3::from_array(color.to_array().map(sanitize));
        let mapped = match self {
            Self::Aces => Vec3::new(aces_filmic(c.x), aces_filmic(c.y), aces_filmic(c.z)),
            Self::PbrNeutral => pbr_neutral(c),
            Self::Clamp => c,
        };
        mapped.clamp(Vec3::ZERO, Vec3::ONE)
    }
}

/// NaN → 0; everything else clamped to [0, f32::MAX] (so −∞ → 0, +∞ → f32::MAX).
fn sanitize(x: f32) -> f32 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, f32::MAX) }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Tonemap {
    type Err = PostError;

    /// Parses a CLI name, ignoring ASCII case and surrounding white space.
    fn from_str(s: &str) -> Result<Self, PostError> {
        Self::ALL
            .into_iter()
            .find(|t| t.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| PostError::UnknownTonemap(s.to_string()))
    }
}
