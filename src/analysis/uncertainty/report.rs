//! `creepfit profile`: the whole computation on a configuration's data ([`run`]) and its
//! outputs ([`write_outputs`]): `intervals.csv`, `profiles.csv`, `summary.json`, `report.md`
//! and a `profile_<constant>.png` per constant.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use serde_json::json;

use super::calibrate::{bartlett, Calibration};
use super::combos::{well_determined, Combination};
use super::predict::{prediction_band, prediction_intervals, BandPoint, PredictedInterval};
use super::profile::{profile_constants, wald_se, ConstantProfile};
use super::{fit_reference, reference_from, starts, Context, Reference, Thresholds};
use crate::config::{LikelihoodSetup, ProfileConfig, RunConfig};
use crate::data::Dataset;
use crate::error::Result;
use crate::model::guess::initial_guess;
use crate::model::{Load, Scale};
use crate::progress::Hooks;
use crate::report::plot::{plot_profile, ProfilePlot};
use crate::report::tables::{jnum, num, write_csv, write_text};

/// How many times the profiles are redone from a better optimum found on a profile.
pub const MAX_RESTARTS: usize = 3;

/// Predictions at one untested load.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadPrediction {
    /// Temperature (°C) and stress (MPa).
    pub temperature_c: f64,
    pub stress_mpa: f64,
    /// Where the load lies against the tested conditions.
    pub extrapolation: crate::baseline::Extrapolation,
    /// How the simulation at the optimum ended (`ruptured`, else why the quantities and the
    /// band are missing).
    pub outcome: &'static str,
    /// Rupture time, minimum rate, rupture strain with their intervals.
    pub quantities: Vec<PredictedInterval>,
    /// The 95 % band of the predicted curve.
    pub band: Vec<BandPoint>,
    /// The thresholds of Δ(−2 ln L) of these intervals and the band (the rupture time's at
    /// this load).
    pub thresholds: Thresholds,
}

/// Wall times of the phases, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timings {
    pub fit: f64,
    pub calibration: f64,
    pub profiles: f64,
    pub combinations: f64,
    /// Prediction phase: the intervals of rupture time, minimum rate and rupture strain (all
    /// loads), and the bands.
    pub predictions: f64,
    pub prediction_intervals: f64,
    pub bands: f64,
    pub total: f64,
}

/// Everything `creepfit profile` computes.
#[derive(Debug, Clone)]
pub struct ProfileRun {
    /// The maximum-likelihood optimum the profiles are measured from.
    pub reference: Reference,
    /// How the reference was found: `multistart` or `constants` (a local fit from given
    /// constants), and −2 ln L at the given constants for the latter.
    pub reference_from: String,
    pub given_neg2ll: Option<f64>,
    /// Whether the reference was refitted without the specimen factors `auto` chose, their
    /// scatter beyond the stress trend zero ([`Core::without_specimens`]).
    pub without_specimens: bool,
    /// The given constants the reference was refitted from (`--constants`), model order.
    pub given: Option<Vec<f64>>,
    /// The thresholds of the constants' (and combinations') intervals, those of the
    /// predictions' intervals, and the calibration behind them.
    pub thresholds: Thresholds,
    pub prediction_thresholds: Thresholds,
    pub calibration: Option<Calibration>,
    /// Profiles of every constant, model order.
    pub profiles: Vec<ConstantProfile>,
    /// Well-determined combinations.
    pub combinations: Vec<Combination>,
    /// Predictions at the configured untested stresses.
    pub predictions: Vec<LoadPrediction>,
    /// Times the profiles were redone from a better optimum found on them.
    pub restarts: usize,
    pub timings: Timings,
}

/// The context of a likelihood setup and its data.
pub fn context<'a>(
    setup: &LikelihoodSetup,
    model: &'a dyn crate::model::Model,
    data: &'a Dataset,
) -> Context<'a> {
    Context {
        auto_effects: setup.auto_effects,
        ..Context::new(
            model,
            &data.curves,
            setup.space.clone(),
            setup.settings,
            setup.ml,
        )
    }
}

/// −2 ln L at constants `x`, the error model estimated there (None where the model cannot
/// be evaluated); with specimen effects the hierarchical fit's with every constant held at
/// `x` (the specimens' effects and scatter fitted).
pub fn neg2ll_at(ctx: &Context, x: &[f64]) -> Option<f64> {
    if ctx.hierarchical() {
        let all: Vec<usize> = (0..ctx.space.len()).collect();
        let f = ctx.fit_row(&ctx.space, x, false, &all, None);
        return f.ok().then_some(f.neg2ll);
    }
    crate::likelihood::residuals_at(ctx.model, ctx.curves, x, &ctx.settings)
        .ok()
        .map(|r| crate::errmodel::ErrorModel::estimate(&r, ctx.ml.lifetime_sd_floor).neg2ll(&r))
        .filter(|v| v.is_finite())
}

/// The untested loads of `pc` at the data's temperature.
pub fn loads(cfg: &RunConfig, data: &Dataset, pc: &ProfileConfig) -> Vec<(f64, Load)> {
    let t = cfg
        .temperature_c
        .or_else(|| data.curves.first().map(|c| c.temperature_c))
        .unwrap_or(f64::NAN);
    pc.predict_stress_mpa
        .iter()
        .map(|&s| (t, Load::new(s, t, cfg.objective.omega_f)))
        .collect()
}

/// Constants that look identifiable by the Wald approximation (the estimate ± 1.96 Wald
/// standard errors inside the box): the ones whose likelihood-ratio statistic calibrates the
/// thresholds (a constant on a bound or in a flat direction has no χ²₁ statistic).
pub fn calibration_constants(ctx: &Context, reference: &Reference) -> Vec<usize> {
    let se = wald_se(ctx, reference);
    (0..ctx.space.len())
        .filter(|&j| {
            let u = ctx.space.to_unit_one(j, reference.params[j]);
            u - 1.96 * se[j] > 0.0 && u + 1.96 * se[j] < 1.0
        })
        .collect()
}

/// The reference, the thresholds and the profiles of every constant (see [`run`]).
#[derive(Debug, Clone)]
pub struct Core {
    /// Whether the analyses went on without the specimen factors `auto` chose (their
    /// scatter beyond the stress trend zero at the reference,
    /// [`Context::settles_without_specimens`]): the reference was refitted without them and
    /// every profile is of the plain likelihood; the caller goes on with
    /// [`Context::without_specimens`].
    pub without_specimens: bool,
    pub reference: Reference,
    pub reference_from: String,
    pub given_neg2ll: Option<f64>,
    /// The pooled thresholds of the constants and of the predictions
    /// ([`Calibration::constants_pooled`]); each profile carries its own.
    pub thresholds: Thresholds,
    pub prediction_thresholds: Thresholds,
    /// The thresholds of the predictions at each load (in the order given): its rupture
    /// time's own.
    pub load_thresholds: Vec<Thresholds>,
    pub calibration: Option<Calibration>,
    pub profiles: Vec<ConstantProfile>,
    pub restarts: usize,
    pub timings: Timings,
}

/// The reference (a multistart, or a local fit from `given`), the calibration of the
/// thresholds (over the constants of [`calibration_constants`] and the rupture time at every
/// load of `loads`), and the profiles of every constant, redone from a better optimum if one
/// turns up on them (at most [`MAX_RESTARTS`] times). The phases are told to
/// `hooks.observer`; the calibration replicates and the profile sides are journaled in
/// `hooks.journal` and resumed from it ([`bartlett`], [`profile_constants`]).
pub fn core(
    ctx: &Context,
    cfg: &RunConfig,
    given: Option<&[f64]>,
    pc: &ProfileConfig,
    loads: &[Load],
    hooks: &Hooks,
) -> Result<Core> {
    let t0 = Instant::now();
    hooks.observer.phase("maximum-likelihood fit", None);
    let (mut reference, from, given_neg2ll) = match given {
        Some(x) => {
            let f = ctx.fit(&ctx.space, x, false);
            (
                reference_from(ctx, vec![f])?,
                "constants".to_string(),
                neg2ll_at(ctx, x),
            )
        }
        None => {
            let guess = initial_guess(
                ctx.model,
                ctx.curves,
                &ctx.space,
                ctx.settings.omega_f,
                &ctx.settings.ode,
            );
            let mut given: Vec<Vec<f64>> = vec![guess.params];
            if let Some(s) = cfg.starts_all_given() {
                given.insert(0, s);
            }
            let st = starts(ctx, &given, pc.starts, pc.seed);
            (fit_reference(ctx, &st)?, "multistart".to_string(), None)
        }
    };
    // Every kind's scatter at zero beyond the stress trend: the reference again without the
    // specimen factors, from the same starts, and everything after on the plain likelihood.
    let plain;
    let without_specimens = ctx.settles_without_specimens(&reference);
    let ctx = if without_specimens {
        plain = ctx.without_specimens();
        reference = match given {
            Some(x) => reference_from(&plain, vec![plain.fit(&plain.space, x, false)])?,
            None => {
                let guess = initial_guess(
                    plain.model,
                    plain.curves,
                    &plain.space,
                    plain.settings.omega_f,
                    &plain.settings.ode,
                );
                let mut given: Vec<Vec<f64>> = vec![guess.params];
                if let Some(s) = cfg.starts_all_given() {
                    given.insert(0, s);
                }
                let st = starts(&plain, &given, pc.starts, pc.seed);
                fit_reference(&plain, &st)?
            }
        };
        &plain
    } else {
        ctx
    };
    let given_neg2ll = match (without_specimens, given) {
        (true, Some(x)) => neg2ll_at(ctx, x),
        _ => given_neg2ll,
    };
    let mut timings = Timings {
        fit: t0.elapsed().as_secs_f64(),
        ..Timings::default()
    };
    let mut restarts = 0;
    loop {
        let t1 = Instant::now();
        let (th, cal) = if pc.calibrate > 0 {
            let cons = calibration_constants(ctx, &reference);
            let qs = super::calibrate::rupture_time_quantities(loads);
            let cal = bartlett(ctx, &reference, &cons, &qs, pc.calibrate, pc.seed, hooks)?;
            (
                (
                    cal.constants_pooled,
                    cal.predictions_pooled,
                    cal.constant_thresholds.clone(),
                    cal.prediction_thresholds.clone(),
                ),
                Some(cal),
            )
        } else {
            let chi2 = Thresholds::chi2(1.0);
            (
                (
                    chi2,
                    chi2,
                    vec![chi2; ctx.space.len()],
                    vec![chi2; loads.len()],
                ),
                None,
            )
        };
        let (th, pth, cth, lth) = th;
        timings.calibration += t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let all: Vec<usize> = (0..ctx.space.len()).collect();
        let profiles = profile_constants(ctx, &reference, &all, &cth, hooks)?;
        timings.profiles += t2.elapsed().as_secs_f64();
        let better = profiles
            .iter()
            .filter_map(|p| p.better())
            .min_by(|a, b| a.delta.total_cmp(&b.delta))
            .cloned();
        match better {
            Some(p) if restarts < MAX_RESTARTS => {
                restarts += 1;
                hooks.observer.phase("refit from a better optimum", None);
                let fits = vec![
                    ctx.fit(&ctx.space, &p.params, false),
                    ctx.fit(&ctx.space, &p.params, true),
                ];
                let mut r = reference_from(ctx, fits)?;
                r.basins = reference.basins.clone();
                r.basins.insert(0, reference.params.clone());
                reference = r;
            }
            _ => {
                return Ok(Core {
                    without_specimens,
                    reference,
                    reference_from: from,
                    given_neg2ll,
                    thresholds: th,
                    prediction_thresholds: pth,
                    load_thresholds: lth,
                    calibration: cal,
                    profiles,
                    restarts,
                    timings,
                })
            }
        }
    }
}

/// The whole computation: [`core`](fn@core), the well-determined combinations and the predictions at
/// the configured untested stresses.
pub fn run(
    cfg: &RunConfig,
    data: &Dataset,
    given: Option<&[f64]>,
    pc: &ProfileConfig,
) -> Result<ProfileRun> {
    run_observed(cfg, data, given, pc, &Hooks::default())
}

/// [`run`] telling `hooks.observer` of its phases and steps, its calibration replicates and
/// profile sides journaled in `hooks.journal` and resumed from it ([`core`](fn@core)).
pub fn run_observed(
    cfg: &RunConfig,
    data: &Dataset,
    given: Option<&[f64]>,
    pc: &ProfileConfig,
    hooks: &Hooks,
) -> Result<ProfileRun> {
    let t0 = Instant::now();
    let model = cfg.build_model()?;
    let ctx = context(&cfg.likelihood_setup(data), model.as_ref(), data);
    let loads = loads(cfg, data, pc);
    let only: Vec<Load> = loads.iter().map(|l| l.1).collect();
    let c = core(&ctx, cfg, given, pc, &only, hooks)?;
    let ctx = if c.without_specimens {
        ctx.without_specimens()
    } else {
        ctx
    };
    let (reference, thresholds, pth, mut timings) = (
        c.reference,
        c.thresholds,
        c.prediction_thresholds,
        c.timings,
    );
    let t3 = Instant::now();
    hooks.observer.phase("combinations", None);
    let combinations = well_determined(&ctx, &reference, &c.profiles, &thresholds, 3);
    timings.combinations = t3.elapsed().as_secs_f64();
    let t4 = Instant::now();
    let fractions = super::predict::band_fractions(pc.band_points);
    let mut predictions = Vec::with_capacity(loads.len());
    let tested = crate::baseline::Tested::of(data, cfg.has_laws());
    let ode = crate::uncertainty::constrained::prediction_ode(&ctx);
    if !loads.is_empty() {
        hooks.phase("predictions", loads.len());
    }
    let scatter = super::predict::specimen_scatter_for(&ctx, &reference, loads.len());
    for ((t, l), pth) in loads.iter().zip(&c.load_thresholds) {
        hooks.check("predictions")?;
        let condition = crate::data::Condition {
            temperature_c: *t,
            stress_mpa: l.stress_mpa,
        };
        let outcome = ctx
            .model
            .simulate(&reference.params, l, &[], &mut [], &ode)
            .outcome
            .as_str();
        let ti = Instant::now();
        let li = prediction_intervals(&ctx, &reference, l, pth, &scatter);
        timings.prediction_intervals += ti.elapsed().as_secs_f64();
        let tb = Instant::now();
        let band = prediction_band(
            &ctx,
            &reference,
            l,
            &fractions,
            pth,
            super::predict::rupture_lo95(&li.quantities),
            &li.members,
        );
        let quantities = li.quantities;
        timings.bands += tb.elapsed().as_secs_f64();
        predictions.push(LoadPrediction {
            temperature_c: *t,
            stress_mpa: l.stress_mpa,
            extrapolation: tested
                .classify(condition)
                .unwrap_or(crate::baseline::Extrapolation::Both),
            outcome,
            quantities,
            band,
            thresholds: *pth,
        });
        hooks.step();
    }
    timings.predictions = t4.elapsed().as_secs_f64();
    timings.total = t0.elapsed().as_secs_f64();
    Ok(ProfileRun {
        reference,
        reference_from: c.reference_from,
        given_neg2ll: c.given_neg2ll,
        without_specimens: c.without_specimens,
        given: given.map(<[f64]>::to_vec),
        thresholds,
        prediction_thresholds: pth,
        calibration: c.calibration,
        profiles: c.profiles,
        combinations,
        predictions,
        restarts: c.restarts,
        timings,
    })
}

/// The x coordinate a constant's profile is shown in: log10 of the value for a log-scale
/// constant, else the value.
fn shown(scale: Scale, v: f64) -> f64 {
    match scale {
        Scale::Log => v.log10(),
        Scale::Linear => v,
    }
}

/// `intervals.csv`'s columns: the contract's, then where `value` comes from
/// (`ml_multistart`, or `ml_refit` from the given constants), the given constant and whether
/// it lies inside the 95 % interval (both empty without `--constants`), and the thresholds of
/// Δ(−2 ln L) the constant's 68 % and 95 % intervals were read at (each constant its own).
pub const INTERVAL_HEADER: [&str; 12] = [
    "name",
    "value",
    "lo68",
    "hi68",
    "lo95",
    "hi95",
    "class",
    "value_source",
    "given_value",
    "given_in95",
    "t68",
    "t95",
];

impl ProfileRun {
    /// Where the reference (every `value`) comes from, as written in `intervals.csv`.
    pub fn value_source(&self) -> &'static str {
        if self.given.is_some() {
            "ml_refit"
        } else {
            "ml_multistart"
        }
    }
}

/// `intervals.csv` rows ([`INTERVAL_HEADER`]).
pub fn interval_rows(run: &ProfileRun) -> Vec<Vec<String>> {
    run.profiles
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let i = &p.interval;
            let given = run.given.as_ref().map(|g| g[j]);
            vec![
                p.name.clone(),
                num(i.value),
                num(i.lo68),
                num(i.hi68),
                num(i.lo95),
                num(i.hi95),
                p.class.as_str().to_string(),
                run.value_source().to_string(),
                given.map_or(String::new(), num),
                given.map_or(String::new(), |g| (i.lo95 <= g && g <= i.hi95).to_string()),
                num(p.thresholds.t68),
                num(p.thresholds.t95),
            ]
        })
        .collect()
}

/// `profiles.csv`: every profile point, the optimum included, with the other constants (the
/// header, then the rows).
pub fn profiles_table(cfg: &RunConfig, run: &ProfileRun) -> (Vec<String>, Vec<Vec<String>>) {
    let names: Vec<String> = cfg.constants.iter().map(|c| c.name.clone()).collect();
    let mut header: Vec<String> = [
        "name",
        "side",
        "value",
        "delta_neg2ll",
        "status",
        "fits",
        "termination",
    ]
    .map(String::from)
    .to_vec();
    header.extend(names);
    let mut rows = Vec::new();
    for p in &run.profiles {
        let mut opt = vec![
            p.name.clone(),
            "optimum".into(),
            num(p.interval.value),
            num(0.0),
            "ok".into(),
            "0".into(),
            String::new(),
        ];
        opt.extend(run.reference.params.iter().map(|v| num(*v)));
        rows.push(opt);
        for (side, s) in [("lower", &p.lower), ("upper", &p.upper)] {
            for q in &s.points {
                let status = if !q.delta.is_finite() {
                    "failed"
                } else if q.retried {
                    "retried"
                } else {
                    "ok"
                };
                let mut row = vec![
                    p.name.clone(),
                    side.into(),
                    num(q.value),
                    if q.delta.is_finite() {
                        num(q.delta)
                    } else {
                        String::new()
                    },
                    status.into(),
                    q.fits.to_string(),
                    q.termination.as_str().into(),
                ];
                row.extend(q.params.iter().map(|v| num(*v)));
                rows.push(row);
            }
        }
    }
    (header, rows)
}

/// Write every output of `creepfit profile` into `out`; plots last. Returns the plots that
/// could not be written.
pub fn write_outputs(cfg: &RunConfig, run: &ProfileRun, out: &Path) -> Result<Vec<String>> {
    write_csv(
        &out.join("intervals.csv"),
        &INTERVAL_HEADER,
        &interval_rows(run),
    )?;
    let (header, rows) = profiles_table(cfg, run);
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_csv(&out.join("profiles.csv"), &header, &rows)?;
    write_text(
        &out.join("summary.json"),
        &serde_json::to_string_pretty(&summary(cfg, run)).expect("JSON of plain values"),
    )?;
    write_text(&out.join("report.md"), &report_md(cfg, run))?;
    let mut failures = Vec::new();
    for (j, p) in run.profiles.iter().enumerate() {
        let scale = cfg.constants[j].scale;
        let unit = cfg.constants[j].unit;
        let x = |v: f64| shown(scale, v);
        let pts: Vec<(f64, f64)> = p
            .lower
            .points
            .iter()
            .chain(&p.upper.points)
            .filter(|q| q.delta.is_finite())
            .map(|q| (x(q.value), q.delta))
            .chain(std::iter::once((x(p.interval.value), 0.0)))
            .collect();
        let failed: Vec<f64> = p
            .lower
            .points
            .iter()
            .chain(&p.upper.points)
            .filter(|q| !q.delta.is_finite())
            .map(|q| x(q.value))
            .collect();
        let th = p.thresholds;
        let plot = ProfilePlot {
            x_label: match scale {
                Scale::Log => format!("log10 {} ({} in {unit})", p.name, p.name),
                Scale::Linear => format!("{} ({unit})", p.name),
            },
            points: pts,
            failed,
            estimate: x(p.interval.value),
            bounds: (x(p.lb), x(p.ub)),
            thresholds: vec![
                (format!("68 % threshold {:.2}", th.t68), th.t68),
                (format!("95 % threshold {:.2}", th.t95), th.t95),
            ],
        };
        let path = out.join(format!("profile_{}.png", p.name));
        if let Err(e) = plot_profile(
            &path,
            &format!(
                "{}: profile likelihood of {} ({})",
                cfg.name,
                p.name,
                p.class.as_str()
            ),
            &plot,
        ) {
            failures.push(e.to_string());
        }
    }
    Ok(failures)
}

/// `summary.json`.
pub fn summary(cfg: &RunConfig, run: &ProfileRun) -> serde_json::Value {
    let r = &run.reference;
    let names: Vec<String> = cfg.constants.iter().map(|c| c.name.clone()).collect();
    let constants: Vec<serde_json::Value> = run
        .profiles
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "value": jnum(p.interval.value),
                "lo68": jnum(p.interval.lo68),
                "hi68": jnum(p.interval.hi68),
                "lo95": jnum(p.interval.lo95),
                "hi95": jnum(p.interval.hi95),
                "class": p.class,
                "t68": jnum(p.thresholds.t68),
                "t95": jnum(p.thresholds.t95),
                "open": p.open.iter().map(|o| json!({
                    "side": o.side,
                    "end": o.end,
                    "limit": jnum(o.limit),
                    "max_delta": jnum(o.max_delta),
                })).collect::<Vec<_>>(),
                "lb": jnum(p.lb),
                "ub": jnum(p.ub),
                "wald_se_unit": jnum(p.wald_se_unit),
                "points": p.lower.points.len() + p.upper.points.len(),
                "fits": p.fits(),
                "failed_points": p.lower.failed_points() + p.upper.failed_points(),
                "retried_points": p.lower.retried_points() + p.upper.retried_points(),
                "lower_end": p.lower.end,
                "upper_end": p.upper.end,
            })
        })
        .collect();
    json!({
        "name": cfg.name,
        "model": cfg.model_name(),
        "data_hash": cfg.data_hash,
        "reference": {
            "from": run.reference_from,
            "without_specimen_factors": run.without_specimens,
            "neg2ll": jnum(r.neg2ll),
            "given_neg2ll": run.given_neg2ll.map(jnum),
            "delta_neg2ll_given": run.given_neg2ll.map(|g| jnum(g - r.neg2ll)),
            "given_constants": run.given.as_ref().map(|g| names.iter().zip(g).zip(&r.params).zip(&run.profiles).map(|(((n, g), v), p)| json!({
                "name": n,
                "given": jnum(*g),
                "value": jnum(*v),
                "difference": jnum(v - g),
                "relative_difference_pct": jnum(100.0 * (v - g) / g.abs()),
                "given_in95": p.interval.lo95 <= *g && *g <= p.interval.hi95,
            })).collect::<Vec<_>>()),
            "constants": names.iter().zip(&r.params).map(|(n, v)| json!({"name": n, "value": jnum(*v)})).collect::<Vec<_>>(),
            "fits": r.fits,
            "failed_fits": r.failed,
            "other_optima": r.basins.len(),
            "strain_sd_pct": r.noise.strain.iter().map(|p| jnum(100.0 * p.marginal_sd())).collect::<Vec<_>>(),
            "phi": r.noise.strain.iter().map(|p| jnum(p.phi)).collect::<Vec<_>>(),
            "lifetime_sd_pct": jnum(100.0 * r.noise.lifetime_sd),
            "specimen_effects": r.specimen.as_ref().map(|sp| sp.kinds.iter().zip(&sp.scatter).map(|(k, t)| json!({
                "kind": k,
                "scatter": jnum(*t),
            })).collect::<Vec<_>>()),
        },
        "thresholds": {
            "t68": jnum(run.thresholds.t68),
            "t95": jnum(run.thresholds.t95),
            "factor": jnum(run.thresholds.factor),
            "prediction_t68": jnum(run.prediction_thresholds.t68),
            "prediction_t95": jnum(run.prediction_thresholds.t95),
            "prediction_factor": jnum(run.prediction_thresholds.factor),
            "chi2_t68": 1.0,
            "chi2_t95": jnum(super::chi2_1(0.95)),
        },
        "calibration": run.calibration,
        "restarts": run.restarts,
        "constants": constants,
        "combinations": run.combinations,
        "predictions": run.predictions,
        "settings": cfg.profile,
    })
}

fn g(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.4e}")
    } else {
        format!("{v:.5}")
    }
}

/// `report.md`.
pub fn report_md(cfg: &RunConfig, run: &ProfileRun) -> String {
    let th = run.thresholds;
    let mut md = format!("# How sure: {}\n\n", cfg.name);
    md += &format!(
        "Maximum-likelihood optimum ({}) at −2 ln L = {:.3}; the error model re-estimated at every profile point (AR(1) reading error per curve; rupture-time scatter {:.2} %).\n\n",
        if run.reference_from == "multistart" {
            format!("multistart, {} fits", run.reference.fits)
        } else {
            "a maximum-likelihood REFIT from the given constants: every value and interval below is about the refit, not the given constants".to_string()
        },
        run.reference.neg2ll,
        100.0 * run.reference.noise.lifetime_sd
    );
    if let Some(sp) = &run.reference.specimen {
        md += &format!(
            "Specimen effects: every fit (the optimum, each profile point, each bootstrap replicate's) integrates each specimen's {} out (Laplace), the scatter between specimens re-estimated with it; at the optimum {}. The constants and predictions are the population's (a median specimen's); a new specimen's scatter is added only to the prediction interval of a new test.\n\n",
            sp.kinds
                .iter()
                .map(|k| format!("{} factor", k.name()))
                .collect::<Vec<_>>()
                .join(" and "),
            sp.kinds
                .iter()
                .zip(&sp.scatter)
                .map(|(k, t)| format!("{} varies {:.1} % between specimens (sd of ln)", k.name(), 100.0 * t))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if let Some(given) = &run.given {
        md += &format!(
            "## The refit against the given constants\n\n−2 ln L at the given constants {}, at the refit {:.3}: difference {} (the given constants are that much less likely under the error model; the 95 % threshold of one constant is {:.3}).\n\n| constant | given | refit | difference | relative | given inside the refit's 95 % interval |\n|---|---|---|---|---|---|\n",
            run.given_neg2ll.map_or("not computable".to_string(), |v| format!("{v:.3}")),
            run.reference.neg2ll,
            run.given_neg2ll
                .map_or("unknown".to_string(), |v| format!("{:.3}", v - run.reference.neg2ll)),
            th.t95
        );
        for ((p, gv), v) in run.profiles.iter().zip(given).zip(&run.reference.params) {
            md += &format!(
                "| {} | {} | {} | {} | {:+.2} % | {} |\n",
                p.name,
                g(*gv),
                g(*v),
                g(v - gv),
                100.0 * (v - gv) / gv.abs(),
                if p.interval.lo95 <= *gv && *gv <= p.interval.hi95 {
                    "yes"
                } else {
                    "NO"
                }
            );
        }
        md += "\n";
    }
    md += &match &run.calibration {
        Some(c) => format!(
            "Thresholds of Δ(−2 ln L), each quantity its own: the mean likelihood-ratio statistic T of its true value over {} parametric-bootstrap replicates ({} failed) at the fitted values (Bartlett correction) times the quantile of F(1, replicates) (the mean is itself estimated), floored at χ²₁'s (1.000 and 3.841); each constant's in the table below, each prediction's with it. A constant on a bound or in a flat direction takes the calibrated constants' pooled thresholds, {:.3} (68 %) and {:.3} (95 %); the predictions pooled: {:.3} and {:.3}.\n\n",
            c.replicates, c.failed, th.t68, th.t95, run.prediction_thresholds.t68, run.prediction_thresholds.t95
        ),
        None => format!(
            "Thresholds of Δ(−2 ln L): the χ²₁ quantiles {:.3} (68 %) and {:.3} (95 %), not calibrated.\n\n",
            th.t68, th.t95
        ),
    };
    if run.restarts > 0 {
        md += &format!(
            "A profile found a lower −2 ln L than the first optimum: the profiles were redone {} time(s) from the better optimum.\n\n",
            run.restarts
        );
    }
    md += "## Constants\n\n| constant | value | 68 % | 95 % | thresholds (68 %, 95 %) | class | open side(s) |\n|---|---|---|---|---|---|---|\n";
    for p in &run.profiles {
        let i = &p.interval;
        let open: Vec<String> = p
            .open
            .iter()
            .map(|o| {
                format!(
                    "{} ({}, {}; Δ ≤ {:.2})",
                    o.side,
                    match o.end {
                        super::profile::SideEnd::Bound => "bound",
                        super::profile::SideEnd::Failed => "fits failed",
                        super::profile::SideEnd::PointLimit => "point limit",
                        _ => "limit",
                    },
                    g(o.limit),
                    o.max_delta
                )
            })
            .collect();
        md += &format!(
            "| {} | {} | [{}, {}] | [{}, {}] | {:.2}, {:.2} | {} | {} |\n",
            p.name,
            g(i.value),
            g(i.lo68),
            g(i.hi68),
            g(i.lo95),
            g(i.hi95),
            p.thresholds.t68,
            p.thresholds.t95,
            p.class.as_str(),
            if open.is_empty() {
                "—".to_string()
            } else {
                open.join("; ")
            }
        );
    }
    let failed: usize = run
        .profiles
        .iter()
        .map(|p| p.lower.failed_points() + p.upper.failed_points())
        .sum();
    let retried: usize = run
        .profiles
        .iter()
        .map(|p| p.lower.retried_points() + p.upper.retried_points())
        .sum();
    let fits: usize = run.profiles.iter().map(|p| p.fits()).sum();
    md += &format!(
        "\n{fits} inner fits; {retried} profile point(s) needed a retry from another start, {failed} failed from every start{}.\n\n",
        if failed > 0 { " (listed in profiles.csv as `failed`)" } else { "" }
    );
    md += "## What the data determine\n\n";
    if run.combinations.is_empty() {
        md += "No combination of two or more constants is determined markedly better than the constants themselves.\n\n";
    } else {
        md += "| combination | value | 95 % | relative half-width | narrowest member alone |\n|---|---|---|---|---|\n";
        for c in &run.combinations {
            let i = &c.interval;
            md += &format!(
                "| {} | {} | [{}, {}] | ±{:.2} % | {} |\n",
                c.expression,
                g(i.value),
                g(i.lo95),
                g(i.hi95),
                50.0 * (i.hi95 - i.lo95) / i.value,
                if c.best_single_halfwidth.is_finite() {
                    format!("±{:.1} %", 100.0 * c.best_single_halfwidth)
                } else {
                    "not identifiable".into()
                }
            );
        }
        md += "\n";
    }
    if !run.predictions.is_empty() {
        md += "## Predictions at untested loads\n\nConfidence interval: the uncertainty of the model's prediction (the constants). Prediction interval: a new test, adding the scatter between specimens.\n\n| load | quantity | prediction | 95 % confidence | 95 % prediction (new test) | specimen scatter (sd of ln) |\n|---|---|---|---|---|---|\n";
        for p in &run.predictions {
            if p.quantities.is_empty() {
                md += &format!(
                    "| {} °C, {} MPa | – | no prediction: the simulation at the optimum ended with `{}` | | | |\n",
                    p.temperature_c, p.stress_mpa, p.outcome
                );
            }
            for q in &p.quantities {
                md += &format!(
                    "| {} °C, {} MPa | {} | {} | [{}, {}]{} (threshold {:.2}) | [{}, {}] | {:.3} ({} residuals) |\n",
                    p.temperature_c,
                    p.stress_mpa,
                    q.quantity,
                    g(q.value),
                    g(q.conf_lo95),
                    g(q.conf_hi95),
                    if q.conf_lo_open || q.conf_hi_open {
                        " (open: the box limits it)"
                    } else {
                        ""
                    },
                    p.thresholds.t95,
                    g(q.pred_lo95),
                    g(q.pred_hi95),
                    q.scatter_sd,
                    q.scatter_n
                );
            }
        }
        md += "\n";
    }
    md
}

/// The run's wall times in words (printed, not in `report.md`: see `timings.json`).
pub fn timings_line(run: &ProfileRun) -> String {
    format!(
        "Wall time {:.2} s (fit {:.2}, calibration {:.2}, profiles {:.2}, combinations {:.2}, predictions {:.2}).\n",
        run.timings.total,
        run.timings.fit,
        run.timings.calibration,
        run.timings.profiles,
        run.timings.combinations,
        run.timings.predictions
    )
}

/// The run identity of `creepfit profile` on `cfg` (bound to its data) kept in its journal:
/// the configuration's ([`crate::config::identity`]), the command, the `[profile]`
/// settings and the given constants (`--constants`, exact), if any.
pub fn identity(cfg: &RunConfig, given: Option<&[f64]>) -> serde_json::Value {
    let mut id = crate::config::identity(cfg);
    id["command"] = "profile".into();
    id["profile"] = serde_json::to_value(&cfg.profile).expect("settings serialise");
    id["given_constants"] = match given {
        Some(g) => g
            .iter()
            .map(|v| crate::journal::exact::to_json(*v))
            .collect(),
        None => serde_json::Value::Null,
    };
    id
}

/// What `profile` refuses before it starts: a prediction load outside what the data tested
/// (at a temperature not tested without a temperature law).
pub fn check(cfg: &RunConfig, data: &Dataset) -> Result<()> {
    let tested = crate::baseline::Tested::of(data, cfg.has_laws());
    for (t, l) in loads(cfg, data, &cfg.profile) {
        let c = crate::data::Condition {
            temperature_c: t,
            stress_mpa: l.stress_mpa,
        };
        if let Err(why) = tested.classify(c) {
            return Err(cfg.error_at("profile.predict_stress_MPa", why));
        }
    }
    Ok(())
}
