//! Hammersley points with a per-pixel Cranley–Patterson rotation (the thesis, listing 6.2).

use crate::SamplerError;
use crate::fixed::div_frac;
use crate::hash::{hash3, kensler_permute};
use crate::pairs::{check_index, impl_sampler_by_pairs, validate_count};

/// The `i`-th of `n` Hammersley points, rotated: the thesis's listing 6.2,
/// `frac((i/N, reversebits(i)/2^32) + (random & 0xffff)/2^16)`, in 0.32 fixed point.
///
/// `rotation` holds the two per-pixel random words; only their low 16 bits are used, shifted to
/// the top (exactly the thesis's `(random & 0xffff) / 2^16`). Fixed-point addition wraps, which
/// is `frac` exactly. Integer-only (`u32`, wrapping): `i/N` is an exact long division
/// ([`div_frac`]) instead of a float division, so the WGSL twin is bit-identical.
///
/// # Panics
/// In debug builds, if `n == 0` or `i >= n`.
#[inline]
pub fn hammersley_point(i: u32, n: u32, rotation: [u32; 2]) -> [u32; 2] {
    let x = div_frac(i, 0, n);
    let y = i.reverse_bits();
    [x.wrapping_add(rotation[0] << 16), y.wrapping_add(rotation[1] << 16)]
}

/// Hammersley sampler for a fixed total of `N` samples per pixel.
///
/// Dimensions come in pairs `(2k, 2k+1)`. Pair 0 is the thesis's sampler exactly: point `index`
/// of the N-point Hammersley set, Cranley–Patterson rotated per pixel. Each further pair uses
/// its own rotation and a Kensler permutation of the index (so the pairs are decorrelated; the
/// thesis re-seeds per bounce for the same reason). Integer-only (`u32`, wrapping).
///
/// **Not progressive.** The set is only uniform once all N points are taken:
/// * a *prefix* of k < N samples covers only `x ∈ [r, r + k/N)` (mod 1) in pair 0 — unbiased
///   over the random per-pixel rotation, but each pixel's estimate is poor (the convergence
///   test measures it);
/// * an *index ≥ N* wraps (`index mod N`): the pattern repeats, the estimate of every pixel
///   stops changing at N samples. [`Hammersley::check_index`] turns that into an error for a
///   caller that wants one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hammersley {
    n: u32,
    seed: u32,
}

impl Hammersley {
    /// A Hammersley sampler for `n` samples per pixel.
    ///
    /// # Errors
    /// [`SamplerError::MissingSampleCount`] if `n == 0`, [`SamplerError::SampleCountTooLarge`]
    /// if `n > 2^30` (CMJ's grid of m·n ≥ N cells must fit in a `u32`).
    pub fn new(n: u32, seed: u32) -> Result<Self, SamplerError> {
        Ok(Self { n: validate_count("hammersley", n)?, seed })
    }

    /// The pattern size N.
    pub fn sample_count(&self) -> u32 {
        self.n
    }

    /// `Ok` if `index < N`; otherwise [`SamplerError::IndexOutOfRange`], which says what the
    /// sampler does there (repeats the pattern).
    pub fn check_index(&self, index: u32) -> Result<(), SamplerError> {
        check_index("hammersley", index, self.n)
    }

    #[inline]
    fn pair(&self, pixel: u32, index: u32, pair: u32) -> [u32; 2] {
        let key = hash3(self.seed, pair, pixel);
        let mut i = index % self.n;
        if pair > 0 {
            i = kensler_permute(i, self.n, key);
        }
        hammersley_point(i, self.n, [key, hash3(key, 0x68e3_1da4, pixel)])
    }
}

impl_sampler_by_pairs!(Hammersley);
