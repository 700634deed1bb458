//! What the study tells the user on the terminal: the plan before rendering and a Markdown
//! summary table at the end.

use super::data::{Row, rows_of, slope};
use super::study::Study;
use furnace_render::Choice;

/// Prints the study's scene, settings and number of configurations (and, when resumed, how
/// many are already complete) on stderr.
pub(super) fn announce(study: &Study, skipped: usize, resumed: bool) {
    let a = &study.args;
    let s = &study.settings;
    eprintln!(
        "chart: {} {}×{}, {} bounces, masking {}, seed {}, up to {} spp: {} configurations{}",
        study.scene_name,
        s.width,
        s.height,
        s.bounces,
        Choice::name(s.specular.masking),
        s.seed,
        a.spp,
        study.configs.len(),
        if resumed { format!(" ({skipped} already complete in {})", a.out.display()) } else { String::new() }
    );
}

/// A Markdown table of each configuration's last checkpoint and slopes.
pub(super) fn summary(study: &Study, rows: &[Row]) -> String {
    let mut s = String::from(
        "| config | spp | seconds | CPU s | RMSE | relMSE | slope RMSE | slope relMSE | ref model |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for c in &study.configs {
        let mine = rows_of(rows, &c.name());
        let Some(last) = mine.last() else { continue };
        let k = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |k| format!("{k:.3}"));
        s.push_str(&format!(
            "| {} | {} | {:.3} | {:.2} | {:.4e} | {:.4e} | {} | {} | {} |\n",
            last.config,
            last.spp,
            last.seconds,
            last.cpu_seconds,
            last.rmse,
            last.relmse,
            k(slope(&mine, |r| r.rmse)),
            k(slope(&mine, |r| r.relmse)),
            if last.reference_matches { "same" } else { "differs" }
        ));
    }
    s
}
