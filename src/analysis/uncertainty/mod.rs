//! How sure the constants and the predictions are: profile likelihoods of the constants under
//! the error model of [`crate::errmodel`], their 68 % and 95 % intervals and identifiability
//! classes ([`profile`]), the combinations of constants the data determine ([`combos`]),
//! confidence and prediction intervals of predicted rupture time, minimum creep rate and
//! rupture strain at an untested load, with a band around the predicted curve ([`predict`]),
//! the calibration of the likelihood-ratio thresholds by a parametric bootstrap
//! ([`calibrate`]), and the measured coverage of all of it on synthetic data with known truth
//! ([`coverage`]).
//!
//! Everything works on the **profile −2 ln L**: the constants not held are re-fitted and the
//! error model (AR(1) reading error per curve, rupture-time scatter) is re-estimated at every
//! profile point ([`constrained::ml_fit_scaled`]), so a profile is the likelihood maximised
//! over everything else. Bounds are those of the configuration and are never loosened: a
//! profile that reaches a bound before crossing its threshold is reported open at that bound.
//!
//! **With specimen effects** (the configuration's `specimen_effects`, [`Context::hierarchical`])
//! every fit is the hierarchical fit of [`crate::likelihood::ml_fit_row`]: the profile −2 ln L
//! is the Laplace marginal likelihood with the specimens' factors integrated out and their
//! scatter re-estimated at every point, the bootstrap replicates draw new specimens
//! ([`replicate`]), and the intervals are those of the population's constants (a median
//! specimen's) and of its predictions.

pub mod calibrate;
pub mod combos;
pub mod constrained;
pub mod coverage;
pub mod predict;
pub mod profile;
pub mod report;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::RwLock;

use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::data::Curve;
use crate::errmodel::{ErrorModel, GrowingError, Residuals};
use crate::error::{Error, Result};
use crate::fit::FitSettings;
use crate::likelihood::{
    raw_objective, EffectStart, LikelihoodProblem, MlFit, MlOptions, SpecimenFit,
};
use crate::lsq::{LeastSquaresProblem, LmOptions};
use crate::model::objective::{CreepProblem, Evaluation, ParamSpace};
use crate::model::Model;

/// What every computation of this module needs: the model, the data, the box, the numerical
/// settings and the error model's options.
pub struct Context<'a> {
    /// The model.
    pub model: &'a dyn Model,
    /// The measured curves (ascending stress).
    pub curves: &'a [Curve],
    /// Bounds and scales of the constants (all free).
    pub space: ParamSpace,
    /// Settings of fits from far starts (the configuration's).
    pub settings: FitSettings,
    /// Settings of warm-started refits: geodesic acceleration off (next to an optimum it
    /// costs twice per iteration and saves no iterations, measured by `diagnose`).
    pub warm: FitSettings,
    /// Error-model options (rupture-time scatter floor, the specimen effects: with any, every
    /// fit of this module is a hierarchical fit and every −2 ln L its Laplace marginal).
    pub ml: MlOptions,
    /// Where the hierarchical fits start their specimen effects, and the constants they belong
    /// to: the reference's once it is found ([`reference_from`]), new specimens' (zero, no
    /// constants) in a bootstrap replicate.
    pub effects: RwLock<Option<(EffectStart, Option<Vec<f64>>)>>,
    /// Whether `specimen_effects = "auto"` chose the specimen effects of `ml`: with the scatter
    /// estimated beyond the stress trend and found zero at the reference, the analyses go on
    /// without them ([`Context::settles_without_specimens`]).
    pub auto_effects: bool,
    /// Whether the reference of the hierarchical fits sits at zero scatter (the fit of
    /// identical specimens won, or every kind's scatter at its floor): its −2 ln L is then the
    /// model without effects, which the hierarchical fits reach only in the limit, so every
    /// fit after it is also fitted without effects and the better one kept
    /// ([`Context::fit_row`]). Set by [`Context::start_effects_at`].
    pub zero_scatter_reference: AtomicBool,
}

impl<'a> Context<'a> {
    /// A context with the warm-start settings derived from `settings`.
    pub fn new(
        model: &'a dyn Model,
        curves: &'a [Curve],
        space: ParamSpace,
        settings: FitSettings,
        ml: MlOptions,
    ) -> Self {
        let warm = FitSettings {
            lm: LmOptions {
                geodesic: None,
                ..settings.lm
            },
            ..settings
        };
        Context {
            model,
            curves,
            space,
            settings,
            warm,
            ml,
            effects: RwLock::new(None),
            auto_effects: false,
            zero_scatter_reference: AtomicBool::new(false),
        }
    }

    /// Whether the analyses go on without the specimen factors, given the reference fit with
    /// them: `auto` chose them, the scatter is estimated beyond the stress trend and the
    /// reference puts every kind's at zero ([`crate::likelihood::scatter_at_zero`]; `diagnose`
    /// decides the same, docs/SPECIMENS.md, "Session 65").
    pub fn settles_without_specimens(&self, reference: &Reference) -> bool {
        self.auto_effects
            && self.ml.specimen.beyond_trend
            && self.hierarchical()
            && crate::likelihood::scatter_at_zero(
                reference.specimen.as_ref().map(|sp| sp.scatter.as_slice()),
            )
    }

    /// The same context without specimen effects: every fit plain.
    pub fn without_specimens(&self) -> Context<'a> {
        Context {
            model: self.model,
            curves: self.curves,
            space: self.space.clone(),
            settings: self.settings,
            warm: self.warm,
            ml: MlOptions {
                specimen: crate::likelihood::SpecimenOptions::NONE,
                ..self.ml
            },
            effects: RwLock::new(None),
            auto_effects: false,
            zero_scatter_reference: AtomicBool::new(false),
        }
    }

    /// Whether the fits carry specimen effects (hierarchical fits).
    pub fn hierarchical(&self) -> bool {
        self.ml.specimen.any()
    }

    /// The same context on other curves (a bootstrap replicate of these: the same specimens,
    /// in the same order), every specimen new: its effects start at zero.
    pub fn on<'b>(&self, curves: &'b [Curve]) -> Context<'b>
    where
        'a: 'b,
    {
        let fresh = self.effect_start().map(|e| {
            (
                EffectStart::fresh(e.kinds.clone(), e.scatter.clone(), curves.len()),
                None,
            )
        });
        Context {
            model: self.model,
            curves,
            space: self.space.clone(),
            settings: self.settings,
            warm: self.warm,
            ml: self.ml,
            effects: RwLock::new(fresh),
            auto_effects: self.auto_effects,
            zero_scatter_reference: AtomicBool::new(false),
        }
    }

    /// The same context on a bootstrap replicate whose new specimens were drawn at the effects
    /// `drawn`, belonging to constants `at`: its hierarchical fits start from those effects
    /// (re-expressed for their start), a known point near the replicate's optimum. Without
    /// effects, [`Context::on`].
    pub fn on_drawn<'b>(
        &self,
        curves: &'b [Curve],
        drawn: Option<&EffectStart>,
        at: &[f64],
    ) -> Context<'b>
    where
        'a: 'b,
    {
        let c = self.on(curves);
        if let (true, Some(d)) = (self.hierarchical(), drawn) {
            let mut w = c.effects.write().unwrap_or_else(|e| e.into_inner());
            *w = Some((d.clone(), Some(at.to_vec())));
        }
        c
    }

    /// The specimen effects the hierarchical fits start from (as stored).
    pub fn effect_start(&self) -> Option<EffectStart> {
        self.stored_effects().map(|e| e.0)
    }

    fn stored_effects(&self) -> Option<(EffectStart, Option<Vec<f64>>)> {
        self.effects
            .read()
            .map(|e| e.clone())
            .unwrap_or_else(|e| e.into_inner().clone())
    }

    /// The specimen effects a hierarchical fit from constants `start` starts with: the stored
    /// ones re-expressed for `start` ([`EffectStart::moved`]: every specimen's own constants
    /// those of the fit they came from).
    pub fn effect_start_for(&self, start: &[f64]) -> Option<EffectStart> {
        let (e, from) = self.stored_effects()?;
        Some(match from {
            Some(from) => e.moved(self.model, &from, start),
            None => e,
        })
    }

    /// Hierarchical fits start from the effects of `fit`, which belong to constants `params`,
    /// from now on (nothing without effects).
    pub fn start_effects_at(&self, fit: Option<&SpecimenFit>, params: &[f64]) {
        if self.hierarchical() {
            let zero = crate::likelihood::scatter_at_zero(fit.map(|sp| sp.scatter.as_slice()));
            self.zero_scatter_reference.store(zero, Ordering::Relaxed);
        }
        if let Some(sp) = fit {
            let mut w = self.effects.write().unwrap_or_else(|e| e.into_inner());
            *w = Some((EffectStart::from(sp), Some(params.to_vec())));
        }
    }

    /// Names of the constants, model order.
    pub fn names(&self) -> Vec<&'static str> {
        self.model.constants().iter().map(|c| c.name).collect()
    }

    /// A maximum-likelihood fit from `start` in `space` (warm settings if `warm`), scaled
    /// for the optimiser ([`constrained::ml_fit_scaled`]).
    pub fn fit(&self, space: &ParamSpace, start: &[f64], warm: bool) -> MlFit {
        let s = if warm { &self.warm } else { &self.settings };
        if self.hierarchical() {
            let h = self.fit_row(space, start, warm, &[], None);
            if warm {
                return h;
            }
            // From a far start also the fit of identical specimens carried on with the
            // effects (the model without effects is the hierarchical one's limit of zero
            // scatter, so its optimum bounds the hierarchical one's): the better of the two
            // (measured: the 560 °C data with rate effects, from the eq. 8 constants, −1213.5
            // directly against −1216.2 without effects).
            let plain = constrained::ml_fit_scaled(self, space, start, s);
            let p = crate::likelihood::with_specimens(
                plain,
                self.model,
                self.curves,
                space,
                &self.warm,
                &self.ml,
            );
            return if p.ok() && (!h.ok() || p.neg2ll < h.neg2ll) {
                p
            } else {
                h
            };
        }
        constrained::ml_fit_scaled(self, space, start, s)
    }

    /// A hierarchical fit ([`crate::likelihood::ml_fit_row`]) from `start` with the effects of
    /// [`Context::effect_start`], the constants `pinned` held at their start values, `row`
    /// appended, every problem scaled (as [`constrained::minimize_scaled`] does for the fits
    /// without effects); a far start (not `warm`) with its white stage first.
    pub fn fit_row(
        &self,
        space: &ParamSpace,
        start: &[f64],
        warm: bool,
        pinned: &[usize],
        row: Option<&dyn crate::likelihood::ExtraRow>,
    ) -> MlFit {
        let s = if warm { &self.warm } else { &self.settings };
        let opts = MlOptions {
            white_first: !warm,
            ..self.ml
        };
        let effects = self.effect_start_for(start);
        let held = crate::likelihood::Held {
            pinned,
            row,
            scaled: true,
        };
        let h = crate::likelihood::ml_fit_row(
            self.model,
            self.curves,
            space,
            start,
            effects.as_ref(),
            s,
            &opts,
            &held,
        );
        if !self.zero_scatter_reference.load(Ordering::Relaxed) {
            return h;
        }
        // The reference at zero scatter: the profile over the scatter includes its boundary,
        // the model without effects, whose −2 ln L the hierarchical fit approaches but does
        // not reach at its floor (the Laplace log-determinant there is not zero).
        let plain = crate::likelihood::ml_fit_row(
            self.model,
            self.curves,
            space,
            start,
            None,
            s,
            &MlOptions {
                specimen: crate::likelihood::SpecimenOptions::NONE,
                ..opts
            },
            &held,
        );
        if plain.ok() && (!h.ok() || plain.neg2ll < h.neg2ll) {
            MlFit {
                iterations: plain.iterations + h.iterations,
                evaluations: plain.evaluations + h.evaluations,
                ..plain
            }
        } else {
            h
        }
    }

    /// The longest measured life among the curves, h (rupture time or last measured time).
    pub fn longest_life_h(&self) -> f64 {
        self.curves.iter().map(|c| c.life_h()).fold(0.0, f64::max)
    }
}

/// The maximum-likelihood optimum every profile is measured from.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Constants, model order.
    pub params: Vec<f64>,
    /// −2 ln L at the optimum.
    pub neg2ll: f64,
    /// The error model at the optimum.
    pub noise: ErrorModel,
    /// Raw residuals at the optimum.
    pub residuals: Residuals,
    /// Predictions at the optimum (eq. 8 at w = 1, both sides).
    pub eval: Evaluation,
    /// Other distinct local optima found (best first), within [`BASIN_WINDOW`] of the best:
    /// the starts an inner fit is retried from.
    pub basins: Vec<Vec<f64>>,
    /// Fits run to find it, and how many of them failed.
    pub fits: usize,
    pub failed: usize,
    /// The specimen effects at the optimum (hierarchical fits; `None` without).
    pub specimen: Option<SpecimenFit>,
}

/// Local optima more than this above the best (−2 ln L) are not kept as retry starts.
pub const BASIN_WINDOW: f64 = 20.0;

impl Reference {
    /// The reference from one successful fit (no other basins known).
    pub fn from_fit(f: MlFit) -> Option<Reference> {
        if !f.ok() {
            return None;
        }
        Some(Reference {
            params: f.params,
            neg2ll: f.neg2ll,
            noise: f.noise,
            residuals: f.residuals?,
            eval: f.eval?,
            basins: vec![],
            fits: 1,
            failed: 0,
            specimen: f.specimen,
        })
    }

    /// The optimum as the fit it came from (for simulating under it).
    pub fn as_fit(&self) -> MlFit {
        MlFit {
            params: self.params.clone(),
            noise: self.noise.clone(),
            neg2ll: self.neg2ll,
            residuals: Some(self.residuals.clone()),
            eval: Some(self.eval.clone()),
            specimen: self.specimen.clone(),
            termination: crate::lsq::Termination::ConvergedObjective,
            iterations: 0,
            evaluations: 0,
            failure: None,
        }
    }
}

/// A parametric-bootstrap replicate of the context's curves under `reference`: with specimen
/// effects every curve a new specimen whose factors are drawn from the fitted scatter
/// ([`crate::diagnose::bootstrap::replicate_hier_drawn`]; the drawn effects are returned
/// too), else the fitted curves plus the error model's reading error and rupture-time
/// scatter ([`crate::diagnose::bootstrap::replicate_data`]; `None`). The reading error does
/// not grow with strain here (g = 0): the intervals' coverage was calibrated so
/// (docs/UNCERTAINTY.md); `diagnose`'s bootstrap fits the growth
/// ([`crate::diagnose::bootstrap::reading_error`]).
pub fn replicate<R: rand::Rng>(
    ctx: &Context,
    reference: &Reference,
    rng: &mut R,
) -> (Vec<Curve>, Option<EffectStart>) {
    if reference.specimen.is_some() {
        crate::diagnose::bootstrap::replicate_hier_drawn(
            ctx.curves,
            ctx.model,
            &reference.as_fit(),
            &GrowingError::constant(&reference.noise.strain),
            &ctx.settings,
            &crate::diagnose::bootstrap::SpecimenShapes::none(),
            rng,
        )
    } else {
        let data = crate::diagnose::bootstrap::replicate_data(
            ctx.curves,
            &reference.eval,
            &reference.noise,
            &GrowingError::constant(&reference.noise.strain),
            rng,
        );
        (data, None)
    }
}

/// The best refit of a bootstrap replicate `data` (drawn at effects `drawn`): warm fits from
/// the reference and its other optima with every specimen's effects at zero, and, with
/// specimen effects, one more from the reference with the drawn effects (a refit from zero
/// effects can stop short of the replicate's optimum: measured in `diagnose`'s null
/// replicates, docs/SPECIMENS.md). `None` if no fit succeeded.
pub fn refit_replicate(
    ctx: &Context,
    reference: &Reference,
    data: &[Curve],
    drawn: Option<&EffectStart>,
) -> Option<MlFit> {
    let c = ctx.on(data);
    let mut fits: Vec<MlFit> = std::iter::once(&reference.params)
        .chain(&reference.basins)
        .map(|s| c.fit(&c.space, s, true))
        .collect();
    if drawn.is_some() && ctx.hierarchical() {
        let d = ctx.on_drawn(data, drawn, &reference.params);
        fits.push(d.fit(&d.space, &reference.params, true));
    }
    fits.into_iter().reduce(MlFit::better).filter(|f| f.ok())
}

/// Starts of the multistart: `given` (if any), then `lhs` Latin-hypercube points of the box
/// drawn from `seed`.
pub fn starts(ctx: &Context, given: &[Vec<f64>], lhs: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = given.to_vec();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for u in crate::sampling::latin_hypercube(lhs, ctx.space.len(), &mut rng) {
        let mut x = vec![0.0; ctx.space.len()];
        ctx.space.from_unit(&u, &mut x);
        out.push(x);
    }
    out
}

/// Maximum-likelihood multistart: a fit from every start (in parallel, results in start
/// order), the best as the reference, and the distinct other optima as retry starts.
pub fn fit_reference(ctx: &Context, starts: &[Vec<f64>]) -> Result<Reference> {
    let fits: Vec<MlFit> = starts
        .par_iter()
        .map(|s| ctx.fit(&ctx.space, s, false))
        .collect();
    reference_from(ctx, fits)
}

/// The reference from a set of fits (see [`fit_reference`]).
pub fn reference_from(ctx: &Context, fits: Vec<MlFit>) -> Result<Reference> {
    let n = fits.len();
    let failed = fits.iter().filter(|f| !f.ok()).count();
    let mut ok: Vec<MlFit> = fits.into_iter().filter(|f| f.ok()).collect();
    ok.sort_by(|a, b| a.neg2ll.total_cmp(&b.neg2ll));
    let Some(best) = ok.first().cloned() else {
        return Err(Error::Numerical(format!(
            "profile: no maximum-likelihood fit succeeded from any of {n} starts"
        )));
    };
    let mut basins: Vec<Vec<f64>> = Vec::new();
    let ub = ctx.space.to_unit(&best.params);
    for f in ok.iter().skip(1) {
        if f.neg2ll > best.neg2ll + BASIN_WINDOW || basins.len() >= 4 {
            break;
        }
        let u = ctx.space.to_unit(&f.params);
        let distinct = |v: &[f64]| u.iter().zip(v).any(|(a, b)| (a - b).abs() > 0.02);
        if distinct(&ub) && basins.iter().all(|b| distinct(&ctx.space.to_unit(b))) {
            basins.push(f.params.clone());
        }
    }
    let mut r = Reference::from_fit(best).expect("ok fit");
    ctx.start_effects_at(r.specimen.as_ref(), &r.params);
    r.basins = basins;
    r.fits = n;
    r.failed = failed;
    Ok(r)
}

/// The Fisher information of the free constants in the unit box at `params` under the error
/// model `noise`: JᵀJ of the whitened residuals (−2 ln L ≈ const + Σ r_w²), so that
/// Δ(−2 ln L) ≈ δᵀ I δ for a step δ in unit coordinates. With specimen effects (a
/// hierarchical context and the reference's `specimen`), the marginal information with the
/// effects integrated out ([`crate::likelihood::marginal_information`]). `None` if the
/// Jacobian could not be evaluated.
pub fn information(
    ctx: &Context,
    space: &ParamSpace,
    params: &[f64],
    noise: &ErrorModel,
    specimen: Option<&SpecimenFit>,
) -> Option<DMatrix<f64>> {
    if let (true, Some(sp)) = (ctx.hierarchical(), specimen) {
        return crate::likelihood::marginal_information(
            ctx.model,
            ctx.curves,
            space,
            params,
            sp,
            &ctx.settings,
            &ctx.ml,
        );
    }
    let problem = LikelihoodProblem::fixed(
        CreepProblem {
            objective: raw_objective(ctx.model, ctx.curves, &ctx.settings),
            space: space.clone(),
            jacobian: ctx.settings.jacobian,
        },
        noise.clone(),
    );
    let u = space.to_unit(params);
    let (m, n) = (problem.n_residuals(), problem.n_params());
    let mut r = vec![0.0; m];
    let mut jac = DMatrix::<f64>::zeros(m, n);
    match problem.residuals_and_jacobian(&u, &mut r, &mut jac) {
        Some(Ok(())) => {}
        Some(Err(_)) => return None,
        None => {
            problem.residuals(&u, &mut r).ok()?;
            let (lb, ub) = (vec![0.0; n], vec![1.0; n]);
            let mut ev = 0;
            crate::lsq::fd_jacobian(&problem, &u, &r, &lb, &ub, 1e-6, &mut jac, &mut ev).ok()?;
        }
    }
    let i = crate::lsq::gram(&jac);
    i.iter().all(|v| v.is_finite()).then_some(i)
}

/// A covariance from an information matrix: the pseudo-inverse (eigenvalues below 1e-12 of
/// the largest count as zero information, i.e. infinite variance along their direction,
/// reported as a variance of 1e12 there).
pub fn covariance(info: &DMatrix<f64>) -> DMatrix<f64> {
    let n = info.nrows();
    let sym = (info + info.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    let lmax = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let mut c = DMatrix::<f64>::zeros(n, n);
    for k in 0..n {
        let l = eig.eigenvalues[k];
        let inv = if l > 1e-12 * lmax && l > 0.0 {
            1.0 / l
        } else {
            1e12
        };
        let v = eig.eigenvectors.column(k);
        c += v * v.transpose() * inv;
    }
    c
}

/// The likelihood-ratio thresholds of Δ(−2 ln L) for the 68.27 % and 95 % intervals: χ²₁
/// quantiles (1.0 and 3.841) when uncalibrated, else [`Thresholds::calibrated`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Thresholds {
    /// Threshold of the 68.27 % interval.
    pub t68: f64,
    /// Threshold of the 95 % interval.
    pub t95: f64,
    /// The 95 % threshold over χ²₁'s (1 when uncalibrated).
    pub factor: f64,
}

/// Coverage of the "68 %" interval: one standard deviation of a normal.
pub const LEVEL_68: f64 = 0.682_689_492_137_085_9;

impl Thresholds {
    /// χ²₁ quantiles scaled by `factor`.
    pub fn chi2(factor: f64) -> Thresholds {
        Thresholds {
            t68: factor * chi2_1(LEVEL_68),
            t95: factor * chi2_1(0.95),
            factor,
        }
    }

    /// The thresholds of a quantity whose likelihood-ratio statistic T has mean `mean_t` over
    /// `n` parametric-bootstrap replicates. T ≈ c·χ²₁ (Bartlett), and c is estimated by that
    /// mean: T/ĉ then follows F(1, n), exactly when the replicates' T are independent c·χ²₁,
    /// so the threshold at level p is ĉ·F₁,ₙ(p) — ĉ·χ²₁(p) would cover 93.6 %, not 95 %, with
    /// n = 20. Floored at χ²₁(p); uncalibrated (n = 0, or no finite mean): χ²₁.
    pub fn calibrated(mean_t: f64, n: usize) -> Thresholds {
        if n == 0 || !mean_t.is_finite() {
            return Thresholds::chi2(1.0);
        }
        let at = |p: f64| chi2_1(p).max(mean_t * f_1n(p, n));
        let t95 = at(0.95);
        Thresholds {
            t68: at(LEVEL_68),
            t95,
            factor: t95 / chi2_1(0.95),
        }
    }
}

/// Quantile of F(1, n) at probability `p`: the square of Student's t with n degrees of
/// freedom at (1 + p)/2.
pub fn f_1n(p: f64, n: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    match StudentsT::new(0.0, 1.0, n as f64) {
        Ok(t) => t.inverse_cdf(0.5 + 0.5 * p).powi(2),
        Err(_) => f64::NAN,
    }
}

/// Quantile of χ² with one degree of freedom at probability `p`.
pub fn chi2_1(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let z = Normal::standard().inverse_cdf(0.5 + 0.5 * p);
    z * z
}

/// Standard normal quantile.
pub fn normal_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi2_quantiles_are_the_textbook_values() {
        assert!((chi2_1(0.95) - 3.841_458_820_694_124).abs() < 1e-9);
        assert!((chi2_1(LEVEL_68) - 1.0).abs() < 1e-9);
        let t = Thresholds::chi2(1.5);
        assert!((t.t95 - 1.5 * 3.841_458_820_694_124).abs() < 1e-9);
    }

    #[test]
    fn f_quantiles_are_the_textbook_values() {
        // F(1, n) 95 % quantiles from the tables (Abramowitz & Stegun 26.6): n = 10, 20, 120.
        for (n, want) in [(10, 4.9646), (20, 4.3512), (120, 3.9201)] {
            assert!(
                (f_1n(0.95, n) - want).abs() < 1e-3,
                "n {n}: {}",
                f_1n(0.95, n)
            );
        }
        // Toward χ²₁ as n grows.
        assert!((f_1n(0.95, 100_000) - chi2_1(0.95)).abs() < 1e-3);
    }

    #[test]
    fn calibrated_thresholds_cover_at_their_level_when_t_is_a_scaled_chi2() {
        // T = c·χ²₁ with c = 2.3; each trial estimates c from n = 20 replicates and asks
        // whether a new T falls below the thresholds. The F rule covers at its level; the
        // mean-scaled χ² quantile (the rule before) falls short at 95 %.
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(90_017);
        let c = 2.3;
        let mut draw = || {
            let z: f64 = StandardNormal.sample(&mut rng);
            c * z * z
        };
        let (trials, n) = (40_000, 20);
        let (mut in95, mut in68, mut in95_chi) = (0, 0, 0);
        for _ in 0..trials {
            let mean = (0..n).map(|_| draw()).sum::<f64>() / n as f64;
            let th = Thresholds::calibrated(mean, n);
            let t = draw();
            in95 += usize::from(t <= th.t95);
            in68 += usize::from(t <= th.t68);
            in95_chi += usize::from(t <= mean * chi2_1(0.95));
        }
        let r = |k: usize| k as f64 / trials as f64;
        // Binomial sd at 40,000 trials: 0.0011 (95 %), 0.0023 (68 %).
        assert!((r(in95) - 0.95).abs() < 0.005, "F rule 95 %: {}", r(in95));
        assert!(
            (r(in68) - LEVEL_68).abs() < 0.01,
            "F rule 68 %: {}",
            r(in68)
        );
        assert!(r(in95_chi) < 0.945, "mean-scaled χ² 95 %: {}", r(in95_chi));
        // Uncalibrated and floored.
        assert_eq!(Thresholds::calibrated(f64::NAN, 20), Thresholds::chi2(1.0));
        assert_eq!(Thresholds::calibrated(2.0, 0), Thresholds::chi2(1.0));
        let low = Thresholds::calibrated(0.5, 20);
        assert_eq!((low.t68, low.t95), (chi2_1(LEVEL_68), chi2_1(0.95)));
    }

    #[test]
    fn covariance_inverts_a_regular_matrix_and_caps_a_singular_one() {
        let i = DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 3.0]);
        let c = covariance(&i);
        let id = &i * &c;
        assert!((id[(0, 0)] - 1.0).abs() < 1e-12 && id[(0, 1)].abs() < 1e-12);
        let s = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let c = covariance(&s);
        // Along (1, −1) no information: a huge variance.
        assert!(c[(0, 0)] > 1e10);
    }
}
