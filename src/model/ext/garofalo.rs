//! `garofalo`: Garofalo's stress function (Garofalo, Trans. Metall. Soc. AIME 227, 351–356,
//! 1963), the creep rate A·sinh(x)^n_G instead of the base model's A·sinh(x), x = Bσ(1 − H)/
//! ((1 − Φ)(1 − ω)). n_G = 1 is the base model; for small x the rate is A(Bσ…)^n_G, Norton's
//! power law with exponent n_G, for large x exponential in stress as before.
//!
//! Why: with the sinh alone the rate's local stress exponent is x·coth(x), so the only way to
//! an exponent of 5 is x ≈ 5, and B must then shrink as the stresses tested rise: across
//! temperatures B follows 1/σ and a temperature law on B steepens the stress dependence between
//! the tested temperatures (docs/TEMPERATURES.md: Alloy 617 at 800 °C, exponents 9–12 where the
//! tests at 750 and 850 °C show 4.5 and 4.9). With n_G the exponent comes from n_G at small x
//! and need not be carried by B. Not one of the effects `diagnose` tests (it is another form of
//! the base model's stress law, not a missing mechanism): it is fitted where a configuration
//! names it. Switched off: n_G = 1 ([`OFF_VALUE`]).

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "garofalo";

/// n_G of the base model's A·sinh(x): the value that switches the extension off.
pub const OFF_VALUE: f64 = 1.0;

/// Largest ln of the rate factor sinh(x)^(n_G − 1) accepted: beyond it the rate overflows
/// (e^500 · A) and the state can only come from a trial step past rupture.
pub const MAX_LN_FACTOR: f64 = 500.0;

/// The extra constant n_G.
pub fn constants() -> Vec<ConstantSpec> {
    vec![ConstantSpec {
        name: "nG",
        unit: "-",
        lb: 0.5,
        ub: 12.0,
        default: OFF_VALUE,
        scale: Scale::Linear,
        role: Role::Other,
        doc: "Garofalo's exponent: creep rate A sinh(x)^nG (nG = 1: the base model)",
    }]
}

/// Rate factor sinh(x)^(n_G − 1) from `sinh_x` = sinh(x) > 0 and `n_minus_1` = n_G − 1, or
/// `None` where sinh(x) ≤ 0 (no physical state) or the factor would overflow.
#[inline(always)]
pub fn rate_factor<S: Scalar>(n_minus_1: S, sinh_x: S) -> Option<S> {
    if !(sinh_x.re() > 0.0) {
        return None;
    }
    let ln_factor = n_minus_1 * sinh_x.ln();
    if !(ln_factor.re() <= MAX_LN_FACTOR) {
        return None;
    }
    Some(ln_factor.exp())
}

/// The value of the extra constant that switches the extension off within [lb, ub]:
/// n_G = 1.
pub fn off_value(lb: f64, ub: f64) -> f64 {
    OFF_VALUE.clamp(lb, ub)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The factor is sinh(x)^(n−1) (closed form), 1 at n = 1, and refused where it overflows.
    #[test]
    fn factor_is_the_power_of_the_sinh() {
        for &(x, n) in &[(0.3, 4.5), (2.0, 1.0), (5.0, 2.5), (0.01, 6.0)] {
            let f: f64 = rate_factor(n - 1.0, f64::sinh(x)).unwrap();
            let want = f64::sinh(x).powf(n - 1.0);
            assert!((f - want).abs() <= 1e-12 * want, "{x} {n}: {f} vs {want}");
        }
        assert_eq!(rate_factor(0.0, f64::sinh(3.0)), Some(1.0));
        assert!(rate_factor(11.0, f64::sinh(60.0)).is_none());
        assert!(rate_factor(1.0, 0.0).is_none());
    }
}
