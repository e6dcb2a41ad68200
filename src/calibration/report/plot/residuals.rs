//! Residuals against a common x (the life fraction t/t_f for `diagnose`'s
//! `residuals_*.png`, one panel per temperature or stress group; any labelled series for
//! `battery`'s `power.png`, one panel).

use std::path::Path;

use super::canvas::{draw_figure, Axis, Drawn, Layer, PanelSpec};
use super::facet::{facets, MAX_PER_PANEL};
use super::geom::{data_range, padded, plottable, thin_markers};
use super::style::{Dash, Entry, Line, Marker, MarkerShape, Rgb, Style};
use super::ticks::Ticks;
use super::{AxisScale, CurveId};
use crate::error::Result;

/// A labelled set of (x, y) points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// The residuals of one test for [`plot_curve_residuals`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CurveSeries {
    pub id: CurveId,
    pub points: Vec<(f64, f64)>,
}

/// Residuals against `x`, one colour per series, all in one panel: markers joined by a thin
/// line in x order, plus a black zero line; the y axis always includes 0. The residuals are
/// whatever the caller computed, whose `y_label` states it.
pub fn plot_residuals(
    path: &Path,
    title: &str,
    series: &[Series],
    x_label: &str,
    y_label: &str,
) -> Result<()> {
    draw_residuals(path, title, series, x_label, y_label).map(|_| ())
}

pub(super) fn draw_residuals(
    path: &Path,
    title: &str,
    series: &[Series],
    x_label: &str,
    y_label: &str,
) -> Result<Drawn> {
    let items: Vec<(String, &[(f64, f64)])> = series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let label = if s.label.trim().is_empty() {
                format!("series {}", i + 1)
            } else {
                s.label.clone()
            };
            (label, s.points.as_slice())
        })
        .collect();
    let panel = residual_panel(String::new(), &items, x_label, y_label);
    draw_figure(path, title, &[panel])
}

/// Residuals of tests (predicted − measured, normalised as `y_label` states) against `x`
/// (t/t_f for `diagnose`): as [`plot_residuals`], in a panel per temperature (split into
/// stress groups beyond [`MAX_PER_PANEL`] curves) whose legend names temperature, stress and
/// specimen of each test. Each panel's y axis covers its own residuals and 0.
pub fn plot_curve_residuals(
    path: &Path,
    title: &str,
    series: &[CurveSeries],
    x_label: &str,
    y_label: &str,
) -> Result<()> {
    draw_figure(
        path,
        title,
        &curve_residual_panels(series, x_label, y_label),
    )
    .map(|_| ())
}

pub(super) fn curve_residual_panels(
    series: &[CurveSeries],
    x_label: &str,
    y_label: &str,
) -> Vec<PanelSpec> {
    let ids: Vec<CurveId> = series.iter().map(|s| s.id.clone()).collect();
    let groups = facets(&ids, MAX_PER_PANEL);
    if groups.is_empty() {
        return vec![residual_panel(String::new(), &[], x_label, y_label)];
    }
    groups
        .iter()
        .map(|f| {
            let items: Vec<(String, &[(f64, f64)])> = f
                .members
                .iter()
                .map(|&i| (series[i].id.label(), series[i].points.as_slice()))
                .collect();
            residual_panel(f.caption.clone(), &items, x_label, y_label)
        })
        .collect()
}

/// One residual panel: a zero line, and each (label, points) as markers joined in x order.
fn residual_panel(
    caption: String,
    items: &[(String, &[(f64, f64)])],
    x_label: &str,
    y_label: &str,
) -> PanelSpec {
    let all = || items.iter().flat_map(|(_, p)| p.iter().copied());
    let x = padded(data_range(all().map(|p| p.0)).unwrap_or((0.0, 1.0)), 0.03);
    let y = padded(
        data_range(all().map(|p| p.1).chain([0.0])).unwrap_or((-1.0, 1.0)),
        0.05,
    );
    let mut layers = vec![Layer {
        line: vec![(x.0, 0.0), (x.1, 0.0)],
        points: vec![],
        style: Style::line(Rgb::BLACK, 1),
    }];
    let mut entries = Vec::new();
    for (k, (label, points)) in items.iter().enumerate() {
        let color = Rgb::palette(k);
        let mut sorted: Vec<(f64, f64)> =
            points.iter().copied().filter(|&p| plottable(p)).collect();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let style = Style {
            color,
            line: Some(Line {
                width: 1,
                dash: Dash::Solid,
                opacity: 0.45,
            }),
            marker: Some(Marker {
                shape: MarkerShape::Circle,
                size: 3,
            }),
        };
        layers.push(Layer {
            points: thin_markers(&sorted, MAX_RESIDUAL_MARKERS),
            line: sorted,
            style,
        });
        entries.push(Entry::styled(label.clone(), style));
    }
    PanelSpec {
        caption,
        x: Axis {
            range: x,
            ticks: Ticks::for_axis(x, AxisScale::Linear),
            desc: x_label.to_string(),
        },
        y: Axis {
            range: y,
            ticks: Ticks::for_axis(y, AxisScale::Linear),
            desc: y_label.to_string(),
        },
        no_data: !all().any(plottable),
        layers,
        labels: vec![],
        entries,
    }
}

/// Most markers per residual series (the line joins every point).
const MAX_RESIDUAL_MARKERS: usize = 80;
