//! `furnace view`: the render's options, a window instead of files (`furnace_view`); Ctrl+S
//! saves what `furnace render` writes, resumable with `furnace render --resume`.

use crate::args::ViewArgs;
use crate::interrupt::Interrupt;
use crate::outputs::{Look, output_paths, write_outputs};
use crate::render::{Job, Prepared, prepare};
use crate::resume;
use crate::shared::Outcome;
use furnace_gpu::{AdapterChoice, GpuContext};
use furnace_render::RenderSettings;
use furnace_scene::Scene;
use furnace_view::{CameraPose, SaveRequest, ScriptSource, ViewConfig, ViewHost};

pub fn run(v: &ViewArgs, interrupt: &Interrupt) -> Result<Outcome, String> {
    let a = &v.render;
    if a.backend == furnace_cli::backend::BackendChoice::Cpu {
        return Err(
            "furnace view draws the GPU integrator's film as it accumulates: it needs a GPU adapter \
             (Mesa's lavapipe counts); use `furnace render --backend cpu` for the CPU integrator"
                .into(),
        );
    }
    // Read the script before anything slow: a bad line is reported at once.
    let script = match &v.script {
        None => None,
        Some(p) if p.as_os_str() == "-" => Some(ScriptSource::Stdin),
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            Some(ScriptSource::File(p.clone(), furnace_view::script::parse(&p.display().to_string(), &text)?))
        }
    };
    if a.checkpoint.is_some() {
        return Err("--checkpoint is for `furnace render`; the viewer saves with Ctrl+S".into());
    }
    let Prepared { job, scene, view, saved, accel } = prepare(a, "view")?;
    let a = &job.args;
    if let Some(range) = a.samples {
        let what = match &a.resume {
            Some(file) => format!("{} is a part (samples {range}) of a split render", file.display()),
            None => "--samples renders a part of a split render".to_string(),
        };
        return Err(format!(
            "{what}: the viewer shows whole renders (continue a part with `furnace render --resume`, or \
             `furnace merge` the parts and view the merged file)"
        ));
    }
    // Without --spp the viewer accumulates until closed; the fixed-N samplers need N.
    let sampler = job.settings.sampler;
    let target_spp = (a.given("spp") || sampler.needs_sample_count() || a.resume.is_some()).then_some(a.spp);
    if sampler.needs_sample_count() && !a.given("spp") && a.resume.is_none() {
        eprintln!(
            "note: the {sampler} sampler builds one pattern of N samples per pixel: N = --spp = {}",
            a.spp
        );
    }
    let choice = match &a.adapter {
        Some(name) => AdapterChoice::Named(name.clone()),
        None => AdapterChoice::Best,
    };
    let ctx = GpuContext::new(&choice).map_err(|e| {
        format!("{e}; furnace view needs a GPU adapter to draw into its window (`furnace render --backend cpu` needs none)")
    })?;
    if !a.quiet {
        eprintln!("viewing on {}", ctx.describe());
        if !furnace_gpu::context::is_hardware(&ctx.info) {
            eprintln!(
                "note: a software adapter: expect about 0.1 million samples per second, and a first frame \
                 of up to a minute or two while it compiles the shader"
            );
        }
    }
    let start = std::time::Instant::now();
    // The default light's probe built a flat scene's BVH: the renderer takes it.
    let renderer = furnace_cli::backend::gpu_renderer(ctx, &scene, &view, job.settings, accel)
        .map_err(|e| e.to_string())?;
    if !a.quiet {
        eprintln!(
            "{}: {} triangles; scene uploaded, BVH built and pipeline compiled in {:.2} s",
            scene.name,
            scene.geometry.triangles.len(),
            start.elapsed().as_secs_f64()
        );
    }
    let (resume, previous_seconds, previous_backend) = match saved {
        Some(s) => (Some((s.film, s.spp)), s.render_time_s, s.backend),
        None => (None, 0.0, None),
    };
    let config = ViewConfig {
        title: format!("furnace — {}", scene.name),
        settings: job.settings,
        camera: view,
        fixed_size: a.given("width") || a.given("height") || a.resume.is_some(),
        target_spp,
        time_limit: a.time_limit,
        exposure: a.exposure,
        tonemap: a.tonemap,
        resume,
        script,
    };
    let mut host = CliHost { job, interrupt, previous_seconds, previous_backend };
    match furnace_view::run(renderer, scene, config, &mut host).map_err(|e| e.to_string())? {
        furnace_view::Outcome::Closed => Ok(Outcome::Done),
        furnace_view::Outcome::Interrupted => Ok(Outcome::Interrupted),
    }
}

/// Saves as `furnace render` does, with the viewer's settings written back into the job.
struct CliHost<'a> {
    job: Job,
    interrupt: &'a Interrupt,
    /// Seconds and backends of the file the view resumed (added to what it records).
    previous_seconds: f64,
    previous_backend: Option<String>,
}

impl ViewHost for CliHost<'_> {
    fn save(&mut self, scene: &Scene, r: SaveRequest) -> Result<String, String> {
        let mut job = Job {
            args: self.job.args.clone(),
            settings: r.settings,
            camera: self.job.camera.clone(),
            scene_name: self.job.scene_name.clone(),
            scene_hash: scene.content_hash(),
            default_light: self.job.default_light,
        };
        apply_settings(&mut job, &r)?;
        if let Some(path) = &r.path {
            job.args.out = path.clone();
        }
        let (png, exr) = output_paths(&job.args.out);
        let mut meta = job.metadata(r.spp, self.previous_seconds + r.seconds, r.film.rejected());
        let (record, _) =
            furnace_render::resume::backend_record(self.previous_backend.as_deref(), &r.backend);
        meta.extra.insert(resume::BACKEND.to_string(), record);
        write_outputs(&r.film, &meta, &Look::of(&job.args), &exr, &png)?;
        let mut message = format!("saved {} and {} ({} spp)", exr.display(), png.display(), r.spp);
        if matches!(r.camera, CameraPose::MovedOrthographic) {
            message.push_str(
                "; note: a moved orthographic camera has no command-line form, so this file cannot be resumed",
            );
        }
        Ok(message)
    }

    fn interrupted(&self) -> bool {
        self.interrupt.requested()
    }
}

/// Writes the viewer's settings, display, environment and camera into the job and its
/// arguments, so that its metadata is what `furnace render` with those options records.
fn apply_settings(job: &mut Job, r: &SaveRequest) -> Result<(), String> {
    let s: &RenderSettings = &r.settings;
    job.settings = *s;
    let a = &mut job.args;
    a.settings.settings = *s;
    a.width = Some(s.width);
    a.height = Some(s.height);
    a.spp = s.sample_count.unwrap_or(r.spp);
    a.exposure = r.exposure;
    a.tonemap = r.tonemap;
    if let Some(i) = r.env_intensity {
        a.environment.env_intensity = Some(i);
    }
    match r.camera {
        CameraPose::Start => {}
        CameraPose::LookAt { eye, target, up, yfov_degrees } => {
            let look = crate::args::LookAt { eye, target, up };
            job.camera = resume::look_at_record(&look, yfov_degrees);
            a.look_at = Some(look);
            a.yfov = Some(yfov_degrees);
            a.camera = None;
        }
        CameraPose::MovedOrthographic => job.camera = "moved-orthographic".into(),
    }
    Ok(())
}
