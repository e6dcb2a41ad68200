//! Helpers shared by the integration tests: the repository root, the binary, JSON files.
#![allow(dead_code)] // each test file uses its own share

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (configurations and data paths are relative to it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Run the `creepfit` binary with `args` from the repository root.
pub fn creepfit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("binary runs")
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}
