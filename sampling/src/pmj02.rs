//! Progressive multi-jittered (0,2) sequences, evaluated directly per index.

use crate::hash::{hash2, hash3, owen_shuffle_index, pcg_hash};
use crate::pairs::impl_sampler_by_pairs;

/// For each level `L` (points `2^L … 2^(L+1) − 1`), the XOR that pairs new point `2^L + i`
/// with the old point `i ^ xor` whose stratum it complements, for x (`[0]`) and y (`[1]`).
///
/// Derived from the generator matrices of the Sobol (0,2)-sequence (van der Corput for x, the
/// Pascal matrix P mod 2 for y): point `2^L + i` must share the top `L` bits of its coordinate
/// with point `j < 2^L` and differ in bit `L`. For x that is `j = i` (xor 0); for y,
/// `P_L·j = P_L·i ⊕ p_L`, i.e. `xor = P_L⁻¹·p_L`, with `P_L` the top-left L×L block and
/// `p_L` the top L entries of column L (solved by back-substitution, P being unit upper
/// triangular). Any (0,2) structure works; this one is derived rather than copied.
pub const PMJ02_XORS: [[u32; 32]; 2] = [[0; 32], pascal_pairing_xors()];

const fn pascal_pairing_xors() -> [u32; 32] {
    // Column c of P as bits: row r ↔ bit r (LSB first here), binomial(c, r) mod 2.
    let mut col = [0u32; 32];
    col[0] = 1;
    let mut c = 1;
    while c < 32 {
        col[c] = col[c - 1] ^ (col[c - 1] << 1);
        c += 1;
    }
    let mut xors = [0u32; 32];
    let mut level = 1;
    while level < 32 {
        // Solve P_L · j = p_L over GF(2), rows L−1 down to 0.
        let target = col[level];
        let mut j = 0u32;
        let mut r = level;
        while r > 0 {
            r -= 1;
            let mut bit = (target >> r) & 1;
            let mut c = r + 1;
            while c < level {
                bit ^= ((col[c] >> r) & 1) & ((j >> c) & 1);
                c += 1;
            }
            j |= bit << r;
        }
        xors[level] = j;
        level += 1;
    }
    xors
}

/// One coordinate of point `index` of a stochastic (0,2)-sequence, as a 0.32 fraction.
///
/// Helmer, Christensen & Kensler ("Stochastic Generation of (t, s) Sample Sequences", EGSR
/// 2021) build PMJ02 sequentially: point `2^L + i` takes the stratum (at resolution `2^(L+1)`)
/// complementary to that of point `(i ^ xor[L])`, and random bits below it. Unrolled, the
/// top bits of point `k` are those of the chain `k → (k − 2^L) ^ xor[L] → … → 0`, each link
/// flipping bit `L` and supplying fresh random bits below bit `L`. This walks that chain
/// directly, so any point costs O(log index) hashes and no table: **addressable**.
/// Integer-only (`u32`, wrapping).
#[inline]
pub fn pmj02_coordinate(index: u32, xors: &[u32; 32], seed: u32) -> u32 {
    let mut undetermined = u32::MAX; // bits of the result not yet fixed by a deeper link
    let mut acc = 0u32; // the random bits, placed
    let mut flips = 0u32; // the stratum flips along the chain
    let mut k = index;
    // hash2(k, seed) = pcg_hash(k ^ pcg_hash(seed)): hoist the seed's half out of the loop.
    let seed = pcg_hash(seed);
    while k != 0 {
        let level = 31 - k.leading_zeros(); // k ∈ [2^L, 2^(L+1))
        // Bits below the (L+1)-bit stratum (none at L = 31: a shift by 32 is not defined).
        let below = u32::MAX.checked_shr(level + 1).unwrap_or(0);
        acc |= pcg_hash(k ^ seed) & undetermined & below;
        undetermined &= !below;
        flips ^= 0x8000_0000 >> level;
        k = (k ^ (1 << level)) ^ xors[level as usize];
    }
    acc |= pcg_hash(seed) & undetermined;
    acc ^ flips
}

/// PMJ02 sampler: progressive multi-jittered (0,2) sequences (Christensen, Kensler &
/// Kilpatrick, "Progressive Multi-Jittered Sample Sequences", EGSR 2018), one independent
/// sequence per pixel and per pair of dimensions `(2k, 2k+1)`.
///
/// Every power-of-two prefix has exactly one point in every elementary interval
/// `2^a × 2^b` (a + b = log2 of the prefix length), so a render may stop at any sample count.
/// Points come from [`pmj02_coordinate`], evaluated directly per index (no tables, unlimited
/// length, any index `< 2^32`). Pairs after the first shuffle the index with their own seed
/// ([`owen_shuffle_index`], Burley 2020's shuffling restricted to map every power-of-two prefix
/// onto itself), which decorrelates the pairs and keeps each prefix a (0,2) net. Needs no N.
/// Integer-only (`u32`, wrapping).
///
/// Its dimension pairs have the same (0,2) stratification as the first two dimensions of
/// [`crate::OwenSobol`] (Helmer et al. 2021 relate the two constructions), and the convergence
/// test measures the same rates for both; the samplers differ in how they pad higher dimensions
/// (independent pairs here, 4-D Sobol groups there, which also stratify dimensions 4k…4k+3
/// jointly) and in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pmj02 {
    seed: u32,
}

impl Pmj02 {
    /// A PMJ02 sampler; different seeds give independent sequences.
    pub fn new(seed: u32) -> Self {
        Self { seed }
    }

    #[inline]
    fn pair(&self, pixel: u32, index: u32, pair: u32) -> [u32; 2] {
        let key = hash3(self.seed, pair, pixel);
        let i = if pair == 0 { index } else { owen_shuffle_index(index, key) };
        [
            pmj02_coordinate(i, &PMJ02_XORS[0], hash2(key, 0x2f6b_1d3b)),
            pmj02_coordinate(i, &PMJ02_XORS[1], hash2(key, 0x7c15_95d9)),
        ]
    }
}

impl_sampler_by_pairs!(Pmj02);
