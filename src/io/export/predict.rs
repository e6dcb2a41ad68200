//! `predict`'s outputs: the console table, predictions.csv and the files and plots of
//! [`crate::predict::write_outputs`].

use std::path::Path;

use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::Result;
use crate::model::Model;
use crate::predict::PredictRun;

use super::plots_done;

/// On stderr: each asked condition outside what the data tested (the files mark them too).
pub fn warn_extrapolation(cfg: &RunConfig, data: &Dataset) {
    let tested = crate::baseline::Tested::of(data, cfg.has_laws());
    for n in crate::predict::extrapolation_notes(&tested, &cfg.predict.at) {
        eprintln!("warning: {n}");
    }
}

/// Write a finished prediction into `out` and print its table.
pub fn write(
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    run: &PredictRun,
    out: &Path,
) -> Result<()> {
    println!("{}: model {}", cfg.name, model.name());
    let names: Vec<&str> = model.constants().iter().map(|c| c.name).collect();
    print!("{}", crate::predict::table(run, &names));
    if let Some(m) = &run.measured {
        print!("{}", m.table(run));
    }
    let failures = crate::predict::write_outputs(out, cfg, data, model, run)?;
    println!("wrote {}", out.display());
    plots_done(out, failures)
}
