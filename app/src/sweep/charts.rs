//! Which charts a sweep draws from its result rows: accuracy (the animated coverage error at
//! each run's screen height) against cost and against build time (Pareto front marked), and
//! every metric against ε; one line per method (the mean over
//! seeds with its range), external candidates as their own markers or levels. The drawing
//! itself is [`frond_preview::charts`].

use std::collections::BTreeMap;

use frond_metrics::MetricId;
use frond_metrics::statistics::pareto_front;
use frond_preview::charts::{Chart, MeanPoint, PALETTE, Panel, Series, Unit, tick};

use super::results::Row;

/// The accuracy the cost and time charts put on their y axis: the animated coverage error
/// (spec §5.4 on covered fractions), each run seen at its own screen height.
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

/// One series per method (first-seen order, colours in turn) of `y` against `x`: every run
/// as a loose point, and for methods built here the line of their grid points' means over
/// seeds; labelled by screen height when the runs were built at several. A candidate's
/// runs become a level at their mean `y` instead when `x_missing_is_level` (a candidate has
/// no build time or ε of its own).
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

/// The charts of a sweep: the coverage error vs billboards, vs texture bytes, vs build time
/// (with the Pareto front over every run), and each metric vs ε.
pub fn sweep_charts(rows: &[Row]) -> Vec<Chart> {
    let cost = |stem: &str, x: &str, label: &str, x_unit: Unit| Chart {
        file_stem: stem.into(),
        columns: 1,
        panels: vec![Panel {
            title: format!("coverage error at the run's size vs {label}"),
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
            title: "coverage error vs build time (Pareto front: no run both faster and more \
                    accurate)"
                .into(),
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
}
