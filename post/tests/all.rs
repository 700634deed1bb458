//! The integration tests of furnace-post, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-post --test all MODULE::`.

#[path = "curves.rs"]
mod curves;
#[path = "files.rs"]
mod files;
#[path = "fuzz.rs"]
mod fuzz;
#[path = "hostile.rs"]
mod hostile;
