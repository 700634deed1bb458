//! [`AdaptiveSampling`]: pixels stop taking samples once their noise is below a threshold.
//!
//! The rule, the same on every backend: after a pixel has been given the samples below index
//! `b`, where `b` is a multiple of [`ADAPTIVE_STEP`] and at least
//! [`AdaptiveSampling::min_samples`], it is tested once: if the relative standard error of its
//! luminance ([`relative_noise`]) is below [`AdaptiveSampling::threshold`], it is marked
//! converged and takes no more samples in this render (its mean never changes again). The
//! test depends only on the pixel's own sums at a fixed sample index, so the image does not
//! depend on how a render is cut into passes, and a saved film (which carries the marks)
//! resumes exactly.
//!
//! Bias: stopping on the samples' own spread favours pixels whose first samples happened to
//! agree, so a pixel that has not yet met its rare bright paths (a caustic, a small light seen
//! by few paths) can stop dark. `min_samples` bounds how often that happens; the bias is
//! measured in `docs/accuracy.md`.

/// Pixels are tested every this many samples (and only then): often enough that a converged
/// pixel stops soon, rarely enough that the test costs nothing next to the samples.
pub const ADAPTIVE_STEP: u32 = 8;

/// Rec. 709 luminance weights, of the noise estimate (the GPU film sums squared luminances with
/// the same weights): furnace-sampling's one definition.
pub use furnace_sampling::LUMINANCE;

/// When pixels stop taking samples ([`crate::RenderSettings::adaptive`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSampling {
    /// A pixel stops when the relative standard error of its luminance is below this (0.01:
    /// its mean is within about 1 % of the converged value, one standard error).
    pub threshold: f32,
    /// No pixel stops before this many samples (the guard against stopping before rare paths
    /// were found).
    pub min_samples: u32,
}

impl AdaptiveSampling {
    /// The default minimum of samples before a pixel may stop.
    pub const DEFAULT_MIN_SAMPLES: u32 = 16;

    /// Whether pixels are tested once they have `samples` samples (a multiple of
    /// [`ADAPTIVE_STEP`], at least `min_samples`, not 0).
    #[inline]
    pub fn tests_at(&self, samples: u32) -> bool {
        samples > 0 && samples.is_multiple_of(ADAPTIVE_STEP) && samples >= self.min_samples
    }

    /// Whether a pixel with these sums over `count` accepted samples has converged.
    #[inline]
    pub fn converged(&self, sum: glam::DVec3, sum_lum_sq: f64, count: u64) -> bool {
        relative_noise(sum, sum_lum_sq, count) < f64::from(self.threshold)
    }
}

/// The luminance of an RGB sample, in `f32` (as the GPU forms it).
#[inline]
pub fn luminance(v: glam::Vec3) -> f32 {
    v.dot(glam::Vec3::from_array(LUMINANCE))
}

/// The relative standard error of a pixel's mean luminance from its sums over `count` samples:
/// `√(s² / n) / mean`, with `s²` the unbiased sample variance; 0 for a pixel whose samples are
/// all black, `+∞` with fewer than two samples or a mean ≤ 0 with spread.
#[inline]
pub fn relative_noise(sum: glam::DVec3, sum_lum_sq: f64, count: u64) -> f64 {
    if count < 2 {
        return f64::INFINITY;
    }
    let n = count as f64;
    let w = glam::Vec3::from_array(LUMINANCE).as_dvec3();
    let mean = sum.dot(w) / n;
    let var = ((sum_lum_sq - n * mean * mean) / (n - 1.0)).max(0.0);
    if var == 0.0 {
        return 0.0;
    }
    if !(mean > 0.0) {
        return f64::INFINITY;
    }
    (var / n).sqrt() / mean
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn relative_noise_of_known_samples() {
        // Samples 1 and 3 (grey): mean 2, s² = 2, standard error 1, relative 0.5.
        let (a, b) = (glam::Vec3::splat(1.0), glam::Vec3::splat(3.0));
        let sum = (a + b).as_dvec3();
        let sq = f64::from(luminance(a)).powi(2) + f64::from(luminance(b)).powi(2);
        assert!((relative_noise(sum, sq, 2) - 0.5).abs() < 1e-6);
        assert_eq!(relative_noise(DVec3::ZERO, 0.0, 16), 0.0, "black converges");
        assert_eq!(relative_noise(DVec3::ONE, 1.0, 1), f64::INFINITY, "one sample says nothing");
        let rule = AdaptiveSampling { threshold: 0.6, min_samples: 16 };
        assert!(rule.converged(sum, sq, 2));
        assert!(!AdaptiveSampling { threshold: 0.4, ..rule }.converged(sum, sq, 2));
        assert!(rule.tests_at(16) && rule.tests_at(24) && !rule.tests_at(8) && !rule.tests_at(20));
        assert!(!AdaptiveSampling { min_samples: 0, ..rule }.tests_at(0));
    }
}
