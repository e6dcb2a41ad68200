//! The sensitivity Jacobian (dual numbers through the integrator) against central finite
//! differences, column by column, on the bundled data; and the one-state fast path against
//! the four-state model.

use creepfit::fit::FitSettings;
use creepfit::lsq::LeastSquaresProblem;
use creepfit::model::objective::{CreepProblem, JacobianMethod, Objective, ObjectiveSettings};
use creepfit::model::registry;
use creepfit::ode::OdeOptions;
use nalgebra::DMatrix;

mod common;
use common::config;

/// Largest relative column error of the sensitivity Jacobian against central differences,
/// at unit-box point `u`.
fn column_errors(cfg_name: &str, model: &str, u: &[f64], w: f64) -> Vec<f64> {
    let cfg = config(cfg_name);
    let data = cfg.load_data().unwrap();
    let model = registry(model).unwrap();
    // Tight tolerances so that the central differences themselves are accurate to ~1e-8.
    let ode = OdeOptions {
        rtol: 1e-12,
        atol: 1e-15,
        ..OdeOptions::default()
    };
    let settings = ObjectiveSettings {
        ode,
        ..FitSettings::from_config(&cfg).objective()
    };
    let problem = CreepProblem {
        objective: Objective::new(
            model.as_ref(),
            &data.curves,
            vec![w; data.curves.len()],
            settings,
        ),
        space: cfg.space(),
        jacobian: JacobianMethod::Sensitivity,
    };
    let (m, n) = (problem.n_residuals(), problem.n_params());
    let mut r = vec![0.0; m];
    problem.residuals(u, &mut r).unwrap();
    let mut js = DMatrix::zeros(m, n);
    problem.jacobian(u, &r, &mut js).unwrap().unwrap();
    let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
    (0..n)
        .map(|j| {
            // Central differences inside the box; second-order one-sided ones at a bound.
            let h = 1e-5;
            let fd: Vec<f64> = if u[j] - h >= 0.0 && u[j] + h <= 1.0 {
                let (mut up, mut um) = (u.to_vec(), u.to_vec());
                up[j] += h;
                um[j] -= h;
                problem.residuals(&up, &mut rp).unwrap();
                problem.residuals(&um, &mut rm).unwrap();
                (0..m).map(|i| (rp[i] - rm[i]) / (2.0 * h)).collect()
            } else {
                let s = if u[j] + h > 1.0 { -h } else { h };
                let (mut u1, mut u2) = (u.to_vec(), u.to_vec());
                u1[j] += s;
                u2[j] += 2.0 * s;
                problem.residuals(&u1, &mut rp).unwrap();
                problem.residuals(&u2, &mut rm).unwrap();
                (0..m)
                    .map(|i| (-3.0 * r[i] + 4.0 * rp[i] - rm[i]) / (2.0 * s))
                    .collect()
            };
            let scale = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
            let diff = (0..m)
                .map(|i| (js[(i, j)] - fd[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            eprintln!(
                "{cfg_name} {:?} col {j}: |J| {scale:.4e} rel err {:.3e}",
                u,
                diff / scale
            );
            diff / scale
        })
        .collect()
}

/// Unit-box points: the middle of the box, a corner region, and a point met by a fit where
/// h is near its upper bound and H sits at saturation (the sensitivity equations are stiff
/// there while the value is not: the case that needs error control on the sensitivities).
const POINTS: [[f64; 6]; 3] = [
    [0.5, 0.3, 0.4, 0.6, 0.5, 0.2],
    [0.9, 0.05, 0.1, 0.3, 0.7, 0.1],
    [0.9647, 0.0872, 0.0815, 0.98, 0.7824, 0.2854],
];

#[test]
fn sensitivity_jacobian_matches_central_differences_on_every_column() {
    for model in ["khd", "khd1"] {
        for (cfg, w) in [("560C.toml", 0.5), ("590C.toml", 1.0)] {
            for u in POINTS {
                for (j, e) in column_errors(cfg, model, &u, w).into_iter().enumerate() {
                    assert!(e < 1e-5, "{model} {cfg} {u:?} column {j}: error {e:e}");
                }
            }
        }
    }
}

/// The registry's `khd` (fast path: one-state reduction) against `khd4` (the four states of
/// eqs. 1–4) on the bundled curves' stresses and measured times, at the default tolerances
/// the fits use and at tight ones: predicted strains and rupture times to 1e-9 relative.
#[test]
fn fast_path_matches_four_state_path() {
    let fast = registry("khd").unwrap();
    let full = registry("khd4").unwrap();
    for cfg_name in ["560C.toml", "590C.toml"] {
        let cfg = config(cfg_name);
        let data = cfg.load_data().unwrap();
        let space = cfg.space();
        for u in POINTS {
            let mut x = vec![0.0; 6];
            space.from_unit(&u, &mut x);
            for c in &data.curves {
                let load = creepfit::model::Load {
                    stress_mpa: c.stress_mpa,
                    temperature_k: c.temperature_c + creepfit::model::ZERO_CELSIUS_K,
                    omega_f: cfg.objective.omega_f,
                };
                let o = OdeOptions {
                    rtol: 1e-12,
                    atol: 1e-15,
                    ..OdeOptions::default()
                };
                let n = c.times_h.len();
                let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
                let ra = fast.simulate(&x, &load, &c.times_h, &mut a, &o);
                let rb = full.simulate(&x, &load, &c.times_h, &mut b, &o);
                assert!(ra.ruptured() && rb.ruptured());
                let rel = |p: f64, q: f64| (p - q).abs() / q.abs().max(1e-300);
                assert!(
                    rel(ra.t_end, rb.t_end) < 1e-9,
                    "{} vs {}",
                    ra.t_end,
                    rb.t_end
                );
                assert_eq!(ra.n_out, rb.n_out);
                for k in 1..ra.n_out {
                    assert!(
                        rel(a[k], b[k]) < 1e-9,
                        "t={} {} vs {}",
                        c.times_h[k],
                        a[k],
                        b[k]
                    );
                }
                assert!(rel(ra.strain_end, rb.strain_end) < 1e-9);
            }
        }
    }
}

/// The fused evaluation the optimiser uses at trial points: the same Jacobian as the
/// separate call, bit for bit, and residuals that differ from the `f64` run only by the
/// integration error of the (differently controlled) dual-number run.
#[test]
fn fused_residuals_and_jacobian_agree_with_the_separate_calls() {
    let cfg = config("560C.toml");
    let data = cfg.load_data().unwrap();
    let model = registry("khd").unwrap();
    let settings = FitSettings::from_config(&cfg);
    let problem = CreepProblem {
        objective: Objective::new(
            model.as_ref(),
            &data.curves,
            vec![0.5; data.curves.len()],
            settings.objective(),
        ),
        space: cfg.space(),
        jacobian: JacobianMethod::Sensitivity,
    };
    let (m, n) = (problem.n_residuals(), problem.n_params());
    for u in POINTS {
        let (mut r, mut rf) = (vec![0.0; m], vec![0.0; m]);
        let (mut j, mut jf) = (DMatrix::zeros(m, n), DMatrix::zeros(m, n));
        problem.residuals(&u, &mut r).unwrap();
        problem.jacobian(&u, &r, &mut j).unwrap().unwrap();
        problem
            .residuals_and_jacobian(&u, &mut rf, &mut jf)
            .unwrap()
            .unwrap();
        assert_eq!(j, jf);
        let scale = r.iter().fold(1.0_f64, |a, v| a.max(v.abs()));
        for (a, b) in r.iter().zip(&rf) {
            assert!((a - b).abs() < 1e-6 * scale, "{a} vs {b} at {u:?}");
        }
    }
    // Finite-difference mode has no fused evaluation.
    let fd = CreepProblem {
        jacobian: JacobianMethod::FiniteDifference,
        ..problem
    };
    let mut r = vec![0.0; m];
    let mut j = DMatrix::zeros(m, n);
    assert!(fd
        .residuals_and_jacobian(&POINTS[0], &mut r, &mut j)
        .is_none());
}

/// A rupture within `HORIZON_MARGIN` of the horizon counts as none with sensitivities and as
/// a rupture without: the optimiser's trial points (evaluated with sensitivities) then stay
/// where the value-only evaluation of its result agrees. Before the margin, a sweep of a
/// generated far material (`tests/data/far_random_304`) lost starts at t_r = 0.999999999 ×
/// the horizon, accepted with sensitivities and failed without. The curve here has the
/// horizon (1 + margin/10) × (and, as control, (1 + 10 margin) ×) the rupture time the model
/// predicts.
#[test]
fn a_rupture_at_the_horizons_edge_is_none_with_sensitivities() {
    use creepfit::model::objective::{HORIZON_FACTOR, HORIZON_MARGIN};
    let cfg = config("590C.toml");
    let data = cfg.load_data().unwrap();
    let model = registry("khd").unwrap();
    let settings = FitSettings::from_config(&cfg).objective();
    let space = cfg.space();
    let u = POINTS[0];
    let mut x = vec![0.0; 6];
    space.from_unit(&u, &mut x);
    let c0 = &data.curves[0];
    let t_r = Objective::new(
        model.as_ref(),
        std::slice::from_ref(c0),
        vec![1.0],
        settings,
    )
    .evaluate(&x)
    .curves[0]
        .rupture_time_h;
    assert!(t_r.is_finite() && t_r > 0.0);
    for (beyond, inside_margin) in [
        (HORIZON_MARGIN / 10.0, true),
        (HORIZON_MARGIN * 10.0, false),
    ] {
        // A measured life that puts the horizon (HORIZON_FACTOR × the life) just past t_r.
        let life = t_r * (1.0 + beyond) / HORIZON_FACTOR;
        let mut c = c0.clone();
        c.times_h = vec![0.0, 0.5 * life, life];
        c.strains = vec![0.0, 0.5 * c0.rupture_strain, c0.rupture_strain];
        c.rupture_time_h = Some(life);
        c.groups = None;
        let curves = [c];
        let problem = CreepProblem {
            objective: Objective::new(model.as_ref(), &curves, vec![1.0], settings),
            space: space.clone(),
            jacobian: JacobianMethod::Sensitivity,
        };
        let (m, n) = (problem.n_residuals(), problem.n_params());
        let mut r = vec![0.0; m];
        // Without sensitivities it ruptures inside the horizon either way.
        problem.residuals(&u, &mut r).unwrap();
        let mut jac = DMatrix::zeros(m, n);
        let with = problem
            .residuals_and_jacobian(&u, &mut r, &mut jac)
            .unwrap();
        match (inside_margin, with) {
            (true, Err(e)) => assert!(e.0.contains("horizon"), "{}", e.0),
            (false, Ok(())) => {}
            (m, w) => panic!("horizon {beyond} past t_r, inside the margin {m}: {w:?}"),
        }
    }
}
