//! `sweep`'s and `merge`'s outputs: the ranked starts, minima, summary and plots
//! ([`crate::sweep::write_outputs`]) and the console report.

use std::path::Path;

use crate::config::RunConfig;
use crate::error::{Error, Result};
use crate::sweep;

use super::plots_done;

/// A finished (or interrupted) sweep part's outputs into `out`; an interrupted sweep is an error after them.
pub fn write(cfg: &RunConfig, plan: &sweep::Plan, run: &sweep::SweepRun, out: &Path) -> Result<()> {
    let out = out.to_path_buf();
    let mut header = plan.header.clone();
    header.shard = cfg.run.shard.unwrap_or((1, 1));
    let coverage = sweep::part_coverage(&header, header.shard, run.solutions.len(), &out);
    let (a, failures) = sweep::write_outputs(
        &header,
        &run.solutions,
        &out,
        run.wall_s,
        run.threads,
        &coverage,
    )?;
    print_sweep(&header, &a);
    println!(
        "{} fits computed now in {:.1} s on {} threads ({:.2} fits/s); {} in the folder",
        run.computed,
        run.wall_s,
        run.threads,
        run.computed as f64 / run.wall_s.max(1e-9),
        run.solutions.len()
    );
    if run.missing > 0 {
        return Err(Error::Invalid(format!(
            "interrupted: {} of {} fits missing (summary.json: \"complete\": false); rerun the same command to resume ({})",
            run.missing,
            run.missing + run.solutions.len(),
            out.display()
        )));
    }
    println!("wrote {}", out.display());
    plots_done(&out, failures)
}

/// What `merge` found on its way, on stderr: folders without a journal, shards missing or
/// incomplete.
pub fn report_merge(m: &sweep::Merged) {
    for d in &m.skipped {
        eprintln!("merge: {}: no sweep journal, skipped", d.display());
    }
    for s in &m.coverage.missing {
        let state = match s.state {
            sweep::ShardState::Incomplete => "incomplete",
            sweep::ShardState::Absent => "absent",
        };
        let dir = s.dir.as_ref().map(|d| format!(" ({})", d.display()));
        eprintln!(
            "merge: shard {}/{} {state}: {} of {} fits{}",
            s.shard,
            s.of,
            s.fits_done,
            s.fits_expected,
            dir.unwrap_or_default()
        );
    }
}

/// `merge`'s outputs into `out`.
pub fn write_merged(m: &sweep::Merged, out: &Path) -> Result<()> {
    let n = m.merged.len() + m.coverage.missing.len();
    let list = |v: Vec<usize>| {
        v.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (a, failures) = sweep::write_outputs(&m.header, &m.solutions, out, 0.0, 0, &m.coverage)?;
    print_sweep(&m.header, &a);
    if m.coverage.complete {
        println!("merged {n} of {n} shards into {}", out.display());
    } else {
        let expected = m.header.n_starts_total() * m.header.w.len();
        eprintln!(
            "merge: partial result: shards {} of {n} ({} of {expected} fits); summary.json says complete: false",
            list(m.merged.iter().map(|p| p.0).collect()),
            m.solutions.len()
        );
        println!(
            "merged {} of {n} shards into {} (partial)",
            m.merged.len(),
            out.display()
        );
    }
    plots_done(out, failures)
}

fn print_sweep(h: &sweep::Header, a: &sweep::Analysis) {
    println!(
        "{}: {} fits ({} starts × {} w), {} completed, {} failed, {} distinct minima",
        h.name,
        a.ranked.len(),
        h.n_starts_total(),
        h.w.len(),
        a.completed,
        a.failed,
        a.clusters.len()
    );
    if a.completed == 0 {
        return;
    }
    let b = &a.ranked[0];
    println!(
        "best: objective {:.6} at w = {:?} (start {}), normalised residual {:.6}, mean |lifetime err| {:.2} %, best basin holds {:.1} % of the fits",
        b.objective,
        h.w[b.w_idx],
        b.start_id,
        b.norm_residual,
        b.lifetime_err_pct,
        100.0 * a.clusters[0].fraction
    );
    if let Some(c) = sweep::best_caution(h, a) {
        println!("caution (the best fit): {c}");
    }
    if let Some(n) = h.objective_note() {
        println!("note: {n}");
    }
    for (n, side, v) in &a.pinned {
        println!("  {n} = {v:.6e} on its {side} bound");
    }
    println!(
        "within 1 % of the best objective: {} solutions; spread of the constants:",
        a.near_best
    );
    for s in &a.spreads {
        println!(
            "  {:>6}: {:.4e} .. {:.4e}  (relative range {:.3}, {:.3} of the box)",
            s.name, s.min, s.max, s.rel_range, s.unit_range
        );
    }
    println!("Pareto set (normalised residual, mean |lifetime err| %, mean |min-rate err| %):");
    for i in (0..a.ranked.len()).filter(|&i| a.pareto[i]).take(15) {
        let s = &a.ranked[i];
        println!(
            "  rank {:>4}  F {:.5}  res {:.5}  life {:>6.2}  rate {:>7.2}  lifetime errors {:?}",
            i + 1,
            s.objective,
            s.norm_residual,
            s.lifetime_err_pct,
            s.min_rate_err_pct,
            s.lifetime_errs_pct
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
    }
}
