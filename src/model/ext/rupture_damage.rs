//! `rupture_damage`: a free damage at rupture ω_f, a constant of the extension that replaces
//! the configured `omega_f` of the load: rupture when ω = C k_σ ε reaches ω_f, so the rupture
//! strain is ω_f/(C k_σ) and the damage factor at rupture 1/(1 − ω_f) is no longer capped at
//! 1.5 (ω_f = 1/3, the seed paper's choice after Dyson's cavitation model).
//!
//! Why ω_f rather than a ductility-exhaustion rupture strain ε_R (rupture at ε = ε_R, i.e.
//! Σ Δε/ε_R = 1; e.g. Spindler, Fatigue Fract. Engng Mater. Struct. 27, 273–281, 2004): the
//! two are the same model family (ω_f = C ε_R), but only ω_f switches the
//! extension off at one fixed value (ω_f = 1/3) whatever C is; with ε_R the base model is the
//! curve ε_R = ω_f/C, not a point, and the nested likelihood-ratio test of `diagnose` needs a
//! point. The event stays linear in the state (ω − ω_f), and its rate C k_σ dε/dt is
//! unchanged, so the rupture time's sensitivity dt_r = −g/ġ now carries ∂g/∂ω_f = −1.
//! Switched off: ω_f = 1/3 ([`OFF_VALUE`]).
//!
//! Limit: the rate grows as exp(Bσ(1 − H)/((1 − Φ)(1 − ω))); where that argument passes
//! ≈ 25 before ω reaches ω_f, the last approach to rupture is shorter than the floating-point
//! resolution of t and the integrator ends with `step_underflow` (a failed simulation, which
//! fits treat as such; measured with the seed's 560 °C constants at ω_f = 0.75, 85 MPa).

use crate::model::{ConstantSpec, Role, Scale};

/// Registry name.
pub const NAME: &str = "rupture_damage";

/// The damage at rupture of the base model (DESIGN.md §1, the default `omega_f`): the value
/// that switches the extension off.
pub const OFF_VALUE: f64 = 1.0 / 3.0;

/// The extra constant ω_f.
pub fn constants() -> Vec<ConstantSpec> {
    vec![ConstantSpec {
        name: "omegaf",
        unit: "-",
        lb: 0.05,
        ub: 0.9,
        default: OFF_VALUE,
        scale: Scale::Linear,
        role: Role::Other,
        doc: "damage at rupture (replaces the configured omega_f): rupture strain omegaf / C",
    }]
}

/// The value of the extra constant that switches the extension off within [lb, ub]: the
/// base model's ω_f = 1/3 (a configuration with another `omega_f` is nested at that value
/// instead; see README).
pub fn off_value(lb: f64, ub: f64) -> f64 {
    OFF_VALUE.clamp(lb, ub)
}
