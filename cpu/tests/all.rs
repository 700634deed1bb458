//! The integration tests of furnace-cpu, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-cpu --test all MODULE::`.

#[path = "cancel.rs"]
mod cancel;
#[path = "determinism.rs"]
mod determinism;
#[path = "film.rs"]
mod film;
#[path = "furnace.rs"]
mod furnace;
