//! The error model of creep data: what a measured curve and a measured rupture time are
//! allowed to differ from the model's prediction by.
//!
//! - **Strain reading error**, per curve: a stationary AR(1) process in measurement order,
//!   e_1 ~ N(0, σ²/(1 − φ²)), e_j = φ·e_{j−1} + σ·z_j, with its own innovation scale σ (strain
//!   as a fraction) and correlation φ. Digitised and logged curves have correlated reading
//!   error (a digitiser's hand, an extensometer's drift): counting every point as independent
//!   overstates the evidence by orders of magnitude. φ = 0 is white noise.
//! - **Rupture-time error**, separately, on a log scale: ln t_f = ln t_r,pred + s·z, one s for
//!   all curves (≈ 1 % scatter of repeated tests at best, far more between specimens). It is
//!   estimated from the lifetime residuals with a floor ([`ErrorModel::estimate`]): a model
//!   with six constants can all but interpolate three rupture times, and the maximum-likelihood
//!   s would then collapse to zero.
//!
//! Estimation is exact Gaussian maximum likelihood given the residuals; the likelihood is the
//! exact AR(1) one (not conditional on the first point), so it is what a dense covariance
//! matrix gives (tested). Whitening turns the residuals into independent standard normal
//! innovations, which is how [`crate::likelihood`] fits constants under this model.

use nalgebra::DMatrix;
use rand::Rng;
use rand_distr::StandardNormal;

use crate::scalar_min::{grid_golden, GridGolden};

/// Largest |φ| an estimate may take: beyond it the process is a random walk in all but name
/// and the likelihood's −ln(1 − φ²) term dominates.
pub const PHI_MAX: f64 = 0.995;
/// AR(1) correlation of a curve's reading error at or above which the error model is read as
/// holding a smooth misfit (the estimate's bound is [`PHI_MAX`], 0.995): between the binned
/// points of a curve, reading error this correlated is a slowly drifting offset, which is
/// what a missed loading strain or primary stage looks like.
pub const PHI_ABSORBS: f64 = 0.99;

/// How many curves' reading errors (`phi`, one per curve) are correlated to
/// [`PHI_ABSORBS`] or more, when that is at least half of them, with the largest marginal sd
/// among those curves (`sd`, one per curve, in the caller's unit); `None` otherwise or without
/// curves. The rule of `diagnose`'s and `fit`'s cautions that the error model may have taken
/// a smooth misfit for correlated noise.
pub fn absorbing_curves(phi: &[f64], sd: &[f64]) -> Option<(usize, f64)> {
    let k = phi.iter().filter(|p| **p >= PHI_ABSORBS).count();
    if phi.is_empty() || 2 * k < phi.len() {
        return None;
    }
    let max_sd = sd
        .iter()
        .zip(phi)
        .filter(|(_, p)| **p >= PHI_ABSORBS)
        .map(|(s, _)| *s)
        .fold(0.0, f64::max);
    Some((k, max_sd))
}

/// The fraction of a curve's largest measured strain at or above which the marginal sd of its
/// fitted reading error writes the curve off: a band of ±2 sd is then as wide as everything
/// the curve measured, so the likelihood would accept almost any curve there and its shape no
/// longer informs the constants. An extensometer's error is a small fraction of a percent of
/// strain; a misfit the model cannot follow (the specimen's own ductility or rate) is what
/// grows an sd that large. Measured (2026-12-03, the curves as fitted): 0.58–4.4 at most per
/// set on generated single-crystal-like data fitted without specimen factors
/// (`scripts/far_material.py`, seeds 1–5), 0.49 on the joint Alloy 617 calibration; at most
/// 0.23 on the seed's data and 0.15 on the per-temperature Alloy 617 fits.
pub const WRITES_OFF: f64 = 0.25;

/// Whether a reading error of marginal sd `sd` writes off a curve whose largest measured
/// strain is `largest` (one unit): sd ≥ [`WRITES_OFF`] × largest, never for a non-positive
/// largest strain or a sd that is not finite.
pub fn writes_off(sd: f64, largest: f64) -> bool {
    sd.is_finite() && largest > 0.0 && sd / largest >= WRITES_OFF
}

/// The curves whose reading error writes them off ([`WRITES_OFF`]): each curve's index and
/// its marginal sd over its largest measured strain (`sd` and `largest` per curve, in one
/// unit), largest ratio first. A curve whose largest strain is not positive, or whose sd is
/// not finite, is never written off.
pub fn written_off_curves(sd: &[f64], largest: &[f64]) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = sd
        .iter()
        .zip(largest)
        .enumerate()
        .filter(|(_, (s, m))| writes_off(**s, **m))
        .map(|(i, (s, m))| (i, s / m))
        .collect();
    out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    out
}

/// Smallest innovation scale (strain fraction): a numerical floor for noise-free curves.
pub const SIGMA_FLOOR: f64 = 1e-9;
/// Default floor of the rupture-time scatter (ln scale): 1 %, the reproducibility of a
/// rupture time under the best conditions.
pub const DEFAULT_LIFETIME_SD_FLOOR: f64 = 0.01;

const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// An AR(1) reading error: innovation sd `sigma` (strain fraction) and correlation `phi`
/// between consecutive measurements.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ar1 {
    /// Innovation standard deviation, strain as a fraction.
    pub sigma: f64,
    /// Correlation of consecutive errors, in (−1, 1).
    pub phi: f64,
}

/// The quadratic S(φ) = a − 2bφ + cφ² of the AR(1) likelihood: the sum of squared
/// innovations (times σ²) of residuals `e` at correlation φ.
#[derive(Debug, Clone, Copy)]
struct Quad {
    a: f64,
    b: f64,
    c: f64,
    n: usize,
}

impl Quad {
    fn of(e: &[f64]) -> Quad {
        let n = e.len();
        let a: f64 = e.iter().map(|v| v * v).sum();
        let b: f64 = e.windows(2).map(|w| w[0] * w[1]).sum();
        let c: f64 = if n > 2 {
            e[1..n - 1].iter().map(|v| v * v).sum()
        } else {
            0.0
        };
        Quad { a, b, c, n }
    }
    fn s(&self, phi: f64) -> f64 {
        (self.a - 2.0 * self.b * phi + self.c * phi * phi).max(0.0)
    }
    /// Profile −2 ln L (σ² at its optimum S/n), without the constant n(ln 2π + 1).
    fn profile(&self, phi: f64) -> f64 {
        let n = self.n as f64;
        let s = self.s(phi).max(n * SIGMA_FLOOR * SIGMA_FLOOR);
        n * (s / n).ln() - (1.0 - phi * phi).ln()
    }
}

impl Ar1 {
    /// White noise of standard deviation `sd`.
    pub fn white(sd: f64) -> Ar1 {
        Ar1 {
            sigma: sd,
            phi: 0.0,
        }
    }

    /// The AR(1) whose errors have marginal standard deviation `sd` and correlation `phi`.
    pub fn with_marginal(sd: f64, phi: f64) -> Ar1 {
        Ar1 {
            sigma: sd * (1.0 - phi * phi).sqrt(),
            phi,
        }
    }

    /// Marginal standard deviation of one error, σ/√(1 − φ²).
    pub fn marginal_sd(&self) -> f64 {
        self.sigma / (1.0 - self.phi * self.phi).sqrt()
    }

    /// Exact maximum-likelihood estimate from residuals `e` (in measurement order), φ within
    /// ±[`PHI_MAX`]. Fewer than 3 residuals give φ = 0.
    pub fn estimate(e: &[f64]) -> Ar1 {
        let n = e.len();
        if n == 0 {
            return Ar1::white(SIGMA_FLOOR);
        }
        let q = Quad::of(e);
        let phi = if n < 3 { 0.0 } else { argmin_phi(&q) };
        let sigma = (q.s(phi) / n as f64).sqrt().max(SIGMA_FLOOR);
        Ar1 { sigma, phi }
    }

    /// Exact −2 ln L of residuals `e` under this process.
    pub fn neg2ll(&self, e: &[f64]) -> f64 {
        let n = e.len() as f64;
        if e.is_empty() {
            return 0.0;
        }
        let s = Quad::of(e).s(self.phi);
        n * (LN_2PI + 2.0 * self.sigma.ln()) - (1.0 - self.phi * self.phi).ln()
            + s / (self.sigma * self.sigma)
    }

    /// Whiten in place: e ↦ independent standard-normal innovations (√(1−φ²)e_1/σ,
    /// (e_j − φe_{j−1})/σ). Linear, so it applies to Jacobian columns alike (`stride` is the
    /// distance between consecutive entries; 1 for a plain slice).
    pub fn whiten_strided(&self, v: &mut [f64], n: usize, stride: usize) {
        if n == 0 {
            return;
        }
        let inv = 1.0 / self.sigma;
        for j in (1..n).rev() {
            v[j * stride] = (v[j * stride] - self.phi * v[(j - 1) * stride]) * inv;
        }
        v[0] *= (1.0 - self.phi * self.phi).sqrt() * inv;
    }

    /// Inverse of [`Ar1::whiten_strided`]: innovations ↦ errors.
    pub fn unwhiten_strided(&self, v: &mut [f64], n: usize, stride: usize) {
        if n == 0 {
            return;
        }
        v[0] *= self.sigma / (1.0 - self.phi * self.phi).sqrt();
        for j in 1..n {
            v[j * stride] = v[j * stride] * self.sigma + self.phi * v[(j - 1) * stride];
        }
    }

    /// [`Ar1::whiten_strided`] on a contiguous slice.
    pub fn whiten(&self, v: &mut [f64]) {
        let n = v.len();
        self.whiten_strided(v, n, 1);
    }

    /// Draw `n` consecutive errors of this stationary process.
    pub fn simulate<R: Rng>(&self, n: usize, rng: &mut R) -> Vec<f64> {
        let mut out = Vec::with_capacity(n);
        let mut prev = 0.0;
        for j in 0..n {
            let z: f64 = rng.sample(StandardNormal);
            let e = if j == 0 {
                self.marginal_sd() * z
            } else {
                self.phi * prev + self.sigma * z
            };
            out.push(e);
            prev = e;
        }
        out
    }

    /// Variance of the mean of `k` consecutive errors:
    /// σ_m²/k² · (k + 2 Σ_{l=1}^{k−1} (k − l) φ^l).
    pub fn mean_variance(&self, k: usize) -> f64 {
        if k == 0 {
            return f64::NAN;
        }
        let m2 = self.marginal_sd().powi(2);
        let kf = k as f64;
        let p = self.phi;
        // Σ_{l=1}^{k−1} (k − l) p^l by recurrence (exact for any p, O(k)).
        let mut sum = 0.0;
        let mut pl = 1.0;
        for l in 1..k {
            pl *= p;
            if pl.abs() < 1e-300 {
                break;
            }
            sum += (kf - l as f64) * pl;
        }
        m2 * (kf + 2.0 * sum) / (kf * kf)
    }
}

/// φ minimising the profile likelihood on [−PHI_MAX, PHI_MAX]: a grid of 80 intervals, then
/// golden section around the best grid point (the profile is smooth and, in practice,
/// unimodal).
fn argmin_phi(q: &Quad) -> f64 {
    grid_golden(
        -PHI_MAX,
        PHI_MAX,
        GridGolden {
            grid: 80,
            iterations: 60,
            tol: 1e-10,
            tie_to_section: true,
            fallback: 0.0,
        },
        |p| q.profile(p),
    )
    .0
}

/// The error model of one data set: an AR(1) per curve and the rupture-time scatter.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorModel {
    /// Strain reading error per curve (the data set's curve order).
    pub strain: Vec<Ar1>,
    /// Standard deviation of ln(t_r,pred / t_f), over curves with a measured rupture time.
    pub lifetime_sd: f64,
}

/// Raw residuals of one data set at one constant set: per curve, predicted − measured strain
/// (fraction) at the measured times, and ln(t_r,pred / t_f) (`None` without a rupture time).
#[derive(Debug, Clone, PartialEq)]
pub struct Residuals {
    /// Strain residuals per curve.
    pub strain: Vec<Vec<f64>>,
    /// Log lifetime residual per curve.
    pub lifetime: Vec<Option<f64>>,
}

impl ErrorModel {
    /// Maximum-likelihood estimate from residuals; the rupture-time scatter is the root mean
    /// square of the log lifetime residuals, not below `lifetime_sd_floor`.
    pub fn estimate(res: &Residuals, lifetime_sd_floor: f64) -> ErrorModel {
        ErrorModel {
            strain: res.strain.iter().map(|e| Ar1::estimate(e)).collect(),
            lifetime_sd: lifetime_scatter(res, lifetime_sd_floor),
        }
    }

    /// As [`ErrorModel::estimate`] with every curve's reading error white (φ = 0): the first
    /// stage of a maximum-likelihood fit, where a smooth misfit is still seen as misfit.
    pub fn estimate_white(res: &Residuals, lifetime_sd_floor: f64) -> ErrorModel {
        let white = |e: &Vec<f64>| {
            let ms = e.iter().map(|v| v * v).sum::<f64>() / e.len().max(1) as f64;
            Ar1::white(ms.sqrt().max(SIGMA_FLOOR))
        };
        ErrorModel {
            strain: res.strain.iter().map(white).collect(),
            lifetime_sd: lifetime_scatter(res, lifetime_sd_floor),
        }
    }

    /// Exact −2 ln L of `res` under this model (strain and lifetime parts).
    pub fn neg2ll(&self, res: &Residuals) -> f64 {
        self.neg2ll_parts(res).iter().sum()
    }

    /// The part of −2 ln L that does not depend on the residuals, for curves of `n_points`
    /// strain readings each and `n_lives` rupture times: Σ n_i(ln 2π + 2 ln σ_i) −
    /// ln(1 − φ_i²) + n_lives(ln 2π + 2 ln s). −2 ln L is this plus the sum of squares of the
    /// whitened residuals.
    pub fn normalising(&self, n_points: impl Iterator<Item = usize>, n_lives: usize) -> f64 {
        let strain: f64 = self
            .strain
            .iter()
            .zip(n_points)
            .filter(|(_, n)| *n > 0)
            .map(|(p, n)| n as f64 * (LN_2PI + 2.0 * p.sigma.ln()) - (1.0 - p.phi * p.phi).ln())
            .sum();
        strain + n_lives as f64 * (LN_2PI + 2.0 * self.lifetime_sd.ln())
    }

    /// −2 ln L split by curve (each curve's strain readings) and the rupture times' part.
    pub fn neg2ll_curves(&self, res: &Residuals) -> (Vec<f64>, f64) {
        let curves = self
            .strain
            .iter()
            .zip(&res.strain)
            .map(|(p, e)| p.neg2ll(e))
            .collect();
        (curves, self.neg2ll_parts(res)[1])
    }

    /// −2 ln L split as [strain, lifetime].
    pub fn neg2ll_parts(&self, res: &Residuals) -> [f64; 2] {
        let strain: f64 = self
            .strain
            .iter()
            .zip(&res.strain)
            .map(|(p, e)| p.neg2ll(e))
            .sum();
        let s = self.lifetime_sd;
        let life: f64 = res
            .lifetime
            .iter()
            .flatten()
            .map(|l| LN_2PI + 2.0 * s.ln() + (l / s).powi(2))
            .sum();
        [strain, life]
    }

    /// Effective number of independent strain observations, Σ n_i (1 − φ_i)/(1 + φ_i) (the
    /// large-sample information of a mean under AR(1)), plus one per rupture time.
    pub fn effective_n(&self, res: &Residuals) -> f64 {
        let s: f64 = self
            .strain
            .iter()
            .zip(&res.strain)
            .map(|(p, e)| e.len() as f64 * (1.0 - p.phi) / (1.0 + p.phi))
            .sum();
        s + res.lifetime.iter().flatten().count() as f64
    }
}

/// Root mean square of the log lifetime residuals, not below `floor`.
fn lifetime_scatter(res: &Residuals, floor: f64) -> f64 {
    let l: Vec<f64> = res.lifetime.iter().flatten().copied().collect();
    let rms = if l.is_empty() {
        0.0
    } else {
        (l.iter().map(|v| v * v).sum::<f64>() / l.len() as f64).sqrt()
    };
    rms.max(floor)
}

/// Largest growth g of [`GrowingError`]: the reading error at a curve's end at most six times
/// its start (the generated data of `synth --world specimens` reach three times).
pub const GROWTH_MAX: f64 = 5.0;

/// Each measured strain of a curve as a fraction of the curve's largest, in [0, 1] (a
/// negative reading counts as 0; a curve that never rises above 0 gives zeros): the x of
/// [`GrowingError`], taken from the data so that it does not move with the constants.
pub fn strain_fractions(strains: &[f64]) -> Vec<f64> {
    let top = strains.iter().copied().fold(0.0_f64, f64::max);
    if top <= 0.0 {
        return vec![0.0; strains.len()];
    }
    strains.iter().map(|e| (e / top).clamp(0.0, 1.0)).collect()
}

/// Reading error that grows with strain, as an extensometer's does over a test that ends in
/// necking: e_j = (1 + g x_j) u_j, with x_j the measured strain as a fraction of the curve's
/// largest ([`strain_fractions`]), u an AR(1) per curve, and one growth g ≥ 0 for the data
/// set. g = 0 is [`ErrorModel`]'s reading error. `diagnose`'s parametric bootstrap draws its
/// replicates' reading error from this model, fitted to the base fit's residuals, so that a
/// null replicate's late readings are as noisy as the data's (measured on a generated null
/// set whose reading error grew 2.1× over each curve, seed 99607: with the homoscedastic
/// replicates rupture_damage's ratio 13.65 was above all 159 null ratios, a false alarm; the
/// same set generated without the growth gave 4.75).
#[derive(Debug, Clone, PartialEq)]
pub struct GrowingError {
    /// g: the reading error at a curve's largest strain is (1 + g) times its value at zero.
    pub growth: f64,
    /// The AR(1) of u per curve (the data set's curve order).
    pub strain: Vec<Ar1>,
}

impl GrowingError {
    /// The homoscedastic model (g = 0) with the given AR(1) per curve.
    pub fn constant(strain: &[Ar1]) -> GrowingError {
        GrowingError {
            growth: 0.0,
            strain: strain.to_vec(),
        }
    }

    /// Exact −2 ln L of per-curve residuals `e` with strain fractions `x`: for each curve the
    /// AR(1) likelihood of e/w plus 2 Σ ln w, w = 1 + g x (the Jacobian of the scaling).
    pub fn neg2ll(&self, e: &[Vec<f64>], x: &[Vec<f64>]) -> f64 {
        self.strain
            .iter()
            .zip(e.iter().zip(x))
            .map(|(p, (e, x))| {
                let (u, logw) = scaled(e, x, self.growth);
                p.neg2ll(&u) + 2.0 * logw
            })
            .sum()
    }

    /// Maximum-likelihood estimate from per-curve residuals `e` and strain fractions `x`: g on
    /// [0, [`GROWTH_MAX`]] (a grid of 41 points, then golden section about the best), each
    /// curve's AR(1) profiled at every g. g = 0 gives each curve's [`Ar1::estimate`] exactly.
    pub fn estimate(e: &[Vec<f64>], x: &[Vec<f64>]) -> GrowingError {
        Self::estimate_with(e, x, |_, _| 0.0)
    }

    /// The growth from residuals of a fit (per-curve `e`, strain fractions `x`) by restricted
    /// likelihood: [`GrowingError::estimate`]'s criterion plus ln det C(g), C the information
    /// of the fit's constants and specimen effects under the error model at g (`design`). A
    /// fit bends towards its noisiest readings, so the residuals there are smaller than their
    /// errors (leverage) and the plain estimate is low: measured on 200 generated sets with
    /// specimen scatter (seeds 177001–177200, `examples/growth_study.rs`), 0.16–0.25 below the
    /// estimate from the true reading errors. The ln det term is the REML correction of
    /// Patterson & Thompson for the fitted mean, on the fit's linearisation; the curves' AR(1)
    /// stay profiled by maximum likelihood. Falls back to the plain estimate where `design`
    /// does not match the residuals.
    pub fn estimate_restricted(
        e: &[Vec<f64>],
        x: &[Vec<f64>],
        design: &RestrictedDesign,
    ) -> GrowingError {
        if !design.matches(e, x) {
            return Self::estimate(e, x);
        }
        let q = design.fixed.nrows();
        let mut scratch = vec![];
        Self::estimate_with(e, x, |g, ar| {
            let mut c = design.fixed.clone();
            for (i, (block, cols)) in design.curves.iter().enumerate() {
                let n = block.nrows();
                let k = cols.len();
                scratch.clear();
                scratch.resize(n * k, 0.0);
                for (a, _) in cols.iter().enumerate() {
                    let col = &mut scratch[a * n..(a + 1) * n];
                    for (j, v) in col.iter_mut().enumerate() {
                        *v = block[(j, a)] / (1.0 + g * x[i][j]);
                    }
                    ar[i].whiten(col);
                }
                // Its Gram matrix, summed in this order (the estimates of the measurements in
                // docs/SPECIMENS.md; `lsq::gram`'s blocked sums move flat optima by up to 0.01).
                for a in 0..k {
                    for b in 0..=a {
                        let v: f64 = (0..n)
                            .map(|j| scratch[a * n + j] * scratch[b * n + j])
                            .sum();
                        c[(cols[a], cols[b])] += v;
                        if a != b {
                            c[(cols[b], cols[a])] += v;
                        }
                    }
                }
            }
            match c.cholesky() {
                Some(ch) => 2.0 * (0..q).map(|j| ch.l()[(j, j)].ln()).sum::<f64>(),
                None => f64::INFINITY,
            }
        })
    }

    /// The grid-then-golden search of g for the profiled −2 ln L plus `extra(g, AR(1)s)`.
    fn estimate_with(
        e: &[Vec<f64>],
        x: &[Vec<f64>],
        mut extra: impl FnMut(f64, &[Ar1]) -> f64,
    ) -> GrowingError {
        let mut at = |g: f64| -> (f64, Vec<Ar1>) {
            let mut total = 0.0;
            let ar: Vec<Ar1> = e
                .iter()
                .zip(x)
                .map(|(e, x)| {
                    let (u, logw) = scaled(e, x, g);
                    let p = Ar1::estimate(&u);
                    total += p.neg2ll(&u) + 2.0 * logw;
                    p
                })
                .collect();
            total += extra(g, &ar);
            (total, ar)
        };
        // The curves' AR(1) of the last evaluation, kept for the end point.
        let mut last: Option<(f64, Vec<Ar1>)> = None;
        let (growth, _) = grid_golden(
            0.0,
            GROWTH_MAX,
            GridGolden {
                grid: 40,
                iterations: 40,
                tol: 1e-6,
                tie_to_section: false,
                fallback: 0.0,
            },
            |g| {
                let (f, ar) = at(g);
                last = Some((g, ar));
                f
            },
        );
        let strain = match last {
            Some((g, ar)) if g == growth => ar,
            _ => at(growth).1,
        };
        GrowingError { growth, strain }
    }

    /// Draw curve `i`'s reading errors at strain fractions `x` (one per reading).
    pub fn simulate<R: Rng>(&self, i: usize, x: &[f64], rng: &mut R) -> Vec<f64> {
        let mut u = self.strain[i].simulate(x.len(), rng);
        if self.growth != 0.0 {
            for (v, x) in u.iter_mut().zip(x) {
                *v *= 1.0 + self.growth * x;
            }
        }
        u
    }
}

/// What [`GrowingError::estimate_restricted`] needs of a fit: per curve the Jacobian of its
/// raw strain residuals (strain as a fraction, one row per reading) in the columns it depends
/// on, and the information of the rows the growth does not scale (rupture times, the specimen
/// effects' penalties), all in the fit's parameters (free constants, then effects).
#[derive(Debug, Clone, PartialEq)]
pub struct RestrictedDesign {
    /// Per curve: its rows' Jacobian (readings × its columns) and those columns' indices.
    pub curves: Vec<(DMatrix<f64>, Vec<usize>)>,
    /// Σ of the other rows' outer products (parameters × parameters).
    pub fixed: DMatrix<f64>,
}

impl RestrictedDesign {
    /// Whether the design fits residuals `e` and strain fractions `x` (one block a curve, a
    /// row a residual, columns within the parameters).
    fn matches(&self, e: &[Vec<f64>], x: &[Vec<f64>]) -> bool {
        let q = self.fixed.nrows();
        self.fixed.ncols() == q
            && self.curves.len() == e.len()
            && x.len() == e.len()
            && self
                .curves
                .iter()
                .zip(e.iter().zip(x))
                .all(|((b, cols), (e, x))| {
                    b.nrows() == e.len()
                        && x.len() == e.len()
                        && b.ncols() == cols.len()
                        && cols.iter().all(|&c| c < q)
                })
    }
}

/// e/w and Σ ln w for w = 1 + g x.
fn scaled(e: &[f64], x: &[f64], g: f64) -> (Vec<f64>, f64) {
    let mut logw = 0.0;
    let u = e
        .iter()
        .zip(x)
        .map(|(e, x)| {
            let w = 1.0 + g * x;
            logw += w.ln();
            e / w
        })
        .collect();
    (u, logw)
}

/// The share ρ of a reading's error variance that averaging does not shrink, by maximum
/// likelihood from the residuals of a curve's group means (`e`, per curve and point, strain
/// fraction, predicted − measured), the group sizes (`sizes`, readings per point; 1 where a
/// point is a reading) and the strain fractions (`x`, [`strain_fractions`]): each point's
/// residual is put in a reading's units by 1/√((1 − ρ)/m + ρ)
/// ([`crate::data::reading_units_factor`]), and the growth and every curve's AR(1) of
/// [`GrowingError`] are profiled at each ρ; the Jacobian of the scaling, −2 Σ ln factor,
/// enters the criterion. ρ on [0, 1]: a grid of 20 intervals, then golden section about the
/// best point, kept only where it gains [`MISFIT_SHARE_LR`] or more over ρ = 0. ρ is
/// identified only where a curve's groups differ in size (equal groups make it one scale
/// with σ); where none do, 0.
///
/// Why: a mean of m readings has 1/m of a reading's variance only where the reading error
/// is white. Where the model misses the curve's shape, or the reading error drifts, a part
/// of every residual is shared by the group's readings and does not shrink with m, and √m
/// weights then count a long group as far more precise than it is.
pub fn estimate_misfit_share(e: &[Vec<f64>], sizes: &[Vec<usize>], x: &[Vec<f64>]) -> f64 {
    let varied = sizes.iter().any(|m| {
        m.iter()
            .skip(1)
            .any(|&k| k != m.get(1).copied().unwrap_or(1))
    });
    if !varied {
        return 0.0;
    }
    let mut u: Vec<Vec<f64>> = e.to_vec();
    let at = |rho: f64, u: &mut Vec<Vec<f64>>| -> f64 {
        let mut log_factor = 0.0;
        for ((ui, ei), mi) in u.iter_mut().zip(e).zip(sizes) {
            for ((v, r), &m) in ui.iter_mut().zip(ei).zip(mi) {
                let f = crate::data::reading_units_factor(m, rho);
                log_factor += f.ln();
                *v = r * f;
            }
        }
        let model = GrowingError::estimate(u, x);
        model.neg2ll(u, x) - 2.0 * log_factor
    };
    let white = at(0.0, &mut u);
    let (rho, best) = grid_golden(
        0.0,
        1.0,
        GridGolden {
            grid: 20,
            iterations: 40,
            tol: 1e-3,
            tie_to_section: false,
            fallback: 0.0,
        },
        |rho| at(rho, &mut u),
    );
    if white - best < MISFIT_SHARE_LR {
        0.0
    } else {
        rho
    }
}

/// [`estimate_misfit_share`] from a fit's residuals (`res`, a group mean's in a reading's
/// units at the curves' current [`crate::data::ReadingGroups::misfit_share`], as every fit
/// reports them) on `curves`: each point's residual is first turned back into its group
/// mean's, and a curve of readings counts every point as a group of one.
pub fn misfit_share_of(curves: &[crate::data::Curve], res: &Residuals) -> f64 {
    let e: Vec<Vec<f64>> = res
        .strain
        .iter()
        .zip(curves)
        .map(|(e, c)| {
            let mut v = e.clone();
            c.from_reading_units(&mut v);
            v
        })
        .collect();
    let sizes: Vec<Vec<usize>> = curves
        .iter()
        .map(|c| match &c.groups {
            Some(g) => g.sizes().collect(),
            None => vec![1; c.times_h.len()],
        })
        .collect();
    let x: Vec<Vec<f64>> = curves
        .iter()
        .map(|c| strain_fractions(&c.strains))
        .collect();
    estimate_misfit_share(&e, &sizes, &x)
}

/// The likelihood ratio at which [`estimate_misfit_share`] moves off white reading error
/// (ρ = 0): 2.71, the 5 % point of ½χ²₀ + ½χ²₁, the ratio's null distribution for one
/// parameter at its boundary (Self & Liang 1987). Below it ρ is 0. Why a test and not the
/// estimate alone: ρ raises the variance of the long groups, and where those lie late in a
/// curve the growth of the reading error with strain does the same, so on short curves the
/// two trade off along a flat ridge (measured on the seed's 590 °C curves with white reading
/// error, 12 points a curve: ρ̂ 1.0 at a likelihood ratio of 0.65 over ρ = 0, the growth
/// going from 0.61 to 0).
pub const MISFIT_SHARE_LR: f64 = 2.71;

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Group means whose error is the two-part model at a known ρ (an AR(1) per curve in a
    /// reading's units, φ 0.3, growth 0.5, six curves of 61 points over groups of 1–40
    /// readings), 40 sets at each ρ: at ρ 0 (white reading error) the estimates stay below
    /// 0.03 (first run: mean 0.0035, sd 0.0045); at 0.3 and 0.9 their mean is within three
    /// standard errors of the truth (first run: 0.312, sd 0.12; 0.847, sd 0.19 — a curve's
    /// few long groups say little about ρ near 1, where the weights are near 1 anyway); equal
    /// groups leave ρ at 0.
    #[test]
    fn the_misfit_share_is_recovered_from_group_means() {
        let mut rng = ChaCha8Rng::seed_from_u64(216_301);
        let curves = 6;
        let sizes: Vec<Vec<usize>> = (0..curves)
            .map(|i| {
                std::iter::once(1)
                    .chain((0..60).map(|k| 1 + (k * 7 + i * 3) % 40))
                    .collect()
            })
            .collect();
        let x: Vec<Vec<f64>> = sizes
            .iter()
            .map(|m| {
                (0..m.len())
                    .map(|j| j as f64 / (m.len() - 1) as f64)
                    .collect()
            })
            .collect();
        for truth in [0.0, 0.3, 0.9] {
            let mut est = vec![];
            for _ in 0..40 {
                let e: Vec<Vec<f64>> = (0..curves)
                    .map(|i| {
                        let u = Ar1::with_marginal(1e-4 * (1 + i) as f64, 0.3)
                            .simulate(sizes[i].len(), &mut rng);
                        u.iter()
                            .zip(&sizes[i])
                            .zip(&x[i])
                            .map(|((u, &m), x)| {
                                u * (1.0 + 0.5 * x) / crate::data::reading_units_factor(m, truth)
                            })
                            .collect()
                    })
                    .collect();
                est.push(estimate_misfit_share(&e, &sizes, &x));
            }
            let mean = est.iter().sum::<f64>() / est.len() as f64;
            let sd = (est.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / 39.0).sqrt();
            if truth == 0.0 {
                // At the bound the estimates are ≥ 0: they stay small (white reading error
                // keeps weights near √m).
                let most = est.iter().cloned().fold(0.0, f64::max);
                assert!(
                    mean < 0.01 && most < 0.03,
                    "truth 0: mean {mean}, largest {most}"
                );
            } else {
                // Unbiased within three standard errors of the mean of 40.
                let se = sd / 40f64.sqrt();
                assert!(
                    (mean - truth).abs() < 3.0 * se,
                    "truth {truth}: mean {mean}, sd {sd}"
                );
            }
        }
        let equal: Vec<Vec<usize>> = (0..3).map(|_| vec![1, 5, 5, 5, 5]).collect();
        let xe: Vec<Vec<f64>> = (0..3).map(|_| vec![0.0, 0.25, 0.5, 0.75, 1.0]).collect();
        let ee: Vec<Vec<f64>> = (0..3)
            .map(|i| vec![0.0, 1e-4, -2e-4 * i as f64, 3e-4, -1e-4])
            .collect();
        assert_eq!(estimate_misfit_share(&ee, &equal, &xe), 0.0);
    }

    /// (sd, largest strain) per curve → the curves written off, largest ratio first.
    #[test]
    fn a_curve_is_written_off_when_its_sd_reaches_a_quarter_of_its_strain() {
        let cases: &[(&[f64], &[f64], &[usize])] = &[
            // The seed's 560 °C fit (0.16 at most): none.
            (&[0.938, 0.85, 0.2], &[6.02, 6.0, 8.0], &[]),
            // At the threshold exactly, and above it; the larger ratio first.
            (&[0.25, 15.56, 0.1], &[1.0, 8.36, 10.0], &[1, 0]),
            // No strain measured, or no sd: never.
            (&[1.0, f64::NAN, 0.5], &[0.0, 1.0, -1.0], &[]),
            (&[], &[], &[]),
        ];
        for (sd, largest, want) in cases {
            let got: Vec<usize> = written_off_curves(sd, largest)
                .iter()
                .map(|(i, _)| *i)
                .collect();
            assert_eq!(&got, want, "{sd:?} {largest:?}");
        }
        let r = written_off_curves(&[15.56], &[8.36]);
        assert!((r[0].1 - 15.56 / 8.36).abs() < 1e-12);
    }

    /// −2 ln L from the dense AR(1) covariance Σ_jk = σ²/(1−φ²) φ^|j−k|.
    fn dense_neg2ll(p: &Ar1, e: &[f64]) -> f64 {
        let n = e.len();
        let m2 = p.marginal_sd().powi(2);
        let cov = DMatrix::from_fn(n, n, |j, k| m2 * p.phi.powi((j as i32 - k as i32).abs()));
        let ch = cov.clone().cholesky().unwrap();
        let v = DVector::from_column_slice(e);
        let x = ch.solve(&v);
        let logdet: f64 = 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        n as f64 * LN_2PI + logdet + v.dot(&x)
    }

    #[test]
    fn normalising_part_plus_whitened_squares_is_the_dense_likelihood() {
        // Against the dense Gaussian: −2 ln L = normalising + ‖whitened residuals‖², with an
        // empty curve and a curve without a rupture time among them.
        let model = ErrorModel {
            strain: vec![
                Ar1 {
                    sigma: 0.15,
                    phi: 0.7,
                },
                Ar1::white(0.2),
                Ar1 {
                    sigma: 0.3,
                    phi: -0.4,
                },
            ],
            lifetime_sd: 0.4,
        };
        let res = Residuals {
            strain: vec![
                vec![0.3, -0.1, 0.25, 0.4, -0.2],
                vec![],
                vec![0.05, 0.0, 0.11, -0.3],
            ],
            lifetime: vec![Some(0.2), None, Some(-0.5)],
        };
        let mut squares = 0.0;
        let mut dense = 0.0;
        for (p, e) in model.strain.iter().zip(&res.strain) {
            let mut w = e.clone();
            p.whiten(&mut w);
            squares += w.iter().map(|v| v * v).sum::<f64>();
            if !e.is_empty() {
                dense += dense_neg2ll(p, e);
            }
        }
        for l in res.lifetime.iter().flatten() {
            squares += (l / model.lifetime_sd).powi(2);
            dense += LN_2PI + 2.0 * model.lifetime_sd.ln() + (l / model.lifetime_sd).powi(2);
        }
        let got = model.normalising(res.strain.iter().map(|e| e.len()), 2) + squares;
        assert!(
            (got - dense).abs() < 1e-10 * dense.abs(),
            "{got} vs {dense}"
        );
        assert!((got - model.neg2ll(&res)).abs() < 1e-10 * dense.abs());
    }

    #[test]
    fn likelihood_equals_the_dense_gaussian() {
        let e = [0.3, -0.1, 0.25, 0.4, -0.2, 0.05, 0.0, 0.11];
        for p in [
            Ar1::white(0.2),
            Ar1 {
                sigma: 0.15,
                phi: 0.7,
            },
            Ar1 {
                sigma: 0.3,
                phi: -0.4,
            },
        ] {
            let a = p.neg2ll(&e);
            let b = dense_neg2ll(&p, &e);
            assert!(
                (a - b).abs() < 1e-10 * b.abs().max(1.0),
                "{p:?}: {a} vs {b}"
            );
        }
    }

    #[test]
    fn whitening_gives_the_likelihood_quadratic_form() {
        // Σ whitened² + log-determinant terms = −2 ln L.
        let e = vec![0.3, -0.1, 0.25, 0.4, -0.2, 0.05];
        let p = Ar1 {
            sigma: 0.2,
            phi: 0.6,
        };
        let mut w = e.clone();
        p.whiten(&mut w);
        let n = e.len() as f64;
        let q: f64 = w.iter().map(|v| v * v).sum();
        let ll = n * (LN_2PI + 2.0 * p.sigma.ln()) - (1.0 - p.phi * p.phi).ln() + q;
        assert!((ll - p.neg2ll(&e)).abs() < 1e-12);
    }

    #[test]
    fn unwhitening_inverts_whitening() {
        let e = vec![0.3, -0.1, 0.25, 0.4, -0.2, 0.05];
        let p = Ar1 {
            sigma: 0.2,
            phi: 0.6,
        };
        let mut w = e.clone();
        p.whiten(&mut w);
        p.unwhiten_strided(&mut w, 6, 1);
        for (a, b) in w.iter().zip(&e) {
            assert!((a - b).abs() < 1e-14);
        }
    }

    #[test]
    fn estimates_recover_the_process() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for (sd, phi) in [(1e-4, 0.0), (3e-4, 0.5), (5e-5, 0.9), (2e-4, -0.3)] {
            let truth = Ar1::with_marginal(sd, phi);
            let e = truth.simulate(20_000, &mut rng);
            let est = Ar1::estimate(&e);
            assert!((est.phi - phi).abs() < 0.02, "phi {} vs {phi}", est.phi);
            assert!(
                (est.marginal_sd() / sd - 1.0).abs() < 0.05,
                "sd {} vs {sd}",
                est.marginal_sd()
            );
            // The estimate maximises the likelihood: the truth is not better.
            assert!(est.neg2ll(&e) <= truth.neg2ll(&e) + 1e-9);
        }
    }

    #[test]
    fn mean_variance_matches_simulation_and_closed_forms() {
        let p = Ar1::with_marginal(1.0, 0.0);
        assert!((p.mean_variance(25) - 1.0 / 25.0).abs() < 1e-15);
        let p = Ar1::with_marginal(2.0, 0.6);
        // k = 2: σ_m²(2 + 2φ)/4.
        assert!((p.mean_variance(2) - 4.0 * (2.0 + 1.2) / 4.0).abs() < 1e-12);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let k = 10;
        let means: Vec<f64> = (0..20_000)
            .map(|_| p.simulate(k, &mut rng).iter().sum::<f64>() / k as f64)
            .collect();
        let v = means.iter().map(|m| m * m).sum::<f64>() / means.len() as f64;
        assert!((v / p.mean_variance(k) - 1.0).abs() < 0.05, "{v}");
    }

    #[test]
    fn lifetime_scatter_has_a_floor() {
        let res = Residuals {
            strain: vec![vec![0.0, 1e-4, -1e-4]],
            lifetime: vec![Some(1e-4), None],
        };
        let m = ErrorModel::estimate(&res, 0.01);
        assert_eq!(m.lifetime_sd, 0.01);
        let res2 = Residuals {
            strain: vec![vec![0.0; 3]],
            lifetime: vec![Some(0.3), Some(-0.4)],
        };
        let m2 = ErrorModel::estimate(&res2, 0.01);
        assert!((m2.lifetime_sd - (0.125f64).sqrt()).abs() < 1e-12);
        // The lifetime part is a Gaussian in ln t.
        let [_, l] = m2.neg2ll_parts(&res2);
        let s = m2.lifetime_sd;
        let want = 2.0 * (LN_2PI + 2.0 * s.ln()) + (0.09 + 0.16) / (s * s);
        assert!((l - want).abs() < 1e-12);
    }

    #[test]
    fn growing_error_likelihood_is_the_dense_one() {
        // Cov = W Σ_AR W with W = diag(1 + g x): against the dense Gaussian.
        let p = Ar1 {
            sigma: 0.2,
            phi: 0.6,
        };
        let e = vec![0.1, -0.3, 0.45, 0.2, -0.5, 0.9, 0.3];
        let x = strain_fractions(&[0.0, 0.5, 1.0, 2.0, 2.5, 3.5, 4.0]);
        assert_eq!(x[0], 0.0);
        assert_eq!(x[6], 1.0);
        let g = 1.7;
        let n = e.len();
        let m2 = p.marginal_sd().powi(2);
        let w: Vec<f64> = x.iter().map(|x| 1.0 + g * x).collect();
        let cov = DMatrix::from_fn(n, n, |j, k| {
            w[j] * w[k] * m2 * p.phi.powi((j as i32 - k as i32).abs())
        });
        let ch = cov.cholesky().unwrap();
        let v = DVector::from_column_slice(&e);
        let logdet: f64 = 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        let dense = n as f64 * LN_2PI + logdet + v.dot(&ch.solve(&v));
        let m = GrowingError {
            growth: g,
            strain: vec![p],
        };
        let got = m.neg2ll(std::slice::from_ref(&e), std::slice::from_ref(&x));
        assert!(
            (got - dense).abs() < 1e-10 * dense.abs(),
            "{got} vs {dense}"
        );
        // g = 0 is the AR(1) alone.
        let m0 = GrowingError::constant(&[p]);
        assert!((m0.neg2ll(std::slice::from_ref(&e), &[x]) - p.neg2ll(&e)).abs() < 1e-12);
    }

    #[test]
    fn strain_fractions_clamp_negative_readings_and_flat_curves() {
        assert_eq!(
            strain_fractions(&[-0.001, 0.002, 0.004]),
            vec![0.0, 0.5, 1.0]
        );
        assert_eq!(strain_fractions(&[0.0, -0.001]), vec![0.0, 0.0]);
        assert!(strain_fractions(&[]).is_empty());
    }

    #[test]
    fn growth_is_recovered_and_absent_growth_is_estimated_small() {
        // 12 curves of 60 readings, x rising like a creep curve (slow, then fast), AR(1) u;
        // 20 data sets per truth, fixed seed. g = 1.5: the mean estimate within 3 standard
        // errors of the truth (no bias beyond sampling). g = 0: the estimate sits on its
        // boundary in about half the sets (at least 5 of 20: P(fewer) = 0.6 % under ½), and
        // the mean is far below the g = 1.5 estimates.
        let x: Vec<f64> = (0..60)
            .map(|j| {
                let t = j as f64 / 59.0;
                0.3 * t + 0.7 * t.powi(6)
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(20261127);
        for truth in [0.0, 1.5] {
            let mut est_g = vec![];
            for _ in 0..20 {
                let m = GrowingError {
                    growth: truth,
                    strain: (0..12)
                        .map(|i| Ar1::with_marginal(1e-4 * (1.0 + 0.1 * i as f64), 0.5))
                        .collect(),
                };
                let e: Vec<Vec<f64>> = (0..12).map(|i| m.simulate(i, &x, &mut rng)).collect();
                let xs = vec![x.clone(); 12];
                let est = GrowingError::estimate(&e, &xs);
                assert!((0.0..=GROWTH_MAX).contains(&est.growth));
                // The estimate is the likelihood's best: no worse than g = 0 with its own
                // profiled AR(1)s.
                let at0 = GrowingError::estimate(&e, &vec![vec![0.0; 60]; 12]);
                assert_eq!(at0.growth, 0.0);
                assert!(est.neg2ll(&e, &xs) <= at0.neg2ll(&e, &xs) + 1e-9);
                est_g.push(est.growth);
            }
            let n = est_g.len() as f64;
            let mean = est_g.iter().sum::<f64>() / n;
            let sd = (est_g.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            if truth > 0.0 {
                assert!((mean - truth).abs() <= 3.0 * sd / n.sqrt(), "{est_g:?}");
            } else {
                assert!(
                    est_g.iter().filter(|g| **g == 0.0).count() >= 5,
                    "{est_g:?}"
                );
                assert!(mean < 0.2, "{est_g:?}");
            }
        }
    }

    #[test]
    fn restricted_growth_corrects_the_leverage_of_a_fitted_mean() {
        // 10 curves of 30 readings at strain fractions rising like a creep curve; each curve's
        // mean a quadratic in its fraction with its own 3 coefficients; reading error
        // (1 + g x) u, u an AR(1) with φ 0.3, g 1.5; 100 data sets, fixed seed.
        // - Residuals of the generalised least-squares fit under the true covariance (the
        //   setting of restricted likelihood, where it is exact): the restricted estimate's
        //   mean is within 3 standard errors of the truth, the plain one's more than 3 below.
        // - Residuals of ordinary least squares (a fit that knows neither the growth nor the
        //   AR(1), as the constants' fit does not know the growth): the plain estimate is low,
        //   the restricted one less so (their paired difference more than 3 standard errors
        //   above zero). The rest of its bias is the unweighted fit's, which the restricted
        //   likelihood does not model.
        let n = 30;
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = j as f64 / (n - 1) as f64;
                0.3 * t + 0.7 * t.powi(6)
            })
            .collect();
        let k = 3;
        let ncurves = 10;
        let truth = 1.5;
        let p = Ar1::with_marginal(1e-3, 0.3);
        let block = DMatrix::from_fn(n, k, |j, a| x[j].powi(a as i32));
        let cov = DMatrix::from_fn(n, n, |i, j| {
            (1.0 + truth * x[i])
                * (1.0 + truth * x[j])
                * p.marginal_sd().powi(2)
                * p.phi.powi((i as i32 - j as i32).abs())
        });
        let vinv = cov.clone().try_inverse().unwrap();
        // I − H of each fit: e = (I − H) y.
        let eye = DMatrix::<f64>::identity(n, n);
        let ols =
            &eye - &block * (block.transpose() * &block).try_inverse().unwrap() * block.transpose();
        let gls = &eye
            - &block
                * (block.transpose() * &vinv * &block).try_inverse().unwrap()
                * block.transpose()
                * &vinv;
        let design = RestrictedDesign {
            curves: (0..ncurves)
                .map(|i| (block.clone(), (k * i..k * (i + 1)).collect()))
                .collect(),
            fixed: DMatrix::zeros(k * ncurves, k * ncurves),
        };
        let m = GrowingError {
            growth: truth,
            strain: vec![p; ncurves],
        };
        let mut rng = ChaCha8Rng::seed_from_u64(20261202);
        let xs = vec![x.clone(); ncurves];
        let stats = |v: &[f64]| {
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let sd = (v.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            (mean, sd / n.sqrt())
        };
        for (name, hat) in [("gls", &gls), ("ols", &ols)] {
            let (mut plain, mut restricted, mut gain) = (vec![], vec![], vec![]);
            for _ in 0..100 {
                let e: Vec<Vec<f64>> = (0..ncurves)
                    .map(|i| {
                        let y = DVector::from_vec(m.simulate(i, &x, &mut rng));
                        (hat * y).iter().copied().collect()
                    })
                    .collect();
                let a = GrowingError::estimate(&e, &xs).growth;
                let b = GrowingError::estimate_restricted(&e, &xs, &design).growth;
                plain.push(a);
                restricted.push(b);
                gain.push(b - a);
            }
            let (mp, sp) = stats(&plain);
            let (mr, sr) = stats(&restricted);
            let (mg, sg) = stats(&gain);
            let msg = format!("{name}: plain {mp} ± {sp}, restricted {mr} ± {sr}");
            eprintln!("{msg}");
            assert!(mp < truth - 3.0 * sp, "{msg}");
            if name == "gls" {
                assert!((mr - truth).abs() <= 3.0 * sr, "{msg}");
            } else {
                assert!(mg > 3.0 * sg, "{msg}, gain {mg} ± {sg}");
            }
        }
        // A design that does not match the residuals falls back to the plain estimate.
        let e: Vec<Vec<f64>> = (0..ncurves).map(|i| m.simulate(i, &x, &mut rng)).collect();
        let short = RestrictedDesign {
            curves: design.curves[..3].to_vec(),
            fixed: design.fixed.clone(),
        };
        assert_eq!(
            GrowingError::estimate_restricted(&e, &xs, &short),
            GrowingError::estimate(&e, &xs)
        );
    }
}
