//! Measured coverage: on synthetic data sets with known truth ([`crate::synth`], no hidden
//! effect: the model is right, the reading error correlated or white, the curves end before
//! rupture, the rupture times scattered by 1 %), how often the nominal 68 % and 95 % intervals
//! contain the true constants and the true rupture time at an untested stress
//! ([`CoverageSettings::stress_factor`] × the lowest tested stress), and how often the 95 %
//! prediction interval contains a new test's life drawn with the generator's scatter.
//!
//! Every set records the intervals of the shipped method (profile likelihood with calibrated
//! thresholds) and of the alternatives measured against it: plain χ² thresholds on the same
//! profiles, the Wald (Fisher information) interval, and — when asked for — the percentile
//! interval of a parametric bootstrap of the prediction. Sets run in parallel; each finished
//! set is appended (flushed) to `coverage.jsonl`, so an interrupted run resumes where it
//! stopped and never loses a finished set.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::constrained::{Predicted, Quantity};
use super::predict::{bootstrap_predictions, percentile95, specimen_scatter};
use super::profile::{quantity_interval, reinterval, Class};
use super::report::{context, core};
use super::{normal_quantile, Thresholds};
use crate::config::{ProfileConfig, RunConfig};
use crate::error::{Error, Result};
use crate::model::Load;
use crate::ode::OdeOptions;
use crate::synth::{generate_in, write_set, World};

/// Settings of a coverage run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoverageSettings {
    /// Latin-hypercube starts of each set's multistart (besides the initial guess).
    pub starts: usize,
    /// Calibration replicates (0: χ² thresholds only).
    pub calibrate: usize,
    /// Bootstrap replicates of the prediction (0: not measured).
    pub bootstrap: usize,
    /// The untested stress as a fraction of the lowest tested one.
    pub stress_factor: f64,
    /// The laboratory the sets come from (with [`World::Specimens`] the configurations fit
    /// specimen effects, `auto`: every set has replicates).
    #[serde(default)]
    pub world: World,
    /// Times of the strain band measured at the untested stress (`[profile] band_points`;
    /// 0: the band is not measured).
    #[serde(default)]
    pub band_points: usize,
}

impl Default for CoverageSettings {
    fn default() -> Self {
        CoverageSettings {
            starts: 16,
            calibrate: 20,
            bootstrap: 0,
            stress_factor: 0.85,
            world: World::Identical,
            band_points: 9,
        }
    }
}

/// A (lo, hi) interval.
pub type Iv = (f64, f64);

fn nan() -> f64 {
    f64::NAN
}

use crate::journal::de_nan_f64 as de_f64;

/// [`de_f64`] for an interval.
fn de_iv<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Iv, D::Error> {
    let (a, b) = <(Option<f64>, Option<f64>)>::deserialize(d)?;
    Ok((a.unwrap_or(f64::NAN), b.unwrap_or(f64::NAN)))
}

fn covers(iv: Iv, truth: f64) -> bool {
    iv.0 <= truth && truth <= iv.1
}

/// One constant of one set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConstantCoverage {
    pub name: String,
    #[serde(deserialize_with = "de_f64")]
    pub truth: f64,
    #[serde(deserialize_with = "de_f64")]
    pub value: f64,
    /// Class under the shipped (calibrated) thresholds, and under plain χ².
    pub class: Class,
    pub class_chi2: Class,
    /// 95 % and 68 % intervals, calibrated thresholds.
    #[serde(deserialize_with = "de_iv")]
    pub cal95: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub cal68: Iv,
    /// The same with plain χ² thresholds.
    #[serde(deserialize_with = "de_iv")]
    pub chi95: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub chi68: Iv,
    /// Wald 95 % interval (unit box, clamped to the bounds).
    #[serde(deserialize_with = "de_iv")]
    pub wald95: Iv,
    /// The truth's likelihood-ratio statistic and the calibration behind the thresholds
    /// (None in records written before it was measured).
    #[serde(default)]
    pub statistic: Option<TruthStatistic>,
}

/// A quantity's likelihood-ratio statistic at its true value on the data, beside its
/// calibration replicates' statistics and the thresholds its intervals were read at: whatever
/// the rule that turns the replicates into thresholds, the interval covers the truth where
/// `t_truth` lies below the threshold (up to the profile's interpolation), so other rules can
/// be measured on the same sets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthStatistic {
    /// −2 ln L with the quantity held at its true value, minus the optimum's (the lower of the
    /// two, should the held fit find a lower one); NaN where the held fit failed.
    #[serde(deserialize_with = "de_f64")]
    pub t_truth: f64,
    /// T of each calibration replicate for this quantity (empty: not calibrated itself).
    pub t_replicates: Vec<f64>,
    /// The thresholds of its 68 % and 95 % intervals.
    #[serde(deserialize_with = "de_f64")]
    pub t68: f64,
    #[serde(deserialize_with = "de_f64")]
    pub t95: f64,
}

/// The rupture time at the untested stress in one set (h).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RuptureCoverage {
    #[serde(deserialize_with = "de_f64")]
    pub stress_mpa: f64,
    #[serde(deserialize_with = "de_f64")]
    pub truth_h: f64,
    #[serde(deserialize_with = "de_f64")]
    pub value_h: f64,
    #[serde(deserialize_with = "de_iv")]
    pub cal95: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub cal68: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub chi95: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub chi68: Iv,
    #[serde(deserialize_with = "de_iv")]
    pub wald95: Iv,
    /// Bootstrap percentile interval (NaN when not measured).
    #[serde(deserialize_with = "de_iv")]
    pub boot95: Iv,
    /// 95 % prediction interval of a new test (calibrated), and the new test's life.
    #[serde(deserialize_with = "de_iv")]
    pub pred95: Iv,
    #[serde(deserialize_with = "de_f64")]
    pub new_test_h: f64,
    /// Whether the calibrated interval is open on a side.
    pub open: bool,
    /// The 95 % confidence interval `predict --intervals` and `profile` write: `cal95`
    /// widened to the confidence-set members of the three quantities' searches (NaN in
    /// records written before it was measured).
    #[serde(default = "nan_iv", deserialize_with = "de_iv")]
    pub shipped95: Iv,
    /// The statistic of the true rupture time (of ln t_r) and its calibration.
    #[serde(default)]
    pub statistic: Option<TruthStatistic>,
}

fn nan_iv() -> Iv {
    (f64::NAN, f64::NAN)
}

/// One time of the 95 % strain band at the untested stress (`creepfit profile`'s and
/// `predict --intervals`' band: calibrated thresholds, the upper end rupture from the rupture
/// time's lower 95 % bound on) beside the true model's strain there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BandCoverage {
    /// Time, h (a fraction of the predicted rupture time).
    #[serde(deserialize_with = "de_f64")]
    pub time_h: f64,
    /// The true constants' strain at this time, % (NaN once they have ruptured).
    #[serde(deserialize_with = "de_f64")]
    pub truth_pct: f64,
    /// Whether the true constants have ruptured by this time.
    pub truth_ruptured: bool,
    /// The band's ends, % (`hi95_pct` NaN where `hi95_ruptured`).
    #[serde(deserialize_with = "de_f64")]
    pub lo95_pct: f64,
    #[serde(deserialize_with = "de_f64")]
    pub hi95_pct: f64,
    /// Whether the band's upper end is rupture.
    pub hi95_ruptured: bool,
}

/// Where a band point stands against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BandHit {
    Covered,
    /// The truth's strain below the lower end.
    Below,
    /// The truth's strain above the upper end, or the truth ruptured where the band holds
    /// the test intact.
    Above,
}

impl BandCoverage {
    /// Covered when the truth's strain lies between the ends; a truth ruptured by this time
    /// is covered only by an upper end that is rupture.
    pub fn hit(&self) -> BandHit {
        if self.truth_ruptured {
            return if self.hi95_ruptured {
                BandHit::Covered
            } else {
                BandHit::Above
            };
        }
        if !(self.truth_pct >= self.lo95_pct) {
            BandHit::Below
        } else if !self.hi95_ruptured && !(self.truth_pct <= self.hi95_pct) {
            BandHit::Above
        } else {
            BandHit::Covered
        }
    }
}

/// One set's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetCoverage {
    pub name: String,
    pub seed: u64,
    pub family: String,
    pub sampling: String,
    #[serde(deserialize_with = "de_f64")]
    pub noise_phi: f64,
    pub curves: usize,
    pub points: usize,
    /// Calibration factor and the mean LR statistic behind it.
    #[serde(deserialize_with = "de_f64")]
    pub factor: f64,
    #[serde(deserialize_with = "de_f64")]
    pub mean_t: f64,
    /// Calibration factor of the prediction's thresholds.
    #[serde(default = "nan", deserialize_with = "de_f64")]
    pub prediction_factor: f64,
    pub constants: Vec<ConstantCoverage>,
    pub rupture: Option<RuptureCoverage>,
    /// The strain band at the untested stress (empty where the rupture time's interval is
    /// not known, or in records written before the band was measured).
    #[serde(default)]
    pub band: Vec<BandCoverage>,
    /// Inner fits of the profiles.
    pub fits: usize,
    /// Times the profiles were redone from a better optimum found on them.
    #[serde(default)]
    pub restarts: usize,
    #[serde(deserialize_with = "de_f64")]
    pub wall_s: f64,
    pub error: Option<String>,
}

impl SetCoverage {
    /// A set's result before anything is measured: every number NaN or zero.
    fn unmeasured(name: String, seed: u64) -> SetCoverage {
        SetCoverage {
            name,
            seed,
            family: String::new(),
            sampling: String::new(),
            noise_phi: f64::NAN,
            curves: 0,
            points: 0,
            factor: f64::NAN,
            mean_t: f64::NAN,
            prediction_factor: f64::NAN,
            constants: vec![],
            rupture: None,
            band: vec![],
            fits: 0,
            restarts: 0,
            wall_s: f64::NAN,
            error: None,
        }
    }
}

/// Generate set `seed` (scenario `none`) into `dir/sets/set-<seed>/` and measure it.
pub fn run_set(dir: &Path, seed: u64, s: &CoverageSettings) -> SetCoverage {
    let t0 = Instant::now();
    let name = format!("set-{seed}");
    let mut out = SetCoverage::unmeasured(name, seed);
    if let Err(e) = measure(dir, seed, s, &mut out) {
        out.error = Some(e.to_string());
    }
    out.wall_s = t0.elapsed().as_secs_f64();
    out
}

fn measure(dir: &Path, seed: u64, s: &CoverageSettings, out: &mut SetCoverage) -> Result<()> {
    let set = generate_in(&out.name, "none", None, seed, s.world)?;
    let folder = dir.join("sets").join(&out.name);
    write_set(&set, &folder)?;
    let t = &set.truth;
    out.family = t.family.clone();
    out.sampling = format!("{:?}", t.sampling).to_lowercase();
    out.noise_phi = t.noise_phi;
    out.curves = t.stresses.len();
    out.points = t.times_h.iter().map(|v| v.len()).sum();
    let cfg = RunConfig::load(&folder.join("config.toml"))?;
    let data = cfg.load_data()?;
    let model = cfg.build_model()?;
    let ctx = context(&cfg.likelihood_setup(&data), model.as_ref(), &data);

    // The untested load and its true rupture time.
    let lowest = t.stresses.iter().copied().fold(f64::INFINITY, f64::min);
    let load = Load::new(
        (s.stress_factor * lowest).round(),
        t.temperature_c,
        cfg.objective.omega_f,
    );
    let tight = OdeOptions {
        rtol: 1e-11,
        atol: 1e-15,
        t_end: 1e12,
        ..OdeOptions::default()
    };
    let truth_run = model.simulate(&t.constants, &load, &[], &mut [], &tight);
    let q = Quantity::Prediction {
        load,
        what: Predicted::LnRuptureTime,
    };

    // What `creepfit profile` does: multistart, calibration, profiles with restarts.
    let pc = ProfileConfig {
        starts: s.starts,
        seed,
        calibrate: s.calibrate,
        predict_stress_mpa: vec![load.stress_mpa],
        ..cfg.profile.clone()
    };
    let c = core(
        &ctx,
        &cfg,
        None,
        &pc,
        &[load],
        &crate::progress::Hooks::default(),
    )?;
    let ctx = if c.without_specimens {
        ctx.without_specimens()
    } else {
        ctx
    };
    let pth = c
        .load_thresholds
        .first()
        .copied()
        .unwrap_or(c.prediction_thresholds);
    let calibration = c.calibration;
    let (reference, th, profiles) = (c.reference, c.thresholds, c.profiles);
    out.factor = th.factor;
    out.prediction_factor = pth.factor;
    let replicates_of = |label: &str| {
        calibration
            .as_ref()
            .and_then(|c| c.per_quantity.iter().find(|q| q.quantity == label))
            .map(|q| q.t.clone())
            .unwrap_or_default()
    };
    // −2 ln L held at a true value: from the optimum and from the truth, the lower.
    let lower = |a: super::constrained::PointFit, b: super::constrained::PointFit| {
        [a, b]
            .into_iter()
            .filter(|f| f.ok())
            .map(|f| f.neg2ll)
            .fold(f64::NAN, f64::min)
    };
    let statistic = |held: f64| {
        if held.is_finite() {
            (held - reference.neg2ll).max(0.0)
        } else {
            f64::NAN
        }
    };
    out.mean_t = calibration.as_ref().map_or(f64::NAN, |c| c.mean_t);
    out.restarts = c.restarts;
    let plain = Thresholds::chi2(1.0);

    // Constants.
    out.fits = profiles.iter().map(|p| p.fits()).sum();
    let se = super::profile::wald_se(&ctx, &reference);
    let names = ctx.names();
    for p in &profiles {
        let j = p.index;
        let c = reinterval(&ctx, &reference, p, &plain);
        let u = ctx.space.to_unit_one(j, reference.params[j]);
        let w = 1.96 * se[j];
        let wald95 = (
            ctx.space.from_unit_one(j, (u - w).max(0.0)),
            ctx.space.from_unit_one(j, (u + w).min(1.0)),
        );
        let v = t.constants[j];
        let held = lower(
            super::constrained::held_fit(&ctx, j, v, &reference.params, true),
            super::constrained::held_fit(&ctx, j, v, &t.constants, true),
        );
        out.constants.push(ConstantCoverage {
            statistic: Some(TruthStatistic {
                t_truth: statistic(held),
                t_replicates: replicates_of(names[j]),
                t68: p.thresholds.t68,
                t95: p.thresholds.t95,
            }),
            name: names[j].to_string(),
            truth: t.constants[j],
            value: reference.params[j],
            class: p.class,
            class_chi2: c.class,
            cal95: (p.interval.lo95, p.interval.hi95),
            cal68: (p.interval.lo68, p.interval.hi68),
            chi95: (c.interval.lo95, c.interval.hi95),
            chi68: (c.interval.lo68, c.interval.hi68),
            wald95,
        });
    }

    // The rupture time at the untested stress.
    if truth_run.ruptured() {
        let qc = quantity_interval(&ctx, &reference, &q, &pth);
        let qp = if pth.factor == 1.0 {
            qc.clone()
        } else {
            quantity_interval(&ctx, &reference, &q, &plain)
        };
        if let (Some(qc), Some(qp)) = (qc, qp) {
            out.fits += qc.fits() + qp.fits();
            let e = |iv: Iv| (iv.0.exp(), iv.1.exp());
            let ic = qc.interval;
            let ip = qp.interval;
            let wald = (ic.value - 1.96 * qc.wald_se, ic.value + 1.96 * qc.wald_se);
            let boot = if s.bootstrap > 0 {
                let b: Vec<f64> = bootstrap_predictions(&ctx, &reference, &load, s.bootstrap, seed)
                    .iter()
                    .map(|r| r[0])
                    .collect();
                percentile95(&b)
            } else {
                (f64::NAN, f64::NAN)
            };
            let scatter = specimen_scatter(&ctx, &reference)[0].0;
            let z = normal_quantile(0.975);
            let add = (z * scatter).powi(2);
            let pred = (
                ic.value - ((ic.value - ic.lo95).powi(2) + add).sqrt(),
                ic.value + ((ic.hi95 - ic.value).powi(2) + add).sqrt(),
            );
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6e65_7774);
            let zt: f64 = StandardNormal.sample(&mut rng);
            // In the specimens world a new test is a new specimen: its own rate and ductility
            // factors drawn from the truth's scatter, its life simulated with them.
            let new_specimen_h = t.specimens.as_ref().and_then(|sp| {
                let (zr, zd): (f64, f64) = (
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                );
                let mut p = t.constants.clone();
                p[0] *= (sp.rate_sd * zr).exp();
                p[5] /= (sp.ductility_sd * zd).exp();
                let r = model.simulate(&p, &load, &[], &mut [], &tight);
                r.ruptured().then_some(r.t_end)
            });
            out.rupture = Some(RuptureCoverage {
                stress_mpa: load.stress_mpa,
                truth_h: truth_run.t_end,
                value_h: ic.value.exp(),
                cal95: e((ic.lo95, ic.hi95)),
                cal68: e((ic.lo68, ic.hi68)),
                chi95: e((ip.lo95, ip.hi95)),
                chi68: e((ip.lo68, ip.hi68)),
                wald95: e(wald),
                boot95: e(boot),
                pred95: e(pred),
                new_test_h: new_specimen_h.unwrap_or(truth_run.t_end) * (t.lifetime_sd * zt).exp(),
                open: ic.lo_open || ic.hi_open,
                shipped95: nan_iv(),
                statistic: Some(TruthStatistic {
                    t_truth: {
                        let (_, tau) = super::profile::penalty_scale(&ctx, &reference, &q);
                        let target = truth_run.t_end.ln();
                        statistic(lower(
                            super::constrained::constrained_fit(
                                &ctx,
                                &q,
                                target,
                                tau,
                                &reference.params,
                                true,
                            ),
                            super::constrained::constrained_fit(
                                &ctx,
                                &q,
                                target,
                                tau,
                                &t.constants,
                                true,
                            ),
                        ))
                    },
                    t_replicates: replicates_of(&super::calibrate::rupture_time_label(&load)),
                    t68: pth.t68,
                    t95: pth.t95,
                }),
            });
            // The intervals and the strain band as `profile` and `predict --intervals`
            // compute them (each spanning the members of every search), against the truth.
            // Only their confidence intervals are read: the scatter given is the rupture
            // time's, the others' new-test widths are not used.
            let li = super::predict::prediction_intervals(
                &ctx,
                &reference,
                &load,
                &pth,
                &[(scatter, 0), (0.0, 0), (0.0, 0)],
            );
            if let (Some(rc), Some(q)) = (out.rupture.as_mut(), li.quantities.first()) {
                if q.quantity == "rupture_time_h" {
                    rc.shipped95 = (q.conf_lo95, q.conf_hi95);
                }
            }
            out.fits += li.quantities.iter().map(|q| q.fits).sum::<usize>();
            let fractions = super::predict::band_fractions(s.band_points);
            let band = super::predict::prediction_band(
                &ctx,
                &reference,
                &load,
                &fractions,
                &pth,
                super::predict::rupture_lo95(&li.quantities),
                &li.members,
            );
            let times: Vec<f64> = band.iter().map(|b| b.time_h).collect();
            let mut strain = vec![f64::NAN; times.len()];
            let r = model.simulate(&t.constants, &load, &times, &mut strain, &tight);
            out.band = band
                .iter()
                .enumerate()
                .map(|(k, b)| {
                    let ruptured = r.ruptured() && k >= r.n_out;
                    BandCoverage {
                        time_h: b.time_h,
                        truth_pct: if ruptured {
                            f64::NAN
                        } else {
                            100.0 * strain[k]
                        },
                        truth_ruptured: ruptured,
                        lo95_pct: b.lo95_pct,
                        hi95_pct: b.hi95_pct,
                        hi95_ruptured: b.hi95_ruptured,
                    }
                })
                .collect();
        }
    }
    Ok(())
}

/// Results already in `dir/coverage.jsonl`, by seed.
pub fn read_results(dir: &Path) -> Result<BTreeMap<u64, SetCoverage>> {
    crate::journal::read_lines_by(
        &dir.join("coverage.jsonl"),
        "a coverage result",
        |r: &SetCoverage| r.seed,
    )
}

/// Measure sets `first_seed .. first_seed + n` into `dir`, skipping those already in
/// `coverage.jsonl`; all results in seed order.
pub fn run_coverage(
    dir: &Path,
    first_seed: u64,
    n: usize,
    s: &CoverageSettings,
    progress: bool,
) -> Result<Vec<SetCoverage>> {
    // Quiet bars draw and print nothing.
    run_coverage_observed(
        dir,
        first_seed,
        n,
        s,
        &crate::progress::Bars::new(!progress),
    )
}

/// [`run_coverage`] telling `observer` of every finished set (a step, and a line with its
/// factors and time) instead of printing.
pub fn run_coverage_observed(
    dir: &Path,
    first_seed: u64,
    n: usize,
    s: &CoverageSettings,
    observer: &dyn crate::progress::Observer,
) -> Result<Vec<SetCoverage>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let done = read_results(dir)?;
    let path = dir.join("coverage.jsonl");
    let file = crate::journal::append_lines(&path)?;
    let todo: Vec<u64> = (0..n as u64)
        .map(|i| first_seed + i)
        .filter(|s| !done.contains_key(s))
        .collect();
    observer.phase("coverage sets", Some(n as u64));
    observer.resumed((n - todo.len()) as u64);
    let fresh: Vec<SetCoverage> = todo
        .par_iter()
        .map(|&seed| {
            let r = run_set(dir, seed, s);
            let line = serde_json::to_string(&r).expect("plain values") + "\n";
            {
                let mut f = file.lock().expect("results lock");
                f.write_all(line.as_bytes())
                    .and_then(|_| f.flush())
                    .map_err(|e| Error::io(&path, e))?;
            }
            observer.advance(1);
            observer.note(&format!(
                "{} {} {}: factor {:.2} (predictions {:.2}), {:.1} s{}",
                r.name,
                r.family,
                r.sampling,
                r.factor,
                r.prediction_factor,
                r.wall_s,
                r.error
                    .as_deref()
                    .map(|e| format!(" error: {e}"))
                    .unwrap_or_default()
            ));
            Ok(r)
        })
        .collect::<Result<_>>()?;
    let mut all = done;
    for r in fresh {
        all.insert(r.seed, r);
    }
    Ok(all
        .into_values()
        .filter(|r| r.seed >= first_seed && r.seed < first_seed + n as u64)
        .collect())
}

/// Covered count and total of one column.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Count {
    pub covered: usize,
    pub n: usize,
}

impl Count {
    fn add(&mut self, hit: bool) {
        self.n += 1;
        self.covered += usize::from(hit);
    }
    /// Covered fraction (NaN for none).
    pub fn rate(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            self.covered as f64 / self.n as f64
        }
    }
}

/// The coverage table of one quantity.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Row {
    pub quantity: String,
    /// Sets where it is classified identifiable (calibrated), and all sets.
    pub identifiable: usize,
    pub sets: usize,
    /// 95 % and 68 %, calibrated, over the identifiable sets.
    pub cal95: Count,
    pub cal68: Count,
    /// 95 % and 68 %, plain χ², over the sets identifiable under χ².
    pub chi95: Count,
    pub chi68: Count,
    /// 95 % calibrated over all sets (open sides at the bound).
    pub cal95_all: Count,
    /// Wald 95 % over the identifiable sets.
    pub wald95: Count,
    /// Bootstrap percentile 95 % (rupture time only).
    pub boot95: Count,
    /// Prediction interval of a new test (rupture time only).
    pub pred95: Count,
}

/// The coverage table: one row per constant and one for the rupture time.
pub fn table(results: &[SetCoverage]) -> Vec<Row> {
    let mut rows: Vec<Row> = Vec::new();
    let ok: Vec<&SetCoverage> = results.iter().filter(|r| r.error.is_none()).collect();
    if let Some(first) = ok.iter().find(|r| !r.constants.is_empty()) {
        for (j, c0) in first.constants.iter().enumerate() {
            let mut row = Row {
                quantity: c0.name.clone(),
                ..Row::default()
            };
            for r in &ok {
                let Some(c) = r.constants.get(j) else {
                    continue;
                };
                row.sets += 1;
                row.cal95_all.add(covers(c.cal95, c.truth));
                if c.class == Class::Identifiable {
                    row.identifiable += 1;
                    row.cal95.add(covers(c.cal95, c.truth));
                    row.cal68.add(covers(c.cal68, c.truth));
                    row.wald95.add(covers(c.wald95, c.truth));
                }
                if c.class_chi2 == Class::Identifiable {
                    row.chi95.add(covers(c.chi95, c.truth));
                    row.chi68.add(covers(c.chi68, c.truth));
                }
            }
            rows.push(row);
        }
    }
    let mut row = Row {
        quantity: "rupture time at the untested stress".into(),
        ..Row::default()
    };
    for r in &ok {
        let Some(rc) = &r.rupture else { continue };
        row.sets += 1;
        row.cal95_all.add(covers(rc.cal95, rc.truth_h));
        if !rc.open {
            row.identifiable += 1;
            row.cal95.add(covers(rc.cal95, rc.truth_h));
            row.cal68.add(covers(rc.cal68, rc.truth_h));
            row.chi95.add(covers(rc.chi95, rc.truth_h));
            row.chi68.add(covers(rc.chi68, rc.truth_h));
            row.wald95.add(covers(rc.wald95, rc.truth_h));
            if rc.boot95.0.is_finite() {
                row.boot95.add(covers(rc.boot95, rc.truth_h));
            }
            row.pred95.add(covers(rc.pred95, rc.new_test_h));
        }
    }
    rows.push(row);
    rows
}

/// The band's pointwise coverage over the sets: all points, and by band time (k of n, the
/// fraction k/n of the predicted rupture time), with the misses on each side, and the sets
/// whose whole band holds the truth's curve.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BandRow {
    /// The band time's index (1-based) and the number of band times; 0 for all points.
    pub k: usize,
    pub of: usize,
    pub covered: Count,
    pub below: usize,
    pub above: usize,
}

/// [`BandRow`]s of `results`, the first over all points, then one per band time; and the
/// count of sets whose every band point covers.
pub fn band_table(results: &[SetCoverage]) -> (Vec<BandRow>, Count) {
    let ok: Vec<&SetCoverage> = results
        .iter()
        .filter(|r| r.error.is_none() && !r.band.is_empty())
        .collect();
    let n = ok.iter().map(|r| r.band.len()).max().unwrap_or(0);
    let mut rows: Vec<BandRow> = (0..=n)
        .map(|k| BandRow {
            k,
            of: n,
            ..BandRow::default()
        })
        .collect();
    let mut whole = Count::default();
    for r in &ok {
        let mut all = true;
        for (k, b) in r.band.iter().enumerate() {
            let hit = b.hit();
            all &= hit == BandHit::Covered;
            for row in [0, k + 1] {
                let row = &mut rows[row];
                row.covered.add(hit == BandHit::Covered);
                row.below += usize::from(hit == BandHit::Below);
                row.above += usize::from(hit == BandHit::Above);
            }
        }
        whole.add(all);
    }
    (rows, whole)
}

/// How often the shipped 95 % interval of the rupture time at the untested stress
/// ([`RuptureCoverage::shipped95`]) holds the truth, over the sets where it was measured and
/// the calibrated interval is closed.
pub fn shipped_rupture(results: &[SetCoverage]) -> Count {
    let mut c = Count::default();
    for rc in results
        .iter()
        .filter(|r| r.error.is_none())
        .filter_map(|r| r.rupture.as_ref())
        .filter(|rc| !rc.open && rc.shipped95.0.is_finite())
    {
        c.add(covers(rc.shipped95, rc.truth_h));
    }
    c
}

/// [`band_table`] as Markdown.
pub fn band_md(results: &[SetCoverage]) -> String {
    let (rows, whole) = band_table(results);
    if whole.n == 0 {
        return String::new();
    }
    let mut md = String::from(
        "| band time (fraction of the predicted rupture time) | points | 95 % band holds the truth | truth below | truth above (or ruptured) |\n|---|---|---|---|---|\n",
    );
    for r in &rows {
        let what = if r.k == 0 {
            "all".to_string()
        } else {
            format!("{}/{}", r.k, r.of)
        };
        md += &format!(
            "| {} | {} | {:.1} % ({}/{}) | {} | {} |\n",
            what,
            r.covered.n,
            100.0 * r.covered.rate(),
            r.covered.covered,
            r.covered.n,
            r.below,
            r.above
        );
    }
    md += &format!(
        "\nWhole band (every time of a set covered): {:.1} % ({}/{}).\n",
        100.0 * whole.rate(),
        whole.covered,
        whole.n
    );
    let s = shipped_rupture(results);
    if s.n > 0 {
        md += &format!(
            "The rupture time's 95 % interval as shipped (spanning the members of the three quantities' searches): {:.1} % ({}/{}).\n",
            100.0 * s.rate(),
            s.covered,
            s.n
        );
    }
    md
}

/// The table as Markdown.
pub fn table_md(rows: &[Row]) -> String {
    let pct = |c: &Count| {
        if c.n == 0 {
            "—".to_string()
        } else {
            format!("{:.1} % ({}/{})", 100.0 * c.rate(), c.covered, c.n)
        }
    };
    let mut md = String::from(
        "| quantity | identifiable / sets | 95 % (shipped) | 68 % (shipped) | 95 % plain χ² | 68 % plain χ² | 95 % Wald | 95 % all sets (open = bound) | 95 % bootstrap | 95 % new test |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        md += &format!(
            "| {} | {}/{} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.quantity,
            r.identifiable,
            r.sets,
            pct(&r.cal95),
            pct(&r.cal68),
            pct(&r.chi95),
            pct(&r.chi68),
            pct(&r.wald95),
            pct(&r.cal95_all),
            pct(&r.boot95),
            pct(&r.pred95)
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_result_with_nan_round_trips_through_json() {
        let r = RuptureCoverage {
            stress_mpa: 80.0,
            truth_h: 1.0,
            value_h: 1.0,
            cal95: (0.5, 2.0),
            cal68: (0.8, 1.2),
            chi95: (0.5, 2.0),
            chi68: (0.8, 1.2),
            wald95: (f64::NAN, f64::INFINITY),
            boot95: (f64::NAN, f64::NAN),
            pred95: (0.4, 2.5),
            new_test_h: 1.1,
            open: false,
            shipped95: (0.5, 2.0),
            statistic: Some(TruthStatistic {
                t_truth: f64::NAN,
                t_replicates: vec![0.5, 2.25],
                t68: 1.0,
                t95: 4.1,
            }),
        };
        let text = serde_json::to_string(&r).unwrap();
        let back: RuptureCoverage = serde_json::from_str(&text).unwrap();
        assert!(back.boot95.0.is_nan() && back.wald95.1.is_nan());
        assert_eq!(back.cal95, r.cal95);
        let st = back.statistic.unwrap();
        assert!(st.t_truth.is_nan());
        assert_eq!((st.t_replicates, st.t95), (vec![0.5, 2.25], 4.1));
        assert!(covers(back.cal95, 1.0) && !covers(back.boot95, 1.0));
    }

    #[test]
    fn a_band_point_covers_as_a_table() {
        let b = |truth: f64, truth_ruptured, lo, hi: f64, hi_r| BandCoverage {
            time_h: 1.0,
            truth_pct: truth,
            truth_ruptured,
            lo95_pct: lo,
            hi95_pct: hi,
            hi95_ruptured: hi_r,
        };
        let nan = f64::NAN;
        for (p, want) in [
            (b(2.0, false, 1.0, 3.0, false), BandHit::Covered),
            (b(1.0, false, 1.0, 3.0, false), BandHit::Covered),
            (b(0.5, false, 1.0, 3.0, false), BandHit::Below),
            (b(3.5, false, 1.0, 3.0, false), BandHit::Above),
            // An upper end that is rupture holds any strain above the lower end.
            (b(50.0, false, 1.0, nan, true), BandHit::Covered),
            (b(0.5, false, 1.0, nan, true), BandHit::Below),
            // A truth ruptured by then: covered only where the band allows rupture.
            (b(nan, true, 1.0, nan, true), BandHit::Covered),
            (b(nan, true, 1.0, 3.0, false), BandHit::Above),
            // A NaN end is no end that holds the truth.
            (b(2.0, false, nan, 3.0, false), BandHit::Below),
        ] {
            assert_eq!(p.hit(), want, "{p:?}");
        }
        let set = |band: Vec<BandCoverage>| SetCoverage {
            band,
            ..SetCoverage::unmeasured("s".into(), 1)
        };
        let (rows, whole) = band_table(&[
            set(vec![
                b(2.0, false, 1.0, 3.0, false),
                b(0.5, false, 1.0, 3.0, false),
            ]),
            set(vec![
                b(2.0, false, 1.0, 3.0, false),
                b(nan, true, 1.0, nan, true),
            ]),
        ]);
        assert_eq!(rows.len(), 3);
        assert_eq!((rows[0].covered.covered, rows[0].covered.n), (3, 4));
        assert_eq!((rows[0].below, rows[0].above), (1, 0));
        assert_eq!((rows[1].covered.covered, rows[2].covered.covered), (2, 1));
        assert_eq!((whole.covered, whole.n), (1, 2));
        // A record written before the band was measured reads with an empty band.
        let mut v = serde_json::to_value(set(vec![])).unwrap();
        v.as_object_mut().unwrap().remove("band");
        let back: SetCoverage = serde_json::from_value(v).unwrap();
        assert!(back.band.is_empty());
    }
}
