//! Bounded Levenberg–Marquardt for nonlinear least squares, min ½‖r(x)‖² s.t. lb ≤ x ≤ ub.
//!
//! Projected steps with an active set: a variable at a bound whose gradient pushes outward
//! is held for the step; the trial point is projected onto the box; finite-difference steps
//! go inward at a bound, so that no residual is ever evaluated outside the box. The problem
//! is the [`LeastSquaresProblem`] trait (residuals, optional analytic Jacobian), in the
//! spirit of the `levenberg-marquardt` crate.

use nalgebra::{DMatrix, DVector};

/// A residual evaluation that could not be carried out (e.g. a simulation failed).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EvalFailure(pub String);

/// A least-squares problem r: ℝⁿ → ℝᵐ.
pub trait LeastSquaresProblem: Sync {
    /// Number of parameters n.
    fn n_params(&self) -> usize;
    /// Number of residuals m.
    fn n_residuals(&self) -> usize;
    /// Write r(x) into `r` (length m).
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure>;
    /// Write the Jacobian ∂r/∂x (m × n) into `jac`; `None` means "not available, use finite
    /// differences" (the default).
    fn jacobian(
        &self,
        _x: &[f64],
        _r: &[f64],
        _jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        None
    }
}

/// Options of [`minimize`]; tolerances are relative unless said otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Most outer iterations (Jacobian evaluations).
    pub max_iterations: usize,
    /// Converged on step: ‖Δx‖ ≤ xtol·(‖x‖ + xtol).
    pub xtol: f64,
    /// Converged on objective: actual and predicted relative reductions ≤ ftol.
    pub ftol: f64,
    /// Converged on gradient: ‖projected gradient‖∞ ≤ gtol·max(1, f).
    pub gtol: f64,
    /// Finite-difference step, relative to max(|x|, 1) (absolute in a unit box).
    pub fd_step: f64,
    /// Initial damping relative to the largest diagonal element of JᵀJ.
    pub lambda0: f64,
    /// Largest damping (relative to the largest diagonal of JᵀJ) before giving up as stalled.
    pub lambda_max: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 200,
            xtol: 1e-10,
            ftol: 1e-12,
            gtol: 1e-12,
            fd_step: 1e-6,
            lambda0: 1e-3,
            lambda_max: 1e16,
        }
    }
}

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The step became negligible.
    ConvergedStep,
    /// The objective stopped decreasing (relative change below ftol).
    ConvergedObjective,
    /// The projected gradient vanished (first-order optimality in the box).
    ConvergedGradient,
    /// No acceptable step could be found even at the largest damping.
    Stalled,
    /// `max_iterations` reached.
    IterationLimit,
    /// The residuals (or the Jacobian) could not be evaluated at the current point.
    SimulationFailure,
}

impl Termination {
    /// Short name for CSV and JSON.
    pub fn as_str(&self) -> &'static str {
        match self {
            Termination::ConvergedStep => "converged_step",
            Termination::ConvergedObjective => "converged_objective",
            Termination::ConvergedGradient => "converged_gradient",
            Termination::Stalled => "stalled",
            Termination::IterationLimit => "iteration_limit",
            Termination::SimulationFailure => "simulation_failure",
        }
    }
    /// Whether the run ended at a (local) minimum.
    pub fn converged(&self) -> bool {
        matches!(
            self,
            Termination::ConvergedStep
                | Termination::ConvergedObjective
                | Termination::ConvergedGradient
        )
    }
}

/// Result of [`minimize`].
#[derive(Debug, Clone, PartialEq)]
pub struct LmReport {
    /// Final point (inside the box).
    pub x: Vec<f64>,
    /// ‖r(x)‖² at the final point (NaN if never evaluable).
    pub objective: f64,
    /// r(x) at the final point.
    pub residuals: Vec<f64>,
    /// Outer iterations (Jacobians).
    pub iterations: usize,
    /// Residual evaluations, finite differences included.
    pub evaluations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// Message of the evaluation failure, if any.
    pub failure: Option<String>,
}

fn sumsq(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Forward-difference Jacobian with steps that stay in the box (backward at an upper bound).
#[allow(clippy::too_many_arguments)]
pub fn fd_jacobian<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x: &[f64],
    r: &[f64],
    lb: &[f64],
    ub: &[f64],
    fd_step: f64,
    jac: &mut DMatrix<f64>,
    evaluations: &mut usize,
) -> Result<(), EvalFailure> {
    let n = x.len();
    let m = r.len();
    let mut xp = x.to_vec();
    let mut rp = vec![0.0; m];
    for j in 0..n {
        let mut h = fd_step * x[j].abs().max(1.0);
        let room_up = ub[j] - x[j];
        let room_down = x[j] - lb[j];
        if h > room_up {
            if room_down >= h {
                h = -h;
            } else if room_up >= room_down {
                h = 0.5 * room_up;
            } else {
                h = -0.5 * room_down;
            }
        }
        let mut ok = false;
        let mut last_err = None;
        for attempt in 0..2 {
            let hj = if attempt == 0 { h } else { -h };
            let xj = x[j] + hj;
            if hj == 0.0 || xj < lb[j] || xj > ub[j] {
                continue;
            }
            xp[j] = xj;
            *evaluations += 1;
            match problem.residuals(&xp, &mut rp) {
                Ok(()) => {
                    let dx = xj - x[j];
                    for i in 0..m {
                        jac[(i, j)] = (rp[i] - r[i]) / dx;
                    }
                    ok = true;
                    break;
                }
                Err(e) => last_err = Some(e),
            }
        }
        xp[j] = x[j];
        if !ok {
            return Err(last_err.unwrap_or_else(|| {
                EvalFailure(format!(
                    "no room for a finite-difference step in parameter {j}"
                ))
            }));
        }
    }
    Ok(())
}

/// Minimise ½‖r(x)‖² over the box [lb, ub] from `x0` (projected onto the box first).
pub fn minimize<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x0: &[f64],
    lb: &[f64],
    ub: &[f64],
    opts: &LmOptions,
) -> LmReport {
    let n = problem.n_params();
    let m = problem.n_residuals();
    assert_eq!(x0.len(), n, "start has the wrong length");
    assert!(
        lb.len() == n && ub.len() == n,
        "bounds have the wrong length"
    );
    let mut x: Vec<f64> = (0..n).map(|j| x0[j].clamp(lb[j], ub[j])).collect();
    let mut r = vec![0.0; m];
    let mut evaluations = 1;
    let fail = |x: Vec<f64>, it, ev, e: EvalFailure, f: f64, r: Vec<f64>| LmReport {
        x,
        objective: f,
        residuals: r,
        iterations: it,
        evaluations: ev,
        termination: Termination::SimulationFailure,
        failure: Some(e.0),
    };
    if let Err(e) = problem.residuals(&x, &mut r) {
        return fail(x, 0, evaluations, e, f64::NAN, r);
    }
    let mut f = sumsq(&r);
    let mut jac = DMatrix::<f64>::zeros(m, n);
    let mut r_trial = vec![0.0; m];
    let mut x_trial = vec![0.0; n];
    let mut lambda = -1.0_f64;
    let mut nu = 2.0_f64;
    let done = |x, f, r, it, ev, t| LmReport {
        x,
        objective: f,
        residuals: r,
        iterations: it,
        evaluations: ev,
        termination: t,
        failure: None,
    };

    for iter in 1..=opts.max_iterations {
        let jac_result = match problem.jacobian(&x, &r, &mut jac) {
            Some(res) => res,
            None => fd_jacobian(
                problem,
                &x,
                &r,
                lb,
                ub,
                opts.fd_step,
                &mut jac,
                &mut evaluations,
            ),
        };
        if let Err(e) = jac_result {
            return fail(x, iter, evaluations, e, f, r);
        }
        let rv = DVector::from_column_slice(&r);
        let g = jac.tr_mul(&rv); // ∇(½‖r‖²)
        let jtj = jac.tr_mul(&jac);

        // Active set and projected gradient.
        let at_lb = |j: usize| x[j] <= lb[j];
        let at_ub = |j: usize| x[j] >= ub[j];
        let free: Vec<usize> = (0..n)
            .filter(|&j| !((at_lb(j) && g[j] > 0.0) || (at_ub(j) && g[j] < 0.0)))
            .collect();
        let pg = (0..n)
            .map(|j| (x[j] - (x[j] - g[j]).clamp(lb[j], ub[j])).abs())
            .fold(0.0, f64::max);
        if pg <= opts.gtol * f.max(1.0) || free.is_empty() {
            return done(x, f, r, iter, evaluations, Termination::ConvergedGradient);
        }
        let diag_max = (0..n)
            .map(|j| jtj[(j, j)])
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        if lambda < 0.0 {
            lambda = opts.lambda0 * diag_max;
        }
        // Inner loop: increase damping until a step reduces the objective.
        loop {
            // Solve on the free set; a free variable at a bound whose step points outward
            // would be cut to zero by the projection, leaving a step that is not a descent
            // step of the remaining variables: hold it and solve again.
            let mut held = free.clone();
            let step = loop {
                let nf = held.len();
                let mut a = DMatrix::<f64>::zeros(nf, nf);
                let mut b = DVector::<f64>::zeros(nf);
                for (p, &jp) in held.iter().enumerate() {
                    b[p] = -g[jp];
                    for (q, &jq) in held.iter().enumerate() {
                        a[(p, q)] = jtj[(jp, jq)];
                    }
                    let d = jtj[(jp, jp)].max(1e-12 * diag_max);
                    a[(p, p)] += lambda * d;
                }
                let Some(ch) = a.cholesky() else {
                    break None;
                };
                let step = ch.solve(&b);
                let blocked: Vec<usize> = held
                    .iter()
                    .enumerate()
                    .filter(|&(p, &jp)| {
                        (at_lb(jp) && step[p] < 0.0) || (at_ub(jp) && step[p] > 0.0)
                    })
                    .map(|(p, _)| p)
                    .collect();
                if blocked.is_empty() || blocked.len() == held.len() {
                    break Some((held, step));
                }
                held = held
                    .iter()
                    .enumerate()
                    .filter(|(p, _)| !blocked.contains(p))
                    .map(|(_, &jp)| jp)
                    .collect();
            };
            let Some((held, step)) = step else {
                lambda *= nu;
                nu *= 2.0;
                if lambda > opts.lambda_max * diag_max {
                    return done(x, f, r, iter, evaluations, Termination::Stalled);
                }
                continue;
            };
            x_trial.copy_from_slice(&x);
            for (p, &jp) in held.iter().enumerate() {
                x_trial[jp] = (x[jp] + step[p]).clamp(lb[jp], ub[jp]);
            }
            let dx = DVector::from_iterator(n, (0..n).map(|j| x_trial[j] - x[j]));
            let dx_norm = dx.norm();
            let x_norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if dx_norm <= opts.xtol * (x_norm + opts.xtol) {
                return done(x, f, r, iter, evaluations, Termination::ConvergedStep);
            }
            // Predicted objective of the linear model at the projected step.
            let jdx = &jac * &dx;
            let pred_f: f64 = (0..m).map(|i| (r[i] + jdx[i]).powi(2)).sum();
            let predicted = f - pred_f;
            evaluations += 1;
            let trial_ok = problem.residuals(&x_trial, &mut r_trial).is_ok();
            let f_trial = if trial_ok {
                sumsq(&r_trial)
            } else {
                f64::INFINITY
            };
            let actual = f - f_trial;
            let rho = if predicted > 0.0 {
                actual / predicted
            } else {
                -1.0
            };
            if trial_ok && f_trial.is_finite() && actual > 0.0 && rho > 1e-4 {
                let f_old = f;
                std::mem::swap(&mut x, &mut x_trial);
                std::mem::swap(&mut r, &mut r_trial);
                f = f_trial;
                lambda *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if actual <= opts.ftol * f_old && predicted <= opts.ftol * f_old {
                    return done(x, f, r, iter, evaluations, Termination::ConvergedObjective);
                }
                if dx_norm <= opts.xtol * (x_norm + opts.xtol) {
                    return done(x, f, r, iter, evaluations, Termination::ConvergedStep);
                }
                break;
            }
            // Rejected: both reductions negligible means we are at the noise floor.
            if trial_ok && predicted.abs() <= opts.ftol * f && actual.abs() <= opts.ftol * f {
                return done(x, f, r, iter, evaluations, Termination::ConvergedObjective);
            }
            lambda *= nu;
            nu *= 2.0;
            if lambda > opts.lambda_max * diag_max {
                return done(x, f, r, iter, evaluations, Termination::Stalled);
            }
        }
    }
    done(
        x,
        f,
        r,
        opts.max_iterations,
        evaluations,
        Termination::IterationLimit,
    )
}
