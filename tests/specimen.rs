//! Specimen effects (random effects) of the likelihood: the Laplace approximation against a
//! brute-force integral, the scatter recovered from generated specimens, and `diagnose` on
//! generated data with specimen scatter (a null set and a hidden effect).

mod common;

use creepfit::config::{LifetimeTerm, ObjectiveKind};
use creepfit::data::{estimate_min_rate, Curve};
use creepfit::errmodel::{Ar1, ErrorModel};
use creepfit::fit::FitSettings;
use creepfit::likelihood::{
    laplace_at, ml_fit, raw_objective, restricted_design, scatter_intervals, split_residuals,
    EffectKind, EffectLayout, MlOptions, SpecimenOptions,
};
use creepfit::lsq::LmOptions;
use creepfit::model::objective::{CurveFactors, JacobianMethod, ParamSpace};
use creepfit::model::{registry, Load, Model, Scale};
use creepfit::ode::OdeOptions;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The seed steel's 560 °C constants (`creepfit fit configs/560C.toml`).
const TRUTH: [f64; 6] = [1.0e-10, 0.1749, 0.563, 5.9e4, 2.21e-5, 4.03];

/// A wide box around them.
fn space() -> ParamSpace {
    ParamSpace::new(
        vec![1e-12, 0.05, 0.2, 1e3, 1e-7, 1.0],
        vec![1e-8, 0.4, 0.9, 1e6, 1e-3, 15.0],
        vec![
            Scale::Log,
            Scale::Linear,
            Scale::Linear,
            Scale::Log,
            Scale::Log,
            Scale::Linear,
        ],
    )
}

fn settings() -> FitSettings {
    FitSettings {
        lm: LmOptions {
            max_iterations: 200,
            ftol: 1e-10,
            ..LmOptions::default()
        },
        ode: OdeOptions {
            rtol: 1e-10,
            atol: 1e-14,
            ..OdeOptions::default()
        },
        omega_f: 1.0 / 3.0,
        lifetime: LifetimeTerm::Both,
        jacobian: JacobianMethod::Sensitivity,
        kind: ObjectiveKind::Likelihood,
        lifetime_sd_floor: 0.01,
    }
}

/// One specimen's curve at `stress` (MPa): the truth with its rate × e^η and rupture strain
/// × e^ζ, `n` points evenly in time to 97 % of its life, white reading error `sd` (strain
/// fraction), its rupture time scattered by 1 %.
fn specimen(
    model: &dyn Model,
    stress: f64,
    eta: f64,
    zeta: f64,
    n: usize,
    sd: f64,
    rng: &mut ChaCha8Rng,
) -> Curve {
    specimen3(model, stress, [eta, zeta, 0.0], n, sd, rng)
}

/// [`specimen`] with a coarsening effect too: Kc × e^κ, `effects` = [η, ζ, κ].
fn specimen3(
    model: &dyn Model,
    stress: f64,
    effects: [f64; 3],
    n: usize,
    sd: f64,
    rng: &mut ChaCha8Rng,
) -> Curve {
    let [eta, zeta, kappa] = effects;
    let mut p = TRUTH.to_vec();
    p[0] *= eta.exp();
    p[5] /= zeta.exp();
    p[4] *= kappa.exp();
    let load = Load::new(stress, 560.0, 1.0 / 3.0);
    let ode = settings().ode;
    let r = model.simulate(&p, &load, &[], &mut [], &ode);
    assert!(r.ruptured());
    let times: Vec<f64> = (0..n)
        .map(|k| 0.97 * r.t_end * k as f64 / (n - 1) as f64)
        .collect();
    let mut e = vec![0.0; n];
    model.simulate(&p, &load, &times, &mut e, &ode);
    for v in e.iter_mut().skip(1) {
        let z: f64 = StandardNormal.sample(rng);
        *v += sd * z;
    }
    let z: f64 = StandardNormal.sample(rng);
    let tf = r.t_end * (0.01 * z).exp();
    Curve {
        temperature_c: 560.0,
        stress_mpa: stress,
        specimen: None,
        groups: None,
        min_rate_estimated: estimate_min_rate(&times, &e, tf),
        rupture_strain: *e.last().unwrap(),
        times_h: times,
        strains: e,
        rupture_time_h: Some(tf),
        min_rate_measured: None,
    }
}

/// −2 ln ∫ p(y | θ, η) N(η; 0, diag τ²) dη by the trapezoidal rule on a grid of ±8 τ per
/// kind (`steps` intervals each), log-sum-exp.
fn brute_force(
    model: &dyn Model,
    curves: &[Curve],
    kinds: &[(usize, f64)],
    tau: &[f64],
    noise: &ErrorModel,
    steps: usize,
) -> f64 {
    let s = settings();
    let nll = |eta: &[f64]| -> f64 {
        let f = CurveFactors {
            index: kinds.iter().map(|k| k.0).collect(),
            factors: vec![kinds
                .iter()
                .zip(eta)
                .map(|((_, sign), e)| (sign * e).exp())
                .collect()],
        };
        let obj = raw_objective(model, curves, &s).with_factors(Some(f));
        let mut r = vec![0.0; obj.n_residuals()];
        obj.residuals(&TRUTH, &mut r).expect("evaluable");
        noise.neg2ll(&split_residuals(curves, &r))
    };
    let grid = |t: f64| -> Vec<f64> {
        (0..=steps)
            .map(|i| -8.0 * t + 16.0 * t * i as f64 / steps as f64)
            .collect()
    };
    let weight = |i: usize| if i == 0 || i == steps { 0.5 } else { 1.0 };
    // log of the integrand at every grid point, with its quadrature weight.
    let mut terms: Vec<f64> = Vec::new();
    let g0 = grid(tau[0]);
    let h0 = g0[1] - g0[0];
    let log_norm =
        |e: f64, t: f64| -0.5 * (e / t).powi(2) - (t * (2.0 * std::f64::consts::PI).sqrt()).ln();
    if tau.len() == 1 {
        for (i, &e) in g0.iter().enumerate() {
            terms.push((weight(i) * h0).ln() - 0.5 * nll(&[e]) + log_norm(e, tau[0]));
        }
    } else {
        let g1 = grid(tau[1]);
        let h1 = g1[1] - g1[0];
        for (i, &e) in g0.iter().enumerate() {
            for (j, &z) in g1.iter().enumerate() {
                terms.push(
                    (weight(i) * weight(j) * h0 * h1).ln() - 0.5 * nll(&[e, z])
                        + log_norm(e, tau[0])
                        + log_norm(z, tau[1]),
                );
            }
        }
    }
    let m = terms.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    -2.0 * (m + terms.iter().map(|t| (t - m).exp()).sum::<f64>().ln())
}

/// The Laplace approximation and the brute-force integral of one specimen's curve of `n`
/// points, its rate (and ductility, if `both`) scattering with `tau`.
fn laplace_and_brute(n: usize, sd: f64, tau: &[f64], both: bool, seed: u64) -> (f64, f64) {
    if both {
        laplace_and_brute_of(
            n,
            sd,
            tau,
            [0.15, -0.05, 0.0],
            &[(EffectKind::Rate, 0, 1.0), (EffectKind::Ductility, 5, -1.0)],
            160,
            seed,
        )
    } else {
        laplace_and_brute_of(
            n,
            sd,
            tau,
            [0.15, 0.0, 0.0],
            &[(EffectKind::Rate, 0, 1.0)],
            4000,
            seed,
        )
    }
}

/// The Laplace approximation and the brute-force integral (`steps` intervals per kind) of one
/// specimen's curve of `n` points at 100 MPa with true effects `effects` ([η, ζ, κ]), white
/// reading error `sd`; `kinds` the effects integrated (kind, its constant's index, the sign
/// of the effect on it), scattering with `tau`.
fn laplace_and_brute_of(
    n: usize,
    sd: f64,
    tau: &[f64],
    effects: [f64; 3],
    kinds: &[(EffectKind, usize, f64)],
    steps: usize,
    seed: u64,
) -> (f64, f64) {
    let model = registry("khd").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let curves = vec![specimen3(model.as_ref(), 100.0, effects, n, sd, &mut rng)];
    let sp = space();
    let which: Vec<EffectKind> = kinds.iter().map(|k| k.0).collect();
    let (layout, dropped) = EffectLayout::new(model.as_ref(), &curves, &sp, &which);
    assert!(dropped.is_empty());
    let layout = layout.unwrap();
    let noise = ErrorModel {
        strain: vec![Ar1::white(sd)],
        lifetime_sd: 0.01,
    };
    let (lap, _) = laplace_at(
        model.as_ref(),
        &curves,
        &sp,
        &TRUTH,
        &layout,
        tau,
        &noise,
        &settings(),
    )
    .unwrap();
    let signs: Vec<(usize, f64)> = kinds.iter().map(|k| (k.1, k.2)).collect();
    let brute = brute_force(model.as_ref(), &curves, &signs, tau, &noise, steps);
    (lap, brute)
}

#[test]
fn laplace_matches_a_brute_force_integral_and_converges_with_the_points() {
    // One specimen's rate effect, τ = 0.3, white reading error of 0.2 % strain: the
    // conditional posterior of η is nearly Gaussian and narrows as points are added, so the
    // Laplace approximation's error (O(1/n) in −2 ln L for a smooth model) falls with n.
    let mut errs = vec![];
    for n in [6, 24, 96] {
        let (lap, brute) = laplace_and_brute(n, 2e-3, &[0.3], false, 3);
        eprintln!(
            "n = {n}: Laplace {lap:.6}, brute force {brute:.6}, difference {:.2e}",
            lap - brute
        );
        errs.push((lap - brute).abs());
    }
    assert!(errs[2] < errs[0], "{errs:?}");
    // Below the bootstrap's tie tolerance (0.01 of −2 ln L): no decision can depend on it.
    assert!(errs[2] < 0.01, "{errs:?}");
}

#[test]
fn laplace_matches_a_two_dimensional_integral() {
    // Rate and ductility of one specimen: a 161 × 161 grid over ±8 τ.
    let (lap, brute) = laplace_and_brute(60, 2e-3, &[0.3, 0.1], true, 5);
    eprintln!("2-D: Laplace {lap:.6}, brute force {brute:.6}");
    assert!((lap - brute).abs() < 0.01, "{lap} vs {brute}");
}

#[test]
fn laplace_matches_a_brute_force_integral_for_a_coarsening_effect() {
    // One specimen whose coarsening rate Kc scatters with τ = 0.3 (its tertiary stage sets
    // in earlier or later): the effect acts through the damage ODE, not a scale of time, so
    // its conditional posterior is less Gaussian than the rate's. 80 points, 0.2 % strain.
    let (lap, brute) = laplace_and_brute_of(
        80,
        2e-3,
        &[0.3],
        [0.0, 0.0, 0.2],
        &[(EffectKind::Coarsening, 4, 1.0)],
        4000,
        7,
    );
    eprintln!("coarsening: Laplace {lap:.6}, brute force {brute:.6}");
    assert!((lap - brute).abs() < 0.01, "{lap} vs {brute}");
}

/// The fit's specimen effects, asserted to be of `kinds` with each 95 % interval covering its
/// true scatter in `truth`.
fn scatter_covers<'a>(
    fit: &'a creepfit::likelihood::MlFit,
    kinds: &[EffectKind],
    truth: &[f64],
) -> &'a creepfit::likelihood::SpecimenFit {
    let f = fit.specimen.as_ref().expect("scatter found");
    eprintln!(
        "scatter {:?} [{:?}, {:?}], −2 ln L {:.2}",
        f.scatter, f.scatter_lo95, f.scatter_hi95, fit.neg2ll
    );
    assert_eq!(f.kinds, kinds);
    for (k, t) in truth.iter().enumerate() {
        assert!(
            f.scatter_lo95[k] <= *t && *t <= f.scatter_hi95[k],
            "kind {k}: {t} outside [{}, {}]",
            f.scatter_lo95[k],
            f.scatter_hi95[k]
        );
    }
    f
}

#[test]
fn the_coarsening_scatter_of_generated_specimens_is_recovered() {
    // 16 specimens at 4 stresses (4 replicates each), creep rate scattering with τ = 0.15 and
    // the coarsening rate Kc with 0.4, 40 points each with 0.02 % strain white reading
    // error: a fit with rate and coarsening effects finds both, each 95 % interval covers
    // its truth, and the fit is far better than one with rate effects alone.
    let model = registry("khd").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let (tr, tk) = (0.15, 0.4);
    let mut curves = vec![];
    for s in [85.0, 95.0, 105.0, 115.0] {
        for _ in 0..4 {
            let e: f64 = StandardNormal.sample(&mut rng);
            let k: f64 = StandardNormal.sample(&mut rng);
            curves.push(specimen3(
                model.as_ref(),
                s,
                [tr * e, 0.0, tk * k],
                40,
                2e-4,
                &mut rng,
            ));
        }
    }
    let sp = space();
    let opts = |coarsening: bool| MlOptions {
        specimen: SpecimenOptions {
            rate: true,
            ductility: false,
            coarsening,
            beyond_trend: false,
        },
        ..MlOptions::default()
    };
    let mut fit = ml_fit(
        model.as_ref(),
        &curves,
        &sp,
        &TRUTH,
        &settings(),
        &opts(true),
    );
    scatter_intervals(
        &mut fit,
        model.as_ref(),
        &curves,
        &sp,
        &settings(),
        &opts(true),
    );
    let f = scatter_covers(&fit, &[EffectKind::Rate, EffectKind::Coarsening], &[tr, tk]);
    // Each curve at its own specimen's factors (what diagnose's residual plots draw since
    // 2026-11-29) is the fit's own prediction; the population's is not.
    let own = raw_objective(model.as_ref(), &curves, &settings())
        .with_factors(f.curve_factors(model.as_ref()))
        .evaluate(&fit.params);
    let population = raw_objective(model.as_ref(), &curves, &settings()).evaluate(&fit.params);
    let fitted = fit.eval.as_ref().expect("evaluated");
    for i in 0..curves.len() {
        assert_eq!(own.curves[i].strain, fitted.curves[i].strain, "curve {i}");
    }
    assert!((0..curves.len()).any(|i| population.curves[i].strain != fitted.curves[i].strain));
    // predict's new-specimen scatter of ln t_r: the rate's τ and the coarsening's τ times
    // d ln t_r / d ln Kc, in quadrature. The elasticity here by direct simulations of the
    // first curve's load at Kc × e^{±0.1} (predict takes the median over the curves).
    let ctx = creepfit::uncertainty::Context::new(
        model.as_ref(),
        &curves,
        space(),
        settings(),
        opts(true),
    );
    let reference =
        creepfit::uncertainty::fit_reference(&ctx, &[TRUTH.to_vec()]).expect("a fit succeeds");
    let rsp = reference.specimen.as_ref().expect("scatter found");
    let life = |kc: f64| {
        let mut p = reference.params.clone();
        p[4] *= kc;
        let load = Load::new(curves[0].stress_mpa, 560.0, 1.0 / 3.0);
        model
            .simulate(&p, &load, &[], &mut [], &settings().ode)
            .t_end
            .ln()
    };
    let e = (life(0.1f64.exp()) - life((-0.1f64).exp())) / 0.2;
    let want = (rsp.scatter[0].powi(2) + (e * rsp.scatter[1]).powi(2)).sqrt();
    let [(s_t, _), _, _] = creepfit::uncertainty::predict::specimen_scatter(&ctx, &reference);
    eprintln!(
        "d ln t_r / d ln Kc {e:.3}; new-specimen sd of ln t_r {s_t:.4}, expected ≥ {want:.4}"
    );
    assert!(e < 0.0, "faster coarsening, shorter life: {e}");
    assert!(s_t >= 0.9 * want, "{s_t} vs {want}");
    assert!(
        s_t > rsp.scatter[0] + 0.01,
        "{s_t} vs the rate's {}",
        rsp.scatter[0]
    );
    let rate_only = ml_fit(
        model.as_ref(),
        &curves,
        &sp,
        &TRUTH,
        &settings(),
        &opts(false),
    );
    eprintln!("rate effects only: −2 ln L {:.2}", rate_only.neg2ll);
    assert!(
        fit.neg2ll < rate_only.neg2ll - 100.0,
        "{} vs {}",
        fit.neg2ll,
        rate_only.neg2ll
    );
}

#[test]
fn the_scatter_of_generated_specimens_is_recovered() {
    // 16 specimens at 4 stresses (4 replicates each), creep rate scattering with τ = 0.2,
    // ductility with 0.08, 40 points each with 0.02 % strain white reading error.
    let model = registry("khd").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let (tr, td) = (0.2, 0.08);
    let mut curves = vec![];
    let mut true_eta = vec![];
    for s in [85.0, 95.0, 105.0, 115.0] {
        for _ in 0..4 {
            let e: f64 = StandardNormal.sample(&mut rng);
            let z: f64 = StandardNormal.sample(&mut rng);
            true_eta.push(tr * e);
            curves.push(specimen(
                model.as_ref(),
                s,
                tr * e,
                td * z,
                40,
                2e-4,
                &mut rng,
            ));
        }
    }
    let sp = space();
    let opts = MlOptions {
        specimen: SpecimenOptions::BOTH,
        ..MlOptions::default()
    };
    let mut fit = ml_fit(model.as_ref(), &curves, &sp, &TRUTH, &settings(), &opts);
    // The null refits' gain-to-come stop does not reach a hierarchical fit (its rounds end on
    // their own plateau test): asked for, the fit is the same to the bit. Asked for with a δ
    // that ends an iteration as soon as two successive falls shrink (the diagnosis's own
    // setting never fires on this fit, so it could not show the stop being ignored).
    let with_stop = FitSettings {
        lm: LmOptions {
            gain_to_come: Some((1, 1e9)),
            ..settings().lm
        },
        ..settings()
    };
    let same = ml_fit(model.as_ref(), &curves, &sp, &TRUTH, &with_stop, &opts);
    assert_eq!((&same.params, same.neg2ll), (&fit.params, fit.neg2ll));
    scatter_intervals(&mut fit, model.as_ref(), &curves, &sp, &settings(), &opts);
    let f = scatter_covers(&fit, &[EffectKind::Rate, EffectKind::Ductility], &[tr, td]);
    // The specimens' own rate factors follow the truth's up to what the constants take (the
    // mean, and a trend with stress): their correlation.
    let est = &f.effects[0];
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (me, mt) = (mean(est), mean(&true_eta));
    let cov: f64 = est
        .iter()
        .zip(&true_eta)
        .map(|(a, b)| (a - me) * (b - mt))
        .sum();
    let va: f64 = est.iter().map(|a| (a - me).powi(2)).sum();
    let vb: f64 = true_eta.iter().map(|b| (b - mt).powi(2)).sum();
    let corr = cov / (va * vb).sqrt();
    eprintln!("correlation of the rate effects with the truth's: {corr:.3}");
    let plain = ml_fit(
        model.as_ref(),
        &curves,
        &sp,
        &TRUTH,
        &settings(),
        &MlOptions::default(),
    );
    assert!(
        fit.neg2ll < plain.neg2ll - 100.0,
        "{} vs {}",
        fit.neg2ll,
        plain.neg2ll
    );
}

/// The scatter's 95 % interval covers its truth in 90–98 % of sets (issue 20's must-show),
/// over 300 generated sets of the specimens world with no hidden effect (rate scatter
/// 10–30 % in every set, ductility 8 % in about half; replicates; reading error growing with
/// strain, white or AR(1)): one hierarchical maximum-likelihood fit of the base model
/// from the data's initial guess, both kinds of specimen effects (`battery::scatter_fit`). Fixed seeds
/// 132001–132300, first run for this test (the study behind it used 131001–131400:
/// rate 94.2 %, ductility 95.4 %; docs/SPECIMENS.md). About 60 s of fits on 2 cores.
#[test]
fn the_scatter_interval_covers_its_truth_at_its_level_over_many_sets() {
    use creepfit::battery::{coverage_of, scatter_fit, wilson, ScatterStart};
    use rayon::prelude::*;
    let dir = tempfile::TempDir::new().unwrap();
    let fits: Vec<_> = (132001..132301u64)
        .into_par_iter()
        .map(|s| {
            scatter_fit(
                dir.path(),
                s,
                "none",
                ScatterStart::Guess,
                creepfit::synth::World::Specimens,
                None,
            )
            .unwrap()
        })
        .collect();
    let cov = coverage_of(fits.iter().map(|f| {
        (
            &f.scatter_true[..],
            &f.scatter_lo95[..],
            &f.scatter_hi95[..],
        )
    }));
    for c in &cov {
        let share = c.covered as f64 / c.true_sets as f64;
        let (lo, hi) = wilson(c.covered, c.true_sets);
        eprintln!(
            "{}: covered {} of {} = {:.1} % (Wilson {:.1}–{:.1} %); zero excluded in {} of {} sets without it",
            c.kind,
            c.covered,
            c.true_sets,
            100.0 * share,
            100.0 * lo,
            100.0 * hi,
            c.spurious,
            c.absent_sets
        );
        assert!(c.true_sets >= 100, "{}: {} sets", c.kind, c.true_sets);
        assert!((0.90..=0.98).contains(&share), "{}: {:.3}", c.kind, share);
    }
    // Every set has rate scatter; the ductility kind is in about half of them.
    assert_eq!(cov[0].true_sets, 300);
}

/// One generated set of the specimens world (`creepfit battery --world specimens`): scenario
/// by `index` (0: none, 2: loading_strain), diagnosed with the default settings.
fn diagnose_generated(index: usize, seed: u64) -> creepfit::battery::SetResult {
    let dir = tempfile::TempDir::new().unwrap();
    let r = creepfit::battery::run_one(dir.path(), index, seed, creepfit::synth::World::Specimens);
    eprintln!(
        "set-{seed} {}: {} curves, true scatter {:?}, estimated {:?} (95 % {:?}–{:?}), λ {:.1} → {} in {:.0} s",
        r.scenario,
        r.curves,
        r.scatter_true,
        r.scatter_est,
        r.scatter_lo95,
        r.scatter_hi95,
        r.lambda,
        r.outcome(),
        r.wall_s
    );
    assert_eq!(r.error, None);
    r
}

/// Generated set `name` of the specimens world (`scenario`, `seed`) written into `dir`, and its
/// configuration loaded back as `creepfit` would.
fn generated_set(
    dir: &std::path::Path,
    name: &str,
    scenario: &str,
    seed: u64,
) -> (creepfit::synth::SynthSet, creepfit::config::RunConfig) {
    let set = creepfit::synth::generate_in(
        name,
        scenario,
        None,
        seed,
        creepfit::synth::World::Specimens,
    )
    .unwrap();
    let folder = dir.join(name);
    creepfit::synth::write_set(&set, &folder).unwrap();
    let cfg = creepfit::config::RunConfig::load(&folder.join("config.toml")).unwrap();
    (set, cfg)
}

/// The curves of `cfg`'s data binned as `diagnose` bins them.
fn binned_curves(cfg: &creepfit::config::RunConfig) -> Vec<Curve> {
    cfg.load_data()
        .unwrap()
        .curves
        .iter()
        .map(|c| creepfit::data::binned(c, cfg.diagnose.max_points))
        .collect()
}

/// A set with specimen scatter and no hidden effect (fresh seed 95001, not used while
/// developing): the hierarchical base model is adequate — before the specimen effects
/// 28 of 30 such sets were `unexplained`.
#[test]
fn a_null_set_with_specimen_scatter_is_adequate() {
    let dir = tempfile::TempDir::new().unwrap();
    let (r, d) = creepfit::battery::run_one_diagnosed(
        dir.path(),
        "none",
        95001,
        creepfit::synth::World::Specimens,
    );
    assert_eq!(r.error, None);
    assert_eq!(r.scenario, "none");
    assert!(r.scatter_true[0] >= 0.1, "the set carries scatter");
    assert_eq!(r.outcome(), "adequate");
    // report.md gives the scatter between specimens and each specimen's factor.
    let cfg =
        creepfit::config::RunConfig::load(&dir.path().join("sets/set-95001/config.toml")).unwrap();
    let d = d.unwrap();
    let md = creepfit::diagnose::report::report_md(&cfg.name, &cfg.diagnose_setup().unwrap(), &d);
    assert!(md.contains("## Specimens"), "{md}");
    assert!(
        md.contains("varies") && md.contains("between specimens"),
        "{md}"
    );
    assert!(md.contains("creep-rate factor"), "{md}");
    // With specimen effects the goodness of fit that decides looks beyond each specimen's own
    // shape; the fixed shapes are reported beside, outside the Holm family.
    use creepfit::diagnose::gof::Shape;
    let deciding: Vec<Shape> = d
        .gof
        .iter()
        .filter(|g| g.decides)
        .map(|g| g.gof.shape)
        .collect();
    assert_eq!(
        deciding,
        [Shape::CommonBeyondSpecimens, Shape::TrendBeyondSpecimens]
    );
    assert!(d
        .gof
        .iter()
        .filter(|g| !g.decides)
        .all(|g| g.p_holm.is_none_or(|p| p.is_nan())));
    assert!(md.contains("reported, not part of the family"), "{md}");
    // The base's factors against stress (one temperature): each kind's slope of the ln
    // factors on ln σ recomputed from the fit's factors; the null set's do not follow stress.
    assert!(md.contains("factors against ln stress"), "{md}");
    let sp = d
        .base
        .specimen
        .as_ref()
        .expect("the base carries specimen effects");
    assert_eq!(d.base.specimen_stress_trend.len(), sp.kinds.len());
    let x: Vec<f64> = d.base.curves.iter().map(|c| c.stress_mpa.ln()).collect();
    let n = x.len() as f64;
    for (t, eta) in d.base.specimen_stress_trend.iter().zip(&sp.effects) {
        let (mx, my) = (x.iter().sum::<f64>() / n, eta.iter().sum::<f64>() / n);
        let sxy: f64 = x.iter().zip(eta).map(|(a, b)| (a - mx) * (b - my)).sum();
        let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
        assert!((t.slope - sxy / sxx).abs() < 1e-9, "{t:?}");
        assert_eq!(t.df, x.len() - 2);
        assert!(!t.follows_stress(), "{t:?}");
    }
    // The battery keeps the diagnosis beside the set, with every test's null statistics:
    // each test's p-value recomputed from them, (1 + #{T* ≥ T − 0.01 or failed})/(B + 1),
    // is the one reported.
    let text = std::fs::read_to_string(dir.path().join("sets/set-95001/diagnosis.json")).unwrap();
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    let cols = j["bootstrap"]["null_statistics"].as_array().unwrap();
    let reported: Vec<f64> = d
        .candidates
        .iter()
        .map(|c| c.p_value.unwrap())
        .chain(d.gof.iter().map(|g| g.p_value))
        .collect();
    assert_eq!(cols.len(), reported.len());
    use creepfit::diagnose::bootstrap::STOP_EXCEEDANCES;
    for (col, want) in cols.iter().zip(&reported) {
        let obs = col["observed"].as_f64().unwrap();
        let vals = col["values"].as_array().unwrap();
        let ge = vals
            .iter()
            .filter(|v| v.as_f64().is_none_or(|x| x >= obs - 0.01))
            .count();
        // The sequential rule: a test stops before 20 replicates only once STOP_EXCEEDANCES
        // of them reach its statistic (decided not significant).
        assert!(
            vals.len() >= 20 || ge >= STOP_EXCEEDANCES,
            "{}: {} replicates, {ge} at or above",
            col["test"],
            vals.len()
        );
        let p = (1 + ge) as f64 / (vals.len() + 1) as f64;
        assert!((p - want).abs() < 1e-12, "{}: {p} vs {want}", col["test"]);
    }
}

/// Specimens that differ in shape too (world `shapes`: each its own coarsening rate, Kc ×
/// e^κ, as Alloy 617's specimens differ in the onset of their tertiary stage), no hidden
/// effect, diagnosed with three kinds of specimen effects (as the shipped Alloy 617
/// configurations fitted them 2026-11-30 to 12-02): the base model is adequate, the coarsening scatter is estimated and
/// its 95 % interval is reported. Seed 174001, the first of a range never used before
/// (taken, not chosen: its diagnosis was first run 2026-11-30 on this code, `adequate`).
#[test]
fn a_null_set_whose_specimens_differ_in_shape_is_adequate() {
    let dir = tempfile::TempDir::new().unwrap();
    let (r, d) = creepfit::battery::run_one_diagnosed(
        dir.path(),
        "none",
        174001,
        creepfit::synth::World::Shapes,
    );
    eprintln!(
        "set-174001: true scatter {:?}, estimated {:?} (95 % {:?}–{:?}) → {} in {:.0} s",
        r.scatter_true,
        r.scatter_est,
        r.scatter_lo95,
        r.scatter_hi95,
        r.outcome(),
        r.wall_s
    );
    assert_eq!(r.error, None);
    assert_eq!(r.outcome(), "adequate");
    // Three kinds, in the order rate, ductility, coarsening; the coarsening scatter found.
    assert_eq!(r.scatter_true.len(), 3);
    assert!(
        r.scatter_true[2] >= 0.15,
        "the set's specimens differ in shape"
    );
    assert_eq!(r.scatter_est.len(), 3);
    assert!(r.scatter_est[2] > 0.0, "{:?}", r.scatter_est);
    assert!(r.scatter_lo95[2] <= r.scatter_est[2] && r.scatter_est[2] <= r.scatter_hi95[2]);
    let d = d.unwrap();
    let sp = d.base.specimen.as_ref().expect("specimen effects");
    assert!(sp
        .kinds
        .contains(&creepfit::likelihood::EffectKind::Coarsening));
    // The decision's goodness of fit is the one beyond each specimen's own shape.
    assert!(d
        .gof
        .iter()
        .filter(|g| g.decides)
        .all(|g| g.gof.shape.beyond_specimens()));
}

/// A catalogued effect (a loading strain) hidden under specimen scatter, clearly
/// detectable: the first fresh seed from 95101 whose set the oracle with the specimens'
/// factors unknown (`battery::oracle_lambda_scatter`, the power table's) gives λ ≥ 100 (four
/// times the detectability threshold; chosen by the generator's truth, never by the
/// verdict): seed 95101 has λ 42.1 (43.0 with the factors known), seed 95102 λ 1,542.9
/// (1,592.0).
///
/// History: seed 95102 came out `adequate` until 2026-11-26 (loading_strain LR 850,
/// bootstrap p 0.168: the null replicates' nested refits gave LRs of hundreds too). It
/// **passes since** (re-run 2026-11-27 on commit ed6a114: `extension:loading_strain`, LR
/// 162.45, bootstrap p 0.006 = 1/160, Holm-adjusted 0.050: at the level exactly; 519 s
/// beside a niced battery, Intel Xeon, 2 cores; `creepfit diagnose` of the same set 626 s,
/// 518 s of it the null bootstrap). Ignored in CI for its time only (a diagnosis that
/// rejects runs the whole bootstrap, its second run and the cause's own goodness of fit:
/// about 10 min here, where CI's budget is 30 for everything);
/// `scripts/bench_battery.sh` runs it. CI names the same set's effect against a family of
/// two extensions (`a_hidden_effect_under_specimen_scatter_is_named_in_a_small_family`). Run it alone with
/// `cargo test --release --test specimen -- --ignored an_effect_under_specimen_scatter_is_named`.
#[test]
#[ignore = "long: one full diagnosis that rejects (about 10 min on 2 cores); scripts/bench_battery.sh runs it"]
fn an_effect_under_specimen_scatter_is_named() {
    let dir = tempfile::TempDir::new().unwrap();
    let seed = (95101..95121)
        .find(|&seed| {
            let (set, cfg) =
                generated_set(dir.path(), &format!("probe-{seed}"), "loading_strain", seed);
            let lambda = creepfit::battery::oracle_lambda_scatter(&cfg, &set.truth)
                .expect("a catalogued effect in the specimens world");
            eprintln!("seed {seed}: λ (factors unknown) {lambda:.1}");
            lambda >= 100.0
        })
        .expect("a clearly detectable set among 20 seeds");
    let r = diagnose_generated(2, seed);
    assert_eq!(r.scenario, "loading_strain");
    assert!(r.lambda_scatter >= 100.0, "oracle λ {}", r.lambda_scatter);
    assert_eq!(r.outcome(), "extension:loading_strain");
}

/// The same hidden loading strain under specimen scatter (set 95102, the seed the ignored
/// test above takes by its oracle λ, never by a verdict) named within CI's budget: the family
/// of tests cut to two extensions (`[diagnose] extensions = ["constant_load",
/// "loading_strain"]`) and the bootstrap to 79 replicates, the smallest that can reject at
/// Holm's first threshold with m = 4 tests (20 m − 1), not extended for the tests close to
/// significance (`bootstrap_extended = 79`: with 319 replicates this test took 359 s
/// beside other tests). The procedure is the whole
/// catalogue's: hierarchical fits, the null of new specimens, Holm, the cause's own
/// goodness of fit beyond specimen shapes.
#[test]
fn a_hidden_effect_under_specimen_scatter_is_named_in_a_small_family() {
    let dir = tempfile::TempDir::new().unwrap();
    let (set, _) = generated_set(dir.path(), "set-95102", "loading_strain", 95102);
    assert_eq!(set.truth.effect.name(), "loading_strain");
    let cfg_path = dir.path().join("set-95102/config.toml");
    let mut text = std::fs::read_to_string(&cfg_path).unwrap();
    text.push_str(
        "\n[diagnose]\nextensions = [\"constant_load\", \"loading_strain\"]\nbootstrap = 79\nbootstrap_extended = 79\n",
    );
    std::fs::write(&cfg_path, text).unwrap();
    let cfg = creepfit::config::RunConfig::load(&cfg_path).unwrap();
    let data = cfg.load_data().unwrap();
    let setup = cfg.diagnose_setup().unwrap();
    let d = creepfit::diagnose::diagnose(&setup, &data, &cfg.diagnose).unwrap();
    eprintln!(
        "set-95102 (small family): {:?} {:?}; {}",
        d.verdict,
        d.cause,
        d.candidates
            .iter()
            .map(|c| format!(
                "{} LR {:.1} p {:?} Holm {:?}",
                c.name, c.lr, c.p_value, c.p_holm
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    assert_eq!(d.candidates.len(), 2);
    assert_eq!(d.bootstrap.replicates, 79);
    assert!(
        d.base.specimen.is_some(),
        "the base carries specimen effects"
    );
    assert_eq!(d.verdict, creepfit::diagnose::Verdict::Extension);
    assert_eq!(d.cause.as_deref(), Some("loading_strain"));
    // Named only with its own goodness of fit holding, beyond specimen shapes.
    let own: Vec<_> = d.cause_gof.iter().filter(|g| g.decides).collect();
    assert!(!own.is_empty());
    assert!(own.iter().all(|g| g.gof.shape.beyond_specimens()));
    // With an extension significant, the caution states the specimens' own shapes exactly
    // when the base's goodness of fit beyond specimen shapes estimates them.
    let tau = d
        .gof
        .iter()
        .filter(|g| g.gof.shape.beyond_specimens())
        .map(|g| g.gof.specimen_shape_sd_pct)
        .fold(f64::NAN, f64::max);
    eprintln!("τ̂ {tau} %; caution {:?}", d.caution);
    // The null replicates' new specimens were given the data's specimens' own shapes,
    // resampled at the spread of the common shape's mixed model.
    let common = d
        .gof
        .iter()
        .find(|g| g.gof.shape == creepfit::diagnose::gof::Shape::CommonBeyondSpecimens)
        .map(|g| g.gof.specimen_shape_sd_pct)
        .expect("tested beyond specimen shapes");
    assert!(
        (d.bootstrap.specimen_shape_sd_pct - common).abs() < 1e-9 * common.max(1.0),
        "null's shapes {} % against τ̂ {common} %",
        d.bootstrap.specimen_shape_sd_pct
    );
    assert_eq!(
        creepfit::diagnose::report::report_md("set-95102", &setup, &d)
            .contains("a shape of its own"),
        common > 0.0
    );
    assert_eq!(
        d.caution
            .as_deref()
            .is_some_and(|c| c.contains("differ in shape beyond their fitted factors")),
        tau > 0.0,
        "τ̂ {tau}: {:?}",
        d.caution
    );
}

/// A nested extension refitted from the base model's hierarchical optimum (its added
/// constants switched off, the base's specimen effects and scatter) never ends with a lower
/// likelihood than the base: its likelihood ratio is ≥ 0. Before the fit ranked its points by
/// the likelihood at the ML scatter (issue 20), the ratio was below zero in most refits (the
/// likelihood was taken at REML's scatter, which grows with the number of constants), by
/// 1.4–3.1 for `loading_strain`, whose switched-off value then left a loading strain of
/// 1.5e-5. Fresh null sets of the specimens world (seeds 99001–99006, not used while
/// developing); the constant-free `constant_load` is not nested and is left out.
#[test]
fn a_nested_extension_refitted_from_the_base_optimum_never_ends_below_it() {
    use creepfit::likelihood::{ml_fit_from, with_specimens, EffectStart};
    let dir = tempfile::TempDir::new().unwrap();
    let (mut checked, mut failed) = (0, 0);
    for seed in 99001..99007u64 {
        let (set, cfg) = generated_set(dir.path(), &format!("set-{seed}"), "none", seed);
        let curves = binned_curves(&cfg);
        let setup = cfg.diagnose_setup().unwrap();
        let ml = MlOptions {
            specimen: SpecimenOptions::BOTH,
            ..MlOptions::default()
        };
        let base = &setup.variants[0];
        let (m, s) = (base.model.as_ref(), &base.space);
        let plain = ml_fit(
            m,
            &curves,
            s,
            &set.truth.constants,
            &setup.settings,
            &MlOptions::default(),
        );
        let b = with_specimens(plain, m, &curves, s, &setup.settings, &ml);
        let Some(effects) = b.specimen.as_ref().map(EffectStart::from) else {
            continue; // no scatter found: nothing hierarchical to check
        };
        let base_names: Vec<&str> = m.constants().iter().map(|c| c.name).collect();
        let direct = MlOptions {
            white_first: false,
            ..ml
        };
        for v in setup.variants[1..].iter().filter(|v| !v.extra.is_empty()) {
            let start: Vec<f64> = v
                .model
                .constants()
                .iter()
                .enumerate()
                .map(
                    |(j, c)| match base_names.iter().position(|n| *n == c.name) {
                        Some(i) => b.params[i],
                        None => {
                            creepfit::model::ext::off_value(c.name, v.space.lb[j], v.space.ub[j])
                                .unwrap_or_else(|| v.space.from_unit_one(j, 0.5))
                        }
                    },
                )
                .collect();
            let f = ml_fit_from(
                v.model.as_ref(),
                &curves,
                &v.space,
                &start,
                Some(&effects),
                &setup.settings,
                &direct,
            );
            if !f.ok() {
                // Measured once (set 99003, stress_ductility): the derivatives at the start
                // could not be simulated (step underflow at 116 MPa) though its residuals
                // could; a failed refit is counted against rejection in the bootstrap.
                eprintln!("set-{seed} {:<20} failed: {:?}", v.name, f.failure);
                failed += 1;
                continue;
            }
            let lr = b.neg2ll - f.neg2ll;
            eprintln!("set-{seed} {:<20} LR {lr:+.4}", v.name);
            assert!(lr >= -1e-3, "set-{seed} {}: LR {lr} below zero", v.name);
            checked += 1;
        }
    }
    assert!(
        checked >= 15 && failed <= 2,
        "{checked} refits checked, {failed} failed"
    );
}

/// Six specimens at three stresses (two each), creep rate scattering with τ = 0.25, 25 points
/// each with 0.02 % strain white reading error, and a hierarchical profile context on them
/// (rate effects) with its reference (the maximum-likelihood fit from the truth).
fn hierarchical_reference<'a>(
    model: &'a dyn Model,
    curves: &'a [Curve],
) -> (
    creepfit::uncertainty::Context<'a>,
    creepfit::uncertainty::Reference,
) {
    let opts = MlOptions {
        specimen: SpecimenOptions {
            rate: true,
            ductility: false,
            coarsening: false,
            beyond_trend: false,
        },
        ..MlOptions::default()
    };
    let ctx = creepfit::uncertainty::Context::new(model, curves, space(), settings(), opts);
    assert!(ctx.hierarchical());
    let reference =
        creepfit::uncertainty::fit_reference(&ctx, &[TRUTH.to_vec()]).expect("a fit succeeds");
    (ctx, reference)
}

fn six_specimens(model: &dyn Model, seed: u64) -> Vec<Curve> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut curves = vec![];
    for s in [90.0, 100.0, 110.0] {
        for _ in 0..2 {
            let e: f64 = StandardNormal.sample(&mut rng);
            curves.push(specimen(model, s, 0.25 * e, 0.0, 25, 2e-4, &mut rng));
        }
    }
    curves
}

/// The hierarchical profile holds a constant two independent ways that must agree: pinned by
/// the box (the rate effects stay in the fit) and held by a penalty row on a function of the
/// constants (the way a prediction is held). Both are Laplace −2 ln L of the same constrained
/// optimum; at the optimum itself Δ = 0, away from it Δ > 0.
#[test]
fn a_hierarchical_profile_holds_a_constant_by_the_box_and_by_a_penalty_alike() {
    use creepfit::uncertainty::constrained::{constrained_fit, held_fit, Coord, Quantity};
    let model = registry("khd").unwrap();
    let curves = six_specimens(model.as_ref(), 31);
    let (ctx, reference) = hierarchical_reference(model.as_ref(), &curves);
    let sp = reference.specimen.as_ref().expect("rate scatter found");
    eprintln!(
        "reference −2 ln L {:.3}, rate scatter {:.3}",
        reference.neg2ll, sp.scatter[0]
    );
    let (lb, ub) = (&ctx.space.lb, &ctx.space.ub);
    let names = ctx.names();
    let coords: Vec<Coord> = (0..names.len())
        .map(|j| Coord::of(names[j], lb[j], ub[j]))
        .collect();
    // At the optimum: nothing to gain or lose.
    let at = held_fit(&ctx, 5, reference.params[5], &reference.params, true);
    assert!(at.ok(), "{:?}", at.failure);
    assert!(
        (at.neg2ll - reference.neg2ll).abs() < 0.05,
        "{} vs {}",
        at.neg2ll,
        reference.neg2ll
    );
    // C (inverse ductility) and A (the rate constant the effects act through), 3 % and 200 %
    // off the optimum: the box and the penalty give the same constrained optimum.
    for (j, factor) in [(5usize, 1.03), (0usize, 3.0)] {
        let v = reference.params[j] * factor;
        let pinned = held_fit(&ctx, j, v, &reference.params, true);
        let mut coef = vec![0.0; names.len()];
        coef[j] = 1.0;
        let q = Quantity::Combination {
            coef,
            coords: coords.clone(),
        };
        let target = coords[j].z(v);
        let row = constrained_fit(&ctx, &q, target, 1e-4, &reference.params, true);
        assert!(
            pinned.ok() && row.ok(),
            "{:?} {:?}",
            pinned.failure,
            row.failure
        );
        let (dp, dr) = (
            pinned.neg2ll - reference.neg2ll,
            row.neg2ll - reference.neg2ll,
        );
        eprintln!("{}: Δ pinned {dp:.4}, by the penalty {dr:.4}", names[j]);
        assert!(dp > 0.1, "{}: Δ {dp}", names[j]);
        assert!((row.coord - target).abs() < 1e-3, "{} {target}", row.coord);
        assert!((dp - dr).abs() < 0.05 * dp.max(1.0), "{dp} vs {dr}");
    }
}

/// The marginal information (effects integrated out) predicts the hierarchical profile's
/// curvature: one Wald standard error from the optimum, the profile has risen by about 1 on
/// either side. The plain information of identical specimens claims the rate constant A far
/// better determined than the data say (the rate factors' mean trades with A).
#[test]
fn the_marginal_information_gives_the_hierarchical_profiles_curvature() {
    use creepfit::uncertainty::constrained::held_fit;
    use creepfit::uncertainty::information;
    let model = registry("khd").unwrap();
    let curves = six_specimens(model.as_ref(), 32);
    let (ctx, reference) = hierarchical_reference(model.as_ref(), &curves);
    let marginal = information(
        &ctx,
        &ctx.space,
        &reference.params,
        &reference.noise,
        reference.specimen.as_ref(),
    )
    .expect("information");
    let plain = information(&ctx, &ctx.space, &reference.params, &reference.noise, None)
        .expect("information");
    let se =
        |i: &nalgebra::DMatrix<f64>, j: usize| creepfit::uncertainty::covariance(i)[(j, j)].sqrt();
    let (sm, sp) = (se(&marginal, 0), se(&plain, 0));
    eprintln!("A: Wald se (unit box) marginal {sm:.5}, plain {sp:.5}");
    assert!(sp < 0.5 * sm, "{sp} vs {sm}");
    for dir in [-1.0, 1.0] {
        let u = ctx.space.to_unit_one(0, reference.params[0]) + dir * sm;
        let v = ctx.space.from_unit_one(0, u);
        let f = held_fit(&ctx, 0, v, &reference.params, true);
        assert!(f.ok(), "{:?}", f.failure);
        let d = f.neg2ll - reference.neg2ll;
        eprintln!(
            "A one se {}: Δ {d:.3}",
            if dir < 0.0 { "below" } else { "above" }
        );
        assert!(d > 0.5 && d < 2.0, "Δ {d}");
    }
}

/// `diagnose`'s bootstrap draws reading error that grows with strain when the data's does
/// (`bootstrap::reading_error`, `errmodel::GrowingError`): 8 curves of the seed's truth with
/// AR(1) reading error (φ 0.5) growing to (1 + g)× at each curve's end, g = 1.5, and the same
/// curves with g = 0 (same draws), each fitted by maximum likelihood from the truth. The
/// likelihood-ratio test of no growth on the fit's residuals rejects it for the first and not
/// for the second (3.84), and across 300 replicates the reading error at each curve's last reading is (1 + ĝ x)
/// times that at its first non-zero one (within 15 %: the sd of an sd from 300 draws is 4 %).
#[test]
fn the_bootstrap_draws_reading_error_that_grows_like_the_datas() {
    use creepfit::diagnose::bootstrap::{reading_error, replicate_data};
    use creepfit::errmodel::{strain_fractions, GrowingError};
    let model = registry("khd").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(20261127);
    let clean: Vec<Curve> = [150.0, 160.0, 170.0, 180.0, 190.0, 200.0, 210.0, 220.0]
        .iter()
        .map(|&s| specimen(model.as_ref(), s, 0.0, 0.0, 50, 0.0, &mut rng))
        .collect();
    let truth = |g: f64| GrowingError {
        growth: g,
        strain: vec![Ar1::with_marginal(3e-4, 0.5); clean.len()],
    };
    let noisy = |g: f64, seed: u64| -> Vec<Curve> {
        let mut r = ChaCha8Rng::seed_from_u64(seed);
        let m = truth(g);
        clean
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let e = m.simulate(i, &strain_fractions(&c.strains), &mut r);
                let strains: Vec<f64> = c.strains.iter().zip(&e).map(|(s, d)| s + d).collect();
                Curve {
                    strains,
                    ..c.clone()
                }
            })
            .collect()
    };
    let opts = MlOptions::default();
    let mut got = vec![];
    for g in [0.0, 1.5] {
        let curves = noisy(g, 7);
        let fit = ml_fit(
            model.as_ref(),
            &curves,
            &space(),
            &TRUTH,
            &settings(),
            &opts,
        );
        assert!(fit.ok());
        let reading = reading_error(&curves, model.as_ref(), &space(), &fit, &settings());
        // The likelihood-ratio test of g = 0 on the fit's residuals (boundary: ½χ²₀ + ½χ²₁,
        // so 3.84 is its 2.5 % point).
        let res = &fit.residuals.as_ref().unwrap().strain;
        let x: Vec<Vec<f64>> = curves
            .iter()
            .map(|c| strain_fractions(&c.strains))
            .collect();
        let design = restricted_design(model.as_ref(), &curves, &space(), &fit, &settings())
            .expect("the fit's Jacobian");
        assert_eq!(
            GrowingError::estimate_restricted(res, &x, &design).growth,
            reading.growth
        );
        let best = GrowingError::estimate(res, &x);
        let zero = GrowingError::estimate(res, &vec![vec![0.0; 50]; curves.len()]);
        let lr = zero.neg2ll(res, &x) - best.neg2ll(res, &x);
        eprintln!("g = {g}: estimated {:.3}, LR {lr:.1}", reading.growth);
        got.push(lr);
        if g == 0.0 {
            continue;
        }
        let eval = fit.eval.as_ref().unwrap();
        let reps: Vec<Vec<Curve>> = (0..300)
            .map(|_| replicate_data(&curves, eval, &fit.noise, &reading, &mut rng))
            .collect();
        for (i, c) in curves.iter().enumerate() {
            let x = strain_fractions(&c.strains);
            let first = x.iter().position(|v| *v > 0.0).unwrap();
            let last = x.len() - 1;
            let sd = |j: usize| {
                let d: Vec<f64> = reps
                    .iter()
                    .map(|r| r[i].strains[j] - eval.curves[i].strain[j])
                    .collect();
                (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt()
            };
            let want = (1.0 + reading.growth * x[last]) / (1.0 + reading.growth * x[first]);
            let ratio = sd(last) / sd(first);
            assert!(
                (ratio / want - 1.0).abs() < 0.15,
                "curve {i}: {ratio} vs {want}"
            );
        }
    }
    assert!(got[0] < 3.84 && got[1] > 3.84, "{got:?}");
}

/// The Jacobian `likelihood::restricted_design` hands the growth's restricted likelihood
/// (`errmodel::GrowingError::estimate_restricted`) is that of the fit's raw strain residuals
/// (strain as a fraction) in its parameters: every entry of every curve's block against a
/// central difference of the residuals, in the free constants (unit box) and in the curve's
/// own specimen effects. Four specimens (two stresses, each tested twice) with rate and
/// ductility factors, fitted with both kinds of effect.
#[test]
fn the_restricted_design_is_the_jacobian_of_the_raw_strain_residuals() {
    let model = registry("khd").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(20261202);
    let curves: Vec<Curve> = [
        (170.0, 0.2, 0.05),
        (170.0, -0.15, -0.05),
        (200.0, 0.1, 0.0),
        (200.0, -0.1, 0.03),
    ]
    .iter()
    .map(|&(s, eta, zeta)| specimen(model.as_ref(), s, eta, zeta, 30, 2e-4, &mut rng))
    .collect();
    let sp_opts = MlOptions {
        specimen: SpecimenOptions::BOTH,
        ..MlOptions::default()
    };
    let fit = ml_fit(
        model.as_ref(),
        &curves,
        &space(),
        &TRUTH,
        &settings(),
        &sp_opts,
    );
    assert!(fit.ok());
    let sp = fit.specimen.as_ref().expect("specimen effects fitted");
    let design = restricted_design(model.as_ref(), &curves, &space(), &fit, &settings())
        .expect("the fit's Jacobian");
    let (layout, _) = EffectLayout::new(model.as_ref(), &curves, &space(), &sp.kinds);
    let layout = layout.unwrap();
    let nt = layout.n_theta;
    let mut x = space().to_unit(&fit.params);
    for &(kind, _, _) in &layout.kinds {
        let k = sp.kinds.iter().position(|q| *q == kind).unwrap();
        x.extend_from_slice(&sp.effects[k]);
    }
    let strain = |x: &[f64]| -> Vec<Vec<f64>> {
        let mut params = space().fixed.clone();
        space().from_unit(&x[..nt], &mut params);
        let obj = raw_objective(model.as_ref(), &curves, &settings())
            .with_factors(Some(layout.factors(&x[nt..])));
        let mut r = vec![0.0; obj.n_residuals()];
        obj.residuals(&params, &mut r).unwrap();
        split_residuals(&curves, &r).strain
    };
    assert_eq!(design.curves.len(), curves.len());
    assert_eq!(design.fixed.nrows(), x.len());
    let h = 1e-6;
    let mut checked = 0;
    for (i, (block, cols)) in design.curves.iter().enumerate() {
        // The free constants, then this curve's own effects (one a kind).
        assert_eq!(cols.len(), nt + layout.kinds.len());
        assert_eq!(block.nrows(), curves[i].times_h.len());
        for (a, &col) in cols.iter().enumerate() {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[col] += h;
            xm[col] -= h;
            let (rp, rm) = (strain(&xp), strain(&xm));
            let scale = block.column(a).amax().max(1e-12);
            for j in 0..block.nrows() {
                let fd = (rp[i][j] - rm[i][j]) / (2.0 * h);
                assert!(
                    (block[(j, a)] - fd).abs() <= 1e-4 * scale,
                    "curve {i}, column {col}, reading {j}: {} against {fd}",
                    block[(j, a)]
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100);
}

/// A nested extension refitted from the base's hierarchical optimum with the extension
/// switched off starts at the base's likelihood and must not end above it (the base refitted
/// first from the optimum stored with the data, the extensions from where it ends, as
/// `diagnose` starts a replicate's extensions from its base refit). Measured on a
/// generated set (seed 100002, `tests/data/warm_drop/`, hidden constant load λ 239, six
/// specimens with rate scatter 0.12 and reading error 0.01 % strain): the base's optimum
/// carries ductility effects of ±0.25 % with a scatter of 0.0013 (near the floor 0.001), and
/// `dislocation_damage`'s warm fit from it ended at −2 ln L −4434.8 against the base's −4592.3:
/// its scatter estimate fell to the floor, the kind was dropped and its effects set to zero,
/// though with readings this precise ±0.25 % of rupture strain is 3–4 reading-error sds
/// (`diagnose` then reported a likelihood ratio of −120.6 for a nested extension).
#[test]
fn a_nested_warm_fit_never_ends_above_the_base_optimum() {
    use creepfit::likelihood::{ml_fit_from, EffectStart};
    let here = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/warm_drop");
    let cfg = creepfit::config::RunConfig::load(&here.join("config.toml")).unwrap();
    let setup = cfg.diagnose_setup().unwrap();
    let curves = binned_curves(&cfg);
    let text = std::fs::read_to_string(here.join("base.json")).unwrap();
    let b: serde_json::Value = serde_json::from_str(&text).unwrap();
    let nums = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    // The stored optimum; once the base is refitted from it, the extensions start where that
    // refit ends, as in `diagnose` (a replicate's base refit, then each extension from it).
    let mut base = nums(&b["constants"]);
    let mut start = EffectStart {
        kinds: b["kinds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| match k.as_str().unwrap() {
                "rate" => EffectKind::Rate,
                _ => EffectKind::Ductility,
            })
            .collect(),
        effects: b["effects"].as_array().unwrap().iter().map(nums).collect(),
        scatter: nums(&b["scatter"]),
        method: Default::default(),
    };
    let ml = MlOptions {
        lifetime_sd_floor: cfg.diagnose.lifetime_sd_floor,
        white_first: false,
        specimen: setup
            .specimen_effects
            .resolve(&curves, setup.specimen_scatter)
            .0,
        hold_scatter: None,
    };
    let mut base_ll = f64::NAN;
    let mut checked = 0;
    for v in &setup.variants {
        let names: Vec<&str> = v.model.constants().iter().map(|c| c.name).collect();
        let mut x = base.clone();
        // The switched-off value of each added constant (strain_softening's φ1 has none, φ0 = 0
        // switches it off: φ1 mid-box).
        for (j, n) in names.iter().enumerate().skip(base.len()) {
            let (lb, ub) = (v.space.lb[j], v.space.ub[j]);
            x.push(creepfit::model::ext::off_value(n, lb, ub).unwrap_or(0.5 * (lb + ub)));
        }
        if v.name != "base" && v.extra.is_empty() {
            continue; // not nested (constant_load)
        }
        let f = ml_fit_from(
            v.model.as_ref(),
            &curves,
            &v.space,
            &x,
            Some(&start),
            &setup.settings,
            &ml,
        );
        eprintln!("{}: −2 ln L {:.2}", v.name, f.neg2ll);
        assert!(f.ok(), "{}", v.name);
        if v.name == "base" {
            // The base refitted from its own optimum does not end above it (it may go on
            // below: since session 83's step-size control it ends at −4597.06 against the
            // stored −4592.34, whose fit had stopped in a crawl).
            base_ll = f.neg2ll;
            assert!(base_ll <= b["neg2ll"].as_f64().unwrap() + 0.5, "{base_ll}");
            base = f.params.clone();
            start = EffectStart::from(f.specimen.as_ref().expect("specimen effects fitted"));
        } else {
            assert!(
                f.neg2ll <= base_ll + 0.01,
                "{}: {} vs {base_ll}",
                v.name,
                f.neg2ll
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 5, "every nested extension of the catalogue");
}

/// A hierarchical fit ends at its rounds' optimum, not where an over-damped first step stopped
/// a round: from the data's initial guess, the fit with the default initial damping ends no
/// more than 0.5 in −2 ln L above the same fit started with a damping of 1e-9 (which cannot
/// take a first step too short to count), on 12 generated sets of the specimens world (fresh
/// seeds 158001–158012, first run for this test). Before the rounds carried their damping,
/// every round after the first ended after one iteration as `converged_step` and the fit
/// ended up to 22.9 above (73 of 100 sets, seeds 131001–131100, by more than 0.1).
#[test]
fn a_hierarchical_fits_rounds_refit_after_every_scatter_step() {
    let dir = tempfile::TempDir::new().unwrap();
    let mut gaps = vec![];
    for seed in 158001..=158012u64 {
        let (_, cfg) = generated_set(dir.path(), &format!("set-{seed}"), "none", seed);
        let curves = binned_curves(&cfg);
        let model = cfg.build_model().unwrap();
        let sp = cfg.space();
        let settings = FitSettings::from_config(&cfg);
        let opts = MlOptions {
            specimen: SpecimenOptions::BOTH,
            ..MlOptions::default()
        };
        let x0 = creepfit::model::guess::initial_guess(
            model.as_ref(),
            &curves,
            &sp,
            settings.omega_f,
            &settings.ode,
        )
        .params;
        let fit = ml_fit(model.as_ref(), &curves, &sp, &x0, &settings, &opts);
        let small = FitSettings {
            lm: LmOptions {
                lambda0: 1e-9,
                ..settings.lm
            },
            ..settings
        };
        let reference = ml_fit(model.as_ref(), &curves, &sp, &x0, &small, &opts);
        assert!(fit.ok() && reference.ok(), "set-{seed}: a fit failed");
        gaps.push((seed, fit.neg2ll - reference.neg2ll));
    }
    eprintln!("−2 ln L above the small-damping fit: {gaps:?}");
    for (seed, gap) in gaps {
        assert!(gap <= 0.5, "set-{seed}: the fit ends {gap:.2} above");
    }
}

/// A calibration replicate's refit starts also where the replicate was drawn: the new
/// specimens' effects at the reference's constants ([`creepfit::uncertainty::Context::on_drawn`]),
/// besides the reference with every effect at zero ([`creepfit::uncertainty::Context::on`]);
/// [`creepfit::uncertainty::refit_replicate`] keeps the lower. Measured on Alloy 617 at
/// 950 °C (docs/UNCERTAINTY.md): refits from zero effects stopped 190–276 above the
/// replicate's optimum in 3 of 20 replicates.
#[test]
fn a_bootstrap_replicate_is_refitted_from_where_it_was_drawn_too() {
    let model = registry("khd").unwrap();
    let curves = six_specimens(model.as_ref(), 4242);
    let (ctx, reference) = hierarchical_reference(model.as_ref(), &curves);
    for r in 0..8 {
        let mut rng = creepfit::diagnose::bootstrap::replicate_rng(5, 11, r);
        let (data, drawn) = creepfit::uncertainty::replicate(&ctx, &reference, &mut rng);
        let drawn = drawn.expect("a hierarchical replicate has drawn effects");
        // The contexts start their fits where they say.
        let zero = ctx.on(&data);
        let at = ctx.on_drawn(&data, Some(&drawn), &reference.params);
        let z = zero.effect_start().unwrap();
        assert!(z.effects.iter().flatten().all(|&v| v == 0.0));
        assert_eq!(at.effect_start().unwrap().effects, drawn.effects);
        assert!(drawn.effects.iter().flatten().any(|&v| v != 0.0));
        let fz = zero.fit(&zero.space, &reference.params, true);
        let fd = at.fit(&at.space, &reference.params, true);
        let best = creepfit::uncertainty::refit_replicate(&ctx, &reference, &data, Some(&drawn))
            .expect("a refit succeeds");
        let lower = fz.neg2ll.min(fd.neg2ll);
        assert!(
            (best.neg2ll - lower).abs() < 1e-6,
            "replicate {r}: kept {} of {} (zero) and {} (drawn)",
            best.neg2ll,
            fz.neg2ll,
            fd.neg2ll
        );
    }
    // (Measured with these seeds: the drawn start lower by 0.010 in replicate 5, the same
    // optimum in the others; a refit that ignored it fails the check above there.)
}

/// `fit`'s scaled polish of a hierarchical fit is repeated while a pass gains (more than
/// `POLISH_GAIN`): one pass of 8 rounds ended its rounds on plateaus where the damping had
/// climbed to 1e4–1e6 of the largest JᵀJ diagonal, hundreds above where further passes go.
/// Alloy 617 at 900 °C with three kinds of effects (measured 2026-11-29): −62024.1 after one
/// pass, −62641.0 after 8 (then a pass gains nothing); the check sits between, 41 above the
/// second, 576 below the first.
#[test]
fn fits_hierarchical_polish_goes_on_while_it_gains() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tmp = tempfile::TempDir::new().unwrap();
    let cfg = tmp.path().join("a900.toml");
    let text = std::fs::read_to_string(root.join("configs/alloy617-900C.toml"))
        .unwrap()
        .replace("../data/", &format!("{}/data/", root.display()));
    // Three kinds of specimen effects (the configuration's until 2026-12-02), under the
    // likelihood objective, their scatter the likelihood's own (the configuration's until
    // 2026-12-03; since, two kinds beyond the stress trend).
    let auto = "specimen_effects = \"auto\"\n";
    let beyond = "specimen_scatter = \"beyond_stress_trend\"\n";
    assert!(text.contains(auto) && text.contains(beyond));
    std::fs::write(
        &cfg,
        text.replace(auto, "").replace(beyond, "").replace(
            "[objective]\n",
            "[objective]\nkind = \"likelihood\"\nspecimen_effects = [\"rate\", \"ductility\", \"coarsening\"]\n",
        ),
    )
    .unwrap();
    let out = tmp.path().join("fit");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args([
            "fit",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let obj = s["objective"].as_f64().unwrap();
    assert!(obj < -62600.0, "−2 ln L {obj}");
}

/// `auto` without replicates, end to end through `fit`: Alloy 617 at 900 °C (seven
/// specimens, one per stress) under the likelihood. With the shipped estimate beyond the
/// stress trend the fit carries both kinds of factors (5 degrees of freedom beyond a level
/// and a line in ln σ) and its note says so and that none are replicates; with the
/// likelihood's own estimate it fits none and says why. Generated null sets of this design
/// fitted without factors raised false alarms where these did not (docs/SPECIMENS.md,
/// "Session 63").
#[test]
fn auto_fits_specimen_factors_without_replicates_only_beyond_the_stress_trend() {
    use common::{creepfit, json, root};
    let tmp = tempfile::TempDir::new().unwrap();
    let text = std::fs::read_to_string(root().join("configs/alloy617-900C.toml"))
        .unwrap()
        .replace("../data/", &format!("{}/data/", root().display()))
        .replace("[objective]\n", "[objective]\nkind = \"likelihood\"\n");
    let beyond = "specimen_scatter = \"beyond_stress_trend\"\n";
    assert!(text.contains(beyond) && text.contains("specimen_effects = \"auto\"\n"));
    let mut notes = Vec::new();
    for (name, cfg_text) in [
        ("beyond", text.clone()),
        (
            "likelihood",
            text.replace(beyond, "specimen_scatter = \"likelihood\"\n"),
        ),
    ] {
        let cfg = tmp.path().join(format!("{name}.toml"));
        std::fs::write(&cfg, cfg_text).unwrap();
        let out = tmp.path().join(name);
        let o = creepfit(&[
            "fit",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = json(&out.join("summary.json"));
        let sp = &s["specimens"];
        notes.push((
            sp["fitted"].as_bool().unwrap(),
            sp["note"].as_str().unwrap_or_default().to_string(),
        ));
    }
    let (fitted, note) = &notes[0];
    assert!(*fitted, "{note}");
    assert!(
        note.contains("(5 degrees of freedom at most)")
            && note.contains("0 of 7 specimens are replicates")
            && note.contains("no replicates)"),
        "{note}"
    );
    let (fitted, note) = &notes[1];
    assert!(!*fitted, "{note}");
    assert!(
        note.contains("treats every specimen as the population's"),
        "{note}"
    );
}

/// Beyond the stress trend, a base fit that puts every kind's scatter at zero is simplified:
/// the diagnosis goes on without specimen factors, as a mixed model's singular fit drops the
/// variance components estimated at zero, and it is then the diagnosis the default gives
/// (`specimen_scatter = "likelihood"` fits no factors without replicates), number for number.
/// The set: generated without specimen scatter (`synth --seed 189002 --scenario
/// constant_load`, the identical world), five specimens at 560 °C, one per stress, so `auto`
/// fits factors beyond the trend (3 degrees of freedom). Measured 2026-12-04 with the full
/// bootstrap: before the simplification the same set was diagnosed with factors whose
/// scatter went to zero, 2.7 times as long (65 s against 24 s on one thread), with other
/// p-values (constant_load 0.095 against 0.273).
#[test]
fn a_zero_scatter_beyond_the_trend_gives_the_diagnosis_without_factors() {
    use common::{creepfit, json};
    let tmp = tempfile::TempDir::new().unwrap();
    let dir = common::synth_set(tmp.path(), 189002, "constant_load");
    let text = std::fs::read_to_string(dir.join("config.toml")).unwrap();
    assert!(!text.contains("specimen_scatter"), "{text}");
    let mut runs = Vec::new();
    for (name, cfg_text) in [
        (
            "likelihood",
            format!("{text}\n[objective]\nspecimen_scatter = \"likelihood\"\n"),
        ),
        (
            "beyond",
            format!("{text}\n[objective]\nspecimen_scatter = \"beyond_stress_trend\"\n"),
        ),
    ] {
        let cfg = dir.join(format!("{name}.toml"));
        std::fs::write(&cfg, cfg_text).unwrap();
        let out = tmp.path().join(name);
        // Four starts per model instead of 16: the equality of two diagnoses, not the
        // multistart's reach (with 16: 83 s in 94ea3cc's CI, 69 s under nextest on 2026-12-05; the
        // data fits most of it).
        let o = creepfit(&[
            "diagnose",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--starts",
            "4",
            "--threads",
            "2",
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        runs.push((json(&out.join("diagnosis.json")), report));
    }
    let (plain, _) = &runs[0];
    let (beyond, report) = &runs[1];
    assert_eq!(plain["specimen_scatter_zero"], false);
    assert_eq!(beyond["specimen_scatter_zero"], true);
    assert!(beyond["base"]["specimen"].is_null());
    let first = beyond["decision"][0].as_str().unwrap();
    assert!(first.starts_with("Specimen factors:"), "{first}");
    assert!(
        report.contains("estimated their scatter beyond the stress trend at zero"),
        "{report}"
    );
    assert_eq!(beyond["verdict"], plain["verdict"]);
    assert_eq!(beyond["base"]["objective"], plain["base"]["objective"]);
    let (a, b) = (
        beyond["candidates"].as_array().unwrap(),
        plain["candidates"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x["name"], y["name"]);
        assert_eq!(x["lr"], y["lr"], "{}", x["name"]);
        assert_eq!(x["p_value"], y["p_value"], "{}", x["name"]);
        assert_eq!(x["null_replicates"], y["null_replicates"], "{}", x["name"]);
    }
}

/// `profile` and `predict --intervals` simplify a zero scatter beyond the stress trend as
/// `diagnose` does: the reference refitted without the factors `auto` chose, every profile of
/// the plain likelihood, so that the intervals are the likelihood estimate's byte for byte
/// and `summary.json` says so. The set is the identical world's 189002 (five specimens, one
/// per stress, no scatter). Measured 2026-12-04 before the simplification: the profile with
/// factors at zero scatter gave B's 95 % interval 0.17474–0.17479 where the plain likelihood
/// gives 0.1629–0.1910, and with the estimate beyond the trend as the default the 16-set
/// coverage battery of tests/profile.rs covered 76 of 102.
#[test]
fn a_zero_scatter_beyond_the_trend_gives_the_intervals_without_factors() {
    use common::{creepfit, json};
    let tmp = tempfile::TempDir::new().unwrap();
    let dir = common::synth_set(tmp.path(), 189002, "constant_load");
    let text = std::fs::read_to_string(dir.join("config.toml")).unwrap();
    let mut runs = Vec::new();
    for how in ["likelihood", "beyond_stress_trend"] {
        let cfg = dir.join(format!("{how}.toml"));
        std::fs::write(
            &cfg,
            // Ten calibration replicates, the fewest allowed (the default 20 is a threshold's
            // accuracy, not what is compared here).
            format!(
                "{text}\n[objective]\nspecimen_scatter = \"{how}\"\n[profile]\ncalibrate = 10\n"
            ),
        )
        .unwrap();
        let prof = tmp.path().join(format!("profile-{how}"));
        let o = creepfit(&[
            "profile",
            cfg.to_str().unwrap(),
            "--out",
            prof.to_str().unwrap(),
            "--threads",
            "2",
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let pred = tmp.path().join(format!("predict-{how}"));
        let o = creepfit(&[
            "predict",
            cfg.to_str().unwrap(),
            "--constants",
            prof.join("intervals.csv").to_str().unwrap(),
            "--at",
            "560:90",
            "--intervals",
            "--out",
            pred.to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        runs.push((prof, pred));
    }
    let read = |p: &std::path::Path| std::fs::read_to_string(p).unwrap();
    let ((p_lik, q_lik), (p_bey, q_bey)) = (&runs[0], &runs[1]);
    assert_eq!(
        json(&p_lik.join("summary.json"))["reference"]["without_specimen_factors"],
        false
    );
    assert_eq!(
        json(&p_bey.join("summary.json"))["reference"]["without_specimen_factors"],
        true
    );
    assert_eq!(
        read(&p_bey.join("intervals.csv")),
        read(&p_lik.join("intervals.csv"))
    );
    assert_eq!(
        read(&p_bey.join("profiles.csv")),
        read(&p_lik.join("profiles.csv"))
    );
    assert_eq!(
        json(&q_lik.join("summary.json"))["refit"]["without_specimen_factors"],
        false
    );
    assert_eq!(
        json(&q_bey.join("summary.json"))["refit"]["without_specimen_factors"],
        true
    );
    assert_eq!(
        read(&q_bey.join("predictions.csv")),
        read(&q_lik.join("predictions.csv"))
    );
}

/// A hierarchical profile whose reference sits at zero scatter is the profile of the model
/// without effects: the scatter is profiled out over [0, ∞), and at 0 the model is that of
/// identical specimens, which the hierarchical fit does not reach at its floor (its Laplace
/// log-determinant there is not zero). Set 189002 of the identical world (five specimens, one
/// per stress, no scatter) with both kinds named and the likelihood's own scatter estimate:
/// the multistart's best fit is the one without effects, and every profile point must come
/// back to it. Measured 2026-12-04 before the held fits took the boundary too: B's 68 %
/// interval 0.174737–0.174792 against its 95 % interval 0.1604–0.1957 (the held fits ended
/// above the 68 % threshold next to the optimum); the 68 % widths were 0.1–16 % of the 95 %
/// ones.
#[test]
fn a_hierarchical_profile_at_zero_scatter_is_the_profile_without_effects() {
    use common::{creepfit, json};
    let tmp = tempfile::TempDir::new().unwrap();
    let dir = common::synth_set(tmp.path(), 189002, "constant_load");
    let text = std::fs::read_to_string(dir.join("config.toml")).unwrap();
    let mut runs = Vec::new();
    for (name, effects) in [("named", "[\"rate\", \"ductility\"]"), ("plain", "[]")] {
        let cfg = dir.join(format!("{name}.toml"));
        std::fs::write(
            &cfg,
            format!(
                "{text}\n[objective]\nspecimen_effects = {effects}\nspecimen_scatter = \"likelihood\"\n[profile]\ncalibrate = 10\n"
            ),
        )
        .unwrap();
        let prof = tmp.path().join(name);
        let o = creepfit(&[
            "profile",
            cfg.to_str().unwrap(),
            "--out",
            prof.to_str().unwrap(),
            "--threads",
            "2",
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        runs.push(prof);
    }
    let (named, plain) = (&runs[0], &runs[1]);
    // The reference: the fit of identical specimens won the multistart.
    let s = json(&named.join("summary.json"));
    assert!(
        s["reference"]["specimen_effects"].is_null(),
        "{}",
        s["reference"]
    );
    assert_eq!(
        s["reference"]["neg2ll"],
        json(&plain.join("summary.json"))["reference"]["neg2ll"]
    );
    // Each side's points where both profiles held the same value: the same Δ(−2 ln L).
    let rows = |p: &std::path::Path| -> Vec<Vec<String>> {
        let mut r = csv::Reader::from_path(p.join("profiles.csv")).unwrap();
        r.records()
            .map(|x| x.unwrap().iter().map(String::from).collect())
            .collect()
    };
    let (a, b) = (rows(named), rows(plain));
    let f = |v: &str| v.parse::<f64>().unwrap();
    let (mut matched, mut total) = (0, 0);
    for name in ["A", "B", "Hstar", "h", "Kc", "C"] {
        for side in ["lower", "upper"] {
            let pick = |r: &[Vec<String>]| -> Vec<(f64, f64)> {
                r.iter()
                    .filter(|x| x[0] == name && x[1] == side && x[4] == "ok")
                    .map(|x| (f(&x[2]), f(&x[3])))
                    .collect()
            };
            let (pa, pb) = (pick(&a), pick(&b));
            assert!(!pa.is_empty(), "{name} {side}");
            let mut n = 0;
            for ((va, da), (vb, db)) in pa.iter().zip(&pb) {
                if (va - vb).abs() > 1e-6 * vb.abs() {
                    break;
                }
                assert!(
                    (da - db).abs() < 0.01,
                    "{name} {side} at {va}: Δ {da} against {db}"
                );
                n += 1;
            }
            assert!(n >= 1, "{name} {side}: no common point");
            matched += n;
            total += pa.len();
        }
    }
    // Where a step's Δ differs in its last digits the two continuations part; most points
    // are still common.
    assert!(2 * matched >= total, "{matched} of {total} points common");
    // And the intervals are regular: the 68 % one about half the 95 % one, as for a
    // quadratic profile (√(t68/t95) = 0.51 at these thresholds).
    let mut r = csv::Reader::from_path(named.join("intervals.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|c| c == n).unwrap();
    for x in r.records() {
        let x = x.unwrap();
        let g = |n: &str| f(&x[col(n)]);
        let ratio = (g("hi68") - g("lo68")) / (g("hi95") - g("lo95"));
        assert!((0.35..0.7).contains(&ratio), "{}: {ratio}", &x[0]);
    }
}
