//! Leave one temperature or one campaign out: how well does a calibration predict a
//! temperature, or a test campaign (another laboratory, heat or batch of specimens), it has
//! not seen? `creepfit holdout CONFIG --temperature T` (or `--campaign NAME`, [`LeftOut`])
//! fits the configuration on every curve not left out (`fit`'s procedure from the configured
//! start, the guess and `[sweep] starts` Latin-hypercube starts: the held-out data choose
//! nothing, not even the basin), predicts the rupture time and the curve of every test left
//! out, and fits the classical baselines ([`crate::baseline`]: Larson–Miller,
//! Orr–Sherby–Dorn, Manson–Haferd, Wilshire where tensile strengths are given) to the same
//! training rupture times. All are scored by the mean |log10(t_predicted / t_measured)| over
//! the held-out tests; the best baseline is "the one to beat".
//!
//! The curve error of a held-out test compares the measured points up to the predicted
//! rupture only ([`curve_error`]): after it the model has no curve (the objective's linear
//! continuation is a device of the fit, not a prediction), and how early it ruptured is
//! reported beside it (predicted life as % of the measured one, [`CurveOutcome`]).

use serde::Serialize;
use serde_json::json;

use crate::baseline::{self, Baseline, BaselineKind, BaselineSettings};
use crate::config::RunConfig;
use crate::data::{Condition, Curve, Dataset, RuptureRecord};
use crate::error::{Error, Result};
use crate::fit::{run_fit_observed, FitRun};
use crate::lmp::LarsonMiller;
use crate::model::objective::{mean_abs, CurvePrediction, Objective};
use crate::model::Load;
use crate::ode::Outcome;
use crate::report::tables::{self, jnum, num};
pub use crate::scores::{
    baseline_columns, one_to_beat, paired_difference, scores_json, scores_table, verdict,
    versus_text, Comparison, LifeScores, PairedDifference, Verdict, LIFE_COLUMNS,
};

/// What a hold-out leaves out of the fit.
#[derive(Debug, Clone, PartialEq)]
pub enum LeftOut {
    /// Every test at this temperature, °C.
    Temperature(f64),
    /// Every test of this campaign: specimens labelled `NAME` or `NAME-…` (the data's
    /// `specimen` column, e.g. `INL2-a` is of campaign `INL2`).
    Campaign(String),
}

impl LeftOut {
    /// Whether curve `c` is left out.
    pub fn contains(&self, c: &Curve) -> bool {
        self.holds(c.temperature_c, c.campaign())
    }
    /// Whether the life-only test `r` is left out.
    pub fn contains_record(&self, r: &RuptureRecord) -> bool {
        self.holds(r.temperature_c, r.campaign())
    }
    fn holds(&self, temperature_c: f64, campaign: Option<&str>) -> bool {
        match self {
            LeftOut::Temperature(t) => temperature_c == *t,
            LeftOut::Campaign(name) => campaign == Some(name.as_str()),
        }
    }
    /// In text: "850 °C", "campaign KAERI2".
    pub fn label(&self) -> String {
        match self {
            LeftOut::Temperature(t) => format!("{t} °C"),
            LeftOut::Campaign(name) => format!("campaign {name}"),
        }
    }
    /// The option that asked for it: "--temperature 850", "--campaign KAERI2".
    pub fn option(&self) -> String {
        match self {
            LeftOut::Temperature(t) => format!("--temperature {t}"),
            LeftOut::Campaign(name) => format!("--campaign {name}"),
        }
    }
    /// The default output folder's name under `results/<name>/`: `holdout-850C`,
    /// `holdout-campaign-KAERI2`.
    pub fn folder(&self) -> String {
        match self {
            LeftOut::Temperature(t) => format!("holdout-{t}C"),
            LeftOut::Campaign(name) => format!("holdout-campaign-{name}"),
        }
    }
    /// The held-out temperature, if a temperature is what is left out.
    pub fn temperature_c(&self) -> Option<f64> {
        match self {
            LeftOut::Temperature(t) => Some(*t),
            LeftOut::Campaign(_) => None,
        }
    }
}

/// The campaigns of `data`'s specimen labels ([`crate::data::campaign_of`]), of its curves and
/// life-only tests, sorted, each once.
pub fn campaigns(data: &Dataset) -> Vec<String> {
    let mut v: Vec<String> = data
        .curves
        .iter()
        .filter_map(|c| c.campaign().map(str::to_string))
        .chain(
            data.lives
                .iter()
                .filter_map(|r| r.campaign().map(str::to_string)),
        )
        .collect();
    v.sort();
    v.dedup();
    v
}

/// One held-out test and its predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// Temperature, °C.
    pub temperature_c: f64,
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
    /// Every baseline's, h, in [`crate::baseline::BaselineKind::ALL`]'s order (NaN where it is absent).
    pub baseline_rupture_time_h: Vec<f64>,
    /// RMS of (predicted − measured strain) / rupture strain over the measured points up to
    /// the predicted rupture, % ([`curve_error`]).
    pub curve_rms_pct: f64,
    /// Measured points that RMS is over.
    pub curve_points: usize,
    /// How far the prediction reaches along the measured curve.
    pub curve_outcome: CurveOutcome,
    /// creepfit's rupture time as % of the measured one (NaN if it did not rupture).
    pub predicted_life_pct: f64,
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
    /// log10(t / t_measured) of baseline `k` of [`crate::baseline::BaselineKind::ALL`].
    pub fn baseline_log10_err(&self, k: usize) -> f64 {
        (self.baseline_rupture_time_h[k] / self.rupture_time_h).log10()
    }
}

/// How far a held-out prediction reaches along the measured curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveOutcome {
    /// It ruptures at or after the last measured point: every point is compared.
    Complete,
    /// It ruptures before the last measured point: only the points up to its rupture are
    /// compared (see the predicted life in %).
    RupturedEarly,
    /// It does not rupture within the integration horizon: every point is compared.
    NoRupture,
    /// The simulation failed: no curve error.
    Failed,
    /// A life-only test (a rupture record without a curve): no curve to compare.
    NoCurve,
}

impl CurveOutcome {
    /// The file form (`complete`, `ruptured_early`, `no_rupture`, `failed`, `no_curve`).
    pub fn as_str(self) -> &'static str {
        match self {
            CurveOutcome::Complete => "complete",
            CurveOutcome::RupturedEarly => "ruptured_early",
            CurveOutcome::NoRupture => "no_rupture",
            CurveOutcome::Failed => "failed",
            CurveOutcome::NoCurve => "no_curve",
        }
    }
}

/// The curve error of one held-out test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveError {
    /// RMS of (predicted − measured strain)/ε_f over the compared points, % (NaN: none).
    pub rms_pct: f64,
    /// Measured points compared.
    pub points: usize,
    /// How far the prediction reaches.
    pub outcome: CurveOutcome,
}

/// Curve error of a prediction `p` of the measured curve `c`: the RMS of (ε_pred − ε)/ε_f (ε_f
/// the measured rupture strain) over the measured points at times up to the predicted rupture
/// (all of them when it ruptures later or not at all), in %. The points after an early
/// rupture are not compared: the model has no strain there (the objective's linear
/// continuation is a device of the fit), and a prediction's lateness or earliness is the
/// life error's to report, not the curve's.
pub fn curve_error(c: &Curve, p: &CurvePrediction) -> CurveError {
    let t_r = p.rupture_time_h;
    let (outcome, upto) = match p.outcome {
        Outcome::Ruptured if t_r.is_finite() => {
            let last = c.times_h.last().copied().unwrap_or(0.0);
            if t_r >= last {
                (CurveOutcome::Complete, f64::INFINITY)
            } else {
                (CurveOutcome::RupturedEarly, t_r)
            }
        }
        Outcome::Horizon => (CurveOutcome::NoRupture, f64::INFINITY),
        _ => {
            return CurveError {
                rms_pct: f64::NAN,
                points: 0,
                outcome: CurveOutcome::Failed,
            }
        }
    };
    let r: Vec<f64> = c
        .times_h
        .iter()
        .zip(&c.strains)
        .zip(&p.strain)
        .filter(|((t, _), _)| **t <= upto)
        .map(|((_, e), pe)| (pe - e) / c.rupture_strain)
        .collect();
    if r.iter().any(|v| !v.is_finite()) {
        return CurveError {
            rms_pct: f64::NAN,
            points: 0,
            outcome: CurveOutcome::Failed,
        };
    }
    let rms = if r.is_empty() {
        f64::NAN
    } else {
        100.0 * (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt()
    };
    CurveError {
        rms_pct: rms,
        points: r.len(),
        outcome,
    }
}

/// What a hold-out run computed.
pub struct Holdout {
    /// What was left out.
    pub left_out: LeftOut,
    /// The fit on the curves not left out.
    pub fit: FitRun,
    /// The baseline on the same training data, or why there is none.
    pub lmp: std::result::Result<LarsonMiller, String>,
    /// Every baseline on the same training data ([`crate::baseline::BaselineKind::ALL`]'s order).
    pub baselines: Vec<Baseline>,
    /// The held-out tests (with a measured rupture time).
    pub tests: Vec<HeldOut>,
    /// The held-out curves.
    pub curves: Vec<Curve>,
    /// The training data (the curves not left out; the diagrams of the training fit draw
    /// them).
    pub training: Dataset,
    /// Under `--intervals`: the maximum-likelihood refit of the training fit's constants the
    /// intervals (and `ml_rupture_time_h`) come from.
    pub intervals_refit: Option<crate::uncertainty::predict::Refit>,
    /// The training fit's objective, and the configured specimen effects it leaves out
    /// ([`crate::config::ObjectiveConfig::effects_left_out`]: all of them under eq. 8).
    pub objective_kind: crate::model::objective::ObjectiveKind,
    pub effects_left_out: Vec<crate::likelihood::EffectKind>,
    /// The training fit's reference temperature of the laws, °C (`None` without laws): the
    /// configuration's, else the training curves' mean ([`RunConfig::for_data`]).
    pub t_ref: Option<f64>,
}

impl Holdout {
    /// What the training fit's objective leaves out ([`crate::config::objective_note`]).
    pub fn objective_note(&self) -> Option<String> {
        crate::config::objective_note(self.objective_kind, &self.effects_left_out)
    }
    /// The training fit's caution about its rupture times ([`crate::fit::lives_caution`]);
    /// `None` without one. A training fit that gives up some tests' lives predicts held-out
    /// tests near them with the same miss.
    pub fn training_caution(&self) -> Option<String> {
        let labels: Vec<String> = self.training.curves.iter().map(Curve::label).collect();
        crate::fit::lives_caution(&labels, &self.fit.fits[self.fit.best].lifetime_err_pct)
    }
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
    /// Under `--intervals` with a campaign left out: what the interval of a new test holds (the
    /// scatter between the training data's specimens) and what it does not (the held-out
    /// campaign's own level, a heat's or a laboratory's: no scatter between campaigns is
    /// added); `None` otherwise. Measured on Alloy 617's two campaigns: 12 of 19 and 7 of 15
    /// held-out lives inside it, against 16 of 20 for a held-out temperature.
    pub fn interval_scope(&self) -> Option<String> {
        let LeftOut::Campaign(name) = &self.left_out else {
            return None;
        };
        if self.inside_pred95().1 == 0 {
            return None;
        }
        let trained = campaigns(&self.training);
        let from = if trained.is_empty() {
            "the training data".to_string()
        } else {
            format!("campaign(s) {}", trained.join(", "))
        };
        Some(format!(
            "the interval of a new test holds the scatter between specimens of {from}, not campaign {name}'s own level (a heat's or a laboratory's): it adds no scatter between campaigns, so read it as the interval of another test from {from}"
        ))
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
    /// The held-out tests' rupture-time errors, creepfit's and every baseline's.
    pub fn scores(&self) -> LifeScores {
        LifeScores::of(self.tests.iter().map(|t| {
            (
                (t.temperature_c, t.stress_mpa),
                t.rupture_time_h,
                t.model_rupture_time_h,
                &t.baseline_rupture_time_h[..],
            )
        }))
    }
    /// creepfit's (mean |log10 error|, held-out tests it predicted a life for).
    pub fn model_score(&self) -> (f64, usize) {
        self.scores().model_score()
    }
    /// Baseline `k`'s (mean |log10 error|, held-out tests it predicted).
    pub fn baseline_score(&self, k: usize) -> (f64, usize) {
        self.scores().baseline_score(k)
    }
    /// The one to beat ([`one_to_beat`]).
    pub fn one_to_beat(&self) -> Option<usize> {
        self.scores().one_to_beat()
    }
    /// creepfit against baseline `k` over the held-out tests ([`paired_difference`]).
    pub fn versus(&self, k: usize) -> Option<PairedDifference> {
        self.scores().versus(k)
    }
    /// Whether creepfit beats it ([`verdict`]).
    pub fn verdict(&self) -> Verdict {
        self.scores().verdict()
    }
    /// Held-out tests per [`CurveOutcome`]: complete, ruptured early, no rupture, failed,
    /// no curve (life-only tests).
    pub fn curve_outcomes(&self) -> [usize; 5] {
        let n = |o: CurveOutcome| self.tests.iter().filter(|t| t.curve_outcome == o).count();
        [
            n(CurveOutcome::Complete),
            n(CurveOutcome::RupturedEarly),
            n(CurveOutcome::NoRupture),
            n(CurveOutcome::Failed),
            n(CurveOutcome::NoCurve),
        ]
    }
    /// The temperatures fitted on, °C, ascending.
    pub fn training_temperatures_c(&self) -> Vec<f64> {
        let mut temps: Vec<f64> = self
            .training
            .curves
            .iter()
            .map(|c| c.temperature_c)
            .collect();
        temps.sort_by(f64::total_cmp);
        temps.dedup();
        temps
    }
    /// Whether a held-out test lies outside the training temperatures (an extrapolation of
    /// the temperature laws).
    pub fn temperature_extrapolation(&self) -> bool {
        let temps = self.training_temperatures_c();
        let (Some(lo), Some(hi)) = (temps.first(), temps.last()) else {
            return true;
        };
        self.tests
            .iter()
            .any(|t| t.temperature_c < *lo || t.temperature_c > *hi)
    }
}

/// Fit `cfg` on the curves of `data` not `left_out`, predict those left out; with
/// `intervals`, also the 95 % intervals of each held-out rupture time from the training data.
pub fn holdout(
    cfg: &RunConfig,
    data: &Dataset,
    left_out: &LeftOut,
    intervals: bool,
) -> Result<Holdout> {
    holdout_observed(
        cfg,
        data,
        left_out,
        intervals,
        &crate::progress::Hooks::default(),
    )
}

/// [`holdout`] telling `hooks.observer` of its phases (the training fits, then the
/// intervals), the training fits journaled in `hooks.journal` and resumed from it
/// ([`crate::fit::run_fit_observed`]).
pub fn holdout_observed(
    cfg: &RunConfig,
    data: &Dataset,
    left_out: &LeftOut,
    intervals: bool,
    hooks: &crate::progress::Hooks,
) -> Result<Holdout> {
    let (test, train): (Vec<Curve>, Vec<Curve>) = data
        .curves
        .iter()
        .cloned()
        .partition(|c| left_out.contains(c));
    // Life-only tests left out: predicted by simulation to rupture at their conditions.
    let lives: Vec<&RuptureRecord> = data
        .lives
        .iter()
        .filter(|r| left_out.contains_record(r))
        .collect();
    let mut temps: Vec<f64> = train.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let what = left_out.option();
    if test.is_empty() && lives.is_empty() {
        return Err(Error::Invalid(match left_out {
            LeftOut::Temperature(_) => format!("{what}: no tests at that temperature"),
            LeftOut::Campaign(_) if campaigns(data).is_empty() => format!(
                "{what}: the data have no specimen labels (a `specimen` column, e.g. INL2-a: campaign INL2) to tell campaigns by"
            ),
            LeftOut::Campaign(_) => format!(
                "{what}: no test's specimen is of that campaign (specimen labels NAME or NAME-…; the data's campaigns: {})",
                campaigns(data).join(", ")
            ),
        }));
    }
    if train.is_empty() {
        return Err(Error::Invalid(format!(
            "{what}: every curve is left out; nothing to fit"
        )));
    }
    // Tests at a temperature the training data lack are predicted through the temperature
    // laws, which need them and two or more training temperatures.
    let new_temperature = test
        .iter()
        .map(|c| c.temperature_c)
        .chain(lives.iter().map(|r| r.temperature_c))
        .any(|t| !temps.contains(&t));
    if new_temperature && !cfg.has_laws() {
        return Err(Error::config(
            &cfg.path,
            "constants: a hold-out across temperatures needs temperature laws (law = \"arrhenius\" or \"linear\" on some constant)",
        ));
    }
    if new_temperature && temps.len() < 2 {
        return Err(Error::Invalid(format!(
            "{what}: {} temperature(s) left to fit; the laws need two or more",
            temps.len()
        )));
    }
    let train_data = Dataset::of_curves(train);
    // Resolved as a run on the training data alone would be: the tests left out do not set
    // the reference temperature of the laws.
    let cfg = &cfg.for_data(&train_data);
    let fit = run_fit_observed(
        cfg.calibration(&train_data)?,
        &train_data,
        cfg.sweep.starts,
        hooks,
    )?;
    let best = &fit.fits[fit.best];
    let lmp = LarsonMiller::fit_curves(&train_data.curves, cfg.predict.lmp_degree)
        .map_err(|e| e.to_string());
    let baselines = baseline::fit_all(
        &baseline::rupture_tests(&train_data.curves),
        &BaselineSettings {
            degree: cfg.predict.lmp_degree,
            tensile: &cfg.predict.tensile_strength,
        },
    );
    let settings = crate::fit::FitSettings::from_config(cfg);
    let eval = Objective::new(
        fit.model.as_ref(),
        &test,
        vec![1.0; test.len()],
        settings.objective(),
    )
    .evaluate(&best.params);
    // One interval per distinct held-out load (replicates share it).
    let mut loads_tc: Vec<(f64, f64)> = test
        .iter()
        .filter(|c| c.rupture_time_h.is_some())
        .map(|c| (c.temperature_c, c.stress_mpa))
        .chain(lives.iter().map(|r| (r.temperature_c, r.stress_mpa)))
        .collect();
    loads_tc.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    loads_tc.dedup();
    let mut intervals_refit = None;
    let by_load: Vec<Option<RuptureInterval>> = if intervals {
        let loads: Vec<Load> = loads_tc
            .iter()
            .map(|&(t, s)| Load::new(s, t, cfg.objective.omega_f))
            .collect();
        let iv = crate::uncertainty::predict::intervals_at_observed(
            &cfg.likelihood_setup(&train_data),
            fit.model.as_ref(),
            &train_data,
            &best.params,
            &loads,
            // Journaled too: the records' keys hash what they are computed from.
            hooks,
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
        vec![None; loads_tc.len()]
    };
    // One held-out test: at (°C, MPa), its specimen, measured and predicted lives (h) and how
    // its curve compares.
    let held = |t: f64,
                sigma: f64,
                specimen: &Option<String>,
                measured: f64,
                model: f64,
                ce: CurveError| HeldOut {
        temperature_c: t,
        stress_mpa: sigma,
        specimen: specimen.clone(),
        rupture_time_h: measured,
        model_rupture_time_h: model,
        lmp_rupture_time_h: lmp.as_ref().map_or(f64::NAN, |l| l.rupture_time(t, sigma)),
        baseline_rupture_time_h: baselines.iter().map(|b| b.predict(t, sigma)).collect(),
        curve_rms_pct: ce.rms_pct,
        curve_points: ce.points,
        curve_outcome: ce.outcome,
        predicted_life_pct: 100.0 * model / measured,
        interval: loads_tc
            .iter()
            .position(|&l| l == (t, sigma))
            .and_then(|k| by_load[k]),
    };
    let mut tests: Vec<HeldOut> = test
        .iter()
        .zip(&eval.curves)
        .filter(|(c, _)| c.rupture_time_h.is_some())
        .map(|(c, p)| {
            held(
                c.temperature_c,
                c.stress_mpa,
                &c.specimen,
                c.rupture_time_h.unwrap_or(f64::NAN),
                p.rupture_time_h,
                curve_error(c, p),
            )
        })
        .collect();
    // The life-only tests: the model simulated to rupture at each condition, over the horizon
    // `predict` gives it.
    let no_curve = CurveError {
        rms_pct: f64::NAN,
        points: 0,
        outcome: CurveOutcome::NoCurve,
    };
    for r in &lives {
        let c = Condition {
            temperature_c: r.temperature_c,
            stress_mpa: r.stress_mpa,
        };
        let lmp_life = lmp
            .as_ref()
            .map_or(f64::NAN, |l| l.rupture_time(c.temperature_c, c.stress_mpa));
        let sim = crate::predict::simulate_at(
            fit.model.as_ref(),
            &best.params,
            c,
            cfg.objective.omega_f,
            &settings.ode,
            crate::predict::horizon(&train_data, lmp_life),
        );
        let model = if sim.ruptured() { sim.t_end } else { f64::NAN };
        // No curve to compare; a prediction without a life says why.
        let outcome = match sim.outcome {
            Outcome::Ruptured => CurveOutcome::NoCurve,
            Outcome::Horizon => CurveOutcome::NoRupture,
            _ => CurveOutcome::Failed,
        };
        tests.push(held(
            r.temperature_c,
            r.stress_mpa,
            &r.specimen,
            r.rupture_time_h,
            model,
            CurveError {
                outcome,
                ..no_curve
            },
        ));
    }
    tests.sort_by(|a, b| {
        a.temperature_c
            .total_cmp(&b.temperature_c)
            .then(a.stress_mpa.total_cmp(&b.stress_mpa))
    });
    Ok(Holdout {
        left_out: left_out.clone(),
        fit,
        lmp,
        baselines,
        tests,
        curves: test,
        objective_kind: cfg.objective.kind,
        effects_left_out: cfg
            .objective
            .effects_left_out(&train_data.curves, crate::config::LocalFits::Fit),
        training: train_data,
        intervals_refit,
        t_ref: cfg.t_ref,
    })
}

/// `holdout.csv` of a finished hold-out: its header and one row per held-out test (measured,
/// creepfit, every baseline; the interval columns with `--intervals`, `specimen` where the
/// data label specimens), as the command writes it and the Python package returns it.
pub fn csv_table(h: &Holdout) -> (Vec<String>, Vec<Vec<String>>) {
    let with_intervals = h.tests.iter().any(|t| t.interval.is_some());
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
    let mut header: Vec<String> = tables::with_specimen(&header, specimens)
        .into_iter()
        .map(str::to_string)
        .collect();
    header.extend(baseline_columns());
    header.extend(CURVE_COLUMNS.iter().map(|c| c.to_string()));
    (header, rows)
}

/// `summary.json` of a finished hold-out of `cfg`.
pub fn summary_json(cfg: &RunConfig, h: &Holdout) -> serde_json::Value {
    let best = &h.fit.fits[h.fit.best];
    let inside_pred95 = {
        let (inside, with) = h.inside_pred95();
        json!({"inside": inside, "tests": with})
    };
    let scores = h.scores();
    let (baselines, one_to_beat) = crate::holdout::scores_json(&scores, &h.baselines);
    let [complete, early, no_rupture, failed, no_curve] = h.curve_outcomes();
    json!({
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
    })
}

/// The printed table.
pub fn table(h: &Holdout) -> String {
    let mut s = format!(
        "held out {}: {} tests\n  T(C)    MPa  specimen  |  t_r meas h  creepfit h     LMP h | log10 err creepfit    LMP | curve rms % e_f\n",
        h.left_out.label(),
        h.tests.len()
    );
    for t in &h.tests {
        s.push_str(&format!(
            "{:>6} {:>6} {:>9} | {:>11.1} {:>11.1} {:>9.1} | {:>18.3} {:>6.3} | {:>8.2}{}\n",
            t.temperature_c,
            t.stress_mpa,
            t.specimen.as_deref().unwrap_or("-"),
            t.rupture_time_h,
            t.model_rupture_time_h,
            t.lmp_rupture_time_h,
            t.model_log10_err(),
            t.lmp_log10_err(),
            t.curve_rms_pct,
            match t.curve_outcome {
                CurveOutcome::Complete => String::new(),
                CurveOutcome::RupturedEarly => format!(
                    "  ruptured early at {:.1} % of the measured life: rms over the first {} points",
                    t.predicted_life_pct, t.curve_points
                ),
                CurveOutcome::NoCurve => "  life only (no curve)".to_string(),
                o => format!("  {}", o.as_str()),
            }
        ));
    }
    if let Some(c) = h.training_caution() {
        s.push_str(&format!("caution (the training fit): {c}\n"));
    }
    if let Some(n) = h.objective_note() {
        s.push_str(&format!("note (the training fit): {n}\n"));
    }
    s.push_str(&format!(
        "mean |log10 error| of the rupture time: creepfit {:.3}, Larson–Miller {:.3}\n",
        h.model_mean_abs_log10(),
        h.lmp_mean_abs_log10()
    ));
    s.push_str(&baselines_table(h));
    let (inside, with) = h.inside_pred95();
    if with > 0 {
        s.push_str("95 % intervals of the rupture time from the training data (maximum-likelihood fit, error model of README \"How sure\"): prediction interval of a NEW TEST | confidence interval of the model's prediction\n");
        for t in &h.tests {
            if let Some(i) = t.interval {
                s.push_str(&format!(
                    "{:>6} {:>6} {:>9} | measured {:>11.1} | new test [{:.1}, {:.1}] {} | model {:.1} [{:.1}, {:.1}]\n",
                    t.temperature_c,
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
        if let Some(n) = h.interval_scope() {
            s.push_str(&format!("note: {n}\n"));
        }
        if let Some(r) = &h.intervals_refit {
            s.push_str(&format!(
                "the intervals are centred on the maximum-likelihood refit of the training fit's constants (holdout.csv: ml_rupture_time_h; −2 ln L {:.3} there, {:.3} at the training fit: difference {:.3}; summary.json: intervals_refit)\n",
                r.neg2ll,
                r.given_neg2ll,
                r.delta_neg2ll()
            ));
            if !r.specimen_effects.is_empty() {
                let kinds: Vec<&str> = r.specimen_effects.iter().map(|k| k.name()).collect();
                s.push_str(&format!(
                    "note: every fit here integrates the specimens' {} factors out (the hierarchical likelihood); the constants are the population's\n",
                    kinds.join(" and ")
                ));
            }
        }
    }
    if let Err(e) = &h.lmp {
        s.push_str(&format!("no Larson–Miller baseline: {e}\n"));
    }
    s
}

/// The printed comparison with the classical baselines: each one's mean |log10 error| over the
/// held-out tests beside creepfit's, its constants or why it is absent, and the one to beat.
pub fn baselines_table(h: &Holdout) -> String {
    scores_table(
        &h.scores(),
        &h.baselines,
        &format!(
            "mean |log10 error| of the rupture time over the {} held-out tests, classical baselines fitted to the same training rupture times:",
            h.tests.len()
        ),
        "held-out test",
    )
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

/// `holdout.csv`'s last columns: creepfit's rupture time as % of the measured one, the
/// [`CurveOutcome`] and the number of measured points `curve_rms_pct` is over.
pub const CURVE_COLUMNS: [&str; 3] = ["predicted_life_pct", "curve_outcome", "curve_points"];

/// The run identity of `holdout` of `cfg` (bound to its data) leaving out `left_out`, kept in
/// its journal: the configuration's ([`crate::config::identity`]: every setting of the
/// training fits, the data's hash, the crate version), the command and what is held out.
pub fn identity(cfg: &RunConfig, left_out: &LeftOut) -> serde_json::Value {
    let mut id = crate::config::identity(cfg);
    id["command"] = "holdout".into();
    match left_out {
        LeftOut::Temperature(t) => id["held_out_temperature_C"] = (*t).into(),
        LeftOut::Campaign(name) => id["held_out_campaign"] = name.as_str().into(),
    }
    id
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::LifetimeTerm;
    use crate::model::build;
    use crate::model::objective::ObjectiveSettings;
    use crate::ode::OdeOptions;

    /// A measured curve of the KHD model at `truth` (100 MPa, 30 points to rupture) and the
    /// objective's prediction of it at `params` (with its continuation after rupture).
    fn measured_and_predicted(params: &[f64]) -> (Curve, CurvePrediction) {
        let truth = [1.2e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0];
        let model = build("khd", &[]).unwrap();
        let ode = OdeOptions {
            rtol: 1e-10,
            atol: 1e-14,
            ..OdeOptions::default()
        };
        let load = Load::new(100.0, 575.0, 1.0 / 3.0);
        let r = model.simulate(&truth, &load, &[], &mut [], &ode);
        let times: Vec<f64> = (0..=30).map(|k| r.t_end * k as f64 / 30.0).collect();
        let mut e = vec![0.0; times.len()];
        model.simulate(&truth, &load, &times, &mut e, &ode);
        let c = Curve {
            temperature_c: 575.0,
            stress_mpa: 100.0,
            specimen: None,
            rupture_strain: *e.last().unwrap(),
            strains: e,
            times_h: times,
            rupture_time_h: Some(r.t_end),
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: r.min_rate,
        };
        let settings = ObjectiveSettings {
            lifetime: LifetimeTerm::Both,
            omega_f: 1.0 / 3.0,
            ode,
        };
        let curves = [c.clone()];
        let p = Objective::new(model.as_ref(), &curves, vec![1.0], settings)
            .evaluate(params)
            .curves
            .remove(0);
        (c, p)
    }

    /// A prediction that ruptures at about a third of the measured life: only the points up
    /// to its rupture are compared, the RMS is finite and bounded by the data (no compared
    /// strain exceeds the larger rupture strain), while the old all-points RMS, with the
    /// linear continuation after rupture, is not.
    #[test]
    fn curve_error_of_an_early_rupture() {
        let (c, p) = measured_and_predicted(&[3.6e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0]);
        let t_meas = c.rupture_time_h.unwrap();
        assert_eq!(p.outcome, Outcome::Ruptured);
        assert!(
            p.rupture_time_h < 0.6 * t_meas,
            "{} of {t_meas}",
            p.rupture_time_h
        );
        let ce = curve_error(&c, &p);
        assert_eq!(ce.outcome, CurveOutcome::RupturedEarly);
        let upto = c.times_h.iter().filter(|t| **t <= p.rupture_time_h).count();
        assert!(upto >= 2 && upto < c.times_h.len(), "{upto}");
        assert_eq!(ce.points, upto);
        // By hand, over those points.
        let ss: f64 = (0..upto)
            .map(|k| ((p.strain[k] - c.strains[k]) / c.rupture_strain).powi(2))
            .sum();
        assert_eq!(ce.rms_pct, 100.0 * (ss / upto as f64).sqrt());
        let bound = 100.0 * p.rupture_strain.max(c.rupture_strain) / c.rupture_strain;
        assert!(
            ce.rms_pct.is_finite() && ce.rms_pct <= bound,
            "{} > {bound}",
            ce.rms_pct
        );
        let n = c.times_h.len();
        let all: f64 = (0..n)
            .map(|k| ((p.strain[k] - c.strains[k]) / c.rupture_strain).powi(2))
            .sum();
        let old = 100.0 * (all / n as f64).sqrt();
        assert!(
            old > bound,
            "the continuation stays within the data: {old} <= {bound}"
        );
    }

    #[test]
    fn curve_error_of_a_late_rupture_failure_and_no_rupture() {
        let (c, p) = measured_and_predicted(&[0.6e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0]);
        assert!(p.rupture_time_h > c.rupture_time_h.unwrap());
        let ce = curve_error(&c, &p);
        assert_eq!(ce.outcome, CurveOutcome::Complete);
        assert_eq!(ce.points, c.times_h.len());
        assert!(ce.rms_pct > 0.0 && ce.rms_pct.is_finite());
        // Same prediction as if it had not ruptured within the horizon: every point.
        let horizon = CurvePrediction {
            outcome: Outcome::Horizon,
            rupture_time_h: f64::NAN,
            ..p.clone()
        };
        let h = curve_error(&c, &horizon);
        assert_eq!(
            (h.outcome, h.points, h.rms_pct),
            (CurveOutcome::NoRupture, ce.points, ce.rms_pct)
        );
        for o in [
            Outcome::StepUnderflow,
            Outcome::MaxSteps,
            Outcome::InvalidStart,
        ] {
            let f = curve_error(
                &c,
                &CurvePrediction {
                    outcome: o,
                    ..p.clone()
                },
            );
            assert_eq!((f.outcome, f.points), (CurveOutcome::Failed, 0));
            assert!(f.rms_pct.is_nan());
        }
        assert_eq!(CurveOutcome::RupturedEarly.as_str(), "ruptured_early");
        assert_eq!(
            serde_json::to_value(CurveOutcome::NoRupture).unwrap(),
            "no_rupture"
        );
    }

    /// Which curves a campaign or a temperature leaves out, as a table.
    #[test]
    fn left_out_tables() {
        use crate::data::campaign_of;
        assert_eq!(campaign_of("INL2-a"), "INL2");
        assert_eq!(campaign_of("KAERI2"), "KAERI2");
        assert_eq!(campaign_of("S-1-b"), "S");
        assert_eq!(campaign_of(""), "");
        let curve = |t: f64, specimen: Option<&str>| Curve {
            temperature_c: t,
            specimen: specimen.map(str::to_string),
            ..measured_and_predicted(&[1.2e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0]).0
        };
        let inl2 = LeftOut::Campaign("INL2".into());
        let t850 = LeftOut::Temperature(850.0);
        for (c, by_campaign, by_temperature) in [
            (curve(850.0, Some("INL2-a")), true, true),
            (curve(950.0, Some("INL2")), true, false),
            (curve(850.0, Some("INL22-a")), false, true),
            (curve(850.0, Some("KAERI2-a")), false, true),
            (curve(850.0, None), false, true),
        ] {
            assert_eq!(inl2.contains(&c), by_campaign, "{:?}", c.specimen);
            assert_eq!(t850.contains(&c), by_temperature, "{:?}", c.specimen);
        }
        assert_eq!(inl2.folder(), "holdout-campaign-INL2");
        assert_eq!(t850.folder(), "holdout-850C");
        assert_eq!(t850.temperature_c(), Some(850.0));
        assert_eq!(inl2.temperature_c(), None);
    }
}
