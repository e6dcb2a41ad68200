//! Recovery: curves simulated from known constants, fitted from a start elsewhere in the
//! box, give the constants back (exactly without noise; stably with noise).

use creepfit::config::{LifetimeTerm, ObjectiveKind};
use creepfit::data::{estimate_min_rate, Curve};
use creepfit::fit::{local_fit, FitSettings};
use creepfit::lsq::LmOptions;
use creepfit::model::objective::{JacobianMethod, ParamSpace};
use creepfit::model::{registry, Load, Model, Scale};
use creepfit::ode::OdeOptions;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The paper's 560 °C box (Table 1).
fn space_560() -> ParamSpace {
    ParamSpace::new(
        vec![1e-10, 0.1, 0.4, 1e4, 1e-6, 3.0],
        vec![1e-9, 0.2, 0.8, 2e5, 3e-5, 10.0],
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

/// Irregularly sampled synthetic curves (like digitized ones) from `truth`, with Gaussian
/// noise of `noise` × rupture strain on every point but t = 0.
fn synth(
    model: &dyn Model,
    truth: &[f64],
    stresses: &[f64],
    n: usize,
    noise: f64,
    seed: u64,
) -> Vec<Curve> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let ode = OdeOptions {
        rtol: 1e-12,
        atol: 1e-15,
        ..OdeOptions::default()
    };
    stresses
        .iter()
        .map(|&s| {
            let load = Load {
                stress_mpa: s,
                temperature_k: 560.0 + creepfit::model::ZERO_CELSIUS_K,
                omega_f: 1.0 / 3.0,
            };
            let mut dummy = [];
            let r = model.simulate(truth, &load, &[], &mut dummy, &ode);
            assert!(r.ruptured());
            let mut times: Vec<f64> = (1..n)
                .map(|k| {
                    let f = (k as f64 + rng.gen_range(-0.4..0.4)) / n as f64;
                    r.t_end * (1.0 - (1.0 - f).powf(1.5))
                })
                .collect();
            times.insert(0, 0.0);
            times.sort_by(|a, b| a.total_cmp(b));
            let mut strain = vec![0.0; times.len()];
            let r2 = model.simulate(truth, &load, &times, &mut strain, &ode);
            assert_eq!(r2.n_out, times.len());
            for e in strain.iter_mut().skip(1) {
                let z: f64 = rng.sample(rand_distr_normal());
                *e += noise * r.strain_end * z;
            }
            Curve {
                temperature_c: 560.0,
                stress_mpa: s,
                specimen: None,
                groups: None,
                min_rate_estimated: estimate_min_rate(&times, &strain, r.t_end),
                times_h: times,
                strains: strain,
                rupture_time_h: Some(r.t_end),
                rupture_strain: r.strain_end,
                min_rate_measured: Some(r.min_rate),
            }
        })
        .collect()
}

/// Standard normal by Box–Muller (keeps the test free of extra crates).
fn rand_distr_normal() -> impl rand::distributions::Distribution<f64> {
    struct N;
    impl rand::distributions::Distribution<f64> for N {
        fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
            let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
            let u2: f64 = rng.gen();
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
    }
    N
}

fn settings() -> FitSettings {
    FitSettings {
        lm: LmOptions {
            max_iterations: 3000,
            ..LmOptions::default()
        },
        ode: OdeOptions::default(),
        omega_f: 1.0 / 3.0,
        lifetime: LifetimeTerm::Both,
        jacobian: JacobianMethod::default(),
        kind: ObjectiveKind::Eq8,
        lifetime_sd_floor: 0.01,
    }
}

/// A start displaced by `shift` in every unit-box coordinate (alternating sign).
fn displaced(space: &ParamSpace, truth: &[f64], shift: f64) -> Vec<f64> {
    let u: Vec<f64> = space
        .to_unit(truth)
        .iter()
        .enumerate()
        .map(|(j, u)| {
            let s = if j % 2 == 0 { shift } else { -shift };
            let v = u + s;
            if (0.02..=0.98).contains(&v) {
                v
            } else {
                u - s
            }
        })
        .collect();
    let mut x = truth.to_vec();
    space.from_unit(&u, &mut x);
    x
}

#[test]
fn recovers_constants_without_noise() {
    let model = registry("khd").unwrap();
    let space = space_560();
    for (truth, stresses, seed) in [
        (
            vec![4e-10, 0.12, 0.55, 6e4, 8e-6, 5.0],
            vec![85.0, 100.0, 110.0],
            1u64,
        ),
        (
            vec![2.5e-10, 0.15, 0.62, 3e4, 1.5e-5, 4.2],
            vec![80.0, 95.0, 105.0, 120.0],
            2,
        ),
    ] {
        let curves = synth(model.as_ref(), &truth, &stresses, 36, 0.0, seed);
        let start = displaced(&space, &truth, 0.12);
        let fit = local_fit(
            model.as_ref(),
            &curves,
            &space,
            &vec![1.0; curves.len()],
            &start,
            "test",
            &settings(),
        );
        assert!(fit.lm.termination.converged(), "{:?}", fit.lm);
        for (j, (got, want)) in fit.params.iter().zip(&truth).enumerate() {
            let rel = (got - want).abs() / want;
            assert!(
                rel < 1e-4,
                "constant {j}: {got} vs {want} (rel {rel:e}); start {start:?}"
            );
        }
        assert!(fit.eval.objective < 1e-12, "{}", fit.eval.objective);
    }
}

#[test]
fn noisy_fit_is_stable_and_reports_its_error() {
    let model = registry("khd").unwrap();
    let space = space_560();
    let truth = vec![4e-10, 0.12, 0.55, 6e4, 8e-6, 5.0];
    let stresses = [85.0, 100.0, 110.0];
    let noise = 0.01; // 1 % of the rupture strain, like careful digitizing
    let mut errs = Vec::new();
    for seed in [11u64, 12, 13] {
        let curves = synth(model.as_ref(), &truth, &stresses, 36, noise, seed);
        let start = displaced(&space, &truth, 0.12);
        let fit = local_fit(
            model.as_ref(),
            &curves,
            &space,
            &[1.0; 3],
            &start,
            "test",
            &settings(),
        );
        eprintln!(
            "seed {seed}: {:?} after {} iterations, {} evaluations, F = {}",
            fit.lm.termination, fit.lm.iterations, fit.lm.evaluations, fit.eval.objective
        );
        assert!(fit.lm.termination.converged(), "{:?}", fit.lm.termination);
        // At the minimum the residual is the noise: Σ r² ≈ m σ² (σ = noise in units of ε_f).
        let m = curves.iter().map(|c| c.times_h.len() - 1).sum::<usize>() as f64;
        let expected = m * noise * noise;
        assert!(
            fit.eval.norm_residual < 1.5 * expected,
            "{} vs {expected}",
            fit.eval.norm_residual
        );
        assert!(fit.eval.norm_residual > 0.3 * expected);
        // Lifetimes are predicted within a few %, and C within 15 %.
        for e in &fit.lifetime_err_pct {
            assert!(e.abs() < 5.0, "lifetime error {e} %");
        }
        let c_err = (fit.params[5] - truth[5]).abs() / truth[5];
        assert!(c_err < 0.15, "C error {c_err}");
        // B and H* slide along a ridge (DESIGN.md §7); their combination S = B(1 − H*), which
        // sets the minimum creep rate's stress dependence, stays determined.
        let s = |p: &[f64]| p[1] * (1.0 - p[2]);
        let s_err = (s(&fit.params) - s(&truth)).abs() / s(&truth);
        assert!(s_err < 0.10, "B(1-H*) error {s_err}");
        errs.push(
            fit.params
                .iter()
                .zip(&truth)
                .map(|(p, t)| (p - t) / t)
                .collect::<Vec<_>>(),
        );
    }
    eprintln!("relative constant errors with 1 % noise (A, B, H*, h, Kc, C):");
    for e in &errs {
        eprintln!(
            "  {:?}",
            e.iter().map(|v| format!("{:+.3}", v)).collect::<Vec<_>>()
        );
    }
}

/// Every extension: curves simulated with the extension switched on and its extra constant at
/// a realistic size are fitted with the same extended model from a displaced start and give
/// back all constants, the extra one included (no noise).
#[test]
fn recovers_extension_constants_without_noise() {
    let truth_base = vec![4e-10, 0.12, 0.55, 6e4, 8e-6, 5.0];
    // (extension, [(true value, lb, ub, scale)] of its constants)
    let lin = Scale::Linear;
    for (ext, extra) in [
        ("constant_load", vec![]),
        ("loading_strain", vec![(8e4, 1e3, 1e7, Scale::Log)]),
        ("dislocation_damage", vec![(6.0, 0.0, 50.0, lin)]),
        ("stress_ductility", vec![(1.5, -10.0, 10.0, lin)]),
        // φ0 (ε/0.2)^φ1 = 8·(ε/0.2)² doubles the rate at the rupture strain ω_f/C ≈ 0.067.
        (
            "strain_softening",
            vec![(8.0, 0.0, 40.0, lin), (2.0, 0.5, 8.0, lin)],
        ),
        ("rupture_damage", vec![(0.45, 0.05, 0.9, lin)]),
        // sinh(x)^1.5: the rate's stress exponent half as large again.
        ("garofalo", vec![(1.5, 0.5, 12.0, lin)]),
    ] {
        let model = creepfit::model::build("khd", &[ext.to_string()]).unwrap();
        let mut space = space_560();
        let mut truth = truth_base.clone();
        for (v, lb, ub, scale) in extra {
            space.lb.push(lb);
            space.ub.push(ub);
            space.scale.push(scale);
            space.fixed.push(lb);
            space.free.push(true);
            truth.push(v);
        }
        let curves = synth(model.as_ref(), &truth, &[85.0, 100.0, 110.0], 36, 0.0, 5);
        let start = displaced(&space, &truth, 0.08);
        let fit = local_fit(
            model.as_ref(),
            &curves,
            &space,
            &[1.0; 3],
            &start,
            "test",
            &settings(),
        );
        assert!(fit.lm.termination.converged(), "{ext}: {:?}", fit.lm);
        for (j, (got, want)) in fit.params.iter().zip(&truth).enumerate() {
            let rel = (got - want).abs() / want.abs();
            assert!(
                rel < 1e-4,
                "{ext}: constant {j}: {got} vs {want} (rel {rel:e})"
            );
        }
    }
}
