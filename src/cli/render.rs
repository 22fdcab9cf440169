//! Render one frame of a tree (alpha-tested, offscreen) to PNG.

use std::path::PathBuf;

use crate::cli::values::PartsArg;
use anyhow::Result;

use crate::cli::args::ImportArgs;
use frond_app::out_folder::write_atomic;
use frond_app::render_cmd::{RenderRequest, frame_png, parse_size, render_tree};
use frond_render::Renderer;

/// `frond render`.
#[derive(clap::Args, Clone, Debug)]
pub struct RenderArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Time in seconds within the clip.
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// Clip name (default: the first).
    #[arg(long)]
    pub clip: Option<String>,
    /// Camera azimuth in degrees (0 looks from +Z, 90 from +X).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub azimuth: f32,
    /// Camera elevation in degrees (positive is above).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub elevation: f32,
    /// Camera distance relative to the framing distance.
    #[arg(long, default_value_t = 1.0)]
    pub zoom: f32,
    /// Image size as WxH.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Orthographic instead of perspective.
    #[arg(long)]
    pub ortho: bool,
    /// Draw only wood or only foliage.
    #[arg(long, value_enum, default_value = "all")]
    pub parts: PartsArg,
    /// Output PNG path.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print coverage and adapter as JSON.
    #[arg(long)]
    pub json: bool,
}

impl RenderArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let RenderArgs {
            import,
            time,
            clip,
            azimuth,
            elevation,
            zoom,
            size,
            ortho,
            parts,
            output,
            json,
        } = self;
        let (width, height) = parse_size(&size)?;
        if let (Ok(o), Ok(i)) = (output.canonicalize(), import.input.canonicalize())
            && o == i
        {
            anyhow::bail!("{}: -o names the input file", output.display());
        }
        let tree = import.load()?;
        let renderer = Renderer::new()?;
        let req = RenderRequest {
            clip,
            time,
            azimuth_deg: azimuth,
            elevation_deg: elevation,
            zoom,
            width,
            height,
            orthographic: ortho,
            parts: parts.into(),
        };
        let frame = render_tree(&renderer, &tree, &req)?;
        write_atomic(&output, &frame_png(&frame)?)?;
        if json {
            let v = serde_json::json!({
                "output": output.display().to_string(),
                "coverage": frame.coverage_fraction(),
                "adapter": renderer.adapter_info(),
            });
            crate::say!("{v}");
        }
        Ok(())
    }
}
