//! Errors of sampler construction and of out-of-range use.

use thiserror::Error;

/// What can go wrong when building or addressing a sampler.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SamplerError {
    /// A sampler that builds one N-point pattern per pixel was given no N, or N = 0.
    #[error("the {sampler} sampler needs a total sample count N ≥ 1 (got {got})")]
    MissingSampleCount {
        /// The sampler's name (`hammersley`, `cmj`).
        sampler: &'static str,
        /// What was given (0 or "none").
        got: String,
    },
    /// A fixed-N sampler was given an N beyond what its integer arithmetic supports.
    #[error("the {sampler} sampler supports N ≤ {max} samples per pixel (got {got})")]
    SampleCountTooLarge {
        /// The sampler's name.
        sampler: &'static str,
        /// What was given.
        got: u32,
        /// The largest supported N.
        max: u32,
    },
    /// A fixed-N sampler was asked for a sample index past its pattern.
    #[error(
        "the {sampler} sampler was built for N = {count} samples per pixel but sample {index} was requested; \
         indices ≥ N repeat the pattern (index mod N), so the image stops converging at N samples — \
         use a progressive sampler (pmj02, sobol, random) or raise N"
    )]
    IndexOutOfRange {
        /// The sampler's name.
        sampler: &'static str,
        /// The requested index.
        index: u32,
        /// The pattern size N.
        count: u32,
    },
    /// An unknown sampler name (from [`crate::SamplerKind`]'s `FromStr`).
    #[error("unknown sampler '{0}' (expected one of: random, hammersley, cmj, pmj02, sobol)")]
    UnknownKind(String),
}
