//! Measured coverage of the intervals of `creepfit profile` on synthetic data sets with known
//! truth (README, "How sure"): `cargo run --release --example coverage -- OUT FIRST_SEED N
//! [--calibrate B] [--bootstrap B] [--starts N] [--threads T] [--band-points N] [--world
//! specimens]` (the band at 9 times by default, 0: none). Resumes an
//! interrupted run in OUT; writes OUT/coverage.md (the table) and OUT/coverage.json. With
//! `--world specimens` the sets carry specimen scatter and replicates
//! ([`creepfit::synth::World::Specimens`]) and every fit integrates the specimens' factors out.
use std::path::PathBuf;

use creepfit::uncertainty::coverage::{run_coverage, table, table_md, CoverageSettings};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: coverage OUT FIRST_SEED N [--calibrate B] [--bootstrap B] [--starts N] [--threads T] [--band-points N] [--world specimens]";
    if args.len() < 3 {
        eprintln!("{usage}");
        std::process::exit(2);
    }
    let out = PathBuf::from(&args[0]);
    let first: u64 = args[1].parse().expect("FIRST_SEED");
    let n: usize = args[2].parse().expect("N");
    let mut s = CoverageSettings::default();
    let mut threads = None;
    let mut i = 3;
    while i + 1 < args.len() {
        if args[i] == "--world" {
            s.world = match args[i + 1].as_str() {
                "specimens" => creepfit::synth::World::Specimens,
                "identical" => creepfit::synth::World::Identical,
                _ => {
                    eprintln!("{usage}");
                    std::process::exit(2);
                }
            };
            i += 2;
            continue;
        }
        let v: usize = args[i + 1].parse().expect("a number");
        match args[i].as_str() {
            "--calibrate" => s.calibrate = v,
            "--bootstrap" => s.bootstrap = v,
            "--starts" => s.starts = v,
            "--threads" => threads = Some(v),
            "--band-points" => s.band_points = v,
            _ => {
                eprintln!("{usage}");
                std::process::exit(2);
            }
        }
        i += 2;
    }
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .unwrap();
    }
    let t0 = std::time::Instant::now();
    let results = run_coverage(&out, first, n, &s, true).expect("coverage run");
    let rows = table(&results);
    let errors = results.iter().filter(|r| r.error.is_some()).count();
    let mut md = format!(
        "Coverage on {} synthetic sets (seeds {}–{}, scenario none), settings {:?}; {} set(s) failed.\n\n",
        results.len(),
        first,
        first + n as u64 - 1,
        s,
        errors
    );
    md += &table_md(&rows);
    let band = creepfit::uncertainty::coverage::band_md(&results);
    if !band.is_empty() {
        md += "\nThe 95 % strain band at the untested stress, pointwise:\n\n";
        md += &band;
    }
    for (label, get) in [
        (
            "constants",
            (|r| r.factor) as fn(&creepfit::uncertainty::coverage::SetCoverage) -> f64,
        ),
        ("predictions", |r| r.prediction_factor),
    ] {
        let mut f: Vec<f64> = results.iter().map(get).filter(|f| f.is_finite()).collect();
        if f.is_empty() {
            continue;
        }
        f.sort_by(|a, b| a.total_cmp(b));
        md += &format!(
            "\nCalibration factor of the {label}: median {:.3}, 10 % {:.3}, 90 % {:.3}.\n",
            f[f.len() / 2],
            f[f.len() / 10],
            f[(9 * f.len()) / 10]
        );
    }
    let wall: f64 = results
        .iter()
        .map(|r| r.wall_s)
        .filter(|w| w.is_finite())
        .sum();
    md += &format!(
        "Sum of per-set wall times {:.0} s; this invocation {:.0} s.\n",
        wall,
        t0.elapsed().as_secs_f64()
    );
    std::fs::write(out.join("coverage.md"), &md).unwrap();
    std::fs::write(
        out.join("coverage.json"),
        serde_json::to_string_pretty(&rows).unwrap(),
    )
    .unwrap();
    print!("{md}");
}
