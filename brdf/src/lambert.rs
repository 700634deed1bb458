//! The Lambertian diffuse BRDF.

use crate::{Bsdf, Lobe, Rgb, Sample, above};
use furnace_sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Lambertian reflection `f = albedo/π`, sampled by the cosine-weighted hemisphere warp of
/// `furnace-sampling` (the thesis's polar mapping), for which the weight is exactly `albedo`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambert {
    /// Diffuse albedo (reflectance) per channel, in `[0, 1]` for energy conservation.
    pub albedo: Rgb,
}

impl Lambert {
    /// A Lambertian surface of the given albedo (each channel clamped to `[0, 1]`, NaN → 0).
    pub fn new(albedo: Rgb) -> Self {
        Self { albedo: crate::clamp_rgb(albedo, 1.0) }
    }
}

impl Bsdf for Lambert {
    /// `albedo/π · cos θi`; 0 unless both directions are above the horizon.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !(above(wo) && above(wi)) {
            return Rgb::ZERO;
        }
        self.albedo * (FRAC_1_PI * wi.z)
    }

    /// Cosine-weighted hemisphere sample; `weight = albedo`, `pdf = cos θi/π`. `uc` is unused.
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2) -> Option<Sample> {
        if !above(wo) {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wi);
        if !(pdf > 0.0) {
            return None; // defensive: the warp keeps cos θi > 0 for u in [0, 1)²
        }
        Some(Sample { wi, weight: self.albedo, pdf, lobe: Lobe::Diffuse })
    }

    /// `cos θi/π` above the horizon (for `wo` above it too), else 0.
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !above(wo) {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi)
    }
}
