//! Re-run chosen sets of a battery (development aid): `cargo run --release --example
//! battery_subset -- OUT INDEX [--oracle] SEED...` runs `battery::run_one(OUT, INDEX, SEED)`
//! for each seed (INDEX picks the scenario, as set INDEX of a battery) and prints one JSON
//! line per set; with `--oracle`, only the oracle's λ of each set (no diagnosis).
use rayon::prelude::*;

fn main() {
    let mut a: Vec<String> = std::env::args().skip(1).collect();
    let oracle = a.iter().any(|s| s == "--oracle");
    a.retain(|s| s != "--oracle");
    if a.len() < 3 {
        eprintln!("usage: battery_subset OUT INDEX [--oracle] SEED...");
        std::process::exit(2);
    }
    let out = std::path::PathBuf::from(&a[0]);
    let index: usize = a[1].parse().expect("INDEX");
    let seeds: Vec<u64> = a[2..].iter().map(|s| s.parse().expect("SEED")).collect();
    let scenario = creepfit::synth::scenario_of(index);
    let lines: Vec<String> = seeds
        .par_iter()
        .map(|&s| {
            if oracle {
                let name = format!("set-{s}");
                let set = creepfit::synth::generate(&name, scenario, s).expect("generate");
                let dir = out.join(&name);
                creepfit::synth::write_set(&set, &dir).expect("write");
                let cfg =
                    creepfit::config::RunConfig::load(&dir.join("config.toml")).expect("config");
                let l = creepfit::battery::oracle_lambda(&cfg, &set.truth);
                format!("{s} {scenario} lambda {l:.2}")
            } else {
                serde_json::to_string(&creepfit::battery::run_one(
                    &out,
                    index,
                    s,
                    creepfit::synth::World::Identical,
                ))
                .unwrap()
            }
        })
        .collect();
    for l in lines {
        println!("{l}");
    }
}
