//! Choosing a sampler by name: [`SamplerKind`] and the statically dispatched [`AnySampler`].

use crate::{Cmj, Hammersley, OwenSobol, Pmj02, RandomSampler, Sampler, SamplerError};
use core::fmt;
use core::str::FromStr;

/// The samplers, by the names the CLI uses.
///
/// | name | progressive | needs N | RMSE slope, disk / smooth 2-D integrand (measured) |
/// |---|---|---|---|
/// | `random` | yes | no | −0.50 / −0.49 |
/// | `hammersley` | no | yes | −0.79 / −0.97 (at the full N only) |
/// | `cmj` | no | yes | −0.76 / −0.79 (at the full N; non-square N is weaker) |
/// | `pmj02` | yes | no | −0.76 / −1.43 |
/// | `sobol` | yes | no | −0.77 / −1.44 |
///
/// (Dimensions 0–1, 256 pixels, N = 4…4096 in powers of two: `tests/convergence.rs`, which
/// writes the full table to `target/test-output/sampling/convergence.md`.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// [`RandomSampler`].
    Random,
    /// [`Hammersley`] (needs N).
    Hammersley,
    /// [`Cmj`] (needs N).
    Cmj,
    /// [`Pmj02`].
    Pmj02,
    /// [`OwenSobol`].
    Sobol,
}

impl SamplerKind {
    /// Every kind, in documentation order.
    pub const ALL: [SamplerKind; 5] = [Self::Random, Self::Hammersley, Self::Cmj, Self::Pmj02, Self::Sobol];

    /// The CLI name (`random`, `hammersley`, `cmj`, `pmj02`, `sobol`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Random => "random",
            Self::Hammersley => "hammersley",
            Self::Cmj => "cmj",
            Self::Pmj02 => "pmj02",
            Self::Sobol => "sobol",
        }
    }

    /// Whether every prefix of the sequence is well distributed (a render may stop anywhere).
    pub fn is_progressive(self) -> bool {
        !self.needs_sample_count()
    }

    /// Whether the sampler must know the total sample count N in advance.
    pub fn needs_sample_count(self) -> bool {
        matches!(self, Self::Hammersley | Self::Cmj)
    }
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SamplerKind {
    type Err = SamplerError;

    /// Parses a CLI name, ignoring ASCII case.
    fn from_str(s: &str) -> Result<Self, SamplerError> {
        Self::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| SamplerError::UnknownKind(s.to_string()))
    }
}

/// Any sampler, dispatched by a `match` (no virtual calls in the inner loop).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnySampler {
    /// See [`RandomSampler`].
    Random(RandomSampler),
    /// See [`Hammersley`].
    Hammersley(Hammersley),
    /// See [`Cmj`].
    Cmj(Cmj),
    /// See [`Pmj02`].
    Pmj02(Pmj02),
    /// See [`OwenSobol`].
    Sobol(OwenSobol),
}

impl AnySampler {
    /// Builds a sampler of `kind` with `seed`. `sample_count` is the total N per pixel; it is
    /// required by the kinds that need it and ignored by the progressive ones.
    ///
    /// # Errors
    /// [`SamplerError::MissingSampleCount`] if a fixed-N kind gets `None` or 0, and
    /// [`SamplerError::SampleCountTooLarge`] past 2^30.
    pub fn new(kind: SamplerKind, seed: u32, sample_count: Option<u32>) -> Result<Self, SamplerError> {
        let count = |sampler: &'static str| {
            sample_count.ok_or(SamplerError::MissingSampleCount { sampler, got: "none".into() })
        };
        Ok(match kind {
            SamplerKind::Random => Self::Random(RandomSampler::new(seed)),
            SamplerKind::Hammersley => Self::Hammersley(Hammersley::new(count("hammersley")?, seed)?),
            SamplerKind::Cmj => Self::Cmj(Cmj::new(count("cmj")?, seed)?),
            SamplerKind::Pmj02 => Self::Pmj02(Pmj02::new(seed)),
            SamplerKind::Sobol => Self::Sobol(OwenSobol::new(seed)),
        })
    }

    /// Which kind this is.
    pub fn kind(&self) -> SamplerKind {
        match self {
            Self::Random(_) => SamplerKind::Random,
            Self::Hammersley(_) => SamplerKind::Hammersley,
            Self::Cmj(_) => SamplerKind::Cmj,
            Self::Pmj02(_) => SamplerKind::Pmj02,
            Self::Sobol(_) => SamplerKind::Sobol,
        }
    }

    /// For fixed-N kinds, `Err` when `index ≥ N` (the pattern would repeat); always `Ok` for
    /// progressive kinds. The CLI uses it to warn before a render runs past N.
    pub fn check_index(&self, index: u32) -> Result<(), SamplerError> {
        match self {
            Self::Hammersley(s) => s.check_index(index),
            Self::Cmj(s) => s.check_index(index),
            _ => Ok(()),
        }
    }
}

macro_rules! dispatch {
    ($self:ident, $s:ident => $e:expr) => {
        match $self {
            AnySampler::Random($s) => $e,
            AnySampler::Hammersley($s) => $e,
            AnySampler::Cmj($s) => $e,
            AnySampler::Pmj02($s) => $e,
            AnySampler::Sobol($s) => $e,
        }
    };
}

impl Sampler for AnySampler {
    #[inline]
    fn bits(&self, pixel: u32, index: u32, dimension: u32) -> u32 {
        dispatch!(self, s => s.bits(pixel, index, dimension))
    }

    #[inline]
    fn bits_2d(&self, pixel: u32, index: u32, dimension: u32) -> [u32; 2] {
        dispatch!(self, s => s.bits_2d(pixel, index, dimension))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for k in SamplerKind::ALL {
            assert_eq!(k.to_string().parse::<SamplerKind>().unwrap(), k);
        }
        assert_eq!("SOBOL".parse::<SamplerKind>().unwrap(), SamplerKind::Sobol);
        let err = "halton".parse::<SamplerKind>().unwrap_err();
        assert!(err.to_string().contains("halton") && err.to_string().contains("pmj02"));
    }

    #[test]
    fn fixed_n_kinds_demand_n() {
        for k in [SamplerKind::Hammersley, SamplerKind::Cmj] {
            assert!(matches!(AnySampler::new(k, 0, None), Err(SamplerError::MissingSampleCount { .. })));
            assert!(AnySampler::new(k, 0, Some(0)).is_err());
            assert!(AnySampler::new(k, 0, Some(16)).is_ok());
        }
        for k in [SamplerKind::Random, SamplerKind::Pmj02, SamplerKind::Sobol] {
            assert!(AnySampler::new(k, 0, None).is_ok());
        }
    }
}
