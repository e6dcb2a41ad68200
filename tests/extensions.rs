//! The extension catalogue (DESIGN.md §6): each extension reduces to the base model when
//! switched off, and its one-state composition matches the extension's defining equations
//! integrated as written (a test-local multi-state model), or a closed form.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use creepfit::dual::Scalar;
use creepfit::model::ext::off_value;
use creepfit::model::{build, registry, CreepModel, Load, Model};
use creepfit::ode::{integrate, OdeOptions};

const BASE: [f64; 6] = [1.0e-10, 0.1283, 0.4049, 3.195e4, 2.222e-5, 4.043];
const OMEGA_F: f64 = 1.0 / 3.0;

fn tight() -> OdeOptions {
    OdeOptions {
        rtol: 1e-12,
        atol: 1e-15,
        ..OdeOptions::default()
    }
}

fn load(sigma: f64) -> Load {
    Load {
        stress_mpa: sigma,
        temperature_k: 560.0 + creepfit::model::ZERO_CELSIUS_K,
        omega_f: OMEGA_F,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Rupture time and strains at `times` of a model.
fn run(m: &dyn Model, x: &[f64], sigma: f64, times: &[f64]) -> (f64, f64, Vec<f64>) {
    let mut out = vec![f64::NAN; times.len()];
    let r = m.simulate(x, &load(sigma), times, &mut out, &tight());
    assert!(r.ruptured(), "{:?}", r.outcome);
    (r.t_end, r.strain_end, out)
}

fn ext(names: &[&str]) -> Box<dyn Model> {
    build(
        "khd",
        &names.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
    )
    .unwrap()
}

fn times(t_end: f64) -> Vec<f64> {
    (0..40).map(|k| t_end * 0.98 * k as f64 / 39.0).collect()
}

#[test]
fn every_extension_switched_off_is_the_base_model() {
    let base = registry("khd1").unwrap();
    // E_L = ∞ (no loading strain), C_d = 0 (no multiplication), ν = 0 (no stress dependence),
    // φ0 = 0 (no softening, whatever φ1), ω_f = 1/3 (the load's damage at rupture).
    let all = ext(&[
        "loading_strain",
        "dislocation_damage",
        "stress_ductility",
        "strain_softening",
        "rupture_damage",
    ]);
    assert_eq!(
        all.constants().iter().map(|c| c.name).collect::<Vec<_>>(),
        ["A", "B", "Hstar", "h", "Kc", "C", "EL", "Cd", "nu", "phi0", "phi1", "omegaf"]
    );
    let mut x = BASE.to_vec();
    x.extend([f64::INFINITY, 0.0, 0.0, 0.0, 2.7, OMEGA_F]);
    for sigma in [85.0, 110.0] {
        let (t0, e0, _) = run(base.as_ref(), &BASE, sigma, &[]);
        let ts = times(t0);
        let (_, _, s0) = run(base.as_ref(), &BASE, sigma, &ts);
        let (t1, e1, s1) = run(all.as_ref(), &x, sigma, &ts);
        assert!(rel(t1, t0) < 1e-12, "{t1} vs {t0}");
        assert!(rel(e1, e0) < 1e-12);
        for k in 1..ts.len() {
            assert!(rel(s1[k], s0[k]) < 1e-12, "{} vs {}", s1[k], s0[k]);
        }
        // Each one alone, switched off.
        for (name, v) in [
            ("loading_strain", vec![f64::INFINITY]),
            ("dislocation_damage", vec![0.0]),
            ("stress_ductility", vec![0.0]),
            ("strain_softening", vec![0.0, 0.6]),
            ("strain_softening", vec![0.0, 7.5]),
            ("rupture_damage", vec![OMEGA_F]),
            ("garofalo", vec![1.0]),
        ] {
            let mut x1 = BASE.to_vec();
            x1.extend(&v);
            let (t, e, s) = run(ext(&[name]).as_ref(), &x1, sigma, &ts);
            assert!(rel(t, t0) < 1e-12, "{name}: {t} vs {t0}");
            assert!(rel(e, e0) < 1e-12, "{name}: {e} vs {e0}");
            for k in 1..ts.len() {
                assert!(rel(s[k], s0[k]) < 1e-12, "{name}: {} vs {}", s[k], s0[k]);
            }
        }
        // The off values the catalogue gives (diagnose's nested start) are these.
        assert_eq!(off_value("phi0", 0.0, 200.0), Some(0.0));
        assert_eq!(off_value("phi1", 0.5, 8.0), None);
        assert_eq!(off_value("omegaf", 0.05, 0.9), Some(OMEGA_F));
        assert_eq!(off_value("nG", 0.5, 12.0), Some(1.0));
    }
    // constant_load has no constant: it changes the prediction, and only in the direction
    // physics says (the true stress rises, so the life shortens).
    let (tc, _, _) = run(ext(&["constant_load"]).as_ref(), &BASE, 100.0, &[]);
    let (tb, _, _) = run(base.as_ref(), &BASE, 100.0, &[]);
    assert!(tc < tb * 0.99, "{tc} vs {tb}");
}

/// The defining equations of `constant_load`, `dislocation_damage` and `strain_softening`
/// integrated as written: state [ε, H, Φ, ω, D] with σ = σ0(1+ε) in the rate and in dH/dt,
/// and the rate multiplied by 1/(1−D), dD/dt = C_d (1−D)² dε/dt, and by 1 + k ε^φ1 with
/// k = φ0/0.2^φ1 (Walker's prefactor form and a power, not the extension's
/// exp(φ1 ln(ε/0.2))), and Garofalo's sinh(x)^n_G as a power (not the extension's factor
/// exp((n_G − 1) ln sinh x) on the rate).
struct Defining {
    constant_load: bool,
    c_d: f64,
    soft: (f64, f64),
    n_g: f64,
}

impl Defining {
    fn plain() -> Defining {
        Defining {
            constant_load: false,
            c_d: 0.0,
            soft: (0.0, 1.0),
            n_g: 1.0,
        }
    }
}

#[derive(Clone, Copy)]
struct Pr<S> {
    x: [S; 6],
    sigma: f64,
    c_d: f64,
}

impl CreepModel<5> for Defining {
    type Prepared<S: Scalar> = Pr<S>;
    fn prepare<S: Scalar>(&self, params: &[S], load: &Load) -> Pr<S> {
        Pr {
            x: [
                params[0], params[1], params[2], params[3], params[4], params[5],
            ],
            sigma: load.stress_mpa,
            c_d: self.c_d,
        }
    }
    fn init<S: Scalar>(&self, _p: &Pr<S>) -> [S; 5] {
        [S::cst(0.0); 5]
    }
    fn rhs<S: Scalar>(&self, p: &Pr<S>, _t: S, y: &[S; 5], dy: &mut [S; 5]) -> bool {
        let [a, b, hs, h, kc, c] = p.x;
        let [eps, hard, phi, om, d] = *y;
        let sig = if self.constant_load {
            (eps + 1.0) * p.sigma
        } else {
            S::cst(p.sigma)
        };
        let denom = (S::cst(1.0) - phi) * (S::cst(1.0) - om);
        if !(denom.re() > 0.0) || !(d.re() < 1.0) {
            return false;
        }
        let arg = b * sig * (S::cst(1.0) - hard) / denom;
        if !(arg.re().abs() < 200.0) {
            return false;
        }
        // Walker's Φ = 1 + k ε^φ1 with the prefactor k = φ0/ε_ref^φ1 (ε_ref = 0.2): the
        // extension's φ0 is the rate's increase at 20 % strain.
        let (p0, p1) = self.soft;
        let soft = if eps.re() > 0.0 {
            eps.powf(p1) * (p0 / 0.2f64.powf(p1)) + 1.0
        } else {
            S::cst(1.0)
        };
        let sinh = if self.n_g == 1.0 {
            arg.sinh()
        } else {
            arg.sinh().powf(self.n_g)
        };
        let rate = a * sinh / (S::cst(1.0) - d) * soft;
        dy[0] = rate;
        dy[1] = h / sig * rate * (S::cst(1.0) - hard / hs);
        let q = S::cst(1.0) - phi;
        dy[2] = kc / 3.0 * q * q * q * q;
        dy[3] = c * rate;
        dy[4] = (S::cst(1.0) - d) * (S::cst(1.0) - d) * rate * p.c_d;
        true
    }
    fn event<S: Scalar>(&self, _p: &Pr<S>, y: &[S; 5]) -> S {
        y[3] - OMEGA_F
    }
    fn event_rate<S: Scalar>(&self, _p: &Pr<S>, _y: &[S; 5], dy: &[S; 5]) -> S {
        dy[3]
    }
    fn strain<S: Scalar>(&self, _p: &Pr<S>, y: &[S; 5]) -> S {
        y[0]
    }
    fn strain_rate<S: Scalar>(&self, _p: &Pr<S>, _y: &[S; 5], dy: &[S; 5]) -> S {
        dy[0]
    }
    fn state_names(&self) -> [&'static str; 5] {
        ["strain", "H", "Phi", "omega", "D"]
    }
}

fn defining(def: &Defining, sigma: f64, ts: &[f64]) -> (f64, Vec<f64>) {
    let p = def.prepare(&BASE, &load(sigma));
    let mut out = vec![f64::NAN; ts.len()];
    let r = integrate(def, &p, ts, &tight(), |k, _, y| out[k] = y[0]);
    assert!(r.ruptured());
    (r.t_end, out)
}

#[test]
fn constant_load_matches_its_defining_equations() {
    let m = ext(&["constant_load"]);
    let def = Defining {
        constant_load: true,
        ..Defining::plain()
    };
    for sigma in [85.0, 100.0, 120.0] {
        let (t_ref, _) = defining(&def, sigma, &[]);
        let ts = times(t_ref);
        let (_, s_ref) = defining(&def, sigma, &ts);
        let (t, _, s) = run(m.as_ref(), &BASE, sigma, &ts);
        assert!(rel(t, t_ref) < 1e-8, "{sigma} MPa: {t} vs {t_ref}");
        for k in 1..ts.len() {
            assert!(rel(s[k], s_ref[k]) < 1e-8, "{} vs {}", s[k], s_ref[k]);
        }
    }
}

#[test]
fn dislocation_damage_matches_its_defining_equations() {
    for c_d in [2.0, 15.0] {
        let m = ext(&["dislocation_damage"]);
        let def = Defining {
            c_d,
            ..Defining::plain()
        };
        let mut x = BASE.to_vec();
        x.push(c_d);
        for sigma in [85.0, 110.0] {
            let (t_ref, _) = defining(&def, sigma, &[]);
            let ts = times(t_ref);
            let (_, s_ref) = defining(&def, sigma, &ts);
            let (t, _, s) = run(m.as_ref(), &x, sigma, &ts);
            assert!(
                rel(t, t_ref) < 1e-8,
                "Cd {c_d}, {sigma} MPa: {t} vs {t_ref}"
            );
            for k in 1..ts.len() {
                assert!(rel(s[k], s_ref[k]) < 1e-8);
            }
        }
    }
}

#[test]
fn loading_strain_is_stress_over_modulus_added_to_the_creep_curve() {
    let base = registry("khd1").unwrap();
    let m = ext(&["loading_strain"]);
    let e_l = 1.5e5;
    let mut x = BASE.to_vec();
    x.push(e_l);
    for sigma in [85.0, 110.0] {
        let (t0, _, _) = run(base.as_ref(), &BASE, sigma, &[]);
        let ts = times(t0);
        let (_, _, s0) = run(base.as_ref(), &BASE, sigma, &ts);
        let (t, e_r, s) = run(m.as_ref(), &x, sigma, &ts);
        assert!(rel(t, t0) < 1e-12, "the life does not change");
        assert_eq!(s[0], sigma / e_l, "strain at t = 0");
        for k in 0..ts.len() {
            assert!((s[k] - (s0[k] + sigma / e_l)).abs() < 1e-14);
        }
        assert!(rel(e_r, OMEGA_F / BASE[5] + sigma / e_l) < 1e-9);
    }
}

#[test]
fn stress_ductility_sets_rupture_strain_by_its_power_law() {
    let m = ext(&["stress_ductility"]);
    for nu in [-2.0, 1.5] {
        let mut x = BASE.to_vec();
        x.push(nu);
        for sigma in [85.0, 100.0, 120.0] {
            let (_, e_r, _) = run(m.as_ref(), &x, sigma, &[]);
            let expected = OMEGA_F / (BASE[5] * (sigma / 100.0f64).powf(nu));
            assert!(
                rel(e_r, expected) < 1e-9,
                "ν {nu}, {sigma} MPa: {e_r} vs {expected}"
            );
        }
    }
}

#[test]
fn unknown_or_misapplied_extensions_are_errors() {
    assert!(build("khd", &["nope".to_string()]).is_err());
    assert!(build("khd4", &["constant_load".to_string()]).is_err());
}

#[test]
fn strain_softening_matches_its_defining_equations() {
    let m = ext(&["strain_softening"]);
    for (p0, p1) in [(40.0, 2.0), (8.0, 0.7), (150.0, 3.5)] {
        let def = Defining {
            soft: (p0, p1),
            ..Defining::plain()
        };
        let mut x = BASE.to_vec();
        x.extend([p0, p1]);
        for sigma in [85.0, 110.0] {
            let (t_ref, _) = defining(&def, sigma, &[]);
            let ts = times(t_ref);
            let (_, s_ref) = defining(&def, sigma, &ts);
            let (t, e_r, s) = run(m.as_ref(), &x, sigma, &ts);
            assert!(
                rel(t, t_ref) < 1e-8,
                "φ {p0} {p1}, {sigma} MPa: {t} vs {t_ref}"
            );
            for k in 1..ts.len() {
                assert!(rel(s[k], s_ref[k]) < 1e-8, "{} vs {}", s[k], s_ref[k]);
            }
            // Softening speeds the curve up; rupture still at ω = Cε = ω_f.
            let (t0, _, _) = run(registry("khd1").unwrap().as_ref(), &BASE, sigma, &[]);
            assert!(t < t0, "{t} vs {t0}");
            assert!(rel(e_r, OMEGA_F / BASE[5]) < 1e-9);
        }
    }
}

/// Garofalo's A·sinh(x)^n_G integrated as written, with and without constant load; a larger
/// n_G at x > 1 shortens the life (the rate grows by sinh(x)^(n_G − 1) > 1).
#[test]
fn garofalo_matches_its_defining_equations() {
    for constant_load in [false, true] {
        let names: &[&str] = if constant_load {
            &["constant_load", "garofalo"]
        } else {
            &["garofalo"]
        };
        let m = ext(names);
        let mut last = f64::INFINITY;
        for n_g in [0.8, 1.3, 2.0] {
            let def = Defining {
                constant_load,
                n_g,
                ..Defining::plain()
            };
            let mut x = BASE.to_vec();
            x.push(n_g);
            let sigma = 100.0;
            let (t_ref, _) = defining(&def, sigma, &[]);
            let ts = times(t_ref);
            let (_, s_ref) = defining(&def, sigma, &ts);
            let (t, e_r, s) = run(m.as_ref(), &x, sigma, &ts);
            assert!(rel(t, t_ref) < 1e-8, "n_G {n_g}: {t} vs {t_ref}");
            for k in 1..ts.len() {
                assert!(rel(s[k], s_ref[k]) < 1e-8, "{} vs {}", s[k], s_ref[k]);
            }
            assert!(t < last, "n_G {n_g}: {t} vs {last}");
            last = t;
            if !constant_load {
                assert!(rel(e_r, OMEGA_F / BASE[5]) < 1e-9);
            }
        }
    }
}

/// A free ω_f is the base model with the load's ω_f set to it: the same curves and rupture,
/// and the rupture strain ω_f/C exactly (ω_f/(C k_σ) with `stress_ductility`).
#[test]
fn rupture_damage_is_the_base_model_at_that_omega_f() {
    let base = registry("khd1").unwrap();
    let m = ext(&["rupture_damage"]);
    for omega_f in [0.12, 0.5, 0.6] {
        let mut x = BASE.to_vec();
        x.push(omega_f);
        for sigma in [85.0, 110.0] {
            let at = Load {
                omega_f,
                ..load(sigma)
            };
            let mut none: [f64; 0] = [];
            let r0 = base.simulate(&BASE, &at, &[], &mut none, &tight());
            assert!(
                r0.ruptured(),
                "ω_f {omega_f}, {sigma} MPa: {:?}",
                r0.outcome
            );
            let ts = times(r0.t_end);
            let mut s0 = vec![f64::NAN; ts.len()];
            base.simulate(&BASE, &at, &ts, &mut s0, &tight());
            // `run` uses the load's ω_f = 1/3: the extension's constant replaces it.
            let (t, e_r, s) = run(m.as_ref(), &x, sigma, &ts);
            assert!(rel(t, r0.t_end) < 1e-12, "{t} vs {}", r0.t_end);
            for k in 1..ts.len() {
                assert!(rel(s[k], s0[k]) < 1e-12);
            }
            assert!(rel(e_r, omega_f / BASE[5]) < 1e-9, "{e_r}");
        }
    }
    let m2 = ext(&["stress_ductility", "rupture_damage"]);
    let (nu, omega_f) = (1.5, 0.6);
    let mut x = BASE.to_vec();
    x.extend([nu, omega_f]);
    for sigma in [85.0, 120.0] {
        let (_, e_r, _) = run(m2.as_ref(), &x, sigma, &[]);
        let want = omega_f / (BASE[5] * (sigma / 100.0f64).powf(nu));
        assert!(rel(e_r, want) < 1e-9, "{e_r} vs {want}");
    }
}

/// The rupture time's sensitivity to ω_f through the event function: g = Cε − ω_f, so
/// dt_r/dω_f = 1/(C ε̇(t_r)) and dε_r/dω_f = 1/C exactly.
#[test]
fn rupture_time_sensitivity_to_omega_f_is_the_event_rate() {
    use creepfit::dual::{Dual, SENS};
    let m = ext(&["rupture_damage"]);
    for (omega_f, sigma) in [(0.2, 100.0), (0.6, 90.0)] {
        let mut x: Vec<Dual<SENS>> = BASE.iter().map(|v| Dual::cst(*v)).collect();
        x.push(Dual::var(omega_f, 0, 1.0));
        let r = m.simulate_sens(&x, &load(sigma), &[], &mut [], &tight());
        assert!(r.ruptured());
        let dt = r.t_end.grad(0);
        let want = 1.0 / (BASE[5] * r.rate_end.re());
        assert!(rel(dt, want) < 1e-9, "{dt} vs {want}");
        assert!(rel(r.strain_end.grad(0), 1.0 / BASE[5]) < 1e-9);
        // And against a central difference of the plain simulation. The step is 1e-5: at
        // 0.6 the rupture time hardly moves with ω_f (dt_r/dω_f = 0.23 h on t_r = 74,473 h),
        // and at 1e-6 the two runs' difference (4.6e-7 h) is within the jitter of their
        // integration errors at rtol 1e-12 (up to 7e-8 h): the difference quotient moved by
        // 2.8e-5 when the step-size controller changed (session 83). At 1e-5 it agrees to
        // 1e-8, with O(h²) truncation below that.
        let h = 1e-5;
        let t_at = |w: f64| {
            let mut xp = BASE.to_vec();
            xp.push(w);
            run(m.as_ref(), &xp, sigma, &[]).0
        };
        let fd = (t_at(omega_f + h) - t_at(omega_f - h)) / (2.0 * h);
        assert!(rel(dt, fd) < 1e-5, "{dt} vs {fd}");
    }
}

/// Noise-free curves of `model` at `x` (36 points each, to 95 % of life).
fn curves_of(model: &dyn Model, x: &[f64], stresses: &[f64]) -> Vec<creepfit::data::Curve> {
    stresses
        .iter()
        .map(|&s| {
            let (t_r, e_r, _) = run(model, x, s, &[]);
            let ts: Vec<f64> = (0..36).map(|k| t_r * 0.95 * k as f64 / 35.0).collect();
            let (_, _, strain) = run(model, x, s, &ts);
            creepfit::data::Curve {
                temperature_c: 560.0,
                stress_mpa: s,
                specimen: None,
                groups: None,
                min_rate_estimated: creepfit::data::estimate_min_rate(&ts, &strain, t_r),
                times_h: ts,
                strains: strain,
                rupture_time_h: Some(t_r),
                rupture_strain: e_r,
                min_rate_measured: None,
            }
        })
        .collect()
}

/// The Jacobian by forward sensitivities (dual numbers through the integrator, the rupture
/// time through the event function) against central differences, column by column, for the
/// new extensions alone and composed (8 constants: the narrow dual numbers; 10: the wide).
#[test]
fn sensitivity_jacobian_of_new_extensions_matches_central_differences() {
    use creepfit::fit::FitSettings;
    use creepfit::lsq::LeastSquaresProblem;
    use creepfit::model::objective::{
        CreepProblem, JacobianMethod, Objective, ObjectiveSettings, ParamSpace,
    };
    use creepfit::model::Scale;
    use nalgebra::DMatrix;
    let cfg = creepfit::config::RunConfig::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/560C.toml"),
    )
    .unwrap();
    let base_lb = [2e-11, 0.08, 0.2, 1e4, 5e-6, 2.0];
    let base_ub = [5e-9, 0.2, 0.7, 2e5, 1e-4, 8.0];
    let base_sc = [
        Scale::Log,
        Scale::Linear,
        Scale::Linear,
        Scale::Log,
        Scale::Log,
        Scale::Linear,
    ];
    // (extensions, their constants' truth, lb, ub)
    type Case<'a> = (&'a [&'a str], Vec<f64>, Vec<f64>, Vec<f64>);
    let cases: [Case; 4] = [
        (&["garofalo"], vec![1.5], vec![0.5], vec![12.0]),
        (
            &["strain_softening"],
            vec![30.0, 2.0],
            vec![0.0, 0.5],
            vec![200.0, 8.0],
        ),
        (&["rupture_damage"], vec![0.45], vec![0.05], vec![0.9]),
        (
            &[
                "constant_load",
                "dislocation_damage",
                "strain_softening",
                "rupture_damage",
            ],
            vec![3.0, 30.0, 2.0, 0.45],
            vec![0.0, 0.0, 0.5, 0.05],
            vec![50.0, 200.0, 8.0, 0.9],
        ),
    ];
    for (names, extra, lb_e, ub_e) in cases {
        let model = ext(names);
        let mut x = BASE.to_vec();
        x.extend(&extra);
        let mut lb = base_lb.to_vec();
        lb.extend(&lb_e);
        let mut ub = base_ub.to_vec();
        ub.extend(&ub_e);
        let mut sc = base_sc.to_vec();
        sc.extend(vec![Scale::Linear; extra.len()]);
        let space = ParamSpace::new(lb, ub, sc);
        let curves = curves_of(model.as_ref(), &x, &[85.0, 100.0, 115.0]);
        let settings = ObjectiveSettings {
            ode: tight(),
            ..FitSettings::from_config(&cfg).objective()
        };
        let problem = CreepProblem {
            objective: Objective::new(model.as_ref(), &curves, vec![0.5; 3], settings),
            space: space.clone(),
            jacobian: JacobianMethod::Sensitivity,
        };
        let (m, n) = (problem.n_residuals(), problem.n_params());
        assert_eq!(n, x.len());
        // Off the truth (residuals not zero), and φ0 off its bound 0.
        let u: Vec<f64> = space
            .to_unit(&x)
            .iter()
            .enumerate()
            .map(|(j, u)| (u + if j % 2 == 0 { 0.01 } else { -0.01 }).clamp(0.02, 0.98))
            .collect();
        let mut r = vec![0.0; m];
        problem.residuals(&u, &mut r).unwrap();
        let mut js = DMatrix::zeros(m, n);
        problem
            .jacobian(&u, &r, &mut js)
            .expect("sensitivities, not finite differences")
            .unwrap();
        let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
        for j in 0..n {
            let h = 1e-5;
            let (mut up, mut um) = (u.clone(), u.clone());
            up[j] += h;
            um[j] -= h;
            problem.residuals(&up, &mut rp).unwrap();
            problem.residuals(&um, &mut rm).unwrap();
            let fd: Vec<f64> = (0..m).map(|i| (rp[i] - rm[i]) / (2.0 * h)).collect();
            let scale = fd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(scale > 0.0, "{names:?}: column {j} is zero");
            let err = (0..m).fold(0.0f64, |a, i| a.max((js[(i, j)] - fd[i]).abs())) / scale;
            eprintln!("{names:?} column {j}: |J| {scale:.3e}, rel err {err:.2e}");
            assert!(err < 1e-5, "{names:?}: column {j}: error {err:e}");
        }
    }
}
