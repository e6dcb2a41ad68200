//! Variance components of specimen scatter: the scatter τ of the specimens' ln factors
//! estimated by restricted maximum likelihood (REML) on the linear mixed model that a
//! hierarchical fit's Gauss–Newton linearisation gives, and its profile interval.
//!
//! At a fit (constants θ⁰, effects η⁰) the whitened residuals of curve i are, to first order,
//! r_i ≈ r_i⁰ + X_i δθ + Z_i (η_i − η_i⁰) with X_i, Z_i the whitened Jacobian rows of the free
//! constants and of the curve's own effects. With y_i = Z_i η_i⁰ − r_i⁰ this is the linear
//! mixed model y_i = X_i δθ + Z_i η_i + e_i, η_i ~ N(0, D), e_i ~ N(0, I), D = diag(τ²), whose
//! restricted log-likelihood is (Woodbury, M_i = D⁻¹ + G_i, G_i = Z_iᵀZ_i)
//!
//!   −2 ℓ_R(τ) = Σ_i ln det(I + D G_i) + ln det(A) + Σ_i y_iᵀV_i⁻¹y_i − bᵀA⁻¹b,
//!   A = Σ_i X_iᵀV_i⁻¹X_i,  b = Σ_i X_iᵀV_i⁻¹y_i,  V_i⁻¹ = I − Z_i M_i⁻¹ Z_iᵀ.
//!
//! This is the "LME step" of Lindstrom & Bates (1990) for nonlinear mixed models. REML
//! rather than ML because the constants absorb part of the specimens' spread: the population
//! rate constant takes their mean and the stress sensitivity a trend with stress, so the ML
//! estimate of τ from five or six specimens is biased low by a factor of about
//! √((n − p)/n); the ln det(A) term is exactly the correction for the p directions the
//! constants take (for a linear model it makes Ση̂²/(n − p) the estimate). Dropping ln det(A)
//! gives the ML criterion ([`Lmm::neg2l`]'s `restricted = false`).

use nalgebra::{DMatrix, DVector};

/// Smallest scatter τ (sd of ln factor) the estimate goes to; a fit ending there is compared
/// with the model without that effect, which is the limit τ → 0.
pub const SCATTER_FLOOR: f64 = 1e-3;
/// Largest scatter τ.
pub const SCATTER_MAX: f64 = 3.0;

/// Whether two or more of `curves` share a temperature and a stress: replicates, without
/// which specimen scatter cannot be told from the constants' stress and temperature
/// dependence.
pub fn has_replicates(curves: &[crate::data::Curve]) -> bool {
    shares_a_condition(curves.iter().map(|c| (c.temperature_c, c.stress_mpa)))
}

/// Whether two of the tests' conditions (temperature °C, stress MPa) are the same.
pub fn shares_a_condition(conditions: impl Iterator<Item = (f64, f64)>) -> bool {
    let c: Vec<(f64, f64)> = conditions.collect();
    c.iter()
        .enumerate()
        .any(|(i, a)| c[i + 1..].iter().any(|b| a == b))
}

/// Degrees of freedom the specimens' factors keep beyond a level per temperature and, where a
/// temperature has two stresses or more, a straight line in ln σ there (the directions
/// `specimen_scatter = "beyond_stress_trend"` takes out of the scatter): Σ_T (n_T − 1 − [two
/// stresses or more at T]) over the tests' `conditions` (temperature °C, stress MPa), one per
/// specimen. An upper bound: the constants take further directions.
pub fn dof_beyond_trend(conditions: impl Iterator<Item = (f64, f64)>) -> usize {
    let mut c: Vec<(f64, f64)> = conditions.collect();
    c.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut dof = 0;
    let mut i = 0;
    while i < c.len() {
        let t = c[i].0;
        let at: Vec<f64> = c[i..]
            .iter()
            .take_while(|x| x.0 == t)
            .map(|x| x.1)
            .collect();
        i += at.len();
        let two_stresses = at.iter().any(|s| *s != at[0]);
        dof += at.len() - 1 - usize::from(two_stresses);
    }
    dof
}

/// Most kinds of specimen effect a curve carries (rate, ductility, coarsening).
pub const MAX_KINDS: usize = 3;
/// A k × k matrix of the effects (k ≤ [`MAX_KINDS`], the rest zero).
pub type KMat = [[f64; MAX_KINDS]; MAX_KINDS];
/// A vector over the effects.
pub type KVec = [f64; MAX_KINDS];

/// One curve's sums for the linear mixed model (k ≤ [`MAX_KINDS`] effects, p fixed effects).
#[derive(Debug, Clone, PartialEq)]
pub struct CurveBlock {
    /// G = ZᵀZ (k × k).
    pub zz: KMat,
    /// XᵀZ (p × k).
    pub xz: Vec<KVec>,
    /// XᵀX (p × p).
    pub xx: DMatrix<f64>,
    /// Xᵀy.
    pub xy: DVector<f64>,
    /// Zᵀy.
    pub zy: KVec,
    /// yᵀy.
    pub yy: f64,
}

/// The linear mixed model of a hierarchical fit's linearisation.
#[derive(Debug, Clone, PartialEq)]
pub struct Lmm {
    /// Effects per curve.
    pub k: usize,
    /// Fixed effects (free constants).
    pub p: usize,
    /// One block per curve.
    pub blocks: Vec<CurveBlock>,
}

/// The k × k matrix M = D⁻¹ + G and its inverse, for scatter `tau` (Gauss–Jordan with
/// partial pivoting; k ≤ [`MAX_KINDS`]).
fn m_inv(k: usize, g: &KMat, tau: &[f64]) -> KMat {
    // One and two kinds in closed form, as before the third kind: the same arithmetic, so
    // fits and batteries of rate and ductility effects reproduce to the bit.
    let mut out = [[0.0; MAX_KINDS]; MAX_KINDS];
    if k == 1 {
        out[0][0] = 1.0 / (1.0 / (tau[0] * tau[0]) + g[0][0]);
        return out;
    }
    if k == 2 {
        let a = 1.0 / (tau[0] * tau[0]) + g[0][0];
        let d = 1.0 / (tau[1] * tau[1]) + g[1][1];
        let (b, c) = (g[0][1], g[1][0]);
        let det = a * d - b * c;
        out[0][0] = d / det;
        out[0][1] = -b / det;
        out[1][0] = -c / det;
        out[1][1] = a / det;
        return out;
    }
    let mut m = *g;
    for a in 0..k {
        m[a][a] += 1.0 / (tau[a] * tau[a]);
    }
    small_inverse(k, &m)
}

/// Inverse of the leading k × k block of `m` (zeros elsewhere; NaN if singular).
pub fn small_inverse(k: usize, m: &KMat) -> KMat {
    let mut a = *m;
    let mut inv = [[0.0; MAX_KINDS]; MAX_KINDS];
    for (d, row) in inv.iter_mut().enumerate().take(k) {
        row[d] = 1.0;
    }
    for c in 0..k {
        let piv = (c..k)
            .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
            .unwrap_or(c);
        a.swap(c, piv);
        inv.swap(c, piv);
        let d = a[c][c];
        for col in 0..k {
            a[c][col] /= d;
            inv[c][col] /= d;
        }
        for r in 0..k {
            if r != c {
                let f = a[r][c];
                for col in 0..k {
                    a[r][col] -= f * a[c][col];
                    inv[r][col] -= f * inv[c][col];
                }
            }
        }
    }
    inv
}

/// Determinant of the leading k × k block of `m` (k ≤ [`MAX_KINDS`]).
pub fn small_det(k: usize, m: &KMat) -> f64 {
    match k {
        0 => 1.0,
        1 => m[0][0],
        2 => m[0][0] * m[1][1] - m[0][1] * m[1][0],
        _ => {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        }
    }
}

/// Whether the leading k × k block of the symmetric `m` is positive definite (all leading
/// minors positive).
pub fn small_pd(k: usize, m: &KMat) -> bool {
    (1..=k).all(|j| small_det(j, m) > 0.0)
}

/// ln det(I + D G) for k ≤ [`MAX_KINDS`].
fn ln_det_idg(k: usize, g: &KMat, tau: &[f64]) -> f64 {
    if k == 1 {
        return (1.0 + tau[0] * tau[0] * g[0][0]).ln();
    }
    if k == 2 {
        let (d0, d1) = (tau[0] * tau[0], tau[1] * tau[1]);
        let m00 = 1.0 + d0 * g[0][0];
        let m11 = 1.0 + d1 * g[1][1];
        return (m00 * m11 - d0 * g[0][1] * d1 * g[1][0]).ln();
    }
    let mut m = [[0.0; MAX_KINDS]; MAX_KINDS];
    for a in 0..k {
        for b in 0..k {
            m[a][b] = tau[a] * tau[a] * g[a][b] + if a == b { 1.0 } else { 0.0 };
        }
    }
    small_det(k, &m).ln()
}

impl Lmm {
    /// The model from the whitened residuals `r` and Jacobian `jac` of a hierarchical
    /// problem: rows `rows[i]` of curve i, fixed-effect columns `0..p`, the effect of kind
    /// `kk` of curve i in column `p + kk·n + i`, current effects `eta` (kind-major).
    pub fn from_jacobian(
        jac: &DMatrix<f64>,
        r: &[f64],
        rows: &[(usize, usize)],
        p: usize,
        k: usize,
        eta: &[f64],
    ) -> Lmm {
        let n = rows.len();
        let m = jac.nrows();
        let data = jac.as_slice();
        let blocks = (0..n)
            .map(|i| {
                let (a, b) = rows[i];
                // Column c of the Jacobian on curve i's rows.
                let col = |c: usize| &data[c * m + a..c * m + b];
                let zc = |kk: usize| col(p + kk * n + i);
                let dot =
                    |x: &[f64], y: &[f64]| -> f64 { x.iter().zip(y).map(|(u, v)| u * v).sum() };
                // y = Z η⁰ − r⁰.
                let y: Vec<f64> = (a..b)
                    .map(|row| {
                        let mut v = -r[row];
                        for kk in 0..k {
                            v += zc(kk)[row - a] * eta[kk * n + i];
                        }
                        v
                    })
                    .collect();
                let mut zz = [[0.0; MAX_KINDS]; MAX_KINDS];
                let mut zy = [0.0; MAX_KINDS];
                for kk in 0..k {
                    for ll in 0..k {
                        zz[kk][ll] = dot(zc(kk), zc(ll));
                    }
                    zy[kk] = dot(zc(kk), &y);
                }
                let xz: Vec<KVec> = (0..p)
                    .map(|c| {
                        let mut v = [0.0; MAX_KINDS];
                        for kk in 0..k {
                            v[kk] = dot(col(c), zc(kk));
                        }
                        v
                    })
                    .collect();
                // Symmetric: each product commutes exactly, so the mirror is the same sum.
                let mut xx = DMatrix::zeros(p, p);
                for c in 0..p {
                    for d in c..p {
                        let v = dot(col(c), col(d));
                        xx[(c, d)] = v;
                        xx[(d, c)] = v;
                    }
                }
                let xy = DVector::from_fn(p, |c, _| dot(col(c), &y));
                let yy = y.iter().map(|v| v * v).sum();
                CurveBlock {
                    zz,
                    xz,
                    xx,
                    xy,
                    zy,
                    yy,
                }
            })
            .collect();
        Lmm { k, p, blocks }
    }

    /// The sums at scatter `tau`: A = Σ XᵀV⁻¹X (lower triangle), b = Σ XᵀV⁻¹y, Σ yᵀV⁻¹y and
    /// Σ ln det(I + D G_i).
    fn sums(&self, tau: &[f64]) -> (DMatrix<f64>, DVector<f64>, f64, f64) {
        let (k, p) = (self.k, self.p);
        let mut a = DMatrix::<f64>::zeros(p, p);
        let mut b = DVector::<f64>::zeros(p);
        let mut q = 0.0;
        let mut ld = 0.0;
        let mut xzm = vec![[0.0; MAX_KINDS]; p];
        for bl in &self.blocks {
            let mi = m_inv(k, &bl.zz, tau);
            ld += ln_det_idg(k, &bl.zz, tau);
            // yᵀV⁻¹y = yᵀy − (Zᵀy)ᵀ M⁻¹ (Zᵀy).
            let mut s = 0.0;
            for kk in 0..k {
                for ll in 0..k {
                    s += bl.zy[kk] * mi[kk][ll] * bl.zy[ll];
                }
            }
            q += bl.yy - s;
            // (XᵀZ) M⁻¹.
            for (v, row) in xzm.iter_mut().zip(&bl.xz) {
                *v = [0.0; MAX_KINDS];
                for ll in 0..k {
                    for kk in 0..k {
                        v[ll] += row[kk] * mi[kk][ll];
                    }
                }
            }
            for c in 0..p {
                let mut bc = bl.xy[c];
                for kk in 0..k {
                    bc -= xzm[c][kk] * bl.zy[kk];
                }
                b[c] += bc;
                // The lower triangle: all the Cholesky factorisation below reads.
                for d in 0..=c {
                    let mut v = bl.xx[(c, d)];
                    for kk in 0..k {
                        v -= xzm[c][kk] * bl.xz[d][kk];
                    }
                    a[(c, d)] += v;
                }
            }
        }
        (a, b, q, ld)
    }

    /// The Cholesky factor of A with a small ridge: A may be near singular (a constant the
    /// data hardly determine), and the ridge, relative to its diagonal, keeps the
    /// factorisation defined without changing the τ-dependence that matters.
    fn factor(&self, mut a: DMatrix<f64>) -> Option<nalgebra::Cholesky<f64, nalgebra::Dyn>> {
        let scale = a
            .diagonal()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-300);
        for c in 0..self.p {
            a[(c, c)] += 1e-12 * scale;
        }
        a.cholesky()
    }

    /// −2 × the (restricted, if `restricted`) log-likelihood at scatter `tau` (one per kind),
    /// up to a constant.
    pub fn neg2l(&self, tau: &[f64], restricted: bool) -> f64 {
        let (a, b, mut q, ld) = self.sums(tau);
        if self.p == 0 {
            return ld + q;
        }
        let Some(ch) = self.factor(a) else {
            return f64::INFINITY;
        };
        let sol = ch.solve(&b);
        q -= b.dot(&sol);
        let mut out = ld + q;
        if restricted {
            out += 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        }
        out
    }

    /// ln det A(τ), A = Σ X_iᵀV_i⁻¹X_i: the constants' information with the effects
    /// integrated out at scatter `tau`, the term REML adds to the ML criterion (0 without
    /// constants; +∞ where A is not positive definite).
    pub fn ln_det_info(&self, tau: &[f64]) -> f64 {
        if self.p == 0 {
            return 0.0;
        }
        let (a, ..) = self.sums(tau);
        match self.factor(a) {
            Some(ch) => 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>(),
            None => f64::INFINITY,
        }
    }

    /// The scatter minimising [`Lmm::neg2l`], each within [[`SCATTER_FLOOR`],
    /// [`SCATTER_MAX`]], by coordinate-wise search in ln τ from `start`.
    pub fn estimate(&self, start: &[f64], restricted: bool) -> Vec<f64> {
        minimise_scatter(start, |t| self.neg2l(t, restricted))
    }

    /// The profile interval of τ_kind at cutoffs `cut` ([`Cutoffs::chi2`] for the χ²₁ rule,
    /// [`Cutoffs::small_sample`] calibrated to the effects' degrees of freedom): the scatters
    /// whose criterion, the others re-estimated, lies within the cutoff of the minimum at
    /// `tau_hat`. The lower end is 0 when the floor is inside; the upper end [`SCATTER_MAX`]
    /// when the interval reaches it.
    pub fn interval(
        &self,
        kind: usize,
        tau_hat: &[f64],
        cut: Cutoffs,
        restricted: bool,
    ) -> (f64, f64) {
        profile_interval(kind, tau_hat, cut, |t| self.neg2l(t, restricted))
    }

    /// The effective degrees of freedom of kind `kind`'s scatter at scatter `tau`: with M the
    /// residual maker of the fixed effects X and Z the kind's effect columns, the effects are
    /// seen beyond the constants through ZᵀMZ, whose eigenvalues λ_j give each direction the
    /// variance τ² + 1/λ_j; the Fisher information of ln τ² is then that of
    /// Σ_j (τ²λ_j / (1 + τ²λ_j))² exact degrees of freedom. n − p for n groups seen precisely
    /// whose levels p fixed effects act on (a one-way model); a direction a constant mimics
    /// exactly (the rate factors' common level and the rate constant) counts nothing, one
    /// the data see poorly in part. The degrees of freedom of [`Cutoffs::small_sample`].
    pub fn effect_dof(&self, kind: usize, tau: f64) -> f64 {
        let (n, p) = (self.blocks.len(), self.p);
        let mut zmz = DMatrix::<f64>::from_fn(n, n, |i, l| {
            if i == l {
                self.blocks[i].zz[kind][kind]
            } else {
                0.0
            }
        });
        if p > 0 {
            let mut xx = DMatrix::<f64>::zeros(p, p);
            for b in &self.blocks {
                xx += &b.xx;
            }
            let eig = xx.symmetric_eigen();
            let top = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(*v));
            // W = Λ^{-1/2} Vᵀ XᵀZ over the directions X determines: ZᵀX(XᵀX)⁺XᵀZ = WᵀW.
            let xz = DMatrix::<f64>::from_fn(p, n, |c, i| self.blocks[i].xz[c][kind]);
            let mut w = eig.eigenvectors.transpose() * xz;
            for j in 0..p {
                let l = eig.eigenvalues[j];
                let f = if l > 1e-12 * top { 1.0 / l.sqrt() } else { 0.0 };
                w.row_mut(j).scale_mut(f);
            }
            zmz -= w.transpose() * w;
        }
        let t2 = tau * tau;
        zmz.symmetric_eigen()
            .eigenvalues
            .iter()
            .map(|&l| {
                let r = t2 * l.max(0.0);
                (r / (1.0 + r)).powi(2)
            })
            .sum()
    }
}

/// Where a scatter's profile interval ends: the rise of −2 ln L from its minimum allowed
/// below the estimate (`lower`) and above it (`upper`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cutoffs {
    /// The rise at the interval's lower end.
    pub lower: f64,
    /// The rise at the interval's upper end.
    pub upper: f64,
}

impl Cutoffs {
    /// The same rise `chi2` at both ends (3.84 for the asymptotic 95 % interval).
    pub fn chi2(chi2: f64) -> Cutoffs {
        Cutoffs {
            lower: chi2,
            upper: chi2,
        }
    }

    /// The profile's cutoffs that make a `level` interval of a scatter whose effects have
    /// `dof` degrees of freedom ([`Lmm::effect_dof`], at least 1) the exact one of a normal
    /// variance, [τ̂·√(d/χ²_{d,(1+level)/2}), τ̂·√(d/χ²_{d,(1−level)/2})]: there the profile
    /// rises by d·(u − 1 − ln u) at u = (τ̂/τ)², so the cutoffs are that rise at u =
    /// χ²_{d,q}/d. The asymptotic χ²₁ rule (3.84 at both ends) is their limit for large d;
    /// with the 3–6 degrees of freedom of a few specimens it ends the interval about 10 %
    /// too low above the estimate (docs/SPECIMENS.md, "The scatter's interval with few
    /// specimens").
    pub fn small_sample(dof: f64, level: f64) -> Cutoffs {
        let d = if dof >= 1.0 { dof } else { 1.0 };
        let quantile = |q: f64| chi2_quantile(d, q);
        let rise = |q: f64| {
            let u = quantile(q) / d;
            d * (u - 1.0 - u.ln())
        };
        Cutoffs {
            lower: rise(0.5 * (1.0 + level)),
            upper: rise(0.5 * (1.0 - level)),
        }
    }
}

/// The `q` quantile of the χ² distribution with `d` ≥ 1 degrees of freedom, by bisection in
/// ln x on the CDF: statrs' own inverse is NaN at the 2.5 % point of one degree of freedom.
pub fn chi2_quantile(d: f64, q: f64) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    let chi = ChiSquared::new(d).expect("d ≥ 1");
    let (mut lo, mut hi) = ((1e-12f64).ln(), (10.0 * d + 100.0).ln());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi.cdf(mid.exp()) < q {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).exp()
}

/// The profile interval of τ_kind at cutoffs `cut` under the criterion `f` (−2 ln L in the
/// scatters, minimal at `tau_hat`): the scatters whose criterion, the others re-estimated,
/// lies within the cutoff of the minimum (`cut.lower` below `tau_hat`, `cut.upper` above).
/// The lower end is 0 when the floor is inside; the upper end [`SCATTER_MAX`] when the
/// interval reaches it.
pub fn profile_interval(
    kind: usize,
    tau_hat: &[f64],
    cut: Cutoffs,
    f: impl Fn(&[f64]) -> f64,
) -> (f64, f64) {
    let k = tau_hat.len();
    let best = f(tau_hat);
    let prof = |lt: f64| -> f64 {
        let mut t = tau_hat.to_vec();
        t[kind] = lt.exp();
        if k == 1 {
            return f(&t) - best;
        }
        // The others re-estimated (coordinate-wise, as [`minimise_scatter`]).
        let rounds = if k > 2 { 3 } else { 1 };
        for _ in 0..rounds {
            for other in (0..k).filter(|&o| o != kind) {
                t[other] = minimise_one(&t, other, &f);
            }
        }
        f(&t) - best
    };
    let lh = tau_hat[kind].clamp(SCATTER_FLOOR, SCATTER_MAX).ln();
    let (lf, lm) = (SCATTER_FLOOR.ln(), SCATTER_MAX.ln());
    let cross = |mut inside: f64, mut outside: f64, chi2: f64| -> f64 {
        for _ in 0..60 {
            let mid = 0.5 * (inside + outside);
            if prof(mid) <= chi2 {
                inside = mid;
            } else {
                outside = mid;
            }
            if (inside - outside).abs() < 1e-6 {
                break;
            }
        }
        0.5 * (inside + outside)
    };
    let lo = if prof(lf) <= cut.lower {
        0.0
    } else {
        cross(lh, lf, cut.lower).exp()
    };
    let hi = if prof(lm) <= cut.upper {
        SCATTER_MAX
    } else {
        cross(lh, lm, cut.upper).exp()
    };
    (lo, hi)
}

/// The value of coordinate `k` of `tau` minimising `f` with the others held: a grid in ln τ,
/// then golden section around its best point.
fn minimise_one(tau: &[f64], k: usize, f: impl Fn(&[f64]) -> f64) -> f64 {
    let g = |lt: f64| {
        let mut t = tau.to_vec();
        t[k] = lt.exp();
        f(&t)
    };
    let (lf, lm) = (SCATTER_FLOOR.ln(), SCATTER_MAX.ln());
    let opts = crate::scalar_min::GridGolden {
        grid: 40,
        iterations: 60,
        tol: 1e-9,
        tie_to_section: true,
        fallback: lf,
    };
    crate::scalar_min::grid_golden(lf, lm, opts, g).0.exp()
}

/// Coordinate-wise minimisation of `f` over the scatters from `start` (clamped to the
/// allowed range).
pub fn minimise_scatter(start: &[f64], f: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let mut tau: Vec<f64> = start
        .iter()
        .map(|t| t.clamp(SCATTER_FLOOR, SCATTER_MAX))
        .collect();
    let rounds = if tau.len() > 1 { 4 } else { 1 };
    for _ in 0..rounds {
        for k in 0..tau.len() {
            tau[k] = minimise_one(&tau, k, &f);
        }
    }
    tau
}

/// The random-effects terms of the Laplace −2 ln L, Σ_i [η_iᵀD⁻¹η_i + ln det(I + D G_i)],
/// for effects `eta` (kind-major: kind k of curve i at k·n + i), Gram matrices `g` and
/// scatter `tau` (one per kind).
pub fn laplace_terms(eta: &[f64], g: &[KMat], tau: &[f64]) -> f64 {
    let n = g.len();
    let k = tau.len();
    let mut s = 0.0;
    for (i, gi) in g.iter().enumerate() {
        for (kk, t) in tau.iter().enumerate() {
            s += (eta[kk * n + i] / t).powi(2);
        }
        s += ln_det_idg(k, gi, tau);
    }
    s
}

/// Where a hierarchical fit's scatter estimate comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScatterMethod {
    /// The linear mixed model of the fit's Gauss–Newton linearisation ([`Lmm`]; Lindstrom &
    /// Bates' LME step): constants and effects move with τ along the linear model.
    #[default]
    LinearMixedModel,
    /// The Laplace criterion at the fitted conditional modes, held ([`laplace_criterion`]):
    /// used once a step of the scatter to the linear mixed model's estimate did not pay
    /// ([`step_pays`]), or that model would stay where this criterion still falls, i.e.
    /// where the linear model's promise of gains from larger or smaller effects is not what
    /// the curves, refitted, deliver.
    LaplaceAtModes,
    /// The linear mixed model's restricted likelihood with a within-temperature trend of the
    /// effects with ln σ as a fixed effect (`[objective] specimen_scatter =
    /// "beyond_stress_trend"`): the scatter of the specimens beyond what follows stress.
    BeyondStressTrend,
}

impl ScatterMethod {
    /// A sentence for reports where the method is not the usual one (empty otherwise).
    pub fn note(self) -> &'static str {
        match self {
            ScatterMethod::LinearMixedModel => "",
            ScatterMethod::LaplaceAtModes => {
                "estimated by the Laplace criterion at the fitted effects (the linear mixed model of the fit's linearisation stopped where that criterion still fell, or its step did not pay)"
            }
            ScatterMethod::BeyondStressTrend => {
                "estimated by restricted likelihood from how the specimens' factors differ beyond a level and a straight line in ln σ at each temperature ([objective] specimen_scatter = \"beyond_stress_trend\"): a trend of the factors with stress, or a difference between temperatures, is not counted as scatter, and costs the fit its penalty at this scatter"
            }
        }
    }
}

/// Whether a step of the scatter paid: the Laplace −2 ln L after refitting the constants
/// and effects at the new scatter (`after`) is not above its value at the previous accepted
/// point (`before`) by more than `tol`. A value that cannot be evaluated (NaN) does not pay.
pub fn step_pays(before: f64, after: f64, tol: f64) -> bool {
    after <= before + tol
}

/// −2 ln L in the scatter `tau` at fixed conditional modes `eta` (kind-major) with Gram
/// matrices `g`: the Laplace terms ([`laplace_terms`]; the data term does not depend on τ
/// at fixed modes), plus, if `restricted`, REML's ln det A(τ) from `lmm`.
pub fn laplace_criterion(lmm: &Lmm, eta: &[f64], g: &[KMat], tau: &[f64], restricted: bool) -> f64 {
    laplace_terms(eta, g, tau)
        + if restricted {
            lmm.ln_det_info(tau)
        } else {
            0.0
        }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// (conditions, degrees of freedom beyond a level and a line in ln σ per temperature).
    #[test]
    fn degrees_of_freedom_beyond_the_trend_count_specimens_past_level_and_line() {
        for (conds, want) in [
            (vec![], 0),
            (vec![(900.0, 30.0)], 0),
            // Two stresses: a level and a line take both.
            (vec![(900.0, 30.0), (900.0, 35.0)], 0),
            // Alloy 617 at 900 °C: seven specimens, seven stresses.
            ((0..7).map(|k| (900.0, 25.0 + 5.0 * k as f64)).collect(), 5),
            // Four specimens at three stresses (a replicate pair): 4 − 2.
            (
                vec![(600.0, 80.0), (600.0, 91.0), (600.0, 80.0), (600.0, 104.0)],
                2,
            ),
            // Replicates at one stress only: a level, no line.
            (vec![(600.0, 80.0), (600.0, 80.0), (600.0, 80.0)], 2),
            // Per temperature, in any order: 3 − 2 at 850, 1 − 1 at 900, 2 − 2 at 950.
            (
                vec![
                    (950.0, 20.0),
                    (850.0, 40.0),
                    (900.0, 30.0),
                    (850.0, 45.0),
                    (950.0, 25.0),
                    (850.0, 50.0),
                ],
                1,
            ),
        ] {
            assert_eq!(dof_beyond_trend(conds.iter().copied()), want, "{conds:?}");
        }
    }

    #[test]
    fn replicates_are_two_tests_at_one_temperature_and_stress() {
        for (conds, want) in [
            (vec![], false),
            (vec![(900.0, 30.0)], false),
            (vec![(900.0, 30.0), (900.0, 35.0), (950.0, 30.0)], false),
            (vec![(900.0, 30.0), (950.0, 30.0), (900.0, 30.0)], true),
            (vec![(750.0, 100.0), (750.0, 100.0)], true),
        ] {
            assert_eq!(shares_a_condition(conds.iter().copied()), want, "{conds:?}");
        }
    }

    /// −2 ln L of the linear mixed model from its dense marginal covariance V = I + Z D Zᵀ,
    /// with β profiled out (restricted: plus ln det XᵀV⁻¹X).
    fn dense(
        x: &DMatrix<f64>,
        z: &DMatrix<f64>,
        y: &DVector<f64>,
        groups: &[(usize, usize)],
        tau: &[f64],
        restricted: bool,
    ) -> f64 {
        let m = y.len();
        let n = groups.len();
        let k = tau.len();
        let mut v = DMatrix::<f64>::identity(m, m);
        for (i, &(a, b)) in groups.iter().enumerate() {
            for r in a..b {
                for s in a..b {
                    for kk in 0..k {
                        v[(r, s)] += z[(r, kk * n + i)] * tau[kk] * tau[kk] * z[(s, kk * n + i)];
                    }
                }
            }
        }
        let ch = v.cholesky().unwrap();
        let ld: f64 = 2.0 * ch.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        let vix = ch.solve(x);
        let viy = ch.solve(y);
        let a = x.transpose() * &vix;
        let b = x.transpose() * &viy;
        let ach = a.clone().cholesky().unwrap();
        let beta = ach.solve(&b);
        let q = y.dot(&viy) - b.dot(&beta);
        let mut out = ld + q;
        if restricted {
            out += 2.0 * ach.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        }
        out
    }

    /// X, Z, y and the groups' row ranges of a linear mixed model.
    type Problem = (
        DMatrix<f64>,
        DMatrix<f64>,
        DVector<f64>,
        Vec<(usize, usize)>,
    );

    /// A random linear mixed model: n groups of `per` rows, p fixed effects, k effects.
    fn problem(seed: u64, n: usize, per: usize, p: usize, k: usize, tau: &[f64]) -> Problem {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
        let m = n * per;
        let x = DMatrix::from_fn(m, p, |_, _| g());
        let mut z = DMatrix::zeros(m, k * n);
        let groups: Vec<(usize, usize)> = (0..n).map(|i| (i * per, (i + 1) * per)).collect();
        for (i, &(a, b)) in groups.iter().enumerate() {
            for r in a..b {
                for kk in 0..k {
                    z[(r, kk * n + i)] = 1.0 + 0.5 * g();
                }
            }
        }
        let beta = DVector::from_fn(p, |_, _| g());
        let mut y = &x * beta;
        for (i, &(a, b)) in groups.iter().enumerate() {
            let eff: Vec<f64> = (0..k).map(|kk| tau[kk] * g()).collect();
            for r in a..b {
                y[r] += g();
                for kk in 0..k {
                    y[r] += z[(r, kk * n + i)] * eff[kk];
                }
            }
        }
        (x, z, y, groups)
    }

    fn lmm_of(
        x: &DMatrix<f64>,
        z: &DMatrix<f64>,
        y: &DVector<f64>,
        groups: &[(usize, usize)],
        k: usize,
    ) -> Lmm {
        // As a hierarchical problem's Jacobian: [X | Z], residual r = −y at η⁰ = 0.
        let p = x.ncols();
        let mut jac = DMatrix::zeros(x.nrows(), p + z.ncols());
        jac.view_mut((0, 0), (x.nrows(), p)).copy_from(x);
        jac.view_mut((0, p), (z.nrows(), z.ncols())).copy_from(z);
        let r: Vec<f64> = y.iter().map(|v| -v).collect();
        Lmm::from_jacobian(&jac, &r, groups, p, k, &vec![0.0; z.ncols()])
    }

    #[test]
    fn woodbury_criterion_equals_the_dense_gaussian() {
        for (k, tau) in [
            (1usize, vec![0.7]),
            (2, vec![0.4, 1.3]),
            (3, vec![0.4, 1.3, 0.8]),
        ] {
            let (x, z, y, groups) = problem(3 + k as u64, 6, 5, 3, k, &tau);
            let lmm = lmm_of(&x, &z, &y, &groups, k);
            for t in [tau.clone(), tau.iter().map(|v| v * 0.3).collect::<Vec<_>>()] {
                for restricted in [false, true] {
                    let a = lmm.neg2l(&t, restricted);
                    let b = dense(&x, &z, &y, &groups, &t, restricted);
                    // The two differ by the constant m ln 2π only through neither: both omit it.
                    assert!(
                        (a - b).abs() < 1e-8 * b.abs().max(1.0),
                        "k {k} {t:?} {restricted}: {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_criterion_does_not_depend_on_where_it_is_linearised() {
        // Moving η⁰ (and r⁰ with it, r⁰ = Zη⁰ − y) leaves y and so the criterion unchanged.
        let (x, z, y, groups) = problem(9, 5, 4, 2, 1, &[0.5]);
        let a = lmm_of(&x, &z, &y, &groups, 1).neg2l(&[0.5], true);
        let p = x.ncols();
        let mut jac = DMatrix::zeros(x.nrows(), p + z.ncols());
        jac.view_mut((0, 0), (x.nrows(), p)).copy_from(&x);
        jac.view_mut((0, p), (z.nrows(), z.ncols())).copy_from(&z);
        let eta: Vec<f64> = (0..z.ncols()).map(|i| 0.1 * i as f64 - 0.2).collect();
        let zeta = &z * DVector::from_column_slice(&eta);
        let r: Vec<f64> = (0..y.len()).map(|i| zeta[i] - y[i]).collect();
        let b = Lmm::from_jacobian(&jac, &r, &groups, p, 1, &eta).neg2l(&[0.5], true);
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }

    #[test]
    fn reml_is_unbiased_where_ml_is_not_and_its_interval_covers() {
        // Groups whose effects are seen through many rows (as a logged curve sees its
        // specimen's rate): τ̂² ≈ Σ η̂²/(n − p) under REML, Σ η̂²/n under ML. Over many data
        // sets the mean REML τ̂² is near τ² and the ML one near τ²(n − p)/n; the 95 %
        // interval covers τ in about 95 % of sets.
        let (n, p, tau) = (6usize, 2usize, 0.3f64);
        let reps = 400;
        let (mut reml, mut ml, mut cover, mut cover_small) = (0.0, 0.0, 0, 0);
        for s in 0..reps {
            let (x, z, y, groups) = {
                // X constant within a group (a constant acts on a curve's level), Z = 10.
                let mut rng = ChaCha8Rng::seed_from_u64(1000 + s);
                let mut g = || -> f64 { StandardNormal.sample(&mut rng) };
                let per = 20;
                let m = n * per;
                let xg: Vec<Vec<f64>> = (0..n).map(|i| vec![1.0, i as f64 - 2.5]).collect();
                let x = DMatrix::from_fn(m, p, |r, c| xg[r / per][c] * 10.0);
                let mut z = DMatrix::zeros(m, n);
                for r in 0..m {
                    z[(r, r / per)] = 10.0;
                }
                let eff: Vec<f64> = (0..n).map(|_| tau * g()).collect();
                let y = DVector::from_fn(m, |r, _| 10.0 * (0.5 + eff[r / per]) + g());
                let groups: Vec<(usize, usize)> =
                    (0..n).map(|i| (i * per, (i + 1) * per)).collect();
                (x, z, y, groups)
            };
            let lmm = lmm_of(&x, &z, &y, &groups, 1);
            let tr = lmm.estimate(&[0.1], true)[0];
            let tm = lmm.estimate(&[0.1], false)[0];
            reml += tr * tr;
            ml += tm * tm;
            let (lo, hi) = lmm.interval(0, &[tr], Cutoffs::chi2(3.841_459), true);
            if lo <= tau && tau <= hi {
                cover += 1;
            }
            // The levels' fixed effects lie in the effects' span: at most n − p degrees of
            // freedom, each effect seen through 20 rows of Z = 10 (τ²λ = 0.09 · 2000 = 180
            // at the truth, less at a small estimate, none at the floor).
            let dof = lmm.effect_dof(0, tr);
            assert!(dof <= (n - p) as f64 + 1e-9, "dof {dof}");
            let (lo, hi) = lmm.interval(0, &[tr], Cutoffs::small_sample(dof, 0.95), true);
            if lo <= tau && tau <= hi {
                cover_small += 1;
            }
        }
        let (reml, ml) = (reml / reps as f64, ml / reps as f64);
        let t2 = tau * tau;
        // se of a mean of τ̂² over 400 sets: τ²·√(2/(n−p))/√400 ≈ 0.035 τ².
        assert!(
            (reml / t2 - 1.0).abs() < 0.12,
            "REML mean τ̂² {reml} vs {t2}"
        );
        assert!(
            (ml / t2 - (n - p) as f64 / n as f64).abs() < 0.12,
            "ML mean τ̂² {ml}"
        );
        let c = cover as f64 / reps as f64;
        assert!((0.90..=0.98).contains(&c), "coverage {c}");
        // Calibrated to the 4 degrees of freedom: 95 % within three binomial standard
        // deviations over 400 sets (0.917–0.983).
        let c_small = cover_small as f64 / reps as f64;
        assert!(
            (0.917..=0.983).contains(&c_small),
            "coverage {c_small} (χ²₁ rule {c})"
        );
    }

    #[test]
    fn small_sample_cutoffs_end_the_profile_at_the_exact_interval_of_a_variance() {
        // d = 5 by hand: χ²₅ quantiles 0.831211 (2.5 %) and 12.83250 (97.5 %); the rise
        // d(u − 1 − ln u) at u = q/5 is 3.11979 below the estimate and 4.80276 above.
        let c = Cutoffs::small_sample(5.0, 0.95);
        assert!((c.lower - 3.11979).abs() < 2e-4, "{c:?}");
        assert!((c.upper - 4.80276).abs() < 2e-4, "{c:?}");
        // Many degrees of freedom: the asymptotic χ²₁ rule at both ends.
        let c = Cutoffs::small_sample(1e6, 0.95);
        assert!((c.lower - 3.841459).abs() < 0.01 && (c.upper - 3.841459).abs() < 0.01);
        // On the profile of a normal variance from d degrees of freedom, −2 ln L(τ) =
        // d ln τ² + d s²/τ², the interval is the χ² pivot's [s √(d/χ²_{.975}), s √(d/χ²_{.025})].
        for (d, q_lo, q_hi) in [(3.0, 0.215795, 9.348404), (5.0, 0.831211, 12.832502)] {
            let s = 0.08;
            let f = |t: &[f64]| d * (t[0] * t[0]).ln() + d * s * s / (t[0] * t[0]);
            let (lo, hi) = profile_interval(0, &[s], Cutoffs::small_sample(d, 0.95), f);
            let (want_lo, want_hi) = (s * (d / q_hi).sqrt(), s * (d / q_lo).sqrt());
            assert!(
                (lo / want_lo - 1.0).abs() < 1e-4,
                "d {d}: {lo} vs {want_lo}"
            );
            assert!(
                (hi / want_hi - 1.0).abs() < 1e-4,
                "d {d}: {hi} vs {want_hi}"
            );
        }
    }

    #[test]
    fn effect_dof_counts_the_effects_beyond_the_constants() {
        // Six groups of 10 rows, one effect per group (Z = 1 on its rows).
        let (n, per) = (6usize, 10usize);
        let m = n * per;
        let groups: Vec<(usize, usize)> = (0..n).map(|i| (i * per, (i + 1) * per)).collect();
        let mut z = DMatrix::zeros(m, n);
        for r in 0..m {
            z[(r, r / per)] = 1.0;
        }
        let y = DVector::from_fn(m, |r, _| (r as f64 * 0.37).sin());
        let level = |r: usize| 1.0 + 0.3 * (r / per) as f64;
        let within = |r: usize| (r % per) as f64 - 4.5;
        // Seen precisely (τ²λ = 10⁶ · 10): whole degrees of freedom.
        for (cols, want) in [
            // No constants: every effect free.
            (vec![], 6.0),
            // A common level: n − 1.
            (vec![&level as &dyn Fn(usize) -> f64], 5.0),
            // A level and a trend across groups: n − 2.
            (
                vec![&level, &|r: usize| (r / per) as f64 * (r / per) as f64],
                4.0,
            ),
            // A level and a column within the groups, orthogonal to every group's level: n − 1.
            (vec![&level, &within], 5.0),
        ] {
            let x = DMatrix::from_fn(m, cols.len(), |r, c| cols[c](r));
            let lmm = lmm_of(&x, &z, &y, &groups, 1);
            let dof = lmm.effect_dof(0, 1e3);
            assert!(
                (dof - want).abs() < 1e-4,
                "{} constants: {dof} vs {want}",
                cols.len()
            );
        }
        // Seen poorly: at τ²λ = 1 (τ² = 0.1, λ = 10 rows of Z = 1) each direction gives a
        // quarter of the information of a precisely seen one.
        let lmm = lmm_of(&DMatrix::zeros(m, 0), &z, &y, &groups, 1);
        let dof = lmm.effect_dof(0, 0.1f64.sqrt());
        assert!((dof - 1.5).abs() < 1e-9, "{dof}");
    }

    #[test]
    fn laplace_terms_are_the_penalty_and_log_determinant() {
        let g = vec![
            [[4.0, 1.0, 0.0], [1.0, 9.0, 0.0], [0.0; 3]],
            [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]],
        ];
        let eta = [0.1, -0.2, 0.3, 0.05];
        let tau = [0.5, 0.25];
        let want: f64 = (0.1f64 / 0.5).powi(2)
            + (-0.2f64 / 0.5).powi(2)
            + (0.3f64 / 0.25).powi(2)
            + (0.05f64 / 0.25).powi(2)
            + ((1.0 + 0.25 * 4.0) * (1.0 + 0.0625 * 9.0) - 0.25 * 1.0 * 0.0625 * 1.0f64).ln()
            + ((1.0 + 0.25 * 2.0) * (1.0 + 0.0625 * 1.0f64)).ln();
        assert!((laplace_terms(&eta, &g, &tau) - want).abs() < 1e-12);
    }

    #[test]
    fn the_closed_forms_of_one_and_two_kinds_agree_with_the_general_inverse() {
        let g = [[4.0, 1.5, 0.0], [1.5, 9.0, 0.0], [0.0; 3]];
        let tau = [0.5, 0.25];
        for k in [1, 2] {
            let mut m = g;
            for a in 0..k {
                m[a][a] += 1.0 / (tau[a] * tau[a]);
            }
            let want = small_inverse(k, &m);
            let got = m_inv(k, &g, &tau);
            for a in 0..k {
                for b in 0..k {
                    assert!((got[a][b] - want[a][b]).abs() < 1e-14, "k {k}: {a}{b}");
                }
            }
            let mut idg = [[0.0; MAX_KINDS]; MAX_KINDS];
            for a in 0..k {
                for b in 0..k {
                    idg[a][b] = tau[a] * tau[a] * g[a][b] + if a == b { 1.0 } else { 0.0 };
                }
            }
            assert!((ln_det_idg(k, &g, &tau) - small_det(k, &idg).ln()).abs() < 1e-14);
        }
    }

    #[test]
    fn three_kinds_match_dense_linear_algebra() {
        // Random symmetric positive definite 3 × 3 Gram matrices: M⁻¹ and ln det(I + D G)
        // against nalgebra's dense inverse and determinant.
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let tau = [0.3, 0.9, 0.5];
        for _ in 0..50 {
            let z = DMatrix::<f64>::from_fn(6, 3, |_, _| StandardNormal.sample(&mut rng));
            let gd = z.transpose() * &z;
            let mut g = [[0.0; MAX_KINDS]; MAX_KINDS];
            for a in 0..3 {
                for b in 0..3 {
                    g[a][b] = gd[(a, b)];
                }
            }
            let d = DMatrix::<f64>::from_diagonal(&DVector::from_iterator(
                3,
                tau.iter().map(|t| t * t),
            ));
            let m = &gd + d.clone().try_inverse().unwrap();
            let mi = m.clone().try_inverse().unwrap();
            let got = m_inv(3, &g, &tau);
            for a in 0..3 {
                for b in 0..3 {
                    assert!((got[a][b] - mi[(a, b)]).abs() < 1e-10 * mi.amax(), "{a}{b}");
                }
            }
            let want = (DMatrix::<f64>::identity(3, 3) + &d * &gd)
                .determinant()
                .ln();
            assert!((ln_det_idg(3, &g, &tau) - want).abs() < 1e-10);
            assert!(small_pd(3, &g));
            let mut neg = g;
            neg[2][2] = -1.0;
            assert!(!small_pd(3, &neg));
        }
    }

    /// The conditional modes (β̂, η̂) of the linear problem at scatter `tau`: penalised least
    /// squares [X Z; 0 D^-1/2] against [y; 0], solved densely.
    fn pls_modes(
        x: &DMatrix<f64>,
        z: &DMatrix<f64>,
        y: &DVector<f64>,
        k: usize,
        n: usize,
        tau: &[f64],
    ) -> (DVector<f64>, Vec<f64>) {
        let (m, p, q) = (x.nrows(), x.ncols(), z.ncols());
        let mut a = DMatrix::zeros(m + q, p + q);
        a.view_mut((0, 0), (m, p)).copy_from(x);
        a.view_mut((0, p), (m, q)).copy_from(z);
        for kk in 0..k {
            for i in 0..n {
                a[(m + kk * n + i, p + kk * n + i)] = 1.0 / tau[kk];
            }
        }
        let mut rhs = DVector::zeros(m + q);
        rhs.rows_mut(0, m).copy_from(y);
        let sol = a.svd(true, true).solve(&rhs, 1e-14).expect("svd solve");
        (
            sol.rows(0, p).into_owned(),
            sol.rows(p, q).iter().copied().collect(),
        )
    }

    /// The linear problem's Lmm linearised at (β, η), with its Gram blocks.
    fn lmm_at(
        x: &DMatrix<f64>,
        z: &DMatrix<f64>,
        y: &DVector<f64>,
        groups: &[(usize, usize)],
        k: usize,
        beta: &DVector<f64>,
        eta: &[f64],
    ) -> (Lmm, Vec<KMat>) {
        let p = x.ncols();
        let n = groups.len();
        let mut jac = DMatrix::zeros(x.nrows(), p + z.ncols());
        jac.view_mut((0, 0), (x.nrows(), p)).copy_from(x);
        jac.view_mut((0, p), (z.nrows(), z.ncols())).copy_from(z);
        let fitted = x * beta + z * DVector::from_column_slice(eta);
        let r: Vec<f64> = (0..y.len()).map(|i| fitted[i] - y[i]).collect();
        let g = groups
            .iter()
            .enumerate()
            .map(|(i, &(a, b))| {
                let mut gi = [[0.0; MAX_KINDS]; MAX_KINDS];
                for kk in 0..k {
                    for ll in 0..k {
                        gi[kk][ll] = (a..b)
                            .map(|row| z[(row, kk * n + i)] * z[(row, ll * n + i)])
                            .sum();
                    }
                }
                gi
            })
            .collect();
        (Lmm::from_jacobian(&jac, &r, groups, p, k, eta), g)
    }

    #[test]
    fn at_the_modes_of_its_own_estimate_the_laplace_criterion_agrees_with_the_linear_model() {
        // Linear in the effects, the Laplace criterion at the modes fitted at the linear
        // model's ML estimate τ̂ lies above the profiled criterion everywhere and touches it
        // at τ̂ (the modes minimise the penalised sum there): its minimiser is τ̂ itself.
        for (seed, k, tau) in [
            (31u64, 1, vec![0.4]),
            (32, 2, vec![0.3, 0.15]),
            (33, 3, vec![0.3, 0.2, 0.5]),
        ] {
            let (n, per, p) = (8, 30, 2);
            let (x, z, y, groups) = problem(seed, n, per, p, k, &tau);
            let ml = lmm_of(&x, &z, &y, &groups, k).estimate(&vec![0.1; k], false);
            let (beta, eta) = pls_modes(&x, &z, &y, k, n, &ml);
            let (lmm, g) = lmm_at(&x, &z, &y, &groups, k, &beta, &eta);
            let modes = minimise_scatter(&ml, |t| laplace_criterion(&lmm, &eta, &g, t, false));
            for kk in 0..k {
                assert!(
                    (modes[kk] / ml[kk]).ln().abs() < 1e-3,
                    "seed {seed}: kind {kk} at the modes {} against the linear model's {}",
                    modes[kk],
                    ml[kk]
                );
            }
            // And above the profiled criterion away from τ̂ (the same constant apart).
            let off = lmm.neg2l(&ml, false) - laplace_criterion(&lmm, &eta, &g, &ml, false);
            for f in [0.3, 0.7, 1.5, 3.0] {
                let t: Vec<f64> = ml.iter().map(|v| v * f).collect();
                let above =
                    laplace_criterion(&lmm, &eta, &g, &t, false) + off - lmm.neg2l(&t, false);
                assert!(above > -1e-9, "seed {seed}, ×{f}: {above}");
            }
        }
    }

    #[test]
    fn the_criterion_at_the_modes_is_minimised_as_a_brute_force_grid_minimises_it() {
        // Modes held at a tenth of the linear model's (as effects the curves do not let
        // grow): the ML and REML minimisers of the criterion at those modes against a
        // 20,000-point grid in ln τ, and REML's term pulling upward.
        let (n, per, p, k) = (8, 30, 2, 1);
        let (x, z, y, groups) = problem(34, n, per, p, k, &[0.5]);
        let ml = lmm_of(&x, &z, &y, &groups, k).estimate(&[0.1], false);
        let (beta, eta) = pls_modes(&x, &z, &y, k, n, &ml);
        let small: Vec<f64> = eta.iter().map(|e| 0.1 * e).collect();
        let (lmm, g) = lmm_at(&x, &z, &y, &groups, k, &beta, &small);
        let mut got = [0.0; 2];
        for (j, restricted) in [false, true].into_iter().enumerate() {
            let f = |t: f64| laplace_criterion(&lmm, &small, &g, &[t], restricted);
            got[j] = minimise_scatter(&[0.1], |t| f(t[0]))[0];
            let (lf, lm) = (SCATTER_FLOOR.ln(), SCATTER_MAX.ln());
            let brute = (0..=20_000)
                .map(|i| (lf + (lm - lf) * i as f64 / 20_000.0).exp())
                .min_by(|a, b| f(*a).total_cmp(&f(*b)))
                .unwrap();
            assert!(
                (got[j] / brute).ln().abs() < 1e-3,
                "{restricted}: {} against {brute}",
                got[j]
            );
            assert!(
                got[j] < 0.5 * ml[0],
                "{restricted}: {} against the linear model's {}",
                got[j],
                ml[0]
            );
        }
        assert!(got[1] > got[0]);
    }

    #[test]
    fn a_step_pays_when_the_likelihood_does_not_rise() {
        for (before, after, pays) in [
            (-100.0, -120.0, true),
            (-100.0, -100.0, true),
            (-100.0, -100.0 + 1e-3, true),
            (-100.0, -100.0 + 2e-3, false),
            (-100.0, -50.0, false),
            (-100.0, f64::NAN, false),
            (f64::NAN, -100.0, false),
        ] {
            assert_eq!(step_pays(before, after, 1e-3), pays, "{before} → {after}");
        }
    }
}
