//! Report bones, skeleton depth, wood/foliage split, clips, looping and bounds.

use anyhow::Result;

use crate::cli::args::ImportArgs;
use crate::cli::progress::print_json;
use frond_app::inspect::{SamplingSummary, inspect};
use frond_scene::{SampleOptions, sample};

/// `frond inspect`.
#[derive(clap::Args, Clone, Debug)]
pub struct InspectArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Clip to sample (default: the first).
    #[arg(long)]
    pub clip: Option<String>,
    /// Uniform samples over the loop.
    #[arg(long, default_value_t = 64)]
    pub samples: usize,
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

impl InspectArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let InspectArgs {
            import,
            clip,
            samples,
            json,
        } = self;
        let tree = import.load()?;
        let start = std::time::Instant::now();
        let sampled = sample(&tree, &SampleOptions { clip, samples })?;
        let summary = SamplingSummary::of(&sampled, start.elapsed().as_secs_f64());
        drop(sampled);
        let report = inspect(&tree, summary);
        if json {
            print_json(&report)?;
        } else {
            print!("{}", super::terminal::safe(&report.text()));
        }
        Ok(())
    }
}
