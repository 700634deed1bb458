//! The file's bytes: buffers (GLB BIN chunk, data URIs, relative files) and the images the
//! materials use, decoded to 8-bit RGBA.

use super::context::Ctx;
use crate::error::SceneError;
use crate::material::Material;
use crate::texture::{ColorSpace, Image, Texture, TextureRef};

/// Decodes the base64 of a data URI (RFC 4648, as the `gltf` crate's own reader does, through
/// the same crate), ignoring whitespace, in the standard or the URL-safe alphabet.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let compact: String = s.chars().filter(|c| !c.is_ascii_whitespace()).collect();
    base64::decode_config(&compact, base64::STANDARD)
        .or_else(|_| base64::decode_config(&compact, base64::URL_SAFE))
        .ok()
}

/// Percent-decodes a relative URI into a path string (byte-wise: never splits UTF-8).
pub(super) fn percent_decode(s: &str) -> String {
    String::from_utf8_lossy(&urlencoding::decode_binary(s.as_bytes())).into_owned()
}

/// How much of a file a URI may name: a buffer reads exactly its `byteLength` (a longer file's
/// rest is not read), an image at most [`MAX_IMAGE_FILE_BYTES`].
#[derive(Clone, Copy)]
enum Extent {
    Buffer(u64),
    Image,
}

/// The largest image file read for a texture: 1 GiB, the RGBA8 texels of the largest texture
/// ([`crate::MAX_TEXTURE_SIZE`]²). PNG and JPEG files are smaller than their texels; a file
/// larger than that could not decode within [`MAX_TEXTURE_DECODE_BYTES`] anyway.
const MAX_IMAGE_FILE_BYTES: u64 = 1 << 30;

/// The most bytes a texture's decoder may allocate (`image::Limits::max_alloc`): 1 GiB, the
/// decoded texels of the largest texture ([`crate::MAX_TEXTURE_SIZE`]²) in 8-bit RGBA. A
/// 16-bit image of that size is refused; smaller ones decode.
const MAX_TEXTURE_DECODE_BYTES: u64 = 1 << 30;

/// Resolves a URI (data URI or relative file) to bytes; `path` names it in errors. A relative
/// URI may go up (`../textures/wood.png`: assets share folders), but an absolute path is
/// refused, and only regular files are read (see [`crate::file`]).
fn resolve_uri(ctx: &Ctx<'_>, uri: &str, path: &str, extent: Extent) -> Result<Vec<u8>, SceneError> {
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
    if crate::file::is_absolute_uri_path(&rel) {
        return Err(ctx.invalid((format!("{path}.uri"), absolute_uri_message(&rel))));
    }
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
    let read = match extent {
        Extent::Buffer(len) => crate::file::read_prefix(&full, len),
        Extent::Image => crate::file::read_regular(&full, MAX_IMAGE_FILE_BYTES, "an image file"),
    };
    read.map_err(|source| SceneError::Io {
        file: ctx.file.to_string(),
        what: format!("{path} '{}'", full.display()),
        source,
    })
}

/// Why an absolute path is refused as a URI (the buffer, image and environment URIs say the
/// same).
pub(super) fn absolute_uri_message(rel: &str) -> String {
    format!(
        "'{rel}' is an absolute path: a glTF URI is relative to the glTF file (or a data URI); \
         copy the file beside the scene or name it relatively"
    )
}

/// Every buffer's bytes, in file order, with the meshopt-compressed buffer views decoded into
/// them; `blob` is the GLB BIN chunk.
pub(super) fn load_buffers(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
        if super::meshopt::is_fallback(&b) {
            // Filled by the compressed views decoded into it (`meshopt::decode_views`); its
            // uri, if any, names uncompressed data for loaders without the extension.
            buffers.push(Vec::new());
            continue;
        }
        let data = match b.source() {
            // Only the first buffer may live in the GLB BIN chunk (§4.4.3.3); any other buffer
            // without a URI is a placeholder (valid, e.g. for extensions): empty.
            gltf::buffer::Source::Bin => match (blob, b.index()) {
                (Some(blob), 0) => blob.to_vec(),
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
            gltf::buffer::Source::Uri(uri) => {
                resolve_uri(ctx, uri, &path, Extent::Buffer(b.length() as u64))?
            }
        };
        if data.len() < b.length() {
            return Err(ctx.invalid((
                format!("{path}.byteLength"),
                format!("byteLength is {} but the data has {} bytes", b.length(), data.len()),
            )));
        }
        buffers.push(data);
    }
    super::meshopt::decode_views(ctx, doc, &mut buffers)?;
    Ok(buffers)
}

/// The images (glTF `images`, same indices): those some material uses decoded, the others
/// 1×1 white placeholders. An image that cannot be read or decoded is an error with
/// [`Ctx::strict`]; otherwise a warning, and the material slots that sample it are emptied (the
/// material's factors alone), its place a placeholder.
pub(super) fn load_images(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    materials: &mut [Material],
    textures: &[Texture],
) -> Result<Vec<Image>, SceneError> {
    let uses = image_uses(doc.images().len(), materials, textures);
    let named_by = super::texture_source::extension_paths(doc.as_json());
    let placeholder = || Image { width: 1, height: 1, texels: vec![[255; 4]] };
    let mut images = Vec::new();
    let mut failed = vec![false; uses.len()];
    for img in doc.images() {
        let i = img.index();
        let use_ = uses.get(i).copied().unwrap_or_default();
        if !use_.srgb && !use_.linear {
            images.push(placeholder());
            continue;
        }
        let named_by = named_by.get(i).and_then(Option::as_deref);
        match decode_image(ctx, doc, &img, buffers, use_, named_by) {
            Ok(image) => images.push(image),
            Err(e) if !ctx.strict => {
                ctx.warn(
                    format!("images[{i}]"),
                    format!(
                        "{}: the textures using it are left out (the material's factors alone)",
                        without_file(&e)
                    ),
                );
                images.push(placeholder());
                failed[i] = true;
            }
            Err(e) => return Err(e),
        }
    }
    forget_failed(materials, textures, &failed);
    Ok(images)
}

/// The error's message without the scene file (a warning is reported with the scene).
fn without_file(e: &SceneError) -> String {
    match e {
        SceneError::Io { what, source, .. } => format!("cannot read {what}: {source}"),
        SceneError::Image { message, .. } => format!("cannot decode image: {message}"),
        SceneError::Invalid { path, message, .. } => format!("{path}: {message}"),
        other => other.to_string(),
    }
}

/// Empties every material slot whose texture samples a `failed` image.
fn forget_failed(materials: &mut [Material], textures: &[Texture], failed: &[bool]) {
    let fails = |r: &Option<TextureRef>| {
        r.and_then(|r| textures.get(r.texture as usize))
            .is_some_and(|t| failed.get(t.image as usize).copied().unwrap_or(false))
    };
    for m in materials {
        for slot in [
            &mut m.base_color_texture,
            &mut m.metallic_roughness_texture,
            &mut m.normal_texture,
            &mut m.emissive_texture,
            &mut m.transmission_texture,
        ] {
            if fails(slot) {
                *slot = None;
            }
        }
    }
}

/// How the materials use an image: through a colour slot (sRGB-encoded: base colour,
/// emissive) or a data slot (linear: metallic-roughness, normal, transmission); neither: unused.
#[derive(Debug, Clone, Copy, Default)]
struct Uses {
    srgb: bool,
    linear: bool,
}

/// For each of the `count` images, how the textures of the materials sample it.
fn image_uses(count: usize, materials: &[Material], textures: &[Texture]) -> Vec<Uses> {
    let mut uses = vec![Uses::default(); count];
    for m in materials {
        for t in m.texture_refs() {
            if let Some(tex) = textures.get(t.texture as usize)
                && let Some(u) = uses.get_mut(tex.image as usize)
            {
                match t.color_space {
                    ColorSpace::Srgb => u.srgb = true,
                    ColorSpace::Linear => u.linear = true,
                }
            }
        }
    }
    uses
}

fn decode_image(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    img: &gltf::Image<'_>,
    buffers: &[Vec<u8>],
    uses: Uses,
    named_by: Option<&str>,
) -> Result<Image, SceneError> {
    let path = format!("images[{}]", img.index());
    // The JSON, not `Image::source()`, which unwraps a missing `uri` and a missing `mimeType`.
    let json = &doc.as_json().images[img.index()];
    let bytes: Vec<u8> = match (&json.uri, &json.buffer_view) {
        (None, Some(index)) => {
            let Some(view) = doc.views().nth(index.value()) else {
                return Err(ctx.invalid((format!("{path}.bufferView"), "buffer view does not exist".into())));
            };
            if json.mime_type.is_none() {
                ctx.warn(
                    format!("{path}.mimeType"),
                    "missing (required with a bufferView): the format is recognised from the bytes",
                );
            }
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
        (Some(uri), None) => resolve_uri(ctx, uri, &path, Extent::Image)?,
        (uri, _) => {
            let which =
                if uri.is_some() { "both a uri and a bufferView" } else { "neither a uri nor a bufferView" };
            return Err(ctx.invalid((path, format!("{which}: an image needs exactly one"))));
        }
    };
    // What the messages call the image: its file, or where its bytes are, and the texture
    // extension that names it.
    let mut name = match (&json.uri, &json.buffer_view) {
        (Some(uri), _) if uri.starts_with("data:") => "a data URI".to_string(),
        (Some(uri), _) => format!("'{}'", percent_decode(uri)),
        (_, Some(view)) => format!("bufferViews[{}]", view.value()),
        _ => String::new(),
    };
    if let Some(by) = named_by {
        name = format!("{name} (named by {by})");
    }
    let image_error =
        |message: String| SceneError::Image { file: ctx.file.to_string(), path: path.clone(), message };
    if super::ktx2::is_ktx2(&bytes) {
        let decoded = super::ktx2::decode(&bytes, crate::MAX_TEXTURE_SIZE)
            .map_err(|e| image_error(format!("{name}: KTX2: {e}")))?;
        return Ok(ktx2_image(ctx, &path, &name, decoded, uses));
    }
    let mut reader = image::ImageReader::new(std::io::Cursor::new(&bytes))
        .with_guessed_format()
        .map_err(|e| image_error(format!("{name}: {e}")))?;
    // The size from the header, refused (with the size in the message) before any texel is
    // allocated; then the decoder gets the width, height and allocation limits, which image's
    // decoders also enforce themselves.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_TEXTURE_DECODE_BYTES);
    reader.limits(limits.clone());
    let mut decoder =
        reader.into_decoder().map_err(|e| image_error(format!("{name}: {}", texture_decode_message(&e))))?;
    let (w, h) = image::ImageDecoder::dimensions(&decoder);
    if w > crate::MAX_TEXTURE_SIZE || h > crate::MAX_TEXTURE_SIZE {
        return Err(image_error(format!("{name}: {}", texture_too_large(w, h))));
    }
    limits.max_image_width = Some(crate::MAX_TEXTURE_SIZE);
    limits.max_image_height = Some(crate::MAX_TEXTURE_SIZE);
    image::ImageDecoder::set_limits(&mut decoder, limits)
        .map_err(|e| image_error(format!("{name}: {}", texture_decode_message(&e))))?;
    // `DynamicImage::from_decoder` allocates the decoded image without consulting the limits.
    if image::ImageDecoder::total_bytes(&decoder) > MAX_TEXTURE_DECODE_BYTES {
        return Err(image_error(format!(
            "{name}: {}",
            texture_decode_message(&image::ImageError::Limits(
                image::error::LimitErrorKind::InsufficientMemory.into()
            ))
        )));
    }
    let decoded = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| image_error(format!("{name}: {}", texture_decode_message(&e))))?;
    let rgba = decoded.to_rgba8();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err(image_error(format!("{name}: zero-sized image")));
    }
    let texels = rgba.pixels().map(|p| p.0).collect();
    Ok(Image { width, height, texels })
}

/// A decoded KTX2 image as 8-bit texels for the slots that use it. 8-bit data is kept as
/// stored, read as sRGB or linear by the slot (as PNG and JPEG are), with a warning when the
/// file's transfer function says otherwise; float data (linear) is encoded for the slot:
/// sRGB-encoded for colour slots, plain for data slots.
fn ktx2_image(ctx: &mut Ctx<'_>, path: &str, name: &str, decoded: super::ktx2::Decoded, uses: Uses) -> Image {
    use super::ktx2::Texels;
    let format = &decoded.format;
    let texels = match decoded.texels {
        Texels::Unorm8 { texels, srgb } => {
            if srgb && uses.linear {
                ctx.warn(
                    path,
                    format!(
                        "{name}: {format} is marked sRGB but a data slot (metallic-roughness, normal) uses it: \
                         its values are read as linear, as glTF requires there"
                    ),
                );
            }
            if !srgb && uses.srgb {
                ctx.warn(
                    path,
                    format!(
                        "{name}: {format} is marked linear but a colour slot (base colour, emissive) uses it: \
                         its values are read as sRGB, as glTF requires there"
                    ),
                );
            }
            texels
        }
        Texels::Float(texels) => {
            if uses.srgb && uses.linear {
                ctx.warn(
                    path,
                    format!("{name}: {format} is used by colour and data slots alike: stored sRGB-encoded for the colour slots"),
                );
            }
            let q = furnace_post::quantize_unorm8;
            let encode =
                |v: f32| if uses.srgb { q(furnace_post::linear_to_srgb(v.clamp(0.0, 1.0))) } else { q(v) };
            texels.into_iter().map(|[r, g, b, a]| [encode(r), encode(g), encode(b), q(a)]).collect()
        }
    };
    Image { width: decoded.width, height: decoded.height, texels }
}

fn texture_too_large(w: u32, h: u32) -> String {
    let max = crate::MAX_TEXTURE_SIZE;
    format!("{w} × {h} texels: a texture may have at most {max} × {max}")
}

/// The decoder's message, with image's limit errors said in furnace's terms.
fn texture_decode_message(e: &image::ImageError) -> String {
    match e {
        image::ImageError::Limits(l) => match l.kind() {
            image::error::LimitErrorKind::DimensionError => {
                let max = crate::MAX_TEXTURE_SIZE;
                format!("larger than the {max} × {max} texels a texture may have")
            }
            _ => format!(
                "decoding needs more than the {} MiB a texture may take",
                MAX_TEXTURE_DECODE_BYTES >> 20
            ),
        },
        other => other.to_string(),
    }
}
