//! The integration tests of furnace-sampling, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-sampling --test all MODULE::`.

/// Helpers the modules share.
mod common;
#[path = "convergence.rs"]
mod convergence;
#[path = "edges.rs"]
mod edges;
#[path = "exactness.rs"]
mod exactness;
#[path = "stratification.rs"]
mod stratification;
#[path = "warps.rs"]
mod warps;
