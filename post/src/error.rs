//! Errors of writing and reading images, each naming the file.

use std::path::PathBuf;
use thiserror::Error;

/// What can go wrong in post-processing I/O. Every file error carries the path it concerns.
#[derive(Debug, Error)]
pub enum PostError {
    /// An operating-system error (creating, syncing or renaming a file, …).
    #[error("{path}: {source}", path = .path.display())]
    Io {
        /// The file concerned (for a failed rename, the final path).
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The `exr` crate could not encode or decode the file.
    #[error("{path}: OpenEXR: {source}", path = .path.display())]
    Exr {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: exr::error::Error,
    },
    /// The `image` crate could not encode the PNG.
    #[error("{path}: PNG: {source}", path = .path.display())]
    Png {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: image::ImageError,
    },
    /// The pixel buffer does not hold `width × height` pixels, or the image is empty.
    #[error("{path}: a {width}×{height} image needs {expected} pixels (and at least one), got {got}", path = .path.display())]
    SizeMismatch {
        /// The file that was to be written.
        path: PathBuf,
        /// The width given.
        width: u32,
        /// The height given.
        height: u32,
        /// `width × height` (saturating).
        expected: usize,
        /// The buffer's length.
        got: usize,
    },
    /// An extra metadata key cannot be stored as an EXR attribute name.
    #[error("{path}: metadata key '{key}' cannot be written: {reason}", path = .path.display())]
    InvalidMetadataKey {
        /// The file that was to be written.
        path: PathBuf,
        /// The offending key.
        key: String,
        /// Why (reserved, empty, too long, not printable ASCII).
        reason: &'static str,
    },
    /// A furnace metadata attribute in an EXR file does not parse as its type.
    #[error("{path}: attribute '{key}' = '{value}' is not a valid {expected}", path = .path.display())]
    InvalidMetadataValue {
        /// The file that was read.
        path: PathBuf,
        /// The attribute name.
        key: String,
        /// Its text.
        value: String,
        /// The expected type (`u32`, `u64`, `f64`).
        expected: &'static str,
    },
    /// The accumulation state (`furnace.resume.*` channels) cannot be written or read.
    #[error("{path}: resume state: {reason}", path = .path.display())]
    FilmState {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// An unknown tone-map name (from [`crate::Tonemap`]'s `FromStr`).
    #[error("unknown tone map '{0}' (expected one of: aces, pbr-neutral, clamp)")]
    UnknownTonemap(String),
}
