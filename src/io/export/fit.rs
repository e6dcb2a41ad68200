//! `fit`'s outputs: constants.csv, errors.csv, curves.csv, specimens.csv, summary.json, the
//! console report, fit.png and the diagrams (stress–rupture, Norton, Larson–Miller).

use std::path::Path;

use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::Result;
use crate::fit::FitRun;
use crate::predict::curve_plots;
use crate::predict::diagrams::Diagrams;
use crate::report::plot::plot_creep_curves;
use crate::report::tables::{self, write_text};

use super::plots_done;

/// Write a finished fit of `data` under `cfg` into `out` and report it on stdout.
pub fn write(cfg: &RunConfig, data: &Dataset, run: &FitRun, out: &Path) -> Result<()> {
    let best = &run.fits[run.best];
    let curves = &data.curves;
    tables::write_constants(
        &out.join("constants.csv"),
        run.model.as_ref(),
        &run.space,
        &best.params,
        cfg.has_laws().then_some(cfg.t_ref).flatten(),
    )?;
    let rows = tables::error_rows(best, curves);
    tables::write_errors(&out.join("errors.csv"), &rows)?;
    tables::write_fit_curves(&out.join("curves.csv"), best, curves)?;
    let summary = tables::fit_summary(cfg, run, curves);
    if let Some(sp) = &run.specimens.fit {
        tables::write_specimens(&out.join("specimens.csv"), sp, curves)?;
    }
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;

    println!(
        "{}: model {}, {} curves, {} local fits in {:.2} s",
        cfg.name,
        run.model.name(),
        curves.len(),
        run.fits.len(),
        run.wall_s
    );
    println!(
        "best: start {}, w = {:?}, objective {:.6}, normalised residual {:.6}, {} ({} iterations, {} evaluations)",
        best.start_label,
        best.w,
        best.eval.objective,
        best.eval.norm_residual,
        best.lm.termination.as_str(),
        best.lm.iterations,
        best.lm.evaluations
    );
    for (j, c) in run.model.constants().iter().enumerate() {
        let pin = if run.space.free[j] {
            run.space
                .at_bound(j, best.params[j], 1e-6)
                .map(|s| format!("  (at {s} bound)"))
                .unwrap_or_default()
        } else {
            "  (held)".to_string()
        };
        println!(
            "  {:>6} = {:<12.6e} {}{}",
            c.name, best.params[j], c.unit, pin
        );
    }
    print!("{}", tables::error_table(&rows, run.used_min_rate));
    if let Some(c) = summary.get("caution").and_then(|c| c.as_str()) {
        println!("caution: {c}");
    }
    if let Some(n) = summary.get("objective_note").and_then(|n| n.as_str()) {
        println!("note: {n}");
    }
    print_specimens(&run.specimens);
    if let Some(a) = summary.get("activation_energy") {
        print_activation(a);
    }
    let per_t = crate::fit::errors_per_temperature(best, curves);
    if per_t.len() > 1 {
        for e in &per_t {
            let at = run.model.constants_at(&best.params, e.temperature_c);
            println!(
                "{:>6} °C: normalised residual {:.6}, mean |lifetime err| {:.2} %, mean |min-rate err| {:.2} %; constants there: {}",
                e.temperature_c,
                e.norm_residual,
                e.mean_lifetime_err_pct,
                e.mean_min_rate_err_pct,
                run.model
                    .inner_constants()
                    .iter()
                    .zip(&at)
                    .map(|(c, v)| format!("{} = {v:.4e}", c.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    if let Some(e) = summary.get("error_model").filter(|e| !e.is_null()) {
        let list = |key: &str, prec: usize| -> String {
            e["curves"]
                .as_array()
                .map(|v| {
                    v.iter()
                        .map(|c| format!("{:.prec$}", c[key].as_f64().unwrap_or(f64::NAN)))
                        .collect::<Vec<_>>()
                        .join(" / ")
                })
                .unwrap_or_default()
        };
        println!(
            "error model at these constants (AR(1) per curve): residual sd {} % strain, φ {}; \
             rupture-time scatter {:.2} % (summary.json: error_model)",
            list("residual_sd_pct", 4),
            list("ar1_phi", 2),
            e["lifetime_sd_pct"].as_f64().unwrap_or(f64::NAN)
        );
    }

    // Plot last: a plotting failure never loses the numeric outputs above.
    let plot_path = out.join("fit.png");
    let plots = curve_plots(
        cfg,
        data,
        &best.params,
        &run.settings.ode,
        run.model.as_ref(),
    );
    let plotted = plot_creep_curves(
        &plot_path,
        &format!("{} — measured (points) and fitted (lines)", cfg.name),
        &plots,
    );
    let mut failures: Vec<String> = plotted.err().map(|e| e.to_string()).into_iter().collect();
    // The diagrams beside the Larson–Miller baseline of the same rupture times (none at one
    // temperature).
    let lmp = crate::lmp::LarsonMiller::fit_curves(&data.curves, cfg.predict.lmp_degree).ok();
    failures.extend(
        Diagrams {
            cfg,
            data,
            model: run.model.as_ref(),
            params: &best.params,
            lmp: lmp.as_ref(),
            asked: &[],
            held_out_c: None,
        }
        .write(out),
    );
    println!("wrote {}", out.display());
    plots_done(out, failures)
}

/// `summary.json`'s `activation_energy` in one line: the ranges over the tested loads.
fn print_activation(a: &serde_json::Value) {
    let range = |side: &str, key: &str| -> String {
        let v: Vec<f64> = a[side]
            .as_array()
            .map(|v| v.iter().filter_map(|x| x[key].as_f64()).collect())
            .unwrap_or_default();
        if v.is_empty() {
            return "-".into();
        }
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        format!("{lo:.0}–{hi:.0}")
    };
    println!(
        "apparent activation energy (kJ/mol; −R ∂ln ε̇_min/∂(1/T), R ∂ln t_r/∂(1/T) at the tested loads; summary.json: activation_energy): model: min rate {}, rupture time {}; data (a stress tested at several temperatures): min rate {}, rupture time {}",
        range("model", "q_min_rate_kj_mol"),
        range("model", "q_rupture_time_kj_mol"),
        range("data", "q_min_rate_kj_mol"),
        range("data", "q_rupture_time_kj_mol"),
    );
}

/// The scatter between specimens a likelihood fit found, in words.
fn print_specimens(sp: &crate::fit::FitSpecimens) {
    if let Some(f) = &sp.fit {
        for (j, k) in f.kinds.iter().enumerate() {
            let what = k.describe();
            if crate::likelihood::scatter_at_bound(f.scatter[j]) {
                println!(
                    "specimens: the {what}'s scatter is at the estimate's bound (sd of ln factor {:.1}): the data do not bound it",
                    f.scatter[j]
                );
                continue;
            }
            println!(
                "specimens: the {what} varies {:.0} % between specimens (sd of ln factor {:.3}, 95 % {:.3}–{:.3}{}; specimens.csv: each specimen's factor)",
                tables::lognormal_cv_pct(f.scatter[j]),
                f.scatter[j],
                f.scatter_lo95[j],
                f.scatter_hi95[j],
                tables::scatter_dof_note(f.scatter_dof.get(j).copied())
            );
        }
        if f.scatter_method != crate::specimen::ScatterMethod::LinearMixedModel {
            println!("specimens: the scatter is {}", f.scatter_method.note());
        }
        for k in &f.dropped {
            println!("specimens: no {k:?} scatter supported by the data (estimated at zero)");
        }
        for (what, groups) in [
            ("temperature", &sp.by_temperature),
            ("campaign", &sp.by_campaign),
        ] {
            if groups.is_empty() {
                continue;
            }
            let per_kind: Vec<String> = f
                .kinds
                .iter()
                .enumerate()
                .map(|(j, k)| {
                    let g: Vec<String> = groups
                        .iter()
                        .map(|g| {
                            let se = if g.se[j].is_finite() {
                                format!(" ± {:.2}", g.se[j])
                            } else {
                                String::new()
                            };
                            format!("{} {:+.2}{se} ({})", g.group, g.mean_ln[j], g.specimens)
                        })
                        .collect();
                    format!("{} {}", k.name(), g.join(", "))
                })
                .collect();
            println!(
                "specimens: mean ln factor by {what} (± standard error; specimens): {}; the factors scatter about 0 in every group by assumption: a mean several standard errors from 0 is a {what} dependence the constants miss and the factors take up",
                per_kind.join("; ")
            );
        }
    }
    for t in &sp.stress_trend {
        if !t.slope.is_finite() {
            continue;
        }
        let flag = if t.follows_stress() {
            format!(
                ": the {} factors follow stress, a stress dependence the constants miss and the factors take up",
                t.kind.name()
            )
        } else {
            String::new()
        };
        println!(
            "specimens: ln {} factor against ln stress within temperatures: slope {:+.2} ± {:.2} (t-test p {}, {} degrees of freedom; called at p < {}){flag}",
            t.kind.name(),
            t.slope,
            t.se,
            tables::p_text(t.p_value),
            t.df,
            crate::likelihood::STRESS_TREND_ALPHA
        );
    }
    for t in &sp.temperature_levels {
        println!(
            "specimens: {}",
            tables::temperature_levels_text(t).replace("**", "")
        );
    }
    for c in &sp.campaign_levels {
        println!(
            "specimens: {}",
            tables::campaign_levels_text(c).replace("**", "")
        );
    }
    if let Some(n) = &sp.note {
        println!("specimens: {n}");
    }
}
