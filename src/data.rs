//! Creep curves and rupture records: read, validate, group by (temperature, stress[, specimen])
//! and match curves with their rupture records (DESIGN.md §3).
//!
//! Files hold strain in percent and rates in percent per hour; everything in this module's
//! output is a fraction (strain) or 1/h (rate).
//!
//! Both CSV files need a header (line 1); columns may come in any order and extra columns are
//! ignored. Every error names the file, the 1-based line (header = line 1) and the field.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Result};

mod min_rate;
pub mod specimen;
mod table;

/// 0 °C in K: files give temperatures in °C, the model's load and the temperature laws work
/// in K.
pub const ZERO_CELSIUS_K: f64 = 273.15;

pub use min_rate::estimate_min_rate;
pub use table::PROGRESS_MIN_BYTES;
pub(crate) use table::{read_file, Table};

/// Required columns of the curves file.
pub const CURVE_COLUMNS: &[&str] = &["temperature_C", "stress_MPa", "time_h", "strain_pct"];
/// Required columns of the ruptures file.
pub const RUPTURE_COLUMNS: &[&str] = &["temperature_C", "stress_MPa", "rupture_time_h"];
/// Fraction of the life a window of [`estimate_min_rate`] must span at least.
pub const MIN_RATE_WINDOW_FRACTION: f64 = 0.15;
/// Fewest points in a window of [`estimate_min_rate`]: with 3, one digitized point that
/// falls back (560 °C, 110 MPa at 10239 h) pulls the slope below that of a lower stress.
pub const MIN_RATE_WINDOW_POINTS: usize = 5;
/// Fewest points a curve may have (after exact duplicates are dropped).
pub const MIN_POINTS: usize = 3;
/// Lowest test temperature a data file may hold, °C: creep tests of the alloys this crate
/// is for run hot (room temperature is already unusual); a value below 0 °C is taken for a
/// typo or a unit mix-up, not a test.
pub const MIN_DATA_TEMPERATURE_C: f64 = 0.0;
/// Highest test temperature a data file may hold, °C: above any creep test of a metal
/// (nickel superalloys are tested to about 1200 °C, refractory metals to about 2000 °C); a
/// larger value is a typo or kelvin where °C is expected.
pub const MAX_DATA_TEMPERATURE_C: f64 = 2000.0;
/// Robust z above which a point is a gross outlier of its curve ([`outlier_z`]).
pub const OUTLIER_Z: f64 = 50.0;
/// Neighbours on each side of a point that its local fit uses ([`outlier_z`]).
pub const OUTLIER_NEIGHBOURS: usize = 3;
/// Floor of the robust spread of a curve's strains in [`outlier_z`] (fraction: 0.01 %
/// strain, the order of a reading error of a digitised or logged curve).
pub const OUTLIER_SPREAD_FLOOR: f64 = 1e-4;

/// A reading later than this many times its test's rupture time is a gross outlier in time
/// ([`after_rupture`]): a specimen is not read after it broke. Real last readings lie at
/// 0.93–1.0007 × the rupture time (the seed data's curves, the 34 Alloy 617 curves); 1.5 is
/// half a life past the rupture, beyond any rounding or digitising of a reading's time, and
/// a digit too many (×10) or a value from another column is far beyond it.
pub const AFTER_RUPTURE_FACTOR: f64 = 1.5;

/// A rupture strain below this fraction of the largest strain its curve reached is refused:
/// strain does not fall by half before rupture, so such a value is a typo or a fraction
/// given where percent is expected (×0.01). A strain at rupture measured on the broken
/// specimen may differ from the extensometer's last reading, but not by half.
pub const MIN_RUPTURE_STRAIN_OF_CURVE: f64 = 0.5;

/// A ruptured test's curve that ends before this fraction of its rupture time is named in a
/// warning: real curves run to 0.93–1.0 of the life (the seed data, Alloy 617), so one that
/// stops at 1 % of it is more likely a unit mix-up between the two files (s or min against h)
/// than a test read for 1 % of its life.
pub const MIN_LIFE_COVERED: f64 = 0.01;

/// Below this strain (fraction, 0.5 %) at every ruptured test, the curves' strains are named
/// in a warning as a likely fraction given where percent is expected: metals rupture in creep
/// at 1–60 % strain.
pub const MIN_RUPTURED_STRAIN: f64 = 0.005;

/// What [`load`] does with gross outliers of a curve ([`outlier_z`] above [`OUTLIER_Z`], or
/// a reading after the test's rupture, [`after_rupture`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutlierPolicy {
    /// Refuse the data: a one-line error naming the first outlier (file, line, value, z)
    /// and the configuration switch. The default.
    #[default]
    Refuse,
    /// Drop the outliers, each named in a warning and in [`Dataset::dropped`].
    Drop,
    /// Keep them as measured, each named in a warning.
    Keep,
}

/// ", specimen S" for a labelled test, "" otherwise: the tail of a message naming a test.
fn specimen_suffix(specimen: &Option<String>) -> String {
    specimen
        .as_ref()
        .map(|s| format!(", specimen {s}"))
        .unwrap_or_default()
}

/// ", specimen = S" for a labelled test, "" otherwise: the tail of a message naming a test by
/// its key columns.
fn specimen_key(specimen: &Option<String>) -> String {
    specimen
        .as_ref()
        .map(|s| format!(", specimen = {s}"))
        .unwrap_or_default()
}

/// A point of a curves file flagged as a gross outlier: its strain far from its neighbours'
/// ([`outlier_z`]) or its time after its test's rupture ([`after_rupture`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Outlier {
    /// The column found wrong: `strain_pct` or `time_h`.
    pub column: &'static str,
    /// The curves file.
    pub file: String,
    /// 1-based line in it.
    pub line: usize,
    /// Its curve: temperature (°C), stress (MPa), specimen.
    #[serde(rename = "temperature_C")]
    pub temperature_c: f64,
    #[serde(rename = "stress_MPa")]
    pub stress_mpa: f64,
    pub specimen: Option<String>,
    /// Time (h) and strain (%) as in the file.
    pub time_h: f64,
    pub strain_pct: f64,
    /// Its robust z (a strain outlier).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
    /// The test's rupture time, h (a time outlier).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rupture_time_h: Option<f64>,
}

impl Outlier {
    /// `FILE:LINE: column '…': …` without the leading file and line.
    fn what(&self) -> String {
        let specimen = specimen_suffix(&self.specimen);
        match (self.z, self.rupture_time_h) {
            (_, Some(tr)) => format!(
                "column 'time_h': {} h is {} × the rupture time {} h of the test at {} °C, {} MPa{} (a reading after the rupture: a mistyped time? the limit is {AFTER_RUPTURE_FACTOR} ×)",
                self.time_h,
                match self.time_h / tr {
                    r if r < 1e4 => format!("{r:.2}"),
                    r => format!("{r:.3e}"),
                },
                tr,
                self.temperature_c,
                self.stress_mpa,
                specimen
            ),
            (z, None) => format!(
                "column 'strain_pct': {} % at {} h is a gross outlier of the curve at {} °C, {} MPa{} (robust z = {:.3e}, the limit is {OUTLIER_Z})",
                self.strain_pct,
                self.time_h,
                self.temperature_c,
                self.stress_mpa,
                specimen,
                z.unwrap_or(f64::NAN)
            ),
        }
    }
}

/// Robust z of every point of a curve (strains as fractions, sorted by time): how far the
/// point lies from the local fit of its neighbours, in units of the curve's robust spread.
///
/// The local fit of point i is the median of the strains of its [`OUTLIER_NEIGHBOURS`]
/// neighbours on each side (at an end, the 2 × [`OUTLIER_NEIGHBOURS`] nearest on the one
/// side); creep strain is nearly monotone in time, so a measured point lies among its
/// neighbours. The scale is the larger of the neighbours' own robust spread (1.4826 × their
/// MAD about that median: a steep part tolerates a larger step) and the curve's robust spread
/// 1.4826 × MAD of all its strains (floored at [`OUTLIER_SPREAD_FLOOR`]). z = |ε_i − median| / scale, except that the
/// first point may lie anywhere from zero up to its neighbours (creep strain starts from zero:
/// a jump on loading is no outlier), only its distance beyond counts. A monotone curve,
/// a steep tertiary end included, stays at a few (the seed data and the 34 Alloy 617 curves:
/// at most 3.98); a reading error is a fraction of 1. Median and MAD are robust: up to
/// [`OUTLIER_NEIGHBOURS`] − 1 neighbouring outliers do not hide each other.
pub fn outlier_z(strains: &[f64]) -> Vec<f64> {
    let n = strains.len();
    let median = |v: &mut Vec<f64>| -> f64 {
        v.sort_by(f64::total_cmp);
        let m = v.len();
        if m == 0 {
            f64::NAN
        } else if m % 2 == 1 {
            v[m / 2]
        } else {
            0.5 * (v[m / 2 - 1] + v[m / 2])
        }
    };
    let mut all = strains.to_vec();
    let med = median(&mut all);
    let mut dev: Vec<f64> = strains.iter().map(|e| (e - med).abs()).collect();
    let spread = (1.4826 * median(&mut dev)).max(OUTLIER_SPREAD_FLOOR);
    let k = OUTLIER_NEIGHBOURS;
    (0..n)
        .map(|i| {
            // k each side, shifted inwards at the ends so that 2k neighbours are used.
            let lo = i.saturating_sub(k).min(n.saturating_sub(2 * k + 1));
            let hi = (lo + 2 * k + 1).min(n);
            let mut nb: Vec<f64> = (lo..hi).filter(|&j| j != i).map(|j| strains[j]).collect();
            if nb.is_empty() {
                return 0.0;
            }
            let m = median(&mut nb);
            let mut spread_nb: Vec<f64> = nb.iter().map(|x| (x - m).abs()).collect();
            let local = 1.4826 * median(&mut spread_nb);
            let e = strains[i];
            // Creep strain starts from zero: the first point may lie anywhere between zero
            // and its neighbours (a jump on loading); only a distance beyond counts.
            let d = if i == 0 && e < m {
                (m.min(0.0) - e).max(0.0)
            } else {
                (e - m).abs()
            };
            d / local.max(spread)
        })
        .collect()
}

/// The readings (indices) of a ruptured test's curve later than [`AFTER_RUPTURE_FACTOR`] ×
/// its rupture time `rupture_h`: mistyped times, where they are fewer than half of the
/// readings. Where most lie beyond, the rupture record is what is suspect: none is flagged,
/// and loading warns that the rupture time is before the last reading.
pub fn after_rupture(times: &[f64], rupture_h: f64) -> Vec<usize> {
    let late: Vec<usize> = (0..times.len())
        .filter(|&k| times[k] > AFTER_RUPTURE_FACTOR * rupture_h)
        .collect();
    if 2 * late.len() < times.len() {
        late
    } else {
        Vec::new()
    }
}

/// The gross outliers of a curve read from `path`, by index: its readings after the test's
/// rupture (`rupture_h`, `None` for a test without one), then among the others the strains
/// with [`outlier_z`] above [`OUTLIER_Z`] (a misplaced reading does not count among its
/// neighbours).
fn curve_outliers(c: &RawCurve, path: &Path, rupture_h: Option<f64>) -> Vec<(usize, Outlier)> {
    let point = |k: usize, z: Option<f64>, tr: Option<f64>| Outlier {
        column: if tr.is_some() { "time_h" } else { "strain_pct" },
        file: path.display().to_string(),
        line: c.lines[k],
        temperature_c: c.temperature_c,
        stress_mpa: c.stress_mpa,
        specimen: c.specimen.clone(),
        time_h: c.times_h[k],
        strain_pct: pct(c.strains[k]),
        z,
        rupture_time_h: tr,
    };
    let late = rupture_h.map_or_else(Vec::new, |tr| after_rupture(&c.times_h, tr));
    let rest: Vec<usize> = (0..c.times_h.len()).filter(|k| !late.contains(k)).collect();
    let strains: Vec<f64> = rest.iter().map(|&k| c.strains[k]).collect();
    let mut found: Vec<(usize, Outlier)> = late
        .iter()
        .map(|&k| (k, point(k, None, rupture_h)))
        .collect();
    found.extend(
        outlier_z(&strains)
            .into_iter()
            .zip(&rest)
            .filter(|(z, _)| *z > OUTLIER_Z)
            .map(|(z, &k)| (k, point(k, Some(z), None))),
    );
    found.sort_by_key(|(k, _)| *k);
    found
}

/// One measured creep curve (one test), ready for fitting.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Test temperature, °C.
    pub temperature_c: f64,
    /// Nominal stress, MPa.
    pub stress_mpa: f64,
    /// Specimen label, when the curves file has a `specimen` column (and the cell is not empty).
    pub specimen: Option<String>,
    /// Measurement times, h, sorted ascending (stable: equal times keep their file order).
    pub times_h: Vec<f64>,
    /// Measured strains (fraction), one per time.
    pub strains: Vec<f64>,
    /// Measured rupture time, h; `None` only for a test declared interrupted.
    pub rupture_time_h: Option<f64>,
    /// Rupture strain (fraction): from the ruptures file, else the last measured strain (the
    /// largest strain among the points at the largest time).
    pub rupture_strain: f64,
    /// Minimum creep rate (1/h) from the ruptures file, if given there.
    pub min_rate_measured: Option<f64>,
    /// Minimum creep rate (1/h) estimated from the curve by [`estimate_min_rate`], with the
    /// rupture time (or, for an interrupted test, the last measured time) as the life.
    pub min_rate_estimated: f64,
    /// Where each point is the mean of a group of readings ([`reduced_to_means`]): the
    /// readings' times, so that the model is averaged over the same times. `None`: every
    /// point is a reading.
    pub groups: Option<std::sync::Arc<ReadingGroups>>,
}

/// The readings behind a curve of group means: their times (h, ascending) and, per point of
/// the curve, the end of its group in them (group k is `times_h[ends[k-1]..ends[k]]`).
#[derive(Debug, Clone, PartialEq)]
pub struct ReadingGroups {
    /// The readings' times, h.
    pub times_h: Vec<f64>,
    /// Per point, one past its group's last reading.
    pub ends: Vec<usize>,
    /// ρ in [0, 1]: the share of a reading's error variance that averaging does not shrink
    /// (a misfit of the model, or reading error correlated over the group), so that a mean
    /// of m readings has (1 − ρ)/m + ρ of a reading's variance ([`reading_units_factor`]).
    /// 0 (white reading error) unless `diagnose` estimated it ([`Curve::with_misfit_share`]).
    pub misfit_share: f64,
}

/// The factor that puts the residual of a mean of `m` readings into a reading's units when a
/// share `rho` of a reading's error variance does not shrink with averaging:
/// 1/√((1 − ρ)/m + ρ). √m at ρ = 0 (computed as such, so that it is bit for bit the white
/// reading error's weight), 1 at ρ = 1 (every mean as precise as one reading).
pub fn reading_units_factor(m: usize, rho: f64) -> f64 {
    if rho == 0.0 {
        (m as f64).sqrt()
    } else {
        1.0 / ((1.0 - rho) / m as f64 + rho).sqrt()
    }
}

impl ReadingGroups {
    /// Per point, its group's size m (readings averaged).
    pub fn sizes(&self) -> impl Iterator<Item = usize> + '_ {
        let mut lo = 0;
        self.ends.iter().map(move |&hi| {
            let m = hi - lo;
            lo = hi;
            m
        })
    }

    /// Per point, the factor that puts its residual in a reading's units
    /// ([`reading_units_factor`] of its group's size at [`ReadingGroups::misfit_share`]): √m
    /// for white reading error, where a mean of m readings has 1/m of a reading's variance.
    pub fn reading_unit_factors(&self) -> impl Iterator<Item = f64> + '_ {
        let rho = self.misfit_share;
        self.sizes().map(move |m| reading_units_factor(m, rho))
    }

    /// The mean over each group of `raw` (one value per reading) into `out` (one per group).
    pub fn average<S: crate::dual::Scalar>(&self, raw: &[S], out: &mut [S]) {
        let mut lo = 0;
        for (o, &hi) in out.iter_mut().zip(&self.ends) {
            let mut acc = S::cst(0.0);
            for v in &raw[lo..hi] {
                acc = acc + *v;
            }
            *o = acc / (hi - lo) as f64;
            lo = hi;
        }
    }
}

/// The campaign (laboratory, heat or batch of specimens) a specimen label names: the text
/// before its first `-` (`INL2-a` → `INL2`), the whole label when it has none.
pub fn campaign_of(specimen: &str) -> &str {
    specimen.split('-').next().unwrap_or(specimen)
}

/// Each curve's test campaign ([`Curve::campaign`]) where the labels name campaigns: every
/// curve labelled, two campaigns or more, and one of them holding specimens at two test
/// conditions (temperature, stress) or more. Labels that only pair replicates (`S4-a` and
/// `S4-b` at one stress, as `synth` writes them) or name each specimen alone (`SX01`) name no
/// campaigns: `None`. A campaign is a laboratory, heat or batch that tested several conditions.
pub fn campaigns(curves: &[Curve]) -> Option<Vec<&str>> {
    let names: Vec<&str> = curves.iter().map(Curve::campaign).collect::<Option<_>>()?;
    let mut distinct = names.clone();
    distinct.sort_unstable();
    distinct.dedup();
    let spans_conditions = |name: &str| {
        let mut at = curves
            .iter()
            .zip(&names)
            .filter(|(_, n)| **n == name)
            .map(|(c, _)| (c.temperature_c, c.stress_mpa));
        let first = at.next();
        at.any(|cond| Some(cond) != first)
    };
    (distinct.len() >= 2 && distinct.iter().any(|n| spans_conditions(n))).then_some(names)
}

impl Curve {
    /// Multiply each point's value in `v` (one per point, e.g. residuals or a design column)
    /// by its group's factor ([`ReadingGroups::reading_unit_factors`]: √m for white reading
    /// error, m the readings its group averages), so that a mean's residual is in a reading's
    /// units and the points of different sizes share one error model. A no-op where every point is a reading (`groups` is `None`).
    pub fn to_reading_units(&self, v: &mut [f64]) {
        if let Some(g) = &self.groups {
            for (v, r) in v.iter_mut().zip(g.reading_unit_factors()) {
                *v *= r;
            }
        }
    }

    /// The curve with its groups' [`ReadingGroups::misfit_share`] set to `rho` (the same
    /// curve where its points are readings).
    pub fn with_misfit_share(&self, rho: f64) -> Curve {
        Curve {
            groups: self.groups.as_ref().map(|g| {
                std::sync::Arc::new(ReadingGroups {
                    misfit_share: rho,
                    ..(**g).clone()
                })
            }),
            ..self.clone()
        }
    }

    /// The inverse of [`Curve::to_reading_units`]: a reading's error at each point turned into
    /// its group mean's.
    pub fn from_reading_units(&self, v: &mut [f64]) {
        if let Some(g) = &self.groups {
            for (v, r) in v.iter_mut().zip(g.reading_unit_factors()) {
                *v /= r;
            }
        }
    }

    /// A curve of two readings (0 and 1 h, 0 and 1 % strain, ruptured at 1 h) at `t` °C and
    /// `s` MPa: for tests of what depends on the conditions and labels only.
    #[cfg(test)]
    pub(crate) fn two_point(t: f64, s: f64, specimen: Option<&str>) -> Curve {
        Curve {
            temperature_c: t,
            stress_mpa: s,
            specimen: specimen.map(str::to_string),
            times_h: vec![0.0, 1.0],
            strains: vec![0.0, 0.01],
            rupture_time_h: Some(1.0),
            rupture_strain: 0.01,
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 0.01,
        }
    }

    /// The minimum creep rate to compare predictions with: the measured one when the ruptures
    /// file gives it, else the estimate from the curve.
    pub fn min_rate(&self) -> f64 {
        self.min_rate_measured.unwrap_or(self.min_rate_estimated)
    }

    /// The largest measured strain (fraction; 0 without points or with none positive).
    pub fn largest_strain(&self) -> f64 {
        self.strains.iter().copied().fold(0.0, f64::max)
    }

    /// The life used for estimates: the rupture time, or the last measured time of an
    /// interrupted test.
    pub fn life_h(&self) -> f64 {
        self.rupture_time_h
            .unwrap_or_else(|| self.times_h.last().copied().unwrap_or(0.0))
    }

    /// The test campaign of its specimen label ([`campaign_of`]), if it has one.
    pub fn campaign(&self) -> Option<&str> {
        self.specimen.as_deref().map(campaign_of)
    }

    /// A short human label, e.g. `560 °C, 85 MPa` or `560 °C, 85 MPa, specimen S3`.
    pub fn label(&self) -> String {
        let mut s = format!("{} °C, {} MPa", self.temperature_c, self.stress_mpa);
        if let Some(sp) = &self.specimen {
            s.push_str(&format!(", specimen {sp}"));
        }
        s
    }
}

/// The curves of one run, with the warnings raised while loading them.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// Sorted by temperature, then stress ascending, then specimen.
    pub curves: Vec<Curve>,
    /// Non-fatal findings (dropped duplicate points, unused rupture records, …), one line each.
    pub warnings: Vec<String>,
    /// Gross outliers dropped on load (`outliers = "drop"`), in file order.
    pub dropped: Vec<Outlier>,
    /// Life-only tests: rupture records that match no curve (at the kept temperature where the
    /// configuration keeps one), in file order. No fit uses them (creepfit fits tests with
    /// curves, the classical baselines the same tests' lives); `holdout` predicts those it
    /// leaves out.
    pub lives: Vec<RuptureRecord>,
}

impl Dataset {
    /// The data set of `curves` alone: no warnings, nothing dropped, no life-only tests.
    pub fn of_curves(curves: Vec<Curve>) -> Dataset {
        Dataset {
            curves,
            warnings: Vec::new(),
            dropped: Vec::new(),
            lives: Vec::new(),
        }
    }
}

impl RuptureRecord {
    /// Its test campaign: the specimen label's text before the first `-` ([`campaign_of`]).
    pub fn campaign(&self) -> Option<&str> {
        self.specimen.as_deref().map(campaign_of)
    }
}

/// A test declared interrupted (it did not rupture: no rupture time, no lifetime term): a
/// configuration's `interrupted` entry.
#[derive(Debug, Clone, PartialEq)]
pub enum Interrupted {
    /// A bare stress (MPa): every curve at that stress. Accepted only when the loaded curves
    /// are at one temperature (the form from before several temperatures).
    Stress(f64),
    /// `"T:σ"` (°C, MPa): every replicate at that temperature and stress; `"T:σ:specimen"`:
    /// the one curve of that specimen.
    At {
        /// Temperature, °C.
        temperature_c: f64,
        /// Stress, MPa.
        stress_mpa: f64,
        /// Specimen label, if given.
        specimen: Option<String>,
    },
}

impl From<f64> for Interrupted {
    fn from(stress_mpa: f64) -> Self {
        Interrupted::Stress(stress_mpa)
    }
}

impl Interrupted {
    /// Parse `"T:σ"` or `"T:σ:specimen"` (°C, MPa; the specimen as in the curves file).
    pub fn parse(s: &str) -> std::result::Result<Interrupted, String> {
        let mut parts = s.splitn(3, ':');
        let (t, sig) = match (parts.next(), parts.next()) {
            (Some(t), Some(sig)) => (t.trim(), sig.trim()),
            _ => {
                return Err(format!(
                "'{s}': expected \"T:stress\" or \"T:stress:specimen\" (°C:MPa), e.g. \"920:80\""
            ))
            }
        };
        let t: f64 = t
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the temperature '{t}'"))?;
        let sig: f64 = sig
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the stress '{sig}'"))?;
        if !(t.is_finite() && t > -ZERO_CELSIUS_K) {
            return Err(format!(
                "'{s}': the temperature must be above absolute zero (°C)"
            ));
        }
        if !(sig.is_finite() && sig > 0.0) {
            return Err(format!("'{s}': the stress must be positive (MPa)"));
        }
        let specimen = match parts.next().map(str::trim) {
            None => None,
            Some("") => return Err(format!("'{s}': empty specimen after the second ':'")),
            Some(sp) => Some(sp.to_string()),
        };
        Ok(Interrupted::At {
            temperature_c: t,
            stress_mpa: sig,
            specimen,
        })
    }

    /// As written in the configuration: `80`, `920:80` or `920:80:S3`.
    pub fn label(&self) -> String {
        match self {
            Interrupted::Stress(s) => format!("{s}"),
            Interrupted::At {
                temperature_c,
                stress_mpa,
                specimen: None,
            } => format!("{temperature_c}:{stress_mpa}"),
            Interrupted::At {
                temperature_c,
                stress_mpa,
                specimen: Some(sp),
            } => format!("{temperature_c}:{stress_mpa}:{sp}"),
        }
    }
}

/// A bare stress serialises as the number (the run identity of a configuration written
/// before keyed entries is unchanged), a keyed entry as its string.
impl serde::Serialize for Interrupted {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Interrupted::Stress(v) => s.serialize_f64(*v),
            _ => s.serialize_str(&self.label()),
        }
    }
}

impl<'de> serde::Deserialize<'de> for Interrupted {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Interrupted;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a stress (MPa) or a string \"T:stress\" / \"T:stress:specimen\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Interrupted, E> {
                Ok(Interrupted::Stress(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Interrupted, E> {
                Ok(Interrupted::Stress(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Interrupted, E> {
                Ok(Interrupted::Stress(v as f64))
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Interrupted, E> {
                Interrupted::parse(v).map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

/// Which curves the `interrupted` entries declare interrupted (one flag per curve), or the
/// first entry that is ambiguous or matches no curve: (its index, what is wrong). `filter`:
/// the temperature filter the curves were loaded with (named in the message).
///
/// A bare stress is accepted only when the curves are at one temperature (as before keyed
/// entries, values compared to 1e-9 relative); a keyed entry matches the curves at its
/// temperature and stress, and its specimen when it gives one.
pub fn interrupted_flags(
    entries: &[Interrupted],
    curves: &[RawCurve],
    filter: Option<f64>,
) -> std::result::Result<Vec<bool>, (usize, String)> {
    let mut temps: Vec<f64> = curves.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let mut flags = vec![false; curves.len()];
    for (k, e) in entries.iter().enumerate() {
        let hit: Vec<usize> = match e {
            Interrupted::Stress(s) => {
                if temps.len() > 1 {
                    let list: Vec<String> = temps.iter().map(|t| t.to_string()).collect();
                    return Err((
                        k,
                        format!(
                            "a bare stress is ambiguous: the curves are at {} temperatures ({} °C); write \"T:σ\" (°C:MPa), e.g. \"{}:{s}\"",
                            temps.len(),
                            list.join(", "),
                            list[0]
                        ),
                    ));
                }
                (0..curves.len())
                    .filter(|&i| close(*s, curves[i].stress_mpa))
                    .collect()
            }
            Interrupted::At {
                temperature_c,
                stress_mpa,
                specimen,
            } => (0..curves.len())
                .filter(|&i| {
                    let c = &curves[i];
                    close(*temperature_c, c.temperature_c)
                        && close(*stress_mpa, c.stress_mpa)
                        && specimen
                            .as_ref()
                            .is_none_or(|sp| c.specimen.as_ref() == Some(sp))
                })
                .collect(),
        };
        if hit.is_empty() {
            let filtered = match filter {
                Some(t) => format!(" (the configuration keeps temperature_C = {t} only)"),
                None => String::new(),
            };
            return Err((k, format!("matches no curve{filtered}")));
        }
        for i in hit {
            flags[i] = true;
        }
    }
    Ok(flags)
}

/// What [`load`] keeps and what it tolerates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadOptions {
    /// Keep only curves at this temperature (°C).
    pub temperature_c: Option<f64>,
    /// Tests declared interrupted: they need no rupture record (see [`interrupted_flags`]).
    pub interrupted: Vec<Interrupted>,
    /// The configuration file and line that declare `interrupted`, named in its errors
    /// (`None`: the errors name the field alone).
    pub interrupted_source: Option<(std::path::PathBuf, usize)>,
    /// Accept curves at several temperatures without a `temperature_c` filter. Off (the
    /// default), that is an error: one set of constants does not fit several temperatures.
    /// A configuration that declares how constants depend on temperature (temperature laws,
    /// DESIGN.md §8) switches it on.
    pub several_temperatures: bool,
    /// What to do with gross outliers of a curve ([`outlier_z`]); refuse by default.
    pub outliers: OutlierPolicy,
}

/// The points of one curve as read from the curves file: grouped, sorted by time (stable)
/// and without exact duplicates.
#[derive(Debug, Clone, PartialEq)]
pub struct RawCurve {
    /// Test temperature, °C.
    pub temperature_c: f64,
    /// Nominal stress, MPa.
    pub stress_mpa: f64,
    /// Specimen label, if any.
    pub specimen: Option<String>,
    /// Times, h, ascending.
    pub times_h: Vec<f64>,
    /// Strains, fraction.
    pub strains: Vec<f64>,
    /// 1-based file line of each point.
    pub lines: Vec<usize>,
    /// 1-based line of the curve's first row in the file.
    pub first_line: usize,
}

/// One row of the ruptures file.
#[derive(Debug, Clone, PartialEq)]
pub struct RuptureRecord {
    /// Test temperature, °C.
    pub temperature_c: f64,
    /// Nominal stress, MPa.
    pub stress_mpa: f64,
    /// Rupture time, h (> 0).
    pub rupture_time_h: f64,
    /// Rupture strain (fraction), if given.
    pub rupture_strain: Option<f64>,
    /// Minimum creep rate, 1/h, if given.
    pub min_rate: Option<f64>,
    /// Specimen label, if the file has the column and the cell is not empty.
    pub specimen: Option<String>,
    /// 1-based line in the file.
    pub line: usize,
}

/// Read both files, group the curves, match each with its rupture record, estimate minimum
/// rates and apply the options.
///
/// Matching is by temperature and stress (exact values as parsed; `560` and `560.0` are the
/// same), and by specimen when both the curve and the record have one. A record with a
/// specimen equal to the curve's wins over a record without specimen; two equally good
/// records for one curve are an error. Records at a temperature that has no curve at all are
/// ignored silently where `opts` keeps one temperature (a lifetimes file may hold others), and
/// with one warning line for all of them where it keeps every temperature (life-only tests,
/// which are not fitted); records at a temperature with curves that match no curve give a
/// warning each. A test declared interrupted gets no
/// rupture time even if a record exists (the record is then ignored, with a warning).
pub fn load(curves: &Path, ruptures: &Path, opts: &LoadOptions) -> Result<Dataset> {
    let (raw, warnings) = read_curves(curves)?;
    let records = read_ruptures(ruptures)?;
    load_read(raw, warnings, records, curves, ruptures, opts)
}

/// [`load`] from the two files' contents in memory (CSV text, same format and rules) instead
/// of from files: what a caller that holds the tables itself (the Python package's
/// DataFrames) uses. `curves` and `ruptures` are the names that errors and warnings give for
/// the tables, with their lines counted as in a file (the header is line 1).
pub fn load_bytes(
    curves: &Path,
    curves_csv: &[u8],
    ruptures: &Path,
    ruptures_csv: &[u8],
    opts: &LoadOptions,
) -> Result<Dataset> {
    let (raw, warnings) = read_curves_from(curves, curves_csv, None)?;
    let records = read_ruptures_from(ruptures, ruptures_csv, None)?;
    load_read(raw, warnings, records, curves, ruptures, opts)
}

/// The part of [`load`] after both tables are read.
fn load_read(
    raw: Vec<RawCurve>,
    mut warnings: Vec<String>,
    records: Vec<RuptureRecord>,
    curves: &Path,
    ruptures: &Path,
    opts: &LoadOptions,
) -> Result<Dataset> {
    let raw: Vec<RawCurve> = match opts.temperature_c {
        Some(t) => raw
            .into_iter()
            .filter(|c| close(c.temperature_c, t))
            .collect(),
        None => raw,
    };
    if raw.is_empty() {
        let msg = match opts.temperature_c {
            Some(t) => format!("no curves at temperature_C = {t}"),
            None => "no curves".to_string(),
        };
        return Err(Error::data(curves, 0, msg));
    }
    if opts.temperature_c.is_none() && !opts.several_temperatures {
        check_one_temperature(&raw, curves)?;
    }
    let flags =
        interrupted_flags(&opts.interrupted, &raw, opts.temperature_c).map_err(|(k, m)| {
            let m = format!("interrupted[{k}] = {}: {m}", opts.interrupted[k].label());
            match &opts.interrupted_source {
                Some((path, line)) => Error::config_at(path, *line, m),
                None => Error::Invalid(m),
            }
        })?;
    let matched = raw
        .iter()
        .map(|c| match_record(c, &records, ruptures))
        .collect::<Result<Vec<Option<usize>>>>()?;
    // A test's rupture time bounds its readings' times (a record of a test declared
    // interrupted is ignored).
    let rupture_h: Vec<Option<f64>> = matched
        .iter()
        .zip(&flags)
        .map(|(m, &i)| m.filter(|_| !i).map(|k| records[k].rupture_time_h))
        .collect();
    let (raw, dropped) = handle_outliers(raw, curves, opts.outliers, &rupture_h, &mut warnings)?;

    let mut used = vec![false; records.len()];
    let mut out = Vec::with_capacity(raw.len());
    for ((c, interrupted), rec) in raw.into_iter().zip(flags).zip(matched) {
        warnings.extend(negative_strain_warning(&c, curves));
        if let Some(i) = rec {
            used[i] = true;
        }
        let rec = match (rec, interrupted) {
            (Some(i), true) => {
                warnings.push(format!(
                    "{}:{}: rupture record ignored: the test at {} °C, {} MPa{} is declared interrupted",
                    ruptures.display(),
                    records[i].line,
                    c.temperature_c,
                    c.stress_mpa,
                    specimen_suffix(&c.specimen)
                ));
                None
            }
            (Some(i), false) => Some(&records[i]),
            (None, true) => None,
            (None, false) => {
                return Err(Error::data(
                    curves,
                    c.first_line,
                    format!(
                    "curve at temperature_C = {}, stress_MPa = {}{} has no rupture record in {} \
                         (declare the test interrupted in the configuration if it did not rupture)",
                    c.temperature_c,
                    c.stress_mpa,
                    specimen_key(&c.specimen),
                    ruptures.display()
                ),
                ))
            }
        };
        out.push(finish_curve(c, rec, curves, ruptures, &mut warnings)?);
    }

    // Unused records at a temperature that has curves: life-only tests.
    let mut lives = Vec::new();
    for (r, u) in records.iter().zip(&used) {
        if !*u && out.iter().any(|c| c.temperature_c == r.temperature_c) {
            lives.push(r.clone());
            warnings.push(format!(
                "{}:{}: rupture record at {} °C, {} MPa{} matches no curve: a life-only test, not fitted (`holdout` predicts it where it leaves it out)",
                ruptures.display(),
                r.line,
                r.temperature_c,
                r.stress_mpa,
                specimen_suffix(&r.specimen)
            ));
        }
    }

    // Records at temperatures without curves: silent where the configuration keeps one
    // temperature (a lifetimes file may hold others), one line where it keeps them all: a
    // life-only test is not fitted, and its life is not in any output.
    if opts.temperature_c.is_none() {
        let lone: Vec<&RuptureRecord> = records
            .iter()
            .zip(&used)
            .filter(|(r, u)| !**u && !out.iter().any(|c| c.temperature_c == r.temperature_c))
            .map(|(r, _)| r)
            .collect();
        lives.extend(lone.iter().map(|r| (*r).clone()));
        if let Some(first) = lone.first() {
            let mut temps: Vec<f64> = lone.iter().map(|r| r.temperature_c).collect();
            temps.sort_by(f64::total_cmp);
            temps.dedup();
            let temps: Vec<String> = temps.iter().map(|t| format!("{t}")).collect();
            warnings.push(format!(
                "{}:{}: {} rupture record(s) at {} °C, where the curves file has no curve, not fitted (first on this line): creepfit fits tests with curves only; `holdout` predicts these lives where it leaves them out",
                ruptures.display(),
                first.line,
                lone.len(),
                temps.join(", ")
            ));
        }
    }

    let ruptured: Vec<&Curve> = out.iter().filter(|c| c.rupture_time_h.is_some()).collect();
    let top = ruptured
        .iter()
        .flat_map(|c| c.strains.iter().copied())
        .fold(f64::NEG_INFINITY, f64::max);
    if !ruptured.is_empty() && top < MIN_RUPTURED_STRAIN {
        warnings.push(format!(
            "{}: column 'strain_pct': every ruptured test's curve stays below {} % strain \
             (largest {} %): strain_pct is in percent (a strain of 5 % is 5, not 0.05)",
            curves.display(),
            pct(MIN_RUPTURED_STRAIN),
            pct(top)
        ));
    }

    out.sort_by(|a, b| {
        a.temperature_c
            .total_cmp(&b.temperature_c)
            .then(a.stress_mpa.total_cmp(&b.stress_mpa))
            .then_with(|| a.specimen.cmp(&b.specimen))
    });
    lives.sort_by_key(|r| r.line);
    Ok(Dataset {
        curves: out,
        warnings,
        dropped,
        lives,
    })
}

/// Apply `policy` to the gross outliers of the curves (`rupture_h`: each curve's rupture
/// time, if it has one): refuse (the first, by line), drop (each in a warning and in the
/// returned list; a curve left with too few points is an error) or keep (each in a warning).
fn handle_outliers(
    raw: Vec<RawCurve>,
    path: &Path,
    policy: OutlierPolicy,
    rupture_h: &[Option<f64>],
    warnings: &mut Vec<String>,
) -> Result<(Vec<RawCurve>, Vec<Outlier>)> {
    let found: Vec<Vec<(usize, Outlier)>> = raw
        .iter()
        .zip(rupture_h)
        .map(|(c, tr)| curve_outliers(c, path, *tr))
        .collect();
    if found.iter().all(Vec::is_empty) {
        return Ok((raw, Vec::new()));
    }
    let mut all: Vec<&Outlier> = found.iter().flatten().map(|(_, o)| o).collect();
    all.sort_by_key(|o| o.line);
    match policy {
        OutlierPolicy::Refuse => {
            let first = all[0];
            let more = if all.len() > 1 {
                format!(" ({} such points in all)", all.len())
            } else {
                String::new()
            };
            Err(Error::data(
                path,
                first.line,
                format!(
                    "{}{more}; fix the row, or set outliers = \"drop\" in the configuration to drop such points (listed as warnings and in manifest.json)",
                    first.what()
                ),
            ))
        }
        OutlierPolicy::Keep => {
            for o in all {
                warnings.push(format!(
                    "{}:{}: {}; kept (outliers = \"keep\")",
                    o.file,
                    o.line,
                    o.what()
                ));
            }
            Ok((raw, Vec::new()))
        }
        OutlierPolicy::Drop => {
            let mut dropped: Vec<Outlier> = Vec::new();
            let mut out = Vec::with_capacity(raw.len());
            for (mut c, f) in raw.into_iter().zip(found) {
                if !f.is_empty() {
                    let skip: std::collections::HashSet<usize> =
                        f.iter().map(|(k, _)| *k).collect();
                    let keep = |v: &[f64]| -> Vec<f64> {
                        v.iter()
                            .enumerate()
                            .filter(|(k, _)| !skip.contains(k))
                            .map(|(_, x)| *x)
                            .collect()
                    };
                    c.times_h = keep(&c.times_h);
                    c.strains = keep(&c.strains);
                    c.lines = c
                        .lines
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| !skip.contains(k))
                        .map(|(_, x)| *x)
                        .collect();
                    dropped.extend(f.into_iter().map(|(_, o)| o));
                    if c.times_h.len() < MIN_POINTS || c.times_h[0] == *c.times_h.last().unwrap() {
                        return Err(Error::data(
                            path,
                            c.first_line,
                            format!(
                                "the curve at {} °C, {} MPa has too few points left ({}) after its gross outliers were dropped",
                                c.temperature_c,
                                c.stress_mpa,
                                c.times_h.len()
                            ),
                        ));
                    }
                }
                out.push(c);
            }
            dropped.sort_by_key(|o| o.line);
            for o in &dropped {
                warnings.push(format!(
                    "{}:{}: {}; dropped (outliers = \"drop\")",
                    o.file,
                    o.line,
                    o.what()
                ));
            }
            Ok((out, dropped))
        }
    }
}

/// Curves at more than one temperature are an error naming them and the line where the
/// second one starts.
fn check_one_temperature(raw: &[RawCurve], path: &Path) -> Result<()> {
    let mut temps: Vec<f64> = raw.iter().map(|c| c.temperature_c).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup_by(|a, b| key_bits(*a) == key_bits(*b));
    if temps.len() < 2 {
        return Ok(());
    }
    let t0 = key_bits(raw[0].temperature_c);
    let second = raw
        .iter()
        .filter(|c| key_bits(c.temperature_c) != t0)
        .map(|c| c.first_line)
        .min()
        .unwrap_or(0);
    let list: Vec<String> = temps.iter().map(|t| t.to_string()).collect();
    Err(Error::data(
        path,
        second,
        format!(
            "column 'temperature_C': the curves are at {} temperatures ({} °C) and the \
             configuration has no temperature_C filter: one set of constants does not fit \
             several temperatures; set temperature_C = {} (say) in the configuration, or \
             give constants a temperature law for one calibration across them (e.g. law = \
             \"arrhenius\" on A and Kc, docs/TEMPERATURES.md)",
            temps.len(),
            list.join(", "),
            list[0]
        ),
    ))
}

/// Relative closeness for values typed by people (temperature filter, interrupted entries).
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

/// Index of the record for curve `c`, if any.
fn match_record(c: &RawCurve, records: &[RuptureRecord], ruptures: &Path) -> Result<Option<usize>> {
    // rank 2: same specimen; rank 1: one of the two has no specimen.
    let mut best: Option<(u8, usize)> = None;
    let mut tie: Option<usize> = None;
    for (i, r) in records.iter().enumerate() {
        if r.temperature_c != c.temperature_c || r.stress_mpa != c.stress_mpa {
            continue;
        }
        let rank = match (&c.specimen, &r.specimen) {
            (Some(a), Some(b)) if a == b => 2,
            (Some(_), Some(_)) => continue,
            _ => 1,
        };
        match best {
            Some((br, _)) if br > rank => {}
            Some((br, _)) if br == rank => tie = Some(i),
            _ => {
                best = Some((rank, i));
                tie = None;
            }
        }
    }
    if let (Some((_, i)), Some(j)) = (best, tie) {
        return Err(Error::data(
            ruptures,
            records[j].line,
            format!(
                "rupture records on lines {} and {} both match the curve at temperature_C = {}, \
                 stress_MPa = {}{}",
                records[i].line,
                records[j].line,
                c.temperature_c,
                c.stress_mpa,
                specimen_key(&c.specimen)
            ),
        ));
    }
    Ok(best.map(|(_, i)| i))
}

fn finish_curve(
    c: RawCurve,
    rec: Option<&RuptureRecord>,
    curves: &Path,
    ruptures: &Path,
    warnings: &mut Vec<String>,
) -> Result<Curve> {
    let t_last = *c
        .times_h
        .last()
        .expect("curves have at least MIN_POINTS points");
    // Largest strain among the points at the largest time.
    let last_strain = c
        .times_h
        .iter()
        .zip(&c.strains)
        .filter(|(t, _)| **t == t_last)
        .map(|(_, e)| *e)
        .fold(f64::NEG_INFINITY, f64::max);
    let rupture_time_h = rec.map(|r| r.rupture_time_h);
    if let Some(r) = rec {
        if r.rupture_time_h < t_last {
            warnings.push(format!(
                "{}:{}: rupture_time_h = {} is before the last measured time {} h of the curve \
                 at {} °C, {} MPa in {}",
                ruptures.display(),
                r.line,
                r.rupture_time_h,
                t_last,
                c.temperature_c,
                c.stress_mpa,
                curves.display()
            ));
        }
    }
    if let Some((r, er)) = rec.and_then(|r| r.rupture_strain.map(|e| (r, e))) {
        let top = c.strains.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if top > 0.0 && er < MIN_RUPTURE_STRAIN_OF_CURVE * top {
            return Err(Error::data(
                ruptures,
                r.line,
                format!(
                    "column 'rupture_strain_pct': {} % is {:.3} × the largest strain {} % that \
                     the curve at {} °C, {} MPa{} reached in {}: a strain at rupture is not below \
                     what the test reached (a fraction where percent is expected?)",
                    pct(er),
                    er / top,
                    pct(top),
                    c.temperature_c,
                    c.stress_mpa,
                    specimen_suffix(&c.specimen),
                    curves.display()
                ),
            ));
        }
    }
    if let Some(r) = rec {
        if t_last < MIN_LIFE_COVERED * r.rupture_time_h {
            warnings.push(format!(
                "{}:{}: column 'time_h': the curve at {} °C, {} MPa ends at {} h, {:.2e} × its \
                 rupture time {} h ({}:{}): are both files in hours?",
                curves.display(),
                c.first_line,
                c.temperature_c,
                c.stress_mpa,
                t_last,
                t_last / r.rupture_time_h,
                r.rupture_time_h,
                ruptures.display(),
                r.line
            ));
        }
    }
    let rupture_strain = rec.and_then(|r| r.rupture_strain).unwrap_or(last_strain);
    if !(rupture_strain > 0.0) {
        // Strain residuals are scaled by the rupture strain: it must be positive.
        return Err(Error::data(
            curves,
            c.first_line,
            format!(
                "column 'strain_pct': the curve at temperature_C = {}, stress_MPa = {}{} ends at \
                 strain {} %, not above zero: no creep to fit (or give rupture_strain_pct in {})",
                c.temperature_c,
                c.stress_mpa,
                specimen_key(&c.specimen),
                last_strain * 100.0,
                ruptures.display()
            ),
        ));
    }
    let life = rupture_time_h.unwrap_or(t_last);
    let min_rate_estimated = estimate_min_rate(&c.times_h, &c.strains, life);
    if min_rate_estimated.is_nan() || min_rate_estimated <= 0.0 {
        warnings.push(format!(
            "{}:{}: could not estimate a positive minimum creep rate for the curve at {} °C, {} MPa \
             (estimate {})",
            curves.display(),
            c.first_line,
            c.temperature_c,
            c.stress_mpa,
            min_rate_estimated
        ));
    }
    Ok(Curve {
        temperature_c: c.temperature_c,
        stress_mpa: c.stress_mpa,
        specimen: c.specimen,
        times_h: c.times_h,
        strains: c.strains,
        rupture_time_h,
        rupture_strain,
        min_rate_measured: rec.and_then(|r| r.min_rate),
        groups: None,
        min_rate_estimated,
    })
}

/// A cell read as a number: parsed, finite and in the allowed range.
struct Field<'a> {
    path: &'a Path,
    line: usize,
    rec: &'a csv::StringRecord,
}

#[derive(Clone, Copy, PartialEq)]
enum Range {
    Any,
    NonNegative,
    Positive,
    /// A test temperature: [`MIN_DATA_TEMPERATURE_C`] to [`MAX_DATA_TEMPERATURE_C`].
    Temperature,
}

impl Field<'_> {
    fn text(&self, col: usize) -> &str {
        self.rec.get(col).unwrap_or("")
    }

    /// `Ok(None)` for an empty cell.
    fn opt_num(&self, col: usize, name: &str, range: Range) -> Result<Option<f64>> {
        let text = self.text(col);
        if text.is_empty() {
            return Ok(None);
        }
        let v: f64 = text.parse().map_err(|_| {
            Error::data(
                self.path,
                self.line,
                format!("column '{name}': cannot parse '{text}' as a number"),
            )
        })?;
        if !v.is_finite() {
            return Err(Error::data(
                self.path,
                self.line,
                format!("column '{name}': '{text}' is not a finite number"),
            ));
        }
        let bad = match range {
            Range::Any => None,
            Range::NonNegative if v < 0.0 => Some("must not be negative".to_string()),
            Range::Positive if v <= 0.0 => Some("must be positive".to_string()),
            Range::Temperature if v < -ZERO_CELSIUS_K => {
                Some("is below absolute zero (-273.15 °C)".to_string())
            }
            Range::Temperature if !(MIN_DATA_TEMPERATURE_C..=MAX_DATA_TEMPERATURE_C).contains(&v) => {
                Some(format!(
                    "a creep test temperature must lie between {MIN_DATA_TEMPERATURE_C} and {MAX_DATA_TEMPERATURE_C} °C (a typo, or kelvin?)"
                ))
            }
            _ => None,
        };
        if let Some(why) = bad {
            return Err(Error::data(
                self.path,
                self.line,
                format!("column '{name}': {why} (got {text})"),
            ));
        }
        Ok(Some(v))
    }

    fn num(&self, col: usize, name: &str, range: Range) -> Result<f64> {
        self.opt_num(col, name, range)?.ok_or_else(|| {
            Error::data(
                self.path,
                self.line,
                format!("column '{name}': empty cell, a number is required"),
            )
        })
    }

    fn opt_text(&self, col: Option<usize>) -> Option<String> {
        col.map(|c| self.text(c))
            .filter(|s| !s.is_empty())
            .map(str::to_string)
    }
}

/// Read the curves file: rows grouped into curves by (temperature, stress[, specimen]) in
/// order of first appearance, each sorted by time (stable), exact duplicate points (same
/// time and same strain) dropped with one warning for the file. Strain is converted to a
/// fraction. Time and memory are linear in the file (plus the O(n log n) sort).
///
/// Negative strains are measurements (an extensometer zero offset, say): kept ([`load`]
/// warns once per curve it keeps).
///
/// Errors: missing file or column, unparsable or non-finite number, negative time,
/// non-positive stress, a curve with fewer than [`MIN_POINTS`] points or with all its times
/// equal, and two specimens mixed in one curve. Rows of one curve may be out of time order
/// locally (digitised tables are), but a curve without specimen whose rows restart in time
/// (a row at or below the curve's first time after larger times), or whose rows come back
/// after rows of other curves at a time below the largest already reached, holds two
/// specimens: the error names both line ranges and asks for a `specimen` column.
pub fn read_curves(path: &Path) -> Result<(Vec<RawCurve>, Vec<String>)> {
    let (bytes, progress) = table::read_file(path)?;
    read_curves_from(path, &bytes, progress)
}

/// [`read_curves`] of the file's bytes, named `path` in errors.
fn read_curves_from(
    path: &Path,
    bytes: &[u8],
    progress: Option<indicatif::ProgressBar>,
) -> Result<(Vec<RawCurve>, Vec<String>)> {
    let mut table = Table::open(path, bytes, CURVE_COLUMNS, progress)?;
    let ct = table.col("temperature_C").unwrap();
    let cs = table.col("stress_MPa").unwrap();
    let cti = table.col("time_h").unwrap();
    let ce = table.col("strain_pct").unwrap();
    let csp = table.col("specimen");

    let mut curves: Vec<RawCurve> = Vec::new();
    let mut tracks: Vec<Track> = Vec::new();
    let mut index: HashMap<(u64, u64, Option<String>), usize> = HashMap::new();
    let mut prev: Option<usize> = None;
    let mut rec = csv::StringRecord::new();
    while let Some(line) = table.next_row(&mut rec)? {
        let f = Field {
            path,
            line,
            rec: &rec,
        };
        let t = f.num(ct, "temperature_C", Range::Temperature)?;
        let s = f.num(cs, "stress_MPa", Range::Positive)?;
        let time = f.num(cti, "time_h", Range::NonNegative)?;
        let e = f.num(ce, "strain_pct", Range::Any)?;
        let sp = csp.map(|c| f.text(c)).filter(|s| !s.is_empty());
        // Rows of one curve usually come together: try the previous row's curve first.
        let k = match prev {
            Some(p)
                if key_bits(curves[p].temperature_c) == key_bits(t)
                    && key_bits(curves[p].stress_mpa) == key_bits(s)
                    && curves[p].specimen.as_deref() == sp =>
            {
                p
            }
            _ => {
                let key = (key_bits(t), key_bits(s), sp.map(str::to_string));
                *index.entry(key).or_insert_with(|| {
                    curves.push(RawCurve {
                        temperature_c: t,
                        stress_mpa: s,
                        specimen: sp.map(str::to_string),
                        times_h: Vec::new(),
                        strains: Vec::new(),
                        lines: Vec::new(),
                        first_line: line,
                    });
                    tracks.push(Track {
                        first_time: time,
                        max_time: time,
                        max_line: line,
                        last_line: line,
                        last_time: time,
                        descents: 0,
                        split: None,
                    });
                    curves.len() - 1
                })
            }
        };
        let tr = &mut tracks[k];
        if !curves[k].times_h.is_empty() && time < tr.last_time {
            tr.descents += 1;
        }
        if tr.split.is_none() && curves[k].specimen.is_none() && !curves[k].times_h.is_empty() {
            let new_block = prev != Some(k);
            if time <= tr.first_time && tr.max_time > tr.first_time {
                tr.split = Some(Split {
                    curve: k,
                    line,
                    before_last: tr.last_line,
                    why: format!(
                        "time_h goes back to {time} h, at or below the curve's first time \
                         {} h, after {} h on line {}",
                        tr.first_time, tr.max_time, tr.max_line
                    ),
                });
            } else if new_block && time < tr.max_time {
                tr.split = Some(Split {
                    curve: k,
                    line,
                    before_last: tr.last_line,
                    why: format!(
                        "after rows of other curves its rows resume at {time} h, before the \
                         {} h already reached on line {}",
                        tr.max_time, tr.max_line
                    ),
                });
            }
        }
        if time > tr.max_time {
            tr.max_time = time;
            tr.max_line = line;
        }
        tr.last_line = line;
        tr.last_time = time;
        let c = &mut curves[k];
        c.times_h.push(time);
        c.strains.push(e / 100.0);
        c.lines.push(line);
        prev = Some(k);
    }
    drop(table);
    if curves.is_empty() {
        return Err(Error::data(path, 0, "no data rows"));
    }
    // A restart means two specimens only where the curve's rows are otherwise in time order
    // (appended one after the other); rows in no order at all (a shuffled table: "times need
    // not be sorted") cannot be told apart and load as one curve.
    let split = tracks
        .iter()
        .zip(&curves)
        .filter(|(tr, c)| tr.descents <= (c.times_h.len() / 10).max(3))
        .filter_map(|(tr, _)| tr.split.as_ref())
        .min_by_key(|sp| sp.line);
    if let Some(sp) = split {
        let c = &curves[sp.curve];
        return Err(Error::data(
            path,
            sp.line,
            format!(
                "column 'time_h': the rows at temperature_C = {}, stress_MPa = {} look like two \
                 specimens in one curve, lines {}–{} and {}–{} ({}); add a 'specimen' column \
                 (or fill its empty cells) to tell them apart",
                c.temperature_c,
                c.stress_mpa,
                c.first_line,
                sp.before_last,
                sp.line,
                tracks[sp.curve].last_line,
                sp.why
            ),
        ));
    }

    let mut dups = Duplicates::default();
    let mut warnings = Vec::new();
    // Tests (temperature, stress) with a labelled specimen: an unlabelled curve among them is
    // likely rows whose 'specimen' cell was left empty.
    let labelled: Vec<(f64, f64)> = curves
        .iter()
        .filter(|c| c.specimen.is_some())
        .map(|c| (c.temperature_c, c.stress_mpa))
        .collect();
    for c in &mut curves {
        sort_and_dedup(c, &mut dups);
        let what = || {
            format!(
                "curve at temperature_C = {}, stress_MPa = {}{}",
                c.temperature_c,
                c.stress_mpa,
                specimen_key(&c.specimen)
            )
        };
        let n = c.times_h.len();
        if n < MIN_POINTS {
            let empty_cell =
                c.specimen.is_none() && labelled.contains(&(c.temperature_c, c.stress_mpa));
            return Err(Error::data(
                path,
                c.first_line,
                format!(
                    "{} has {n} distinct point(s); at least {MIN_POINTS} are needed{}",
                    what(),
                    if empty_cell {
                        " (its rows have an empty 'specimen' cell, while other rows of this \
                         temperature and stress name a specimen: fill the cell)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if c.times_h[0] == c.times_h[n - 1] {
            return Err(Error::data(
                path,
                c.first_line,
                format!(
                    "column 'time_h': the {} has all its {n} points at time_h = {}: no time \
                     span to fit",
                    what(),
                    c.times_h[0]
                ),
            ));
        }
    }
    if let Some((line, of, time, strain)) = dups.first {
        let more = if dups.count > 1 {
            format!(
                " (and {} more exact duplicate(s), {} in all, in {} curve(s))",
                dups.count - 1,
                dups.count,
                dups.curves
            )
        } else {
            String::new()
        };
        warnings.insert(
            0,
            format!(
                "{}:{line}: duplicate point (time_h = {time}, strain_pct = {}) of line {of} \
                 dropped{more}",
                path.display(),
                pct(strain)
            ),
        );
    }
    Ok((curves, warnings))
}

/// One warning for a curve's negative strains (count, most negative value, first line), if
/// it has any: they are measurements (an extensometer zero offset, say), not errors.
fn negative_strain_warning(c: &RawCurve, path: &Path) -> Option<String> {
    let (mut count, mut lowest, mut first) = (0usize, 0.0f64, usize::MAX);
    for (e, l) in c.strains.iter().zip(&c.lines) {
        if *e < 0.0 {
            count += 1;
            lowest = lowest.min(*e);
            first = first.min(*l);
        }
    }
    (count > 0).then(|| {
        format!(
            "{}:{first}: column 'strain_pct': {count} negative strain(s) in the curve at {} °C, \
             {} MPa{}, down to {} % (first on this line); kept as measured (e.g. an \
             extensometer zero offset)",
            path.display(),
            c.temperature_c,
            c.stress_mpa,
            specimen_suffix(&c.specimen),
            pct(lowest)
        )
    })
}

/// A strain fraction as percent text without binary noise (0.00155 → "0.155").
fn pct(strain: f64) -> f64 {
    (strain * 100.0 * 1e9).round() / 1e9
}

/// What [`read_curves`] tracks per curve while reading, to tell two specimens apart.
struct Track {
    /// Time of the curve's first row, h.
    first_time: f64,
    /// Largest time so far, h, and its line.
    max_time: f64,
    max_line: usize,
    /// Line of the curve's latest row.
    last_line: usize,
    /// Time of the curve's latest row, h.
    last_time: f64,
    /// Rows whose time is below the curve's previous row's (in file order).
    descents: usize,
    /// The first place where the rows look like two specimens, if any.
    split: Option<Split>,
}

/// The first place where a curve's rows look like two specimens.
struct Split {
    curve: usize,
    /// Line of the row that starts the second specimen.
    line: usize,
    /// Line of the curve's last row before it.
    before_last: usize,
    why: String,
}

/// Exact duplicate points dropped over a file.
#[derive(Default)]
struct Duplicates {
    count: usize,
    curves: usize,
    /// The first dropped row (file line, line it repeats, time, strain).
    first: Option<(usize, usize, f64, f64)>,
}

/// Bits of a key value with -0.0 folded onto 0.0, so that equal numbers group together.
fn key_bits(v: f64) -> u64 {
    if v == 0.0 {
        0.0f64.to_bits()
    } else {
        v.to_bits()
    }
}

/// Sort a curve's points by time (stable: equal times keep their file order) and drop exact
/// duplicates (same time and strain as an earlier kept point). O(n log n); a run of equal
/// times is checked through a hash set, so long runs stay linear.
fn sort_and_dedup(c: &mut RawCurve, dups: &mut Duplicates) {
    let n = c.times_h.len();
    let mut idx: Vec<u32> = (0..n as u32).collect();
    idx.sort_by(|&a, &b| c.times_h[a as usize].total_cmp(&c.times_h[b as usize])); // stable
    let (mut t, mut e, mut l) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    let mut run_start = 0; // first kept point with the current time
    let mut seen: HashMap<u64, usize> = HashMap::new(); // strain bits → kept index, long runs
    let mut dropped = 0;
    for &i in &idx {
        let i = i as usize;
        let (ti, ei, li) = (c.times_h[i], c.strains[i], c.lines[i]);
        if t.last() != Some(&ti) {
            run_start = t.len();
            seen.clear();
        }
        let run = t.len() - run_start;
        let earlier = if run < 16 {
            (run_start..t.len()).find(|&k| e[k] == ei)
        } else {
            if seen.is_empty() {
                for k in run_start..t.len() {
                    seen.entry(key_bits(e[k])).or_insert(k);
                }
            }
            seen.get(&key_bits(ei)).copied()
        };
        if let Some(k) = earlier {
            dropped += 1;
            dups.count += 1;
            match dups.first {
                Some((fl, ..)) if fl <= li => {}
                _ => dups.first = Some((li, l[k], ti, ei)),
            }
            continue;
        }
        if run >= 16 {
            seen.insert(key_bits(ei), t.len());
        }
        t.push(ti);
        e.push(ei);
        l.push(li);
    }
    if dropped > 0 {
        dups.curves += 1;
    }
    c.times_h = t;
    c.strains = e;
    c.lines = l;
}

/// Read the ruptures file. Rupture strain (percent) and minimum rate (percent per hour) are
/// optional columns, and empty cells mean "not given"; both are converted to fractions.
///
/// Errors: missing file or column, unparsable or non-finite number, non-positive stress or
/// rupture time, non-positive rupture strain or minimum rate when given.
pub fn read_ruptures(path: &Path) -> Result<Vec<RuptureRecord>> {
    let (bytes, progress) = table::read_file(path)?;
    read_ruptures_from(path, &bytes, progress)
}

/// [`read_ruptures`] of a table's CSV text in memory, named `path` in errors (the Python
/// package's DataFrames).
pub fn read_ruptures_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<RuptureRecord>> {
    read_ruptures_from(path, bytes, None)
}

/// [`read_ruptures`] of the file's bytes, named `path` in errors.
fn read_ruptures_from(
    path: &Path,
    bytes: &[u8],
    progress: Option<indicatif::ProgressBar>,
) -> Result<Vec<RuptureRecord>> {
    let mut table = Table::open(path, bytes, RUPTURE_COLUMNS, progress)?;
    let ct = table.col("temperature_C").unwrap();
    let cs = table.col("stress_MPa").unwrap();
    let ctf = table.col("rupture_time_h").unwrap();
    let cef = table.col("rupture_strain_pct");
    let cmr = table.col("min_rate_pct_per_h");
    let csp = table.col("specimen");
    let mut out = Vec::new();
    let mut rec = csv::StringRecord::new();
    while let Some(line) = table.next_row(&mut rec)? {
        let f = Field {
            path,
            line,
            rec: &rec,
        };
        let rupture_strain = match cef {
            Some(c) => f.opt_num(c, "rupture_strain_pct", Range::Positive)?,
            None => None,
        };
        let min_rate = match cmr {
            Some(c) => f.opt_num(c, "min_rate_pct_per_h", Range::Positive)?,
            None => None,
        };
        out.push(RuptureRecord {
            temperature_c: f.num(ct, "temperature_C", Range::Temperature)?,
            stress_mpa: f.num(cs, "stress_MPa", Range::Positive)?,
            rupture_time_h: f.num(ctf, "rupture_time_h", Range::Positive)?,
            rupture_strain: rupture_strain.map(|v| v / 100.0),
            min_rate: min_rate.map(|v| v / 100.0),
            specimen: f.opt_text(csp),
            line,
        });
    }
    Ok(out)
}

/// One condition to predict: temperature (°C) and stress (MPa).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    /// Test temperature, °C.
    #[serde(rename = "temperature_C")]
    pub temperature_c: f64,
    /// Nominal stress, MPa.
    #[serde(rename = "stress_MPa")]
    pub stress_mpa: f64,
}

impl Condition {
    /// Parse `T:σ` (°C and MPa), e.g. `575:100`.
    pub fn parse(s: &str) -> std::result::Result<Condition, String> {
        let (t, sig) = s
            .trim()
            .split_once(':')
            .ok_or_else(|| format!("'{s}': expected T:stress (°C:MPa), e.g. 575:100"))?;
        let t: f64 = t
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the temperature '{}'", t.trim()))?;
        let sig: f64 = sig
            .trim()
            .parse()
            .map_err(|_| format!("'{s}': cannot parse the stress '{}'", sig.trim()))?;
        if !(t.is_finite() && t > -ZERO_CELSIUS_K) {
            return Err(format!(
                "'{s}': the temperature must be above absolute zero (°C)"
            ));
        }
        if !(sig.is_finite() && sig > 0.0) {
            return Err(format!("'{s}': the stress must be positive (MPa)"));
        }
        Ok(Condition {
            temperature_c: t,
            stress_mpa: sig,
        })
    }

    /// Parse a comma-separated list `T:σ[,T:σ…]`.
    pub fn parse_list(s: &str) -> std::result::Result<Vec<Condition>, String> {
        s.split(',')
            .filter(|p| !p.trim().is_empty())
            .map(Condition::parse)
            .collect()
    }

    /// `575 °C, 100 MPa`.
    pub fn label(&self) -> String {
        format!("{} °C, {} MPa", self.temperature_c, self.stress_mpa)
    }
}

/// `c` with at most `max_points` points: the first point as it is, the others in
/// `max_points − 1` groups (fewer where that would leave a group under 4 points) of consecutive
/// points whose sizes differ by at most one, each group
/// replaced by one point at its mean time t̄ whose strain is the value at t̄ of a
/// least-squares quadratic through the group's points (the group's mean for fewer than 4
/// points or no time spread). The quadratic matters where the curve bends: the plain mean of a
/// group's strains exceeds the curve at t̄ by ε''·var(t)/2, which near rupture is larger than
/// the reading error of a logged curve and would read as misfit; the local quadratic's value
/// at t̄ is unbiased for a quadratic (and, for a symmetric group, a cubic) curve and still
/// averages the reading error over the group.
pub fn binned(c: &Curve, max_points: usize) -> Curve {
    let n = c.times_h.len();
    if n <= max_points || max_points < 2 {
        return c.clone();
    }
    let mut times = vec![c.times_h[0]];
    let mut strains = vec![c.strains[0]];
    for (lo, hi) in group_bounds(n, max_points) {
        let (t, e) = (&c.times_h[lo..hi], &c.strains[lo..hi]);
        let tm = t.iter().sum::<f64>() / t.len() as f64;
        times.push(tm);
        strains.push(local_quadratic_at_mean(t, e, tm));
    }
    Curve {
        times_h: times,
        strains,
        groups: None,
        ..c.clone()
    }
}

/// The groups a curve of `n` readings longer than `max_points` is reduced to: the first
/// reading alone (not listed), the others in `max_points − 1` runs of consecutive readings
/// (fewer where that would leave a run under 4) whose sizes differ by at most one, as
/// (first, one past the last). At least 4 a group: the local quadratic needs them, and the
/// plain mean a smaller group falls back to is biased where the curve bends (a 3-point mean
/// in the first hours of a logged primary stage is off by more than its reading error).
fn group_bounds(n: usize, max_points: usize) -> impl Iterator<Item = (usize, usize)> {
    let groups = (max_points - 1).min((n - 1) / 4).max(1);
    (0..groups).map(move |g| (1 + g * (n - 1) / groups, 1 + (g + 1) * (n - 1) / groups))
}

/// How a curve longer than `max_points` is reduced ([`reduce`]).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Reduction {
    /// Each group's local least-squares quadratic at its mean time (`binned`).
    #[default]
    LocalQuadratic,
    /// Each group's mean, the model averaged over the same readings (`reduced_to_means`).
    Means,
    /// The same over groups that span equal strain ranges, not equal counts
    /// (`reduced_to_strain_means`), each point weighed by its group's size.
    StrainMeans,
}

impl Reduction {
    /// Whether this is the default (left out of written configurations).
    pub fn is_default(&self) -> bool {
        *self == Reduction::default()
    }

    /// The configuration's name of it.
    pub fn as_str(&self) -> &'static str {
        match self {
            Reduction::LocalQuadratic => "local_quadratic",
            Reduction::Means => "means",
            Reduction::StrainMeans => "strain_means",
        }
    }
}

/// How `diagnose` weighs the group means of [`Reduction::StrainMeans`]
/// ([`ReadingGroups::misfit_share`]).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum MisfitShare {
    /// ρ = 0: a mean of m readings has 1/m of a reading's error variance (weight √m), exact
    /// for white reading error. The default: its null battery is calibrated (the must-show's
    /// 200 sets, 5 false alarms).
    #[default]
    White,
    /// ρ estimated from the base model's fit and held for the whole diagnosis (weights
    /// 1/√((1 − ρ)/m + ρ)). Experimental: 6 false alarms on 33 null sets (session 75).
    Estimate,
}

impl MisfitShare {
    /// Whether this is the default (left out of written configurations).
    pub fn is_default(&self) -> bool {
        *self == MisfitShare::default()
    }

    /// The configuration's name of it.
    pub fn as_str(&self) -> &'static str {
        match self {
            MisfitShare::White => "white",
            MisfitShare::Estimate => "estimate",
        }
    }

    /// Whether `diagnose` estimates ρ for curves reduced by `reduction`: only with
    /// `estimate`, only for `strain_means` (equal-count groups are all of one size, so ρ
    /// only scales the reading error), and only where some curve was grouped.
    pub fn estimated(self, reduction: Reduction, any_grouped: bool) -> bool {
        self == MisfitShare::Estimate && reduction == Reduction::StrainMeans && any_grouped
    }
}

/// The groups a curve of readings `strains` (in time order) longer than `max_points` is
/// reduced to by [`Reduction::StrainMeans`]: the first reading alone (not listed), the others
/// in runs of consecutive readings whose strains span at most a common range s, the smallest
/// s that gives at most `max_points − 1` runs (greedy runs, s by bisection), as (first, one
/// past the last). Where the strain moves fast for its reading error (the primary stage's
/// first hours, the tertiary stage) a run is one reading or a few; along a slow secondary
/// stage it is long. Equal-count runs (`reduction = "means"`) average the tertiary stage's few
/// readings into a handful of points and lose the shape between them: on a generated set
/// with a hidden constant load (182012), the ratio that names it falls from 68 on every
/// reading to 31 on equal-count means of 4–5 readings.
pub fn strain_group_bounds(raw: &[f64], max_points: usize) -> Vec<(usize, usize)> {
    let n = raw.len();
    if n < 2 {
        return vec![];
    }
    let strains = smoothed_rise(raw, strain_window(n, max_points));
    let budget = max_points.saturating_sub(1).max(1);
    // Greedy runs of span at most `s` (inclusive), starting at reading 1.
    let runs = |s: f64, out: Option<&mut Vec<(usize, usize)>>| -> usize {
        let mut count = 0;
        let mut out = out;
        let mut i = 1;
        while i < n {
            let (mut lo, mut hi) = (strains[i], strains[i]);
            let mut j = i + 1;
            while j < n {
                let (l, h) = (lo.min(strains[j]), hi.max(strains[j]));
                if !(h - l <= s) {
                    break;
                }
                (lo, hi) = (l, h);
                j += 1;
            }
            if let Some(o) = out.as_deref_mut() {
                o.push((i, j));
            }
            count += 1;
            i = j;
        }
        count
    };
    let (lo_all, hi_all) = strains[1..]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let range = hi_all - lo_all;
    let mut out = Vec::with_capacity(budget);
    if !(range.is_finite() && range > 0.0) {
        // A flat curve (or non-finite strains): equal-count runs.
        out.extend(group_bounds(n, max_points));
        return out;
    }
    // runs(range) = 1 ≤ budget; runs is non-increasing in s (a greedy run at a larger span
    // reaches at least as far).
    let (mut a, mut b) = (0.0, range);
    for _ in 0..200 {
        let mid = 0.5 * (a + b);
        if runs(mid, None) <= budget {
            b = mid;
        } else {
            a = mid;
        }
        if b - a <= 1e-12 * range {
            break;
        }
    }
    runs(b, Some(&mut out));
    out
}

/// Half-width k of [`smoothed_rise`]'s window for `n` readings reduced to `max_points`: the
/// mean group size, at least 8 and at most 25 readings. Measured on noisy copies of the
/// seed's 590 °C curves reduced to 12 points (`tests/reduction.rs`), the means' variance in
/// a reading's units: 1.40 on the raw readings, 0.929 on a moving mean of 5, 0.967 on the
/// line at k = 4 (6,600 values each), 0.984 and 0.996 at k = 8 (6,600 and 33,000 values).
/// A wide window misplaces boundaries where the curve bends within it (the primary stage's
/// first readings), which costs information there but biases no mean.
fn strain_window(n: usize, max_points: usize) -> usize {
    (n / max_points.max(1)).clamp(8, 25)
}

/// The strain's rise as the groups of [`strain_group_bounds`] see it: at each reading the
/// value there of the least-squares line (in reading index) through the `2k + 1` readings
/// about it (one-sided at the ends, where a moving mean would lag behind the tertiary
/// stage's rise), then the running maximum. Groups drawn on the readings themselves end
/// where one reading's error reaches past the span, so their means are biased by the very
/// readings that ended them (measured on noisy copies of the seed's 590 °C curves: the
/// residuals at the true constants had 1.40 times a reading's variance; `tests/reduction.rs`);
/// on the smoothed, monotone rise one reading moves a boundary by a fraction of its error.
fn smoothed_rise(strains: &[f64], k: usize) -> Vec<f64> {
    let n = strains.len();
    // Prefix sums of 1, j, j², v, j·v.
    let mut p = vec![[0.0f64; 5]; n + 1];
    for (j, v) in strains.iter().enumerate() {
        let x = j as f64;
        let q = p[j];
        p[j + 1] = [q[0] + 1.0, q[1] + x, q[2] + x * x, q[3] + v, q[4] + x * v];
    }
    let mut top = f64::NEG_INFINITY;
    (0..n)
        .map(|i| {
            let (lo, hi) = if i < k {
                (0, (2 * k + 1).min(n))
            } else if i + k + 1 > n {
                (n.saturating_sub(2 * k + 1), n)
            } else {
                (i - k, i + k + 1)
            };
            let d: [f64; 5] = std::array::from_fn(|c| p[hi][c] - p[lo][c]);
            let [s0, s1, s2, sv, sxv] = d;
            let det = s0 * s2 - s1 * s1;
            let value = if det > 0.0 {
                let b = (s0 * sxv - s1 * sv) / det;
                let a = (sv - b * s1) / s0;
                a + b * i as f64
            } else {
                sv / s0
            };
            top = top.max(value);
            top
        })
        .collect()
}

/// `c` with at most `max_points` points, reduced as `how` says.
pub fn reduce(c: &Curve, max_points: usize, how: Reduction) -> Curve {
    match how {
        Reduction::LocalQuadratic => binned(c, max_points),
        Reduction::Means => reduced_to_means(c, max_points),
        Reduction::StrainMeans => reduced_to_strain_means(c, max_points),
    }
}

/// `c` with at most `max_points` points as [`binned`] groups them, each point the plain mean
/// of its group's readings at the group's mean time, the readings' times kept
/// ([`Curve::groups`]): the model is then compared through its own mean over the same
/// times, so the point has a mean's reading error (1/m of a reading's variance, where the
/// local quadratic's value has about 2.25/m) and no bias where the curve bends.
pub fn reduced_to_means(c: &Curve, max_points: usize) -> Curve {
    let n = c.times_h.len();
    if n <= max_points || max_points < 2 || c.groups.is_some() {
        return c.clone();
    }
    means_over(c, group_bounds(n, max_points))
}

/// `c` with at most `max_points` points as [`strain_group_bounds`] groups them, each point
/// the plain mean of its group's readings, as [`reduced_to_means`]; the groups differ in size,
/// and every fit weighs a point by its size ([`Curve::to_reading_units`]).
pub fn reduced_to_strain_means(c: &Curve, max_points: usize) -> Curve {
    let n = c.times_h.len();
    if n <= max_points || max_points < 2 || c.groups.is_some() {
        return c.clone();
    }
    means_over(c, strain_group_bounds(&c.strains, max_points))
}

/// `c`'s first reading and the plain means of the runs `bounds` of its other readings, the
/// readings' times kept ([`Curve::groups`]).
fn means_over(c: &Curve, bounds: impl IntoIterator<Item = (usize, usize)>) -> Curve {
    let mut times = vec![c.times_h[0]];
    let mut strains = vec![c.strains[0]];
    let mut ends = vec![1];
    for (lo, hi) in bounds {
        let m = (hi - lo) as f64;
        times.push(c.times_h[lo..hi].iter().sum::<f64>() / m);
        strains.push(c.strains[lo..hi].iter().sum::<f64>() / m);
        ends.push(hi);
    }
    Curve {
        times_h: times,
        strains,
        groups: Some(std::sync::Arc::new(ReadingGroups {
            times_h: c.times_h.clone(),
            ends,
            misfit_share: 0.0,
        })),
        ..c.clone()
    }
}

/// Value at `tm` (the mean of `t`) of the least-squares quadratic through (t, e); the mean of
/// `e` when there are fewer than 4 points or the quadratic is degenerate.
fn local_quadratic_at_mean(t: &[f64], e: &[f64], tm: f64) -> f64 {
    let m = t.len();
    let mean = e.iter().sum::<f64>() / m as f64;
    if m < 4 {
        return mean;
    }
    // Centred, scaled abscissa x = (t − t̄)/s; fit e = a + b x + c x².
    let s = t.iter().map(|v| (v - tm).abs()).fold(0.0, f64::max);
    if !(s > 0.0) {
        return mean;
    }
    let (mut s0, mut s1, mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut r0, mut r1, mut r2) = (0.0, 0.0, 0.0);
    for (ti, ei) in t.iter().zip(e) {
        let x = (ti - tm) / s;
        let x2 = x * x;
        s0 += 1.0;
        s1 += x;
        s2 += x2;
        s3 += x2 * x;
        s4 += x2 * x2;
        r0 += ei;
        r1 += x * ei;
        r2 += x2 * ei;
    }
    let a = nalgebra::Matrix3::new(s0, s1, s2, s1, s2, s3, s2, s3, s4);
    match a.lu().solve(&nalgebra::Vector3::new(r0, r1, r2)) {
        Some(c) if c[0].is_finite() => c[0],
        _ => mean,
    }
}

/// Content hash of loaded data (16 hex digits): every curve's temperature, stress, specimen,
/// times and strains, rupture record and the minimum rates the run uses, bit for bit, in
/// order. O(n) in the points, no copy of the data.
pub fn data_hash(data: &Dataset) -> String {
    let mut h = crate::identity::fnv1a(b"creepfit-data-v1");
    let f = |x: f64, h: &mut u64| *h = crate::identity::fnv1a_from(*h, &x.to_bits().to_le_bytes());
    let opt = |x: Option<f64>| x.unwrap_or(f64::NAN);
    for c in &data.curves {
        h = crate::identity::fnv1a_from(h, &(c.times_h.len() as u64).to_le_bytes());
        f(c.temperature_c, &mut h);
        f(c.stress_mpa, &mut h);
        match &c.specimen {
            Some(s) => {
                h = crate::identity::fnv1a_from(h, &(s.len() as u64 + 1).to_le_bytes());
                h = crate::identity::fnv1a_from(h, s.as_bytes());
            }
            None => h = crate::identity::fnv1a_from(h, &0u64.to_le_bytes()),
        }
        for (t, e) in c.times_h.iter().zip(&c.strains) {
            f(*t, &mut h);
            f(*e, &mut h);
        }
        f(opt(c.rupture_time_h), &mut h);
        f(c.rupture_strain, &mut h);
        f(opt(c.min_rate_measured), &mut h);
        f(c.min_rate_estimated, &mut h);
    }
    format!("{h:016x}")
}

/// Record in the run's manifest the data points the loader dropped (`outliers = "drop"`) and
/// its warnings (`data_warnings`: a rupture time before the curve's last reading, negative
/// strains kept, repeated points — printed on stderr too), so that the folder says on what
/// data its numbers stand.
pub fn note_data(folder: &mut crate::output::RunFolder, data: &Dataset) {
    if !data.warnings.is_empty() {
        folder.note("data_warnings", serde_json::json!(data.warnings));
    }
    if !data.dropped.is_empty() {
        folder.note(
            "dropped_points",
            serde_json::to_value(&data.dropped).expect("JSON of plain values"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the reduction keeps of the reading error's averaging: on pure white noise of sd σ
    /// in groups of 4 equally spaced readings, a reduced point's variance is the least-squares
    /// quadratic's intercept variance e₀ᵀ(XᵀX)⁻¹e₀ σ² = 41/64 σ² (x = ±1/3, ±1), where the
    /// group's mean would have σ²/4: the reduced curve holds 0.25/0.64 = 39 % of the readings'
    /// information about a smooth model (docs/SPECIMENS.md, "Session 71").
    /// `diagnose` estimates the misfit share only when asked, only for `strain_means` and only
    /// where a curve was grouped; every other case keeps √m (ρ = 0).
    #[test]
    fn the_misfit_share_is_estimated_only_when_asked_for_strain_means() {
        use MisfitShare::{Estimate, White};
        use Reduction::{LocalQuadratic, Means, StrainMeans};
        let table = [
            (White, StrainMeans, true, false),
            (White, StrainMeans, false, false),
            (White, Means, true, false),
            (Estimate, StrainMeans, true, true),
            (Estimate, StrainMeans, false, false),
            (Estimate, Means, true, false),
            (Estimate, LocalQuadratic, true, false),
        ];
        for (how, reduction, grouped, want) in table {
            assert_eq!(
                how.estimated(reduction, grouped),
                want,
                "{how:?} {reduction:?} grouped {grouped}"
            );
        }
        assert!(White.is_default() && !Estimate.is_default());
        assert_eq!((White.as_str(), Estimate.as_str()), ("white", "estimate"));
    }

    #[test]
    fn a_reduced_point_has_the_local_quadratics_variance() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let groups = 99;
        let n = 1 + 4 * groups;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(216_101);
        // The variance of the reduced points (the first, kept as it is, left out) over 200
        // curves of white noise: 19,800 values, the estimate's relative sd √(2/19,800) = 1 %.
        let mut variance = |reduce: &dyn Fn(&Curve) -> Curve| {
            let (mut sum2, mut count) = (0.0, 0usize);
            for _ in 0..200 {
                let c = Curve {
                    temperature_c: 600.0,
                    stress_mpa: 100.0,
                    specimen: None,
                    times_h: (0..n).map(|k| k as f64).collect(),
                    strains: (0..n).map(|_| StandardNormal.sample(&mut rng)).collect(),
                    rupture_time_h: None,
                    rupture_strain: 1.0,
                    min_rate_measured: None,
                    groups: None,
                    min_rate_estimated: 1e-3,
                };
                let b = reduce(&c);
                assert_eq!(b.strains.len(), groups + 1);
                for v in &b.strains[1..] {
                    sum2 += v * v;
                    count += 1;
                }
            }
            sum2 / count as f64
        };
        let quadratic = variance(&|c| binned(c, groups + 1));
        assert!(
            (quadratic / (41.0 / 64.0) - 1.0).abs() < 0.04,
            "{quadratic}"
        );
        // The same groups as means: 1/4 of a reading's variance.
        let means = variance(&|c| reduced_to_means(c, groups + 1));
        assert!((means / 0.25 - 1.0).abs() < 0.04, "{means}");
    }

    /// A logged creep curve of `n` readings at equal times: a primary stage, a long
    /// secondary one and a tertiary stage that ends steep (strain fraction of the last).
    fn creep_like(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let x = k as f64 / (n - 1) as f64;
                0.01 * (1.0 - (-x / 0.02).exp()) + 0.02 * x + 0.002 / (1.02 - x)
            })
            .collect()
    }

    /// The strain groups cover readings 1..n in order, at most `max_points − 1` of them, each
    /// within the common span and each as long as the span allows (the greedy run is maximal:
    /// with its next reading it would exceed the span); the tertiary stage's last readings
    /// are each alone and the secondary stage's runs are long; fewer readings than
    /// `max_points` give no reduction; a flat curve falls back to equal counts.
    #[test]
    fn strain_groups_span_equal_strain_ranges() {
        let e = creep_like(500);
        let g = strain_group_bounds(&e, 100);
        assert!(g.len() <= 99 && g.len() >= 90, "{}", g.len());
        assert_eq!(g[0].0, 1);
        assert_eq!(g.last().unwrap().1, 500);
        assert!(g.windows(2).all(|w| w[0].1 == w[1].0));
        // On the smoothed rise the groups are drawn on, each is as long as the span allows.
        let rise = smoothed_rise(&e, strain_window(500, 100));
        let span_of = |lo: usize, hi: usize| rise[hi - 1] - rise[lo];
        let s = g
            .iter()
            .map(|&(lo, hi)| span_of(lo, hi))
            .fold(0.0, f64::max);
        for &(lo, hi) in &g {
            if hi < e.len() {
                assert!(span_of(lo, hi + 1) > s, "group {lo}..{hi} could have grown");
            }
        }
        // The last five readings alone (the tertiary stage's steps exceed the span).
        assert!(
            g[g.len() - 5..].iter().all(|&(lo, hi)| hi - lo == 1),
            "{:?}",
            &g[g.len() - 5..]
        );
        // The longest run lies in the secondary stage and is far longer than equal counts.
        let (lo, hi) = *g.iter().max_by_key(|&&(lo, hi)| hi - lo).unwrap();
        assert!(hi - lo > 10 && lo > 25 && hi < 450, "{lo}..{hi}");
        // The curve of means keeps the groups (sizes 1 upward) and the readings' times.
        let c = Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: None,
            times_h: (0..500).map(|k| k as f64).collect(),
            strains: e.clone(),
            rupture_time_h: Some(499.0),
            rupture_strain: *e.last().unwrap(),
            min_rate_measured: None,
            groups: None,
            min_rate_estimated: 1e-3,
        };
        let r = reduce(&c, 100, Reduction::StrainMeans);
        assert_eq!(r.strains.len(), g.len() + 1);
        assert_eq!(r.groups.as_ref().unwrap().times_h.len(), 500);
        assert_eq!(reduce(&r, 100, Reduction::StrainMeans), r);
        let short = Curve {
            times_h: c.times_h[..80].to_vec(),
            strains: c.strains[..80].to_vec(),
            ..c.clone()
        };
        assert_eq!(reduce(&short, 100, Reduction::StrainMeans), short);
        let flat = strain_group_bounds(&[0.0; 401], 100);
        assert_eq!(flat, group_bounds(401, 100).collect::<Vec<_>>());
    }

    /// 200 groups of 1–40 readings after a first reading alone (their [`ReadingGroups`], ρ
    /// 0) and a curve of their means: the sizes, the readings in all, the groups, the curve.
    fn grouped_curve() -> (Vec<usize>, usize, ReadingGroups, Curve) {
        let sizes: Vec<usize> = (0..200).map(|k| 1 + k % 40).collect();
        let n = 1 + sizes.iter().sum::<usize>();
        let mut ends = vec![1];
        for m in &sizes {
            ends.push(ends.last().unwrap() + m);
        }
        let g = ReadingGroups {
            times_h: (0..n).map(|k| k as f64).collect(),
            ends,
            misfit_share: 0.0,
        };
        let c = Curve {
            temperature_c: 600.0,
            stress_mpa: 100.0,
            specimen: None,
            times_h: vec![0.0; sizes.len() + 1],
            strains: vec![0.0; sizes.len() + 1],
            rupture_time_h: None,
            rupture_strain: 1.0,
            min_rate_measured: None,
            groups: Some(std::sync::Arc::new(g.clone())),
            min_rate_estimated: 1e-3,
        };
        (sizes, n, g, c)
    }

    /// Group means of white noise times √m (sizes 1 to 40) have a reading's variance: the
    /// weighting that lets points of different sizes share one error model. Without it the
    /// pooled variance of these means would be about a sixth of a reading's.
    #[test]
    fn means_in_reading_units_have_a_readings_variance() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(216_102);
        let (sizes, n, g, c) = grouped_curve();
        let (mut plain, mut scaled, mut count) = (0.0, 0.0, 0usize);
        for _ in 0..100 {
            let raw: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
            let mut means = vec![0.0; sizes.len() + 1];
            g.average(&raw, &mut means);
            let mut v = means.clone();
            c.to_reading_units(&mut v);
            for (a, b) in means.iter().zip(&v) {
                plain += a * a;
                scaled += b * b;
                count += 1;
            }
            c.from_reading_units(&mut v);
            assert!(v.iter().zip(&means).all(|(a, b)| (a - b).abs() < 1e-12));
        }
        let (plain, scaled) = (plain / count as f64, scaled / count as f64);
        assert!((scaled - 1.0).abs() < 0.05, "{scaled}");
        assert!(plain < 0.25, "{plain}");
    }

    /// Group means of a two-part error — white reading error of variance 1 − ρ and a part
    /// shared by every reading of a group (variance ρ, what averaging does not shrink) — put
    /// in a reading's units at the group's ρ have a reading's variance at every size (1 to
    /// 40), and √m alone (ρ taken as 0) overstates the long groups' precision.
    #[test]
    fn means_of_a_two_part_error_in_reading_units_have_a_readings_variance() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(216_103);
        let rho = 0.2;
        let (sizes, n, g, c) = grouped_curve();
        let two = c.with_misfit_share(rho);
        assert_eq!(two.groups.as_ref().unwrap().misfit_share, rho);
        assert_eq!(c.with_misfit_share(0.0), c);
        // Variance in reading units of the long groups (m ≥ 30) and the single readings.
        let (mut long, mut long_white, mut single, mut nl, mut ns) = (0.0, 0.0, 0.0, 0, 0);
        for _ in 0..400 {
            let mut raw: Vec<f64> = (0..n)
                .map(|_| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    (1.0 - rho).sqrt() * z
                })
                .collect();
            let mut lo = 0;
            for &hi in &g.ends {
                let z: f64 = StandardNormal.sample(&mut rng);
                let shared = rho.sqrt() * z;
                for v in &mut raw[lo..hi] {
                    *v += shared;
                }
                lo = hi;
            }
            let mut means = vec![0.0; sizes.len() + 1];
            g.average(&raw, &mut means);
            let (mut v, mut w) = (means.clone(), means.clone());
            two.to_reading_units(&mut v);
            c.to_reading_units(&mut w);
            for (k, m) in g.sizes().enumerate() {
                if m >= 30 {
                    long += v[k] * v[k];
                    long_white += w[k] * w[k];
                    nl += 1;
                } else if m == 1 {
                    single += v[k] * v[k];
                    ns += 1;
                }
            }
            two.from_reading_units(&mut v);
            assert!(v.iter().zip(&means).all(|(a, b)| (a - b).abs() < 1e-12));
        }
        let (long, long_white, single) =
            (long / nl as f64, long_white / nl as f64, single / ns as f64);
        // 8,400 long and 2,000 single values: sd of the estimates about 1.5 % and 3.2 %.
        assert!((long - 1.0).abs() < 0.06, "{long}");
        assert!((single - 1.0).abs() < 0.13, "{single}");
        // √m alone: about (0.8/35 + 0.2)·35 ≈ 7.8 times a reading's variance.
        assert!(long_white > 5.0, "{long_white}");
        // The factor's ends: √m at ρ = 0, 1 at ρ = 1.
        assert_eq!(reading_units_factor(9, 0.0), 3.0);
        assert!((reading_units_factor(9, 1.0) - 1.0).abs() < 1e-15);
        assert!((reading_units_factor(1, 0.37) - 1.0).abs() < 1e-15);
    }

    /// Which labels name campaigns, as a table: Alloy 617's, `synth`'s replicate pairs,
    /// specimens each alone, one curve unlabelled, one-condition campaigns, a small campaign.
    #[test]
    fn campaigns_are_labels_that_span_conditions() {
        let set = |v: &[(f64, f64, Option<&str>)]| -> Vec<Curve> {
            v.iter()
                .map(|&(t, s, sp)| Curve::two_point(t, s, sp))
                .collect()
        };
        let cases: Vec<(Vec<Curve>, Option<Vec<&str>>)> = vec![
            (
                set(&[
                    (850.0, 43.0, Some("INL2-a")),
                    (850.0, 43.0, Some("INL2-b")),
                    (850.0, 35.0, Some("KAERI2-a")),
                    (900.0, 25.0, Some("KAERI2-a")),
                ]),
                Some(vec!["INL2", "INL2", "KAERI2", "KAERI2"]),
            ),
            (
                set(&[
                    (600.0, 129.0, Some("S1-a")),
                    (600.0, 147.0, Some("S2-a")),
                    (600.0, 181.0, Some("S4-a")),
                    (600.0, 181.0, Some("S4-b")),
                ]),
                None,
            ),
            (
                set(&[(600.0, 129.0, Some("SX01")), (600.0, 147.0, Some("SX02"))]),
                None,
            ),
            (
                set(&[
                    (850.0, 43.0, Some("A-1")),
                    (850.0, 50.0, Some("A-2")),
                    (850.0, 35.0, None),
                ]),
                None,
            ),
            (
                set(&[(850.0, 43.0, Some("A-1")), (850.0, 50.0, Some("A-2"))]),
                None,
            ),
            (
                set(&[
                    (850.0, 43.0, Some("A-1")),
                    (900.0, 43.0, Some("A-2")),
                    (850.0, 35.0, Some("B-1")),
                ]),
                Some(vec!["A", "A", "B"]),
            ),
        ];
        for (i, (curves, want)) in cases.iter().enumerate() {
            assert_eq!(&campaigns(curves), want, "case {i}");
        }
    }
    use std::fs::File;
    use std::io::Write;
    use std::path::PathBuf;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        let mut f = File::create(&p).unwrap();
        f.write_all(text.as_bytes()).unwrap();
        p
    }

    /// Deterministic pseudo-random numbers in [0, 1) (xorshift), no dependency needed.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn tables_in_memory_load_as_the_files() {
        let dir = tempfile::tempdir().unwrap();
        let curves = "temperature_C,stress_MPa,time_h,strain_pct,specimen\n\
            560,100,0,0,a\n560,100,10,1.5,a\n560,100,10,1.5,a\n560,100,20,3,a\n560,100,30,7.25,a\n";
        let ruptures =
            "temperature_C,stress_MPa,rupture_time_h,rupture_strain_pct\n560,100,31,7.5\n";
        let (c, r) = (
            write(dir.path(), "c.csv", curves),
            write(dir.path(), "r.csv", ruptures),
        );
        let opts = LoadOptions::default();
        let from_files = load(&c, &r, &opts).unwrap();
        let from_memory =
            load_bytes(&c, curves.as_bytes(), &r, ruptures.as_bytes(), &opts).unwrap();
        // Same curves bit for bit, same warnings (the duplicate on line 4) naming the same table.
        assert_eq!(from_memory, from_files);
        assert!(from_memory.warnings[0].contains("c.csv:4: duplicate point"));
        // Errors name the table as given, with its line.
        let bad = curves.replace("560,100,20,3,a", "560,100,-20,3,a");
        let e = load_bytes(
            Path::new("<t>"),
            bad.as_bytes(),
            &r,
            ruptures.as_bytes(),
            &opts,
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "<t>:5: column 'time_h': must not be negative (got -20)");
    }

    /// A rupture record at a temperature without curves (a life-only test): one warning line
    /// where every temperature is kept, naming the file, the first line, the count and the
    /// temperatures; none where the configuration keeps one temperature.
    #[test]
    fn life_only_records_are_named_where_every_temperature_is_kept() {
        let curves = "temperature_C,stress_MPa,time_h,strain_pct\n\
            560,100,0,0\n560,100,10,1.5\n560,100,20,3\n560,100,30,7.25\n";
        let ruptures = "temperature_C,stress_MPa,rupture_time_h\n560,100,31\n600,80,900\n\
            600,90,400\n650,70,120\n";
        let load_with = |temperature_c| {
            load_bytes(
                Path::new("c.csv"),
                curves.as_bytes(),
                Path::new("r.csv"),
                ruptures.as_bytes(),
                &LoadOptions {
                    temperature_c,
                    ..LoadOptions::default()
                },
            )
            .unwrap()
        };
        let all = load_with(None);
        assert_eq!(all.curves.len(), 1);
        let w: Vec<&String> = all
            .warnings
            .iter()
            .filter(|w| w.contains("not fitted"))
            .collect();
        assert_eq!(w.len(), 1, "{:?}", all.warnings);
        assert!(
            w[0].starts_with("r.csv:3: 3 rupture record(s) at 600, 650 °C"),
            "{}",
            w[0]
        );
        let one = load_with(Some(560.0));
        assert_eq!(one.curves, all.curves);
        assert!(
            one.warnings.iter().all(|w| !w.contains("not fitted")),
            "{:?}",
            one.warnings
        );
    }

    #[test]
    fn readings_after_the_rupture_are_time_outliers_where_few() {
        // (times h, rupture time h, flagged)
        let table: [(&[f64], f64, &[usize]); 8] = [
            (&[0.0, 10.0, 20.0, 90.0], 100.0, &[]),
            // The last reading at or a little past the rupture: real data (≤ 1.0007 ×).
            (&[0.0, 10.0, 20.0, 100.07], 100.0, &[]),
            (&[0.0, 10.0, 20.0, 150.0], 100.0, &[]),
            (&[0.0, 10.0, 20.0, 90.0, 150.1], 100.0, &[4]),
            (&[0.0, 10.0, 20.0, 1e30], 100.0, &[3]),
            (&[0.0, 10.0, 900.0, 20.0, 1000.0, 30.0], 100.0, &[2, 4]),
            // Half or more beyond: the rupture record is the suspect, no reading is.
            (&[0.0, 10.0, 200.0, 300.0], 100.0, &[]),
            (&[0.0, 200.0, 300.0, 400.0], 100.0, &[]),
        ];
        for (times, tr, want) in table {
            assert_eq!(after_rupture(times, tr), want, "{times:?} {tr}");
        }
    }

    #[test]
    fn outlier_z_of_curves_and_spikes() {
        // A monotone curve with a steep end: every point within its neighbours (z ≤ 1) but
        // the ends, which stay small.
        let tertiary: Vec<f64> = (0..40)
            .map(|k| {
                let t = k as f64 / 40.0;
                0.002 + 0.01 * t + 0.05 * t.powi(8)
            })
            .collect();
        let z = outlier_z(&tertiary);
        let n = z.len();
        assert!(z.iter().all(|v| *v < 5.0), "{z:?}");
        // A loading jump at t = 0 (first point 0, the rest near 0.5 %): small.
        let mut jump = vec![0.0];
        jump.extend((0..20).map(|k| 0.01 + 1e-5 * k as f64));
        let z = outlier_z(&jump);
        assert!(z.iter().all(|v| *v < 1.0), "{z:?}");
        // … but a first point far above or below (a typo) is one.
        jump[0] = 0.5;
        assert!(outlier_z(&jump)[0] > OUTLIER_Z);
        jump[0] = -0.5;
        assert!(outlier_z(&jump)[0] > OUTLIER_Z);
        // Gross spikes, one or two adjacent, in the middle and at the end.
        let mut spiky = tertiary.clone();
        spiky[10] = 1e4;
        spiky[11] = 1e4;
        spiky[n - 1] = 1e4;
        let z = outlier_z(&spiky);
        let flagged: Vec<usize> = (0..n).filter(|&k| z[k] > OUTLIER_Z).collect();
        assert_eq!(flagged, [10, 11, n - 1], "{z:?}");
        // A negative typo far below its neighbours.
        let mut neg = tertiary.clone();
        neg[20] = -5.0;
        let z = outlier_z(&neg);
        assert!(z[20] > OUTLIER_Z && z.iter().filter(|v| **v > OUTLIER_Z).count() == 1);
        // Three points: the median of the other two, scale from their range or the spread.
        let z = outlier_z(&[0.0, 0.01, 100.0]);
        assert!(z[2] > OUTLIER_Z && z[0] < 1.0 && z[1] < 1.0, "{z:?}");
    }

    #[test]
    fn data_temperatures_must_be_those_of_a_creep_test() {
        let dir = tempfile::tempdir().unwrap();
        for (t, ok) in [
            ("0", true),
            ("2000", true),
            ("-0.5", false),
            ("2001", false),
            ("-300", false),
        ] {
            let c = write(
                dir.path(),
                "c.csv",
                &format!("temperature_C,stress_MPa,time_h,strain_pct\n{t},100,0,0\n{t},100,5,1\n{t},100,10,2\n"),
            );
            let r = read_curves(&c);
            assert_eq!(r.is_ok(), ok, "{t}: {r:?}");
            if !ok {
                let e = r.unwrap_err().to_string();
                assert!(e.contains("c.csv:2: column 'temperature_C'"), "{e}");
            }
            let r = write(
                dir.path(),
                "r.csv",
                &format!("temperature_C,stress_MPa,rupture_time_h\n{t},100,20\n"),
            );
            assert_eq!(read_ruptures(&r).is_ok(), ok, "{t}");
        }
    }

    #[test]
    fn min_rate_linear_exact() {
        let t = [0.0, 3.0, 10.0, 11.0, 40.0, 41.0, 77.0, 100.0];
        let e: Vec<f64> = t.iter().map(|t| 0.01 + 2.5e-4 * t).collect();
        let r = estimate_min_rate(&t, &e, 100.0);
        assert!((r - 2.5e-4).abs() < 1e-12, "{r}");
    }

    #[test]
    fn min_rate_three_stage_curve() {
        // ε = a t + b (1 − e^(−t/τ)) + c t^4 on a life of 10 000 h.
        let (a, b, tau, c) = (1e-6, 2e-3, 300.0, 2.5e-18);
        let life = 10_000.0;
        let eps = |t: f64| a * t + b * (1.0 - (-t / tau).exp()) + c * t.powi(4);
        let rate = |t: f64| a + b / tau * (-t / tau).exp() + 4.0 * c * t.powi(3);
        let true_min = (0..=100_000)
            .map(|k| rate(k as f64 * life / 100_000.0))
            .fold(f64::INFINITY, f64::min);
        let mut rng = Rng(0x9e3779b97f4a7c15);
        let mut t = vec![0.0];
        while *t.last().unwrap() < life * 0.97 {
            let dt = 60.0 + 200.0 * rng.next();
            t.push(t.last().unwrap() + dt);
        }
        let e: Vec<f64> = t
            .iter()
            .map(|&t| eps(t) + 2e-5 * (rng.next() - 0.5))
            .collect();
        let r = estimate_min_rate(&t, &e, life);
        let rel = (r - true_min) / true_min;
        assert!(rel.abs() < 0.05, "estimate {r}, true {true_min}, rel {rel}");
    }

    #[test]
    fn min_rate_ignores_single_fallback_point() {
        let mut t: Vec<f64> = (0..30).map(|k| k as f64 * 10.0).collect();
        let mut e: Vec<f64> = t.iter().map(|t| 1e-3 * t).collect();
        e[12] -= 0.02; // a point that falls back
        t[29] = 290.0;
        let r = estimate_min_rate(&t, &e, 300.0);
        assert!(r > 0.0 && (r - 1e-3).abs() / 1e-3 < 0.5, "{r}");
    }

    #[test]
    fn min_rate_fallback_secant() {
        // Curve much shorter than the window: secant slope.
        let t = [0.0, 1.0, 2.0];
        let e = [0.0, 0.5, 1.0];
        assert_eq!(estimate_min_rate(&t, &e, 1000.0), 0.5);
        assert_eq!(estimate_min_rate(&[1.0, 1.0, 1.0], &e, 10.0), 0.0);
    }

    #[test]
    fn sorting_duplicates_and_specimens() {
        let dir = tempfile::tempdir().unwrap();
        let c = write(
            dir.path(),
            "c.csv",
            "specimen,strain_pct,time_h,stress_MPa,temperature_C,note\n\
             S1,0,0,100,600,x\n\
             S1,1,10,100,600,x\n\
             S1,0.5,5,100,600,x\n\
             S1,1,10,100,600,x\n\
             S1,1.2,10,100,600,x\n\
             S2,0,0,100,600,x\n\
             S2,1,5,100,600,x\n\
             S2,2,10,100,600,x\n",
        );
        let r = write(
            dir.path(),
            "r.csv",
            "temperature_C,stress_MPa,rupture_time_h,rupture_strain_pct,min_rate_pct_per_h,specimen\n\
             600,100,20,,,S1\n\
             600,100,30,3,0.05,S2\n\
             600,90,30,3,,\n\
             700,90,30,3,,\n",
        );
        let ds = load(&c, &r, &LoadOptions::default()).unwrap();
        assert_eq!(ds.curves.len(), 2);
        let s1 = &ds.curves[0];
        assert_eq!(s1.specimen.as_deref(), Some("S1"));
        assert_eq!(s1.times_h, vec![0.0, 5.0, 10.0, 10.0]);
        assert_eq!(s1.strains, vec![0.0, 0.005, 0.01, 0.012]);
        assert_eq!(s1.rupture_time_h, Some(20.0));
        assert_eq!(s1.rupture_strain, 0.012);
        assert_eq!(s1.min_rate_measured, None);
        let s2 = &ds.curves[1];
        assert_eq!(s2.rupture_time_h, Some(30.0));
        assert_eq!(s2.rupture_strain, 0.03);
        assert_eq!(s2.min_rate_measured, Some(0.0005));
        // One duplicate, one unused record at 600 °C, and (every temperature kept) the record
        // at 700 °C, where no curve is, named as a life-only test.
        assert_eq!(ds.warnings.len(), 3, "{:?}", ds.warnings);
        assert!(ds.warnings[0].contains("c.csv:5: duplicate point"));
        assert!(ds.warnings[1].contains("r.csv:4:"));
        assert!(ds.warnings[2].contains("r.csv:5: 1 rupture record(s) at 700 °C"));
        // Keeping 600 °C only, the 700 °C record is silent.
        let at600 = LoadOptions {
            temperature_c: Some(600.0),
            ..LoadOptions::default()
        };
        let ds = load(&c, &r, &at600).unwrap();
        assert_eq!(ds.warnings.len(), 2, "{:?}", ds.warnings);
    }

    #[test]
    fn interrupted_and_filter() {
        let dir = tempfile::tempdir().unwrap();
        let c = write(
            dir.path(),
            "c.csv",
            "temperature_C,stress_MPa,time_h,strain_pct\n\
             600,100,0,0\n600,100,5,1\n600,100,10,2\n\
             600,80,0,0\n600,80,5,1\n600,80,10,2\n\
             650,80,0,0\n650,80,5,1\n650,80,10,2\n",
        );
        let r = write(
            dir.path(),
            "r.csv",
            "temperature_C,stress_MPa,rupture_time_h\n600,100,20\n",
        );
        let opts = LoadOptions {
            temperature_c: Some(600.0),
            interrupted: vec![80.0.into()],
            ..Default::default()
        };
        let ds = load(&c, &r, &opts).unwrap();
        assert_eq!(ds.curves.len(), 2);
        assert_eq!(ds.curves[0].stress_mpa, 80.0);
        assert_eq!(ds.curves[0].rupture_time_h, None);
        assert_eq!(ds.curves[0].rupture_strain, 0.02);
        assert_eq!(ds.curves[1].stress_mpa, 100.0);
        let err = load(
            &c,
            &r,
            &LoadOptions {
                temperature_c: Some(700.0),
                interrupted: vec![],
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("no curves at temperature_C = 700"));
        let err = load(&c, &r, &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("c.csv:8:") && err.contains("2 temperatures"),
            "{err}"
        );
        let several = LoadOptions {
            several_temperatures: true,
            ..Default::default()
        };
        let err = load(&c, &r, &several).unwrap_err().to_string();
        assert!(
            err.contains("c.csv:5:") && err.contains("no rupture record"),
            "{err}"
        );
    }

    /// Two temperatures with the same stress (80 MPa) at both, replicates at 920 °C.
    fn two_temperatures(dir: &Path) -> (PathBuf, PathBuf) {
        let c = write(
            dir,
            "c.csv",
            "temperature_C,stress_MPa,time_h,strain_pct,specimen\n\
             720,80,0,0,A\n720,80,5,1,A\n720,80,10,2,A\n\
             920,80,0,0,S1\n920,80,5,1,S1\n920,80,9,2,S1\n\
             920,80,0,0,S2\n920,80,5,1,S2\n920,80,8,2,S2\n\
             920,100,0,0,S1\n920,100,2,1,S1\n920,100,4,2,S1\n",
        );
        let r = write(
            dir,
            "r.csv",
            "temperature_C,stress_MPa,rupture_time_h,specimen\n\
             720,80,10,A\n920,80,9,S1\n920,80,8,S2\n920,100,4,S1\n",
        );
        (c, r)
    }

    fn keyed(entries: &[&str]) -> LoadOptions {
        LoadOptions {
            interrupted: entries
                .iter()
                .map(|e| Interrupted::parse(e).unwrap())
                .collect(),
            several_temperatures: true,
            ..Default::default()
        }
    }

    /// Rupture times by (temperature, stress, specimen).
    fn lives(ds: &Dataset) -> Vec<(f64, f64, String, Option<f64>)> {
        ds.curves
            .iter()
            .map(|c| {
                (
                    c.temperature_c,
                    c.stress_mpa,
                    c.specimen.clone().unwrap_or_default(),
                    c.rupture_time_h,
                )
            })
            .collect()
    }

    #[test]
    fn interrupted_is_keyed_by_temperature_and_stress() {
        let dir = tempfile::tempdir().unwrap();
        let (c, r) = two_temperatures(dir.path());
        let s = |x: &str| x.to_string();
        // Nothing interrupted: every test ruptured.
        let all = load(&c, &r, &keyed(&[])).unwrap();
        assert!(all.curves.iter().all(|c| c.rupture_time_h.is_some()));
        // "920:80:S1": that one curve only; the 720 °C test at the same stress keeps its life.
        let one = load(&c, &r, &keyed(&["920:80:S1"])).unwrap();
        assert_eq!(
            lives(&one),
            [
                (720.0, 80.0, s("A"), Some(10.0)),
                (920.0, 80.0, s("S1"), None),
                (920.0, 80.0, s("S2"), Some(8.0)),
                (920.0, 100.0, s("S1"), Some(4.0)),
            ]
        );
        assert!(
            one.warnings.iter().any(
                |w| w.contains("r.csv:3:") && w.contains("specimen S1 is declared interrupted")
            ),
            "{:?}",
            one.warnings
        );
        // "920:80" (no specimen): both replicates at 920 °C, still not 720 °C. Typed as
        // 920.0 and 8e1: compared as values.
        let both = load(&c, &r, &keyed(&["920.0:8e1"])).unwrap();
        assert_eq!(
            lives(&both).iter().map(|l| l.3).collect::<Vec<_>>(),
            [Some(10.0), None, None, Some(4.0)]
        );
        // A bare stress with two temperatures: refused, asking for "T:σ".
        let bare = LoadOptions {
            interrupted: vec![80.0.into()],
            several_temperatures: true,
            ..Default::default()
        };
        let e = load(&c, &r, &bare).unwrap_err().to_string();
        assert_eq!(
            e,
            "interrupted[0] = 80: a bare stress is ambiguous: the curves are at 2 temperatures (720, 920 °C); write \"T:σ\" (°C:MPa), e.g. \"720:80\""
        );
        // … but accepted at one temperature (the temperature filter): both 920 °C replicates,
        // as before keyed entries.
        let filtered = LoadOptions {
            temperature_c: Some(920.0),
            interrupted: vec![80.0.into()],
            ..Default::default()
        };
        let ds = load(&c, &r, &filtered).unwrap();
        assert_eq!(
            lives(&ds).iter().map(|l| l.3).collect::<Vec<_>>(),
            [None, None, Some(4.0)]
        );
        // An entry that matches no curve: an error naming it (the file and line when known).
        for (entries, want) in [
            (
                &["920:80:S1", "900:80"][..],
                "interrupted[1] = 900:80: matches no curve",
            ),
            (
                &["720:80:S9"][..],
                "interrupted[0] = 720:80:S9: matches no curve",
            ),
            (&["920:90"][..], "interrupted[0] = 920:90: matches no curve"),
        ] {
            let mut o = keyed(entries);
            o.interrupted_source = Some((PathBuf::from("run.toml"), 7));
            let e = load(&c, &r, &o).unwrap_err().to_string();
            assert_eq!(e, format!("run.toml:7: {want}"));
        }
        let mut o = keyed(&["720:80"]);
        o.temperature_c = Some(920.0);
        o.several_temperatures = false;
        let e = load(&c, &r, &o).unwrap_err().to_string();
        assert!(
            e.contains("matches no curve (the configuration keeps temperature_C = 920 only)"),
            "{e}"
        );
    }

    #[test]
    fn several_temperatures_without_a_filter_or_a_law_are_refused_with_both_ways_out() {
        let dir = tempfile::tempdir().unwrap();
        let (c, r) = two_temperatures(dir.path());
        let e = load(&c, &r, &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("{}:", c.display())), "{e}");
        assert!(
            e.contains("the curves are at 2 temperatures (720, 920 °C)"),
            "{e}"
        );
        assert!(e.contains("set temperature_C = 720 (say)"), "{e}");
        assert!(e.contains("law = \"arrhenius\" on A and Kc"), "{e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }

    #[test]
    fn interrupted_entries_parse_and_serialise() {
        let at = |t: f64, s: f64, sp: Option<&str>| Interrupted::At {
            temperature_c: t,
            stress_mpa: s,
            specimen: sp.map(str::to_string),
        };
        for (text, want) in [
            ("920:80", at(920.0, 80.0, None)),
            (" 920 : 80.5 ", at(920.0, 80.5, None)),
            ("920:80:INL2-a", at(920.0, 80.0, Some("INL2-a"))),
            ("920:80: S:3 ", at(920.0, 80.0, Some("S:3"))),
        ] {
            assert_eq!(Interrupted::parse(text).unwrap(), want, "{text}");
        }
        for bad in ["80", "x:80", "920:y", "920:-5", "920:80:", "-300:80"] {
            assert!(Interrupted::parse(bad).is_err(), "{bad}");
        }
        // A bare stress serialises as the number it always was (the run identity), keyed
        // entries as strings; both read back.
        let v = vec![
            Interrupted::Stress(70.0),
            at(920.0, 80.0, None),
            at(920.0, 80.0, Some("S1")),
        ];
        let j = serde_json::to_string(&v).unwrap();
        assert_eq!(j, r#"[70.0,"920:80","920:80:S1"]"#);
        assert_eq!(serde_json::to_string(&vec![70.0f64]).unwrap(), "[70.0]");
        let back: Vec<Interrupted> = serde_json::from_str(&j).unwrap();
        assert_eq!(back, v);
        let t: std::collections::BTreeMap<String, Vec<Interrupted>> =
            toml::from_str("i = [70, 85.5, \"920:80\"]").unwrap();
        assert_eq!(t["i"], [70.0.into(), 85.5.into(), at(920.0, 80.0, None)]);
    }

    #[test]
    fn ragged_row_and_empty_cell() {
        let dir = tempfile::tempdir().unwrap();
        let c = write(
            dir.path(),
            "c.csv",
            "temperature_C,stress_MPa,time_h,strain_pct\n600,100,0,0\n600,100,5\n",
        );
        let e = read_curves(&c).unwrap_err().to_string();
        assert!(e.contains("c.csv:3:") && e.contains("3 fields"), "{e}");
        let c = write(
            dir.path(),
            "c2.csv",
            "temperature_C,stress_MPa,time_h,strain_pct\n600,100,0,0\n600,100,,1\n",
        );
        let e = read_curves(&c).unwrap_err().to_string();
        assert!(e.contains("c2.csv:3:") && e.contains("'time_h'"), "{e}");
        let r = write(
            dir.path(),
            "r.csv",
            "temperature_C,stress_MPa,rupture_time_h\n600,100,0\n",
        );
        let e = read_ruptures(&r).unwrap_err().to_string();
        assert!(
            e.contains("r.csv:2:") && e.contains("rupture_time_h"),
            "{e}"
        );
    }
}
