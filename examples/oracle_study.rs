//! Both oracles of generated sets from the specimen world, without diagnosing them:
//! `cargo run --release --example oracle_study -- OUT SCENARIO FIRST_SEED N` generates sets
//! FIRST_SEED … FIRST_SEED+N−1 of SCENARIO (a catalogued effect) into OUT and prints, per set,
//! the oracle λ with the specimens' factors known (`battery::oracle_lambda`) and unknown
//! (`battery::oracle_lambda_scatter`), then how many sets each calls detectable (λ ≥ 25).
//! With a fifth argument K, it then diagnoses (`battery::run_one_diagnosed`, all cores) the
//! first K sets, in seed order, that are detectable with the factors unknown, printing one
//! line per set as it finishes: the power of `diagnose` on sets of the power table.
use rayon::prelude::*;

/// Seed, effect size, λ with the factors known, λ with them unknown, curves.
type Row = (u64, f64, f64, f64, usize);

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 4 && a.len() != 5 {
        eprintln!("usage: oracle_study OUT SCENARIO FIRST_SEED N [K]");
        std::process::exit(2);
    }
    let out = std::path::PathBuf::from(&a[0]);
    let scenario = a[1].clone();
    let first: u64 = a[2].parse().expect("FIRST_SEED");
    let n: u64 = a[3].parse().expect("N");
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
        let (r, _) = creepfit::battery::run_one_diagnosed(
            &out.join("diagnosed"),
            &scenario,
            *s,
            creepfit::synth::World::Specimens,
        );
        done += 1;
        named += usize::from(r.named_correctly());
        println!(
            "diagnosed {s} {scenario}: {} (λ known {known:.1}, unknown {unknown:.1}; {:.0} s)",
            r.error.clone().unwrap_or_else(|| r.outcome()),
            r.wall_s
        );
        std::io::stdout().flush().ok();
    }
    if k > 0 {
        println!("# named correctly: {named} of {done} diagnosed detectable sets");
    }
}
