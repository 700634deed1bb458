//! The uniform block of a dispatch ([`FrameParams`]): the camera, the lights' constants, the
//! sampler, the settings' flags, and where the dispatch lies in the pass. The renderer writes one
//! per dispatch, copied from the per-render part [`frame_params`] makes.

use crate::brdf;
use crate::sampling::SamplerParams;
use crate::shared::WgslType;
use furnace_accel::offset_scale_of_bounds;
use furnace_render::{LightSampling, RenderSettings};
use furnace_scene::{AlphaMode, Camera, Emitters, Projection, Scene};

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
        /// Invocations per pixel in a workgroup of [`GROUP_SIZE`](super::GROUP_SIZE) (a power of two): 1 — an
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
pub(super) fn frame_params_with(
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
            let (lo, hi) = scene.bounds();
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
pub(super) fn set_camera_params(p: &mut FrameParams, camera: &Camera) {
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
