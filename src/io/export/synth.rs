//! `synth`'s outputs: one generated set's folder (curves.csv, truth.json, config.toml) and
//! its console line.

use std::path::Path;

use crate::error::Result;
use crate::synth::SynthSet;

/// Write generated set `name` of `scenario` into `dir` and say what it holds.
pub fn write(set: &SynthSet, name: &str, scenario: &str, dir: &Path) -> Result<()> {
    crate::synth::write_set(set, dir)?;
    println!(
        "{name}: {} ({}), {} curves, {:?}",
        scenario,
        set.truth.family,
        set.truth.stresses.len(),
        set.truth.sampling
    );
    Ok(())
}
