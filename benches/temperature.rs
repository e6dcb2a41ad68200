//! Criterion benchmarks of the joint calibration across temperatures:
//!
//! - `joint/local_fit_*`: one local fit at w = 1 from the computed initial guess, of the
//!   seed's 560 °C and 590 °C data alone (`configs/560C.toml`, `configs/590C.toml`, 6
//!   constants each) and of both together (`configs/cmv-joint.toml`, 2 temperatures × 3
//!   curves, 8 constants: A and Kc with activation energies). The bound: the joint
//!   fit costs at most 2.5× a single-temperature one.
//! - `joint/guess_*`: the computed initial guess alone (the paper's IV.C procedure; for the
//!   joint configuration per temperature, the laws fitted, then again per temperature with
//!   the common constants held and the laws fitted once more).
//! - `joint/local_fit_*_displaced_w1`: the same two fits from their optimum displaced by 0.05
//!   in every scaled coordinate: the cost of the fit itself, whatever the guess.
//! - `joint/fit_procedure_*`: the same two as `fit --start guess` does them (the guess, then
//!   a local fit for every w of the grid, in parallel).
//! - `constants/local_fit_{6,10}_free`: one local fit of the same nine synthetic curves at
//!   three temperatures (KHD with A and Kc Arrhenius, B and C linear in T: 10 constants) from
//!   the same displaced start, with the four law parameters held at their true values (6 free
//!   constants, narrow dual numbers) or free (10, wide dual numbers). The bound: 10
//!   constants cost at most 2× 6.

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use creepfit::config::{RunConfig, StartChoice};
use creepfit::data::{estimate_min_rate, Curve, Dataset};
use creepfit::fit::{local_fit, run_fit, FitSettings};
use creepfit::model::guess::initial_guess;
use creepfit::model::objective::{Objective, ParamSpace};
use creepfit::model::{build, with_laws, LawKind, Load, Model, Scale};
use creepfit::ode::OdeOptions;

fn resolved(name: &str, guess_only: bool) -> (RunConfig, Dataset) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = RunConfig::load(&root.join("configs").join(name)).unwrap();
    if guess_only {
        cfg.fit.starts = StartChoice::Guess;
    }
    let data = cfg.load_data().unwrap();
    (cfg.with_data(&data), data)
}

fn synthetic(model: &dyn Model, truth: &[f64]) -> Vec<Curve> {
    let ode = OdeOptions {
        rtol: 1e-12,
        atol: 1e-15,
        ..OdeOptions::default()
    };
    let mut out = Vec::new();
    for (t, s) in [
        (560.0, 85.0),
        (560.0, 100.0),
        (560.0, 110.0),
        (575.0, 80.0),
        (575.0, 95.0),
        (575.0, 105.0),
        (590.0, 75.0),
        (590.0, 90.0),
        (590.0, 100.0),
    ] {
        let load = Load::new(s, t, 1.0 / 3.0);
        let r = model.simulate(truth, &load, &[], &mut [], &ode);
        let times: Vec<f64> = (0..36)
            .map(|k| r.t_end * (1.0 - (1.0 - k as f64 / 36.0).powf(1.5)))
            .collect();
        let mut e = vec![0.0; times.len()];
        model.simulate(truth, &load, &times, &mut e, &ode);
        out.push(Curve {
            temperature_c: t,
            stress_mpa: s,
            specimen: None,
            groups: None,
            min_rate_estimated: estimate_min_rate(&times, &e, r.t_end),
            times_h: times,
            strains: e,
            rupture_time_h: Some(r.t_end),
            rupture_strain: r.strain_end,
            min_rate_measured: None,
        });
    }
    out
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("joint");
    g.sample_size(10);
    for name in ["560C.toml", "590C.toml", "cmv-joint.toml"] {
        let (cfg, data) = resolved(name, true);
        let model = cfg.build_model().unwrap();
        let space = cfg.space();
        let settings = FitSettings::from_config(&cfg);
        let guess = initial_guess(
            model.as_ref(),
            &data.curves,
            &space,
            settings.omega_f,
            &settings.ode,
        );
        let w = vec![1.0; data.curves.len()];
        let f = local_fit(
            model.as_ref(),
            &data.curves,
            &space,
            &w,
            &guess.params,
            "",
            &settings,
        );
        eprintln!(
            "{name}: local fit from the guess: {} iterations, {} evaluations, objective {}",
            f.lm.iterations, f.lm.evaluations, f.eval.objective
        );
        let stem = name.trim_end_matches(".toml");
        g.bench_function(format!("guess_{stem}"), |b| {
            b.iter(|| {
                initial_guess(
                    model.as_ref(),
                    black_box(&data.curves),
                    &space,
                    settings.omega_f,
                    &settings.ode,
                )
            })
        });
        g.bench_function(format!("local_fit_{stem}_from_guess_w1"), |b| {
            b.iter(|| {
                local_fit(
                    model.as_ref(),
                    &data.curves,
                    &space,
                    &w,
                    black_box(&guess.params),
                    "",
                    &settings,
                )
            })
        });
        // The same from the optimum displaced by 0.05 in every scaled coordinate (alternating
        // sign): the cost of the fit itself, apart from how far each guess lies.
        let u: Vec<f64> = space
            .to_unit(&f.params)
            .iter()
            .enumerate()
            .map(|(j, u)| {
                let d = if j % 2 == 0 { 0.05 } else { -0.05 };
                if (0.0..=1.0).contains(&(u + d)) {
                    u + d
                } else {
                    u - d
                }
            })
            .collect();
        let mut displaced = f.params.clone();
        space.from_unit(&u, &mut displaced);
        let fd = local_fit(
            model.as_ref(),
            &data.curves,
            &space,
            &w,
            &displaced,
            "",
            &settings,
        );
        eprintln!(
            "{name}: local fit from the displaced optimum: {} iterations, {} evaluations, objective {}",
            fd.lm.iterations, fd.lm.evaluations, fd.eval.objective
        );
        g.bench_function(format!("local_fit_{stem}_displaced_w1"), |b| {
            b.iter(|| {
                local_fit(
                    model.as_ref(),
                    &data.curves,
                    &space,
                    &w,
                    black_box(&displaced),
                    "",
                    &settings,
                )
            })
        });
        g.bench_function(format!("fit_procedure_{stem}_guess"), |b| {
            b.iter(|| run_fit(black_box(&cfg).calibration(&data).unwrap(), &data).unwrap())
        });
    }
    // Where a joint evaluation's time goes: eq. 8's residuals of the joint model at its
    // optimum against those of the model without laws at each temperature's constants there
    // (the same simulations: the laws themselves cost one exp per constant and simulation).
    let (cfg, data) = resolved("cmv-joint.toml", false);
    let model = cfg.build_model().unwrap();
    let settings = FitSettings::from_config(&cfg);
    let x = cfg.starts_all_given().unwrap();
    let obj = Objective::new(
        model.as_ref(),
        &data.curves,
        vec![1.0; data.curves.len()],
        settings.objective(),
    );
    let mut r = vec![0.0; obj.n_residuals()];
    g.bench_function("residuals_cmv-joint_at_its_optimum", |b| {
        b.iter(|| obj.residuals(black_box(&x), &mut r).unwrap())
    });
    let plain = build("khd", &[]).unwrap();
    for t in [560.0, 590.0] {
        let curves: Vec<Curve> = data
            .curves
            .iter()
            .filter(|c| c.temperature_c == t)
            .cloned()
            .collect();
        let at = model.constants_at(&x, t);
        let o = Objective::new(plain.as_ref(), &curves, vec![1.0; 3], settings.objective());
        let mut r = vec![0.0; o.n_residuals()];
        g.bench_function(
            format!("residuals_{t}C_without_laws_at_those_constants"),
            |b| b.iter(|| o.residuals(black_box(&at), &mut r).unwrap()),
        );
    }
    g.finish();

    use LawKind::*;
    let model = with_laws(
        build("khd", &[]).unwrap(),
        &[Arrhenius, Linear, Constant, Constant, Arrhenius, Linear],
        575.0,
    );
    let truth = [
        1.2e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0, 350.0, -2e-4, 250.0, -0.01,
    ];
    let curves = synthetic(model.as_ref(), &truth);
    let space = ParamSpace::new(
        vec![1e-11, 0.05, 0.2, 1e3, 1e-7, 1.5, 100.0, -2e-3, 100.0, -0.05],
        vec![1e-7, 0.3, 0.9, 1e6, 1e-3, 10.0, 600.0, 2e-3, 600.0, 0.05],
        vec![
            Scale::Log,
            Scale::Linear,
            Scale::Linear,
            Scale::Log,
            Scale::Log,
            Scale::Linear,
            Scale::Linear,
            Scale::Linear,
            Scale::Linear,
            Scale::Linear,
        ],
    );
    // A start 0.1 away from the truth in every scaled coordinate of the model's constants.
    let mut start = truth.to_vec();
    let u: Vec<f64> = space
        .to_unit(&truth)
        .iter()
        .enumerate()
        .map(|(j, u)| {
            if j < 6 && j % 2 == 0 {
                u + 0.1
            } else if j < 6 {
                u - 0.1
            } else {
                *u
            }
        })
        .collect();
    space.from_unit(&u, &mut start);
    let (cfg, _) = resolved("560C.toml", false);
    let settings = FitSettings::from_config(&cfg);
    let held = {
        let mut s = space.clone();
        for (j, &v) in truth.iter().enumerate().skip(6) {
            s.hold(j, v);
        }
        s
    };
    let w = vec![1.0; curves.len()];
    for (label, sp) in [("6", &held), ("10", &space)] {
        let f = local_fit(model.as_ref(), &curves, sp, &w, &start, "", &settings);
        eprintln!(
            "{label} free constants: {} iterations, {} evaluations, objective {:e}, {:?}",
            f.lm.iterations, f.lm.evaluations, f.eval.objective, f.lm.termination
        );
    }
    let mut g = c.benchmark_group("constants");
    g.sample_size(10);
    g.bench_function("local_fit_6_free", |b| {
        b.iter(|| {
            local_fit(
                model.as_ref(),
                &curves,
                &held,
                &w,
                black_box(&start),
                "",
                &settings,
            )
        })
    });
    g.bench_function("local_fit_10_free", |b| {
        b.iter(|| {
            local_fit(
                model.as_ref(),
                &curves,
                &space,
                &w,
                black_box(&start),
                "",
                &settings,
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
