//! The command line: parses arguments, resolves the configuration, calls the library and
//! writes its outputs (src/main.rs is only the entry point).

pub mod cli;
