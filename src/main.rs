//! The `frond` command line.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use frond::inspect::inspect;
use frond::output::write_atomic;
use frond_scene::generator::{Preset, generate};
use frond_scene::{ImportOptions, import};

#[derive(Parser)]
#[command(
    name = "frond",
    version,
    about = "Animated billboard-cloud LOD chains for wind-animated trees"
)]
struct Cli {
    /// Log more (-v info, -vv debug); RUST_LOG overrides.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone, Debug)]
struct ImportArgs {
    /// Input tree (.glb or .gltf).
    input: PathBuf,
    /// Treat this material as foliage (repeatable).
    #[arg(long = "foliage-material", value_name = "NAME")]
    foliage_material: Vec<String>,
    /// Treat this material as wood (repeatable).
    #[arg(long = "wood-material", value_name = "NAME")]
    wood_material: Vec<String>,
}

impl ImportArgs {
    fn load(&self) -> Result<frond_scene::Tree> {
        let options = ImportOptions {
            foliage_materials: self.foliage_material.clone(),
            wood_materials: self.wood_material.clone(),
        };
        Ok(import(&self.input, &options)?)
    }
}

#[derive(Subcommand)]
enum Command {
    /// Report bones, skeleton depth, wood/foliage split, clips, looping and bounds.
    Inspect {
        #[command(flatten)]
        import: ImportArgs,
        /// Machine-readable JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Write a skinned, wind-animated sample tree (.glb).
    Sample {
        /// Size: small (~2k foliage triangles), medium (~20k), large (~200k), xlarge (~1M).
        #[arg(long, default_value = "small", value_parser = ["small", "medium", "large", "xlarge"])]
        preset: String,
        /// Random seed: same preset and seed, same bytes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output .glb path.
        #[arg(short, long)]
        output: PathBuf,
    },
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Inspect { import, json } => {
            let tree = import.load()?;
            let report = inspect(&tree);
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&report).context("serialising the report")?
                );
            } else {
                print!("{}", report.text());
            }
        }
        Command::Sample { preset, seed, output } => {
            let preset = Preset::parse(&preset).with_context(|| format!("unknown preset '{preset}'"))?;
            let tree = generate(preset, seed).context("generating the sample tree")?;
            write_atomic(&output, &tree.glb)?;
            tracing::info!("wrote {} ({} bytes)", output.display(), tree.glb.len());
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
