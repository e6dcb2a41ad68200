//! creepfit: calibrates the material constants of continuum-damage creep constitutive
//! equations (Kowalewski–Hayhurst–Dyson form, and Kachanov–Rabotnov) against measured creep
//! curves, searches the constants' space globally, diagnoses what the calibrated model still
//! gets wrong, and predicts untested conditions with intervals.
//!
//! Units throughout: time in h, stress in MPa, strain as a fraction (files use percent).
//!
//! # The library's layers
//!
//! Lowest first, one folder of `src/` each; a module imports only from its own layer or a
//! lower one (checked by `scripts/layers.py`, which the test command runs). Every module is
//! re-exported at the crate root under its own name (`creepfit::fit`, `creepfit::diagnose`).
//!
//! | layer (folder) | modules | what |
//! |---|---|---|
//! | [`infra`] | [`error`], [`output`], [`identity`], [`journal`], [`progress`] | the error enum, atomic files, run identities, resumable work, progress observers |
//! | [`numerics`] | [`dual`], [`lsq`], [`ode`], [`sampling`], [`scalar_min`] | forward-mode duals, the bounded Levenberg–Marquardt solver, the integrator (an [`ode::OdeSystem`] with events, no creep words), start sampling, one-dimensional minimisation (grid then golden section) |
//! | `data` | [`data`], [`specimen`] | curves, ruptures, conditions, specimens |
//! | `model` | [`model`] | model families (registry), extensions, temperature laws, the eq. 8 objective, initial guesses |
//! | [`statistics`] | [`errmodel`], [`likelihood`], [`activation`], [`lmp`], [`baseline`], [`synth`] | error models, the likelihood, activation energies, Larson–Miller and the classical baselines, generated data |
//! | [`settings`] | [`config`] | the resolved run configuration |
//! | [`calibration`] | [`fit`], [`report`], [`sweep`] | local fits, their tables and plots, the multistart sweep |
//! | [`analysis`] | [`predict`], [`diagnose`], [`uncertainty`], [`holdout`] | predictions, model-form diagnosis, profiles and intervals, held-out validation |
//! | [`experiments`] | [`battery`] | calibration of `diagnose` over many generated sets |
//! | [`app`] | [`cli`] | the command line (files, locks, journals and exporters around the calls below) |
//!
//! # Calibrating in memory
//!
//! Every command is a library call on data in memory; files are one way to get the data in.
//! A fit of the seed paper's 560 °C curves from a configuration text and CSV bytes (here the
//! bundled files, read at compile time):
//!
//! ```
//! use std::path::Path;
//! use creepfit::config::RunConfig;
//!
//! let text = r#"
//! name = "cmv-560C"
//! curves = "curves.csv"
//! ruptures = "ruptures.csv"
//! temperature_C = 560
//! model = "khd"
//!
//! [constants]
//! A     = { lb = 1e-10, ub = 1e-9,  start = 1e-9,    scale = "log" }
//! B     = { lb = 0.1,   ub = 0.2,   start = 0.11 }
//! Hstar = { lb = 0.4,   ub = 0.8,   start = 0.426 }
//! h     = { lb = 1e4,   ub = 2e5,   start = 5.05e4,  scale = "log" }
//! Kc    = { lb = 1e-6,  ub = 3e-5,  start = 6.86e-6, scale = "log" }
//! C     = { lb = 3,     ub = 10,    start = 4.311 }
//!
//! [sweep]
//! starts = 6
//! "#;
//! let cfg = RunConfig::from_str(text, Path::new("560C.toml"))?;
//! let data = cfg.load_data_from(
//!     Path::new("curves.csv"),
//!     include_bytes!("../data/creep_560C.csv"),
//!     Path::new("ruptures.csv"),
//!     include_bytes!("../data/lifetimes.csv"),
//! )?;
//! let cfg = cfg.with_data(&data);
//! assert_eq!(data.curves.len(), 3); // 85, 100 and 110 MPa
//!
//! // The paper's procedure: local fits from the guess and the configured start.
//! let run = creepfit::fit::run_fit(cfg.calibration(&data)?, &data)?;
//! let best = &run.fits[run.best];
//! let names: Vec<&str> = run.model.constants().iter().map(|c| c.name).collect();
//! assert_eq!(names, ["A", "B", "Hstar", "h", "Kc", "C"]);
//! // The paper's mean |lifetime error| at 560 °C is 2.45 % (its Table 6); this fit's is lower.
//! assert!(best.mean_lifetime_err() <= 2.45, "{}", best.mean_lifetime_err());
//!
//! // The multistart sweep, with a progress callback (fits done, fits in all) and a flag
//! // that stops it (here never raised).
//! let stop = std::sync::atomic::AtomicBool::new(false);
//! let sweep = creepfit::sweep::run_in_memory(&cfg, &data, &stop, &|done, total| {
//!     assert!(done <= total);
//! })?;
//! assert_eq!(sweep.missing, 0);
//! let a = creepfit::sweep::analyse(&sweep.plan.header, &sweep.solutions);
//! // 6 Latin-hypercube starts and the guess, each at the 10 lifetime weights w of the default grid.
//! assert_eq!((a.completed, a.failed), (70, 0));
//! assert!(a.ranked.iter().all(|s| s.objective >= a.ranked[0].objective));
//! # Ok::<(), creepfit::Error>(())
//! ```
//!
//! The configuration hands out what each analysis takes, built once: `cfg.diagnose_setup()`
//! to [`diagnose::diagnose`] (what the fitted model still gets wrong, as a
//! [`diagnose::Diagnosis`] with its [`diagnose::Verdict`]), `cfg.predict_setup(&data)` to
//! [`predict::run`], `cfg.likelihood_setup(&data)` to [`uncertainty`] (profiles and
//! intervals); the command line ([`cli`], [`commands`]) wraps these calls with output
//! folders, journals and exporters ([`export`]), and the Python package (`python/`) with
//! pandas DataFrames.

// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must take the failure path.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Numerical loops index several arrays with one index; iterator chains would obscure them.
#![allow(clippy::needless_range_loop)]

// The layers, lowest first (see the table above); each top-level module is re-exported at
// the crate root under its own name (`crate::fit`, `creepfit::diagnose`), so paths do not
// name the layer.
pub mod analysis;
pub mod app;
pub mod calibration;
pub mod data;
pub mod experiments;
pub mod infra;
pub mod io;
pub mod model;
pub mod numerics;
pub mod settings;
pub mod statistics;

pub use analysis::{diagnose, holdout, predict, scores, simulate, uncertainty};
pub use app::{cli, commands};
pub use calibration::{fit, report, sweep};
pub use data::specimen;
pub use experiments::battery;
pub use infra::{error, identity, journal, output, progress};
pub use io::export;
pub use numerics::{dual, lsq, ode, sampling, scalar_min};
pub use settings::config;
pub use statistics::{activation, baseline, errmodel, likelihood, lmp, synth};

pub use error::{Error, Result};
