//! Predictions at untested conditions: what `creepfit predict` computes and writes.
//!
//! At each asked (temperature, stress) the calibrated model (with its temperature laws) is
//! integrated to rupture: the predicted curve, rupture time, rupture strain and minimum creep
//! rate. Beside each, the Larson–Miller baseline ([`crate::lmp`]) and the other classical
//! baselines ([`crate::baseline`]) fitted to the rupture times of the configuration's data,
//! each marked where the condition lies outside the temperatures or stresses it was fitted
//! on, so that the model's life is always shown next to the standard ones. The plots a creep
//! engineer reads: the predicted curves and the diagrams of [`crate::report::diagrams`]
//! (stress–rupture, Norton, Larson–Miller) with the asked conditions on them.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::baseline::{self, Baseline, BaselineKind, BaselineSettings, Extrapolation};
use crate::config::RunConfig;
use crate::data::{Curve, Dataset};
use crate::error::{Error, Result};
use crate::lmp::LarsonMiller;
use crate::model::{Load, Model};
use crate::objective::HORIZON_FACTOR;
use crate::ode::{OdeOptions, Outcome};
use crate::report::diagrams::{Asked, Diagrams};
use crate::report::plot::{
    plot_creep_curves, plot_xy, AxisScale, CurveId, CurvePlot, Dash, Rgb, XyAxes, XyGroup,
};
use crate::report::tables::{self, jnum, num, write_csv, write_csv_rows, write_text};

/// One condition to predict: temperature (°C) and stress (MPa).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    /// Test temperature, °C.
    #[serde(rename = "temperature_C")]
    pub temperature_c: f64,
    /// Nominal stress, MPa.
    #[serde(rename = "stress_MPa")]
    pub stress_mpa: f64,
}

impl Condition {
    /// Parse `T:σ` (°C and MPa), e.g. `575:100`.
    pub fn parse(s: &str) -> std::result::Result<Condition, String> {
        let (t, sig) = s
            .trim()
            .split_once(':')
            .ok_or_else(|| format!("'{s}': expected T:stress (°C:MPa), e.g. 575:100"))?;
        let t: f64 = t
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the temperature '{}'", t.trim()))?;
        let sig: f64 = sig
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the stress '{}'", sig.trim()))?;
        if !(t.is_finite() && t > -crate::model::ZERO_CELSIUS_K) {
            return Err(format!(
                "'{s}': the temperature must be above absolute zero (°C)"
            ));
        }
        if !(sig.is_finite() && sig > 0.0) {
            return Err(format!("'{s}': the stress must be positive (MPa)"));
        }
        Ok(Condition {
            temperature_c: t,
            stress_mpa: sig,
        })
    }

    /// Parse a comma-separated list `T:σ[,T:σ…]`.
    pub fn parse_list(s: &str) -> std::result::Result<Vec<Condition>, String> {
        s.split(',')
            .filter(|p| !p.trim().is_empty())
            .map(Condition::parse)
            .collect()
    }

    /// `575 °C, 100 MPa`.
    pub fn label(&self) -> String {
        format!("{} °C, {} MPa", self.temperature_c, self.stress_mpa)
    }
}

/// The model's prediction at one condition.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// Where.
    pub condition: Condition,
    /// How the simulation ended.
    pub outcome: Outcome,
    /// Rupture time, h (NaN without rupture).
    pub rupture_time_h: f64,
    /// Rupture strain, fraction (NaN without rupture).
    pub rupture_strain: f64,
    /// Minimum creep rate, 1/h.
    pub min_rate: f64,
    /// Dense predicted curve: (time h, strain fraction, the model's outputs).
    pub curve: Vec<(f64, f64, Vec<f64>)>,
    /// The Larson–Miller baseline's rupture time, h (NaN without a baseline).
    pub lmp_rupture_time_h: f64,
    /// Every baseline's rupture time, h, in [`BaselineKind::ALL`]'s order (NaN where absent
    /// or where it cannot predict).
    pub baseline_rupture_time_h: Vec<f64>,
    /// Where the condition lies against each baseline's fitted ranges (`None`: absent).
    pub baseline_extrapolation: Vec<Option<Extrapolation>>,
}

/// Everything `predict` computed.
pub struct PredictRun {
    /// One prediction per condition, in the order asked.
    pub predictions: Vec<Prediction>,
    /// The Larson–Miller baseline, or why there is none.
    pub lmp: std::result::Result<LarsonMiller, String>,
    /// Every baseline ([`BaselineKind::ALL`]'s order), each fitted or why it is absent.
    pub baselines: Vec<Baseline>,
    /// Names of the model's output columns (H, Phi, omega for KHD).
    pub output_names: Vec<&'static str>,
    /// Intervals per condition under `--intervals` ([`crate::uncertainty::predict::intervals_at`]).
    pub intervals: Option<Vec<crate::uncertainty::predict::ConditionIntervals>>,
}

/// `predictions.csv`'s interval columns under `--intervals`, with the quantity and interval
/// each reads: the 95 % prediction interval of a new test (`_lo95`/`_hi95`), then the 95 %
/// confidence interval of the model's prediction (`_conf_lo95`/`_conf_hi95`).
pub const INTERVAL_COLUMNS: [(&str, &str, bool, bool); 12] = [
    ("rupture_time_lo95_h", "rupture_time_h", false, false),
    ("rupture_time_hi95_h", "rupture_time_h", false, true),
    (
        "rupture_strain_lo95_pct",
        "rupture_strain_pct",
        false,
        false,
    ),
    ("rupture_strain_hi95_pct", "rupture_strain_pct", false, true),
    (
        "min_rate_lo95_pct_per_h",
        "min_rate_pct_per_h",
        false,
        false,
    ),
    ("min_rate_hi95_pct_per_h", "min_rate_pct_per_h", false, true),
    ("rupture_time_conf_lo95_h", "rupture_time_h", true, false),
    ("rupture_time_conf_hi95_h", "rupture_time_h", true, true),
    (
        "rupture_strain_conf_lo95_pct",
        "rupture_strain_pct",
        true,
        false,
    ),
    (
        "rupture_strain_conf_hi95_pct",
        "rupture_strain_pct",
        true,
        true,
    ),
    (
        "min_rate_conf_lo95_pct_per_h",
        "min_rate_pct_per_h",
        true,
        false,
    ),
    (
        "min_rate_conf_hi95_pct_per_h",
        "min_rate_pct_per_h",
        true,
        true,
    ),
];

/// Dense time grid from 0 to `t_end` (h), refined towards the end of life.
pub fn dense_grid(t_end: f64, n: usize) -> Vec<f64> {
    let mut g: Vec<f64> = (0..=n)
        .map(|i| {
            let s = i as f64 / n as f64;
            t_end * (1.0 - (1.0 - s).powi(2))
        })
        .collect();
    g.dedup();
    g
}

/// Integration horizon of a prediction: [`HORIZON_FACTOR`] × the longer of the longest
/// measured life of the data and the baseline's life at the condition.
pub(crate) fn horizon(data: &Dataset, lmp_life: f64) -> f64 {
    let longest = data
        .curves
        .iter()
        .map(|c| c.life_h())
        .fold(0.0f64, f64::max);
    let base = if lmp_life.is_finite() && lmp_life < 1e12 {
        longest.max(lmp_life)
    } else {
        longest
    };
    HORIZON_FACTOR * base.max(1.0)
}

/// One simulation at `c` with the run's integrator: rupture time, strain, minimum rate.
pub fn simulate_at(
    model: &dyn Model,
    params: &[f64],
    c: Condition,
    omega_f: f64,
    ode: &OdeOptions,
    t_end: f64,
) -> crate::ode::SimResult {
    let load = Load::new(c.stress_mpa, c.temperature_c, omega_f);
    let o = OdeOptions { t_end, ..*ode };
    model.simulate(params, &load, &[], &mut [], &o)
}

/// Predict at `conditions` with `model` at `params`; the baseline is fitted to the rupture
/// times of `data`.
pub fn predict(
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    conditions: &[Condition],
) -> PredictRun {
    let ode = cfg.solver.ode_options();
    let omega_f = cfg.objective.omega_f;
    let lmp =
        LarsonMiller::fit_curves(&data.curves, cfg.predict.lmp_degree).map_err(|e| e.to_string());
    let baselines = baseline::fit_all(
        &baseline::rupture_tests(&data.curves),
        &BaselineSettings {
            degree: cfg.predict.lmp_degree,
            tensile: &cfg.predict.tensile_strength,
        },
    );
    let predictions = conditions
        .iter()
        .map(|&c| {
            let lmp_life = lmp
                .as_ref()
                .map_or(f64::NAN, |l| l.rupture_time(c.temperature_c, c.stress_mpa));
            let t_end = horizon(data, lmp_life);
            let res = simulate_at(model, params, c, omega_f, &ode, t_end);
            let load = Load::new(c.stress_mpa, c.temperature_c, omega_f);
            let grid = dense_grid(res.t_end, 200);
            let (_, curve) = model.trajectory(params, &load, &grid, &OdeOptions { t_end, ..ode });
            let ruptured = res.ruptured();
            Prediction {
                condition: c,
                outcome: res.outcome,
                rupture_time_h: if ruptured { res.t_end } else { f64::NAN },
                rupture_strain: if ruptured { res.strain_end } else { f64::NAN },
                min_rate: res.min_rate,
                curve,
                lmp_rupture_time_h: lmp_life,
                baseline_rupture_time_h: baselines
                    .iter()
                    .map(|b| b.predict(c.temperature_c, c.stress_mpa))
                    .collect(),
                baseline_extrapolation: baselines
                    .iter()
                    .map(|b| {
                        b.fit
                            .as_ref()
                            .ok()
                            .map(|f| f.extrapolation(c.temperature_c, c.stress_mpa))
                    })
                    .collect(),
            }
        })
        .collect();
    PredictRun {
        predictions,
        lmp,
        baselines,
        output_names: model.output_names(),
        intervals: None,
    }
}

/// The printed table: model and baseline side by side.
pub fn table(run: &PredictRun) -> String {
    let mut s = String::new();
    s.push_str(
        "  T(C)      MPa |  t_r model h    t_r LMP h  model/LMP | e_r model % | min rate %/h\n",
    );
    for p in &run.predictions {
        let f = |v: f64, w: usize, d: usize| {
            if v.is_finite() {
                format!("{v:>w$.d$}")
            } else {
                format!("{:>w$}", "-")
            }
        };
        s.push_str(&format!(
            "{:>6} {:>8} | {} {} {} | {} | {:>12.4e}{}\n",
            p.condition.temperature_c,
            p.condition.stress_mpa,
            f(p.rupture_time_h, 12, 0),
            f(p.lmp_rupture_time_h, 12, 0),
            f(p.rupture_time_h / p.lmp_rupture_time_h, 10, 3),
            f(100.0 * p.rupture_strain, 11, 3),
            100.0 * p.min_rate,
            if p.outcome == Outcome::Ruptured {
                String::new()
            } else {
                format!("  ({})", p.outcome.as_str())
            }
        ));
    }
    if let Some(iv) = &run.intervals {
        s.push_str(
            "95 % intervals (maximum-likelihood fit from these constants, error model of README \"How sure\"): \
             prediction interval of a NEW TEST (adds the scatter between specimens) | confidence interval of the model's prediction\n",
        );
        for (p, c) in run.predictions.iter().zip(iv) {
            for q in &c.quantities {
                s.push_str(&format!(
                    "{:>6} {:>8} | {:<19} {:.5e} | new test [{:.5e}, {:.5e}] | model [{:.5e}, {:.5e}]\n",
                    p.condition.temperature_c,
                    p.condition.stress_mpa,
                    q.quantity,
                    q.value,
                    q.pred_lo95,
                    q.pred_hi95,
                    q.conf_lo95,
                    q.conf_hi95
                ));
            }
        }
    }
    match &run.lmp {
        Ok(l) => s.push_str(&format!(
            "Larson–Miller baseline: C = {:.3}, master curve of degree {} in log10 stress, fitted to {} rupture times at {} °C (rms log10 error {:.3})\n",
            l.c,
            l.coefficients.len() - 1,
            l.n_tests,
            l.temperatures_c.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(", "),
            l.rms_log10
        )),
        Err(e) => s.push_str(&format!("no Larson–Miller baseline: {e}\n")),
    }
    s.push_str(&baselines_table(run));
    s
}

/// The printed baselines: each one's rupture time at every condition (marked `*` outside its
/// fitted ranges), then its constants or why it is absent.
pub fn baselines_table(run: &PredictRun) -> String {
    let mut s = String::from(
        "classical baselines fitted to the same rupture times (h; * = outside the temperatures or stresses fitted on):\n  T(C)      MPa |",
    );
    for b in &run.baselines {
        s.push_str(&format!(" {:>16}", b.kind.name()));
    }
    s.push('\n');
    for p in &run.predictions {
        s.push_str(&format!(
            "{:>6} {:>8} |",
            p.condition.temperature_c, p.condition.stress_mpa
        ));
        for (v, x) in p
            .baseline_rupture_time_h
            .iter()
            .zip(&p.baseline_extrapolation)
        {
            let mark = match x {
                Some(Extrapolation::No) | None => " ",
                Some(_) => "*",
            };
            if v.is_finite() {
                s.push_str(&format!(" {v:>15.0}{mark}"));
            } else {
                s.push_str(&format!(" {:>15}{mark}", "-"));
            }
        }
        s.push('\n');
    }
    for b in &run.baselines {
        s.push_str(&format!("  {}\n", b.describe()));
    }
    s
}

/// `larson_miller.csv`'s columns after the contract four: the Larson–Miller extrapolation
/// mark, then the rupture time and extrapolation mark of each other baseline in
/// [`BaselineKind::ALL`]'s order (`lmp_extrapolation,osd_rupture_time_h,osd_extrapolation,…`).
pub fn baseline_columns() -> Vec<String> {
    let mut v = vec!["lmp_extrapolation".to_string()];
    for k in &BaselineKind::ALL[1..] {
        v.push(format!("{}_rupture_time_h", k.key()));
        v.push(format!("{}_extrapolation", k.key()));
    }
    v
}

/// Warnings about conditions outside the tested ranges (extrapolation).
pub fn extrapolation_notes(data: &Dataset, conditions: &[Condition]) -> Vec<String> {
    let range = |f: fn(&Curve) -> f64| {
        data.curves
            .iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (t0, t1) = range(|c| c.temperature_c);
    let (s0, s1) = range(|c| c.stress_mpa);
    let mut out = Vec::new();
    for c in conditions {
        let mut what = Vec::new();
        if c.temperature_c < t0 || c.temperature_c > t1 {
            what.push(format!("temperature outside the tested {t0}–{t1} °C"));
        }
        if c.stress_mpa < s0 || c.stress_mpa > s1 {
            what.push(format!("stress outside the tested {s0}–{s1} MPa"));
        }
        if !what.is_empty() {
            out.push(format!("{}: extrapolation: {}", c.label(), what.join(", ")));
        }
    }
    out
}

/// Write `predictions.csv`, `larson_miller.csv`, `curves.csv` and `summary.json` into `out`,
/// then the plots; returns the plots that could not be drawn.
pub fn write_outputs(
    out: &Path,
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    run: &PredictRun,
) -> Result<Vec<String>> {
    let rows: Vec<Vec<String>> = run
        .predictions
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![
                num(p.condition.temperature_c),
                num(p.condition.stress_mpa),
                num(p.rupture_time_h),
                num(100.0 * p.rupture_strain),
                num(100.0 * p.min_rate),
            ];
            if let Some(iv) = &run.intervals {
                for (_, q, conf, hi) in INTERVAL_COLUMNS {
                    let v = iv[k].get(q).map_or(f64::NAN, |i| match (conf, hi) {
                        (false, false) => i.pred_lo95,
                        (false, true) => i.pred_hi95,
                        (true, false) => i.conf_lo95,
                        (true, true) => i.conf_hi95,
                    });
                    row.push(num(v));
                }
            }
            row
        })
        .collect();
    let mut header = vec![
        "temperature_C",
        "stress_MPa",
        "rupture_time_h",
        "rupture_strain_pct",
        "min_rate_pct_per_h",
    ];
    if run.intervals.is_some() {
        header.extend(INTERVAL_COLUMNS.iter().map(|c| c.0));
    }
    write_csv(&out.join("predictions.csv"), &header, &rows)?;
    let lmp_rows: Vec<Vec<String>> = run
        .predictions
        .iter()
        .map(|p| {
            let c = p.condition;
            vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(p.lmp_rupture_time_h),
                match &run.lmp {
                    Ok(l) => num(l.lmp(c.stress_mpa)),
                    Err(_) => String::new(),
                },
            ]
            .into_iter()
            .chain((0..BaselineKind::ALL.len()).flat_map(|k| {
                let mark =
                    p.baseline_extrapolation[k].map_or(String::new(), |x| x.as_str().to_string());
                if k == 0 {
                    vec![mark]
                } else {
                    vec![num(p.baseline_rupture_time_h[k]), mark]
                }
            }))
            .collect()
        })
        .collect();
    let mut header = vec![
        "temperature_C",
        "stress_MPa",
        "rupture_time_h",
        "larson_miller_parameter_K",
    ];
    let extra = baseline_columns();
    header.extend(extra.iter().map(String::as_str));
    write_csv(&out.join("larson_miller.csv"), &header, &lmp_rows)?;
    let mut header = vec!["temperature_C", "stress_MPa", "time_h", "strain_pct"];
    header.extend(run.output_names.iter().copied());
    let curve_rows = run.predictions.iter().flat_map(|p| {
        p.curve.iter().map(move |(t, e, y)| {
            let mut row = vec![
                num(p.condition.temperature_c),
                num(p.condition.stress_mpa),
                num(*t),
                num(100.0 * e),
            ];
            row.extend(y.iter().map(|v| num(*v)));
            row
        })
    });
    write_csv_rows(&out.join("curves.csv"), &header, curve_rows)?;
    if let Some(iv) = &run.intervals {
        let rows: Vec<Vec<String>> = run
            .predictions
            .iter()
            .zip(iv)
            .flat_map(|(p, ci)| {
                ci.band.iter().map(move |b| {
                    vec![
                        num(p.condition.temperature_c),
                        num(p.condition.stress_mpa),
                        num(b.time_h),
                        num(b.strain_pct),
                        num(b.lo95_pct),
                        num(b.hi95_pct),
                    ]
                })
            })
            .collect();
        write_csv(&out.join("band.csv"), &BAND_COLUMNS, &rows)?;
    }
    let names: Vec<&str> = model.inner_constants().iter().map(|c| c.name).collect();
    let summary = json!({
        "model": model.name(),
        "T_ref_C": cfg.t_ref,
        "constants": model.constants().iter().zip(params).map(|(c, v)| json!({"name": c.name, "value": v, "unit": c.unit})).collect::<Vec<_>>(),
        "predictions": run.predictions.iter().map(|p| {
            let at = model.constants_at(params, p.condition.temperature_c);
            json!({
                "temperature_C": p.condition.temperature_c,
                "stress_MPa": p.condition.stress_mpa,
                "outcome": p.outcome,
                "rupture_time_h": jnum(p.rupture_time_h),
                "rupture_strain_pct": jnum(100.0 * p.rupture_strain),
                "min_rate_pct_per_h": jnum(100.0 * p.min_rate),
                "larson_miller_rupture_time_h": jnum(p.lmp_rupture_time_h),
                "baselines": BaselineKind::ALL.iter().enumerate().map(|(k, b)| {
                    (b.key().to_string(), json!({
                        "rupture_time_h": jnum(p.baseline_rupture_time_h[k]),
                        "extrapolation": p.baseline_extrapolation[k],
                    }))
                }).collect::<serde_json::Map<_, _>>(),
                "constants_at_temperature": names.iter().zip(&at).map(|(n, v)| (n.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
            })
        }).collect::<Vec<_>>(),
        "larson_miller": match &run.lmp {
            Ok(l) => json!(l),
            Err(e) => json!({"error": e}),
        },
        "baselines": run.baselines.iter().map(Baseline::to_json).collect::<Vec<_>>(),
        "extrapolation": extrapolation_notes(data, &run.predictions.iter().map(|p| p.condition).collect::<Vec<_>>()),
    });
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;
    Ok(plots(out, cfg, data, model, params, run))
}

/// `band.csv`'s columns under `--intervals`: the 95 % confidence band of each predicted curve
/// (the model's prediction, from the constants' uncertainty; pointwise prediction profile
/// likelihood) at `[profile] band_points` fractions of its rupture time.
pub const BAND_COLUMNS: [&str; 6] = [
    "temperature_C",
    "stress_MPa",
    "time_h",
    "strain_pct",
    "strain_conf_lo95_pct",
    "strain_conf_hi95_pct",
];

/// Most measured points a plot draws per curve.
const PLOT_POINTS: usize = 2000;

fn plots(
    out: &Path,
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    run: &PredictRun,
) -> Vec<String> {
    let mut failures = Vec::new();
    // 1. Predicted curves, with the measured curve of the same test where there is one.
    let curves: Vec<CurvePlot> = run
        .predictions
        .iter()
        .map(|p| {
            let c = p.condition;
            let measured: Vec<(f64, f64)> = data
                .curves
                .iter()
                .filter(|d| d.temperature_c == c.temperature_c && d.stress_mpa == c.stress_mpa)
                .flat_map(|d| {
                    tables::thin(
                        d.times_h
                            .iter()
                            .zip(&d.strains)
                            .map(|(t, e)| (*t, 100.0 * e))
                            .collect(),
                        PLOT_POINTS,
                    )
                })
                .collect();
            CurvePlot {
                id: CurveId {
                    temperature_c: c.temperature_c,
                    stress_mpa: c.stress_mpa,
                    specimen: None,
                },
                measured,
                predicted: p.curve.iter().map(|(t, e, _)| (*t, 100.0 * e)).collect(),
            }
        })
        .collect();
    if let Err(e) = plot_creep_curves(
        &out.join("curves.png"),
        &format!(
            "{} — predicted curves (measured points where tested)",
            cfg.name
        ),
        &curves,
    ) {
        failures.push(e.to_string());
    }
    // 1b. Under --intervals: each predicted curve with its 95 % confidence band.
    if let Some(iv) = &run.intervals {
        let mut groups = Vec::new();
        for (k, (p, ci)) in run.predictions.iter().zip(iv).enumerate() {
            if ci.band.is_empty() {
                continue;
            }
            groups.push(XyGroup::line(
                p.condition.label(),
                p.curve.iter().map(|(t, e, _)| (*t, 100.0 * e)).collect(),
                Rgb::palette(k),
                Dash::Solid,
            ));
            for (label, side) in [
                (format!("{}: 95 % band", p.condition.label()), true),
                (String::new(), false),
            ] {
                groups.push(XyGroup::line(
                    label,
                    ci.band
                        .iter()
                        .map(|b| (b.time_h, if side { b.hi95_pct } else { b.lo95_pct }))
                        .collect(),
                    Rgb::palette(k),
                    Dash::Dashed,
                ));
            }
        }
        if !groups.is_empty() {
            if let Err(e) = plot_xy(
                &out.join("band.png"),
                &format!(
                    "{} — predicted curves with the 95 % confidence band of the model's prediction",
                    cfg.name
                ),
                XyAxes {
                    x_label: "time (h)",
                    y_label: "creep strain (%)",
                    x_scale: AxisScale::Linear,
                    y_scale: AxisScale::Linear,
                },
                &groups,
            ) {
                failures.push(e.to_string());
            }
        }
    }

    // The engineering diagrams: stress–rupture, Norton, Larson–Miller.
    let asked: Vec<Asked> = run
        .predictions
        .iter()
        .map(|p| Asked {
            temperature_c: p.condition.temperature_c,
            stress_mpa: p.condition.stress_mpa,
            rupture_time_h: p.rupture_time_h,
            min_rate: p.min_rate,
        })
        .collect();
    failures.extend(
        Diagrams {
            cfg,
            data,
            model,
            params,
            lmp: run.lmp.as_ref().ok(),
            asked: &asked,
            held_out_c: None,
        }
        .write(out),
    );
    failures
}

/// The constants' reference temperature written with them (`T_ref` row of constants.csv),
/// if the file has one.
pub fn constants_t_ref(path: &Path) -> Result<Option<(f64, usize)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    for (i, line) in text.lines().enumerate() {
        let mut f = line.split(',');
        if f.next().map(str::trim) == Some(tables::T_REF_ROW) {
            let v = f.next().unwrap_or("").trim();
            let t: f64 = v.parse().map_err(|_| {
                Error::data(
                    path,
                    i + 1,
                    format!("column 'value': cannot parse '{v}' as a number"),
                )
            })?;
            return Ok(Some((t, i + 1)));
        }
    }
    Ok(None)
}

/// Constants fitted about another reference temperature than the configuration's mean
/// different constants: an error naming both.
pub fn check_t_ref(path: &Path, cfg: &RunConfig) -> Result<()> {
    if let Some((t, line)) = constants_t_ref(path)? {
        match cfg.t_ref {
            Some(c) if c == t => {}
            other => {
                return Err(Error::data(
                    path,
                    line,
                    format!(
                        "T_ref: these constants are about T_ref = {t} °C, the configuration resolves T_ref = {}; set T_ref = {t} in {}",
                        other.map_or("none (no temperature laws)".to_string(), |c| format!("{c} °C")),
                        cfg.path.display()
                    ),
                ))
            }
        }
    }
    Ok(())
}
