//! [`CpuRenderer`]: the path tracer.

use furnace_accel::{BuildOptions, Bvh, Hit, offset_ray_origin_scaled, offset_scale_of_bounds};
use furnace_brdf::{Bsdf, Frame, MetallicRoughness, MetallicRoughnessParams, SpecularOptions};
use furnace_render::layout::{
    self, BOUNCE_BSDF_DIRECTION, BOUNCE_BSDF_LOBE, BOUNCE_RUSSIAN_ROULETTE, DIM_PIXEL,
};
use furnace_render::{
    ADAPTIVE_STEP, AovSample, Film, Integrator, LightSampling, LightSelection, RenderError, RenderSettings,
};
use furnace_sampling::{AnySampler, Sampler};
use furnace_scene::{AlphaMode, Camera, Emitters, LightBvh, MaterialSample, Scene, oct_decode};
use furnace_scene::{Environment, EnvironmentSampler};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

mod lights;

use lights::{SunDisc, Vertex};

/// A scene prepared for rendering through one camera: its BVH, per-triangle material indices,
/// sampler, and the film that [`Integrator::render_pass`] adds to.
///
/// See the [crate docs](crate) for the algorithm; the sampler dimensions are
/// [`furnace_render::layout`]'s.
pub struct CpuRenderer {
    scene: Arc<Scene>,
    settings: RenderSettings,
    film: Film,
    bvh: Bvh,
    sampler: AnySampler,
    camera: Camera,
    /// Material index of each triangle, clamped into `scene.materials`.
    triangle_materials: Vec<u32>,
    /// Per material, its emission and BSDF when they do not vary over the surface (no
    /// texture): built once here instead of at every hit (bit-identical to building them at
    /// the hit, `Material::evaluate` ignores the UV without textures).
    constant_materials: Vec<Option<ConstantMaterial>>,
    /// `oct_decode` of each vertex normal, decoded once here rather than three times per hit.
    normals: Vec<Vec3>,
    /// Whether any material is alpha-masked (otherwise rays skip the mask callback).
    any_masked: bool,
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
}

/// A material's emission and BSDF, when they are the same everywhere on its surface.
struct ConstantMaterial {
    emission: Vec3,
    bsdf: MetallicRoughness,
    /// The base colour: the albedo AOV.
    base_color: Vec3,
}

/// The material at a hit: built once, or evaluated there.
enum Shading<'a> {
    Constant(&'a ConstantMaterial),
    Evaluated(MaterialSample),
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
        let sampler = AnySampler::new(settings.sampler, settings.seed, settings.sample_count)?;
        let g = &scene.geometry;
        let bvh = Bvh::from_indexed(&g.positions, &g.triangles, BuildOptions::default());
        let triangle_materials = (0..g.triangle_count()).map(|t| scene.triangle_material(t) as u32).collect();
        let any_masked = scene.materials.iter().any(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. }));
        let constant_materials = scene
            .materials
            .iter()
            .map(|m| {
                (!m.uses_textures()).then(|| {
                    let params = m.evaluate(Vec2::ZERO, &scene.textures, &scene.images);
                    ConstantMaterial {
                        emission: params.emission,
                        bsdf: bsdf(&params, settings.specular),
                        base_color: params.base_color,
                    }
                })
            })
            .collect();
        let normals = g.normals.iter().map(|&e| oct_decode(e)).collect();
        let (lo, hi) = g.bounds();
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
        Ok(Self {
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
            point_lights: scene.point_lights().copied().collect(),
            sky: scene.sky(),
            film: Film::for_settings(&settings),
            scene,
            settings,
            bvh,
            sampler,
            camera: *camera,
            triangle_materials,
            constant_materials,
            normals,
            any_masked,
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
    /// # Errors
    /// [`RenderError::FilmSize`] if `film` is not `settings.width × settings.height`; for a
    /// fixed-N sampler, [`RenderError::Sampler`] when the pass would run past N (the pattern
    /// would repeat). Nothing is rendered then.
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
            self.render_block(film, block, block_end);
            if let Some(rule) = &self.settings.adaptive
                && rule.tests_at(block_end)
            {
                film.test_convergence(rule);
            }
            block = block_end;
        }
        Ok(())
    }

    /// Samples `first..end` of every pixel still taking samples, rows in parallel.
    fn render_block(&self, film: &mut Film, first: u32, end: u32) {
        let w = self.settings.width;
        let rejected: u64 = film
            .rows_mut()
            .into_par_iter()
            .enumerate()
            .map(|(y, mut row)| {
                let mut rejected = 0;
                let aovs = row.has_aovs();
                for x in 0..w {
                    if !row.is_active(x as usize) {
                        continue;
                    }
                    for index in first..end {
                        let mut aov = AovSample::MISS;
                        let mut value = self.sample_into(x, y as u32, index, aovs.then_some(&mut aov));
                        if let Some(max) = self.settings.clamp {
                            value = furnace_render::clamp_sample(value, max);
                        }
                        rejected += u64::from(!row.add_sample_with_aovs(x as usize, value, &aov));
                    }
                }
                rejected
            })
            .sum();
        film.add_rejected(rejected);
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
        let ray = self.camera.generate_ray(film_point, self.settings.width, self.settings.height);
        self.trace(pixel, index, ray.origin, ray.direction, aov)
    }

    /// The path tracing loop: radiance arriving at `origin` from direction `-direction`. With
    /// `aov`, what the first ray hits is written there (it is left as it is for a miss).
    fn trace(
        &self,
        pixel: u32,
        index: u32,
        mut origin: Vec3,
        mut direction: Vec3,
        mut aov: Option<&mut AovSample>,
    ) -> Vec3 {
        let scene = &self.scene;
        let mut radiance = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        // `event` counts the scattering events so far; the loop body handles one ray.
        let mut event = 0;
        // The solid-angle pdf of the BSDF sample that made the ray (`None`: the camera's), for
        // the MIS weights of the lights it reaches.
        let mut bsdf_pdf: Option<f32> = None;
        // The receiving side (geometric normal) of the vertex the ray left, for the light BVH's
        // probabilities in those weights.
        let mut normal = Vec3::ZERO;
        loop {
            let Some(hit) = self.closest_hit(origin, direction) else {
                // The ray leaves the scene: the sky, the environment and the sun discs it sees.
                radiance += throughput * self.sky;
                if let Some(env) = &self.environment {
                    radiance += throughput * self.environment_seen(env, direction, bsdf_pdf);
                }
                if !self.sun_discs.is_empty() {
                    radiance += throughput * self.sun_discs_seen(direction, bsdf_pdf);
                }
                break;
            };
            let material_index = self.triangle_materials[hit.triangle as usize] as usize;
            let material = &scene.materials[material_index];
            // Textured materials are evaluated at the hit's UV; the others were built once.
            let (uv, shading) = match &self.constant_materials[material_index] {
                Some(c) => (Vec2::ZERO, Shading::Constant(c)),
                None => {
                    let uv = scene.geometry.uv(hit.triangle as usize, hit.barycentrics.x, hit.barycentrics.y);
                    (uv, Shading::Evaluated(material.evaluate(uv, &scene.textures, &scene.images)))
                }
            };
            let t = hit.triangle as usize;
            let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
            let interpolated = self.shading_normal(t, b1, b2);
            let surface = scene.surface_point(t, (b1, b2), material, uv, direction, interpolated);
            if let Some(aov) = aov.take() {
                let (base_color, emission) = match &shading {
                    Shading::Constant(c) => (c.base_color, c.emission),
                    Shading::Evaluated(params) => (params.base_color, params.emission),
                };
                // The front of an emitter: its colour is its light, like the sky's (albedo 1).
                let emits = emission != Vec3::ZERO && surface.as_ref().is_some_and(|s| !s.back_face);
                *aov = AovSample {
                    albedo: if emits { Vec3::ONE } else { base_color },
                    // The back of a single-sided surface (black) has no shading normal.
                    normal: surface.as_ref().map_or(Vec3::ZERO, |s| s.shading),
                    depth: Some(hit.t),
                };
            }
            let Some(surface) = surface else {
                // The back of a single-sided surface: black, like a one-sided BSDF.
                break;
            };
            let emission = match &shading {
                Shading::Constant(c) => c.emission,
                Shading::Evaluated(params) => params.emission,
            };
            // Emission is one-sided: the back of a double-sided emitter does not emit. Reached
            // by a BSDF sample, it is weighted against the light sample that could have found it.
            if !surface.back_face {
                if self.emitters.is_some() && emission != Vec3::ZERO {
                    let cos_light = -surface.geometric.dot(direction);
                    let w =
                        self.emission_weight(bsdf_pdf, origin, normal, material_index, t, hit.t, cos_light);
                    radiance += throughput * emission * w;
                } else {
                    radiance += throughput * emission;
                }
            }
            if event == self.settings.bounces {
                break;
            }
            let evaluated;
            let bsdf = match &shading {
                Shading::Constant(c) => &c.bsdf,
                Shading::Evaluated(params) => {
                    evaluated = bsdf(params, self.settings.specular);
                    &evaluated
                }
            };
            let frame = Frame::new(surface.shading);
            let wo = frame.to_local(-direction);
            let leave = offset_ray_origin_scaled(surface.position, surface.geometric, self.offset_scale);

            // Delta suns: gathered by a shadow ray only.
            for sun in &self.suns {
                let to_sun = -sun.direction;
                if to_sun.dot(surface.geometric) > 0.0 {
                    let f = bsdf.eval(wo, frame.to_local(to_sun));
                    if f != Vec3::ZERO && !self.occluded(leave, to_sun) {
                        radiance += throughput * f * sun.irradiance;
                    }
                }
            }

            // Point and spot lights, delta lights too: a shadow ray to each.
            if !self.point_lights.is_empty() {
                radiance += self.gather_point_lights(throughput, bsdf, wo, frame, &surface, leave);
            }

            // Emitters, sun discs and the environment: one light sample each (next-event
            // estimation).
            if self.settings.light_sampling != LightSampling::Bsdf
                && (self.emitters.is_some() || !self.sun_discs.is_empty() || self.env_sampler.is_some())
            {
                let vertex = Vertex { throughput, bsdf, wo, frame, surface: &surface, leave };
                if self.emitters.is_some() {
                    radiance += self.sample_emitter(pixel, index, event, &vertex);
                }
                if !self.sun_discs.is_empty() {
                    radiance += self.sample_sun_discs(pixel, index, event, &vertex);
                }
                if self.env_sampler.is_some() {
                    radiance += self.sample_environment(pixel, index, event, &vertex);
                }
            }

            // Continue the path by sampling the BSDF.
            let dim = layout::bounce(event);
            let [u1, u2] = self.sampler.value_2d(pixel, index, dim + BOUNCE_BSDF_DIRECTION);
            // The lobe choice `uc` is drawn only where the material has two lobes.
            let uc = || self.sampler.value(pixel, index, dim + BOUNCE_BSDF_LOBE);
            let Some(s) = bsdf.sample_lazy(wo, Vec2::new(u1, u2), uc) else { break };
            let wi = frame.to_world(s.wi);
            if !(wi.dot(surface.geometric) > 0.0) {
                // Above the shading normal's horizon but below the surface: the path ends
                // (continuing would enter the surface from its own side).
                break;
            }
            throughput *= s.weight;
            bsdf_pdf = Some(s.pdf);
            event += 1;
            if self.settings.russian_roulette && event >= 3 {
                let survive = furnace_render::russian_roulette_survival(throughput);
                if !(self.sampler.value(pixel, index, dim + BOUNCE_RUSSIAN_ROULETTE) < survive) {
                    break;
                }
                throughput /= survive;
            }
            origin = leave;
            normal = surface.geometric;
            direction = wi;
        }
        radiance
    }

    /// `Geometry::shading_normal` over the pre-decoded normals (same arithmetic, same bits).
    #[inline]
    fn shading_normal(&self, t: usize, b1: f32, b2: f32) -> Option<Vec3> {
        let [a, b, c] = *self.scene.geometry.triangles.get(t)?;
        let n = |i: u32| self.normals.get(i as usize).copied();
        Some(((1.0 - b1 - b2) * n(a)? + b1 * n(b)? + b2 * n(c)?).normalize_or_zero())
    }

    fn alpha_passes(&self, triangle: u32, barycentrics: Vec2) -> bool {
        let material = &self.scene.materials[self.triangle_materials[triangle as usize] as usize];
        self.scene.alpha_passes(triangle as usize, (barycentrics.x, barycentrics.y), material)
    }

    fn closest_hit(&self, origin: Vec3, direction: Vec3) -> Option<Hit> {
        if self.any_masked {
            self.bvh.closest_hit_masked(origin, direction, f32::INFINITY, |t, b| self.alpha_passes(t, b))
        } else {
            self.bvh.closest_hit(origin, direction, f32::INFINITY)
        }
    }

    /// What the point and spot lights add at a scattering event (throughput included): a
    /// shadow ray to each, stopping `SHADOW_EPSILON·d` short of it; a contribution that is not
    /// finite (a light on the surface, d → 0) adds nothing. Summed over the lights first, as
    /// the WGSL twin does.
    fn gather_point_lights(
        &self,
        throughput: Vec3,
        bsdf: &MetallicRoughness,
        wo: Vec3,
        frame: Frame,
        surface: &furnace_scene::SurfacePoint,
        leave: Vec3,
    ) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for light in &self.point_lights {
            let to_light = light.position - surface.position;
            let d2 = to_light.length_squared();
            if !(d2 > 0.0) {
                continue;
            }
            let d = d2.sqrt();
            let wi = to_light / d;
            if wi.dot(surface.geometric) > 0.0 {
                let li = light.intensity_towards(-wi, d);
                if li != Vec3::ZERO {
                    let f = bsdf.eval(wo, frame.to_local(wi));
                    let contribution = throughput * f * li / d2;
                    if f != Vec3::ZERO
                        && contribution.is_finite()
                        && !self.occluded_within(leave, wi, d * (1.0 - furnace_render::SHADOW_EPSILON))
                    {
                        sum += contribution;
                    }
                }
            }
        }
        sum
    }

    fn occluded(&self, origin: Vec3, direction: Vec3) -> bool {
        self.occluded_within(origin, direction, f32::INFINITY)
    }

    /// Whether a surface lies along `direction` from `origin` closer than `t_max`.
    fn occluded_within(&self, origin: Vec3, direction: Vec3, t_max: f32) -> bool {
        if self.any_masked {
            self.bvh.occluded_masked(origin, direction, t_max, |t, b| self.alpha_passes(t, b))
        } else {
            self.bvh.occluded(origin, direction, t_max)
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

    /// At most 4, and about 2¹⁸ samples per pass (a fifth of a second on two cores).
    fn converged_pixels(&self) -> Option<u64> {
        self.film.converged_count()
    }

    fn pass_samples(&self) -> u32 {
        let pixels = u64::from(self.settings.width) * u64::from(self.settings.height);
        (262_144 / pixels.max(1)).clamp(1, 4) as u32
    }
}

/// The BSDF of evaluated material parameters.
fn bsdf(params: &MaterialSample, specular: SpecularOptions) -> MetallicRoughness {
    MetallicRoughness::new(
        MetallicRoughnessParams {
            base_color: params.base_color,
            metallic: params.metallic,
            roughness: params.roughness,
            specular_factor: params.specular_factor,
            specular_color: params.specular_color,
        },
        specular,
    )
}
