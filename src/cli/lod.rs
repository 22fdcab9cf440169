//! Animated billboard LOD chain: LOD0 (the input) and one LOD per screen height, skinned
//! or vertex-animated, with a combined file, mapping sidecars and <name>_report.json.

use std::path::PathBuf;

use anyhow::Result;

use crate::cli::args::{BuildArgs, ImportArgs, RunArgs};
use crate::cli::progress::{Spinner, print_json};
use crate::lod_cmd::{LodRequest, run_lod};
use frond_export::AnimationMode;
use frond_export::vat::VatFormat;
use frond_lod::method::ignored_options;
use frond_lod::{
    ChainRequest, CloudOptions, Method, MethodName, SkeletonOptions, SpectralOptions,
    screen_height_at, tree_height,
};
use frond_render::Renderer;
use frond_scene::Length;

/// `frond lod`.
#[derive(clap::Args, Clone, Debug)]
pub struct LodArgs {
    #[command(flatten)]
    pub import: ImportArgs,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Clustering: auto (see the README's rule), per-bone, static, spectral (SCA with
    /// the axis-phase type; spectral-naive, spectral-dominating-axis and
    /// spectral-axis-phase name the type) or skeleton (SBCS with the rotation-spectral
    /// bone type; skeleton-axis-angle and skeleton-rotation-spectral name the type).
    #[arg(long, default_value = "auto", value_parser = clap::builder::PossibleValuesParser::new(frond_lod::METHOD_NAMES.iter().map(|(n, _)| *n)))]
    pub method: String,
    /// Screen heights in pixels the whole tree covers, one LOD each, nearest first.
    #[arg(long, value_delimiter = ',', default_value = "600,200,60")]
    pub lods: Vec<f32>,
    /// LODs by viewing distance instead (world units), with --fov and --resolution.
    #[arg(long, value_delimiter = ',', conflicts_with = "lods")]
    pub distances: Option<Vec<f32>>,
    /// Vertical field of view in degrees (for --distances).
    #[arg(long, default_value_t = 60.0)]
    pub fov: f32,
    /// Image height in pixels (for --distances and MSFT_screencoverage).
    #[arg(long, default_value_t = 1080.0)]
    pub resolution: f32,
    /// Screen-space error budget in pixels.
    #[arg(long, default_value_t = 1.0)]
    pub pixel_error: f32,
    /// Override the derived ε: a length, or a percentage of the bounding-box diagonal.
    #[arg(long)]
    pub epsilon: Option<Length>,
    /// skin (glTF skin and channels), vat (vertex animation textures, EXR half), vat-png16,
    /// or spectral (skinned billboards + a small float texture of each billboard's cosine
    /// terms, with reference shaders; spectral and per-bone methods).
    #[arg(long, default_value = "skin", value_parser = ["skin", "vat", "vat-png16", "spectral"])]
    pub animation: String,
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub build: BuildArgs,
    /// Largest atlas side per LOD.
    #[arg(long, default_value_t = 4096)]
    pub max_atlas: u32,
    /// Dilated texels around each billboard texture: 2 covers bilinear filtering and the
    /// first mip level, which is all a LOD shown near its own size uses.
    #[arg(long, default_value_t = 2)]
    pub padding: u32,
    /// Add MSFT_lod (with MSFT_screencoverage) to the combined file.
    #[arg(long)]
    pub msft_lod: bool,
    /// Write textures as PNG files next to the GLBs instead of embedding them.
    #[arg(long)]
    pub external_textures: bool,
    /// Print the report (<name>_report.json) to stdout.
    #[arg(long)]
    pub json: bool,
}

impl LodArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let LodArgs {
            import,
            output,
            method,
            lods,
            distances,
            fov,
            resolution,
            pixel_error,
            epsilon,
            animation,
            run:
                RunArgs {
                    seed,
                    samples,
                    clip,
                },
            build,
            max_atlas,
            padding,
            msft_lod,
            external_textures,
            json,
        } = self;
        let tree = import.load()?;
        let renderer = Renderer::new()?;
        let screen_heights = match distances {
            Some(d) => {
                let h = tree_height(&tree);
                d.iter()
                    .map(|&z| {
                        if !(z.is_finite() && z > 0.0) {
                            anyhow::bail!("--distances: {z} is not a positive distance");
                        }
                        Ok(screen_height_at(h, z, fov, resolution))
                    })
                    .collect::<Result<Vec<_>>>()?
            }
            None => lods,
        };
        let spectral_animation = animation == "spectral";
        let name = MethodName::parse(&method).unwrap_or(MethodName::Auto);
        let (spectral, skeleton) = build.method_options()?;
        for w in ignored_options(
            name,
            spectral != SpectralOptions::default(),
            skeleton != SkeletonOptions::default(),
            spectral_animation,
        ) {
            tracing::warn!("{w}");
        }
        let req = LodRequest {
            chain: ChainRequest {
                method: Method::new(name, spectral, skeleton),
                screen_heights,
                pixel_error,
                epsilon,
                spectral_animation,
                seed,
                samples,
                clip,
                cloud: CloudOptions {
                    planes: build.planes,
                    view_penalty: build.view_penalty.map(f32::to_radians),
                    increased_density: build.increased_density,
                    max_atlas,
                    supersample: build.supersample,
                    padding,
                },
            },
            animation: match animation.as_str() {
                "vat" => AnimationMode::Vat(VatFormat::ExrHalf),
                "vat-png16" => AnimationMode::Vat(VatFormat::Png16),
                "spectral" => AnimationMode::Spectral,
                _ => AnimationMode::Skin,
            },
            msft_lod,
            resolution,
            external_textures,
        };
        let bar = Spinner::new();
        let result = run_lod(&renderer, &tree, &req, &output, &|m: &str| bar.say(m));
        drop(bar);
        let report = result?;
        if json {
            print_json(&report)?;
        } else {
            for l in &report.lods {
                println!(
                    "{}: {} triangles, {} billboards, {} bones, {} texture bytes ({})",
                    l.file, l.triangles, l.billboards, l.bones, l.texture_bytes, l.method
                );
            }
            println!(
                "{}: {} LODs combined; {}; {:.2} s",
                report.combined,
                report.lods.len(),
                frond_lod::report::report_name(&report.name),
                report.timings_s["total"].as_f64().unwrap_or(0.0)
            );
        }
        Ok(())
    }
}
