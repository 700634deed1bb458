//! How a pass is cut into dispatches: blocks of samples (adaptive sampling's test points),
//! dispatches of a few rows × a few samples bounded by a watchdog budget and fitted to their
//! measured time ([`DispatchSizing`]), workgroup tiles of pixels × invocations per pixel
//! ([`tile_of`]), and the choice of invocations per pixel ([`hardware_group_samples`],
//! [`GroupTuner`]). Films do not depend on any of it, bit for bit.

use super::GROUP_SIZE;

/// Uniform slots are this far apart (WebGPU's largest `min_uniform_buffer_offset_alignment`).
pub(super) const SLOT: u64 = 256;

/// A block of a pass: samples `first..end`, then (with `converge`) adaptive sampling's test.
#[derive(Debug, Clone, Copy)]
pub(super) struct Block {
    pub(super) first: u32,
    pub(super) end: u32,
    pub(super) converge: bool,
}

/// One dispatch of a pass: rows `row_offset ..` × samples `first_sample ..`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Dispatch {
    pub(super) row_offset: u32,
    pub(super) rows: u32,
    pub(super) first_sample: u32,
    pub(super) samples: u32,
}

/// One step of a pass's submission: a dispatch of samples (its uniform slot, workgroup rows and
/// tile width) or the adaptive-sampling test after a block.
#[derive(Debug, Clone, Copy)]
pub(super) enum Step {
    Samples { slot: usize, groups_y: u32, tile_width: u32 },
    Converge,
}

/// The most invocations per pixel on hardware adapters: 16, where throughput stops growing on
/// small images (`furnace bench --group-samples N`, BENCHMARKS.md): a 256² image alone does not
/// fill a large GPU.
pub(super) const HARDWARE_GROUP_SAMPLES: u32 = 16;

/// Invocations per pixel on a hardware adapter for an image of `pixels` pixels: the largest
/// power of two up to `HARDWARE_GROUP_SAMPLES` whose dispatch of every pixel stays within
/// `samples_per_dispatch` invocations (at least 1). Small images get 16 invocations per pixel to
/// fill the GPU; large ones few, so that one dispatch covers the whole image: an image cut into
/// dispatches of unequal rows leaves the GPU idle behind the last one (BENCHMARKS.md).
pub fn hardware_group_samples(pixels: u64, samples_per_dispatch: u64) -> u32 {
    let mut n = HARDWARE_GROUP_SAMPLES;
    while n > 1 && pixels * u64::from(n) > samples_per_dispatch {
        n /= 2;
    }
    n
}

/// The tile of a workgroup with `group_samples` invocations per pixel: (width, height) pixels,
/// as square as powers of two allow (width ≥ height).
pub fn tile(group_samples: u32) -> (u32, u32) {
    tile_of(GROUP_SIZE, group_samples)
}

/// [`tile`] for workgroups of `group_size` invocations (a multiple of 32: the width is a power of
/// two, the height what is left).
pub fn tile_of(group_size: u32, group_samples: u32) -> (u32, u32) {
    let pixels = group_size / group_samples;
    let width = 1 << pixels.trailing_zeros().div_ceil(2);
    (width, pixels / width)
}

/// Chooses between the image-size rule's invocations per pixel ([`hardware_group_samples`]) and
/// one per pixel by timing passes, as a render's first passes alternate them. The rule fills the
/// GPU with several samples of a pixel side by side; one invocation per pixel runs all of a
/// pixel's samples one after another, a lane whose path ends starting the next (path
/// regeneration), which wins where path lengths differ a lot. Which one is faster depends on
/// the scene, not on a size or a bounce count that could be read beforehand: the sunlit interior
/// is faster at one per pixel, the Cornell box of as many triangles slower (BENCHMARKS.md). The
/// film does not depend on the choice, bit for bit, so trying both costs no
/// image; after one pass left unmeasured (the GPU's clocks may still be rising), each candidate
/// is measured [`GroupTuner::TRIALS`] times, in turn, and its fastest pass counts.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupTuner {
    /// The rule's choice and the alternative, 1.
    candidates: [u32; 2],
    /// Per candidate: its fastest pass so far, in seconds per sample of every pixel, and the
    /// number of its passes measured.
    best: [f64; 2],
    measured: [u32; 2],
    /// Whether the first pass, left unmeasured, has run.
    settled: bool,
    /// The decision, once both candidates have had their trials.
    chosen: Option<u32>,
}

impl GroupTuner {
    /// Timed passes per candidate before the choice.
    pub const TRIALS: u32 = 2;

    /// One invocation per pixel is chosen only if its fastest pass beats the rule's by this
    /// fraction (otherwise the rule's choice stays): a margin well above the run-to-run spread
    /// of one configuration's passes.
    pub const MARGIN: f64 = 0.02;

    /// A tuner between `rule` invocations per pixel and 1; `None` when the rule already gives 1.
    pub fn new(rule: u32) -> Option<Self> {
        (rule > 1).then_some(Self {
            candidates: [rule, 1],
            best: [f64::INFINITY; 2],
            measured: [0; 2],
            settled: false,
            chosen: None,
        })
    }

    /// The invocations per pixel the next pass should use: the choice once made, else the
    /// candidate with fewer measured passes (the alternative first, then in turn).
    pub fn next(&self) -> u32 {
        match self.chosen {
            Some(n) => n,
            None if self.measured[1] <= self.measured[0] => self.candidates[1],
            None => self.candidates[0],
        }
    }

    /// Whether the choice is made.
    pub fn chosen(&self) -> Option<u32> {
        self.chosen
    }

    /// Records a pass rendered at `group_samples` invocations per pixel that took `seconds` for
    /// `samples` samples of every pixel; passes at another value (a pass of fewer samples than
    /// the rule's choice is capped) are not the candidates' and are ignored.
    pub fn record(&mut self, group_samples: u32, samples: u32, seconds: f64) {
        if self.chosen.is_some() || samples == 0 || !(seconds > 0.0) {
            return;
        }
        let Some(k) = self.candidates.iter().position(|&c| c == group_samples) else { return };
        if !self.settled {
            self.settled = true;
            return;
        }
        self.best[k] = self.best[k].min(seconds / f64::from(samples));
        self.measured[k] += 1;
        if self.measured.iter().all(|&m| m >= Self::TRIALS) {
            let one_wins = self.best[1] < self.best[0] * (1.0 - Self::MARGIN);
            self.chosen = Some(if one_wins { self.candidates[1] } else { self.candidates[0] });
        }
    }
}

/// A pass whose predecessor took longer than this (seconds) is submitted dispatch by dispatch,
/// with the cancel flag polled between: a quarter of the one second within which Ctrl-C is to
/// be answered. Shorter passes stay one submission (no wait between dispatches).
pub(super) const LONG_PASS_SECONDS: f64 = 0.25;

/// A dispatch longer than this (seconds) makes the next ones smaller ([`DispatchSizing::fit`]):
/// a quarter of the second within which a cancel flag is to be answered.
const LONG_DISPATCH_SECONDS: f64 = 0.25;

/// Halvings of the dispatches for paths of up to `bounces` scattering events: none up to 16, else
/// as many as make a dispatch of paths that all reach the limit no longer than one of 16-bounce
/// paths (`⌈log₂((bounces + 1) / 17)⌉`: 6 at 1024); measured dispatch times correct it after
/// the first pass.
fn initial_dispatch_shift(bounces: u32) -> u32 {
    let ratio = (f64::from(bounces) + 1.0) / 17.0;
    if ratio > 1.0 { ratio.log2().ceil() as u32 } else { 0 }
}

/// How one device's passes are cut into dispatches: at most about
/// [`DispatchSizing::samples_per_dispatch`] samples each (so that no dispatch runs long enough to
/// trip a driver watchdog), halved while dispatches run long ([`DispatchSizing::fit`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct DispatchSizing {
    /// About how many samples one dispatch computes at most (the watchdog bound).
    pub(super) samples_per_dispatch: u64,
    /// Samples one invocation loops over at most (1 on software adapters).
    max_samples_per_invocation: u32,
    /// How many times dispatches are halved from `samples_per_dispatch`; for paths of more than
    /// 16 bounces it starts at what paths of every bounce would need.
    shift: u32,
}

impl DispatchSizing {
    /// The sizing on a software or hardware adapter for paths of up to `bounces` events.
    pub(super) fn new(software: bool, bounces: u32) -> Self {
        // Software adapters are slow and may end any shader loop after 65535 iterations per
        // invocation (all loops together): small dispatches, one sample per invocation there.
        let (samples_per_dispatch, max_samples_per_invocation) =
            if software { (1 << 16, 1) } else { (1 << 23, 8) };
        Self { samples_per_dispatch, max_samples_per_invocation, shift: initial_dispatch_shift(bounces) }
    }

    /// Whether this is a software adapter's sizing (one sample per invocation).
    pub(super) fn is_software(&self) -> bool {
        self.max_samples_per_invocation == 1
    }

    /// Whether dispatches are halved now (long paths, or a long dispatch measured).
    pub(super) fn is_halved(&self) -> bool {
        self.shift > 0
    }

    /// Samples per dispatch now: [`DispatchSizing::samples_per_dispatch`] halved `shift` times,
    /// so that a dispatch of long paths stays short enough for a cancel flag to be answered
    /// within a second ([`DispatchSizing::fit`]).
    fn dispatch_samples(&self) -> u64 {
        (self.samples_per_dispatch >> self.shift).max(1)
    }

    /// After a pass whose dispatches took `seconds` each (the longest, or the mean): halves the
    /// dispatches until one would take about a tenth of a second when one took more than
    /// [`LONG_DISPATCH_SECONDS`], doubles them back (up to
    /// [`DispatchSizing::samples_per_dispatch`]) when one took under a twentieth. Films do not
    /// depend on where dispatches are cut.
    pub(super) fn fit(&mut self, seconds: f64) {
        let max_shift = 63 - self.samples_per_dispatch.leading_zeros();
        if seconds > LONG_DISPATCH_SECONDS {
            let halvings = (seconds / 0.1).log2().ceil().max(1.0) as u32;
            self.shift = (self.shift + halvings).min(max_shift);
        } else if seconds < 0.05 && self.shift > 0 {
            self.shift -= 1;
        }
    }

    /// The dispatches of a pass of samples `first .. first + n` over an image of `width ×
    /// height`; each covers whole tiles of `tile_height` rows (the shader checks a pixel against
    /// the image, not against its dispatch's rows, so a dispatch must not end inside a tile).
    pub(super) fn dispatches(
        &self,
        (width, height): (u32, u32),
        first: u32,
        n: u32,
        group_samples: u32,
        tile_height: u32,
    ) -> Vec<Dispatch> {
        let (w, h) = (width.max(1), height.max(1));
        // Samples per pixel in one dispatch: a loop of up to max_samples_per_invocation, or one
        // per invocation of a group.
        let per_invocation = if group_samples > 1 {
            group_samples.min(n)
        } else {
            n.min(self.max_samples_per_invocation).max(1)
        };
        // At least one row, at most the image (an image shorter than a tile is one dispatch),
        // whole tiles.
        let rows = (self.dispatch_samples() / (u64::from(w) * u64::from(per_invocation)))
            .clamp(1, u64::from(h)) as u32;
        // As many dispatches as that needs, of equal heights: a thin last dispatch would leave
        // the GPU idle behind its few long paths.
        let rows = h.div_ceil(h.div_ceil(rows));
        let rows = rows.div_ceil(tile_height) * tile_height;
        let mut v = Vec::new();
        let mut s = 0;
        while s < n {
            let samples = per_invocation.min(n - s);
            let mut row = 0;
            while row < h {
                v.push(Dispatch {
                    row_offset: row,
                    rows: rows.min(h - row),
                    first_sample: first + s,
                    samples,
                });
                row += rows;
            }
            s += samples;
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_paths_start_with_smaller_dispatches() {
        let shifts: Vec<u32> = [0, 4, 16, 17, 33, 34, 1024].map(initial_dispatch_shift).to_vec();
        assert_eq!(shifts, [0, 0, 0, 1, 1, 2, 6]);
    }

    /// 16 per pixel while a whole-image dispatch stays within the budget, then halves.
    #[test]
    fn invocations_per_pixel_follow_the_image_size() {
        let budget = 1 << 23;
        for (w, h, n) in [
            (256, 256, 16),
            (512, 512, 16),
            (1024, 1024, 8),
            (1920, 1080, 4),
            (1920, 1440, 2),
            (3840, 2160, 1),
            (8192, 8192, 1),
            (1, 1, 16),
        ] {
            assert_eq!(hardware_group_samples(w * h, budget), n, "{w}×{h}");
        }
    }

    /// The tuner tries the alternative first, then each candidate in turn, ignores the first pass
    /// and passes at other values, and keeps the rule's choice unless one invocation per pixel is
    /// faster by more than the margin.
    #[test]
    fn group_tuner_times_both_and_keeps_the_rule_unless_one_wins() {
        assert_eq!(GroupTuner::new(1), None, "nothing to choose");
        let run = |rule_s: f64, one_s: f64| {
            let mut t = GroupTuner::new(4).unwrap();
            let mut order = Vec::new();
            while t.chosen().is_none() {
                let n = t.next();
                order.push(n);
                // A pass of 8 samples; a capped pass (2 per pixel) in between changes nothing.
                t.record(n, 8, 8.0 * if n == 1 { one_s } else { rule_s });
                t.record(2, 2, 1e-9);
                assert!(order.len() <= 5, "{order:?}");
            }
            (order, t.chosen().unwrap(), t.next())
        };
        // The first pass (at 1) unmeasured, then 1, 4, 1, 4.
        assert_eq!(run(1.0, 0.5), (vec![1, 1, 4, 1, 4], 1, 1));
        assert_eq!(run(1.0, 0.99), (vec![1, 1, 4, 1, 4], 4, 4), "within the margin: the rule");
        assert_eq!(run(0.5, 1.0).1, 4);
        // The fastest pass of each counts; nothing is recorded once chosen.
        let mut t = GroupTuner::new(2).unwrap();
        for (n, s) in [(1, 100.0), (1, 3.0), (2, 2.0), (1, 9.0), (2, 2.5)] {
            t.record(n, 1, s);
        }
        assert_eq!(t.chosen(), Some(2));
        t.record(1, 1, 0.1);
        assert_eq!(t.chosen(), Some(2));
        let mut t = GroupTuner::new(2).unwrap();
        for (n, s) in [(1, 100.0), (1, 1.0), (2, 2.0), (1, 9.0), (2, 2.5)] {
            t.record(n, 1, s);
        }
        assert_eq!(t.chosen(), Some(1));
    }
}
