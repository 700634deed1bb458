//! The integration tests of furnace-gpu, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-gpu --test all MODULE::`.

#[path = "cancel.rs"]
mod cancel;
#[path = "errors.rs"]
mod errors;
#[path = "film.rs"]
mod film;
#[path = "multi.rs"]
mod multi;
