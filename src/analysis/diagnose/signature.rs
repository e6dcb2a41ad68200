//! What a calibrated model gets wrong, per curve and stage, in numbers: explanation only.
//! Nothing here decides anything ([`super::decide`] does, from likelihoods and bootstraps).
//!
//! Everything compares like with like: the model's strain at the measured times with the
//! measured strain (a curve that ends at 97 % of life is compared with the model at 97 % of
//! life, never with the model's strain at its own rupture). Sign convention throughout:
//! **predicted − measured**, in % of the curve's rupture strain ε_f (positive: the model
//! over-predicts the strain). Each stage bias has a z-score under the curve's fitted AR(1)
//! reading error (the variance of a mean of correlated errors), so "large" means large against
//! the curve's own noise.

use crate::data::Curve;
use crate::errmodel::Ar1;

/// Stages as fractions of the measured life: primary [0, 1/3), secondary [1/3, 2/3),
/// tertiary [2/3, end].
pub const STAGES: [(&str, f64, f64); 3] = [
    ("primary", 0.0, 1.0 / 3.0),
    ("secondary", 1.0 / 3.0, 2.0 / 3.0),
    ("tertiary", 2.0 / 3.0, f64::INFINITY),
];
/// Coherent z-scores (over the curves) at least this large are listed as findings: a
/// reporting convention (about 2 standard errors), not a decision rule.
pub const REPORT_Z: f64 = 2.0;

/// Diagnostics of one curve.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CurveSignature {
    /// Test temperature, °C.
    pub temperature_c: f64,
    /// Stress, MPa.
    pub stress_mpa: f64,
    /// Specimen, if the data have one.
    pub specimen: Option<String>,
    /// Time-weighted mean of predicted − measured strain per stage, % of ε_f.
    pub stage_bias_pct: [f64; 3],
    /// z-score of each stage's mean residual under the fitted AR(1) (NaN: no points).
    pub stage_z: [f64; 3],
    /// Predicted − measured strain at the first measured time, % of ε_f.
    pub first_point_pct: f64,
    /// Life fraction of the last measured point (t_last / t_f).
    pub last_fraction: f64,
    /// Measured and predicted strain at the last measured time, %.
    pub last_point_pct: (f64, f64),
    /// Lifetime error (t_pred − t_f)/t_f, % (NaN without a rupture time).
    pub lifetime_err_pct: f64,
    /// Fitted reading error: marginal sd (% strain) and correlation φ.
    pub noise_sd_pct: f64,
    pub noise_phi: f64,
    /// The reading error writes the curve off as noise: its marginal sd is at least
    /// [`crate::errmodel::WRITES_OFF`] of the curve's largest measured strain.
    pub written_off: bool,
}

/// One finding for the report: a stable `code`, a sentence and its key number.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Finding {
    /// `primary_bias`, `secondary_bias`, `tertiary_bias`, `first_point`, `last_point`,
    /// `lifetime_bias`.
    pub code: &'static str,
    /// What was found, in words and numbers.
    pub text: String,
    /// The coherent z-score over the curves.
    pub z: f64,
}

/// Time-weighted mean of `r` over the points with lo ≤ t < hi, and the number of points.
fn stage_mean(t: &[f64], r: &[f64], lo: f64, hi: f64) -> (f64, usize, usize) {
    let n = t.len();
    let (mut sw, mut s, mut k, mut first) = (0.0, 0.0, 0, usize::MAX);
    for j in 0..n {
        if t[j] < lo || t[j] >= hi {
            continue;
        }
        let left = if j > 0 { t[j] - t[j - 1] } else { 0.0 };
        let right = if j + 1 < n { t[j + 1] - t[j] } else { 0.0 };
        let w = 0.5 * (left + right);
        sw += w;
        s += w * r[j];
        k += 1;
        first = first.min(j);
    }
    let m = if sw > 0.0 {
        s / sw
    } else if k > 0 {
        (first..first + k).map(|j| r[j]).sum::<f64>() / k as f64
    } else {
        f64::NAN
    };
    (m, k, first)
}

/// Diagnostics of one curve from its raw residuals `e` (predicted − measured, fraction), its
/// predicted rupture time and its fitted reading error.
pub fn curve_signature(c: &Curve, e: &[f64], t_pred: f64, noise: &Ar1) -> CurveSignature {
    let life = c.life_h();
    let mut stage_bias_pct = [f64::NAN; 3];
    let mut stage_z = [f64::NAN; 3];
    for (s, (_, lo, hi)) in STAGES.iter().enumerate() {
        let (m, k, _) = stage_mean(&c.times_h, e, lo * life, hi * life);
        if k > 0 {
            stage_bias_pct[s] = 100.0 * m / c.rupture_strain;
            stage_z[s] = m / noise.mean_variance(k).sqrt();
        }
    }
    let n = c.times_h.len();
    let t_last = c.times_h[n - 1];
    CurveSignature {
        temperature_c: c.temperature_c,
        stress_mpa: c.stress_mpa,
        specimen: c.specimen.clone(),
        stage_bias_pct,
        stage_z,
        first_point_pct: 100.0 * e[0] / c.rupture_strain,
        last_fraction: t_last / life,
        last_point_pct: (
            100.0 * c.strains[n - 1],
            100.0 * (c.strains[n - 1] + e[n - 1]),
        ),
        lifetime_err_pct: match c.rupture_time_h {
            Some(t) => 100.0 * (t_pred - t) / t,
            None => f64::NAN,
        },
        noise_sd_pct: 100.0 * noise.marginal_sd(),
        noise_phi: noise.phi,
        written_off: crate::errmodel::writes_off(noise.marginal_sd(), c.largest_strain()),
    }
}

/// Combine per-curve z-scores into one (Stouffer): Σ z / √m over the finite ones.
fn coherent(z: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = z.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.iter().sum::<f64>() / (v.len() as f64).sqrt()
}

fn fmt_list(v: impl Iterator<Item = f64>) -> String {
    v.map(|x| format!("{x:+.2}"))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The misses common to the curves whose coherent z-score reaches [`REPORT_Z`], largest
/// first, in words and numbers. `lifetime_sd` is the fitted rupture-time scatter (ln scale).
pub fn findings(sig: &[CurveSignature], lifetime_sd: f64) -> Vec<Finding> {
    let mut out = Vec::new();
    let codes = ["primary_bias", "secondary_bias", "tertiary_bias"];
    for (s, (name, _, _)) in STAGES.iter().enumerate() {
        let z = coherent(sig.iter().map(|c| c.stage_z[s]));
        if z.abs() >= REPORT_Z {
            out.push(Finding {
                code: codes[s],
                text: format!(
                    "{name} stage {} (predicted − measured, % of the rupture strain, per stress: {}; coherent z {:+.1})",
                    if z > 0.0 { "over-predicted" } else { "under-predicted" },
                    fmt_list(sig.iter().map(|c| c.stage_bias_pct[s])),
                    z
                ),
                z,
            });
        }
    }
    let life: Vec<f64> = sig
        .iter()
        .map(|c| c.lifetime_err_pct)
        .filter(|v| v.is_finite())
        .collect();
    if !life.is_empty() && lifetime_sd > 0.0 {
        let z = coherent(life.iter().map(|v| (1.0 + v / 100.0).ln() / lifetime_sd));
        if z.abs() >= REPORT_Z {
            out.push(Finding {
                code: "lifetime_bias",
                text: format!(
                    "predicted lives are {} ({} %; scatter of rupture times {:.1} %, coherent z {:+.1})",
                    if z < 0.0 { "too short" } else { "too long" },
                    fmt_list(life.iter().copied()),
                    100.0 * lifetime_sd,
                    z
                ),
                z,
            });
        }
    }
    out.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_mean_weights_by_time_interval() {
        // Dense points at a bias of 1 in [0, 1), one sparse point of 0 weighing as much.
        let t = [0.0, 0.1, 0.2, 0.3, 2.0, 3.0];
        let r = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0];
        let (m, k, _) = stage_mean(&t, &r, 0.0, 10.0);
        // weights 0.05, 0.1, 0.1, 0.9, 1.35, 0.5 → (0.05+0.1+0.1+0.9)/3.0
        assert!((m - 1.15 / 3.0).abs() < 1e-12, "{m}");
        assert_eq!(k, 6);
        assert!(stage_mean(&t, &r, 5.0, 6.0).0.is_nan());
    }

    #[test]
    fn signature_compares_at_the_measured_times() {
        // A curve that ends at 96 % of life, predicted exactly: no bias anywhere, whatever the
        // model does after the last point.
        let c = Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: Some("S1".into()),
            times_h: vec![0.0, 10.0, 40.0, 70.0, 96.0],
            strains: vec![0.0, 0.01, 0.02, 0.03, 0.06],
            rupture_time_h: Some(100.0),
            rupture_strain: 0.06,
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 3e-4,
        };
        let e = [0.0; 5];
        let s = curve_signature(&c, &e, 100.0, &Ar1::white(1e-4));
        // Written off only from a quarter of the curve's largest strain (6 %): sd 1.5 %.
        assert!(!s.written_off);
        assert!(!curve_signature(&c, &e, 100.0, &Ar1::white(0.0149)).written_off);
        assert!(curve_signature(&c, &e, 100.0, &Ar1::white(0.015)).written_off);
        assert_eq!(s.stage_bias_pct, [0.0; 3]);
        assert!((s.last_fraction - 0.96).abs() < 1e-12);
        assert_eq!(s.last_point_pct.0, s.last_point_pct.1);
        assert_eq!(s.lifetime_err_pct, 0.0);
        assert!(findings(std::slice::from_ref(&s), 0.01).is_empty());
        // Over-prediction of 1e-3 (1.67 % of ε_f) in the tertiary stage on a quiet curve.
        let e = [0.0, 0.0, 0.0, 1e-3, 1e-3];
        let s = curve_signature(&c, &e, 100.0, &Ar1::white(1e-4));
        assert!((s.stage_bias_pct[2] - 100.0 * 1e-3 / 0.06).abs() < 1e-9);
        assert!(s.stage_z[2] > 10.0);
        let f = findings(&[s.clone(), s], 0.01);
        assert_eq!(f[0].code, "tertiary_bias");
        assert!(f[0].text.contains("over-predicted"));
    }
}
