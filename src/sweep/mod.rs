//! Multistart global search: Latin-hypercube starts in the unit box × the w candidates, a
//! bounded LM from every (start, w) pair in parallel, then ranking, the Pareto set over the
//! paper's three criteria, distinct minima and identifiability.
//!
//! Reproducible and resumable: all starts are drawn serially from one seed before any
//! parallel work, every fit is deterministic, and each finished fit is appended (flushed) to
//! `journal.jsonl` in the output folder. A rerun on the same folder computes only what is
//! missing; `--shard I/N` computes the starts with `start_id % N == I − 1`; [`merge`] unites
//! shard journals. The final files are a function of the set of solutions alone, so they are
//! identical for any thread count, shard split or interruption history.

mod analysis;
mod journal;

pub use analysis::{analyse, Analysis, Cluster, Spread};
/// Read a sweep journal (`None` when the file does not exist): for tests and tools.
pub use journal::read as read_journal;
pub use journal::{Header, Solution};

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::fit::{local_fit, param_space, weight_candidates, FitSettings};
use crate::guess::initial_guess;
use crate::model::build;
use crate::objective::mean_abs;

/// Options of one sweep run (command line over configuration).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepOptions {
    /// Number of Latin-hypercube starts.
    pub starts: usize,
    /// Seed of the start sequence.
    pub seed: u64,
    /// Worker threads (None: rayon's default, all cores).
    pub threads: Option<usize>,
    /// (I, N): run the I-th (1-based) of N disjoint parts.
    pub shard: Option<(usize, usize)>,
    /// Output folder.
    pub out: PathBuf,
    /// Stop (as if interrupted) after this many new solutions: for tests of resumption.
    pub stop_after: Option<usize>,
    /// Show a progress bar (only drawn when stderr is a terminal).
    pub progress: bool,
}

/// Set by the SIGINT handler: no new fits start, running ones finish and are journaled.
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

/// Latin-hypercube sample of `n` points in [0, 1]^k: each coordinate's n values fall one in
/// each of n equal strata, in a random order; drawn serially from `rng`.
pub fn latin_hypercube(n: usize, k: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut pts = vec![vec![0.0; k]; n];
    for j in 0..k {
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let s = rng.gen_range(0..=i);
            perm.swap(i, s);
        }
        for i in 0..n {
            pts[i][j] = (perm[i] as f64 + rng.gen::<f64>()) / n as f64;
        }
    }
    pts
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

/// Draw the starts and fix the w candidates for a configuration.
pub fn plan(cfg: &RunConfig, data: &Dataset, starts: usize, seed: u64) -> Result<Plan> {
    if starts == 0 {
        return Err(Error::Invalid("--starts must be at least 1".into()));
    }
    let model = build(&cfg.model, &cfg.extensions)?;
    let space = param_space(cfg);
    let settings = FitSettings::from_config(cfg);
    let ws = weight_candidates(cfg, data.curves.len())?;
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
    let mut extra = None;
    if cfg.sweep.include_guess {
        let (label, x) = match cfg.starts_all_given() {
            Some(x) => ("config", x),
            None => (
                "guess",
                initial_guess(
                    model.as_ref(),
                    &data.curves,
                    &space,
                    settings.omega_f,
                    &settings.ode,
                )
                .params,
            ),
        };
        extra = Some(label.to_string());
        start_params.push(x);
    }
    let names: Vec<String> = model
        .constants()
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let header = Header::new(
        cfg,
        data,
        &names,
        &space,
        starts,
        seed,
        extra,
        &ws,
        &start_params,
    );
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
}

/// Run (or resume) a sweep part into `opts.out`, journaling every finished fit.
pub fn run_sweep(cfg: &RunConfig, data: &Dataset, opts: &SweepOptions) -> Result<(Plan, SweepRun)> {
    let t0 = Instant::now();
    let plan = plan(cfg, data, opts.starts, opts.seed)?;
    let model = build(&cfg.model, &cfg.extensions)?;
    let space = param_space(cfg);
    let settings = FitSettings::from_config(cfg);
    let (shard_i, shard_n) = opts.shard.unwrap_or((1, 1));
    if shard_n == 0 || shard_i == 0 || shard_i > shard_n {
        return Err(Error::Invalid(format!(
            "--shard {shard_i}/{shard_n}: need 1 ≤ I ≤ N"
        )));
    }
    let mut header = plan.header.clone();
    header.shard = (shard_i, shard_n);
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let journal_path = opts.out.join(journal::FILE);
    let existing = journal::read(&journal_path)?;
    let mut solutions = match existing {
        Some((h, sols)) => {
            if h.fingerprint != header.fingerprint || h.shard != header.shard {
                return Err(Error::Invalid(format!(
                    "{} belongs to a different sweep (configuration, data, starts, seed or shard differ); use another --out",
                    journal_path.display()
                )));
            }
            sols
        }
        None => {
            journal::create(&journal_path, &header)?;
            Vec::new()
        }
    };
    let done: std::collections::HashSet<(usize, usize)> =
        solutions.iter().map(|s| (s.start_id, s.w_idx)).collect();
    let jobs: Vec<(usize, usize)> = (0..plan.starts.len())
        .filter(|s| s % shard_n == shard_i - 1)
        .flat_map(|s| (0..plan.ws.len()).map(move |w| (s, w)))
        .filter(|j| !done.contains(j))
        .collect();

    let threads = opts
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
    let bar = progress_bar(jobs.len(), opts.progress);
    pool.install(|| {
        jobs.par_iter().for_each(|&(s, wi)| {
            if STOP.load(Ordering::SeqCst) {
                return;
            }
            if let Some(k) = opts.stop_after {
                if started.fetch_add(1, Ordering::SeqCst) >= k {
                    return;
                }
            }
            let fit = local_fit(
                model.as_ref(),
                &data.curves,
                &space,
                &plan.ws[wi],
                &plan.starts[s],
                "",
                &settings,
            );
            let sol = Solution {
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
                params: fit.params.clone(),
            };
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
    let total_part = (0..plan.starts.len())
        .filter(|s| s % shard_n == shard_i - 1)
        .count()
        * plan.ws.len();
    let missing = total_part - solutions.len();
    Ok((
        plan,
        SweepRun {
            solutions,
            computed,
            missing,
            wall_s: t0.elapsed().as_secs_f64(),
            threads,
        },
    ))
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

/// Read the journals of shard folders, check they belong to one sweep and together cover it,
/// and return the unsharded header and all solutions.
pub fn merge(dirs: &[PathBuf]) -> Result<(Header, Vec<Solution>)> {
    let mut header: Option<Header> = None;
    let mut all = Vec::new();
    let mut shards_seen = std::collections::BTreeSet::new();
    for d in dirs {
        let path = d.join(journal::FILE);
        let (h, sols) = journal::read(&path)?
            .ok_or_else(|| Error::Invalid(format!("{}: no sweep journal here", path.display())))?;
        if let Some(h0) = &header {
            if h0.fingerprint != h.fingerprint {
                return Err(Error::Invalid(format!(
                    "{}: a different sweep than {}",
                    path.display(),
                    dirs[0].display()
                )));
            }
        }
        if !shards_seen.insert(h.shard) {
            return Err(Error::Invalid(format!(
                "{}: shard {}/{} given twice",
                path.display(),
                h.shard.0,
                h.shard.1
            )));
        }
        all.extend(sols);
        header.get_or_insert(h);
    }
    let mut header =
        header.ok_or_else(|| Error::Invalid("merge needs at least one folder".into()))?;
    let mut keys = std::collections::HashSet::new();
    all.retain(|s| keys.insert((s.start_id, s.w_idx)));
    let expected = header.n_starts_total() * header.w.len();
    if all.len() != expected {
        return Err(Error::Invalid(format!(
            "the shards hold {} of the sweep's {expected} fits: a shard is missing or unfinished",
            all.len()
        )));
    }
    header.shard = (1, 1);
    Ok((header, all))
}

/// Write the final files of a (complete or partial) set of solutions into `out`.
pub fn write_outputs(
    header: &Header,
    solutions: &[Solution],
    out: &Path,
    wall_s: f64,
    threads: usize,
) -> Result<Analysis> {
    let analysis = analyse(header, solutions);
    analysis::write(header, &analysis, out, wall_s, threads)?;
    Ok(analysis)
}
