//! Goodness of fit beyond the error model: does a misfit shape common to every curve remain?
//!
//! Reading error is independent between specimens; a model-form error repeats on every curve
//! at the same fraction of life. The statistic is the likelihood ratio for adding a common
//! shape to the fitted model's predictions — piecewise-linear "hat" functions of the life
//! fraction τ = t/t_life at [`KNOTS`], each in units of the curve's rupture strain, plus a
//! common log-lifetime bias — with the constants held and the error model re-estimated under
//! both hypotheses:
//!
//!   G = −2 ln L(residuals | error model) − min over (b, error model) of −2 ln L(residuals − X b | error model).
//!
//! Re-estimating the error model under the alternative matters: a misfit that the null's
//! AR(1) absorbs as strongly correlated "noise" shows up as a large drop of the noise once the
//! common shape takes it. G is about χ² with as many degrees of freedom as columns if the
//! model and the error model are right; [`crate::diagnose`] calibrates it by a parametric
//! bootstrap instead (the fitted constants absorb part of any shape). The fitted coefficients
//! say where the model misses: they are the common misfit shape, in % of the rupture strain.

use nalgebra::{DMatrix, DVector};

use crate::data::Curve;
use crate::errmodel::{ErrorModel, Residuals};

/// Knots of the common shape, in fractions of the measured life.
pub const KNOTS: [f64; 8] = [0.0, 0.03, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0];

/// Which misfit shape the alternative allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// One shape for all curves (in units of each curve's ε_f): a model-form error that
    /// repeats on every curve at the same fraction of life.
    Common,
    /// A shape per curve: what is left after the shared constants compromised between the
    /// curves (measured: catches early transients the common shape misses, and misses mid-life
    /// steps the common shape catches — so both are tested).
    PerCurve,
}

/// Both shapes, in the order `diagnose` tests them.
pub const SHAPES: [Shape; 2] = [Shape::Common, Shape::PerCurve];

/// The statistic and the misfit shape behind it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Gof {
    /// The alternative's shape.
    pub shape: Shape,
    /// G, the likelihood-ratio statistic.
    pub statistic: f64,
    /// Columns used (knots with data, plus the lifetime bias if any curve has a rupture time).
    pub dof: usize,
    /// Common misfit (predicted − measured) at each knot, % of the rupture strain (NaN for a
    /// knot without data).
    pub shape_pct: Vec<f64>,
    /// Common log-lifetime bias ln(t_pred/t_meas) (NaN without rupture times).
    pub lifetime_bias: f64,
    /// Each curve's part of G (the data's curve order): its strain readings' −2 ln L under the
    /// null's error model less that under the alternative's; with `lifetime_g` they sum to G
    /// (before G's floor at 0). Descriptive, not a test: where the misfit sits.
    pub curve_g: Vec<f64>,
    /// The rupture times' part of G.
    pub lifetime_g: f64,
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

/// The design of the common shape: one row per residual (per curve its strains, then its
/// lifetime), columns the knots (strain fraction per unit coefficient) and the lifetime bias;
/// only the columns that carry data.
fn design(curves: &[Curve], res: &Residuals, shape: Shape) -> (DMatrix<f64>, Vec<usize>) {
    let nk = KNOTS.len();
    let m: usize = curves.iter().map(|c| c.times_h.len() + 1).sum();
    let per = shape == Shape::PerCurve;
    let ncols = if per { nk * curves.len() + 1 } else { nk + 1 };
    let life_col = ncols - 1;
    let mut x = DMatrix::<f64>::zeros(m, ncols);
    let mut off = 0;
    for (i, c) in curves.iter().enumerate() {
        let n = c.times_h.len();
        let life = c.life_h();
        let base = if per { i * nk } else { 0 };
        for j in 0..n {
            for k in 0..nk {
                x[(off + j, base + k)] = hat(k, c.times_h[j] / life) * c.rupture_strain;
            }
        }
        if res.lifetime[i].is_some() {
            x[(off + n, life_col)] = 1.0;
        }
        off += n + 1;
    }
    let keep: Vec<usize> = (0..ncols)
        .filter(|&k| x.column(k).norm_squared() > 0.0)
        .collect();
    (x.select_columns(&keep), keep)
}

/// Whitened copies of the residual vector and of the design's columns under `noise`.
fn whitened(
    curves: &[Curve],
    res: &Residuals,
    x: &DMatrix<f64>,
    noise: &ErrorModel,
) -> (DVector<f64>, DMatrix<f64>) {
    let m = x.nrows();
    let mut r = DVector::<f64>::zeros(m);
    let mut xw = x.clone();
    let mut off = 0;
    for (i, c) in curves.iter().enumerate() {
        let n = c.times_h.len();
        r.as_mut_slice()[off..off + n].copy_from_slice(&res.strain[i]);
        let p = &noise.strain[i];
        p.whiten(&mut r.as_mut_slice()[off..off + n]);
        for k in 0..xw.ncols() {
            p.whiten(&mut xw.as_mut_slice()[k * m + off..k * m + off + n]);
        }
        if let Some(l) = res.lifetime[i] {
            r[off + n] = l / noise.lifetime_sd;
            for k in 0..xw.ncols() {
                xw[(off + n, k)] /= noise.lifetime_sd;
            }
        }
        off += n + 1;
    }
    (r, xw)
}

/// Least-squares coefficients of `r` on the columns of `x` (pseudo-inverse when singular).
fn solve(x: &DMatrix<f64>, r: &DVector<f64>) -> DVector<f64> {
    let (xtr, xtx) = crate::lsq::normal_products(x, r.as_slice());
    match xtx.clone().cholesky() {
        Some(ch) => ch.solve(&xtr),
        None => {
            let pinv = xtx
                .clone()
                .pseudo_inverse(1e-12 * xtx.diagonal().max())
                .unwrap_or_else(|_| DMatrix::zeros(x.ncols(), x.ncols()));
            pinv * xtr
        }
    }
}

/// `res` less the common shape `X b`.
fn subtract(curves: &[Curve], res: &Residuals, x: &DMatrix<f64>, b: &DVector<f64>) -> Residuals {
    let fit = x * b;
    let mut out = res.clone();
    let mut off = 0;
    for (i, c) in curves.iter().enumerate() {
        let n = c.times_h.len();
        for j in 0..n {
            out.strain[i][j] -= fit[off + j];
        }
        if let Some(l) = out.lifetime[i].as_mut() {
            *l -= fit[off + n];
        }
        off += n + 1;
    }
    out
}

/// G for the raw residuals `res` of `curves`, whose maximum-likelihood error model is `noise`
/// (estimated with rupture-time scatter floor `lifetime_sd_floor`), against `shape`.
pub fn statistic(
    curves: &[Curve],
    res: &Residuals,
    noise: &ErrorModel,
    lifetime_sd_floor: f64,
    shape: Shape,
) -> Gof {
    let (x, keep) = design(curves, res, shape);
    let l0 = noise.neg2ll(res);
    // Alternate: the shape by generalised least squares at the current error model, the
    // error model by maximum likelihood on what the shape leaves; each step lowers −2 ln L.
    let mut nz = noise.clone();
    let mut b = DVector::<f64>::zeros(x.ncols());
    let mut l1 = l0;
    // The alternative's residuals and error model, for the parts of G.
    let mut alt = (res.clone(), noise.clone());
    for _ in 0..20 {
        let (rw, xw) = whitened(curves, res, &x, &nz);
        let bn = solve(&xw, &rw);
        let left = subtract(curves, res, &x, &bn);
        let nn = ErrorModel::estimate(&left, lifetime_sd_floor);
        let ln = nn.neg2ll(&left);
        if !(ln < l1 - 1e-9) {
            if ln <= l1 {
                b = bn;
                l1 = ln;
                alt = (left, nn);
            }
            break;
        }
        b = bn;
        nz = nn.clone();
        l1 = ln;
        alt = (left, nn);
    }
    let parts0 = noise.neg2ll_curves(res);
    let parts1 = alt.1.neg2ll_curves(&alt.0);
    let curve_g: Vec<f64> = parts0.0.iter().zip(&parts1.0).map(|(a, b)| a - b).collect();
    let lifetime_g = parts0.1 - parts1.1;
    let nk = KNOTS.len();
    let life_col = keep.last().copied().unwrap_or(0);
    let mut sum = vec![0.0; nk];
    let mut cnt = vec![0usize; nk];
    let mut lifetime_bias = f64::NAN;
    for (p, &k) in keep.iter().enumerate() {
        if k == life_col && res.lifetime.iter().any(|l| l.is_some()) {
            lifetime_bias = b[p];
        } else {
            sum[k % nk] += b[p];
            cnt[k % nk] += 1;
        }
    }
    let shape_pct: Vec<f64> = (0..nk)
        .map(|k| {
            if cnt[k] > 0 {
                100.0 * sum[k] / cnt[k] as f64
            } else {
                f64::NAN
            }
        })
        .collect();
    Gof {
        shape,
        statistic: (l0 - l1).max(0.0),
        dof: keep.len(),
        shape_pct,
        lifetime_bias,
        curve_g,
        lifetime_g,
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
        assert_eq!(hat(7, 1.2), 1.0);
        // Between 0.03 and 0.1: 0.065 is half way.
        assert!((hat(1, 0.065) - 0.5).abs() < 1e-12);
        assert!((hat(2, 0.065) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn null_statistic_is_about_chi_square_and_a_common_shape_is_found() {
        // Pure AR(1) noise, error model estimated as diagnose does: G is about χ²(dof), whose
        // mean is dof (a little more in finite samples: the error model is re-estimated).
        let curves: Vec<Curve> = (0..3).map(|_| curve(60)).collect();
        let truth = ErrorModel {
            strain: vec![Ar1::with_marginal(1e-4, 0.5); 3],
            lifetime_sd: 0.02,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let reps = 2000;
        let mut mean = 0.0;
        let mut dof = 0;
        for _ in 0..reps {
            let res = Residuals {
                strain: (0..3)
                    .map(|i| truth.strain[i].simulate(60, &mut rng))
                    .collect(),
                lifetime: (0..3)
                    .map(|_| Some(0.02 * Ar1::white(1.0).simulate(1, &mut rng)[0]))
                    .collect(),
            };
            let noise = ErrorModel::estimate(&res, 0.01);
            let g = statistic(&curves, &res, &noise, 0.01, Shape::Common);
            mean += g.statistic / reps as f64;
            dof = g.dof;
        }
        assert_eq!(dof, 9);
        assert!(mean > 8.5 && mean < 12.0, "mean {mean}");
        // A common over-prediction of 1 % of ε_f in the middle of life on top of the noise:
        // found, and its size recovered.
        let res = Residuals {
            strain: (0..3)
                .map(|i| {
                    let e = truth.strain[i].simulate(60, &mut rng);
                    (0..60)
                        .map(|k| 0.01 * 0.05 * hat(4, k as f64 / 59.0) + e[k])
                        .collect()
                })
                .collect(),
            lifetime: vec![Some(0.0); 3],
        };
        let noise = ErrorModel::estimate(&res, 0.01);
        let g = statistic(&curves, &res, &noise, 0.01, Shape::Common);
        assert!((g.shape_pct[4] - 1.0).abs() < 0.2, "{:?}", g.shape_pct);
        assert!(g.statistic > 50.0, "{}", g.statistic);
        // The per-curve alternative has a shape per curve (3 × 8 knots + lifetime) and finds it
        // too, each curve's at about 1 %.
        let g = statistic(&curves, &res, &noise, 0.01, Shape::PerCurve);
        assert_eq!(g.dof, 25);
        assert!((g.shape_pct[4] - 1.0).abs() < 0.2, "{:?}", g.shape_pct);
        assert!(g.statistic > 50.0, "{}", g.statistic);
    }

    #[test]
    fn the_parts_of_g_sum_to_it_and_sit_where_the_misfit_is() {
        // Four curves of AR(1) noise; a late misfit of 3 % of ε_f on curve 2 alone.
        let curves: Vec<Curve> = (0..4).map(|_| curve(60)).collect();
        let p = Ar1::with_marginal(1e-4, 0.5);
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let res = Residuals {
            strain: (0..4)
                .map(|i| {
                    let e = p.simulate(60, &mut rng);
                    let bump = if i == 2 { 0.03 * 0.05 } else { 0.0 };
                    (0..60)
                        .map(|k| bump * hat(6, k as f64 / 59.0) + e[k])
                        .collect()
                })
                .collect(),
            lifetime: (0..4)
                .map(|_| Some(0.02 * Ar1::white(1.0).simulate(1, &mut rng)[0]))
                .collect(),
        };
        let noise = ErrorModel::estimate(&res, 0.01);
        for shape in SHAPES {
            let g = statistic(&curves, &res, &noise, 0.01, shape);
            assert_eq!(g.curve_g.len(), 4);
            let sum: f64 = g.curve_g.iter().sum::<f64>() + g.lifetime_g;
            // G is the null's −2 ln L less the alternative's; the parts are the same split
            // by curve, exactly.
            assert!(
                (sum - g.statistic).abs() < 1e-6 * g.statistic.max(1.0),
                "{shape:?}: {sum} vs {}",
                g.statistic
            );
        }
        // The per-curve alternative gives the misfit curve most of G.
        let g = statistic(&curves, &res, &noise, 0.01, Shape::PerCurve);
        let top = (0..4)
            .max_by(|&a, &b| g.curve_g[a].total_cmp(&g.curve_g[b]))
            .unwrap();
        assert_eq!(top, 2, "{:?}", g.curve_g);
        assert!(
            g.curve_g[2] > 0.5 * g.statistic,
            "{:?} of {}",
            g.curve_g,
            g.statistic
        );
    }
}
