//! The joint `diagnose` on generated two-temperature data: N sets (seeds SEED..SEED+N) of
//! [`creepfit::synth::two_temperature_set`]; with EFFECT = name:value the truth has that
//! extension (`loading_strain:EL`, `stress_ductility:nu`, `dislocation_damage:Cd`). Prints the
//! verdict and cause of each set, then the counts.
//!
//! Usage: cargo run --release --example joint_battery -- N SEED [EFFECT]
use std::path::Path;

use creepfit::config::RunConfig;
use creepfit::data::Dataset;
use creepfit::diagnose::diagnose;
use creepfit::synth::{two_temperature_set, TWO_TEMPERATURE_CONFIG};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args[1].parse()?;
    let seed0: u64 = args[2].parse()?;
    let effect: Option<(String, f64)> = args.get(3).map(|e| {
        let (k, v) = e.split_once(':').expect("EFFECT is name:value");
        (k.to_string(), v.parse().expect("a number"))
    });
    let mut counts = std::collections::BTreeMap::<String, usize>::new();
    for seed in seed0..seed0 + n {
        let Some(curves) =
            two_temperature_set(seed, effect.as_ref().map(|(k, v)| (k.as_str(), *v)))?
        else {
            println!("{seed} skipped: a curve does not rupture");
            continue;
        };
        let data = Dataset::of_curves(curves);
        let cfg = RunConfig::from_str(TWO_TEMPERATURE_CONFIG, Path::new("joint-battery.toml"))?
            .with_data(&data);
        let t0 = std::time::Instant::now();
        match diagnose(&cfg.diagnose_setup()?, &data, &cfg.diagnose) {
            Ok(d) => {
                let v = format!("{:?} {}", d.verdict, d.cause.clone().unwrap_or_default());
                println!("{seed} {v} ({:.1} s)", t0.elapsed().as_secs_f64());
                *counts.entry(v).or_default() += 1;
            }
            Err(e) => {
                println!("{seed} failed: {e}");
                *counts.entry("failed".into()).or_default() += 1;
            }
        }
    }
    println!("{counts:?}");
    Ok(())
}
