//! `simulate`'s outputs: curves.csv (dense trajectories with the model's outputs),
//! ruptures.csv (each test's outcome), objective.json under `--w`, the console report and
//! simulate.png.

use std::path::Path;

use crate::config::RunConfig;
use crate::data::Dataset;
use crate::error::Result;
use crate::model::objective::Evaluation;
use crate::model::Model;
use crate::ode::OdeOptions;
use crate::predict::curve_plots;
use crate::report::plot::plot_creep_curves;
use crate::report::tables::{self, num, write_csv, write_text};
use crate::simulate::Simulated;

use super::plots_done;

/// Write the simulated tests (and the objective at one weight `w`, when asked) into `out`.
#[allow(clippy::too_many_arguments)]
pub fn write(
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    ode: &OdeOptions,
    sims: &[Simulated],
    objective: Option<(f64, &Evaluation)>,
    out: &Path,
) -> Result<()> {
    let specimens = tables::has_specimens(&data.curves);
    let specimen =
        |c: &crate::data::Curve| specimens.then(|| c.specimen.clone().unwrap_or_default());
    let mut rupture_rows = Vec::new();
    for s in sims {
        let (c, res) = (s.curve, &s.result);
        let mut row = vec![
            num(c.temperature_c),
            num(c.stress_mpa),
            if res.ruptured() {
                num(res.t_end)
            } else {
                String::new()
            },
            if res.ruptured() {
                num(100.0 * res.strain_end)
            } else {
                String::new()
            },
            // A failed simulation has no minimum rate (only a rupture or the horizon do).
            s.min_rate().map(|r| num(100.0 * r)).unwrap_or_default(),
            res.outcome.as_str().to_string(),
        ];
        row.extend(specimen(c));
        rupture_rows.push(row);
        println!(
            "{} °C {:>6} MPa{}: {} at t = {:.1} h, strain {:.3} %, min rate {:.4e} %/h",
            c.temperature_c,
            c.stress_mpa,
            c.specimen
                .as_ref()
                .map(|s| format!(" (specimen {s})"))
                .unwrap_or_default(),
            res.outcome.as_str(),
            res.t_end,
            100.0 * res.strain_end,
            100.0 * res.min_rate
        );
    }
    // The model's output columns (H, Phi, omega for KHD) after the strain.
    let mut curve_header = vec!["temperature_C", "stress_MPa", "time_h", "strain_pct"];
    curve_header.extend(model.output_names());
    // Rows formatted as they are written (a logged curve gives a million of them).
    let curve_rows = sims.iter().flat_map(|s| {
        let c = s.curve;
        s.trajectory.iter().map(move |(t, e, y)| {
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(*t),
                num(100.0 * e),
            ];
            row.extend(y.iter().map(|v| num(*v)));
            row.extend(specimen(c));
            row
        })
    });
    tables::write_csv_rows(
        &out.join("curves.csv"),
        &tables::with_specimen(&curve_header, specimens),
        curve_rows,
    )?;
    let rupture_header = [
        "temperature_C",
        "stress_MPa",
        "rupture_time_h",
        "rupture_strain_pct",
        "min_rate_pct_per_h",
        "outcome",
    ];
    write_csv(
        &out.join("ruptures.csv"),
        &tables::with_specimen(&rupture_header, specimens),
        &rupture_rows,
    )?;
    if let Some((w, e)) = objective {
        println!(
            "objective {:.12e} at w = {w} (normalised residual {:.12e})",
            e.objective, e.norm_residual
        );
        let json = serde_json::json!({
            "w": w,
            "objective": e.objective,
            "norm_residual": e.norm_residual,
            "lifetime_errors_pct": e.lifetime_errors_pct(&data.curves),
        });
        write_text(
            &out.join("objective.json"),
            &serde_json::to_string_pretty(&json).expect("JSON of plain values"),
        )?;
    }
    let plots = curve_plots(cfg, data, params, ode, model);
    let plotted = plot_creep_curves(
        &out.join("simulate.png"),
        &format!("{} — simulated", cfg.name),
        &plots,
    );
    println!("wrote {}", out.display());
    plots_done(
        out,
        plotted.err().map(|e| e.to_string()).into_iter().collect(),
    )
}
