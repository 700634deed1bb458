//! Which image a texture samples. The image-format extensions name an image in their format,
//! `source` the fallback for clients without it: KHR_texture_basisu (KTX2 with Basis Universal)
//! first, then EXT_texture_webp, then `source`. EXT_texture_avif is never taken: no AV1
//! decoder builds here without system libraries (the pure-Rust ones need a newer compiler
//! than the workspace's, or unsafe bindings); a file that requires it is refused, one that
//! only uses it falls back to `source` with a warning.

use super::context::Ctx;
use super::resources::percent_decode;
use crate::error::SceneError;
use gltf::json;

/// KHR_texture_basisu: a KTX2 image (ETC1S or UASTC payload).
pub const BASISU: &str = "KHR_texture_basisu";
/// EXT_texture_webp: a WebP image.
pub const WEBP: &str = "EXT_texture_webp";
/// EXT_texture_avif: an AVIF image (not decoded).
pub const AVIF: &str = "EXT_texture_avif";

/// The image-format extensions that are decoded, in the order they are preferred.
const DECODED: [&str; 2] = [BASISU, WEBP];

/// `extensions.<ext>.source` of a texture: `None` without the extension, `Some(None)` when its
/// source is not a non-negative integer.
fn extension_source(tj: &json::Texture, ext: &str) -> Option<Option<usize>> {
    let value = tj.extensions.as_ref()?.others.get(ext)?;
    Some(value.get("source").and_then(json::Value::as_u64).and_then(|s| usize::try_from(s).ok()))
}

/// The image texture `t` samples, or `None` (with a warning from the caller) when it has none
/// that exists. Warns about an extension whose source is invalid and about an AVIF image left
/// for the fallback.
pub(super) fn choose(ctx: &mut Ctx<'_>, doc: &gltf::Document, t: usize, tj: &json::Texture) -> Option<u32> {
    let count = doc.images().len();
    for ext in DECODED {
        match extension_source(tj, ext) {
            None => {}
            Some(Some(i)) if i < count => return Some(i as u32),
            Some(_) => ctx.warn(
                format!("textures[{t}].extensions.{ext}.source"),
                format!("not one of the {count} images: the extension is ignored"),
            ),
        }
    }
    let source = tj.source.value();
    let source = (source < count).then_some(source as u32);
    if let Some(avif) = extension_source(tj, AVIF) {
        let image = avif.map_or("an invalid image".to_string(), |i| format!("images[{i}]"));
        let fallback = match source {
            Some(s) => format!("its fallback images[{s}] (`source`) is used"),
            None => "the texture has no fallback `source`".to_string(),
        };
        ctx.warn(
            format!("textures[{t}].extensions.{AVIF}"),
            format!("{image} is AVIF, which furnace does not decode: {fallback}"),
        );
    }
    source
}

/// For each image, the path of the first texture extension that names it
/// (`textures[1].extensions.KHR_texture_basisu`), for its error messages.
pub(super) fn extension_paths(root: &json::Root) -> Vec<Option<String>> {
    let mut paths = vec![None; root.images.len()];
    for (t, tj) in root.textures.iter().enumerate() {
        for ext in DECODED {
            if let Some(Some(i)) = extension_source(tj, ext)
                && let Some(p) = paths.get_mut(i)
                && p.is_none()
            {
                *p = Some(format!("textures[{t}].extensions.{ext}"));
            }
        }
    }
    paths
}

/// The error for a file that requires EXT_texture_avif: names the first texture that uses it
/// and its image.
pub(super) fn avif_required(ctx: &Ctx<'_>, root: &json::Root, required_at: usize) -> SceneError {
    let used = root.textures.iter().enumerate().find_map(|(t, tj)| Some((t, extension_source(tj, AVIF)?)));
    let path = match used {
        Some((t, Some(i))) => {
            let name = match root.images.get(i).and_then(|im| im.uri.as_deref()) {
                Some(uri) if uri.starts_with("data:") => " (a data URI)".to_string(),
                Some(uri) => format!(" '{}'", percent_decode(uri)),
                None => String::new(),
            };
            format!("textures[{t}].extensions.{AVIF} (images[{i}]{name})")
        }
        Some((t, None)) => format!("textures[{t}].extensions.{AVIF}"),
        None => format!("extensionsRequired[{required_at}]"),
    };
    SceneError::UnsupportedExtension {
        file: ctx.file.to_string(),
        path,
        extension: format!("{AVIF} (AVIF images are not decoded: no AV1 decoder is built in)"),
    }
}
