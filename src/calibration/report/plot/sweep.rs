//! The plots of `sweep`: the multistart "waterfall" of objectives (`waterfall.png`) and the
//! spread of the best constants within their bounds (`parameters.png`).

use std::path::Path;

use super::canvas::{draw_figure, Axis, Drawn, Label, Layer, PanelSpec};
use super::geom::{integer_ticks, log_range, plottable, LOG_MIN, MAX_ABS};
use super::style::{Dash, Entry, Line, MarkerShape, Rgb, Style, Swatch};
use super::ticks::Ticks;
use super::AxisScale;
use crate::error::{Error, Result};

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
pub(super) fn counts_note(c: RunCounts) -> String {
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
    draw_waterfall(path, title, objectives_sorted).map(|_| ())
}

pub(super) fn draw_waterfall(path: &Path, title: &str, objectives_sorted: &[f64]) -> Result<Drawn> {
    draw_figure(path, title, &[waterfall_panel(objectives_sorted)])
}

fn waterfall_panel(objectives_sorted: &[f64]) -> PanelSpec {
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
    let (ylo, yhi) = log_range(pts.iter().map(|p| p.1));
    // In log10 coordinates; values below the axis sit at its floor, marked as clamped.
    let pts: Vec<(f64, f64, bool)> = pts
        .into_iter()
        .map(|(r, v, c)| {
            if v < ylo {
                (r, ylo.log10(), true)
            } else {
                (r, v.log10(), c)
            }
        })
        .collect();
    let y = (ylo.log10(), yhi.log10());
    let x = (0.5, n.max(1) as f64 + 0.5);
    let n_clamped = pts.iter().filter(|p| p.2).count();
    let xt = integer_ticks(n.max(1), 10);
    let xt = Ticks {
        labels: xt.iter().map(|v| format!("{}", v.round() as i64)).collect(),
        values: xt,
    };
    let color = Rgb::palette(0);
    let red = Rgb::RED;
    let marker = if n <= 200 { 4 } else { 2 };
    let each = Style::line(color, 2).with_marker(MarkerShape::Circle, marker);
    let mut layers = vec![
        Layer {
            line: pts.iter().map(|p| (p.0, p.1)).collect(),
            points: vec![],
            style: Style::line(color, 2),
        },
        Layer {
            line: vec![],
            points: pts.iter().filter(|p| !p.2).map(|p| (p.0, p.1)).collect(),
            style: Style::points(color, MarkerShape::Circle, marker),
        },
    ];
    let mut entries = vec![Entry::styled("objective of each fit", each)];
    if let Some(best) = pts.first().filter(|p| p.0 == 1.0) {
        let style = Style::points(red, MarkerShape::Circle, 7);
        layers.push(Layer {
            line: vec![],
            points: vec![(best.0, best.1)],
            style,
        });
        entries.push(Entry::styled(
            format!("best: {}", significant(objectives_sorted[0], 6)),
            style,
        ));
    }
    if n_clamped > 0 {
        let style = Style::points(red, MarkerShape::Triangle, 6);
        layers.push(Layer {
            line: vec![],
            points: pts.iter().filter(|p| p.2).map(|p| (p.0, p.1)).collect(),
            style,
        });
        entries.push(Entry::styled(
            format!("{n_clamped} value(s) ≤ 0, shown at {floor:.1e}"),
            style,
        ));
    }
    entries.push(Entry::note(counts_note(counts)));
    PanelSpec {
        caption: String::new(),
        x: Axis {
            range: x,
            ticks: xt,
            desc: "rank (1 = best)".into(),
        },
        y: Axis {
            range: y,
            ticks: Ticks::for_axis(y, AxisScale::Log),
            desc: "objective (log scale)".into(),
        },
        no_data: pts.is_empty(),
        layers,
        labels: vec![],
        entries,
    }
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
    draw_parameters(path, title, names, scaled_solutions).map(|_| ())
}

pub(super) fn draw_parameters(
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
    let x = (-0.5, n.max(1) as f64 - 0.5);
    let k = scaled_solutions.len();
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
    let grey = Rgb(102, 102, 102);
    let mut layers = Vec::new();
    let mut labels = Vec::new();
    for (u, text) in [(0.0, "lower bound"), (1.0, "upper bound")] {
        layers.push(Layer {
            line: vec![(x.0, u), (x.1, u)],
            points: vec![],
            style: Style {
                color: grey,
                line: Some(Line {
                    width: 1,
                    dash: Dash::Dashed,
                    opacity: 1.0,
                }),
                marker: None,
            },
        });
        labels.push(Label {
            text: text.into(),
            at: (x.1, u),
            below: u < 0.5,
            color: grey,
        });
    }
    // Worst first so that better solutions are drawn on top.
    for r in (1..k).rev() {
        let t = if k > 2 {
            (r - 1) as f64 / (k - 2) as f64
        } else {
            0.0
        };
        let pts = polyline(&scaled_solutions[r]);
        layers.push(Layer {
            line: pts.clone(),
            points: pts,
            style: Style::line(rank_color(t), 1).with_marker(MarkerShape::Circle, 4),
        });
    }
    let mut entries = Vec::new();
    if let Some(best) = scaled_solutions.first() {
        let style = Style::line(Rgb::RED, 3).with_marker(MarkerShape::Circle, 6);
        let pts = polyline(best);
        layers.push(Layer {
            line: pts.clone(),
            points: pts,
            style,
        });
        entries.push(Entry::styled("best", style));
    }
    if k > 1 {
        let label = if k > 2 {
            format!("ranks 2–{k} (dark to light)")
        } else {
            "rank 2".to_string()
        };
        entries.push(Entry::new(
            label,
            Swatch::Range(rank_color(0.0), rank_color(1.0)),
        ));
    }
    let panel = PanelSpec {
        caption: String::new(),
        x: Axis {
            range: x,
            ticks: Ticks {
                values: (0..n).map(|j| j as f64).collect(),
                labels: names.to_vec(),
            },
            desc: "constant".into(),
        },
        y: Axis {
            range: (lo, hi),
            ticks: Ticks::of(
                [0.0, 0.25, 0.5, 0.75, 1.0]
                    .iter()
                    .map(|&v| (v, format!("{v:.2}")))
                    .collect(),
            ),
            desc: "scaled position u in bounds".into(),
        },
        no_data: n == 0
            || k == 0
            || !scaled_solutions
                .iter()
                .any(|s| polyline(s).into_iter().any(plottable)),
        layers,
        labels,
        entries,
    };
    draw_figure(path, title, &[panel])
}

/// Dark blue (t = 0, rank 2) to light grey-blue (t = 1, worst rank).
fn rank_color(t: f64) -> Rgb {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + (b - a) * t).round() as u8;
    Rgb(lerp(31.0, 185.0), lerp(70.0, 200.0), lerp(140.0, 222.0))
}
