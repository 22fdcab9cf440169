//! Merge the summaries of a sharded batch (summary.shard-*.json in each folder) into one
//! summary.json + summary.csv.

use std::path::PathBuf;

use anyhow::Result;

use crate::cli::progress::finish_batch;
use frond_app::batch::summary::{BatchSummary, merge, read_summary, summaries_in};

/// `frond batch-merge`.
#[derive(clap::Args, Clone, Debug)]
pub struct BatchMergeArgs {
    /// Output folders of the shards (often one shared folder).
    #[arg(required = true)]
    pub outputs: Vec<PathBuf>,
    /// Folder for the merged summary (default: the first).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the merged summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

impl BatchMergeArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let BatchMergeArgs {
            outputs,
            output,
            json,
        } = self;
        let mut parts = Vec::new();
        for dir in &outputs {
            for path in summaries_in(dir)? {
                let s = read_summary(&path)?;
                parts.push((path, s));
            }
        }
        let (summary, warnings) = merge(&parts)?;
        for w in &warnings {
            crate::say_err!("warning: {w}");
        }
        let dir = output.unwrap_or_else(|| outputs[0].clone());
        frond_app::out_folder::OutFolder::new(&dir).create()?;
        summary.write(&dir, &BatchSummary::stem(None))?;
        finish_batch(&summary, &dir, json)?;
        Ok(())
    }
}
