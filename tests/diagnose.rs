//! `diagnose` on data it was not made from.
//!
//! - A reduced battery of generated data sets (`creepfit::synth`: three material families,
//!   3–5 stresses, digitised or logged sampling ending at 95–100 % of life, some curves cut at
//!   a strain limit, white or AR(1) reading error, 1 % scatter of rupture times, shuffled rows;
//!   every catalogued effect over a range of sizes, and no effect): the battery's machinery
//!   (confusion matrix, power table, summary, resume) and its two rates on the first two sets
//!   of the cycle (`synth::scenario_of`): set 1001 without an effect is not a false alarm,
//!   set 1002's constant load is named. Fixed development seeds. Until 2026-12-05 it was six
//!   sets (1001–1006: also loading_strain, dislocation_damage, a second no-effect set and
//!   stress_ductility, all as expected) and the suite's longest test (617 s of a 36.7 min
//!   CI); `creepfit battery DIR --seed 1001 --sets 6 --threads 2` on 2026-12-05 (AMD EPYC,
//!   2 cores, a test build beside it for the first sets): 43 + 222 s for the two kept, 448 s
//!   for the four left out. Loading strain is named in tests/temperature.rs' joint diagnosis
//!   and under specimen scatter in tests/specimen.rs, both against one other extension; the
//!   whole catalogue's naming of the other effects is left to the batteries.
//!   The calibration itself — false-alarm rate and power over many sets, on seeds not used
//!   while developing — is `creepfit battery`, run by `scripts/bench_battery.sh`.
//! - Real laboratory curves (Alloy 617, `data/alloy617/`): the verdict and the cause are the
//!   same on all points and on every 10th point, at every temperature, and a conclusion is
//!   reached at three of the four (`-- --ignored`: eight diagnoses of Alloy 617; with the
//!   configurations' scatter beyond the stress trend since 2026-12-03 — `auto` then fits
//!   specimen factors at 900 °C too — run by hand as the same eight diagnoses on
//!   8225e34's binary: 750 °C strain_softening both, 850 °C unexplained both, 900 °C
//!   strain_softening both, 950 °C adequate both; 361 s for 750 °C on every 10th point,
//!   347 + 504 s at 850, 91 + 138 s at 900, 28 + 34 s at 950, beside niced runs; with the
//!   three kinds shipped before 2026-12-02 the verdicts differed at 900 and 950 °C).
//! - The contract of `diagnosis.json` on the seed's 590 °C data.

use std::path::{Path, PathBuf};

use creepfit::battery::{rates, run_battery, run_battery_observed, write_reports};
use tempfile::TempDir;

mod common;
use common::*;

#[test]
fn battery_of_2_generated_sets() {
    let dir = TempDir::new().unwrap();
    let results = run_battery_observed(
        dir.path(),
        1001,
        2,
        creepfit::synth::World::Identical,
        None,
        &creepfit::battery::SetOverrides::default(),
        &TestProgress::new("battery_of_2_generated_sets"),
    )
    .unwrap();
    assert_eq!(results.len(), 2);
    let r = write_reports(dir.path(), &results, 1001).unwrap();
    for (i, res) in results.iter().enumerate() {
        eprintln!(
            "{i:2} {:8} {:20} λ {:12.1} {:5} → {} ({:?})",
            res.name,
            res.scenario,
            res.lambda,
            res.detectable,
            res.outcome(),
            res.error
        );
    }
    assert_eq!(r.errors, 0, "every set generated and diagnosed");
    assert_eq!(r.null_sets, 1);
    assert_eq!(r.false_alarms, 0, "a false alarm on set 1001");
    let (det, named): (usize, usize) = r.named.iter().fold((0, 0), |(d, k), e| (d + e.2, k + e.3));
    // Set 1002's constant load is detectable (oracle λ 693) and named.
    assert_eq!(det, 1, "detectable catalogued sets");
    assert_eq!(named, 1, "set 1002's constant load named");
    let set_1002 = results.iter().find(|r| r.seed == 1002).unwrap();
    assert_eq!(set_1002.outcome(), "extension:constant_load");
    // The reports add up: the confusion matrix counts every set once.
    let conf = std::fs::read_to_string(dir.path().join("confusion.csv")).unwrap();
    let total: usize = conf
        .lines()
        .skip(1)
        .flat_map(|l| l.split(',').skip(1).map(|v| v.parse::<usize>().unwrap()))
        .sum();
    assert_eq!(total, 2);
    assert!(dir.path().join("power.png").exists());
    // summary.json holds the same rates; identical specimens carry no scatter to cover.
    let sj = json(&dir.path().join("summary.json"));
    assert_eq!(sj["null_sets"], 1);
    assert_eq!(
        sj["false_alarms"].as_u64().unwrap() as usize,
        r.false_alarms
    );
    assert_eq!(sj["errors"], 0);
    for c in sj["scatter"].as_array().unwrap() {
        assert_eq!(c["true_sets"], 0, "{c}");
        assert_eq!(c["absent_sets"], 0, "{c}");
    }
    // Resuming a finished battery recomputes nothing and gives the same results.
    let again = run_battery(
        dir.path(),
        1001,
        2,
        creepfit::synth::World::Identical,
        None,
        false,
    )
    .unwrap();
    let text = |v: &[creepfit::battery::SetResult]| serde_json::to_string(v).unwrap();
    assert_eq!(text(&again), text(&results));
    assert_eq!(
        serde_json::to_string(&rates(&again)).unwrap(),
        serde_json::to_string(&r).unwrap()
    );
}

/// Asks to stop from the start.
struct StopNow;

impl creepfit::progress::Observer for StopNow {
    fn cancelled(&self) -> bool {
        true
    }
}

/// A battery asked to stop starts no set, records none, and ends with an interruption that
/// says how to resume; a rerun then computes the sets (the Python package's Ctrl-C).
#[test]
fn a_battery_asked_to_stop_starts_no_set() {
    let dir = TempDir::new().unwrap();
    let err = run_battery_observed(
        dir.path(),
        1001,
        3,
        creepfit::synth::World::Identical,
        Some("none"),
        &creepfit::battery::SetOverrides::default(),
        &StopNow,
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(err, creepfit::Error::Interrupted(_)),
        "not an interruption: {msg}"
    );
    assert!(
        msg.contains("results.jsonl") && msg.contains("resume"),
        "{msg}"
    );
    let recorded = std::fs::read_to_string(dir.path().join("results.jsonl")).unwrap_or_default();
    assert!(recorded.is_empty(), "sets recorded: {recorded}");
    assert!(!dir.path().join("sets").exists(), "a set was generated");
}

/// `data/alloy617/` with every 10th point of each curve kept.
fn every_tenth(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("data/alloy617/creep_alloy617.csv")).unwrap();
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            out += line;
            out.push('\n');
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        let key = format!("{},{},{}", f[0], f[1], f[4]);
        let k = seen.entry(key).or_insert(0);
        if (*k).is_multiple_of(10) {
            out += line;
            out.push('\n');
        }
        *k += 1;
    }
    let p = dir.join("creep_10th.csv");
    std::fs::write(&p, out).unwrap();
    p
}

/// All four temperatures (8 diagnoses; about 30 minutes on 2 cores, module comment):
/// `cargo test --release --test diagnose -- --ignored` (out of CI's budget;
/// scripts/bench_battery.sh runs it).
#[test]
#[ignore = "long: 8 diagnoses of Alloy 617"]
fn alloy617_verdict_does_not_depend_on_the_logging_density_at_any_temperature() {
    same_verdict_on_every_tenth_point(&[750, 850, 900, 950]);
}

fn same_verdict_on_every_tenth_point(temps: &[u32]) {
    let dir = TempDir::new().unwrap();
    let thin = every_tenth(dir.path());
    let progress = TestProgress::new("alloy617 logging density");
    let mut conclusions = 0;
    for &t in temps {
        let cfg = root().join(format!("configs/alloy617-{t}C.toml"));
        let text = std::fs::read_to_string(&cfg)
            .unwrap()
            .replace(
                "../data/alloy617/creep_alloy617.csv",
                thin.to_str().unwrap(),
            )
            .replace(
                "../data/alloy617/ruptures_alloy617.csv",
                root()
                    .join("data/alloy617/ruptures_alloy617.csv")
                    .to_str()
                    .unwrap(),
            );
        let thin_cfg = dir.path().join(format!("thin-{t}.toml"));
        std::fs::write(&thin_cfg, text).unwrap();
        let mut verdicts = Vec::new();
        for (c, tag) in [(cfg, "all"), (thin_cfg, "tenth")] {
            let out = dir.path().join(format!("{t}-{tag}"));
            let o = creepfit(&[
                "diagnose",
                c.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ]);
            assert!(
                o.status.success(),
                "{t} °C {tag}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let d = json(&out.join("diagnosis.json"));
            progress.line(&format!("{t} °C {tag}: {} {}", d["verdict"], d["cause"]));
            verdicts.push((d["verdict"].clone(), d["cause"].clone()));
            let md = std::fs::read_to_string(out.join("report.md")).unwrap();
            assert!(md.contains("What the calibrated base model gets wrong"));
            assert!(md.contains("## Specimens"));
            if t == 850 {
                // 850 °C has replicates: the report gives the scatter and each specimen's factor.
                assert!(md.contains("between specimens"));
                assert!(md.contains("factors against ln stress"), "{md}");
                // The base's stress trend of each kind: the slope of its factors (as in
                // diagnosis.json) on ln stress, one temperature here, recomputed.
                let base = &d["base"];
                let x: Vec<f64> = base["curves"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|c| c["stress_mpa"].as_f64().unwrap().ln())
                    .collect();
                let trends = base["specimen_stress_trend"].as_array().unwrap();
                let effects = base["specimen"]["effects"].as_array().unwrap();
                assert_eq!(trends.len(), effects.len());
                for (tr, eta) in trends.iter().zip(effects) {
                    let y: Vec<f64> = eta
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|v| v.as_f64().unwrap())
                        .collect();
                    let n = x.len() as f64;
                    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
                    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
                    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
                    let got = tr["slope_per_ln_stress"].as_f64().unwrap();
                    assert!(
                        (got - sxy / sxx).abs() < 1e-9,
                        "{got} against {}",
                        sxy / sxx
                    );
                    assert_eq!(tr["df"].as_u64().unwrap() as usize, x.len() - 2);
                }
            }
        }
        assert_eq!(verdicts[0], verdicts[1], "{t} °C: all points vs every 10th");
        if verdicts[0].0 != "unexplained" {
            conclusions += 1;
        }
    }
    // The must-show: a conclusion (`adequate`, or a cause whose own fit holds) at
    // three of the four temperatures or more (with the configurations of 2026-12-03: 750 and
    // 900 °C strain_softening, 950 °C adequate, 850 °C unexplained).
    if temps.len() == 4 {
        assert!(conclusions >= 3, "conclusions at {conclusions} of 4");
    }
}

/// A base fit that gives up one test's life says so in the caution
/// (`fit::missed_lives_caution`): the seed's 560 °C data with the 110 MPa rupture time made
/// 100× longer (3,111,100 h, longer than the lower stresses' lives, which no constants of the
/// model give) — the likelihood follows the curves and the other two lives and misses that
/// one by about 98× (measured 2026-12-06 at the defaults: −3.7 %, −6.6 %, −99.0 %; 22 s).
#[test]
fn a_base_fit_that_gives_up_a_life_says_so() {
    let dir = TempDir::new().unwrap();
    let path = seed_560_with_life(dir.path(), "560,110,31111,", "560,110,3111100,");
    let out = dir.path().join("d");
    // The caution, not the calibration: few starts and replicates, as the contract test.
    let o = creepfit(&[
        "diagnose",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--bootstrap",
        "39",
        "--starts",
        "4",
        "--alpha",
        "0.4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = json(&out.join("diagnosis.json"));
    let errs: Vec<f64> = d["base"]["lifetime_errs_pct"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // Ascending stress: 85, 100, 110 MPa.
    assert!(errs[2] <= -90.0, "{errs:?}");
    assert!(errs[..2].iter().all(|e| e.abs() < 50.0), "{errs:?}");
    let caution = d["caution"].as_str().expect("a caution");
    assert!(
        caution.contains("1 of 3 predicted rupture times miss")
            && caution.contains("worst 560 °C, 110 MPa"),
        "{caution}"
    );
}

#[test]
fn diagnosis_json_keeps_its_contract() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("d");
    let o = creepfit(&[
        "diagnose",
        "configs/590C.toml",
        "--out",
        out.to_str().unwrap(),
        // The contract, not the calibration (that is `creepfit battery`'s): 39 replicates
        // at α = 0.4 instead of 159 at 0.05, so that Holm's first threshold α/8 = 0.05 can
        // still be met (p ≥ 1/40) and the rejecting tests are run again as at the default;
        // 134 s of CI before (2026-11-29).
        "--bootstrap",
        "39",
        // Four Latin-hypercube starts per model instead of 16: the contract, not the
        // multistart's reach.
        "--starts",
        "4",
        // A test close to significance (p ≤ α/2 after 39) goes on to 79: the rule's
        // replicate counts are checked below (159 until 2026-12-05: the run then took 94 s
        // on 2 threads, 52 s of it bootstrapping the rejecting tests again).
        "--bootstrap-extended",
        "79",
        "--alpha",
        "0.4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = json(&out.join("diagnosis.json"));
    assert!(["adequate", "extension", "unexplained"].contains(&d["verdict"].as_str().unwrap()));
    assert_eq!(d["cause"].is_null(), d["verdict"] != "extension");
    assert_eq!(d["alpha"], 0.4);
    assert!(d["evidence"].is_array());
    // A caution is a sentence or null (the 590 °C base fit's reading error is not correlated
    // to its bound on half of the curves).
    assert!(d["caution"].is_null() || d["caution"].is_string());
    // No specimen factors asked for (no replicates, the default scatter), so none left out.
    assert_eq!(d["specimen_scatter_zero"], false);
    // The default reduction weighs no group means by an estimated misfit share: the key is
    // there, null.
    assert!(d.as_object().unwrap().contains_key("misfit_share"));
    assert!(d["misfit_share"].is_null(), "{}", d["misfit_share"]);
    let cands = d["candidates"].as_array().unwrap();
    assert_eq!(cands.len(), creepfit::model::ext::CATALOGUE.len());
    for c in cands.iter().chain(std::iter::once(&d["base"])) {
        for k in [
            "name",
            "extra_constants",
            "objective",
            "delta_bic",
            "loo_rmse",
            "gain_pct",
            "constants",
            "p_value",
        ] {
            assert!(c.get(k).is_some(), "{} lacks {k}", c["name"]);
        }
        // How the kept fit's iteration ended, in the words of `lsq::Termination`.
        let t = c["termination"]
            .as_str()
            .expect("a fitted model's termination");
        assert!(
            [
                "converged_step",
                "converged_objective",
                "converged_gradient",
                "stalled",
                "plateau",
                "small_gain_to_come",
                "iteration_limit"
            ]
            .contains(&t),
            "{t}"
        );
        // An unconverged fit is named in the caution.
        if ["stalled", "iteration_limit"].contains(&t) {
            let caution = d["caution"].as_str().expect("a caution");
            assert!(
                caution.contains(&format!("{} ({t})", c["name"].as_str().unwrap())),
                "{caution}"
            );
        }
    }
    assert!(d["base"]["lr_critical"].is_null());
    let alpha = d["alpha"].as_f64().unwrap();
    for c in cands {
        let p = c["p_value"].as_f64().unwrap();
        assert!(p > 0.0 && p <= 1.0, "{p}");
        // The ratio needed for p ≤ α agrees with the p-value reported beside it (39
        // replicates can give p ≤ 0.4, so it is a number unless refits failed).
        if let Some(crit) = c["lr_critical"].as_f64() {
            let lr = c["lr"].as_f64().unwrap();
            assert_eq!(
                lr > crit,
                p <= alpha,
                "{}: lr {lr}, needed {crit}, p {p}",
                c["name"]
            );
        }
    }
    assert!(cands.iter().any(|c| c["lr_critical"].is_f64()));
    // A test decided not significant early is dropped from the later replicates (no specimen
    // effects here): it had at least 10 null ratios at or above its own. One close to
    // significance after the 39 (p ≤ α/2) went on towards 79 (2 · 40 − 1); the others
    // ended at 39. So every test's count of replicates is the rule's.
    let reps = d["bootstrap"]["replicates"].as_u64().unwrap();
    let (first, most) = (39, d["bootstrap"]["most"].as_u64().unwrap());
    assert_eq!(most, 79);
    assert!(d["base"]["null_replicates"].is_null());
    let nulls = d["bootstrap"]["null_statistics"].as_array().unwrap();
    for c in cands {
        let l = c["null_replicates"].as_u64().unwrap();
        assert!(l <= reps && reps <= most);
        let p = c["p_value"].as_f64().unwrap();
        let column = nulls.iter().find(|n| n["test"] == c["name"]).unwrap();
        let values = column["values"].as_array().unwrap();
        assert_eq!(values.len() as u64, l, "{}", c["name"]);
        let obs = column["observed"].as_f64().unwrap_or(f64::NAN);
        let g = values
            .iter()
            .filter(|v| v.as_f64().is_none_or(|x| x >= obs))
            .count();
        let decided = g >= 10;
        let ended_first = l == first && (g + 1) as f64 / (first + 1) as f64 > alpha / 2.0;
        // Or the whole family was settled before 39: every test's p-value already bound
        // above Holm's smallest threshold and α/2 (six extensions and two shapes: α/2).
        let stopped = d["bootstrap"]["stopped_early"].as_bool().unwrap();
        let settled = stopped && l == reps && (g + 1) as f64 / (first + 1) as f64 > alpha / 2.0;
        assert!(
            !obs.is_finite() || decided || ended_first || settled || l == most,
            "{}: {g} of {l} at or above, {reps} replicates",
            c["name"]
        );
        if decided {
            assert!(!c["significant"].as_bool().unwrap(), "{}", c["name"]);
            assert!(p >= 11.0 / (l + 1) as f64, "{}: p {p} over {l}", c["name"]);
        }
    }
    assert!(
        cands
            .iter()
            .any(|c| c["null_replicates"].as_u64().unwrap() < reps),
        "at 590 °C some extension is clearly not significant"
    );
    // The tests that rejected with the replicates' own starts were bootstrapped again with the
    // start that found the extension's best fit on the data (measured at 590 °C:
    // dislocation_damage and strain_softening; at 560 °C none rejects since the bootstrap
    // draws the reading error's growth with strain); the report's Method names them.
    assert_eq!(d["base"]["null_again"], false);
    let again: Vec<&str> = cands
        .iter()
        .filter(|c| c["null_again"].as_bool().unwrap())
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert!(!again.is_empty(), "no test was run again at 590 °C");
    // What the second run changed is recorded beside it, and its count is the p-value's. The
    // fresh start raises some replicates' ratios (measured at 590 °C at the defaults,
    // 2026-12-05: 23 of dislocation_damage's 159 and 3 of strain_softening's, none to the
    // data's ratio).
    assert!(
        cands
            .iter()
            .filter(|c| c["null_again"].as_bool().unwrap())
            .any(|c| c["null_again_effect"]["raised"].as_u64().unwrap() > 0),
        "the second run raised no replicate's ratio"
    );
    for c in cands {
        let e = &c["null_again_effect"];
        if !c["null_again"].as_bool().unwrap() {
            assert!(e.is_null(), "{}: an effect without a second run", c["name"]);
            continue;
        }
        let n = c["null_replicates"].as_u64().unwrap() as f64;
        // The second run's effect is counted over the test's own replicates.
        assert_eq!(e["replicates"], c["null_replicates"], "{}: {e}", c["name"]);
        let above = e["at_or_above"][1].as_u64().unwrap() as f64;
        let p = c["p_value"].as_f64().unwrap();
        assert!(
            (p - (1.0 + above) / (n + 1.0)).abs() < 1e-12,
            "{}: {e}",
            c["name"]
        );
        assert!(e["raised"].as_u64().unwrap() as f64 <= n);
        assert!(
            e["at_or_above"][0].as_u64().unwrap()
                <= e["at_or_above"][1].as_u64().unwrap() + e["raised"].as_u64().unwrap()
        );
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    // The Method says how many replicates were drawn where sampling stopped early.
    let stopped = d["bootstrap"]["stopped_early"].as_bool().unwrap();
    assert_eq!(
        md.contains("drawn: sampling stopped once no test could become significant"),
        stopped
    );
    assert_eq!(
        md.contains("stopped early: no test could become significant"),
        stopped
    );
    // The Method names each test run again with what its second run changed.
    let clauses: Vec<String> = cands
        .iter()
        .filter(|c| c["null_again"].as_bool().unwrap())
        .map(|c| {
            let e = &c["null_again_effect"];
            format!(
                "{}: {} of {} replicates' ratios raised, {} → {} at or above the data's",
                c["name"].as_str().unwrap(),
                e["raised"],
                e["replicates"],
                e["at_or_above"][0],
                e["at_or_above"][1]
            )
        })
        .collect();
    assert_eq!(clauses.len(), again.len());
    assert!(
        md.contains(&format!(
            "p-values are the second run's ({})",
            clauses.join("; ")
        )),
        "{md}"
    );
    let gof = d["gof"].as_array().unwrap();
    assert_eq!(gof.len(), creepfit::diagnose::gof::SHAPES.len());
    // No specimen effects at 590 °C: the fixed common and per-curve shapes decide, the shapes
    // beyond specimen shapes are reported only (no Holm-adjusted p-value).
    let deciding: Vec<&str> = gof
        .iter()
        .filter(|g| g["decides"].as_bool().unwrap())
        .map(|g| g["gof"]["shape"].as_str().unwrap())
        .collect();
    assert_eq!(deciding, ["common", "per_curve"]);
    assert!(gof
        .iter()
        .filter(|g| !g["decides"].as_bool().unwrap())
        .all(|g| g["p_holm"].as_f64().is_none()));
    assert!(gof.iter().all(|g| g["p_value"].as_f64().unwrap() > 0.0));
    assert!(out.join("report.md").exists());
    // The reading error's growth with strain that the bootstrap drew (the seed's digitised
    // 590 °C curves: their late readings are far noisier, g at its bound 5), said in the report.
    let g = d["base"]["noise"]["reading_error_growth"].as_f64().unwrap();
    assert!((0.0..=creepfit::errmodel::GROWTH_MAX).contains(&g), "{g}");
    assert!(
        g > 0.0 && md.contains("The reading error grows with strain"),
        "{g}: {md}"
    );
    // No replicates at 590 °C: the report says why the base model carries no specimen scatter.
    assert!(md.contains("## Specimens") && md.contains("no two specimens share"));
    assert!(out.join("residuals_base.png").exists());
    // Identical for any thread count (on a smaller diagnosis: 2 random starts per model, 19
    // replicates at α = 0.5, so that the replicates can reject; the full one above is the
    // contract, this the determinism).
    let small = |threads: &str, out: &Path| {
        let o = creepfit(&[
            "diagnose",
            "configs/560C.toml",
            "--starts",
            "2",
            "--bootstrap",
            "19",
            "--alpha",
            "0.5",
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        json(&out.join("diagnosis.json"))
    };
    let d = small("2", &dir.path().join("d2"));
    let d1 = small("1", &dir.path().join("d1"));
    for k in ["verdict", "cause", "candidates", "base", "gof", "bootstrap"] {
        let strip = |v: &serde_json::Value| {
            let mut v = v.clone();
            if let Some(o) = v.as_object_mut() {
                o.remove("wall_s");
                o.remove("phase_s");
            }
            v
        };
        assert_eq!(strip(&d[k]), strip(&d1[k]), "{k}");
    }
}

/// The family stop, end to end: the seed's 560 °C data, where no test of the family comes
/// close (measured 2026-12-03: every test had a null statistic at or above its own after the
/// first batch), stop their null bootstrap as soon as Holm's procedure could reject none of
/// the 8 tests — each has a replicate at or above its statistic, so each p-value after the 159
/// would be at least 2/160 > α/8 — and the report says how many were drawn. Without the
/// stop the run draws all 159 (16.7 s against 7.4 s on the AMD EPYC of that day).
#[test]
fn a_diagnosis_that_can_reject_nothing_stops_its_bootstrap_early() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("d");
    let o = creepfit(&[
        "diagnose",
        "configs/560C.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = json(&out.join("diagnosis.json"));
    let boot = &d["bootstrap"];
    let (drawn, max) = (
        boot["replicates"].as_u64().unwrap(),
        boot["max"].as_u64().unwrap(),
    );
    assert_eq!(max, 159);
    assert_eq!(
        boot["most"].as_u64().unwrap(),
        max,
        "no extension at the defaults"
    );
    assert!(boot["stopped_early"].as_bool().unwrap(), "{boot}");
    assert!(drawn < max, "{drawn}");
    // Nothing significant, and nothing could have been: the family (every extension and the
    // shapes that decide) each with a null statistic at or above its own.
    let alpha = d["alpha"].as_f64().unwrap();
    let cands = d["candidates"].as_array().unwrap();
    assert!(cands.iter().all(|c| !c["significant"].as_bool().unwrap()));
    assert_eq!(d["verdict"], "adequate");
    let deciding: Vec<&str> = d["gof"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|g| g["decides"].as_bool().unwrap())
        .map(|g| g["gof"]["shape"].as_str().unwrap())
        .collect();
    let m = cands.len() + deciding.len();
    assert_eq!(m, 8);
    let nulls = boot["null_statistics"].as_array().unwrap();
    let family: Vec<&serde_json::Value> = nulls
        .iter()
        .filter(|n| {
            let t = n["test"].as_str().unwrap();
            !t.starts_with("base ")
                || (t.contains("common goodness") && deciding.contains(&"common"))
                || (t.contains("per-curve") && deciding.contains(&"per_curve"))
        })
        .collect();
    assert_eq!(family.len(), m, "{nulls:?}");
    for n in family {
        let obs = n["observed"].as_f64().unwrap();
        let g = n["values"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|v| v.as_f64().is_none_or(|x| x >= obs))
            .count();
        assert!(
            (g + 1) as f64 / (max + 1) as f64 > alpha / m as f64,
            "{}: {g} at or above",
            n["test"]
        );
    }
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    // Each test's line says how many replicates its p-value is from: its resolution.
    for c in cands {
        let n = c["null_replicates"].as_u64().unwrap();
        assert!(n <= drawn, "{c}");
        let line = format!(
            "- {}: LR {:.2}, bootstrap p = {:.3} ({n} replicates)",
            c["name"].as_str().unwrap(),
            c["lr"].as_f64().unwrap(),
            c["p_value"].as_f64().unwrap()
        );
        assert!(md.contains(&line), "{line}");
    }
    assert!(md.contains(&format!(
        "at most {max} ({drawn} drawn: sampling stopped once no test could become significant"
    )));
    assert!(md.contains("stopped early: no test could become significant"));
}
