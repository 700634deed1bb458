//! Image metrics: how far a render is from a reference, one definition for every tool and test.
//!
//! All statistics are computed in `f64` over every channel value (H×W×3): non-finite candidate
//! values are counted and replaced by 0; **RMSE** is `sqrt(mean((c − r)²))` and **relative
//! MSE** `mean((c − r)² / (r² + ε))` with ε = [`REL_MSE_EPSILON`] = 1e-2, both averaged over all
//! channel values; the **mean ratio** is the per-channel image mean of the candidate over that of
//! the reference; and `z = (c − r) / sqrt(max(σ_r² + σ_c², 1e-12))` is taken per channel value,
//! its mean and (population) standard deviation and the fractions `|z| > 3` and `|z| > 4` over
//! all of them. These are the statistics (and the ε) of the script that scored the Mitsuba 3
//! references furnace is checked against, so figures compare across tools.
//!
//! ```
//! use furnace_post::metrics::{ErrorSum, score};
//! use glam::Vec3;
//! let reference = [Vec3::splat(0.5), Vec3::ONE];
//! let candidate = [Vec3::splat(0.5), Vec3::splat(1.5)];
//! let s = score(&candidate, &reference, None, None)?;
//! assert!((s.rmse - (0.75f64 / 6.0).sqrt()).abs() < 1e-12);
//! let mut e = ErrorSum::default();
//! e.add(1.5, 1.0);
//! assert!((e.rel_mse() - 0.25 / 1.01).abs() < 1e-12);
//! # Ok::<(), furnace_post::metrics::MetricsError>(())
//! ```

use glam::Vec3;

/// ε of the relative MSE, `(c − r)² / (r² + ε)`: keeps dark reference values from dominating.
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Relative error floor of the z statistics, `10⁻⁶ · reference`: f32 images of tens of thousands
/// of samples are not exact to better than that, so a pixel that is the same in every sample
/// (an emitter seen directly) does not count as a 100σ deviation.
pub const Z_ROUNDING_FLOOR: f64 = 1e-6;

/// Floor of the summed variance in the z-score.
const VAR_FLOOR: f64 = 1e-12;

/// Statistics of the per-value z-scores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZStats {
    /// Mean of z.
    pub mean: f64,
    /// Population standard deviation of z (NumPy's `std`, ddof 0).
    pub std: f64,
    /// Fraction of values with |z| > 3.
    pub frac_gt3: f64,
    /// Fraction of values with |z| > 4.
    pub frac_gt4: f64,
}

/// The scores of a candidate against a reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Scores {
    /// Root mean squared error over all channel values.
    pub rmse: f64,
    /// Mean of `(c − r)² / (r² + ε)` over all channel values ([`REL_MSE_EPSILON`]).
    pub rel_mse: f64,
    /// Candidate mean / reference mean, per channel.
    pub mean_ratio: [f64; 3],
    /// Number of non-finite candidate channel values (counted as 0 everywhere else).
    pub nonfinite: usize,
    /// z-score statistics, when the reference's standard error is given.
    pub z: Option<ZStats>,
}

pub(crate) fn channels(v: Vec3) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// A candidate value as the metrics use it: non-finite → 0.
fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() { x } else { 0.0 }
}

/// Scores `candidate` against `reference` (pixels in the same order). `ref_stderr` enables the
/// z statistics; `cand_stderr` adds the candidate's variance to them. All slices must have the
/// same length.
pub fn score(
    candidate: &[Vec3],
    reference: &[Vec3],
    ref_stderr: Option<&[Vec3]>,
    cand_stderr: Option<&[Vec3]>,
) -> Result<Scores, MetricsError> {
    let n = reference.len();
    if candidate.len() != n
        || ref_stderr.is_some_and(|s| s.len() != n)
        || cand_stderr.is_some_and(|s| s.len() != n)
    {
        return Err(MetricsError::SizeMismatch);
    }
    if n == 0 {
        return Err(MetricsError::Empty);
    }
    let values = (3 * n) as f64;
    let mut nonfinite = 0usize;
    let mut errors = ErrorSum::default();
    let (mut sum_c, mut sum_r) = ([0.0f64; 3], [0.0f64; 3]);
    for (&c, &r) in candidate.iter().zip(reference) {
        let (c, r) = (channels(c), channels(r));
        for k in 0..3 {
            if !c[k].is_finite() {
                nonfinite += 1;
            }
            let ck = finite_or_zero(c[k]);
            errors.add(ck, r[k]);
            sum_c[k] += ck;
            sum_r[k] += r[k];
        }
    }
    let z = ref_stderr.map(|sref| {
        let zs: Vec<f64> = (0..n)
            .flat_map(|i| {
                let (c, r, s) = (channels(candidate[i]), channels(reference[i]), channels(sref[i]));
                let sc = cand_stderr.map_or([0.0; 3], |sc| channels(sc[i]));
                (0..3).map(move |k| {
                    // Float rounding floors the error: a reference pixel whose every sample is
                    // the same (an emitter filling it) has a "standard error" of f32 rounding.
                    let rounding = Z_ROUNDING_FLOOR * r[k];
                    let var = (s[k] * s[k] + sc[k] * sc[k]).max(rounding * rounding);
                    (finite_or_zero(c[k]) - r[k]) / var.max(VAR_FLOOR).sqrt()
                })
            })
            .collect();
        let mean = zs.iter().sum::<f64>() / values;
        let var = zs.iter().map(|z| (z - mean) * (z - mean)).sum::<f64>() / values;
        let frac = |t: f64| zs.iter().filter(|z| z.abs() > t).count() as f64 / values;
        ZStats { mean, std: var.sqrt(), frac_gt3: frac(3.0), frac_gt4: frac(4.0) }
    });
    Ok(Scores {
        rmse: errors.rmse(),
        rel_mse: errors.rel_mse(),
        mean_ratio: [0, 1, 2].map(|k| sum_c[k] / sum_r[k]),
        nonfinite,
        z,
    })
}

/// Why two images cannot be scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum MetricsError {
    /// The candidate, the reference and the standard errors do not have the same pixel count.
    #[error("images of different sizes")]
    SizeMismatch,
    /// No pixels.
    #[error("empty images")]
    Empty,
}

/// Running sums of squared and relative squared errors over channel values: RMSE, MSE and
/// relative MSE as defined above, for callers that visit values their own way.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ErrorSum {
    squared: f64,
    relative: f64,
    values: u64,
}

impl ErrorSum {
    /// Adds one channel value of the candidate and the reference's.
    #[inline]
    pub fn add(&mut self, candidate: f64, reference: f64) {
        let d = candidate - reference;
        self.squared += d * d;
        self.relative += d * d / (reference * reference + REL_MSE_EPSILON);
        self.values += 1;
    }

    /// Adds the three channels of a pixel.
    #[inline]
    pub fn add_rgb(&mut self, candidate: [f64; 3], reference: [f64; 3]) {
        for k in 0..3 {
            self.add(candidate[k], reference[k]);
        }
    }

    /// Channel values added.
    pub fn values(&self) -> u64 {
        self.values
    }

    /// Mean squared error (0 without values).
    pub fn mse(&self) -> f64 {
        if self.values == 0 { 0.0 } else { self.squared / self.values as f64 }
    }

    /// Root mean squared error.
    pub fn rmse(&self) -> f64 {
        self.mse().sqrt()
    }

    /// Relative MSE, `mean((c − r)² / (r² + ε))`.
    pub fn rel_mse(&self) -> f64 {
        if self.values == 0 { 0.0 } else { self.relative / self.values as f64 }
    }
}

/// The error map: per pixel the mean over channels of |c − r| (non-finite candidate values as
/// 0), divided by its 99th percentile (linear interpolation, as NumPy's default) so that the
/// 99th percentile is white, clamped to [0, 1]. Grey, linear (encode with sRGB for display).
pub fn error_map(candidate: &[Vec3], reference: &[Vec3]) -> Vec<Vec3> {
    let err: Vec<f64> = candidate
        .iter()
        .zip(reference)
        .map(|(&c, &r)| {
            let (c, r) = (channels(c), channels(r));
            (0..3).map(|k| (finite_or_zero(c[k]) - r[k]).abs()).sum::<f64>() / 3.0
        })
        .collect();
    let mut sorted: Vec<f64> = err.iter().copied().filter(|e| e.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let p99 = percentile(&sorted, 0.99);
    // All-equal images (or a p99 of 0): scale by the maximum instead, or leave black.
    let scale = if p99 > 0.0 { p99 } else { sorted.last().copied().unwrap_or(0.0) };
    err.iter()
        .map(|&e| {
            let v = if scale > 0.0 && e.is_finite() { (e / scale).clamp(0.0, 1.0) } else { 0.0 };
            Vec3::splat(v as f32)
        })
        .collect()
}

/// The `q` quantile of sorted values, interpolating linearly between ranks (0 when empty).
fn percentile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => 0.0,
        n => {
            let pos = q * (n - 1) as f64;
            let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
            sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + b.abs())
    }

    #[test]
    fn identical_images_score_zero_error_and_unit_ratio() {
        let img = [Vec3::new(0.5, 1.0, 2.0), Vec3::new(0.25, 0.1, 3.0)];
        let se = [Vec3::splat(0.1); 2];
        let s = score(&img, &img, Some(&se), None).unwrap();
        assert_eq!((s.rmse, s.rel_mse, s.nonfinite), (0.0, 0.0, 0));
        assert_eq!(s.mean_ratio, [1.0; 3]);
        assert_eq!(s.z, Some(ZStats { mean: 0.0, std: 0.0, frac_gt3: 0.0, frac_gt4: 0.0 }));
    }

    #[test]
    fn constant_offset_gives_known_numbers() {
        // r = 1 everywhere, c = 1.5, σ_r = 0.125: d = 0.5, rel = 0.25 / 1.01, ratio 1.5,
        // z = 0.5 / 0.125 = 4 exactly (|z| > 4 is strict, as in compare.py).
        let r = [Vec3::ONE; 4];
        let c = [Vec3::splat(1.5); 4];
        let se = [Vec3::splat(0.125); 4];
        let s = score(&c, &r, Some(&se), None).unwrap();
        assert!(close(s.rmse, 0.5), "{s:?}");
        assert!(close(s.rel_mse, 0.25 / 1.01), "{s:?}");
        assert!(s.mean_ratio.iter().all(|&m| close(m, 1.5)), "{s:?}");
        assert_eq!(s.z, Some(ZStats { mean: 4.0, std: 0.0, frac_gt3: 1.0, frac_gt4: 0.0 }));
        // The candidate's stderr adds in quadrature: z = 0.5 / sqrt(2 · 0.125²) = 2.83.
        let z = score(&c, &r, Some(&se), Some(&se)).unwrap().z.unwrap();
        assert!(close(z.mean, 0.5 / (2.0f64 * 0.015625).sqrt()), "{z:?}");
        assert_eq!((z.frac_gt3, z.frac_gt4), (0.0, 0.0));
    }

    #[test]
    fn mixed_offsets_per_channel() {
        // One pixel, offsets (+0.1, −0.1, 0) on r = (0, 1, 2): RMSE sqrt(0.02 / 3),
        // rel (0.01/0.01 + 0.01/1.01 + 0) / 3; z = (+1, −1, 0) → mean 0, std sqrt(2/3).
        let r = [Vec3::new(0.0, 1.0, 2.0)];
        let c = [Vec3::new(0.1, 0.9, 2.0)];
        let se = [Vec3::splat(0.1)];
        let s = score(&c, &r, Some(&se), None).unwrap();
        assert!((s.rmse - (0.02f64 / 3.0).sqrt()).abs() < 1e-7, "{s:?}");
        assert!((s.rel_mse - (1.0 + 0.01 / 1.01) / 3.0).abs() < 1e-6, "{s:?}");
        assert!(s.mean_ratio[0].is_infinite() && (s.mean_ratio[1] - 0.9).abs() < 1e-7);
        let z = s.z.unwrap();
        assert!(z.mean.abs() < 1e-6 && (z.std - (2.0f64 / 3.0).sqrt()).abs() < 1e-5, "{z:?}");
    }

    #[test]
    fn nonfinite_candidate_values_count_as_zero() {
        let r = [Vec3::ONE, Vec3::ONE];
        let c = [Vec3::new(f32::NAN, 1.0, f32::INFINITY), Vec3::ONE];
        let s = score(&c, &r, None, None).unwrap();
        assert_eq!(s.nonfinite, 2);
        assert!(close(s.rmse, (2.0f64 / 6.0).sqrt()), "{s:?}");
        assert!(close(s.mean_ratio[0], 0.5) && close(s.mean_ratio[1], 1.0), "{s:?}");
        assert!(s.z.is_none());
    }

    /// A pixel on an emitter: every sample the same, the reference's error f32 rounding; a
    /// candidate off by 10⁻⁷ relative is not a deviation.
    #[test]
    fn float_rounding_floors_the_error() {
        let r = Vec3::splat(0.2);
        let s = score(&[r * (1.0 + 1e-7)], &[r], Some(&[Vec3::splat(1e-9)]), None).unwrap();
        assert!(s.z.unwrap().mean.abs() < 0.2, "{s:?}");
    }

    #[test]
    fn zero_stderr_is_floored() {
        let s = score(&[Vec3::splat(1e-6)], &[Vec3::ZERO], Some(&[Vec3::ZERO]), None).unwrap();
        assert!((s.z.unwrap().mean - 1e-6 / 1e-6).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn size_mismatch_and_empty_are_errors() {
        assert!(score(&[Vec3::ONE], &[Vec3::ONE; 2], None, None).is_err());
        assert!(score(&[Vec3::ONE], &[Vec3::ONE], Some(&[]), None).is_err());
        assert!(score(&[], &[], None, None).is_err());
    }

    #[test]
    fn error_map_maps_the_99th_percentile_to_white() {
        // 200 pixels with errors 0..199: p99 = 197.01; the largest two clamp to 1.
        let r = vec![Vec3::ZERO; 200];
        let c: Vec<Vec3> = (0..200).map(|i| Vec3::splat(i as f32)).collect();
        let m = error_map(&c, &r);
        assert_eq!(m[0], Vec3::ZERO);
        assert!((m[100].x - (100.0 / 197.01) as f32).abs() < 1e-6, "{}", m[100]);
        assert_eq!((m[198], m[199]), (Vec3::ONE, Vec3::ONE));
        // Identical images: all black, no division by zero.
        assert!(error_map(&r, &r).iter().all(|&p| p == Vec3::ZERO));
    }

    #[test]
    fn error_sum_is_the_score_s_rmse_and_rel_mse() {
        let r = [Vec3::new(0.0, 1.0, 2.0), Vec3::splat(0.5)];
        let c = [Vec3::new(0.1, 0.9, 2.5), Vec3::splat(0.25)];
        let s = score(&c, &r, None, None).unwrap();
        let mut e = ErrorSum::default();
        for (c, r) in c.iter().zip(&r) {
            e.add_rgb(channels(*c), channels(*r));
        }
        assert_eq!((e.rmse(), e.rel_mse(), e.values()), (s.rmse, s.rel_mse, 6));
        assert_eq!(ErrorSum::default().rel_mse(), 0.0);
    }
}
