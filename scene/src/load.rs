//! The glTF 2.0 / GLB loader: parse, check required extensions, validate, load buffers
//! ourselves (so that a missing file is named), flatten the default scene into world space.

use crate::accessor::{Located, read_floats, read_indices};
use crate::camera::{Camera, Projection};
use crate::error::{SceneError, Warning};
use crate::geometry::{Geometry, encode_tangent, generate_tangents, oct_encode};
use crate::material::{AlphaMode, Material};
use crate::texture::{ColorSpace, Image, Texture, TextureRef, TextureTransform, WrapMode};
use crate::{Light, Scene, Sky, Sun};
use glam::{Affine3A, Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::Dimensions;
use std::collections::HashSet;
use std::path::Path;

/// Extensions furnace honours, so a file may require them.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_specular",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
];

/// Extensions whose absence changes the look but which furnace ignores with a warning when
/// only *used* (never when *required*).
const IGNORED_WITH_WARNING: &str = "is used but not supported: ignored";

/// Marks a texture whose image is missing.
const NO_IMAGE: u32 = u32::MAX;

struct Ctx<'a> {
    file: &'a str,
    base: Option<&'a Path>,
    warnings: Vec<Warning>,
    seen: HashSet<(String, String)>,
}

impl Ctx<'_> {
    fn warn(&mut self, path: impl Into<String>, message: impl Into<String>) {
        let (path, message) = (path.into(), message.into());
        if self.seen.insert((path.clone(), message.clone())) {
            self.warnings.push(Warning { path, message });
        }
    }
    fn invalid(&self, (path, message): Located) -> SceneError {
        SceneError::Invalid { file: self.file.to_string(), path, message }
    }
}

/// Decodes the base64 of a data URI (RFC 4648, as the `gltf` crate's own reader does, through
/// the same crate), ignoring whitespace, in the standard or the URL-safe alphabet.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let compact: String = s.chars().filter(|c| !c.is_ascii_whitespace()).collect();
    base64::decode_config(&compact, base64::STANDARD)
        .or_else(|_| base64::decode_config(&compact, base64::URL_SAFE))
        .ok()
}

/// Percent-decodes a relative URI into a path string (byte-wise: never splits UTF-8).
fn percent_decode(s: &str) -> String {
    String::from_utf8_lossy(&urlencoding::decode_binary(s.as_bytes())).into_owned()
}

/// Resolves a URI (data URI or relative file) to bytes; `what` names it in errors.
fn resolve_uri(ctx: &Ctx<'_>, uri: &str, path: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((meta, data)) = rest.split_once(',') else {
            return Err(ctx.invalid((format!("{path}.uri"), "malformed data URI".into())));
        };
        if !meta.ends_with(";base64") {
            return Err(ctx.invalid((format!("{path}.uri"), "data URI is not base64-encoded".into())));
        }
        return base64_decode(data)
            .ok_or_else(|| ctx.invalid((format!("{path}.uri"), "invalid base64 in data URI".into())));
    }
    if uri.contains("://") {
        return Err(ctx.invalid((
            format!("{path}.uri"),
            format!("'{uri}': only relative file URIs and data URIs are supported"),
        )));
    }
    let rel = percent_decode(uri);
    let Some(base) = ctx.base else {
        return Err(SceneError::Io {
            file: ctx.file.to_string(),
            what: format!("{path} '{rel}'"),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "external file referenced from an in-memory scene",
            ),
        });
    };
    let full = base.join(&rel);
    std::fs::read(&full).map_err(|source| SceneError::Io {
        file: ctx.file.to_string(),
        what: format!("{path} '{}'", full.display()),
        source,
    })
}

fn validation_message(e: &gltf::json::validation::Error) -> &'static str {
    use gltf::json::validation::Error as E;
    match e {
        E::IndexOutOfBounds => "index out of bounds",
        E::Invalid => "invalid value",
        E::Missing => "missing required value",
        E::Oversize => "size exceeds system limits",
        E::Unsupported => "unsupported extension",
    }
}

/// Index checks that gltf-json's validator itself relies on (it indexes `accessors` with a
/// primitive's POSITION before checking it, and would panic).
fn precheck(root: &gltf::json::Root) -> Result<(), Located> {
    let na = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let path = format!("meshes[{m}].primitives[{p}]");
            for (sem, idx) in &prim.attributes {
                if idx.value() >= na {
                    let name = match sem {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "?".into(),
                    };
                    return Err((
                        format!("{path}.attributes.{name}"),
                        format!("accessor {} does not exist ({na} accessors)", idx.value()),
                    ));
                }
            }
            if let Some(i) = &prim.indices
                && i.value() >= na
            {
                return Err((
                    format!("{path}.indices"),
                    format!("accessor {} does not exist ({na} accessors)", i.value()),
                ));
            }
        }
    }
    Ok(())
}

/// Loads a glTF (JSON or GLB) from bytes. `base` resolves relative URIs.
pub(crate) fn load(bytes: &[u8], file: &str, base: Option<&Path>) -> Result<Scene, SceneError> {
    let mut ctx = Ctx { file, base, warnings: Vec::new(), seen: HashSet::new() };
    // gltf 1.4's GLB reader underflows (panics) on a header length below 12: check first.
    if bytes.starts_with(b"glTF") {
        let len = bytes.get(8..12).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if (len as usize) < 12 || bytes.len() < 12 {
            return Err(SceneError::Parse {
                file: file.to_string(),
                message: format!("GLB header length {len} is shorter than the 12-byte header"),
            });
        }
    }
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;
    let doc = gltf.document;
    let blob = gltf.blob;
    let root = doc.as_json();

    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(SceneError::UnsupportedExtension {
                file: file.to_string(),
                path: format!("extensionsRequired[{i}]"),
                extension: ext.clone(),
            });
        }
    }
    precheck(root).map_err(|e| ctx.invalid(e))?;
    {
        use gltf::json::validation::{Error as VE, Validate};
        let mut errors = Vec::new();
        root.validate(root, gltf::json::Path::new, &mut |path, err| {
            let path = path().to_string();
            // gltf-json is stricter than the specification here: an accessor without a
            // bufferView is all zeros (§3.6.2.1) and a texture's source is optional (§5.29);
            // both are handled below. Unsupported extensions were checked above.
            // A texture whose source is out of range is ignored with a warning (lenient: the
            // geometry is still renderable).
            let texture_source = path.starts_with("textures[") && path.ends_with("].source");
            let spec_allows =
                (err == VE::Missing && path.starts_with("accessors[") && path.ends_with("].bufferView"))
                    || (texture_source && matches!(err, VE::Missing | VE::IndexOutOfBounds));
            if err != VE::Unsupported && !spec_allows {
                errors.push((path, validation_message(&err)));
            }
        });
        if let Some((path, msg)) = errors.first() {
            let more = if errors.len() > 1 {
                format!(" (and {} more problems)", errors.len() - 1)
            } else {
                String::new()
            };
            return Err(ctx.invalid((path.clone(), format!("{msg}{more}"))));
        }
    }
    for (i, ext) in root.extensions_used.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            ctx.warn(format!("extensionsUsed[{i}]"), format!("{ext} {IGNORED_WITH_WARNING}"));
        }
    }

    // Buffers.
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
        let data = match b.source() {
            // Only the first buffer may live in the GLB BIN chunk (§4.4.3.3); any other buffer
            // without a URI is a placeholder (valid, e.g. for extensions): empty.
            gltf::buffer::Source::Bin => match (&blob, b.index()) {
                (Some(blob), 0) => blob.clone(),
                _ => {
                    ctx.warn(&path, "no data (no uri and no GLB BIN chunk): treated as empty");
                    buffers.push(Vec::new());
                    continue;
                }
            },
            gltf::buffer::Source::Uri(uri) if uri.contains("://") && !uri.starts_with("data:") => {
                ctx.warn(&path, format!("'{uri}' is not a local file: treated as empty"));
                buffers.push(Vec::new());
                continue;
            }
            gltf::buffer::Source::Uri(uri) => resolve_uri(&ctx, uri, &path)?,
        };
        if data.len() < b.length() {
            return Err(ctx.invalid((
                format!("{path}.byteLength"),
                format!("byteLength is {} but the data has {} bytes", b.length(), data.len()),
            )));
        }
        buffers.push(data);
    }

    // Textures and materials.
    let mut textures = Vec::new();
    for (t, tj) in doc.textures().zip(&root.textures) {
        // The JSON `source`, not `Texture::source()`, which unwraps a missing one.
        let image = tj.source.value();
        let image = if image < doc.images().len() {
            image as u32
        } else {
            ctx.warn(format!("textures[{}]", t.index()), "no image source: texture ignored");
            NO_IMAGE
        };
        let s = t.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        };
        textures.push(Texture { image, wrap_s: wrap(s.wrap_s()), wrap_t: wrap(s.wrap_t()) });
    }
    let mut materials: Vec<Material> = doc.materials().map(|m| read_material(&mut ctx, &m)).collect();
    let default_material = materials.len() as u32;
    materials.push(Material::default());
    let needs_uv = materials.iter().any(Material::uses_textures);
    let needs_tangent = materials.iter().any(|m| m.normal_texture.is_some());

    // Images used by some material: decode; others stay empty 1×1 white placeholders.
    let mut used_images = vec![false; doc.images().len()];
    for m in &materials {
        for t in [m.base_color_texture, m.metallic_roughness_texture, m.normal_texture, m.emissive_texture]
            .into_iter()
            .flatten()
        {
            if let Some(tex) = textures.get(t.texture as usize)
                && let Some(u) = used_images.get_mut(tex.image as usize)
            {
                *u = true;
            }
        }
    }
    let mut images = Vec::new();
    for img in doc.images() {
        if !used_images.get(img.index()).copied().unwrap_or(false) {
            images.push(Image { width: 1, height: 1, texels: vec![[255; 4]] });
            continue;
        }
        images.push(decode_image(&ctx, &img, &buffers)?);
    }

    // The scene to render.
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Err(SceneError::NothingToRender {
            file: file.to_string(),
            reason: "the file has no scene".into(),
        });
    };
    let mut sky = Vec3::ZERO;
    if let Some(raw) = scene.extras()
        && let Ok(v) = gltf::json::deserialize::from_str::<gltf::json::Value>(raw.get())
        && let Some(bg) = v.get("background_radiance_rgb")
    {
        let arr: Option<Vec<f32>> =
            bg.as_array().map(|a| a.iter().filter_map(|x| x.as_f64().map(|x| x as f32)).collect());
        match arr {
            Some(a) if a.len() == 3 && a.iter().all(|x| x.is_finite() && *x >= 0.0) => {
                sky = Vec3::new(a[0], a[1], a[2]);
            }
            _ => ctx.warn(
                format!("scenes[{}].extras.background_radiance_rgb", scene.index()),
                "not three non-negative numbers: sky left black",
            ),
        }
    }

    let mut geo = Geometry::default();
    let mut cameras = Vec::new();
    let mut sun: Option<Sun> = None;
    let mut lights = Vec::new();
    let mut dropped = 0usize;
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let npath = format!("nodes[{}]", node.index());
        if std::mem::replace(&mut visited[node.index()], true) {
            ctx.warn(npath, "node reached twice (cycle or shared child): skipped");
            continue;
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            ctx.warn(npath, "non-finite transform: subtree skipped");
            continue;
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
        if node.skin().is_some() || node.weights().is_some() {
            ctx.warn(&npath, "skinning and morph targets are not supported: rest pose used");
        }
        if let Some(cam) = node.camera() {
            cameras.push(make_camera(&mut ctx, &cam, world));
        }
        if let Some(light) = node.light() {
            let lpath = format!("KHR_lights_punctual.lights[{}]", light.index());
            match crate::light::punctual(&light, world) {
                Ok(Light::Sun(_)) if sun.is_some() => {
                    ctx.warn(lpath, "only the first directional light is used as the sun");
                }
                Ok(Light::Sun(s)) => sun = Some(s),
                Ok(other) => lights.push(other),
                Err((path, why)) => ctx.warn(if path.is_empty() { lpath } else { path.to_string() }, why),
            }
        }
        if let Some(mesh) = node.mesh() {
            for prim in mesh.primitives() {
                let ppath = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                add_primitive(
                    &mut ctx,
                    &prim,
                    &ppath,
                    &npath,
                    world,
                    &buffers,
                    needs_uv,
                    needs_tangent,
                    default_material,
                    &mut geo,
                    &mut dropped,
                )?;
            }
        }
    }
    if geo.triangles.is_empty() {
        let reason = if dropped > 0 {
            format!("all {dropped} triangles have zero area")
        } else {
            "the scene has no triangles".to_string()
        };
        return Err(SceneError::NothingToRender { file: file.to_string(), reason });
    }
    if dropped > 0 {
        ctx.warn("", format!("{dropped} zero-area triangles dropped (they cannot be hit)"));
    }
    check_scale(&mut ctx, &geo);
    if !needs_uv {
        geo.uvs = Vec::new();
    }
    if !needs_tangent {
        geo.tangents = Vec::new();
    }
    Ok(Scene {
        name: file.to_string(),
        geometry: geo,
        materials,
        textures,
        images,
        cameras,
        lights: sun
            .map(Light::Sun)
            .into_iter()
            .chain((sky != Vec3::ZERO).then_some(Light::Sky(Sky { radiance: sky })))
            .collect(),
        warnings: ctx.warnings,
        dropped_triangles: dropped,
    })
}

/// Largest world coordinate magnitude of a scene that f32 ray tracing handles: above it the
/// Möller–Trumbore products (edge² × distance) overflow and hits are lost. The Cornell box
/// renders its s = 1 image when scaled by 1e12 (|coordinates| ≤ 2e12) and breaks at 1e13
/// (`furnace-cpu`'s `tests/stability.rs`); 2⁴² ≈ 4.4e12.
pub const MAX_COORDINATE: f32 = 4_398_046_511_104.0;

/// Smallest largest-coordinate magnitude of a scene that f32 ray tracing handles: below it the
/// Möller–Trumbore triple products (three lengths multiplied, (2e-13)³ < 1.2e-38) become
/// subnormal and hits lose their precision. Ray offsets scale with the scene
/// (`furnace_accel::offset_scale`), so they are not the limit: the Cornell box renders its
/// s = 1 image scaled by 1e-12 (|coordinates| ≤ 2e-12) and breaks at 1e-13
/// (`furnace-cpu`'s `tests/stability.rs`); 2⁻³⁹ ≈ 1.8e-12.
pub const MIN_COORDINATE: f32 = 1.818_989_4e-12;

/// Warns when the scene's coordinates lie outside what the renderer measured to be scale
/// invariant ([`MIN_COORDINATE`] … [`MAX_COORDINATE`]).
fn check_scale(ctx: &mut Ctx<'_>, geo: &Geometry) {
    let used: HashSet<u32> = geo.triangles.iter().flatten().copied().collect();
    let max = used.iter().map(|&i| geo.positions[i as usize].abs().max_element()).fold(0.0f32, f32::max);
    if max > MAX_COORDINATE {
        ctx.warn(
            "",
            format!(
                "coordinates up to {max:e}: beyond ~{MAX_COORDINATE:.1e} f32 ray–triangle tests overflow and \
                 hits are lost; scale the scene down"
            ),
        );
    } else if max < MIN_COORDINATE {
        ctx.warn(
            "",
            format!(
                "all coordinates within ±{max:e}: below ~{MIN_COORDINATE:.1e} f32 ray–triangle tests lose \
                 precision (subnormal products) and hits are lost; scale the scene up"
            ),
        );
    }
}

fn make_camera(ctx: &mut Ctx<'_>, cam: &gltf::Camera<'_>, world: Mat4) -> Camera {
    // Remove scale: keep rotation (orthonormalised columns) and translation.
    let (_, rot, t) = world.to_scale_rotation_translation();
    let world_from_camera = Affine3A::from_rotation_translation(rot.normalize(), t);
    let projection = match cam.projection() {
        gltf::camera::Projection::Perspective(p) => {
            let yfov = p.yfov();
            if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                ctx.warn(
                    format!("cameras[{}].perspective.yfov", cam.index()),
                    "yfov outside (0, π): 45° used",
                );
            }
            Projection::Perspective {
                yfov: if yfov > 0.0 && yfov < std::f32::consts::PI {
                    yfov
                } else {
                    crate::camera::DEFAULT_YFOV
                },
                aspect_ratio: p.aspect_ratio(),
            }
        }
        gltf::camera::Projection::Orthographic(o) => {
            Projection::Orthographic { xmag: o.xmag(), ymag: o.ymag() }
        }
    };
    Camera { world_from_camera, projection }
}

fn texture_ref(
    ctx: &mut Ctx<'_>,
    info: Option<gltf::texture::Info<'_>>,
    space: ColorSpace,
    path: String,
) -> Option<TextureRef> {
    let info = info?;
    let transform = info.texture_transform().map(|t| TextureTransform {
        offset: Vec2::from(t.offset()),
        rotation: t.rotation(),
        scale: Vec2::from(t.scale()),
    });
    let tex_coord = info.texture_transform().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
    if tex_coord != 0 {
        ctx.warn(path, format!("uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is stored: UV0 used"));
    }
    Some(TextureRef { texture: info.texture().index() as u32, tex_coord, color_space: space, transform })
}

fn read_material(ctx: &mut Ctx<'_>, m: &gltf::Material<'_>) -> Material {
    let i = m.index().unwrap_or(0);
    let p = format!("materials[{i}]");
    let pbr = m.pbr_metallic_roughness();
    let base_color_texture = texture_ref(
        ctx,
        pbr.base_color_texture(),
        ColorSpace::Srgb,
        format!("{p}.pbrMetallicRoughness.baseColorTexture"),
    );
    let metallic_roughness_texture = texture_ref(
        ctx,
        pbr.metallic_roughness_texture(),
        ColorSpace::Linear,
        format!("{p}.pbrMetallicRoughness.metallicRoughnessTexture"),
    );
    let (normal_texture, normal_scale) = match m.normal_texture() {
        Some(n) => {
            let r = TextureRef {
                texture: n.texture().index() as u32,
                tex_coord: n.tex_coord(),
                color_space: ColorSpace::Linear,
                transform: None,
            };
            (Some(r), n.scale())
        }
        None => (None, 1.0),
    };
    let emissive_texture =
        texture_ref(ctx, m.emissive_texture(), ColorSpace::Srgb, format!("{p}.emissiveTexture"));
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emissive = Vec3::from(m.emissive_factor()) * strength;
    if m.emissive_factor().iter().any(|&x| x > 1.0) {
        ctx.warn(
            format!("{p}.emissiveFactor"),
            "exceeds 1 (the spec's limit; use KHR_materials_emissive_strength): used as given",
        );
    }
    let alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
        gltf::material::AlphaMode::Blend => {
            ctx.warn(format!("{p}.alphaMode"), "BLEND is rendered opaque");
            AlphaMode::Blend
        }
    };
    let (specular_factor, specular_color_factor) = match m.specular() {
        Some(s) => {
            if s.specular_texture().is_some() || s.specular_color_texture().is_some() {
                ctx.warn(
                    format!("{p}.extensions.KHR_materials_specular"),
                    "specular textures are not supported: factors only",
                );
            }
            (s.specular_factor(), Vec3::from(s.specular_color_factor()))
        }
        None => (1.0, Vec3::ONE),
    };
    if m.occlusion_texture().is_some() {
        ctx.warn("", "occlusionTexture ignored (a path tracer computes occlusion)");
    }
    for (present, name) in [
        (m.transmission().is_some(), "KHR_materials_transmission"),
        (m.volume().is_some(), "KHR_materials_volume"),
        (m.ior().is_some(), "KHR_materials_ior"),
        (m.unlit(), "KHR_materials_unlit"),
        (m.pbr_specular_glossiness().is_some(), "KHR_materials_pbrSpecularGlossiness"),
    ] {
        if present {
            ctx.warn("", format!("{name} is not supported: ignored"));
        }
    }
    let clamp01 = |x: f32| if x.is_nan() { 1.0 } else { x.clamp(0.0, 1.0) };
    Material {
        name: m.name().map(str::to_string),
        base_color_factor: Vec4::from(pbr.base_color_factor()),
        base_color_texture,
        metallic_factor: clamp01(pbr.metallic_factor()),
        roughness_factor: clamp01(pbr.roughness_factor()),
        metallic_roughness_texture,
        normal_texture,
        normal_scale,
        emissive,
        emissive_texture,
        alpha_mode,
        double_sided: m.double_sided(),
        specular_factor,
        specular_color_factor,
    }
}

fn decode_image(ctx: &Ctx<'_>, img: &gltf::Image<'_>, buffers: &[Vec<u8>]) -> Result<Image, SceneError> {
    let path = format!("images[{}]", img.index());
    let bytes: Vec<u8> = match img.source() {
        gltf::image::Source::View { view, .. } => {
            let buf = buffers.get(view.buffer().index()).map(Vec::as_slice).unwrap_or(&[]);
            let end = view.offset().checked_add(view.length());
            match end.and_then(|e| buf.get(view.offset()..e)) {
                Some(s) => s.to_vec(),
                None => {
                    return Err(
                        ctx.invalid((format!("bufferViews[{}]", view.index()), "exceeds its buffer".into()))
                    );
                }
            }
        }
        gltf::image::Source::Uri { uri, .. } => resolve_uri(ctx, uri, &path)?,
    };
    let decoded = image::load_from_memory(&bytes).map_err(|e| SceneError::Image {
        file: ctx.file.to_string(),
        path: path.clone(),
        message: e.to_string(),
    })?;
    let rgba = decoded.to_rgba8();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err(SceneError::Image {
            file: ctx.file.to_string(),
            path,
            message: "zero-sized image".into(),
        });
    }
    let texels = rgba.pixels().map(|p| p.0).collect();
    Ok(Image { width, height, texels })
}

#[allow(clippy::too_many_arguments)]
fn add_primitive(
    ctx: &mut Ctx<'_>,
    prim: &gltf::Primitive<'_>,
    ppath: &str,
    npath: &str,
    world: Mat4,
    buffers: &[Vec<u8>],
    needs_uv: bool,
    needs_tangent: bool,
    default_material: u32,
    geo: &mut Geometry,
    dropped: &mut usize,
) -> Result<(), SceneError> {
    if prim.mode() != gltf::mesh::Mode::Triangles {
        ctx.warn(ppath, format!("mode {:?} is not TRIANGLES: primitive skipped", prim.mode()));
        return Ok(());
    }
    if prim.extension_value("KHR_draco_mesh_compression").is_some() {
        ctx.warn(ppath, "KHR_draco_mesh_compression is not supported: uncompressed fallback used if any");
    }
    let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
        ctx.warn(ppath, "no POSITION attribute: primitive skipped");
        return Ok(());
    };
    let (pos, _) = read_floats(&pos_acc, buffers, &[Dimensions::Vec3]).map_err(|e| ctx.invalid(e))?;
    let nverts = pos.len() / 3;
    // NaN and infinite positions are an error, not dropped triangles: the glTF Validator
    // reports them (ACCESSOR_INVALID_FLOAT), and a model with a broken vertex is one the user
    // wants to hear about by name rather than see rendered with a hole.
    if let Some(i) = pos.iter().position(|x| !x.is_finite()) {
        let v = i / 3;
        return Err(ctx.invalid((
            format!("{ppath}.attributes.POSITION"),
            format!(
                "accessors[{}] vertex {v} is ({}, {}, {}): positions must be finite",
                pos_acc.index(),
                pos[3 * v],
                pos[3 * v + 1],
                pos[3 * v + 2]
            ),
        )));
    }
    let check_count = |ctx: &Ctx<'_>, name: &str, n: usize| {
        if n != nverts {
            Err(ctx.invalid((
                format!("{ppath}.attributes.{name}"),
                format!("count {n} differs from POSITION's count {nverts}"),
            )))
        } else {
            Ok(())
        }
    };
    let normals = match prim.get(&gltf::Semantic::Normals) {
        Some(acc) => {
            let (n, _) = read_floats(&acc, buffers, &[Dimensions::Vec3]).map_err(|e| ctx.invalid(e))?;
            check_count(ctx, "NORMAL", n.len() / 3)?;
            Some(n)
        }
        None => None,
    };
    let uvs = match prim.get(&gltf::Semantic::TexCoords(0)) {
        Some(acc) if needs_uv => {
            let (t, _) = read_floats(&acc, buffers, &[Dimensions::Vec2]).map_err(|e| ctx.invalid(e))?;
            check_count(ctx, "TEXCOORD_0", t.len() / 2)?;
            Some(t)
        }
        _ => None,
    };
    let tangents = match prim.get(&gltf::Semantic::Tangents) {
        Some(acc) if needs_tangent => {
            let (t, _) = read_floats(&acc, buffers, &[Dimensions::Vec4]).map_err(|e| ctx.invalid(e))?;
            check_count(ctx, "TANGENT", t.len() / 4)?;
            Some(t)
        }
        _ => None,
    };
    let indices: Vec<u32> = match prim.indices() {
        Some(acc) => {
            let idx = read_indices(&acc, buffers).map_err(|e| ctx.invalid(e))?;
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= nverts) {
                return Err(
                    ctx.invalid((format!("{ppath}.indices"), format!("index {bad} ≥ vertex count {nverts}")))
                );
            }
            idx
        }
        None => (0..nverts as u32).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        ctx.warn(ppath, format!("{} indices is not a multiple of 3: the rest ignored", indices.len()));
    }
    let material = prim.material().index().map_or(default_material, |i| i as u32);

    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let flip = Mat3::from_mat4(world).determinant() < 0.0;
    let wp: Vec<Vec3> =
        pos.chunks_exact(3).map(|p| world.transform_point3(Vec3::new(p[0], p[1], p[2]))).collect();
    // Finite positions that the node's (finite) transform takes past f32's range.
    if let Some(v) = wp.iter().position(|p| !p.is_finite()) {
        return Err(ctx.invalid((
            format!("{npath}: {ppath}.attributes.POSITION"),
            format!(
                "vertex {v} ({}, {}, {}) transformed to world space is {}: the node's transform takes it \
                 beyond f32's range (3.4e38)",
                pos[3 * v],
                pos[3 * v + 1],
                pos[3 * v + 2],
                wp[v]
            ),
        )));
    }
    // Shading normals in world space; `None` if absent or any is unusable (then per-face).
    let wn: Option<Vec<Vec3>> = normals.and_then(|n| {
        let v: Vec<Vec3> = n
            .chunks_exact(3)
            .map(|c| (normal_matrix * Vec3::new(c[0], c[1], c[2])).normalize_or_zero())
            .collect();
        if v.iter().all(|x| *x != Vec3::ZERO) {
            Some(v)
        } else {
            ctx.warn(
                format!("{ppath}.attributes.NORMAL"),
                "zero or non-finite normals: per-face normals used",
            );
            None
        }
    });
    let uv_at = |i: usize| {
        uvs.as_ref().and_then(|t| t.get(2 * i..2 * i + 2)).map_or(Vec2::ZERO, |c| Vec2::new(c[0], c[1]))
    };
    let base = geo.positions.len();
    if wn.is_some() {
        // Indexed: copy this instance's vertices once.
        if base + nverts > u32::MAX as usize {
            return Err(ctx.invalid((ppath.to_string(), "more than 2^32 vertices".into())));
        }
        geo.positions.extend_from_slice(&wp);
        if let Some(wn) = &wn {
            geo.normals.extend(wn.iter().map(|&n| oct_encode(n)));
            if needs_tangent {
                // The file's tangents transform as directions (not by the inverse transpose);
                // a mirroring transform flips the handedness. Otherwise generate them.
                let world3 = Mat3::from_mat4(world);
                let from_file: Option<Vec<Vec4>> = tangents.as_ref().map(|t| {
                    t.chunks_exact(4)
                        .map(|c| {
                            let w = if (c[3] < 0.0) != flip { -1.0 } else { 1.0 };
                            (world3 * Vec3::new(c[0], c[1], c[2])).normalize_or_zero().extend(w)
                        })
                        .collect()
                });
                let usable = from_file.filter(|v| v.iter().all(|t| t.truncate() != Vec3::ZERO));
                let generated = usable.unwrap_or_else(|| {
                    let local: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
                    let uv: Vec<Vec2> = (0..nverts).map(uv_at).collect();
                    generate_tangents(&wp, wn, &uv, &local)
                });
                geo.tangents.extend(generated.into_iter().map(encode_tangent));
            }
        }
        if needs_uv {
            geo.uvs.extend((0..nverts).map(uv_at));
        }
    }
    for t in indices.chunks_exact(3) {
        let (mut a, b, mut c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        if flip {
            std::mem::swap(&mut a, &mut c);
        }
        let (pa, pb, pc) = (wp[a], wp[b], wp[c]);
        let cross = (pb - pa).cross(pc - pa);
        let area2 = cross.length();
        // The face normal. `length` squares the cross product, which overflows f32 for edges
        // beyond ~4e9 and underflows below ~5e-12: such triangles were dropped as if
        // degenerate. Then it is formed in f64, where the positions' differences are exact and
        // nothing over- or underflows; only a zero cross product (zero area) drops a triangle.
        let face_normal = if area2 > 0.0 && area2.is_finite() {
            cross / area2
        } else {
            let (da, db, dc) = (pa.as_dvec3(), pb.as_dvec3(), pc.as_dvec3());
            let c64 = (db - da).cross(dc - da);
            let l = c64.length();
            if !(l > 0.0 && l.is_finite()) {
                *dropped += 1;
                continue;
            }
            (c64 / l).as_vec3()
        };
        if wn.is_some() {
            geo.triangles.push([(base + a) as u32, (base + b) as u32, (base + c) as u32]);
        } else {
            let v0 = geo.positions.len();
            if v0 + 3 > u32::MAX as usize {
                return Err(ctx.invalid((ppath.to_string(), "more than 2^32 vertices".into())));
            }
            let n = oct_encode(face_normal);
            let face_tangent = needs_tangent.then(|| {
                let uv = [uv_at(a), uv_at(b), uv_at(c)];
                generate_tangents(&[pa, pb, pc], &[face_normal; 3], &uv, &[[0, 1, 2]])[0]
            });
            for &i in &[a, b, c] {
                geo.positions.push(wp[i]);
                geo.normals.push(n);
                if needs_uv {
                    geo.uvs.push(uv_at(i));
                }
                if let Some(t) = face_tangent {
                    geo.tangents.push(encode_tangent(t));
                }
            }
            geo.triangles.push([v0 as u32, v0 as u32 + 1, v0 as u32 + 2]);
        }
        geo.triangle_materials.push(material);
    }
    Ok(())
}
