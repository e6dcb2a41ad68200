//! Constants fitted by maximum likelihood under the error model of [`crate::errmodel`].
//!
//! The residuals come from eq. 8's residual vector at w = 1 on every curve with the lifetime
//! term on both sides ([`crate::model::objective::Objective`]): strain (ε_pred − ε)/ε_f, multiplied
//! back by ε_f, and (t_r − t_f)/t_f, taken as ln(1 + ·) = ln(t_r/t_f). Whitened by the error
//! model (AR(1) innovations per curve, log lifetime residuals over their scatter), their sum
//! of squares is −2 ln L up to terms of the error model alone; the error model itself is
//! profiled out: re-estimated from the residuals at every accepted point of the
//! Levenberg–Marquardt iteration ([`LeastSquaresProblem::reweight`]), so constants and error
//! model converge together and −2 ln L falls at every step.
//!
//! The predictions are the model's at the measured times; after a predicted rupture, eq. 8's
//! C¹ continuation keeps the residual smooth for the optimiser, and the log lifetime term —
//! weighted by the estimated scatter of rupture times, not by a chosen w — is what keeps a fit
//! from rupturing early and following the data with the continuation.
//!
//! **Specimen effects** (a nonlinear mixed-effects model): real specimens are not identical,
//! so each curve i may carry its own creep-rate factor e^{η_i} on the model's rate constant
//! ([`Role::Rate`], KHD: A) and its own ductility factor e^{ζ_i} (the inverse-ductility
//! constant divided by it, [`Role::InverseDuctility`], KHD: C), with η_i ~ N(0, τ_r²) and
//! ζ_i ~ N(0, τ_d²) independent between specimens. The likelihood integrates them out by the
//! **Laplace approximation** at the conditional modes with the Gauss–Newton Hessian
//! (Lindstrom & Bates 1990; nlme's and NONMEM's FOCE-type ML):
//!
//!   −2 ln L ≈ −2 ln p(y | θ, η̂) + Σ_i [η̂_iᵀ D⁻¹ η̂_i + ln det(I + D G_i)],
//!
//! D = diag(τ²), G_i = J_iᵀJ_i the whitened sensitivity of curve i's residuals to its own
//! effects. Laplace rather than adaptive quadrature because every curve carries tens to
//! thousands of points: the conditional posterior of a specimen's effect is then very nearly
//! Gaussian (the approximation is exact for a model linear in η and its error falls like
//! 1/n), it costs no extra simulation (G_i comes from the Jacobian the fit computes anyway:
//! ∂r/∂η_i = x_rate·∂r/∂x_rate on curve i's rows), and it keeps the fit one Levenberg–Marquardt
//! problem in (θ, η) with the penalty residuals η_i/τ — the penalised least squares of
//! Lindstrom & Bates. Tested against a brute-force integral over η. The scatter τ is
//! re-estimated between rounds of that least squares by maximum likelihood on the linear
//! mixed model of the current linearisation (Lindstrom & Bates' LME step), guarded by the
//! Laplace −2 ln L itself: a step whose refit raises it is taken back, and where the linear
//! model would stay while the Laplace terms at the fitted modes fall elsewhere (they lie
//! above the −2 ln L profiled over the effects and touch it at the current τ), the fit goes
//! on with the minimisers of those terms, each a descent
//! ([`crate::specimen::ScatterMethod::LaplaceAtModes`]). The −2 ln L a fit reports is the
//! Laplace value at the τ that minimises it there, while the scatter it reports is the
//! restricted-likelihood (REML) estimate, unbiased for a handful of specimens (the fit's
//! report says why the two differ), from the criterion the fit ended on. τ = 0 (no scatter) is the model without
//! effects, fitted first; the better of the two is kept, so τ̂ = 0 is a possible estimate.

use std::sync::Mutex;

use nalgebra::DMatrix;

use crate::data::Curve;
use crate::errmodel::{ErrorModel, Residuals, RestrictedDesign};
use crate::lsq::{minimize, EvalFailure, LeastSquaresProblem, Termination};
use crate::model::objective::FitSettings;
use crate::model::objective::LifetimeTerm;
use crate::model::objective::{
    CreepProblem, CurveFactors, Evaluation, Objective, ObjectiveSettings, ParamSpace,
};
use crate::model::{Model, Role};
use crate::specimen::{minimise_scatter, Cutoffs, Lmm, ScatterMethod};

/// Options of [`ml_fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MlOptions {
    /// Floor of the rupture-time scatter (ln scale).
    pub lifetime_sd_floor: f64,
    /// Fit with white reading errors first, then with the AR(1) model from there (a fresh
    /// start); `false` polishes with the AR(1) model directly (a start at an optimum already
    /// found, which the white stage could only lead away from).
    pub white_first: bool,
    /// Which specimen effects (random effects) the fit carries.
    pub specimen: SpecimenOptions,
    /// Hold the scatter of each kind (rate, ductility, coarsening; sd of the ln factor) at
    /// these values instead of estimating it: `diagnose` with
    /// [`SpecimenOptions::beyond_trend`] fits every extension at the base's scatter.
    pub hold_scatter: Option<[f64; 3]>,
}

/// The index of `kind` in [`MlOptions::hold_scatter`].
pub fn kind_index(kind: EffectKind) -> usize {
    match kind {
        EffectKind::Rate => 0,
        EffectKind::Ductility => 1,
        EffectKind::Coarsening => 2,
    }
}

/// Whether a fit's specimen scatter is zero for every kind: `scatter` is the REML estimate of
/// each kind the fit kept (`None` when it kept none), zero being [`SCATTER_FLOOR`]. Where the
/// scatter is estimated beyond the stress trend every model is compared at the base's scatter,
/// and at zero that is the plain model: the analyses then go on without specimen factors
/// (a singular fit simplified).
pub fn scatter_at_zero(scatter: Option<&[f64]>) -> bool {
    scatter.is_none_or(|s| s.iter().all(|t| *t <= 1.01 * SCATTER_FLOOR))
}

/// [`MlOptions::hold_scatter`] from a fit's specimen report: each kind's scatter, the floor
/// for kinds it does not carry (dropped at zero scatter).
pub fn held_scatter(sp: Option<&SpecimenFit>) -> [f64; 3] {
    let mut h = [SCATTER_FLOOR; 3];
    if let Some(sp) = sp {
        for (k, t) in sp.kinds.iter().zip(&sp.scatter) {
            h[kind_index(*k)] = t.max(SCATTER_FLOOR);
        }
    }
    h
}

impl Default for MlOptions {
    fn default() -> Self {
        MlOptions {
            lifetime_sd_floor: crate::errmodel::DEFAULT_LIFETIME_SD_FLOOR,
            white_first: true,
            specimen: SpecimenOptions::NONE,
            hold_scatter: None,
        }
    }
}

/// A kind of specimen effect: a specimen's own creep rate, its own ductility, or its own
/// coarsening (tertiary softening) rate.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum EffectKind {
    /// Creep-rate factor e^η on the rate constant.
    Rate,
    /// Ductility factor e^ζ: the inverse-ductility constant divided by it.
    Ductility,
    /// Coarsening-rate factor e^κ on the softening constant (KHD: Kc): when a specimen's
    /// tertiary stage sets in. Measured on Alloy 617 at 900 °C (one fit per curve, seven
    /// specimens): Kc ranges 9e-4 to 4.6e-2 1/h between specimens, while the reading error of
    /// each single-curve fit is 0.07–0.21 % strain against 0.1–1.2 % for a joint fit with rate
    /// and ductility factors only.
    Coarsening,
}

impl EffectKind {
    /// The constant role the effect acts through.
    pub fn role(self) -> Role {
        match self {
            EffectKind::Rate => Role::Rate,
            EffectKind::Ductility => Role::InverseDuctility,
            EffectKind::Coarsening => Role::Softening,
        }
    }
    /// Sign of the effect on its constant's logarithm.
    fn sign(self) -> f64 {
        match self {
            EffectKind::Rate => 1.0,
            EffectKind::Ductility => -1.0,
            EffectKind::Coarsening => 1.0,
        }
    }
    /// Name in reports and configurations.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::Rate => "rate",
            EffectKind::Ductility => "ductility",
            EffectKind::Coarsening => "coarsening",
        }
    }
    /// What varies, in words.
    pub fn describe(self) -> &'static str {
        match self {
            EffectKind::Rate => "creep rate",
            EffectKind::Ductility => "rupture strain (ductility)",
            EffectKind::Coarsening => "coarsening (tertiary softening) rate",
        }
    }
}

/// `[objective] specimen_scatter`: how the scatter between specimens is estimated.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum SpecimenScatter {
    /// Maximum likelihood over all the factors.
    Likelihood,
    /// Restricted likelihood beyond a within-temperature trend with ln σ; every model of a
    /// diagnosis at the base's scatter.
    #[default]
    BeyondStressTrend,
}

impl SpecimenScatter {
    /// Whether this is the likelihood's own estimate (the default before 2026-12-04: what a
    /// run identity without the key means).
    pub fn is_likelihood(&self) -> bool {
        *self == SpecimenScatter::Likelihood
    }
}

/// Which specimen effects a maximum-likelihood fit carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct SpecimenOptions {
    /// A creep-rate factor per specimen.
    pub rate: bool,
    /// A ductility factor per specimen.
    pub ductility: bool,
    /// A coarsening-rate factor per specimen (only when asked for by name: `auto` fits rate
    /// and ductility).
    pub coarsening: bool,
    /// The scatter estimated by restricted likelihood beyond a within-temperature trend of the
    /// factors with ln σ ([`EffectLayout::lmm`]), not by maximum likelihood over all of them
    /// (`[objective] specimen_scatter = "beyond_stress_trend"`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub beyond_trend: bool,
}

impl SpecimenOptions {
    /// No specimen effects: every specimen is the population's.
    pub const NONE: SpecimenOptions = SpecimenOptions {
        rate: false,
        ductility: false,
        coarsening: false,
        beyond_trend: false,
    };
    /// Both kinds.
    pub const BOTH: SpecimenOptions = SpecimenOptions {
        rate: true,
        ductility: true,
        coarsening: false,
        beyond_trend: false,
    };
    /// These kinds with the scatter estimated as `how` says.
    pub fn with_scatter(self, how: SpecimenScatter) -> SpecimenOptions {
        SpecimenOptions {
            beyond_trend: how == SpecimenScatter::BeyondStressTrend,
            ..self
        }
    }
    /// Whether any effect is asked for.
    pub fn any(&self) -> bool {
        self.rate || self.ductility || self.coarsening
    }
    /// The kinds asked for, rate first.
    pub fn kinds(&self) -> Vec<EffectKind> {
        let mut k = vec![];
        if self.rate {
            k.push(EffectKind::Rate);
        }
        if self.ductility {
            k.push(EffectKind::Ductility);
        }
        if self.coarsening {
            k.push(EffectKind::Coarsening);
        }
        k
    }
}

/// Largest |ln factor| of one specimen (a factor of 20 either way): a bound for the optimiser,
/// far beyond any scatter a real data set shows.
pub const EFFECT_MAX: f64 = 3.0;
pub use crate::specimen::{laplace_terms, SCATTER_FLOOR, SCATTER_MAX};

/// Whether a scatter estimate sits at [`SCATTER_MAX`]: the data cannot bound it (measured
/// 2026-11-29: the coarsening kind on Alloy 617 at 950 °C, modes within ±0.3 and the estimate
/// at 3.0); reports say so rather than "varies 9,000 %".
pub fn scatter_at_bound(tau: f64) -> bool {
    tau >= 0.999 * SCATTER_MAX
}

/// The χ² quantile of a 95 % profile interval of one parameter.
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;
/// Least fall of the restricted −2 ln L for which a fit moves its scatter estimate.
pub const SCATTER_TOL: f64 = 1e-3;
/// A scatter estimate that changes by less than this (relative) has settled.
pub const SCATTER_RTOL: f64 = 0.01;

/// Whether every kind's scatter in `a` is within [`SCATTER_RTOL`] (relative, on the log
/// scale) of `b`'s: the scatter has settled.
pub fn scatter_settled(a: &[f64], b: &[f64]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x / y).ln().abs() < SCATTER_RTOL)
}
/// The plateau test of a hierarchical fit's LM ([`crate::lsq::LmOptions::plateau`]): −2 ln L
/// (the residuals' sum of squares plus the error model's log-determinant,
/// [`crate::lsq::LeastSquaresProblem::objective_offset`]) within 0.01 over 6 iterations.
/// The penalised problem has flat valleys (a specimen's effect against the constants it
/// scatters) along which the Gauss–Newton model keeps
/// promising gains that the profiled error model's small moves never let the relative tests
/// confirm: measured on generated specimen data, a third of the bootstrap's refits ran to
/// the iteration limit with −2 ln L constant to 1e-5.
pub const PLATEAU: (usize, f64) = (6, 0.01);
/// Most rounds of the alternation between the effects and the scatter.
pub const SCATTER_ROUNDS: usize = 8;
/// Scatter τ a fit without a better guess starts from (10 %).
pub const SCATTER_START: f64 = 0.1;

/// Where the specimen effects sit: their kinds, constants and rows.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectLayout {
    /// Per kind: the kind, its constant's index in the model and its column among the free
    /// constants.
    pub kinds: Vec<(EffectKind, usize, usize)>,
    /// Curves (one effect of each kind per curve).
    pub n_curves: usize,
    /// Free constants (the first parameters).
    pub n_theta: usize,
    /// Data residuals (before the penalty rows).
    pub m_data: usize,
    /// Per curve, its rows [start, end) among the data residuals (strains and lifetime).
    pub rows: Vec<(usize, usize)>,
    /// Directions of the effects whose scatter is not estimated (empty unless
    /// [`SpecimenOptions::beyond_trend`]): per kind (its index in `kinds`), each temperature
    /// with two stresses or more (the curves' weights of [`stress_trend_weights`]) and, with
    /// two temperatures or more, the contrasts of their levels
    /// ([`temperature_level_weights`]). In the linear mixed model of the scatter each is a
    /// fixed effect ([`EffectLayout::lmm`]).
    pub trend: Vec<(usize, Vec<(usize, f64)>)>,
}

/// Of `cols`, the indices of those that leave the span of `x`'s columns and of the columns
/// kept before them by more than [`SPAN_TOLERANCE`] of their norm (modified Gram–Schmidt,
/// twice). A trend direction the constants already carry (a temperature's level where the
/// rate follows an Arrhenius law) adds nothing to the fixed effects; kept, it would make
/// their information singular, and the ridge that keeps its factorisation defined would
/// give the restricted likelihood a spurious dependence on the scatter.
fn beyond_span(x: nalgebra::DMatrixView<f64>, cols: &[Vec<f64>]) -> Vec<usize> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(u, v)| u * v).sum() };
    let add = |c: &[f64], basis: &mut Vec<Vec<f64>>| -> bool {
        let norm0 = dot(c, c).sqrt();
        if !(norm0 > 0.0) {
            return false;
        }
        let mut v = c.to_vec();
        for _ in 0..2 {
            for q in basis.iter() {
                let d = dot(&v, q);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= d * b);
            }
        }
        let norm = dot(&v, &v).sqrt();
        if norm > SPAN_TOLERANCE * norm0 {
            v.iter_mut().for_each(|a| *a /= norm);
            basis.push(v);
            true
        } else {
            false
        }
    };
    for c in x.column_iter() {
        add(c.as_slice(), &mut basis);
    }
    (0..cols.len())
        .filter(|&j| add(&cols[j], &mut basis))
        .collect()
}

/// Relative norm below which a trend direction counts as inside the constants' span
/// ([`beyond_span`]): its information is then ≤ 1e-8 of its own, far above the 1e-12 ridge of
/// the linear mixed model's factorisation.
const SPAN_TOLERANCE: f64 = 1e-4;

/// With two test temperatures or more, one direction per temperature but the first (in
/// increasing order): the curves' weights 1{T_i = T} − n_T/n, of unit norm. They span how
/// the effects' means differ between temperatures, orthogonal to their common level (which
/// the constants carry) and to every within-temperature stress trend: factors that follow
/// temperature are a temperature dependence the model lacks, not specimen scatter, exactly
/// as factors that follow stress ([`crate::specimen::dof_beyond_trend`] counts them out).
pub fn temperature_level_weights(curves: &[Curve]) -> Vec<Vec<(usize, f64)>> {
    let mut temps: Vec<f64> = curves.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let n = curves.len() as f64;
    temps
        .iter()
        .skip(1)
        .map(|&t| {
            let share = curves.iter().filter(|c| c.temperature_c == t).count() as f64 / n;
            let w: Vec<f64> = curves
                .iter()
                .map(|c| f64::from(u8::from(c.temperature_c == t)) - share)
                .collect();
            let norm = w.iter().map(|v| v * v).sum::<f64>().sqrt();
            w.into_iter()
                .enumerate()
                .map(|(i, v)| (i, v / norm))
                .collect()
        })
        .collect()
}

/// Per temperature whose curves were tested at more than one stress: the curves' weights
/// (x_i − x̄)/‖x − x̄‖ with x = ln σ, so that Σ w_i η_i is the effects' within-temperature
/// regression slope on ln σ times ‖x − x̄‖, zero for effects that do not follow stress.
pub fn stress_trend_weights(curves: &[Curve]) -> Vec<Vec<(usize, f64)>> {
    let mut temps: Vec<f64> = curves.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let mut out = Vec::new();
    for t in temps {
        let at: Vec<usize> = (0..curves.len())
            .filter(|&i| curves[i].temperature_c == t)
            .collect();
        let x: Vec<f64> = at.iter().map(|&i| curves[i].stress_mpa.ln()).collect();
        let xm = x.iter().sum::<f64>() / x.len() as f64;
        let norm = x.iter().map(|v| (v - xm) * (v - xm)).sum::<f64>().sqrt();
        if !(norm > 1e-9) {
            continue;
        }
        out.push(
            at.iter()
                .zip(&x)
                .map(|(&i, v)| (i, (v - xm) / norm))
                .collect(),
        );
    }
    out
}

impl EffectLayout {
    /// This layout with [`EffectLayout::trend`] set for every kind on `curves`: the
    /// within-temperature stress trends and the temperatures' level contrasts.
    pub fn with_trend(mut self, curves: &[Curve]) -> EffectLayout {
        let mut groups = stress_trend_weights(curves);
        groups.extend(temperature_level_weights(curves));
        self.trend = (0..self.kinds.len())
            .flat_map(|k| groups.iter().map(move |w| (k, w.clone())))
            .collect();
        self
    }

    /// The layout of the kinds `keep` (indices into `kinds`), with their trend directions.
    pub fn keeping(&self, keep: &[usize]) -> EffectLayout {
        EffectLayout {
            kinds: keep.iter().map(|&k| self.kinds[k]).collect(),
            trend: self
                .trend
                .iter()
                .filter_map(|(k, w)| keep.iter().position(|g| g == k).map(|p| (p, w.clone())))
                .collect(),
            ..self.clone()
        }
    }

    /// The linear mixed model of the whitened residuals `r` and Jacobian `jac` at effects
    /// `eta` ([`Lmm::from_jacobian`]); each direction of [`EffectLayout::trend`] (Σ_i w_i·Z_i,
    /// Z_i the effect's column of curve i) is a fixed-effect column besides the constants, so
    /// that the scatter is estimated from how the effects differ beyond those trends.
    pub fn lmm(&self, jac: &DMatrix<f64>, r: &[f64], eta: &[f64]) -> Lmm {
        let (nt, n, kk) = (self.n_theta, self.n_curves, self.kinds.len());
        if self.trend.is_empty() {
            return Lmm::from_jacobian(jac, r, &self.rows, nt, kk, eta);
        }
        let ne = self.n_effects();
        let m = jac.nrows();
        let cols: Vec<Vec<f64>> = self
            .trend
            .iter()
            .map(|(k, w)| {
                let mut c = vec![0.0; m];
                for (i, wi) in w {
                    let (a, b) = self.rows[*i];
                    for (row, v) in c.iter_mut().enumerate().take(b).skip(a) {
                        *v += wi * jac[(row, nt + k * n + i)];
                    }
                }
                c
            })
            .collect();
        let keep = beyond_span(jac.columns(0, nt), &cols);
        let g = keep.len();
        let mut aug = DMatrix::<f64>::zeros(m, nt + g + ne);
        aug.columns_mut(0, nt).copy_from(&jac.columns(0, nt));
        aug.columns_mut(nt + g, ne).copy_from(&jac.columns(nt, ne));
        for (j, &c) in keep.iter().enumerate() {
            aug.column_mut(nt + j).copy_from_slice(&cols[c]);
        }
        Lmm::from_jacobian(&aug, r, &self.rows, nt + g, kk, eta)
    }

    /// The layout of `kinds` for `model` on `curves` in `space`; kinds whose constant the
    /// model lacks or `space` holds fixed are left out (listed in the second value).
    pub fn new(
        model: &dyn Model,
        curves: &[Curve],
        space: &ParamSpace,
        kinds: &[EffectKind],
    ) -> (Option<EffectLayout>, Vec<EffectKind>) {
        let mut out = vec![];
        let mut dropped = vec![];
        for &k in kinds {
            let j = model.constants().iter().position(|c| c.role == k.role());
            match j {
                Some(j) if space.free[j] => {
                    let col = space.free[..j].iter().filter(|f| **f).count();
                    out.push((k, j, col));
                }
                _ => dropped.push(k),
            }
        }
        if out.is_empty() || curves.is_empty() {
            return (None, kinds.to_vec());
        }
        let mut rows = Vec::with_capacity(curves.len());
        let mut off = 0;
        for c in curves {
            let n = c.times_h.len() + 1;
            rows.push((off, off + n));
            off += n;
        }
        (
            Some(EffectLayout {
                kinds: out,
                trend: Vec::new(),
                n_curves: curves.len(),
                n_theta: space.n_free(),
                m_data: off,
                rows,
            }),
            dropped,
        )
    }

    /// Number of effect parameters.
    pub fn n_effects(&self) -> usize {
        self.kinds.len() * self.n_curves
    }

    /// The per-curve factors of effects `eta` (kind-major: kind k, curve i at k·n + i).
    pub fn factors(&self, eta: &[f64]) -> CurveFactors {
        let n = self.n_curves;
        CurveFactors {
            index: self.kinds.iter().map(|k| k.1).collect(),
            factors: (0..n)
                .map(|i| {
                    self.kinds
                        .iter()
                        .enumerate()
                        .map(|(k, (kind, _, _))| (kind.sign() * eta[k * n + i]).exp())
                        .collect()
                })
                .collect(),
        }
    }

    /// G_i = J_iᵀJ_i (k × k, row-major) of every curve from the whitened effect columns of
    /// `jac` (the full problem's Jacobian).
    pub fn gram(&self, jac: &DMatrix<f64>) -> Vec<crate::specimen::KMat> {
        let n = self.n_curves;
        (0..n)
            .map(|i| {
                let (a, b) = self.rows[i];
                let mut g = [[0.0; crate::specimen::MAX_KINDS]; crate::specimen::MAX_KINDS];
                for k in 0..self.kinds.len() {
                    for l in 0..=k {
                        let ck = jac.column(self.n_theta + k * n + i);
                        let cl = jac.column(self.n_theta + l * n + i);
                        let v: f64 = (a..b).map(|r| ck[r] * cl[r]).sum();
                        g[k][l] = v;
                        g[l][k] = v;
                    }
                }
                g
            })
            .collect()
    }
}

/// Eq. 8 at w = 1 on every curve, lifetime term on both sides: the residual vector the
/// likelihood transforms.
pub fn raw_objective<'a>(
    model: &'a dyn Model,
    curves: &'a [Curve],
    settings: &FitSettings,
) -> Objective<'a> {
    Objective::new(
        model,
        curves,
        vec![1.0; curves.len()],
        ObjectiveSettings {
            lifetime: LifetimeTerm::Both,
            ..settings.objective()
        },
    )
}

/// Raw residuals from an eq. 8 residual vector of [`raw_objective`] (layout: per curve its
/// strain residuals, then its lifetime residual): strain as a fraction, a group mean's in a
/// reading's units ([`Curve::to_reading_units`]), and ln of the life ratio.
pub fn split_residuals(curves: &[Curve], r: &[f64]) -> Residuals {
    let mut off = 0;
    let mut strain = Vec::with_capacity(curves.len());
    let mut lifetime = Vec::with_capacity(curves.len());
    for c in curves {
        let n = c.times_h.len();
        let mut e: Vec<f64> = r[off..off + n]
            .iter()
            .map(|v| v * c.rupture_strain)
            .collect();
        c.to_reading_units(&mut e);
        strain.push(e);
        lifetime.push(c.rupture_time_h.map(|_| r[off + n].ln_1p()));
        off += n + 1;
    }
    Residuals { strain, lifetime }
}

/// Raw residuals of `model` at `params`.
pub fn residuals_at(
    model: &dyn Model,
    curves: &[Curve],
    params: &[f64],
    settings: &FitSettings,
) -> Result<Residuals, EvalFailure> {
    let obj = raw_objective(model, curves, settings);
    let mut r = vec![0.0; obj.n_residuals()];
    obj.residuals(params, &mut r)?;
    Ok(split_residuals(curves, &r))
}

/// −2 ln L as a least-squares problem in the unit box, with the error model profiled out
/// (re-estimated at every accepted point). With specimen effects ([`EffectLayout`]) the
/// parameters are the free constants in the unit box followed by the effects (ln factors,
/// kind-major), and the residuals the data's followed by one penalty residual η/τ per effect.
pub struct LikelihoodProblem<'a> {
    /// Eq. 8 (w = 1, both sides) in the unit box.
    pub inner: CreepProblem<'a>,
    /// The current error model.
    noise: Mutex<ErrorModel>,
    /// Floor of the rupture-time scatter.
    lifetime_sd_floor: f64,
    /// Keep the error model fixed (no profiling): −2 ln L at a known error model.
    fixed: bool,
    /// Profile the error model with every reading error white (φ = 0).
    white: bool,
    /// Specimen effects, if the problem carries them.
    effects: Option<EffectLayout>,
    /// Their scatter τ per kind (sd of the ln factor), profiled unless `hold_scatter`.
    scatter: Mutex<Vec<f64>>,
    /// Keep the scatter where it is (the effects are then penalised least squares at it).
    hold_scatter: bool,
    /// Per curve and reading, a known factor w ≥ 1 on the reading error (a reading error
    /// that grows with strain, [`crate::errmodel::GrowingError`]): the AR(1) is that of the
    /// residual over w. `None`: w = 1.
    reading_scale: Option<Vec<Vec<f64>>>,
}

impl<'a> LikelihoodProblem<'a> {
    /// The problem for `inner` starting from error model `noise`.
    pub fn new(inner: CreepProblem<'a>, noise: ErrorModel, lifetime_sd_floor: f64) -> Self {
        LikelihoodProblem {
            inner,
            noise: Mutex::new(noise),
            lifetime_sd_floor,
            fixed: false,
            white: false,
            effects: None,
            scatter: Mutex::new(vec![]),
            hold_scatter: false,
            reading_scale: None,
        }
    }

    /// The problem for `inner` starting from the white error model `noise`, profiled with
    /// φ = 0 on every curve.
    pub fn white(inner: CreepProblem<'a>, noise: ErrorModel, lifetime_sd_floor: f64) -> Self {
        LikelihoodProblem {
            white: true,
            ..LikelihoodProblem::new(inner, noise, lifetime_sd_floor)
        }
    }

    /// The problem at a known, fixed error model `noise`.
    pub fn fixed(inner: CreepProblem<'a>, noise: ErrorModel) -> Self {
        LikelihoodProblem {
            fixed: true,
            ..LikelihoodProblem::new(inner, noise, 0.0)
        }
    }

    /// The same problem with each reading's error multiplied by a known factor (`scale`: per
    /// curve, one w > 0 per reading): residuals and Jacobian rows are divided by w before the
    /// AR(1) whitens them. −2 ln L then leaves out 2 Σ ln w, a constant of the data set,
    /// so differences between models on the same data are exact. `None`: w = 1.
    pub fn with_reading_scale(mut self, scale: Option<Vec<Vec<f64>>>) -> Self {
        if let Some(w) = &scale {
            let curves = self.curves();
            assert_eq!(w.len(), curves.len(), "one scale per curve");
            for (w, c) in w.iter().zip(curves) {
                assert_eq!(w.len(), c.times_h.len(), "one scale per reading");
            }
        }
        self.reading_scale = scale;
        self
    }

    /// The same problem with specimen effects laid out as `layout`, their scatter starting at
    /// `scatter` (one per kind) and profiled unless `hold` (then held there).
    pub fn with_effects(mut self, layout: EffectLayout, scatter: Vec<f64>, hold: bool) -> Self {
        assert_eq!(scatter.len(), layout.kinds.len(), "one scatter per kind");
        self.effects = Some(layout);
        self.scatter = Mutex::new(scatter);
        self.hold_scatter = hold;
        self
    }

    /// The current error model.
    pub fn noise(&self) -> ErrorModel {
        self.noise.lock().expect("noise lock").clone()
    }

    /// The current scatter per kind of effect (empty without effects).
    pub fn scatter(&self) -> Vec<f64> {
        self.scatter.lock().expect("scatter lock").clone()
    }

    /// The specimen effects' layout, if any.
    pub fn effects(&self) -> Option<&EffectLayout> {
        self.effects.as_ref()
    }

    fn curves(&self) -> &[Curve] {
        self.inner.objective.curves()
    }

    /// The eq. 8 problem with the curves' constants multiplied by the factors of `eta`.
    fn at_effects(&self, layout: &EffectLayout, eta: &[f64]) -> CreepProblem<'a> {
        CreepProblem {
            objective: self
                .inner
                .objective
                .clone()
                .with_factors(Some(layout.factors(eta))),
            space: self.inner.space.clone(),
            jacobian: self.inner.jacobian,
        }
    }

    /// Whiten eq. 8 residuals `r` (and the Jacobian rows of `jac`, if given) in place.
    fn transform(&self, r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) {
        let noise = self.noise();
        let s = noise.lifetime_sd;
        let mut off = 0;
        for (i, c) in self.curves().iter().enumerate() {
            let n = c.times_h.len();
            let ef = c.rupture_strain;
            let p = &noise.strain[i];
            let w = self.reading_scale.as_ref().map(|w| &w[i]);
            let scale = |v: &mut [f64]| {
                for v in v.iter_mut() {
                    *v *= ef;
                }
                c.to_reading_units(v);
                if let Some(w) = w {
                    for (v, w) in v.iter_mut().zip(w) {
                        *v /= w;
                    }
                }
            };
            scale(&mut r[off..off + n]);
            p.whiten(&mut r[off..off + n]);
            if let Some(j) = jac.as_deref_mut() {
                let nrows = j.nrows();
                for k in 0..j.ncols() {
                    let col = &mut j.as_mut_slice()[k * nrows + off..k * nrows + off + n];
                    scale(col);
                    p.whiten(col);
                }
            }
            let rel = r[off + n];
            let d = if c.rupture_time_h.is_some() {
                r[off + n] = rel.ln_1p() / s;
                1.0 / ((1.0 + rel) * s)
            } else {
                r[off + n] = 0.0;
                0.0
            };
            if let Some(j) = jac.as_deref_mut() {
                for k in 0..j.ncols() {
                    j[(off + n, k)] *= d;
                }
            }
            off += n + 1;
        }
    }

    /// The penalty residuals η/τ of the effects `eta` at scatter `tau`.
    fn penalties(layout: &EffectLayout, eta: &[f64], tau: &[f64], out: &mut [f64]) {
        let n = layout.n_curves;
        for k in 0..layout.kinds.len() {
            for i in 0..n {
                out[k * n + i] = eta[k * n + i] / tau[k];
            }
        }
    }

    /// The full Jacobian from the whitened data Jacobian `jt` of the free constants at
    /// parameters `x`: the effect columns are ±x_c·∂r/∂x_c of their constant c on their curve's
    /// rows, the penalty rows 1/τ on their effect.
    fn assemble(
        &self,
        layout: &EffectLayout,
        jt: &DMatrix<f64>,
        x: &[f64],
        jac: &mut DMatrix<f64>,
    ) {
        let nt = layout.n_theta;
        let n = layout.n_curves;
        let md = layout.m_data;
        jac.fill(0.0);
        jac.view_mut((0, 0), (md, nt)).copy_from(jt);
        let space = &self.inner.space;
        let mut phys = vec![0.0; space.len()];
        space.from_unit(&x[..nt], &mut phys);
        let tau = self.scatter();
        for (k, &(kind, j, col)) in layout.kinds.iter().enumerate() {
            let d = kind.sign() * phys[j] / space.dx_du(j, phys[j]);
            for i in 0..n {
                let (a, b) = layout.rows[i];
                let c = nt + k * n + i;
                for row in a..b {
                    jac[(row, c)] = jt[(row, col)] * d;
                }
                jac[(md + k * n + i, c)] = 1.0 / tau[k];
            }
        }
    }

    /// Re-estimate the reading error and rupture-time scatter from the residuals `r` (whitened
    /// under the current model) and rewrite `r` and `jac`'s data rows; whether it changed.
    fn reweight_noise(&self, r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> bool {
        let mut guard = self.noise.lock().expect("noise lock");
        let old = guard.clone();
        // Back to raw residuals (strain fraction, ln lifetime) under the old model.
        let curves = self.curves();
        let mut res = Residuals {
            strain: Vec::with_capacity(curves.len()),
            lifetime: Vec::with_capacity(curves.len()),
        };
        let mut off = 0;
        for (i, c) in curves.iter().enumerate() {
            let n = c.times_h.len();
            let mut e = r[off..off + n].to_vec();
            old.strain[i].unwhiten_strided(&mut e, n, 1);
            res.strain.push(e);
            res.lifetime
                .push(c.rupture_time_h.map(|_| r[off + n] * old.lifetime_sd));
            off += n + 1;
        }
        let new = if self.white {
            ErrorModel::estimate_white(&res, self.lifetime_sd_floor)
        } else {
            ErrorModel::estimate(&res, self.lifetime_sd_floor)
        };
        if new == old {
            return false;
        }
        let mut off = 0;
        for (i, c) in curves.iter().enumerate() {
            let n = c.times_h.len();
            let (po, pn) = (&old.strain[i], &new.strain[i]);
            r[off..off + n].copy_from_slice(&res.strain[i]);
            pn.whiten(&mut r[off..off + n]);
            if let Some(j) = jac.as_deref_mut() {
                let nrows = j.nrows();
                for k in 0..j.ncols() {
                    let col = &mut j.as_mut_slice()[k * nrows + off..k * nrows + off + n];
                    // Both maps are linear and keep +0 exactly: an effect column of
                    // another curve (zero on these rows) is left as it is.
                    if col.iter().all(|&v| v == 0.0) {
                        continue;
                    }
                    po.unwhiten_strided(col, n, 1);
                    pn.whiten(col);
                }
            }
            let ratio = old.lifetime_sd / new.lifetime_sd;
            r[off + n] *= ratio;
            if let Some(j) = jac.as_deref_mut() {
                for k in 0..j.ncols() {
                    j[(off + n, k)] *= ratio;
                }
            }
            off += n + 1;
        }
        *guard = new;
        true
    }

    /// Set the scatter to its restricted-likelihood estimate on the linear mixed model of
    /// the current linearisation ([`crate::specimen`]: the LME step of Lindstrom & Bates),
    /// rewriting the penalty rows; whether it changed.
    fn reweight_scatter(&self, x: &[f64], r: &mut [f64], jac: &mut DMatrix<f64>) -> bool {
        let Some(layout) = &self.effects else {
            return false;
        };
        let (nt, n, md) = (layout.n_theta, layout.n_curves, layout.m_data);
        let eta = &x[nt..];
        let lmm = layout.lmm(jac, r, eta);
        let mut guard = self.scatter.lock().expect("scatter lock");
        let new = lmm.estimate(&guard, true);
        // A change the criterion does not see (its search's own resolution) would only keep
        // the iteration from converging: the scatter moves when −2ℓ_R falls by more than
        // [`SCATTER_TOL`].
        if !(lmm.neg2l(&new, true) < lmm.neg2l(&guard, true) - SCATTER_TOL) {
            return false;
        }
        Self::penalties(layout, eta, &new, &mut r[md..]);
        for k in 0..layout.kinds.len() {
            for i in 0..n {
                jac[(md + k * n + i, nt + k * n + i)] = 1.0 / new[k];
            }
        }
        *guard = new;
        true
    }
}

impl LeastSquaresProblem for LikelihoodProblem<'_> {
    fn n_params(&self) -> usize {
        self.inner.n_params() + self.effects.as_ref().map_or(0, |l| l.n_effects())
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals() + self.effects.as_ref().map_or(0, |l| l.n_effects())
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let Some(layout) = &self.effects else {
            self.inner.residuals(u, r)?;
            self.transform(r, None);
            return Ok(());
        };
        let (nt, md) = (layout.n_theta, layout.m_data);
        let eta = &u[nt..];
        self.at_effects(layout, eta)
            .residuals(&u[..nt], &mut r[..md])?;
        self.transform(&mut r[..md], None);
        Self::penalties(layout, eta, &self.scatter(), &mut r[md..]);
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let Some(layout) = &self.effects else {
            return match self.inner.residuals_and_jacobian(u, r, jac)? {
                Ok(()) => {
                    self.transform(r, Some(jac));
                    Some(Ok(()))
                }
                Err(e) => Some(Err(e)),
            };
        };
        let (nt, md) = (layout.n_theta, layout.m_data);
        let eta = &u[nt..];
        let mut jt = DMatrix::<f64>::zeros(md, nt);
        match self.at_effects(layout, eta).residuals_and_jacobian(
            &u[..nt],
            &mut r[..md],
            &mut jt,
        )? {
            Ok(()) => {
                self.transform(&mut r[..md], Some(&mut jt));
                self.assemble(layout, &jt, u, jac);
                Self::penalties(layout, eta, &self.scatter(), &mut r[md..]);
                Some(Ok(()))
            }
            Err(e) => Some(Err(e)),
        }
    }
    fn objective_offset(&self) -> f64 {
        let curves = self.curves();
        let lives = curves.iter().filter(|c| c.rupture_time_h.is_some()).count();
        self.noise
            .lock()
            .expect("noise lock")
            .normalising(curves.iter().map(|c| c.times_h.len()), lives)
    }
    fn damping_scale(&self, jtj: &DMatrix<f64>) -> Option<Vec<f64>> {
        // With specimen effects: the constants damped by the diagonal of the Schur
        // complement of the effects' block (the constants' curvature once every effect has
        // followed them), the effects by their own diagonal. A constant that the effects
        // can compensate (the rate constant against every specimen's rate factor) then moves
        // freely along that valley instead of crawling.
        let layout = self.effects.as_ref()?;
        let (nt, n, k) = (layout.n_theta, layout.n_curves, layout.kinds.len());
        let mut out: Vec<f64> = (0..jtj.nrows()).map(|j| jtj[(j, j)]).collect();
        for i in 0..n {
            let idx: Vec<usize> = (0..k).map(|kk| nt + kk * n + i).collect();
            let h = DMatrix::from_fn(k, k, |a, b| jtj[(idx[a], idx[b])]);
            let Some(hi) = h.try_inverse() else {
                continue;
            };
            for (a, out_a) in out.iter_mut().enumerate().take(nt) {
                let mut v = 0.0;
                for p in 0..k {
                    for q in 0..k {
                        v += jtj[(a, idx[p])] * hi[(p, q)] * jtj[(idx[q], a)];
                    }
                }
                *out_a -= v;
            }
        }
        for v in out.iter_mut().take(nt) {
            *v = v.max(0.0);
        }
        Some(out)
    }
    fn reweight(&self, x: &[f64], r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> bool {
        if self.fixed {
            return false;
        }
        let a = self.reweight_noise(r, jac.as_deref_mut());
        let b = match jac {
            Some(j) if self.effects.is_some() && !self.hold_scatter => {
                self.reweight_scatter(x, r, j)
            }
            _ => false,
        };
        a || b
    }
}

/// The specimen effects of a maximum-likelihood fit.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SpecimenFit {
    /// The kinds fitted (rate first).
    pub kinds: Vec<EffectKind>,
    /// Scatter per kind: sd of the ln factor between specimens (0.23 ≈ "varies 23 %"), the
    /// restricted-likelihood estimate ([`crate::specimen`]).
    pub scatter: Vec<f64>,
    /// Per kind: lower end of the scatter's 95 % profile interval (0 when zero scatter is
    /// inside it).
    pub scatter_lo95: Vec<f64>,
    /// Per kind: upper end of the 95 % interval.
    pub scatter_hi95: Vec<f64>,
    /// Per kind: the degrees of freedom the interval was calibrated to
    /// ([`crate::specimen::Lmm::effect_dof`]): about the specimens less the directions the
    /// constants take up, less where the data see the factors poorly; below 2 the data
    /// hardly separate the scatter from the constants (NaN before [`scatter_intervals`]).
    pub scatter_dof: Vec<f64>,
    /// Per kind, per curve: the specimen's ln factor (conditional mode; rate: its creep rate
    /// is e^η times the population's; ductility: its rupture strain e^ζ times).
    pub effects: Vec<Vec<f64>>,
    /// Per kind, per curve: the sd of that ln factor given the data (Laplace).
    pub effects_sd: Vec<Vec<f64>>,
    /// The random-effects terms of −2 ln L (penalties and log-determinants).
    pub neg2ll_effects: f64,
    /// Which criterion the scatter was estimated by (the linear mixed model's, or the Laplace
    /// criterion at the modes where that model's step did not pay or it stopped short).
    pub scatter_method: crate::specimen::ScatterMethod,
    /// Kinds asked for but not fitted (their constant held fixed or absent), or dropped
    /// because their scatter went to zero.
    pub dropped: Vec<EffectKind>,
}

/// The specimens' mean ln factor in one group of curves (a temperature, a campaign).
/// Under the hierarchical model the factors scatter about 0 in every group; a group mean
/// several standard errors from 0 is a dependence on what defines the group that the
/// constants miss and the factors take up.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FactorGroup {
    /// The group's name ("850 °C", "KAERI2").
    pub group: String,
    /// Specimens (curves) in it.
    pub specimens: usize,
    /// Per kind, in the fit's order: the mean of the specimens' ln factors (conditional modes).
    pub mean_ln: Vec<f64>,
    /// Per kind: its standard error, the specimens' sample sd / √n (NaN for one specimen).
    pub se: Vec<f64>,
}

impl SpecimenFit {
    /// Each curve's factors on `model`'s constants (`None` without curves): what simulates a
    /// curve at its own specimen's constants rather than the population's.
    pub fn curve_factors(&self, model: &dyn Model) -> Option<CurveFactors> {
        let n = self.effects.first()?.len();
        let index: Vec<usize> = self
            .kinds
            .iter()
            .map(|k| {
                model
                    .constants()
                    .iter()
                    .position(|c| c.role == k.role())
                    .expect("fitted kinds have their constant")
            })
            .collect();
        Some(CurveFactors {
            index,
            factors: (0..n)
                .map(|i| {
                    self.kinds
                        .iter()
                        .zip(&self.effects)
                        .map(|(k, e)| (k.sign() * e[i]).exp())
                        .collect()
                })
                .collect(),
        })
    }

    /// The specimens' mean ln factors per group of `curves` (the curves the fit was made on,
    /// in its order), `key` naming a curve's group (`None`: in no group); groups in order of
    /// first appearance.
    pub fn by_group(
        &self,
        curves: &[Curve],
        key: impl Fn(&Curve) -> Option<String>,
    ) -> Vec<FactorGroup> {
        let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
        for (i, c) in curves.iter().enumerate() {
            let Some(k) = key(c) else { continue };
            match groups.iter_mut().find(|g| g.0 == k) {
                Some(g) => g.1.push(i),
                None => groups.push((k, vec![i])),
            }
        }
        groups
            .into_iter()
            .map(|(group, idx)| {
                let n = idx.len() as f64;
                let (mean_ln, se) = self
                    .effects
                    .iter()
                    .map(|eta| {
                        let m = idx.iter().map(|&i| eta[i]).sum::<f64>() / n;
                        let var =
                            idx.iter().map(|&i| (eta[i] - m).powi(2)).sum::<f64>() / (n - 1.0);
                        (
                            m,
                            if idx.len() > 1 {
                                (var / n).sqrt()
                            } else {
                                f64::NAN
                            },
                        )
                    })
                    .unzip();
                FactorGroup {
                    group,
                    specimens: idx.len(),
                    mean_ln,
                    se,
                }
            })
            .collect()
    }
}

/// How one kind of specimen factor follows stress within temperatures: the pooled
/// least-squares slope of the ln factors (conditional modes) on ln σ with an intercept per
/// temperature, and its two-sided t-test. The hierarchical model draws every specimen's factor
/// from one distribution whatever its stress; a slope far from 0 is a stress dependence the
/// constants miss and the factors take up (for the ductility: what `stress_ductility`'s ν
/// would carry, with the opposite sign), which the goodness-of-fit tests cannot see because
/// the factors have absorbed it. Pharmacometrics' check of random effects against covariates.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StressTrend {
    /// The kind of factor.
    pub kind: EffectKind,
    /// d(ln factor)/d(ln σ) within a temperature (dimensionless; NaN without two stresses at
    /// one temperature). Named as in `fit`'s `summary.json`.
    #[serde(rename = "slope_per_ln_stress")]
    pub slope: f64,
    /// Its standard error (NaN without a residual degree of freedom).
    pub se: f64,
    /// Residual degrees of freedom: specimens − temperatures − 1.
    pub df: usize,
    /// Two-sided p-value of slope = 0 (Student t with `df`; NaN where `se` is).
    pub p_value: f64,
    /// Specimens (curves) and temperatures it was computed from.
    pub specimens: usize,
    pub temperatures: usize,
}

/// The level of [`StressTrend::follows_stress`]. At 0.05 the ductility's trend was called on
/// 19 of 261 generated null sets (7.3 %; 20 % of those without a true ductility scatter, whose
/// factors then take up misfit); at 0.01 on 7 of 261, the rate's on 2 of 335 (seeds
/// 562001–562400; validated on fresh seeds in docs/DIAGNOSE.md).
pub const STRESS_TREND_ALPHA: f64 = 0.01;

impl StressTrend {
    /// Whether the factors follow stress: p below [`STRESS_TREND_ALPHA`] (false where the
    /// trend could not be computed).
    pub fn follows_stress(&self) -> bool {
        self.p_value < STRESS_TREND_ALPHA
    }
}

/// The pooled within-group slope of `y` on `x` (groups by `group`), its standard error and
/// residual degrees of freedom (n − groups − 1), as in [`StressTrend`].
pub fn within_group_slope(x: &[f64], y: &[f64], group: &[usize]) -> (f64, f64, usize) {
    let mut ids: Vec<usize> = group.to_vec();
    ids.sort_unstable();
    ids.dedup();
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for g in &ids {
        let idx: Vec<usize> = (0..x.len()).filter(|&i| group[i] == *g).collect();
        let n = idx.len() as f64;
        let mx = idx.iter().map(|&i| x[i]).sum::<f64>() / n;
        let my = idx.iter().map(|&i| y[i]).sum::<f64>() / n;
        for &i in &idx {
            sxx += (x[i] - mx).powi(2);
            sxy += (x[i] - mx) * (y[i] - my);
            syy += (y[i] - my).powi(2);
        }
    }
    let df = x.len().saturating_sub(ids.len() + 1);
    // Stresses equal to rounding within every group: no slope.
    if sxx <= 1e-12 * x.len() as f64 {
        return (f64::NAN, f64::NAN, df);
    }
    let b = sxy / sxx;
    let se = if df > 0 {
        ((syy - b * sxy).max(0.0) / df as f64 / sxx).sqrt()
    } else {
        f64::NAN
    };
    (b, se, df)
}

/// How one kind of specimen factor differs between groups of specimens: test temperatures
/// ([`TemperatureLevels`], `G` the temperature in °C) or test campaigns ([`CampaignLevels`], `G`
/// the campaign's name). The ln factors' (conditional modes') mean per group, and an F-test of
/// equal group levels in a covariance analysis beside a slope on ln σ (and, for campaigns, a
/// level per temperature). Called at p < [`STRESS_TREND_ALPHA`], like the stress trend.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GroupLevels<G> {
    /// The kind of factor.
    pub kind: EffectKind,
    /// Per group (temperatures increasing, campaigns in name order): the mean of its
    /// specimens' ln factors.
    pub mean_ln: Vec<(G, f64)>,
    /// The F statistic of equal levels (NaN where the test cannot be made: the groups
    /// confounded with the other columns, too few specimens, or the kind's scatter at its
    /// floor, where the factors are zero).
    pub f: f64,
    /// Its degrees of freedom: the group levels the other columns leave free, and the
    /// specimens less the rank of all columns.
    pub df: (usize, usize),
    /// Its p-value (NaN where `f` is).
    pub p_value: f64,
    /// With two groups (one degree of freedom between them): the difference of their levels
    /// (ln factor) that the test calls with probability [`DETECT_POWER`] at its level, given
    /// the scatter about the levels that the factors show ([`NestedTest::detectable`]). NaN
    /// with more groups or where there is no test. Read beside a test not called: a smaller
    /// difference would have gone unseen more often than not.
    pub detectable_ln: f64,
    /// For campaigns (random groups): the sd of the ln factor of a new specimen from a new
    /// campaign, √(σ_w² + σ_c²), with its 95 % interval ([`new_group_sd`]: Graybill–Wang from
    /// the test's mean squares): (estimate, lower, upper). The scatter between specimens read
    /// as if they were independent is too narrow here where campaigns differ (its interval
    /// rests on the specimens' degrees of freedom, this one on the campaigns' too). `None` for
    /// temperatures (fixed levels) and where the test is not made or the campaigns are
    /// nearly confounded with temperature and stress.
    pub new_group_sd: Option<(f64, f64, f64)>,
}

/// The power at which [`GroupLevels::detectable_ln`] states the difference a test can see.
pub const DETECT_POWER: f64 = 0.8;

impl<G> GroupLevels<G> {
    /// Whether the groups differ: p below [`STRESS_TREND_ALPHA`], the stress trend's level
    /// (false where the test could not be made).
    pub fn differ(&self) -> bool {
        self.p_value < STRESS_TREND_ALPHA
    }
}

/// How one kind of specimen factor differs between test temperatures: the F-test of equal
/// levels beside a pooled slope on ln σ ([`StressTrend`]'s model against one intercept). The
/// hierarchical model draws every specimen's factor from one distribution at every
/// temperature; levels far apart are a temperature dependence the constants' laws miss and
/// the factors take up (on the seed's steel the ductility factors are ~0.6 at 560 °C and ~1.6
/// at 590 °C: a rupture strain that grows with temperature, which the KHD model's one ω_f/C
/// does not carry).
pub type TemperatureLevels = GroupLevels<f64>;

/// How one kind's specimen ln factors differ between test campaigns (laboratories, heats or
/// batches of specimens: [`crate::data::campaign_of`]) beyond what temperature and stress
/// explain: an F-test of equal campaign levels beside a level per temperature and a common
/// slope on ln σ (the campaigns compared within the temperatures they share). Called, the
/// specimens of one campaign resemble each other more than those of another: a heat or
/// laboratory effect, which iid specimen factors read as scatter between specimens and which a
/// prediction for a new campaign must carry on top.
pub type CampaignLevels = GroupLevels<String>;

/// The F-test of the columns `extra` beyond the columns `base` in a least-squares fit
/// ([`nested_test`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NestedTest {
    /// ((RSS_base − RSS_full)/d₁)/(RSS_full/d₂); NaN where d₁ or d₂ is 0.
    pub f: f64,
    /// d₁ = rank(full) − rank(base).
    pub d1: usize,
    /// d₂ = n − rank(full).
    pub d2: usize,
    /// With d₁ = 1: the coefficient δ of an extra column (the last that leaves the base's
    /// span) at which the test rejects at [`STRESS_TREND_ALPHA`] with probability
    /// [`DETECT_POWER`], at the residual scatter σ̂² = RSS_full/d₂: δ = σ̂·√(λ*/‖M k‖²), with λ*
    /// the noncentrality of that power ([`noncentrality_for_power`]) and M k the column's
    /// residual on the base columns. With indicator columns of two groups and a level in the
    /// base, δ is the difference of the two groups' levels. NaN otherwise.
    pub detectable: f64,
    /// The mean squares (RSS_base − RSS_full)/d₁ and RSS_full/d₂ of the F statistic.
    pub ms: (f64, f64),
    /// The coefficient q of a random group variance in the extra columns' expected mean
    /// square, E[(RSS_base − RSS_full)/d₁] = σ_w² + q σ_g² where y = base·β + Z c + e with c ~
    /// N(0, σ_g² I), e ~ N(0, σ_w² I) and Z the `extra` columns: q = ‖M Z‖²_F/d₁, M the
    /// projection off the base columns (Z lies in the full span). NaN where `f` is.
    pub q: f64,
}

/// The F statistic of the columns `extra` beyond the columns `base` in the least-squares fit
/// of `y`, ((RSS_base − RSS_full)/d₁)/(RSS_full/d₂), with d₁ = rank(full) − rank(base) and
/// d₂ = n − rank(full) (ranks from the singular values, so that columns the others span count
/// nothing); NaN where d₁ or d₂ is 0.
pub fn nested_f(y: &[f64], base: &[Vec<f64>], extra: &[Vec<f64>]) -> (f64, usize, usize) {
    let t = nested(y, base, extra, false);
    (t.f, t.d1, t.d2)
}

/// [`nested_f`] with the difference the test can detect ([`NestedTest::detectable`]).
pub fn nested_test(y: &[f64], base: &[Vec<f64>], extra: &[Vec<f64>]) -> NestedTest {
    nested(y, base, extra, true)
}

/// [`nested_test`]; the detectable difference (a root search) only where `detect`.
fn nested(y: &[f64], base: &[Vec<f64>], extra: &[Vec<f64>], detect: bool) -> NestedTest {
    let n = y.len();
    // Residual sum of squares and rank of least squares of `v` on the columns `cols` (SVD).
    let fit = |v: &[f64], cols: &[&Vec<f64>]| -> (f64, usize) {
        let b = nalgebra::DVector::from_column_slice(v);
        if cols.is_empty() {
            return (b.norm_squared(), 0);
        }
        let a = DMatrix::from_fn(n, cols.len(), |i, c| cols[c][i]);
        let svd = a.clone().svd(true, true);
        let top = svd.singular_values.iter().fold(0.0f64, |m, v| m.max(*v));
        let rank = svd
            .singular_values
            .iter()
            .filter(|v| **v > 1e-10 * top)
            .count();
        let sol = svd.solve(&b, 1e-10 * top).expect("U and V computed");
        ((&b - &a * sol).norm_squared(), rank)
    };
    let base_cols: Vec<&Vec<f64>> = base.iter().collect();
    let full_cols: Vec<&Vec<f64>> = base.iter().chain(extra).collect();
    let (rss_base, r_base) = fit(y, &base_cols);
    let (rss_full, r_full) = fit(y, &full_cols);
    let (d1, d2) = (r_full - r_base, n.saturating_sub(r_full));
    if d1 == 0 || d2 == 0 {
        return NestedTest {
            f: f64::NAN,
            d1,
            d2,
            detectable: f64::NAN,
            ms: (f64::NAN, f64::NAN),
            q: f64::NAN,
        };
    }
    let ms = (
        (rss_base - rss_full).max(0.0) / d1 as f64,
        rss_full / d2 as f64,
    );
    let f = ms.0 / ms.1;
    let q = extra.iter().map(|k| fit(k, &base_cols).0).sum::<f64>() / d1 as f64;
    let detectable = if d1 == 1 && detect {
        // The extra direction beyond the base is one line: any extra column's residual on
        // the base spans it; the last one's coefficient is the contrast reported.
        let beyond = extra
            .iter()
            .rev()
            .map(|k| fit(k, &base_cols).0)
            .find(|r| *r > 1e-12 * n as f64)
            .unwrap_or(f64::NAN);
        let lam = noncentrality_for_power(1, d2, STRESS_TREND_ALPHA, DETECT_POWER);
        (rss_full / d2 as f64 * lam / beyond).sqrt()
    } else {
        f64::NAN
    };
    NestedTest {
        f,
        d1,
        d2,
        detectable,
        ms,
        q,
    }
}

/// The sd of a new observation from a new group, √(σ_w² + σ_g²), and its two-sided interval at
/// `level`, from the mean squares of a [`NestedTest`] whose extra columns are group
/// indicators (a one-way random-effects covariance analysis): σ_w² + σ_g² = θ₁/q + (1 − 1/q)θ₂
/// with θ₁ = E(MS_extra), θ₂ = E(MS_resid). The estimate puts max(0, (MS₁ − MS₂)/q) for σ_g²;
/// the interval is Graybill and Wang's modified large-sample interval for a sum of expected
/// mean squares with positive coefficients (Burdick & Graybill, *Confidence Intervals on
/// Variance Components*, 1992, §3.2), exact when either coefficient is zero. `None` where the
/// test was not made or q ≤ 1 (the groups nearly confounded with the base columns: the
/// coefficient of θ₂ would be negative).
pub fn new_group_sd(t: &NestedTest, level: f64) -> Option<(f64, f64, f64)> {
    if !(t.f.is_finite() && t.q.is_finite() && t.q > 1.0 && t.ms.1 > 0.0) {
        return None;
    }
    let (c1, c2) = (1.0 / t.q, 1.0 - 1.0 / t.q);
    let (m1, m2) = t.ms;
    let a = 0.5 * (1.0 - level);
    // n/χ²_n at the upper and lower a points.
    let ratio = |n: usize, p: f64| n as f64 / crate::specimen::chi2_quantile(n as f64, p);
    let g = |n| 1.0 - ratio(n, 1.0 - a);
    let h = |n| ratio(n, a) - 1.0;
    let gamma = c1 * m1 + c2 * m2;
    let lo = gamma - ((g(t.d1) * c1 * m1).powi(2) + (g(t.d2) * c2 * m2).powi(2)).sqrt();
    let hi = gamma + ((h(t.d1) * c1 * m1).powi(2) + (h(t.d2) * c2 * m2).powi(2)).sqrt();
    let est = m2 + ((m1 - m2) / t.q).max(0.0);
    Some((est.sqrt(), lo.max(0.0).sqrt(), hi.sqrt()))
}

/// Upper tail of the noncentral F distribution with (`d1`, `d2`) degrees of freedom and
/// noncentrality `lam` at `f`: the Poisson(λ/2) mixture of the central tails,
/// Σ_j e^{−λ/2}(λ/2)^j/j! · (1 − I_x(d₁/2 + j, d₂/2)), x = d₁f/(d₁f + d₂), summed until the
/// Poisson weights left are below 1e-14.
pub fn noncentral_f_upper(f: f64, d1: usize, d2: usize, lam: f64) -> f64 {
    if f.is_nan() || d1 == 0 || d2 == 0 || !(lam >= 0.0) {
        return f64::NAN;
    }
    let (a, b) = (d1 as f64 / 2.0, d2 as f64 / 2.0);
    let x = d1 as f64 * f / (d1 as f64 * f + d2 as f64);
    let half = lam / 2.0;
    let mut weight = (-half).exp();
    let (mut sum, mut used) = (0.0, 0.0);
    for j in 0..100_000 {
        sum += weight * (1.0 - statrs::function::beta::beta_reg(a + j as f64, b, x));
        used += weight;
        if 1.0 - used < 1e-14 && j as f64 > half {
            break;
        }
        weight *= half / (j + 1) as f64;
    }
    sum
}

/// The noncentrality λ at which the F-test with (`d1`, `d2`) degrees of freedom at level
/// `alpha` rejects with probability `power` (bisection on [`noncentral_f_upper`] beyond the
/// central critical value; NaN for a zero degree of freedom).
pub fn noncentrality_for_power(d1: usize, d2: usize, alpha: f64, power: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, FisherSnedecor};
    if d1 == 0 || d2 == 0 {
        return f64::NAN;
    }
    let Ok(central) = FisherSnedecor::new(d1 as f64, d2 as f64) else {
        return f64::NAN;
    };
    let crit = central.inverse_cdf(1.0 - alpha);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while noncentral_f_upper(crit, d1, d2, hi) < power && hi < 1e6 {
        hi *= 2.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if noncentral_f_upper(crit, d1, d2, mid) < power {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The curves' distinct test temperatures (°C, increasing) and each curve's index into them.
fn temperature_index(curves: &[Curve]) -> (Vec<f64>, Vec<usize>) {
    let mut temps: Vec<f64> = curves.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let index = curves
        .iter()
        .map(|c| {
            temps
                .iter()
                .position(|t| *t == c.temperature_c)
                .unwrap_or(0)
        })
        .collect();
    (temps, index)
}

/// The indicator columns of `group`'s distinct values (in increasing order).
fn indicators(group: &[usize]) -> Vec<Vec<f64>> {
    let mut ids: Vec<usize> = group.to_vec();
    ids.sort_unstable();
    ids.dedup();
    ids.iter()
        .map(|id| {
            group
                .iter()
                .map(|gi| f64::from(u8::from(gi == id)))
                .collect()
        })
        .collect()
}

/// The F statistic of equal group levels for `y` with a pooled slope on `x` (covariance
/// analysis: one intercept per group against one in all; [`nested_f`]), and its degrees of
/// freedom (groups − 1, n − groups − 1 where x is not constant within every group; the ranks
/// otherwise); NaN with fewer than two groups or no residual degree of freedom.
pub fn between_group_f(x: &[f64], y: &[f64], group: &[usize]) -> (f64, usize, usize) {
    let t = between_group_test(x, y, group);
    (t.f, t.d1, t.d2)
}

/// [`between_group_f`] as a [`NestedTest`] (with the difference it can detect).
fn between_group_test(x: &[f64], y: &[f64], group: &[usize]) -> NestedTest {
    let levels = indicators(group);
    let n = y.len();
    if levels.len() < 2 {
        return NestedTest {
            f: f64::NAN,
            d1: levels.len().saturating_sub(1),
            d2: n.saturating_sub(levels.len() + 1),
            detectable: f64::NAN,
            ms: (f64::NAN, f64::NAN),
            q: f64::NAN,
        };
    }
    nested_test(y, &[vec![1.0; n], x.to_vec()], &levels)
}

/// Upper tail of the F distribution with (`d1`, `d2`) degrees of freedom at `f` (NaN for NaN
/// or a zero degree of freedom; 0 for an infinite `f`).
pub fn f_upper(f: f64, d1: usize, d2: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, FisherSnedecor};
    if f.is_nan() || d1 == 0 || d2 == 0 {
        return f64::NAN;
    }
    if f.is_infinite() {
        return 0.0;
    }
    match FisherSnedecor::new(d1 as f64, d2 as f64) {
        Ok(d) => d.sf(f),
        Err(_) => f64::NAN,
    }
}

/// Two-sided p-value of a t statistic with `df` degrees of freedom (NaN for NaN or df 0; 0
/// for an infinite t, a slope without scatter about it).
pub fn t_two_sided(t: f64, df: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    if t.is_nan() || df == 0 {
        return f64::NAN;
    }
    if t.is_infinite() {
        return 0.0;
    }
    match StudentsT::new(0.0, 1.0, df as f64) {
        Ok(d) => 2.0 * d.sf(t.abs()),
        Err(_) => f64::NAN,
    }
}

impl SpecimenFit {
    /// Per kind, how the specimens' ln factors differ between temperatures
    /// ([`TemperatureLevels`]; empty with one temperature); `curves` are the curves the fit
    /// was made on, in its order.
    pub fn temperature_levels(&self, curves: &[Curve]) -> Vec<TemperatureLevels> {
        let (temps, group) = temperature_index(curves);
        if temps.len() < 2 {
            return Vec::new();
        }
        let x: Vec<f64> = curves.iter().map(|c| c.stress_mpa.ln()).collect();
        self.group_levels(&temps, &group, false, |eta| {
            between_group_test(&x, eta, &group)
        })
    }

    /// Per kind, how the specimens' ln factors differ between test campaigns beyond a level
    /// per temperature and a common slope on ln σ ([`CampaignLevels`]); empty where the labels
    /// name no campaigns ([`crate::data::campaigns`]). `curves` are the curves the fit was
    /// made on, in its order.
    pub fn campaign_levels(&self, curves: &[Curve]) -> Vec<CampaignLevels> {
        let Some(camps) = crate::data::campaigns(curves) else {
            return Vec::new();
        };
        let mut names: Vec<&str> = camps.clone();
        names.sort_unstable();
        names.dedup();
        let campaign: Vec<usize> = camps
            .iter()
            .map(|c| names.iter().position(|n| n == c).unwrap_or(0))
            .collect();
        let (_, temperature) = temperature_index(curves);
        let mut base = indicators(&temperature);
        base.push(curves.iter().map(|c| c.stress_mpa.ln()).collect());
        let extra = indicators(&campaign);
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        self.group_levels(&names, &campaign, true, |eta| {
            nested_test(eta, &base, &extra)
        })
    }

    /// Per kind, the mean ln factor of each group (`group[i]` the index into `names` of curve
    /// i) and the F-test `test` makes of the kind's ln factors; no test (NaN) at the scatter's
    /// floor, where the factors are zero but for rounding. Where the groups are `random`
    /// (campaigns), also the sd of a new specimen from a new group.
    fn group_levels<G: Clone>(
        &self,
        names: &[G],
        group: &[usize],
        random: bool,
        test: impl Fn(&[f64]) -> NestedTest,
    ) -> Vec<GroupLevels<G>> {
        self.kinds
            .iter()
            .zip(&self.effects)
            .enumerate()
            .map(|(k, (&kind, eta))| {
                let mean_ln = names
                    .iter()
                    .enumerate()
                    .map(|(g, name)| {
                        let v: Vec<f64> = (0..eta.len())
                            .filter(|&i| group[i] == g)
                            .map(|i| eta[i])
                            .collect();
                        (name.clone(), v.iter().sum::<f64>() / v.len() as f64)
                    })
                    .collect();
                let mut t = test(eta);
                if self.scatter[k] <= crate::specimen::SCATTER_FLOOR * (1.0 + 1e-9) {
                    t.f = f64::NAN;
                    t.detectable = f64::NAN;
                }
                let new_group_sd = if random { new_group_sd(&t, 0.95) } else { None };
                GroupLevels {
                    kind,
                    mean_ln,
                    f: t.f,
                    df: (t.d1, t.d2),
                    p_value: f_upper(t.f, t.d1, t.d2),
                    detectable_ln: t.detectable,
                    new_group_sd,
                }
            })
            .collect()
    }

    /// Per kind, how the specimens' ln factors follow ln σ within temperatures
    /// ([`StressTrend`]); `curves` are the curves the fit was made on, in its order.
    pub fn stress_trend(&self, curves: &[Curve]) -> Vec<StressTrend> {
        let x: Vec<f64> = curves.iter().map(|c| c.stress_mpa.ln()).collect();
        let mut temps: Vec<f64> = Vec::new();
        let group: Vec<usize> = curves
            .iter()
            .map(|c| match temps.iter().position(|t| *t == c.temperature_c) {
                Some(i) => i,
                None => {
                    temps.push(c.temperature_c);
                    temps.len() - 1
                }
            })
            .collect();
        self.kinds
            .iter()
            .zip(&self.effects)
            .map(|(&kind, eta)| {
                let (slope, se, df) = within_group_slope(&x, eta, &group);
                StressTrend {
                    kind,
                    slope,
                    se,
                    df,
                    p_value: t_two_sided(slope / se, df),
                    specimens: curves.len(),
                    temperatures: temps.len(),
                }
            })
            .collect()
    }
}

/// A maximum-likelihood fit: constants and error model.
#[derive(Debug, Clone)]
pub struct MlFit {
    /// Fitted constants (physical), model order: the population's (a median specimen's).
    pub params: Vec<f64>,
    /// The error model at the fit.
    pub noise: ErrorModel,
    /// −2 ln L at the fit (NaN if the fit failed); with specimen effects the Laplace
    /// approximation of the marginal likelihood, minimised over the scatter (maximum
    /// likelihood; [`SpecimenFit::scatter`] is the REML estimate).
    pub neg2ll: f64,
    /// Raw residuals at the fit (with specimen effects: at each specimen's own constants).
    pub residuals: Option<Residuals>,
    /// Predictions at the fit (eq. 8 at w = 1, both sides, for reports; with specimen
    /// effects each curve's at its specimen's own constants).
    pub eval: Option<Evaluation>,
    /// The specimen effects, if the fit carries any (scatter above zero).
    pub specimen: Option<SpecimenFit>,
    /// How the iteration ended.
    pub termination: Termination,
    /// LM iterations.
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Why it failed, if it did.
    pub failure: Option<String>,
}

impl MlFit {
    /// Whether the fit ended at an evaluable point.
    pub fn ok(&self) -> bool {
        self.neg2ll.is_finite() && self.termination != Termination::SimulationFailure
    }

    /// The better of two fits of one start (`self` on a tie, and when both failed): `other`
    /// when it ended at an evaluable point with a lower −2 ln L, or `self` failed.
    pub fn better(self, other: MlFit) -> MlFit {
        match (self.ok(), other.ok()) {
            (true, true) if other.neg2ll < self.neg2ll => other,
            (false, true) => other,
            _ => self,
        }
    }

    fn failed(start: &[f64], msg: String, iterations: usize, evaluations: usize) -> MlFit {
        MlFit {
            params: start.to_vec(),
            noise: ErrorModel {
                strain: vec![],
                lifetime_sd: f64::NAN,
            },
            neg2ll: f64::NAN,
            residuals: None,
            eval: None,
            specimen: None,
            termination: Termination::SimulationFailure,
            iterations,
            evaluations,
            failure: Some(msg),
        }
    }

    /// The per-curve factors of the fitted specimen effects (`None` without effects), for
    /// simulating each curve at its specimen's own constants.
    pub fn factors(&self, model: &dyn Model) -> Option<CurveFactors> {
        self.specimen.as_ref()?.curve_factors(model)
    }
}

/// Where a hierarchical fit starts its specimen effects: their ln factors (kind-major, as
/// [`SpecimenFit::effects`] flattened) and their scatter, per kind.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectStart {
    /// The kinds, in the order of `scatter`.
    pub kinds: Vec<EffectKind>,
    /// Per kind, per curve: the ln factor.
    pub effects: Vec<Vec<f64>>,
    /// Per kind: the scatter.
    pub scatter: Vec<f64>,
    /// The criterion the scatter came from: a warm start's own report is taken by it.
    pub method: ScatterMethod,
}

impl EffectStart {
    /// New specimens: every effect zero, the scatter `scatter` (the same kinds).
    pub fn fresh(kinds: Vec<EffectKind>, scatter: Vec<f64>, n_curves: usize) -> Self {
        EffectStart {
            effects: vec![vec![0.0; n_curves]; kinds.len()],
            kinds,
            scatter,
            method: ScatterMethod::LinearMixedModel,
        }
    }
}

impl EffectStart {
    /// These effects, which belong to population constants `from` (model order), re-expressed
    /// for constants `to`: every specimen keeps its own constants (the rate constant
    /// A·e^η, the inverse ductility C/e^ζ of `from`). A warm start that moves a constant an
    /// effect acts through (a profile holding A away from the optimum) then starts with every
    /// specimen's curve as it was, instead of every specimen moved by the step.
    pub fn moved(&self, model: &dyn Model, from: &[f64], to: &[f64]) -> EffectStart {
        let mut out = self.clone();
        for (k, kind) in self.kinds.iter().enumerate() {
            let Some(j) = model.constants().iter().position(|c| c.role == kind.role()) else {
                continue;
            };
            let (a, b) = (from.get(j).copied(), to.get(j).copied());
            if let (Some(a), Some(b)) = (a, b) {
                let shift = kind.sign() * (a / b).ln();
                if shift.is_finite() {
                    for v in out.effects[k].iter_mut() {
                        *v += shift;
                    }
                }
            }
        }
        out
    }
}

impl From<&SpecimenFit> for EffectStart {
    fn from(f: &SpecimenFit) -> Self {
        EffectStart {
            kinds: f.kinds.clone(),
            effects: f.effects.clone(),
            scatter: f.scatter.clone(),
            method: f.scatter_method,
        }
    }
}

/// One residual appended to a fit's problem, a function of the constants alone: how a profile
/// holds a prediction near a target (the penalty row (g − c)/τ) in a fit with specimen
/// effects, whose problem is built inside [`ml_fit_row`].
pub trait ExtraRow: Sync {
    /// The residual and its gradient over the free constants' unit coordinates of `space` at
    /// their unit point `u`; `None` where it cannot be evaluated.
    fn row(&self, space: &ParamSpace, u: &[f64]) -> Option<(f64, Vec<f64>)>;
}

/// `inner` with the row of `row` appended (its Jacobian zero in the specimen effects'
/// columns, which follow the `nt` constants), every residual multiplied by `c`.
///
/// Why the factor: [`minimize`]'s first damping is λ₀·max JᵀJ_jj times each JᵀJ_jj, so it
/// grows with the square of the Jacobian's scale; whitened likelihood residuals have JᵀJ
/// diagonals of 1e7–1e9, and a held fit started next to its optimum then takes steps of
/// ~1e-11 of the box and stops on its plateau test or step tolerance where it began
/// (measured: a held minimum rate and rupture strain that did not move). With c such that
/// max JᵀJ_jj = 1 at the start the damping is the intended λ₀·JᵀJ_jj; the minimiser of
/// ‖c·r‖² is that of ‖r‖².
struct WithRow<'a, P: LeastSquaresProblem> {
    inner: &'a P,
    row: Option<&'a dyn ExtraRow>,
    space: &'a ParamSpace,
    nt: usize,
    c: f64,
}

impl<P: LeastSquaresProblem> WithRow<'_, P> {
    /// The row's residual and gradient at `u` (`None` without a row).
    fn eval(&self, u: &[f64]) -> Result<Option<(f64, Vec<f64>)>, EvalFailure> {
        let Some(row) = self.row else {
            return Ok(None);
        };
        row.row(self.space, &u[..self.nt])
            .filter(|(v, g)| v.is_finite() && g.iter().all(|d| d.is_finite()))
            .map(Some)
            .ok_or_else(|| EvalFailure("the held quantity could not be evaluated".into()))
    }
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for WithRow<'_, P> {
    fn n_params(&self) -> usize {
        self.inner.n_params()
    }
    fn n_residuals(&self) -> usize {
        self.inner.n_residuals() + usize::from(self.row.is_some())
    }
    fn residuals(&self, u: &[f64], r: &mut [f64]) -> Result<(), EvalFailure> {
        let m = self.inner.n_residuals();
        self.inner.residuals(u, &mut r[..m])?;
        if let Some((v, _)) = self.eval(u)? {
            r[m] = v;
        }
        for v in r.iter_mut() {
            *v *= self.c;
        }
        Ok(())
    }
    fn residuals_and_jacobian(
        &self,
        u: &[f64],
        r: &mut [f64],
        jac: &mut DMatrix<f64>,
    ) -> Option<Result<(), EvalFailure>> {
        let (m, n) = (self.inner.n_residuals(), self.n_params());
        let mut ji = DMatrix::<f64>::zeros(m, n);
        if let Err(e) = self.inner.residuals_and_jacobian(u, &mut r[..m], &mut ji)? {
            return Some(Err(e));
        }
        let row = match self.eval(u) {
            Ok(x) => x,
            Err(e) => return Some(Err(e)),
        };
        jac.view_mut((0, 0), (m, n)).copy_from(&ji);
        if let Some((v, grad)) = row {
            for k in 0..n {
                jac[(m, k)] = if k < grad.len() { grad[k] } else { 0.0 };
            }
            r[m] = v;
        }
        for v in r.iter_mut() {
            *v *= self.c;
        }
        *jac *= self.c;
        Some(Ok(()))
    }
    fn reweight(&self, x: &[f64], r: &mut [f64], mut jac: Option<&mut DMatrix<f64>>) -> bool {
        // The inner problem rewrites only its own rows; the row does not depend on the
        // error model. It works on the unscaled residuals.
        let inv = 1.0 / self.c;
        for v in r.iter_mut() {
            *v *= inv;
        }
        if let Some(j) = jac.as_deref_mut() {
            *j *= inv;
        }
        let changed = self.inner.reweight(x, r, jac.as_deref_mut());
        for v in r.iter_mut() {
            *v *= self.c;
        }
        if let Some(j) = jac {
            *j *= self.c;
        }
        changed
    }
    fn objective_offset(&self) -> f64 {
        self.c * self.c * self.inner.objective_offset()
    }
    fn damping_scale(&self, jtj: &DMatrix<f64>) -> Option<Vec<f64>> {
        self.inner.damping_scale(jtj)
    }
}

/// The unit-box columns (among `space`'s free constants) of the model-order constants
/// `pinned` that are free in `space`.
fn pinned_columns(space: &ParamSpace, pinned: &[usize]) -> Vec<usize> {
    pinned
        .iter()
        .filter(|&&j| j < space.len() && space.free[j])
        .map(|&j| space.free[..j].iter().filter(|f| **f).count())
        .collect()
}

/// How [`ml_fit_row`] holds a fit: constants pinned by the box, a row appended, and whether
/// every problem is scaled (a profile's fits, which start next to their optimum: with
/// whitened residuals' JᵀJ diagonals of 1e7–1e9 the first damping would otherwise keep them
/// where they began).
#[derive(Clone, Copy, Default)]
pub struct Held<'a> {
    /// Model-order constants (free in the fit's space) held at their start values by the box.
    pub pinned: &'a [usize],
    /// A row appended to every least-squares problem.
    pub row: Option<&'a dyn ExtraRow>,
    /// Scale every problem so that max JᵀJ_jj = 1 at its start (tolerances in −2 ln L units
    /// are scaled with it).
    pub scaled: bool,
}

impl Held<'_> {
    /// A fit like any other: nothing held, nothing scaled.
    pub const NONE: Held<'static> = Held {
        pinned: &[],
        row: None,
        scaled: false,
    };
}

/// [`minimize`] on `problem`, with `held.row` appended when given and scaled if
/// `held.scaled` (else exactly [`minimize`] on `problem`).
#[allow(clippy::too_many_arguments)]
fn minimize_with<P: LeastSquaresProblem>(
    problem: &P,
    held: &Held,
    space: &ParamSpace,
    x0: &[f64],
    lo: &[f64],
    hi: &[f64],
    lm: &crate::lsq::LmOptions,
) -> crate::lsq::LmReport {
    if held.row.is_none() && !held.scaled {
        return minimize(problem, x0, lo, hi, lm);
    }
    {
        {
            let mut p = WithRow {
                inner: problem,
                row: held.row,
                space,
                nt: space.n_free(),
                c: 1.0,
            };
            let (m, n) = (p.n_residuals(), p.n_params());
            let mut r = vec![0.0; m];
            let mut jac = DMatrix::<f64>::zeros(m, n);
            if let Some(Ok(())) = p.residuals_and_jacobian(x0, &mut r, &mut jac) {
                let diag_max = (0..n)
                    .map(|j| jac.column(j).norm_squared())
                    .fold(0.0, f64::max);
                if held.scaled && diag_max.is_finite() && diag_max > 1.0 {
                    p.c = 1.0 / diag_max.sqrt();
                }
            }
            // Absolute tolerances on the objective scale with it.
            let c2 = p.c * p.c;
            let lm = crate::lsq::LmOptions {
                plateau: lm.plateau.map(|(k, d)| (k, d * c2)),
                gain_to_come: lm.gain_to_come.map(|(k, d)| (k, d * c2)),
                ..*lm
            };
            let mut rep = minimize(&p, x0, lo, hi, &lm);
            rep.objective /= c2;
            for v in rep.residuals.iter_mut() {
                *v /= p.c;
            }
            rep
        }
    }
}

/// Fit `model`'s constants to `curves` by maximum likelihood from `start` (physical,
/// model order; constants not free in `space` stay at their held values); with
/// `opts.specimen`, with specimen effects integrated out. A kind of effect whose scatter ends
/// at [`SCATTER_FLOOR`] is dropped (the model without it is the limit τ → 0), so the result
/// is the model without effects where the data show no scatter.
pub fn ml_fit(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    start: &[f64],
    settings: &FitSettings,
    opts: &MlOptions,
) -> MlFit {
    ml_fit_from(model, curves, space, start, None, settings, opts)
}

/// [`ml_fit`] with the specimen effects starting at `effects` (kinds the fit does not carry
/// are ignored; kinds it carries but `effects` lacks start at zero effects and
/// [`SCATTER_START`]).
pub fn ml_fit_from(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    start: &[f64],
    effects: Option<&EffectStart>,
    settings: &FitSettings,
    opts: &MlOptions,
) -> MlFit {
    ml_fit_row(
        model,
        curves,
        space,
        start,
        effects,
        settings,
        opts,
        &Held::NONE,
    )
}

/// [`ml_fit_from`] held as `held` says: the constants `pinned` (model order, free in `space`)
/// held at their `start` values by the box (so that, unlike a constant held in `space`, the specimen effects
/// acting through them stay in the fit: a profile of the rate constant with rate effects),
/// and `row` appended to every least-squares problem of the fit (a profile's penalty holding
/// a function of the constants near a target; [`ExtraRow`]), every problem scaled if asked
/// ([`Held::scaled`]). The reported −2 ln L is the
/// likelihood's alone, without the row; with a row a warm start's own report is not a
/// candidate (it does not hold the target).
#[allow(clippy::too_many_arguments)]
pub fn ml_fit_row(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    start: &[f64],
    effects: Option<&EffectStart>,
    settings: &FitSettings,
    opts: &MlOptions,
    held: &Held,
) -> MlFit {
    let (pinned, row) = (held.pinned, held.row);
    // The gain-to-come stop is for fits without specimen effects: a hierarchical fit's
    // rounds end on their plateau test ([`PLATEAU`]), and with both, the rounds' paths moved
    // the null refits' ends (Alloy 617 950 °C: `lr_critical` up to 4.4 away, p-values alike).
    let plain;
    let settings = if opts.specimen.any() && settings.lm.gain_to_come.is_some() {
        plain = FitSettings {
            lm: crate::lsq::LmOptions {
                gain_to_come: None,
                ..settings.lm
            },
            ..*settings
        };
        &plain
    } else {
        settings
    };
    // A warm start with specimen effects may be evaluable only with its specimens' factors
    // (the population's constants at a stress where a median specimen does not rupture in
    // the horizon while every tested one does): it is checked with them further down.
    let warm_effects = opts.specimen.any()
        && effects.is_some_and(|e| e.effects.iter().flatten().any(|v| *v != 0.0));
    let res = match residuals_at(model, curves, start, settings) {
        Ok(r) => Some(r),
        Err(_) if warm_effects => None,
        Err(e) => return MlFit::failed(start, e.0, 0, 1),
    };
    let inner = || CreepProblem {
        objective: raw_objective(model, curves, settings),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let u0 = space.to_unit(start);
    let pins = pinned_columns(space, pinned);
    let (mut lo, mut hi) = (vec![0.0; u0.len()], vec![1.0; u0.len()]);
    for &k in &pins {
        (lo[k], hi[k]) = (u0[k], u0[k]);
    }
    // Stage 1: white reading errors, no specimen effects. A smooth misfit (a loading strain
    // left out, a primary stage missed) is what an AR(1) model with φ near 1 explains as
    // noise; from such a start the profiled likelihood cannot see it, and the LM stops where
    // it began. With white errors it is misfit and the constants move to remove it.
    // With specimen effects the white stage is the hierarchical fit's own white round (the
    // effects fitted with the constants): a white fit without them first takes the
    // specimens' differences into the constants (a stress sensitivity that mimics the rate
    // factors' trend with stress), a valley the hierarchical fit was measured not to leave
    // (−2 ln L −8852.7 against −8967.6 from the same start with the white round alone, on
    // 16 generated specimens).
    let specimen_layout = if opts.specimen.any() {
        let (layout, dropped) = EffectLayout::new(model, curves, space, &opts.specimen.kinds());
        let layout = layout.map(|l| {
            if opts.specimen.beyond_trend {
                l.with_trend(curves)
            } else {
                l
            }
        });
        (layout, dropped)
    } else {
        (None, vec![])
    };
    let res = match (res, &specimen_layout.0) {
        (Some(r), _) => Some(r),
        (None, Some(_)) => None,
        (None, None) => match residuals_at(model, curves, start, settings) {
            Ok(r) => Some(r),
            Err(e) => return MlFit::failed(start, e.0, 0, 1),
        },
    };
    let (u1, it1, ev1) = if opts.white_first && specimen_layout.0.is_none() {
        let res = res.as_ref().expect("evaluated without effects");
        let white = LikelihoodProblem::white(
            inner(),
            ErrorModel::estimate_white(res, opts.lifetime_sd_floor),
            opts.lifetime_sd_floor,
        );
        let lm1 = minimize_with(&white, held, space, &u0, &lo, &hi, &settings.lm);
        if lm1.termination == Termination::SimulationFailure {
            return MlFit::failed(
                start,
                lm1.failure.unwrap_or_default(),
                lm1.iterations,
                lm1.evaluations,
            );
        }
        (lm1.x, lm1.iterations, lm1.evaluations)
    } else {
        (u0, 0, 0)
    };
    // Stage 2: the full error model, from stage 1's point.
    let mut x1 = start.to_vec();
    space.from_unit(&u1, &mut x1);
    let res1 = if opts.white_first && specimen_layout.0.is_none() {
        match residuals_at(model, curves, &x1, settings) {
            Ok(r) => Some(r),
            Err(e) => return MlFit::failed(start, e.0, it1, ev1),
        }
    } else {
        res
    };
    let noise1 = res1
        .as_ref()
        .map(|r| ErrorModel::estimate(r, opts.lifetime_sd_floor));
    if let (Some(layout), dropped) = specimen_layout {
        let n = layout.n_curves;
        // New specimens (no effects given, or all zero) get a white round first.
        let fresh = opts.white_first || !warm_effects;
        let (eta, scatter): (Vec<f64>, Vec<f64>) = {
            let mut eta = Vec::with_capacity(layout.n_effects());
            let mut tau = Vec::with_capacity(layout.kinds.len());
            for &(kind, _, _) in &layout.kinds {
                match effects.and_then(|e| e.kinds.iter().position(|k| *k == kind)) {
                    Some(j) if effects.unwrap().effects[j].len() == n => {
                        let e = effects.unwrap();
                        eta.extend(
                            e.effects[j]
                                .iter()
                                .map(|v| v.clamp(-EFFECT_MAX, EFFECT_MAX)),
                        );
                        tau.push(e.scatter[j].max(SCATTER_FLOOR));
                    }
                    _ => {
                        eta.extend(std::iter::repeat_n(0.0, n));
                        tau.push(SCATTER_START);
                    }
                }
            }
            // Rate effects that start at zero (new specimens) start instead from each curve's
            // life against the population's: a specimen that creeps e^η times faster lives
            // about e^η times shorter. Measured: the refits of a bootstrap replicate start
            // nearer their optimum.
            if let Some(k) = layout.kinds.iter().position(|k| k.0 == EffectKind::Rate) {
                let rate = &mut eta[k * n..(k + 1) * n];
                if rate.iter().all(|v| *v == 0.0) {
                    if let Some(ev) = raw_objective(model, curves, settings).evaluate(&x1).into() {
                        let ev: Evaluation = ev;
                        for (i, c) in curves.iter().enumerate() {
                            let tp = ev.curves[i].rupture_time_h;
                            if let Some(tf) = c.rupture_time_h {
                                if tp.is_finite() && tp > 0.0 && tf > 0.0 {
                                    rate[i] = (tp / tf).ln().clamp(-1.0, 1.0);
                                }
                            }
                        }
                    }
                }
            }
            (eta, tau)
        };
        let noise1 = match noise1 {
            Some(n) => n,
            None => {
                let obj =
                    raw_objective(model, curves, settings).with_factors(Some(layout.factors(&eta)));
                let mut r = vec![0.0; obj.n_residuals()];
                if let Err(e) = obj.residuals(&x1, &mut r) {
                    return MlFit::failed(start, e.0, it1, ev1 + 1);
                }
                ErrorModel::estimate(&split_residuals(curves, &r), opts.lifetime_sd_floor)
            }
        };
        // A warm start is an optimum already found (the base's, with an extension switched
        // off): its own report is a candidate, so that a refit never ends worse than where
        // it began. The alternation does not minimise the Laplace −2 ln L exactly (its
        // log-determinants are held within a round), and a nested extension refitted from
        // the base optimum was measured to end up to 3 units above it.
        // Its report is taken with the kinds of effects it has: a kind the start dropped (its
        // scatter at the floor) would otherwise come back with zero effects and a scatter
        // estimated at the start, whose Laplace terms cost likelihood that the start did not
        // pay (measured: a nested refit 0.87 below its start on a null set, 99005).
        let at_start = (!fresh && row.is_none())
            .then(|| {
                let given: Vec<usize> = (0..layout.kinds.len())
                    .filter(|&k| {
                        let kind = layout.kinds[k].0;
                        effects.is_some_and(|e| {
                            e.kinds
                                .iter()
                                .position(|q| *q == kind)
                                .is_some_and(|j| e.effects[j].len() == n)
                        })
                    })
                    .collect();
                if given.is_empty() {
                    return None;
                }
                let reduced = layout.keeping(&given);
                let mut u = space.to_unit(&x1);
                for &k in &given {
                    u.extend_from_slice(&eta[k * n..(k + 1) * n]);
                }
                let tau: Vec<f64> = given.iter().map(|&k| scatter[k]).collect();
                let mut f = finish_hier(
                    model,
                    curves,
                    space,
                    &u,
                    &reduced,
                    &tau,
                    effects.map_or(ScatterMethod::LinearMixedModel, |e| e.method),
                    settings,
                    opts,
                )?;
                if let Some(sp) = f.specimen.as_mut() {
                    let missing = (0..layout.kinds.len()).filter(|k| !given.contains(k));
                    sp.dropped.extend(missing.map(|k| layout.kinds[k].0));
                }
                Some(f)
            })
            .flatten();
        let mut fit = match hier_fit(
            model, curves, space, &x1, &eta, scatter, layout, settings, opts, &noise1, fresh,
            &pins, held,
        ) {
            Ok(f) => f,
            // The search met a point it could not simulate: a warm start keeps its own
            // report (`stalled`: no step beyond it was found), a fresh one fails.
            Err(f) => match at_start {
                Some(s) => {
                    return MlFit {
                        termination: Termination::Stalled,
                        iterations: f.1 + it1,
                        evaluations: f.2 + ev1,
                        ..s
                    }
                }
                None => return MlFit::failed(start, f.0, f.1 + it1, f.2 + ev1),
            },
        };
        if let Some(s) = at_start.filter(|s| s.neg2ll < fit.neg2ll) {
            fit = MlFit {
                termination: fit.termination,
                iterations: fit.iterations,
                evaluations: fit.evaluations,
                ..s
            };
        }
        fit.iterations += it1;
        fit.evaluations += ev1;
        if let Some(sp) = fit.specimen.as_mut() {
            sp.dropped.extend(dropped);
        }
        return fit;
    }
    let noise1 = noise1.expect("evaluated without effects");
    let problem = LikelihoodProblem::new(inner(), noise1, opts.lifetime_sd_floor);
    let mut lm = minimize_with(&problem, held, space, &u1, &lo, &hi, &settings.lm);
    lm.iterations += it1;
    lm.evaluations += ev1;
    if lm.termination == Termination::SimulationFailure {
        return MlFit::failed(
            start,
            lm.failure.unwrap_or_default(),
            lm.iterations,
            lm.evaluations,
        );
    }
    let mut x = start.to_vec();
    space.from_unit(&lm.x, &mut x);
    plain_report(model, curves, x, settings, opts, &lm)
}

/// The report of a fit without specimen effects at constants `x`: the error model
/// re-estimated there and −2 ln L.
fn plain_report(
    model: &dyn Model,
    curves: &[Curve],
    x: Vec<f64>,
    settings: &FitSettings,
    opts: &MlOptions,
    lm: &crate::lsq::LmReport,
) -> MlFit {
    let Ok(res) = residuals_at(model, curves, &x, settings) else {
        return MlFit::failed(
            &x,
            "the fitted point could not be evaluated".into(),
            lm.iterations,
            lm.evaluations,
        );
    };
    let noise = ErrorModel::estimate(&res, opts.lifetime_sd_floor);
    let neg2ll = noise.neg2ll(&res);
    let eval = raw_objective(model, curves, settings).evaluate(&x);
    MlFit {
        params: x,
        noise,
        neg2ll,
        residuals: Some(res),
        eval: Some(eval),
        specimen: None,
        termination: lm.termination,
        iterations: lm.iterations,
        evaluations: lm.evaluations,
        failure: None,
    }
}

/// The fit `plain` (without specimen effects) carried on with the specimen effects of `opts`
/// from its constants (effects zero, scatter at [`SCATTER_START`]): the better of the two
/// (`plain` itself when `opts` asks for no effects or `plain` failed).
pub fn with_specimens(
    plain: MlFit,
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    settings: &FitSettings,
    opts: &MlOptions,
) -> MlFit {
    if !opts.specimen.any() || !plain.ok() {
        return plain;
    }
    let polish = MlOptions {
        white_first: false,
        ..*opts
    };
    let h = ml_fit_from(model, curves, space, &plain.params, None, settings, &polish);
    if h.ok() && h.neg2ll < plain.neg2ll {
        MlFit {
            iterations: h.iterations + plain.iterations,
            evaluations: h.evaluations + plain.evaluations,
            ..h
        }
    } else {
        plain
    }
}

/// The hierarchical LM from constants `theta` (physical) and effects `eta` (kind-major) with
/// the scatter starting at `scatter` and re-estimated by maximum likelihood after every
/// round; then [`finish_hier`]; the unit-box columns `pins` held by the box, and `held`'s row
/// and scaling applied to every problem ([`ml_fit_row`]). A failure gives (message, iterations, evaluations).
#[allow(clippy::too_many_arguments)]
fn hier_fit(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    theta: &[f64],
    eta: &[f64],
    scatter: Vec<f64>,
    layout: EffectLayout,
    settings: &FitSettings,
    opts: &MlOptions,
    noise: &ErrorModel,
    white_round: bool,
    pins: &[usize],
    held: &Held,
) -> Result<MlFit, (String, usize, usize)> {
    let nt = layout.n_theta;
    let ne = layout.n_effects();
    let mut lo = vec![0.0; nt + ne];
    let mut hi = vec![1.0; nt + ne];
    for j in nt..nt + ne {
        lo[j] = -EFFECT_MAX;
        hi[j] = EFFECT_MAX;
    }
    let mut x = space.to_unit(theta);
    for &k in pins {
        (lo[k], hi[k]) = (x[k], x[k]);
    }
    x.extend_from_slice(eta);
    let mut tau = match opts.hold_scatter {
        Some(h) => layout.kinds.iter().map(|k| h[kind_index(k.0)]).collect(),
        None => scatter,
    };
    // Beyond the stress trend, the scatter is the restricted likelihood's of the linear mixed
    // model with the trends as fixed effects: no criterion at the modes (which would count
    // the trends) and no descent test of the Laplace −2 ln L (which the estimate does not
    // minimise).
    let beyond = !layout.trend.is_empty();
    let mut noise = noise.clone();
    let (mut its, mut evs) = (0, 0);
    let mut termination = Termination::ConvergedObjective;
    // Lindstrom & Bates' alternation: the constants and effects by penalised least squares
    // at a held scatter (the reading error profiled as always), then the scatter by
    // maximum likelihood on the linear mixed model there; until the scatter settles.
    // Updating the scatter at every LM step instead was measured to fall into 2-cycles (τ
    // 0.058 ↔ 0.167, the step and the estimate chasing each other) that ran to the
    // iteration limit in a third of the bootstrap's refits.
    let inner = || CreepProblem {
        objective: raw_objective(model, curves, settings),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let mut white_lambda = None;
    if white_round {
        // New specimens' effects are fitted against white reading errors first: at an
        // optimum without effects the AR(1) model (φ near 1) has taken each specimen's
        // offset for correlated noise, and the profiled likelihood cannot see what an effect
        // would gain (measured: polished from there directly, the hierarchical fit stayed at
        // the plain optimum, −2 ln L −3213 against −3520 white first).
        let mut params = space.fixed.clone();
        space.from_unit(&x[..nt], &mut params);
        let obj =
            raw_objective(model, curves, settings).with_factors(Some(layout.factors(&x[nt..])));
        let mut r = vec![0.0; obj.n_residuals()];
        if obj.residuals(&params, &mut r).is_ok() {
            let white_noise =
                ErrorModel::estimate_white(&split_residuals(curves, &r), opts.lifetime_sd_floor);
            let problem = LikelihoodProblem::white(inner(), white_noise, opts.lifetime_sd_floor)
                .with_effects(layout.clone(), tau.clone(), true);
            let white_opts = crate::lsq::LmOptions {
                cut_overdamped: true,
                ..settings.lm
            };
            let lm = minimize_with(&problem, held, space, &x, &lo, &hi, &white_opts);
            its += lm.iterations;
            evs += lm.evaluations;
            if lm.termination == Termination::SimulationFailure {
                return Err((lm.failure.unwrap_or_default(), its, evs));
            }
            white_lambda = Some(lm.lambda);
            x = lm.x;
            space.from_unit(&x[..nt], &mut params);
            let obj =
                raw_objective(model, curves, settings).with_factors(Some(layout.factors(&x[nt..])));
            if obj.residuals(&params, &mut r).is_ok() {
                noise = ErrorModel::estimate(&split_residuals(curves, &r), opts.lifetime_sd_floor);
            }
        }
    }
    // The last accepted round: its Laplace −2 ln L, point, error model, scatter and Gram
    // blocks, to step back to when a scatter step does not pay.
    struct Accepted {
        neg2ll: f64,
        x: Vec<f64>,
        noise: ErrorModel,
        tau: Vec<f64>,
        g: Vec<crate::specimen::KMat>,
    }
    let mut accepted: Option<Accepted> = None;
    let mut method = ScatterMethod::LinearMixedModel;
    let lives = curves.iter().filter(|c| c.rupture_time_h.is_some()).count();
    // Each round after the first picks up the damping the previous one ended with. A fresh
    // λ₀ (scaled by the largest diagonal of JᵀJ on top of Marquardt's diagonal scaling)
    // starts at a relative damping near 1e5, whose first step, after a small change of the
    // scatter, is shorter than xtol: the round then ended as `converged_step` after one
    // iteration without refitting anything (traced on a generated null set with rate and
    // ductility effects: every round after the first; the base fit ended 2.85 in −2 ln L
    // above the optimum the carried damping reaches, and every extension's ratio grew by as
    // much). Measured on 100 generated sets (seeds 131001–131100, from the guess): the fit
    // ends lower in 73, by up to 22.9, higher in none.
    let mut lambda0 = white_lambda.map_or(settings.lm.lambda0, |l| {
        carried_damping(l, settings.lm.lambda0)
    });
    for _ in 0..SCATTER_ROUNDS {
        let problem = LikelihoodProblem::new(inner(), noise.clone(), opts.lifetime_sd_floor)
            .with_effects(layout.clone(), tau.clone(), true);
        let lm_opts = crate::lsq::LmOptions {
            plateau: Some(PLATEAU),
            lambda0,
            cut_overdamped: true,
            ..settings.lm
        };
        let lm = minimize_with(&problem, held, space, &x, &lo, &hi, &lm_opts);
        its += lm.iterations;
        evs += lm.evaluations;
        if lm.termination == Termination::SimulationFailure {
            return Err((lm.failure.unwrap_or_default(), its, evs));
        }
        lambda0 = carried_damping(lm.lambda, settings.lm.lambda0);
        x = lm.x;
        noise = problem.noise();
        termination = lm.termination;
        let Some((rr, jac, profiled)) =
            whitened_at(model, curves, space, &x, &layout, &tau, settings, opts)
        else {
            return Err(("the fitted point could not be evaluated".into(), its, evs));
        };
        let g = layout.gram(&jac);
        // The Laplace −2 ln L here (the error model profiled at this point, as `rr` is
        // whitened; Gauss–Newton blocks, as the linear mixed model's).
        let data: f64 = rr[..layout.m_data].iter().map(|v| v * v).sum::<f64>()
            + profiled.normalising(curves.iter().map(|c| c.times_h.len()), lives);
        let now = data + laplace_terms(&x[nt..], &g, &tau);
        if opts.hold_scatter.is_some() {
            // The scatter is held: one round of penalised least squares at it.
            break;
        }
        if let Some(prev) = accepted.as_ref().filter(|_| !beyond) {
            if !crate::specimen::step_pays(prev.neg2ll, now, SCATTER_TOL) {
                // The linear mixed model's step did not pay: its linearisation promised a
                // gain from larger (or smaller) effects that the curves, refitted, do not
                // deliver. Back to the last accepted point, and from there on the scatter
                // steps of the criterion at the modes, each a descent of the Laplace
                // −2 ln L (the data term does not move with τ at held modes).
                x = prev.x.clone();
                noise = prev.noise.clone();
                let back = prev.tau.clone();
                if method == ScatterMethod::LaplaceAtModes {
                    // Already on those steps: the last one's refit did not pay either.
                    tau = back;
                    break;
                }
                method = ScatterMethod::LaplaceAtModes;
                let eta = prev.x[nt..].to_vec();
                tau = minimise_scatter(&back, |t| laplace_terms(&eta, &prev.g, t));
                if scatter_settled(&tau, &back) {
                    tau = back;
                    break;
                }
                continue;
            }
        }
        let lmm = layout.lmm(&jac, &rr, &x[nt..]);
        // Maximum likelihood, not REML: the fit's −2 ln L compares models with different
        // constants, and REML's scatter grows with their number ([`finish_hier`]).
        let at_modes = |t: &[f64]| laplace_terms(&x[nt..], &g, t);
        let (new, settled) = match method {
            ScatterMethod::LinearMixedModel | ScatterMethod::BeyondStressTrend => {
                let new = lmm.estimate(&tau, beyond);
                let settled = !(lmm.neg2l(&new, beyond) < lmm.neg2l(&tau, beyond) - SCATTER_TOL);
                let stays = settled || scatter_settled(&new, &tau);
                // Where the linear model would stay, the criterion at the modes must not see
                // a descent: it lies above the Laplace −2 ln L profiled over the effects and
                // touches it here, so a lower value elsewhere is a lower likelihood there
                // (measured on Alloy 617 at 950 °C: the linear model held the coarsening
                // scatter at its bound 3.0, where the criterion at the modes was lowest at
                // 0.2–0.4).
                let better = (stays && !beyond)
                    .then(|| minimise_scatter(&tau, at_modes))
                    .filter(|b| at_modes(b) < at_modes(&tau) - SCATTER_TOL);
                match better {
                    Some(b) => {
                        method = ScatterMethod::LaplaceAtModes;
                        (b, false)
                    }
                    None => (new, settled),
                }
            }
            ScatterMethod::LaplaceAtModes => {
                let new = minimise_scatter(&tau, at_modes);
                let settled = !(at_modes(&new) < at_modes(&tau) - SCATTER_TOL);
                (new, settled)
            }
        };
        let settled = settled || scatter_settled(&new, &tau);
        accepted = Some(Accepted {
            neg2ll: now,
            x: x.clone(),
            noise: noise.clone(),
            tau: tau.clone(),
            g,
        });
        tau = new;
        if settled {
            break;
        }
    }
    let mut fit = finish_hier(
        model, curves, space, &x, &layout, &tau, method, settings, opts,
    )
    .ok_or_else(|| {
        (
            "the fitted point could not be evaluated".to_string(),
            its,
            evs,
        )
    })?;
    fit.termination = termination;
    fit.iterations = its;
    fit.evaluations = evs;
    Ok(fit)
}

/// The initial damping of a hierarchical round from the relative damping `last` the previous
/// round ended with (NaN if it tried no step): `last`, but never above `fresh` (the
/// configured λ₀) nor below 1e-12, where the damping no longer matters.
pub fn carried_damping(last: f64, fresh: f64) -> f64 {
    if last.is_finite() && last > 0.0 {
        last.min(fresh).max(fresh.min(1e-12))
    } else {
        fresh
    }
}

/// The scatter's (ML, REML) estimates at a hierarchical fit's point from `tau` (the fit's
/// last scatter), by the criterion `method` names: the linear mixed model `lmm` of the
/// point's linearisation, or, where the fit found that model's steps not to pay, the Laplace
/// criterion at the modes `eta` (Gram blocks `g`), whose ML estimate is taken as `tau` (the
/// fit's own; for a warm start's report, the start's reported scatter, which
/// [`report_hier`] re-minimises for the likelihood anyway); and the method they came from.
fn scatter_estimates(
    lmm: &Lmm,
    eta: &[f64],
    g: &[crate::specimen::KMat],
    tau: &[f64],
    method: ScatterMethod,
    lmm_has_trend: bool,
) -> (Vec<f64>, Vec<f64>, ScatterMethod) {
    let at_modes = |t: &[f64], restricted: bool| {
        crate::specimen::laplace_criterion(lmm, eta, g, t, restricted)
    };
    let by_modes = |ml: Vec<f64>| {
        let reml = minimise_scatter(&ml, |t| at_modes(t, true));
        (ml, reml, ScatterMethod::LaplaceAtModes)
    };
    if lmm_has_trend {
        // Beyond the stress trend: the restricted likelihood's scatter, for −2 ln L too.
        let reml = lmm.estimate(tau, true);
        return (reml.clone(), reml, ScatterMethod::BeyondStressTrend);
    }
    match method {
        ScatterMethod::LinearMixedModel | ScatterMethod::BeyondStressTrend => {
            let ml = lmm.estimate(tau, false);
            // Where the linear model stays at the scatter the modes were fitted at, the
            // criterion at the modes must not fall elsewhere ([`hier_fit`]'s check; here for
            // a report taken at a start's optimum without rounds).
            if scatter_settled(&ml, tau) {
                let better = minimise_scatter(&ml, |t| at_modes(t, false));
                if at_modes(&better, false) < at_modes(&ml, false) - SCATTER_TOL {
                    return by_modes(better);
                }
            }
            let reml = lmm.estimate(&ml, true);
            (ml, reml, method)
        }
        ScatterMethod::LaplaceAtModes => by_modes(tau.to_vec()),
    }
}

/// The hierarchical fit's report at parameters `x` (free constants in the unit box, then the
/// effects): the error model re-estimated there, −2 ln L by the Laplace approximation at the
/// maximum-likelihood scatter, the scatter reported at its restricted-likelihood (REML)
/// estimate, the effects and their sds. A kind whose REML scatter is at [`SCATTER_FLOOR`] is
/// dropped (its effects set to zero: they are zero to within τ² there), and with none left
/// the report is the plain fit's at these constants.
///
/// Why two estimates: REML's scatter is the unbiased one for a handful of specimens (what
/// reports and intervals show), but its criterion depends on how many constants the model
/// has, so a likelihood taken at REML's scatter penalises a model for every constant it adds
/// (measured: nested extensions refitted from the base optimum ended 1.5–3 units of −2 ln L
/// above it on null sets of 4–6 specimens, a null distribution of likelihood ratios below
/// zero). The likelihood that ranks fits and gives the ratios is maximised over the scatter
/// as over the constants, as likelihood-ratio tests between models with different constants
/// require.
#[allow(clippy::too_many_arguments)]
fn finish_hier(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    x: &[f64],
    layout: &EffectLayout,
    tau: &[f64],
    method: ScatterMethod,
    settings: &FitSettings,
    opts: &MlOptions,
) -> Option<MlFit> {
    let nt = layout.n_theta;
    let n = layout.n_curves;
    let mut params = space.fixed.clone();
    space.from_unit(&x[..nt], &mut params);
    // The scatter at its estimate at x, under the error model re-estimated at x.
    let (rr, jac, noise) = whitened_at(model, curves, space, x, layout, tau, settings, opts)?;
    let lmm = layout.lmm(&jac, &rr, &x[nt..]);
    let (tau_ml, tau, method) = match opts.hold_scatter {
        Some(_) => (tau.to_vec(), tau.to_vec(), method),
        None => scatter_estimates(
            &lmm,
            &x[nt..],
            &layout.gram(&jac),
            tau,
            method,
            !layout.trend.is_empty(),
        ),
    };
    let keep: Vec<usize> = (0..tau.len())
        .filter(|&k| tau[k] > 1.01 * SCATTER_FLOOR)
        .collect();
    if keep.len() == tau.len() {
        return report_hier(
            model,
            curves,
            space,
            params,
            x,
            layout,
            tau,
            tau_ml,
            method,
            rr,
            jac,
            noise,
            vec![],
            settings,
            opts.hold_scatter.is_some(),
        );
    }
    // A kind at the floor is dropped only where that does not cost likelihood: with readings
    // precise enough, effects of a fraction of a percent still move the curves by several
    // reading-error sds, and setting them to zero cost a nested extension's warm fit 158
    // units of −2 ln L (tests/specimen.rs, `a_nested_warm_fit_never_ends_above_the_base_optimum`).
    let floored: Vec<f64> = tau.iter().map(|t| t.max(SCATTER_FLOOR)).collect();
    let floored_ml: Vec<f64> = tau_ml.iter().map(|t| t.max(SCATTER_FLOOR)).collect();
    let kept = report_hier(
        model,
        curves,
        space,
        params.clone(),
        x,
        layout,
        floored,
        floored_ml,
        method,
        rr,
        jac,
        noise,
        vec![],
        settings,
        opts.hold_scatter.is_some(),
    );
    let dropped: Vec<EffectKind> = (0..tau.len())
        .filter(|k| !keep.contains(k))
        .map(|k| layout.kinds[k].0)
        .collect();
    let reduced = if keep.is_empty() {
        let lm = crate::lsq::LmReport {
            x: x[..nt].to_vec(),
            objective: f64::NAN,
            residuals: vec![],
            iterations: 0,
            evaluations: 0,
            termination: Termination::ConvergedObjective,
            failure: None,
            lambda: f64::NAN,
        };
        let f = plain_report(model, curves, params, settings, opts, &lm);
        f.ok().then_some(f)
    } else {
        (|| {
            let l = layout.keeping(&keep);
            let mut xr = x[..nt].to_vec();
            for &k in &keep {
                xr.extend_from_slice(&x[nt + k * n..nt + (k + 1) * n]);
            }
            let t: Vec<f64> = keep.iter().map(|&k| tau[k]).collect();
            let (rr, jac, noise) = whitened_at(model, curves, space, &xr, &l, &t, settings, opts)?;
            let lmm = l.lmm(&jac, &rr, &xr[nt..]);
            let (t_ml, t, method) = match opts.hold_scatter {
                Some(_) => (t.clone(), t.clone(), method),
                None => scatter_estimates(
                    &lmm,
                    &xr[nt..],
                    &l.gram(&jac),
                    &t,
                    method,
                    !l.trend.is_empty(),
                ),
            };
            report_hier(
                model,
                curves,
                space,
                params.clone(),
                &xr,
                &l,
                t,
                t_ml,
                method,
                rr,
                jac,
                noise,
                dropped,
                settings,
                opts.hold_scatter.is_some(),
            )
        })()
    };
    match (kept, reduced) {
        (Some(a), Some(b)) => Some(if b.neg2ll <= a.neg2ll { b } else { a }),
        (a, b) => b.or(a),
    }
}

/// The report of [`finish_hier`] for `layout`'s kinds at `x`, the scatter `tau` (REML, as
/// reported) and `tau_ml` (the likelihood's, refined here), `rr`, `jac` and `noise` whitened
/// there; `dropped` is listed as dropped.
#[allow(clippy::too_many_arguments)]
fn report_hier(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    params: Vec<f64>,
    x: &[f64],
    layout: &EffectLayout,
    tau: Vec<f64>,
    tau_ml: Vec<f64>,
    method: ScatterMethod,
    rr: Vec<f64>,
    jac: DMatrix<f64>,
    noise: ErrorModel,
    dropped: Vec<EffectKind>,
    settings: &FitSettings,
    held: bool,
) -> Option<MlFit> {
    let n = layout.n_curves;
    let nt = layout.n_theta;
    let eta = &x[nt..];
    let fixed = LikelihoodProblem::fixed(
        CreepProblem {
            objective: raw_objective(model, curves, settings),
            space: space.clone(),
            jacobian: settings.jacobian,
        },
        noise.clone(),
    )
    .with_effects(layout.clone(), tau_ml.clone(), true);
    let g = exact_blocks(&fixed, layout, x, &rr, &jac);
    // The likelihood's scatter: the minimiser of the Laplace −2 ln L at the fit (its data
    // term does not depend on τ). Not the linear mixed model's ML estimate, which assumes the
    // constants move with it: a constant collinear with the effects (a ductility that
    // varies with stress beside specimens' ductility) would take their spread there, and
    // the likelihood at the constants as they are would fall.
    // (Held, or estimated beyond the stress trend: −2 ln L at that scatter.)
    let tau_ml = if held || !layout.trend.is_empty() {
        tau_ml
    } else {
        crate::specimen::minimise_scatter(&tau_ml, |t| laplace_terms(eta, &g, t))
    };
    let terms = laplace_terms(eta, &g, &tau_ml);
    let factors = layout.factors(eta);
    let obj = raw_objective(model, curves, settings).with_factors(Some(factors));
    let mut r = vec![0.0; obj.n_residuals()];
    obj.residuals(&params, &mut r).ok()?;
    let res = split_residuals(curves, &r);
    let neg2ll = noise.neg2ll(&res) + terms;
    let k = layout.kinds.len();
    let mut effects = vec![vec![0.0; n]; k];
    let mut effects_sd = vec![vec![0.0; n]; k];
    for i in 0..n {
        // Posterior covariance (G_i + D⁻¹)⁻¹, D at the likelihood's scatter.
        let h = DMatrix::from_fn(k, k, |a, b| {
            g[i][a][b]
                + if a == b {
                    1.0 / (tau_ml[a] * tau_ml[a])
                } else {
                    0.0
                }
        });
        let cov = h.try_inverse().unwrap_or_else(|| DMatrix::zeros(k, k));
        for a in 0..k {
            effects[a][i] = eta[a * n + i];
            effects_sd[a][i] = cov[(a, a)].max(0.0).sqrt();
        }
    }
    let eval = obj.evaluate(&params);
    Some(MlFit {
        params,
        noise,
        neg2ll,
        residuals: Some(res),
        eval: Some(eval),
        specimen: Some(SpecimenFit {
            kinds: layout.kinds.iter().map(|k| k.0).collect(),
            scatter_lo95: vec![f64::NAN; tau.len()],
            scatter_hi95: vec![f64::NAN; tau.len()],
            scatter_dof: vec![f64::NAN; tau.len()],
            scatter: tau,
            effects,
            effects_sd,
            neg2ll_effects: terms,
            scatter_method: method,
            dropped,
        }),
        termination: Termination::ConvergedObjective,
        iterations: 0,
        evaluations: 0,
        failure: None,
    })
}

/// The 95 % profile intervals of the scatter of `fit` (filled into its
/// [`SpecimenFit::scatter_lo95`] and [`SpecimenFit::scatter_hi95`]), from the restricted
/// likelihood of the linear mixed model at the fit ([`crate::specimen::Lmm::interval`]), or
/// of the Laplace criterion at the modes where the estimate came from that
/// ([`SpecimenFit::scatter_method`]); the cutoffs calibrated to each kind's degrees of
/// freedom ([`Cutoffs::small_sample`]), as a few specimens give.
/// Kept out of every fit because the bootstrap's refits do not need it. No-op without
/// specimen effects or when the fit cannot be evaluated again.
pub fn scatter_intervals(
    fit: &mut MlFit,
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    settings: &FitSettings,
    opts: &MlOptions,
) {
    let Some(sp) = fit.specimen.as_mut() else {
        return;
    };
    let kinds: Vec<EffectKind> = sp.kinds.clone();
    let (Some(layout), _) = EffectLayout::new(model, curves, space, &kinds) else {
        return;
    };
    let layout = if sp.scatter_method == ScatterMethod::BeyondStressTrend {
        layout.with_trend(curves)
    } else {
        layout
    };
    let mut x = space.to_unit(&fit.params);
    for e in &sp.effects {
        x.extend_from_slice(e);
    }
    let Some((rr, jac, _)) = whitened_at(
        model,
        curves,
        space,
        &x,
        &layout,
        &sp.scatter,
        settings,
        opts,
    ) else {
        return;
    };
    let nt = layout.n_theta;
    let lmm = layout.lmm(&jac, &rr, &x[nt..]);
    let g = layout.gram(&jac);
    for k in 0..kinds.len() {
        // Calibrated to the effects' degrees of freedom beyond the constants (and the trend
        // directions, which are fixed effects of `lmm`).
        let dof = lmm.effect_dof(k, sp.scatter[k]);
        sp.scatter_dof[k] = dof;
        let cut = Cutoffs::small_sample(dof, 0.95);
        // Under the criterion the estimate came from.
        let (lo, hi) = match sp.scatter_method {
            ScatterMethod::LinearMixedModel | ScatterMethod::BeyondStressTrend => {
                lmm.interval(k, &sp.scatter, cut, true)
            }
            // The upper end from the criterion at the modes (the linear model's promise of
            // gains from larger effects is what failed); the lower end from the linear model,
            // which turns exact as the effects shrink to zero, while the criterion at held
            // modes cannot let them shrink (its penalty η̂²/τ² grows without bound).
            ScatterMethod::LaplaceAtModes => {
                let (_, hi) = crate::specimen::profile_interval(k, &sp.scatter, cut, |t| {
                    crate::specimen::laplace_criterion(&lmm, &x[nt..], &g, t, true)
                });
                let (lo, _) = lmm.interval(k, &sp.scatter, cut, true);
                (lo.min(sp.scatter[k]), hi)
            }
        };
        sp.scatter_lo95[k] = lo;
        sp.scatter_hi95[k] = hi;
    }
}

/// −2 ln L at fixed constants `theta` (physical), error model `noise` and scatter `tau` (one
/// per kind of `layout`), the effects integrated out by the Laplace approximation: the
/// conditional modes η̂ found by penalised least squares with the constants held, then
/// −2 ln p(y | θ, η̂) + Σ_i [η̂_iᵀD⁻¹η̂_i + ln det(I + D G_i)]. Returns (−2 ln L, η̂
/// kind-major), `None` if the data cannot be evaluated. What a fit's −2 ln L is at its
/// optimum, here as a function of the constants (for tests against a brute-force integral
/// and for profiles).
#[allow(clippy::too_many_arguments)]
pub fn laplace_at(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    theta: &[f64],
    layout: &EffectLayout,
    tau: &[f64],
    noise: &ErrorModel,
    settings: &FitSettings,
) -> Option<(f64, Vec<f64>)> {
    let nt = layout.n_theta;
    let ne = layout.n_effects();
    let u = space.to_unit(theta);
    let mut lo = u.clone();
    let mut hi = u.clone();
    lo.extend(std::iter::repeat_n(-EFFECT_MAX, ne));
    hi.extend(std::iter::repeat_n(EFFECT_MAX, ne));
    let mut x0 = u;
    x0.extend(std::iter::repeat_n(0.0, ne));
    let problem = LikelihoodProblem::fixed(
        CreepProblem {
            objective: raw_objective(model, curves, settings),
            space: space.clone(),
            jacobian: settings.jacobian,
        },
        noise.clone(),
    )
    .with_effects(layout.clone(), tau.to_vec(), true);
    let lm = minimize(&problem, &x0, &lo, &hi, &settings.lm);
    if lm.termination == Termination::SimulationFailure {
        return None;
    }
    let m = problem.n_residuals();
    let mut rr = vec![0.0; m];
    let mut jac = DMatrix::<f64>::zeros(m, problem.n_params());
    problem
        .residuals_and_jacobian(&lm.x, &mut rr, &mut jac)?
        .ok()?;
    let eta = lm.x[nt..].to_vec();
    let g = exact_blocks(&problem, layout, &lm.x, &rr, &jac);
    let mut params = space.fixed.clone();
    space.from_unit(&lm.x[..nt], &mut params);
    let obj = raw_objective(model, curves, settings).with_factors(Some(layout.factors(&eta)));
    let mut r = vec![0.0; obj.n_residuals()];
    obj.residuals(&params, &mut r).ok()?;
    let res = split_residuals(curves, &r);
    Some((noise.neg2ll(&res) + laplace_terms(&eta, &g, tau), eta))
}

/// Per curve, the Hessian of ½‖r‖² in its own effects at `x`: G_i = J_iᵀJ_i plus the
/// residuals' curvature Σ r ∂²r/∂η∂η (the Gauss–Newton Hessian alone leaves the Laplace
/// approximation off by a few hundredths of −2 ln L however many points a curve has, measured
/// against a brute-force integral: the curvature term grows like √n, G like n, and
/// ln det carries their ratio). The curvature by a forward difference of the Jacobian in
/// each kind of effect (all curves at once: a curve's residuals depend on its own effects
/// only). Falls back to G where the sum is not positive definite.
fn exact_blocks(
    problem: &LikelihoodProblem,
    layout: &EffectLayout,
    x: &[f64],
    rr: &[f64],
    jac: &DMatrix<f64>,
) -> Vec<crate::specimen::KMat> {
    let g = layout.gram(jac);
    let (nt, n, k) = (layout.n_theta, layout.n_curves, layout.kinds.len());
    const H: f64 = 1e-5;
    let mut curv = vec![[[0.0; crate::specimen::MAX_KINDS]; crate::specimen::MAX_KINDS]; n];
    for l in 0..k {
        let mut xp = x.to_vec();
        for i in 0..n {
            xp[nt + l * n + i] += H;
        }
        let m = problem.n_residuals();
        let mut rp = vec![0.0; m];
        let mut jp = DMatrix::<f64>::zeros(m, problem.n_params());
        match problem.residuals_and_jacobian(&xp, &mut rp, &mut jp) {
            Some(Ok(())) => {}
            _ => return g,
        }
        for i in 0..n {
            let (a, b) = layout.rows[i];
            for kk in 0..k {
                let c = nt + kk * n + i;
                curv[i][kk][l] = (a..b)
                    .map(|row| rr[row] * (jp[(row, c)] - jac[(row, c)]) / H)
                    .sum();
            }
        }
    }
    g.iter()
        .zip(&curv)
        .map(|(gi, ci)| {
            let mut h = [[0.0; crate::specimen::MAX_KINDS]; crate::specimen::MAX_KINDS];
            for a in 0..k {
                for b in 0..k {
                    h[a][b] = gi[a][b] + 0.5 * (ci[a][b] + ci[b][a]);
                }
            }
            if crate::specimen::small_pd(k, &h) {
                h
            } else {
                *gi
            }
        })
        .collect()
}

/// The information of the free constants (unit box of `space`) at constants `params` with the
/// specimens' effects `sp` integrated out: with J the whitened Jacobian of the constants (θ)
/// and effects (η), penalty rows η/τ included, the Schur complement I_θθ − I_θη I_ηη⁻¹ I_ηθ
/// of JᵀJ (the Laplace marginal's curvature in θ once every effect has followed). `None`
/// where a kind of `sp` cannot act in `space`, or it cannot be evaluated. The constants an
/// effect can compensate (the rate constant against every specimen's rate factor) carry the
/// scatter's uncertainty here, which a plain fit's JᵀJ leaves out.
pub fn marginal_information(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    params: &[f64],
    sp: &SpecimenFit,
    settings: &FitSettings,
    opts: &MlOptions,
) -> Option<DMatrix<f64>> {
    let (layout, dropped) = EffectLayout::new(model, curves, space, &sp.kinds);
    let layout = layout?;
    if !dropped.is_empty() {
        return None;
    }
    let mut x = space.to_unit(params);
    let mut tau = Vec::with_capacity(layout.kinds.len());
    for &(kind, _, _) in &layout.kinds {
        let k = sp.kinds.iter().position(|q| *q == kind)?;
        x.extend_from_slice(&sp.effects[k]);
        tau.push(sp.scatter[k].max(SCATTER_FLOOR));
    }
    let (_, jac, _) = whitened_at(model, curves, space, &x, &layout, &tau, settings, opts)?;
    let nt = layout.n_theta;
    let jtj = crate::lsq::gram(&jac);
    let n = jtj.nrows();
    let a = jtj.view((0, 0), (nt, nt)).into_owned();
    let b = jtj.view((0, nt), (nt, n - nt)).into_owned();
    let d = jtj.view((nt, nt), (n - nt, n - nt)).into_owned();
    let dinv = d.try_inverse()?;
    let i = a - &b * dinv * b.transpose();
    let i = (&i + i.transpose()) * 0.5;
    i.iter().all(|v| v.is_finite()).then_some(i)
}

/// The Jacobian of `fit`'s residuals in its parameters (free constants in the unit box of
/// `space`, then its specimen effects), as [`RestrictedDesign`] wants it for the growth of the
/// reading error: each curve's strain rows raw (strain as a fraction), the rupture-time and
/// penalty rows whitened under the fit's error model. `None` where the fit kept no residuals,
/// a kind of its effects cannot act in `space`, or the Jacobian cannot be evaluated.
pub fn restricted_design(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    fit: &MlFit,
    settings: &FitSettings,
) -> Option<RestrictedDesign> {
    fit.residuals.as_ref()?;
    if fit.noise.strain.len() != curves.len() || fit.params.len() != space.len() {
        return None;
    }
    let inner = CreepProblem {
        objective: raw_objective(model, curves, settings),
        space: space.clone(),
        jacobian: settings.jacobian,
    };
    let mut x = space.to_unit(&fit.params);
    let mut problem = LikelihoodProblem::fixed(inner, fit.noise.clone());
    let mut layout = None;
    if let Some(sp) = &fit.specimen {
        let (l, dropped) = EffectLayout::new(model, curves, space, &sp.kinds);
        let l = l?;
        if !dropped.is_empty() {
            return None;
        }
        let mut tau = Vec::with_capacity(l.kinds.len());
        for &(kind, _, _) in &l.kinds {
            let k = sp.kinds.iter().position(|q| *q == kind)?;
            x.extend_from_slice(&sp.effects[k]);
            tau.push(sp.scatter[k].max(SCATTER_FLOOR));
        }
        problem = problem.with_effects(l.clone(), tau, true);
        layout = Some(l);
    }
    let m = problem.n_residuals();
    let q = problem.n_params();
    let mut rr = vec![0.0; m];
    let mut jac = DMatrix::<f64>::zeros(m, q);
    problem
        .residuals_and_jacobian(&x, &mut rr, &mut jac)?
        .ok()?;
    if jac.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let nt = space.n_free();
    let mut fixed = DMatrix::<f64>::zeros(q, q);
    let mut add_row = |row: usize| {
        for a in 0..q {
            let ja = jac[(row, a)];
            if ja == 0.0 {
                continue;
            }
            for b in 0..q {
                fixed[(a, b)] += ja * jac[(row, b)];
            }
        }
    };
    let mut blocks = Vec::with_capacity(curves.len());
    let mut off = 0;
    for (i, c) in curves.iter().enumerate() {
        let n = c.times_h.len();
        let mut cols: Vec<usize> = (0..nt).collect();
        if let Some(l) = &layout {
            cols.extend((0..l.kinds.len()).map(|k| nt + k * l.n_curves + i));
        }
        let mut block = DMatrix::<f64>::zeros(n, cols.len());
        for (a, &col) in cols.iter().enumerate() {
            let mut v: Vec<f64> = (0..n).map(|j| jac[(off + j, col)]).collect();
            fit.noise.strain[i].unwhiten_strided(&mut v, n, 1);
            block.column_mut(a).copy_from_slice(&v);
        }
        blocks.push((block, cols));
        add_row(off + n);
        off += n + 1;
    }
    for row in off..m {
        add_row(row);
    }
    Some(RestrictedDesign {
        curves: blocks,
        fixed,
    })
}

/// The whitened residuals and Jacobian of the hierarchical problem at `x` under the error
/// model re-estimated from the raw residuals there, and that error model.
#[allow(clippy::too_many_arguments)]
fn whitened_at(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    x: &[f64],
    layout: &EffectLayout,
    tau: &[f64],
    settings: &FitSettings,
    opts: &MlOptions,
) -> Option<(Vec<f64>, DMatrix<f64>, ErrorModel)> {
    let nt = layout.n_theta;
    let mut params = space.fixed.clone();
    space.from_unit(&x[..nt], &mut params);
    let obj = raw_objective(model, curves, settings).with_factors(Some(layout.factors(&x[nt..])));
    let mut r = vec![0.0; obj.n_residuals()];
    obj.residuals(&params, &mut r).ok()?;
    let noise = ErrorModel::estimate(&split_residuals(curves, &r), opts.lifetime_sd_floor);
    let p = LikelihoodProblem::fixed(
        CreepProblem {
            objective: raw_objective(model, curves, settings),
            space: space.clone(),
            jacobian: settings.jacobian,
        },
        noise.clone(),
    )
    .with_effects(layout.clone(), tau.to_vec(), true);
    let m = p.n_residuals();
    let mut rr = vec![0.0; m];
    let mut jac = DMatrix::<f64>::zeros(m, p.n_params());
    p.residuals_and_jacobian(x, &mut rr, &mut jac)?.ok()?;
    Some((rr, jac, noise))
}

/// The smallest sum of squared whitened residuals of `model` on `curves` under the known error
/// model `noise` (no profiling; each reading's error multiplied by `scale`, if given,
/// [`LikelihoodProblem::with_reading_scale`]; each curve's constants multiplied by its
/// `factors`, if given: known specimen effects), over fits from `starts`: the noncentrality
/// of a likelihood-ratio test that knows the error model. Returns (minimum, its constants);
/// `None` if every start failed.
#[allow(clippy::too_many_arguments)]
pub fn min_whitened_ss(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    starts: &[Vec<f64>],
    settings: &FitSettings,
    noise: &ErrorModel,
    scale: Option<&[Vec<f64>]>,
    factors: Option<&CurveFactors>,
) -> Option<(f64, Vec<f64>)> {
    let mut best: Option<(f64, Vec<f64>)> = None;
    for s in starts {
        let problem = LikelihoodProblem::fixed(
            CreepProblem {
                objective: raw_objective(model, curves, settings).with_factors(factors.cloned()),
                space: space.clone(),
                jacobian: settings.jacobian,
            },
            noise.clone(),
        )
        .with_reading_scale(scale.map(<[Vec<f64>]>::to_vec));
        let u0 = space.to_unit(s);
        let k = u0.len();
        let lm = minimize(&problem, &u0, &vec![0.0; k], &vec![1.0; k], &settings.lm);
        if lm.termination == Termination::SimulationFailure || !lm.objective.is_finite() {
            continue;
        }
        if best.as_ref().is_none_or(|b| lm.objective < b.0) {
            let mut x = s.clone();
            space.from_unit(&lm.x, &mut x);
            best = Some((lm.objective, x));
        }
    }
    best
}

/// The smallest penalised sum of squares Σ r²/σ² + Σ η²/τ² of `model` on `curves` at the
/// known error model `noise` (each reading's error multiplied by `scale`, if given) and the
/// known scatter τ > 0 of each kind in `kinds` (the effects
/// free, kind-major, started at `eta0`), over fits from `starts`: on noise-free
/// data, the "expected data" noncentrality of a likelihood-ratio test between two
/// hierarchical models is the difference of two such minima (the specimens' factors unknown,
/// as in every laboratory; [`min_whitened_ss`] knows them). Kinds whose constant the model
/// lacks or `space` holds are left out with their scatter. Returns (minimum, constants,
/// effects); `None` if every start failed. [`min_penalised`] with the error model profiled
/// instead is what a fit that must estimate it reaches.
#[allow(clippy::too_many_arguments)]
pub fn min_penalised_ss(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    starts: &[Vec<f64>],
    settings: &FitSettings,
    noise: &ErrorModel,
    scale: Option<&[Vec<f64>]>,
    kinds: &[(EffectKind, f64)],
    eta0: &[f64],
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    min_penalised(
        model, curves, space, starts, settings, noise, scale, kinds, eta0, None,
    )
}

/// [`min_penalised_ss`], or with `profile = Some(floor)` the error model re-estimated with
/// the constants (AR(1) per curve and the rupture-time scatter above `floor`, started at
/// `noise`, as every likelihood fit profiles it; the scatter still held): then the minimum
/// is the penalised −2 ln L, Σ r²/σ² + Σ η²/τ² plus the error model's normalising term
/// (with `scale`, the AR(1) is that of the residual over w and 2 Σ ln w is left out).
#[allow(clippy::too_many_arguments)]
pub fn min_penalised(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    starts: &[Vec<f64>],
    settings: &FitSettings,
    noise: &ErrorModel,
    scale: Option<&[Vec<f64>]>,
    kinds: &[(EffectKind, f64)],
    eta0: &[f64],
    profile: Option<f64>,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let wanted: Vec<EffectKind> = kinds.iter().map(|k| k.0).collect();
    let (layout, _) = EffectLayout::new(model, curves, space, &wanted);
    let n = curves.len();
    let (tau, eta_start): (Vec<f64>, Vec<f64>) = match &layout {
        Some(l) => {
            let mut tau = vec![];
            let mut eta = vec![];
            for (kind, _, _) in &l.kinds {
                let k = wanted
                    .iter()
                    .position(|w| w == kind)
                    .expect("a wanted kind");
                tau.push(kinds[k].1);
                eta.extend_from_slice(&eta0[k * n..(k + 1) * n]);
            }
            (tau, eta)
        }
        None => (vec![], vec![]),
    };
    let mut best: Option<(f64, Vec<f64>, Vec<f64>)> = None;
    for s in starts {
        let inner = CreepProblem {
            objective: raw_objective(model, curves, settings),
            space: space.clone(),
            jacobian: settings.jacobian,
        };
        let problem = match profile {
            Some(floor) => LikelihoodProblem::new(inner, noise.clone(), floor),
            None => LikelihoodProblem::fixed(inner, noise.clone()),
        }
        .with_reading_scale(scale.map(<[Vec<f64>]>::to_vec));
        let problem = match &layout {
            Some(l) => problem.with_effects(l.clone(), tau.clone(), true),
            None => problem,
        };
        let mut u0 = space.to_unit(s);
        let nt = u0.len();
        u0.extend_from_slice(&eta_start);
        let k = u0.len();
        let mut lo = vec![0.0; k];
        let mut hi = vec![1.0; k];
        for j in nt..k {
            lo[j] = -EFFECT_MAX;
            hi[j] = EFFECT_MAX;
        }
        let lm = minimize(&problem, &u0, &lo, &hi, &settings.lm);
        if lm.termination == Termination::SimulationFailure || !lm.objective.is_finite() {
            continue;
        }
        let value = if profile.is_some() {
            lm.objective + problem.objective_offset()
        } else {
            lm.objective
        };
        if best.as_ref().is_none_or(|b| value < b.0) {
            let mut x = s.clone();
            space.from_unit(&lm.x[..nt], &mut x);
            best = Some((value, x, lm.x[nt..].to_vec()));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_round_picks_up_the_damping_the_last_one_ended_with() {
        use super::carried_damping;
        // (last, fresh) → initial damping of the next round.
        let table = [
            (1e-5, 1e-3, 1e-5),     // carried
            (0.5, 1e-3, 1e-3),      // never above the configured λ₀
            (1e-20, 1e-3, 1e-12),   // nor below 1e-12
            (1e-20, 1e-14, 1e-14),  // unless λ₀ itself is smaller
            (f64::NAN, 1e-3, 1e-3), // no step tried: fresh
            (0.0, 1e-3, 1e-3),
            (f64::INFINITY, 1e-3, 1e-3),
        ];
        for (last, fresh, want) in table {
            assert_eq!(carried_damping(last, fresh), want, "{last} {fresh}");
        }
    }

    #[test]
    fn a_scatter_has_settled_when_every_kind_moved_less_than_one_percent() {
        use super::scatter_settled;
        let table: [(&[f64], &[f64], bool); 5] = [
            (&[0.2], &[0.2019], true),
            (&[0.2], &[0.2021], false),
            (&[0.2021], &[0.2], false),
            (&[0.2, 0.05], &[0.2019, 0.0504], true),
            (&[0.2, 0.05], &[0.2, 0.051], false),
        ];
        for (a, b, want) in table {
            assert_eq!(scatter_settled(a, b), want, "{a:?} {b:?}");
        }
    }

    /// A ruptured two-point curve at `t` °C and `s` MPa: what the factor summaries read of a
    /// curve (its temperature, stress and specimen).
    /// The stress-trend weights: one group per temperature with two stresses or more, each
    /// centred and of unit norm, so that effects a + b ln σ give Σ w η = b‖x − x̄‖ and
    /// effects without a trend 0.
    #[test]
    fn stress_trend_weights_are_the_within_temperature_regression() {
        let curves = vec![
            crate::data::Curve::two_point(850.0, 30.0, None),
            crate::data::Curve::two_point(850.0, 43.0, None),
            crate::data::Curve::two_point(850.0, 43.0, None),
            crate::data::Curve::two_point(900.0, 20.0, None),
            crate::data::Curve::two_point(950.0, 15.0, None),
            crate::data::Curve::two_point(950.0, 25.0, None),
        ];
        let w = stress_trend_weights(&curves);
        // 900 °C has one curve: no group.
        assert_eq!(w.len(), 2);
        assert_eq!(
            w[0].iter().map(|(i, _)| *i).collect::<Vec<_>>(),
            vec![0, 1, 2]
        );
        assert_eq!(w[1].iter().map(|(i, _)| *i).collect::<Vec<_>>(), vec![4, 5]);
        for g in &w {
            let sum: f64 = g.iter().map(|(_, v)| v).sum();
            let norm: f64 = g.iter().map(|(_, v)| v * v).sum();
            assert!(sum.abs() < 1e-12 && (norm - 1.0).abs() < 1e-12, "{g:?}");
        }
        let x: Vec<f64> = [30.0f64, 43.0, 43.0].iter().map(|s| s.ln()).collect();
        let xm = x.iter().sum::<f64>() / 3.0;
        let spread = x.iter().map(|v| (v - xm).powi(2)).sum::<f64>().sqrt();
        let (a, b) = (0.4, -1.7);
        let dot: f64 = w[0].iter().map(|(i, wi)| wi * (a + b * x[*i])).sum();
        assert!((dot - b * spread).abs() < 1e-12, "{dot}");
    }

    /// The scatter beyond the trend against the closed form of a balanced one-way
    /// random-effects model: 8 specimens at two temperatures, 40 whitened readings each
    /// (unit variance), an intercept as the constant, each specimen's effect a strong trend
    /// with ln σ, a level that differs between the temperatures, plus its own part u_i. The
    /// restricted likelihood of the curve means with q fixed columns gives
    /// τ̂² = RSS/(n − q) − 1/m: with the trends and the level contrast as fixed effects
    /// (q = 4) the scatter is that of u alone; with the stress trends alone (q = 3) the
    /// level is counted as scatter, and without any (q = 1) the trends are too.
    #[test]
    fn the_scatter_beyond_the_trend_is_the_restricted_anova_estimate() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let stresses = [(850.0, 30.0), (850.0, 35.0), (850.0, 40.0), (850.0, 45.0)]
            .into_iter()
            .chain([(900.0, 20.0), (900.0, 24.0), (900.0, 28.0), (900.0, 32.0)]);
        let curves: Vec<Curve> = stresses
            .map(|(t, s)| crate::data::Curve::two_point(t, s, None))
            .collect();
        let (n, m) = (curves.len(), 40usize);
        let u = [0.30, -0.20, 0.10, -0.25, -0.10, 0.25, -0.30, 0.20];
        let slope = |t: f64| if t < 875.0 { 4.0 } else { -3.0 };
        let level = |t: f64| if t < 875.0 { 0.0 } else { 1.0 };
        let groups = stress_trend_weights(&curves);
        let levels = temperature_level_weights(&curves);
        assert_eq!(levels.len(), 1);
        let mut eta = vec![0.0; n];
        for g in &groups {
            let x: Vec<f64> = g.iter().map(|(i, _)| curves[*i].stress_mpa.ln()).collect();
            let xm = x.iter().sum::<f64>() / x.len() as f64;
            for ((i, _), xi) in g.iter().zip(&x) {
                let t = curves[*i].temperature_c;
                eta[*i] = slope(t) * (xi - xm) + level(t) + u[*i];
            }
        }
        // Jacobian: the intercept, then one effect column per curve; residuals r = −y at
        // zero effects, y = Zη + e.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(58);
        let mut jac = DMatrix::<f64>::zeros(n * m, 1 + n);
        let mut r = vec![0.0; n * m];
        let mut means = vec![0.0; n];
        for i in 0..n {
            for row in i * m..(i + 1) * m {
                jac[(row, 0)] = 1.0;
                jac[(row, 1 + i)] = 1.0;
                let e: f64 = StandardNormal.sample(&mut rng);
                r[row] = -(eta[i] + e);
                means[i] += (eta[i] + e) / m as f64;
            }
        }
        let layout = EffectLayout {
            kinds: vec![(EffectKind::Rate, 0, 0)],
            trend: Vec::new(),
            n_curves: n,
            n_theta: 1,
            m_data: n * m,
            rows: (0..n).map(|i| (i * m, (i + 1) * m)).collect(),
        };
        // The closed form: least squares of the curve means on the fixed columns.
        let closed = |cols: &[Vec<f64>]| -> f64 {
            let q = cols.len();
            let x = DMatrix::from_fn(n, q, |i, c| cols[c][i]);
            let y = nalgebra::DVector::from_column_slice(&means);
            let beta = (x.transpose() * &x).try_inverse().expect("full rank") * x.transpose() * &y;
            let rss = (&y - &x * beta).norm_squared();
            (rss / (n - q) as f64 - 1.0 / m as f64).max(0.0).sqrt()
        };
        let column = |g: &Vec<(usize, f64)>| {
            let mut c = vec![0.0; n];
            for (i, w) in g {
                c[*i] = *w;
            }
            c
        };
        let zero = vec![0.0; n];
        let plain = layout.lmm(&jac, &r, &zero).estimate(&[0.1], true)[0];
        let beyond = layout
            .clone()
            .with_trend(&curves)
            .lmm(&jac, &r, &zero)
            .estimate(&[0.1], true)[0];
        let stress_only = EffectLayout {
            trend: groups.iter().map(|w| (0, w.clone())).collect(),
            ..layout.clone()
        }
        .lmm(&jac, &r, &zero)
        .estimate(&[0.1], true)[0];
        let ones = vec![1.0; n];
        let want_plain = closed(std::slice::from_ref(&ones));
        let mut cols = vec![ones];
        cols.extend(groups.iter().map(column));
        let want_stress_only = closed(&cols);
        cols.extend(levels.iter().map(column));
        let want_beyond = closed(&cols);
        for (got, want) in [
            (plain, want_plain),
            (stress_only, want_stress_only),
            (beyond, want_beyond),
        ] {
            assert!((got / want - 1.0).abs() < 0.01, "{got} {want}");
        }
        // The trend is ~1 in ln factor across each temperature's stresses and the level 1
        // between them; u's sd is 0.25.
        assert!(plain > 2.0 * beyond, "{plain} {beyond}");
        assert!(stress_only > 1.5 * beyond, "{stress_only} {beyond}");
        let u_sd = (u.iter().map(|v| v * v).sum::<f64>() / (n - 4) as f64).sqrt();
        assert!((beyond - u_sd).abs() < 0.1, "{beyond} {u_sd}");
    }

    /// A level contrast the constants already carry (an intercept and a temperature law
    /// spanning both temperatures' levels, as A and its activation energy do) changes
    /// nothing: the fixed columns' span is the same, and the scatter with the contrast is the
    /// one without it.
    #[test]
    fn a_level_contrast_the_constants_span_leaves_the_scatter_alone() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let conds = [(850.0, 30.0), (850.0, 35.0), (850.0, 40.0)]
            .into_iter()
            .chain([(900.0, 20.0), (900.0, 24.0), (900.0, 28.0), (900.0, 32.0)]);
        let curves: Vec<Curve> = conds
            .map(|(t, s)| crate::data::Curve::two_point(t, s, None))
            .collect();
        let (n, m) = (curves.len(), 30usize);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(71);
        let eta: Vec<f64> = (0..n)
            .map(|i| {
                let z: f64 = StandardNormal.sample(&mut rng);
                0.2 * z
                    + if curves[i].temperature_c > 875.0 {
                        0.7
                    } else {
                        0.0
                    }
            })
            .collect();
        let mut jac = DMatrix::<f64>::zeros(n * m, 2 + n);
        let mut r = vec![0.0; n * m];
        for i in 0..n {
            for row in i * m..(i + 1) * m {
                jac[(row, 0)] = 1.0;
                // An Arrhenius-like column: the level at the second temperature.
                jac[(row, 1)] = if curves[i].temperature_c > 875.0 {
                    -0.3
                } else {
                    0.2
                };
                jac[(row, 2 + i)] = 1.0;
                let e: f64 = StandardNormal.sample(&mut rng);
                r[row] = -(eta[i] + e);
            }
        }
        let layout = EffectLayout {
            kinds: vec![(EffectKind::Rate, 0, 0)],
            trend: stress_trend_weights(&curves)
                .into_iter()
                .map(|w| (0, w))
                .collect(),
            n_curves: n,
            n_theta: 2,
            m_data: n * m,
            rows: (0..n).map(|i| (i * m, (i + 1) * m)).collect(),
        };
        let zero = vec![0.0; n];
        let without = layout.lmm(&jac, &r, &zero).estimate(&[0.1], true)[0];
        let lmm = layout.clone().with_trend(&curves).lmm(&jac, &r, &zero);
        // The contrast is left out of the fixed effects: the constants carry it.
        assert_eq!(lmm.p, 2 + 2);
        let with = lmm.estimate(&[0.1], true)[0];
        assert!(without > 0.05, "{without}");
        assert!((with / without - 1.0).abs() < 1e-3, "{with} {without}");
    }

    /// The F-test of equal temperature levels with a pooled stress slope: on null data
    /// (one level, a slope, normal scatter; stresses that differ between the groups) over
    /// 4,000 sets its rejections at 5 % and 1 % are within binomial limits of those rates
    /// (the statistic's null law is exact); with the same stresses in every group it is the
    /// one-way analysis of variance's F with the slope taken out of the residual (closed
    /// form), and levels 1.5 sd apart are rejected as often as the noncentral F says.
    #[test]
    fn temperature_levels_f_test_holds_its_level_and_sees_a_level() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let group = [0usize, 0, 0, 1, 1, 1, 1, 2, 2];
        let x = [4.4, 4.6, 4.7, 4.2, 4.3, 4.5, 4.6, 3.9, 4.1];
        let balanced = [0usize, 0, 0, 1, 1, 1, 2, 2, 2];
        let xb = [4.2, 4.4, 4.6, 4.2, 4.4, 4.6, 4.2, 4.4, 4.6];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2026_1204);
        let (mut r05, mut r01, mut power) = (0, 0, 0);
        let sets = 4000;
        for _ in 0..sets {
            let e: Vec<f64> = (0..9).map(|_| StandardNormal.sample(&mut rng)).collect();
            let y: Vec<f64> = (0..9).map(|i| 0.3 - 2.0 * x[i] + e[i]).collect();
            let (f, d1, d2) = between_group_f(&x, &y, &group);
            assert_eq!((d1, d2), (2, 5));
            let p = f_upper(f, d1, d2);
            r05 += usize::from(p < 0.05);
            r01 += usize::from(p < 0.01);
            let shifted: Vec<f64> = (0..9)
                .map(|i| 0.3 - 2.0 * xb[i] + 1.5 * balanced[i] as f64 + e[i])
                .collect();
            let (f, d1, d2) = between_group_f(&xb, &shifted, &balanced);
            power += usize::from(f_upper(f, d1, d2) < 0.05);
        }
        // Binomial 99.9 % limits: 5 % of 4,000 is 200 ± 45, 1 % is 40 ± 21.
        assert!((155..=245).contains(&r05), "{r05}");
        assert!((19..=61).contains(&r01), "{r01}");
        // The power is the noncentral F's (2, 5) tail beyond the 5 % critical value, with
        // λ = Σ n_g (μ_g − μ̄)² = 3·(1.5² + 0 + 1.5²): a Poisson mixture of beta tails.
        let crit = {
            use statrs::distribution::{ContinuousCDF, FisherSnedecor};
            FisherSnedecor::new(2.0, 5.0).unwrap().inverse_cdf(0.95)
        };
        let (lam, xq) = (13.5f64, 2.0 * crit / (2.0 * crit + 5.0));
        let mut term = (-lam / 2.0).exp();
        let mut exact = 0.0;
        for j in 0..200 {
            exact += term * (1.0 - statrs::function::beta::beta_reg(1.0 + j as f64, 2.5, xq));
            term *= lam / 2.0 / (j + 1) as f64;
        }
        let got = power as f64 / sets as f64;
        let sd = (exact * (1.0 - exact) / sets as f64).sqrt();
        assert!((got - exact).abs() < 3.3 * sd, "{got} {exact}");
        // The closed form with the same stresses in every group: the slope is orthogonal to
        // the levels, so F = (SSB/2) / ((SSW − S²xy/Sxx)/5) with within-group sums.
        let yb = [1.0, 1.3, 0.7, 2.0, 2.5, 2.3, 0.1, 0.4, 0.2];
        let (f, d1, d2) = between_group_f(&xb, &yb, &balanced);
        let mean = |v: &[f64], g: usize| (0..3).map(|k| v[3 * g + k]).sum::<f64>() / 3.0;
        let grand = yb.iter().sum::<f64>() / 9.0;
        let ssb: f64 = (0..3).map(|g| 3.0 * (mean(&yb, g) - grand).powi(2)).sum();
        let ssw: f64 = (0..9).map(|i| (yb[i] - mean(&yb, i / 3)).powi(2)).sum();
        let sxx: f64 = (0..9).map(|i| (xb[i] - mean(&xb, i / 3)).powi(2)).sum();
        let sxy: f64 = (0..9)
            .map(|i| (xb[i] - mean(&xb, i / 3)) * (yb[i] - mean(&yb, i / 3)))
            .sum();
        let want = (ssb / 2.0) / ((ssw - sxy * sxy / sxx) / 5.0);
        assert_eq!((d1, d2), (2, 5));
        assert!((f / want - 1.0).abs() < 1e-9, "{f} {want}");
        // One group: no test.
        assert!(between_group_f(&x, &x, &[0; 9]).0.is_nan());
    }

    /// The noncentral F's tail: the central one at λ = 0; for d₂ → ∞ and d₁ = 1 the normal
    /// closed form, √λ* = z₀.₉₉₅ + z₀.₈ where the test at 1 % has 80 % power.
    #[test]
    fn noncentral_f_tail_and_the_noncentrality_of_a_power() {
        for (f, d1, d2) in [(2.5, 1, 4), (0.7, 3, 10), (8.0, 2, 28)] {
            let (a, b) = (noncentral_f_upper(f, d1, d2, 0.0), f_upper(f, d1, d2));
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        // Monotone in λ.
        let tails: Vec<f64> = [0.0, 1.0, 5.0, 20.0]
            .iter()
            .map(|l| noncentral_f_upper(7.0, 1, 6, *l))
            .collect();
        assert!(tails.windows(2).all(|w| w[0] < w[1]), "{tails:?}");
        let lam = noncentrality_for_power(1, 10_000_000, 0.01, 0.8);
        let want = (2.575_829_3_f64 + 0.841_621_2).powi(2);
        assert!((lam - want).abs() < 0.01, "{lam} {want}");
        // And the tail there is the power asked, at the test's own critical value.
        use statrs::distribution::{ContinuousCDF, FisherSnedecor};
        let crit = FisherSnedecor::new(1.0, 3.0).unwrap().inverse_cdf(0.99);
        let lam3 = noncentrality_for_power(1, 3, 0.01, 0.8);
        assert!((noncentral_f_upper(crit, 1, 3, lam3) - 0.8).abs() < 1e-9);
        assert!(noncentrality_for_power(1, 0, 0.01, 0.8).is_nan());
    }

    /// The difference a two-group test detects: the closed form with a level only
    /// (σ̂·√(λ*(1/n_A + 1/n_B)), σ̂ the pooled sd within the groups), and its power on 4,000
    /// generated data sets of the campaigns world's layout (6 specimens at one temperature,
    /// the campaigns alternating in stress order, a stress slope): a shift of that size with
    /// the true σ is called at 1 % in 80 % of them.
    #[test]
    fn the_detectable_difference_is_called_with_its_power() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let y = [0.1, -0.3, 0.4, 0.0, 1.2, 0.8, 1.5];
        let group = [0usize, 0, 0, 0, 1, 1, 1];
        let ones = vec![1.0; 7];
        let t = nested_test(&y, &[ones], &indicators(&group));
        let mean = |g: usize| {
            let v: Vec<f64> = (0..7).filter(|&i| group[i] == g).map(|i| y[i]).collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let ssw: f64 = (0..7).map(|i| (y[i] - mean(group[i])).powi(2)).sum();
        let lam = noncentrality_for_power(1, 5, STRESS_TREND_ALPHA, DETECT_POWER);
        let want = (ssw / 5.0 * lam * (1.0 / 4.0 + 1.0 / 3.0)).sqrt();
        assert_eq!((t.d1, t.d2), (1, 5));
        assert!(
            (t.detectable / want - 1.0).abs() < 1e-9,
            "{} {want}",
            t.detectable
        );
        // More than two groups: no single difference.
        let three = nested_test(&y, &[vec![1.0; 7]], &indicators(&[0, 0, 1, 1, 2, 2, 2]));
        assert!(three.detectable.is_nan() && three.f.is_finite());

        let x: Vec<f64> = [60.0f64, 60.0, 70.0, 80.0, 90.0, 100.0]
            .iter()
            .map(|s| s.ln())
            .collect();
        let camp: Vec<usize> = (0..6).map(|k| k % 2).collect();
        let base = vec![vec![1.0; 6], x.clone()];
        let extra = indicators(&camp);
        // With σ = 1 the detectable shift is √(λ*/‖M k_B‖²); ‖M k_B‖² from any noise-free y.
        let beyond = {
            let kb: Vec<f64> = camp.iter().map(|c| *c as f64).collect();
            // The residual sum of squares of k_B on a level and the slope.
            let n = 6.0;
            let (sx, sk) = (x.iter().sum::<f64>() / n, kb.iter().sum::<f64>() / n);
            let sxx: f64 = x.iter().map(|v| (v - sx).powi(2)).sum();
            let sxk: f64 = x.iter().zip(&kb).map(|(a, b)| (a - sx) * (b - sk)).sum();
            let skk: f64 = kb.iter().map(|b| (b - sk).powi(2)).sum();
            skk - sxk * sxk / sxx
        };
        let d2 = 6 - 3;
        let shift =
            (noncentrality_for_power(1, d2, STRESS_TREND_ALPHA, DETECT_POWER) / beyond).sqrt();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(69);
        let (sets, mut called) = (4000, 0);
        for _ in 0..sets {
            let yy: Vec<f64> = (0..6)
                .map(|i| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    0.3 - 2.0 * x[i] + shift * camp[i] as f64 + e
                })
                .collect();
            let (f, d1, d2) = nested_f(&yy, &base, &extra);
            called += usize::from(f_upper(f, d1, d2) < STRESS_TREND_ALPHA);
        }
        // Binomial 99.9 % limits about 0.8 of 4,000: 3,200 ± 41.
        assert!((3159..=3241).contains(&called), "{called}");
    }

    /// The campaign test on the Alloy 617 layout (INL2 pairs at 750, 850 and 950 °C, KAERI2
    /// single specimens at 850, 900 and 950 °C): its level under the null of a temperature
    /// level and a stress slope the campaigns share, its power against a campaign shift (the
    /// noncentral F's), the closed form of the nested fits, and where no test can be made.
    #[test]
    fn campaign_levels_f_test_holds_its_level_and_sees_a_campaign() {
        use super::{EffectKind, SpecimenFit};
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let layout: [(f64, f64, &str); 14] = [
            (750.0, 118.0, "INL2-a"),
            (750.0, 118.0, "INL2-b"),
            (750.0, 137.0, "INL2-a"),
            (850.0, 43.0, "INL2-a"),
            (850.0, 43.0, "INL2-b"),
            (850.0, 54.0, "INL2-a"),
            (850.0, 35.0, "KAERI2-a"),
            (850.0, 50.0, "KAERI2-a"),
            (900.0, 25.0, "KAERI2-a"),
            (900.0, 40.0, "KAERI2-a"),
            (950.0, 29.0, "INL2-a"),
            (950.0, 29.0, "INL2-b"),
            (950.0, 20.0, "KAERI2-a"),
            (950.0, 30.0, "KAERI2-a"),
        ];
        let curves: Vec<crate::data::Curve> = layout
            .iter()
            .map(|&(t, s, sp)| crate::data::Curve::two_point(t, s, Some(sp)))
            .collect();
        let fit_of = |rate: Vec<f64>| SpecimenFit {
            kinds: vec![EffectKind::Rate],
            scatter: vec![0.3],
            scatter_lo95: vec![0.1],
            scatter_hi95: vec![0.6],
            scatter_dof: vec![8.0],
            effects_sd: vec![vec![0.05; rate.len()]],
            effects: vec![rate],
            neg2ll_effects: 0.0,
            scatter_method: Default::default(),
            dropped: vec![],
        };
        let level = |t: f64| match t as i64 {
            750 => 0.4,
            850 => -0.2,
            900 => 0.1,
            _ => -0.5,
        };
        let null_mean: Vec<f64> = layout
            .iter()
            .map(|&(t, s, _)| level(t) - 0.8 * s.ln())
            .collect();
        let kaeri: Vec<f64> = layout
            .iter()
            .map(|&(_, _, sp)| f64::from(u8::from(sp.starts_with("KAERI2"))))
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(202_612_042);
        let (mut r05, mut r01, mut power) = (0, 0, 0);
        let sets = 4000;
        for _ in 0..sets {
            let e: Vec<f64> = (0..14).map(|_| StandardNormal.sample(&mut rng)).collect();
            let y: Vec<f64> = (0..14).map(|i| null_mean[i] + e[i]).collect();
            let c = &fit_of(y).campaign_levels(&curves)[0];
            // Two campaigns: one level beyond the four temperatures' and the slope; 14
            // specimens less those 6 columns.
            assert_eq!(c.df, (1, 8));
            r05 += usize::from(c.p_value < 0.05);
            r01 += usize::from(c.p_value < 0.01);
            let y: Vec<f64> = (0..14)
                .map(|i| null_mean[i] + 1.5 * kaeri[i] + e[i])
                .collect();
            power += usize::from(fit_of(y).campaign_levels(&curves)[0].p_value < 0.05);
        }
        // Binomial 99.9 % limits: 5 % of 4,000 is 200 ± 45, 1 % is 40 ± 21.
        assert!((155..=245).contains(&r05), "{r05}");
        assert!((19..=61).contains(&r01), "{r01}");
        // Power: the noncentral F (1, 8) beyond its 5 % critical value, λ = δ²·‖M k‖² with M
        // the residual maker of the null's columns and k the KAERI2 indicator.
        let cols = |extra: bool| {
            let mut m = nalgebra::DMatrix::<f64>::zeros(14, if extra { 6 } else { 5 });
            for (i, &(t, s, _)) in layout.iter().enumerate() {
                let ti = [750.0, 850.0, 900.0, 950.0]
                    .iter()
                    .position(|v| *v == t)
                    .unwrap();
                m[(i, ti)] = 1.0;
                m[(i, 4)] = s.ln();
                if extra {
                    m[(i, 5)] = kaeri[i];
                }
            }
            m
        };
        let resid = |x: &nalgebra::DMatrix<f64>, v: &nalgebra::DVector<f64>| {
            let xtx = (x.transpose() * x).try_inverse().unwrap();
            v - x * (xtx * (x.transpose() * v))
        };
        let k = nalgebra::DVector::from_vec(kaeri.clone());
        let lam = 1.5f64.powi(2) * resid(&cols(false), &k).norm_squared();
        let crit = {
            use statrs::distribution::{ContinuousCDF, FisherSnedecor};
            FisherSnedecor::new(1.0, 8.0).unwrap().inverse_cdf(0.95)
        };
        let xq = crit / (crit + 8.0);
        let mut term = (-lam / 2.0).exp();
        let mut exact = 0.0;
        for j in 0..300 {
            exact += term * (1.0 - statrs::function::beta::beta_reg(0.5 + j as f64, 4.0, xq));
            term *= lam / 2.0 / (j + 1) as f64;
        }
        let got = power as f64 / sets as f64;
        let sd = (exact * (1.0 - exact) / sets as f64).sqrt();
        assert!((got - exact).abs() < 3.3 * sd, "{got} {exact}");
        // The closed form by the normal equations of both designs, on fixed factors.
        let y: Vec<f64> = (0..14)
            .map(|i| null_mean[i] + 0.3 * kaeri[i] + 0.1 * ((i * 7 % 5) as f64 - 2.0))
            .collect();
        let yv = nalgebra::DVector::from_vec(y.clone());
        let (rss0, rss1) = (
            resid(&cols(false), &yv).norm_squared(),
            resid(&cols(true), &yv).norm_squared(),
        );
        let c = &fit_of(y.clone()).campaign_levels(&curves)[0];
        let want = (rss0 - rss1) / (rss1 / 8.0);
        assert!((c.f / want - 1.0).abs() < 1e-9, "{} {want}", c.f);
        let mean = |pre: &str| {
            let v: Vec<f64> = (0..14)
                .filter(|&i| layout[i].2.starts_with(pre))
                .map(|i| y[i])
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        assert_eq!(c.mean_ln[0].0, "INL2");
        assert!((c.mean_ln[0].1 - mean("INL2")).abs() < 1e-12);
        assert!((c.mean_ln[1].1 - mean("KAERI2")).abs() < 1e-12);
        // Campaigns confounded with temperatures (INL2 only at 750 °C, KAERI2 only at 900 °C):
        // nothing beyond the temperature levels, no test.
        let split: Vec<crate::data::Curve> = layout
            .iter()
            .map(|&(_, s, sp)| {
                let t = if sp.starts_with("INL2") { 750.0 } else { 900.0 };
                crate::data::Curve::two_point(t, s, Some(sp))
            })
            .collect();
        let c = &fit_of(y.clone()).campaign_levels(&split)[0];
        assert!(c.f.is_nan() && c.p_value.is_nan() && c.df.0 == 0, "{c:?}");
        // Labels without campaigns (each specimen its own), or one unlabelled curve: none.
        let own: Vec<crate::data::Curve> = layout
            .iter()
            .enumerate()
            .map(|(i, &(t, s, _))| crate::data::Curve::two_point(t, s, Some(&format!("S{i}"))))
            .collect();
        assert!(fit_of(y.clone()).campaign_levels(&own).is_empty());
        // `synth`'s replicate pairs (`S4-a`, `S4-b` at one stress) name conditions, not
        // campaigns: between them the test would be one of the stress trend's lack of fit.
        let pairs: Vec<crate::data::Curve> = layout
            .iter()
            .map(|&(t, s, _)| {
                let label = format!("S{t}x{s}-a");
                crate::data::Curve::two_point(t, s, Some(&label))
            })
            .collect();
        assert!(fit_of(y.clone()).campaign_levels(&pairs).is_empty());
        let mut one_unlabelled = curves.clone();
        one_unlabelled[3].specimen = None;
        assert!(fit_of(y.clone())
            .campaign_levels(&one_unlabelled)
            .is_empty());
        // At the scatter's floor the factors are zero: no test.
        let mut floor = fit_of(y);
        floor.scatter = vec![crate::specimen::SCATTER_FLOOR];
        assert!(floor.campaign_levels(&curves)[0].f.is_nan());
    }

    /// Group means and standard errors of known factors, as a table.
    #[test]
    fn within_group_slope_is_the_dummy_variable_regression() {
        use nalgebra::{DMatrix, DVector};
        // Three temperatures with their own offsets, a common slope 0.7 and noise: the pooled
        // slope and its standard error against ordinary least squares on [x, one column per
        // group] solved directly.
        let x = [3.2, 3.5, 3.9, 4.1, 2.9, 3.0, 3.6, 4.4, 4.0, 3.3];
        let group = [0, 0, 0, 1, 1, 1, 1, 2, 2, 2];
        let offs = [0.3, -0.5, 1.2];
        let noise = [
            0.05, -0.02, 0.08, -0.11, 0.03, 0.07, -0.04, 0.01, -0.06, 0.09,
        ];
        let y: Vec<f64> = (0..10)
            .map(|i| 0.7 * x[i] + offs[group[i]] + noise[i])
            .collect();
        let (b, se, df) = super::within_group_slope(&x, &y, &group);
        let mut d = DMatrix::<f64>::zeros(10, 4);
        for i in 0..10 {
            d[(i, 0)] = x[i];
            d[(i, 1 + group[i])] = 1.0;
        }
        let yv = DVector::from_vec(y.clone());
        let xtx_inv = (d.transpose() * &d).try_inverse().unwrap();
        let beta = &xtx_inv * d.transpose() * &yv;
        let resid = &yv - &d * &beta;
        let s2 = resid.norm_squared() / 6.0;
        assert_eq!(df, 6);
        assert!((b - beta[0]).abs() < 1e-12, "{b} {}", beta[0]);
        assert!((se - (s2 * xtx_inv[(0, 0)]).sqrt()).abs() < 1e-12);
        // Exact data: the slope itself, no scatter about it.
        let exact: Vec<f64> = (0..10).map(|i| 0.7 * x[i] + offs[group[i]]).collect();
        let (b, se, _) = super::within_group_slope(&x, &exact, &group);
        assert!((b - 0.7).abs() < 1e-12 && se < 1e-6);
        // One stress per group: no slope.
        let (b, se, df) = super::within_group_slope(&[1.0, 2.0], &[0.1, 0.2], &[0, 1]);
        assert!(b.is_nan() && se.is_nan() && df == 0);
    }

    #[test]
    fn stress_trend_reads_the_factors_against_ln_stress_per_temperature() {
        use super::{EffectKind, SpecimenFit};
        let curve = |t: f64, s: f64| crate::data::Curve::two_point(t, s, None);
        let curves = [
            curve(850.0, 40.0),
            curve(900.0, 25.0),
            curve(850.0, 60.0),
            curve(900.0, 35.0),
            curve(850.0, 50.0),
        ];
        // Rate: 0.5 ln σ plus an offset per temperature (what the constants would miss);
        // ductility: the same value at every stress.
        let rate: Vec<f64> = curves
            .iter()
            .map(|c| 0.5 * c.stress_mpa.ln() + if c.temperature_c == 900.0 { -1.0 } else { 0.3 })
            .collect();
        let fit = SpecimenFit {
            kinds: vec![EffectKind::Rate, EffectKind::Ductility],
            scatter: vec![0.3, 0.2],
            scatter_lo95: vec![0.1, 0.0],
            scatter_hi95: vec![0.6, 0.5],
            scatter_dof: vec![4.0, 4.0],
            effects: vec![rate, vec![0.1; 5]],
            effects_sd: vec![vec![0.05; 5], vec![0.05; 5]],
            neg2ll_effects: 0.0,
            scatter_method: Default::default(),
            dropped: vec![],
        };
        let tr = fit.stress_trend(&curves);
        assert_eq!(tr.len(), 2);
        assert_eq!(
            (tr[0].kind, tr[0].specimens, tr[0].temperatures, tr[0].df),
            (EffectKind::Rate, 5, 2, 2)
        );
        assert!((tr[0].slope - 0.5).abs() < 1e-12 && tr[0].se < 1e-6);
        assert!(tr[0].p_value < 1e-6);
        assert!(tr[1].slope.abs() < 1e-12 && tr[1].kind == EffectKind::Ductility);
        // The decision, as a table: (p, follows stress).
        for (p, yes) in [
            (0.0, true),
            (0.0099, true),
            (0.01, false),
            (0.5, false),
            (f64::NAN, false),
        ] {
            let t = super::StressTrend {
                p_value: p,
                ..tr[0].clone()
            };
            assert_eq!(t.follows_stress(), yes, "p {p}");
        }
    }

    #[test]
    fn the_better_fit_is_the_evaluable_one_with_the_lower_likelihood_self_on_ties() {
        let fit = |neg2ll: f64| MlFit {
            neg2ll,
            termination: Termination::ConvergedObjective,
            ..MlFit::failed(&[neg2ll], String::new(), 0, 0)
        };
        let failed = |tag: f64| MlFit::failed(&[tag], String::new(), 0, 0);
        // (self, other, which one is kept: its params[0])
        let table = [
            (fit(-5.0), fit(-7.0), -7.0),
            (fit(-7.0), fit(-5.0), -7.0),
            (fit(-5.0), fit(-5.0), -5.0),
            (failed(1.0), fit(-5.0), -5.0),
            (fit(-5.0), failed(1.0), -5.0),
            (failed(1.0), failed(2.0), 1.0),
            (fit(f64::NAN), fit(-5.0), -5.0),
        ];
        for (a, b, want) in table {
            let kept = a.better(b).params[0];
            assert!(
                kept == want || (kept.is_nan() && want.is_nan()),
                "{kept} vs {want}"
            );
        }
    }

    #[test]
    fn t_p_values() {
        // Tabulated two-sided 5 % points: t(10) 2.228139, t(2) 4.302653; the normal 1.959964.
        assert!((super::t_two_sided(2.228_138_851_986_274, 10) - 0.05).abs() < 1e-9);
        assert!((super::t_two_sided(-4.302_652_729_749_464, 2) - 0.05).abs() < 1e-9);
        assert!((super::t_two_sided(1.959_963_984_540_054, 10_000_000) - 0.05).abs() < 1e-6);
        assert!(super::t_two_sided(f64::NAN, 5).is_nan());
        assert!(super::t_two_sided(1.0, 0).is_nan());
        assert_eq!(super::t_two_sided(f64::NEG_INFINITY, 3), 0.0);
    }

    #[test]
    fn factors_by_group() {
        use super::{EffectKind, SpecimenFit};
        let fit = SpecimenFit {
            kinds: vec![EffectKind::Rate, EffectKind::Ductility],
            scatter: vec![0.3, 0.2],
            scatter_lo95: vec![0.1, 0.0],
            scatter_hi95: vec![0.6, 0.5],
            scatter_dof: vec![4.0, 4.0],
            effects: vec![vec![0.1, 0.3, -0.2, 0.5], vec![0.0, 0.2, 0.1, -0.1]],
            effects_sd: vec![vec![0.05; 4], vec![0.05; 4]],
            neg2ll_effects: 0.0,
            scatter_method: Default::default(),
            dropped: vec![],
        };
        let curve = |t: f64, sp: &str| crate::data::Curve::two_point(t, 100.0, Some(sp));
        let curves = [
            curve(850.0, "A-1"),
            curve(900.0, "B-1"),
            curve(850.0, "B-2"),
            curve(850.0, "A-2"),
        ];
        let by_t = fit.by_group(&curves, |c| Some(format!("{} °C", c.temperature_c)));
        assert_eq!(by_t.len(), 2);
        assert_eq!((by_t[0].group.as_str(), by_t[0].specimens), ("850 °C", 3));
        // Rate at 850 °C: 0.1, −0.2, 0.5: mean 0.4/3, sd² = Σ(x − m)²/2.
        let m = 0.4 / 3.0;
        let sd2 = [0.1, -0.2, 0.5]
            .iter()
            .map(|x: &f64| (x - m).powi(2))
            .sum::<f64>()
            / 2.0;
        assert!((by_t[0].mean_ln[0] - m).abs() < 1e-15);
        assert!((by_t[0].se[0] - (sd2 / 3.0).sqrt()).abs() < 1e-15);
        assert!((by_t[0].mean_ln[1] - 0.0).abs() < 1e-15);
        assert_eq!((by_t[1].group.as_str(), by_t[1].specimens), ("900 °C", 1));
        assert_eq!(by_t[1].mean_ln, [0.3, 0.2]);
        assert!(by_t[1].se.iter().all(|v| v.is_nan()));
        let by_c = fit.by_group(&curves, |c| c.campaign().map(str::to_string));
        assert_eq!(
            by_c.iter()
                .map(|g| (g.group.as_str(), g.specimens))
                .collect::<Vec<_>>(),
            [("A", 2), ("B", 2)]
        );
        assert!((by_c[0].mean_ln[0] - 0.3).abs() < 1e-15);
        assert!((by_c[1].mean_ln[1] - 0.15).abs() < 1e-15);
    }

    use super::*;
    use crate::errmodel::Ar1;

    #[test]
    fn split_residuals_undo_the_eq8_scaling() {
        let c = Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: None,
            times_h: vec![0.0, 1.0],
            strains: vec![0.0, 0.01],
            rupture_time_h: Some(10.0),
            rupture_strain: 0.05,
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 1e-3,
        };
        let r = [0.1, -0.2, 0.5];
        let s = split_residuals(std::slice::from_ref(&c), &r);
        assert!((s.strain[0][0] - 0.005).abs() < 1e-15);
        assert!((s.strain[0][1] + 0.01).abs() < 1e-15);
        assert!((s.lifetime[0].unwrap() - 1.5f64.ln()).abs() < 1e-15);
        let m = ErrorModel {
            strain: vec![Ar1::white(1e-3)],
            lifetime_sd: 0.1,
        };
        assert!(m.neg2ll(&s).is_finite());
    }
}

#[cfg(test)]
mod new_group_sd_tests {
    use super::{indicators, nested, new_group_sd, NestedTest};
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    /// The χ² pivot's interval of an sd from a mean square `ms` on `d` degrees of freedom.
    fn pivot(ms: f64, d: usize) -> (f64, f64) {
        let chi = ChiSquared::new(d as f64).unwrap();
        (
            (ms * d as f64 / chi.inverse_cdf(0.975)).sqrt(),
            (ms * d as f64 / chi.inverse_cdf(0.025)).sqrt(),
        )
    }

    /// Where one coefficient vanishes the interval is the exact χ² pivot of the other mean
    /// square: q → ∞ leaves the residual's (σ_w² alone), q → 1 the extra columns' (MS₁/q).
    #[test]
    fn new_group_sd_is_the_exact_pivot_where_one_mean_square_counts() {
        let t = |q: f64| NestedTest {
            f: 2.0,
            d1: 3,
            d2: 7,
            detectable: f64::NAN,
            ms: (0.5, 0.25),
            q,
        };
        let (est, lo, hi) = new_group_sd(&t(1e12), 0.95).unwrap();
        let (plo, phi) = pivot(0.25, 7);
        assert!((est - 0.5).abs() < 1e-6, "{est}");
        assert!(
            (lo - plo).abs() < 1e-6 * plo && (hi - phi).abs() < 1e-6 * phi,
            "{lo} {hi}"
        );
        let q = 1.0 + 1e-12;
        let (_, lo, hi) = new_group_sd(&t(q), 0.95).unwrap();
        let (plo, phi) = pivot(0.5 / q, 3);
        assert!(
            (lo - plo).abs() < 1e-6 * plo && (hi - phi).abs() < 1e-6 * phi,
            "{lo} {hi}"
        );
        // No interval where the test is not made or the groups are confounded (q ≤ 1).
        assert!(new_group_sd(&t(0.8), 0.95).is_none());
        assert!(new_group_sd(
            &NestedTest {
                f: f64::NAN,
                ..t(3.0)
            },
            0.95
        )
        .is_none());
    }

    /// Coverage over 2,000 generated sets per design: specimens alternating between two
    /// campaigns along ln σ (as in `synth --world campaigns`), a level and a slope on ln σ,
    /// campaign sd 0 or 3 within-campaign sds. The interval of the sd of a new specimen from a
    /// new campaign covers it in 95 % give or take three binomial standard errors (0.935), and
    /// at most 98 % (Graybill–Wang is conservative where the campaigns' single degree of
    /// freedom dominates). The interval that treats the specimens as independent (the χ²
    /// pivot on the residual about level and slope, n − 2 degrees of freedom) falls far
    /// below where the campaigns differ.
    #[test]
    fn new_group_sd_covers_a_new_campaigns_specimen() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(215_001);
        for (n, ratio) in [(4usize, 0.0f64), (4, 3.0), (10, 0.0), (10, 3.0)] {
            let truth = (1.0 + ratio * ratio).sqrt();
            let x: Vec<f64> = (0..n).map(|i| (40.0 + 10.0 * i as f64).ln()).collect();
            let camp: Vec<usize> = (0..n).map(|i| i % 2).collect();
            let base = vec![vec![1.0; n], x.clone()];
            let extra = indicators(&camp);
            let (mut cov, mut iid) = (0, 0);
            let sets = 2000;
            for _ in 0..sets {
                let mut z = || -> f64 { StandardNormal.sample(&mut rng) };
                let c = [ratio * z(), ratio * z()];
                let y: Vec<f64> = (0..n).map(|i| 0.3 * x[i] + c[camp[i]] + z()).collect();
                let t = nested(&y, &base, &extra, false);
                let (_, lo, hi) = new_group_sd(&t, 0.95).expect("q > 1 in this design");
                cov += (lo <= truth && truth <= hi) as usize;
                let rss_base = t.ms.0 * t.d1 as f64 + t.ms.1 * t.d2 as f64;
                let (lo, hi) = pivot(rss_base / (n - 2) as f64, n - 2);
                iid += (lo <= truth && truth <= hi) as usize;
            }
            let (cov, iid) = (cov as f64 / sets as f64, iid as f64 / sets as f64);
            assert!((0.935..=0.98).contains(&cov), "n {n}, ratio {ratio}: {cov}");
            if n == 10 && ratio > 0.0 {
                assert!(iid < 0.8, "n {n}, ratio {ratio}: independent {iid}");
            }
        }
    }
}
