//! Where an axis is ticked and how its ticks read: one label format per axis, plain numbers
//! while every tick lies within [`PLAIN_MIN`, `PLAIN_MAX`] in magnitude, powers of ten
//! (`10⁵`, `2×10⁴`, `10⁻³`) for all of them otherwise, never a mixture.

use super::AxisScale;

/// Largest magnitude a tick may have for the axis to be labelled with plain numbers.
pub const PLAIN_MAX: f64 = 1e4;
/// Smallest non-zero magnitude a tick may have for the axis to be labelled with plain numbers.
pub const PLAIN_MIN: f64 = 1e-3;

/// Tick positions and labels for an axis over `[lo, hi]`: between 2 and `max` ticks (max ≥ 5)
/// inside the range for any finite range with lo < hi (lo > 0 on a log axis), every label
/// distinct and with the digits its spacing needs, all labels of the axis in one format
/// (`tick_labels`). Linear: multiples of 1, 2 or 5 × 10^k. Log: powers of ten when at least
/// three fall inside (every 2nd, 5th … when too many); else 1, 2, 5 × 10^k when at least
/// three fall inside, or 1…9 × 10^k when at least four do; else linear ticks (a range within
/// one decade, such as 0.24–0.40, gets 0.24, 0.26, …, 0.40; 77–130 MPa gets 80, 90, …, 130).
/// A degenerate or non-finite range gives no ticks.
pub fn axis_ticks(lo: f64, hi: f64, scale: AxisScale, max: usize) -> Vec<(f64, String)> {
    let max = max.max(5);
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Vec::new();
    }
    let (values, step) = match scale {
        AxisScale::Linear => {
            let (v, s) = linear_ticks(lo, hi, max);
            (v, Some(s))
        }
        AxisScale::Log => {
            if !(lo > 0.0) {
                return Vec::new();
            }
            match log_ticks(lo, hi, max) {
                Some(v) => (v, None),
                None => {
                    let (v, s) = linear_ticks(lo, hi, max);
                    (v, Some(s))
                }
            }
        }
    };
    let labels = tick_labels(&values, step);
    values.into_iter().zip(labels).collect()
}

/// The multiples of the smallest 1-2-5 step that gives at most `max` of them in `[lo, hi]`,
/// and that step.
fn linear_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, f64) {
    let span = hi - lo;
    let count = |step: f64| -> f64 {
        ((hi / step + 1e-9).floor() - (lo / step - 1e-9).ceil() + 1.0).max(0.0)
    };
    // From a step at least the span (≤ 2 ticks) downwards, while the count stays ≤ max.
    let mut exp = span.log10().ceil() as i32;
    let mut best = 10f64.powi(exp);
    'down: loop {
        for m in [5.0, 2.0, 1.0] {
            let step = m * 10f64.powi(exp - 1);
            if !(step > 0.0) || count(step) > max as f64 {
                break 'down;
            }
            best = step;
        }
        exp -= 1;
        if exp < -330 {
            break;
        }
    }
    let first = (lo / best - 1e-9).ceil();
    let last = (hi / best + 1e-9).floor();
    let values = (0..=(last - first).max(0.0) as usize)
        .map(|k| ((first + k as f64) * best).clamp(lo, hi))
        .collect();
    (values, best)
}

/// Ticks of a log axis over `[lo, hi]` (lo > 0) from powers of ten or their 1-2-5 / 1…9
/// multiples; `None` when too few of them fall inside (use linear ticks).
fn log_ticks(lo: f64, hi: f64, max: usize) -> Option<Vec<f64>> {
    let (a, b) = (lo.log10(), hi.log10());
    let inside = |v: f64| v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12);
    let (k0, k1) = ((a - 1e-9).ceil() as i64, (b + 1e-9).floor() as i64);
    let decades = k1 - k0 + 1;
    if decades >= 3 {
        let every = [1i64, 2, 5, 10, 20, 50, 100]
            .into_iter()
            .find(|d| (decades + d - 1) / d <= max as i64)
            .unwrap_or(100);
        let start = k0.div_euclid(every) * every;
        let v: Vec<f64> = (0..)
            .map(|i| start + i * every)
            .take_while(|k| *k <= k1)
            .filter(|k| *k >= k0)
            .map(|k| 10f64.powi(k as i32))
            .collect();
        if v.len() >= 2 {
            return Some(v);
        }
    }
    // 1-2-5 multiples when three fall inside; 1…9 multiples when four do (fewer leave most
    // of a short axis unlabelled: linear ticks then label it better, e.g. 80, 90, …, 130).
    for (mantissas, least) in [
        (&[1.0, 2.0, 5.0][..], 3),
        (&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0][..], 4),
    ] {
        let v: Vec<f64> = ((a.floor() as i64)..=(b.ceil() as i64))
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k as i32)))
            .filter(|v| inside(*v))
            .collect();
        if v.len() >= least && v.len() <= max {
            return Some(v);
        }
    }
    None
}

/// How the labels of one axis are written.
#[cfg(test)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabelFormat {
    /// Plain decimal numbers, one number of decimals for the axis (`0.25`, `1000`).
    Plain,
    /// Powers of ten: `10⁵`, `2×10⁴`, `−5×10⁻⁸` (and `0`).
    Power,
}

/// The format of one label: [`LabelFormat::Power`] when it contains a power of ten, else
/// [`LabelFormat::Plain`]; `None` for `0`, which reads the same in both.
#[cfg(test)]
pub fn label_format(label: &str) -> Option<LabelFormat> {
    if label == "0" {
        None
    } else if label.contains("10") && label.chars().any(is_superscript) {
        Some(LabelFormat::Power)
    } else {
        Some(LabelFormat::Plain)
    }
}

/// Labels of the ticks `values` of one axis, all in one format: plain numbers (the fewest
/// decimals that state every tick to 1e-6 of the spacing) when every non-zero tick lies in
/// [`PLAIN_MIN`, `PLAIN_MAX`] in magnitude, else powers of ten. `step` is the spacing of
/// linear ticks (their powers share the step's exponent: `0, 2×10⁴, 4×10⁴ …`); `None` for
/// the ticks of a log axis (each its own exponent: `10³, 10⁴, 10⁵`). Negative numbers get a
/// proper minus sign (−).
pub fn tick_labels(values: &[f64], step: Option<f64>) -> Vec<String> {
    let zero_tol = match step {
        Some(s) => 1e-6 * s,
        None => 0.0,
    };
    let clean = |v: f64| if v.abs() <= zero_tol { 0.0 } else { v };
    let plain = values.iter().map(|v| clean(*v)).all(|v| {
        let a = v.abs();
        a == 0.0 || (PLAIN_MIN * (1.0 - 1e-12)..=PLAIN_MAX * (1.0 + 1e-12)).contains(&a)
    });
    // The tolerance within which a label states its tick.
    let tol = |v: f64| match step {
        Some(s) => 1e-6 * s,
        None => 1e-9 * v.abs(),
    };
    if plain && step.is_none() {
        // Log ticks differ in magnitude: each its shortest plain form (0.001, 0.01, …, 1000).
        return values
            .iter()
            .map(|&v| {
                minus(
                    (0..=12)
                        .map(|d| format!("{:.*}", d, v))
                        .find(|s| (s.parse::<f64>().unwrap() - v).abs() <= tol(v))
                        .unwrap_or_else(|| format!("{v}")),
                )
            })
            .collect();
    }
    if plain {
        let decimals = (0..=12)
            .find(|&d| {
                values.iter().all(|&v| {
                    (format!("{:.*}", d, clean(v)).parse::<f64>().unwrap() - clean(v)).abs()
                        <= tol(v)
                })
            })
            .unwrap_or(12);
        return values
            .iter()
            .map(|&v| minus(format!("{:.*}", decimals, clean(v))))
            .collect();
    }
    match step {
        Some(step) => {
            // A common exponent: the step's.
            let e = (step.log10() + 1e-9).floor() as i32;
            let scale = 10f64.powi(e);
            let decimals = (0..=12)
                .find(|&d| {
                    values.iter().all(|&v| {
                        let m = clean(v) / scale;
                        (format!("{:.*}", d, m).parse::<f64>().unwrap() - m).abs() * scale <= tol(v)
                    })
                })
                .unwrap_or(12);
            values
                .iter()
                .map(|&v| power_label(format!("{:.*}", decimals, clean(v) / scale), e))
                .collect()
        }
        None => values
            .iter()
            .map(|&v| {
                if v == 0.0 {
                    return "0".to_string();
                }
                let e = (v.abs().log10() + 1e-9).floor() as i32;
                let m = v / 10f64.powi(e);
                let text = (0..=12)
                    .map(|d| format!("{:.*}", d, m))
                    .find(|s| (s.parse::<f64>().unwrap() - m).abs() <= 1e-9 * m.abs())
                    .unwrap_or_else(|| format!("{m}"));
                power_label(text, e)
            })
            .collect(),
    }
}

/// `mantissa×10^e` with a superscript exponent; a mantissa of 1 is left out (`10⁵`), zero
/// is `0`.
fn power_label(mantissa: String, e: i32) -> String {
    let m: f64 = mantissa.parse().unwrap_or(f64::NAN);
    if m == 0.0 {
        "0".to_string()
    } else if m == 1.0 {
        format!("10{}", superscript(e))
    } else if m == -1.0 {
        format!("−10{}", superscript(e))
    } else {
        format!("{}×10{}", minus(mantissa), superscript(e))
    }
}

/// A hyphen-minus replaced by the minus sign.
fn minus(s: String) -> String {
    if let Some(rest) = s.strip_prefix('-') {
        format!("−{rest}")
    } else {
        s
    }
}

const SUPERSCRIPTS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];

#[cfg(test)]
fn is_superscript(c: char) -> bool {
    SUPERSCRIPTS.contains(&c) || c == '⁻'
}

/// `e` in superscript digits (`⁻³`).
fn superscript(e: i32) -> String {
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for d in e.unsigned_abs().to_string().chars() {
        s.push(SUPERSCRIPTS[d.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// The number a label states (the inverse of [`tick_labels`]): plain (`−0.25`) or a power of
/// ten (`2×10⁴`, `10⁻³`, `−10⁵`).
#[cfg(test)]
pub fn label_value(label: &str) -> Option<f64> {
    let s = label.replace('−', "-");
    if !s.chars().any(is_superscript) {
        return s.parse().ok();
    }
    let (mantissa, power) = match s.split_once('×') {
        Some((m, p)) => (m.parse::<f64>().ok()?, p),
        None => match s.strip_prefix('-') {
            Some(p) => (-1.0, p),
            None => (1.0, s.as_str()),
        },
    };
    let exp_text = power.strip_prefix("10")?;
    let (negative, digits) = match exp_text.strip_prefix('⁻') {
        Some(d) => (true, d),
        None => (false, exp_text),
    };
    if digits.is_empty() {
        return None;
    }
    let mut e: i32 = 0;
    for c in digits.chars() {
        e = 10 * e + SUPERSCRIPTS.iter().position(|&d| d == c)? as i32;
    }
    Some(mantissa * 10f64.powi(if negative { -e } else { e }))
}

/// Most labelled ticks on an axis.
pub const MAX_TICKS: usize = 10;

/// A labelled tick set for one axis, at positions in the chart's coordinate (log10 of the
/// value on a log axis).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Ticks {
    pub values: Vec<f64>,
    pub labels: Vec<String>,
}

impl Ticks {
    pub fn of(pairs: Vec<(f64, String)>) -> Ticks {
        let (values, labels) = pairs.into_iter().unzip();
        Ticks { values, labels }
    }

    /// Ticks of an axis over `range` drawn in the coordinate of `scale`: the range itself on a
    /// linear axis, log10 of the values on a log axis (ticks placed at log10 of their values,
    /// labelled with the values).
    pub fn for_axis(range: (f64, f64), scale: AxisScale) -> Ticks {
        match scale {
            AxisScale::Linear => Ticks::of(axis_ticks(range.0, range.1, scale, MAX_TICKS)),
            AxisScale::Log => {
                let pairs = axis_ticks(
                    10f64.powf(range.0),
                    10f64.powf(range.1),
                    AxisScale::Log,
                    MAX_TICKS,
                );
                Ticks::of(pairs.into_iter().map(|(v, l)| (v.log10(), l)).collect())
            }
        }
    }

    /// The label of the tick at `v`.
    pub fn label(&self, v: f64) -> String {
        self.values
            .iter()
            .position(|t| (t - v).abs() <= 1e-9 * t.abs().max(1e-300))
            .map(|i| self.labels[i].clone())
            .unwrap_or_else(|| format!("{v}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use AxisScale::{Linear, Log};

    const MAX: usize = 10;

    /// Every non-degenerate tick set: 2..=max ticks inside the range, increasing, distinct
    /// labels that state their values, one format for the whole axis.
    fn check_ticks(lo: f64, hi: f64, scale: AxisScale, t: &[(f64, String)]) {
        assert!(
            (2..=MAX).contains(&t.len()),
            "[{lo}, {hi}] {scale:?}: {} ticks {t:?}",
            t.len()
        );
        assert!(t.iter().all(|(v, _)| *v >= lo && *v <= hi), "{t:?}");
        assert!(t.windows(2).all(|w| w[0].0 < w[1].0), "{t:?}");
        let spacing = t
            .windows(2)
            .map(|w| w[1].0 - w[0].0)
            .fold(f64::INFINITY, f64::min);
        for (i, (v, label)) in t.iter().enumerate() {
            assert!(
                t[i + 1..].iter().all(|(_, l)| l != label),
                "labels repeat: {t:?}"
            );
            let parsed = label_value(label).unwrap_or_else(|| panic!("'{label}'"));
            assert!(
                (parsed - v).abs() <= 1e-3 * spacing,
                "label '{label}' for {v} (spacing {spacing})"
            );
        }
        let formats: Vec<LabelFormat> = t.iter().filter_map(|(_, l)| label_format(l)).collect();
        assert!(
            formats.windows(2).all(|w| w[0] == w[1]),
            "[{lo}, {hi}] {scale:?}: mixed label formats {t:?}"
        );
    }

    fn labels(lo: f64, hi: f64, scale: AxisScale) -> Vec<String> {
        let t = axis_ticks(lo, hi, scale, MAX);
        check_ticks(lo, hi, scale, &t);
        t.into_iter().map(|p| p.1).collect()
    }

    #[test]
    fn axis_ticks_table() {
        // (lo, hi, scale, expected labels)
        let cases: Vec<(f64, f64, AxisScale, &[&str])> = vec![
            (
                0.0,
                1.0,
                Linear,
                &["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"],
            ),
            (
                -20.6,
                19.9,
                Linear,
                &["−20", "−15", "−10", "−5", "0", "5", "10", "15"],
            ),
            // Up to 1e4: plain.
            (
                0.0,
                9_100.0,
                Linear,
                &[
                    "0", "1000", "2000", "3000", "4000", "5000", "6000", "7000", "8000", "9000",
                ],
            ),
            // Beyond 1e4: every label a power of ten with the step's exponent.
            (
                0.0,
                91_000.0,
                Linear,
                &[
                    "0", "10⁴", "2×10⁴", "3×10⁴", "4×10⁴", "5×10⁴", "6×10⁴", "7×10⁴", "8×10⁴",
                    "9×10⁴",
                ],
            ),
            // A creep-time axis to 15,000 h (step 2000): the step's exponent, integer mantissas.
            (
                0.0,
                15_300.0,
                Linear,
                &[
                    "0", "2×10³", "4×10³", "6×10³", "8×10³", "10×10³", "12×10³", "14×10³",
                ],
            ),
            (
                -1.1e-7,
                1.1e-7,
                Linear,
                &["−10×10⁻⁸", "−5×10⁻⁸", "0", "5×10⁻⁸", "10×10⁻⁸"],
            ),
            // The 560 °C waterfall: minima 0.2527 and 0.3809 within one decade (padded).
            (
                0.2007,
                0.4795,
                Log,
                &["0.25", "0.30", "0.35", "0.40", "0.45"],
            ),
            // 590 °C: minima 1.1252 and 1.1260, padded by 0.1 decade.
            (
                0.8938,
                1.4167,
                Log,
                &["0.9", "1.0", "1.1", "1.2", "1.3", "1.4"],
            ),
            (
                1e-3,
                1e3,
                Log,
                &["0.001", "0.01", "0.1", "1", "10", "100", "1000"],
            ),
            // A rupture-time axis to 1e4 h: plain; one decade more: all powers.
            (50.0, 1.2e4, Log, &["100", "1000", "10000"]),
            (50.0, 2e5, Log, &["10²", "10³", "10⁴", "10⁵"]),
            (1e-5, 0.2, Log, &["10⁻⁵", "10⁻⁴", "10⁻³", "10⁻²", "10⁻¹"]),
            (
                0.05,
                5.0,
                Log,
                &["0.05", "0.1", "0.2", "0.5", "1", "2", "5"],
            ),
            // A stress axis within one decade: linear ticks, not 80, 90, 100 alone.
            (77.0, 131.0, Log, &["80", "90", "100", "110", "120", "130"]),
            (17.0, 160.0, Log, &["20", "50", "100"]),
            (2e3, 6e4, Log, &["2×10³", "5×10³", "10⁴", "2×10⁴", "5×10⁴"]),
        ];
        for (lo, hi, scale, want) in cases {
            assert_eq!(labels(lo, hi, scale), want, "[{lo}, {hi}] {scale:?}");
        }
        // Invariants only.
        for (lo, hi, scale) in [
            (-0.03, 0.97, Linear),
            (1e6, 1e6 + 1.0, Linear),
            (1e-9, 3e-9, Linear),
            (-1e-12, 1e-12, Linear),
            (123.456, 123.457, Linear),
            (1e-31, 1e9, Log),
            (1.1251, 1.1262, Log),
            (3.0e7, 4.5e7, Log),
            (9_000.0, 11_000.0, Linear),
            (0.0005, 0.002, Linear),
        ] {
            labels(lo, hi, scale);
        }
        // Wide log ranges are thinned to at most MAX decades.
        let t = axis_ticks(1e-31, 1e9, Log, MAX);
        assert!(t
            .iter()
            .all(|(v, _)| (v.log10() - v.log10().round()).abs() < 1e-9));
        // Degenerate ranges give no ticks (the plots widen them first).
        assert!(axis_ticks(1.0, 1.0, Linear, 10).is_empty());
        assert!(axis_ticks(f64::NAN, 1.0, Linear, 10).is_empty());
        assert!(axis_ticks(0.0, 1.0, Log, 10).is_empty());
    }

    #[test]
    fn labels_never_mix_plain_and_powers() {
        // The three forms the old labels mixed on one log axis (1000, 10000, 1e5).
        let l = tick_labels(&[1e3, 1e4, 1e5], None);
        assert_eq!(l, ["10³", "10⁴", "10⁵"]);
        let l = tick_labels(&[1e3, 1e4], None);
        assert_eq!(l, ["1000", "10000"]);
        // A tick below PLAIN_MIN turns the whole axis to powers.
        let l = tick_labels(&[5e-4, 1e-3, 1.5e-3], Some(5e-4));
        assert_eq!(l, ["5×10⁻⁴", "10×10⁻⁴", "15×10⁻⁴"]);
    }

    #[test]
    fn label_values_round_trip() {
        for (label, v) in [
            ("0", 0.0),
            ("−2.5", -2.5),
            ("10⁵", 1e5),
            ("−10⁵", -1e5),
            ("2×10⁴", 2e4),
            ("−5×10⁻⁸", -5e-8),
            ("1.5×10¹²", 1.5e12),
        ] {
            let got = label_value(label).unwrap();
            assert!((got - v).abs() <= 1e-12 * v.abs(), "{label}: {got}");
        }
        assert_eq!(label_value("10"), Some(10.0));
        assert_eq!(label_value("×10⁵"), None);
        assert!((label_value("10000001×10⁻¹").unwrap() - 1000000.1).abs() < 1e-6);
        assert_eq!(label_format("0"), None);
        assert_eq!(label_format("1000"), Some(LabelFormat::Plain));
        assert_eq!(label_format("10⁻³"), Some(LabelFormat::Power));
    }
}
