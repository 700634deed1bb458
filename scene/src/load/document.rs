//! Parsing and checking the document before anything is read from it: the GLB header, the
//! required and used extensions, and gltf-json's validation (with the leniencies the
//! specification allows).

use super::context::Ctx;
use crate::accessor::Located;
use crate::error::SceneError;

/// Extensions furnace honours, so a file may require them.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_specular",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_unlit",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    super::variants::EXTENSION,
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    super::instancing::EXTENSION,
    super::texture_source::BASISU,
    super::texture_source::WEBP,
];

/// An extension a glTF file lists (`extensionsUsed`, `extensionsRequired`), as
/// [`Scene::extensions`](crate::Scene::extensions) reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExtensionUse {
    /// The extension's name (`EXT_mesh_gpu_instancing`).
    pub name: String,
    /// The file lists it in `extensionsRequired`: a reader that does not honour it must refuse
    /// the file.
    pub required: bool,
}

impl ExtensionUse {
    /// furnace honours it (it is one of [`SUPPORTED_EXTENSIONS`]); otherwise the loader ignores
    /// it with a warning.
    pub fn honoured(&self) -> bool {
        SUPPORTED_EXTENSIONS.contains(&self.name.as_str())
    }
}

/// The extensions `root` lists: those of `extensionsUsed` in its order, then any only in
/// `extensionsRequired` (which glTF forbids, but a file may do), each once.
pub(super) fn extensions(root: &gltf::json::Root) -> Vec<ExtensionUse> {
    let mut out: Vec<ExtensionUse> = Vec::new();
    for name in root.extensions_used.iter().chain(&root.extensions_required) {
        if !out.iter().any(|e| &e.name == name) {
            let required = root.extensions_required.contains(name);
            out.push(ExtensionUse { name: name.clone(), required });
        }
    }
    out
}

/// Extensions whose absence changes the look but which furnace ignores with a warning when
/// only *used* (never when *required*).
const IGNORED_WITH_WARNING: &str = "is used but not supported: ignored";

/// Parses a glTF (JSON or GLB) without gltf-json's validation (see [`check`]): the document
/// and the GLB BIN chunk, if any.
pub(super) fn parse(bytes: &[u8], file: &str) -> Result<(gltf::Document, Option<Vec<u8>>), SceneError> {
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
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| SceneError::Parse {
        file: file.to_string(),
        message: without_found_value(&e.to_string()),
    })?;
    Ok((gltf.document, gltf.blob))
}

/// The JSON parser's message without the value it found (serde's `invalid type: string "…",
/// expected …`, `unknown variant `…``): the line, the column and what was expected say where
/// and what is wrong, and a file that is not glTF (a text file named by mistake) must not have
/// its content printed.
fn without_found_value(message: &str) -> String {
    let mut m = message.to_string();
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(i) = m.find(prefix)
            && let Some(j) = m.rfind(", expected").filter(|&j| j > i)
        {
            let found = &m[i + prefix.len()..j];
            let kind = found.split(['`', '"']).next().unwrap_or("").trim().to_string();
            m.replace_range(i + prefix.len()..j, &kind);
        }
    }
    for prefix in ["unknown variant `", "unknown field `"] {
        if let Some(i) = m.find(prefix)
            && let Some(j) = m.rfind("`, expected").filter(|&j| j >= i + prefix.len())
        {
            m.replace_range(i + prefix.len() - 2..j + 1, "");
        }
    }
    m
}

/// Refuses a required extension furnace does not support and a document that fails
/// validation; warns about each used extension it ignores.
pub(super) fn check(ctx: &mut Ctx<'_>, root: &gltf::json::Root) -> Result<(), SceneError> {
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if ext == super::texture_source::AVIF {
            return Err(super::texture_source::avif_required(ctx, root, i));
        }
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(SceneError::UnsupportedExtension {
                file: ctx.file.to_string(),
                path: format!("extensionsRequired[{i}]"),
                extension: ext.clone(),
            });
        }
    }
    precheck(root).map_err(|e| ctx.invalid(e))?;
    validate(ctx, root)?;
    for (i, ext) in root.extensions_used.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            ctx.warn(format!("extensionsUsed[{i}]"), format!("{ext} {IGNORED_WITH_WARNING}"));
        }
    }
    Ok(())
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

/// gltf-json's validation: the first problem (and how many more) is an error.
fn validate(ctx: &Ctx<'_>, root: &gltf::json::Root) -> Result<(), SceneError> {
    use gltf::json::validation::{Error as VE, Validate};
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, err| {
        let path = path().to_string();
        // gltf-json is stricter than the specification here: an accessor without a
        // bufferView is all zeros (§3.6.2.1) and a texture's source is optional (§5.29);
        // both are handled where they are read. Unsupported extensions are checked by `check`.
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::without_found_value;

    #[test]
    fn parse_messages_keep_no_found_value() {
        let cases = [
            (
                "invalid type: string \"secret, expected x\", expected u32 at line 3 column 9",
                "invalid type: string, expected u32 at line 3 column 9",
            ),
            (
                "invalid value: integer `42`, expected a u8 at line 1 column 2",
                "invalid value: integer, expected a u8 at line 1 column 2",
            ),
            (
                "unknown variant `SECRET`, expected `SCALAR` or `VEC2` at line 2 column 4",
                "unknown variant, expected `SCALAR` or `VEC2` at line 2 column 4",
            ),
            ("expected value at line 1 column 1", "expected value at line 1 column 1"),
            ("missing field `asset` at line 1 column 2", "missing field `asset` at line 1 column 2"),
        ];
        for (raw, want) in cases {
            assert_eq!(without_found_value(raw), want);
        }
    }
}
