//! Model-free residual diagnostics of a calibrated model: where, per curve and stage, the
//! prediction misses the measurement, whether the misses are systematic, and how they trend
//! with stress. Residuals are normalised by the measured rupture strain: r = (pred − meas)/ε_f.

use crate::data::Curve;
use crate::objective::CurvePrediction;

/// A stage mean bias is systematic above this fraction of ε_f (digitising error of the
/// bundled curves is ≈ 0.5–1 % of ε_f).
pub const STAGE_BIAS: f64 = 0.02;
/// Runs-test z below this means the residual signs cluster: a systematic misfit, not noise.
/// Digitised curves have autocorrelated digitising error, so the threshold is stricter than
/// the usual −1.96 and a stage bias is required as well.
pub const RUNS_Z: f64 = -2.5;
/// An offset at t = 0 above this fraction of ε_f (same sign on every curve) is a loading strain.
pub const LOADING_OFFSET: f64 = 0.02;
/// Measured rupture strains that vary by more than this (ln max/min) monotonically with
/// stress, while the model's are constant, are a stress-dependent ductility.
pub const DUCTILITY_SPREAD: f64 = 0.08;
/// Predicted rupture strains off by more than this (|ln pred/meas|, same sign on every curve)
/// are a rupture-strain miss: ten times the scatter of a last digitised point (≈ 0.5 % of
/// ε_f). In the base model the rupture strain is ω_f/C, tied to the tertiary curvature; a
/// consistent miss means the tertiary acceleration has another source.
pub const RUPTURE_STRAIN_MISS: f64 = 0.05;
/// Lifetime errors of one sign on every curve with a mean above this, %, are a lifetime bias.
pub const LIFETIME_BIAS_PCT: f64 = 3.0;
/// Points through which the strain at t = 0 is extrapolated (after the first time point).
pub const T0_POINTS: usize = 4;

/// Diagnostics of one curve.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CurveSignature {
    /// Stress, MPa.
    pub stress_mpa: f64,
    /// Time-weighted mean normalised residual in the primary, secondary and tertiary third of
    /// the measured life (each point weighs half the interval to its neighbours, so dense
    /// digitising does not dominate).
    pub stage_bias: [f64; 3],
    /// Number of same-sign runs of the residuals, and the Wald–Wolfowitz z statistic.
    pub runs: usize,
    /// Runs-test z (negative: fewer runs than chance).
    pub runs_z: f64,
    /// Measured minus predicted strain extrapolated to t = 0, in units of ε_f.
    pub offset_t0: f64,
    /// Measured and predicted rupture strain (fraction).
    pub rupture_strain: (f64, f64),
    /// Lifetime error, % (NaN if unknown).
    pub lifetime_err_pct: f64,
}

/// One named finding: a stable `code`, a sentence and its key number.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Finding {
    /// `tertiary_bias`, `primary_bias`, `secondary_bias`, `loading_strain`, `ductility_trend`,
    /// `clustered_residuals`, `rupture_strain`, `lifetime_bias`.
    pub code: &'static str,
    /// What was found, in words and numbers.
    pub text: String,
    /// The key number (mean bias, offset or spread).
    pub value: f64,
}

/// Intercept at t = 0 of the least-squares line through `(t, y)`.
fn intercept(t: &[f64], y: &[f64]) -> f64 {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = t.iter().map(|v| (v - mt).powi(2)).sum();
    let sxy: f64 = t.iter().zip(y).map(|(a, b)| (a - mt) * (b - my)).sum();
    if sxx > 0.0 {
        my - sxy / sxx * mt
    } else {
        my
    }
}

/// Wald–Wolfowitz runs test on the signs of `r` (zeros skipped): (runs, z).
pub fn runs_test(r: &[f64]) -> (usize, f64) {
    let s: Vec<bool> = r.iter().filter(|v| **v != 0.0).map(|v| *v > 0.0).collect();
    let n1 = s.iter().filter(|b| **b).count() as f64;
    let n2 = s.len() as f64 - n1;
    let runs = if s.is_empty() {
        0
    } else {
        1 + s.windows(2).filter(|w| w[0] != w[1]).count()
    };
    let n = n1 + n2;
    if n1 == 0.0 || n2 == 0.0 {
        // One sign only: as systematic as it gets.
        return (runs, f64::NEG_INFINITY);
    }
    let mu = 2.0 * n1 * n2 / n + 1.0;
    let var = 2.0 * n1 * n2 * (2.0 * n1 * n2 - n) / (n * n * (n - 1.0));
    (runs, (runs as f64 - mu) / var.sqrt())
}

/// Time-weighted mean of `r` over the points with `lo ≤ t < hi`.
fn stage_mean(t: &[f64], r: &[f64], lo: f64, hi: f64) -> f64 {
    let n = t.len();
    let (mut sw, mut s) = (0.0, 0.0);
    for k in 0..n {
        if t[k] < lo || t[k] >= hi {
            continue;
        }
        let left = if k > 0 { t[k] - t[k - 1] } else { 0.0 };
        let right = if k + 1 < n { t[k + 1] - t[k] } else { 0.0 };
        let w = 0.5 * (left + right);
        sw += w;
        s += w * r[k];
    }
    if sw > 0.0 {
        s / sw
    } else {
        0.0
    }
}

/// Diagnostics of one curve from its measurement and its prediction.
pub fn curve_signature(c: &Curve, p: &CurvePrediction) -> CurveSignature {
    let r: Vec<f64> = (0..c.times_h.len())
        .map(|k| (p.strain[k] - c.strains[k]) / c.rupture_strain)
        .collect();
    let life = c.life_h();
    let stage_bias = [
        stage_mean(&c.times_h, &r, 0.0, life / 3.0),
        stage_mean(&c.times_h, &r, life / 3.0, 2.0 * life / 3.0),
        stage_mean(&c.times_h, &r, 2.0 * life / 3.0, f64::INFINITY),
    ];
    let (runs, runs_z) = runs_test(&r);
    let k1 = c.times_h.len().min(T0_POINTS + 1);
    let (t, m, q) = (&c.times_h[..k1], &c.strains[..k1], &p.strain[..k1]);
    let offset_t0 = (intercept(t, m) - intercept(t, q)) / c.rupture_strain;
    CurveSignature {
        stress_mpa: c.stress_mpa,
        stage_bias,
        runs,
        runs_z,
        offset_t0,
        rupture_strain: (c.rupture_strain, p.rupture_strain),
        lifetime_err_pct: match c.rupture_time_h {
            Some(t) => 100.0 * (p.rupture_time_h - t) / t,
            None => f64::NAN,
        },
    }
}

/// The systematic findings over all curves (ascending stress).
pub fn findings(sig: &[CurveSignature]) -> Vec<Finding> {
    let mut out = Vec::new();
    if sig.is_empty() {
        return out;
    }
    let clustered = sig.iter().any(|s| s.runs_z < RUNS_Z);
    let names = ["primary", "secondary", "tertiary"];
    let codes = ["primary_bias", "secondary_bias", "tertiary_bias"];
    for st in 0..3 {
        let b: Vec<f64> = sig.iter().map(|s| s.stage_bias[st]).collect();
        let mean = b.iter().sum::<f64>() / b.len() as f64;
        let same_sign = b.iter().all(|v| v.signum() == mean.signum());
        let big = b.iter().filter(|v| v.abs() > STAGE_BIAS).count();
        if clustered && mean.abs() > STAGE_BIAS && (same_sign || big * 2 > b.len()) {
            out.push(Finding {
                code: codes[st],
                text: format!(
                    "{} stage {} (mean {:+.1} % of the rupture strain; per stress {})",
                    names[st],
                    if mean > 0.0 {
                        "over-predicted"
                    } else {
                        "under-predicted"
                    },
                    100.0 * mean,
                    fmt_list(&b, 100.0)
                ),
                value: mean,
            });
        }
    }
    let off: Vec<f64> = sig.iter().map(|s| s.offset_t0).collect();
    let mo = off.iter().sum::<f64>() / off.len() as f64;
    if off
        .iter()
        .all(|v| v.signum() == mo.signum() && v.abs() > LOADING_OFFSET)
    {
        out.push(Finding {
            code: "loading_strain",
            text: format!(
                "measured strain extrapolated to t = 0 exceeds the prediction by {} % of the \
                 rupture strain (per stress)",
                fmt_list(&off, 100.0)
            ),
            value: mo,
        });
    }
    if sig.iter().all(|s| s.runs_z < RUNS_Z) && !out.iter().any(|f| f.code.ends_with("_bias")) {
        out.push(Finding {
            code: "clustered_residuals",
            text: format!(
                "residual signs cluster on every curve (runs-test z {}) without a stage bias \
                 above {} % of the rupture strain: a shape the model does not follow",
                fmt_list(&sig.iter().map(|s| s.runs_z).collect::<Vec<_>>(), 1.0),
                100.0 * STAGE_BIAS
            ),
            value: sig.iter().map(|s| s.runs_z).fold(f64::INFINITY, f64::min),
        });
    }
    let miss: Vec<f64> = sig
        .iter()
        .map(|s| (s.rupture_strain.1 / s.rupture_strain.0).ln())
        .collect();
    let mm = miss.iter().sum::<f64>() / miss.len() as f64;
    if miss
        .iter()
        .all(|v| v.signum() == mm.signum() && v.abs() > RUPTURE_STRAIN_MISS)
    {
        out.push(Finding {
            code: "rupture_strain",
            text: format!(
                "predicted rupture strain {} % against measured {} %",
                fmt_list(
                    &sig.iter().map(|s| s.rupture_strain.1).collect::<Vec<_>>(),
                    100.0
                ),
                fmt_list(
                    &sig.iter().map(|s| s.rupture_strain.0).collect::<Vec<_>>(),
                    100.0
                )
            ),
            value: mm,
        });
    }
    let life: Vec<f64> = sig.iter().map(|s| s.lifetime_err_pct).collect();
    let ml = life.iter().sum::<f64>() / life.len() as f64;
    if life.iter().all(|v| v.signum() == ml.signum()) && ml.abs() > LIFETIME_BIAS_PCT {
        out.push(Finding {
            code: "lifetime_bias",
            text: format!(
                "every predicted life is {} ({} %)",
                if ml < 0.0 { "too short" } else { "too long" },
                fmt_list(&life, 1.0)
            ),
            value: ml,
        });
    }
    if sig.len() >= 2 {
        let meas: Vec<f64> = sig.iter().map(|s| s.rupture_strain.0.ln()).collect();
        let pred: Vec<f64> = sig.iter().map(|s| s.rupture_strain.1.ln()).collect();
        let spread = |v: &[f64]| {
            v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - v.iter().cloned().fold(f64::INFINITY, f64::min)
        };
        let monotone =
            meas.windows(2).all(|w| w[1] >= w[0]) || meas.windows(2).all(|w| w[1] <= w[0]);
        let dm: Vec<f64> = meas.iter().zip(&pred).map(|(m, p)| m - p).collect();
        if monotone && spread(&meas) > DUCTILITY_SPREAD && spread(&dm) > DUCTILITY_SPREAD {
            out.push(Finding {
                code: "ductility_trend",
                text: format!(
                    "measured rupture strain {} with stress ({} %), predicted {} %",
                    if meas[meas.len() - 1] > meas[0] {
                        "rises"
                    } else {
                        "falls"
                    },
                    fmt_list(
                        &sig.iter().map(|s| s.rupture_strain.0).collect::<Vec<_>>(),
                        100.0
                    ),
                    fmt_list(
                        &sig.iter().map(|s| s.rupture_strain.1).collect::<Vec<_>>(),
                        100.0
                    ),
                ),
                value: spread(&meas),
            });
        }
    }
    out
}

fn fmt_list(v: &[f64], scale: f64) -> String {
    v.iter()
        .map(|x| format!("{:+.2}", scale * x))
        .collect::<Vec<_>>()
        .join(" / ")
}

/// The findings an extension is meant to remove (DESIGN.md §6).
pub fn targets(extension: &str) -> &'static [&'static str] {
    match extension {
        "loading_strain" => &["loading_strain", "primary_bias"],
        "stress_ductility" => &["ductility_trend", "tertiary_bias", "rupture_strain"],
        "constant_load" => &["tertiary_bias", "secondary_bias", "rupture_strain"],
        "dislocation_damage" => &["tertiary_bias", "secondary_bias", "rupture_strain"],
        _ => &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_test_against_hand_counts() {
        // + + - - + - : 4 runs, n1 = 3, n2 = 3: μ = 4, σ² = 2·9·(18−6)/(36·5) = 1.2
        let (r, z) = runs_test(&[1.0, 2.0, -1.0, -3.0, 0.5, -0.1]);
        assert_eq!(r, 4);
        assert!(z.abs() < 1e-12);
        // + + + - - - : 2 runs: z = (2 − 4)/√1.2
        let (r, z) = runs_test(&[1.0, 1.0, 1.0, -1.0, -1.0, -1.0]);
        assert_eq!(r, 2);
        assert!((z + 2.0 / 1.2f64.sqrt()).abs() < 1e-12);
        assert_eq!(runs_test(&[1.0, 2.0]).1, f64::NEG_INFINITY);
    }

    #[test]
    fn stage_mean_weights_by_time_interval() {
        // Dense points at a bias of 1 in [0, 1), one sparse point of 0 weighing as much.
        let t = [0.0, 0.1, 0.2, 0.3, 2.0, 3.0];
        let r = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0];
        let m = stage_mean(&t, &r, 0.0, 10.0);
        // weights 0.05, 0.1, 0.1, 0.9, 1.35, 0.5 → (0.05+0.1+0.1+0.9)/3.0
        assert!((m - 1.15 / 3.0).abs() < 1e-12, "{m}");
    }

    #[test]
    fn intercept_of_exact_line() {
        assert!((intercept(&[1.0, 2.0, 4.0], &[3.0, 5.0, 9.0]) - 1.0).abs() < 1e-12);
    }
}
