//! `diagnose`'s outputs: diagnosis.json, timings.json, report.md (also printed) and the
//! residual plots of the base model and of the chosen (else lowest-AIC) extension.

use std::path::Path;

use crate::config::{DiagnoseSetup, RunConfig};
use crate::data::Dataset;
use crate::diagnose::Diagnosis;
use crate::error::Result;
use crate::journal::Journal;
use crate::report::plot::plot_curve_residuals;
use crate::report::tables::{write_text, write_timings};

use super::plots_done;

/// Write a finished diagnosis of `data` under `cfg` (its models: `setup`) into `out` and print
/// its report.
pub fn write(
    cfg: &RunConfig,
    setup: &DiagnoseSetup,
    data: &Dataset,
    d: &Diagnosis,
    journal: Option<&Journal>,
    out: &Path,
) -> Result<()> {
    write_text(
        &out.join("diagnosis.json"),
        &serde_json::to_string_pretty(d).expect("JSON of plain values"),
    )?;
    write_timings(
        out,
        "diagnose",
        journal,
        serde_json::json!({ "wall_s": d.wall_s, "phase_s": d.phase_s, "phase_lm": d.phase_lm }),
    )?;
    let md = crate::diagnose::report::report_md(&cfg.name, setup, d);
    write_text(&out.join("report.md"), &md)?;
    let mut failures = Vec::new();
    for (name, series) in
        crate::diagnose::report::residual_series(setup, data, cfg.diagnose.max_points, d)?
    {
        let path = out.join(format!("residuals_{name}.png"));
        if let Err(e) = plot_curve_residuals(
            &path,
            &format!("{}: residuals of {name}", cfg.name),
            &series,
            "t / t_f",
            "predicted − measured, % of rupture strain",
        ) {
            failures.push(e.to_string());
        }
    }
    print!("{md}");
    println!("wrote {}", out.display());
    plots_done(out, failures)
}
