//! [`CpuRenderer`]: the path tracer.

use furnace_accel::{Hit, SceneAccel, offset_scale_of_bounds};
use furnace_brdf::iridescence::ThinFilm;
use furnace_brdf::{HitBsdf, LayeredParams, SpecularOptions};
use furnace_render::layout::DIM_PIXEL;
use furnace_render::{
    ADAPTIVE_STEP, AovSample, CancelFlag, Film, Integrator, LightSampling, LightSelection, RenderError,
    RenderSettings,
};
use furnace_sampling::{AnySampler, Sampler};
use furnace_scene::{
    AlphaMode, Camera, CameraRays, Emitters, LightBvh, MaterialSample, PointLightDistribution, Scene,
    VertexAttributes, oct_decode,
};
use furnace_scene::{Environment, EnvironmentSampler, blend_keeps, blend_seed};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

mod accel;
mod lights;
mod path;

use accel::{Trace, Tracer, WORLD};
use lights::SunDisc;

/// A scene prepared for rendering through one camera: its BVH, per-triangle material indices,
/// sampler, and the film that [`Integrator::render_pass`] adds to.
///
/// See the [crate docs](crate) for the algorithm; the sampler dimensions are
/// [`furnace_render::layout`]'s.
pub struct CpuRenderer {
    scene: Arc<Scene>,
    settings: RenderSettings,
    film: Film,
    accel: SceneAccel,
    sampler: AnySampler,
    camera: Camera,
    /// The camera's rays for the settings' image size.
    rays: CameraRays,
    /// Material index of each triangle, clamped into `scene.materials`.
    triangle_materials: Vec<u32>,
    /// Per material, its emission and BSDF when they do not vary over the surface (no
    /// texture): built once here instead of at every hit (bit-identical to building them at
    /// the hit, `Material::evaluate` ignores the UV without textures).
    constant_materials: Vec<Option<ConstantMaterial>>,
    /// `oct_decode` of each vertex normal, decoded once here rather than three times per hit.
    normals: Vec<Vec3>,
    /// Whether any material is alpha-masked or blended (otherwise rays skip the alpha
    /// callback).
    any_alpha: bool,
    /// Whether any material is blended (path rays then draw a blend seed).
    any_blended: bool,
    /// Whether shadow rays can cross some material (a thin-walled sheet, an η = 1 solid, a
    /// blended surface); otherwise they are plain occlusion tests.
    any_crossable: bool,
    /// The ray offsets' length scale (`furnace_accel::offset_scale_of_bounds`).
    offset_scale: f32,
    /// The scene's delta suns ([`Scene::suns`] without a disc).
    suns: Vec<furnace_scene::Sun>,
    /// The scene's sun discs ([`Scene::suns`] with one).
    sun_discs: Vec<SunDisc>,
    /// The emissive triangles; `None` without any.
    emitters: Option<Emitters>,
    /// The light BVH over them when light samples choose by it
    /// ([`furnace_render::LightSelection::Bvh`]), else `None` (chosen by power).
    light_bvh: Option<LightBvh>,
    /// Point and spot lights ([`Scene::point_lights`]).
    point_lights: Vec<furnace_scene::PointLight>,
    /// Their choice by power (`None`: no light has power).
    point_choice: Option<PointLightDistribution>,
    /// One of them per event ([`furnace_render::PointLightSampling::effective`] is `One`), else all.
    one_point_light: bool,
    /// Radiance of an escaping ray ([`Scene::sky`]).
    sky: Vec3,
    /// The environment map ([`Scene::environment`]).
    environment: Option<Environment>,
    /// Its rotation's cosine and sine, formed once ([`Environment::y_rotation`]).
    env_rotation: furnace_scene::YRotation,
    /// Its importance sampler when light samples take it
    /// ([`furnace_render::EnvSampling::effective`] not `Off`, the map not black).
    env_sampler: Option<EnvironmentSampler>,
    /// How the environment's light samples and BSDF rays are weighted
    /// ([`furnace_render::EnvSampling::weights`]).
    env_weights: LightSampling,
    /// Polled once per sample: raised, the pass stops ([`Integrator::set_cancel_flag`]).
    cancel: CancelFlag,
}

/// A material's parameters and BSDF, when they are the same everywhere on its surface.
struct ConstantMaterial {
    params: MaterialSample,
    bsdf: HitBsdf,
}

/// The material at a hit: built once, or evaluated there.
enum Shading<'a> {
    Constant(&'a ConstantMaterial),
    Evaluated(MaterialSample),
}

impl Shading<'_> {
    /// The material's parameters at the hit.
    #[inline]
    fn params(&self) -> &MaterialSample {
        match self {
            Self::Constant(c) => &c.params,
            Self::Evaluated(p) => p,
        }
    }
}

impl std::fmt::Debug for CpuRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CpuRenderer")
            .field("scene", &self.scene.name)
            .field("triangles", &self.triangle_materials.len())
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl CpuRenderer {
    /// Builds the BVH over the scene's triangles and the sampler of `settings`, to render the
    /// scene through `camera` (often [`Scene::default_camera`]) into an empty film.
    ///
    /// # Errors
    /// [`RenderError::Sampler`]: a fixed-N sampler without [`RenderSettings::sample_count`].
    pub fn new(
        scene: impl Into<Arc<Scene>>,
        camera: &Camera,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        let scene = scene.into();
        // The sampler's error before the build.
        AnySampler::new(settings.sampler, settings.seed, settings.sample_count)?;
        let accel = Self::accel_for(&scene);
        Self::with_accel(scene, camera, settings, accel)
    }

    /// The acceleration structure [`CpuRenderer::new`] builds for `scene`: built once by a
    /// caller that also traces rays before rendering (the CLI's default-light probe), it is
    /// given to [`CpuRenderer::with_accel`] instead of built twice.
    pub fn accel_for(scene: &Scene) -> SceneAccel {
        accel::scene_accel(scene)
    }

    /// [`CpuRenderer::new`] with the structure of [`CpuRenderer::accel_for`] already built.
    ///
    /// # Errors
    /// As [`CpuRenderer::new`]; [`RenderError::Device`] if `accel` was not built for this
    /// scene's triangles and instances.
    pub fn with_accel(
        scene: impl Into<Arc<Scene>>,
        camera: &Camera,
        settings: RenderSettings,
        accel: SceneAccel,
    ) -> Result<Self, RenderError> {
        let scene = scene.into();
        let sampler = AnySampler::new(settings.sampler, settings.seed, settings.sample_count)?;
        let g = &scene.geometry;
        if !accel.fits(g.triangle_count(), scene.instancing.instances.len()) {
            return Err(RenderError::Device(
                "the acceleration structure given was not built for this scene's triangles and instances"
                    .into(),
            ));
        }
        let triangle_materials = (0..g.triangle_count()).map(|t| scene.triangle_material(t) as u32).collect();
        let any_alpha = scene.materials.iter().any(|m| m.alpha_mode != AlphaMode::Opaque);
        let any_blended = scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Blend);
        let any_crossable = any_blended || scene.materials.iter().any(|m| m.passes_shadow_rays());
        let constant_materials = scene
            .materials
            .iter()
            .map(|m| {
                // Constant: no texture, and no vertex colour to multiply the base colour.
                (!m.uses_textures() && g.colors.is_empty()).then(|| {
                    let params = m.evaluate(&VertexAttributes::default(), &scene.textures, &scene.images);
                    ConstantMaterial { bsdf: bsdf(&params, m, m.ior, settings.specular, Vec3::Z), params }
                })
            })
            .collect();
        let normals = g.normals.iter().map(|&e| oct_decode(e)).collect();
        let (lo, hi) = scene.bounds();
        let offset_scale = offset_scale_of_bounds(lo, hi);
        let emitters = Emitters::new(&scene);
        let light_bvh = emitters
            .as_ref()
            .filter(|_| settings.light_selection == LightSelection::Bvh)
            .map(|e| e.light_bvh(&scene));
        let environment = scene.environment().cloned();
        let env_sampler = environment
            .as_ref()
            .zip(settings.env_sampling.light_samples(settings.light_sampling))
            .and_then(|(e, compensated)| e.sampler(compensated));
        let point_lights: Vec<furnace_scene::PointLight> = scene.point_lights().copied().collect();
        let rays = camera.rays(settings.width, settings.height);
        Ok(Self {
            cancel: CancelFlag::new(),
            env_rotation: environment
                .as_ref()
                .map_or(furnace_scene::YRotation::IDENTITY, Environment::y_rotation),
            environment,
            env_sampler,
            env_weights: settings.env_sampling.weights(settings.light_sampling),
            suns: scene.suns().filter(|s| !s.is_disc()).copied().collect(),
            sun_discs: scene.suns().filter(|s| s.is_disc()).map(SunDisc::new).collect(),
            emitters,
            light_bvh,
            point_choice: PointLightDistribution::new(&point_lights),
            one_point_light: settings.point_lights.chooses(point_lights.len()),
            point_lights,
            sky: scene.sky(),
            film: Film::for_settings(&settings),
            scene,
            settings,
            accel,
            sampler,
            camera: *camera,
            rays,
            triangle_materials,
            constant_materials,
            normals,
            any_alpha,
            any_blended,
            any_crossable,
            offset_scale,
        })
    }

    /// [`CpuRenderer::new`] through the scene's [`Scene::default_camera`] (its first camera, or a
    /// view framing its geometry).
    ///
    /// # Errors
    /// As [`CpuRenderer::new`].
    pub fn with_default_camera(
        scene: impl Into<Arc<Scene>>,
        settings: RenderSettings,
    ) -> Result<Self, RenderError> {
        let scene = scene.into();
        let camera = scene.default_camera();
        Self::new(scene, &camera, settings)
    }

    /// The scene being rendered.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The camera it renders through.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// An empty film of the settings' size (with AOVs if [`RenderSettings::aovs`]).
    pub fn new_film(&self) -> Film {
        Film::for_settings(&self.settings)
    }

    /// Samples per pixel of each pass at the settings' image size ([`Integrator::pass_samples`]):
    /// at most 4, and about 2¹⁸ samples per pass (a fifth of a second on two cores).
    pub fn pass_samples_for(settings: &RenderSettings) -> u32 {
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        (262_144 / pixels.max(1)).clamp(1, 4) as u32
    }

    /// Bytes of the buffer a pass of [`CpuRenderer::pass_samples_for`] samples computes before
    /// adding them to the film: one colour per pixel and sample, and one [`AovSample`] each with
    /// AOVs.
    pub fn pass_buffer_bytes(settings: &RenderSettings) -> u64 {
        let per_sample = size_of::<Vec3>() + if settings.aovs { size_of::<AovSample>() } else { 0 };
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        pixels * u64::from(Self::pass_samples_for(settings)) * per_sample as u64
    }

    /// The film of [`Integrator::render_pass`].
    pub fn film_ref(&self) -> &Film {
        &self.film
    }

    /// Adds samples `first_sample .. first_sample + samples_per_pixel` of every pixel to `film`,
    /// rows in parallel on the current rayon pool. Each pixel's samples are added in index
    /// order by one task, so the film is bit-identical for any number of threads. Non-finite
    /// samples are rejected and counted ([`Film::rejected`]).
    ///
    /// This is [`Integrator::render_pass`] into a film the caller holds (which the renderer
    /// does not keep).
    ///
    /// A raised cancel flag ([`Integrator::set_cancel_flag`]) stops the pass within a sample's
    /// time: the samples are computed into a buffer first and added to the film only once every
    /// pixel has them (whole blocks of samples, see below), so the film never holds part of a
    /// sample index.
    ///
    /// # Errors
    /// [`RenderError::FilmSize`] if `film` is not `settings.width × settings.height`; for a
    /// fixed-N sampler, [`RenderError::Sampler`] when the pass would run past N (the pattern
    /// would repeat). Nothing is rendered then. [`RenderError::Interrupted`] when the cancel
    /// flag stopped the pass: the film holds the blocks finished before it.
    pub fn render_into(
        &self,
        film: &mut Film,
        first_sample: u32,
        samples_per_pixel: u32,
    ) -> Result<(), RenderError> {
        let (w, h) = (self.settings.width, self.settings.height);
        RenderError::check_film(film, &self.settings)?;
        if samples_per_pixel == 0 || w == 0 || h == 0 {
            return Ok(());
        }
        self.sampler.check_index(first_sample.saturating_add(samples_per_pixel - 1))?;
        // Sample indices stop at u32::MAX (4·10⁹ samples per pixel).
        let end = first_sample.saturating_add(samples_per_pixel);
        // Adaptive sampling tests pixels at multiples of ADAPTIVE_STEP: the pass is rendered in
        // blocks that end there, each followed by the test where it applies.
        let mut block = first_sample;
        while block < end {
            let block_end = match self.settings.adaptive {
                Some(_) => (block / ADAPTIVE_STEP + 1).saturating_mul(ADAPTIVE_STEP).min(end),
                None => end,
            };
            if !self.render_block(film, block, block_end)? {
                return Err(RenderError::Interrupted { samples: block - first_sample });
            }
            if let Some(rule) = &self.settings.adaptive
                && rule.tests_at(block_end)
            {
                film.test_convergence(rule);
            }
            block = block_end;
        }
        Ok(())
    }

    /// Samples `first..end` of every pixel still taking samples, rows in parallel: computed
    /// into a buffer (one sample per pixel and index, polling the cancel flag before each), then
    /// added to the film in index order. `false`, with the film untouched, if the flag stopped
    /// it; [`RenderError::OutOfMemory`] if the buffer cannot be allocated.
    fn render_block(&self, film: &mut Film, first: u32, end: u32) -> Result<bool, RenderError> {
        let w = self.settings.width as usize;
        let per_pixel = (end - first) as usize;
        let aovs = film.has_aovs();
        let row_len = w * per_pixel;
        let n = row_len * self.settings.height as usize;
        let mut values = try_filled(n, Vec3::ZERO)?;
        let mut aov_values = if aovs { try_filled(n, AovSample::MISS)? } else { Vec::new() };
        let mut aov_rows: Vec<Option<&mut [AovSample]>> = if aovs {
            aov_values.chunks_mut(row_len).map(Some).collect()
        } else {
            (0..self.settings.height).map(|_| None).collect()
        };
        let shared: &Film = film;
        let finished = values.par_chunks_mut(row_len).zip(aov_rows.par_iter_mut()).enumerate().all(
            |(y, (row, aov_row))| {
                for x in 0..w {
                    if !shared.is_active(y * w + x) {
                        continue;
                    }
                    for (k, index) in (first..end).enumerate() {
                        if self.cancel.is_raised() {
                            return false;
                        }
                        let slot = x * per_pixel + k;
                        let mut aov = AovSample::MISS;
                        let mut value = self.sample_into(x as u32, y as u32, index, aovs.then_some(&mut aov));
                        if let Some(max) = self.settings.clamp {
                            value = furnace_render::clamp_sample(value, max);
                        }
                        row[slot] = value;
                        if let Some(a) = aov_row {
                            a[slot] = aov;
                        }
                    }
                }
                true
            },
        );
        if !finished {
            return Ok(false);
        }
        let rejected: u64 = film
            .rows_mut()
            .into_par_iter()
            .zip(values.par_chunks(row_len))
            .enumerate()
            .map(|(y, (mut row, samples))| {
                let mut rejected = 0;
                for x in 0..w {
                    if !row.is_active(x) {
                        continue;
                    }
                    for k in 0..per_pixel {
                        let slot = x * per_pixel + k;
                        let aov = aov_values.get(y * row_len + slot).unwrap_or(&AovSample::MISS);
                        rejected += u64::from(!row.add_sample_with_aovs(x, samples[slot], aov));
                    }
                }
                rejected
            })
            .sum();
        film.add_rejected(rejected);
        Ok(true)
    }

    /// One path sample of pixel `(x, y)`, sample number `index`: the radiance carried by the
    /// camera ray through the sampler-chosen point of the pixel.
    pub fn sample(&self, x: u32, y: u32, index: u32) -> Vec3 {
        self.sample_into(x, y, index, None)
    }

    /// [`CpuRenderer::sample`] and what its camera ray hit first ([`AovSample`]).
    pub fn sample_with_aovs(&self, x: u32, y: u32, index: u32) -> (Vec3, AovSample) {
        let mut aov = AovSample::MISS;
        let value = self.sample_into(x, y, index, Some(&mut aov));
        (value, aov)
    }

    fn sample_into(&self, x: u32, y: u32, index: u32, aov: Option<&mut AovSample>) -> Vec3 {
        let pixel = y.wrapping_mul(self.settings.width).wrapping_add(x);
        let [ux, uy] = self.sampler.value_2d(pixel, index, DIM_PIXEL);
        let film_point = Vec2::new(x as f32 + ux, y as f32 + uy);
        let ray = self.rays.generate(film_point);
        match &self.accel {
            SceneAccel::Flat(accel) => {
                Tracer { renderer: self, accel }.trace(pixel, index, ray.origin, ray.direction, aov)
            }
            SceneAccel::TwoLevel(accel) => {
                Tracer { renderer: self, accel }.trace(pixel, index, ray.origin, ray.direction, aov)
            }
        }
    }

    /// `Geometry::shading_normal` over the pre-decoded normals (same arithmetic, same bits),
    /// carried to world space by `instance` (an index into the scene's instances, [`WORLD`] for
    /// a world-space triangle).
    #[inline]
    fn shading_normal(&self, instance: u32, t: usize, b1: f32, b2: f32) -> Option<Vec3> {
        let [a, b, c] = *self.scene.geometry.triangles.get(t)?;
        let n = |i: u32| self.normals.get(i as usize).copied();
        let n = ((1.0 - b1 - b2) * n(a)? + b1 * n(b)? + b2 * n(c)?).normalize_or_zero();
        Some(match self.instance(instance) {
            Some(i) => i.normal(n),
            None => n,
        })
    }

    /// Instance `instance` of the scene (`None` for [`WORLD`]).
    #[inline]
    fn instance(&self, instance: u32) -> Option<&furnace_scene::Instance> {
        if instance == WORLD { None } else { self.scene.instancing.instances.get(instance as usize) }
    }

    fn alpha_passes(&self, triangle: u32, barycentrics: Vec2) -> bool {
        let material = &self.scene.materials[self.triangle_materials[triangle as usize] as usize];
        self.scene.alpha_passes(triangle as usize, (barycentrics.x, barycentrics.y), material)
    }

    /// The coverage of a hit ([`Scene::coverage`]): 1 in a scene without alpha.
    fn coverage(&self, triangle: u32, barycentrics: Vec2) -> f32 {
        if !self.any_alpha {
            return 1.0;
        }
        let material = &self.scene.materials[self.triangle_materials[triangle as usize] as usize];
        self.scene.coverage(triangle as usize, (barycentrics.x, barycentrics.y), material)
    }

    /// Whether a path ray of blend seed `seed` stops at a hit: not at a mask's cut-out, and at
    /// a blended surface with probability equal to its coverage.
    fn stops(&self, seed: u32, instance: u32, triangle: u32, barycentrics: Vec2) -> bool {
        let material = &self.scene.materials[self.triangle_materials[triangle as usize] as usize];
        let b = (barycentrics.x, barycentrics.y);
        match material.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { .. } => self.scene.alpha_passes(triangle as usize, b, material),
            AlphaMode::Blend => {
                // Each instance of a triangle decides on its own: one ray crossing two copies
                // keeps each with its coverage, not both or neither.
                let seed = if instance == WORLD { seed } else { seed ^ instance.wrapping_mul(0x9e37_79b9) };
                blend_keeps(seed, triangle, self.scene.coverage(triangle as usize, b, material))
            }
        }
    }
}

impl<A: Trace> Tracer<'_, A> {
    fn closest_hit(&self, origin: Vec3, direction: Vec3) -> Option<(Hit, u32)> {
        if self.any_alpha {
            let seed = if self.any_blended { blend_seed(origin, direction) } else { 0 };
            self.accel
                .closest_hit_masked(origin, direction, f32::INFINITY, |i, t, b| self.stops(seed, i, t, b))
        } else {
            self.accel.closest_hit(origin, direction, f32::INFINITY)
        }
    }

    /// The fraction of light a shadow ray from `origin` along `direction` carries over
    /// `t_max`: 0 where a surface blocks it, else the product of what the surfaces it crosses
    /// let through (a thin-walled sheet its T′; a blended surface of coverage c its 1 − c, plus
    /// c × T′ if it is a sheet) and the absorption of the volume it starts in (`medium`).
    fn transmittance(&self, origin: Vec3, direction: Vec3, t_max: f32, medium: Vec3) -> Vec3 {
        let mut carried = if medium == Vec3::ZERO { Vec3::ONE } else { absorption(medium, t_max) };
        if !self.any_crossable {
            return if self.occluded_within(origin, direction, t_max) { Vec3::ZERO } else { carried };
        }
        let scene = &self.scene;
        let blocked = self.accel.occluded_masked(origin, direction, t_max, |instance, t, b| {
            let material_index = self.triangle_materials[t as usize] as usize;
            let material = &scene.materials[material_index];
            let coverage = match material.alpha_mode {
                AlphaMode::Opaque => 1.0,
                AlphaMode::Mask { .. } if !self.alpha_passes(t, b) => return false,
                AlphaMode::Mask { .. } => 1.0,
                AlphaMode::Blend => scene.coverage(t as usize, (b.x, b.y), material),
            };
            if !material.passes_shadow_rays() {
                if coverage >= 1.0 {
                    return true;
                }
                carried *= 1.0 - coverage;
                return carried == Vec3::ZERO;
            }
            // A sheet (or an η = 1 solid): T′ at the angle to its shading normal, times its tint.
            let normal = self.shading_normal(instance, t as usize, b.x, b.y).unwrap_or(Vec3::Z);
            let params = match &self.constant_materials[material_index] {
                Some(c) => c.bsdf.sheet_transmittance(direction.dot(normal)),
                None => {
                    let at = scene.geometry.attributes(t as usize, b.x, b.y);
                    let p = material.evaluate(&at, &scene.textures, &scene.images);
                    bsdf(&p, material, material.ior, self.settings.specular, Vec3::Z)
                        .sheet_transmittance(direction.dot(normal))
                }
            };
            carried *= if coverage >= 1.0 { params } else { (1.0 - coverage) + coverage * params };
            carried == Vec3::ZERO
        });
        if blocked { Vec3::ZERO } else { carried }
    }

    /// Whether a surface lies along `direction` from `origin` closer than `t_max`.
    fn occluded_within(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        // Without crossable materials there are no blended ones: only masks filter hits here.
        if self.any_alpha {
            self.accel.occluded_masked(origin, direction, t_max, |_, t, b| self.alpha_passes(t, b))
        } else {
            self.accel.occluded(origin, direction, t_max)
        }
    }
}

impl Integrator for CpuRenderer {
    fn name(&self) -> &'static str {
        "cpu"
    }

    /// `cpu: ` and the target (`x86_64-linux`): the math library's `sin`, `exp`, … may round
    /// differently elsewhere.
    fn describe(&self) -> String {
        format!("cpu: {}-{}", std::env::consts::ARCH, std::env::consts::OS)
    }

    fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    fn render_pass(&mut self, first_sample: u32, samples_per_pixel: u32) -> Result<(), RenderError> {
        let mut film = std::mem::replace(&mut self.film, Film::new(0, 0));
        let result = self.render_into(&mut film, first_sample, samples_per_pixel);
        self.film = film;
        result
    }

    fn film(&mut self) -> Result<Film, RenderError> {
        Ok(self.film.clone())
    }

    fn set_film(&mut self, film: &Film) -> Result<(), RenderError> {
        RenderError::check_film(film, &self.settings)?;
        self.film.clone_from(film);
        Ok(())
    }

    fn converged_pixels(&self) -> Option<u64> {
        self.film.converged_count()
    }

    fn pass_samples(&self) -> u32 {
        Self::pass_samples_for(&self.settings)
    }

    fn set_cancel_flag(&mut self, flag: CancelFlag) {
        self.cancel = flag;
    }
}

/// `n` copies of `value`, or [`RenderError::OutOfMemory`] instead of an abort when they do not
/// fit.
fn try_filled<T: Clone>(n: usize, value: T) -> Result<Vec<T>, RenderError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| RenderError::OutOfMemory {
        what: "the pass's sample buffer",
        bytes: (n as u64).saturating_mul(size_of::<T>() as u64),
    })?;
    v.resize(n, value);
    Ok(v)
}

/// `exp(−σ·t)` per channel, 1 where σ is 0 (also for t = ∞).
#[inline]
fn absorption(sigma: Vec3, t: f32) -> Vec3 {
    let f = |s: f32| if s > 0.0 { (-s * t).exp() } else { 1.0 };
    Vec3::new(f(sigma.x), f(sigma.y), f(sigma.z))
}

/// The BSDF of a hit's evaluated material parameters ([`HitBsdf::new`]) with the index `ior`
/// (the material's, or a dispersive solid's at the path's wavelength), its clear coat's normal
/// `coat_normal` in the shading frame (`Vec3::Z`: the shading normal).
#[inline]
fn bsdf(
    params: &MaterialSample,
    material: &furnace_scene::Material,
    ior: f32,
    specular: SpecularOptions,
    coat_normal: Vec3,
) -> HitBsdf {
    HitBsdf::new(
        &LayeredParams {
            base_color: params.base_color,
            metallic: params.metallic,
            roughness: params.roughness,
            specular_factor: params.specular_factor,
            specular_color: params.specular_color,
            transmission: params.transmission,
            ior,
            volume: material.volume,
            clearcoat: params.clearcoat,
            clearcoat_roughness: params.clearcoat_roughness,
            clearcoat_normal: coat_normal,
            sheen_color: params.sheen_color,
            sheen_roughness: params.sheen_roughness,
            iridescence: params.iridescence,
            film: ThinFilm { ior: params.iridescence_ior, thickness: params.iridescence_thickness },
            diffuse_transmission: params.diffuse_transmission,
            diffuse_transmission_color: params.diffuse_transmission_color,
            anisotropy: params.anisotropy,
        },
        specular,
    )
}
