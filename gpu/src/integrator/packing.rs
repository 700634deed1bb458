//! The scene packed into the integrator's buffers on the host: the point lights' records
//! ([`GpuPointLight`]), the emitters' alias table or light BVH ([`emitter_words`],
//! [`light_bvh_words`]), the environment map and its CDFs ([`environment_words`]), all of it with
//! the BVH's and the scene's words in a [`PackedScene`], made once for every device of a render.

use super::frame::frame_params_with;
use super::{FrameParams, SceneFeatures};
use crate::sampling::SamplerParams;
use crate::scene::SceneBuffers;
use crate::shared::WgslType;
use crate::traverse::BvhBuffers;
use crate::{GpuContext, GpuError};
use bytemuck::Zeroable;
use furnace_accel::Bvh;
use furnace_render::RenderSettings;
use furnace_sampling::AnySampler;
use furnace_scene::{Camera, Emitters, LightBvh, PointLightDistribution, Scene};

#[cfg(doc)]
use super::GpuRenderer;

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
/// ([`furnace_render::LightSelection::Bvh`]), as `u32` words read by the shader as `vec4<u32>`: per emitter
/// its triangle, its path from the root (two words, levels 0–31 then 32–63) and a pad —
/// `4·n` words — then the nodes, depth first, [`LIGHT_BVH_NODE_WORDS`] each (`lo.xyz`, `φ`,
/// `hi.xyz`, `cos θo`, `axis.xyz`, `child`, the floats as bits): 16 bytes per emitter and 48
/// per node, `2n − 1` nodes. 16-byte records let the shader read a node in three 16-byte loads
/// instead of twelve 4-byte ones.
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

/// The `emitters` buffer's words: the alias table's records ([`emitter_words`]), or with
/// `features.light_bvh` the light BVH's ([`light_bvh_words`]); `None` for a scene without
/// emitters (no buffer, no binding).
pub(super) fn emitter_buffer_words(
    scene: &Scene,
    emitters: Option<&Emitters>,
    features: SceneFeatures,
) -> Option<Vec<u32>> {
    emitters
        .map(|e| if features.light_bvh { light_bvh_words(e, &e.light_bvh(scene)) } else { emitter_words(e) })
}

/// The environment's buffers, labelled: its texels, and its CDFs when it is light-sampled
/// ([`environment_words`]); none without an environment. [`GpuError::TooLarge`] for one over
/// `limit` bytes.
pub(super) fn environment_buffer_words(
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
    pub(super) settings: RenderSettings,
    pub(super) sampler: AnySampler,
    pub(super) base: FrameParams,
    pub(super) features: SceneFeatures,
    pub(super) bvh_depth: usize,
    pub(super) triangles: usize,
    pub(super) bvh_words: BvhBuffers,
    /// With instances: the TLAS and the instances (`bvh_words` then holds every mesh's BVH).
    pub(super) instance_words: Option<crate::traverse::InstanceBuffers>,
    pub(super) scene_words: SceneBuffers,
    pub(super) point_lights: Vec<GpuPointLight>,
    pub(super) emitter_words: Option<Vec<u32>>,
    pub(super) environment: Vec<(&'static str, Vec<u32>)>,
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
        if !scene.instancing.is_empty() {
            return Err(GpuError::Unsupported(
                "a scene with instances: pack it with PackedScene::instanced (GpuRenderer::new does)".into(),
            ));
        }
        if bvh.input_count() != g.triangle_count() || bvh.layout() != furnace_accel::Layout::Cwbvh {
            return Err(GpuError::Unsupported(format!(
                "a {:?} BVH over {} triangles for a scene of {} (the GPU traverses a CWBVH of the scene's triangles)",
                bvh.layout(),
                bvh.input_count(),
                g.triangle_count()
            )));
        }
        let traversal = (BvhBuffers::new(bvh, limit)?, None, bvh.depth());
        Self::with_traversal(scene, camera, (settings, sampler), traversal, limit)
    }

    /// The rest of a packed scene around its traversal's buffers (`bvh_words`, `instance_words`
    /// and the deepest BVH's depth): the frame's constants, the scene's, the lights' and the
    /// environment's words.
    fn with_traversal(
        scene: &Scene,
        camera: &Camera,
        (settings, sampler): (RenderSettings, AnySampler),
        (bvh_words, instance_words, bvh_depth): (BvhBuffers, Option<crate::traverse::InstanceBuffers>, usize),
        limit: u64,
    ) -> Result<Self, GpuError> {
        let sampler_params = SamplerParams::new(settings.sampler, settings.seed, settings.sample_count)?;
        let scene_emitters = Emitters::new(scene);
        let features = SceneFeatures {
            split_triangles: bvh_words.is_split(),
            ..SceneFeatures::with_emitters(scene, &settings, scene_emitters.is_some())
        };
        Ok(Self {
            settings,
            sampler,
            base: frame_params_with(scene, camera, &settings, sampler_params, scene_emitters.as_ref()),
            features,
            bvh_depth,
            triangles: scene.geometry.triangles.len(),
            bvh_words,
            instance_words,
            scene_words: SceneBuffers::new(scene, limit)?,
            point_lights: point_light_records(scene),
            emitter_words: emitter_buffer_words(scene, scene_emitters.as_ref(), features),
            environment: environment_buffer_words(scene, &settings, limit)?,
        })
    }

    /// Packs `scene`, which has instances, for the two-level traversal: furnace-accel's
    /// [`furnace_accel::TwoLevel`] with the world triangles as an instance of their own (placed by
    /// the identity, which changes no bit of them), every mesh's CWBVH in the node and triangle
    /// buffers, the TLAS and the instances.
    ///
    /// # Errors
    /// As [`PackedScene::new`].
    pub(crate) fn instanced(
        scene: &Scene,
        camera: &Camera,
        settings: RenderSettings,
        limit: u64,
    ) -> Result<Self, GpuError> {
        let sampler = renderable_sampler(scene, &settings)?;
        let g = &scene.geometry;
        let inst = &scene.instancing;
        let world = inst.world_triangles;
        let with_world = world > 0;
        let meshes: Vec<std::ops::Range<u32>> =
            with_world.then_some(0..world).into_iter().chain(inst.meshes.iter().cloned()).collect();
        let shift = u32::from(with_world);
        let mut placements: Vec<(u32, glam::Affine3A)> = Vec::with_capacity(inst.instances.len() + 1);
        let mut transforms: Vec<(glam::Affine3A, u32)> = Vec::with_capacity(inst.instances.len() + 1);
        if with_world {
            placements.push((0, glam::Affine3A::IDENTITY));
            transforms.push((glam::Affine3A::IDENTITY, 0));
        }
        for (k, i) in inst.instances.iter().enumerate() {
            placements.push((i.mesh + shift, i.world_from_object));
            // CpuRenderer::stops: an instance's blend seeds are mixed by its index.
            transforms.push((i.world_from_object, (k as u32).wrapping_mul(0x9e37_79b9)));
        }
        let two = furnace_accel::TwoLevel::build(&g.positions, &g.triangles, 0..0, &meshes, &placements);
        let (bvh_words, words) = crate::traverse::InstanceBuffers::new(&two, &transforms, limit)?;
        drop(two);
        let depth = words.depth;
        Self::with_traversal(scene, camera, (settings, sampler), (bvh_words, Some(words), depth), limit)
    }

    /// The largest upload limit of `contexts` ([`PackedScene::new`]'s `limit`): a device with a
    /// smaller one refuses the scene in [`GpuRenderer::with_packed`] if it does not fit.
    pub(crate) fn limit_of<'a>(contexts: impl IntoIterator<Item = &'a GpuContext>) -> u64 {
        contexts.into_iter().map(GpuContext::upload_limit).max().unwrap_or(u64::MAX)
    }

    /// Every buffer the scene uploads, named as a [`GpuError::TooLarge`] names it.
    fn buffers(&self) -> Vec<(&'static str, &[u32])> {
        let [nodes, tris] = self.bvh_words.extra();
        let mut buffers: Vec<(&str, &[u32])> = vec![
            ("BVH node", nodes),
            ("BVH triangle", tris),
            ("BVH triangle (second)", &self.bvh_words.triangles_high),
        ];
        if let Some(inst) = &self.instance_words {
            let [tlas, instances] = inst.extra();
            buffers.push(("TLAS node", tlas));
            buffers.push(("instance", instances));
        }
        buffers.extend(SceneBuffers::EXTRA_NAMES.into_iter().zip(self.scene_words.extra()));
        buffers.push(("scene transmission", bytemuck::cast_slice(&self.scene_words.transmission)));
        buffers.push(("scene layers", bytemuck::cast_slice(&self.scene_words.layers)));
        buffers.push(("scene iridescence", bytemuck::cast_slice(&self.scene_words.iridescence)));
        buffers.push(("scene specular", bytemuck::cast_slice(&self.scene_words.specular)));
        buffers.push((
            "scene diffuse transmission",
            bytemuck::cast_slice(&self.scene_words.diffuse_transmission),
        ));
        buffers.push(("scene anisotropy", bytemuck::cast_slice(&self.scene_words.anisotropy)));
        buffers.push(("point light", bytemuck::cast_slice(&self.point_lights)));
        buffers.extend(self.emitter_words.as_deref().map(|w| ("emitter", w)));
        buffers.extend(self.environment.iter().map(|(label, w)| (*label, w.as_slice())));
        buffers
    }

    /// The device memory the render takes, part by part: the acceleration structure, the
    /// scene's geometry and materials, its lights, its environment, and the film `film` bytes.
    pub(super) fn device_parts(&self, film: u64) -> Vec<(&'static str, u64)> {
        let mut parts = vec![("BVH", 0), ("geometry and materials", 0), ("lights", 0), ("environment", 0)];
        for (what, words) in self.buffers() {
            let part = match what {
                w if w.starts_with("BVH") || w.starts_with("TLAS") || w == "instance" => 0,
                w if w.starts_with("scene") => 1,
                "point light" | "emitter" => 2,
                _ => 3,
            };
            parts[part].1 += size_of_val(words) as u64;
        }
        parts.push(("film", film));
        parts
    }

    /// [`GpuError::TooLarge`] for the first buffer over `limit` bytes (a device's own limit,
    /// where the scene was packed for a larger one).
    pub(super) fn check_limit(&self, limit: u64) -> Result<(), GpuError> {
        let buffers = self.buffers();
        for (what, words) in buffers {
            let bytes = size_of_val(words) as u64;
            if bytes > limit {
                return Err(GpuError::TooLarge { what: format!("the {what} buffer"), bytes, limit });
            }
        }
        Ok(())
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_accel::BuildOptions;

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
}
