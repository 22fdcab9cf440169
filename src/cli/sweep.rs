//! Run `frond lod` over a grid of screen heights (or fixed ε) × methods × seeds, evaluate
//! every LOD (and external candidates) with `frond eval`, and write results.csv, the
//! stability table, failures and charts (SVG + PNG).

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::cli::args::{BuildArgs, ImportArgs};
use crate::cli::progress::{Progress, print_json};
use crate::cli::values::MethodArg;
use frond_app::eval_cmd::EvalRequest;
use frond_app::lod_settings::{DEFAULT_LODS_TEXT, LodSettings, Sampling};
use frond_app::sweep::grid::{Grid, parse_epsilons};
use frond_app::sweep::{SweepRequest, run_sweep};
use frond_render::Renderer;

/// `frond sweep`.
#[derive(clap::Args, Clone, Debug)]
pub struct SweepArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Methods to compare.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "per-bone,static"
    )]
    pub method: Vec<MethodArg>,
    /// Screen heights (pixels), one LOD each; ε follows the screen-space rule.
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_LODS_TEXT)]
    pub lods: Vec<f32>,
    /// Fixed ε instead of screen heights: a range "A..B" (with --steps) or a list "A,B,C";
    /// each a length or a percentage of the bounding-box diagonal.
    #[arg(long)]
    pub epsilon: Option<String>,
    /// Values of an --epsilon range, both ends included.
    #[arg(long, default_value_t = 6)]
    pub steps: usize,
    /// Screen height (pixels) the fixed-ε LODs are textured and evaluated at.
    #[arg(long, default_value_t = 600.0)]
    pub screen_height: f32,
    /// Seeds per configuration (1..=N).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// External candidate (any glTF) evaluated at every screen height (repeatable).
    #[arg(long = "candidate", value_name = "FILE")]
    pub candidates: Vec<PathBuf>,
    /// Views a ring of the coverage metric.
    #[arg(long, default_value_t = frond_metrics::DEFAULT_VIEWS)]
    pub views: u32,
    /// Frames of the animated coverage metric.
    #[arg(long, default_value_t = frond_metrics::DEFAULT_FRAMES)]
    pub frames: u32,
    /// Animation samples over the loop (build and trajectory metrics).
    #[arg(long, default_value_t = 64)]
    pub samples: usize,
    /// Clip to sample (default: the first).
    #[arg(long)]
    pub clip: Option<String>,
    /// Plane search, bake and method options.
    #[command(flatten)]
    pub build: BuildArgs,
    /// Seconds one run's build (or evaluation) may take before it is stopped and recorded
    /// as a timeout.
    #[arg(long, default_value_t = 900)]
    pub timeout: u64,
    /// Keep every run's LOD files under runs/ (default: only their reports).
    #[arg(long)]
    pub keep: bool,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

impl SweepArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let SweepArgs {
            import,
            output,
            method,
            lods,
            epsilon,
            steps,
            screen_height,
            seeds,
            candidates,
            views,
            frames,
            samples,
            clip,
            build,
            timeout,
            keep,
            json,
        } = self;
        let tree = import.load()?;
        let diagonal = tree.bounds.diagonal();
        let grid = match &epsilon {
            Some(text) => {
                if !(screen_height.is_finite() && screen_height >= 1.0) {
                    anyhow::bail!("--screen-height must be at least 1 pixel");
                }
                Grid::Epsilons {
                    values: parse_epsilons(text, steps, diagonal).context("--epsilon")?,
                    screen_height,
                }
            }
            None => {
                if let Some(h) = lods.iter().find(|h| !(h.is_finite() && **h >= 1.0)) {
                    anyhow::bail!("--lods: {h} is not a screen height of at least 1 pixel");
                }
                Grid::ScreenHeights(lods)
            }
        };
        let defaults = LodSettings::defaults(&import.input, &output);
        let lod = LodSettings {
            read: import.read(),
            sampling: Sampling {
                samples,
                clip: clip.clone(),
                ..defaults.sampling.clone()
            },
            build: build.settings(),
            ..defaults
        };
        let eval = EvalRequest {
            views,
            frames,
            // Each row is judged at its own screen height (`SweepRow::screen_height`).
            screen_height: screen_height.max(1.0),
            fov_deg: lod.fov,
            resolution: lod.resolution,
            samples,
            clip,
            limits: import.limits.limits(),
            white_albedo: false,
            lighting: Default::default(),
        };
        let req = SweepRequest {
            exe: std::env::current_exe().context("locating the frond executable")?,
            lod,
            methods: method.iter().map(|m| m.0.text().to_string()).collect(),
            grid,
            seeds: (1..=seeds).collect(),
            candidates,
            timeout: std::time::Duration::from_secs(timeout.max(1)),
            keep,
            diagonal,
            tree_height: tree.height(),
        };
        let renderer = Renderer::new()?;
        let bar = Progress::start();
        let result = run_sweep(&renderer, &tree, &req, &eval, &output, &|d, t, m| {
            bar.step(d, t, m)
        });
        drop(bar);
        let summary = result?;
        if json {
            print_json(&summary)?;
        } else {
            crate::say!(
                "{}: {} runs ({} failed); results.csv, stability.md, charts; {:.1} s",
                output.display(),
                summary.runs,
                summary.failed,
                summary.timings_s.total
            );
        }
        if summary.failed > 0 {
            crate::say_err!(
                "{} of {} runs failed (listed in {})",
                summary.failed,
                summary.runs,
                output.join("stability.md").display()
            );
        }
        Ok(())
    }
}
