//! furnace-scene: glTF 2.0 scenes flattened for a path tracer.
//!
//! * **Loading** ([`Scene::load`], [`Scene::from_slice`]): glTF 2.0 JSON and GLB (Khronos glTF
//!   2.0 specification) through the `gltf` crate's parser and validator; buffers, images and
//!   accessors are read here, with every offset, stride, count and index checked, so that no
//!   input panics and every error names the file and the glTF JSON path ([`SceneError`]).
//!   The default scene's node hierarchy is flattened into world-space indexed triangles
//!   ([`Geometry`]): instanced meshes expanded, shading normals transformed by the
//!   inverse-transpose and octahedral-encoded (Cigolle et al. 2014), per-face normals when a
//!   primitive has none, zero-area triangles dropped and counted; a NaN or infinite position
//!   (or one a node's transform takes beyond f32's range) is an error naming the primitive,
//!   its accessor and the vertex. Reads are bounded: only regular files, a scene of at most
//!   [`MAX_SCENE_FILE_BYTES`], a buffer up to its `byteLength`, image sizes checked from their
//!   headers ([`MAX_TEXTURE_SIZE`], [`MAX_ENVIRONMENT_TEXELS`]) before decoding; URIs relative to
//!   the scene (absolute paths refused).
//! * **Skins, morph targets, animation** (glTF 2.0 §3.7.2.2, §3.7.3, appendix C): posed when
//!   loaded, so every renderer sees posed triangles: morph targets add their weighted
//!   displacements to positions, normals and tangents; skinned vertices are placed by linear
//!   blend skinning (Σ wₖ · world(jointₖ) · inverseBindₖ); an animation chosen by
//!   [`LoadOptions::animation`] is sampled at [`LoadOptions::time`] (STEP, LINEAR with slerp,
//!   CUBICSPLINE) into the nodes' transforms and weights before they are flattened.
//! * **Compressed meshes**: `KHR_draco_mesh_compression` primitives decoded by draco-core (a
//!   Rust port of Google's Draco decoder), `EXT_meshopt_compression` and
//!   `KHR_meshopt_compression` buffer views by meshoptimizer's own decoders (the `meshopt`
//!   crate) before accessors read them; a corrupt or truncated payload is an error naming the
//!   primitive or the buffer view.
//! * **Materials** ([`Material`]): metallic-roughness with KHR_materials_specular and
//!   KHR_materials_emissive_strength, alpha MASK, double-sided; KHR_materials_pbrSpecularGlossiness
//!   converted to metallic-roughness (the Khronos converter's formulas); KHR_materials_variants
//!   selected by [`LoadOptions::variant`]; textures stored as 8-bit RGBA and
//!   decoded (sRGB → linear, IEC 61966-2-1) when sampled bilinearly with glTF wrap modes and
//!   KHR_texture_transform ([`TextureRef::sample_bilinear`]).
//! * **Image formats**: PNG, JPEG and the others of the `image` crate; WebP (EXT_texture_webp);
//!   KTX2 (KHR_texture_basisu: ETC1S and UASTC transcoded by Binomial's Basis Universal
//!   transcoder; plain 8-bit, 16-bit and float formats, BCn, ETC2 and ASTC blocks), mip level 0.
//!   AVIF (EXT_texture_avif) is not decoded: its fallback `source` is used. An image that cannot
//!   be used is a [`Warning`] and its textures are left out, or an error with
//!   [`LoadOptions::strict`].
//! * **Camera, sun and sky** ([`Camera`], [`Sun`]) with the reference renders' conventions
//!   (`tests/data/references/README.md`): camera looks down −Z, pixel `(i, j)` covers
//!   `[i, i+1] × [j, j+1]` with row 0 at the top; the sun is a KHR_lights_punctual directional
//!   light whose irradiance is `color × intensity` W/m² travelling along the node's −Z; the sky is
//!   `scenes[i].extras.background_radiance_rgb`.
//! * **Environment maps** ([`Environment`], [`EnvironmentMap`]): latitude-longitude `.hdr` /
//!   `.exr` images from `scenes[i].extras.environment = {"uri", "intensity"}` or set by the
//!   caller, looked up texel-centred as the references are, importance-sampled by
//!   [`EnvironmentSampler`]; [`EnvironmentMap::studio`] is the neutral light for scenes without
//!   one ([`Scene::has_own_light`]).
//! * **Built-in scenes** ([`builtin`]): the reference Cornell box and a white-furnace sphere.
//!
//! Unsupported features (transmission, point lights, BLEND...) give one [`Warning`] each, never a
//! failure; a *required* unsupported extension (e.g. `KHR_materials_iridescence`) is an error.
//!
//! ```
//! use furnace_scene::{Scene, builtin};
//! let scene: Scene = builtin::cornell_box()?;
//! assert_eq!(scene.geometry.triangle_count(), 20_516);
//! let camera = scene.default_camera();
//! let ray = camera.generate_ray(glam::Vec2::new(128.0, 128.0), 256, 256);
//! assert!(ray.direction.is_normalized());
//! assert!(scene.sun().is_some());
//! # Ok::<(), furnace_scene::SceneError>(())
//! ```

mod accessor;
pub mod builtin;
mod camera;
mod emitter;
mod environment;
mod error;
mod file;
mod forest;
mod geometry;
mod hash;
mod instancing;
mod light;
mod light_bvh;
mod load;
mod material;
mod surface;
mod texture;

pub use camera::{Camera, CameraRays, DEFAULT_YFOV, FLAT_THICKNESS, Projection, Ray};
pub use emitter::{Emitters, luminance, triangle_area};
pub use environment::{
    Environment, EnvironmentError, EnvironmentMap, EnvironmentSample, EnvironmentSampler,
    MAX_ENVIRONMENT_TEXELS, YRotation, direction_to_uv, uv_to_direction,
};
pub use error::{SceneError, Warning};
pub use geometry::{
    Geometry, MAX_UV_SETS, VertexAttributes, decode_color, decode_tangent, encode_color, encode_tangent,
    generate_tangents, oct_decode, oct_encode,
};
pub use instancing::{Instance, Instancing};
pub use light::{Light, PointLight, PointLightDistribution, Sky, SpotCone, Sun};
pub use light_bvh::{LEAF as LIGHT_BVH_LEAF, LightBounds, LightBvh, LightBvhNode};
pub use load::{
    ExtensionUse, MAX_COORDINATE, MAX_INSTANCES, MAX_TRIANGLES, MIN_COORDINATE, SUPPORTED_EXTENSIONS,
};
pub use material::{
    AlphaMode, Anisotropy, ClearcoatLayer, DiffuseTransmissionFactors, Iridescence, Material, MaterialLayers,
    MaterialSample, SheenLayer, SpecularTextures,
};
pub use surface::{SurfacePoint, blend_keeps, blend_seed, geometric_normal, valid_reflection_normal};
pub use texture::{
    ColorSpace, Image, MAX_TEXTURE_SIZE, Texture, TextureRef, TextureTransform, WrapMode, srgb_to_linear,
};

use std::path::Path;

/// The largest scene file [`Scene::load`] reads: 4 GiB, the most a GLB container can hold (its
/// length field is a `u32`). A `.gltf`'s JSON has no such limit in the format, but JSON that
/// large (its buffers are data URIs or separate files) is beyond any real asset, and the loader
/// holds the whole file and its parsed document in memory.
pub const MAX_SCENE_FILE_BYTES: u64 = u32::MAX as u64;

/// A scene ready to render: world-space triangles, materials, textures, cameras, sun and sky.
/// All fields are public: override the lights or cameras by assigning them ([`Scene::set_sun`],
/// [`Scene::set_sky`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The file it came from, or `<built-in NAME>`.
    pub name: String,
    /// The triangles.
    pub geometry: Geometry,
    /// Which of them are meshes placed by instances, in object space (empty: all are in world
    /// space).
    pub instancing: Instancing,
    /// Materials; the last one is glTF's default material, used by primitives without one.
    pub materials: Vec<Material>,
    /// Textures (glTF `textures`, same indices).
    pub textures: Vec<Texture>,
    /// Images (glTF `images`, same indices; images no material uses are 1×1 white).
    pub images: Vec<Image>,
    /// Cameras in node traversal order (depth-first, children in file order).
    pub cameras: Vec<Camera>,
    /// The lights: the first KHR_lights_punctual directional light as a [`Light::Sun`], the
    /// scene's `extras.background_radiance_rgb` as a [`Light::Sky`] (none: black sky).
    pub lights: Vec<Light>,
    /// What the loader ignored or repaired, each reported once.
    pub warnings: Vec<Warning>,
    /// Degenerate (zero-area) triangles dropped while loading (non-finite positions are an
    /// error).
    pub dropped_triangles: usize,
    /// The glTF extensions the file lists (none for a scene not loaded from glTF). What the
    /// file says, not what renders: not part of [`Scene::content_hash`].
    pub extensions: Vec<ExtensionUse>,
    /// The file's KHR_materials_variants names, in file order (empty without the extension).
    /// Not part of [`Scene::content_hash`]: the variant loaded shows in the triangles'
    /// materials, which are.
    pub variants: Vec<String>,
    /// The file's animations, in file order (empty without any). Not part of
    /// [`Scene::content_hash`]: the pose loaded shows in the geometry, cameras and lights,
    /// which are.
    pub animations: Vec<AnimationInfo>,
    /// The animation the scene was posed by and the time, in seconds, it was sampled at
    /// ([`LoadOptions::animation`], [`LoadOptions::time`]); `None`: the nodes' own transforms
    /// and morph weights.
    pub posed_by: Option<(usize, f32)>,
}

/// One of a glTF file's animations, as [`Scene::animations`] lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationInfo {
    /// Its `name` (`""` without one: select it by its index).
    pub name: String,
    /// The last keyframe time of its samplers, in seconds (0 when none can be read).
    pub duration: f32,
}

/// How [`Scene::load_with`] treats what it can work around, which material variant it loads,
/// and the animation pose.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadOptions {
    /// A missing, unreadable or undecodable image is an error. Without it (the default) it is a
    /// [`Warning`] naming the image and the reason, and the material slots that sample the
    /// image are left empty: those materials render with their factors alone.
    pub strict: bool,
    /// The KHR_materials_variants variant to load, by name (or, when no variant has that name,
    /// by index): each primitive whose mappings list it takes the mapped material, the others
    /// keep their own. `None` (the default) loads every primitive's own material. A value that
    /// names no variant of the file is [`SceneError::UnknownVariant`].
    pub variant: Option<String>,
    /// The animation to pose the scene by, by name (or, when no animation has that name, by
    /// index): its node translation, rotation, scale and morph weight channels sampled at
    /// [`LoadOptions::time`] (0 without it). A value that names no animation of the file is
    /// [`SceneError::UnknownAnimation`]. `None` (the default): animation 0 if `time` is given,
    /// else no animation (the nodes' own transforms and weights).
    pub animation: Option<String>,
    /// The time, in seconds, the animation is sampled at (each channel clamped to its keyframes'
    /// range). Given without [`LoadOptions::animation`], the file's first animation; a file
    /// without animations is then [`SceneError::UnknownAnimation`].
    pub time: Option<f32>,
}

/// Sizes of a scene, for logs and benchmarks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneStats {
    /// Triangles kept.
    pub triangles: usize,
    /// Vertices stored.
    pub vertices: usize,
    /// Materials (including the default one).
    pub materials: usize,
    /// Whether per-vertex UVs are stored (some material uses a texture).
    pub stores_uvs: bool,
    /// Bytes of [`Geometry`] arrays.
    pub geometry_bytes: usize,
    /// Bytes of texels.
    pub texture_bytes: usize,
    /// `geometry_bytes / triangles`.
    pub bytes_per_triangle: f64,
    /// Degenerate (zero-area) triangles dropped.
    pub dropped_triangles: usize,
    /// Meshes stored once and placed by instances ([`Instancing::meshes`]).
    pub meshes: usize,
    /// Their placements.
    pub instances: usize,
    /// The triangles the image shows: the world-space ones plus each instance's mesh.
    pub instanced_triangles: u64,
    /// Bytes of the instances (transform, inverse, normal matrix, mesh).
    pub instance_bytes: usize,
}

impl Scene {
    /// The material index of triangle `t`, clamped into `materials` (a triangle without one
    /// takes the last material, the loader's default).
    pub fn triangle_material(&self, t: usize) -> usize {
        let last = self.materials.len().saturating_sub(1);
        self.geometry.triangle_materials.get(t).map_or(last, |&m| (m as usize).min(last))
    }

    /// Loads a `.gltf` or `.glb` file; buffers and images are resolved relative to it. Only a
    /// regular file of at most [`MAX_SCENE_FILE_BYTES`] is read (a FIFO, a device or a
    /// directory is an error, not a wait or an endless read).
    ///
    /// An image that is missing, unreadable or undecodable is a [`Warning`] and the material
    /// slots that sample it are left empty (see [`LoadOptions`]; [`Scene::load_with`] can make
    /// it an error).
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] with `options`.
    pub fn load_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let bytes = file::read_regular(path, MAX_SCENE_FILE_BYTES, "a scene file")
            .map_err(|source| SceneError::Io { file: file.clone(), what: "the scene file".into(), source })?;
        load::load(&bytes, &file, Some(path.parent().unwrap_or(Path::new("."))), options)
    }

    /// Loads glTF or GLB bytes named `name` (for messages). External URIs are an error; data
    /// URIs and the GLB `BIN` chunk work.
    pub fn from_slice(bytes: &[u8], name: &str) -> Result<Self, SceneError> {
        Self::from_slice_with(bytes, name, &LoadOptions::default())
    }

    /// [`Scene::from_slice`] with `options`.
    pub fn from_slice_with(bytes: &[u8], name: &str, options: &LoadOptions) -> Result<Self, SceneError> {
        load::load(bytes, name, None, options)
    }

    /// Camera `index` of [`Scene::cameras`], if there is one.
    pub fn camera(&self, index: usize) -> Option<Camera> {
        self.cameras.get(index).copied()
    }

    /// The first camera, or without one [`Camera::frame_bounds`] of the geometry.
    pub fn default_camera(&self) -> Camera {
        self.camera(0).unwrap_or_else(|| {
            let (lo, hi) = self.bounds();
            Camera::frame_bounds(lo, hi)
        })
    }

    /// Multiplies every length of the scene by `s` (> 0): vertex positions, camera positions and
    /// orthographic cameras' extents. Directions (normals, tangents, camera orientations, the
    /// sun's), fields of view and radiometry do not change, so a renderer with scale-robust ray
    /// offsets renders the same image (the stability suites check it from 1e-12 to 1e12).
    ///
    /// # Panics
    /// If `s` is not finite and positive (a mirror or a collapse is not a change of unit).
    pub fn scale_lengths(&mut self, s: f32) {
        assert!(s.is_finite() && s > 0.0, "scale_lengths: the factor must be finite and > 0, got {s}");
        for p in &mut self.geometry.positions {
            *p *= s;
        }
        // M·(s·p) = s·(M·p) for the linear part: only the translations scale.
        for i in &mut self.instancing.instances {
            let mut world = i.world_from_object;
            world.translation *= s;
            *i = Instance::new(i.mesh, world.into()).unwrap_or(*i);
        }
        for c in &mut self.cameras {
            c.world_from_camera.translation *= s;
            if let Projection::Orthographic { xmag, ymag } = &mut c.projection {
                *xmag *= s;
                *ymag *= s;
            }
        }
    }

    /// Sizes and bytes per triangle.
    pub fn stats(&self) -> SceneStats {
        let g = &self.geometry;
        let geometry_bytes = g.bytes();
        SceneStats {
            triangles: g.triangle_count(),
            vertices: g.positions.len(),
            materials: self.materials.len(),
            stores_uvs: !g.uvs.is_empty(),
            geometry_bytes,
            texture_bytes: self.images.iter().map(|i| i.texels.len() * 4).sum(),
            bytes_per_triangle: geometry_bytes as f64 / g.triangle_count().max(1) as f64,
            dropped_triangles: self.dropped_triangles,
            meshes: self.instancing.meshes.len(),
            instances: self.instancing.instances.len(),
            instanced_triangles: if self.instancing.is_empty() {
                g.triangle_count() as u64
            } else {
                u64::from(self.instancing.world_triangles) + self.instancing.instanced_triangles()
            },
            instance_bytes: self.instancing.instances.len() * size_of::<Instance>(),
        }
    }
}
