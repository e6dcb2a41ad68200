//! Bounded Levenberg–Marquardt for nonlinear least squares, min ½‖r(x)‖² s.t. lb ≤ x ≤ ub.
//!
//! Projected steps with an active set: a variable at a bound whose gradient pushes outward
//! is held for the step; the step is projected onto the box, or cut back to the first bound
//! it meets when that keeps more of the predicted reduction; finite-difference steps go
//! inward at a bound, so that no residual is ever evaluated outside the box.
//!
//! Optional geodesic acceleration (Transtrum & Sethna, arXiv:1201.5885): the step v gets the
//! second-order correction a/2 from the residuals' directional second derivative along v
//! (one extra residual evaluation), which lets the iteration follow curved valleys in long
//! steps instead of crawling along them. A problem that computes residuals and Jacobian in one
//! evaluation (dual numbers) is evaluated that way at every trial point, so an accepted step
//! costs no separate Jacobian. The problem is the [`LeastSquaresProblem`] trait, in the spirit
//! of the `levenberg-marquardt` crate.
//!
//! **Large problems** (a logged curve of a million points) need not store the m × n Jacobian:
//! a problem that [prefers](LeastSquaresProblem::prefers_normal_equations) it hands the
//! iteration its [`NormalEquations`] JᵀJ and Jᵀr, accumulated while the residuals are
//! produced, and everything the iteration does is then done on n × n systems: the linear
//! model's reduction for a step v is −(2·gᵀv + vᵀ·JᵀJ·v) instead of ‖r‖² − ‖r + J·v‖², and
//! the geodesic correction's Jᵀ·r_vv is accumulated by the problem from the probe's
//! residuals and the Jacobian produced once more at x
//! ([`LeastSquaresProblem::geodesic_normal`]). The steps, tests and terminations are the same.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

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
    /// differences". The default takes it from
    /// [`LeastSquaresProblem::residuals_and_jacobian`] (residuals into a scratch vector), so a
    /// problem that gives both together need not give the Jacobian alone; `None` where that
    /// is not available either.
    fn jacobian(
        &self,
        x: &[f64],
        _r: &[f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let mut scratch = vec![0.0; self.n_residuals()];
        self.residuals_and_jacobian(x, &mut scratch, jac)
    }
    /// r(x) and ∂r/∂x together, for problems that get both from one evaluation (dual
    /// numbers) at little more than the price of r alone: the optimiser then evaluates every
    /// trial point this way and an accepted trial needs no separate Jacobian. `None` (the
    /// default) means "not available".
    fn residuals_and_jacobian(
        &self,
        _x: &[f64],
        _r: &mut [f64],
        _jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        None
    }
    /// For problems whose residual weights are estimated from the residuals themselves (a
    /// profiled likelihood: iteratively reweighted least squares inside the iteration): called
    /// at every accepted point `x` with its residuals `r` (and its Jacobian, when already
    /// computed); re-estimate the weights, rewrite `r` (and `jac`) under the new weights and
    /// return `true`, or return `false` (the default) when nothing changed. Re-estimating the
    /// weights at fixed x must not increase the problem's true objective, so that the
    /// iteration stays a descent method on it.
    fn reweight(&self, _x: &[f64], _r: &mut [f64], _jac: Option<&mut DMatrix<f64>>) -> bool {
        false
    }
    /// The part of the problem's true objective that its residuals do not carry under the
    /// current weights (a profiled likelihood: −2 ln L = ‖r‖² + the error model's
    /// log-determinant), for the plateau test ([`LmOptions::plateau`]). Reweighting at the
    /// maximum-likelihood weights holds ‖r‖² near the number of readings, so a test on ‖r‖²
    /// alone would see a plateau where the likelihood still falls. Default 0.
    fn objective_offset(&self) -> f64 {
        0.0
    }
    /// The damping's scale per parameter at the current point, given JᵀJ (`None`, the
    /// default: its diagonal, Marquardt's scaling). A problem whose parameters come in
    /// blocks that trade off against each other (random effects against the constants they
    /// scatter) can give the diagonal of the Schur complement instead, so that a direction
    /// the other block compensates is not damped as if it were stiff.
    fn damping_scale(&self, _jtj: &DMatrix<f64>) -> Option<Vec<f64>> {
        None
    }
    /// Whether [`minimize`] should work on the normal equations
    /// ([`LeastSquaresProblem::residuals_and_normal_equations`]) instead of a stored m × n
    /// Jacobian: for problems whose Jacobian would dominate memory and time. Such a problem
    /// is never [reweighted](LeastSquaresProblem::reweight). Default `false`.
    fn prefers_normal_equations(&self) -> bool {
        false
    }
    /// r(x) and the normal equations JᵀJ, Jᵀr at x, accumulated while the residuals are
    /// produced (no m × n Jacobian is stored). `None` (the default) means "not available".
    fn residuals_and_normal_equations(
        &self,
        _x: &[f64],
        _r: &mut [f64],
        _ne: &mut NormalEquations,
    ) -> Option<Result<(), EvalFailure>> {
        None
    }
    /// For the geodesic acceleration on the normal equations: J(x)ᵀ·r_vv along the step `v`,
    /// with r_vv = 2/h·((r_probe − r)/h − J(x)·v) from the residuals `r` at x and `r_probe`
    /// at x + h·v (the stored path's formula), written into `jt_rvv`; J(x) is produced anew
    /// (one more evaluation at x) and not stored. `None` (the default): no acceleration.
    fn geodesic_normal(
        &self,
        _x: &[f64],
        _v: &[f64],
        _h: f64,
        _r: &[f64],
        _r_probe: &[f64],
        _jt_rvv: &mut [f64],
    ) -> Option<Result<(), EvalFailure>> {
        None
    }
}

/// The normal equations of the linearised problem at a point: JᵀJ (n × n) and Jᵀr.
#[derive(Debug, Clone, PartialEq)]
pub struct NormalEquations {
    /// JᵀJ.
    pub jtj: DMatrix<f64>,
    /// Jᵀr, the gradient of ½‖r‖².
    pub jtr: DVector<f64>,
}

impl NormalEquations {
    /// Zeros for `n` parameters.
    pub fn zeros(n: usize) -> Self {
        NormalEquations {
            jtj: DMatrix::zeros(n, n),
            jtr: DVector::zeros(n),
        }
    }
    /// From a stored Jacobian `jac` (m × n) and residuals `r`: the products the iteration
    /// forms on the stored path.
    pub fn from_jacobian(jac: &DMatrix<f64>, r: &[f64]) -> Self {
        let (jtr, jtj) = normal_products(jac, r);
        NormalEquations { jtj, jtr }
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
    /// Geodesic acceleration (Transtrum & Sethna 2012): the largest accepted 2‖a‖/‖v‖ of
    /// the second-order correction a to the step v; `None` switches acceleration off.
    pub geodesic: Option<f64>,
    /// Step of the finite difference along v that gives the directional second derivative
    /// of the residuals, as a fraction of v.
    pub geodesic_h: f64,
    /// Stop on a plateau: (K, δ) ends the iteration when the objective has stayed within δ
    /// (absolute) over the last K iterations (`None`: never). For a profiled likelihood,
    /// whose weights move at every iteration, the relative tests may never pass along a
    /// flat valley while the likelihood no longer changes on the scale that matters
    /// (0.01 in −2 ln L is below any decision).
    pub plateau: Option<(usize, f64)>,
    /// Stop when the gain still to come is small: (K, δ) compares the objective's falls over
    /// the last two windows of K iterations, d₁ then d₂, and stops when the iteration
    /// converges linearly (q = d₂/d₁ < 0.9) and the geometric tail d₂·q/(1 − q) of the falls
    /// still to come is at most δ (absolute), or when nothing fell over the last window and
    /// at most δ over the one before (`None`: never). For refits that crawl along a flat
    /// valley, whose last iterations change the objective far below any decision.
    pub gain_to_come: Option<(usize, f64)>,
    /// A step shorter than `xtol` only because of the damping (the undamped step is not
    /// short, no step was rejected since the last accepted one) is not convergence: the
    /// damping is cut by [`OVERDAMPED_CUT`] and the step solved again. On for the
    /// hierarchical fits, whose rounds start heavily damped next to a moved optimum; off
    /// elsewhere, where the diagnosis was calibrated without it.
    pub cut_overdamped: bool,
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
            geodesic: None,
            geodesic_h: 0.1,
            plateau: None,
            gain_to_come: None,
            cut_overdamped: false,
        }
    }
}

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// The objective stayed within [`LmOptions::plateau`]'s δ over its last K iterations.
    Plateau,
    /// The falls of the objective shrink geometrically and their tail is below
    /// [`LmOptions::gain_to_come`]'s δ.
    SmallGainToCome,
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
            Termination::Plateau => "plateau",
            Termination::SmallGainToCome => "small_gain_to_come",
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
                | Termination::Plateau
                | Termination::SmallGainToCome
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
    /// Damping of the last step tried, relative to the largest diagonal of JᵀJ (NaN if no
    /// step was tried): where a continued iteration ([`LmOptions::lambda0`]) picks up.
    pub lambda: f64,
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

/// Floor of the damping's scale JᵀJ_jj and ridge of the undamped model, relative to the
/// largest diagonal of JᵀJ: keeps the systems solvable when a column of J vanishes.
const DIAG_FLOOR: f64 = 1e-12;

/// Solve (JᵀJ + diag(d))·s = −g restricted to the variables `held`, with d_p = `diag(j_p)`:
/// the Cholesky factor (reused for the geodesic correction) and the step, or `None` if the
/// system is not positive definite.
fn solve_held(
    jtj: &DMatrix<f64>,
    g: &DVector<f64>,
    held: &[usize],
    diag: impl Fn(usize) -> f64,
) -> Option<(Cholesky<f64, Dyn>, DVector<f64>)> {
    let nf = held.len();
    let mut a = DMatrix::<f64>::zeros(nf, nf);
    let mut b = DVector::<f64>::zeros(nf);
    for (p, &jp) in held.iter().enumerate() {
        b[p] = -g[jp];
        for (q, &jq) in held.iter().enumerate() {
            a[(p, q)] = jtj[(jp, jq)];
        }
        a[(p, p)] += diag(jp);
    }
    let ch = a.cholesky()?;
    let step = ch.solve(&b);
    Some((ch, step))
}

/// The displacement x → clamp(x + scale·step) of the variables `held` (full length).
fn projected(
    x: &[f64],
    step: &DVector<f64>,
    scale: f64,
    held: &[usize],
    lb: &[f64],
    ub: &[f64],
) -> DVector<f64> {
    let mut v = DVector::<f64>::zeros(x.len());
    for (p, &jp) in held.iter().enumerate() {
        v[jp] = (x[jp] + scale * step[p]).clamp(lb[jp], ub[jp]) - x[jp];
    }
    v
}

/// ‖r + J·v‖², the linear model's objective after the displacement v.
fn model_objective(jac: &DMatrix<f64>, r: &[f64], v: &DVector<f64>) -> f64 {
    let jv = jac * v;
    (0..r.len()).map(|i| (r[i] + jv[i]).powi(2)).sum()
}

/// The linear model of the residuals at the current point: a stored Jacobian, or only its
/// normal equations (large problems).
enum Linear<'a> {
    /// J itself (m × n) with the residuals r.
    Stored(&'a DMatrix<f64>, &'a [f64]),
    /// JᵀJ and Jᵀr alone.
    Normal(&'a DMatrix<f64>, &'a DVector<f64>),
}

impl Linear<'_> {
    /// Reduction of ‖r‖² = `f` that the linear model predicts for the displacement v:
    /// f − ‖r + J·v‖² from a stored J, −(2·gᵀv + vᵀ·JᵀJ·v) from the normal equations.
    fn reduction(&self, f: f64, v: &DVector<f64>) -> f64 {
        match self {
            Linear::Stored(jac, r) => f - model_objective(jac, r, v),
            Linear::Normal(jtj, g) => -(2.0 * g.dot(v) + v.dot(&(*jtj * v))),
        }
    }
}

/// The undamped (Gauss–Newton) step on the variables `held` from `x`, projected onto the
/// box (`None` if the model cannot be solved): what the iteration could still gain
/// ([`Linear::reduction`] of it), and whether a short damped step is short because of the
/// damping (its length).
fn gauss_newton_velocity(
    jtj: &DMatrix<f64>,
    g: &DVector<f64>,
    x: &[f64],
    lb: &[f64],
    ub: &[f64],
    held: &[usize],
    diag_max: f64,
) -> Option<DVector<f64>> {
    solve_held(jtj, g, held, |_| DIAG_FLOOR * diag_max)
        .map(|(_, step)| projected(x, &step, 1.0, held, lb, ub))
}

/// The factor the damping is cut by when a step was short only because of it
/// ([`LmOptions::cut_overdamped`]).
pub const OVERDAMPED_CUT: f64 = 1e-3;

/// The gain-to-come test of [`LmOptions::gain_to_come`] on the objective at three iterations
/// K apart (`f0`, `f1`, `f2`): the falls d₁ = f0 − f1 and d₂ = f1 − f2 shrink by q = d₂/d₁ <
/// 0.9 and their geometric tail d₂·q/(1 − q) is at most `delta`, or nothing fell over the
/// last window (d₂ ≤ 0) and at most `delta` over the one before.
pub fn small_gain_to_come(f0: f64, f1: f64, f2: f64, delta: f64) -> bool {
    let (d1, d2) = (f0 - f1, f1 - f2);
    if !(d1.is_finite() && d2.is_finite()) {
        return false;
    }
    if d2 <= 0.0 {
        return d1 <= delta;
    }
    if d1 <= 0.0 || d2 >= 0.9 * d1 {
        return false;
    }
    let q = d2 / d1;
    d2 * q / (1.0 - q) <= delta
}

/// The work of [`minimize`] runs: how many, their iterations and evaluations, and how many of
/// them ran to [`LmOptions::max_iterations`] (with those runs' iterations). Where a command's time goes is
/// the count of its iterations; runs at the limit were stopped before any convergence test
/// passed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LmCounts {
    /// Runs of [`minimize`].
    pub runs: u64,
    /// Their iterations (Jacobians), as [`LmReport::iterations`] counts them.
    pub iterations: u64,
    /// Runs that ended with [`Termination::IterationLimit`].
    pub runs_at_limit: u64,
    /// The iterations of those runs.
    pub iterations_at_limit: u64,
    /// Evaluations of the residuals (with or without their Jacobian), as
    /// [`LmReport::evaluations`] counts them: the cost of an iteration differs between
    /// options (a geodesic acceleration's probe, rejected trials), its evaluations do not.
    pub evaluations: u64,
}

impl LmCounts {
    /// Every run of [`minimize`] in this process so far, on any thread ([`LmCounter`]).
    pub fn now() -> Self {
        PROCESS_COUNTS.snapshot()
    }

    /// The runs between `earlier` and `self` (two snapshots of one counter).
    pub fn since(&self, earlier: &LmCounts) -> LmCounts {
        LmCounts {
            runs: self.runs.saturating_sub(earlier.runs),
            iterations: self.iterations.saturating_sub(earlier.iterations),
            runs_at_limit: self.runs_at_limit.saturating_sub(earlier.runs_at_limit),
            iterations_at_limit: self
                .iterations_at_limit
                .saturating_sub(earlier.iterations_at_limit),
            evaluations: self.evaluations.saturating_sub(earlier.evaluations),
        }
    }
}

/// A counter of [`LmCounts`] that any thread may add to (relaxed atomics: the counts are
/// sums, the order of additions does not matter).
#[derive(Debug, Default)]
pub struct LmCounter([std::sync::atomic::AtomicU64; 5]);

impl LmCounter {
    /// A counter at zero.
    pub const fn new() -> Self {
        use std::sync::atomic::AtomicU64;
        LmCounter([
            AtomicU64::new(0),
            AtomicU64::new(0),
            AtomicU64::new(0),
            AtomicU64::new(0),
            AtomicU64::new(0),
        ])
    }

    /// Count one finished run.
    pub fn record(&self, report: &LmReport) {
        use std::sync::atomic::Ordering::Relaxed;
        let it = report.iterations as u64;
        self.0[0].fetch_add(1, Relaxed);
        self.0[1].fetch_add(it, Relaxed);
        self.0[4].fetch_add(report.evaluations as u64, Relaxed);
        if report.termination == Termination::IterationLimit {
            self.0[2].fetch_add(1, Relaxed);
            self.0[3].fetch_add(it, Relaxed);
        }
    }

    /// The counts so far.
    pub fn snapshot(&self) -> LmCounts {
        use std::sync::atomic::Ordering::Relaxed;
        LmCounts {
            runs: self.0[0].load(Relaxed),
            iterations: self.0[1].load(Relaxed),
            runs_at_limit: self.0[2].load(Relaxed),
            iterations_at_limit: self.0[3].load(Relaxed),
            evaluations: self.0[4].load(Relaxed),
        }
    }
}

/// Every [`minimize`] run of the process. A difference of two snapshots counts the runs in
/// between on every thread: exactly one command's work in the binary (one command per
/// process), the sum with any concurrent work elsewhere (threads of a Python session, tests).
static PROCESS_COUNTS: LmCounter = LmCounter::new();

/// Minimise ½‖r(x)‖² over the box [lb, ub] from `x0` (projected onto the box first).
pub fn minimize<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x0: &[f64],
    lb: &[f64],
    ub: &[f64],
    opts: &LmOptions,
) -> LmReport {
    let report = minimize_uncounted(problem, x0, lb, ub, opts);
    PROCESS_COUNTS.record(&report);
    report
}

/// [`minimize`] without counting the run.
fn minimize_uncounted<P: LeastSquaresProblem + ?Sized>(
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
    // Relative damping of the last step tried, for the report.
    let last_lambda = std::cell::Cell::new(f64::NAN);
    let fail = |x: Vec<f64>, it, ev, e: EvalFailure, f: f64, r: Vec<f64>| LmReport {
        x,
        objective: f,
        residuals: r,
        iterations: it,
        evaluations: ev,
        termination: Termination::SimulationFailure,
        failure: Some(e.0),
        lambda: last_lambda.get(),
    };
    // Normal-equations mode: JᵀJ and Jᵀr of every evaluation, no m × n Jacobian.
    let mut ne = NormalEquations::zeros(n);
    let mut ne_trial = NormalEquations::zeros(n);
    let normal = problem.prefers_normal_equations()
        && match problem.residuals_and_normal_equations(&x, &mut r, &mut ne) {
            Some(Ok(())) => true,
            Some(Err(e)) => return fail(x, 0, evaluations, e, f64::NAN, r),
            None => false,
        };
    let stored_rows = if normal { 0 } else { m };
    let mut jac = DMatrix::<f64>::zeros(stored_rows, n);
    let mut jac_trial = DMatrix::<f64>::zeros(stored_rows, n);
    // Whether `jac` holds the Jacobian at `x` already (from a fused evaluation).
    let mut jac_fresh = normal
        || match problem.residuals_and_jacobian(&x, &mut r, &mut jac) {
            Some(Ok(())) => true,
            Some(Err(e)) => return fail(x, 0, evaluations, e, f64::NAN, r),
            None => {
                if let Err(e) = problem.residuals(&x, &mut r) {
                    return fail(x, 0, evaluations, e, f64::NAN, r);
                }
                false
            }
        };
    let mut f = sumsq(&r);
    let mut r_trial = vec![0.0; m];
    let mut x_trial = vec![0.0; n];
    let mut x_probe = vec![0.0; n];
    let mut r_probe = vec![0.0; if opts.geodesic.is_some() { m } else { 0 }];
    let mut jt_rvv = vec![0.0; n];
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
        lambda: last_lambda.get(),
    };

    // The true objective at the start of each iteration (plateau and gain-to-come tests).
    let mut history: Vec<f64> = Vec::new();
    for iter in 1..=opts.max_iterations {
        if !normal && problem.reweight(&x, &mut r, jac_fresh.then_some(&mut jac)) {
            f = sumsq(&r);
        }
        if opts.plateau.is_some() || opts.gain_to_come.is_some() {
            history.push(f + problem.objective_offset());
        }
        if let Some((k, delta)) = opts.gain_to_come {
            let i = history.len() - 1;
            if k > 0
                && i >= 2 * k
                && small_gain_to_come(history[i - 2 * k], history[i - k], history[i], delta)
            {
                return done(x, f, r, iter, evaluations, Termination::SmallGainToCome);
            }
        }
        if let Some((k, delta)) = opts.plateau {
            if history.len() > k {
                let w = &history[history.len() - k - 1..];
                let (lo, hi) = w
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                        (a.min(*v), b.max(*v))
                    });
                if hi - lo <= delta {
                    return done(x, f, r, iter, evaluations, Termination::Plateau);
                }
            }
        }
        let jac_result = if jac_fresh {
            Ok(())
        } else {
            match problem.jacobian(&x, &r, &mut jac) {
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
            }
        };
        if let Err(e) = jac_result {
            return fail(x, iter, evaluations, e, f, r);
        }
        // ∇(½‖r‖²) and JᵀJ.
        // The stored Jacobian's non-zero blocks, for its products with vectors below.
        let blocks = if normal { None } else { Blocks::of(&jac) };
        let (g, jtj) = if normal {
            (ne.jtr.clone(), ne.jtj.clone())
        } else {
            (
                tr_vec_with(blocks.as_ref(), &jac, &r),
                gram_with(blocks.as_ref(), &jac),
            )
        };
        let lin = if normal {
            Linear::Normal(&jtj, &g)
        } else {
            Linear::Stored(&jac, &r)
        };

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
        let scale = problem.damping_scale(&jtj);

        // Inner loop: increase damping until a step reduces the objective.
        loop {
            last_lambda.set(lambda / diag_max);
            // Solve on the free set; a free variable at a bound whose step points outward
            // would be cut to zero by the projection, leaving a step that is not a descent
            // step of the remaining variables: hold it and solve again.
            let mut held = free.clone();
            let step = loop {
                let Some((ch, step)) = solve_held(&jtj, &g, &held, |j| {
                    let d = scale.as_ref().map_or(jtj[(j, j)], |s| s[j]);
                    lambda * d.max(DIAG_FLOOR * diag_max)
                }) else {
                    break None;
                };
                let blocked: Vec<usize> = held
                    .iter()
                    .enumerate()
                    .filter(|&(p, &jp)| {
                        (at_lb(jp) && step[p] < 0.0) || (at_ub(jp) && step[p] > 0.0)
                    })
                    .map(|(p, _)| p)
                    .collect();
                if blocked.is_empty() || blocked.len() == held.len() {
                    break Some((held, step, ch));
                }
                held = held
                    .iter()
                    .enumerate()
                    .filter(|(p, _)| !blocked.contains(p))
                    .map(|(_, &jp)| jp)
                    .collect();
            };
            let Some((held, step, ch)) = step else {
                lambda *= nu;
                nu *= 2.0;
                if lambda > opts.lambda_max * diag_max {
                    return done(x, f, r, iter, evaluations, Termination::Stalled);
                }
                continue;
            };
            // Velocity v: the step projected onto the box, or the step cut back to the first
            // bound it crosses (which keeps its direction), whichever the linear model
            // predicts to reduce the objective more. A clamped step can leave a narrow
            // valley; a cut step cannot, as the model decreases along the whole step.
            let mut v = projected(&x, &step, 1.0, &held, lb, ub);
            let mut cut = 1.0_f64;
            for (p, &jp) in held.iter().enumerate() {
                if step[p] > 0.0 {
                    cut = cut.min((ub[jp] - x[jp]) / step[p]);
                } else if step[p] < 0.0 {
                    cut = cut.min((lb[jp] - x[jp]) / step[p]);
                }
            }
            let v_norm = v.norm();
            let x_norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            let step_tol = opts.xtol * (x_norm + opts.xtol);
            if v_norm <= step_tol {
                // A step this short only because of the damping is not convergence: where
                // the undamped step is not short and no step was rejected since the last
                // accepted one, the damping is cut and the step solved again.
                if opts.cut_overdamped
                    && nu == 2.0
                    && lambda > DIAG_FLOOR * diag_max
                    && gauss_newton_velocity(&jtj, &g, &x, lb, ub, &held, diag_max)
                        .map_or(f64::INFINITY, |v| v.norm())
                        > step_tol
                {
                    lambda = (lambda * OVERDAMPED_CUT).max(DIAG_FLOOR * diag_max);
                    continue;
                }
                return done(x, f, r, iter, evaluations, Termination::ConvergedStep);
            }
            let mut predicted = lin.reduction(f, &v);
            if cut < 1.0 {
                let vc = projected(&x, &step, cut, &held, lb, ub);
                let pc = lin.reduction(f, &vc);
                if pc > predicted {
                    predicted = pc;
                    v = vc;
                }
            }
            if !(predicted > 0.0) {
                // Not a descent step of the model: damp more without evaluating.
                lambda *= nu;
                nu *= 2.0;
                if lambda > opts.lambda_max * diag_max {
                    return done(x, f, r, iter, evaluations, Termination::Stalled);
                }
                continue;
            }
            for j in 0..n {
                x_trial[j] = x[j] + v[j];
            }
            if let Some(alpha) = opts.geodesic {
                // Geodesic acceleration: second-order correction a along v, from
                // r_vv ≈ (2/h)·((r(x + h·v) − r)/h − J·v) and (JᵀJ + λD)·a = −Jᵀ·r_vv;
                // the step v + a/2 is taken if 2‖a‖ ≤ alpha·‖v‖.
                let hh = opts.geodesic_h;
                for j in 0..n {
                    x_probe[j] = x[j] + hh * v[j];
                }
                evaluations += 1;
                let probed = if normal {
                    problem.residuals(&x_probe, &mut r_probe).is_ok() && {
                        let geo = problem.geodesic_normal(
                            &x,
                            v.as_slice(),
                            hh,
                            &r,
                            &r_probe,
                            &mut jt_rvv,
                        );
                        if geo.is_some() {
                            evaluations += 1;
                        }
                        matches!(geo, Some(Ok(())))
                    }
                } else {
                    let ok = problem.residuals(&x_probe, &mut r_probe).is_ok();
                    if ok {
                        let jv = &jac * &v;
                        let rvv = DVector::from_iterator(
                            m,
                            (0..m).map(|i| 2.0 / hh * ((r_probe[i] - r[i]) / hh - jv[i])),
                        );
                        let jt = tr_vec_with(blocks.as_ref(), &jac, rvv.as_slice());
                        jt_rvv.copy_from_slice(jt.as_slice());
                    }
                    ok
                };
                let accel = if probed {
                    let b = DVector::from_iterator(held.len(), held.iter().map(|&jp| -jt_rvv[jp]));
                    let a = ch.solve(&b);
                    (2.0 * a.norm() <= alpha * v.norm()).then_some(a)
                } else {
                    None
                };
                // A large correction means v leaves the region where the second-order
                // expansion holds, or that r_vv is noise (integration error over h²·‖v‖²
                // when v is small): then the plain step v is tried.
                if let Some(a) = accel {
                    for (p, &jp) in held.iter().enumerate() {
                        x_trial[jp] = (x[jp] + v[jp] + 0.5 * a[p]).clamp(lb[jp], ub[jp]);
                    }
                }
            }
            let dx_norm = (0..n)
                .map(|j| (x_trial[j] - x[j]).powi(2))
                .sum::<f64>()
                .sqrt();
            evaluations += 1;
            let (trial_ok, trial_jac) = if normal {
                let res =
                    problem.residuals_and_normal_equations(&x_trial, &mut r_trial, &mut ne_trial);
                (matches!(res, Some(Ok(()))), true)
            } else {
                match problem.residuals_and_jacobian(&x_trial, &mut r_trial, &mut jac_trial) {
                    Some(res) => (res.is_ok(), true),
                    None => (problem.residuals(&x_trial, &mut r_trial).is_ok(), false),
                }
            };
            let f_trial = if trial_ok {
                sumsq(&r_trial)
            } else {
                f64::INFINITY
            };
            // Gain ratio against the linear model's prediction for v (predicted > 0 here):
            // the geodesic correction bends the step, it is not part of the model.
            let actual = f - f_trial;
            let rho = actual / predicted;
            // The objective has converged when the step's actual and predicted reductions
            // and what the undamped model could still gain are all below ftol·f; the last
            // keeps a heavily damped step far from a minimum (tiny predicted reduction of a
            // huge f) from passing for convergence.
            let negligible = |reduction: f64| reduction.abs() <= opts.ftol * f;
            let objective_converged = trial_ok
                && negligible(actual)
                && negligible(predicted)
                && negligible(
                    gauss_newton_velocity(&jtj, &g, &x, lb, ub, &held, diag_max)
                        .map_or(f64::INFINITY, |v| lin.reduction(f, &v)),
                );
            if trial_ok && f_trial.is_finite() && actual > 0.0 && rho > 1e-4 {
                std::mem::swap(&mut x, &mut x_trial);
                std::mem::swap(&mut r, &mut r_trial);
                if normal {
                    std::mem::swap(&mut ne, &mut ne_trial);
                } else if trial_jac {
                    std::mem::swap(&mut jac, &mut jac_trial);
                }
                jac_fresh = trial_jac;
                f = f_trial;
                lambda *= (1.0_f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if objective_converged {
                    return done(x, f, r, iter, evaluations, Termination::ConvergedObjective);
                }
                if dx_norm <= opts.xtol * (x_norm + opts.xtol) {
                    // As above: a short step of an overdamped iteration goes on, less damped.
                    if opts.cut_overdamped
                        && lambda > DIAG_FLOOR * diag_max
                        // (`x_trial` holds the point the step left, where jtj and g are.)
                        && gauss_newton_velocity(&jtj, &g, &x_trial, lb, ub, &held, diag_max)
                            .map_or(f64::INFINITY, |v| v.norm())
                            > opts.xtol * (x_norm + opts.xtol)
                    {
                        lambda = (lambda * OVERDAMPED_CUT).max(DIAG_FLOOR * diag_max);
                        break;
                    }
                    return done(x, f, r, iter, evaluations, Termination::ConvergedStep);
                }
                break;
            }
            // Rejected with negligible reductions: we are at the noise floor.
            if objective_converged {
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

/// Rows per block of [`gram`]'s zero-skipping (nalgebra's dot product unrolls by 8).
const GRAM_BLOCK: usize = 8;

/// JᵀJ of an m × n matrix, bit for bit nalgebra's `jac.tr_mul(jac)`, at a fraction of its
/// cost for the Jacobians of problems with specimen effects: each entry is the same 8-way
/// unrolled dot product, computed once for the upper triangle and mirrored (the products
/// commute exactly), and 8-row blocks where either column is exactly zero are skipped (they
/// add exact zeros; an effect column is zero outside its curve's rows). A matrix with a
/// non-finite entry goes to nalgebra unchanged (0·∞ must stay NaN).
pub fn gram(jac: &DMatrix<f64>) -> DMatrix<f64> {
    gram_with(Blocks::of(jac).as_ref(), jac)
}

/// Jᵀr and JᵀJ, bit for bit nalgebra's `jac.tr_mul(&r)` and `jac.tr_mul(jac)` (see [`gram`]).
pub fn normal_products(jac: &DMatrix<f64>, r: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let blocks = Blocks::of(jac);
    (
        tr_vec_with(blocks.as_ref(), jac, r),
        gram_with(blocks.as_ref(), jac),
    )
}

/// [`gram`] with the non-zero blocks of `jac` known (`None`: not finite, nalgebra's product).
fn gram_with(blocks: Option<&Blocks>, jac: &DMatrix<f64>) -> DMatrix<f64> {
    match blocks {
        Some(bl) => bl.gram(jac),
        None => jac.tr_mul(jac),
    }
}

/// Jᵀv, bit for bit nalgebra's, with the non-zero blocks of `jac` known (see [`gram_with`]).
fn tr_vec_with(blocks: Option<&Blocks>, jac: &DMatrix<f64>, v: &[f64]) -> DVector<f64> {
    match blocks {
        Some(bl) => bl.tr_vec(jac, v),
        None => jac.tr_mul(&DVector::from_column_slice(v)),
    }
}

/// Which 8-row blocks of each column of a finite matrix hold a non-zero entry, as runs
/// [first, end) of consecutive blocks.
struct Blocks {
    runs: Vec<Vec<(usize, usize)>>,
}

impl Blocks {
    /// None if the matrix has a non-finite entry.
    fn of(jac: &DMatrix<f64>) -> Option<Blocks> {
        let (m, n) = jac.shape();
        let data = jac.as_slice();
        if !data.iter().all(|v| v.is_finite()) {
            return None;
        }
        let runs = (0..n)
            .map(|k| {
                let col = &data[k * m..(k + 1) * m];
                let mut runs: Vec<(usize, usize)> = Vec::new();
                for (b, chunk) in col.chunks_exact(GRAM_BLOCK).enumerate() {
                    if chunk.iter().any(|&v| v != 0.0) {
                        match runs.last_mut() {
                            Some(last) if last.1 == b => last.1 = b + 1,
                            _ => runs.push((b, b + 1)),
                        }
                    }
                }
                runs
            })
            .collect();
        Some(Blocks { runs })
    }

    /// nalgebra's dot product of `a` and `b` over the block runs `runs` (the other blocks add
    /// exact zeros) and the tail rows past the last whole block.
    #[inline]
    fn dot(a: &[f64], b: &[f64], runs: impl Iterator<Item = (usize, usize)>) -> f64 {
        let mut acc = [0.0f64; GRAM_BLOCK];
        for (lo, hi) in runs {
            let (ra, rb) = (
                &a[lo * GRAM_BLOCK..hi * GRAM_BLOCK],
                &b[lo * GRAM_BLOCK..hi * GRAM_BLOCK],
            );
            for (ca, cb) in ra.chunks_exact(GRAM_BLOCK).zip(rb.chunks_exact(GRAM_BLOCK)) {
                for k in 0..GRAM_BLOCK {
                    acc[k] += ca[k] * cb[k];
                }
            }
        }
        let mut res = 0.0;
        res += acc[0] + acc[4];
        res += acc[1] + acc[5];
        res += acc[2] + acc[6];
        res += acc[3] + acc[7];
        for k in (a.len() / GRAM_BLOCK) * GRAM_BLOCK..a.len() {
            res += a[k] * b[k];
        }
        res
    }

    fn gram(&self, jac: &DMatrix<f64>) -> DMatrix<f64> {
        let (m, n) = jac.shape();
        let data = jac.as_slice();
        let mut out = DMatrix::zeros(n, n);
        for i in 0..n {
            let a = &data[i * m..(i + 1) * m];
            for j in i..n {
                let b = &data[j * m..(j + 1) * m];
                let res = Self::dot(a, b, Both::new(&self.runs[i], &self.runs[j]));
                out[(i, j)] = res;
                out[(j, i)] = res;
            }
        }
        out
    }

    fn tr_vec(&self, jac: &DMatrix<f64>, r: &[f64]) -> DVector<f64> {
        let (m, n) = jac.shape();
        let data = jac.as_slice();
        DVector::from_fn(n, |i, _| {
            Self::dot(&data[i * m..(i + 1) * m], r, self.runs[i].iter().copied())
        })
    }
}

/// The overlaps of two increasing lists of disjoint runs [first, end), in increasing order.
struct Both<'a> {
    a: &'a [(usize, usize)],
    b: &'a [(usize, usize)],
}

impl<'a> Both<'a> {
    fn new(a: &'a [(usize, usize)], b: &'a [(usize, usize)]) -> Self {
        Both { a, b }
    }
}

impl Iterator for Both<'_> {
    type Item = (usize, usize);
    #[inline]
    fn next(&mut self) -> Option<(usize, usize)> {
        while let (Some(&x), Some(&y)) = (self.a.first(), self.b.first()) {
            let (lo, hi) = (x.0.max(y.0), x.1.min(y.1));
            // The run that ends first has no further overlap.
            if x.1 <= y.1 {
                self.a = &self.a[1..];
            } else {
                self.b = &self.b[1..];
            }
            if lo < hi {
                return Some((lo, hi));
            }
        }
        None
    }
}

#[cfg(test)]
mod gram_tests {
    use super::{gram, normal_products};
    use nalgebra::DMatrix;
    use rand::{Rng, SeedableRng};

    /// A Jacobian shaped like one with specimen effects: dense columns, and columns non-zero
    /// only on one curve's rows (block boundaries not multiples of 8), plus a penalty row.
    fn effects_like(m: usize, dense: usize, curves: usize, seed: u64) -> DMatrix<f64> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let n = dense + curves;
        let mut j = DMatrix::zeros(m, n);
        for k in 0..dense {
            for r in 0..m {
                j[(r, k)] = rng.gen_range(-1e3..1e3) * 10f64.powi(rng.gen_range(-6..6));
            }
        }
        let per = (m - curves) / curves.max(1);
        for c in 0..curves {
            for r in c * per + 3..((c + 1) * per + 1).min(m) {
                j[(r, dense + c)] = rng.gen_range(-5.0..5.0);
            }
            j[(m - curves + c, dense + c)] = 0.7;
        }
        j
    }

    #[test]
    fn gram_is_nalgebras_tr_mul_bit_for_bit() {
        for (m, dense, curves, seed) in [
            (1, 1, 0, 1),
            (7, 2, 1, 2),
            (64, 3, 2, 3),
            (1003, 6, 13, 4),
            (5000, 8, 26, 5),
        ] {
            let j = effects_like(m.max(curves + 1), dense, curves, seed);
            let want = j.tr_mul(&j);
            let got = gram(&j);
            assert_eq!(got.shape(), want.shape());
            let r: Vec<f64> = (0..j.nrows()).map(|i| (i as f64 * 0.37).sin()).collect();
            let (jtr, jtj) = normal_products(&j, &r);
            let want_r = j.tr_mul(&nalgebra::DVector::from_column_slice(&r));
            assert_eq!(jtj, got);
            for (g, w) in jtr.iter().zip(want_r.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "Jᵀr, m {m}: {g} vs {w}");
            }
            for (g, w) in got.iter().zip(want.iter()) {
                assert_eq!(g.to_bits(), w.to_bits(), "m {m}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn gram_is_tr_mul_for_random_zero_patterns() {
        // Columns with random runs of zero rows (any length, any offset): every kind of
        // overlap between two columns' non-zero block runs.
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for trial in 0..50 {
            let (m, n) = (rng.gen_range(1..300), rng.gen_range(1..9));
            let mut j = DMatrix::from_fn(m, n, |_, _| rng.gen_range(-2.0..2.0));
            for k in 0..n {
                for _ in 0..rng.gen_range(0..6) {
                    let a = rng.gen_range(0..m);
                    let b = (a + rng.gen_range(0..80)).min(m);
                    for r in a..b {
                        j[(r, k)] = if rng.gen_bool(0.5) { 0.0 } else { -0.0 };
                    }
                }
            }
            let r: Vec<f64> = (0..m).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let (jtr, jtj) = normal_products(&j, &r);
            let want = j.tr_mul(&j);
            let want_r = j.tr_mul(&nalgebra::DVector::from_column_slice(&r));
            for (g, w) in jtj
                .iter()
                .zip(want.iter())
                .chain(jtr.iter().zip(want_r.iter()))
            {
                assert_eq!(g.to_bits(), w.to_bits(), "trial {trial}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn gram_keeps_non_finite_entries_poisoning() {
        let mut j = effects_like(40, 2, 2, 9);
        // An infinity where the other effect column is zero: 0·∞ = NaN in JᵀJ.
        j[(0, 0)] = f64::INFINITY;
        let got = gram(&j);
        let want = j.tr_mul(&j);
        for (g, w) in got.iter().zip(want.iter()) {
            assert!(g.to_bits() == w.to_bits() || (g.is_nan() && w.is_nan()));
        }
        assert!(got[(0, 3)].is_nan(), "0·∞ must stay NaN");
    }
}
