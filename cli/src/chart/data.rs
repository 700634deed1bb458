//! The study's data: rows (one per configuration × checkpoint), the least-squares slope, the
//! CSV and JSON files, and the `--external` CSV of peer series. A row's configuration is its
//! values of the study's axes (`axes::AXES`), which give its keys and columns.

use super::axes::{self, AXES};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

/// One measurement: a configuration at a checkpoint.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The configuration's name (`sobol/caps/mis/solid-angle/bvh/comp-off/cpu`, see
    /// `axes::name`).
    pub config: String,
    /// The configuration's value of each axis (sampler, GGX sampling, light sampling, …,
    /// backend, denoising), in the order of `axes::AXES`, as the command line spells them.
    pub axes: Vec<String>,
    /// Samples per pixel.
    pub spp: u32,
    /// Wall time of the render passes that produced this image (seconds).
    pub seconds: f64,
    /// CPU time (user + system, all threads of the process) of those passes, in seconds, at
    /// 10 ms resolution (Linux `/proc/self/stat`; NaN where unavailable). On a loaded machine
    /// it is a steadier measure of the CPU backend's work than wall time.
    pub cpu_seconds: f64,
    /// Root mean squared error against the reference.
    pub rmse: f64,
    /// Relative MSE against the reference (`furnace_post::metrics`, ε = 1e-2).
    pub relmse: f64,
    /// Whether the reference was rendered with this configuration's model (masking,
    /// compensation); `false`: the error has a bias floor that is not the method's.
    pub reference_matches: bool,
    /// Samples per pixel actually taken, on average (below `spp` under adaptive sampling).
    pub mean_spp: f64,
}

impl Row {
    /// Its value of the axis of key `key` (`light_sampling`).
    pub fn axis(&self, key: &str) -> &str {
        &self.axes[index(key)]
    }
}

/// The environment sampling a render uses by default with `light_sampling`: compensated, or
/// importance under `nee` (compensation needs MIS). A configuration's name leaves it out.
pub fn default_env_sampling(light_sampling: &str) -> &'static str {
    if light_sampling == "nee" { "importance" } else { "compensated" }
}

/// The columns of chart.csv as files have them (columns added later go at the end, so that a
/// reader of the older columns by position still works): the measurements and the axes, by
/// key. The axes not among them follow, in the order of `axes::AXES`.
const CSV_COLUMNS: [&str; 19] = [
    "config",
    "sampler",
    "sampling",
    "compensation",
    "backend",
    "spp",
    "seconds",
    "rmse",
    "relmse",
    "reference_matches",
    "cpu_seconds",
    "light_sampling",
    "triangle_sampling",
    "light_selection",
    "env_sampling",
    "noise_threshold",
    "denoise",
    "mean_spp",
    "point_lights",
];

/// The columns of the study's CSV file, in order.
pub fn csv_columns() -> Vec<&'static str> {
    let added = AXES.iter().map(|a| a.key).filter(|k| !CSV_COLUMNS.contains(k));
    CSV_COLUMNS.iter().copied().chain(added).collect()
}

/// A row's cell of column `key` in the CSV: numbers in Rust's shortest round-trip form, an
/// unknown CPU time empty.
fn csv_cell(r: &Row, key: &str) -> String {
    match key {
        "config" => r.config.clone(),
        "spp" => r.spp.to_string(),
        "seconds" => r.seconds.to_string(),
        "cpu_seconds" if r.cpu_seconds.is_finite() => r.cpu_seconds.to_string(),
        "cpu_seconds" => String::new(),
        "rmse" => r.rmse.to_string(),
        "relmse" => r.relmse.to_string(),
        "reference_matches" => r.reference_matches.to_string(),
        "mean_spp" => r.mean_spp.to_string(),
        axis => r.axis(axis).to_string(),
    }
}

/// The rows as CSV, with the header of [`csv_columns`].
pub fn to_csv(rows: &[Row]) -> String {
    let columns = csv_columns();
    let mut s = columns.join(",");
    s.push('\n');
    for r in rows {
        let cells: Vec<String> = columns.iter().map(|k| csv_cell(r, k)).collect();
        let _ = writeln!(s, "{}", cells.join(","));
    }
    s
}

/// A row as a JSON object: its measurements and its value of each axis.
pub fn row_json(r: &Row) -> Value {
    let mut v = json!({
        "config": r.config,
        "spp": r.spp,
        "seconds": finite(r.seconds),
        "cpu_seconds": finite(r.cpu_seconds),
        "rmse": finite(r.rmse),
        "relmse": finite(r.relmse),
        "reference_matches": r.reference_matches,
        "mean_spp": finite(r.mean_spp),
    });
    for (a, value) in AXES.iter().zip(&r.axes) {
        v[a.key] = json!(value);
    }
    v
}

/// `x` as a JSON number, `null` when not finite (JSON has no NaN or infinity).
fn finite(x: f64) -> Value {
    if x.is_finite() { json!(x) } else { Value::Null }
}

/// A row read back from the JSON of a previous run. A row saved before an axis existed has no
/// key of it: it was rendered with the axis's `before` value (an axis without one is
/// required). Such a row's configuration is renamed to today's name for it, so that a resumed
/// study finds it (the axes added since whose value has no part in the name leave it as it
/// was).
pub fn row_from_json(v: &Value) -> Result<Row, String> {
    let text = |k: &str| {
        v.get(k).and_then(Value::as_str).map(str::to_string).ok_or_else(|| format!("a row has no '{k}'"))
    };
    let num = |k: &str| match v.get(k) {
        Some(Value::Null) => Ok(f64::NAN),
        Some(x) => x.as_f64().ok_or_else(|| format!("a row's '{k}' is not a number")),
        None => Err(format!("a row has no '{k}'")),
    };
    let spp = v
        .get("spp")
        .and_then(Value::as_u64)
        .and_then(|n| u32::try_from(n).ok())
        .ok_or_else(|| "a row has no valid 'spp'".to_string())?;
    let config = text("config")?;
    let mut absent = false;
    let mut values = Vec::with_capacity(AXES.len());
    for a in AXES {
        values.push(match (v.get(a.key), a.before) {
            (None, Some(before)) => {
                absent = true;
                before.to_string()
            }
            _ => text(a.key)?,
        });
    }
    // Compensated environment sampling under nee is the plain importance
    // (`EnvSampling::effective`): what a row with nee from before the axis rendered.
    if v.get("env_sampling").is_none() {
        let (light, env) = (index("light_sampling"), index("env_sampling"));
        values[env] = default_env_sampling(&values[light]).to_string();
    }
    Ok(Row {
        config: if absent { axes::name(&values) } else { config },
        axes: values,
        spp,
        seconds: num("seconds")?,
        cpu_seconds: num("cpu_seconds").unwrap_or(f64::NAN),
        rmse: num("rmse")?,
        relmse: num("relmse")?,
        reference_matches: v.get("reference_matches").and_then(Value::as_bool).unwrap_or(true),
        // Rows saved before adaptive sampling: every sample taken.
        mean_spp: num("mean_spp").unwrap_or(f64::from(spp)),
    })
}

/// The position of the axis of key `key` in `axes::AXES`.
fn index(key: &str) -> usize {
    AXES.iter().position(|a| a.key == key).unwrap_or_else(|| unreachable!("the study has an axis {key}"))
}

/// Least-squares slope of `ln y` against `ln x` over the points with `x > 0` and finite
/// `y > 0`: the convergence rate (−0.5 for RMSE of independent samples). `None` with fewer than
/// two such points or when every `x` is the same.
pub fn log_log_slope(points: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .into_iter()
        .filter(|&(x, y)| x > 0.0 && x.is_finite() && y > 0.0 && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Rows of `config`, ordered by spp.
pub fn rows_of<'r>(rows: &'r [Row], config: &str) -> Vec<&'r Row> {
    let mut v: Vec<&Row> = rows.iter().filter(|r| r.config == config).collect();
    v.sort_by_key(|r| r.spp);
    v
}

/// The log-log slope of `metric` against spp over `rows` (see [`log_log_slope`]).
pub fn slope(rows: &[&Row], metric: fn(&Row) -> f64) -> Option<f64> {
    log_log_slope(rows.iter().map(|r| (f64::from(r.spp), metric(r))))
}

/// One point of an external series (`--external`): any field may be missing.
#[derive(Debug, Clone, PartialEq)]
pub struct ExternalPoint {
    /// The series it belongs to (its legend entry).
    pub label: String,
    /// Samples per pixel.
    pub spp: Option<f64>,
    /// Seconds.
    pub seconds: Option<f64>,
    /// RMSE against the same reference.
    pub rmse: Option<f64>,
    /// Relative MSE (ε = 1e-2, as `furnace compare`).
    pub relmse: Option<f64>,
}

/// The header an `--external` CSV must start with.
pub const EXTERNAL_HEADER: &str = "label,spp,seconds,rmse,relmse";

/// Parses an `--external` CSV: the header [`EXTERNAL_HEADER`], then one point per line; fields
/// may be empty (missing), blank lines and lines starting with `#` are skipped; no quoting (a
/// label cannot hold a comma).
pub fn parse_external(path: &Path, text: &str) -> Result<Vec<ExternalPoint>, String> {
    let p = path.display();
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let header_ok =
        lines.next().is_some_and(|(_, l)| l.split(',').map(str::trim).eq(EXTERNAL_HEADER.split(',')));
    if !header_ok {
        return Err(format!("{p}: the first line must be the header '{EXTERNAL_HEADER}'"));
    }
    let mut points = Vec::new();
    for (n, line) in lines {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 5 {
            return Err(format!("{p}:{n}: {} fields, expected 5 ({EXTERNAL_HEADER})", f.len()));
        }
        let num = |i: usize, name: &str| -> Result<Option<f64>, String> {
            if f[i].is_empty() {
                return Ok(None);
            }
            match f[i].parse::<f64>() {
                Ok(x) if x.is_finite() && x > 0.0 => Ok(Some(x)),
                _ => Err(format!("{p}:{n}: {name} '{}' is not a positive number", f[i])),
            }
        };
        if f[0].is_empty() {
            return Err(format!("{p}:{n}: empty label"));
        }
        points.push(ExternalPoint {
            label: f[0].to_string(),
            spp: num(1, "spp")?,
            seconds: num(2, "seconds")?,
            rmse: num(3, "rmse")?,
            relmse: num(4, "relmse")?,
        });
    }
    if points.is_empty() {
        return Err(format!("{p}: no data rows"));
    }
    Ok(points)
}

/// The first key under which `recorded` and `now` differ, with both values (`None`: equal).
pub fn first_difference(recorded: &Value, now: &Value) -> Option<(String, String, String)> {
    let show = |v: Option<&Value>| v.map_or_else(|| "(absent)".to_string(), Value::to_string);
    match (recorded.as_object(), now.as_object()) {
        (Some(a), Some(b)) => {
            let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter()
                .find(|k| a.get(*k) != b.get(*k))
                .map(|k| (k.clone(), show(a.get(k)), show(b.get(k))))
        }
        _ => (recorded != now).then(|| (String::new(), recorded.to_string(), now.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_an_exact_power_law_is_its_exponent() {
        // y = 3 x^-0.5 at x = 1, 2, 4, …, 1024: the fit is exact up to rounding (1e-12).
        let pts: Vec<(f64, f64)> = (0..11).map(|k| (2f64.powi(k), 3.0 * 2f64.powi(k).powf(-0.5))).collect();
        assert!((log_log_slope(pts).unwrap() + 0.5).abs() < 1e-12);
        let pts = [(1.0, 1.0), (10.0, 1e-3)];
        assert!((log_log_slope(pts).unwrap() + 3.0).abs() < 1e-12);
    }

    #[test]
    fn slope_is_least_squares_over_the_logs() {
        // ln x = 0, 1, 2 and ln y = 0, 0, 3: slope = Σ(dx·dy)/Σdx² = (−1·−1 + 0 + 1·2)/2 = 1.5.
        let e = std::f64::consts::E;
        let pts = [(1.0, 1.0), (e, 1.0), (e * e, e.powi(3))];
        assert!((log_log_slope(pts).unwrap() - 1.5).abs() < 1e-12);
    }

    #[test]
    fn slope_skips_unusable_points_and_needs_two() {
        assert_eq!(log_log_slope([(1.0, 1.0)]), None);
        assert_eq!(log_log_slope([(2.0, 1.0), (2.0, 0.5)]), None, "all x equal");
        let pts = [(1.0, 1.0), (2.0, 0.0), (4.0, f64::NAN), (0.0, 1.0), (4.0, 0.25)];
        assert!((log_log_slope(pts).unwrap() + 1.0).abs() < 1e-12);
    }

    /// A row of `config` with these axis values (by key; the others the defaults' names).
    fn row(config: &str, given: &[(&str, &str)]) -> Row {
        let defaults = [
            ("sampler", "sobol"),
            ("sampling", "caps"),
            ("light_sampling", "mis"),
            ("triangle_sampling", "solid-angle"),
            ("light_selection", "bvh"),
            ("env_sampling", "compensated"),
            ("compensation", "off"),
            ("backend", "cpu"),
            ("point_lights", "auto"),
            ("noise_threshold", "off"),
            ("denoise", "off"),
        ];
        let value = |key: &str| {
            given.iter().chain(&defaults).find(|(k, _)| *k == key).map(|(_, v)| v.to_string()).unwrap()
        };
        Row {
            config: config.into(),
            axes: AXES.iter().map(|a| value(a.key)).collect(),
            spp: 4,
            seconds: 0.5,
            cpu_seconds: f64::NAN,
            rmse: 0.25,
            relmse: 0.125,
            reference_matches: true,
            mean_spp: 4.0,
        }
    }

    #[test]
    fn csv_and_json_rows_round_trip() {
        let row = Row {
            spp: 8,
            seconds: 0.125,
            cpu_seconds: 0.25,
            rmse: 0.1 + 0.2,
            relmse: 1e-7,
            reference_matches: false,
            mean_spp: 6.5,
            ..row(
                "sobol/caps/nee/area/power/comp-off/cpu",
                &[
                    ("light_sampling", "nee"),
                    ("triangle_sampling", "area"),
                    ("light_selection", "power"),
                    ("env_sampling", "importance"),
                    ("point_lights", "one"),
                    ("noise_threshold", "0.05"),
                    ("denoise", "on"),
                ],
            )
        };
        assert_eq!(row_from_json(&row_json(&row)).unwrap(), row);
        let csv = to_csv(std::slice::from_ref(&row));
        // The columns of files written before the axes were listed, in their order.
        let header = "config,sampler,sampling,compensation,backend,spp,seconds,rmse,relmse,reference_matches,\
                      cpu_seconds,light_sampling,triangle_sampling,light_selection,env_sampling,noise_threshold,\
                      denoise,mean_spp,point_lights";
        assert_eq!(
            csv,
            format!(
                "{header}\nsobol/caps/nee/area/power/comp-off/cpu,sobol,caps,off,cpu,8,0.125,0.30000000000000004,0.0000001,false,0.25,nee,area,power,importance,0.05,on,6.5,one\n"
            )
        );
        // An unknown CPU time is an empty cell, null in the JSON.
        let unknown = Row { cpu_seconds: f64::NAN, ..row.clone() };
        assert!(to_csv(std::slice::from_ref(&unknown)).contains(",false,,nee,"));
        assert!(row_from_json(&row_json(&unknown)).unwrap().cpu_seconds.is_nan());
    }

    /// A row as saved by an older version: `config` its name then, without the keys of `absent`
    /// (nor those of the axes added after the environment sampling's).
    fn old_row(config: &str, light_sampling: &str, triangle_sampling: &str, absent: &[&str]) -> Value {
        let mut v = row_json(&row(
            config,
            &[("light_sampling", light_sampling), ("triangle_sampling", triangle_sampling)],
        ));
        for k in ["env_sampling", "noise_threshold", "denoise", "mean_spp"].iter().chain(absent) {
            v.as_object_mut().unwrap().remove(*k);
        }
        v
    }

    /// A row's config, light sampling, triangle sampling and light selection.
    fn axes(row: &Row) -> (&str, &str, &str, &str) {
        (&row.config, row.axis("light_sampling"), row.axis("triangle_sampling"), row.axis("light_selection"))
    }

    #[test]
    fn a_row_saved_before_light_sampling_is_mis() {
        // A row of a study saved before all three axes: no key of them, the older name.
        let v = old_row(
            "sobol/caps/comp-off/cpu",
            "",
            "",
            &["light_sampling", "triangle_sampling", "light_selection"],
        );
        let row = row_from_json(&v).unwrap();
        assert_eq!(axes(&row), ("sobol/caps/mis/area/power/comp-off/cpu", "mis", "area", "power"));
        assert_eq!((row.spp, row.rmse), (4, 0.25));
        assert!(row.cpu_seconds.is_nan());
    }

    #[test]
    fn a_row_saved_before_triangle_sampling_is_area() {
        // A row of a study saved after the light-sampling axis but before this one (and the
        // light-selection axis).
        let v = old_row("sobol/caps/nee/comp-off/cpu", "nee", "", &["triangle_sampling", "light_selection"]);
        let row = row_from_json(&v).unwrap();
        assert_eq!(axes(&row), ("sobol/caps/nee/area/power/comp-off/cpu", "nee", "area", "power"));
        assert_eq!((row.spp, row.rmse, row.relmse), (4, 0.25, 0.125));
        // Under nee the environment was sampled by importance (compensation needs MIS).
        assert_eq!(row.axis("env_sampling"), "importance");
    }

    #[test]
    fn a_row_saved_before_light_selection_is_power() {
        // A row of a study saved after the triangle-sampling axis but before this one: light
        // samples then chose their triangle in proportion to power.
        let v =
            old_row("sobol/caps/nee/solid-angle/comp-off/cpu", "nee", "solid-angle", &["light_selection"]);
        let row = row_from_json(&v).unwrap();
        assert_eq!(
            axes(&row),
            ("sobol/caps/nee/solid-angle/power/comp-off/cpu", "nee", "solid-angle", "power")
        );
        assert_eq!((row.spp, row.rmse, row.relmse), (4, 0.25, 0.125));
        // A row that has the key keeps its name and value.
        let mut v = v;
        v["light_selection"] = "bvh".into();
        v["config"] = "sobol/caps/nee/solid-angle/bvh/comp-off/cpu".into();
        let row = row_from_json(&v).unwrap();
        assert_eq!(axes(&row), ("sobol/caps/nee/solid-angle/bvh/comp-off/cpu", "nee", "solid-angle", "bvh"));
    }

    #[test]
    fn a_row_saved_before_point_lights_is_auto_and_keeps_its_name() {
        let v =
            old_row("sobol/caps/mis/solid-angle/bvh/comp-off/cpu", "mis", "solid-angle", &["point_lights"]);
        assert!(v.get("point_lights").is_none());
        let row = row_from_json(&v).unwrap();
        assert_eq!(
            (row.config.as_str(), row.axis("point_lights")),
            ("sobol/caps/mis/solid-angle/bvh/comp-off/cpu", "auto")
        );
        assert_eq!((row.axis("noise_threshold"), row.axis("denoise"), row.mean_spp), ("off", "off", 4.0));
    }

    #[test]
    fn a_row_saved_before_env_sampling_is_compensated_and_keeps_its_name() {
        let v = old_row("sobol/caps/mis/solid-angle/bvh/comp-off/cpu", "mis", "solid-angle", &[]);
        let row = row_from_json(&v).unwrap();
        assert_eq!(
            (row.config.as_str(), row.axis("env_sampling")),
            ("sobol/caps/mis/solid-angle/bvh/comp-off/cpu", "compensated")
        );
        // The other methods have a part of their own in the name.
        let with_env = |env: &str| {
            let mut values = row.axes.clone();
            values[index("env_sampling")] = env.into();
            axes::name(&values)
        };
        assert_eq!(with_env("importance"), "sobol/caps/mis/solid-angle/bvh/env-importance/comp-off/cpu");
        let mut row = row.clone();
        row.config = with_env("off");
        row.axes[index("env_sampling")] = "off".into();
        let back = row_from_json(&row_json(&row)).unwrap();
        assert_eq!((back.config, back.axes), (row.config, row.axes));
    }

    #[test]
    fn a_row_without_a_required_axis_is_refused() {
        for key in ["sampler", "sampling", "compensation", "backend"] {
            let mut v = row_json(&row("sobol/caps/mis/solid-angle/bvh/comp-off/cpu", &[]));
            v.as_object_mut().unwrap().remove(key);
            assert_eq!(row_from_json(&v).unwrap_err(), format!("a row has no '{key}'"));
        }
    }

    /// Every `chart.json` under `dir`, recursively.
    fn chart_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                chart_files(&path, out);
            } else if path.file_name().is_some_and(|n| n == "chart.json") {
                out.push(path);
            }
        }
    }

    /// The studies in docs/charts, written by earlier versions: every row reads back under the
    /// name its axes give, and writes back the same value under every key it had (its name
    /// aside where an axis was added since).
    #[test]
    fn the_committed_studies_read_back() {
        let mut files = Vec::new();
        chart_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/charts"), &mut files);
        assert!(!files.is_empty());
        for path in files {
            let doc: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            for v in doc["rows"].as_array().unwrap() {
                let row = row_from_json(v).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert_eq!(row.config, axes::name(&row.axes), "{}", path.display());
                let renamed = AXES.iter().any(|a| v.get(a.key).is_none());
                let back = row_json(&row);
                for (k, x) in v.as_object().unwrap() {
                    if !(renamed && k == "config") {
                        assert_eq!(&back[k], x, "{}: {k}", path.display());
                    }
                }
            }
        }
    }

    #[test]
    fn external_csv_parses_with_missing_fields_and_comments() {
        let text = "# Mitsuba 3 scalar_rgb on this VM\nlabel, spp,seconds,rmse,relmse\n\nmitsuba,16,2.5,0.01,\nmitsuba,64,,0.005,1e-4\n";
        let pts = parse_external(Path::new("m.csv"), text).unwrap();
        assert_eq!(pts.len(), 2);
        assert_eq!(
            pts[0],
            ExternalPoint {
                label: "mitsuba".into(),
                spp: Some(16.0),
                seconds: Some(2.5),
                rmse: Some(0.01),
                relmse: None
            }
        );
        assert_eq!((pts[1].seconds, pts[1].relmse), (None, Some(1e-4)));
    }

    #[test]
    fn external_csv_errors_name_the_line() {
        let bad = |t: &str| parse_external(Path::new("e.csv"), t).unwrap_err();
        assert!(bad("a,b\n").contains("header"), "{}", bad("a,b\n"));
        assert!(bad("label,spp,seconds,rmse,relmse\n").contains("no data rows"));
        let e = bad("label,spp,seconds,rmse,relmse\nx,1,2,3\n");
        assert!(e.contains("e.csv:2") && e.contains("4 fields"), "{e}");
        let e = bad("label,spp,seconds,rmse,relmse\nx,1,2,-3,\n");
        assert!(e.contains("e.csv:2") && e.contains("rmse"), "{e}");
    }

    #[test]
    fn first_difference_names_the_key() {
        let a = json!({"bounces": 4, "spp": 64});
        assert_eq!(first_difference(&a, &a), None);
        let b = json!({"bounces": 3, "spp": 64});
        assert_eq!(first_difference(&a, &b), Some(("bounces".into(), "4".into(), "3".into())));
        let c = json!({"bounces": 4});
        assert_eq!(first_difference(&a, &c), Some(("spp".into(), "64".into(), "(absent)".into())));
    }
}
