//! The integrator's kernel: which features a scene needs ([`SceneFeatures`]), the WGSL composed
//! for them ([`shader_source`]: the generated declarations, the twins, and the integrator's
//! `shadow.wgsl`, `lights.wgsl` and `integrator.wgsl` with the `#if` blocks of those features
//! only), its bindings ([`binding_table`]), its workgroup size ([`group_size_for`]) and the
//! compute pipelines built from it.

use super::frame::{env_flags_wgsl, frame_flags_wgsl};
use super::packing::{light_bvh_consts_wgsl, point_light_flags_wgsl};
use super::{FrameParams, GpuPointLight};
use crate::film::FilmPrecision;
use crate::shared::{Binding, BindingKind, BindingTable, GpuStruct, wgsl_struct};
use crate::{GpuContext, GpuError, brdf, scene, traverse, wgsl};
use furnace_render::{LightSelection, RenderSettings, TriangleSampling};
use furnace_scene::{AlphaMode, Emitters, Scene};

#[cfg(doc)]
use super::GpuRenderer;

/// The shadow rays of the integrator: the traversal's hit filter (alpha masks, thin-walled
/// sheets crossed by shadow rays), their origins and the queue of the shadow rays a scattering
/// event takes.
const SHADOW_WGSL: &str = include_str!("../wgsl/shadow.wgsl");

/// The light samples of a scattering event, one function per light kind (point lights,
/// emitters, the sun's disc, the environment), and the MIS weights.
const LIGHTS_WGSL: &str = include_str!("../wgsl/lights.wgsl");

/// The path loop (`trace_samples` and its stages), the `main` entry point and adaptive
/// sampling's `converge`.
const INTEGRATOR_WGSL: &str = include_str!("../wgsl/integrator.wgsl");

/// Words of the counter buffer (`ray_counter`): rays, nodes and triangles as 64-bit pairs, then
/// fallbacks and the deepest stack.
pub(super) const COUNTER_WORDS: usize = 8;

/// Invocations in a workgroup as `integrator.wgsl` declares it (`GROUP_SIZE`, checked by
/// `tests/integrator.rs`): 256, the largest that every WebGPU device accepts
/// (`max_compute_invocations_per_workgroup`'s default), and faster than 64 or 128
/// (BENCHMARKS.md). Hardware adapters that accept [`HARDWARE_GROUP_SIZE`] get that instead
/// ([`group_size_for`]). The film is the same, bit for bit, for every size.
pub const GROUP_SIZE: u32 = 256;

/// Invocations in a workgroup on hardware adapters that accept it: 1024. The driver must fit a
/// whole workgroup on one multiprocessor, so on a GPU of 64 Ki registers per multiprocessor the
/// megakernel gets at most 64 registers per invocation instead of the 128 it takes in workgroups
/// of 256: twice the resident warps for some spilling, which pays on the emitter,
/// environment-map and interior scenes and costs nothing measurable on the Cornell box; 512
/// (still 128 registers) is slower than 256 (BENCHMARKS.md).
pub const HARDWARE_GROUP_SIZE: u32 = 1024;

/// The workgroup size of the integrator for a scene's features on an adapter
/// ([`default_group_size`] of its limits).
pub fn group_size_for(ctx: &GpuContext, features: SceneFeatures) -> u32 {
    let limits = ctx.device.limits();
    default_group_size(
        crate::context::is_hardware(&ctx.info),
        limits.max_compute_invocations_per_workgroup,
        limits.max_compute_workgroup_storage_size,
        features,
    )
}

/// The workgroup size for an adapter described by whether it is hardware and its two workgroup
/// limits (invocations, bytes of workgroup memory): [`HARDWARE_GROUP_SIZE`] on a hardware
/// adapter whose workgroups hold that many invocations and whose workgroup memory holds the
/// shader's per-invocation arrays at that size in at most half of it (the compiler takes
/// workgroup memory of its own for spilled registers, at 1024 invocations more than the
/// kernel's 16 KiB; with AOVs the kernel's arrays alone are 48 KiB), else [`GROUP_SIZE`]
/// (software adapters run an invocation's loop on a CPU thread: there is no occupancy to gain).
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

/// The integrator's shader as a pipeline compiles it: [`shader_source`] with workgroups of
/// `group_size` invocations and a traversal stack of `stack_size` node groups.
pub fn pipeline_source(
    precision: FilmPrecision,
    features: SceneFeatures,
    group_size: u32,
    stack_size: u32,
) -> String {
    let source = shader_source(precision, features);
    crate::traverse::with_stack_size(&with_group_size(&source, group_size), stack_size)
}

/// The constants of `layers.wgsl`: the sheen table's size and place in `turquin_table`, the
/// sheen's smallest α, the smallest probability of a layer and the largest `f32` below 1.
fn layers_consts_wgsl() -> String {
    use furnace_brdf::sheen::{SHEEN_ALPHA_MIN, SHEEN_TABLE_SIZE};
    format!(
        "const SHEEN_TABLE_SIZE: u32 = {SHEEN_TABLE_SIZE}u;\nconst SHEEN_TABLE_OFFSET: u32 = {}u;\n\
         const SHEEN_ALPHA_MIN: f32 = {SHEEN_ALPHA_MIN:?};\nconst LAYER_MIN_PROBABILITY: f32 = {:?};\n\
         const LAYER_ONE_BELOW: f32 = {:?};\n",
        crate::brdf::TURQUIN_TABLE_LEN,
        furnace_brdf::layered::MIN_LAYER_PROBABILITY,
        furnace_brdf::dielectric::ONE_BELOW,
    )
}

/// `source` (a [`shader_source`]) with workgroups of `n` invocations instead of [`GROUP_SIZE`].
pub fn with_group_size(source: &str, n: u32) -> String {
    source.replace(
        &format!("const GROUP_SIZE: u32 = {GROUP_SIZE}u;"),
        &format!("const GROUP_SIZE: u32 = {n}u;"),
    )
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
    if features.split_triangles {
        bindings.push(traverse::split_binding());
    }
    if features.instances {
        bindings.extend(traverse::instance_binding_list());
    }
    bindings.extend(scene::binding_list());
    bindings.push(Binding::read("turquin_table", "array<f32>"));
    bindings.push(Binding::read("point_lights", "array<PointLight>"));
    if features.transmission {
        bindings.push(Binding::read("scene_transmission", "array<SceneTransmission>"));
    }
    if features.clearcoat || features.sheen {
        bindings.push(Binding::read("scene_layers", "array<SceneLayers>"));
    }
    if features.iridescence {
        bindings.push(Binding::read("scene_iridescence", "array<SceneIridescence>"));
    }
    if features.specular_textures {
        bindings.push(Binding::read("scene_specular", "array<SceneSpecular>"));
    }
    if features.enabled("DIFFUSE_TRANSMISSION") {
        bindings.push(Binding::read("scene_diffuse_transmission", "array<SceneDiffuseTransmission>"));
    }
    if features.anisotropy {
        bindings.push(Binding::read("scene_anisotropy", "array<SceneAnisotropy>"));
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
    /// `scene_transmission` records), or a diffusely transmissive one (which needs the same
    /// scattering stage: rays that cross, media, light samples from behind).
    pub transmission: bool,
    /// A material shadow rays cross (a thin-walled sheet, multiplied by its T′; an η = 1 solid).
    pub thin_walled: bool,
    /// An alpha-blended material (stochastic transparency: the blend seed of path rays, the
    /// coverage of hits, shadow rays multiplied by 1 − coverage).
    pub blend: bool,
    /// A KHR_materials_unlit material (its colour added at a hit, where the path ends).
    pub unlit: bool,
    /// Emissive triangles are sampled by solid angle where that is precise
    /// ([`TriangleSampling::SolidAngle`]; with `emitters` only), else by area: the spherical
    /// triangle's code is composed only then.
    pub solid_angle_triangles: bool,
    /// Some material reads vertex attributes: a texture's UV set, or the scene's vertex colours
    /// (`scene_attributes` is read at hits; without, a hit's attributes are a constant).
    pub vertex_attributes: bool,
    /// Some texture samples a UV set other than UV0 (with `vertex_attributes`): only then does
    /// a hit interpolate the other sets and a lookup choose among them.
    pub uv_sets: bool,
    /// The scene has vertex colours (with `vertex_attributes`): only then are they read.
    pub vertex_colors: bool,
    /// Some material has a clear coat (KHR_materials_clearcoat; `scene_layers` records).
    pub clearcoat: bool,
    /// Some material has a sheen (KHR_materials_sheen; `scene_layers` records, the sheen
    /// albedo table after the Turquin tables).
    pub sheen: bool,
    /// Some material is iridescent (KHR_materials_iridescence; `scene_iridescence` records, the
    /// film's Fresnel in the brdf module).
    pub iridescence: bool,
    /// Some material has a KHR_materials_specular texture (`scene_specular` records, read at
    /// hits).
    pub specular_textures: bool,
    /// Some material transmits diffusely (KHR_materials_diffuse_transmission; with
    /// `transmission`, the `scene_diffuse_transmission` records).
    pub diffuse_transmission: bool,
    /// Some material is anisotropic (KHR_materials_anisotropy; `scene_anisotropy` records, the
    /// stretched GGX in the brdf module, the BSDF frame along the direction).
    pub anisotropy: bool,
    /// Some material disperses (KHR_materials_dispersion; with `transmission`): paths draw a
    /// wavelength at their first dispersive solid (the spectrum module and its tables).
    pub dispersion: bool,
    /// Shared meshes placed by instances (the two-level traversal: the TLAS and the instances
    /// bound, hits carried to world space by their instance).
    pub instances: bool,
    /// The BVH's triangle slots take two bindings (more than one binding holds:
    /// [`crate::traverse::BvhBuffers::is_split`]); set by the packing, not by the scene.
    pub split_triangles: bool,
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

    pub(super) fn with_emitters(scene: &Scene, settings: &RenderSettings, emitters: bool) -> Self {
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
            transmission: scene
                .materials
                .iter()
                .any(|m| m.is_transmissive() || m.diffuse_transmission.is_some()),
            thin_walled: scene.materials.iter().any(|m| m.passes_shadow_rays()),
            blend: scene.materials.iter().any(|m| m.alpha_mode == AlphaMode::Blend),
            unlit: scene.materials.iter().any(|m| m.unlit),
            solid_angle_triangles: emitters && settings.triangle_sampling == TriangleSampling::SolidAngle,
            vertex_attributes: scene.materials.iter().any(|m| m.uses_textures())
                || !scene.geometry.colors.is_empty(),
            uv_sets: scene.materials.iter().flat_map(|m| m.texture_refs()).any(|t| t.tex_coord > 0),
            vertex_colors: !scene.geometry.colors.is_empty(),
            clearcoat: scene.materials.iter().any(|m| m.layers.clearcoat.is_some()),
            sheen: scene.materials.iter().any(|m| m.layers.sheen.is_some()),
            iridescence: scene.materials.iter().any(|m| m.iridescence.is_some()),
            specular_textures: scene.materials.iter().any(|m| !m.specular_textures.is_empty()),
            diffuse_transmission: scene.materials.iter().any(|m| m.diffuse_transmission.is_some()),
            anisotropy: scene.materials.iter().any(|m| m.anisotropy.is_some()),
            dispersion: scene.disperses(),
            instances: !scene.instancing.is_empty(),
            split_triangles: false,
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
    /// `AOVS`, `ADAPTIVE`, `TRANSMISSION`, `THIN_WALLED`, `BLEND`, `UNLIT`, `SHADOW_FILTER` (shadow rays
    /// cross something: thin-walled sheets or blended surfaces), `TRACE_COUNTERS`, `VERTEX_ATTRIBUTES`, `UV_SETS`, `VERTEX_COLORS`, `CLEARCOAT`, `SHEEN`, `LAYERS` (either), `IRIDESCENCE`, `SPECULAR_TEXTURES`,
    /// `DIFFUSE_TRANSMISSION` (with `TRANSMISSION`), `ANISOTROPY`, `DISPERSION` (with `TRANSMISSION`), `LOBE_ESTIMATES` (the material's albedo
    /// estimate: `LAYERS` or `DIFFUSE_TRANSMISSION`),
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
            "BLEND" => self.blend,
            "UNLIT" => self.unlit,
            "SHADOW_FILTER" => (self.transmission && self.thin_walled) || self.blend,
            "SOLID_ANGLE_TRIANGLES" => self.emitters && self.solid_angle_triangles,
            "TRACE_COUNTERS" => self.trace_counters,
            "VERTEX_ATTRIBUTES" => self.vertex_attributes,
            "UV_SETS" => self.vertex_attributes && self.uv_sets,
            "VERTEX_COLORS" => self.vertex_attributes && self.vertex_colors,
            "CLEARCOAT" => self.clearcoat,
            "SHEEN" => self.sheen,
            "LAYERS" => self.clearcoat || self.sheen,
            "IRIDESCENCE" => self.iridescence,
            "SPECULAR_TEXTURES" => self.specular_textures,
            "DIFFUSE_TRANSMISSION" => self.transmission && self.diffuse_transmission,
            "ANISOTROPY" => self.anisotropy,
            "DISPERSION" => self.transmission && self.dispersion,
            "INSTANCES" => self.instances,
            "SPLIT_TRIANGLES" => self.split_triangles,
            "LOBE_ESTIMATES" => self.enabled("LAYERS") || self.enabled("DIFFUSE_TRANSMISSION"),
            "QUEUED_POINT_LIGHTS" => self.point_lights_queued() > 0,
            "ONE_POINT_LIGHT" => self.point_lights && self.one_point_light,
            _ => panic!("no scene feature {name} (an #if of the integrator's WGSL)"),
        }
    }
}

/// The composed WGSL of the integrator for a film precision (for tests and tools): the
/// generated declarations (sampler layout, `FRAME_*` flags, [`FrameParams`], the BSDF's, the
/// scene's and the traversal's structs and constants, the bindings of [`binding_table`]), the
/// twins, and the integrator's `shadow.wgsl`, `lights.wgsl` and `integrator.wgsl`, with the code
/// of the scene `features` only.
pub fn shader_source(precision: FilmPrecision, features: SceneFeatures) -> String {
    let generated = [
        furnace_render::layout::wgsl(),
        frame_flags_wgsl(),
        wgsl_struct::<FrameParams>(true),
        brdf::declarations(),
        scene::declarations(),
        traverse::declarations(),
        if features.instances { traverse::instance_declarations() } else { String::new() },
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
        if features.enabled("LAYERS") { layers_consts_wgsl() } else { String::new() },
        if features.enabled("DIFFUSE_TRANSMISSION") {
            format!(
                "const DT_MIN_PROBABILITY: f32 = {:?};\n",
                furnace_brdf::layered::MIN_TRANSMISSION_PROBABILITY
            )
        } else {
            String::new()
        },
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
    let integrator_feature = |name: &str| match name {
        "ADAPTIVE_ON_GPU" => features.adaptive && precision == FilmPrecision::F64,
        _ => features.enabled(name),
    };
    wgsl::compose(&[
        &generated,
        wgsl::SAMPLING,
        &wgsl::select(wgsl::BRDF, |name| features.enabled(name)),
        &if features.transmission {
            wgsl::select(wgsl::DIELECTRIC, |name| features.enabled(name))
        } else {
            String::new()
        },
        if features.enabled("DIFFUSE_TRANSMISSION") { wgsl::DIFFUSE_TRANSMISSION } else { "" },
        &if features.enabled("DISPERSION") {
            furnace_brdf::spectrum::wgsl() + wgsl::SPECTRUM
        } else {
            String::new()
        },
        &wgsl::select(wgsl::SCENE, |name| features.enabled(name)),
        &wgsl::select(wgsl::TRAVERSE, |name| features.enabled(name)),
        &light_bvh,
        &environment,
        &precision.wgsl(),
        &wgsl::select(wgsl::PATH, |name| features.enabled(name)),
        &if features.enabled("LAYERS") {
            wgsl::select(wgsl::LAYERS, |name| features.enabled(name))
        } else {
            String::new()
        },
        &wgsl::select(wgsl::MATERIAL, |name| features.enabled(name)),
        &wgsl::select(SHADOW_WGSL, integrator_feature),
        &wgsl::select(LIGHTS_WGSL, integrator_feature),
        &wgsl::select(INTEGRATOR_WGSL, integrator_feature),
    ])
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
    /// limit). Without the counters the driver unrolls the node test's loop over eight children,
    /// which speeds up traversal-bound scenes (BENCHMARKS.md), and software adapters compile the
    /// megakernel several times faster.
    NoLoopBounding,
    /// None of the checks (for profiling with the `pipeline_stats` example; the renderer never
    /// uses it).
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
            // `Kernel::new`.
            Self::Unchecked => wgpu::ShaderRuntimeChecks::unchecked(),
        }
    }
}

/// The integrator's bind group layout and compute pipelines, built by [`Kernel::new`].
#[derive(Debug)]
pub(super) struct Kernel {
    /// The layout of [`binding_table`]'s bindings.
    pub(super) layout: wgpu::BindGroupLayout,
    /// The `main` entry point: samples of the pixels of a dispatch.
    pub(super) main: wgpu::ComputePipeline,
    /// Adaptive sampling's test on the GPU (the `converge` entry point; `f64` films only).
    pub(super) converge: Option<wgpu::ComputePipeline>,
    /// Invocations per workgroup.
    pub(super) group_size: u32,
}

impl Kernel {
    /// The kernel for a film precision and the scene features, in workgroups of `group_size`
    /// invocations ([`group_size_for`]) with a traversal stack of `stack_size` node groups,
    /// compiled with wgpu's runtime `checks`.
    ///
    /// # Errors
    /// A validation error of the device (the shader, its layout or a pipeline).
    #[allow(unsafe_code)]
    pub(super) fn new(
        ctx: &GpuContext,
        precision: FilmPrecision,
        features: SceneFeatures,
        checks: ShaderChecks,
        group_size: u32,
        stack_size: u32,
    ) -> Result<Self, GpuError> {
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
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some("integrator"),
            source: wgpu::ShaderSource::Wgsl(
                pipeline_source(precision, features, group_size, stack_size).into(),
            ),
        };
        let module = match checks {
            ShaderChecks::Checked => device.create_shader_module(desc),
            // SAFETY: the checks turned off guard against what this shader does not do. Every loop
            // of the integrator ends (loops over counts, over the bits of a mask that each iteration
            // clears, a binary search, the traversal of a finite tree built here, the path loop
            // bounded by the bounces and MAX_SHEET_PASSES); with `Unchecked` (which the renderer
            // does not use), its local arrays are indexed within bounds (the traversal stack by a depth kept
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
        Ok(Self { layout, main: pipeline, converge, group_size })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pipeline's source has the stack and workgroup sizes it is given; the trace counters
    /// are composed only into the counting kernel.
    #[test]
    fn the_kernel_is_composed_for_its_sizes_and_counters() {
        let source = shader_source(FilmPrecision::F64, SceneFeatures::default());
        let stack = crate::traverse::with_stack_size(&source, 8);
        assert!(
            stack.contains("const TRV_STACK_SIZE: u32 = 8u;") && !stack.contains("TRV_STACK_SIZE: u32 = 16u")
        );
        let sized = pipeline_source(FilmPrecision::F64, SceneFeatures::default(), 1024, 8);
        assert!(
            sized.contains("const TRV_STACK_SIZE: u32 = 8u;")
                && sized.contains("const GROUP_SIZE: u32 = 1024u;")
        );
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
        assert_eq!(crate::integrator::tile_of(1024, 4), (16, 16));
        // What `group_size_for` weighs against half of a device's workgroup memory (48 KiB on
        // some hardware adapters): the kernel's arrays at 1024 fit without AOVs, not with them.
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
