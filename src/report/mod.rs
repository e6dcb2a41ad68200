//! Reports: output files, printed tables and plots.

pub mod diagrams;
pub mod plot;
pub mod tables;
