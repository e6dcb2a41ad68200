//! Fits of a large logged curve (100,000 points, as a data logger writes them): the two-stage
//! local fit (bin-averaged curves, then the full data) reaches the minimum of the plain
//! one-stage fit of the full data, converged by the same rules; the binned objective is the
//! full one's to within its binning terms; the reported fit's predictions are recomputed.

use std::path::Path;

use creepfit::config::RunConfig;
use creepfit::data::{estimate_min_rate, Curve};
use creepfit::fit::{is_large, local_fit, with_predictions, FitSettings, MULTIRES_BINNED_POINTS};
use creepfit::lsq::minimize;
use creepfit::model::objective::{bin_curves, CreepProblem, Objective};
use creepfit::model::{build, Load};
use creepfit::ode::OdeOptions;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The 560 °C fit's constants (README): A, B, H*, h, Kc, C.
const CONSTANTS: [f64; 6] = [
    1.0e-10,
    0.1749367,
    0.5630134,
    5.903132e4,
    2.212783e-5,
    4.031361,
];

fn config() -> RunConfig {
    RunConfig::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/560C.toml")).unwrap()
}

/// Three 560 °C tests simulated from [`CONSTANTS`] with Gaussian noise of 0.002 % strain
/// (fixed seed), the 100 MPa one logged at `n` points, the others at 1,000; times uniform up
/// to 99.5 % of the life (as `examples/gen_large.rs`).
fn logged_curves(n: usize) -> Vec<Curve> {
    let model = build("khd", &[]).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    [(85.0, 1000), (100.0, n), (110.0, 1000)]
        .into_iter()
        .map(|(stress, points)| {
            let load = Load::new(stress, 560.0, 1.0 / 3.0);
            let opts = OdeOptions::default();
            let life = model.simulate(&CONSTANTS, &load, &[], &mut [], &opts).t_end;
            let times: Vec<f64> = (0..points)
                .map(|k| 0.995 * life * k as f64 / (points - 1) as f64)
                .collect();
            let mut strains = vec![0.0; points];
            model.simulate(&CONSTANTS, &load, &times, &mut strains, &opts);
            for e in &mut strains {
                let (u1, u2): (f64, f64) = (rng.gen::<f64>().max(1e-300), rng.gen());
                let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                *e += 2e-5 * z;
            }
            Curve {
                temperature_c: 560.0,
                stress_mpa: stress,
                specimen: None,
                groups: None,
                min_rate_estimated: estimate_min_rate(&times, &strains, life),
                rupture_strain: *strains.last().unwrap(),
                times_h: times,
                strains,
                rupture_time_h: Some(life),
                min_rate_measured: None,
            }
        })
        .collect()
}

#[test]
fn two_stage_fit_reaches_the_minimum_of_the_plain_fit() {
    let cfg = config();
    let settings = FitSettings::from_config(&cfg);
    let space = cfg.space();
    let model = build("khd", &[]).unwrap();
    let curves = logged_curves(100_000);
    assert!(is_large(&curves));
    let start = cfg.starts_all_given().unwrap();
    let w = vec![1.0; curves.len()];

    let two = local_fit(
        model.as_ref(),
        &curves,
        &space,
        &w,
        &start,
        "config",
        &settings,
    );

    let problem = CreepProblem {
        objective: Objective::new(model.as_ref(), &curves, w.clone(), settings.objective()),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let u0 = space.to_unit(&start);
    let k = u0.len();
    let plain = minimize(&problem, &u0, &vec![0.0; k], &vec![1.0; k], &settings.lm);

    // The first stage alone: the binned fit, its constants scored on the full data.
    let bins = bin_curves(&curves, MULTIRES_BINNED_POINTS);
    let coarse = CreepProblem {
        objective: Objective::binned(model.as_ref(), &bins, w.clone(), settings.objective()),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let first = minimize(&coarse, &u0, &vec![0.0; k], &vec![1.0; k], &settings.lm);
    let mut x1 = start.clone();
    space.from_unit(&first.x, &mut x1);
    let f1 = problem.objective.evaluate(&x1).objective;

    assert!(two.lm.termination.converged(), "{:?}", two.lm.termination);
    assert!(plain.termination.converged(), "{:?}", plain.termination);
    // The same minimum: converged fits of this objective differ by ~1e-7 relative (where
    // they stop along the flat B–H* valley, and the integration error of the objective, of
    // that order at rtol 1e-8), so within 1e-6; the binned fit's own constants (3.5e-6 off
    // here) do not pass that: the second stage has to make it up (a false convergence at
    // its first step would leave them).
    let rel = |f: f64| (f - plain.objective) / plain.objective;
    let report = format!(
        "plain {} two-stage {} ({:e}) first stage {} ({:e})",
        plain.objective,
        two.eval.objective,
        rel(two.eval.objective),
        f1,
        rel(f1)
    );
    assert!(rel(two.eval.objective).abs() < 1e-6, "{report}");
    assert!(rel(f1) > 1e-6, "the first stage alone would pass: {report}");
    // The fitted constants lie on the flat B–H* valley, where the data determine B(1 − H*)
    // and the other constants well.
    let mut x = start.clone();
    space.from_unit(&plain.x, &mut x);
    let s = |p: &[f64]| p[1] * (1.0 - p[2]);
    assert!((s(&two.params) / s(&x) - 1.0).abs() < 1e-5);
    for j in [0, 3, 4, 5] {
        assert!(
            (two.params[j] / x[j] - 1.0).abs() < 1e-4,
            "constant {j}: {} vs {}",
            two.params[j],
            x[j]
        );
    }

    // The large fit kept no predictions; the reported one gets them, the evaluation's own.
    assert!(two.eval.curves.iter().all(|p| p.strain.is_empty()));
    let reported = with_predictions(two.clone(), model.as_ref(), &curves, &settings);
    let full = problem.objective.evaluate(&two.params);
    assert_eq!(reported.eval, full);
    assert_eq!(reported.eval.objective, two.eval.objective);
}

#[test]
fn binned_objective_is_the_full_one_up_to_binning_terms() {
    let cfg = config();
    let settings = FitSettings::from_config(&cfg);
    let model = build("khd", &[]).unwrap();
    let curves = logged_curves(100_000);
    let bins = bin_curves(&curves, MULTIRES_BINNED_POINTS);
    assert_eq!(bins.curves[1].times_h.len(), MULTIRES_BINNED_POINTS);
    assert_eq!(
        bins.curves[0], curves[0],
        "short curves are kept as they are"
    );
    let w = vec![0.5; 3];
    let full = Objective::new(model.as_ref(), &curves, w.clone(), settings.objective());
    let binned = Objective::binned(model.as_ref(), &bins, w, settings.objective());
    assert_eq!(
        binned.n_residuals(),
        1000 + 1000 + MULTIRES_BINNED_POINTS + 3 + 1
    );
    // At the true constants the full objective is the measurement noise, σ = 0.002 %
    // strain a point. The scatter term keeps all of it but one degree of freedom a bin of
    // the long curve (the slope within the bin, whose misfit the binned objective omits):
    // binned ≈ full − bins·(σ/ε_f)², up to a χ² spread of √(2·bins)·(σ/ε_f)², 0.14 % of
    // the full value here; 1 % is seven of those.
    let noise = (2e-5 / curves[1].rupture_strain).powi(2);
    let deficit = MULTIRES_BINNED_POINTS as f64 * noise;
    let at_truth = (full.evaluate(&CONSTANTS), binned.evaluate(&CONSTANTS));
    let gap = at_truth.0.objective - at_truth.1.objective;
    assert!(
        (gap - deficit).abs() < 0.01 * at_truth.0.objective,
        "full {} binned {} gap {gap} expected {deficit}",
        at_truth.0.objective,
        at_truth.1.objective
    );
    // What moves the minimum are differences between constant sets: the same in both.
    let mut off = CONSTANTS.to_vec();
    off[5] *= 1.01;
    let (f, b) = (full.evaluate(&off), binned.evaluate(&off));
    let (df, db) = (
        f.objective - at_truth.0.objective,
        b.objective - at_truth.1.objective,
    );
    assert!(df > 10.0 * at_truth.0.objective, "a visible change: {df}");
    assert!((db / df - 1.0).abs() < 1e-3, "change full {df} binned {db}");
    // And the residual vector says what the evaluation says.
    let mut r = vec![0.0; binned.n_residuals()];
    binned.residuals(&off, &mut r).unwrap();
    let ss: f64 = r.iter().map(|v| v * v).sum();
    assert!((ss / b.objective - 1.0).abs() < 1e-12);
}
