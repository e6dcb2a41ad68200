//! `constant_load`: tests at constant load — the true stress rises as the section shrinks,
//! σ = σ0(1+ε) (constant volume), in the creep rate and in the hardening law. No new constant.
//!
//! With σ(ε) in dH/dt = (h/σ) ε̇ (1 − H/H*), H stays a function of ε alone:
//! dH/dε = h/(σ0(1+ε)) (1 − H/H*)  ⇒  H = H*(1 − exp(−(h/(σ0 H*)) ln(1+ε))),
//! so the one-state reduction (DESIGN.md §1) still holds.

use crate::dual::Scalar;

/// Registry name.
pub const NAME: &str = "constant_load";

/// True-stress factor σ/σ0 at creep strain ε.
#[inline(always)]
pub fn stress_factor<S: Scalar>(eps: S) -> S {
    eps + 1.0
}

/// The strain measure that replaces ε in H(ε) = H*(1 − exp(−h g(ε)/(σ0 H*))): g = ln(1+ε).
#[inline(always)]
pub fn hardening_strain<S: Scalar>(eps: S) -> S {
    (eps + 1.0).ln()
}
