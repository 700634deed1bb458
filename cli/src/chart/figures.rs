//! The study's four charts (RMSE and relative MSE, each against spp and against time): one
//! series per configuration and per `--external` label, with the notes that explain them.

use super::axes::Config;
use super::data::{self, ExternalPoint, Row, rows_of, slope};
use super::plot::{self, Labels, Marker, Series, Style};
use super::study::{Study, dedup};
use crate::args::{ChartBackend, ChartTime, Switch};
use crate::resume;
use furnace_brdf::SpecularSampling;
use furnace_render::{
    Choice, EnvSampling, LightSampling, LightSelection, PointLightSampling, TriangleSampling,
};
use furnace_sampling::SamplerKind;
use plotters::style::RGBColor;

/// One error metric that is charted.
struct Metric {
    /// In file names (`rmse`).
    key: &'static str,
    /// In titles (`RMSE`).
    name: &'static str,
    row: fn(&Row) -> f64,
    external: fn(&ExternalPoint) -> Option<f64>,
    /// Its slope against spp for independent samples.
    ideal: &'static str,
}

/// Colour per sampler (matplotlib's tab10, grey for random).
fn sampler_color(s: SamplerKind) -> RGBColor {
    match s {
        SamplerKind::Sobol => RGBColor(31, 119, 180),
        SamplerKind::Pmj02 => RGBColor(255, 127, 14),
        SamplerKind::Random => RGBColor(90, 90, 90),
        SamplerKind::Hammersley => RGBColor(44, 160, 44),
        SamplerKind::Cmj => RGBColor(214, 39, 40),
    }
}

/// `c` moved by `t` of the way towards `to`.
fn mix(c: RGBColor, to: RGBColor, t: f64) -> RGBColor {
    let f = |v: u8, w: u8| (f64::from(v) + (f64::from(w) - f64::from(v)) * t).round() as u8;
    RGBColor(f(c.0, to.0), f(c.1, to.1), f(c.2, to.2))
}

/// `c` shaded by light sampling: lighter for bsdf, darker for nee, as is for mis.
fn shade(c: RGBColor, light: LightSampling) -> RGBColor {
    // Towards white by half, towards black by 40%.
    match light {
        LightSampling::Bsdf => mix(c, RGBColor(255, 255, 255), 0.5),
        LightSampling::Nee => mix(c, RGBColor(0, 0, 0), 0.4),
        LightSampling::Mis => c,
    }
}

/// `c` tinted by triangle sampling: towards amber for area, as is for solid-angle (a tint, not
/// a lightness, so that it stays apart from the light-sampling shades, grey included).
fn tint(c: RGBColor, triangle: TriangleSampling) -> RGBColor {
    match triangle {
        TriangleSampling::Area => mix(c, RGBColor(230, 160, 0), 0.45),
        TriangleSampling::SolidAngle => c,
    }
}

/// `c` tinted by light selection: towards violet for power, as is for bvh (a hue of its own,
/// apart from the light-sampling shades and the triangle-sampling amber).
fn tint_selection(c: RGBColor, selection: LightSelection) -> RGBColor {
    match selection {
        LightSelection::Power => mix(c, RGBColor(148, 0, 211), 0.45),
        LightSelection::Bvh => c,
    }
}

/// `c` tinted by environment sampling: towards teal for off, towards crimson for compensated,
/// as is for importance (hues of their own, apart from the other axes' shades and tints).
fn tint_env(c: RGBColor, env: EnvSampling) -> RGBColor {
    match env {
        EnvSampling::Off => mix(c, RGBColor(0, 150, 136), 0.45),
        EnvSampling::Importance => c,
        EnvSampling::Compensated => mix(c, RGBColor(200, 0, 60), 0.45),
    }
}

/// `c` tinted by point-light gathering: towards olive for all, towards navy for one, as is for
/// auto.
fn tint_points(c: RGBColor, points: PointLightSampling) -> RGBColor {
    match points {
        PointLightSampling::Auto => c,
        PointLightSampling::All => mix(c, RGBColor(128, 128, 0), 0.45),
        PointLightSampling::One => mix(c, RGBColor(0, 0, 128), 0.45),
    }
}

fn fmt_slope(k: f64) -> String {
    format!("{k:.2}").replace('-', "−")
}

/// How many samplers, sampling methods, light samplings, triangle samplings, light selections,
/// compensation states and backends the study has: a legend entry names only what varies.
struct Varying {
    samplers: usize,
    sampling: usize,
    light_sampling: usize,
    triangle_sampling: usize,
    light_selection: usize,
    env_sampling: usize,
    point_lights: usize,
    compensations: usize,
    backends: usize,
    thresholds: usize,
    denoise: usize,
}

impl Varying {
    fn of(study: &Study) -> Self {
        Self {
            samplers: dedup(&study.args.samplers).len(),
            sampling: dedup(&study.args.sampling).len(),
            light_sampling: dedup(&study.args.light_sampling).len(),
            triangle_sampling: dedup(&study.args.triangle_sampling).len(),
            light_selection: dedup(&study.args.light_selection).len(),
            env_sampling: dedup(&study.args.env_sampling).len(),
            point_lights: dedup(&study.args.point_lights).len(),
            compensations: study.compensations().len(),
            backends: dedup(&study.args.backends).len(),
            thresholds: dedup(&study.args.noise_threshold).len(),
            denoise: dedup(&study.args.denoise).len(),
        }
    }

    /// The legend text of configuration `c`.
    fn label(&self, c: &Config) -> String {
        let vary = |n: usize| n > 1;
        let s = &c.settings;
        let mut parts = vec![s.sampler.to_string()];
        if vary(self.sampling) {
            parts.push(Choice::name(s.specular.sampling).to_string());
        }
        if vary(self.light_sampling) {
            parts.push(Choice::name(s.light_sampling).to_string());
        }
        if vary(self.triangle_sampling) {
            parts.push(Choice::name(s.triangle_sampling).to_string());
        }
        if vary(self.light_selection) {
            parts.push(Choice::name(s.light_selection).to_string());
        }
        if vary(self.env_sampling) {
            parts.push(format!("env {}", Choice::name(s.env_sampling)));
        }
        if vary(self.point_lights) {
            parts.push(format!("points {}", Choice::name(s.point_lights)));
        }
        if vary(self.compensations) {
            parts.push(format!("comp {}", resume::cli_name(&c.compensation())));
        }
        if vary(self.backends) || c.backend == ChartBackend::Gpu {
            parts.push(resume::cli_name(&c.backend));
        }
        if let Some(t) = s.adaptive.map(|a| a.threshold) {
            parts.push(format!("adaptive {t}"));
        } else if vary(self.thresholds) {
            parts.push("all pixels".into());
        }
        if c.denoise == Switch::On {
            parts.push("denoised".into());
        } else if vary(self.denoise) {
            parts.push("raw".into());
        }
        if vary(self.samplers) || parts.len() > 1 { parts.join(" ") } else { c.name() }
    }
}

/// Draws the four charts into the study's directory.
pub(super) fn save_charts(study: &Study, rows: &[Row], external: &[ExternalPoint]) -> Result<(), String> {
    let varying = Varying::of(study);
    let metrics = [
        Metric { key: "rmse", name: "RMSE", row: |r| r.rmse, external: |p| p.rmse, ideal: "−0.5" },
        Metric {
            key: "relmse",
            name: "relative MSE",
            row: |r| r.relmse,
            external: |p| p.relmse,
            ideal: "−1",
        },
    ];
    for metric in &metrics {
        for by_time in [false, true] {
            let mut series = config_series(study, rows, &varying, metric, by_time);
            series.extend(external_series(external, metric, by_time));
            let (labels, file_x) = labels(study, &varying, metric, by_time);
            plot::write_chart(&study.args.out.join(format!("{}_vs_{file_x}", metric.key)), &labels, &series)?;
        }
    }
    Ok(())
}

/// One series per configuration with rows: colour by sampler (shaded by light sampling, tinted by
/// triangle sampling, by light selection and by environment sampling, each when it varies), marker by sampling method,
/// dashed with compensation, hollow on the GPU.
fn config_series(
    study: &Study,
    rows: &[Row],
    varying: &Varying,
    metric: &Metric,
    by_time: bool,
) -> Vec<Series> {
    let time_of = |r: &Row| match study.args.time {
        ChartTime::Wall => r.seconds,
        ChartTime::Cpu => r.cpu_seconds,
    };
    let mut series = Vec::new();
    for c in &study.configs {
        let mine = rows_of(rows, &c.name());
        if mine.is_empty() {
            continue;
        }
        let matches = study.reference_for(c).1;
        let mut text = varying.label(c);
        if !by_time && let Some(k) = slope(&mine, metric.row) {
            text.push_str(&format!("  slope {}", fmt_slope(k)));
        }
        if !matches {
            text.push_str("  (≠ ref model)");
        }
        let points = mine
            .iter()
            .map(|r| (if by_time { time_of(r) } else { f64::from(r.spp) }, (metric.row)(r)))
            .collect();
        let s = &c.settings;
        let mut color = sampler_color(s.sampler);
        if varying.light_sampling > 1 {
            color = shade(color, s.light_sampling);
        }
        if varying.triangle_sampling > 1 {
            color = tint(color, s.triangle_sampling);
        }
        if varying.light_selection > 1 {
            color = tint_selection(color, s.light_selection);
        }
        if varying.env_sampling > 1 {
            color = tint_env(color, s.env_sampling);
        }
        if varying.point_lights > 1 {
            color = tint_points(color, s.point_lights);
        }
        if let Some(adaptive) = s.adaptive {
            // Adaptive configurations: mixed with a colour of their own per threshold.
            let k = dedup(&study.args.noise_threshold)
                .iter()
                .filter(|t| t.value().is_some())
                .position(|t| t.value() == Some(adaptive.threshold));
            let own = [(44, 160, 44), (255, 127, 14), (148, 103, 189), (140, 86, 75)][k.unwrap_or(0) % 4];
            let mix = |a: u8, b: u8| ((u16::from(a) + 3 * u16::from(b)) / 4) as u8;
            color = RGBColor(mix(color.0, own.0), mix(color.1, own.1), mix(color.2, own.2));
        }
        let style = Style {
            color,
            marker: match s.specular.sampling {
                SpecularSampling::SphericalCaps => Marker::Circle,
                SpecularSampling::Vndf => Marker::Triangle,
                SpecularSampling::Ndf => Marker::Square,
            },
            dashed: s.specular.compensation || c.denoise == Switch::On,
            hollow: c.backend == ChartBackend::Gpu,
        };
        series.push(Series { label: text, points, style });
    }
    series
}

/// One series per `--external` label, in first-seen order, with the points that have the
/// axis values.
fn external_series(external: &[ExternalPoint], metric: &Metric, by_time: bool) -> Vec<Series> {
    let mut ext_labels: Vec<&str> = Vec::new();
    for p in external {
        if !ext_labels.contains(&p.label.as_str()) {
            ext_labels.push(&p.label);
        }
    }
    let ext_colors = [(148, 103, 189), (140, 86, 75), (227, 119, 194), (188, 189, 34), (23, 190, 207)];
    let mut series = Vec::new();
    for (k, name) in ext_labels.iter().enumerate() {
        let pts: Vec<&ExternalPoint> = external.iter().filter(|p| p.label == *name).collect();
        let points: Vec<(f64, f64)> = pts
            .iter()
            .filter_map(|p| Some((if by_time { p.seconds? } else { p.spp? }, (metric.external)(p)?)))
            .collect();
        let mut text = format!("{name} (external)");
        if !by_time && let Some(k) = data::log_log_slope(points.iter().copied()) {
            text.push_str(&format!("  slope {}", fmt_slope(k)));
        }
        let (r, g, b) = ext_colors[k % ext_colors.len()];
        let style = Style { color: RGBColor(r, g, b), marker: Marker::Cross, dashed: false, hollow: false };
        series.push(Series { label: text, points, style });
    }
    series
}

/// The chart's titles and note, and the x part of its file name (`spp` or `time`).
fn labels(study: &Study, varying: &Varying, metric: &Metric, by_time: bool) -> (Labels, &'static str) {
    let s = &study.settings;
    // The scene's file name: its full path belongs in chart.json, not in a title.
    let scene = std::path::Path::new(&study.scene_name)
        .file_name()
        .map_or_else(|| study.scene_name.clone(), |n| n.to_string_lossy().into_owned());
    let what = format!("{scene} {}×{}, {} bounces", s.width, s.height, s.bounces);
    let (x, file_x) = match (by_time, study.args.time) {
        (false, _) => ("samples per pixel", "spp"),
        (true, ChartTime::Wall) => ("seconds (wall time of the render passes)", "time"),
        (true, ChartTime::Cpu) => ("CPU seconds of the render passes (all threads)", "time"),
    };
    let labels = Labels {
        title: format!("{what}: {} vs {}", metric.name, if by_time { "time" } else { "samples per pixel" }),
        x: x.to_string(),
        y: format!("{} against the reference", metric.name),
        note: note(study, varying, metric, by_time),
        x_powers_of_two: !by_time,
    };
    (labels, file_x)
}

/// The line under the legend: what the axis or the slopes are, the references, and what the
/// markers and line styles mean.
fn note(study: &Study, varying: &Varying, metric: &Metric, by_time: bool) -> String {
    let mut note = if by_time {
        format!(
            "Time: {} of the render passes only (no setup, BVH build, read-back or metrics). Fixed-N \
             samplers: one render per checkpoint.",
            match study.args.time {
                ChartTime::Wall => "wall time",
                ChartTime::Cpu => "process CPU time (user + system, all threads)",
            }
        )
    } else {
        format!(
            "Slope: least squares of log error vs log spp over the checkpoints ({} for independent \
             samples).",
            metric.ideal
        )
    };
    note.push_str(&format!(" Reference: {}.", study.reference.name()));
    if let Some(rc) = &study.compensated {
        note.push_str(&format!(" Compensation on: {}.", rc.name()));
    }
    if varying.sampling > 1 {
        note.push_str(" Markers: caps ●, vndf ▲, ndf ■.");
    }
    if varying.light_sampling > 1 {
        note.push_str(
            " Light sampling: bsdf (BSDF rays only, lighter), nee (light samples only, darker), mis (both, \
             power heuristic).",
        );
    }
    if varying.triangle_sampling > 1 {
        note.push_str(
            " Triangle sampling: solid-angle (light samples uniform in the solid angle), area (uniform on \
             the triangle's area, tinted amber).",
        );
    }
    if varying.light_selection > 1 {
        note.push_str(
            " Light selection: bvh (the emissive triangle chosen by a light BVH's importance at the \
             shading point), power (in proportion to power, tinted violet).",
        );
    }
    if varying.env_sampling > 1 {
        note.push_str(
            " Environment sampling: importance (light samples by the map's luminance), off (BSDF rays \
             only, tinted teal), compensated (MIS compensation, tinted crimson).",
        );
    }
    if varying.point_lights > 1 {
        note.push_str(
            " Point lights: auto (all up to 4 lights, one beyond), all (a shadow ray to each, tinted olive), \
             one (one chosen by power per event, tinted navy).",
        );
    }
    if study.configs.iter().any(|c| c.settings.specular.compensation) {
        note.push_str(" Dashed: compensation on.");
    }
    if study.configs.iter().any(|c| c.backend == ChartBackend::Gpu) {
        note.push_str(" Hollow markers: GPU.");
    }
    if study.configs.iter().any(|c| !study.reference_for(c).1) {
        note.push_str(" ≠ ref model: rendered with another BRDF model than the reference (biased).");
    }
    if metric.key == "relmse" {
        note.push_str(" relMSE = mean (x−r)²/(r²+0.01).");
    }
    note
}
