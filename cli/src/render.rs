//! `furnace render`: load, render in passes with a progress bar, write EXR + PNG.

use crate::args::RenderArgs;
use crate::interrupt::Interrupt;
use crate::outputs::{Look, check_outputs, output_paths, write_outputs};
use crate::resume;
use crate::shared::{Outcome, image_size};
use furnace_accel::SceneAccel;
use furnace_cli::backend::{self, BackendChoice};
use furnace_post::{ExrWithState, Metadata, read_exr_with_state};
use furnace_render::{Budget, Film, Integrator, RenderSettings, SAMPLER_LAYOUT_VERSION, Session, Stop};
use furnace_scene::{Camera, LoadOptions, Projection, Scene, builtin};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// A render's settings, resolved from the arguments, the scene and (when resuming) the file.
pub(crate) struct Job {
    pub args: RenderArgs,
    pub settings: RenderSettings,
    /// The camera's [`resume::CAMERA`] record (from [`select_camera`]).
    pub camera: String,
    pub scene_name: String,
    pub scene_hash: String,
    /// The default light's decision ([`resume::DEFAULT_LIGHT`]: `studio` or `none`), where the
    /// rule decided (no `--env`, no environment of the scene's own).
    pub default_light: Option<&'static str>,
}

impl Job {
    /// The EXR metadata of a render of this job with `spp` samples per pixel done.
    pub(crate) fn metadata(&self, spp: u32, render_time_s: f64, rejected: u64) -> Metadata {
        let a = &self.args;
        let metadata = Metadata {
            spp: Some(spp),
            scene: Some(self.scene_name.clone()),
            render_time_s: Some(render_time_s),
            rejected_samples: Some(rejected),
            extra: [
                (resume::SCENE_HASH, self.scene_hash.clone()),
                (resume::SAMPLER_LAYOUT, SAMPLER_LAYOUT_VERSION.to_string()),
                (resume::CAMERA, self.camera.clone()),
                (resume::TARGET_SPP, a.spp.to_string()),
                (resume::TONEMAP, a.tonemap.to_string()),
                (resume::EXPOSURE, a.exposure.to_string()),
            ]
            .into_iter()
            .chain(a.samples.map(|r| (resume::SAMPLE_RANGE, r.to_string())))
            .chain(a.sun_angle.map(|d| (resume::SUN_ANGLE, d.to_string())))
            .chain(resume::env_records(&a.environment))
            .chain(self.default_light.map(|d| (resume::DEFAULT_LIGHT, d.to_string())))
            .chain(a.load.variant.clone().map(|v| (resume::VARIANT, v)))
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
            ..Metadata::default()
        };
        resume::with_settings(metadata, &self.settings)
    }
}

/// A saved render to continue: its film and how far it got.
pub(crate) struct Saved {
    pub film: Film,
    pub spp: u32,
    pub render_time_s: f64,
    /// Its [`resume::BACKEND`] record (`None` in files from before the record).
    pub backend: Option<String>,
}

/// A render prepared from its arguments (and, with `--resume`, its file): the job, the scene
/// with the options applied, the camera, and the saved film to continue.
pub(crate) struct Prepared {
    pub job: Job,
    pub scene: Scene,
    pub view: Camera,
    pub saved: Option<Saved>,
    /// The scene's structure, when the default light's probe built it (for the backend).
    pub accel: Option<SceneAccel>,
}

/// Reads the file to resume (filling the settings not given), loads the scene, applies
/// `--sun-angle` and the environment options, chooses the camera and the size, and checks that
/// a resumed file matches. `command` names the subcommand in messages.
pub(crate) fn prepare(a: &RenderArgs, command: &str) -> Result<Prepared, String> {
    if a.denoise && !furnace_denoise::available() {
        // Before any rendering: the one line that says how to get it.
        return Err(furnace_denoise::DenoiseError::NotBuilt.to_string());
    }
    let mut args = a.clone();
    // With --resume: the file's record fills the settings not given.
    let resumed = match &a.resume {
        Some(path) => {
            let file = read_exr_with_state(path).map_err(|e| e.to_string())?;
            if file.state.is_none() {
                return Err(format!(
                    "{}: no furnace resume state (furnace.resume.* channels): it was not written by \
                     `furnace render` (or by a version before resume), so it cannot be continued",
                    path.display()
                ));
            }
            resume::apply_recorded(&mut args, path, &file.metadata, file.width, file.height)?;
            Some(file)
        }
        None => None,
    };

    // Compensated given with nee is refused; by default (or from a file's record) it means the
    // plain distribution under nee (`EnvSampling::effective`).
    if args.given("env-sampling") {
        crate::env::check_sampling(
            args.settings.settings.env_sampling,
            args.settings.settings.light_sampling,
        )?;
    }
    check_samples(&mut args)?;
    let mut scene =
        load_scene(args.scene.as_deref(), &args.load.options()).map_err(|e| match (&a.resume, &a.scene) {
            // The scene came from the file's record: say so, and how to point at it.
            (Some(file), None) => {
                format!(
                    "{e} (the scene {} was rendered from; give its path after `{command}`)",
                    file.display()
                )
            }
            _ => e,
        })?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    if let Some(deg) = args.sun_angle
        && scene.set_sun_angular_diameter(deg) == 0
    {
        eprintln!("warning: {}: --sun-angle {deg} is ignored: the scene has no sun", scene.name);
    }
    // A resumed render follows its record of the default light (a file without one was made
    // before the rule: the rule of then), so that the same scene is rebuilt.
    let recorded = resumed.as_ref().map(|f| f.metadata.extra.get(resume::DEFAULT_LIGHT).map(String::as_str));
    let mut accel = None;
    let default_light = match crate::env::apply_resumed(&mut scene, &args.environment, recorded, &mut accel)?
    {
        crate::env::Applied::Rule(d) => Some(d.record()),
        _ => None,
    };
    let layout_uses = furnace_render::resume::LayoutUse {
        samples_lights: scene.samples_lights(),
        chooses_point_lights: args.settings.settings.point_lights.chooses(scene.point_lights().count()),
        samples_wavelengths: scene.disperses(),
    };
    let scene_hash = scene.content_hash();
    let (camera, view) = select_camera(&scene, &args)?;
    let (width, height) = image_size(&view, args.width, args.height)?;
    let sampler = args.settings.settings.sampler;
    let settings = RenderSettings {
        width,
        height,
        sample_count: sampler.needs_sample_count().then_some(args.spp),
        // The file's AOVs are kept when resuming; they cannot be added to a file without them
        // (they must sum the same samples as the image, from the first).
        // --denoise takes the albedo and normal as guides: AOVs on for a new render.
        aovs: args.aovs
            || (args.denoise && resumed.is_none())
            || resumed.as_ref().and_then(|f| f.state.as_ref()).is_some_and(Film::has_aovs),
        ..args.settings.settings
    };
    if let Some(file) = &resumed
        && args.aovs
        && !file.state.as_ref().is_some_and(Film::has_aovs)
    {
        return Err(format!(
            "{}: rendered without AOVs, so --aovs cannot be added when resuming (the AOVs must average \
             the same samples as the image); render again with --aovs",
            a.resume.clone().unwrap_or_default().display()
        ));
    }
    let job = Job { scene_name: scene.name.clone(), scene_hash, camera, settings, args, default_light };
    let a = &job.args;

    let saved = match resumed {
        Some(file) => {
            let path = a.resume.clone().unwrap_or_default();
            let recorded = resume::identity(&file.metadata, file.width, file.height);
            let now = resume::identity(&job.metadata(0, 0.0, 0), width, height);
            resume::check_same(&path, &file.metadata, &recorded, &now, layout_uses).map_err(|e| {
                resume::variant_hint(e, &file.metadata, a.load.variant.as_deref(), !scene.variants.is_empty())
            })?;
            let saved = restore(&path, file)?;
            Some(saved)
        }
        None => None,
    };
    Ok(Prepared { job, scene, view, saved, accel })
}

/// `--samples A..B` against `--spp N` (the whole render's count): N defaults to B for a
/// progressive sampler, must be given for a fixed-N one, and the range must lie in `0..N`.
fn check_samples(args: &mut RenderArgs) -> Result<(), String> {
    let Some(range) = args.samples else { return Ok(()) };
    if !args.given("spp") && args.resume.is_none() {
        if args.settings.settings.sampler.needs_sample_count() {
            return Err(format!(
                "--samples {range}: the {} sampler builds one pattern of N samples per pixel, so a part \
                 needs the whole render's N: give --spp N",
                args.settings.settings.sampler
            ));
        }
        args.spp = range.end;
    }
    if range.end > args.spp {
        return Err(format!(
            "--samples {range} goes past the render's {} samples per pixel (--spp is the whole render's \
             count; sample indices run from 0 to {})",
            args.spp,
            args.spp - 1
        ));
    }
    Ok(())
}

pub fn run(a: &RenderArgs, interrupt: &Interrupt) -> Result<Outcome, String> {
    let Prepared { job, scene, view, saved, accel } = prepare(a, "render")?;
    let a = &job.args;
    check_outputs(&a.out, a.denoise)?;
    let (width, height) = (job.settings.width, job.settings.height);
    let settings = job.settings;
    // The sample indices this run renders: the part's range, or the whole render's.
    let (start, end) = a.samples.map_or((0, a.spp), |r| (r.start, r.end));
    if let Some(s) = &saved
        && start + s.spp >= end
    {
        let file = a.resume.clone().unwrap_or_default();
        match a.samples {
            Some(range) => eprintln!(
                "{} already holds every sample of its part {range}: nothing to render",
                file.display()
            ),
            None => eprintln!(
                "{} already has {} samples per pixel (target {}): nothing to render; give a \
                 larger --spp to continue",
                file.display(),
                s.spp,
                a.spp
            ),
        }
        return Ok(Outcome::Done);
    }

    if settings.sampler.needs_sample_count() && a.time_limit.is_some() {
        eprintln!(
            "warning: the {} sampler builds one pattern of N = {} samples per pixel; if --time-limit \
             stops the render before N, the partial pattern is poorly stratified (prefer sobol or pmj02)",
            settings.sampler, a.spp
        );
    }
    // Memory planned before the BVH is built and the film allocated.
    let on_cpu = a.backend != BackendChoice::Gpu;
    let instances = scene.instancing.instances.len();
    let plan = crate::memory::Plan::new(&settings, scene.geometry.triangle_count(), instances, on_cpu);
    if let Some((free, limit)) = crate::memory::free_memory() {
        plan.check(&settings, free, limit)?;
    }
    let (film, first, previous_time, previous_backend) = match saved {
        Some(s) => (Some(s.film), start + s.spp, s.render_time_s, s.backend),
        None => (None, start, 0.0, None),
    };
    let mut backend = backend::open_chosen(
        a.backend,
        a.adapter.as_deref(),
        a.gpus.as_ref(),
        Arc::new(scene),
        &view,
        settings,
        accel,
    )?;
    if let Some(film) = &film {
        backend.set_film(film).map_err(|e| e.to_string())?;
    }
    backend.set_cancel_flag(interrupt.flag());
    if backend.name() != "cpu" && !a.quiet {
        eprintln!("rendering on {}", backend.describe());
    }
    let (backend_record, backend_changed) =
        furnace_render::resume::backend_record(previous_backend.as_deref(), &backend.describe());
    if backend_changed && !a.quiet {
        eprintln!(
            "note: continuing a render made on {} with {}: the same sample indices, so the same image \
             statistically, but not bit for bit an uninterrupted render on either",
            previous_backend.unwrap_or_default(),
            backend.describe()
        );
    }
    let (png_path, exr_path) = output_paths(&a.out);
    // The EXR and PNG of the film holding samples start..done after `seconds` of this run.
    let save = |backend: &mut dyn Integrator, done: u32, seconds: f64, look: &Look| {
        let film = backend.film().map_err(|e| e.to_string())?;
        let mut metadata = job.metadata(done - start, previous_time + seconds, film.rejected());
        metadata.extra.insert(resume::BACKEND.to_string(), backend_record.clone());
        write_outputs(&film, &metadata, look, &exr_path, &png_path).map(|()| film)
    };
    // Checkpoints are not denoised (only the final image is).
    let checkpoint_look = Look { denoise: None, ..Look::of(a) };
    let mut checkpoint = |backend: &mut dyn Integrator, done: u32, seconds: f64| {
        save(backend, done, seconds, &checkpoint_look).map(drop)
    };
    let pass = render_passes(&mut backend, &job, (first, end), interrupt, &mut checkpoint)?;
    if pass.done == first {
        // Ctrl-C before a whole sample of every pixel: nothing new; leave every file as it was.
        eprintln!("interrupted before the first sample of every pixel: nothing rendered, nothing written");
        return Ok(Outcome::Interrupted);
    }
    let film = save(&mut backend, pass.done, pass.seconds, &Look::of(a))?;

    if let Some(why) = black_image(&film) {
        eprintln!("warning: {}: the image is black: {why}", job.scene_name);
    }
    let stopped_by_user = pass.stop == Stop::Cancelled;
    if !a.quiet || stopped_by_user {
        let rendered = u64::from(pass.done - first);
        let rate = (u64::from(width) * u64::from(height) * rendered) as f64 / pass.seconds.max(1e-9) / 1e6;
        let from = if first > start { format!(" (resumed at {first})") } else { String::new() };
        let asked = a.samples.map_or_else(|| a.spp.to_string(), |r| r.to_string());
        let stopped = match pass.stop {
            Stop::Finished => String::new(),
            Stop::TimeLimit => format!(" (stopped by --time-limit; asked {asked})"),
            Stop::Cancelled => format!(" (interrupted; asked {asked})"),
            Stop::Converged => " (every pixel converged)".to_string(),
        };
        let held = match a.samples {
            Some(_) => format!("samples {start}..{} of {}", pass.done, a.spp),
            None => format!("{} spp", pass.done),
        };
        eprintln!(
            "{}: {width}×{height}, {held}{from}{stopped}, {} bounces, {} sampler, {} backend: {:.2} s ({rate:.2} Msamples/s)",
            job.scene_name,
            settings.bounces,
            settings.sampler,
            backend.name(),
            pass.seconds,
        );
        if let Some(converged) = film.converged_count() {
            let pixels = film.counts().len().max(1) as f64;
            let mean_spp = film.counts().iter().sum::<u64>() as f64 / pixels;
            eprintln!(
                "adaptive sampling: {:.1} % of pixels converged below {}, {mean_spp:.1} spp per pixel on average",
                100.0 * converged as f64 / pixels,
                settings.adaptive.map_or(0.0, |t| t.threshold)
            );
        }
        if film.rejected() > 0 {
            eprintln!("warning: {} non-finite samples rejected", film.rejected());
        }
        eprintln!("wrote {} and {}", exr_path.display(), png_path.display());
        if pass.done < end && pass.stop != Stop::Converged {
            let to = a.samples.map_or_else(|| format!("{end} spp"), |r| format!("the end of part {r}"));
            eprintln!(
                "to continue to {to}: furnace render --resume {}",
                shell_quote(&exr_path.display().to_string())
            );
        }
    }
    Ok(if stopped_by_user { Outcome::Interrupted } else { Outcome::Done })
}

/// Why a film is black, when no pixel has a non-zero mean; `None` otherwise. Every warning the
/// scene gave was printed before: this is the last word, for the causes no check foresaw.
fn black_image(film: &Film) -> Option<String> {
    let pixels = film.counts().len();
    if pixels == 0 || (0..pixels).any(|i| film.mean(i) != glam::DVec3::ZERO) {
        return None;
    }
    let accepted: u64 = film.counts().iter().sum();
    Some(if accepted == 0 {
        format!("all {} samples were non-finite and rejected (see the warnings above)", film.rejected())
    } else {
        "no sample carried light to the camera: no light reaches what it sees, or it sees nothing \
         (`furnace info SCENE` lists the lights and cameras; --env studio lights any scene)"
            .to_string()
    })
}

/// What the pass loop did.
struct Passes {
    /// Samples per pixel in the film now (the next sample index).
    done: u32,
    /// Seconds spent rendering in this run.
    seconds: f64,
    stop: Stop,
}

/// Saves the render so far: given the integrator, the next sample index and the seconds of
/// this run.
type Checkpoint<'a> = dyn FnMut(&mut dyn Integrator, u32, f64) -> Result<(), String> + 'a;

/// Renders passes from sample index `first` up to `end` (`(first, end)`), until done, the time
/// limit or Ctrl-C / SIGTERM, with a progress bar (or, when stderr is not a terminal, a progress
/// line after the first pass and then every 10 s), calling `checkpoint` (the integrator, the
/// next sample index, seconds so far) every `--checkpoint` seconds. A pass that fails leaves
/// the film with the passes before it.
fn render_passes(
    backend: &mut dyn Integrator,
    job: &Job,
    (first, end): (u32, u32),
    interrupt: &Interrupt,
    checkpoint: &mut Checkpoint<'_>,
) -> Result<Passes, String> {
    let a = &job.args;
    let bar = progress_bar(a.quiet, end, first);
    let log_lines = !a.quiet && bar.is_hidden();
    let mut last_log: Option<Instant> = None;
    let start = Instant::now();
    let mut session = Session::new(backend, first);
    let mut progress = |p: &furnace_render::Progress| {
        bar.set_position(u64::from(p.done));
        let converged = p.converged.map(|c| format!(", {:.1} % converged", 100.0 * c)).unwrap_or_default();
        bar.set_message(format!("{:.2} Msamples/s{converged}", p.msamples_per_s));
        if log_lines && last_log.is_none_or(|t| t.elapsed().as_secs_f64() >= 10.0) {
            let done = match a.samples {
                Some(r) => format!("{}/{} spp of part {r}", p.done - r.start, r.len()),
                None => format!("{}/{} spp", p.done, p.target),
            };
            eprintln!("progress: {done}, {:.1} s, {:.2} Msamples/s{converged}", p.elapsed, p.msamples_per_s);
            last_log = Some(Instant::now());
        }
    };
    let stop = loop {
        // Each run of the session ends at the time limit (what is left of it), or with
        // --checkpoint after the first pass that ends past the interval.
        let elapsed = start.elapsed().as_secs_f64();
        let budget = Budget {
            spp: end,
            time_limit: a.time_limit.map(|t| (t - elapsed).max(0.0)),
            min_seconds: a.checkpoint,
        };
        let stop = match session.run(&budget, &|| interrupt.requested(), &mut progress) {
            Ok(stop) => stop,
            Err(e) => {
                bar.finish_and_clear();
                return Err(save_after_failure(session, first, start, checkpoint, &e.to_string(), &a.out));
            }
        };
        if a.checkpoint.is_none() || stop != Stop::TimeLimit {
            break stop;
        }
        // The interval or the time limit: the limit if, at the mean pass time, the next pass
        // would end past it.
        let t = session.timing();
        let mean_pass = t.wall / t.passes.max(1) as f64;
        if a.time_limit.is_some_and(|limit| start.elapsed().as_secs_f64() + mean_pass > limit) {
            break stop;
        }
        let done = session.done();
        checkpoint(session.integrator(), done, start.elapsed().as_secs_f64())?;
    };
    bar.finish_and_clear();
    Ok(Passes { done: session.done(), seconds: start.elapsed().as_secs_f64(), stop })
}

/// The error of a pass that failed (a device lost, memory exhausted), after saving the passes
/// before it when there are any, so that nothing rendered is lost: says what was saved and how
/// to continue it.
fn save_after_failure(
    mut session: Session<'_>,
    first: u32,
    start: Instant,
    checkpoint: &mut Checkpoint<'_>,
    error: &str,
    out: &Path,
) -> String {
    let done = session.done();
    if done == first {
        return error.to_string();
    }
    let exr = output_paths(out).1;
    match checkpoint(session.integrator(), done, start.elapsed().as_secs_f64()) {
        Ok(()) => format!(
            "{error} (the render so far, {} samples per pixel, is saved in {}: continue it with \
             furnace render --resume {})",
            done - first,
            exr.display(),
            shell_quote(&exr.display().to_string())
        ),
        Err(save) => format!("{error} (saving the render so far failed too: {save})"),
    }
}

/// The film saved in `file`, checked: its state must be that of its own RGB image (each
/// pixel's `f32(sum / count)`), which catches a file edited after furnace wrote it.
pub(crate) fn restore(path: &Path, file: ExrWithState) -> Result<Saved, String> {
    let p = path.display();
    let meta = &file.metadata;
    let spp = meta.spp.ok_or_else(|| format!("{p}: no 'furnace.spp' attribute; it cannot be resumed"))?;
    if meta.rejected_samples.is_none() {
        return Err(format!("{p}: no 'furnace.rejectedSamples' attribute; it cannot be resumed"));
    }
    // The film's rejected samples are the metadata's (read_exr_with_state).
    let film = file.state.ok_or_else(|| format!("{p}: no furnace resume state"))?;
    if let Some(c) = film.counts().iter().find(|&&c| c > u64::from(spp)) {
        return Err(format!("{p}: a pixel has {c} samples but the file says {spp} spp; it was modified"));
    }
    if let Some(e) = resume::modified_bounces(path, meta) {
        return Err(e);
    }
    // A render holds at most its part's samples, or the whole render's.
    let whole = meta.extra.get(resume::TARGET_SPP).and_then(|v| v.parse::<u32>().ok());
    let part =
        meta.extra.get(resume::SAMPLE_RANGE).and_then(|v| v.parse::<furnace_render::SampleRange>().ok());
    if let Some(most) = part.map(|r| r.len()).or(whole)
        && spp > most
    {
        return Err(format!(
            "{p}: attribute 'furnace.spp' = {spp} is more than the {most} samples per pixel the render \
             was asked for; it was modified"
        ));
    }
    // Every sample taken was either added to its pixel or rejected: together they are at most
    // spp per pixel (fewer where adaptive sampling stopped a pixel).
    let taken = u128::from(spp) * film.counts().len() as u128;
    let added: u128 = film.counts().iter().map(|&c| u128::from(c)).sum();
    if u128::from(film.rejected()) + added > taken {
        return Err(format!(
            "{p}: attribute 'furnace.rejectedSamples' = {} is more than the {} samples that 'furnace.spp' \
             = {spp} leaves unaccounted for; it was modified",
            film.rejected(),
            taken.saturating_sub(added)
        ));
    }
    if let Some(t) = meta.render_time_s
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(format!("{p}: attribute 'furnace.renderTimeS' = {t} is not a time in seconds"));
    }
    let rgb = film.to_rgb_f32();
    let stored = file.pixels.iter().flat_map(|v| v.to_array());
    if let Some(i) = rgb.iter().zip(stored).position(|(a, b)| a.to_bits() != b.to_bits()) {
        let (x, y) = ((i / 3) as u32 % file.width, (i / 3) as u32 / file.width);
        return Err(format!(
            "{p}: the resume state does not match the image at pixel ({x}, {y}); the file was modified \
             after furnace wrote it"
        ));
    }
    Ok(Saved {
        film,
        spp,
        render_time_s: meta.render_time_s.unwrap_or(0.0),
        backend: meta.extra.get(resume::BACKEND).cloned(),
    })
}

/// The camera that `args` ask for and its [`resume::CAMERA`] record: with `--look-at`, that pose
/// with `--yfov` (default: the scene's first perspective camera's, else 45°), recorded by
/// [`resume::look_at_record`]; else camera `--camera` of the scene (the first without it),
/// recorded by its index, or for a scene without cameras the view framed around its geometry,
/// recorded as [`resume::FRAMED`].
pub(crate) fn select_camera(scene: &Scene, args: &RenderArgs) -> Result<(String, Camera), String> {
    if let Some(look) = &args.look_at {
        let yfov = args.yfov.unwrap_or_else(|| default_yfov(scene));
        return Ok((resume::look_at_record(look, yfov), look.camera(yfov)));
    }
    let n = scene.cameras.len();
    match args.camera {
        None if n == 0 => Ok((resume::FRAMED.to_string(), scene.default_camera())),
        None => Ok(("0".to_string(), scene.default_camera())),
        Some(_) if n == 0 => Err(format!(
            "{} has no cameras (without --camera the view is framed around its geometry)",
            scene.name
        )),
        Some(i) if i as usize >= n => Err(format!(
            "{} has {n} camera{} (--camera 0 to {}), not camera {i}",
            scene.name,
            if n == 1 { "" } else { "s" },
            n - 1
        )),
        Some(i) => Ok((i.to_string(), scene.cameras[i as usize])),
    }
}

/// The `--yfov` of a `--look-at` camera not given one, in degrees: that of the scene's first
/// perspective camera, else 45.
fn default_yfov(scene: &Scene) -> f32 {
    scene
        .cameras
        .iter()
        .find_map(|c| match c.projection {
            Projection::Perspective { yfov, .. } => Some(yfov.to_degrees()),
            Projection::Orthographic { .. } => None,
        })
        .filter(|d| *d > 0.0 && *d < 180.0)
        .unwrap_or(45.0)
}

/// `s` quoted for a POSIX shell when it needs it.
fn shell_quote(s: &str) -> String {
    if !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b"-_./,:+@%".contains(&b)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

pub(crate) fn load_scene(path: Option<&Path>, options: &LoadOptions) -> Result<Scene, String> {
    let builtin = |p: &Path| p.to_str().is_some_and(crate::args::is_builtin_scene);
    let is_file = path.is_some_and(|p| !builtin(p));
    crate::shared::check_builtin_options(options, is_file)?;
    match path {
        // The procedural stress scenes of `furnace bench --scene interior:N` and `forest:N`.
        Some(p) if builtin(p) => match crate::args::parse_scene(p.to_str().unwrap_or_default())? {
            crate::args::SceneArg::Interior(n) => Ok(builtin::sunlit_interior(n)),
            crate::args::SceneArg::Forest(n, seed) => Ok(builtin::forest(n, seed)),
            _ => Err(format!("'{}': not a scene", p.display())),
        },
        Some(p) => Scene::load_with(p, options).map_err(|e| e.to_string()),
        None => builtin::cornell_box().map_err(|e| e.to_string()),
    }
}

fn progress_bar(quiet: bool, spp: u32, done: u32) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(u64::from(spp)).with_position(u64::from(done));
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{bar:40.cyan/blue}] {pos}/{len} spp  {msg}  ETA {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
