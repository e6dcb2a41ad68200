//! Predictions at untested conditions: what `creepfit predict` computes and writes.
//!
//! At each asked (temperature, stress) the calibrated model (with its temperature laws) is
//! integrated to rupture: the predicted curve, rupture time, rupture strain and minimum creep
//! rate. Beside each, the Larson–Miller baseline ([`crate::lmp`]) and the other classical
//! baselines ([`crate::baseline`]) fitted to the rupture times of the configuration's data,
//! each marked where the condition lies outside the temperatures or stresses it was fitted
//! on, so that the model's life is always shown next to the standard ones. The plots a creep
//! engineer reads: the predicted curves and the diagrams of [`crate::predict::diagrams`]
//! (stress–rupture, Norton, Larson–Miller) with the asked conditions on them.

pub mod diagrams;
pub mod measured;

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

pub use crate::baseline::Extrapolation;
use crate::baseline::{self, Baseline, BaselineKind, BaselineSettings};
use crate::baseline::{Tested, STRESS_MARGIN_FACTOR, TEMPERATURE_MARGIN_C};
use crate::config::{PredictSetup, RunConfig};
use crate::data::Condition;
use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::lmp::LarsonMiller;
use crate::model::objective::HORIZON_FACTOR;
use crate::model::{Load, Model};
use crate::ode::{OdeOptions, Outcome};
use crate::report::plot::{
    plot_creep_curves, plot_xy, AxisScale, CurveId, CurvePlot, Dash, Rgb, XyAxes, XyGroup,
};
use crate::report::tables::{self, jnum, num, write_csv, write_csv_rows, write_text};
use diagrams::{Asked, Diagrams};

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
    /// Minimum creep rate, 1/h (NaN when the simulation failed: only a rupture or the
    /// horizon reached give one).
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

/// Which constants a prediction comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstantsSource {
    /// The constants of `--constants FILE`, as given.
    Given,
    /// The maximum-likelihood refit from them that `--intervals` centres its intervals on.
    MlRefit,
}

impl ConstantsSource {
    /// The name written in files.
    pub fn as_str(&self) -> &'static str {
        match self {
            ConstantsSource::Given => "given",
            ConstantsSource::MlRefit => "ml_refit",
        }
    }
}

/// Everything `predict` computed.
pub struct PredictRun {
    /// The constants of the predictions (model order): the given ones, or the
    /// maximum-likelihood refit from them under `--intervals` (`source` says which).
    pub params: Vec<f64>,
    /// Which constants `params` are.
    pub source: ConstantsSource,
    /// One prediction per condition, in the order asked.
    pub predictions: Vec<Prediction>,
    /// Per condition, where it lies against the tested conditions ([`Tested::classify`]; a
    /// condition beyond the limits is marked `both` here — `creepfit predict` refuses it
    /// before predicting).
    pub extrapolation: Vec<Extrapolation>,
    /// Under `--intervals`: the predictions at the given constants (beside the refit's) and
    /// the refit itself.
    pub given: Option<Vec<Prediction>>,
    pub refit: Option<crate::uncertainty::predict::Refit>,
    /// Under `--intervals`: the bootstrap calibration of the intervals' thresholds (`None`
    /// without it).
    pub calibration: Option<crate::uncertainty::calibrate::Calibration>,
    /// The Larson–Miller baseline, or why there is none.
    pub lmp: std::result::Result<LarsonMiller, String>,
    /// Every baseline ([`BaselineKind::ALL`]'s order), each fitted or why it is absent.
    pub baselines: Vec<Baseline>,
    /// Names of the model's output columns (H, Phi, omega for KHD).
    pub output_names: Vec<&'static str>,
    /// Intervals per condition under `--intervals` ([`crate::uncertainty::predict::intervals_at`]).
    pub intervals: Option<Vec<crate::uncertainty::predict::ConditionIntervals>>,
    /// Under `--tests FILE`: its measured lives against the predictions ([`measured`]).
    pub measured: Option<measured::MeasuredTests>,
    /// Under `--intervals`: where the intervals' wall time went (`timings.json`, not a
    /// result).
    pub interval_timings: Option<crate::uncertainty::predict::IntervalsTimings>,
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
    setup: &PredictSetup,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    conditions: &[Condition],
) -> PredictRun {
    let ode = setup.ode;
    let omega_f = setup.omega_f;
    let lmp =
        LarsonMiller::fit_curves(&data.curves, setup.predict.lmp_degree).map_err(|e| e.to_string());
    let baselines = baseline::fit_all(
        &baseline::rupture_tests(&data.curves),
        &BaselineSettings {
            degree: setup.predict.lmp_degree,
            tensile: &setup.predict.tensile_strength,
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
            let ran = ruptured || res.outcome == Outcome::Horizon;
            Prediction {
                condition: c,
                outcome: res.outcome,
                rupture_time_h: if ruptured { res.t_end } else { f64::NAN },
                rupture_strain: if ruptured { res.strain_end } else { f64::NAN },
                min_rate: if ran && res.min_rate.is_finite() {
                    res.min_rate
                } else {
                    f64::NAN
                },
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
    let tested = Tested::of(data, setup.has_laws);
    PredictRun {
        params: params.to_vec(),
        source: ConstantsSource::Given,
        extrapolation: conditions
            .iter()
            .map(|c| {
                tested
                    .classify_measured(*c)
                    .unwrap_or(Extrapolation::BeyondLimits)
            })
            .collect(),
        predictions,
        given: None,
        refit: None,
        calibration: None,
        lmp,
        baselines,
        output_names: model.output_names(),
        intervals: None,
        measured: None,
        interval_timings: None,
    }
}

/// `predict`'s computation at the configuration's conditions (`[predict] at`): at the given
/// constants `params`, or under `[predict] intervals` at the maximum-likelihood refit the
/// intervals are centred on ([`centre_on_intervals`]; the given constants' predictions
/// beside). `setup` is [`crate::config::RunConfig::predict_setup`] on `data`.
pub fn run(
    setup: &PredictSetup,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
) -> Result<PredictRun> {
    run_observed(
        setup,
        data,
        model,
        params,
        &crate::progress::Hooks::default(),
    )
}

/// [`run`] reporting the phases of the intervals to `hooks.observer`.
pub fn run_observed(
    setup: &PredictSetup,
    data: &Dataset,
    model: &dyn Model,
    params: &[f64],
    hooks: &crate::progress::Hooks,
) -> Result<PredictRun> {
    let at = &setup.predict.at;
    let given = predict(setup, data, model, params, at);
    if !setup.predict.intervals {
        return Ok(given);
    }
    let loads: Vec<Load> = at
        .iter()
        .map(|c| Load::new(c.stress_mpa, c.temperature_c, setup.omega_f))
        .collect();
    let iv = crate::uncertainty::predict::intervals_at_observed(
        &setup.likelihood,
        model,
        data,
        params,
        &loads,
        hooks,
    )?;
    let centre = predict(setup, data, model, &iv.refit.params, at);
    Ok(centre_on_intervals(centre, iv, given.predictions))
}

/// At least one condition to predict: else the error says where to give them (`--at` or
/// `[predict] at`).
pub fn check_asked(cfg: &RunConfig) -> Result<()> {
    if cfg.predict.at.is_empty() {
        return Err(Error::config(
            &cfg.path,
            "predict.at: no conditions to predict: give --at T:stress[,T:stress…], --tests FILE, [predict] at or [predict] tests",
        ));
    }
    Ok(())
}

/// Every condition of `[predict] at` within what the data can predict ([`Tested::classify`]):
/// else an error naming the first one (as `--at` when `from_cli`, else as the configuration's
/// field).
pub fn check_conditions(cfg: &RunConfig, data: &Dataset, from_cli: bool) -> Result<()> {
    let tested = Tested::of(data, cfg.has_laws());
    for (k, c) in cfg.predict.at.iter().enumerate() {
        if let Err(why) = tested.classify(*c) {
            let at = format!("{}:{}", c.temperature_c, c.stress_mpa);
            return Err(if from_cli {
                Error::Invalid(format!("--at {at}: {why}"))
            } else {
                cfg.error_at(&format!("predict.at[{k}]"), format!("\"{at}\": {why}"))
            });
        }
    }
    Ok(())
}

/// `run` (the predictions at the refit of `iv`) centred on its intervals: each predicted
/// quantity that has an interval takes the interval's own centre (the same constants; the
/// minimum rate integrated more finely there), so that every row's numbers and intervals
/// have one centre; `given` holds the predictions at the given constants.
pub fn centre_on_intervals(
    mut run: PredictRun,
    iv: crate::uncertainty::predict::IntervalsRun,
    given: Vec<Prediction>,
) -> PredictRun {
    for (p, c) in run.predictions.iter_mut().zip(&iv.conditions) {
        if let Some(q) = c.get("rupture_time_h") {
            p.rupture_time_h = q.value;
        }
        if let Some(q) = c.get("rupture_strain_pct") {
            p.rupture_strain = q.value / 100.0;
        }
        if let Some(q) = c.get("min_rate_pct_per_h") {
            p.min_rate = q.value / 100.0;
        }
    }
    run.source = ConstantsSource::MlRefit;
    run.given = Some(given);
    run.refit = Some(iv.refit);
    run.calibration = iv.calibration;
    run.intervals = Some(iv.conditions);
    run.interval_timings = Some(iv.timings);
    run
}

/// The run identity of `creepfit predict --intervals` on `cfg` (bound to its data) kept in its
/// journal: the configuration's ([`crate::config::identity`]), the command, the `[predict]`
/// and `[profile]` settings (the conditions, the calibration and the bands) and the given
/// constants, exact.
pub fn identity(cfg: &RunConfig, params: &[f64]) -> Value {
    let mut id = crate::config::identity(cfg);
    id["command"] = "predict".into();
    id["predict"] = serde_json::to_value(&cfg.predict).expect("settings serialise");
    id["profile"] = serde_json::to_value(&cfg.profile).expect("settings serialise");
    id["given_constants"] = params
        .iter()
        .map(|v| crate::journal::exact::to_json(*v))
        .collect();
    id
}

/// The printed table: model and baseline side by side, which constants the numbers come
/// from, and under `--intervals` the refit's distance from the given constants.
pub fn table(run: &PredictRun, names: &[&str]) -> String {
    let mut s = String::new();
    let f = |v: f64, w: usize, d: usize| {
        if v.is_finite() {
            format!("{v:>w$.d$}")
        } else {
            format!("{:>w$}", "-")
        }
    };
    let e = |v: f64| {
        if v.is_finite() {
            format!("{v:>12.4e}")
        } else {
            format!("{:>12}", "-")
        }
    };
    if let Some(r) = &run.refit {
        s.push_str(&format!(
            "constants: the maximum-likelihood refit from the given constants (every number and interval below is centred on it; predictions.csv: constants = ml_refit, the given constants' predictions in given_* columns). −2 ln L {:.3} at the refit, {:.3} at the given constants (difference {:.3}):\n",
            r.neg2ll,
            r.given_neg2ll,
            r.delta_neg2ll()
        ));
        if !r.specimen_effects.is_empty() {
            let kinds: Vec<&str> = r.specimen_effects.iter().map(|k| k.name()).collect();
            s.push_str(&format!(
                "  note: every fit here integrates the specimens' {} factors out (the hierarchical likelihood); the constants are the population's\n",
                kinds.join(" and ")
            ));
        }
        s.push_str(&campaign_notes(&r.campaign_levels));
        for (n, (g, v)) in names.iter().zip(r.given.iter().zip(&r.params)) {
            s.push_str(&format!(
                "  {n:>8}: given {g:.6e}, refit {v:.6e} ({:+.2} %)\n",
                100.0 * (v - g) / g.abs().max(f64::MIN_POSITIVE)
            ));
        }
    } else {
        s.push_str("constants: as given\n");
    }
    s.push_str(
        "  T(C)      MPa |  t_r model h    t_r LMP h  model/LMP | e_r model % | min rate %/h | extrapolation\n",
    );
    for (k, p) in run.predictions.iter().enumerate() {
        s.push_str(&format!(
            "{:>6} {:>8} | {} {} {} | {} | {} | {}{}\n",
            p.condition.temperature_c,
            p.condition.stress_mpa,
            f(p.rupture_time_h, 12, 0),
            f(p.lmp_rupture_time_h, 12, 0),
            f(p.rupture_time_h / p.lmp_rupture_time_h, 10, 3),
            f(100.0 * p.rupture_strain, 11, 3),
            e(100.0 * p.min_rate),
            run.extrapolation.get(k).map_or("-", |x| x.as_str()),
            if p.outcome == Outcome::Ruptured {
                String::new()
            } else {
                format!("  ({})", p.outcome.as_str())
            }
        ));
    }
    if let Some(given) = &run.given {
        s.push_str("at the given constants (predictions.csv: given_*):\n");
        for p in given {
            s.push_str(&format!(
                "{:>6} {:>8} | {} {:>12} {:>10} | {} | {}{}\n",
                p.condition.temperature_c,
                p.condition.stress_mpa,
                f(p.rupture_time_h, 12, 0),
                "",
                "",
                f(100.0 * p.rupture_strain, 11, 3),
                e(100.0 * p.min_rate),
                if p.outcome == Outcome::Ruptured {
                    String::new()
                } else {
                    format!("  ({})", p.outcome.as_str())
                }
            ));
        }
    }
    if let Some(iv) = &run.intervals {
        s.push_str(
            "95 % intervals (centred on the maximum-likelihood refit, error model of README \"How sure\"): \
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
                Some(Extrapolation::None) | None => " ",
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

/// A stress (MPa) to 0.1 MPa, as printed in a note.
fn round_mpa(x: f64) -> f64 {
    (x * 10.0).round() / 10.0
}

/// Warnings about conditions outside the tested ranges (extrapolations within the margins).
pub fn extrapolation_notes(tested: &Tested, conditions: &[Condition]) -> Vec<String> {
    let (t0, t1) = tested.temperature_range();
    conditions
        .iter()
        .filter_map(|c| {
            let x = tested.classify_measured(*c).ok()?;
            if x == Extrapolation::BeyondLimits {
                let why = tested.classify(*c).err().unwrap_or_default();
                return Some(format!(
                    "{}: beyond the limits of a prediction ({why}); predicted because it is a measured test of --tests, marked extrapolation = beyond_limits",
                    c.label()
                ));
            }
            let (s0, s1) = tested.stress_range(c.temperature_c);
            let mut what = Vec::new();
            if matches!(x, Extrapolation::Temperature | Extrapolation::Both) {
                what.push(format!("temperature outside the tested {t0}–{t1} °C"));
            }
            if matches!(x, Extrapolation::Stress | Extrapolation::Both) {
                what.push(match tested.around(c.temperature_c) {
                    Some((lo, hi)) => format!(
                        "stress outside the {}–{} MPa tested around {} °C (the ranges of {} and {} °C, interpolated)",
                        round_mpa(s0),
                        round_mpa(s1),
                        c.temperature_c,
                        lo,
                        hi
                    ),
                    None => format!(
                        "stress outside the {s0}–{s1} MPa tested at {} °C",
                        c.temperature_c
                    ),
                });
            }
            (!what.is_empty()).then(|| format!("{}: extrapolation: {}", c.label(), what.join(", ")))
        })
        .collect()
}

/// Write `predictions.csv`, `larson_miller.csv`, `curves.csv` and `summary.json` into `out`,
/// then the plots; returns the plots that could not be drawn.
pub fn write_outputs(
    out: &Path,
    cfg: &RunConfig,
    data: &Dataset,
    model: &dyn Model,
    run: &PredictRun,
) -> Result<Vec<String>> {
    let params = &run.params[..];
    let (header, rows) = predictions_table(run);
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
                        b.hi95_ruptured.to_string(),
                        b.lo95_open.to_string(),
                    ]
                })
            })
            .collect();
        write_csv(&out.join("band.csv"), &BAND_COLUMNS, &rows)?;
    }
    if let Some(m) = &run.measured {
        let (header, rows) = m.csv();
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        write_csv(&out.join("tests.csv"), &header, &rows)?;
    }
    let summary = summary_json(cfg, data, model, run);
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary).expect("JSON of plain values"),
    )?;
    Ok(plots(out, cfg, data, model, params, run))
}

/// `predict`'s `summary.json` ([`write_outputs`]).
pub fn summary_json(cfg: &RunConfig, data: &Dataset, model: &dyn Model, run: &PredictRun) -> Value {
    let params = &run.params[..];
    let names: Vec<&str> = model.inner_constants().iter().map(|c| c.name).collect();
    let all_names: Vec<&str> = model.constants().iter().map(|c| c.name).collect();
    let given_row = |p: Option<&Prediction>| {
        p.map(|g| {
            json!({
                "outcome": g.outcome.as_str(),
                "rupture_time_h": jnum(g.rupture_time_h),
                "rupture_strain_pct": jnum(100.0 * g.rupture_strain),
                "min_rate_pct_per_h": jnum(100.0 * g.min_rate),
            })
        })
    };
    let tested = Tested::of(data, cfg.has_laws());
    let (t0, t1) = tested.temperature_range();
    json!({
        "model": model.name(),
        "T_ref_C": cfg.t_ref,
        "constants_source": run.source,
        "constants": model.constants().iter().zip(params).map(|(c, v)| json!({"name": c.name, "value": v, "unit": c.unit})).collect::<Vec<_>>(),
        "refit": run.refit.as_ref().map(|r| json!({
            "what": "the maximum-likelihood fit from the given constants under the error model (README, \"How sure\"); every number of predictions.csv but the given_* columns, band.csv and the plots come from it",
            "neg2ll": jnum(r.neg2ll),
            "given_neg2ll": jnum(r.given_neg2ll),
            "delta_neg2ll": jnum(r.delta_neg2ll()),
            "specimen_effects": r.specimen_effects,
            "without_specimen_factors": r.without_specimen_factors,
            "campaign_levels": r.campaign_levels,
            "constants": all_names.iter().zip(r.given.iter().zip(&r.params)).map(|(n, (g, v))| json!({
                "name": n,
                "given": g,
                "refit": v,
                "difference": v - g,
                "relative_difference_pct": jnum(100.0 * (v - g) / g.abs()),
            })).collect::<Vec<_>>(),
        })),
        "interval_calibration": run.calibration.as_ref().map(|c| json!({
            "what": "the parametric-bootstrap calibration of the intervals' likelihood-ratio thresholds ([profile] calibrate replicates): each condition's intervals use the thresholds of its own rupture time, mean T over the replicates times the quantile of F(1, replicates), floored at χ²₁'s (per_quantity); prediction_factor is the 95 % threshold over χ²₁'s of the rupture times pooled",
            "replicates": c.replicates,
            "failed": c.failed,
            "prediction_factor": jnum(c.prediction_factor),
            "constants_factor": jnum(c.factor),
            "mean_t": jnum(c.mean_t),
            "per_quantity": c.per_quantity.iter().map(|q| json!({"quantity": q.quantity, "mean_t": jnum(q.mean_t), "replicates": q.replicates, "t": q.t, "t68": jnum(q.thresholds.t68), "t95": jnum(q.thresholds.t95)})).collect::<Vec<_>>(),
        })),
        "predictions": run.predictions.iter().enumerate().map(|(k, p)| {
            let at = model.constants_at(params, p.condition.temperature_c);
            json!({
                "temperature_C": p.condition.temperature_c,
                "stress_MPa": p.condition.stress_mpa,
                "outcome": p.outcome.as_str(),
                "extrapolation": run.extrapolation.get(k),
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
                "given": given_row(run.given.as_ref().and_then(|g| g.get(k))),
            })
        }).collect::<Vec<_>>(),
        "limits": {
            "tested_temperatures_C": tested.temperatures.iter().map(|t| json!({"temperature_C": t.0, "stress_MPa": [t.1, t.2]})).collect::<Vec<_>>(),
            "temperature_range_C": [jnum(t0), jnum(t1)],
            "temperature_margin_C": TEMPERATURE_MARGIN_C,
            "stress_margin_factor": STRESS_MARGIN_FACTOR,
            "temperature_laws": cfg.has_laws(),
        },
        "larson_miller": match &run.lmp {
            Ok(l) => json!(l),
            Err(e) => json!({"error": e}),
        },
        "baselines": run.baselines.iter().map(Baseline::to_json).collect::<Vec<_>>(),
        "extrapolation": extrapolation_notes(&tested, &run.predictions.iter().map(|p| p.condition).collect::<Vec<_>>()),
        "tests": run.measured.as_ref().map(|m| m.json(run)),
    })
}

/// The header and rows of `predictions.csv` ([`write_outputs`]).
pub fn predictions_table(run: &PredictRun) -> (Vec<&'static str>, Vec<Vec<String>>) {
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
            row.push(
                run.extrapolation
                    .get(k)
                    .map_or("", |x| x.as_str())
                    .to_string(),
            );
            row.push(p.outcome.as_str().to_string());
            row.push(run.source.as_str().to_string());
            if let Some(g) = run.given.as_ref().and_then(|g| g.get(k)) {
                row.extend([
                    num(g.rupture_time_h),
                    num(100.0 * g.rupture_strain),
                    num(100.0 * g.min_rate),
                    g.outcome.as_str().to_string(),
                ]);
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
    header.extend(ROW_COLUMNS);
    if run.given.is_some() {
        header.extend(GIVEN_COLUMNS);
    }
    (header, rows)
}

/// `predictions.csv`'s columns after the contract's (and the interval columns): where the
/// condition lies against the tested ones ([`Extrapolation`]), how the simulation ended
/// ([`Outcome`]; a failed one leaves the numbers empty) and which constants the row's numbers
/// come from ([`ConstantsSource`]).
pub const ROW_COLUMNS: [&str; 3] = ["extrapolation", "outcome", "constants"];

/// `predictions.csv`'s last columns when the row's constants are the refit (`--intervals`):
/// the predictions at the given constants.
pub const GIVEN_COLUMNS: [&str; 4] = [
    "given_rupture_time_h",
    "given_rupture_strain_pct",
    "given_min_rate_pct_per_h",
    "given_outcome",
];

/// `band.csv`'s columns under `--intervals`: the 95 % confidence band of each predicted curve
/// (the model's prediction, from the constants' uncertainty; pointwise prediction profile
/// likelihood) at `[profile] band_points` fractions of its rupture time. Where constants of
/// the confidence set rupture the test by the time (`strain_conf_hi95_ruptured`), the upper
/// end is rupture and its cell is empty. Where the lower end's search stopped before it
/// crossed the threshold (`strain_conf_lo95_open`), the set's lowest strain may lie below.
pub const BAND_COLUMNS: [&str; 8] = [
    "temperature_C",
    "stress_MPa",
    "time_h",
    "strain_pct",
    "strain_conf_lo95_pct",
    "strain_conf_hi95_pct",
    "strain_conf_hi95_ruptured",
    "strain_conf_lo95_open",
];

pub use crate::report::plot::PLOT_POINTS;

/// A polyline of (time h, strain %).
pub type Line = Vec<(f64, f64)>;

/// The band as `band.png` draws it around `curve` (time h, strain %): at each time of the
/// curve within the band's times, the curve widened by the band's lower and upper
/// half-widths relative to the strain (absolute where a band strain is not positive),
/// interpolated linearly in time between the band's points. At a band point this is the band
/// itself (band and curve share their centre); between points the band keeps its relative
/// width about the curve, so that it surrounds the curve it is drawn with (straight lines
/// between the band's points would cut through a steep tertiary curve). The upper line ends
/// at the last band point whose upper end is not rupture (`hi95_ruptured`): after it the
/// test may have ruptured. Empty without band points.
pub fn band_lines(
    curve: &[(f64, f64)],
    band: &[crate::uncertainty::predict::BandPoint],
) -> (Line, Line) {
    let relative = band.iter().all(|p| p.strain_pct > 0.0);
    let scale = |e: f64| if relative { e } else { 1.0 };
    let intact_until = band
        .iter()
        .filter(|p| !p.hi95_ruptured && p.hi95_pct.is_finite())
        .map(|p| p.time_h)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut b: Vec<(f64, f64, f64)> = band
        .iter()
        .map(|p| {
            let e = scale(p.strain_pct);
            (
                p.time_h,
                (p.strain_pct - p.lo95_pct) / e,
                if p.time_h <= intact_until {
                    (p.hi95_pct - p.strain_pct) / e
                } else {
                    f64::NAN
                },
            )
        })
        .collect();
    b.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (Some(first), Some(last)) = (b.first().copied(), b.last().copied()) else {
        return (vec![], vec![]);
    };
    let half = |t: f64| -> (f64, f64) {
        let k = b.iter().position(|x| x.0 >= t).unwrap_or(b.len() - 1);
        if k == 0 || b[k].0 == t {
            return (b[k].1, b[k].2);
        }
        let (a, c) = (b[k - 1], b[k]);
        let w = (t - a.0) / (c.0 - a.0);
        (a.1 + w * (c.1 - a.1), a.2 + w * (c.2 - a.2))
    };
    let mut times: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(t, _)| *t >= first.0 && *t <= last.0)
        .collect();
    // The band's own points, with their strains, so that the drawn band passes through them.
    times.extend(band.iter().map(|p| (p.time_h, p.strain_pct)));
    times.sort_by(|x, y| x.0.total_cmp(&y.0));
    times.dedup_by(|x, y| x.0 == y.0);
    let lo = times
        .iter()
        .map(|&(t, e)| (t, e - half(t).0 * scale(e)))
        .collect();
    let hi = times
        .iter()
        .filter(|&&(t, _)| t <= intact_until)
        .map(|&(t, e)| (t, e + half(t).1 * scale(e)))
        .collect();
    (lo, hi)
}

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
            let curve: Vec<(f64, f64)> = p.curve.iter().map(|(t, e, _)| (*t, 100.0 * e)).collect();
            let (lo, hi) = band_lines(&curve, &ci.band);
            groups.push(XyGroup::line(
                p.condition.label(),
                curve,
                Rgb::palette(k),
                Dash::Solid,
            ));
            for (label, line) in [
                (format!("{}: 95 % band", p.condition.label()), hi),
                (String::new(), lo),
            ] {
                groups.push(XyGroup::line(label, line, Rgb::palette(k), Dash::Dashed));
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

/// Measured points and dense predicted curves for a plot.
pub fn curve_plots(
    cfg: &RunConfig,
    data: &Dataset,
    params: &[f64],
    ode: &OdeOptions,
    model: &dyn crate::model::Model,
) -> Vec<CurvePlot> {
    data.curves
        .iter()
        .map(|c| {
            let load = Load::of_curve(c, cfg.objective.omega_f);
            let o = crate::model::objective::curve_horizon(c, ode);
            let res = model.simulate(params, &load, &[], &mut [], &o);
            let grid = crate::predict::dense_grid(res.t_end, 400);
            let (_, traj) = model.trajectory(params, &load, &grid, &o);
            CurvePlot {
                id: CurveId::of(c),
                measured: tables::thin(
                    c.times_h
                        .iter()
                        .zip(&c.strains)
                        .map(|(t, e)| (*t, 100.0 * e))
                        .collect(),
                    PLOT_POINTS,
                ),
                predicted: traj.iter().map(|(t, e, _)| (*t, 100.0 * e)).collect(),
            }
        })
        .collect()
}

/// The printout's notes on the test campaigns of a refit with specimen effects: one line per
/// kind on how its factors differ between campaigns, then what a new test's interval leaves
/// out, unless a kind's line has said it already (its campaigns differ); empty without
/// campaigns.
fn campaign_notes(levels: &[crate::likelihood::CampaignLevels]) -> String {
    if levels.is_empty() {
        return String::new();
    }
    let mut s: String = levels
        .iter()
        .map(|c| {
            format!(
                "  note: {}\n",
                crate::report::tables::campaign_levels_text(c)
            )
        })
        .collect();
    if levels.iter().any(|c| c.differ()) {
        return s;
    }
    s.push_str("  note: a new test's interval draws its specimen from one population of specimens, whichever campaign it comes from: for a specimen of a campaign not in the data it leaves the difference between campaigns out\n");
    s
}

#[cfg(test)]
mod tests {
    /// The campaign notes: none without campaigns; with them a line per kind (the report's
    /// campaign line) and the sentence on what a new test's interval leaves out.
    #[test]
    fn campaign_notes_say_what_a_new_tests_interval_leaves_out() {
        use crate::likelihood::{CampaignLevels, EffectKind};
        assert_eq!(campaign_notes(&[]), "");
        let level = |kind| CampaignLevels {
            kind,
            mean_ln: vec![("INL2".into(), 0.21), ("KAERI2".into(), -0.25)],
            f: 7.35,
            df: (1, 28),
            p_value: 0.011,
            detectable_ln: 0.82,
            new_group_sd: None,
        };
        let s = campaign_notes(&[level(EffectKind::Rate), level(EffectKind::Ductility)]);
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines.len(), 3, "{s}");
        assert!(lines[0]
            .starts_with("  note: The ln rate factors between campaigns: mean +0.21 for INL2"));
        assert!(lines[1].starts_with("  note: The ln ductility factors between campaigns"));
        assert!(lines[2].contains("leaves the difference between campaigns out"));
        // Where a kind's campaigns differ, its own line says what the interval leaves out
        // and the closing sentence would repeat it.
        let called = CampaignLevels {
            p_value: 0.009,
            ..level(EffectKind::Rate)
        };
        let s = campaign_notes(&[called, level(EffectKind::Ductility)]);
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines.len(), 2, "{s}");
        assert!(
            lines[0].contains("its interval leaves this difference out"),
            "{s}"
        );
        assert_eq!(s.matches("leaves").count(), 1, "{s}");
    }

    use super::*;
    use crate::uncertainty::predict::BandPoint;

    fn tested(laws: bool) -> Tested {
        Tested {
            temperatures: vec![(560.0, 85.0, 110.0), (590.0, 100.0, 120.0)],
            laws,
        }
    }

    fn at(t: f64, s: f64) -> Condition {
        Condition {
            temperature_c: t,
            stress_mpa: s,
        }
    }

    #[test]
    fn where_a_condition_lies() {
        use Extrapolation as X;
        let t = tested(true);
        // (temperature, stress, Some(class) or None = refused)
        let table = [
            (560.0, 100.0, Some(X::None)),
            // Between 560 and 590 °C the ends interpolated on log σ: at 575 °C
            // √(85·100) = 92.20 to √(110·120) = 114.89 MPa; at 567.5 °C from
            // 85^0.75·100^0.25 = 88.53 MPa. Outside: marked; refused only beyond 1.5 times
            // the union 85–120 MPa.
            (575.0, 100.0, Some(X::None)),
            (575.0, 92.3, Some(X::None)),
            (575.0, 92.1, Some(X::Stress)),
            (575.0, 114.8, Some(X::None)),
            (575.0, 115.0, Some(X::Stress)),
            (567.5, 88.6, Some(X::None)),
            (567.5, 88.4, Some(X::Stress)),
            (575.0, 85.0, Some(X::Stress)),
            (575.0, 120.0, Some(X::Stress)),
            (575.0, 84.0, Some(X::Stress)),
            (575.0, 57.0, Some(X::Stress)),
            (575.0, 56.0, Option::None),
            (575.0, 179.9, Some(X::Stress)),
            (575.0, 180.1, Option::None),
            (560.0, 120.0, Some(X::Stress)), // above 560 °C's own 110 MPa
            (560.0, 85.0 / 1.5, Some(X::Stress)),
            (560.0, 85.0 / 1.5 * 0.999, Option::None),
            (590.0, 180.0, Some(X::Stress)),
            (590.0, 180.1, Option::None),
            (600.0, 110.0, Some(X::Temperature)), // nearest tested: 590 °C, 100–120 MPa
            (615.0, 110.0, Some(X::Temperature)),
            (615.1, 110.0, Option::None),
            (535.0, 90.0, Some(X::Temperature)),
            (534.9, 90.0, Option::None),
            (600.0, 75.0, Some(X::Both)),
            (600.0, 66.0, Option::None), // below 100/1.5 at 590 °C's range
            (5000.0, 100.0, Option::None),
            (20.0, 100.0, Option::None),
        ];
        for (temp, s, want) in table {
            let got = t.classify(at(temp, s));
            // A measured test (`predict --tests`) beyond the margins is marked, not refused.
            let measured = t.classify_measured(at(temp, s));
            match want {
                Some(x) => {
                    assert_eq!(got, Ok(x), "{temp} °C {s} MPa");
                    assert_eq!(measured, Ok(x), "{temp} °C {s} MPa");
                }
                Option::None => {
                    assert!(got.is_err(), "{temp} °C {s} MPa: {got:?}");
                    assert_eq!(measured, Ok(X::BeyondLimits), "{temp} °C {s} MPa");
                }
            }
        }
        // Without a temperature law only the tested temperatures, for a measured test too.
        let t = tested(false);
        assert!(t.classify_measured(at(575.0, 100.0)).is_err());
        assert_eq!(X::BeyondLimits.as_str(), "beyond_limits");
        assert_eq!(t.classify(at(560.0, 100.0)), Ok(X::None));
        let e = t.classify(at(575.0, 100.0)).unwrap_err();
        assert!(e.contains("no temperature law") && e.contains("575"), "{e}");
        assert_eq!(serde_json::to_value(X::Both).unwrap(), "both");
    }

    #[test]
    fn the_drawn_band_surrounds_its_curve_to_its_end() {
        // A steep convex curve and a band whose half-widths grow towards rupture.
        let curve: Vec<(f64, f64)> = (0..=400)
            .map(|k| {
                let t = k as f64 * 2.5;
                (t, 0.1 + 0.001 * t + 5.0 * (t / 1000.0).powi(12))
            })
            .collect();
        let e = |t: f64| 0.1 + 0.001 * t + 5.0 * (t / 1000.0).powi(12);
        let band: Vec<BandPoint> = (1..=9)
            .map(|k| {
                let t = 1000.0 * k as f64 / 9.0;
                let w = 0.02 + 0.05 * (t / 1000.0).powi(6);
                BandPoint {
                    time_h: t,
                    strain_pct: e(t),
                    lo95_pct: e(t) * (1.0 - w),
                    hi95_pct: e(t) * (1.0 + 1.5 * w),
                    hi95_ruptured: false,
                    lo95_open: false,
                }
            })
            .collect();
        let (lo, hi) = band_lines(&curve, &band);
        assert_eq!(lo.len(), hi.len());
        // From the first band point to the curve's end (the last band point).
        assert!((lo[0].0 - 1000.0 / 9.0).abs() < 1e-9);
        assert_eq!(lo.last().unwrap().0, 1000.0);
        assert_eq!(hi.last().unwrap().0, curve.last().unwrap().0);
        for ((t, l), (_, h)) in lo.iter().zip(&hi) {
            let c = e(*t);
            assert!(*l <= c && c <= *h, "{t}: {l} {c} {h}");
        }
        // Through the band's own points.
        for b in &band {
            let k = lo.iter().position(|p| p.0 == b.time_h).unwrap();
            assert!((lo[k].1 - b.lo95_pct).abs() < 1e-12 && (hi[k].1 - b.hi95_pct).abs() < 1e-12);
        }
        // Straight lines between the band's points would cut through this curve.
        let (a, b) = (&band[7], &band[8]);
        let tm = 0.5 * (a.time_h + b.time_h);
        assert!(0.5 * (a.lo95_pct + b.lo95_pct) > e(tm));
        assert_eq!(band_lines(&curve, &[]), (vec![], vec![]));
        // The last three points' upper ends are rupture: the upper line ends at the sixth
        // point, unchanged before it; the lower line runs to the end as before.
        let mut cut = band.clone();
        for p in &mut cut[6..] {
            p.hi95_pct = f64::NAN;
            p.hi95_ruptured = true;
        }
        let (lo2, hi2) = band_lines(&curve, &cut);
        assert_eq!(lo2, lo);
        assert_eq!(hi2.last().unwrap().0, band[5].time_h);
        assert_eq!(hi2[..], hi[..hi2.len()]);
        assert!(hi2.iter().all(|p| p.1.is_finite()));
        // Every upper end rupture: no upper line.
        for p in &mut cut {
            p.hi95_pct = f64::NAN;
            p.hi95_ruptured = true;
        }
        let (lo3, hi3) = band_lines(&curve, &cut);
        assert_eq!(lo3, lo);
        assert!(hi3.is_empty());
    }
}
