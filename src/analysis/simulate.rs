//! `simulate`: the measured tests simulated at given constants, each to its rupture or to
//! the integration horizon ([`crate::model::objective::curve_horizon`]), with a dense trajectory
//! for the curve files and plots. The computation only: `crate::export::simulate` writes it.

use crate::data::{Curve, Dataset};
use crate::model::objective::{Evaluation, Objective, ObjectiveSettings};
use crate::model::{Load, Model};
use crate::ode::{OdeOptions, SimResult};

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
