//! [`Session`]: a progressive render — passes of a few samples per pixel added to an
//! [`Integrator`]'s film until a [`Budget`] is spent or the caller cancels, with a progress
//! report after every pass. `furnace render`, `chart`, `bench` (and the viewer) drive their
//! integrators through it.

use crate::{Film, Integrator, RenderError};
use std::time::Instant;

/// When a session stops. The first limit reached ends it; at least one pass is rendered by a
/// run that has samples left to render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Samples per pixel the film should reach (the total, counting a resumed film's).
    pub spp: u32,
    /// Stop *before* a pass that would, at the mean pass time so far, end past this many seconds
    /// of this run (a render's `--time-limit`).
    pub time_limit: Option<f64>,
    /// Stop *after* the first pass that ends at or past this many seconds of this run (a
    /// benchmark's minimum measuring time).
    pub min_seconds: Option<f64>,
}

impl Budget {
    /// Up to `spp` samples per pixel, no time limit.
    pub fn spp(spp: u32) -> Self {
        Self { spp, time_limit: None, min_seconds: None }
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// The film has the budget's samples per pixel.
    Finished,
    /// A time limit of the budget.
    TimeLimit,
    /// The caller's cancellation (Ctrl-C); the film holds every pass finished before it.
    Cancelled,
    /// Adaptive sampling: every pixel has converged (before the budget's spp).
    Converged,
}

/// Time spent in the passes of a session, all runs together.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timing {
    /// Wall seconds of the `render_pass` calls, nothing else.
    pub wall: f64,
    /// Process CPU seconds (user + system, all threads) of those calls, at 10 ms resolution, when
    /// the session measures them ([`Session::measure_cpu_time`]); NaN otherwise, or where the
    /// platform does not report it (see [`process_cpu_seconds`]).
    pub cpu: f64,
    /// Device seconds of the passes where the integrator measures them
    /// ([`Integrator::last_pass_device_seconds`]); 0 otherwise.
    pub device: f64,
    /// Passes rendered.
    pub passes: u64,
}

/// What a progress callback is told after each pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Samples per pixel in the film now.
    pub done: u32,
    /// The budget's samples per pixel.
    pub target: u32,
    /// Samples per pixel added by the pass just finished.
    pub pass: u32,
    /// Samples per pixel the film had when the session began.
    pub first: u32,
    /// Wall seconds since the current run began.
    pub elapsed: f64,
    /// Samples (pixels × samples per pixel) per second added by this run so far, in millions
    /// (counting converged pixels as if they took their samples).
    pub msamples_per_s: f64,
    /// With adaptive sampling: the fraction of pixels converged.
    pub converged: Option<f64>,
}

/// A progressive render of one integrator, from the samples its film already has.
pub struct Session<'a> {
    integrator: &'a mut dyn Integrator,
    first: u32,
    done: u32,
    timing: Timing,
    cpu_time: bool,
}

impl std::fmt::Debug for Session<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("integrator", &self.integrator.name())
            .field("first", &self.first)
            .field("done", &self.done)
            .field("timing", &self.timing)
            .finish()
    }
}

impl<'a> Session<'a> {
    /// A session continuing `integrator`'s film, which holds samples `0..done` of every pixel
    /// (0 for a new render; a resumed render's recorded spp).
    pub fn new(integrator: &'a mut dyn Integrator, done: u32) -> Self {
        Self { integrator, first: done, done, timing: Timing::default(), cpu_time: false }
    }

    /// Whether passes also measure the process's CPU time ([`Timing::cpu`]; off by default: it
    /// reads `/proc/self/stat` twice a pass, ≈ 0.3 % of a 15 ms GPU pass).
    pub fn measure_cpu_time(&mut self, on: bool) {
        self.cpu_time = on;
    }

    /// Samples per pixel in the film now: the next pass starts at this sample index.
    pub fn done(&self) -> u32 {
        self.done
    }

    /// Samples per pixel the film had when the session began.
    pub fn first(&self) -> u32 {
        self.first
    }

    /// Time spent in passes so far.
    pub fn timing(&self) -> Timing {
        self.timing
    }

    /// The integrator.
    pub fn integrator(&mut self) -> &mut dyn Integrator {
        self.integrator
    }

    /// The film so far.
    ///
    /// # Errors
    /// The integrator's ([`Integrator::film`]).
    pub fn film(&mut self) -> Result<Film, RenderError> {
        self.integrator.film()
    }

    /// Renders passes of [`Integrator::pass_samples`] samples per pixel (the last one shorter, to
    /// end at the budget's spp) until the budget is spent or `cancel` returns `true` (asked
    /// before every pass) or the integrator stops a pass at its [`crate::CancelFlag`]
    /// ([`Stop::Cancelled`], the samples it finished counted), calling `progress` after each
    /// whole pass. Can be called again with a larger
    /// budget to continue (a chart's checkpoints); time limits count from the start of each run.
    ///
    /// # Errors
    /// The integrator's; the film then holds the passes finished before the failing one.
    pub fn run(
        &mut self,
        budget: &Budget,
        cancel: &dyn Fn() -> bool,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Stop, RenderError> {
        let start = Instant::now();
        let run_first = self.done;
        let pixels =
            f64::from(self.integrator.settings().width) * f64::from(self.integrator.settings().height);
        while self.done < budget.spp {
            if cancel() {
                return Ok(Stop::Cancelled);
            }
            if self.integrator.converged_pixels().is_some_and(|c| c as f64 >= pixels) {
                return Ok(Stop::Converged);
            }
            let elapsed = start.elapsed().as_secs_f64();
            let per_pass = self.integrator.pass_samples().max(1);
            if self.done > run_first {
                if let Some(limit) = budget.time_limit {
                    // At the mean pass time so far, would the next pass end past the limit?
                    let passes = f64::from(self.done - run_first) / f64::from(per_pass);
                    if elapsed + elapsed / passes.max(1.0) > limit {
                        return Ok(Stop::TimeLimit);
                    }
                }
                if budget.min_seconds.is_some_and(|m| elapsed >= m) {
                    return Ok(Stop::TimeLimit);
                }
            }
            let n = per_pass.min(budget.spp - self.done);
            let measure = self.cpu_time;
            let cpu_seconds = || if measure { process_cpu_seconds() } else { None };
            let (wall, cpu) = (Instant::now(), cpu_seconds());
            // A pass stopped by the integrator's cancel flag keeps its whole samples.
            let (n, interrupted) = match self.integrator.render_pass(self.done, n) {
                Ok(()) => (n, false),
                Err(RenderError::Interrupted { samples }) => (samples.min(n), true),
                Err(e) => return Err(e),
            };
            self.timing.wall += wall.elapsed().as_secs_f64();
            self.timing.cpu += match (cpu, cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            };
            self.timing.device += self.integrator.last_pass_device_seconds().unwrap_or(0.0);
            self.timing.passes += 1;
            self.done += n;
            if interrupted {
                return Ok(Stop::Cancelled);
            }
            let elapsed = start.elapsed().as_secs_f64();
            let converged = self.integrator.converged_pixels();
            progress(&Progress {
                done: self.done,
                target: budget.spp,
                pass: n,
                first: self.first,
                elapsed,
                msamples_per_s: pixels * f64::from(self.done - run_first) / elapsed.max(1e-9) / 1e6,
                converged: converged.map(|c| c as f64 / pixels.max(1.0)),
            });
            if converged.is_some_and(|c| c as f64 >= pixels) && self.done < budget.spp {
                return Ok(Stop::Converged);
            }
        }
        Ok(Stop::Finished)
    }
}

/// CPU time of this process so far (user + system, all threads), in seconds at the kernel's
/// `USER_HZ` resolution of 1/100 s, from `/proc/self/stat`; `None` where that does not exist.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name: state is field 3, utime 14, stime 15.
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i - 3).and_then(|v| v.parse::<u64>().ok());
    // USER_HZ is 100 on every Linux architecture's /proc ABI.
    Some((ticks(14)? + ticks(15)?) as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RenderSettings;
    use glam::Vec3;

    /// An integrator whose sample `i` of every pixel is `i`: the film tells which samples it got.
    struct Counting {
        settings: RenderSettings,
        film: Film,
        passes: Vec<(u32, u32)>,
        pass_samples: u32,
        fail_at: Option<u32>,
        /// A pass containing this sample stops after the samples before it.
        interrupt_at: Option<u32>,
    }

    impl Counting {
        fn new(pass_samples: u32) -> Self {
            let settings = RenderSettings { width: 2, height: 2, ..Default::default() };
            Self {
                settings,
                film: Film::new(2, 2),
                passes: Vec::new(),
                pass_samples,
                fail_at: None,
                interrupt_at: None,
            }
        }
    }

    impl Integrator for Counting {
        fn name(&self) -> &'static str {
            "counting"
        }
        fn describe(&self) -> String {
            "counting: test".into()
        }
        fn settings(&self) -> &RenderSettings {
            &self.settings
        }
        fn render_pass(&mut self, first: u32, n: u32) -> Result<(), RenderError> {
            if self.fail_at.is_some_and(|f| (first..first + n).contains(&f)) {
                return Err(RenderError::Device("device lost".into()));
            }
            self.passes.push((first, n));
            let stop = self.interrupt_at.filter(|s| (first..first + n).contains(s));
            for i in first..stop.unwrap_or(first + n) {
                for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    self.film.add_sample(x, y, Vec3::splat(i as f32));
                }
            }
            match stop {
                Some(s) => Err(RenderError::Interrupted { samples: s - first }),
                None => Ok(()),
            }
        }
        fn film(&mut self) -> Result<Film, RenderError> {
            Ok(self.film.clone())
        }
        fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
            RenderError::check_film(film, &self.settings)?;
            self.film = film.clone();
            Ok(())
        }
        fn pass_samples(&self) -> u32 {
            self.pass_samples
        }
    }

    #[test]
    fn a_pass_stopped_by_its_integrator_keeps_its_whole_samples_and_cancels() {
        let mut c = Counting::new(4);
        c.interrupt_at = Some(6);
        let mut reports = Vec::new();
        let mut s = Session::new(&mut c, 0);
        assert_eq!(
            s.run(&Budget::spp(16), &|| false, &mut |p| reports.push(p.done)).unwrap(),
            Stop::Cancelled
        );
        // Pass 4..8 stopped at sample 6: samples 0..6 are in the film, and the next run goes on
        // from 6.
        assert_eq!(s.done(), 6);
        assert_eq!(reports, [4]);
        let film = s.film().unwrap();
        assert_eq!(film.sample_count(1, 1), 6);
        assert_eq!(film.pixel(1, 1).x, (0..6).sum::<u32>() as f64 / 6.0);
        c.interrupt_at = None;
        let mut s = Session::new(&mut c, 6);
        assert_eq!(s.run(&Budget::spp(8), &|| false, &mut |_| ()).unwrap(), Stop::Finished);
        assert_eq!(s.film().unwrap().sample_count(0, 0), 8);
        assert_eq!(c.passes, [(0, 4), (4, 4), (6, 2)]);
    }

    #[test]
    fn runs_to_the_budget_in_passes_and_continues() {
        let mut c = Counting::new(3);
        let mut reports = Vec::new();
        {
            let mut s = Session::new(&mut c, 0);
            assert_eq!(
                s.run(&Budget::spp(7), &|| false, &mut |p| reports.push(p.done)).unwrap(),
                Stop::Finished
            );
            assert_eq!(
                s.run(&Budget::spp(8), &|| false, &mut |p| reports.push(p.done)).unwrap(),
                Stop::Finished
            );
            assert_eq!(s.done(), 8);
            assert_eq!(s.timing().passes, 4);
            // Samples 0..8 once each: the mean of 0..=7.
            assert_eq!(s.film().unwrap().pixel(1, 1), glam::DVec3::splat(3.5));
        }
        assert_eq!(c.passes, [(0, 3), (3, 3), (6, 1), (7, 1)]);
        assert_eq!(reports, [3, 6, 7, 8]);
    }

    #[test]
    fn a_resumed_session_starts_at_its_samples() {
        let mut c = Counting::new(4);
        let mut s = Session::new(&mut c, 5);
        s.run(&Budget::spp(6), &|| false, &mut |_| {}).unwrap();
        assert_eq!(s.first(), 5);
        assert_eq!(c.passes, [(5, 1)]);
    }

    #[test]
    fn cancellation_is_asked_before_every_pass() {
        let mut c = Counting::new(1);
        let asked = std::cell::Cell::new(0);
        let cancel = || {
            asked.set(asked.get() + 1);
            asked.get() > 2
        };
        let stop = Session::new(&mut c, 0).run(&Budget::spp(10), &cancel, &mut |_| {}).unwrap();
        assert_eq!(stop, Stop::Cancelled);
        assert_eq!(c.passes.len(), 2);
    }

    #[test]
    fn time_limits_render_at_least_one_pass() {
        for budget in [
            Budget { time_limit: Some(0.0), ..Budget::spp(10) },
            Budget { min_seconds: Some(0.0), ..Budget::spp(10) },
        ] {
            let mut c = Counting::new(2);
            assert_eq!(
                Session::new(&mut c, 0).run(&budget, &|| false, &mut |_| {}).unwrap(),
                Stop::TimeLimit
            );
            assert_eq!(c.passes, [(0, 2)], "{budget:?}");
        }
    }

    #[test]
    fn an_error_keeps_the_passes_before_it() {
        let mut c = Counting::new(2);
        c.fail_at = Some(4);
        let mut s = Session::new(&mut c, 0);
        let e = s.run(&Budget::spp(10), &|| false, &mut |_| {}).unwrap_err();
        assert_eq!(e.to_string(), "device lost");
        assert_eq!(s.done(), 4);
        assert_eq!(s.film().unwrap().sample_count(0, 0), 4);
    }

    #[test]
    fn process_cpu_time_grows_with_work() {
        let Some(t0) = process_cpu_seconds() else { return };
        // Spin for 200 ms of wall time: the process's CPU time cannot fall, and grows by at
        // least one 10 ms tick even if a busy machine gives us a tenth of a core.
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while start.elapsed().as_millis() < 200 {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        let t1 = process_cpu_seconds().unwrap();
        assert!(t1 >= t0 + 0.01, "{t0} {t1}");
    }
}
