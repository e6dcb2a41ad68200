//! The run's resolved settings: the TOML schema, validated and resolved once
//! ([`config::RunConfig`]), handing out built things (a model, a parameter space, fit
//! settings).

pub mod config;
