//! `profile`'s outputs: intervals.csv, profiles.csv, summary.json, report.md and the profile
//! plots ([`crate::uncertainty::report::write_outputs`]), timings.json and the console
//! report.

use std::path::Path;

use serde_json::json;

use crate::config::RunConfig;
use crate::error::Result;
use crate::journal::Journal;
use crate::uncertainty::report::{report_md, timings_line, write_outputs, ProfileRun};

use super::plots_done;

/// Write a finished profile run into `out` and print its report.
pub fn write(
    cfg: &RunConfig,
    run: &ProfileRun,
    journal: Option<&Journal>,
    out: &Path,
) -> Result<()> {
    let failures = write_outputs(cfg, run, out)?;
    crate::report::tables::write_timings(
        out,
        "profile",
        journal,
        json!({ "timings_s": run.timings }),
    )?;
    print!("{}", report_md(cfg, run));
    print!("{}", timings_line(run));
    println!("wrote {}", out.display());
    plots_done(out, failures)
}
