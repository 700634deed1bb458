//! The integration tests of furnace-accel, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-accel --test all MODULE::`.

/// Helpers the modules share.
mod common;
#[path = "deep_trees.rs"]
mod deep_trees;
#[path = "degenerate.rs"]
mod degenerate;
#[path = "determinism.rs"]
mod determinism;
#[path = "instances.rs"]
mod instances;
#[path = "queries.rs"]
mod queries;
#[path = "self_intersection.rs"]
mod self_intersection;
