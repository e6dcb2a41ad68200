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
use crate::report::tables::{self, write_csv, write_text};
use crate::simulate::{self, Simulated};

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
    for s in sims {
        let (c, res) = (s.curve, &s.result);
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
    let header = simulate::curves_header(model, sims);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    tables::write_csv_rows(
        &out.join("curves.csv"),
        &header,
        simulate::curves_rows(sims),
    )?;
    let (header, rows) = simulate::ruptures_table(sims);
    write_csv(&out.join("ruptures.csv"), &header, &rows)?;
    if let Some((w, e)) = objective {
        println!(
            "objective {:.12e} at w = {w} (normalised residual {:.12e})",
            e.objective, e.norm_residual
        );
        write_text(
            &out.join("objective.json"),
            &serde_json::to_string_pretty(&simulate::objective_json(data, w, e))
                .expect("JSON of plain values"),
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
