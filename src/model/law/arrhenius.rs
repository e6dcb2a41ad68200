//! `arrhenius`: c(T) = c_ref · exp(−(Q/R)(1/T − 1/T_ref)), with the activation energy Q in
//! kJ/mol and T, T_ref in K. At T = T_ref the factor is exactly 1, whatever Q: c_ref is the
//! value at the reference temperature, which is taken inside the tested range (by default
//! their mean) so that c_ref and Q are not collinear. For a positive c_ref only.

use crate::dual::Scalar;

/// Registry name.
pub const NAME: &str = "arrhenius";

/// Name of the law's parameter (the constant `A` gets `A.Q`).
pub const PARAM: &str = "Q";
/// Unit of Q.
pub const UNIT: &str = "kJ/mol";
/// Default bounds of Q, kJ/mol: from no temperature dependence to well above the activation
/// energies of creep (self-diffusion in steels and nickel alloys: 250–300 kJ/mol; apparent
/// values of power-law creep up to ~700).
pub const DEFAULT_BOUNDS: (f64, f64) = (0.0, 1000.0);

/// The gas constant, kJ/(mol·K).
pub const R_KJ_PER_MOL_K: f64 = 8.314_462_618e-3;

/// The abscissa of the law, x = 1/T − 1/T_ref (1/K): ln c = ln c_ref − (Q/R)·x.
#[inline(always)]
pub fn abscissa(t_k: f64, t_ref_k: f64) -> f64 {
    1.0 / t_k - 1.0 / t_ref_k
}

/// c(T) = c_ref · exp(−(Q/R)(1/T − 1/T_ref)).
#[inline(always)]
pub fn eval<S: Scalar>(c_ref: S, q: S, t_k: f64, t_ref_k: f64) -> S {
    c_ref * (q * (-abscissa(t_k, t_ref_k) / R_KJ_PER_MOL_K)).exp()
}

/// The factor c(T)/c_ref at activation energy `q` (kJ/mol).
pub fn factor(q: f64, t_k: f64, t_ref_k: f64) -> f64 {
    eval(1.0, q, t_k, t_ref_k)
}

/// (c_ref, Q) from per-temperature values `values` (> 0) at `t_k`: the least-squares line of
/// ln c against 1/T − 1/T_ref; with `q_held` = Some(Q) only c_ref is fitted. `None` without
/// two distinct temperatures (and no held Q) or with a non-positive value.
pub fn fit(t_k: &[f64], values: &[f64], t_ref_k: f64, q_held: Option<f64>) -> Option<(f64, f64)> {
    if values.is_empty() || values.iter().any(|v| !(*v > 0.0) || !v.is_finite()) {
        return None;
    }
    let x: Vec<f64> = t_k.iter().map(|&t| abscissa(t, t_ref_k)).collect();
    let y: Vec<f64> = values.iter().map(|v| v.ln()).collect();
    let n = x.len() as f64;
    let q = match q_held {
        Some(q) => q,
        None => {
            let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
            let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
            if !(sxx > 0.0) {
                return None;
            }
            let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
            -sxy / sxx * R_KJ_PER_MOL_K
        }
    };
    // ln c_ref = mean(ln c + (Q/R) x)
    let ln_c = x
        .iter()
        .zip(&y)
        .map(|(a, b)| b + q / R_KJ_PER_MOL_K * a)
        .sum::<f64>()
        / n;
    Some((ln_c.exp(), q))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_temperature_gives_the_reference_value_exactly() {
        for q in [0.0, 123.4, 987.0] {
            assert_eq!(
                eval(3.7e-9, q, 833.15, 833.15).to_bits(),
                3.7e-9f64.to_bits()
            );
        }
        // Q = 0 at any temperature: exactly c_ref.
        assert_eq!(
            eval(3.7e-9, 0.0, 863.15, 848.15).to_bits(),
            3.7e-9f64.to_bits()
        );
    }

    #[test]
    fn fit_recovers_a_known_law() {
        let (c, q, t_ref) = (2.5e-9, 310.0, 848.15);
        let t = [833.15, 848.15, 863.15, 900.0];
        let v: Vec<f64> = t.iter().map(|&tk| eval(c, q, tk, t_ref)).collect();
        let (c2, q2) = fit(&t, &v, t_ref, None).unwrap();
        assert!(
            (c2 / c - 1.0).abs() < 1e-12 && (q2 / q - 1.0).abs() < 1e-10,
            "{c2} {q2}"
        );
        let (c3, q3) = fit(&t, &v, t_ref, Some(q)).unwrap();
        assert!((c3 / c - 1.0).abs() < 1e-12 && q3 == q);
        assert!(fit(&t[..1], &v[..1], t_ref, None).is_none());
        // Q/R in K: 310 kJ/mol between 560 and 590 °C is a factor exp(37285·Δ(1/T)).
        let f = factor(q, 863.15, 833.15);
        assert!((f.ln() - q / R_KJ_PER_MOL_K * (1.0 / 833.15 - 1.0 / 863.15)).abs() < 1e-12);
    }
}
