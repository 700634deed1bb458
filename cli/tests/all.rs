//! The integration tests of furnace-cli, as one test binary: one compile and link of the
//! crate's dependencies for all of them, instead of one per file (most of CI's build time on
//! 2 cores). Each module is one file beside this one, run alone with
//! `cargo test -p furnace-cli --test all MODULE::`.

#[path = "chart.rs"]
mod chart;
#[path = "cli.rs"]
mod cli;
/// Helpers the modules share.
mod common;
#[path = "gpu.rs"]
mod gpu;
#[path = "hostile.rs"]
mod hostile;
#[path = "view.rs"]
mod view;
