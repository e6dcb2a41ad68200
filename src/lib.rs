//! creepfit: calibrates the material constants of continuum-damage creep constitutive
//! equations (Kowalewski–Hayhurst–Dyson form) against measured creep curves.
//!
//! Units throughout: time in h, stress in MPa, strain as a fraction (files use percent).

// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must take the failure path.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Numerical loops index several arrays with one index; iterator chains would obscure them.
#![allow(clippy::needless_range_loop)]

pub mod activation;
pub mod baseline;
pub mod battery;
pub mod cli;
pub mod config;
pub mod data;
pub mod diagnose;
pub mod dual;
pub mod errmodel;
pub mod error;
pub mod fit;
pub mod holdout;
pub mod identity;
pub mod journal;
pub mod likelihood;
pub mod lmp;
pub mod lsq;
pub mod model;
pub mod ode;
pub mod output;
pub mod predict;
pub mod progress;
pub mod report;
pub mod sampling;
pub mod specimen;
pub mod sweep;
pub mod synth;
pub mod uncertainty;

pub use error::{Error, Result};
