//! Integer hashes and permutations shared by the samplers (all `u32`, wrapping).
//!
//! * [`pcg_hash`] — the one-round PCG hash recommended by Jarzynski & Olano, "Hash Functions
//!   for GPU Rendering", JCGT 9(3), 2020.
//! * [`kensler_permute`], [`kensler_hash`] — the hashed permutation and the jitter hash of
//!   Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01, 2013.
//! * [`owen_scramble`] — nested uniform (Owen) scrambling by a Laine–Karras-style hash on
//!   reversed bits, Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020, with the
//!   improved constants published by N. Vegdahl (2021).

/// One round of the PCG hash (Jarzynski & Olano 2020): a bijection on `u32`.
///
/// `state = v·747796405 + 2891336453; word = ((state >> ((state >> 28) + 4)) ^ state)·277803737;
/// return (word >> 22) ^ word`.
#[inline]
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// Hash of two words: `pcg_hash(a ^ pcg_hash(b))`.
///
/// For a fixed `b` it is a bijection in `a` (and vice versa), so distinct keys never collide
/// along one coordinate.
#[inline]
pub fn hash2(a: u32, b: u32) -> u32 {
    pcg_hash(a ^ pcg_hash(b))
}

/// Hash of three words, nested like [`hash2`]: a bijection in each word for the others fixed.
#[inline]
pub fn hash3(a: u32, b: u32, c: u32) -> u32 {
    pcg_hash(a ^ pcg_hash(b ^ pcg_hash(c)))
}

/// Hash of four words, nested like [`hash2`]: a bijection in each word for the others fixed.
#[inline]
pub fn hash4(a: u32, b: u32, c: u32, d: u32) -> u32 {
    pcg_hash(a ^ pcg_hash(b ^ pcg_hash(c ^ pcg_hash(d))))
}

/// Kensler's hashed permutation: element `i` of a pseudo-random permutation of `[0, l)` chosen
/// by the pattern `p` (Kensler 2013, listing "permute", final version with cycle-walking).
///
/// `i` must be `< l` and `l ≥ 1`; the result is `< l`, and `i ↦ result` is a bijection of
/// `[0, l)` for every `p`. The loop runs ~`(next power of two ≥ l) / l` < 2 times on average.
#[inline]
pub fn kensler_permute(mut i: u32, l: u32, p: u32) -> u32 {
    debug_assert!(l >= 1 && i < l, "kensler_permute needs i < l (i = {i}, l = {l})");
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    // (i + p) % l. *Deviation:* Kensler's C wraps `i + p` modulo 2^32 first; this is the exact
    // rotation by p mod l (equally a bijection), computed without overflow.
    let q = p % l;
    if i >= l - q { i - (l - q) } else { i + q }
}

/// Kensler's `randfloat` hash as a 0.32 fixed-point fraction (Kensler 2013).
///
/// *Deviation:* the paper returns `i / (2^32 + 512)` as a float to stay below 1; here the `u32`
/// itself is the fraction `i / 2^32`, which is in `[0, 1)` by construction.
#[inline]
pub fn kensler_hash(mut i: u32, p: u32) -> u32 {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i = i.wrapping_mul(0xb365_34e5);
    i ^= i >> 12;
    i ^= i >> 21;
    i = i.wrapping_mul(0x93fc_4795);
    i ^= 0xdf6e_307f;
    i ^= i >> 17;
    i = i.wrapping_mul(1 | (p >> 18));
    i
}

/// A Laine–Karras-style hash in which output bit `k` depends only on input bits `0..=k` (and
/// the seed): additions, odd multiplications and `x ^= x·even` carry information only upwards.
///
/// Constants from N. Vegdahl's improvement (2021) of Burley 2020's `laine_karras_permutation`.
#[inline]
pub fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Nested uniform (Owen) scrambling of a 0.32 fraction (Burley 2020): bit-reverse, apply
/// [`laine_karras`], bit-reverse back. Output bit `31 − k` depends only on input bits
/// `31 − k … 31`, so every dyadic interval `[a/2^m, (a+1)/2^m)` maps onto another one: the
/// scramble permutes elementary intervals and preserves (t, m, s)-net structure.
#[inline]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// Shuffles a sample index by nested uniform scrambling that maps every power-of-two prefix
/// `[0, 2^m)` onto itself: `owen_scramble(i, seed) ^ owen_scramble(0, seed)`.
///
/// Burley 2020 shuffles with `owen_scramble(i, seed)` alone, which sends the prefix to a random
/// aligned block of the sequence (the high bits of the result are a seed-dependent constant).
/// XOR-ing the image of 0 cancels that constant: the result is still a nested permutation
/// (bit k depends only on bits ≥ k), aligned blocks still map to aligned blocks, and in
/// addition the shuffled index has the same highest set bit as `i`, so sequence code that
/// costs O(log index) (Sobol's matrix product, PMJ02's chain) stays O(log i) instead of
/// O(32). *Deviation from Burley 2020*, measured in the convergence and stratification tests.
#[inline]
pub fn owen_shuffle_index(i: u32, seed: u32) -> u32 {
    owen_scramble(i, seed) ^ owen_scramble(0, seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_hash_known_values() {
        // Derived by hand from the formula: v = 0 → state = 2891336453 = 0xAC564B05,
        // shift = (0xA + 4) = 14, word = ((0xAC564B05 >> 14) ^ 0xAC564B05) · 277803737.
        let state: u32 = 2_891_336_453;
        let word = ((state >> 14) ^ state).wrapping_mul(277_803_737);
        assert_eq!(pcg_hash(0), (word >> 22) ^ word);
        assert_eq!(state >> 28, 0xA);
    }

    #[test]
    fn pcg_hash_is_a_bijection_on_a_sample() {
        // A bijection cannot map 2^20 distinct inputs to fewer outputs.
        let mut out: Vec<u32> = (0..1u32 << 20).map(pcg_hash).collect();
        out.sort_unstable();
        out.dedup();
        assert_eq!(out.len(), 1 << 20);
    }

    #[test]
    fn kensler_permute_is_a_permutation() {
        for l in [1u32, 2, 3, 5, 16, 17, 100, 255, 256, 1000, 4097] {
            for p in [0u32, 1, 0xdead_beef, 0x8000_0000, u32::MAX] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = kensler_permute(i, l, p);
                    assert!(j < l, "l={l} p={p} i={i} -> {j}");
                    assert!(!seen[j as usize], "l={l} p={p}: {j} twice");
                    seen[j as usize] = true;
                }
            }
        }
        // Huge l: the modular rotation must not overflow.
        let l = u32::MAX;
        assert!(kensler_permute(l - 1, l, u32::MAX - 3) < l);
    }

    #[test]
    fn owen_scramble_maps_dyadic_intervals_to_dyadic_intervals() {
        // Two fractions that share their top m bits must still share their top m bits.
        let mut x = 0x9e37_79b9u32;
        for seed in [0u32, 1, 0x1234_5678, u32::MAX] {
            for _ in 0..10_000 {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                let m = x % 33;
                let mask = if m == 0 { 0 } else { u32::MAX << (32 - m) };
                let y = (x & mask) | (x.rotate_left(7) & !mask);
                assert_eq!(owen_scramble(x, seed) & mask, owen_scramble(y, seed) & mask, "m={m}");
            }
        }
    }

    #[test]
    fn owen_shuffle_permutes_each_power_of_two_prefix() {
        for seed in [0u32, 5, 0xFFFF_0000] {
            for m in [0u32, 1, 4, 10] {
                let mut seen = vec![false; 1 << m];
                for i in 0..1u32 << m {
                    let j = owen_shuffle_index(i, seed);
                    assert!(j < 1 << m, "seed {seed} m {m}: {i} -> {j}");
                    assert!(!seen[j as usize]);
                    seen[j as usize] = true;
                    assert_eq!(j.leading_zeros(), i.leading_zeros());
                }
            }
        }
    }

    #[test]
    fn owen_scramble_is_a_bijection_on_a_sample() {
        let mut out: Vec<u32> = (0..1u32 << 18).map(|i| owen_scramble(i << 14, 77)).collect();
        out.sort_unstable();
        out.dedup();
        assert_eq!(out.len(), 1 << 18);
    }
}
