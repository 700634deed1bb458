//! Independent uniform random samples: a counter-based PCG hash.

use crate::Sampler;
use crate::hash::{hash2, hash4};
use core::convert::Infallible;

/// Independent random samples: `bits = hash4(seed, dimension, index, pixel)` with the PCG hash
/// of Jarzynski & Olano 2020 ([`crate::hash::pcg_hash`]), nested once per coordinate.
///
/// Progressive (every prefix is an i.i.d. uniform sample), needs no N, converges as N^-1/2.
/// Integer-only (`u32`, wrapping), so its WGSL twin is bit-identical. For fixed
/// `(pixel, dimension, seed)` the map `index ↦ bits` is a bijection of `u32`: no value repeats
/// within 2^32 samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RandomSampler {
    seed: u32,
}

impl RandomSampler {
    /// A random sampler; different seeds give independent images.
    pub fn new(seed: u32) -> Self {
        Self { seed }
    }

    /// The seed.
    pub fn seed(&self) -> u32 {
        self.seed
    }
}

impl Sampler for RandomSampler {
    #[inline]
    fn bits(&self, pixel: u32, index: u32, dimension: u32) -> u32 {
        hash4(self.seed, dimension, index, pixel)
    }
}

/// A sequential generator over the same hash: `next_u32` returns `hash2(key, counter)` and
/// increments the counter, so the stream is addressable too ([`RandomStream::at`] jumps to any
/// position in O(1)).
///
/// Implements `rand_core` 0.10's [`rand_core::TryRng`] with `Error = Infallible` (hence
/// [`rand_core::Rng`]), so it plugs into the `rand` ecosystem. Integer-only (`u32`, wrapping);
/// `next_u64` is two consecutive `u32`s, low word first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RandomStream {
    key: u32,
    counter: u32,
}

impl RandomStream {
    /// A stream keyed by `(pixel, dimension, seed)`, starting at counter 0.
    pub fn new(pixel: u32, dimension: u32, seed: u32) -> Self {
        Self { key: hash2(hash2(seed, dimension), pixel), counter: 0 }
    }

    /// The same stream positioned at `counter`.
    pub fn at(mut self, counter: u32) -> Self {
        self.counter = counter;
        self
    }

    /// The next value as a 0.32 fraction (integer-only).
    #[inline]
    pub fn next_bits(&mut self) -> u32 {
        let v = hash2(self.counter, self.key);
        self.counter = self.counter.wrapping_add(1);
        v
    }

    /// The next value in `[0, 1)` (exact conversion, [`crate::to_unit_f32`]).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        crate::to_unit_f32(self.next_bits())
    }
}

impl rand_core::TryRng for RandomStream {
    type Error = Infallible;

    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok(self.next_bits())
    }

    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        let lo = self.next_bits() as u64;
        let hi = self.next_bits() as u64;
        Ok(lo | (hi << 32))
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(4) {
            let bytes = self.next_bits().to_le_bytes();
            chunk.copy_from_slice(&bytes[..chunk.len()]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;

    #[test]
    fn stream_is_addressable_and_implements_rng() {
        let mut a = RandomStream::new(3, 4, 5);
        let first: Vec<u32> = (0..10).map(|_| a.next_u32()).collect();
        let mut b = RandomStream::new(3, 4, 5).at(7);
        assert_eq!(b.next_u32(), first[7]);
        let mut c = RandomStream::new(3, 4, 5);
        assert_eq!(c.next_u64(), first[0] as u64 | ((first[1] as u64) << 32));
        let mut bytes = [0u8; 6];
        RandomStream::new(3, 4, 5).fill_bytes(&mut bytes);
        assert_eq!(&bytes[..4], &first[0].to_le_bytes());
        assert_eq!(&bytes[4..], &first[1].to_le_bytes()[..2]);
    }

    #[test]
    fn sampler_distinguishes_every_coordinate() {
        let s = RandomSampler::new(1);
        let base = s.bits(10, 20, 30);
        assert_ne!(base, s.bits(11, 20, 30));
        assert_ne!(base, s.bits(10, 21, 30));
        assert_ne!(base, s.bits(10, 20, 31));
        assert_ne!(base, RandomSampler::new(2).bits(10, 20, 30));
    }
}
