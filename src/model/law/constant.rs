//! `constant`: the constant does not depend on temperature (the default law).

use crate::dual::Scalar;

/// Registry name.
pub const NAME: &str = "constant";

/// c(T) = c_ref.
#[inline(always)]
pub fn eval<S: Scalar>(c_ref: S) -> S {
    c_ref
}

/// The value common to the per-temperature `values`: their mean (geometric for a constant on
/// a log scale, `log` true).
pub fn fit(values: &[f64], log: bool) -> f64 {
    let n = values.len().max(1) as f64;
    if log {
        (values.iter().map(|v| v.ln()).sum::<f64>() / n).exp()
    } else {
        values.iter().sum::<f64>() / n
    }
}
