//! `linear`: c(T) = c_ref + s·(T − T_ref), linear in the temperature, with the slope s in
//! the constant's unit per K (named e.g. `B.slope`).

use crate::dual::Scalar;

/// Registry name.
pub const NAME: &str = "linear";

/// Name of the law's parameter (the constant `B` gets `B.slope`).
pub const PARAM: &str = "slope";

/// Default bounds of the slope for a constant boxed in [lb, ub]: ±(ub − lb)/100 per K, i.e.
/// the whole box over 100 K.
pub fn default_bounds(lb: f64, ub: f64) -> (f64, f64) {
    let s = (ub - lb) / 100.0;
    (-s, s)
}

/// c(T) = c_ref + s·(T − T_ref).
#[inline(always)]
pub fn eval<S: Scalar>(c_ref: S, slope: S, t_k: f64, t_ref_k: f64) -> S {
    c_ref + slope * (t_k - t_ref_k)
}

/// (c_ref, s) from per-temperature `values` at `t_k`: the least-squares line; with
/// `slope_held` only c_ref is fitted. `None` without two distinct temperatures (and no held
/// slope).
pub fn fit(
    t_k: &[f64],
    values: &[f64],
    t_ref_k: f64,
    slope_held: Option<f64>,
) -> Option<(f64, f64)> {
    if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let x: Vec<f64> = t_k.iter().map(|&t| t - t_ref_k).collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, values.iter().sum::<f64>() / n);
    let s = match slope_held {
        Some(s) => s,
        None => {
            let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
            if !(sxx > 0.0) {
                return None;
            }
            x.iter()
                .zip(values)
                .map(|(a, b)| (a - mx) * (b - my))
                .sum::<f64>()
                / sxx
        }
    };
    Some((my - s * mx, s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_line_and_the_reference_is_exact() {
        let t = [823.15, 863.15, 900.0];
        let v: Vec<f64> = t.iter().map(|&tk| eval(0.15, -4e-4, tk, 843.15)).collect();
        let (c, s) = fit(&t, &v, 843.15, None).unwrap();
        assert!((c - 0.15).abs() < 1e-14 && (s + 4e-4).abs() < 1e-15);
        assert_eq!(eval(0.15, 7.0, 843.15, 843.15).to_bits(), 0.15f64.to_bits());
    }
}
