//! [`GpuRenderer`]: furnace-cpu's path tracer on the GPU.
//!
//! The shader is the concatenation of the twins — [`wgsl::SAMPLING`], [`wgsl::BRDF`],
//! [`wgsl::SCENE`], [`wgsl::TRAVERSE`], the film module — and `integrator.wgsl`, a line-for-line
//! twin of `CpuRenderer::trace` (same sampler dimensions, same branches), so the GPU estimates the
//! same integral with the same sample points; images agree with the CPU's within noise
//! (`tests/integrator.rs`).
//!
//! A pass of `n` samples per pixel is cut into dispatches of a few rows × a few samples, each
//! bounded to about [`GpuRenderer::samples_per_dispatch`] samples, so that no dispatch runs long
//! enough to trip a driver watchdog. A workgroup ([`group_size_for`]: 1024 invocations on hardware
//! adapters that accept it, else [`GROUP_SIZE`]) covers a tile of
//! pixels with [`GpuRenderer::group_samples`] invocations per pixel: with 1, an invocation owns
//! its pixel and adds its samples in index order; with more, each computes one sample and the
//! pixel's first invocation adds them, after a barrier, in index order — the same additions in
//! the same order, so the film does not depend on the grouping (nor on the workgroup size), bit
//! for bit. Grouping keeps a large GPU busy on small images and lets short invocations replace
//! each other (measured in BENCHMARKS.md, "GPU integrator"); one invocation per pixel runs a
//! pixel's samples one after another, which wins where path lengths differ a lot. The renderer
//! times both on its first passes and keeps the faster ([`GroupTuner`]).
//!
//! Bindings (group 0): 0 the [`FrameParams`] uniform (dynamic offset, one slot per dispatch),
//! 1–2 the film, 3–4 the BVH, 5–10 the scene, 11 the Turquin table, 12 the ray counter — twelve
//! storage buffers, within every Vulkan/Metal/DX12 adapter's per-stage limit (the WebGPU default
//! of 8 is not: the device is opened with the adapter's own limits).
//!
//! Counting (for `furnace bench`): with [`GpuRenderer::set_count_rays`] on, every invocation
//! adds the rays it traced (closest-hit and shadow), the BVH nodes and triangles it tested, its
//! fallback sweeps and its deepest stack to 64-bit counters with a few atomics
//! ([`GpuRenderer::take_trace_counts`]); off — the default — no atomic runs (the counters cost a
//! few per cent of throughput). [`GpuRenderer::set_timing`] records GPU
//! timestamps around each pass where the adapter has `TIMESTAMP_QUERY`.

use crate::film::{FilmPrecision, GpuFilm};
use crate::sampling::SamplerParams;
use crate::scene::{GpuScene, SceneBuffers};
use crate::shared::{Binding, BindingKind, BindingTable, GpuStruct, WgslType, wgsl_struct};
use crate::traverse::BvhBuffers;
use crate::{GpuContext, GpuError, brdf, scene, traverse, wgsl};
use bytemuck::Zeroable;
use furnace_accel::{BuildOptions, Bvh, offset_scale_of_bounds};
use furnace_render::ADAPTIVE_STEP;
use furnace_render::{
    CancelFlag, Film, Integrator, LightSampling, LightSelection, RenderError, RenderSettings,
    TriangleSampling,
};
use furnace_sampling::AnySampler;
use furnace_scene::{AlphaMode, Camera, Emitters, LightBvh, PointLightDistribution, Projection, Scene};

crate::wgsl_consts! {
    /// The `FRAME_*` flags as WGSL `const` declarations (composed into the integrator shader).
    fn frame_flags_wgsl;
    /// `FrameParams.flags`: Russian roulette on.
    pub const FRAME_RUSSIAN_ROULETTE: u32 = 1;
    /// `FrameParams.flags`: orthographic camera.
    pub const FRAME_ORTHOGRAPHIC: u32 = 2;
    /// `FrameParams.flags`: some material is alpha-masked (rays call the alpha test).
    pub const FRAME_ANY_MASKED: u32 = 4;
    /// `FrameParams.flags`: the scene has a sun.
    pub const FRAME_HAS_SUN: u32 = 8;
    /// `FrameParams.flags`: no light samples of emitters and sun discs (`LightSampling::Bsdf`).
    pub const FRAME_NO_LIGHT_SAMPLES: u32 = 32;
    /// `FrameParams.flags`: BSDF-sampled rays that reach an emitter or a sun disc add nothing
    /// (`LightSampling::Nee`).
    pub const FRAME_NO_BSDF_LIGHT: u32 = 64;
}

crate::gpu_struct! {
    /// The uniform block of one dispatch (192 bytes); its WGSL declaration is generated from this
    /// one ([`crate::shared::wgsl_struct`]).
    pub struct FrameParams {
        /// Camera-to-world rotation/scale columns (xyz) and translation.
        pub cam_x: [f32; 4] => WgslType::VEC4_F32,
        /// See `cam_x`.
        pub cam_y: [f32; 4] => WgslType::VEC4_F32,
        /// See `cam_x`.
        pub cam_z: [f32; 4] => WgslType::VEC4_F32,
        /// See `cam_x`.
        pub cam_t: [f32; 4] => WgslType::VEC4_F32,
        /// Direction sunlight travels (xyz); `1 − cos θ` of its disc (w; 0: a delta sun).
        pub sun_direction: [f32; 4] => WgslType::VEC4_F32,
        /// Sun irradiance (rgb); the disc's radiance per unit irradiance, `1/(π sin²θ)` (w).
        pub sun_irradiance: [f32; 4] => WgslType::VEC4_F32,
        /// Sky radiance (rgb).
        pub sky: [f32; 4] => WgslType::VEC4_F32,
        /// The sampler.
        pub sampler: SamplerParams => SamplerParams::wgsl_type(),
        /// Image width.
        pub width: u32 => WgslType::U32,
        /// Image height.
        pub height: u32 => WgslType::U32,
        /// First sample index of this dispatch.
        pub first_sample: u32 => WgslType::U32,
        /// Samples per pixel in this dispatch.
        pub samples: u32 => WgslType::U32,
        /// Scattering events per path.
        pub bounces: u32 => WgslType::U32,
        /// `FRAME_*` bits.
        pub flags: u32 => WgslType::U32,
        /// [`brdf::options_flags`] of the settings' specular options.
        pub bsdf_flags: u32 => WgslType::U32,
        /// First image row of this dispatch.
        pub row_offset: u32 => WgslType::U32,
        /// `tan(yfov/2)` (perspective) or `ymag` (orthographic), computed as furnace-scene's
        /// `Camera::generate_ray` does.
        pub fov_scale: f32 => WgslType::F32,
        /// `width / height` as the CPU computes it.
        pub aspect: f32 => WgslType::F32,
        /// Invocations per pixel in a workgroup of [`GROUP_SIZE`] (a power of two): 1 — an
        /// invocation owns a pixel and loops over `samples`; more — each computes one sample and
        /// the workgroup adds them in index order (small images: more of the GPU busy).
        pub group_samples: u32 => WgslType::U32,
        /// Width in pixels of a workgroup's tile of `GROUP_SIZE / group_samples` pixels.
        pub tile_width: u32 => WgslType::U32,
        /// The ray offsets' length scale ([`furnace_accel::offset_scale_of_bounds`] of the scene).
        pub offset_scale: f32 => WgslType::F32,
        /// Records in `point_lights` (0: the loop over them is skipped).
        pub point_light_count: u32 => WgslType::U32,
        /// Emissive triangles in `emitters` (0: none).
        pub emitter_count: u32 => WgslType::U32,
        /// [`Emitters::total_weight`], the selection pdfs' denominator.
        pub emitter_total: f32 => WgslType::F32,
        /// The environment map's columns (0: none).
        pub env_width: u32 => WgslType::U32,
        /// Its rows.
        pub env_height: u32 => WgslType::U32,
        /// Its intensity.
        pub env_intensity: f32 => WgslType::F32,
        /// Cosine of its rotation about +Y ([`furnace_scene::Environment::rotation_cos_sin`]).
        pub env_cos: f32 => WgslType::F32,
        /// Sine of its rotation.
        pub env_sin: f32 => WgslType::F32,
        /// [`ENV_VISIBLE`].
        pub env_flags: u32 => WgslType::U32,
        /// The sample clamp (`RenderSettings::clamp`; 0: off).
        pub sample_clamp: f32 => WgslType::F32,
        /// Adaptive sampling's noise threshold (`RenderSettings::adaptive`; 0: off).
        pub noise_threshold: f32 => WgslType::F32,
    }
}

const _: () = assert!(size_of::<FrameParams>() == 224);

crate::wgsl_consts! {
    /// The `ENV_*` flags as WGSL `const` declarations.
    fn env_flags_wgsl;
    /// `FrameParams.env_flags`: camera rays that leave the scene see the environment.
    pub const ENV_VISIBLE: u32 = 1;
}

crate::gpu_struct! {
    /// A point or spot light as the WGSL reads it (`furnace_scene::PointLight`), 64 bytes.
    pub struct GpuPointLight as "PointLight" {
        /// World-space position.
        pub position: [f32; 3] => WgslType::VEC3_F32,
        /// `range` (0: none).
        pub range: f32 => WgslType::F32,
        /// Radiant intensity, W/sr.
        pub intensity: [f32; 3] => WgslType::VEC3_F32,
        /// [`POINT_LIGHT_SPOT`], [`POINT_LIGHT_RANGE`].
        pub flags: u32 => WgslType::U32,
        /// The direction a spot light points.
        pub spot_direction: [f32; 3] => WgslType::VEC3_F32,
        /// `cos(innerConeAngle)`.
        pub cos_inner: f32 => WgslType::F32,
        /// `cos(outerConeAngle)`.
        pub cos_outer: f32 => WgslType::F32,
        /// [`PointLightDistribution::cdf`] of this light (`--point-lights one`; 0 where no
        /// light has power).
        pub choice_cdf: f32 => WgslType::F32,
        /// [`PointLightDistribution::pmf`] of this light.
        pub choice_pmf: f32 => WgslType::F32,
        /// Rust-only padding to 64 bytes.
        pub pad: u32 => WgslType::PAD,
    }
}

const _: () = assert!(size_of::<GpuPointLight>() == 64);

crate::wgsl_consts! {
    /// The `POINT_LIGHT_*` flags as WGSL `const` declarations.
    fn point_light_flags_wgsl;
    /// `GpuPointLight.flags`: a spot light (the cone applies).
    pub const POINT_LIGHT_SPOT: u32 = 1;
    /// `GpuPointLight.flags`: a `range` window applies.
    pub const POINT_LIGHT_RANGE: u32 = 2;
}

impl GpuPointLight {
    /// The record of `light` (its choice by power left 0: [`point_light_records`] fills it).
    pub fn new(light: &furnace_scene::PointLight) -> Self {
        let (spot_direction, cos_inner, cos_outer) =
            light.spot.map_or(([0.0; 3], 1.0, 0.0), |c| (c.direction.to_array(), c.cos_inner, c.cos_outer));
        let flags = if light.spot.is_some() { POINT_LIGHT_SPOT } else { 0 }
            | if light.range.is_some() { POINT_LIGHT_RANGE } else { 0 };
        Self {
            position: light.position.to_array(),
            range: light.range.unwrap_or(0.0),
            intensity: light.intensity.to_array(),
            flags,
            spot_direction,
            cos_inner,
            cos_outer,
            choice_cdf: 0.0,
            choice_pmf: 0.0,
            pad: 0,
        }
    }
}

/// The records of the scene's point and spot lights with their choice by power; one zero
/// record when there are none (a binding cannot be empty; `FrameParams::point_light_count`
/// stays 0 and no shader work is done).
pub fn point_light_records(scene: &Scene) -> Vec<GpuPointLight> {
    let lights: Vec<furnace_scene::PointLight> = scene.point_lights().copied().collect();
    let mut v: Vec<GpuPointLight> = lights.iter().map(GpuPointLight::new).collect();
    if let Some(choice) = PointLightDistribution::new(&lights) {
        for ((record, &cdf), &pmf) in v.iter_mut().zip(choice.cdf()).zip(choice.pmf()) {
            record.choice_cdf = cdf;
            record.choice_pmf = pmf;
        }
    }
    if v.is_empty() {
        v.push(GpuPointLight::zeroed());
    }
    v
}

/// The `emitters` buffer of a scene's [`Emitters`], as `u32` words: per emitter its triangle,
/// its alias-table bin's alias and threshold (`f32` bits) — `3·n` words — then per material its
/// selection weight (`f32` bits): 12 bytes per emitter and 4 per material. A scene without
/// emitters has no such buffer, binding or shader code.
pub fn emitter_words(e: &Emitters) -> Vec<u32> {
    let mut words = Vec::with_capacity(3 * e.len() + e.material_weights().len());
    for (&t, bin) in e.triangles().iter().zip(e.bins()) {
        words.extend([t, bin.alias, bin.threshold.to_bits()]);
    }
    words.extend(e.material_weights().iter().map(|w| w.to_bits()));
    words
}

crate::wgsl_consts! {
    /// The light BVH's constants as WGSL `const` declarations (composed with `light_bvh.wgsl`).
    fn light_bvh_consts_wgsl;
    /// Words per light-BVH node in the `emitters` buffer ([`light_bvh_words`]).
    pub const LIGHT_BVH_NODE_WORDS: u32 = 12;
    /// A node's `child` word holds a leaf's item ([`furnace_scene::LIGHT_BVH_LEAF`]).
    pub const LIGHT_BVH_LEAF: u32 = furnace_scene::LIGHT_BVH_LEAF;
}

/// The `emitters` buffer when light samples choose by the [`LightBvh`] `bvh` of `e`
/// ([`LightSelection::Bvh`]), as `u32` words read by the shader as `vec4<u32>`: per emitter
/// its triangle, its path from the root (two words, levels 0–31 then 32–63) and a pad —
/// `4·n` words — then the nodes, depth first, [`LIGHT_BVH_NODE_WORDS`] each (`lo.xyz`, `φ`,
/// `hi.xyz`, `cos θo`, `axis.xyz`, `child`, the floats as bits): 16 bytes per emitter and 48
/// per node, `2n − 1` nodes. 16-byte records let a node be three 16-byte loads (twelve 4-byte
/// ones cost more on the H200, BENCHMARKS.md).
pub fn light_bvh_words(e: &Emitters, bvh: &LightBvh) -> Vec<u32> {
    let mut words = Vec::with_capacity(4 * e.len() + LIGHT_BVH_NODE_WORDS as usize * bvh.nodes().len());
    for (&t, &trail) in e.triangles().iter().zip(bvh.trails()) {
        words.extend([t, trail as u32, (trail >> 32) as u32, 0]);
    }
    for node in bvh.nodes() {
        let b = &node.bounds;
        words.extend(b.lo.to_array().map(f32::to_bits));
        words.push(b.phi.to_bits());
        words.extend(b.hi.to_array().map(f32::to_bits));
        words.push(b.cos_theta_o.to_bits());
        words.extend(b.axis.to_array().map(f32::to_bits));
        words.push(node.child);
    }
    words
}

/// The `environment` and `environment_cdf` buffers of an environment map, as `f32` bits: its
/// texels (RGB, row-major, row 0 at the top; 12 bytes each, `f32` as the CPU holds them: a sun of
/// 10⁶ W/(m²·sr) does not fit `f16`, whose largest value is 65 504, nor RGB9E5's 65 408), and,
/// when `sampler` is given (the map is light-sampled), its conditional CDFs (W per row) then its
/// marginal CDF (H) — the same `f32` values the CPU samples with (4 bytes a texel; none
/// without sampling). Two buffers, so that a 4096 × 2048 map (96 + 32 MiB) fits the 128 MiB a
/// binding may have on every adapter.
pub fn environment_words(
    env: &furnace_scene::Environment,
    sampler: Option<&furnace_scene::EnvironmentSampler>,
) -> [Vec<u32>; 2] {
    let texels = env.map.texels().iter().flat_map(|t| t.to_array()).map(f32::to_bits).collect();
    let cdfs = sampler.map_or_else(Vec::new, |s| {
        let d = s.distribution();
        d.conditional_cdf().iter().chain(d.marginal_cdf()).map(|c| c.to_bits()).collect()
    });
    [texels, cdfs]
}

/// Words of the counter buffer (`ray_counter`): rays, nodes and triangles as 64-bit pairs, then
/// fallbacks and the deepest stack.
const COUNTER_WORDS: usize = 8;

/// Uniform slots are this far apart (WebGPU's largest `min_uniform_buffer_offset_alignment`).
const SLOT: u64 = 256;

/// A block of a pass: samples `first..end`, then (with `converge`) adaptive sampling's test.
#[derive(Debug, Clone, Copy)]
struct Block {
    first: u32,
    end: u32,
    converge: bool,
}

/// One dispatch of a pass: rows `row_offset ..` × samples `first_sample ..`.
#[derive(Debug, Clone, Copy)]
struct Dispatch {
    row_offset: u32,
    rows: u32,
    first_sample: u32,
    samples: u32,
}

/// Invocations in a workgroup as `integrator.wgsl` declares it (`GROUP_SIZE`, checked by
/// `tests/integrator.rs`): 256, the largest that every WebGPU device accepts
/// (`max_compute_invocations_per_workgroup`'s default), and faster than 64 or 128 (BENCHMARKS.md,
/// "GPU integrator"). Hardware adapters that accept [`HARDWARE_GROUP_SIZE`] get that instead
/// ([`group_size_for`]). The film is the same, bit for bit, for every size.
pub const GROUP_SIZE: u32 = 256;

/// Invocations in a workgroup on hardware adapters that accept it: 1024. The driver must fit a
/// whole workgroup on one multiprocessor, so on an NVIDIA GPU (64 Ki registers per SM) the
/// megakernel gets at most 64 registers per invocation instead of the 128 it takes in workgroups
/// of 256: twice the resident warps (50 % occupancy instead of 25 %) for some spilling. Measured
/// on the H200 (BENCHMARKS.md, "Speed"): +2–15 % on the emitter, environment-map and interior
/// scenes, the Cornell box within ±3 %; 512 (still 128 registers) was slower than 256.
pub const HARDWARE_GROUP_SIZE: u32 = 1024;

/// The workgroup size of the integrator for a scene's features on an adapter:
/// `FURNACE_GROUP_SIZE` when set ([`ProfilingOverrides`]), else [`HARDWARE_GROUP_SIZE`] on a
/// hardware adapter whose workgroups hold that many invocations and whose workgroup memory holds
/// the shader's per-invocation arrays at that size in at most half of it (the compiler takes
/// workgroup memory of its own for spilled registers: at 1024 invocations the H200's driver
/// took 28 KiB besides the kernel's 16 KiB, and its limit is 48 KiB; with AOVs the kernel's
/// arrays alone are 48 KiB), else [`GROUP_SIZE`] (software adapters: lavapipe runs an
/// invocation's loop on a CPU thread, there is no occupancy to gain).
pub fn group_size_for(ctx: &GpuContext, overrides: &ProfilingOverrides, features: SceneFeatures) -> u32 {
    overrides.group_size.unwrap_or_else(|| {
        let limits = ctx.device.limits();
        default_group_size(
            crate::context::is_hardware(&ctx.info),
            limits.max_compute_invocations_per_workgroup,
            limits.max_compute_workgroup_storage_size,
            features,
        )
    })
}

/// [`group_size_for`]'s rule without the override, for an adapter described by whether it is
/// hardware and its two workgroup limits (invocations, bytes of workgroup memory).
pub fn default_group_size(
    hardware: bool,
    max_invocations: u32,
    max_workgroup_bytes: u32,
    features: SceneFeatures,
) -> u32 {
    let arrays_fit = 2 * workgroup_bytes(HARDWARE_GROUP_SIZE, features) <= max_workgroup_bytes;
    if hardware && arrays_fit && max_invocations >= HARDWARE_GROUP_SIZE {
        HARDWARE_GROUP_SIZE
    } else {
        GROUP_SIZE
    }
}

/// The bytes of `var<workgroup>` arrays `integrator.wgsl` declares for workgroups of
/// `group_size`: one `vec4<f32>` per invocation for the samples, two more with AOVs.
pub fn workgroup_bytes(group_size: u32, features: SceneFeatures) -> u32 {
    group_size * 16 * if features.aovs { 3 } else { 1 }
}

/// The integrator's shader as a pipeline compiles it: [`shader_source`] with the profiling
/// `overrides` applied, workgroups of `group_size` invocations and a traversal stack of
/// `stack_size` node groups.
///
/// # Errors
/// [`GpuError::Unsupported`] when a shader edit's text does not occur in the shader.
pub fn pipeline_source(
    precision: FilmPrecision,
    features: SceneFeatures,
    overrides: &ProfilingOverrides,
    group_size: u32,
    stack_size: u32,
) -> Result<String, GpuError> {
    let source = overrides.apply(shader_source(precision, features))?;
    Ok(crate::traverse::with_stack_size(&with_group_size(&source, group_size), stack_size))
}

/// `source` (a [`shader_source`]) with workgroups of `n` invocations instead of [`GROUP_SIZE`].
pub fn with_group_size(source: &str, n: u32) -> String {
    source.replace(
        &format!("const GROUP_SIZE: u32 = {GROUP_SIZE}u;"),
        &format!("const GROUP_SIZE: u32 = {n}u;"),
    )
}

/// The most invocations per pixel on hardware adapters: 16, where throughput stops growing on
/// small images (`furnace bench --group-samples N`, BENCHMARKS.md "Occupancy"): a 256² image
/// alone does not fill a large GPU.
const HARDWARE_GROUP_SAMPLES: u32 = 16;

/// Invocations per pixel on a hardware adapter for an image of `pixels` pixels: the largest
/// power of two up to `HARDWARE_GROUP_SAMPLES` whose dispatch of every pixel stays within
/// `samples_per_dispatch` invocations (at least 1). Small images get 16 invocations per pixel to
/// fill the GPU; large ones few, so that one dispatch covers the whole image: measured on the
/// H200 (BENCHMARKS.md, "Speed"), 1920×1440 at 4 per pixel was cut into dispatches of 1092 and
/// 348 rows and ran 23 % slower than at 2 (one dispatch per 2 samples), while 1920×1080 is as
/// fast at 4 as at 16.
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
/// two, the height what is left; see
/// [`ProfilingOverrides::group_size`]).
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
/// the scene, not on a size or a bounce count that could be read beforehand: on the H200 the
/// sunlit interior ran 2–20 % faster at one per pixel and the Cornell box of as many triangles
/// 4–16 % slower at 4 and 6 bounces (BENCHMARKS.md, "Invocations per pixel against path
/// length"). The film does not depend on the choice, bit for bit, so trying both costs no
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
    /// fraction (otherwise the rule's choice stays): a margin above the ~0.3 % run-to-run
    /// spread of one configuration on the H200.
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

/// Counters of the traversal, summed over the counting passes (see [`GpuRenderer::set_count_rays`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TraceCounts {
    /// Rays traced (closest-hit and shadow).
    pub rays: u64,
    /// BVH nodes whose child boxes were tested.
    pub nodes: u64,
    /// Ray-triangle tests.
    pub triangles: u64,
    /// Traces whose stack overflowed into the fallback sweep.
    pub fallbacks: u32,
    /// Deepest traversal stack reached by any trace.
    pub max_stack_depth: u32,
}

/// The scene, BVH, film and pipeline on one device.
#[derive(Debug)]
pub struct GpuRenderer {
    ctx: GpuContext,
    settings: RenderSettings,
    sampler: AnySampler,
    base: FrameParams,
    pipeline: wgpu::ComputePipeline,
    /// Adaptive sampling's test on the GPU (the `converge` entry point; `f64` films only).
    converge: Option<wgpu::ComputePipeline>,
    /// Its count of converged pixels (and the number last read from it, or from the host's
    /// marks for an `F32Pass` film).
    converged_counter: Option<wgpu::Buffer>,
    converged: Option<u64>,
    layout: wgpu::BindGroupLayout,
    film: GpuFilm,
    scene: GpuScene,
    bvh: [wgpu::Buffer; 2],
    turquin: wgpu::Buffer,
    point_lights: wgpu::Buffer,
    emitters: Option<wgpu::Buffer>,
    /// The environment's texels and, when light-sampled, its CDFs (empty without one).
    environment: Vec<wgpu::Buffer>,
    features: SceneFeatures,
    bytes_per_triangle: f64,
    bvh_bytes: u64,
    scene_bytes: u64,
    ray_counter: wgpu::Buffer,
    samples_per_dispatch: u64,
    max_samples_per_invocation: u32,
    group_samples: Option<u32>,
    /// Whether adaptive sampling's test runs at its test points (off when several devices share
    /// a render: their films are tested together, [`crate::MultiGpuRenderer`]).
    convergence_tests: bool,
    /// The choice of invocations per pixel by timing, where the renderer chooses
    /// ([`GpuRenderer::tuner_for`]).
    tuner: Option<GroupTuner>,
    /// Invocations per workgroup ([`group_size_for`]).
    group_size: u32,
    /// Node groups of the traversal stack ([`ProfilingOverrides::stack_size`] for the uploaded
    /// tree's depth).
    stack_size: u32,
    timer: Option<Timer>,
    /// Triangles uploaded (what [`GpuRenderer::reconfigure`] checks a scene against).
    triangles: usize,
    /// Whether the film is kept drawable ([`GpuRenderer::enable_display`]).
    display: bool,
    /// Polled between dispatches of a long pass ([`Integrator::set_cancel_flag`]).
    cancel: Option<CancelFlag>,
    /// Wall seconds of the last pass's submissions (0 before the first): a pass after one longer
    /// than [`LONG_PASS_SECONDS`] is submitted dispatch by dispatch, so that it can be stopped
    /// (the first too when its dispatches start halved for long paths).
    last_pass_seconds: f64,
    /// How many times dispatches are halved from [`GpuRenderer::samples_per_dispatch`]
    /// ([`GpuRenderer::fit_dispatches`]); for paths of more than 16 bounces it starts at what
    /// paths of every bounce would need.
    dispatch_shift: u32,
    /// Copies of the film's pass state taken before a pass submitted dispatch by dispatch
    /// ([`GpuFilm::pass_state`], then the convergence counter), to give it back if stopped.
    pass_backup: Vec<wgpu::Buffer>,
}

/// A pass whose predecessor took longer than this (seconds) is submitted dispatch by dispatch,
/// with the cancel flag polled between: a quarter of the one second within which Ctrl-C is to
/// be answered. Shorter passes stay one submission (no wait between dispatches).
const LONG_PASS_SECONDS: f64 = 0.25;

/// A dispatch longer than this (seconds) makes the next ones smaller
/// ([`GpuRenderer::fit_dispatches`]): a quarter of the second within which a cancel flag is to be
/// answered.
const LONG_DISPATCH_SECONDS: f64 = 0.25;

/// Halvings of the dispatches for paths of up to `bounces` scattering events: none up to 16, else
/// as many as make a dispatch of paths that all reach the limit no longer than one of 16-bounce
/// paths (`⌈log₂((bounces + 1) / 17)⌉`: 6 at 1024); measured dispatch times correct it after
/// the first pass.
fn initial_dispatch_shift(bounces: u32) -> u32 {
    let ratio = (f64::from(bounces) + 1.0) / 17.0;
    if ratio > 1.0 { ratio.log2().ceil() as u32 } else { 0 }
}

/// One step of a pass's submission: a dispatch of samples (its uniform slot, workgroup rows and
/// tile width) or the adaptive-sampling test after a block.
#[derive(Debug, Clone, Copy)]
enum Step {
    Samples { slot: usize, groups_y: u32, tile_width: u32 },
    Converge,
}

/// GPU timestamps around each pass's compute pass (adapters with `TIMESTAMP_QUERY`).
#[derive(Debug)]
struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    period_ns: f32,
    last: Option<f64>,
}

/// The integrator's bindings, group 0 from binding 0: the [`FrameParams`] uniform (dynamic
/// offset, one slot per dispatch), the film, the BVH, the scene, the Turquin table and the ray
/// counter. One table gives the shader's declarations, the layout and the bind group.
pub fn binding_table(precision: FilmPrecision, features: SceneFeatures) -> BindingTable {
    let params = Binding {
        name: "params",
        ty: FrameParams::NAME.to_string(),
        kind: BindingKind::Uniform { dynamic: true, min_size: size_of::<FrameParams>() as u64 },
    };
    let mut bindings = vec![params];
    bindings.extend(precision.binding_list());
    bindings.extend(traverse::binding_list());
    bindings.extend(scene::binding_list());
    bindings.push(Binding::read("turquin_table", "array<f32>"));
    bindings.push(Binding::read("point_lights", "array<PointLight>"));
    if features.transmission {
        bindings.push(Binding::read("scene_transmission", "array<SceneTransmission>"));
    }
    if features.emitters {
        // Chosen by the light BVH: 16-byte records and nodes, read as vec4 (three loads a node).
        let ty = if features.light_bvh { "array<vec4<u32>>" } else { "array<u32>" };
        bindings.push(Binding::read("emitters", ty));
    }
    if features.environment {
        bindings.push(Binding::read("environment", "array<f32>"));
        if features.env_sampling {
            bindings.push(Binding::read("environment_cdf", "array<f32>"));
        }
    }
    bindings.push(Binding::read_write("ray_counter", &format!("array<atomic<u32>, {COUNTER_WORDS}>")));
    if features.aovs {
        bindings.push(precision.aov_binding());
    }
    if features.adaptive {
        bindings.push(Binding::read_write("film_converged", "array<u32>"));
        bindings.push(Binding::read_write("converged_counter", "array<atomic<u32>, 4>"));
    }
    BindingTable::new(0, 0, bindings)
}

/// Point and spot lights whose shadow rays are queued, at most: each takes a slot of the
/// per-event shadow queue (40 bytes of private memory) and a shadow iteration of the path loop
/// after every path ray, also where it is not taken; more lights are traced where they are
/// gathered, through a second traversal call.
pub const MAX_QUEUED_POINT_LIGHTS: u32 = 4;

/// The light and material features a scene uses that the integrator shader is composed for:
/// code for a feature the scene lacks is left out at compile time (no GPU work, no registers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SceneFeatures {
    /// Point or spot lights (the shadow-ray loop over `point_lights`).
    pub point_lights: bool,
    /// The number of point and spot lights when it is at most [`MAX_QUEUED_POINT_LIGHTS`] (else
    /// 0), or 1 when one is chosen per event (`one_point_light`): their shadow rays are then
    /// queued like the other light samples' (a slot each, traced through the path loop's one
    /// traversal call) instead of traced where they are gathered.
    pub queued_point_lights: u32,
    /// One point or spot light per event, chosen by power ([`furnace_render::PointLightSampling::effective`]
    /// is `One`; with `point_lights` only).
    pub one_point_light: bool,
    /// Emissive triangles (their light samples and the MIS weights of their emission).
    pub emitters: bool,
    /// A sun without a disc, a delta light (its shadow ray at each scattering event).
    pub delta_sun: bool,
    /// A sun with a disc (its cone samples, and its radiance seen by escaping rays).
    pub sun_disc: bool,
    /// Emitters chosen by the light BVH ([`LightSelection::Bvh`]; with `emitters` only).
    pub light_bvh: bool,
    /// An environment map (its lookup by escaping rays; its texels bound).
    pub environment: bool,
    /// The environment map is light-sampled (its CDFs bound, its light samples and MIS weights).
    pub env_sampling: bool,
    /// The film sums the first-hit AOVs ([`RenderSettings::aovs`]: their binding, the record of
    /// the camera ray's hit and its sums).
    pub aovs: bool,
    /// Adaptive sampling ([`RenderSettings::adaptive`]: converged pixels are skipped; with an
    /// `f64` film the test runs on the GPU, the `converge` entry point).
    pub adaptive: bool,
    /// A transmissive material (the dielectric BSDF, volumes' absorption, the
    /// `scene_transmission` records).
    pub transmission: bool,
    /// A material shadow rays cross (a thin-walled sheet, multiplied by its T′; an η = 1 solid).
    pub thin_walled: bool,
    /// Emissive triangles are sampled by solid angle where that is precise
    /// ([`TriangleSampling::SolidAngle`]; with `emitters` only), else by area: the spherical
    /// triangle's code is composed only then.
    pub solid_angle_triangles: bool,
    /// The passes count what they trace ([`GpuRenderer::set_count_rays`]: rays, BVH nodes and
    /// triangles per invocation, added to the ray counter at its end). Not a property of the
    /// scene: the counting kernel is a variant of its own, so that rendering pays nothing for it.
    pub trace_counters: bool,
}

impl SceneFeatures {
    /// The features `scene` uses when rendered with `settings`.
    pub fn of(scene: &Scene, settings: &RenderSettings) -> Self {
        Self::with_emitters(scene, settings, Emitters::new(scene).is_some())
    }

    fn with_emitters(scene: &Scene, settings: &RenderSettings, emitters: bool) -> Self {
        Self {
            point_lights: scene.point_lights().next().is_some(),
            queued_point_lights: match scene.point_lights().count() {
                n if settings.point_lights.chooses(n) => 1,
                n if n <= MAX_QUEUED_POINT_LIGHTS as usize => n as u32,
                _ => 0,
            },
            one_point_light: settings.point_lights.chooses(scene.point_lights().count()),
            emitters,
            delta_sun: scene.sun().is_some_and(|s| !s.is_disc()),
            sun_disc: scene.sun().is_some_and(|s| s.is_disc()),
            light_bvh: emitters && settings.light_selection == LightSelection::Bvh,
            environment: scene.environment().is_some(),
            env_sampling: scene.environment().is_some_and(|e| !e.is_black())
                && settings.env_sampling.light_samples(settings.light_sampling).is_some(),
            aovs: settings.aovs,
            adaptive: settings.adaptive.is_some(),
            transmission: scene.materials.iter().any(|m| m.is_transmissive()),
            thin_walled: scene.materials.iter().any(|m| m.passes_shadow_rays()),
            solid_angle_triangles: emitters && settings.triangle_sampling == TriangleSampling::SolidAngle,
            trace_counters: false,
        }
    }

    /// The `SHADOW_KINDS` and `SHADOW_SLOTS` constants, as WGSL.
    pub fn wgsl(self) -> String {
        let kinds = self.shadow_kinds();
        format!("const SHADOW_KINDS: u32 = {kinds}u;\nconst SHADOW_SLOTS: u32 = {}u;\n", kinds.max(1))
    }

    /// The shadow rays a scattering event queues at most (integrator.wgsl's `defer_shadow`;
    /// `SHADOW_SLOTS`, the size of a WGSL array, is this but at least 1): one per light kind
    /// sampled there (the delta sun, the emitters, the sun disc, the environment) and one per
    /// point light when they are queued ([`SceneFeatures::queued_point_lights`]).
    pub fn shadow_kinds(self) -> u32 {
        let kinds = [self.delta_sun, self.emitters, self.sun_disc, self.enabled("SAMPLES_ENVIRONMENT")];
        kinds.iter().filter(|&&k| k).count() as u32 + self.point_lights_queued()
    }

    /// [`SceneFeatures::queued_point_lights`] where the scene has point lights, else 0.
    fn point_lights_queued(self) -> u32 {
        if self.point_lights { self.queued_point_lights } else { 0 }
    }

    /// Whether the `// #if NAME` blocks of the shader ([`wgsl::select`]) are composed:
    /// `HAS_EMITTERS`, `HAS_DELTA_SUN`, `HAS_SUN_DISC`, `HAS_ENVIRONMENT`, `SAMPLES_ENVIRONMENT`,
    /// `SAMPLES_LIGHTS` (any light sample: the MIS weights), `LIGHT_BVH`, `SOLID_ANGLE_TRIANGLES`,
    /// `AOVS`, `ADAPTIVE`, `TRANSMISSION`, `THIN_WALLED`, `TRACE_COUNTERS`,
    /// `QUEUED_POINT_LIGHTS` and `ONE_POINT_LIGHT`
    /// (`ADAPTIVE_ON_GPU` is chosen by [`shader_source`]: adaptive with an `f64` film).
    pub fn enabled(self, name: &str) -> bool {
        match name {
            "HAS_EMITTERS" => self.emitters,
            "LIGHT_BVH" => self.emitters && self.light_bvh,
            "HAS_DELTA_SUN" => self.delta_sun,
            "HAS_SUN_DISC" => self.sun_disc,
            "HAS_ENVIRONMENT" => self.environment,
            "SAMPLES_ENVIRONMENT" => self.environment && self.env_sampling,
            "SAMPLES_LIGHTS" => self.emitters || self.sun_disc || (self.environment && self.env_sampling),
            "HAS_POINT_LIGHTS" => self.point_lights,
            "AOVS" => self.aovs,
            "ADAPTIVE" => self.adaptive,
            "TRANSMISSION" => self.transmission,
            "THIN_WALLED" => self.transmission && self.thin_walled,
            "SOLID_ANGLE_TRIANGLES" => self.emitters && self.solid_angle_triangles,
            "TRACE_COUNTERS" => self.trace_counters,
            "QUEUED_POINT_LIGHTS" => self.point_lights_queued() > 0,
            "ONE_POINT_LIGHT" => self.point_lights && self.one_point_light,
            _ => panic!("no scene feature {name} (integrator.wgsl's #if)"),
        }
    }
}

/// The composed WGSL of the integrator for a film precision (for tests and tools): the
/// generated declarations (sampler layout, `FRAME_*` flags, [`FrameParams`], the BSDF's, the
/// scene's and the traversal's structs and constants, the bindings of [`binding_table`]), the
/// twins, and `integrator.wgsl`, with the code of the scene `features` only.
pub fn shader_source(precision: FilmPrecision, features: SceneFeatures) -> String {
    let generated = [
        furnace_render::layout::wgsl(),
        frame_flags_wgsl(),
        wgsl_struct::<FrameParams>(true),
        brdf::declarations(),
        scene::declarations(),
        traverse::declarations(),
        point_light_flags_wgsl(),
        wgsl_struct::<GpuPointLight>(false),
        format!("const SHADOW_EPSILON: f32 = {:?};\n", furnace_render::SHADOW_EPSILON),
        format!("const MAX_SHEET_PASSES: u32 = {}u;\n", furnace_render::MAX_SHEET_PASSES),
        format!(
            "const SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE: f32 = {:?};\nconst SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE: f32 = {:?};\n",
            furnace_sampling::warp::SPHERICAL_TRIANGLE_MIN_SOLID_ANGLE,
            furnace_sampling::warp::SPHERICAL_TRIANGLE_MAX_SOLID_ANGLE
        ),
        features.wgsl(),
        binding_table(precision, features).wgsl(),
        if features.aovs { format!("alias aov_sum_t = {};\n", precision.aov_sum_type()) } else { String::new() },
    ]
    .concat();
    let light_bvh =
        if features.enabled("LIGHT_BVH") { light_bvh_consts_wgsl() + wgsl::LIGHT_BVH } else { String::new() };
    let environment = if features.enabled("HAS_ENVIRONMENT") {
        env_flags_wgsl() + &wgsl::select(wgsl::ENVIRONMENT, |name| features.enabled(name))
    } else {
        String::new()
    };
    let integrator = wgsl::select(include_str!("wgsl/integrator.wgsl"), |name| match name {
        "ADAPTIVE_ON_GPU" => features.adaptive && precision == FilmPrecision::F64,
        _ => features.enabled(name),
    });
    wgsl::compose(&[
        &generated,
        wgsl::SAMPLING,
        wgsl::BRDF,
        if features.transmission { wgsl::DIELECTRIC } else { "" },
        wgsl::SCENE,
        &wgsl::select(wgsl::TRAVERSE, |name| features.enabled(name)),
        &light_bvh,
        &environment,
        precision.wgsl(),
        wgsl::PATH,
        &wgsl::select(wgsl::MATERIAL, |name| features.enabled(name)),
        &integrator,
    ])
}

/// The film `settings` need: with AOVs and adaptive-sampling marks when they ask for them.
fn film_for(
    ctx: &GpuContext,
    settings: &RenderSettings,
    precision: FilmPrecision,
) -> Result<GpuFilm, GpuError> {
    GpuFilm::with_parts(
        ctx,
        settings.width,
        settings.height,
        precision,
        settings.aovs,
        settings.adaptive.is_some(),
    )
}

/// Adaptive sampling's count of converged pixels (kept by the `converge` kernel); `None`
/// without adaptive sampling.
fn converged_counter(ctx: &GpuContext, settings: &RenderSettings) -> Result<Option<wgpu::Buffer>, GpuError> {
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    settings.adaptive.map(|_| ctx.buffer_init("converged counter", &[0; 16], usage)).transpose()
}

/// A storage buffer of `words`, padded to 16 bytes (a binding cannot be empty); large buffers
/// (an environment map's texels) are not copied on the way.
fn storage_buffer(ctx: &GpuContext, label: &str, words: &[u32]) -> Result<wgpu::Buffer, GpuError> {
    if words.len() >= 4 {
        return ctx.buffer_init(label, bytemuck::cast_slice(words), wgpu::BufferUsages::STORAGE);
    }
    let mut v = words.to_vec();
    v.resize(4, 0);
    ctx.buffer_init(label, bytemuck::cast_slice(&v), wgpu::BufferUsages::STORAGE)
}

/// The emitters' buffer (records, or light BVH nodes with `features.light_bvh`); `None` (and no
/// binding) for a scene without emitters.
fn emitter_buffer(
    ctx: &GpuContext,
    scene: &Scene,
    emitters: Option<&Emitters>,
    features: SceneFeatures,
) -> Result<Option<wgpu::Buffer>, GpuError> {
    emitter_buffer_words(scene, emitters, features).map(|w| storage_buffer(ctx, "emitters", &w)).transpose()
}

/// The words of [`emitter_buffer`].
fn emitter_buffer_words(
    scene: &Scene,
    emitters: Option<&Emitters>,
    features: SceneFeatures,
) -> Option<Vec<u32>> {
    emitters
        .map(|e| if features.light_bvh { light_bvh_words(e, &e.light_bvh(scene)) } else { emitter_words(e) })
}

/// The environment's texels, and its CDFs when it is light-sampled; none (and no binding)
/// without one.
fn environment_buffers(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &RenderSettings,
    limit: u64,
) -> Result<Vec<wgpu::Buffer>, GpuError> {
    environment_buffer_words(scene, settings, limit)?
        .iter()
        .map(|(label, w)| storage_buffer(ctx, label, w))
        .collect()
}

/// The labels and words of [`environment_buffers`].
fn environment_buffer_words(
    scene: &Scene,
    settings: &RenderSettings,
    limit: u64,
) -> Result<Vec<(&'static str, Vec<u32>)>, GpuError> {
    let mut environment = Vec::new();
    if let Some(env) = scene.environment() {
        let sampler = settings
            .env_sampling
            .light_samples(settings.light_sampling)
            .and_then(|compensated| env.sampler(compensated));
        let [texels, cdfs] = environment_words(env, sampler.as_ref());
        for (what, w) in [("environment map", &texels), ("environment map's CDFs", &cdfs)] {
            let bytes = 4 * w.len() as u64;
            if bytes > limit {
                return Err(GpuError::TooLarge { what: what.into(), bytes, limit });
            }
        }
        environment.push(("environment", texels));
        if sampler.is_some() {
            environment.push(("environment cdf", cdfs));
        }
    }
    Ok(environment)
}

/// What a renderer uploads, made on the host: the BVH's and the scene's words, the emitters' (a
/// light BVH) and the environment's (its CDFs), and the frame's constants. A render on several
/// GPUs makes it once for all its devices ([`crate::MultiGpuRenderer`]).
#[derive(Debug)]
pub(crate) struct PackedScene {
    settings: RenderSettings,
    sampler: AnySampler,
    base: FrameParams,
    features: SceneFeatures,
    bvh_depth: usize,
    triangles: usize,
    bvh_words: BvhBuffers,
    scene_words: SceneBuffers,
    point_lights: Vec<GpuPointLight>,
    emitter_words: Option<Vec<u32>>,
    environment: Vec<(&'static str, Vec<u32>)>,
}

impl PackedScene {
    /// Packs `scene` with its CWBVH `bvh` for `settings`, every buffer at most `limit` bytes (the
    /// largest limit of the devices that will upload it: each checks its own,
    /// [`PackedScene::check_limit`]).
    ///
    /// # Errors
    /// As [`GpuRenderer::with_bvh`], but no device error.
    pub(crate) fn new(
        scene: &Scene,
        bvh: &Bvh,
        camera: &Camera,
        settings: RenderSettings,
        limit: u64,
    ) -> Result<Self, GpuError> {
        let sampler = renderable_sampler(scene, &settings)?;
        let g = &scene.geometry;
        if bvh.input_count() != g.triangle_count() || bvh.layout() != furnace_accel::Layout::Cwbvh {
            return Err(GpuError::Unsupported(format!(
                "a {:?} BVH over {} triangles for a scene of {} (the GPU traverses a CWBVH of the scene's triangles)",
                bvh.layout(),
                bvh.input_count(),
                g.triangle_count()
            )));
        }
        let sampler_params = SamplerParams::new(settings.sampler, settings.seed, settings.sample_count)?;
        let scene_emitters = Emitters::new(scene);
        let features = SceneFeatures::with_emitters(scene, &settings, scene_emitters.is_some());
        Ok(Self {
            settings,
            sampler,
            base: frame_params_with(scene, camera, &settings, sampler_params, scene_emitters.as_ref()),
            features,
            bvh_depth: bvh.depth(),
            triangles: g.triangles.len(),
            bvh_words: BvhBuffers::new(bvh, limit)?,
            scene_words: SceneBuffers::new(scene, limit)?,
            point_lights: point_light_records(scene),
            emitter_words: emitter_buffer_words(scene, scene_emitters.as_ref(), features),
            environment: environment_buffer_words(scene, &settings, limit)?,
        })
    }

    /// The largest upload limit of `contexts` ([`PackedScene::new`]'s `limit`): a device with a
    /// smaller one refuses the scene in [`GpuRenderer::with_packed`] if it does not fit.
    pub(crate) fn limit_of<'a>(contexts: impl IntoIterator<Item = &'a GpuContext>) -> u64 {
        contexts.into_iter().map(GpuContext::upload_limit).max().unwrap_or(u64::MAX)
    }

    /// [`GpuError::TooLarge`] for the first buffer over `limit` bytes (a device's own limit,
    /// where the scene was packed for a larger one).
    fn check_limit(&self, limit: u64) -> Result<(), GpuError> {
        let [nodes, tris] = self.bvh_words.extra();
        let mut buffers: Vec<(&str, &[u32])> = vec![("BVH node", nodes), ("BVH triangle", tris)];
        buffers.extend(SceneBuffers::EXTRA_NAMES.into_iter().zip(self.scene_words.extra()));
        buffers.push(("scene transmission", bytemuck::cast_slice(&self.scene_words.transmission)));
        buffers.extend(self.emitter_words.as_deref().map(|w| ("emitter", w)));
        buffers.extend(self.environment.iter().map(|(label, w)| (*label, w.as_slice())));
        for (what, words) in buffers {
            let bytes = size_of_val(words) as u64;
            if bytes > limit {
                return Err(GpuError::TooLarge { what: format!("the {what} buffer"), bytes, limit });
            }
        }
        Ok(())
    }
}

/// The runtime checks wgpu adds to the integrator's shader when it translates it (naga's
/// SPIR-V for Vulkan): none of them changes what a correct shader computes, only its speed and
/// its compile time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShaderChecks {
    /// wgpu's defaults: local arrays' indices clamped, every loop bounded by a 64-bit counter,
    /// integer division guarded (buffer accesses: by the driver's robustBufferAccess2 where it
    /// has it).
    Checked,
    /// No loop counters (the other checks kept): the default. Every loop of the integrator ends
    /// (the traversal's and the light BVH's on the trees furnace builds, the path's at the bounce
    /// limit). Without the counters the driver unrolls the node test's loop over eight children:
    /// on the H200 the sunlit interior ran 17 % faster (1920×1440, 6 bounces, 21 nodes per ray),
    /// and, once the kernel traced every ray through one call site, the emitter and
    /// environment-map scenes 7–18 % faster (BENCHMARKS.md, "Speed"). Lavapipe compiles the
    /// megakernel 3–4 times faster without them.
    NoLoopBounding,
    /// None of the checks (profiling only).
    Unchecked,
}

impl Default for ShaderChecks {
    /// [`ShaderChecks::NoLoopBounding`], on every adapter and for every kernel.
    fn default() -> Self {
        Self::NoLoopBounding
    }
}

impl ShaderChecks {
    /// wgpu's runtime checks for this choice.
    pub fn runtime_checks(self) -> wgpu::ShaderRuntimeChecks {
        match self {
            Self::Checked => wgpu::ShaderRuntimeChecks::checked(),
            Self::NoLoopBounding => {
                let mut c = wgpu::ShaderRuntimeChecks::checked();
                c.force_loop_bounding = false;
                c
            }
            // SAFETY (of the value; creating a module with it is the unsafe step): see
            // `integrator_pipeline`.
            Self::Unchecked => wgpu::ShaderRuntimeChecks::unchecked(),
        }
    }
}

/// Overrides of the integrator's shader for profiling, read from the environment when a
/// pipeline is built (`docs/device/speed-*.sh`); unset, the shader is the tested one:
///
/// | variable | effect |
/// |---|---|
/// | `FURNACE_SHADER_CHECKS=checked\|noloop\|unchecked` | [`ShaderChecks`] instead of the adapter's default |
/// | `FURNACE_TRV_STACK=N` | a traversal stack of N node groups instead of the tree's depth's ([`ProfilingOverrides::stack_size`]) |
/// | `FURNACE_GROUP_SIZE=N` | workgroups of N invocations (a multiple of 32 — whole warps — from 32 to 1024, within the adapter's limit) instead of [`group_size_for`]'s choice |
/// | `FURNACE_SHADER_EDIT=FILE` | text edits of the composed shader, for timing variants (a part left out, a cheaper form): FILE holds blocks `<<<` line, the text, `===` line, its replacement, `>>>` line; each text must occur in the shader |
#[derive(Debug, Clone, Default)]
pub struct ProfilingOverrides {
    /// `FURNACE_SHADER_CHECKS`.
    pub checks: Option<ShaderChecks>,
    /// `FURNACE_TRV_STACK`.
    pub stack: Option<u32>,
    /// `FURNACE_GROUP_SIZE`.
    pub group_size: Option<u32>,
    /// `FURNACE_SHADER_EDIT`: (text, replacement) pairs, applied in order.
    pub edits: Vec<(String, String)>,
}

/// The (text, replacement) blocks of a `FURNACE_SHADER_EDIT` file (see [`ProfilingOverrides`]).
fn parse_shader_edits(path: &str, text: &str) -> Result<Vec<(String, String)>, GpuError> {
    let bad = |k: usize, what: &str| {
        GpuError::Unsupported(format!("FURNACE_SHADER_EDIT={path}: block {k}: {what}"))
    };
    let mut edits = Vec::new();
    for (k, block) in text.split("<<<\n").skip(1).enumerate() {
        let (old, rest) = block.split_once("\n===\n").ok_or_else(|| bad(k + 1, "no `===` line"))?;
        // An empty replacement: `>>>` right after the `===` line.
        let new = match rest.strip_prefix(">>>") {
            Some(_) => "",
            None => rest.split_once("\n>>>").ok_or_else(|| bad(k + 1, "no `>>>` line"))?.0,
        };
        if old.is_empty() {
            return Err(bad(k + 1, "empty text"));
        }
        edits.push((old.to_string(), new.to_string()));
    }
    if edits.is_empty() {
        return Err(GpuError::Unsupported(format!("FURNACE_SHADER_EDIT={path}: no `<<<` block")));
    }
    Ok(edits)
}

impl ProfilingOverrides {
    /// The overrides set in the environment.
    ///
    /// # Errors
    /// [`GpuError::Unsupported`] naming the variable when a value is not one of the table's.
    pub fn from_env() -> Result<Self, GpuError> {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.is_empty());
        let checks = match var("FURNACE_SHADER_CHECKS").as_deref() {
            None => None,
            Some("checked") => Some(ShaderChecks::Checked),
            Some("noloop") => Some(ShaderChecks::NoLoopBounding),
            Some("unchecked") => Some(ShaderChecks::Unchecked),
            Some(v) => {
                return Err(GpuError::Unsupported(format!(
                    "FURNACE_SHADER_CHECKS={v}: expected checked, noloop or unchecked"
                )));
            }
        };
        let stack = match var("FURNACE_TRV_STACK") {
            None => None,
            Some(v) => Some(v.parse::<u32>().ok().filter(|&n| n > 0).ok_or_else(|| {
                GpuError::Unsupported(format!("FURNACE_TRV_STACK={v}: expected a positive integer"))
            })?),
        };
        let group_size = match var("FURNACE_GROUP_SIZE") {
            None => None,
            Some(v) => {
                Some(v.parse::<u32>().ok().filter(|n| n % 32 == 0 && (32..=1024).contains(n)).ok_or_else(
                    || {
                        GpuError::Unsupported(format!(
                            "FURNACE_GROUP_SIZE={v}: expected a multiple of 32, 32 to 1024"
                        ))
                    },
                )?)
            }
        };
        let edits = match var("FURNACE_SHADER_EDIT") {
            None => Vec::new(),
            Some(path) => {
                let text = std::fs::read_to_string(&path)
                    .map_err(|e| GpuError::Unsupported(format!("FURNACE_SHADER_EDIT={path}: {e}")))?;
                parse_shader_edits(&path, &text)?
            }
        };
        Ok(Self { checks, stack, group_size, edits })
    }

    /// `source` (a [`shader_source`]) with the edits applied (the
    /// workgroup size is [`group_size_for`]'s, applied with [`with_group_size`]; the stack size
    /// [`ProfilingOverrides::stack_size`]'s, applied with [`crate::traverse::with_stack_size`]).
    ///
    /// # Errors
    /// [`GpuError::Unsupported`] when an edit's text does not occur in the shader.
    pub fn apply(&self, source: String) -> Result<String, GpuError> {
        let mut s = source;
        for (k, (old, new)) in self.edits.iter().enumerate() {
            if !s.contains(old.as_str()) {
                return Err(GpuError::Unsupported(format!(
                    "FURNACE_SHADER_EDIT: block {} does not occur in the shader: {old:?}",
                    k + 1
                )));
            }
            s = s.replace(old.as_str(), new);
        }
        Ok(s)
    }

    /// The traversal stack for a tree of `depth` node levels ([`furnace_accel::Bvh::depth`]):
    /// `FURNACE_TRV_STACK` when set, else [`crate::traverse::stack_size_for`]'s.
    pub fn stack_size(&self, depth: usize) -> u32 {
        self.stack.unwrap_or_else(|| crate::traverse::stack_size_for(depth))
    }
}

/// The integrator's bind group layout and compute pipeline for a film precision and the scene
/// features.
#[allow(unsafe_code)]
fn integrator_pipeline(
    ctx: &GpuContext,
    precision: FilmPrecision,
    features: SceneFeatures,
    overrides: &ProfilingOverrides,
    group_size: u32,
    stack_size: u32,
) -> Result<(wgpu::BindGroupLayout, wgpu::ComputePipeline, Option<wgpu::ComputePipeline>), GpuError> {
    let entries = binding_table(precision, features).layout_entries();
    let device = &ctx.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("integrator"),
        entries: &entries,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("integrator"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let checks = overrides.checks.unwrap_or_default();
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some("integrator"),
        source: wgpu::ShaderSource::Wgsl(
            pipeline_source(precision, features, overrides, group_size, stack_size)?.into(),
        ),
    };
    let module = match checks {
        ShaderChecks::Checked => device.create_shader_module(desc),
        // SAFETY: the checks turned off guard against what this shader does not do. Every loop
        // of the integrator ends (loops over counts, over the bits of a mask that each iteration
        // clears, a binary search, the traversal of a finite tree built here, the path loop
        // bounded by the bounces and MAX_SHEET_PASSES); with `Unchecked` (a profiling override
        // only), its local arrays are indexed within bounds (the traversal stack by a depth kept
        // below TRV_STACK_SIZE), integer divisions are by non-zero values (group_samples ≥ 1,
        // the emitter count tested first), and buffer accesses stay in bounds on a device with
        // robustBufferAccess2 regardless (wgpu leaves those checks to the driver there).
        _ => unsafe { device.create_shader_module_trusted(desc, checks.runtime_checks()) },
    };
    let entry = |name: &str| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(name),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(name),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    let pipeline = entry("main");
    let converge = (features.adaptive && precision == FilmPrecision::F64).then(|| entry("converge"));
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Wgpu(e.to_string()));
    }
    Ok((layout, pipeline, converge))
}

/// The render's sampler, once the scene and settings are known to be renderable on the GPU: one
/// directional light at most, and a sampler it can build. Called before the BVH is built, so
/// that a refusal costs nothing.
pub(crate) fn renderable_sampler(scene: &Scene, settings: &RenderSettings) -> Result<AnySampler, GpuError> {
    let suns = scene.suns().count();
    if suns > 1 {
        return Err(GpuError::Unsupported(format!(
            "the scene has {suns} directional lights; the GPU integrator renders one (the CPU \
             integrator renders any number)"
        )));
    }
    Ok(AnySampler::new(settings.sampler, settings.seed, settings.sample_count)?)
}

impl GpuRenderer {
    /// Uploads `scene` (seen through `camera`) and builds the pipeline for `settings`.
    ///
    /// # Errors
    /// The sampler's (fixed-N samplers need `sample_count`), [`GpuError::TooLarge`] when a
    /// buffer exceeds the adapter's limits, [`GpuError::Unsupported`] for more than one
    /// directional light, or a pipeline error.
    pub fn new(
        ctx: GpuContext,
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Self, GpuError> {
        renderable_sampler(scene, &settings)?;
        let g = &scene.geometry;
        let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
        Self::with_bvh(ctx, scene, &bvh, camera, settings)
    }

    /// [`GpuRenderer::new`] with the scene's BVH already built (`Bvh::from_indexed` over its
    /// positions and triangles with the default options): several devices rendering one scene
    /// build it once ([`crate::MultiGpuRenderer`]).
    ///
    /// # Errors
    /// As [`GpuRenderer::new`]; [`GpuError::Unsupported`] if `bvh` is not a CWBVH built over the
    /// scene's triangles.
    pub fn with_bvh(
        ctx: GpuContext,
        scene: &Scene,
        bvh: &Bvh,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Self, GpuError> {
        let packed = PackedScene::new(scene, bvh, camera, settings, ctx.upload_limit())?;
        Self::with_packed(ctx, &packed)
    }

    /// [`GpuRenderer::with_bvh`] from the scene as packed on the host ([`PackedScene`]): several
    /// devices rendering one scene pack it once and each uploads the same words.
    ///
    /// # Errors
    /// A device error, or a pipeline error.
    pub(crate) fn with_packed(ctx: GpuContext, packed: &PackedScene) -> Result<Self, GpuError> {
        packed.check_limit(ctx.upload_limit())?;
        let PackedScene { settings, sampler, base, features, bvh_depth, triangles, .. } = *packed;
        let [nodes, tris] = packed.bvh_words.extra();
        let bvh = [storage_buffer(&ctx, "bvh nodes", nodes)?, storage_buffer(&ctx, "bvh triangles", tris)?];
        let bvh_bytes = bvh.iter().map(wgpu::Buffer::size).sum();
        let gpu_scene = GpuScene::upload_buffers(&ctx, &packed.scene_words)?;
        let ray_counter = ctx.buffer_init(
            "ray counter",
            bytemuck::cast_slice(&[0u32; COUNTER_WORDS]),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let turquin = storage_buffer(&ctx, "turquin", bytemuck::cast_slice(&brdf::turquin_table()))?;
        let point_lights = storage_buffer(&ctx, "point lights", bytemuck::cast_slice(&packed.point_lights))?;
        let emitters =
            packed.emitter_words.as_ref().map(|w| storage_buffer(&ctx, "emitters", w)).transpose()?;
        let environment = packed
            .environment
            .iter()
            .map(|(label, w)| storage_buffer(&ctx, label, w))
            .collect::<Result<Vec<_>, _>>()?;
        let precision = FilmPrecision::for_context(&ctx);
        let film = film_for(&ctx, &settings, precision)?;
        let overrides = ProfilingOverrides::from_env()?;
        let group_size = group_size_for(&ctx, &overrides, features);
        let limit = ctx.device.limits().max_compute_invocations_per_workgroup;
        if group_size > limit {
            return Err(GpuError::Unsupported(format!(
                "FURNACE_GROUP_SIZE={group_size}: the adapter's workgroups hold at most {limit} invocations"
            )));
        }
        let stack_size = overrides.stack_size(bvh_depth);
        let (layout, pipeline, converge) =
            integrator_pipeline(&ctx, precision, features, &overrides, group_size, stack_size)?;
        let converged_counter = converged_counter(&ctx, &settings)?;
        // Software adapters (lavapipe) run ~1 Msample/s and end any shader loop after 65535
        // iterations per invocation (all loops together): one sample per invocation there.
        let software = !crate::context::is_hardware(&ctx.info);
        let (samples_per_dispatch, max_samples_per_invocation) =
            if software { (1 << 16, 1) } else { (1 << 23, 8) };
        let mut renderer = Self {
            bytes_per_triangle: gpu_scene.bytes_per_triangle(),
            bvh_bytes,
            scene_bytes: gpu_scene.bytes
                + emitters.as_ref().map_or(0, wgpu::Buffer::size)
                + environment.iter().map(wgpu::Buffer::size).sum::<u64>(),
            ray_counter,
            ctx,
            settings,
            sampler,
            base,
            pipeline,
            converge,
            converged: settings.adaptive.map(|_| 0),
            converged_counter,
            layout,
            film,
            scene: gpu_scene,
            bvh,
            turquin,
            point_lights,
            emitters,
            environment,
            features,
            samples_per_dispatch,
            max_samples_per_invocation,
            group_samples: None,
            convergence_tests: true,
            tuner: None,
            group_size,
            stack_size,
            timer: None,
            triangles,
            display: false,
            cancel: None,
            last_pass_seconds: 0.0,
            dispatch_shift: initial_dispatch_shift(settings.bounces),
            pass_backup: Vec::new(),
        };
        renderer.tuner = renderer.tuner_for();
        Ok(renderer)
    }

    /// The device.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The film on the device (for a display: [`crate::present::FilmPresenter`]).
    pub fn gpu_film(&self) -> &GpuFilm {
        &self.film
    }

    /// Makes the film drawable by [`crate::present::FilmPresenter`] (see
    /// [`GpuFilm::enable_display`]); it stays so across [`GpuRenderer::reconfigure`].
    ///
    /// # Errors
    /// A device error.
    pub fn enable_display(&mut self) -> Result<(), GpuError> {
        self.display = true;
        self.film.enable_display(&self.ctx)
    }

    /// Looks through `camera` from the next pass on. The film is not cleared: call
    /// [`GpuRenderer::clear_film`] when the samples so far were of another view.
    pub fn set_camera(&mut self, camera: &Camera) {
        set_camera_params(&mut self.base, camera);
    }

    /// Zeroes the film (a new accumulation, from sample index 0).
    ///
    /// # Errors
    /// A device error.
    pub fn clear_film(&mut self) -> Result<(), GpuError> {
        self.film.clear(&self.ctx)
    }

    /// Renders `scene` (the one it was made with, or the same geometry with other lights'
    /// intensities, as a viewer's environment slider makes) with new `settings` through `camera`,
    /// keeping the uploaded geometry, materials and BVH: the sampler, the uniform block, the
    /// emitters' and environment's buffers and the pipeline are rebuilt as the settings need, the
    /// film is cleared (remade at a new size). A viewer calls it for each change of settings.
    ///
    /// # Errors
    /// As [`GpuRenderer::new`], and [`GpuError::Unsupported`] for a scene whose triangle count
    /// differs from the uploaded one.
    pub fn reconfigure(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<(), GpuError> {
        if scene.geometry.triangles.len() != self.triangles {
            return Err(GpuError::Unsupported(format!(
                "reconfigure with a scene of {} triangles, the renderer holds {}: make a new renderer",
                scene.geometry.triangles.len(),
                self.triangles
            )));
        }
        let sampler = AnySampler::new(settings.sampler, settings.seed, settings.sample_count)?;
        let sampler_params = SamplerParams::new(settings.sampler, settings.seed, settings.sample_count)?;
        let scene_emitters = Emitters::new(scene);
        let features = SceneFeatures {
            trace_counters: self.features.trace_counters,
            ..SceneFeatures::with_emitters(scene, &settings, scene_emitters.is_some())
        };
        let old = self.settings;
        if features.light_bvh != self.features.light_bvh || features.emitters != self.features.emitters {
            self.emitters = emitter_buffer(&self.ctx, scene, scene_emitters.as_ref(), features)?;
        }
        let env_samples = |s: &RenderSettings| s.env_sampling.light_samples(s.light_sampling);
        if env_samples(&old) != env_samples(&settings) || features.environment != self.features.environment {
            self.environment = environment_buffers(&self.ctx, scene, &settings, self.ctx.upload_limit())?;
        }
        let precision = self.film.precision();
        if features != self.features {
            self.rebuild_pipeline(features)?;
        }
        if settings.adaptive.is_some() != old.adaptive.is_some() {
            self.converged_counter = converged_counter(&self.ctx, &settings)?;
        }
        self.converged = settings.adaptive.map(|_| 0);
        self.write_converged_counter(0)?;
        if (settings.width, settings.height, settings.aovs, settings.adaptive.is_some())
            != (old.width, old.height, old.aovs, old.adaptive.is_some())
        {
            self.film = film_for(&self.ctx, &settings, precision)?;
            if self.display {
                self.film.enable_display(&self.ctx)?;
            }
        } else {
            self.film.clear(&self.ctx)?;
        }
        self.base = frame_params_with(scene, camera, &settings, sampler_params, scene_emitters.as_ref());
        self.sampler = sampler;
        self.settings = settings;
        // Another scene or size: the invocations per pixel are chosen again.
        self.tuner = self.tuner_for();
        Ok(())
    }

    /// The settings it renders with.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Scene bytes on the GPU per triangle (geometry, BVH excluded).
    pub fn bytes_per_triangle(&self) -> f64 {
        self.bytes_per_triangle
    }

    /// Bytes of the BVH on the GPU (nodes and triangle references).
    pub fn bvh_bytes(&self) -> u64 {
        self.bvh_bytes
    }

    /// Node groups the traversal stack holds: as many as the uploaded tree has levels below its
    /// root, at most [`crate::traverse::DEFAULT_STACK_SIZE`] ([`crate::traverse::stack_size_for`];
    /// `FURNACE_TRV_STACK` overrides it).
    pub fn traversal_stack_size(&self) -> u32 {
        self.stack_size
    }

    /// Invocations per workgroup of the integrator ([`group_size_for`]).
    pub fn group_size(&self) -> u32 {
        self.group_size
    }

    /// Bytes of the scene buffers on the GPU (geometry, materials, textures; BVH excluded).
    pub fn scene_bytes(&self) -> u64 {
        self.scene_bytes
    }

    /// Whether the passes that follow count what they trace ([`GpuRenderer::take_trace_counts`];
    /// off by default). Counting runs a kernel of its own, built here when the choice changes
    /// (the counters cost the H200 1.5–3 % of throughput, so the rendering kernel has none).
    ///
    /// # Errors
    /// A pipeline error.
    pub fn set_count_rays(&mut self, on: bool) -> Result<(), GpuError> {
        if on != self.features.trace_counters {
            self.rebuild_pipeline(SceneFeatures { trace_counters: on, ..self.features })?;
        }
        Ok(())
    }

    /// Builds the integrator's pipeline for `features` (and the workgroup size they get: AOVs'
    /// arrays need a smaller one) and keeps them.
    fn rebuild_pipeline(&mut self, features: SceneFeatures) -> Result<(), GpuError> {
        let overrides = ProfilingOverrides::from_env()?;
        let group_size = group_size_for(&self.ctx, &overrides, features);
        (self.layout, self.pipeline, self.converge) = integrator_pipeline(
            &self.ctx,
            self.film.precision(),
            features,
            &overrides,
            group_size,
            self.stack_size,
        )?;
        self.group_size = group_size;
        self.features = features;
        Ok(())
    }

    /// The rays (closest-hit and shadow) traced by the counting passes since the last call, which
    /// resets the counter.
    ///
    /// # Errors
    /// A device error while reading the counter back.
    pub fn take_ray_count(&mut self) -> Result<u64, GpuError> {
        Ok(self.take_trace_counts()?.rays)
    }

    /// All the traversal counters of the counting passes since the last call, which resets
    /// them: rays, BVH nodes and triangles tested (divide by `rays` for steps per ray), fallback
    /// sweeps, deepest stack.
    ///
    /// # Errors
    /// A device error while reading the counters back.
    pub fn take_trace_counts(&mut self) -> Result<TraceCounts, GpuError> {
        let w = crate::film::read_buffer(&self.ctx, &self.ray_counter)?;
        self.ctx.queue.write_buffer(&self.ray_counter, 0, bytemuck::cast_slice(&[0u32; COUNTER_WORDS]));
        self.ctx.queue.submit([]);
        self.ctx.wait()?;
        let pair = |k: usize| u64::from(w[k]) | (u64::from(w[k + 1]) << 32);
        Ok(TraceCounts {
            rays: pair(0),
            nodes: pair(2),
            triangles: pair(4),
            fallbacks: w[6],
            max_stack_depth: w[7],
        })
    }

    /// Invocations per pixel in a workgroup: `None` (the default) chooses — on hardware, up to
    /// 16 by image size ([`hardware_group_samples`]) or 1, whichever its first passes ran faster
    /// ([`GroupTuner`]; by image size alone with adaptive sampling), 1 on software adapters;
    /// `Some(n)` forces `n` (rounded down to a power of two that divides the workgroup size). The film
    /// does not depend on it, bit for bit.
    pub fn set_group_samples(&mut self, n: Option<u32>) {
        self.group_samples =
            n.map(|n| 1 << n.clamp(1, self.group_size).ilog2().min(self.group_size.trailing_zeros()));
        self.tuner = self.tuner_for();
    }

    /// The timing choice between the image-size rule and one invocation per pixel
    /// ([`GroupTuner`]): on hardware adapters, where [`GpuRenderer::set_group_samples`] has not
    /// fixed it, without adaptive sampling (whose passes are cut into blocks at its test
    /// points), and on images large enough that the rule chose fewer than
    /// [`HARDWARE_GROUP_SAMPLES`] (more than 1): a smaller image at one invocation per pixel
    /// leaves most of the GPU idle (the box at 256² ran at half speed on the H100), and its
    /// passes are short enough for the host's part of a pass to blur the timing.
    fn tuner_for(&self) -> Option<GroupTuner> {
        let software = self.max_samples_per_invocation == 1;
        if software || self.group_samples.is_some() || self.settings.adaptive.is_some() {
            return None;
        }
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        let rule = hardware_group_samples(pixels, self.samples_per_dispatch);
        if rule >= HARDWARE_GROUP_SAMPLES {
            return None;
        }
        GroupTuner::new(rule)
    }

    /// The timing choice of invocations per pixel, where the renderer makes one: the candidate
    /// the next pass tries, or the one chosen.
    pub fn group_tuner(&self) -> Option<&GroupTuner> {
        self.tuner.as_ref()
    }

    /// The invocations per pixel the next pass of `samples_per_pixel` samples uses.
    pub fn group_samples(&self, samples_per_pixel: u32) -> u32 {
        // Software adapters (lavapipe) run invocations on a few CPU threads: nothing to fill.
        let software = self.max_samples_per_invocation == 1;
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        let n = self.group_samples.unwrap_or(if software {
            1
        } else if let Some(t) = &self.tuner {
            t.next()
        } else {
            hardware_group_samples(pixels, self.samples_per_dispatch)
        });
        // More invocations than samples would idle.
        let cap = samples_per_pixel.max(1);
        if n > cap { 1 << cap.ilog2() } else { n }
    }

    /// Whether passes record GPU timestamps (where the adapter has `TIMESTAMP_QUERY`): then
    /// [`GpuRenderer::last_pass_gpu_seconds`] gives each pass's time on the GPU. Returns whether
    /// timing is on.
    pub fn set_timing(&mut self, on: bool) -> bool {
        if !on || !self.ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            self.timer = None;
            return false;
        }
        if self.timer.is_none() {
            let d = &self.ctx.device;
            self.timer = Some(Timer {
                queries: d.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                }),
                resolve: d.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamps"),
                    size: 16,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                period_ns: self.ctx.queue.get_timestamp_period(),
                last: None,
            });
        }
        true
    }

    /// The GPU time of the last pass's compute work, from its timestamps (timing on).
    pub fn last_pass_gpu_seconds(&self) -> Option<f64> {
        self.timer.as_ref().and_then(|t| t.last)
    }

    /// About how many samples one dispatch computes (the watchdog bound).
    pub fn samples_per_dispatch(&self) -> u64 {
        self.samples_per_dispatch
    }

    /// How the film sums.
    pub fn film_precision(&self) -> FilmPrecision {
        self.film.precision()
    }

    /// The dispatches of a pass; each covers whole tiles of `tile_height` rows (the shader
    /// checks a pixel against the image, not against its dispatch's rows, so a dispatch must not
    /// end inside a tile).
    fn dispatches(&self, first: u32, n: u32, group_samples: u32, tile_height: u32) -> Vec<Dispatch> {
        let (w, h) = (self.settings.width.max(1), self.settings.height.max(1));
        // Samples per pixel in one dispatch: a loop of up to max_samples_per_invocation, or one
        // per invocation of a group.
        let per_invocation = if group_samples > 1 {
            group_samples.min(n)
        } else {
            n.min(self.max_samples_per_invocation).max(1)
        };
        // At least one row, at most the image (an image shorter than a tile is one dispatch: the
        // `clamp(8, h)` here before panicked for images under 8 rows), whole tiles.
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

    /// Samples per dispatch now: [`GpuRenderer::samples_per_dispatch`] halved `dispatch_shift`
    /// times, so that a dispatch of long paths stays short enough for a cancel flag to be
    /// answered within a second ([`GpuRenderer::fit_dispatches`]).
    fn dispatch_samples(&self) -> u64 {
        (self.samples_per_dispatch >> self.dispatch_shift).max(1)
    }

    /// After a pass whose dispatches took `seconds` each (the longest, or the mean): halves the
    /// dispatches until one would take about a tenth of a second when one took more than
    /// [`LONG_DISPATCH_SECONDS`], doubles them back (up to
    /// [`GpuRenderer::samples_per_dispatch`]) when one took under a twentieth. Films do not
    /// depend on where dispatches are cut.
    fn fit_dispatches(&mut self, seconds: f64) {
        let max_shift = 63 - self.samples_per_dispatch.leading_zeros();
        if seconds > LONG_DISPATCH_SECONDS {
            let halvings = (seconds / 0.1).log2().ceil().max(1.0) as u32;
            self.dispatch_shift = (self.dispatch_shift + halvings).min(max_shift);
        } else if seconds < 0.05 && self.dispatch_shift > 0 {
            self.dispatch_shift -= 1;
        }
    }

    /// Adds samples `first_sample .. first_sample + samples_per_pixel` of every pixel to the film
    /// (then folds an `F32Pass` film). Errors as the CPU's for a fixed-N sampler run past N, and
    /// on any device error (validation, out of memory, device lost).
    pub fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), GpuError> {
        if samples_per_pixel == 0 || self.settings.width == 0 || self.settings.height == 0 {
            return Ok(());
        }
        self.sampler.check_index(first_sample.saturating_add(samples_per_pixel - 1))?;
        let end = first_sample.saturating_add(samples_per_pixel);
        let Some(rule) = self.settings.adaptive else {
            let group_samples = self.group_samples(samples_per_pixel);
            let start = std::time::Instant::now();
            self.render_blocks(&[Block { first: first_sample, end, converge: false }])?;
            if let Some(t) = &mut self.tuner {
                t.record(group_samples, samples_per_pixel, start.elapsed().as_secs_f64());
            }
            return self.film.fold(&self.ctx);
        };
        // Adaptive sampling tests pixels at multiples of ADAPTIVE_STEP: blocks that end there,
        // each followed by the test where it applies.
        let mut blocks = Vec::new();
        let mut block = first_sample;
        while block < end {
            let block_end = (block / ADAPTIVE_STEP + 1).saturating_mul(ADAPTIVE_STEP).min(end);
            let converge = self.convergence_tests && rule.tests_at(block_end);
            blocks.push(Block { first: block, end: block_end, converge });
            block = block_end;
        }
        if self.converge.is_some() {
            // An f64 film: every block and test in one submission, the count read once.
            self.render_blocks(&blocks)?;
            if blocks.iter().any(|b| b.converge) {
                self.converged = Some(self.read_converged_counter()?);
            }
            return Ok(());
        }
        // An F32Pass film: each block folded on the host and tested there.
        let mut total = Some(0.0);
        for b in &blocks {
            let seconds = self.render_blocks(&[Block { converge: false, ..*b }]).map_err(|e| match e {
                GpuError::Interrupted { .. } => GpuError::Interrupted { samples: b.first - first_sample },
                e => e,
            })?;
            total = total.zip(seconds).map(|(a, b)| a + b);
            self.film.fold(&self.ctx)?;
            if b.converge {
                self.converged = self.film.test_convergence_on_host(&self.ctx, &rule)?;
            }
        }
        if let Some(t) = &mut self.timer {
            t.last = total;
        }
        Ok(())
    }

    /// With adaptive sampling: whether passes run its test at its test points (the default), or
    /// only skip the pixels already marked converged — for a caller that tests the film
    /// itself, as [`crate::MultiGpuRenderer`] tests the sum of its devices' films, then marks
    /// them with [`GpuRenderer::set_converged`].
    pub fn set_convergence_tests(&mut self, on: bool) {
        self.convergence_tests = on;
    }

    /// With adaptive sampling: replaces the film's convergence marks (one per pixel, row-major;
    /// marked pixels take no more samples), leaving its sums as they are; nothing without it.
    ///
    /// # Errors
    /// As [`GpuFilm::set_marks`]: `marks` must hold one mark per pixel.
    pub fn set_converged(&mut self, marks: &[bool]) -> Result<(), GpuError> {
        if self.settings.adaptive.is_none() {
            return Ok(());
        }
        self.film.set_marks(&self.ctx, marks)?;
        let n = marks.iter().filter(|&&m| m).count() as u64;
        self.converged = Some(n);
        self.write_converged_counter(n)
    }

    /// The GPU's count of converged pixels (kept by the `converge` kernel).
    fn read_converged_counter(&self) -> Result<u64, GpuError> {
        let Some(counter) = &self.converged_counter else { return Ok(0) };
        Ok(u64::from(crate::film::read_buffer(&self.ctx, counter)?[0]))
    }

    /// Sets the GPU's count of converged pixels (after a film was loaded or cleared).
    fn write_converged_counter(&self, n: u64) -> Result<(), GpuError> {
        if let Some(counter) = &self.converged_counter {
            let n = u32::try_from(n).map_err(|_| GpuError::Wgpu(format!("{n} converged pixels")))?;
            self.ctx.queue.write_buffer(counter, 0, bytemuck::cast_slice(&[n, 0, 0, 0]));
            self.ctx.queue.submit([]);
            self.ctx.wait()?;
        }
        Ok(())
    }

    /// Records one step of a pass into `pass`.
    fn record_step(&self, pass: &mut wgpu::ComputePass<'_>, step: Step, bind: &wgpu::BindGroup) {
        match step {
            Step::Samples { slot, groups_y, tile_width } => {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, bind, &[(slot as u64 * SLOT) as u32]);
                pass.dispatch_workgroups(self.settings.width.div_ceil(tile_width), groups_y, 1);
            }
            Step::Converge => {
                let Some(pipeline) = &self.converge else { return };
                // After the block's samples (wgpu orders the dispatches' storage accesses):
                // every pixel not yet converged tested once, the newly converged counted.
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind, &[0]);
                let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
                let groups = pixels.div_ceil(u64::from(self.group_size));
                let x = groups.clamp(1, 65_535) as u32;
                pass.dispatch_workgroups(x, groups.div_ceil(u64::from(x)).max(1) as u32, 1);
            }
        }
    }

    /// Submits `steps` one submission each, polling the cancel flag after each: raised before
    /// the last, the film is given back as it was before the pass (`F64`: from copies taken
    /// first; `F32Pass`: its pass buffers cleared) and [`GpuError::Interrupted`] returned.
    /// Returns the longest dispatch of samples, in seconds.
    fn submit_steps_one_by_one(&mut self, steps: &[Step], bind: &wgpu::BindGroup) -> Result<f64, GpuError> {
        let mut state = self.film.pass_state();
        state.extend(&self.converged_counter);
        if self.pass_backup.len() != state.len() {
            self.pass_backup = state
                .iter()
                .map(|b| {
                    self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("pass backup"),
                        size: b.size(),
                        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    })
                })
                .collect();
        }
        let copy = |from: &[&wgpu::Buffer], to: &[&wgpu::Buffer]| {
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            for (a, b) in from.iter().zip(to) {
                encoder.copy_buffer_to_buffer(a, 0, b, 0, a.size());
            }
            encoder.finish()
        };
        let backup: Vec<&wgpu::Buffer> = self.pass_backup.iter().collect();
        if !state.is_empty() {
            self.ctx.queue.submit([copy(&state, &backup)]);
        }
        let cancel = self.cancel.clone().unwrap_or_default();
        let mut longest = 0.0f64;
        for (k, step) in steps.iter().enumerate() {
            let started = std::time::Instant::now();
            let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("integrator"),
                    timestamp_writes: None,
                });
                self.record_step(&mut pass, *step, bind);
            }
            self.ctx.queue.submit([encoder.finish()]);
            self.ctx.wait()?;
            if matches!(step, Step::Samples { .. }) {
                longest = longest.max(started.elapsed().as_secs_f64());
            }
            if cancel.is_raised() && k + 1 < steps.len() {
                if !state.is_empty() {
                    self.ctx.queue.submit([copy(&backup, &state)]);
                    self.ctx.wait()?;
                }
                self.film.drop_pass(&self.ctx)?;
                self.fit_dispatches(longest);
                return Err(GpuError::Interrupted { samples: 0 });
            }
        }
        Ok(longest)
    }

    /// Renders `blocks` in order in one compute pass and one submission: each block's samples
    /// of every pixel still taking samples, then (with `converge`) the GPU's adaptive-sampling
    /// test; returns the device seconds when timing.
    fn render_blocks(&mut self, blocks: &[Block]) -> Result<Option<f64>, GpuError> {
        let mut slots: Vec<FrameParams> = Vec::new();
        // Per block: its dispatches (slot, rows), its grouping, whether the test follows.
        let mut plan = Vec::new();
        for b in blocks {
            let group_samples = self.group_samples(b.end - b.first);
            let (tile_width, tile_height) = tile_of(self.group_size, group_samples);
            let dispatches = self.dispatches(b.first, b.end - b.first, group_samples, tile_height);
            let mut list = Vec::new();
            for d in &dispatches {
                list.push((slots.len(), d.rows.div_ceil(tile_height)));
                slots.push(FrameParams {
                    first_sample: d.first_sample,
                    samples: d.samples,
                    row_offset: d.row_offset,
                    group_samples,
                    tile_width,
                    ..self.base
                });
            }
            plan.push((list, tile_width, b.converge));
        }
        let mut bytes = vec![0u8; slots.len().max(1) * SLOT as usize];
        for (k, p) in slots.iter().enumerate() {
            bytes[k * SLOT as usize..][..size_of::<FrameParams>()].copy_from_slice(bytemuck::bytes_of(p));
        }
        let device = &self.ctx.device;
        let params = self.ctx.buffer_init("frame params", &bytes, wgpu::BufferUsages::UNIFORM)?;
        let mut resources = vec![wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &params,
            offset: 0,
            size: wgpu::BufferSize::new(size_of::<FrameParams>() as u64),
        })];
        resources.extend(self.film.resources());
        resources.extend(self.bvh.iter().map(wgpu::Buffer::as_entire_binding));
        resources.extend(self.scene.resources());
        resources.push(self.turquin.as_entire_binding());
        resources.push(self.point_lights.as_entire_binding());
        if let Some(t) = &self.scene.transmission {
            resources.push(t.as_entire_binding());
        }
        if let Some(e) = &self.emitters {
            resources.push(e.as_entire_binding());
        }
        resources.extend(self.environment.iter().map(wgpu::Buffer::as_entire_binding));
        resources.push(self.ray_counter.as_entire_binding());
        if let Some(aov) = &self.film.aov {
            resources.push(aov.as_entire_binding());
        }
        if let (Some(marks), Some(counter)) = (&self.film.converged, &self.converged_counter) {
            resources.push(marks.as_entire_binding());
            resources.push(counter.as_entire_binding());
        }
        let entries = binding_table(self.film.precision(), self.features).bind_entries(resources);
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("integrator"),
            layout: &self.layout,
            entries: &entries,
        });
        let steps: Vec<Step> = plan
            .iter()
            .flat_map(|(list, tile_width, converge)| {
                let samples = list.iter().map(|&(slot, groups_y)| Step::Samples {
                    slot,
                    groups_y,
                    tile_width: *tile_width,
                });
                samples.chain((*converge && self.converge.is_some()).then_some(Step::Converge))
            })
            .collect();
        // A pass after a long one is split where a cancel flag may stop it, and so is the first
        // when its paths may be long (its dispatches start halved).
        let split = self.cancel.is_some()
            && steps.len() > 1
            && (self.last_pass_seconds > LONG_PASS_SECONDS
                || (self.last_pass_seconds == 0.0 && self.dispatch_shift > 0));
        let started = std::time::Instant::now();
        let sample_steps = steps.iter().filter(|s| matches!(s, Step::Samples { .. })).count().max(1);
        let longest = if split {
            Some(self.submit_steps_one_by_one(&steps, &bind)?)
        } else {
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let timestamp_writes = self.timer.as_ref().map(|t| wgpu::ComputePassTimestampWrites {
                    query_set: &t.queries,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                });
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("integrator"),
                    timestamp_writes,
                });
                for step in &steps {
                    self.record_step(&mut pass, *step, &bind);
                }
            }
            if let Some(t) = &self.timer {
                encoder.resolve_query_set(&t.queries, 0..2, &t.resolve, 0);
            }
            self.ctx.queue.submit([encoder.finish()]);
            self.ctx.wait()?;
            None
        };
        self.last_pass_seconds = started.elapsed().as_secs_f64().max(f64::MIN_POSITIVE);
        self.fit_dispatches(longest.unwrap_or(self.last_pass_seconds / sample_steps as f64));
        if let Some(t) = &mut self.timer {
            t.last = if split {
                None
            } else {
                let w = crate::film::read_buffer(&self.ctx, &t.resolve)?;
                let (begin, end) =
                    (u64::from(w[0]) | u64::from(w[1]) << 32, u64::from(w[2]) | u64::from(w[3]) << 32);
                Some(end.wrapping_sub(begin) as f64 * f64::from(t.period_ns) * 1e-9)
            };
        }
        Ok(self.timer.as_ref().and_then(|t| t.last))
    }

    /// The film so far (sums in `f64`, counts, rejected samples), read back.
    pub fn film(&self) -> Result<Film, GpuError> {
        self.film.read(&self.ctx)
    }

    /// Replaces the film (to resume a saved render, or with an empty film to start again).
    pub fn load_film(&mut self, data: &Film) -> Result<(), GpuError> {
        self.film.write(&self.ctx, data)?;
        self.converged = data.converged_count();
        self.write_converged_counter(self.converged.unwrap_or(0))
    }
}

impl Integrator for GpuRenderer {
    fn name(&self) -> &'static str {
        "gpu"
    }

    fn describe(&self) -> String {
        format!("gpu: {}", self.ctx.describe())
    }

    fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError> {
        Ok(GpuRenderer::render_pass(self, first_sample, samples_per_pixel)?)
    }

    fn film(&mut self) -> Result<Film, RenderError> {
        Ok(GpuRenderer::film(self)?)
    }

    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        Ok(self.load_film(film)?)
    }

    /// About 2²⁴ samples per pass on hardware (tens of milliseconds on a large GPU), 2¹⁶ on a
    /// software adapter; 1 to 64 samples per pixel.
    fn pass_samples(&self) -> u32 {
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        let target: u64 = if crate::context::is_hardware(&self.ctx.info) { 1 << 24 } else { 1 << 16 };
        (target / pixels.max(1)).clamp(1, 64) as u32
    }

    fn last_pass_device_seconds(&self) -> Option<f64> {
        self.last_pass_gpu_seconds()
    }

    fn converged_pixels(&self) -> Option<u64> {
        self.converged
    }

    /// Polled between dispatches of a long pass (one after a pass longer than a quarter of a
    /// second, and the first of paths of more than 16 bounces): such a pass is submitted
    /// dispatch by dispatch, so that it stops within one dispatch's time.
    fn set_cancel_flag(&mut self, flag: CancelFlag) {
        self.cancel = Some(flag);
    }
}

/// The per-render part of the uniform block.
pub fn frame_params(
    scene: &Scene,
    camera: &Camera,
    s: &RenderSettings,
    sampler: SamplerParams,
) -> FrameParams {
    frame_params_with(scene, camera, s, sampler, Emitters::new(scene).as_ref())
}

/// [`frame_params`] with the scene's emitters already built.
fn frame_params_with(
    scene: &Scene,
    camera: &Camera,
    s: &RenderSettings,
    sampler: SamplerParams,
    emitters: Option<&Emitters>,
) -> FrameParams {
    let any_masked = scene.materials.iter().any(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. }));
    let mut flags = 0;
    if s.russian_roulette {
        flags |= FRAME_RUSSIAN_ROULETTE;
    }
    if any_masked {
        flags |= FRAME_ANY_MASKED;
    }
    flags |= match s.light_sampling {
        LightSampling::Bsdf => FRAME_NO_LIGHT_SAMPLES,
        LightSampling::Nee => FRAME_NO_BSDF_LIGHT,
        LightSampling::Mis => 0,
    };
    let (sun_direction, sun_irradiance) = match scene.sun() {
        Some(sun) => {
            flags |= FRAME_HAS_SUN;
            let (t, k) = (sun.one_minus_cos(), sun.radiance_scale());
            (sun.direction.extend(t).to_array(), sun.irradiance.extend(k).to_array())
        }
        None => ([0.0; 4], [0.0; 4]),
    };
    let env = scene.environment();
    let rotation = env.map_or(furnace_scene::YRotation::IDENTITY, |e| e.y_rotation());
    let mut p = FrameParams {
        cam_x: [0.0; 4],
        cam_y: [0.0; 4],
        cam_z: [0.0; 4],
        cam_t: [0.0; 4],
        sun_direction,
        sun_irradiance,
        sky: scene.sky().extend(0.0).to_array(),
        sampler,
        width: s.width,
        height: s.height,
        first_sample: 0,
        samples: 0,
        bounces: s.bounces,
        flags,
        bsdf_flags: brdf::options_flags(s.specular),
        row_offset: 0,
        fov_scale: 1.0,
        aspect: 1.0,
        group_samples: 1,
        tile_width: 8,
        offset_scale: {
            let (lo, hi) = scene.geometry.bounds();
            offset_scale_of_bounds(lo, hi)
        },
        point_light_count: scene.point_lights().count() as u32,
        emitter_count: emitters.map_or(0, |e| e.len() as u32),
        emitter_total: emitters.map_or(0.0, Emitters::total_weight),
        env_width: env.map_or(0, |e| e.map.width()),
        env_height: env.map_or(0, |e| e.map.height()),
        env_intensity: env.map_or(0.0, |e| e.intensity),
        env_cos: rotation.cos,
        env_sin: rotation.sin,
        env_flags: if env.is_some_and(|e| e.visible) { ENV_VISIBLE } else { 0 },
        sample_clamp: s.clamp.unwrap_or(0.0),
        noise_threshold: s.adaptive.map_or(0.0, |a| a.threshold),
    };
    set_camera_params(&mut p, camera);
    p
}

/// Writes `camera` (pose, projection) into the uniform block of an image of `p.width × p.height`.
fn set_camera_params(p: &mut FrameParams, camera: &Camera) {
    let m = camera.world_from_camera;
    let v4 = |v: glam::Vec3A| [v.x, v.y, v.z, 0.0];
    let (fov_scale, ortho) = match camera.projection {
        Projection::Perspective { yfov, .. } => ((yfov * 0.5).tan(), 0),
        Projection::Orthographic { ymag, .. } => (ymag, FRAME_ORTHOGRAPHIC),
    };
    p.cam_x = v4(m.matrix3.x_axis);
    p.cam_y = v4(m.matrix3.y_axis);
    p.cam_z = v4(m.matrix3.z_axis);
    p.cam_t = v4(m.translation);
    p.fov_scale = fov_scale;
    p.aspect = p.width.max(1) as f32 / p.height.max(1) as f32;
    p.flags = (p.flags & !FRAME_ORTHOGRAPHIC) | ortho;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_paths_start_with_smaller_dispatches() {
        let shifts: Vec<u32> = [0, 4, 16, 17, 33, 34, 1024].map(initial_dispatch_shift).to_vec();
        assert_eq!(shifts, [0, 0, 0, 1, 1, 2, 6]);
    }

    /// A scene packed for one device's limit is checked again against another's: the first
    /// buffer over it is named, and a limit it fits passes.
    #[test]
    fn a_packed_scene_is_checked_against_each_devices_limit() {
        let scene = furnace_scene::builtin::cornell_box().unwrap();
        let g = &scene.geometry;
        let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
        let settings = RenderSettings { width: 8, height: 8, ..RenderSettings::default() };
        let packed = PackedScene::new(&scene, &bvh, &scene.default_camera(), settings, u64::MAX).unwrap();
        let nodes = 4 * packed.bvh_words.nodes.len() as u64;
        let largest = [nodes, 4 * packed.bvh_words.triangles.len() as u64]
            .into_iter()
            .chain(packed.scene_words.extra().iter().map(|w| 4 * w.len() as u64))
            .max()
            .unwrap();
        assert!(packed.check_limit(largest).is_ok());
        match packed.check_limit(nodes - 1) {
            Err(GpuError::TooLarge { what, bytes, limit }) => {
                assert_eq!((what.as_str(), bytes, limit), ("the BVH node buffer", nodes, nodes - 1));
            }
            other => panic!("expected TooLarge, got {other:?}"),
        }
    }

    /// 16 per pixel while a whole-image dispatch stays within the budget, then halves: the
    /// sizes measured on the H200 (BENCHMARKS.md, "Speed").
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

    /// The stack override decides the traversal's stack size; no override leaves the shader as
    /// composed. The trace counters are composed only into the counting kernel.
    #[test]
    fn profiling_overrides_rewrite_the_shader() {
        let source = shader_source(FilmPrecision::F64, SceneFeatures::default());
        assert_eq!(ProfilingOverrides::default().apply(source.clone()).unwrap(), source);
        let stack = crate::traverse::with_stack_size(&source, 8);
        assert!(
            stack.contains("const TRV_STACK_SIZE: u32 = 8u;") && !stack.contains("TRV_STACK_SIZE: u32 = 16u")
        );
        assert_eq!(ProfilingOverrides { stack: Some(8), ..Default::default() }.stack_size(3), 8);
        assert_eq!(ProfilingOverrides::default().stack_size(3), 2);
        let counting =
            shader_source(FilmPrecision::F64, SceneFeatures { trace_counters: true, ..Default::default() });
        for update in [
            "trace_stats.nodes += 1u;",
            "trace_stats.triangles += 1u;",
            "trace_stats.fallbacks += 1u;",
            "trace_stats.max_depth = max(trace_stats.max_depth, depth);",
            "rays_traced += ",
            "counter_add(0u, rays_traced);",
        ] {
            assert!(counting.contains(update) && !source.contains(update), "{update}");
        }
        let wide = with_group_size(&source, 1024);
        assert!(wide.contains("const GROUP_SIZE: u32 = 1024u;") && !wide.contains("GROUP_SIZE: u32 = 256u"));
        assert_eq!(tile_of(1024, 4), (16, 16));
        // What `group_size_for` weighs against half of a device's workgroup memory (48 KiB on
        // NVIDIA's Vulkan driver): the kernel's arrays at 1024 fit without AOVs, not with them.
        let aovs = SceneFeatures { aovs: true, ..Default::default() };
        assert_eq!(workgroup_bytes(HARDWARE_GROUP_SIZE, SceneFeatures::default()), 16 * 1024);
        assert_eq!(workgroup_bytes(HARDWARE_GROUP_SIZE, aovs), 48 * 1024);
        assert_eq!(workgroup_bytes(GROUP_SIZE, aovs), 12 * 1024);
        let plain = SceneFeatures::default();
        assert_eq!(default_group_size(true, 1024, 48 * 1024, plain), HARDWARE_GROUP_SIZE);
        assert_eq!(default_group_size(true, 1024, 48 * 1024, aovs), GROUP_SIZE);
        assert_eq!(default_group_size(true, 256, 48 * 1024, plain), GROUP_SIZE);
        assert_eq!(default_group_size(false, 1024, 48 * 1024, plain), GROUP_SIZE);
    }

    /// A shader-edit file's blocks replace their text in order; a text the shader lacks, a block
    /// without its `===` or `>>>` line, or a file without blocks is an error naming it.
    #[test]
    fn shader_edits_replace_text_or_say_why_not() {
        let source = shader_source(FilmPrecision::F64, SceneFeatures::default());
        let file = "<<<\nconst SHADOW_EPSILON: f32\n===\nconst SHADOW_EPSILON_X: f32\n>>>\n";
        let edits = parse_shader_edits("e.txt", file).unwrap();
        assert_eq!(
            edits,
            [("const SHADOW_EPSILON: f32".to_string(), "const SHADOW_EPSILON_X: f32".to_string())]
        );
        let edited = ProfilingOverrides { edits, ..Default::default() }.apply(source.clone()).unwrap();
        assert!(
            edited.contains("const SHADOW_EPSILON_X: f32") && !edited.contains("const SHADOW_EPSILON: f32")
        );
        let removal = parse_shader_edits("e.txt", "<<<\nconst SHADOW_EPSILON: f32\n===\n>>>\n").unwrap();
        assert_eq!(removal, [("const SHADOW_EPSILON: f32".to_string(), String::new())]);
        let missing = parse_shader_edits("e.txt", "<<<\nno such text\n===\nx\n>>>\n").unwrap();
        let err = ProfilingOverrides { edits: missing, ..Default::default() }.apply(source).unwrap_err();
        assert!(err.to_string().contains("block 1 does not occur"), "{err}");
        for (bad, why) in [
            ("<<<\nx\n>>>\n", "no `===` line"),
            ("<<<\nx\n===\ny\n", "no `>>>` line"),
            ("x", "no `<<<` block"),
        ] {
            let err = parse_shader_edits("e.txt", bad).unwrap_err().to_string();
            assert!(err.contains("e.txt") && err.contains(why), "{bad:?}: {err}");
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

    /// Loop counters are off by default; every choice keeps the other checks as documented.
    #[test]
    fn shader_checks() {
        assert_eq!(ShaderChecks::default(), ShaderChecks::NoLoopBounding);
        let c = ShaderChecks::NoLoopBounding.runtime_checks();
        assert!(!c.force_loop_bounding && c.bounds_checks && c.int_div_checks);
        let c = ShaderChecks::Checked.runtime_checks();
        assert!(c.force_loop_bounding && c.bounds_checks);
        assert!(!ShaderChecks::Unchecked.runtime_checks().bounds_checks);
    }
}
