//! `creepfit diagnose`: what the calibrated model gets wrong, whether a catalogued extension
//! explains it, and how sure that is — a calibrated statistical decision.
//!
//! 1. **Fits by maximum likelihood** under the error model of [`crate::errmodel`] (AR(1)
//!    reading error per curve, log-normal rupture-time scatter; [`crate::likelihood`]): the
//!    base model and the base model plus each catalogued extension (DESIGN.md §6), each by
//!    multistart (the initial guess, [`DiagnoseConfig::starts`] Latin-hypercube starts, and for
//!    an extension the base optimum with the extension switched off, so that a nested
//!    extension can never fit worse than the base).
//! 2. **Statistics**: per extension the likelihood ratio T = −2 ln L_base − (−2 ln L_ext); for
//!    the base model the goodness-of-fit statistics G of [`gof`] (a misfit shape common to the
//!    curves, and one per curve).
//! 3. **Null distributions** by a parametric bootstrap under the fitted base model and its
//!    error model ([`bootstrap`]); every replicate is refitted by every model from warm starts
//!    plus random starts (an extension clearly not significant, with 10 null ratios at or
//!    above its own, is no longer refitted when no specimen effects are fitted).
//! 4. **Decision** ([`decide`]): Holm over the extension tests and the base goodness of fit at
//!    level α; attribution by AIC among the rejected extensions, with the bootstrap's spread
//!    deciding what cannot be told apart; the chosen extension must pass its own
//!    goodness-of-fit test (a second bootstrap under the extended model), else `unexplained`.
//! 5. **Explanation** ([`signature`]) and the leave-one-stress-out prediction error of every
//!    candidate as the out-of-sample check — reported, never a veto.

pub mod bootstrap;
pub mod decide;
pub mod gof;
pub mod hooks;
pub mod report;
pub mod signature;

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

pub use crate::config::DiagnoseConfig;
use crate::config::DiagnoseSetup;
use crate::data::{Curve, Dataset};
use crate::errmodel::GrowingError;
use crate::error::{Error, Result};
use crate::fit::FitSettings;
use crate::likelihood::{
    ml_fit, ml_fit_from, raw_objective, with_specimens, EffectStart, MlFit, MlOptions,
};
use crate::lsq::LmCounts;
use crate::model::ext;
use crate::model::guess::initial_guess;
use crate::model::objective::mean_abs;
use crate::sampling::latin_hypercube;
use bootstrap::SpecimenShapes;
pub use decide::Verdict;
use decide::{ExtensionEvidence, SelectInput};
pub use hooks::Hooks;
use signature::{curve_signature, findings, CurveSignature, Finding};

/// Separates the random streams of the bootstraps of one run.
const NULL_STREAM: u64 = 1;
const GOF_STREAM: u64 = 2;

// One model in the comparison: the base model or the base plus one extension, built by
// `RunConfig::diagnose_setup`.
use crate::config::ModelVariant as Spec;

/// What diagnose does with a model of the comparison.
trait SpecExt {
    fn names(&self) -> Vec<&'static str>;
    fn start_from_base(&self, base_names: &[&str], base: &[f64]) -> Vec<f64>;
    fn grid_from(&self, from_base: &[f64]) -> Vec<Vec<f64>>;
    fn probe_from(&self, from_base: &[f64]) -> Vec<Vec<f64>>;
    fn random_start(&self, rng: &mut ChaCha8Rng) -> Vec<f64>;
}

impl SpecExt for Spec {
    fn names(&self) -> Vec<&'static str> {
        self.model.constants().iter().map(|c| c.name).collect()
    }
    /// A start for this model from base constants `base` (by name); the constants the base
    /// lacks take their switched-off value.
    fn start_from_base(&self, base_names: &[&str], base: &[f64]) -> Vec<f64> {
        self.names()
            .iter()
            .enumerate()
            .map(|(j, n)| match base_names.iter().position(|b| b == n) {
                Some(i) => base[i].clamp(self.space.lb[j], self.space.ub[j]),
                None => ext::off_value(n, self.space.lb[j], self.space.ub[j])
                    .unwrap_or_else(|| self.space.from_unit_one(j, 0.5)),
            })
            .collect()
    }
    /// Starts at the base optimum `from_base` (this model's constants, the added ones
    /// switched off) with each added constant in turn at a quarter, half and three quarters
    /// of its range: the base constants are already right where the extension is small, and
    /// a random start of all constants rarely finds an added constant's basin when its effect
    /// is large (a loading strain of 1 % at the base optimum with E_L off is far downhill of
    /// nothing the LM can see).
    fn grid_from(&self, from_base: &[f64]) -> Vec<Vec<f64>> {
        let names = self.names();
        let mut out = Vec::new();
        for e in &self.extra {
            let Some(j) = names.iter().position(|n| n == e) else {
                continue;
            };
            for u in [0.25, 0.5, 0.75] {
                let mut x = from_base.to_vec();
                x[j] = self.space.from_unit_one(j, u);
                out.push(x);
            }
        }
        out
    }
    /// Starts at the base optimum `from_base` (this model's constants, the added ones
    /// switched off) with the extension switched slightly on ([`ext::probe_starts`]): where
    /// the likelihood is flat around the switched-off start. Used on the data and in every
    /// null replicate alike.
    fn probe_from(&self, from_base: &[f64]) -> Vec<Vec<f64>> {
        let names = self.names();
        ext::probe_starts(&self.name)
            .into_iter()
            .map(|probe| {
                let mut x = from_base.to_vec();
                for (c, v) in probe {
                    if let Some(j) = names.iter().position(|n| *n == c) {
                        x[j] = v.clamp(self.space.lb[j], self.space.ub[j]);
                    }
                }
                x
            })
            .collect()
    }
    /// A random start, uniform in the unit box.
    fn random_start(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let u: Vec<f64> = (0..self.space.n_free()).map(|_| rng.gen()).collect();
        let mut x = vec![0.0; self.space.len()];
        self.space.from_unit(&u, &mut x);
        x
    }
}

/// The best (lowest −2 ln L) of maximum-likelihood fits from `starts`, the first `warm` of
/// them optima already found (polished directly, their specimen effects starting at
/// `effects`; the others are fresh starts, also fitted with white reading errors first);
/// ties go to the earlier start. `None` when every start failed; the count of failed starts
/// comes along.
fn fit_best(
    spec: &Spec,
    curves: &[Curve],
    starts: &[Vec<f64>],
    warm: usize,
    effects: Option<&EffectStart>,
    settings: &FitSettings,
    ml: &MlOptions,
) -> (Option<MlFit>, usize) {
    let all = fit_all(spec, curves, starts, warm, effects, settings, ml);
    let failed = all.iter().filter(|(_, f)| !f.ok()).count();
    let (warm_fits, fresh): (Vec<_>, Vec<_>) = all.into_iter().partition(|(i, _)| *i < warm);
    let mut fits: Vec<MlFit> = warm_fits.into_iter().map(|(_, f)| f).collect();
    if !fresh.is_empty() {
        let fresh: Vec<MlFit> = fresh.into_iter().map(|(_, f)| f).collect();
        fits.extend(polish(spec, curves, &fresh, 1, settings, ml));
    }
    let best = fits
        .into_iter()
        .filter(|f| f.ok())
        .reduce(|a, b| if b.neg2ll < a.neg2ll { b } else { a });
    (best, failed)
}

/// The specimen effects of `ml` added to up to `k` distinct optima among `fits` (fits
/// without them, best first): each the better of its hierarchical fit and itself.
fn polish(
    spec: &Spec,
    curves: &[Curve],
    fits: &[MlFit],
    k: usize,
    settings: &FitSettings,
    ml: &MlOptions,
) -> Vec<MlFit> {
    if !ml.specimen.any() {
        return fits.to_vec();
    }
    let tops = distinct_fits(spec, fits, k);
    let mut out: Vec<MlFit> = tops
        .into_par_iter()
        .map(|f| with_specimens(f, spec.model.as_ref(), curves, &spec.space, settings, ml))
        .collect();
    // The others stay as they are (they hold the failed starts' records and other basins).
    out.extend(fits.iter().cloned());
    out
}

/// Maximum-likelihood fits from every start, in parallel, in start order, each with its
/// start's index (the first `warm` polished directly with their specimen effects starting at
/// `effects`, the others both directly and white first, the better kept); a start within
/// 1e-6 of the box of an earlier one is fitted once.
fn fit_all(
    spec: &Spec,
    curves: &[Curve],
    starts: &[Vec<f64>],
    warm: usize,
    effects: Option<&EffectStart>,
    settings: &FitSettings,
    ml: &MlOptions,
) -> Vec<(usize, MlFit)> {
    let units: Vec<Vec<f64>> = starts.iter().map(|s| spec.space.to_unit(s)).collect();
    let unique: Vec<(usize, &Vec<f64>)> = starts
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            !(0..*i).any(|j| {
                units[j]
                    .iter()
                    .zip(&units[*i])
                    .all(|(a, b)| (a - b).abs() <= 1e-6)
            })
        })
        .collect();
    unique
        .par_iter()
        .map(|&(i, s)| {
            let direct = MlOptions {
                white_first: false,
                ..*ml
            };
            let model = spec.model.as_ref();
            if i < warm {
                let f = ml_fit_from(model, curves, &spec.space, s, effects, settings, &direct);
                return (i, f);
            }
            // A fresh start is fitted without specimen effects ([`polish`] adds them to the
            // best optima found): the multistart's job is to find the basins, and a fit
            // without effects costs a fraction of one with them.
            let direct = MlOptions {
                specimen: crate::likelihood::SpecimenOptions::NONE,
                ..direct
            };
            let white = MlOptions {
                specimen: crate::likelihood::SpecimenOptions::NONE,
                ..*ml
            };
            let d = ml_fit(model, curves, &spec.space, s, settings, &direct);
            // A fresh start both ways: white first finds what an AR(1) model with φ near 1
            // takes for noise (a loading strain), the direct path keeps basins the white
            // stage leads away from (measured on the seed's 590 °C data).
            let w = ml_fit(model, curves, &spec.space, s, settings, &white);
            (i, d.better(w))
        })
        .collect()
}

/// A fresh start of an extension's fits on the data that every null replicate repeats: the
/// one whose fit was best among the fresh starts on the data, rebuilt in the replicate as it
/// was built on the data. The replicates' own starts are the data's few warm ones (the base
/// optimum, the probes, the data's optimum); the data's best basin is often found from a
/// grid or a random start that they lack, so that the data's ratio had no counterpart in the
/// null (measured on a null set with specimen scatter, 98148: stress_ductility LR 6.2 above
/// all 159 null ratios, p 0.006; with the data's whole grid in every replicate, p 0.09, at
/// four times the cost).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Recipe {
    /// The base optimum with the extension switched off: every replicate starts there anyway.
    FromBase,
    /// Grid start `k` of [`SpecExt::grid_from`] at the replicate's base optimum.
    Grid(usize),
    /// A start that does not depend on the data's fits (the initial guess's, a Latin
    /// hypercube point): the same in every replicate.
    Fixed(Vec<f64>),
}

/// The [`Recipe`] of start `j` among an extension's `starts` on the data, laid out as
/// `diagnose_observed` builds them: the base optimum, the probes, the initial guess, the
/// grid, the Latin hypercube.
fn recipe_of(spec: &Spec, starts: &[Vec<f64>], j: usize) -> Recipe {
    let np = ext::probe_starts(&spec.name).len();
    let ng = spec.grid_from(&starts[0]).len();
    match j {
        0 => Recipe::FromBase,
        j if (2 + np..2 + np + ng).contains(&j) => Recipe::Grid(j - 2 - np),
        j => Recipe::Fixed(starts[j].clone()),
    }
}

/// `ml` for the fits of an extension beside base fit `base`: with the scatter estimated
/// beyond the stress trend ([`crate::likelihood::SpecimenOptions::beyond_trend`]) the scatter
/// held at the base's, so that every model is compared at the scatter estimated under the
/// null (as a score test takes its nuisances); `ml` with its scatter free otherwise.
fn ext_options(ml: &MlOptions, base: Option<&MlFit>) -> MlOptions {
    let hold = base
        .and_then(|b| b.specimen.as_ref())
        .filter(|_| ml.specimen.beyond_trend)
        .map(|sp| crate::likelihood::held_scatter(Some(sp)));
    MlOptions {
        hold_scatter: hold,
        ..*ml
    }
}

/// Whether the diagnosis goes on without the specimen factors `auto` chose
/// ([`decide::without_specimen_factors`]): beyond the stress trend with the base fit's
/// scatter at zero for every kind.
fn singular_scatter(auto: bool, ml: &MlOptions, base: Option<&MlFit>) -> bool {
    let Some(base) = base else { return false };
    let scatter = base.specimen.as_ref().map(|sp| sp.scatter.as_slice());
    decide::without_specimen_factors(auto, ml.specimen.beyond_trend, ml.specimen.any(), scatter)
}

/// A base refit that beats the base fit by less than this (−2 ln L) does not replace it.
const CROSS_TOL: f64 = 1e-3;

/// Whether `ext` carries specimen effects of a kind that `base` does not (the base's fit
/// dropped it at zero scatter, or carries none).
fn more_structure(ext: Option<&MlFit>, base: &MlFit) -> bool {
    let kinds = |f: &MlFit| f.specimen.as_ref().map_or(vec![], |s| s.kinds.clone());
    let have = kinds(base);
    ext.is_some_and(|e| kinds(e).iter().any(|k| !have.contains(k)))
}

/// Cross-starts, where the fits carry specimen effects: the base model is refitted from the
/// optimum of the extension with the largest likelihood ratio (its constants projected onto
/// the base's by name, its specimen effects and scatter as they are) when that extension
/// carries specimen effects of a kind the base fit has not (it stopped at zero scatter), or
/// the base fit carries any; where that beats the base fit, it replaces it and every
/// extension that now fits worse than the base is polished again from the new base optimum
/// (effects included), the better kept. Measured: on a generated set with specimen scatter
/// (seed 95102, rate scatter 0.28) the base's hierarchical fit stopped at zero scatter while
/// every extension's found it, so each ratio mixed the extension with the scatter (LR 850);
/// and a hierarchical fit from zero effects can stop in a valley hundreds of −2 ln L units
/// above its optimum (Alloy 617 at 900 °C: in 12 of 156 null replicates by more than 10),
/// which an extension fitted from more starts reads as evidence. The same rule runs on the
/// data and in every null replicate. Without specimen effects nothing happens: refitting the
/// base from the best extension unconditionally was measured to make the null bootstrap
/// anti-conservative on identical specimens (set 1001 of tests/diagnose.rs, no effect: every
/// extension's p fell, stress_ductility 0.0375 → 0.006, a false alarm), presumably because
/// the replicates' bases, fitted from fewer starts than the data's, gained more from it.
/// Returns the indices of the fits it replaced (0 = the base).
fn cross_start(
    specs: &[Spec],
    fits: &mut [Option<MlFit>],
    curves: &[Curve],
    settings: &FitSettings,
    ml: &MlOptions,
) -> Vec<usize> {
    let Some(base) = fits[0].as_ref() else {
        return vec![];
    };
    let best_ext = (1..fits.len())
        .filter_map(|k| fits[k].as_ref().filter(|f| f.ok()).map(|f| (k, f.neg2ll)))
        .reduce(|a, b| if b.1 < a.1 { b } else { a });
    let Some((k, ext_ll)) = best_ext else {
        return vec![];
    };
    let hierarchical = base.specimen.is_some() || more_structure(fits[k].as_ref(), base);
    if ext_ll >= base.neg2ll - CROSS_TOL || !hierarchical {
        return vec![];
    }
    let direct = MlOptions {
        white_first: false,
        hold_scatter: None,
        ..*ml
    };
    let ext = fits[k].as_ref().expect("found");
    let names = specs[k].names();
    let start: Vec<f64> = specs[0]
        .names()
        .iter()
        .enumerate()
        .map(|(j, n)| {
            let i = names.iter().position(|m| m == n).expect("base constant");
            ext.params[i].clamp(specs[0].space.lb[j], specs[0].space.ub[j])
        })
        .collect();
    let effects = ext.specimen.as_ref().map(EffectStart::from);
    let b = ml_fit_from(
        specs[0].model.as_ref(),
        curves,
        &specs[0].space,
        &start,
        effects.as_ref(),
        settings,
        &direct,
    );
    if !(b.ok() && b.neg2ll < base.neg2ll - CROSS_TOL) {
        return vec![];
    }
    let base_names = specs[0].names();
    let from = b.specimen.as_ref().map(EffectStart::from);
    let direct_ext = ext_options(&direct, Some(&b));
    let redo: Vec<usize> = (1..fits.len())
        .filter(|&j| {
            fits[j]
                .as_ref()
                .is_none_or(|f| !f.ok() || f.neg2ll > b.neg2ll)
        })
        .collect();
    let refits: Vec<(usize, MlFit)> = redo
        .par_iter()
        .map(|&j| {
            let s = specs[j].start_from_base(&base_names, &b.params);
            let m = specs[j].model.as_ref();
            let f = ml_fit_from(
                m,
                curves,
                &specs[j].space,
                &s,
                from.as_ref(),
                settings,
                &direct_ext,
            );
            (j, f)
        })
        .collect();
    fits[0] = Some(b);
    let mut changed = vec![0];
    for (j, f) in refits {
        let better = f.ok()
            && fits[j]
                .as_ref()
                .is_none_or(|g| !g.ok() || f.neg2ll < g.neg2ll);
        if better {
            fits[j] = Some(f);
            changed.push(j);
        }
    }
    changed
}

/// The null refits' gain-to-come stop ([`crate::lsq::LmOptions::gain_to_come`]): windows of 10
/// iterations, a tail of at most 0.001 in −2 ln L. Refits that crawl along a flat valley
/// otherwise run to the iteration limit for changes far below any decision (the seed's 560 °C
/// diagnosis: 737 of 3,480 fits at the limit, half of all iterations). Measured there: with
/// 0.001 the p-values and the `lr_critical` of every test are those of the run without the
/// stop (to 0.01) and a quarter of the iterations go; with 0.01, `lr_critical` moved by up to
/// 0.27 (the refits stopped short enough to narrow the null), so not that. The fits on the
/// data keep the full iteration: at 0.01 there, one extension's ratio fell from 9.80 to 7.09.
pub const REFIT_GAIN_TO_COME: (usize, f64) = (10, 1e-3);

/// Local optima whose −2 ln L on the data is more than this above the best are not used as
/// warm starts of the bootstrap refits: replicates under the null differ from the data by a
/// few units of −2 ln L, so such a basin does not become the best in a replicate.
pub const BASIN_WINDOW: f64 = 10.0;

/// Up to `k` distinct local optima among `fits` within [`BASIN_WINDOW`] of the best, best
/// first: a fit is new when its −2 ln L differs by more than 0.01 from every kept one or its
/// constants by more than 0.02 of the box in some coordinate.
fn distinct_optima(spec: &Spec, fits: &[MlFit], k: usize) -> Vec<Vec<f64>> {
    distinct_fits(spec, fits, k)
        .into_iter()
        .map(|f| f.params)
        .collect()
}

/// The fits behind [`distinct_optima`].
fn distinct_fits(spec: &Spec, fits: &[MlFit], k: usize) -> Vec<MlFit> {
    let mut ok: Vec<&MlFit> = fits.iter().filter(|f| f.ok()).collect();
    ok.sort_by(|a, b| a.neg2ll.total_cmp(&b.neg2ll));
    let best = ok.first().map_or(f64::NAN, |f| f.neg2ll);
    let mut kept: Vec<&MlFit> = Vec::new();
    for f in ok {
        if kept.len() >= k || f.neg2ll > best + BASIN_WINDOW {
            break;
        }
        let u = spec.space.to_unit(&f.params);
        let same = kept.iter().any(|g| {
            let v = spec.space.to_unit(&g.params);
            (f.neg2ll - g.neg2ll).abs() <= 0.01
                && u.iter().zip(&v).all(|(a, b)| (a - b).abs() <= 0.02)
        });
        if !same {
            kept.push(f);
        }
    }
    kept.into_iter().cloned().collect()
}

/// Leave-one-stress-out prediction of one candidate.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Loo {
    /// RMS over held-out curves of the time-weighted mean squared normalised strain
    /// residual (density of logging does not matter). NaN if a fold failed.
    pub rmse: f64,
    /// Mean |held-out lifetime error|, %. NaN if a fold failed.
    pub lifetime_err_pct: f64,
    /// Folds whose fit failed from every start (their stress, MPa): no prediction is made
    /// for them, and the totals are NaN.
    pub failed_folds: Vec<f64>,
}

/// Time-weighted mean of squared normalised residuals of one curve.
fn weighted_ms(c: &Curve, pred: &[f64]) -> f64 {
    let n = c.times_h.len();
    let (mut sw, mut s) = (0.0, 0.0);
    for j in 0..n {
        let left = if j > 0 {
            c.times_h[j] - c.times_h[j - 1]
        } else {
            0.0
        };
        let right = if j + 1 < n {
            c.times_h[j + 1] - c.times_h[j]
        } else {
            0.0
        };
        let w = 0.5 * (left + right);
        let r = (pred[j] - c.strains[j]) / c.rupture_strain;
        sw += w;
        s += w * r * r;
    }
    if sw > 0.0 {
        s / sw
    } else {
        f64::NAN
    }
}

fn leave_one_stress_out(
    spec: &Spec,
    curves: &[Curve],
    full: &[f64],
    fallback: &[Vec<f64>],
    settings: &FitSettings,
    ml: &MlOptions,
) -> Loo {
    let mut groups: Vec<(f64, f64)> = curves
        .iter()
        .map(|c| (c.temperature_c, c.stress_mpa))
        .collect();
    groups.dedup();
    if groups.len() < 2 {
        return Loo {
            rmse: f64::NAN,
            lifetime_err_pct: f64::NAN,
            failed_folds: vec![],
        };
    }
    // Per fold: its stress and, unless it failed, per held-out curve (mean squared
    // normalised strain residual, |lifetime error| %).
    type Fold = (f64, Option<Vec<(f64, f64)>>);
    let folds: Vec<Fold> = groups
        .par_iter()
        .map(|&(t, s)| {
            let (train, test): (Vec<Curve>, Vec<Curve>) = curves
                .iter()
                .cloned()
                .partition(|c| !(c.temperature_c == t && c.stress_mpa == s));
            let polish = MlOptions {
                white_first: false,
                ..*ml
            };
            let mut fit = ml_fit(
                spec.model.as_ref(),
                &train,
                &spec.space,
                full,
                settings,
                &polish,
            );
            for st in fallback {
                if fit.ok() {
                    break;
                }
                fit = ml_fit(spec.model.as_ref(), &train, &spec.space, st, settings, ml);
            }
            if !fit.ok() {
                return (s, None);
            }
            let ev = raw_objective(spec.model.as_ref(), &test, settings).evaluate(&fit.params);
            let errs: Vec<(f64, f64)> = test
                .iter()
                .zip(&ev.curves)
                .map(|(c, p)| {
                    let life = match c.rupture_time_h {
                        Some(tf) => 100.0 * (p.rupture_time_h - tf).abs() / tf,
                        None => f64::NAN,
                    };
                    (weighted_ms(c, &p.strain), life)
                })
                .collect();
            if errs.iter().any(|e| !e.0.is_finite()) {
                return (s, None);
            }
            (s, Some(errs))
        })
        .collect();
    let failed_folds: Vec<f64> = folds
        .iter()
        .filter(|f| f.1.is_none())
        .map(|f| f.0)
        .collect();
    if !failed_folds.is_empty() {
        return Loo {
            rmse: f64::NAN,
            lifetime_err_pct: f64::NAN,
            failed_folds,
        };
    }
    let all: Vec<(f64, f64)> = folds.into_iter().flat_map(|f| f.1.unwrap()).collect();
    let ms = all.iter().map(|e| e.0).sum::<f64>() / all.len() as f64;
    let life: Vec<f64> = all.iter().map(|e| e.1).collect();
    Loo {
        rmse: ms.sqrt(),
        lifetime_err_pct: mean_abs(&life),
        failed_folds,
    }
}

/// The fitted error model in report units.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NoiseSummary {
    /// Marginal sd of the reading error per curve, % strain.
    pub strain_sd_pct: Vec<f64>,
    /// AR(1) correlation per curve.
    pub phi: Vec<f64>,
    /// Scatter of rupture times (sd of ln t), %.
    pub lifetime_sd_pct: f64,
    /// Growth g of the reading error with strain ([`crate::errmodel::GrowingError`]): at a
    /// curve's largest strain the reading error is (1 + g) times its value at zero; 0 when
    /// it does not grow. The parametric bootstraps draw their replicates' reading error so.
    pub reading_error_growth: f64,
}

/// Whether a candidate could be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    /// Fitted from at least one start.
    Fitted,
    /// Every start failed.
    Failed,
}

/// One fitted model in the comparison (`diagnosis.json` → `base`, `candidates`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Candidate {
    /// `base` or the extension's name.
    pub name: String,
    /// The model's registry name with its extensions, e.g. `khd+constant_load`.
    pub model: String,
    /// Names of the constants it adds to the base model.
    pub extra_constants: Vec<String>,
    /// Whether it could be fitted.
    pub status: FitStatus,
    /// Starts that failed (simulation failure).
    pub failed_starts: usize,
    /// How the Levenberg–Marquardt iteration of the kept fit ended (`None` if not fitted):
    /// `iteration_limit` or `stalled` mean it stopped before convergence, so `objective`
    /// may lie above the optimum (the diagnosis then carries a caution,
    /// [`decide::unconverged_fits_caution`]).
    pub termination: Option<crate::lsq::Termination>,
    /// −2 ln L at the maximum-likelihood fit (what `diagnose` compares; NaN if not fitted).
    pub objective: f64,
    /// Number of fitted constants.
    pub k: usize,
    /// AIC = −2 ln L + 2k.
    pub aic: f64,
    /// Likelihood-ratio statistic against the base model, −2 ln L_base − (−2 ln L).
    pub lr: f64,
    /// Bootstrap p-value of the likelihood-ratio test (null: the base model suffices).
    pub p_value: Option<f64>,
    /// Holm-adjusted p-value within the family.
    pub p_holm: Option<f64>,
    /// The likelihood ratio this extension would have needed for a bootstrap p ≤ α before
    /// Holm's adjustment: its null distribution's upper-α quantile
    /// ([`bootstrap::critical_value`]); `None` for the base, or when the replicates cannot give
    /// p ≤ α. Far above a χ² quantile (3.84 for one added constant at 5 %), it says the null
    /// refits disagree and only a large effect can show.
    pub lr_critical: Option<f64>,
    /// Null replicates behind `p_value` and `lr_critical` (`None` for the base): fewer than
    /// the bootstrap's when the test was decided not significant early and dropped from the
    /// later replicates (only without specimen effects; see [`bootstrap::sequential`]).
    pub null_replicates: Option<usize>,
    /// Whether the null bootstrap was run again for this test with the fresh start that
    /// found the data's best fit added to every replicate's refits (a test that rejected with
    /// the replicates' own starts; `p_value` and `lr_critical` are then the second run's).
    pub null_again: bool,
    /// What that second run changed (`None` where it was not run): replicates whose ratio
    /// it raised, and the replicates at or above the data's ratio before and after.
    pub null_again_effect: Option<bootstrap::AgainEffect>,
    /// Rejected the base model at level α (Holm).
    pub significant: bool,
    /// BIC − BIC(base) with the effective number of observations of the base's error model
    /// (Σ n_i (1 − φ_i)/(1 + φ_i) + rupture times): for orientation only, not the decision.
    pub delta_bic: f64,
    /// Leave-one-stress-out RMSE of the held-out normalised strain (see [`Loo`]).
    pub loo_rmse: f64,
    /// Mean |held-out lifetime error|, %.
    pub loo_lifetime_err_pct: f64,
    /// Folds whose fit failed (stress, MPa).
    pub loo_failed_folds: Vec<f64>,
    /// Reduction of `loo_rmse` against the base model, %.
    pub gain_pct: f64,
    /// Fitted constants (name, value).
    pub constants: Vec<(String, f64)>,
    /// Constants on a bound: (name, lower/upper).
    pub pinned: Vec<(String, String)>,
    /// Lifetime errors per curve, %.
    pub lifetime_errs_pct: Vec<f64>,
    /// The fitted error model.
    pub noise: Option<NoiseSummary>,
    /// The specimen effects (scatter between specimens and each specimen's factors), when
    /// the fit carries any.
    pub specimen: Option<crate::likelihood::SpecimenFit>,
    /// Per kind of specimen effect, how the factors follow stress within temperatures
    /// ([`crate::likelihood::StressTrend`]; empty without effects): information beside the
    /// tests, not part of the decision.
    pub specimen_stress_trend: Vec<crate::likelihood::StressTrend>,
    /// Per kind of specimen effect, how the factors differ between temperatures
    /// ([`crate::likelihood::TemperatureLevels`]; empty without effects or with one
    /// temperature): information beside the tests, not part of the decision.
    pub specimen_temperature_levels: Vec<crate::likelihood::TemperatureLevels>,
    /// Per kind of specimen effect, how the factors differ between test campaigns beyond
    /// temperature and stress ([`crate::likelihood::CampaignLevels`]; empty without effects
    /// or two campaigns): information beside the tests, not part of the decision.
    pub specimen_campaign_levels: Vec<crate::likelihood::CampaignLevels>,
    /// Per-curve explanation.
    pub curves: Vec<CurveSignature>,
}

/// A goodness-of-fit test of one model against its own bootstrap.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GofTest {
    /// The model tested (`base` or an extension name).
    pub model: String,
    /// The statistic G, the alternative's shape (`common` or `per_curve`) and the misfit
    /// shape behind it.
    pub gof: gof::Gof,
    /// Bootstrap p-value.
    pub p_value: f64,
    /// Holm-adjusted p-value (the base model's test is part of the family; NaN for a test
    /// reported beside the decision).
    pub p_holm: Option<f64>,
    /// Replicates used.
    pub replicates: usize,
    /// Whether the test is part of the decision ([`gof::decides`]): with specimen effects the
    /// fixed common and per-curve shapes are reported only (the per-curve one says how much
    /// the specimens differ in shape), without them the shapes beyond specimen shapes are.
    pub decides: bool,
}

/// Two rejected extensions the data cannot tell apart.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Indistinguishable {
    /// The other extension.
    pub name: String,
    /// Its AIC minus the cause's.
    pub delta_aic: f64,
    /// 95 % quantile of |T*_cause − T*_other| over the null replicates.
    pub spread95: f64,
}

/// How the bootstrap went.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BootstrapInfo {
    /// Null replicates drawn (under the fitted base model).
    pub replicates: usize,
    /// The most that were allowed for every test.
    pub max: usize,
    /// The most that were allowed for a test close to significance (p ≤ α/2 after `max`).
    pub most: usize,
    /// Sampling stopped early: every test was clearly not significant (10 null statistics
    /// at or above its own), or Holm's procedure could reject none of them any more.
    pub stopped_early: bool,
    /// The spread of the specimens' own shapes the replicates' new specimens were given,
    /// resampled from the data's specimens ([`bootstrap::SpecimenShapes`]): root mean square
    /// at a knot, % of the rupture strain (τ̂ of the goodness of fit beyond specimen shapes);
    /// 0 when they differ by their fitted factors only (no specimen effects, or τ̂ = 0).
    pub specimen_shape_sd_pct: f64,
    /// Replicates whose base refit failed from every start.
    pub failed_base_refits: usize,
    /// Per extension: replicates whose refit failed (they count against rejection).
    pub failed_extension_refits: Vec<(String, usize)>,
    /// Every test's statistic in every replicate it was computed in, replicate order (the
    /// null distribution itself; `null` where a refit failed): for plots and for checking a
    /// multiplicity procedure on the joint distribution of the tests.
    pub null_statistics: Vec<NullColumn>,
}

/// One test's null statistics (`diagnosis.json` → `bootstrap.null_statistics`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct NullColumn {
    /// The test: an extension's name, or `base common goodness of fit` / `base per-curve
    /// goodness of fit`.
    pub test: String,
    /// Its statistic on the data (likelihood ratio or G).
    pub observed: f64,
    /// Its statistic in replicates `0..values.len()` (NaN, written `null`: a refit failed).
    pub values: Vec<f64>,
}

/// The outcome of [`diagnose`] (`diagnosis.json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Diagnosis {
    /// `adequate`, `extension` or `unexplained`.
    pub verdict: Verdict,
    /// The extension named as the cause, for `extension`.
    pub cause: Option<String>,
    /// For `unexplained` after an extension was significant: the extension that came closest.
    pub closest: Option<String>,
    /// False-alarm level of the family of tests.
    pub alpha: f64,
    /// What the base model misses, in words and numbers (explanation, not decision).
    pub evidence: Vec<Finding>,
    /// The base model.
    pub base: Candidate,
    /// Every extension tried.
    pub candidates: Vec<Candidate>,
    /// Significant extensions the data cannot tell apart from the cause.
    pub indistinguishable: Vec<Indistinguishable>,
    /// Goodness of fit of the base model (one test per misfit shape).
    pub gof: Vec<GofTest>,
    /// Goodness of fit of the significant extension with the lowest AIC (empty without one).
    pub cause_gof: Vec<GofTest>,
    /// The null bootstrap.
    pub bootstrap: BootstrapInfo,
    /// The decision, step by step, in words.
    pub decision: Vec<String>,
    /// Where the base fit's error model may have taken misfit for correlated reading error
    /// ([`decide::absorbed_misfit_caution`]) or written a curve off as noise
    /// ([`crate::fit::written_off_caution`]), failed null refits may have kept a test from
    /// rejecting ([`decide::failed_refits_caution`]), or a fit on the data stopped before
    /// convergence ([`decide::unconverged_fits_caution`]); joined by ". Also: "; `null`
    /// otherwise.
    pub caution: Option<String>,
    /// Whether the diagnosis went on without the specimen factors that `specimen_effects =
    /// "auto"` chose, because the base fit estimated every kind's scatter beyond the stress
    /// trend at zero ([`decide::without_specimen_factors`]): every model was then fitted
    /// without factors and the bootstrap drew identical specimens.
    pub specimen_scatter_zero: bool,
    /// With `reduction = "strain_means"` and `misfit_share = "estimate"` on grouped curves:
    /// the share ρ of a reading's error variance that the group means do not shrink,
    /// estimated from the base fit and held for the diagnosis (a mean of m readings has
    /// (1 − ρ)/m + ρ of a reading's variance); `null` otherwise (white reading error, ρ = 0).
    #[serde(default)]
    pub misfit_share: Option<f64>,
    /// The settings used.
    pub settings: DiagnoseConfig,
    /// Wall time, s (not in `diagnosis.json`, whose content does not depend on how the run
    /// went: `timings.json`).
    #[serde(skip)]
    pub wall_s: f64,
    /// Wall time per phase, s: fits on the data, null bootstrap, the cause's
    /// goodness-of-fit bootstrap, leave-one-stress-out (`timings.json`).
    #[serde(skip)]
    pub phase_s: PhaseTimes,
    /// Levenberg–Marquardt runs and iterations per phase (`timings.json`).
    #[serde(skip)]
    pub phase_lm: PhaseWork,
}

/// Wall time per phase of [`diagnose`], s.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct PhaseTimes {
    /// Multistart fits of every model on the data.
    pub fits: f64,
    /// Null bootstrap, its second run included.
    pub null_bootstrap: f64,
    /// The null bootstrap's second run (the rejecting tests again with their data start).
    pub null_again: f64,
    /// Goodness-of-fit bootstrap of the chosen extension.
    pub cause_bootstrap: f64,
    /// Leave-one-stress-out refits.
    pub loo: f64,
}

/// The Levenberg–Marquardt work of each phase of [`diagnose`] (the phases of [`PhaseTimes`]):
/// its time is the count of its iterations, and runs at the iteration limit are the ones
/// stopped unconverged. Counted process-wide ([`LmCounts::now`]): exact for the binary's one
/// diagnosis, a sum with any concurrent work in a library caller.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct PhaseWork {
    /// The whole diagnosis.
    pub total: LmCounts,
    /// Multistart fits of every model on the data.
    pub fits: LmCounts,
    /// Null bootstrap, its second run included.
    pub null_bootstrap: LmCounts,
    /// The null bootstrap's second run.
    pub null_again: LmCounts,
    /// Goodness-of-fit bootstrap of the chosen extension.
    pub cause_bootstrap: LmCounts,
    /// Leave-one-stress-out refits.
    pub loo: LmCounts,
}

fn noise_summary(spec: &Spec, curves: &[Curve], f: &MlFit, settings: &FitSettings) -> NoiseSummary {
    NoiseSummary {
        reading_error_growth: bootstrap::reading_error(
            curves,
            spec.model.as_ref(),
            &spec.space,
            f,
            settings,
        )
        .growth,
        strain_sd_pct: f
            .noise
            .strain
            .iter()
            .map(|p| 100.0 * p.marginal_sd())
            .collect(),
        phi: f.noise.strain.iter().map(|p| p.phi).collect(),
        lifetime_sd_pct: 100.0 * f.noise.lifetime_sd,
    }
}

fn signatures(curves: &[Curve], f: &MlFit) -> Vec<CurveSignature> {
    let (Some(res), Some(ev)) = (&f.residuals, &f.eval) else {
        return vec![];
    };
    curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            curve_signature(
                c,
                &res.strain[i],
                ev.curves[i].rupture_time_h,
                &f.noise.strain[i],
            )
        })
        .collect()
}

fn candidate(
    spec: &Spec,
    curves: &[Curve],
    fit: Option<&MlFit>,
    failed: usize,
    settings: &FitSettings,
) -> Candidate {
    let k = spec.space.n_free();
    let mut c = Candidate {
        name: spec.name.clone(),
        model: spec.model.name().to_string(),
        extra_constants: spec.extra.clone(),
        status: FitStatus::Failed,
        failed_starts: failed,
        termination: None,
        objective: f64::NAN,
        k,
        aic: f64::NAN,
        lr: f64::NAN,
        p_value: None,
        p_holm: None,
        lr_critical: None,
        null_replicates: None,
        null_again: false,
        null_again_effect: None,
        significant: false,
        delta_bic: f64::NAN,
        loo_rmse: f64::NAN,
        loo_lifetime_err_pct: f64::NAN,
        loo_failed_folds: vec![],
        gain_pct: f64::NAN,
        constants: vec![],
        pinned: vec![],
        lifetime_errs_pct: vec![],
        noise: None,
        specimen: None,
        specimen_stress_trend: vec![],
        specimen_temperature_levels: vec![],
        specimen_campaign_levels: vec![],
        curves: vec![],
    };
    if let Some(f) = fit {
        c.status = FitStatus::Fitted;
        c.termination = Some(f.termination);
        c.objective = f.neg2ll;
        c.aic = f.neg2ll + 2.0 * k as f64;
        c.constants = spec
            .names()
            .iter()
            .zip(&f.params)
            .map(|(n, v)| (n.to_string(), *v))
            .collect();
        c.pinned = (0..spec.space.len())
            .filter_map(|j| {
                spec.space
                    .at_bound(j, f.params[j], 1e-6)
                    .map(|b| (spec.names()[j].to_string(), b.to_string()))
            })
            .collect();
        if let Some(ev) = &f.eval {
            c.lifetime_errs_pct = ev.lifetime_errors_pct(curves);
        }
        c.noise = Some(noise_summary(spec, curves, f, settings));
        c.specimen = f.specimen.clone();
        c.specimen_stress_trend = f
            .specimen
            .as_ref()
            .map(|s| s.stress_trend(curves))
            .unwrap_or_default();
        c.specimen_temperature_levels = f
            .specimen
            .as_ref()
            .map(|s| s.temperature_levels(curves))
            .unwrap_or_default();
        c.specimen_campaign_levels = f
            .specimen
            .as_ref()
            .map(|s| s.campaign_levels(curves))
            .unwrap_or_default();
        c.curves = signatures(curves, f);
    }
    c
}

/// Null replicate `b`'s data under the base fit `base` (its own random stream, which is
/// returned for the replicate's random starts): [`null_replicate`] and [`null_again`] must
/// draw the same data.
#[allow(clippy::too_many_arguments)]
fn null_data(
    specs: &[Spec],
    base: &MlFit,
    curves: &[Curve],
    settings: &FitSettings,
    dc: &DiagnoseConfig,
    shapes: &SpecimenShapes,
    reading: &GrowingError,
    b: usize,
) -> (Vec<Curve>, ChaCha8Rng, Option<EffectStart>) {
    let mut rng = bootstrap::replicate_rng(dc.seed, NULL_STREAM, b);
    let (data, drawn) = bootstrap::replicate_hier_drawn(
        curves,
        specs[0].model.as_ref(),
        base,
        reading,
        settings,
        shapes,
        &mut rng,
    );
    (data, rng, drawn)
}

/// A bootstrap replicate's refit `fit` (from the fitted models' basins and random starts,
/// new specimens' effects starting at zero) and its fit from the point it was drawn at (the
/// constants `params` of the model it was drawn under, the `drawn` effects and scatter): the
/// better. From zero effects alone, a hierarchical refit can stop in a valley hundreds of
/// −2 ln L units above the optimum, and every extension's refit, from more starts, then
/// reads that as evidence (measured on Alloy 617 at 900 °C, 156 null replicates: the refit
/// from zero effects ended more than 10 above the one from the drawn point in 12, by up to
/// 527; the other way round in 2).
#[allow(clippy::too_many_arguments)]
fn with_drawn_start(
    fit: Option<MlFit>,
    spec: &Spec,
    data: &[Curve],
    params: &[f64],
    drawn: Option<&EffectStart>,
    settings: &FitSettings,
    ml: &MlOptions,
) -> Option<MlFit> {
    let Some(drawn) = drawn.filter(|_| ml.specimen.any()) else {
        return fit;
    };
    let d = ml_fit_from(
        spec.model.as_ref(),
        data,
        &spec.space,
        params,
        Some(drawn),
        settings,
        ml,
    );
    match fit {
        Some(f) => Some(f.better(d)),
        None => d.ok().then_some(d),
    }
}

/// What one null replicate gives: the likelihood ratio of every extension and the base
/// goodness-of-fit statistic (NaN where a refit failed), whether the base refit failed, and
/// (when it did not) the base refit's −2 ln L and constants, for [`null_again`]. An extension
/// whose test is no longer `active` is not refitted (NaN).
#[allow(clippy::too_many_arguments)]
fn null_replicate(
    specs: &[Spec],
    fits: &[Option<MlFit>],
    basins: &[Vec<Vec<f64>>],
    curves: &[Curve],
    settings: &FitSettings,
    ml: &MlOptions,
    dc: &DiagnoseConfig,
    shapes: &SpecimenShapes,
    reading: &GrowingError,
    b: usize,
    active: &[bool],
) -> Vec<f64> {
    let base = fits[0].as_ref().expect("base fitted");
    let (data, mut rng, drawn) = null_data(specs, base, curves, settings, dc, shapes, reading, b);
    let n_ext = specs.len() - 1;
    let mut starts = basins[0].clone();
    for _ in 0..dc.replicate_starts {
        starts.push(specs[0].random_start(&mut rng));
    }
    // Random starts of the extensions, drawn before any fit (fixed stream use).
    let ext_random: Vec<Vec<Vec<f64>>> = specs[1..]
        .iter()
        .map(|s| {
            (0..dc.replicate_starts)
                .map(|_| s.random_start(&mut rng))
                .collect()
        })
        .collect();
    // New specimens: their effects start at zero, the scatter at the data's estimate.
    let fresh = base
        .specimen
        .as_ref()
        .map(|sp| EffectStart::fresh(sp.kinds.clone(), sp.scatter.clone(), curves.len()));
    let (b0, _) = fit_best(
        &specs[0],
        &data,
        &starts,
        basins[0].len(),
        fresh.as_ref(),
        settings,
        ml,
    );
    let b0 = with_drawn_start(
        b0,
        &specs[0],
        &data,
        &base.params,
        drawn.as_ref(),
        settings,
        ml,
    );
    let ng = gof::SHAPES.len();
    let mut out = vec![f64::NAN; n_ext + ng + 1];
    let Some(b0) = b0 else {
        out[n_ext + ng] = 1.0; // base refit failed
        return out;
    };
    let base_names = specs[0].names();
    let mut rep_fits: Vec<Option<MlFit>> = vec![Some(b0)];
    for (k, spec) in specs[1..].iter().enumerate() {
        if !active[k] {
            // Decided not significant (Besag–Clifford): not refitted any more.
            rep_fits.push(None);
            continue;
        }
        let b0 = rep_fits[0].as_ref().expect("base refitted");
        // From the replicate's base optimum with the extension switched off (a nested
        // extension starts at the base's likelihood and keeps its start if it finds nothing
        // better), with it slightly on where the likelihood is flat around that start (the
        // data's fits use the same probes), and from the extension's data optimum.
        let from_base = spec.start_from_base(&base_names, &b0.params);
        let mut st = spec.probe_from(&from_base);
        st.insert(0, from_base);
        st.extend(basins[k + 1].iter().take(1).cloned());
        let warm = st.len();
        st.extend(ext_random[k].iter().cloned());
        let from = b0.specimen.as_ref().map(EffectStart::from);
        let ml_ext = ext_options(ml, Some(b0));
        let (fk, _) = fit_best(spec, &data, &st, warm, from.as_ref(), settings, &ml_ext);
        rep_fits.push(fk);
    }
    // The same cross-start as on the data, among the extensions still refitted.
    cross_start(specs, &mut rep_fits, &data, settings, ml);
    let b0 = rep_fits[0].as_ref().expect("base refitted");
    for k in 0..n_ext {
        out[k] = rep_fits[k + 1]
            .as_ref()
            .filter(|f| f.ok())
            .map_or(f64::NAN, |f| b0.neg2ll - f.neg2ll);
    }
    let gs = gof::all(
        &data,
        b0.residuals.as_ref().expect("fitted"),
        &b0.noise,
        ml.lifetime_sd_floor,
    );
    for (g, x) in gs.iter().enumerate() {
        out[n_ext + g] = x.statistic;
    }
    out[n_ext + ng] = 0.0;
    out.push(b0.neg2ll);
    out.extend_from_slice(&b0.params);
    // The scatter the replicate's extensions were held at ([`null_again`] holds it too).
    if let Some(h) = ext_options(ml, Some(b0)).hold_scatter {
        out.extend_from_slice(&h);
    }
    out
}

/// A replicate's likelihood ratio with one start more: the larger of the first run's (`first`,
/// NaN if that refit failed) and the new start's (`None` if its fit failed).
fn again_ratio(first: f64, new: Option<f64>) -> f64 {
    match new {
        Some(v) if !(first >= v) => v,
        _ => first,
    }
}

/// Null replicate `b` again for the extensions marked `again`: the same replicate data, the
/// extension fitted from its [`Recipe`] (a fresh start), and its likelihood ratio the larger
/// of `first`'s (that replicate's row from [`null_replicate`]) and the new fit's against the
/// base refit recorded there. The other statistics are NaN; a failed base refit stays failed.
#[allow(clippy::too_many_arguments)]
fn null_again(
    specs: &[Spec],
    base: &MlFit,
    recipes: &[Option<Recipe>],
    first: &[f64],
    curves: &[Curve],
    settings: &FitSettings,
    ml: &MlOptions,
    dc: &DiagnoseConfig,
    shapes: &SpecimenShapes,
    reading: &GrowingError,
    b: usize,
    again: &[bool],
) -> Vec<f64> {
    let n_ext = specs.len() - 1;
    let ng = gof::SHAPES.len();
    let mut out = vec![f64::NAN; n_ext + ng + 1];
    out[n_ext + ng] = 1.0;
    if first.len() <= n_ext + ng + 1 || first[n_ext + ng] > 0.0 {
        return out; // the base refit failed there
    }
    let np = specs[0].names().len();
    let (b0_ll, b0_params) = (
        first[n_ext + ng + 1],
        &first[n_ext + ng + 2..(n_ext + ng + 2 + np).min(first.len())],
    );
    let held = &first[(n_ext + ng + 2 + np).min(first.len())..];
    let ml_ext = MlOptions {
        hold_scatter: (held.len() == 3).then(|| [held[0], held[1], held[2]]),
        ..*ml
    };
    let (data, _, _) = null_data(specs, base, curves, settings, dc, shapes, reading, b);
    let base_names = specs[0].names();
    for k in (0..n_ext).filter(|&k| again[k]) {
        let spec = &specs[k + 1];
        let start = match &recipes[k + 1] {
            Some(Recipe::Grid(g)) => spec
                .grid_from(&spec.start_from_base(&base_names, b0_params))
                .get(*g)
                .cloned(),
            Some(Recipe::Fixed(x)) => Some(x.clone()),
            _ => None,
        };
        let Some(start) = start else {
            out[k] = first[k];
            continue;
        };
        let (f, _) = fit_best(spec, &data, &[start], 0, None, settings, &ml_ext);
        out[k] = again_ratio(first[k], f.filter(|f| f.ok()).map(|f| b0_ll - f.neg2ll));
    }
    out[n_ext + ng] = 0.0;
    out
}

/// The specimens' own shapes a parametric bootstrap gives its new specimens
/// ([`bootstrap::SpecimenShapes`]), from the goodness of fit `gs` of the fitted model: with
/// specimen effects those of [`gof::Shape::CommonBeyondSpecimens`]'s alternative — how the
/// specimens differ in shape beyond any misfit they share, so that a misfit shared by every
/// specimen (a model's error) is not drawn as the specimens' own — and none without specimen
/// effects (a specimen is then the population, and its shape the model's error). Without
/// them the likelihood ratios' null drew specimens that differ by the fitted factors only,
/// and an extension that bends each specimen's tertiary stage gained on the data by their
/// own shapes and on no replicate (session 52: 3 false alarms in 6 null sets whose specimens
/// differ in coarsening rate).
fn null_shapes(gs: &[gof::Gof], effects: bool) -> SpecimenShapes {
    if !effects {
        return SpecimenShapes::none();
    }
    gs.iter()
        .find(|g| g.shape == gof::Shape::CommonBeyondSpecimens)
        .map_or_else(SpecimenShapes::none, SpecimenShapes::from_gof)
}

/// How many null replicates `dc` asks for: [`DiagnoseConfig::bootstrap`] for every test, up
/// to [`DiagnoseConfig::bootstrap_extended`] for a test whose p-value is then at most α/2.
pub fn depth_of(dc: &DiagnoseConfig) -> bootstrap::Depth {
    bootstrap::Depth::new(dc.bootstrap, dc.most_replicates(), dc.alpha / 2.0)
}

/// Goodness-of-fit bootstrap of one fitted model: replicates under it, refitted by it.
#[allow(clippy::too_many_arguments)]
fn gof_bootstrap(
    spec: &Spec,
    fit: &MlFit,
    basins: &[Vec<f64>],
    curves: &[Curve],
    settings: &FitSettings,
    ml: &MlOptions,
    dc: &DiagnoseConfig,
    hooks: &Hooks,
) -> Result<Vec<GofTest>> {
    let gs: Vec<gof::Gof> = gof::all(
        curves,
        fit.residuals.as_ref().expect("fitted"),
        &fit.noise,
        ml.lifetime_sd_floor,
    );
    let on: Vec<bool> = gof::SHAPES
        .iter()
        .map(|sh| gof::decides(*sh, ml.specimen.any()))
        .collect();
    let observed: Vec<f64> = gs
        .iter()
        .zip(&on)
        .map(|(g, f)| if *f { g.statistic } else { f64::NAN })
        .collect();
    let reading = bootstrap::reading_error(curves, spec.model.as_ref(), &spec.space, fit, settings);
    let shapes = null_shapes(&gs, ml.specimen.any());
    let key = hooks::model_key(&(&spec.name, fit, basins, gof::SHAPES, &shapes.pool));
    let phase = "cause's goodness-of-fit bootstrap";
    let none = vec![false; observed.len()];
    let sampled = hooks.sequential(
        phase,
        GOF_STREAM,
        &key,
        &observed,
        &none,
        depth_of(dc).with_family_stop(dc.alpha),
        |b, _| {
            let mut rng = bootstrap::replicate_rng(dc.seed, GOF_STREAM, b);
            let (data, drawn) = bootstrap::replicate_hier_drawn(
                curves,
                spec.model.as_ref(),
                fit,
                &reading,
                settings,
                &shapes,
                &mut rng,
            );
            let mut st = basins.to_vec();
            for _ in 0..dc.replicate_starts {
                st.push(spec.random_start(&mut rng));
            }
            let fresh = fit
                .specimen
                .as_ref()
                .map(|sp| EffectStart::fresh(sp.kinds.clone(), sp.scatter.clone(), curves.len()));
            let (f, _) = fit_best(spec, &data, &st, basins.len(), fresh.as_ref(), settings, ml);
            let f = with_drawn_start(f, spec, &data, &fit.params, drawn.as_ref(), settings, ml);
            match f.as_ref() {
                Some(f) => gof::all(
                    &data,
                    f.residuals.as_ref().expect("fitted"),
                    &f.noise,
                    ml.lifetime_sd_floor,
                )
                .iter()
                .map(|g| g.statistic)
                .collect(),
                None => vec![f64::NAN; gof::SHAPES.len()],
            }
        },
    )?;
    let p: Vec<f64> = gs
        .iter()
        .enumerate()
        .map(|(k, g)| bootstrap::p_value(g.statistic, &sampled.column(k)))
        .collect();
    let (_, adj) = decide::holm_among(&p, &on, dc.alpha);
    Ok(gs
        .into_iter()
        .enumerate()
        .map(|(k, g)| GofTest {
            model: spec.name.clone(),
            gof: g,
            p_value: p[k],
            p_holm: Some(adj[k]),
            replicates: sampled.computed[k],
            decides: on[k],
        })
        .collect())
}

/// The data fits' `dc.starts` fresh starts of `spec`: a Latin hypercube of its free
/// constants' unit box seeded by `dc.seed`, in physical units.
fn fresh_starts(spec: &Spec, dc: &DiagnoseConfig) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(dc.seed);
    latin_hypercube(dc.starts, spec.space.n_free(), &mut rng)
        .into_iter()
        .map(|u| {
            let mut x = vec![0.0; spec.space.len()];
            spec.space.from_unit(&u, &mut x);
            x
        })
        .collect()
}

/// The share ρ of the reading error that the means of `curves`' groups do not shrink
/// ([`crate::data::ReadingGroups::misfit_share`], [`crate::errmodel::estimate_misfit_share`]),
/// from the residuals of the base model's best fit (`spec`, at ρ = 0) from `start` (the
/// initial guess) and the data fits' Latin-hypercube starts, its best polished with the
/// specimen factors `ml` asks for; `None` where no start could be fitted. Without the
/// polish (sessions 74–75) each curve's own creep rate was left in its residuals, a misfit
/// shared by every reading of a group that averaging does not shrink: on session 75's 16
/// logged null sets with white reading error ρ̂ was 0.70–0.99 where the truth's residuals
/// give 0.
fn group_misfit_share(
    spec: &Spec,
    curves: &[Curve],
    start: Vec<f64>,
    dc: &DiagnoseConfig,
    settings: &FitSettings,
    ml: &MlOptions,
) -> Option<f64> {
    let mut starts = vec![start];
    starts.extend(fresh_starts(spec, dc));
    let best = fit_best(spec, curves, &starts, 0, None, settings, ml).0?;
    let res = best.residuals.as_ref()?;
    Some(crate::errmodel::misfit_share_of(curves, res))
}

/// Diagnose `data` with the models of `setup` ([`crate::config::RunConfig::diagnose_setup`]) and the
/// `[diagnose]` settings `dc` (the configuration's, with the command line's overrides).
pub fn diagnose(setup: &DiagnoseSetup, data: &Dataset, dc: &DiagnoseConfig) -> Result<Diagnosis> {
    diagnose_observed(setup, data, dc, &Hooks::default())
}

/// The likelihood options of the data fits on curves `reduced`: the configured specimen
/// effects (those the curves can carry) at the configured scatter criterion, the scatter free.
fn data_options(setup: &DiagnoseSetup, reduced: &[Curve], dc: &DiagnoseConfig) -> MlOptions {
    MlOptions {
        lifetime_sd_floor: dc.lifetime_sd_floor,
        white_first: true,
        specimen: setup
            .specimen_effects
            .resolve(reduced, setup.specimen_scatter)
            .0
            .with_scatter(setup.specimen_scatter),
        hold_scatter: None,
    }
}

/// The initial guess on curves `reduced`: the family's procedure on its bare model (per
/// temperature with the laws), in the bare model's constants.
fn bare_guess(setup: &DiagnoseSetup, reduced: &[Curve]) -> crate::model::guess::Guess {
    initial_guess(
        setup.bare.model.as_ref(),
        reduced,
        &setup.bare.space,
        setup.settings.omega_f,
        &setup.settings.ode,
    )
}

/// [`diagnose`] reporting its phases to `hooks.observer` (and stopping when it asks to), its
/// bootstrap replicates journaled in (and resumed from) `hooks.journal`.
pub fn diagnose_observed(
    setup: &DiagnoseSetup,
    data: &Dataset,
    dc: &DiagnoseConfig,
    hooks: &Hooks,
) -> Result<Diagnosis> {
    dc.validate()
        .map_err(|m| Error::Diagnose(format!("{}: {}", m.field, m.what)))?;
    let t0 = Instant::now();
    let lm0 = LmCounts::now();
    let reduced: Vec<Curve> = data
        .curves
        .iter()
        .map(|c| crate::data::reduce(c, dc.max_points, dc.reduction))
        .collect();
    let settings = setup.settings;
    let ml = data_options(setup, &reduced, dc);
    // Whether the configuration fits specimen factors (a base refitted without them,
    // [`singular_scatter`], is journaled under a key of its own).
    let setup_effects = ml.specimen.any();
    let specs = &setup.variants;

    // The initial guess (the family's procedure on its bare model, per temperature with the
    // laws), extended by name.
    let khd_names = setup.bare.names();
    let guess = bare_guess(setup, &reduced);
    // Groups of different sizes (`strain_means`, `misfit_share = "estimate"`): the share of
    // the reading error their means do not shrink, estimated once from the base model's fit
    // at white reading error and held for the whole diagnosis (data fits, replicates' draws
    // and refits).
    let misfit_share = dc
        .misfit_share
        .estimated(dc.reduction, reduced.iter().any(|c| c.groups.is_some()))
        .then(|| {
            hooks.phase("the group means' error", 1);
            let start = specs[0].start_from_base(&khd_names, &guess.params);
            group_misfit_share(&specs[0], &reduced, start, dc, &settings, &ml)
        })
        .flatten();
    let binned_curves: Vec<Curve> = match misfit_share {
        Some(rho) if rho > 0.0 => reduced.iter().map(|c| c.with_misfit_share(rho)).collect(),
        _ => reduced,
    };
    let curves = &binned_curves;

    // 1. Fits on the data.
    let mut fits: Vec<Option<MlFit>> = Vec::with_capacity(specs.len());
    let mut failed_starts = Vec::with_capacity(specs.len());
    let mut start_sets: Vec<Vec<Vec<f64>>> = Vec::with_capacity(specs.len());
    let mut basins: Vec<Vec<Vec<f64>>> = Vec::with_capacity(specs.len());
    hooks.phase("fits on the data", specs.len());
    // One model's fits: the base's optimum (`base`) seeds each extension's starts, so the
    // base is fitted first and the extensions, independent of each other, in parallel.
    let fit_model = |i: usize,
                     base: Option<&MlFit>,
                     ml: &MlOptions|
     -> Result<(hooks::ModelFits, Vec<Vec<f64>>)> {
        let spec = &specs[i];
        let mut starts = vec![spec.start_from_base(&khd_names, &guess.params)];
        if i > 0 {
            if let Some(b) = base {
                let from_base = spec.start_from_base(&specs[0].names(), &b.params);
                let probes = spec.probe_from(&from_base);
                starts.extend(spec.grid_from(&from_base));
                starts.splice(0..0, std::iter::once(from_base).chain(probes));
            }
        }
        starts.extend(fresh_starts(spec, dc));
        // Journaled per model: the fits take about half of a diagnosis (measured on Alloy
        // 617: 110 s of 235 s), too long to redo after an interruption.
        // A base refitted without the specimen factors the configuration asks for (their
        // scatter at zero, [`singular_scatter`]) is journaled apart from the fit with them.
        let key = if ml.specimen.any() == setup_effects {
            hooks::fits_key(i, &spec.name, &starts)
        } else {
            hooks::fits_key(
                i,
                &format!("{}/without-specimen-factors", spec.name),
                &starts,
            )
        };
        if let Some(done) = hooks.fits_done(&key) {
            return Ok((done, starts));
        }
        hooks.check("fits on the data")?;
        // The base optimum (extension off) is polished directly: a nested extension then
        // never fits worse than the base; so are the probes (the extension slightly on,
        // [`ext::probe_starts`]), which the null replicates refit from too; every other
        // start is fresh. An extension with no
        // constant of its own (constant_load) is not nested: the base optimum is no optimum
        // of it, so it is a fresh start too, fitted both ways. Measured (set 60138 of the
        // evaluation battery, a hidden constant load of λ 31.9): polished directly from the
        // base optimum, the AR(1) fit took the misfit for noise (φ 0.995) and ended 551 units
        // of −2 ln L above the base; no other start found the basin of the truth.
        let warm = if i > 0 && base.is_some() && !spec.extra.is_empty() {
            1 + ext::probe_starts(&spec.name).len()
        } else {
            0
        };
        // The base optimum's specimen effects start the extension's warm fit: a nested
        // extension then starts at the base's likelihood.
        let warm_effects = base
            .filter(|_| i > 0)
            .and_then(|f| f.specimen.as_ref())
            .map(EffectStart::from);
        // An extension's fits at the base's scatter where it is held ([`ext_options`]).
        let ml = if i > 0 { ext_options(ml, base) } else { *ml };
        let fitted = fit_all(
            spec,
            curves,
            &starts,
            warm,
            warm_effects.as_ref(),
            &settings,
            &ml,
        );
        let failed = fitted.iter().filter(|(_, f)| !f.ok()).count();
        // The fresh start whose fit is best: the replicates repeat it ([`Recipe`]).
        let recipe = fitted
            .iter()
            .filter(|(j, f)| *j >= warm && f.ok())
            .min_by(|a, b| a.1.neg2ll.total_cmp(&b.1.neg2ll))
            .map(|(j, _)| *j);
        let (warm_fits, fresh): (Vec<_>, Vec<_>) = fitted.into_iter().partition(|(j, _)| *j < warm);
        let mut all: Vec<MlFit> = warm_fits.into_iter().map(|(_, f)| f).collect();
        let fresh: Vec<MlFit> = fresh.into_iter().map(|(_, f)| f).collect();
        all.extend(polish(
            spec,
            curves,
            &fresh,
            dc.replicate_basins,
            &settings,
            &ml,
        ));
        let basins = distinct_optima(spec, &all, dc.replicate_basins);
        let best =
            all.into_iter()
                .filter(|f| f.ok())
                .reduce(|a, b| if b.neg2ll < a.neg2ll { b } else { a });
        let best = best.map(|mut f| {
            crate::likelihood::scatter_intervals(
                &mut f,
                spec.model.as_ref(),
                curves,
                &spec.space,
                &settings,
                &ml,
            );
            f
        });
        if i == 0 && best.is_none() {
            return Err(Error::Diagnose(format!(
                "the base model could not be fitted from any of {} starts",
                starts.len()
            )));
        }
        let done = hooks::ModelFits {
            best,
            failed,
            basins,
            recipe,
        };
        hooks.fits_finished(&key, &done)?;
        Ok((done, starts))
    };
    let base_out = fit_model(0, None, &ml)?;
    // Every kind's scatter at zero: the diagnosis goes on without specimen factors, the
    // base refitted plain ([`singular_scatter`]).
    let singular = singular_scatter(
        matches!(
            setup.specimen_effects,
            crate::config::SpecimenEffects::Auto(_)
        ),
        &ml,
        base_out.0.best.as_ref(),
    );
    let (ml, base_out) = if singular {
        let plain = MlOptions {
            specimen: crate::likelihood::SpecimenOptions::NONE,
            ..ml
        };
        let out = fit_model(0, None, &plain)?;
        (plain, out)
    } else {
        (ml, base_out)
    };
    let ext_out: Vec<_> = (1..specs.len())
        .into_par_iter()
        .map(|i| fit_model(i, base_out.0.best.as_ref(), &ml))
        .collect::<Result<_>>()?;
    let mut recipes: Vec<Option<Recipe>> = Vec::with_capacity(specs.len());
    for (i, (done, starts)) in std::iter::once(base_out).chain(ext_out).enumerate() {
        fits.push(done.best);
        failed_starts.push(done.failed);
        basins.push(done.basins);
        recipes.push(
            done.recipe
                .filter(|_| i > 0)
                .map(|j| recipe_of(&specs[i], &starts, j)),
        );
        start_sets.push(starts);
    }
    for j in cross_start(specs, &mut fits, curves, &settings, &ml) {
        let f = fits[j].as_mut().expect("replaced by a fit");
        let spec = &specs[j];
        crate::likelihood::scatter_intervals(
            f,
            spec.model.as_ref(),
            curves,
            &spec.space,
            &settings,
            &ml,
        );
        // The new optimum leads the warm starts of the bootstrap's refits.
        basins[j].insert(0, f.params.clone());
        basins[j].truncate(dc.replicate_basins.max(1));
    }
    let mut phase = PhaseTimes {
        fits: t0.elapsed().as_secs_f64(),
        ..PhaseTimes::default()
    };
    let lm_fits = LmCounts::now();
    let mut work = PhaseWork {
        fits: lm_fits.since(&lm0),
        ..PhaseWork::default()
    };
    let base_fit = fits[0].clone().expect("checked");
    let n_ext = specs.len() - 1;

    // 2. Observed statistics.
    let lr_obs: Vec<f64> = (1..specs.len())
        .map(|k| {
            fits[k]
                .as_ref()
                .map_or(f64::NAN, |f| base_fit.neg2ll - f.neg2ll)
        })
        .collect();
    let gof_obs: Vec<gof::Gof> = gof::all(
        curves,
        base_fit.residuals.as_ref().expect("fitted"),
        &base_fit.noise,
        ml.lifetime_sd_floor,
    );
    let ng = gof_obs.len();

    // 3. Null bootstrap under the base model. Refits start next to their optimum, where
    //    geodesic acceleration costs twice per iteration and saves no iterations (measured on
    //    the 560 °C data: 36 iterations in 5 ms without, 32 in 10 ms with). They stop when
    //    the gain still to come is below [`REFIT_GAIN_TO_COME`]'s δ.
    let warm = FitSettings {
        lm: crate::lsq::LmOptions {
            geodesic: None,
            gain_to_come: Some(REFIT_GAIN_TO_COME),
            ..settings.lm
        },
        ..settings
    };
    let mut observed = lr_obs.clone();
    observed.extend(gof_obs.iter().map(|g| g.statistic));
    // The tests of the family: every extension's, and the goodness-of-fit shapes that decide
    // for this model. A test reported beside (NaN observed for the bootstrap's early stop) is
    // computed on every replicate the run makes and never holds the run up.
    let effects = ml.specimen.any();
    let in_family: Vec<bool> = (0..n_ext + ng)
        .map(|k| k < n_ext || gof::decides(gof::SHAPES[k - n_ext], effects))
        .collect();
    let observed_seq: Vec<f64> = observed
        .iter()
        .zip(&in_family)
        .map(|(o, f)| if *f { *o } else { f64::NAN })
        .collect();
    // The null's specimens differ in shape as much as the data's do beyond what they share.
    let shapes = null_shapes(&gof_obs, effects);
    // The null's reading error, estimated once from the base fit (every replicate draws it).
    let reading = bootstrap::reading_error(
        curves,
        specs[0].model.as_ref(),
        &specs[0].space,
        fits[0].as_ref().expect("base fitted"),
        &warm,
    );
    let key = hooks::model_key(&(&fits, &basins, &recipes, gof::SHAPES, &shapes.pool));
    // An extension decided not significant (STOP_EXCEEDANCES null ratios at or above its
    // own) is not refitted in later replicates. With specimen effects a replicate's
    // cross-start then starts the base from the best of the extensions still refitted: it
    // improved a null base in 43 of 159 replicates of a null set with scatter, by 0.001 to
    // 0.066 in −2 ln L, against ratios of 1–10 needed to reject (docs/SPECIMENS.md, "Decided
    // extensions are dropped with specimen effects too").
    let droppable: Vec<bool> = (0..n_ext + ng).map(|k| k < n_ext).collect();
    let sampled = hooks.sequential(
        "null bootstrap",
        NULL_STREAM,
        &key,
        &observed_seq,
        &droppable,
        depth_of(dc).with_family_stop(dc.alpha),
        |b, active| {
            null_replicate(
                specs, &fits, &basins, curves, &warm, &ml, dc, &shapes, &reading, b, active,
            )
        },
    )?;
    // The tests that reject there (Holm, the whole family), bootstrapped again on the same
    // replicates with the fresh start that found the data's best fit ([`Recipe`]) added to
    // their refits ([`null_again`]: a replicate's ratio becomes the larger of the two fits').
    // A ratio can only grow so, a p-value only grow, and Holm's procedure rejects no test
    // more when p-values grow: a test not rejected with the replicates' own starts would not
    // be rejected with that start added either. So only the rejecting ones are run again:
    // running every replicate's refits with that start cost 3–4 times as much (measured:
    // 160–210 s against 40–70 s on three null sets with specimen scatter). Without it, the
    // data's ratio was above every replicate's for want of that start.
    let first_p: Vec<f64> = observed
        .iter()
        .enumerate()
        .map(|(k, o)| bootstrap::p_value(*o, &sampled.column(k)))
        .collect();
    let (rejects, _) = decide::holm_among(&first_p, &in_family, dc.alpha);
    let again: Vec<bool> = (0..n_ext + ng)
        .map(|k| {
            k < n_ext
                && rejects[k]
                && matches!(recipes[k + 1], Some(Recipe::Grid(_) | Recipe::Fixed(_)))
        })
        .collect();
    let mut again_effect: Vec<Option<bootstrap::AgainEffect>> = vec![None; n_ext];
    let t_again = std::time::Instant::now();
    let lm_again = LmCounts::now();
    let sampled = if again.iter().any(|a| *a) {
        let observed_again: Vec<f64> = observed
            .iter()
            .zip(&again)
            .map(|(o, a)| if *a { *o } else { f64::NAN })
            .collect();
        // Tests not run again start decided (NaN observed); the others are refitted each on
        // its own here (no cross-start joins them), so each drops once decided.
        let droppable_again = vec![true; n_ext + ng];
        let second = hooks.sequential(
            "null bootstrap, significant tests again",
            NULL_STREAM,
            &hooks::model_key(&(&key, &again)),
            &observed_again,
            &droppable_again,
            depth_of(dc),
            |b, active| {
                let redo: Vec<bool> = (0..n_ext + ng).map(|k| again[k] && active[k]).collect();
                null_again(
                    specs,
                    fits[0].as_ref().expect("base fitted"),
                    &recipes,
                    sampled.reps.get(b).map_or(&[][..], |r| r.as_slice()),
                    curves,
                    &warm,
                    &ml,
                    dc,
                    &shapes,
                    &reading,
                    b,
                    &redo,
                )
            },
        )?;
        for k in (0..n_ext).filter(|&k| again[k]) {
            // Over the second run's replicates, all of which the first computed too (a test
            // that rejected was never dropped from the first run).
            again_effect[k] = Some(bootstrap::again_effect(
                &sampled.column(k),
                &second.column(k),
                observed[k],
            ));
        }
        bootstrap::merged(sampled, &second, &again)
    } else {
        sampled
    };
    phase.null_bootstrap = t0.elapsed().as_secs_f64() - phase.fits;
    phase.null_again = t_again.elapsed().as_secs_f64();
    let lm_null = LmCounts::now();
    work.null_bootstrap = lm_null.since(&lm_fits);
    work.null_again = lm_null.since(&lm_again);
    let reps = &sampled.reps;
    let failed_base_refits = reps.iter().filter(|r| r[n_ext + ng] > 0.0).count();
    let col = |k: usize| -> Vec<f64> { sampled.column(k) };
    let p_ext: Vec<f64> = (0..n_ext)
        .map(|k| bootstrap::p_value(lr_obs[k], &col(k)))
        .collect();
    let p_gof: Vec<f64> = gof_obs
        .iter()
        .enumerate()
        .map(|(g, o)| bootstrap::p_value(o.statistic, &col(n_ext + g)))
        .collect();
    let spread: Vec<Vec<f64>> = (0..n_ext)
        .map(|j| {
            (0..n_ext)
                .map(|k| bootstrap::spread95(&col(j), &col(k)))
                .collect()
        })
        .collect();

    // 4. Decision, stage 1.
    let mut cands: Vec<Candidate> = specs
        .iter()
        .zip(&fits)
        .zip(&failed_starts)
        .map(|((s, f), &n)| candidate(s, curves, f.as_ref(), n, &warm))
        .collect();
    let select_input = SelectInput {
        alpha: dc.alpha,
        extensions: (0..n_ext)
            .map(|k| ExtensionEvidence {
                name: specs[k + 1].name.clone(),
                p_value: p_ext[k],
                aic: cands[k + 1].aic,
            })
            .collect(),
        base_gof_p: p_gof.clone(),
        base_gof_decides: in_family[n_ext..].to_vec(),
        spread,
    };
    let sel = decide::select(&select_input);
    // Stage 2: the best extension's own goodness of fit.
    let cause_gof: Vec<GofTest> = match sel.best {
        Some(b) => gof_bootstrap(
            &specs[b + 1],
            fits[b + 1]
                .as_ref()
                .expect("rejected candidates are fitted"),
            &basins[b + 1],
            curves,
            &warm,
            &ml,
            dc,
            hooks,
        )?,
        None => vec![],
    };
    let cause_p: Vec<f64> = cause_gof
        .iter()
        .filter(|g| g.decides)
        .map(|g| g.p_value)
        .collect();
    let (verdict, cause_idx) = decide::verdict(&sel, &cause_p, dc.alpha);
    let t_loo = Instant::now();
    phase.cause_bootstrap = t0.elapsed().as_secs_f64() - phase.fits - phase.null_bootstrap;
    let lm_loo = LmCounts::now();
    work.cause_bootstrap = lm_loo.since(&lm_null);

    // 5. Leave-one-stress-out, explanation, assembly.
    hooks.phase("leave-one-stress-out", specs.len());
    let loos: Vec<Loo> = specs
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let params = fits[i].as_ref().map(|f| &f.params);
            hooks.loo(i, &s.name, params, &start_sets[i], || match params {
                Some(p) => leave_one_stress_out(s, curves, p, &start_sets[i], &settings, &ml),
                None => Loo {
                    rmse: f64::NAN,
                    lifetime_err_pct: f64::NAN,
                    failed_folds: vec![],
                },
            })
        })
        .collect::<Result<_>>()?;
    phase.loo = t_loo.elapsed().as_secs_f64();
    work.loo = LmCounts::now().since(&lm_loo);
    let n_eff = base_fit
        .noise
        .effective_n(base_fit.residuals.as_ref().expect("fitted"));
    for (i, c) in cands.iter_mut().enumerate() {
        c.loo_rmse = loos[i].rmse;
        c.loo_lifetime_err_pct = loos[i].lifetime_err_pct;
        c.loo_failed_folds = loos[i].failed_folds.clone();
        c.gain_pct = 100.0 * (loos[0].rmse - loos[i].rmse) / loos[0].rmse;
        if i > 0 {
            let k = i - 1;
            c.lr = lr_obs[k];
            c.p_value = Some(p_ext[k]);
            c.p_holm = Some(sel.adjusted[k]);
            c.lr_critical = bootstrap::critical_value(&col(k), dc.alpha);
            c.null_replicates = Some(sampled.computed[k]);
            c.null_again = again[k];
            c.null_again_effect = again_effect[k];
            c.significant = sel.rejected[k];
            c.delta_bic = -lr_obs[k] + (c.k as f64 - cands_k0(specs)) * n_eff.ln();
        } else {
            c.lr = 0.0;
            c.delta_bic = 0.0;
        }
    }
    let mut base = cands.remove(0);
    base.lr = 0.0;
    let evidence = findings(&base.curves, base_fit.noise.lifetime_sd);
    let cause = cause_idx.map(|k| specs[k + 1].name.clone());
    let closest = match (verdict, sel.best) {
        (Verdict::Unexplained, Some(b)) => Some(specs[b + 1].name.clone()),
        _ => None,
    };
    let indistinguishable = if cause.is_some() {
        sel.indistinguishable
            .iter()
            .map(|&(i, d, s)| Indistinguishable {
                name: specs[i + 1].name.clone(),
                delta_aic: d,
                spread95: s,
            })
            .collect()
    } else {
        vec![]
    };
    let base_gof: Vec<GofTest> = gof_obs
        .into_iter()
        .enumerate()
        .map(|(g, o)| GofTest {
            model: "base".into(),
            gof: o,
            p_value: p_gof[g],
            p_holm: Some(sel.base_gof_adjusted[g]),
            replicates: sampled.computed[n_ext + g],
            decides: in_family[n_ext + g],
        })
        .collect();
    let mut decision = decision_words(&cands, &sel, &base_gof, &cause_gof, verdict, dc);
    if singular {
        decision.insert(
            0,
            "Specimen factors: the base fit estimates every kind's scatter beyond the stress \
             trend at zero, so every model is compared at zero scatter, without specimen \
             factors (the base refitted so), and the bootstrap draws identical specimens."
                .into(),
        );
    }
    let failed_extension_refits = (0..n_ext)
        .map(|k| {
            (
                specs[k + 1].name.clone(),
                reps[..sampled.computed[k]]
                    .iter()
                    .filter(|r| r[k].is_nan() && r[n_ext + ng] == 0.0)
                    .count(),
            )
        })
        .collect();
    // Per test: its failed refits among the replicates it was computed on (a NaN statistic:
    // the base refit failed there, or the extension's).
    let failed_per_test: Vec<(String, usize, usize)> = (0..n_ext + ng)
        .map(|k| {
            let name = if k < n_ext {
                specs[k + 1].name.clone()
            } else {
                format!(
                    "base {} goodness of fit",
                    shape_name(gof::SHAPES[k - n_ext])
                )
            };
            let n = sampled.computed[k];
            (name, reps[..n].iter().filter(|r| r[k].is_nan()).count(), n)
        })
        .collect();
    let labels: Vec<String> = curves.iter().map(Curve::label).collect();
    let cautions: Vec<String> = [
        base.noise
            .as_ref()
            .and_then(|n| decide::absorbed_misfit_caution(&n.phi, &n.strain_sd_pct)),
        // A curve the base's reading error writes off: the tests see nothing of its shape.
        base.noise.as_ref().and_then(|n| {
            let largest: Vec<f64> = curves.iter().map(|c| 100.0 * c.largest_strain()).collect();
            crate::fit::written_off_caution(&labels, &n.strain_sd_pct, &largest)
        }),
        // A base fit that misses every life by 10×, or some by 5×, or more: the tests judge a fit
        // that has given those lives up.
        crate::fit::lives_caution(&labels, &base.lifetime_errs_pct),
        decide::failed_refits_caution(&failed_per_test, dc.alpha),
        decide::one_draw_caution(
            &select_input,
            &sel,
            &lr_obs,
            &sampled.computed[..n_ext],
            dc.bootstrap,
            dc.most_replicates() > dc.bootstrap,
        ),
        sel.best.and_then(|b| {
            let tests: Vec<decide::CauseTest> = cause_gof
                .iter()
                .filter(|g| g.decides)
                .map(|g| decide::CauseTest {
                    name: shape_name(g.gof.shape).to_string(),
                    p_value: g.p_value,
                    replicates: g.replicates,
                })
                .collect();
            decide::one_draw_cause_caution(
                &specs[b + 1].name,
                &tests,
                dc.alpha,
                dc.bootstrap,
                dc.most_replicates() > dc.bootstrap,
            )
        }),
        decide::unconverged_fits_caution(
            &std::iter::once(&base)
                .chain(&cands)
                .filter_map(|c| c.termination.map(|t| (c.name.clone(), t)))
                .collect::<Vec<_>>(),
        ),
        base.specimen.as_ref().and_then(|sp| {
            let kinds: Vec<&str> = sp.kinds.iter().map(|k| k.describe()).collect();
            decide::specimen_factors_caution(
                crate::specimen::has_replicates(curves),
                ml.specimen.beyond_trend,
                &kinds,
                &sp.effects,
            )
        }),
        // Only with specimen effects: without them the shapes beyond specimen shapes are
        // reported beside, the null draws no shapes, and the caution's words would not hold.
        decide::specimen_shapes_caution(
            cands.iter().any(|c| c.significant),
            base_gof
                .iter()
                .filter(|g| effects && g.gof.shape.beyond_specimens())
                .map(|g| g.gof.specimen_shape_sd_pct)
                .filter(|v| v.is_finite())
                .fold(f64::NAN, f64::max),
        ),
    ]
    .into_iter()
    .flatten()
    .collect();
    let caution = (!cautions.is_empty()).then(|| cautions.join(". Also: "));
    Ok(Diagnosis {
        verdict,
        cause,
        closest,
        alpha: dc.alpha,
        evidence,
        base,
        candidates: cands,
        indistinguishable,
        gof: base_gof,
        cause_gof,
        bootstrap: BootstrapInfo {
            replicates: reps.len(),
            max: dc.bootstrap,
            most: depth_of(dc).most(),
            stopped_early: sampled.stopped_early,
            specimen_shape_sd_pct: shapes.sd_pct(),
            failed_base_refits,
            failed_extension_refits,
            null_statistics: failed_per_test
                .iter()
                .enumerate()
                .map(|(k, (name, _, _))| NullColumn {
                    test: name.clone(),
                    observed: observed[k],
                    values: col(k),
                })
                .collect(),
        },
        decision,
        caution,
        specimen_scatter_zero: singular,
        misfit_share,
        settings: dc.clone(),
        wall_s: t0.elapsed().as_secs_f64(),
        phase_s: phase,
        phase_lm: PhaseWork {
            total: LmCounts::now().since(&lm0),
            ..work
        },
    })
}

/// The shape's name in reports.
pub fn shape_name(s: gof::Shape) -> &'static str {
    match s {
        gof::Shape::Common => "common",
        gof::Shape::PerCurve => "per-curve",
        gof::Shape::CommonBeyondSpecimens => "common (beyond specimen shapes)",
        gof::Shape::TrendBeyondSpecimens => "stress/temperature trend (beyond specimen shapes)",
    }
}

/// " (N replicates)" beside a bootstrap p-value: its resolution, 1/(N + 1) — a test decided
/// early, or a run stopped early, reports a p-value from fewer than the run's most.
fn replicates_words(n: Option<usize>) -> String {
    n.map_or(String::new(), |n| {
        format!(" ({n} replicate{})", if n == 1 { "" } else { "s" })
    })
}

/// Number of fitted constants of the base model.
fn cands_k0(specs: &[Spec]) -> f64 {
    specs[0].space.n_free() as f64
}

fn decision_words(
    cands: &[Candidate],
    sel: &decide::Selection,
    base_gof: &[GofTest],
    cause_gof: &[GofTest],
    verdict: Verdict,
    dc: &DiagnoseConfig,
) -> Vec<String> {
    let n_gof = base_gof.iter().filter(|g| g.decides).count();
    let m = cands.len() + n_gof;
    let mut out = vec![format!(
        "Family of {m} tests at α = {} (Holm): {} likelihood-ratio test(s) of an extension against the base model, and {} goodness-of-fit test(s) of the base model.",
        dc.alpha,
        cands.len(),
        n_gof
    )];
    for c in cands {
        out.push(format!(
            "{}: LR {:.2}, bootstrap p = {:.3}{}, Holm-adjusted {:.3} → {}",
            c.name,
            c.lr,
            c.p_value.unwrap_or(f64::NAN),
            replicates_words(c.null_replicates),
            c.p_holm.unwrap_or(f64::NAN),
            if c.significant {
                "rejects the base model"
            } else {
                "not significant"
            }
        ));
    }
    for g in base_gof.iter().filter(|g| !g.decides) {
        out.push(format!(
            "base goodness of fit, {} shape (reported, not part of the family: {}): G {:.1}, bootstrap p = {:.3}{}",
            shape_name(g.gof.shape),
            if g.gof.shape.beyond_specimens() {
                "without specimen effects every curve's own shape is model error"
            } else {
                "with specimen effects a shape of each specimen's own is specimen scatter"
            },
            g.gof.statistic,
            g.p_value,
            replicates_words(Some(g.replicates))
        ));
    }
    for g in base_gof.iter().filter(|g| g.decides) {
        let rejected = g.p_holm.unwrap_or(1.0) <= dc.alpha && sel.base_gof_rejected;
        out.push(format!(
            "base goodness of fit, {} shape: G {:.1}, bootstrap p = {:.3}{}, Holm-adjusted {:.3} → {}",
            shape_name(g.gof.shape),
            g.gof.statistic,
            g.p_value,
            replicates_words(Some(g.replicates)),
            g.p_holm.unwrap_or(f64::NAN),
            if rejected {
                "a misfit beyond the error model remains"
            } else {
                "no misfit of this shape beyond the error model"
            }
        ));
    }
    if let Some(b) = sel.best {
        out.push(format!(
            "lowest AIC among the significant extensions: {}",
            cands[b].name
        ));
    }
    if !cause_gof.is_empty() {
        let fails = decide::holm(
            &cause_gof
                .iter()
                .filter(|g| g.decides)
                .map(|g| g.p_value)
                .collect::<Vec<_>>(),
            dc.alpha,
        )
        .0
        .iter()
        .any(|r| *r);
        out.push(format!(
            "{}'s own goodness of fit: {} → {}",
            cause_gof[0].model,
            cause_gof
                .iter()
                .map(|g| format!(
                    "{} shape G {:.1}, p = {:.3}{}{}",
                    shape_name(g.gof.shape),
                    g.gof.statistic,
                    g.p_value,
                    replicates_words(Some(g.replicates)),
                    if g.decides { "" } else { " (reported only)" }
                ))
                .collect::<Vec<_>>()
                .join("; "),
            if fails {
                "still misfits: not an explanation"
            } else {
                "fits within its error model"
            }
        ));
    }
    out.push(format!("verdict: {}", verdict.as_str()));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RunConfig;
    use crate::data::binned;
    use std::path::Path;

    fn seed_config(extra: &str) -> RunConfig {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(dir.join("configs/560C.toml")).unwrap() + extra;
        RunConfig::from_str(&text, &dir.join("configs/560C.toml")).unwrap()
    }

    /// `strain_means`' misfit share from the base fit, on a generated null set with specimen
    /// scatter and white reading error (180036: 5 logged curves, rate scatter 0.26,
    /// ductility 0.08; its residuals at the true constants and factors give ρ 0, the
    /// example `misfit_share_truth`): 0, so the √m weights hold. Before the base fit was
    /// polished with the specimen factors this gave 0.987 (session 75's null battery).
    #[test]
    fn the_misfit_share_of_a_white_null_set_with_specimen_scatter_is_zero() {
        let dir =
            std::env::temp_dir().join(format!("creepfit-misfit-share-{}", std::process::id()));
        let set = crate::synth::generate_in(
            "set-180036",
            "none",
            None,
            180_036,
            crate::synth::World::Specimens,
        )
        .unwrap();
        assert_eq!(set.truth.noise_phi, 0.0);
        crate::synth::write_set(&set, &dir).unwrap();
        let cfg = RunConfig::load(&dir.join("config.toml")).unwrap();
        let data = cfg.load_data().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let dc = DiagnoseConfig {
            starts: 4,
            ..cfg.diagnose.clone()
        };
        let reduced: Vec<Curve> = data
            .curves
            .iter()
            .map(|c| crate::data::reduce(c, dc.max_points, crate::data::Reduction::StrainMeans))
            .collect();
        assert!(reduced.iter().any(|c| c.groups.is_some()));
        let setup = cfg.diagnose_setup().unwrap();
        let ml = data_options(&setup, &reduced, &dc);
        assert!(ml.specimen.any());
        let spec = &setup.variants[0];
        // diagnose's start: the bare model's initial guess.
        let start = spec.start_from_base(&setup.bare.names(), &bare_guess(&setup, &reduced).params);
        let rho = group_misfit_share(spec, &reduced, start, &dc, &setup.settings, &ml).unwrap();
        assert_eq!(rho, 0.0);
    }

    #[test]
    fn binning_keeps_short_curves_and_follows_the_curve_where_it_bends() {
        let cfg = seed_config("");
        let data = cfg.load_data().unwrap();
        let c = &data.curves[0];
        assert_eq!(binned(c, 60), *c);
        let b = binned(c, 10);
        assert!(b.times_h.len() <= 10);
        assert_eq!(b.times_h[0], c.times_h[0]);
        assert!(b.times_h.windows(2).all(|w| w[0] <= w[1]));
        // A steeply bending logged curve (strain ∝ 1/(1 − t) up to 97 % of life), 2,000
        // points: the binned value at each group's mean time is the curve's there to 5e-4 of
        // the strain, and at least 10 times closer than the plain mean of the group, which is
        // off by about ε''·var(t)/2.
        let times: Vec<f64> = (0..2000).map(|k| 0.97 * k as f64 / 1999.0).collect();
        let f = |t: f64| 0.01 / (1.0 - t);
        let long = Curve {
            times_h: times.clone(),
            strains: times.iter().map(|&t| f(t)).collect(),
            ..c.clone()
        };
        // A curve too short for max_points groups of 4: fewer, larger groups, none under 4
        // points (a 3-point group would fall back to its biased mean).
        let short = Curve {
            times_h: times[..300].to_vec(),
            strains: times[..300].iter().map(|&t| f(t)).collect(),
            ..c.clone()
        };
        assert_eq!(binned(&short, 100).times_h.len(), 1 + 299 / 4);
        let b = binned(&long, 60);
        assert_eq!(b.times_h.len(), 60);
        let mut worst_mean = 0.0f64;
        for (j, (&t, &e)) in b.times_h.iter().zip(&b.strains).enumerate().skip(1) {
            let (lo, hi) = (1 + (j - 1) * 1999 / 59, 1 + j * 1999 / 59);
            assert!((33..=34).contains(&(hi - lo)), "balanced groups");
            let g: Vec<f64> = (lo..hi).map(|i| f(times[i])).collect();
            let mean = g.iter().sum::<f64>() / g.len() as f64;
            let (err, err_mean) = ((e - f(t)).abs(), (mean - f(t)).abs());
            assert!(err < 5e-4 * f(t), "group {j}: {e} vs {}", f(t));
            assert!(
                err <= err_mean / 10.0 + 1e-15,
                "group {j}: {err} vs mean's {err_mean}"
            );
            worst_mean = worst_mean.max(err_mean / f(t));
        }
        assert!(
            worst_mean > 1e-4,
            "the plain mean would be biased: {worst_mean}"
        );
    }

    #[test]
    fn a_start_more_keeps_the_better_ratio_and_a_failure_never_counts() {
        let nan = f64::NAN;
        for (first, new, want) in [
            (1.0, Some(2.0), 2.0),
            (3.0, Some(2.0), 3.0),
            (1.0, None, 1.0),
            (nan, Some(2.0), 2.0),
            (-0.5, Some(-1.0), -0.5),
        ] {
            assert_eq!(again_ratio(first, new), want, "{first} {new:?}");
        }
        assert!(again_ratio(nan, None).is_nan());
    }

    #[test]
    fn a_candidate_that_could_not_be_fitted_is_reported() {
        let cfg = seed_config("");
        let data = cfg.load_data().unwrap();
        let sp = cfg.diagnose_setup().unwrap().variants;
        let c = candidate(
            &sp[1],
            &data.curves,
            None,
            17,
            &FitSettings::from_config(&cfg),
        );
        assert_eq!(c.status, FitStatus::Failed);
        assert_eq!(c.failed_starts, 17);
        assert!(c.objective.is_nan() && c.aic.is_nan());
        assert_eq!(c.name, "constant_load");
    }

    #[test]
    fn a_failed_leave_one_out_fold_is_reported_never_filled_in() {
        // B so small that no curve ruptures within the horizon: every fold fails.
        let cfg = seed_config("");
        let data = cfg.load_data().unwrap();
        let mut sp = cfg.diagnose_setup().unwrap().variants.remove(0);
        sp.space.lb[1] = 1e-7;
        sp.space.ub[1] = 2e-7;
        let settings = FitSettings::from_config(&cfg);
        let mut start = cfg.starts_all_given().unwrap();
        start[1] = 1.5e-7;
        let loo = leave_one_stress_out(
            &sp,
            &data.curves,
            &start,
            &[start.clone()],
            &settings,
            &MlOptions::default(),
        );
        assert_eq!(loo.failed_folds, vec![85.0, 100.0, 110.0]);
        assert!(loo.rmse.is_nan() && loo.lifetime_err_pct.is_nan());
    }
}
