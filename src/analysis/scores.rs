//! Rupture lives predicted against measured ones: each method's mean |log10 error|, the
//! classical baseline to beat, and creepfit against each baseline with a 95 % interval that
//! takes the test conditions as its units. `holdout` scores its held-out tests so, and
//! `predict --tests` the measured tests of a file.

use serde::Serialize;
use serde_json::json;

use crate::baseline::{Baseline, BaselineKind};
use crate::model::objective::mean_abs;
use crate::report::tables::jnum;

/// Whether creepfit beats the one to beat.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Its mean |log10 error| over every held-out test is below the best baseline's.
    Beats,
    /// It is not (or it did not predict every held-out test's life).
    DoesNotBeat,
    /// No baseline predicted every held-out test: nothing to compare with.
    NotComparable,
}

/// The one to beat: the index of the smallest mean |log10 error| among the baselines that
/// predicted every one of the `n_tests` held-out tests (`scores`: mean and tests predicted,
/// per baseline); `None` when none did. Ties go to the first.
pub fn one_to_beat(scores: &[(f64, usize)], n_tests: usize) -> Option<usize> {
    (0..scores.len())
        .filter(|&k| n_tests > 0 && scores[k].1 == n_tests && scores[k].0.is_finite())
        .fold(None, |best: Option<usize>, k| match best {
            Some(b) if scores[b].0 <= scores[k].0 => Some(b),
            _ => Some(k),
        })
}

/// creepfit's `model` score (mean, tests predicted) against the one to beat's.
pub fn verdict(model: (f64, usize), best: Option<(f64, usize)>, n_tests: usize) -> Verdict {
    match best {
        None => Verdict::NotComparable,
        Some((b, _)) if model.1 == n_tests && model.0 < b => Verdict::Beats,
        Some(_) => Verdict::DoesNotBeat,
    }
}

/// What the held-out tests say about creepfit against one baseline: whether the difference of
/// their mean |log10 error| is larger than the held-out lives' own scatter could make it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Comparison {
    /// The 95 % interval of the difference lies below zero: creepfit's errors are smaller.
    CreepfitBetter,
    /// It lies above zero: the baseline's are smaller.
    BaselineBetter,
    /// It contains zero (or there are too few conditions for an interval): the held-out
    /// tests do not tell the two apart.
    NotToldApart,
}

/// creepfit's mean |log10 error| minus a baseline's over the held-out tests both predicted,
/// with a 95 % interval that treats the test *conditions* (temperature, stress) as the
/// independent units: replicates at one condition share what both predictions miss there, so
/// they are not independent pieces (a cluster-robust, CR1, variance of the mean over the
/// tests, Student's t on conditions − 1 degrees of freedom). Tests of one campaign share its
/// offset too, which with one or two campaigns no interval can see: the interval is the one
/// the tests can give, not a bound on a new campaign.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PairedDifference {
    /// Mean over the tests of |creepfit's log10 error| − |the baseline's|.
    pub mean: f64,
    /// Its 95 % interval (NaN with fewer than two conditions).
    pub lo95: f64,
    pub hi95: f64,
    /// Tests both predicted, and their distinct conditions.
    pub tests: usize,
    pub conditions: usize,
    /// What the interval says.
    pub comparison: Comparison,
}

/// [`PairedDifference`] of `model` and `base` (log10 errors, one per test; NaN where a
/// method predicted no life) at `conditions` (°C, MPa per test). `None` when no test has both.
pub fn paired_difference(
    conditions: &[(f64, f64)],
    model: &[f64],
    base: &[f64],
) -> Option<PairedDifference> {
    let both: Vec<((f64, f64), f64)> = conditions
        .iter()
        .zip(model.iter().zip(base))
        .filter(|(_, (m, b))| m.is_finite() && b.is_finite())
        .map(|(c, (m, b))| (*c, m.abs() - b.abs()))
        .collect();
    let n = both.len();
    if n == 0 {
        return None;
    }
    let mean = both.iter().map(|(_, d)| d).sum::<f64>() / n as f64;
    // Per condition, the sum of the deviations from the mean (CR1 cluster scores).
    let mut groups: Vec<((f64, f64), f64)> = Vec::new();
    for (c, d) in &both {
        match groups.iter_mut().find(|(g, _)| g == c) {
            Some((_, s)) => *s += d - mean,
            None => groups.push((*c, d - mean)),
        }
    }
    let g = groups.len();
    let (lo95, hi95) = if g < 2 {
        (f64::NAN, f64::NAN)
    } else {
        let var = groups.iter().map(|(_, s)| s * s).sum::<f64>() / (n as f64).powi(2) * g as f64
            / (g - 1) as f64;
        let t = t_quantile_975(g - 1);
        let half = t * var.sqrt();
        (mean - half, mean + half)
    };
    let comparison = if hi95 < 0.0 {
        Comparison::CreepfitBetter
    } else if lo95 > 0.0 {
        Comparison::BaselineBetter
    } else {
        Comparison::NotToldApart
    };
    Some(PairedDifference {
        mean,
        lo95,
        hi95,
        tests: n,
        conditions: g,
        comparison,
    })
}

/// The 97.5 % point of Student's t on `df` degrees of freedom.
fn t_quantile_975(df: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, df as f64)
        .map(|t| t.inverse_cdf(0.975))
        .unwrap_or(f64::NAN)
}

/// Rupture-time errors log10(t_predicted / t_measured) of creepfit and of every classical
/// baseline over a set of tests with measured lives (NaN where a method predicted none), and
/// what they say: each one's mean |log10 error|, the one to beat, creepfit against each. The
/// held-out tests of `holdout` and the measured tests of `predict --tests` are scored so.
#[derive(Debug, Clone, PartialEq)]
pub struct LifeScores {
    /// Per test: its condition (°C, MPa).
    pub conditions: Vec<(f64, f64)>,
    /// Per test: creepfit's log10 error.
    pub model: Vec<f64>,
    /// Per baseline ([`BaselineKind::ALL`]'s order), per test: its log10 error.
    pub baselines: Vec<Vec<f64>>,
}

impl LifeScores {
    /// The scores of tests given as (condition (°C, MPa), measured life, creepfit's life,
    /// every baseline's life), lives in h (NaN: not predicted).
    pub fn of<'a>(tests: impl Iterator<Item = ((f64, f64), f64, f64, &'a [f64])>) -> LifeScores {
        let mut s = LifeScores {
            conditions: Vec::new(),
            model: Vec::new(),
            baselines: Vec::new(),
        };
        for (c, measured, model, baselines) in tests {
            s.conditions.push(c);
            s.model.push((model / measured).log10());
            s.baselines.resize(baselines.len(), Vec::new());
            for (column, b) in s.baselines.iter_mut().zip(baselines) {
                column.push((b / measured).log10());
            }
        }
        if s.baselines.is_empty() {
            s.baselines = vec![Vec::new(); BaselineKind::ALL.len()];
        }
        s
    }
    /// Number of tests.
    pub fn len(&self) -> usize {
        self.model.len()
    }
    /// Whether there are no tests.
    pub fn is_empty(&self) -> bool {
        self.model.is_empty()
    }
    /// creepfit's (mean |log10 error|, tests it predicted a life for).
    pub fn model_score(&self) -> (f64, usize) {
        score(&self.model)
    }
    /// creepfit's mean signed log10 error over the tests it predicted: the level its lives
    /// share on these tests (+: too long), e.g. a campaign's offset (NaN: none predicted).
    pub fn model_bias(&self) -> f64 {
        bias(&self.model)
    }
    /// Baseline `k`'s mean signed log10 error.
    pub fn baseline_bias(&self, k: usize) -> f64 {
        bias(&self.baselines[k])
    }
    /// Baseline `k`'s (mean |log10 error|, tests it predicted).
    pub fn baseline_score(&self, k: usize) -> (f64, usize) {
        score(&self.baselines[k])
    }
    /// The one to beat ([`one_to_beat`]).
    pub fn one_to_beat(&self) -> Option<usize> {
        let scores: Vec<(f64, usize)> = (0..self.baselines.len())
            .map(|k| self.baseline_score(k))
            .collect();
        one_to_beat(&scores, self.len())
    }
    /// creepfit against baseline `k` over the tests both predicted ([`paired_difference`]).
    pub fn versus(&self, k: usize) -> Option<PairedDifference> {
        paired_difference(&self.conditions, &self.model, &self.baselines[k])
    }
    /// Whether creepfit beats the one to beat ([`verdict`]).
    pub fn verdict(&self) -> Verdict {
        verdict(
            self.model_score(),
            self.one_to_beat().map(|k| self.baseline_score(k)),
            self.len(),
        )
    }
}

/// (mean |e|, finite entries) of log10 errors `e`.
fn score(e: &[f64]) -> (f64, usize) {
    (mean_abs(e), e.iter().filter(|v| v.is_finite()).count())
}

/// Mean of the finite entries of `e` (NaN: none).
fn bias(e: &[f64]) -> f64 {
    let f: Vec<f64> = e.iter().copied().filter(|v| v.is_finite()).collect();
    if f.is_empty() {
        f64::NAN
    } else {
        f.iter().sum::<f64>() / f.len() as f64
    }
}

/// `summary.json`'s `baselines` (each baseline's own entry with, where fitted, its
/// `mean_abs_log10_err`, `mean_log10_err` (signed), `tests_predicted` and
/// `creepfit_difference`) and `one_to_beat` of
/// `scores` (`holdout`'s held-out tests, `predict --tests`'s measured ones).
pub fn scores_json(
    scores: &LifeScores,
    baselines: &[Baseline],
) -> (Vec<serde_json::Value>, Option<serde_json::Value>) {
    let entries = baselines
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let (v, c) = scores.baseline_score(k);
            let mut j = b.to_json();
            if b.fit.is_ok() {
                j["mean_abs_log10_err"] = jnum(v);
                j["mean_log10_err"] = jnum(scores.baseline_bias(k));
                j["tests_predicted"] = json!(c);
                j["creepfit_difference"] = difference_json(scores.versus(k));
            }
            j
        })
        .collect();
    let one_to_beat = scores.one_to_beat().map(|k| {
        json!({
            "kind": baselines[k].kind,
            "name": baselines[k].kind.name(),
            "mean_abs_log10_err": jnum(scores.baseline_score(k).0),
            "creepfit_difference": difference_json(scores.versus(k)),
        })
    });
    (entries, one_to_beat)
}

/// A [`PairedDifference`] as JSON (its NaN ends as null), null without one.
pub fn difference_json(d: Option<PairedDifference>) -> serde_json::Value {
    d.map_or(serde_json::Value::Null, |d| {
        json!({
            "mean": jnum(d.mean),
            "lo95": jnum(d.lo95),
            "hi95": jnum(d.hi95),
            "tests": d.tests,
            "conditions": d.conditions,
            "comparison": d.comparison,
        })
    })
}

/// The printed comparison of `scores`: `header`, then creepfit's and each of `baselines`'
/// mean |log10 error| (with its constants or why it is absent), the one to beat and creepfit
/// against it. `tests` names the tests ("held-out test") where none predicted every one.
pub fn scores_table(
    scores: &LifeScores,
    baselines: &[Baseline],
    header: &str,
    tests: &str,
) -> String {
    let n = scores.len();
    let (m, m_n) = scores.model_score();
    let of = |c: usize| {
        if c < n {
            format!("  (a life for {c} of {n} tests)")
        } else {
            String::new()
        }
    };
    let mut s = format!("{header}\n  {:<16} {:>6.3}{}\n", "creepfit", m, of(m_n));
    for (k, b) in baselines.iter().enumerate() {
        match &b.fit {
            Ok(_) => {
                let (v, c) = scores.baseline_score(k);
                s.push_str(&format!(
                    "  {:<16} {:>6.3}{}  [{}]\n",
                    b.kind.name(),
                    v,
                    of(c),
                    b.describe()
                ));
            }
            Err(e) => s.push_str(&format!("  {:<16} absent: {e}\n", b.kind.name())),
        }
    }
    // The level each method's lives share on these tests: what a campaign's offset looks like.
    let mut levels = vec![format!("creepfit {:+.3}", scores.model_bias())];
    for (k, b) in baselines.iter().enumerate() {
        if b.fit.is_ok() {
            levels.push(format!("{} {:+.3}", b.kind.name(), scores.baseline_bias(k)));
        }
    }
    s.push_str(&format!(
        "mean log10(predicted/measured), the level the lives share (+: predicted too long): {}\n",
        levels.join(", ")
    ));
    match scores.one_to_beat() {
        Some(k) => {
            let v = scores.baseline_score(k).0;
            s.push_str(&format!(
                "the one to beat: {} {:.3}; creepfit {:.3} {}\n",
                baselines[k].kind.name(),
                v,
                m,
                match scores.verdict() {
                    Verdict::Beats => "beats it",
                    _ => "does NOT beat it",
                }
            ));
            if let Some(d) = scores.versus(k) {
                s.push_str(&format!(
                    "  {}\n",
                    versus_text(baselines[k].kind.name(), &d)
                ));
            }
        }
        None => s.push_str(&format!(
            "the one to beat: none (no baseline predicted every {tests})\n"
        )),
    }
    s
}

/// One line on creepfit against the baseline `name`: the difference of the mean |log10
/// error|, its 95 % interval and what it says.
pub fn versus_text(name: &str, d: &PairedDifference) -> String {
    let interval = if d.lo95.is_finite() {
        format!("95 % {:+.3} to {:+.3}", d.lo95, d.hi95)
    } else {
        "no interval".to_string()
    };
    format!(
        "creepfit − {name}: {:+.3} in mean |log10 error| ({interval}, over {} tests at {} conditions): {}",
        d.mean,
        d.tests,
        d.conditions,
        match d.comparison {
            Comparison::CreepfitBetter => "creepfit's errors are smaller",
            Comparison::BaselineBetter => "the baseline's errors are smaller",
            Comparison::NotToldApart =>
                "the tests do not tell the two apart (the interval contains zero)",
        }
    )
}

/// The first columns of `holdout.csv` and of `predict --tests`'s `tests.csv`: the condition,
/// the measured life, creepfit's and Larson–Miller's, and their log10 errors.
pub const LIFE_COLUMNS: [&str; 7] = [
    "temperature_C",
    "stress_MPa",
    "rupture_time_h",
    "model_rupture_time_h",
    "lmp_rupture_time_h",
    "model_log10_err",
    "lmp_log10_err",
];

/// `holdout.csv`'s baseline columns, after the contract columns (and `specimen`): the
/// rupture time and log10 error of each baseline besides Larson–Miller (whose columns come
/// earlier), in [`BaselineKind::ALL`]'s order: `osd_rupture_time_h,osd_log10_err,mh_…,wilshire_…`.
pub fn baseline_columns() -> Vec<String> {
    BaselineKind::ALL[1..]
        .iter()
        .flat_map(|k| {
            [
                format!("{}_rupture_time_h", k.key()),
                format!("{}_log10_err", k.key()),
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paired comparison's error rates by simulation (seed 851001, 4,000 sets per
    /// design). Held-out log10 errors e = (what the method misses at the condition) − (the
    /// specimen's own scatter ε): the two methods' misses at a condition drawn from one
    /// distribution (so neither is better on average) and ε shared by both, as the measured
    /// life is. The interval must cover zero in 93–97 % of sets: with every test its own
    /// condition, with replicate pairs, and with three replicates at five conditions, where an
    /// interval that took every test as independent covers far less (also asserted, so that
    /// the grouping is what holds the rate). With creepfit's misses smaller, the comparison
    /// must never say the baseline is better more often than the 2.5 % of one tail.
    #[test]
    fn paired_difference_holds_its_error_rates() {
        use rand::{Rng, SeedableRng};
        use rand_distr::StandardNormal;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(851001);
        let sets = 4000;
        // (replicates per condition, miss sd creepfit, miss sd baseline, specimen sd)
        for (reps, sm, sb, se) in [
            (vec![1; 10], 0.15, 0.15, 0.10),
            (vec![1, 2, 1, 2, 1, 2, 1, 2, 1, 2], 0.15, 0.15, 0.10),
            (vec![3; 5], 0.20, 0.20, 0.05),
            (vec![1, 2, 1, 2, 1, 2, 1], 0.05, 0.25, 0.15),
        ] {
            let (mut covered, mut naive_covered, mut better, mut worse) = (0, 0, 0, 0);
            for _ in 0..sets {
                let (mut cond, mut m, mut b) = (vec![], vec![], vec![]);
                for (c, &r) in reps.iter().enumerate() {
                    let am = sm * rng.sample::<f64, _>(StandardNormal);
                    let ab = sb * rng.sample::<f64, _>(StandardNormal);
                    for _ in 0..r {
                        let eps = se * rng.sample::<f64, _>(StandardNormal);
                        cond.push((850.0, 30.0 + c as f64));
                        m.push(am - eps);
                        b.push(ab - eps);
                    }
                }
                let d = paired_difference(&cond, &m, &b).unwrap();
                assert_eq!(d.conditions, reps.len());
                covered += usize::from(d.lo95 <= 0.0 && 0.0 <= d.hi95);
                better += usize::from(d.comparison == Comparison::CreepfitBetter);
                worse += usize::from(d.comparison == Comparison::BaselineBetter);
                // Every test its own condition: the interval that ignores the replicates.
                let own: Vec<(f64, f64)> = (0..cond.len()).map(|i| (850.0, i as f64)).collect();
                let n = paired_difference(&own, &m, &b).unwrap();
                naive_covered += usize::from(n.lo95 <= 0.0 && 0.0 <= n.hi95);
            }
            let (cov, naive) = (
                covered as f64 / sets as f64,
                naive_covered as f64 / sets as f64,
            );
            let (better, worse) = (better as f64 / sets as f64, worse as f64 / sets as f64);
            eprintln!("{reps:?} {sm} {sb} {se}: coverage {cov}, independent {naive}, better {better}, worse {worse}");
            if sm == sb {
                assert!((0.93..=0.97).contains(&cov), "{reps:?}: coverage {cov}");
                if reps.iter().all(|&r| r == 3) {
                    assert!(naive < 0.90, "{reps:?}: tests as independent {naive}");
                }
            } else {
                // One tail's 2.5 %; and the comparison responds: creepfit called better
                // far more often than the 2.5 % a null allows in that tail.
                assert!(
                    worse <= 0.025,
                    "{reps:?}: baseline called better in {worse}"
                );
                assert!(better > 0.1, "{reps:?}: creepfit called better in {better}");
            }
        }
    }

    /// The paired difference by hand: two conditions, one with a replicate pair.
    #[test]
    fn paired_difference_by_hand() {
        let cond = [(850.0, 40.0), (850.0, 40.0), (850.0, 50.0), (900.0, 30.0)];
        let m = [0.3, -0.1, 0.2, f64::NAN];
        let b = [0.1, 0.1, -0.4, 0.2];
        let d = paired_difference(&cond, &m, &b).unwrap();
        // d = 0.2, 0.0, −0.2 over two conditions; the NaN test is left out.
        assert_eq!((d.tests, d.conditions), (3, 2));
        assert!(d.mean.abs() < 1e-15);
        // Cluster scores 0.2 + 0.0 and −0.2: var = (0.04 + 0.04)/9 · 2/1, t(1) = 12.706.
        let half = 12.706_204_736 * (0.08f64 / 9.0 * 2.0).sqrt();
        assert!(
            (d.hi95 - half).abs() < 1e-6 && (d.lo95 + half).abs() < 1e-6,
            "{d:?}"
        );
        assert_eq!(d.comparison, Comparison::NotToldApart);
        assert!(paired_difference(&cond[3..], &m[3..], &b[3..]).is_none());
        let one = paired_difference(&cond[..2], &m[..2], &b[..2]).unwrap();
        assert!(one.lo95.is_nan() && one.comparison == Comparison::NotToldApart);
    }

    #[test]
    fn the_level_the_lives_share_by_hand() {
        let s = LifeScores::of(
            [
                ((850.0, 50.0), 100.0, 200.0, &[50.0, f64::NAN][..]),
                ((850.0, 60.0), 100.0, 50.0, &[25.0, f64::NAN][..]),
                ((900.0, 30.0), 100.0, f64::NAN, &[100.0, f64::NAN][..]),
            ]
            .into_iter(),
        );
        // log10 2 and log10 0.5 cancel; the third test has no creepfit life.
        assert!(s.model_bias().abs() < 1e-15);
        assert!((s.model_score().0 - 2f64.log10()).abs() < 1e-15);
        let want = (0.5f64.log10() + 0.25f64.log10()) / 3.0;
        assert!((s.baseline_bias(0) - want).abs() < 1e-15);
        assert!(s.baseline_bias(1).is_nan());
    }

    #[test]
    fn one_to_beat_and_verdict_tables() {
        let nan = f64::NAN;
        // (scores per baseline (mean, tests predicted), tests) → the one to beat.
        for (scores, n, want) in [
            (vec![(0.24, 13), (0.22, 13), (0.25, 13)], 13, Some(1)),
            (vec![(0.24, 13), (0.10, 12), (0.25, 13)], 13, Some(0)),
            (vec![(0.24, 13), (0.24, 13)], 13, Some(0)),
            (vec![(nan, 0), (0.3, 13)], 13, Some(1)),
            (vec![(nan, 0), (0.1, 5)], 13, None),
            (vec![], 13, None),
            (vec![(nan, 0)], 0, None),
        ] {
            assert_eq!(one_to_beat(&scores, n), want, "{scores:?}");
        }
        use Verdict::*;
        for (model, best, n, want) in [
            ((0.20, 13), Some((0.22, 13)), 13, Beats),
            ((0.22, 13), Some((0.22, 13)), 13, DoesNotBeat),
            ((0.25, 13), Some((0.22, 13)), 13, DoesNotBeat),
            // A life missing for one test: does not beat a baseline that predicted all.
            ((0.10, 12), Some((0.22, 13)), 13, DoesNotBeat),
            ((nan, 0), Some((0.22, 13)), 13, DoesNotBeat),
            ((0.10, 13), None, 13, NotComparable),
        ] {
            assert_eq!(verdict(model, best, n), want, "{model:?} {best:?}");
        }
        assert_eq!(serde_json::to_value(DoesNotBeat).unwrap(), "does_not_beat");
    }
}
