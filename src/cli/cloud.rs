//! Build a static billboard cloud of the foliage (average pose) with baked atlases.

use std::path::PathBuf;

use anyhow::Result;
use frond_scene::Length;

use crate::cli::args::{ImportArgs, RunArgs};
use crate::cli::progress::{Spinner, print_json};
use crate::cli::values::BakeRasteriserArg;
use frond_app::cloud_cmd::{CloudRequest, run_cloud};
use frond_app::lod_settings::BakeRasteriser;
use frond_billboard::cloud::CloudParams;
use frond_billboard::plane_search::SearchParams;
use frond_render::Renderer;

/// `frond cloud`.
#[derive(clap::Args, Clone, Debug)]
pub struct CloudArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Largest vertex distance from a billboard: a length, or a percentage of the rest-pose
    /// bounding-box diagonal ("5%"); 0 = coplanar up to float noise.
    #[arg(long, default_value = "5%")]
    pub epsilon: Length,
    /// Candidate planes per iteration (the thesis's S).
    #[arg(long, default_value_t = 500)]
    pub planes: usize,
    /// Seed and loop sampling.
    #[command(flatten)]
    pub run: RunArgs,
    /// Favour billboards seen from this elevation in degrees (0 = vertical billboards).
    #[arg(long, value_name = "DEG")]
    pub view_penalty: Option<f32>,
    /// Weight contributions by 1/(d/ε+1) (distance falloff).
    #[arg(long)]
    pub falloff: bool,
    /// Least-squares refit of each plane (kept only if its triangles stay within ε).
    #[arg(long)]
    pub refit: bool,
    /// At most this many billboards; leftovers join the nearest plane.
    #[arg(long)]
    pub max_planes: Option<usize>,
    /// Bake every triangle valid for a plane, not only its own.
    #[arg(long)]
    pub increased_density: bool,
    /// Texels per world unit (default: 1024 across the bounding-box diagonal).
    #[arg(long)]
    pub texels_per_unit: Option<f32>,
    /// Largest atlas side; density is lowered (and reported) when the quads do not fit.
    #[arg(long, default_value_t = 4096)]
    pub max_atlas: u32,
    /// Rasteriser of the atlas: cpu (the same atlas on every machine) or wgpu (a GPU's).
    #[arg(long, value_enum, default_value_t = BakeRasteriserArg::Cpu)]
    pub bake_rasteriser: BakeRasteriserArg,
    /// Views of the coverage check (0 skips it).
    #[arg(long, default_value_t = 5)]
    pub coverage_views: u32,
    /// Screen height of the coverage check: the tree's rest height spans this many pixels of
    /// a 1080-pixel screen with a 60° vertical field of view.
    #[arg(long, default_value_t = 600.0)]
    pub coverage_height: f32,
    /// Use the plain O(planes·S·triangles) search (for comparison).
    #[arg(long)]
    pub plain: bool,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print stats.json to stdout.
    #[arg(long)]
    pub json: bool,
}

impl CloudArgs {
    /// Runs the command.
    pub fn run(self) -> Result<()> {
        let CloudArgs {
            import,
            epsilon,
            planes,
            run:
                RunArgs {
                    seed,
                    samples,
                    clip,
                },
            view_penalty,
            falloff,
            refit,
            max_planes,
            increased_density,
            texels_per_unit,
            max_atlas,
            bake_rasteriser,
            coverage_views,
            coverage_height,
            plain,
            output,
            json,
        } = self;
        let tree = import.load()?;
        let renderer = Renderer::new()?;
        let diag = tree.bounds.diagonal();
        let mut params = CloudParams {
            increased_density,
            ..Default::default()
        };
        params.search = SearchParams {
            candidates: planes,
            seed,
            view_penalty: view_penalty.map(f32::to_radians),
            falloff,
            refit,
            max_planes,
            accelerated: !plain,
            ..Default::default()
        };
        params.bake.texels_per_unit =
            texels_per_unit.unwrap_or(1024.0 / diag.max(f32::MIN_POSITIVE));
        params.bake.max_atlas = max_atlas;
        params.bake.rasteriser = BakeRasteriser::from(bake_rasteriser).rasteriser();
        let req = CloudRequest {
            epsilon,
            params,
            samples,
            clip,
            coverage_views,
            coverage_height,
        };
        let bar = Spinner::start();
        bar.say(&format!(
            "building the billboard cloud of {}",
            import.input.display()
        ));
        let result = run_cloud(&renderer, &tree, &req, &output);
        drop(bar);
        let report = result?;
        if json {
            print_json(&report)?;
        } else {
            crate::say!(
                "{}: {} billboards (ε = {:.4}), area {:.1}, atlas {}x{}, coverage error {}, search {:.3} s, bake {:.3} s, total {:.3} s",
                output.display(),
                report.billboards,
                report.epsilon,
                report.total_area,
                report.cloud.atlas_width,
                report.cloud.atlas_height,
                report
                    .coverage_error
                    .map(|c| format!("{c:.4}"))
                    .unwrap_or_else(|| "skipped".into()),
                report.cloud.timings_s.plane_search,
                report.cloud.timings_s.bake,
                report.cloud.timings_s.total
            );
        }
        Ok(())
    }
}
