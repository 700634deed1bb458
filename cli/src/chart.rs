//! `furnace chart`: speed against accuracy. Renders one scene progressively under several
//! configurations — sampler × BRDF sampling method × light sampling × triangle sampling × light
//! selection × energy compensation × backend — and records at checkpoints of 1, 2, 4, … samples
//! per pixel (and `--spp`) the wall time and the error against a reference image; writes the
//! data as CSV and JSON and draws error-vs-spp and error-vs-time charts (PNG and SVG).
//!
//! * **Error**: `furnace_post::metrics::score` (the metrics of `furnace compare`): RMSE over all channel values, and relative MSE
//!   `mean((x − r)² / (r² + ε))` over all pixels and channels with ε = 1e-2.
//! * **Time**: the wall time of the `render_pass` calls that produced the image, nothing else —
//!   not the scene load, BVH build, upload or pipeline creation, not reading the film back and
//!   not the metrics. A GPU pass includes waiting for the device and folding the pass into the
//!   film (`GpuRenderer::render_pass` returns when both are done).
//! * **Progressive samplers** (random, pmj02, sobol) render once up to `--spp`; the image is
//!   scored at each checkpoint and the time is the total up to it.
//! * **Fixed-N samplers** (hammersley, cmj) build one pattern of N samples per pixel and are only
//!   well distributed at the full N, so each checkpoint is its own render with N = the
//!   checkpoint, timed from its first pass. That is how they are used correctly; it costs about
//!   twice the samples of a progressive run.
//! * **Model and reference**: a configuration whose BRDF model (masking, compensation) differs
//!   from the one the reference was rendered with converges to a different image: its error
//!   flattens at that bias. Each row records whether its reference matches (`reference_matches`);
//!   a reference may be given for each compensation state (`--reference`,
//!   `--reference-compensated`).
//! * **Resume**: `--out DIR` holds `chart.json` (settings and rows; the source of truth) and
//!   `chart.csv`, rewritten atomically after every checkpoint. Re-running the same command skips
//!   the complete configurations and the checkpoints of fixed-N samplers already done; a
//!   progressive configuration stopped part-way is rendered again from sample 0 (its film is not
//!   saved). Different settings are refused. Ctrl-C finishes the current pass, saves the data
//!   and charts, and exits with code 130.

mod axes;
mod data;
mod figures;
mod measure;
mod plot;
mod prepare;
mod reference;
mod report;
mod save;
mod study;

use crate::args::ChartArgs;
use crate::interrupt::Interrupt;
use crate::shared::Outcome;
use data::ExternalPoint;
use measure::{Progress, Runner};
use std::path::PathBuf;

/// Runs the study of `a`, resuming the one saved in `--out` if there is one.
pub fn run(a: &ChartArgs, interrupt: &Interrupt) -> Result<Outcome, String> {
    let study = prepare::prepare(a)?;
    let external = read_external(&a.external)?;
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut rows = save::load_saved(&a.out, &study.settings_json())?;
    let resumed = !rows.is_empty();
    let plan = study.plan(&mut rows);
    if !a.quiet {
        report::announce(&study, study.configs.len() - plan.todo.len(), resumed);
    }
    let pixels = u64::from(study.settings.width) * u64::from(study.settings.height);
    let progress = Progress::new(a.quiet, plan.total_spp, plan.done_spp, pixels);
    let mut runner = Runner::new(&study, interrupt, progress, rows);
    let complete = runner.run_all(&plan.todo)?;
    let (mut rows, machine) = runner.finish();
    save::save_data(&study, &mut rows, &machine)?;
    figures::save_charts(&study, &rows, &external)?;
    if !a.quiet {
        print!("{}", report::summary(&study, &rows));
        eprintln!(
            "wrote {} (chart.csv, chart.json, {{rmse,relmse}}_vs_{{spp,time}}.{{png,svg}})",
            a.out.display()
        );
    }
    if !complete {
        eprintln!("interrupted: the checkpoints done are saved; re-run the same command to resume");
        return Ok(Outcome::Interrupted);
    }
    Ok(Outcome::Done)
}

/// The points of every `--external` file, in order.
fn read_external(paths: &[PathBuf]) -> Result<Vec<ExternalPoint>, String> {
    let points = paths
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
            data::parse_external(p, &text)
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(points.concat())
}
