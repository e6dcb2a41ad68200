//! `strain_softening`: tertiary creep by strain softening, the creep rate multiplied by
//! Φ(ε) = 1 + φ0 ε^φ1 — the softening function of Walker's unified viscoplastic model of
//! Alloy 617 (Sham & Walker, "Preliminary development of a unified viscoplastic constitutive
//! model for Alloy 617 with special reference to long term creep behavior", HTR2008-58274,
//! 2008; the basis of ASME's Alloy 617 constitutive model as written up by Messner & Sham,
//! Argonne National Laboratory, 2020: ṗ = ε̇0 Φ(p) χ(T) F with Φ = 1 + φ0 p^φ1, p the
//! equivalent inelastic strain).
//!
//! Why this form: it is the tertiary term of the constitutive model written for this alloy
//! class, it makes the rate grow with strain without the 1/(1 − ω) cap of the base model, and
//! Φ is a function of the creep strain alone, so H, ω and Φ stay functions of ε and the
//! one-state reduction (DESIGN.md §1) still holds. φ1 = 1 is `dislocation_damage`'s factor
//! 1 + C_d ε; φ1 > 1 lets the softening start late and rise steeply (fitted on Alloy 617:
//! φ1 ≈ 0.8 at 950 °C, 3.5 at 850 °C, 7–8 at 750 and 900 °C; README "Ductile tertiary creep").
//! Switched off: φ0 = 0 (φ1 then has no effect).

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "strain_softening";

/// The extra constants φ0 and φ1. φ0 reaches 1e4: a late, steep softening (φ1 = 5–6) of a
/// ductile alloy needs φ0 in the hundreds to thousands (φ0·0.4^6 = 10 at φ0 ≈ 2400); on the
/// Alloy 617 data at 750 and 900 °C a first box of 0–200 held φ0 at its bound.
pub fn constants() -> Vec<ConstantSpec> {
    vec![
        ConstantSpec {
            name: "phi0",
            unit: "-",
            lb: 0.0,
            ub: 1e4,
            default: 0.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "strain-softening prefactor: creep rate x (1 + phi0 eps^phi1)",
        },
        ConstantSpec {
            name: "phi1",
            unit: "-",
            lb: 0.5,
            ub: 8.0,
            default: 2.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "strain-softening exponent: creep rate x (1 + phi0 eps^phi1)",
        },
    ]
}

/// Rate factor Φ = 1 + φ0 ε^φ1 at creep strain ε (fraction); 1 at ε ≤ 0, where ε^φ1 → 0
/// (φ1 > 0) but its derivative in φ1, ln ε · ε^φ1, is not defined at ε = 0.
#[inline(always)]
pub fn rate_factor<S: Scalar>(phi0: S, phi1: S, eps: S) -> S {
    if eps.re() > 0.0 {
        phi0 * (phi1 * eps.ln()).exp() + 1.0
    } else {
        S::cst(1.0)
    }
}

/// The value of constant `name` that switches the extension off within [lb, ub]: φ0 = 0;
/// `None` for φ1 (no value of it switches the softening off).
pub fn off_value(name: &str, lb: f64, ub: f64) -> Option<f64> {
    (name == "phi0").then(|| 0.0f64.clamp(lb, ub))
}

/// Starts slightly on ([`super::probe_starts`]): φ1 = 1, 2, 4 with φ0 = 0.05·5^φ1, a 5 %
/// faster creep at 20 % strain each, from a softening over the whole curve to a late one.
pub fn probe_starts() -> Vec<Vec<(&'static str, f64)>> {
    [1.0f64, 2.0, 4.0]
        .iter()
        .map(|&p1| vec![("phi0", 0.05 * 5f64.powf(p1)), ("phi1", p1)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dual::Dual;

    #[test]
    fn probe_starts_soften_by_five_percent_at_twenty_percent_strain() {
        for p in probe_starts() {
            let (phi0, phi1) = (p[0].1, p[1].1);
            assert!((rate_factor(phi0, phi1, 0.2) - 1.05).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn rate_factor_against_hand_computation() {
        // 1 + 12·0.3^2.5 = 1 + 12·0.049295... (0.3^2.5 = 0.09·sqrt(0.3)).
        let want = 1.0 + 12.0 * 0.09 * 0.3f64.sqrt();
        let got = rate_factor(12.0, 2.5, 0.3);
        assert!((got - want).abs() < 1e-15 * want, "{got} vs {want}");
        // φ1 = 1 is dislocation_damage's 1 + C_d ε.
        assert_eq!(
            rate_factor(7.0, 1.0, 0.2),
            super::super::dislocation_damage::rate_factor(7.0, 0.2)
        );
        // Switched off: exactly 1 at any strain; at ε = 0 exactly 1 for any constants.
        for eps in [0.0, 1e-9, 0.4, 0.8] {
            assert_eq!(rate_factor(0.0, 3.0, eps), 1.0);
        }
        assert_eq!(rate_factor(50.0, 0.7, 0.0), 1.0);
    }

    #[test]
    fn rate_factor_derivatives_against_closed_forms() {
        // d/dφ0 = ε^φ1, d/dφ1 = φ0 ln ε ε^φ1, d/dε = φ0 φ1 ε^(φ1−1), at ε > 0 and at ε = 0.
        let (p0, p1, e) = (12.0, 2.5, 0.3);
        let f = rate_factor(
            Dual::<3>::var(p0, 0, 1.0),
            Dual::<3>::var(p1, 1, 1.0),
            Dual::<3>::var(e, 2, 1.0),
        );
        let pw = e.powf(p1);
        for (k, want) in [pw, p0 * e.ln() * pw, p0 * p1 * e.powf(p1 - 1.0)]
            .into_iter()
            .enumerate()
        {
            assert!((f.grad(k) - want).abs() < 1e-13 * want.abs(), "{k}");
        }
        let f0 = rate_factor(
            Dual::<3>::var(p0, 0, 1.0),
            Dual::<3>::var(p1, 1, 1.0),
            Dual::<3>::cst(0.0),
        );
        assert!((0..3).all(|k| f0.grad(k) == 0.0 && f0.grad(k).is_finite()));
    }
}
