//! Start points of the local fits: a model's own initial-guess procedure (named in its
//! registry entry, e.g. the KHD procedure of the seed paper's section IV.C in
//! [`crate::model::khd_guess`]), or the centre of the box for a model without one.
//!
//! With constants that follow temperature laws, the guess is made per temperature (the
//! model's procedure on that temperature's curves, in a box that holds every value the law
//! can reach there) and each law is then fitted to those per-temperature values
//! ([`crate::model::law`], e.g. ln c on 1/T for an Arrhenius law); with several temperatures
//! the procedure then runs once more per temperature with the constants common to all
//! temperatures held, and the laws are fitted again ([`per_temperature`]).

use serde::Serialize;

use crate::data::Curve;
use crate::model::law::Laws;
use crate::model::objective::ParamSpace;
use crate::model::{LawKind, Model, Scale, ZERO_CELSIUS_K};
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
    /// per-temperature values (twice with several temperatures: the second time with the
    /// common constants held).
    PerTemperature,
}

/// A model's own initial-guess procedure: constants (model order) for `curves` of one
/// temperature within `space`, with damage at rupture `omega_f` and integration options `ode`.
pub type GuessFn = fn(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    omega_f: f64,
    ode: &OdeOptions,
) -> Guess;

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
/// registry entry has one, else the centre of the box; per temperature for a model with
/// temperature laws ([`per_temperature`]).
pub fn initial_guess(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    omega_f: f64,
    ode: &OdeOptions,
) -> Guess {
    model.initial_guess(curves, space, omega_f, ode)
}

/// The guess of a model with temperature laws: `inner`'s own guess at each temperature of
/// `curves` (on that temperature's curves, in a box that holds every value the laws can reach
/// there: the image of the constant's bounds and its law parameter's bounds), then each law
/// fitted to its constant's per-temperature values ([`LawKind::fit`]: e.g. ln c against
/// 1/T − 1/T_ref for an Arrhenius law); a held law parameter keeps its value and only c_ref
/// is fitted. With several temperatures, a second pass runs `inner`'s procedure again at each
/// temperature with the constants that follow no law held at the first pass's values, and
/// fits the laws to those per-temperature values (reported in `per_temperature`). Values
/// outside their bounds are put on them (listed in `clamped`).
pub fn per_temperature(
    inner: &dyn Model,
    laws: &Laws,
    curves: &[Curve],
    space: &ParamSpace,
    omega_f: f64,
    ode: &OdeOptions,
) -> Guess {
    let n = laws.n_inner();
    let specs = inner.constants();
    // Temperatures in ascending order (the curves are sorted by temperature).
    let mut temps: Vec<f64> = Vec::new();
    for c in curves {
        if !temps
            .iter()
            .any(|t| t.to_bits() == c.temperature_c.to_bits())
        {
            temps.push(c.temperature_c);
        }
    }
    let bounds = |j: usize| (space.lb[j], space.ub[j]);
    let param_bounds = |p: usize| {
        if space.free[p] {
            (space.lb[p], space.ub[p])
        } else {
            (space.fixed[p], space.fixed[p])
        }
    };
    // The model's procedure at temperature `t`, with the constants that follow no law held
    // at `common` when given.
    let guess_at = |t: f64, common: Option<&[f64]>| -> Guess {
        let t_k = t + ZERO_CELSIUS_K;
        let group: Vec<Curve> = curves
            .iter()
            .filter(|c| c.temperature_c.to_bits() == t.to_bits())
            .cloned()
            .collect();
        let (mut lb, mut ub) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for j in 0..n {
            let (lo, hi) = match laws.param[j] {
                Some(p) => laws.kinds[j].range_at(bounds(j), param_bounds(p), t_k, laws.t_ref_k),
                None => bounds(j),
            };
            lb.push(lo);
            ub.push(hi);
        }
        let mut t_space = ParamSpace::new(lb, ub, space.scale[..n].to_vec());
        if let Some(x) = common {
            for j in (0..n).filter(|&j| laws.param[j].is_none()) {
                t_space.hold(j, x[j]);
            }
        }
        inner.initial_guess(&group, &t_space, omega_f, ode)
    };
    let mut per_t: Vec<(f64, Vec<f64>)> = Vec::with_capacity(temps.len());
    let mut min_rates = Vec::new();
    let mut clamped: Vec<String> = Vec::new();
    for &t in &temps {
        let g = guess_at(t, None);
        min_rates.extend(g.min_rates.iter().copied());
        for c in g.clamped {
            if !clamped.contains(&c) {
                clamped.push(c);
            }
        }
        per_t.push((t, g.params));
    }
    let t_k: Vec<f64> = temps.iter().map(|t| t + ZERO_CELSIUS_K).collect();
    let mut x: Vec<f64> = (0..space.len())
        .map(|j| {
            if space.free[j] {
                space.from_unit_one(j, 0.5)
            } else {
                space.fixed[j]
            }
        })
        .collect();
    let put = |j: usize, v: f64, x: &mut Vec<f64>, clamped: &mut Vec<String>, name: &str| {
        let (lo, hi) = (space.lb[j], space.ub[j]);
        let c = if v.is_finite() {
            v.clamp(lo, hi)
        } else {
            space.from_unit_one(j, 0.5)
        };
        if c != v && !clamped.iter().any(|s| s == name) {
            clamped.push(name.to_string());
        }
        x[j] = c;
    };
    // Each constant's law fitted to its per-temperature values (`laws_only`: only the
    // constants that follow a law).
    let regress = |per_t: &[(f64, Vec<f64>)],
                   x: &mut Vec<f64>,
                   clamped: &mut Vec<String>,
                   laws_only: bool| {
        for j in 0..n {
            let values: Vec<f64> = per_t.iter().map(|(_, p)| p[j]).collect();
            let log = space.scale[j] == Scale::Log;
            match laws.param[j] {
                None if laws_only => {}
                None => {
                    let (c, _) = LawKind::Constant
                        .fit(&t_k, &values, laws.t_ref_k, Some(0.0), log)
                        .unwrap_or((f64::NAN, 0.0));
                    put(j, c, x, clamped, specs[j].name);
                }
                Some(p) => {
                    let kind = laws.kinds[j];
                    let held = (!space.free[p]).then(|| space.fixed[p]);
                    // One temperature and a free parameter: the parameter from the centre
                    // of its box (it cannot be told from one temperature).
                    let fitted = kind
                        .fit(&t_k, &values, laws.t_ref_k, held, log)
                        .or_else(|| {
                            kind.fit(
                                &t_k[..1],
                                &values[..1],
                                laws.t_ref_k,
                                Some(held.unwrap_or_else(|| space.from_unit_one(p, 0.5))),
                                log,
                            )
                        });
                    let (c, q) = fitted.unwrap_or((f64::NAN, f64::NAN));
                    put(j, c, x, clamped, specs[j].name);
                    if space.free[p] {
                        let name =
                            crate::model::law::param_name(specs[j].name, kind).unwrap_or_default();
                        put(p, q, x, clamped, &name);
                    }
                }
            }
        }
    };
    regress(&per_t, &mut x, &mut clamped, false);
    // Second pass, with several temperatures: the constants common to all temperatures are
    // now one compromise of their per-temperature values, with which the per-temperature
    // values of the others (e.g. A, fitted with each temperature's own B) no longer agree;
    // the procedure is run again per temperature with the common constants held, and the
    // laws fitted to those values. On the seed's 560 + 590 °C data the first pass gave
    // Q_A = 0 and Q_Kc = 1000 kJ/mol (both on bounds; the fit ends at 598 and 0).
    if temps.len() > 1 {
        let common = x.clone();
        per_t = temps
            .iter()
            .map(|&t| (t, guess_at(t, Some(&common)).params))
            .collect();
        regress(&per_t, &mut x, &mut clamped, true);
    }
    Guess {
        params: x,
        min_rates,
        clamped,
        procedure: GuessProcedure::PerTemperature,
        per_temperature: per_t,
    }
}
