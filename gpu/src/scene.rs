//! The scene on the GPU: the Rust side of [`crate::wgsl::SCENE`] — the storage buffers a
//! [`Scene`] becomes, the declarations a shader adds to read them, and the bind group entries.
//!
//! Six read-only storage buffers, each checked against the adapter's per-binding limit
//! ([`GpuError::TooLarge`] names the one that does not fit). One code path for every adapter:
//! no binding arrays, no sampled textures; all images live in one buffer of RGBA8 texels
//! filtered by hand in WGSL.
//!
//! | WGSL name | element | bytes | holds |
//! |---|---|---|---|
//! | `scene_triangles` | [`GpuSceneTriangle`] | 16 per triangle | vertex indices, material index (clamped like furnace-cpu's) |
//! | `scene_vertices` | [`GpuVertex`] | 16 per vertex | world position, octahedral shading normal (`oct_encode`, decoded in WGSL as `oct_decode`) |
//! | `scene_attributes` | `vec2<u32>` | 8 per UV set and vertex, **only when some material is textured**, + 8 per vertex **only with vertex colours** | the UV sets materials sample (`f32` bits), then `COLOR_0` as RGBA unorm16, vertex by vertex (the stride in each material's flags) |
//! | `scene_tangents` | `vec2<u32>` | 8 per vertex, **only when some material is normal-mapped or anisotropic** | snorm16 tangent + handedness, as `Geometry::tangents` |
//! | `scene_materials` | [`GpuMaterial`] | 256 per material | factors, flags, four resolved [`GpuTextureRef`]s |
//! | `scene_texels` | `u32` | 4 per texel of each **used** image, + 2 KiB | the sRGB and linear decode tables (512 `f32`), then RGBA8 texels (R in the low byte) |
//!
//! An absent buffer is bound as one zeroed element (bindings cannot be empty).
//!
//! A texture reference holds what the lookup needs (where its image starts in `scene_texels`,
//! its size, wrap modes, colour space, KHR_texture_transform matrix) so that a lookup reads one
//! record and no texture or image table. Texels are decoded through the tables at the head of
//! `scene_texels`, which hold `srgb_to_linear(i/255)` and `i/255` as computed by
//! furnace-scene: decoding is bit-identical to the CPU's; only the bilinear weights and the
//! texture transform differ by float rounding (see `scene.wgsl`).
//!
//! A shader that reads the scene composes [`crate::wgsl::SCENE`] (through [`crate::wgsl::select`]) and declares the buffers with
//! [`bindings`]; the traversal's alpha callback is then one line:
//!
//! ```wgsl
//! fn hit_filter(triangle_id: u32, u: f32, v: f32) -> bool { return scene_alpha_passes(triangle_id, u, v); }
//! ```

use bytemuck::Zeroable;
use furnace_scene::{AlphaMode, ColorSpace, Scene, Texture, TextureRef, WrapMode, srgb_to_linear};

use crate::shared::{Binding, BindingTable, WgslType, wgsl_struct};
use crate::{GpuContext, GpuError};

mod extensions;

pub use extensions::{
    GpuAnisotropy, GpuDiffuseTransmission, GpuIridescence, GpuLayers, GpuSpecularTextures, GpuTransmission,
};
use extensions::{
    anisotropy_record, diffuse_transmission_record, iridescence_record, layers_record, specular_record,
    transmission_record,
};

/// Number of bindings the scene uses ([`bindings`], [`GpuScene::layout_entries`]).
pub const BINDING_COUNT: u32 = 6;

/// Words of decode tables before the first texel.
pub const TABLE_WORDS: u32 = 512;

crate::wgsl_consts! {
    /// The WGSL `const` declarations of the constants below (`SCENE_` + the Rust name),
    /// composed by [`declarations`].
    fn consts_wgsl prefix "SCENE_";
    /// Word of `scene_texels` where the sRGB decode table starts (`srgb_to_linear(i / 255)`).
    pub const SRGB_TABLE: u32 = 0;
    /// Word of `scene_texels` where the linear decode table starts (`i / 255`).
    pub const LINEAR_TABLE: u32 = 256;
    /// [`GpuMaterial::flags`] bits 0–1: the alpha mode ([`ALPHA_OPAQUE`], [`ALPHA_MASK`],
    /// [`ALPHA_BLEND`]).
    pub const ALPHA_MODE_BITS: u32 = 3;
    /// Alpha mode code of [`AlphaMode::Opaque`].
    pub const ALPHA_OPAQUE: u32 = 0;
    /// Alpha mode code of [`AlphaMode::Mask`] (cutoff in [`GpuMaterial::alpha_cutoff`]).
    pub const ALPHA_MASK: u32 = 1;
    /// Alpha mode code of [`AlphaMode::Blend`] (stochastic transparency, as on the CPU).
    pub const ALPHA_BLEND: u32 = 2;
    /// [`GpuMaterial::flags`]: `doubleSided`.
    pub const MATERIAL_DOUBLE_SIDED: u32 = 4;
    /// [`GpuMaterial::flags`]: some slot has a texture (`Material::uses_textures`): the hit needs
    /// its UV.
    pub const MATERIAL_TEXTURED: u32 = 8;
    /// [`GpuMaterial::flags`]: the scene has vertex colours (`COLOR_0`, the last word of each
    /// vertex's attributes), which multiply the base colour.
    pub const MATERIAL_VERTEX_COLOR: u32 = 16;
    /// [`GpuMaterial::flags`]: KHR_materials_unlit (the base colour seen as is, nothing
    /// reflected).
    pub const MATERIAL_UNLIT: u32 = 32;
    /// [`GpuMaterial::flags`] bits 8–10: the UV sets the material's textures sample (the highest
    /// `texCoord` + 1).
    pub const MATERIAL_UV_SETS_SHIFT: u32 = 8;
    /// [`GpuMaterial::flags`] bits 12–14: `scene_attributes` words per vertex (the scene's UV
    /// sets, + 1 with vertex colours; the same in every material).
    pub const MATERIAL_STRIDE_SHIFT: u32 = 12;

    /// [`GpuTextureRef::flags`]: the slot has a texture (otherwise a lookup is opaque white).
    pub const TEXTURE_PRESENT: u32 = 1;
    /// [`GpuTextureRef::flags`]: RGB is sRGB-encoded ([`ColorSpace::Srgb`]); alpha is always linear.
    pub const TEXTURE_SRGB: u32 = 2;
    /// [`GpuTextureRef::flags`]: apply [`GpuTextureRef::transform`] (KHR_texture_transform).
    pub const TEXTURE_TRANSFORM: u32 = 4;
    /// [`GpuTextureRef::flags`] bits 4–5: `wrapS` ([`WRAP_REPEAT`], [`WRAP_CLAMP`], [`WRAP_MIRRORED`]).
    pub const WRAP_S_SHIFT: u32 = 4;
    /// [`GpuTextureRef::flags`] bits 6–7: `wrapT`.
    pub const WRAP_T_SHIFT: u32 = 6;
    /// [`GpuTextureRef::flags`] bits 8–9: the UV set (`texCoord`).
    pub const TEXTURE_UV_SET_SHIFT: u32 = 8;
    /// Wrap code of [`WrapMode::Repeat`].
    pub const WRAP_REPEAT: u32 = 0;
    /// Wrap code of [`WrapMode::ClampToEdge`].
    pub const WRAP_CLAMP: u32 = 1;
    /// Wrap code of [`WrapMode::MirroredRepeat`].
    pub const WRAP_MIRRORED: u32 = 2;

    /// [`GpuTransmission::flags`]: the material transmits (`transmissionFactor` > 0).
    pub const TRANSMISSIVE: u32 = 1;
    /// [`GpuTransmission::flags`]: it bounds a solid (KHR_materials_volume); otherwise a sheet.
    pub const VOLUME: u32 = 2;
}

crate::gpu_struct! {
    /// A triangle: its three vertex indices and its material (WGSL `SceneTriangle`).
    pub struct GpuSceneTriangle as "SceneTriangle" {
        /// First vertex.
        pub i0: u32 => WgslType::U32,
        /// Second vertex.
        pub i1: u32 => WgslType::U32,
        /// Third vertex.
        pub i2: u32 => WgslType::U32,
        /// Index into `scene_materials`.
        pub material: u32 => WgslType::U32,
    }
}

crate::gpu_struct! {
    /// A vertex: world position and octahedral-encoded unit shading normal (WGSL `SceneVertex`,
    /// `vec3<f32>` + `u32` in 16 bytes).
    pub struct GpuVertex as "SceneVertex" {
        /// World-space position.
        pub position: [f32; 3] => WgslType::VEC3_F32,
        /// `furnace_scene::oct_encode` of the shading normal.
        pub normal: u32 => WgslType::U32,
    }
}

crate::gpu_struct! {
    /// One material slot's texture, resolved (WGSL `SceneTextureRef`): where its image is in
    /// `scene_texels`, its size, wrap modes, colour space and texture transform.
    pub struct GpuTextureRef as "SceneTextureRef" {
        /// Index in `scene_texels` of texel (0, 0) (≥ [`TABLE_WORDS`]).
        pub texel_offset: u32 => WgslType::U32,
        /// Image width in texels.
        pub width: u32 => WgslType::U32,
        /// Image height in texels.
        pub height: u32 => WgslType::U32,
        /// [`TEXTURE_PRESENT`], [`TEXTURE_SRGB`], [`TEXTURE_TRANSFORM`], wrap codes.
        pub flags: u32 => WgslType::U32,
        /// `TextureTransform::matrix()` as computed on the CPU, its first two rows column by
        /// column: `uv' = (t[0]·u + t[2]·v + t[4], t[1]·u + t[3]·v + t[5])`.
        pub transform: [f32; 6] => WgslType::ARRAY_F32_6,
            /// Rust-only zeros up to 48 bytes (WGSL pads by itself).
        pub pad: [u32; 2] => WgslType::PAD,
    }
}

crate::gpu_struct! {
    /// A material as the WGSL reads it (`SceneMaterial`): `furnace_scene::Material` with its
    /// textures resolved. 256 bytes.
    pub struct GpuMaterial as "SceneMaterial" {
        /// `baseColorFactor`, linear RGBA.
        pub base_color_factor: [f32; 4] => WgslType::VEC4_F32,
        /// Emitted radiance factor (`emissiveFactor × emissiveStrength`).
        pub emissive: [f32; 3] => WgslType::VEC3_F32,
        /// `normalTexture.scale`.
        pub normal_scale: f32 => WgslType::F32,
        /// KHR_materials_specular `specularColorFactor`.
        pub specular_color_factor: [f32; 3] => WgslType::VEC3_F32,
        /// KHR_materials_specular `specularFactor`.
        pub specular_factor: f32 => WgslType::F32,
        /// `metallicFactor`.
        pub metallic_factor: f32 => WgslType::F32,
        /// `roughnessFactor`.
        pub roughness_factor: f32 => WgslType::F32,
        /// `alphaCutoff` (MASK only; 0 otherwise).
        pub alpha_cutoff: f32 => WgslType::F32,
        /// Alpha mode ([`ALPHA_MODE_BITS`]), [`MATERIAL_DOUBLE_SIDED`], [`MATERIAL_TEXTURED`].
        pub flags: u32 => WgslType::U32,
        /// `baseColorTexture`.
        pub base_color_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `metallicRoughnessTexture`.
        pub metallic_roughness_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `normalTexture` (absent when the scene stores no tangents: the CPU then skips the normal
        /// map too).
        pub normal_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
        /// `emissiveTexture`.
        pub emissive_texture: GpuTextureRef => GpuTextureRef::wgsl_type(),
    }
}

const _: () = assert!(size_of::<GpuSceneTriangle>() == 16);
const _: () = assert!(size_of::<GpuVertex>() == 16);
const _: () = assert!(size_of::<GpuTextureRef>() == 48);
const _: () = assert!(size_of::<GpuMaterial>() == 256);

/// The WGSL declarations of the six scene buffers at `@group(group)`, bindings `first` …
/// `first + 5`, in the order of the [module table](self).
pub fn bindings(group: u32, first: u32) -> String {
    declarations() + &BindingTable::new(group, first, binding_list()).wgsl()
}

/// The WGSL declarations [`crate::wgsl::SCENE`] needs besides its bindings: the `SCENE_*`
/// constants and the four structs of the scene buffers, generated from the Rust.
pub fn declarations() -> String {
    [
        consts_wgsl(),
        wgsl_struct::<GpuSceneTriangle>(false),
        wgsl_struct::<GpuVertex>(false),
        wgsl_struct::<GpuTextureRef>(false),
        wgsl_struct::<GpuMaterial>(false),
        wgsl_struct::<GpuTransmission>(false),
        wgsl_struct::<GpuLayers>(false),
        wgsl_struct::<GpuIridescence>(false),
        wgsl_struct::<GpuSpecularTextures>(false),
        wgsl_struct::<GpuAnisotropy>(false),
        wgsl_struct::<GpuDiffuseTransmission>(false),
    ]
    .concat()
}

/// The scene's six read-only storage bindings, in [`GpuScene::resources`] order.
pub fn binding_list() -> Vec<Binding> {
    vec![
        Binding::read("scene_triangles", "array<SceneTriangle>"),
        Binding::read("scene_vertices", "array<SceneVertex>"),
        Binding::read("scene_attributes", "array<vec2<u32>>"),
        Binding::read("scene_tangents", "array<vec2<u32>>"),
        Binding::read("scene_materials", "array<SceneMaterial>"),
        Binding::read("scene_texels", "array<u32>"),
    ]
}

/// A slot's texture reference and texture, if both indices (texture, image) are in range.
fn resolve<'a>(scene: &'a Scene, r: &'a Option<TextureRef>) -> Option<(&'a TextureRef, &'a Texture)> {
    let r = r.as_ref()?;
    let tex = scene.textures.get(r.texture as usize)?;
    scene.images.get(tex.image as usize).map(|_| (r, tex))
}

fn wrap_code(w: WrapMode) -> u32 {
    match w {
        WrapMode::Repeat => WRAP_REPEAT,
        WrapMode::ClampToEdge => WRAP_CLAMP,
        WrapMode::MirroredRepeat => WRAP_MIRRORED,
    }
}

/// A scene packed into the words of the six storage buffers (CPU side; [`GpuScene::upload`]
/// copies them to the device, parity tests hand them to their test kernels).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneBuffers {
    /// `scene_triangles`.
    pub triangles: Vec<GpuSceneTriangle>,
    /// `scene_vertices`.
    pub vertices: Vec<GpuVertex>,
    /// `scene_attributes` (empty when no material is textured and the scene has no vertex
    /// colours).
    pub attributes: Vec<[u32; 2]>,
    /// `scene_tangents` (empty when no material is normal-mapped or anisotropic).
    pub tangents: Vec<[u32; 2]>,
    /// `scene_materials`.
    pub materials: Vec<GpuMaterial>,
    /// `scene_texels`: [`TABLE_WORDS`] words of decode tables, then each used image's texels.
    pub texels: Vec<u32>,
    /// Images stored (those some material slot uses).
    pub image_count: usize,
    /// `scene_transmission`, one record per material; empty unless some material transmits.
    pub transmission: Vec<GpuTransmission>,
    /// `scene_layers`, one record per material; empty unless some material has a coat or a
    /// sheen.
    pub layers: Vec<GpuLayers>,
    /// `scene_iridescence`, one record per material; empty unless some material is iridescent.
    pub iridescence: Vec<GpuIridescence>,
    /// `scene_specular`, one record per material; empty unless some material has a
    /// KHR_materials_specular texture.
    pub specular: Vec<GpuSpecularTextures>,
    /// `scene_diffuse_transmission`, one record per material; empty unless some material
    /// transmits diffusely.
    pub diffuse_transmission: Vec<GpuDiffuseTransmission>,
    /// `scene_anisotropy`, one record per material; empty unless some material is anisotropic.
    pub anisotropy: Vec<GpuAnisotropy>,
}

/// Which optional vertex attributes a scene's shading reads: UVs only when some material is
/// textured, tangents only when some material has a normal map or an anisotropy direction (and
/// the scene has tangents), colours when the scene has them.
#[derive(Clone, Copy)]
struct Kept {
    tangents: bool,
    /// UV sets stored per vertex (0 unless textured).
    uv_sets: u32,
    colors: bool,
}

impl Kept {
    fn of(scene: &Scene) -> Self {
        let g = &scene.geometry;
        let textured = scene.materials.iter().any(|m| m.uses_textures());
        Self {
            tangents: !g.tangents.is_empty()
                && scene.materials.iter().any(|m| {
                    m.normal_texture.is_some()
                        || m.layers.clearcoat.as_ref().is_some_and(|c| c.normal_texture.is_some())
                        || m.anisotropy.is_some()
                }),
            uv_sets: if textured { g.uv_sets().min(furnace_scene::MAX_UV_SETS) as u32 } else { 0 },
            colors: !g.colors.is_empty(),
        }
    }

    /// `scene_attributes` words per vertex.
    fn stride(self) -> u32 {
        self.uv_sets + u32::from(self.colors)
    }
}

/// Checks the geometry and material buffers against `limit` bytes before any is allocated.
fn check_sizes(scene: &Scene, kept: Kept, limit: u64) -> Result<(), GpuError> {
    let check = |what: String, bytes: u64| {
        if bytes > limit { Err(GpuError::TooLarge { what, bytes, limit }) } else { Ok(()) }
    };
    let g = &scene.geometry;
    let nv = g.positions.len() as u64;
    let nt = g.triangles.len() as u64;
    check(format!("the scene's triangle buffer ({nt} triangles)"), nt * 16)?;
    check(format!("the scene's vertex buffer ({nv} vertices)"), nv * 16)?;
    if kept.stride() > 0 {
        check(
            format!("the scene's vertex attribute buffer ({nv} vertices)"),
            nv * 8 * u64::from(kept.stride()),
        )?;
    }
    if kept.tangents {
        check(format!("the scene's tangent buffer ({nv} vertices)"), nv * 8)?;
    }
    check(format!("the scene's material buffer ({} materials)", scene.materials.len()), {
        scene.materials.len() as u64 * 256
    })
}

/// The images some material slot uses, in first-use order, and where each starts in the texel
/// buffer (after the two 256-entry decode tables).
struct ImageLayout {
    offset: Vec<Option<u64>>,
    used: Vec<usize>,
    words: u64,
}

impl ImageLayout {
    fn of(scene: &Scene, kept: Kept, limit: u64) -> Result<Self, GpuError> {
        let mut offset: Vec<Option<u64>> = vec![None; scene.images.len()];
        let mut used = Vec::new();
        let mut words = u64::from(TABLE_WORDS);
        for m in &scene.materials {
            let slots = [
                &m.base_color_texture,
                &m.metallic_roughness_texture,
                if kept.tangents { &m.normal_texture } else { &None },
                &m.emissive_texture,
                &m.transmission_texture,
                &m.specular_textures.specular,
                &m.specular_textures.color,
            ];
            let clearcoat = m.layers.clearcoat.iter().flat_map(|c| {
                [&c.texture, &c.roughness_texture, if kept.tangents { &c.normal_texture } else { &None }]
            });
            let sheen = m.layers.sheen.iter().flat_map(|s| [&s.color_texture, &s.roughness_texture]);
            let film = m.iridescence.iter().flat_map(|i| [&i.texture, &i.thickness_texture]);
            let dt = m.diffuse_transmission.iter().flat_map(|d| [&d.texture, &d.color_texture]);
            let anisotropy = m.anisotropy.iter().map(|a| &a.texture);
            for slot in
                slots.into_iter().chain(clearcoat).chain(sheen).chain(film).chain(dt).chain(anisotropy)
            {
                if let Some((_, tex)) = resolve(scene, slot) {
                    let i = tex.image as usize;
                    if offset[i].is_none() {
                        offset[i] = Some(words);
                        used.push(i);
                        let img = &scene.images[i];
                        words += u64::from(img.width) * u64::from(img.height);
                    }
                }
            }
        }
        let texel_limit = limit.min(4 << 32);
        if words * 4 > texel_limit {
            return Err(GpuError::TooLarge {
                what: format!("the scene's texel buffer ({} images)", used.len()),
                bytes: words * 4,
                limit: texel_limit,
            });
        }
        Ok(Self { offset, used, words })
    }

    /// The GPU record of a texture slot (zero: untextured).
    fn texture_ref(&self, scene: &Scene, slot: &Option<TextureRef>) -> GpuTextureRef {
        let Some((r, tex)) = resolve(scene, slot) else { return GpuTextureRef::zeroed() };
        let img = &scene.images[tex.image as usize];
        let mut flags = TEXTURE_PRESENT
            | (wrap_code(tex.wrap_s) << WRAP_S_SHIFT)
            | (wrap_code(tex.wrap_t) << WRAP_T_SHIFT)
            | ((r.tex_coord & 3) << TEXTURE_UV_SET_SHIFT);
        if r.color_space == ColorSpace::Srgb {
            flags |= TEXTURE_SRGB;
        }
        let mut transform = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        if let Some(t) = &r.transform {
            flags |= TEXTURE_TRANSFORM;
            let m = t.matrix();
            transform = [m.x_axis.x, m.x_axis.y, m.y_axis.x, m.y_axis.y, m.z_axis.x, m.z_axis.y];
        }
        GpuTextureRef {
            // Fits: the texel buffer was checked against 2³² words.
            texel_offset: self.offset[tex.image as usize].unwrap_or(0) as u32,
            width: img.width.max(1),
            height: img.height.max(1),
            flags,
            transform,
            pad: [0; 2],
        }
    }

    /// The texel buffer: the sRGB and linear decode tables, then each used image's texels.
    fn texels(&self, scene: &Scene) -> Vec<u32> {
        let mut texels = Vec::with_capacity(self.words as usize);
        texels.extend((0..256).map(|i| srgb_to_linear(i as f32 / 255.0).to_bits()));
        texels.extend((0..256u32).map(|i| (i as f32 / 255.0).to_bits()));
        for &i in &self.used {
            let img = &scene.images[i];
            let n = img.width as usize * img.height as usize;
            texels.extend(img.texels.iter().take(n).map(|&t| u32::from_le_bytes(t)));
            // A short image reads as transparent black on the CPU (`Image::texel`'s ZERO).
            texels.resize(texels.len() + n.saturating_sub(img.texels.len()), 0);
        }
        debug_assert_eq!(texels.len() as u64, self.words);
        texels
    }
}

/// The triangle and vertex records. Triangles' material indices are clamped to the last material
/// (glTF's default), as furnace-cpu does.
fn geometry(scene: &Scene) -> (Vec<GpuSceneTriangle>, Vec<GpuVertex>) {
    let g = &scene.geometry;
    let last = scene.materials.len().saturating_sub(1) as u32;
    let triangles = g
        .triangles
        .iter()
        .enumerate()
        .map(|(t, &[i0, i1, i2])| GpuSceneTriangle {
            i0,
            i1,
            i2,
            material: g.triangle_materials.get(t).copied().unwrap_or(last).min(last),
        })
        .collect();
    let vertices = g
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| GpuVertex {
            position: p.to_array(),
            // A vertex without a normal cannot come from the loader; +Z as oct_encode's
            // fallback.
            normal: g.normals.get(i).copied().unwrap_or(furnace_scene::oct_encode(glam::Vec3::Z)),
        })
        .collect();
    (triangles, vertices)
}

/// `scene_attributes`: per vertex its [`Kept::uv_sets`] UV sets (`f32` bits), then its colour
/// (RGBA unorm16, R and G in the first word's low and high halves).
fn vertex_attributes(g: &furnace_scene::Geometry, kept: Kept) -> Vec<[u32; 2]> {
    if kept.stride() == 0 {
        return Vec::new();
    }
    let stored = g.uv_sets();
    let mut out = Vec::with_capacity(g.positions.len() * kept.stride() as usize);
    for i in 0..g.positions.len() {
        for k in 0..kept.uv_sets as usize {
            let uv = g.uvs.get(i * stored + k).copied().unwrap_or_default();
            out.push([uv.x.to_bits(), uv.y.to_bits()]);
        }
        if kept.colors {
            let c = g.colors.get(i).copied().unwrap_or([u16::MAX; 4]).map(u32::from);
            out.push([c[0] | (c[1] << 16), c[2] | (c[3] << 16)]);
        }
    }
    out
}

/// A material's GPU record, its texture slots through `texture_ref`.
fn material_record(
    m: &furnace_scene::Material,
    kept: Kept,
    texture_ref: &dyn Fn(&Option<TextureRef>) -> GpuTextureRef,
) -> GpuMaterial {
    let (alpha, cutoff) = match m.alpha_mode {
        AlphaMode::Opaque => (ALPHA_OPAQUE, 0.0),
        AlphaMode::Mask { cutoff } => (ALPHA_MASK, cutoff),
        AlphaMode::Blend => (ALPHA_BLEND, 0.0),
    };
    let mut flags = alpha;
    if m.double_sided {
        flags |= MATERIAL_DOUBLE_SIDED;
    }
    if m.uses_textures() {
        flags |= MATERIAL_TEXTURED;
    }
    if kept.colors {
        flags |= MATERIAL_VERTEX_COLOR;
    }
    if m.unlit {
        flags |= MATERIAL_UNLIT;
    }
    let sets = m.texture_refs().map(|t| t.tex_coord + 1).max().unwrap_or(0).min(kept.uv_sets);
    flags |= (sets << MATERIAL_UV_SETS_SHIFT) | (kept.stride() << MATERIAL_STRIDE_SHIFT);
    GpuMaterial {
        base_color_factor: m.base_color_factor.to_array(),
        emissive: m.emissive.to_array(),
        normal_scale: m.normal_scale,
        specular_color_factor: m.specular_color_factor.to_array(),
        specular_factor: m.specular_factor,
        metallic_factor: m.metallic_factor,
        roughness_factor: m.roughness_factor,
        alpha_cutoff: cutoff,
        flags,
        base_color_texture: texture_ref(&m.base_color_texture),
        metallic_roughness_texture: texture_ref(&m.metallic_roughness_texture),
        normal_texture: if kept.tangents { texture_ref(&m.normal_texture) } else { GpuTextureRef::zeroed() },
        emissive_texture: texture_ref(&m.emissive_texture),
    }
}

impl SceneBuffers {
    /// Packs `scene`, checking every buffer against `max_binding` bytes (pass
    /// [`GpuContext::max_storage_binding`], or a small value to test the error) before
    /// allocating it.
    ///
    /// Only what shading reads is kept: UVs only when some material is textured, tangents only
    /// when some material has a normal map or is anisotropic (and the scene has tangents), images only when a
    /// material slot uses them. Triangles' material indices are clamped to the last material
    /// (glTF's default), as furnace-cpu does; a texture or image index out of range makes the
    /// slot untextured (the CPU's lookup then returns white too).
    ///
    /// # Errors
    /// [`GpuError::TooLarge`] naming the first buffer over `max_binding` bytes (or over the
    /// 2³² texel words a `u32` index reaches).
    pub fn new(scene: &Scene, max_binding: u64) -> Result<Self, GpuError> {
        let kept = Kept::of(scene);
        check_sizes(scene, kept, max_binding)?;
        let images = ImageLayout::of(scene, kept, max_binding)?;
        let (triangles, vertices) = geometry(scene);
        let g = &scene.geometry;
        let attributes = vertex_attributes(g, kept);
        let tangents = if kept.tangents {
            (0..g.positions.len())
                .map(|i| {
                    // A missing tangent reads as None on the CPU; zero here gives the same (no
                    // perturbation: a zero tangent has no orthogonal part).
                    let e = g.tangents.get(i).copied().unwrap_or([0; 4]).map(|c| u32::from(c as u16));
                    [e[0] | (e[1] << 16), e[2] | (e[3] << 16)]
                })
                .collect()
        } else {
            Vec::new()
        };
        let texture_ref = |slot: &Option<TextureRef>| images.texture_ref(scene, slot);
        let materials = scene.materials.iter().map(|m| material_record(m, kept, &texture_ref)).collect();
        // Diffuse transmission scatters through the transmission kernels (their records say
        // which material bounds a solid).
        let diffuse = scene.materials.iter().any(|m| m.diffuse_transmission.is_some());
        let transmission = if diffuse || scene.materials.iter().any(|m| m.is_transmissive()) {
            scene.materials.iter().map(|m| transmission_record(m, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        let layers = if scene.materials.iter().any(|m| !m.layers.is_empty()) {
            scene.materials.iter().map(|m| layers_record(m, kept, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        let iridescence = if scene.materials.iter().any(|m| m.iridescence.is_some()) {
            scene.materials.iter().map(|m| iridescence_record(m, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        let specular = if scene.materials.iter().any(|m| !m.specular_textures.is_empty()) {
            scene.materials.iter().map(|m| specular_record(m, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        let anisotropy = if scene.materials.iter().any(|m| m.anisotropy.is_some()) {
            scene.materials.iter().map(|m| anisotropy_record(m, kept, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        let diffuse_transmission = if diffuse {
            scene.materials.iter().map(|m| diffuse_transmission_record(m, &texture_ref)).collect()
        } else {
            Vec::new()
        };
        Ok(Self {
            triangles,
            vertices,
            attributes,
            tangents,
            materials,
            texels: images.texels(scene),
            image_count: images.used.len(),
            transmission,
            layers,
            iridescence,
            specular,
            diffuse_transmission,
            anisotropy,
        })
    }

    /// The names of [`extra`](Self::extra)'s buffers, in its order.
    pub const EXTRA_NAMES: [&'static str; 6] = [
        "scene triangles",
        "scene vertices",
        "scene vertex attributes",
        "scene tangents",
        "scene materials",
        "scene texels",
    ];

    /// The six buffers' words in binding order (an absent one as 4 zero words), e.g. for
    /// a test kernel (`furnace_tests::gpu::run_with`) with [`bindings`]`(0, 3)`.
    pub fn extra(&self) -> [&[u32]; 6] {
        fn w(s: &[u32]) -> &[u32] {
            const EMPTY: &[u32] = &[0; 4];
            if s.is_empty() { EMPTY } else { s }
        }
        [
            w(bytemuck::cast_slice(&self.triangles)),
            w(bytemuck::cast_slice(&self.vertices)),
            w(bytemuck::cast_slice(&self.attributes)),
            w(bytemuck::cast_slice(&self.tangents)),
            w(bytemuck::cast_slice(&self.materials)),
            w(&self.texels),
        ]
    }

    /// Bytes of the per-triangle and per-vertex buffers (triangles, vertices, attributes,
    /// tangents).
    pub fn geometry_bytes(&self) -> u64 {
        (size_of_val(self.triangles.as_slice())
            + size_of_val(self.vertices.as_slice())
            + size_of_val(self.attributes.as_slice())
            + size_of_val(self.tangents.as_slice())) as u64
    }

    /// [`Self::geometry_bytes`] per triangle (0 without triangles).
    pub fn bytes_per_triangle(&self) -> f64 {
        if self.triangles.is_empty() {
            0.0
        } else {
            self.geometry_bytes() as f64 / self.triangles.len() as f64
        }
    }

    /// Bytes of all six buffers as uploaded.
    pub fn bytes(&self) -> u64 {
        self.extra().iter().map(|w| size_of_val(*w) as u64).sum()
    }
}

/// A scene's six storage buffers on the device.
#[derive(Debug)]
pub struct GpuScene {
    /// The buffers in binding order ([`bindings`]).
    pub buffers: [wgpu::Buffer; 6],
    /// Triangles.
    pub triangle_count: usize,
    /// [`SceneBuffers::geometry_bytes`].
    pub geometry_bytes: u64,
    /// [`SceneBuffers::bytes`].
    pub bytes: u64,
    /// `scene_transmission` ([`SceneBuffers::transmission`]); `None` without transmission.
    pub transmission: Option<wgpu::Buffer>,
    /// `scene_layers` ([`SceneBuffers::layers`]); `None` without coats and sheens.
    pub layers: Option<wgpu::Buffer>,
    /// `scene_iridescence` ([`SceneBuffers::iridescence`]); `None` without iridescence.
    pub iridescence: Option<wgpu::Buffer>,
    /// `scene_specular` ([`SceneBuffers::specular`]); `None` without specular textures.
    pub specular: Option<wgpu::Buffer>,
    /// `scene_diffuse_transmission` ([`SceneBuffers::diffuse_transmission`]); `None` without
    /// diffuse transmission.
    pub diffuse_transmission: Option<wgpu::Buffer>,
    /// `scene_anisotropy` ([`SceneBuffers::anisotropy`]); `None` without anisotropy.
    pub anisotropy: Option<wgpu::Buffer>,
}

impl GpuScene {
    /// Packs `scene` ([`SceneBuffers::new`]) within this device's largest storage binding and
    /// buffer size, and uploads it.
    ///
    /// # Errors
    /// [`GpuError::TooLarge`] when a buffer exceeds the device's limits (nothing is allocated on
    /// the device then); a wgpu error if an allocation fails.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        let limit = ctx.upload_limit();
        Self::upload_buffers(ctx, &SceneBuffers::new(scene, limit)?)
    }

    /// Uploads already packed buffers.
    pub fn upload_buffers(ctx: &GpuContext, packed: &SceneBuffers) -> Result<Self, GpuError> {
        let names = SceneBuffers::EXTRA_NAMES;
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let words = packed.extra();
        let mut made = Vec::with_capacity(names.len());
        for (name, w) in names.iter().zip(words) {
            made.push(ctx.buffer_init(
                name,
                bytemuck::cast_slice(w),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            )?);
        }
        let buffers: [wgpu::Buffer; 6] = made.try_into().expect("one buffer per name");
        let transmission = if packed.transmission.is_empty() {
            None
        } else {
            Some(ctx.buffer_init(
                "scene transmission",
                bytemuck::cast_slice(&packed.transmission),
                wgpu::BufferUsages::STORAGE,
            )?)
        };
        let optional = |name: &str, words: &[u8]| {
            if words.is_empty() {
                Ok(None)
            } else {
                ctx.buffer_init(name, words, wgpu::BufferUsages::STORAGE).map(Some)
            }
        };
        let layers = optional("scene layers", bytemuck::cast_slice(&packed.layers))?;
        let iridescence = optional("scene iridescence", bytemuck::cast_slice(&packed.iridescence))?;
        let specular = optional("scene specular", bytemuck::cast_slice(&packed.specular))?;
        let diffuse_transmission =
            optional("scene diffuse transmission", bytemuck::cast_slice(&packed.diffuse_transmission))?;
        let anisotropy = optional("scene anisotropy", bytemuck::cast_slice(&packed.anisotropy))?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Wgpu(e.to_string()));
        }
        ctx.check()?;
        Ok(Self {
            buffers,
            triangle_count: packed.triangles.len(),
            geometry_bytes: packed.geometry_bytes(),
            bytes: packed.bytes()
                + size_of_val(packed.transmission.as_slice()) as u64
                + size_of_val(packed.layers.as_slice()) as u64
                + size_of_val(packed.iridescence.as_slice()) as u64
                + size_of_val(packed.specular.as_slice()) as u64
                + size_of_val(packed.diffuse_transmission.as_slice()) as u64
                + size_of_val(packed.anisotropy.as_slice()) as u64,
            transmission,
            layers,
            iridescence,
            specular,
            diffuse_transmission,
            anisotropy,
        })
    }

    /// Bytes of the per-triangle and per-vertex buffers per triangle.
    pub fn bytes_per_triangle(&self) -> f64 {
        if self.triangle_count == 0 { 0.0 } else { self.geometry_bytes as f64 / self.triangle_count as f64 }
    }

    /// Bind group layout entries of the six buffers at bindings `first` … `first + 5`
    /// (read-only storage, compute stage).
    pub fn layout_entries(first: u32) -> Vec<wgpu::BindGroupLayoutEntry> {
        BindingTable::new(0, first, binding_list()).layout_entries()
    }

    /// The six buffers, in [`binding_list`] order.
    pub fn resources(&self) -> Vec<wgpu::BindingResource<'_>> {
        self.buffers.iter().map(wgpu::Buffer::as_entire_binding).collect()
    }

    /// Bind group entries matching [`GpuScene::layout_entries`].
    pub fn bind_entries(&self, first: u32) -> Vec<wgpu::BindGroupEntry<'_>> {
        BindingTable::new(0, first, binding_list()).bind_entries(self.resources())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bindings_name_six_buffers_in_order() {
        let b = BindingTable::new(1, 4, binding_list()).wgsl();
        assert!(b.starts_with("@group(1) @binding(4) var<storage, read> scene_triangles"));
        assert!(b.contains("@binding(9) var<storage, read> scene_texels: array<u32>;"));
        assert_eq!(b.lines().count(), BINDING_COUNT as usize);
        // `bindings` is the declarations the buffers need, then the buffers.
        assert_eq!(bindings(1, 4), declarations() + &b);
    }

    #[test]
    fn cornell_box_keeps_no_uvs_tangents_or_texels() {
        let scene = furnace_scene::builtin::cornell_box().unwrap();
        let b = SceneBuffers::new(&scene, u64::MAX).unwrap();
        assert!(b.attributes.is_empty() && b.tangents.is_empty());
        assert_eq!(b.texels.len(), TABLE_WORDS as usize);
        assert_eq!(b.triangles.len(), scene.geometry.triangle_count());
        // The decode tables are furnace-scene's values, bit for bit.
        assert_eq!(f32::from_bits(b.texels[(SRGB_TABLE + 128) as usize]), srgb_to_linear(128.0 / 255.0));
        assert_eq!(f32::from_bits(b.texels[(LINEAR_TABLE + 255) as usize]), 1.0);
    }
}
