//! PNG plots of calibration results: measured against predicted creep curves, residuals,
//! the multistart "waterfall" of objectives and the spread of the best constants within
//! their bounds.
//!
//! Every plot is 1000×700 px and is drawn with the DejaVu Sans font embedded in the binary
//! (registered with plotters' `ab_glyph` support), so no system fonts are needed.
//!
//! Robustness: non-finite points (and points with a magnitude above 1e150) are skipped,
//! lines are broken at them and clipped to the axes, degenerate ranges (one point, all
//! equal values) are widened, empty inputs give an axes-only plot saying "no data", and
//! log axes clamp non-positive values to a floor. Any drawing or encoding failure, and any
//! panic inside plotters, is returned as [`Error::Plot`]; nothing is written unless the
//! whole image was drawn.

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
pub const WIDTH: u32 = 1000;
/// Image height in pixels.
pub const HEIGHT: u32 = 700;

/// The embedded font (DejaVu Sans, see `assets/DejaVu-LICENSE.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// The family name under which the embedded font is registered and used.
const FONT: &str = "sans-serif";

const TITLE_SIZE: f64 = 28.0;
const AXIS_DESC_SIZE: f64 = 22.0;
const TICK_SIZE: f64 = 17.0;
const LEGEND_SIZE: f64 = 18.0;

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

/// Measured (markers) against predicted (lines) creep curves, one colour per stress: the
/// paper's Figures 6/7. Axes: "time (h)" and "strain (%)", both starting at 0 unless data are
/// negative. The axes cover every measured point; predicted curves are drawn up to 1.5× the
/// measured extent on each axis and clipped beyond, so a runaway prediction near rupture
/// cannot squash the data (without measured points the predictions set the axes).
pub fn plot_creep_curves(path: &Path, title: &str, curves: &[CurvePlot]) -> Result<()> {
    let measured_x = curves.iter().flat_map(|c| c.measured.iter().map(|p| p.0));
    let measured_y = curves.iter().flat_map(|c| c.measured.iter().map(|p| p.1));
    let predicted_x = curves.iter().flat_map(|c| c.predicted.iter().map(|p| p.0));
    let predicted_y = curves.iter().flat_map(|c| c.predicted.iter().map(|p| p.1));
    let x_range = creep_axis(data_range(measured_x), data_range(predicted_x));
    let y_range = creep_axis(data_range(measured_y), data_range(predicted_y));
    let has_data = curves
        .iter()
        .any(|c| c.measured.iter().chain(&c.predicted).any(|&p| plottable(p)));

    render(path, |root| {
        let mut chart = chart_builder(root, title)
            .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
        configure_mesh(&mut chart, "time (h)", "strain (%)")?;

        for (i, curve) in curves.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let label = if curve.label.trim().is_empty() {
                format!("curve {}", i + 1)
            } else {
                curve.label.clone()
            };
            let pieces = clip_polyline(&curve.predicted, x_range, y_range);
            chart
                .draw_series(
                    pieces
                        .into_iter()
                        .map(|piece| PathElement::new(piece, color.stroke_width(2))),
                )?
                .label(label)
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (24, 0)], color.stroke_width(2))
                        + Circle::new((12, 0), 4, color.filled())
                });
            chart.draw_series(
                inside(&curve.measured, x_range, y_range)
                    .map(|p| Circle::new(p, 4, color.filled())),
            )?;
        }
        if !curves.is_empty() {
            // Style key: markers are measurements, lines are predictions.
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label("measured")
                .legend(|(x, y)| Circle::new((x + 12, y), 4, BLACK.filled()));
            chart
                .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
                .label("predicted")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], BLACK.stroke_width(2))
                });
        }
        if !has_data {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
}

/// Residuals (measured − predicted, normalised by the caller) against `x` (typically the life
/// fraction t/t_f), one colour per series: markers joined by a thin line in x order, plus a
/// black zero line. The y axis always includes 0.
pub fn plot_residuals(
    path: &Path,
    title: &str,
    series: &[Series],
    x_label: &str,
    y_label: &str,
) -> Result<()> {
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let x_range = padded(data_range(xs).unwrap_or((0.0, 1.0)), 0.03);
    let y_range = padded(data_range(ys.chain([0.0])).unwrap_or((-1.0, 1.0)), 0.05);
    let has_data = series
        .iter()
        .any(|s| s.points.iter().any(|&p| plottable(p)));

    render(path, |root| {
        let mut chart = chart_builder(root, title)
            .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
        configure_mesh(&mut chart, x_label, y_label)?;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x_range.0, 0.0), (x_range.1, 0.0)],
            BLACK.stroke_width(1),
        )))?;

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
            chart
                .draw_series(
                    inside(&sorted, x_range, y_range).map(|p| Circle::new(p, 4, color.filled())),
                )?
                .label(label)
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (24, 0)], color.mix(0.45).stroke_width(1))
                        + Circle::new((12, 0), 4, color.filled())
                });
        }
        if !has_data {
            no_data(&mut chart, (mid(x_range), mid(y_range)))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// Sorted objective against rank (1 = best), log-scale y: the multistart "waterfall". Ranks
/// are the 1-based positions in `objectives_sorted`; non-finite values (failed starts) are
/// skipped, non-positive ones are shown at a floor (100× below the smallest positive value)
/// as red triangles, the best point is drawn in red.
pub fn plot_waterfall(path: &Path, title: &str, objectives_sorted: &[f64]) -> Result<()> {
    let n = objectives_sorted.len();
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
    let x_ticks = integer_ticks(n.max(1), 10);

    render(path, |root| {
        let mut chart = chart_builder(root, title).build_cartesian_2d(
            FixedTicks::new(x_range, x_ticks),
            (y_range.0..y_range.1).log_scale(),
        )?;
        chart
            .configure_mesh()
            .x_desc("rank (1 = best)")
            .y_desc("objective (log scale)")
            .x_label_formatter(&|v| format!("{}", v.round() as i64))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .y_labels(12)
            .axis_desc_style((FONT, AXIS_DESC_SIZE))
            .label_style((FONT, TICK_SIZE))
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(BLACK.mix(0.04))
            .draw()?;

        let color = PALETTE[0];
        chart.draw_series(std::iter::once(PathElement::new(
            line.clone(),
            color.stroke_width(2),
        )))?;
        let marker = if n <= 200 { 4 } else { 2 };
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| !p.2)
                    .map(|p| Circle::new((p.0, p.1), marker, color.filled())),
            )?
            .label(format!("objective ({} of {n} runs finite)", pts.len()))
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (24, 0)], color.stroke_width(2))
                    + Circle::new((12, 0), 4, color.filled())
            });
        if let Some(best) = pts.first().filter(|p| p.0 == 1.0) {
            chart
                .draw_series(std::iter::once(Circle::new(
                    (best.0, best.1),
                    7,
                    PALETTE[3].filled(),
                )))?
                .label("best")
                .legend(|(x, y)| Circle::new((x + 12, y), 6, PALETTE[3].filled()));
        }
        if n_clamped > 0 {
            chart
                .draw_series(
                    pts.iter()
                        .filter(|p| p.2)
                        .map(|p| TriangleMarker::new((p.0, p.1), 6, PALETTE[3].filled())),
                )?
                .label(format!("{n_clamped} value(s) ≤ 0, shown at {floor:.1e}"))
                .legend(|(x, y)| TriangleMarker::new((x + 12, y), 6, PALETTE[3].filled()));
        }
        if pts.is_empty() {
            no_data(&mut chart, (mid(x_range), (y_range.0 * y_range.1).sqrt()))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
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
    let names: Vec<String> = names.to_vec();

    render(path, |root| {
        let x_ticks: Vec<f64> = (0..n).map(|j| j as f64).collect();
        let mut chart = chart_builder(root, title).build_cartesian_2d(
            FixedTicks::new(x_range, x_ticks),
            FixedTicks::new((lo, hi), vec![0.0, 0.25, 0.5, 0.75, 1.0]),
        )?;
        let formatter = |v: &f64| {
            let j = v.round();
            if (v - j).abs() < 1e-6 && j >= 0.0 {
                names.get(j as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_desc("constant")
            .y_desc("scaled position u in bounds")
            .x_label_formatter(&formatter)
            .y_label_formatter(&|v| format!("{v:.2}"))
            .axis_desc_style((FONT, AXIS_DESC_SIZE))
            .label_style((FONT, TICK_SIZE))
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(BLACK.mix(0.0))
            .draw()?;
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
            let anno = chart.draw_series(
                inside(&pts, x_range, (lo, hi)).map(|p| Circle::new(p, 4, color.filled())),
            )?;
            if r == 1 {
                let label = if k > 2 {
                    format!("ranks 2–{k}")
                } else {
                    "rank 2".to_string()
                };
                let c0 = rank_color(0.0);
                let c1 = rank_color(1.0);
                anno.label(label).legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + Circle::new((4, 0), 4, c0.filled())
                        + Circle::new((20, 0), 4, c1.filled())
                });
            }
        }
        if let Some(best) = scaled_solutions.first() {
            let red = PALETTE[3];
            let pts = polyline(best);
            chart.draw_series(
                clip_polyline(&pts, x_range, (lo, hi))
                    .into_iter()
                    .map(|piece| PathElement::new(piece, red.stroke_width(3))),
            )?;
            chart
                .draw_series(
                    inside(&pts, x_range, (lo, hi)).map(|p| Circle::new(p, 6, red.filled())),
                )?
                .label("best")
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (24, 0)], red.stroke_width(3))
                        + Circle::new((12, 0), 6, red.filled())
                });
        }
        if n == 0 || k == 0 {
            no_data(&mut chart, (mid(x_range), 0.5))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

// ---------------------------------------------------------------------------------------------
// Drawing infrastructure

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;
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
/// failed plot leaves no half-drawn file behind.
fn render<F>(path: &Path, draw: F) -> Result<()>
where
    F: FnOnce(&Root<'_>) -> DrawResult,
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
    let drawn = catch_unwind(AssertUnwindSafe(|| -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    }));
    match drawn {
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
        Error::Io { source, .. } => Error::plot(path, source.to_string()),
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
    output::persist(tmp, path).map_err(plot_err)
}

fn chart_builder<'a, 'b>(
    root: &'a Root<'b>,
    title: &str,
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(root);
    builder
        .margin(20)
        .x_label_area_size(65)
        .y_label_area_size(95);
    if !title.trim().is_empty() {
        builder.caption(title, (FONT, TITLE_SIZE));
    }
    builder
}

type Chart2d<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

fn configure_mesh(chart: &mut Chart2d<'_, '_>, x_desc: &str, y_desc: &str) -> DrawResult {
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(10)
        .y_labels(10)
        .axis_desc_style((FONT, AXIS_DESC_SIZE))
        .label_style((FONT, TICK_SIZE))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(BLACK.mix(0.04))
        .draw()?;
    Ok(())
}

fn draw_legend<'a, 'b: 'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'b>, Cartesian2d<X, Y>>,
    position: SeriesLabelPosition,
) -> DrawResult
where
    X: Ranged,
    Y: Ranged,
{
    chart
        .configure_series_labels()
        .position(position)
        .margin(12)
        .legend_area_size(34)
        .label_font((FONT, LEGEND_SIZE))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .draw()?;
    Ok(())
}

/// A linear f64 axis whose ticks (and vertical/horizontal grid lines) are exactly the given
/// values, with no light grid lines. (plotters' `with_key_points` cannot be used with
/// `configure_mesh` for f64 axes.)
#[derive(Clone)]
struct FixedTicks {
    inner: RangedCoordf64,
    ticks: Vec<f64>,
}

impl FixedTicks {
    fn new((lo, hi): (f64, f64), ticks: Vec<f64>) -> Self {
        FixedTicks {
            inner: (lo..hi).into(),
            ticks: ticks
                .into_iter()
                .filter(|t| (lo..=hi).contains(t))
                .collect(),
        }
    }
}

impl Ranged for FixedTicks {
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

impl ValueFormatter<f64> for FixedTicks {
    fn format(value: &f64) -> String {
        RangedCoordf64::format(value)
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
        let err = render(&path, |_| panic!("inside plotters")).unwrap_err();
        assert!(err.to_string().contains("inside plotters"), "{err}");
        let err = render(&path, |_| Err("drawing failed".into())).unwrap_err();
        assert!(err.to_string().contains("drawing failed"), "{err}");
        assert!(!path.exists(), "no file is written for a failed plot");
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
