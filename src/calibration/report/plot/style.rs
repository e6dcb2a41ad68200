//! Colours, the styles series are drawn in, and legend entries whose swatch is the series'
//! own style (a dashed line gets a dashed swatch, points get a point), laid out so that no
//! entry is ever left out.

use plotters::style::{FontDesc, RGBColor};

use super::canvas::{ensure_font, FONT};

/// A colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rgb(pub u8, pub u8, pub u8);

/// Tableau 10.
const PALETTE: [Rgb; 10] = [
    Rgb(31, 119, 180),
    Rgb(255, 127, 14),
    Rgb(44, 160, 44),
    Rgb(214, 39, 40),
    Rgb(148, 103, 189),
    Rgb(140, 86, 75),
    Rgb(227, 119, 194),
    Rgb(127, 127, 127),
    Rgb(188, 189, 34),
    Rgb(23, 190, 207),
];

/// Anchors of the temperature scale, cool (dark blue) to hot (dark red), each dark enough
/// to read on white.
const RAMP: [Rgb; 8] = [
    Rgb(49, 54, 149),
    Rgb(69, 117, 180),
    Rgb(0, 150, 150),
    Rgb(77, 146, 33),
    Rgb(200, 140, 0),
    Rgb(235, 90, 20),
    Rgb(210, 40, 40),
    Rgb(120, 0, 40),
];

impl Rgb {
    pub const BLACK: Rgb = Rgb(0, 0, 0);
    pub const RED: Rgb = Rgb(214, 39, 40);

    /// The `i`-th colour of the categorical palette (Tableau 10, cycled).
    pub fn palette(i: usize) -> Rgb {
        PALETTE[i % PALETTE.len()]
    }

    /// The temperature scale at `t` ∈ [0, 1] (0 cool, 1 hot), interpolated between its anchors.
    pub fn ramp(t: f64) -> Rgb {
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let x = t * (RAMP.len() - 1) as f64;
        let i = (x.floor() as usize).min(RAMP.len() - 2);
        let f = x - i as f64;
        let (a, b) = (RAMP[i], RAMP[i + 1]);
        let lerp = |p: u8, q: u8| (p as f64 + (q as f64 - p as f64) * f).round() as u8;
        Rgb(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
    }

    pub(super) fn rgb(self) -> RGBColor {
        RGBColor(self.0, self.1, self.2)
    }
}

/// The colour of each temperature of `temperatures` (°C) on the cool-to-hot scale: the
/// distinct temperatures evenly spaced over the scale by rank (so 4 temperatures get 4
/// well-separated colours whatever their spacing), equal temperatures the same colour.
pub fn temperature_colors(temperatures: &[f64]) -> Vec<Rgb> {
    let mut distinct: Vec<f64> = temperatures.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup_by(|a, b| a.total_cmp(b).is_eq());
    let n = distinct.len();
    temperatures
        .iter()
        .map(|t| {
            let rank = distinct
                .iter()
                .position(|d| d.total_cmp(t).is_eq())
                .unwrap_or(0);
            Rgb::ramp(if n > 1 {
                rank as f64 / (n - 1) as f64
            } else {
                0.0
            })
        })
        .collect()
}

/// How a line is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    Solid,
    Dashed,
    Dotted,
}

/// A line's stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    pub width: u32,
    pub dash: Dash,
    /// 1 = opaque.
    pub opacity: f64,
}

/// The shape of markers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MarkerShape {
    /// A filled circle.
    #[default]
    Circle,
    /// An open circle (e.g. tests held out of a fit).
    OpenCircle,
    /// A filled triangle (e.g. asked conditions beside measurements, failed fits).
    Triangle,
    /// A filled triangle pointing right: a curve continues beyond the axes.
    Arrow,
}

/// Markers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Marker {
    pub shape: MarkerShape,
    /// Radius, px.
    pub size: u32,
}

/// How a series is drawn: its colour, line (if any) and markers (if any).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Style {
    pub color: Rgb,
    pub line: Option<Line>,
    pub marker: Option<Marker>,
}

impl Style {
    /// A solid line of `width` px.
    pub fn line(color: Rgb, width: u32) -> Style {
        Style {
            color,
            line: Some(Line {
                width,
                dash: Dash::Solid,
                opacity: 1.0,
            }),
            marker: None,
        }
    }
    /// A dashed line of `width` px.
    pub fn dashed(color: Rgb, width: u32) -> Style {
        Style {
            color,
            line: Some(Line {
                width,
                dash: Dash::Dashed,
                opacity: 1.0,
            }),
            marker: None,
        }
    }
    /// Markers of `shape` and radius `size` px.
    pub fn points(color: Rgb, shape: MarkerShape, size: u32) -> Style {
        Style {
            color,
            line: None,
            marker: Some(Marker { shape, size }),
        }
    }
    /// This style with markers added.
    pub fn with_marker(mut self, shape: MarkerShape, size: u32) -> Style {
        self.marker = Some(Marker { shape, size });
        self
    }
}

/// The symbol of a legend entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Swatch {
    /// The style a series is drawn in: its line (solid, dashed or dotted) and its marker.
    Style(Style),
    /// Two circles: a range of colours.
    Range(Rgb, Rgb),
    /// No symbol: a note.
    Blank,
}

/// One legend entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub label: String,
    pub swatch: Swatch,
}

impl Entry {
    pub fn new(label: impl Into<String>, swatch: Swatch) -> Entry {
        Entry {
            label: label.into(),
            swatch,
        }
    }
    /// An entry whose swatch is `style`.
    pub fn styled(label: impl Into<String>, style: Style) -> Entry {
        Entry::new(label, Swatch::Style(style))
    }
    /// A note without symbol.
    pub fn note(label: impl Into<String>) -> Entry {
        Entry::new(label, Swatch::Blank)
    }
}

/// Legend text size, px.
pub const LEGEND_SIZE: f64 = 16.0;
/// Height of one legend text line, px.
pub const LEGEND_LINE: i32 = LEGEND_SIZE as i32 + 5;
/// Gap after each entry, px.
const ENTRY_GAP: i32 = 5;
/// Padding inside the legend box above the first and below the last entry, px.
const BOX_PAD: i32 = 8;
/// Left of the text within the legend box (the swatch is before it), px.
pub const TEXT_X: i32 = 48;

/// Every legend entry wrapped to the legend's width: the text lines of each entry, in order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LegendLayout {
    pub entries: Vec<Vec<String>>,
}

impl LegendLayout {
    /// Lays out `entries` for a legend `width` px wide: each label wrapped at spaces to the
    /// width left for text (a longer word stands alone). No entry is left out.
    pub fn new(entries: &[Entry], width: u32) -> LegendLayout {
        let text_w = (width as i32 - TEXT_X - 12).max(40) as u32;
        LegendLayout {
            entries: entries.iter().map(|e| wrap(&e.label, text_w)).collect(),
        }
    }

    /// Height of the legend box, px (0 without entries).
    pub fn height(&self) -> i32 {
        if self.entries.is_empty() {
            return 0;
        }
        let lines: i32 = self.entries.iter().map(|l| l.len() as i32).sum();
        2 * BOX_PAD + lines * LEGEND_LINE + self.entries.len() as i32 * ENTRY_GAP
    }

    /// The top of each entry's first line within the box, px.
    pub fn tops(&self) -> Vec<i32> {
        let mut y = BOX_PAD;
        self.entries
            .iter()
            .map(|l| {
                let top = y;
                y += l.len() as i32 * LEGEND_LINE + ENTRY_GAP;
                top
            })
            .collect()
    }
}

/// Width of `text` in the legend font, px (a generous estimate if the font cannot measure).
pub fn text_width(text: &str) -> u32 {
    let estimate = || (0.62 * LEGEND_SIZE * text.chars().count() as f64).ceil() as u32;
    if ensure_font().is_err() {
        return estimate();
    }
    FontDesc::from((FONT, LEGEND_SIZE))
        .box_size(text)
        .map(|(w, _)| w)
        .unwrap_or_else(|_| estimate())
}

/// Greedy word wrap of `text` to lines at most `width` px wide (a longer word stands alone).
pub fn wrap(text: &str, width: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut current = String::new();
    for word in text.split_whitespace() {
        let candidate = if current.is_empty() {
            word.to_string()
        } else {
            format!("{current} {word}")
        };
        if current.is_empty() || text_width(&candidate) <= width {
            current = candidate;
        } else {
            lines.push(std::mem::replace(&mut current, word.to_string()));
        }
    }
    if !current.is_empty() || lines.is_empty() {
        lines.push(current);
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temperature_colors_are_ordered_distinct_and_shared() {
        let temps = [850.0, 750.0, 950.0, 900.0, 850.0];
        let c = temperature_colors(&temps);
        assert_eq!(c[0], c[4], "equal temperatures, equal colours");
        assert_eq!(c[1], RAMP[0], "the coolest is the scale's start");
        assert_eq!(c[2], RAMP[7], "the hottest its end");
        let distinct: Vec<Rgb> = vec![c[1], c[0], c[3], c[2]];
        for (i, a) in distinct.iter().enumerate() {
            for b in &distinct[i + 1..] {
                let d = (a.0 as i32 - b.0 as i32).abs()
                    + (a.1 as i32 - b.1 as i32).abs()
                    + (a.2 as i32 - b.2 as i32).abs();
                assert!(d > 80, "{a:?} and {b:?} too alike");
            }
        }
        assert_eq!(temperature_colors(&[600.0]), vec![RAMP[0]]);
        assert!(temperature_colors(&[]).is_empty());
        assert_eq!(Rgb::ramp(0.5), {
            let (a, b) = (RAMP[3], RAMP[4]);
            let m = |p: u8, q: u8| ((p as f64 + q as f64) / 2.0).round() as u8;
            Rgb(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
        });
    }

    #[test]
    fn legend_layout_keeps_every_word_of_every_entry() {
        let entries: Vec<Entry> = (0..40)
            .map(|i| {
                Entry::styled(
                    format!(
                        "850 °C, {} MPa, specimen KAERI2-{i} with a long name",
                        20 + i
                    ),
                    Style::line(Rgb::palette(i), 2),
                )
            })
            .collect();
        let layout = LegendLayout::new(&entries, 250);
        assert_eq!(layout.entries.len(), 40);
        for (e, lines) in entries.iter().zip(&layout.entries) {
            assert_eq!(lines.join(" "), e.label);
            assert!(lines.len() >= 2, "a long label wraps: {lines:?}");
            for l in lines.iter().filter(|l| l.contains(' ')) {
                assert!(text_width(l) <= 250 - TEXT_X as u32 - 12, "{l}");
            }
        }
        // The height grows with the entries: 40 entries cannot fit in 700 px.
        assert!(layout.height() > 700, "{}", layout.height());
        let tops = layout.tops();
        assert!(tops.windows(2).all(|w| w[1] > w[0]));
        assert!(*tops.last().unwrap() < layout.height());
        assert_eq!(LegendLayout::new(&[], 250).height(), 0);
    }

    #[test]
    fn text_is_measured_with_the_font() {
        let short = text_width("30 MPa");
        let long = text_width("30 MPa, 850 °C, KAERI2-a");
        assert!(short > 20 && long > 2 * short, "{short} {long}");
    }
}
