//! Leave one temperature out: how well does a calibration predict a temperature it has not
//! seen? `creepfit holdout CONFIG --temperature T` fits the configuration on every curve not
//! at T (`fit`'s procedure from the configured start, the guess and `[sweep] starts`
//! Latin-hypercube starts: the held-out data choose nothing, not even the basin), predicts the rupture time and the curve of
//! every test at T, and fits the Larson–Miller baseline to the same training rupture times.
//! Both are scored by the mean |log10(t_predicted / t_measured)| over the held-out tests.

use std::path::Path;

use serde_json::json;

use crate::config::{Overrides, RunConfig};
use crate::data::{Curve, Dataset};
use crate::error::{Error, Result};
use crate::fit::{run_fit_multistart, FitRun};
use crate::lmp::LarsonMiller;
use crate::model::Load;
use crate::objective::{mean_abs, Objective};
use crate::output::RunFolder;
use crate::report::plot::{plot_creep_curves, plot_xy, AxisScale, XyAxes, XyGroup};
use crate::report::tables::{self, jnum, num, write_csv, write_text};

/// One held-out test and its predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// Stress, MPa.
    pub stress_mpa: f64,
    /// Specimen label, if any.
    pub specimen: Option<String>,
    /// Measured rupture time, h.
    pub rupture_time_h: f64,
    /// creepfit's rupture time, h (NaN if the prediction did not rupture).
    pub model_rupture_time_h: f64,
    /// The Larson–Miller baseline's, h (NaN without a baseline).
    pub lmp_rupture_time_h: f64,
    /// RMS of (predicted − measured strain) / rupture strain over the measured points, %.
    pub curve_rms_pct: f64,
    /// Under `--intervals`: the rupture time's 95 % intervals at this test's load from the
    /// training data ([`crate::uncertainty::predict::intervals_at`]), or none.
    pub interval: Option<RuptureInterval>,
}

/// The 95 % intervals of a held-out test's rupture time, h.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RuptureInterval {
    /// Prediction at the maximum-likelihood constants the intervals were computed from.
    pub value_h: f64,
    /// Prediction interval of a new test (adds the specimen scatter).
    pub pred95: (f64, f64),
    /// Confidence interval of the model's prediction.
    pub conf95: (f64, f64),
}

impl RuptureInterval {
    /// Whether the measured rupture time lies in the prediction interval of a new test.
    pub fn contains(&self, t_h: f64) -> bool {
        self.pred95.0 <= t_h && t_h <= self.pred95.1
    }
}

impl HeldOut {
    /// log10(t_model / t_measured).
    pub fn model_log10_err(&self) -> f64 {
        (self.model_rupture_time_h / self.rupture_time_h).log10()
    }
    /// log10(t_lmp / t_measured).
    pub fn lmp_log10_err(&self) -> f64 {
        (self.lmp_rupture_time_h / self.rupture_time_h).log10()
    }
}

/// What a hold-out run computed.
pub struct Holdout {
    /// The temperature left out, °C.
    pub temperature_c: f64,
    /// The fit on the other temperatures.
    pub fit: FitRun,
    /// The baseline on the same training data, or why there is none.
    pub lmp: std::result::Result<LarsonMiller, String>,
    /// The held-out tests (with a measured rupture time).
    pub tests: Vec<HeldOut>,
    /// The held-out curves.
    pub curves: Vec<Curve>,
    /// Under `--intervals`: the maximum-likelihood refit of the training fit's constants the
    /// intervals (and `ml_rupture_time_h`) come from.
    pub intervals_refit: Option<crate::uncertainty::predict::Refit>,
}

impl Holdout {
    /// creepfit's mean |log10 error| of the rupture time over the held-out tests.
    pub fn model_mean_abs_log10(&self) -> f64 {
        mean_abs(
            &self
                .tests
                .iter()
                .map(|t| t.model_log10_err())
                .collect::<Vec<_>>(),
        )
    }
    /// Under `--intervals`: (measured lives inside the 95 % prediction interval of a new test,
    /// tests with an interval).
    pub fn inside_pred95(&self) -> (usize, usize) {
        let with: Vec<&HeldOut> = self.tests.iter().filter(|t| t.interval.is_some()).collect();
        let inside = with
            .iter()
            .filter(|t| t.interval.is_some_and(|i| i.contains(t.rupture_time_h)))
            .count();
        (inside, with.len())
    }
    /// The baseline's.
    pub fn lmp_mean_abs_log10(&self) -> f64 {
        mean_abs(
            &self
                .tests
                .iter()
                .map(|t| t.lmp_log10_err())
                .collect::<Vec<_>>(),
        )
    }
}

/// Fit `cfg` on the curves of `data` not at `temperature_c`, predict those at it; with
/// `intervals`, also the 95 % intervals of each held-out rupture time from the training data.
pub fn holdout(
    cfg: &RunConfig,
    data: &Dataset,
    temperature_c: f64,
    intervals: bool,
) -> Result<Holdout> {
    if !cfg.has_laws() {
        return Err(Error::config(
            &cfg.path,
            "constants: a hold-out across temperatures needs temperature laws (law = \"arrhenius\" or \"linear\" on some constant)",
        ));
    }
    let (test, train): (Vec<Curve>, Vec<Curve>) = data
        .curves
        .iter()
        .cloned()
        .partition(|c| c.temperature_c == temperature_c);
    let mut temps: Vec<f64> = train.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    if test.is_empty() {
        return Err(Error::Invalid(format!(
            "--temperature {temperature_c}: no curves at that temperature"
        )));
    }
    if temps.len() < 2 {
        return Err(Error::Invalid(format!(
            "--temperature {temperature_c}: {} temperature(s) left to fit; the laws need two or more",
            temps.len()
        )));
    }
    let train_data = Dataset {
        curves: train,
        warnings: Vec::new(),
        dropped: Vec::new(),
    };
    let fit = run_fit_multistart(cfg, &train_data, cfg.sweep.starts)?;
    let best = &fit.fits[fit.best];
    let lmp = LarsonMiller::fit_curves(&train_data.curves, cfg.predict.lmp_degree)
        .map_err(|e| e.to_string());
    let settings = crate::fit::FitSettings::from_config(cfg);
    let eval = Objective::new(
        fit.model.as_ref(),
        &test,
        vec![1.0; test.len()],
        settings.objective(),
    )
    .evaluate(&best.params);
    // One interval per distinct held-out stress (replicates share it).
    let mut stresses: Vec<f64> = test
        .iter()
        .filter(|c| c.rupture_time_h.is_some())
        .map(|c| c.stress_mpa)
        .collect();
    stresses.sort_by(f64::total_cmp);
    stresses.dedup();
    let mut intervals_refit = None;
    let by_stress: Vec<Option<RuptureInterval>> = if intervals {
        let loads: Vec<Load> = stresses
            .iter()
            .map(|&s| Load::new(s, temperature_c, cfg.objective.omega_f))
            .collect();
        let iv = crate::uncertainty::predict::intervals_at(
            cfg,
            fit.model.as_ref(),
            &train_data,
            &best.params,
            &loads,
        )?;
        intervals_refit = Some(iv.refit);
        iv.conditions
            .iter()
            .map(|ci| {
                ci.get("rupture_time_h").map(|q| RuptureInterval {
                    value_h: q.value,
                    pred95: (q.pred_lo95, q.pred_hi95),
                    conf95: (q.conf_lo95, q.conf_hi95),
                })
            })
            .collect()
    } else {
        vec![None; stresses.len()]
    };
    let tests = test
        .iter()
        .zip(&eval.curves)
        .filter(|(c, _)| c.rupture_time_h.is_some())
        .map(|(c, p)| {
            let n = c.times_h.len();
            let ss: f64 = (0..n)
                .map(|k| ((p.strain[k] - c.strains[k]) / c.rupture_strain).powi(2))
                .sum();
            HeldOut {
                stress_mpa: c.stress_mpa,
                specimen: c.specimen.clone(),
                rupture_time_h: c.rupture_time_h.unwrap_or(f64::NAN),
                model_rupture_time_h: p.rupture_time_h,
                lmp_rupture_time_h: lmp
                    .as_ref()
                    .map_or(f64::NAN, |l| l.rupture_time(c.temperature_c, c.stress_mpa)),
                curve_rms_pct: 100.0 * (ss / n as f64).sqrt(),
                interval: stresses
                    .iter()
                    .position(|&s| s == c.stress_mpa)
                    .and_then(|k| by_stress[k]),
            }
        })
        .collect();
    Ok(Holdout {
        temperature_c,
        fit,
        lmp,
        tests,
        curves: test,
        intervals_refit,
    })
}

/// The printed table.
pub fn table(h: &Holdout) -> String {
    let mut s = format!(
        "held out {} °C: {} tests\n   MPa  specimen  |  t_r meas h  creepfit h     LMP h | log10 err creepfit    LMP | curve rms % e_f\n",
        h.temperature_c,
        h.tests.len()
    );
    for t in &h.tests {
        s.push_str(&format!(
            "{:>6} {:>9} | {:>11.1} {:>11.1} {:>9.1} | {:>18.3} {:>6.3} | {:>8.2}\n",
            t.stress_mpa,
            t.specimen.as_deref().unwrap_or("-"),
            t.rupture_time_h,
            t.model_rupture_time_h,
            t.lmp_rupture_time_h,
            t.model_log10_err(),
            t.lmp_log10_err(),
            t.curve_rms_pct
        ));
    }
    s.push_str(&format!(
        "mean |log10 error| of the rupture time: creepfit {:.3}, Larson–Miller {:.3}\n",
        h.model_mean_abs_log10(),
        h.lmp_mean_abs_log10()
    ));
    let (inside, with) = h.inside_pred95();
    if with > 0 {
        s.push_str("95 % intervals of the rupture time from the training data (maximum-likelihood fit, error model of README \"How sure\"): prediction interval of a NEW TEST | confidence interval of the model's prediction\n");
        for t in &h.tests {
            if let Some(i) = t.interval {
                s.push_str(&format!(
                    "{:>6} {:>9} | measured {:>11.1} | new test [{:.1}, {:.1}] {} | model {:.1} [{:.1}, {:.1}]\n",
                    t.stress_mpa,
                    t.specimen.as_deref().unwrap_or("-"),
                    t.rupture_time_h,
                    i.pred95.0,
                    i.pred95.1,
                    if i.contains(t.rupture_time_h) { "inside " } else { "OUTSIDE" },
                    i.value_h,
                    i.conf95.0,
                    i.conf95.1
                ));
            }
        }
        s.push_str(&format!(
            "measured lives inside the 95 % prediction interval of a new test: {inside} of {with}\n"
        ));
        if let Some(r) = &h.intervals_refit {
            s.push_str(&format!(
                "the intervals are centred on the maximum-likelihood refit of the training fit's constants (holdout.csv: ml_rupture_time_h; −2 ln L {:.3} there, {:.3} at the training fit: difference {:.3}; summary.json: intervals_refit)\n",
                r.neg2ll,
                r.given_neg2ll,
                r.delta_neg2ll()
            ));
        }
    }
    if let Err(e) = &h.lmp {
        s.push_str(&format!("no Larson–Miller baseline: {e}\n"));
    }
    s
}

/// `holdout.csv`'s columns under `--intervals` (after `curve_rms_pct`): the 95 % prediction
/// interval of a new test, the 95 % confidence interval of the model's prediction, and the
/// prediction at the maximum-likelihood constants both were computed from (h).
pub const INTERVAL_COLUMNS: [&str; 5] = [
    "rupture_time_lo95_h",
    "rupture_time_hi95_h",
    "rupture_time_conf_lo95_h",
    "rupture_time_conf_hi95_h",
    "ml_rupture_time_h",
];

/// `creepfit holdout`: run, print, write `holdout.csv`, `constants.csv`, `summary.json`,
/// `curves.png` and `parity.png`.
pub fn holdout_cmd(config: &Path, temperature_c: f64, cli: &Overrides) -> Result<()> {
    let (cfg, data) = crate::cli::load(config, cli)?;
    let out = cfg.out_dir(&format!("holdout-{temperature_c}C"));
    let mut folder = RunFolder::begin(&out, "holdout")?;
    crate::cli::note_data(&mut folder, &data);
    folder.finish(holdout_into(&cfg, &data, temperature_c, &out))
}

/// `holdout`'s computation and outputs into `out`.
fn holdout_into(cfg: &RunConfig, data: &Dataset, temperature_c: f64, out: &Path) -> Result<()> {
    let h = holdout(cfg, data, temperature_c, cfg.predict.intervals)?;
    let with_intervals = h.tests.iter().any(|t| t.interval.is_some());
    let best = &h.fit.fits[h.fit.best];
    let specimens = h.tests.iter().any(|t| t.specimen.is_some());
    let rows: Vec<Vec<String>> = h
        .tests
        .iter()
        .map(|t| {
            let mut r = vec![
                num(h.temperature_c),
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
            r
        })
        .collect();
    let mut header = vec![
        "temperature_C",
        "stress_MPa",
        "rupture_time_h",
        "model_rupture_time_h",
        "lmp_rupture_time_h",
        "model_log10_err",
        "lmp_log10_err",
        "curve_rms_pct",
    ];
    if with_intervals {
        header.extend(INTERVAL_COLUMNS);
    }
    write_csv(
        &out.join("holdout.csv"),
        &tables::with_specimen(&header, specimens),
        &rows,
    )?;
    tables::write_constants(
        &out.join("constants.csv"),
        h.fit.model.as_ref(),
        &h.fit.space,
        &best.params,
        cfg.t_ref,
    )?;
    let inside_pred95 = {
        let (inside, with) = h.inside_pred95();
        json!({"inside": inside, "tests": with})
    };
    let summary = json!({
        "held_out_temperature_C": h.temperature_c,
        "model": h.fit.model.name(),
        "objective_kind": cfg.objective.kind,
        "T_ref_C": cfg.t_ref,
        "training_objective": jnum(best.eval.objective),
        "training_w": best.w,
        "training_termination": best.lm.termination,
        "training_lifetime_err_pct": best.lifetime_err_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
        "tests": h.tests.len(),
        "model_mean_abs_log10_err": jnum(h.model_mean_abs_log10()),
        "lmp_mean_abs_log10_err": jnum(h.lmp_mean_abs_log10()),
        "inside_pred95": inside_pred95,
        "intervals_refit": h.intervals_refit.as_ref().map(|r| json!({
            "what": "the intervals and ml_rupture_time_h come from the maximum-likelihood refit of the training fit's constants",
            "neg2ll": jnum(r.neg2ll),
            "training_fit_neg2ll": jnum(r.given_neg2ll),
            "delta_neg2ll": jnum(r.delta_neg2ll()),
            "constants": h.fit.model.constants().iter().zip(r.given.iter().zip(&r.params)).map(|(c, (g, v))| json!({
                "name": c.name, "training_fit": g, "refit": v, "difference": v - g,
            })).collect::<Vec<_>>(),
        })),
        "mean_curve_rms_pct": jnum(mean_abs(&h.tests.iter().map(|t| t.curve_rms_pct).collect::<Vec<_>>())),
        "larson_miller": match &h.lmp {
            Ok(l) => json!(l),
            Err(e) => json!({"error": e}),
        },
        "wall_s": h.fit.wall_s,
    });
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;
    print!("{}", table(&h));
    let mut failures = Vec::new();
    let held = Dataset {
        curves: h.curves.clone(),
        warnings: Vec::new(),
        dropped: Vec::new(),
    };
    let plots = crate::cli::curve_plots(
        cfg,
        &held,
        &best.params,
        &h.fit.settings.ode,
        h.fit.model.as_ref(),
    );
    if let Err(e) = plot_creep_curves(
        &out.join("curves.png"),
        &format!(
            "{} — {} °C held out: measured (points), predicted (lines)",
            cfg.name, h.temperature_c
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
        .filter(|v| v.is_finite() && **v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let diag = |f: f64| vec![(lo / 1.2, f * lo / 1.2), (hi * 1.2, f * hi * 1.2)];
    let groups = vec![
        XyGroup {
            label: format!("creepfit: mean |log10 err| {:.3}", h.model_mean_abs_log10()),
            line: vec![],
            points: h
                .tests
                .iter()
                .map(|t| (t.rupture_time_h, t.model_rupture_time_h))
                .collect(),
            dashed: false,
            color: Some(0),
            triangles: false,
        },
        XyGroup {
            label: format!(
                "Larson–Miller: mean |log10 err| {:.3}",
                h.lmp_mean_abs_log10()
            ),
            line: vec![],
            points: h
                .tests
                .iter()
                .map(|t| (t.rupture_time_h, t.lmp_rupture_time_h))
                .collect(),
            dashed: false,
            color: Some(1),
            triangles: false,
        },
        XyGroup {
            label: "predicted = measured".into(),
            line: diag(1.0),
            points: vec![],
            dashed: false,
            color: None,
            triangles: false,
        },
        XyGroup {
            label: "factor 2".into(),
            line: diag(2.0),
            points: vec![],
            dashed: true,
            color: None,
            triangles: false,
        },
        XyGroup {
            label: String::new(),
            line: diag(0.5),
            points: vec![],
            dashed: true,
            color: None,
            triangles: false,
        },
    ];
    if let Err(e) = plot_xy(
        &out.join("parity.png"),
        &format!(
            "{} — rupture times at {} °C, held out",
            cfg.name, h.temperature_c
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
    println!("wrote {}", out.display());
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::PlotsNotWritten {
            out: out.to_path_buf(),
            failures,
        })
    }
}
