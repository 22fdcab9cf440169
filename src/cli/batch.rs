//! Run `frond lod` over a tree library: every .glb/.gltf below a folder, or a TOML
//! manifest's trees with their own settings. `OUTDIR/<path without extension>/` per tree,
//! summary.json + summary.csv; up-to-date trees are skipped, failed ones recorded.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::cli::args::{BuildArgs, LimitArgs, MaterialArgs};
use crate::cli::progress::{BatchBar, finish_batch};
use crate::cli::values::{AnimationArg, EngineArg, MethodArg};
use frond_app::batch::inputs::Overrides;
use frond_app::batch::shard::Shard;
use frond_app::batch::tree_job::TreeContext;
use frond_app::batch::{BatchRequest, default_max_memory, parse_memory, run_batch};
use frond_app::engine_preset::EnginePreset;
use frond_app::lod_settings::{Animation, BuildSettings, Engine, Named};

/// `frond batch`.
#[derive(clap::Args, Clone, Debug)]
pub struct BatchArgs {
    /// A folder, or a .toml manifest (`[defaults]` and `[[tree]] path = ...` with method, lods,
    /// animation, foliage_material, ...; see docs/batch.md).
    pub input: PathBuf,
    /// Output folder (a shared volume for sharded runs).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Trees at once (default: one per core); each gets cores/jobs threads.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: Option<u64>,
    /// Do shard i of n (0-based), chosen by a hash of each tree's path relative to INPUT;
    /// `auto` reads JOB_COMPLETION_INDEX/JOB_COMPLETIONS (Kubernetes Indexed Job) or
    /// SLURM_ARRAY_TASK_ID/_MIN/_COUNT (Slurm array). Writes summary.shard-i-of-n.*.
    #[arg(long, value_name = "i/n|auto")]
    pub shard: Option<String>,
    /// Engine conventions (texture limits, external textures, MSFT_lod, VAT format,
    /// joint and influence checks; docs/engines.md).
    #[arg(long, value_enum)]
    pub preset: Option<EngineArg>,
    /// Memory the running trees may use together, like 8G (default: 3/4 of what is
    /// available); a larger tree runs alone.
    #[arg(long, value_name = "SIZE")]
    pub max_memory: Option<String>,
    /// Also run `frond eval` on every LOD at its screen height; metrics go to the summary.
    #[arg(long)]
    pub eval: bool,
    /// Skip each tree's preview page (`<name>_preview.html`) and the batch's `index.html`
    /// linking them.
    #[arg(long)]
    pub no_preview: bool,
    /// Clustering method of every tree (default: frond lod's).
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Screen heights in pixels, one LOD each (default: frond lod's).
    #[arg(long, value_delimiter = ',')]
    pub lods: Option<Vec<f32>>,
    /// skin, vat (EXR half), vat-png16 (refused by the web preset) or spectral.
    #[arg(long, value_enum)]
    pub animation: Option<AnimationArg>,
    /// Random seed of every tree.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Animation samples over the loop.
    #[arg(long)]
    pub samples: Option<usize>,
    /// Clip to sample.
    #[arg(long)]
    pub clip: Option<String>,
    /// Screen-space error budget in pixels.
    #[arg(long)]
    pub pixel_error: Option<f32>,
    /// Materials named as foliage or wood.
    #[command(flatten)]
    pub materials: MaterialArgs,
    /// What reading the input may cost.
    #[command(flatten)]
    pub limits: LimitArgs,
    /// Plane search, bake and method options.
    #[command(flatten)]
    pub build: BuildArgs,
    /// Seconds one tree's `frond lod` (or one eval) may take before it is stopped and
    /// recorded as failed.
    #[arg(long, default_value_t = 3600)]
    pub timeout: u64,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

impl BatchArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let BatchArgs {
            input,
            output,
            jobs,
            shard,
            preset,
            max_memory,
            eval,
            no_preview,
            method,
            lods,
            animation,
            seed,
            samples,
            clip,
            pixel_error,
            materials:
                MaterialArgs {
                    foliage_material,
                    wood_material,
                },
            limits,
            build,
            timeout,
            json,
        } = self;
        let defaults = Overrides {
            method: method.map(|m| m.0.text().to_string()),
            lods,
            animation: animation.map(|a| Animation::from(a).text().to_string()),
            foliage_material: (!foliage_material.is_empty()).then_some(foliage_material),
            wood_material: (!wood_material.is_empty()).then_some(wood_material),
            clip,
            seed,
            samples,
            pixel_error,
            clouds: build.clouds,
            clusters: build.clusters,
        };
        defaults.check("command line")?;
        let preset = preset.and_then(|p| EnginePreset::named(Engine::from(p).text()));
        if let (Some(p), Some(a)) = (&preset, animation) {
            p.check_animation(a.into())?;
        }
        let shard = match shard.as_deref() {
            None => None,
            Some("auto") => Some(Shard::from_env(&|k| std::env::var(k).ok()).context("--shard")?),
            Some(s) => Some(Shard::parse(s).context("--shard")?),
        };
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let jobs = jobs.map_or(cores, |j| j as usize);
        let build = BuildSettings {
            clouds: None,
            clusters: None,
            ..build.settings()
        };
        let req = BatchRequest {
            input,
            out_dir: output.clone(),
            jobs,
            shard,
            max_memory: match &max_memory {
                Some(m) => parse_memory(m).context("--max-memory")?,
                None => default_max_memory(),
            },
            context: TreeContext {
                exe: std::env::current_exe().context("locating the frond executable")?,
                out_dir: output.clone(),
                defaults,
                build,
                preset,
                eval,
                preview: !no_preview,
                timeout: std::time::Duration::from_secs(timeout.max(1)),
                threads: (cores / jobs).max(1),
                limits: limits.limits(),
            },
        };
        let bar = BatchBar::start();
        let result = run_batch(&req, &bar);
        drop(bar);
        let summary = result?;
        finish_batch(&summary, &output, json)?;
        Ok(())
    }
}
