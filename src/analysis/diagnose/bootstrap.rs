//! The parametric bootstrap behind `diagnose`'s p-values: replicate data sets simulated from
//! a fitted model with its fitted error model, at the measured times of the real curves, each
//! refitted exactly as the real data were (warm starts plus random starts), so that the
//! statistics' null distributions include everything the procedure does — the error model's
//! estimation, the optimiser, the early ends of the curves.
//!
//! Replicate b draws from its own random stream (seed, b), and replicates run in batches of
//! [`BATCH`] whose size does not depend on the thread count: results are identical for any
//! number of threads. Sampling stops early (Besag & Clifford 1991) once every test has at
//! least [`STOP_EXCEEDANCES`] replicates at or above its observed statistic: the p-values are
//! then at least 11/(b + 1), above 0.068 for the default 159 replicates. A test whose
//! statistic costs a fit of its own (an extension's likelihood ratio) may be decided alone
//! the same way and dropped from the later replicates; its p-value is then the one of the
//! replicates up to its stop, still a valid p-value (Besag & Clifford's sequential test).
//! A test whose p-value after the first replicates is close to significance (at most α/2,
//! where Holm's thresholds are a few replicates apart) goes on to more ([`Depth`]); its
//! p-value is then the one over all of them, and the rule's p-values stay exact.
//! Where the tests sampled together are the whole family of Holm's procedure, sampling also
//! stops once every test's p-value is bound above Holm's smallest threshold α/m (and above
//! the extension's level where tests may be extended; [`Depth::settled`]): nothing can be
//! rejected any more, so every decision is the one the whole run would make; the p-values
//! reported are then those of the replicates drawn, each above that bound.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

use crate::data::Curve;
use crate::errmodel::{strain_fractions, ErrorModel, GrowingError};
use crate::fit::FitSettings;
use crate::likelihood::{raw_objective, restricted_design, EffectStart, MlFit};
use crate::model::objective::{Evaluation, ParamSpace};
use crate::model::Model;

/// Replicates per batch (fixed, for thread-count invariance).
pub const BATCH: usize = 10;
/// Exceedances per test after which sampling may stop.
pub const STOP_EXCEEDANCES: usize = 10;

/// The random stream of replicate `b` (0-based) of a bootstrap seeded with `seed`; `purpose`
/// separates independent bootstraps of one run.
pub fn replicate_rng(seed: u64, purpose: u64, b: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ purpose.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    rng.set_stream(b as u64 + 1);
    rng
}

/// The reading error a bootstrap under `fit` draws: `fit`'s AR(1) per curve, growing with
/// strain ([`GrowingError`]) when the restricted likelihood of its residuals says so
/// ([`GrowingError::estimate_restricted`], the fit's Jacobian from `model` in `space`), its
/// growth and AR(1)s then estimated together from them; when the best growth is zero (or
/// `fit` kept no residuals), `fit`'s own AR(1)s unchanged.
pub fn reading_error(
    curves: &[Curve],
    model: &dyn Model,
    space: &ParamSpace,
    fit: &MlFit,
    settings: &FitSettings,
) -> GrowingError {
    let constant = GrowingError::constant(&fit.noise.strain);
    let Some(res) = fit.residuals.as_ref() else {
        return constant;
    };
    let x: Vec<Vec<f64>> = curves
        .iter()
        .map(|c| strain_fractions(&c.strains))
        .collect();
    if res.strain.iter().zip(&x).any(|(e, x)| e.len() != x.len()) {
        return constant;
    }
    let est = match restricted_design(model, curves, space, fit, settings) {
        Some(d) => GrowingError::estimate_restricted(&res.strain, &x, &d),
        None => GrowingError::estimate(&res.strain, &x),
    };
    if est.growth > 0.0 {
        est
    } else {
        constant
    }
}

/// Curve `c`'s strain fractions, only where `reading` grows (else zeros are never read).
fn fractions_of(c: &Curve, reading: &GrowingError) -> Vec<f64> {
    if reading.growth != 0.0 {
        strain_fractions(&c.strains)
    } else {
        vec![0.0; c.times_h.len()]
    }
}

/// A replicate of `curves`: the fitted model's predictions at the measured times (`eval`,
/// with the objective's continuation after a predicted rupture, exactly what the fit was
/// compared with) plus AR(1) reading error per curve, and rupture times scattered on the log
/// scale by the fitted lifetime scatter. Everything else (times, rupture strain used for
/// normalisation, the estimated minimum rate) is the real curve's.
///
/// The reading error is `reading` (per curve an AR(1), growing with the curve's measured strain
/// fraction when its growth is not zero: [`reading_error`]); `noise` gives the lifetime scatter.
pub fn replicate_data<R: Rng>(
    curves: &[Curve],
    eval: &Evaluation,
    noise: &ErrorModel,
    reading: &GrowingError,
    rng: &mut R,
) -> Vec<Curve> {
    curves
        .iter()
        .zip(&eval.curves)
        .enumerate()
        .map(|(i, (c, p))| {
            let mut e = reading.simulate(i, &fractions_of(c, reading), rng);
            c.from_reading_units(&mut e);
            let strains: Vec<f64> = p.strain.iter().zip(&e).map(|(s, d)| s + d).collect();
            let z: f64 = rng.sample(StandardNormal);
            let rupture_time_h = c.rupture_time_h.map(|t| {
                let base = if p.rupture_time_h.is_finite() {
                    p.rupture_time_h
                } else {
                    t
                };
                base * (noise.lifetime_sd * z).exp()
            });
            Curve {
                strains,
                rupture_time_h,
                ..c.clone()
            }
        })
        .collect()
}

/// Strain at each of curve `c`'s readings of a shape given at the goodness of fit's knots
/// ([`super::gof::KNOTS`], in fractions of `c`'s life) in units of `c`'s rupture strain: the
/// goodness of fit's design columns ([`super::gof::knot_column`]) weighted by `coefs`.
pub fn shape_at(c: &Curve, coefs: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; c.times_h.len()];
    for (k, v) in coefs.iter().enumerate() {
        for (o, h) in out.iter_mut().zip(super::gof::knot_column(c, k)) {
            *o += h * v;
        }
    }
    out
}

/// Root mean square of knot coefficients over the knots with data (a knot without data has a
/// prediction of exactly 0); 0 when there are none.
fn rms_with_data(shapes: &[Vec<f64>]) -> f64 {
    let (ss, n) = shapes
        .iter()
        .flatten()
        .filter(|v| **v != 0.0)
        .fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 {
        0.0
    } else {
        (ss / n as f64).sqrt()
    }
}

/// The specimens' own shapes a hierarchical bootstrap gives its new specimens: the data's
/// specimens' shapes beyond the shape they share (the best linear unbiased predictions of the
/// goodness of fit's mixed model, [`super::gof::Shape::CommonBeyondSpecimens`]), rescaled so
/// that their mean square is that model's τ̂² (the predictions are shrunk towards zero), and
/// resampled: each new specimen takes one of them, drawn uniformly, at its own life
/// fractions. Resampled rather than drawn independently at each knot because a real
/// specimen's shape is one coherent curve (a tertiary stage that starts early or late): on
/// generated null sets whose specimens differ in coarsening rate, independent knots at τ̂
/// left two of three false alarms standing (session 53).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpecimenShapes {
    /// The shapes to resample, knot coefficients in fractions of the rupture strain.
    pub pool: Vec<Vec<f64>>,
}

impl SpecimenShapes {
    /// No shapes: specimens differ by their fitted factors only.
    pub fn none() -> SpecimenShapes {
        SpecimenShapes::default()
    }

    /// The shapes of the goodness of fit `g` (one beyond specimen shapes): its per-curve
    /// predictions scaled to mean square τ̂² over the knots with data; none when τ̂ = 0.
    pub fn from_gof(g: &super::gof::Gof) -> SpecimenShapes {
        let tau = g.specimen_shape_sd_pct / 100.0;
        let rms = rms_with_data(&g.specimen_shapes);
        if !(tau > 0.0) || rms == 0.0 {
            return SpecimenShapes::none();
        }
        let scale = tau / rms;
        SpecimenShapes {
            pool: g
                .specimen_shapes
                .iter()
                .map(|u| u.iter().map(|v| v * scale).collect())
                .collect(),
        }
    }

    /// The pool's root mean square over the knots with data, % of the rupture strain (τ̂;
    /// 0 without shapes).
    pub fn sd_pct(&self) -> f64 {
        100.0 * rms_with_data(&self.pool)
    }

    /// Whether there is no shape to draw.
    pub fn is_empty(&self) -> bool {
        self.pool.is_empty()
    }

    /// A new specimen's shape at real curve `c`'s readings, as strain to add to the model's
    /// prediction (measured − predicted): one of the pool, drawn uniformly (one draw from
    /// `rng`). The pool holds misfits in the residuals' sign (predicted − measured), so a
    /// specimen whose tertiary stage came early (measured above the prediction late in life)
    /// gives new specimens whose readings lie above it there too.
    pub fn draw<R: Rng>(&self, c: &Curve, rng: &mut R) -> Vec<f64> {
        let j = rng.gen_range(0..self.pool.len());
        shape_at(c, &self.pool[j]).into_iter().map(|v| -v).collect()
    }
}

/// A replicate of `curves` under a fitted hierarchical model (`fit`, with specimen effects):
/// every curve a NEW specimen, its effects drawn from the fitted scatter; each curve's
/// measured times scaled by the ratio of the new specimen's predicted life to the fitted life
/// of the real one (so a shorter-lived specimen is logged over its own shorter life, as the
/// real one was over its own); the model's predictions there plus AR(1) reading error, and
/// the rupture time scattered on the log scale by the fitted lifetime scatter; and each new
/// specimen's own shape drawn from `shapes` (none when it is empty). Without specimen effects
/// in `fit` this is [`replicate_data`] (a specimen is then the population, and `shapes` is
/// not used).
///
/// Returns the point the replicate was drawn at too: the new specimens' effects with `fit`'s
/// kinds and scatter (`None` without specimen effects), a known start for the replicate's
/// refit. The shapes are drawn last, curve by curve after its rupture time, so without shapes
/// the stream's use (and the replicate) is that of a model without them.
pub fn replicate_hier_drawn<R: Rng>(
    curves: &[Curve],
    model: &dyn Model,
    fit: &MlFit,
    reading: &GrowingError,
    settings: &FitSettings,
    shapes: &SpecimenShapes,
    rng: &mut R,
) -> (Vec<Curve>, Option<EffectStart>) {
    let eval = fit.eval.as_ref().expect("fitted");
    let Some(sp) = &fit.specimen else {
        return (replicate_data(curves, eval, &fit.noise, reading, rng), None);
    };
    let n = curves.len();
    // Draw every effect first (a fixed use of the stream), kind-major.
    let draws: Vec<Vec<f64>> = sp
        .scatter
        .iter()
        .map(|t| {
            (0..n)
                .map(|_| t * rng.sample::<f64, _>(StandardNormal))
                .collect()
        })
        .collect();
    let drawn = EffectStart {
        kinds: sp.kinds.clone(),
        effects: draws.clone(),
        scatter: sp.scatter.clone(),
        method: sp.scatter_method,
    };
    let mut base = fit.clone();
    base.specimen = Some(crate::likelihood::SpecimenFit {
        effects: draws,
        ..sp.clone()
    });
    let factors = base.factors(model);
    // The new specimens' lives at the real times (only their rupture times are used).
    let obj = raw_objective(model, curves, settings).with_factors(factors.clone());
    let first = obj.evaluate(&fit.params);
    let scaled: Vec<Curve> = curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let (old, new) = (
                eval.curves[i].rupture_time_h,
                first.curves[i].rupture_time_h,
            );
            let ratio = if old.is_finite() && new.is_finite() && old > 0.0 {
                new / old
            } else {
                1.0
            };
            Curve {
                times_h: c.times_h.iter().map(|t| t * ratio).collect(),
                rupture_time_h: c.rupture_time_h.map(|t| t * ratio),
                groups: c.groups.as_ref().map(|g| {
                    std::sync::Arc::new(crate::data::ReadingGroups {
                        times_h: g.times_h.iter().map(|t| t * ratio).collect(),
                        ends: g.ends.clone(),
                        misfit_share: g.misfit_share,
                    })
                }),
                ..c.clone()
            }
        })
        .collect();
    let ev = raw_objective(model, &scaled, settings)
        .with_factors(factors)
        .evaluate(&fit.params);
    let data = scaled
        .into_iter()
        .zip(&ev.curves)
        .enumerate()
        .map(|(i, (c, p))| {
            // The real curve's strain fractions: the replicate's times are the real ones
            // scaled by the new specimen's life, so its readings fall at the same fractions.
            let mut e = reading.simulate(i, &fractions_of(&curves[i], reading), rng);
            // A group mean's error from a reading's (the reading error model's units).
            curves[i].from_reading_units(&mut e);
            let mut strains: Vec<f64> = p.strain.iter().zip(&e).map(|(s, d)| s + d).collect();
            let z: f64 = rng.sample(StandardNormal);
            let rupture_time_h = c.rupture_time_h.map(|t| {
                let base = if p.rupture_time_h.is_finite() {
                    p.rupture_time_h
                } else {
                    t
                };
                base * (fit.noise.lifetime_sd * z).exp()
            });
            if !shapes.is_empty() {
                // At the real curve's life fractions (the replicate's times are scaled).
                let u = shapes.draw(&curves[i], rng);
                strains.iter_mut().zip(&u).for_each(|(s, d)| *s += d);
            }
            Curve {
                strains,
                rupture_time_h,
                ..c
            }
        })
        .collect();
    (data, Some(drawn))
}

/// Statistics closer than this (in units of −2 ln L) are ties: the fits converge to about
/// 1e-3 of −2 ln L, so a nested extension fitted at its switched-off value gives T = 0 up to
/// that noise, on the data and in the replicates alike; without a tolerance the sign of the
/// noise would decide the p-value.
pub const TIE: f64 = 0.01;

/// Monte Carlo p-value of observed statistic `obs` against replicate statistics `sample`:
/// (1 + #{T* ≥ T − [`TIE`] or T* not computed}) / (B + 1). A replicate whose refit failed
/// counts against rejection: a failure never counts as evidence.
pub fn p_value(obs: f64, sample: &[f64]) -> f64 {
    if !obs.is_finite() {
        return 1.0;
    }
    let ge = sample.iter().filter(|&&s| !(s < obs - TIE)).count();
    (1 + ge) as f64 / (sample.len() + 1) as f64
}

/// The critical value of the test at level `alpha` before any multiplicity adjustment: the
/// statistic an observation needs for [`p_value`] ≤ `alpha` against `sample` (its null's upper
/// `alpha` quantile, a replicate not computed counted as exceeding everything, plus
/// [`TIE`]). `None` when no observation can reach it (fewer than 1/α − 1 replicates, or too
/// many not computed). For α < 1 (`diagnose` allows at most 0.5) the quantile is always one of
/// the replicates. A wide null (a critical value far above a χ² quantile) says the
/// replicates' refits disagree, so a real effect needs a large ratio to show.
pub fn critical_value(sample: &[f64], alpha: f64) -> Option<f64> {
    // p ≤ α ⇔ #{T* ≥ T − TIE or not computed} ≤ α(B + 1) − 1 =: k.
    let k = (alpha * (sample.len() + 1) as f64 - 1.0 + 1e-9).floor();
    if k < 0.0 {
        return None;
    }
    let mut s: Vec<f64> = sample
        .iter()
        .map(|v| if v.is_nan() { f64::INFINITY } else { *v })
        .collect();
    s.sort_by(|a, b| b.total_cmp(a));
    s.get(k as usize).filter(|v| v.is_finite()).map(|v| v + TIE)
}

/// The replicates of [`sequential`].
#[derive(Debug, Clone, PartialEq)]
pub struct Sampled {
    /// Each replicate's statistics, replicate order; a statistic after its test was dropped
    /// is NaN and not part of the test ([`Sampled::column`]).
    pub reps: Vec<Vec<f64>>,
    /// Per statistic: the leading replicates in which it was computed (all of them unless its
    /// test was decided and dropped).
    pub computed: Vec<usize>,
    /// Sampling stopped before `first`: every test was clearly not significant, or (with
    /// [`Depth::with_family_stop`]) the family was settled as not rejected.
    pub stopped_early: bool,
}

impl Sampled {
    /// Statistic `k` over the replicates in which it was computed.
    pub fn column(&self, k: usize) -> Vec<f64> {
        self.reps[..self.computed[k]].iter().map(|r| r[k]).collect()
    }
}

/// How many replicates a sequential bootstrap draws: `first` for every test, and up to
/// `most` for a test whose p-value after `first` is at most `extend_p`, where more replicates
/// can change a decision (Holm's thresholds α/m … α/2 are within a few replicates of
/// 1/(first + 1)). The p-values stay exact: the DP of
/// `the_extended_sequential_p_value_is_valid_at_every_level` computes their null
/// distribution under the rule, P(p ≤ a) ≤ a at every a. Built by [`Depth::new`], which
/// keeps `most ≥ first`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Depth {
    /// Replicates of every test (unless decided earlier, [`STOP_EXCEEDANCES`]).
    first: usize,
    /// Most replicates of a test that is still close to significance after `first`.
    most: usize,
    /// The p-value after `first` at or below which a test goes on to `most`.
    extend_p: f64,
    /// The level of Holm's procedure over the tests sampled together (the finite observed
    /// statistics), where sampling may stop once it can reject none of them
    /// ([`Depth::settled`]); `None`: no such stop.
    family_alpha: Option<f64>,
}

impl Depth {
    /// `first` replicates for every test, up to `most` (raised to `first` if below it) for a
    /// test whose p-value after `first` is at most `extend_p`.
    pub fn new(first: usize, most: usize, extend_p: f64) -> Depth {
        Depth {
            first,
            most: most.max(first),
            extend_p,
            family_alpha: None,
        }
    }

    /// The same, and sampling stops as soon as Holm's procedure at `alpha` over the tests
    /// sampled together can reject none of them whatever the later replicates
    /// ([`Depth::settled`]): only for a bootstrap whose tests are the whole family Holm's
    /// procedure is applied to.
    pub fn with_family_stop(self, alpha: f64) -> Depth {
        Depth {
            family_alpha: Some(alpha),
            ..self
        }
    }

    /// Whether the tests sampled together, `exceed[k]` replicates at or above test k's
    /// observed statistic so far, are settled as not rejected: every test's p-value after
    /// `first` can only be at least (exceed + 1)/(first + 1), and where that is above Holm's
    /// smallest threshold α/m (m = `exceed.len()`) — and, where tests may go on to `most`
    /// (`most > first`), above `extend_p` too, so that none does and its p-value cannot
    /// fall — Holm's first step rejects nothing and so nothing at all: the decisions are the
    /// ones the whole run would give. At the defaults (159 replicates, no extension, a family
    /// of 8 at α = 0.05) α/m is 1/160: once every test has one replicate at or above its
    /// statistic, none can be rejected. False without [`Depth::with_family_stop`] or tests.
    pub fn settled(&self, exceed: &[usize]) -> bool {
        let Some(alpha) = self.family_alpha else {
            return false;
        };
        if exceed.is_empty() {
            return false;
        }
        let holm_first = alpha / exceed.len() as f64;
        let bound = if self.most > self.first {
            holm_first.max(self.extend_p)
        } else {
            holm_first
        };
        exceed
            .iter()
            .all(|&g| (g + 1) as f64 / (self.first + 1) as f64 > bound)
    }

    /// `max` replicates, no extension (the rule before session 59).
    pub fn fixed(max: usize) -> Depth {
        Depth::new(max, max, 0.0)
    }

    /// Replicates of every test.
    pub fn first(&self) -> usize {
        self.first
    }

    /// Most replicates of any test (at least [`Depth::first`]).
    pub fn most(&self) -> usize {
        self.most
    }

    /// Whether a test with `g` replicates at or above its statistic among the `n` drawn goes
    /// on sampling (asked after every batch): not once decided at [`STOP_EXCEEDANCES`]
    /// (Besag & Clifford), not after `first` unless its p-value (g + 1)/(first + 1) is at
    /// most `extend_p`, and not at `most`.
    pub fn goes_on(&self, n: usize, g: usize) -> bool {
        if g >= STOP_EXCEEDANCES {
            return false;
        }
        if n < self.first {
            return true;
        }
        if n == self.first && (g + 1) as f64 / (self.first + 1) as f64 > self.extend_p {
            return false;
        }
        n < self.most
    }

    /// The end of the batch that begins at replicate `lo`: [`BATCH`] replicates, cut at
    /// `first` and at `most`.
    pub fn batch_end(&self, lo: usize) -> usize {
        if lo < self.first {
            (lo + BATCH).min(self.first)
        } else {
            (lo + BATCH).min(self.most)
        }
    }
}

/// [`sequential_in`] to `max` replicates, no extension.
pub fn sequential<F>(observed: &[f64], droppable: &[bool], max: usize, one: F) -> Sampled
where
    F: Fn(usize, &[bool]) -> Vec<f64> + Sync,
{
    sequential_in(observed, droppable, Depth::fixed(max), one, |_| {})
}

/// Run replicates of `one` in batches to `depth.first`; after each batch stop if every one
/// of the `observed` statistics has at least [`STOP_EXCEEDANCES`] replicates at or above it
/// (NaN: a failed refit, counted as at or above), or, with [`Depth::with_family_stop`], once
/// Holm's procedure over them can reject none ([`Depth::settled`]). A statistic marked `droppable` whose test
/// has reached that count on its own (or whose observed value is not finite) is decided:
/// `one(b, active)` is told so through `active[k] = false` and may leave it NaN from then
/// on. After `depth.first` the tests [`Depth::goes_on`] keeps go on to `depth.most`
/// (`extending(n)` is told first, n the most replicates to come), each counted until it is
/// decided; the others end at `depth.first`. Every decision falls between batches of fixed
/// size, so the result does not depend on the thread count.
pub fn sequential_in<F, E>(
    observed: &[f64],
    droppable: &[bool],
    depth: Depth,
    one: F,
    extending: E,
) -> Sampled
where
    F: Fn(usize, &[bool]) -> Vec<f64> + Sync,
    E: Fn(usize),
{
    let n = observed.len();
    let exceed = |out: &[Vec<f64>], k: usize| out.iter().filter(|r| !(r[k] < observed[k])).count();
    let first = depth.first;
    let most = depth.most;
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(first);
    let mut active: Vec<bool> = (0..n)
        .map(|k| !droppable[k] || observed[k].is_finite())
        .collect();
    let mut computed = vec![0usize; n];
    // The next batch of replicates, each told which tests are still computed.
    let draw = |out: &mut Vec<Vec<f64>>, active: &[bool]| {
        let lo = out.len();
        let batch: Vec<Vec<f64>> = (lo..depth.batch_end(lo))
            .into_par_iter()
            .map(|b| one(b, active))
            .collect();
        out.extend(batch);
    };
    while out.len() < first {
        draw(&mut out, &active);
        for k in 0..n {
            if active[k] {
                computed[k] = out.len();
                if droppable[k] && exceed(&out[..computed[k]], k) >= STOP_EXCEEDANCES {
                    active[k] = false;
                }
            }
        }
        let done = (0..n).all(|k| {
            !observed[k].is_finite() || exceed(&out[..computed[k]], k) >= STOP_EXCEEDANCES
        });
        let tested: Vec<usize> = (0..n)
            .filter(|&k| observed[k].is_finite())
            .map(|k| exceed(&out[..computed[k]], k))
            .collect();
        if (done || depth.settled(&tested)) && out.len() < first {
            return Sampled {
                reps: out,
                computed,
                stopped_early: true,
            };
        }
    }
    // The tests close to significance go on; the others end here.
    let mut going: Vec<bool> = (0..n)
        .map(|k| {
            observed[k].is_finite()
                && computed[k] == first
                && depth.goes_on(first, exceed(&out[..first], k))
        })
        .collect();
    if going.iter().any(|g| *g) {
        extending(most - first);
        active.copy_from_slice(&going);
    }
    while going.iter().any(|g| *g) {
        draw(&mut out, &active);
        for k in 0..n {
            if going[k] {
                computed[k] = out.len();
                if !depth.goes_on(out.len(), exceed(&out[..computed[k]], k)) {
                    going[k] = false;
                    active[k] = false;
                }
            }
        }
    }
    Sampled {
        reps: out,
        computed,
        stopped_early: false,
    }
}

/// `first` with the statistics marked `redo` taken from `second` (the same replicates run
/// again for those statistics): their columns and computed counts are `second`'s; rows
/// `second` did not reach are NaN there and not part of the test.
pub fn merged(first: Sampled, second: &Sampled, redo: &[bool]) -> Sampled {
    let mut out = first;
    let n = out.reps.first().map_or(0, |r| r.len());
    while out.reps.len() < second.reps.len() {
        out.reps.push(vec![f64::NAN; n]);
    }
    for k in (0..redo.len()).filter(|&k| redo[k]) {
        for (b, row) in out.reps.iter_mut().enumerate() {
            row[k] = second.reps.get(b).map_or(f64::NAN, |r| r[k]);
        }
        out.computed[k] = second.computed[k];
    }
    out.stopped_early = out.stopped_early && second.stopped_early;
    out
}

/// What a test's second null run changed ([`merged`]'s `second` against `first`, over the
/// replicates both runs computed): how many replicates' ratios it raised (or filled in
/// where the first refit failed), and the replicates at or above the observed `obs` as
/// [`p_value`] counts them (a failed refit counts) in the first run and in the second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct AgainEffect {
    /// Replicates whose ratio the second run raised, or computed where the first failed.
    pub raised: usize,
    /// Replicates at or above the observed ratio: first run, second run.
    pub at_or_above: [usize; 2],
    /// The replicates counted: those of the second run (the test's `null_replicates`; 0 in
    /// a file written before session 79).
    #[serde(default)]
    pub replicates: usize,
}

/// [`AgainEffect`] of `second` (the second run's column) against `first` over the second
/// run's replicates; `obs` the data's ratio.
pub fn again_effect(first: &[f64], second: &[f64], obs: f64) -> AgainEffect {
    let above = |s: f64| !(s < obs - TIE);
    let mut e = AgainEffect {
        raised: 0,
        at_or_above: [0, 0],
        replicates: second.len(),
    };
    for (b, &a) in second.iter().enumerate() {
        let f = first.get(b).copied().unwrap_or(f64::NAN);
        if a.is_finite() && !(f >= a) {
            e.raised += 1;
        }
        e.at_or_above[0] += usize::from(above(f));
        e.at_or_above[1] += usize::from(above(a));
    }
    e
}

/// The 95 % quantile of |a_b − c_b| over replicates where both are finite (NaN if none).
pub fn spread95(a: &[f64], c: &[f64]) -> f64 {
    let mut d: Vec<f64> = a
        .iter()
        .zip(c)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (x - y).abs())
        .collect();
    if d.is_empty() {
        return f64::NAN;
    }
    d.sort_by(|x, y| x.total_cmp(y));
    let idx = ((0.95 * d.len() as f64).ceil() as usize).clamp(1, d.len()) - 1;
    d[idx]
}

#[cfg(test)]
mod tests {
    /// The second run's effect, counted by hand: raised where the second ratio is larger or
    /// the first failed; at or above the data's ratio as `p_value` counts (NaN counts).
    #[test]
    fn the_second_null_runs_effect_is_counted_as_p_value_counts() {
        let nan = f64::NAN;
        // (first, second, obs, raised, at or above first, second)
        type Row = (Vec<f64>, Vec<f64>, f64, usize, [usize; 2]);
        let table: Vec<Row> = vec![
            (vec![1.0, 2.0, 3.0], vec![1.0, 2.0, 3.0], 10.0, 0, [0, 0]),
            (vec![1.0, 2.0, 3.0], vec![1.0, 12.0, 3.0], 10.0, 1, [0, 1]),
            (vec![0.0, 9.0], vec![71.0, 9.5], 10.0, 2, [0, 1]),
            // A failed first refit counts as at or above; filled in below the ratio, no more.
            (vec![nan, 2.0], vec![4.0, 2.0], 10.0, 1, [1, 0]),
            // Failed in both: counts in both, raised in neither.
            (vec![nan], vec![nan], 10.0, 0, [1, 1]),
            // Within TIE of the ratio counts as at or above.
            (vec![9.995], vec![9.995], 10.0, 0, [1, 1]),
            // The second run computed fewer replicates than the first.
            (vec![1.0, 2.0, 30.0], vec![11.0], 10.0, 1, [0, 1]),
        ];
        for (first, second, obs, raised, at) in table {
            let e = super::again_effect(&first, &second, obs);
            assert_eq!(e.raised, raised, "{first:?} {second:?}");
            assert_eq!(e.at_or_above, at, "{first:?} {second:?}");
            assert_eq!(e.replicates, second.len());
            // Whatever the second run changed, p_value over its replicates is its count.
            let n = second.len();
            let p = super::p_value(obs, &second);
            assert!((p - (1 + at[1]) as f64 / (n + 1) as f64).abs() < 1e-12);
        }
    }

    use super::*;

    fn curve(n: usize, stress_mpa: f64) -> Curve {
        Curve {
            temperature_c: 600.0,
            stress_mpa,
            specimen: None,
            strains: vec![0.0; n],
            times_h: (0..n).map(|k| 80.0 * k as f64 / (n - 1) as f64).collect(),
            rupture_time_h: Some(80.0),
            rupture_strain: 0.05,
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 1e-4,
        }
    }

    /// Independent N(0, τ²) coefficients at every knot: the mixed model's own random shape.
    fn normal_shape(c: &Curve, tau: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let z: Vec<f64> = (0..crate::diagnose::gof::KNOTS.len())
            .map(|_| tau * rng.sample::<f64, _>(StandardNormal))
            .collect();
        shape_at(c, &z)
    }

    #[test]
    fn a_knot_shape_has_the_variance_of_its_hats() {
        // Closed form: with independent N(0, τ²) coefficients, Var u(t) = (τ ε_f)² Σ_k
        // hat_k(t)². At a knot (t = 0.5 of life) that is (τ ε_f)²; half way between two knots
        // (0.4) half of it; readings at 0.4 and 0.5 covary by (τ ε_f)² / 2. 4000 draws: the
        // variances' standard error is 2.2 %.
        let c = curve(81, 100.0); // a reading every 1.25 % of life
        let tau = 0.02;
        let v0 = (tau * c.rupture_strain).powi(2);
        let mut rng = ChaCha8Rng::seed_from_u64(53_001);
        let n = 4000;
        let (mut s50, mut s40, mut c45) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let u = normal_shape(&c, tau, &mut rng);
            assert_eq!(u.len(), c.times_h.len());
            s50 += u[40] * u[40] / n as f64;
            s40 += u[32] * u[32] / n as f64;
            c45 += u[32] * u[40] / n as f64;
        }
        assert!((s50 / v0 - 1.0).abs() < 0.1, "{}", s50 / v0);
        assert!((s40 / v0 - 0.5).abs() < 0.05, "{}", s40 / v0);
        assert!((c45 / v0 - 0.5).abs() < 0.06, "{}", c45 / v0);
    }

    /// Thirty specimens, each its own shape at τ = 1 % of ε_f (independent knots) plus AR(1)
    /// reading error of a fifth of that, and the goodness of fit beyond specimen shapes of
    /// their residuals; also the true shapes.
    fn thirty_shapes(seed: u64) -> (Vec<Curve>, crate::diagnose::gof::Gof, Vec<Vec<f64>>) {
        use crate::diagnose::gof;
        use crate::errmodel::{Ar1, Residuals};
        let curves: Vec<Curve> = (0..30).map(|i| curve(60, 50.0 + 3.0 * i as f64)).collect();
        let p = Ar1::with_marginal(1e-4, 0.5);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut truth = vec![];
        let strain = curves
            .iter()
            .map(|c| {
                let z: Vec<f64> = (0..gof::KNOTS.len())
                    .map(|_| 0.01 * rng.sample::<f64, _>(StandardNormal))
                    .collect();
                let u = shape_at(c, &z);
                truth.push(z);
                let e = p.simulate(c.times_h.len(), &mut rng);
                u.iter().zip(&e).map(|(a, b)| a + b).collect()
            })
            .collect();
        let res = Residuals {
            strain,
            lifetime: (0..30)
                .map(|_| Some(0.02 * rng.sample::<f64, _>(StandardNormal)))
                .collect(),
        };
        let noise = ErrorModel::estimate(&res, 0.01);
        let g = gof::statistic(
            &curves,
            &res,
            &noise,
            0.01,
            gof::Shape::CommonBeyondSpecimens,
        );
        (curves, g, truth)
    }

    #[test]
    fn specimen_shapes_are_what_the_mixed_model_estimates() {
        // The goodness of fit's mixed model (whose shapes the bootstrap resamples) finds τ
        // within 15 % (240 random coefficients: about 3 standard errors), no common shape (G
        // below χ²(9)'s 99.9 % point, 27.9), and each specimen's own shape: its predictions
        // less their mean over the specimens (the fixed common shape takes that) are within
        // a fifth of τ of the true shapes less theirs, in root mean square. Seeds 53_011–013.
        for seed in 53_011..53_014u64 {
            let (_, g, truth) = thirty_shapes(seed);
            assert!(
                (g.specimen_shape_sd_pct - 1.0).abs() < 0.15,
                "seed {seed}: τ̂ {} %",
                g.specimen_shape_sd_pct
            );
            assert!(g.statistic < 27.9, "seed {seed}: G {}", g.statistic);
            assert_eq!(g.specimen_shapes.len(), 30);
            let nk = truth[0].len();
            let mean = |v: &[Vec<f64>], k: usize| v.iter().map(|u| u[k]).sum::<f64>() / 30.0;
            let mut ss = 0.0;
            for k in 0..nk {
                let (mt, mp) = (mean(&truth, k), mean(&g.specimen_shapes, k));
                for (t, p) in truth.iter().zip(&g.specimen_shapes) {
                    ss += ((p[k] - mp) - (t[k] - mt)).powi(2);
                }
            }
            let rms = (ss / (30 * nk) as f64).sqrt();
            assert!(rms < 0.002, "seed {seed}: rms {rms} against τ 0.01");
        }
    }

    #[test]
    fn resampled_shapes_have_the_fitted_spread_and_come_from_the_data() {
        // The pool is the predictions scaled to mean square τ̂²; a draw is one of them at the
        // curve's readings, each about equally often (600 draws from 30: 20 expected each).
        let (curves, g, _) = thirty_shapes(53_021);
        let sh = SpecimenShapes::from_gof(&g);
        assert_eq!(sh.pool.len(), 30);
        let all: Vec<f64> = sh.pool.iter().flatten().copied().collect();
        let ms = all.iter().map(|v| v * v).sum::<f64>() / all.len() as f64;
        let tau = g.specimen_shape_sd_pct / 100.0;
        assert!(
            (ms.sqrt() / tau - 1.0).abs() < 1e-9,
            "{} vs {tau}",
            ms.sqrt()
        );
        let mut rng = ChaCha8Rng::seed_from_u64(53_022);
        let mut hits = [0usize; 30];
        for _ in 0..600 {
            // In the readings' sign: measured − predicted, the residuals' negative.
            let u: Vec<f64> = sh.draw(&curves[3], &mut rng).iter().map(|v| -v).collect();
            let j = (0..30)
                .find(|&j| shape_at(&curves[3], &sh.pool[j]) == u)
                .expect("a drawn shape is one of the pool's");
            hits[j] += 1;
        }
        assert!(hits.iter().all(|&h| (5..=40).contains(&h)), "{hits:?}");
        // No spread, no shapes.
        let flat = crate::diagnose::gof::Gof {
            specimen_shape_sd_pct: 0.0,
            ..g.clone()
        };
        assert!(SpecimenShapes::from_gof(&flat).is_empty());
    }

    #[test]
    fn p_values_count_failures_against_rejection() {
        assert_eq!(p_value(5.0, &[1.0, 2.0, 3.0]), 0.25);
        assert_eq!(p_value(2.0, &[1.0, 2.0, 3.0]), 0.75);
        assert_eq!(p_value(5.0, &[1.0, f64::NAN, 3.0]), 0.5);
        assert_eq!(p_value(f64::NAN, &[1.0]), 1.0);
        // A nested extension at its switched-off value: T = 0 up to fitting noise on the data
        // and in the replicates; the noise's sign must not make it significant.
        assert_eq!(p_value(2e-7, &[-3e-6, -1e-5, -2e-4]), 1.0);
    }

    #[test]
    fn critical_values_are_where_the_p_value_crosses_alpha() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261126);
        let mut reached = 0;
        for case in 0..2000 {
            let b = rng.gen_range(1..200);
            let sample: Vec<f64> = (0..b)
                .map(|_| {
                    if rng.gen_bool(0.05) {
                        f64::NAN
                    } else {
                        // Ties on a coarse grid as well as continuous values.
                        if case % 2 == 0 {
                            rng.gen_range(-5.0f64..50.0)
                        } else {
                            rng.gen_range(0..20) as f64
                        }
                    }
                })
                .collect();
            let alpha = [0.01, 0.05, 0.1][case % 3];
            match critical_value(&sample, alpha) {
                Some(c) => {
                    reached += 1;
                    // Just above it the test rejects, just below it does not.
                    assert!(p_value(c + 1e-9, &sample) <= alpha, "case {case}");
                    assert!(p_value(c - 1e-6, &sample) > alpha, "case {case}");
                }
                None => {
                    // Nothing reaches α: not even an observation above every replicate.
                    assert!(p_value(1e12, &sample) > alpha, "case {case}");
                }
            }
        }
        // Not vacuous: the property above ran on many samples that can reach α (809 of 2000).
        assert!(reached >= 500, "{reached}");
        // By hand: 19 replicates at α = 0.05 leave no room for any exceedance.
        let s: Vec<f64> = (1..=19).map(f64::from).collect();
        assert_eq!(critical_value(&s, 0.05), Some(19.0 + TIE));
        assert_eq!(critical_value(&s[..18], 0.05), None);
        let mut with_failure = s.clone();
        with_failure[0] = f64::NAN;
        assert_eq!(critical_value(&with_failure, 0.05), None);
    }

    #[test]
    fn sequential_stops_only_when_every_test_is_clearly_not_significant() {
        // Test 0 typical (T = 0.5 of uniform replicates), test 1 extreme: no early stop.
        let one = |b: usize, _: &[bool]| vec![(b % 7) as f64 / 7.0, (b % 5) as f64];
        let none = [false, false];
        let s = sequential(&[0.5, 100.0], &none, 99, one);
        assert_eq!(s.reps.len(), 99);
        assert_eq!(s.computed, vec![99, 99]);
        assert!(!s.stopped_early);
        // Both typical: stops after the first batch with ≥ 10 exceedances each.
        let s = sequential(&[0.1, 0.0], &none, 99, one);
        assert!(s.stopped_early);
        assert_eq!(s.reps.len() % BATCH, 0);
        assert!(s.reps.len() < 99);
        // Identical whatever the thread count.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let s1 = pool.install(|| sequential(&[0.1, 0.0], &none, 99, one));
        assert_eq!(s, s1);
    }

    /// A droppable test decided alone stops being computed after the batch that decided it;
    /// the other tests run to the end with the same values as without dropping.
    #[test]
    fn a_decided_test_is_dropped_and_the_others_are_unchanged() {
        use std::sync::Mutex;
        let calls = Mutex::new(vec![0usize; 3]);
        // Statistic 0 typical (decided after a few batches), 1 extreme, 2 typical but not
        // droppable.
        let one = |b: usize, active: &[bool]| {
            let mut r = vec![f64::NAN; 3];
            for k in 0..3 {
                if active[k] {
                    calls.lock().unwrap()[k] += 1;
                    r[k] = ((b * (k + 3)) % 11) as f64 / 11.0;
                }
            }
            r
        };
        let observed = [0.3, 5.0, 0.3];
        let s = sequential(&observed, &[true, true, false], 159, one);
        let full = sequential(&observed, &[false; 3], 159, one);
        assert!(!s.stopped_early);
        assert_eq!(s.reps.len(), 159);
        // Test 0 reached 10 exceedances within its first 20 replicates.
        let c0 = s.computed[0];
        assert!(c0 > 0 && c0 <= 20 && c0 % BATCH == 0, "{c0}");
        assert!(s.column(0).iter().filter(|v| **v >= 0.3).count() >= STOP_EXCEEDANCES);
        assert!(s.reps[c0..].iter().all(|r| r[0].is_nan()));
        assert_eq!(s.computed[1], 159);
        assert_eq!(s.computed[2], 159);
        assert_eq!(s.column(1), full.column(1));
        assert_eq!(s.column(2), full.column(2));
        assert_eq!(&full.column(0)[..c0], &s.column(0)[..]);
        // A statistic not observed (its model not fitted on the data) is never computed.
        let s = sequential(&[f64::NAN, 5.0], &[true, true], 20, |_, a: &[bool]| {
            assert!(!a[0]);
            vec![f64::NAN, 0.0]
        });
        assert_eq!(s.computed, vec![0, 20]);
        assert!(s.column(0).is_empty());
    }

    /// The exact null distribution of the p-value (g + 1)/(n + 1) a single test reports
    /// under `goes_on` (decisions after every batch of [`Depth::batch_end`]): under the null
    /// the data's statistic and the replicates' are exchangeable, so the exceedances follow
    /// Pólya's urn — the next replicate is at or above the data's with probability
    /// (g + 1)/(n + 2) after g of n.
    fn null_p_distribution(
        depth: &Depth,
        goes_on: impl Fn(usize, usize) -> bool,
    ) -> Vec<(f64, f64)> {
        let most = depth.most;
        let mut at: Vec<f64> = vec![1.0]; // P(g) among the running paths
        let mut out: Vec<(f64, f64)> = Vec::new();
        let mut n = 0;
        while n < most && !at.is_empty() {
            let end = depth.batch_end(n);
            while n < end {
                let mut next = vec![0.0; at.len() + 1];
                for (g, pr) in at.iter().enumerate() {
                    let q = (g + 1) as f64 / (n + 2) as f64;
                    next[g + 1] += pr * q;
                    next[g] += pr * (1.0 - q);
                }
                at = next;
                n += 1;
            }
            for (g, pr) in at.iter_mut().enumerate() {
                if *pr > 0.0 && !goes_on(n, g) {
                    out.push(((g + 1) as f64 / (n + 1) as f64, *pr));
                    *pr = 0.0;
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    /// The largest P(p ≤ a)/a over the support of the reported p-value.
    fn worst_size_ratio(dist: &[(f64, f64)]) -> f64 {
        let mut cum = 0.0;
        let mut worst: f64 = 0.0;
        for (i, (p, pr)) in dist.iter().enumerate() {
            cum += pr;
            if dist.get(i + 1).is_none_or(|(q, _)| *q > *p) {
                worst = worst.max(cum / p);
            }
        }
        worst
    }

    #[test]
    fn the_extended_sequential_p_value_is_valid_at_every_level() {
        for depth in [
            Depth::new(159, 639, 0.025),
            Depth::new(159, 639, 0.05),
            Depth::new(99, 399, 0.025),
            Depth::fixed(159),
        ] {
            let dist = null_p_distribution(&depth, |n, g| depth.goes_on(n, g));
            let total: f64 = dist.iter().map(|d| d.1).sum();
            assert!((total - 1.0).abs() < 1e-9, "{depth:?}: {total}");
            let worst = worst_size_ratio(&dist);
            assert!(worst <= 1.0 + 1e-9, "{depth:?}: P(p ≤ a)/a reaches {worst}");
            // Not vacuous: the smallest p-value is 1/(most + 1), with exactly that chance.
            let (p0, pr0) = dist[0];
            let most = depth.most as f64;
            assert!((p0 - 1.0 / (most + 1.0)).abs() < 1e-12, "{depth:?}: {p0}");
            assert!((pr0 - 1.0 / (most + 1.0)).abs() < 1e-9, "{depth:?}: {pr0}");
        }
        // With the family stop a test's p-value stays valid at every level (m = 1, 2, 8; with
        // and without extension): the family's other tests settle at some batch t0 (from the
        // first on: the earliest stop this test can meet), after which its own exceedances
        // end the run. Without extension and m = 8 that is its first replicate at or above
        // its statistic.
        for (first, most) in [(159, 639), (159, 159)] {
            for m in [1usize, 2, 8] {
                for t0 in (10..first).step_by(10) {
                    let depth = Depth::new(first, most, 0.025).with_family_stop(0.05);
                    let dist = null_p_distribution(&depth, |n, g| {
                        let mut family = vec![if n >= t0 { 1000 } else { 0 }; m];
                        family[0] = g;
                        depth.goes_on(n, g) && !(n < depth.first && depth.settled(&family))
                    });
                    let worst = worst_size_ratio(&dist);
                    assert!(
                        worst <= 1.0 + 1e-9,
                        "{first}/{most}, m = {m}, t0 = {t0}: P(p ≤ a)/a reaches {worst}"
                    );
                }
            }
        }
        // The check can fail: stopping as soon as the p-value looks significant is not a
        // valid rule, and the DP says so.
        let depth = Depth::new(159, 639, 0.025);
        let peeking = null_p_distribution(&depth, |n, g| {
            depth.goes_on(n, g) && (g + 1) as f64 / (n + 1) as f64 > 0.02
        });
        assert!(worst_size_ratio(&peeking) > 1.2);
    }

    #[test]
    fn a_family_is_settled_once_holm_can_reject_nothing() {
        let d = Depth::new(159, 639, 0.025).with_family_stop(0.05);
        // (exceedances so far, settled): m = 8, bound max(0.05/8, 0.025) = 0.025 = 4/160.
        let eight = |g: usize, last: usize| {
            let mut v = vec![g; 7];
            v.push(last);
            v
        };
        for (exceed, want) in [
            (eight(4, 4), true),   // 5/160 = 0.03125 > 0.025
            (eight(4, 3), false),  // 4/160 = 0.025 is not above it: could still reject
            (eight(10, 0), false), // one test with nothing above its statistic yet
            (eight(20, 10), true),
            (vec![8], true),  // m = 1: bound α = 0.05; 9/160 = 0.05625
            (vec![7], false), // 8/160 = 0.05
            (vec![], false),  // no tests: nothing to settle
        ] {
            assert_eq!(d.settled(&exceed), want, "{exceed:?}");
        }
        // m = 1 with a looser extension level: the extension's level bounds it.
        let wide = Depth::new(159, 639, 0.1).with_family_stop(0.05);
        assert!(!wide.settled(&[8])); // 0.05625 ≤ 0.1: may go on to 639 and fall
        assert!(wide.settled(&[16])); // 17/160 = 0.10625
                                      // Without the family stop, never.
        assert!(!Depth::new(159, 639, 0.025).settled(&[100, 100]));
        // No extension (the defaults: most = first): Holm's α/m alone. m = 8: 1/160.
        let d = Depth::new(159, 159, 0.025).with_family_stop(0.05);
        assert!(d.settled(&eight(1, 1))); // 2/160 > 1/160: no test can be rejected
        assert!(!d.settled(&eight(1, 0))); // one test still at 1/160
        assert!(d.settled(&[4, 4])); // m = 2: 5/160 > 0.025
        assert!(!d.settled(&[4, 3])); // 4/160 = 0.025
        assert!(d.settled(&[8]) && !d.settled(&[7])); // m = 1: α
    }

    /// Holm's decisions at `alpha` over the p-values of every test of `s`.
    fn holm_decisions(observed: &[f64], s: &Sampled, alpha: f64) -> Vec<bool> {
        let p: Vec<f64> = (0..observed.len())
            .map(|k| p_value(observed[k], &s.column(k)))
            .collect();
        crate::diagnose::decide::holm(&p, alpha).0
    }

    /// The family stop changes no decision: over many families of tests whose statistics
    /// sit anywhere from far beyond their nulls to well inside them (p-values from 0 to 1,
    /// many near Holm's thresholds), Holm's decisions on the stopped run are those of the
    /// whole run, which it never exceeds; and it does stop some runs early.
    #[test]
    fn the_family_stop_makes_the_decisions_of_the_whole_run() {
        let alpha = 0.05;
        for (depth, min_stopped) in [
            (Depth::new(159, 639, alpha / 2.0), 50),
            (Depth::new(159, 159, alpha / 2.0), 80),
        ] {
            family_stop_cases(depth, alpha, min_stopped);
        }
    }

    fn family_stop_cases(depth: Depth, alpha: f64, min_stopped: usize) {
        let mut stopped = 0;
        let mut rejecting = 0;
        for case in 0..400u64 {
            let mut rng = ChaCha8Rng::seed_from_u64(6200 + case);
            let m = 1 + (case % 6) as usize;
            // Test k's replicate exceeds its observed statistic with probability q[k].
            let q: Vec<f64> = (0..m)
                .map(|_| match rng.gen_range(0..4) {
                    0 => 0.0,
                    1 => rng.gen_range(0.0..0.06),
                    2 => rng.gen_range(0.02..0.2),
                    _ => rng.gen_range(0.0..1.0),
                })
                .collect();
            let one = |b: usize, _: &[bool]| {
                let mut r = ChaCha8Rng::seed_from_u64(case * 100_000 + b as u64);
                q.iter()
                    .map(|&qk| if r.gen::<f64>() < qk { 2.0 } else { 0.0 })
                    .collect::<Vec<f64>>()
            };
            let observed = vec![1.0; m];
            let droppable = vec![false; m];
            let whole = sequential_in(&observed, &droppable, depth, one, |_| {});
            let family = depth.with_family_stop(alpha);
            let fast = sequential_in(&observed, &droppable, family, one, |_| {});
            let want = holm_decisions(&observed, &whole, alpha);
            assert_eq!(
                holm_decisions(&observed, &fast, alpha),
                want,
                "case {case}: {q:?}"
            );
            assert!(fast.reps.len() <= whole.reps.len());
            assert_eq!(&whole.reps[..fast.reps.len()], &fast.reps[..]);
            if fast.reps.len() < whole.reps.len() {
                stopped += 1;
                // Stopped only where nothing is rejected, each p-value above the bound.
                assert!(!want.iter().any(|r| *r), "case {case}");
            }
            rejecting += want.iter().any(|r| *r) as usize;
        }
        // Not vacuous: both kinds of family occur, and the stop saves replicates.
        assert!(
            stopped >= min_stopped && rejecting >= 50,
            "{depth:?}: {stopped} {rejecting}"
        );
    }

    #[test]
    fn a_test_close_to_significance_goes_on_to_the_most_replicates() {
        let depth = Depth::new(159, 639, 0.025);
        // Replicate b's statistics: 0 never reaches its observed value (goes on to 639),
        // 1 reaches it in 1 of 40 (5 of the first 159: ends at 159), 2 in 1 of 2 (decided
        // after 20), 3 not droppable and never reached, 4 in 1 of 150 (one of the first 159:
        // goes on and is decided by its 10th exceedance, at 1,500 > 639: runs to the end).
        let one = |b: usize, _: &[bool]| {
            vec![
                0.0,
                if b % 40 == 7 { 2.0 } else { 0.0 },
                (b % 2) as f64,
                0.0,
                if b % 150 == 3 { 2.0 } else { 0.0 },
            ]
        };
        let observed = [1.0, 1.0, 1.0, 1.0, 1.0];
        let droppable = [true, true, true, false, true];
        let told = std::sync::Mutex::new(Vec::new());
        let s = sequential_in(&observed, &droppable, depth, one, |n| {
            told.lock().unwrap().push(n)
        });
        assert_eq!(s.computed, vec![639, 159, 20, 639, 639]);
        assert_eq!(s.reps.len(), 639);
        assert_eq!(*told.lock().unwrap(), vec![480]);
        assert_eq!(p_value(1.0, &s.column(0)), 1.0 / 640.0);
        assert_eq!(p_value(1.0, &s.column(1)), 5.0 / 160.0);
        // A test that reaches its tenth exceedance after `first` ends there.
        let one = |b: usize, _: &[bool]| vec![if b % 60 == 3 { 2.0 } else { 0.0 }];
        let s = sequential_in(&[1.0], &[true], depth, one, |_| {});
        // Exceedances at 3, 63, 123 of the first 159 (p 4/160 = 0.025: goes on), …: the
        // 10th is replicate 543, in the batch 539–548.
        assert_eq!(s.computed, vec![549]);
        // The same replicates and counts whatever the thread count.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let s1 = pool.install(|| sequential_in(&[1.0], &[true], depth, one, |_| {}));
        assert_eq!(s, s1);
        // Without the extension (`fixed`), the old rule: everything ends at 159.
        let s = sequential_in(
            &observed,
            &droppable,
            Depth::fixed(159),
            |b, _| {
                vec![
                    0.0,
                    if b % 40 == 7 { 2.0 } else { 0.0 },
                    (b % 2) as f64,
                    0.0,
                    0.0,
                ]
            },
            |_| panic!("no extension"),
        );
        assert_eq!(s.computed, vec![159, 159, 20, 159, 159]);
    }

    #[test]
    fn merged_takes_the_redone_columns_and_their_counts() {
        let first = Sampled {
            reps: vec![vec![1.0, 2.0, 3.0]; 4],
            computed: vec![4, 4, 2],
            stopped_early: false,
        };
        let second = Sampled {
            reps: vec![vec![f64::NAN, 20.0, f64::NAN]; 3],
            computed: vec![0, 3, 0],
            stopped_early: true,
        };
        let m = merged(first.clone(), &second, &[false, true, false]);
        assert_eq!(m.column(0), first.column(0));
        assert_eq!(m.column(2), first.column(2));
        assert_eq!(m.column(1), vec![20.0; 3]);
        assert_eq!(m.computed, vec![4, 3, 2]);
        assert!(m.reps[3][1].is_nan());
        assert_eq!(m.reps.len(), 4);
        assert!(!m.stopped_early);
    }

    #[test]
    fn spread_is_the_95_percent_quantile() {
        let a: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let c = vec![0.0; 100];
        assert_eq!(spread95(&a, &c), 94.0);
        assert!(spread95(&[f64::NAN], &[1.0]).is_nan());
    }
}
