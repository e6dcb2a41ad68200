//! `stress_ductility`: a rupture ductility that varies with stress, dω/dt = C (σ/σ_ref)^ν dε/dt,
//! so ω = C (σ/σ_ref)^ν ε and the rupture strain is ω_f / (C (σ/σ_ref)^ν). σ_ref is fixed
//! ([`SIGMA_REF_MPA`]) so that ν does not trade off against C. Switched off: ν = 0.

use crate::dual::Scalar;
use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "stress_ductility";

/// Reference stress of the ductility law, MPa.
pub const SIGMA_REF_MPA: f64 = 100.0;

/// The extra constant ν.
pub fn constants() -> Vec<ConstantSpec> {
    vec![ConstantSpec {
        name: "nu",
        unit: "-",
        lb: -10.0,
        ub: 10.0,
        default: 0.0,
        scale: Scale::Linear,
        role: Role::Other,
        doc: "stress exponent of the damage rate: omega = C (stress/100 MPa)^nu eps",
    }]
}

/// Factor (σ/σ_ref)^ν on C.
#[inline(always)]
pub fn ductility_factor<S: Scalar>(nu: S, stress_mpa: f64) -> S {
    (nu * (stress_mpa / SIGMA_REF_MPA).ln()).exp()
}

/// The value of the extra constant that switches the extension off within [lb, ub]:
/// ν = 0 (inside the box).
pub fn off_value(lb: f64, ub: f64) -> f64 {
    0.0f64.clamp(lb, ub)
}
