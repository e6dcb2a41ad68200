//! Analysis of calibrated models: predictions, the model-form diagnosis, profiles and
//! intervals, and held-out validation.

pub mod diagnose;
pub mod holdout;
pub mod predict;
pub mod scores;
pub mod simulate;
pub mod uncertainty;
