//! # furnace-denoise
//!
//! Denoising of a path tracer's linear HDR image with [Intel Open Image Denoise][oidn] 2.x
//! (OIDN: a U-Net trained on Monte Carlo noise), optionally guided by the first-hit albedo and
//! normal images. OIDN is a native library, so it is optional: this crate always builds and has
//! the same API either way, and only with its `oidn` cargo feature does [`denoise`] do anything;
//! without it, [`denoise`] returns [`DenoiseError::NotBuilt`], whose message says how to get
//! it, and [`available`] is `false`.
//!
//! ```text
//! OIDN_DIR=$(bash denoise/install-oidn.sh)          # OIDN 2.5.1 from the pyoidn wheel
//! OIDN_DIR=… cargo test -p furnace-denoise --features oidn
//! ```
//!
//! A binary that links OIDN must find `libOpenImageDenoise.so.2` at run time: this crate's own
//! tests and examples get an rpath to `$OIDN_DIR/lib`; another crate's binaries need one line
//! in their build script — see the README, "Run-time library path".
//!
//! ## What [`denoise`] does
//!
//! 1. **Checks** the buffers: a non-empty `width × height` image, every given buffer exactly
//!    `width × height` pixels (row-major, top row first), a normal guide only with an albedo
//!    guide (OIDN uses normals only together with albedo). Any violation is an error, never a
//!    panic.
//! 2. **Replaces non-finite pixels** (a NaN or ±∞ in any channel; one such pixel would otherwise
//!    spread over the network's receptive field, or break the HDR auto-exposure, which averages
//!    the whole image) by the mean of the finite pixels among its 8 neighbours (0 when it has
//!    none) — in the colour and in the guides. [`Denoised::non_finite`] says how many.
//! 3. **Creates the device** ([`DeviceKind`]) and, with guides and
//!    [`Options::prefilter_guides`], **denoises the guides first** (see that field: with the
//!    `oidn` crate 2.5.1 this is an approximation of OIDN's own albedo/normal prefiltering).
//! 4. **Runs OIDN's `RT` filter** on the colour with the guides, and returns the result with the
//!    device's name and the time each step took ([`Denoised`]).
//!
//! Each call creates its own device and filters: simple, and the cost is measured
//! ([`Denoised::device_seconds`] is at most a few milliseconds; the first filter commit, which
//! loads the weights, is part of [`Denoised::seconds`]).
//!
//! ## Example
//!
//! ```
//! use furnace_denoise::{DenoiseError, Guides, Options, denoise};
//! use glam::Vec3;
//!
//! let (width, height) = (64, 48);
//! // A noisy render and its first-hit albedo and normal (here: made up).
//! let color: Vec<Vec3> = (0..width * height)
//!     .map(|i| Vec3::splat(0.5 + 0.4 * ((i * 7919 % 101) as f32 / 50.0 - 1.0)))
//!     .collect();
//! let albedo = vec![Vec3::splat(0.8); color.len()];
//! let normal = vec![Vec3::Z; color.len()];
//! let guides = Guides { albedo: Some(&albedo), normal: Some(&normal) };
//!
//! match denoise(width, height, &color, guides, &Options::default()) {
//!     Ok(out) => {
//!         assert_eq!(out.pixels.len(), color.len());
//!         println!("{} in {:.3} s", out.device, out.seconds);
//!     }
//!     // Built without the `oidn` feature: the message says how to get it.
//!     Err(e @ DenoiseError::NotBuilt) => eprintln!("{e}"),
//!     Err(e) => panic!("{e}"),
//! }
//! ```
//!
//! [oidn]: https://www.openimagedenoise.org

use glam::Vec3;

#[cfg(feature = "oidn")]
mod backend;

/// Which OIDN device runs the filter.
///
/// OIDN loads a device module per kind (`libOpenImageDenoise_device_{cpu,cuda,hip,sycl}.so`);
/// a kind whose module or driver is missing fails fast (well under a millisecond) with OIDN's
/// "unsupported device type" error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum DeviceKind {
    /// A GPU if OIDN can drive one, else the CPU: the first of CUDA, HIP, SYCL, Metal (macOS
    /// only) and CPU that OIDN can create. That is OIDN's own preference (GPUs before the CPU);
    /// it is spelled out here rather than left to `OIDN_DEVICE_TYPE_DEFAULT` so that
    /// [`Denoised::device`] can say which device ran (the safe `oidn` API cannot query it).
    #[default]
    Default,
    /// The CPU (on TBB threads: all cores).
    Cpu,
    /// An NVIDIA GPU through CUDA (needs the NVIDIA driver's `libcuda.so.1`).
    Cuda,
    /// An AMD GPU through HIP (needs ROCm's `libamdhip64`).
    Hip,
    /// An Intel GPU through SYCL (needs the Level Zero loader).
    Sycl,
    /// An Apple GPU through Metal (macOS).
    Metal,
}

impl DeviceKind {
    /// The name used in [`Denoised::device`] and in errors: `CPU`, `CUDA`, `HIP`, `SYCL`,
    /// `Metal`, or `default`.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Default => "default",
            DeviceKind::Cpu => "CPU",
            DeviceKind::Cuda => "CUDA",
            DeviceKind::Hip => "HIP",
            DeviceKind::Sycl => "SYCL",
            DeviceKind::Metal => "Metal",
        }
    }
}

/// OIDN's filter quality (its `quality` parameter): a speed/quality trade-off of the network.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Quality {
    /// OIDN's default, which is `High`.
    #[default]
    Default,
    /// Lowest quality, fastest: for interactive previews.
    Fast,
    /// Lower precision where the device supports it (GPUs): for interactive use. On the CPU
    /// it may be the same as `High`.
    Balanced,
    /// Highest quality: for final frames.
    High,
}

/// How to denoise. `Options::default()`: [`DeviceKind::Default`], [`Quality::Default`],
/// guides prefiltered, HDR colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Options {
    /// Which device runs the filters.
    pub device: DeviceKind,
    /// The filters' quality.
    pub quality: Quality,
    /// With guides: denoise the albedo and normal images first, each with a filter of its own,
    /// and then the colour with the denoised guides — OIDN's recommendation for guides that are
    /// themselves noisy (depth of field, motion blur, glossy or transmissive first hits, few
    /// samples). Without guides it does nothing.
    ///
    /// **With the `oidn` crate 2.5.1 this is an approximation** of OIDN's own prefiltering: the
    /// crate's safe API has no way to run OIDN's albedo-only and normal-only filters (it always
    /// binds a colour image), and its `clean_aux` setter sets a parameter OIDN does not know
    /// (`clean_aux`, not `cleanAux`; OIDN ignores it, with a warning at `OIDN_VERBOSE=2`). So
    /// the guides are denoised as LDR colour images (the normal mapped from [-1, 1] to [0, 1]
    /// and back, so components beyond ±1 are clamped) with OIDN's LDR colour weights, and the
    /// main filter then runs with OIDN's weights for noisy guides. The tests measure that this still helps when the guides are
    /// noisy and does no harm when they are clean; the cost is two more filter runs.
    pub prefilter_guides: bool,
    /// The colour is HDR (linear radiance, any non-negative value): OIDN scales it by an
    /// automatic exposure before the network. `false`: linear LDR colour in [0, 1] (OIDN
    /// clamps it to that range).
    pub hdr: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { device: DeviceKind::Default, quality: Quality::Default, prefilter_guides: true, hdr: true }
    }
}

/// Optional guide images (OIDN's auxiliary features), each `width × height` pixels like the
/// colour. They help most at edges and fine texture, which they keep sharp.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Guides<'a> {
    /// The albedo (reflectance) at the first hit, in [0, 1], averaged over the pixel's samples
    /// like the colour. For a perfect mirror or glass, the albedo of what it shows (or 1).
    pub albedo: Option<&'a [Vec3]>,
    /// The shading normal at the first hit, world or camera space, components in [-1, 1] (any
    /// length), averaged over the pixel's samples. Only together with [`Guides::albedo`].
    pub normal: Option<&'a [Vec3]>,
}

impl Guides<'_> {
    /// No guides: colour only.
    pub const NONE: Guides<'static> = Guides { albedo: None, normal: None };
}

/// The result of [`denoise`].
#[derive(Debug, Clone, PartialEq)]
pub struct Denoised {
    /// The denoised colour: `width × height` pixels, row-major, top row first, linear like the
    /// input, finite.
    pub pixels: Vec<Vec3>,
    /// The device that ran the filters, e.g. `OIDN CPU` or `OIDN CUDA`.
    pub device: String,
    /// Seconds to create and commit the OIDN device (loading its module).
    pub device_seconds: f64,
    /// Seconds of the guide prefilters (0 without them); part of [`Denoised::seconds`].
    pub prefilter_seconds: f64,
    /// Seconds of filtering: creating and committing the filters (which loads their weights),
    /// copying the images in and out, and executing them — everything after the device exists.
    pub seconds: f64,
    /// How many non-finite pixels were replaced before denoising (see the crate docs).
    pub non_finite: NonFinite,
}

/// Counts of non-finite pixels (a NaN or ±∞ in any channel) replaced before denoising.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct NonFinite {
    /// In the colour.
    pub color: usize,
    /// In the albedo guide.
    pub albedo: usize,
    /// In the normal guide.
    pub normal: usize,
}

impl NonFinite {
    /// All of them.
    pub fn total(&self) -> usize {
        self.color + self.albedo + self.normal
    }
}

/// Why [`denoise`] failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DenoiseError {
    /// This build has no OIDN (the crate's `oidn` feature, the CLI's `denoise` feature, is off).
    #[error("{NOT_BUILT}")]
    NotBuilt,
    /// `width` or `height` is 0.
    #[error("cannot denoise an empty image ({width}×{height})")]
    EmptyImage {
        /// The width given.
        width: u32,
        /// The height given.
        height: u32,
    },
    /// A buffer does not hold `width × height` pixels.
    #[error("the {buffer} image has {len} pixels, but a {width}×{height} image has {expected}")]
    LengthMismatch {
        /// `color`, `albedo` or `normal`.
        buffer: &'static str,
        /// Its length.
        len: usize,
        /// `width × height`.
        expected: u64,
        /// The width given.
        width: u32,
        /// The height given.
        height: u32,
    },
    /// A normal guide without an albedo guide.
    #[error("a normal guide needs an albedo guide too (OIDN uses normals only together with albedo)")]
    NormalWithoutAlbedo,
    /// OIDN failed: creating the device (e.g. `unsupported device type: CUDA` when there is no
    /// such GPU or driver), allocating or running a filter. Context, then OIDN's own message.
    #[error("Open Image Denoise: {0}")]
    Oidn(String),
}

/// The message of [`DenoiseError::NotBuilt`]: one line, what to do.
const NOT_BUILT: &str = "this furnace was built without denoising: install OIDN 2.5.1 \
    (`bash denoise/install-oidn.sh` prints its directory) and rebuild with \
    `OIDN_DIR=<that directory> cargo build --release -p furnace-cli --features denoise`";

/// Whether this build can denoise: `true` with the `oidn` feature. (A binary built with it that
/// cannot find the OIDN libraries does not start at all, so there is no run-time "maybe".)
pub fn available() -> bool {
    cfg!(feature = "oidn")
}

/// Denoises `color` (`width × height` linear RGB pixels, row-major, top row first), optionally
/// guided by albedo and normal images; see the crate docs for the steps and
/// [`Options`] for the choices.
///
/// # Errors
/// [`DenoiseError::EmptyImage`], [`DenoiseError::LengthMismatch`] and
/// [`DenoiseError::NormalWithoutAlbedo`] for bad arguments (checked in every build),
/// [`DenoiseError::NotBuilt`] without the `oidn` feature, [`DenoiseError::Oidn`] when OIDN
/// fails.
pub fn denoise(
    width: u32,
    height: u32,
    color: &[Vec3],
    guides: Guides<'_>,
    options: &Options,
) -> Result<Denoised, DenoiseError> {
    check(width, height, color, guides)?;
    run(width, height, color, guides, options)
}

#[cfg(feature = "oidn")]
fn run(
    width: u32,
    height: u32,
    color: &[Vec3],
    guides: Guides<'_>,
    options: &Options,
) -> Result<Denoised, DenoiseError> {
    let (w, h) = (width as usize, height as usize);
    let mut non_finite = NonFinite::default();
    let (color, n) = sanitized(w, h, color);
    non_finite.color = n;
    let albedo = guides.albedo.map(|a| {
        let (a, n) = sanitized(w, h, a);
        non_finite.albedo = n;
        a
    });
    let normal = guides.normal.map(|a| {
        let (a, n) = sanitized(w, h, a);
        non_finite.normal = n;
        a
    });
    let out = backend::run(w, h, &color, albedo.as_deref(), normal.as_deref(), options)?;
    Ok(Denoised {
        pixels: out.pixels.chunks_exact(3).map(Vec3::from_slice).collect(),
        device: out.device,
        device_seconds: out.device_seconds,
        prefilter_seconds: out.prefilter_seconds,
        seconds: out.seconds,
        non_finite,
    })
}

#[cfg(not(feature = "oidn"))]
fn run(_: u32, _: u32, _: &[Vec3], _: Guides<'_>, _: &Options) -> Result<Denoised, DenoiseError> {
    Err(DenoiseError::NotBuilt)
}

/// The argument checks of [`denoise`].
fn check(width: u32, height: u32, color: &[Vec3], guides: Guides<'_>) -> Result<(), DenoiseError> {
    if width == 0 || height == 0 {
        return Err(DenoiseError::EmptyImage { width, height });
    }
    // In u64: u32 × u32 cannot overflow it. A buffer of exactly this length exists in memory,
    // so after this check `3 × len` floats cannot overflow usize either.
    let expected = u64::from(width) * u64::from(height);
    for (buffer, image) in [("color", Some(color)), ("albedo", guides.albedo), ("normal", guides.normal)] {
        if let Some(image) = image
            && image.len() as u64 != expected
        {
            return Err(DenoiseError::LengthMismatch { buffer, len: image.len(), expected, width, height });
        }
    }
    if guides.normal.is_some() && guides.albedo.is_none() {
        return Err(DenoiseError::NormalWithoutAlbedo);
    }
    Ok(())
}

/// `image` as OIDN's packed `float3` (`w × h × 3` floats), each non-finite pixel replaced by the
/// mean of its finite 8-neighbours (0 if none is), and how many were replaced.
#[cfg_attr(not(feature = "oidn"), allow(dead_code))]
fn sanitized(w: usize, h: usize, image: &[Vec3]) -> (Vec<f32>, usize) {
    let finite = |p: &Vec3| p.is_finite();
    let mut out = Vec::with_capacity(3 * image.len());
    let mut replaced = 0;
    for (i, p) in image.iter().enumerate() {
        let p = if finite(p) {
            *p
        } else {
            replaced += 1;
            let (x, y) = (i % w, i / w);
            let (mut sum, mut n) = (Vec3::ZERO, 0u32);
            for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    let q = image[ny * w + nx];
                    if finite(&q) {
                        sum += q;
                        n += 1;
                    }
                }
            }
            if n == 0 { Vec3::ZERO } else { sum / n as f32 }
        };
        out.extend_from_slice(&p.to_array());
    }
    (out, replaced)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_arguments_in_every_build() {
        let px = vec![Vec3::ONE; 6];
        let opts = Options::default();
        assert_eq!(
            denoise(0, 5, &[], Guides::NONE, &opts),
            Err(DenoiseError::EmptyImage { width: 0, height: 5 })
        );
        assert_eq!(
            denoise(2, 2, &px, Guides::NONE, &opts),
            Err(DenoiseError::LengthMismatch { buffer: "color", len: 6, expected: 4, width: 2, height: 2 })
        );
        let short = vec![Vec3::ONE; 5];
        assert_eq!(
            denoise(3, 2, &px, Guides { albedo: Some(&px), normal: Some(&short) }, &opts),
            Err(DenoiseError::LengthMismatch { buffer: "normal", len: 5, expected: 6, width: 3, height: 2 })
        );
        assert_eq!(
            denoise(3, 2, &px, Guides { albedo: None, normal: Some(&px) }, &opts),
            Err(DenoiseError::NormalWithoutAlbedo)
        );
        // u32::MAX² does not fit in u32 but does in u64: a mismatch, not an overflow.
        assert!(matches!(
            denoise(u32::MAX, u32::MAX, &px, Guides::NONE, &opts),
            Err(DenoiseError::LengthMismatch { expected: 18446744065119617025, .. })
        ));
    }

    #[test]
    fn non_finite_pixels_become_their_finite_neighbours_mean() {
        let (w, h) = (3, 2);
        let nan = Vec3::new(f32::NAN, 0.0, 0.0);
        let inf = Vec3::new(0.0, f32::INFINITY, 0.0);
        #[rustfmt::skip]
        let image = [
            Vec3::splat(1.0), nan,              Vec3::splat(3.0),
            Vec3::splat(4.0), Vec3::splat(5.0), inf,
        ];
        let (out, replaced) = sanitized(w, h, &image);
        assert_eq!(replaced, 2);
        // (1,0): neighbours 1, 3, 4, 5 (the ∞ pixel is not finite) → 13/4.
        assert_eq!(&out[3..6], &[3.25; 3]);
        // (2,1): neighbours 3, 5 (the NaN pixel is not finite) → 4.
        assert_eq!(&out[15..18], &[4.0; 3]);
        assert_eq!(&out[..3], &[1.0; 3]);
        // No finite neighbour at all: 0.
        let (out, replaced) = sanitized(1, 1, &[nan]);
        assert_eq!((out, replaced), (vec![0.0; 3], 1));
    }

    #[cfg(not(feature = "oidn"))]
    #[test]
    fn without_the_feature_denoise_is_not_built_and_says_how_to_get_it() {
        assert!(!available());
        let px = vec![Vec3::ONE; 4];
        let err = denoise(2, 2, &px, Guides::NONE, &Options::default()).unwrap_err();
        assert_eq!(err, DenoiseError::NotBuilt);
        let msg = err.to_string();
        assert!(!msg.contains('\n'), "one line: {msg}");
        for needle in ["install-oidn.sh", "OIDN_DIR=", "--features denoise", "furnace-cli", "2.5.1"] {
            assert!(msg.contains(needle), "{needle:?} missing from: {msg}");
        }
    }

    #[cfg(feature = "oidn")]
    #[test]
    fn with_the_feature_it_is_available() {
        assert!(available());
    }
}
