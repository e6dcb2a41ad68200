//! Coverage of the specimen scatter's 95 % interval on generated data (issue 20: "the scatter
//! estimate covers its truth in 90–98 % of sets"), on hundreds of sets rather than a
//! battery's few: `cargo run --release --example scatter_coverage -- OUT FIRST_SEED N
//! [SCENARIO [WORLD [KINDS]]]` fits N sets of the `specimens` world (or WORLD: `shapes`;
//! scenario `none` unless given) with [`creepfit::battery::scatter_fit`] — the base model, the
//! specimen effects of the set's configuration (rate and ductility; in `shapes` coarsening
//! too) or KINDS (comma-separated, e.g. `rate,ductility,coarsening`), from
//! the data's initial guess and from the true constants — and writes one JSON line per set
//! and start to OUT/fits.jsonl as each set ends (an interrupted run resumes with the seeds it
//! has not finished), then OUT/summary.md: per start and kind, how often the interval covers
//! the truth (Wilson 95 %) and how often it excludes zero where the truth has no such scatter.
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Mutex;

use creepfit::battery::{coverage_of, scatter_fit, wilson, ScatterFit, ScatterStart};
use rayon::prelude::*;

const STARTS: [(&str, ScatterStart); 2] = [
    ("guess", ScatterStart::Guess),
    ("truth", ScatterStart::Truth),
];

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() < 3 {
        eprintln!("usage: scatter_coverage OUT FIRST_SEED N [SCENARIO [WORLD [KINDS]]]");
        std::process::exit(2);
    }
    let out = PathBuf::from(&a[0]);
    let first: u64 = a[1].parse().expect("FIRST_SEED");
    let n: u64 = a[2].parse().expect("N");
    let scenario = a.get(3).cloned().unwrap_or_else(|| "none".into());
    let world = match a.get(4).map(String::as_str) {
        None | Some("specimens") => creepfit::synth::World::Specimens,
        Some("shapes") => creepfit::synth::World::Shapes,
        Some(w) => {
            eprintln!("WORLD: specimens or shapes, not {w}");
            std::process::exit(2);
        }
    };
    let kinds = a.get(5).map(|k| creepfit::likelihood::SpecimenOptions {
        rate: k.split(',').any(|x| x == "rate"),
        ductility: k.split(',').any(|x| x == "ductility"),
        coarsening: k.split(',').any(|x| x == "coarsening"),
        beyond_trend: false,
    });
    std::fs::create_dir_all(&out).expect("OUT");
    let path = out.join("fits.jsonl");
    // Finished sets: both starts on record (a line cut by an interruption is dropped).
    let mut have: BTreeMap<(u64, String), ScatterFit> = BTreeMap::new();
    if let Ok(text) = std::fs::read_to_string(&path) {
        for l in text.lines() {
            if let Ok((start, f)) = serde_json::from_str::<(String, ScatterFit)>(l) {
                have.insert((f.seed, start), f);
            }
        }
    }
    let done = |s: u64| {
        STARTS
            .iter()
            .all(|(k, _)| have.contains_key(&(s, k.to_string())))
    };
    let todo: Vec<u64> = (first..first + n).filter(|&s| !done(s)).collect();
    eprintln!(
        "{} sets to fit ({} done)",
        todo.len(),
        n as usize - todo.len()
    );
    // Rewrite the file with the whole records only, then append.
    let mut text = String::new();
    for ((_, start), f) in &have {
        text.push_str(&serde_json::to_string(&(start, f)).unwrap());
        text.push('\n');
    }
    std::fs::write(&path, text).expect("fits.jsonl");
    let file = Mutex::new(
        std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .expect("fits.jsonl"),
    );
    let fresh: Vec<(String, ScatterFit)> = todo
        .par_iter()
        .flat_map_iter(|&seed| {
            let rows: Vec<(String, ScatterFit)> = STARTS
                .iter()
                .map(|(k, st)| {
                    let f = scatter_fit(&out, seed, &scenario, *st, world, kinds).expect("set");
                    (k.to_string(), f)
                })
                .collect();
            let mut w = file.lock().unwrap();
            for r in &rows {
                writeln!(w, "{}", serde_json::to_string(r).unwrap()).expect("write");
            }
            w.flush().expect("flush");
            eprintln!("{seed} done");
            rows
        })
        .collect();
    for (start, f) in fresh {
        have.insert((f.seed, start), f);
    }
    let mut s = format!(
        "# Scatter coverage, {world:?} world, kinds {}, scenario {scenario}, seeds {first}–{}\n\n| start | kind | sets with the scatter | covered | % (Wilson 95 %) | sets without | zero excluded |\n|---|---|---|---|---|---|---|\n",
        a.get(5).map_or("of the configuration", String::as_str),
        first + n - 1
    );
    // The fits of start `k` over the asked seeds.
    let fits_of = |k: &str| -> Vec<&ScatterFit> {
        have.iter()
            .filter(|((seed, st), _)| st == k && (first..first + n).contains(seed))
            .map(|(_, f)| f)
            .collect()
    };
    for (k, _) in STARTS {
        let fits = fits_of(k);
        let cov = coverage_of(fits.iter().map(|f| {
            (
                &f.scatter_true[..],
                &f.scatter_lo95[..],
                &f.scatter_hi95[..],
            )
        }));
        for c in cov {
            let (lo, hi) = wilson(c.covered, c.true_sets);
            s.push_str(&format!(
                "| {k} | {} | {} | {} | {:.1} ({:.1}–{:.1}) | {} | {} |\n",
                c.kind,
                c.true_sets,
                c.covered,
                100.0 * c.covered as f64 / c.true_sets.max(1) as f64,
                100.0 * lo,
                100.0 * hi,
                c.absent_sets,
                c.spurious
            ));
        }
    }
    // Where the Laplace criterion at the modes refuted the linear mixed model's estimate.
    for (k, _) in STARTS {
        let fits = fits_of(k);
        let laplace = fits
            .iter()
            .filter(|f| f.scatter_method == Some(creepfit::specimen::ScatterMethod::LaplaceAtModes))
            .count();
        s.push_str(&format!(
            "\n{k}: the scatter estimated by the Laplace criterion at the modes (the linear mixed model stopped short or overshot) in {laplace} of {} sets\n",
            fits.len()
        ));
    }
    s.push_str(&by_reading_error(&out, &have, first, n));
    std::fs::write(out.join("summary.md"), &s).expect("summary.md");
    print!("{s}");
}

/// Where the ductility interval excludes zero though the set has no ductility scatter, by the
/// generator's sampling and reading-error correlation φ (from each set's truth.json), with
/// the fits' mean φ beside the true one: the guess start's fits.
fn by_reading_error(
    out: &std::path::Path,
    have: &BTreeMap<(u64, String), ScatterFit>,
    first: u64,
    n: u64,
) -> String {
    const BINS: [(f64, f64, &str); 3] = [
        (0.0, 1e-9, "0 (white)"),
        (1e-9, 0.6, "0–0.6"),
        (0.6, 1.0, "0.6–1"),
    ];
    // (sampling, bin) → (sets, zero excluded, Σ true φ, Σ mean fitted φ)
    let mut t: BTreeMap<(String, usize), (usize, usize, f64, f64)> = BTreeMap::new();
    for ((seed, start), f) in have {
        if start != "guess" || !(first..first + n).contains(seed) || f.scatter_true[1] > 0.0 {
            continue;
        }
        let truth = out
            .join("sets")
            .join(format!("set-{seed}"))
            .join("truth.json");
        let Ok(text) = std::fs::read_to_string(&truth) else {
            continue;
        };
        let v: serde_json::Value = serde_json::from_str(&text).expect("truth.json");
        let phi = v["noise_phi"].as_f64().unwrap_or(f64::NAN);
        let sampling = v["sampling"].as_str().unwrap_or("?").to_string();
        let Some(bin) = BINS.iter().position(|(lo, hi, _)| phi >= *lo && phi < *hi) else {
            continue;
        };
        let fitted = if f.phi_est.is_empty() {
            f64::NAN
        } else {
            f.phi_est.iter().sum::<f64>() / f.phi_est.len() as f64
        };
        let e = t.entry((sampling, bin)).or_default();
        e.0 += 1;
        e.1 += usize::from(f.scatter_lo95[1] > 0.0);
        e.2 += phi;
        e.3 += fitted;
    }
    let mut s = String::from(
        "\n## Sets without ductility scatter (start: guess), by the generator's reading error\n\n| sampling | true φ | sets | zero excluded | % | mean true φ | mean fitted φ |\n|---|---|---|---|---|---|---|\n",
    );
    for ((sampling, bin), (k, x, tp, fp)) in &t {
        s.push_str(&format!(
            "| {sampling} | {} | {k} | {x} | {:.1} | {:.3} | {:.3} |\n",
            BINS[*bin].2,
            100.0 * *x as f64 / *k as f64,
            tp / *k as f64,
            fp / *k as f64
        ));
    }
    s
}
