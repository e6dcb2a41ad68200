//! Apparent activation energies: what a joint calibration says about how fast creep speeds up
//! with temperature, in the number metallurgists compare (kJ/mol).
//!
//! A law's own Q (e.g. `A.Q`) is not that number when more than one constant depends on
//! temperature: with ε̇ = A sinh(Bσ…) and B following a law too, the minimum creep rate at a
//! fixed stress has the apparent activation energy Q_app = −R ∂ln ε̇_min/∂(1/T) ≈ Q_A +
//! Bσ·coth(Bσ)·Q_B, stress-dependent and larger than Q_A. Q_app is what the 250–400 kJ/mol
//! of nickel alloys' creep refers to, and what the data give directly where one stress was
//! tested at several temperatures ([`from_data`]).

use serde::{Deserialize, Serialize};

use crate::data::Curve;
use crate::model::{Load, Model};
use crate::ode::OdeOptions;

/// Gas constant, kJ/(mol·K).
pub const R_KJ: f64 = 8.314_462_618e-3;
/// Half-step of the central difference in temperature, K.
const DT_K: f64 = 5.0;

/// Apparent activation energies of the model at one condition (kJ/mol; NaN where a
/// simulation did not give the quantity at T ± 5 K).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Apparent {
    #[serde(rename = "temperature_C")]
    pub temperature_c: f64,
    #[serde(rename = "stress_MPa")]
    pub stress_mpa: f64,
    /// −R ∂ln ε̇_min/∂(1/T), kJ/mol.
    pub q_min_rate_kj_mol: f64,
    /// R ∂ln t_r/∂(1/T), kJ/mol.
    pub q_rupture_time_kj_mol: f64,
}

/// The model's apparent activation energies at (`temperature_c`, `stress_mpa`) by a central
/// difference in 1/T (T ± 5 K), simulating up to `t_end` h.
pub fn apparent(
    model: &dyn Model,
    params: &[f64],
    temperature_c: f64,
    stress_mpa: f64,
    omega_f: f64,
    ode: &OdeOptions,
    t_end: f64,
) -> Apparent {
    let o = OdeOptions { t_end, ..*ode };
    let at = |t: f64| {
        let r = model.simulate(params, &Load::new(stress_mpa, t, omega_f), &[], &mut [], &o);
        let life = if r.ruptured() { r.t_end } else { f64::NAN };
        (r.min_rate, life)
    };
    let (lo, hi) = (at(temperature_c - DT_K), at(temperature_c + DT_K));
    let k = |t: f64| t + 273.15;
    let dinv = 1.0 / k(temperature_c - DT_K) - 1.0 / k(temperature_c + DT_K);
    let nan_unless = |v: f64| if v.is_finite() { v } else { f64::NAN };
    Apparent {
        temperature_c,
        stress_mpa,
        q_min_rate_kj_mol: nan_unless(R_KJ * (hi.0.ln() - lo.0.ln()) / dinv),
        q_rupture_time_kj_mol: nan_unless(R_KJ * (lo.1.ln() - hi.1.ln()) / dinv),
    }
}

/// An activation energy measured directly: one stress tested at two or more temperatures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measured {
    #[serde(rename = "stress_MPa")]
    pub stress_mpa: f64,
    /// The temperatures, °C (ascending, with repeats for replicates).
    #[serde(rename = "temperatures_C")]
    pub temperatures_c: Vec<f64>,
    /// Least-squares slope of ln ε̇_min on 1/T times −R, kJ/mol (measured minimum rates, or
    /// the estimate from each curve).
    pub q_min_rate_kj_mol: f64,
    /// Least-squares slope of ln t_r on 1/T times R, kJ/mol (NaN: fewer than two ruptured
    /// tests at two temperatures).
    pub q_rupture_time_kj_mol: f64,
}

/// Slope of y on x by least squares (NaN with fewer than two distinct x).
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    if x.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        f64::NAN
    }
}

/// Activation energies the data give by themselves: for every stress tested at two or more
/// temperatures, the Arrhenius slopes of the minimum rate and the rupture time.
pub fn from_data(curves: &[Curve]) -> Vec<Measured> {
    let mut stresses: Vec<f64> = curves.iter().map(|c| c.stress_mpa).collect();
    stresses.sort_by(f64::total_cmp);
    stresses.dedup();
    stresses
        .into_iter()
        .filter_map(|s| {
            let mut at: Vec<&Curve> = curves.iter().filter(|c| c.stress_mpa == s).collect();
            at.sort_by(|a, b| a.temperature_c.total_cmp(&b.temperature_c));
            let first = at.first()?.temperature_c;
            if at.iter().all(|c| c.temperature_c == first) {
                return None;
            }
            let inv = |c: &Curve| 1.0 / (c.temperature_c + 273.15);
            let (x, y): (Vec<f64>, Vec<f64>) = at
                .iter()
                .filter(|c| c.min_rate() > 0.0)
                .map(|c| (inv(c), c.min_rate().ln()))
                .unzip();
            let (xl, yl): (Vec<f64>, Vec<f64>) = at
                .iter()
                .filter_map(|c| c.rupture_time_h.map(|t| (inv(c), t.ln())))
                .unzip();
            Some(Measured {
                stress_mpa: s,
                temperatures_c: at.iter().map(|c| c.temperature_c).collect(),
                q_min_rate_kj_mol: -R_KJ * slope(&x, &y),
                q_rupture_time_kj_mol: R_KJ * slope(&xl, &yl),
            })
        })
        .collect()
}

/// A fit's `summary.json` → `activation_energy`: the model's apparent activation energies
/// at every tested load, and the data's own where one stress was tested at several
/// temperatures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForFit {
    pub model: Vec<Apparent>,
    pub data: Vec<Measured>,
}

/// [`ForFit`] of constants `params` of `model` fitted to `curves` (simulations up to 100 × the
/// longest measured life).
pub fn for_fit(
    model: &dyn Model,
    params: &[f64],
    curves: &[Curve],
    omega_f: f64,
    ode: &OdeOptions,
) -> ForFit {
    let longest = curves.iter().map(|c| c.life_h()).fold(1.0f64, f64::max);
    let mut loads: Vec<(f64, f64)> = curves
        .iter()
        .map(|c| (c.temperature_c, c.stress_mpa))
        .collect();
    loads.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    loads.dedup();
    ForFit {
        model: loads
            .iter()
            .map(|&(t, s)| apparent(model, params, t, s, omega_f, ode, 100.0 * longest))
            .collect(),
        data: from_data(curves),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_an_exact_arrhenius_line_is_its_activation_energy() {
        // ε̇ = c exp(−Q/RT) at four temperatures: the measured Q is Q.
        let q = 300.0;
        let t: [f64; 4] = [750.0, 850.0, 900.0, 950.0];
        let x: Vec<f64> = t.iter().map(|t| 1.0 / (t + 273.15)).collect();
        let y: Vec<f64> = x.iter().map(|x| 2.0 - q / R_KJ * x).collect();
        assert!((-R_KJ * slope(&x, &y) - q).abs() < 1e-9 * q);
        assert!(slope(&[1.0], &[2.0]).is_nan());
        assert!(slope(&[1.0, 1.0], &[2.0, 3.0]).is_nan());
    }
}
