//! Running the renders and measuring them: each configuration's backend (warmed up), timed
//! passes up to each checkpoint, the error against the reference, progress, and the rows
//! saved after every checkpoint.

use super::axes::Config;
use super::data::Row;
use super::save::save_data;
use super::study::Study;
use crate::args::{ChartBackend, Switch};
use crate::interrupt::Interrupt;
use crate::shared::WARM_UP_SECONDS;
use furnace_cli::backend::{self, Backend, BackendChoice};
use furnace_post::metrics::score;
use furnace_render::{Budget, Film, Integrator, RenderSettings, Session, Stop, Timing};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};
use std::time::Instant;

/// The integrator of `config`, fresh (an empty film), and for a GPU its adapter in one line;
/// `n` is N for a fixed-N sampler.
fn make_backend(study: &Study, c: &Config, n: Option<u32>) -> Result<(Backend, Option<String>), String> {
    let settings = RenderSettings {
        sample_count: n,
        // The albedo and normal guide the denoiser.
        aovs: c.denoise == Switch::On,
        ..c.settings
    };
    let choice = match c.backend {
        ChartBackend::Cpu => BackendChoice::Cpu,
        ChartBackend::Gpu => BackendChoice::Gpu,
    };
    let camera = study.scene.default_camera();
    let adapter = if choice == BackendChoice::Gpu { study.args.adapter.as_deref() } else { None };
    let mut backend = backend::open(choice, adapter, study.scene.clone(), &camera, settings, None)
        .map_err(|e| e.to_string())?;
    // Untimed warm-up passes, then discarded: the first passes of a process pay costs that are
    // not the method's — the driver compiling the pipeline on first dispatch, rayon starting
    // its threads, and above all an idle GPU's clocks ramping up (a 1-spp warm-up is too short
    // for them): every configuration renders one pass, the first of each backend in the process
    // passes for WARM_UP_SECONDS, and so does every GPU configuration: one that needs a pipeline
    // of its own (another light selection, say) leaves the GPU idle for the seconds of its
    // compile, after which the first checkpoints would run several times slower than warm.
    static WARM: [std::sync::atomic::AtomicBool; 2] =
        [std::sync::atomic::AtomicBool::new(false), std::sync::atomic::AtomicBool::new(false)];
    let first = !WARM[c.backend as usize].swap(true, std::sync::atomic::Ordering::Relaxed);
    let long = first || c.backend == ChartBackend::Gpu;
    let start = Instant::now();
    backend.render_pass(0, 1).map_err(|e| e.to_string())?;
    while long && start.elapsed().as_secs_f64() < WARM_UP_SECONDS {
        backend.render_pass(0, 1).map_err(|e| e.to_string())?;
    }
    backend.set_film(&Film::for_settings(&settings)).map_err(|e| e.to_string())?;
    let adapter = match &mut backend {
        Backend::Gpu(g) => Some(g.context().describe()),
        Backend::Gpus(g) => Some(g.describe()),
        Backend::Cpu(_) => None,
    };
    Ok((backend, adapter))
}

/// The error of `film` against `reference` (the metrics of `furnace compare`).
fn measure(film: &Film, reference: &[Vec3]) -> Result<(f64, f64), String> {
    let rgb: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
    let s = score(&rgb, reference, None, None).map_err(|e| e.to_string())?;
    Ok((s.rmse, s.rel_mse))
}

/// Progress over the whole study, in samples.
pub(super) struct Progress {
    bar: ProgressBar,
    pixels: u64,
}

impl Progress {
    pub(super) fn new(quiet: bool, total_spp: u64, done_spp: u64, pixels: u64) -> Self {
        let bar = if quiet {
            ProgressBar::hidden()
        } else {
            let bar = ProgressBar::new(total_spp * pixels).with_position(done_spp * pixels);
            if let Ok(style) = ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40.cyan/blue}] {percent:>3}%  {msg}  ETA {eta}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        };
        Self { bar, pixels }
    }

    fn advance(&self, spp: u32, msg: String) {
        self.bar.inc(u64::from(spp) * self.pixels);
        self.bar.set_message(msg);
    }
}

/// Renders a study's configurations, scoring each checkpoint and saving the rows after it.
pub(super) struct Runner<'s> {
    study: &'s Study,
    interrupt: &'s Interrupt,
    progress: Progress,
    rows: Vec<Row>,
    /// The machine description recorded in `chart.json`.
    machine: Value,
}

impl<'s> Runner<'s> {
    /// A runner that adds to the saved `rows`.
    pub(super) fn new(
        study: &'s Study,
        interrupt: &'s Interrupt,
        progress: Progress,
        rows: Vec<Row>,
    ) -> Self {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let machine = json!({ "cpu_threads": threads, "furnace_version": env!("CARGO_PKG_VERSION") });
        Self { study, interrupt, progress, rows, machine }
    }
}

impl Runner<'_> {
    /// Renders each configuration's checkpoints left (`todo`); `false` if Ctrl-C stopped it.
    pub(super) fn run_all(&mut self, todo: &[(Config, Vec<u32>)]) -> Result<bool, String> {
        for (c, left) in todo {
            if !self.run_config(c, left)? {
                return Ok(false);
            }
            if self.progress.bar.is_hidden() && !self.study.args.quiet {
                eprintln!("done: {}", c.name());
            }
        }
        Ok(true)
    }

    /// Ends the progress bar; the rows and the machine description.
    pub(super) fn finish(self) -> (Vec<Row>, Value) {
        self.progress.bar.finish_and_clear();
        (self.rows, self.machine)
    }

    /// Renders checkpoints `left` of `c`: a fixed-N sampler renders each as its own render
    /// with N = the checkpoint, a progressive one renders once through all of them. `false`
    /// if Ctrl-C stopped it.
    fn run_config(&mut self, c: &Config, left: &[u32]) -> Result<bool, String> {
        let renders: Vec<(Option<u32>, &[u32])> = if c.settings.sampler.needs_sample_count() {
            left.iter().map(|n| (Some(*n), std::slice::from_ref(n))).collect()
        } else {
            vec![(None, left)]
        };
        for (n, targets) in renders {
            let (mut backend, adapter) = make_backend(self.study, c, n)?;
            self.note_adapter(adapter);
            if !self.render_to(&mut backend, c, targets)? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Renders `c` from sample 0 up to each of `targets` (ascending), timing the passes, and
    /// records each checkpoint. Returns `false` if Ctrl-C stopped it.
    fn render_to(
        &mut self,
        backend: &mut dyn Integrator,
        c: &Config,
        targets: &[u32],
    ) -> Result<bool, String> {
        let name = c.name();
        let last = targets.last().copied().unwrap_or(0);
        let mut session = Session::new(backend, 0);
        session.measure_cpu_time(true);
        for &target in targets {
            let stop = session
                .run(&Budget::spp(target), &|| self.interrupt.requested(), &mut |p| {
                    self.progress.advance(p.pass, format!("{name} {}/{last}", p.done));
                })
                .map_err(|e| e.to_string())?;
            if stop == Stop::Cancelled {
                return Ok(false);
            }
            let film = session.film().map_err(|e| e.to_string())?;
            self.checkpoint(c, target, session.timing(), &film)?;
        }
        Ok(true)
    }

    /// Scores `c`'s film at `spp`, replaces its row for that checkpoint, and saves the data.
    fn checkpoint(&mut self, c: &Config, spp: u32, mut time: Timing, film: &Film) -> Result<(), String> {
        let name = c.name();
        let (reference, matches) = self.study.reference_for(c);
        let (rmse, relmse) = if c.denoise == Switch::On {
            // The denoised image, guided by the AOVs, on OIDN's default device (a GPU it can
            // drive, else the CPU), as `render --denoise`; its wall and CPU time count as the
            // checkpoint's.
            let rgb: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
            let cpu = furnace_render::process_cpu_seconds();
            let start = Instant::now();
            let options = furnace_denoise::Options { prefilter_guides: false, ..Default::default() };
            let d = crate::outputs::denoise_film(film, &rgb, &options)
                .map_err(|e| format!("{name}: denoising: {e}"))?;
            time.wall += start.elapsed().as_secs_f64();
            time.cpu += match (cpu, furnace_render::process_cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            };
            let s = score(&d.pixels, &reference.pixels, None, None).map_err(|e| e.to_string())?;
            (s.rmse, s.rel_mse)
        } else {
            measure(film, &reference.pixels)?
        };
        let mean_spp = film.counts().iter().sum::<u64>() as f64 / film.counts().len().max(1) as f64;
        self.rows.retain(|r| !(r.config == name && r.spp == spp));
        self.rows.push(c.row(spp, time, (rmse, relmse), matches, mean_spp));
        if film.rejected() > 0 {
            self.progress
                .bar
                .suspend(|| eprintln!("warning: {name}: {} non-finite samples rejected", film.rejected()));
        }
        save_data(self.study, &mut self.rows, &self.machine)
    }

    /// Records the GPU adapter's name in the machine description (the first one seen).
    fn note_adapter(&mut self, adapter: Option<String>) {
        if let Some(name) = adapter
            && self.machine.get("gpu_adapter").is_none()
        {
            self.machine["gpu_adapter"] = json!(name);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measure_uses_the_compare_metrics() {
        // A 2×1 film holding (1.5, 1.5, 1.5) and (0, 0, 0) against a reference of ones:
        // squared errors 0.25 ×3 and 1 ×3 → RMSE sqrt(1.25/2); relMSE (0.25 + 1)/2 / 1.01.
        let film =
            Film::from_parts(2, 1, vec![glam::DVec3::splat(3.0), glam::DVec3::ZERO], vec![2, 2], 0).unwrap();
        let (rmse, relmse) = measure(&film, &[Vec3::ONE, Vec3::ONE]).unwrap();
        assert!((rmse - 0.625f64.sqrt()).abs() < 1e-12, "{rmse}");
        assert!((relmse - 0.625 / 1.01).abs() < 1e-12, "{relmse}");
        assert!(measure(&film, &[Vec3::ONE]).is_err(), "size mismatch");
    }
}
