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
    /// A furnace metadata attribute in an EXR file does not parse as its type. The message
    /// shows the value only as [`printable_excerpt`] does.
    #[error("{path}: attribute '{key}' = {shown} is not a valid {expected}", path = .path.display(), shown = printable_excerpt(.value))]
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
    /// The path names something other than a regular file (a directory, a FIFO, a device):
    /// it is not opened.
    #[error("{path}: {kind}, not a regular file: images are read only from regular files", path = .path.display())]
    NotAFile {
        /// The path given.
        path: PathBuf,
        /// What it is (`a FIFO`, `a directory`, …).
        kind: &'static str,
    },
    /// The header's data window is larger than [`crate::MAX_IMAGE_SIDE`] on a side.
    #[error(
        "{path}: header attribute 'dataWindow' gives {width}×{height} pixels, more than furnace reads \
         ({max} per side, the largest image it renders)",
        path = .path.display(),
        max = crate::MAX_IMAGE_SIDE
    )]
    TooLarge {
        /// The file that was read.
        path: PathBuf,
        /// The width the header gives.
        width: u64,
        /// The height the header gives.
        height: u64,
    },
    /// The headers claim more pixel data than the file can hold, even compressed at
    /// [`crate::MAX_COMPRESSION_RATIO`]: a damaged or crafted file.
    #[error(
        "{path}: header attribute 'dataWindow' gives {width}×{height} pixels, {claimed} bytes of pixel \
         data with the layers before it, more than a file of {file_bytes} bytes holds: the file is \
         truncated or damaged",
        path = .path.display()
    )]
    TooLittleData {
        /// The file that was read.
        path: PathBuf,
        /// The width of the layer that went over.
        width: u64,
        /// Its height.
        height: u64,
        /// Uncompressed bytes claimed by the headers up to that layer.
        claimed: u64,
        /// The file's length.
        file_bytes: u64,
    },
    /// An unknown tone-map name (from [`crate::Tonemap`]'s `FromStr`).
    #[error("unknown tone map '{0}' (expected one of: aces, pbr-neutral, clamp)")]
    UnknownTonemap(String),
}

/// How furnace's messages show a text read from a file (an attribute value): in quotes if it is
/// short printable ASCII, else only its length — never a file's raw bytes, which could be
/// control sequences for the terminal or megabytes long.
pub fn printable_excerpt(text: &str) -> String {
    /// The longest value shown: a number, a sampler's name, a sample range.
    const SHOWN: usize = 40;
    if text.len() <= SHOWN && text.bytes().all(|b| b.is_ascii_graphic() || b == b' ') {
        format!("'{text}'")
    } else {
        format!("(a text of {} bytes)", text.len())
    }
}
