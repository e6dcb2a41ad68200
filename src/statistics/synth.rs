//! Synthetic creep data sets for measuring `diagnose` (and anything else) on data it was not
//! made from: material families with jittered constants, 3–5 stresses, digitised-like or
//! logged sampling that ends before rupture (95–100 % of life), some curves cut at a strain
//! limit, white or AR(1) reading error of 0.005–0.03 % strain, ≈ 1 % scatter of rupture
//! times, shuffled rows — with every catalogued extension over a range of sizes, no effect,
//! and two effects outside the catalogue. Every set is written in the input formats (curves
//! CSV, ruptures CSV, a run configuration) with its truth (`truth.json`).
//!
//! The generator shares the crate's model code (the true curves are the crate's simulations
//! of the true model), but not its estimation: sampling, noise, cut-offs and the effects
//! outside the catalogue are built here independently of what `diagnose` assumes.

use std::path::Path;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::model::{build, Load};
use crate::ode::OdeOptions;

/// A material family: KHD constants [A, B, H*, h, Kc, C], a stress range and a search box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Family {
    /// Name in `truth.json`.
    pub name: &'static str,
    /// Test temperature written to the files, °C.
    pub temperature_c: f64,
    /// Central constants [A 1/h, B 1/MPa, H*, h MPa, Kc 1/h, C].
    pub constants: [f64; 6],
    /// Stress range, MPa.
    pub stress: (f64, f64),
    /// Bounds [lb, ub] of the configuration written with each set.
    pub bounds: [(f64, f64); 6],
}

/// The families: the 0.5CrMoV steel of the seed paper at 560 °C and at 590 °C (constants of
/// `creepfit fit` on the seed data, h moved inside the box at 590 °C), and a stronger,
/// more ductile steel (a 9Cr-like family: lower A, higher stresses, C ≈ 2.5).
pub const FAMILIES: [Family; 3] = [
    Family {
        name: "cmv560",
        temperature_c: 560.0,
        constants: [1.0e-10, 0.1749, 0.563, 5.9e4, 2.21e-5, 4.03],
        stress: (80.0, 115.0),
        bounds: BOX,
    },
    Family {
        name: "cmv590",
        temperature_c: 590.0,
        constants: [5.0e-9, 0.1062, 0.30, 1.5e5, 6.9e-5, 3.0],
        stress: (95.0, 125.0),
        bounds: BOX,
    },
    Family {
        name: "p91like",
        temperature_c: 600.0,
        constants: [2.0e-11, 0.085, 0.45, 8.0e4, 1.0e-5, 2.5],
        stress: (130.0, 180.0),
        bounds: BOX,
    },
];

/// The search box of the generated configurations: wide around every family.
const BOX: [(f64, f64); 6] = [
    (1e-13, 1e-7),
    (0.03, 0.4),
    (0.1, 0.9),
    (5e3, 1e6),
    (1e-7, 1e-3),
    (1.0, 15.0),
];

/// The effect hidden in a data set, with its size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Effect {
    /// The base model as it is.
    None,
    /// Constant-load tests (catalogued; no size parameter: the effect grows with the rupture
    /// strain).
    ConstantLoad,
    /// Strain on loading σ/E_L (catalogued), E_L in MPa.
    LoadingStrain { e_l: f64 },
    /// Dislocation multiplication, rate × (1 + C_d ε) (catalogued).
    DislocationDamage { c_d: f64 },
    /// Ductility (σ/100 MPa)^−ν (catalogued).
    StressDuctility { nu: f64 },
    /// Strain softening, rate × (1 + φ0 (ε/0.2)^φ1) (catalogued; φ0 the rate's increase at
    /// 20 % strain, as the extension's constant).
    StrainSoftening { phi0: f64, phi1: f64 },
    /// Damage at rupture ω_f instead of 1/3 (catalogued).
    RuptureDamage { omega_f: f64 },
    /// Outside the catalogue: an extra transient primary strain amp·ε_f·(1 − e^(−t/(τ t_r)))
    /// (anelastic recovery strain, a second primary mechanism).
    PrimaryTransient { amp: f64, tau: f64 },
    /// Outside the catalogue: a sudden extra strain amp·ε_f at mid-life, a logistic step of
    /// width 4 % of life (a microstructural instability or a furnace excursion).
    MidLifeStep { amp: f64 },
}

impl Effect {
    /// Scenario name: `none`, the extension's name, or the effect's.
    pub fn name(&self) -> &'static str {
        match self {
            Effect::None => "none",
            Effect::ConstantLoad => "constant_load",
            Effect::LoadingStrain { .. } => "loading_strain",
            Effect::DislocationDamage { .. } => "dislocation_damage",
            Effect::StressDuctility { .. } => "stress_ductility",
            Effect::StrainSoftening { .. } => "strain_softening",
            Effect::RuptureDamage { .. } => "rupture_damage",
            Effect::PrimaryTransient { .. } => "primary_transient",
            Effect::MidLifeStep { .. } => "mid_life_step",
        }
    }
    /// Whether the effect is in the extension catalogue.
    pub fn catalogued(&self) -> bool {
        crate::model::ext::CATALOGUE.contains(&self.name())
    }
    /// The catalogued extension that models the effect and its constants' true values
    /// (appended to the base model's); empty for none and for effects outside the catalogue.
    pub fn true_extension(&self) -> (Vec<String>, Vec<f64>) {
        match *self {
            Effect::ConstantLoad => (vec!["constant_load".into()], vec![]),
            Effect::LoadingStrain { e_l } => (vec!["loading_strain".into()], vec![e_l]),
            Effect::DislocationDamage { c_d } => (vec!["dislocation_damage".into()], vec![c_d]),
            Effect::StressDuctility { nu } => (vec!["stress_ductility".into()], vec![nu]),
            Effect::StrainSoftening { phi0, phi1 } => {
                (vec!["strain_softening".into()], vec![phi0, phi1])
            }
            Effect::RuptureDamage { omega_f } => (vec!["rupture_damage".into()], vec![omega_f]),
            _ => (vec![], vec![]),
        }
    }
    /// The effect's size as one number (for power-versus-size tables): E_L in MPa, C_d, ν,
    /// φ0 (the rate's increase at 20 % strain; until 2026-11-28 the prefactor of ε^φ1), ω_f,
    /// amp (fraction of ε_f); 0 for none and constant load.
    pub fn size(&self) -> f64 {
        match *self {
            Effect::None | Effect::ConstantLoad => 0.0,
            Effect::LoadingStrain { e_l } => e_l,
            Effect::DislocationDamage { c_d } => c_d,
            Effect::StressDuctility { nu } => nu,
            Effect::StrainSoftening { phi0, .. } => phi0,
            Effect::RuptureDamage { omega_f } => omega_f,
            Effect::PrimaryTransient { amp, .. } => amp,
            Effect::MidLifeStep { amp } => amp,
        }
    }
}

/// The scenarios of `synth` and of a battery's tables (the battery's cycle is [`scenario_of`]).
pub const SCENARIOS: [&str; 9] = [
    "none",
    "constant_load",
    "loading_strain",
    "dislocation_damage",
    "stress_ductility",
    "primary_transient",
    "mid_life_step",
    "strain_softening",
    "rupture_damage",
];

/// How the curves were sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Points clicked along the plotted curve: 25–70 per curve, about evenly along its arc
    /// length in the normalised plot, jittered.
    Digitised,
    /// A data logger: 200–600 points per curve at regular intervals of time.
    Logged,
}

/// The laboratory the data come from: identical specimens (every curve the true model's), or
/// specimens as real laboratories test them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum World {
    /// Every specimen the population's: the sets of earlier batteries, bit for bit.
    #[default]
    Identical,
    /// Specimens that are not identical: each curve's creep rate carries its own log-normal
    /// factor (sd 10–30 %), in half the sets its ductility too (sd 8 %); one or two stresses
    /// are tested twice (replicates, with a `specimen` column); the reading error grows with
    /// strain (sd × (1 + g ε/ε_f), g up to 2). Drawn from a stream of its own, so that the
    /// rest of a set (family, stresses, sampling, noise) is the identical world's.
    Specimens,
    /// The specimens world, and each specimen also its own onset of tertiary creep: a
    /// log-normal factor on the coarsening rate (KHD: Kc, sd 15–50 %), as Alloy 617's
    /// specimens differ in shape. The rate, ductility, replicates and error growth are the
    /// specimens world's for the same seed (drawn first from the same stream); the sets'
    /// configurations fit all three kinds of specimen effects, as the shipped Alloy 617
    /// configurations do.
    Shapes,
    /// The specimens world with its specimens from two test campaigns (heats or
    /// laboratories, `A` and `B`): each campaign carries its own log-normal factor on the
    /// creep rate (sd 10–40 % between campaigns) on top of each specimen's. The tests
    /// alternate between the campaigns in stress order (a replicate pair is split between
    /// them), labelled `A-1`, `B-1`, `A-2`, … Everything else is the specimens world's for the
    /// same seed (the campaign factors drawn last from the same stream), and the sets'
    /// configurations are too (`auto` specimen effects, which read the campaign factor as part
    /// of each specimen's).
    Campaigns,
}

impl World {
    /// Whether the world's specimens differ (a `specimen` column, factors in the truth).
    pub fn has_specimens(self) -> bool {
        self != World::Identical
    }
}

/// The specimens of a set in the [`World::Specimens`] world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct SpecimenTruth {
    /// sd of the ln creep-rate factor between specimens.
    pub rate_sd: f64,
    /// sd of the ln ductility factor (0: none).
    pub ductility_sd: f64,
    /// Per curve: its ln creep-rate factor.
    pub rate_effects: Vec<f64>,
    /// Per curve: its ln ductility factor (rupture strain × e^ζ).
    pub ductility_effects: Vec<f64>,
    /// sd of the ln coarsening-rate factor (0: none; world `shapes` only).
    #[serde(default)]
    pub coarsening_sd: f64,
    /// Per curve: its ln coarsening-rate factor (Kc × e^κ; empty without).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub coarsening_effects: Vec<f64>,
    /// Per curve: the specimen label written to the files.
    pub labels: Vec<String>,
    /// sd of the ln creep-rate factor between campaigns (0: none; world `campaigns` only).
    #[serde(default)]
    pub campaign_sd: f64,
    /// Per curve: the ln creep-rate factor of its campaign, included in `rate_effects` (empty
    /// without campaigns).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub campaign_effects: Vec<f64>,
    /// Growth of the reading error with strain: sd × (1 + g ε/ε_f).
    pub error_growth: f64,
    /// Per curve: the ε_f of that growth, the true strain at which the curve's reading error
    /// is (1 + g) times its start (fraction). Empty in sets written before 2026-12-05: then
    /// each curve's largest true strain stands for it ([`SpecimenTruth::growth_strain`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub error_growth_strain: Vec<f64>,
}

impl SpecimenTruth {
    /// The factor on the reading error at strain `e` of a curve whose growth ends at `eps_f`
    /// (both fractions): 1 + g e/ε_f, as the data were drawn.
    pub fn reading_factor(&self, e: f64, eps_f: f64) -> f64 {
        1.0 + self.error_growth * e / eps_f
    }

    /// The ε_f of curve `i`'s reading-error growth ([`SpecimenTruth::error_growth_strain`]),
    /// or `largest` (the curve's largest true strain) where the set did not record it.
    pub fn growth_strain(&self, i: usize, largest: f64) -> f64 {
        self.error_growth_strain.get(i).copied().unwrap_or(largest)
    }

    /// The true scatter per kind: rate, ductility, and coarsening in world `shapes`. In world
    /// `campaigns` the rate's is that of a new specimen from a new campaign,
    /// √(specimen sd² + campaign sd²): what iid specimen factors stand for.
    pub fn scatter_true(&self) -> Vec<f64> {
        let rate = self.rate_sd.hypot(self.campaign_sd);
        let mut v = vec![rate, self.ductility_sd];
        if !self.coarsening_effects.is_empty() {
            v.push(self.coarsening_sd);
        }
        v
    }
}

/// Separates the specimen world's random stream from the set's own.
const SPECIMEN_STREAM: u64 = 0x5ee0_5ca7_7e25_0001;

/// Everything that defines a generated set (the truth).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Set name.
    pub name: String,
    /// Seed it was generated from.
    pub seed: u64,
    /// Family name.
    pub family: String,
    /// Temperature, °C.
    pub temperature_c: f64,
    /// The hidden effect.
    pub effect: Effect,
    /// True KHD constants [A, B, H*, h, Kc, C].
    pub constants: Vec<f64>,
    /// Stresses, MPa, one per curve (a replicated stress twice).
    pub stresses: Vec<f64>,
    /// Sampling.
    pub sampling: Sampling,
    /// Reading error: marginal sd per curve (strain fraction) and AR(1) correlation.
    pub noise_sd: Vec<f64>,
    pub noise_phi: f64,
    /// Scatter of rupture times (sd of ln t).
    pub lifetime_sd: f64,
    /// Strain limit (fraction) the curves were cut at, if any.
    pub strain_cut: Option<f64>,
    /// Per curve: the true rupture time (h) and the measured one.
    pub true_rupture_h: Vec<f64>,
    pub rupture_h: Vec<f64>,
    /// Per curve: the noise-free strain at the sampled times (fraction).
    pub true_strain: Vec<Vec<f64>>,
    /// Per curve: the sampled times (h).
    pub times_h: Vec<Vec<f64>>,
    /// The world the set comes from.
    #[serde(default)]
    pub world: World,
    /// The specimens (worlds `specimens` and `shapes`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specimens: Option<SpecimenTruth>,
}

/// One generated data set: its files' contents and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSet {
    /// The truth.
    pub truth: Truth,
    /// `curves.csv`.
    pub curves_csv: String,
    /// `ruptures.csv`.
    pub ruptures_csv: String,
    /// `config.toml` (paths relative to the set's folder).
    pub config_toml: String,
}

fn normal<R: Rng>(rng: &mut R) -> f64 {
    rng.sample(StandardNormal)
}

fn log_uniform<R: Rng>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.gen::<f64>() * (hi.ln() - lo.ln())).exp()
}

/// Draw the effect of a scenario with a random size.
pub fn draw_effect<R: Rng>(scenario: &str, rng: &mut R) -> Effect {
    match scenario {
        "constant_load" => Effect::ConstantLoad,
        // E_L so that σ/E_L spans about 0.03–1.5 % strain at 100 MPa.
        "loading_strain" => Effect::LoadingStrain {
            e_l: log_uniform(rng, 7e3, 3e5),
        },
        "dislocation_damage" => Effect::DislocationDamage {
            c_d: log_uniform(rng, 0.5, 40.0),
        },
        "stress_ductility" => {
            let m = 0.3 + 3.7 * rng.gen::<f64>();
            Effect::StressDuctility {
                nu: if rng.gen::<bool>() { m } else { -m },
            }
        }
        // At the families' rupture strains (≈ 0.05–0.15) the rate factor 1 + k ε^φ1 at rupture
        // spans ≈ 1.0001 to ≈ 40 (measured: sets with factors 1.02–1.03 and 1.10–1.15 at the
        // last point, seeds 12 and 14, gave `adequate`; an upper end of k = 150 stayed there).
        // Drawn as the prefactor k of ε^φ1 (the extension's form until 2026-11-28, so the
        // sets are the same), given as the extension's φ0 = k·0.2^φ1.
        "strain_softening" => {
            let k = log_uniform(rng, 2.0, 2000.0);
            let phi1 = 1.5 + 1.5 * rng.gen::<f64>();
            Effect::StrainSoftening {
                phi0: k * crate::model::ext::strain_softening::EPS_REF.powf(phi1),
                phi1,
            }
        }
        // ω_f = (1/3)·r^±1, r from 1.05 to 2: rupture strain and final acceleration change.
        "rupture_damage" => {
            let r = log_uniform(rng, 1.05, 2.0);
            Effect::RuptureDamage {
                omega_f: if rng.gen::<bool>() {
                    r / 3.0
                } else {
                    1.0 / (3.0 * r)
                },
            }
        }
        "primary_transient" => Effect::PrimaryTransient {
            amp: log_uniform(rng, 0.01, 0.1),
            tau: 0.02 + 0.08 * rng.gen::<f64>(),
        },
        "mid_life_step" => Effect::MidLifeStep {
            amp: log_uniform(rng, 0.01, 0.08),
        },
        _ => Effect::None,
    }
}

/// Jittered constants of a family, inside its box.
fn jitter<R: Rng>(f: &Family, rng: &mut R) -> [f64; 6] {
    let c = f.constants;
    let mut x = [
        c[0] * (0.3 * normal(rng)).exp(),
        c[1] * (1.0 + 0.05 * normal(rng)),
        c[2] + 0.05 * normal(rng),
        c[3] * (0.3 * normal(rng)).exp(),
        c[4] * (0.3 * normal(rng)).exp(),
        c[5] * (1.0 + 0.1 * normal(rng)),
    ];
    for (v, (lo, hi)) in x.iter_mut().zip(f.bounds) {
        // Keep 2 % of the (log) box away from the bounds.
        let (l, h) = if lo > 0.0 && hi / lo > 50.0 {
            let (a, b) = (lo.ln(), hi.ln());
            ((a + 0.02 * (b - a)).exp(), (b - 0.02 * (b - a)).exp())
        } else {
            (lo + 0.02 * (hi - lo), hi - 0.02 * (hi - lo))
        };
        *v = v.clamp(l, h);
    }
    x
}

/// Normalised arc-length positions → times: `n` points about evenly along the curve
/// (t/t_last, ε/ε_last) with jitter, first at t = 0.
fn digitised_times<R: Rng>(dense_t: &[f64], dense_e: &[f64], n: usize, rng: &mut R) -> Vec<f64> {
    let m = dense_t.len();
    let (tl, el) = (dense_t[m - 1], dense_e[m - 1].max(1e-12));
    let mut s = vec![0.0; m];
    for k in 1..m {
        let dt = (dense_t[k] - dense_t[k - 1]) / tl;
        let de = (dense_e[k] - dense_e[k - 1]) / el;
        s[k] = s[k - 1] + (dt * dt + de * de).sqrt();
    }
    let total = s[m - 1];
    let mut out = vec![0.0];
    for k in 1..n - 1 {
        let target = (k as f64 + 0.35 * (2.0 * rng.gen::<f64>() - 1.0)) / (n - 1) as f64 * total;
        let j = s.partition_point(|v| *v < target).clamp(1, m - 1);
        let f = (target - s[j - 1]) / (s[j] - s[j - 1]).max(1e-300);
        out.push(dense_t[j - 1] + f.clamp(0.0, 1.0) * (dense_t[j] - dense_t[j - 1]));
    }
    out.push(tl);
    out.sort_by(|a, b| a.total_cmp(b));
    out
}

/// Generate the set `name` of `scenario` from `seed`.
pub fn generate(name: &str, scenario: &str, seed: u64) -> Result<SynthSet> {
    generate_inner(name, scenario, None, seed, World::Identical)
}

/// [`generate`] with the effect (and its size) given instead of drawn; everything else is
/// drawn from `seed` as for the effect's scenario.
pub fn generate_with_effect(name: &str, effect: Effect, seed: u64) -> Result<SynthSet> {
    generate_inner(name, effect.name(), Some(effect), seed, World::Identical)
}

/// [`generate`] in `world` (with `effect` given, or drawn for `scenario` when `None`).
pub fn generate_in(
    name: &str,
    scenario: &str,
    effect: Option<Effect>,
    seed: u64,
    world: World,
) -> Result<SynthSet> {
    generate_inner(name, scenario, effect, seed, world)
}

/// The specimens of a set of `stresses` in the specimens world, from their own stream:
/// replicated stresses, labels, effects, the error growth; in world `shapes` then the
/// coarsening factors, drawn last so that everything before is the specimens world's.
fn draw_specimens(stresses: &[f64], seed: u64, world: World) -> (Vec<f64>, SpecimenTruth) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ SPECIMEN_STREAM);
    let rate_sd = 0.1 + 0.2 * rng.gen::<f64>();
    let ductility_sd = if rng.gen::<bool>() { 0.08 } else { 0.0 };
    let n_rep = rng.gen_range(1..=2usize).min(stresses.len());
    let mut reps: Vec<usize> = (0..stresses.len()).collect();
    reps.shuffle(&mut rng);
    reps.truncate(n_rep);
    let mut tests = Vec::new();
    let mut labels = Vec::new();
    for (k, &s) in stresses.iter().enumerate() {
        tests.push(s);
        labels.push(format!("S{}-a", k + 1));
        if reps.contains(&k) {
            tests.push(s);
            labels.push(format!("S{}-b", k + 1));
        }
    }
    let mut rate_effects: Vec<f64> = tests.iter().map(|_| rate_sd * normal(&mut rng)).collect();
    let ductility_effects = tests
        .iter()
        .map(|_| ductility_sd * normal(&mut rng))
        .collect();
    let error_growth = 2.0 * rng.gen::<f64>();
    let (coarsening_sd, coarsening_effects) = if world == World::Shapes {
        let sd = 0.15 + 0.35 * rng.gen::<f64>();
        (sd, tests.iter().map(|_| sd * normal(&mut rng)).collect())
    } else {
        (0.0, vec![])
    };
    let (campaign_sd, campaign_effects) = if world == World::Campaigns {
        let sd = 0.1 + 0.3 * rng.gen::<f64>();
        let levels = [sd * normal(&mut rng), sd * normal(&mut rng)];
        let mut count = [0usize; 2];
        let mut effects = Vec::with_capacity(tests.len());
        for (k, label) in labels.iter_mut().enumerate() {
            let c = k % 2;
            count[c] += 1;
            *label = format!("{}-{}", ["A", "B"][c], count[c]);
            rate_effects[k] += levels[c];
            effects.push(levels[c]);
        }
        (sd, effects)
    } else {
        (0.0, vec![])
    };
    (
        tests,
        SpecimenTruth {
            rate_sd,
            ductility_sd,
            rate_effects,
            ductility_effects,
            coarsening_sd,
            coarsening_effects,
            labels,
            campaign_sd,
            campaign_effects,
            error_growth,
            error_growth_strain: vec![],
        },
    )
}

fn generate_inner(
    name: &str,
    scenario: &str,
    effect: Option<Effect>,
    seed: u64,
    world: World,
) -> Result<SynthSet> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let family = FAMILIES[rng.gen_range(0..FAMILIES.len())];
    let drawn = draw_effect(scenario, &mut rng);
    let effect = effect.unwrap_or(drawn);
    let base = jitter(&family, &mut rng);
    let n_stress = rng.gen_range(3..=5);
    let (lo, hi) = family.stress;
    let stresses: Vec<f64> = (0..n_stress)
        .map(|k| {
            let s = lo + (hi - lo) * k as f64 / (n_stress - 1) as f64;
            (s + 2.0 * (2.0 * rng.gen::<f64>() - 1.0)).round()
        })
        .collect();
    let (tests, specimens) = match world {
        World::Identical => (stresses.clone(), None),
        World::Specimens | World::Shapes | World::Campaigns => {
            let (t, sp) = draw_specimens(&stresses, seed, world);
            (t, Some(sp))
        }
    };
    let sampling = if rng.gen::<f64>() < 0.75 {
        Sampling::Digitised
    } else {
        Sampling::Logged
    };
    let noise_level = 5e-5 + 2.5e-4 * rng.gen::<f64>();
    let noise_phi = if rng.gen::<bool>() {
        0.0
    } else {
        0.3 + 0.6 * rng.gen::<f64>()
    };
    let cut = rng.gen::<f64>() < 0.2;
    let lifetime_sd = 0.01;

    // The true model.
    let (exts, extra) = effect.true_extension();
    let model = build("khd", &exts)?;
    let mut params = base.to_vec();
    params.extend(extra);
    let ode = OdeOptions {
        rtol: 1e-11,
        atol: 1e-15,
        ..OdeOptions::default()
    };
    let mut truth = Truth {
        name: name.to_string(),
        seed,
        family: family.name.to_string(),
        temperature_c: family.temperature_c,
        effect,
        constants: base.to_vec(),
        stresses: tests.clone(),
        sampling,
        noise_sd: vec![],
        noise_phi,
        lifetime_sd,
        strain_cut: None,
        true_rupture_h: vec![],
        rupture_h: vec![],
        true_strain: vec![],
        times_h: vec![],
        world,
        specimens: specimens.clone(),
    };
    let mut rows: Vec<(f64, f64)> = Vec::new(); // (stress, time, strain) via parallel vecs
    let mut row_stress: Vec<f64> = Vec::new();
    let mut row_test: Vec<usize> = Vec::new();
    let mut ruptures = String::from(if specimens.is_some() {
        "temperature_C,stress_MPa,rupture_time_h,specimen\n"
    } else {
        "temperature_C,stress_MPa,rupture_time_h\n"
    });
    // Simulate every curve densely to its rupture.
    let mut dense: Vec<(f64, Vec<f64>, Vec<f64>)> = Vec::new();
    // The constants of test k: the population's with its specimen's factors (A × e^η,
    // C / e^ζ, Kc × e^κ).
    let test_params = |k: usize| -> Vec<f64> {
        let mut p = params.clone();
        if let Some(sp) = &specimens {
            p[0] *= sp.rate_effects[k].exp();
            p[5] /= sp.ductility_effects[k].exp();
            if let Some(kappa) = sp.coarsening_effects.get(k) {
                p[4] *= kappa.exp();
            }
        }
        p
    };
    for (k, &s) in tests.iter().enumerate() {
        let params = test_params(k);
        let load = Load::new(s, family.temperature_c, 1.0 / 3.0);
        let r = model.simulate(&params, &load, &[], &mut [], &ode);
        if !(r.ruptured() && r.t_end > 1.0 && r.t_end < 1e7) {
            return Err(Error::Invalid(format!(
                "synth {name}: the true model does not rupture in [1 h, 1e7 h] at {s} MPa"
            )));
        }
        let t_r = r.t_end;
        let grid: Vec<f64> = (0..=2000)
            .map(|k| t_r * (1.0 - (1.0 - k as f64 / 2000.0).powi(2)) * 0.9999)
            .collect();
        let mut e = vec![0.0; grid.len()];
        model.simulate(&params, &load, &grid, &mut e, &ode);
        dense.push((t_r, grid, e));
    }
    let eps_f_min = dense
        .iter()
        .map(|d| *d.2.last().unwrap())
        .fold(f64::INFINITY, f64::min);
    let strain_cut = cut.then(|| {
        // A plot edge at a round value below the least ductile curve's end.
        let lim = 0.7 * eps_f_min * 100.0;
        let step = if lim > 5.0 { 1.0 } else { 0.5 };
        ((lim / step).floor() * step).max(step) / 100.0
    });
    truth.strain_cut = strain_cut;
    for (i, &s) in tests.iter().enumerate() {
        let params = test_params(i);
        let (t_r, grid, e) = &dense[i];
        let load = Load::new(s, family.temperature_c, 1.0 / 3.0);
        let last = t_r * (0.95 + 0.05 * rng.gen::<f64>());
        let upto = grid.partition_point(|t| *t <= last).max(2);
        let mut times = match sampling {
            Sampling::Digitised => {
                let n = rng.gen_range(25..=70);
                digitised_times(&grid[..upto], &e[..upto], n, &mut rng)
            }
            Sampling::Logged => {
                let n = rng.gen_range(200..=600);
                (0..n).map(|k| last * k as f64 / (n - 1) as f64).collect()
            }
        };
        times[0] = 0.0;
        let mut strain = vec![0.0; times.len()];
        model.simulate(&params, &load, &times, &mut strain, &ode);
        let eps_f = e[upto - 1];
        for (k, v) in strain.iter_mut().enumerate() {
            let tau = times[k] / t_r;
            match effect {
                Effect::PrimaryTransient { amp, tau: tt } => {
                    *v += amp * eps_f * (1.0 - (-tau / tt).exp())
                }
                Effect::MidLifeStep { amp } => {
                    *v += amp * eps_f / (1.0 + (-(tau - 0.5) / 0.04).exp())
                }
                _ => {}
            }
        }
        if let Some(lim) = strain_cut {
            let keep = strain.iter().take_while(|v| **v <= lim).count().max(10);
            times.truncate(keep);
            strain.truncate(keep);
        }
        let sd = noise_level * (0.8 + 0.45 * rng.gen::<f64>());
        let ar = crate::errmodel::Ar1::with_marginal(sd, noise_phi);
        let mut err = ar.simulate(times.len(), &mut rng);
        if let Some(sp) = &specimens {
            for (v, e) in err.iter_mut().zip(&strain) {
                *v *= sp.reading_factor(*e, eps_f);
            }
        }
        if let Some(sp) = truth.specimens.as_mut() {
            sp.error_growth_strain.push(eps_f);
        }
        for k in 0..times.len() {
            rows.push((times[k], strain[k] + err[k]));
            row_stress.push(s);
            row_test.push(i);
        }
        let t_f = t_r * (lifetime_sd * normal(&mut rng)).exp();
        match &specimens {
            None => ruptures += &format!("{},{},{}\n", family.temperature_c, s, fmt(t_f)),
            Some(sp) => {
                ruptures += &format!(
                    "{},{},{},{}\n",
                    family.temperature_c,
                    s,
                    fmt(t_f),
                    sp.labels[i]
                )
            }
        }
        truth.noise_sd.push(sd);
        truth.true_rupture_h.push(*t_r);
        truth.rupture_h.push(t_f);
        truth.true_strain.push(strain);
        truth.times_h.push(times);
    }
    // Shuffled rows.
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.shuffle(&mut rng);
    let mut curves = String::from(if specimens.is_some() {
        "temperature_C,stress_MPa,time_h,strain_pct,specimen\n"
    } else {
        "temperature_C,stress_MPa,time_h,strain_pct\n"
    });
    for k in order {
        curves += &format!(
            "{},{},{},{}",
            family.temperature_c,
            row_stress[k],
            fmt(rows[k].0),
            fmt(100.0 * rows[k].1)
        );
        if let Some(sp) = &specimens {
            curves += ",";
            curves += &sp.labels[row_test[k]];
        }
        curves += "\n";
    }
    let names = ["A", "B", "Hstar", "h", "Kc", "C"];
    let logs = [true, false, false, true, true, false];
    let mut config = format!(
        "# Generated by `creepfit synth` (seed {seed}, scenario {scenario}); truth in truth.json.\n\
         name = \"{name}\"\ncurves = \"curves.csv\"\nruptures = \"ruptures.csv\"\n\
         temperature_C = {}\nmodel = \"khd\"\n\n[constants]\n",
        family.temperature_c
    );
    for j in 0..6 {
        let (l, u) = family.bounds[j];
        config += &format!(
            "{:<5} = {{ lb = {l:e}, ub = {u:e}{} }}\n",
            names[j],
            if logs[j] { ", scale = \"log\"" } else { "" }
        );
    }
    if world == World::Shapes {
        config += "\n[objective]\nspecimen_effects = [\"rate\", \"ductility\", \"coarsening\"]\n";
    }
    Ok(SynthSet {
        truth,
        curves_csv: curves,
        ruptures_csv: ruptures,
        config_toml: config,
    })
}

/// `config` (a generated set's `config.toml`) with `[objective] specimen_effects` set to
/// `kinds`: the line replaced where the configuration has one, else the table added.
pub fn with_specimen_effects(config: &str, kinds: &[crate::likelihood::EffectKind]) -> String {
    let list = kinds
        .iter()
        .map(|k| format!("\"{}\"", k.name()))
        .collect::<Vec<_>>()
        .join(", ");
    let line = format!("specimen_effects = [{list}]");
    if config.lines().any(|l| l.starts_with("specimen_effects")) {
        config
            .lines()
            .map(|l| {
                if l.starts_with("specimen_effects") {
                    line.clone()
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    } else {
        format!("{config}\n[objective]\n{line}\n")
    }
}

/// `config` (a generated set's configuration) with `[objective] specimen_scatter = how`: the
/// line added to its `[objective]` table, or the table added.
pub fn with_specimen_scatter(config: &str, how: crate::likelihood::SpecimenScatter) -> String {
    let word = match how {
        crate::likelihood::SpecimenScatter::Likelihood => "likelihood",
        crate::likelihood::SpecimenScatter::BeyondStressTrend => "beyond_stress_trend",
    };
    with_line_in(
        config,
        "objective",
        &format!("specimen_scatter = \"{word}\""),
    )
}

/// `config` with `line` added first in its table `[table]`, or the table added at the end.
fn with_line_in(config: &str, table: &str, line: &str) -> String {
    let head = format!("[{table}]");
    let lines: Vec<&str> = config.lines().collect();
    match lines.iter().position(|l| l.trim() == head) {
        Some(at) => {
            let mut out: Vec<&str> = lines.clone();
            out.insert(at + 1, line);
            out.join("\n") + "\n"
        }
        None => format!("{config}\n{head}\n{line}\n"),
    }
}

/// `config` (a generated set's configuration) with `[diagnose] bootstrap_extended = most`: a
/// battery's sets then sample a test close to significance on to `most` replicates.
pub fn with_bootstrap_extended(config: &str, most: usize) -> String {
    with_line_in(config, "diagnose", &format!("bootstrap_extended = {most}"))
}

/// `config` (a generated set's configuration, which has no such line) with `[diagnose]
/// max_points = n`: the most points per curve `diagnose` works on.
pub fn with_diagnose_max_points(config: &str, n: usize) -> String {
    with_line_in(config, "diagnose", &format!("max_points = {n}"))
}

/// `config` (a generated set's configuration, which has no such line) with `[diagnose]
/// reduction = how`: how `diagnose` reduces a curve longer than `max_points`.
pub fn with_diagnose_reduction(config: &str, how: crate::data::Reduction) -> String {
    with_line_in(
        config,
        "diagnose",
        &format!("reduction = \"{}\"", how.as_str()),
    )
}

/// `config` (a generated set's configuration, which has no such line) with `[diagnose]
/// misfit_share = how`: how `diagnose` weighs `strain_means`' group means.
pub fn with_diagnose_misfit_share(config: &str, how: crate::data::MisfitShare) -> String {
    with_line_in(
        config,
        "diagnose",
        &format!("misfit_share = \"{}\"", how.as_str()),
    )
}

/// Shortest round-trip text of a number.
fn fmt(v: f64) -> String {
    format!("{v}")
}

/// Write `set` into folder `dir` (created): curves.csv, ruptures.csv, config.toml, truth.json.
pub fn write_set(set: &SynthSet, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let w = |f: &str, text: &str| -> Result<()> {
        let p = dir.join(f);
        std::fs::write(&p, text).map_err(|e| Error::io(&p, e))
    };
    w("curves.csv", &set.curves_csv)?;
    w("ruptures.csv", &set.ruptures_csv)?;
    w("config.toml", &set.config_toml)?;
    w("truth.json", &truth_json(&set.truth))
}

/// truth.json's text (pretty JSON).
pub fn truth_json(truth: &Truth) -> String {
    serde_json::to_string_pretty(truth).expect("plain values")
}

/// `Ok` for a scenario of [`SCENARIOS`], else the error of a `--scenario` option naming the
/// known ones.
pub fn check_scenario(sc: &str) -> Result<()> {
    if SCENARIOS.contains(&sc) {
        return Ok(());
    }
    Err(Error::Invalid(format!(
        "--scenario: unknown scenario '{sc}' (known: {})",
        SCENARIOS.join(", ")
    )))
}

/// The scenario of set `i` of a battery: sets cycle through [`SCENARIOS`] with `none` twice
/// as often (a quarter of a battery is null data, for the false-alarm rate), except
/// `strain_softening` and `rupture_damage`, which `synth --scenario` generates but the
/// battery's cycle (and so its measured rates) does not include yet.
pub fn scenario_of(i: usize) -> &'static str {
    const CYCLE: [&str; 8] = [
        "none",
        "constant_load",
        "loading_strain",
        "dislocation_damage",
        "none",
        "stress_ductility",
        "primary_transient",
        "mid_life_step",
    ];
    CYCLE[i % CYCLE.len()]
}

/// The configuration of [`two_temperature_set`]'s data: KHD with A and Kc Arrhenius (T_ref the
/// mean test temperature, 575 °C), boxes about the seed steel's (paths are placeholders: the
/// data come in memory).
pub const TWO_TEMPERATURE_CONFIG: &str = r#"
name = "two-temperatures"
curves = "curves.csv"
ruptures = "ruptures.csv"
model = "khd"
extensions = []
[constants]
A     = { lb = 1e-11, ub = 1e-7, scale = "log", law = "arrhenius", Q = { lb = 0, ub = 1000 } }
B     = { lb = 0.05,  ub = 0.3 }
Hstar = { lb = 0.2,   ub = 0.9 }
h     = { lb = 1e3,   ub = 1e6,  scale = "log" }
Kc    = { lb = 1e-7,  ub = 1e-3, scale = "log", law = "arrhenius", Q = { lb = 0, ub = 1000 } }
C     = { lb = 1.5,   ub = 10 }
[objective]
w_grid = [1.0]
"#;

/// A generated data set at two temperatures for the joint calibration and `diagnose`: KHD
/// with A and Kc Arrhenius about 575 °C, its truth drawn from `seed` about the seed steel's
/// (A_ref, h, Kc_ref ×/÷ e^0.3, B ± 5 %, H* ± 0.03, C ± 10 %, Q_A 350 ± 50, Q_Kc 250 ± 50 kJ/mol),
/// three curves at 560 °C (85/100/110 MPa) and three at 590 °C (75/90/100 MPa), each stress ± 2
/// MPa; 30 points a curve to rupture; an AR(1) reading error of marginal sd 0.005–0.03 %
/// strain with φ = 0 (half the sets) or 0.3–0.9; a 1 % log-normal scatter of the rupture times.
/// `effect` (an extension's name and the value of its constant) adds that extension to the
/// truth (common to both temperatures). `None` when a curve does not rupture.
pub fn two_temperature_set(
    seed: u64,
    effect: Option<(&str, f64)>,
) -> Result<Option<Vec<crate::data::Curve>>> {
    use crate::model::{with_laws, LawKind};
    let exts: Vec<String> = effect.iter().map(|(k, _)| k.to_string()).collect();
    let mut kinds = vec![
        LawKind::Arrhenius,
        LawKind::Constant,
        LawKind::Constant,
        LawKind::Constant,
        LawKind::Arrhenius,
        LawKind::Constant,
    ];
    kinds.extend(exts.iter().map(|_| LawKind::Constant));
    let model = with_laws(build("khd", &exts)?, &kinds, 575.0);
    let ode = OdeOptions {
        rtol: 1e-10,
        atol: 1e-13,
        ..OdeOptions::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = vec![
        1.2e-9 * (0.3 * normal(&mut rng)).exp(),
        0.12 * (1.0 + 0.05 * normal(&mut rng)),
        0.55 + 0.03 * normal(&mut rng),
        6e4 * (0.3 * normal(&mut rng)).exp(),
        1.5e-5 * (0.3 * normal(&mut rng)).exp(),
        5.0 * (1.0 + 0.1 * normal(&mut rng)),
    ];
    if let Some((_, v)) = effect {
        truth.push(v);
    }
    truth.push(350.0 + 50.0 * normal(&mut rng));
    truth.push(250.0 + 50.0 * normal(&mut rng));
    let sd = 5e-5 + 2.5e-4 * rng.gen::<f64>();
    let phi = if rng.gen::<bool>() {
        0.0
    } else {
        0.3 + 0.6 * rng.gen::<f64>()
    };
    let mut curves = Vec::new();
    for (t, s0) in [
        (560.0, 85.0),
        (560.0, 100.0),
        (560.0, 110.0),
        (590.0, 75.0),
        (590.0, 90.0),
        (590.0, 100.0),
    ] {
        let s: f64 = (s0 + 2.0 * (2.0 * rng.gen::<f64>() - 1.0)).round();
        let load = Load::new(s, t, 1.0 / 3.0);
        let r = model.simulate(&truth, &load, &[], &mut [], &ode);
        if !r.ruptured() {
            return Ok(None);
        }
        let m = 30;
        let mut times: Vec<f64> = (0..m)
            .map(|k| {
                let f = if k == 0 || k == m - 1 {
                    k as f64 / (m - 1) as f64
                } else {
                    (k as f64 + rng.gen_range(-0.35..0.35)) / (m - 1) as f64
                };
                r.t_end * (1.0 - (1.0 - f).powf(1.5))
            })
            .collect();
        times.sort_by(|a, b| a.total_cmp(b));
        let mut e = vec![0.0; m];
        model.simulate(&truth, &load, &times, &mut e, &ode);
        let mut prev = 0.0;
        for (k, v) in e.iter_mut().enumerate() {
            let innov = normal(&mut rng);
            let err = if k == 0 {
                sd * innov
            } else {
                phi * prev + sd * (1.0 - phi * phi).sqrt() * innov
            };
            prev = err;
            *v += err;
        }
        let t_r = r.t_end * (0.01 * normal(&mut rng)).exp();
        curves.push(crate::data::Curve {
            temperature_c: t,
            stress_mpa: s,
            specimen: None,
            groups: None,
            min_rate_estimated: crate::data::estimate_min_rate(&times, &e, t_r),
            rupture_strain: e[m - 1],
            times_h: times,
            strains: e,
            rupture_time_h: Some(t_r),
            min_rate_measured: None,
        });
    }
    Ok(Some(curves))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_are_reproducible_and_end_before_rupture() {
        for (i, sc) in SCENARIOS.iter().enumerate() {
            let a = generate("t", sc, 100 + i as u64).unwrap();
            let b = generate("t", sc, 100 + i as u64).unwrap();
            assert_eq!(a, b);
            let t = &a.truth;
            assert_eq!(t.effect.name(), *sc);
            for (k, times) in t.times_h.iter().enumerate() {
                let last = *times.last().unwrap();
                assert!(last <= t.true_rupture_h[k] * 1.0 + 1e-9);
                if t.strain_cut.is_none() {
                    assert!(last >= 0.95 * t.true_rupture_h[k] * 0.9999, "{sc}");
                }
                assert_eq!(times[0], 0.0);
            }
            assert!((3..=5).contains(&t.stresses.len()));
            assert!(t.noise_sd.iter().all(|s| (4e-5..=3.7e-4).contains(s)));
        }
    }

    /// World `shapes` is the specimens world of the same seed (tests, labels, rate and
    /// ductility factors, error growth) with a coarsening factor per specimen on Kc: the
    /// curves' lives change with it, and its configuration fits all three kinds.
    #[test]
    fn the_shapes_world_is_the_specimens_world_with_own_coarsening_rates() {
        for seed in [3101_u64, 3102, 3103] {
            let a = generate_in("t", "none", None, seed, World::Specimens).unwrap();
            let b = generate_in("t", "none", None, seed, World::Shapes).unwrap();
            let (sa, sb) = (
                a.truth.specimens.clone().unwrap(),
                b.truth.specimens.clone().unwrap(),
            );
            assert_eq!(a.truth.stresses, b.truth.stresses);
            assert_eq!(
                (&sa.labels, &sa.rate_effects, &sa.ductility_effects),
                (&sb.labels, &sb.rate_effects, &sb.ductility_effects)
            );
            assert_eq!(sa.error_growth, sb.error_growth);
            assert!(sa.coarsening_effects.is_empty() && sa.coarsening_sd == 0.0);
            assert_eq!(sb.coarsening_effects.len(), sb.labels.len());
            assert!((0.15..=0.5).contains(&sb.coarsening_sd));
            assert_eq!(sb.scatter_true().len(), 3);
            assert_eq!(sa.scatter_true().len(), 2);
            // Kc × e^κ: a faster coarsening shortens the life (KHD), a slower one lengthens it.
            for k in 0..sb.labels.len() {
                let ratio = b.truth.true_rupture_h[k] / a.truth.true_rupture_h[k];
                let kappa = sb.coarsening_effects[k];
                assert!(
                    (ratio - 1.0) * kappa < 0.0 || kappa.abs() < 1e-3,
                    "seed {seed} specimen {k}: κ {kappa}, life ratio {ratio}"
                );
            }
            assert!(b
                .config_toml
                .contains("specimen_effects = [\"rate\", \"ductility\", \"coarsening\"]"));
            assert!(!a.config_toml.contains("specimen_effects"));
        }
    }

    /// World `campaigns` is the specimens world of the same seed with each specimen's rate
    /// factor moved by its campaign's: campaigns alternate in stress order, both span two
    /// conditions (so `data::campaigns` names them), the lives shift with the campaign factor,
    /// and the rate's true scatter is a new specimen's from a new campaign.
    #[test]
    fn the_campaigns_world_is_the_specimens_world_with_a_factor_per_campaign() {
        for seed in [3101_u64, 3102, 3103, 3104] {
            let a = generate_in("t", "none", None, seed, World::Specimens).unwrap();
            let b = generate_in("t", "none", None, seed, World::Campaigns).unwrap();
            let (sa, sb) = (
                a.truth.specimens.clone().unwrap(),
                b.truth.specimens.clone().unwrap(),
            );
            assert_eq!(a.truth.stresses, b.truth.stresses);
            assert_eq!(sa.ductility_effects, sb.ductility_effects);
            assert!(sa.campaign_effects.is_empty() && sa.campaign_sd == 0.0);
            assert!((0.1..=0.4).contains(&sb.campaign_sd));
            let n = sb.labels.len();
            assert_eq!(sb.campaign_effects.len(), n);
            for k in 0..n {
                let (c, other) = if k % 2 == 0 { ("A", 1) } else { ("B", 0) };
                assert_eq!(sb.labels[k], format!("{c}-{}", k / 2 + 1));
                assert_eq!(sb.campaign_effects[k], sb.campaign_effects[k % 2]);
                assert_ne!(sb.campaign_effects[k], sb.campaign_effects[other]);
                let shift = sb.rate_effects[k] - sa.rate_effects[k];
                assert!((shift - sb.campaign_effects[k]).abs() < 1e-12);
                // A × e^η: a faster creep rate shortens the life.
                let ratio = b.truth.true_rupture_h[k] / a.truth.true_rupture_h[k];
                assert!((ratio - 1.0) * shift < 0.0, "seed {seed} specimen {k}");
            }
            let rate = sb.scatter_true()[0];
            assert!((rate - sb.rate_sd.hypot(sb.campaign_sd)).abs() < 1e-12);
            let dir = tempfile::tempdir().unwrap();
            write_set(&b, dir.path()).unwrap();
            let (_, data) =
                crate::config::load(&dir.path().join("config.toml"), &Default::default()).unwrap();
            let named = crate::data::campaigns(&data.curves).expect("the campaigns are named");
            assert!(named.iter().all(|c| *c == "A" || *c == "B"));
            assert_eq!(a.config_toml, b.config_toml);
        }
    }

    /// The battery's `--specimen-effects` in a set's configuration: added as a table, or
    /// replacing the line of world `shapes`; read back as those kinds.
    #[test]
    fn specimen_effects_are_set_in_a_generated_configuration() {
        use crate::likelihood::EffectKind::{Coarsening, Ductility, Rate};
        for world in [World::Specimens, World::Shapes] {
            let set = generate_in("t", "none", None, 3101, world).unwrap();
            for kinds in [vec![Rate], vec![Rate, Ductility, Coarsening], vec![]] {
                let text = with_specimen_effects(&set.config_toml, &kinds);
                let cfg = crate::config::RunConfig::from_str_with(
                    &text,
                    std::path::Path::new("t.toml"),
                    &Default::default(),
                )
                .unwrap();
                assert_eq!(
                    cfg.objective.specimen_effects,
                    crate::config::SpecimenEffects::Kinds(kinds.clone()),
                    "{world:?}: {text}"
                );
            }
        }
    }

    /// The battery's `--specimen-scatter` in a set's configuration: into the `[objective]`
    /// table where the set has one (after `--specimen-effects`), else as a table; read back
    /// as that estimate, with the kinds untouched.
    #[test]
    fn the_specimen_scatter_is_set_in_a_generated_configuration() {
        use crate::likelihood::{EffectKind::Rate, SpecimenScatter};
        let set = generate_in("t", "none", None, 3102, World::Specimens).unwrap();
        let with_kinds = with_specimen_effects(&set.config_toml, &[Rate]);
        for (text, kinds) in [
            (set.config_toml.clone(), None),
            (with_kinds, Some(vec![Rate])),
        ] {
            let text = with_specimen_scatter(&text, SpecimenScatter::BeyondStressTrend);
            let cfg = crate::config::RunConfig::from_str_with(
                &text,
                std::path::Path::new("t.toml"),
                &Default::default(),
            )
            .unwrap();
            assert_eq!(
                cfg.objective.specimen_scatter,
                SpecimenScatter::BeyondStressTrend,
                "{text}"
            );
            if let Some(k) = kinds {
                assert_eq!(
                    cfg.objective.specimen_effects,
                    crate::config::SpecimenEffects::Kinds(k),
                    "{text}"
                );
            }
            // The bootstrap's extension beside it, and alone.
            for t in [text.clone(), set.config_toml.clone()] {
                let t = with_bootstrap_extended(&t, 639);
                let cfg = crate::config::RunConfig::from_str_with(
                    &t,
                    std::path::Path::new("t.toml"),
                    &Default::default(),
                )
                .unwrap();
                assert_eq!(cfg.diagnose.most_replicates(), 639, "{t}");
                assert_eq!(cfg.diagnose.bootstrap_extended, Some(639));
                // `--diagnose-max-points` beside it (the same table), and alone.
                for t in [t.clone(), set.config_toml.clone()] {
                    let t = with_diagnose_max_points(&t, 600);
                    let cfg = crate::config::RunConfig::from_str_with(
                        &t,
                        std::path::Path::new("t.toml"),
                        &Default::default(),
                    )
                    .unwrap();
                    assert_eq!(cfg.diagnose.max_points, 600, "{t}");
                    let t = with_diagnose_reduction(&t, crate::data::Reduction::Means);
                    let cfg = crate::config::RunConfig::from_str_with(
                        &t,
                        std::path::Path::new("t.toml"),
                        &Default::default(),
                    )
                    .unwrap();
                    assert_eq!(cfg.diagnose.reduction, crate::data::Reduction::Means, "{t}");
                    assert_eq!(cfg.diagnose.max_points, 600, "{t}");
                }
            }
        }
        let cfg = crate::config::RunConfig::from_str_with(
            &set.config_toml,
            std::path::Path::new("t.toml"),
            &Default::default(),
        )
        .unwrap();
        assert_eq!(cfg.diagnose.most_replicates(), cfg.diagnose.bootstrap);
        assert_eq!(cfg.diagnose.max_points, 100);
    }

    /// The coarsening factors are drawn N(0, sd²): over many sets, the mean of (κ/sd)² is 1
    /// within its sampling error (χ² with n degrees of freedom: sd of the mean √(2/n)) and
    /// the mean of κ/sd is 0 (sd 1/√n).
    #[test]
    fn coarsening_factors_have_the_stated_scatter() {
        let (mut n, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for seed in 0..400_u64 {
            let stresses = [100.0, 110.0, 120.0, 130.0];
            let (_, sp) = draw_specimens(&stresses, 7_000 + seed, World::Shapes);
            for k in &sp.coarsening_effects {
                let z = k / sp.coarsening_sd;
                n += 1.0;
                s1 += z;
                s2 += z * z;
            }
        }
        let (m1, m2) = (s1 / n, s2 / n);
        assert!(m1.abs() < 4.0 / n.sqrt(), "mean {m1} over {n}");
        assert!(
            (m2 - 1.0).abs() < 4.0 * (2.0 / n).sqrt(),
            "mean square {m2} over {n}"
        );
    }
}
