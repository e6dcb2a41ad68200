//! `simulate`: the measured tests simulated at given constants, each to its rupture or to
//! the integration horizon ([`crate::model::objective::curve_horizon`]), with a dense trajectory
//! for the curve files and plots. The computation and its tables (curves.csv, ruptures.csv,
//! objective.json): `crate::export::simulate` writes them, the Python package returns them.

use crate::data::{Curve, Dataset};
use crate::model::objective::{Evaluation, Objective, ObjectiveSettings};
use crate::model::{Load, Model};
use crate::ode::{OdeOptions, SimResult};
use crate::report::tables::{num, with_specimen};

/// Points of the dense time grid of each simulated curve (besides the measured times).
pub const GRID_POINTS: usize = 200;

/// One measured test simulated.
pub struct Simulated<'a> {
    /// The measured curve whose load (temperature, stress, specimen) was simulated.
    pub curve: &'a Curve,
    /// How the simulation ended (rupture time h, strain and minimum rate as fractions).
    pub result: SimResult,
    /// (time h, strain fraction, the model's outputs) on the dense grid and the measured
    /// times up to the end of the simulation.
    pub trajectory: Vec<(f64, f64, Vec<f64>)>,
}

impl Simulated<'_> {
    /// The minimum creep rate (1/h) when it is one: a rupture or the horizon reached. A
    /// failed simulation has none.
    pub fn min_rate(&self) -> Option<f64> {
        (self.result.ruptured() || self.result.outcome == crate::ode::Outcome::Horizon)
            .then_some(self.result.min_rate)
    }
}

/// Every curve of `data` simulated at `params` (`omega_f`: the rupture damage of the loads).
pub fn simulate<'a>(
    model: &dyn Model,
    params: &[f64],
    data: &'a Dataset,
    omega_f: f64,
    ode: &OdeOptions,
) -> Vec<Simulated<'a>> {
    data.curves
        .iter()
        .map(|c| {
            let load = Load::of_curve(c, omega_f);
            let o = crate::model::objective::curve_horizon(c, ode);
            let result = model.simulate(params, &load, &[], &mut [], &o);
            let mut grid = crate::predict::dense_grid(result.t_end, GRID_POINTS);
            grid.extend(c.times_h.iter().copied().filter(|t| *t <= result.t_end));
            grid.sort_by(|a, b| a.total_cmp(b));
            grid.dedup();
            let (_, trajectory) = model.trajectory(params, &load, &grid, &o);
            Simulated {
                curve: c,
                result,
                trajectory,
            }
        })
        .collect()
}

/// The eq. 8 objective at `params` with one lifetime weight `w` on every curve.
pub fn objective_at(
    model: &dyn Model,
    data: &Dataset,
    params: &[f64],
    w: f64,
    settings: ObjectiveSettings,
) -> Evaluation {
    Objective::new(model, &data.curves, vec![w; data.curves.len()], settings).evaluate(params)
}

/// Whether a simulated test has a specimen label: the tables then end with a `specimen`
/// column.
fn has_specimens(sims: &[Simulated]) -> bool {
    sims.iter().any(|s| s.curve.specimen.is_some())
}

/// `ruptures.csv`'s columns before the `specimen` column (present when a curve has one).
pub const RUPTURES_COLUMNS: [&str; 6] = [
    "temperature_C",
    "stress_MPa",
    "rupture_time_h",
    "rupture_strain_pct",
    "min_rate_pct_per_h",
    "outcome",
];

/// `ruptures.csv`: each simulated test's rupture time (h) and strain (%) where it ruptured,
/// its minimum rate (%/h) where it has one, and how the simulation ended (header, rows).
pub fn ruptures_table(sims: &[Simulated]) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let specimens = has_specimens(sims);
    let rows = sims
        .iter()
        .map(|s| {
            let (c, res) = (s.curve, &s.result);
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                if res.ruptured() {
                    num(res.t_end)
                } else {
                    String::new()
                },
                if res.ruptured() {
                    num(100.0 * res.strain_end)
                } else {
                    String::new()
                },
                // A failed simulation has no minimum rate (only a rupture or the horizon do).
                s.min_rate().map(|r| num(100.0 * r)).unwrap_or_default(),
                res.outcome.as_str().to_string(),
            ];
            if specimens {
                row.push(c.specimen.clone().unwrap_or_default());
            }
            row
        })
        .collect();
    (with_specimen(&RUPTURES_COLUMNS, specimens), rows)
}

/// `curves.csv`'s header: the load, time (h) and strain (%), the model's outputs (H, Phi,
/// omega for KHD), and `specimen` when a simulated test has one.
pub fn curves_header(model: &dyn Model, sims: &[Simulated]) -> Vec<String> {
    let mut h: Vec<String> = ["temperature_C", "stress_MPa", "time_h", "strain_pct"]
        .map(String::from)
        .to_vec();
    h.extend(model.output_names().iter().map(|n| n.to_string()));
    if has_specimens(sims) {
        h.push("specimen".into());
    }
    h
}

/// `curves.csv`'s rows ([`curves_header`]), one per trajectory point, formatted as they are
/// written: an iterator, since a logged curve gives a million of them.
pub fn curves_rows<'a>(sims: &'a [Simulated]) -> impl Iterator<Item = Vec<String>> + 'a {
    let specimens = has_specimens(sims);
    sims.iter().flat_map(move |s| {
        let c = s.curve;
        s.trajectory.iter().map(move |(t, e, y)| {
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(*t),
                num(100.0 * e),
            ];
            row.extend(y.iter().map(|v| num(*v)));
            if specimens {
                row.push(c.specimen.clone().unwrap_or_default());
            }
            row
        })
    })
}

/// `objective.json`: the eq. 8 objective `e` at the one lifetime weight `w`, its normalised
/// residual and each curve's lifetime error (%).
pub fn objective_json(data: &Dataset, w: f64, e: &Evaluation) -> serde_json::Value {
    serde_json::json!({
        "w": w,
        "objective": e.objective,
        "norm_residual": e.norm_residual,
        "lifetime_errors_pct": e.lifetime_errors_pct(&data.curves),
    })
}
