//! # furnace (the command-line tool)
//!
//! A thin composition of the furnace crates — no rendering logic of its own:
//!
//! * `furnace render [SCENE]` loads a glTF/GLB scene (`furnace_scene`; the built-in reference
//!   Cornell box without one), renders it in passes of a few samples per pixel with the CPU
//!   reference integrator (`furnace_cpu`), showing progress with `indicatif`, and writes the
//!   linear image as OpenEXR (with the render's metadata) and the tone-mapped sRGB image as PNG
//!   (`furnace_post`).
//! * `furnace info SCENE` prints a scene's sizes, lights, camera and loader warnings.
//! * `furnace compare CANDIDATE.exr REFERENCE.exr [--stderr …]` scores a render against a
//!   reference as `shared/oracle/compare.py` does (RMSE, relative MSE, mean ratio, z-scores).
//!
//! Every error is one line on stderr, `error: …`, naming the file where there is one, and the
//! exit code is 1; no user input panics.

mod args;
mod compare;
mod info;
mod render;

use clap::Parser;
use clap::error::ErrorKind;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match args::Cli::try_parse() {
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
        args::Command::Render(a) => render::run(&a),
        args::Command::Info(a) => info::run(&a),
        args::Command::Compare(a) => compare::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => fail(&message),
    }
}

/// Prints `error: MESSAGE` on stderr and returns exit code 1.
fn fail(message: &str) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::FAILURE
}

/// clap's message as one line, without its `error: ` prefix, usage block and `--help` hint.
fn clap_one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("invalid arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first).trim();
    format!("{first} (see 'furnace --help')")
}
