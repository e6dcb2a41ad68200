//! The Larson–Miller baseline: the standard of the trade for rupture life, beside which every
//! model prediction is shown.
//!
//! The Larson–Miller parameter of a test at temperature T (K) that ruptured after t_r (h) is
//! LMP = T·(C + log10 t_r). Tests of one material fall on one master curve LMP(σ), taken as a
//! polynomial of degree d in x = log10 σ: LMP = Σ_k a_k x^k. Then
//!
//!   log10 t_r = Σ_k a_k x^k / T − C,
//!
//! which is linear in (a_0 … a_d, C): the constant C and the master curve are fitted together
//! by linear least squares on log10 t_r (the quantity a life prediction is judged by), and a
//! prediction is t_r = 10^(LMP(σ)/T − C). C is determined only with tests at two or more
//! temperatures (at one temperature a_0/T and C are the same column).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::data::Curve;
use crate::data::ZERO_CELSIUS_K;
use crate::error::{Error, Result};

/// Default degree of the master curve in log10 σ.
pub const DEFAULT_DEGREE: usize = 2;

/// A fitted Larson–Miller relation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LarsonMiller {
    /// The Larson–Miller constant C (time in h).
    pub c: f64,
    /// Coefficients a_0 … a_d of the master curve LMP = Σ a_k (log10 σ)^k, K (σ in MPa).
    pub coefficients: Vec<f64>,
    /// Rupture times it was fitted to.
    pub n_tests: usize,
    /// Distinct temperatures among them, °C.
    pub temperatures_c: Vec<f64>,
    /// Stress range of the tests, MPa (the master curve is an interpolation inside it).
    pub stress_range_mpa: (f64, f64),
    /// Root-mean-square residual of log10 t_r at the fit.
    pub rms_log10: f64,
}

/// The Larson–Miller parameter T·(C + log10 t_r) of a test at `temperature_c` (°C) that
/// ruptured after `rupture_time_h` (h).
pub fn parameter(temperature_c: f64, rupture_time_h: f64, c: f64) -> f64 {
    (temperature_c + ZERO_CELSIUS_K) * (c + rupture_time_h.log10())
}

impl LarsonMiller {
    /// Fit C and a master curve of `degree` to rupture tests (°C, MPa, h). Needs two or more
    /// temperatures, `degree` + 1 distinct stresses and more tests than unknowns.
    pub fn fit(tests: &[(f64, f64, f64)], degree: usize) -> Result<LarsonMiller> {
        let bad = |m: String| Err(Error::Invalid(format!("Larson–Miller fit: {m}")));
        if let Some(t) = tests
            .iter()
            .find(|t| !(t.1 > 0.0 && t.2 > 0.0 && t.0.is_finite() && t.1.is_finite()))
        {
            return bad(format!(
                "a test needs a positive stress and rupture time (got {} °C, {} MPa, {} h)",
                t.0, t.1, t.2
            ));
        }
        let mut temps: Vec<f64> = tests.iter().map(|t| t.0).collect();
        temps.sort_by(f64::total_cmp);
        temps.dedup();
        if temps.len() < 2 {
            return bad(format!(
                "rupture times at {} temperature(s); C needs two or more",
                temps.len()
            ));
        }
        let mut stresses: Vec<f64> = tests.iter().map(|t| t.1).collect();
        stresses.sort_by(f64::total_cmp);
        stresses.dedup();
        let k = degree + 2;
        if stresses.len() < degree + 1 || tests.len() < k {
            return bad(format!(
                "{} tests at {} stresses cannot determine C and a master curve of degree {degree}",
                tests.len(),
                stresses.len()
            ));
        }
        // Columns: x^k / T (k = 0..=degree), then −1 (for C); x centred for conditioning
        // would change the coefficients' meaning, and the degrees used here are small.
        let n = tests.len();
        let mut a = DMatrix::<f64>::zeros(n, k);
        let mut b = DVector::<f64>::zeros(n);
        for (i, &(t_c, s, t_r)) in tests.iter().enumerate() {
            let inv_t = 1.0 / (t_c + ZERO_CELSIUS_K);
            let x = s.log10();
            for p in 0..=degree {
                a[(i, p)] = x.powi(p as i32) * inv_t;
            }
            a[(i, k - 1)] = -1.0;
            b[i] = t_r.log10();
        }
        // Column scaling keeps the least-squares problem well conditioned (1/T ~ 1e-3).
        let scale: Vec<f64> = (0..k)
            .map(|j| a.column(j).norm().max(f64::MIN_POSITIVE))
            .collect();
        for j in 0..k {
            let s = scale[j];
            a.column_mut(j).iter_mut().for_each(|v| *v /= s);
        }
        let svd = a.clone().svd(true, true);
        let smax = svd.singular_values.max();
        if svd.singular_values.min() <= 1e-12 * smax {
            return bad("the tests do not determine C and the master curve (collinear)".into());
        }
        let sol = svd
            .solve(&b, 1e-14 * smax)
            .map_err(|e| Error::Invalid(format!("Larson–Miller fit: {e}")))?;
        let coef: Vec<f64> = (0..k).map(|j| sol[j] / scale[j]).collect();
        let fit = LarsonMiller {
            c: coef[k - 1],
            coefficients: coef[..k - 1].to_vec(),
            n_tests: n,
            temperatures_c: temps,
            stress_range_mpa: (stresses[0], *stresses.last().unwrap()),
            rms_log10: 0.0,
        };
        let ss: f64 = tests
            .iter()
            .map(|&(t, s, tr)| (fit.rupture_time(t, s).log10() - tr.log10()).powi(2))
            .sum();
        Ok(LarsonMiller {
            rms_log10: (ss / n as f64).sqrt(),
            ..fit
        })
    }

    /// Fit to the rupture times of measured curves (interrupted tests are left out).
    pub fn fit_curves(curves: &[Curve], degree: usize) -> Result<LarsonMiller> {
        let tests: Vec<(f64, f64, f64)> = curves
            .iter()
            .filter_map(|c| c.rupture_time_h.map(|t| (c.temperature_c, c.stress_mpa, t)))
            .collect();
        Self::fit(&tests, degree)
    }

    /// The master curve: LMP at `stress_mpa`.
    pub fn lmp(&self, stress_mpa: f64) -> f64 {
        let x = stress_mpa.log10();
        self.coefficients
            .iter()
            .enumerate()
            .map(|(k, a)| a * x.powi(k as i32))
            .sum()
    }

    /// Predicted rupture time (h) at `temperature_c` (°C) and `stress_mpa`.
    pub fn rupture_time(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        10f64.powf(self.lmp(stress_mpa) / (temperature_c + ZERO_CELSIUS_K) - self.c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameter_of_a_textbook_test() {
        // 538 °C (811.15 K), 10,000 h, C = 20: LMP = 811.15 × 24 = 19,467.6.
        assert!((parameter(538.0, 1e4, 20.0) - 19_467.6).abs() < 1e-9);
    }

    /// Rupture times made by a known relation (C = 20, a quadratic master curve) give it
    /// back exactly, and its predictions at untested conditions.
    #[test]
    fn recovers_a_known_relation() {
        let (c, a) = (20.0, [3.1e4, -2.5e3, -1.2e3]);
        let truth = LarsonMiller {
            c,
            coefficients: a.to_vec(),
            n_tests: 0,
            temperatures_c: vec![],
            stress_range_mpa: (0.0, 0.0),
            rms_log10: 0.0,
        };
        let mut tests = Vec::new();
        for t in [550.0, 575.0, 600.0] {
            for s in [60.0, 80.0, 100.0, 130.0] {
                tests.push((t, s, truth.rupture_time(t, s)));
            }
        }
        let fit = LarsonMiller::fit(&tests, 2).unwrap();
        assert!((fit.c - c).abs() < 1e-8, "C = {}", fit.c);
        for (x, y) in fit.coefficients.iter().zip(&a) {
            assert!((x - y).abs() < 1e-8 * y.abs(), "{x} vs {y}");
        }
        assert!(fit.rms_log10 < 1e-10);
        let (t, s) = (565.0, 70.0);
        assert!((fit.rupture_time(t, s) / truth.rupture_time(t, s) - 1.0).abs() < 1e-9);
        // The closed form: log10 t_r = LMP/T − C.
        let lmp = truth.lmp(s);
        assert!(
            (truth.rupture_time(t, s).log10() - (lmp / (t + ZERO_CELSIUS_K) - c)).abs() < 1e-12
        );
        assert_eq!(fit.temperatures_c, vec![550.0, 575.0, 600.0]);
    }

    #[test]
    fn one_temperature_or_too_few_tests_is_an_error() {
        let one = [
            (560.0, 85.0, 9.1e4),
            (560.0, 100.0, 5.2e4),
            (560.0, 110.0, 3.1e4),
        ];
        let e = LarsonMiller::fit(&one, 1).unwrap_err().to_string();
        assert!(e.contains("two or more"), "{e}");
        let few = [(560.0, 85.0, 9.1e4), (590.0, 100.0, 5.1e3)];
        assert!(LarsonMiller::fit(&few, 2).is_err());
        assert!(LarsonMiller::fit(&[(560.0, -1.0, 1.0), (590.0, 1.0, 1.0)], 0).is_err());
    }
}
