//! What `diagnose` reports while it runs and what it resumes from: an [`Observer`](crate::progress::Observer) told of
//! every phase and step, and an optional [`Journal`](crate::journal::Journal) of the bootstrap replicates'
//! statistics. Replicate b of a bootstrap is a pure function of the seed, the stream and b
//! ([`super::bootstrap::replicate_rng`]) and of the fitted models it is drawn under and
//! refitted from: the journal keys it by (stream, hash of those fits, b), so a rerun into the
//! same folder reads the replicates that are done and computes only the others, and the
//! result is the uninterrupted run's bit for bit.

use std::sync::Mutex;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::bootstrap::{Depth, Sampled};
use crate::errmodel::{Ar1, ErrorModel, Residuals};
use crate::error::{Error, Result};
use crate::journal::{debug_hash, exact, Exact};
use crate::likelihood::{EffectKind, MlFit, SpecimenFit};
use crate::lsq::Termination;
use crate::model::objective::{CurvePrediction, Evaluation};

pub use crate::progress::Hooks;

/// The run identity of a diagnosis of `cfg` (bound to its data) kept in its journal: the
/// configuration's ([`crate::config::identity`]: every setting that changes a fit, the
/// data's hash, the crate version), the command and the `[diagnose]` settings used.
pub fn identity(cfg: &crate::config::RunConfig) -> serde_json::Value {
    let mut id = crate::config::identity(cfg);
    id["command"] = "diagnose".into();
    id["diagnose"] = serde_json::to_value(&cfg.diagnose).expect("settings serialise");
    id
}

/// The key of a bootstrap's replicates: the hash of what they are drawn under and refitted
/// from (the fits on the data and their basins).
pub fn model_key<T: std::fmt::Debug + ?Sized>(fitted: &T) -> String {
    debug_hash(fitted)
}

impl Hooks<'_> {
    /// [`super::bootstrap::sequential`] of replicates `one(b, active)` drawn from random
    /// stream `stream` under the fits whose [`model_key`] is `key`: each replicate read from
    /// the journal when it is there, else computed and journaled (flushed) as it finishes;
    /// the phase `name` counts them. `Err` when the observer asks to stop (the replicates
    /// finished so far are journaled) or a journal write fails.
    #[allow(clippy::too_many_arguments)]
    pub fn sequential<F>(
        &self,
        name: &str,
        stream: u64,
        key: &str,
        observed: &[f64],
        droppable: &[bool],
        depth: Depth,
        one: F,
    ) -> Result<Sampled>
    where
        F: Fn(usize, &[bool]) -> Vec<f64> + Sync,
    {
        let prefix = format!("rep/{stream}/{key}/");
        // A phase over replicates `range`: those an earlier run journaled count as resumed.
        let phase = |label: &str, range: std::ops::Range<usize>| {
            self.phase(label, range.len());
            if let Some(j) = self.journal {
                let found = range
                    .filter(|b| j.contains(&format!("{prefix}{b}")))
                    .count();
                self.observer.resumed(found as u64);
            }
        };
        phase(name, 0..depth.first());
        let failure: Mutex<Option<Error>> = Mutex::new(None);
        let stop = || {
            self.observer.cancelled() || failure.lock().unwrap_or_else(|e| e.into_inner()).is_some()
        };
        let extending = |n: usize| {
            phase(
                &format!("{name}, tests close to significance"),
                depth.first()..depth.first() + n,
            )
        };
        let journaled = |b: usize, active: &[bool]| {
            let k = format!("{prefix}{b}");
            if let Some(r) = self.journal.and_then(|j| j.get::<Exact>(&k)) {
                return r.0;
            }
            if stop() {
                // Not computed: the run stops and this is never used.
                return vec![f64::NAN; observed.len() + 1];
            }
            let r = one(b, active);
            if let Some(j) = self.journal {
                if let Err(e) = j.put(&k, &Exact(r.clone())) {
                    failure
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .get_or_insert(e);
                }
            }
            self.step();
            r
        };
        let out = super::bootstrap::sequential_in(observed, droppable, depth, journaled, extending);
        if let Some(e) = failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e);
        }
        self.check(name)?;
        Ok(out)
    }
}

/// What the fits on the data keep of one model (a journal record): its best fit (`None`: no
/// start converged), the number of failed starts and the distinct optima the replicates
/// start from.
#[derive(Debug, Clone)]
pub struct ModelFits {
    /// The best fit on the data, scatter intervals included.
    pub best: Option<MlFit>,
    /// Starts whose fit failed.
    pub failed: usize,
    /// Distinct optima (constants) found on the data.
    pub basins: Vec<Vec<f64>>,
    /// Index of the fresh start whose fit was best (the null replicates repeat it).
    pub recipe: Option<usize>,
}

/// The journal key of the fits on the data of model `i` (named `name`) from `starts`.
pub fn fits_key(i: usize, name: &str, starts: &[Vec<f64>]) -> String {
    format!("fits/{i}/{name}/{}", debug_hash(starts))
}

impl Hooks<'_> {
    /// The fits on the data journaled under `key` ([`fits_key`]) by an earlier run, if any
    /// (counted as a resumed step).
    pub fn fits_done(&self, key: &str) -> Option<ModelFits> {
        let r = self.journal.and_then(|j| j.get::<FitsRecord>(key))?;
        self.observer.resumed(1);
        Some(r.into())
    }

    /// The leave-one-stress-out check of model `i` (named `name`) fitted to `params` (`None`:
    /// not fitted) from `starts`: read from the journal when an earlier run finished it, else
    /// `compute()`d and journaled (flushed). `Err` when the observer asks to stop first.
    pub fn loo(
        &self,
        i: usize,
        name: &str,
        params: Option<&Vec<f64>>,
        starts: &[Vec<f64>],
        compute: impl FnOnce() -> super::Loo,
    ) -> Result<super::Loo> {
        let key = format!("loo/{i}/{name}/{}", debug_hash(&(params, starts)));
        if let Some(r) = self.journal.and_then(|j| j.get::<LooRecord>(&key)) {
            self.observer.resumed(1);
            return Ok(super::Loo {
                rmse: r.rmse,
                lifetime_err_pct: r.lifetime_err_pct,
                failed_folds: r.failed_folds.0,
            });
        }
        self.check("leave-one-stress-out")?;
        let loo = compute();
        if let Some(j) = self.journal {
            j.put(
                &key,
                &LooRecord {
                    rmse: loo.rmse,
                    lifetime_err_pct: loo.lifetime_err_pct,
                    failed_folds: Exact(loo.failed_folds.clone()),
                },
            )?;
        }
        self.step();
        Ok(loo)
    }

    /// The fits on the data `f` are done: journaled (flushed) under `key`, a step.
    pub fn fits_finished(&self, key: &str, f: &ModelFits) -> Result<()> {
        if let Some(j) = self.journal {
            j.put(key, &FitsRecord::from(f))?;
        }
        self.step();
        Ok(())
    }
}

/// A [`super::Loo`] as a journal record, numbers exact.
#[derive(Serialize, Deserialize)]
struct LooRecord {
    #[serde(with = "exact")]
    rmse: f64,
    #[serde(with = "exact")]
    lifetime_err_pct: f64,
    failed_folds: Exact,
}

/// A [`ModelFits`] as a journal record: every field, every number exact
/// ([`crate::journal::exact`]), so that a fit read back is the fit that was computed.
#[derive(Serialize, Deserialize)]
struct FitsRecord {
    best: Option<MlFitRecord>,
    failed: usize,
    basins: Vec<Exact>,
    /// Absent in journals written before it existed.
    #[serde(default)]
    recipe: Option<usize>,
}

#[derive(Serialize, Deserialize)]
struct MlFitRecord {
    params: Exact,
    /// Per curve: the AR(1) [σ, φ].
    strain_noise: Vec<Exact>,
    #[serde(with = "exact")]
    lifetime_sd: f64,
    #[serde(with = "exact")]
    neg2ll: f64,
    residuals: Option<ResidualsRecord>,
    eval: Option<EvaluationRecord>,
    specimen: Option<SpecimenRecord>,
    termination: Termination,
    iterations: usize,
    evaluations: usize,
    failure: Option<String>,
}

#[derive(Serialize, Deserialize)]
struct ResidualsRecord {
    strain: Vec<Exact>,
    /// Exact numbers, `null` for none.
    lifetime: Vec<Value>,
}

#[derive(Serialize, Deserialize)]
struct EvaluationRecord {
    #[serde(with = "exact")]
    objective: f64,
    #[serde(with = "exact")]
    norm_residual: f64,
    curves: Vec<CurveRecord>,
}

#[derive(Serialize, Deserialize)]
struct CurveRecord {
    outcome: crate::ode::Outcome,
    #[serde(with = "exact")]
    rupture_time_h: f64,
    #[serde(with = "exact")]
    rupture_strain: f64,
    #[serde(with = "exact")]
    min_rate: f64,
    strain: Exact,
}

#[derive(Serialize, Deserialize)]
struct SpecimenRecord {
    kinds: Vec<EffectKind>,
    scatter: Exact,
    scatter_lo95: Exact,
    scatter_hi95: Exact,
    /// Absent from journals written before it existed (their intervals the χ²₁ rule's):
    /// NaN, as before the intervals are computed.
    #[serde(default)]
    scatter_dof: Option<Exact>,
    effects: Vec<Exact>,
    effects_sd: Vec<Exact>,
    #[serde(with = "exact")]
    neg2ll_effects: f64,
    /// Absent from journals written before it existed: the linear mixed model's, as then.
    #[serde(default)]
    scatter_method: crate::specimen::ScatterMethod,
    dropped: Vec<EffectKind>,
}

fn exacts(v: &[Vec<f64>]) -> Vec<Exact> {
    v.iter().map(|x| Exact(x.clone())).collect()
}

fn plain(v: Vec<Exact>) -> Vec<Vec<f64>> {
    v.into_iter().map(|x| x.0).collect()
}

impl From<&ModelFits> for FitsRecord {
    fn from(m: &ModelFits) -> Self {
        FitsRecord {
            best: m.best.as_ref().map(|f| MlFitRecord {
                params: Exact(f.params.clone()),
                strain_noise: f
                    .noise
                    .strain
                    .iter()
                    .map(|a| Exact(vec![a.sigma, a.phi]))
                    .collect(),
                lifetime_sd: f.noise.lifetime_sd,
                neg2ll: f.neg2ll,
                residuals: f.residuals.as_ref().map(|r| ResidualsRecord {
                    strain: exacts(&r.strain),
                    lifetime: r
                        .lifetime
                        .iter()
                        .map(|x| x.map_or(Value::Null, exact::to_json))
                        .collect(),
                }),
                eval: f.eval.as_ref().map(|e| EvaluationRecord {
                    objective: e.objective,
                    norm_residual: e.norm_residual,
                    curves: e
                        .curves
                        .iter()
                        .map(|c| CurveRecord {
                            outcome: c.outcome,
                            rupture_time_h: c.rupture_time_h,
                            rupture_strain: c.rupture_strain,
                            min_rate: c.min_rate,
                            strain: Exact(c.strain.clone()),
                        })
                        .collect(),
                }),
                specimen: f.specimen.as_ref().map(|s| SpecimenRecord {
                    kinds: s.kinds.clone(),
                    scatter: Exact(s.scatter.clone()),
                    scatter_lo95: Exact(s.scatter_lo95.clone()),
                    scatter_hi95: Exact(s.scatter_hi95.clone()),
                    scatter_dof: Some(Exact(s.scatter_dof.clone())),
                    effects: exacts(&s.effects),
                    effects_sd: exacts(&s.effects_sd),
                    neg2ll_effects: s.neg2ll_effects,
                    scatter_method: s.scatter_method,
                    dropped: s.dropped.clone(),
                }),
                termination: f.termination,
                iterations: f.iterations,
                evaluations: f.evaluations,
                failure: f.failure.clone(),
            }),
            failed: m.failed,
            basins: exacts(&m.basins),
            recipe: m.recipe,
        }
    }
}

impl From<FitsRecord> for ModelFits {
    fn from(r: FitsRecord) -> Self {
        ModelFits {
            best: r.best.map(|f| MlFit {
                params: f.params.0,
                noise: ErrorModel {
                    strain: f
                        .strain_noise
                        .into_iter()
                        .map(|a| Ar1 {
                            sigma: a.0.first().copied().unwrap_or(f64::NAN),
                            phi: a.0.get(1).copied().unwrap_or(f64::NAN),
                        })
                        .collect(),
                    lifetime_sd: f.lifetime_sd,
                },
                neg2ll: f.neg2ll,
                residuals: f.residuals.map(|r| Residuals {
                    strain: plain(r.strain),
                    lifetime: r.lifetime.iter().map(exact::from_json).collect(),
                }),
                eval: f.eval.map(|e| Evaluation {
                    objective: e.objective,
                    norm_residual: e.norm_residual,
                    curves: e
                        .curves
                        .into_iter()
                        .map(|c| CurvePrediction {
                            outcome: c.outcome,
                            rupture_time_h: c.rupture_time_h,
                            rupture_strain: c.rupture_strain,
                            min_rate: c.min_rate,
                            strain: c.strain.0,
                        })
                        .collect(),
                }),
                specimen: f.specimen.map(|s| SpecimenFit {
                    kinds: s.kinds,
                    scatter: s.scatter.0,
                    scatter_lo95: s.scatter_lo95.0,
                    scatter_dof: s
                        .scatter_dof
                        .map_or_else(|| vec![f64::NAN; s.scatter_hi95.0.len()], |d| d.0),
                    scatter_hi95: s.scatter_hi95.0,
                    effects: plain(s.effects),
                    effects_sd: plain(s.effects_sd),
                    neg2ll_effects: s.neg2ll_effects,
                    scatter_method: s.scatter_method,
                    dropped: s.dropped,
                }),
                termination: f.termination,
                iterations: f.iterations,
                evaluations: f.evaluations,
                failure: f.failure,
            }),
            failed: r.failed,
            basins: plain(r.basins),
            recipe: r.recipe,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::journal::Journal;
    use crate::progress::{StopWhen, SILENT};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Replicate statistics of a toy bootstrap: a pure function of b, NaN now and then.
    fn toy(b: usize, _: &[bool]) -> Vec<f64> {
        let x = ((b * 7919) % 113) as f64 / 113.0;
        vec![x, if b % 9 == 4 { f64::NAN } else { 1.0 - x }, 0.0]
    }

    #[test]
    fn an_interrupted_bootstrap_resumes_to_the_same_replicates() {
        let d = tempfile::TempDir::new().unwrap();
        let id = serde_json::json!({"command": "test"});
        let observed = [0.99, 0.995];
        let plain = super::super::bootstrap::sequential(&observed, &[false; 2], 60, toy);
        // Stopped after 15 new replicates (some more finish in flight and are kept).
        let kept = {
            let j = Journal::open(d.path(), &id).unwrap();
            let stop = StopWhen::new(&SILENT, || j.written() >= 15);
            let hooks = Hooks {
                observer: &stop,
                journal: Some(&j),
            };
            let e = hooks
                .sequential("toy", 1, "k", &observed, &[false; 2], Depth::fixed(60), toy)
                .unwrap_err();
            assert!(matches!(e, Error::Interrupted(_)), "{e}");
            j.written() as usize
        };
        assert!((15..60).contains(&kept), "{kept}");
        // The rerun computes only the missing replicates and gives the same result.
        let j = Journal::open(d.path(), &id).unwrap();
        assert_eq!(j.found(), kept);
        let calls = AtomicUsize::new(0);
        let hooks = Hooks {
            observer: &SILENT,
            journal: Some(&j),
        };
        let resumed = hooks
            .sequential(
                "toy",
                1,
                "k",
                &observed,
                &[false; 2],
                Depth::fixed(60),
                |b, a| {
                    calls.fetch_add(1, Ordering::SeqCst);
                    toy(b, a)
                },
            )
            .unwrap();
        assert_eq!(calls.load(Ordering::SeqCst), 60 - kept);
        let bits = |r: &Sampled| {
            (
                r.reps
                    .iter()
                    .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
                r.computed.clone(),
                r.stopped_early,
            )
        };
        assert_eq!(bits(&resumed), bits(&plain));
        // Replicates under another fit (another key) are not reused.
        let calls = AtomicUsize::new(0);
        hooks
            .sequential(
                "toy",
                1,
                "other",
                &observed,
                &[false; 2],
                Depth::fixed(60),
                |b, a| {
                    calls.fetch_add(1, Ordering::SeqCst);
                    toy(b, a)
                },
            )
            .unwrap();
        assert_eq!(calls.load(Ordering::SeqCst), 60);
    }

    #[test]
    fn fits_on_the_data_come_back_from_the_journal_bit_for_bit() {
        let curve = CurvePrediction {
            outcome: crate::ode::Outcome::Ruptured,
            rupture_time_h: 1234.5678901234567,
            rupture_strain: f64::INFINITY,
            min_rate: 1e-7 / 3.0,
            strain: vec![0.0, 0.1 / 7.0, f64::NAN],
        };
        let fit = MlFit {
            params: vec![1.0 / 3.0, -2e-300, f64::MAX],
            noise: ErrorModel {
                strain: vec![Ar1 {
                    sigma: 1e-4 / 3.0,
                    phi: 0.987654321,
                }],
                lifetime_sd: f64::NAN,
            },
            neg2ll: -8967.612345,
            residuals: Some(Residuals {
                strain: vec![vec![1e-5, -f64::INFINITY], vec![]],
                lifetime: vec![Some(0.25), None, Some(f64::NAN)],
            }),
            eval: Some(Evaluation {
                objective: 0.1 + 0.2,
                norm_residual: f64::NEG_INFINITY,
                curves: vec![curve],
            }),
            specimen: Some(SpecimenFit {
                kinds: vec![EffectKind::Rate],
                scatter: vec![0.23],
                scatter_lo95: vec![0.0],
                scatter_hi95: vec![f64::NAN],
                scatter_dof: vec![3.5],
                effects: vec![vec![-0.1, 0.2 / 3.0]],
                effects_sd: vec![vec![0.05, 0.07]],
                neg2ll_effects: 12.5,
                scatter_method: crate::specimen::ScatterMethod::LaplaceAtModes,
                dropped: vec![EffectKind::Ductility],
            }),
            termination: Termination::ConvergedStep,
            iterations: 17,
            evaluations: 40,
            failure: Some("x".into()),
        };
        let fits = ModelFits {
            best: Some(fit),
            failed: 2,
            basins: vec![vec![0.5, 1.0 / 7.0]],
            recipe: Some(3),
        };
        let d = tempfile::TempDir::new().unwrap();
        let id = serde_json::json!({"command": "test"});
        let key = fits_key(0, "base", &[vec![1.0]]);
        {
            let j = Journal::open(d.path(), &id).unwrap();
            let h = Hooks {
                observer: &SILENT,
                journal: Some(&j),
            };
            assert!(h.fits_done(&key).is_none());
            h.fits_finished(&key, &fits).unwrap();
        }
        let j = Journal::open(d.path(), &id).unwrap();
        let h = Hooks {
            observer: &SILENT,
            journal: Some(&j),
        };
        let back = h.fits_done(&key).expect("journaled");
        // Debug writes every number in shortest round-trip form: equal text, equal bits.
        assert_eq!(format!("{back:?}"), format!("{fits:?}"));
        assert!(h.fits_done(&fits_key(0, "base", &[vec![2.0]])).is_none());
        let none = ModelFits {
            best: None,
            failed: 5,
            basins: vec![],
            recipe: None,
        };
        h.fits_finished("fits/1/x/0", &none).unwrap();
        assert_eq!(
            format!("{:?}", h.fits_done("fits/1/x/0").unwrap()),
            format!("{none:?}")
        );
        // A record written before the intervals' degrees of freedom existed reads back with
        // them unknown (NaN), everything else as written.
        let mut v = serde_json::to_value(FitsRecord::from(&fits)).unwrap();
        v["best"]["specimen"]
            .as_object_mut()
            .unwrap()
            .remove("scatter_dof")
            .expect("written");
        let old = ModelFits::from(serde_json::from_value::<FitsRecord>(v).unwrap());
        let sp = old.best.as_ref().unwrap().specimen.as_ref().unwrap();
        assert!(sp.scatter_dof.len() == 1 && sp.scatter_dof[0].is_nan());
        assert_eq!(sp.scatter_hi95.len(), 1);
        assert_eq!(sp.scatter, vec![0.23]);
    }
}
