//! Write a skinned, wind-animated sample tree (.glb).

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::cli::values::SampleSize;
use frond_app::out_folder::write_atomic;
use frond_scene::generator::generate;

/// `frond sample`.
#[derive(clap::Args, Clone, Debug)]
pub struct SampleArgs {
    /// Size: small (~2k foliage triangles), medium (~20k), large (~200k), xlarge (~1M), or
    /// slender (~6k, large leaves round a trunk under a pixel wide when the tree is 60 px tall).
    #[arg(long, value_enum, default_value = "small")]
    pub preset: SampleSize,
    /// Random seed: same preset and seed, same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output .glb path.
    #[arg(short, long)]
    pub output: PathBuf,
}

impl SampleArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let SampleArgs {
            preset,
            seed,
            output,
        } = self;
        let tree = generate(preset.into(), seed).context("generating the sample tree")?;
        write_atomic(&output, &tree.glb)?;
        tracing::info!("wrote {} ({} bytes)", output.display(), tree.glb.len());
        Ok(())
    }
}
