//! The application: the command line parsed and resolved ([`cli`]) and dispatched to the
//! commands ([`commands`]), which schedule the library's work and hand each result to its
//! exporter (`crate::export`). src/main.rs is only the entry point.

pub mod cli;
pub mod commands;
