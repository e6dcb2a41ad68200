//! Experiments over many generated worlds: the battery that calibrates `diagnose`.

pub mod battery;
