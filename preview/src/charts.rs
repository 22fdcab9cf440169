//! Charts drawn as SVG with plotters and rasterised to PNG with resvg: panels on a grid, each
//! with one line per series (mean points with min–max bars), loose points, dashed horizontal
//! levels and a Pareto step front, ticks written in the units people read ([`crate::units`]),
//! the legend in the emptiest corner. `frond sweep` chooses what to chart; this module only
//! draws what it is given.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use resvg::{tiny_skia, usvg};

use crate::units;

/// A mean point of a line: (x, y) with the (min, max) of y when it is the mean of several
/// values (drawn as a vertical error bar), or `None` for a single value.
pub type MeanPoint = (f64, f64, Option<(f64, f64)>);

/// A colour as red, green and blue in 0–255, so callers need not depend on plotters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// The same colour as plotters draws it.
    fn plotters(self) -> RGBColor {
        RGBColor(self.0, self.1, self.2)
    }
}

/// The colours series take in turn: eight of matplotlib's "tab10" colours (its grey and olive
/// left out), which stay apart on white.
pub const PALETTE: [Rgb; 8] = [
    Rgb(31, 119, 180),
    Rgb(214, 39, 40),
    Rgb(44, 160, 44),
    Rgb(148, 103, 189),
    Rgb(255, 127, 14),
    Rgb(23, 190, 207),
    Rgb(140, 86, 75),
    Rgb(227, 119, 194),
];

/// One line or point set of a panel, with its entry in the legend.
#[derive(Clone, Debug)]
pub struct Series {
    /// The name in the legend (a method or candidate).
    pub name: String,
    /// The colour of its line, bars, points, labels and level.
    pub color: Rgb,
    /// Points joined by a line (x sorted), each with an optional (min, max) bar.
    pub line: Vec<MeanPoint>,
    /// A label beside each point of `line` (e.g. its screen height), or none.
    pub labels: Vec<String>,
    /// Loose points: hollow and faint behind a line, filled when the series has no line.
    pub points: Vec<(f64, f64)>,
    /// A label beside each loose point when the series has no line, or none.
    pub point_labels: Vec<String>,
    /// A dashed horizontal line across the panel at this y (a value with no x to plot it at).
    pub level: Option<f64>,
}

/// One chart panel: its axes and what is drawn on them.
#[derive(Clone, Debug)]
pub struct Panel {
    /// The caption above the plot.
    pub title: String,
    /// The x axis's description ("(log scale)" is appended when `x_log`).
    pub x_label: String,
    /// The y axis's description.
    pub y_label: String,
    /// Whether x is drawn on a log10 scale (values must be positive), with ticks at round
    /// numbers ([`log_ticks`]) or powers of two for bytes.
    pub x_log: bool,
    /// How the x axis's ticks are written.
    pub x_unit: Unit,
    /// How the y axis's ticks are written.
    pub y_unit: Unit,
    /// The series, drawn in order (later ones on top) and listed in the legend.
    pub series: Vec<Series>,
    /// The Pareto front, x increasing: drawn as a step line with ringed points.
    pub front: Vec<(f64, f64)>,
}

/// How an axis's ticks are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// A plain number ([`tick`]).
    Plain,
    /// Bytes, as KB and MB ([`units::bytes`]); a log axis of bytes ticks at powers of two.
    Bytes,
    /// Seconds, as ms and s ([`units::duration`]).
    Seconds,
}

impl Unit {
    /// The text of a tick at `v` on an axis of this unit.
    pub fn tick(self, v: f64) -> String {
        match self {
            Unit::Plain => tick(v),
            Unit::Bytes => units::bytes(v),
            Unit::Seconds => units::duration(v),
        }
    }
}

/// A chart file: panels on a grid of `columns`, each panel 760 × 480 pixels.
#[derive(Clone, Debug)]
pub struct Chart {
    /// The file name without extension (`<stem>.svg`, `<stem>.png`).
    pub file_stem: String,
    /// Panels per row (at least one is used).
    pub columns: usize,
    /// The panels, row by row.
    pub panels: Vec<Panel>,
}

/// A chart could not be drawn or rasterised.
#[derive(Debug, thiserror::Error)]
pub enum ChartError {
    /// plotters failed while drawing the SVG.
    #[error("drawing a chart: {reason}")]
    Draw {
        /// plotters' error, as it describes itself.
        reason: String,
    },
    /// The drawn SVG could not be parsed for rasterising.
    #[error("reading a chart's SVG: {reason}")]
    ReadSvg {
        /// The SVG parser's error.
        reason: String,
    },
    /// No image of the chart's size could be allocated (zero or too large).
    #[error("allocating a chart image of {width} × {height} pixels")]
    Allocate {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The rasterised chart could not be encoded as PNG.
    #[error("encoding a chart PNG: {reason}")]
    EncodePng {
        /// The PNG encoder's error.
        reason: String,
    },
}

/// The fonts the charts' text is rasterised with ([`chart_fonts`]).
pub struct ChartFonts {
    /// resvg's options holding the font database.
    options: usvg::Options<'static>,
}

impl std::fmt::Debug for ChartFonts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChartFonts")
            .field("faces", &self.options.fontdb.len())
            .finish()
    }
}

/// The plot of one panel once its axes are built: f64 coordinates on both axes (x already
/// in log10 when the panel's x is logarithmic).
type Plot<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws a chart as SVG: a white page of `columns` panels per row.
pub fn chart_svg(chart: &Chart) -> Result<String, ChartError> {
    let cols = chart.columns.max(1);
    let rows = chart.panels.len().div_ceil(cols).max(1);
    let (pw, ph) = (760u32, 480u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (pw * cols as u32, ph * rows as u32))
            .into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let areas = root.split_evenly((rows, cols));
        for (panel, area) in chart.panels.iter().zip(areas.iter()) {
            draw_panel(panel, area)?;
        }
        root.present().map_err(plot_err)?;
    }
    Ok(svg)
}

/// A plotters error as a [`ChartError`].
fn plot_err<E: std::fmt::Debug>(e: E) -> ChartError {
    ChartError::Draw {
        reason: format!("{e:?}"),
    }
}

impl Panel {
    /// Where `x` lies on the plot's x axis: its log10 on a log axis, itself otherwise.
    fn x_coord(&self, x: f64) -> f64 {
        if self.x_log { x.log10() } else { x }
    }
}

/// Draws one panel in `area`, in order: axes and mesh, the log axis's own ticks, each series
/// (line with bars and labels, loose points, level), the Pareto front, the legend.
fn draw_panel<DB: DrawingBackend>(
    p: &Panel,
    area: &DrawingArea<DB, Shift>,
) -> Result<(), ChartError> {
    let (x, y) = panel_bounds(p);
    let mut chart = draw_axes(p, area, x, y)?;
    if p.x_log {
        draw_log_ticks(p, area, &mut chart, x, y)?;
    }
    for s in &p.series {
        draw_series(p, s, &mut chart, x)?;
    }
    draw_front(p, &mut chart)?;
    draw_legend(p, &mut chart, x, y)
}

/// The plot's x and y ranges: the finite data (lines with their bars, points, levels) padded
/// by 6 % each side, y kept from going below zero when no value is negative; (0, 1) for an
/// axis with no finite value.
fn panel_bounds(p: &Panel) -> ((f64, f64), (f64, f64)) {
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for s in &p.series {
        for &(x, y, bar) in &s.line {
            xs.push(p.x_coord(x));
            ys.push(y);
            if let Some((lo, hi)) = bar {
                ys.extend([lo, hi]);
            }
        }
        for &(x, y) in &s.points {
            xs.push(p.x_coord(x));
            ys.push(y);
        }
        ys.extend(s.level);
    }
    let finite = |v: &[f64]| {
        let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let lo = f.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) }
    };
    let pad = |(lo, hi): (f64, f64)| {
        let w = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
        (lo - 0.06 * w, hi + 0.06 * w)
    };
    let (x0, x1) = pad(finite(&xs));
    let (y0, y1) = pad(finite(&ys));
    let y0 = if finite(&ys).0 >= 0.0 {
        y0.max(0.0)
    } else {
        y0
    };
    ((x0, x1), (y0, y1))
}

/// Builds the panel's plot over `(x0, x1)` × `(y0, y1)` and draws its caption, axes and mesh,
/// ticks written in the axes' units. A log x axis gets no x ticks or vertical mesh here
/// ([`draw_log_ticks`] draws them).
fn draw_axes<'a, DB: DrawingBackend>(
    p: &Panel,
    area: &'a DrawingArea<DB, Shift>,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<Plot<'a, DB>, ChartError> {
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 17))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(plot_err)?;
    let (x_unit, y_unit) = (p.x_unit, p.y_unit);
    let fmt_x = move |v: &f64| x_unit.tick(*v);
    let fmt_y = move |v: &f64| y_unit.tick(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(if p.x_log {
        format!("{} (log scale)", p.x_label)
    } else {
        p.x_label.clone()
    })
    .y_desc(&p.y_label)
    .x_label_formatter(&fmt_x)
    .y_label_formatter(&fmt_y)
    .light_line_style(RGBColor(235, 235, 235));
    if p.x_log {
        // Log axes get their ticks at 1, 2, 5 × 10^k (plotters would space them evenly in
        // log10 and write 1.585, 2.512).
        mesh.x_labels(0).disable_x_mesh();
    }
    mesh.draw().map_err(plot_err)?;
    Ok(chart)
}

/// Draws a log x axis's ticks: a light vertical line and the value written in the axis's unit
/// at each round number ([`log_ticks`]; powers of two for bytes, [`binary_ticks`]).
fn draw_log_ticks<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    area: &DrawingArea<DB, Shift>,
    chart: &mut Plot<'a, DB>,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), ChartError> {
    let base = area.get_base_pixel();
    let style = ("sans-serif", 13).into_font().color(&BLACK);
    let (lo, hi) = (10f64.powf(x0), 10f64.powf(x1));
    let ticks = if p.x_unit == Unit::Bytes {
        binary_ticks(lo, hi)
    } else {
        log_ticks(lo, hi)
    };
    for v in ticks {
        chart
            .draw_series(LineSeries::new(
                [(v.log10(), y0), (v.log10(), y1)],
                RGBColor(225, 225, 225).stroke_width(1),
            ))
            .map_err(plot_err)?;
        let (px, py) = chart.backend_coord(&(v.log10(), y0));
        let text = p.x_unit.tick(v);
        let w = 3.5 * text.len() as f64;
        area.draw(&Text::new(
            text,
            (px - base.0 - w as i32, py - base.1 + 6),
            style.clone(),
        ))
        .map_err(plot_err)?;
    }
    Ok(())
}

/// Draws one series: its line (with bars and labels), its loose points, its level across
/// `(x0, x1)`; the first of these drawn carries the series' legend entry.
fn draw_series<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    s: &Series,
    chart: &mut Plot<'a, DB>,
    x: (f64, f64),
) -> Result<(), ChartError> {
    let mut labelled = false;
    if !s.line.is_empty() {
        draw_line(p, s, chart)?;
        labelled = true;
    }
    if !s.points.is_empty() {
        draw_points(p, s, chart, !labelled)?;
        labelled = true;
    }
    if let Some(level) = s.level {
        draw_level(s, level, chart, x, !labelled)?;
    }
    Ok(())
}

/// Draws a series' line (with its legend entry), then the min–max bar of each mean point that
/// has one, then the labels beside its points.
fn draw_line<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    s: &Series,
    chart: &mut Plot<'a, DB>,
) -> Result<(), ChartError> {
    let c = s.color.plotters();
    chart
        .draw_series(LineSeries::new(
            s.line.iter().map(|&(x, y, _)| (p.x_coord(x), y)),
            c.stroke_width(2),
        ))
        .map_err(plot_err)?
        .label(&s.name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    chart
        .draw_series(s.line.iter().filter_map(|&(x, y, bar)| {
            bar.map(|(lo, hi)| {
                ErrorBar::new_vertical(p.x_coord(x), lo, y, hi, c.stroke_width(1), 6)
            })
        }))
        .map_err(plot_err)?;
    draw_labels(
        p,
        chart,
        c,
        s.line.iter().map(|&(x, y, _)| (x, y)),
        &s.labels,
    )
}

/// Writes each label beside its point, in the series' colour.
fn draw_labels<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    chart: &mut Plot<'a, DB>,
    c: RGBColor,
    points: impl Iterator<Item = (f64, f64)>,
    labels: &[String],
) -> Result<(), ChartError> {
    chart
        .draw_series(points.zip(labels).map(|((x, y), label)| {
            Text::new(
                label.clone(),
                (p.x_coord(x), y),
                ("sans-serif", 12).into_font().color(&c.mix(0.9)),
            )
        }))
        .map_err(plot_err)?;
    Ok(())
}

/// Draws a series' loose points: filled and labelled when the series has no line, hollow and
/// faint behind it otherwise; with the legend entry (a filled dot) when `legend`.
fn draw_points<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    s: &Series,
    chart: &mut Plot<'a, DB>,
    legend: bool,
) -> Result<(), ChartError> {
    let c = s.color.plotters();
    let filled = s.line.is_empty();
    let ann = chart
        .draw_series(s.points.iter().map(|&(x, y)| {
            let style = if filled {
                c.filled()
            } else {
                c.mix(0.45).stroke_width(1)
            };
            Circle::new((p.x_coord(x), y), if filled { 4 } else { 3 }, style)
        }))
        .map_err(plot_err)?;
    if legend {
        ann.label(&s.name)
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, c.filled()));
    }
    if filled {
        draw_labels(p, chart, c, s.points.iter().copied(), &s.point_labels)?;
    }
    Ok(())
}

/// Draws a series' level as a dashed line across `(x0, x1)` at y = `level`, with the legend
/// entry (a line) when `legend`.
fn draw_level<'a, DB: DrawingBackend + 'a>(
    s: &Series,
    level: f64,
    chart: &mut Plot<'a, DB>,
    (x0, x1): (f64, f64),
    legend: bool,
) -> Result<(), ChartError> {
    let c = s.color.plotters();
    let ann = chart
        .draw_series(DashedLineSeries::new(
            vec![(x0, level), (x1, level)],
            8,
            5,
            c.stroke_width(2),
        ))
        .map_err(plot_err)?;
    if legend {
        ann.label(&s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    }
    Ok(())
}

/// Draws the panel's Pareto front, if any: a black step line through its points (each point's
/// y held until the next point's x), then a black ring on each point. A front of one point is
/// its ring alone, which then carries the legend entry (a line of one point is no line, and
/// SVG rasterisers skip it with a warning).
fn draw_front<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    chart: &mut Plot<'a, DB>,
) -> Result<(), ChartError> {
    if p.front.len() > 1 {
        let mut steps = Vec::new();
        for (i, &(x, y)) in p.front.iter().enumerate() {
            if i > 0 {
                steps.push((p.x_coord(x), p.front[i - 1].1));
            }
            steps.push((p.x_coord(x), y));
        }
        chart
            .draw_series(LineSeries::new(steps, BLACK.stroke_width(1)))
            .map_err(plot_err)?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(1)));
    }
    if !p.front.is_empty() {
        let rings = chart
            .draw_series(
                p.front
                    .iter()
                    .map(|&(x, y)| Circle::new((p.x_coord(x), y), 7, BLACK.stroke_width(2))),
            )
            .map_err(plot_err)?;
        if p.front.len() == 1 {
            rings
                .label("Pareto front")
                .legend(|(x, y)| Circle::new((x + 9, y), 5, BLACK.stroke_width(2)));
        }
    }
    Ok(())
}

/// Draws the legend on a translucent white box in the plot's emptiest corner
/// ([`legend_corner`]).
fn draw_legend<'a, DB: DrawingBackend + 'a>(
    p: &Panel,
    chart: &mut Plot<'a, DB>,
    x: (f64, f64),
    y: (f64, f64),
) -> Result<(), ChartError> {
    chart
        .configure_series_labels()
        .position(legend_corner(p, x, y))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(plot_err)
}

/// The ticks of a log axis from `lo` to `hi` (> 0): 1, 2 and 5 × 10^k, or only the powers of
/// ten when those would be more than a dozen, or 1 to 9 × 10^k when fewer than three. Empty
/// when the range is not positive and finite.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let series = |mantissas: &[f64]| -> Vec<f64> {
        let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (k0..=k1)
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9))
            .collect()
    };
    let nice = series(&[1.0, 2.0, 5.0]);
    if nice.len() > 12 {
        series(&[1.0])
    } else if nice.len() < 3 {
        series(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    } else {
        nice
    }
}

/// The ticks of a log axis of bytes: powers of two (64 KB, 128 KB, …), every second or fourth
/// one when there would be more than ten. Empty when the range is not positive and finite.
pub fn binary_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (k0, k1) = (lo.log2().ceil() as i32, hi.log2().floor() as i32);
    let n = (k1 - k0 + 1).max(0) as usize;
    let step = n.div_ceil(10).max(1).next_power_of_two() as i32;
    (k0..=k1)
        .filter(|k| k.rem_euclid(step) == 0)
        .map(|k| 2f64.powi(k))
        .collect()
}

/// A plain axis tick or point label: 4 significant digits, trailing zeros dropped (`0.25`,
/// `600`, `3.200e7` outside 1e-4 to 1e6).
pub fn tick(x: f64) -> String {
    let s = crate::units::four_significant(x);
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The corner of the plot over `(x0, x1)` × `(y0, y1)` holding the fewest data points, for
/// the legend.
fn legend_corner(p: &Panel, (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> SeriesLabelPosition {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for s in &p.series {
        pts.extend(s.line.iter().map(|&(x, y, _)| (p.x_coord(x), y)));
        pts.extend(s.points.iter().map(|&(x, y)| (p.x_coord(x), y)));
    }
    pts.extend(p.front.iter().map(|&(x, y)| (p.x_coord(x), y)));
    let norm = |(x, y): (f64, f64)| ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0));
    let count = |right: bool, upper: bool| {
        pts.iter()
            .map(|&q| norm(q))
            .filter(|&(nx, ny)| {
                (if right { nx > 0.55 } else { nx < 0.45 })
                    && (if upper { ny > 0.65 } else { ny < 0.35 })
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, count(true, true)),
        (SeriesLabelPosition::UpperLeft, count(false, true)),
        (SeriesLabelPosition::LowerRight, count(true, false)),
        (SeriesLabelPosition::LowerLeft, count(false, false)),
    ]
    .into_iter()
    .min_by_key(|&(_, n)| n)
    .map_or(SeriesLabelPosition::UpperRight, |(c, _)| c)
}

/// Fonts for rasterising the charts' text: the system's, with the first sans-serif family of
/// DejaVu Sans, Liberation Sans, Noto Sans, Arial and Helvetica that is installed (else any
/// installed family) standing for the SVG's `sans-serif`.
pub fn chart_fonts() -> ChartFonts {
    let mut opt = usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_system_fonts();
    let family = [
        "DejaVu Sans",
        "Liberation Sans",
        "Noto Sans",
        "Arial",
        "Helvetica",
    ]
    .into_iter()
    .find(|f| {
        db.faces()
            .any(|face| face.families.iter().any(|(name, _)| name == f))
    })
    .map(str::to_string)
    .or_else(|| {
        db.faces()
            .next()
            .and_then(|f| f.families.first().map(|(n, _)| n.clone()))
    });
    if let Some(f) = family {
        db.set_sans_serif_family(f);
    }
    ChartFonts { options: opt }
}

/// Rasterises an SVG (as [`chart_svg`] draws it) to PNG bytes at its own size, its text in
/// `fonts`.
pub fn svg_to_png(svg: &str, fonts: &ChartFonts) -> Result<Vec<u8>, ChartError> {
    let tree = usvg::Tree::from_str(svg, &fonts.options).map_err(|e| ChartError::ReadSvg {
        reason: e.to_string(),
    })?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        tiny_skia::Pixmap::new(size.width(), size.height()).ok_or(ChartError::Allocate {
            width: size.width(),
            height: size.height(),
        })?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap.encode_png().map_err(|e| ChartError::EncodePng {
        reason: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_round_numbers() {
        assert_eq!(
            log_ticks(12.0, 2800.0),
            [20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0]
        );
        assert_eq!(
            log_ticks(1.0, 1e9).len(),
            10,
            "powers of ten when 1-2-5 crowd"
        );
        assert_eq!(log_ticks(1.5, 4.5), [2.0, 3.0, 4.0]);
        assert!(log_ticks(0.0, 1.0).is_empty());
        assert_eq!(Unit::Bytes.tick(524288.0), "512 KB");
        assert_eq!(
            binary_ticks(60_000.0, 300_000.0),
            [65536.0, 131072.0, 262144.0]
        );
        assert!(binary_ticks(1.0, 1e9).len() <= 10);
        assert_eq!(Unit::Seconds.tick(0.25), "250 ms");
    }

    #[test]
    fn a_front_of_one_point_is_a_ring_without_a_line() {
        let panel = |front: Vec<(f64, f64)>| Panel {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x_log: false,
            x_unit: Unit::Plain,
            y_unit: Unit::Plain,
            series: vec![Series {
                name: "cards".into(),
                color: PALETTE[0],
                line: vec![],
                labels: vec![],
                points: vec![(1.0, 0.5), (2.0, 0.25)],
                point_labels: vec!["600 px".into(), "60 px".into()],
                level: None,
            }],
            front,
        };
        // Polylines of the SVG, as their numbers of points.
        let polylines = |front| {
            let chart = Chart {
                file_stem: "c".into(),
                columns: 1,
                panels: vec![panel(front)],
            };
            let svg = chart_svg(&chart).expect("svg");
            (svg.split("<polyline").skip(1))
                .map(|p| {
                    let points = p.split("points=\"").nth(1).unwrap_or_default();
                    points
                        .split('"')
                        .next()
                        .unwrap_or_default()
                        .split_whitespace()
                        .count()
                })
                .collect::<Vec<usize>>()
        };
        // Two points: a step line of three; one point: no line of one point (which SVG
        // rasterisers skip with a warning).
        assert!(polylines(vec![(1.0, 0.5), (2.0, 0.25)]).contains(&3));
        let one = polylines(vec![(1.0, 0.5)]);
        assert!(one.iter().all(|&n| n >= 2), "{one:?}");
    }

    #[test]
    fn ticks_drop_trailing_zeros() {
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(600.0), "600");
        assert_eq!(tick(3.2e7), "3.200e7");
    }
}
