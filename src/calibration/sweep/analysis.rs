//! From a set of solutions to the sweep's answers: ranking, Pareto set, distinct minima
//! (single-linkage clusters in the unit box), identifiability near the best, and the files.

use std::path::Path;

use serde_json::{json, Value};

use super::journal::{Header, Solution};
use super::Coverage;
use crate::error::Result;
use crate::report::plot::{plot_parameters, plot_waterfall};
use crate::report::tables::{jnum, num, write_csv, write_text};

/// Two solutions belong to one minimum when a chain of solutions links them with steps of
/// at most this distance (max-norm in unit-box coordinates): long flat valleys stay one basin.
pub const CLUSTER_LINK: f64 = 0.05;
/// Solutions within this relative distance of the best objective enter the identifiability
/// spread.
pub const NEAR_BEST: f64 = 0.01;
/// A constant is on a bound when its unit-box coordinate is within this of 0 or 1.
pub const BOUND_TOL: f64 = 1e-6;
/// Relative resolution of the normalised residual in the Pareto comparison.
pub const PARETO_TOL_REL_RESIDUAL: f64 = 1e-3;
/// Resolution of the mean lifetime and min-rate errors in the Pareto comparison, percentage
/// points.
pub const PARETO_TOL_PCT: f64 = 0.1;
/// How many of the best solutions the parameter plot shows.
pub const PLOT_BEST_K: usize = 20;

/// One distinct minimum.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// 1-based, in order of the best objective.
    pub id: usize,
    /// Number of solutions in it.
    pub size: usize,
    /// Share of the successful solutions.
    pub fraction: f64,
    /// Index (into the ranked list) of its best solution.
    pub best: usize,
}

/// Spread of one constant among the solutions near the best.
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    pub name: String,
    pub min: f64,
    pub max: f64,
    /// (max − min) / |value at the best solution|.
    pub rel_range: f64,
    /// (max − min) in unit-box coordinates.
    pub unit_range: f64,
}

/// Everything the sweep's files say.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// Solutions, best first (failed ones last, by start and w).
    pub ranked: Vec<Solution>,
    /// Cluster id per ranked solution (0 for a failed one).
    pub cluster: Vec<usize>,
    /// Pareto flag per ranked solution.
    pub pareto: Vec<bool>,
    /// The distinct minima, best first.
    pub clusters: Vec<Cluster>,
    /// Spreads of the constants among solutions within `NEAR_BEST` of the best.
    pub spreads: Vec<Spread>,
    /// How many solutions are within `NEAR_BEST`.
    pub near_best: usize,
    /// Constants of the best solution on a bound: (name, "lower"/"upper", value).
    pub pinned: Vec<(String, String, f64)>,
    /// Successful and failed fits.
    pub completed: usize,
    pub failed: usize,
}

fn crit(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::INFINITY
    }
}

/// Pareto flags for criteria rows (all minimised), given in rank order.
///
/// Criteria are compared at a resolution (`PARETO_TOL_*`): each is quantised to bins of that
/// width (the residual on a log scale); a row is dominated by one that is no worse in every bin
/// and better in one, or equal in all bins and ranked higher. Quantising keeps dominance
/// transitive (the front is never empty); without it the flat valleys put hundreds of
/// copies of one basin on the front.
pub fn pareto_front(c: &[[f64; 3]]) -> Vec<bool> {
    let bin = |q: usize, v: f64| -> f64 {
        if !v.is_finite() {
            return f64::INFINITY;
        }
        match q {
            0 => (v.max(f64::MIN_POSITIVE).ln() / PARETO_TOL_REL_RESIDUAL.ln_1p()).floor(),
            _ => (v / PARETO_TOL_PCT).floor(),
        }
    };
    let qc: Vec<[f64; 3]> = c
        .iter()
        .map(|v| [bin(0, v[0]), bin(1, v[1]), bin(2, v[2])])
        .collect();
    (0..qc.len())
        .map(|i| {
            !(0..qc.len()).any(|o| {
                o != i
                    && (0..3).all(|q| qc[o][q] <= qc[i][q])
                    && ((0..3).any(|q| qc[o][q] < qc[i][q]) || o < i)
            })
        })
        .collect()
}

/// A solution's Pareto criteria; a fit that did not converge (iteration limit, stalled) is
/// not a minimum, so it gets the worst values and can neither dominate nor join the front
/// while converged fits exist.
fn pareto_criteria(s: &Solution) -> [f64; 3] {
    if s.status.starts_with("converged") {
        [
            crit(s.norm_residual),
            crit(s.lifetime_err_pct),
            crit(s.min_rate_err_pct),
        ]
    } else {
        [f64::INFINITY; 3]
    }
}

/// Rank, cluster and summarise a set of solutions.
pub fn analyse(header: &Header, solutions: &[Solution]) -> Analysis {
    let mut ranked = solutions.to_vec();
    ranked.sort_by(|a, b| {
        let ka = (!a.ok(), if a.ok() { a.objective } else { 0.0 });
        let kb = (!b.ok(), if b.ok() { b.objective } else { 0.0 });
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(a.start_id.cmp(&b.start_id))
            .then(a.w_idx.cmp(&b.w_idx))
    });
    let n_ok = ranked.iter().filter(|s| s.ok()).count();
    let k = header.names.len();
    let unit: Vec<Vec<f64>> = ranked[..n_ok]
        .iter()
        .map(|s| (0..k).map(|j| header.to_unit(j, s.params[j])).collect())
        .collect();

    // Pareto set over (normalised residual, mean lifetime error, mean min-rate error).
    let c: Vec<[f64; 3]> = ranked[..n_ok].iter().map(pareto_criteria).collect();
    let mut pareto = pareto_front(&c);
    pareto.resize(ranked.len(), false);

    // Single-linkage clusters (union–find).
    let mut parent: Vec<usize> = (0..n_ok).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for i in 0..n_ok {
        for o in (i + 1)..n_ok {
            let d = (0..k)
                .map(|j| (unit[i][j] - unit[o][j]).abs())
                .fold(0.0, f64::max);
            if d <= CLUSTER_LINK {
                let (a, b) = (find(&mut parent, i), find(&mut parent, o));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut cluster = vec![0usize; ranked.len()];
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut root_id = std::collections::HashMap::new();
    for i in 0..n_ok {
        let r = find(&mut parent, i);
        let id = *root_id.entry(r).or_insert_with(|| {
            clusters.push(Cluster {
                id: clusters.len() + 1,
                size: 0,
                fraction: 0.0,
                best: i,
            });
            clusters.len()
        });
        cluster[i] = id;
        clusters[id - 1].size += 1;
    }
    for cl in &mut clusters {
        cl.fraction = cl.size as f64 / n_ok.max(1) as f64;
    }

    // Identifiability near the best.
    let mut spreads = Vec::new();
    let mut near_best = 0;
    let mut pinned = Vec::new();
    if n_ok > 0 {
        let best = &ranked[0];
        // Within NEAR_BEST of |best| (the likelihood objective, −2 ln L, can be negative).
        let limit = if best.objective >= 0.0 {
            best.objective * (1.0 + NEAR_BEST)
        } else {
            best.objective * (1.0 - NEAR_BEST)
        };
        let near: Vec<&Solution> = ranked[..n_ok]
            .iter()
            .filter(|s| s.objective <= limit)
            .collect();
        near_best = near.len();
        for j in 0..k {
            let vals: Vec<f64> = near.iter().map(|s| s.params[j]).collect();
            let (lo, hi) = vals
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            spreads.push(Spread {
                name: header.names[j].clone(),
                min: lo,
                max: hi,
                rel_range: (hi - lo) / best.params[j].abs(),
                unit_range: header.to_unit(j, hi) - header.to_unit(j, lo),
            });
            let u = header.to_unit(j, best.params[j]);
            if u <= BOUND_TOL {
                pinned.push((header.names[j].clone(), "lower".into(), best.params[j]));
            } else if u >= 1.0 - BOUND_TOL {
                pinned.push((header.names[j].clone(), "upper".into(), best.params[j]));
            }
        }
    }
    Analysis {
        completed: n_ok,
        failed: ranked.len() - n_ok,
        ranked,
        cluster,
        pareto,
        clusters,
        spreads,
        near_best,
        pinned,
    }
}

fn w_text(w: &[f64]) -> String {
    w.iter().map(|v| num(*v)).collect::<Vec<_>>().join(";")
}

/// Write `ranked.csv`, `minima.csv`, `summary.json` (which says whether the result is
/// complete: the shards it lacks (`coverage`) and the (start_id, w_idx) pairs without a
/// solution (`missing`)), then the plots; returns the plots that could not be written (`plot
/// PATH: why`), after every numeric file is in place.
///
/// `ranked.csv`'s `lifetime_err_pct` and `min_rate_err_pct` are means of absolute per-curve
/// errors (the DESIGN contract's names, kept); `mean_abs_lifetime_err_pct` and
/// `mean_abs_min_rate_err_pct` repeat them under names that cannot be mistaken for the
/// signed per-curve errors of `errors.csv`.
pub fn write(
    header: &Header,
    a: &Analysis,
    coverage: &Coverage,
    missing: &[(usize, usize)],
    out: &Path,
    wall_s: f64,
    threads: usize,
) -> Result<Vec<String>> {
    let (head, rows) = ranked_table(header, a);
    write_csv(&out.join("ranked.csv"), &head, &rows)?;
    let (mhead, mrows) = minima_table(header, a);
    write_csv(&out.join("minima.csv"), &mhead, &mrows)?;

    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary(header, a, coverage, missing, wall_s, threads))
            .expect("plain JSON"),
    )?;

    // Plots last: a failure is reported after the numbers are safely in place. The
    // waterfall gets every fit, failed ones (no objective, ranked last) included, so that
    // its counts add up.
    let mut failures = Vec::new();
    let objs: Vec<f64> = a.ranked.iter().map(|s| s.objective).collect();
    let scaled: Vec<Vec<f64>> = a
        .ranked
        .iter()
        .filter(|s| s.ok())
        .take(PLOT_BEST_K)
        .map(|s| {
            (0..header.names.len())
                .map(|j| header.to_unit(j, s.params[j]))
                .collect()
        })
        .collect();
    let title = &header.name;
    if let Err(e) = plot_waterfall(
        &out.join("waterfall.png"),
        &format!("{title}: sorted local minima"),
        &objs,
    ) {
        failures.push(e.to_string());
    }
    if let Err(e) = plot_parameters(
        &out.join("parameters.png"),
        &format!("{title}: best {} solutions within the bounds", scaled.len()),
        &header.names,
        &scaled,
    ) {
        failures.push(e.to_string());
    }
    Ok(failures)
}

/// The header and rows of `ranked.csv` ([`write`]).
pub fn ranked_table<'a>(header: &'a Header, a: &Analysis) -> (Vec<&'a str>, Vec<Vec<String>>) {
    let mut head: Vec<&str> = vec![
        "rank",
        "start_id",
        "w",
        "objective",
        "norm_residual",
        "lifetime_err_pct",
        "mean_abs_lifetime_err_pct",
        "min_rate_err_pct",
        "mean_abs_min_rate_err_pct",
        "status",
        "iterations",
        "evaluations",
        "cluster",
        "pareto",
    ];
    head.extend(header.names.iter().map(|s| s.as_str()));
    let rows: Vec<Vec<String>> = a
        .ranked
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let mut r = vec![
                (i + 1).to_string(),
                s.start_id.to_string(),
                w_text(&header.w[s.w_idx]),
                num(s.objective),
                num(s.norm_residual),
                num(s.lifetime_err_pct),
                num(s.lifetime_err_pct),
                num(s.min_rate_err_pct),
                num(s.min_rate_err_pct),
                s.status.clone(),
                s.iterations.to_string(),
                s.evaluations.to_string(),
                a.cluster[i].to_string(),
                u8::from(a.pareto[i]).to_string(),
            ];
            r.extend(s.params.iter().map(|v| num(*v)));
            r
        })
        .collect();
    (head, rows)
}

/// The header and rows of `minima.csv` ([`write`]).
pub fn minima_table<'a>(header: &'a Header, a: &Analysis) -> (Vec<&'a str>, Vec<Vec<String>>) {
    let mut mhead: Vec<&str> = vec!["cluster", "size", "fraction", "best_objective"];
    mhead.extend(header.names.iter().map(|s| s.as_str()));
    let mrows: Vec<Vec<String>> = a
        .clusters
        .iter()
        .map(|c| {
            let best = &a.ranked[c.best];
            let mut r = vec![
                c.id.to_string(),
                c.size.to_string(),
                num(c.fraction),
                num(best.objective),
            ];
            r.extend(best.params.iter().map(|v| num(*v)));
            r
        })
        .collect();
    (mhead, mrows)
}

fn constants_json(header: &Header, p: &[f64]) -> Value {
    let mut m = serde_json::Map::new();
    for (n, v) in header.names.iter().zip(p) {
        m.insert(n.clone(), jnum(*v));
    }
    Value::Object(m)
}

/// `summary.json` of a sweep. `complete` is true when no shard (`coverage`) and no
/// (start_id, w_idx) pair (`missing`) is missing; `missing` lists the shards left out (see
/// [`super::MissingShard`]), `missing_fits` / `missing_pairs` the fits without a solution.
pub fn summary(
    header: &Header,
    a: &Analysis,
    coverage: &Coverage,
    missing: &[(usize, usize)],
    wall_s: f64,
    threads: usize,
) -> Value {
    let sol_json = |i: usize| {
        let s = &a.ranked[i];
        json!({
            "rank": i + 1,
            "start_id": s.start_id,
            "w": header.w[s.w_idx],
            "objective": jnum(s.objective),
            "norm_residual": jnum(s.norm_residual),
            "lifetime_err_pct": jnum(s.lifetime_err_pct),
            "min_rate_err_pct": jnum(s.min_rate_err_pct),
            "lifetime_errs_pct": s.lifetime_errs_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
            "cluster": a.cluster[i],
            "status": s.status,
            "constants": constants_json(header, &s.params),
        })
    };
    let best_by_w: Vec<Value> = (0..header.w.len())
        .filter_map(|wi| {
            a.ranked
                .iter()
                .position(|s| s.ok() && s.w_idx == wi)
                .map(sol_json)
        })
        .collect();
    let pareto: Vec<Value> = (0..a.ranked.len())
        .filter(|&i| a.pareto[i])
        .map(sol_json)
        .collect();
    json!({
        "name": header.name,
        "model": header.model,
        "extensions": header.extensions,
        "run_id": header.fingerprint,
        "shard": format!("{}/{}", header.shard.0, header.shard.1),
        "complete": coverage.complete && missing.is_empty(),
        "missing": coverage.missing,
        "missing_fits": missing.len(),
        "missing_pairs": missing.iter().map(|(s, w)| json!({"start_id": s, "w_idx": w})).collect::<Vec<_>>(),
        "starts": header.n_starts_total(),
        "lhs_starts": header.n_starts,
        "extra_start": header.extra_start,
        "repaired_starts": header.repaired_starts,
        "seed": header.seed,
        "w_candidates": header.w.len(),
        "fits": a.ranked.len(),
        "completed": a.completed,
        "failed": a.failed,
        "distinct_minima": a.clusters.len(),
        "best_basin_fraction": a.clusters.first().map(|c| c.fraction),
        "best": if a.completed > 0 { sol_json(0) } else { Value::Null },
        "caution": best_caution(header, a),
        "objective_kind": header.objective_kind,
        "specimen_effects_not_fitted": header.effects_not_fitted,
        "objective_note": header.objective_note(),
        "best_by_w": best_by_w,
        "pareto": pareto,
        "pinned_at_bounds": a.pinned.iter().map(|(n, s, v)| json!({"name": n, "bound": s, "value": v})).collect::<Vec<_>>(),
        "identifiability": {
            "within_pct_of_best": 100.0 * NEAR_BEST,
            "solutions": a.near_best,
            "constants": a.spreads.iter().map(|s| json!({
                "name": s.name, "min": jnum(s.min), "max": jnum(s.max),
                "rel_range": jnum(s.rel_range), "unit_range": jnum(s.unit_range)
            })).collect::<Vec<_>>(),
        },
        "minima": a.clusters.iter().map(|c| json!({
            "cluster": c.id, "size": c.size, "fraction": c.fraction,
            "best_objective": jnum(a.ranked[c.best].objective),
            "constants": constants_json(header, &a.ranked[c.best].params),
        })).collect::<Vec<_>>(),
        "wall_s": wall_s,
        "threads": threads,
    })
}

/// The caution about the best fit's rupture times ([`crate::fit::lives_caution`], `fit`'s rule:
/// every life missed by 10× or more, or some by 5×), naming the worst curve; `None` without a
/// completed fit.
pub fn best_caution(header: &Header, a: &Analysis) -> Option<String> {
    if a.completed == 0 {
        return None;
    }
    crate::fit::lives_caution(&header.curve_labels(), &a.ranked[0].lifetime_errs_pct)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_trade_offs_and_drops_dominated_and_near_copies() {
        let c = [
            [0.25, 9.45, 44.05],    // best residual, poor lifetime
            [0.38, 2.1, 21.0],      // worse residual, better lifetime and rate: a trade-off
            [0.39, 2.5, 22.0],      // dominated by row 1 on all three
            [0.25001, 9.46, 44.06], // same bins as row 0 within tolerance, ranked lower: a copy
            [0.50, 1.0, 60.0],      // best lifetime: on the front
            [f64::NAN, 0.5, 10.0],  // unknown residual counts as worst, but best on the others
        ];
        let f = pareto_front(&c);
        assert_eq!(f, vec![true, true, false, false, true, true]);
    }

    #[test]
    fn unconverged_fits_stay_off_the_pareto_front() {
        let sol = |status: &str, res: f64, life: f64| Solution {
            start_id: 0,
            w_idx: 0,
            objective: res,
            norm_residual: res,
            lifetime_err_pct: life,
            min_rate_err_pct: 20.0,
            lifetime_errs_pct: vec![life],
            status: status.into(),
            iterations: 10,
            evaluations: 20,
            params: vec![1.0],
        };
        // The unconverged row would be a trade-off by its numbers (best lifetime error).
        let rows = [
            sol("converged_objective", 0.25, 9.4),
            sol("converged_step", 0.38, 2.1),
            sol("iteration_limit", 0.34, 1.0),
            sol("stalled", 0.20, 9.9),
        ];
        let c: Vec<[f64; 3]> = rows.iter().map(pareto_criteria).collect();
        assert_eq!(pareto_front(&c), vec![true, true, false, false]);
    }

    #[test]
    fn pareto_front_is_never_empty_and_keeps_one_of_identical_rows() {
        let c = [[1.0, 1.0, 1.0]; 4];
        assert_eq!(pareto_front(&c), vec![true, false, false, false]);
        assert!(pareto_front(&[]).is_empty());
    }
}
