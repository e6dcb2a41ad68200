//! Command-line interface (DESIGN.md §5): the arguments (clap), resolved into the
//! configuration's overrides, dispatched to [`super::commands`].

// The doc comments of the command-line types are clap's help texts, written for the terminal
// (`[diagnose] starts` is a TOML table, `<name>` a placeholder), not rustdoc links or HTML.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use super::commands;
use crate::config::load;
use crate::config::DiagnoseOverrides;
use crate::config::{Overrides, RunOptions, StartChoice};
use crate::error::{Error, Result};
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
        /// Most replicates of a test whose p-value after --bootstrap is at most alpha/2
        /// (default: [diagnose] bootstrap_extended, else none; 639 = 4 x 160 - 1 at the default
        /// --bootstrap). Opt-in: 8 false alarms in the 200-set null battery against 7 without,
        /// but 2-4 times as long on a set with an effect
        #[arg(long)]
        bootstrap_extended: Option<usize>,
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
        /// The laboratory: identical specimens; specimens with their own creep rate and
        /// ductility, replicates and a reading error growing with strain; or those with their
        /// own onset of tertiary creep too (`shapes`).
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
        /// Scenario of every set (default: cycle through none, constant_load,
        /// loading_strain, dislocation_damage, none, stress_ductility, primary_transient,
        /// mid_life_step). `--scenario none` measures the false-alarm rate alone.
        #[arg(long)]
        scenario: Option<String>,
        /// Specimen effects of every set's likelihood analyses (comma-separated kinds:
        /// rate, ductility, coarsening), written into each set's configuration: the battery
        /// then measures that configuration's calibration (default: the world's own,
        /// `auto` in `specimens`, all three in `shapes`).
        #[arg(long, value_enum, value_delimiter = ',')]
        specimen_effects: Option<Vec<crate::likelihood::EffectKind>>,
        /// `[objective] specimen_scatter` of every set's configuration
        /// (`beyond_stress_trend`, the default, or `likelihood`): the battery measures that
        /// estimate's calibration.
        #[arg(long, value_enum, default_value = "beyond_stress_trend")]
        specimen_scatter: crate::likelihood::SpecimenScatter,
        /// `[diagnose] bootstrap_extended` of every set's configuration: the battery
        /// measures the calibration of sampling a test close to significance on to so many
        /// replicates (639 at the default bootstrap).
        #[arg(long)]
        bootstrap_extended: Option<usize>,
        /// `[diagnose] max_points` of every set's configuration (default 100): the battery
        /// measures the calibration of `diagnose` on curves reduced to at most so many points
        /// (600: the generated logged curves whole).
        #[arg(long)]
        diagnose_max_points: Option<usize>,
        /// `[diagnose] reduction` of every set's configuration (default `local_quadratic`):
        /// the battery measures the calibration of `diagnose` on curves reduced to group means
        /// compared with the model's means (`means`; `strain_means`: groups spanning equal
        /// strain ranges, each weighed by its size).
        #[arg(long, value_enum)]
        diagnose_reduction: Option<crate::data::Reduction>,
        /// `[diagnose] misfit_share` of every set's configuration (default `white`): how
        /// `strain_means`' group means are weighed (`estimate`: the share of the reading
        /// error that averaging does not shrink, from the base fit; experimental).
        #[arg(long, value_enum)]
        diagnose_misfit_share: Option<crate::data::MisfitShare>,
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
        /// Tests to predict and score: a rupture-times file (ruptures format:
        /// temperature_C,stress_MPa,rupture_time_h[,specimen]), e.g. another campaign's. Each
        /// test's condition is predicted (instead of --at / [predict] at), its measured life
        /// compared with creepfit's and every classical baseline's in tests.csv, and their mean
        /// |log10 error| in summary.json (`tests`).
        #[arg(long, value_name = "FILE", conflicts_with = "at")]
        tests: Option<PathBuf>,
        /// Add the 95 % prediction interval of a new test and the 95 % confidence interval
        /// of the model's prediction (profile likelihood) to predictions.csv. The run is
        /// journaled (journal.jsonl) and resumes in the same folder after an interruption.
        #[arg(long)]
        intervals: bool,
        /// Output folder (default results/<name>/predict/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bars (drawn on stderr only when it is a terminal).
        #[arg(long, short)]
        quiet: bool,
        /// Stop after this many new journal records, as if interrupted (for tests of
        /// resumption; with --intervals).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// Leave one temperature (or one campaign) out: fit on the others, predict the held-out
    /// tests' rupture times and curves, and compare with the classical baselines (Larson–Miller,
    /// Orr–Sherby–Dorn, Manson–Haferd; Wilshire with [predict] tensile_strength) fitted to the
    /// same training rupture times; the best of them is named the one to beat.
    #[command(group(clap::ArgGroup::new("left_out").required(true).args(["temperature", "campaign"])))]
    Holdout {
        /// Run configuration (TOML).
        config: PathBuf,
        /// The temperature to leave out, °C.
        #[arg(long)]
        temperature: Option<f64>,
        /// The campaign to leave out: every test whose specimen label is NAME or NAME-… (e.g.
        /// INL2 for INL2-a, INL2-b), at whatever temperature.
        #[arg(long, value_name = "NAME")]
        campaign: Option<String>,
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
        /// Output folder (default results/<name>/holdout-<T>C/, or holdout-campaign-<NAME>/).
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
            commands::fit(&config, &cli)
        }
        Command::Simulate {
            config,
            constants,
            out,
            w,
        } => commands::simulate(&config, constants, &out_only(out), w),
        Command::Predict {
            config,
            constants,
            at,
            tests,
            intervals,
            out,
            threads,
            quiet,
            stop_after,
        } => {
            let mut at = at
                .map(|s| {
                    crate::data::Condition::parse_list(&s)
                        .map_err(|m| Error::Invalid(format!("--at: {m}")))
                })
                .transpose()?;
            let tests = match tests {
                Some(file) => {
                    let records = crate::predict::measured::read(&file)?;
                    at = Some(crate::predict::measured::conditions(&records));
                    Some((file, records))
                }
                None => None,
            };
            let mut cli = Overrides {
                predict_at: at,
                predict_intervals: intervals.then_some(true),
                ..long_run(out, quiet, stop_after)
            };
            cli.run.threads = threads;
            commands::predict(&config, &constants, tests.as_ref(), &cli)
        }
        Command::Holdout {
            config,
            temperature,
            campaign,
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
            let left_out = match (temperature, campaign) {
                (Some(t), _) => crate::holdout::LeftOut::Temperature(t),
                (None, Some(name)) => crate::holdout::LeftOut::Campaign(name),
                (None, None) => unreachable!("clap requires --temperature or --campaign"),
            };
            commands::holdout(&config, &left_out, &cli)
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
            commands::sweep(&cfg, &data)
        }
        Command::Merge {
            dirs,
            out,
            require_all,
        } => commands::merge(&dirs, &out, require_all),
        Command::Diagnose {
            config,
            out,
            starts,
            seed,
            bootstrap,
            bootstrap_extended,
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
                    bootstrap_extended,
                    alpha,
                },
                ..long_run(out, quiet, stop_after)
            };
            cli.run.threads = threads;
            commands::diagnose(&config, &cli)
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
            commands::profile(&config, constants.as_deref(), &cli)
        }
        Command::Synth {
            out,
            sets,
            seed,
            scenario,
            world,
        } => commands::synth(&out, sets, seed, scenario.as_deref(), world),
        Command::Battery {
            out,
            sets,
            seed,
            threads,
            world,
            scenario,
            specimen_effects,
            specimen_scatter,
            bootstrap_extended,
            diagnose_max_points,
            diagnose_reduction,
            diagnose_misfit_share,
            quiet,
        } => commands::with_threads(threads, || {
            commands::battery(
                &out,
                sets,
                seed,
                world,
                scenario.as_deref(),
                &crate::battery::SetOverrides {
                    effects: specimen_effects,
                    scatter: specimen_scatter,
                    bootstrap_extended,
                    max_points: diagnose_max_points,
                    reduction: diagnose_reduction,
                    misfit_share: diagnose_misfit_share,
                },
                quiet,
            )
        }),
    }
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
