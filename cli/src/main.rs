//! # furnace (the command-line tool)
//!
//! A thin composition of the furnace crates — no rendering logic of its own:
//!
//! * `furnace render [SCENE]` loads a glTF/GLB scene (`furnace_scene`; the built-in reference
//!   Cornell box without one), renders it in passes of a few samples per pixel with the CPU
//!   reference integrator (`furnace_cpu`), showing progress with `indicatif`, and writes the
//!   linear image as OpenEXR (with the render's metadata) and the tone-mapped sRGB image as PNG
//!   (`furnace_post`).
//!   `--resume PATH.exr` continues a saved render bit-identically (the EXR carries the film's
//!   exact sums and counts, `resume.rs`); Ctrl-C stops the render within a second, saves, and exits
//!   with code 130 (`interrupt.rs`). The loop drives a `furnace_render::Session` over the
//!   integrator that `furnace_cli::backend::open` chooses (CPU or GPU).
//! * `furnace view [SCENE]` takes render's options and shows the GPU integrator's film as it
//!   converges, in a window (`furnace_view`): camera controls, a settings panel, a HUD; Ctrl+S
//!   saves what `render` writes (`view.rs`).
//! * `furnace info SCENE` prints a scene's sizes, lights, cameras (with their `--camera` index)
//!   and loader warnings, then the render settings that render's settings flags (taken too)
//!   make, a line per field of `furnace_render::fields::FIELDS`.
//! * `furnace render --samples A..B` renders one part of a split render (global sample indices
//!   A…B−1); `furnace merge PARTS… -o OUT` checks that the parts are of one render and disjoint,
//!   lists missing samples, and adds their films into the single run's (`merge.rs`).
//! * `furnace compare CANDIDATE.exr REFERENCE.exr [--stderr …]` scores a render against a
//!   reference with `furnace_post::metrics` (RMSE, relative MSE, mean ratio, z-scores).
//! * `furnace bench [--backend …] [--scene cbox|interior:N|PATH]` measures a backend:
//!   Msamples/s, Mrays/s, ms per frame, time to first frame, GPU bytes per triangle, as a
//!   Markdown table and JSON (`bench.rs`).
//! * `furnace chart --reference REF.exr [--samplers …] [--sampling …]` charts speed against
//!   accuracy: error against the reference and render time at checkpoints, per configuration,
//!   as CSV, JSON, PNG and SVG (`chart.rs`); resumable.
//!
//! Every error is one line on stderr, `error: …`, naming the file where there is one, and the
//! exit code is 1; no user input panics.

mod args;
mod bench;
mod chart;
mod compare;
mod default_light;
mod env;
mod info;
mod interrupt;
mod memory;
mod merge;
mod outputs;
mod render;
mod resume;
mod shared;
mod view;

use clap::error::ErrorKind;
use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches};
use std::process::ExitCode;

fn main() -> ExitCode {
    quiet_device_select_layer();
    let cli = match parse() {
        Ok(cli) => cli,
        Err(e) => {
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                // Help and version go to stdout with exit code 0.
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                let _ = e.print();
                return ExitCode::FAILURE;
            }
            return fail(&clap_one_line(&e));
        }
    };
    let result = match cli.command {
        args::Command::Render(a) => render::run(&a, &interrupt::Interrupt::install()),
        args::Command::View(a) => view::run(&a, &interrupt::Interrupt::install()),
        args::Command::Info(a) => info::run(&a).map(|()| shared::Outcome::Done),
        args::Command::Compare(a) => compare::run(&a).map(|()| shared::Outcome::Done),
        args::Command::Merge(a) => merge::run(&a).map(|()| shared::Outcome::Done),
        args::Command::Bench(a) => bench::run(&a).map(|()| shared::Outcome::Done),
        args::Command::Chart(a) => chart::run(&a, &interrupt::Interrupt::install()),
    };
    match result {
        Ok(shared::Outcome::Done) => ExitCode::SUCCESS,
        // 128 + SIGINT, what a shell reports for a process ended by Ctrl-C.
        Ok(shared::Outcome::Interrupted) => ExitCode::from(130),
        Err(message) => fail(&message),
    }
}

/// Switches off Mesa's Vulkan device-selection layer for this process, unless the user set its
/// switches (`NODEVICE_SELECT`, `MESA_VK_DEVICE_SELECT`). The layer is an implicit layer that
/// Mesa's Vulkan drivers install, loaded into every Vulkan instance; it connects to a Wayland
/// display to put the display's GPU first, and without `XDG_RUNTIME_DIR` (a headless shell, a
/// container, a batch job) libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set in
/// the environment.` twice on a run that did not fail, lines that read as furnace's own errors.
/// furnace ranks adapters itself (`furnace_gpu::context`), so it needs nothing from the layer;
/// switching it off in every session, not only headless ones, keeps the adapters' order (and
/// so `--gpus` indices) the same whatever the session's display.
fn quiet_device_select_layer() {
    if std::env::var_os("NODEVICE_SELECT").is_none() && std::env::var_os("MESA_VK_DEVICE_SELECT").is_none() {
        // SAFETY: the first statement of `main`, before any thread is started, so no other
        // thread reads or writes the environment meanwhile.
        #[allow(unsafe_code)]
        unsafe {
            std::env::set_var("NODEVICE_SELECT", "1");
        }
    }
}

/// The command line, with `RenderArgs::given` filled from clap's value sources.
fn parse() -> Result<args::Cli, clap::Error> {
    let matches = args::Cli::command().try_get_matches()?;
    let mut cli = args::Cli::from_arg_matches(&matches)?;
    let (render, name) = match &mut cli.command {
        args::Command::Render(a) => (Some(a), "render"),
        args::Command::View(v) => (Some(&mut v.render), "view"),
        _ => (None, ""),
    };
    if let (Some(a), Some(m)) = (render, matches.subcommand_matches(name)) {
        a.given = m
            .ids()
            .map(|id| id.as_str())
            .filter(|id| m.value_source(id) == Some(ValueSource::CommandLine))
            .map(str::to_string)
            .collect();
    }
    Ok(cli)
}

/// Prints `error: MESSAGE` on stderr and returns exit code 1.
fn fail(message: &str) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::FAILURE
}

/// clap's message as one line, without its `error: ` prefix, usage block and `--help` hint; a
/// first line ending in `:` (the arguments that are missing) takes the indented lines under it.
fn clap_one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let mut lines = text.lines().skip_while(|l| l.trim().is_empty());
    let first = lines.next().unwrap_or("invalid arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first).trim();
    let listed: Vec<&str> = if first.ends_with(':') {
        lines
            .take_while(|l| l.starts_with(char::is_whitespace) && !l.trim().is_empty())
            .map(str::trim)
            .collect()
    } else {
        Vec::new()
    };
    if listed.is_empty() {
        format!("{first} (see 'furnace --help')")
    } else {
        format!("{first} {} (see 'furnace --help')", listed.join(", "))
    }
}
