//! Maximum-likelihood fits with one function of the constants held: a constant itself (held
//! in the box, [`held_fit`]) or any smooth function g of them — a combination such as
//! B(1 − H*), a predicted rupture time at an untested load — ([`constrained_fit`]).
//!
//! A function is held by a penalty residual (g(θ) − c)/τ appended to the whitened residuals.
//! The penalised optimum θ* is the exact constrained optimum for its own value g(θ*) (any θ
//! with the same g and a lower −2 ln L would have a lower penalised objective too), so every
//! point returned is an exact profile point at abscissa g(θ*), which lies within O(τ²) of c;
//! with τ a small fraction of g's standard error the two differ negligibly, and the
//! crossing search of [`crate::uncertainty::profile`] uses the exact abscissa anyway.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::dual::{Dual, Scalar, SENS};
use crate::errmodel::ErrorModel;
use crate::likelihood::{raw_objective, residuals_at, LikelihoodProblem, MlFit};
use crate::lsq::{minimize, EvalFailure, LeastSquaresProblem, Termination};
use crate::model::objective::{CreepProblem, ParamSpace};
use crate::model::Load;
use crate::ode::{OdeOptions, Outcome};

use super::Context;

/// Predictions at an untested load are integrated up to this multiple of the longest measured
/// life; one that has not ruptured by then is a failed evaluation.
pub const PREDICTION_HORIZON: f64 = 1e4;

/// Relative tolerance of the simulations that locate a predicted minimum creep rate.
pub const MIN_RATE_RTOL: f64 = 1e-10;

/// The coordinate a constant enters combinations in: products and ratios of constants are
/// linear in these.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coord {
    /// ln x (a positive constant).
    Log,
    /// ln(1 − x): a saturation fraction such as H*, which the KHD rate sees through
    /// 1 − H → 1 − H* (so B(1 − H*) is a product in these coordinates).
    LogComplement,
    /// x itself (a constant that may be zero or negative).
    Linear,
}

impl Coord {
    /// The coordinate of constant `name` with bounds [lb, ub].
    pub fn of(name: &str, lb: f64, ub: f64) -> Coord {
        if name == "Hstar" && lb >= 0.0 && ub < 1.0 {
            Coord::LogComplement
        } else if lb > 0.0 {
            Coord::Log
        } else {
            Coord::Linear
        }
    }
    /// z(x).
    pub fn z(&self, x: f64) -> f64 {
        match self {
            Coord::Log => x.ln(),
            Coord::LogComplement => (1.0 - x).ln(),
            Coord::Linear => x,
        }
    }
    /// dz/dx.
    pub fn dz_dx(&self, x: f64) -> f64 {
        match self {
            Coord::Log => 1.0 / x,
            Coord::LogComplement => -1.0 / (1.0 - x),
            Coord::Linear => 1.0,
        }
    }
    /// How constant `name` is written in a combination: `B`, `(1−Hstar)`.
    pub fn symbol(&self, name: &str) -> String {
        match self {
            Coord::LogComplement => format!("(1−{name})"),
            _ => name.to_string(),
        }
    }
}

/// A predicted quantity of one test at a given load.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Predicted {
    /// ln of the rupture time (h).
    LnRuptureTime,
    /// ln of the rupture strain (fraction).
    LnRuptureStrain,
    /// ln of the minimum creep rate (1/h).
    LnMinRate,
    /// Strain (fraction) at a time (h); after a predicted rupture, the linear continuation at
    /// the rupture rate (as in the objective), so that the quantity stays smooth.
    StrainAt(f64),
}

/// A smooth function of the constants that a fit can hold.
#[derive(Debug, Clone, PartialEq)]
pub enum Quantity {
    /// Σ_j coef_j · z_j(x_j), with z_j the [`Coord`] of constant j.
    Combination { coef: Vec<f64>, coords: Vec<Coord> },
    /// A prediction at `load`.
    Prediction { load: Load, what: Predicted },
}

impl Quantity {
    /// Largest first step of an interval search: the Wald standard error can be huge (a flat
    /// direction of the constants) while the quantity itself is well determined. 0.5 on the
    /// log scale (a factor 1.65), or half the value for a strain.
    pub fn search_cap(&self, g: f64) -> f64 {
        match self {
            Quantity::Prediction {
                what: Predicted::StrainAt(_),
                ..
            } => 0.5 * g.abs().max(1e-6),
            _ => 0.5,
        }
    }
    /// Scale of the penalty that holds this quantity, as a fraction of its Wald standard
    /// error: 0.02, or 0.2 for a minimum rate (whose value is smooth only to ~1e-9, which a
    /// tighter penalty would turn into noise of the objective).
    pub fn penalty_fraction(&self) -> f64 {
        match self {
            Quantity::Prediction {
                what: Predicted::LnMinRate,
                ..
            } => 0.2,
            _ => 0.02,
        }
    }

    /// The value at physical constants `x` (None where the simulation fails).
    pub fn value(&self, ctx: &Context, x: &[f64]) -> Option<f64> {
        match self {
            Quantity::Combination { coef, coords } => Some(
                coef.iter()
                    .zip(coords)
                    .zip(x)
                    .map(|((a, c), v)| if *a == 0.0 { 0.0 } else { a * c.z(*v) })
                    .sum(),
            )
            .filter(|v: &f64| v.is_finite()),
            Quantity::Prediction { load, what } => predict_value(ctx, x, load, *what),
        }
    }

    /// The value and its gradient with respect to the free constants' unit coordinates of
    /// `space`, at unit point `u`.
    pub fn value_and_gradient(
        &self,
        ctx: &Context,
        space: &ParamSpace,
        u: &[f64],
    ) -> Option<(f64, Vec<f64>)> {
        let n = space.len();
        let mut x = vec![0.0; n];
        space.from_unit(u, &mut x);
        let free: Vec<usize> = (0..n).filter(|&j| space.free[j]).collect();
        match self {
            Quantity::Combination { coef, coords } => {
                let g = self.value(ctx, &x)?;
                let grad = free
                    .iter()
                    .map(|&j| coef[j] * coords[j].dz_dx(x[j]) * space.dx_du(j, x[j]))
                    .collect();
                Some((g, grad))
            }
            Quantity::Prediction { load, what } => {
                if matches!(what, Predicted::LnMinRate) || free.len() > SENS {
                    // Central differences in the unit box (the minimum rate is located on the
                    // integrator's steps and carries no derivative).
                    let g = self.value(ctx, &x)?;
                    let h = 1e-5;
                    let mut grad = Vec::with_capacity(free.len());
                    for k in 0..free.len() {
                        let mut up = u.to_vec();
                        let mut dn = u.to_vec();
                        let (hu, hd) = ((1.0 - u[k]).min(h), u[k].min(h));
                        up[k] += hu;
                        dn[k] -= hd;
                        let mut xu = vec![0.0; n];
                        let mut xd = vec![0.0; n];
                        space.from_unit(&up, &mut xu);
                        space.from_unit(&dn, &mut xd);
                        let (gu, gd) = (self.value(ctx, &xu)?, self.value(ctx, &xd)?);
                        grad.push((gu - gd) / (hu + hd).max(1e-300));
                    }
                    return Some((g, grad));
                }
                let mut xd = vec![Dual::<SENS>::cst(0.0); n];
                for (k, &j) in free.iter().enumerate() {
                    xd[j] = Dual::var(x[j], k, space.dx_du(j, x[j]));
                }
                for j in 0..n {
                    if !space.free[j] {
                        xd[j] = Dual::cst(x[j]);
                    }
                }
                let d = predict_dual(ctx, &xd, load, *what)?;
                Some((d.v, d.d[..free.len()].to_vec()))
            }
        }
    }
}

/// Integration options for a prediction: the run's tolerances, the horizon
/// [`PREDICTION_HORIZON`] × the longest measured life.
pub fn prediction_ode(ctx: &Context) -> OdeOptions {
    OdeOptions {
        t_end: PREDICTION_HORIZON * ctx.longest_life_h().max(1.0),
        ..ctx.settings.ode
    }
}

fn predict_value(ctx: &Context, x: &[f64], load: &Load, what: Predicted) -> Option<f64> {
    let mut ode = prediction_ode(ctx);
    if what == Predicted::LnMinRate {
        // The minimum rate is located on the integrator's steps: at the fits' tolerance it
        // is smooth in the constants only to ~3e-7 (measured), too rough for a held
        // quantity; at 1e-10 the steps are four times shorter.
        ode.rtol = ode.rtol.min(MIN_RATE_RTOL);
    }
    let times: Vec<f64> = match what {
        Predicted::StrainAt(t) => vec![t],
        _ => vec![],
    };
    let mut out = vec![0.0; times.len()];
    let r = ctx.model.simulate(x, load, &times, &mut out, &ode);
    if r.outcome != Outcome::Ruptured {
        return None;
    }
    let v = match what {
        Predicted::LnRuptureTime => r.t_end.ln(),
        Predicted::LnRuptureStrain => r.strain_end.ln(),
        Predicted::LnMinRate => r.min_rate.ln(),
        Predicted::StrainAt(t) => {
            if r.n_out == 1 {
                out[0]
            } else {
                r.strain_end + r.rate_end * (t - r.t_end)
            }
        }
    };
    v.is_finite().then_some(v)
}

fn predict_dual(
    ctx: &Context,
    x: &[Dual<SENS>],
    load: &Load,
    what: Predicted,
) -> Option<Dual<SENS>> {
    let ode = prediction_ode(ctx);
    let times: Vec<f64> = match what {
        Predicted::StrainAt(t) => vec![t],
        _ => vec![],
    };
    let mut out = vec![Dual::<SENS>::cst(0.0); times.len()];
    let r = ctx.model.simulate_sens(x, load, &times, &mut out, &ode);
    if r.outcome != Outcome::Ruptured {
        return None;
    }
    let v = match what {
        Predicted::LnRuptureTime => r.t_end.ln(),
        Predicted::LnRuptureStrain => r.strain_end.ln(),
        Predicted::LnMinRate => return None,
        Predicted::StrainAt(t) => {
            if r.n_out == 1 {
                out[0]
            } else {
                r.strain_end + r.rate_end * (-r.t_end + t)
            }
        }
    };
    (v.v.is_finite() && v.d.iter().all(|d| d.is_finite())).then_some(v)
}

/// One fit of a profile: where it ended and how.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointFit {
    /// Constants at the end, model order.
    pub params: Vec<f64>,
    /// −2 ln L there (error model re-estimated), NaN if the fit failed.
    pub neg2ll: f64,
    /// The value of the held function there (the held constant's unit coordinate, or g).
    pub coord: f64,
    /// How the optimiser stopped.
    pub termination: Termination,
    /// LM iterations.
    pub iterations: usize,
    /// Why it failed, if it did.
    pub failure: Option<String>,
}

impl PointFit {
    /// Whether the fit ended at an evaluable point.
    pub fn ok(&self) -> bool {
        self.neg2ll.is_finite() && self.termination != Termination::SimulationFailure
    }
    fn failed(start: &[f64], msg: String, iterations: usize) -> PointFit {
        PointFit {
            params: start.to_vec(),
            neg2ll: f64::NAN,
            coord: f64::NAN,
            termination: Termination::SimulationFailure,
            iterations,
            failure: Some(msg),
        }
    }
}

/// Fit with constant `j` held at physical `value`, from `start` (its j-th entry is replaced).
/// With specimen effects the constant is held by the box instead of the space, so that the
/// effects acting through it stay in the fit ([`crate::likelihood::ml_fit_row`]).
pub fn held_fit(ctx: &Context, j: usize, value: f64, start: &[f64], warm: bool) -> PointFit {
    let mut s = start.to_vec();
    s[j] = value;
    let f = if ctx.hierarchical() {
        ctx.fit_row(&ctx.space, &s, warm, &[j], None)
    } else {
        let mut space = ctx.space.clone();
        space.hold(j, value);
        ctx.fit(&space, &s, warm)
    };
    PointFit {
        coord: ctx.space.to_unit_one(j, value),
        neg2ll: if f.ok() { f.neg2ll } else { f64::NAN },
        params: f.params,
        termination: f.termination,
        iterations: f.iterations,
        failure: f.failure,
    }
}

/// A least-squares problem with its residuals (and Jacobian) multiplied by `c`.
///
/// Why: [`crate::lsq::minimize`] damps with λ·JᵀJ_jj where λ starts at λ₀·max JᵀJ_jj, so
/// its first damping grows with the square of the Jacobian's scale. Whitened likelihood
/// residuals have JᵀJ diagonals of 1e7–1e9 (reading errors of ~1e-4 strain): the first steps
/// are then ~1e-11 of the box, and a fit started near its optimum stops at once as
/// `converged_step` — measured on the 560 °C data, a held prediction did not move at all.
/// Scaling the problem so that max JᵀJ_jj = 1 at the start gives the intended Marquardt
/// damping λ₀·JᵀJ_jj; the minimiser of ‖c·r‖² is that of ‖r‖².
pub struct Scaled<'p, P: LeastSquaresProblem> {
    /// The problem.
    pub inner: &'p P,
    /// The factor.
    pub c: f64,
}

impl<P: LeastSquaresProblem> Scaled<'_, P> {
    fn scale(&self, r: &mut [f64], jac: Option<&mut DMatrix<f64>>, by: f64) {
        for v in r.iter_mut() {
            *v *= by;
        }
        if let Some(j) = jac {
            *j *= by;
        }
    }
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Scaled<'_, P> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals()
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        self.inner.residuals(u, r)?;
        self.scale(r, None, self.c);
        Ok(())
    }
    fn jacobian(
        &self,
        u: &[f64],
        r: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let res = self.inner.jacobian(u, r, jac)?;
        if res.is_ok() {
            *jac *= self.c;
        }
        Some(res)
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let res = self.inner.residuals_and_jacobian(u, r, jac)?;
        if res.is_ok() {
            self.scale(r, Some(jac), self.c);
        }
        Some(res)
    }
    fn reweight(&self, x: &[f64], r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> bool {
        let inv = 1.0 / self.c;
        self.scale(r, jac.as_deref_mut(), inv);
        let changed = self.inner.reweight(x, r, jac.as_deref_mut());
        self.scale(r, jac, self.c);
        changed
    }
    fn objective_offset(&self) -> f64 {
        self.c * self.c * self.inner.objective_offset()
    }
}

/// [`minimize`] on `problem` scaled so that max JᵀJ_jj = 1 at the start (see [`Scaled`]).
pub fn minimize_scaled<P: LeastSquaresProblem>(
    problem: &P,
    u0: &[f64],
    opts: &crate::lsq::LmOptions,
) -> crate::lsq::LmReport {
    let (m, k) = (problem.n_residuals(), problem.n_params());
    let mut r = vec![0.0; m];
    let mut jac = DMatrix::<f64>::zeros(m, k);
    let (lb, ub) = (vec![0.0; k], vec![1.0; k]);
    let fused = problem.residuals_and_jacobian(u0, &mut r, &mut jac);
    let ok = match fused {
        Some(res) => res.is_ok(),
        None => {
            let mut ev = 0;
            problem.residuals(u0, &mut r).is_ok()
                && crate::lsq::fd_jacobian(
                    problem,
                    u0,
                    &r,
                    &lb,
                    &ub,
                    opts.fd_step,
                    &mut jac,
                    &mut ev,
                )
                .is_ok()
        }
    };
    let diag_max = (0..k)
        .map(|j| jac.column(j).norm_squared())
        .fold(0.0, f64::max);
    let c = if ok && diag_max.is_finite() && diag_max > 1.0 {
        1.0 / diag_max.sqrt()
    } else {
        1.0
    };
    let scaled = Scaled { inner: problem, c };
    let mut rep = minimize(&scaled, u0, &lb, &ub, opts);
    rep.objective /= c * c;
    for v in rep.residuals.iter_mut() {
        *v /= c;
    }
    rep
}

/// [`crate::likelihood::ml_fit`] with the problem scaled ([`minimize_scaled`]): the
/// constants free in `space` and the error model fitted from `start`.
pub fn ml_fit_scaled(
    ctx: &Context,
    space: &ParamSpace,
    start: &[f64],
    settings: &crate::fit::FitSettings,
) -> MlFit {
    let failed = |msg: String, it: usize, ev: usize| MlFit {
        params: start.to_vec(),
        noise: ErrorModel {
            strain: vec![],
            lifetime_sd: f64::NAN,
        },
        neg2ll: f64::NAN,
        residuals: None,
        eval: None,
        specimen: None,
        termination: Termination::SimulationFailure,
        iterations: it,
        evaluations: ev,
        failure: Some(msg),
    };
    let res = match residuals_at(ctx.model, ctx.curves, start, settings) {
        Ok(r) => r,
        Err(e) => return failed(e.0, 0, 1),
    };
    let noise = ErrorModel::estimate(&res, ctx.ml.lifetime_sd_floor);
    let problem = LikelihoodProblem::new(
        CreepProblem {
            objective: raw_objective(ctx.model, ctx.curves, settings),
            space: space.clone(),
            jacobian: settings.jacobian,
        },
        noise,
        ctx.ml.lifetime_sd_floor,
    );
    let u0 = space.to_unit(start);
    let lm = minimize_scaled(&problem, &u0, &settings.lm);
    if lm.termination == Termination::SimulationFailure {
        return failed(
            lm.failure.unwrap_or_default(),
            lm.iterations,
            lm.evaluations,
        );
    }
    let mut x = start.to_vec();
    space.from_unit(&lm.x, &mut x);
    let Ok(res) = residuals_at(ctx.model, ctx.curves, &x, settings) else {
        return failed(
            "the fitted point could not be evaluated".into(),
            lm.iterations,
            lm.evaluations,
        );
    };
    let noise = ErrorModel::estimate(&res, ctx.ml.lifetime_sd_floor);
    let neg2ll = noise.neg2ll(&res);
    let eval = raw_objective(ctx.model, ctx.curves, settings).evaluate(&x);
    MlFit {
        params: x,
        noise,
        neg2ll,
        residuals: Some(res),
        eval: Some(eval),
        specimen: None,
        termination: lm.termination,
        iterations: lm.iterations,
        evaluations: lm.evaluations,
        failure: None,
    }
}

/// −2 ln L plus the penalty ((g − c)/τ)² as a least-squares problem in the unit box.
struct Penalised<'p, 'a> {
    inner: LikelihoodProblem<'a>,
    ctx: &'p Context<'a>,
    q: &'p Quantity,
    target: f64,
    tau: f64,
}

impl LeastSquaresProblem for Penalised<'_, '_> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals() + 1
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let m = self.inner.n_residuals();
        self.inner.residuals(u, &mut r[..m])?;
        let mut x = vec![0.0; self.ctx.space.len()];
        self.inner.inner.space.from_unit(u, &mut x);
        let g = self
            .q
            .value(self.ctx, &x)
            .ok_or_else(|| EvalFailure("the held quantity could not be evaluated".into()))?;
        r[m] = (g - self.target) / self.tau;
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let m = self.inner.n_residuals();
        let n = self.n_params();
        let mut ji = DMatrix::<f64>::zeros(m, n);
        match self.inner.residuals_and_jacobian(u, &mut r[..m], &mut ji)? {
            Ok(()) => {}
            Err(e) => return Some(Err(e)),
        }
        let Some((g, grad)) = self
            .q
            .value_and_gradient(self.ctx, &self.inner.inner.space, u)
        else {
            return Some(Err(EvalFailure(
                "the held quantity could not be evaluated".into(),
            )));
        };
        jac.view_mut((0, 0), (m, n)).copy_from(&ji);
        for k in 0..n {
            jac[(m, k)] = grad[k] / self.tau;
        }
        r[m] = (g - self.target) / self.tau;
        Some(Ok(()))
    }
    fn reweight(&self, x: &[f64], r: &mut [f64], jac: Option<&mut DMatrix<f64>>) -> bool {
        // The inner problem rewrites only its own rows (by curve offsets); the penalty row
        // does not depend on the error model.
        self.inner.reweight(x, r, jac)
    }
    fn objective_offset(&self) -> f64 {
        self.inner.objective_offset()
    }
}

/// The penalty row (g − c)/τ of [`constrained_fit`] for a hierarchical fit
/// ([`crate::likelihood::ExtraRow`]).
struct HeldRow<'p, 'a> {
    ctx: &'p Context<'a>,
    q: &'p Quantity,
    target: f64,
    tau: f64,
}

impl crate::likelihood::ExtraRow for HeldRow<'_, '_> {
    fn row(&self, space: &ParamSpace, u: &[f64]) -> Option<(f64, Vec<f64>)> {
        let (g, grad) = self.q.value_and_gradient(self.ctx, space, u)?;
        Some((
            (g - self.target) / self.tau,
            grad.into_iter().map(|d| d / self.tau).collect(),
        ))
    }
}

/// Fit with the quantity `q` held near `target` by the penalty of scale `tau`, from `start`
/// (with specimen effects a hierarchical fit with the penalty's row appended).
/// The returned point's `coord` is the exact g at the end (see the module docs).
pub fn constrained_fit(
    ctx: &Context,
    q: &Quantity,
    target: f64,
    tau: f64,
    start: &[f64],
    warm: bool,
) -> PointFit {
    if ctx.hierarchical() {
        let row = HeldRow {
            ctx,
            q,
            target,
            tau,
        };
        let f = ctx.fit_row(&ctx.space, start, warm, &[], Some(&row));
        if !f.ok() {
            let msg = f.failure.unwrap_or_else(|| "the fit failed".into());
            return PointFit::failed(start, msg, f.iterations);
        }
        let Some(g) = q.value(ctx, &f.params) else {
            return PointFit::failed(start, "the held quantity could not be evaluated".into(), 0);
        };
        return PointFit {
            params: f.params,
            neg2ll: f.neg2ll,
            coord: g,
            termination: f.termination,
            iterations: f.iterations,
            failure: None,
        };
    }
    let settings = if warm { &ctx.warm } else { &ctx.settings };
    let res = match residuals_at(ctx.model, ctx.curves, start, settings) {
        Ok(r) => r,
        Err(e) => return PointFit::failed(start, e.0, 0),
    };
    let noise = ErrorModel::estimate(&res, ctx.ml.lifetime_sd_floor);
    let problem = Penalised {
        inner: LikelihoodProblem::new(
            CreepProblem {
                objective: raw_objective(ctx.model, ctx.curves, settings),
                space: ctx.space.clone(),
                jacobian: settings.jacobian,
            },
            noise,
            ctx.ml.lifetime_sd_floor,
        ),
        ctx,
        q,
        target,
        tau,
    };
    let u0 = ctx.space.to_unit(start);
    let lm = minimize_scaled(&problem, &u0, &settings.lm);
    if lm.termination == Termination::SimulationFailure {
        return PointFit::failed(start, lm.failure.unwrap_or_default(), lm.iterations);
    }
    let mut x = start.to_vec();
    ctx.space.from_unit(&lm.x, &mut x);
    let Ok(res) = residuals_at(ctx.model, ctx.curves, &x, settings) else {
        return PointFit::failed(start, "the end point could not be evaluated".into(), 0);
    };
    let Some(g) = q.value(ctx, &x) else {
        return PointFit::failed(start, "the held quantity could not be evaluated".into(), 0);
    };
    let noise = ErrorModel::estimate(&res, ctx.ml.lifetime_sd_floor);
    PointFit {
        params: x,
        neg2ll: noise.neg2ll(&res),
        coord: g,
        termination: lm.termination,
        iterations: lm.iterations,
        failure: None,
    }
}
