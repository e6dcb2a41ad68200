//! creepfit: calibrates the material constants of continuum-damage creep constitutive
//! equations (Kowalewski–Hayhurst–Dyson form) against measured creep curves.
//!
//! Units throughout: time in h, stress in MPa, strain as a fraction (files use percent).

pub mod config;
pub mod data;
pub mod error;
pub mod model;
pub mod lsq;
pub mod ode;

pub use error::{Error, Result};
