//! The bounded Levenberg–Marquardt on classic least-squares problems with known minima
//! (Moré, Garbow & Hillstrom 1981), bounded and unbounded, and a check that no residual is
//! ever evaluated outside the box.

use creepfit::lsq::{
    minimize, small_gain_to_come, EvalFailure, LeastSquaresProblem, LmCounter, LmCounts, LmOptions,
    Termination,
};
use std::sync::Mutex;

struct Fun<F: Fn(&[f64], &mut [f64]) + Sync> {
    n: usize,
    m: usize,
    f: F,
}

impl<F: Fn(&[f64], &mut [f64]) + Sync> LeastSquaresProblem for Fun<F> {
    fn n_params(&self) -> usize {
        self.n
    }
    fn n_residuals(&self) -> usize {
        self.m
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        (self.f)(x, r);
        Ok(())
    }
}

const INF: f64 = f64::INFINITY;

fn free(n: usize) -> (Vec<f64>, Vec<f64>) {
    (vec![-INF; n], vec![INF; n])
}

fn rosenbrock() -> Fun<impl Fn(&[f64], &mut [f64]) + Sync> {
    Fun {
        n: 2,
        m: 2,
        f: |x: &[f64], r: &mut [f64]| {
            r[0] = 10.0 * (x[1] - x[0] * x[0]);
            r[1] = 1.0 - x[0];
        },
    }
}

#[test]
fn rosenbrock_unbounded() {
    let (lb, ub) = free(2);
    let rep = minimize(&rosenbrock(), &[-1.2, 1.0], &lb, &ub, &LmOptions::default());
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert!(
        (rep.x[0] - 1.0).abs() < 1e-8 && (rep.x[1] - 1.0).abs() < 1e-8,
        "{:?}",
        rep.x
    );
    assert!(rep.objective < 1e-20);
}

#[test]
fn rosenbrock_with_active_upper_bound() {
    // x1 ≤ 0.5: the constrained minimum is (0.5, 0.25) with f = 0.25.
    let rep = minimize(
        &rosenbrock(),
        &[-1.2, 1.0],
        &[-2.0, -1.0],
        &[0.5, 2.0],
        &LmOptions::default(),
    );
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert_eq!(rep.x[0], 0.5);
    assert!((rep.x[1] - 0.25).abs() < 1e-9, "{:?}", rep.x);
    assert!((rep.objective - 0.25).abs() < 1e-12);
}

#[test]
fn beale() {
    let y = [1.5, 2.25, 2.625];
    let p = Fun {
        n: 2,
        m: 3,
        f: move |x: &[f64], r: &mut [f64]| {
            for i in 0..3 {
                r[i] = y[i] - x[0] * (1.0 - x[1].powi(i as i32 + 1));
            }
        },
    };
    let (lb, ub) = free(2);
    let rep = minimize(&p, &[1.0, 1.0], &lb, &ub, &LmOptions::default());
    assert!(
        (rep.x[0] - 3.0).abs() < 1e-8 && (rep.x[1] - 0.5).abs() < 1e-8,
        "{:?}",
        rep.x
    );
}

#[test]
fn powell_singular() {
    // Singular Jacobian at the solution: convergence is only linear, but it must get there.
    let p = Fun {
        n: 4,
        m: 4,
        f: |x: &[f64], r: &mut [f64]| {
            r[0] = x[0] + 10.0 * x[1];
            r[1] = 5f64.sqrt() * (x[2] - x[3]);
            r[2] = (x[1] - 2.0 * x[2]).powi(2);
            r[3] = 10f64.sqrt() * (x[0] - x[3]).powi(2);
        },
    };
    let (lb, ub) = free(4);
    let opts = LmOptions {
        max_iterations: 1000,
        ..LmOptions::default()
    };
    let rep = minimize(&p, &[3.0, -1.0, 0.0, 1.0], &lb, &ub, &opts);
    assert!(
        rep.objective < 1e-16,
        "{} {:?}",
        rep.objective,
        rep.termination
    );
    assert!(rep.x.iter().all(|v| v.abs() < 1e-3), "{:?}", rep.x);
}

#[test]
fn freudenstein_roth_reaches_one_of_its_known_minima() {
    let p = Fun {
        n: 2,
        m: 2,
        f: |x: &[f64], r: &mut [f64]| {
            r[0] = -13.0 + x[0] + ((5.0 - x[1]) * x[1] - 2.0) * x[1];
            r[1] = -29.0 + x[0] + ((x[1] + 1.0) * x[1] - 14.0) * x[1];
        },
    };
    let (lb, ub) = free(2);
    let rep = minimize(&p, &[0.5, -2.0], &lb, &ub, &LmOptions::default());
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    let global = rep.objective < 1e-16 && (rep.x[0] - 5.0).abs() < 1e-6;
    let local = (rep.objective - 48.98425367924).abs() < 1e-6 && (rep.x[0] - 11.41).abs() < 0.01;
    assert!(global || local, "{} at {:?}", rep.objective, rep.x);
    // From a start in the global basin it must find the zero residual.
    let rep = minimize(&p, &[6.0, 3.0], &lb, &ub, &LmOptions::default());
    assert!(
        rep.objective < 1e-16 && (rep.x[1] - 4.0).abs() < 1e-8,
        "{:?}",
        rep.x
    );
}

fn box3d() -> Fun<impl Fn(&[f64], &mut [f64]) + Sync> {
    Fun {
        n: 3,
        m: 10,
        f: |x: &[f64], r: &mut [f64]| {
            for (i, ri) in r.iter_mut().enumerate() {
                let t = 0.1 * (i + 1) as f64;
                *ri =
                    (-t * x[0]).exp() - (-t * x[1]).exp() - x[2] * ((-t).exp() - (-10.0 * t).exp());
            }
        },
    }
}

#[test]
fn box_3d() {
    let (lb, ub) = free(3);
    let rep = minimize(
        &box3d(),
        &[0.0, 10.0, 20.0],
        &lb,
        &ub,
        &LmOptions::default(),
    );
    assert!(rep.objective < 1e-20, "{}", rep.objective);
    assert!(
        (rep.x[0] - 1.0).abs() < 1e-6
            && (rep.x[1] - 10.0).abs() < 1e-5
            && (rep.x[2] - 1.0).abs() < 1e-6,
        "{:?}",
        rep.x
    );
}

#[test]
fn bard() {
    let y = [
        0.14, 0.18, 0.22, 0.25, 0.29, 0.32, 0.35, 0.39, 0.37, 0.58, 0.73, 0.96, 1.34, 2.10, 4.39,
    ];
    let p = Fun {
        n: 3,
        m: 15,
        f: move |x: &[f64], r: &mut [f64]| {
            for i in 0..15 {
                let u = (i + 1) as f64;
                let v = 16.0 - u;
                let w = u.min(v);
                r[i] = y[i] - (x[0] + u / (v * x[1] + w * x[2]));
            }
        },
    };
    let (lb, ub) = free(3);
    let rep = minimize(&p, &[1.0, 1.0, 1.0], &lb, &ub, &LmOptions::default());
    assert!(
        (rep.objective - 8.21487730657e-3).abs() < 1e-12,
        "{}",
        rep.objective
    );
}

/// Wraps a problem and records every point at which residuals were requested.
struct Recorder<P> {
    inner: P,
    seen: Mutex<Vec<Vec<f64>>>,
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Recorder<P> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        self.seen.lock().unwrap().push(x.to_vec());
        self.inner.residuals(x, r)
    }
}

#[test]
fn no_iterate_or_finite_difference_step_leaves_the_box() {
    for opts in [LmOptions::default(), geo()] {
        box_run(&opts);
    }
}

fn box_run(opts: &LmOptions) {
    // Box 3-D in a box that excludes its minimum (1, 10, 1): several bounds become active,
    // one of them at the start point, where finite differences must step inward; with and
    // without geodesic acceleration (whose probe point must stay inside too).
    let lb = [0.0, 5.0, 1.5];
    let ub = [2.0, 9.5, 3.0];
    let rec = Recorder {
        inner: box3d(),
        seen: Mutex::new(Vec::new()),
    };
    let rep = minimize(&rec, &[2.0, 5.0, 3.0], &lb, &ub, opts);
    let seen = rec.seen.into_inner().unwrap();
    assert!(seen.len() > 10);
    for x in &seen {
        for j in 0..3 {
            assert!(
                x[j] >= lb[j] && x[j] <= ub[j],
                "evaluated outside the box: {x:?}"
            );
        }
    }
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    // KKT conditions at the result, with a central-difference gradient of ½‖r‖².
    let f = |x: &[f64]| {
        let mut r = vec![0.0; 10];
        box3d().residuals(x, &mut r).unwrap();
        0.5 * r.iter().map(|v| v * v).sum::<f64>()
    };
    let mut active = 0;
    for j in 0..3 {
        let h = 1e-7;
        let mut xp = rep.x.clone();
        let mut xm = rep.x.clone();
        xp[j] += h;
        xm[j] -= h;
        let g = (f(&xp) - f(&xm)) / (2.0 * h);
        if rep.x[j] <= lb[j] {
            assert!(g >= -1e-6, "at lb with g = {g}");
            active += 1;
        } else if rep.x[j] >= ub[j] {
            assert!(g <= 1e-6, "at ub with g = {g}");
            active += 1;
        } else {
            // Forward differences (step 1e-6) limit the gradient's accuracy to about 1e-7.
            assert!(
                g.abs() < 1e-6,
                "free variable {j} with gradient {g}: {rep:?}"
            );
        }
    }
    assert!(active >= 1, "the box should bind: {:?}", rep.x);
}

/// A problem that cannot be evaluated in part of its domain (like a simulation that fails).
#[test]
fn evaluation_failure_is_reported_at_the_start_and_avoided_later() {
    let p = Fun {
        n: 1,
        m: 1,
        f: |x: &[f64], r: &mut [f64]| r[0] = x[0] - 2.0,
    };
    struct Failing<P>(P);
    impl<P: LeastSquaresProblem> LeastSquaresProblem for Failing<P> {
        fn n_params(&self) -> usize {
            1
        }
        fn n_residuals(&self) -> usize {
            1
        }
        fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
            if x[0] > 3.0 {
                return Err(EvalFailure("simulation failed".into()));
            }
            self.0.residuals(x, r)
        }
    }
    let fp = Failing(p);
    let rep = minimize(&fp, &[5.0], &[-10.0], &[10.0], &LmOptions::default());
    assert_eq!(rep.termination, Termination::SimulationFailure);
    assert!(rep.failure.as_deref() == Some("simulation failed"));
    let rep = minimize(&fp, &[-8.0], &[-10.0], &[10.0], &LmOptions::default());
    assert!(rep.termination.converged());
    assert!((rep.x[0] - 2.0).abs() < 1e-9);
}

/// Counts the calls of the Jacobian entry points, and offers the fused evaluation.
struct Counted<P> {
    inner: P,
    fused: bool,
    jac_calls: std::sync::atomic::AtomicUsize,
    fused_calls: std::sync::atomic::AtomicUsize,
}

fn rosen_jac(x: &[f64], jac: &mut nalgebra::DMatrix<f64>) {
    jac[(0, 0)] = -20.0 * x[0];
    jac[(0, 1)] = 10.0;
    jac[(1, 0)] = -1.0;
    jac[(1, 1)] = 0.0;
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Counted<P> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        self.inner.residuals(x, r)
    }
    fn jacobian(
        &self,
        x: &[f64],
        _r: &[f64],
        jac: &mut nalgebra::DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        self.jac_calls
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        rosen_jac(x, jac);
        Some(Ok(()))
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        jac: &mut nalgebra::DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        if !self.fused {
            return None;
        }
        self.fused_calls
            .fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        rosen_jac(x, jac);
        Some(self.inner.residuals(x, r))
    }
}

fn geo() -> LmOptions {
    LmOptions {
        geodesic: Some(0.75),
        ..LmOptions::default()
    }
}

/// Rosenbrock's valley narrowed by `k` (k = 10 is the classic function).
fn narrow_rosenbrock(k: f64) -> Fun<impl Fn(&[f64], &mut [f64]) + Sync> {
    Fun {
        n: 2,
        m: 2,
        f: move |x: &[f64], r: &mut [f64]| {
            r[0] = k * (x[1] - x[0] * x[0]);
            r[1] = 1.0 - x[0];
        },
    }
}

#[test]
fn geodesic_acceleration_follows_a_narrow_curved_valley() {
    // The creep objective's minima lie at the end of long curved valleys; plain LM crawls
    // along them in short steps. With the valley narrowed 100× (k = 1000), measured: 256
    // iterations plain, 86 accelerated; the same minimum.
    let (lb, ub) = free(2);
    let long = |o: LmOptions| LmOptions {
        max_iterations: 10_000,
        ..o
    };
    let plain = minimize(
        &narrow_rosenbrock(1000.0),
        &[-1.2, 1.0],
        &lb,
        &ub,
        &long(LmOptions::default()),
    );
    let accel = minimize(
        &narrow_rosenbrock(1000.0),
        &[-1.2, 1.0],
        &lb,
        &ub,
        &long(geo()),
    );
    for rep in [&plain, &accel] {
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        assert!(
            (rep.x[0] - 1.0).abs() < 1e-8 && (rep.x[1] - 1.0).abs() < 1e-8,
            "{:?}",
            rep.x
        );
    }
    assert!(
        2 * accel.iterations < plain.iterations && accel.evaluations < plain.evaluations,
        "accelerated {} iterations / {} evaluations, plain {} / {}",
        accel.iterations,
        accel.evaluations,
        plain.iterations,
        plain.evaluations
    );
    // And it still honours an active bound.
    let rep = minimize(
        &rosenbrock(),
        &[-1.2, 1.0],
        &[-2.0, -1.0],
        &[0.5, 2.0],
        &geo(),
    );
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert_eq!(rep.x[0], 0.5);
    assert!((rep.x[1] - 0.25).abs() < 1e-9, "{:?}", rep.x);
}

#[test]
fn fused_evaluation_replaces_the_separate_jacobian_and_changes_nothing() {
    let run = |fused: bool| {
        let p = Counted {
            inner: rosenbrock(),
            fused,
            jac_calls: Default::default(),
            fused_calls: Default::default(),
        };
        let rep = minimize(&p, &[-1.2, 1.0], &[-2.0, -1.0], &[0.8, 2.0], &geo());
        let jac = p.jac_calls.load(std::sync::atomic::Ordering::SeqCst);
        let fus = p.fused_calls.load(std::sync::atomic::Ordering::SeqCst);
        (rep, jac, fus)
    };
    let (sep, sep_jac, sep_fused) = run(false);
    let (fus, fus_jac, fus_fused) = run(true);
    assert!(sep.termination.converged() && fus.termination.converged());
    // Same iterates bit for bit: the fused values are the same numbers.
    assert_eq!(sep.x, fus.x);
    assert_eq!(sep.iterations, fus.iterations);
    assert_eq!(sep.evaluations, fus.evaluations);
    // Without fusion one Jacobian per iteration; with it none, every trial is fused.
    assert_eq!((sep_jac, sep_fused), (sep.iterations, 0));
    assert_eq!(fus_jac, 0);
    assert!(fus_fused > fus.iterations, "{fus_fused} fused calls");
}

#[test]
fn a_heavily_damped_step_is_not_taken_for_convergence() {
    // r = 1e4·(x − 1): the initial damping (relative to the largest diagonal of JᵀJ, 1e8)
    // makes the first step ~1e-5 of the way, a reduction of ~2e-5·f. With ftol = 1e-4 that
    // step alone once passed for convergence; what the undamped model could still gain
    // (all of f) must keep the iteration going to x = 1.
    let p = Fun {
        n: 1,
        m: 1,
        f: |x: &[f64], r: &mut [f64]| r[0] = 1e4 * (x[0] - 1.0),
    };
    let opts = LmOptions {
        ftol: 1e-4,
        ..LmOptions::default()
    };
    let rep = minimize(&p, &[0.0], &[-10.0], &[10.0], &opts);
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert!(
        (rep.x[0] - 1.0).abs() < 1e-6,
        "{:?} after {} iterations",
        rep.x,
        rep.iterations
    );
}

#[test]
fn a_step_short_only_because_of_the_damping_is_not_convergence() {
    // Two variables whose curvatures are 1e16 apart: the initial damping, relative to the
    // largest diagonal of JᵀJ, makes the weak variable's first step ~1e-13 long, below
    // xtol·‖x‖. That once ended the run as `converged_step` at its start, two units from the
    // minimum (as the rounds of a hierarchical fit ended, after a scatter step, at relative
    // dampings near 1e5); the undamped step is not short, so the damping must give way.
    // Without the option the run stops where it began, as it does in the fits that were
    // calibrated without it.
    let p = Fun {
        n: 2,
        m: 2,
        f: |x: &[f64], r: &mut [f64]| {
            r[0] = 1e8 * (x[0] - 1.0);
            r[1] = x[1] - 2.0;
        },
    };
    let opts = LmOptions {
        cut_overdamped: true,
        ..LmOptions::default()
    };
    let rep = minimize(&p, &[1.0, 0.0], &[-10.0; 2], &[10.0; 2], &opts);
    assert!(rep.termination.converged(), "{:?}", rep.termination);
    assert!(
        (rep.x[1] - 2.0).abs() < 1e-6 && (rep.x[0] - 1.0).abs() < 1e-12,
        "{:?} after {} iterations ({:?})",
        rep.x,
        rep.iterations,
        rep.termination
    );
    let off = minimize(
        &p,
        &[1.0, 0.0],
        &[-10.0; 2],
        &[10.0; 2],
        &LmOptions::default(),
    );
    assert_eq!(off.termination, Termination::ConvergedStep);
    assert_eq!(off.x[1], 0.0);
}

/// Rosenbrock's residuals and a constant one, with their scale σ profiled as a likelihood
/// profiles its reading error: r = g(x)/σ, σ re-estimated as ‖g‖/√m at every accepted point.
/// Then ‖r‖² = m there whatever x is, and the true objective is −2 ln L = m + m ln σ² (+ a
/// constant): the part [`LeastSquaresProblem::objective_offset`] gives (`offset: true`).
struct Profiled {
    sigma: Mutex<f64>,
    offset: bool,
}

impl Profiled {
    fn g(x: &[f64]) -> [f64; 3] {
        [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0], 0.1]
    }
}

impl LeastSquaresProblem for Profiled {
    fn n_params(&self) -> usize {
        2
    }
    fn n_residuals(&self) -> usize {
        3
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let s = *self.sigma.lock().unwrap();
        for (ri, gi) in r.iter_mut().zip(Self::g(x)) {
            *ri = gi / s;
        }
        Ok(())
    }
    fn reweight(
        &self,
        _x: &[f64],
        r: &mut [f64],
        jac: Option<&mut nalgebra::DMatrix<f64>>,
    ) -> bool {
        let mut guard = self.sigma.lock().unwrap();
        let old = *guard;
        let ss: f64 = r.iter().map(|v| (v * old).powi(2)).sum();
        let new = (ss / r.len() as f64).sqrt();
        if new == old {
            return false;
        }
        for v in r.iter_mut() {
            *v *= old / new;
        }
        if let Some(j) = jac {
            *j *= old / new;
        }
        *guard = new;
        true
    }
    fn objective_offset(&self) -> f64 {
        if self.offset {
            3.0 * (*self.sigma.lock().unwrap()).powi(2).ln()
        } else {
            0.0
        }
    }
}

#[test]
fn the_plateau_test_sees_a_profiled_likelihood_fall_where_the_residuals_do_not() {
    let opts = LmOptions {
        plateau: Some((6, 0.01)),
        ..LmOptions::default()
    };
    let (lb, ub) = free(2);
    let run = |offset| {
        let p = Profiled {
            sigma: Mutex::new(1.0),
            offset,
        };
        minimize(&p, &[-1.2, 1.0], &lb, &ub, &opts)
    };
    let rep = run(true);
    assert!(
        (rep.x[0] - 1.0).abs() < 1e-4 && (rep.x[1] - 1.0).abs() < 1e-4,
        "{:?} after {} iterations ({:?})",
        rep.x,
        rep.iterations,
        rep.termination
    );
    // The control: a plateau test on ‖r‖² alone (held at 3 by the reweighting) stops the
    // search on its seventh iteration, far from the minimum.
    let blind = run(false);
    assert_eq!(blind.termination, Termination::Plateau);
    assert!((blind.x[0] - 1.0).abs() > 0.1, "{:?}", blind.x);
}

/// r(x) = x − 1 with a Jacobian twice the true one: every step goes half way, so the
/// iteration converges linearly (the objective falls by 4 per iteration) and its relative
/// tests never pass; only the gradient test ends it, near 1e-12.
struct HalfWay;

impl LeastSquaresProblem for HalfWay {
    fn n_params(&self) -> usize {
        1
    }
    fn n_residuals(&self) -> usize {
        1
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        r[0] = x[0] - 1.0;
        Ok(())
    }
    fn jacobian(
        &self,
        _x: &[f64],
        _r: &[f64],
        jac: &mut nalgebra::DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        jac[(0, 0)] = 2.0;
        Some(Ok(()))
    }
}

#[test]
fn the_gain_to_come_test_is_a_table() {
    // (f at three iterations K apart, δ, stop?)
    let table = [
        ((1.0, 0.5, 0.25), 1e-3, false),     // q = 0.5, tail 0.25
        ((1e-3, 5e-4, 2.5e-4), 1e-3, true),  // q = 0.5, tail 2.5e-4
        ((1.0, 0.0, -0.95), 1e-3, false),    // q = 0.95: too slow to extrapolate
        ((1.0, 1.0, 1.0), 1e-3, true),       // nothing fell over either window
        ((1.0005, 1.0, 1.0), 1e-3, true),    // nothing fell, 5e-4 before
        ((1.1, 1.0, 1.0), 1e-3, false),      // nothing fell now, 0.1 before
        ((1.0, 1.0, 0.5), 1e-3, false),      // a fall after none: not converging
        ((1.0, f64::NAN, 0.5), 1e-3, false), // not evaluable
    ];
    for ((a, b, c), delta, want) in table {
        assert_eq!(
            small_gain_to_come(a, b, c, delta),
            want,
            "({a}, {b}, {c}), δ {delta}"
        );
    }
}

#[test]
fn the_gain_to_come_stop_ends_a_linear_crawl_within_its_tail() {
    let (lb, ub) = free(1);
    let full = minimize(&HalfWay, &[0.0], &lb, &ub, &LmOptions::default());
    let delta = 1e-6;
    let opts = LmOptions {
        gain_to_come: Some((5, delta)),
        ..LmOptions::default()
    };
    let cut = minimize(&HalfWay, &[0.0], &lb, &ub, &opts);
    assert_eq!(cut.termination, Termination::SmallGainToCome);
    assert!(cut.termination.converged());
    // The objective's falls are exactly geometric here, so the tail is the gain still to
    // come (the minimum is 0): the stop leaves at most δ of it, and not far less.
    assert!(cut.objective <= delta, "{} left", cut.objective);
    assert!(
        cut.objective > delta / 1e3,
        "{} left: stopped late",
        cut.objective
    );
    assert!(
        2 * cut.iterations < full.iterations,
        "{} iterations against {}",
        cut.iterations,
        full.iterations
    );
}

#[test]
fn lm_counts_count_runs_iterations_evaluations_and_runs_at_the_limit() {
    // Exactly, on a counter of its own: one run stopped by the limit, one converged.
    let (lb, ub) = free(2);
    let capped = LmOptions {
        max_iterations: 3,
        ..LmOptions::default()
    };
    let counter = LmCounter::new();
    let short = minimize(&rosenbrock(), &[-1.2, 1.0], &lb, &ub, &capped);
    assert_eq!(short.termination, Termination::IterationLimit);
    assert_eq!(short.iterations, 3);
    let full = minimize(&rosenbrock(), &[-1.2, 1.0], &lb, &ub, &LmOptions::default());
    assert!(full.termination.converged(), "{:?}", full.termination);
    counter.record(&short);
    counter.record(&full);
    assert_eq!(
        counter.snapshot(),
        LmCounts {
            runs: 2,
            iterations: 3 + full.iterations as u64,
            runs_at_limit: 1,
            iterations_at_limit: 3,
            evaluations: (short.evaluations + full.evaluations) as u64,
        }
    );
    // An iteration evaluates at least once (its trial point), and the start once more.
    assert!(short.evaluations > short.iterations, "{short:?}");
    // The process's counter: other tests of this binary run beside this one, so the
    // difference is at least this run's.
    let before = LmCounts::now();
    let again = minimize(&rosenbrock(), &[-1.2, 1.0], &lb, &ub, &capped);
    let d = LmCounts::now().since(&before);
    assert_eq!(again.termination, Termination::IterationLimit);
    assert!(d.runs >= 1 && d.runs_at_limit >= 1, "{d:?}");
    assert!(d.iterations >= 3 && d.iterations_at_limit >= 3, "{d:?}");
    assert!(d.runs_at_limit <= d.runs && d.iterations_at_limit <= d.iterations);
    assert!(d.evaluations > d.iterations, "{d:?}");
}
