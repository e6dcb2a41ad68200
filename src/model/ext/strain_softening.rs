//! `strain_softening`: tertiary creep by strain softening, the creep rate multiplied by
//! Φ(ε) = 1 + φ0 (ε/ε_ref)^φ1 with ε_ref = 0.2 ([`EPS_REF`]) — the softening function of
//! Walker's unified viscoplastic model of Alloy 617 (Sham & Walker, "Preliminary development
//! of a unified viscoplastic constitutive model for Alloy 617 with special reference to long
//! term creep behavior", HTR2008-58274, 2008; the basis of ASME's Alloy 617 constitutive
//! model as written up by Messner & Sham, Argonne National Laboratory, 2020:
//! ṗ = ε̇0 Φ(p) χ(T) F with Φ = 1 + φ0 p^φ1 in their notation, p the
//! equivalent inelastic strain). Written about a reference strain, φ0 is the rate's
//! increase at 20 % strain (Walker's prefactor is φ0/ε_ref^φ1): the same family, but the fit's
//! valley is nearly straight. With the prefactor of ε^φ1 as the constant (until 2026-11-28)
//! the curves' strains tie it to φ1 along a curved ridge (prefactor ≈ k/ε^φ1), where
//! Levenberg–Marquardt crawled: on the seed's 560 °C data 176 of the diagnosis's fits of this
//! extension ran to the 200-iteration limit still falling (64 since), the data's likelihood
//! ratio was 0.57 short of its optimum, and the diagnosis took 49.8 s (27.6 s since;
//! docs/DIAGNOSE.md, "Where the time goes").
//!
//! Why this form: it is the tertiary term of the constitutive model written for this alloy
//! class, it makes the rate grow with strain without the 1/(1 − ω) cap of the base model, and
//! Φ is a function of the creep strain alone, so H, ω and Φ stay functions of ε and the
//! one-state reduction (DESIGN.md §1) still holds. φ1 = 1 is `dislocation_damage`'s factor
//! 1 + C_d ε with C_d = φ0/ε_ref; φ1 > 1 lets the softening start late and rise steeply
//! (fitted on Alloy 617 in the earlier form: φ1 ≈ 0.8 at 950 °C, 3.5 at 850 °C, 7–8 at 750 and
//! 900 °C; README "Ductile tertiary creep").
//! Switched off: φ0 = 0 (φ1 then has no effect).

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "strain_softening";

/// The reference strain ε_ref of the softening factor (a fraction): φ0 is the creep rate's
/// relative increase there. 20 %: within the rupture strains of the seed's steel and of
/// Alloy 617 (≈ 0.05–0.55), the strain where the probe starts soften by 5 %.
pub const EPS_REF: f64 = 0.2;

/// The extra constants φ0 and φ1. The box of φ0, 0–1e4, holds every softening of the
/// earlier form's box (prefactor of ε^φ1 in 0–1e4, i.e. φ0 ≤ 1e4·0.2^φ1 ≤ 4,472) and more:
/// on the Alloy 617 data at 750 °C that form's prefactor sat at its bound (1e4, φ1 7.9).
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
            doc: "strain-softening: creep rate x (1 + phi0 (eps/0.2)^phi1); the rate's increase at 20 % strain",
        },
        ConstantSpec {
            name: "phi1",
            unit: "-",
            lb: 0.5,
            ub: 8.0,
            default: 2.0,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "strain-softening exponent: creep rate x (1 + phi0 (eps/0.2)^phi1)",
        },
    ]
}

/// Rate factor Φ = 1 + φ0 (ε/ε_ref)^φ1 at creep strain ε (fraction); 1 at ε ≤ 0, where
/// ε^φ1 → 0 (φ1 > 0) but its derivative in φ1, ln(ε/ε_ref)·(ε/ε_ref)^φ1, is not defined at
/// ε = 0.
#[inline(always)]
pub fn rate_factor<S: Scalar>(phi0: S, phi1: S, eps: S) -> S {
    if eps.re() > 0.0 {
        phi0 * (phi1 * (eps * (1.0 / EPS_REF)).ln()).exp() + 1.0
    } else {
        S::cst(1.0)
    }
}

/// The value of constant `name` that switches the extension off within [lb, ub]: φ0 = 0;
/// `None` for φ1 (no value of it switches the softening off).
pub fn off_value(name: &str, lb: f64, ub: f64) -> Option<f64> {
    (name == "phi0").then(|| 0.0f64.clamp(lb, ub))
}

/// Starts slightly on ([`super::probe_starts`]): φ1 = 1, 2, 4 with φ0 = 0.05, a 5 %
/// faster creep at 20 % strain each, from a softening over the whole curve to a late one.
pub fn probe_starts() -> Vec<Vec<(&'static str, f64)>> {
    [1.0f64, 2.0, 4.0]
        .iter()
        .map(|&p1| vec![("phi0", 0.05), ("phi1", p1)])
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
        // 1 + 12·1.5^2.5 = 1 + 12·2.25·sqrt(1.5) (ε/ε_ref = 0.3/0.2 = 1.5).
        let want = 1.0 + 12.0 * 2.25 * 1.5f64.sqrt();
        let got = rate_factor(12.0, 2.5, 0.3);
        assert!((got - want).abs() < 1e-14 * want, "{got} vs {want}");
        // At the reference strain the factor is 1 + φ0 whatever φ1.
        for p1 in [0.5, 1.0, 3.0, 8.0] {
            assert!((rate_factor(0.4, p1, EPS_REF) - 1.4).abs() < 1e-15, "{p1}");
        }
        // φ1 = 1 is dislocation_damage's 1 + C_d ε with C_d = φ0/ε_ref.
        let dd = super::super::dislocation_damage::rate_factor(7.0 / EPS_REF, 0.3);
        assert!((rate_factor(7.0, 1.0, 0.3) - dd).abs() < 1e-14 * dd);
        // Switched off: exactly 1 at any strain; at ε = 0 exactly 1 for any constants.
        for eps in [0.0, 1e-9, 0.4, 0.8] {
            assert_eq!(rate_factor(0.0, 3.0, eps), 1.0);
        }
        assert_eq!(rate_factor(50.0, 0.7, 0.0), 1.0);
    }

    #[test]
    fn rate_factor_derivatives_against_closed_forms() {
        // With x = ε/ε_ref: d/dφ0 = x^φ1, d/dφ1 = φ0 ln x · x^φ1, d/dε = φ0 φ1 x^(φ1−1)/ε_ref,
        // at ε > 0 and at ε = 0.
        let (p0, p1, e) = (12.0, 2.5, 0.3);
        let x = e / EPS_REF;
        let f = rate_factor(
            Dual::<3>::var(p0, 0, 1.0),
            Dual::<3>::var(p1, 1, 1.0),
            Dual::<3>::var(e, 2, 1.0),
        );
        let pw = x.powf(p1);
        for (k, want) in [pw, p0 * x.ln() * pw, p0 * p1 * x.powf(p1 - 1.0) / EPS_REF]
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
