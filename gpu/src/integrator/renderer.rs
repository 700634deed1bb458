//! [`GpuRenderer`]'s making and settings: the upload of a packed scene, the kernel built for its
//! features, reconfiguration with new settings, and the choices of invocations per pixel.

use super::dispatch::{DispatchSizing, HARDWARE_GROUP_SAMPLES};
use super::frame::{frame_params_with, set_camera_params};
use super::kernel::{COUNTER_WORDS, Kernel};
use super::packing::{emitter_buffer_words, environment_buffer_words};
use super::{
    GpuRenderer, GroupTuner, PackedScene, SceneFeatures, ShaderChecks, TraceCounts, group_size_for,
    hardware_group_samples, renderable_sampler,
};
use crate::film::{FilmPrecision, GpuFilm};
use crate::sampling::SamplerParams;
use crate::scene::GpuScene;
use crate::{GpuContext, GpuError, brdf};
use furnace_accel::{BuildOptions, Bvh};
use furnace_render::RenderSettings;
use furnace_sampling::AnySampler;
use furnace_scene::{Camera, Emitters, Scene};

/// The film `settings` need: with AOVs and adaptive-sampling marks when they ask for them.
pub(super) fn film_for(
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
pub(super) fn storage_buffer(ctx: &GpuContext, label: &str, words: &[u32]) -> Result<wgpu::Buffer, GpuError> {
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

impl GpuRenderer {
    /// Uploads `scene` (seen through `camera`) and builds the pipeline for `settings`.
    ///
    /// # Errors
    /// The sampler's (fixed-N samplers need `sample_count`), [`GpuError::TooLarge`] when a
    /// buffer exceeds the adapter's limits, [`GpuError::OutOfDeviceMemory`] when all of them
    /// exceed its memory (both before anything is allocated), [`GpuError::Unsupported`] for more than one
    /// directional light, or a pipeline error.
    pub fn new(
        ctx: GpuContext,
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Self, GpuError> {
        renderable_sampler(scene, &settings)?;
        if !scene.instancing.is_empty() {
            let packed = PackedScene::instanced(scene, camera, settings, ctx.upload_limit())?;
            return Self::with_packed(ctx, &packed);
        }
        let g = &scene.geometry;
        let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
        Self::with_bvh(ctx, scene, &bvh, camera, settings)
    }

    /// [`GpuRenderer::new`] with the scene's BVH already built (`Bvh::from_indexed` over its
    /// positions and triangles with the default options): several devices rendering one scene
    /// build it once ([`crate::MultiGpuRenderer`]). The scene must have no instances
    /// ([`Scene::flattened`]).
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
        let limit = ctx.upload_limit();
        Self::with_bvh_within(ctx, scene, bvh, camera, settings, limit)
    }

    /// [`GpuRenderer::with_bvh`] with every buffer packed within `limit` bytes (the device's own
    /// limit is [`GpuContext::upload_limit`]; a smaller one exercises the packing of large
    /// scenes on small ones: the BVH's triangle slots beyond one binding go to a second).
    ///
    /// # Errors
    /// As [`GpuRenderer::with_bvh`]; [`GpuError::TooLarge`] for a buffer over `limit` that
    /// cannot be split.
    pub fn with_bvh_within(
        ctx: GpuContext,
        scene: &Scene,
        bvh: &Bvh,
        camera: &Camera,
        settings: RenderSettings,
        limit: u64,
    ) -> Result<Self, GpuError> {
        let packed = PackedScene::new(scene, bvh, camera, settings, limit.min(ctx.upload_limit()))?;
        Self::with_packed(ctx, &packed)
    }

    /// [`GpuRenderer::with_bvh`] from the scene as packed on the host ([`PackedScene`]): several
    /// devices rendering one scene pack it once and each uploads the same words.
    ///
    /// # Errors
    /// [`GpuError::OutOfDeviceMemory`] before anything is allocated when the scene and film
    /// need more than the device has room for, a device error, or a pipeline error.
    pub(crate) fn with_packed(ctx: GpuContext, packed: &PackedScene) -> Result<Self, GpuError> {
        packed.check_limit(ctx.upload_limit())?;
        let PackedScene { settings, sampler, base, features, bvh_depth, triangles, .. } = *packed;
        let precision = FilmPrecision::for_context(&ctx);
        let (w, h) = (settings.width, settings.height);
        let film = GpuFilm::device_bytes(w, h, precision, settings.aovs, settings.adaptive.is_some());
        let memory_parts = packed.device_parts(film);
        if let Some(memory) = ctx.memory() {
            crate::memory::check_fits(&memory_parts, memory, &ctx.info.name)?;
        }
        let [nodes, tris] = packed.bvh_words.extra();
        let mut bvh =
            vec![storage_buffer(&ctx, "bvh nodes", nodes)?, storage_buffer(&ctx, "bvh triangles", tris)?];
        if packed.bvh_words.is_split() {
            bvh.push(storage_buffer(&ctx, "bvh triangles (second)", &packed.bvh_words.triangles_high)?);
        }
        if let Some(inst) = &packed.instance_words {
            let [tlas, instances] = inst.extra();
            bvh.push(storage_buffer(&ctx, "tlas nodes", tlas)?);
            bvh.push(storage_buffer(&ctx, "instances", instances)?);
        }
        let bvh_bytes = bvh.iter().map(wgpu::Buffer::size).sum();
        let gpu_scene = GpuScene::upload_buffers(&ctx, &packed.scene_words)?;
        let ray_counter = ctx.buffer_init(
            "ray counter",
            bytemuck::cast_slice(&[0u32; COUNTER_WORDS]),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let mut tables = brdf::turquin_table();
        if features.sheen {
            tables.extend(brdf::sheen_table());
        }
        let turquin = storage_buffer(&ctx, "turquin", bytemuck::cast_slice(&tables))?;
        let point_lights = storage_buffer(&ctx, "point lights", bytemuck::cast_slice(&packed.point_lights))?;
        let emitters =
            packed.emitter_words.as_ref().map(|w| storage_buffer(&ctx, "emitters", w)).transpose()?;
        let environment = packed
            .environment
            .iter()
            .map(|(label, w)| storage_buffer(&ctx, label, w))
            .collect::<Result<Vec<_>, _>>()?;
        let film = film_for(&ctx, &settings, precision)?;
        let stack_size = crate::traverse::stack_size_for(bvh_depth);
        let group_size = group_size_for(&ctx, features);
        let kernel = Kernel::new(&ctx, precision, features, ShaderChecks::default(), group_size, stack_size)?;
        let converged_counter = converged_counter(&ctx, &settings)?;
        let sizing = DispatchSizing::new(!crate::context::is_hardware(&ctx.info), settings.bounces);
        let mut renderer = Self {
            bytes_per_triangle: gpu_scene.bytes_per_triangle(),
            bvh_bytes,
            scene_bytes: gpu_scene.bytes
                + emitters.as_ref().map_or(0, wgpu::Buffer::size)
                + environment.iter().map(wgpu::Buffer::size).sum::<u64>(),
            memory_parts,
            ray_counter,
            ctx,
            settings,
            sampler,
            base,
            kernel,
            converged: settings.adaptive.map(|_| 0),
            converged_counter,
            film,
            scene: gpu_scene,
            bvh,
            turquin,
            point_lights,
            emitters,
            environment,
            features,
            sizing,
            group_samples: None,
            convergence_tests: true,
            tuner: None,
            stack_size,
            timer: None,
            triangles,
            display: false,
            cancel: None,
            last_pass_seconds: 0.0,
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
            split_triangles: self.features.split_triangles,
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

    /// The device memory its scene and film take, part by part (the BVH, geometry and
    /// materials, lights, environment, film), as weighed against the device's memory before
    /// the upload ([`crate::memory::check_fits`]).
    pub fn memory_parts(&self) -> &[(&'static str, u64)] {
        &self.memory_parts
    }

    /// Node groups the traversal stack holds: as many as the uploaded tree has levels below its
    /// root, at most [`crate::traverse::DEFAULT_STACK_SIZE`] ([`crate::traverse::stack_size_for`]).
    pub fn traversal_stack_size(&self) -> u32 {
        self.stack_size
    }

    /// Invocations per workgroup of the integrator ([`group_size_for`]).
    pub fn group_size(&self) -> u32 {
        self.kernel.group_size
    }

    /// Bytes of the scene buffers on the GPU (geometry, materials, textures; BVH excluded).
    pub fn scene_bytes(&self) -> u64 {
        self.scene_bytes
    }

    /// Whether the passes that follow count what they trace ([`GpuRenderer::take_trace_counts`];
    /// off by default). Counting runs a kernel of its own, built here when the choice changes
    /// (the counters cost throughput, so the rendering kernel has none).
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
        let group_size = group_size_for(&self.ctx, features);
        let precision = self.film.precision();
        self.kernel = Kernel::new(
            &self.ctx,
            precision,
            features,
            ShaderChecks::default(),
            group_size,
            self.stack_size,
        )?;
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
            n.map(|n| 1 << n.clamp(1, self.group_size()).ilog2().min(self.group_size().trailing_zeros()));
        self.tuner = self.tuner_for();
    }

    /// The timing choice between the image-size rule and one invocation per pixel
    /// ([`GroupTuner`]): on hardware adapters, where [`GpuRenderer::set_group_samples`] has not
    /// fixed it, without adaptive sampling (whose passes are cut into blocks at its test
    /// points), and on images large enough that the rule chose fewer than
    /// [`HARDWARE_GROUP_SAMPLES`] (more than 1): a smaller image at one invocation per pixel
    /// leaves most of the GPU idle, and its passes are short enough for the host's part of a pass to blur the timing.
    fn tuner_for(&self) -> Option<GroupTuner> {
        let software = self.sizing.is_software();
        if software || self.group_samples.is_some() || self.settings.adaptive.is_some() {
            return None;
        }
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        let rule = hardware_group_samples(pixels, self.sizing.samples_per_dispatch);
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
        // Software adapters run invocations on a few CPU threads: nothing to fill.
        let software = self.sizing.is_software();
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        let n = self.group_samples.unwrap_or(if software {
            1
        } else if let Some(t) = &self.tuner {
            t.next()
        } else {
            hardware_group_samples(pixels, self.sizing.samples_per_dispatch)
        });
        // More invocations than samples would idle.
        let cap = samples_per_pixel.max(1);
        if n > cap { 1 << cap.ilog2() } else { n }
    }

    /// About how many samples one dispatch computes (the watchdog bound).
    pub fn samples_per_dispatch(&self) -> u64 {
        self.sizing.samples_per_dispatch
    }

    /// How the film sums.
    pub fn film_precision(&self) -> FilmPrecision {
        self.film.precision()
    }
}
