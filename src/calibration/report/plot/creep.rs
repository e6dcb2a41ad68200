//! Measured against predicted creep curves (`fit.png`, `simulate.png`, `curves.png` of
//! `predict` and `holdout`): the paper's Figures 6/7, one panel per temperature or stress
//! group.

use std::path::Path;

use super::canvas::{draw_figure, Axis, Drawn, Layer, PanelSpec};
use super::facet::{facets, Facet, MAX_PER_PANEL};
use super::geom::{cut_polyline, data_range, from_zero, plottable, thin_markers};
use super::style::{Entry, MarkerShape, Rgb, Style};
use super::ticks::Ticks;
use super::{AxisScale, CurveId};
use crate::error::Result;

/// Predicted curves are drawn up to this multiple of their panel's measured extent (in time
/// and in strain); a curve running further is cut there and its end marked with an arrow.
pub const PREDICTED_EXTENT: f64 = 3.0;
/// Most markers drawn per measured curve (evenly by index; the axes still cover every
/// measured point).
pub const MAX_MARKERS: usize = 60;

/// One test for [`plot_creep_curves`]: measured points (markers) and the predicted curve
/// (a line) in one colour.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CurvePlot {
    /// Temperature, stress and specimen: the panel and the legend entry.
    pub id: CurveId,
    /// Measured (time h, strain %).
    pub measured: Vec<(f64, f64)>,
    /// Predicted (time h, strain %), dense enough to look smooth, in time order.
    pub predicted: Vec<(f64, f64)>,
}

/// Measured (markers) against predicted (lines) creep curves, a colour per test, a panel per
/// temperature (split into stress groups beyond [`MAX_PER_PANEL`] curves) with a legend
/// naming every test. Axes "time (h)" and "strain (%)" from 0, covering every measured point
/// and every predicted curve as drawn: a prediction is drawn to its end (its rupture) unless
/// it runs beyond [`PREDICTED_EXTENT`] × the panel's measured extent, where it is cut and
/// marked (without measured points the predictions set the axes).
pub fn plot_creep_curves(path: &Path, title: &str, curves: &[CurvePlot]) -> Result<()> {
    draw_creep_curves(path, title, curves).map(|_| ())
}

pub(super) fn draw_creep_curves(path: &Path, title: &str, curves: &[CurvePlot]) -> Result<Drawn> {
    draw_figure(path, title, &creep_panels(curves))
}

/// The panels of [`plot_creep_curves`].
pub(super) fn creep_panels(curves: &[CurvePlot]) -> Vec<PanelSpec> {
    let ids: Vec<CurveId> = curves.iter().map(|c| c.id.clone()).collect();
    let groups = facets(&ids, MAX_PER_PANEL);
    if groups.is_empty() {
        return vec![creep_panel(
            &Facet {
                caption: String::new(),
                members: vec![],
            },
            curves,
        )];
    }
    groups.iter().map(|f| creep_panel(f, curves)).collect()
}

fn creep_panel(f: &Facet, curves: &[CurvePlot]) -> PanelSpec {
    let members: Vec<&CurvePlot> = f.members.iter().map(|&i| &curves[i]).collect();
    let measured = || members.iter().flat_map(|c| c.measured.iter().copied());
    // Where predictions are cut: a multiple of the measured extent (none without data).
    let limit = |v: Option<(f64, f64)>| match v {
        Some((lo, hi)) if lo.abs().max(hi.abs()) > 0.0 => PREDICTED_EXTENT * lo.abs().max(hi.abs()),
        _ => f64::INFINITY,
    };
    let x_max = limit(data_range(measured().map(|p| p.0)));
    let y_max = limit(data_range(measured().map(|p| p.1)));

    let mut layers = Vec::new();
    let mut entries = Vec::new();
    let mut drawn: Vec<(f64, f64)> = measured().collect();
    let mut any_cut = false;
    for (k, c) in members.iter().enumerate() {
        let color = Rgb::palette(k);
        let (predicted, cut) = cut_polyline(&c.predicted, x_max, y_max);
        drawn.extend(predicted.iter().copied());
        if cut {
            any_cut = true;
            if let Some(&end) = predicted.iter().rev().find(|p| plottable(**p)) {
                layers.push(Layer {
                    line: vec![],
                    points: vec![end],
                    style: Style::points(color, MarkerShape::Arrow, 7),
                });
            }
        }
        layers.push(Layer {
            line: predicted,
            points: vec![],
            style: Style::line(color, 2),
        });
        layers.push(Layer {
            line: vec![],
            points: thin_markers(&c.measured, MAX_MARKERS),
            style: Style::points(color, MarkerShape::Circle, 4),
        });
        entries.push(Entry::styled(
            c.id.label(),
            Style::line(color, 2).with_marker(MarkerShape::Circle, 4),
        ));
    }
    if !members.is_empty() {
        entries.push(Entry::styled(
            "measured",
            Style::points(Rgb::BLACK, MarkerShape::Circle, 4),
        ));
        entries.push(Entry::styled("predicted", Style::line(Rgb::BLACK, 2)));
    }
    if any_cut {
        entries.push(Entry::styled(
            format!("prediction cut at {PREDICTED_EXTENT}× the measured extent"),
            Style::points(Rgb::BLACK, MarkerShape::Arrow, 7),
        ));
    }
    let x = from_zero(data_range(drawn.iter().map(|p| p.0)), 0.03);
    let y = from_zero(data_range(drawn.iter().map(|p| p.1)), 0.04);
    PanelSpec {
        caption: f.caption.clone(),
        x: Axis {
            range: x,
            ticks: Ticks::for_axis(x, AxisScale::Linear),
            desc: "time (h)".into(),
        },
        y: Axis {
            range: y,
            ticks: Ticks::for_axis(y, AxisScale::Linear),
            desc: "strain (%)".into(),
        },
        layers,
        labels: vec![],
        entries,
        no_data: !drawn.iter().any(|p| plottable(*p)),
    }
}
