//! `dislocation_damage`: multiplication of mobile dislocations (Dyson): the creep rate is
//! multiplied by 1/(1−D) with dD/dt = C_d (1−D)² dε/dt.
//!
//! D is a function of ε alone: dD/dε = C_d (1−D)² ⇒ 1/(1−D) = 1 + C_d ε, so the factor is
//! 1 + C_d ε and the one-state reduction still holds. Switched off: C_d = 0.

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "dislocation_damage";

/// The extra constant C_d.
pub fn constants() -> Vec<ConstantSpec> {
    vec![ConstantSpec {
        name: "Cd",
        unit: "-",
        lb: 0.0,
        ub: 50.0,
        default: 1.0,
        scale: Scale::Linear,
        role: Role::Other,
        doc: "dislocation multiplication per unit strain: rate factor 1/(1-D) = 1 + Cd eps",
    }]
}

/// Rate factor 1/(1−D) = 1 + C_d ε at creep strain ε.
#[inline(always)]
pub fn rate_factor<S: Scalar>(c_d: S, eps: S) -> S {
    c_d * eps + 1.0
}

/// The value of the extra constant that switches the extension off within [lb, ub]:
/// C_d = 0 (inside the box).
pub fn off_value(lb: f64, ub: f64) -> f64 {
    0.0f64.clamp(lb, ub)
}
