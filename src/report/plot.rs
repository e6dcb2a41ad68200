//! PNG plots of calibration results: measured against predicted creep curves, residuals,
//! the multistart "waterfall" of objectives and the spread of the best constants within
//! their bounds.
//!
//! Every plot is 1200×700 px and is drawn with the DejaVu Sans font embedded in the binary
//! (registered with plotters' `ab_glyph` support), so no system fonts are needed. The chart
//! takes the left part of the image and its legend a panel of its own on the right
//! ([`LEGEND_WIDTH`]), so a legend never covers data. Every axis is labelled by
//! [`axis_ticks`]: at least two labelled ticks for any finite range, on linear and log axes
//! alike (a log axis spanning less than a decade gets intermediate or linear ticks instead of
//! none).
//!
//! Robustness: non-finite points (and points with a magnitude above 1e150) are skipped,
//! lines are broken at them and clipped to the axes, degenerate ranges (one point, all
//! equal values) are widened, empty inputs give an axes-only plot saying "no data", and
//! log axes clamp non-positive values to a floor. Any drawing or encoding failure, and any
//! panic inside plotters, is returned as [`Error::Plot`]; nothing is written unless the
//! whole image was drawn.

use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

use crate::error::{Error, Result};
use crate::output;

/// Image width in pixels.
pub const WIDTH: u32 = 1200;
/// Image height in pixels.
pub const HEIGHT: u32 = 700;
/// Width of the legend panel at the right of every image, px.
pub const LEGEND_WIDTH: u32 = 250;

/// The embedded font (DejaVu Sans, see `assets/DejaVu-LICENSE.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// The family name under which the embedded font is registered and used.
const FONT: &str = "sans-serif";

const TITLE_SIZE: f64 = 28.0;
const AXIS_DESC_SIZE: f64 = 22.0;
const TICK_SIZE: f64 = 17.0;
const LEGEND_SIZE: f64 = 17.0;
/// At most this many labelled ticks on a linear or log axis.
const MAX_TICKS: usize = 10;

/// Coordinates with a larger magnitude are treated like non-finite ones (skipped).
const MAX_ABS: f64 = 1e150;
/// Smallest value shown on a log axis.
const LOG_MIN: f64 = 1e-150;
/// Most decades a log axis spans (from the largest value down); smaller values sit at the floor.
const MAX_LOG_DECADES: f64 = 40.0;
/// Predicted creep curves are shown up to this multiple of the measured extent.
const PREDICTED_EXTENT: f64 = 1.5;

/// Tableau 10 palette, cycled.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A labelled set of (x, y) points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// One stress level for [`plot_creep_curves`]: measured points (drawn as markers) and the
/// predicted curve (drawn as a line) in the same colour.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CurvePlot {
    /// Legend label, e.g. "100 MPa".
    pub label: String,
    /// Measured (time h, strain %).
    pub measured: Vec<(f64, f64)>,
    /// Predicted (time h, strain %), dense enough to look smooth.
    pub predicted: Vec<(f64, f64)>,
}

/// Scale of a plot axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisScale {
    Linear,
    Log,
}

/// Tick positions and labels for an axis over `[lo, hi]`: between 2 and `max` ticks (max ≥ 5)
/// inside the range for any finite range with lo < hi (lo > 0 on a log axis), every label
/// distinct and with the digits its spacing needs. Linear: multiples of 1, 2 or 5 × 10^k.
/// Log: powers of ten when at least three fall inside (every 2nd, 5th … when too many); else
/// 1, 2, 5 × 10^k or 1…9 × 10^k when at least three fall inside; else linear ticks (a range
/// within one decade, such as 0.24–0.40, gets 0.24, 0.26, …, 0.40). A degenerate or
/// non-finite range gives no ticks.
pub fn axis_ticks(lo: f64, hi: f64, scale: AxisScale, max: usize) -> Vec<(f64, String)> {
    let max = max.max(5);
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Vec::new();
    }
    match scale {
        AxisScale::Linear => {
            let (values, step) = linear_ticks(lo, hi, max);
            let labels = linear_labels(&values, step);
            values.into_iter().zip(labels).collect()
        }
        AxisScale::Log => {
            if !(lo > 0.0) {
                return Vec::new();
            }
            let values = log_ticks(lo, hi, max);
            match values {
                Some(v) => v.iter().map(|&x| (x, log_label(x))).collect(),
                None => {
                    let (values, step) = linear_ticks(lo, hi, max);
                    let labels = linear_labels(&values, step);
                    values.into_iter().zip(labels).collect()
                }
            }
        }
    }
}

/// The multiples of the smallest 1-2-5 step that gives at most `max` of them in `[lo, hi]`,
/// and that step.
fn linear_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, f64) {
    let span = hi - lo;
    let count = |step: f64| -> f64 {
        ((hi / step + 1e-9).floor() - (lo / step - 1e-9).ceil() + 1.0).max(0.0)
    };
    // From a step at least the span (≤ 2 ticks) downwards, while the count stays ≤ max.
    let mut exp = span.log10().ceil() as i32;
    let mut best = 10f64.powi(exp);
    'down: loop {
        for m in [5.0, 2.0, 1.0] {
            let step = m * 10f64.powi(exp - 1);
            if !(step > 0.0) || count(step) > max as f64 {
                break 'down;
            }
            best = step;
        }
        exp -= 1;
        if exp < -330 {
            break;
        }
    }
    let first = (lo / best - 1e-9).ceil();
    let last = (hi / best + 1e-9).floor();
    let values = (0..=(last - first).max(0.0) as usize)
        .map(|k| ((first + k as f64) * best).clamp(lo, hi))
        .collect();
    (values, best)
}

/// Labels of linear ticks: one number of decimals for all, the fewest that state each tick to
/// 1e-6 of the step; scientific notation for magnitudes ≥ 1e5 or steps < 1e-4.
fn linear_labels(values: &[f64], step: f64) -> Vec<String> {
    let tol = 1e-6 * step;
    let big = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let clean = |v: f64| if v.abs() < tol { 0.0 } else { v };
    if big >= 1e5 || step < 1e-4 {
        return values
            .iter()
            .map(|&v| shortest_sci(clean(v), tol))
            .collect();
    }
    let decimals = (0..=12)
        .find(|&d| {
            values
                .iter()
                .all(|&v| (format!("{:.*}", d, clean(v)).parse::<f64>().unwrap() - v).abs() <= tol)
        })
        .unwrap_or(12);
    values
        .iter()
        .map(|&v| format!("{:.*}", decimals, clean(v)))
        .collect()
}

/// The shortest scientific form of `v` within `tol` ("0" for zero).
fn shortest_sci(v: f64, tol: f64) -> String {
    if v == 0.0 {
        return "0".to_string();
    }
    (0..=15)
        .map(|d| format!("{:.*e}", d, v))
        .find(|s| (s.parse::<f64>().unwrap() - v).abs() <= tol)
        .unwrap_or_else(|| format!("{v:e}"))
}

/// Ticks of a log axis over `[lo, hi]` (lo > 0) from powers of ten or their 1-2-5 / 1…9
/// multiples; `None` when fewer than three of them fall inside (use linear ticks).
fn log_ticks(lo: f64, hi: f64, max: usize) -> Option<Vec<f64>> {
    let (a, b) = (lo.log10(), hi.log10());
    let inside = |v: f64| v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12);
    let (k0, k1) = ((a - 1e-9).ceil() as i64, (b + 1e-9).floor() as i64);
    let decades = k1 - k0 + 1;
    if decades >= 3 {
        let every = [1i64, 2, 5, 10, 20, 50, 100]
            .into_iter()
            .find(|d| (decades + d - 1) / d <= max as i64)
            .unwrap_or(100);
        let start = k0.div_euclid(every) * every;
        let v: Vec<f64> = (0..)
            .map(|i| start + i * every)
            .take_while(|k| *k <= k1)
            .filter(|k| *k >= k0)
            .map(|k| 10f64.powi(k as i32))
            .collect();
        if v.len() >= 2 {
            return Some(v);
        }
    }
    for mantissas in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
    ] {
        let v: Vec<f64> = ((a.floor() as i64)..=(b.ceil() as i64))
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k as i32)))
            .filter(|v| inside(*v))
            .collect();
        if v.len() >= 3 && v.len() <= max {
            return Some(v);
        }
    }
    None
}

/// Label of a log tick (a power of ten or a small multiple of one): plain for 1e-3 ≤ v < 1e5,
/// else scientific.
fn log_label(v: f64) -> String {
    let tol = 1e-9 * v;
    if (1e-3..1e5).contains(&v) {
        (0..=6)
            .map(|d| format!("{:.*}", d, v))
            .find(|s| (s.parse::<f64>().unwrap() - v).abs() <= tol)
            .unwrap_or_else(|| format!("{v}"))
    } else {
        shortest_sci(v, tol)
    }
}

/// A labelled tick set for one axis.
#[derive(Debug, Clone, Default, PartialEq)]
struct Ticks {
    values: Vec<f64>,
    labels: Vec<String>,
}

impl Ticks {
    fn of(pairs: Vec<(f64, String)>) -> Ticks {
        let (values, labels) = pairs.into_iter().unzip();
        Ticks { values, labels }
    }
    fn auto((lo, hi): (f64, f64), scale: AxisScale) -> Ticks {
        Ticks::of(axis_ticks(lo, hi, scale, MAX_TICKS))
    }
    /// The label of the tick at `v`.
    fn label(&self, v: f64) -> String {
        self.values
            .iter()
            .position(|t| (t - v).abs() <= 1e-9 * t.abs().max(1e-300))
            .map(|i| self.labels[i].clone())
            .unwrap_or_else(|| format!("{v}"))
    }
}

/// A pixel rectangle of the image: (x0, x1), (y0, y1).
type PxRect = ((i32, i32), (i32, i32));

/// What a plot drew, for tests: the tick labels plotters formatted on each axis, and the pixel
/// rectangles (x range, y range) of the chart's plotting area and of the legend box.
#[derive(Debug, Clone, Default, PartialEq)]
struct Drawn {
    x_labels: Vec<String>,
    y_labels: Vec<String>,
    plot_px: PxRect,
    legend_px: Option<PxRect>,
}

/// The legend symbol of an entry.
#[derive(Clone, Copy)]
enum Glyph {
    /// A line segment.
    Line(ShapeStyle),
    /// A filled circle of the given radius.
    Marker(RGBColor, i32),
    /// A line segment with a filled circle on it.
    LineMarker(ShapeStyle, RGBColor, i32),
    /// A filled triangle.
    Triangle(RGBColor),
    /// Two circles: a colour range.
    Pair(RGBColor, RGBColor),
    /// No symbol: a note.
    Note,
}

/// One legend entry.
struct Key {
    label: String,
    glyph: Glyph,
}

fn key(label: impl Into<String>, glyph: Glyph) -> Key {
    Key {
        label: label.into(),
        glyph,
    }
}

/// Measured (markers) against predicted (lines) creep curves, one colour per stress: the
/// paper's Figures 6/7. Axes: "time (h)" and "strain (%)", both starting at 0 unless data are
/// negative. The axes cover every measured point; predicted curves are drawn up to 1.5× the
/// measured extent on each axis and clipped beyond, so a runaway prediction near rupture
/// cannot squash the data (without measured points the predictions set the axes).
pub fn plot_creep_curves(path: &Path, title: &str, curves: &[CurvePlot]) -> Result<()> {
    creep_curves(path, title, curves).map(|_| ())
}

fn creep_curves(path: &Path, title: &str, curves: &[CurvePlot]) -> Result<Drawn> {
    let measured_x = curves.iter().flat_map(|c| c.measured.iter().map(|p| p.0));
    let measured_y = curves.iter().flat_map(|c| c.measured.iter().map(|p| p.1));
    let predicted_x = curves.iter().flat_map(|c| c.predicted.iter().map(|p| p.0));
    let predicted_y = curves.iter().flat_map(|c| c.predicted.iter().map(|p| p.1));
    let x_range = creep_axis(data_range(measured_x), data_range(predicted_x));
    let y_range = creep_axis(data_range(measured_y), data_range(predicted_y));
    let has_data = curves
        .iter()
        .any(|c| c.measured.iter().chain(&c.predicted).any(|&p| plottable(p)));
    let (xt, yt) = (
        Ticks::auto(x_range, AxisScale::Linear),
        Ticks::auto(y_range, AxisScale::Linear),
    );

    let mut keys = Vec::new();
    render(path, title, |area, drawn| {
        let mut chart = linear_chart(area, (x_range, &xt), (y_range, &yt))?;
        configure_mesh(&mut chart, "time (h)", "strain (%)", &xt, &yt, drawn)?;

        for (i, curve) in curves.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let label = if curve.label.trim().is_empty() {
                format!("curve {}", i + 1)
            } else {
                curve.label.clone()
            };
            let pieces = clip_polyline(&curve.predicted, x_range, y_range);
            chart.draw_series(
                pieces
                    .into_iter()
                    .map(|piece| PathElement::new(piece, color.stroke_width(2))),
            )?;
            chart.draw_series(
                inside(&curve.measured, x_range, y_range)
                    .map(|p| Circle::new(p, 4, color.filled())),
            )?;
            keys.push(key(
                label,
                Glyph::LineMarker(color.stroke_width(2), color, 4),
            ));
        }
        if !curves.is_empty() {
            // Style key: markers are measurements, lines are predictions.
            keys.push(key("measured", Glyph::Marker(BLACK, 4)));
            keys.push(key("predicted", Glyph::Line(BLACK.stroke_width(2))));
        }
        if !has_data {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(std::mem::take(&mut keys))
    })
}

/// Residuals against `x` (typically the life fraction t/t_f), one colour per series: markers
/// joined by a thin line in x order, plus a black zero line. The y axis always includes 0.
/// The residuals are predicted − measured (the sign of the objective's residual vector and of
/// the biases in diagnose's report.md), normalised by the caller, whose `y_label` states it.
pub fn plot_residuals(
    path: &Path,
    title: &str,
    series: &[Series],
    x_label: &str,
    y_label: &str,
) -> Result<()> {
    residuals(path, title, series, x_label, y_label).map(|_| ())
}

fn residuals(
    path: &Path,
    title: &str,
    series: &[Series],
    x_label: &str,
    y_label: &str,
) -> Result<Drawn> {
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let x_range = padded(data_range(xs).unwrap_or((0.0, 1.0)), 0.03);
    let y_range = padded(data_range(ys.chain([0.0])).unwrap_or((-1.0, 1.0)), 0.05);
    let has_data = series
        .iter()
        .any(|s| s.points.iter().any(|&p| plottable(p)));
    let (xt, yt) = (
        Ticks::auto(x_range, AxisScale::Linear),
        Ticks::auto(y_range, AxisScale::Linear),
    );

    render(path, title, |area, drawn| {
        let mut chart = linear_chart(area, (x_range, &xt), (y_range, &yt))?;
        configure_mesh(&mut chart, x_label, y_label, &xt, &yt, drawn)?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x_range.0, 0.0), (x_range.1, 0.0)],
            BLACK.stroke_width(1),
        )))?;

        let mut keys = Vec::new();
        for (i, s) in series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let label = if s.label.trim().is_empty() {
                format!("series {}", i + 1)
            } else {
                s.label.clone()
            };
            let mut sorted: Vec<(f64, f64)> =
                s.points.iter().copied().filter(|&p| plottable(p)).collect();
            sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
            let line_style = color.mix(0.45).stroke_width(1);
            chart.draw_series(
                clip_polyline(&sorted, x_range, y_range)
                    .into_iter()
                    .map(|piece| PathElement::new(piece, line_style)),
            )?;
            chart.draw_series(
                inside(&sorted, x_range, y_range).map(|p| Circle::new(p, 4, color.filled())),
            )?;
            keys.push(key(label, Glyph::LineMarker(line_style, color, 4)));
        }
        if !has_data {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(keys)
    })
}

/// How many local fits a waterfall shows: `ran` = `finite` + `failed` (no objective).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunCounts {
    pub ran: usize,
    pub finite: usize,
    pub failed: usize,
}

/// Counts of a waterfall's input: every value is one fit; a non-finite one failed.
pub fn run_counts(objectives: &[f64]) -> RunCounts {
    let finite = objectives.iter().filter(|v| v.is_finite()).count();
    RunCounts {
        ran: objectives.len(),
        finite,
        failed: objectives.len() - finite,
    }
}

/// The waterfall's statement of the counts: how many fits ran, how many have a finite
/// objective, how many failed.
fn counts_note(c: RunCounts) -> String {
    let failed = if c.failed > 0 {
        format!("{} failed (no objective, not drawn)", c.failed)
    } else {
        "0 failed".to_string()
    };
    format!("{} fits ran: {} finite, {failed}", c.ran, c.finite)
}

/// Sorted objective against rank (1 = best), log-scale y: the multistart "waterfall".
/// `objectives_sorted` holds one value per local fit, best first, as in ranked.csv: ranks are
/// the 1-based positions (the rank column of ranked.csv), non-finite values are failed fits
/// (counted in the legend, not drawn), non-positive ones are shown at a floor (100× below the
/// smallest positive value) as red triangles; the best point is drawn in red and its value
/// given in the legend.
pub fn plot_waterfall(path: &Path, title: &str, objectives_sorted: &[f64]) -> Result<()> {
    waterfall(path, title, objectives_sorted).map(|_| ())
}

fn waterfall(path: &Path, title: &str, objectives_sorted: &[f64]) -> Result<Drawn> {
    let n = objectives_sorted.len();
    let counts = run_counts(objectives_sorted);
    let min_pos = objectives_sorted
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if min_pos.is_finite() {
        (min_pos / 100.0).clamp(LOG_MIN, MAX_ABS)
    } else {
        1e-12
    };
    // (rank, value shown, clamped?)
    let pts: Vec<(f64, f64, bool)> = objectives_sorted
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .map(|(i, &v)| {
            let rank = (i + 1) as f64;
            if v > 0.0 {
                (rank, v.clamp(LOG_MIN, MAX_ABS), false)
            } else {
                (rank, floor, true)
            }
        })
        .collect();
    let x_range = (0.5, n.max(1) as f64 + 0.5);
    let y_range = log_range(pts.iter().map(|p| p.1));
    let pts: Vec<(f64, f64, bool)> = pts
        .into_iter()
        .map(|(r, v, c)| {
            if v < y_range.0 {
                (r, y_range.0, true)
            } else {
                (r, v, c)
            }
        })
        .collect();
    let line: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
    let n_clamped = pts.iter().filter(|p| p.2).count();
    let xt = Ticks {
        values: integer_ticks(n.max(1), 10),
        labels: integer_ticks(n.max(1), 10)
            .iter()
            .map(|v| format!("{}", v.round() as i64))
            .collect(),
    };
    let yt = Ticks::auto(y_range, AxisScale::Log);

    render(path, title, |area, drawn| {
        let y_axis: LogCoord<f64> = (y_range.0..y_range.1).log_scale().into();
        let mut chart = chart_builder(area).build_cartesian_2d(
            FixedTicks::new(
                RangedCoordf64::from(x_range.0..x_range.1),
                xt.values.clone(),
            ),
            FixedTicks::new(y_axis, yt.values.clone()),
        )?;
        configure_mesh(
            &mut chart,
            "rank (1 = best)",
            "objective (log scale)",
            &xt,
            &yt,
            drawn,
        )?;

        let color = PALETTE[0];
        chart.draw_series(std::iter::once(PathElement::new(
            line.clone(),
            color.stroke_width(2),
        )))?;
        let marker = if n <= 200 { 4 } else { 2 };
        chart.draw_series(
            pts.iter()
                .filter(|p| !p.2)
                .map(|p| Circle::new((p.0, p.1), marker, color.filled())),
        )?;
        let mut keys = vec![key(
            "objective of each fit",
            Glyph::LineMarker(color.stroke_width(2), color, 4),
        )];
        if let Some(best) = pts.first().filter(|p| p.0 == 1.0) {
            chart.draw_series(std::iter::once(Circle::new(
                (best.0, best.1),
                7,
                PALETTE[3].filled(),
            )))?;
            keys.push(key(
                format!("best: {}", significant(objectives_sorted[0], 6)),
                Glyph::Marker(PALETTE[3], 6),
            ));
        }
        if n_clamped > 0 {
            chart.draw_series(
                pts.iter()
                    .filter(|p| p.2)
                    .map(|p| TriangleMarker::new((p.0, p.1), 6, PALETTE[3].filled())),
            )?;
            keys.push(key(
                format!("{n_clamped} value(s) ≤ 0, shown at {floor:.1e}"),
                Glyph::Triangle(PALETTE[3]),
            ));
        }
        keys.push(key(counts_note(counts), Glyph::Note));
        if pts.is_empty() {
            no_data(&mut chart, (mid(x_range), (y_range.0 * y_range.1).sqrt()))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(keys)
    })
}

/// `v` with `digits` significant digits (plain notation for 1e-4 ≤ |v| < 1e6).
fn significant(v: f64, digits: usize) -> String {
    if !v.is_finite() || v == 0.0 {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i64;
    if (-4..6).contains(&mag) {
        let decimals = (digits as i64 - 1 - mag).max(0) as usize;
        format!("{:.*}", decimals, v)
    } else {
        format!("{:.*e}", digits.saturating_sub(1), v)
    }
}

/// Each constant of the best-k solutions within its bounds (a parallel-coordinates plot): one
/// column per constant (x = constant index, labelled with `names`), y = scaled position u
/// (0 = lower bound, 1 = upper bound, dashed). Each solution is a polyline through its
/// columns, fading from dark to light with rank; the best (first) one is thick and red.
/// Values outside [0, 1] are drawn at the edge of the axis (−0.05 or 1.05), non-finite
/// values are skipped. Every solution must have `names.len()` values, otherwise
/// [`Error::Invalid`].
pub fn plot_parameters(
    path: &Path,
    title: &str,
    names: &[String],
    scaled_solutions: &[Vec<f64>],
) -> Result<()> {
    parameters(path, title, names, scaled_solutions).map(|_| ())
}

fn parameters(
    path: &Path,
    title: &str,
    names: &[String],
    scaled_solutions: &[Vec<f64>],
) -> Result<Drawn> {
    let n = names.len();
    if let Some((i, s)) = scaled_solutions
        .iter()
        .enumerate()
        .find(|(_, s)| s.len() != n)
    {
        return Err(Error::Invalid(format!(
            "plot {}: solution {} has {} values for {n} constant names",
            path.display(),
            i + 1,
            s.len()
        )));
    }
    let (lo, hi) = (-0.05, 1.05);
    let x_range = (-0.5, n.max(1) as f64 - 0.5);
    let k = scaled_solutions.len();
    // Rank r (0-based) as a polyline; values clamped into the visible band.
    let polyline = |s: &Vec<f64>| -> Vec<(f64, f64)> {
        s.iter()
            .enumerate()
            .map(|(j, &u)| {
                (
                    j as f64,
                    if u.is_finite() {
                        u.clamp(lo, hi)
                    } else {
                        f64::NAN
                    },
                )
            })
            .collect()
    };
    let xt = Ticks {
        values: (0..n).map(|j| j as f64).collect(),
        labels: names.to_vec(),
    };
    let yt = Ticks::of(
        [0.0, 0.25, 0.5, 0.75, 1.0]
            .iter()
            .map(|&v| (v, format!("{v:.2}")))
            .collect(),
    );

    render(path, title, |area, drawn| {
        let mut chart = linear_chart(area, (x_range, &xt), ((lo, hi), &yt))?;
        configure_mesh(
            &mut chart,
            "constant",
            "scaled position u in bounds",
            &xt,
            &yt,
            drawn,
        )?;
        for (u, text) in [(0.0, "lower bound"), (1.0, "upper bound")] {
            chart.draw_series(DashedLineSeries::new(
                vec![(x_range.0, u), (x_range.1, u)],
                8,
                5,
                BLACK.mix(0.6).stroke_width(1),
            ))?;
            let pos = if u > 0.5 { VPos::Bottom } else { VPos::Top };
            chart.plotting_area().draw(&Text::new(
                text,
                (x_range.1, u),
                TextStyle::from((FONT, 14))
                    .color(&BLACK.mix(0.6))
                    .pos(Pos::new(HPos::Right, pos)),
            ))?;
        }

        let mut keys = Vec::new();
        // Worst first so that better solutions are drawn on top.
        for r in (1..k).rev() {
            let t = if k > 2 {
                (r - 1) as f64 / (k - 2) as f64
            } else {
                0.0
            };
            let color = rank_color(t);
            let pts = polyline(&scaled_solutions[r]);
            chart.draw_series(
                clip_polyline(&pts, x_range, (lo, hi))
                    .into_iter()
                    .map(|piece| PathElement::new(piece, color.stroke_width(1))),
            )?;
            chart.draw_series(
                inside(&pts, x_range, (lo, hi)).map(|p| Circle::new(p, 4, color.filled())),
            )?;
        }
        if let Some(best) = scaled_solutions.first() {
            let red = PALETTE[3];
            let pts = polyline(best);
            chart.draw_series(
                clip_polyline(&pts, x_range, (lo, hi))
                    .into_iter()
                    .map(|piece| PathElement::new(piece, red.stroke_width(3))),
            )?;
            chart.draw_series(
                inside(&pts, x_range, (lo, hi)).map(|p| Circle::new(p, 6, red.filled())),
            )?;
            keys.push(key("best", Glyph::LineMarker(red.stroke_width(3), red, 6)));
        }
        if k > 1 {
            let label = if k > 2 {
                format!("ranks 2–{k} (dark to light)")
            } else {
                "rank 2".to_string()
            };
            keys.push(key(label, Glyph::Pair(rank_color(0.0), rank_color(1.0))));
        }
        if n == 0 || k == 0 {
            no_data(&mut chart, (mid(x_range), 0.5))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(keys)
    })
}

/// One group of an [`plot_xy`] chart: a line and markers in one colour, one legend entry.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct XyGroup {
    /// Legend label.
    pub label: String,
    /// Drawn as a line (in the given order).
    pub line: Vec<(f64, f64)>,
    /// Drawn as markers.
    pub points: Vec<(f64, f64)>,
    /// Dashed line (e.g. a baseline) instead of a solid one.
    pub dashed: bool,
    /// Palette index of the colour (groups of one temperature share one); `None`: black.
    pub color: Option<usize>,
    /// Triangles instead of circles as markers (e.g. asked conditions beside measurements).
    pub triangles: bool,
}

/// Axes of an [`plot_xy`] chart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XyAxes<'a> {
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub x_scale: AxisScale,
    pub y_scale: AxisScale,
}

/// Lines and markers over linear or log axes (a log axis draws log10 of the values and
/// labels its ticks with the values; non-positive values are left out of it), in the colour
/// each group names; the axes cover every plottable value, padded by 5 %. For the stress–rupture
/// and Larson–Miller diagrams of `predict` and the parity plot of `holdout`. Groups with
/// neither line nor points only add their legend entry (a note); an empty label adds none.
pub fn plot_xy(path: &Path, title: &str, axes: XyAxes<'_>, groups: &[XyGroup]) -> Result<()> {
    xy(path, title, axes, groups).map(|_| ())
}

fn xy(path: &Path, title: &str, axes: XyAxes<'_>, groups: &[XyGroup]) -> Result<Drawn> {
    let to = |v: f64, scale: AxisScale| match scale {
        AxisScale::Linear => v,
        AxisScale::Log if v > 0.0 => v.log10(),
        AxisScale::Log => f64::NAN,
    };
    let tr = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
        pts.iter()
            .map(|&(x, y)| (to(x, axes.x_scale), to(y, axes.y_scale)))
            .collect()
    };
    type Points = Vec<(f64, f64)>;
    let groups_t: Vec<(Points, Points)> = groups
        .iter()
        .map(|g| (tr(&g.line), tr(&g.points)))
        .collect();
    let all = || groups_t.iter().flat_map(|(l, p)| l.iter().chain(p.iter()));
    let x_range = padded(data_range(all().map(|p| p.0)).unwrap_or((0.0, 1.0)), 0.05);
    let y_range = padded(data_range(all().map(|p| p.1)).unwrap_or((0.0, 1.0)), 0.05);
    let has_data = all().any(|&p| plottable(p));
    let ticks = |(lo, hi): (f64, f64), scale: AxisScale| match scale {
        AxisScale::Linear => Ticks::auto((lo, hi), AxisScale::Linear),
        AxisScale::Log => {
            let pairs = axis_ticks(10f64.powf(lo), 10f64.powf(hi), AxisScale::Log, MAX_TICKS);
            Ticks::of(pairs.into_iter().map(|(v, l)| (v.log10(), l)).collect())
        }
    };
    let (xt, yt) = (ticks(x_range, axes.x_scale), ticks(y_range, axes.y_scale));
    let desc = |label: &str, scale: AxisScale| match scale {
        AxisScale::Linear => label.to_string(),
        AxisScale::Log => format!("{label} (log scale)"),
    };
    render(path, title, |area, drawn| {
        let mut chart = linear_chart(area, (x_range, &xt), (y_range, &yt))?;
        configure_mesh(
            &mut chart,
            &desc(axes.x_label, axes.x_scale),
            &desc(axes.y_label, axes.y_scale),
            &xt,
            &yt,
            drawn,
        )?;
        let mut keys = Vec::new();
        for (g, (line, points)) in groups.iter().zip(&groups_t) {
            let color = g.color.map_or(BLACK, |i| PALETTE[i % PALETTE.len()]);
            let style = color.stroke_width(2);
            for piece in clip_polyline(line, x_range, y_range) {
                if g.dashed {
                    chart.draw_series(DashedLineSeries::new(piece, 10, 6, style))?;
                } else {
                    chart.draw_series(std::iter::once(PathElement::new(piece, style)))?;
                }
            }
            if g.triangles {
                chart.draw_series(
                    inside(points, x_range, y_range)
                        .map(|p| TriangleMarker::new(p, 8, color.filled())),
                )?;
            } else {
                chart.draw_series(
                    inside(points, x_range, y_range).map(|p| Circle::new(p, 5, color.filled())),
                )?;
            }
            let glyph = match (line.is_empty(), points.is_empty()) {
                (false, false) => Glyph::LineMarker(style, color, 5),
                (false, true) => Glyph::Line(style),
                (true, false) if g.triangles => Glyph::Triangle(color),
                (true, false) => Glyph::Marker(color, 5),
                (true, true) => Glyph::Note,
            };
            if !g.label.is_empty() {
                keys.push(key(g.label.clone(), glyph));
            }
        }
        if !has_data {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(keys)
    })
}

// ---------------------------------------------------------------------------------------------
// Drawing infrastructure

type DrawResult<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;
type Root<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Registers the embedded font once; the result of the first attempt is kept.
fn ensure_font() -> std::result::Result<(), String> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            // "sans-serif" is what we use; the other generic families are registered too so
            // that any default text style inside plotters also finds a font.
            for family in [FONT, "serif", "monospace"] {
                register_font(family, FontStyle::Normal, FONT_BYTES)
                    .map_err(|_| "the embedded font DejaVuSans.ttf cannot be parsed".to_string())?;
            }
            Ok(())
        })
        .clone()
}

/// Draws into an in-memory RGB buffer (catching panics) and only then writes the PNG, so a
/// failed plot leaves no half-drawn file behind. The title goes across the top; `draw` gets
/// the chart's area (left) and returns the legend entries, which are drawn into the panel on
/// the right.
fn render<F>(path: &Path, title: &str, draw: F) -> Result<Drawn>
where
    F: FnOnce(&Root<'_>, &mut Drawn) -> DrawResult<Vec<Key>>,
{
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(Error::plot(path, "the file name must end in .png"));
    }
    ensure_font().map_err(|m| Error::plot(path, m))?;

    let mut buffer = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    let mut drawn = Drawn::default();
    let result = catch_unwind(AssertUnwindSafe(|| -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        let body = if title.trim().is_empty() {
            root.margin(10, 0, 0, 0)
        } else {
            root.margin(8, 0, 0, 0).titled(title, (FONT, TITLE_SIZE))?
        };
        let (chart_area, legend_area) = body.split_horizontally(WIDTH - LEGEND_WIDTH);
        let keys = draw(&chart_area, &mut drawn)?;
        drawn.legend_px = draw_keys(&legend_area, &keys)?;
        root.present()?;
        Ok(())
    }));
    match result {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(Error::plot(path, e.to_string())),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            return Err(Error::plot(path, format!("panic while drawing: {what}")));
        }
    }

    // Encoded into a temporary file beside `path` and renamed into place: the old PNG or
    // the new one, never a truncated one (crate::output).
    let plot_err = |e: Error| match e {
        Error::Io { err, .. } => Error::plot(path, err.to_string()),
        other => Error::plot(path, other.to_string()),
    };
    let tmp = output::temp_beside(path, ".png").map_err(plot_err)?;
    let written = catch_unwind(AssertUnwindSafe(|| -> DrawResult {
        let mut out = BitMapBackend::new(tmp.path(), (WIDTH, HEIGHT));
        out.blit_bitmap((0, 0), (WIDTH, HEIGHT), &buffer)?;
        out.present()?;
        Ok(())
    }));
    match written {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(Error::plot(path, e.to_string())),
        Err(_) => return Err(Error::plot(path, "panic while writing the PNG")),
    }
    let len = tmp.as_file().metadata().map(|m| m.len()).unwrap_or(0);
    output::charge(len as usize).map_err(|e| Error::plot(path, e.to_string()))?;
    output::persist(tmp, path).map_err(plot_err)?;
    Ok(drawn)
}

fn chart_builder<'a, 'b>(area: &'a Root<'b>) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(20)
        .margin_right(10)
        .x_label_area_size(65)
        .y_label_area_size(95);
    builder
}

type LinearChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<FixedTicks<RangedCoordf64>, FixedTicks<RangedCoordf64>>,
>;

/// A chart with linear axes over the ranges, ticked at the given ticks.
fn linear_chart<'a, 'b>(
    area: &'a Root<'b>,
    (x_range, xt): ((f64, f64), &Ticks),
    (y_range, yt): ((f64, f64), &Ticks),
) -> DrawResult<LinearChart<'a, 'b>> {
    Ok(chart_builder(area).build_cartesian_2d(
        FixedTicks::new(
            RangedCoordf64::from(x_range.0..x_range.1),
            xt.values.clone(),
        ),
        FixedTicks::new(
            RangedCoordf64::from(y_range.0..y_range.1),
            yt.values.clone(),
        ),
    )?)
}

fn pixel_rect<DB: DrawingBackend, CT: CoordTranslate>(area: &DrawingArea<DB, CT>) -> PxRect {
    let (x, y) = area.get_pixel_range();
    ((x.start, x.end), (y.start, y.end))
}

/// Axis descriptions and the tick labels of `xt` and `yt` (recorded in `drawn` as plotters
/// asks for them), with grid lines at the ticks.
fn configure_mesh<X, Y>(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<FixedTicks<X>, FixedTicks<Y>>>,
    x_desc: &str,
    y_desc: &str,
    xt: &Ticks,
    yt: &Ticks,
    drawn: &mut Drawn,
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let seen_x = RefCell::new(Vec::new());
    let seen_y = RefCell::new(Vec::new());
    let fx = |v: &f64| {
        let s = xt.label(*v);
        seen_x.borrow_mut().push(s.clone());
        s
    };
    let fy = |v: &f64| {
        let s = yt.label(*v);
        seen_y.borrow_mut().push(s.clone());
        s
    };
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .axis_desc_style((FONT, AXIS_DESC_SIZE))
        .label_style((FONT, TICK_SIZE))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(BLACK.mix(0.0))
        .draw()?;
    let unique = |v: Vec<String>| {
        let mut out: Vec<String> = Vec::new();
        for s in v {
            if !out.contains(&s) {
                out.push(s);
            }
        }
        out
    };
    drawn.x_labels = unique(seen_x.into_inner());
    drawn.y_labels = unique(seen_y.into_inner());
    Ok(())
}

/// Draws the legend entries into `area` (the panel right of the chart): a symbol and the
/// label, wrapped to the panel's width, in a light box; entries that do not fit are counted
/// in a last line. Returns the box's pixel rectangle.
fn draw_keys(area: &Root<'_>, keys: &[Key]) -> DrawResult<Option<PxRect>> {
    if keys.is_empty() {
        return Ok(None);
    }
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    let style = TextStyle::from((FONT, LEGEND_SIZE)).pos(Pos::new(HPos::Left, VPos::Center));
    let (x_box, y_box) = (4, 20);
    let text_x = x_box + 44;
    let max_text = (w - text_x - 10).max(40) as u32;
    let line_h = LEGEND_SIZE as i32 + 5;
    // Lay out: wrapped lines of each entry.
    let mut rows: Vec<(usize, Vec<String>)> = Vec::new();
    let mut y = y_box + 10;
    let mut hidden = 0;
    for (i, k) in keys.iter().enumerate() {
        let lines = wrap(area, &k.label, &style, max_text)?;
        let need = lines.len() as i32 * line_h + 6;
        if y + need + line_h > h - 10 && i + 1 < keys.len() {
            hidden = keys.len() - i;
            break;
        }
        rows.push((i, lines));
        y += need;
    }
    let y_end = y + if hidden > 0 { line_h } else { 0 } + 4;
    area.draw(&Rectangle::new(
        [(x_box, y_box), (w - 6, y_end)],
        WHITE.mix(0.9).filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x_box, y_box), (w - 6, y_end)],
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    let mut y = y_box + 10;
    for (i, lines) in &rows {
        let yc = y + line_h / 2;
        draw_glyph(area, keys[*i].glyph, (x_box + 22, yc))?;
        for (j, line) in lines.iter().enumerate() {
            area.draw(&Text::new(
                line.clone(),
                (text_x, yc + j as i32 * line_h),
                style.clone(),
            ))?;
        }
        y += lines.len() as i32 * line_h + 6;
    }
    if hidden > 0 {
        area.draw(&Text::new(
            format!("… and {hidden} more"),
            (text_x, y + line_h / 2),
            style.clone(),
        ))?;
    }
    let ((x0, _), (y0, _)) = pixel_rect(area);
    Ok(Some(((x0 + x_box, x0 + w - 6), (y0 + y_box, y0 + y_end))))
}

/// Greedy word wrap of `text` to lines at most `width` px wide (a longer word stands alone).
fn wrap(area: &Root<'_>, text: &str, style: &TextStyle, width: u32) -> DrawResult<Vec<String>> {
    let mut lines: Vec<String> = Vec::new();
    let mut current = String::new();
    for word in text.split_whitespace() {
        let candidate = if current.is_empty() {
            word.to_string()
        } else {
            format!("{current} {word}")
        };
        if current.is_empty() || area.estimate_text_size(&candidate, style)?.0 <= width {
            current = candidate;
        } else {
            lines.push(std::mem::replace(&mut current, word.to_string()));
        }
    }
    if !current.is_empty() || lines.is_empty() {
        lines.push(current);
    }
    Ok(lines)
}

fn draw_glyph(area: &Root<'_>, glyph: Glyph, (x, y): (i32, i32)) -> DrawResult {
    match glyph {
        Glyph::Line(s) => area.draw(&PathElement::new(vec![(x - 14, y), (x + 14, y)], s))?,
        Glyph::Marker(c, r) => area.draw(&Circle::new((x, y), r, c.filled()))?,
        Glyph::LineMarker(s, c, r) => {
            area.draw(&PathElement::new(vec![(x - 14, y), (x + 14, y)], s))?;
            area.draw(&Circle::new((x, y), r, c.filled()))?;
        }
        Glyph::Triangle(c) => area.draw(&TriangleMarker::new((x, y), 6, c.filled()))?,
        Glyph::Pair(a, b) => {
            area.draw(&Circle::new((x - 8, y), 4, a.filled()))?;
            area.draw(&Circle::new((x + 8, y), 4, b.filled()))?;
        }
        Glyph::Note => {}
    }
    Ok(())
}

/// An f64 axis (linear or log, `inner`) whose ticks (and grid lines) are exactly the given
/// values, with no light grid lines. (plotters' `with_key_points` cannot be used with
/// `configure_mesh` for f64 axes.)
struct FixedTicks<C> {
    inner: C,
    ticks: Vec<f64>,
}

impl<C: Ranged<ValueType = f64>> FixedTicks<C> {
    fn new(inner: C, ticks: Vec<f64>) -> Self {
        let r = inner.range();
        let (lo, hi) = (r.start.min(r.end), r.start.max(r.end));
        FixedTicks {
            inner,
            ticks: ticks
                .into_iter()
                .filter(|t| (lo..=hi).contains(t))
                .collect(),
        }
    }
}

impl<C: Ranged<ValueType = f64>> Ranged for FixedTicks<C> {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
}

impl<C: Ranged<ValueType = f64>> ValueFormatter<f64> for FixedTicks<C> {
    fn format(value: &f64) -> String {
        format!("{value}")
    }
}

fn no_data<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<X, Y>>,
    at: (f64, f64),
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart.plotting_area().draw(&Text::new(
        "no data",
        at,
        TextStyle::from((FONT, 26)).pos(Pos::new(HPos::Center, VPos::Center)),
    ))?;
    Ok(())
}

fn mid((lo, hi): (f64, f64)) -> f64 {
    0.5 * lo + 0.5 * hi
}

/// Dark blue (t = 0, rank 2) to light grey-blue (t = 1, worst rank).
fn rank_color(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + (b - a) * t).round() as u8;
    RGBColor(lerp(31.0, 185.0), lerp(70.0, 200.0), lerp(140.0, 222.0))
}

// ---------------------------------------------------------------------------------------------
// Data sanitising (pure functions)

fn plottable(p: (f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite() && p.0.abs() <= MAX_ABS && p.1.abs() <= MAX_ABS
}

fn plottable_value(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_ABS
}

/// Min and max of the plottable values, `None` if there are none.
fn data_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| plottable_value(*v))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// Widens `[lo, hi]` by `frac` of its span on both sides; a degenerate range (one value, or a
/// span below 1e-12 of the magnitude) becomes `c ± 10 %` of `c` (or `±1` around zero).
fn padded((lo, hi): (f64, f64), frac: f64) -> (f64, f64) {
    let span = hi - lo;
    let scale = lo.abs().max(hi.abs());
    if span.is_finite() && span > 1e-12 * scale && span > 0.0 {
        (lo - frac * span, hi + frac * span)
    } else {
        let c = 0.5 * lo + 0.5 * hi;
        let h = if c != 0.0 { 0.1 * c.abs() } else { 1.0 };
        (c - h, c + h)
    }
}

/// An axis of the creep-curve plot: measured extent, predictions up to 1.5× of it, starting at
/// 0 unless there are negative values.
fn creep_axis(measured: Option<(f64, f64)>, predicted: Option<(f64, f64)>) -> (f64, f64) {
    let (lo, hi) = match (measured, predicted) {
        (Some((ml, mh)), Some((pl, ph))) => {
            let reach = mh.abs().max(ml.abs()) * PREDICTED_EXTENT;
            let lo = ml.min(pl.max(-reach));
            let hi = mh.max(ph.min(reach));
            (lo, hi)
        }
        (Some(m), None) => m,
        (None, Some(p)) => p,
        (None, None) => (0.0, 1.0),
    };
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let (plo, phi) = padded((lo, hi), 0.03);
    (if lo >= 0.0 { 0.0 } else { plo }, phi)
}

/// A log axis range covering the (positive) values, padded by 5 % of the decades (at least
/// 0.1 decade), or one decade each side of a single value.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(None, |acc: Option<(f64, f64)>, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
        .unwrap_or((1.0, 1.0));
    let (l0, l1) = (
        lo.clamp(LOG_MIN, MAX_ABS).log10(),
        hi.clamp(LOG_MIN, MAX_ABS).log10(),
    );
    // plotters enumerates every decade for its light mesh lines: keep the span bounded.
    let l0 = l0.max(l1 - MAX_LOG_DECADES);
    let span = l1 - l0;
    let pad = if span > 1e-9 {
        (0.05 * span).max(0.1)
    } else {
        1.0
    };
    (10f64.powf(l0 - pad), 10f64.powf(l1 + pad))
}

/// About `max` integer ticks 1..=n with a 1-2-5 step.
fn integer_ticks(n: usize, max: usize) -> Vec<f64> {
    let mut step = 1usize;
    'search: for decade in [
        1usize, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000,
    ] {
        for m in [1usize, 2, 5] {
            step = m * decade;
            if n / step < max {
                break 'search;
            }
        }
    }
    let mut ticks = vec![1.0];
    ticks.extend(
        (1..=n / step)
            .map(|i| (i * step) as f64)
            .filter(|&v| v > 1.0),
    );
    ticks
}

/// The plottable points inside the axes.
fn inside(
    points: &[(f64, f64)],
    x: (f64, f64),
    y: (f64, f64),
) -> impl Iterator<Item = (f64, f64)> + '_ {
    points
        .iter()
        .copied()
        .filter(move |&p| plottable(p) && p.0 >= x.0 && p.0 <= x.1 && p.1 >= y.0 && p.1 <= y.1)
}

/// Liang–Barsky clipping of the segment `p`–`q` to the rectangle; unclipped ends are returned
/// bit-for-bit so consecutive segments join exactly.
fn clip_segment(
    p: (f64, f64),
    q: (f64, f64),
    x: (f64, f64),
    y: (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (pk, qk) in [
        (-dx, p.0 - x.0),
        (dx, x.1 - p.0),
        (-dy, p.1 - y.0),
        (dy, y.1 - p.1),
    ] {
        if pk == 0.0 {
            if qk < 0.0 {
                return None;
            }
        } else {
            let r = qk / pk;
            if pk < 0.0 {
                if r > t1 {
                    return None;
                }
                t0 = t0.max(r);
            } else {
                if r < t0 {
                    return None;
                }
                t1 = t1.min(r);
            }
        }
    }
    let a = if t0 == 0.0 {
        p
    } else {
        (p.0 + t0 * dx, p.1 + t0 * dy)
    };
    let b = if t1 == 1.0 {
        q
    } else {
        (p.0 + t1 * dx, p.1 + t1 * dy)
    };
    Some((a, b))
}

/// Splits a polyline at non-plottable points and clips it to the rectangle; returns the
/// visible pieces (each with at least two points).
fn clip_polyline(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut pieces = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let finish = |current: &mut Vec<(f64, f64)>, pieces: &mut Vec<Vec<(f64, f64)>>| {
        if current.len() >= 2 {
            pieces.push(std::mem::take(current));
        } else {
            current.clear();
        }
    };
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        let clipped = if plottable(p) && plottable(q) {
            clip_segment(p, q, x, y)
        } else {
            None
        };
        match clipped {
            Some((a, b)) => {
                if current.last() != Some(&a) {
                    finish(&mut current, &mut pieces);
                    current.push(a);
                }
                current.push(b);
            }
            None => finish(&mut current, &mut pieces),
        }
    }
    finish(&mut current, &mut pieces);
    pieces
}

/// One constant's profile likelihood for [`plot_profile`], in the coordinate it is shown in
/// (the value, or log10 of it for a log-scale constant; the caller's `x_label` says which).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProfilePlot {
    /// X axis description, e.g. `log10 A (A in 1/h)`.
    pub x_label: String,
    /// (x, Δ(−2 ln L)) of the profile points that were fitted, any order.
    pub points: Vec<(f64, f64)>,
    /// x of points whose fit failed from every start.
    pub failed: Vec<f64>,
    /// x of the estimate (Δ = 0).
    pub estimate: f64,
    /// x of the lower and upper bounds.
    pub bounds: (f64, f64),
    /// Thresholds drawn as horizontal lines, with their labels (e.g. "95 %: 3.84").
    pub thresholds: Vec<(String, f64)>,
}

/// A profile likelihood: Δ(−2 ln L) against the constant, the estimate, the thresholds of the
/// intervals (dashed horizontal lines) and the bounds (dotted vertical lines, where inside
/// the axis range); failed points as red triangles on the x axis. The y axis shows 0 to
/// 1.3 × the highest threshold (higher points are clipped).
pub fn plot_profile(path: &Path, title: &str, p: &ProfilePlot) -> Result<()> {
    profile_chart(path, title, p).map(|_| ())
}

fn profile_chart(path: &Path, title: &str, p: &ProfilePlot) -> Result<Drawn> {
    let t_max = p
        .thresholds
        .iter()
        .map(|t| t.1)
        .filter(|v| v.is_finite())
        .fold(1.0, f64::max);
    let xs = p
        .points
        .iter()
        .map(|q| q.0)
        .chain(p.failed.iter().copied())
        .chain(std::iter::once(p.estimate));
    let x_range = padded(data_range(xs).unwrap_or((0.0, 1.0)), 0.04);
    let y_top = 1.3 * t_max;
    let y_range = (-0.04 * y_top, y_top);
    let (xt, yt) = (
        Ticks::auto(x_range, AxisScale::Linear),
        Ticks::auto(y_range, AxisScale::Linear),
    );
    let mut pts: Vec<(f64, f64)> = p.points.iter().copied().filter(|&q| plottable(q)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    render(path, title, |area, drawn| {
        let mut chart = linear_chart(area, (x_range, &xt), (y_range, &yt))?;
        configure_mesh(&mut chart, &p.x_label, "Δ(−2 ln L)", &xt, &yt, drawn)?;
        let mut keys = Vec::new();
        for (i, (label, t)) in p.thresholds.iter().enumerate() {
            let color = PALETTE[(i + 1) % PALETTE.len()];
            chart.draw_series(DashedLineSeries::new(
                vec![(x_range.0, *t), (x_range.1, *t)],
                10,
                6,
                color.stroke_width(2),
            ))?;
            keys.push(key(label.clone(), Glyph::Line(color.stroke_width(2))));
        }
        let mut bound_shown = false;
        for b in [p.bounds.0, p.bounds.1] {
            if b.is_finite() && b >= x_range.0 && b <= x_range.1 {
                chart.draw_series(DashedLineSeries::new(
                    vec![(b, y_range.0), (b, y_range.1)],
                    3,
                    4,
                    BLACK.mix(0.7).stroke_width(2),
                ))?;
                bound_shown = true;
            }
        }
        if bound_shown {
            keys.push(key("bound", Glyph::Line(BLACK.mix(0.7).stroke_width(2))));
        }
        let color = PALETTE[0];
        chart.draw_series(
            clip_polyline(&pts, x_range, y_range)
                .into_iter()
                .map(|piece| PathElement::new(piece, color.stroke_width(2))),
        )?;
        chart.draw_series(
            inside(&pts, x_range, y_range).map(|q| Circle::new(q, 4, color.filled())),
        )?;
        keys.push(key(
            "profile (others re-fitted)",
            Glyph::LineMarker(color.stroke_width(2), color, 4),
        ));
        if plottable_value(p.estimate) {
            chart.draw_series(std::iter::once(Circle::new(
                (p.estimate, 0.0),
                7,
                PALETTE[3].filled(),
            )))?;
            keys.push(key("estimate", Glyph::Marker(PALETTE[3], 6)));
        }
        if !p.failed.is_empty() {
            chart.draw_series(
                p.failed
                    .iter()
                    .filter(|x| plottable_value(**x))
                    .map(|&x| TriangleMarker::new((x, 0.0), 7, PALETTE[3].filled())),
            )?;
            keys.push(key(
                format!("{} failed fit(s)", p.failed.len()),
                Glyph::Triangle(PALETTE[3]),
            ));
        }
        if pts.is_empty() {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        drawn.plot_px = pixel_rect(chart.plotting_area());
        Ok(keys)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tempfile::TempDir;

    const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];

    fn assert_png(path: &Path) {
        let bytes = std::fs::read(path).expect("plot written");
        assert_eq!(
            &bytes[..8],
            &PNG_SIGNATURE,
            "{} is not a PNG",
            path.display()
        );
        assert!(
            bytes.len() > 10_000,
            "{} is only {} bytes",
            path.display(),
            bytes.len()
        );
    }

    /// A KHD-like creep curve: primary, secondary and tertiary creep up to rupture at `tf`.
    fn creep_curve(tf: f64, eps_f: f64, n: usize) -> Vec<(f64, f64)> {
        (0..=n)
            .map(|i| {
                let t = tf * i as f64 / n as f64;
                let x = t / tf;
                let strain =
                    eps_f * (0.15 * (1.0 - (-20.0 * x).exp()) + 0.35 * x) + eps_f * 0.5 * x.powi(8);
                (t, strain)
            })
            .collect()
    }

    fn example_curves() -> Vec<CurvePlot> {
        [
            (100.0, 9000.0, 12.0),
            (120.0, 3500.0, 14.0),
            (140.0, 1200.0, 16.0),
            (160.0, 450.0, 18.0),
        ]
        .iter()
        .map(|&(stress, tf, eps_f)| CurvePlot {
            label: format!("{stress} MPa"),
            measured: creep_curve(tf * 1.05, eps_f * 0.95, 25)
                .into_iter()
                .skip(1)
                .collect(),
            predicted: creep_curve(tf, eps_f, 400),
        })
        .collect()
    }

    #[test]
    fn creep_curves_png_with_text() {
        let dir = TempDir::new().unwrap();
        let curves = example_curves();
        let with_title = dir.path().join("curves.png");
        let without_title = dir.path().join("curves_untitled.png");
        plot_creep_curves(&with_title, "Creep curves at 550 °C", &curves).unwrap();
        plot_creep_curves(&without_title, "", &curves).unwrap();
        assert_png(&with_title);
        assert_png(&without_title);
        // The title is rendered text, so the images must differ.
        assert_ne!(
            std::fs::read(&with_title).unwrap(),
            std::fs::read(&without_title).unwrap()
        );
        // Two different titles also differ (text, not just reserved space).
        let other = dir.path().join("curves_other.png");
        plot_creep_curves(&other, "Creep curves at 600 °C", &curves).unwrap();
        assert_ne!(
            std::fs::read(&with_title).unwrap(),
            std::fs::read(&other).unwrap()
        );
    }

    #[test]
    fn residuals_png() {
        let dir = TempDir::new().unwrap();
        let series: Vec<Series> = (0..4)
            .map(|k| Series {
                label: format!("{} MPa", 100 + 20 * k),
                points: (0..40)
                    .map(|i| {
                        let x = i as f64 / 39.0;
                        (
                            x,
                            0.05 * ((k as f64 + 1.0) * 6.0 * x).sin() + 0.01 * k as f64,
                        )
                    })
                    .collect(),
            })
            .collect();
        let path = dir.path().join("residuals.png");
        plot_residuals(
            &path,
            "Residuals",
            &series,
            "life fraction t/t_f",
            "residual (normalised)",
        )
        .unwrap();
        assert_png(&path);
    }

    #[test]
    fn waterfall_png() {
        let dir = TempDir::new().unwrap();
        let objectives: Vec<f64> = (0..64)
            .map(|i| 1e-3 * (1.0 + (i as f64 / 8.0).powi(3)))
            .collect();
        let path = dir.path().join("waterfall.png");
        plot_waterfall(&path, "Multistart objectives", &objectives).unwrap();
        assert_png(&path);
    }

    #[test]
    fn parameters_png() {
        let dir = TempDir::new().unwrap();
        let names: Vec<String> = ["A", "B", "h", "H*", "Kc", "C", "D"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let solutions: Vec<Vec<f64>> = (0..10)
            .map(|r| {
                (0..names.len())
                    .map(|j| {
                        (0.2 + 0.08 * j as f64 + 0.03 * r as f64 * ((j + r) as f64).sin())
                            .clamp(0.0, 1.0)
                    })
                    .collect()
            })
            .collect();
        let path = dir.path().join("parameters.png");
        plot_parameters(&path, "Best 10 solutions within bounds", &names, &solutions).unwrap();
        assert_png(&path);
    }

    #[test]
    fn profile_png_and_degenerate_profiles() {
        let dir = TempDir::new().unwrap();
        let good = ProfilePlot {
            x_label: "log10 A (A in 1/h)".into(),
            points: (0..12)
                .map(|i| (-10.0 + 0.1 * i as f64, (0.3 * i as f64 - 1.5).powi(2)))
                .collect(),
            failed: vec![],
            estimate: -9.5,
            bounds: (-10.0, -9.0),
            thresholds: vec![("68 %".into(), 1.0), ("95 %".into(), 3.84)],
        };
        let path = dir.path().join("profile_A.png");
        plot_profile(&path, "A", &good).unwrap();
        assert_png(&path);
        for (k, bad) in [
            ProfilePlot::default(),
            ProfilePlot {
                points: vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)],
                estimate: f64::NAN,
                failed: vec![f64::NAN, 2.0],
                bounds: (f64::NEG_INFINITY, f64::NAN),
                ..good.clone()
            },
            ProfilePlot {
                points: vec![(3.0, 0.0); 5],
                estimate: 3.0,
                ..good.clone()
            },
        ]
        .iter()
        .enumerate()
        {
            let path = dir.path().join(format!("bad{k}.png"));
            plot_profile(&path, "degenerate", bad).unwrap();
            assert_png(&path);
        }
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let dir = TempDir::new().unwrap();
        let p = |name: &str| dir.path().join(format!("{name}.png"));
        let nan = f64::NAN;
        let inf = f64::INFINITY;

        // Creep curves.
        let cases: Vec<Vec<CurvePlot>> = vec![
            vec![],
            vec![CurvePlot::default()],
            vec![CurvePlot {
                label: "one".into(),
                measured: vec![(1.0, 1.0)],
                predicted: vec![(1.0, 1.0)],
            }],
            vec![CurvePlot {
                label: "flat".into(),
                measured: vec![(5.0, 2.0); 4],
                predicted: vec![(5.0, 2.0); 10],
            }],
            vec![CurvePlot {
                label: "nan".into(),
                measured: vec![(nan, 1.0), (1.0, inf), (2.0, 1.0), (-inf, nan)],
                predicted: vec![(0.0, 0.0), (nan, nan), (1.0, 1.0), (2.0, 1e300), (3.0, 2.0)],
            }],
            vec![CurvePlot {
                label: "all nan".into(),
                measured: vec![(nan, nan)],
                predicted: vec![(inf, -inf), (nan, 0.0)],
            }],
            vec![CurvePlot {
                label: "runaway".into(),
                measured: vec![(0.0, 0.0), (10.0, 1.0)],
                predicted: vec![(0.0, 0.0), (10.0, 1.0), (10.5, 1e9), (1e12, 1e12)],
            }],
            vec![CurvePlot {
                label: "negative".into(),
                measured: vec![(-1.0, -2.0), (1.0, -1.0)],
                predicted: vec![],
            }],
            (0..25)
                .map(|i| CurvePlot {
                    label: format!("{i}"),
                    measured: vec![(i as f64, 1e-20 * i as f64)],
                    predicted: vec![],
                })
                .collect(),
        ];
        for (i, curves) in cases.iter().enumerate() {
            plot_creep_curves(&p(&format!("creep{i}")), "degenerate", curves)
                .unwrap_or_else(|e| panic!("creep case {i}: {e}"));
        }

        // Residuals.
        let cases: Vec<Vec<Series>> = vec![
            vec![],
            vec![Series::default()],
            vec![Series {
                label: "one".into(),
                points: vec![(0.5, 0.0)],
            }],
            vec![Series {
                label: "flat".into(),
                points: vec![(0.5, 3.0); 5],
            }],
            vec![Series {
                label: "nan".into(),
                points: vec![(nan, 1.0), (0.2, inf), (0.4, -0.1), (0.6, 0.2), (inf, inf)],
            }],
        ];
        for (i, series) in cases.iter().enumerate() {
            plot_residuals(&p(&format!("res{i}")), "", series, "x", "y")
                .unwrap_or_else(|e| panic!("residual case {i}: {e}"));
        }

        // Waterfall.
        let cases: Vec<Vec<f64>> = vec![
            vec![],
            vec![1.0],
            vec![0.0],
            vec![-1.0, 0.0],
            vec![2.0; 10],
            vec![nan, inf, -inf],
            vec![0.0, 1e-300, 1e-5, 1.0, 1e300, nan, f64::MAX],
            (0..5000).map(|i| 1.0 + i as f64).collect(),
        ];
        for (i, objectives) in cases.iter().enumerate() {
            plot_waterfall(&p(&format!("water{i}")), "w", objectives)
                .unwrap_or_else(|e| panic!("waterfall case {i}: {e}"));
        }

        // Parameters.
        let names = |n: usize| -> Vec<String> { (0..n).map(|i| format!("c{i}")).collect() };
        let cases: Vec<(Vec<String>, Vec<Vec<f64>>)> = vec![
            (vec![], vec![]),
            (names(3), vec![]),
            (vec![], vec![vec![]]),
            (names(1), vec![vec![0.5]]),
            (names(2), vec![vec![0.5, 0.5], vec![0.5, 0.5]]),
            (names(3), vec![vec![nan, -3.0, 7.0], vec![inf, 0.5, nan]]),
            (names(3), (0..200).map(|_| vec![0.0, 1.0, 0.5]).collect()),
        ];
        for (i, (names, sols)) in cases.iter().enumerate() {
            plot_parameters(&p(&format!("par{i}")), "p", names, sols)
                .unwrap_or_else(|e| panic!("parameter case {i}: {e}"));
        }
        // Mismatched lengths are the caller's error.
        let err = plot_parameters(&p("par_bad"), "p", &names(3), &[vec![0.5; 2]]).unwrap_err();
        assert!(matches!(err, Error::Invalid(_)), "{err}");
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = TempDir::new().unwrap();
        let path = dir.path().join("no/such/dir/plot.png");
        let err = plot_creep_curves(&path, "t", &example_curves()).unwrap_err();
        assert!(matches!(err, Error::Plot { .. }), "{err}");
        assert!(err.to_string().starts_with("plot "), "{err}");
        assert!(plot_residuals(&path, "t", &[], "x", "y").is_err());
        assert!(plot_waterfall(&path, "t", &[1.0, 2.0]).is_err());
        assert!(plot_parameters(&path, "t", &["a".to_string()], &[vec![0.5]]).is_err());
        assert!(!path.exists());
    }

    #[test]
    fn non_png_name_is_an_error() {
        let dir = TempDir::new().unwrap();
        let path = dir.path().join("plot.svg");
        assert!(matches!(
            plot_waterfall(&path, "t", &[1.0]),
            Err(Error::Plot { .. })
        ));
        assert!(!path.exists());
        let upper = dir.path().join("plot.PNG");
        plot_waterfall(&upper, "t", &[1.0, 2.0]).unwrap();
        assert!(upper.exists());
    }

    #[test]
    fn drawing_errors_and_panics_become_errors() {
        let dir = TempDir::new().unwrap();
        let path = dir.path().join("boom.png");
        let err = render(&path, "", |_, _| panic!("inside plotters")).unwrap_err();
        assert!(err.to_string().contains("inside plotters"), "{err}");
        let err = render(&path, "", |_, _| Err("drawing failed".into())).unwrap_err();
        assert!(err.to_string().contains("drawing failed"), "{err}");
        assert!(!path.exists(), "no file is written for a failed plot");
    }

    /// Every non-degenerate tick set: 2..=max ticks inside the range, increasing, distinct
    /// labels that state their values.
    fn check_ticks(lo: f64, hi: f64, scale: AxisScale, t: &[(f64, String)]) {
        assert!(
            (2..=MAX_TICKS).contains(&t.len()),
            "[{lo}, {hi}] {scale:?}: {} ticks {t:?}",
            t.len()
        );
        assert!(t.iter().all(|(v, _)| *v >= lo && *v <= hi), "{t:?}");
        assert!(t.windows(2).all(|w| w[0].0 < w[1].0), "{t:?}");
        let spacing = t
            .windows(2)
            .map(|w| w[1].0 - w[0].0)
            .fold(f64::INFINITY, f64::min);
        for (i, (v, label)) in t.iter().enumerate() {
            assert!(
                t[i + 1..].iter().all(|(_, l)| l != label),
                "labels repeat: {t:?}"
            );
            let parsed: f64 = label.parse().unwrap_or_else(|_| panic!("'{label}'"));
            assert!(
                (parsed - v).abs() <= 1e-3 * spacing,
                "label '{label}' for {v} (spacing {spacing})"
            );
        }
    }

    #[test]
    fn axis_ticks_table() {
        use AxisScale::{Linear, Log};
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        // (lo, hi, scale, expected labels, or None to check only the invariants)
        let cases: Vec<(f64, f64, AxisScale, Option<Vec<String>>)> = vec![
            (
                0.0,
                1.0,
                Linear,
                Some(s(&["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"])),
            ),
            (
                -20.6,
                19.9,
                Linear,
                Some(s(&["-20", "-15", "-10", "-5", "0", "5", "10", "15"])),
            ),
            (
                0.0,
                91_000.0,
                Linear,
                Some(s(&[
                    "0", "10000", "20000", "30000", "40000", "50000", "60000", "70000", "80000",
                    "90000",
                ])),
            ),
            (-0.03, 0.97, Linear, None),
            (1e6, 1e6 + 1.0, Linear, None),
            (1e-9, 3e-9, Linear, None),
            (-1e-12, 1e-12, Linear, None),
            (
                -1.1e-7,
                1.1e-7,
                Linear,
                Some(s(&["-1e-7", "-5e-8", "0", "5e-8", "1e-7"])),
            ),
            (123.456, 123.457, Linear, None),
            // The 560 °C waterfall: minima 0.2527 and 0.3809 within one decade (padded).
            (
                0.2007,
                0.4795,
                Log,
                Some(s(&["0.25", "0.30", "0.35", "0.40", "0.45"])),
            ),
            // 590 °C: minima 1.1252 and 1.1260, padded by 0.1 decade.
            (
                0.8938,
                1.4167,
                Log,
                Some(s(&["0.9", "1.0", "1.1", "1.2", "1.3", "1.4"])),
            ),
            (
                1e-3,
                1e3,
                Log,
                Some(s(&["0.001", "0.01", "0.1", "1", "10", "100", "1000"])),
            ),
            (
                0.05,
                5.0,
                Log,
                Some(s(&["0.05", "0.1", "0.2", "0.5", "1", "2", "5"])),
            ),
            (1e-31, 1e9, Log, None),
            (1.1251, 1.1262, Log, None),
            (3.0e7, 4.5e7, Log, None),
        ];
        for (lo, hi, scale, want) in cases {
            let t = axis_ticks(lo, hi, scale, MAX_TICKS);
            check_ticks(lo, hi, scale, &t);
            if let Some(want) = want {
                let labels: Vec<String> = t.iter().map(|p| p.1.clone()).collect();
                assert_eq!(labels, want, "[{lo}, {hi}] {scale:?}");
            }
        }
        // Wide log ranges are thinned to at most MAX_TICKS decades.
        let t = axis_ticks(1e-31, 1e9, Log, MAX_TICKS);
        assert!(t
            .iter()
            .all(|(v, _)| (v.log10() - v.log10().round()).abs() < 1e-9));
        // Degenerate ranges give no ticks (the plots widen them first).
        assert!(axis_ticks(1.0, 1.0, Linear, 10).is_empty());
        assert!(axis_ticks(f64::NAN, 1.0, Linear, 10).is_empty());
        assert!(axis_ticks(0.0, 1.0, Log, 10).is_empty());
    }

    #[test]
    fn waterfall_counts_add_up_and_a_narrow_log_axis_is_labelled() {
        // The 590 °C sweep's shape: 2211 fits, 11 of them failed (ranked last), two minima
        // 0.07 % apart; and the 560 °C one: minima 0.2527 and 0.3809.
        let mut obj: Vec<f64> = (0..2200)
            .map(|i| if i < 1100 { 1.125188 } else { 1.12596 })
            .collect();
        obj.extend([f64::NAN; 11]);
        let c = run_counts(&obj);
        assert_eq!((c.ran, c.finite, c.failed), (2211, 2200, 11));
        assert_eq!(
            counts_note(c),
            "2211 fits ran: 2200 finite, 11 failed (no objective, not drawn)"
        );
        let dir = TempDir::new().unwrap();
        let drawn = waterfall(&dir.path().join("w590.png"), "590", &obj).unwrap();
        assert!(drawn.y_labels.len() >= 2, "{:?}", drawn.y_labels);
        let obj560: Vec<f64> = (0..610)
            .map(|i| if i < 251 { 0.252655 } else { 0.38094 })
            .collect();
        let drawn = waterfall(&dir.path().join("w560.png"), "560", &obj560).unwrap();
        assert!(drawn.y_labels.len() >= 3, "{:?}", drawn.y_labels);
        assert!(
            drawn.y_labels.contains(&"0.25".to_string()),
            "{:?}",
            drawn.y_labels
        );
        assert!(
            drawn.y_labels.contains(&"0.40".to_string()),
            "{:?}",
            drawn.y_labels
        );
        assert!(drawn.x_labels.len() >= 2, "{:?}", drawn.x_labels);
        assert_eq!(
            counts_note(run_counts(&obj560)),
            "610 fits ran: 610 finite, 0 failed"
        );
    }

    #[test]
    fn every_plot_labels_both_axes_and_keeps_its_legend_outside_the_data() {
        let dir = TempDir::new().unwrap();
        let p = |n: &str| dir.path().join(format!("{n}.png"));
        let narrow: Vec<Series> = (0..3)
            .map(|k| Series {
                label: format!("{} MPa", 85 + 10 * k),
                points: (0..30)
                    .map(|i| (i as f64 / 29.0, 1e-7 * ((i + k) as f64).sin()))
                    .collect(),
            })
            .collect();
        let drawings = [
            (
                "creep",
                creep_curves(&p("creep"), "t", &example_curves()).unwrap(),
            ),
            (
                "residuals",
                residuals(&p("res"), "t", &narrow, "t / t_f", "predicted − measured").unwrap(),
            ),
            (
                "waterfall",
                waterfall(&p("water"), "t", &[1e-3, 2e-3, 5e-1, f64::NAN]).unwrap(),
            ),
            (
                "profile",
                profile_chart(
                    &p("prof"),
                    "t",
                    &ProfilePlot {
                        x_label: "B (1/MPa)".into(),
                        points: (0..9)
                            .map(|i| {
                                let x = 0.15 + 0.01 * i as f64;
                                (x, ((x - 0.19) / 0.02).powi(2))
                            })
                            .collect(),
                        failed: vec![0.24],
                        estimate: 0.19,
                        bounds: (0.1, 0.23),
                        thresholds: vec![("68 %".into(), 1.0), ("95 %".into(), 3.84)],
                    },
                )
                .unwrap(),
            ),
            (
                "parameters",
                parameters(
                    &p("par"),
                    "t",
                    &["A".to_string(), "B".to_string()],
                    &[vec![0.2, 0.9], vec![0.3, 0.8], vec![0.5, 0.5]],
                )
                .unwrap(),
            ),
        ];
        for (what, d) in &drawings {
            assert!(d.x_labels.len() >= 2, "{what}: x labels {:?}", d.x_labels);
            assert!(d.y_labels.len() >= 2, "{what}: y labels {:?}", d.y_labels);
            let ((px0, px1), (py0, py1)) = d.plot_px;
            assert!(
                px1 - px0 > 500 && py1 - py0 > 400,
                "{what}: plot area {:?}",
                d.plot_px
            );
            let ((lx0, lx1), (ly0, ly1)) = d.legend_px.expect("a legend");
            assert!(
                lx0 >= px1,
                "{what}: legend {:?} overlaps the plot {:?}",
                d.legend_px,
                d.plot_px
            );
            assert!(
                lx1 <= WIDTH as i32 && ly0 < ly1 && ly1 <= HEIGHT as i32,
                "{what}"
            );
        }
        // The narrow residual range (1e-7 wide) still gets distinct labels.
        let res = &drawings[1].1;
        let mut labels = res.y_labels.clone();
        labels.dedup();
        assert_eq!(labels.len(), res.y_labels.len());
    }

    #[test]
    fn clipping() {
        let r = (0.0, 1.0);
        assert_eq!(
            clip_segment((0.2, 0.2), (0.8, 0.8), r, r),
            Some(((0.2, 0.2), (0.8, 0.8)))
        );
        assert_eq!(
            clip_segment((0.5, 0.5), (0.5, 2.0), r, r),
            Some(((0.5, 0.5), (0.5, 1.0)))
        );
        assert_eq!(clip_segment((2.0, 2.0), (3.0, 3.0), r, r), None);
        assert_eq!(
            clip_segment((-1.0, 0.5), (2.0, 0.5), r, r),
            Some(((0.0, 0.5), (1.0, 0.5)))
        );
        let pieces = clip_polyline(
            &[
                (0.1, 0.1),
                (0.2, 0.2),
                (0.3, 5.0),
                (0.4, 0.4),
                (0.5, 0.5),
                (f64::NAN, 0.5),
                (0.7, 0.7),
                (0.8, 0.8),
            ],
            r,
            r,
        );
        assert_eq!(pieces.len(), 3, "{pieces:?}");
        assert_eq!(pieces[0].first(), Some(&(0.1, 0.1)));
        assert!(pieces.iter().all(|p| p.len() >= 2));
        assert!(pieces
            .iter()
            .flatten()
            .all(|p| (0.0..=1.0).contains(&p.0) && (0.0..=1.0).contains(&p.1)));
    }

    #[test]
    fn ranges() {
        assert_eq!(padded((2.0, 2.0), 0.05), (1.8, 2.2));
        assert_eq!(padded((0.0, 0.0), 0.05), (-1.0, 1.0));
        let (lo, hi) = creep_axis(Some((0.0, 10.0)), Some((0.0, 1e9)));
        assert_eq!(lo, 0.0);
        assert!(hi > 15.0 && hi < 16.0, "{hi}");
        let (lo, hi) = log_range([0.5].into_iter());
        assert!(lo > 0.0 && lo < 0.5 && hi > 0.5);
        let (lo, hi) = log_range(std::iter::empty());
        assert!(lo > 0.0 && hi > lo);
        assert_eq!(integer_ticks(5, 10), vec![1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(integer_ticks(5000, 10).len() <= 11);
    }
}
