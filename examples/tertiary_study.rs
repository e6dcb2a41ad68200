//! Ductile tertiary creep on real Alloy 617 (README, "Ductile tertiary creep"): at each
//! temperature of `configs/alloy617-<T>C.toml`, the base KHD model and the base with
//! `strain_softening`, `rupture_damage`, `constant_load` and their combinations, each fitted
//! by maximum likelihood (the error model of `diagnose`, curves reduced to 60 points as
//! `[diagnose] max_points = 60` does) from the initial guess, 32 Latin-hypercube starts (seed 1)
//! and — so that a model is never worse than one it nests — the optimum of every fitted model
//! it contains with the added constants switched off (φ1 at 1, 2 and 4 where φ0 = 0) and
//! each added constant at 1/4, 1/2, 3/4 of its range. Prints per model: −2 ln L, AIC, the
//! lifetime errors, measured against predicted rupture strains, the last-point strain error,
//! and writes a plot of measured and fitted curves per model into OUT.
//!
//! Usage: cargo run --release --example tertiary_study -- OUT [T ...]
use std::path::Path;

use creepfit::config::RunConfig;
use creepfit::data::Curve;
use creepfit::fit::FitSettings;
use creepfit::likelihood::{ml_fit, MlFit, MlOptions};
use creepfit::model::objective::ParamSpace;
use creepfit::model::{build, ext, Load, Model};
use creepfit::report::plot::{plot_creep_curves, CurvePlot};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// The models, each after every model it nests.
const MODELS: &[&[&str]] = &[
    &[],
    &["constant_load"],
    &["strain_softening"],
    &["rupture_damage"],
    &["strain_softening", "rupture_damage"],
    &["constant_load", "strain_softening"],
    &["constant_load", "rupture_damage"],
    &["constant_load", "strain_softening", "rupture_damage"],
];

fn space_of(model: &dyn Model, base: &ParamSpace) -> ParamSpace {
    let (mut lb, mut ub, mut sc) = (base.lb.clone(), base.ub.clone(), base.scale.clone());
    for c in &model.constants()[6..] {
        lb.push(c.lb);
        ub.push(c.ub);
        sc.push(c.scale);
    }
    ParamSpace::new(lb, ub, sc)
}

/// Starts from the optimum `x` of `sub`: this model's constants by name, the added ones
/// switched off (φ1 at 1, 2, 4), then each added one at 1/4, 1/2, 3/4 of its range.
fn nested(model: &dyn Model, space: &ParamSpace, sub: &dyn Model, x: &[f64]) -> Vec<Vec<f64>> {
    let names: Vec<&str> = model.constants().iter().map(|c| c.name).collect();
    let subn: Vec<&str> = sub.constants().iter().map(|c| c.name).collect();
    let added: Vec<usize> = (0..names.len())
        .filter(|j| !subn.contains(&names[*j]))
        .collect();
    let mut off: Vec<f64> = names
        .iter()
        .enumerate()
        .map(|(j, n)| match subn.iter().position(|m| m == n) {
            Some(i) => x[i],
            None => ext::off_value(n, space.lb[j], space.ub[j]).unwrap_or(2.0),
        })
        .collect();
    let mut out = Vec::new();
    match names.iter().position(|n| *n == "phi1") {
        Some(j) if added.contains(&j) => {
            for v in [1.0, 2.0, 4.0] {
                off[j] = v;
                out.push(off.clone());
            }
        }
        _ => out.push(off.clone()),
    }
    for &j in &added {
        for u in [0.25, 0.5, 0.75] {
            let mut s = off.clone();
            s[j] = space.from_unit_one(j, u);
            out.push(s);
        }
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = Path::new(&args[1]);
    let temps: Vec<u32> = if args.len() > 2 {
        args[2..].iter().map(|a| a.parse().unwrap()).collect()
    } else {
        vec![750, 850, 900, 950]
    };
    for t in temps {
        let cfg = RunConfig::load(Path::new(&format!("configs/alloy617-{t}C.toml"))).unwrap();
        let data = cfg.load_data().unwrap();
        let curves: Vec<Curve> = data
            .curves
            .iter()
            .map(|c| creepfit::data::binned(c, 60))
            .collect();
        let settings = FitSettings::from_config(&cfg);
        let base_space = cfg.space();
        let mut fitted: Vec<(Box<dyn Model>, MlFit)> = Vec::new();
        for exts in MODELS {
            let names: Vec<String> = exts.iter().map(|s| s.to_string()).collect();
            let model = build("khd", &names).unwrap();
            let space = space_of(model.as_ref(), &base_space);
            let guess = creepfit::model::guess::initial_guess(
                model.as_ref(),
                &curves,
                &space,
                settings.omega_f,
                &settings.ode,
            );
            let mut fresh = vec![guess.params];
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            for u in creepfit::sampling::latin_hypercube(32, space.len(), &mut rng) {
                let mut x = vec![0.0; space.len()];
                space.from_unit(&u, &mut x);
                fresh.push(x);
            }
            let mut warm = Vec::new();
            for (sub, f) in &fitted {
                let subn: Vec<&str> = sub.constants().iter().map(|c| c.name).collect();
                let nests = subn
                    .iter()
                    .all(|n| model.constants().iter().any(|c| c.name == *n));
                if nests && f.ok() {
                    warm.extend(nested(model.as_ref(), &space, sub.as_ref(), &f.params));
                }
            }
            let jobs: Vec<(Vec<f64>, bool)> = fresh
                .iter()
                .flat_map(|x| [(x.clone(), true), (x.clone(), false)])
                .chain(warm.into_iter().map(|x| (x, false)))
                .collect();
            let fits: Vec<MlFit> = jobs
                .par_iter()
                .map(|(x, white_first)| {
                    let opts = MlOptions {
                        white_first: *white_first,
                        ..MlOptions::default()
                    };
                    ml_fit(model.as_ref(), &curves, &space, x, &settings, &opts)
                })
                .collect();
            let n_failed = fits.iter().filter(|f| !f.ok()).count();
            let best = fits
                .into_iter()
                .filter(|f| f.ok())
                .reduce(|a, b| if b.neg2ll < a.neg2ll { b } else { a })
                .expect("some fit succeeded");
            report(t, model.as_ref(), &best, &curves, &settings, n_failed, out);
            fitted.push((model, best));
        }
    }
}

/// One line of numbers per model and its plot.
fn report(
    t: u32,
    model: &dyn Model,
    f: &MlFit,
    curves: &[Curve],
    settings: &FitSettings,
    failed: usize,
    out: &Path,
) {
    let k = f.params.len();
    let (mut life, mut ef_pred, mut ef_meas, mut last) = (vec![], vec![], vec![], vec![]);
    let mut plots = Vec::new();
    for c in curves {
        let load = Load::of_curve(c, settings.omega_f);
        let r = model.simulate(&f.params, &load, &[], &mut [], &settings.ode);
        let t_meas = c.rupture_time_h.unwrap_or(f64::NAN);
        life.push(100.0 * (r.t_end - t_meas) / t_meas);
        ef_pred.push(100.0 * r.strain_end);
        ef_meas.push(100.0 * c.rupture_strain);
        // Predicted − measured strain at the last measured time, % of the measured one
        // (NaN where the prediction ruptured before it).
        let tl = *c.times_h.last().unwrap();
        let mut e = [f64::NAN];
        let rl = model.simulate(&f.params, &load, &[tl], &mut e, &settings.ode);
        let el = *c.strains.last().unwrap();
        last.push(if rl.n_out == 1 {
            100.0 * (e[0] - el) / el
        } else {
            f64::NAN
        });
        let grid: Vec<f64> = (0..=200).map(|i| r.t_end * i as f64 / 200.0).collect();
        let mut s = vec![f64::NAN; grid.len()];
        let rg = model.simulate(&f.params, &load, &grid, &mut s, &settings.ode);
        plots.push(CurvePlot {
            id: creepfit::report::plot::CurveId::of(c),
            measured: c
                .times_h
                .iter()
                .zip(&c.strains)
                .map(|(a, b)| (*a, 100.0 * b))
                .collect(),
            predicted: grid[..rg.n_out]
                .iter()
                .zip(&s)
                .map(|(a, b)| (*a, 100.0 * b))
                .collect(),
        });
    }
    let mean_abs = |v: &[f64]| {
        let ok: Vec<f64> = v
            .iter()
            .filter(|x| x.is_finite())
            .map(|x| x.abs())
            .collect();
        ok.iter().sum::<f64>() / ok.len().max(1) as f64
    };
    let fmt = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.1}"))
            .collect::<Vec<_>>()
            .join(" / ")
    };
    let consts: Vec<String> = model
        .constants()
        .iter()
        .zip(&f.params)
        .map(|(c, v)| format!("{}={v:.4e}", c.name))
        .collect();
    println!(
        "{t} | {} | k {k} | -2lnL {:.2} | AIC {:.2} | mean|life| {:.1} | mean|last| {:.1} | life {} | ef meas {} | ef pred {} | last {} | {} | failed {failed} | {:?}",
        model.name(),
        f.neg2ll,
        f.neg2ll + 2.0 * k as f64,
        mean_abs(&life),
        mean_abs(&last),
        fmt(&life),
        fmt(&ef_meas),
        fmt(&ef_pred),
        fmt(&last),
        consts.join(" "),
        f.termination,
    );
    std::fs::create_dir_all(out).unwrap();
    plot_creep_curves(
        &out.join(format!("{t}C-{}.png", model.name())),
        &format!(
            "Alloy 617 {t} °C, {}: measured (points) and fitted (lines)",
            model.name()
        ),
        &plots,
    )
    .unwrap();
}
