//! Specimen scatter on generated data (development aid): `cargo run --release --example
//! specimen_study -- OUT SEED...` generates a `specimens`-world set of the `none` scenario per
//! seed, fits it by maximum likelihood with and without specimen effects (curves reduced to
//! `[diagnose] max_points`), and prints per set the true and estimated scatter, −2 ln L both
//! ways and the time.
use std::time::Instant;

use creepfit::config::RunConfig;
use creepfit::fit::FitSettings;
use creepfit::likelihood::{ml_fit, MlOptions, SpecimenOptions};
use creepfit::synth::{generate_in, write_set, World};
use rayon::prelude::*;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let out = std::path::PathBuf::from(&a[0]);
    let scenario = std::env::var("SCENARIO").unwrap_or_else(|_| "none".into());
    let seeds: Vec<u64> = a[1..].iter().map(|s| s.parse().expect("SEED")).collect();
    let lines: Vec<String> = seeds
        .par_iter()
        .map(|&s| {
            let name = format!("set-{s}");
            let set = generate_in(&name, &scenario, None, s, World::Specimens).expect("generate");
            let dir = out.join(&name);
            write_set(&set, &dir).expect("write");
            let cfg = RunConfig::load(&dir.join("config.toml")).expect("config");
            let data = cfg.load_data().expect("data");
            let curves: Vec<_> = data
                .curves
                .iter()
                .map(|c| creepfit::data::binned(c, cfg.diagnose.max_points))
                .collect();
            let model = cfg.build_model().expect("model");
            let space = cfg.space();
            let settings = FitSettings::from_config(&cfg);
            let start = set.truth.constants.clone();
            let t0 = Instant::now();
            let plain = ml_fit(
                model.as_ref(),
                &curves,
                &space,
                &start,
                &settings,
                &MlOptions::default(),
            );
            let t1 = t0.elapsed().as_secs_f64();
            let mut hier = ml_fit(
                model.as_ref(),
                &curves,
                &space,
                &start,
                &settings,
                &MlOptions {
                    specimen: SpecimenOptions::BOTH,
                    ..MlOptions::default()
                },
            );
            let t2 = t0.elapsed().as_secs_f64() - t1;
            creepfit::likelihood::scatter_intervals(
                &mut hier,
                model.as_ref(),
                &curves,
                &space,
                &settings,
                &MlOptions {
                    specimen: SpecimenOptions::BOTH,
                    ..MlOptions::default()
                },
            );
            // Warm refits from the optimum, both ways.
            let direct = MlOptions { white_first: false, ..MlOptions::default() };
            let t3 = Instant::now();
            let pw = ml_fit(model.as_ref(), &curves, &space, &plain.params, &settings, &direct);
            let tp = t3.elapsed().as_secs_f64();
            let hw = creepfit::likelihood::ml_fit_from(
                model.as_ref(), &curves, &space, &hier.params,
                hier.specimen.as_ref().map(creepfit::likelihood::EffectStart::from).as_ref(),
                &settings,
                &MlOptions { specimen: SpecimenOptions::BOTH, ..direct },
            );
            let th = t3.elapsed().as_secs_f64() - tp;
            eprintln!("{s} warm plain {} it {:.3}s {:.3} | warm hier {} it {:.3}s {:.3}", pw.iterations, tp, pw.neg2ll, hw.iterations, th, hw.neg2ll);
            let sp = set.truth.specimens.as_ref().unwrap();
            let (est, eff) = match &hier.specimen {
                Some(f) => (
                    format!(
                        "{:?} {:?} [{:?}, {:?}] ({} it)",
                        f.kinds,
                        f.scatter.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
                        f.scatter_lo95.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
                        f.scatter_hi95.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
                        hier.iterations
                    ),
                    format!(
                        "eta {:?} true {:?}",
                        f.effects[0].iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>(),
                        sp.rate_effects.iter().map(|v| (v * 1e3).round() / 1e3).collect::<Vec<_>>()
                    ),
                ),
                None => ("none".into(), String::new()),
            };
            format!(
                "{s} n={} true rate {:.3} duct {:.3} | est {est} | -2lnL plain {:.1} hier {:.1} | {:.1}s {:.1}s\n   {eff}",
                curves.len(),
                sp.rate_sd,
                sp.ductility_sd,
                plain.neg2ll,
                hier.neg2ll,
                t1,
                t2
            )
        })
        .collect();
    for l in lines {
        println!("{l}");
    }
}
