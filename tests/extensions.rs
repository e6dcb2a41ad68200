//! The extension catalogue (DESIGN.md §6): each extension reduces to the base model when
//! switched off, and its one-state composition matches the extension's defining equations
//! integrated as written (a test-local multi-state model), or a closed form.

// `!(x > 0.0)` is deliberate: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use creepfit::dual::Scalar;
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
    // E_L = ∞ (no loading strain), C_d = 0 (no multiplication), ν = 0 (no stress dependence).
    let all = ext(&["loading_strain", "dislocation_damage", "stress_ductility"]);
    assert_eq!(
        all.constants().iter().map(|c| c.name).collect::<Vec<_>>(),
        ["A", "B", "Hstar", "h", "Kc", "C", "EL", "Cd", "nu"]
    );
    let mut x = BASE.to_vec();
    x.extend([f64::INFINITY, 0.0, 0.0]);
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
            ("loading_strain", f64::INFINITY),
            ("dislocation_damage", 0.0),
            ("stress_ductility", 0.0),
        ] {
            let mut x1 = BASE.to_vec();
            x1.push(v);
            let (t, _, _) = run(ext(&[name]).as_ref(), &x1, sigma, &[]);
            assert!(rel(t, t0) < 1e-12, "{name}: {t} vs {t0}");
        }
    }
    // constant_load has no constant: it changes the prediction, and only in the direction
    // physics says (the true stress rises, so the life shortens).
    let (tc, _, _) = run(ext(&["constant_load"]).as_ref(), &BASE, 100.0, &[]);
    let (tb, _, _) = run(base.as_ref(), &BASE, 100.0, &[]);
    assert!(tc < tb * 0.99, "{tc} vs {tb}");
}

/// The defining equations of `constant_load` and `dislocation_damage` integrated as written:
/// state [ε, H, Φ, ω, D] with σ = σ0(1+ε) in the rate and in dH/dt, and the rate multiplied by
/// 1/(1−D), dD/dt = C_d (1−D)² dε/dt.
struct Defining {
    constant_load: bool,
    c_d: f64,
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
        let rate = a * arg.sinh() / (S::cst(1.0) - d);
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
        c_d: 0.0,
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
            constant_load: false,
            c_d,
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
