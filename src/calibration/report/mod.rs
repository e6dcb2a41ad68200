//! Reports: output files, printed tables and plots.

pub mod plot;
pub mod tables;
