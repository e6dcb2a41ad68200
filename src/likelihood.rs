//! Constants fitted by maximum likelihood under the error model of [`crate::errmodel`].
//!
//! The residuals come from eq. 8's residual vector at w = 1 on every curve with the lifetime
//! term on both sides ([`crate::objective::Objective`]): strain (ε_pred − ε)/ε_f, multiplied
//! back by ε_f, and (t_r − t_f)/t_f, taken as ln(1 + ·) = ln(t_r/t_f). Whitened by the error
//! model (AR(1) innovations per curve, log lifetime residuals over their scatter), their sum
//! of squares is −2 ln L up to terms of the error model alone; the error model itself is
//! profiled out: re-estimated from the residuals at every accepted point of the
//! Levenberg–Marquardt iteration ([`LeastSquaresProblem::reweight`]), so constants and error
//! model converge together and −2 ln L falls at every step.
//!
//! The predictions are the model's at the measured times; after a predicted rupture, eq. 8's
//! C¹ continuation keeps the residual smooth for the optimiser, and the log lifetime term —
//! weighted by the estimated scatter of rupture times, not by a chosen w — is what keeps a fit
//! from rupturing early and following the data with the continuation.

use std::sync::Mutex;

use nalgebra::DMatrix;

use crate::config::LifetimeTerm;
use crate::data::Curve;
use crate::errmodel::{ErrorModel, Residuals};
use crate::fit::FitSettings;
use crate::lsq::{minimize, EvalFailure, LeastSquaresProblem, Termination};
use crate::model::Model;
use crate::objective::{CreepProblem, Evaluation, Objective, ObjectiveSettings, ParamSpace};

/// Options of [`ml_fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MlOptions {
    /// Floor of the rupture-time scatter (ln scale).
    pub lifetime_sd_floor: f64,
    /// Fit with white reading errors first, then with the AR(1) model from there (a fresh
    /// start); `false` polishes with the AR(1) model directly (a start at an optimum already
    /// found, which the white stage could only lead away from).
    pub white_first: bool,
}

impl Default for MlOptions {
    fn default() -> Self {
        MlOptions {
            lifetime_sd_floor: crate::errmodel::DEFAULT_LIFETIME_SD_FLOOR,
            white_first: true,
        }
    }
}

/// Eq. 8 at w = 1 on every curve, lifetime term on both sides: the residual vector the
/// likelihood transforms.
pub fn raw_objective<'a>(
    model: &'a dyn Model,
    curves: &'a [Curve],
    settings: &FitSettings,
) -> Objective<'a> {
    Objective::new(
        model,
        curves,
        vec![1.0; curves.len()],
        ObjectiveSettings {
            lifetime: LifetimeTerm::Both,
            ..settings.objective()
        },
    )
}

/// Raw residuals from an eq. 8 residual vector of [`raw_objective`] (layout: per curve its
/// strain residuals, then its lifetime residual).
pub fn split_residuals(curves: &[Curve], r: &[f64]) -> Residuals {
    let mut off = 0;
    let mut strain = Vec::with_capacity(curves.len());
    let mut lifetime = Vec::with_capacity(curves.len());
    for c in curves {
        let n = c.times_h.len();
        strain.push(
            r[off..off + n]
                .iter()
                .map(|v| v * c.rupture_strain)
                .collect(),
        );
        lifetime.push(c.rupture_time_h.map(|_| r[off + n].ln_1p()));
        off += n + 1;
    }
    Residuals { strain, lifetime }
}

/// Raw residuals of `model` at `params`.
pub fn residuals_at(
    model: &dyn Model,
    curves: &[Curve],
    params: &[f64],
    settings: &FitSettings,
) -> Result<Residuals, EvalFailure> {
    let obj = raw_objective(model, curves, settings);
    let mut r = vec![0.0; obj.n_residuals()];
    obj.residuals(params, &mut r)?;
    Ok(split_residuals(curves, &r))
}

/// −2 ln L as a least-squares problem in the unit box, with the error model profiled out
/// (re-estimated at every accepted point).
pub struct LikelihoodProblem<'a> {
    /// Eq. 8 (w = 1, both sides) in the unit box.
    pub inner: CreepProblem<'a>,
    /// The current error model.
    noise: Mutex<ErrorModel>,
    /// Floor of the rupture-time scatter.
    lifetime_sd_floor: f64,
    /// Keep the error model fixed (no profiling): −2 ln L at a known error model.
    fixed: bool,
    /// Profile the error model with every reading error white (φ = 0).
    white: bool,
}

impl<'a> LikelihoodProblem<'a> {
    /// The problem for `inner` starting from error model `noise`.
    pub fn new(inner: CreepProblem<'a>, noise: ErrorModel, lifetime_sd_floor: f64) -> Self {
        LikelihoodProblem {
            inner,
            noise: Mutex::new(noise),
            lifetime_sd_floor,
            fixed: false,
            white: false,
        }
    }

    /// The problem for `inner` starting from the white error model `noise`, profiled with
    /// φ = 0 on every curve.
    pub fn white(inner: CreepProblem<'a>, noise: ErrorModel, lifetime_sd_floor: f64) -> Self {
        LikelihoodProblem {
            white: true,
            ..LikelihoodProblem::new(inner, noise, lifetime_sd_floor)
        }
    }

    /// The problem at a known, fixed error model `noise`.
    pub fn fixed(inner: CreepProblem<'a>, noise: ErrorModel) -> Self {
        LikelihoodProblem {
            inner,
            noise: Mutex::new(noise),
            lifetime_sd_floor: 0.0,
            fixed: true,
            white: false,
        }
    }

    /// The current error model.
    pub fn noise(&self) -> ErrorModel {
        self.noise.lock().expect("noise lock").clone()
    }

    fn curves(&self) -> &[Curve] {
        self.inner.objective.curves()
    }

    /// Whiten eq. 8 residuals `r` (and the Jacobian rows of `jac`, if given) in place.
    fn transform(&self, r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) {
        let noise = self.noise();
        let s = noise.lifetime_sd;
        let mut off = 0;
        for (i, c) in self.curves().iter().enumerate() {
            let n = c.times_h.len();
            let ef = c.rupture_strain;
            let p = &noise.strain[i];
            for v in &mut r[off..off + n] {
                *v *= ef;
            }
            p.whiten(&mut r[off..off + n]);
            if let Some(j) = jac.as_deref_mut() {
                let nrows = j.nrows();
                for k in 0..j.ncols() {
                    let col = &mut j.as_mut_slice()[k * nrows + off..k * nrows + off + n];
                    for v in col.iter_mut() {
                        *v *= ef;
                    }
                    p.whiten(col);
                }
            }
            let rel = r[off + n];
            let d = if c.rupture_time_h.is_some() {
                r[off + n] = rel.ln_1p() / s;
                1.0 / ((1.0 + rel) * s)
            } else {
                r[off + n] = 0.0;
                0.0
            };
            if let Some(j) = jac.as_deref_mut() {
                for k in 0..j.ncols() {
                    j[(off + n, k)] *= d;
                }
            }
            off += n + 1;
        }
    }
}

impl LeastSquaresProblem for LikelihoodProblem<'_> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals()
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        self.inner.residuals(u, r)?;
        self.transform(r, None);
        Ok(())
    }
    fn jacobian(
        &self,
        u: &[f64],
        _r: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let mut raw = vec![0.0; self.n_residuals()];
        self.residuals_and_jacobian(u, &mut raw, jac)
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        match self.inner.residuals_and_jacobian(u, r, jac)? {
            Ok(()) => {
                self.transform(r, Some(jac));
                Some(Ok(()))
            }
            Err(e) => Some(Err(e)),
        }
    }
    fn reweight(&self, _x: &[f64], r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> bool {
        if self.fixed {
            return false;
        }
        let mut guard = self.noise.lock().expect("noise lock");
        let old = guard.clone();
        // Back to raw residuals (strain fraction, ln lifetime) under the old model.
        let curves = self.curves();
        let mut res = Residuals {
            strain: Vec::with_capacity(curves.len()),
            lifetime: Vec::with_capacity(curves.len()),
        };
        let mut off = 0;
        for (i, c) in curves.iter().enumerate() {
            let n = c.times_h.len();
            let mut e = r[off..off + n].to_vec();
            old.strain[i].unwhiten_strided(&mut e, n, 1);
            res.strain.push(e);
            res.lifetime
                .push(c.rupture_time_h.map(|_| r[off + n] * old.lifetime_sd));
            off += n + 1;
        }
        let new = if self.white {
            ErrorModel::estimate_white(&res, self.lifetime_sd_floor)
        } else {
            ErrorModel::estimate(&res, self.lifetime_sd_floor)
        };
        if new == old {
            return false;
        }
        let mut off = 0;
        for (i, c) in curves.iter().enumerate() {
            let n = c.times_h.len();
            let (po, pn) = (&old.strain[i], &new.strain[i]);
            r[off..off + n].copy_from_slice(&res.strain[i]);
            pn.whiten(&mut r[off..off + n]);
            if let Some(j) = jac.as_deref_mut() {
                let nrows = j.nrows();
                for k in 0..j.ncols() {
                    let col = &mut j.as_mut_slice()[k * nrows + off..k * nrows + off + n];
                    po.unwhiten_strided(col, n, 1);
                    pn.whiten(col);
                }
            }
            let ratio = old.lifetime_sd / new.lifetime_sd;
            r[off + n] *= ratio;
            if let Some(j) = jac.as_deref_mut() {
                for k in 0..j.ncols() {
                    j[(off + n, k)] *= ratio;
                }
            }
            off += n + 1;
        }
        *guard = new;
        true
    }
}

/// A maximum-likelihood fit: constants and error model.
#[derive(Debug, Clone)]
pub struct MlFit {
    /// Fitted constants (physical), model order.
    pub params: Vec<f64>,
    /// The error model at the fit.
    pub noise: ErrorModel,
    /// −2 ln L at the fit (NaN if the fit failed).
    pub neg2ll: f64,
    /// Raw residuals at the fit.
    pub residuals: Option<Residuals>,
    /// Predictions at the fit (eq. 8 at w = 1, both sides, for reports).
    pub eval: Option<Evaluation>,
    /// How the iteration ended.
    pub termination: Termination,
    /// LM iterations.
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Why it failed, if it did.
    pub failure: Option<String>,
}

impl MlFit {
    /// Whether the fit ended at an evaluable point.
    pub fn ok(&self) -> bool {
        self.neg2ll.is_finite() && self.termination != Termination::SimulationFailure
    }

    fn failed(start: &[f64], msg: String, iterations: usize, evaluations: usize) -> MlFit {
        MlFit {
            params: start.to_vec(),
            noise: ErrorModel {
                strain: vec![],
                lifetime_sd: f64::NAN,
            },
            neg2ll: f64::NAN,
            residuals: None,
            eval: None,
            termination: Termination::SimulationFailure,
            iterations,
            evaluations,
            failure: Some(msg),
        }
    }
}

/// Fit `model`'s constants to `curves` by maximum likelihood from `start` (physical,
/// model order; constants not free in `space` stay at their held values).
pub fn ml_fit(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    start: &[f64],
    settings: &FitSettings,
    opts: &MlOptions,
) -> MlFit {
    let res = match residuals_at(model, curves, start, settings) {
        Ok(r) => r,
        Err(e) => return MlFit::failed(start, e.0, 0, 1),
    };
    let inner = || CreepProblem {
        objective: raw_objective(model, curves, settings),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let u0 = space.to_unit(start);
    let (lo, hi) = (vec![0.0; u0.len()], vec![1.0; u0.len()]);
    // Stage 1: white reading errors. A smooth misfit (a loading strain left out, a primary
    // stage missed) is what an AR(1) model with φ near 1 explains as noise; from such a start
    // the profiled likelihood cannot see it, and the LM stops where it began. With white
    // errors it is misfit and the constants move to remove it.
    let (u1, it1, ev1) = if opts.white_first {
        let white = LikelihoodProblem::white(
            inner(),
            ErrorModel::estimate_white(&res, opts.lifetime_sd_floor),
            opts.lifetime_sd_floor,
        );
        let lm1 = minimize(&white, &u0, &lo, &hi, &settings.lm);
        if lm1.termination == Termination::SimulationFailure {
            return MlFit::failed(
                start,
                lm1.failure.unwrap_or_default(),
                lm1.iterations,
                lm1.evaluations,
            );
        }
        (lm1.x, lm1.iterations, lm1.evaluations)
    } else {
        (u0, 0, 0)
    };
    // Stage 2: the full error model, from stage 1's point.
    let res1 = if opts.white_first {
        let mut x1 = start.to_vec();
        space.from_unit(&u1, &mut x1);
        match residuals_at(model, curves, &x1, settings) {
            Ok(r) => r,
            Err(e) => return MlFit::failed(start, e.0, it1, ev1),
        }
    } else {
        res
    };
    let problem = LikelihoodProblem::new(
        inner(),
        ErrorModel::estimate(&res1, opts.lifetime_sd_floor),
        opts.lifetime_sd_floor,
    );
    let mut lm = minimize(&problem, &u1, &lo, &hi, &settings.lm);
    lm.iterations += it1;
    lm.evaluations += ev1;
    if lm.termination == Termination::SimulationFailure {
        return MlFit::failed(
            start,
            lm.failure.unwrap_or_default(),
            lm.iterations,
            lm.evaluations,
        );
    }
    let mut x = start.to_vec();
    space.from_unit(&lm.x, &mut x);
    let Ok(res) = residuals_at(model, curves, &x, settings) else {
        return MlFit::failed(
            start,
            "the fitted point could not be evaluated".into(),
            lm.iterations,
            lm.evaluations,
        );
    };
    let noise = ErrorModel::estimate(&res, opts.lifetime_sd_floor);
    let neg2ll = noise.neg2ll(&res);
    let eval = raw_objective(model, curves, settings).evaluate(&x);
    MlFit {
        params: x,
        noise,
        neg2ll,
        residuals: Some(res),
        eval: Some(eval),
        termination: lm.termination,
        iterations: lm.iterations,
        evaluations: lm.evaluations,
        failure: None,
    }
}

/// The smallest sum of squared whitened residuals of `model` on `curves` under the known error
/// model `noise` (no profiling), over fits from `starts`: the noncentrality of a
/// likelihood-ratio test that knows the error model. Returns (minimum, its constants);
/// `None` if every start failed.
pub fn min_whitened_ss(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    starts: &[Vec<f64>],
    settings: &FitSettings,
    noise: &ErrorModel,
) -> Option<(f64, Vec<f64>)> {
    let mut best: Option<(f64, Vec<f64>)> = None;
    for s in starts {
        let problem = LikelihoodProblem::fixed(
            CreepProblem {
                objective: raw_objective(model, curves, settings),
                space: space.clone(),
                jacobian: settings.jacobian,
            },
            noise.clone(),
        );
        let u0 = space.to_unit(s);
        let k = u0.len();
        let lm = minimize(&problem, &u0, &vec![0.0; k], &vec![1.0; k], &settings.lm);
        if lm.termination == Termination::SimulationFailure || !lm.objective.is_finite() {
            continue;
        }
        if best.as_ref().is_none_or(|b| lm.objective < b.0) {
            let mut x = s.clone();
            space.from_unit(&lm.x, &mut x);
            best = Some((lm.objective, x));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errmodel::Ar1;

    #[test]
    fn split_residuals_undo_the_eq8_scaling() {
        let c = Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: None,
            times_h: vec![0.0, 1.0],
            strains: vec![0.0, 0.01],
            rupture_time_h: Some(10.0),
            rupture_strain: 0.05,
            min_rate_measured: None,
            min_rate_estimated: 1e-3,
        };
        let r = [0.1, -0.2, 0.5];
        let s = split_residuals(std::slice::from_ref(&c), &r);
        assert!((s.strain[0][0] - 0.005).abs() < 1e-15);
        assert!((s.strain[0][1] + 0.01).abs() < 1e-15);
        assert!((s.lifetime[0].unwrap() - 1.5f64.ln()).abs() < 1e-15);
        let m = ErrorModel {
            strain: vec![Ar1::white(1e-3)],
            lifetime_sd: 0.1,
        };
        assert!(m.neg2ll(&s).is_finite());
    }
}
