//! Drawing: the embedded font, the figure's layout (one panel, or a grid of panels each with
//! its own legend), panels drawn from a [`PanelSpec`], and the PNG written atomically with
//! any drawing failure or plotters panic returned as [`Error::Plot`].

use std::cell::RefCell;
use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::OnceLock;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ColorType, ImageEncoder};
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

use super::geom::{clip_polyline, inside};
use super::style::{
    Dash, Entry, LegendLayout, MarkerShape, Rgb, Style, Swatch, LEGEND_LINE, LEGEND_SIZE, TEXT_X,
};
use super::ticks::Ticks;
use crate::error::{Error, Result};
use crate::output;

/// Width of a one-panel image, px.
pub const WIDTH: u32 = 1200;
/// Least height of a one-panel image, px (more when its legend needs it).
pub const HEIGHT: u32 = 700;
/// Width of the legend panel right of a one-panel chart, px.
pub const LEGEND_WIDTH: u32 = 250;
/// Width of one panel of a grid, px (its chart and its legend).
pub const PANEL_WIDTH: u32 = 900;
/// Least height of one panel of a grid, px (more when its legend needs it).
pub const PANEL_HEIGHT: u32 = 420;
/// Width of the legend of a grid's panel, px.
pub const PANEL_LEGEND_WIDTH: u32 = 290;

/// The embedded font (DejaVu Sans, see `assets/DejaVu-LICENSE.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../../../assets/DejaVuSans.ttf");
/// The family name under which the embedded font is registered and used.
pub const FONT: &str = "sans-serif";

const TITLE_SIZE: f64 = 28.0;
const CAPTION_SIZE: f64 = 21.0;
const AXIS_DESC_SIZE: f64 = 20.0;
const TICK_SIZE: f64 = 16.0;
/// Height of the band holding the image's title, px (a thin margin without a title).
const TITLE_BAND: u32 = 50;
const NO_TITLE_BAND: u32 = 12;
/// Height of the band holding a panel's caption, px.
const CAPTION_BAND: u32 = 34;
/// Top of the legend box within its panel's legend area, px.
const LEGEND_TOP: i32 = 12;

/// Registers the embedded font once; the result of the first attempt is kept.
pub fn ensure_font() -> std::result::Result<(), String> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            // "sans-serif" is what we use; the other generic families are registered too so
            // that any default text style inside plotters also finds a font.
            for family in [FONT, "serif", "monospace"] {
                register_font(family, FontStyle::Normal, FONT_BYTES)
                    .map_err(|_| "the embedded font DejaVuSans.ttf cannot be parsed".to_string())?;
            }
            Ok(())
        })
        .clone()
}

/// One axis of a panel: its range and ticks in the chart's coordinate (log10 of the values
/// on a log axis) and its description.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Axis {
    pub range: (f64, f64),
    pub ticks: Ticks,
    pub desc: String,
}

/// A series as drawn: a polyline and markers in one style, in the chart's coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    pub line: Vec<(f64, f64)>,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
}

/// A text in the chart's coordinates, anchored by its right end and top or bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    pub text: String,
    pub at: (f64, f64),
    /// Below the point (else above it).
    pub below: bool,
    pub color: Rgb,
}

/// Everything one panel draws: caption, axes, series, texts and legend entries.
#[derive(Debug, Clone, PartialEq)]
pub struct PanelSpec {
    pub caption: String,
    pub x: Axis,
    pub y: Axis,
    pub layers: Vec<Layer>,
    pub labels: Vec<Label>,
    pub entries: Vec<Entry>,
    /// Nothing to draw: the panel says "no data".
    pub no_data: bool,
}

/// A pixel rectangle of the image: (x0, x1), (y0, y1).
pub type PxRect = ((i32, i32), (i32, i32));

/// What a figure drew, for tests: its size and per panel the tick labels plotters formatted,
/// the axis ranges, the pixel rectangles of the plotting area and of the legend box, and
/// the legend's text (each entry's lines joined).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Drawn {
    pub size: (u32, u32),
    pub panels: Vec<PanelDrawn>,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub struct PanelDrawn {
    pub caption: String,
    pub x_labels: Vec<String>,
    pub y_labels: Vec<String>,
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    pub plot_px: PxRect,
    pub legend_px: Option<PxRect>,
    pub legend: Vec<String>,
}

/// The arrangement of a figure: image size, columns of the grid, size of each panel and
/// width of each panel's legend, px.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    pub size: (u32, u32),
    pub cols: usize,
    pub panel: (u32, u32),
    pub legend_w: u32,
    pub title_band: u32,
}

/// Width of the legend of each of `n` panels, px.
pub fn legend_width(n: usize) -> u32 {
    if n <= 1 {
        LEGEND_WIDTH
    } else {
        PANEL_LEGEND_WIDTH
    }
}

/// The layout of `n` panels whose tallest legend box is `legend_h` px: one panel is
/// [`WIDTH`] × [`HEIGHT`]; more go in a grid of 2 columns (up to 8 panels), 3 (up to 18) or 4,
/// each [`PANEL_WIDTH`] × [`PANEL_HEIGHT`]. Panels grow taller when a legend needs it, so
/// every legend fits beside its chart.
pub fn layout(n: usize, legend_h: i32, titled: bool) -> Layout {
    let title_band = if titled { TITLE_BAND } else { NO_TITLE_BAND };
    // The caption band, the legend's top offset and a margin below it.
    let need = (CAPTION_BAND as i32 + LEGEND_TOP + legend_h.max(0) + 12) as u32;
    if n <= 1 {
        let panel_h = (HEIGHT - title_band).max(need);
        return Layout {
            size: (WIDTH, title_band + panel_h),
            cols: 1,
            panel: (WIDTH, panel_h),
            legend_w: legend_width(1),
            title_band,
        };
    }
    let cols = if n <= 8 {
        2
    } else if n <= 18 {
        3
    } else {
        4
    };
    let rows = n.div_ceil(cols) as u32;
    let panel_h = PANEL_HEIGHT.max(need);
    Layout {
        size: (cols as u32 * PANEL_WIDTH, title_band + rows * panel_h),
        cols,
        panel: (PANEL_WIDTH, panel_h),
        legend_w: legend_width(n),
        title_band,
    }
}

/// Draws `panels` (the exporters always give at least one) into a PNG at `path` under
/// `title`, laid out by [`layout`].
pub fn draw_figure(path: &Path, title: &str, panels: &[PanelSpec]) -> Result<Drawn> {
    ensure_font().map_err(|m| Error::plot(path, m))?;
    let lw = legend_width(panels.len());
    let legends: Vec<LegendLayout> = panels
        .iter()
        .map(|p| LegendLayout::new(&p.entries, lw))
        .collect();
    let tallest = legends.iter().map(|l| l.height()).max().unwrap_or(0);
    let lay = layout(panels.len(), tallest, !title.trim().is_empty());
    render(path, title, lay, |body| {
        let mut drawn = Vec::new();
        for (k, (spec, legend)) in panels.iter().zip(&legends).enumerate() {
            let (col, row) = ((k % lay.cols) as i32, (k / lay.cols) as i32);
            let (pw, ph) = lay.panel;
            let area = body
                .clone()
                .shrink((col * pw as i32, row * ph as i32), (pw, ph));
            drawn.push(draw_panel(&area, spec, lay.legend_w, legend)?);
        }
        Ok(drawn)
    })
}

type DrawResult<T = ()> = std::result::Result<T, Box<dyn std::error::Error>>;
type Root<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Draws into an in-memory RGB buffer (catching panics) and only then writes the PNG, so a
/// failed plot leaves no half-drawn file behind. The title goes across the top; `draw` gets
/// the area below it.
pub fn render<F>(path: &Path, title: &str, lay: Layout, draw: F) -> Result<Drawn>
where
    F: FnOnce(&Root<'_>) -> DrawResult<Vec<PanelDrawn>>,
{
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(Error::plot(path, "the file name must end in .png"));
    }
    ensure_font().map_err(|m| Error::plot(path, m))?;

    let (w, h) = lay.size;
    let mut buffer = vec![255u8; (w * h * 3) as usize];
    let mut panels = Vec::new();
    let result = catch_unwind(AssertUnwindSafe(|| -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(lay.title_band);
        if !title.trim().is_empty() {
            top.draw(&Text::new(
                title.to_string(),
                (w as i32 / 2, lay.title_band as i32 / 2 + 3),
                TextStyle::from((FONT, TITLE_SIZE)).pos(Pos::new(HPos::Center, VPos::Center)),
            ))?;
        }
        panels = draw(&body)?;
        root.present()?;
        Ok(())
    }));
    match result {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(Error::plot(path, e.to_string())),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".to_string());
            return Err(Error::plot(path, format!("panic while drawing: {what}")));
        }
    }

    // Encoded into a temporary file beside `path` and renamed into place: the old PNG or
    // the new one, never a truncated one (crate::output).
    let plot_err = |e: Error| match e {
        Error::Io { err, .. } => Error::plot(path, err.to_string()),
        other => Error::plot(path, other.to_string()),
    };
    let tmp = output::temp_beside(path, ".png").map_err(plot_err)?;
    let mut file = std::io::BufWriter::new(tmp.as_file());
    PngEncoder::new_with_quality(&mut file, CompressionType::Default, FilterType::Adaptive)
        .write_image(&buffer, w, h, ColorType::Rgb8)
        .map_err(|e| Error::plot(path, e.to_string()))?;
    file.flush().map_err(|e| Error::plot(path, e.to_string()))?;
    drop(file);
    let len = tmp.as_file().metadata().map(|m| m.len()).unwrap_or(0);
    output::charge(len as usize).map_err(|e| Error::plot(path, e.to_string()))?;
    output::persist(tmp, path).map_err(plot_err)?;
    Ok(Drawn {
        size: lay.size,
        panels,
    })
}

type LinearChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<FixedTicks<RangedCoordf64>, FixedTicks<RangedCoordf64>>,
>;

/// One panel: caption above the chart, the chart, its legend box at the right.
fn draw_panel(
    area: &Root<'_>,
    spec: &PanelSpec,
    legend_w: u32,
    legend: &LegendLayout,
) -> DrawResult<PanelDrawn> {
    let (w, _) = area.dim_in_pixel();
    let chart_w = w.saturating_sub(legend_w).max(1);
    let body = if spec.caption.is_empty() {
        area.clone()
    } else {
        let (band, body) = area.split_vertically(CAPTION_BAND);
        // Centred over the plotting area (right of the ~90 px of y labels).
        band.draw(&Text::new(
            spec.caption.clone(),
            (chart_w as i32 / 2 + 40, CAPTION_BAND as i32 / 2 + 2),
            TextStyle::from((FONT, CAPTION_SIZE)).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        body
    };
    let (chart_area, legend_area) = body.split_horizontally(chart_w);
    let (x, y) = (spec.x.range, spec.y.range);
    let mut chart: LinearChart = ChartBuilder::on(&chart_area)
        .margin(12)
        .margin_right(14)
        .x_label_area_size(58)
        .y_label_area_size(92)
        .build_cartesian_2d(
            FixedTicks::new(RangedCoordf64::from(x.0..x.1), spec.x.ticks.values.clone()),
            FixedTicks::new(RangedCoordf64::from(y.0..y.1), spec.y.ticks.values.clone()),
        )?;
    let (x_labels, y_labels) = configure_mesh(&mut chart, &spec.x, &spec.y)?;
    for layer in &spec.layers {
        draw_layer(&mut chart, layer, x, y)?;
    }
    for l in &spec.labels {
        let pos = Pos::new(HPos::Right, if l.below { VPos::Top } else { VPos::Bottom });
        chart.plotting_area().draw(&Text::new(
            l.text.clone(),
            l.at,
            TextStyle::from((FONT, 14)).color(&l.color.rgb()).pos(pos),
        ))?;
    }
    if spec.no_data {
        chart.plotting_area().draw(&Text::new(
            "no data",
            (0.5 * x.0 + 0.5 * x.1, 0.5 * y.0 + 0.5 * y.1),
            TextStyle::from((FONT, 26)).pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
    }
    let plot_px = pixel_rect(chart.plotting_area());
    let legend_px = draw_legend(&legend_area, &spec.entries, legend)?;
    Ok(PanelDrawn {
        caption: spec.caption.clone(),
        x_labels,
        y_labels,
        x_range: x,
        y_range: y,
        plot_px,
        legend_px,
        legend: legend.entries.iter().map(|l| l.join(" ")).collect(),
    })
}

/// A layer's line (clipped to the axes, broken at non-plottable points) and its markers
/// (those inside the axes).
fn draw_layer(
    chart: &mut LinearChart<'_, '_>,
    layer: &Layer,
    x: (f64, f64),
    y: (f64, f64),
) -> DrawResult {
    let color = layer.style.color.rgb();
    if let Some(line) = layer.style.line {
        let style = color.mix(line.opacity).stroke_width(line.width);
        for piece in clip_polyline(&layer.line, x, y) {
            match line.dash {
                Dash::Solid => {
                    chart.draw_series(std::iter::once(PathElement::new(piece, style)))?;
                }
                Dash::Dashed => {
                    chart.draw_series(DashedLineSeries::new(piece, 10, 6, style))?;
                }
                Dash::Dotted => {
                    chart.draw_series(DashedLineSeries::new(piece, 3, 4, style))?;
                }
            }
        }
    }
    if let Some(m) = layer.style.marker {
        let pts = inside(&layer.points, x, y);
        let r = m.size as i32;
        match m.shape {
            MarkerShape::Circle => {
                chart.draw_series(pts.map(|p| Circle::new(p, r, color.filled())))?;
            }
            MarkerShape::OpenCircle => {
                chart.draw_series(pts.map(|p| Circle::new(p, r, color.stroke_width(2))))?;
            }
            MarkerShape::Triangle => {
                chart.draw_series(pts.map(|p| TriangleMarker::new(p, r, color.filled())))?;
            }
            MarkerShape::Arrow => {
                chart.draw_series(
                    pts.map(|p| EmptyElement::at(p) + Polygon::new(arrow(r), color.filled())),
                )?;
            }
        }
    }
    Ok(())
}

/// A right-pointing triangle of radius `r` about the origin, px.
fn arrow(r: i32) -> Vec<(i32, i32)> {
    vec![(-r / 2, -r), (r + r / 2, 0), (-r / 2, r)]
}

fn pixel_rect<DB: DrawingBackend, CT: CoordTranslate>(area: &DrawingArea<DB, CT>) -> PxRect {
    let (x, y) = area.get_pixel_range();
    ((x.start, x.end), (y.start, y.end))
}

/// Axis descriptions and the tick labels (returned as plotters asks for them, each once),
/// with grid lines at the ticks.
fn configure_mesh(
    chart: &mut LinearChart<'_, '_>,
    x: &Axis,
    y: &Axis,
) -> DrawResult<(Vec<String>, Vec<String>)> {
    let seen_x = RefCell::new(Vec::new());
    let seen_y = RefCell::new(Vec::new());
    let fx = |v: &f64| {
        let s = x.ticks.label(*v);
        seen_x.borrow_mut().push(s.clone());
        s
    };
    let fy = |v: &f64| {
        let s = y.ticks.label(*v);
        seen_y.borrow_mut().push(s.clone());
        s
    };
    chart
        .configure_mesh()
        .x_desc(x.desc.as_str())
        .y_desc(y.desc.as_str())
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .axis_desc_style((FONT, AXIS_DESC_SIZE))
        .label_style((FONT, TICK_SIZE))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(BLACK.mix(0.0))
        .draw()?;
    let unique = |v: Vec<String>| {
        let mut out: Vec<String> = Vec::new();
        for s in v {
            if !out.contains(&s) {
                out.push(s);
            }
        }
        out
    };
    Ok((unique(seen_x.into_inner()), unique(seen_y.into_inner())))
}

/// Draws every legend entry (a swatch and the wrapped label) in a light box at the top of
/// `area`; returns the box's pixel rectangle.
fn draw_legend(
    area: &Root<'_>,
    entries: &[Entry],
    layout: &LegendLayout,
) -> DrawResult<Option<PxRect>> {
    if entries.is_empty() {
        return Ok(None);
    }
    let (w, _) = area.dim_in_pixel();
    let (x0, x1) = (4, w as i32 - 6);
    let (y0, y1) = (LEGEND_TOP, LEGEND_TOP + layout.height());
    area.draw(&Rectangle::new(
        [(x0, y0), (x1, y1)],
        WHITE.mix(0.9).filled(),
    ))?;
    area.draw(&Rectangle::new(
        [(x0, y0), (x1, y1)],
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    let style = TextStyle::from((FONT, LEGEND_SIZE)).pos(Pos::new(HPos::Left, VPos::Center));
    for ((entry, lines), top) in entries.iter().zip(&layout.entries).zip(layout.tops()) {
        let yc = y0 + top + LEGEND_LINE / 2;
        draw_swatch(area, entry.swatch, (26, yc))?;
        for (j, line) in lines.iter().enumerate() {
            area.draw(&Text::new(
                line.clone(),
                (TEXT_X, yc + j as i32 * LEGEND_LINE),
                style.clone(),
            ))?;
        }
    }
    let ((ax, _), (ay, _)) = pixel_rect(area);
    Ok(Some(((ax + x0, ax + x1), (ay + y0, ay + y1))))
}

/// The swatch of a legend entry, centred at (x, y) px: the entry's own line (solid, dashed
/// or dotted, 32 px long) and marker.
fn draw_swatch(area: &Root<'_>, swatch: Swatch, (x, y): (i32, i32)) -> DrawResult {
    match swatch {
        Swatch::Style(s) => {
            let color = s.color.rgb();
            if let Some(line) = s.line {
                let style = color.mix(line.opacity).stroke_width(line.width);
                let dashes: &[(i32, i32)] = match line.dash {
                    Dash::Solid => &[(-16, 16)],
                    Dash::Dashed => &[(-16, -8), (-4, 4), (8, 16)],
                    Dash::Dotted => &[(-16, -14), (-10, -8), (-4, -2), (2, 4), (8, 10), (14, 16)],
                };
                for &(a, b) in dashes {
                    area.draw(&PathElement::new(vec![(x + a, y), (x + b, y)], style))?;
                }
            }
            if let Some(m) = s.marker {
                let r = m.size as i32;
                match m.shape {
                    MarkerShape::Circle => area.draw(&Circle::new((x, y), r, color.filled()))?,
                    MarkerShape::OpenCircle => {
                        area.draw(&Circle::new((x, y), r, color.stroke_width(2)))?
                    }
                    MarkerShape::Triangle => {
                        area.draw(&TriangleMarker::new((x, y), r, color.filled()))?
                    }
                    MarkerShape::Arrow => area.draw(
                        &(EmptyElement::at((x, y)) + Polygon::new(arrow(r), color.filled())),
                    )?,
                }
            }
        }
        Swatch::Range(a, b) => {
            area.draw(&Circle::new((x - 8, y), 4, a.rgb().filled()))?;
            area.draw(&Circle::new((x + 8, y), 4, b.rgb().filled()))?;
        }
        Swatch::Blank => {}
    }
    Ok(())
}

/// An f64 axis whose ticks (and grid lines) are exactly the given values, with no light grid
/// lines. (plotters' `with_key_points` cannot be used with `configure_mesh` for f64 axes.)
struct FixedTicks<C> {
    inner: C,
    ticks: Vec<f64>,
}

impl<C: Ranged<ValueType = f64>> FixedTicks<C> {
    fn new(inner: C, ticks: Vec<f64>) -> Self {
        let r = inner.range();
        let (lo, hi) = (r.start.min(r.end), r.start.max(r.end));
        FixedTicks {
            inner,
            ticks: ticks
                .into_iter()
                .filter(|t| (lo..=hi).contains(t))
                .collect(),
        }
    }
}

impl<C: Ranged<ValueType = f64>> Ranged for FixedTicks<C> {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
}

impl<C: Ranged<ValueType = f64>> ValueFormatter<f64> for FixedTicks<C> {
    fn format(value: &f64) -> String {
        format!("{value}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tempfile::TempDir;

    #[test]
    fn layouts_fit_every_legend() {
        let one = layout(1, 200, true);
        assert_eq!(one.size, (WIDTH, HEIGHT));
        assert_eq!(one.cols, 1);
        // A legend taller than the image: the image grows to hold it.
        let tall = layout(1, 1500, true);
        assert!(tall.size.1 >= TITLE_BAND + CAPTION_BAND + LEGEND_TOP as u32 + 1500);
        // Eight panels: 2 columns, 4 rows.
        let eight = layout(8, 200, true);
        assert_eq!(eight.cols, 2);
        assert_eq!(eight.size, (2 * PANEL_WIDTH, TITLE_BAND + 4 * PANEL_HEIGHT));
        assert_eq!(layout(9, 0, true).cols, 3);
        assert_eq!(layout(19, 0, false).cols, 4);
        for (n, h) in [(1, 0), (1, 5000), (3, 800), (8, 100), (20, 2000)] {
            let l = layout(n, h, true);
            assert!(
                CAPTION_BAND as i32 + LEGEND_TOP + h <= l.panel.1 as i32,
                "{n} panels, legend {h} px: {l:?}"
            );
            let rows = n.div_ceil(l.cols) as u32;
            assert_eq!(l.size.1, l.title_band + rows * l.panel.1);
        }
    }

    #[test]
    fn drawing_errors_and_panics_become_errors() {
        let dir = TempDir::new().unwrap();
        let path = dir.path().join("boom.png");
        let lay = layout(1, 0, false);
        let err = render(&path, "", lay, |_| panic!("inside plotters")).unwrap_err();
        assert!(err.to_string().contains("inside plotters"), "{err}");
        let err = render(&path, "", lay, |_| Err("drawing failed".into())).unwrap_err();
        assert!(err.to_string().contains("drawing failed"), "{err}");
        assert!(!path.exists(), "no file is written for a failed plot");
    }
}
