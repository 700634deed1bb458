//! `furnace bench`: throughput of a backend on a scene — Msamples/s, Mrays/s, ms per frame, time
//! to first frame and GPU memory per triangle — as a Markdown table and JSON.
//!
//! * Time to first frame: from the start of setup (adapter, scene build or load, BVH, upload,
//!   pipeline) to the end of the first pass of one sample per pixel. That pass is a warm-up and
//!   is not part of the measured passes; on a hardware GPU more untimed passes follow for
//!   [`WARM_UP_SECONDS`], while the GPU's clocks ramp up.
//! * Then passes of the backend's own size (`Integrator::pass_samples`) until `--min-seconds` have
//!   passed, or exactly `--spp` samples per pixel.
//! * Rays (closest-hit and shadow): on the GPU, counted during the measured passes by the
//!   counting variant of the kernel (`GpuRenderer::set_count_rays`; a few per cent slower than
//!   the rendering kernel, which `--no-rays` measures). The CPU integrator has no counter: its rays
//!   per sample are estimated by a counting GPU render of the same scene and settings on a small
//!   image of the same aspect ratio (the two backends trace the same paths), when an adapter is
//!   available; the output says which.

use crate::args::{BenchArgs, SceneArg};
use crate::shared::{WARM_UP_SECONDS, image_size, write_atomically};
use furnace_cli::backend::{self, Backend};
use furnace_gpu::{AdapterChoice, GpuContext, GpuRenderer};
use furnace_render::{Budget, Integrator, RenderSettings, Session};
use furnace_scene::{Scene, builtin};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Pixels and samples per pixel of the render on which CPU rays per sample are counted on a
/// hardware GPU: 65 536 paths.
const ESTIMATE: (f64, u32) = (4096.0, 16);
/// The same on a software adapter, whose rate is a few hundredths of a hardware GPU's: 4096
/// paths, enough for rays per sample within a few percent.
const ESTIMATE_SOFTWARE: (f64, u32) = (1024.0, 4);

/// The time to the first frame in its parts, in seconds: making the scene (load or generate),
/// building its structure (a CPU render's, or a GPU render's without instances: one BVH or, on
/// the CPU, the BVHs and TLAS), the default light's probe (rays through that structure), opening
/// the backend (the rest: on the GPU the upload and pipeline, and an instanced scene's BVHs and
/// TLAS; on the CPU the lights' and materials' tables) and the first pass (with what the driver
/// does at a pipeline's first dispatch).
#[derive(Debug, Clone, Copy)]
struct FirstFrame {
    scene: f64,
    bvh: f64,
    probe: f64,
    open: f64,
    pass: f64,
}

/// One benchmark's results.
#[derive(Debug, Clone)]
struct Report {
    backend: &'static str,
    adapter: String,
    scene: String,
    triangles: u64,
    /// Triangles in the image (the instances counted) and the instances.
    placed: u64,
    instances: usize,
    /// The process's peak resident memory at the end, in bytes (`None` where unknown).
    host_peak_bytes: Option<u64>,
    width: u32,
    height: u32,
    bounces: u32,
    sampler: String,
    light_sampling: &'static str,
    triangle_sampling: &'static str,
    light_selection: &'static str,
    point_lights: &'static str,
    env_sampling: &'static str,
    spp: u32,
    seconds: f64,
    time_to_first_frame_s: f64,
    /// Its parts: the scene made, the backend opened, the first pass.
    first_frame: FirstFrame,
    rays: Rays,
    gpu: Option<GpuMemory>,
    profile: Option<GpuProfile>,
    /// Each device's work and the waits in the timed passes, and the seconds of one
    /// collection of the film after them (several GPUs).
    load: Option<(furnace_gpu::multi::Load, f64)>,
}

/// Where the GPU's time goes (GPU backend).
#[derive(Debug, Clone, Copy)]
struct GpuProfile {
    /// Sum of the measured passes' GPU timestamps (compute only; `None` without
    /// `TIMESTAMP_QUERY`).
    gpu_seconds: Option<f64>,
    /// Invocations per pixel in a workgroup.
    group_samples: u32,
    /// Invocations per workgroup.
    group_size: u32,
    /// Node groups of the traversal stack.
    traversal_stack: u32,
    /// Traversal counters of the measured passes (`None` with `--no-rays`).
    counts: Option<furnace_gpu::integrator::TraceCounts>,
}

/// How many rays the measured passes traced.
#[derive(Debug, Clone)]
enum Rays {
    /// Counted on the GPU during the measured passes.
    Counted(u64),
    /// Rays per sample counted on a smaller render (how, in words).
    Estimated { per_sample: f64, how: String },
    /// Not counted (why).
    None(String),
}

/// Scene and BVH bytes on the GPU.
#[derive(Debug, Clone, Copy)]
struct GpuMemory {
    bytes_per_triangle: f64,
    scene_bytes: u64,
    bvh_bytes: u64,
}

impl Report {
    fn samples(&self) -> f64 {
        f64::from(self.width) * f64::from(self.height) * f64::from(self.spp)
    }

    fn msamples_per_s(&self) -> f64 {
        self.samples() / self.seconds.max(1e-12) / 1e6
    }

    fn rays_per_sample(&self) -> Option<f64> {
        match &self.rays {
            Rays::Counted(n) => Some(*n as f64 / self.samples().max(1.0)),
            Rays::Estimated { per_sample, .. } => Some(*per_sample),
            Rays::None(_) => None,
        }
    }

    fn mrays_per_s(&self) -> Option<f64> {
        self.rays_per_sample().map(|r| r * self.msamples_per_s())
    }

    /// Milliseconds per sample per pixel of the whole image.
    fn ms_per_frame(&self) -> f64 {
        self.seconds * 1e3 / f64::from(self.spp.max(1))
    }

    /// The GPU profile as text lines (empty on the CPU).
    fn profile_lines(&self) -> String {
        let Some(p) = self.profile else { return String::new() };
        let mut s = format!(
            "GPU: {} invocation(s) per pixel in a workgroup of {}",
            p.group_samples,
            furnace_gpu::integrator::GROUP_SIZE
        );
        if let Some(g) = p.gpu_seconds {
            let _ = write!(
                s,
                "; GPU timestamps {:.3} ms/frame = {:.1}% of wall time",
                g * 1e3 / f64::from(self.spp.max(1)),
                100.0 * g / self.seconds.max(1e-12)
            );
        }
        if let Some(c) = p.counts {
            let per = |x: u64| x as f64 / c.rays.max(1) as f64;
            let _ = write!(
                s,
                "; per ray: {:.1} nodes, {:.1} triangles; deepest stack {}, fallback sweeps {}",
                per(c.nodes),
                per(c.triangles),
                c.max_stack_depth,
                c.fallbacks
            );
        }
        s.push('\n');
        s
    }

    /// Each device's rate and busy share, the idle share and the collection time (several
    /// GPUs; empty otherwise).
    fn load_lines(&self) -> String {
        let Some((l, collect)) = &self.load else { return String::new() };
        let mut s = String::new();
        for d in &l.devices {
            let _ = writeln!(
                s,
                "GPU {}: {:.2} Msamples/s while rendering, busy {:.1}% of the passes' shares",
                d.index,
                d.rate() / 1e6,
                100.0 * l.busy(d)
            );
        }
        let _ = writeln!(
            s,
            "GPUs: {:.1}% of their time waiting for the slowest of a share; collecting films {:.3} s in the \
             timed passes, {:.3} s for one collection after them",
            100.0 * l.idle(),
            l.collect_seconds,
            collect
        );
        s
    }

    fn rays_note(&self) -> String {
        match &self.rays {
            Rays::Counted(_) => "counted on the GPU".to_string(),
            Rays::Estimated { how, .. } => format!("estimated: {how}"),
            Rays::None(why) => format!("not counted: {why}"),
        }
    }

    fn table(&self) -> String {
        let opt =
            |v: Option<f64>, digits: usize| v.map_or_else(|| "–".to_string(), |x| format!("{x:.digits$}"));
        let mrays = match (&self.rays, self.mrays_per_s()) {
            (Rays::Estimated { .. }, Some(m)) => format!("≈ {m:.2}"),
            (_, m) => opt(m, 2),
        };
        let gpu = self.gpu.map_or_else(
            || "–".to_string(),
            |g| {
                format!(
                    "{:.1} + BVH {:.1}",
                    g.bytes_per_triangle,
                    g.bvh_bytes as f64 / self.triangles.max(1) as f64
                )
            },
        );
        let mut s = String::new();
        s.push_str(
            "| backend | adapter | scene | triangles | size | bounces | sampler | spp | s | Msamples/s \
             | Mrays/s | rays/sample | ms/frame | first frame s | GPU bytes/triangle |\n",
        );
        s.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {}×{} | {} | {} | {} | {:.2} | {:.2} | {} | {} | {:.2} | {:.2} | {} |",
            self.backend,
            self.adapter.replace('|', "/"),
            self.scene.replace('|', "/"),
            self.triangles,
            self.width,
            self.height,
            self.bounces,
            self.sampler,
            self.spp,
            self.seconds,
            self.msamples_per_s(),
            mrays,
            opt(self.rays_per_sample(), 3),
            self.ms_per_frame(),
            self.time_to_first_frame_s,
            gpu,
        );
        let _ = writeln!(s, "\nrays: {}", self.rays_note());
        let mib = |b: u64| b as f64 / 1048576.0;
        let host =
            self.host_peak_bytes.map_or_else(|| "unknown".to_string(), |b| format!("{:.1} MiB", mib(b)));
        let gpu = self.gpu.map_or_else(String::new, |g| {
            format!("; GPU {:.1} MiB of scene and {:.1} MiB of BVH", mib(g.scene_bytes), mib(g.bvh_bytes))
        });
        let _ = writeln!(
            s,
            "memory: {} triangles stored, {} in the image, {} instances; host peak {host}{gpu}",
            self.triangles, self.placed, self.instances
        );
        let FirstFrame { scene, bvh, probe, open, pass } = self.first_frame;
        let parts = match (self.backend, self.instances) {
            ("cpu", _) => "lights, materials, film",
            (_, 0) => "upload, pipeline",
            _ => "BVHs, TLAS, upload, pipeline",
        };
        let _ = writeln!(
            s,
            "first frame: scene {scene:.2} s, BVH {bvh:.2} s, default-light probe {probe:.2} s, {} opened \
             {open:.2} s ({parts}), first pass {pass:.2} s",
            self.backend
        );
        s.push_str(&self.profile_lines());
        s.push_str(&self.load_lines());
        s
    }

    fn json(&self) -> String {
        let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
        let g = self.gpu;
        let p = self.profile;
        let counts = p.and_then(|p| p.counts);
        let per_ray = |f: fn(&furnace_gpu::integrator::TraceCounts) -> u64| {
            finite(counts.map(|c| f(&c) as f64 / c.rays.max(1) as f64))
        };
        let devices = self.load.as_ref().map(|(l, _)| {
            l.devices
                .iter()
                .map(|d| {
                    serde_json::json!({
                        "index": d.index,
                        "msamples_per_s": finite(Some(d.rate() / 1e6)),
                        "busy_seconds": finite(Some(d.busy_seconds)),
                        "busy": finite(Some(l.busy(d))),
                    })
                })
                .collect::<Vec<_>>()
        });
        let mut value = serde_json::json!({
            "backend": self.backend,
            "adapter": self.adapter,
            "scene": self.scene,
            "triangles": self.triangles,
            "width": self.width,
            "height": self.height,
            "bounces": self.bounces,
            "sampler": self.sampler,
            "light_sampling": self.light_sampling,
            "triangle_sampling": self.triangle_sampling,
            "light_selection": self.light_selection,
            "point_lights": self.point_lights,
            "env_sampling": self.env_sampling,
            "spp": self.spp,
            "seconds": finite(Some(self.seconds)),
            "msamples_per_s": finite(Some(self.msamples_per_s())),
            "mrays_per_s": finite(self.mrays_per_s()),
            "rays_per_sample": finite(self.rays_per_sample()),
            "rays_counted": self.rays_note(),
            "ms_per_frame": finite(Some(self.ms_per_frame())),
            "time_to_first_frame_s": finite(Some(self.time_to_first_frame_s)),
            "first_frame_scene_s": finite(Some(self.first_frame.scene)),
            "first_frame_open_s": finite(Some(self.first_frame.open)),
            "first_frame_pass_s": finite(Some(self.first_frame.pass)),
            "gpu_bytes_per_triangle": finite(g.map(|g| g.bytes_per_triangle)),
            "gpu_bvh_bytes_per_triangle": finite(g.map(|g| g.bvh_bytes as f64 / self.triangles.max(1) as f64)),
            "gpu_scene_bytes": g.map(|g| g.scene_bytes),
            "gpu_bvh_bytes": g.map(|g| g.bvh_bytes),
            "gpu_group_samples": p.map(|p| p.group_samples),
            "gpu_group_size": p.map(|p| p.group_size),
            "gpu_traversal_stack": p.map(|p| p.traversal_stack),
            "gpu_timestamp_seconds": finite(p.and_then(|p| p.gpu_seconds)),
            "gpu_timestamp_ms_per_frame":
                finite(p.and_then(|p| p.gpu_seconds).map(|g| g * 1e3 / f64::from(self.spp.max(1)))),
            "nodes_per_ray": per_ray(|c| c.nodes),
            "triangles_per_ray": per_ray(|c| c.triangles),
            "max_stack_depth": counts.map(|c| c.max_stack_depth),
            "fallback_sweeps": counts.map(|c| c.fallbacks),
            "gpus_idle": finite(self.load.as_ref().map(|(l, _)| l.idle())),
            "gpus_collect_seconds": finite(self.load.as_ref().map(|(l, _)| l.collect_seconds)),
            "gpus_one_collection_seconds": finite(self.load.as_ref().map(|(_, c)| *c)),
        });
        // Beside the macro's list, which is at its recursion limit.
        value["first_frame_bvh_s"] = serde_json::json!(finite(Some(self.first_frame.bvh)));
        value["first_frame_probe_s"] = serde_json::json!(finite(Some(self.first_frame.probe)));
        value["gpus"] = serde_json::json!(devices);
        value["placed_triangles"] = serde_json::json!(self.placed);
        value["instances"] = serde_json::json!(self.instances);
        value["host_peak_bytes"] = serde_json::json!(self.host_peak_bytes);
        let mut text = serde_json::to_string_pretty(&value).unwrap_or_default();
        text.push('\n');
        text
    }
}

fn load(scene: &SceneArg, options: &furnace_scene::LoadOptions) -> Result<Scene, String> {
    crate::shared::check_builtin_options(options, matches!(scene, SceneArg::File(_)))?;
    match scene {
        SceneArg::Cbox => builtin::cornell_box().map_err(|e| e.to_string()),
        SceneArg::Interior(n) => Ok(builtin::sunlit_interior(*n)),
        SceneArg::Forest(n, seed) => Ok(builtin::forest(*n, *seed)),
        SceneArg::File(p) => Scene::load_with(p, options).map_err(|e| e.to_string()),
    }
}

pub fn run(a: &BenchArgs) -> Result<(), String> {
    let given = &a.settings.settings;
    if given.sampler.needs_sample_count() && a.spp.is_none() {
        return Err(format!(
            "the {} sampler needs the sample count in advance: give --spp (or use sobol, pmj02 or random)",
            given.sampler
        ));
    }
    // Compensated given with nee is refused; the default under nee is the plain distribution.
    if a.settings.given("env-sampling") {
        crate::env::check_sampling(given.env_sampling, given.light_sampling)?;
    }
    let start = Instant::now();
    let options = a.load.options();
    let mut scene = load(&a.scene, &options)?;
    let scene_seconds = start.elapsed().as_secs_f64();
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    if a.flatten {
        let placed = scene.stats().instanced_triangles;
        if placed > furnace_scene::MAX_TRIANGLES {
            return Err(format!(
                "--flatten: {placed} placed triangles, more than the {} a scene may store",
                furnace_scene::MAX_TRIANGLES
            ));
        }
        scene = scene.flattened();
    }
    // The scene's structure, built here to time it apart from the rest of opening, for the
    // default light's probe and then the backend, which takes it (the GPU builds an instanced
    // scene's layout of its own, in opening).
    let building = Instant::now();
    let mut accel =
        backend::takes_prebuilt(a.backend, &scene).then(|| furnace_cpu::CpuRenderer::accel_for(&scene));
    let bvh_seconds = building.elapsed().as_secs_f64();
    let probing = Instant::now();
    crate::env::apply(&mut scene, &a.environment, &mut accel)?;
    let probe_seconds = probing.elapsed().as_secs_f64();
    let camera = scene.default_camera();
    let (width, height) = match (a.width, a.height, &a.scene) {
        // The reference size for the Cornell box.
        (None, None, SceneArg::Cbox) => (256, 256),
        (w, h, _) => image_size(&camera, w, h)?,
    };
    let settings = RenderSettings {
        width,
        height,
        // The warm-up frame and the measured samples.
        sample_count: given.sampler.needs_sample_count().then(|| a.spp.map_or(1, |n| n.saturating_add(1))),
        ..*given
    };
    let triangles = scene.geometry.triangle_count() as u64;
    let (placed, instances) = (scene.stats().instanced_triangles, scene.instancing.instances.len());
    let scene_point_lights = scene.point_lights().count();
    let scene_name = match &a.scene {
        SceneArg::Cbox => "cbox".to_string(),
        SceneArg::Interior(n) => format!("interior:{n}"),
        SceneArg::Forest(n, seed) => format!("forest:{n}:{seed}"),
        SceneArg::File(p) => p.display().to_string(),
    } + if a.flatten { " (flattened)" } else { "" };
    let scene = Arc::new(scene);
    let opening = Instant::now();
    let mut engine = backend::open_chosen(
        a.backend,
        a.adapter.as_deref(),
        a.gpus.as_ref(),
        scene.clone(),
        &camera,
        settings,
        accel,
    )?;
    let adapter = adapter_name(&mut engine);
    let open_seconds = opening.elapsed().as_secs_f64();
    let backend_name = engine.name();
    if !a.quiet {
        eprintln!(
            "benchmarking {scene_name} ({triangles} triangles) at {width}×{height} on {backend_name} ({adapter})"
        );
    }
    engine.render_pass(0, 1).map_err(|e| e.to_string())?;
    let time_to_first_frame_s = start.elapsed().as_secs_f64();
    // The first frame's parts: making the scene, opening the backend (BVH, upload, pipeline)
    // and the first pass (with what the driver does at a pipeline's first dispatch).
    let pass_seconds = time_to_first_frame_s - scene_seconds - bvh_seconds - probe_seconds - open_seconds;
    let first_frame = FirstFrame {
        scene: scene_seconds,
        bvh: bvh_seconds,
        probe: probe_seconds,
        open: open_seconds,
        pass: pass_seconds,
    };
    let per_pass = warm_up(&mut engine, a, &settings)?;
    let measured = measure(&mut engine, a)?;
    let (rays, gpu, profile, load) =
        results(&mut engine, a, &measured, per_pass, || estimate_rays(a, &scene, &camera, settings))?;
    let report = Report {
        backend: backend_name,
        adapter,
        scene: scene_name,
        triangles,
        placed,
        instances,
        host_peak_bytes: host_peak_bytes(),
        width,
        height,
        bounces: settings.bounces,
        sampler: settings.sampler.to_string(),
        light_sampling: settings.light_sampling.name(),
        triangle_sampling: settings.triangle_sampling.name(),
        light_selection: settings.light_selection.name(),
        // The method used: `auto` resolved by the scene's number of lights.
        point_lights: settings.point_lights.effective(scene_point_lights).name(),
        env_sampling: settings.env_sampling.effective(settings.light_sampling).name(),
        spp: measured.spp,
        seconds: measured.seconds,
        time_to_first_frame_s,
        first_frame,
        rays,
        gpu,
        profile,
        load,
    };
    write_report(&report, a.json.as_deref())
}

/// The adapter (or adapters, or CPU threads) the backend runs on, in words.
fn adapter_name(engine: &mut Backend) -> String {
    match engine {
        Backend::Gpu(g) => g.context().info.name.clone(),
        Backend::Gpus(g) => {
            let names: Vec<String> = g.renderers().map(|r| r.context().info.name.clone()).collect();
            match names.first() {
                Some(first) if names.iter().all(|n| n == first) => format!("{} × {first}", names.len()),
                _ => names.join(" + "),
            }
        }
        Backend::Cpu(_) => {
            format!("{} threads", std::thread::available_parallelism().map_or(1, |n| n.get()))
        }
    }
}

/// The untimed passes after the first frame: the counting kernel's first dispatch, and on a
/// hardware GPU passes of the measured size for [`WARM_UP_SECONDS`]. Returns the backend's
/// samples per pixel of a pass.
fn warm_up(engine: &mut Backend, a: &BenchArgs, settings: &RenderSettings) -> Result<u32, String> {
    if let Some(r) = engine.gpu()
        && !a.no_rays
    {
        // The counting kernel is a pipeline of its own, built after the first frame (which
        // rendering would show) and run once untimed: a software adapter compiles it at its
        // first dispatch.
        r.set_count_rays(true).map_err(|e| e.to_string())?;
        engine.render_pass(0, 1).map_err(|e| e.to_string())?;
    }
    if let Some(r) = engine.gpu() {
        r.set_group_samples(a.group_samples);
    }
    let per_pass = engine.pass_samples().max(1);
    let hardware = match engine {
        Backend::Gpu(r) => furnace_gpu::context::is_hardware(&r.context().info),
        Backend::Gpus(g) => g.renderers().all(|r| furnace_gpu::context::is_hardware(&r.context().info)),
        Backend::Cpu(_) => false,
    };
    if hardware {
        // Passes of the measured size where the sampler allows (a fixed-N sampler's N counts
        // only the measured samples): the renderer's choice of invocations per pixel, made by
        // timing its first passes of that size, is then made here.
        let warm_spp = if settings.sampler.needs_sample_count() { 1 } else { per_pass };
        let warm = Instant::now();
        while warm.elapsed().as_secs_f64() < WARM_UP_SECONDS {
            engine.render_pass(0, warm_spp).map_err(|e| e.to_string())?;
        }
    }
    Ok(per_pass)
}

/// What the timed passes did.
struct Measured {
    /// Samples per pixel rendered.
    spp: u32,
    /// Their wall time.
    seconds: f64,
    /// Their GPU timestamps' sum, where the adapter has timestamps.
    gpu_seconds: Option<f64>,
}

/// The timed passes from sample 1 (after the warm-up frame): exactly --spp, or until
/// --min-seconds.
fn measure(engine: &mut Backend, a: &BenchArgs) -> Result<Measured, String> {
    let mut timing = false;
    if let Some(r) = engine.gpu() {
        r.take_trace_counts().map_err(|e| e.to_string())?;
        timing = r.set_timing(true);
    }
    if let Backend::Gpus(g) = engine {
        timing = g.set_timing(true);
        g.reset_load();
    }
    let timer = Instant::now();
    let budget = match a.spp {
        Some(n) => Budget::spp(n.saturating_add(1)),
        None => Budget { min_seconds: Some(a.min_seconds), ..Budget::spp(u32::MAX) },
    };
    let mut session = Session::new(engine, 1);
    session.run(&budget, &|| false, &mut |_| {}).map_err(|e| e.to_string())?;
    let (spp, device) = (session.done() - 1, session.timing().device);
    Ok(Measured { spp, seconds: timer.elapsed().as_secs_f64(), gpu_seconds: timing.then_some(device) })
}

/// The rays, GPU memory, GPU profile and devices' loads of the timed passes
/// (`estimate`: the CPU's rays, counted by a small GPU render).
type Results = (Rays, Option<GpuMemory>, Option<GpuProfile>, Option<(furnace_gpu::multi::Load, f64)>);

fn results(
    engine: &mut Backend,
    a: &BenchArgs,
    measured: &Measured,
    per_pass: u32,
    estimate: impl FnOnce() -> Rays,
) -> Result<Results, String> {
    let gpu_seconds = measured.gpu_seconds;
    Ok(match engine {
        Backend::Gpu(r) => {
            r.set_timing(false);
            let counts = r.take_trace_counts().map_err(|e| e.to_string())?;
            let memory = GpuMemory {
                bytes_per_triangle: r.bytes_per_triangle(),
                scene_bytes: r.scene_bytes(),
                bvh_bytes: r.bvh_bytes(),
            };
            let profile = GpuProfile {
                gpu_seconds,
                group_samples: r.group_samples(per_pass),
                group_size: r.group_size(),
                traversal_stack: r.traversal_stack_size(),
                counts: (!a.no_rays).then_some(counts),
            };
            let rays =
                if a.no_rays { Rays::None("--no-rays".to_string()) } else { Rays::Counted(counts.rays) };
            (rays, Some(memory), Some(profile), None)
        }
        Backend::Gpus(g) => {
            // The devices' loads in the timed passes, and the time of one collection of every
            // device's film (which a render does at its end, at each checkpoint it saves and
            // at each adaptive-sampling test).
            let load = g.load();
            let t = Instant::now();
            Integrator::film(g.as_mut()).map_err(|e| e.to_string())?;
            let load = Some((load, t.elapsed().as_secs_f64()));
            g.set_timing(false);
            // The first device's kernel shape, for its own share of a pass (every device
            // decides alike for one model).
            let profile = g.renderers().next().map(|r| GpuProfile {
                gpu_seconds,
                group_samples: r.group_samples(Integrator::pass_samples(r)),
                group_size: r.group_size(),
                traversal_stack: r.traversal_stack_size(),
                counts: None,
            });
            (Rays::None("no ray counts on several GPUs".to_string()), None, profile, load)
        }
        Backend::Cpu(_) if a.no_rays => (Rays::None("--no-rays".to_string()), None, None, None),
        Backend::Cpu(_) => (estimate(), None, None, None),
    })
}

/// The process's peak resident set (`VmHWM` of `/proc/self/status`), where the system has it.
fn host_peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The table on stdout, and the JSON to `json` (`-`: the JSON on stdout, the table on stderr).
fn write_report(report: &Report, json_path: Option<&Path>) -> Result<(), String> {
    let json = report.json();
    match json_path {
        Some(p) if p == Path::new("-") => {
            eprint!("{}", report.table());
            print!("{json}");
        }
        Some(p) => {
            print!("{}", report.table());
            write_atomically(p, json.as_bytes())?;
        }
        None => print!("{}", report.table()),
    }
    std::io::stdout().flush().map_err(|e| format!("stdout: {e}"))
}

/// CPU rays per sample, counted by a GPU render of the same scene and settings on a small image
/// of the same aspect ratio ([`ESTIMATE`], [`ESTIMATE_SOFTWARE`]).
fn estimate_rays(
    a: &BenchArgs,
    scene: &Scene,
    camera: &furnace_scene::Camera,
    settings: RenderSettings,
) -> Rays {
    let choice = match &a.adapter {
        Some(name) => AdapterChoice::Named(name.clone()),
        None => AdapterChoice::Best,
    };
    let ctx = match GpuContext::new(&choice) {
        Ok(c) => c,
        Err(e) => {
            return Rays::None(format!(
                "the CPU integrator has no ray counter and no GPU adapter counts for it ({e})"
            ));
        }
    };
    let (pixels, spp) =
        if furnace_gpu::context::is_hardware(&ctx.info) { ESTIMATE } else { ESTIMATE_SOFTWARE };
    let (w, h) = (f64::from(settings.width), f64::from(settings.height));
    let scale = (pixels / (w * h)).sqrt().min(1.0);
    let (sw, sh) = (((w * scale).round() as u32).max(1), ((h * scale).round() as u32).max(1));
    let small = RenderSettings {
        width: sw,
        height: sh,
        sample_count: settings.sample_count.map(|n| n.max(spp)),
        ..settings
    };
    let adapter = ctx.info.name.clone();
    let count = || -> Result<u64, String> {
        let mut r = GpuRenderer::new(ctx, scene, camera, small).map_err(|e| e.to_string())?;
        r.set_count_rays(true).map_err(|e| e.to_string())?;
        r.render_pass(0, spp).map_err(|e| e.to_string())?;
        r.take_ray_count().map_err(|e| e.to_string())
    };
    match count() {
        Ok(n) => Rays::Estimated {
            per_sample: n as f64 / (f64::from(sw) * f64::from(sh) * f64::from(spp)),
            how: format!(
                "rays per sample counted on the GPU ({adapter}) on a {sw}×{sh} render at {spp} spp of the same scene and settings"
            ),
        },
        Err(e) => Rays::None(format!("the CPU integrator has no ray counter and the GPU count failed ({e})")),
    }
}
