//! The file's bytes: buffers (GLB BIN chunk, data URIs, relative files) and the images the
//! materials use, decoded to 8-bit RGBA.

use super::context::Ctx;
use crate::error::SceneError;
use crate::material::Material;
use crate::texture::{Image, Texture};

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

/// Every buffer's bytes, in file order; `blob` is the GLB BIN chunk.
pub(super) fn load_buffers(
    ctx: &mut Ctx<'_>,
    doc: &gltf::Document,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
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
            gltf::buffer::Source::Uri(uri) => resolve_uri(ctx, uri, &path)?,
        };
        if data.len() < b.length() {
            return Err(ctx.invalid((
                format!("{path}.byteLength"),
                format!("byteLength is {} but the data has {} bytes", b.length(), data.len()),
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The images (glTF `images`, same indices): those some material uses decoded, the others
/// 1×1 white placeholders.
pub(super) fn load_images(
    ctx: &Ctx<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    materials: &[Material],
    textures: &[Texture],
) -> Result<Vec<Image>, SceneError> {
    let used = used_images(doc.images().len(), materials, textures);
    let mut images = Vec::new();
    for img in doc.images() {
        if !used.get(img.index()).copied().unwrap_or(false) {
            images.push(Image { width: 1, height: 1, texels: vec![[255; 4]] });
            continue;
        }
        images.push(decode_image(ctx, &img, buffers)?);
    }
    Ok(images)
}

/// For each of the `count` images, whether a texture of some material samples it.
fn used_images(count: usize, materials: &[Material], textures: &[Texture]) -> Vec<bool> {
    let mut used = vec![false; count];
    for m in materials {
        for t in [m.base_color_texture, m.metallic_roughness_texture, m.normal_texture, m.emissive_texture]
            .into_iter()
            .flatten()
        {
            if let Some(tex) = textures.get(t.texture as usize)
                && let Some(u) = used.get_mut(tex.image as usize)
            {
                *u = true;
            }
        }
    }
    used
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
