//! The KHD model's initial-guess procedure: the seed paper's section IV.C, made concrete
//! (the model's registry entry, [`super::ModelEntry`], names it):
//!
//! 1. **C** from the rupture strain: ω = Cε exactly, so C = ω_f / mean(ε_f).
//! 2. **A, B, H\*, h** together: at the minimum creep rate H ≈ H*, Φ ≈ 0, ω ≈ 0, so
//!    ε̇_min(σ) = A·sinh(S·σ) with S = B(1 − H*). For a trial (H*, h) the pair (A, S) comes
//!    from a least-squares fit of ln ε̇_min against ln sinh(Sσ) (a one-dimensional search in S,
//!    A in closed form) and B = S/(1 − H*); (H*, h) are then fitted to the primary part of
//!    every curve (the points before 30 % of life) with the full model.
//! 3. **Kc** by a one-dimensional fit of eq. 8 (w = 1) with all the others held.
//!
//! Measured minimum creep rates come from the ruptures file where given, else from the curve
//! (see [`crate::data::estimate_min_rate`]). Every value is finally put inside its bounds.
//! The curves are those of one temperature ([`crate::model::guess`] runs the procedure per
//! temperature when constants follow temperature laws).

use crate::data::Curve;
use crate::lsq::{minimize, EvalFailure, LeastSquaresProblem, LmOptions};
use crate::model::guess::{Guess, GuessProcedure};
use crate::model::objective::LifetimeTerm;
use crate::model::objective::{
    CreepProblem, JacobianMethod, Objective, ObjectiveSettings, ParamSpace, MAX_PARAMS,
};
use crate::model::Model;
use crate::ode::OdeOptions;

/// Fraction of the rupture life taken as the primary stage for fitting H* and h.
pub const PRIMARY_FRACTION: f64 = 0.3;

/// Index of each KHD constant in a parameter vector (the order of [`super::khd::constants`]).
const IA: usize = 0;
const IB: usize = 1;
const IHS: usize = 2;
const IH: usize = 3;
const IKC: usize = 4;
const IC: usize = 5;

/// ln A minimising Σ (ln ε̇_i − ln A − ln sinh(S σ_i))² at a given S (closed form: the mean),
/// with the sum of squares left: rates in 1/h, stresses in MPa, S in 1/MPa.
pub fn min_rate_intercept(stress: &[f64], ln_rates: &[f64], s: f64) -> (f64, f64) {
    let lsh: Vec<f64> = stress.iter().map(|sig| ln_sinh(s * sig)).collect();
    let ln_a = ln_rates.iter().zip(&lsh).map(|(l, q)| l - q).sum::<f64>() / ln_rates.len() as f64;
    let c = ln_rates
        .iter()
        .zip(&lsh)
        .map(|(l, q)| (l - ln_a - q).powi(2))
        .sum::<f64>();
    (c, ln_a)
}

/// (A, S) minimising Σ (ln ε̇_i − ln A − ln sinh(S σ_i))² for given rates.
pub fn fit_min_rates(stress: &[f64], rates: &[f64]) -> (f64, f64) {
    let ln_rates: Vec<f64> = rates.iter().map(|r| r.ln()).collect();
    let cost = |s: f64| min_rate_intercept(stress, &ln_rates, s);
    // Golden-section search on ln S over a wide bracket (S σ from 1e-3 to 100).
    let smax = stress.iter().cloned().fold(0.0, f64::max).max(1e-12);
    let (mut lo, mut hi) = ((1e-3 / smax).ln(), (100.0 / smax).ln());
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (cost(x1.exp()).0, cost(x2.exp()).0);
    for _ in 0..200 {
        if f1 < f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = cost(x1.exp()).0;
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = cost(x2.exp()).0;
        }
    }
    let s = (0.5 * (lo + hi)).exp();
    (cost(s).1.exp(), s)
}

/// ln sinh(x) without overflow for large x.
fn ln_sinh(x: f64) -> f64 {
    if x > 20.0 {
        x - std::f64::consts::LN_2 + (-(-2.0 * x).exp()).ln_1p()
    } else {
        x.sinh().ln()
    }
}

/// The free ones of (H*, h) → constants with A, B from the minimum-rate regression (a held
/// B fixes S = B(1 − H*) and A is then the regression's intercept at that S; a held A or
/// B keeps its value); residuals of the primary stage of every curve.
struct PrimaryProblem<'a> {
    objective: Objective<'a>,
    space: ParamSpace,
    base: Vec<f64>,
    a: f64,
    s: f64,
    stress: Vec<f64>,
    ln_rates: Vec<f64>,
    /// Which of [IHS, IH] the problem moves, in that order.
    free: Vec<usize>,
}

impl PrimaryProblem<'_> {
    fn params(&self, u: &[f64]) -> [f64; MAX_PARAMS] {
        let mut x = [0.0; MAX_PARAMS];
        x[..self.base.len()].copy_from_slice(&self.base);
        for (k, &j) in self.free.iter().enumerate() {
            x[j] = self.space.from_unit_one(j, u[k]);
        }
        let held = |j: usize| !self.space.free[j];
        if held(IB) {
            if !held(IA) {
                let s = x[IB] * (1.0 - x[IHS]);
                x[IA] = min_rate_intercept(&self.stress, &self.ln_rates, s).1.exp();
            }
        } else {
            if !held(IA) {
                x[IA] = self.a;
            }
            x[IB] = self.s / (1.0 - x[IHS]);
        }
        x
    }
}

impl LeastSquaresProblem for PrimaryProblem<'_> {
    fn n_params(&self) -> usize {
        self.free.len()
    }
    fn n_residuals(&self) -> usize {
        self.objective.n_residuals()
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let x = self.params(u);
        self.objective.residuals(&x[..self.base.len()], r)
    }
}

/// Run the procedure for the KHD constants [A, B, H*, h, Kc, C] within `space`. A held
/// constant of `space` keeps its value and every step is made with it: e.g. with B and H*
/// held, A is the minimum-rate regression's intercept at S = B(1 − H*) (how
/// [`crate::model::guess::per_temperature`] makes the per-temperature values of constants that
/// follow a law consistent with the constants common to all temperatures).
pub fn initial_guess(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    omega_f: f64,
    ode: &OdeOptions,
) -> Guess {
    let n = space.len();
    let mid = |j: usize| space.from_unit_one(j, 0.5);
    let held = |j: usize| !space.free[j];
    let mut x: Vec<f64> = (0..n)
        .map(|j| if held(j) { space.fixed[j] } else { mid(j) })
        .collect();

    // 1. C from the mean rupture strain.
    let mean_ef = curves.iter().map(|c| c.rupture_strain).sum::<f64>() / curves.len() as f64;
    if !held(IC) {
        x[IC] = omega_f / mean_ef;
    }
    // A free damage at rupture (`rupture_damage`) starts at the ω_f that C was guessed with.
    let omegaf = super::ext::rupture_damage::constants()[0].name;
    if let Some(j) = model.constants().iter().position(|c| c.name == omegaf) {
        if !held(j) {
            x[j] = omega_f.clamp(space.lb[j], space.ub[j]);
        }
    }

    // 2. Minimum rates → (A, S); then (H*, h) on the primary stages.
    let min_rates: Vec<f64> = curves
        .iter()
        .map(|c| c.min_rate_measured.unwrap_or(c.min_rate_estimated))
        .collect();
    let stress: Vec<f64> = curves.iter().map(|c| c.stress_mpa).collect();
    let (a, s) = fit_min_rates(&stress, &min_rates);
    if !held(IA) {
        x[IA] = a;
    }
    let primary: Vec<Curve> = curves
        .iter()
        .map(|c| {
            let t_f = c
                .rupture_time_h
                .unwrap_or_else(|| *c.times_h.last().unwrap());
            let keep = c
                .times_h
                .iter()
                .take_while(|&&t| t <= PRIMARY_FRACTION * t_f)
                .count()
                .max(3)
                .min(c.times_h.len());
            Curve {
                times_h: c.times_h[..keep].to_vec(),
                strains: c.strains[..keep].to_vec(),
                rupture_time_h: None,
                // The guess's primary stage is read at the points themselves.
                groups: None,
                ..c.clone()
            }
        })
        .collect();
    let prob = PrimaryProblem {
        // The primary-stage fit has no lifetime term (w = 0); the run's ω_f and integrator.
        objective: Objective::new(
            model,
            &primary,
            vec![0.0; primary.len()],
            ObjectiveSettings {
                lifetime: LifetimeTerm::Late,
                omega_f,
                ode: *ode,
            },
        ),
        space: space.clone(),
        base: x.clone(),
        a,
        s,
        stress: stress.clone(),
        ln_rates: min_rates.iter().map(|r| r.ln()).collect(),
        free: [IHS, IH].into_iter().filter(|&j| !held(j)).collect(),
    };
    // A few starts in H* guard against the primary fit stalling at a bound.
    let nf = prob.free.len();
    let mut best_f = f64::INFINITY;
    let mut best_u: Vec<f64> = prob
        .free
        .iter()
        .map(|&j| space.to_unit_one(j, mid(j)))
        .collect();
    let h_starts: &[f64] = match (nf, held(IHS)) {
        (0, _) => &[],
        (_, true) => &[0.5],
        _ => &[0.2, 0.5, 0.8],
    };
    for &u0 in h_starts {
        let start: Vec<f64> = prob
            .free
            .iter()
            .map(|&j| if j == IHS { u0 } else { 0.5 })
            .collect();
        let rep = minimize(
            &prob,
            &start,
            &vec![0.0; nf],
            &vec![1.0; nf],
            &LmOptions {
                max_iterations: 60,
                ..LmOptions::default()
            },
        );
        if rep.objective < best_f {
            best_f = rep.objective;
            best_u = rep.x;
        }
    }
    let xp = prob.params(&best_u);
    x[IA] = xp[IA];
    x[IB] = xp[IB];
    x[IHS] = xp[IHS];
    x[IH] = xp[IH];

    // Clamp before the Kc fit so that it runs inside the box.
    let mut clamped = Vec::new();
    let names = model.constants();
    let clamp = |x: &mut Vec<f64>, clamped: &mut Vec<String>| {
        for j in 0..n {
            let v = x[j].clamp(space.lb[j], space.ub[j]);
            if v != x[j] || !x[j].is_finite() {
                let name = names[j].name.to_string();
                if !clamped.contains(&name) {
                    clamped.push(name);
                }
                x[j] = if x[j].is_finite() { v } else { mid(j) };
            }
        }
    };
    clamp(&mut x, &mut clamped);

    // 3. Kc alone on eq. 8 with w = 1 (unless held).
    if !held(IKC) {
        let mut kc_space = space.clone();
        for j in 0..n {
            if j != IKC {
                kc_space.hold(j, x[j]);
            }
        }
        let problem = CreepProblem {
            // The guess's own choice: Kc fitted to both sides of the lifetime error at w = 1.
            objective: Objective::new(
                model,
                curves,
                vec![1.0; curves.len()],
                ObjectiveSettings {
                    lifetime: LifetimeTerm::Both,
                    omega_f,
                    ode: *ode,
                },
            ),
            space: kc_space.clone(),
            jacobian: JacobianMethod::default(),
        };
        let mut best = (f64::INFINITY, x[IKC]);
        for u0 in [0.1, 0.5, 0.9] {
            let rep = minimize(&problem, &[u0], &[0.0], &[1.0], &LmOptions::default());
            if rep.objective < best.0 {
                best = (rep.objective, kc_space.from_unit_one(IKC, rep.x[0]));
            }
        }
        x[IKC] = best.1;
        clamp(&mut x, &mut clamped);
    }
    Guess {
        params: x,
        min_rates,
        clamped,
        procedure: GuessProcedure::Model,
        per_temperature: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_rate_regression_recovers_sinh_law() {
        let (a, s): (f64, f64) = (3e-10, 0.07);
        let stress = [85.0, 100.0, 110.0, 130.0];
        let rates: Vec<f64> = stress.iter().map(|sig| a * (s * sig).sinh()).collect();
        let (a2, s2) = fit_min_rates(&stress, &rates);
        assert!((a2 - a).abs() / a < 1e-6, "{a2}");
        assert!((s2 - s).abs() / s < 1e-7, "{s2}");
    }

    #[test]
    fn ln_sinh_is_accurate_for_large_arguments() {
        for x in [0.5f64, 5.0, 19.9, 20.1, 50.0, 700.0] {
            let exact = if x < 300.0 {
                x.sinh().ln()
            } else {
                x - std::f64::consts::LN_2
            };
            assert!(
                (ln_sinh(x) - exact).abs() < 1e-12 * exact.abs().max(1.0),
                "{x}"
            );
        }
    }
}
