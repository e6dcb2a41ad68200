//! The large-problem path of the least-squares fit: the normal equations accumulated while the
//! dual residuals stream out of the integrator equal JᵀJ and Jᵀr of the stored sensitivity
//! Jacobian, and the geodesic correction's Jᵀ·r_vv streamed from the Jacobian produced anew
//! equals the stored path's.

use creepfit::fit::FitSettings;
use creepfit::lsq::{LeastSquaresProblem, NormalEquations};
use creepfit::model::objective::{CreepProblem, JacobianMethod, Objective};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod common;
use common::config;

/// Largest entry of |a − b| relative to the largest entry of |b|.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

#[test]
fn streamed_normal_equations_equal_those_of_the_stored_jacobian() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // The joint seed calibration streams through the temperature laws (A and Kc Arrhenius:
    // 8 free constants, the most one narrow dual pass carries).
    for cfg_name in ["560C.toml", "590C.toml", "cmv-joint.toml"] {
        let cfg = config(cfg_name);
        let data = cfg.load_data().unwrap();
        let cfg = cfg.with_data(&data);
        let model = cfg.build_model().unwrap();
        let settings = FitSettings::from_config(&cfg);
        let mut checked = 0;
        for _ in 0..6 {
            let w: Vec<f64> = data.curves.iter().map(|_| rng.gen::<f64>()).collect();
            let problem = CreepProblem {
                objective: Objective::new(model.as_ref(), &data.curves, w, settings.objective()),
                space: cfg.space(),
                jacobian: JacobianMethod::Sensitivity,
            };
            let (m, n) = (problem.n_residuals(), problem.n_params());
            // A random point of the unit box that simulates (most do).
            let u: Vec<f64> = (0..n).map(|_| rng.gen_range(0.1..0.9)).collect();
            let (mut r, mut jac) = (vec![0.0; m], DMatrix::zeros(m, n));
            if problem
                .residuals_and_jacobian(&u, &mut r, &mut jac)
                .unwrap()
                .is_err()
            {
                continue;
            }
            let stored = NormalEquations::from_jacobian(&jac, &r);
            let mut r2 = vec![f64::NAN; m];
            let mut ne = NormalEquations::zeros(n);
            problem
                .residuals_and_normal_equations(&u, &mut r2, &mut ne)
                .expect("sensitivities")
                .unwrap();
            assert_eq!(r, r2, "the residuals are the same numbers");
            let (dj, dg) = (
                rel_diff(ne.jtj.as_slice(), stored.jtj.as_slice()),
                rel_diff(ne.jtr.as_slice(), stored.jtr.as_slice()),
            );
            assert!(
                dj < 1e-12 && dg < 1e-12,
                "{cfg_name} {u:?}: JtJ {dj:e}, Jtr {dg:e}"
            );

            // Geodesic: Jᵀ·r_vv along a random step, both ways.
            let h = 0.1;
            let v: Vec<f64> = (0..n).map(|_| rng.gen_range(-0.02..0.02)).collect();
            let xp: Vec<f64> = (0..n).map(|j| u[j] + h * v[j]).collect();
            let mut rp = vec![0.0; m];
            problem.residuals(&xp, &mut rp).unwrap();
            let jv = &jac * DVector::from_column_slice(&v);
            let rvv =
                DVector::from_iterator(m, (0..m).map(|i| 2.0 / h * ((rp[i] - r[i]) / h - jv[i])));
            let want = jac.tr_mul(&rvv);
            let mut got = vec![0.0; n];
            problem
                .geodesic_normal(&u, &v, h, &r, &rp, &mut got)
                .expect("sensitivities")
                .unwrap();
            let d = rel_diff(&got, want.as_slice());
            assert!(d < 1e-12, "{cfg_name} {u:?}: geodesic Jᵀr_vv {d:e}");
            checked += 1;
        }
        assert!(checked > 0, "{cfg_name}: no random point simulated");
    }
}

/// With more free constants than one narrow dual pass carries, a problem large enough for
/// the normal equations keeps the stored Jacobian, from sensitivities (never finite
/// differences): 9 constants (KHD, A and Kc Arrhenius, B linear) on the 560 °C curves
/// resampled to 7,000 points each (21,003 residuals).
#[test]
fn more_free_constants_than_the_narrow_pass_keep_the_stored_sensitivity_jacobian() {
    use creepfit::model::objective::ParamSpace;
    use creepfit::model::{build, with_laws, LawKind::*};
    let cfg = config("560C.toml");
    let data = cfg.load_data().unwrap();
    let settings = FitSettings::from_config(&cfg);
    let model = with_laws(
        build("khd", &[]).unwrap(),
        &[Arrhenius, Linear, Constant, Constant, Arrhenius, Constant],
        575.0,
    );
    let curves: Vec<_> = data
        .curves
        .iter()
        .map(|c| {
            let (t0, t1) = (c.times_h[0], *c.times_h.last().unwrap());
            let times: Vec<f64> = (0..7000)
                .map(|k| t0 + (t1 - t0) * k as f64 / 6999.0)
                .collect();
            let strains = times
                .iter()
                .map(|&t| {
                    let j = c
                        .times_h
                        .partition_point(|&x| x <= t)
                        .clamp(1, c.times_h.len() - 1);
                    let (ta, tb) = (c.times_h[j - 1], c.times_h[j]);
                    let (ea, eb) = (c.strains[j - 1], c.strains[j]);
                    ea + (eb - ea) * (t - ta) / (tb - ta)
                })
                .collect();
            let mut c = c.clone();
            c.times_h = times;
            c.strains = strains;
            c
        })
        .collect();
    let specs = model.constants();
    let space = ParamSpace::new(
        specs.iter().map(|c| c.lb).collect(),
        specs.iter().map(|c| c.ub).collect(),
        specs.iter().map(|c| c.scale).collect(),
    );
    let problem = CreepProblem {
        objective: Objective::new(model.as_ref(), &curves, vec![1.0; 3], settings.objective()),
        space: space.clone(),
        jacobian: JacobianMethod::Sensitivity,
    };
    let (m, n) = (problem.n_residuals(), problem.n_params());
    assert_eq!(n, 9);
    assert!(m >= creepfit::model::objective::NORMAL_EQUATIONS_MIN_RESIDUALS);
    assert!(!problem.prefers_normal_equations());
    let mut x = cfg.starts_all_given().unwrap();
    x.extend([300.0, 0.0, 200.0]);
    let u = space.to_unit(&x);
    let mut ne = NormalEquations::zeros(n);
    assert!(problem
        .residuals_and_normal_equations(&u, &mut vec![0.0; m], &mut ne)
        .is_none());
    let (mut r, mut jac) = (vec![0.0; m], DMatrix::zeros(m, n));
    problem
        .residuals_and_jacobian(&u, &mut r, &mut jac)
        .expect("sensitivities, not finite differences")
        .unwrap();
    // Every column carries a derivative (A.Q and Kc.Q act at 560 °C, 15 K below T_ref).
    for j in 0..n {
        assert!(jac.column(j).amax() > 0.0, "column {j} is zero");
    }
}

/// y = a·e^(−b·t) + c fitted to 60 points of such a curve with a kink added: r(x) with its
/// analytic Jacobian, offered either as a stored Jacobian or as normal equations only.
struct Decay {
    t: Vec<f64>,
    y: Vec<f64>,
    normal: bool,
}

impl Decay {
    fn new(normal: bool) -> Self {
        let t: Vec<f64> = (0..60).map(|i| i as f64 * 0.1).collect();
        let y = t
            .iter()
            .map(|&t| 2.5 * (-1.3 * t).exp() + 0.4 + 0.02 * (3.0 * t).sin())
            .collect();
        Decay { t, y, normal }
    }
    fn jac(&self, x: &[f64]) -> DMatrix<f64> {
        DMatrix::from_fn(self.t.len(), 3, |i, j| {
            let e = (-x[1] * self.t[i]).exp();
            match j {
                0 => e,
                1 => -x[0] * self.t[i] * e,
                _ => 1.0,
            }
        })
    }
}

impl LeastSquaresProblem for Decay {
    fn n_params(&self) -> usize {
        3
    }
    fn n_residuals(&self) -> usize {
        self.t.len()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), creepfit::lsq::EvalFailure> {
        for ((ri, t), y) in r.iter_mut().zip(&self.t).zip(&self.y) {
            *ri = x[0] * (-x[1] * t).exp() + x[2] - y;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), creepfit::lsq::EvalFailure>> {
        jac.copy_from(&self.jac(x));
        Some(self.residuals(x, r))
    }
    fn prefers_normal_equations(&self) -> bool {
        self.normal
    }
    fn residuals_and_normal_equations(
        &self,
        x: &[f64],
        r: &mut [f64],
        ne: &mut NormalEquations,
    ) -> Option<Result<(), creepfit::lsq::EvalFailure>> {
        self.residuals(x, r).unwrap();
        *ne = NormalEquations::from_jacobian(&self.jac(x), r);
        Some(Ok(()))
    }
    fn geodesic_normal(
        &self,
        x: &[f64],
        v: &[f64],
        h: f64,
        r: &[f64],
        r_probe: &[f64],
        jt_rvv: &mut [f64],
    ) -> Option<Result<(), creepfit::lsq::EvalFailure>> {
        let jac = self.jac(x);
        let jv = &jac * DVector::from_column_slice(v);
        let rvv = DVector::from_iterator(
            r.len(),
            (0..r.len()).map(|i| 2.0 / h * ((r_probe[i] - r[i]) / h - jv[i])),
        );
        jt_rvv.copy_from_slice(jac.tr_mul(&rvv).as_slice());
        Some(Ok(()))
    }
}

#[test]
fn the_iteration_on_normal_equations_follows_the_stored_one() {
    use creepfit::lsq::{minimize, LmOptions};
    // Unbounded, and with c held at an upper bound below its optimum; plain and geodesic.
    for (ub_c, geodesic) in [
        (10.0, None),
        (10.0, Some(0.75)),
        (0.3, None),
        (0.3, Some(0.75)),
    ] {
        let opts = LmOptions {
            geodesic,
            ..LmOptions::default()
        };
        let (lb, ub) = ([0.0, 0.0, -10.0], [10.0, 10.0, ub_c]);
        let x0 = [1.0, 0.2, 0.0];
        let stored = minimize(&Decay::new(false), &x0, &lb, &ub, &opts);
        let normal = minimize(&Decay::new(true), &x0, &lb, &ub, &opts);
        assert!(stored.termination.converged(), "{:?}", stored.termination);
        assert_eq!(normal.termination, stored.termination);
        assert_eq!(normal.iterations, stored.iterations);
        for j in 0..3 {
            assert!(
                (normal.x[j] - stored.x[j]).abs() < 1e-9,
                "{ub_c} {geodesic:?}: {:?} vs {:?}",
                normal.x,
                stored.x
            );
        }
        assert!((normal.objective / stored.objective - 1.0).abs() < 1e-12);
        if ub_c < 1.0 {
            assert_eq!(normal.x[2], ub_c, "held at its bound");
        }
    }
}
