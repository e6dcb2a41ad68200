//! Multistart global search: Latin-hypercube starts in the unit box × the w candidates, a
//! bounded LM from every (start, w) pair in parallel, then ranking, the Pareto set over the
//! paper's three criteria, distinct minima and identifiability.
//!
//! Reproducible and resumable: all starts are drawn serially from one seed before any
//! parallel work, every fit is deterministic, and each finished fit is appended (flushed) to
//! `journal.jsonl` in the output folder. A rerun on the same folder computes only what is
//! missing; `--shard I/N` computes the starts with `start_id % N == I − 1` (`--shard auto`
//! takes I and N from a scheduler's job array, [`array`](mod@array)); [`merge`] unites the shard
//! journals, also of an incomplete set. The final files are a function of the set of solutions alone, so they are
//! identical for any thread count, shard split or interruption history.
//!
//! Safe: the journal's header holds the run identity ([`crate::identity`]); a resume or merge
//! of a different sweep is refused, naming the first differing setting. One sweep at a time
//! writes into a folder ([`crate::output::lock_folder`]).

mod analysis;
pub mod array;
mod journal;

pub use analysis::{
    analyse, best_caution, minima_table, ranked_table, summary, Analysis, Cluster, Spread,
};
/// Read a sweep journal (`None` when the file does not exist): for tests and tools.
pub use journal::read as read_journal;
pub use journal::{Header, Solution};

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::config::{Calibration, RunConfig};
use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::fit::{local_fit, FitSettings};
use crate::model::guess::initial_guess;
use crate::model::objective::mean_abs;
use crate::output::{lock_folder, RunFolder};
use crate::sampling::latin_hypercube;

/// The part of a sweep the command line asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardArg {
    /// `--shard I/N`: the I-th (1-based) of N parts.
    Part(usize, usize),
    /// `--shard auto`: I and N from the job array's environment ([`array::shard_from_env`]).
    Auto,
}

/// Folder of shard I of N inside a sweep folder: `shard-I-of-N`.
pub fn shard_dir(sweep_dir: &Path, (i, n): (usize, usize)) -> PathBuf {
    sweep_dir.join(format!("shard-{i}-of-{n}"))
}

/// Where a sweep part writes, from the resolved shard and the command line's `--out`:
/// unsharded runs and `--shard I/N --out DIR` write into `--out` (default `default_dir`);
/// `--shard auto` writes into `shard-I-of-N/` inside it, so that every task of an array can
/// share one command line; `--shard I/N` without `--out` into `default_dir/shard-I-of-N/`.
pub fn part_dir(
    shard: Option<(usize, usize)>,
    auto: bool,
    out: Option<PathBuf>,
    default_dir: PathBuf,
) -> PathBuf {
    match (shard, out) {
        (None, out) => out.unwrap_or(default_dir),
        (Some(s), Some(out)) if auto => shard_dir(&out, s),
        (Some(_), Some(out)) => out,
        (Some(s), None) => shard_dir(&default_dir, s),
    }
}

/// Set by the SIGINT handler: no new fits start, running ones finish and are journaled.
/// [`run_sweep`] clears it when it starts.
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Install a SIGINT (Ctrl-C) handler that sets [`STOP`]; a second Ctrl-C kills at once.
pub fn install_sigint_handler() {
    #[cfg(unix)]
    {
        extern "C" fn on_sigint(_: libc::c_int) {
            if STOP.swap(true, Ordering::SeqCst) {
                unsafe { libc::_exit(130) };
            }
        }
        // SAFETY: the handler only touches an atomic and calls the async-signal-safe _exit.
        unsafe {
            libc::signal(libc::SIGINT, on_sigint as *const () as libc::sighandler_t);
        }
    }
}

/// Everything a sweep computes from the configuration before any fit.
pub struct Plan {
    /// Journal header: what identifies this sweep.
    pub header: Header,
    /// Start constants (physical), indexed by start_id.
    pub starts: Vec<Vec<f64>>,
    /// w candidates (per-curve weights).
    pub ws: Vec<Vec<f64>>,
}

/// Draw the starts (`cfg.sweep`) and fix the w candidates for a configuration, whose
/// calibration of `data` ([`RunConfig::calibration`]) is `cal`.
pub fn plan(cfg: &RunConfig, cal: &Calibration, data: &Dataset) -> Result<Plan> {
    let (starts, seed) = (cfg.sweep.starts, cfg.sweep.seed);
    if starts == 0 {
        return Err(Error::Invalid("--starts must be at least 1".into()));
    }
    let (model, space, settings) = (&cal.model, &cal.space, &cal.settings);
    let ws = cal.weights.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = space.n_free();
    let mut start_params: Vec<Vec<f64>> = latin_hypercube(starts, k, &mut rng)
        .iter()
        .map(|u| {
            let mut x = vec![0.0; space.len()];
            space.from_unit(u, &mut x);
            x
        })
        .collect();
    // The extra start: the configuration's start values, else the model's initial guess.
    let (label, anchor) = match cal.given_start.clone() {
        Some(x) => ("config", x),
        None => (
            "guess",
            initial_guess(
                model.as_ref(),
                &data.curves,
                space,
                settings.omega_f,
                &settings.ode,
            )
            .params,
        ),
    };
    // Starts that cannot be evaluated are moved toward the extra start, or, where that cannot
    // be evaluated either, toward the evaluable Latin-hypercube point nearest to it (and the
    // extra start too: its start_id is then among the repaired).
    start_params.push(anchor);
    let n = start_params.len();
    let target = if crate::fit::evaluable(
        model.as_ref(),
        &data.curves,
        space,
        settings,
        &start_params[n - 1],
    ) {
        Some(start_params[n - 1].clone())
    } else {
        crate::fit::evaluable_anchor(
            model.as_ref(),
            &data.curves,
            space,
            settings,
            &start_params[n - 1],
            seed,
        )
    };
    let mut repaired = match &target {
        Some(t) if cfg.sweep.repair => crate::fit::repair_starts(
            model.as_ref(),
            &data.curves,
            space,
            settings,
            &mut start_params,
            t,
        ),
        _ => vec![],
    };
    let anchor = start_params.pop().expect("pushed");
    let mut extra = None;
    if cfg.sweep.include_guess {
        extra = Some(label.to_string());
        start_params.push(anchor);
    } else {
        repaired.retain(|&i| i < n - 1);
    }
    let names: Vec<String> = model
        .constants()
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let mut header = Header::new(cfg, data, &names, space, extra, &ws, &start_params);
    header.repaired_starts = repaired;
    Ok(Plan {
        header,
        starts: start_params,
        ws,
    })
}

/// What a sweep run did.
pub struct SweepRun {
    /// All solutions of this run's part (from the journal and newly computed), unordered.
    pub solutions: Vec<Solution>,
    /// Fits computed in this run.
    pub computed: usize,
    /// Fits of this part still missing (non-zero after an interruption).
    pub missing: usize,
    /// Wall time of this run, s.
    pub wall_s: f64,
    /// Threads used.
    pub threads: usize,
    /// The output folder, locked and owned by this run while this value lives: write the
    /// outputs, then [`RunFolder::finish`] it (its manifest).
    pub folder: RunFolder,
}

/// Run (or resume) a sweep part of the resolved configuration `cfg` (bound to `data`) into
/// its output folder (`cfg.out_dir("sweep")`), journaling every finished fit. Refused at
/// once when another run holds the folder's lock, or when the folder holds a different
/// sweep (the error names the first differing setting).
pub fn run_sweep(cfg: &RunConfig, data: &Dataset) -> Result<(Plan, SweepRun)> {
    let t0 = Instant::now();
    STOP.store(false, Ordering::SeqCst);
    let out = cfg.out_dir("sweep");
    let cal = cfg.calibration(data)?;
    let plan = plan(cfg, &cal, data)?;
    let (model, space, settings) = (&cal.model, &cal.space, &cal.settings);
    let (shard_i, shard_n) = cfg.run.shard.unwrap_or((1, 1));
    if shard_n == 0 || shard_i == 0 || shard_i > shard_n {
        return Err(Error::Invalid(format!(
            "--shard {shard_i}/{shard_n}: need 1 ≤ I ≤ N"
        )));
    }
    let mut header = plan.header.clone();
    header.shard = (shard_i, shard_n);
    let lock = lock_folder(&out)?;
    let journal_path = out.join(journal::FILE);
    let existing = journal::read(&journal_path)?;
    let mut solutions = match existing {
        Some((h, sols)) => {
            let folder = |what: String| Error::Folder {
                path: journal_path.clone(),
                message: format!(
                    "this folder holds {what}; use another --out or delete the folder"
                ),
            };
            if let Some((field, held, asked)) = h.difference(&header) {
                return Err(folder(format!(
                    "a sweep with {field} = {held}, the configuration asks for {asked}"
                )));
            }
            if h.shard != header.shard {
                return Err(folder(format!(
                    "shard {}/{} of this sweep, the command asks for {shard_i}/{shard_n}",
                    h.shard.0, h.shard.1
                )));
            }
            sols
        }
        None => {
            check_bound(cfg, data)?;
            journal::create(&journal_path, &header)?;
            Vec::new()
        }
    };
    // After the identity comparison, so that a folder of another sweep is named as such.
    check_bound(cfg, data)?;
    // The folder is this sweep's: its journal is what it resumes from, the rest is redone.
    let folder = RunFolder::take_over(lock, "sweep", &|f| f == journal::FILE)?;
    crate::output::record(&journal_path);
    let jobs = missing(&header, &solutions);

    let threads = cfg
        .run
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Invalid(format!("thread pool: {e}")))?;
    let writer = Mutex::new(journal::Appender::open(&journal_path)?);
    let new: Mutex<Vec<Solution>> = Mutex::new(Vec::new());
    let started = AtomicUsize::new(0);
    let write_error: Mutex<Option<Error>> = Mutex::new(None);
    let bar = progress_bar(jobs.len(), cfg.run.progress);
    pool.install(|| {
        jobs.par_iter().for_each(|&(s, wi)| {
            if STOP.load(Ordering::SeqCst) {
                return;
            }
            if let Some(k) = cfg.run.stop_after {
                if started.fetch_add(1, Ordering::SeqCst) >= k {
                    return;
                }
            }
            let sol = solve(model.as_ref(), data, space, settings, &plan, (s, wi));
            if let Err(e) = writer.lock().unwrap().append(&sol) {
                write_error.lock().unwrap().get_or_insert(e);
                STOP.store(true, Ordering::SeqCst);
            }
            new.lock().unwrap().push(sol);
            bar.inc(1);
        })
    });
    bar.finish_and_clear();
    if let Some(e) = write_error.into_inner().unwrap() {
        return Err(e);
    }
    let new = new.into_inner().unwrap();
    let computed = new.len();
    solutions.extend(new);
    let missing = missing(&header, &solutions).len();
    Ok((
        plan,
        SweepRun {
            solutions,
            computed,
            missing,
            wall_s: t0.elapsed().as_secs_f64(),
            threads,
            folder,
        },
    ))
}

/// The local fit of start `s` at w candidate `wi` of `plan`, as a journal entry.
fn solve(
    model: &dyn crate::model::Model,
    data: &Dataset,
    space: &crate::model::objective::ParamSpace,
    settings: &FitSettings,
    plan: &Plan,
    (s, wi): (usize, usize),
) -> Solution {
    let fit = local_fit(
        model,
        &data.curves,
        space,
        &plan.ws[wi],
        &plan.starts[s],
        "",
        settings,
    );
    Solution {
        start_id: s,
        w_idx: wi,
        objective: fit.eval.objective,
        norm_residual: fit.eval.norm_residual,
        lifetime_err_pct: mean_abs(&fit.lifetime_err_pct),
        min_rate_err_pct: mean_abs(&fit.min_rate_err_pct),
        lifetime_errs_pct: fit.lifetime_err_pct.clone(),
        status: if fit.eval.objective.is_finite() {
            fit.lm.termination.as_str().to_string()
        } else {
            "simulation_failure".to_string()
        },
        iterations: fit.lm.iterations,
        evaluations: fit.lm.evaluations,
        params: fit.params,
    }
}

/// What [`run_in_memory`] computed.
pub struct MemoryRun {
    /// The starts and w candidates.
    pub plan: Plan,
    /// The solutions computed, unordered.
    pub solutions: Vec<Solution>,
    /// Fits not computed because `stop` was raised.
    pub missing: usize,
    /// Wall time, s.
    pub wall_s: f64,
    /// Threads used.
    pub threads: usize,
}

/// The whole sweep of the resolved configuration `cfg` (bound to `data`) in memory: the same
/// starts and fits as [`run_sweep`] (so the same files from [`write_outputs`]), without an
/// output folder, journal or shards. `on_fit` is called after each fit (from the worker
/// threads) with the number done and the total: a progress hook. Raising `stop` starts no
/// new fit (the running ones finish); [`MemoryRun::missing`] then counts the rest.
pub fn run_in_memory(
    cfg: &RunConfig,
    data: &Dataset,
    stop: &AtomicBool,
    on_fit: &(dyn Fn(usize, usize) + Sync),
) -> Result<MemoryRun> {
    let t0 = Instant::now();
    check_bound(cfg, data)?;
    let cal = cfg.calibration(data)?;
    let plan = plan(cfg, &cal, data)?;
    let (model, space, settings) = (&cal.model, &cal.space, &cal.settings);
    let jobs = missing(&plan.header, &[]);
    let threads = cfg
        .run
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Invalid(format!("thread pool: {e}")))?;
    let done = AtomicUsize::new(0);
    let solutions: Vec<Solution> = pool.install(|| {
        jobs.par_iter()
            .filter_map(|&job| {
                if stop.load(Ordering::SeqCst) {
                    return None;
                }
                let sol = solve(model.as_ref(), data, space, settings, &plan, job);
                on_fit(done.fetch_add(1, Ordering::SeqCst) + 1, jobs.len());
                Some(sol)
            })
            .collect()
    });
    Ok(MemoryRun {
        missing: jobs.len() - solutions.len(),
        plan,
        solutions,
        wall_s: t0.elapsed().as_secs_f64(),
        threads,
    })
}

/// The configuration must have been resolved on these very data (its `data_hash`).
fn check_bound(cfg: &RunConfig, data: &Dataset) -> Result<()> {
    if cfg.data_hash != crate::data::data_hash(data) {
        return Err(Error::Invalid(
            "the configuration is not bound to these data (build it with RunConfig::resolve or with_data)".into(),
        ));
    }
    Ok(())
}

fn progress_bar(len: usize, enabled: bool) -> indicatif::ProgressBar {
    if !enabled || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} fits  {per_sec}  ETA {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar
}

/// How far a shard's fits got, for a shard that is not (wholly) in a result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ShardState {
    /// Its journal holds some but not all of its fits (an interrupted or failed task).
    Incomplete,
    /// None of the folders holds its journal (a task that never started, or whose folder
    /// was not given).
    Absent,
}

/// A shard that the result leaves out: summary.json's `missing` entries.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissingShard {
    /// I of `--shard I/N`.
    pub shard: usize,
    /// N of `--shard I/N`.
    pub of: usize,
    pub state: ShardState,
    /// Fits its journal holds.
    pub fits_done: usize,
    /// Fits the shard has in all.
    pub fits_expected: usize,
    /// Its folder, where one was found.
    pub dir: Option<PathBuf>,
}

/// How much of the sweep a result covers: summary.json's `complete` (every fit of the sweep
/// is in it) and `missing` (the shards left out).
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    pub complete: bool,
    pub missing: Vec<MissingShard>,
}

/// Number of fits of shard `i` of `n` (1-based `i`): its starts (`start_id % n == i − 1`) × w.
pub fn shard_fits(header: &Header, (i, n): (usize, usize)) -> usize {
    (0..header.n_starts_total())
        .filter(|s| s % n == i - 1)
        .count()
        * header.w.len()
}

/// The coverage of one sweep run's folder, shard `(i, n)` of which holds `done` fits: the
/// shard itself if unfinished, and the other shards, which are absent from it.
pub fn part_coverage(header: &Header, (i, n): (usize, usize), done: usize, dir: &Path) -> Coverage {
    let mut missing = Vec::new();
    for k in 1..=n {
        let expected = shard_fits(header, (k, n));
        let (state, fits_done, dir) = if k == i {
            (ShardState::Incomplete, done, Some(dir.to_path_buf()))
        } else {
            (ShardState::Absent, 0, None)
        };
        if fits_done < expected {
            missing.push(MissingShard {
                shard: k,
                of: n,
                state,
                fits_done,
                fits_expected: expected,
                dir,
            });
        }
    }
    Coverage {
        complete: missing.is_empty(),
        missing,
    }
}

/// What [`merge`] found: the unsharded header, the solutions of the complete shards, and
/// what is left out.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The sweep's header, shard set to 1/1.
    pub header: Header,
    /// All solutions of the complete shards.
    pub solutions: Vec<Solution>,
    /// The complete shards that entered the result: (I, folder).
    pub merged: Vec<(usize, PathBuf)>,
    /// Incomplete and absent shards.
    pub coverage: Coverage,
    /// Folders given that hold no journal (or an empty one): skipped.
    pub skipped: Vec<PathBuf>,
}

/// Read the journals of shard folders, check they belong to one sweep (the same fingerprint
/// and the same N), and unite the shards whose journals hold all of their fits. Incomplete
/// shards (an interrupted task) are left out whole, so the result is a function of the set
/// of complete shards alone; they and the shards no folder holds are listed in the returned
/// coverage. A folder without a journal (or with an empty one, a task killed at its start)
/// is skipped and listed.
pub fn merge(dirs: &[PathBuf]) -> Result<Merged> {
    let mut header: Option<(Header, &PathBuf)> = None;
    let mut parts: std::collections::BTreeMap<usize, (&PathBuf, Vec<Solution>)> =
        Default::default();
    let mut skipped = Vec::new();
    for d in dirs {
        let path = d.join(journal::FILE);
        let empty = std::fs::metadata(&path).is_ok_and(|m| m.len() == 0);
        let Some((h, sols)) = (if empty { None } else { journal::read(&path)? }) else {
            skipped.push(d.clone());
            continue;
        };
        if let Some((h0, d0)) = &header {
            if let Some((field, first, here)) = h0.difference(&h) {
                return Err(Error::Folder {
                    path: path.clone(),
                    message: format!(
                        "a different sweep than {}: {field} = {here} here, {first} there",
                        d0.display()
                    ),
                });
            }
            if h0.shard.1 != h.shard.1 {
                return Err(Error::Folder {
                    path: path.clone(),
                    message: format!(
                        "shard {}/{} of a split into {} parts, but {} holds shard {}/{}",
                        h.shard.0,
                        h.shard.1,
                        h.shard.1,
                        d0.display(),
                        h0.shard.0,
                        h0.shard.1
                    ),
                });
            }
        }
        let (i, n) = h.shard;
        if i == 0 || n == 0 || i > n {
            return Err(Error::data(
                &path,
                1,
                format!("shard {i}/{n}: need 1 <= I <= N"),
            ));
        }
        if let Some(s) = sols.iter().find(|s| {
            s.start_id % n != i - 1 || s.start_id >= h.n_starts_total() || s.w_idx >= h.w.len()
        }) {
            return Err(Error::data(
                &path,
                0,
                format!(
                    "holds start {} at w index {}, which is not a fit of shard {i}/{n}",
                    s.start_id, s.w_idx
                ),
            ));
        }
        if let Some((other, _)) = parts.get(&i) {
            return Err(Error::Invalid(format!(
                "{}: shard {i}/{n} given twice (also {})",
                path.display(),
                other.display()
            )));
        }
        parts.insert(i, (d, sols));
        header.get_or_insert((h, d));
    }
    let (mut header, _) = header.ok_or_else(|| {
        Error::Invalid(format!(
            "none of the {} folder(s) holds a sweep journal ({})",
            dirs.len(),
            journal::FILE
        ))
    })?;
    let n = header.shard.1;
    let mut solutions = Vec::new();
    let mut merged = Vec::new();
    let mut missing = Vec::new();
    for i in 1..=n {
        let expected = shard_fits(&header, (i, n));
        match parts.remove(&i) {
            Some((d, sols)) if sols.len() == expected => {
                solutions.extend(sols);
                merged.push((i, d.clone()));
            }
            Some((d, sols)) => missing.push(MissingShard {
                shard: i,
                of: n,
                state: ShardState::Incomplete,
                fits_done: sols.len(),
                fits_expected: expected,
                dir: Some(d.clone()),
            }),
            None => missing.push(MissingShard {
                shard: i,
                of: n,
                state: ShardState::Absent,
                fits_done: 0,
                fits_expected: expected,
                dir: None,
            }),
        }
    }
    header.shard = (1, 1);
    Ok(Merged {
        header,
        solutions,
        merged,
        coverage: Coverage {
            complete: missing.is_empty(),
            missing,
        },
        skipped,
    })
}

/// The (start_id, w_idx) pairs of `header`'s part of the sweep that `solutions` lack.
pub fn missing(header: &Header, solutions: &[Solution]) -> Vec<(usize, usize)> {
    let (i, n) = header.shard;
    let done: std::collections::HashSet<(usize, usize)> =
        solutions.iter().map(|s| (s.start_id, s.w_idx)).collect();
    (0..header.n_starts_total())
        .filter(|s| s % n == i - 1)
        .flat_map(|s| (0..header.w.len()).map(move |w| (s, w)))
        .filter(|j| !done.contains(j))
        .collect()
}

/// Write the final files of a (complete or partial) set of solutions into `out`: the
/// numeric files first, then the plots. `summary.json` says whether the set is complete
/// and what is missing. Returns the analysis and the plots that could not be written
/// (`plot PATH: why`; the caller reports them, see [`Error::PlotsNotWritten`]): an error
/// of a numeric file is an `Err`, a plot's is not.
pub fn write_outputs(
    header: &Header,
    solutions: &[Solution],
    out: &Path,
    wall_s: f64,
    threads: usize,
    coverage: &Coverage,
) -> Result<(Analysis, Vec<String>)> {
    let analysis = analyse(header, solutions);
    let missing = missing(header, solutions);
    let failures = analysis::write(header, &analysis, coverage, &missing, out, wall_s, threads)?;
    Ok((analysis, failures))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn where_a_part_writes() {
        let d = || PathBuf::from("results/x/sweep");
        let o = || Some(PathBuf::from("o"));
        let cases = [
            (None, false, None, "results/x/sweep"),
            (None, false, o(), "o"),
            (Some((2, 3)), false, None, "results/x/sweep/shard-2-of-3"),
            (Some((2, 3)), false, o(), "o"),
            (Some((2, 3)), true, None, "results/x/sweep/shard-2-of-3"),
            (Some((2, 3)), true, o(), "o/shard-2-of-3"),
        ];
        for (shard, auto, out, want) in cases {
            assert_eq!(part_dir(shard, auto, out, d()), PathBuf::from(want));
        }
    }
}
