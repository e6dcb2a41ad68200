//! Profile likelihoods of the constants, their intervals and identifiability classes, and
//! the likelihood-ratio interval of any smooth function of the constants.
//!
//! **Constants** ([`profile_constants`]): from the optimum outward on each side, constant j is
//! stepped in its unit-box coordinate (log scale for log constants) and the others and the
//! error model are re-fitted at every step, warm-started from the previous step. The step
//! adapts so that the signed root √Δ of Δ = −2 ln L − min grows by about [`ROOT_STEP`] per
//! step (a quadratic profile is then sampled evenly up to its 95 % crossing in about six
//! steps); a step that grows it by more than twice that is halved and redone. A side ends
//! when Δ crosses the 95 % threshold, at the bound (the last step lands exactly on it), or
//! after [`MAX_POINTS`] points. Interval ends are interpolated linearly in √Δ between the
//! two points around a crossing (exact for a quadratic profile).
//!
//! **Inner fits are never silently skipped**: each point is fitted from the previous point;
//! when that fails, or lands above the 68 % threshold (where a continuation stuck in a side
//! valley would narrow the interval), it is fitted again from the optimum with the held value
//! put in, and the lower is kept (with specimen effects also from the optimum cold: new
//! effects, the white stage first); when both fail, from the other local optima of the
//! multistart and from two random starts. Every point records how many fits it took and
//! whether it needed a retry; a point that fails from every start is recorded as failed and
//! the step is halved; a side that cannot go on ends as `failed`, and the interval is open
//! on that side (reported in `summary.json`).
//!
//! **Classes**: `identifiable` when both sides cross the 95 % threshold inside the bounds;
//! `structurally_non_identifiable` when the profile is flat — it stays within [`FLAT_TOL`] of
//! its minimum across the whole box on both sides (the data say nothing about the constant
//! alone); otherwise `practically_non_identifiable`, with the open side(s) and the bound(s)
//! reached.
//!
//! **A better optimum**: if a profile point lies more than [`BETTER_TOL`] below the
//! reference, the reference was not the global optimum: the caller refits from that point and
//! profiles again ([`crate::uncertainty::report::core`](fn@crate::uncertainty::report::core)).

use std::sync::Mutex;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::constrained::{constrained_fit, held_fit, PointFit, Quantity};
use super::{covariance, information, Context, Reference, Thresholds};
use crate::journal::debug_hash;
use crate::lsq::Termination;
use crate::progress::Hooks;

/// Target growth of √Δ per continuation step.
pub const ROOT_STEP: f64 = 0.35;
/// Most points per side of a constant's profile.
pub const MAX_POINTS: usize = 40;
/// Smallest continuation step, unit box.
pub const MIN_STEP: f64 = 1e-4;
/// Largest continuation step, unit box.
pub const MAX_STEP: f64 = 0.2;
/// A profile that stays within this of its minimum (−2 ln L) over the whole box is flat:
/// 1/75 of the 95 % threshold, far above the optimiser's accuracy (~1e-5).
pub const FLAT_TOL: f64 = 0.05;
/// A profile point this far (−2 ln L) below the reference means the reference was not the
/// global optimum.
pub const BETTER_TOL: f64 = 0.05;

/// Identifiability of a constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    /// The profile crosses the 95 % threshold on both sides inside the bounds.
    Identifiable,
    /// It does not on one or both sides (see the open sides).
    PracticallyNonIdentifiable,
    /// It is flat across the whole box.
    StructurallyNonIdentifiable,
}

impl Class {
    /// The name in `intervals.csv`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Class::Identifiable => "identifiable",
            Class::PracticallyNonIdentifiable => "practically_non_identifiable",
            Class::StructurallyNonIdentifiable => "structurally_non_identifiable",
        }
    }
}

/// How one side of a profile ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SideEnd {
    /// Δ crossed the 95 % threshold.
    Crossed,
    /// The bound was reached below the threshold.
    Bound,
    /// The held quantity could not be moved further (the box limits it) below the threshold.
    Unreachable,
    /// [`MAX_POINTS`] points without crossing.
    PointLimit,
    /// The inner fits failed from every start and the step could not be reduced further.
    Failed,
    /// Not searched: the caller knows the side is open (the upper side of a band point
    /// after the rupture time's lower confidence bound).
    NotSearched,
}

/// One point of a profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProfilePoint {
    /// The held value (physical units for a constant; g for a quantity).
    pub value: f64,
    /// Its coordinate: unit box for a constant, g for a quantity.
    pub coord: f64,
    /// −2 ln L − its minimum (NaN for a failed point).
    pub delta: f64,
    /// The other constants at this point, model order.
    pub params: Vec<f64>,
    /// Fits run for this point.
    pub fits: usize,
    /// Whether the first fit failed or was bettered by a retry.
    pub retried: bool,
    /// How the kept fit ended (`simulation_failure` for a failed point).
    pub termination: Termination,
    /// Why it failed, for a failed point.
    pub failure: Option<String>,
}

impl ProfilePoint {
    fn ok(&self) -> bool {
        self.delta.is_finite()
    }
}

/// One side of a profile, from the optimum outward.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Side {
    /// The points, nearest the optimum first (the optimum itself not included).
    pub points: Vec<ProfilePoint>,
    /// How the side ended.
    pub end: SideEnd,
}

impl Side {
    /// Number of fits on this side.
    pub fn fits(&self) -> usize {
        self.points.iter().map(|p| p.fits).sum()
    }
    /// Number of failed points.
    pub fn failed_points(&self) -> usize {
        self.points.iter().filter(|p| !p.ok()).count()
    }
    /// Number of points that needed a retry.
    pub fn retried_points(&self) -> usize {
        self.points.iter().filter(|p| p.retried).count()
    }
    /// The lowest point, if any lies below the optimum.
    fn lowest(&self) -> Option<&ProfilePoint> {
        self.points
            .iter()
            .filter(|p| p.ok())
            .min_by(|a, b| a.delta.total_cmp(&b.delta))
    }
}

/// 68 % and 95 % interval ends; an open end is the limit the profile reached (a bound).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// The estimate.
    pub value: f64,
    pub lo68: f64,
    pub hi68: f64,
    pub lo95: f64,
    pub hi95: f64,
    /// The 95 % interval is open below (lo95 is the limit reached, not a crossing).
    pub lo_open: bool,
    /// The 95 % interval is open above.
    pub hi_open: bool,
}

/// A side that did not cross, with the limit it reached.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenSide {
    /// `lower` or `upper`.
    pub side: &'static str,
    /// How the side ended.
    pub end: SideEnd,
    /// The limit reached (the bound for [`SideEnd::Bound`]), physical units.
    pub limit: f64,
    /// Largest Δ reached on that side.
    pub max_delta: f64,
}

/// The profile of one constant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstantProfile {
    /// Constant name.
    pub name: String,
    /// Index, model order.
    pub index: usize,
    /// Lower and upper bounds.
    pub lb: f64,
    pub ub: f64,
    /// The intervals.
    pub interval: Interval,
    /// The thresholds of Δ(−2 ln L) they were read at.
    pub thresholds: Thresholds,
    /// Identifiability.
    pub class: Class,
    /// Sides that did not cross the 95 % threshold.
    pub open: Vec<OpenSide>,
    /// Wald (Fisher information) standard error in the unit box (for comparison).
    pub wald_se_unit: f64,
    /// The two sides.
    pub lower: Side,
    pub upper: Side,
}

impl ConstantProfile {
    /// Fits run for this profile.
    pub fn fits(&self) -> usize {
        self.lower.fits() + self.upper.fits()
    }
    /// The lowest point below the reference, if any is more than [`BETTER_TOL`] below it.
    pub fn better(&self) -> Option<&ProfilePoint> {
        [self.lower.lowest(), self.upper.lowest()]
            .into_iter()
            .flatten()
            .filter(|p| p.delta < -BETTER_TOL)
            .min_by(|a, b| a.delta.total_cmp(&b.delta))
    }
}

/// Where the signed root √Δ of a side first reaches √t: interpolated linearly in √Δ between
/// the points around the crossing (`points`: (coord, Δ), nearest the optimum first, starting
/// with the optimum itself at Δ = 0). `None` if it never does.
pub fn crossing(points: &[(f64, f64)], t: f64) -> Option<f64> {
    let rt = t.sqrt();
    let mut prev: Option<(f64, f64)> = None;
    for &(c, d) in points {
        if !d.is_finite() {
            continue;
        }
        let r = d.max(0.0).sqrt();
        if r >= rt {
            return Some(match prev {
                Some((pc, pr)) if r > pr => pc + (c - pc) * (rt - pr) / (r - pr),
                _ => c,
            });
        }
        prev = Some((c, r));
    }
    None
}

/// Fit one profile point of constant j at unit coordinate `u`, warm-started from `warm` (see
/// the module docs for the retries).
fn fit_point(
    ctx: &Context,
    reference: &Reference,
    j: usize,
    u: f64,
    warm: &[f64],
    t68: f64,
    seed: u64,
) -> ProfilePoint {
    let value = ctx.space.from_unit_one(j, u);
    let mut fits = 1;
    let first = held_fit(ctx, j, value, warm, true);
    let mut best = first.clone();
    let mut retried = false;
    let delta = |f: &PointFit| f.neg2ll - reference.neg2ll;
    if !first.ok() || delta(&first) > t68 {
        fits += 1;
        let alt = held_fit(ctx, j, value, &reference.params, true);
        if alt.ok() && (!best.ok() || alt.neg2ll < best.neg2ll - 1e-6) {
            best = alt;
            retried = true;
        }
        // With specimen effects, once more from the optimum cold (new effects, the white
        // stage first): both warm starts carry effects that can leave the held fit where it
        // began, every other constant unmoved and the objective flat for six iterations
        // (`plateau`). Measured on generated set 90014 (specimens world): A's lower side
        // stopped every point there, its 95 % interval [5.54e-9, 7.76e-9] (χ²) missed the
        // true 4.08e-9, whose own held fit is 1.6 above the optimum; with this fit
        // [3.11e-9, 1.23e-8].
        if ctx.hierarchical() {
            fits += 1;
            let cold = held_fit(ctx, j, value, &reference.params, false);
            if cold.ok() && (!best.ok() || cold.neg2ll < best.neg2ll - 1e-6) {
                best = cold;
                retried = true;
            }
        }
    }
    if !best.ok() {
        retried = true;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut others: Vec<Vec<f64>> = reference.basins.clone();
        for _ in 0..2 {
            let uu: Vec<f64> = (0..ctx.space.len()).map(|_| rng.gen()).collect();
            let mut x = vec![0.0; ctx.space.len()];
            ctx.space.from_unit(&uu, &mut x);
            others.push(x);
        }
        for s in others {
            fits += 1;
            let f = held_fit(ctx, j, value, &s, false);
            if f.ok() && (!best.ok() || f.neg2ll < best.neg2ll) {
                best = f;
            }
        }
    }
    ProfilePoint {
        value,
        coord: u,
        delta: if best.ok() { delta(&best) } else { f64::NAN },
        params: best.params,
        fits,
        retried,
        termination: best.termination,
        failure: best.failure,
    }
}

/// Where the points of one side are kept as they finish: each step's point (predictor and
/// corrector together) under `{key}/step{n}`, so that a run killed inside a side resumes at
/// its last finished step. The loop's state follows from the points alone (they are exact in
/// the journal), so a resumed side is the uninterrupted one bit for bit.
struct PointMemo<'a> {
    hooks: &'a Hooks<'a>,
    key: String,
    write_error: &'a Mutex<Option<crate::Error>>,
}

impl PointMemo<'_> {
    /// Step n's point from the journal, else computed by `f` and journaled; `None` when it is
    /// not journaled and the observer asks to stop (or a journal write failed).
    fn get_or(&self, n: usize, f: impl FnOnce() -> ProfilePoint) -> Option<ProfilePoint> {
        let k = format!("{}/step{n}", self.key);
        let journal = self.hooks.journal;
        if let Some(r) = journal.and_then(|jl| jl.get::<PointRecord>(&k)) {
            return Some(r.into());
        }
        if self.hooks.observer.cancelled() || self.write_error.lock().is_ok_and(|e| e.is_some()) {
            return None;
        }
        let p = f();
        if let Some(jl) = journal {
            if let Err(e) = jl.put(&k, &PointRecord::from(&p)) {
                self.write_error
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .get_or_insert(e);
            }
        }
        Some(p)
    }
}

/// One side (`dir` = −1 lower, +1 upper) of constant j's profile by continuation; each
/// step's point goes through `memo` (journal); `None` when it stopped before the end.
fn constant_side(
    ctx: &Context,
    reference: &Reference,
    j: usize,
    dir: f64,
    se_u: f64,
    th: &Thresholds,
    memo: &PointMemo,
) -> Option<Side> {
    let u_hat = ctx.space.to_unit_one(j, reference.params[j]);
    let bound = if dir < 0.0 { 0.0 } else { 1.0 };
    let mut points = Vec::new();
    let mut u = u_hat;
    let mut r_prev = 0.0;
    let mut warm = reference.params.clone();
    // The point before `warm` and its coordinate (the optimum before the first point).
    let mut prev: Option<(f64, Vec<f64>)> = None;
    let mut h = (ROOT_STEP * se_u).clamp(MIN_STEP, MAX_STEP);
    let seed = 0x5eed ^ ((j as u64) << 8) ^ u64::from(dir > 0.0);
    // Steps taken, kept or not (the journal's key of each step's point).
    let mut n = 0;
    loop {
        if (bound - u) * dir <= 1e-12 {
            return Some(Side {
                points,
                end: SideEnd::Bound,
            });
        }
        if points.len() >= MAX_POINTS {
            return Some(Side {
                points,
                end: SideEnd::PointLimit,
            });
        }
        let mut u_new = u + dir * h;
        if (bound - u_new) * dir < 0.25 * h {
            u_new = bound; // land exactly on the bound
        }
        let point_seed = seed ^ (points.len() as u64) << 16;
        let p = memo.get_or(n, || {
            let mut p = match &prev {
                // Predictor: the others extrapolated along the last step's tangent (a ridge such
                // as B(1−H*) = const at 590 °C is followed, not left and refound).
                Some((u_prev, x_prev)) => {
                    let start = tangent_start(ctx, &warm, x_prev, u - u_prev, u_new - u);
                    fit_point(ctx, reference, j, u_new, &start, th.t68, point_seed)
                }
                None => fit_point(ctx, reference, j, u_new, &warm, th.t68, point_seed),
            };
            if prev.is_some() && (!p.ok() || p.delta.max(0.0).sqrt() - r_prev > 2.0 * ROOT_STEP) {
                // The corrector from the previous point itself, kept if lower.
                let q = fit_point(ctx, reference, j, u_new, &warm, th.t68, point_seed);
                if q.ok() && (!p.ok() || q.delta < p.delta) {
                    p = ProfilePoint {
                        fits: p.fits + q.fits,
                        retried: true,
                        ..q
                    };
                } else {
                    p.fits += q.fits;
                }
            }
            p
        })?;
        n += 1;
        if !p.ok() {
            points.push(p);
            if h <= MIN_STEP {
                return Some(Side {
                    points,
                    end: SideEnd::Failed,
                });
            }
            h = (0.5 * h).max(MIN_STEP);
            continue;
        }
        let r = p.delta.max(0.0).sqrt();
        if r - r_prev > 2.0 * ROOT_STEP && h > MIN_STEP {
            // Too coarse: redo the step shorter (the point is not kept).
            h = (0.5 * h).max(MIN_STEP);
            continue;
        }
        let step = (u_new - u).abs();
        let slope = (r - r_prev) / step.max(1e-12);
        h = if slope > 1e-9 {
            (ROOT_STEP / slope).clamp(0.5 * step, 2.0 * step)
        } else {
            2.0 * step
        }
        .clamp(MIN_STEP, MAX_STEP);
        let crossed = p.delta >= th.t95;
        prev = Some((u, std::mem::replace(&mut warm, p.params.clone())));
        u = u_new;
        r_prev = r;
        points.push(p);
        if crossed {
            return Some(Side {
                points,
                end: SideEnd::Crossed,
            });
        }
    }
}

/// Start of the next profile point by linear extrapolation of the other constants in the unit
/// box: `last` was reached from `before` by a step `ds` of the held coordinate, the next step
/// is `dn`; clamped to the box. Why: continuation from `last` alone leaves the others where
/// they were, and along a narrow ridge (B·(1−H*) fixed at 590 °C) a warm fit started off it
/// by more than a small step converges to a far worse local optimum (Δ ≈ 83 instead of
/// 0.02), so the step never grew and the side ran out of points.
fn tangent_start(ctx: &Context, last: &[f64], before: &[f64], ds: f64, dn: f64) -> Vec<f64> {
    if ds.abs() < 1e-15 {
        return last.to_vec();
    }
    let a = ctx.space.to_unit(last);
    let b = ctx.space.to_unit(before);
    let u: Vec<f64> = a
        .iter()
        .zip(&b)
        .map(|(&ua, &ub)| (ua + (ua - ub) * dn / ds).clamp(0.0, 1.0))
        .collect();
    let mut x = last.to_vec();
    ctx.space.from_unit(&u, &mut x);
    x
}

/// The (coord, Δ) sequence of a side, starting with the optimum.
fn side_curve(u_hat: f64, side: &Side) -> Vec<(f64, f64)> {
    std::iter::once((u_hat, 0.0))
        .chain(
            side.points
                .iter()
                .filter(|p| p.ok())
                .map(|p| (p.coord, p.delta)),
        )
        .collect()
}

/// Wald standard errors of the constants in the unit box at the reference (1e6 where the
/// information matrix could not be computed).
pub fn wald_se(ctx: &Context, reference: &Reference) -> Vec<f64> {
    match information(
        ctx,
        &ctx.space,
        &reference.params,
        &reference.noise,
        reference.specimen.as_ref(),
    ) {
        Some(i) => {
            let c = covariance(&i);
            (0..c.nrows()).map(|k| c[(k, k)].max(0.0).sqrt()).collect()
        }
        None => vec![1e6; ctx.space.len()],
    }
}

/// Profiles of the constants `which` (indices, model order), each against its own
/// thresholds `th[j]` (model order), their sides in parallel. Each
/// side is a step of the phase `profile sides` of `hooks.observer`, journaled in
/// `hooks.journal` as it finishes (keyed by the hash of the reference and the thresholds, the
/// constant and the side), each step's point too (a side killed half-way resumes at its last
/// point), and read back from it; `Err` ([`crate::Error::Interrupted`]) when
/// the observer asks to stop (the finished sides are journaled).
pub fn profile_constants(
    ctx: &Context,
    reference: &Reference,
    which: &[usize],
    th: &[Thresholds],
    hooks: &Hooks,
) -> crate::Result<Vec<ConstantProfile>> {
    let se = wald_se(ctx, reference);
    let tasks: Vec<(usize, f64)> = which.iter().flat_map(|&j| [(j, -1.0), (j, 1.0)]).collect();
    let prefix = format!("side/{}/", debug_hash(&(reference, th, &se)));
    let key =
        |j: usize, dir: f64| format!("{prefix}{j}/{}", if dir < 0.0 { "lower" } else { "upper" });
    hooks.phase("profile sides", tasks.len());
    if let Some(jl) = hooks.journal {
        let found = tasks
            .iter()
            .filter(|(j, d)| jl.contains(&key(*j, *d)))
            .count();
        hooks.observer.resumed(found as u64);
    }
    let write_error: Mutex<Option<crate::Error>> = Mutex::new(None);
    let sides: Vec<Option<Side>> = tasks
        .par_iter()
        .map(|&(j, dir)| {
            let k = key(j, dir);
            if let Some(r) = hooks.journal.and_then(|jl| jl.get::<SideRecord>(&k)) {
                return Some(r.into());
            }
            if hooks.observer.cancelled() || write_error.lock().is_ok_and(|e| e.is_some()) {
                return None;
            }
            let memo = PointMemo {
                hooks,
                key: k.clone(),
                write_error: &write_error,
            };
            let side = constant_side(ctx, reference, j, dir, se[j], &th[j], &memo)?;
            if let Some(jl) = hooks.journal {
                if let Err(e) = jl.put(&k, &SideRecord::from(&side)) {
                    write_error
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .get_or_insert(e);
                }
            }
            hooks.step();
            Some(side)
        })
        .collect();
    if let Some(e) = write_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e);
    }
    if sides.iter().any(Option::is_none) {
        return Err(hooks.interrupted("profile sides"));
    }
    let sides: Vec<Side> = sides.into_iter().flatten().collect();
    let names = ctx.names();
    Ok(which
        .iter()
        .enumerate()
        .map(|(k, &j)| {
            let lower = sides[2 * k].clone();
            let upper = sides[2 * k + 1].clone();
            summarise(ctx, reference, j, names[j], lower, upper, se[j], &th[j])
        })
        .collect())
}

/// A [`Side`] as a journal record: every field, numbers exact ([`crate::journal::exact`]).
#[derive(Serialize, Deserialize)]
struct SideRecord {
    points: Vec<PointRecord>,
    end: SideEnd,
}

/// A [`ProfilePoint`] as a journal record (one step of a side, or part of a [`SideRecord`]).
#[derive(Serialize, Deserialize)]
struct PointRecord {
    #[serde(with = "crate::journal::exact")]
    value: f64,
    #[serde(with = "crate::journal::exact")]
    coord: f64,
    #[serde(with = "crate::journal::exact")]
    delta: f64,
    #[serde(with = "crate::journal::exact::vec")]
    params: Vec<f64>,
    fits: usize,
    retried: bool,
    termination: Termination,
    failure: Option<String>,
}

impl From<&ProfilePoint> for PointRecord {
    fn from(p: &ProfilePoint) -> Self {
        PointRecord {
            value: p.value,
            coord: p.coord,
            delta: p.delta,
            params: p.params.clone(),
            fits: p.fits,
            retried: p.retried,
            termination: p.termination,
            failure: p.failure.clone(),
        }
    }
}

impl From<PointRecord> for ProfilePoint {
    fn from(p: PointRecord) -> Self {
        ProfilePoint {
            value: p.value,
            coord: p.coord,
            delta: p.delta,
            params: p.params,
            fits: p.fits,
            retried: p.retried,
            termination: p.termination,
            failure: p.failure,
        }
    }
}

impl From<&Side> for SideRecord {
    fn from(s: &Side) -> Self {
        SideRecord {
            points: s.points.iter().map(PointRecord::from).collect(),
            end: s.end,
        }
    }
}

impl From<SideRecord> for Side {
    fn from(r: SideRecord) -> Self {
        Side {
            points: r.points.into_iter().map(ProfilePoint::from).collect(),
            end: r.end,
        }
    }
}

/// The same profile read at other thresholds: intervals and class from its points (exact as
/// long as the profile was computed with thresholds at least as high, so that its sides reach
/// the new crossings).
pub fn reinterval(
    ctx: &Context,
    reference: &Reference,
    p: &ConstantProfile,
    th: &Thresholds,
) -> ConstantProfile {
    summarise(
        ctx,
        reference,
        p.index,
        &p.name,
        p.lower.clone(),
        p.upper.clone(),
        p.wald_se_unit,
        th,
    )
}

#[allow(clippy::too_many_arguments)]
fn summarise(
    ctx: &Context,
    reference: &Reference,
    j: usize,
    name: &str,
    lower: Side,
    upper: Side,
    se_u: f64,
    th: &Thresholds,
) -> ConstantProfile {
    let sp = &ctx.space;
    let u_hat = sp.to_unit_one(j, reference.params[j]);
    let (cl, cu) = (side_curve(u_hat, &lower), side_curve(u_hat, &upper));
    let phys = |u: f64| sp.from_unit_one(j, u);
    let limit = |side: &Side, c: &[(f64, f64)], bound: f64| match side.end {
        SideEnd::Bound => bound,
        _ => c.last().map_or(bound, |p| phys(p.0)),
    };
    let lim_lo = limit(&lower, &cl, sp.lb[j]);
    let lim_hi = limit(&upper, &cu, sp.ub[j]);
    let end = |c: &[(f64, f64)], t: f64, lim: f64| crossing(c, t).map(phys).unwrap_or(lim);
    let interval = Interval {
        value: reference.params[j],
        lo68: end(&cl, th.t68, lim_lo),
        hi68: end(&cu, th.t68, lim_hi),
        lo95: end(&cl, th.t95, lim_lo),
        hi95: end(&cu, th.t95, lim_hi),
        lo_open: crossing(&cl, th.t95).is_none(),
        hi_open: crossing(&cu, th.t95).is_none(),
    };
    let max_delta = |c: &[(f64, f64)]| c.iter().map(|p| p.1).fold(0.0, f64::max);
    let mut open = Vec::new();
    if interval.lo_open {
        open.push(OpenSide {
            side: "lower",
            end: lower.end,
            limit: lim_lo,
            max_delta: max_delta(&cl),
        });
    }
    if interval.hi_open {
        open.push(OpenSide {
            side: "upper",
            end: upper.end,
            limit: lim_hi,
            max_delta: max_delta(&cu),
        });
    }
    let flat = lower.end == SideEnd::Bound
        && upper.end == SideEnd::Bound
        && max_delta(&cl).max(max_delta(&cu)) < FLAT_TOL;
    let class = if open.is_empty() {
        Class::Identifiable
    } else if flat {
        Class::StructurallyNonIdentifiable
    } else {
        Class::PracticallyNonIdentifiable
    };
    ConstantProfile {
        name: name.to_string(),
        index: j,
        lb: sp.lb[j],
        ub: sp.ub[j],
        interval,
        thresholds: *th,
        class,
        open,
        wald_se_unit: se_u,
        lower,
        upper,
    }
}

/// The likelihood-ratio interval of a quantity g (a combination or a prediction).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityInterval {
    /// g at the optimum and the interval ends (g's own units: ln for log quantities).
    pub interval: Interval,
    /// Wald standard error of g (Fisher information).
    pub wald_se: f64,
    /// The profile points found on each side, nearest the optimum first.
    pub lower: Side,
    pub upper: Side,
}

impl QuantityInterval {
    /// Fits run.
    pub fn fits(&self) -> usize {
        self.lower.fits() + self.upper.fits()
    }
}

/// Wald standard error of g at the reference: √(∇gᵀ C ∇g) in the unit box (NaN if g or the
/// information cannot be evaluated).
pub fn quantity_se(ctx: &Context, reference: &Reference, q: &Quantity) -> (f64, f64) {
    let u = ctx.space.to_unit(&reference.params);
    let Some((g, grad)) = q.value_and_gradient(ctx, &ctx.space, &u) else {
        return (f64::NAN, f64::NAN);
    };
    let Some(info) = information(
        ctx,
        &ctx.space,
        &reference.params,
        &reference.noise,
        reference.specimen.as_ref(),
    ) else {
        return (g, f64::NAN);
    };
    let c = covariance(&info);
    let gv = nalgebra::DVector::from_column_slice(&grad);
    (g, (gv.transpose() * &c * &gv)[(0, 0)].max(0.0).sqrt())
}

/// The quantity's value ĝ at the reference and the scale τ of the penalty that holds it
/// there for the calibration and the coverage run: [`Quantity::penalty_fraction`] of its Wald
/// standard error, capped by [`Quantity::search_cap`] (the cap alone where the error cannot
/// be evaluated). The interval search ([`quantity_side`]) adapts τ to the profile's width.
pub fn penalty_scale(ctx: &Context, reference: &Reference, q: &Quantity) -> (f64, f64) {
    let (g, se) = quantity_se(ctx, reference, q);
    let cap = q.search_cap(g);
    let se = if se.is_finite() && se > 0.0 {
        se.min(cap)
    } else {
        cap
    };
    (g, q.penalty_fraction() * se)
}

/// Most fits per side of a quantity's interval search.
pub const MAX_SEARCH: usize = 12;

/// Fit at g = `target` from the warm start, retried from the reference and the other optima
/// if it fails; and, when it lands above the 68 % threshold, also from the reference (a
/// penalised fit can stop short of its optimum in a narrow valley: measured, points at
/// |g − ĝ| < 1e-8 with Δ = 93) and, with specimen effects, from the reference cold (new
/// effects, the white stage first: both warm starts carry effects that can hold the fit where
/// it began, as [`fit_point`]'s do). Every successful fit is returned: each is a profile point
/// or an upper bound on one, and [`envelope`] keeps the ones consistent with the others.
fn quantity_points(
    ctx: &Context,
    reference: &Reference,
    q: &Quantity,
    target: f64,
    tau: f64,
    warm: &[f64],
    t68: f64,
) -> Vec<ProfilePoint> {
    let point = |f: PointFit, fits: usize, retried: bool| ProfilePoint {
        value: f.coord,
        coord: f.coord,
        delta: if f.ok() {
            f.neg2ll - reference.neg2ll
        } else {
            f64::NAN
        },
        params: f.params,
        fits,
        retried,
        termination: f.termination,
        failure: f.failure,
    };
    let first = constrained_fit(ctx, q, target, tau, warm, true);
    if first.ok() {
        let d = first.neg2ll - reference.neg2ll;
        let mut out = vec![point(first, 1, false)];
        if d > t68 && warm != reference.params.as_slice() {
            let alt = constrained_fit(ctx, q, target, tau, &reference.params, true);
            if alt.ok() {
                out.push(point(alt, 1, true));
            }
        }
        if d > t68 && ctx.hierarchical() {
            let cold = constrained_fit(ctx, q, target, tau, &reference.params, false);
            if cold.ok() {
                out.push(point(cold, 1, true));
            }
        }
        return out;
    }
    let mut fits = 1;
    let mut others = vec![reference.params.clone()];
    others.extend(reference.basins.iter().cloned());
    for s in others {
        fits += 1;
        let f = constrained_fit(ctx, q, target, tau, &s, false);
        if f.ok() {
            return vec![point(f, fits, true)];
        }
    }
    vec![point(first, fits, true)]
}

/// The points of one side (`dir` = ±1 from ĝ) that can be profile points: outward from ĝ,
/// a point is dropped when a point farther out, or at the same g, has a lower Δ (a profile
/// rises away from its optimum on each side; the dropped fit stopped above its optimum).
/// Returns (coord, Δ), nearest first.
pub fn envelope(points: &[ProfilePoint], g_hat: f64, dir: f64) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.ok() && (p.coord - g_hat) * dir >= 0.0)
        .map(|p| (p.coord, p.delta))
        .collect();
    // Outward, and at one g the highest Δ first: the scan from the outside then meets the
    // lowest first and drops the others (fits that landed at one g from several starts).
    v.sort_by(|a, b| {
        ((a.0 - g_hat) * dir)
            .total_cmp(&((b.0 - g_hat) * dir))
            .then(b.1.total_cmp(&a.1))
    });
    let mut keep = Vec::with_capacity(v.len());
    let mut min_out = f64::INFINITY;
    for &(c, d) in v.iter().rev() {
        if d <= min_out + 1e-6 {
            keep.push((c, d));
            min_out = min_out.min(d);
        }
    }
    keep.reverse();
    keep
}

/// One side of a quantity's interval: secant steps on the signed root √Δ towards the 95 %
/// threshold, from the Wald guess ĝ ± se·√t95 (se capped by [`Quantity::search_cap`]),
/// until |Δ − t95| ≤ 0.05·t95. The penalty scale follows the profile's own width: after each
/// point, s = |g − ĝ|/√Δ and τ = fraction · s (a penalty much wider than the profile would
/// not move g). A side is `unreachable` when a step asked for moves g by less than 1 % of the
/// way and Δ by less than 1 % of the threshold: the box stops the quantity there.
fn quantity_side(
    ctx: &Context,
    reference: &Reference,
    q: &Quantity,
    g_hat: f64,
    se: f64,
    dir: f64,
    th: &Thresholds,
) -> Side {
    let rt = th.t95.sqrt();
    let cap = q.search_cap(g_hat);
    let se = if se.is_finite() && se > 0.0 {
        se.min(cap)
    } else {
        cap
    };
    let mut width = se;
    let mut points: Vec<ProfilePoint> = Vec::new();
    let mut target = g_hat + dir * se * rt;
    for _ in 0..MAX_SEARCH {
        let tau = q.penalty_fraction() * width;
        let before = envelope(&points, g_hat, dir);
        // Warm start: the kept point nearest the target.
        let warm = before
            .iter()
            .min_by(|a, b| (a.0 - target).abs().total_cmp(&(b.0 - target).abs()))
            .and_then(|&(c, _)| points.iter().find(|p| p.ok() && p.coord == c))
            .map_or(reference.params.clone(), |p| p.params.clone());
        let new = quantity_points(ctx, reference, q, target, tau, &warm, th.t68);
        let any_ok = new.iter().any(|p| p.ok());
        points.extend(new);
        if !any_ok {
            target = g_hat + 0.5 * (target - g_hat);
            continue;
        }
        let (far_before, delta_before) = before
            .last()
            .map_or((0.0, 0.0), |&(c, d)| ((c - g_hat) * dir, d));
        let env = envelope(&points, g_hat, dir);
        for &(c, d) in &env {
            if d > 1e-3 && (c - g_hat).abs() > 0.0 {
                width = width.min((c - g_hat).abs() / d.sqrt());
            }
        }
        if env
            .iter()
            .any(|&(_, d)| (d - th.t95).abs() <= 0.05 * th.t95)
        {
            return Side {
                points,
                end: SideEnd::Crossed,
            };
        }
        // Fits that succeeded but all landed on the other side of ĝ (a held quantity the
        // penalty cannot move, e.g. on noise-free data): no step was made; ask for less.
        let Some(&(fc, fd)) = env.last() else {
            target = g_hat + 0.5 * (target - g_hat);
            continue;
        };
        let asked = (target - g_hat) * dir - far_before;
        let got = (fc - g_hat) * dir - far_before;
        if fd < th.t95 && asked > 0.0 && got < 0.01 * asked && fd - delta_before < 0.01 * th.t95 {
            return Side {
                points,
                end: SideEnd::Unreachable,
            };
        }
        // Bracket in the signed root: the farthest kept point below, the nearest above.
        let mut below = (g_hat, 0.0);
        let mut above: Option<(f64, f64)> = None;
        for &(pc, pd) in &env {
            let pr = pd.max(0.0).sqrt();
            if pr < rt {
                below = (pc, pr);
            } else if above.is_none() {
                above = Some((pc, pr));
            }
        }
        if let Some((_, ar)) = above {
            // A bracket narrow enough for the interpolation in √Δ (Δ within 1.5 around the
            // threshold): done.
            if ar * ar - below.1 * below.1 <= 1.5 {
                return Side {
                    points,
                    end: SideEnd::Crossed,
                };
            }
        }
        target = match above {
            Some((ac, ar)) if ar > below.1 => {
                below.0 + (ac - below.0) * (rt - below.1) / (ar - below.1)
            }
            Some((ac, _)) => 0.5 * (below.0 + ac),
            None => {
                let (bc, br) = below;
                let grow = if br > 1e-6 { (rt / br).min(4.0) } else { 4.0 };
                g_hat + (bc - g_hat) * grow.max(1.2)
            }
        };
    }
    let crossed = points.iter().any(|p| p.ok() && p.delta >= th.t95);
    Side {
        points,
        end: if crossed {
            SideEnd::Crossed
        } else {
            SideEnd::PointLimit
        },
    }
}

/// The 68 % and 95 % likelihood-ratio intervals of quantity `q` (both sides in parallel).
/// The 95 % ends are searched; the 68 % ends are interpolated in √Δ among the points found.
pub fn quantity_interval(
    ctx: &Context,
    reference: &Reference,
    q: &Quantity,
    th: &Thresholds,
) -> Option<QuantityInterval> {
    quantity_interval_sides(ctx, reference, q, th, true)
}

/// [`quantity_interval`], the upper side searched only if `upper`: else it has no points
/// (`SideEnd::NotSearched`), and the upper ends are NaN and open.
pub fn quantity_interval_sides(
    ctx: &Context,
    reference: &Reference,
    q: &Quantity,
    th: &Thresholds,
    upper: bool,
) -> Option<QuantityInterval> {
    let (g_hat, se) = quantity_se(ctx, reference, q);
    if !g_hat.is_finite() {
        return None;
    }
    let (lower, upper) = if upper {
        rayon::join(
            || quantity_side(ctx, reference, q, g_hat, se, -1.0, th),
            || quantity_side(ctx, reference, q, g_hat, se, 1.0, th),
        )
    } else {
        (
            quantity_side(ctx, reference, q, g_hat, se, -1.0, th),
            Side {
                points: Vec::new(),
                end: SideEnd::NotSearched,
            },
        )
    };
    let curve = |s: &Side, dir: f64| {
        let mut c = envelope(&s.points, g_hat, dir);
        c.insert(0, (g_hat, 0.0));
        c
    };
    let (cl, cu) = (curve(&lower, -1.0), curve(&upper, 1.0));
    // Where a side stopped within 5 % of the threshold below it, the crossing is extrapolated
    // in √Δ from its outermost point; a side that did not get there is open at the farthest
    // point reached.
    let end = |c: &[(f64, f64)], side: &Side, t: f64| {
        crossing(c, t).or_else(|| {
            let &(pc, pd) = c.last()?;
            (side.end == SideEnd::Crossed && pd > 0.0)
                .then(|| g_hat + (pc - g_hat) * (t / pd).sqrt())
        })
    };
    let far = |c: &[(f64, f64)], side: &Side| {
        if side.end == SideEnd::NotSearched {
            f64::NAN
        } else {
            c.last().map_or(g_hat, |p| p.0)
        }
    };
    let interval = Interval {
        value: g_hat,
        lo68: end(&cl, &lower, th.t68).unwrap_or(far(&cl, &lower)),
        hi68: end(&cu, &upper, th.t68).unwrap_or(far(&cu, &upper)),
        lo95: end(&cl, &lower, th.t95).unwrap_or(far(&cl, &lower)),
        hi95: end(&cu, &upper, th.t95).unwrap_or(far(&cu, &upper)),
        lo_open: end(&cl, &lower, th.t95).is_none(),
        hi_open: end(&cu, &upper, th.t95).is_none(),
    };
    Some(QuantityInterval {
        interval,
        wald_se: se,
        lower,
        upper,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_is_exact_for_a_quadratic_profile() {
        // Δ = ((c − 1)/0.5)², 95 % crossing at 1 + 0.5·1.96.
        let pts: Vec<(f64, f64)> = [1.0, 1.3, 1.6, 1.9, 2.2]
            .iter()
            .map(|&c: &f64| (c, ((c - 1.0) / 0.5).powi(2)))
            .collect();
        let t = 3.841_458_820_694_124;
        let c = crossing(&pts, t).unwrap();
        assert!((c - (1.0 + 0.5 * t.sqrt())).abs() < 1e-12, "{c}");
        // Lower side: coordinates decreasing.
        let pts: Vec<(f64, f64)> = [1.0, 0.7, 0.4, 0.1]
            .iter()
            .map(|&c: &f64| (c, ((c - 1.0) / 0.5).powi(2)))
            .collect();
        let c = crossing(&pts, 1.0).unwrap();
        assert!((c - 0.5).abs() < 1e-12, "{c}");
        // Never crosses.
        assert!(crossing(&pts[..2], t).is_none());
    }

    /// The envelope as a table: (points as (g, Δ), side) → kept points, nearest first.
    #[test]
    fn envelope_keeps_the_lowest_point_outward_as_a_table() {
        let point = |(c, d): (f64, f64)| ProfilePoint {
            value: c,
            coord: c,
            delta: d,
            params: vec![],
            fits: 1,
            retried: false,
            termination: Termination::ConvergedStep,
            failure: None,
        };
        type Row = (&'static [(f64, f64)], f64, &'static [(f64, f64)]);
        let rows: [Row; 6] = [
            // A rising profile: every point kept, nearest first.
            (
                &[(1.3, 2.0), (1.1, 0.5), (1.6, 4.0)],
                1.0,
                &[(1.1, 0.5), (1.3, 2.0), (1.6, 4.0)],
            ),
            // A point above one farther out stopped short of its optimum: dropped.
            (
                &[(1.1, 0.5), (1.3, 5.0), (1.6, 4.0)],
                1.0,
                &[(1.1, 0.5), (1.6, 4.0)],
            ),
            // Points on the other side of ĝ belong to the other side.
            (&[(0.8, 1.0), (1.2, 1.0)], 1.0, &[(1.2, 1.0)]),
            (
                &[(0.8, 1.0), (1.2, 1.0), (0.5, 3.0)],
                -1.0,
                &[(0.8, 1.0), (0.5, 3.0)],
            ),
            // Fits that landed at one g: the lowest kept, whatever their order.
            (&[(1.3, 2.8), (1.3, 2.4), (1.3, 2.8)], 1.0, &[(1.3, 2.4)]),
            // A failed point (NaN) is no point.
            (&[(1.3, f64::NAN), (1.1, 0.5)], 1.0, &[(1.1, 0.5)]),
        ];
        for (pts, dir, want) in rows {
            let p: Vec<ProfilePoint> = pts.iter().copied().map(point).collect();
            assert_eq!(envelope(&p, 1.0, dir), want.to_vec(), "{pts:?} dir {dir}");
        }
    }

    #[test]
    fn classes_have_their_contract_names() {
        assert_eq!(Class::Identifiable.as_str(), "identifiable");
        assert_eq!(
            serde_json::to_value(Class::StructurallyNonIdentifiable).unwrap(),
            "structurally_non_identifiable"
        );
        assert_eq!(
            Class::PracticallyNonIdentifiable.as_str(),
            "practically_non_identifiable"
        );
    }
}
