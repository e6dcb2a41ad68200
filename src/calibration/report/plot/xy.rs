//! Lines and markers over linear or log axes, one panel: the engineering diagrams
//! (stress–rupture, Norton, Larson–Miller), `holdout`'s parity plot, `predict`'s band plot.

use std::path::Path;

use super::canvas::{draw_figure, Axis, Drawn, Layer, PanelSpec};
use super::geom::{data_range, padded, plottable};
use super::style::{Dash, Entry, Line, Marker, MarkerShape, Rgb, Style};
use super::ticks::Ticks;
use super::AxisScale;
use crate::error::Result;

/// One group of a [`plot_xy`] chart: a line and/or markers in one colour and at most one
/// legend entry, whose swatch is the group's own line (solid or dashed) and marker.
#[derive(Debug, Clone, PartialEq)]
pub struct XyGroup {
    /// Legend label; empty: no entry.
    pub label: String,
    /// Drawn as a line (in the given order) when `stroke` is set.
    pub line: Vec<(f64, f64)>,
    /// Drawn as markers when `marker` is set.
    pub points: Vec<(f64, f64)>,
    pub color: Rgb,
    /// The line's stroke; `None`: no line.
    pub stroke: Option<Dash>,
    /// The markers' shape; `None`: no markers.
    pub marker: Option<MarkerShape>,
}

impl XyGroup {
    /// A solid (or dashed) line.
    pub fn line(
        label: impl Into<String>,
        line: Vec<(f64, f64)>,
        color: Rgb,
        dash: Dash,
    ) -> XyGroup {
        XyGroup {
            label: label.into(),
            line,
            points: vec![],
            color,
            stroke: Some(dash),
            marker: None,
        }
    }
    /// Markers.
    pub fn points(
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
        color: Rgb,
        shape: MarkerShape,
    ) -> XyGroup {
        XyGroup {
            label: label.into(),
            line: vec![],
            points,
            color,
            stroke: None,
            marker: Some(shape),
        }
    }
    /// A legend entry with this look and no data (a key to the styles of the chart).
    pub fn key(
        label: impl Into<String>,
        color: Rgb,
        stroke: Option<Dash>,
        marker: Option<MarkerShape>,
    ) -> XyGroup {
        XyGroup {
            label: label.into(),
            line: vec![],
            points: vec![],
            color,
            stroke,
            marker,
        }
    }

    /// The style the group is drawn in (and its swatch).
    fn style(&self) -> Style {
        let size = match self.marker {
            Some(MarkerShape::Triangle) => 8,
            _ => 5,
        };
        Style {
            color: self.color,
            line: self.stroke.map(|dash| Line {
                width: 2,
                dash,
                opacity: 1.0,
            }),
            marker: self.marker.map(|shape| Marker { shape, size }),
        }
    }
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
/// labels its ticks with the values; non-positive values are left out of it); the axes cover
/// every value drawn, padded by 5 %. The legend lists every labelled group in order.
pub fn plot_xy(path: &Path, title: &str, axes: XyAxes<'_>, groups: &[XyGroup]) -> Result<()> {
    draw_xy(path, title, axes, groups).map(|_| ())
}

pub(super) fn draw_xy(
    path: &Path,
    title: &str,
    axes: XyAxes<'_>,
    groups: &[XyGroup],
) -> Result<Drawn> {
    draw_figure(path, title, &[xy_panel(axes, groups)])
}

/// A value in an axis' coordinate: itself, or log10 of it (NaN for non-positive values).
pub(super) fn to_axis(v: f64, scale: AxisScale) -> f64 {
    match scale {
        AxisScale::Linear => v,
        AxisScale::Log if v > 0.0 => v.log10(),
        AxisScale::Log => f64::NAN,
    }
}

/// The one panel of [`plot_xy`].
pub(super) fn xy_panel(axes: XyAxes<'_>, groups: &[XyGroup]) -> PanelSpec {
    let tr = |pts: &[(f64, f64)]| -> Vec<(f64, f64)> {
        pts.iter()
            .map(|&(x, y)| (to_axis(x, axes.x_scale), to_axis(y, axes.y_scale)))
            .collect()
    };
    let layers: Vec<Layer> = groups
        .iter()
        .map(|g| Layer {
            line: if g.stroke.is_some() {
                tr(&g.line)
            } else {
                vec![]
            },
            points: if g.marker.is_some() {
                tr(&g.points)
            } else {
                vec![]
            },
            style: g.style(),
        })
        .collect();
    let all = || {
        layers
            .iter()
            .flat_map(|l| l.line.iter().chain(&l.points))
            .copied()
    };
    let x = padded(data_range(all().map(|p| p.0)).unwrap_or((0.0, 1.0)), 0.05);
    let y = padded(data_range(all().map(|p| p.1)).unwrap_or((0.0, 1.0)), 0.05);
    let desc = |label: &str, scale: AxisScale| match scale {
        AxisScale::Linear => label.to_string(),
        AxisScale::Log => format!("{label} (log scale)"),
    };
    let entries = groups
        .iter()
        .filter(|g| !g.label.is_empty())
        .map(|g| Entry::styled(g.label.clone(), g.style()))
        .collect();
    PanelSpec {
        caption: String::new(),
        x: Axis {
            range: x,
            ticks: Ticks::for_axis(x, axes.x_scale),
            desc: desc(axes.x_label, axes.x_scale),
        },
        y: Axis {
            range: y,
            ticks: Ticks::for_axis(y, axes.y_scale),
            desc: desc(axes.y_label, axes.y_scale),
        },
        no_data: !all().any(plottable),
        layers,
        labels: vec![],
        entries,
    }
}
