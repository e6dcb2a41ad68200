//! PNG plots of calibration results: measured against predicted creep curves, residuals,
//! engineering diagrams (stress–rupture, Norton, Larson–Miller; [`crate::predict::diagrams`]),
//! the multistart "waterfall", the spread of the best constants and profile likelihoods.
//!
//! Every exporter builds `canvas::PanelSpec`s (pure: axes, series, legend entries) and draws
//! them with `canvas::draw_figure`:
//! - Many curves are split into panels (`facet.rs`): one per temperature, a temperature with
//!   more than [`MAX_PER_PANEL`] curves split into groups of neighbouring stresses; each panel
//!   has its own legend naming temperature, stress and specimen of every curve in it.
//! - A legend never leaves an entry out and never covers data: it sits beside its chart and
//!   the image (or each panel) grows taller when the entries need it (`canvas::layout`).
//! - A legend swatch is the series' own style (`style::Swatch`): a dashed line gets a
//!   dashed swatch, points a point.
//! - The axes cover everything drawn (`geom.rs`); a predicted creep curve running far beyond
//!   the measured ones is cut at [`PREDICTED_EXTENT`] × their extent and marked with an arrow.
//! - Tick labels (`ticks.rs`) use one format per axis: plain numbers while every tick lies
//!   within 1e-3…1e4 in magnitude, powers of ten (`10⁵`, `2×10⁴`) otherwise.
//!
//! A one-panel image is 1200 px wide and at least 700 px high; a grid has panels of 900 ×
//! ≥ 420 px in 2 to 4 columns. Text uses the DejaVu Sans font embedded in the binary, so no
//! system fonts are needed. Non-finite points (and magnitudes above 1e150) are skipped, lines
//! broken at them, degenerate ranges widened, empty inputs give a panel saying "no data", log
//! axes leave out non-positive values. Any drawing or encoding failure, and any panic inside
//! plotters, is returned as [`Error::Plot`](crate::error::Error::Plot); nothing is written
//! unless the whole image was drawn.

mod canvas;
mod creep;
mod facet;
mod geom;
mod profile;
mod residuals;
mod style;
mod sweep;
mod ticks;
mod xy;

pub use canvas::{HEIGHT, LEGEND_WIDTH, PANEL_HEIGHT, PANEL_WIDTH, WIDTH};
pub use creep::{plot_creep_curves, CurvePlot, MAX_MARKERS, PREDICTED_EXTENT};
pub use facet::{MAX_PER_PANEL, PLOT_POINTS};
pub use profile::{plot_profile, ProfilePlot};
pub use residuals::{plot_curve_residuals, plot_residuals, CurveSeries, Series};
pub use style::{temperature_colors, Dash, MarkerShape, Rgb};
pub use sweep::{plot_parameters, plot_waterfall, run_counts, RunCounts};
pub use ticks::{axis_ticks, PLAIN_MAX, PLAIN_MIN};
pub use xy::{plot_xy, XyAxes, XyGroup};

/// Scale of a plot axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisScale {
    Linear,
    Log,
}

/// Which test a curve belongs to: what its panel and its legend entry say.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CurveId {
    /// °C.
    pub temperature_c: f64,
    /// MPa.
    pub stress_mpa: f64,
    pub specimen: Option<String>,
}

impl CurveId {
    /// The test of a measured curve.
    pub fn of(c: &crate::data::Curve) -> CurveId {
        CurveId {
            temperature_c: c.temperature_c,
            stress_mpa: c.stress_mpa,
            specimen: c.specimen.clone(),
        }
    }

    /// `850 °C, 30 MPa, KAERI2-a` (without a specimen: `850 °C, 30 MPa`).
    pub fn label(&self) -> String {
        let mut s = format!("{} °C, {} MPa", self.temperature_c, self.stress_mpa);
        if let Some(sp) = self.specimen.as_ref().filter(|s| !s.trim().is_empty()) {
            s.push_str(&format!(", {sp}"));
        }
        s
    }
}

#[cfg(test)]
mod tests;
