//! The charts: log-log line charts drawn with `plotters` into a PNG (encoded by furnace-post,
//! written atomically) and an SVG, with the legend in a panel of its own to the right of the
//! plot so that it never hides a curve.
//!
//! Text is drawn with `ab_glyph` from DejaVu Sans (`cli/assets/fonts/`, compiled in), so no system
//! font library is needed. The SVG names the font family `sans-serif` and leaves the glyphs to
//! the viewer.

use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// The font the charts are drawn with (DejaVu Sans 2.37; licence in cli/assets/fonts/).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Chart size in pixels (PNG) and user units (SVG).
pub const SIZE: (u32, u32) = (1200, 720);
/// Width of the legend panel.
const LEGEND_WIDTH: u32 = 380;

/// A marker shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// A circle.
    Circle,
    /// An upward triangle.
    Triangle,
    /// A square.
    Square,
    /// A diagonal cross.
    Cross,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    /// Line and marker colour.
    pub color: RGBColor,
    /// Marker shape at each point.
    pub marker: Marker,
    /// A dashed line (instead of solid).
    pub dashed: bool,
    /// Hollow markers (instead of filled).
    pub hollow: bool,
}

/// One curve: its legend text, its points (x, y; both > 0) and its style.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// The points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// How it is drawn.
    pub style: Style,
}

/// A chart's titles.
#[derive(Debug, Clone)]
pub struct Labels {
    /// Above the plot.
    pub title: String,
    /// Under the x axis.
    pub x: String,
    /// Beside the y axis.
    pub y: String,
    /// A line under the legend (e.g. what the slopes are).
    pub note: String,
    /// Label the x axis at powers of two (samples per pixel) instead of 1-2-5 steps.
    pub x_powers_of_two: bool,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in and known to parse (the unit test draws with it).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Writes `base.png` and `base.svg`, each atomically. Series without usable points are
/// listed in the legend but draw nothing.
pub fn write_chart(base: &Path, labels: &Labels, series: &[Series]) -> Result<(), String> {
    register_font();
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, labels, series)?;
        root.present().map_err(|e| format!("drawing the chart: {e}"))?;
    }
    let pixels: Vec<[u8; 3]> = rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    furnace_post::write_png(base.with_extension("png"), w, h, &pixels).map_err(|e| e.to_string())?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root, labels, series)?;
        root.present().map_err(|e| format!("drawing the chart: {e}"))?;
    }
    crate::shared::write_atomically(&base.with_extension("svg"), svg.as_bytes())
}

/// The range of the positive finite values of `v`, widened to whole decades-ish margins on
/// a log axis; `(0.1, 10)` when there are none.
fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), x| (lo.min(x), hi.max(x)));
    if !(lo <= hi) {
        return (0.1, 10.0);
    }
    // 8% of the span in log space on each side (at least a factor 1.25 overall).
    let span = (hi / lo).ln().max(0.2);
    let pad = (0.08 * span).exp();
    (lo / pad, hi * pad)
}

/// 1, 2, 5 × 10^k in `[lo, hi]`; 1…9 × 10^k when that gives fewer than four.
fn steps_125(lo: f64, hi: f64) -> Vec<f64> {
    let v = decade_multiples(lo, hi, &[1.0, 2.0, 5.0]);
    if v.len() >= 4 { v } else { decade_steps(lo, hi) }
}

/// 1…9 × 10^k in `[lo, hi]` (the light grid of a log axis).
fn decade_steps(lo: f64, hi: f64) -> Vec<f64> {
    decade_multiples(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

fn decade_multiples(lo: f64, hi: f64, m: &[f64]) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (k0..=k1)
        .flat_map(|k| m.iter().map(move |&m| m * 10f64.powi(k)))
        .filter(|&v| v >= lo && v <= hi)
        .collect()
}

/// 2^k in `[lo, hi]`, every other one when there are more than 12.
fn powers_of_two(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return Vec::new();
    }
    let v: Vec<f64> = (lo.log2().floor() as i32..=hi.log2().ceil() as i32)
        .map(|k| 2f64.powi(k))
        .filter(|&v| v >= lo && v <= hi)
        .collect();
    if v.len() > 12 { v.into_iter().step_by(2).collect() } else { v }
}

/// A tick label: plain decimals with up to four significant digits from 0.001 to 99 999,
/// else `1e-4`-style.
pub fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (0.001..100_000.0).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
        return s.to_string();
    }
    let e = a.log10().floor() as i32;
    let m = v / 10f64.powi(e);
    if (m.round() - m).abs() < 1e-6 { format!("{}e{e}", m.round()) } else { format!("{m:.1}e{e}") }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    labels: &Labels,
    series: &[Series],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("drawing the chart: {e}");
    root.fill(&WHITE).map_err(err)?;
    let (plot_area, legend_area) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
    let (x0, x1) = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let (y0, y1) = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(&labels.title, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (x0..x1)
                .log_scale()
                .with_key_points(if labels.x_powers_of_two {
                    powers_of_two(x0, x1)
                } else {
                    steps_125(x0, x1)
                })
                .with_light_points(decade_steps(x0, x1)),
            (y0..y1).log_scale().with_key_points(steps_125(y0, y1)).with_light_points(decade_steps(y0, y1)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&labels.x)
        .y_desc(&labels.y)
        .axis_desc_style(("sans-serif", 17))
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(err)?;
    for s in series {
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|&(x, y)| x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())
            .collect();
        let line = s.style.color.stroke_width(2);
        if s.style.dashed {
            chart.draw_series(DashedLineSeries::new(pts.clone(), 9, 6, line)).map_err(err)?;
        } else {
            chart.draw_series(LineSeries::new(pts.clone(), line)).map_err(err)?;
        }
        for &p in &pts {
            draw_marker(chart.plotting_area(), p, s.style, 5).map_err(err)?;
        }
    }

    // The legend: a line segment with its marker, then the label, one entry per row.
    let legend = legend_area.margin(50, 10, 8, 10);
    // Rows shrink so that the entries and the note below them fit the height (the note was
    // drawn past the bottom, its lines piled on each other, with 30 series).
    let note_lines = wrap(&labels.note, 46);
    let room = SIZE.1 as i32 - 58 - 14 - 17 * note_lines.len() as i32;
    let row = 22i32.min((room / series.len().max(1) as i32).max(10));
    let font = ("sans-serif", if row >= 18 { 14 } else { 11 }).into_font();
    for (i, s) in series.iter().enumerate() {
        let y = i as i32 * row + row / 2;
        let stroke = s.style.color.stroke_width(2);
        if s.style.dashed {
            for k in 0..3 {
                let a = k * 12;
                legend.draw(&PathElement::new(vec![(a, y), (a + 7, y)], stroke)).map_err(err)?;
            }
        } else {
            legend.draw(&PathElement::new(vec![(0, y), (32, y)], stroke)).map_err(err)?;
        }
        draw_marker(&legend, (16, y), s.style, 5).map_err(err)?;
        legend.draw(&Text::new(s.label.clone(), (42, y - 7), font.clone())).map_err(err)?;
    }
    let note_y = series.len() as i32 * row + 14;
    let note_font = ("sans-serif", 13).into_font().color(&RGBColor(90, 90, 90));
    for (k, line) in note_lines.iter().enumerate() {
        legend.draw(&Text::new(line.clone(), (0, note_y + 17 * k as i32), note_font.clone())).map_err(err)?;
    }
    Ok(())
}

/// `text` broken into lines of at most `width` characters at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 1 + word.chars().count() <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Draws a marker of `style` centred on `p` (in `area`'s coordinates).
fn draw_marker<DB: DrawingBackend, CT: CoordTranslate>(
    area: &DrawingArea<DB, CT>,
    p: CT::From,
    style: Style,
    size: i32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    CT::From: Clone + 'static,
{
    let shape = if style.hollow { style.color.stroke_width(2) } else { style.color.filled() };
    match style.marker {
        Marker::Circle => area.draw(&Circle::new(p, size, shape)),
        Marker::Triangle => area.draw(&TriangleMarker::new(p, size + 1, shape)),
        Marker::Square => {
            let s = size - 1;
            area.draw(&(EmptyElement::at(p) + Rectangle::new([(-s, -s), (s, s)], shape)))
        }
        Marker::Cross => area.draw(&Cross::new(p, size, style.color.stroke_width(2))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(1.0), "1");
        assert_eq!(tick(64.0), "64");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(0.001), "0.001");
        assert_eq!(tick(0.0025), "0.0025");
        assert_eq!(tick(0.005), "0.005");
        assert_eq!(tick(100.0), "100");
        assert_eq!(tick(0.0005), "5e-4");
        assert_eq!(tick(0.00025), "2.5e-4");
        assert_eq!(tick(1e6), "1e6");
    }

    #[test]
    fn log_range_pads_and_handles_empty() {
        assert_eq!(log_range([].into_iter()), (0.1, 10.0));
        let (lo, hi) = log_range([1.0, 100.0, -1.0, f64::NAN].into_iter());
        assert!(lo < 1.0 && lo > 0.5 && hi > 100.0 && hi < 200.0, "{lo} {hi}");
        let (lo, hi) = log_range([2.0].into_iter());
        assert!(lo < 2.0 && hi > 2.0);
    }

    #[test]
    fn tick_positions() {
        assert_eq!(steps_125(0.03, 0.6), vec![0.05, 0.1, 0.2, 0.5]);
        assert_eq!(steps_125(0.11, 0.35), vec![0.2, 0.30000000000000004]);
        assert_eq!(powers_of_two(0.8, 70.0), vec![1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]);
        assert_eq!(powers_of_two(1.0, 1e5).len(), 9, "17 powers thinned to 9");
    }

    #[test]
    fn wrap_breaks_at_spaces() {
        assert_eq!(wrap("aa bb cc", 5), vec!["aa bb", "cc"]);
        assert!(wrap("", 5).is_empty());
    }
}
