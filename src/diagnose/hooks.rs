//! What `diagnose` reports while it runs and what it resumes from: an [`Observer`] told of
//! every phase and step, and an optional [`Journal`] of the bootstrap replicates'
//! statistics. Replicate b of a bootstrap is a pure function of the seed, the stream and b
//! ([`super::bootstrap::replicate_rng`]) and of the fitted models it is drawn under and
//! refitted from: the journal keys it by (stream, hash of those fits, b), so a rerun into the
//! same folder reads the replicates that are done and computes only the others, and the
//! result is the uninterrupted run's bit for bit.

use std::sync::Mutex;

use crate::error::{Error, Result};
use crate::journal::{debug_hash, Exact};

pub use crate::progress::Hooks;

/// The run identity of a diagnosis of `cfg` (bound to its data) kept in its journal: the
/// configuration's ([`crate::identity::identity`]: every setting that changes a fit, the
/// data's hash, the crate version), the command and the `[diagnose]` settings used.
pub fn identity(cfg: &crate::config::RunConfig) -> serde_json::Value {
    let mut id = crate::identity::identity(cfg);
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
    /// [`super::bootstrap::sequential`] of replicates `one(b)` drawn from random stream
    /// `stream` under the fits whose [`model_key`] is `key`: each replicate read from the
    /// journal when it is there, else computed and journaled (flushed) as it finishes; the
    /// phase `name` counts them. `Err` when the observer asks to stop (the replicates
    /// finished so far are journaled) or a journal write fails.
    pub fn sequential<F>(
        &self,
        name: &str,
        stream: u64,
        key: &str,
        observed: &[f64],
        max: usize,
        one: F,
    ) -> Result<(Vec<Vec<f64>>, bool)>
    where
        F: Fn(usize) -> Vec<f64> + Sync,
    {
        let prefix = format!("rep/{stream}/{key}/");
        self.phase(name, max);
        if let Some(j) = self.journal {
            let found = (0..max)
                .filter(|b| j.contains(&format!("{prefix}{b}")))
                .count();
            self.observer.resumed(found as u64);
        }
        let failure: Mutex<Option<Error>> = Mutex::new(None);
        let stop = || {
            self.observer.cancelled() || failure.lock().unwrap_or_else(|e| e.into_inner()).is_some()
        };
        let out = super::bootstrap::sequential(observed, max, |b| {
            let k = format!("{prefix}{b}");
            if let Some(r) = self.journal.and_then(|j| j.get::<Exact>(&k)) {
                return r.0;
            }
            if stop() {
                // Not computed: the run stops and this is never used.
                return vec![f64::NAN; observed.len() + 1];
            }
            let r = one(b);
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
        });
        if let Some(e) = failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e);
        }
        self.check(name)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::journal::Journal;
    use crate::progress::{StopWhen, SILENT};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Replicate statistics of a toy bootstrap: a pure function of b, NaN now and then.
    fn toy(b: usize) -> Vec<f64> {
        let x = ((b * 7919) % 113) as f64 / 113.0;
        vec![x, if b % 9 == 4 { f64::NAN } else { 1.0 - x }, 0.0]
    }

    #[test]
    fn an_interrupted_bootstrap_resumes_to_the_same_replicates() {
        let d = tempfile::TempDir::new().unwrap();
        let id = serde_json::json!({"command": "test"});
        let observed = [0.99, 0.995];
        let plain = super::super::bootstrap::sequential(&observed, 60, toy);
        // Stopped after 15 new replicates (some more finish in flight and are kept).
        let kept = {
            let j = Journal::open(d.path(), &id).unwrap();
            let stop = StopWhen::new(&SILENT, || j.written() >= 15);
            let hooks = Hooks {
                observer: &stop,
                journal: Some(&j),
            };
            let e = hooks
                .sequential("toy", 1, "k", &observed, 60, toy)
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
            .sequential("toy", 1, "k", &observed, 60, |b| {
                calls.fetch_add(1, Ordering::SeqCst);
                toy(b)
            })
            .unwrap();
        assert_eq!(calls.load(Ordering::SeqCst), 60 - kept);
        let bits = |r: &(Vec<Vec<f64>>, bool)| {
            (
                r.0.iter()
                    .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
                r.1,
            )
        };
        assert_eq!(bits(&resumed), bits(&plain));
        // Replicates under another fit (another key) are not reused.
        let calls = AtomicUsize::new(0);
        hooks
            .sequential("toy", 1, "other", &observed, 60, |b| {
                calls.fetch_add(1, Ordering::SeqCst);
                toy(b)
            })
            .unwrap();
        assert_eq!(calls.load(Ordering::SeqCst), 60);
    }
}
