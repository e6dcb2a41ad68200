//! `battery`'s outputs: the reports over every finished set ([`crate::battery::write_reports`])
//! and the console summary; the generated sets and `results.jsonl` the battery appended are
//! recorded in the folder's manifest.

use std::path::Path;

use crate::battery::SetResult;
use crate::error::Result;

/// Record in the manifest what the battery wrote in `out` as it went (`results.jsonl`, every
/// file under `sets/`), finished or not.
pub fn record_written(out: &Path) {
    crate::output::record(&out.join("results.jsonl"));
    fn walk(d: &Path) {
        for e in std::fs::read_dir(d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p);
            } else {
                crate::output::record(&p);
            }
        }
    }
    walk(&out.join("sets"));
}

/// Write the battery's reports over `results` (first seed `seed`) into `out`: their rates.
pub fn write(out: &Path, results: &[SetResult], seed: u64) -> Result<crate::battery::Rates> {
    crate::battery::write_reports(out, results, seed)
}

/// The console's summary line of a battery's `results` with their rates `r`.
pub fn print_summary(results: &[SetResult], r: &crate::battery::Rates) {
    println!(
        "{} sets: false alarms {} of {} no-effect sets; named correctly (detectable): {}; outside the catalogue with an extension verdict: {} of {}",
        results.len(),
        r.false_alarms,
        r.null_sets,
        r.named
            .iter()
            .map(|(e, _, d, k)| format!("{e} {k}/{d}"))
            .collect::<Vec<_>>()
            .join(", "),
        r.outside_extension,
        r.outside_sets
    );
}
