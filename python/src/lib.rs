//! `creepfit._native`: the Python package's bridge to the creepfit library.
//!
//! Every function takes the run configuration (a TOML file's path, TOML text, or the JSON of a
//! Python dict with the TOML file's keys) and, optionally, the curves and ruptures tables as CSV
//! text (the Python layer writes its DataFrames so), calls the functions the command line
//! calls, and returns the output files' contents as text (CSV tables, JSON documents), made by
//! the same code that writes them: the Python layer reads them into DataFrames and dicts. The
//! work runs on a thread of its own with the GIL released; the calling thread waits for it,
//! reports progress and checks for Ctrl-C (KeyboardInterrupt) every [`POLL`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use creepfit::config::{DiagnoseOverrides, Overrides, RunConfig, RunOptions, StartChoice};
use creepfit::data::Condition;
use creepfit::data::Dataset;
use creepfit::error::Error;
use creepfit::report::tables;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    creepfit,
    CreepfitError,
    PyValueError,
    "Bad input or a failed run: the crate's one-line message (`FILE:LINE: field: what` where \
     there is a file and a line); `path` and `line` name them (None where there is none)."
);

/// How often the waiting thread wakes to report progress and check for Ctrl-C.
const POLL: Duration = Duration::from_millis(100);

/// Name of a configuration given as TOML text or as a dict, in errors and as the default run
/// name (no file of that name is read).
const CONFIG_NAME: &str = "<config>";
/// Names of the tables given in memory, in errors and warnings (their lines counted as in a
/// CSV file: the header is line 1, so the DataFrame's row at position k is line k + 2).
const CURVES_NAME: &str = "<curves DataFrame>";
const RUPTURES_NAME: &str = "<ruptures DataFrame>";
const CONSTANTS_NAME: &str = "<constants>";
/// The name a `tests` table has in errors when it did not come from a file.
const TESTS_NAME: &str = "<tests DataFrame>";

/// The library's error as a `CreepfitError` with its message and, for a file's error, the
/// file and line.
fn py_err(e: Error) -> PyErr {
    let (path, line) = match &e {
        Error::Data { path, line, .. } | Error::Config { path, line, .. } => (
            Some(path.display().to_string()),
            (*line > 0).then_some(*line),
        ),
        Error::Io { path, .. } => (Some(path.display().to_string()), None),
        _ => (None, None),
    };
    let err = CreepfitError::new_err(e.to_string());
    Python::attach(|py| {
        let v = err.value(py);
        // Attributes of a fresh exception object: setting them cannot fail in practice.
        let _ = v.setattr("path", path);
        let _ = v.setattr("line", line);
    });
    err
}

/// Where the configuration comes from.
enum Source {
    /// A TOML file: read as the command line reads it.
    Path(PathBuf),
    /// TOML text.
    Toml(String),
    /// The JSON of a dict with the TOML file's keys.
    Json(String),
}

impl Source {
    fn new(kind: &str, text: String) -> PyResult<Source> {
        match kind {
            "path" => Ok(Source::Path(PathBuf::from(text))),
            "toml" => Ok(Source::Toml(text)),
            "json" => Ok(Source::Json(text)),
            k => Err(PyValueError::new_err(format!(
                "config kind '{k}': expected path, toml or json"
            ))),
        }
    }
}

/// The curves and ruptures tables as CSV text.
struct Tables {
    curves: String,
    ruptures: String,
}

/// Keys a configuration needs that name the data files; given placeholders (never read) when
/// the data come as tables and the configuration does not name files.
const DATA_KEYS: [(&str, &str); 2] = [("curves", CURVES_NAME), ("ruptures", RUPTURES_NAME)];

/// The TOML text of a JSON configuration (a dict's): objects are tables, arrays arrays,
/// numbers integers or floats as written, strings strings; `null` has no TOML form and is an
/// error naming the key.
fn json_to_toml(v: &serde_json::Value, key: &str) -> Result<toml::Value, Error> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => {
            return Err(Error::config(
                CONFIG_NAME,
                format!("{key}: None has no TOML form; leave the key out for its default"),
            ))
        }
        J::Bool(b) => toml::Value::Boolean(*b),
        J::Number(n) => match n.as_i64() {
            Some(i) => toml::Value::Integer(i),
            None => toml::Value::Float(n.as_f64().ok_or_else(|| {
                Error::config(CONFIG_NAME, format!("{key}: {n} is out of range"))
            })?),
        },
        J::String(s) => toml::Value::String(s.clone()),
        J::Array(a) => toml::Value::Array(
            a.iter()
                .enumerate()
                .map(|(i, x)| json_to_toml(x, &format!("{key}[{i}]")))
                .collect::<Result<_, _>>()?,
        ),
        J::Object(m) => {
            let mut t = toml::map::Map::new();
            for (k, x) in m {
                let name = if key.is_empty() {
                    k.clone()
                } else {
                    format!("{key}.{k}")
                };
                t.insert(k.clone(), json_to_toml(x, &name)?);
            }
            toml::Value::Table(t)
        }
    })
}

/// The configuration (with the command line's settings `cli`) and its data: the files it names,
/// or the tables given. Warnings are appended to `warnings`.
fn resolve(
    src: &Source,
    cli: &Overrides,
    tables: Option<&Tables>,
    warnings: &mut Vec<String>,
) -> Result<(RunConfig, Dataset), Error> {
    let cfg = match src {
        // The command line's way: the file and the files it names.
        Source::Path(p) if tables.is_none() => {
            let (cfg, data) = RunConfig::resolve(p, cli)?;
            warnings.extend(cfg.warnings.iter().chain(&data.warnings).cloned());
            return Ok((cfg, data));
        }
        Source::Path(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| Error::io(p, e))?;
            toml_config(&text, p, cli)?
        }
        // Without tables the data are the files the text names: nothing to add.
        Source::Toml(text) if tables.is_none() => {
            RunConfig::from_str_with(text, Path::new(CONFIG_NAME), cli)?
        }
        Source::Toml(text) => toml_config(text, Path::new(CONFIG_NAME), cli)?,
        Source::Json(json) => {
            let v: serde_json::Value = serde_json::from_str(json)
                .map_err(|e| Error::config(CONFIG_NAME, format!("not a configuration: {e}")))?;
            let mut t = match json_to_toml(&v, "")? {
                toml::Value::Table(t) => t,
                _ => {
                    return Err(Error::config(
                        CONFIG_NAME,
                        "a configuration is a dict of the TOML file's keys",
                    ))
                }
            };
            if tables.is_some() {
                for (k, name) in DATA_KEYS {
                    t.entry(k.to_string())
                        .or_insert_with(|| toml::Value::String(name.to_string()));
                }
            }
            let text =
                toml::to_string(&t).map_err(|e| Error::config(CONFIG_NAME, e.to_string()))?;
            // The TOML text is ours, not the user's: its line numbers mean nothing to them.
            RunConfig::from_str_with(&text, Path::new(CONFIG_NAME), cli).map_err(|e| match e {
                Error::Config { path, message, .. } => Error::Config {
                    path,
                    line: 0,
                    message,
                },
                e => e,
            })?
        }
    };
    match tables {
        None => load_named(cfg, warnings),
        Some(t) => {
            let data = cfg.load_data_from(
                Path::new(CURVES_NAME),
                t.curves.as_bytes(),
                Path::new(RUPTURES_NAME),
                t.ruptures.as_bytes(),
            )?;
            let cfg = cfg.with_data(&data);
            warnings.extend(cfg.warnings.iter().chain(&data.warnings).cloned());
            Ok((cfg, data))
        }
    }
}

/// The data files `cfg` names, loaded and bound to it ([`RunConfig::resolve`]'s second half).
fn load_named(cfg: RunConfig, warnings: &mut Vec<String>) -> Result<(RunConfig, Dataset), Error> {
    let data = cfg.load_data()?;
    let cfg = cfg.with_data(&data);
    warnings.extend(cfg.warnings.iter().chain(&data.warnings).cloned());
    Ok((cfg, data))
}

/// A TOML configuration whose data come as tables: the text with placeholder data keys in
/// front where it names no files, its errors' lines those of the text as given.
fn toml_config(text: &str, path: &Path, cli: &Overrides) -> Result<RunConfig, Error> {
    let missing: Vec<(&str, &str)> = match text.parse::<toml::Table>() {
        Ok(t) => DATA_KEYS
            .iter()
            .filter(|(k, _)| !t.contains_key(*k))
            .copied()
            .collect(),
        // Not TOML: the library reports where, on the text as given.
        Err(_) => Vec::new(),
    };
    let head: String = missing
        .iter()
        .map(|(k, name)| format!("{k} = {}\n", toml::Value::String(name.to_string())))
        .collect();
    let shift = missing.len();
    RunConfig::from_str_with(&format!("{head}{text}"), path, cli).map_err(|e| match e {
        Error::Config {
            path: p,
            line,
            message,
        } if p == path && line > 0 => Error::Config {
            path: p,
            line: line.saturating_sub(shift),
            message,
        },
        e => e,
    })
}

/// Progress of a run, written by the work and read by the waiting thread.
#[derive(Default)]
struct Progress {
    done: AtomicUsize,
    total: AtomicUsize,
    /// Raised by the waiting thread (Ctrl-C, a failing callback): start no new work.
    stop: AtomicBool,
    /// The phase the library reports (`fits on the data`, `null bootstrap`, …; empty: one
    /// phase, the command's).
    phase: std::sync::Mutex<String>,
}

/// The library's phases and steps as the counts the waiting thread reports (each phase
/// counts from 0 to its steps, 0 where it does not know them); the library asks it whether
/// to stop (`stop`: Ctrl-C or a failing callback), and stops at its next check, keeping
/// nothing (no journal in memory).
impl creepfit::progress::Observer for Progress {
    fn phase(&self, name: &str, total: Option<u64>) {
        *self.phase.lock().unwrap_or_else(|e| e.into_inner()) = name.to_string();
        self.done.store(0, Ordering::SeqCst);
        self.total
            .store(total.unwrap_or(0) as usize, Ordering::SeqCst);
    }
    fn resumed(&self, n: u64) {
        self.done.fetch_add(n as usize, Ordering::SeqCst);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n as usize, Ordering::SeqCst);
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }
}

impl Progress {
    /// The library's hooks reporting to this progress, with no journal.
    fn hooks(&self) -> creepfit::progress::Hooks<'_> {
        creepfit::progress::Hooks {
            observer: self,
            journal: None,
        }
    }
}

/// Run `work` on a thread of its own while this thread waits with the GIL released, calling
/// `callback(done, total, phase)` every [`POLL`] (from this thread, with the GIL: a bar's elapsed
/// time moves even when the work reports no counts) and checking for signals. A KeyboardInterrupt or a failing callback raises `stop`, waits for the
/// work to end (GIL released) and is returned; a panic of the work is a RuntimeError.
fn run_detached<T: Send>(
    py: Python<'_>,
    callback: Option<&Bound<'_, PyAny>>,
    work: impl FnOnce(&Progress) -> Result<T, Error> + Send,
) -> PyResult<T> {
    let progress = Progress::default();
    let (tx, rx) = mpsc::channel();
    // A receiver is not Sync: behind a mutex, the closures that wait on it are Send.
    let rx = std::sync::Mutex::new(rx);
    let recv = |timeout: Option<Duration>| {
        let rx = rx.lock().unwrap_or_else(|e| e.into_inner());
        match timeout {
            Some(t) => rx.recv_timeout(t),
            None => rx.recv().map_err(|_| mpsc::RecvTimeoutError::Disconnected),
        }
    };
    std::thread::scope(|s| {
        let p = &progress;
        s.spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(p)));
            let _ = tx.send(r);
        });
        let finish = |e: PyErr| -> PyResult<T> {
            progress.stop.store(true, Ordering::SeqCst);
            let _ = py.detach(|| recv(None));
            Err(e)
        };
        loop {
            let got = py.detach(|| recv(Some(POLL)));
            if let Some(cb) = callback {
                let now = (
                    progress.done.load(Ordering::SeqCst),
                    progress.total.load(Ordering::SeqCst),
                    progress
                        .phase
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .clone(),
                );
                if let Err(e) = cb.call1(now) {
                    if got.is_ok() {
                        return Err(e);
                    }
                    return finish(e);
                }
            }
            match got {
                Ok(Ok(r)) => return r.map_err(py_err),
                Ok(Err(panic)) => {
                    let what = panic
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    return Err(PyRuntimeError::new_err(format!(
                        "creepfit: internal error (a panic): {what}"
                    )));
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        return finish(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err("creepfit: the worker thread ended"))
                }
            }
        }
    })
}

/// `f` on a pool of `threads` workers (rayon's global pool when `None`), as the command line's
/// `--threads`.
fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<T, Error> + Send,
) -> Result<T, Error> {
    match threads {
        None => f(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::Invalid(format!("threads = {n}: {e}")))?
            .install(f),
    }
}

fn tables_of(curves: Option<String>, ruptures: Option<String>) -> PyResult<Option<Tables>> {
    match (curves, ruptures) {
        (None, None) => Ok(None),
        (Some(curves), Some(ruptures)) => Ok(Some(Tables { curves, ruptures })),
        _ => Err(CreepfitError::new_err(
            "give both the curves and the ruptures tables, or neither (the configuration's files)",
        )),
    }
}

/// The constants of a constants table's CSV text (name,value[,…]), named `name` in errors
/// ([`CONSTANTS_NAME`] when `None`), for `cfg`'s model.
fn given_constants(
    text: &str,
    name: Option<&str>,
    cfg: &RunConfig,
    model: &dyn creepfit::model::Model,
) -> Result<Vec<f64>, Error> {
    let name = PathBuf::from(name.unwrap_or(CONSTANTS_NAME));
    tables::read_constants_bytes(&name, text.as_bytes(), cfg, model)
}

/// Outputs by name (CSV or JSON text) and the warnings of the run.
type Outputs = (HashMap<&'static str, String>, Vec<String>);

fn json(v: &impl serde::Serialize) -> String {
    serde_json::to_string(v).expect("JSON of plain values")
}

/// `creepfit fit`: the paper's procedure. Returns constants.csv, errors.csv, curves.csv and
/// summary.json's texts.
#[pyfunction]
#[pyo3(signature = (config, kind, curves=None, ruptures=None, start=None, w=None))]
fn fit(
    py: Python<'_>,
    config: String,
    kind: &str,
    curves: Option<String>,
    ruptures: Option<String>,
    start: Option<String>,
    w: Option<f64>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let start = start
        .map(|s| match s.as_str() {
            "both" => Ok(StartChoice::Both),
            "config" => Ok(StartChoice::Config),
            "guess" => Ok(StartChoice::Guess),
            _ => Err(CreepfitError::new_err(format!(
                "start: '{s}': expected 'both', 'config' or 'guess'"
            ))),
        })
        .transpose()?;
    let cli = Overrides {
        w,
        fit_starts: Some(start.unwrap_or_default()),
        ..Overrides::default()
    };
    run_detached(py, None, move |_| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        let run = creepfit::fit::run_fit(cfg.calibration(&data)?, &data)?;
        let best = &run.fits[run.best];
        let mut out = HashMap::new();
        let constants = tables::constants_rows(
            run.model.as_ref(),
            &run.space,
            &best.params,
            cfg.has_laws().then_some(cfg.t_ref).flatten(),
        );
        out.insert(
            "constants",
            tables::csv_text(&tables::CONSTANTS_COLUMNS, constants.iter()),
        );
        let (h, rows) = tables::errors_table(&tables::error_rows(best, &data.curves));
        out.insert("errors", tables::csv_text(&h, rows.iter()));
        let (h, rows) = tables::fit_curves_table(best, &data.curves);
        out.insert("curves", tables::csv_text(&h, rows));
        out.insert(
            "summary",
            json(&tables::fit_summary(&cfg, &run, &data.curves)),
        );
        Ok((out, warnings))
    })
}

/// `creepfit sweep` in memory: ranked.csv, minima.csv and summary.json's texts. `progress`
/// is called with (fits done, fits in all).
#[pyfunction]
#[pyo3(signature = (config, kind, curves=None, ruptures=None, starts=None, seed=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn sweep(
    py: Python<'_>,
    config: String,
    kind: &str,
    curves: Option<String>,
    ruptures: Option<String>,
    starts: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let cli = Overrides {
        starts,
        seed,
        run: RunOptions {
            threads,
            ..RunOptions::default()
        },
        ..Overrides::default()
    };
    let (out, warnings, missing) = run_detached(py, progress.as_ref(), move |p| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        let run = creepfit::sweep::run_in_memory(&cfg, &data, &p.stop, &|done, total| {
            p.total.store(total, Ordering::SeqCst);
            p.done.store(done, Ordering::SeqCst);
        })?;
        let header = &run.plan.header;
        let a = creepfit::sweep::analyse(header, &run.solutions);
        let missing = creepfit::sweep::missing(header, &run.solutions);
        let coverage = creepfit::sweep::Coverage {
            complete: true,
            missing: Vec::new(),
        };
        let mut out = HashMap::new();
        let (h, rows) = creepfit::sweep::ranked_table(header, &a);
        out.insert("ranked", tables::csv_text(&h, rows.iter()));
        let (h, rows) = creepfit::sweep::minima_table(header, &a);
        out.insert("minima", tables::csv_text(&h, rows.iter()));
        out.insert(
            "summary",
            json(&creepfit::sweep::summary(
                header,
                &a,
                &coverage,
                &missing,
                run.wall_s,
                run.threads,
            )),
        );
        Ok((out, warnings, run.missing))
    })?;
    if missing > 0 {
        return Err(CreepfitError::new_err(format!(
            "interrupted: {missing} fits missing"
        )));
    }
    Ok((out, warnings))
}

/// `creepfit diagnose`: diagnosis.json's text. `progress` is told of its phases (the fits on
/// the data, the bootstraps, …) and their replicates; a raised stop ends it at the library's
/// next check.
#[pyfunction]
#[pyo3(signature = (config, kind, curves=None, ruptures=None, starts=None, seed=None, bootstrap=None, bootstrap_extended=None, alpha=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn diagnose(
    py: Python<'_>,
    config: String,
    kind: &str,
    curves: Option<String>,
    ruptures: Option<String>,
    starts: Option<usize>,
    seed: Option<u64>,
    bootstrap: Option<usize>,
    bootstrap_extended: Option<usize>,
    alpha: Option<f64>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let cli = Overrides {
        diagnose: DiagnoseOverrides {
            starts,
            seed,
            bootstrap,
            bootstrap_extended,
            alpha,
        },
        run: RunOptions {
            threads,
            ..RunOptions::default()
        },
        ..Overrides::default()
    };
    run_detached(py, progress.as_ref(), move |p| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        cfg.check_diagnose(&data)?;
        let d = with_threads(cfg.run.threads, || {
            creepfit::diagnose::diagnose_observed(
                &cfg.diagnose_setup()?,
                &data,
                &cfg.diagnose,
                &p.hooks(),
            )
        })?;
        let mut out = HashMap::new();
        out.insert("diagnosis", json(&d));
        Ok((out, warnings))
    })
}

/// `creepfit predict`: predictions.csv and summary.json's texts. `constants` is a constants
/// table's CSV text (name,value[,…]), named `constants_name` in errors; `at` the conditions as `T:σ[,T:σ…]` (default:
/// the configuration's `[predict] at`).
#[pyfunction]
#[pyo3(signature = (config, kind, constants, constants_name=None, curves=None, ruptures=None, at=None, intervals=None, tests=None, tests_name=None))]
#[allow(clippy::too_many_arguments)]
fn predict(
    py: Python<'_>,
    config: String,
    kind: &str,
    constants: String,
    constants_name: Option<String>,
    curves: Option<String>,
    ruptures: Option<String>,
    at: Option<String>,
    intervals: Option<bool>,
    tests: Option<String>,
    tests_name: Option<String>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let mut at = at
        .map(|s| Condition::parse_list(&s).map_err(|m| py_err(Error::Invalid(format!("at: {m}")))))
        .transpose()?;
    let tests = match tests {
        Some(text) => {
            if at.is_some() {
                return Err(CreepfitError::new_err("give `at` or `tests`, not both"));
            }
            let name = PathBuf::from(tests_name.as_deref().unwrap_or(TESTS_NAME));
            let records =
                creepfit::predict::measured::read_bytes(&name, text.as_bytes()).map_err(py_err)?;
            at = Some(creepfit::predict::measured::conditions(&records));
            Some((name, records))
        }
        None => None,
    };
    let cli = Overrides {
        predict_at: at,
        predict_intervals: intervals,
        ..Overrides::default()
    };
    run_detached(py, None, move |_| {
        let mut warnings = Vec::new();
        let (mut cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        let tests = match tests {
            Some(t) => Some(t),
            None => creepfit::predict::measured::from_config(&mut cfg)?,
        };
        creepfit::predict::check_asked(&cfg)?;
        let model = cfg.build_model()?;
        let params = given_constants(&constants, constants_name.as_deref(), &cfg, &*model)?;
        match &tests {
            Some((name, records)) => {
                creepfit::predict::measured::check(name, records, &cfg, &data)?
            }
            None => creepfit::predict::check_conditions(&cfg, &data, cli.predict_at.is_some())?,
        }
        let tested = creepfit::baseline::Tested::of(&data, cfg.has_laws());
        warnings.extend(creepfit::predict::extrapolation_notes(
            &tested,
            &cfg.predict.at,
        ));
        let mut run =
            creepfit::predict::run(&cfg.predict_setup(&data), &data, model.as_ref(), &params)?;
        let mut out = HashMap::new();
        if let Some((name, records)) = &tests {
            let m = creepfit::predict::measured::MeasuredTests::of(name, records, &run);
            let (h, rows) = m.csv();
            let h: Vec<&str> = h.iter().map(String::as_str).collect();
            out.insert("tests", tables::csv_text(&h, rows.iter()));
            run.measured = Some(m);
        }
        let (h, rows) = creepfit::predict::predictions_table(&run);
        out.insert("predictions", tables::csv_text(&h, rows.iter()));
        out.insert(
            "summary",
            json(&creepfit::predict::summary_json(
                &cfg,
                &data,
                model.as_ref(),
                &run,
            )),
        );
        Ok((out, warnings))
    })
}

/// `creepfit holdout`: fit without the tests left out (`temperature`, °C, or `campaign`, a
/// specimen label's prefix; exactly one), predict them, compare with the classical baselines.
/// Returns holdout.csv, the training fit's constants.csv and summary.json's texts; in memory:
/// no journal, no output folder, no plots.
#[pyfunction]
#[pyo3(signature = (config, kind, curves=None, ruptures=None, temperature=None, campaign=None, starts=None, seed=None, intervals=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn holdout(
    py: Python<'_>,
    config: String,
    kind: &str,
    curves: Option<String>,
    ruptures: Option<String>,
    temperature: Option<f64>,
    campaign: Option<String>,
    starts: Option<usize>,
    seed: Option<u64>,
    intervals: Option<bool>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let left_out = match (temperature, campaign) {
        (Some(t), None) => creepfit::holdout::LeftOut::Temperature(t),
        (None, Some(name)) => creepfit::holdout::LeftOut::Campaign(name),
        _ => {
            return Err(CreepfitError::new_err(
                "give the temperature or the campaign to leave out (one of them)",
            ))
        }
    };
    let cli = Overrides {
        starts,
        seed,
        predict_intervals: intervals,
        run: RunOptions {
            threads,
            ..RunOptions::default()
        },
        ..Overrides::default()
    };
    run_detached(py, progress.as_ref(), move |p| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        let h = with_threads(cfg.run.threads, || {
            creepfit::holdout::holdout_observed(
                &cfg,
                &data,
                &left_out,
                cfg.predict.intervals,
                &p.hooks(),
            )
        })?;
        let mut out = HashMap::new();
        let (h_cols, rows) = creepfit::holdout::csv_table(&h);
        let h_cols: Vec<&str> = h_cols.iter().map(String::as_str).collect();
        out.insert("holdout", tables::csv_text(&h_cols, rows.iter()));
        let constants = tables::constants_rows(
            h.fit.model.as_ref(),
            &h.fit.space,
            &h.fit.fits[h.fit.best].params,
            h.t_ref,
        );
        out.insert(
            "constants",
            tables::csv_text(&tables::CONSTANTS_COLUMNS, constants.iter()),
        );
        out.insert("summary", json(&creepfit::holdout::summary_json(&cfg, &h)));
        Ok((out, warnings))
    })
}

/// `creepfit profile`: profile likelihoods of every constant, their intervals, the
/// well-determined combinations and the prediction intervals, from the maximum-likelihood fit
/// started at `constants` (a constants table's CSV text, named `constants_name` in errors) or,
/// without it, from a multistart. Returns intervals.csv, profiles.csv, summary.json and
/// report.md's texts; in memory: no journal, no output folder, no plots.
#[pyfunction]
#[pyo3(signature = (config, kind, constants=None, constants_name=None, curves=None, ruptures=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn profile(
    py: Python<'_>,
    config: String,
    kind: &str,
    constants: Option<String>,
    constants_name: Option<String>,
    curves: Option<String>,
    ruptures: Option<String>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    let cli = Overrides {
        run: RunOptions {
            threads,
            ..RunOptions::default()
        },
        ..Overrides::default()
    };
    run_detached(py, progress.as_ref(), move |p| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &cli, tables.as_ref(), &mut warnings)?;
        let run = with_threads(cfg.run.threads, || {
            let model = cfg.build_model()?;
            let given = constants
                .as_deref()
                .map(|text| given_constants(text, constants_name.as_deref(), &cfg, &*model))
                .transpose()?;
            creepfit::uncertainty::report::check(&cfg, &data)?;
            creepfit::uncertainty::report::run_observed(
                &cfg,
                &data,
                given.as_deref(),
                &cfg.profile,
                &p.hooks(),
            )
        })?;
        use creepfit::uncertainty::report as r;
        let mut out = HashMap::new();
        out.insert(
            "intervals",
            tables::csv_text(&r::INTERVAL_HEADER, r::interval_rows(&run).iter()),
        );
        let (h, rows) = r::profiles_table(&cfg, &run);
        let h: Vec<&str> = h.iter().map(String::as_str).collect();
        out.insert("profiles", tables::csv_text(&h, rows.iter()));
        out.insert("summary", json(&r::summary(&cfg, &run)));
        out.insert("report", r::report_md(&cfg, &run));
        Ok((out, warnings))
    })
}

/// `creepfit simulate`: every configured test simulated at the constants (a constants table's
/// CSV text, named `constants_name` in errors; default: the configuration's start values), to
/// its rupture or the horizon. Returns curves.csv and ruptures.csv's texts, and
/// objective.json's with `w` (the eq. 8 objective at that one lifetime weight).
#[pyfunction]
#[pyo3(signature = (config, kind, constants=None, constants_name=None, curves=None, ruptures=None, w=None))]
#[allow(clippy::too_many_arguments)]
fn simulate(
    py: Python<'_>,
    config: String,
    kind: &str,
    constants: Option<String>,
    constants_name: Option<String>,
    curves: Option<String>,
    ruptures: Option<String>,
    w: Option<f64>,
) -> PyResult<Outputs> {
    let src = Source::new(kind, config)?;
    let tables = tables_of(curves, ruptures)?;
    if let Some(w) = w {
        if !(0.0..=1.0).contains(&w) {
            return Err(py_err(Error::Invalid(format!(
                "w: must be a weight in [0, 1], not {w}"
            ))));
        }
    }
    run_detached(py, None, move |_| {
        let mut warnings = Vec::new();
        let (cfg, data) = resolve(&src, &Overrides::default(), tables.as_ref(), &mut warnings)?;
        let model = cfg.build_model()?;
        let params = match &constants {
            Some(text) => given_constants(text, constants_name.as_deref(), &cfg, &*model)?,
            None => cfg.starts_all_given().ok_or_else(|| {
                Error::config(
                    &cfg.path,
                    "simulate needs constants or a start value for every constant",
                )
            })?,
        };
        let settings = creepfit::fit::FitSettings::from_config(&cfg);
        let model = model.as_ref();
        let sims = creepfit::simulate::simulate(
            model,
            &params,
            &data,
            cfg.objective.omega_f,
            &settings.ode,
        );
        use creepfit::simulate as sim;
        let mut out = HashMap::new();
        let h = sim::curves_header(model, &sims);
        let h: Vec<&str> = h.iter().map(String::as_str).collect();
        out.insert("curves", tables::csv_text(&h, sim::curves_rows(&sims)));
        let (h, rows) = sim::ruptures_table(&sims);
        out.insert("ruptures", tables::csv_text(&h, rows.iter()));
        if let Some(w) = w {
            let e = sim::objective_at(model, &data, &params, w, settings.objective());
            out.insert("objective", json(&sim::objective_json(&data, w, &e)));
        }
        Ok((out, warnings))
    })
}

/// `creepfit synth`'s set of `seed`: curves.csv, ruptures.csv, config.toml and truth.json's
/// texts, those the command writes into its folder `name` (`set-SEED` there). `scenario`:
/// one of `synth --scenario`'s; `world`: one of `--world`'s (identical, specimens, shapes,
/// campaigns).
#[pyfunction]
#[pyo3(signature = (seed, scenario, world, name))]
fn synth(
    seed: u64,
    scenario: &str,
    world: &str,
    name: &str,
) -> PyResult<HashMap<&'static str, String>> {
    use creepfit::synth as sy;
    check_scenario(scenario)?;
    let world = world_of(world)?;
    let set = sy::generate_in(name, scenario, None, seed, world).map_err(py_err)?;
    Ok(HashMap::from([
        ("curves", set.curves_csv),
        ("ruptures", set.ruptures_csv),
        ("config", set.config_toml),
        ("truth", sy::truth_json(&set.truth)),
    ]))
}

/// `Ok` for a scenario of `synth --scenario`, else the error naming the known ones.
fn check_scenario(scenario: &str) -> PyResult<()> {
    creepfit::synth::check_scenario(scenario).map_err(|_| {
        py_err(Error::Invalid(format!(
            "scenario: unknown scenario '{scenario}' (known: {})",
            creepfit::synth::SCENARIOS.join(", ")
        )))
    })
}

/// The laboratory `world` names (`synth --world`'s values).
fn world_of(world: &str) -> PyResult<creepfit::synth::World> {
    serde_json::from_value(serde_json::Value::String(world.to_string())).map_err(|_| {
        py_err(Error::Invalid(format!(
            "world: unknown world '{world}' (known: identical, specimens, shapes, campaigns)"
        )))
    })
}

/// The reports `creepfit battery` writes into its folder, by name.
const BATTERY_REPORTS: [(&str, &str); 6] = [
    ("results", "results.csv"),
    ("confusion", "confusion.csv"),
    ("confusion_detectable", "confusion_detectable.csv"),
    ("power", "power.csv"),
    ("summary", "summary.json"),
    ("report", "summary.md"),
];

/// `creepfit battery`: `sets` generated sets from `seed` (of `scenario`, else the battery's
/// cycle) in `world`, each diagnosed, into `folder`; resumed from the sets an earlier run of
/// the same battery finished there. Returns the reports' texts (results.csv, confusion.csv,
/// confusion_detectable.csv, power.csv, summary.json, summary.md). A raised stop starts no
/// new set; the running ones finish and are recorded.
#[pyfunction]
#[pyo3(signature = (folder, sets, seed, world, scenario=None, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn battery(
    py: Python<'_>,
    folder: String,
    sets: usize,
    seed: u64,
    world: &str,
    scenario: Option<String>,
    threads: Option<usize>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<HashMap<&'static str, String>> {
    let world = world_of(world)?;
    if let Some(sc) = &scenario {
        check_scenario(sc)?;
    }
    let out = PathBuf::from(folder);
    let (texts, _) = run_detached(py, progress.as_ref(), move |p| {
        with_threads(threads, || {
            creepfit::commands::battery_observed(
                &out,
                sets,
                seed,
                world,
                scenario.as_deref(),
                &creepfit::battery::SetOverrides::default(),
                p,
            )
        })?;
        let mut texts = HashMap::new();
        for (key, file) in BATTERY_REPORTS {
            let path = out.join(file);
            let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
            texts.insert(key, text);
        }
        Ok((texts, Vec::<String>::new()))
    })?;
    Ok(texts)
}

/// The creepfit library: calibration of creep-damage constitutive equations.
#[pymodule]
mod _native {
    #[pymodule_export]
    use super::{
        battery, diagnose, fit, holdout, predict, profile, simulate, sweep, synth, CreepfitError,
    };
}
