//! The integration tests of furnace-brdf, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-brdf --test all MODULE::`.

#[path = "anisotropy.rs"]
mod anisotropy;
#[path = "chi2.rs"]
mod chi2;
/// Helpers the modules share.
mod common;
#[path = "consistency.rs"]
mod consistency;
#[path = "dielectric.rs"]
mod dielectric;
#[path = "diffuse_transmission.rs"]
mod diffuse_transmission;
#[path = "iridescence.rs"]
mod iridescence;
#[path = "layers.rs"]
mod layers;
#[path = "stability.rs"]
mod stability;
#[path = "turquin_tables.rs"]
mod turquin_tables;
#[path = "where_methods_fail.rs"]
mod where_methods_fail;
#[path = "white_furnace.rs"]
mod white_furnace;
