//! Owen-scrambled Sobol (Burley 2020).

use crate::Sampler;
use crate::hash::{hash2, hash3, owen_scramble, owen_shuffle_index};

/// Sobol direction numbers for the first four dimensions, as 0.32 fractions (`V[d][k]` is the
/// column for index bit `k`).
///
/// * dimension 0: van der Corput, `V[k] = 2^(31−k)`;
/// * dimension 1: the Pascal matrix mod 2, `V[k] = V[k−1] ^ (V[k−1] >> 1)`;
/// * dimensions 2 and 3: Joe & Kuo's `new-joe-kuo-6.21201` parameters
///   (s = 2, a = 1, m = 1 3) and (s = 3, a = 1, m = 1 3 1), by the standard recurrence
///   `V[k] = V[k−s] ^ (V[k−s] >> s) ^ ⊕_{j=1}^{s−1} a_j·V[k−j]`.
pub const SOBOL_DIRECTIONS: [[u32; 32]; 4] = [
    van_der_corput_directions(),
    pascal_directions(),
    joe_kuo_directions(2, 1, &[1, 3]),
    joe_kuo_directions(3, 1, &[1, 3, 1]),
];

const fn van_der_corput_directions() -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        v[k] = 1 << (31 - k);
        k += 1;
    }
    v
}

const fn pascal_directions() -> [u32; 32] {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
}

/// Direction numbers from a primitive polynomial of degree `s` with coefficient bits `a`
/// (Joe & Kuo's convention) and initial odd integers `m_1 … m_s`.
const fn joe_kuo_directions(s: usize, a: u32, m: &[u32]) -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < s {
        v[k] = m[k] << (31 - k);
        k += 1;
    }
    while k < 32 {
        let mut x = v[k - s] ^ (v[k - s] >> s);
        let mut j = 1;
        while j < s {
            if (a >> (s - 1 - j)) & 1 == 1 {
                x ^= v[k - j];
            }
            j += 1;
        }
        v[k] = x;
        k += 1;
    }
    v
}

/// Unscrambled Sobol point `index`, dimension `dim < 4`, as a 0.32 fraction: the XOR of the
/// direction numbers of the set bits of `index` (natural order, not Gray code).
/// Integer-only (`u32`).
///
/// Dimensions 0 and 1 use closed forms (equal to the matrix product, tested): van der Corput is
/// `reverse_bits(index)`; for the Pascal matrix, binomial(c, r) is odd iff `r ⊆ c` (Lucas), so
/// row r is the XOR of the index bits at supersets of r — a 5-step superset-XOR transform —
/// then bit-reversed. Dimensions 2 and 3 loop over the set bits of `index`.
///
/// # Panics
/// If `dim >= 4`.
#[inline]
pub fn sobol_bits(index: u32, dim: usize) -> u32 {
    match dim {
        0 => index.reverse_bits(),
        1 => {
            let mut x = index;
            x ^= (x >> 1) & 0x5555_5555;
            x ^= (x >> 2) & 0x3333_3333;
            x ^= (x >> 4) & 0x0F0F_0F0F;
            x ^= (x >> 8) & 0x00FF_00FF;
            x ^= (x >> 16) & 0x0000_FFFF;
            x.reverse_bits()
        }
        _ => sobol_bits_by_matrix(index, dim),
    }
}

/// [`sobol_bits`] by the generic matrix product (any `dim < 4`): the reference for the closed
/// forms.
///
/// # Panics
/// If `dim >= 4`.
#[inline]
pub fn sobol_bits_by_matrix(mut index: u32, dim: usize) -> u32 {
    let v = &SOBOL_DIRECTIONS[dim];
    let mut x = 0;
    while index != 0 {
        x ^= v[index.trailing_zeros() as usize];
        index &= index - 1;
    }
    x
}

/// Owen-scrambled Sobol sampler (Burley, "Practical Hash-based Owen Scrambling", 2020).
///
/// Dimensions are grouped by four, `(4k … 4k+3)`. For group `k` of a pixel, with
/// `seed_k = hash(seed, k, pixel)`:
///
/// ```text
/// i' = owen_shuffle_index(index, seed_k)                      // shuffle (Burley §4, "padding")
/// x_d = owen_scramble(sobol(i', d), hash(seed_k, d)),  d = 0..3   // nested uniform scramble
/// ```
///
/// The index shuffle ([`owen_shuffle_index`], a prefix-preserving variant of Burley's) permutes
/// every power-of-two prefix onto itself, so each prefix is still a prefix of Sobol: dimensions
/// `(4k, 4k+1)` are a (0, 2)-sequence in base 2 (one point in every elementary interval of
/// every power-of-two prefix), and the groups are statistically independent of each other.
/// Progressive, any index `< 2^32`, needs no N. Integer-only (`u32`, wrapping).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwenSobol {
    seed: u32,
}

impl OwenSobol {
    /// An Owen-scrambled Sobol sampler; different seeds give independent scrambles.
    pub fn new(seed: u32) -> Self {
        Self { seed }
    }

    #[inline]
    fn group_seed(&self, pixel: u32, dimension: u32) -> u32 {
        hash3(self.seed, dimension / 4, pixel)
    }
}

impl Sampler for OwenSobol {
    #[inline]
    fn bits(&self, pixel: u32, index: u32, dimension: u32) -> u32 {
        let seed = self.group_seed(pixel, dimension);
        let d = dimension % 4;
        let i = owen_shuffle_index(index, seed);
        owen_scramble(sobol_bits(i, d as usize), hash2(seed, d))
    }

    #[inline]
    fn bits_2d(&self, pixel: u32, index: u32, dimension: u32) -> [u32; 2] {
        if dimension % 4 == 3 {
            // The pair straddles two groups.
            return [self.bits(pixel, index, dimension), self.bits(pixel, index, dimension.wrapping_add(1))];
        }
        let seed = self.group_seed(pixel, dimension);
        let d = dimension % 4;
        let i = owen_shuffle_index(index, seed);
        [
            owen_scramble(sobol_bits(i, d as usize), hash2(seed, d)),
            owen_scramble(sobol_bits(i, d as usize + 1), hash2(seed, d + 1)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_equal_the_matrix_product() {
        let mut x = 0x2545_f491u32;
        for i in (0..70_000u32).chain([u32::MAX, 1 << 31, 0xAAAA_AAAA]) {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            for idx in [i, x] {
                for dim in 0..4 {
                    assert_eq!(sobol_bits(idx, dim), sobol_bits_by_matrix(idx, dim), "{idx} {dim}");
                }
            }
        }
    }
}
