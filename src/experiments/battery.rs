//! `creepfit battery`: measure `diagnose` on many generated data sets ([`crate::synth`]) —
//! its false-alarm rate on data without an effect, how often it names a catalogued effect,
//! how often an effect outside the catalogue gets an `extension` verdict, and its power
//! against effect size.
//!
//! **Detectable** is defined by an oracle that knows the truth: the base model is fitted to the
//! noise-free true observations (strain at the sampled times, the true rupture times) under
//! the TRUE error model (in the specimen worlds with the reading error's growth with strain,
//! [`true_reading_scale`]); the smallest sum of squared whitened residuals, λ, is the
//! noncentrality of a likelihood-ratio test that knows the error model. A set is detectable
//! when λ ≥ [`DETECTABLE_LAMBDA`] = 25: the base model misses the truth by five standard errors.
//! In the specimen world that oracle knows each specimen's factor, which no test does: there a
//! catalogued effect's set is detectable by [`oracle_lambda_scatter`] instead, the same
//! noncentrality with the factors unknown (penalised by the true scatter) and the generating
//! extension fitted beside the base ([`SetResult::power_lambda`]).
//!
//! Sets are diagnosed in parallel; each finished set is appended (flushed) to
//! `results.jsonl`, so an interrupted battery resumes where it stopped.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::config::RunConfig;
use crate::data::Curve;
use crate::diagnose::{diagnose, Verdict};
use crate::errmodel::{Ar1, ErrorModel};
use crate::error::{Error, Result};
use crate::fit::FitSettings;
use crate::likelihood::EffectKind;
use crate::likelihood::{min_penalised_ss, min_whitened_ss};
use crate::model::build;
use crate::synth::{generate_in, scenario_of, write_set, SpecimenTruth, Truth, World};

/// Oracle noncentrality at or above which an effect counts as detectable.
pub const DETECTABLE_LAMBDA: f64 = 25.0;

/// One diagnosed set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetResult {
    /// Set name (`set-<seed>`).
    pub name: String,
    /// Generator seed.
    pub seed: u64,
    /// Hidden effect (`none`, an extension name, or an effect outside the catalogue).
    pub scenario: String,
    /// Material family.
    pub family: String,
    /// Effect size (see [`crate::synth::Effect::size`]).
    #[serde(deserialize_with = "de_f64")]
    pub size: f64,
    /// Sampling (`digitised` or `logged`).
    pub sampling: String,
    /// AR(1) correlation of the reading error.
    #[serde(deserialize_with = "de_f64")]
    pub noise_phi: f64,
    /// Number of curves.
    pub curves: usize,
    /// Oracle noncentrality λ (0 for no effect by construction: NaN if the oracle failed).
    #[serde(deserialize_with = "de_f64")]
    pub lambda: f64,
    /// Oracle λ with the specimens' factors unknown ([`oracle_lambda_scatter`]; specimen
    /// world and catalogued effects only, NaN otherwise).
    #[serde(default = "nan", deserialize_with = "de_f64")]
    pub lambda_scatter: f64,
    /// The set's λ ≥ [`DETECTABLE_LAMBDA`]: `lambda_scatter` where there is one, else `lambda`.
    pub detectable: bool,
    /// Verdict, cause, and for `unexplained` the closest extension.
    pub verdict: Option<Verdict>,
    pub cause: Option<String>,
    pub closest: Option<String>,
    /// Bootstrap p-values per extension, and of the base goodness of fit.
    #[serde(deserialize_with = "de_named_f64")]
    pub p_values: Vec<(String, f64)>,
    #[serde(deserialize_with = "de_vec_f64")]
    pub gof_p: Vec<f64>,
    /// Bootstrap replicates drawn.
    pub replicates: usize,
    /// Wall time of `diagnose`, s.
    #[serde(deserialize_with = "de_f64")]
    pub wall_s: f64,
    /// The world the set comes from.
    #[serde(default)]
    pub world: World,
    /// True scatter of the specimens' ln creep-rate and ln ductility factors (worlds with
    /// specimens), and of their ln coarsening factors (world `shapes`).
    #[serde(default)]
    pub scatter_true: Vec<f64>,
    /// The base model's estimated scatter per kind (rate, ductility, and coarsening where the
    /// fit carries it; 0 where the fit carries none) and its 95 % interval.
    #[serde(default, deserialize_with = "de_vec_f64")]
    pub scatter_est: Vec<f64>,
    #[serde(default, deserialize_with = "de_vec_f64")]
    pub scatter_lo95: Vec<f64>,
    #[serde(default, deserialize_with = "de_vec_f64")]
    pub scatter_hi95: Vec<f64>,
    /// Where the specimens name campaigns: the base fit's sd of the ln rate factor of a new
    /// specimen from a new campaign, and its 95 % interval
    /// ([`crate::likelihood::GroupLevels::new_group_sd`]); empty where there is none.
    #[serde(default, deserialize_with = "de_vec_f64")]
    pub new_campaign_rate: Vec<f64>,
    /// Why the set could not be generated or diagnosed, if so.
    pub error: Option<String>,
}

/// Numbers JSON wrote as `null` (NaN: a p-value not computed, an interval not known) read
/// back as NaN.
fn de_vec_f64<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Vec<f64>, D::Error> {
    let v = Vec::<Option<f64>>::deserialize(d)?;
    Ok(v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

use crate::journal::de_nan_f64 as de_f64;

fn nan() -> f64 {
    f64::NAN
}

/// [`de_vec_f64`] for named numbers.
fn de_named_f64<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Vec<(String, f64)>, D::Error> {
    let v = Vec::<(String, Option<f64>)>::deserialize(d)?;
    Ok(v.into_iter()
        .map(|(n, x)| (n, x.unwrap_or(f64::NAN)))
        .collect())
}

impl SetResult {
    /// The outcome as one label: `adequate`, `unexplained`, `extension:<name>`, or `error`.
    pub fn outcome(&self) -> String {
        match (self.verdict, &self.cause) {
            (Some(Verdict::Extension), Some(c)) => format!("extension:{c}"),
            (Some(v), _) => v.as_str().to_string(),
            (None, _) => "error".into(),
        }
    }
    /// The λ that says whether the set is detectable and bins it in the power table:
    /// [`SetResult::lambda_scatter`] where the set has one (specimens, a catalogued effect),
    /// else [`SetResult::lambda`].
    pub fn power_lambda(&self) -> f64 {
        if self.world.has_specimens()
            && crate::model::ext::CATALOGUE.contains(&self.scenario.as_str())
        {
            self.lambda_scatter
        } else {
            self.lambda
        }
    }
    /// A catalogued effect named as the cause.
    pub fn named_correctly(&self) -> bool {
        self.cause.as_deref() == Some(self.scenario.as_str())
    }
}

/// The noise-free true observations of a generated set (strain at the sampled times, the
/// true rupture times) as curves without specimen labels.
pub fn true_curves(truth: &Truth) -> Vec<Curve> {
    truth
        .stresses
        .iter()
        .enumerate()
        .map(|(i, &s)| Curve {
            temperature_c: truth.temperature_c,
            stress_mpa: s,
            specimen: None,
            times_h: truth.times_h[i].clone(),
            strains: truth.true_strain[i].clone(),
            rupture_time_h: Some(truth.true_rupture_h[i]),
            rupture_strain: *truth.true_strain[i].last().unwrap_or(&1.0),
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: crate::data::estimate_min_rate(
                &truth.times_h[i],
                &truth.true_strain[i],
                truth.true_rupture_h[i],
            ),
        })
        .collect()
}

/// The set's true error model (AR(1) per curve and the rupture-time scatter; the growth of
/// the specimen world's reading error with strain is [`true_reading_scale`]).
pub fn true_noise(truth: &Truth) -> ErrorModel {
    ErrorModel {
        strain: truth
            .noise_sd
            .iter()
            .map(|&sd| Ar1::with_marginal(sd, truth.noise_phi))
            .collect(),
        lifetime_sd: truth.lifetime_sd,
    }
}

/// The factor on each true reading's error where the set's reading error grows with strain
/// (the specimen worlds: 1 + g ε/ε_f, as `synth` drew it, ε the true strain of the reading):
/// per curve, one per reading of [`true_curves`]; `None` where it does not grow. An oracle
/// without it takes every reading to be as precise as the first, and overstates what the
/// late readings — a tertiary stage, where most catalogued effects act — tell.
pub fn true_reading_scale(truth: &Truth) -> Option<Vec<Vec<f64>>> {
    let sp = truth
        .specimens
        .as_ref()
        .filter(|sp| sp.error_growth > 0.0)?;
    Some(
        truth
            .true_strain
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let top = e.iter().copied().fold(0.0_f64, f64::max);
                let eps_f = sp.growth_strain(i, top);
                e.iter().map(|&e| sp.reading_factor(e, eps_f)).collect()
            })
            .collect(),
    )
}

/// The oracle's starts in `space`: `truth_start`, the initial guess on `curves`, and 8
/// Latin-hypercube points of the set's seed.
pub fn oracle_starts(
    model: &dyn crate::model::Model,
    space: &crate::model::objective::ParamSpace,
    curves: &[Curve],
    settings: &FitSettings,
    truth_start: Vec<f64>,
    seed: u64,
) -> Vec<Vec<f64>> {
    let guess =
        crate::model::guess::initial_guess(model, curves, space, settings.omega_f, &settings.ode);
    let mut starts = vec![truth_start, guess.params];
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seed);
    for u in crate::sampling::latin_hypercube(8, space.len(), &mut rng) {
        let mut x = vec![0.0; space.len()];
        space.from_unit(&u, &mut x);
        starts.push(x);
    }
    starts
}

/// Oracle λ of a generated set (see the module docs): the base model at each specimen's
/// own (known) factors.
pub fn oracle_lambda(cfg: &RunConfig, truth: &Truth) -> f64 {
    let settings = FitSettings::from_config(cfg);
    let Ok(model) = build(&cfg.model, &[]) else {
        return f64::NAN;
    };
    let curves = true_curves(truth);
    let noise = true_noise(truth);
    let scale = true_reading_scale(truth);
    let space = cfg.space();
    let starts = oracle_starts(
        model.as_ref(),
        &space,
        &curves,
        &settings,
        truth.constants.clone(),
        truth.seed,
    );
    // Known specimen effects: the base model at each specimen's own constants.
    let factors = truth.specimens.as_ref().map(|sp| {
        let role = |r: crate::model::Role| {
            model
                .constants()
                .iter()
                .position(|c| c.role == r)
                .expect("the base model has its rate and ductility constants")
        };
        let mut index = vec![
            role(crate::model::Role::Rate),
            role(crate::model::Role::InverseDuctility),
        ];
        if !sp.coarsening_effects.is_empty() {
            index.push(role(crate::model::Role::Softening));
        }
        crate::model::objective::CurveFactors {
            index,
            factors: (0..sp.rate_effects.len())
                .map(|i| {
                    let mut f = vec![sp.rate_effects[i].exp(), (-sp.ductility_effects[i]).exp()];
                    if let Some(k) = sp.coarsening_effects.get(i) {
                        f.push(k.exp());
                    }
                    f
                })
                .collect(),
        }
    });
    min_whitened_ss(
        model.as_ref(),
        &curves,
        &space,
        &starts,
        &settings,
        &noise,
        scale.as_deref(),
        factors.as_ref(),
    )
    .map_or(f64::NAN, |b| b.0)
}

/// Oracle λ of a set from the specimen world with the specimens' factors **unknown**, as they
/// are to `diagnose` and in every laboratory: the "expected data" noncentrality of the
/// likelihood-ratio test between the hierarchical base model and the hierarchical true model,
/// both at the true error model (its growth with strain included) and the true scatter —
///
///   λ_s = min over (θ, η) of the base's [Σ r²/σ² + Σ η²/τ²] − the same minimum of the
///   catalogued extension that generated the set (its own constants free),
///
/// on the noise-free true observations. [`oracle_lambda`] gives the base model each
/// specimen's true factor, so an effect that specimen factors can absorb (a constant load
/// that a faster specimen mimics) counts there as detectable although no test that must
/// estimate the factors can see it. `None` for the identical world (then λ_s = λ), for no
/// effect (0 by construction) and for effects outside the catalogue (no alternative to fit);
/// NaN where an oracle fit failed.
pub fn oracle_lambda_scatter(cfg: &RunConfig, truth: &Truth) -> Option<f64> {
    let sp = truth.specimens.as_ref()?;
    let (exts, extra) = truth.effect.true_extension();
    if exts.is_empty() {
        return None;
    }
    let Ok(setup) = cfg.diagnose_setup() else {
        return Some(f64::NAN);
    };
    let Some(alt) = setup.variants.iter().find(|v| v.name == exts[0]) else {
        return Some(f64::NAN);
    };
    let base = &setup.variants[0];
    let settings = &setup.settings;
    let curves = true_curves(truth);
    let noise = true_noise(truth);
    let scale = true_reading_scale(truth);
    // The kinds the truth carries (a scatter of zero is no kind: every factor is 1).
    let mut kinds = vec![];
    let mut eta0 = vec![];
    for (kind, sd, effects) in [
        (EffectKind::Rate, sp.rate_sd, &sp.rate_effects),
        (
            EffectKind::Ductility,
            sp.ductility_sd,
            &sp.ductility_effects,
        ),
        (
            EffectKind::Coarsening,
            sp.coarsening_sd,
            &sp.coarsening_effects,
        ),
    ] {
        if sd > 0.0 {
            kinds.push((kind, sd));
            eta0.extend_from_slice(effects);
        }
    }
    let mut alt_truth = truth.constants.clone();
    alt_truth.extend_from_slice(&extra);
    let min = |v: &crate::config::ModelVariant, start: Vec<f64>| {
        let starts = oracle_starts(
            v.model.as_ref(),
            &v.space,
            &curves,
            settings,
            start,
            truth.seed,
        );
        min_penalised_ss(
            v.model.as_ref(),
            &curves,
            &v.space,
            &starts,
            settings,
            &noise,
            scale.as_deref(),
            &kinds,
            &eta0,
        )
        .map(|b| b.0)
    };
    Some(
        match (min(base, truth.constants.clone()), min(alt, alt_truth)) {
            (Some(b), Some(a)) => b - a,
            _ => f64::NAN,
        },
    )
}

/// Generate set `seed` (the `index`-th of its battery, scenario [`scenario_of`]`(index)`) into
/// `dir/sets/set-<seed>/`, diagnose it, and compute its oracle λ.
pub fn run_one(dir: &Path, index: usize, seed: u64, world: World) -> SetResult {
    run_one_diagnosed(dir, scenario_of(index), seed, world).0
}

/// [`run_one`] of a given scenario (one of [`crate::synth::SCENARIOS`]), with the diagnosis
/// itself (`None` where the set could not be generated or diagnosed: the result's `error`
/// says why).
pub fn run_one_diagnosed(
    dir: &Path,
    scenario: &str,
    seed: u64,
    world: World,
) -> (SetResult, Option<crate::diagnose::Diagnosis>) {
    run_one_diagnosed_with(dir, scenario, seed, world, &SetOverrides::default())
}

/// What a battery writes into every set's configuration: the configuration whose calibration
/// it measures (by default the world's own).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SetOverrides {
    /// `[objective] specimen_effects` (else the world's: `auto` in `specimens`).
    pub effects: Option<Vec<EffectKind>>,
    /// `[objective] specimen_scatter` (written into every set's configuration).
    pub scatter: crate::likelihood::SpecimenScatter,
    /// `[diagnose] bootstrap_extended` (written only when given).
    pub bootstrap_extended: Option<usize>,
    /// `[diagnose] max_points` (written only when given).
    pub max_points: Option<usize>,
    /// `[diagnose] reduction` (written only when given).
    pub reduction: Option<crate::data::Reduction>,
    /// `[diagnose] misfit_share` (written only when given).
    pub misfit_share: Option<crate::data::MisfitShare>,
}

/// [`run_one_diagnosed`] with the set's configuration overridden as `overrides` says.
pub fn run_one_diagnosed_with(
    dir: &Path,
    scenario: &str,
    seed: u64,
    world: World,
    overrides: &SetOverrides,
) -> (SetResult, Option<crate::diagnose::Diagnosis>) {
    let mut diagnosis = None;
    let name = format!("set-{seed}");
    let mut r = SetResult {
        name: name.clone(),
        seed,
        scenario: scenario.to_string(),
        family: String::new(),
        size: f64::NAN,
        sampling: String::new(),
        noise_phi: f64::NAN,
        curves: 0,
        lambda: f64::NAN,
        lambda_scatter: f64::NAN,
        detectable: false,
        verdict: None,
        cause: None,
        closest: None,
        p_values: vec![],
        gof_p: vec![],
        replicates: 0,
        wall_s: f64::NAN,
        world,
        scatter_true: vec![],
        scatter_est: vec![],
        scatter_lo95: vec![],
        scatter_hi95: vec![],
        new_campaign_rate: vec![],
        error: None,
    };
    let folder = dir.join("sets").join(&name);
    let res = (|| -> Result<()> {
        let mut set = generate_in(&name, scenario, None, seed, world)?;
        if let Some(k) = &overrides.effects {
            set.config_toml = crate::synth::with_specimen_effects(&set.config_toml, k);
        }
        // Always written: the set's configuration reads the same under any later default.
        set.config_toml = crate::synth::with_specimen_scatter(&set.config_toml, overrides.scatter);
        if let Some(most) = overrides.bootstrap_extended {
            set.config_toml = crate::synth::with_bootstrap_extended(&set.config_toml, most);
        }
        if let Some(n) = overrides.max_points {
            set.config_toml = crate::synth::with_diagnose_max_points(&set.config_toml, n);
        }
        if let Some(how) = overrides.reduction {
            set.config_toml = crate::synth::with_diagnose_reduction(&set.config_toml, how);
        }
        if let Some(how) = overrides.misfit_share {
            set.config_toml = crate::synth::with_diagnose_misfit_share(&set.config_toml, how);
        }
        write_set(&set, &folder)?;
        let t = &set.truth;
        r.family = t.family.clone();
        r.size = t.effect.size();
        r.sampling = serde_json::to_value(t.sampling)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        r.noise_phi = t.noise_phi;
        r.curves = t.stresses.len();
        let cfg = RunConfig::load(&folder.join("config.toml"))?;
        let data = cfg.load_data()?;
        r.lambda = oracle_lambda(&cfg, t);
        r.lambda_scatter = oracle_lambda_scatter(&cfg, t).unwrap_or(f64::NAN);
        r.detectable = r.power_lambda() >= DETECTABLE_LAMBDA;
        let d = diagnose(&cfg.diagnose_setup()?, &data, &cfg.diagnose)?;
        r.verdict = Some(d.verdict);
        r.cause = d.cause.clone();
        r.closest = d.closest.clone();
        r.p_values = d
            .candidates
            .iter()
            .map(|c| (c.name.clone(), c.p_value.unwrap_or(f64::NAN)))
            .collect();
        r.gof_p = d.gof.iter().map(|g| g.p_value).collect();
        r.replicates = d.bootstrap.replicates;
        r.wall_s = d.wall_s;
        // The whole diagnosis beside the set (its null statistics too): why a set was missed
        // or raised an alarm can be read afterwards, and a multiplicity procedure checked on
        // the tests' joint null distributions without diagnosing again.
        crate::output::write_atomic(&folder.join("diagnosis.json"), |w| {
            serde_json::to_writer(&mut *w, &d).map_err(std::io::Error::from)
        })?;
        diagnosis = Some(d.clone());
        (r.scatter_est, r.scatter_lo95, r.scatter_hi95) = scatter_by_kind(d.base.specimen.as_ref());
        r.new_campaign_rate = d
            .base
            .specimen_campaign_levels
            .iter()
            .find(|c| c.kind == EffectKind::Rate)
            .and_then(|c| c.new_group_sd)
            .map_or_else(Vec::new, |(e, lo, hi)| vec![e, lo, hi]);
        if let Some(sp) = &t.specimens {
            r.scatter_true = true_by_kind(sp, r.scatter_est.len());
        }
        Ok(())
    })();
    if let Err(e) = res {
        r.error = Some(e.to_string());
    }
    (r, diagnosis)
}

/// Results already in `dir/results.jsonl` (an interrupted battery), by seed.
pub fn read_results(dir: &Path) -> Result<BTreeMap<u64, SetResult>> {
    crate::journal::read_lines_by(
        &dir.join("results.jsonl"),
        "a battery result",
        |r: &SetResult| r.seed,
    )
}

/// Run sets `first_seed .. first_seed + n` (set i gets scenario `scenario`, or by default
/// [`scenario_of`]`(i)`: a battery of one scenario, e.g. `none` for the false-alarm rate
/// alone) into `dir`, skipping those already in `results.jsonl`; returns all results, in seed
/// order. With `progress`, a line per finished set on stderr (and a bar on a terminal).
pub fn run_battery(
    dir: &Path,
    first_seed: u64,
    n: usize,
    world: World,
    scenario: Option<&str>,
    progress: bool,
) -> Result<Vec<SetResult>> {
    // Quiet bars draw and print nothing.
    run_battery_observed(
        dir,
        first_seed,
        n,
        world,
        scenario,
        &SetOverrides::default(),
        &crate::progress::Bars::new(!progress),
    )
}

/// [`run_battery`] telling `observer` of every finished set (a step, and a line with its
/// outcome) instead of printing. When the observer asks to stop, no new set starts, the
/// running ones finish and are recorded, and the battery ends with [`Error::Interrupted`]:
/// a rerun into the same folder resumes from `results.jsonl`.
pub fn run_battery_observed(
    dir: &Path,
    first_seed: u64,
    n: usize,
    world: World,
    scenario: Option<&str>,
    overrides: &SetOverrides,
    observer: &dyn crate::progress::Observer,
) -> Result<Vec<SetResult>> {
    if let Some(sc) = scenario {
        crate::synth::check_scenario(sc)?;
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let done = read_results(dir)?;
    let path: PathBuf = dir.join("results.jsonl");
    let file = crate::journal::append_lines(&path)?;
    let todo: Vec<(usize, u64)> = (0..n)
        .map(|i| (i, first_seed + i as u64))
        .filter(|(_, s)| !done.contains_key(s))
        .collect();
    let counter = std::sync::atomic::AtomicUsize::new(0);
    let total = todo.len();
    observer.phase("sets", Some(n as u64));
    observer.resumed((n - total) as u64);
    let fresh: Vec<Option<SetResult>> = todo
        .par_iter()
        .map(|&(i, seed)| {
            if observer.cancelled() {
                return Ok(None);
            }
            let sc = scenario.unwrap_or_else(|| scenario_of(i));
            let r = run_one_diagnosed_with(dir, sc, seed, world, overrides).0;
            let line = serde_json::to_string(&r).expect("plain values") + "\n";
            {
                let mut f = file.lock().expect("results lock");
                f.write_all(line.as_bytes())
                    .and_then(|_| f.flush())
                    .map_err(|e| Error::io(&path, e))?;
            }
            let k = counter.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
            observer.advance(1);
            observer.note(&format!(
                "[{k}/{total}] {} {}: {} (λ = {:.1}{}, {:.1} s)",
                r.name,
                r.scenario,
                r.error.clone().unwrap_or_else(|| r.outcome()),
                r.lambda,
                if r.lambda_scatter.is_nan() {
                    String::new()
                } else {
                    format!(
                        ", with the specimens' factors unknown {:.1}",
                        r.lambda_scatter
                    )
                },
                r.wall_s
            ));
            Ok(Some(r))
        })
        .collect::<Result<_>>()?;
    if observer.cancelled() {
        return Err(Error::Interrupted(format!(
            "stopped during the battery; the finished sets are in {}: rerun the same battery into the same folder to resume",
            path.display()
        )));
    }
    let mut all = done;
    for r in fresh.into_iter().flatten() {
        all.insert(r.seed, r);
    }
    Ok(all
        .into_values()
        .filter(|r| r.seed >= first_seed && r.seed < first_seed + n as u64)
        .collect())
}

/// Wilson 95 % interval of k successes in n.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let (k, n) = (k as f64, n as f64);
    let z = 1.959_964;
    let p = k / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    (c - h, c + h)
}

/// The headline rates of a battery.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rates {
    /// No-effect sets: count, false alarms (any verdict but `adequate`), rate, Monte Carlo
    /// standard error and Wilson 95 % interval.
    pub null_sets: usize,
    pub false_alarms: usize,
    pub false_alarm_rate: f64,
    pub false_alarm_se: f64,
    pub false_alarm_ci95: (f64, f64),
    /// Per catalogued effect: (name, sets, detectable, named correctly among detectable).
    pub named: Vec<(String, usize, usize, usize)>,
    /// Outside the catalogue: sets, and how many got an `extension` verdict.
    pub outside_sets: usize,
    pub outside_extension: usize,
    /// Sets that failed to generate or diagnose.
    pub errors: usize,
    /// Specimens-world sets, per kind of specimen scatter (`rate`, `ductility`): see
    /// [`ScatterCoverage`].
    pub scatter: Vec<ScatterCoverage>,
    /// Sets whose specimens name campaigns: how the interval of a new campaign's specimen's
    /// rate sd ([`SetResult::new_campaign_rate`]) did against the true rate scatter (of a
    /// new specimen from a new campaign); kind `rate_new_campaign`, no sets where none had it.
    pub new_campaign: ScatterCoverage,
}

/// How the base fit's 95 % interval of one kind of specimen scatter did against the truth
/// over a battery's diagnosed sets.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ScatterCoverage {
    /// `rate` or `ductility`.
    pub kind: String,
    /// Sets whose specimens carry this scatter (true sd > 0).
    pub true_sets: usize,
    /// Of those, sets whose interval contains the true sd. A kind the fit dropped at zero
    /// scatter has no interval and counts as not covered.
    pub covered: usize,
    /// Sets whose specimens do not carry it (true sd 0) but whose interval excludes zero: a
    /// scatter found that is not there.
    pub spurious: usize,
    /// Sets whose specimens do not carry it.
    pub absent_sets: usize,
}

/// The true scatter per kind of a set's specimens, as long as the `fitted` kinds' estimates
/// at least: a kind fitted that the world does not draw has true scatter 0, so its coverage
/// row counts it absent (a scatter found there is spurious), in a battery and in
/// [`scatter_fit`] alike.
fn true_by_kind(sp: &SpecimenTruth, fitted: usize) -> Vec<f64> {
    let mut v = sp.scatter_true();
    v.resize(fitted.max(v.len()), 0.0);
    v
}

/// [`ScatterCoverage`] per kind over the diagnosed specimens-world sets of `ok`.
fn scatter_coverage(ok: &[&SetResult]) -> Vec<ScatterCoverage> {
    coverage_of(ok.iter().map(|r| {
        (
            &r.scatter_true[..],
            &r.scatter_lo95[..],
            &r.scatter_hi95[..],
        )
    }))
}

/// [`ScatterCoverage`] per kind (rate, ductility) over sets given as (true sd, lower and upper
/// end of the 95 % interval) per kind; a set without an entry for a kind is not counted for
/// it.
pub fn coverage_of<'a>(
    sets: impl Iterator<Item = (&'a [f64], &'a [f64], &'a [f64])> + Clone,
) -> Vec<ScatterCoverage> {
    ["rate", "ductility", "coarsening"]
        .iter()
        .enumerate()
        .filter(|(k, _)| *k < 2 || sets.clone().any(|(tr, _, _)| tr.len() > *k))
        .map(|(k, kind)| {
            let mut c = ScatterCoverage {
                kind: kind.to_string(),
                true_sets: 0,
                covered: 0,
                spurious: 0,
                absent_sets: 0,
            };
            for (tr, los, his) in sets.clone() {
                let (Some(&t), Some(&lo), Some(&hi)) = (tr.get(k), los.get(k), his.get(k)) else {
                    continue;
                };
                if t > 0.0 {
                    c.true_sets += 1;
                    c.covered += usize::from(lo <= t && t <= hi);
                } else {
                    c.absent_sets += 1;
                    c.spurious += usize::from(lo > 0.0);
                }
            }
            c
        })
        .collect()
}

/// The base model's scatter on one generated set of the specimens world by one hierarchical
/// maximum-likelihood fit (both kinds of specimen effects, as `fit` and `diagnose` carry them
/// on data with replicates; curves reduced to `[diagnose] max_points`) from one start,
/// without the multistart of `diagnose`: what [`scatter_fit`] gives.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScatterFit {
    /// The set's seed.
    pub seed: u64,
    /// True sd of the ln rate and ln ductility factors, and of the ln coarsening factors in
    /// world `shapes` (0: none).
    #[serde(deserialize_with = "de_vec_f64")]
    pub scatter_true: Vec<f64>,
    /// Estimated sd per kind (rate, ductility, coarsening where fitted; 0 where the fit
    /// dropped the kind).
    #[serde(deserialize_with = "de_vec_f64")]
    pub scatter_est: Vec<f64>,
    /// Lower end of the 95 % REML profile interval per kind (NaN: kind dropped; `null` in
    /// JSON, read back as NaN).
    #[serde(deserialize_with = "de_vec_f64")]
    pub scatter_lo95: Vec<f64>,
    /// Upper end of the 95 % interval per kind (NaN: kind dropped).
    #[serde(deserialize_with = "de_vec_f64")]
    pub scatter_hi95: Vec<f64>,
    /// −2 ln L of the fit (NaN: it failed).
    #[serde(deserialize_with = "de_f64")]
    pub neg2ll: f64,
    /// Outer iterations of the fit.
    pub iterations: usize,
    /// The fitted reading error's AR(1) correlation φ per curve (data order): with the
    /// generator's one φ per set, it shows how well short curves estimate it. Empty in
    /// records written before it was kept.
    #[serde(default, deserialize_with = "de_vec_f64")]
    pub phi_est: Vec<f64>,
    /// Which criterion gave the scatter (`None`: no specimen effects kept, or a record
    /// written before it was kept).
    #[serde(default)]
    pub scatter_method: Option<crate::specimen::ScatterMethod>,
}

/// Where [`scatter_fit`] starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScatterStart {
    /// The data's initial guess (the family's procedure): the path of a user's fit.
    Guess,
    /// The true constants: the interval's calibration without search failure.
    Truth,
}

/// Generate set `seed` of `world` (a world with specimens; `scenario`) into
/// `dir/sets/set-<seed>/`, fit the base model with the specimen effects its configuration
/// names (`specimens`: rate and ductility; `shapes`: and coarsening), or `kinds` when given,
/// from `start`, and compute the REML
/// profile intervals of the scatter ([`crate::likelihood::scatter_intervals`]): the
/// interval's coverage over many sets is [`coverage_of`] of the results. Far cheaper than a
/// battery (about 0.2 s a set against a diagnosis's minute), so the coverage can be
/// measured on hundreds of sets.
pub fn scatter_fit(
    dir: &Path,
    seed: u64,
    scenario: &str,
    start: ScatterStart,
    world: World,
    kinds: Option<crate::likelihood::SpecimenOptions>,
) -> Result<ScatterFit> {
    use crate::likelihood::{ml_fit, scatter_intervals, MlOptions};
    let name = format!("set-{seed}");
    let set = generate_in(&name, scenario, None, seed, world)?;
    let folder = dir.join("sets").join(&name);
    write_set(&set, &folder)?;
    let sp = set.truth.specimens.as_ref().ok_or_else(|| {
        Error::Invalid(format!(
            "{name}: a specimens-world set without its specimens' truth"
        ))
    })?;
    let cfg = RunConfig::load(&folder.join("config.toml"))?;
    let data = cfg.load_data()?;
    let curves: Vec<Curve> = data
        .curves
        .iter()
        .map(|c| crate::data::reduce(c, cfg.diagnose.max_points, cfg.diagnose.reduction))
        .collect();
    let model = cfg.build_model()?;
    let space = cfg.space();
    let settings = FitSettings::from_config(&cfg);
    let opts = MlOptions {
        specimen: kinds.unwrap_or_else(|| cfg.objective.specimen_options(&curves).0),
        ..MlOptions::default()
    };
    let x0 = match start {
        ScatterStart::Guess => {
            crate::model::guess::initial_guess(
                model.as_ref(),
                &curves,
                &space,
                settings.omega_f,
                &settings.ode,
            )
            .params
        }
        ScatterStart::Truth => set.truth.constants.clone(),
    };
    let mut fit = ml_fit(model.as_ref(), &curves, &space, &x0, &settings, &opts);
    scatter_intervals(&mut fit, model.as_ref(), &curves, &space, &settings, &opts);
    let (scatter_est, scatter_lo95, scatter_hi95) = scatter_by_kind(fit.specimen.as_ref());
    let scatter_true = true_by_kind(sp, scatter_est.len());
    Ok(ScatterFit {
        seed,
        scatter_true,
        scatter_est,
        scatter_lo95,
        scatter_hi95,
        neg2ll: fit.neg2ll,
        iterations: fit.iterations,
        phi_est: fit.noise.strain.iter().map(|a| a.phi).collect(),
        scatter_method: fit.specimen.as_ref().map(|f| f.scatter_method),
    })
}

/// A fit's scatter estimate and 95 % interval per kind (rate, ductility, and coarsening where
/// the fit carries it): 0 where the fit does not carry the kind, and NaN ends (the interval
/// of a kind the fit dropped is not known).
fn scatter_by_kind(sp: Option<&crate::likelihood::SpecimenFit>) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (mut est, mut lo, mut hi) = (vec![], vec![], vec![]);
    let third = sp.is_some_and(|f| {
        f.kinds.contains(&EffectKind::Coarsening) || f.dropped.contains(&EffectKind::Coarsening)
    });
    let kinds: &[EffectKind] = if third {
        &[
            EffectKind::Rate,
            EffectKind::Ductility,
            EffectKind::Coarsening,
        ]
    } else {
        &[EffectKind::Rate, EffectKind::Ductility]
    };
    for &kind in kinds {
        let got = sp.and_then(|f| {
            f.kinds
                .iter()
                .position(|k| *k == kind)
                .map(|j| (f.scatter[j], f.scatter_lo95[j], f.scatter_hi95[j]))
        });
        let (e, l, h) = got.unwrap_or((0.0, f64::NAN, f64::NAN));
        est.push(e);
        lo.push(l);
        hi.push(h);
    }
    (est, lo, hi)
}

/// Compute the [`Rates`] of a set of results.
pub fn rates(results: &[SetResult]) -> Rates {
    let ok: Vec<&SetResult> = results.iter().filter(|r| r.error.is_none()).collect();
    let null: Vec<&&SetResult> = ok.iter().filter(|r| r.scenario == "none").collect();
    let fa = null
        .iter()
        .filter(|r| r.verdict != Some(Verdict::Adequate))
        .count();
    let n0 = null.len();
    let rate = if n0 > 0 {
        fa as f64 / n0 as f64
    } else {
        f64::NAN
    };
    let named = crate::model::ext::CATALOGUE
        .iter()
        .map(|e| {
            let sets: Vec<&&SetResult> = ok.iter().filter(|r| r.scenario == *e).collect();
            let det: Vec<&&&SetResult> = sets.iter().filter(|r| r.detectable).collect();
            let good = det.iter().filter(|r| r.named_correctly()).count();
            (e.to_string(), sets.len(), det.len(), good)
        })
        .collect();
    let outside: Vec<&&SetResult> = ok
        .iter()
        .filter(|r| {
            r.scenario != "none" && !crate::model::ext::CATALOGUE.contains(&r.scenario.as_str())
        })
        .collect();
    Rates {
        null_sets: n0,
        false_alarms: fa,
        false_alarm_rate: rate,
        false_alarm_se: if n0 > 0 {
            (rate * (1.0 - rate) / n0 as f64).sqrt()
        } else {
            f64::NAN
        },
        false_alarm_ci95: wilson(fa, n0),
        named,
        outside_sets: outside.len(),
        outside_extension: outside
            .iter()
            .filter(|r| r.verdict == Some(Verdict::Extension))
            .count(),
        errors: results.len() - ok.len(),
        scatter: scatter_coverage(&ok),
        new_campaign: new_campaign_coverage(&ok),
    }
}

/// [`Rates::new_campaign`]: the sets with a new campaign's rate sd, against the true rate
/// scatter (world `campaigns`: √(specimen sd² + campaign sd²)).
fn new_campaign_coverage(ok: &[&SetResult]) -> ScatterCoverage {
    let with: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = ok
        .iter()
        .filter(|r| r.new_campaign_rate.len() == 3 && !r.scatter_true.is_empty())
        .map(|r| {
            let n = &r.new_campaign_rate;
            (vec![r.scatter_true[0]], vec![n[1]], vec![n[2]])
        })
        .collect();
    let mut c = coverage_of(with.iter().map(|(t, lo, hi)| (&t[..], &lo[..], &hi[..]))).remove(0);
    c.kind = "rate_new_campaign".into();
    c
}

/// The outcome labels of the confusion matrix, in column order.
pub fn outcome_labels() -> Vec<String> {
    let mut v = vec!["adequate".to_string(), "unexplained".to_string()];
    v.extend(
        crate::model::ext::CATALOGUE
            .iter()
            .map(|e| format!("extension:{e}")),
    );
    v.push("error".into());
    v
}

/// Confusion matrix rows (scenario, counts per [`outcome_labels`]) of `results` (optionally
/// only the detectable effect sets; no-effect sets always count).
pub fn confusion(results: &[SetResult], detectable_only: bool) -> Vec<(String, Vec<usize>)> {
    let labels = outcome_labels();
    crate::synth::SCENARIOS
        .iter()
        .map(|sc| {
            let counts = labels
                .iter()
                .map(|l| {
                    results
                        .iter()
                        .filter(|r| {
                            r.scenario == *sc
                                && (!detectable_only || r.detectable || r.scenario == "none")
                                && r.outcome() == *l
                        })
                        .count()
                })
                .collect();
            (sc.to_string(), counts)
        })
        .collect()
}

/// Bins of λ for the power table.
pub const LAMBDA_BINS: [(f64, f64); 6] = [
    (0.0, 5.0),
    (5.0, 25.0),
    (25.0, 100.0),
    (100.0, 1e3),
    (1e3, 1e4),
    (1e4, f64::INFINITY),
];

/// One row of the power table.
#[derive(Debug, Clone, PartialEq)]
pub struct PowerRow {
    /// Catalogued effect.
    pub effect: String,
    /// λ bin [lo, hi).
    pub bin: (f64, f64),
    /// Sets in the bin, named correctly, with any alarm (verdict not `adequate`).
    pub sets: usize,
    pub named: usize,
    pub any_alarm: usize,
    /// Mean effect size.
    pub mean_size: f64,
}

/// Power table: per catalogued effect and λ bin, how many sets named the effect.
pub fn power(results: &[SetResult]) -> Vec<PowerRow> {
    let mut out = Vec::new();
    for e in crate::model::ext::CATALOGUE {
        for &(lo, hi) in &LAMBDA_BINS {
            let sets: Vec<&SetResult> = results
                .iter()
                .filter(|r| {
                    r.error.is_none()
                        && r.scenario == *e
                        && r.power_lambda() >= lo
                        && r.power_lambda() < hi
                })
                .collect();
            if sets.is_empty() {
                continue;
            }
            let named = sets.iter().filter(|r| r.named_correctly()).count();
            let any = sets
                .iter()
                .filter(|r| r.verdict != Some(Verdict::Adequate))
                .count();
            let size = sets.iter().map(|r| r.size).sum::<f64>() / sets.len() as f64;
            out.push(PowerRow {
                effect: e.to_string(),
                bin: (lo, hi),
                sets: sets.len(),
                named,
                any_alarm: any,
                mean_size: size,
            });
        }
    }
    out
}

/// Write results.csv, confusion.csv, confusion_detectable.csv, power.csv, summary.md and
/// power.png into `dir`.
pub fn write_reports(dir: &Path, results: &[SetResult], first_seed: u64) -> Result<Rates> {
    use crate::report::tables::{num, write_csv, write_text};
    let rows: Vec<Vec<String>> = results
        .iter()
        .map(|r| {
            vec![
                r.name.clone(),
                r.seed.to_string(),
                r.scenario.clone(),
                r.family.clone(),
                num(r.size),
                r.sampling.clone(),
                num(r.noise_phi),
                r.curves.to_string(),
                num(r.lambda),
                u8::from(r.detectable).to_string(),
                r.outcome(),
                r.closest.clone().unwrap_or_default(),
                r.p_values
                    .iter()
                    .map(|(n, p)| format!("{n}={p}"))
                    .collect::<Vec<_>>()
                    .join(";"),
                r.gof_p
                    .iter()
                    .map(|p| num(*p))
                    .collect::<Vec<_>>()
                    .join(";"),
                r.replicates.to_string(),
                num(r.wall_s),
                r.error.clone().unwrap_or_default(),
                num(r.lambda_scatter),
            ]
        })
        .collect();
    write_csv(
        &dir.join("results.csv"),
        &[
            "name",
            "seed",
            "scenario",
            "family",
            "size",
            "sampling",
            "noise_phi",
            "curves",
            "lambda",
            "detectable",
            "outcome",
            "closest",
            "p_values",
            "gof_p",
            "replicates",
            "wall_s",
            "error",
            "lambda_scatter",
        ],
        &rows,
    )?;
    let labels = outcome_labels();
    let mut header = vec!["scenario".to_string()];
    header.extend(labels.iter().cloned());
    let hdr: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    for (file, det) in [("confusion.csv", false), ("confusion_detectable.csv", true)] {
        let rows: Vec<Vec<String>> = confusion(results, det)
            .into_iter()
            .map(|(s, c)| {
                let mut v = vec![s];
                v.extend(c.iter().map(|x| x.to_string()));
                v
            })
            .collect();
        write_csv(&dir.join(file), &hdr, &rows)?;
    }
    let pw = power(results);
    write_csv(
        &dir.join("power.csv"),
        &[
            "effect",
            "lambda_lo",
            "lambda_hi",
            "sets",
            "named",
            "any_alarm",
            "mean_size",
        ],
        &pw.iter()
            .map(|p| {
                vec![
                    p.effect.clone(),
                    num(p.bin.0),
                    num(p.bin.1),
                    p.sets.to_string(),
                    p.named.to_string(),
                    p.any_alarm.to_string(),
                    num(p.mean_size),
                ]
            })
            .collect::<Vec<_>>(),
    )?;
    let r = rates(results);
    let mut md = format!(
        "# diagnose battery: {} sets, seeds {}..{}\n\n",
        results.len(),
        first_seed,
        first_seed + results.len() as u64 - 1
    );
    md += &format!(
        "- False alarms on no-effect data: {} of {} = {:.1} % (Monte Carlo se {:.1} %, Wilson 95 % {:.1}–{:.1} %)\n",
        r.false_alarms,
        r.null_sets,
        100.0 * r.false_alarm_rate,
        100.0 * r.false_alarm_se,
        100.0 * r.false_alarm_ci95.0,
        100.0 * r.false_alarm_ci95.1
    );
    for (e, n, d, k) in &r.named {
        let (lo, hi) = wilson(*k, *d);
        md += &format!(
            "- {e}: {n} sets, {d} detectable (λ ≥ {DETECTABLE_LAMBDA}), named correctly in {k} = {:.1} % (Wilson 95 % {:.1}–{:.1} %)\n",
            100.0 * *k as f64 / (*d).max(1) as f64,
            100.0 * lo,
            100.0 * hi
        );
    }
    if results.iter().any(|r| !r.lambda_scatter.is_nan()) {
        md += &format!(
            "- Detectable: specimen-world sets of a catalogued effect by the oracle with the specimens' factors unknown (`lambda_scatter`); with them known (`lambda`), {} of those sets would be\n",
            results
                .iter()
                .filter(|r| !r.lambda_scatter.is_nan() && r.lambda >= DETECTABLE_LAMBDA)
                .count()
        );
    }
    md += &format!(
        "- Effects outside the catalogue: {} sets, `extension` verdict in {} = {:.1} %\n",
        r.outside_sets,
        r.outside_extension,
        100.0 * r.outside_extension as f64 / r.outside_sets.max(1) as f64
    );
    md += &format!("- Sets that failed to generate or diagnose: {}\n", r.errors);
    for c in r.scatter.iter().filter(|c| c.true_sets + c.absent_sets > 0) {
        let (lo, hi) = wilson(c.covered, c.true_sets);
        md += &format!(
            "- Specimen scatter of the {}: its 95 % interval covers the true sd in {} of {} sets that carry it = {:.1} % (Wilson 95 % {:.1}–{:.1} %); excludes zero in {} of {} sets that do not\n",
            c.kind,
            c.covered,
            c.true_sets,
            100.0 * c.covered as f64 / c.true_sets.max(1) as f64,
            100.0 * lo,
            100.0 * hi,
            c.spurious,
            c.absent_sets
        );
    }
    let c = &r.new_campaign;
    if c.true_sets > 0 {
        let (lo, hi) = wilson(c.covered, c.true_sets);
        md += &format!(
            "- A new specimen from a new campaign (sets whose specimens name campaigns): the 95 % interval of its rate sd covers the true sd in {} of {} sets = {:.1} % (Wilson 95 % {:.1}–{:.1} %)\n",
            c.covered,
            c.true_sets,
            100.0 * c.covered as f64 / c.true_sets as f64,
            100.0 * lo,
            100.0 * hi
        );
    }
    for (title, det) in [
        ("all sets", false),
        ("detectable effect sets (and all no-effect sets)", true),
    ] {
        md += &format!(
            "\n## Confusion matrix, {title}\n\n| truth \\ outcome | {} |\n|{}\n",
            labels.join(" | "),
            "---|".repeat(labels.len() + 1)
        );
        for (s, c) in confusion(results, det) {
            md += &format!(
                "| {s} | {} |\n",
                c.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
        }
    }
    md += "\n## Power against the oracle's λ\n\n| effect | λ | sets | named correctly | any alarm | mean size |\n|---|---|---|---|---|---|\n";
    for p in &pw {
        let (lo, hi) = p.bin;
        md += &format!(
            "| {} | {lo}–{} | {} | {} ({:.0} %) | {} | {:.3} |\n",
            p.effect,
            if hi.is_finite() {
                format!("{hi}")
            } else {
                "∞".into()
            },
            p.sets,
            p.named,
            100.0 * p.named as f64 / p.sets as f64,
            p.any_alarm,
            p.mean_size
        );
    }
    write_text(&dir.join("summary.md"), &md)?;
    write_text(
        &dir.join("summary.json"),
        &(serde_json::to_string_pretty(&r).expect("plain values") + "\n"),
    )?;
    // Power plot: named-correctly rate against log10 λ (bin centres), one series per effect.
    let series: Vec<crate::report::plot::Series> = crate::model::ext::CATALOGUE
        .iter()
        .map(|e| crate::report::plot::Series {
            label: e.to_string(),
            points: pw
                .iter()
                .filter(|p| p.effect == *e)
                .map(|p| {
                    let (lo, hi) = p.bin;
                    let c = if hi.is_finite() {
                        (lo.max(1.0) * hi).sqrt()
                    } else {
                        lo * 3.0
                    };
                    (c.log10(), 100.0 * p.named as f64 / p.sets as f64)
                })
                .collect(),
        })
        .collect();
    crate::report::plot::plot_residuals(
        &dir.join("power.png"),
        "diagnose: effects named correctly against the oracle's noncentrality",
        &series,
        "log10 λ (oracle noncentrality; detectable: λ ≥ 25)",
        "named correctly, % of sets",
    )?;
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A set whose numbers are not known (NaN: an oracle that failed, a p-value not
    /// computed, a scatter interval of a dropped kind) reads back from its JSON line: a
    /// resumed battery failed on exactly this (`null` where an f64 was expected).
    #[test]
    fn unknown_numbers_survive_the_results_file() {
        let mut r = run_one_skeleton();
        r.p_values = vec![("constant_load".into(), f64::NAN), ("x".into(), 0.25)];
        r.gof_p = vec![f64::NAN, 0.5];
        r.scatter_est = vec![0.2, 0.0];
        r.scatter_lo95 = vec![0.1, f64::NAN];
        r.scatter_hi95 = vec![0.3, f64::NAN];
        let line = serde_json::to_string(&r).unwrap();
        assert!(line.contains("null"));
        let back: SetResult = serde_json::from_str(&line).unwrap();
        assert!(back.lambda.is_nan() && back.size.is_nan() && back.wall_s.is_nan());
        assert!(back.p_values[0].1.is_nan() && back.p_values[1].1 == 0.25);
        assert!(back.gof_p[0].is_nan() && back.gof_p[1] == 0.5);
        assert!(back.scatter_lo95[1].is_nan() && back.scatter_hi95[0] == 0.3);
        // Written again, it is the same line.
        assert_eq!(serde_json::to_string(&back).unwrap(), line);
    }

    /// A scatter fit with a dropped kind (NaN interval ends) reads back from its JSON line as
    /// it was written: `examples/scatter_coverage.rs` resumes from those lines.
    #[test]
    fn a_scatter_fit_with_a_dropped_kind_reads_back_from_json() {
        let f = ScatterFit {
            seed: 7,
            scatter_true: vec![0.2, 0.0],
            scatter_est: vec![0.18, 0.0],
            scatter_lo95: vec![0.1, f64::NAN],
            scatter_hi95: vec![0.4, f64::NAN],
            neg2ll: -123.5,
            iterations: 12,
            phi_est: vec![0.25, 0.5],
            scatter_method: Some(crate::specimen::ScatterMethod::LaplaceAtModes),
        };
        let text = serde_json::to_string(&("guess", &f)).unwrap();
        let (start, back): (String, ScatterFit) = serde_json::from_str(&text).unwrap();
        assert_eq!(start, "guess");
        assert_eq!((back.seed, back.iterations, back.neg2ll), (7, 12, -123.5));
        assert_eq!(back.scatter_lo95[0], 0.1);
        assert!(back.scatter_lo95[1].is_nan() && back.scatter_hi95[1].is_nan());
        assert_eq!(back.scatter_method, f.scatter_method);
        assert_eq!(back.phi_est, vec![0.25, 0.5]);
        // A record written before φ was kept reads with none.
        let old = text.replace(",\"phi_est\":[0.25,0.5]", "");
        assert!(!old.contains("phi_est"), "{old}");
        let (_, back): (String, ScatterFit) = serde_json::from_str(&old).unwrap();
        assert!(back.phi_est.is_empty());
    }

    /// Each kind's estimate and interval in the fixed order rate, ductility, whatever order
    /// the fit carries them in: 0 and NaN ends for a kind the fit lacks, and for no fit.
    #[test]
    fn a_kind_fitted_that_the_world_does_not_draw_is_true_zero() {
        let specimens = SpecimenTruth {
            rate_sd: 0.2,
            ductility_sd: 0.08,
            ..SpecimenTruth::default()
        };
        let shapes = SpecimenTruth {
            coarsening_sd: 0.3,
            coarsening_effects: vec![0.1, -0.2],
            ..specimens.clone()
        };
        // (truth, kinds fitted, true scatter by kind)
        let rows: [(&SpecimenTruth, usize, Vec<f64>); 4] = [
            (&specimens, 2, vec![0.2, 0.08]),
            (&specimens, 3, vec![0.2, 0.08, 0.0]),
            (&shapes, 3, vec![0.2, 0.08, 0.3]),
            (&shapes, 2, vec![0.2, 0.08, 0.3]),
        ];
        for (truth, fitted, want) in rows {
            assert_eq!(true_by_kind(truth, fitted), want, "{fitted} fitted");
        }
        // So a specimens-world battery that fits coarsening gets a coarsening row, all absent.
        let t = true_by_kind(&specimens, 3);
        let cov = coverage_of(std::iter::once((
            &t[..],
            &[0.1, 0.0, 0.0][..],
            &[0.3, 0.2, 0.1][..],
        )));
        let row = cov
            .iter()
            .find(|c| c.kind == "coarsening")
            .expect("a coarsening row");
        assert_eq!((row.true_sets, row.absent_sets, row.spurious), (0, 1, 0));
    }

    #[test]
    fn scatter_by_kind_puts_rate_first_and_marks_a_missing_kind() {
        use crate::likelihood::SpecimenFit;
        let fit = |kinds: Vec<EffectKind>, s: Vec<f64>| SpecimenFit {
            scatter_lo95: s.iter().map(|v| v / 2.0).collect(),
            scatter_hi95: s.iter().map(|v| v * 2.0).collect(),
            scatter_dof: vec![f64::NAN; s.len()],
            effects: vec![vec![]; kinds.len()],
            effects_sd: vec![vec![]; kinds.len()],
            kinds,
            scatter: s,
            neg2ll_effects: 0.0,
            scatter_method: Default::default(),
            dropped: vec![],
        };
        let both = fit(
            vec![EffectKind::Ductility, EffectKind::Rate],
            vec![0.1, 0.3],
        );
        assert_eq!(
            scatter_by_kind(Some(&both)),
            (vec![0.3, 0.1], vec![0.15, 0.05], vec![0.6, 0.2])
        );
        let rate = fit(vec![EffectKind::Rate], vec![0.2]);
        let (e, lo, hi) = scatter_by_kind(Some(&rate));
        assert_eq!((e[0], lo[0], hi[0], e[1]), (0.2, 0.1, 0.4, 0.0));
        assert!(lo[1].is_nan() && hi[1].is_nan());
        let (e, lo, _) = scatter_by_kind(None);
        assert_eq!(e, vec![0.0, 0.0]);
        assert!(lo.iter().all(|v| v.is_nan()));
    }

    /// Coverage counts as a table: covered inside the interval (ends included), a dropped
    /// kind (no interval) not covered, a scatter that is not there found only when the
    /// interval excludes zero; sets of the identical world and failed sets left out.
    #[test]
    fn scatter_coverage_counts_as_a_table() {
        let set = |t: [f64; 2], lo: [f64; 2], hi: [f64; 2]| {
            let mut r = run_one_skeleton();
            r.error = None;
            r.scatter_true = t.to_vec();
            r.scatter_lo95 = lo.to_vec();
            r.scatter_hi95 = hi.to_vec();
            r
        };
        let nan = f64::NAN;
        let mut identical = set([0.2, 0.0], [0.1, 0.0], [0.3, 0.0]);
        identical.scatter_true.clear();
        let mut failed = set([0.2, 0.08], [0.1, 0.0], [0.3, 0.2]);
        failed.error = Some("x".into());
        let results = vec![
            set([0.2, 0.08], [0.1, 0.05], [0.3, 0.2]), // both covered
            set([0.2, 0.08], [0.2, 0.09], [0.3, 0.2]), // rate at the lower end; ductility not
            set([0.2, 0.08], [0.1, nan], [0.19, nan]), // rate above; ductility dropped
            set([0.1, 0.0], [0.05, 0.0], [0.2, 0.01]), // no ductility scatter, none found
            set([0.1, 0.0], [0.05, 0.02], [0.2, 0.1]), // no ductility scatter, one found
            set([0.1, 0.0], [0.05, nan], [0.2, nan]),  // no ductility scatter, kind dropped
            identical,
            failed,
        ];
        let r = rates(&results);
        let c = |k: &str| r.scatter.iter().find(|c| c.kind == k).unwrap().clone();
        let rate = c("rate");
        assert_eq!((rate.true_sets, rate.covered), (6, 5));
        assert_eq!((rate.absent_sets, rate.spurious), (0, 0));
        let d = c("ductility");
        assert_eq!((d.true_sets, d.covered), (3, 1));
        assert_eq!((d.absent_sets, d.spurious), (3, 1));
        assert_eq!(r.errors, 1);
        // No set names campaigns: no sets in the new campaign's row.
        assert_eq!(r.new_campaign.true_sets, 0);
        assert_eq!(r.new_campaign.kind, "rate_new_campaign");
        // Sets with a new campaign's sd: scored against the true rate scatter (ends included).
        let campaign = |t: f64, lo: f64, hi: f64| {
            let mut r = set([t, 0.08], [0.1, 0.05], [0.3, 0.2]);
            r.new_campaign_rate = vec![0.5 * (lo + hi), lo, hi];
            r
        };
        let r = rates(&[
            campaign(0.3, 0.2, 0.9),
            campaign(0.3, 0.3, 0.9),
            campaign(0.3, 0.31, 0.9),
            set([0.2, 0.08], [0.1, 0.05], [0.3, 0.2]),
        ]);
        assert_eq!((r.new_campaign.true_sets, r.new_campaign.covered), (3, 2));
    }

    /// Which λ places a set in the power table, as a table: the oracle with the specimens'
    /// factors unknown for a catalogued effect in the specimen world, the known-factor one
    /// elsewhere (the identical world, no effect, effects outside the catalogue).
    #[test]
    fn the_power_lambda_is_the_scatter_oracle_for_catalogued_effects_under_scatter() {
        for (world, scenario, lambda, scatter, want) in [
            (World::Specimens, "constant_load", 3094.4, 3.3, 3.3),
            (World::Specimens, "loading_strain", 44.9, 40.8, 40.8),
            (World::Specimens, "none", 0.0, f64::NAN, 0.0),
            (World::Specimens, "primary_transient", 80.0, f64::NAN, 80.0),
            (World::Identical, "constant_load", 3094.4, f64::NAN, 3094.4),
            (World::Identical, "constant_load", 3094.4, 3.3, 3094.4),
        ] {
            let r = SetResult {
                world,
                scenario: scenario.into(),
                lambda,
                lambda_scatter: scatter,
                ..run_one_skeleton()
            };
            assert_eq!(r.power_lambda(), want, "{world:?} {scenario}");
        }
        // A catalogued effect under scatter whose oracle failed is not detectable by default.
        let r = SetResult {
            scenario: "constant_load".into(),
            lambda: 3094.4,
            ..run_one_skeleton()
        };
        assert!(r.power_lambda().is_nan());
    }

    /// summary.md counts the sets the known-factor oracle would have called detectable beside
    /// the scatter oracle's, and results.csv carries both λ.
    #[test]
    fn the_summary_names_both_oracles() {
        let dir = tempfile::tempdir().unwrap();
        let set = |seed: u64, lambda: f64, scatter: f64| SetResult {
            name: format!("set-{seed}"),
            seed,
            scenario: "constant_load".into(),
            lambda,
            lambda_scatter: scatter,
            detectable: scatter >= DETECTABLE_LAMBDA,
            verdict: Some(Verdict::Adequate),
            error: None,
            ..run_one_skeleton()
        };
        let results = vec![set(1, 3094.4, 3.3), set(2, 232.2, 71.7), set(3, 5.0, 1.0)];
        write_reports(dir.path(), &results, 1).unwrap();
        let md = std::fs::read_to_string(dir.path().join("summary.md")).unwrap();
        assert!(md.contains("- constant_load: 3 sets, 1 detectable"), "{md}");
        assert!(
            md.contains("with them known (`lambda`), 2 of those sets would be"),
            "{md}"
        );
        let csv = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == "lambda_scatter").unwrap();
        assert_eq!(lines.next().unwrap().split(',').nth(col), Some("3.3"));
    }

    fn run_one_skeleton() -> SetResult {
        // A set whose generator numbers are not known.
        SetResult {
            name: "set-1".into(),
            seed: 1,
            scenario: "none".into(),
            family: String::new(),
            size: f64::NAN,
            sampling: String::new(),
            noise_phi: 0.3,
            curves: 0,
            lambda: f64::NAN,
            lambda_scatter: f64::NAN,
            detectable: false,
            verdict: None,
            cause: None,
            closest: None,
            p_values: vec![],
            gof_p: vec![],
            replicates: 0,
            wall_s: f64::NAN,
            world: World::Specimens,
            scatter_true: vec![0.2, 0.08],
            scatter_est: vec![],
            scatter_lo95: vec![],
            scatter_hi95: vec![],
            new_campaign_rate: vec![],
            error: Some("not generated".into()),
        }
    }
}
