//! Both oracles of generated sets from the specimen world, without diagnosing them:
//! `cargo run --release --example oracle_study -- OUT SCENARIO FIRST_SEED N` generates sets
//! FIRST_SEED … FIRST_SEED+N−1 of SCENARIO (a catalogued effect) into OUT and prints, per set,
//! the oracle λ with the specimens' factors known (`battery::oracle_lambda`) and unknown
//! (`battery::oracle_lambda_scatter`), then how many sets each calls detectable (λ ≥ 25).
//! With a fifth argument K, it then diagnoses (`battery::run_one_diagnosed`, all cores) the
//! first K sets, in seed order, that are detectable with the factors unknown, printing one
//! line per set as it finishes: the power of `diagnose` on sets of the power table. Beside its
//! verdict, the likelihood ratio of the set's measured data at the true error model and the
//! true scatter (`LR at the truth's nuisances`): where that is large and `diagnose` misses,
//! the loss is in estimating the error model and the scatter, not in the data. With `ratio`
//! instead of K: that ratio alone, of sets diagnosed before.
use rayon::prelude::*;

/// Seed, effect size, λ with the factors known, λ with them unknown, curves.
type Row = (u64, f64, f64, f64, usize);

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 4 && a.len() != 5 {
        eprintln!("usage: oracle_study OUT SCENARIO FIRST_SEED N [K | ratio]");
        std::process::exit(2);
    }
    let out = std::path::PathBuf::from(&a[0]);
    let scenario = a[1].clone();
    let first: u64 = a[2].parse().expect("FIRST_SEED");
    let n: u64 = a[3].parse().expect("N");
    if a.get(4).map(String::as_str) == Some("ratio") {
        // Only the data's ratio of sets diagnosed before (OUT/diagnosed/sets/set-<seed>).
        for s in first..first + n {
            let (lr, lr_est) = data_ratio(&out.join("diagnosed"), &scenario, s);
            println!(
                "{s} {scenario} LR at the truth's nuisances {lr:.2}, with the error model estimated {lr_est:.2}"
            );
        }
        return;
    }
    let k: usize = a.get(4).map_or(0, |v| v.parse().expect("K"));
    let rows: Vec<Row> = (first..first + n)
        .into_par_iter()
        .map(|s| {
            let name = format!("set-{s}");
            let set = creepfit::synth::generate_in(
                &name,
                &scenario,
                None,
                s,
                creepfit::synth::World::Specimens,
            )
            .expect("generate");
            let dir = out.join(&name);
            creepfit::synth::write_set(&set, &dir).expect("write");
            let cfg = creepfit::config::RunConfig::load(&dir.join("config.toml")).expect("config");
            let known = creepfit::battery::oracle_lambda(&cfg, &set.truth);
            let unknown =
                creepfit::battery::oracle_lambda_scatter(&cfg, &set.truth).unwrap_or(f64::NAN);
            (
                s,
                set.truth.effect.size(),
                known,
                unknown,
                set.truth.stresses.len(),
            )
        })
        .collect();
    println!("seed scenario size curves lambda_known_factors lambda_unknown_factors");
    for (s, size, k, u, c) in &rows {
        println!("{s} {scenario} {size:.4e} {c} {k:.2} {u:.2}");
    }
    let det = |f: &dyn Fn(&Row) -> f64| rows.iter().filter(|r| f(r) >= 25.0).count();
    println!(
        "# detectable (λ ≥ 25): {} of {} with the factors known, {} with them unknown",
        det(&|r| r.2),
        rows.len(),
        det(&|r| r.3)
    );
    use std::io::Write;
    let mut named = 0;
    let mut done = 0;
    for (s, _, known, unknown, _) in rows.iter().filter(|r| r.3 >= 25.0).take(k) {
        let (r, d) = creepfit::battery::run_one_diagnosed(
            &out.join("diagnosed"),
            &scenario,
            *s,
            creepfit::synth::World::Specimens,
        );
        done += 1;
        named += usize::from(r.named_correctly());
        let (lr_data, lr_est) = data_ratio(&out.join("diagnosed"), &scenario, *s);
        let lr_diag = d
            .as_ref()
            .and_then(|d| d.candidates.iter().find(|c| c.name == scenario))
            .map_or(f64::NAN, |c| c.lr);
        println!(
            "diagnosed {s} {scenario}: {} (λ known {known:.1}, unknown {unknown:.1}; LR at the truth's nuisances {lr_data:.1}, error model estimated {lr_est:.1}, in diagnose {lr_diag:.1}; {:.0} s)",
            r.error.clone().unwrap_or_else(|| r.outcome()),
            r.wall_s
        );
        std::io::stdout().flush().ok();
    }
    if k > 0 {
        println!("# named correctly: {named} of {done} diagnosed detectable sets");
    }
}

/// The likelihood ratio of set `seed`'s measured data (as `diagnose` loads them from
/// `dir/sets/set-<seed>/`) between the hierarchical base model and the generating extension at
/// the true error model and the true scatter, the specimens' factors free; and the same with
/// the error model estimated with the constants (the scatter still the truth's).
fn data_ratio(dir: &std::path::Path, scenario: &str, seed: u64) -> (f64, f64) {
    let name = format!("set-{seed}");
    let Ok(set) = creepfit::synth::generate_in(
        &name,
        scenario,
        None,
        seed,
        creepfit::synth::World::Specimens,
    ) else {
        return (f64::NAN, f64::NAN);
    };
    let t = &set.truth;
    let Some(sp) = t.specimens.as_ref() else {
        return (f64::NAN, f64::NAN);
    };
    let cfg = creepfit::config::RunConfig::load(&dir.join("sets").join(&name).join("config.toml"))
        .expect("config");
    let data = cfg.load_data().expect("data");
    // The truth's curve of each loaded curve, by specimen label.
    let idx: Vec<usize> = data
        .curves
        .iter()
        .map(|c| {
            sp.labels
                .iter()
                .position(|l| Some(l.as_str()) == c.specimen.as_deref())
                .expect("a generated specimen")
        })
        .collect();
    let truth_noise = creepfit::battery::true_noise(t);
    let noise = creepfit::errmodel::ErrorModel {
        strain: idx.iter().map(|&i| truth_noise.strain[i]).collect(),
        lifetime_sd: truth_noise.lifetime_sd,
    };
    // The reading error's growth of each loaded curve: the truth's factor per reading where
    // the curve holds every generated reading, else from its measured strains.
    let truth_scale = creepfit::battery::true_reading_scale(t);
    let scale: Option<Vec<Vec<f64>>> = truth_scale.as_ref().map(|w| {
        data.curves
            .iter()
            .zip(&idx)
            .map(|(c, &i)| {
                if w[i].len() == c.strains.len() {
                    w[i].clone()
                } else {
                    let top = t.true_strain[i].iter().copied().fold(0.0_f64, f64::max);
                    let eps_f = sp.growth_strain(i, top);
                    c.strains
                        .iter()
                        .map(|e| sp.reading_factor(e.max(0.0), eps_f))
                        .collect()
                }
            })
            .collect()
    });
    let mut kinds = vec![(creepfit::likelihood::EffectKind::Rate, sp.rate_sd)];
    let mut eta: Vec<f64> = idx.iter().map(|&i| sp.rate_effects[i]).collect();
    if sp.ductility_sd > 0.0 {
        kinds.push((creepfit::likelihood::EffectKind::Ductility, sp.ductility_sd));
        eta.extend(idx.iter().map(|&i| sp.ductility_effects[i]));
    }
    let setup = cfg.diagnose_setup().expect("setup");
    let mut alt_truth = t.constants.clone();
    alt_truth.extend(t.effect.true_extension().1);
    let fit = |v: &creepfit::config::ModelVariant, start: &Vec<f64>, profile: Option<f64>| {
        let starts = creepfit::battery::oracle_starts(
            v.model.as_ref(),
            &v.space,
            &data.curves,
            &setup.settings,
            start.clone(),
            seed,
        );
        creepfit::likelihood::min_penalised(
            v.model.as_ref(),
            &data.curves,
            &v.space,
            &starts,
            &setup.settings,
            &noise,
            scale.as_deref(),
            &kinds,
            &eta,
            profile,
        )
        .map_or(f64::NAN, |b| b.0)
    };
    let Some(alt) = setup.variants.iter().find(|v| v.name == scenario) else {
        return (f64::NAN, f64::NAN);
    };
    let floor = creepfit::errmodel::DEFAULT_LIFETIME_SD_FLOOR;
    (
        fit(&setup.variants[0], &t.constants, None) - fit(alt, &alt_truth, None),
        fit(&setup.variants[0], &t.constants, Some(floor)) - fit(alt, &alt_truth, Some(floor)),
    )
}
