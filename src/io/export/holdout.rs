//! `holdout`'s outputs: holdout.csv (each held-out test: measured, creepfit, every
//! baseline), constants.csv of the training fit, summary.json, the console table,
//! curves.png, parity.png and the diagrams of the training fit with every test.

use std::path::Path;

use serde_json::json;

use crate::baseline::BaselineKind;
use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::Result;
use crate::holdout::{
    baseline_columns, table, Holdout, LeftOut, RuptureInterval, CURVE_COLUMNS, INTERVAL_COLUMNS,
};
use crate::model::objective::mean_abs;
use crate::predict::diagrams::Diagrams;
use crate::report::plot::{
    plot_creep_curves, plot_xy, AxisScale, Dash, MarkerShape, Rgb, XyAxes, XyGroup,
};
use crate::report::tables::{self, jnum, num, write_csv, write_text};

use super::plots_done;

/// Write a finished holdout into `out` and print its table.
pub fn write(cfg: &RunConfig, data: &Dataset, h: &Holdout, out: &Path) -> Result<()> {
    let with_intervals = h.tests.iter().any(|t| t.interval.is_some());
    let best = &h.fit.fits[h.fit.best];
    let specimens = h.tests.iter().any(|t| t.specimen.is_some());
    let rows: Vec<Vec<String>> = h
        .tests
        .iter()
        .map(|t| {
            let mut r = vec![
                num(t.temperature_c),
                num(t.stress_mpa),
                num(t.rupture_time_h),
                num(t.model_rupture_time_h),
                num(t.lmp_rupture_time_h),
                num(t.model_log10_err()),
                num(t.lmp_log10_err()),
                num(t.curve_rms_pct),
            ];
            if with_intervals {
                let i = t.interval;
                let f = |g: fn(&RuptureInterval) -> f64| num(i.as_ref().map_or(f64::NAN, g));
                r.extend([
                    f(|i| i.pred95.0),
                    f(|i| i.pred95.1),
                    f(|i| i.conf95.0),
                    f(|i| i.conf95.1),
                    f(|i| i.value_h),
                ]);
            }
            if specimens {
                r.push(t.specimen.clone().unwrap_or_default());
            }
            for k in 1..BaselineKind::ALL.len() {
                r.push(num(t.baseline_rupture_time_h[k]));
                r.push(num(t.baseline_log10_err(k)));
            }
            r.extend([
                num(t.predicted_life_pct),
                t.curve_outcome.as_str().to_string(),
                t.curve_points.to_string(),
            ]);
            r
        })
        .collect();
    let mut header = crate::holdout::LIFE_COLUMNS.to_vec();
    header.push("curve_rms_pct");
    if with_intervals {
        header.extend(INTERVAL_COLUMNS);
    }
    let mut header = tables::with_specimen(&header, specimens);
    let baseline_columns = baseline_columns();
    header.extend(baseline_columns.iter().map(String::as_str));
    header.extend(CURVE_COLUMNS);
    write_csv(&out.join("holdout.csv"), &header, &rows)?;
    tables::write_constants(
        &out.join("constants.csv"),
        h.fit.model.as_ref(),
        &h.fit.space,
        &best.params,
        h.t_ref,
    )?;
    let inside_pred95 = {
        let (inside, with) = h.inside_pred95();
        json!({"inside": inside, "tests": with})
    };
    let scores = h.scores();
    let (baselines, one_to_beat) = crate::holdout::scores_json(&scores, &h.baselines);
    let [complete, early, no_rupture, failed, no_curve] = h.curve_outcomes();
    let summary = json!({
        "held_out_temperature_C": h.left_out.temperature_c(),
        "held_out": match &h.left_out {
            LeftOut::Temperature(t) => json!({"kind": "temperature", "temperature_C": t}),
            LeftOut::Campaign(name) => json!({"kind": "campaign", "campaign": name}),
        },
        "model": h.fit.model.name(),
        "objective_kind": cfg.objective.kind,
        "T_ref_C": h.t_ref,
        "training_objective": jnum(best.eval.objective),
        "training_w": best.w,
        "training_termination": best.lm.termination,
        "training_lifetime_err_pct": best.lifetime_err_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
        "training_caution": h.training_caution(),
        "specimen_effects_not_fitted": h.effects_left_out,
        "objective_note": h.objective_note(),
        "tests": h.tests.len(),
        "model_mean_abs_log10_err": jnum(h.model_mean_abs_log10()),
        "lmp_mean_abs_log10_err": jnum(h.lmp_mean_abs_log10()),
        "inside_pred95": inside_pred95,
        "interval_scope": h.interval_scope(),
        "intervals_refit": h.intervals_refit.as_ref().map(|r| json!({
            "what": "the intervals and ml_rupture_time_h come from the maximum-likelihood refit of the training fit's constants",
            "neg2ll": jnum(r.neg2ll),
            "training_fit_neg2ll": jnum(r.given_neg2ll),
            "delta_neg2ll": jnum(r.delta_neg2ll()),
            "specimen_effects": r.specimen_effects,
            "constants": h.fit.model.constants().iter().zip(r.given.iter().zip(&r.params)).map(|(c, (g, v))| json!({
                "name": c.name, "training_fit": g, "refit": v, "difference": v - g,
            })).collect::<Vec<_>>(),
        })),
        "mean_curve_rms_pct": jnum(mean_abs(&h.tests.iter().map(|t| t.curve_rms_pct).collect::<Vec<_>>())),
        "larson_miller": match &h.lmp {
            Ok(l) => json!(l),
            Err(e) => json!({"error": e}),
        },
        "model_tests_predicted": h.model_score().1,
        "model_mean_log10_err": jnum(scores.model_bias()),
        "baselines": baselines,
        "one_to_beat": one_to_beat,
        "creepfit_vs_one_to_beat": h.verdict(),
        "curve_outcomes": {
            "complete": complete,
            "ruptured_early": early,
            "no_rupture": no_rupture,
            "failed": failed,
            "no_curve": no_curve,
        },
        "training_temperatures_C": h.training_temperatures_c(),
        "temperature_extrapolation": h.temperature_extrapolation(),
    });
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;
    print!("{}", table(h));
    let mut failures = Vec::new();
    let held = Dataset::of_curves(h.curves.clone());
    let plots = crate::predict::curve_plots(
        cfg,
        &held,
        &best.params,
        &h.fit.settings.ode,
        h.fit.model.as_ref(),
    );
    if h.curves.is_empty() {
        // Only life-only tests held out: no curve to draw.
    } else if let Err(e) = plot_creep_curves(
        &out.join("curves.png"),
        &format!(
            "{} — {} held out: measured (points), predicted (lines)",
            cfg.name,
            h.left_out.label()
        ),
        &plots,
    ) {
        failures.push(e.to_string());
    }
    let meas: Vec<f64> = h.tests.iter().map(|t| t.rupture_time_h).collect();
    let (lo, hi) = meas
        .iter()
        .chain(h.tests.iter().map(|t| &t.model_rupture_time_h))
        .chain(h.tests.iter().map(|t| &t.lmp_rupture_time_h))
        .chain(h.tests.iter().flat_map(|t| &t.baseline_rupture_time_h))
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let diag = |f: f64| vec![(lo / 1.2, f * lo / 1.2), (hi * 1.2, f * hi * 1.2)];
    let mut groups = vec![
        XyGroup::points(
            format!("creepfit: mean |log10 err| {:.3}", h.model_mean_abs_log10()),
            h.tests
                .iter()
                .map(|t| (t.rupture_time_h, t.model_rupture_time_h))
                .collect(),
            Rgb::palette(0),
            MarkerShape::Circle,
        ),
        XyGroup::points(
            format!(
                "Larson–Miller: mean |log10 err| {:.3}",
                h.lmp_mean_abs_log10()
            ),
            h.tests
                .iter()
                .map(|t| (t.rupture_time_h, t.lmp_rupture_time_h))
                .collect(),
            Rgb::palette(1),
            MarkerShape::Circle,
        ),
        XyGroup::line("predicted = measured", diag(1.0), Rgb::BLACK, Dash::Solid),
        XyGroup::line("factor 2", diag(2.0), Rgb::BLACK, Dash::Dashed),
        XyGroup::line("", diag(0.5), Rgb::BLACK, Dash::Dashed),
    ];
    // The other baselines' points after Larson–Miller's, before the lines.
    for (k, b) in h.baselines.iter().enumerate().skip(1) {
        if b.fit.is_ok() {
            groups.insert(
                groups.len() - 3,
                XyGroup::points(
                    format!(
                        "{}: mean |log10 err| {:.3}",
                        b.kind.name(),
                        h.baseline_score(k).0
                    ),
                    h.tests
                        .iter()
                        .map(|t| (t.rupture_time_h, t.baseline_rupture_time_h[k]))
                        .filter(|p| p.1.is_finite())
                        .collect(),
                    Rgb::palette(k + 1),
                    MarkerShape::Triangle,
                ),
            );
        }
    }
    if let Err(e) = plot_xy(
        &out.join("parity.png"),
        &format!(
            "{} — rupture times of {}, held out",
            cfg.name,
            h.left_out.label()
        ),
        XyAxes {
            x_label: "measured rupture time (h)",
            y_label: "predicted rupture time (h)",
            x_scale: AxisScale::Log,
            y_scale: AxisScale::Log,
        },
        &groups,
    ) {
        failures.push(e.to_string());
    }
    // A held-out temperature's tests are drawn as open circles beside the training ones; a
    // held-out campaign shares its temperatures with the training data, and the diagrams
    // show the training tests alone (parity.png and curves.png show the held-out ones).
    failures.extend(
        Diagrams {
            cfg,
            data: match h.left_out {
                LeftOut::Temperature(_) => data,
                LeftOut::Campaign(_) => &h.training,
            },
            model: h.fit.model.as_ref(),
            params: &best.params,
            lmp: h.lmp.as_ref().ok(),
            asked: &[],
            held_out_c: h.left_out.temperature_c(),
        }
        .write(out),
    );
    println!("wrote {}", out.display());
    plots_done(out, failures)
}
