//! The reading error's growth with strain, fitted against the truth (development aid):
//! `cargo run --release --example growth_study -- OUT SEED...` generates a `specimens`-world
//! set of the `none` scenario per seed, fits the base model with both kinds of specimen
//! effects (curves reduced to `[diagnose] max_points`, as `diagnose` does) and prints per set:
//! the generator's growth g (per unit of ε/ε_f, which a plot edge's cut makes larger than the
//! estimator's unit, strain as a fraction of the curve's largest), the growth estimated from
//! the true reading errors (data − truth, all readings, the estimator's units), the same on the
//! binned curves (`oracle_binned`: what the fit's residuals estimate), from the fit's residuals
//! by maximum likelihood (plain) and the one `diagnose` draws (restricted). `MAX_POINTS=N`
//! bins to N points instead of the configuration's.
use creepfit::config::RunConfig;
use creepfit::errmodel::{strain_fractions, GrowingError};
use creepfit::fit::FitSettings;
use creepfit::likelihood::{ml_fit, MlOptions, SpecimenOptions};
use creepfit::synth::{generate_in, write_set, World};
use rayon::prelude::*;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let out = std::path::PathBuf::from(&a[0]);
    let seeds: Vec<u64> = a[1..].iter().map(|s| s.parse().expect("SEED")).collect();
    let lines: Vec<String> = seeds
        .par_iter()
        .map(|&s| {
            let name = format!("set-{s}");
            let set = generate_in(&name, "none", None, s, World::Specimens).expect("generate");
            let dir = out.join(&name);
            write_set(&set, &dir).expect("write");
            let cfg = RunConfig::load(&dir.join("config.toml")).expect("config");
            let data = cfg.load_data().expect("data");
            let t = &set.truth;
            let g = t.specimens.as_ref().expect("specimens").error_growth;
            // The true reading errors, in the set's curve order (one curve per test, the
            // truth's order: matched by the first reading's time and the curve's length).
            let max_points: usize = std::env::var("MAX_POINTS")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(cfg.diagnose.max_points);
            let mut e_true = vec![];
            let mut x_true = vec![];
            let (mut e_binned, mut x_binned) = (vec![], vec![]);
            for c in &data.curves {
                let k = (0..t.times_h.len())
                    .find(|&k| {
                        t.times_h[k].len() == c.times_h.len()
                            && (t.times_h[k].last().unwrap() - c.times_h.last().unwrap()).abs()
                                <= 1e-6 * c.times_h.last().unwrap()
                    })
                    .expect("curve in truth");
                let e: Vec<f64> = c
                    .strains
                    .iter()
                    .zip(&t.true_strain[k])
                    .map(|(m, tr)| tr - m)
                    .collect();
                e_true.push(e);
                x_true.push(strain_fractions(&c.strains));
                // The same on the curve `diagnose` sees: binning is linear in the readings,
                // so the binned curve's errors are the binned truth minus the binned data.
                let b = creepfit::data::binned(c, max_points);
                let bt = creepfit::data::binned(
                    &creepfit::data::Curve {
                        strains: t.true_strain[k].clone(),
                        ..c.clone()
                    },
                    max_points,
                );
                e_binned.push(
                    bt.strains
                        .iter()
                        .zip(&b.strains)
                        .map(|(a, m)| a - m)
                        .collect(),
                );
                x_binned.push(strain_fractions(&b.strains));
            }
            let g_oracle = GrowingError::estimate(&e_true, &x_true).growth;
            let g_oracle_binned = GrowingError::estimate(&e_binned, &x_binned).growth;
            let curves: Vec<_> = data
                .curves
                .iter()
                .map(|c| creepfit::data::binned(c, max_points))
                .collect();
            let model = cfg.build_model().expect("model");
            let space = cfg.space();
            let settings = FitSettings::from_config(&cfg);
            let fit = ml_fit(
                model.as_ref(),
                &curves,
                &space,
                &t.constants,
                &settings,
                &MlOptions {
                    specimen: SpecimenOptions::BOTH,
                    ..MlOptions::default()
                },
            );
            let res = fit.residuals.as_ref().expect("fitted");
            let x: Vec<Vec<f64>> = curves
                .iter()
                .map(|c| strain_fractions(&c.strains))
                .collect();
            let g_plain = GrowingError::estimate(&res.strain, &x).growth;
            let g_fit = creepfit::diagnose::bootstrap::reading_error(
                &curves,
                model.as_ref(),
                &space,
                &fit,
                &settings,
            )
            .growth;
            format!(
                "{s} {:?} cut {:?} g {:.3} oracle {:.3} oracle_binned {:.3} plain {:.3} fit {:.3}",
                t.sampling, t.strain_cut, g, g_oracle, g_oracle_binned, g_plain, g_fit
            )
        })
        .collect();
    for l in lines {
        println!("{l}");
    }
}
