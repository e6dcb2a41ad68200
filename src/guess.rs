//! Start points of the local fits: a model's own initial-guess procedure (named in its
//! registry entry, e.g. the KHD procedure of the seed paper's section IV.C in
//! [`crate::model::khd_guess`]), or the centre of the box for a model without one.
//!
//! With constants that follow temperature laws, the guess is made per temperature (the
//! model's procedure on that temperature's curves, in a box that holds every value the law
//! can reach there) and each law is then fitted to those per-temperature values
//! ([`crate::model::law`], e.g. ln c on 1/T for an Arrhenius law).

use serde::Serialize;

use crate::data::Curve;
use crate::model::Model;
use crate::objective::ParamSpace;
use crate::ode::OdeOptions;

/// How a start point was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GuessProcedure {
    /// The model's own procedure (its registry entry's).
    Model,
    /// The model has none: the centre of the box (in the optimiser's scaled coordinates).
    BoxCentre,
    /// The model's procedure per temperature, then each temperature law fitted to the
    /// per-temperature values.
    PerTemperature,
}

/// A model's own initial-guess procedure: constants (model order) for `curves` of one
/// temperature within `space`, with damage at rupture `omega_f` and integration options `ode`.
pub type GuessFn =
    fn(model: &dyn Model, curves: &[Curve], space: &ParamSpace, omega_f: f64, ode: &OdeOptions) -> Guess;

/// What the guess procedure found.
#[derive(Debug, Clone, PartialEq)]
pub struct Guess {
    /// The initial constants, inside the bounds, in the model's order.
    pub params: Vec<f64>,
    /// Minimum creep rate used per curve, 1/h (empty when the procedure uses none).
    pub min_rates: Vec<f64>,
    /// Which constants had to be clamped to a bound.
    pub clamped: Vec<String>,
    /// How the guess was made.
    pub procedure: GuessProcedure,
    /// With temperature laws: the guess at each temperature (°C, the model's constants
    /// there), from which the laws were fitted.
    pub per_temperature: Vec<(f64, Vec<f64>)>,
}

/// The centre of the box (scaled coordinates 0.5): the start of a model without a guess
/// procedure.
pub fn box_centre(space: &ParamSpace) -> Guess {
    let mut x = vec![0.0; space.len()];
    space.from_unit(&vec![0.5; space.n_free()], &mut x);
    Guess {
        params: x,
        min_rates: Vec::new(),
        clamped: Vec::new(),
        procedure: GuessProcedure::BoxCentre,
        per_temperature: Vec::new(),
    }
}

/// The initial guess of `model` on `curves` within `space`: the model's own procedure if its
/// registry entry has one, else the centre of the box.
pub fn initial_guess(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    omega_f: f64,
    ode: &OdeOptions,
) -> Guess {
    match model.guess_procedure() {
        Some(g) => g(model, curves, space, omega_f, ode),
        None => box_centre(space),
    }
}
