//! Typed errors and warnings. Every error names the file (or the built-in scene) and, where
//! there is one, the place in it as a glTF JSON path (`accessors[2].bufferView`).

use std::fmt;

/// Why a scene could not be loaded. `Display` gives one line: `FILE: PLACE: what went wrong`.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file (the scene itself, or a buffer or image it references) could not be read.
    #[error("{file}: cannot read {what}: {source}")]
    Io {
        /// The scene file.
        file: String,
        /// What was being read: the scene itself or `buffers[0] 'x.bin'` and the like.
        what: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The bytes are not glTF: bad JSON, a bad GLB container.
    #[error("{file}: not a glTF 2.0 file: {message}")]
    Parse {
        /// The scene file.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// The glTF is structurally invalid at `path` (validation, bounds, counts).
    #[error("{file}: {path}: {message}")]
    Invalid {
        /// The scene file.
        file: String,
        /// The glTF JSON path of the offending item.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// The file requires an extension furnace cannot honour (e.g. Draco compression).
    #[error("{file}: {path}: requires unsupported extension {extension}")]
    UnsupportedExtension {
        /// The scene file.
        file: String,
        /// Where it is required (`extensionsRequired[0]`).
        path: String,
        /// The extension's name.
        extension: String,
    },
    /// An image could not be decoded.
    #[error("{file}: {path}: cannot decode image: {message}")]
    Image {
        /// The scene file.
        file: String,
        /// The glTF JSON path of the image (`images[3]`).
        path: String,
        /// The decoder's message.
        message: String,
    },
    /// The environment map the scene names (`scenes[0].extras.environment.uri`) could not be
    /// used.
    #[error("{file}: {path}: {source}")]
    Environment {
        /// The scene file.
        file: String,
        /// The glTF JSON path of the reference.
        path: String,
        /// What is wrong with the map (names the map's file).
        source: crate::EnvironmentError,
    },
    /// The material variant a load asked for ([`crate::LoadOptions::variant`]) is neither a
    /// name nor an index of the file's KHR_materials_variants.
    #[error("{file}: no material variant '{variant}': {}", variant_list(available))]
    UnknownVariant {
        /// The scene file.
        file: String,
        /// The name asked for.
        variant: String,
        /// The file's variants, in order.
        available: Vec<String>,
    },
    /// The animation a load asked for ([`crate::LoadOptions::animation`], or animation 0 for a
    /// [`crate::LoadOptions::time`] alone) is neither a name nor an index of the file's
    /// animations.
    #[error("{file}: no animation '{animation}': {}", animation_list(available))]
    UnknownAnimation {
        /// The scene file.
        file: String,
        /// The name asked for.
        animation: String,
        /// The file's animations, in order.
        available: Vec<crate::AnimationInfo>,
    },
    /// The file is valid but yields no renderable triangle.
    #[error("{file}: nothing to render: {reason}")]
    NothingToRender {
        /// The scene file.
        file: String,
        /// Why (no scene, no mesh, every triangle degenerate...).
        reason: String,
    },
}

impl SceneError {
    /// A short name of the error's kind, for summaries (`io`, `parse`, `invalid`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Io { .. } => "io",
            Self::Parse { .. } => "parse",
            Self::Invalid { .. } => "invalid",
            Self::UnsupportedExtension { .. } => "unsupported-extension",
            Self::Image { .. } => "image",
            Self::Environment { .. } => "environment",
            Self::UnknownVariant { .. } => "unknown-variant",
            Self::UnknownAnimation { .. } => "unknown-animation",
            Self::NothingToRender { .. } => "nothing-to-render",
        }
    }
}

/// The variants a file offers, for [`SceneError::UnknownVariant`]'s message.
fn variant_list(names: &[String]) -> String {
    if names.is_empty() {
        return "the file has no variants (KHR_materials_variants)".to_string();
    }
    let quoted: Vec<String> = names.iter().enumerate().map(|(i, n)| format!("{i} '{n}'")).collect();
    format!("the file's variants are {}", quoted.join(", "))
}

/// The animations a file offers, for [`SceneError::UnknownAnimation`]'s message.
fn animation_list(animations: &[crate::AnimationInfo]) -> String {
    if animations.is_empty() {
        return "the file has no animations".to_string();
    }
    let listed: Vec<String> =
        animations.iter().enumerate().map(|(i, a)| format!("{i} '{}' ({} s)", a.name, a.duration)).collect();
    format!("the file's animations are {}", listed.join(", "))
}

/// Something the loader ignored or repaired; the scene still loads. Identical warnings are
/// reported once (see [`crate::Scene::warnings`]).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Warning {
    /// The glTF JSON path it concerns (`meshes[0].primitives[1]`), or `""` for the whole file.
    pub path: String,
    /// What was ignored or repaired.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}
