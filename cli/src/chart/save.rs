//! The study's files in `--out`: `chart.json` (settings, machine, configurations and rows; the
//! source of truth on resume) and `chart.csv`, each written atomically.

use super::axes::AXES;
use super::data::{self, Row, rows_of, slope};
use super::study::Study;
use crate::shared::write_atomically;
use serde_json::{Value, json};
use std::path::Path;

/// The data file (settings and rows) in `--out`.
const JSON_NAME: &str = "chart.json";
/// The rows as CSV in `--out`.
const CSV_NAME: &str = "chart.csv";
/// Version of the `chart.json` layout.
const FORMAT: u64 = 1;

/// The saved study in `dir`, if any: its rows, after checking that its settings are `now`'s.
pub(super) fn load_saved(dir: &Path, now: &Value) -> Result<Vec<Row>, String> {
    let path = dir.join(JSON_NAME);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let p = path.display();
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("{p}: not a furnace chart file ({e})"))?;
    if v.get("format").and_then(Value::as_u64) != Some(FORMAT) {
        return Err(format!("{p}: not a furnace chart file of format {FORMAT}"));
    }
    let mut recorded = v.get("settings").cloned().unwrap_or(Value::Null);
    // A study saved before an axis that is always recorded rendered only the axis's value of
    // then (an axis recorded only when used is absent from such a study and from today's).
    if let Some(s) = recorded.as_object_mut() {
        for axis in AXES.iter().filter(|a| a.unrecorded.is_none()) {
            if let Some(before) = axis.before {
                s.entry(axis.list).or_insert_with(|| json!([before]));
            }
        }
    }
    if let Some((key, was, is)) = data::first_difference(&recorded, now) {
        return Err(format!(
            "{} holds a study with other settings ({key}: {was} there, {is} now); re-run with the same \
             settings to resume it, or give another --out",
            dir.display()
        ));
    }
    let rows = v.get("rows").and_then(Value::as_array).ok_or_else(|| format!("{p}: no 'rows'"))?;
    rows.iter().map(|r| data::row_from_json(r).map_err(|e| format!("{p}: {e}"))).collect()
}

/// Writes chart.json and chart.csv (rows in configuration order, then by spp).
pub(super) fn save_data(study: &Study, rows: &mut [Row], machine: &Value) -> Result<(), String> {
    let order = |r: &Row| study.configs.iter().position(|c| c.name() == r.config).unwrap_or(usize::MAX);
    rows.sort_by_key(|r| (order(r), r.spp));
    let doc = json!({
        "format": FORMAT,
        "settings": study.settings_json(),
        "reference_path": study.reference.path.display().to_string(),
        "reference_compensated_path": study.compensated.as_ref().map(|r| r.path.display().to_string()),
        "machine": machine,
        "metrics": "rmse: sqrt(mean over pixels and channels of (x - r)^2); relmse: mean over pixels and channels \
                    of (x - r)^2 / (r^2 + 0.01) (furnace compare)",
        "timing": "seconds: wall time of the render passes that produced the image (progressive samplers: all \
                   passes up to the checkpoint; fixed-N samplers: the passes of that checkpoint's own N-sample \
                   render); excludes scene load, BVH build, upload, pipeline creation, film read-back and metrics. \
                   cpu_seconds: the process's CPU time (user + system, all threads; 10 ms ticks of \
                   /proc/self/stat) over the same passes",
        "slopes": "least squares of ln(error) against ln(spp) over the configuration's checkpoints",
        "configs": configs_json(study, rows),
        "rows": rows.iter().map(data::row_json).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())? + "\n";
    let dir = &study.args.out;
    write_atomically(&dir.join(JSON_NAME), text.as_bytes())?;
    write_atomically(&dir.join(CSV_NAME), data::to_csv(rows).as_bytes())
}

/// Each configuration's name, value of each axis, reference, completeness and slopes.
fn configs_json(study: &Study, rows: &[Row]) -> Vec<Value> {
    study
        .configs
        .iter()
        .map(|c| {
            let name = c.name();
            let mine = rows_of(rows, &name);
            let (r, matches) = study.reference_for(c);
            let mut v = json!({
                "config": name,
                "reference": r.path.display().to_string(),
                "reference_matches": matches,
                "complete": mine.len() == study.checkpoints.len(),
                "slope_rmse_vs_spp": slope(&mine, |r| r.rmse),
                "slope_relmse_vs_spp": slope(&mine, |r| r.relmse),
            });
            for axis in AXES {
                v[axis.key] = json!(c.value(axis));
            }
            v
        })
        .collect()
}
