//! # furnace-cli
//!
//! The library half of the `furnace` binary: what its subcommands share and other programs
//! (tests, tools) may call — the choice of integrator ([`backend`]). The binary itself
//! (`src/main.rs`) composes the furnace crates into `furnace render`, `info`, `compare`,
//! `bench` and `chart`.

pub mod backend;
