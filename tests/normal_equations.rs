//! The large-problem path of the least-squares fit: the normal equations accumulated while the
//! dual residuals stream out of the integrator equal JᵀJ and Jᵀr of the stored sensitivity
//! Jacobian, and the geodesic correction's Jᵀ·r_vv streamed from the Jacobian produced anew
//! equals the stored path's.

use std::path::Path;

use creepfit::config::RunConfig;
use creepfit::fit::{param_space, FitSettings};
use creepfit::lsq::{LeastSquaresProblem, NormalEquations};
use creepfit::model::build;
use creepfit::objective::{CreepProblem, JacobianMethod, Objective};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn config(name: &str) -> RunConfig {
    RunConfig::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("configs")
            .join(name),
    )
    .unwrap()
}

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
    for cfg_name in ["560C.toml", "590C.toml"] {
        let cfg = config(cfg_name);
        let data = cfg.load_data().unwrap();
        let model = build(&cfg.model, &cfg.extensions).unwrap();
        let settings = FitSettings::from_config(&cfg);
        for _ in 0..6 {
            let w: Vec<f64> = data.curves.iter().map(|_| rng.gen::<f64>()).collect();
            let problem = CreepProblem {
                objective: Objective::new(model.as_ref(), &data.curves, w, settings.objective()),
                space: param_space(&cfg),
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
        }
    }
}
