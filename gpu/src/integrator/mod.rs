//! [`GpuRenderer`]: furnace-cpu's path tracer on the GPU.
//!
//! The shader is the concatenation of the twins — [`crate::wgsl::SAMPLING`], [`crate::wgsl::BRDF`],
//! [`crate::wgsl::SCENE`], [`crate::wgsl::TRAVERSE`], the film module — and the integrator's own WGSL
//! (`shadow.wgsl`, `lights.wgsl`, `integrator.wgsl`), a line-for-line twin of
//! `CpuRenderer::trace` (same sampler dimensions, same branches), so the GPU estimates the
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
//! each other (BENCHMARKS.md); one invocation per pixel runs a
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
//! ([`GpuRenderer::take_trace_counts`]); off — the default — no atomic runs (the counting
//! kernel is a variant of its own, so that rendering pays nothing for the counters).
//! [`GpuRenderer::set_timing`] records GPU timestamps around each pass where the adapter has
//! `TIMESTAMP_QUERY`.
//!
//! | module | what it holds |
//! |---|---|
//! | `frame` | [`FrameParams`], the uniform block of a dispatch, and [`frame_params`] |
//! | `packing` | the scene's buffers made on the host: [`GpuPointLight`], [`emitter_words`], [`light_bvh_words`], [`environment_words`], `PackedScene` |
//! | `kernel` | [`SceneFeatures`], [`shader_source`], [`binding_table`], the workgroup size ([`group_size_for`]), [`ShaderChecks`] and the pipelines |
//! | `dispatch` | blocks, dispatches, tiles ([`tile_of`]), invocations per pixel ([`hardware_group_samples`], [`GroupTuner`]) and the dispatches fitted to their measured time |
//! | `renderer` | [`GpuRenderer`]'s upload, reconfiguration and settings |
//! | `pass` | [`GpuRenderer::render_pass`]: the plan of a pass, its bind group, its submission and timing |

mod dispatch;
mod frame;
mod kernel;
mod packing;
mod pass;
mod renderer;

pub use dispatch::{GroupTuner, hardware_group_samples, tile, tile_of};
pub use frame::{
    ENV_VISIBLE, FRAME_ANY_MASKED, FRAME_HAS_SUN, FRAME_NO_BSDF_LIGHT, FRAME_NO_LIGHT_SAMPLES,
    FRAME_ORTHOGRAPHIC, FRAME_RUSSIAN_ROULETTE, FrameParams, env_flags_wgsl, frame_flags_wgsl, frame_params,
};
pub use kernel::{
    GROUP_SIZE, HARDWARE_GROUP_SIZE, MAX_QUEUED_POINT_LIGHTS, SceneFeatures, ShaderChecks, binding_table,
    default_group_size, group_size_for, pipeline_source, shader_source, with_group_size, workgroup_bytes,
};
pub use packing::{
    GpuPointLight, LIGHT_BVH_LEAF, LIGHT_BVH_NODE_WORDS, POINT_LIGHT_RANGE, POINT_LIGHT_SPOT, emitter_words,
    environment_words, light_bvh_consts_wgsl, light_bvh_words, point_light_flags_wgsl, point_light_records,
};
pub(crate) use packing::{PackedScene, renderable_sampler};

use crate::GpuContext;
use crate::film::GpuFilm;
use crate::scene::GpuScene;
use dispatch::DispatchSizing;
use furnace_render::{CancelFlag, Film, Integrator, RenderError, RenderSettings};
use furnace_sampling::AnySampler;
use kernel::Kernel;
use pass::Timer;

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
    /// The pipelines (and their workgroup size) for `features`.
    kernel: Kernel,
    /// Its count of converged pixels (and the number last read from it, or from the host's
    /// marks for an `F32Pass` film).
    converged_counter: Option<wgpu::Buffer>,
    converged: Option<u64>,
    film: GpuFilm,
    scene: GpuScene,
    /// The traversal's buffers: nodes and triangles, then (with instances) the TLAS and the
    /// instances.
    bvh: Vec<wgpu::Buffer>,
    turquin: wgpu::Buffer,
    point_lights: wgpu::Buffer,
    emitters: Option<wgpu::Buffer>,
    /// The environment's texels and, when light-sampled, its CDFs (empty without one).
    environment: Vec<wgpu::Buffer>,
    features: SceneFeatures,
    bytes_per_triangle: f64,
    bvh_bytes: u64,
    scene_bytes: u64,
    /// The device memory weighed before the upload, part by part (the film as first made).
    memory_parts: Vec<(&'static str, u64)>,
    ray_counter: wgpu::Buffer,
    /// How passes are cut into dispatches.
    sizing: DispatchSizing,
    /// Invocations per pixel fixed by [`GpuRenderer::set_group_samples`].
    group_samples: Option<u32>,
    /// Whether adaptive sampling's test runs at its test points (off when several devices share
    /// a render: their films are tested together, [`crate::MultiGpuRenderer`]).
    convergence_tests: bool,
    /// The choice of invocations per pixel by timing, where the renderer chooses
    /// ([`GpuRenderer::tuner_for`]).
    tuner: Option<GroupTuner>,
    /// Node groups of the traversal stack ([`crate::traverse::stack_size_for`] the uploaded
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
    /// than `LONG_PASS_SECONDS` is submitted dispatch by dispatch, so that it can be stopped
    /// (the first too when its dispatches start halved for long paths).
    last_pass_seconds: f64,
    /// Copies of the film's pass state taken before a pass submitted dispatch by dispatch
    /// ([`GpuFilm::pass_state`], then the convergence counter), to give it back if stopped.
    pass_backup: Vec<wgpu::Buffer>,
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
