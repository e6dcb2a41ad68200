//! The paper's calibration procedure: initial guess, a bounded LM fit for every lifetime
//! weight, and the choice of the best weight.
//!
//! **Best-w rule.** Objective values at different w are not comparable. Every converged
//! local fit is scored on the paper's criteria — the normalised strain residual, the mean
//! absolute lifetime error and, where the ruptures file gives measured minimum rates, the mean
//! absolute minimum-rate error. Each criterion is min–max normalised over the candidates
//! (0 = best candidate, 1 = worst) and the candidate with the smallest sum wins: the
//! compromise closest to the ideal point, which is Pareto-optimal by construction. Ties go
//! to the earlier candidate.

use std::time::Instant;

use rayon::prelude::*;

use crate::config::{LifetimeTerm, RunConfig};
use crate::data::{Curve, Dataset};
use crate::error::{Error, Result};
use crate::guess::{initial_guess, Guess};
use crate::lsq::{minimize, LmOptions, LmReport, Termination};
use crate::model::{registry, Model};
use crate::objective::{mean_abs, CreepProblem, Evaluation, Objective, ParamSpace};
use crate::ode::OdeOptions;

/// Numerical settings of a fit.
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
}

impl FitSettings {
    /// Settings from a run configuration.
    pub fn from_config(cfg: &RunConfig) -> Self {
        FitSettings {
            lm: LmOptions {
                max_iterations: cfg.solver.max_iterations,
                ..LmOptions::default()
            },
            ode: OdeOptions {
                rtol: cfg.solver.rtol,
                atol: cfg.solver.atol,
                ..OdeOptions::default()
            },
            omega_f: cfg.objective.omega_f,
            lifetime: cfg.objective.lifetime_term,
        }
    }
}

/// One local fit from one start at one weight vector.
#[derive(Debug, Clone)]
pub struct LocalFit {
    /// Where the start came from (`config`, `guess`, `lhs:17`, …).
    pub start_label: String,
    /// Start constants (physical).
    pub start: Vec<f64>,
    /// Lifetime weight per curve (ascending stress).
    pub w: Vec<f64>,
    /// Fitted constants (physical).
    pub params: Vec<f64>,
    /// The optimiser's report (unit-box coordinates).
    pub lm: LmReport,
    /// Evaluation at the fitted constants.
    pub eval: Evaluation,
    /// Signed lifetime errors per curve, %.
    pub lifetime_err_pct: Vec<f64>,
    /// Signed minimum-rate errors per curve, %.
    pub min_rate_err_pct: Vec<f64>,
    /// Wall time of this fit, s.
    pub wall_s: f64,
}

impl LocalFit {
    /// Mean absolute lifetime error, %.
    pub fn mean_lifetime_err(&self) -> f64 {
        mean_abs(&self.lifetime_err_pct)
    }
    /// Mean absolute minimum-rate error, %.
    pub fn mean_min_rate_err(&self) -> f64 {
        mean_abs(&self.min_rate_err_pct)
    }
    /// Whether the fit ended at an evaluable point: converged, or stopped by the iteration
    /// limit or stalled on the long flat valleys of this objective (DESIGN.md §7), which
    /// `termination` reports; not a simulation failure.
    pub fn ok(&self) -> bool {
        self.lm.termination != Termination::SimulationFailure && self.eval.objective.is_finite()
    }
}

/// Bounds and scales of a configuration as a [`ParamSpace`].
pub fn param_space(cfg: &RunConfig) -> ParamSpace {
    ParamSpace::new(
        cfg.constants.iter().map(|c| c.lb).collect(),
        cfg.constants.iter().map(|c| c.ub).collect(),
        cfg.constants.iter().map(|c| c.scale).collect(),
    )
}

/// Bounded LM from `start` (physical constants) at lifetime weights `w`.
pub fn local_fit(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    w: &[f64],
    start: &[f64],
    start_label: &str,
    settings: &FitSettings,
) -> LocalFit {
    let t0 = Instant::now();
    let problem = CreepProblem {
        objective: Objective {
            model,
            curves,
            w: w.to_vec(),
            lifetime: settings.lifetime,
            omega_f: settings.omega_f,
            ode: settings.ode,
        },
        space: space.clone(),
    };
    let u0 = space.to_unit(start);
    let k = u0.len();
    let lm = minimize(&problem, &u0, &vec![0.0; k], &vec![1.0; k], &settings.lm);
    let mut params = start.to_vec();
    space.from_unit(&lm.x, &mut params);
    let eval = problem.objective.evaluate(&params);
    LocalFit {
        start_label: start_label.to_string(),
        start: start.to_vec(),
        w: w.to_vec(),
        lifetime_err_pct: eval.lifetime_errors_pct(curves),
        min_rate_err_pct: eval.min_rate_errors_pct(curves),
        params,
        lm,
        eval,
        wall_s: t0.elapsed().as_secs_f64(),
    }
}

/// The weight vectors a configuration asks for: each w of `w_grid` for every curve, then
/// each explicit `w_sets` entry (which must have one weight per curve).
pub fn weight_candidates(cfg: &RunConfig, n_curves: usize) -> Result<Vec<Vec<f64>>> {
    let mut out: Vec<Vec<f64>> = cfg
        .objective
        .w_grid
        .iter()
        .map(|&w| vec![w; n_curves])
        .collect();
    for (k, set) in cfg.objective.w_sets.iter().enumerate() {
        if set.len() != n_curves {
            return Err(Error::config(
                &cfg.path,
                format!(
                    "objective.w_sets[{k}] has {} weights but the data have {n_curves} curves",
                    set.len()
                ),
            ));
        }
        out.push(set.clone());
    }
    Ok(out)
}

/// Index of the best fit by the documented rule (module docs); `None` if no fit is usable.
pub fn choose_best(fits: &[LocalFit], use_min_rate: bool) -> Option<usize> {
    let ok: Vec<usize> = (0..fits.len()).filter(|&i| fits[i].ok()).collect();
    if ok.is_empty() {
        return None;
    }
    type Criterion = fn(&LocalFit) -> f64;
    let mut crits: Vec<Criterion> = vec![|f| f.eval.norm_residual, |f| f.mean_lifetime_err()];
    if use_min_rate {
        crits.push(|f| f.mean_min_rate_err());
    }
    let mut score = vec![0.0; ok.len()];
    for crit in &crits {
        let vals: Vec<f64> = ok.iter().map(|&i| crit(&fits[i])).collect();
        let finite: Vec<f64> = vals.iter().cloned().filter(|v| v.is_finite()).collect();
        if finite.is_empty() {
            continue;
        }
        let lo = finite.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = finite.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        for (s, v) in score.iter_mut().zip(&vals) {
            *s += if !v.is_finite() {
                1.0
            } else if hi > lo {
                (v - lo) / (hi - lo)
            } else {
                0.0
            };
        }
    }
    let mut best = 0;
    for k in 1..ok.len() {
        if score[k] < score[best] {
            best = k;
        }
    }
    Some(ok[best])
}

/// Everything `creepfit fit` computed.
pub struct FitRun {
    /// The model fitted.
    pub model: Box<dyn Model>,
    /// The parameter space.
    pub space: ParamSpace,
    /// The initial-guess procedure's result.
    pub guess: Guess,
    /// Every local fit (start × w).
    pub fits: Vec<LocalFit>,
    /// Index of the chosen fit in `fits`.
    pub best: usize,
    /// Whether measured minimum rates entered the choice.
    pub used_min_rate: bool,
    /// Settings used.
    pub settings: FitSettings,
    /// Total wall time, s.
    pub wall_s: f64,
}

/// Which start points `fit` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum StartChoice {
    /// The configuration's start values (if all are given) and the computed initial guess.
    #[default]
    Both,
    /// Only the configuration's start values (an error if one is missing).
    Config,
    /// Only the computed initial guess.
    Guess,
}

/// What `fit` runs beyond the configuration.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FitRequest {
    /// Start points.
    pub starts: StartChoice,
    /// One w for every curve, replacing the configuration's `w_grid` and `w_sets`.
    pub w: Option<f64>,
}

/// The paper's procedure on a configuration and its data: the initial guess, and — from the
/// configured start (if every constant has one) and from the guess — a local fit for every
/// weight vector; the best by [`choose_best`].
pub fn run_fit(cfg: &RunConfig, data: &Dataset) -> Result<FitRun> {
    run_fit_with(cfg, data, &FitRequest::default())
}

/// [`run_fit`] with a choice of starts and weights.
pub fn run_fit_with(cfg: &RunConfig, data: &Dataset, req: &FitRequest) -> Result<FitRun> {
    let t0 = Instant::now();
    let model = registry(&cfg.model)?;
    let space = param_space(cfg);
    let settings = FitSettings::from_config(cfg);
    let curves = &data.curves;
    let guess = initial_guess(
        model.as_ref(),
        curves,
        &space,
        settings.omega_f,
        &settings.ode,
    );
    let mut starts: Vec<(String, Vec<f64>)> = Vec::new();
    if req.starts != StartChoice::Guess {
        match cfg.starts_all_given() {
            Some(s) => starts.push(("config".to_string(), s)),
            None if req.starts == StartChoice::Config => {
                return Err(Error::config(
                    &cfg.path,
                    "--start config needs a start value for every constant",
                ))
            }
            None => {}
        }
    }
    if req.starts != StartChoice::Config {
        starts.push(("guess".to_string(), guess.params.clone()));
    }
    let ws = match req.w {
        Some(w) if w >= 0.0 && w.is_finite() => vec![vec![w; curves.len()]],
        Some(w) => {
            return Err(Error::Invalid(format!(
                "--w must be a finite weight >= 0, not {w}"
            )))
        }
        None => weight_candidates(cfg, curves.len())?,
    };
    let jobs: Vec<_> = starts
        .iter()
        .flat_map(|s| ws.iter().map(move |w| (s, w)))
        .collect();
    let fits: Vec<LocalFit> = jobs
        .par_iter()
        .map(|((label, start), w)| {
            local_fit(model.as_ref(), curves, &space, w, start, label, &settings)
        })
        .collect();
    let used_min_rate = curves.iter().all(|c| c.min_rate_measured.is_some());
    let best = choose_best(&fits, used_min_rate).ok_or_else(|| {
        Error::Numerical(format!(
            "none of the {} local fits reached an evaluable point (first: {})",
            fits.len(),
            fits.first()
                .map(|f| f
                    .lm
                    .failure
                    .clone()
                    .unwrap_or_else(|| f.lm.termination.as_str().into()))
                .unwrap_or_default()
        ))
    })?;
    Ok(FitRun {
        model,
        space,
        guess,
        fits,
        best,
        used_min_rate,
        settings,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}
