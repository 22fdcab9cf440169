//! The command line's clap layer: one file per command with its arguments and `run`, which
//! turns them into a library request, runs it and prints the result. The work itself lives in
//! the application library, [`frond_app`], and the pipeline crates.

pub mod args;
pub mod batch;
pub mod batch_merge;
pub mod child;
pub mod cloud;
pub mod eval;
pub mod flags;
pub mod inspect;
pub mod lod;
pub mod progress;
pub mod render;
pub mod sample;
pub mod sweep;
pub mod terminal;
pub mod values;
pub mod view;

use anyhow::Result;

/// Every `frond` command.
#[derive(clap::Subcommand, Clone, Debug)]
pub enum Command {
    /// Report bones, skeleton depth, wood/foliage split, clips, looping and bounds.
    Inspect(inspect::InspectArgs),
    /// Render one frame of a tree (alpha-tested, offscreen) to PNG.
    Render(render::RenderArgs),
    /// Build a static billboard cloud of the foliage (average pose) with baked atlases.
    Cloud(cloud::CloudArgs),
    /// Animated billboard LOD chain: LOD0 (the input) and one LOD per screen height, skinned
    /// or vertex-animated, with a combined file, mapping sidecars and `<name>_report.json`.
    Lod(lod::LodArgs),
    /// Compare a candidate (a LOD, any glTF) with the original: colour (coverage), colour
    /// difference, distance, orientation and animation metrics, and cost.
    Eval(eval::EvalArgs),
    /// Run `frond lod` over a grid of screen heights (or fixed ε) × methods × seeds, evaluate
    /// every LOD (and external candidates) with `frond eval`, and write results.csv, the
    /// stability table, failures and charts (SVG + PNG).
    Sweep(sweep::SweepArgs),
    /// Run `frond lod` over a tree library: every .glb/.gltf below a folder, or a TOML
    /// manifest's trees with their own settings. `OUTDIR/<path without extension>/` per tree,
    /// summary.json + summary.csv; up-to-date trees are skipped, failed ones recorded.
    Batch(batch::BatchArgs),
    /// Merge the summaries of a sharded batch (summary.shard-*.json in each folder) into one
    /// summary.json + summary.csv.
    BatchMerge(batch_merge::BatchMergeArgs),
    /// Write a skinned, wind-animated sample tree (.glb).
    Sample(sample::SampleArgs),
    /// Serve an output folder on localhost and open its preview page (the live view needs the
    /// files served: browsers do not let a page opened from disk read the GLBs beside it).
    View(view::ViewArgs),
    /// A child run of `frond batch` or `frond sweep`: its settings on standard input.
    #[command(hide = true)]
    Child(child::ChildArgs),
}

impl Command {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        match self {
            Command::Inspect(args) => args.run(),
            Command::Render(args) => args.run(),
            Command::Cloud(args) => args.run(),
            Command::Lod(args) => args.run(),
            Command::Eval(args) => args.run(),
            Command::Sweep(args) => args.run(),
            Command::Batch(args) => args.run(),
            Command::BatchMerge(args) => args.run(),
            Command::Sample(args) => args.run(),
            Command::View(args) => args.run(),
            Command::Child(args) => args.run(),
        }
    }
}
