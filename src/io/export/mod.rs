//! Exporters, one per command's result (hyperfine's options → scheduler → exporters): each
//! takes what the library computed and writes the files the command contract names
//! (`docs/FORMATS.md`) and the console report. No computation beyond formatting happens
//! here, except what a plot needs to draw (a curve simulated on a dense grid).

pub mod battery;
pub mod diagnose;
pub mod fit;
pub mod holdout;
pub mod predict;
pub mod profile;
pub mod simulate;
pub mod sweep;
pub mod synth;

use std::path::Path;

use crate::error::{Error, Result};

/// `Ok` if every plot was written, else the error saying the numbers are in `out`.
pub fn plots_done(out: &Path, failures: Vec<String>) -> Result<()> {
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::PlotsNotWritten {
            out: out.to_path_buf(),
            failures,
        })
    }
}
