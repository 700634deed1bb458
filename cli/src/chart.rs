//! `furnace chart`: speed against accuracy. Renders one scene progressively under several
//! configurations — sampler × BRDF sampling method × energy compensation × backend — and records
//! at checkpoints of 1, 2, 4, … samples per pixel (and `--spp`) the wall time and the error
//! against a reference image; writes the data as CSV and JSON and draws error-vs-spp and
//! error-vs-time charts (PNG and SVG).
//!
//! * **Error**: `furnace_post::metrics::score` (the metrics of `furnace compare`): RMSE over all channel values, and relative MSE
//!   `mean((x − r)² / (r² + ε))` over all pixels and channels with ε = 1e-2.
//! * **Time**: the wall time of the `render_pass` calls that produced the image, nothing else —
//!   not the scene load, BVH build, upload or pipeline creation, not reading the film back and
//!   not the metrics. A GPU pass includes waiting for the device and folding the pass into the
//!   film (`GpuRenderer::render_pass` returns when both are done).
//! * **Progressive samplers** (random, pmj02, sobol) render once up to `--spp`; the image is
//!   scored at each checkpoint and the time is the total up to it.
//! * **Fixed-N samplers** (hammersley, cmj) build one pattern of N samples per pixel and are only
//!   well distributed at the full N, so each checkpoint is its own render with N = the
//!   checkpoint, timed from its first pass. That is how they are used correctly; it costs about
//!   twice the samples of a progressive run.
//! * **Model and reference**: a configuration whose BRDF model (masking, compensation) differs
//!   from the one the reference was rendered with converges to a different image: its error
//!   flattens at that bias. Each row records whether its reference matches (`reference_matches`);
//!   a reference may be given for each compensation state (`--reference`,
//!   `--reference-compensated`).
//! * **Resume**: `--out DIR` holds `chart.json` (settings and rows; the source of truth) and
//!   `chart.csv`, rewritten atomically after every checkpoint. Re-running the same command skips
//!   the complete configurations and the checkpoints of fixed-N samplers already done; a
//!   progressive configuration stopped part-way is rendered again from sample 0 (its film is not
//!   saved). Different settings are refused. Ctrl-C finishes the current pass, saves the data
//!   and charts, and exits with code 130.

mod data;
mod plot;

use crate::args::{MaskingArg, SamplingArg, SceneArg, Switch};
use crate::interrupt::Interrupt;
use crate::render::Outcome;
use crate::resume;
use clap::{Args, ValueEnum};
use data::{ExternalPoint, Row};
use furnace_brdf::SpecularOptions;
use furnace_cli::backend::{self, Backend, BackendChoice};
use furnace_post::metrics::score;
use furnace_render::{Budget, Film, Integrator, RenderSettings, Session, Stop, Timing};
use furnace_sampling::SamplerKind;
use furnace_scene::{Scene, builtin};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The data file (settings and rows) in `--out`.
const JSON_NAME: &str = "chart.json";
/// The rows as CSV in `--out`.
const CSV_NAME: &str = "chart.csv";
/// Version of the `chart.json` layout.
const FORMAT: u64 = 1;
/// The largest `--spp`.
const MAX_SPP: u32 = 1 << 20;

/// `furnace chart`.
#[derive(Debug, Clone, Args)]
#[command(after_long_help = "\
Fixed-N samplers (hammersley, cmj) need the sample count in advance: each checkpoint is rendered \
as its own render with N = that checkpoint (how they are meant to be used), so they cost about \
twice the samples of a progressive sampler, and their time at a checkpoint is that render's.

Errors, against the reference, over all pixels and channels (as `furnace compare`): RMSE = sqrt(mean (x − r)²); relative MSE = mean (x − r)² / (r² + ε), \
ε = 1e-2. Slopes: least squares of ln(error) against ln(spp) over the checkpoints.

Time is the wall time of the render passes only: no scene load, BVH build, upload, pipeline \
creation, film read-back or error computation.

--external FILE.csv adds peer series (e.g. another renderer timed on the same machine) to the \
charts. Format: a header line `label,spp,seconds,rmse,relmse`, then one point per line; empty \
fields are allowed (a point without seconds is left out of the time charts, one without rmse out \
of the RMSE charts); lines starting with # are comments; no quoting. relmse must use ε = 1e-2 \
(as `furnace compare`).

Example (Mitsuba's reference of the built-in Cornell box, Mitsuba's BRDF model):
  furnace chart --reference cbox_ref_bounces4.exr --masking separable --compensation off \\
      --samplers sobol,pmj02,random,hammersley --sampling caps,vndf,ndf --spp 64 --out chart")]
pub struct ChartArgs {
    /// The reference image (.exr; its size is the study's image size): a long render of the
    /// same scene, e.g. Mitsuba's, or one of furnace's own (then its recorded settings are
    /// checked: scene, bounces, camera, model).
    #[arg(long, value_name = "REF.exr")]
    pub reference: PathBuf,
    /// A second reference, rendered with energy compensation on, for the configurations with
    /// --compensation on (--reference then serves those with it off).
    #[arg(long, value_name = "REF.exr")]
    pub reference_compensated: Option<PathBuf>,
    /// Whether --reference was rendered with energy compensation, when it is not a furnace
    /// render (which records it) [default: off, as Mitsuba and other renderers].
    #[arg(long, value_enum, value_name = "on|off")]
    pub reference_compensation: Option<Switch>,
    /// The scene: cbox (the built-in reference Cornell box), interior:N, or a .gltf/.glb path.
    #[arg(long, default_value = "cbox", value_parser = crate::args::parse_scene)]
    pub scene: SceneArg,
    /// Smith masking of every configuration; match the reference's renderer (Mitsuba:
    /// separable) [default: the reference's, if furnace rendered it; else height-correlated].
    #[arg(long, value_enum)]
    pub masking: Option<MaskingArg>,
    /// Samplers, comma-separated: random, hammersley, cmj, pmj02, sobol.
    #[arg(long, value_delimiter = ',', default_value = "sobol,pmj02,random,hammersley,cmj")]
    pub samplers: Vec<SamplerKind>,
    /// BRDF (GGX) sampling methods, comma-separated: ndf, vndf, caps.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "caps,vndf,ndf")]
    pub sampling: Vec<SamplingArg>,
    /// Energy compensation, comma-separated: on, off [default: the reference's; with
    /// --reference-compensated, off and on].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub compensation: Vec<Switch>,
    /// Backends, comma-separated: cpu, gpu.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "cpu")]
    pub backends: Vec<ChartBackend>,
    /// The GPU adapter for --backends gpu: a part of its name or its index.
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
    /// Samples per pixel of the last checkpoint (checkpoints: 1, 2, 4, … and this).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: u32,
    /// Scattering events per path [default: the reference's, if furnace rendered it; else 4].
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Seed of the samplers' scrambling (1, not render's 0: a reference rendered with furnace's
    /// defaults is then independent of the study).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// The study's directory: chart.csv, chart.json, and the charts (rmse_vs_spp, rmse_vs_time,
    /// relmse_vs_spp, relmse_vs_time; .png and .svg). An existing study there is resumed.
    #[arg(long, value_name = "DIR", default_value = "chart")]
    pub out: PathBuf,
    /// Peer series to draw on the same axes (CSV: label,spp,seconds,rmse,relmse); repeatable.
    #[arg(long, value_name = "FILE.csv")]
    pub external: Vec<PathBuf>,
    /// The time axis of the error-vs-time charts: wall (wall time of the render passes) or cpu
    /// (the process's CPU time over them, all threads: steadier than wall time on a machine
    /// shared with other work, meaningless for the GPU backend). Both are recorded; this only
    /// picks what the charts show (--external seconds are drawn on the same axis).
    #[arg(long, value_enum, default_value_t = ChartTime::Wall)]
    pub time: ChartTime,
    /// No progress bar and no summary table (warnings and errors are still printed).
    #[arg(long, short)]
    pub quiet: bool,
}

/// `furnace chart --backends`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ChartBackend {
    /// The CPU reference integrator.
    Cpu,
    /// The wgpu integrator (`--adapter` picks the adapter; else the best one, software too).
    Gpu,
}

/// `furnace chart --time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ChartTime {
    /// Wall time.
    Wall,
    /// Process CPU time (user + system, all threads).
    Cpu,
}

/// One configuration of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Config {
    sampler: SamplerKind,
    sampling: SamplingArg,
    compensation: Switch,
    backend: ChartBackend,
}

impl Config {
    /// `sobol/caps/comp-off/cpu`.
    fn name(&self) -> String {
        format!(
            "{}/{}/comp-{}/{}",
            self.sampler,
            resume::cli_name(&self.sampling),
            resume::cli_name(&self.compensation),
            resume::cli_name(&self.backend)
        )
    }

    fn row(&self, spp: u32, time: Timing, rmse: f64, relmse: f64, reference_matches: bool) -> Row {
        Row {
            config: self.name(),
            sampler: self.sampler.to_string(),
            sampling: resume::cli_name(&self.sampling),
            compensation: resume::cli_name(&self.compensation),
            backend: resume::cli_name(&self.backend),
            spp,
            seconds: time.wall,
            cpu_seconds: time.cpu,
            rmse,
            relmse,
            reference_matches,
        }
    }
}

/// A reference image and the model it was rendered with.
struct Reference {
    path: PathBuf,
    width: u32,
    height: u32,
    pixels: Vec<Vec3>,
    /// 16 hex digits of a hash of the pixels (the study records it).
    hash: String,
    compensation: Switch,
    /// The masking it records (a furnace render), `None` when unknown.
    masking: Option<MaskingArg>,
    metadata: furnace_post::Metadata,
    /// Whether furnace wrote it (it carries `furnace.scene_hash`).
    furnace: bool,
}

impl Reference {
    fn load(path: &Path, declared: Option<Switch>, default: Switch) -> Result<Self, String> {
        let (width, height, pixels, metadata) = furnace_post::read_exr(path).map_err(|e| e.to_string())?;
        let p = path.display();
        let recorded = |key: &str| metadata.extra.get(key).map(String::as_str);
        let furnace = recorded(resume::SCENE_HASH).is_some();
        let compensation = match recorded(resume::COMPENSATION) {
            Some(v) => {
                let c = Switch::from_str(v, false).map_err(|_| format!("{p}: unknown compensation '{v}'"))?;
                if let Some(d) = declared.filter(|&d| d != c) {
                    return Err(format!(
                        "{p} records --compensation {v}, but --reference-compensation says {}",
                        resume::cli_name(&d)
                    ));
                }
                c
            }
            None => declared.unwrap_or(default),
        };
        let masking = recorded(resume::MASKING)
            .map(|v| MaskingArg::from_str(v, false).map_err(|_| format!("{p}: unknown masking '{v}'")))
            .transpose()?;
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for v in pixels.iter().flat_map(|v| v.to_array()) {
            // FNV-1a over the f32 bits.
            for b in v.to_bits().to_le_bytes() {
                h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        Ok(Self {
            path: path.to_path_buf(),
            width,
            height,
            pixels,
            hash: format!("{h:016x}"),
            compensation,
            masking,
            metadata,
            furnace,
        })
    }

    fn settings(&self) -> Value {
        json!({
            "pixels_hash": self.hash,
            "compensation": resume::cli_name(&self.compensation),
            "masking": self.masking.map(|m| resume::cli_name(&m)),
        })
    }

    fn name(&self) -> String {
        self.path
            .file_name()
            .map_or_else(|| self.path.display().to_string(), |n| n.to_string_lossy().into_owned())
    }
}

/// 1, 2, 4, … below `spp`, then `spp`.
fn checkpoints(spp: u32) -> Vec<u32> {
    let mut v: Vec<u32> = (0..32).map(|k| 1u32 << k).take_while(|&n| n < spp).collect();
    v.push(spp);
    v
}

/// `v` without repeated values, in first-seen order.
fn dedup<T: PartialEq + Copy>(v: &[T]) -> Vec<T> {
    let mut out = Vec::new();
    for &x in v {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// Everything a study's numbers depend on: a resumed study must have the same.
struct Study {
    args: ChartArgs,
    scene: std::sync::Arc<Scene>,
    scene_name: String,
    settings: RenderSettings,
    masking: MaskingArg,
    checkpoints: Vec<u32>,
    configs: Vec<Config>,
    reference: Reference,
    compensated: Option<Reference>,
}

impl Study {
    /// The reference a configuration is scored against, and whether its model matches.
    fn reference_for(&self, c: &Config) -> (&Reference, bool) {
        let r = match &self.compensated {
            Some(rc) if rc.compensation == c.compensation => rc,
            _ => &self.reference,
        };
        let masking_ok = r.masking.is_none_or(|m| m == self.masking);
        (r, masking_ok && r.compensation == c.compensation)
    }

    fn settings_json(&self) -> Value {
        let names = |v: Vec<String>| Value::from(v);
        json!({
            "scene": self.scene_name,
            "scene_hash": self.scene.content_hash(),
            "width": self.settings.width,
            "height": self.settings.height,
            "bounces": self.settings.bounces,
            "seed": self.settings.seed,
            "masking": resume::cli_name(&self.masking),
            "russian_roulette": "off",
            "spp": self.args.spp,
            "checkpoints": self.checkpoints,
            "samplers": names(dedup(&self.args.samplers).iter().map(ToString::to_string).collect()),
            "sampling": names(dedup(&self.args.sampling).iter().map(resume::cli_name).collect()),
            "compensation": names(self.compensations().iter().map(resume::cli_name).collect()),
            "backends": names(dedup(&self.args.backends).iter().map(resume::cli_name).collect()),
            "adapter": self.args.adapter,
            "reference": self.reference.settings(),
            "reference_compensated": self.compensated.as_ref().map(Reference::settings),
        })
    }

    fn compensations(&self) -> Vec<Switch> {
        if self.args.compensation.is_empty() {
            // Default: the references' models (both, when a compensated one is given).
            let mut v = vec![self.reference.compensation];
            v.extend(self.compensated.as_ref().map(|r| r.compensation));
            dedup(&v)
        } else {
            dedup(&self.args.compensation)
        }
    }

    /// Samples per pixel a configuration renders in all: `spp`, or the sum of the checkpoints
    /// for a fixed-N sampler.
    fn config_spp(&self, c: &Config) -> u64 {
        if c.sampler.needs_sample_count() {
            self.checkpoints.iter().map(|&n| u64::from(n)).sum()
        } else {
            u64::from(self.args.spp)
        }
    }
}

fn load_scene(scene: &SceneArg) -> Result<(Scene, String), String> {
    Ok(match scene {
        SceneArg::Cbox => (builtin::cornell_box().map_err(|e| e.to_string())?, "cbox".to_string()),
        SceneArg::Interior(n) => (builtin::sunlit_interior(*n), format!("interior:{n}")),
        SceneArg::File(p) => (Scene::load(p).map_err(|e| e.to_string())?, p.display().to_string()),
    })
}

/// Resolves the study from the arguments and the references, checking what a furnace reference
/// records; prints warnings about biased or correlated comparisons.
fn prepare(a: &ChartArgs) -> Result<Study, String> {
    let (scene, scene_name) = load_scene(&a.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {}: {w}", scene.name);
    }
    let reference = Reference::load(&a.reference, a.reference_compensation, Switch::Off)?;
    let compensated =
        a.reference_compensated.as_deref().map(|p| Reference::load(p, None, Switch::On)).transpose()?;
    if let Some(rc) = &compensated {
        if rc.compensation != Switch::On {
            return Err(format!(
                "{} records --compensation off: --reference-compensated takes a render with compensation on",
                rc.path.display()
            ));
        }
        if reference.compensation == Switch::On {
            return Err(format!(
                "{} was rendered with compensation on too: --reference takes the render without it when \
                 --reference-compensated is given",
                reference.path.display()
            ));
        }
        if (rc.width, rc.height) != (reference.width, reference.height) {
            return Err(format!(
                "size mismatch: {} is {}×{} but {} is {}×{}",
                rc.path.display(),
                rc.width,
                rc.height,
                reference.path.display(),
                reference.width,
                reference.height
            ));
        }
    }
    let scene_hash = scene.content_hash();
    let mut recorded_bounces = None;
    for r in std::iter::once(&reference).chain(&compensated) {
        let p = r.path.display();
        if !r.furnace {
            continue;
        }
        let extra = |k: &str| r.metadata.extra.get(k).map(String::as_str);
        if extra(resume::SCENE_HASH) != Some(scene_hash.as_str()) {
            return Err(format!(
                "{p} was rendered from another scene (or another version of it) than {scene_name}"
            ));
        }
        if let Some(c) = extra(resume::CAMERA).filter(|&c| c != "0" && c != resume::FRAMED) {
            return Err(format!(
                "{p} was rendered with --camera {c}; furnace chart renders the scene's first camera"
            ));
        }
        if let Some(b) = r.metadata.bounces {
            match (a.bounces, recorded_bounces) {
                (Some(given), _) if given != b => {
                    return Err(format!("{p} was rendered with --bounces {b}, not {given}"));
                }
                (_, Some(other)) if other != b => {
                    return Err(format!("the two references differ in bounces ({other} and {b})"));
                }
                _ => recorded_bounces = Some(b),
            }
        }
        if let Some(n) = r.metadata.spp
            && u64::from(n) < 16 * u64::from(a.spp)
        {
            eprintln!(
                "warning: {p} has {n} spp, less than 16 × --spp {}: its own noise adds to the measured error \
                 at the last checkpoints",
                a.spp
            );
        }
    }
    let masking = match (a.masking, reference.masking) {
        (Some(m), _) => m,
        (None, Some(m)) => m,
        (None, None) => {
            eprintln!(
                "note: {} records no model (not a furnace render): assuming masking height-correlated and \
                 compensation {}; give --masking and --reference-compensation to match the renderer that made \
                 it (Mitsuba 3: --masking separable --reference-compensation off)",
                reference.path.display(),
                resume::cli_name(&reference.compensation)
            );
            MaskingArg::HeightCorrelated
        }
    };
    for r in std::iter::once(&reference).chain(&compensated) {
        if let Some(m) = r.masking.filter(|&m| m != masking) {
            eprintln!(
                "warning: {} was rendered with --masking {}, the study uses {}: every configuration is biased \
                 against it (reference_matches = false)",
                r.path.display(),
                resume::cli_name(&m),
                resume::cli_name(&masking)
            );
        }
    }
    if !reference.furnace && a.bounces.is_none() {
        eprintln!(
            "note: {} records no bounces: using 4 (give --bounces to change)",
            reference.path.display()
        );
    }
    let bounces = a.bounces.or(recorded_bounces).unwrap_or(4);
    let settings = RenderSettings {
        width: reference.width,
        height: reference.height,
        bounces,
        seed: a.seed,
        russian_roulette: false,
        ..RenderSettings::default()
    };
    let mut study = Study {
        args: a.clone(),
        scene: std::sync::Arc::new(scene),
        scene_name,
        settings,
        masking,
        checkpoints: checkpoints(a.spp),
        configs: Vec::new(),
        reference,
        compensated,
    };
    for backend in dedup(&a.backends) {
        for compensation in study.compensations() {
            for sampling in dedup(&a.sampling) {
                for sampler in dedup(&a.samplers) {
                    study.configs.push(Config { sampler, sampling, compensation, backend });
                }
            }
        }
    }
    if study.configs.is_empty() {
        return Err("no configurations: give at least one sampler, sampling method and backend".into());
    }
    for comp in study.compensations() {
        let probe = Config { compensation: comp, ..study.configs[0] };
        let (r, matches) = study.reference_for(&probe);
        if !matches && r.compensation != comp {
            eprintln!(
                "warning: the configurations with compensation {} are scored against {}, rendered with \
                 compensation {}: their error flattens at that model difference (reference_matches = false; \
                 give --reference-compensated for a matching reference)",
                resume::cli_name(&comp),
                r.path.display(),
                resume::cli_name(&r.compensation)
            );
        }
    }
    for r in std::iter::once(&study.reference).chain(&study.compensated) {
        let (Some(sampler), Some(seed)) = (&r.metadata.sampler, r.metadata.seed) else { continue };
        if r.furnace && seed == u64::from(a.seed) && study.configs.iter().any(|c| c.sampler.name() == sampler)
        {
            eprintln!(
                "warning: {} was rendered with the {sampler} sampler and seed {seed}, as this study's {sampler} \
                 configurations: their first samples are the reference's own, so their error is underestimated \
                 (give another --seed)",
                r.path.display()
            );
        }
    }
    Ok(study)
}

/// The saved study in `dir`, if any: its rows, after checking that its settings are `now`'s.
fn load_saved(dir: &Path, now: &Value) -> Result<Vec<Row>, String> {
    let path = dir.join(JSON_NAME);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let p = path.display();
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("{p}: not a furnace chart file ({e})"))?;
    if v.get("format").and_then(Value::as_u64) != Some(FORMAT) {
        return Err(format!("{p}: not a furnace chart file of format {FORMAT}"));
    }
    let recorded = v.get("settings").cloned().unwrap_or(Value::Null);
    if let Some((key, was, is)) = data::first_difference(&recorded, now) {
        return Err(format!(
            "{} holds a study with other settings ({key}: {was} there, {is} now); re-run with the same \
             settings to resume it, or give another --out",
            dir.display()
        ));
    }
    let rows = v.get("rows").and_then(Value::as_array).ok_or_else(|| format!("{p}: no 'rows'"))?;
    rows.iter().map(|r| data::row_from_json(r).map_err(|e| format!("{p}: {e}"))).collect()
}

/// Writes `bytes` to `path` atomically (`furnace_post::write_bytes_atomic`).
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    furnace_post::write_bytes_atomic(path, bytes).map_err(|e| e.to_string())
}

/// Rows of `config`, ordered by spp.
fn rows_of<'r>(rows: &'r [Row], config: &str) -> Vec<&'r Row> {
    let mut v: Vec<&Row> = rows.iter().filter(|r| r.config == config).collect();
    v.sort_by_key(|r| r.spp);
    v
}

fn slope(rows: &[&Row], metric: fn(&Row) -> f64) -> Option<f64> {
    data::log_log_slope(rows.iter().map(|r| (f64::from(r.spp), metric(r))))
}

/// Writes chart.json and chart.csv (rows in configuration order, then by spp).
fn save_data(study: &Study, rows: &mut [Row], machine: &Value) -> Result<(), String> {
    let order = |r: &Row| study.configs.iter().position(|c| c.name() == r.config).unwrap_or(usize::MAX);
    rows.sort_by_key(|r| (order(r), r.spp));
    let configs: Vec<Value> = study
        .configs
        .iter()
        .map(|c| {
            let name = c.name();
            let mine = rows_of(rows, &name);
            let (r, matches) = study.reference_for(c);
            json!({
                "config": name,
                "sampler": c.sampler.to_string(),
                "sampling": resume::cli_name(&c.sampling),
                "compensation": resume::cli_name(&c.compensation),
                "backend": resume::cli_name(&c.backend),
                "reference": r.path.display().to_string(),
                "reference_matches": matches,
                "complete": mine.len() == study.checkpoints.len(),
                "slope_rmse_vs_spp": slope(&mine, |r| r.rmse),
                "slope_relmse_vs_spp": slope(&mine, |r| r.relmse),
            })
        })
        .collect();
    let doc = json!({
        "format": FORMAT,
        "settings": study.settings_json(),
        "reference_path": study.reference.path.display().to_string(),
        "reference_compensated_path": study.compensated.as_ref().map(|r| r.path.display().to_string()),
        "machine": machine,
        "metrics": "rmse: sqrt(mean over pixels and channels of (x - r)^2); relmse: mean over pixels and channels \
                    of (x - r)^2 / (r^2 + 0.01) (furnace compare)",
        "timing": "seconds: wall time of the render passes that produced the image (progressive samplers: all \
                   passes up to the checkpoint; fixed-N samplers: the passes of that checkpoint's own N-sample \
                   render); excludes scene load, BVH build, upload, pipeline creation, film read-back and metrics. \
                   cpu_seconds: the process's CPU time (user + system, all threads; 10 ms ticks of \
                   /proc/self/stat) over the same passes",
        "slopes": "least squares of ln(error) against ln(spp) over the configuration's checkpoints",
        "configs": configs,
        "rows": rows.iter().map(data::row_json).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())? + "\n";
    let dir = &study.args.out;
    write_atomically(&dir.join(JSON_NAME), text.as_bytes())?;
    write_atomically(&dir.join(CSV_NAME), data::to_csv(rows).as_bytes())
}

/// Colour per sampler (matplotlib's tab10, grey for random).
fn sampler_color(s: SamplerKind) -> plotters::style::RGBColor {
    use plotters::style::RGBColor;
    match s {
        SamplerKind::Sobol => RGBColor(31, 119, 180),
        SamplerKind::Pmj02 => RGBColor(255, 127, 14),
        SamplerKind::Random => RGBColor(90, 90, 90),
        SamplerKind::Hammersley => RGBColor(44, 160, 44),
        SamplerKind::Cmj => RGBColor(214, 39, 40),
    }
}

/// Draws the four charts into the study's directory.
fn save_charts(study: &Study, rows: &[Row], external: &[ExternalPoint]) -> Result<(), String> {
    use plot::{Labels, Marker, Series, Style};
    let vary = |n: usize| n > 1;
    let (ns, nm, nc, nb) = (
        dedup(&study.args.samplers).len(),
        dedup(&study.args.sampling).len(),
        study.compensations().len(),
        dedup(&study.args.backends).len(),
    );
    let label = |c: &Config| {
        let mut parts = vec![c.sampler.to_string()];
        if vary(nm) {
            parts.push(resume::cli_name(&c.sampling));
        }
        if vary(nc) {
            parts.push(format!("comp {}", resume::cli_name(&c.compensation)));
        }
        if vary(nb) || c.backend == ChartBackend::Gpu {
            parts.push(resume::cli_name(&c.backend));
        }
        if vary(ns) || parts.len() > 1 { parts.join(" ") } else { c.name() }
    };
    let mut ext_labels: Vec<&str> = Vec::new();
    for p in external {
        if !ext_labels.contains(&p.label.as_str()) {
            ext_labels.push(&p.label);
        }
    }
    let ext_colors = [(148, 103, 189), (140, 86, 75), (227, 119, 194), (188, 189, 34), (23, 190, 207)];
    let s = &study.settings;
    let what = format!("{} {}×{}, {} bounces", study.scene_name, s.width, s.height, s.bounces);
    let biased_any = study.configs.iter().any(|c| !study.reference_for(c).1);
    let time_of = |r: &Row| match study.args.time {
        ChartTime::Wall => r.seconds,
        ChartTime::Cpu => r.cpu_seconds,
    };
    for (metric, metric_name, get, ext_get, ideal) in [
        (
            "rmse",
            "RMSE",
            (|r: &Row| r.rmse) as fn(&Row) -> f64,
            (|p: &ExternalPoint| p.rmse) as fn(&ExternalPoint) -> Option<f64>,
            "−0.5",
        ),
        ("relmse", "relative MSE", |r: &Row| r.relmse, |p: &ExternalPoint| p.relmse, "−1"),
    ] {
        for by_time in [false, true] {
            let mut series = Vec::new();
            for c in &study.configs {
                let mine = rows_of(rows, &c.name());
                if mine.is_empty() {
                    continue;
                }
                let matches = study.reference_for(c).1;
                let mut text = label(c);
                if !by_time && let Some(k) = slope(&mine, get) {
                    text.push_str(&format!("  slope {}", fmt_slope(k)));
                }
                if !matches {
                    text.push_str("  (≠ ref model)");
                }
                let points = mine
                    .iter()
                    .map(|r| (if by_time { time_of(r) } else { f64::from(r.spp) }, get(r)))
                    .collect();
                let style = Style {
                    color: sampler_color(c.sampler),
                    marker: match c.sampling {
                        SamplingArg::Caps => Marker::Circle,
                        SamplingArg::Vndf => Marker::Triangle,
                        SamplingArg::Ndf => Marker::Square,
                    },
                    dashed: c.compensation == Switch::On,
                    hollow: c.backend == ChartBackend::Gpu,
                };
                series.push(Series { label: text, points, style });
            }
            for (k, name) in ext_labels.iter().enumerate() {
                let pts: Vec<&ExternalPoint> = external.iter().filter(|p| p.label == *name).collect();
                let points: Vec<(f64, f64)> = pts
                    .iter()
                    .filter_map(|p| Some((if by_time { p.seconds? } else { p.spp? }, ext_get(p)?)))
                    .collect();
                let mut text = format!("{name} (external)");
                if !by_time && let Some(k) = data::log_log_slope(points.iter().copied()) {
                    text.push_str(&format!("  slope {}", fmt_slope(k)));
                }
                let (r, g, b) = ext_colors[k % ext_colors.len()];
                let style = Style {
                    color: plotters::style::RGBColor(r, g, b),
                    marker: Marker::Cross,
                    dashed: false,
                    hollow: false,
                };
                series.push(Series { label: text, points, style });
            }
            let mut note = if by_time {
                format!(
                    "Time: {} of the render passes only (no setup, BVH build, read-back or metrics). Fixed-N \
                     samplers: one render per checkpoint.",
                    match study.args.time {
                        ChartTime::Wall => "wall time",
                        ChartTime::Cpu => "process CPU time (user + system, all threads)",
                    }
                )
            } else {
                format!(
                    "Slope: least squares of log error vs log spp over the checkpoints ({ideal} for independent \
                     samples)."
                )
            };
            note.push_str(&format!(" Reference: {}.", study.reference.name()));
            if let Some(rc) = &study.compensated {
                note.push_str(&format!(" Compensation on: {}.", rc.name()));
            }
            if nm > 1 {
                note.push_str(" Markers: caps ●, vndf ▲, ndf ■.");
            }
            if study.configs.iter().any(|c| c.compensation == Switch::On) {
                note.push_str(" Dashed: compensation on.");
            }
            if study.configs.iter().any(|c| c.backend == ChartBackend::Gpu) {
                note.push_str(" Hollow markers: GPU.");
            }
            if biased_any {
                note.push_str(" ≠ ref model: rendered with another BRDF model than the reference (biased).");
            }
            if metric == "relmse" {
                note.push_str(" relMSE = mean (x−r)²/(r²+0.01).");
            }
            let (x, file_x) = match (by_time, study.args.time) {
                (false, _) => ("samples per pixel", "spp"),
                (true, ChartTime::Wall) => ("seconds (wall time of the render passes)", "time"),
                (true, ChartTime::Cpu) => ("CPU seconds of the render passes (all threads)", "time"),
            };
            let labels = Labels {
                title: format!(
                    "{what}: {metric_name} vs {}",
                    if by_time { "time" } else { "samples per pixel" }
                ),
                x: x.to_string(),
                y: format!("{metric_name} against the reference"),
                note,
                x_powers_of_two: !by_time,
            };
            plot::write_chart(&study.args.out.join(format!("{metric}_vs_{file_x}")), &labels, &series)?;
        }
    }
    Ok(())
}

fn fmt_slope(k: f64) -> String {
    format!("{k:.2}").replace('-', "−")
}

/// How long the first configuration of each backend in a process warms up (see `make_backend`).
const WARM_UP_SECONDS: f64 = 1.0;

/// The integrator of `config`, fresh (an empty film), and for a GPU its adapter in one line;
/// `n` is N for a fixed-N sampler.
fn make_backend(study: &Study, c: &Config, n: Option<u32>) -> Result<(Backend, Option<String>), String> {
    let settings = RenderSettings {
        sampler: c.sampler,
        sample_count: n,
        specular: SpecularOptions {
            masking: study.masking.into(),
            sampling: c.sampling.into(),
            compensation: c.compensation == Switch::On,
        },
        ..study.settings
    };
    let choice = match c.backend {
        ChartBackend::Cpu => BackendChoice::Cpu,
        ChartBackend::Gpu => BackendChoice::Gpu,
    };
    let camera = study.scene.default_camera();
    let adapter = if choice == BackendChoice::Gpu { study.args.adapter.as_deref() } else { None };
    let mut backend =
        backend::open(choice, adapter, study.scene.clone(), &camera, settings).map_err(|e| e.to_string())?;
    // Untimed warm-up passes, then discarded: the first passes of a process pay costs that are
    // not the method's — the driver compiling the pipeline on first dispatch, rayon starting
    // its threads, and above all an idle GPU's clocks ramping up (on the H100 the first
    // configuration's checkpoints took 3–5× the same work later, and a 1-spp warm-up did not
    // help): every configuration renders one pass, the first of each backend in the process
    // passes for WARM_UP_SECONDS.
    static WARM: [std::sync::atomic::AtomicBool; 2] =
        [std::sync::atomic::AtomicBool::new(false), std::sync::atomic::AtomicBool::new(false)];
    let first = !WARM[c.backend as usize].swap(true, std::sync::atomic::Ordering::Relaxed);
    let start = Instant::now();
    backend.render_pass(0, 1).map_err(|e| e.to_string())?;
    while first && start.elapsed().as_secs_f64() < WARM_UP_SECONDS {
        backend.render_pass(0, 1).map_err(|e| e.to_string())?;
    }
    backend.set_film(&Film::new(settings.width, settings.height)).map_err(|e| e.to_string())?;
    let adapter = match &mut backend {
        Backend::Gpu(g) => Some(g.context().describe()),
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
struct Progress {
    bar: ProgressBar,
    pixels: u64,
}

impl Progress {
    fn new(quiet: bool, total_spp: u64, done_spp: u64, pixels: u64) -> Self {
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

/// Renders `config` from sample 0 up to each of `targets` (ascending), timing the passes;
/// `at(spp, time, film)` is called at each. Returns `false` if Ctrl-C stopped it.
fn render_to(
    backend: &mut dyn Integrator,
    targets: &[u32],
    interrupt: &Interrupt,
    progress: &Progress,
    name: &str,
    mut at: impl FnMut(u32, Timing, &Film) -> Result<(), String>,
) -> Result<bool, String> {
    let last = targets.last().copied().unwrap_or(0);
    let mut session = Session::new(backend, 0);
    session.measure_cpu_time(true);
    for &target in targets {
        let stop = session
            .run(&Budget::spp(target), &|| interrupt.requested(), &mut |p| {
                progress.advance(p.pass, format!("{name} {}/{last}", p.done));
            })
            .map_err(|e| e.to_string())?;
        if stop == Stop::Cancelled {
            return Ok(false);
        }
        let film = session.film().map_err(|e| e.to_string())?;
        at(target, session.timing(), &film)?;
    }
    Ok(true)
}

pub fn run(a: &ChartArgs, interrupt: &Interrupt) -> Result<Outcome, String> {
    let study = prepare(a)?;
    let external = a
        .external
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            data::parse_external(p, &text)
        })
        .collect::<Result<Vec<_>, String>>()?
        .concat();
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut rows = load_saved(&a.out, &study.settings_json())?;
    let resumed = !rows.is_empty();

    // What is left: complete configurations are skipped; a progressive one stopped part-way
    // starts again (its rows are replaced); a fixed-N one keeps its finished checkpoints.
    let mut todo: Vec<(Config, Vec<u32>)> = Vec::new();
    let (mut total, mut done_spp) = (0u64, 0u64);
    for c in &study.configs {
        let name = c.name();
        let have: Vec<u32> = rows_of(&rows, &name).iter().map(|r| r.spp).collect();
        total += study.config_spp(c);
        let left: Vec<u32> = if c.sampler.needs_sample_count() {
            study.checkpoints.iter().copied().filter(|n| !have.contains(n)).collect()
        } else if study.checkpoints.iter().all(|n| have.contains(n)) {
            Vec::new()
        } else {
            rows.retain(|r| r.config != name);
            study.checkpoints.clone()
        };
        let left_spp: u64 = if c.sampler.needs_sample_count() {
            left.iter().map(|&n| u64::from(n)).sum()
        } else if left.is_empty() {
            0
        } else {
            u64::from(a.spp)
        };
        done_spp += study.config_spp(c) - left_spp;
        if !left.is_empty() {
            todo.push((*c, left));
        }
    }
    let s = &study.settings;
    let pixels = u64::from(s.width) * u64::from(s.height);
    if !a.quiet {
        let skipped = study.configs.len() - todo.len();
        eprintln!(
            "chart: {} {}×{}, {} bounces, masking {}, seed {}, up to {} spp: {} configurations{}",
            study.scene_name,
            s.width,
            s.height,
            s.bounces,
            resume::cli_name(&study.masking),
            s.seed,
            a.spp,
            study.configs.len(),
            if resumed {
                format!(" ({skipped} already complete in {})", a.out.display())
            } else {
                String::new()
            }
        );
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut machine = json!({ "cpu_threads": threads, "furnace_version": env!("CARGO_PKG_VERSION") });
    let progress = Progress::new(a.quiet, total, done_spp, pixels);
    let mut interrupted = false;
    'configs: for (c, left) in &todo {
        let name = c.name();
        let (reference, matches) = study.reference_for(c);
        let on_checkpoint = |spp: u32, time: Timing, film: &Film, rows: &mut Vec<Row>, machine: &Value| {
            let (rmse, relmse) = measure(film, &reference.pixels)?;
            rows.retain(|r| !(r.config == name && r.spp == spp));
            rows.push(c.row(spp, time, rmse, relmse, matches));
            if film.rejected() > 0 {
                progress.bar.suspend(|| {
                    eprintln!("warning: {name}: {} non-finite samples rejected", film.rejected())
                });
            }
            save_data(&study, rows, machine)
        };

        if c.sampler.needs_sample_count() {
            for &n in left {
                let (mut backend, adapter) = make_backend(&study, c, Some(n))?;
                note_adapter(&mut machine, adapter);
                let complete = render_to(&mut backend, &[n], interrupt, &progress, &name, |spp, t, film| {
                    on_checkpoint(spp, t, film, &mut rows, &machine)
                })?;
                if !complete {
                    interrupted = true;
                    break 'configs;
                }
            }
        } else {
            let (mut backend, adapter) = make_backend(&study, c, None)?;
            note_adapter(&mut machine, adapter);
            let complete = render_to(&mut backend, left, interrupt, &progress, &name, |spp, t, film| {
                on_checkpoint(spp, t, film, &mut rows, &machine)
            })?;
            if !complete {
                interrupted = true;
                break 'configs;
            }
        }
        if progress.bar.is_hidden() && !a.quiet {
            eprintln!("done: {name}");
        }
    }
    progress.bar.finish_and_clear();
    save_data(&study, &mut rows, &machine)?;
    save_charts(&study, &rows, &external)?;
    if !a.quiet {
        print!("{}", summary(&study, &rows));
        eprintln!(
            "wrote {} (chart.csv, chart.json, {{rmse,relmse}}_vs_{{spp,time}}.{{png,svg}})",
            a.out.display()
        );
    }
    if interrupted {
        eprintln!("interrupted: the checkpoints done are saved; re-run the same command to resume");
        return Ok(Outcome::Interrupted);
    }
    Ok(Outcome::Done)
}

/// Records the GPU adapter's name in the machine description (the first one seen).
fn note_adapter(machine: &mut Value, adapter: Option<String>) {
    if let Some(name) = adapter
        && machine.get("gpu_adapter").is_none()
    {
        machine["gpu_adapter"] = json!(name);
    }
}

/// A Markdown table of each configuration's last checkpoint and slopes.
fn summary(study: &Study, rows: &[Row]) -> String {
    let mut s = String::from(
        "| config | spp | seconds | CPU s | RMSE | relMSE | slope RMSE | slope relMSE | ref model |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for c in &study.configs {
        let mine = rows_of(rows, &c.name());
        let Some(last) = mine.last() else { continue };
        let k = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |k| format!("{k:.3}"));
        s.push_str(&format!(
            "| {} | {} | {:.3} | {:.2} | {:.4e} | {:.4e} | {} | {} | {} |\n",
            last.config,
            last.spp,
            last.seconds,
            last.cpu_seconds,
            last.rmse,
            last.relmse,
            k(slope(&mine, |r| r.rmse)),
            k(slope(&mine, |r| r.relmse)),
            if last.reference_matches { "same" } else { "differs" }
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_are_powers_of_two_then_spp() {
        assert_eq!(checkpoints(1), vec![1]);
        assert_eq!(checkpoints(8), vec![1, 2, 4, 8]);
        assert_eq!(checkpoints(12), vec![1, 2, 4, 8, 12]);
    }

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

    #[test]
    fn dedup_keeps_first_order() {
        assert_eq!(dedup(&[3, 1, 3, 2, 1]), vec![3, 1, 2]);
    }
}
