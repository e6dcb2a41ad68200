//! `true_strain_load`: constant-load tests with the true stress written σ = σ0 exp(ε), the
//! form used where ε is the logarithmic (true) strain (constant volume: σ = σ0 exp(ε_true)).
//! The crate's ε is the engineering strain of the files, for which constant volume gives
//! σ0(1 + ε) exactly (`constant_load`); exp(ε) exceeds 1 + ε by 6.5 % at ε = 0.4 and 24 % at
//! ε = 0.8. No new constant; an alternative to `constant_load`, not composed with it.
//!
//! With σ(ε) in dH/dt = (h/σ) ε̇ (1 − H/H*): dH/dε = h/(σ0 e^ε)(1 − H/H*) ⇒
//! H = H*(1 − exp(−(h/(σ0 H*))(1 − e^(−ε)))), so H is a function of ε alone and the
//! one-state reduction still holds.

use crate::dual::Scalar;

/// Registry name.
pub const NAME: &str = "true_strain_load";

/// True-stress factor σ/σ0 = exp(ε) at creep strain ε.
#[inline(always)]
pub fn stress_factor<S: Scalar>(eps: S) -> S {
    eps.exp()
}

/// The strain measure that replaces ε in H(ε) = H*(1 − exp(−h g(ε)/(σ0 H*))): g = 1 − e^(−ε).
#[inline(always)]
pub fn hardening_strain<S: Scalar>(eps: S) -> S {
    S::cst(1.0) - (-eps).exp()
}
