//! The classical rupture-life parameters, shown beside every creepfit life so that the
//! standard answer to beat is always on the page.
//!
//! Each relates the rupture time t_r (h) of a test at temperature T (K) and stress σ (MPa) to a
//! master curve, a polynomial of degree d in x = log10 σ, and each is fitted to the same
//! rupture times by least squares in log10 t_r (what a life prediction is judged by):
//!
//! - **Larson–Miller** ([`crate::lmp`]): T·(C + log10 t_r) = Σ a_k x^k.
//! - **Orr–Sherby–Dorn**: log10 t_r − Q/(ln 10·R·T) = Σ a_k x^k, Q in kJ/mol: iso-stress lines
//!   parallel in log t_r against 1/T. Linear in (a, Q).
//! - **Manson–Haferd**: (log10 t_r − log10 t_a)/(T − T_a) = Σ a_k x^k: iso-stress lines
//!   straight in log t_r against T, meeting at (T_a, log10 t_a) below the tested temperatures.
//!   Linear in (log10 t_a, a) at fixed T_a; T_a (K) is profiled over T_min − 10⁴ K … T_min − 1 K.
//! - **Wilshire**: σ/σ_TS = exp(−k1·(t_r·exp(−Q*/(R T)))^u) with the tensile strength σ_TS(T)
//!   given per temperature; no master-curve degree. Its inverse,
//!   ln t_r = (1/u)·ln(−ln(σ/σ_TS)) − ln(k1)/u + Q*/(R T),
//!   is linear in (1/u, −ln(k1)/u, Q*). One (k1, u) over the whole stress range
//!   (Wilshire's papers often split it at the yield stress; with a few tests per temperature
//!   one region is what the data determine).
//!
//! The variation between them is real (different physics of the iso-stress lines), hence a
//! trait, [`RuptureParameter`]; [`fit_all`] fits every one and keeps, for each that the data
//! cannot determine, the reason.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::data::Curve;
use crate::data::ZERO_CELSIUS_K;
use crate::error::{Error, Result};
use crate::lmp::LarsonMiller;
use crate::model::law::arrhenius::R_KJ_PER_MOL_K;

/// Which classical parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BaselineKind {
    /// T·(C + log10 t_r) = f(log10 σ).
    LarsonMiller,
    /// log10 t_r − Q/(ln 10·R·T) = f(log10 σ).
    OrrSherbyDorn,
    /// (log10 t_r − log10 t_a)/(T − T_a) = f(log10 σ).
    MansonHaferd,
    /// σ/σ_TS = exp(−k1·(t_r·exp(−Q*/(R T)))^u).
    Wilshire,
}

impl BaselineKind {
    /// Every baseline, in the order of the outputs.
    pub const ALL: [BaselineKind; 4] = [
        BaselineKind::LarsonMiller,
        BaselineKind::OrrSherbyDorn,
        BaselineKind::MansonHaferd,
        BaselineKind::Wilshire,
    ];

    /// Its name as printed.
    pub fn name(self) -> &'static str {
        match self {
            BaselineKind::LarsonMiller => "Larson–Miller",
            BaselineKind::OrrSherbyDorn => "Orr–Sherby–Dorn",
            BaselineKind::MansonHaferd => "Manson–Haferd",
            BaselineKind::Wilshire => "Wilshire",
        }
    }

    /// The prefix of its columns (`lmp_rupture_time_h`, `osd_rupture_time_h`, …).
    pub fn key(self) -> &'static str {
        match self {
            BaselineKind::LarsonMiller => "lmp",
            BaselineKind::OrrSherbyDorn => "osd",
            BaselineKind::MansonHaferd => "mh",
            BaselineKind::Wilshire => "wilshire",
        }
    }
}

/// The tensile strength σ_TS (MPa) at one temperature (°C): `[predict] tensile_strength`
/// entries `"T:σ_TS"`. Wilshire's baseline needs it at every temperature it is fitted on or
/// predicts at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TensileStrength {
    /// Temperature, °C.
    #[serde(rename = "temperature_C")]
    pub temperature_c: f64,
    /// Ultimate tensile strength at that temperature, MPa.
    #[serde(rename = "strength_MPa")]
    pub strength_mpa: f64,
}

impl TensileStrength {
    /// Parse `T:σ_TS` (°C and MPa), e.g. `850:260`.
    pub fn parse(s: &str) -> std::result::Result<TensileStrength, String> {
        let (t, v) = s
            .trim()
            .split_once(':')
            .ok_or_else(|| format!("'{s}': expected T:strength (°C:MPa), e.g. 850:260"))?;
        let t: f64 = t
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the temperature '{}'", t.trim()))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the strength '{}'", v.trim()))?;
        if !(t.is_finite() && t > -ZERO_CELSIUS_K) {
            return Err(format!(
                "'{s}': the temperature must be above absolute zero (°C)"
            ));
        }
        if !(v.is_finite() && v > 0.0) {
            return Err(format!(
                "'{s}': the tensile strength must be positive (MPa)"
            ));
        }
        Ok(TensileStrength {
            temperature_c: t,
            strength_mpa: v,
        })
    }
}

/// σ_TS (MPa) at `temperature_c` (°C): the table's value, linearly interpolated between its
/// temperatures; `None` outside them (the tensile strength is not extrapolated).
pub fn tensile_at(table: &[TensileStrength], temperature_c: f64) -> Option<f64> {
    let mut t: Vec<TensileStrength> = table.to_vec();
    t.sort_by(|a, b| a.temperature_c.total_cmp(&b.temperature_c));
    if let Some(e) = t.iter().find(|e| e.temperature_c == temperature_c) {
        return Some(e.strength_mpa);
    }
    t.windows(2)
        .find(|w| w[0].temperature_c < temperature_c && temperature_c < w[1].temperature_c)
        .map(|w| {
            let f =
                (temperature_c - w[0].temperature_c) / (w[1].temperature_c - w[0].temperature_c);
            w[0].strength_mpa + f * (w[1].strength_mpa - w[0].strength_mpa)
        })
}

/// What the baselines are fitted with besides the rupture times.
#[derive(Debug, Clone, Copy)]
pub struct BaselineSettings<'a> {
    /// Degree of the master curve in log10 σ (`[predict] lmp_degree`).
    pub degree: usize,
    /// Tensile strengths per temperature (Wilshire only; empty: no Wilshire baseline).
    pub tensile: &'a [TensileStrength],
}

/// The tests a baseline was fitted to and how well it reproduces them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedOn {
    /// Rupture times it was fitted to.
    pub n_tests: usize,
    /// Distinct temperatures among them, °C.
    pub temperatures_c: Vec<f64>,
    /// Stress range of the tests, MPa.
    pub stress_range_mpa: (f64, f64),
    /// Root-mean-square residual of log10 t_r at the fit.
    pub rms_log10: f64,
}

/// Where a condition lies against the temperatures and stresses a baseline was fitted on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Extrapolation {
    /// Inside both ranges.
    None,
    /// Temperature outside the fitted temperatures.
    Temperature,
    /// Stress outside the fitted stresses.
    Stress,
    /// Both outside.
    Both,
    /// Beyond the margins of a prediction ([`TEMPERATURE_MARGIN_C`],
    /// [`STRESS_MARGIN_FACTOR`]): only a measured test of `predict --tests` is predicted
    /// there (`--at` and `[predict] at` refuse it), so that one test far from the data does
    /// not stop the scoring of a campaign's file.
    BeyondLimits,
}

impl Extrapolation {
    /// Where (`temperature_c` °C, `stress_mpa` MPa) lies against `on`'s ranges (bounds inside).
    pub fn of(on: &FittedOn, temperature_c: f64, stress_mpa: f64) -> Extrapolation {
        let (t0, t1) = on
            .temperatures_c
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(*t), b.max(*t))
            });
        let t_out = !(t0 <= temperature_c && temperature_c <= t1);
        let (s0, s1) = on.stress_range_mpa;
        let s_out = !(s0 <= stress_mpa && stress_mpa <= s1);
        match (t_out, s_out) {
            (false, false) => Extrapolation::None,
            (true, false) => Extrapolation::Temperature,
            (false, true) => Extrapolation::Stress,
            (true, true) => Extrapolation::Both,
        }
    }

    /// The file form (`none`, `temperature`, `stress`, `both`), as `predict`'s own column.
    pub fn as_str(self) -> &'static str {
        match self {
            Extrapolation::None => "none",
            Extrapolation::Temperature => "temperature",
            Extrapolation::Stress => "stress",
            Extrapolation::Both => "both",
            Extrapolation::BeyondLimits => "beyond_limits",
        }
    }
}

/// A classical time–temperature parameter of rupture life.
pub trait RuptureParameter: std::fmt::Debug + Send + Sync {
    /// Fit to rupture tests (°C, MPa, h) by least squares in log10 t_r; an error saying why
    /// when the tests cannot determine it.
    fn fit(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Result<Self>
    where
        Self: Sized;
    /// Which one.
    fn kind(&self) -> BaselineKind;
    /// Its name as printed.
    fn name(&self) -> &'static str {
        self.kind().name()
    }
    /// Predicted rupture time (h) at `temperature_c` (°C) and `stress_mpa` (NaN where it
    /// cannot predict, e.g. Wilshire without a tensile strength there).
    fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64;
    /// The tests it was fitted to and its rms error on them.
    fn fitted_on(&self) -> FittedOn;
    /// Its fitted constants as printed: name, value, unit.
    fn constants(&self) -> Vec<(String, f64, &'static str)>;
    /// Its fitted constants and [`FittedOn`] as JSON.
    fn to_json(&self) -> Value;
    /// Where a condition lies against its fitted ranges.
    fn extrapolation(&self, temperature_c: f64, stress_mpa: f64) -> Extrapolation {
        Extrapolation::of(&self.fitted_on(), temperature_c, stress_mpa)
    }
}

/// One baseline fitted to a set of rupture times, or why it could not be.
#[derive(Debug)]
pub struct Baseline {
    /// Which.
    pub kind: BaselineKind,
    /// The fit, or the reason it is absent.
    pub fit: std::result::Result<Box<dyn RuptureParameter>, String>,
}

impl Baseline {
    /// Its rupture time (h) at a condition; NaN when absent.
    pub fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        self.fit
            .as_ref()
            .map_or(f64::NAN, |b| b.predict(temperature_c, stress_mpa))
    }

    /// `{kind, name, ...its constants}` or `{kind, name, error}`.
    pub fn to_json(&self) -> Value {
        let mut v = match &self.fit {
            Ok(b) => b.to_json(),
            Err(e) => json!({ "error": e }),
        };
        if let Value::Object(m) = &mut v {
            m.insert("kind".into(), json!(self.kind));
            m.insert("name".into(), json!(self.kind.name()));
        }
        v
    }

    /// One line: its constants and fit, or why it is absent.
    pub fn describe(&self) -> String {
        match &self.fit {
            Ok(b) => {
                let on = b.fitted_on();
                let c: Vec<String> = b
                    .constants()
                    .iter()
                    .map(|(n, v, u)| {
                        if u.is_empty() {
                            format!("{n} = {v:.5}")
                        } else {
                            format!("{n} = {v:.5} {u}")
                        }
                    })
                    .collect();
                format!(
                    "{}: {}; fitted to {} rupture times at {} °C, {}–{} MPa, rms log10 error {:.3}",
                    self.kind.name(),
                    c.join(", "),
                    on.n_tests,
                    on.temperatures_c
                        .iter()
                        .map(|t| t.to_string())
                        .collect::<Vec<_>>()
                        .join(", "),
                    on.stress_range_mpa.0,
                    on.stress_range_mpa.1,
                    on.rms_log10
                )
            }
            Err(e) => format!("{}: absent: {e}", self.kind.name()),
        }
    }
}

/// The rupture tests (°C, MPa, h) of measured curves; interrupted tests are left out.
pub fn rupture_tests(curves: &[Curve]) -> Vec<(f64, f64, f64)> {
    curves
        .iter()
        .filter_map(|c| c.rupture_time_h.map(|t| (c.temperature_c, c.stress_mpa, t)))
        .collect()
}

/// Every baseline of [`BaselineKind::ALL`] fitted to `tests`, each with its fit or the reason
/// it is absent.
pub fn fit_all(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Vec<Baseline> {
    fn boxed<P: RuptureParameter + 'static>(
        r: Result<P>,
    ) -> std::result::Result<Box<dyn RuptureParameter>, String> {
        r.map(|p| Box::new(p) as Box<dyn RuptureParameter>)
            .map_err(|e| e.to_string())
    }
    BaselineKind::ALL
        .iter()
        .map(|&kind| Baseline {
            kind,
            fit: match kind {
                BaselineKind::LarsonMiller => {
                    boxed(<LarsonMiller as RuptureParameter>::fit(tests, settings))
                }
                BaselineKind::OrrSherbyDorn => boxed(OrrSherbyDorn::fit(tests, settings)),
                BaselineKind::MansonHaferd => boxed(MansonHaferd::fit(tests, settings)),
                BaselineKind::Wilshire => boxed(Wilshire::fit(tests, settings)),
            },
        })
        .collect()
}

/// The tests' distinct temperatures and stresses (sorted), after checking that each test has
/// a positive stress and rupture time and that there are `min_temps` temperatures, `min_stresses`
/// stresses and `min_tests` tests.
fn check_tests(
    what: &str,
    tests: &[(f64, f64, f64)],
    min_temps: usize,
    min_stresses: usize,
    min_tests: usize,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let bad = |m: String| Err(Error::Invalid(format!("{what} fit: {m}")));
    if let Some(t) = tests.iter().find(|t| {
        !(t.1 > 0.0 && t.2 > 0.0 && t.0.is_finite() && t.1.is_finite() && t.2.is_finite())
    }) {
        return bad(format!(
            "a test needs a positive stress and rupture time (got {} °C, {} MPa, {} h)",
            t.0, t.1, t.2
        ));
    }
    let mut temps: Vec<f64> = tests.iter().map(|t| t.0).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    if temps.len() < min_temps {
        return bad(format!(
            "rupture times at {} temperature(s); it needs {min_temps} or more",
            temps.len()
        ));
    }
    let mut stresses: Vec<f64> = tests.iter().map(|t| t.1).collect();
    stresses.sort_by(f64::total_cmp);
    stresses.dedup();
    if stresses.len() < min_stresses || tests.len() < min_tests {
        return bad(format!(
            "{} tests at {} stresses cannot determine it (it needs {min_tests} tests at {min_stresses} stresses or more)",
            tests.len(),
            stresses.len()
        ));
    }
    Ok((temps, stresses))
}

/// Linear least squares of `b` on the columns of `a` (each scaled to unit norm, SVD): the
/// coefficients and the sum of squared residuals, or why the columns do not determine them.
fn lstsq(mut a: DMatrix<f64>, b: &DVector<f64>) -> std::result::Result<(Vec<f64>, f64), String> {
    let k = a.ncols();
    let scale: Vec<f64> = (0..k)
        .map(|j| a.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    for j in 0..k {
        let s = scale[j];
        a.column_mut(j).iter_mut().for_each(|v| *v /= s);
    }
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    if !(svd.singular_values.min() > 1e-12 * smax) {
        return Err("the tests do not determine its constants (collinear)".into());
    }
    let sol = svd.solve(b, 1e-14 * smax).map_err(|e| e.to_string())?;
    let r = &a * &sol - b;
    let coef = (0..k).map(|j| sol[j] / scale[j]).collect();
    Ok((coef, r.norm_squared()))
}

/// Σ a_k x^k.
fn poly(coefficients: &[f64], x: f64) -> f64 {
    coefficients
        .iter()
        .enumerate()
        .map(|(k, a)| a * x.powi(k as i32))
        .sum()
}

/// [`FittedOn`] of `tests` with rms of log10 t_r under `predict`.
fn fitted_on(
    tests: &[(f64, f64, f64)],
    temps: Vec<f64>,
    stresses: &[f64],
    predict: impl Fn(f64, f64) -> f64,
) -> FittedOn {
    let ss: f64 = tests
        .iter()
        .map(|&(t, s, tr)| (predict(t, s).log10() - tr.log10()).powi(2))
        .sum();
    FittedOn {
        n_tests: tests.len(),
        temperatures_c: temps,
        stress_range_mpa: (stresses[0], *stresses.last().unwrap()),
        rms_log10: (ss / tests.len() as f64).sqrt(),
    }
}

fn kelvin(t_c: f64) -> f64 {
    t_c + ZERO_CELSIUS_K
}

impl RuptureParameter for LarsonMiller {
    fn fit(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Result<Self> {
        LarsonMiller::fit(tests, settings.degree)
    }
    fn kind(&self) -> BaselineKind {
        BaselineKind::LarsonMiller
    }
    fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        self.rupture_time(temperature_c, stress_mpa)
    }
    fn fitted_on(&self) -> FittedOn {
        FittedOn {
            n_tests: self.n_tests,
            temperatures_c: self.temperatures_c.clone(),
            stress_range_mpa: self.stress_range_mpa,
            rms_log10: self.rms_log10,
        }
    }
    fn constants(&self) -> Vec<(String, f64, &'static str)> {
        let mut v = vec![("C".to_string(), self.c, "")];
        v.extend(
            self.coefficients
                .iter()
                .enumerate()
                .map(|(k, a)| (format!("a{k}"), *a, "K")),
        );
        v
    }
    fn to_json(&self) -> Value {
        json!(self)
    }
}

/// A fitted Orr–Sherby–Dorn relation: log10 t_r = Q/(ln 10·R·T) + Σ a_k (log10 σ)^k.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrrSherbyDorn {
    /// Activation energy Q, kJ/mol.
    pub q_kj_per_mol: f64,
    /// Coefficients a_0 … a_d of the master curve P = Σ a_k (log10 σ)^k (P in log10 h).
    pub coefficients: Vec<f64>,
    /// The tests and the fit's rms.
    #[serde(flatten)]
    pub fitted_on: FittedOn,
}

impl OrrSherbyDorn {
    /// The Orr–Sherby–Dorn parameter log10 t_r − Q/(ln 10·R·T) of a test (°C, h).
    pub fn parameter(&self, temperature_c: f64, rupture_time_h: f64) -> f64 {
        rupture_time_h.log10() - self.q_term(temperature_c)
    }
    /// The master curve at `stress_mpa`.
    pub fn master(&self, stress_mpa: f64) -> f64 {
        poly(&self.coefficients, stress_mpa.log10())
    }
    fn q_term(&self, temperature_c: f64) -> f64 {
        self.q_kj_per_mol * osd_column(temperature_c)
    }
}

/// 1/(ln 10·R·T): the column of Q (kJ/mol) in log10 t_r.
fn osd_column(temperature_c: f64) -> f64 {
    1.0 / (std::f64::consts::LN_10 * R_KJ_PER_MOL_K * kelvin(temperature_c))
}

impl RuptureParameter for OrrSherbyDorn {
    fn fit(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Result<Self> {
        let d = settings.degree;
        let k = d + 2;
        let (temps, stresses) = check_tests("Orr–Sherby–Dorn", tests, 2, d + 1, k)?;
        let mut a = DMatrix::<f64>::zeros(tests.len(), k);
        let mut b = DVector::<f64>::zeros(tests.len());
        for (i, &(t, s, tr)) in tests.iter().enumerate() {
            let x = s.log10();
            for p in 0..=d {
                a[(i, p)] = x.powi(p as i32);
            }
            a[(i, k - 1)] = osd_column(t);
            b[i] = tr.log10();
        }
        let (coef, _) =
            lstsq(a, &b).map_err(|m| Error::Invalid(format!("Orr–Sherby–Dorn fit: {m}")))?;
        let mut fit = OrrSherbyDorn {
            q_kj_per_mol: coef[k - 1],
            coefficients: coef[..k - 1].to_vec(),
            fitted_on: FittedOn {
                n_tests: 0,
                temperatures_c: vec![],
                stress_range_mpa: (0.0, 0.0),
                rms_log10: 0.0,
            },
        };
        fit.fitted_on = fitted_on(tests, temps, &stresses, |t, s| fit.predict(t, s));
        Ok(fit)
    }
    fn kind(&self) -> BaselineKind {
        BaselineKind::OrrSherbyDorn
    }
    fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        10f64.powf(self.master(stress_mpa) + self.q_term(temperature_c))
    }
    fn fitted_on(&self) -> FittedOn {
        self.fitted_on.clone()
    }
    fn constants(&self) -> Vec<(String, f64, &'static str)> {
        let mut v = vec![("Q".to_string(), self.q_kj_per_mol, "kJ/mol")];
        v.extend(
            self.coefficients
                .iter()
                .enumerate()
                .map(|(k, a)| (format!("a{k}"), *a, "")),
        );
        v
    }
    fn to_json(&self) -> Value {
        json!(self)
    }
}

/// A fitted Manson–Haferd relation: log10 t_r = log10 t_a + (T − T_a)·Σ a_k (log10 σ)^k.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MansonHaferd {
    /// Temperature of the convergence point T_a, K (below the fitted temperatures).
    pub t_a_k: f64,
    /// log10 of the convergence point's time t_a (h).
    pub log10_t_a: f64,
    /// Coefficients a_0 … a_d of the master curve P = Σ a_k (log10 σ)^k (P in log10 h per K).
    pub coefficients: Vec<f64>,
    /// The tests and the fit's rms.
    #[serde(flatten)]
    pub fitted_on: FittedOn,
}

/// The profile of T_a searches T_min − T_a over this range, K (log-spaced grid, then golden
/// section): from just below the lowest test temperature (the guard T_a < T_min) to far
/// below it, where the iso-stress lines no longer converge (the parameter then loses its
/// temperature dependence).
pub const MH_T_A_GAP_K: (f64, f64) = (1.0, 1e4);
/// Points of the grid over [`MH_T_A_GAP_K`].
const MH_GRID: usize = 241;

impl MansonHaferd {
    /// The Manson–Haferd parameter (log10 t_r − log10 t_a)/(T − T_a) of a test (°C, h).
    pub fn parameter(&self, temperature_c: f64, rupture_time_h: f64) -> f64 {
        (rupture_time_h.log10() - self.log10_t_a) / (kelvin(temperature_c) - self.t_a_k)
    }
    /// The master curve at `stress_mpa`.
    pub fn master(&self, stress_mpa: f64) -> f64 {
        poly(&self.coefficients, stress_mpa.log10())
    }

    /// The linear least squares at fixed T_a (K): ([log10 t_a, a_0 … a_d], SSE of log10 t_r):
    /// the profile [`RuptureParameter::fit`] minimises over T_a.
    pub fn at_t_a(
        tests: &[(f64, f64, f64)],
        degree: usize,
        t_a_k: f64,
    ) -> std::result::Result<(Vec<f64>, f64), String> {
        let k = degree + 2;
        let mut a = DMatrix::<f64>::zeros(tests.len(), k);
        let mut b = DVector::<f64>::zeros(tests.len());
        for (i, &(t, s, tr)) in tests.iter().enumerate() {
            let x = s.log10();
            let dt = kelvin(t) - t_a_k;
            a[(i, 0)] = 1.0;
            for p in 0..=degree {
                a[(i, p + 1)] = dt * x.powi(p as i32);
            }
            b[i] = tr.log10();
        }
        lstsq(a, &b)
    }
}

impl RuptureParameter for MansonHaferd {
    fn fit(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Result<Self> {
        let d = settings.degree;
        let bad = |m: String| Error::Invalid(format!("Manson–Haferd fit: {m}"));
        if d == 0 {
            // log10 t_a + (T − T_a)·a_0: log10 t_a and T_a·a_0 are the same column.
            return Err(bad(
                "a master curve of degree 0 cannot separate T_a from t_a (set [predict] lmp_degree ≥ 1)".into(),
            ));
        }
        let (temps, stresses) = check_tests("Manson–Haferd", tests, 2, d + 1, d + 3)?;
        let t_min = kelvin(temps[0]);
        // Profile over g = ln(T_min − T_a).
        let (g0, g1) = (MH_T_A_GAP_K.0.ln(), MH_T_A_GAP_K.1.ln());
        let sse = |g: f64| -> f64 {
            Self::at_t_a(tests, d, t_min - g.exp()).map_or(f64::INFINITY, |r| r.1)
        };
        let grid: Vec<f64> = (0..MH_GRID)
            .map(|i| g0 + (g1 - g0) * i as f64 / (MH_GRID - 1) as f64)
            .collect();
        let values: Vec<f64> = grid.iter().map(|&g| sse(g)).collect();
        let best = (0..MH_GRID)
            .filter(|&i| values[i].is_finite())
            .min_by(|&i, &j| values[i].total_cmp(&values[j]))
            .ok_or_else(|| bad("the tests do not determine its constants at any T_a".into()))?;
        if best == 0 {
            return Err(bad(format!(
                "the least-squares T_a runs into the lowest test temperature (T_min − T_a = {} K, the edge of the range searched): the data do not determine the convergence point",
                MH_T_A_GAP_K.0
            )));
        }
        if best == MH_GRID - 1 {
            return Err(bad(format!(
                "the least-squares T_a runs to −∞ (the sum of squares still falls at T_min − T_a = {} K, the edge of the range searched): the iso-stress lines do not converge (their limit is parallel lines in log t_r against T, the Manson–Succop form), so T_a and t_a are not determined",
                MH_T_A_GAP_K.1
            )));
        }
        let g = golden_min(&sse, grid[best - 1], grid[best + 1]);
        let t_a_k = t_min - g.exp();
        let (coef, _) = Self::at_t_a(tests, d, t_a_k).map_err(bad)?;
        let mut fit = MansonHaferd {
            t_a_k,
            log10_t_a: coef[0],
            coefficients: coef[1..].to_vec(),
            fitted_on: FittedOn {
                n_tests: 0,
                temperatures_c: vec![],
                stress_range_mpa: (0.0, 0.0),
                rms_log10: 0.0,
            },
        };
        fit.fitted_on = fitted_on(tests, temps, &stresses, |t, s| fit.predict(t, s));
        Ok(fit)
    }
    fn kind(&self) -> BaselineKind {
        BaselineKind::MansonHaferd
    }
    fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        10f64.powf(self.log10_t_a + (kelvin(temperature_c) - self.t_a_k) * self.master(stress_mpa))
    }
    fn fitted_on(&self) -> FittedOn {
        self.fitted_on.clone()
    }
    fn constants(&self) -> Vec<(String, f64, &'static str)> {
        let mut v = vec![
            ("T_a".to_string(), self.t_a_k, "K"),
            ("log10 t_a".to_string(), self.log10_t_a, ""),
        ];
        v.extend(
            self.coefficients
                .iter()
                .enumerate()
                .map(|(k, a)| (format!("a{k}"), *a, "1/K")),
        );
        v
    }
    fn to_json(&self) -> Value {
        json!(self)
    }
}

/// The minimum of `f` on [a, b] by golden-section search, to a bracket of 1e-13·(1 + |x|).
fn golden_min(f: &impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..200 {
        if (b - a).abs() <= 1e-13 * (1.0 + a.abs().max(b.abs())) {
            break;
        }
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    if fc <= fd {
        c
    } else {
        d
    }
}

/// A fitted Wilshire relation: σ/σ_TS = exp(−k1·(t_r·exp(−Q*/(R T)))^u).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Wilshire {
    /// k1 (dimensionless, with t_r in h).
    pub k1: f64,
    /// The exponent u.
    pub u: f64,
    /// Activation energy Q*, kJ/mol.
    pub q_star_kj_per_mol: f64,
    /// The tensile strengths it uses, °C and MPa.
    pub tensile_strength: Vec<TensileStrength>,
    /// The tests and the fit's rms.
    #[serde(flatten)]
    pub fitted_on: FittedOn,
}

impl Wilshire {
    /// The temperature-compensated time t_r·exp(−Q*/(R T)) of a test (°C, h).
    pub fn compensated_time(&self, temperature_c: f64, rupture_time_h: f64) -> f64 {
        rupture_time_h * (-self.q_star_kj_per_mol / (R_KJ_PER_MOL_K * kelvin(temperature_c))).exp()
    }
    /// σ/σ_TS at a compensated time: exp(−k1·θ^u).
    pub fn normalised_stress(&self, compensated_time: f64) -> f64 {
        (-self.k1 * compensated_time.powf(self.u)).exp()
    }
}

impl RuptureParameter for Wilshire {
    fn fit(tests: &[(f64, f64, f64)], settings: &BaselineSettings) -> Result<Self> {
        let bad = |m: String| Error::Invalid(format!("Wilshire fit: {m}"));
        if settings.tensile.is_empty() {
            return Err(bad(
                "no tensile strength given ([predict] tensile_strength = [\"T:σ_TS\", …]); Wilshire needs σ_TS at each temperature".into(),
            ));
        }
        let (temps, stresses) = check_tests("Wilshire", tests, 2, 2, 3)?;
        let mut a = DMatrix::<f64>::zeros(tests.len(), 3);
        let mut b = DVector::<f64>::zeros(tests.len());
        for (i, &(t, s, tr)) in tests.iter().enumerate() {
            let ts = tensile_at(settings.tensile, t)
                .ok_or_else(|| bad(format!("no tensile strength at {t} °C")))?;
            if !(s < ts) {
                return Err(bad(format!(
                    "the test at {t} °C, {s} MPa is at or above the tensile strength {ts} MPa"
                )));
            }
            // ln t_r = (1/u)·ln(−ln(σ/σ_TS)) − ln(k1)/u + Q*/(R T), in log10 t_r.
            a[(i, 0)] = (-(s / ts).ln()).ln() / std::f64::consts::LN_10;
            a[(i, 1)] = 1.0 / std::f64::consts::LN_10;
            a[(i, 2)] = 1.0 / (R_KJ_PER_MOL_K * kelvin(t) * std::f64::consts::LN_10);
            b[i] = tr.log10();
        }
        let (coef, _) = lstsq(a, &b).map_err(bad)?;
        let (inv_u, w, q) = (coef[0], coef[1], coef[2]);
        if !(inv_u > 0.0) {
            return Err(bad(format!(
                "the fitted 1/u = {inv_u:.4} is not positive: life does not fall with stress in Wilshire's form"
            )));
        }
        let u = 1.0 / inv_u;
        let mut fit = Wilshire {
            k1: (-w * u).exp(),
            u,
            q_star_kj_per_mol: q,
            tensile_strength: settings.tensile.to_vec(),
            fitted_on: FittedOn {
                n_tests: 0,
                temperatures_c: vec![],
                stress_range_mpa: (0.0, 0.0),
                rms_log10: 0.0,
            },
        };
        fit.fitted_on = fitted_on(tests, temps, &stresses, |t, s| fit.predict(t, s));
        Ok(fit)
    }
    fn kind(&self) -> BaselineKind {
        BaselineKind::Wilshire
    }
    fn predict(&self, temperature_c: f64, stress_mpa: f64) -> f64 {
        let Some(ts) = tensile_at(&self.tensile_strength, temperature_c) else {
            return f64::NAN;
        };
        if !(stress_mpa < ts) {
            return f64::NAN;
        }
        (-(stress_mpa / ts).ln() / self.k1).powf(1.0 / self.u)
            * (self.q_star_kj_per_mol / (R_KJ_PER_MOL_K * kelvin(temperature_c))).exp()
    }
    fn fitted_on(&self) -> FittedOn {
        self.fitted_on.clone()
    }
    fn constants(&self) -> Vec<(String, f64, &'static str)> {
        vec![
            ("k1".to_string(), self.k1, ""),
            ("u".to_string(), self.u, ""),
            ("Q*".to_string(), self.q_star_kj_per_mol, "kJ/mol"),
        ]
    }
    fn to_json(&self) -> Value {
        json!(self)
    }
}

/// Farthest a prediction may lie outside the tested temperatures, °C (beyond: an error). A
/// creep mechanism (and the activation energy a temperature law carries) can change within
/// some tens of kelvin; 25 °C keeps a prediction close to the data.
pub const TEMPERATURE_MARGIN_C: f64 = 25.0;
/// Farthest a prediction may lie outside the stresses tested at its temperature, as a factor
/// (beyond: an error): 1.5 below the lowest or above the highest. With the stress exponents
/// of these alloys (5–10) a factor 1.5 in stress is already a factor 8–60 in life.
pub const STRESS_MARGIN_FACTOR: f64 = 1.5;

/// The tested conditions of a data set: each tested temperature with the range of stresses
/// tested there, and whether the configuration has temperature laws.
#[derive(Debug, Clone, PartialEq)]
pub struct Tested {
    /// (temperature °C, lowest stress MPa, highest stress MPa), ascending temperature.
    pub temperatures: Vec<(f64, f64, f64)>,
    /// Whether some constant follows a temperature law: without one the constants describe
    /// the tested temperature only.
    pub laws: bool,
}

/// Where a condition lies against the tested conditions ([`Tested::classify`]).
enum Place {
    /// Within the margins, with its extrapolation.
    Inside(Extrapolation),
    /// Beyond a margin: why.
    Beyond(String),
    /// Not predictable by the configuration at all: why.
    Impossible(String),
}

/// Where a temperature lies among the tested ones: (temperature °C, lowest, highest stress
/// MPa) of the one that applies, or of the two around it.
enum Neighbours {
    None,
    One((f64, f64, f64)),
    Between((f64, f64, f64), (f64, f64, f64)),
}

/// Relative closeness of two temperatures or stresses typed by people.
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

impl Tested {
    /// The tested conditions of `data`.
    pub fn of(data: &crate::data::Dataset, laws: bool) -> Tested {
        let mut temperatures: Vec<(f64, f64, f64)> = Vec::new();
        for c in &data.curves {
            match temperatures.iter_mut().find(|t| same(t.0, c.temperature_c)) {
                Some(t) => {
                    t.1 = t.1.min(c.stress_mpa);
                    t.2 = t.2.max(c.stress_mpa);
                }
                None => temperatures.push((c.temperature_c, c.stress_mpa, c.stress_mpa)),
            }
        }
        temperatures.sort_by(|a, b| a.0.total_cmp(&b.0));
        Tested { temperatures, laws }
    }

    /// The tested temperatures' range, °C.
    pub fn temperature_range(&self) -> (f64, f64) {
        (
            self.temperatures.first().map_or(f64::NAN, |t| t.0),
            self.temperatures.last().map_or(f64::NAN, |t| t.0),
        )
    }

    /// The stresses (MPa) that count as tested at `t` °C: at a tested temperature its own
    /// range; between two tested temperatures each end interpolated linearly in temperature on
    /// log σ between theirs; outside the tested temperatures the nearest one's. Creep campaigns
    /// test lower stresses at higher temperatures, so the tested conditions are a band falling
    /// with temperature, and the corners of the union of two temperatures' ranges (the high
    /// stress of the lower temperature at the higher one) were never tested: Alloy 617 at
    /// 800 °C, between 750 °C's 95–137 MPa and 850 °C's 30–70 MPa, counts 53.4–97.9 MPa as
    /// tested, not 30–137.
    pub fn stress_range(&self, t: f64) -> (f64, f64) {
        match self.neighbours(t) {
            Neighbours::None => (f64::NAN, f64::NAN),
            Neighbours::One(x) => (x.1, x.2),
            Neighbours::Between(a, b) => {
                let f = (t - a.0) / (b.0 - a.0);
                let log_mix = |u: f64, v: f64| (u.ln() + f * (v.ln() - u.ln())).exp();
                (log_mix(a.1, b.1), log_mix(a.2, b.2))
            }
        }
    }

    /// The widest stresses (MPa) at `t` °C that the margin [`STRESS_MARGIN_FACTOR`] is taken
    /// from: as [`Tested::stress_range`], but between two tested temperatures the union of
    /// their ranges (a prediction there is marked as a stress extrapolation outside the
    /// interpolated range, and refused only beyond the margin around the union).
    pub fn stress_limits(&self, t: f64) -> (f64, f64) {
        match self.neighbours(t) {
            Neighbours::None => (f64::NAN, f64::NAN),
            Neighbours::One(x) => (x.1, x.2),
            Neighbours::Between(a, b) => (a.1.min(b.1), a.2.max(b.2)),
        }
    }

    /// The two tested temperatures around `t` (°C) when it lies strictly between two, the
    /// ones [`Tested::stress_range`] interpolates between.
    pub fn around(&self, t: f64) -> Option<(f64, f64)> {
        match self.neighbours(t) {
            Neighbours::Between(a, b) => Some((a.0, b.0)),
            _ => None,
        }
    }

    /// The tested temperature at `t` (or the nearest outside the tested range), or the two
    /// tested temperatures around it.
    fn neighbours(&self, t: f64) -> Neighbours {
        let ts = &self.temperatures;
        if ts.is_empty() || t.is_nan() {
            return Neighbours::None;
        }
        if let Some(x) = ts.iter().find(|x| same(x.0, t)) {
            return Neighbours::One(*x);
        }
        if t < ts[0].0 {
            return Neighbours::One(ts[0]);
        }
        let last = ts[ts.len() - 1];
        if t > last.0 {
            return Neighbours::One(last);
        }
        let k = ts.iter().position(|x| x.0 > t).unwrap_or(ts.len() - 1);
        Neighbours::Between(ts[k - 1], ts[k])
    }

    /// Where `c` lies: `Ok` with its extrapolation inside the margins
    /// ([`TEMPERATURE_MARGIN_C`], [`STRESS_MARGIN_FACTOR`]), `Err` with why the
    /// configuration cannot predict it (another temperature without a temperature law, or
    /// beyond a margin).
    pub fn classify(
        &self,
        c: crate::data::Condition,
    ) -> std::result::Result<Extrapolation, String> {
        match self.place(c) {
            Place::Inside(x) => Ok(x),
            Place::Beyond(why) | Place::Impossible(why) => Err(why),
        }
    }

    /// Where a measured test `c` lies (`predict --tests`): as [`Tested::classify`], but a test
    /// beyond the margins is [`Extrapolation::BeyondLimits`], not an error; `Err` only where
    /// the configuration cannot predict at all (another temperature without a temperature law,
    /// no tested condition).
    pub fn classify_measured(
        &self,
        c: crate::data::Condition,
    ) -> std::result::Result<Extrapolation, String> {
        match self.place(c) {
            Place::Inside(x) => Ok(x),
            Place::Beyond(_) => Ok(Extrapolation::BeyondLimits),
            Place::Impossible(why) => Err(why),
        }
    }

    fn place(&self, c: crate::data::Condition) -> Place {
        let (t0, t1) = self.temperature_range();
        let (t, s) = (c.temperature_c, c.stress_mpa);
        if !(t0.is_finite() && t1.is_finite()) {
            return Place::Impossible("the data hold no tested condition".into());
        }
        if !self.laws && !self.temperatures.iter().any(|x| same(x.0, t)) {
            return Place::Impossible(format!(
                "{t} °C is not a tested temperature and the configuration has no temperature law: its constants describe {} °C only; predict at {}, or give constants a temperature law (e.g. law = \"arrhenius\" on A, docs/FORMATS.md) and fit curves at several temperatures",
                self.temperatures
                    .iter()
                    .map(|x| x.0.to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                self.temperatures
                    .iter()
                    .map(|x| format!("{} °C", x.0))
                    .collect::<Vec<_>>()
                    .join(" or ")
            ));
        }
        if t < t0 - TEMPERATURE_MARGIN_C || t > t1 + TEMPERATURE_MARGIN_C {
            return Place::Beyond(format!(
                "{t} °C is more than {TEMPERATURE_MARGIN_C} °C outside the tested temperatures ({t0}–{t1} °C): beyond what the configuration can predict (docs/FORMATS.md, \"Limits of a prediction\")"
            ));
        }
        let (l0, l1) = self.stress_limits(t);
        if s < l0 / STRESS_MARGIN_FACTOR || s > l1 * STRESS_MARGIN_FACTOR {
            return Place::Beyond(format!(
                "{s} MPa is more than a factor {STRESS_MARGIN_FACTOR} outside the stresses tested at {t} °C ({l0}–{l1} MPa): beyond what the configuration can predict (docs/FORMATS.md, \"Limits of a prediction\")"
            ));
        }
        let (s0, s1) = self.stress_range(t);
        let in_t = t >= t0 && t <= t1;
        // Relative tolerance: the interpolated ends are computed through logarithms.
        let in_s = s >= s0 * (1.0 - 1e-12) && s <= s1 * (1.0 + 1e-12);
        Place::Inside(match (in_t, in_s) {
            (true, true) => Extrapolation::None,
            (true, false) => Extrapolation::Stress,
            (false, true) => Extrapolation::Temperature,
            (false, false) => Extrapolation::Both,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEMPS: [f64; 3] = [550.0, 575.0, 600.0];
    const STRESSES: [f64; 4] = [60.0, 80.0, 100.0, 130.0];

    fn settings(degree: usize) -> BaselineSettings<'static> {
        BaselineSettings {
            degree,
            tensile: &[],
        }
    }

    /// Rupture tests at TEMPS × STRESSES made by `truth`, times (1 + noise_k) with a fixed
    /// pattern of relative errors.
    fn tests_of(truth: &dyn RuptureParameter, noise: f64) -> Vec<(f64, f64, f64)> {
        let pattern = [0.7, -1.1, 0.4, -0.2, 1.3, -0.9];
        let mut k = 0;
        let mut out = Vec::new();
        for t in TEMPS {
            for s in STRESSES {
                let f = 10f64.powf(noise * pattern[k % pattern.len()]);
                k += 1;
                out.push((t, s, truth.predict(t, s) * f));
            }
        }
        out
    }

    fn blank() -> FittedOn {
        FittedOn {
            n_tests: 0,
            temperatures_c: vec![],
            stress_range_mpa: (0.0, 0.0),
            rms_log10: 0.0,
        }
    }

    /// Σ (log10 predicted − log10 measured)².
    fn sse(b: &dyn RuptureParameter, tests: &[(f64, f64, f64)]) -> f64 {
        tests
            .iter()
            .map(|&(t, s, tr)| (b.predict(t, s).log10() - tr.log10()).powi(2))
            .sum()
    }

    /// On rupture times with 2 % scatter in log10 the least-squares fit is no worse than the
    /// truth's constants (else the fit missed its minimum), its rms is that of its SSE, and it
    /// is not zero (the scatter is seen).
    fn noisy_fit_is_no_worse_than_the_truth(
        truth: &dyn RuptureParameter,
        fit: impl Fn(&[(f64, f64, f64)]) -> Box<dyn RuptureParameter>,
    ) {
        let noisy = tests_of(truth, 0.02);
        let f = fit(&noisy);
        let (s_fit, s_truth) = (sse(f.as_ref(), &noisy), sse(truth, &noisy));
        assert!(s_fit <= s_truth * (1.0 + 1e-9), "{s_fit} > {s_truth}");
        let rms = f.fitted_on().rms_log10;
        assert!((rms * rms * noisy.len() as f64 - s_fit).abs() <= 1e-9 * s_fit);
        assert!(rms > 1e-3, "{rms}");
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn kinds_have_distinct_names_and_keys() {
        let keys: Vec<&str> = BaselineKind::ALL.iter().map(|k| k.key()).collect();
        assert_eq!(keys, ["lmp", "osd", "mh", "wilshire"]);
        assert_eq!(
            serde_json::to_value(BaselineKind::OrrSherbyDorn).unwrap(),
            "orr_sherby_dorn"
        );
    }

    #[test]
    fn orr_sherby_dorn_recovers_its_constants() {
        // Q = 320 kJ/mol; P at 100 MPa = −15.2: log10 t_r ≈ 4.2 at 575 °C.
        let truth = OrrSherbyDorn {
            q_kj_per_mol: 320.0,
            coefficients: vec![-2.0, -4.5, -0.8],
            fitted_on: blank(),
        };
        let tests = tests_of(&truth, 0.0);
        let fit = OrrSherbyDorn::fit(&tests, &settings(2)).unwrap();
        assert!(rel(fit.q_kj_per_mol, 320.0) < 1e-9, "{}", fit.q_kj_per_mol);
        for (x, y) in fit.coefficients.iter().zip(&truth.coefficients) {
            assert!(rel(*x, *y) < 1e-8, "{x} vs {y}");
        }
        assert!(fit.fitted_on.rms_log10 < 1e-10);
        assert_eq!(fit.fitted_on.n_tests, 12);
        assert_eq!(fit.fitted_on.temperatures_c, TEMPS.to_vec());
        assert_eq!(fit.fitted_on.stress_range_mpa, (60.0, 130.0));
        // The prediction inverts the fit: the parameter of its own prediction is the master
        // curve, and log10 t_r = P + Q/(ln 10·R·T) by hand.
        for (t, s) in [(565.0, 70.0), (610.0, 140.0)] {
            let tr = fit.predict(t, s);
            assert!((fit.parameter(t, tr) - fit.master(s)).abs() < 1e-12);
            let by_hand = truth.master(s)
                + 320.0 / (std::f64::consts::LN_10 * 8.314_462_618e-3 * (t + 273.15));
            assert!((tr.log10() - by_hand).abs() < 1e-9);
        }
        noisy_fit_is_no_worse_than_the_truth(&truth, |t| {
            Box::new(OrrSherbyDorn::fit(t, &settings(2)).unwrap())
        });
    }

    #[test]
    fn manson_haferd_recovers_its_constants() {
        // Iso-stress lines meeting at T_a = 420 K, log10 t_a = 14: log10 t_r ≈ 4 at 575 °C.
        let truth = MansonHaferd {
            t_a_k: 420.0,
            log10_t_a: 14.0,
            coefficients: vec![-0.01, -0.005, -0.001],
            fitted_on: blank(),
        };
        let tests = tests_of(&truth, 0.0);
        let fit = MansonHaferd::fit(&tests, &settings(2)).unwrap();
        assert!((fit.t_a_k - 420.0).abs() < 1e-6, "T_a = {}", fit.t_a_k);
        assert!((fit.log10_t_a - 14.0).abs() < 1e-8, "{}", fit.log10_t_a);
        for (x, y) in fit.coefficients.iter().zip(&truth.coefficients) {
            assert!(rel(*x, *y) < 1e-7, "{x} vs {y}");
        }
        assert!(fit.fitted_on.rms_log10 < 1e-10);
        for (t, s) in [(565.0, 70.0), (610.0, 140.0)] {
            let tr = fit.predict(t, s);
            assert!((fit.parameter(t, tr) - fit.master(s)).abs() < 1e-12);
            assert!(rel(tr, truth.predict(t, s)) < 1e-8);
        }
        // A convergence point at the edge of the search: T_a just below the tested
        // temperatures (0.5 K) is refused, not returned at the bound.
        let edge = MansonHaferd {
            t_a_k: 550.0 + 273.15 - 0.5,
            ..truth.clone()
        };
        let e = MansonHaferd::fit(&tests_of(&edge, 0.0), &settings(2))
            .unwrap_err()
            .to_string();
        assert!(e.contains("runs into the lowest test temperature"), "{e}");
        // Iso-stress lines parallel in log t_r against T (log10 t_r = 30 − 0.03·T − 3·x):
        // T_a → −∞, refused.
        let parallel: Vec<(f64, f64, f64)> = TEMPS
            .iter()
            .flat_map(|&t| {
                STRESSES.iter().map(move |&s| {
                    (
                        t,
                        s,
                        10f64.powf(30.0 - 0.03 * (t + 273.15) - 3.0 * s.log10()),
                    )
                })
            })
            .collect();
        let e = MansonHaferd::fit(&parallel, &settings(2))
            .unwrap_err()
            .to_string();
        assert!(e.contains("runs to −∞"), "{e}");
        noisy_fit_is_no_worse_than_the_truth(&truth, |t| {
            Box::new(MansonHaferd::fit(t, &settings(2)).unwrap())
        });
    }

    #[test]
    fn manson_haferd_profile_is_the_minimum_over_t_a() {
        // Brute force: at no T_a of a fine scan is the SSE below the fit's.
        let truth = MansonHaferd {
            t_a_k: 500.0,
            log10_t_a: 12.0,
            coefficients: vec![-0.015, -0.002, -0.0015],
            fitted_on: blank(),
        };
        let tests = tests_of(&truth, 0.03);
        let fit = MansonHaferd::fit(&tests, &settings(2)).unwrap();
        let (_, sse_fit) = MansonHaferd::at_t_a(&tests, 2, fit.t_a_k).unwrap();
        for i in 0..4000 {
            let t_a = 823.15 - 1.0 - i as f64 * 0.5;
            let (_, sse) = MansonHaferd::at_t_a(&tests, 2, t_a).unwrap();
            assert!(
                sse >= sse_fit * (1.0 - 1e-9),
                "T_a = {t_a}: {sse} < {sse_fit}"
            );
        }
        assert!((fit.fitted_on.rms_log10.powi(2) * 12.0 - sse_fit).abs() < 1e-9 * sse_fit);
    }

    fn tensile() -> Vec<TensileStrength> {
        [
            (550.0, 480.0),
            (575.0, 450.0),
            (600.0, 410.0),
            (650.0, 330.0),
        ]
        .iter()
        .map(|&(t, v)| TensileStrength {
            temperature_c: t,
            strength_mpa: v,
        })
        .collect()
    }

    #[test]
    fn wilshire_recovers_its_constants() {
        let ts = tensile();
        let truth = Wilshire {
            k1: 20.0,
            u: 0.15,
            q_star_kj_per_mol: 200.0,
            tensile_strength: ts.clone(),
            fitted_on: blank(),
        };
        let tests = tests_of(&truth, 0.0);
        let s = BaselineSettings {
            degree: 2,
            tensile: &ts,
        };
        let fit = Wilshire::fit(&tests, &s).unwrap();
        assert!(rel(fit.k1, 20.0) < 1e-8, "k1 = {}", fit.k1);
        assert!(rel(fit.u, 0.15) < 1e-9, "u = {}", fit.u);
        assert!(rel(fit.q_star_kj_per_mol, 200.0) < 1e-9);
        assert!(fit.fitted_on.rms_log10 < 1e-10);
        // The prediction inverts the fit: the normalised stress at its own compensated time
        // is σ/σ_TS; between tabulated temperatures σ_TS is interpolated (625 °C: 370 MPa).
        for (t, s) in [(565.0, 70.0), (625.0, 140.0)] {
            let tr = fit.predict(t, s);
            let sts = tensile_at(&ts, t).unwrap();
            assert!(rel(fit.normalised_stress(fit.compensated_time(t, tr)), s / sts) < 1e-10);
        }
        assert_eq!(tensile_at(&ts, 625.0), Some(370.0));
        // No σ_TS at 700 °C (not extrapolated), a stress above σ_TS: no prediction.
        assert!(fit.predict(700.0, 100.0).is_nan());
        assert!(fit.predict(575.0, 460.0).is_nan());
        noisy_fit_is_no_worse_than_the_truth(&truth, |t| Box::new(Wilshire::fit(t, &s).unwrap()));
    }

    #[test]
    fn wilshire_is_absent_without_tensile_strengths() {
        let lm = LarsonMiller {
            c: 20.0,
            coefficients: vec![3.1e4, -2.5e3, -1.2e3],
            n_tests: 0,
            temperatures_c: vec![],
            stress_range_mpa: (0.0, 0.0),
            rms_log10: 0.0,
        };
        let tests = tests_of(&lm, 0.0);
        let all = fit_all(&tests, &settings(2));
        assert_eq!(
            all.iter().map(|b| b.kind).collect::<Vec<_>>(),
            BaselineKind::ALL
        );
        let e = all[3].fit.as_ref().unwrap_err();
        assert!(e.contains("no tensile strength"), "{e}");
        assert!(all[3].describe().contains("absent"));
        assert!(all[3].predict(575.0, 80.0).is_nan());
        assert!(all[3].to_json()["error"].is_string());
        // The Larson–Miller baseline is the one of `crate::lmp`, to the bit.
        let direct = LarsonMiller::fit(&tests, 2).unwrap();
        let b = all[0].fit.as_ref().unwrap();
        assert_eq!(b.predict(565.0, 70.0), direct.rupture_time(565.0, 70.0));
        assert_eq!(all[0].to_json()["c"], json!(direct.c));
        // Without a tensile strength at a tested temperature: the reason names it.
        let two = tensile()[..2].to_vec();
        let e = Wilshire::fit(
            &tests,
            &BaselineSettings {
                degree: 2,
                tensile: &two,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("no tensile strength at 600 °C"), "{e}");
    }

    #[test]
    fn one_temperature_or_too_few_stresses_is_an_error() {
        let one = [
            (560.0, 85.0, 9.1e4),
            (560.0, 100.0, 5.2e4),
            (560.0, 110.0, 3.1e4),
            (560.0, 120.0, 1.1e4),
        ];
        let ts = [
            TensileStrength {
                temperature_c: 560.0,
                strength_mpa: 400.0,
            },
            TensileStrength {
                temperature_c: 590.0,
                strength_mpa: 380.0,
            },
        ];
        let s = BaselineSettings {
            degree: 1,
            tensile: &ts,
        };
        for b in fit_all(&one, &s) {
            let e = b.fit.unwrap_err();
            assert!(e.contains("1 temperature(s)"), "{:?}: {e}", b.kind);
        }
        // Two temperatures but two stresses for a quadratic master curve.
        let few = [
            (560.0, 85.0, 9.1e4),
            (560.0, 100.0, 5.2e4),
            (590.0, 85.0, 5.1e3),
            (590.0, 100.0, 2.0e3),
        ];
        let e = OrrSherbyDorn::fit(&few, &settings(2))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("Orr–Sherby–Dorn") && e.contains("2 stresses"),
            "{e}"
        );
        let e = MansonHaferd::fit(&few, &settings(2))
            .unwrap_err()
            .to_string();
        assert!(e.contains("Manson–Haferd") && e.contains("stresses"), "{e}");
        let e = MansonHaferd::fit(&few, &settings(0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("degree 0"), "{e}");
        // A stress at the tensile strength.
        let above = [
            (560.0, 85.0, 9.1e4),
            (560.0, 400.0, 5.2e4),
            (590.0, 85.0, 5.1e3),
        ];
        let e = Wilshire::fit(&above, &s).unwrap_err().to_string();
        assert!(e.contains("at or above the tensile strength"), "{e}");
        assert!(
            OrrSherbyDorn::fit(&[(560.0, -1.0, 1.0), (590.0, 1.0, 1.0)], &settings(0)).is_err()
        );
    }

    #[test]
    fn extrapolation_table() {
        let on = FittedOn {
            n_tests: 6,
            temperatures_c: vec![750.0, 900.0, 950.0],
            stress_range_mpa: (18.0, 137.0),
            rms_log10: 0.1,
        };
        use Extrapolation::*;
        for (t, s, want) in [
            (850.0, 40.0, Extrapolation::None),
            (750.0, 18.0, Extrapolation::None),
            (950.0, 137.0, Extrapolation::None),
            (700.0, 40.0, Temperature),
            (1000.0, 40.0, Temperature),
            (850.0, 10.0, Stress),
            (850.0, 200.0, Stress),
            (700.0, 200.0, Both),
            (f64::NAN, 40.0, Temperature),
        ] {
            assert_eq!(Extrapolation::of(&on, t, s), want, "{t} °C {s} MPa");
        }
        assert_eq!(Both.as_str(), "both");
        assert_eq!(serde_json::to_value(Extrapolation::None).unwrap(), "none");
    }

    #[test]
    fn tensile_strength_entries_parse() {
        assert_eq!(
            TensileStrength::parse(" 850 : 260 ").unwrap(),
            TensileStrength {
                temperature_c: 850.0,
                strength_mpa: 260.0
            }
        );
        for bad in ["850", "x:260", "850:y", "850:-1", "-300:100"] {
            assert!(TensileStrength::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(tensile_at(&tensile(), 549.0), None);
        assert_eq!(tensile_at(&tensile(), 650.0), Some(330.0));
    }
}
