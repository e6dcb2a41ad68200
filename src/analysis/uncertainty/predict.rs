//! Intervals of predictions at an untested load: rupture time, minimum creep rate and rupture
//! strain, and a band around the predicted curve.
//!
//! Two intervals are kept apart:
//! - the **confidence interval** of the model's prediction — what the uncertainty of the
//!   constants allows — by the prediction profile likelihood: the quantity g (ln t_r,
//!   ln ε̇_min, ln ε_r, or the strain at a time) is held by
//!   [`crate::uncertainty::constrained::constrained_fit`] and its likelihood-ratio interval
//!   found by [`crate::uncertainty::profile::quantity_interval`];
//! - the **prediction interval of a new test**, which adds the scatter between specimens:
//!   on the log scale, each half-width is √(h_conf² + (z·s)²) with z the normal 97.5 %
//!   quantile and s the specimen scatter — for the rupture time the error model's scatter of
//!   ln t_f (the root mean square of the lifetime residuals, floored; or the pooled scatter
//!   within groups of replicate tests at one load, where there are replicates and it is
//!   larger), for the minimum rate and the rupture strain the root mean square of the log
//!   residuals of the measured (or, where the ruptures file has none, estimated) values;
//!   where the error model carries specimen effects (`[objective] specimen_effects`), the
//!   hierarchical fit's scatter of a new specimen's factors where it is wider.
//!
//! The functions take the model, the fitted constants with their error model (a
//! [`Reference`]) and a [`Load`]: a temperature carried by the load reaches the model through
//! it, so they work unchanged for models with temperature laws. The parametric bootstrap
//! ([`bootstrap_predictions`]) is the alternative measured against the profile in README
//! ("How sure").

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::constrained::{Predicted, Quantity};
use super::profile::{quantity_interval, quantity_interval_sides, Interval, QuantityInterval};
use super::{normal_quantile, Context, Reference, Thresholds};
use crate::diagnose::bootstrap::replicate_rng;
use crate::journal::{debug_hash, Exact};
use crate::likelihood::EffectKind;
use crate::model::Load;

/// Random stream of the prediction bootstrap.
const PREDICTION_STREAM: u64 = 13;

/// A quantity predicted at one load, with its intervals (physical units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictedInterval {
    /// `rupture_time_h`, `min_rate_pct_per_h` or `rupture_strain_pct`.
    pub quantity: &'static str,
    /// Prediction at the fitted constants.
    pub value: f64,
    /// Confidence interval of the model's prediction, 68 % and 95 %.
    pub conf_lo68: f64,
    pub conf_hi68: f64,
    pub conf_lo95: f64,
    pub conf_hi95: f64,
    /// Whether the confidence interval is open (the box stops the profile) below / above.
    pub conf_lo_open: bool,
    pub conf_hi_open: bool,
    /// 95 % prediction interval of a new test at this load.
    pub pred_lo95: f64,
    pub pred_hi95: f64,
    /// Specimen scatter added (sd on the ln scale) and how many residuals it rests on.
    pub scatter_sd: f64,
    pub scatter_n: usize,
    /// Wald standard error of ln g (for comparison).
    pub wald_se_ln: f64,
    /// Fits run for the confidence interval.
    pub fits: usize,
    /// Points of the profile search, for reports: (ln g, Δ).
    pub profile: Vec<(f64, f64)>,
}

/// Which prediction and how to show it: (quantity name, predicted, scale to the physical
/// unit: h, %/h, %).
const QUANTITIES: [(&str, Predicted, f64); 3] = [
    ("rupture_time_h", Predicted::LnRuptureTime, 1.0),
    ("min_rate_pct_per_h", Predicted::LnMinRate, 100.0),
    ("rupture_strain_pct", Predicted::LnRuptureStrain, 100.0),
];

/// [`specimen_scatter`] for a run that predicts at `loads` conditions, computed once for all
/// of them (with specimen effects it is a hierarchical fit); none (NaN, 0) without loads.
pub fn specimen_scatter_for(
    ctx: &Context,
    reference: &Reference,
    loads: usize,
) -> [(f64, usize); 3] {
    if loads == 0 {
        [(f64::NAN, 0); 3]
    } else {
        specimen_scatter(ctx, reference)
    }
}

/// The specimen scatter (sd of ln) of rupture time, minimum rate and rupture strain, with
/// the number of residuals behind each (see the module docs).
pub fn specimen_scatter(ctx: &Context, reference: &Reference) -> [(f64, usize); 3] {
    let lifetimes: Vec<f64> = reference
        .residuals
        .lifetime
        .iter()
        .flatten()
        .copied()
        .collect();
    let mut s_t = reference.noise.lifetime_sd;
    // Replicates: pooled within-group scatter of ln t_f at one (temperature, stress).
    if let Some(r) = crate::fit::replicate_scatter(ctx.curves).1 {
        s_t = s_t.max(r);
    }
    let rms = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
        }
    };
    let rates: Vec<f64> = ctx
        .curves
        .iter()
        .zip(&reference.eval.curves)
        .map(|(c, p)| (p.min_rate / c.min_rate()).ln())
        .filter(|v| v.is_finite())
        .collect();
    let strains: Vec<f64> = ctx
        .curves
        .iter()
        .zip(&reference.eval.curves)
        .map(|(c, p)| (p.rupture_strain / c.rupture_strain).ln())
        .filter(|v| v.is_finite())
        .collect();
    let (mut s_r, mut s_e) = (rms(&rates), rms(&strains));
    // With specimen effects in the error model (replicates in the data, or asked for), the
    // hierarchical fit's scatter of a new specimen's creep-rate factor carries over exactly
    // to ln t_r and ln ε̇_min (every rate of the model scales with A, so the time scale does),
    // the ductility factor's to ln ε_r; each is used where it is wider than the residuals'.
    if let Some(sp) = new_specimen_scatter(ctx, reference) {
        for (k, tau) in sp.kinds.iter().zip(&sp.scatter) {
            match k {
                EffectKind::Rate => {
                    s_t = s_t.max(*tau);
                    s_r = if s_r.is_finite() { s_r.max(*tau) } else { *tau };
                }
                EffectKind::Ductility => {
                    s_e = if s_e.is_finite() { s_e.max(*tau) } else { *tau };
                }
                EffectKind::Coarsening => {}
            }
        }
        // A coarsening factor acts on ln t_r and ln ε̇_min through the simulation, not
        // proportionally: its elasticities are measured by central differences of the
        // population's predictions (ln factor ±0.1) on the data's conditions, the median of
        // the curves taken, and its scatter added to the rate's in quadrature (independent
        // effects).
        if let Some(j) = sp.kinds.iter().position(|k| *k == EffectKind::Coarsening) {
            let tau_k = sp.scatter[j];
            let tau_r = sp
                .kinds
                .iter()
                .position(|k| *k == EffectKind::Rate)
                .map_or(0.0, |i| sp.scatter[i]);
            let [e_t, e_r] = coarsening_elasticities(ctx, reference);
            let add = |s: f64, e: f64| {
                let v = (tau_r * tau_r + (e * tau_k).powi(2)).sqrt();
                if !e.is_finite() {
                    s
                } else if s.is_finite() {
                    s.max(v)
                } else {
                    v
                }
            };
            s_t = add(s_t, e_t);
            s_r = add(s_r, e_r);
        }
    }
    [
        (s_t, lifetimes.len()),
        (s_r, rates.len()),
        (s_e, strains.len()),
    ]
}

/// Median over the data's curves of d ln t_r / d ln Kc and d ln ε̇_min / d ln Kc at the
/// reference constants (central differences at ±0.1 in ln Kc; NaN where no curve gives both
/// sides).
fn coarsening_elasticities(ctx: &Context, reference: &Reference) -> [f64; 2] {
    let Some(kc) = ctx
        .model
        .constants()
        .iter()
        .position(|c| c.role == crate::model::Role::Softening)
    else {
        return [f64::NAN; 2];
    };
    let h: f64 = 0.1;
    let at = |f: f64| {
        crate::likelihood::raw_objective(ctx.model, ctx.curves, &ctx.settings)
            .with_factors(Some(crate::model::objective::CurveFactors {
                index: vec![kc],
                factors: vec![vec![f]; ctx.curves.len()],
            }))
            .evaluate(&reference.params)
    };
    let (up, down) = (at(h.exp()), at((-h).exp()));
    let median = |mut v: Vec<f64>| {
        v.retain(|x| x.is_finite());
        if v.is_empty() {
            return f64::NAN;
        }
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let d = |g: &dyn Fn(&crate::model::objective::CurvePrediction) -> f64| {
        median(
            up.curves
                .iter()
                .zip(&down.curves)
                .map(|(u, w)| (g(u).ln() - g(w).ln()) / (2.0 * h))
                .collect(),
        )
    };
    [d(&|p| p.rupture_time_h), d(&|p| p.min_rate)]
}

/// The specimen effects of the hierarchical fit from `reference`'s constants, when the
/// context's error model carries any (`None` otherwise, or when the fit finds no scatter).
pub fn new_specimen_scatter(
    ctx: &Context,
    reference: &Reference,
) -> Option<crate::likelihood::SpecimenFit> {
    if !ctx.ml.specimen.any() {
        return None;
    }
    // A hierarchical reference carries its own (every fit of the context is hierarchical).
    if ctx.hierarchical() {
        return reference.specimen.clone();
    }
    let opts = crate::likelihood::MlOptions {
        white_first: false,
        ..ctx.ml
    };
    let h = crate::likelihood::ml_fit_from(
        ctx.model,
        ctx.curves,
        &ctx.space,
        &reference.params,
        None,
        &ctx.warm,
        &opts,
    );
    if h.ok() {
        h.specimen
    } else {
        None
    }
}

/// A prediction interval from a confidence interval on the ln scale: each half-width
/// combined with z·s in quadrature.
fn widen(g: f64, lo: f64, hi: f64, s: f64) -> (f64, f64) {
    let z = normal_quantile(0.975);
    let add = (z * s).powi(2);
    (
        g - ((g - lo).powi(2) + add).sqrt(),
        g + ((hi - g).powi(2) + add).sqrt(),
    )
}

/// The constants of the 95 % confidence set {Δ ≤ t95} that a search found, with their Δ.
fn members_of<'a>(
    qi: &'a QuantityInterval,
    th: &'a Thresholds,
) -> impl Iterator<Item = (&'a Vec<f64>, f64)> + 'a {
    qi.lower
        .points
        .iter()
        .chain(&qi.upper.points)
        .filter(move |p| p.delta <= th.t95)
        .map(|p| (&p.params, p.delta))
}

/// An interval's ends widened to every member of the confidence set: `members` holds each
/// member's value of the quantity (NaN where it cannot be predicted) and its Δ. The interval
/// of g is the range of g over the set {Δ ≤ t} (the profile's duality), so a member outside
/// an end shows that end's search stopped short; members within t68 widen the 68 % ends too.
/// Returns whether an end moved.
fn widen_to_set(iv: &mut Interval, members: &[(f64, f64)], th: &Thresholds) -> bool {
    let before = (iv.lo95, iv.hi95, iv.lo68, iv.hi68);
    for &(g, d) in members.iter().filter(|(g, _)| g.is_finite()) {
        if d <= th.t95 {
            iv.lo95 = iv.lo95.min(g);
            iv.hi95 = iv.hi95.max(g);
        }
        if d <= th.t68 {
            iv.lo68 = iv.lo68.min(g);
            iv.hi68 = iv.hi68.max(g);
        }
    }
    before != (iv.lo95, iv.hi95, iv.lo68, iv.hi68)
}

/// The intervals at one load and the confidence set's members their searches found.
pub struct LoadIntervals {
    pub quantities: Vec<PredictedInterval>,
    /// Constants inside the 95 % confidence set, for [`prediction_band`].
    pub members: Vec<Vec<f64>>,
}

/// Confidence and prediction intervals of rupture time, minimum rate and rupture strain at
/// `load` (the three profile searches in parallel), the prediction intervals widened by
/// `scatter` ([`specimen_scatter`], the same at every load: computed once per run, since
/// with specimen effects it is a hierarchical fit). A quantity that cannot be predicted (no
/// rupture within the horizon at the fitted constants) is left out. The three searches
/// explore one confidence set: each interval spans every member any of them found
/// ([`widen_to_set`]).
pub fn prediction_intervals(
    ctx: &Context,
    reference: &Reference,
    load: &Load,
    th: &Thresholds,
    scatter: &[(f64, usize); 3],
) -> LoadIntervals {
    let qi: Vec<Option<QuantityInterval>> = QUANTITIES
        .par_iter()
        .map(|&(_, what, _)| {
            let q = Quantity::Prediction { load: *load, what };
            quantity_interval(ctx, reference, &q, th)
        })
        .collect();
    let members: Vec<(&Vec<f64>, f64)> = qi
        .iter()
        .flatten()
        .flat_map(|q| members_of(q, th))
        .collect();
    // Every member's three quantities (NaN where it does not predict one).
    let values: Vec<[f64; 3]> = members
        .par_iter()
        .map(|(x, _)| {
            QUANTITIES.map(|(_, what, _)| {
                Quantity::Prediction { load: *load, what }
                    .value(ctx, x)
                    .unwrap_or(f64::NAN)
            })
        })
        .collect();
    let quantities = QUANTITIES
        .iter()
        .zip(qi.iter())
        .zip(scatter.iter().copied())
        .enumerate()
        .filter_map(|(k, (((name, _, unit), qi), (s, n)))| {
            let qi = qi.as_ref()?;
            let mut iv = qi.interval;
            let pooled: Vec<(f64, f64)> = values
                .iter()
                .zip(&members)
                .map(|(v, (_, d))| (v[k], *d))
                .collect();
            widen_to_set(&mut iv, &pooled, th);
            let (plo, phi) = widen(
                iv.value,
                iv.lo95,
                iv.hi95,
                if s.is_finite() { s } else { 0.0 },
            );
            let phys = |v: f64| unit * v.exp();
            let mut profile: Vec<(f64, f64)> = qi
                .lower
                .points
                .iter()
                .chain(&qi.upper.points)
                .filter(|p| p.delta.is_finite())
                .map(|p| (p.coord, p.delta))
                .chain(std::iter::once((iv.value, 0.0)))
                .collect();
            profile.sort_by(|a, b| a.0.total_cmp(&b.0));
            Some(PredictedInterval {
                quantity: name,
                value: phys(iv.value),
                conf_lo68: phys(iv.lo68),
                conf_hi68: phys(iv.hi68),
                conf_lo95: phys(iv.lo95),
                conf_hi95: phys(iv.hi95),
                conf_lo_open: iv.lo_open,
                conf_hi_open: iv.hi_open,
                pred_lo95: phys(plo),
                pred_hi95: phys(phi),
                scatter_sd: s,
                scatter_n: n,
                wald_se_ln: qi.wald_se,
                fits: qi.fits(),
                profile,
            })
        })
        .collect();
    LoadIntervals {
        quantities,
        members: members.into_iter().map(|(x, _)| x.clone()).collect(),
    }
}

/// The 95 % confidence interval of the rupture time alone at `load` (h): (value, lo, hi).
pub fn rupture_time_interval(
    ctx: &Context,
    reference: &Reference,
    load: &Load,
    th: &Thresholds,
) -> Option<(f64, f64, f64, usize)> {
    let q = Quantity::Prediction {
        load: *load,
        what: Predicted::LnRuptureTime,
    };
    let qi = quantity_interval(ctx, reference, &q, th)?;
    let iv = qi.interval;
    Some((iv.value.exp(), iv.lo95.exp(), iv.hi95.exp(), qi.fits()))
}

/// The lower end of the rupture time's 95 % confidence interval among `quantities` (h), for
/// [`prediction_band`]; `None` where it has none.
pub fn rupture_lo95(quantities: &[PredictedInterval]) -> Option<f64> {
    quantities
        .iter()
        .find(|q| q.quantity == QUANTITIES[0].0)
        .map(|q| q.conf_lo95)
        .filter(|v| v.is_finite())
}

/// One time of the band around a predicted curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandPoint {
    /// Time, h.
    pub time_h: f64,
    /// Predicted strain, %.
    pub strain_pct: f64,
    /// 95 % confidence band of the model's strain at this time, %.
    pub lo95_pct: f64,
    /// NaN where `hi95_ruptured`.
    pub hi95_pct: f64,
    /// Whether constants inside the 95 % confidence set rupture the test by this time (the
    /// time is at or after the rupture time's lower 95 % confidence bound): the strain has
    /// no upper bound there.
    pub hi95_ruptured: bool,
    /// Whether the lower end is open: its search stopped (at the box, a step limit or a
    /// failure) before Δ crossed the threshold, so the set's lowest strain may lie below.
    pub lo95_open: bool,
}

/// The 95 % confidence band of the predicted strain at `load` at the fractions `fractions` of
/// the predicted rupture time (pointwise prediction profile likelihood, in parallel).
///
/// At a time at or after `rupture_lo95_h`, the lower end of the rupture time's 95 %
/// confidence interval under the same thresholds, the upper side is not searched: the
/// confidence set {Δ ≤ t95} holds constants that rupture by then (those at the rupture
/// time's lower end), so the strain's upper bound is rupture (`hi95_ruptured`); before it,
/// every constant of the set still holds the test intact, since the profile of the rupture
/// time is above t95 below its lower end. (The strain after a rupture is the objective's
/// linear continuation, which a search would follow to thousands of per cent.) Each end spans
/// every member of the confidence set found by any time's search or given in `members`
/// (those of the three quantities' searches, [`LoadIntervals::members`]).
pub fn prediction_band(
    ctx: &Context,
    reference: &Reference,
    load: &Load,
    fractions: &[f64],
    th: &Thresholds,
    rupture_lo95_h: Option<f64>,
    members: &[Vec<f64>],
) -> Vec<BandPoint> {
    let q = Quantity::Prediction {
        load: *load,
        what: Predicted::LnRuptureTime,
    };
    let Some(ln_t) = q.value(ctx, &reference.params) else {
        return vec![];
    };
    let t_r = ln_t.exp();
    let found: Vec<(BandPoint, Vec<Vec<f64>>)> = fractions
        .par_iter()
        .filter_map(|&f| {
            let t = f * t_r;
            let q = Quantity::Prediction {
                load: *load,
                what: Predicted::StrainAt(t),
            };
            let ruptured = rupture_lo95_h.is_some_and(|lo| t >= lo);
            let qi = quantity_interval_sides(ctx, reference, &q, th, !ruptured)?;
            let iv = qi.interval;
            // The constants of the confidence set this search found.
            let members = qi
                .lower
                .points
                .iter()
                .chain(&qi.upper.points)
                .filter(|p| p.delta <= th.t95)
                .map(|p| p.params.clone())
                .collect();
            Some((
                BandPoint {
                    time_h: t,
                    strain_pct: 100.0 * iv.value,
                    lo95_pct: 100.0 * iv.lo95,
                    hi95_pct: if ruptured { f64::NAN } else { 100.0 * iv.hi95 },
                    hi95_ruptured: ruptured,
                    lo95_open: iv.lo_open,
                },
                members,
            ))
        })
        .collect();
    let mut band: Vec<BandPoint> = found.iter().map(|(b, _)| b.clone()).collect();
    // Every member's strain at every band time (%; None once it has ruptured; NaN beyond the
    // horizon of a member that did not rupture within it; a failed simulation is unused).
    let times: Vec<f64> = band.iter().map(|b| b.time_h).collect();
    let ode = super::constrained::prediction_ode(ctx);
    let strains: Vec<Vec<Option<f64>>> = found
        .iter()
        .flat_map(|(_, m)| m)
        .chain(members)
        .collect::<Vec<_>>()
        .par_iter()
        .filter_map(|x| {
            let mut out = vec![0.0; times.len()];
            let r = ctx.model.simulate(x, load, &times, &mut out, &ode);
            let after = match r.outcome {
                crate::ode::Outcome::Ruptured => None,
                crate::ode::Outcome::Horizon => Some(f64::NAN),
                _ => return None,
            };
            Some(
                (0..times.len())
                    .map(|k| {
                        if k < r.n_out {
                            Some(100.0 * out[k])
                        } else {
                            after
                        }
                    })
                    .collect(),
            )
        })
        .collect();
    widen_to_members(&mut band, &strains);
    band
}

/// Each band point widened to every member of the confidence set found by any point's
/// search (`strains[m][k]`: member m's strain at band time k, %, `None` once it has ruptured,
/// NaN where it is not known):
/// the set's strain at a time spans at least its members', so a search that stopped short
/// at one time (a lower end above what another time's search found, although the strain
/// only grows with time) is corrected by the others. A member ruptured by a time makes that
/// time's upper end rupture.
fn widen_to_members(band: &mut [BandPoint], strains: &[Vec<Option<f64>>]) {
    for (k, b) in band.iter_mut().enumerate() {
        for m in strains {
            match m.get(k).copied().flatten() {
                Some(e) if e.is_finite() => {
                    b.lo95_pct = b.lo95_pct.min(e);
                    if !b.hi95_ruptured {
                        b.hi95_pct = b.hi95_pct.max(e);
                    }
                }
                Some(_) => {}
                None => {
                    b.hi95_ruptured = true;
                    b.hi95_pct = f64::NAN;
                }
            }
        }
    }
}

/// Predictions of replicate data sets: ln of (rupture time, minimum rate, rupture strain) at
/// `load` after refitting each of `b` replicates simulated under the reference and its error
/// model (warm starts: the reference and its other optima). NaN where a refit or prediction
/// failed. Replicate k uses its own random stream: the result does not depend on the thread
/// count.
pub fn bootstrap_predictions(
    ctx: &Context,
    reference: &Reference,
    load: &Load,
    b: usize,
    seed: u64,
) -> Vec<[f64; 3]> {
    (0..b)
        .into_par_iter()
        .map(|k| {
            let mut rng = replicate_rng(seed, PREDICTION_STREAM, k);
            let (data, drawn) = super::replicate(ctx, reference, &mut rng);
            let c = ctx.on(&data);
            let Some(f) = super::refit_replicate(ctx, reference, &data, drawn.as_ref()) else {
                return [f64::NAN; 3];
            };
            let mut out = [f64::NAN; 3];
            for (k, (_, what, _)) in QUANTITIES.iter().enumerate() {
                let q = Quantity::Prediction {
                    load: *load,
                    what: *what,
                };
                out[k] = q.value(&c, &f.params).unwrap_or(f64::NAN);
            }
            out
        })
        .collect()
}

/// The (2.5 %, 97.5 %) percentiles of the finite values of `v` (NaN if fewer than 10).
pub fn percentile95(v: &[f64]) -> (f64, f64) {
    let mut f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.len() < 10 {
        return (f64::NAN, f64::NAN);
    }
    f.sort_by(|a, b| a.total_cmp(b));
    let q = |p: f64| {
        let x = p * (f.len() - 1) as f64;
        let (i, w) = (x.floor() as usize, x - x.floor());
        f[i] * (1.0 - w) + f[(i + 1).min(f.len() - 1)] * w
    };
    (q(0.025), q(0.975))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_interval_adds_the_scatter_in_quadrature() {
        let z = normal_quantile(0.975);
        let (lo, hi) = widen(0.0, -0.3, 0.4, 0.1);
        assert!((lo + (0.09 + (0.1 * z).powi(2)).sqrt()).abs() < 1e-12);
        assert!((hi - (0.16 + (0.1 * z).powi(2)).sqrt()).abs() < 1e-12);
        // No scatter: the confidence interval itself.
        assert_eq!(widen(1.0, 0.5, 2.0, 0.0), (0.5, 2.0));
    }

    /// A condition's intervals come back from the journal bit for bit (NaN, infinities and
    /// the open flags included); a record of another shape is recomputed, not misread.
    #[test]
    fn a_journaled_condition_comes_back_exactly() {
        let q = |k: usize, v: f64| PredictedInterval {
            quantity: QUANTITIES[k].0,
            value: v,
            conf_lo68: v * 0.9,
            conf_hi68: 0.1 + v,
            conf_lo95: f64::NEG_INFINITY,
            conf_hi95: 1.0 / 3.0,
            conf_lo_open: true,
            conf_hi_open: false,
            pred_lo95: f64::NAN,
            pred_hi95: 2.0_f64.sqrt(),
            scatter_sd: 0.123_456_789_012_345_67,
            scatter_n: 7,
            wald_se_ln: f64::INFINITY,
            fits: 13,
            profile: vec![(1e-300, 0.5), (-2.5, f64::NAN)],
        };
        let c = ConditionIntervals {
            quantities: vec![q(2, 17.25), q(0, 1234.5678)],
            band: vec![BandPoint {
                time_h: 0.1 + 0.2,
                strain_pct: 5e-324,
                lo95_pct: -0.0,
                hi95_pct: f64::MAX,
                hi95_ruptured: true,
                lo95_open: true,
            }],
        };
        let text = serde_json::to_string(&ConditionRecord::of(&c)).unwrap();
        let back = serde_json::from_str::<ConditionRecord>(&text)
            .unwrap()
            .intervals()
            .unwrap();
        assert_eq!(format!("{back:?}"), format!("{c:?}"));
        let bits = |c: &ConditionIntervals| -> Vec<u64> {
            c.band
                .iter()
                .flat_map(|b| [b.time_h, b.strain_pct, b.lo95_pct, b.hi95_pct])
                .map(f64::to_bits)
                .collect()
        };
        assert_eq!(bits(&back), bits(&c));
        let short = text.replacen("[1234.5678,", "[", 1);
        let r: ConditionRecord = serde_json::from_str(&short).unwrap();
        assert!(r.intervals().is_none(), "{short}");
    }

    /// The band spans every member of the confidence set at every time: a lower end above a
    /// member's strain comes down to it, an upper end below it goes up, a member ruptured by
    /// a time makes that time's upper end rupture; members inside change nothing.
    #[test]
    fn the_band_spans_every_member_found() {
        let point = |t: f64, lo: f64, e: f64, hi: f64| BandPoint {
            time_h: t,
            strain_pct: e,
            lo95_pct: lo,
            hi95_pct: hi,
            hi95_ruptured: !hi.is_finite(),
            lo95_open: false,
        };
        let band = vec![
            point(1.0, 1.0, 1.5, 2.0),
            point(2.0, 5.8, 6.0, 6.5),
            point(3.0, 4.5, 9.0, f64::NAN),
        ];
        // Inside: nothing moves.
        let mut b = band.clone();
        widen_to_members(&mut b, &[vec![Some(1.2), Some(6.0), Some(8.0)]]);
        assert_eq!(format!("{b:?}"), format!("{band:?}"));
        // A member at 4.9 % at time 2 (the search's 5.8 % was too high), above the upper end
        // at time 1, and ruptured by time 3.
        let mut b = band.clone();
        widen_to_members(
            &mut b,
            &[
                vec![Some(2.4), Some(4.9), None],
                vec![Some(1.1), Some(6.1), Some(4.0)],
            ],
        );
        assert_eq!((b[0].lo95_pct, b[0].hi95_pct), (1.0, 2.4));
        assert_eq!((b[1].lo95_pct, b[1].hi95_pct), (4.9, 6.5));
        assert_eq!(b[2].lo95_pct, 4.0);
        assert!(b[2].hi95_ruptured && b[2].hi95_pct.is_nan());
        // A member that did not rupture within its horizon: its strains up to it count, and
        // after it nothing is known (NaN), which marks nothing.
        let mut b = band.clone();
        widen_to_members(&mut b, &[vec![Some(0.9), Some(f64::NAN), Some(f64::NAN)]]);
        assert_eq!((b[0].lo95_pct, b[1].lo95_pct), (0.9, 5.8));
        assert!(!b[1].hi95_ruptured && b[1].hi95_pct == 6.5);
        // A member ruptured by time 2 marks time 2 too.
        let mut b = band.clone();
        widen_to_members(&mut b, &[vec![Some(1.5), None, None]]);
        assert!(!b[0].hi95_ruptured && b[1].hi95_ruptured && b[1].hi95_pct.is_nan());
        assert_eq!(b[1].lo95_pct, 5.8);
    }

    /// An interval spans every member of the confidence set: a member within t95 outside an
    /// end moves that 95 % end, within t68 the 68 % end too; members beyond t95 or without a
    /// value move nothing.
    #[test]
    fn an_interval_spans_every_member_of_the_set() {
        let th = Thresholds {
            t68: 1.0,
            t95: 4.0,
            factor: 1.0,
        };
        let iv = Interval {
            value: 0.0,
            lo68: -1.0,
            hi68: 1.0,
            lo95: -2.0,
            hi95: 2.0,
            lo_open: false,
            hi_open: false,
        };
        let ends = |i: &Interval| (i.lo95, i.lo68, i.hi68, i.hi95);
        for (members, moved, want) in [
            (vec![(0.5, 0.3), (-1.5, 3.0)], false, (-2.0, -1.0, 1.0, 2.0)),
            (vec![(-2.5, 3.9)], true, (-2.5, -1.0, 1.0, 2.0)),
            (vec![(1.4, 0.9), (3.0, 4.0)], true, (-2.0, -1.0, 1.4, 3.0)),
            (
                vec![(9.0, 4.5), (f64::NAN, 0.1), (-9.0, f64::NAN)],
                false,
                (-2.0, -1.0, 1.0, 2.0),
            ),
        ] {
            let mut i = iv;
            assert_eq!(widen_to_set(&mut i, &members, &th), moved, "{members:?}");
            assert_eq!(ends(&i), want, "{members:?}");
            assert_eq!((i.value, i.lo_open, i.hi_open), (0.0, false, false));
        }
    }

    #[test]
    fn percentiles_interpolate() {
        let v: Vec<f64> = (0..=100).map(|k| k as f64).collect();
        let (lo, hi) = percentile95(&v);
        assert!((lo - 2.5).abs() < 1e-12 && (hi - 97.5).abs() < 1e-12);
        assert!(percentile95(&[1.0, f64::NAN]).0.is_nan());
    }
}

/// What `creepfit predict --intervals` adds at one condition: the intervals of the three
/// predicted quantities.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionIntervals {
    /// The intervals ([`prediction_intervals`]); a quantity that cannot be predicted is left
    /// out.
    pub quantities: Vec<PredictedInterval>,
    /// The 95 % confidence band of the predicted curve at `[profile] band_points` times
    /// ([`prediction_band`]); empty if the prediction does not rupture.
    pub band: Vec<BandPoint>,
}

impl ConditionIntervals {
    /// The interval of `quantity` (`rupture_time_h`, …), if it could be computed.
    pub fn get(&self, quantity: &str) -> Option<&PredictedInterval> {
        self.quantities.iter().find(|q| q.quantity == quantity)
    }
}

/// The maximum-likelihood refit that intervals are centred on, and how far it lies from the
/// constants it started from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refit {
    /// The given constants (model order).
    pub given: Vec<f64>,
    /// The refitted constants: the maximum-likelihood fit from `given` (model order).
    pub params: Vec<f64>,
    /// −2 ln L at the refit and at the given constants (error model estimated at each; NaN
    /// where the given constants cannot be evaluated).
    pub neg2ll: f64,
    pub given_neg2ll: f64,
    /// The kinds of specimen effects the refit's likelihood (and every profile's) integrates
    /// out (empty: identical specimens); its constants are then the population's.
    pub specimen_effects: Vec<EffectKind>,
    /// Whether the refit left out the specimen factors `auto` chose, their scatter beyond
    /// the stress trend zero ([`super::Context::settles_without_specimens`]).
    pub without_specimen_factors: bool,
    /// Per kind of specimen effect, how the refit's factors differ between the test campaigns
    /// the labels name (empty without effects or campaigns): a new test's interval draws the
    /// specimen from one population, so for a campaign not in the data it leaves that
    /// difference out.
    pub campaign_levels: Vec<crate::likelihood::CampaignLevels>,
}

impl Refit {
    /// −2 ln L at the given constants minus at the refit (≥ 0 up to the optimiser's
    /// tolerance: how much less likely the given constants are).
    pub fn delta_neg2ll(&self) -> f64 {
        self.given_neg2ll - self.neg2ll
    }
}

/// What `creepfit predict --intervals` computes: the refit the intervals are centred on and
/// the intervals at each condition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IntervalsRun {
    pub refit: Refit,
    pub conditions: Vec<ConditionIntervals>,
    /// The bootstrap calibration of the intervals' thresholds (`None` with `[profile]
    /// calibrate = 0`: plain χ² thresholds).
    pub calibration: Option<super::calibrate::Calibration>,
    /// Where the wall time went (not a result: `timings.json`).
    #[serde(skip)]
    pub timings: IntervalsTimings,
}

/// Wall time of each phase of [`intervals_at_observed`], s (a resumed phase counts only what
/// it computed again).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct IntervalsTimings {
    /// The maximum-likelihood refit the intervals are centred on (and its refit without
    /// specimen factors, where they settle at zero).
    pub refit: f64,
    /// The bootstrap calibration of the thresholds (`[profile] calibrate` replicates).
    pub calibration: f64,
    /// The specimen scatter of a new test (a hierarchical fit where the error model has
    /// specimen effects).
    pub scatter: f64,
    /// The profile searches of rupture time, minimum rate and rupture strain, all conditions.
    pub intervals: f64,
    /// The confidence bands of the curves, all conditions.
    pub bands: f64,
    /// The whole computation.
    pub total: f64,
}

/// A condition's intervals as journaled: every number exact (non-finite ones by name), so
/// that a resumed run writes what an uninterrupted one writes.
#[derive(Debug, Serialize, serde::Deserialize)]
struct ConditionRecord {
    quantities: Vec<QuantityRecord>,
    /// Per band point: time (h), strain, lo95, hi95 (%).
    band: Vec<Exact>,
    /// Per band point, `hi95_ruptured`.
    band_ruptured: Vec<bool>,
    /// Per band point, `lo95_open`.
    band_lo_open: Vec<bool>,
}

/// One [`PredictedInterval`] as journaled.
#[derive(Debug, Serialize, serde::Deserialize)]
struct QuantityRecord {
    /// Index in [`QUANTITIES`].
    quantity: usize,
    /// value, conf_lo68, conf_hi68, conf_lo95, conf_hi95, pred_lo95, pred_hi95, scatter_sd,
    /// wald_se_ln.
    numbers: Exact,
    open: (bool, bool),
    scatter_n: usize,
    fits: usize,
    /// The profile's points, (coordinate, Δ) flattened.
    profile: Exact,
}

impl ConditionRecord {
    fn of(c: &ConditionIntervals) -> ConditionRecord {
        ConditionRecord {
            quantities: c
                .quantities
                .iter()
                .map(|q| QuantityRecord {
                    quantity: QUANTITIES
                        .iter()
                        .position(|(n, _, _)| *n == q.quantity)
                        .expect("a quantity of QUANTITIES"),
                    numbers: Exact(vec![
                        q.value,
                        q.conf_lo68,
                        q.conf_hi68,
                        q.conf_lo95,
                        q.conf_hi95,
                        q.pred_lo95,
                        q.pred_hi95,
                        q.scatter_sd,
                        q.wald_se_ln,
                    ]),
                    open: (q.conf_lo_open, q.conf_hi_open),
                    scatter_n: q.scatter_n,
                    fits: q.fits,
                    profile: Exact(q.profile.iter().flat_map(|&(x, d)| [x, d]).collect()),
                })
                .collect(),
            band: c
                .band
                .iter()
                .map(|b| Exact(vec![b.time_h, b.strain_pct, b.lo95_pct, b.hi95_pct]))
                .collect(),
            band_ruptured: c.band.iter().map(|b| b.hi95_ruptured).collect(),
            band_lo_open: c.band.iter().map(|b| b.lo95_open).collect(),
        }
    }

    /// The intervals again; `None` for a record of another shape (recomputed).
    fn intervals(&self) -> Option<ConditionIntervals> {
        let quantities = self
            .quantities
            .iter()
            .map(|q| {
                let n = &q.numbers.0;
                if n.len() != 9 || q.profile.0.len() % 2 != 0 {
                    return None;
                }
                Some(PredictedInterval {
                    quantity: QUANTITIES.get(q.quantity)?.0,
                    value: n[0],
                    conf_lo68: n[1],
                    conf_hi68: n[2],
                    conf_lo95: n[3],
                    conf_hi95: n[4],
                    conf_lo_open: q.open.0,
                    conf_hi_open: q.open.1,
                    pred_lo95: n[5],
                    pred_hi95: n[6],
                    scatter_sd: n[7],
                    scatter_n: q.scatter_n,
                    wald_se_ln: n[8],
                    fits: q.fits,
                    profile: q.profile.0.chunks(2).map(|p| (p[0], p[1])).collect(),
                })
            })
            .collect::<Option<Vec<_>>>()?;
        if self.band_ruptured.len() != self.band.len() || self.band_lo_open.len() != self.band.len()
        {
            return None;
        }
        let band = self
            .band
            .iter()
            .zip(self.band_ruptured.iter().zip(&self.band_lo_open))
            .map(|(b, (&hi95_ruptured, &lo95_open))| match b.0[..] {
                [time_h, strain_pct, lo95_pct, hi95_pct] => Some(BandPoint {
                    time_h,
                    strain_pct,
                    lo95_pct,
                    hi95_pct,
                    hi95_ruptured,
                    lo95_open,
                }),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        Some(ConditionIntervals { quantities, band })
    }
}

/// The fractions of the predicted rupture time at which a band is computed: k/n for
/// k = 1 … n (`[profile] band_points` = n), so that the band runs to the rupture time, as
/// far as the curve it surrounds.
pub fn band_fractions(n: usize) -> Vec<f64> {
    (1..=n).map(|k| k as f64 / n as f64).collect()
}

/// Intervals at untested conditions for `predict --intervals`: a local maximum-likelihood
/// fit from `params` under the error model (as `profile --constants`; the intervals are
/// centred on it, [`Refit`]), thresholds calibrated as `profile` does (`[profile] calibrate`
/// bootstrap replicates over the rupture times at the conditions; plain χ² with 0), then
/// [`prediction_intervals`] and [`prediction_band`] at each `load`.
pub fn intervals_at(
    setup: &crate::config::LikelihoodSetup,
    model: &dyn crate::model::Model,
    data: &crate::data::Dataset,
    params: &[f64],
    loads: &[Load],
) -> crate::error::Result<IntervalsRun> {
    intervals_at_observed(
        setup,
        model,
        data,
        params,
        loads,
        &crate::progress::Hooks::default(),
    )
}

/// [`intervals_at`] telling `hooks.observer` of its phases (refit, calibration replicates,
/// one step per condition's intervals and band); `Err` when it asks to stop. Nothing is
/// journaled (the calibration replicates only if `hooks.journal` is given).
pub fn intervals_at_observed(
    setup: &crate::config::LikelihoodSetup,
    model: &dyn crate::model::Model,
    data: &crate::data::Dataset,
    params: &[f64],
    loads: &[Load],
    hooks: &crate::progress::Hooks,
) -> crate::error::Result<IntervalsRun> {
    let t0 = Instant::now();
    let mut timings = IntervalsTimings::default();
    hooks.observer.phase("maximum-likelihood refit", None);
    let ctx = super::report::context(setup, model, data);
    let f = ctx.fit(&ctx.space, params, false);
    let mut reference = super::reference_from(&ctx, vec![f])?;
    // Every kind's scatter at zero beyond the stress trend: refitted without the specimen
    // factors, and the intervals of the plain likelihood ([`Context::settles_without_specimens`]).
    let without_specimen_factors = ctx.settles_without_specimens(&reference);
    let ctx = if without_specimen_factors {
        let plain = ctx.without_specimens();
        let f = plain.fit(&plain.space, params, false);
        reference = super::reference_from(&plain, vec![f])?;
        plain
    } else {
        ctx
    };
    let refit = Refit {
        given: params.to_vec(),
        params: reference.params.clone(),
        neg2ll: reference.neg2ll,
        given_neg2ll: super::report::neg2ll_at(&ctx, params).unwrap_or(f64::NAN),
        specimen_effects: reference
            .specimen
            .as_ref()
            .map(|s| s.kinds.clone())
            .unwrap_or_default(),
        without_specimen_factors,
        campaign_levels: reference
            .specimen
            .as_ref()
            .map(|s| s.campaign_levels(ctx.curves))
            .unwrap_or_default(),
    };
    timings.refit = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let pc = &setup.profile;
    let (th, calibration) = if pc.calibrate > 0 {
        let cons = super::report::calibration_constants(&ctx, &reference);
        let qs = super::calibrate::rupture_time_quantities(loads);
        let cal =
            super::calibrate::bartlett(&ctx, &reference, &cons, &qs, pc.calibrate, pc.seed, hooks)?;
        (cal.prediction_thresholds.clone(), Some(cal))
    } else {
        (vec![Thresholds::chi2(1.0); loads.len()], None)
    };
    timings.calibration = t1.elapsed().as_secs_f64();
    let fractions = band_fractions(pc.band_points);
    let t2 = Instant::now();
    let scatter = specimen_scatter_for(&ctx, &reference, loads.len());
    timings.scatter = t2.elapsed().as_secs_f64();
    const PHASE: &str = "intervals at the conditions";
    hooks.phase(PHASE, loads.len());
    // Each condition's intervals journaled under the hash of what they are computed from.
    let prefix = format!(
        "intervals/{}/",
        debug_hash(&(&reference, &th, &scatter, &fractions))
    );
    if let Some(j) = hooks.journal {
        let found = loads
            .iter()
            .filter(|l| j.contains(&format!("{prefix}{}", debug_hash(l))))
            .count();
        hooks.observer.resumed(found as u64);
    }
    let conditions = loads
        .iter()
        .zip(&th)
        .map(|(l, th)| {
            let key = format!("{prefix}{}", debug_hash(l));
            if let Some(c) = hooks
                .journal
                .and_then(|j| j.get::<ConditionRecord>(&key))
                .and_then(|r| r.intervals())
            {
                return Ok(c);
            }
            hooks.check(PHASE)?;
            let ti = Instant::now();
            let li = prediction_intervals(&ctx, &reference, l, th, &scatter);
            timings.intervals += ti.elapsed().as_secs_f64();
            let tb = Instant::now();
            let band = prediction_band(
                &ctx,
                &reference,
                l,
                &fractions,
                th,
                rupture_lo95(&li.quantities),
                &li.members,
            );
            let quantities = li.quantities;
            timings.bands += tb.elapsed().as_secs_f64();
            let c = ConditionIntervals { quantities, band };
            if let Some(j) = hooks.journal {
                j.put(&key, &ConditionRecord::of(&c))?;
            }
            hooks.step();
            Ok(c)
        })
        .collect::<crate::error::Result<_>>()?;
    timings.total = t0.elapsed().as_secs_f64();
    Ok(IntervalsRun {
        refit,
        conditions,
        calibration,
        timings,
    })
}
