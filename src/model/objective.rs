//! The seed paper's objective (eq. 8) as a residual vector, the mapping of constants to the
//! optimiser's unit box, and the evaluation of a constant set for reports.
//!
//! Residual layout: for each curve (ascending stress) its strain residuals
//! (ε_pred(t_j) − ε_j)/ε_f at every measured time, then one lifetime residual
//! √w·(t_f,pred − t_f)/t_f ("late": only when positive, else 0).
//!
//! **After a predicted rupture** a measured time t_j > t_r gets the C¹ continuation
//! ε_pred(t_j) = ε_r + ε̇_r·(t_j − t_r) (strain and rate at rupture). Holding ε_r instead is
//! continuous but has a kink in the constants whenever t_r crosses a measured time (DESIGN.md
//! §7: half the 590 °C fits ended on such kinks); the linear continuation matches value and
//! first derivative there, so the residual vector is C¹ and Levenberg–Marquardt sees a smooth
//! problem. It also penalises early rupture through the strain term, which the "late"
//! lifetime term does not.

use nalgebra::DMatrix;

use serde::{Deserialize, Serialize};

use crate::data::Curve;
use crate::dual::{Dual, Scalar, SENS, SENS_WIDE};
use crate::lsq::LmOptions;
use crate::lsq::{EvalFailure, LeastSquaresProblem, NormalEquations};
use crate::model::{Load, Model, Scale};
use crate::ode::{OdeOptions, Outcome, SimResult};

/// Integration horizon as a multiple of the longest measured time of a curve (rupture time
/// or last point): a prediction that has not ruptured by then is a failed simulation.
pub const HORIZON_FACTOR: f64 = 1000.0;

/// Relative margin below the horizon within which a rupture found with sensitivities (dual
/// numbers) counts as none. Sensitivities take part in the integrator's step control, so the
/// value-only integration of the same constants can reach the horizon where the dual one
/// ruptured a hair before it: an optimiser whose trial points are evaluated with
/// sensitivities then ends where the value-only evaluation of its result fails (far-material
/// data, `scripts/far_material.py 304 DIR 300 random`: 8 of 101 sweep starts lost so, each
/// at t_r = 0.999999999 × the horizon). With the margin the optimiser stays where both agree.
pub const HORIZON_MARGIN: f64 = 1e-3;

/// `ode` integrating curve `c` up to its horizon: [`HORIZON_FACTOR`] × the longest measured
/// time (rupture time or last point), h. The one rule every simulation of a measured curve
/// uses (the objective, `simulate`, the plots).
pub fn curve_horizon(c: &Curve, ode: &OdeOptions) -> OdeOptions {
    let last = c.times_h.last().copied().unwrap_or(0.0);
    let span = c.rupture_time_h.unwrap_or(0.0).max(last);
    OdeOptions {
        t_end: HORIZON_FACTOR * span,
        ..*ode
    }
}

/// Largest number of constants a model may have (fixed-size parameter buffers): the base
/// model's six, the extensions' three and a temperature-law constant for each of them fit.
pub const MAX_PARAMS: usize = 32;

/// From this many residuals on, a [`CreepProblem`] with sensitivities hands the optimiser
/// its normal equations, accumulated curve by curve as the integrator produces the
/// predictions, instead of an m × k Jacobian (`lsq`'s large-problem mode). Below it the
/// stored Jacobian's arithmetic is kept, so results on ordinary data stay bit for bit.
pub const NORMAL_EQUATIONS_MIN_RESIDUALS: usize = 20_000;

/// Bounds, scale and free/fixed status of every constant; maps to the unit box [0, 1]^k of
/// the free constants, in which the optimiser works.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpace {
    /// Lower bounds (physical units).
    pub lb: Vec<f64>,
    /// Upper bounds.
    pub ub: Vec<f64>,
    /// Scale per constant.
    pub scale: Vec<Scale>,
    /// Values of the held constants (used where `free[j]` is false).
    pub fixed: Vec<f64>,
    /// Which constants the optimiser moves.
    pub free: Vec<bool>,
}

impl ParamSpace {
    /// All constants free.
    pub fn new(lb: Vec<f64>, ub: Vec<f64>, scale: Vec<Scale>) -> Self {
        let n = lb.len();
        assert!(n <= MAX_PARAMS, "too many constants");
        ParamSpace {
            fixed: lb.clone(),
            free: vec![true; n],
            lb,
            ub,
            scale,
        }
    }
    /// Number of constants.
    pub fn len(&self) -> usize {
        self.lb.len()
    }
    /// Whether there are no constants.
    pub fn is_empty(&self) -> bool {
        self.lb.is_empty()
    }
    /// Number of free constants.
    pub fn n_free(&self) -> usize {
        self.free.iter().filter(|f| **f).count()
    }
    /// Hold constant `j` at `value`.
    pub fn hold(&mut self, j: usize, value: f64) {
        self.free[j] = false;
        self.fixed[j] = value;
    }
    /// Unit-box coordinate of constant `j` at physical value `x`.
    pub fn to_unit_one(&self, j: usize, x: f64) -> f64 {
        let (lb, ub) = (self.lb[j], self.ub[j]);
        match self.scale[j] {
            Scale::Linear => (x - lb) / (ub - lb),
            Scale::Log => (x.ln() - lb.ln()) / (ub.ln() - lb.ln()),
        }
    }
    /// Physical value of constant `j` at unit-box coordinate `u`.
    pub fn from_unit_one(&self, j: usize, u: f64) -> f64 {
        let (lb, ub) = (self.lb[j], self.ub[j]);
        let x = match self.scale[j] {
            Scale::Linear => lb + u * (ub - lb),
            Scale::Log => (lb.ln() + u * (ub.ln() - lb.ln())).exp(),
        };
        x.clamp(lb, ub)
    }
    /// Unit-box coordinates of the free constants of a full physical vector.
    pub fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        (0..self.len())
            .filter(|&j| self.free[j])
            .map(|j| self.to_unit_one(j, x[j]))
            .collect()
    }
    /// Full physical vector from the free constants' unit coordinates (held ones filled in).
    pub fn from_unit(&self, u: &[f64], x: &mut [f64]) {
        let mut k = 0;
        for j in 0..self.len() {
            if self.free[j] {
                x[j] = self.from_unit_one(j, u[k]);
                k += 1;
            } else {
                x[j] = self.fixed[j];
            }
        }
    }
    /// Derivative dx/du of constant `j` at physical value `x` (h per unit coordinate).
    pub fn dx_du(&self, j: usize, x: f64) -> f64 {
        let (lb, ub) = (self.lb[j], self.ub[j]);
        match self.scale[j] {
            Scale::Linear => ub - lb,
            Scale::Log => x * (ub.ln() - lb.ln()),
        }
    }
    /// Whether physical constant `j` sits on a bound (within `tol` in unit coordinates).
    pub fn at_bound(&self, j: usize, x: f64, tol: f64) -> Option<&'static str> {
        let u = self.to_unit_one(j, x);
        if u <= tol {
            Some("lower")
        } else if u >= 1.0 - tol {
            Some("upper")
        } else {
            None
        }
    }
}

/// How the least-squares Jacobian of eq. 8 is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JacobianMethod {
    /// Forward sensitivities: one simulation per curve in dual numbers carries ∂r/∂u: of up
    /// to [`SENS`] free constants in the narrow dual numbers, of up to [`SENS_WIDE`] in the
    /// wide ones, and of more in chunks of [`SENS_WIDE`] (one simulation per chunk).
    #[default]
    Sensitivity,
    /// Forward differences in the unit box, one extra simulation per free constant.
    FiniteDifference,
}

/// Number types eq. 8 can be evaluated in: `f64`, and dual numbers for the Jacobian.
pub trait SimScalar: Scalar {
    /// Simulate through the object-safe model in this number type.
    fn simulate(
        model: &dyn Model,
        params: &[Self],
        load: &Load,
        times: &[f64],
        out: &mut [Self],
        opts: &OdeOptions,
    ) -> SimResult<Self>;
}

impl SimScalar for f64 {
    fn simulate(
        model: &dyn Model,
        params: &[f64],
        load: &Load,
        times: &[f64],
        out: &mut [f64],
        opts: &OdeOptions,
    ) -> SimResult {
        model.simulate(params, load, times, out, opts)
    }
}

impl SimScalar for Dual<SENS> {
    fn simulate(
        model: &dyn Model,
        params: &[Self],
        load: &Load,
        times: &[f64],
        out: &mut [Self],
        opts: &OdeOptions,
    ) -> SimResult<Self> {
        model.simulate_sens(params, load, times, out, opts)
    }
}

impl SimScalar for Dual<SENS_WIDE> {
    fn simulate(
        model: &dyn Model,
        params: &[Self],
        load: &Load,
        times: &[f64],
        out: &mut [Self],
        opts: &OdeOptions,
    ) -> SimResult<Self> {
        model.simulate_sens_wide(params, load, times, out, opts)
    }
}

/// What eq. 8 needs besides the model, the curves and the weights; taken from the resolved
/// configuration ([`FitSettings::objective`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectiveSettings {
    /// Which lifetime errors count.
    pub lifetime: LifetimeTerm,
    /// Damage at rupture ω_f.
    pub omega_f: f64,
    /// Integration options (the horizon is set per curve).
    pub ode: OdeOptions,
}

/// Eq. 8 for one set of curves, one model and one weight per curve. Built only by
/// [`Objective::new`], so every objective takes its settings from one place.
#[derive(Clone)]
pub struct Objective<'a> {
    model: &'a dyn Model,
    curves: &'a [Curve],
    /// Bin-averaged data ([`Objective::binned`]): a weight per point and the scatter term.
    bins: Option<&'a Binned>,
    w: Vec<f64>,
    lifetime: LifetimeTerm,
    omega_f: f64,
    ode: OdeOptions,
    /// Per-curve factors on some constants (specimen effects), if any.
    effects: Option<CurveFactors>,
}

/// Multiplicative factors on some constants, one set per curve: the constants of curve `i`
/// are the population's with `params[index[k]] × factors[i][k]`. This is how a specimen's
/// own creep rate or ductility enters a simulation (random effects, [`crate::likelihood`]).
/// Derivatives with respect to the population constants stay exact (the factor multiplies
/// the dual number).
#[derive(Debug, Clone, PartialEq)]
pub struct CurveFactors {
    /// Index in the model's constants of each factor's constant.
    pub index: Vec<usize>,
    /// Per curve, one factor per entry of `index`.
    pub factors: Vec<Vec<f64>>,
}

/// Prediction for one curve at one constant set.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvePrediction {
    /// How the simulation ended.
    pub outcome: Outcome,
    /// Predicted rupture time, h (NaN if it did not rupture).
    pub rupture_time_h: f64,
    /// Predicted rupture strain, fraction.
    pub rupture_strain: f64,
    /// Predicted minimum strain rate, 1/h.
    pub min_rate: f64,
    /// Predicted strain at the measured times (with the post-rupture continuation).
    pub strain: Vec<f64>,
}

/// Objective value and its parts at one constant set.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// Eq. 8 (sum of squared residuals), NaN where a simulation failed.
    pub objective: f64,
    /// The strain term alone, Σ((ε_pred − ε)/ε_f)², comparable across w.
    pub norm_residual: f64,
    /// Per-curve predictions.
    pub curves: Vec<CurvePrediction>,
}

impl Evaluation {
    /// Signed lifetime errors, % of the measured rupture time (NaN if unknown).
    pub fn lifetime_errors_pct(&self, curves: &[Curve]) -> Vec<f64> {
        self.curves
            .iter()
            .zip(curves)
            .map(|(p, c)| match c.rupture_time_h {
                Some(t) => 100.0 * (p.rupture_time_h - t) / t,
                None => f64::NAN,
            })
            .collect()
    }
    /// Signed minimum-rate errors, % of the measured (or, where not given, estimated) rate.
    pub fn min_rate_errors_pct(&self, curves: &[Curve]) -> Vec<f64> {
        self.curves
            .iter()
            .zip(curves)
            .map(|(p, c)| {
                let m = c.min_rate_measured.unwrap_or(c.min_rate_estimated);
                100.0 * (p.min_rate - m) / m
            })
            .collect()
    }
}

/// Bin-averaged curves for the first stage of a multi-resolution fit ([`bin_curves`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Binned {
    /// The curves, each point at the mean time and mean strain of its bin.
    pub curves: Vec<Curve>,
    /// Weight of each point: √(points in its bin).
    pub weights: Vec<Vec<f64>>,
    /// The full data's strain residual that no prediction can change: Σ over bins and their
    /// points of ((δε − s·δt)/ε_f)², δ the deviation from the bin's mean, s the bin's
    /// least-squares slope (measurement scatter about a straight line within each bin).
    pub scatter: f64,
}

/// Bin-averaged curves: a curve of more than `max_points` points becomes bins of ⌈n /
/// max_points⌉ consecutive points (the last one may hold fewer), each a point at the mean
/// time and mean strain of its bin with the weight √count; shorter curves are kept as they
/// are (weight 1). Eq. 8 of these ([`Objective::binned`]) is eq. 8 of the full data up to
/// terms of the order of the prediction's curvature and of its slope's misfit within a bin
/// (Σ(ε_pred − ε)² over a bin = count·(ε_pred(t̄) − ε̄)² + scatter + those terms), so its
/// minimum lies close to the full data's, and with the scatter included its value is on the
/// full data's scale (the LM's tolerances are relative).
pub fn bin_curves(curves: &[Curve], max_points: usize) -> Binned {
    let max_points = max_points.max(1);
    let mut scatter = 0.0;
    let (curves, weights) = curves
        .iter()
        .map(|c| {
            let n = c.times_h.len();
            if n <= max_points {
                return (c.clone(), vec![1.0; n]);
            }
            let size = n.div_ceil(max_points);
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let (mut times, mut strains, mut weights) = (Vec::new(), Vec::new(), Vec::new());
            for (t, e) in c.times_h.chunks(size).zip(c.strains.chunks(size)) {
                let (tm, em) = (mean(t), mean(e));
                let (mut stt, mut ste, mut see) = (0.0, 0.0, 0.0);
                for (ti, ei) in t.iter().zip(e) {
                    let (dt, de) = (ti - tm, ei - em);
                    stt += dt * dt;
                    ste += dt * de;
                    see += de * de;
                }
                let fitted = if stt > 0.0 { ste * ste / stt } else { 0.0 };
                scatter += (see - fitted).max(0.0) / (c.rupture_strain * c.rupture_strain);
                times.push(tm);
                strains.push(em);
                weights.push((t.len() as f64).sqrt());
            }
            // Field by field: `..c.clone()` would copy the long vectors only to drop them.
            let binned = Curve {
                temperature_c: c.temperature_c,
                stress_mpa: c.stress_mpa,
                specimen: c.specimen.clone(),
                times_h: times,
                strains,
                rupture_time_h: c.rupture_time_h,
                rupture_strain: c.rupture_strain,
                min_rate_measured: c.min_rate_measured,
                groups: None,
                min_rate_estimated: c.min_rate_estimated,
            };
            (binned, weights)
        })
        .unzip();
    Binned {
        curves,
        weights,
        scatter,
    }
}

/// Mean of absolute values, skipping NaN (NaN if none).
pub fn mean_abs(v: &[f64]) -> f64 {
    let f: Vec<f64> = v
        .iter()
        .filter(|x| x.is_finite())
        .map(|x| x.abs())
        .collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}

impl<'a> Objective<'a> {
    /// The measured curves.
    pub fn curves(&self) -> &'a [Curve] {
        self.curves
    }

    /// Eq. 8 of `model` on `curves` (ascending stress) with lifetime weight `w[i]` on curve
    /// `i` (one per curve) and the run's `settings`.
    pub fn new(
        model: &'a dyn Model,
        curves: &'a [Curve],
        w: Vec<f64>,
        settings: ObjectiveSettings,
    ) -> Self {
        assert_eq!(w.len(), curves.len(), "one lifetime weight per curve");
        Objective {
            model,
            curves,
            bins: None,
            w,
            lifetime: settings.lifetime,
            omega_f: settings.omega_f,
            ode: settings.ode,
            effects: None,
        }
    }

    /// The same objective with the constants of each curve multiplied by its factors
    /// (`None`: the population's constants for every curve).
    pub fn with_factors(mut self, effects: Option<CurveFactors>) -> Self {
        if let Some(e) = &effects {
            assert_eq!(
                e.factors.len(),
                self.curves.len(),
                "one factor set per curve"
            );
        }
        self.effects = effects;
        self
    }

    /// The per-curve factors, if any.
    pub fn factors(&self) -> Option<&CurveFactors> {
        self.effects.as_ref()
    }

    /// The constants of curve `i`: `params` with the curve's factors applied (a copy on the
    /// stack; `params` itself when there are no factors).
    #[inline]
    fn curve_params<S: Scalar>(&self, i: usize, params: &[S], buf: &mut [S; MAX_PARAMS]) -> usize {
        let n = params.len();
        buf[..n].copy_from_slice(params);
        if let Some(e) = &self.effects {
            for (k, &j) in e.index.iter().enumerate() {
                buf[j] = buf[j] * e.factors[i][k];
            }
        }
        n
    }

    /// Eq. 8 of bin-averaged curves ([`bin_curves`]): the strain residual of curve `i`,
    /// point `k` multiplied by `bins.weights[i][k]`, and one more residual after all curves'
    /// residuals, the constant √`bins.scatter`.
    pub fn binned(
        model: &'a dyn Model,
        bins: &'a Binned,
        w: Vec<f64>,
        settings: ObjectiveSettings,
    ) -> Self {
        assert_eq!(
            bins.weights.len(),
            bins.curves.len(),
            "one weight vector per curve"
        );
        for (wv, c) in bins.weights.iter().zip(&bins.curves) {
            assert_eq!(wv.len(), c.times_h.len(), "one weight per measured point");
        }
        Objective {
            bins: Some(bins),
            ..Objective::new(model, &bins.curves, w, settings)
        }
    }

    /// The lifetime weights, one per curve.
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// Number of residuals: every measured point plus one lifetime term per curve (plus the
    /// scatter term of binned data).
    pub fn n_residuals(&self) -> usize {
        self.curves
            .iter()
            .map(|c| c.times_h.len() + 1)
            .sum::<usize>()
            + usize::from(self.bins.is_some())
    }

    fn load(&self, c: &Curve) -> Load {
        Load::of_curve(c, self.omega_f)
    }

    fn ode_for(&self, c: &Curve) -> OdeOptions {
        curve_horizon(c, &self.ode)
    }

    /// Simulate curve `i` at `params`, writing the predicted strain (with continuation) into
    /// `strain`. Returns (outcome, rupture time, rupture strain, min rate).
    fn predict<S: SimScalar>(
        &self,
        i: usize,
        params: &[S],
        strain: &mut [S],
    ) -> Result<(Outcome, S, S, f64), EvalFailure> {
        let c = &self.curves[i];
        let mut buf = [S::cst(0.0); MAX_PARAMS];
        let n = self.curve_params(i, params, &mut buf);
        if let Some(g) = &c.groups {
            // A curve of group means: the model at every reading, averaged as the readings were.
            let mut raw = vec![S::cst(0.0); g.times_h.len()];
            let res = S::simulate(
                self.model,
                &buf[..n],
                &self.load(c),
                &g.times_h,
                &mut raw,
                &self.ode_for(c),
            );
            let out = self.conclude(i, &res, &g.times_h, |k, s| raw[k] = s);
            g.average(&raw, strain);
            return out;
        }
        let res = S::simulate(
            self.model,
            &buf[..n],
            &self.load(c),
            &c.times_h,
            strain,
            &self.ode_for(c),
        );
        self.conclude(i, &res, &c.times_h, |k, s| strain[k] = s)
    }

    /// How simulation `res` of curve `i` at `times` (its points', or its readings' where the
    /// points are group means) ends for eq. 8: the post-rupture continuation handed to
    /// `cont(k, strain)` for every time after the rupture, and (outcome, rupture time,
    /// rupture strain, min rate), or the failure.
    fn conclude<S: Scalar>(
        &self,
        i: usize,
        res: &SimResult<S>,
        times: &[f64],
        mut cont: impl FnMut(usize, S),
    ) -> Result<(Outcome, S, S, f64), EvalFailure> {
        let c = &self.curves[i];
        let n = times.len();
        match res.outcome {
            Outcome::Ruptured
                if S::N_GRAD > 0
                    && c.rupture_time_h.is_some()
                    && res.t_end.re() > (1.0 - HORIZON_MARGIN) * self.ode_for(c).t_end =>
            {
                Err(EvalFailure(format!(
                    "{} °C {} MPa: ruptures within {} % of the integration horizon \
                     (with sensitivities: counted as no rupture)",
                    c.temperature_c,
                    c.stress_mpa,
                    100.0 * HORIZON_MARGIN
                )))
            }
            Outcome::Ruptured => {
                for (k, &t) in times.iter().enumerate().skip(res.n_out) {
                    cont(k, res.strain_end + res.rate_end * (-res.t_end + t));
                }
                Ok((res.outcome, res.t_end, res.strain_end, res.min_rate))
            }
            Outcome::Horizon if c.rupture_time_h.is_none() && res.n_out == n => Ok((
                res.outcome,
                S::cst(f64::NAN),
                S::cst(f64::NAN),
                res.min_rate,
            )),
            other => Err(EvalFailure(format!(
                "{} °C {} MPa: {}",
                c.temperature_c,
                c.stress_mpa,
                other.as_str()
            ))),
        }
    }

    /// The relative lifetime error (t_r − t_exp)/t_exp that eq. 8 counts: with the `late`
    /// term only a late prediction (positive error), else zero.
    fn lifetime_error<S: SimScalar>(&self, t_r: S, t_exp: f64) -> S {
        let rel = (t_r - t_exp) / t_exp;
        match self.lifetime {
            LifetimeTerm::Late if !(rel.re() > 0.0) => S::cst(0.0),
            _ => rel,
        }
    }

    /// Fill `r` (length [`Objective::n_residuals`]) at the physical constants `params`.
    pub fn residuals(&self, params: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        self.residuals_in(params, r)
    }

    /// [`Objective::residuals`] in any [`SimScalar`]: with dual-number constants the residuals
    /// carry their derivatives.
    pub fn residuals_in<S: SimScalar>(&self, params: &[S], r: &mut [S]) -> Result<(), EvalFailure> {
        let mut off = 0;
        for (i, c) in self.curves.iter().enumerate() {
            let n = c.times_h.len();
            let (_, t_r, _, _) = self.predict(i, params, &mut r[off..off + n])?;
            let inv = 1.0 / c.rupture_strain;
            for k in 0..n {
                r[off + k] = (r[off + k] - c.strains[k]) * inv;
            }
            if let Some(b) = self.bins {
                for (rk, wk) in r[off..off + n].iter_mut().zip(&b.weights[i]) {
                    *rk = *rk * *wk;
                }
            }
            r[off + n] = match c.rupture_time_h {
                Some(t_exp) => self.lifetime_error(t_r, t_exp) * self.w[i].sqrt(),
                None => S::cst(0.0),
            };
            off += n + 1;
        }
        if let Some(b) = self.bins {
            r[off] = S::cst(b.scatter.sqrt());
        }
        Ok(())
    }

    /// The residuals of [`Objective::residuals_in`] in dual numbers, handed to `sink(i0,
    /// residuals)` in order and in chunks (residuals i0, i0 + 1, …) as the integrator
    /// produces them: nothing as long as the data is stored. Same arithmetic as
    /// `residuals_in`.
    pub fn stream_residuals(
        &self,
        params: &[Dual<SENS>],
        mut sink: impl FnMut(usize, &[Dual<SENS>]),
    ) -> Result<(), EvalFailure> {
        const CHUNK: usize = 256;
        let mut buf = [Dual::<SENS>::cst(0.0); CHUNK];
        let mut off = 0;
        for (i, c) in self.curves.iter().enumerate() {
            let n = c.times_h.len();
            let inv = 1.0 / c.rupture_strain;
            let pw = self.bins.map(|b| &b.weights[i][..]);
            let mut points = |k0: usize, strains: &[Dual<SENS>]| {
                for (j0, part) in (k0..).step_by(CHUNK).zip(strains.chunks(CHUNK)) {
                    for (j, (s, rk)) in part.iter().zip(buf.iter_mut()).enumerate() {
                        let k = j0 + j;
                        *rk = (*s - c.strains[k]) * inv;
                        if let Some(pw) = pw {
                            *rk = *rk * pw[k];
                        }
                    }
                    sink(off + j0, &buf[..part.len()]);
                }
            };
            let mut pbuf = [Dual::<SENS>::cst(0.0); MAX_PARAMS];
            let np = self.curve_params(i, params, &mut pbuf);
            let t_r = if let Some(g) = &c.groups {
                // Group means: the model at every reading, averaged, then as any point.
                let mut raw = vec![Dual::<SENS>::cst(0.0); g.times_h.len()];
                let res = self.model.simulate_sens(
                    &pbuf[..np],
                    &self.load(c),
                    &g.times_h,
                    &mut raw,
                    &self.ode_for(c),
                );
                let (_, t_r, _, _) = self.conclude(i, &res, &g.times_h, |k, s| raw[k] = s)?;
                let mut mean = vec![Dual::<SENS>::cst(0.0); n];
                g.average(&raw, &mut mean);
                points(0, &mean);
                t_r
            } else {
                let res = self.model.simulate_sens_each(
                    &pbuf[..np],
                    &self.load(c),
                    &c.times_h,
                    &mut points,
                    &self.ode_for(c),
                );
                self.conclude(i, &res, &c.times_h, |k, s| points(k, &[s]))?
                    .1
            };
            let life = match c.rupture_time_h {
                Some(t_exp) => self.lifetime_error(t_r, t_exp) * self.w[i].sqrt(),
                None => Dual::cst(0.0),
            };
            sink(off + n, &[life]);
            off += n + 1;
        }
        if let Some(b) = self.bins {
            sink(off, &[Dual::cst(b.scatter.sqrt())]);
        }
        Ok(())
    }

    /// Evaluate everything reports need at `params`; a failed simulation gives NaN entries.
    pub fn evaluate(&self, params: &[f64]) -> Evaluation {
        let mut curves = Vec::with_capacity(self.curves.len());
        let mut objective = 0.0;
        let mut norm = 0.0;
        for (i, c) in self.curves.iter().enumerate() {
            let n = c.times_h.len();
            let mut strain = vec![f64::NAN; n];
            match self.predict(i, params, &mut strain) {
                Ok((outcome, t_r, e_r, min_rate)) => {
                    let s: f64 = match self.bins {
                        None => (0..n)
                            .map(|k| ((strain[k] - c.strains[k]) / c.rupture_strain).powi(2))
                            .sum(),
                        Some(b) => (0..n)
                            .map(|k| {
                                ((strain[k] - c.strains[k]) / c.rupture_strain * b.weights[i][k])
                                    .powi(2)
                            })
                            .sum(),
                    };
                    norm += s;
                    objective += s;
                    if let Some(t_exp) = c.rupture_time_h {
                        let rel = self.lifetime_error(t_r, t_exp);
                        objective += self.w[i] * rel * rel;
                    }
                    curves.push(CurvePrediction {
                        outcome,
                        rupture_time_h: t_r,
                        rupture_strain: e_r,
                        min_rate,
                        strain,
                    });
                }
                Err(_) => {
                    let mut buf = [0.0; MAX_PARAMS];
                    let np = self.curve_params(i, params, &mut buf);
                    // What the simulation reached, at the points as they are compared (a group
                    // mean of the readings it did not all reach is NaN).
                    let res = match &c.groups {
                        Some(g) => {
                            let mut raw = vec![f64::NAN; g.times_h.len()];
                            let res = self.model.simulate(
                                &buf[..np],
                                &self.load(c),
                                &g.times_h,
                                &mut raw,
                                &self.ode_for(c),
                            );
                            g.average(&raw, &mut strain);
                            res
                        }
                        None => self.model.simulate(
                            &buf[..np],
                            &self.load(c),
                            &c.times_h,
                            &mut strain,
                            &self.ode_for(c),
                        ),
                    };
                    objective = f64::NAN;
                    norm = f64::NAN;
                    curves.push(CurvePrediction {
                        outcome: res.outcome,
                        rupture_time_h: f64::NAN,
                        rupture_strain: f64::NAN,
                        min_rate: res.min_rate,
                        strain,
                    });
                }
            }
        }
        let scatter = self.bins.map_or(0.0, |b| b.scatter);
        Evaluation {
            objective: objective + scatter,
            norm_residual: norm + scatter,
            curves,
        }
    }
}

/// Eq. 8 in the unit box of a [`ParamSpace`]: what the optimiser sees.
pub struct CreepProblem<'a> {
    /// The objective in physical constants.
    pub objective: Objective<'a>,
    /// The mapping to the unit box.
    pub space: ParamSpace,
    /// How the Jacobian is computed.
    pub jacobian: JacobianMethod,
}

impl LeastSquaresProblem for CreepProblem<'_> {
    fn n_params(&self) -> usize {
        self.space.n_free()
    }
    fn n_residuals(&self) -> usize {
        self.objective.n_residuals()
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let mut x = [0.0; MAX_PARAMS];
        let n = self.space.len();
        self.space.from_unit(u, &mut x[..n]);
        self.objective.residuals(&x[..n], r)
    }
    fn jacobian(
        &self,
        u: &[f64],
        _r: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        self.sensitivities(u, None, jac)
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        self.sensitivities(u, Some(r), jac)
    }
    fn prefers_normal_equations(&self) -> bool {
        self.streams_normal_equations()
            && self.objective.n_residuals() >= NORMAL_EQUATIONS_MIN_RESIDUALS
    }
    fn residuals_and_normal_equations(
        &self,
        u: &[f64],
        r: &mut [f64],
        ne: &mut NormalEquations,
    ) -> Option<Result<(), EvalFailure>> {
        let (xd, n_free) = self.dual_params(u)?;
        let mut acc = NormalAccumulator::default();
        let res = self
            .objective
            .stream_residuals(&xd[..self.space.len()], |i0, rs| {
                for (ri, di) in r[i0..i0 + rs.len()].iter_mut().zip(rs) {
                    *ri = di.v;
                }
                acc.add(rs);
            });
        Some(res.map(|()| acc.write(ne, n_free)))
    }
    fn geodesic_normal(
        &self,
        u: &[f64],
        v: &[f64],
        h: f64,
        r: &[f64],
        r_probe: &[f64],
        jt_rvv: &mut [f64],
    ) -> Option<Result<(), EvalFailure>> {
        let (xd, n_free) = self.dual_params(u)?;
        let mut vv = [0.0; SENS];
        vv[..n_free].copy_from_slice(&v[..n_free]);
        let mut sum = [0.0; SENS];
        let res = self
            .objective
            .stream_residuals(&xd[..self.space.len()], |i0, rs| {
                let mut part = [0.0; SENS];
                for (i, ri) in (i0..).zip(rs) {
                    let mut jv = 0.0;
                    for k in 0..SENS {
                        jv += ri.d[k] * vv[k];
                    }
                    let rvv = 2.0 / h * ((r_probe[i] - r[i]) / h - jv);
                    for k in 0..SENS {
                        part[k] += ri.d[k] * rvv;
                    }
                }
                for k in 0..SENS {
                    sum[k] += part[k];
                }
            });
        jt_rvv[..n_free].copy_from_slice(&sum[..n_free]);
        Some(res)
    }
}

/// JᵀJ and Jᵀr of dual-number residuals, accumulated chunk by chunk: fixed 8 × 8 (the
/// unused rows are zero) in local sums over a chunk (kept in registers) that are then added
/// to the total, which also keeps the rounding of a million-term sum at that of a few
/// hundred terms.
#[derive(Default)]
struct NormalAccumulator {
    jtj: [[f64; SENS]; SENS],
    jtr: [f64; SENS],
}

impl NormalAccumulator {
    /// Add the residuals `rs` (values and gradients).
    fn add(&mut self, rs: &[Dual<SENS>]) {
        let mut jtj = [[0.0; SENS]; SENS];
        let mut jtr = [0.0; SENS];
        for ri in rs {
            for a in 0..SENS {
                jtr[a] += ri.d[a] * ri.v;
                for b in 0..SENS {
                    jtj[a][b] += ri.d[a] * ri.d[b];
                }
            }
        }
        for a in 0..SENS {
            self.jtr[a] += jtr[a];
            for b in 0..SENS {
                self.jtj[a][b] += jtj[a][b];
            }
        }
    }

    /// The sums for the first `n` gradient components into `ne`.
    fn write(self, ne: &mut NormalEquations, n: usize) {
        ne.jtj = nalgebra::DMatrix::from_fn(n, n, |a, b| self.jtj[a][b]);
        ne.jtr = nalgebra::DVector::from_fn(n, |a, _| self.jtr[a]);
    }
}

impl CreepProblem<'_> {
    /// Whether the optimiser may work on streamed normal equations: sensitivities asked
    /// for and at most [`SENS`] free constants (one narrow dual pass gives every column of
    /// JᵀJ; with more, the stored Jacobian of chunked wide passes is used).
    fn streams_normal_equations(&self) -> bool {
        self.jacobian == JacobianMethod::Sensitivity && self.space.n_free() <= SENS
    }

    /// The physical constants at unit-box point `u` as `Dual<K>` numbers, the free constants
    /// `first..end` (in free-constant order) seeded with dx/du, the others constant.
    fn seeded<const K: usize>(&self, u: &[f64], first: usize, end: usize) -> [Dual<K>; MAX_PARAMS] {
        debug_assert!(end - first <= K);
        let n = self.space.len();
        let mut x = [0.0; MAX_PARAMS];
        self.space.from_unit(u, &mut x[..n]);
        let mut xd = [Dual::<K>::cst(0.0); MAX_PARAMS];
        let mut k = 0;
        for j in 0..n {
            xd[j] = if self.space.free[j] {
                let d = if (first..end).contains(&k) {
                    Dual::var(x[j], k - first, self.space.dx_du(j, x[j]))
                } else {
                    Dual::cst(x[j])
                };
                k += 1;
                d
            } else {
                Dual::cst(x[j])
            };
        }
        xd
    }

    /// The constants as narrow dual numbers seeded for every free constant, and the number
    /// of free ones, for the streamed normal equations; `None` where those are not used
    /// ([`CreepProblem::streams_normal_equations`]).
    fn dual_params(&self, u: &[f64]) -> Option<([Dual<SENS>; MAX_PARAMS], usize)> {
        if !self.streams_normal_equations() {
            return None;
        }
        let n_free = self.space.n_free();
        Some((self.seeded::<SENS>(u, 0, n_free), n_free))
    }

    /// The sensitivity Jacobian (dual numbers), and the residuals with it if `r` is given;
    /// `None` only when the configuration asks for finite differences. The width of the dual
    /// numbers follows the number of free constants: [`SENS`] (the common case, as fast as
    /// before there was a choice), [`SENS_WIDE`], or chunks of [`SENS_WIDE`] constants, one
    /// simulation of every curve per chunk.
    fn sensitivities(
        &self,
        u: &[f64],
        mut r: Option<&mut [f64]>,
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        if self.jacobian != JacobianMethod::Sensitivity {
            return None;
        }
        let n_free = self.space.n_free();
        if n_free <= SENS {
            return Some(self.sensitivity_pass::<SENS>(u, 0, n_free, r, jac));
        }
        let mut first = 0;
        while first < n_free {
            let end = (first + SENS_WIDE).min(n_free);
            if let Err(e) = self.sensitivity_pass::<SENS_WIDE>(u, first, end, r.take(), jac) {
                return Some(Err(e));
            }
            first = end;
        }
        Some(Ok(()))
    }

    /// One simulation of every curve in `Dual<K>` with the free constants `first..end`
    /// seeded (in free-constant order): fills those columns of `jac`, and `r` if given.
    fn sensitivity_pass<const K: usize>(
        &self,
        u: &[f64],
        first: usize,
        end: usize,
        r: Option<&mut [f64]>,
        jac: &mut DMatrix<f64>,
    ) -> Result<(), EvalFailure>
    where
        Dual<K>: SimScalar + DualBuffer,
    {
        let n = self.space.len();
        let xd = self.seeded::<K>(u, first, end);
        // The dual residuals go to a buffer kept per thread: for a logged curve of a million
        // points it is 72 MB, which a fresh allocation per Jacobian would page-fault in anew.
        Dual::<K>::with_buffer(|rd| {
            rd.clear();
            rd.resize(self.objective.n_residuals(), Dual::<K>::cst(0.0));
            self.objective.residuals_in(&xd[..n], rd)?;
            // One pass over the dual residuals (the column-by-column copy reads them k times).
            let m = rd.len();
            let js = jac.as_mut_slice();
            for (i, ri) in rd.iter().enumerate() {
                for c in first..end {
                    js[c * m + i] = ri.d[c - first];
                }
            }
            if let Some(r) = r {
                for (ri, di) in r.iter_mut().zip(rd.iter()) {
                    *ri = di.re();
                }
            }
            Ok(())
        })
    }
}

/// Dual numbers with a reusable residual buffer per thread (one per width).
pub trait DualBuffer: Sized {
    /// Run `f` on this thread's buffer.
    fn with_buffer<R>(f: impl FnOnce(&mut Vec<Self>) -> R) -> R;
}

thread_local! {
    /// Reused buffer of [`CreepProblem::sensitivity_pass`], narrow width.
    static DUAL_RESIDUALS: std::cell::RefCell<Vec<Dual<SENS>>> =
        const { std::cell::RefCell::new(Vec::new()) };
    /// Reused buffer of [`CreepProblem::sensitivity_pass`], wide width.
    static DUAL_RESIDUALS_WIDE: std::cell::RefCell<Vec<Dual<SENS_WIDE>>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

impl DualBuffer for Dual<SENS> {
    fn with_buffer<R>(f: impl FnOnce(&mut Vec<Self>) -> R) -> R {
        DUAL_RESIDUALS.with(|b| f(&mut b.borrow_mut()))
    }
}

impl DualBuffer for Dual<SENS_WIDE> {
    fn with_buffer<R>(f: impl FnOnce(&mut Vec<Self>) -> R) -> R {
        DUAL_RESIDUALS_WIDE.with(|b| f(&mut b.borrow_mut()))
    }
}

/// Which side of the lifetime error enters the objective (eq. 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LifetimeTerm {
    /// Only when the prediction ruptures later than measured (the paper).
    #[default]
    Late,
    /// Always.
    Both,
}

/// What a local fit minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectiveKind {
    /// The seed paper's eq. 8 at each lifetime weight w (README, "Choices").
    #[default]
    Eq8,
    /// −2 ln L under the error model ([`crate::likelihood`]: AR(1) reading error per curve,
    /// log-normal rupture-time scatter, both estimated with the constants): the strain and
    /// lifetime terms weighed by their own measured scatter instead of by w, and a densely
    /// logged curve counts as much as its correlated errors say, not by its point count.
    Likelihood,
}

/// Numerical settings of a fit: a view of the resolved `RunConfig`, derived from it only
/// by `FitSettings::from_config` (in `crate::config`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// Levenberg–Marquardt options (unit-box coordinates).
    pub lm: LmOptions,
    /// Integration options.
    pub ode: OdeOptions,
    /// Damage at rupture ω_f.
    pub omega_f: f64,
    /// Lifetime term of eq. 8.
    pub lifetime: LifetimeTerm,
    /// How the local fits' Jacobian is computed.
    pub jacobian: JacobianMethod,
    /// What the local fits minimise.
    pub kind: ObjectiveKind,
    /// Floor of the rupture-time scatter (ln scale) under [`ObjectiveKind::Likelihood`].
    pub lifetime_sd_floor: f64,
}

impl FitSettings {
    /// What eq. 8 takes of these settings.
    pub fn objective(&self) -> ObjectiveSettings {
        ObjectiveSettings {
            lifetime: self.lifetime,
            omega_f: self.omega_f,
            ode: self.ode,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(times: Vec<f64>, strains: Vec<f64>) -> Curve {
        Curve {
            temperature_c: 560.0,
            stress_mpa: 100.0,
            specimen: None,
            times_h: times,
            strains,
            rupture_time_h: Some(10.0),
            rupture_strain: 0.5,
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 0.01,
        }
    }

    #[test]
    fn bins_average_consecutive_points_and_keep_the_scatter_about_their_lines() {
        // 7 points, at most 3 a curve: bins of 3, 3 and 1 point.
        let t = vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        // On a line but for ±d at the middle point of the first bin and the ends of the
        // second: the scatter about each bin's least-squares line.
        let d = 0.01;
        let e: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(k, &t)| 0.1 * t + [0.0, d, 0.0, d, 0.0, d, 0.0][k])
            .collect();
        let short = curve(vec![0.0, 1.0, 2.0], vec![0.0, 0.1, 0.2]);
        let b = bin_curves(&[curve(t, e.clone()), short.clone()], 3);
        assert_eq!(b.curves[1], short);
        assert_eq!(b.weights[1], vec![1.0; 3]);
        let c = &b.curves[0];
        assert_eq!(c.times_h, vec![1.0, 4.0, 6.0]);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-15;
        assert!(close(c.strains[0], 0.1 + d / 3.0));
        assert!(close(c.strains[1], 0.4 + 2.0 * d / 3.0));
        assert!(close(c.strains[2], e[6]));
        let s3 = 3f64.sqrt();
        assert_eq!(b.weights[0], vec![s3, s3, 1.0]);
        // A bump (0, d, 0) or a dip (d, 0, d) about a line: deviations (−1, 2, −1)·d/3 from
        // the mean, none of them along the slope: 6·d²/9 each, over ε_f² = 0.25.
        let want = 2.0 * (6.0 * d * d / 9.0) / 0.25;
        assert!((b.scatter - want).abs() < 1e-15, "{} vs {want}", b.scatter);
        assert_eq!(c.rupture_strain, 0.5);
        assert_eq!(c.min_rate_estimated, 0.01);
    }
}
