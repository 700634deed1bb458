//! 0.32 fixed-point helpers: exact division and the one conversion to `f32`.
//!
//! Every sampler computes its sample as a `u32` fraction `bits / 2^32` with wrapping `u32`
//! arithmetic only (no `u64`, no `f64`), because WGSL has neither 64-bit integers nor a
//! correctly rounded `f32` division: integer code is the only way for the GPU twin to be
//! bit-identical. The helpers here are the building blocks.

/// Converts a 0.32 fixed-point fraction to `f32` in `[0, 1)`, exactly.
///
/// Keeps the top 24 bits (an `f32` has a 24-bit significand), so the result is
/// `(bits >> 8) · 2^-24`: both factors and the product are exactly representable, hence the
/// result is identical on every IEEE-754 machine and in WGSL. The largest value is
/// `1 − 2^-24`, never `1.0`.
#[inline]
pub fn to_unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// `floor((hi · 2^32 + lo) / d)` for `hi < d`: a fraction `(hi + lo/2^32) / d` in 0.32 fixed
/// point, by long division in `u32` only.
///
/// Divisors below 2^16 take two 16-bit digit steps (two hardware divisions); larger ones a
/// 32-step restoring division. Both paths are exact, so they agree bit for bit (tested).
///
/// # Panics
/// In debug builds, if `d == 0` or `hi >= d` (the quotient would not fit in 32 bits).
#[inline]
pub fn div_frac(hi: u32, lo: u32, d: u32) -> u32 {
    debug_assert!(d != 0 && hi < d, "div_frac needs hi < d (hi = {hi}, d = {d})");
    if d <= 0xFFFF {
        // r < d < 2^16, so (r << 16) | digit < 2^32: no overflow.
        let n1 = (hi << 16) | (lo >> 16);
        let (q1, r1) = (n1 / d, n1 % d);
        let n2 = (r1 << 16) | (lo & 0xFFFF);
        (q1 << 16) | (n2 / d)
    } else {
        div_frac_bitwise(hi, lo, d)
    }
}

/// The restoring-division path of [`div_frac`], valid for any `d ≥ 1`, `hi < d`.
///
/// Public so that tests (and the WGSL twin's tests) can check the fast path against it.
#[inline]
pub fn div_frac_bitwise(hi: u32, lo: u32, d: u32) -> u32 {
    let mut r = hi;
    let mut q = 0u32;
    let mut bit = 32;
    while bit > 0 {
        bit -= 1;
        // r < d ≤ 2^32 − 1; 2r + 1 may need 33 bits: keep the carry separately.
        let carry = r >> 31;
        r = (r << 1) | ((lo >> bit) & 1);
        q <<= 1;
        if carry == 1 || r >= d {
            r = r.wrapping_sub(d);
            q |= 1;
        }
    }
    q
}

/// `floor(sqrt(n))` in `u32` arithmetic (bit-by-bit; exact for every `n`).
///
/// Kensler's CMJ uses `sqrtf(N)`, which can round up just below a perfect square for large N;
/// the integer square root is the value the paper means.
#[inline]
pub fn isqrt(n: u32) -> u32 {
    let mut rem = n;
    let mut root = 0u32;
    let mut bit = 1u32 << 30;
    while bit > n {
        bit >>= 2;
    }
    while bit != 0 {
        if rem >= root + bit {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Test-only reference: the same quotient with 64-bit arithmetic.
    fn reference(hi: u32, lo: u32, d: u32) -> u32 {
        ((((hi as u64) << 32) | lo as u64) / d as u64) as u32
    }

    #[test]
    fn unit_conversion_is_exact_and_below_one() {
        assert_eq!(to_unit_f32(0), 0.0);
        assert_eq!(to_unit_f32(0x8000_0000), 0.5);
        assert_eq!(to_unit_f32(u32::MAX), 1.0 - 2f32.powi(-24));
        assert!(to_unit_f32(u32::MAX) < 1.0);
    }

    #[test]
    fn div_frac_matches_64_bit_division() {
        let mut x = 0x1234_5678u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        let divisors = [1, 2, 3, 7, 255, 256, 1000, 0xFFFF, 0x1_0000, 0x1_0001, 1 << 31, u32::MAX];
        for &d in &divisors {
            for _ in 0..2000 {
                let hi = next() % d;
                let lo = next();
                assert_eq!(div_frac(hi, lo, d), reference(hi, lo, d), "d={d} hi={hi} lo={lo}");
                assert_eq!(div_frac_bitwise(hi, lo, d), reference(hi, lo, d));
            }
            // Extremes of the numerator.
            assert_eq!(div_frac(d - 1, u32::MAX, d), reference(d - 1, u32::MAX, d));
            assert_eq!(div_frac(0, 0, d), 0);
        }
        for _ in 0..20000 {
            let d = next().max(1);
            let hi = next() % d;
            let lo = next();
            assert_eq!(div_frac(hi, lo, d), reference(hi, lo, d), "d={d} hi={hi} lo={lo}");
        }
    }

    #[test]
    fn isqrt_is_exact() {
        for n in 0..100_000u32 {
            let r = isqrt(n);
            assert!(r * r <= n && (r + 1) * (r + 1) > n, "n={n} r={r}");
        }
        for n in [u32::MAX, u32::MAX - 1, 65535 * 65535, 65535 * 65535 - 1, 1 << 31] {
            let r = isqrt(n) as u64;
            assert!(r * r <= n as u64 && (r + 1) * (r + 1) > n as u64, "n={n}");
        }
    }
}
