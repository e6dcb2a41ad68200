//! Command-line interface (DESIGN.md §5): argument parsing and the commands, which call the
//! library and write the output files.

// The doc comments of the command-line types are clap's help texts, written for the terminal
// (`[diagnose] starts` is a TOML table, `<name>` a placeholder), not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};

use crate::config::load;
use crate::config::DiagnoseOverrides;
use crate::config::{Overrides, RunConfig, RunOptions, StartChoice};
use crate::data::note_data;
use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::fit::FitSettings;
use crate::journal::take_with_journal;
use crate::model::objective::Objective;
use crate::model::Load;
use crate::ode::OdeOptions;
use crate::output::RunFolder;
use crate::predict::diagrams::Diagrams;
use crate::predict::{curve_plots, PLOT_POINTS};
use crate::progress::stop_after;
use crate::progress::Bars;
use crate::report::plot::{plot_creep_curves, plot_curve_residuals, CurveId, CurveSeries};
use crate::report::tables::write_timings;
use crate::report::tables::{self, num, write_csv, write_text};
use crate::sweep;

/// creepfit: calibrate creep-damage constitutive equations against measured creep curves.
#[derive(Debug, Parser)]
#[command(name = "creepfit", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// The paper's procedure: initial guess, a local bounded LM fit for every w, the best w.
    Fit {
        /// Run configuration (TOML).
        config: PathBuf,
        /// Output folder (default results/<name>/fit/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Start points: the configuration's, the computed initial guess, or both.
        #[arg(long, value_enum, default_value_t = StartChoice::Both)]
        start: StartChoice,
        /// One lifetime weight w for every curve instead of the configured w_grid/w_sets.
        #[arg(long)]
        w: Option<f64>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
    },
    /// Multistart: Latin-hypercube starts × w candidates, a local fit from each, in parallel.
    Sweep {
        /// Run configuration (TOML).
        config: PathBuf,
        /// Latin-hypercube starts (default: the configuration's [sweep] starts).
        #[arg(long)]
        starts: Option<usize>,
        /// Seed of the starts (default: the configuration's [sweep] seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Run the I-th of N disjoint parts of the start set, e.g. 2/3; `auto` takes I and N
        /// from a job array's environment (Slurm, Grid Engine, AWS Batch) and writes into
        /// `shard-I-of-N/` inside the output folder.
        #[arg(long, value_parser = parse_shard)]
        shard: Option<sweep::ShardArg>,
        /// Output folder (default results/<name>/sweep/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Stop after this many new fits, as if interrupted (for tests of resumption).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
    },
    /// Combine the journals of sweep shards into the unsharded result.
    Merge {
        /// Shard output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output folder of the merged result.
        #[arg(long)]
        out: PathBuf,
        /// Refuse (write nothing, exit non-zero) unless every shard is complete.
        #[arg(long)]
        require_all: bool,
    },
    /// What the calibrated model gets wrong, the named cause, and what an extension gains.
    Diagnose {
        /// Run configuration (TOML).
        config: PathBuf,
        /// Output folder (default results/<name>/diagnose/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Latin-hypercube starts per model (default: [diagnose] starts).
        #[arg(long)]
        starts: Option<usize>,
        /// Seed of the starts and the bootstrap (default: [diagnose] seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Most bootstrap replicates (default: [diagnose] bootstrap).
        #[arg(long)]
        bootstrap: Option<usize>,
        /// False-alarm level (default: [diagnose] alpha).
        #[arg(long)]
        alpha: Option<f64>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
        /// Stop after this many new journal records, as if interrupted (for tests of
        /// resumption).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// How sure the constants and predictions are: profile likelihoods, intervals,
    /// identifiability, well-determined combinations, prediction intervals.
    Profile {
        /// Run configuration (TOML).
        config: PathBuf,
        /// constants.csv (name,value,…) to start the maximum-likelihood fit from (default: a
        /// multistart).
        #[arg(long)]
        constants: Option<PathBuf>,
        /// Output folder (default results/<name>/profile/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
        /// Stop after this many new journal records, as if interrupted (for tests of
        /// resumption).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// Generate synthetic data sets with known hidden effects (input formats + truth.json).
    Synth {
        /// Output folder: one sub-folder per set.
        out: PathBuf,
        /// Number of sets.
        #[arg(long, default_value_t = 8)]
        sets: usize,
        /// Seed of the first set (set i has seed SEED + i).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Scenario of every set (default: cycle through the battery's): none, constant_load,
        /// loading_strain, dislocation_damage, stress_ductility, primary_transient,
        /// mid_life_step, strain_softening, rupture_damage.
        #[arg(long)]
        scenario: Option<String>,
        /// The laboratory: identical specimens, or specimens with their own creep rate and
        /// ductility, replicates and a reading error growing with strain.
        #[arg(long, value_enum, default_value_t = crate::synth::World::Identical)]
        world: crate::synth::World,
    },
    /// Generate a battery of data sets, diagnose each, and write the confusion matrix and
    /// power tables (resumes an interrupted battery in the same folder).
    Battery {
        /// Output folder.
        out: PathBuf,
        /// Number of sets.
        #[arg(long, default_value_t = 40)]
        sets: usize,
        /// Seed of the first set (set i has seed SEED + i).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// The laboratory the sets come from (see `synth --world`).
        #[arg(long, value_enum, default_value_t = crate::synth::World::Identical)]
        world: crate::synth::World,
        /// No progress bar and no line per set.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Predict at untested conditions: curves, rupture time, rupture strain and minimum
    /// creep rate, beside the classical baselines (Larson–Miller, Orr–Sherby–Dorn,
    /// Manson–Haferd, Wilshire) fitted to the configuration's rupture times.
    Predict {
        /// Run configuration (TOML).
        config: PathBuf,
        /// constants.csv of a fit (name,value,…).
        #[arg(long)]
        constants: PathBuf,
        /// Conditions T:stress in °C:MPa, comma-separated, e.g. 575:100,560:70 (default: the
        /// configuration's [predict] at).
        #[arg(long, allow_hyphen_values = true)]
        at: Option<String>,
        /// Add the 95 % prediction interval of a new test and the 95 % confidence interval
        /// of the model's prediction (profile likelihood) to predictions.csv.
        #[arg(long)]
        intervals: bool,
        /// Output folder (default results/<name>/predict/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
    },
    /// Leave one temperature out: fit on the others, predict the held-out tests' rupture
    /// times and curves, and compare with the classical baselines (Larson–Miller,
    /// Orr–Sherby–Dorn, Manson–Haferd; Wilshire with [predict] tensile_strength) fitted to the
    /// same training rupture times; the best of them is named the one to beat.
    Holdout {
        /// Run configuration (TOML).
        config: PathBuf,
        /// The temperature to leave out, °C.
        #[arg(long)]
        temperature: f64,
        /// Latin-hypercube starts of the fit besides the guess (default: [sweep] starts).
        #[arg(long)]
        starts: Option<usize>,
        /// Seed of the starts (default: [sweep] seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Add the 95 % intervals of each held-out rupture time (prediction interval of a new
        /// test, confidence interval of the model's prediction) from the training data, and
        /// count the measured lives inside (default: [predict] intervals).
        #[arg(long)]
        intervals: bool,
        /// Output folder (default results/<name>/holdout-<T>C/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
        /// Stop after this many new journal records, as if interrupted (for tests of
        /// resumption).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// Simulate the configured tests with given constants (dense curves, ruptures).
    Simulate {
        /// Run configuration (TOML).
        config: PathBuf,
        /// constants.csv (name,value,…); default: the configuration's start values.
        #[arg(long)]
        constants: Option<PathBuf>,
        /// Output folder (default results/<name>/simulate/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also print the eq. 8 objective with this lifetime weight w on every curve.
        #[arg(long)]
        w: Option<f64>,
    },
}

/// Command-line settings that only say where the outputs go.
fn out_only(out: Option<PathBuf>) -> Overrides {
    Overrides {
        run: RunOptions {
            out,
            ..RunOptions::default()
        },
        ..Overrides::default()
    }
}

/// Command-line settings of a long command: where the outputs go, whether progress is drawn
/// (not under `--quiet`), and the test-only stop.
fn long_run(out: Option<PathBuf>, quiet: bool, stop_after: Option<usize>) -> Overrides {
    Overrides {
        run: RunOptions {
            out,
            progress: !quiet,
            stop_after,
            ..RunOptions::default()
        },
        ..Overrides::default()
    }
}

/// `Ok` if every plot was written, else the error saying the numbers are in `out`.
fn plots_done(out: &Path, failures: Vec<String>) -> Result<()> {
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::PlotsNotWritten {
            out: out.to_path_buf(),
            failures,
        })
    }
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Fit {
            config,
            out,
            start,
            w,
            quiet,
        } => {
            let cli = Overrides {
                w,
                fit_starts: Some(start),
                ..long_run(out, quiet, None)
            };
            fit(&config, &cli)
        }
        Command::Simulate {
            config,
            constants,
            out,
            w,
        } => simulate(&config, constants, &out_only(out), w),
        Command::Predict {
            config,
            constants,
            at,
            intervals,
            out,
            quiet,
        } => {
            let at = at
                .map(|s| {
                    crate::data::Condition::parse_list(&s)
                        .map_err(|m| Error::Invalid(format!("--at: {m}")))
                })
                .transpose()?;
            let cli = Overrides {
                predict_at: at,
                predict_intervals: intervals.then_some(true),
                ..long_run(out, quiet, None)
            };
            predict_cmd(&config, &constants, &cli)
        }
        Command::Holdout {
            config,
            temperature,
            starts,
            seed,
            intervals,
            out,
            quiet,
            stop_after,
        } => {
            let cli = Overrides {
                starts,
                seed,
                predict_intervals: intervals.then_some(true),
                ..long_run(out, quiet, stop_after)
            };
            crate::holdout::holdout_cmd(&config, temperature, &cli)
        }
        Command::Sweep {
            config,
            starts,
            seed,
            threads,
            shard,
            out,
            stop_after,
            quiet,
        } => {
            let auto = shard == Some(sweep::ShardArg::Auto);
            let shard = match shard {
                None => None,
                Some(sweep::ShardArg::Part(i, n)) => Some((i, n)),
                Some(sweep::ShardArg::Auto) => Some(sweep::array::shard_from_process_env()?),
            };
            let given_out = out.clone();
            let cli = Overrides {
                starts,
                seed,
                run: RunOptions {
                    out,
                    threads,
                    shard,
                    stop_after,
                    progress: !quiet,
                },
                ..Overrides::default()
            };
            let (mut cfg, data) = load(&config, &cli)?;
            // Where this part writes: `--shard auto` into shard-I-of-N/ of the output folder.
            let default_dir = PathBuf::from("results").join(&cfg.name).join("sweep");
            let out = sweep::part_dir(shard, auto, given_out, default_dir);
            if let (true, Some((i, n))) = (auto, shard) {
                println!("shard {i}/{n} of the job array into {}", out.display());
            }
            cfg.run.out = Some(out);
            sweep_cmd(&cfg, &data)
        }
        Command::Merge {
            dirs,
            out,
            require_all,
        } => merge_cmd(&dirs, &out, require_all),
        Command::Diagnose {
            config,
            out,
            starts,
            seed,
            bootstrap,
            alpha,
            threads,
            quiet,
            stop_after,
        } => {
            let mut cli = Overrides {
                diagnose: DiagnoseOverrides {
                    starts,
                    seed,
                    bootstrap,
                    alpha,
                },
                ..long_run(out, quiet, stop_after)
            };
            cli.run.threads = threads;
            diagnose_cmd(&config, &cli)
        }
        Command::Profile {
            config,
            constants,
            out,
            threads,
            quiet,
            stop_after,
        } => {
            let mut cli = long_run(out, quiet, stop_after);
            cli.run.threads = threads;
            let (cfg, data) = load(&config, &cli)?;
            with_threads(cfg.run.threads, || {
                crate::uncertainty::report::profile_command(&cfg, &data, constants.as_deref())
            })
        }
        Command::Synth {
            out,
            sets,
            seed,
            scenario,
            world,
        } => synth_cmd(&out, sets, seed, scenario.as_deref(), world),
        Command::Battery {
            out,
            sets,
            seed,
            threads,
            world,
            quiet,
        } => with_threads(threads, || {
            // One writer, one battery per folder: the lock, then the identity (refused before
            // anything changes), then the folder is this run's (what it resumes from kept).
            let lock = crate::output::lock_folder(&out)?;
            let id = serde_json::json!({
                "command": "battery",
                "seed": seed,
                "world": world,
                "scenarios": crate::synth::SCENARIOS,
                "version": env!("CARGO_PKG_VERSION"),
            });
            crate::identity::bind_folder(&out, BATTERY_IDENTITY, "results.jsonl", &id)?;
            let folder = RunFolder::take_over(lock, "battery", &|f| {
                f == BATTERY_IDENTITY || f == "results.jsonl" || f.starts_with("sets/")
            })?;
            crate::output::record(&out.join(BATTERY_IDENTITY));
            let outcome = battery_into(&out, sets, seed, world, quiet);
            folder.finish(outcome)
        }),
    }
}

/// File of a battery folder that holds its run identity (first seed, scenarios, version).
pub const BATTERY_IDENTITY: &str = "battery.json";

/// `battery`'s computation and outputs into `out` (its generated sets and the appended
/// `results.jsonl` are recorded in the manifest as written by the run).
fn battery_into(
    out: &Path,
    sets: usize,
    seed: u64,
    world: crate::synth::World,
    quiet: bool,
) -> Result<()> {
    let out = out.to_path_buf();
    let record_all = |out: &Path| {
        crate::output::record(&out.join("results.jsonl"));
        fn walk(d: &Path) {
            for e in std::fs::read_dir(d).into_iter().flatten().flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(&p);
                } else {
                    crate::output::record(&p);
                }
            }
        }
        walk(&out.join("sets"));
    };
    let bars = Bars::new(quiet);
    let results = crate::battery::run_battery_observed(&out, seed, sets, world, &bars);
    bars.clear();
    record_all(&out);
    let results = results?;
    let r = crate::battery::write_reports(&out, &results, seed)?;
    println!(
        "{} sets: false alarms {} of {} no-effect sets; named correctly (detectable): {}; outside the catalogue with an extension verdict: {} of {}",
        results.len(),
        r.false_alarms,
        r.null_sets,
        r.named
            .iter()
            .map(|(e, _, d, k)| format!("{e} {k}/{d}"))
            .collect::<Vec<_>>()
            .join(", "),
        r.outside_extension,
        r.outside_sets
    );
    println!("wrote {}", out.display());
    Ok(())
}

/// The distinct test temperatures of the data, °C, ascending.
fn temperatures(data: &Dataset) -> Vec<f64> {
    let mut t: Vec<f64> = data.curves.iter().map(|c| c.temperature_c).collect();
    t.sort_by(f64::total_cmp);
    t.dedup();
    t
}

/// Run `f` on a pool of `threads` workers (rayon's default pool when `None`).
fn with_threads<T: Send>(
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

fn diagnose_cmd(config: &Path, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    diagnose_check(&cfg, &data)?;
    let out = cfg.out_dir("diagnose");
    let (mut folder, journal) =
        take_with_journal(&out, "diagnose", &crate::diagnose::hooks::identity(&cfg))?;
    note_data(&mut folder, &data);
    let bars = Bars::new(!cfg.run.progress);
    let stop = stop_after(&bars, &journal, cfg.run.stop_after);
    let hooks = crate::diagnose::Hooks {
        observer: &stop,
        journal: Some(&journal),
    };
    let outcome = diagnose_into(&cfg, &data, &out, &hooks, &bars);
    folder.finish(outcome)
}

/// What `diagnose` refuses before it starts: data at several temperatures without a
/// temperature law.
pub fn diagnose_check(cfg: &RunConfig, data: &Dataset) -> Result<()> {
    let temps = temperatures(data);
    if temps.len() > 1 && !cfg.has_laws() {
        return Err(Error::config(
            &cfg.path,
            format!(
                "temperature_C: diagnose works at one temperature unless a constant follows a temperature law; the data have {} ({} °C): set temperature_C",
                temps.len(),
                temps.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    Ok(())
}

/// `diagnose`'s computation and outputs into `out`.
fn diagnose_into(
    cfg: &RunConfig,
    data: &Dataset,
    out: &Path,
    hooks: &crate::diagnose::Hooks,
    bars: &Bars,
) -> Result<()> {
    let d = with_threads(cfg.run.threads, || {
        crate::diagnose::diagnose_observed(cfg, data, &cfg.diagnose, hooks)
    });
    bars.clear();
    let d = d?;
    write_text(
        &out.join("diagnosis.json"),
        &serde_json::to_string_pretty(&d).expect("JSON of plain values"),
    )?;
    write_timings(
        out,
        "diagnose",
        hooks.journal,
        serde_json::json!({ "wall_s": d.wall_s, "phase_s": d.phase_s }),
    )?;
    let md = crate::diagnose::report::report_md(cfg, &d);
    write_text(&out.join("report.md"), &md)?;
    // Residual plots of the base model and of the chosen (else lowest-AIC) extension, on
    // the curves diagnose worked on.
    let mut failures = Vec::new();
    let chosen = d
        .candidates
        .iter()
        .find(|c| Some(&c.name) == d.cause.as_ref())
        .or_else(|| {
            d.candidates
                .iter()
                .filter(|c| c.aic.is_finite())
                .min_by(|a, b| a.aic.total_cmp(&b.aic))
        });
    let curves: Vec<crate::data::Curve> = data
        .curves
        .iter()
        .map(|c| crate::data::binned(c, cfg.diagnose.max_points))
        .collect();
    for c in std::iter::once(&d.base).chain(chosen) {
        let mut exts = cfg.extensions.clone();
        if c.name != "base" {
            exts.push(c.name.clone());
        }
        let model = cfg.build_model_with(&exts)?;
        let x: Vec<f64> = c.constants.iter().map(|p| p.1).collect();
        let settings = FitSettings::from_config(cfg);
        let obj = crate::likelihood::raw_objective(model.as_ref(), &curves, &settings);
        let ev = obj.evaluate(&x);
        let series: Vec<CurveSeries> = curves
            .iter()
            .zip(&ev.curves)
            .map(|(cu, p)| CurveSeries {
                id: CurveId::of(cu),
                points: tables::thin(
                    (0..cu.times_h.len())
                        .map(|k| {
                            (
                                cu.times_h[k] / cu.life_h(),
                                100.0 * (p.strain[k] - cu.strains[k]) / cu.rupture_strain,
                            )
                        })
                        .collect(),
                    PLOT_POINTS,
                ),
            })
            .collect();
        let path = out.join(format!("residuals_{}.png", c.name));
        if let Err(e) = plot_curve_residuals(
            &path,
            &format!("{}: residuals of {}", cfg.name, c.name),
            &series,
            "t / t_f",
            "predicted − measured, % of rupture strain",
        ) {
            failures.push(e.to_string());
        }
    }
    print!("{md}");
    println!("wrote {}", out.display());
    plots_done(out, failures)
}

fn synth_cmd(
    out: &Path,
    sets: usize,
    seed: u64,
    scenario: Option<&str>,
    world: crate::synth::World,
) -> Result<()> {
    if let Some(sc) = scenario {
        if !crate::synth::SCENARIOS.contains(&sc) {
            return Err(crate::Error::Invalid(format!(
                "--scenario: unknown scenario '{sc}' (known: {})",
                crate::synth::SCENARIOS.join(", ")
            )));
        }
    }
    for i in 0..sets {
        let s = seed + i as u64;
        let sc = scenario.unwrap_or_else(|| crate::synth::scenario_of(i));
        let name = format!("set-{s}");
        let set = crate::synth::generate_in(&name, sc, None, s, world)?;
        crate::synth::write_set(&set, &out.join(&name))?;
        println!(
            "{name}: {} ({}), {} curves, {:?}",
            sc,
            set.truth.family,
            set.truth.stresses.len(),
            set.truth.sampling
        );
    }
    println!("wrote {}", out.display());
    Ok(())
}

fn parse_shard(s: &str) -> std::result::Result<sweep::ShardArg, String> {
    if s.trim() == "auto" {
        return Ok(sweep::ShardArg::Auto);
    }
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 2/3, or auto")?;
    let i: usize = i
        .trim()
        .parse()
        .map_err(|_| format!("bad shard index '{i}'"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("bad shard count '{n}'"))?;
    if i == 0 || n == 0 || i > n {
        return Err(format!("shard {i}/{n}: need 1 <= I <= N"));
    }
    Ok(sweep::ShardArg::Part(i, n))
}

fn sweep_cmd(cfg: &RunConfig, data: &Dataset) -> Result<()> {
    sweep::install_sigint_handler();
    let out = cfg.out_dir("sweep");
    let (plan, mut run) = sweep::run_sweep(cfg, data)?;
    note_data(&mut run.folder, data);
    let outcome = sweep_outputs(cfg, &plan, &run, &out);
    run.folder.finish(outcome)
}

/// A sweep's outputs into `out`; an interrupted sweep is an error after them.
fn sweep_outputs(
    cfg: &RunConfig,
    plan: &sweep::Plan,
    run: &sweep::SweepRun,
    out: &Path,
) -> Result<()> {
    let out = out.to_path_buf();
    let mut header = plan.header.clone();
    header.shard = cfg.run.shard.unwrap_or((1, 1));
    let coverage = sweep::part_coverage(&header, header.shard, run.solutions.len(), &out);
    let (a, failures) = sweep::write_outputs(
        &header,
        &run.solutions,
        &out,
        run.wall_s,
        run.threads,
        &coverage,
    )?;
    print_sweep(&header, &a);
    println!(
        "{} fits computed now in {:.1} s on {} threads ({:.2} fits/s); {} in the folder",
        run.computed,
        run.wall_s,
        run.threads,
        run.computed as f64 / run.wall_s.max(1e-9),
        run.solutions.len()
    );
    if run.missing > 0 {
        return Err(Error::Invalid(format!(
            "interrupted: {} of {} fits missing (summary.json: \"complete\": false); rerun the same command to resume ({})",
            run.missing,
            run.missing + run.solutions.len(),
            out.display()
        )));
    }
    println!("wrote {}", out.display());
    plots_done(&out, failures)
}

fn merge_cmd(dirs: &[PathBuf], out: &Path, require_all: bool) -> Result<()> {
    let m = sweep::merge(dirs)?;
    for d in &m.skipped {
        eprintln!("merge: {}: no sweep journal, skipped", d.display());
    }
    for s in &m.coverage.missing {
        let state = match s.state {
            sweep::ShardState::Incomplete => "incomplete",
            sweep::ShardState::Absent => "absent",
        };
        let dir = s.dir.as_ref().map(|d| format!(" ({})", d.display()));
        eprintln!(
            "merge: shard {}/{} {state}: {} of {} fits{}",
            s.shard,
            s.of,
            s.fits_done,
            s.fits_expected,
            dir.unwrap_or_default()
        );
    }
    let n = m.merged.len() + m.coverage.missing.len();
    let list = |v: Vec<usize>| {
        v.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !m.coverage.complete && (require_all || m.merged.is_empty()) {
        return Err(Error::Invalid(format!(
            "merge{}: {} of {n} shards complete (missing or incomplete: {}); nothing written",
            if require_all { " --require-all" } else { "" },
            m.merged.len(),
            list(m.coverage.missing.iter().map(|s| s.shard).collect())
        )));
    }
    let folder = RunFolder::begin(out, "merge")?;
    folder.finish(merge_into(&m, out))
}

/// `merge`'s outputs into `out`.
fn merge_into(m: &sweep::Merged, out: &Path) -> Result<()> {
    let n = m.merged.len() + m.coverage.missing.len();
    let list = |v: Vec<usize>| {
        v.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (a, failures) = sweep::write_outputs(&m.header, &m.solutions, out, 0.0, 0, &m.coverage)?;
    print_sweep(&m.header, &a);
    if m.coverage.complete {
        println!("merged {n} of {n} shards into {}", out.display());
    } else {
        let expected = m.header.n_starts_total() * m.header.w.len();
        eprintln!(
            "merge: partial result: shards {} of {n} ({} of {expected} fits); summary.json says complete: false",
            list(m.merged.iter().map(|p| p.0).collect()),
            m.solutions.len()
        );
        println!(
            "merged {} of {n} shards into {} (partial)",
            m.merged.len(),
            out.display()
        );
    }
    plots_done(out, failures)
}

fn print_sweep(h: &sweep::Header, a: &sweep::Analysis) {
    println!(
        "{}: {} fits ({} starts × {} w), {} completed, {} failed, {} distinct minima",
        h.name,
        a.ranked.len(),
        h.n_starts_total(),
        h.w.len(),
        a.completed,
        a.failed,
        a.clusters.len()
    );
    if a.completed == 0 {
        return;
    }
    let b = &a.ranked[0];
    println!(
        "best: objective {:.6} at w = {:?} (start {}), normalised residual {:.6}, mean |lifetime err| {:.2} %, best basin holds {:.1} % of the fits",
        b.objective,
        h.w[b.w_idx],
        b.start_id,
        b.norm_residual,
        b.lifetime_err_pct,
        100.0 * a.clusters[0].fraction
    );
    for (n, side, v) in &a.pinned {
        println!("  {n} = {v:.6e} on its {side} bound");
    }
    println!(
        "within 1 % of the best objective: {} solutions; spread of the constants:",
        a.near_best
    );
    for s in &a.spreads {
        println!(
            "  {:>6}: {:.4e} .. {:.4e}  (relative range {:.3}, {:.3} of the box)",
            s.name, s.min, s.max, s.rel_range, s.unit_range
        );
    }
    println!("Pareto set (normalised residual, mean |lifetime err| %, mean |min-rate err| %):");
    for i in (0..a.ranked.len()).filter(|&i| a.pareto[i]).take(15) {
        let s = &a.ranked[i];
        println!(
            "  rank {:>4}  F {:.5}  res {:.5}  life {:>6.2}  rate {:>7.2}  lifetime errors {:?}",
            i + 1,
            s.objective,
            s.norm_residual,
            s.lifetime_err_pct,
            s.min_rate_err_pct,
            s.lifetime_errs_pct
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
    }
}

/// `summary.json`'s `activation_energy` in one line: the ranges over the tested loads.
fn print_activation(a: &serde_json::Value) {
    let range = |side: &str, key: &str| -> String {
        let v: Vec<f64> = a[side]
            .as_array()
            .map(|v| v.iter().filter_map(|x| x[key].as_f64()).collect())
            .unwrap_or_default();
        if v.is_empty() {
            return "-".into();
        }
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        format!("{lo:.0}–{hi:.0}")
    };
    println!(
        "apparent activation energy (kJ/mol; −R ∂ln ε̇_min/∂(1/T), R ∂ln t_r/∂(1/T) at the tested loads; summary.json: activation_energy): model: min rate {}, rupture time {}; data (a stress tested at several temperatures): min rate {}, rupture time {}",
        range("model", "q_min_rate_kj_mol"),
        range("model", "q_rupture_time_kj_mol"),
        range("data", "q_min_rate_kj_mol"),
        range("data", "q_rupture_time_kj_mol"),
    );
}

/// The scatter between specimens a likelihood fit found, in words.
fn print_specimens(sp: &crate::fit::FitSpecimens) {
    if let Some(f) = &sp.fit {
        for (j, k) in f.kinds.iter().enumerate() {
            let what = match k {
                crate::likelihood::EffectKind::Rate => "creep rate",
                crate::likelihood::EffectKind::Ductility => "rupture strain (ductility)",
            };
            println!(
                "specimens: the {what} varies {:.0} % between specimens (sd of ln factor {:.3}, 95 % {:.3}–{:.3}; specimens.csv: each specimen's factor)",
                tables::lognormal_cv_pct(f.scatter[j]),
                f.scatter[j],
                f.scatter_lo95[j],
                f.scatter_hi95[j]
            );
        }
        for k in &f.dropped {
            println!("specimens: no {k:?} scatter supported by the data (estimated at zero)");
        }
    }
    if let Some(n) = &sp.note {
        println!("specimens: {n}");
    }
}

fn fit(config: &Path, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    let out = cfg.out_dir("fit");
    let mut folder = RunFolder::begin(&out, "fit")?;
    note_data(&mut folder, &data);
    folder.finish(fit_into(&cfg, &data, &out))
}

/// `fit`'s computation and outputs into `out`.
fn fit_into(cfg: &RunConfig, data: &Dataset, out: &Path) -> Result<()> {
    let out = out.to_path_buf();
    let bars = Bars::new(!cfg.run.progress);
    let hooks = crate::progress::Hooks {
        observer: &bars,
        journal: None,
    };
    let run = crate::fit::run_fit_observed(cfg, data, 0, &hooks);
    bars.clear();
    let run = run?;
    let best = &run.fits[run.best];
    let curves = &data.curves;
    tables::write_constants(
        &out.join("constants.csv"),
        run.model.as_ref(),
        &run.space,
        &best.params,
        cfg.has_laws().then_some(cfg.t_ref).flatten(),
    )?;
    let rows = tables::error_rows(best, curves);
    tables::write_errors(&out.join("errors.csv"), &rows)?;
    tables::write_fit_curves(&out.join("curves.csv"), best, curves)?;
    let summary = tables::fit_summary(cfg, &run, curves);
    if let Some(sp) = &run.specimens.fit {
        tables::write_specimens(&out.join("specimens.csv"), sp, curves)?;
    }
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;

    println!(
        "{}: model {}, {} curves, {} local fits in {:.2} s",
        cfg.name,
        run.model.name(),
        curves.len(),
        run.fits.len(),
        run.wall_s
    );
    println!(
        "best: start {}, w = {:?}, objective {:.6}, normalised residual {:.6}, {} ({} iterations, {} evaluations)",
        best.start_label,
        best.w,
        best.eval.objective,
        best.eval.norm_residual,
        best.lm.termination.as_str(),
        best.lm.iterations,
        best.lm.evaluations
    );
    for (j, c) in run.model.constants().iter().enumerate() {
        let pin = if run.space.free[j] {
            run.space
                .at_bound(j, best.params[j], 1e-6)
                .map(|s| format!("  (at {s} bound)"))
                .unwrap_or_default()
        } else {
            "  (held)".to_string()
        };
        println!(
            "  {:>6} = {:<12.6e} {}{}",
            c.name, best.params[j], c.unit, pin
        );
    }
    print!("{}", tables::error_table(&rows, run.used_min_rate));
    print_specimens(&run.specimens);
    if let Some(a) = summary.get("activation_energy") {
        print_activation(a);
    }
    let per_t = crate::fit::errors_per_temperature(best, curves);
    if per_t.len() > 1 {
        for e in &per_t {
            let at = run.model.constants_at(&best.params, e.temperature_c);
            println!(
                "{:>6} °C: normalised residual {:.6}, mean |lifetime err| {:.2} %, mean |min-rate err| {:.2} %; constants there: {}",
                e.temperature_c,
                e.norm_residual,
                e.mean_lifetime_err_pct,
                e.mean_min_rate_err_pct,
                run.model
                    .inner_constants()
                    .iter()
                    .zip(&at)
                    .map(|(c, v)| format!("{} = {v:.4e}", c.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    if let Some(e) = summary.get("error_model").filter(|e| !e.is_null()) {
        let list = |key: &str, prec: usize| -> String {
            e["curves"]
                .as_array()
                .map(|v| {
                    v.iter()
                        .map(|c| format!("{:.prec$}", c[key].as_f64().unwrap_or(f64::NAN)))
                        .collect::<Vec<_>>()
                        .join(" / ")
                })
                .unwrap_or_default()
        };
        println!(
            "error model at these constants (AR(1) per curve): residual sd {} % strain, φ {}; \
             rupture-time scatter {:.2} % (summary.json: error_model)",
            list("residual_sd_pct", 4),
            list("ar1_phi", 2),
            e["lifetime_sd_pct"].as_f64().unwrap_or(f64::NAN)
        );
    }

    // Plot last: a plotting failure never loses the numeric outputs above.
    let plot_path = out.join("fit.png");
    let plots = curve_plots(
        cfg,
        data,
        &best.params,
        &run.settings.ode,
        run.model.as_ref(),
    );
    let plotted = plot_creep_curves(
        &plot_path,
        &format!("{} — measured (points) and fitted (lines)", cfg.name),
        &plots,
    );
    let mut failures: Vec<String> = plotted.err().map(|e| e.to_string()).into_iter().collect();
    // The diagrams beside the Larson–Miller baseline of the same rupture times (none at one
    // temperature).
    let lmp = crate::lmp::LarsonMiller::fit_curves(&data.curves, cfg.predict.lmp_degree).ok();
    failures.extend(
        Diagrams {
            cfg,
            data,
            model: run.model.as_ref(),
            params: &best.params,
            lmp: lmp.as_ref(),
            asked: &[],
            held_out_c: None,
        }
        .write(&out),
    );
    println!("wrote {}", out.display());
    plots_done(&out, failures)
}

fn predict_cmd(config: &Path, constants: &Path, cli: &Overrides) -> Result<()> {
    let (cfg, data) = load(config, cli)?;
    crate::predict::check_asked(&cfg)?;
    let model = cfg.build_model()?;
    let params = tables::read_constants_for(constants, &cfg, model.as_ref())?;
    // What the configuration can predict: refused before anything is written.
    crate::predict::check_conditions(&cfg, &data, cli.predict_at.is_some())?;
    let out = cfg.out_dir("predict");
    let mut folder = RunFolder::begin(&out, "predict")?;
    note_data(&mut folder, &data);
    folder.finish(predict_into(&cfg, &data, model.as_ref(), &params, &out))
}

/// `predict`'s computation and outputs into `out`: at the given constants, or under
/// `--intervals` at the maximum-likelihood refit the intervals are centred on (the given
/// constants' predictions beside).
fn predict_into(
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn crate::model::Model,
    params: &[f64],
    out: &Path,
) -> Result<()> {
    let tested = crate::baseline::Tested::of(data, cfg.has_laws());
    for n in crate::predict::extrapolation_notes(&tested, &cfg.predict.at) {
        eprintln!("warning: {n}");
    }
    let bars = Bars::new(!cfg.run.progress);
    let hooks = crate::progress::Hooks {
        observer: &bars,
        journal: None,
    };
    let run = crate::predict::run_observed(cfg, data, model, params, &hooks);
    bars.clear();
    let run = run?;
    println!("{}: model {}", cfg.name, model.name());
    let names: Vec<&str> = model.constants().iter().map(|c| c.name).collect();
    print!("{}", crate::predict::table(&run, &names));
    let failures = crate::predict::write_outputs(out, cfg, data, model, &run)?;
    println!("wrote {}", out.display());
    plots_done(out, failures)
}

fn simulate(
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
        Some(path) => tables::read_constants_for(&path, &cfg, model.as_ref())?,
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
    folder.finish(simulate_into(&cfg, &data, model.as_ref(), &params, w, &out))
}

/// `simulate`'s computation and outputs into `out`.
fn simulate_into(
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn crate::model::Model,
    params: &[f64],
    w: Option<f64>,
    out: &Path,
) -> Result<()> {
    let settings = FitSettings::from_config(cfg);
    let ode = settings.ode;
    let mut trajectories = Vec::new();
    let mut rupture_rows = Vec::new();
    let specimens = tables::has_specimens(&data.curves);
    let specimen =
        |c: &crate::data::Curve| specimens.then(|| c.specimen.clone().unwrap_or_default());
    for c in &data.curves {
        let load = Load::of_curve(c, cfg.objective.omega_f);
        let span = c
            .rupture_time_h
            .unwrap_or(0.0)
            .max(*c.times_h.last().unwrap_or(&0.0));
        let o = OdeOptions {
            t_end: crate::model::objective::HORIZON_FACTOR * span,
            ..ode
        };
        let res = model.simulate(params, &load, &[], &mut [], &o);
        let mut grid = crate::predict::dense_grid(res.t_end, 200);
        grid.extend(c.times_h.iter().copied().filter(|t| *t <= res.t_end));
        grid.sort_by(|a, b| a.total_cmp(b));
        grid.dedup();
        let (_, traj) = model.trajectory(params, &load, &grid, &o);
        trajectories.push((c, traj));
        rupture_rows.push(vec![
            num(c.temperature_c),
            num(c.stress_mpa),
            if res.ruptured() {
                num(res.t_end)
            } else {
                String::new()
            },
            if res.ruptured() {
                num(100.0 * res.strain_end)
            } else {
                String::new()
            },
            // A failed simulation has no minimum rate (only a rupture or the horizon do).
            if res.ruptured() || res.outcome == crate::ode::Outcome::Horizon {
                num(100.0 * res.min_rate)
            } else {
                String::new()
            },
            res.outcome.as_str().to_string(),
        ]);
        rupture_rows.last_mut().unwrap().extend(specimen(c));
        println!(
            "{} °C {:>6} MPa{}: {} at t = {:.1} h, strain {:.3} %, min rate {:.4e} %/h",
            c.temperature_c,
            c.stress_mpa,
            c.specimen
                .as_ref()
                .map(|s| format!(" (specimen {s})"))
                .unwrap_or_default(),
            res.outcome.as_str(),
            res.t_end,
            100.0 * res.strain_end,
            100.0 * res.min_rate
        );
    }
    // The model's output columns (H, Phi, omega for KHD) after the strain.
    let mut curve_header = vec!["temperature_C", "stress_MPa", "time_h", "strain_pct"];
    curve_header.extend(model.output_names());
    // Rows formatted as they are written (a logged curve gives a million of them).
    let curve_rows = trajectories.iter().flat_map(|(c, traj)| {
        traj.iter().map(|(t, e, y)| {
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(*t),
                num(100.0 * e),
            ];
            row.extend(y.iter().map(|v| num(*v)));
            row.extend(specimen(c));
            row
        })
    });
    tables::write_csv_rows(
        &out.join("curves.csv"),
        &tables::with_specimen(&curve_header, specimens),
        curve_rows,
    )?;
    let rupture_header = [
        "temperature_C",
        "stress_MPa",
        "rupture_time_h",
        "rupture_strain_pct",
        "min_rate_pct_per_h",
        "outcome",
    ];
    write_csv(
        &out.join("ruptures.csv"),
        &tables::with_specimen(&rupture_header, specimens),
        &rupture_rows,
    )?;
    if let Some(w) = w {
        let objective = Objective::new(
            model,
            &data.curves,
            vec![w; data.curves.len()],
            settings.objective(),
        );
        let e = objective.evaluate(params);
        println!(
            "objective {:.12e} at w = {w} (normalised residual {:.12e})",
            e.objective, e.norm_residual
        );
        let json = serde_json::json!({
            "w": w,
            "objective": e.objective,
            "norm_residual": e.norm_residual,
            "lifetime_errors_pct": e.lifetime_errors_pct(&data.curves),
        });
        write_text(
            &out.join("objective.json"),
            &serde_json::to_string_pretty(&json).expect("JSON of plain values"),
        )?;
    }
    let plots = curve_plots(cfg, data, params, &ode, model);
    let plotted = plot_creep_curves(
        &out.join("simulate.png"),
        &format!("{} — simulated", cfg.name),
        &plots,
    );
    println!("wrote {}", out.display());
    plots_done(
        out,
        plotted.err().map(|e| e.to_string()).into_iter().collect(),
    )
}
