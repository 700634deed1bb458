//! Correlated multi-jittered sampling (Kensler 2013).

use crate::SamplerError;
use crate::fixed::{div_frac, isqrt};
use crate::hash::{hash3, kensler_hash, kensler_permute};
use crate::pairs::{check_index, impl_sampler_by_pairs, validate_count};

/// Sample `s` of Kensler's N-point correlated multi-jittered pattern `p`, in 0.32 fixed point
/// (Kensler 2013, final listing, aspect ratio 1):
///
/// ```text
/// m = floor(sqrt(N)), n = ceil(N / m)
/// s  = permute(s, N, p·0x51633e2d)          // shuffle the order: any prefix is a random subset
/// sx = permute(s mod m, m, p·0x68bc21eb)    // correlated shuffles of columns ...
/// sy = permute(s div m, n, p·0x02e5be93)    // ... and rows
/// x  = (sx + (sy + jx) / n) / m             // = (sx·n + sy + jx) / (m·n)
/// y  = (s + jy) / N
/// ```
///
/// with `jx = hash(s, p·0x967a889b)`, `jy = hash(s, p·0x368cc8b7)` ([`kensler_hash`]).
/// Non-square N is handled as the paper does: an m × n grid with m·n ≥ N cells, of which N are
/// used; x is N-rook stratified on the m·n fine columns, y on N fine rows.
///
/// *Deviations:* `x` and `y` are computed as exact fixed-point quotients ([`div_frac`]) rather
/// than in float, and `m` by an exact integer square root; integer-only (`u32`, wrapping).
///
/// # Panics
/// In debug builds, if `n == 0` or `s >= n`.
#[inline]
pub fn cmj_point(s: u32, n_total: u32, p: u32) -> [u32; 2] {
    let m = isqrt(n_total);
    let n = n_total.div_ceil(m);
    let s = kensler_permute(s, n_total, p.wrapping_mul(0x5163_3e2d));
    let sx = kensler_permute(s % m, m, p.wrapping_mul(0x68bc_21eb));
    let sy = kensler_permute(s / m, n, p.wrapping_mul(0x02e5_be93));
    let jx = kensler_hash(s, p.wrapping_mul(0x967a_889b));
    let jy = kensler_hash(s, p.wrapping_mul(0x368c_c8b7));
    [div_frac(sx * n + sy, jx, m * n), div_frac(s, jy, n_total)]
}

/// Correlated multi-jittered sampler for a fixed total of `N` samples per pixel: one
/// Kensler pattern per pixel and per pair of dimensions `(2k, 2k+1)`, the pattern index `p`
/// hashed from (seed, pair, pixel). Integer-only (`u32`, wrapping).
///
/// **Not progressive**, though less fragile than [`crate::Hammersley`]: the index is shuffled
/// inside the pattern, so a prefix of k < N samples is a random subset of the N strata (about
/// as good as jittered sampling with k strata, measured by the convergence test). An index
/// ≥ N wraps (`index mod N`) and repeats the pattern; [`Cmj::check_index`] reports it as an
/// error for a caller that wants one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cmj {
    n: u32,
    seed: u32,
}

impl Cmj {
    /// A CMJ sampler for `n` samples per pixel.
    ///
    /// # Errors
    /// [`SamplerError::MissingSampleCount`] if `n == 0`, [`SamplerError::SampleCountTooLarge`]
    /// if `n > 2^30` (CMJ's grid of m·n ≥ N cells must fit in a `u32`).
    pub fn new(n: u32, seed: u32) -> Result<Self, SamplerError> {
        Ok(Self { n: validate_count("cmj", n)?, seed })
    }

    /// The pattern size N.
    pub fn sample_count(&self) -> u32 {
        self.n
    }

    /// `Ok` if `index < N`; otherwise [`SamplerError::IndexOutOfRange`].
    pub fn check_index(&self, index: u32) -> Result<(), SamplerError> {
        check_index("cmj", index, self.n)
    }

    #[inline]
    fn pair(&self, pixel: u32, index: u32, pair: u32) -> [u32; 2] {
        cmj_point(index % self.n, self.n, hash3(self.seed, pair, pixel))
    }
}

impl_sampler_by_pairs!(Cmj);
