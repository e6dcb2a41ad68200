//! Calibration: local fits, the multistart sweep, and the tables and plots they write
//! (which the analysis layer writes through too).

pub mod fit;
pub mod report;
pub mod sweep;
