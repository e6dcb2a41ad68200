//! What the data determine: the combinations of constants that are well determined even where
//! the constants alone are not.
//!
//! The Fisher information of the constants is taken in their natural coordinates z
//! ([`Coord`]: ln x, ln(1 − H*) for H*), where a product or ratio of powers of constants is a
//! linear combination. Its eigenvectors with the largest eigenvalues are the best-determined
//! directions; each is scaled so that its largest exponent is 1, its exponents rounded to
//! halves (|exponent| < 0.25 dropped; tenths if halves lose the precision), and the rounded
//! combination Π x_j^{a_j} — such as B(1 − H*) — is kept when the half-width of its own 95 %
//! profile-likelihood interval ([`quantity_interval`]) is at most [`WELL_DETERMINED_HW`] on
//! the log scale and at most a third of that of every main constant (exponent ≥ 0.5) in it
//! alone (else the constant says as much by itself).

use serde::Serialize;

use super::constrained::{Coord, Quantity};
use super::profile::{quantity_interval, ConstantProfile, Interval};
use super::{covariance, information, Context, Reference, Thresholds};

/// Largest half-width of the 95 % profile-likelihood interval (log scale, i.e. relative) of
/// a combination called well determined: ±10 %.
pub const WELL_DETERMINED_HW: f64 = 0.1;

/// Half-width of constant j's 95 % profile interval in coordinate `c` (∞ if open or absent).
fn member_halfwidth(profiles: &[ConstantProfile], j: usize, c: Coord) -> f64 {
    match profiles.iter().find(|p| p.index == j) {
        Some(p) if p.class == super::profile::Class::Identifiable => {
            0.5 * (c.z(p.interval.hi95) - c.z(p.interval.lo95)).abs()
        }
        _ => f64::INFINITY,
    }
}

/// A well-determined combination of constants.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Combination {
    /// E.g. `B·(1−Hstar)` or `A / Kc^0.5`.
    pub expression: String,
    /// Exponent of each constant in its coordinate (model order; 0: not in it).
    pub exponents: Vec<f64>,
    /// The combination's value and intervals (physical: the product itself).
    pub interval: Interval,
    /// Wald standard error of ln(combination).
    pub wald_se_ln: f64,
    /// Narrowest 95 % half-width (its coordinate) of a main constant in it, alone (∞ if every
    /// one of them is not identifiable).
    pub best_single_halfwidth: f64,
    /// Eigenvalue rank it came from (1 = best determined direction).
    pub rank: usize,
    /// Fits run for its profile.
    pub fits: usize,
}

/// The expression of a combination: positive exponents before the slash, negative after.
pub fn expression(names: &[&str], coords: &[Coord], exps: &[f64]) -> String {
    let term = |j: usize, e: f64| {
        let s = coords[j].symbol(names[j]);
        if (e - 1.0).abs() < 1e-9 {
            s
        } else {
            format!("{s}^{e}")
        }
    };
    let num: Vec<String> = (0..exps.len())
        .filter(|&j| exps[j] > 0.0)
        .map(|j| term(j, exps[j]))
        .collect();
    let den: Vec<String> = (0..exps.len())
        .filter(|&j| exps[j] < 0.0)
        .map(|j| term(j, -exps[j]))
        .collect();
    let n = if num.is_empty() {
        "1".to_string()
    } else {
        num.join("·")
    };
    if den.is_empty() {
        n
    } else {
        format!("{n} / {}", den.join("·"))
    }
}

/// Round an eigenvector to exponents: scaled so the largest |component| is 1 (and positive),
/// rounded to halves, components below 0.25 dropped.
pub fn round_exponents(v: &[f64]) -> Vec<f64> {
    round_exponents_to(v, 0.5)
}

/// [`round_exponents`] to multiples of `step` (components below `step`/2 dropped).
pub fn round_exponents_to(v: &[f64], step: f64) -> Vec<f64> {
    let (imax, vmax) =
        v.iter().enumerate().fold(
            (0, 0.0),
            |acc, (i, x)| if x.abs() > acc.1 { (i, x.abs()) } else { acc },
        );
    if vmax == 0.0 {
        return vec![0.0; v.len()];
    }
    let sign = v[imax].signum();
    v.iter()
        .map(|x| {
            let s = sign * x / vmax;
            if s.abs() < 0.5 * step {
                0.0
            } else {
                let r = (s / step).round() * step;
                (r * 1e6).round() / 1e6
            }
        })
        .collect()
}

/// The well-determined combinations (at most `max`), with their profile-likelihood
/// intervals (physical values).
pub fn well_determined(
    ctx: &Context,
    reference: &Reference,
    profiles: &[ConstantProfile],
    th: &Thresholds,
    max: usize,
) -> Vec<Combination> {
    let sp = &ctx.space;
    let n = sp.len();
    let names = ctx.names();
    let coords: Vec<Coord> = (0..n)
        .map(|j| Coord::of(names[j], sp.lb[j], sp.ub[j]))
        .collect();
    let Some(info_u) = information(
        ctx,
        sp,
        &reference.params,
        &reference.noise,
        reference.specimen.as_ref(),
    ) else {
        return vec![];
    };
    // dz/du per constant: I_z = D⁻¹ I_u D⁻¹.
    let d: Vec<f64> = (0..n)
        .map(|j| {
            let x = reference.params[j];
            coords[j].dz_dx(x) * sp.dx_du(j, x)
        })
        .collect();
    let info_z = nalgebra::DMatrix::from_fn(n, n, |a, b| info_u[(a, b)] / (d[a] * d[b]));
    let cov_z = covariance(&info_z);
    let eig = ((&info_z + info_z.transpose()) * 0.5).symmetric_eigen();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut out: Vec<Combination> = Vec::new();
    let mut seen: Vec<Vec<f64>> = Vec::new();
    for (rank, &k) in order.iter().enumerate() {
        if out.len() >= max {
            break;
        }
        let v: Vec<f64> = eig.eigenvectors.column(k).iter().copied().collect();
        // The simplest rounding whose own profile-likelihood interval is narrow: halves,
        // else tenths. Judged on the profile (which respects the bounds), not on the Wald
        // standard error (which does not: a constant pinned at a bound has a huge Wald
        // variance that leaks into every combination containing it).
        let mut pick = None;
        for step in [0.5, 0.1] {
            let a = round_exponents_to(&v, step);
            let main: Vec<usize> = (0..n).filter(|&j| a[j].abs() >= 0.5).collect();
            if (0..n).filter(|&j| a[j] != 0.0).count() < 2 || main.len() < 2 || seen.contains(&a) {
                continue;
            }
            let av = nalgebra::DVector::from_column_slice(&a);
            let se = (av.transpose() * &cov_z * &av)[(0, 0)].max(0.0).sqrt();
            // The narrowest 95 % half-width (in its coordinate) of a main member alone.
            let best_single = main
                .iter()
                .map(|&j| member_halfwidth(profiles, j, coords[j]))
                .fold(f64::INFINITY, f64::min);
            let q = Quantity::Combination {
                coef: a.clone(),
                coords: coords.clone(),
            };
            let Some(qi) = quantity_interval(ctx, reference, &q, th) else {
                continue;
            };
            let iv = qi.interval;
            let hw = 0.5 * (iv.hi95 - iv.lo95);
            if std::env::var("CREEPFIT_DEBUG_COMBOS").is_ok() {
                eprintln!(
                    "rank {} λ {:.3e} a {:?} wald se {:.2e} half-width {:.3e} best single {:.3e}",
                    rank + 1,
                    eig.eigenvalues[k],
                    a,
                    se,
                    hw,
                    best_single
                );
            }
            if !iv.lo_open && !iv.hi_open && hw <= WELL_DETERMINED_HW && hw <= best_single / 3.0 {
                pick = Some((a, se, best_single, qi));
                break;
            }
        }
        let Some((a, se, best_single, qi)) = pick else {
            continue;
        };
        seen.push(a.clone());
        let iv = qi.interval;
        let e = |g: f64| g.exp();
        out.push(Combination {
            expression: expression(&names, &coords, &a),
            exponents: a,
            interval: Interval {
                value: e(iv.value),
                lo68: e(iv.lo68),
                hi68: e(iv.hi68),
                lo95: e(iv.lo95),
                hi95: e(iv.hi95),
                lo_open: iv.lo_open,
                hi_open: iv.hi_open,
            },
            wald_se_ln: se,
            best_single_halfwidth: best_single,
            rank: rank + 1,
            fits: qi.fits(),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponents_round_to_halves_and_read_as_products() {
        let a = round_exponents(&[0.01, -0.69, -0.72, 0.05, 0.0, 0.1]);
        assert_eq!(a, vec![0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let names = ["A", "B", "Hstar", "h", "Kc", "C"];
        let coords = [
            Coord::Log,
            Coord::Log,
            Coord::LogComplement,
            Coord::Log,
            Coord::Log,
            Coord::Log,
        ];
        assert_eq!(expression(&names, &coords, &a), "B·(1−Hstar)");
        let b = round_exponents(&[0.8, 0.0, 0.0, 0.0, -0.45, 0.0]);
        assert_eq!(b, vec![1.0, 0.0, 0.0, 0.0, -0.5, 0.0]);
        assert_eq!(expression(&names, &coords, &b), "A / Kc^0.5");
    }

    #[test]
    fn natural_coordinates_make_products_linear() {
        let c = Coord::LogComplement;
        assert!((c.z(0.4) - 0.6f64.ln()).abs() < 1e-15);
        assert!((c.dz_dx(0.4) + 1.0 / 0.6).abs() < 1e-15);
        assert_eq!(Coord::of("Hstar", 0.1, 0.9), Coord::LogComplement);
        assert_eq!(Coord::of("nu", -10.0, 10.0), Coord::Linear);
        assert_eq!(Coord::of("A", 1e-10, 1e-9), Coord::Log);
    }
}
