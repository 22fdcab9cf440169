//! The rows of a sweep (one per run: parameters, seed, cost, every metric, time per stage), how a
//! run failed, and the per-configuration stability table (thesis §8.3, spec §5.8).

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use frond_lod::LodReport;
use frond_metrics::EvalReport;
use frond_metrics::MetricId;
use frond_metrics::statistics::Spread;
use serde::{Deserialize, Serialize};

use crate::csv_text::text_cell;

/// Cost columns of `results.csv`: from `frond lod`'s report, or `frond eval`'s for candidates.
const COST_COLUMNS: &[&str] = &[
    "billboards",
    "triangles",
    "wood_triangles",
    "bones",
    "texture_bytes",
    "billboard_area",
    "draw_calls",
    "file_bytes",
];

/// Time columns of `results.csv` (seconds): `frond lod`'s stages, its total and the evaluation.
const TIME_COLUMNS: &[&str] = &[
    "t_sample",
    "t_reference_pose",
    "t_plane_search",
    "t_bake",
    "t_motion_fit",
    "t_budget",
    "t_wood",
    "t_export",
    "t_lod",
    "t_eval",
];

/// The coverage ratio (spec §5.4 filtered; [`frond_metrics::CoverageMetrics::ratio`]): per
/// (view, frame) pair the run's covered area over the tree's, then the mean; below 1 the LOD
/// thins, above 1 it bloats.
pub const COVERAGE_RATIO: &str = "coverage_ratio";

/// The (view, frame) pairs the thesis' binary coverage error discarded (spec §5.4: a pair above
/// 1, or one where the original covers no pixel), kept for the thesis' experiments; the filtered
/// errors discard none.
const DISCARDED_PAIRS: &str = "discarded_pairs";

/// Key columns of `results.csv`, before [`columns`].
const KEY_COLUMNS: [&str; 9] = [
    "run",
    "method",
    "lod_method",
    "screen_height",
    "epsilon",
    "epsilon_pct",
    "seed",
    "status",
    "reason",
];

/// Numeric columns of `results.csv`, in order: cost; the static and animated coverage errors
/// with their maxima after both, as the file always had them, and the coverage ratio; every
/// other metric's mean and max in [`MetricId::ALL`] order, the binary coverage error followed
/// by the pairs it discarded; the times. A row lacks those that do not apply (empty cell).
pub fn columns() -> Vec<&'static str> {
    let mut c = COST_COLUMNS.to_vec();
    let [stat, anim] = [MetricId::CoverageStatic, MetricId::CoverageAnimated];
    c.extend([
        stat.column(),
        anim.column(),
        stat.max_column(),
        anim.max_column(),
        COVERAGE_RATIO,
    ]);
    for id in MetricId::ALL
        .into_iter()
        .filter(|id| ![stat, anim].contains(id))
    {
        c.extend([id.column(), id.max_column()]);
        if id == MetricId::CoverageBinary {
            c.push(DISCARDED_PAIRS);
        }
    }
    c.extend_from_slice(TIME_COLUMNS);
    c
}

/// Columns measured in seconds: they differ between otherwise identical runs.
pub fn is_timing(column: &str) -> bool {
    column.starts_with("t_")
}

/// The quantities of the stability table: cost, every metric but the derived ones
/// ([`MetricId::is_derived`]), the coverage ratio and the build time.
pub fn stability_quantities() -> Vec<&'static str> {
    let mut q = vec!["billboards", "billboard_area", "texture_bytes", "bones"];
    q.extend(
        MetricId::ALL
            .into_iter()
            .filter(|id| !id.is_derived())
            .map(MetricId::column),
    );
    q.push(COVERAGE_RATIO);
    q.push("t_lod");
    q
}

/// One run of the sweep (or one evaluation of an external candidate).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Run id, also the folder under `runs/`.
    pub run: String,
    /// `per-bone`, `static`, … or `candidate:<file name>`.
    pub method: String,
    /// The method the LOD was built with (`auto` resolves per LOD size), from its report.
    pub lod_method: Option<String>,
    /// The grid point (`600px`, or `eps0.25` for a fixed ε), shared by the seeds of one
    /// configuration.
    pub point: String,
    /// Screen height the LOD was built and evaluated at (pixels).
    pub screen_height: f32,
    /// Plane tolerance in world units (the LOD's, from its report), when known.
    pub epsilon: Option<f64>,
    /// ε as a percentage of the rest-pose bounding-box diagonal.
    pub epsilon_pct: Option<f64>,
    /// The run's random seed (`frond lod`'s); None for an external candidate.
    pub seed: Option<u64>,
    /// Why the run failed (`timeout`, `error`, `empty output`, `error > 1`, `NaN`, with
    /// details; [`judge`]); None when it did not.
    pub failure: Option<String>,
    /// The numeric columns ([`columns`]) it has.
    pub values: BTreeMap<String, f64>,
}

impl Row {
    /// A value, NaN when absent.
    pub fn get(&self, column: &str) -> f64 {
        self.values.get(column).copied().unwrap_or(f64::NAN)
    }
    /// Whether this row is an external candidate rather than a `frond lod` run.
    pub fn is_candidate(&self) -> bool {
        self.method.starts_with("candidate:")
    }
}

/// A report's `f32` as the report file writes it (its shortest decimal) read as an `f64`, so a
/// column holds the number the file shows rather than the `f32`'s binary expansion.
fn as_written(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// Fills a row's cost and LOD timings from `frond lod`'s report (its LOD1 entry).
pub fn add_lod_report(row: &mut Row, report: &LodReport) {
    if let Some(lod) = report.lods.get(1) {
        row.lod_method = Some(lod.method.name().to_string());
        for (col, value) in [
            ("billboards", lod.billboards),
            ("triangles", lod.triangles),
            ("wood_triangles", lod.wood_triangles),
            ("bones", lod.bones),
            ("texture_bytes", lod.texture_bytes),
        ] {
            row.values.insert(col.into(), value as f64);
        }
        row.epsilon = lod.epsilon.map(as_written);
        let t = &lod.timings_s;
        for (stage, seconds) in [
            ("reference_pose", t.build.reference_pose),
            ("plane_search", t.build.plane_search),
            ("bake", t.build.bake),
            ("motion_fit", t.build.motion_fit),
            ("budget", t.budget),
            ("wood", t.wood),
            ("export", t.export),
        ] {
            row.values.insert(format!("t_{stage}"), seconds);
        }
    } else {
        row.epsilon = None;
    }
    row.values
        .insert("t_sample".into(), report.timings_s.sample);
    row.values.insert("t_lod".into(), report.timings_s.total);
}

/// Fills a row's metrics (and, for candidates, cost) from `frond eval`'s report: each metric's
/// mean and max (absent when skipped), the coverage ratio and the binary error's discarded pairs.
pub fn add_eval_report(row: &mut Row, eval: &EvalReport) {
    for id in MetricId::ALL {
        let m = eval.metric(id);
        insert_finite(row, id.column(), m.mean);
        insert_finite(row, id.max_column(), m.max);
    }
    insert_finite(row, COVERAGE_RATIO, Some(eval.coverage.ratio));
    row.values
        .insert(DISCARDED_PAIRS.into(), eval.coverage.discarded_pairs as f64);
    let c = &eval.cost.candidate;
    for (col, value) in [
        ("billboard_area", c.billboard_area),
        ("draw_calls", c.file.draw_calls as f64),
        ("file_bytes", c.file.file_bytes as f64),
    ] {
        insert_finite(row, col, Some(value));
    }
    if row.is_candidate() {
        // The file's joints and decoded texture bytes fill the columns `frond lod` names
        // `bones` and `texture_bytes`.
        for (col, value) in [
            ("billboards", c.billboards as f64),
            ("triangles", c.file.triangles as f64),
            ("bones", c.file.joints_total as f64),
            ("texture_bytes", c.file.texture_decoded_bytes as f64),
        ] {
            row.values.insert(col.into(), value);
        }
    }
    row.values.insert("t_eval".into(), eval.timings_s.total);
}

/// Sets `column` to `value` when it is a finite number: a metric that could not be computed
/// stays absent (and reads as NaN), as the report file writes it (`null`).
fn insert_finite(row: &mut Row, column: &str, value: Option<f64>) {
    if let Some(x) = value.filter(|x| x.is_finite()) {
        row.values.insert(column.into(), x);
    }
}

/// The coverage errors a run is judged by: the tree seen whole, on the first frame and over the
/// loop (spec §5.4 filtered, at the row's screen height).
const JUDGED: [MetricId; 2] = [MetricId::CoverageStatic, MetricId::CoverageAnimated];

/// Why an evaluated run counts as failed, or None. In this order:
///
/// - `empty output`: a LOD (not a candidate) without foliage, neither billboard nor leaf card;
/// - `NaN`: a coverage error (the static and animated ones) or the coverage ratio has no value, or any column
///   is not a number;
/// - `error > 1`: a coverage error above 1. The filtered error (spec §5.4 on covered fractions)
///   is, per (view, frame), the area the run misses plus the area it adds over the area the
///   tree covers. What it misses is at most the tree's area (a run covering nothing scores
///   exactly 1), so it passes 1 only where the run adds more area outside the tree than it
///   shares with it: the LOD bloats past any fidelity, the thesis' "error above 1".
///
/// The thesis' binary error's discarded pairs (pairs above 1 there) no longer fail a run: the
/// filtered error discards none, and `discarded_pairs` stays in the CSV for the thesis'
/// experiments.
pub fn judge(row: &Row, eval: &EvalReport) -> Option<String> {
    // Foliage is billboards, or the cards method's leaf cards (triangles beside the wood).
    // (A missing count is NaN: no card.)
    let has_cards = row.get("triangles") - row.get("wood_triangles") > 0.0;
    if !row.is_candidate() && row.get("billboards") == 0.0 && !has_cards {
        return Some("empty output: the LOD has no foliage (no billboard, no card)".into());
    }
    for id in JUDGED {
        if !row.get(id.column()).is_finite() {
            let why = eval
                .metric(id)
                .skipped_reason
                .as_deref()
                .unwrap_or("no value");
            return Some(format!("NaN: {}: {why}", id.column()));
        }
    }
    if !row.get(COVERAGE_RATIO).is_finite() {
        return Some(format!("NaN: {COVERAGE_RATIO}"));
    }
    if let Some((k, _)) = row.values.iter().find(|(_, v)| !v.is_finite()) {
        return Some(format!("NaN: {k}"));
    }
    for id in JUDGED {
        let error = row.get(id.column());
        if error > 1.0 {
            let ratio = row.get(COVERAGE_RATIO);
            return Some(format!(
                "error > 1: {} = {} at {} px: the run adds more area outside the tree than it \
                 shares with it (coverage ratio {})",
                id.column(),
                sig(error),
                row.screen_height,
                sig(ratio)
            ));
        }
    }
    None
}

/// `results.csv`: key columns, then [`columns`].
pub fn results_csv(rows: &[Row]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let columns = columns();
    let mut header: Vec<&str> = KEY_COLUMNS.to_vec();
    header.extend_from_slice(&columns);
    w.write_record(&header).context("writing results.csv")?;
    for r in rows {
        let mut rec = vec![
            text_cell(&r.run).into_owned(),
            text_cell(&r.method).into_owned(),
            text_cell(r.lod_method.as_deref().unwrap_or_default()).into_owned(),
            format!("{}", r.screen_height),
            opt(r.epsilon),
            opt(r.epsilon_pct),
            r.seed.map(|s| s.to_string()).unwrap_or_default(),
            if r.failure.is_some() { "failed" } else { "ok" }.to_string(),
            text_cell(r.failure.as_deref().unwrap_or_default()).into_owned(),
        ];
        rec.extend(columns.iter().map(|c| opt(r.values.get(*c).copied())));
        w.write_record(&rec).context("writing results.csv")?;
    }
    w.into_inner().context("writing results.csv")
}

fn opt(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v}"),
        Some(_) => "NaN".into(),
        None => String::new(),
    }
}

/// One configuration (method and grid point) over its seeds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Stability {
    /// The configuration's method, as its rows name it.
    pub method: String,
    /// Screen height in pixels the configuration was built and evaluated at.
    pub screen_height: f32,
    /// ε of the configuration (world units): the fixed one, or the rule's.
    pub epsilon: Option<f64>,
    /// ε as a percentage of the rest-pose bounding-box diagonal, mean over its runs.
    pub epsilon_pct: Option<f64>,
    /// Runs of the configuration (one per seed), failed ones included.
    pub runs: usize,
    /// Those of its runs that failed.
    pub failed: usize,
    /// Spread of each [`stability_quantities`] quantity over the runs that have it.
    pub spread: BTreeMap<String, Spread>,
}

/// The stability table: one entry per configuration, in the rows' order.
pub fn stability(rows: &[Row]) -> Vec<Stability> {
    let mut order: Vec<(String, String)> = Vec::new();
    let mut groups: BTreeMap<(String, String), Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.is_candidate()) {
        let key = (r.method.clone(), r.point.clone());
        if !groups.contains_key(&key) {
            order.push(key.clone());
        }
        groups.entry(key).or_default().push(r);
    }
    let quantities = stability_quantities();
    order
        .into_iter()
        .map(|key| {
            let g = &groups[&key];
            let first = g[0];
            let spread = quantities
                .iter()
                .filter_map(|q| {
                    let xs: Vec<f64> = g.iter().map(|r| r.get(q)).collect();
                    Spread::of(&xs).map(|s| (q.to_string(), s))
                })
                .collect();
            let eps: Vec<f64> = g.iter().filter_map(|r| r.epsilon).collect();
            let pct: Vec<f64> = g.iter().filter_map(|r| r.epsilon_pct).collect();
            let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
            Stability {
                method: first.method.clone(),
                screen_height: first.screen_height,
                epsilon: mean(&eps),
                epsilon_pct: mean(&pct),
                runs: g.len(),
                failed: g.iter().filter(|r| r.failure.is_some()).count(),
                spread,
            }
        })
        .collect()
}

/// `stability.csv`: one line per configuration and quantity.
pub fn stability_csv(table: &[Stability]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "method",
        "screen_height",
        "epsilon",
        "epsilon_pct",
        "runs",
        "failed",
        "quantity",
        "n",
        "mean",
        "min",
        "max",
        "avg_abs_dev",
        "relative",
    ])
    .context("writing stability.csv")?;
    for s in table {
        for (q, sp) in &s.spread {
            w.write_record([
                text_cell(&s.method).into_owned(),
                format!("{}", s.screen_height),
                opt(s.epsilon),
                opt(s.epsilon_pct),
                s.runs.to_string(),
                s.failed.to_string(),
                text_cell(q).into_owned(),
                sp.n.to_string(),
                format!("{}", sp.mean),
                format!("{}", sp.min),
                format!("{}", sp.max),
                format!("{}", sp.avg_abs_dev),
                format!("{}", sp.relative),
            ])
            .context("writing stability.csv")?;
        }
    }
    w.into_inner().context("writing stability.csv")
}

/// `stability.md`: a Markdown table per configuration row, "mean (average absolute deviation,
/// relative)" per quantity, then the failed runs with their reasons.
pub fn stability_markdown(table: &[Stability], rows: &[Row]) -> String {
    let metric = |id: MetricId| (id.column(), id.short_label());
    let mut cols = vec![("billboards", "billboards"), ("billboard_area", "area")];
    cols.extend([
        metric(MetricId::CoverageStatic),
        metric(MetricId::CoverageAnimated),
        (COVERAGE_RATIO, "coverage ratio"),
        metric(MetricId::ColourDifference),
        metric(MetricId::DominatingAxis),
        metric(MetricId::DominatingAxisSpectral),
    ]);
    cols.push(("t_lod", "build s"));
    let mut s = String::from("| method | screen px | ε | ε % diag | runs | failed |");
    for (_, h) in &cols {
        s.push_str(&format!(" {h} |"));
    }
    s.push_str("\n|---|---|---|---|---|---|");
    s.push_str(&"---|".repeat(cols.len()));
    s.push('\n');
    for t in table {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |",
            t.method,
            t.screen_height,
            t.epsilon.map(|e| format!("{e:.4}")).unwrap_or_default(),
            t.epsilon_pct.map(|e| format!("{e:.2}")).unwrap_or_default(),
            t.runs,
            t.failed
        ));
        for (q, _) in &cols {
            match t.spread.get(*q) {
                Some(sp) => s.push_str(&format!(
                    " {} ({}, {:.1} %) |",
                    sig(sp.mean),
                    sig(sp.avg_abs_dev),
                    100.0 * sp.relative
                )),
                None => s.push_str(" – |"),
            }
        }
        s.push('\n');
    }
    s.push_str(
        "\nEach cell: mean (average absolute deviation, relative deviation) over the seeds.\n",
    );
    let failed: Vec<&Row> = rows.iter().filter(|r| r.failure.is_some()).collect();
    if failed.is_empty() {
        s.push_str("\nNo run failed.\n");
    } else {
        s.push_str("\nFailed runs:\n\n");
        for r in failed {
            s.push_str(&format!(
                "- `{}` ({}, {} px, seed {}): {}\n",
                r.run,
                r.method,
                r.screen_height,
                r.seed.map(|x| x.to_string()).unwrap_or("-".into()),
                r.failure.as_deref().unwrap_or("")
            ));
        }
    }
    s
}

/// A number with 4 significant digits, without exponent for ordinary magnitudes (the charts'
/// ticks write numbers alike).
pub use frond_preview::units::four_significant as sig;

#[cfg(test)]
mod tests {
    use super::*;
    use frond_metrics::report::{Costs, CoverageMetrics, EvalTimings, Metric};

    fn row(method: &str, seed: u64, billboards: f64, colour: f64) -> Row {
        let mut values = BTreeMap::new();
        values.insert("billboards".into(), billboards);
        values.insert("coverage_animated".into(), colour);
        Row {
            run: format!("{method}_600px_s{seed}"),
            method: method.into(),
            lod_method: None,
            point: "600px".into(),
            screen_height: 600.0,
            epsilon: Some(0.1),
            epsilon_pct: Some(1.0),
            seed: Some(seed),
            failure: None,
            values,
        }
    }

    #[test]
    fn stability_groups_seeds_of_one_configuration() {
        let mut rows = vec![
            row("static", 1, 10.0, 0.2),
            row("static", 2, 12.0, 0.4),
            row("per-bone", 1, 100.0, 0.1),
        ];
        rows[1].failure = Some("timeout".into());
        let t = stability(&rows);
        assert_eq!(t.len(), 2);
        assert_eq!(
            (t[0].method.as_str(), t[0].runs, t[0].failed),
            ("static", 2, 1)
        );
        let b = t[0].spread["billboards"];
        assert_eq!(
            (b.mean, b.min, b.max, b.avg_abs_dev),
            (11.0, 10.0, 12.0, 1.0)
        );
        assert!((t[0].spread["coverage_animated"].mean - 0.3).abs() < 1e-12);
        assert_eq!(t[1].spread["billboards"].n, 1);
        let md = stability_markdown(&t, &rows);
        assert!(md.contains("| static | 600 |"), "{md}");
        assert!(md.contains("timeout"), "{md}");
        let csv = String::from_utf8(stability_csv(&t).unwrap()).unwrap();
        assert!(
            csv.lines()
                .any(|l| l.starts_with("static,600,0.1,1,2,1,billboards,2,11,10,12,1,"))
        );
    }

    /// An eval report whose k-th metric ([`MetricId::ALL`] order) has `metric(k)` as its mean
    /// and max, with coverage ratio `ratio` over `pairs` (view, frame) pairs, `discarded` of
    /// them discarded by the binary error.
    fn eval_report(
        metric: impl Fn(usize) -> (Option<f64>, Option<f64>),
        ratio: f64,
        discarded: usize,
        pairs: usize,
    ) -> EvalReport {
        let m = |k: usize| {
            let id = MetricId::ALL[k];
            let (mean, max) = metric(k);
            Metric {
                mean,
                max,
                skipped_reason: mean.is_none().then(|| format!("{} skipped", id.column())),
                definition: id.definition().into(),
            }
        };
        let at = |id: MetricId| m(MetricId::ALL.iter().position(|x| *x == id).unwrap());
        EvalReport {
            schema_version: frond_metrics::report::EVAL_SCHEMA_VERSION,
            original: "o.glb".into(),
            candidate: "c.glb".into(),
            clip: None,
            samples: 8,
            views: 5,
            elevations_deg: vec![0.0, 30.0],
            frames: 5,
            screen_height: 600.0,
            fov_deg: 60.0,
            resolution: 1080.0,
            size: [800, 660],
            samples_per_side: 2,
            tree_height: 1.0,
            coverage: CoverageMetrics {
                static_: at(MetricId::CoverageStatic),
                animated: at(MetricId::CoverageAnimated),
                binary: at(MetricId::CoverageBinary),
                foliage: at(MetricId::CoverageFoliage),
                ratio,
                loop_change: None,
                loop_change_ratio: None,
                discarded_pairs: discarded,
                pairs,
            },
            colour_difference: at(MetricId::ColourDifference),
            colour_shift: 0.0,
            plane_distance: at(MetricId::PlaneDistance),
            projected_distance: at(MetricId::ProjectedDistance),
            euclidean_distance: at(MetricId::EuclideanDistance),
            orientation: at(MetricId::Orientation),
            dominating_axis: at(MetricId::DominatingAxis),
            dominating_axis_spectral: at(MetricId::DominatingAxisSpectral),
            matching: String::new(),
            cost: Costs::default(),
            timings_s: EvalTimings::default(),
        }
    }

    /// A static run of 10 billboards, both coverage errors 0.2, read from an eval report with
    /// the binary error's `discarded` pairs of 50 and coverage ratio `ratio`.
    fn evaluated(ratio: f64, discarded: usize) -> (Row, EvalReport) {
        let coverage = |k: usize| {
            if k < 2 {
                (Some(0.2), Some(0.2))
            } else {
                (None, None)
            }
        };
        let eval = eval_report(coverage, ratio, discarded, 50);
        let mut r = row("static", 1, 10.0, 0.2);
        add_eval_report(&mut r, &eval);
        (r, eval)
    }

    #[test]
    fn judging_runs() {
        let (mut r, ok) = evaluated(0.9, 0);
        assert_eq!(judge(&r, &ok), None);
        // The binary error's discarded pairs stay in the row, and fail nothing.
        let (r2, eval2) = evaluated(0.9, 7);
        assert_eq!(r2.get(DISCARDED_PAIRS), 7.0);
        assert_eq!(judge(&r2, &eval2), None);
        // A filtered error above 1: the LOD adds more area than it shares with the tree.
        r.values.insert("coverage_animated".into(), 1.25);
        r.values.insert(COVERAGE_RATIO.into(), 2.5);
        let why = judge(&r, &ok).unwrap();
        assert!(
            why.starts_with("error > 1: coverage_animated = 1.250 at 600 px")
                && why.contains("2.500"),
            "{why}"
        );
        // Exactly 1 (a LOD covering nothing) is no fidelity, but not a failure of its own.
        r.values.insert("coverage_animated".into(), 1.0);
        assert_eq!(judge(&r, &ok), None);
        r.values.remove(COVERAGE_RATIO);
        assert_eq!(judge(&r, &ok).unwrap(), "NaN: coverage_ratio");
        r.values.insert(COVERAGE_RATIO.into(), 0.9);
        r.values.remove("coverage_static");
        assert!(judge(&r, &ok).unwrap().starts_with("NaN: coverage_static"));
        r.values.insert("billboards".into(), 0.0);
        assert!(judge(&r, &ok).unwrap().starts_with("empty output"));
        // The cards method writes leaf cards, no billboard: 1000 triangles beside the wood.
        r.values.insert("coverage_static".into(), 0.2);
        r.values.insert("triangles".into(), 1859.0);
        r.values.insert("wood_triangles".into(), 859.0);
        assert_eq!(judge(&r, &ok), None);
        r.values.insert("triangles".into(), 859.0);
        assert!(judge(&r, &ok).unwrap().starts_with("empty output"));
        // A skipped coverage error names the report's reason.
        let (mut r, _) = evaluated(0.9, 0);
        let none = eval_report(|_| (None, None), 0.9, 0, 50);
        r.values.remove("coverage_static");
        assert_eq!(
            judge(&r, &none).unwrap(),
            "NaN: coverage_static: coverage_static skipped"
        );
    }

    #[test]
    fn csv_has_every_column() {
        let csv = String::from_utf8(results_csv(&[row("static", 1, 10.0, 0.25)]).unwrap()).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 9 + columns().len());
        let line: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(line.len(), header.len());
        let at = |c: &str| line[header.iter().position(|h| *h == c).unwrap()];
        assert_eq!(at("billboards"), "10");
        assert_eq!(at("coverage_animated"), "0.25");
        assert_eq!(at("status"), "ok");
        assert_eq!(at("t_bake"), "");
    }

    #[test]
    fn csv_header_uses_exactly_the_metric_ids_columns() {
        let csv = String::from_utf8(results_csv(&[]).unwrap()).unwrap();
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let metric_columns: Vec<&str> = header
            .iter()
            .copied()
            .filter(|c| {
                !KEY_COLUMNS.contains(c)
                    && !COST_COLUMNS.contains(c)
                    && !TIME_COLUMNS.contains(c)
                    && ![DISCARDED_PAIRS, COVERAGE_RATIO].contains(c)
            })
            .collect();
        let mut want: Vec<&str> = MetricId::ALL
            .iter()
            .flat_map(|id| [id.column(), id.max_column()])
            .collect();
        want.sort_unstable();
        let mut got = metric_columns;
        got.sort_unstable();
        assert_eq!(got, want);
        // The file's layout is stable: sweeps are compared across versions.
        assert_eq!(
            header.join(","),
            "run,method,lod_method,screen_height,epsilon,epsilon_pct,seed,status,reason,\
             billboards,triangles,wood_triangles,bones,texture_bytes,billboard_area,draw_calls,\
             file_bytes,coverage_static,coverage_animated,coverage_static_max,\
             coverage_animated_max,coverage_ratio,coverage_binary,coverage_binary_max,\
             discarded_pairs,coverage_foliage,coverage_foliage_max,colour_difference,\
             colour_difference_max,plane_distance,plane_distance_max,projected_distance,\
             projected_distance_max,euclidean_distance,euclidean_distance_max,orientation,\
             orientation_max,dominating_axis,dominating_axis_max,dominating_axis_spectral,\
             dominating_axis_spectral_max,t_sample,t_reference_pose,t_plane_search,t_bake,\
             t_motion_fit,t_budget,t_wood,t_export,t_lod,t_eval"
        );
        // Every metric but the derived one is in the stability table, with the ratio.
        let q = stability_quantities();
        for id in MetricId::ALL {
            assert_eq!(q.contains(&id.column()), !id.is_derived(), "{id:?}");
        }
        assert!(q.contains(&COVERAGE_RATIO));
    }

    #[test]
    fn eval_reports_fill_every_metric_column() {
        let eval = eval_report(|k| (Some(k as f64), Some(10.0 + k as f64)), 1.125, 3, 50);
        let mut r = row("static", 1, 10.0, 0.2);
        add_eval_report(&mut r, &eval);
        for (k, id) in MetricId::ALL.into_iter().enumerate() {
            assert_eq!(r.get(id.column()), k as f64, "{id:?}");
            assert_eq!(r.get(id.max_column()), 10.0 + k as f64, "{id:?}");
        }
        assert_eq!(r.get(COVERAGE_RATIO), 1.125);
        assert_eq!(r.get(DISCARDED_PAIRS), 3.0);
        // The CSV writes them back in their columns.
        let csv = String::from_utf8(results_csv(&[r]).unwrap()).unwrap();
        let mut lines = csv.lines().map(|l| l.split(',').collect::<Vec<_>>());
        let (header, line) = (lines.next().unwrap(), lines.next().unwrap());
        let at = |c: &str| line[header.iter().position(|h| *h == c).unwrap()];
        assert_eq!(at("coverage_ratio"), "1.125");
        assert_eq!(at("discarded_pairs"), "3");
        assert_eq!(at("coverage_binary"), "2");
        assert_eq!(at("coverage_foliage_max"), "13");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(sig(0.123456), "0.1235");
        assert_eq!(sig(1234.5), "1234");
        assert_eq!(sig(12.0), "12.00");
        assert_eq!(sig(3.2e7), "3.200e7");
    }
}
