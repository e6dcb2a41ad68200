//! A constant's profile likelihood (`profile_<constant>.png` of `profile`).

use std::path::Path;

use super::canvas::{draw_figure, Axis, Drawn, Layer, PanelSpec};
use super::geom::{data_range, padded, plottable, plottable_value};
use super::style::{Dash, Entry, Line, MarkerShape, Rgb, Style};
use super::ticks::Ticks;
use super::AxisScale;
use crate::error::Result;

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
    draw_profile(path, title, p).map(|_| ())
}

pub(super) fn draw_profile(path: &Path, title: &str, p: &ProfilePlot) -> Result<Drawn> {
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
    let x = padded(data_range(xs).unwrap_or((0.0, 1.0)), 0.04);
    let y_top = 1.3 * t_max;
    let y = (-0.04 * y_top, y_top);
    let mut pts: Vec<(f64, f64)> = p.points.iter().copied().filter(|&q| plottable(q)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));

    let mut layers = Vec::new();
    let mut entries = Vec::new();
    for (i, (label, t)) in p.thresholds.iter().enumerate() {
        let style = Style::dashed(Rgb::palette(i + 1), 2);
        layers.push(Layer {
            line: vec![(x.0, *t), (x.1, *t)],
            points: vec![],
            style,
        });
        entries.push(Entry::styled(label.clone(), style));
    }
    let bound_style = Style {
        color: Rgb(77, 77, 77),
        line: Some(Line {
            width: 2,
            dash: Dash::Dotted,
            opacity: 1.0,
        }),
        marker: None,
    };
    let bounds: Vec<f64> = [p.bounds.0, p.bounds.1]
        .into_iter()
        .filter(|b| b.is_finite() && *b >= x.0 && *b <= x.1)
        .collect();
    for &b in &bounds {
        layers.push(Layer {
            line: vec![(b, y.0), (b, y.1)],
            points: vec![],
            style: bound_style,
        });
    }
    if !bounds.is_empty() {
        entries.push(Entry::styled("bound", bound_style));
    }
    let color = Rgb::palette(0);
    let profile = Style::line(color, 2).with_marker(MarkerShape::Circle, 4);
    layers.push(Layer {
        line: pts.clone(),
        points: pts.clone(),
        style: profile,
    });
    entries.push(Entry::styled("profile (others re-fitted)", profile));
    if plottable_value(p.estimate) {
        let style = Style::points(Rgb::RED, MarkerShape::Circle, 7);
        layers.push(Layer {
            line: vec![],
            points: vec![(p.estimate, 0.0)],
            style,
        });
        entries.push(Entry::styled("estimate", style));
    }
    if !p.failed.is_empty() {
        let style = Style::points(Rgb::RED, MarkerShape::Triangle, 7);
        layers.push(Layer {
            line: vec![],
            points: p.failed.iter().map(|&f| (f, 0.0)).collect(),
            style,
        });
        entries.push(Entry::styled(
            format!("{} failed fit(s)", p.failed.len()),
            style,
        ));
    }
    let panel = PanelSpec {
        caption: String::new(),
        x: Axis {
            range: x,
            ticks: Ticks::for_axis(x, AxisScale::Linear),
            desc: p.x_label.clone(),
        },
        y: Axis {
            range: y,
            ticks: Ticks::for_axis(y, AxisScale::Linear),
            desc: "Δ(−2 ln L)".into(),
        },
        no_data: pts.is_empty(),
        layers,
        labels: vec![],
        entries,
    };
    draw_figure(path, title, &[panel])
}
