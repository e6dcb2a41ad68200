//! Goodness of fit beyond the error model: does a misfit shape common to every curve remain?
//!
//! Reading error is independent between specimens; a model-form error repeats on every curve
//! at the same fraction of life. The statistic projects the whitened residuals (under the
//! fitted AR(1) and lifetime scatter) onto a common shape — piecewise-linear "hat" functions
//! of the life fraction τ = t/t_life at [`KNOTS`], each in units of the curve's rupture strain,
//! plus a common log-lifetime bias — and returns the squared length of the projection:
//!
//!   G = r_wᵀ X_w (X_wᵀ X_w)⁻¹ X_wᵀ r_w,
//!
//! the likelihood-ratio statistic for adding that common shape with the constants held. It
//! is about χ² with as many degrees of freedom as columns if the model and the error model
//! are right; [`crate::diagnose`] calibrates it by a parametric bootstrap instead (the fitted
//! constants absorb part of any shape). The fitted coefficients say where the model misses:
//! they are the common misfit shape, in % of the rupture strain.

use nalgebra::{DMatrix, DVector};

use crate::data::Curve;
use crate::errmodel::{ErrorModel, Residuals};

/// Knots of the common shape, in fractions of the measured life.
pub const KNOTS: [f64; 7] = [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0];

/// The statistic and the misfit shape behind it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Gof {
    /// G, the squared length of the projection.
    pub statistic: f64,
    /// Columns used (knots with data, plus the lifetime bias if any curve has a rupture time).
    pub dof: usize,
    /// Common misfit (predicted − measured) at each knot, % of the rupture strain (NaN for a
    /// knot without data).
    pub shape_pct: Vec<f64>,
    /// Common log-lifetime bias ln(t_pred/t_meas) (NaN without rupture times).
    pub lifetime_bias: f64,
}

/// Hat function `k` of [`KNOTS`] at life fraction `tau` (clamped to [0, 1]).
pub fn hat(k: usize, tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    let x = KNOTS[k];
    let left = if k > 0 { KNOTS[k - 1] } else { x };
    let right = if k + 1 < KNOTS.len() { KNOTS[k + 1] } else { x };
    if t == x {
        1.0
    } else if t < x && t > left {
        (t - left) / (x - left)
    } else if t > x && t < right {
        (right - t) / (right - x)
    } else {
        0.0
    }
}

/// G for the raw residuals `res` of `curves` under `noise`.
pub fn statistic(curves: &[Curve], res: &Residuals, noise: &ErrorModel) -> Gof {
    let nk = KNOTS.len();
    let m: usize = curves.iter().map(|c| c.times_h.len() + 1).sum();
    let ncol = nk + 1;
    let mut x = DMatrix::<f64>::zeros(m, ncol);
    let mut r = DVector::<f64>::zeros(m);
    let mut off = 0;
    for (i, c) in curves.iter().enumerate() {
        let n = c.times_h.len();
        let life = c.life_h();
        for j in 0..n {
            let tau = c.times_h[j] / life;
            for k in 0..nk {
                x[(off + j, k)] = hat(k, tau) * c.rupture_strain;
            }
            r[off + j] = res.strain[i][j];
        }
        let p = &noise.strain[i];
        p.whiten(&mut r.as_mut_slice()[off..off + n]);
        for k in 0..nk {
            p.whiten(&mut x.as_mut_slice()[k * m + off..k * m + off + n]);
        }
        if let Some(l) = res.lifetime[i] {
            r[off + n] = l / noise.lifetime_sd;
            x[(off + n, nk)] = 1.0 / noise.lifetime_sd;
        }
        off += n + 1;
    }
    // Keep the columns that carry data.
    let keep: Vec<usize> = (0..ncol)
        .filter(|&k| x.column(k).norm_squared() > 0.0)
        .collect();
    let xk = x.select_columns(&keep);
    let xtx = xk.tr_mul(&xk);
    let xtr = xk.tr_mul(&r);
    let (coef, g) = match xtx.clone().cholesky() {
        Some(ch) => {
            let b = ch.solve(&xtr);
            let g = b.dot(&xtr);
            (b, g)
        }
        None => {
            // Degenerate design (collinear knots on sparse data): pseudo-inverse.
            let pinv = xtx
                .clone()
                .pseudo_inverse(1e-12 * xtx.diagonal().max())
                .unwrap_or_else(|_| DMatrix::zeros(keep.len(), keep.len()));
            let b = &pinv * &xtr;
            let g = b.dot(&xtr);
            (b, g)
        }
    };
    let mut shape_pct = vec![f64::NAN; nk];
    let mut lifetime_bias = f64::NAN;
    for (p, &k) in keep.iter().enumerate() {
        if k < nk {
            shape_pct[k] = 100.0 * coef[p];
        } else {
            lifetime_bias = coef[p];
        }
    }
    Gof {
        statistic: g.max(0.0),
        dof: keep.len(),
        shape_pct,
        lifetime_bias,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errmodel::Ar1;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn curve(n: usize) -> Curve {
        let times: Vec<f64> = (0..n).map(|k| 100.0 * k as f64 / (n - 1) as f64).collect();
        Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: None,
            strains: vec![0.0; n],
            times_h: times,
            rupture_time_h: Some(100.0),
            rupture_strain: 0.05,
            min_rate_measured: None,
            min_rate_estimated: 1e-4,
        }
    }

    #[test]
    fn hats_partition_unity() {
        for k in 0..=100 {
            let t = k as f64 / 100.0;
            let s: f64 = (0..KNOTS.len()).map(|j| hat(j, t)).sum();
            assert!((s - 1.0).abs() < 1e-12, "{t}: {s}");
        }
        assert_eq!(hat(0, 0.0), 1.0);
        assert_eq!(hat(6, 1.2), 1.0);
        assert!((hat(1, 0.05) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn null_statistic_is_chi_square_and_a_common_shape_is_found() {
        // Pure AR(1) noise with the true error model: G ~ χ²(dof), mean = dof.
        let curves: Vec<Curve> = (0..3).map(|_| curve(40)).collect();
        let noise = ErrorModel {
            strain: vec![Ar1::with_marginal(1e-4, 0.5); 3],
            lifetime_sd: 0.02,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let reps = 4000;
        let mut mean = 0.0;
        let mut dof = 0;
        for _ in 0..reps {
            let res = Residuals {
                strain: (0..3)
                    .map(|i| noise.strain[i].simulate(40, &mut rng))
                    .collect(),
                lifetime: (0..3)
                    .map(|_| Some(0.02 * Ar1::white(1.0).simulate(1, &mut rng)[0]))
                    .collect(),
            };
            let g = statistic(&curves, &res, &noise);
            mean += g.statistic / reps as f64;
            dof = g.dof;
        }
        assert_eq!(dof, 8);
        assert!((mean - 8.0).abs() < 0.3, "mean {mean}");
        // A common over-prediction of 1 % of ε_f in the middle of life.
        let res = Residuals {
            strain: (0..3)
                .map(|_| {
                    (0..40)
                        .map(|k| 0.01 * 0.05 * hat(3, k as f64 / 39.0))
                        .collect()
                })
                .collect(),
            lifetime: vec![Some(0.0); 3],
        };
        let g = statistic(&curves, &res, &noise);
        assert!((g.shape_pct[3] - 1.0).abs() < 1e-9, "{:?}", g.shape_pct);
        assert!(g.shape_pct[0].abs() < 1e-9);
        assert!(g.statistic > 50.0);
    }
}
