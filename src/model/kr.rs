//! The Kachanov–Rabotnov creep-damage model, a second model family: a Norton creep rate
//! enhanced by a scalar damage ω with its own stress exponent,
//!
//!   dε/dt = A (σ/σ₀)ⁿ / (1 − ω)ⁿ,   dω/dt = B (σ/σ₀)^χ / (1 − ω)^φ,
//!
//! σ₀ = [`SIGMA0`] (100 MPa, so that A and B are rates in 1/h at 100 MPa). Unlike KHD it has
//! no primary stage and its rupture strain follows from the constants
//! (ε_r ≈ A/((φ + 1 − n)B)·(σ/σ₀)^(n−χ)), so it varies with stress. The damage law
//! integrates in closed form: ψ = (1 − ω)^(φ+1) falls linearly, ψ = 1 − t/t_r with
//! t_r = 1/((φ + 1) B (σ/σ₀)^χ); the model is integrated in the state [ε, ψ] (ψ exact under
//! any Runge–Kutta step, the strain rate A (σ/σ₀)ⁿ ψ^(−n/(φ+1)) without the singular
//! (1 − ω)^(−φ)), and ruptures at ψ = [`PSI_R`]. The strain in closed form ([`closed_form`]):
//! ε = A (σ/σ₀)ⁿ t_r (φ + 1)[1 − ψ^((φ+1−n)/(φ+1))]/(φ + 1 − n).
//!
//! This file is the whole family: constants, equations, output columns, initial guess; its
//! registry entry ([`super::REGISTRY`], `kr`) is the only other place that names it. It takes
//! no catalogued extension (those are KHD's).

use super::{ConstantSpec, CreepModel, Load, Role, Scale};
use crate::data::Curve;
use crate::dual::Scalar;
use crate::model::guess::{Guess, GuessProcedure};
use crate::model::objective::ParamSpace;
use crate::model::Model;
use crate::ode::OdeOptions;

/// Reference stress σ₀, MPa.
pub const SIGMA0: f64 = 100.0;

/// Rupture: at 99.9 % of the damage life t_r (ψ = 1e-3). The damage reaches 1 only at t_r,
/// where the strain rate is infinite; for φ = 6 the event at ω = 0.99 would lie 1e-14·t_r
/// before t_r, below what a double resolves (measured: step underflow), while at ψ = 1e-3
/// (ω = 0.63 for φ = 6) the strain rate is (1e3)^(n/(φ+1)) times the minimum (52 for
/// n = 4) and the strain is within ψ^((φ+1−n)/(φ+1)) (5 %) of its limit. (KHD's ω_f of the
/// configuration does not apply.)
pub const PSI_R: f64 = 1e-3;

/// The five constants [A, n, B, chi, phi] with default bounds wide enough for steels and
/// nickel alloys between 500 and 1000 °C.
pub fn constants() -> Vec<ConstantSpec> {
    vec![
        ConstantSpec {
            name: "A",
            unit: "1/h",
            lb: 1e-12,
            ub: 1e-1,
            default: 1e-5,
            scale: Scale::Log,
            role: Role::Rate,
            doc: "Norton creep rate at 100 MPa, no damage",
        },
        ConstantSpec {
            name: "n",
            unit: "-",
            lb: 1.0,
            ub: 15.0,
            default: 5.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "Norton stress exponent",
        },
        ConstantSpec {
            name: "Bd",
            unit: "1/h",
            lb: 1e-12,
            ub: 1e-1,
            default: 1e-4,
            scale: Scale::Log,
            role: Role::InverseDuctility,
            doc: "damage rate at 100 MPa, no damage",
        },
        ConstantSpec {
            name: "chi",
            unit: "-",
            lb: 1.0,
            ub: 15.0,
            default: 4.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "stress exponent of the damage rate",
        },
        ConstantSpec {
            name: "phi",
            unit: "-",
            lb: 1.0,
            ub: 30.0,
            default: 6.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "damage exponent of the damage rate",
        },
    ]
}

/// Per-simulation constants.
#[derive(Debug, Clone, Copy)]
pub struct KrPrepared<S> {
    /// A (σ/σ₀)ⁿ, 1/h
    pub rate0: S,
    /// n/(φ + 1)
    pub alpha: S,
    /// 1/t_r = (φ + 1) B (σ/σ₀)^χ, 1/h
    pub inv_life: S,
    /// 1/(φ + 1)
    pub inv_phi1: S,
}

/// The model, state y = [ε, ψ] with ψ = (1 − ω)^(φ+1).
#[derive(Debug, Clone, Copy, Default)]
pub struct Kr;

/// Output columns beside the strain.
pub const OUTPUTS: [&str; 1] = ["omega"];

impl CreepModel<2> for Kr {
    type Prepared<S: Scalar> = KrPrepared<S>;
    fn prepare<S: Scalar>(&self, params: &[S], load: &Load) -> KrPrepared<S> {
        let ln_s = (load.stress_mpa / SIGMA0).ln();
        let (a, n, b, chi, phi) = (params[0], params[1], params[2], params[3], params[4]);
        let phi1 = phi + 1.0;
        KrPrepared {
            rate0: a * (n * ln_s).exp(),
            alpha: n / phi1,
            inv_life: phi1 * b * (chi * ln_s).exp(),
            inv_phi1: S::cst(1.0) / phi1,
        }
    }
    fn init<S: Scalar>(&self, _p: &KrPrepared<S>) -> [S; 2] {
        [S::cst(0.0), S::cst(1.0)]
    }
    #[inline(always)]
    fn rhs<S: Scalar>(&self, p: &KrPrepared<S>, _t: S, y: &[S; 2], dy: &mut [S; 2]) -> bool {
        if !(y[1].re() > 0.0) {
            return false;
        }
        dy[0] = p.rate0 * (-(p.alpha * y[1].ln())).exp();
        dy[1] = -p.inv_life;
        dy[0].is_finite()
    }
    #[inline(always)]
    fn event<S: Scalar>(&self, _p: &KrPrepared<S>, y: &[S; 2]) -> S {
        S::cst(PSI_R) - y[1]
    }
    #[inline(always)]
    fn event_rate<S: Scalar>(&self, _p: &KrPrepared<S>, _y: &[S; 2], dy: &[S; 2]) -> S {
        -dy[1]
    }
    #[inline(always)]
    fn strain<S: Scalar>(&self, _p: &KrPrepared<S>, y: &[S; 2]) -> S {
        y[0]
    }
    #[inline(always)]
    fn strain_rate<S: Scalar>(&self, _p: &KrPrepared<S>, _y: &[S; 2], dy: &[S; 2]) -> S {
        dy[0]
    }
    fn state_names(&self) -> [&'static str; 2] {
        ["strain", "psi"]
    }
    fn output_names(&self) -> &'static [&'static str] {
        &OUTPUTS
    }
    fn outputs(&self, p: &KrPrepared<f64>, _t: f64, y: &[f64; 2], out: &mut Vec<f64>) {
        out.push(1.0 - y[1].max(0.0).powf(p.inv_phi1));
    }
}

/// The closed form at constants [A, n, B, chi, phi] and `stress_mpa`: (damage life t_r in h,
/// life to rupture at [`PSI_R`] in h, strain at time `t` h < t_r as a fraction). For tests
/// and the guess.
pub fn closed_form(params: &[f64], stress_mpa: f64, t: f64) -> (f64, f64, f64) {
    let (a, n, b, chi, phi) = (params[0], params[1], params[2], params[3], params[4]);
    let s = stress_mpa / SIGMA0;
    let t_r = 1.0 / ((phi + 1.0) * b * s.powf(chi));
    let t_f = t_r * (1.0 - PSI_R);
    let q = phi + 1.0 - n;
    let u = 1.0 - t / t_r;
    let eps = if q.abs() < 1e-12 {
        -a * s.powf(n) * t_r * u.ln()
    } else {
        a * s.powf(n) * t_r * (phi + 1.0) * (1.0 - u.powf(q / (phi + 1.0))) / q
    };
    (t_r, t_f, eps)
}

/// The initial guess in closed form from the curves' minimum creep rates, lives and rupture
/// strains: n and A from ln ε̇_min on ln(σ/σ₀) (the rate at ω = 0 is A(σ/σ₀)ⁿ); φ from the
/// mean damage tolerance λ = ε_r/(ε̇_min t_r) = (φ + 1)/(φ + 1 − n) of the curves, so that
/// φ + 1 = λn/(λ − 1); χ and B from ln t_r = −ln((φ + 1)B) − χ ln(σ/σ₀). With one stress
/// the exponents keep their defaults (or the held values); every value is put inside its
/// bounds.
pub fn initial_guess(
    model: &dyn Model,
    curves: &[Curve],
    space: &ParamSpace,
    _omega_f: f64,
    _ode: &OdeOptions,
) -> Guess {
    let names = model.constants();
    let n_c = names.len();
    let mut x: Vec<f64> = (0..n_c)
        .map(|j| {
            if space.free[j] {
                names[j].default
            } else {
                space.fixed[j]
            }
        })
        .collect();
    let ruptured: Vec<&Curve> = curves
        .iter()
        .filter(|c| c.rupture_time_h.is_some_and(|t| t > 0.0) && c.min_rate() > 0.0)
        .collect();
    let ln_s: Vec<f64> = ruptured
        .iter()
        .map(|c| (c.stress_mpa / SIGMA0).ln())
        .collect();
    let ln_rate: Vec<f64> = ruptured.iter().map(|c| c.min_rate().ln()).collect();
    let ln_life: Vec<f64> = ruptured
        .iter()
        .map(|c| c.rupture_time_h.unwrap_or(f64::NAN).ln())
        .collect();
    let spread = ln_s.iter().map(|v| (v - ln_s[0]).abs()).fold(0.0, f64::max);
    let (in_, ia, ib, ichi, iphi) = (1, 0, 2, 3, 4);
    if !ruptured.is_empty() {
        // Slope (when free and there is a stress range) and intercept.
        let line = |y: &[f64], slope: Option<f64>| -> (f64, f64) {
            let m = ln_s.len() as f64;
            let xm = ln_s.iter().sum::<f64>() / m;
            let ym = y.iter().sum::<f64>() / m;
            let b = slope.unwrap_or_else(|| {
                let sxy: f64 = ln_s.iter().zip(y).map(|(a, b)| (a - xm) * (b - ym)).sum();
                let sxx: f64 = ln_s.iter().map(|a| (a - xm).powi(2)).sum();
                sxy / sxx
            });
            (b, ym - b * xm)
        };
        let fixed_slope = |j: usize, x: &[f64]| (!space.free[j] || spread < 1e-3).then_some(x[j]);
        let (n, ln_a) = line(&ln_rate, fixed_slope(in_, &x));
        x[in_] = n;
        x[ia] = ln_a.exp();
        let lambda = ruptured
            .iter()
            .map(|c| c.rupture_strain / (c.min_rate() * c.rupture_time_h.unwrap_or(f64::NAN)))
            .filter(|v| v.is_finite())
            .sum::<f64>()
            / ruptured.len() as f64;
        if space.free[iphi] && lambda > 1.0 {
            x[iphi] = lambda * n / (lambda - 1.0) - 1.0;
        }
        let phi = x[iphi].clamp(space.lb[iphi], space.ub[iphi]);
        let neg: Vec<f64> = ln_life.iter().map(|v| -v).collect();
        let (chi, c0) = line(&neg, fixed_slope(ichi, &x));
        x[ichi] = chi;
        x[ib] = c0.exp() / (phi + 1.0);
    }
    let mut clamped = Vec::new();
    for j in 0..n_c {
        if !space.free[j] {
            x[j] = space.fixed[j];
            continue;
        }
        let v = if x[j].is_finite() {
            x[j].clamp(space.lb[j], space.ub[j])
        } else {
            space.from_unit_one(j, 0.5)
        };
        if v != x[j] {
            clamped.push(names[j].name.to_string());
        }
        x[j] = v;
    }
    Guess {
        params: x,
        min_rates: ruptured.iter().map(|c| c.min_rate()).collect(),
        clamped,
        procedure: GuessProcedure::Model,
        per_temperature: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::build;

    const TRUTH: [f64; 5] = [2e-5, 4.0, 1e-4, 3.5, 6.0];

    fn tight() -> OdeOptions {
        OdeOptions {
            rtol: 1e-10,
            atol: 1e-14,
            ..OdeOptions::default()
        }
    }

    #[test]
    fn simulation_matches_the_closed_form() {
        let m = build("kr", &[]).unwrap();
        for stress in [80.0, 120.0, 160.0] {
            let (_, t_end, _) = closed_form(&TRUTH, stress, 0.0);
            let times: Vec<f64> = (1..=50).map(|k| t_end * k as f64 / 51.0).collect();
            let mut out = vec![0.0; times.len()];
            let load = Load::new(stress, 600.0, 1.0 / 3.0);
            let r = m.simulate(&TRUTH, &load, &times, &mut out, &tight());
            assert_eq!(r.n_out, times.len(), "{r:?}");
            assert!(
                (r.t_end / t_end - 1.0).abs() < 1e-6,
                "{} {}",
                r.t_end,
                t_end
            );
            for (t, e) in times.iter().zip(&out) {
                let (_, _, want) = closed_form(&TRUTH, stress, *t);
                assert!((e / want - 1.0).abs() < 1e-6, "t {t}: {e} vs {want}");
            }
            // The minimum rate is the undamaged Norton rate at t = 0.
            let want = TRUTH[0] * (stress / SIGMA0).powf(TRUTH[1]);
            assert!((r.min_rate / want - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn guess_recovers_the_constants_from_exact_curve_summaries() {
        let m = build("kr", &[]).unwrap();
        let cs = constants();
        let space = ParamSpace::new(
            cs.iter().map(|c| c.lb).collect(),
            cs.iter().map(|c| c.ub).collect(),
            cs.iter().map(|c| c.scale).collect(),
        );
        let curves: Vec<Curve> = [70.0, 100.0, 140.0]
            .iter()
            .map(|&s| {
                let (t_r, _, _) = closed_form(&TRUTH, s, 0.0);
                // The asymptotic rupture strain (ω → 1): the guess's relation is exact there.
                let eps_r = TRUTH[0] * (s / SIGMA0).powf(TRUTH[1]) * t_r * (TRUTH[4] + 1.0)
                    / (TRUTH[4] + 1.0 - TRUTH[1]);
                Curve {
                    temperature_c: 600.0,
                    stress_mpa: s,
                    specimen: None,
                    times_h: vec![0.0, t_r],
                    strains: vec![0.0, eps_r],
                    rupture_time_h: Some(t_r),
                    rupture_strain: eps_r,
                    min_rate_measured: Some(TRUTH[0] * (s / SIGMA0).powf(TRUTH[1])),
                    groups: None,
                    min_rate_estimated: f64::NAN,
                }
            })
            .collect();
        let g = initial_guess(m.as_ref(), &curves, &space, 1.0 / 3.0, &tight());
        for (got, want) in g.params.iter().zip(TRUTH) {
            assert!((got / want - 1.0).abs() < 1e-9, "{:?}", g.params);
        }
        assert!(g.clamped.is_empty());
    }
}
