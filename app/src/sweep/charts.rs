//! Charts of a sweep, drawn with plotters as SVG and rasterised to PNG with resvg: accuracy
//! against cost and against build time (Pareto front marked), and every metric against ε; one
//! line per method, external candidates as their own markers.

use std::collections::BTreeMap;

use anyhow::{Context, Result, anyhow};
use frond_metrics::MetricId;
use frond_metrics::statistics::pareto_front;
use plotters::prelude::*;
use resvg::{tiny_skia, usvg};

use super::results::{Row, sig};

/// A configuration's mean (x, y) with the (min, max) of y over its seeds when it has several.
pub type MeanPoint = (f64, f64, Option<(f64, f64)>);

/// One line or point set of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub color: RGBColor,
    /// Points joined by a line (x sorted), each with an optional (min, max) bar.
    pub line: Vec<MeanPoint>,
    /// A label beside each point of `line` (its screen height), or none.
    pub labels: Vec<String>,
    /// Loose points (every run).
    pub points: Vec<(f64, f64)>,
    /// A label beside each loose point (its screen height) when the series has no line.
    pub point_labels: Vec<String>,
    /// A horizontal reference line (a candidate with no x).
    pub level: Option<f64>,
}

/// One chart panel.
#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_log: bool,
    /// How the axes' ticks are written.
    pub x_unit: Unit,
    pub y_unit: Unit,
    pub series: Vec<Series>,
    /// The Pareto front, drawn as a step line with ringed points.
    pub front: Vec<(f64, f64)>,
}

/// How an axis's ticks are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// A plain number.
    Plain,
    /// Bytes, as KB and MB.
    Bytes,
    /// Seconds, as ms and s.
    Seconds,
}

impl Unit {
    /// A tick's text.
    fn tick(self, v: f64) -> String {
        match self {
            Unit::Plain => tick(v),
            Unit::Bytes => frond_preview::units::bytes(v),
            Unit::Seconds => frond_preview::units::duration(v),
        }
    }
}

/// A chart file: panels on a grid of `columns`.
#[derive(Clone, Debug)]
pub struct Chart {
    pub file_stem: String,
    pub columns: usize,
    pub panels: Vec<Panel>,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// The accuracy the cost and time charts put on their y axis.
pub const ACCURACY: MetricId = MetricId::CoverageAnimated;

/// The y-axis label of the cost and time charts.
fn accuracy_label() -> String {
    format!("{} (lower is better)", ACCURACY.label())
}

/// The metrics charted against ε: all but the derived ones ([`MetricId::is_derived`]).
pub fn charted_metrics() -> impl Iterator<Item = MetricId> {
    MetricId::ALL.into_iter().filter(|id| !id.is_derived())
}

/// The runs on the Pareto front of build time against accuracy (both minimised), cheapest
/// first; candidates (not built here) take no part.
pub fn front(rows: &[Row]) -> Vec<&Row> {
    let timed: Vec<&Row> = rows.iter().filter(|r| !r.is_candidate()).collect();
    let pts: Vec<(f64, f64)> = timed
        .iter()
        .map(|r| (r.get("t_lod"), r.get(ACCURACY.column())))
        .collect();
    pareto_front(&pts).into_iter().map(|i| timed[i]).collect()
}

/// Rows of each method in first-seen order, candidates apart.
fn by_method(rows: &[Row]) -> Vec<(String, Vec<&Row>)> {
    let mut out: Vec<(String, Vec<&Row>)> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(m, _)| *m == r.method) {
            Some((_, v)) => v.push(r),
            None => out.push((r.method.clone(), vec![r])),
        }
    }
    out
}

/// Per grid point of one method: mean x, mean y and the y range over seeds (finite values
/// only), each with its grid point's screen height as a label.
fn config_means(rows: &[&Row], x: &str, y: &str) -> Vec<(MeanPoint, String)> {
    let mut groups: BTreeMap<&str, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        groups.entry(r.point.as_str()).or_default().push(r);
    }
    let mut pts: Vec<(MeanPoint, String)> = groups
        .values()
        .filter_map(|g| {
            let pairs: Vec<(f64, f64)> = g
                .iter()
                .map(|r| (r.get(x), r.get(y)))
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .collect();
            if pairs.is_empty() {
                return None;
            }
            let n = pairs.len() as f64;
            let mx = pairs.iter().map(|p| p.0).sum::<f64>() / n;
            let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
            let lo = pairs.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = pairs.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
            let label = format!("{} px", tick(f64::from(g[0].screen_height)));
            Some(((mx, my, (pairs.len() > 1).then_some((lo, hi))), label))
        })
        .collect();
    pts.sort_by(|a, b| a.0.0.total_cmp(&b.0.0));
    pts
}

fn series_for(rows: &[Row], x: &str, y: &str, x_missing_is_level: bool) -> Vec<Series> {
    by_method(rows)
        .into_iter()
        .enumerate()
        .map(|(i, (name, rs))| {
            let candidate = rs[0].is_candidate();
            let (points, point_labels): (Vec<(f64, f64)>, Vec<String>) = rs
                .iter()
                .map(|r| {
                    let label = format!("{} px", tick(f64::from(r.screen_height)));
                    ((r.get(x), r.get(y)), label)
                })
                .filter(|((a, b), _)| a.is_finite() && b.is_finite())
                .unzip();
            let level = (candidate && x_missing_is_level)
                .then(|| {
                    let ys: Vec<f64> = rs
                        .iter()
                        .map(|r| r.get(y))
                        .filter(|v| v.is_finite())
                        .collect();
                    (!ys.is_empty()).then(|| ys.iter().sum::<f64>() / ys.len() as f64)
                })
                .flatten();
            let means = if candidate {
                Vec::new()
            } else {
                config_means(&rs, x, y)
            };
            // Labelled by screen height unless every point has the same (a fixed-size ε grid).
            let sizes: std::collections::BTreeSet<&String> = means.iter().map(|m| &m.1).collect();
            let several = sizes.len() > 1;
            Series {
                name,
                color: PALETTE[i % PALETTE.len()],
                labels: if several {
                    means.iter().map(|m| m.1.clone()).collect()
                } else {
                    Vec::new()
                },
                line: means.into_iter().map(|m| m.0).collect(),
                point_labels: if several { point_labels } else { Vec::new() },
                points: if candidate && x_missing_is_level {
                    Vec::new()
                } else {
                    points
                },
                level,
            }
        })
        .collect()
}

/// Whether positive values want a log axis: they span more than 20× and crowd the low end (the
/// median below a quarter of the way up), as billboard counts over a range of ε do. An even
/// grid from 0 (ε = 0 is stored as a tiny positive value) stays linear.
fn wants_log(xs: impl Iterator<Item = f64>) -> bool {
    let mut v: Vec<f64> = xs.filter(|x| x.is_finite()).collect();
    if v.is_empty() || v.iter().any(|&x| x <= 0.0) {
        return false;
    }
    v.sort_by(f64::total_cmp);
    let (lo, hi) = (v[0], v[v.len() - 1]);
    let median = v[v.len() / 2];
    hi / lo > 20.0 && median < lo + 0.25 * (hi - lo)
}

/// The charts of a sweep: accuracy vs billboards, vs texture bytes, vs build time (with the
/// Pareto front over every run), and each metric vs ε.
pub fn sweep_charts(rows: &[Row]) -> Vec<Chart> {
    let cost = |stem: &str, x: &str, label: &str, x_unit: Unit| Chart {
        file_stem: stem.into(),
        columns: 1,
        panels: vec![Panel {
            title: format!("accuracy vs {label}"),
            x_label: label.into(),
            y_label: accuracy_label(),
            x_log: wants_log(rows.iter().map(|r| r.get(x))),
            x_unit,
            y_unit: Unit::Plain,
            series: series_for(rows, x, ACCURACY.column(), false),
            front: Vec::new(),
        }],
    };
    let mut charts = vec![
        cost(
            "accuracy_vs_billboards",
            "billboards",
            "billboards",
            Unit::Plain,
        ),
        cost(
            "accuracy_vs_texture_bytes",
            "texture_bytes",
            "texture bytes",
            Unit::Bytes,
        ),
    ];
    // Build time: every run a point; the front over all of them.
    let front = front(rows)
        .iter()
        .map(|r| (r.get("t_lod"), r.get(ACCURACY.column())))
        .collect();
    // Candidates were not built here: their accuracy is a dashed level.
    let mut series = series_for(rows, "t_lod", ACCURACY.column(), true);
    for s in &mut series {
        s.line.clear();
    }
    charts.push(Chart {
        file_stem: "accuracy_vs_time".into(),
        columns: 1,
        panels: vec![Panel {
            title: "speed vs accuracy (Pareto front: no run both faster and more accurate)".into(),
            x_label: "build time of the LOD".into(),
            y_label: accuracy_label(),
            x_unit: Unit::Seconds,
            y_unit: Unit::Plain,
            x_log: wants_log(
                rows.iter()
                    .filter(|r| !r.is_candidate())
                    .map(|r| r.get("t_lod")),
            ),
            series,
            front,
        }],
    });
    let eps_rows = with_eps_column(rows);
    // ε as the model's scale (% of its diagonal); and as what a player sees: in screen pixels
    // at the LOD's size for a grid of ε at one size, or the screen height itself for a grid of
    // sizes (where ε is the pixel error by construction, about the same number of pixels at
    // every point).
    let heights: std::collections::BTreeSet<u32> = rows
        .iter()
        .filter(|r| !r.is_candidate())
        .map(|r| r.screen_height.to_bits())
        .collect();
    let screen = if heights.len() > 1 {
        (
            "metrics_vs_screen_height",
            SCREEN_HEIGHT,
            "screen height of the tree (pixels)",
            "screen height",
        )
    } else {
        (
            "metrics_vs_epsilon_px",
            EPSILON_PX,
            "ε in screen pixels at the LOD's size",
            "ε",
        )
    };
    for (stem, column, label, versus) in [
        (
            "metrics_vs_epsilon",
            "epsilon_pct",
            "ε (% of the bounding-box diagonal)",
            "ε",
        ),
        screen,
    ] {
        let x_log = wants_log(eps_rows.iter().map(|r| r.get(column)));
        charts.push(Chart {
            file_stem: stem.into(),
            columns: 2,
            panels: charted_metrics()
                .map(|id| Panel {
                    title: format!("{} vs {versus}", id.label()),
                    x_label: label.into(),
                    y_label: id.label().into(),
                    x_log,
                    x_unit: Unit::Plain,
                    y_unit: Unit::Plain,
                    series: series_for(&eps_rows, column, id.column(), true),
                    front: Vec::new(),
                })
                .collect(),
        });
    }
    charts
}

/// The column of ε in screen pixels at the LOD's screen height (filled by the sweep).
pub const EPSILON_PX: &str = "epsilon_px";
/// The column of the screen height a run was built at, for charting.
const SCREEN_HEIGHT: &str = "screen_height";

/// Rows with ε% and the screen height as columns, so they can be charted like any value.
fn with_eps_column(rows: &[Row]) -> Vec<Row> {
    rows.iter()
        .map(|r| {
            let mut r = r.clone();
            if !r.is_candidate() {
                r.values
                    .insert(SCREEN_HEIGHT.into(), f64::from(r.screen_height));
            }
            if let Some(e) = r.epsilon_pct.filter(|_| !r.is_candidate()) {
                r.values.insert("epsilon_pct".into(), e);
            }
            r
        })
        .collect()
}

/// Draws a chart as SVG.
pub fn chart_svg(chart: &Chart) -> Result<String> {
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

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing a chart: {e:?}")
}

fn draw_panel<DB: DrawingBackend>(
    p: &Panel,
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let tx = |x: f64| if p.x_log { x.log10() } else { x };
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for s in &p.series {
        for &(x, y, bar) in &s.line {
            xs.push(tx(x));
            ys.push(y);
            if let Some((lo, hi)) = bar {
                ys.extend([lo, hi]);
            }
        }
        for &(x, y) in &s.points {
            xs.push(tx(x));
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
        // Log axes get their ticks at 1, 2, 5 × 10^k below (plotters would space them evenly
        // in log10 and write 1.585, 2.512).
        mesh.x_labels(0).disable_x_mesh();
    }
    mesh.draw().map_err(plot_err)?;
    if p.x_log {
        let base = area.get_base_pixel();
        let style = ("sans-serif", 13).into_font().color(&BLACK);
        let (lo, hi) = (10f64.powf(x0), 10f64.powf(x1));
        let ticks = if x_unit == Unit::Bytes {
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
            let text = x_unit.tick(v);
            let w = 3.5 * text.len() as f64;
            area.draw(&Text::new(
                text,
                (px - base.0 - w as i32, py - base.1 + 6),
                style.clone(),
            ))
            .map_err(plot_err)?;
        }
    }
    for s in &p.series {
        let c = s.color;
        let mut labelled = false;
        if !s.line.is_empty() {
            chart
                .draw_series(LineSeries::new(
                    s.line.iter().map(|&(x, y, _)| (tx(x), y)),
                    c.stroke_width(2),
                ))
                .map_err(plot_err)?
                .label(&s.name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
            labelled = true;
            chart
                .draw_series(s.line.iter().filter_map(|&(x, y, bar)| {
                    bar.map(|(lo, hi)| {
                        ErrorBar::new_vertical(tx(x), lo, y, hi, c.stroke_width(1), 6)
                    })
                }))
                .map_err(plot_err)?;
            chart
                .draw_series(s.line.iter().zip(&s.labels).map(|(&(x, y, _), label)| {
                    Text::new(
                        label.clone(),
                        (tx(x), y),
                        ("sans-serif", 12).into_font().color(&c.mix(0.9)),
                    )
                }))
                .map_err(plot_err)?;
        }
        if !s.points.is_empty() {
            let filled = s.line.is_empty();
            let ann = chart
                .draw_series(s.points.iter().map(|&(x, y)| {
                    let style = if filled {
                        c.filled()
                    } else {
                        c.mix(0.45).stroke_width(1)
                    };
                    Circle::new((tx(x), y), if filled { 4 } else { 3 }, style)
                }))
                .map_err(plot_err)?;
            if !labelled {
                ann.label(&s.name)
                    .legend(move |(x, y)| Circle::new((x + 9, y), 4, c.filled()));
                labelled = true;
            }
            if s.line.is_empty() {
                chart
                    .draw_series(
                        s.points
                            .iter()
                            .zip(&s.point_labels)
                            .map(|(&(x, y), label)| {
                                Text::new(
                                    label.clone(),
                                    (tx(x), y),
                                    ("sans-serif", 12).into_font().color(&c.mix(0.9)),
                                )
                            }),
                    )
                    .map_err(plot_err)?;
            }
        }
        if let Some(level) = s.level {
            let ann = chart
                .draw_series(DashedLineSeries::new(
                    vec![(x0, level), (x1, level)],
                    8,
                    5,
                    c.stroke_width(2),
                ))
                .map_err(plot_err)?;
            if !labelled {
                ann.label(&s.name).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
            }
        }
    }
    // A front of one point is its ring alone (a line of one point is no line).
    if p.front.len() > 1 {
        let mut steps = Vec::new();
        for (i, &(x, y)) in p.front.iter().enumerate() {
            if i > 0 {
                steps.push((tx(x), p.front[i - 1].1));
            }
            steps.push((tx(x), y));
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
                    .map(|&(x, y)| Circle::new((tx(x), y), 7, BLACK.stroke_width(2))),
            )
            .map_err(plot_err)?;
        if p.front.len() == 1 {
            rings
                .label("Pareto front")
                .legend(|(x, y)| Circle::new((x + 9, y), 5, BLACK.stroke_width(2)));
        }
    }
    chart
        .configure_series_labels()
        .position(legend_corner(p, (x0, x1), (y0, y1), tx))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(plot_err)?;
    Ok(())
}

/// The ticks of a log axis from `lo` to `hi` (> 0): 1, 2 and 5 × 10^k, or only the powers of
/// ten when those would be more than a dozen, or 1 to 9 × 10^k when fewer than three.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
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
/// one when there would be more than ten.
fn binary_ticks(lo: f64, hi: f64) -> Vec<f64> {
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

/// An axis tick: 4 significant digits, trailing zeros dropped.
fn tick(x: f64) -> String {
    let s = sig(x);
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The corner of the plot holding the fewest data points, for the legend.
fn legend_corner(
    p: &Panel,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    tx: impl Fn(f64) -> f64,
) -> SeriesLabelPosition {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for s in &p.series {
        pts.extend(s.line.iter().map(|&(x, y, _)| (tx(x), y)));
        pts.extend(s.points.iter().map(|&(x, y)| (tx(x), y)));
    }
    pts.extend(p.front.iter().map(|&(x, y)| (tx(x), y)));
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

/// Fonts for rasterising the charts' text: the system's, with a sans-serif family that exists.
pub fn chart_fonts() -> usvg::Options<'static> {
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
    opt
}

/// Rasterises an SVG to PNG bytes at its own size.
pub fn svg_to_png(svg: &str, options: &usvg::Options) -> Result<Vec<u8>> {
    let tree = usvg::Tree::from_str(svg, options).context("reading a chart's SVG")?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        tiny_skia::Pixmap::new(size.width(), size.height()).context("allocating a chart image")?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap.encode_png().context("encoding a chart PNG")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_axes_only_for_wide_low_crowded_values() {
        // Billboard counts over a range of ε: wide and crowded low.
        assert!(wants_log(
            [12.0, 20.0, 40.0, 150.0, 1000.0, 2800.0].into_iter()
        ));
        // An even ε grid from (nearly) 0: linear, like the thesis's figures.
        assert!(!wants_log(
            [0.001, 1.5, 3.0, 4.5, 7.5, 11.25, 15.0, 18.75, 22.5].into_iter()
        ));
        // Narrow, zero or negative values: linear.
        assert!(!wants_log([1.0, 2.0, 6.0].into_iter()));
        assert!(!wants_log([0.0, 1.0, 100.0].into_iter()));
        assert!(!wants_log(std::iter::empty()));
    }

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
