//! `predict --tests FILE`: the predictions against the measured lives of tests the calibration
//! has not seen — another campaign, heat or laboratory, given as a rupture-times file —
//! scored as `holdout` scores its held-out tests ([`crate::scores::LifeScores`]): creepfit's
//! and every classical baseline's mean |log10 error|, the one to beat, and creepfit against
//! each with a 95 % interval over the tests' conditions.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::{ConstantsSource, PredictRun};
use crate::baseline::{BaselineKind, Extrapolation};
use crate::data::{Condition, RuptureRecord};
use crate::error::{Error, Result};
use crate::ode::Outcome;
use crate::report::tables::{jnum, num};
use crate::scores::LifeScores;

/// One measured test and its predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredTest {
    /// Temperature, °C.
    pub temperature_c: f64,
    /// Stress, MPa.
    pub stress_mpa: f64,
    /// Specimen label, if the file gives one.
    pub specimen: Option<String>,
    /// 1-based line in the file.
    pub line: usize,
    /// Measured rupture time, h.
    pub rupture_time_h: f64,
    /// creepfit's rupture time at the test's condition, h (`predictions.csv`'s; NaN if the
    /// prediction did not rupture).
    pub model_rupture_time_h: f64,
    /// Every baseline's, h, in [`BaselineKind::ALL`]'s order (NaN where absent).
    pub baseline_rupture_time_h: Vec<f64>,
    /// Where the condition lies against the calibration's tested conditions.
    pub extrapolation: Extrapolation,
    /// How creepfit's simulation at the condition ended (`model_rupture_time_h` is NaN unless
    /// it ruptured).
    pub outcome: Outcome,
    /// Under `--intervals`: the 95 % prediction interval of a new test's rupture time, h.
    pub pred95: Option<(f64, f64)>,
}

impl MeasuredTest {
    /// log10(t_model / t_measured).
    pub fn model_log10_err(&self) -> f64 {
        (self.model_rupture_time_h / self.rupture_time_h).log10()
    }
    /// log10(t / t_measured) of baseline `k` of [`BaselineKind::ALL`].
    pub fn baseline_log10_err(&self, k: usize) -> f64 {
        (self.baseline_rupture_time_h[k] / self.rupture_time_h).log10()
    }
    /// Whether the measured life lies inside the 95 % prediction interval (`None` without one).
    pub fn inside_pred95(&self) -> Option<bool> {
        self.pred95
            .map(|(lo, hi)| lo <= self.rupture_time_h && self.rupture_time_h <= hi)
    }
}

/// The measured tests of a `--tests` file, each with its predictions.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredTests {
    /// The file.
    pub file: PathBuf,
    /// Its tests, in file order.
    pub tests: Vec<MeasuredTest>,
    /// Which constants creepfit's lives come from: the given ones, or under `--intervals`
    /// their maximum-likelihood refit (`predictions.csv`'s `constants`).
    pub constants: ConstantsSource,
}

/// The tests of `file` (the ruptures format: `temperature_C,stress_MPa,rupture_time_h`, with
/// optional `specimen`, `rupture_strain_pct`, `min_rate_pct_per_h`; errors name file, line and
/// field); a file without a test is an error.
pub fn read(file: &Path) -> Result<Vec<RuptureRecord>> {
    non_empty(file, crate::data::read_ruptures(file)?)
}

/// `[predict] tests`: the file the configuration names read and its tests made `cfg`'s
/// conditions, as `--tests` does; `None` when it names none (or the command line's `--at` or
/// `--tests` replaced it).
pub fn from_config(
    cfg: &mut crate::config::RunConfig,
) -> Result<Option<(PathBuf, Vec<RuptureRecord>)>> {
    let Some(file) = cfg.predict.tests.clone() else {
        return Ok(None);
    };
    let records = read(&file)?;
    cfg.predict.at = conditions(&records);
    Ok(Some((file, records)))
}

/// [`read`] of the table's CSV text in memory, named `name` in errors.
pub fn read_bytes(name: &Path, bytes: &[u8]) -> Result<Vec<RuptureRecord>> {
    non_empty(name, crate::data::read_ruptures_bytes(name, bytes)?)
}

fn non_empty(file: &Path, records: Vec<RuptureRecord>) -> Result<Vec<RuptureRecord>> {
    if records.is_empty() {
        return Err(Error::data(file, 0, "no tests (rows) to predict"));
    }
    Ok(records)
}

/// Every test of `records` (read from `file`) one that `cfg` on `data` can predict at all
/// ([`crate::baseline::Tested::classify_measured`]): else an error naming the first one's
/// line. A test beyond the margins of a prediction is predicted and marked
/// (`beyond_limits`), not refused: one test far from the data does not stop the scoring of
/// the others (as `holdout` predicts every test it leaves out).
pub fn check(
    file: &Path,
    records: &[RuptureRecord],
    cfg: &crate::config::RunConfig,
    data: &crate::data::Dataset,
) -> Result<()> {
    let tested = crate::baseline::Tested::of(data, cfg.has_laws());
    for r in records {
        let c = Condition {
            temperature_c: r.temperature_c,
            stress_mpa: r.stress_mpa,
        };
        if let Err(why) = tested.classify_measured(c) {
            return Err(Error::data(
                file,
                r.line,
                format!(
                    "test at {} °C, {} MPa: {why}",
                    r.temperature_c, r.stress_mpa
                ),
            ));
        }
    }
    Ok(())
}

/// The distinct conditions of `records`, in file order: what `predict` predicts (replicates
/// share one prediction).
pub fn conditions(records: &[RuptureRecord]) -> Vec<Condition> {
    let mut out: Vec<Condition> = Vec::new();
    for r in records {
        let c = Condition {
            temperature_c: r.temperature_c,
            stress_mpa: r.stress_mpa,
        };
        if !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

impl MeasuredTests {
    /// Each of `records` (read from `file`) with `run`'s predictions at its condition (`run`
    /// predicted at [`conditions`] of them).
    pub fn of(file: &Path, records: &[RuptureRecord], run: &PredictRun) -> MeasuredTests {
        let tests = records
            .iter()
            .map(|r| {
                let k = run.predictions.iter().position(|p| {
                    p.condition.temperature_c == r.temperature_c
                        && p.condition.stress_mpa == r.stress_mpa
                });
                let p = k.map(|k| &run.predictions[k]);
                MeasuredTest {
                    temperature_c: r.temperature_c,
                    stress_mpa: r.stress_mpa,
                    specimen: r.specimen.clone(),
                    line: r.line,
                    rupture_time_h: r.rupture_time_h,
                    model_rupture_time_h: p.map_or(f64::NAN, |p| p.rupture_time_h),
                    baseline_rupture_time_h: p.map_or_else(
                        || vec![f64::NAN; BaselineKind::ALL.len()],
                        |p| p.baseline_rupture_time_h.clone(),
                    ),
                    extrapolation: k
                        .and_then(|k| run.extrapolation.get(k).copied())
                        .unwrap_or(Extrapolation::Both),
                    outcome: p.map_or(Outcome::InvalidStart, |p| p.outcome),
                    pred95: k.and_then(|k| {
                        let iv = run.intervals.as_ref()?.get(k)?;
                        iv.get("rupture_time_h").map(|q| (q.pred_lo95, q.pred_hi95))
                    }),
                }
            })
            .collect();
        MeasuredTests {
            file: file.to_path_buf(),
            tests,
            constants: run.source,
        }
    }

    /// The tests' rupture-time errors, creepfit's and every baseline's.
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

    /// Under `--intervals`: (measured lives inside the 95 % prediction interval of a new test,
    /// tests with an interval).
    pub fn inside_pred95(&self) -> (usize, usize) {
        let with: Vec<bool> = self
            .tests
            .iter()
            .filter_map(|t| t.inside_pred95())
            .collect();
        (with.iter().filter(|b| **b).count(), with.len())
    }

    /// The printed comparison with the classical baselines (and, under `--intervals`, the
    /// lives inside the intervals of a new test).
    pub fn table(&self, run: &PredictRun) -> String {
        let mut s = crate::scores::scores_table(
            &self.scores(),
            &run.baselines,
            &format!(
                "mean |log10 error| of the rupture time over the {} tests of {}, classical baselines fitted to the configuration's rupture times:",
                self.tests.len(),
                self.file.display()
            ),
            "test of the file",
        );
        let beyond = self.beyond_limits();
        if beyond > 0 {
            s.push_str(&format!(
                "{beyond} of the {} tests lie beyond the limits of a prediction (extrapolation = beyond_limits in tests.csv): scored with the others, their lives extrapolated beyond the margins\n",
                self.tests.len()
            ));
        }
        let (inside, with) = self.inside_pred95();
        if with > 0 {
            s.push_str(&format!(
                "measured lives inside the 95 % prediction interval of a new test: {inside} of {with}\n"
            ));
        }
        s
    }

    /// How many tests lie beyond the limits of a prediction (predicted and marked).
    pub fn beyond_limits(&self) -> usize {
        self.tests
            .iter()
            .filter(|t| t.extrapolation == Extrapolation::BeyondLimits)
            .count()
    }

    /// `tests.csv`: per test its condition, measured and predicted lives, log10 errors, the
    /// file's line and (under `--intervals`) the interval of a new test.
    pub fn csv(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let mut header: Vec<String> = crate::scores::LIFE_COLUMNS
            .iter()
            .chain(&["specimen", "line", "extrapolation", "outcome", "constants"])
            .map(|s| s.to_string())
            .collect();
        header.extend(crate::scores::baseline_columns());
        let intervals = self.tests.iter().any(|t| t.pred95.is_some());
        if intervals {
            header.extend(
                [
                    "rupture_time_lo95_h",
                    "rupture_time_hi95_h",
                    "inside_pred95",
                ]
                .iter()
                .map(|s| s.to_string()),
            );
        }
        let rows = self
            .tests
            .iter()
            .map(|t| {
                let mut row = vec![
                    num(t.temperature_c),
                    num(t.stress_mpa),
                    num(t.rupture_time_h),
                    num(t.model_rupture_time_h),
                    num(t.baseline_rupture_time_h[0]),
                    num(t.model_log10_err()),
                    num(t.baseline_log10_err(0)),
                    t.specimen.clone().unwrap_or_default(),
                    t.line.to_string(),
                    t.extrapolation.as_str().to_string(),
                    t.outcome.as_str().to_string(),
                    self.constants.as_str().to_string(),
                ];
                for k in 1..BaselineKind::ALL.len() {
                    row.push(num(t.baseline_rupture_time_h[k]));
                    row.push(num(t.baseline_log10_err(k)));
                }
                if intervals {
                    let (lo, hi) = t.pred95.unwrap_or((f64::NAN, f64::NAN));
                    row.push(num(lo));
                    row.push(num(hi));
                    row.push(t.inside_pred95().map_or(String::new(), |b| b.to_string()));
                }
                row
            })
            .collect();
        (header, rows)
    }

    /// `summary.json`'s `tests`.
    pub fn json(&self, run: &PredictRun) -> Value {
        let scores = self.scores();
        let (baselines, one_to_beat) = crate::scores::scores_json(&scores, &run.baselines);
        let (m, m_n) = scores.model_score();
        let (inside, with) = self.inside_pred95();
        let mut conditions = scores.conditions.clone();
        conditions.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        conditions.dedup();
        json!({
            "what": "the measured lives of --tests FILE against creepfit's predictions (predictions.csv's rupture_time_h at each test's condition) and the classical baselines fitted to the configuration's rupture times; per test in tests.csv",
            "file": self.file.display().to_string(),
            "tests": self.tests.len(),
            "conditions": conditions.len(),
            "model_mean_abs_log10_err": jnum(m),
            "model_mean_log10_err": jnum(scores.model_bias()),
            "model_tests_predicted": m_n,
            "beyond_limits": self.beyond_limits(),
            "baselines": baselines,
            "one_to_beat": one_to_beat,
            "creepfit_vs_one_to_beat": scores.verdict(),
            "inside_pred95": (with > 0).then(|| json!({"inside": inside, "tests": with})),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(t: f64, s: f64, life: f64, line: usize) -> RuptureRecord {
        RuptureRecord {
            temperature_c: t,
            stress_mpa: s,
            rupture_time_h: life,
            rupture_strain: None,
            min_rate: None,
            specimen: None,
            line,
        }
    }

    #[test]
    fn replicates_share_one_condition_in_file_order() {
        let r = [
            record(850.0, 50.0, 100.0, 2),
            record(800.0, 70.0, 300.0, 3),
            record(850.0, 50.0, 140.0, 4),
        ];
        let c = conditions(&r);
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].temperature_c, c[0].stress_mpa), (850.0, 50.0));
        assert_eq!((c[1].temperature_c, c[1].stress_mpa), (800.0, 70.0));
    }

    #[test]
    fn errors_and_the_interval_by_hand() {
        let t = MeasuredTest {
            temperature_c: 850.0,
            stress_mpa: 50.0,
            specimen: None,
            line: 2,
            rupture_time_h: 100.0,
            model_rupture_time_h: 1000.0,
            baseline_rupture_time_h: vec![10.0, f64::NAN, 100.0, f64::NAN],
            extrapolation: Extrapolation::None,
            outcome: Outcome::Ruptured,
            pred95: Some((50.0, 99.0)),
        };
        assert!((t.model_log10_err() - 1.0).abs() < 1e-12);
        assert!((t.baseline_log10_err(0) + 1.0).abs() < 1e-12);
        assert!(t.baseline_log10_err(1).is_nan());
        assert_eq!(t.baseline_log10_err(2), 0.0);
        assert_eq!(t.inside_pred95(), Some(false));
    }
}
