//! What several subcommands share: how a run ended, the image size a camera gives, the
//! scene's load options, and atomic file writes.

use crate::args::MAX_SIDE;
use furnace_scene::{Camera, Projection};
use std::path::Path;

/// Untimed rendering before a timed measurement (`bench`, `chart`): an idle GPU's clocks take
/// about a second to ramp up, so a measurement that starts right after a pipeline's compile or a
/// scene load (seconds of an idle GPU) reads low (BENCHMARKS.md, "Speed").
pub const WARM_UP_SECONDS: f64 = 1.0;

/// Default image width (and height for a square camera such as the built-in Cornell box's).
pub const DEFAULT_WIDTH: u32 = 512;

/// Largest number of pixels accepted (8192² — 2 GiB of `f64` film).
const MAX_PIXELS: u64 = 1 << 26;

/// Refuses the load options only a glTF file honours (`--variant`, `--animation`, `--time`) for a
/// built-in scene (`is_file` false).
pub(crate) fn check_builtin_options(
    options: &furnace_scene::LoadOptions,
    is_file: bool,
) -> Result<(), String> {
    if is_file {
        return Ok(());
    }
    if let Some(v) = &options.variant {
        return Err(format!("--variant {v}: the built-in scenes have no material variants"));
    }
    if let Some(a) = &options.animation {
        return Err(format!("--animation {a}: the built-in scenes have no animations"));
    }
    if let Some(t) = options.time {
        return Err(format!("--time {t}: the built-in scenes have no animations"));
    }
    Ok(())
}

/// How a render ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Finished (or stopped by `--time-limit`, or nothing was left to render).
    Done,
    /// Stopped by Ctrl-C (exit code 130); the partial render is saved if a pass was done.
    Interrupted,
}

/// The image size: given sides win; a missing side follows the camera's aspect ratio (the
/// file's `aspectRatio`, or `xmag/ymag` of an orthographic camera; square without one).
pub(crate) fn image_size(
    camera: &Camera,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<(u32, u32), String> {
    let aspect = match camera.projection {
        Projection::Perspective { aspect_ratio, .. } => aspect_ratio.unwrap_or(1.0),
        Projection::Orthographic { xmag, ymag } => xmag / ymag,
    };
    let aspect = if aspect.is_finite() && aspect > 0.0 { f64::from(aspect) } else { 1.0 };
    let side = |x: f64| x.round().clamp(1.0, f64::from(MAX_SIDE)) as u32;
    let (w, h) = match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, side(f64::from(w) / aspect)),
        (None, Some(h)) => (side(f64::from(h) * aspect), h),
        (None, None) => (DEFAULT_WIDTH, side(f64::from(DEFAULT_WIDTH) / aspect)),
    };
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(format!("a {w}×{h} image is too large (at most {MAX_PIXELS} pixels)"));
    }
    Ok((w, h))
}

/// Writes `bytes` to `path` atomically (`furnace_post::write_bytes_atomic`).
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    furnace_post::write_bytes_atomic(path, bytes).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use furnace_scene::builtin;

    #[test]
    fn cornell_box_defaults_to_512_square() {
        let camera = builtin::cornell_box().unwrap().default_camera();
        assert_eq!(image_size(&camera, None, None).unwrap(), (512, 512));
        assert_eq!(image_size(&camera, Some(64), None).unwrap(), (64, 64));
        assert!(image_size(&camera, Some(16_384), Some(16_384)).is_err());
    }
}
