//! # furnace-post
//!
//! From linear radiance to files: exposure, tone mapping, the exact sRGB transfer function,
//! 8-bit quantisation, and atomic OpenEXR / PNG output (the thesis, §4.1–4.3).
//!
//! ## The display pipeline ([`to_srgb8`])
//!
//! 1. **Exposure** — multiply by [`exposure_scale`]`(ev) = 2^ev` (the thesis §4.1, without its
//!    FP16 scale factor: EV 0 leaves radiance unchanged).
//! 2. **Tone map** — [`Tonemap`]: `aces` (Narkowicz 2015, "ACES Filmic Tone Mapping Curve", the
//!    thesis listing 4.1), `pbr-neutral` (Khronos PBR Neutral, 2024), or `clamp`.
//!    Non-finite input is defined: NaN → 0, +∞ → 1, negatives → 0.
//! 3. **Encode** — the exact sRGB OETF of IEC 61966-2-1 ([`linear_to_srgb`], the thesis §4.3;
//!    not the `x^(1/2.2)` approximation), inverse [`srgb_to_linear`].
//! 4. **Quantise** — round to nearest 8-bit code ([`quantize_unorm8`]); every code survives
//!    code → linear → code.
//!
//! ## Metrics
//!
//! [`metrics`]: RMSE, relative MSE (one ε, 1e-2), mean ratio and z-scores of a render against a
//! reference — what `furnace compare`, `furnace chart` and the reference tests report.
//!
//! ## Files
//!
//! [`write_exr`] stores the *linear* image as 32-bit float RGB with the render's [`Metadata`]
//! as text attributes; [`read_exr`] reads it back bit-identically and also reads other
//! renderers' EXRs (e.g. Mitsuba 3's `B,G,R` float references). [`write_exr_with_state`] adds a
//! progressive render's exact accumulation state (a `furnace_render::Film`'s per-pixel `f64` sums and counts, in the
//! [`RESUME_LAYER`] channels) so that it can be resumed bit-identically; [`read_exr_with_state`]
//! reads it back. [`write_png`] stores the 8-bit sRGB image. All writers are **atomic**: they
//! write a temporary file in the target's directory and rename it into place, so an
//! interrupted write never leaves a truncated image, and a failed write removes its temporary
//! file; [`stage`], [`stage_exr_with_state_and`] and [`stage_png`] write several files that are
//! renamed into place together, or not at all. Readers open regular files only (a FIFO or a device
//! is refused before it is opened) and check the header's image size against [`MAX_IMAGE_SIDE`]
//! and the file's length ([`MAX_COMPRESSION_RATIO`]) before any pixel is allocated. Errors are
//! [`PostError`]s naming the file.
//!
//! ## Example
//!
//! ```
//! use furnace_post::{Metadata, Tonemap, read_exr, to_srgb8, write_exr, write_png};
//! use glam::Vec3;
//!
//! let (w, h) = (2, 1);
//! let radiance = vec![Vec3::new(0.18, 0.18, 0.18), Vec3::new(4.0, 1.0, 0.25)];
//! let dir = std::env::temp_dir().join(format!("furnace-post-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//!
//! let meta = Metadata { spp: Some(64), sampler: Some("sobol".into()), ..Metadata::default() };
//! write_exr(dir.join("render.exr"), w, h, &radiance, &meta)?;
//! let (rw, rh, back, back_meta) = read_exr(dir.join("render.exr"))?;
//! assert_eq!((rw, rh), (w, h));
//! assert_eq!(back, radiance); // 32-bit float: bit-identical
//! assert_eq!(back_meta, meta);
//!
//! let srgb = to_srgb8(&radiance, 0.0, Tonemap::Aces);
//! assert_eq!(srgb[0], [141, 141, 141]); // ACES(0.18) = 0.2669 → sRGB 0.5534 → 141
//! write_png(dir.join("render.png"), w, h, &srgb)?;
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod atomic;
mod error;
mod exr_io;
pub mod metrics;
mod png_io;
mod srgb;
mod tonemap;

pub use atomic::{
    Staged, remove_stale_temporaries, remove_temporaries_in_flight, stage, write_atomic, write_bytes_atomic,
};
pub use error::{PostError, printable_excerpt};
pub use exr_io::{
    AOV_CHANNELS, ExrWithState, ExtraChannel, MAX_COMPRESSION_RATIO, MAX_IMAGE_SIDE, Metadata, RESUME_LAYER,
    read_exr, read_exr_metadata, read_exr_with_state, stage_exr_with_state_and, state_channel_count,
    write_exr, write_exr_with_state, write_exr_with_state_and,
};
pub use png_io::{stage_png, write_png};
pub use srgb::{linear_to_srgb, pixel_to_srgb8, quantize_unorm8, srgb_to_linear, srgb8_to_linear, to_srgb8};
pub use tonemap::{Tonemap, aces_filmic, exposure_scale, pbr_neutral};
