//! # furnace-sampling
//!
//! Addressable sample generators for Monte Carlo rendering, the warps that turn their points
//! into directions, and the chi-square harness that checks any sampling routine against its pdf.
//!
//! ## Samplers
//!
//! Every sampler answers [`Sampler::value`]`(pixel, index, dimension) -> f32 in [0, 1)`, and
//! [`Sampler::value_2d`] for a pair of dimensions. Samplers are **addressable**: any sample is
//! computed directly from its coordinates, never from a previous one, so the order of
//! evaluation, the thread count, CPU versus GPU, or splitting a render across machines cannot
//! change an image. All of them use only `u32` integer arithmetic (wrapping) and produce a
//! 0.32 fixed-point fraction ([`Sampler::bits`]); the one conversion to `f32` is exact
//! ([`to_unit_f32`]), so a WGSL twin can be bit-identical.
//!
//! | kind | algorithm | progressive | needs N |
//! |---|---|---|---|
//! | `random` | PCG hash of (pixel, index, dimension, seed) — Jarzynski & Olano 2020 | yes | no |
//! | `hammersley` | Hammersley with per-pixel Cranley-Patterson rotation (the thesis, listing 6.2) | no | yes |
//! | `cmj` | correlated multi-jittered, Kensler 2013 (Pixar TM 13-01) | no | yes |
//! | `pmj02` | progressive multi-jittered (0,2), Christensen, Kensler & Kilpatrick 2018, by the stochastic construction of Helmer, Christensen & Kensler 2021 | yes | no |
//! | `sobol` | Owen-scrambled Sobol, Burley 2020 (hash-based nested uniform scrambling, shuffled 4-D padding) | yes | no |
//!
//! *Progressive* means every prefix of the sample sequence is well distributed, so a render may
//! stop at any sample count. The two samplers that need N build one N-point pattern per pixel;
//! see [`Hammersley`] and [`Cmj`] for what happens when they are stopped early or asked for an
//! index ≥ N.
//!
//! ## Warps
//!
//! [`warp`] maps the unit square to the disk, the hemisphere, a cone and a triangle; each warp
//! comes with its pdf. [`AliasTable`] samples one of many items (lights) by weight in constant
//! time; [`Distribution2D`] samples a piecewise-constant density on the square (environment maps).
//!
//! Each warp and sampler is checked by a chi-square test against its pdf (the workspace's
//! `furnace-tests` crate holds the harness).
//!
//! ## Example
//!
//! ```
//! use furnace_sampling::{Sampler, SamplerKind, AnySampler};
//!
//! // An Owen-scrambled Sobol sampler with seed 7; it needs no sample count.
//! let sampler = AnySampler::new(SamplerKind::Sobol, 7, None).unwrap();
//! let pixel = 42; // any u32 that identifies the pixel, e.g. y * width + x
//! let [u, v] = sampler.value_2d(pixel, 0, 0);
//! assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
//! // Addressable: asking again, in any order, gives the same bits.
//! assert_eq!(sampler.value_2d(pixel, 0, 0), [u, v]);
//! ```

mod alias;
mod cmj;
mod distribution;
mod error;
pub mod fixed;
mod hammersley;
pub mod hash;
mod kind;
mod pairs;
mod pmj02;
mod random;
mod sobol;
pub mod warp;

pub use alias::{AliasBin, AliasTable};
pub use cmj::{Cmj, cmj_point};
pub use distribution::Distribution2D;
pub use error::SamplerError;
pub use fixed::to_unit_f32;
pub use hammersley::{Hammersley, hammersley_point};
pub use kind::{AnySampler, SamplerKind};
pub use pairs::MAX_SAMPLE_COUNT;
pub use pmj02::{PMJ02_XORS, Pmj02, pmj02_coordinate};
pub use random::{RandomSampler, RandomStream};
pub use sobol::{OwenSobol, SOBOL_DIRECTIONS, sobol_bits, sobol_bits_by_matrix};

/// The Rec. 709 luminance weights of linear RGB: `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
///
/// Every sampling decision that weighs colours by one number uses them (the BSDF's lobe choice,
/// the light selection by power, the adaptive sampler's noise estimate), on the CPU and, as a
/// generated WGSL `const`, on the GPU. Defined here, the lowest crate those share.
pub const LUMINANCE: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// An addressable sampler: a sample is a pure function of `(pixel, index, dimension)`.
///
/// * `pixel` — any `u32` naming the pixel (e.g. `y * width + x`); different pixels get
///   decorrelated patterns.
/// * `index` — the sample number within the pixel, `0, 1, 2, …`.
/// * `dimension` — which coordinate of the sample vector (camera jitter, then two or three per
///   bounce, …). Samplers built from 2-D patterns (Hammersley, CMJ, PMJ02) pair dimensions
///   `(2k, 2k+1)`: call [`Sampler::value_2d`] with an even `dimension` to get a stratified 2-D
///   point. Owen-Sobol groups dimensions by four, `(4k … 4k+3)`.
///
/// Implementations use only wrapping `u32` arithmetic and return 0.32 fixed point from
/// [`Sampler::bits`]; [`Sampler::value`] converts exactly with [`to_unit_f32`].
pub trait Sampler: Send + Sync {
    /// The sample as a 0.32 fixed-point fraction `bits / 2^32`.
    ///
    /// Integer-only (`u32`, wrapping), so that the WGSL twin is bit-identical.
    fn bits(&self, pixel: u32, index: u32, dimension: u32) -> u32;

    /// Dimensions `dimension` and `dimension + 1` as 0.32 fixed point.
    ///
    /// Integer-only (`u32`, wrapping). Samplers built from 2-D patterns override this to compute
    /// the pair at once; the result always equals two calls to [`Sampler::bits`].
    fn bits_2d(&self, pixel: u32, index: u32, dimension: u32) -> [u32; 2] {
        [self.bits(pixel, index, dimension), self.bits(pixel, index, dimension.wrapping_add(1))]
    }

    /// The sample in `[0, 1)`: [`to_unit_f32`] of [`Sampler::bits`] (integer arithmetic, then
    /// one exact conversion to `f32`).
    fn value(&self, pixel: u32, index: u32, dimension: u32) -> f32 {
        to_unit_f32(self.bits(pixel, index, dimension))
    }

    /// Dimensions `dimension` and `dimension + 1` in `[0, 1)²` (integer arithmetic, then one
    /// exact conversion to `f32` per coordinate).
    fn value_2d(&self, pixel: u32, index: u32, dimension: u32) -> [f32; 2] {
        let [a, b] = self.bits_2d(pixel, index, dimension);
        [to_unit_f32(a), to_unit_f32(b)]
    }
}
