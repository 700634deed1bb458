//! 8-bit sRGB PNG output through the `image` crate.

use crate::PostError;
use crate::atomic::{Staged, stage};
use crate::exr_io::check_size;
use image::ImageEncoder;
use image::codecs::png::PngEncoder;
use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes an 8-bit RGB PNG, rows top to bottom, atomically (temporary file + rename: an
/// interrupted write never leaves a truncated PNG at `path`, and a failed one leaves no temporary
/// file). The pixels are already sRGB-encoded (see [`crate::to_srgb8`]); no colour chunk is
/// written, and PNG readers assume sRGB.
///
/// # Errors
/// [`PostError::SizeMismatch`] if `pixels.len() != width · height` or the image is empty;
/// [`PostError::Png`] / [`PostError::Io`] on encoding or file errors. All name `path`.
pub fn write_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    pixels: &[[u8; 3]],
) -> Result<(), PostError> {
    stage_png(path, width, height, pixels)?.commit()
}

/// What [`write_png`] writes, left at its temporary name until [`Staged::commit`]: for files
/// that are replaced together or not at all (a render's EXR and PNG).
///
/// # Errors
/// As [`write_png`].
pub fn stage_png(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    pixels: &[[u8; 3]],
) -> Result<Staged, PostError> {
    let path = path.as_ref();
    check_size(path, width, height, pixels.len())?;
    let bytes: Vec<u8> = pixels.iter().flatten().copied().collect();
    stage(path, |file| {
        let mut out = BufWriter::new(file);
        PngEncoder::new(&mut out)
            .write_image(&bytes, width, height, image::ExtendedColorType::Rgb8)
            .map_err(|source| PostError::Png { path: path.to_path_buf(), source })?;
        out.flush().map_err(|source| PostError::Io { path: path.to_path_buf(), source })
    })
}
