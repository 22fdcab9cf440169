//! `frond sweep`: `frond lod` over a parameter grid (screen heights, or fixed ε) × methods ×
//! seeds, every result scored by `frond eval`, external candidates scored beside them; writes
//! `results.csv`, the stability table, the failures and the charts.
//!
//! Each build is a child process of the same `frond` binary with a wall-clock limit, so a run
//! that fails, panics or hangs is recorded with its reason and the sweep goes on. Evaluation
//! runs in the sweep's own process: the original's loop is sampled and its coverage images
//! rendered once per screen height, not once per run.

pub mod charts;
pub mod grid;
pub mod page;
pub mod results;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::child_job::{JobEnd, run_job};
use crate::child_request::ChildRequest;
use crate::eval_cmd::{EvalContext, EvalRequest, same_bytes};
use crate::lod_cmd::lod_name;
use crate::lod_settings::{LodSettings, MethodChoice, Sampling};
use crate::out_folder::{OutFolder, write_atomic};
use frond_lod::LodReport;
use frond_lod::method::{MethodName, PickContext, auto_method};
use frond_render::Renderer;
use frond_scene::{ImportOptions, Length, Tree};
use grid::{Grid, GridPoint};
use results::{Row, Stability};

/// What `frond sweep` was asked for.
#[derive(Clone, Debug)]
pub struct SweepRequest {
    /// The `frond` executable each run starts.
    pub exe: PathBuf,
    /// Every run's `frond lod` settings but output, method, screen height, seed and ε: the
    /// input and how it is read, sampling, plane search and bake options.
    pub lod: LodSettings,
    /// Methods of `frond lod --method`.
    pub methods: Vec<String>,
    /// The grid of screen heights, or of fixed ε at one screen height.
    pub grid: Grid,
    /// Seeds each grid point is built with.
    pub seeds: Vec<u64>,
    /// External candidates (any glTF), evaluated at every grid point's screen height.
    pub candidates: Vec<PathBuf>,
    /// Wall-clock limit of one `lod` child (the evaluation runs in the sweep's process, which
    /// renders the original once per screen height for every run).
    pub timeout: Duration,
    /// Keep every run's LOD files (otherwise only the report, eval.json and the logs stay).
    pub keep: bool,
    /// Rest-pose bounding-box diagonal of the input, for ε in %.
    pub diagonal: f32,
    /// Rest-pose height of the input, for ε in screen pixels at a LOD's screen height.
    pub tree_height: f32,
}

/// `summary.json`.
#[derive(Debug, Serialize, Deserialize)]
pub struct SweepSummary {
    /// The input tree.
    pub input: String,
    /// The methods swept.
    pub methods: Vec<String>,
    /// The seeds each point was built with.
    pub seeds: Vec<u64>,
    /// The grid points' labels (`600px`, `eps0.25`).
    pub grid: Vec<String>,
    /// External candidates evaluated beside the runs.
    pub candidates: Vec<String>,
    /// Rows: every run and candidate evaluation.
    pub runs: usize,
    /// Rows that failed (with their reason in `rows`).
    pub failed: usize,
    /// One row per run or candidate evaluation, as `results.csv` has them.
    pub rows: Vec<Row>,
    /// Each configuration over its seeds, as `stability.csv` has them.
    pub stability: Vec<Stability>,
    /// Runs on the Pareto front of build time vs the animated coverage error at the run's
    /// screen height ([`charts::ACCURACY`]).
    pub pareto_front: Vec<String>,
    /// Every file written, this summary last.
    pub files: Vec<String>,
    /// Wall times, seconds.
    pub timings_s: SweepTimings,
}

/// `summary.json`'s wall times, in seconds.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SweepTimings {
    /// The whole sweep.
    pub total: f64,
}

impl GridPoint {
    /// The point's label in run ids and tables.
    fn label(&self) -> String {
        match self.epsilon {
            Some(e) => format!("eps{}", trim(e)),
            None => format!("{}px", trim(self.screen_height)),
        }
    }
}

fn trim(x: f32) -> String {
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Runs the sweep of `tree` into `out_dir` (runs under `out_dir/runs/`), evaluating with
/// `eval`'s views, frames, samples and clip; `progress(done, total, what)`.
pub fn run_sweep(
    renderer: &Renderer,
    tree: &Tree,
    req: &SweepRequest,
    eval: &EvalRequest,
    out_dir: &Path,
    progress: &dyn Fn(usize, usize, &str),
) -> Result<SweepSummary> {
    let t0 = Instant::now();
    let input = tree.source.as_path();
    let tree_name = lod_name(tree);
    if req.methods.is_empty() {
        bail!("no method to sweep");
    }
    if req.seeds.is_empty() {
        bail!("the number of seeds must be at least 1");
    }
    for c in &req.candidates {
        if !c.is_file() {
            bail!("candidate {}: no such file", c.display());
        }
    }
    let mut ctx = EvalContext::new(renderer, tree, eval)?;
    let points = req.grid.points();
    // Every run's folder is a checked name inside OUT/runs, itself checked inside OUT (a
    // `runs` link to elsewhere is refused, not written through).
    let out = OutFolder::new(out_dir);
    out.create()?;
    let runs = OutFolder::new(out.create_dir_all("runs")?);
    let total = req.methods.len() * points.len() * req.seeds.len()
        + req.candidates.len() * distinct_heights(&points).len();
    let mut done = 0;
    let mut rows = Vec::new();
    for method in &req.methods {
        for p in &points {
            for &seed in &req.seeds {
                let id = format!("{method}_{}_s{seed}", p.label());
                progress(done, total, &id);
                let dir = runs.path(&id)?;
                rows.push(lod_run(
                    &mut ctx, &tree_name, req, method, p, seed, &dir, &id,
                )?);
                done += 1;
            }
        }
    }
    for cand in &req.candidates {
        let file = cand
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| cand.display().to_string());
        for h in distinct_heights(&points) {
            let id = format!(
                "candidate_{}_{}px",
                frond_export::textures::sanitize(&file),
                trim(h)
            );
            progress(done, total, &id);
            rows.push(candidate_run(
                &mut ctx,
                cand,
                &file,
                h,
                &runs.path(&id)?,
                &id,
            )?);
            done += 1;
        }
    }
    progress(done, total, "writing tables and charts");
    let stability = results::stability(&rows);
    let charts = charts::sweep_charts(&rows);
    let fonts = frond_preview::charts::chart_fonts();
    let mut files: Vec<(String, Vec<u8>)> = vec![
        ("results.csv".into(), results::results_csv(&rows)?),
        ("stability.csv".into(), results::stability_csv(&stability)?),
        (
            "stability.md".into(),
            results::stability_markdown(&stability, &rows).into_bytes(),
        ),
    ];
    for c in &charts {
        let svg = frond_preview::charts::chart_svg(c)?;
        let png = frond_preview::charts::svg_to_png(&svg, &fonts)?;
        files.push((format!("{}.svg", c.file_stem), svg.into_bytes()));
        files.push((format!("{}.png", c.file_stem), png));
    }
    let pareto: Vec<String> = charts::front(&rows).iter().map(|r| r.run.clone()).collect();
    files.push((
        "index.html".into(),
        page::sweep_page(&input.display().to_string(), &rows, &charts, &pareto).into_bytes(),
    ));
    let summary_name = "summary.json";
    let mut names: Vec<String> = files
        .iter()
        .map(|(n, _)| out_dir.join(n).display().to_string())
        .collect();
    names.push(out_dir.join(summary_name).display().to_string());
    let summary = SweepSummary {
        input: input.display().to_string(),
        methods: req.methods.clone(),
        seeds: req.seeds.clone(),
        grid: points.iter().map(GridPoint::label).collect(),
        candidates: req
            .candidates
            .iter()
            .map(|c| c.display().to_string())
            .collect(),
        runs: rows.len(),
        failed: rows.iter().filter(|r| r.failure.is_some()).count(),
        rows,
        stability,
        pareto_front: pareto,
        files: names,
        timings_s: SweepTimings {
            total: t0.elapsed().as_secs_f64(),
        },
    };
    // The summary last: a summary on disk means the files it lists are there.
    for (name, bytes) in &files {
        out.write_atomic(name, bytes)?;
    }
    let json = serde_json::to_vec_pretty(&summary).context("serialising the sweep summary")?;
    out.write_atomic(summary_name, &json)?;
    Ok(summary)
}

/// Screen heights of the grid, each once, in order.
fn distinct_heights(points: &[GridPoint]) -> Vec<f32> {
    let mut h: Vec<f32> = Vec::new();
    for p in points {
        if !h.contains(&p.screen_height) {
            h.push(p.screen_height);
        }
    }
    h
}

fn new_row(id: &str, method: &str, point: &str, screen_height: f32, seed: Option<u64>) -> Row {
    Row {
        run: id.into(),
        method: method.into(),
        lod_method: None,
        point: point.into(),
        screen_height,
        epsilon: None,
        epsilon_pct: None,
        seed,
        failure: None,
        values: BTreeMap::new(),
    }
}

/// Evaluates the file `candidate` into `row` at the row's screen height; the report is also
/// kept as `dir/eval.json`. A candidate that cannot be read fails the row, not the sweep.
fn evaluate_into(ctx: &mut EvalContext, row: &mut Row, candidate: &Path, dir: &Path) -> Result<()> {
    let imported = frond_scene::import(
        candidate,
        &ImportOptions {
            allow_empty: true,
            ..Default::default()
        },
    );
    let cand = match imported {
        Ok(t) => t,
        Err(e) => {
            row.failure = Some(format!("error: eval: {e}"));
            return Ok(());
        }
    };
    let same_file = same_bytes(ctx.original_path(), candidate);
    let report = match ctx.evaluate(&cand, same_file, row.screen_height) {
        Ok(r) => r,
        Err(e) => {
            // Through anyhow, whose `{:#}` prints the causes too.
            row.failure = Some(format!("error: eval: {:#}", anyhow::Error::from(e)));
            return Ok(());
        }
    };
    let json = serde_json::to_vec_pretty(&report).context("serialising an eval report")?;
    write_atomic(&dir.join("eval.json"), &json)?;
    results::add_eval_report(row, &report);
    row.failure = results::judge(row, &report);
    Ok(())
}

#[expect(
    clippy::too_many_arguments,
    reason = "one grid point of the sweep: context, tree, method, point, seed and paths"
)]
fn lod_run(
    ctx: &mut EvalContext,
    tree_name: &str,
    req: &SweepRequest,
    method: &str,
    p: &GridPoint,
    seed: u64,
    dir: &Path,
    id: &str,
) -> Result<Row> {
    let mut row = new_row(id, method, &p.label(), p.screen_height, Some(seed));
    if std::fs::symlink_metadata(dir).is_ok() {
        let (runs, id) = OutFolder::of_file(dir)?;
        runs.remove_dir_all(&id).context("clearing an old run")?;
    }
    // `auto` picks by LOD rank: each run builds one LOD, so resolve the rule for this grid
    // point's rank among the grid's screen heights (nearest first), as `frond lod` would.
    let given =
        MethodChoice::parse(method).with_context(|| format!("unknown method '{method}'"))?;
    let resolved = match given.method() {
        MethodName::AUTO => {
            let heights = distinct_heights(&req.grid.points());
            let rank = heights.iter().filter(|&&h| h > p.screen_height).count();
            let cards = frond_lod::methods::cards::is_card_foliage(ctx.original());
            let lod = PickContext {
                index: rank,
                spectral_animation: false,
                card_foliage: cards,
                screen_height: p.screen_height,
            };
            MethodChoice::named(auto_method(&lod).0)
        }
        _ => given,
    };
    let settings = LodSettings {
        output: dir.join("lod"),
        method: resolved,
        lods: vec![p.screen_height],
        epsilon: p.epsilon.map(Length::World),
        // A grid point measures the method at the ε and size asked for: the chain's cost
        // budgets would widen ε to half the input's triangles.
        cost_budgets: false,
        // The sweep evaluates every point itself, and its own page shows the charts.
        measure: false,
        preview: false,
        sampling: Sampling {
            seed,
            ..req.lod.sampling.clone()
        },
        ..req.lod.clone()
    };
    let end = run_job(
        &req.exe,
        &ChildRequest::Lod(settings),
        dir,
        "lod",
        req.timeout,
    )?;
    let report_path = dir
        .join("lod")
        .join(frond_lod::report::report_name(tree_name));
    let report: Result<LodReport, String> = match end {
        JobEnd::Done => std::fs::read(&report_path)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .ok_or_else(|| format!("error: lod: {}: unreadable report", report_path.display())),
        JobEnd::TimedOut(d) => Err(format!("timeout: lod ran past {} s", d.as_secs_f64())),
        JobEnd::Failed(why) => Err(format!("error: lod: {why}")),
    };
    row.epsilon = p.epsilon.map(f64::from);
    match report {
        Ok(r) => results::add_lod_report(&mut row, &r),
        Err(why) => row.failure = Some(why),
    }
    row.epsilon_pct = row.epsilon.map(|e| 100.0 * e / f64::from(req.diagonal));
    if let Some(e) = row.epsilon.filter(|_| req.tree_height > 0.0) {
        let px = e * f64::from(p.screen_height) / f64::from(req.tree_height);
        row.values.insert(charts::EPSILON_PX.into(), px);
    }
    if row.failure.is_some() {
        return Ok(row);
    }
    let lod1 = dir.join("lod").join(format!("{tree_name}_LOD1.glb"));
    evaluate_into(ctx, &mut row, &lod1, dir)?;
    if !req.keep {
        prune_run(&dir.join("lod"))?;
    }
    Ok(row)
}

/// Removes a run's LOD files, keeping its report.
fn prune_run(lod_dir: &Path) -> Result<()> {
    let folder = OutFolder::new(lod_dir);
    let entries = std::fs::read_dir(lod_dir)
        .with_context(|| format!("{}: cannot list", lod_dir.display()))?;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with("_report.json") {
            continue;
        }
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            folder.remove_dir_all(&name)?;
        } else {
            folder.remove_file(&name)?;
        }
    }
    Ok(())
}

fn candidate_run(
    ctx: &mut EvalContext,
    candidate: &Path,
    file: &str,
    screen_height: f32,
    dir: &Path,
    id: &str,
) -> Result<Row> {
    let mut row = new_row(
        id,
        &format!("candidate:{file}"),
        &format!("{}px", trim(screen_height)),
        screen_height,
        None,
    );
    OutFolder::new(dir).create()?;
    evaluate_into(ctx, &mut row, candidate, dir)?;
    Ok(row)
}
