//! Command-line arguments (clap derive) and their value parsers. The render settings' flags
//! are built from the settings' own description (`settings`).

mod chart;
mod settings;

pub use chart::{ChartArgs, ChartBackend, ChartTime};
pub use settings::{Bench, Render, SettingsArgs, choice};

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use furnace_cli::backend::BackendChoice;
use furnace_denoise::DeviceKind;
use furnace_post::Tonemap;
use furnace_render::SampleRange;
use furnace_scene::Camera;
use glam::Vec3;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::str::FromStr;

/// furnace: a progressive path tracer.
#[derive(Debug, Parser)]
#[command(name = "furnace", version, about, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a glTF/GLB scene (the built-in reference Cornell box without one) to PATH.exr
    /// (linear, with metadata) and PATH.png (tone-mapped sRGB).
    Render(RenderArgs),
    /// Watch a scene render live in a window: the GPU integrator's film converging, tone-mapped
    /// on the GPU; move the camera (orbit, pan, dolly, fly), change settings, save EXR + PNG
    /// (Ctrl+S: what `render` writes, resumable with `render --resume`). Takes render's options;
    /// without --spp it accumulates until closed. Press ? in the window for the controls.
    View(ViewArgs),
    /// Print a scene's triangles, materials, textures, lights, camera and loader warnings, and
    /// the render settings that render's settings flags (given here too) make.
    Info(InfoArgs),
    /// Score a candidate EXR against a reference EXR (furnace_post::metrics): RMSE,
    /// relative MSE, per-channel mean ratio and, with --stderr, per-pixel z-score statistics.
    Compare(CompareArgs),
    /// Add up the parts of a split render (`furnace render --samples A..B`) into PATH.exr and
    /// PATH.png, as the single run would have written them (the same film to float rounding);
    /// refuses parts of different renders, overlapping parts and, unless --allow-gaps, missing
    /// samples (listed).
    Merge(MergeArgs),
    /// Measure a backend on a scene: Msamples/s, Mrays/s, ms per frame, time to first frame and
    /// GPU bytes per triangle, as a Markdown table and JSON.
    Bench(BenchArgs),
    /// Speed against accuracy: render a scene under several configurations (sampler × BRDF
    /// sampling × compensation × backend), record error against a reference and time at
    /// checkpoints of 1, 2, 4, … spp, and write CSV, JSON and error-vs-spp / error-vs-time charts.
    Chart(ChartArgs),
}

/// How a scene file is loaded (`render`, `view`, `info`, `bench`).
#[derive(Debug, Clone, Default, Args)]
pub struct LoadArgs {
    /// A missing, unreadable or undecodable texture image is an error [default: a warning, and
    /// the material renders with its factors alone].
    #[arg(long)]
    pub strict: bool,
    /// The KHR_materials_variants variant to load, by name or index (`furnace info` lists a
    /// file's variants) [default: each primitive's own material].
    #[arg(long, value_name = "NAME")]
    pub variant: Option<String>,
    /// The animation to pose the scene by, by name or index (`furnace info` lists a file's
    /// animations), sampled at --time [default: with --time, animation 0; else none: the nodes'
    /// own transforms and morph weights].
    #[arg(long, value_name = "NAME")]
    pub animation: Option<String>,
    /// The time, in seconds, at which the animation is sampled (each channel clamped to its
    /// keyframes) [default: 0 with --animation].
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = parse_time)]
    pub time: Option<f32>,
}

impl LoadArgs {
    /// The scene crate's load options these flags make.
    pub fn options(&self) -> furnace_scene::LoadOptions {
        furnace_scene::LoadOptions {
            strict: self.strict,
            variant: self.variant.clone(),
            animation: self.animation.clone(),
            time: self.time,
        }
    }
}

/// `furnace render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// The .gltf or .glb scene, or interior:N (the procedural sunlit interior of about N
    /// triangles, e.g. interior:1e7, for stress tests), or forest:N or forest:N:SEED (N instanced plants
    /// of 10⁴–10⁵ triangles on terrain, e.g. forest:1e5); without it, the built-in reference
    /// Cornell box (with --resume: the scene the file was rendered from).
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub load: LoadArgs,
    /// Samples per pixel (the total, also when resuming; also N of the fixed-N samplers
    /// hammersley and cmj).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Continue the render saved in PATH.exr (by furnace, finished, stopped by --time-limit or
    /// Ctrl-C) up to --spp samples per pixel, bit-identical to an uninterrupted render. Settings
    /// not given are the file's; settings given must match it. Writes to PATH unless --out.
    #[arg(long, value_name = "PATH.exr")]
    pub resume: Option<PathBuf>,
    /// Render only the global sample indices A to B−1 of the render: one part of a split render
    /// (`furnace merge` adds the parts up to the film of a single run). --spp is then the whole
    /// render's sample count (default B; the fixed-N samplers hammersley and cmj need it given).
    /// The part is recorded in the EXR; --resume continues it up to B.
    #[arg(long, value_name = "A..B", conflicts_with = "noise-threshold")]
    pub samples: Option<SampleRange>,
    /// Also save the render so far (EXR and PNG, atomically) every SECONDS of rendering, so that
    /// a process killed without warning (SIGKILL, a lost node) loses at most that much work.
    /// Ctrl-C and SIGTERM (a scheduler's cancel, preemption or time limit) always save.
    #[arg(long, allow_negative_numbers = true, value_name = "SECONDS", value_parser = parse_interval)]
    pub checkpoint: Option<f64>,
    // The render settings (--bounces, --sampler, --seed, the material model, the light
    // sampling, --clamp, adaptive sampling), from `furnace_render::fields`.
    #[command(flatten)]
    pub settings: SettingsArgs<Render>,
    /// Image width in pixels [default: 512, or from --height and the camera's aspect ratio].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub width: Option<u32>,
    /// Image height in pixels [default: from the width and the camera's aspect ratio; 512 for
    /// the built-in Cornell box].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub height: Option<u32>,
    /// Exposure in stops (EV) applied before tone mapping the PNG (the EXR stays unscaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub exposure: f32,
    /// Tone map of the PNG: aces, pbr-neutral, clamp.
    #[arg(long, default_value_t = Tonemap::default())]
    pub tonemap: Tonemap,
    /// Which of the scene's cameras to render (0-based, in `furnace info` order) [default: the
    /// first; a scene without one is framed around its geometry].
    #[arg(long, value_name = "INDEX")]
    pub camera: Option<u32>,
    /// A free camera instead of the scene's: at the eye (EX,EY,EZ), looking at the target
    /// (TX,TY,TZ), with up (UX,UY,UZ) [default up: 0,1,0]; world coordinates of the scene. The
    /// image is square unless --width and --height say otherwise.
    #[arg(
        long,
        value_name = "EX,EY,EZ,TX,TY,TZ[,UX,UY,UZ]",
        allow_hyphen_values = true,
        conflicts_with = "camera"
    )]
    pub look_at: Option<LookAt>,
    /// Vertical field of view of the --look-at camera in degrees, between 0 and 180 [default:
    /// the scene's first perspective camera's, else 45].
    #[arg(long, allow_negative_numbers = true, value_name = "DEG", requires = "look_at", value_parser = parse_yfov)]
    pub yfov: Option<f32>,
    /// Denoise the finished image with Intel Open Image Denoise, guided by the albedo and normal
    /// AOVs (so it implies --aovs): writes PATH.denoised.png and the EXR layer denoised.R/G/B;
    /// the raw image stays exact and resumable. Needs a furnace built with `--features denoise`.
    #[arg(long)]
    pub denoise: bool,
    /// Where Open Image Denoise runs: auto (a GPU it can drive, else the CPU), cpu, cuda, hip,
    /// sycl, metal.
    #[arg(long, value_parser = denoise_device(), default_value = "auto", value_name = "DEVICE")]
    pub denoise_device: DeviceKind,
    /// Denoise the albedo and normal guides first (for noisy guides: a few samples per pixel,
    /// textures finer than a pixel; about 3× the denoising time).
    #[arg(long)]
    pub denoise_prefilter: bool,
    /// Also write the first-hit AOVs, averaged over the same samples as the image, as layers of
    /// the EXR: albedo.R/G/B (base colour; 1 where the camera sees the sky), normal.X/Y/Z (world
    /// shading normal; 0 for the sky) and Z (distance along the camera ray; +inf for the sky).
    /// Costs 64 bytes per pixel while rendering. A resumed render keeps the file's AOVs.
    #[arg(long)]
    pub aovs: bool,
    /// The sun's angular diameter in degrees (0: a delta sun, hard shadows; the real sun is
    /// about 0.53), replacing the scene's `extras.angular_diameter_deg`.
    #[arg(long, allow_negative_numbers = true, value_name = "DEG", value_parser = parse_sun_angle)]
    pub sun_angle: Option<f32>,
    // The environment map and how it is placed (--env, --env-intensity, --env-rotation,
    // --env-visible).
    #[command(flatten)]
    pub environment: EnvArgs,
    /// Where to render: cpu (the reference integrator), gpu (wgpu: Vulkan, Metal or DX12), or
    /// auto (a hardware GPU if there is one, else the CPU; software GPUs such as lavapipe are
    /// slower than the CPU integrator and used only when asked for).
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// The GPU adapter: a part of its name (case-insensitive), its PCI address (0000:18:00.0, as
    /// `nvidia-smi --query-gpu=pci.bus_id` prints it) or its index in the list that an unknown
    /// name prints; implies --backend gpu when --backend is auto.
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
    /// Render on several GPUs at once: `all` (every hardware adapter), or a comma-separated
    /// list of adapters as --adapter names them (a part of a name takes every adapter that
    /// matches: `H200`). Each pass's samples are shared among them; a GPU that fails leaves its
    /// samples to the others. Not with --adapter or --backend cpu.
    #[arg(long, value_name = "all|LIST", conflicts_with = "adapter")]
    pub gpus: Option<furnace_cli::backend::GpuSet>,
    /// Output path: writes PATH.png and PATH.exr (a .png or .exr extension is replaced).
    #[arg(long, default_value = "furnace")]
    pub out: PathBuf,
    /// No progress bar and no summary (warnings and errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
    /// Stop after this many seconds (at a whole number of passes; at least one pass is done).
    #[arg(long, allow_negative_numbers = true, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_limit: Option<f64>,
    /// The ids of the arguments given on the command line (not defaulted): filled by `main`
    /// from clap's matches; a resumed render takes the others from the file.
    #[arg(skip)]
    pub given: BTreeSet<String>,
}

impl RenderArgs {
    /// Whether argument `id` (the field name) was given on the command line.
    pub fn given(&self, id: &str) -> bool {
        self.given.contains(id)
    }
}

/// The values of `--denoise-device`: its name, help and device.
const DENOISE_DEVICES: [(&str, &str, DeviceKind); 6] = [
    ("auto", "A GPU Open Image Denoise can drive, else the CPU", DeviceKind::Default),
    ("cpu", "The CPU", DeviceKind::Cpu),
    ("cuda", "An NVIDIA GPU (CUDA)", DeviceKind::Cuda),
    ("hip", "An AMD GPU (HIP)", DeviceKind::Hip),
    ("sycl", "An Intel GPU (SYCL)", DeviceKind::Sycl),
    ("metal", "An Apple GPU (Metal)", DeviceKind::Metal),
];

/// `--denoise-device`: a device of [`DENOISE_DEVICES`] by name.
fn denoise_device() -> impl TypedValueParser<Value = DeviceKind> {
    PossibleValuesParser::new(DENOISE_DEVICES.map(|(name, help, _)| PossibleValue::new(name).help(help)))
        .try_map(|s| {
            DENOISE_DEVICES
                .iter()
                .find(|d| d.0 == s)
                .map(|d| d.2)
                .ok_or_else(|| format!("'{s}' is not a device"))
        })
}

/// `--look-at`: a perspective camera's pose, from an eye, a target and an up direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LookAt {
    /// Where the camera is.
    pub eye: Vec3,
    /// The point it looks at (not the eye).
    pub target: Vec3,
    /// Which way is up (not parallel to `target - eye`; the camera's up is its part orthogonal
    /// to the view direction).
    pub up: Vec3,
}

impl LookAt {
    /// The perspective camera of this pose with a vertical field of view of `yfov_deg` degrees.
    pub fn camera(&self, yfov_deg: f32) -> Camera {
        Camera::look_at(self.eye, self.target, self.up, yfov_deg.to_radians())
    }
}

impl FromStr for LookAt {
    type Err = String;

    /// `EX,EY,EZ,TX,TY,TZ` or `EX,EY,EZ,TX,TY,TZ,UX,UY,UZ` (up defaults to +Y): finite numbers,
    /// the eye not at the target, the up direction not parallel to the view direction.
    fn from_str(s: &str) -> Result<Self, String> {
        let x = s
            .split(',')
            .map(|t| match t.trim().parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => Err(format!("'{}' is not a finite number", t.trim())),
                Err(_) => Err(format!("'{}' is not a number", t.trim())),
            })
            .collect::<Result<Vec<f32>, String>>()?;
        let up = match x.len() {
            6 => Vec3::Y,
            9 => Vec3::from_slice(&x[6..]),
            n => {
                return Err(format!(
                    "expected 6 or 9 comma-separated numbers (eye x,y,z, target x,y,z[, up x,y,z]), \
                     got {n}"
                ));
            }
        };
        let look = LookAt { eye: Vec3::from_slice(&x[0..3]), target: Vec3::from_slice(&x[3..6]), up };
        // What `Camera::look_at` needs for a direction: a view vector and an up vector whose
        // squared lengths neither overflow nor underflow in f32.
        let view = look.target - look.eye;
        if view == Vec3::ZERO {
            return Err("the eye and the target are the same point".into());
        }
        let forward = view.normalize_or_zero();
        if forward == Vec3::ZERO {
            return Err("the eye and the target are too far apart or too close together".into());
        }
        if look.up == Vec3::ZERO {
            return Err("the up direction is zero".into());
        }
        let length = look.up.length();
        if !(1e-10..=1e10).contains(&length) {
            return Err(format!("the up direction's length {length:e} is out of range (1e-10 to 1e10)"));
        }
        // Nearly parallel would leave the camera's roll to rounding.
        if forward.cross(look.up / length).length() < 1e-4 {
            return Err(
                "the up direction is parallel to the view direction (from the eye to the target)".into()
            );
        }
        Ok(look)
    }
}

impl std::fmt::Display for LookAt {
    /// The nine numbers, comma-separated, each as Rust's shortest form that parses back to the
    /// same `f32` (what the EXR records, so that a resumed render rebuilds the same camera).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b, c] = self.eye.to_array();
        let [d, e, g] = self.target.to_array();
        let [h, i, j] = self.up.to_array();
        write!(f, "{a},{b},{c},{d},{e},{g},{h},{i},{j}")
    }
}

/// `furnace view`.
#[derive(Debug, Clone, Args)]
#[command(
    mut_arg("spp", |a| a.help("Stop accumulating at this many samples per pixel (also N of the fixed-N samplers hammersley and cmj) [default: never; 64 for hammersley and cmj]").hide_default_value(true)),
    mut_arg("out", |a| a.help("Where Ctrl+S saves: PATH.png and PATH.exr (a .png or .exr extension is replaced)")),
    mut_arg("time_limit", |a| a.help("Stop accumulating after this many seconds of rendering")),
    mut_arg("quiet", |a| a.help("No messages on stderr (warnings and errors are still printed)")),
    mut_arg("samples", |a| a.hide(true)),
    mut_arg("checkpoint", |a| a.hide(true)),
    mut_arg("backend", |a| a.help("gpu or auto (both: the GPU integrator, software adapters such as lavapipe included); cpu is refused: the window shows the GPU's film"))
)]
pub struct ViewArgs {
    /// The render's options.
    #[command(flatten)]
    pub render: RenderArgs,
    /// Drive the viewer by the commands of FILE (`-`: standard input, read as it comes), one per
    /// line, each acknowledged on stdout: wait-spp N, wait-frames N, wait-seconds S, drag
    /// left|middle|right DX DY, scroll STEPS, key NAME, hold KEY SECONDS, set NAME VALUE, save
    /// \[PATH\], resize W H, print, quit.
    #[arg(long, value_name = "FILE|-")]
    pub script: Option<PathBuf>,
}

/// `furnace info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The .gltf or .glb scene.
    pub scene: PathBuf,
    #[command(flatten)]
    pub load: LoadArgs,
    // The render settings' flags, as `furnace render` takes them: the settings they make are
    // printed after the scene.
    #[command(flatten)]
    pub settings: SettingsArgs<Render>,
}

/// `furnace compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The candidate render (.exr).
    pub candidate: PathBuf,
    /// The reference render (.exr), of the same size.
    pub reference: PathBuf,
    /// The reference's per-pixel standard error (.exr): enables the z-score statistics.
    #[arg(long, value_name = "REF_STDERR.exr")]
    pub stderr: Option<PathBuf>,
    /// The candidate's per-pixel standard error (.exr), added in quadrature to the reference's.
    #[arg(long, value_name = "C_STDERR.exr", requires = "stderr")]
    pub candidate_stderr: Option<PathBuf>,
    /// Write a PNG of |candidate − reference| per pixel, its 99th percentile mapped to white.
    #[arg(long, value_name = "PATH.png")]
    pub error_map: Option<PathBuf>,
}

/// `furnace merge`.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// The parts: EXRs written by `furnace render --samples A..B` of one render (whole renders
    /// and earlier merges of it are parts too), in any order.
    #[arg(required = true, value_name = "PART.exr")]
    pub parts: Vec<PathBuf>,
    /// Output path: writes PATH.exr and PATH.png (a .png or .exr extension is replaced); never
    /// one of the parts.
    #[arg(long, short, value_name = "PATH")]
    pub out: PathBuf,
    /// Merge even if sample indices of the render are missing (a part not rendered, or stopped
    /// early): the image is then the mean over the samples present, and the file lists them.
    #[arg(long)]
    pub allow_gaps: bool,
    /// Tone map of the PNG: aces, pbr-neutral, clamp [default: the parts'].
    #[arg(long)]
    pub tonemap: Option<Tonemap>,
    /// Exposure of the PNG in stops [default: the parts'].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_exposure)]
    pub exposure: Option<f32>,
    /// Denoise the merged image with Intel Open Image Denoise (guided by the albedo and normal
    /// when every part has AOVs: render them with --aovs or --denoise): writes
    /// PATH.denoised.png and the EXR layer denoised.R/G/B, as `render --denoise` does. Needs a
    /// furnace built with `--features denoise`.
    #[arg(long)]
    pub denoise: bool,
    /// Where Open Image Denoise runs: auto, cpu, cuda, hip, sycl, metal.
    #[arg(long, value_parser = denoise_device(), default_value = "auto", value_name = "DEVICE")]
    pub denoise_device: DeviceKind,
    /// No summary (errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `furnace bench`.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Where to run: cpu, gpu or auto (as `furnace render --backend`).
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    pub backend: BackendChoice,
    /// The GPU adapter: a part of its name or its index; implies --backend gpu when auto.
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
    /// Run on several GPUs at once (as `furnace render --gpus`): `all` or a list of adapters.
    /// No ray counts (as --no-rays).
    #[arg(long, value_name = "all|LIST", conflicts_with_all = ["adapter", "group_samples"])]
    pub gpus: Option<furnace_cli::backend::GpuSet>,
    /// The scene: cbox (the built-in reference Cornell box), interior:N (the procedural sunlit
    /// interior of about N triangles, e.g. interior:1e6), forest:N or forest:N:SEED (N instanced plants
    /// on terrain, e.g. forest:1e5), or a .gltf/.glb path.
    #[arg(long, default_value = "cbox", value_parser = parse_scene)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub load: LoadArgs,
    /// Image width [default: 256 for cbox, else 512 or from --height and the camera].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub width: Option<u32>,
    /// Image height [default: 256 for cbox, else from the width and the camera].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub height: Option<u32>,
    /// Measure exactly this many samples per pixel (after the 1-spp first frame) instead of
    /// passes for --min-seconds.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Without --spp: render passes until this many seconds have passed.
    #[arg(long, allow_negative_numbers = true, value_name = "SECONDS", default_value_t = 2.0, value_parser = parse_seconds)]
    pub min_seconds: f64,
    // The settings whose speed it measures (--bounces, --sampler, the light sampling), as
    // `furnace render` takes them.
    #[command(flatten)]
    pub settings: SettingsArgs<Bench>,
    // The environment map and how it is placed (as `furnace render`).
    #[command(flatten)]
    pub environment: EnvArgs,
    /// Also write the results as JSON to PATH (`-`: JSON on stdout, the table on stderr).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Copy the scene's instances into world space before rendering (one BVH over every placed
    /// triangle): what instancing saves, or costs, measured on the same scene.
    #[arg(long)]
    pub flatten: bool,
    /// Do not count rays: on the GPU, no traversal counters (rays, nodes, triangles per ray);
    /// on the CPU, no estimate of rays per sample (it renders a small image on a GPU adapter,
    /// software included).
    #[arg(long)]
    pub no_rays: bool,
    /// GPU: invocations per pixel in a workgroup (a power of two, 1–1024: up to the workgroup's
    /// size, 1024 on most hardware and 256 on software adapters) instead of the renderer's choice
    /// (on hardware 16 for small images, fewer for large ones; 1 on software adapters) — for
    /// occupancy studies.
    #[arg(
        long,
        value_name = "N",
        value_parser = clap::value_parser!(u32).range(1..=i64::from(furnace_gpu::integrator::HARDWARE_GROUP_SIZE))
    )]
    pub group_samples: Option<u32>,
    /// No progress line on stderr.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `furnace bench --scene`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SceneArg {
    /// The built-in reference Cornell box.
    Cbox,
    /// `furnace_scene::builtin::sunlit_interior` of about this many triangles.
    Interior(u32),
    /// `furnace_scene::builtin::forest` of this many instances, with this seed.
    Forest(u32, u64),
    /// A glTF/GLB file.
    File(PathBuf),
}

/// The most triangles `--scene interior:N` accepts.
pub const MAX_INTERIOR_TRIANGLES: u32 = 20_000_000;

/// A whole number written plainly or in scientific notation (`1000000`, `1e6`, `1_000_000`).
fn whole_number(n: &str) -> Option<u64> {
    let t = n.trim().replace('_', "");
    t.parse::<u64>().ok().or_else(|| {
        t.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && *x >= 0.0 && x.fract() == 0.0 && *x < 1e19)
            .map(|x| x as u64)
    })
}

/// Whether `s` names a built-in scene with a parameter (`interior:N`, `forest:N`).
pub(crate) fn is_builtin_scene(s: &str) -> bool {
    s.starts_with("interior:") || s.starts_with("forest:")
}

pub(crate) fn parse_scene(s: &str) -> Result<SceneArg, String> {
    if s == "cbox" {
        return Ok(SceneArg::Cbox);
    }
    if let Some(rest) = s.strip_prefix("forest:") {
        let (n, seed) = rest.split_once(':').unwrap_or((rest, "0"));
        let max = furnace_scene::MAX_INSTANCES;
        return match (whole_number(n), whole_number(seed)) {
            (Some(v), Some(seed)) if (1..=max).contains(&v) => Ok(SceneArg::Forest(v as u32, seed)),
            (Some(v), Some(_)) => Err(format!("forest:{v}: the instance count must be from 1 to {max}")),
            _ => Err(format!(
                "'{s}': forest:N[:SEED] needs a whole number of instances and of seed (e.g. forest:1e5 or forest:1000:7)"
            )),
        };
    }
    if let Some(n) = s.strip_prefix("interior:") {
        let value = whole_number(n);
        return match value {
            Some(v) if (1..=u64::from(MAX_INTERIOR_TRIANGLES)).contains(&v) => {
                Ok(SceneArg::Interior(v as u32))
            }
            Some(v) => {
                Err(format!("interior:{v}: the triangle count must be from 1 to {MAX_INTERIOR_TRIANGLES}"))
            }
            None => Err(format!(
                "'{s}': interior:N needs a whole number of triangles (e.g. interior:1000000 or interior:1e6)"
            )),
        };
    }
    let lower = s.to_ascii_lowercase();
    if lower.ends_with(".gltf") || lower.ends_with(".glb") {
        return Ok(SceneArg::File(PathBuf::from(s)));
    }
    Err(format!(
        "unknown scene '{s}': expected cbox, interior:N (about N triangles), forest:N (N instanced plants) or a \
         .gltf/.glb path"
    ))
}

/// The largest image side accepted: the largest image furnace reads back
/// (`furnace_post::MAX_IMAGE_SIDE`), so that every render can be resumed, merged and compared.
/// A 16384² film takes 8 GiB of sums and counts, more with AOVs or adaptive sampling.
pub const MAX_SIDE: u32 = furnace_post::MAX_IMAGE_SIDE;

/// `--env`: a map file, the built-in studio, or no environment.
#[derive(Debug, Clone, PartialEq)]
pub enum EnvArg {
    /// A latitude-longitude .hdr/.exr map.
    File(PathBuf),
    /// The built-in studio map (`EnvironmentMap::studio`).
    Studio,
    /// No environment, not even the default light.
    None,
}

impl std::fmt::Display for EnvArg {
    /// As given: the path, `studio` or `none` (what the EXR records).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::File(p) => write!(f, "{}", p.display()),
            Self::Studio => f.write_str("studio"),
            Self::None => f.write_str("none"),
        }
    }
}

/// The environment options of `furnace render`, `bench` and `chart`.
#[derive(Debug, Clone, Default, Args)]
pub struct EnvArgs {
    /// The environment map: FILE (a latitude-longitude .hdr or .exr; ./studio for a file of
    /// that name), studio (the built-in neutral studio light) or none (no environment). It
    /// replaces the scene's own. Without it, a scene with no light of its own (no sun, sky,
    /// lamp, emissive material or environment) is lit by the built-in studio.
    #[arg(long, value_name = "FILE|studio|none", value_parser = parse_env)]
    pub env: Option<EnvArg>,
    /// Scale of the environment's radiance (the scene's own or --env's) [default: the scene's,
    /// else 1].
    #[arg(long, value_name = "X", allow_negative_numbers = true, value_parser = parse_env_intensity)]
    pub env_intensity: Option<f32>,
    /// Rotation of the environment about +Y in degrees, right-handed (+X turns towards −Z)
    /// [default: the scene's, else 0].
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = parse_env_rotation)]
    pub env_rotation: Option<f32>,
    /// Whether camera rays that leave the scene see the environment (off: they see the scene's
    /// constant sky, black without one; it still lights the scene and shows in reflections)
    /// [default: on].
    #[arg(long, value_enum, value_name = "on|off")]
    pub env_visible: Option<Switch>,
}

impl EnvArgs {
    /// Whether an option that changes an environment (intensity, rotation, visibility) was given.
    pub fn adjusts(&self) -> bool {
        self.env_intensity.is_some() || self.env_rotation.is_some() || self.env_visible.is_some()
    }
}

pub(crate) fn parse_env(s: &str) -> Result<EnvArg, String> {
    match s {
        "" => Err("--env needs a file, studio or none".into()),
        "studio" => Ok(EnvArg::Studio),
        "none" => Ok(EnvArg::None),
        _ => Ok(EnvArg::File(PathBuf::from(s))),
    }
}

fn parse_env_intensity(s: &str) -> Result<f32, String> {
    let x: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(format!("the environment's intensity must be a finite number ≥ 0 (got {s})"))
    }
}

fn parse_env_rotation(s: &str) -> Result<f32, String> {
    let d: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of degrees"))?;
    if d.is_finite() {
        Ok(d)
    } else {
        Err(format!("the environment's rotation must be a finite number of degrees (got {s})"))
    }
}

/// An on/off switch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// A vertical field of view in degrees: a number strictly between 0 and 180.
pub(crate) fn parse_yfov(s: &str) -> Result<f32, String> {
    let d: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of degrees"))?;
    if d > 0.0 && d < 180.0 {
        Ok(d)
    } else {
        Err(format!("the vertical field of view must be between 0 and 180 degrees, both excluded (got {s})"))
    }
}

fn parse_sun_angle(s: &str) -> Result<f32, String> {
    let d: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of degrees"))?;
    if (0.0..=180.0).contains(&d) {
        Ok(d)
    } else {
        Err(format!("the sun's angular diameter must be between 0 and 180 degrees (got {s})"))
    }
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    let ev: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of stops"))?;
    if ev.is_finite() && ev.abs() <= 64.0 {
        Ok(ev)
    } else {
        Err(format!("exposure must be between -64 and 64 stops (got {s})"))
    }
}

fn parse_interval(s: &str) -> Result<f64, String> {
    positive_seconds(s, "the checkpoint interval")
}

/// `--time`: a finite number of seconds ≥ 0.
fn parse_time(s: &str) -> Result<f32, String> {
    let t: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if t.is_finite() && t >= 0.0 {
        Ok(t)
    } else {
        Err(format!("the animation time must be a finite number of seconds ≥ 0 (got {s})"))
    }
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    positive_seconds(s, "the time limit")
}

/// A positive, finite number of seconds; `what` names it in the error.
fn positive_seconds(s: &str, what: &str) -> Result<f64, String> {
    let t: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number of seconds"))?;
    if t.is_finite() && t > 0.0 {
        Ok(t)
    } else {
        Err(format!("{what} must be a positive number of seconds (got {s})"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn defaults_match_the_library_defaults() {
        let cli = Cli::try_parse_from(["furnace", "render"]).unwrap();
        let Command::Render(a) = cli.command else { panic!("not render") };
        assert_eq!(a.settings.settings, furnace_render::RenderSettings::default());
        assert!(a.settings.given.is_empty());
        assert_eq!(a.tonemap, Tonemap::Aces);
        assert_eq!((a.spp, a.exposure), (64, 0.0));
        let cli = Cli::try_parse_from(["furnace", "bench", "--light-selection", "power"]).unwrap();
        let Command::Bench(b) = cli.command else { panic!("not bench") };
        assert_eq!(b.settings.settings.light_selection, furnace_render::LightSelection::Power);
        assert!(b.settings.given("light-selection") && !b.settings.given("bounces"));
        assert!(
            Cli::try_parse_from(["furnace", "bench", "--seed", "1"]).is_err(),
            "bench measures at seed 0"
        );
    }

    #[test]
    fn negative_exposure_parses() {
        let cli = Cli::try_parse_from(["furnace", "render", "--exposure", "-1.5"]).unwrap();
        let Command::Render(a) = cli.command else { panic!("not render") };
        assert_eq!(a.exposure, -1.5);
        assert!(Cli::try_parse_from(["furnace", "render", "--exposure", "nan"]).is_err());
        assert!(Cli::try_parse_from(["furnace", "render", "--time-limit", "0"]).is_err());
        assert!(Cli::try_parse_from(["furnace", "render", "--spp", "0"]).is_err());
    }

    #[test]
    fn signed_values_parse_without_equals() {
        let render = |args: &[&str]| Cli::try_parse_from([&["furnace", "render"], args].concat());
        let Command::Render(a) =
            render(&["--exposure", "-1", "--env-rotation", "-90", "--look-at", "-1,0,0,0,0,0"])
                .unwrap()
                .command
        else {
            panic!("not render")
        };
        assert_eq!((a.exposure, a.environment.env_rotation), (-1.0, Some(-90.0)));
        // A negative value where none is valid reaches its parser, which says why it is refused
        // (not clap's "unexpected argument '-1'").
        for (flag, needle) in [
            ("--sun-angle", "-1"),
            ("--clamp", "above 0"),
            ("--time-limit", "positive"),
            ("--env-intensity", "-1"),
            ("--bounces", "whole number"),
        ] {
            let e = render(&[flag, "-1"]).unwrap_err().to_string();
            assert!(e.contains(needle) && !e.contains("unexpected argument"), "{flag}: {e}");
        }
        let merge = Cli::try_parse_from(["furnace", "merge", "a.exr", "-o", "m", "--exposure", "-2"]);
        assert!(merge.is_ok(), "{merge:?}");
    }

    #[test]
    fn bounces_are_bounded_everywhere() {
        let max = furnace_render::MAX_BOUNCES.to_string();
        let over = (furnace_render::MAX_BOUNCES + 1).to_string();
        for command in ["render", "view", "bench", "chart"] {
            let parse = |n: &str| Cli::try_parse_from(["furnace", command, "--bounces", n]);
            if command != "chart" {
                assert!(parse(&max).is_ok(), "{command} --bounces {max}");
            }
            let e = parse(&over).unwrap_err().to_string();
            assert!(e.contains("at most 1024 scattering events"), "{command}: {e}");
            assert!(parse("4294967295").is_err(), "{command}");
        }
    }

    #[test]
    fn look_at_parses_displays_and_round_trips() {
        let l: LookAt = "-1, 2.5,3e-3,0,0,0".parse().unwrap();
        assert_eq!((l.eye, l.target, l.up), (Vec3::new(-1.0, 2.5, 3e-3), Vec3::ZERO, Vec3::Y));
        assert_eq!(l.to_string(), "-1,2.5,0.003,0,0,0,0,1,0");
        // Numbers that are not short decimals come back bit for bit.
        let odd = LookAt {
            eye: Vec3::new(0.1 + 0.2, -1.0 / 3.0, 1e-30),
            target: Vec3::new(1.2345678e18, 7.0e-8, -0.0),
            up: Vec3::new(0.0, 0.6, 0.80000013),
        };
        let back: LookAt = odd.to_string().parse().unwrap();
        let bits = |l: &LookAt| [l.eye, l.target, l.up].map(|v| v.to_array().map(f32::to_bits));
        assert_eq!(bits(&back), bits(&odd));
        // The camera is at the eye, looking at the target.
        let c = "0,0,4,0,0,0".parse::<LookAt>().unwrap().camera(45.0);
        assert_eq!(Vec3::from(c.world_from_camera.translation), Vec3::new(0.0, 0.0, 4.0));
        assert!((c.world_from_camera.transform_vector3(Vec3::NEG_Z) - Vec3::NEG_Z).length() < 1e-6);
    }

    #[test]
    fn bad_look_at_values_say_what_is_wrong() {
        for (s, needle) in [
            ("1,2", "expected 6 or 9 comma-separated numbers"),
            ("1,2,3,4,5,6,7", "got 7"),
            ("1,2,x,4,5,6", "'x' is not a number"),
            ("1,2,inf,4,5,6", "'inf' is not a finite number"),
            ("1,2,3,1,2,3", "the same point"),
            ("0,0,0,0,5,0", "parallel"),
            ("0,0,0,1,0,0,0,0,0", "the up direction is zero"),
            ("-3e38,0,0,3e38,0,0", "too far apart or too close together"),
            ("0,0,0,1e-30,0,0", "too far apart or too close together"),
            ("0,0,0,1,0,0,0,1e-20,0", "is out of range (1e-10 to 1e10)"),
        ] {
            let e = s.parse::<LookAt>().unwrap_err();
            assert!(e.contains(needle), "{s}: {e}");
        }
    }

    #[test]
    fn yfov_needs_look_at_and_look_at_excludes_camera() {
        let parse = |args: &[&str]| Cli::try_parse_from([&["furnace", "render"], args].concat());
        let Command::Render(a) = parse(&["--look-at", "-1,0,0,0,0,0", "--yfov", "30"]).unwrap().command
        else {
            panic!("not render")
        };
        assert_eq!((a.look_at.map(|l| l.eye), a.yfov), (Some(Vec3::NEG_X), Some(30.0)));
        assert!(parse(&["--yfov", "30"]).is_err());
        assert!(parse(&["--look-at", "1,0,0,0,0,0", "--camera", "0"]).is_err());
        for bad in ["0", "180", "-5", "nan"] {
            assert!(parse(&["--look-at", "1,0,0,0,0,0", "--yfov", bad]).is_err(), "{bad}");
        }
    }
}
