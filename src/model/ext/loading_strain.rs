//! `loading_strain`: an instantaneous strain on loading at t = 0, ε_total = σ/E_L + ε_creep
//! (E_L: an apparent loading modulus, MPa; elastic and instantaneous plastic strain together).
//! The creep equations are unchanged; only the strain read-out moves. Switched off: E_L = ∞.

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "loading_strain";

/// The extra constant E_L.
pub fn constants() -> Vec<ConstantSpec> {
    vec![ConstantSpec {
        name: "EL",
        unit: "MPa",
        lb: 1e3,
        ub: 1e7,
        default: 1e5,
        scale: Scale::Log,
        role: Role::Other,
        doc: "apparent loading modulus: strain on loading = stress / EL",
    }]
}

/// Strain on loading σ/E_L (fraction).
#[inline(always)]
pub fn loading_strain<S: Scalar>(e_l: S, stress_mpa: f64) -> S {
    S::cst(stress_mpa) / e_l
}

/// The value of the extra constant that switches the extension off within [lb, ub]:
/// E_L at its upper bound: the smallest loading strain the box allows.
pub fn off_value(_lb: f64, ub: f64) -> f64 {
    ub
}
