//! Command-line interface (DESIGN.md §5): argument parsing and the commands, which call the
//! library and write the output files.

use std::path::{Path, PathBuf};

use clap::{Parser, Subcommand};

use crate::config::RunConfig;
use crate::data::{self, Dataset};
use crate::diagnose::{diagnose, DiagnoseOptions};
use crate::error::Result;
use crate::fit::{run_fit_with, FitRequest, StartChoice};
use crate::model::{build, Load};
use crate::ode::OdeOptions;
use crate::report::plot::{plot_creep_curves, plot_residuals, CurvePlot, Series};
use crate::report::tables::{self, default_out, ensure_dir, num, write_csv, write_text};
use crate::sweep::{self, SweepOptions};

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
        /// Run the I-th of N disjoint parts of the start set, e.g. 2/3.
        #[arg(long, value_parser = parse_shard)]
        shard: Option<(usize, usize)>,
        /// Output folder (default results/<name>/sweep/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Stop after this many new fits, as if interrupted (for tests of resumption).
        #[arg(long, hide = true)]
        stop_after: Option<usize>,
    },
    /// Combine the journals of sweep shards into the unsharded result.
    Merge {
        /// Shard output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output folder of the merged result.
        #[arg(long)]
        out: PathBuf,
    },
    /// What the calibrated model gets wrong, the named cause, and what an extension gains.
    Diagnose {
        /// Run configuration (TOML).
        config: PathBuf,
        /// Output folder (default results/<name>/diagnose/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Latin-hypercube starts per model (plus the initial guess).
        #[arg(long, default_value_t = 16)]
        starts: usize,
        /// Seed of the starts.
        #[arg(long, default_value_t = 1)]
        seed: u64,
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

/// Load a configuration and its data.
pub fn load(config: &Path) -> Result<(RunConfig, Dataset)> {
    let cfg = RunConfig::load(config)?;
    let data = data::load(&cfg.curves, &cfg.ruptures, &cfg.load_options())?;
    for w in &data.warnings {
        eprintln!("warning: {w}");
    }
    Ok((cfg, data))
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Fit {
            config,
            out,
            start,
            w,
        } => fit(&config, out, &FitRequest { starts: start, w }),
        Command::Simulate {
            config,
            constants,
            out,
            w,
        } => simulate(&config, constants, out, w),
        Command::Sweep {
            config,
            starts,
            seed,
            threads,
            shard,
            out,
            stop_after,
        } => {
            let (cfg, data) = load(&config)?;
            let opts = SweepOptions {
                starts: starts.unwrap_or(cfg.sweep.starts),
                seed: seed.unwrap_or(cfg.sweep.seed),
                threads,
                shard,
                out: out.unwrap_or_else(|| default_out(&cfg.name, "sweep")),
                stop_after,
                progress: true,
            };
            sweep_cmd(&cfg, &data, &opts)
        }
        Command::Merge { dirs, out } => merge_cmd(&dirs, &out),
        Command::Diagnose {
            config,
            out,
            starts,
            seed,
        } => diagnose_cmd(&config, out, &DiagnoseOptions { starts, seed }),
    }
}

fn diagnose_cmd(config: &Path, out: Option<PathBuf>, opts: &DiagnoseOptions) -> Result<()> {
    let (cfg, data) = load(config)?;
    let d = diagnose(&cfg, &data, opts)?;
    let out = out.unwrap_or_else(|| default_out(&cfg.name, "diagnose"));
    ensure_dir(&out)?;
    write_text(
        &out.join("diagnosis.json"),
        &serde_json::to_string_pretty(&d).expect("JSON of plain values"),
    )?;
    let md = crate::diagnose::report_md(&cfg, &d);
    write_text(&out.join("report.md"), &md)?;
    // Residual plots of the base model and of the chosen (else best-BIC) extension.
    let chosen = d
        .candidates
        .iter()
        .find(|c| Some(&c.name) == d.cause.as_ref())
        .or_else(|| d.candidates.iter().min_by(|a, b| a.bic.total_cmp(&b.bic)));
    for c in std::iter::once(&d.base).chain(chosen) {
        let exts: Vec<String> = if c.name == "base" {
            vec![]
        } else {
            vec![c.name.clone()]
        };
        let model = build(&cfg.model, &exts)?;
        let x: Vec<f64> = c.constants.iter().map(|p| p.1).collect();
        let settings = crate::fit::FitSettings::from_config(&cfg);
        let obj = crate::diagnose::objective(model.as_ref(), &data.curves, &settings);
        let ev = obj.evaluate(&x);
        let series: Vec<Series> = data
            .curves
            .iter()
            .zip(&ev.curves)
            .map(|(cu, p)| Series {
                label: format!("{} MPa", cu.stress_mpa),
                points: tables::thin(
                    (0..cu.times_h.len())
                        .map(|k| {
                            (
                                cu.times_h[k] / cu.life_h(),
                                100.0 * (cu.strains[k] - p.strain[k]) / cu.rupture_strain,
                            )
                        })
                        .collect(),
                    PLOT_POINTS,
                ),
            })
            .collect();
        let path = out.join(format!("residuals_{}.png", c.name));
        if let Err(e) = plot_residuals(
            &path,
            &format!("{}: residuals of {}", cfg.name, c.name),
            &series,
            "t / t_f",
            "measured − predicted, % of rupture strain",
        ) {
            eprintln!("warning: {e}");
        }
    }
    print!("{md}");
    println!("wrote {}", out.display());
    Ok(())
}

fn parse_shard(s: &str) -> std::result::Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 2/3")?;
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
    Ok((i, n))
}

fn sweep_cmd(cfg: &RunConfig, data: &Dataset, opts: &SweepOptions) -> Result<()> {
    sweep::install_sigint_handler();
    let (plan, run) = sweep::run_sweep(cfg, data, opts)?;
    let mut header = plan.header.clone();
    header.shard = opts.shard.unwrap_or((1, 1));
    let a = sweep::write_outputs(&header, &run.solutions, &opts.out, run.wall_s, run.threads)?;
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
        return Err(crate::Error::Invalid(format!(
            "interrupted: {} of {} fits missing; rerun the same command to resume ({})",
            run.missing,
            run.missing + run.solutions.len(),
            opts.out.display()
        )));
    }
    println!("wrote {}", opts.out.display());
    Ok(())
}

fn merge_cmd(dirs: &[PathBuf], out: &Path) -> Result<()> {
    let (header, sols) = sweep::merge(dirs)?;
    ensure_dir(out)?;
    let a = sweep::write_outputs(&header, &sols, out, 0.0, 0)?;
    print_sweep(&header, &a);
    println!("merged {} folders into {}", dirs.len(), out.display());
    Ok(())
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

/// Dense time grid from 0 to `t_end` (h), with extra resolution near the end of life.
fn dense_grid(t_end: f64, n: usize) -> Vec<f64> {
    let mut g: Vec<f64> = (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64;
            // uniform over most of life, refined near rupture
            t_end * (1.0 - (1.0 - s).powi(2))
        })
        .collect();
    g.dedup();
    g
}

fn fit(config: &Path, out: Option<PathBuf>, req: &FitRequest) -> Result<()> {
    let (cfg, data) = load(config)?;
    let run = run_fit_with(&cfg, &data, req)?;
    let out = out.unwrap_or_else(|| default_out(&cfg.name, "fit"));
    ensure_dir(&out)?;
    let best = &run.fits[run.best];
    let curves = &data.curves;
    tables::write_constants(
        &out.join("constants.csv"),
        run.model.as_ref(),
        &run.space,
        &best.params,
    )?;
    let rows = tables::error_rows(best, curves);
    tables::write_errors(&out.join("errors.csv"), &rows)?;
    tables::write_fit_curves(&out.join("curves.csv"), best, curves)?;
    let summary = tables::fit_summary(&run, curves);
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
        let pin = run
            .space
            .at_bound(j, best.params[j], 1e-6)
            .map(|s| format!("  (at {s} bound)"))
            .unwrap_or_default();
        println!(
            "  {:>6} = {:<12.6e} {}{}",
            c.name, best.params[j], c.unit, pin
        );
    }
    print!("{}", tables::error_table(&rows, run.used_min_rate));

    // Plot last: a plotting failure never loses the numeric outputs above.
    let plot_path = out.join("fit.png");
    let plots = curve_plots(
        &cfg,
        &data,
        &best.params,
        &run.settings.ode,
        run.model.as_ref(),
    );
    match plot_creep_curves(
        &plot_path,
        &format!("{} — measured (points) and fitted (lines)", cfg.name),
        &plots,
    ) {
        Ok(()) => println!("wrote {}", out.display()),
        Err(e) => {
            eprintln!("warning: plot not written: {e}");
            println!("wrote {} (without plot)", out.display());
        }
    }
    Ok(())
}

/// Most measured points a plot draws per curve ([`tables::thin`]).
const PLOT_POINTS: usize = 2000;

/// Measured points and dense predicted curves for a plot.
fn curve_plots(
    cfg: &RunConfig,
    data: &Dataset,
    params: &[f64],
    ode: &OdeOptions,
    model: &dyn crate::model::Model,
) -> Vec<CurvePlot> {
    data.curves
        .iter()
        .map(|c| {
            let load = Load {
                stress_mpa: c.stress_mpa,
                omega_f: cfg.objective.omega_f,
            };
            let span = c
                .rupture_time_h
                .unwrap_or(0.0)
                .max(*c.times_h.last().unwrap_or(&0.0));
            let o = OdeOptions {
                t_end: crate::objective::HORIZON_FACTOR * span,
                ..*ode
            };
            let res = model.simulate(params, &load, &[], &mut [], &o);
            let grid = dense_grid(res.t_end, 400);
            let (_, traj) = model.trajectory(params, &load, &grid, &o);
            CurvePlot {
                label: match &c.specimen {
                    Some(sp) => format!("{} MPa, {sp}", c.stress_mpa),
                    None => format!("{} MPa", c.stress_mpa),
                },
                measured: tables::thin(
                    c.times_h
                        .iter()
                        .zip(&c.strains)
                        .map(|(t, e)| (*t, 100.0 * e))
                        .collect(),
                    PLOT_POINTS,
                ),
                predicted: traj.iter().map(|(t, e, _)| (*t, 100.0 * e)).collect(),
            }
        })
        .collect()
}

fn simulate(
    config: &Path,
    constants: Option<PathBuf>,
    out: Option<PathBuf>,
    w: Option<f64>,
) -> Result<()> {
    let (cfg, data) = load(config)?;
    let model = build(&cfg.model, &cfg.extensions)?;
    let params = match constants {
        Some(path) => tables::read_constants(&path, model.as_ref())?,
        None => cfg.starts_all_given().ok_or_else(|| {
            crate::Error::config(
                &cfg.path,
                "simulate needs --constants FILE or a start value for every constant",
            )
        })?,
    };
    let out = out.unwrap_or_else(|| default_out(&cfg.name, "simulate"));
    ensure_dir(&out)?;
    let ode = OdeOptions {
        rtol: cfg.solver.rtol,
        atol: cfg.solver.atol,
        ..OdeOptions::default()
    };
    let names = model.state_names();
    let idx = |n: &str| names.iter().position(|s| *s == n);
    let (ih, iphi, iom) = (idx("H"), idx("Phi"), idx("omega"));
    let mut trajectories = Vec::new();
    let mut rupture_rows = Vec::new();
    let specimens = tables::has_specimens(&data.curves);
    let specimen =
        |c: &crate::data::Curve| specimens.then(|| c.specimen.clone().unwrap_or_default());
    for c in &data.curves {
        let load = Load {
            stress_mpa: c.stress_mpa,
            omega_f: cfg.objective.omega_f,
        };
        let span = c
            .rupture_time_h
            .unwrap_or(0.0)
            .max(*c.times_h.last().unwrap_or(&0.0));
        let o = OdeOptions {
            t_end: crate::objective::HORIZON_FACTOR * span,
            ..ode
        };
        let res = model.simulate(&params, &load, &[], &mut [], &o);
        let mut grid = dense_grid(res.t_end, 200);
        grid.extend(c.times_h.iter().copied().filter(|t| *t <= res.t_end));
        grid.sort_by(|a, b| a.total_cmp(b));
        grid.dedup();
        let (_, traj) = model.trajectory(&params, &load, &grid, &o);
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
            num(100.0 * res.min_rate),
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
    let curve_header = [
        "temperature_C",
        "stress_MPa",
        "time_h",
        "strain_pct",
        "H",
        "Phi",
        "omega",
    ];
    // Rows formatted as they are written (a logged curve gives a million of them).
    let curve_rows = trajectories.iter().flat_map(|(c, traj)| {
        traj.iter().map(|(t, e, y)| {
            let get = |i: Option<usize>| i.map(|i| num(y[i])).unwrap_or_default();
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(*t),
                num(100.0 * e),
                get(ih),
                get(iphi),
                get(iom),
            ];
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
    ];
    write_csv(
        &out.join("ruptures.csv"),
        &tables::with_specimen(&rupture_header, specimens),
        &rupture_rows,
    )?;
    if let Some(w) = w {
        let objective = crate::objective::Objective {
            model: model.as_ref(),
            curves: &data.curves,
            w: vec![w; data.curves.len()],
            lifetime: cfg.objective.lifetime_term,
            omega_f: cfg.objective.omega_f,
            ode,
        };
        let e = objective.evaluate(&params);
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
    let plots = curve_plots(&cfg, &data, &params, &ode, model.as_ref());
    if let Err(e) = plot_creep_curves(
        &out.join("simulate.png"),
        &format!("{} — simulated", cfg.name),
        &plots,
    ) {
        eprintln!("warning: plot not written: {e}");
    }
    println!("wrote {}", out.display());
    Ok(())
}
