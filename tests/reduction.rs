//! `[diagnose] reduction = "means"`: a curve reduced to group means carries its readings'
//! times, and the objective compares each mean with the model's own mean over the same
//! readings — the same numbers as the model at every reading averaged by hand, and a
//! sensitivity Jacobian that matches central differences through the averaging.

use std::path::Path;

use creepfit::config::RunConfig;
use creepfit::data::{reduced_to_means, Curve};
use creepfit::fit::FitSettings;
use creepfit::lsq::LeastSquaresProblem;
use creepfit::model::objective::{CreepProblem, JacobianMethod, Objective, ObjectiveSettings};
use creepfit::model::registry;
use creepfit::ode::OdeOptions;
use nalgebra::DMatrix;

mod common;
use common::config;

/// The seed's 590 °C curves (36–70 readings) and the same reduced to 12 points.
fn curves() -> (RunConfig, Vec<Curve>, Vec<Curve>) {
    let cfg = config("590C.toml");
    let raw = cfg.load_data().unwrap().curves;
    let reduced: Vec<Curve> = raw.iter().map(|c| reduced_to_means(c, 12)).collect();
    (cfg, raw, reduced)
}

#[test]
fn a_mean_is_compared_with_the_models_mean_over_its_readings() {
    let (cfg, raw, reduced) = curves();
    let model = registry("khd").unwrap();
    let settings = FitSettings::from_config(&cfg).objective();
    let space = cfg.space();
    let mut params = space.fixed.clone();
    space.from_unit(&[0.5, 0.3, 0.4, 0.6, 0.5, 0.2], &mut params);
    let whole =
        Objective::new(model.as_ref(), &raw, vec![1.0; raw.len()], settings).evaluate(&params);
    let means =
        Objective::new(model.as_ref(), &reduced, vec![1.0; raw.len()], settings).evaluate(&params);
    for (i, (c, r)) in raw.iter().zip(&reduced).enumerate() {
        let g = r.groups.as_ref().expect("reduced");
        assert_eq!(g.times_h, c.times_h);
        assert_eq!(r.times_h.len(), 12.min(c.times_h.len()));
        let mut lo = 0;
        for (k, &hi) in g.ends.iter().enumerate() {
            let m = (hi - lo) as f64;
            let model_mean: f64 = whole.curves[i].strain[lo..hi].iter().sum::<f64>() / m;
            let data_mean: f64 = c.strains[lo..hi].iter().sum::<f64>() / m;
            assert!(
                (means.curves[i].strain[k] - model_mean).abs() <= 1e-12 * model_mean.abs(),
                "curve {i} point {k}: {} against {model_mean}",
                means.curves[i].strain[k]
            );
            assert!((r.strains[k] - data_mean).abs() <= 1e-15);
            lo = hi;
        }
        assert_eq!(
            means.curves[i].rupture_time_h,
            whole.curves[i].rupture_time_h
        );
    }
}

#[test]
fn the_sensitivity_jacobian_of_means_matches_central_differences() {
    let (cfg, _, reduced) = curves();
    let model = registry("khd").unwrap();
    let settings = ObjectiveSettings {
        ode: OdeOptions {
            rtol: 1e-12,
            atol: 1e-15,
            ..OdeOptions::default()
        },
        ..FitSettings::from_config(&cfg).objective()
    };
    let problem = CreepProblem {
        objective: Objective::new(model.as_ref(), &reduced, vec![1.0; reduced.len()], settings),
        space: cfg.space(),
        jacobian: JacobianMethod::Sensitivity,
    };
    let u = [0.5, 0.3, 0.4, 0.6, 0.5, 0.2];
    let (m, n) = (problem.n_residuals(), problem.n_params());
    let mut r = vec![0.0; m];
    problem.residuals(&u, &mut r).unwrap();
    let mut js = DMatrix::zeros(m, n);
    problem.jacobian(&u, &r, &mut js).unwrap().unwrap();
    let mut jf = DMatrix::zeros(m, n);
    let mut rf = vec![0.0; m];
    problem
        .residuals_and_jacobian(&u, &mut rf, &mut jf)
        .unwrap()
        .unwrap();
    // The fused call integrates with the sensitivities (its own steps): equal to the
    // integration's accuracy.
    for (a, b) in r.iter().zip(&rf) {
        assert!((a - b).abs() <= 1e-9 * (1.0 + a.abs()), "{a} {b}");
    }
    let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
    for j in 0..n {
        let h = 1e-5;
        let (mut up, mut um) = (u.to_vec(), u.to_vec());
        up[j] += h;
        um[j] -= h;
        problem.residuals(&up, &mut rp).unwrap();
        problem.residuals(&um, &mut rm).unwrap();
        let fd: Vec<f64> = (0..m).map(|i| (rp[i] - rm[i]) / (2.0 * h)).collect();
        let scale = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
        let err = |jac: &DMatrix<f64>| {
            (0..m)
                .map(|i| (jac[(i, j)] - fd[i]).powi(2))
                .sum::<f64>()
                .sqrt()
                / scale
        };
        assert!(err(&js) < 1e-5, "column {j}: {:e}", err(&js));
        assert!(err(&jf) < 1e-5, "fused, column {j}: {:e}", err(&jf));
    }
}

#[test]
fn the_reduction_is_read_from_the_diagnose_table() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/590C.toml"))
            .unwrap();
    let at = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/x.toml");
    let read = |extra: &str| {
        RunConfig::from_str_with(&format!("{text}\n{extra}"), &at, &Default::default())
    };
    assert_eq!(
        read("").unwrap().diagnose.reduction,
        creepfit::data::Reduction::LocalQuadratic
    );
    assert_eq!(
        read("[diagnose]\nreduction = \"means\"\n")
            .unwrap()
            .diagnose
            .reduction,
        creepfit::data::Reduction::Means
    );
    let err = read("[diagnose]\nreduction = \"median\"\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("reduction") && err.contains("means"), "{err}");
}
