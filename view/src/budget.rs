//! How many samples per pixel a frame renders: as many as fit the frame's time budget, from
//! the measured cost of the frames before (the GPU's passes block until done, so a pass's wall
//! time is its cost).

/// The frame budget while the user moves the camera or drags a slider: 30 frames per second.
pub const INTERACTIVE_SECONDS: f64 = 1.0 / 30.0;
/// The frame budget while nothing moves: larger passes (less overhead per sample) while the
/// window still answers within about 70 ms.
pub const STILL_SECONDS: f64 = 1.0 / 15.0;
/// The most samples per pixel of one frame.
pub const MAX_SAMPLES: u32 = 256;

/// The measured cost of a sample per pixel and the choice it gives.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameBudget {
    /// Seconds per sample per pixel (exponential average), once a frame was measured.
    seconds_per_spp: Option<f64>,
    /// The samples of the last frame (the next may at most double it).
    last: u32,
}

impl FrameBudget {
    /// Samples per pixel for a frame of `budget` seconds, at most `cap` (and at most twice the
    /// last frame's, so that one cheap frame does not make the next a long one), at least 1.
    pub fn samples(&self, budget: f64, cap: u32) -> u32 {
        let cap = cap.clamp(1, MAX_SAMPLES);
        let Some(t) = self.seconds_per_spp.filter(|t| *t > 0.0) else {
            return 1;
        };
        let fit = (budget / t).floor().clamp(1.0, f64::from(MAX_SAMPLES)) as u32;
        fit.min(self.last.max(1).saturating_mul(2)).min(cap).max(1)
    }

    /// Records a frame of `spp` samples per pixel that took `seconds`.
    pub fn record(&mut self, spp: u32, seconds: f64) {
        if spp == 0 || !seconds.is_finite() || seconds < 0.0 {
            return;
        }
        let t = seconds / f64::from(spp);
        self.seconds_per_spp = Some(match self.seconds_per_spp {
            None => t,
            Some(old) => 0.5 * old + 0.5 * t,
        });
        self.last = spp;
    }

    /// Forgets the cost (a new scene size or settings: the next frame is measured afresh).
    pub fn forget(&mut self) {
        *self = Self::default();
    }

    /// The measured seconds per sample per pixel.
    pub fn seconds_per_spp(&self) -> Option<f64> {
        self.seconds_per_spp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_at_one_sample_then_fits_the_budget_growing_at_most_twofold() {
        let mut b = FrameBudget::default();
        assert_eq!(b.samples(STILL_SECONDS, 64), 1);
        b.record(1, 0.001); // 1 ms per spp: 66 fit a still frame
        assert_eq!(b.samples(STILL_SECONDS, 1000), 2, "at most twice the last frame");
        for _ in 0..10 {
            let n = b.samples(STILL_SECONDS, 1000);
            b.record(n, f64::from(n) * 0.001);
        }
        assert_eq!(b.samples(STILL_SECONDS, 1000), 66);
        assert_eq!(b.samples(INTERACTIVE_SECONDS, 1000), 33);
        assert_eq!(b.samples(STILL_SECONDS, 5), 5, "the cap (samples left to the target)");
    }

    #[test]
    fn a_slow_device_renders_one_sample_per_frame() {
        let mut b = FrameBudget::default();
        b.record(1, 2.0);
        assert_eq!(b.samples(INTERACTIVE_SECONDS, 64), 1);
        b.record(1, f64::NAN); // ignored
        assert_eq!(b.seconds_per_spp(), Some(2.0));
        b.forget();
        assert_eq!(b.seconds_per_spp(), None);
    }
}
