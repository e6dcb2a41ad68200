//! The commands as a scheduler (hyperfine's options → scheduler → exporters): each resolves
//! its configuration, refuses what it cannot do before anything is written, takes its output
//! folder (lock, journal, manifest), runs the library with progress and the test-only stop,
//! and hands the result to its exporter (`crate::export`). No numbers are computed or
//! formatted here.

use std::path::{Path, PathBuf};

use crate::config::{load, Overrides, RunConfig};
use crate::data::{note_data, Dataset};
use crate::error::{Error, Result};
use crate::export;
use crate::fit::FitSettings;
use crate::journal::{take_with_journal, Journal};
use crate::output::RunFolder;
use crate::progress::{stop_after, Bars, Hooks};
use crate::sweep;

/// File of a battery folder that holds its run identity (first seed, scenarios, version).
pub const BATTERY_IDENTITY: &str = "battery.json";

/// Run `f` on a pool of `threads` workers (rayon's default pool when `None`).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    match threads {
        None => f(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::Invalid(format!("--threads {n}: {e}")))?
            .install(f),
    }
}

/// Take `out` for `command` (lock, manifest) with its journal bound to `identity`, note the
/// data, and run `work` with its hooks (progress bars, the test-only stop, the journal); the
/// folder is finished with the outcome. `work` clears the bars before it writes.
fn journaled(
    cfg: &RunConfig,
    data: &Dataset,
    out: &Path,
    command: &str,
    identity: &serde_json::Value,
    work: impl FnOnce(&Hooks, &Bars, &Journal) -> Result<()>,
) -> Result<()> {
    let (mut folder, journal) = take_with_journal(out, command, identity)?;
    note_data(&mut folder, data);
    let bars = Bars::new(!cfg.run.progress);
    let stop = stop_after(&bars, &journal, cfg.run.stop_after);
    let hooks = Hooks {
        observer: &stop,
        journal: Some(&journal),
    };
    folder.finish(work(&hooks, &bars, &journal))
}

/// `creepfit fit`.
pub fn fit(config: &Path, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    let out = cfg.out_dir("fit");
    let mut folder = RunFolder::begin(&out, "fit")?;
    note_data(&mut folder, &data);
    let bars = Bars::new(!cfg.run.progress);
    let hooks = Hooks {
        observer: &bars,
        journal: None,
    };
    let outcome = (|| {
        let run = cfg
            .calibration(&data)
            .and_then(|cal| crate::fit::run_fit_observed(cal, &data, 0, &hooks));
        bars.clear();
        export::fit::write(&cfg, &data, &run?, &out)
    })();
    folder.finish(outcome)
}

/// `creepfit simulate`: at the constants of `constants` (else the configuration's starts),
/// with the objective at one lifetime weight `w` when asked.
pub fn simulate(
    config: &Path,
    constants: Option<PathBuf>,
    cli: &Overrides,
    w: Option<f64>,
) -> Result<()> {
    if let Some(w) = w {
        if !(0.0..=1.0).contains(&w) {
            return Err(Error::Invalid(format!(
                "--w: must be a weight in [0, 1], not {w}"
            )));
        }
    }
    let (cfg, data) = load(config, cli)?;
    let model = cfg.build_model()?;
    let params = match constants {
        Some(path) => crate::report::tables::read_constants_for(&path, &cfg, model.as_ref())?,
        None => cfg.starts_all_given().ok_or_else(|| {
            Error::config(
                &cfg.path,
                "simulate needs --constants FILE or a start value for every constant",
            )
        })?,
    };
    let out = cfg.out_dir("simulate");
    let mut folder = RunFolder::begin(&out, "simulate")?;
    note_data(&mut folder, &data);
    let settings = FitSettings::from_config(&cfg);
    let model = model.as_ref();
    let sims =
        crate::simulate::simulate(model, &params, &data, cfg.objective.omega_f, &settings.ode);
    let objective = w.map(|w| {
        let e = crate::simulate::objective_at(model, &data, &params, w, settings.objective());
        (w, e)
    });
    let outcome = export::simulate::write(
        &cfg,
        &data,
        model,
        &params,
        &settings.ode,
        &sims,
        objective.as_ref().map(|(w, e)| (*w, e)),
        &out,
    );
    folder.finish(outcome)
}

/// `creepfit predict` at the constants of `constants`: at them, or under `--intervals` at
/// the maximum-likelihood refit the intervals are centred on (the given constants'
/// predictions beside).
///
/// With `tests` (`--tests FILE`: the file and its records) the conditions are the tests', and
/// their measured lives are scored against the predictions.
pub fn predict(
    config: &Path,
    constants: &Path,
    tests: Option<&(PathBuf, Vec<crate::data::RuptureRecord>)>,
    cli: &Overrides,
) -> Result<()> {
    let (mut cfg, data) = load(config, cli)?;
    let from_config = crate::predict::measured::from_config(&mut cfg)?;
    let tests = tests.or(from_config.as_ref());
    crate::predict::check_asked(&cfg)?;
    let model = cfg.build_model()?;
    let params = crate::report::tables::read_constants_for(constants, &cfg, model.as_ref())?;
    // What the configuration can predict: refused before anything is written.
    match tests {
        Some((file, records)) => crate::predict::measured::check(file, records, &cfg, &data)?,
        None => crate::predict::check_conditions(&cfg, &data, cli.predict_at.is_some())?,
    }
    let out = cfg.out_dir("predict");
    let work = |hooks: &Hooks, bars: &Bars, journal: Option<&Journal>| {
        let t0 = std::time::Instant::now();
        let setup = cfg.predict_setup(&data);
        let run = with_threads(cfg.run.threads, || {
            crate::predict::run_observed(&setup, &data, model.as_ref(), &params, hooks)
        });
        bars.clear();
        let mut run = run?;
        if let Some((file, records)) = tests {
            run.measured = Some(crate::predict::measured::MeasuredTests::of(
                file, records, &run,
            ));
        }
        if let Some(t) = &run.interval_timings {
            crate::report::tables::write_timings(
                &out,
                "predict",
                journal,
                serde_json::json!({
                    "wall_s": t0.elapsed().as_secs_f64(),
                    "intervals_s": t,
                }),
            )?;
        }
        export::predict::write(&cfg, &data, model.as_ref(), &run, &out)
    };
    // With intervals (minutes on dense curves) the run is journaled and resumes: the
    // calibration replicates and each condition's intervals.
    if cfg.predict.intervals {
        let identity = crate::predict::identity(&cfg, &params);
        return journaled(&cfg, &data, &out, "predict", &identity, |hooks, bars, j| {
            export::predict::warn_extrapolation(&cfg, &data);
            work(hooks, bars, Some(j))
        });
    }
    let mut folder = RunFolder::begin(&out, "predict")?;
    note_data(&mut folder, &data);
    export::predict::warn_extrapolation(&cfg, &data);
    let bars = Bars::new(!cfg.run.progress);
    let hooks = Hooks {
        observer: &bars,
        journal: None,
    };
    folder.finish(work(&hooks, &bars, None))
}

/// `creepfit holdout`: fit without the tests `left_out`, predict them, compare with the
/// classical baselines.
pub fn holdout(config: &Path, left_out: &crate::holdout::LeftOut, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    let out = cfg.out_dir(&left_out.folder());
    let identity = crate::holdout::identity(&cfg, left_out);
    journaled(
        &cfg,
        &data,
        &out,
        "holdout",
        &identity,
        |hooks, bars, journal| {
            let t0 = std::time::Instant::now();
            let h = crate::holdout::holdout_observed(
                &cfg,
                &data,
                left_out,
                cfg.predict.intervals,
                hooks,
            );
            bars.clear();
            let h = h?;
            crate::report::tables::write_timings(
                &out,
                "holdout",
                Some(journal),
                serde_json::json!({
                    "wall_s": t0.elapsed().as_secs_f64(),
                    "training_fit_s": h.fit.wall_s,
                }),
            )?;
            export::holdout::write(&cfg, &data, &h, &out)
        },
    )
}

/// `creepfit sweep` (one part of a job array when `cfg.run.shard` says so).
pub fn sweep(cfg: &RunConfig, data: &Dataset) -> Result<()> {
    sweep::install_sigint_handler();
    let out = cfg.out_dir("sweep");
    let (plan, mut run) = sweep::run_sweep(cfg, data)?;
    note_data(&mut run.folder, data);
    let outcome = export::sweep::write(cfg, &plan, &run, &out);
    run.folder.finish(outcome)
}

/// `creepfit merge`: the finished parts of a sharded sweep into `out`; refused (nothing
/// written) when a part is missing and `require_all`, or when none is complete.
pub fn merge(dirs: &[PathBuf], out: &Path, require_all: bool) -> Result<()> {
    let m = sweep::merge(dirs)?;
    export::sweep::report_merge(&m);
    let n = m.merged.len() + m.coverage.missing.len();
    if !m.coverage.complete && (require_all || m.merged.is_empty()) {
        return Err(Error::Invalid(format!(
            "merge{}: {} of {n} shards complete (missing or incomplete: {}); nothing written",
            if require_all { " --require-all" } else { "" },
            m.merged.len(),
            m.coverage
                .missing
                .iter()
                .map(|s| s.shard.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let folder = RunFolder::begin(out, "merge")?;
    folder.finish(export::sweep::write_merged(&m, out))
}

/// `creepfit diagnose`.
pub fn diagnose(config: &Path, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    cfg.check_diagnose(&data)?;
    let out = cfg.out_dir("diagnose");
    let identity = crate::diagnose::hooks::identity(&cfg);
    journaled(
        &cfg,
        &data,
        &out,
        "diagnose",
        &identity,
        |hooks, bars, journal| {
            let setup = cfg.diagnose_setup()?;
            let d = with_threads(cfg.run.threads, || {
                crate::diagnose::diagnose_observed(&setup, &data, &cfg.diagnose, hooks)
            });
            bars.clear();
            export::diagnose::write(&cfg, &setup, &data, &d?, Some(journal), &out)
        },
    )
}

/// `creepfit profile`, from the constants of `constants` when given (else from a fit).
pub fn profile(config: &Path, constants: Option<&Path>, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    with_threads(cfg.run.threads, || {
        let model = cfg.build_model()?;
        let given = match constants {
            Some(p) => Some(crate::report::tables::read_constants_for(
                p,
                &cfg,
                model.as_ref(),
            )?),
            None => None,
        };
        crate::uncertainty::report::check(&cfg, &data)?;
        let out = cfg.out_dir("profile");
        let identity = crate::uncertainty::report::identity(&cfg, given.as_deref());
        journaled(
            &cfg,
            &data,
            &out,
            "profile",
            &identity,
            |hooks, bars, journal| {
                let run = crate::uncertainty::report::run_observed(
                    &cfg,
                    &data,
                    given.as_deref(),
                    &cfg.profile,
                    hooks,
                );
                bars.clear();
                export::profile::write(&cfg, &run?, Some(journal), &out)
            },
        )
    })
}

/// `creepfit synth`: `sets` generated data sets from seed `seed` (one `scenario`, else the
/// scenarios in turn) into `out`.
pub fn synth(
    out: &Path,
    sets: usize,
    seed: u64,
    scenario: Option<&str>,
    world: crate::synth::World,
) -> Result<()> {
    if let Some(sc) = scenario {
        crate::synth::check_scenario(sc)?;
    }
    for i in 0..sets {
        let s = seed + i as u64;
        let sc = scenario.unwrap_or_else(|| crate::synth::scenario_of(i));
        let name = format!("set-{s}");
        let set = crate::synth::generate_in(&name, sc, None, s, world)?;
        export::synth::write(&set, &name, sc, &out.join(&name))?;
    }
    println!("wrote {}", out.display());
    Ok(())
}

/// `creepfit battery`: `sets` generated sets from seed `seed` diagnosed into `out`, resumed
/// from what an earlier run of the same battery finished there.
pub fn battery(
    out: &Path,
    sets: usize,
    seed: u64,
    world: crate::synth::World,
    scenario: Option<&str>,
    overrides: &crate::battery::SetOverrides,
    quiet: bool,
) -> Result<()> {
    let bars = Bars::new(quiet);
    let run = battery_observed(out, sets, seed, world, scenario, overrides, &bars);
    bars.clear();
    let (results, rates) = run?;
    export::battery::print_summary(&results, &rates);
    println!("wrote {}", out.display());
    Ok(())
}

/// [`battery`] telling `observer` of its sets (and stopping when it asks to: the finished
/// sets stay recorded for a rerun), printing nothing: the sets' results in seed order and
/// the rates its reports give.
pub fn battery_observed(
    out: &Path,
    sets: usize,
    seed: u64,
    world: crate::synth::World,
    scenario: Option<&str>,
    overrides: &crate::battery::SetOverrides,
    observer: &dyn crate::progress::Observer,
) -> Result<(Vec<crate::battery::SetResult>, crate::battery::Rates)> {
    if let Some(sc) = scenario {
        crate::synth::check_scenario(sc)?;
    }
    // One writer, one battery per folder: the lock, then the identity (refused before
    // anything changes), then the folder is this run's (what it resumes from kept).
    let lock = crate::output::lock_folder(out)?;
    let mut id = serde_json::json!({
        "command": "battery",
        "seed": seed,
        "world": world,
        "scenarios": crate::synth::SCENARIOS,
        "version": env!("CARGO_PKG_VERSION"),
    });
    // Only when given: the folders of earlier batteries (the cycle of scenarios) resume.
    if let Some(sc) = scenario {
        id["scenario"] = sc.into();
    }
    if let Some(k) = &overrides.effects {
        id["specimen_effects"] = serde_json::json!(k);
    }
    // Recorded for the estimate beyond the stress trend only, default or not: batteries
    // with the likelihood's own estimate (the default before 2026-12-04) never recorded it,
    // and one of them must not be resumed with the other estimate, nor the reverse.
    if !overrides.scatter.is_likelihood() {
        id["specimen_scatter"] = serde_json::json!(overrides.scatter);
    }
    if let Some(most) = overrides.bootstrap_extended {
        id["bootstrap_extended"] = most.into();
    }
    if let Some(n) = overrides.max_points {
        id["diagnose_max_points"] = n.into();
    }
    if let Some(how) = overrides.reduction {
        id["diagnose_reduction"] = how.as_str().into();
    }
    if let Some(how) = overrides.misfit_share {
        id["diagnose_misfit_share"] = how.as_str().into();
    }
    crate::identity::bind_folder(out, BATTERY_IDENTITY, "results.jsonl", &id)?;
    let folder = RunFolder::take_over(lock, "battery", &|f| {
        f == BATTERY_IDENTITY || f == "results.jsonl" || f.starts_with("sets/")
    })?;
    crate::output::record(&out.join(BATTERY_IDENTITY));
    let results =
        crate::battery::run_battery_observed(out, seed, sets, world, scenario, overrides, observer);
    export::battery::record_written(out);
    let outcome = results.and_then(|r| {
        let rates = export::battery::write(out, &r, seed)?;
        Ok((r, rates))
    });
    folder.finish(outcome)
}
