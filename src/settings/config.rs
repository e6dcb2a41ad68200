//! The run configuration: the TOML file (DESIGN.md §4, `docs/FORMATS.md`) and the command line
//! resolved ONCE into one validated, serialisable [`RunConfig`] that every command takes
//! (ripgrep's LowArgs → HiArgs: the file's raw form stays private to this module).
//!
//! Unknown keys are errors everywhere. Paths are resolved relative to the configuration
//! file's directory. Constants come out in the model's order. A base-model constant missing
//! from `[constants]` is an error; an extension's constant missing from it takes the
//! extension's documented default bounds and scale (no start), and [`RunConfig::warnings`]
//! says so. Errors read `FILE:LINE: field: what`.
//!
//! What identifies a run (the sweep journal's identity, `crate::identity`) is the
//! serialisation of this type minus the fields listed in [`IDENTITY_EXCLUDED`], so a setting
//! added here later is covered by construction.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::data::Condition;
use crate::data::{self, Dataset, LoadOptions};
use crate::error::{Error, Result};
use crate::lsq::LmOptions;
use crate::model::law::{self as laws, LawKind};
use crate::model::objective::{FitSettings, JacobianMethod, ParamSpace};
pub use crate::model::objective::{LifetimeTerm, ObjectiveKind};
use crate::model::{self, Model, Scale};
use crate::ode::OdeOptions;

/// Names of the extension catalogue (DESIGN.md §6): what `diagnose` tests. A model may also
/// take [`model::ext::FORMS`].
pub const EXTENSION_NAMES: &[&str] = model::ext::CATALOGUE;

/// Top-level fields of [`RunConfig`]'s serialisation that do not change any result and are
/// therefore left out of the run identity: where the configuration file is (`path`), the run
/// name (`name`, only a label and the default output folder), where the data files are
/// (`curves`, `ruptures`: their loaded content is in `data_hash` instead), and how and where
/// the run is carried out (`run`: output folder, threads, shard, progress bar, test stop).
/// `diagnose`, `predict` and `profile` are left out too: they keep no journal, and their
/// settings change no fit or sweep result.
pub const IDENTITY_EXCLUDED: &[&str] = &[
    "path", "name", "curves", "ruptures", "run", "diagnose", "predict", "profile", "outliers",
];

/// Which start points `fit` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum StartChoice {
    /// The configuration's start values (if all are given) and the computed initial guess.
    #[default]
    Both,
    /// Only the configuration's start values (an error if one is missing).
    Config,
    /// Only the computed initial guess.
    Guess,
}

/// One constant as the run uses it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstantConfig {
    /// Name, as in the model's [`model::ConstantSpec`].
    pub name: String,
    /// Physical unit, from the model (not a setting: not serialised).
    #[serde(skip)]
    pub unit: &'static str,
    /// Lower bound (the constant's unit).
    pub lb: f64,
    /// Upper bound.
    pub ub: f64,
    /// Start value, if the configuration gives one.
    pub start: Option<f64>,
    /// Scale in the optimiser.
    pub scale: Scale,
    /// Temperature law of the constant (`constant` unless declared; `constant` for the laws'
    /// own parameters). The bounds and start are those of its value at `T_ref`.
    #[serde(default)]
    pub law: LawKind,
    /// Held at `start` by the optimiser (a law parameter given as a number; every law
    /// parameter when the data have one temperature only).
    #[serde(default)]
    pub held: bool,
}

/// `[objective]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectiveConfig {
    /// What the local fits minimise: `eq8` (default) or `likelihood`. Under `likelihood`
    /// the lifetime weights do not enter (one fit per start, w = 1 reported).
    pub kind: ObjectiveKind,
    /// Floor of the rupture-time scatter (ln scale) of the `likelihood` objective. Default
    /// 0.01 (1 %, the best reproducibility of a rupture time).
    pub lifetime_sd_floor: f64,
    /// Most points per curve the run works on (0, the default: all): a longer curve is
    /// reduced as `diagnose` reduces it ([`crate::data::binned`]: the first point kept,
    /// the rest groups of consecutive points). A densely logged curve then weighs in the objective about as much as
    /// a digitised one, not by its point count (README, "Alloy 617").
    pub max_points: usize,
    /// Weights in [0, 1] applied to every curve alike; each gives one fit. Default 0.1, …, 1.0.
    pub w_grid: Vec<f64>,
    /// Explicit per-curve weight vectors (ascending-stress order), each weight in [0, 1];
    /// each gives one fit, in addition to `w_grid`. Default empty.
    pub w_sets: Vec<Vec<f64>>,
    /// Lifetime term side. Default `late`.
    pub lifetime_term: LifetimeTerm,
    /// Damage at rupture ω_f. Default 1/3.
    pub omega_f: f64,
    /// Specimen effects of the likelihood (random effects integrated out, [`crate::likelihood`]):
    /// each curve's own creep-rate factor (`rate`) and ductility factor (`ductility`), their
    /// scatter between specimens estimated. `"auto"` (default): both when the data have
    /// replicates (two or more specimens at one temperature and stress), none otherwise —
    /// with one specimen per condition a specimen's own rate or ductility cannot be told
    /// from the stress and temperature dependence of the constants. A list (`["rate"]`,
    /// `["rate", "ductility"]`, `["rate", "ductility", "coarsening"]`, `[]`) asks for exactly
    /// those (`coarsening`: a factor on the softening constant Kc, only by name).
    pub specimen_effects: SpecimenEffects,
    /// How the specimens' scatter is estimated. `"beyond_stress_trend"` (default since
    /// 2026-12-04): by restricted likelihood from how the factors differ beyond a straight
    /// line in ln σ at each temperature, and `diagnose` compares every model at the base
    /// model's scatter, so that an effect that follows stress shows as misfit of the base
    /// instead of as a larger scatter (docs/SPECIMENS.md, "The scatter beyond the stress
    /// trend"). `"likelihood"`: by maximum likelihood over all the specimens' factors (the
    /// default before). Left out of the run's identity when `likelihood`, as every run before
    /// the change recorded it, so that those runs keep their run ids and a folder of one
    /// estimate is never resumed with the other.
    #[serde(skip_serializing_if = "SpecimenScatter::is_likelihood")]
    pub specimen_scatter: SpecimenScatter,
}

pub use crate::likelihood::SpecimenScatter;

impl ObjectiveConfig {
    /// The specimen effects for `curves` with the configured scatter estimate, and a note for
    /// the user when `auto` left them out.
    pub fn specimen_options(
        &self,
        curves: &[crate::data::Curve],
    ) -> (crate::likelihood::SpecimenOptions, Option<String>) {
        let (o, note) = self.specimen_effects.resolve(curves, self.specimen_scatter);
        (o.with_scatter(self.specimen_scatter), note)
    }

    /// The specimen effects this configuration asks for on `curves` (`auto` resolved) that
    /// the local fits of `fit` and `sweep` leave out: all of them under eq. 8, which has
    /// none; under the likelihood, those of `sweep` only (`fit` adds them to its best start).
    pub fn effects_left_out(
        &self,
        curves: &[crate::data::Curve],
        command: LocalFits,
    ) -> Vec<crate::likelihood::EffectKind> {
        match (self.kind, command) {
            (ObjectiveKind::Likelihood, LocalFits::Fit) => Vec::new(),
            _ => self.specimen_options(curves).0.kinds(),
        }
    }
}

/// The command whose local fits [`objective_note`] speaks of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocalFits {
    /// `fit`: its best start carries the effects under the likelihood.
    Fit,
    /// `sweep`: no local fit carries effects.
    Sweep,
}

/// What the objective of `fit`'s or `sweep`'s local fits leaves out, for a user comparing
/// its number with another command's: a sentence where the configuration's specimen effects
/// `left_out` ([`ObjectiveConfig::effects_left_out`]) are not fitted, else `None`. Under the
/// likelihood only `sweep` leaves them out.
pub fn objective_note(
    kind: ObjectiveKind,
    left_out: &[crate::likelihood::EffectKind],
) -> Option<String> {
    if left_out.is_empty() {
        return None;
    }
    let kinds = left_out
        .iter()
        .map(|k| k.name())
        .collect::<Vec<_>>()
        .join(" and ");
    Some(match kind {
        ObjectiveKind::Likelihood => format!(
            "the objective is −2 ln L of the population model without specimen effects: the configuration's {kinds} effects are not fitted by sweep's local fits; `fit` adds them to its best start, and its summary.json → specimens.neg2ll_without_effects is the number to compare with this one"
        ),
        ObjectiveKind::Eq8 => format!(
            "the objective is eq. 8, which has no specimen effects: every specimen is fitted as the population's, and the configuration's {kinds} effects (specimen_effects, on these data) are not fitted; they belong to the likelihood, which `diagnose`, `profile` and `predict --intervals` use, and `fit` fits them with [objective] kind = \"likelihood\""
        ),
    })
}

/// `[objective] specimen_effects`: `"auto"` or a list of kinds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SpecimenEffects {
    /// `"auto"`: both kinds with replicates in the data; without, both where the scatter is
    /// estimated beyond the stress trend from at least [`MIN_DOF_BEYOND_TREND`] degrees of
    /// freedom, none otherwise.
    Auto(AutoWord),
    /// Exactly these kinds.
    Kinds(Vec<crate::likelihood::EffectKind>),
}

/// The word `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    /// `auto`.
    Auto,
}

/// Fewest degrees of freedom beyond the within-temperature stress trend
/// ([`crate::specimen::dof_beyond_trend`]) at which `auto` fits specimen effects to data
/// without replicates, with `specimen_scatter = "beyond_stress_trend"`: with one, the scatter
/// is a single specimen's departure from the line, and its interval has no upper end.
pub const MIN_DOF_BEYOND_TREND: usize = 2;

impl SpecimenEffects {
    /// The effects for `curves` when the scatter is estimated by `scatter`, and a note for the
    /// user when `auto` decided from the design: effects left out, or fitted without replicates.
    /// Without replicates the scatter can be told from the constants' stress dependence only
    /// beyond it: a null set with specimen scatter and one specimen per stress, fitted
    /// without effects, reads the specimens' differences as misfit (docs/SPECIMENS.md,
    /// "Session 63").
    pub fn resolve(
        &self,
        curves: &[crate::data::Curve],
        scatter: crate::likelihood::SpecimenScatter,
    ) -> (crate::likelihood::SpecimenOptions, Option<String>) {
        use crate::likelihood::{EffectKind, SpecimenOptions, SpecimenScatter};
        match self {
            SpecimenEffects::Auto(_) => {
                let dof = crate::specimen::dof_beyond_trend(
                    curves.iter().map(|c| (c.temperature_c, c.stress_mpa)),
                );
                if crate::specimen::has_replicates(curves) {
                    (SpecimenOptions::BOTH, None)
                } else if scatter == SpecimenScatter::BeyondStressTrend
                    && dof >= MIN_DOF_BEYOND_TREND
                {
                    (
                        SpecimenOptions::BOTH,
                        Some(format!("no two specimens share a temperature and stress: each specimen's creep rate and ductility factors are fitted, their scatter estimated from how they differ beyond a level and a straight line in ln stress at each temperature ({dof} degrees of freedom at most); a stress or temperature dependence the model misses can still go into the factors, at the cost of their penalty at that scatter (the Specimens section of a diagnosis tests whether they follow stress within temperatures and whether they differ between temperatures; their mean per temperature is in summary.json → specimens.by_temperature)")),
                    )
                } else {
                    (
                        SpecimenOptions::NONE,
                        Some("no two specimens share a temperature and stress: specimen-to-specimen scatter cannot be told from the stress and temperature dependence of the constants, so the likelihood treats every specimen as the population's (set [objective] specimen_effects to fit it anyway, or specimen_scatter = \"beyond_stress_trend\" to fit it beyond the stress trend where the data have the degrees of freedom)".into()),
                    )
                }
            }
            SpecimenEffects::Kinds(k) => (
                SpecimenOptions {
                    rate: k.contains(&EffectKind::Rate),
                    ductility: k.contains(&EffectKind::Ductility),
                    coarsening: k.contains(&EffectKind::Coarsening),
                    beyond_trend: false,
                },
                None,
            ),
        }
    }
}

impl Default for ObjectiveConfig {
    fn default() -> Self {
        ObjectiveConfig {
            kind: ObjectiveKind::Eq8,
            lifetime_sd_floor: crate::errmodel::DEFAULT_LIFETIME_SD_FLOOR,
            max_points: 0,
            w_grid: (1..=10).map(|k| k as f64 / 10.0).collect(),
            w_sets: Vec::new(),
            lifetime_term: LifetimeTerm::Late,
            omega_f: 1.0 / 3.0,
            specimen_effects: SpecimenEffects::Auto(AutoWord::Auto),
            specimen_scatter: SpecimenScatter::BeyondStressTrend,
        }
    }
}

impl ObjectiveConfig {
    /// All per-curve weight vectors of the run: first each `w_grid` value repeated for every
    /// curve, then the `w_sets`. A `w_sets` entry whose length is not `n_curves` is an error
    /// (reported against `path`, the configuration file).
    pub fn weight_vectors(&self, n_curves: usize, path: &Path) -> Result<Vec<Vec<f64>>> {
        if self.kind == ObjectiveKind::Likelihood {
            // The likelihood weighs the lifetimes by their estimated scatter, not by w.
            return Ok(vec![vec![1.0; n_curves]]);
        }
        let mut out: Vec<Vec<f64>> = self.w_grid.iter().map(|&w| vec![w; n_curves]).collect();
        for (k, set) in self.w_sets.iter().enumerate() {
            if set.len() != n_curves {
                return Err(Error::config(
                    path,
                    format!(
                        "objective.w_sets[{k}]: has {} weights but the data have {n_curves} curves",
                        set.len()
                    ),
                ));
            }
            out.push(set.clone());
        }
        Ok(out)
    }
}

/// `[sweep]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SweepConfig {
    /// Number of Latin hypercube starts (`--starts` overrides). Default 256.
    pub starts: usize,
    /// Seed of the start sequence (`--seed` overrides). Default 1.
    pub seed: u64,
    /// Also start from the configured start / initial guess. Default true.
    pub include_guess: bool,
    /// Move starts that cannot be evaluated toward an evaluable point
    /// ([`crate::fit::repair_starts`]). Default true; false keeps every Latin-hypercube
    /// point where it was drawn (its fit then fails at the start and is reported as failed).
    pub repair: bool,
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            starts: 256,
            seed: 1,
            include_guess: true,
            repair: true,
        }
    }
}

/// `fit`'s own choices (command line).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitConfig {
    /// Start points of `fit` (`--start`).
    pub starts: StartChoice,
}

/// Every numerical setting of the integrator and of the local least-squares fits, resolved:
/// the `[solver]` keys of the file and the fixed values of the ones the file does not expose
/// ([`LmOptions`] and [`OdeOptions`] are derived from this in one place).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Relative tolerance of the integrator. Default 1e-8, from the accuracy study in README.md
    /// (`scripts/tolerance_study.sh`): the objective is then within 1e-7 relative of its
    /// tight-tolerance value and the fit reaches the same minimum to 1e-7, 1.7× faster than
    /// at 1e-10.
    pub rtol: f64,
    /// Absolute tolerance of the integrator (strain fraction). Default 1e-13.
    pub atol: f64,
    /// Most integrator steps (accepted + rejected) per simulation (not in the file).
    pub max_steps: usize,
    /// Iteration limit of a local fit. Default 200.
    pub max_iterations: usize,
    /// Relative objective change at which a local fit has converged. Default 1e-8: the
    /// objective itself is accurate to about 1e-7 at the default `rtol`, and smaller changes
    /// only chase integration error (README.md, "Speed").
    pub ftol: f64,
    /// Step convergence of a local fit, relative (not in the file).
    pub xtol: f64,
    /// Gradient convergence of a local fit, relative (not in the file).
    pub gtol: f64,
    /// Finite-difference step in the unit box (not in the file).
    pub fd_step: f64,
    /// Initial Levenberg–Marquardt damping, relative to max diag JᵀJ (not in the file).
    pub lambda0: f64,
    /// Largest damping before a fit counts as stalled (not in the file).
    pub lambda_max: f64,
    /// Geodesic acceleration of the Levenberg–Marquardt steps (Transtrum & Sethna 2012):
    /// follows the curved, nearly flat valleys of this objective in a third of the
    /// iterations. Default true.
    pub geodesic: bool,
    /// Largest accepted ratio 2‖a‖/‖v‖ of geodesic acceleration to velocity (Transtrum &
    /// Sethna's 0.75; 0.5 and 1.5 measured no better on the 560 °C sweep; not in the file).
    pub geodesic_alpha: f64,
    /// Finite-difference step along v for the acceleration, fraction of v (not in the file).
    pub geodesic_h: f64,
    /// Jacobian of the local fits: "sensitivity" (default) or "finite_difference".
    pub jacobian: JacobianMethod,
}

impl Default for SolverConfig {
    fn default() -> Self {
        let lm = LmOptions::default();
        let ode = OdeOptions::default();
        SolverConfig {
            rtol: 1e-8,
            atol: ode.atol,
            max_steps: ode.max_steps,
            max_iterations: lm.max_iterations,
            ftol: 1e-8,
            xtol: lm.xtol,
            gtol: lm.gtol,
            fd_step: lm.fd_step,
            lambda0: lm.lambda0,
            lambda_max: lm.lambda_max,
            geodesic: true,
            geodesic_alpha: 0.75,
            geodesic_h: lm.geodesic_h,
            jacobian: JacobianMethod::default(),
        }
    }
}

impl SolverConfig {
    /// Levenberg–Marquardt options of every local fit.
    pub fn lm_options(&self) -> LmOptions {
        LmOptions {
            max_iterations: self.max_iterations,
            xtol: self.xtol,
            ftol: self.ftol,
            gtol: self.gtol,
            fd_step: self.fd_step,
            lambda0: self.lambda0,
            lambda_max: self.lambda_max,
            geodesic: self.geodesic.then_some(self.geodesic_alpha),
            geodesic_h: self.geodesic_h,
            plateau: None,
            gain_to_come: None,
            cut_overdamped: false,
        }
    }
    /// Integration options (the horizon `t_end` is set per curve by its user).
    pub fn ode_options(&self) -> OdeOptions {
        OdeOptions {
            rtol: self.rtol,
            atol: self.atol,
            max_steps: self.max_steps,
            ..OdeOptions::default()
        }
    }
}

/// `[diagnose]`: the calibrated model comparison of `creepfit diagnose` (README, "Diagnose").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DiagnoseConfig {
    /// False-alarm level of the family of tests (extension likelihood ratios and the base
    /// model's goodness of fit, Holm). Default 0.05.
    pub alpha: f64,
    /// Most parametric-bootstrap replicates per test family (fewer when every test is
    /// clearly not significant; Besag–Clifford stopping). Default [`DEFAULT_BOOTSTRAP`]: the
    /// smallest that can reject at Holm's first threshold α/m at α = 0.05 over every
    /// catalogued extension and two goodness-of-fit tests (m = 8: 159 replicates, p ≥ 1/160).
    pub bootstrap: usize,
    /// Most replicates of a test whose p-value after `bootstrap` replicates is at most α/2
    /// (Besag–Clifford stopping still applies): the decisions where `bootstrap` replicates
    /// resolve too coarsely (Holm's α/8 … α/2 are 1–4 replicates in 160) are taken on more.
    /// Default (`None`): no extension, every test at most `bootstrap`. With 639 (four times
    /// the resolution) the 200-set null battery gave 8 false alarms (4.0 %) against 7, but a
    /// set with a significant effect takes 2–4 times as long, so it is opt-in
    /// (docs/SPECIMENS.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap_extended: Option<usize>,
    /// Latin-hypercube starts per model on the data (plus the initial guess). Default 16.
    pub starts: usize,
    /// Warm starts per model and bootstrap replicate: the best distinct local optima found
    /// on the data (the fitted optimum first). Default 3.
    pub replicate_basins: usize,
    /// Random starts per model and bootstrap replicate, besides the warm starts. Default 0:
    /// measured on the 560 °C data, 4 of 20 random starts reach the best basin and one costs
    /// 7× a warm start; the data's own basins are the better use of the time.
    pub replicate_starts: usize,
    /// Seed of the starts and of the bootstrap. Default 1.
    pub seed: u64,
    /// Floor of the rupture-time scatter, ln scale (1 % by default: the best
    /// reproducibility of a rupture time).
    pub lifetime_sd_floor: f64,
    /// Extensions to test (default: the whole catalogue, less those the model already has).
    pub extensions: Vec<String>,
    /// Most points per curve `diagnose` works on: a longer curve is averaged in groups of
    /// consecutive points (time and strain; the first point is kept as it is). Averaging keeps
    /// what a curve says about a smooth model, and makes the verdict independent of how
    /// densely a curve was logged. Default 100: digitised curves (the seed's have 36–70
    /// points) are used as they are, logged ones (hundreds to thousands) are reduced.
    pub max_points: usize,
    /// How a longer curve is reduced: `local_quadratic` (default: each group's local
    /// quadratic at its mean time), `means` (each group's mean, compared with the model's
    /// mean over the same readings: a mean's reading error and no curvature bias) or
    /// `strain_means` (the same over groups spanning equal strain ranges, so that the
    /// primary and tertiary stages keep their readings; each point weighed by its group's
    /// size).
    #[serde(skip_serializing_if = "crate::data::Reduction::is_default")]
    pub reduction: crate::data::Reduction,
    /// How `strain_means`' group means are weighed: `white` (default: √m, a mean of m
    /// readings with 1/m of a reading's error variance; its null battery is calibrated) or
    /// `estimate` (the share ρ that averaging does not shrink, estimated from the base fit;
    /// experimental, its false alarms are not calibrated: docs/SPECIMENS.md, "Session 75").
    #[serde(skip_serializing_if = "crate::data::MisfitShare::is_default")]
    pub misfit_share: crate::data::MisfitShare,
}

/// Default most bootstrap replicates of `diagnose`: 20 m − 1 for m = the catalogued
/// extensions + 2 goodness-of-fit tests, so that the smallest p-value 1/(20 m) reaches
/// Holm's first threshold α/m at α = 0.05 (119 with four extensions, 159 with six).
pub const DEFAULT_BOOTSTRAP: usize = 20 * (EXTENSION_NAMES.len() + 2) - 1;

impl Default for DiagnoseConfig {
    fn default() -> Self {
        DiagnoseConfig {
            alpha: 0.05,
            bootstrap: DEFAULT_BOOTSTRAP,
            bootstrap_extended: None,
            starts: 16,
            replicate_basins: 3,
            replicate_starts: 0,
            seed: 1,
            lifetime_sd_floor: crate::errmodel::DEFAULT_LIFETIME_SD_FLOOR,
            extensions: Vec::new(),
            max_points: 100,
            reduction: crate::data::Reduction::LocalQuadratic,
            misfit_share: crate::data::MisfitShare::White,
        }
    }
}

impl DiagnoseConfig {
    /// The most replicates of a test close to significance: `bootstrap_extended`, by default
    /// (and never fewer than) `bootstrap`.
    pub fn most_replicates(&self) -> usize {
        self.bootstrap_extended
            .unwrap_or(self.bootstrap)
            .max(self.bootstrap)
    }

    /// Check the values; `Err` names the field.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        let bad = |field: &str, what: String| Err(invalid(format!("diagnose.{field}"), what));
        if !(self.alpha > 0.0 && self.alpha <= 0.5) {
            return bad("alpha", format!("must be in (0, 0.5] (got {})", self.alpha));
        }
        if self.max_points < 10 {
            return bad(
                "max_points",
                format!("must be at least 10 (got {})", self.max_points),
            );
        }
        if self.replicate_basins == 0 {
            return bad(
                "replicate_basins",
                "must be at least 1 (the fitted optimum)".into(),
            );
        }
        if !(self.lifetime_sd_floor > 0.0 && self.lifetime_sd_floor.is_finite()) {
            return bad(
                "lifetime_sd_floor",
                format!("must be positive (got {})", self.lifetime_sd_floor),
            );
        }
        for (i, e) in self.extensions.iter().enumerate() {
            if !EXTENSION_NAMES.contains(&e.as_str()) {
                return bad(
                    "extensions",
                    format!(
                        "unknown extension '{e}' (known: {})",
                        EXTENSION_NAMES.join(", ")
                    ),
                );
            }
            if self.extensions[..i].contains(e) {
                return bad("extensions", format!("'{e}' is listed twice"));
            }
        }
        // Holm's first threshold is α/m over m = extensions + 2 goodness-of-fit tests; the
        // smallest bootstrap p-value is 1/(B + 1).
        let m = if self.extensions.is_empty() {
            EXTENSION_NAMES.len() + 2
        } else {
            self.extensions.len() + 2
        };
        let need = (m as f64 / self.alpha - 1e-9).ceil() as usize - 1;
        if self.bootstrap < need {
            return bad(
                "bootstrap",
                format!(
                    "{} replicates can never reject at alpha = {} over {m} tests (the smallest \
                     p-value is 1/(bootstrap + 1)); use at least {need}",
                    self.bootstrap, self.alpha
                ),
            );
        }
        Ok(())
    }
}

/// `[predict]`: what `creepfit predict` predicts when the command line does not say.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PredictConfig {
    /// Conditions to predict (`at = ["575:100", "560:70"]` in the file: °C:MPa); `--at`
    /// replaces them.
    pub at: Vec<Condition>,
    /// Degree of the Larson–Miller master curve in log10 σ. Default 2.
    pub lmp_degree: usize,
    /// Intervals beside each prediction (`--intervals`): the 95 % prediction interval of a
    /// new test and the 95 % confidence interval of the model's prediction, from the profile
    /// likelihood under the error model (README, "How sure"). Default false.
    #[serde(default)]
    pub intervals: bool,
    /// Tensile strength per temperature (`tensile_strength = ["850:260", …]` in the file:
    /// °C:MPa), for the Wilshire baseline of `predict` and `holdout`; empty: no Wilshire.
    #[serde(default)]
    pub tensile_strength: Vec<crate::baseline::TensileStrength>,
    /// Tests to predict and score (`tests = "campaign.csv"` in the file, relative to it: a
    /// rupture-times file, as `--tests` reads), instead of `at`; `--tests` and `--at` replace
    /// it. `None`: none.
    #[serde(default)]
    pub tests: Option<PathBuf>,
}

impl Default for PredictConfig {
    fn default() -> Self {
        PredictConfig {
            at: Vec::new(),
            lmp_degree: crate::lmp::DEFAULT_DEGREE,
            intervals: false,
            tensile_strength: Vec::new(),
            tests: None,
        }
    }
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawPredict {
    #[serde(default)]
    at: Vec<String>,
    lmp_degree: Option<usize>,
    intervals: Option<bool>,
    #[serde(default)]
    tensile_strength: Vec<String>,
    tests: Option<String>,
}

/// `[profile]`: the profile likelihoods, intervals and prediction intervals of
/// `creepfit profile` (README, "How sure").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProfileConfig {
    /// Latin-hypercube starts of the maximum-likelihood multistart (besides the configured
    /// start and the initial guess). Default 16.
    pub starts: usize,
    /// Seed of the starts and of the bootstraps. Default 1.
    pub seed: u64,
    /// Floor of the rupture-time scatter, ln scale. Default 0.01.
    pub lifetime_sd_floor: f64,
    /// Parametric-bootstrap replicates that calibrate the likelihood-ratio thresholds
    /// (0: plain χ² thresholds). Default 20.
    pub calibrate: usize,
    /// Untested stresses (MPa, at the data's temperature) to give prediction intervals at.
    /// Default none.
    #[serde(rename = "predict_stress_MPa")]
    pub predict_stress_mpa: Vec<f64>,
    /// Times of the band around each predicted curve (evenly spaced fractions of the
    /// predicted life). Default 9.
    pub band_points: usize,
}

impl Default for ProfileConfig {
    fn default() -> Self {
        ProfileConfig {
            starts: 16,
            seed: 1,
            lifetime_sd_floor: crate::errmodel::DEFAULT_LIFETIME_SD_FLOOR,
            calibrate: 20,
            predict_stress_mpa: Vec::new(),
            band_points: 9,
        }
    }
}

impl ProfileConfig {
    /// Check the values; `Err` names the field.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        let bad = |field: &str, what: String| Err(invalid(format!("profile.{field}"), what));
        if !(self.lifetime_sd_floor > 0.0 && self.lifetime_sd_floor.is_finite()) {
            return bad(
                "lifetime_sd_floor",
                format!("must be positive (got {})", self.lifetime_sd_floor),
            );
        }
        if self.calibrate > 0 && self.calibrate < 10 {
            return bad(
                "calibrate",
                format!(
                    "0 (no calibration) or at least 10 replicates (got {})",
                    self.calibrate
                ),
            );
        }
        if let Some(s) = self
            .predict_stress_mpa
            .iter()
            .find(|s| !(s.is_finite() && **s > 0.0))
        {
            return bad(
                "predict_stress_MPa",
                format!("stresses must be positive and finite (got {s})"),
            );
        }
        if self.band_points > 50 {
            return bad(
                "band_points",
                format!("at most 50 (got {})", self.band_points),
            );
        }
        Ok(())
    }
}

/// How and where a run is carried out: nothing here changes a result, so the run identity
/// leaves it out ([`IDENTITY_EXCLUDED`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunOptions {
    /// Output folder (`--out`); `None`: `results/<name>/<command>/`.
    pub out: Option<PathBuf>,
    /// Worker threads of a sweep (`--threads`); `None`: all cores.
    pub threads: Option<usize>,
    /// (I, N): the I-th (1-based) of N disjoint parts of a sweep (`--shard I/N`).
    pub shard: Option<(usize, usize)>,
    /// Stop (as if interrupted) after this many new fits: for tests of resumption.
    pub stop_after: Option<usize>,
    /// Draw a progress bar (only when stderr is a terminal).
    pub progress: bool,
}

/// What the command line may set over the file; `None` keeps the file's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// `--starts`: Latin-hypercube starts of a sweep.
    pub starts: Option<usize>,
    /// `--seed`: seed of the sweep's starts.
    pub seed: Option<u64>,
    /// `--w`: one lifetime weight for every curve, replacing `w_grid` and `w_sets`.
    pub w: Option<f64>,
    /// `--start`: `fit`'s start points.
    pub fit_starts: Option<StartChoice>,
    /// `diagnose`'s command-line settings.
    pub diagnose: DiagnoseOverrides,
    /// `--at`: conditions of `predict`, replacing `[predict] at`.
    pub predict_at: Option<Vec<Condition>>,
    /// `--intervals`: intervals beside `predict`'s predictions, over `[predict] intervals`.
    pub predict_intervals: Option<bool>,
    /// Where and how to run (never part of the identity).
    pub run: RunOptions,
}

/// What `diagnose`'s command line may set over `[diagnose]`; `None` keeps the file's value.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DiagnoseOverrides {
    /// `--starts`: Latin-hypercube starts per model.
    pub starts: Option<usize>,
    /// `--seed`: seed of the starts and the bootstrap.
    pub seed: Option<u64>,
    /// `--bootstrap`: most bootstrap replicates.
    pub bootstrap: Option<usize>,
    /// `--bootstrap-extended`: most replicates of a test close to significance.
    pub bootstrap_extended: Option<usize>,
    /// `--alpha`: false-alarm level.
    pub alpha: Option<f64>,
}

/// The resolved, validated run configuration: built once from the TOML file and the command
/// line (and bound to the content hash of its data by [`RunConfig::with_data`]), then passed
/// to every command. Serialisable; see [`IDENTITY_EXCLUDED`] for what the run identity skips.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// The configuration file itself.
    pub path: PathBuf,
    /// Run name (outputs go to `results/<name>/`). Default: the file's stem. No path
    /// separators and no `..`.
    pub name: String,
    /// Curves CSV, resolved against the configuration's directory.
    pub curves: PathBuf,
    /// Ruptures CSV, resolved against the configuration's directory.
    pub ruptures: PathBuf,
    /// Content hash of the loaded data ([`crate::data::data_hash`]); empty until
    /// [`RunConfig::with_data`] binds the configuration to its data.
    pub data_hash: String,
    /// Keep only curves at this temperature (°C).
    #[serde(rename = "temperature_C")]
    pub temperature_c: Option<f64>,
    /// Reference temperature of the temperature laws, °C: the constants' bounds and starts
    /// are their values there. Default, when some constant has a law: the mean test
    /// temperature of the data (resolved by [`RunConfig::with_data`]).
    #[serde(rename = "T_ref")]
    pub t_ref: Option<f64>,
    /// Whether `t_ref` was resolved from the data ([`RunConfig::with_data`]) rather than
    /// given: a fit on other data (a hold-out's training data) resolves it from those
    /// ([`RunConfig::for_data`]). Not part of the run identity (`t_ref` is).
    #[serde(skip)]
    pub t_ref_from_data: bool,
    /// Model registry name. Default `khd`.
    pub model: String,
    /// Extension names (DESIGN.md §6), in the order given.
    pub extensions: Vec<String>,
    /// Tests declared interrupted: `"T:σ"`, `"T:σ:specimen"`, or a bare stress (MPa) when
    /// the data are at one temperature ([`data::interrupted_flags`]).
    pub interrupted: Vec<data::Interrupted>,
    /// What loading does with gross outliers of a curve (`refuse`, `drop`, `keep`; see
    /// [`data::outlier_z`]). Not part of the run identity: the points it drops change the
    /// data, whose hash is.
    #[serde(default)]
    pub outliers: data::OutlierPolicy,
    /// Constants in the model's order (with extension defaults filled in).
    pub constants: Vec<ConstantConfig>,
    /// `[objective]`, with `--w` applied.
    pub objective: ObjectiveConfig,
    /// `[solver]`, every setting resolved.
    pub solver: SolverConfig,
    /// `[sweep]`, with `--starts` and `--seed` applied.
    pub sweep: SweepConfig,
    /// `fit`'s choices.
    pub fit: FitConfig,
    /// `[diagnose]`, with the command line applied. Not part of the run identity: no
    /// journal is kept for `diagnose`, and these settings change no fit or sweep.
    pub diagnose: DiagnoseConfig,
    /// `[predict]`, with `--at` applied. Not part of the run identity (it changes no fit).
    #[serde(default)]
    pub predict: PredictConfig,
    /// `[profile]`. Not part of the run identity: no journal is kept for `profile`, and these
    /// settings change no fit or sweep.
    #[serde(default)]
    pub profile: ProfileConfig,
    /// Where and how the run is carried out (not part of the identity).
    pub run: RunOptions,
    /// Notes for the user found while resolving (e.g. an extension constant that took its
    /// default bounds); printed on stderr by the binary. Not a setting.
    #[serde(skip)]
    pub warnings: Vec<String>,
}

/// What the likelihood analyses (`profile`, `predict --intervals`, coverage) take, built once
/// from the configuration on its data by [`RunConfig::likelihood_setup`].
pub struct LikelihoodSetup {
    /// Bounds, scales and held constants.
    pub space: ParamSpace,
    /// Objective, integrator and solver settings.
    pub settings: FitSettings,
    /// The maximum-likelihood options (`[profile]`'s rupture-time floor, the specimen
    /// effects resolved on the data).
    pub ml: crate::likelihood::MlOptions,
    /// Whether `specimen_effects = "auto"` chose the effects of `ml` (a zero scatter beyond
    /// the stress trend then leaves them out, [`crate::likelihood::scatter_at_zero`]).
    pub auto_effects: bool,
    /// `[profile]`: thresholds, calibration, steps.
    pub profile: ProfileConfig,
}

/// What `predict` takes, built once from the configuration on its data by
/// [`RunConfig::predict_setup`].
pub struct PredictSetup {
    /// The integrator's settings (the horizon is set per condition).
    pub ode: OdeOptions,
    /// Rupture damage of the loads.
    pub omega_f: f64,
    /// `[predict]`: the conditions, intervals or not, the baselines' settings.
    pub predict: PredictConfig,
    /// Whether a constant follows a temperature law (what counts as tested).
    pub has_laws: bool,
    /// The intervals' likelihood setup.
    pub likelihood: LikelihoodSetup,
}

/// A model `diagnose` compares: the configured model (`base`) or it with one extension more,
/// on its parameter space.
pub struct ModelVariant {
    /// `base`, the extension's name, or `bare` (the family without extensions).
    pub name: String,
    /// The model (with the configuration's temperature laws).
    pub model: Box<dyn Model>,
    /// Bounds, scales and held constants.
    pub space: ParamSpace,
    /// Names of the constants this variant adds to the base model.
    pub extra: Vec<String>,
}

/// What `diagnose` takes, built once from the configuration by [`RunConfig::diagnose_setup`]
/// (its `[diagnose]` settings come beside it, so the command line's overrides apply).
pub struct DiagnoseSetup {
    /// The base model first, then each extension tried.
    pub variants: Vec<ModelVariant>,
    /// The family's model without extensions: the initial guess is made on it.
    pub bare: ModelVariant,
    /// Objective, integrator and solver settings.
    pub settings: FitSettings,
    /// Which specimen effects the likelihood carries (resolved on the curves diagnosed).
    pub specimen_effects: SpecimenEffects,
    /// How their scatter is estimated.
    pub specimen_scatter: SpecimenScatter,
    /// The configured model's extensions.
    pub extensions: Vec<String>,
}

/// What `fit` takes: the calibration of one data set, built once from the configuration by
/// [`RunConfig::calibration`] (ripgrep's LowArgs → HiArgs: the resolved object hands out
/// built things; the library never reads the whole configuration).
pub struct Calibration {
    /// The model (family, extensions, temperature laws).
    pub model: Box<dyn Model>,
    /// Bounds, scales and held constants.
    pub space: ParamSpace,
    /// Objective, integrator and solver settings.
    pub settings: FitSettings,
    /// Which starts: the given one, the computed initial guess, or both.
    pub start_choice: StartChoice,
    /// The configuration's start (model order) when every constant has one.
    pub given_start: Option<Vec<f64>>,
    /// Seed of the Latin-hypercube starts (a multistart fit, the fallback anchor).
    pub seed: u64,
    /// Every per-curve lifetime-weight vector to fit with (one under the likelihood).
    pub weights: Vec<Vec<f64>>,
    /// The specimen effects the likelihood fits after the best fit (none under eq. 8).
    pub specimen_effects: crate::likelihood::SpecimenOptions,
    /// Why there are none (`auto` without replicates), for the user.
    pub specimen_note: Option<String>,
    /// The configuration file, named in errors.
    pub source: PathBuf,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    name: Option<String>,
    curves: PathBuf,
    ruptures: PathBuf,
    #[serde(rename = "temperature_C")]
    temperature_c: Option<f64>,
    #[serde(rename = "T_ref")]
    t_ref: Option<f64>,
    #[serde(default = "default_model")]
    model: String,
    #[serde(default)]
    extensions: Vec<String>,
    #[serde(default)]
    interrupted: Vec<data::Interrupted>,
    #[serde(default)]
    outliers: data::OutlierPolicy,
    #[serde(default)]
    constants: BTreeMap<String, RawConstant>,
    #[serde(default)]
    objective: ObjectiveConfig,
    #[serde(default)]
    sweep: SweepConfig,
    #[serde(default)]
    solver: RawSolver,
    #[serde(default)]
    diagnose: DiagnoseConfig,
    #[serde(default)]
    predict: RawPredict,
    #[serde(default)]
    profile: ProfileConfig,
}

fn default_model() -> String {
    "khd".to_string()
}

/// A constant as the file gives it: its box, start and scale, its temperature law and the
/// law's parameter under the parameter's name (e.g. `Q = { lb = 200, ub = 500 }`). Unknown
/// keys land in `rest` and are reported by name (serde cannot deny them next to a flattened
/// map).
#[derive(Deserialize)]
struct RawConstant {
    lb: f64,
    ub: f64,
    start: Option<f64>,
    scale: Option<Scale>,
    law: Option<LawKind>,
    #[serde(flatten)]
    rest: BTreeMap<String, RawLawParam>,
}

/// A law parameter: a number (held at that value) or a box like a constant's.
enum RawLawParam {
    Held(f64),
    Free(RawBox),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBox {
    lb: f64,
    ub: f64,
    start: Option<f64>,
    scale: Option<Scale>,
}

impl<'de> Deserialize<'de> for RawLawParam {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RawLawParam;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a number (the parameter held at it) or a table { lb, ub[, start][, scale] }",
                )
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Self::Value, E> {
                Ok(RawLawParam::Held(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Self::Value, E> {
                Ok(RawLawParam::Held(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Self::Value, E> {
                Ok(RawLawParam::Held(v as f64))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                RawBox::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(RawLawParam::Free)
            }
        }
        d.deserialize_any(V)
    }
}

/// `[solver]` as the file gives it: the keys a user may set.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    rtol: Option<f64>,
    atol: Option<f64>,
    max_iterations: Option<usize>,
    ftol: Option<f64>,
    geodesic: Option<bool>,
    jacobian: Option<JacobianMethod>,
}

/// A validation failure: the dotted field (e.g. `constants.B`, `solver.ftol`) and what is
/// wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    /// Dotted field path, as in the TOML file.
    pub field: String,
    /// What is wrong, one line.
    pub what: String,
}

fn invalid(field: impl Into<String>, what: impl Into<String>) -> Invalid {
    Invalid {
        field: field.into(),
        what: what.into(),
    }
}

impl RunConfig {
    /// Read and validate a configuration file, with nothing from the command line and no
    /// data bound (see [`RunConfig::resolve`] for a whole run).
    pub fn load(path: &Path) -> Result<RunConfig> {
        Self::load_with(path, &Overrides::default())
    }

    /// Read a configuration file and apply the command line.
    pub fn load_with(path: &Path, cli: &Overrides) -> Result<RunConfig> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_str_with(&text, path, cli)
    }

    /// A whole run's configuration: the file, the command line and the data, loaded and
    /// bound (the one way the binary builds it).
    pub fn resolve(path: &Path, cli: &Overrides) -> Result<(RunConfig, Dataset)> {
        let cfg = Self::load_with(path, cli)?;
        let data = cfg.load_data()?;
        Ok((cfg.with_data(&data), data))
    }

    /// The configuration a run on `data` alone would resolve: bound to `data` by
    /// [`RunConfig::with_data`], with `T_ref` resolved from `data`'s curves when the
    /// configuration did not give it. A hold-out's training fit uses it, so that the tests it
    /// leaves out do not set the reference temperature, the box and the starts of the laws
    /// (on Alloy 617 without KAERI2's 900 °C curves, holding 900 °C out gave creepfit 0.205 at
    /// the full data's T_ref of 872.06 °C and 0.175 at the training curves' 864.81 °C).
    pub fn for_data(&self, data: &Dataset) -> RunConfig {
        let mut c = self.clone();
        if c.t_ref_from_data {
            c.t_ref = None;
            c.t_ref_from_data = false;
        }
        c.with_data(data)
    }

    /// Bind the configuration to the content hash of its loaded data.
    ///
    /// With temperature laws this also resolves what depends on the data: `T_ref` defaults
    /// to the mean test temperature (over the curves; exactly their temperature when they
    /// share one), and with one temperature in the data every law parameter is held (at its
    /// start, else at 0 or the bound nearest to it): it cannot be determined from one
    /// temperature, and the fit is then the fit without laws (bit for bit at the default
    /// `T_ref`).
    pub fn with_data(mut self, data: &Dataset) -> RunConfig {
        self.data_hash = crate::data::data_hash(data);
        if self.has_laws() && !data.curves.is_empty() {
            let temps: Vec<f64> = data.curves.iter().map(|c| c.temperature_c).collect();
            let lo = temps.iter().cloned().fold(f64::INFINITY, f64::min);
            let one = temps.iter().all(|t| *t == lo);
            if self.t_ref.is_none() {
                // lo + mean(t − lo): exactly lo when all are equal.
                let mean_dev = temps.iter().map(|t| t - lo).sum::<f64>() / temps.len() as f64;
                self.t_ref = Some(lo + mean_dev);
                self.t_ref_from_data = true;
            }
            if one {
                let mut held = Vec::new();
                let n = self.n_model_constants();
                for c in self.constants[n..].iter_mut().filter(|c| !c.held) {
                    let v = c.start.unwrap_or_else(|| 0.0f64.clamp(c.lb, c.ub));
                    c.start = Some(v);
                    c.held = true;
                    held.push(format!("{} = {v}", c.name));
                }
                if !held.is_empty() {
                    self.warnings.push(format!(
                        "{}: the data are at one temperature ({lo} °C): the temperature laws' parameters cannot be determined and are held ({})",
                        self.path.display(),
                        held.join(", ")
                    ));
                }
            }
        }
        self
    }

    /// Parse and validate configuration `text`; `path` locates relative data paths and names
    /// the file in errors.
    pub fn from_str(text: &str, path: &Path) -> Result<RunConfig> {
        Self::from_str_with(text, path, &Overrides::default())
    }

    /// [`RunConfig::from_str`] with the command line applied.
    pub fn from_str_with(text: &str, path: &Path, cli: &Overrides) -> Result<RunConfig> {
        let raw: RawConfig = toml::from_str(text).map_err(|e| toml_error(text, path, &e))?;
        let at = |inv: Invalid| {
            Error::config_at(
                path,
                field_line(text, &inv.field),
                format!("{}: {}", inv.field, inv.what),
            )
        };
        let cli_err = |inv: Invalid| Error::Invalid(format!("{}: {}", inv.field, inv.what));
        validate_overrides(cli).map_err(cli_err)?;
        let cfg = Self::from_raw(raw, path, cli).map_err(at)?;
        cfg.validate().map_err(at)?;
        Ok(cfg)
    }

    fn from_raw(
        raw: RawConfig,
        path: &Path,
        cli: &Overrides,
    ) -> std::result::Result<RunConfig, Invalid> {
        model::registry(&raw.model).map_err(|e| invalid("model", e.to_string()))?;
        validate_extensions(&raw.extensions)?;
        let base = model::registry(&raw.model).map_err(|e| invalid("model", e.to_string()))?;
        let n_base = base.constants().len();
        let m = model::build(&raw.model, &raw.extensions)
            .map_err(|e| invalid("extensions", e.to_string()))?;
        let specs = m.constants();
        for name in raw.constants.keys() {
            if !specs.iter().any(|s| s.name == name) {
                return Err(invalid(
                    "constants",
                    format!(
                        "unknown constant '{name}' for model '{}' (known: {})",
                        m.name(),
                        specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
                    ),
                ));
            }
        }
        let mut constants = Vec::with_capacity(specs.len());
        let mut missing_base = Vec::new();
        let mut warnings = Vec::new();
        for (j, s) in specs.iter().enumerate() {
            let c = match raw.constants.get(s.name) {
                Some(r) => ConstantConfig {
                    name: s.name.to_string(),
                    unit: s.unit,
                    lb: r.lb,
                    ub: r.ub,
                    start: r.start,
                    scale: r.scale.unwrap_or(s.scale),
                    law: r.law.unwrap_or_default(),
                    held: false,
                },
                None => {
                    if j < n_base {
                        missing_base.push(s.name);
                    } else {
                        warnings.push(format!(
                            "{}: constants.{}: not in [constants]; the extension's default bounds [{}, {}] ({} scale) apply, without a start",
                            path.display(),
                            s.name,
                            s.lb,
                            s.ub,
                            if s.scale == Scale::Log { "log" } else { "linear" }
                        ));
                    }
                    ConstantConfig {
                        name: s.name.to_string(),
                        unit: s.unit,
                        lb: s.lb,
                        ub: s.ub,
                        start: None,
                        scale: s.scale,
                        law: LawKind::Constant,
                        held: false,
                    }
                }
            };
            validate_constant(&c).map_err(|m| invalid(format!("constants.{}", c.name), m))?;
            constants.push(c);
        }
        // The laws' parameters, after the model's constants (model order).
        let with_params =
            laws::constants_with_laws(specs, &constants.iter().map(|c| c.law).collect::<Vec<_>>());
        for (s, c) in specs.iter().zip(constants.clone()) {
            let allowed = c.law.param();
            if let Some(r) = raw.constants.get(s.name) {
                if let Some(key) = r.rest.keys().find(|k| Some(k.as_str()) != allowed) {
                    let what = match LawKind::ALL.iter().find(|l| l.param() == Some(key.as_str())) {
                        Some(l) => format!(
                            "`{key}` is the parameter of law \"{}\", but the constant's law is \"{}\"{}",
                            l.name(),
                            c.law.name(),
                            if c.law == LawKind::Constant { " (say law = \"...\")" } else { "" }
                        ),
                        None => format!(
                            "unknown field `{key}`, expected one of `lb`, `ub`, `start`, `scale`, `law`{}",
                            allowed.map(|p| format!(", `{p}`")).unwrap_or_default()
                        ),
                    };
                    return Err(invalid(format!("constants.{}.{key}", s.name), what));
                }
            }
            let Some(param) = allowed else { continue };
            let name = format!("{}.{param}", s.name);
            let spec = with_params
                .iter()
                .find(|p| p.name == name)
                .expect("a law parameter for every law");
            let given = raw.constants.get(s.name).and_then(|r| r.rest.get(param));
            let p = match given {
                Some(RawLawParam::Held(v)) => ConstantConfig {
                    name: name.clone(),
                    unit: spec.unit,
                    lb: *v,
                    ub: *v,
                    start: Some(*v),
                    scale: Scale::Linear,
                    law: LawKind::Constant,
                    held: true,
                },
                Some(RawLawParam::Free(b)) => ConstantConfig {
                    name: name.clone(),
                    unit: spec.unit,
                    lb: b.lb,
                    ub: b.ub,
                    start: b.start,
                    scale: b.scale.unwrap_or(Scale::Linear),
                    law: LawKind::Constant,
                    held: false,
                },
                None => {
                    warnings.push(format!(
                        "{}: constants.{name}: not given; the law's default bounds [{}, {}] {} apply, without a start",
                        path.display(),
                        spec.lb,
                        spec.ub,
                        spec.unit
                    ));
                    ConstantConfig {
                        name: name.clone(),
                        unit: spec.unit,
                        lb: spec.lb,
                        ub: spec.ub,
                        start: None,
                        scale: Scale::Linear,
                        law: LawKind::Constant,
                        held: false,
                    }
                }
            };
            validate_constant(&p).map_err(|m| invalid(format!("constants.{name}"), m))?;
            constants.push(p);
        }
        if !missing_base.is_empty() {
            return Err(invalid(
                "constants",
                format!(
                    "missing {} (every constant of the base model '{}' needs lb and ub)",
                    missing_base.join(", "),
                    raw.model
                ),
            ));
        }

        let name = match raw.name {
            Some(n) => n,
            None => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "run".into()),
        };
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut objective = raw.objective;
        if let Some(w) = cli.w {
            objective.w_grid = vec![w];
            objective.w_sets.clear();
        }
        let d = SolverConfig::default();
        let rs = raw.solver;
        let solver = SolverConfig {
            rtol: rs.rtol.unwrap_or(d.rtol),
            atol: rs.atol.unwrap_or(d.atol),
            max_iterations: rs.max_iterations.unwrap_or(d.max_iterations),
            ftol: rs.ftol.unwrap_or(d.ftol),
            geodesic: rs.geodesic.unwrap_or(d.geodesic),
            jacobian: rs.jacobian.unwrap_or(d.jacobian),
            ..d
        };
        let sweep = SweepConfig {
            starts: cli.starts.unwrap_or(raw.sweep.starts),
            seed: cli.seed.unwrap_or(raw.sweep.seed),
            ..raw.sweep
        };
        Ok(RunConfig {
            path: path.to_path_buf(),
            name,
            curves: dir.join(&raw.curves),
            ruptures: dir.join(&raw.ruptures),
            data_hash: String::new(),
            temperature_c: raw.temperature_c,
            t_ref: raw.t_ref,
            t_ref_from_data: false,
            model: raw.model,
            extensions: raw.extensions,
            interrupted: raw.interrupted,
            outliers: raw.outliers,
            constants,
            objective,
            solver,
            sweep,
            fit: FitConfig {
                starts: cli.fit_starts.unwrap_or_default(),
            },
            diagnose: DiagnoseConfig {
                starts: cli.diagnose.starts.unwrap_or(raw.diagnose.starts),
                seed: cli.diagnose.seed.unwrap_or(raw.diagnose.seed),
                bootstrap: cli.diagnose.bootstrap.unwrap_or(raw.diagnose.bootstrap),
                bootstrap_extended: cli
                    .diagnose
                    .bootstrap_extended
                    .or(raw.diagnose.bootstrap_extended),
                alpha: cli.diagnose.alpha.unwrap_or(raw.diagnose.alpha),
                ..raw.diagnose
            },
            predict: PredictConfig {
                at: match &cli.predict_at {
                    Some(at) => at.clone(),
                    None => raw
                        .predict
                        .at
                        .iter()
                        .enumerate()
                        .map(|(k, s)| {
                            Condition::parse(s).map_err(|m| invalid(format!("predict.at[{k}]"), m))
                        })
                        .collect::<std::result::Result<_, _>>()?,
                },
                lmp_degree: raw.predict.lmp_degree.unwrap_or(crate::lmp::DEFAULT_DEGREE),
                intervals: cli
                    .predict_intervals
                    .or(raw.predict.intervals)
                    .unwrap_or(false),
                tensile_strength: raw
                    .predict
                    .tensile_strength
                    .iter()
                    .enumerate()
                    .map(|(k, s)| {
                        crate::baseline::TensileStrength::parse(s)
                            .map_err(|m| invalid(format!("predict.tensile_strength[{k}]"), m))
                    })
                    .collect::<std::result::Result<_, _>>()?,
                // The command line's conditions (`--at`, or `--tests`'s) replace the file's.
                tests: match (&cli.predict_at, &raw.predict.tests) {
                    (None, Some(t)) if !raw.predict.at.is_empty() => {
                        return Err(invalid(
                            "predict.tests",
                            format!(
                                "\"{t}\": give either predict.at (conditions) or predict.tests (a file of tests), not both"
                            ),
                        ))
                    }
                    (None, Some(t)) => Some(dir.join(t)),
                    _ => None,
                },
            },
            profile: raw.profile,
            run: cli.run.clone(),
            warnings,
        })
    }

    /// Check every setting; the first problem found, by field.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        validate_name(&self.name)?;
        model::registry(&self.model).map_err(|e| invalid("model", e.to_string()))?;
        validate_extensions(&self.extensions)?;
        let m = model::build(&self.model, &self.extensions)
            .map_err(|e| invalid("extensions", e.to_string()))?;
        let n_inner = m.constants().len();
        if self.constants.len() < n_inner {
            return Err(invalid(
                "constants",
                format!(
                    "the model '{}' has {n_inner} constants, the configuration {}",
                    m.name(),
                    self.constants.len()
                ),
            ));
        }
        let kinds: Vec<LawKind> = self.constants[..n_inner].iter().map(|c| c.law).collect();
        let all = laws::constants_with_laws(m.constants(), &kinds);
        let names: Vec<&str> = all.iter().map(|s| s.name).collect();
        if self.constant_names() != names {
            return Err(invalid(
                "constants",
                format!(
                    "the model '{}' has the constants {} (in this order), not {}",
                    m.name(),
                    names.join(", "),
                    self.constant_names().join(", ")
                ),
            ));
        }
        for c in &self.constants {
            validate_constant(c).map_err(|m| invalid(format!("constants.{}", c.name), m))?;
        }
        for c in &self.constants[n_inner..] {
            if c.law != LawKind::Constant {
                return Err(invalid(
                    format!("constants.{}", c.name),
                    "a law's parameter has no law of its own",
                ));
            }
        }
        if let Some(t) = self.t_ref {
            if !(t.is_finite() && t > -crate::data::ZERO_CELSIUS_K) {
                return Err(invalid(
                    "T_ref",
                    format!("must be a finite temperature above absolute zero, °C (got {t})"),
                ));
            }
        }
        if let Some(t) = self.temperature_c {
            if !t.is_finite() {
                return Err(invalid(
                    "temperature_C",
                    format!("must be finite (got {t})"),
                ));
            }
        }
        for (k, e) in self.interrupted.iter().enumerate() {
            if let data::Interrupted::Stress(s) = *e {
                if !(s.is_finite() && s > 0.0) {
                    return Err(invalid(
                        format!("interrupted[{k}]"),
                        format!("stresses must be positive and finite (got {s})"),
                    ));
                }
            }
        }
        validate_objective(&self.objective)?;
        if self.sweep.starts == 0 {
            return Err(invalid("sweep.starts", "must be at least 1"));
        }
        validate_solver(&self.solver)?;
        self.diagnose.validate()?;
        for (k, e) in self.predict.tensile_strength.iter().enumerate() {
            if self.predict.tensile_strength[..k]
                .iter()
                .any(|o| o.temperature_c == e.temperature_c)
            {
                return Err(invalid(
                    format!("predict.tensile_strength[{k}]"),
                    format!("{} °C is given twice", e.temperature_c),
                ));
            }
        }
        if self.predict.lmp_degree > 4 {
            return Err(invalid(
                "predict.lmp_degree",
                format!("must be at most 4 (got {})", self.predict.lmp_degree),
            ));
        }
        self.profile.validate()?;
        validate_run(&self.run)
    }

    /// The model's full name with its extensions, e.g. `khd+constant_load`.
    pub fn model_name(&self) -> String {
        std::iter::once(self.model.as_str())
            .chain(self.extensions.iter().map(|s| s.as_str()))
            .collect::<Vec<_>>()
            .join("+")
    }

    /// The output folder of `command`: `--out`, else `results/<name>/<command>/`.
    pub fn out_dir(&self, command: &str) -> PathBuf {
        self.run
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from("results").join(&self.name).join(command))
    }

    /// Options for [`data::load`]: the temperature filter and the interrupted tests.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            temperature_c: self.temperature_c,
            interrupted: self.interrupted.clone(),
            interrupted_source: Some((self.path.clone(), self.interrupted_line())),
            several_temperatures: self.has_laws(),
            outliers: self.outliers,
        }
    }

    /// The line of `interrupted` in the configuration file, for the errors its entries raise
    /// once the data are loaded (0: no entries, or the file cannot be read again).
    fn interrupted_line(&self) -> usize {
        if self.interrupted.is_empty() {
            return 0;
        }
        std::fs::read_to_string(&self.path).map_or(0, |t| field_line(&t, "interrupted"))
    }

    /// Whether some constant follows a temperature law other than `constant`.
    pub fn has_laws(&self) -> bool {
        self.constants.iter().any(|c| c.law != LawKind::Constant)
    }

    /// Number of the model's own constants (the laws' parameters follow them).
    pub fn n_model_constants(&self) -> usize {
        let n_params = self
            .constants
            .iter()
            .filter(|c| c.law.param().is_some())
            .count();
        self.constants.len() - n_params
    }

    /// The model of the run: the registry's model with its extensions and, when some
    /// constant has a temperature law, the laws about `T_ref` ([`laws::with_laws`]).
    pub fn build_model(&self) -> Result<Box<dyn Model>> {
        self.build_model_with(&self.extensions)
    }

    /// The configured model with `extensions` instead of the configured ones, carrying the
    /// configuration's temperature laws on the constants it declares (matched by name; an
    /// extension's constant it does not declare is common to all temperatures): the run's
    /// model ([`RunConfig::build_model`]) and the models `diagnose` compares.
    pub fn build_model_with(&self, extensions: &[String]) -> Result<Box<dyn Model>> {
        let m = model::build(&self.model, extensions)?;
        if !self.has_laws() {
            return Ok(m);
        }
        let t_ref = self.t_ref.ok_or_else(|| {
            Error::config(
                &self.path,
                "T_ref: not resolved; bind the configuration to its data (RunConfig::resolve or with_data) or give T_ref",
            )
        })?;
        let kinds: Vec<LawKind> = m
            .constants()
            .iter()
            .map(|c| {
                self.constants
                    .iter()
                    .find(|k| k.name == c.name)
                    .map_or(LawKind::Constant, |k| k.law)
            })
            .collect();
        Ok(laws::with_laws(m, &kinds, t_ref))
    }

    /// Load the run's data ([`data::load`] with [`RunConfig::load_options`]), each curve
    /// averaged down to `objective.max_points` points when that is set.
    pub fn load_data(&self) -> Result<Dataset> {
        let data = data::load(&self.curves, &self.ruptures, &self.load_options())?;
        Ok(self.binned(data))
    }

    /// [`RunConfig::load_data`] from the two tables' CSV text in memory instead of the
    /// configured files ([`data::load_bytes`]; `curves` and `ruptures` name them in errors).
    pub fn load_data_from(
        &self,
        curves: &Path,
        curves_csv: &[u8],
        ruptures: &Path,
        ruptures_csv: &[u8],
    ) -> Result<Dataset> {
        let opts = self.load_options();
        let data = data::load_bytes(curves, curves_csv, ruptures, ruptures_csv, &opts)?;
        Ok(self.binned(data))
    }

    /// `data` with each curve averaged down to `objective.max_points` points when that is set.
    fn binned(&self, mut data: Dataset) -> Dataset {
        if self.objective.max_points > 0 {
            for c in &mut data.curves {
                *c = crate::data::binned(c, self.objective.max_points);
            }
        }
        data
    }

    /// Bounds and scales of the constants as a [`ParamSpace`]; held constants (law
    /// parameters given as a number, or of data at one temperature) are held at their start.
    pub fn space(&self) -> ParamSpace {
        let mut space = ParamSpace::new(self.lower(), self.upper(), self.scales());
        for (j, c) in self.constants.iter().enumerate() {
            if c.held {
                space.hold(
                    j,
                    c.start.expect("a held constant has its value (validated)"),
                );
            }
        }
        space
    }

    /// The calibration this configuration asks for on `data`, built once: the model, its
    /// parameter space, the fit settings, the starts and the lifetime weights
    /// ([`Calibration`]). Refused here, before any work: a `w_sets` entry of the wrong
    /// length.
    pub fn calibration(&self, data: &Dataset) -> Result<Calibration> {
        let given_start = self.starts_all_given();
        let (specimen_effects, specimen_note) = self.objective.specimen_options(&data.curves);
        Ok(Calibration {
            model: self.build_model()?,
            space: self.space(),
            settings: FitSettings::from_config(self),
            start_choice: self.fit.starts,
            given_start,
            seed: self.sweep.seed,
            weights: self
                .objective
                .weight_vectors(data.curves.len(), &self.path)?,
            specimen_effects,
            specimen_note,
            source: self.path.clone(),
        })
    }

    /// What `diagnose` refuses before it starts: data at several temperatures without a
    /// temperature law.
    pub fn check_diagnose(&self, data: &Dataset) -> Result<()> {
        let mut temps: Vec<f64> = data.curves.iter().map(|c| c.temperature_c).collect();
        temps.sort_by(f64::total_cmp);
        temps.dedup();
        if temps.len() > 1 && !self.has_laws() {
            return Err(Error::config(
                &self.path,
                format!(
                    "temperature_C: diagnose works at one temperature unless a constant follows a temperature law; the data have {} ({} °C): set temperature_C",
                    temps.len(),
                    temps.iter().map(|t| t.to_string()).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// What the likelihood analyses take on `data` ([`LikelihoodSetup`]).
    pub fn likelihood_setup(&self, data: &Dataset) -> LikelihoodSetup {
        LikelihoodSetup {
            space: self.space(),
            settings: FitSettings::from_config(self),
            ml: crate::likelihood::MlOptions {
                lifetime_sd_floor: self.profile.lifetime_sd_floor,
                // Not read by the profile's fits: without specimen effects they are scaled
                // AR(1) fits (`uncertainty::constrained::ml_fit_scaled`), with them each
                // far start has its white stage and each warm one none (`Context::fit_row`).
                white_first: false,
                specimen: self.objective.specimen_options(&data.curves).0,
                hold_scatter: None,
            },
            auto_effects: matches!(self.objective.specimen_effects, SpecimenEffects::Auto(_)),
            profile: self.profile.clone(),
        }
    }

    /// What `predict` takes on `data` ([`PredictSetup`]).
    pub fn predict_setup(&self, data: &Dataset) -> PredictSetup {
        PredictSetup {
            ode: self.solver.ode_options(),
            omega_f: self.objective.omega_f,
            predict: self.predict.clone(),
            has_laws: self.has_laws(),
            likelihood: self.likelihood_setup(data),
        }
    }

    /// What `diagnose` takes, built once ([`DiagnoseSetup`]): the configured model, then it
    /// plus each extension to test (`[diagnose] extensions`, else the family's catalogue);
    /// bounds from the configuration where it names the constant, else the extension's
    /// defaults; and the family's bare model on the configuration's bounds for the initial
    /// guess.
    pub fn diagnose_setup(&self) -> Result<DiagnoseSetup> {
        Ok(DiagnoseSetup {
            variants: self.model_variants()?,
            bare: self.bare_variant()?,
            settings: FitSettings::from_config(self),
            specimen_effects: self.objective.specimen_effects.clone(),
            specimen_scatter: self.objective.specimen_scatter,
            extensions: self.extensions.clone(),
        })
    }

    fn model_variants(&self) -> Result<Vec<ModelVariant>> {
        let base_space = self.space();
        let mut out = Vec::new();
        // By default the extensions the model's family composes with (its registry entry's).
        let wanted: Vec<String> = if self.diagnose.extensions.is_empty() {
            crate::model::entry(&self.model)?
                .extensions
                .iter()
                .map(|s| s.to_string())
                .collect()
        } else {
            self.diagnose.extensions.clone()
        };
        let mut lists: Vec<(String, Vec<String>)> = vec![("base".into(), self.extensions.clone())];
        for e in wanted {
            if self.extensions.contains(&e) {
                continue;
            }
            let mut l = self.extensions.clone();
            l.push(e.clone());
            lists.push((e, l));
        }
        for (name, exts) in lists {
            let model = self.build_model_with(&exts)?;
            let (mut lb, mut ub, mut sc) = (vec![], vec![], vec![]);
            let mut extra = vec![];
            let mut held = vec![];
            for (j, c) in model.constants().iter().enumerate() {
                match self.constants.iter().position(|k| k.name == c.name) {
                    Some(i) => {
                        lb.push(base_space.lb[i]);
                        ub.push(base_space.ub[i]);
                        sc.push(base_space.scale[i]);
                        if !base_space.free[i] {
                            held.push((j, base_space.fixed[i]));
                        }
                    }
                    None => {
                        lb.push(c.lb);
                        ub.push(c.ub);
                        sc.push(c.scale);
                        extra.push(c.name.to_string());
                    }
                }
            }
            let mut space = ParamSpace::new(lb, ub, sc);
            for (j, v) in held {
                space.hold(j, v);
            }
            out.push(ModelVariant {
                name,
                model,
                space,
                extra,
            });
        }
        Ok(out)
    }

    /// The family's model without extensions (temperature laws kept) on the configuration's
    /// bounds of its constants.
    fn bare_variant(&self) -> Result<ModelVariant> {
        let model = self.build_model_with(&[])?;
        let s = self.space();
        let idx: Vec<usize> = model
            .constants()
            .iter()
            .map(|k| {
                self.constants
                    .iter()
                    .position(|c| c.name == k.name)
                    .expect("a constant of the family's model is configured (validated)")
            })
            .collect();
        let mut space = ParamSpace::new(
            idx.iter().map(|&i| s.lb[i]).collect(),
            idx.iter().map(|&i| s.ub[i]).collect(),
            idx.iter().map(|&i| s.scale[i]).collect(),
        );
        for (j, &i) in idx.iter().enumerate() {
            if !s.free[i] {
                space.hold(j, s.fixed[i]);
            }
        }
        Ok(ModelVariant {
            name: "bare".into(),
            model,
            space,
            extra: Vec::new(),
        })
    }

    /// The start vector (model order) if every constant has a start, else `None`.
    pub fn starts_all_given(&self) -> Option<Vec<f64>> {
        self.constants.iter().map(|c| c.start).collect()
    }

    /// Lower bounds, model order.
    pub fn lower(&self) -> Vec<f64> {
        self.constants.iter().map(|c| c.lb).collect()
    }

    /// Upper bounds, model order.
    pub fn upper(&self) -> Vec<f64> {
        self.constants.iter().map(|c| c.ub).collect()
    }

    /// Scales, model order.
    pub fn scales(&self) -> Vec<Scale> {
        self.constants.iter().map(|c| c.scale).collect()
    }

    /// Constant names, model order.
    pub fn constant_names(&self) -> Vec<&str> {
        self.constants.iter().map(|c| c.name.as_str()).collect()
    }

    /// A one-line error about the setting `field` (dotted, e.g. `predict.at[1]`) of this
    /// configuration, at its line in the file where the file can be read and holds it.
    pub fn error_at(&self, field: &str, what: impl std::fmt::Display) -> Error {
        let line = std::fs::read_to_string(&self.path)
            .map(|t| field_line(&t, field))
            .unwrap_or(0);
        Error::config_at(&self.path, line, format!("{field}: {what}"))
    }
}

fn validate_name(name: &str) -> std::result::Result<(), Invalid> {
    if name.trim().is_empty() {
        return Err(invalid("name", "must not be empty"));
    }
    if name.contains(['/', '\\', '\0']) || name.contains("..") {
        return Err(invalid(
            "name",
            format!(
                "'{name}' must not contain '/', '\\' or '..' (it names the folder results/<name>/)"
            ),
        ));
    }
    Ok(())
}

fn validate_extensions(exts: &[String]) -> std::result::Result<(), Invalid> {
    for (i, ext) in exts.iter().enumerate() {
        if !model::ext::ALL.contains(&ext.as_str()) {
            return Err(invalid(
                "extensions",
                format!(
                    "unknown extension '{ext}' (known: {})",
                    model::ext::ALL.join(", ")
                ),
            ));
        }
        if exts[..i].contains(ext) {
            return Err(invalid("extensions", format!("'{ext}' is listed twice")));
        }
    }
    Ok(())
}

fn validate_constant(c: &ConstantConfig) -> std::result::Result<(), String> {
    if !c.lb.is_finite() || !c.ub.is_finite() {
        return Err(format!(
            "bounds must be finite (lb = {}, ub = {})",
            c.lb, c.ub
        ));
    }
    if c.held {
        // Held at its start, which must lie in [lb, ub] (lb = ub = start for a law parameter
        // given as a number).
        if c.start.is_none() {
            return Err("a held constant needs its value (start)".into());
        }
        if c.lb > c.ub {
            return Err(format!("lb ({}) must not be above ub ({})", c.lb, c.ub));
        }
    } else if c.lb >= c.ub {
        return Err(format!("lb ({}) must be below ub ({})", c.lb, c.ub));
    }
    if c.law == LawKind::Arrhenius && c.lb <= 0.0 {
        return Err(format!(
            "law \"arrhenius\" needs a positive constant (lb > 0, lb = {})",
            c.lb
        ));
    }
    if c.scale == Scale::Log && c.lb <= 0.0 {
        return Err(format!("scale \"log\" needs lb > 0 (lb = {})", c.lb));
    }
    if let Some(s) = c.start {
        if !(s >= c.lb && s <= c.ub) {
            return Err(format!(
                "start ({s}) is outside the bounds [{}, {}]",
                c.lb, c.ub
            ));
        }
    }
    Ok(())
}

fn valid_weight(w: f64) -> bool {
    (0.0..=1.0).contains(&w)
}

fn validate_objective(o: &ObjectiveConfig) -> std::result::Result<(), Invalid> {
    if o.w_grid.is_empty() && o.w_sets.is_empty() {
        return Err(invalid(
            "objective.w_grid",
            "w_grid and w_sets are both empty; give at least one weight",
        ));
    }
    for &w in &o.w_grid {
        if !valid_weight(w) {
            return Err(invalid(
                "objective.w_grid",
                format!("weights must be in [0, 1] (got {w})"),
            ));
        }
    }
    for (k, set) in o.w_sets.iter().enumerate() {
        if set.is_empty() {
            return Err(invalid(
                format!("objective.w_sets[{k}]"),
                "empty weight set",
            ));
        }
        for &w in set {
            if !valid_weight(w) {
                return Err(invalid(
                    format!("objective.w_sets[{k}]"),
                    format!("weights must be in [0, 1] (got {w})"),
                ));
            }
        }
    }
    if (1..10).contains(&o.max_points) {
        return Err(invalid(
            "objective.max_points",
            format!(
                "must be 0 (all points) or at least 10 (got {})",
                o.max_points
            ),
        ));
    }
    if !(o.lifetime_sd_floor > 0.0 && o.lifetime_sd_floor.is_finite()) {
        return Err(invalid(
            "objective.lifetime_sd_floor",
            format!("must be positive (got {})", o.lifetime_sd_floor),
        ));
    }
    if !(o.omega_f > 0.0 && o.omega_f < 1.0) {
        return Err(invalid(
            "objective.omega_f",
            format!("must be in (0, 1) (got {})", o.omega_f),
        ));
    }
    Ok(())
}

fn validate_solver(s: &SolverConfig) -> std::result::Result<(), Invalid> {
    let positive = [
        ("rtol", s.rtol),
        ("atol", s.atol),
        ("xtol", s.xtol),
        ("gtol", s.gtol),
        ("fd_step", s.fd_step),
        ("lambda0", s.lambda0),
        ("lambda_max", s.lambda_max),
        ("geodesic_alpha", s.geodesic_alpha),
        ("geodesic_h", s.geodesic_h),
    ];
    for (k, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(
                format!("solver.{k}"),
                format!("must be positive (got {v})"),
            ));
        }
    }
    if !(s.ftol > 0.0 && s.ftol < 1.0) {
        return Err(invalid(
            "solver.ftol",
            format!("must be in (0, 1) (got {})", s.ftol),
        ));
    }
    if s.max_iterations == 0 {
        return Err(invalid("solver.max_iterations", "must be at least 1"));
    }
    if s.max_steps == 0 {
        return Err(invalid("solver.max_steps", "must be at least 1"));
    }
    Ok(())
}

fn validate_run(r: &RunOptions) -> std::result::Result<(), Invalid> {
    if let Some((i, n)) = r.shard {
        if i == 0 || n == 0 || i > n {
            return Err(invalid("--shard", format!("{i}/{n}: need 1 <= I <= N")));
        }
    }
    if r.threads == Some(0) {
        return Err(invalid("--threads", "must be at least 1"));
    }
    Ok(())
}

fn validate_overrides(cli: &Overrides) -> std::result::Result<(), Invalid> {
    if cli.starts == Some(0) {
        return Err(invalid("--starts", "must be at least 1"));
    }
    if let Some(w) = cli.w {
        if !valid_weight(w) {
            return Err(invalid(
                "--w",
                format!("must be a weight in [0, 1], not {w}"),
            ));
        }
    }
    validate_run(&cli.run)
}

/// 1-based line of byte offset `pos` in `text`.
fn line_at(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())].matches('\n').count() + 1
}

/// The line of the TOML file where `field` (dotted, e.g. `constants.B`, `objective.w_sets[0]`)
/// is given: the deepest part of it that the file contains (its table header when the key
/// itself is absent); 0 when the file does not mention it at all.
fn field_line(text: &str, field: &str) -> usize {
    let Ok(doc) = toml_edit::ImDocument::parse(text) else {
        return 0;
    };
    let mut table: &dyn toml_edit::TableLike = doc.as_table();
    let mut found = None;
    for part in field.split('.') {
        let key = part.split('[').next().unwrap_or(part);
        let Some((k, item)) = table.get_key_value(key) else {
            break;
        };
        found = k.span().or_else(|| item.span()).or(found);
        match item.as_table_like() {
            Some(t) => table = t,
            None => break,
        }
    }
    found.map_or(0, |r| line_at(text, r.start))
}

/// The dotted name of the deepest key of the TOML `text` whose key or value covers byte
/// `pos` (e.g. `sweep.sead` for an unknown key in `[sweep]`).
fn field_at(text: &str, pos: usize) -> Option<String> {
    fn walk(t: &dyn toml_edit::TableLike, pos: usize, prefix: &str) -> Option<String> {
        for (k, item) in t.iter() {
            let name = if prefix.is_empty() {
                k.to_string()
            } else {
                format!("{prefix}.{k}")
            };
            let key_span = t.get_key_value(k).and_then(|(key, _)| key.span());
            let covers = |r: Option<std::ops::Range<usize>>| r.is_some_and(|r| r.contains(&pos));
            if let Some(sub) = item.as_table_like() {
                if let Some(deeper) = walk(sub, pos, &name) {
                    return Some(deeper);
                }
            }
            if covers(key_span) || covers(item.span()) {
                return Some(name);
            }
        }
        None
    }
    let doc = toml_edit::ImDocument::parse(text).ok()?;
    walk(doc.as_table(), pos, "")
}

/// toml's error as one line: `FILE:LINE: field: what`.
fn toml_error(text: &str, path: &Path, e: &toml::de::Error) -> Error {
    let msg = e.message().trim().replace('\n', " ");
    let Some(span) = e.span() else {
        return Error::config(path, msg);
    };
    let line = line_at(text, span.start);
    match field_at(text, span.start) {
        Some(field) => Error::config_at(path, line, format!("{field}: {msg}")),
        None => Error::config_at(path, line, msg),
    }
}

impl FitSettings {
    /// The settings of the resolved configuration `cfg` (the one place they are derived).
    pub fn from_config(cfg: &RunConfig) -> Self {
        FitSettings {
            lm: cfg.solver.lm_options(),
            ode: cfg.solver.ode_options(),
            omega_f: cfg.objective.omega_f,
            lifetime: cfg.objective.lifetime_term,
            jacobian: cfg.solver.jacobian,
            kind: cfg.objective.kind,
            lifetime_sd_floor: cfg.objective.lifetime_sd_floor,
        }
    }
}

/// The canonical identity of a configuration: its serialisation without the excluded
/// fields, plus the crate version.
pub fn identity(cfg: &RunConfig) -> serde_json::Value {
    let mut v = serde_json::to_value(cfg).expect("a configuration serialises");
    if let serde_json::Value::Object(m) = &mut v {
        for k in IDENTITY_EXCLUDED {
            m.remove(*k);
        }
        m.insert(
            "version".into(),
            serde_json::Value::String(env!("CARGO_PKG_VERSION").into()),
        );
    }
    v
}

/// Resolve the run configuration (file + command line) and load its data: the one place
/// the commands build them.
pub fn load(config: &Path, cli: &Overrides) -> Result<(RunConfig, Dataset)> {
    let (cfg, data) = RunConfig::resolve(config, cli)?;
    for w in cfg.warnings.iter().chain(&data.warnings) {
        eprintln!("warning: {w}");
    }
    Ok((cfg, data))
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "t"
curves = "../data/c.csv"
ruptures = "r.csv"
temperature_C = 560
model = "khd"
extensions = []
interrupted = [70]

[constants]
A     = { lb = 1e-10, ub = 1e-9, start = 1e-9,   scale = "log" }
B     = { lb = 0.1,   ub = 0.2,  start = 0.11 }
Hstar = { lb = 0.4,   ub = 0.8 }
h     = { lb = 1e4,   ub = 2e5,  start = 5.05e4, scale = "log" }
Kc    = { lb = 1e-6,  ub = 3e-5, start = 6.86e-6, scale = "log" }
C     = { lb = 3,     ub = 10,   start = 4.311 }

[objective]
w_grid = [0.5, 1.0]
w_sets = [[0.12, 0.12, 1.0]]
lifetime_term = "both"
omega_f = 0.3

[sweep]
starts = 10
seed = 7

[solver]
rtol = 1e-8
"#;

    /// The six base constants, as a `[constants]` table.
    const CONSTANTS: &str = "[constants]\n\
        A     = { lb = 1e-10, ub = 1e-9, scale = \"log\" }\n\
        B     = { lb = 0.1,   ub = 0.2 }\n\
        Hstar = { lb = 0.4,   ub = 0.8 }\n\
        h     = { lb = 1e4,   ub = 2e5, scale = \"log\" }\n\
        Kc    = { lb = 1e-6,  ub = 3e-5, scale = \"log\" }\n\
        C     = { lb = 3,     ub = 10 }\n";

    fn parse(text: &str) -> Result<RunConfig> {
        RunConfig::from_str(text, Path::new("cfg/run.toml"))
    }

    #[test]
    fn full_config() {
        let c = parse(FULL).unwrap();
        assert_eq!(c.name, "t");
        assert_eq!(c.curves, Path::new("cfg/../data/c.csv"));
        assert_eq!(c.ruptures, Path::new("cfg/r.csv"));
        assert_eq!(c.temperature_c, Some(560.0));
        assert_eq!(c.interrupted, vec![data::Interrupted::Stress(70.0)]);
        assert_eq!(c.constant_names(), ["A", "B", "Hstar", "h", "Kc", "C"]);
        assert_eq!(c.constants[0].scale, Scale::Log);
        assert_eq!(c.constants[1].scale, Scale::Linear);
        assert_eq!(c.constants[5].lb, 3.0);
        assert_eq!(c.constants[5].start, Some(4.311));
        // Hstar without a start
        assert_eq!(c.constants[2].start, None);
        assert_eq!(c.constants[2].lb, 0.4);
        assert_eq!(c.constants[3].scale, Scale::Log);
        assert_eq!(c.starts_all_given(), None);
        assert_eq!(c.objective.lifetime_term, LifetimeTerm::Both);
        assert_eq!(c.objective.omega_f, 0.3);
        assert_eq!(c.sweep.starts, 10);
        assert_eq!(c.sweep.seed, 7);
        assert!(c.sweep.include_guess);
        assert_eq!(c.solver.rtol, 1e-8);
        assert_eq!(c.solver.atol, 1e-13);
        let w = c.objective.weight_vectors(3, &c.path).unwrap();
        assert_eq!(w.len(), 3);
        assert_eq!(w[0], vec![0.5; 3]);
        assert_eq!(w[2], vec![0.12, 0.12, 1.0]);
        assert!(c.objective.weight_vectors(2, &c.path).is_err());
        assert_eq!(
            c.load_options().interrupted,
            vec![data::Interrupted::Stress(70.0)]
        );
        assert!(c.warnings.is_empty());
        assert_eq!(c.model_name(), "khd");
        assert_eq!(c.out_dir("fit"), Path::new("results/t/fit"));
    }

    #[test]
    fn defaults() {
        let c = parse(&format!(
            "curves = \"a.csv\"\nruptures = \"b.csv\"\n{CONSTANTS}"
        ))
        .unwrap();
        assert_eq!(c.name, "run");
        assert_eq!(c.model, "khd");
        assert_eq!(c.objective.w_grid.len(), 10);
        assert_eq!(c.objective.w_grid[2], 0.3);
        assert_eq!(c.objective.w_grid[9], 1.0);
        assert!(c.objective.w_sets.is_empty());
        assert_eq!(c.objective.lifetime_term, LifetimeTerm::Late);
        assert_eq!(c.objective.omega_f, 1.0 / 3.0);
        assert_eq!(c.sweep.starts, 256);
        assert_eq!(c.sweep.seed, 1);
        assert_eq!(c.solver.max_iterations, 200);
        assert_eq!(c.solver.ftol, 1e-8);
        assert!(c.solver.geodesic);
        assert_eq!(c.constants.len(), 6);
        assert_eq!(c.fit.starts, StartChoice::Both);
        assert_eq!(c.data_hash, "");
    }

    /// The resolved solver settings give exactly the options the fits used before they were
    /// resolved in one place (results must not change).
    #[test]
    fn specimen_effects_parse_by_name_and_resolve_to_those_kinds() {
        use crate::likelihood::SpecimenOptions;
        for (list, want) in [
            ("[]", SpecimenOptions::NONE),
            ("[\"rate\", \"ductility\"]", SpecimenOptions::BOTH),
            (
                "[\"rate\", \"coarsening\"]",
                SpecimenOptions {
                    rate: true,
                    ductility: false,
                    coarsening: true,
                    beyond_trend: false,
                },
            ),
        ] {
            let c = parse(&format!(
                "curves = \"a.csv\"\nruptures = \"b.csv\"\n{CONSTANTS}\n[objective]\nspecimen_effects = {list}\n"
            ))
            .unwrap();
            assert_eq!(
                c.objective
                    .specimen_effects
                    .resolve(&[], Default::default())
                    .0,
                want,
                "{list}"
            );
        }
        let bad = parse(&format!(
            "curves = \"a.csv\"\nruptures = \"b.csv\"\n{CONSTANTS}\n[objective]\nspecimen_effects = [\"hardening\"]\n"
        ));
        assert!(bad.is_err());
    }

    /// `auto` as a table over designs and scatter estimates: replicates give both kinds;
    /// without, both only beyond the stress trend with two degrees of freedom there or more.
    #[test]
    fn auto_fits_effects_without_replicates_only_beyond_the_trend_with_the_freedom() {
        use crate::likelihood::{SpecimenOptions, SpecimenScatter};
        let curve = |t: f64, s: f64| crate::data::Curve::two_point(t, s, None);
        let seven: Vec<_> = (0..7)
            .map(|k| curve(900.0, 25.0 + 5.0 * k as f64))
            .collect();
        let three: Vec<_> = (0..3)
            .map(|k| curve(900.0, 25.0 + 5.0 * k as f64))
            .collect();
        let four: Vec<_> = (0..4)
            .map(|k| curve(900.0, 25.0 + 5.0 * k as f64))
            .collect();
        let pair = vec![curve(750.0, 100.0), curve(750.0, 100.0)];
        let (lik, beyond) = (
            SpecimenScatter::Likelihood,
            SpecimenScatter::BeyondStressTrend,
        );
        for (curves, scatter, want, note) in [
            (&pair, lik, SpecimenOptions::BOTH, None),
            (&pair, beyond, SpecimenOptions::BOTH, None),
            (
                &seven,
                lik,
                SpecimenOptions::NONE,
                Some("treats every specimen"),
            ),
            (
                &seven,
                beyond,
                SpecimenOptions::BOTH,
                Some("(5 degrees of freedom"),
            ),
            (
                &four,
                beyond,
                SpecimenOptions::BOTH,
                Some("(2 degrees of freedom"),
            ),
            (
                &three,
                beyond,
                SpecimenOptions::NONE,
                Some("treats every specimen"),
            ),
        ] {
            let (o, n) = SpecimenEffects::Auto(AutoWord::Auto).resolve(curves, scatter);
            assert_eq!(o, want, "{} curves, {scatter:?}", curves.len());
            match note {
                None => assert!(n.is_none(), "{n:?}"),
                Some(t) => assert!(n.as_deref().is_some_and(|n| n.contains(t)), "{n:?}"),
            }
        }
        // A list is taken as it is.
        let list = SpecimenEffects::Kinds(vec![crate::likelihood::EffectKind::Rate]);
        assert!(!list.resolve(&three, beyond).0.ductility);
    }

    /// Which configured specimen effects `fit`'s and `sweep`'s local fits leave out, as a
    /// table: all of them under eq. 8, `sweep`'s alone under the likelihood, none where none
    /// are configured or `auto` finds no replicates; the note names the kinds and the
    /// objective.
    #[test]
    fn the_effects_left_out_by_objective_and_command() {
        use crate::likelihood::EffectKind::{Ductility, Rate};
        let curve = |t: f64, s: f64| crate::data::Curve::two_point(t, s, None);
        let pair = vec![curve(750.0, 100.0), curve(750.0, 100.0)];
        let single = vec![curve(750.0, 100.0), curve(750.0, 120.0)];
        let (fit, sweep) = (LocalFits::Fit, LocalFits::Sweep);
        for (kind, effects, curves, command, want, note) in [
            (
                "eq8",
                "\"auto\"",
                &pair,
                fit,
                vec![Rate, Ductility],
                Some("eq. 8"),
            ),
            (
                "eq8",
                "\"auto\"",
                &pair,
                sweep,
                vec![Rate, Ductility],
                Some("eq. 8"),
            ),
            (
                "eq8",
                "[\"rate\"]",
                &single,
                fit,
                vec![Rate],
                Some("rate effects"),
            ),
            ("eq8", "[]", &pair, fit, vec![], None),
            ("eq8", "\"auto\"", &single, fit, vec![], None),
            ("likelihood", "\"auto\"", &pair, fit, vec![], None),
            (
                "likelihood",
                "\"auto\"",
                &pair,
                sweep,
                vec![Rate, Ductility],
                Some("−2 ln L"),
            ),
            ("likelihood", "[]", &pair, sweep, vec![], None),
        ] {
            let cfg = parse(&format!(
                "curves = \"a.csv\"\nruptures = \"b.csv\"\n{CONSTANTS}\n[objective]\nkind = \"{kind}\"\nspecimen_effects = {effects}\n"
            ))
            .unwrap();
            let left = cfg.objective.effects_left_out(curves, command);
            assert_eq!(left, want, "{kind} {effects} {command:?}");
            let n = objective_note(cfg.objective.kind, &left);
            match note {
                None => assert!(n.is_none(), "{n:?}"),
                Some(t) => assert!(n.as_deref().is_some_and(|n| n.contains(t)), "{n:?}"),
            }
        }
    }

    /// `specimen_scatter`: the estimate beyond the stress trend by default (since
    /// 2026-12-04), the likelihood's by name (carried into the resolved options), anything
    /// else refused.
    #[test]
    fn specimen_scatter_parses_and_reaches_the_resolved_options() {
        let cfg = |extra: &str| {
            parse(&format!(
                "curves = \"a.csv\"\nruptures = \"b.csv\"\n{CONSTANTS}\n[objective]\nspecimen_effects = [\"rate\"]\n{extra}"
            ))
        };
        let default = cfg("").unwrap();
        assert_eq!(
            default.objective.specimen_scatter,
            SpecimenScatter::BeyondStressTrend
        );
        let (o, _) = default.objective.specimen_options(&[]);
        assert!(o.rate && o.beyond_trend, "{o:?}");
        let lik = cfg("specimen_scatter = \"likelihood\"\n").unwrap();
        assert!(!lik.objective.specimen_options(&[]).0.beyond_trend);
        assert!(cfg("specimen_scatter = \"trend\"\n").is_err());
        // In a run's identity the estimate beyond the trend is written and the likelihood's
        // is not, as every run before the default changed recorded it: a folder of one is
        // never resumed with the other.
        let written =
            |c: &RunConfig| serde_json::to_value(&c.objective).unwrap()["specimen_scatter"].clone();
        assert_eq!(written(&default), "beyond_stress_trend");
        assert!(written(&lik).is_null());
    }

    #[test]
    fn solver_options_match_the_previous_construction() {
        let s = SolverConfig::default();
        assert_eq!(
            s.lm_options(),
            LmOptions {
                max_iterations: 200,
                ftol: 1e-8,
                geodesic: Some(0.75),
                ..LmOptions::default()
            }
        );
        assert_eq!(
            s.ode_options(),
            OdeOptions {
                rtol: 1e-8,
                atol: 1e-13,
                ..OdeOptions::default()
            }
        );
    }

    #[test]
    fn command_line_overrides_the_file() {
        let cli = Overrides {
            starts: Some(3),
            seed: Some(9),
            w: Some(0.4),
            fit_starts: Some(StartChoice::Guess),
            diagnose: DiagnoseOverrides {
                starts: Some(5),
                bootstrap: Some(199),
                bootstrap_extended: Some(799),
                ..DiagnoseOverrides::default()
            },
            predict_at: None,
            predict_intervals: None,
            run: RunOptions {
                out: Some("o".into()),
                threads: Some(1),
                ..RunOptions::default()
            },
        };
        let c = RunConfig::from_str_with(FULL, Path::new("cfg/run.toml"), &cli).unwrap();
        assert_eq!((c.sweep.starts, c.sweep.seed), (3, 9));
        assert_eq!((c.diagnose.starts, c.diagnose.bootstrap), (5, 199));
        assert_eq!(c.diagnose.most_replicates(), 799);
        assert_eq!(c.diagnose.alpha, 0.05);
        assert_eq!(c.objective.w_grid, vec![0.4]);
        assert!(c.objective.w_sets.is_empty());
        assert_eq!(c.fit.starts, StartChoice::Guess);
        assert_eq!(c.out_dir("fit"), Path::new("o"));
        let bad = Overrides {
            w: Some(1.5),
            ..Overrides::default()
        };
        let e = RunConfig::from_str_with(FULL, Path::new("cfg/run.toml"), &bad)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--w") && e.contains("[0, 1]"), "{e}");
    }

    #[test]
    fn extension_constants_take_their_defaults_with_a_note() {
        let c = parse(&format!(
            "curves = \"a.csv\"\nruptures = \"b.csv\"\nextensions = [\"loading_strain\"]\n{CONSTANTS}"
        ))
        .unwrap();
        assert_eq!(c.constants.len(), 7);
        assert_eq!(c.constants[6].name, "EL");
        assert_eq!(c.warnings.len(), 1);
        assert!(
            c.warnings[0].contains("constants.EL") && c.warnings[0].contains("default"),
            "{:?}",
            c.warnings
        );
        assert_eq!(c.model_name(), "khd+loading_strain");
    }

    /// The serialisation round-trips (the journal stores it; the identity is made from it).
    #[test]
    fn serialisation_round_trips() {
        let c = parse(FULL).unwrap();
        let json = serde_json::to_string(&c).unwrap();
        let mut back: RunConfig = serde_json::from_str(&json).unwrap();
        // units are the model's, not settings
        for (b, c) in back.constants.iter_mut().zip(&c.constants) {
            b.unit = c.unit;
        }
        assert_eq!(back, c);
        assert!(back.validate().is_ok());
    }

    fn err_of(text: &str) -> String {
        let e = parse(text).unwrap_err().to_string();
        assert!(!e.contains('\n'), "multi-line error: {e}");
        assert!(e.starts_with("cfg/run.toml"), "{e}");
        e
    }

    #[test]
    fn errors() {
        let base = "curves = \"a.csv\"\nruptures = \"b.csv\"\n";
        let cases: &[(&str, &str)] = &[
            (
                "bogus = 1\n",
                "cfg/run.toml:3: bogus: unknown field `bogus`",
            ),
            (
                "model = \"nope\"\n",
                "cfg/run.toml:3: model: unknown model 'nope'",
            ),
            (
                "extensions = [\"constant_load\", \"constant_load\"]\n",
                "cfg/run.toml:3: extensions: 'constant_load' is listed twice",
            ),
            (
                "extensions = [\"loading_strain\"]\n[constants]\nEL = { lb = 2, ub = 1 }\n",
                "cfg/run.toml:5: constants.EL: lb (2) must be below ub (1)",
            ),
            (
                "extensions = [\"foo\"]\n",
                "cfg/run.toml:3: extensions: unknown extension 'foo'",
            ),
            (
                "[constants]\nX = { lb = 1, ub = 2 }\n",
                "cfg/run.toml:3: constants: unknown constant 'X'",
            ),
            (
                "[constants]\nB = { lb = 1, ub = 2, foo = 3 }\n",
                "unknown field `foo`",
            ),
            (
                "[constants]\nB = { lb = 2, ub = 1 }\n",
                "cfg/run.toml:4: constants.B: lb (2) must be below ub (1)",
            ),
            (
                "[constants]\nB = { lb = 1, ub = inf }\n",
                "cfg/run.toml:4: constants.B: bounds must be finite",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, scale = \"log\" }\n",
                "constants.B: scale \"log\" needs lb > 0",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, start = 2 }\n",
                "constants.B: start (2) is outside",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, scale = \"ln\" }\n",
                "unknown variant `ln`",
            ),
            // A base constant missing from [constants] is an error naming all missing ones.
            (
                "[constants]\nB = { lb = 0.1, ub = 0.2 }\n",
                "cfg/run.toml:3: constants: missing A, Hstar, h, Kc, C",
            ),
            (
                "[objective]\nw_grid = []\n",
                "cfg/run.toml:4: objective.w_grid: w_grid and w_sets are both empty",
            ),
            (
                "[objective]\nw_grid = [-0.1]\n",
                "cfg/run.toml:4: objective.w_grid: weights must be in [0, 1] (got -0.1)",
            ),
            (
                "[objective]\nw_grid = [0.5, 1.2]\n",
                "objective.w_grid: weights must be in [0, 1] (got 1.2)",
            ),
            (
                "[objective]\n\nw_sets = [[1, 1.01]]\n",
                "cfg/run.toml:5: objective.w_sets[0]: weights must be in [0, 1] (got 1.01)",
            ),
            (
                "[objective]\nomega_f = 1.0\n",
                "objective.omega_f: must be in (0, 1)",
            ),
            (
                "[objective]\nlifetime_term = \"early\"\n",
                "unknown variant `early`",
            ),
            (
                "[solver]\nrtol = 0\n",
                "cfg/run.toml:4: solver.rtol: must be positive",
            ),
            ("[solver]\nftol = 1\n", "solver.ftol: must be in (0, 1)"),
            ("[solver]\natol = -1e-3\n", "solver.atol: must be positive"),
            ("[solver]\nxtol = 1e-3\n", "unknown field `xtol`"),
            (
                "[sweep]\nstarts = 0\n",
                "cfg/run.toml:4: sweep.starts: must be at least 1",
            ),
            (
                "[sweep]\nthreads = 2\n",
                "cfg/run.toml:4: sweep.threads: unknown field `threads`",
            ),
            (
                "[objective]\nomega_f = \"x\"\n",
                "cfg/run.toml:4: objective.omega_f: invalid type",
            ),
            (
                "[constants]\nB = { lb = 1, ub = 2, foo = 3 }\n",
                "cfg/run.toml:4: constants.B.foo: unknown field `foo`",
            ),
            (
                "name = \"../../x\"\n",
                "cfg/run.toml:3: name: '../../x' must not contain",
            ),
            ("name = \"a/b\"\n", "name: 'a/b' must not contain"),
            (
                "interrupted = [\"920\"]\n",
                "cfg/run.toml:3: interrupted: '920': expected \"T:stress\"",
            ),
            (
                "interrupted = [85, \"920:x\"]\n",
                "cfg/run.toml:3: interrupted: '920:x': cannot parse the stress 'x'",
            ),
            (
                "[predict]\ntensile_strength = [\"850:260\", \"850:250\"]\n",
                "cfg/run.toml:4: predict.tensile_strength[1]: 850 °C is given twice",
            ),
            (
                "[predict]\ntensile_strength = [\"850\"]\n",
                "cfg/run.toml:4: predict.tensile_strength[0]: '850': expected T:strength",
            ),
            (
                "interrupted = [85, -1]\n",
                "cfg/run.toml:3: interrupted[1]: stresses must be positive",
            ),
            ("name = \" \"\n", "name: must not be empty"),
        ];
        for (extra, want) in cases {
            // constants first so that a case about another table is not a missing constant
            let text = if extra.contains("[constants]") {
                format!("{base}{extra}")
            } else {
                format!("{base}{extra}{CONSTANTS}")
            };
            let e = err_of(&text);
            assert!(e.contains(want), "for {extra:?}: got {e}, want {want}");
        }
        let e = err_of("ruptures = \"b.csv\"\n");
        assert!(e.contains("missing field `curves`"), "{e}");
    }
    /// Keyed `interrupted` entries through a configuration: the data's two temperatures share
    /// a stress, one test declared; an entry matching no curve names the file and line.
    #[test]
    fn interrupted_keyed_through_the_configuration() {
        let dir = tempfile::tempdir().unwrap();
        let w = |n: &str, t: &str| std::fs::write(dir.path().join(n), t).unwrap();
        w(
            "c.csv",
            "temperature_C,stress_MPa,time_h,strain_pct\n\
             720,80,0,0\n720,80,5,1\n720,80,10,2\n720,90,0,0\n720,90,3,1\n720,90,6,2\n\
             920,80,0,0\n920,80,2,1\n920,80,4,2\n",
        );
        w(
            "r.csv",
            "temperature_C,stress_MPa,rupture_time_h\n720,80,10\n720,90,6\n920,80,4\n",
        );
        let cfg = |interrupted: &str| {
            let p = dir.path().join("run.toml");
            w(
                "run.toml",
                &format!(
                    "curves = \"c.csv\"\nruptures = \"r.csv\"\n{interrupted}\n{}\
                     A = {{ lb = 1e-10, ub = 1e-9, scale = \"log\", law = \"arrhenius\", Q = {{ lb = 0, ub = 500 }} }}\n",
                    CONSTANTS.replace("A     = { lb = 1e-10, ub = 1e-9, scale = \"log\" }\n", "")
                ),
            );
            RunConfig::resolve(&p, &Overrides::default())
        };
        let (_, data) = cfg("interrupted = [\"920:80\"]").unwrap();
        let lives: Vec<Option<f64>> = data.curves.iter().map(|c| c.rupture_time_h).collect();
        assert_eq!(lives, [Some(10.0), Some(6.0), None]);
        let e = cfg("\ninterrupted = [\"920:80\", \"920:90\"]")
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with("run.toml:4: interrupted[1] = 920:90: matches no curve"),
            "{e}"
        );
        let e = cfg("interrupted = [80]").unwrap_err().to_string();
        assert!(
            e.contains("run.toml:3: interrupted[0] = 80: a bare stress is ambiguous")
                && e.contains("\"720:80\""),
            "{e}"
        );
    }
}
