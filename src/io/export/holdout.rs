//! `holdout`'s outputs: holdout.csv (each held-out test: measured, creepfit, every
//! baseline), constants.csv of the training fit, summary.json, the console table,
//! curves.png, parity.png and the diagrams of the training fit with every test.

use std::path::Path;

use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::Result;
use crate::holdout::{table, Holdout, LeftOut};
use crate::predict::diagrams::Diagrams;
use crate::report::plot::{
    plot_creep_curves, plot_xy, AxisScale, Dash, MarkerShape, Rgb, XyAxes, XyGroup,
};
use crate::report::tables::{self, write_csv, write_text};

use super::plots_done;

/// Write a finished holdout into `out` and print its table.
pub fn write(cfg: &RunConfig, data: &Dataset, h: &Holdout, out: &Path) -> Result<()> {
    let best = &h.fit.fits[h.fit.best];
    let (header, rows) = crate::holdout::csv_table(h);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_csv(&out.join("holdout.csv"), &header, &rows)?;
    tables::write_constants(
        &out.join("constants.csv"),
        h.fit.model.as_ref(),
        &h.fit.space,
        &best.params,
        h.t_ref,
    )?;
    let summary = crate::holdout::summary_json(cfg, h);
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
