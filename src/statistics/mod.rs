//! Statistical models of the data around a creep model: the reading-error model, the
//! likelihood (specimen effects integrated out), apparent activation energies, Larson–Miller
//! and the other classical time–temperature parameters, and generated data sets.

pub mod activation;
pub mod baseline;
pub mod errmodel;
pub mod likelihood;
pub mod lmp;
pub mod synth;
