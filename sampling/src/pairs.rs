//! What the samplers built from 2-D patterns share: the fixed-N bookkeeping of Hammersley and
//! CMJ, and the `Sampler` impl that maps dimension pairs `(2k, 2k+1)` onto pattern `k`.

use crate::SamplerError;

/// The largest N of the fixed-N samplers (2^30): CMJ's m·n grid must fit in a `u32`.
pub const MAX_SAMPLE_COUNT: u32 = 1 << 30;

/// Validates a fixed-N sampler's N.
pub(crate) fn validate_count(sampler: &'static str, n: u32) -> Result<u32, SamplerError> {
    if n == 0 {
        Err(SamplerError::MissingSampleCount { sampler, got: "0".into() })
    } else if n > MAX_SAMPLE_COUNT {
        Err(SamplerError::SampleCountTooLarge { sampler, got: n, max: MAX_SAMPLE_COUNT })
    } else {
        Ok(n)
    }
}

/// `Ok` if `index < count`, else the error that says what the sampler does there.
pub(crate) fn check_index(sampler: &'static str, index: u32, count: u32) -> Result<(), SamplerError> {
    if index < count { Ok(()) } else { Err(SamplerError::IndexOutOfRange { sampler, index, count }) }
}

/// Implements [`crate::Sampler`] for a type with
/// `fn pair(&self, pixel: u32, index: u32, pair: u32) -> [u32; 2]`: dimension `d` is coordinate
/// `d & 1` of pattern `d / 2`; `bits_2d` at an even dimension computes the pair once.
macro_rules! impl_sampler_by_pairs {
    ($ty:ty) => {
        impl $crate::Sampler for $ty {
            #[inline]
            fn bits(&self, pixel: u32, index: u32, dimension: u32) -> u32 {
                self.pair(pixel, index, dimension / 2)[(dimension & 1) as usize]
            }

            #[inline]
            fn bits_2d(&self, pixel: u32, index: u32, dimension: u32) -> [u32; 2] {
                if dimension & 1 == 0 {
                    self.pair(pixel, index, dimension / 2)
                } else {
                    // The pair straddles two patterns.
                    let next = dimension.wrapping_add(1);
                    [self.bits(pixel, index, dimension), self.bits(pixel, index, next)]
                }
            }
        }
    };
}
pub(crate) use impl_sampler_by_pairs;
