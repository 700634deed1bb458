//! `furnace chart`'s arguments: the axes of the study (each a comma-separated list of a
//! setting's values) and its output.

use super::{EnvArgs, SceneArg, Switch, choice, parse_scene};
use clap::{Args, ValueEnum};
use furnace_brdf::{Masking, SpecularSampling};
use furnace_render::{EnvSampling, LightSampling, LightSelection, PointLightSampling, TriangleSampling};
use furnace_sampling::SamplerKind;
use std::path::PathBuf;

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
      --samplers sobol,pmj02,random,hammersley --sampling caps,vndf,ndf --spp 64 --out chart

Example (the light-sampling strategies on a Cornell box lit by an area light):
  furnace chart --reference cbox_area_ref_bounces4.exr --scene cbox_area.gltf --masking separable \\
      --compensation off --samplers sobol --sampling caps --light-sampling bsdf,nee,mis --spp 64 \\
      --out chart_lights")]
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
    #[arg(long, default_value = "cbox", value_parser = parse_scene)]
    pub scene: SceneArg,
    /// Smith masking of every configuration; match the reference's renderer (Mitsuba:
    /// separable) [default: the reference's, if furnace rendered it; else height-correlated].
    #[arg(long, value_parser = choice::<Masking>())]
    pub masking: Option<Masking>,
    /// Samplers, comma-separated: random, hammersley, cmj, pmj02, sobol.
    #[arg(long, value_delimiter = ',', default_value = "sobol,pmj02,random,hammersley,cmj")]
    pub samplers: Vec<SamplerKind>,
    /// BRDF (GGX) sampling methods, comma-separated: ndf, vndf, caps.
    #[arg(long, value_parser = choice::<SpecularSampling>(), value_delimiter = ',', default_value = "caps,vndf,ndf")]
    pub sampling: Vec<SpecularSampling>,
    /// Energy compensation, comma-separated: on, off [default: the reference's; with
    /// --reference-compensated, off and on].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub compensation: Vec<Switch>,
    /// How light of emitters and sun discs is found, comma-separated: bsdf, nee, mis (as
    /// `furnace render --light-sampling`).
    #[arg(long, value_parser = choice::<LightSampling>(), value_delimiter = ',', default_value = "mis")]
    pub light_sampling: Vec<LightSampling>,
    /// How a light sample picks its point on an emissive triangle, comma-separated:
    /// solid-angle, area (as `furnace render --triangle-sampling`).
    #[arg(long, value_parser = choice::<TriangleSampling>(), value_delimiter = ',', default_value = "solid-angle")]
    pub triangle_sampling: Vec<TriangleSampling>,
    /// How a light sample chooses the emissive triangle, comma-separated: bvh, power (as
    /// `furnace render --light-selection`).
    #[arg(long, value_parser = choice::<LightSelection>(), value_delimiter = ',', default_value = "bvh")]
    pub light_selection: Vec<LightSelection>,
    /// How the point and spot lights are gathered, comma-separated: auto, all, one (as
    /// `furnace render --point-lights`).
    #[arg(long, value_parser = choice::<PointLightSampling>(), value_delimiter = ',', default_value = "auto")]
    pub point_lights: Vec<PointLightSampling>,
    /// How light samples gather the environment map, comma-separated: off, importance,
    /// compensated (as `furnace render --env-sampling`; compensated is not combined with
    /// --light-sampling nee).
    #[arg(long, value_parser = choice::<EnvSampling>(), value_delimiter = ',', default_value = "compensated")]
    pub env_sampling: Vec<EnvSampling>,
    // The environment map of the study's scene and how it is placed (as `furnace render`; the
    // reference must have been rendered with the same).
    #[command(flatten)]
    pub environment: EnvArgs,
    /// Backends, comma-separated: cpu, gpu.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "cpu")]
    pub backends: Vec<ChartBackend>,
    /// The GPU adapter for --backends gpu: a part of its name or its index.
    /// Adaptive sampling (render --noise-threshold): off and/or thresholds, each its own
    /// configuration (checkpoints at the same spp; fewer samples taken, so less time).
    #[arg(long, value_delimiter = ',', default_value = "off", value_parser = parse_threshold_choice)]
    pub noise_threshold: Vec<Threshold>,
    /// Denoising with Open Image Denoise (render --denoise, guided by the AOVs): off and/or on,
    /// each its own configuration; a denoised checkpoint's time includes the denoising.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "off")]
    pub denoise: Vec<Switch>,
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
    /// Samples per pixel of the last checkpoint (checkpoints: 1, 2, 4, … and this).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: u32,
    /// Scattering events per path, at most 1024 [default: the reference's, if furnace rendered
    /// it; else 4].
    #[arg(long, allow_negative_numbers = true, value_parser = parse_bounces)]
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

/// `--bounces N` (of `chart`, whose `--bounces` has no default): as the settings' field checks it.
fn parse_bounces(s: &str) -> Result<u32, String> {
    let mut settings = furnace_render::RenderSettings::default();
    (field("bounces").set)(&mut settings, s).map(|()| settings.bounces)
}

/// The settings' field of flag `flag`.
fn field(flag: &str) -> &'static furnace_render::fields::Field {
    furnace_render::fields::field(flag).unwrap_or_else(|| unreachable!("the settings have a field {flag}"))
}

/// The largest `furnace chart --spp`.
const MAX_SPP: u32 = 1 << 20;

/// A `chart --noise-threshold` value: `off`, or a threshold (its `f32` bits: `Eq` for the axes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Threshold(pub Option<u32>);

impl Threshold {
    /// The threshold, `None` for off.
    pub fn value(self) -> Option<f32> {
        self.0.map(f32::from_bits)
    }

    /// `off` or the number.
    pub fn name(self) -> String {
        self.value().map_or_else(|| "off".to_string(), |t| t.to_string())
    }
}

/// `off` or a finite number above 0.
fn parse_threshold_choice(s: &str) -> Result<Threshold, String> {
    if s.trim().eq_ignore_ascii_case("off") {
        return Ok(Threshold(None));
    }
    parse_noise_threshold(s).map(|t| Threshold(Some(t.to_bits())))
}

/// `--noise-threshold T`: as the settings' field checks it.
fn parse_noise_threshold(s: &str) -> Result<f32, String> {
    let mut settings = furnace_render::RenderSettings::default();
    (field("noise-threshold").set)(&mut settings, s).map(|()| settings.adaptive.map_or(0.0, |a| a.threshold))
}
