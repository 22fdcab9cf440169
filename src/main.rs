//! The `frond` command line.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

use frond::batch::inputs::{ANIMATION_NAMES, Overrides};
use frond::batch::preset::{EnginePreset, PRESET_NAMES};
use frond::batch::shard::Shard;
use frond::batch::summary::{BatchSummary, Status, TreeEntry, merge, read_summary, summaries_in};
use frond::batch::tree_job::TreeContext;
use frond::batch::{BatchProgress, BatchRequest, default_max_memory, parse_memory, run_batch};
use frond::cloud_cmd::{CloudRequest, run_cloud};
use frond::eval_cmd::{EvalRequest, evaluate, image_for_screen_height, same_bytes};
use frond::inspect::{SamplingSummary, inspect};
use frond::lod_cmd::{LodRequest, run_lod};
use frond::output::write_atomic;
use frond::render_cmd::{RenderRequest, frame_png, parse_size, render_tree};
use frond::sweep::grid::{Grid, parse_epsilons};
use frond::sweep::{SweepRequest, run_sweep};
use frond_billboard::cloud::CloudParams;
use frond_billboard::plane_search::SearchParams;
use frond_export::AnimationMode;
use frond_export::vat::VatFormat;
use frond_lod::method::ignored_options;
use frond_lod::{
    ChainRequest, CloudOptions, Method, MethodName, SkeletonOptions, SpectralOptions,
    screen_height_at, tree_height,
};
use frond_render::{Renderer, TreeParts};
use frond_scene::generator::{Preset, generate};
use frond_scene::{ImportOptions, Length, SampleOptions, import, sample};

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
    #[command(flatten)]
    limits: LimitArgs,
}

impl ImportArgs {
    fn load(&self) -> Result<frond_scene::Tree> {
        let options = ImportOptions {
            foliage_materials: self.foliage_material.clone(),
            wood_materials: self.wood_material.clone(),
            limits: self.limits.limits(),
            ..Default::default()
        };
        Ok(import(&self.input, &options)?)
    }
}

/// What reading one input may cost (every command that reads a tree; `frond batch` passes
/// them to each tree's run).
#[derive(clap::Args, Clone, Debug)]
struct LimitArgs {
    /// Refuse an input whose file plus external buffers exceed this size (K, M, G: binary
    /// units; 1G = 1 GiB).
    #[arg(long, value_name = "SIZE", default_value = "1G", value_parser = parse_size_arg)]
    max_input_size: u64,
    /// Refuse an input whose base-colour textures decode to more than this, at 4 bytes a
    /// texel (384M = six 4096² maps); checked from the image headers before decoding.
    #[arg(long, value_name = "SIZE", default_value = "384M", value_parser = parse_size_arg)]
    max_texture_memory: u64,
    /// Refuse an input whose mesh instances add up to more vertices than this (counted from
    /// the accessors before decoding; 8000000 is four times the xlarge sample).
    #[arg(long, value_name = "N", default_value_t = frond_scene::input_file::DEFAULT_MAX_VERTICES)]
    max_vertices: u64,
}

impl LimitArgs {
    fn limits(&self) -> frond_scene::InputLimits {
        frond_scene::InputLimits {
            max_input_bytes: self.max_input_size,
            max_texture_bytes: self.max_texture_memory,
            max_vertices: self.max_vertices,
        }
    }
}

/// A size option's value (`parse_memory`'s units), for clap.
fn parse_size_arg(text: &str) -> std::result::Result<u64, String> {
    parse_memory(text).map_err(|e| format!("{e:#}"))
}

/// Plane search and bake options of `frond lod`, which `frond sweep` passes to every build.
#[derive(clap::Args, Clone, Debug)]
struct BuildArgs {
    /// Candidate planes per iteration of the plane search.
    #[arg(long, default_value_t = 100)]
    planes: usize,
    /// Favour billboards seen from this elevation in degrees (0 = vertical billboards).
    #[arg(long, value_name = "DEG")]
    view_penalty: Option<f32>,
    /// Bake every triangle valid for a plane, not only its own.
    #[arg(long)]
    increased_density: bool,
    /// Supersamples per texel side when baking (1-16; 4 = 4×4, 2 is ~2.5× faster).
    #[arg(long, default_value_t = 4)]
    supersample: u32,
    /// Spectral methods: animation clusters per LOD (default: one per 10 pixels of screen
    /// height, at least 1).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    clusters: Option<u64>,
    /// Spectral methods: animation zone size, a length or % of the diagonal (default: 2% or
    /// the LOD's ε, the larger; 0: a zone per triangle, triangles with one centre sharing one).
    #[arg(long, value_name = "SIZE")]
    zone_size: Option<Length>,
    /// Spectral methods: no shared-bone binding; billboards translate in world space only.
    #[arg(long)]
    no_shared_bone: bool,
    /// Skeleton methods: billboard clouds per LOD (default: as few as merges that cannot be
    /// seen at the LOD's size allow; a budget CJR cannot reach collapses sibling bones).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    clouds: Option<u64>,
    /// Skeleton methods: merged bones keep their own animation and only their foliage turns
    /// by the common rotation (thesis §7.1.2; the foliage then drifts off its branch).
    #[arg(long)]
    average_bone: bool,
}

impl BuildArgs {
    /// The spectral and skeleton methods' options (description types at their defaults: the
    /// method name sets them).
    fn method_options(&self) -> Result<(SpectralOptions, SkeletonOptions)> {
        Ok((
            SpectralOptions {
                clusters: self.clusters.map(|k| k as usize),
                zone_size: self.zone_size,
                shared_bone: !self.no_shared_bone,
                ..Default::default()
            },
            SkeletonOptions {
                clouds: self.clouds.map(|c| c as usize),
                average_bone: self.average_bone,
                ..Default::default()
            },
        ))
    }

    /// The same options as `frond lod` arguments.
    fn to_args(&self) -> Vec<String> {
        let mut a = vec![
            "--planes".to_string(),
            self.planes.to_string(),
            "--supersample".to_string(),
            self.supersample.to_string(),
        ];
        if let Some(v) = self.view_penalty {
            a.extend(["--view-penalty".to_string(), v.to_string()]);
        }
        if self.increased_density {
            a.push("--increased-density".to_string());
        }
        if let Some(k) = self.clusters {
            a.extend(["--clusters".to_string(), k.to_string()]);
        }
        if let Some(z) = &self.zone_size {
            a.extend(["--zone-size".to_string(), z.to_string()]);
        }
        if self.no_shared_bone {
            a.push("--no-shared-bone".to_string());
        }
        if let Some(c) = self.clouds {
            a.extend(["--clouds".to_string(), c.to_string()]);
        }
        if self.average_bone {
            a.push("--average-bone".to_string());
        }
        a
    }
}

/// Seed and loop sampling, shared by the commands that build billboards.
#[derive(clap::Args, Clone, Debug)]
struct RunArgs {
    /// Random seed: same input and seed, same files.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Animation samples over the loop.
    #[arg(long, default_value_t = 64)]
    samples: usize,
    /// Clip to sample (default: the first); billboards' own motion plays only this one.
    #[arg(long)]
    clip: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Report bones, skeleton depth, wood/foliage split, clips, looping and bounds.
    Inspect {
        #[command(flatten)]
        import: ImportArgs,
        /// Clip to sample (default: the first).
        #[arg(long)]
        clip: Option<String>,
        /// Uniform samples over the loop.
        #[arg(long, default_value_t = 64)]
        samples: usize,
        /// Machine-readable JSON on stdout.
        #[arg(long)]
        json: bool,
    },
    /// Render one frame of a tree (alpha-tested, offscreen) to PNG.
    Render {
        #[command(flatten)]
        import: ImportArgs,
        /// Time in seconds within the clip.
        #[arg(long, default_value_t = 0.0)]
        time: f32,
        /// Clip name (default: the first).
        #[arg(long)]
        clip: Option<String>,
        /// Camera azimuth in degrees (0 looks from +Z, 90 from +X).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        azimuth: f32,
        /// Camera elevation in degrees (positive is above).
        #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
        elevation: f32,
        /// Camera distance relative to the framing distance.
        #[arg(long, default_value_t = 1.0)]
        zoom: f32,
        /// Image size as WxH.
        #[arg(long, default_value = "512x512")]
        size: String,
        /// Orthographic instead of perspective.
        #[arg(long)]
        ortho: bool,
        /// Draw only wood or only foliage.
        #[arg(long, value_parser = ["all", "wood", "foliage"], default_value = "all")]
        parts: String,
        /// Output PNG path.
        #[arg(short, long)]
        output: PathBuf,
        /// Print coverage and adapter as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Build a static billboard cloud of the foliage (average pose) with baked atlases.
    Cloud {
        #[command(flatten)]
        import: ImportArgs,
        /// Largest vertex distance from a billboard: a length, or a percentage of the rest-pose
        /// bounding-box diagonal ("5%"); 0 = coplanar up to float noise.
        #[arg(long, default_value = "5%")]
        epsilon: String,
        /// Candidate planes per iteration (the thesis's S).
        #[arg(long, default_value_t = 500)]
        planes: usize,
        #[command(flatten)]
        run: RunArgs,
        /// Favour billboards seen from this elevation in degrees (0 = vertical billboards).
        #[arg(long, value_name = "DEG")]
        view_penalty: Option<f32>,
        /// Weight contributions by 1/(d/ε+1) (distance falloff).
        #[arg(long)]
        falloff: bool,
        /// Least-squares refit of each plane (kept only if its triangles stay within ε).
        #[arg(long)]
        refit: bool,
        /// At most this many billboards; leftovers join the nearest plane.
        #[arg(long)]
        max_planes: Option<usize>,
        /// Bake every triangle valid for a plane, not only its own.
        #[arg(long)]
        increased_density: bool,
        /// Texels per world unit (default: 1024 across the bounding-box diagonal).
        #[arg(long)]
        texels_per_unit: Option<f32>,
        /// Largest atlas side; density is lowered (and reported) when the quads do not fit.
        #[arg(long, default_value_t = 4096)]
        max_atlas: u32,
        /// Views of the coverage check (0 skips it).
        #[arg(long, default_value_t = 5)]
        coverage_views: u32,
        /// Image size of the coverage check.
        #[arg(long, default_value = "800x600")]
        coverage_size: String,
        /// Use the plain O(planes·S·triangles) search (for comparison).
        #[arg(long)]
        plain: bool,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Print stats.json to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Animated billboard LOD chain: LOD0 (the input) and one LOD per screen height, skinned
    /// or vertex-animated, with a combined file, mapping sidecars and <name>_report.json.
    Lod {
        #[command(flatten)]
        import: ImportArgs,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Clustering: auto (see the README's rule), per-bone, static, spectral (SCA with
        /// the axis-phase type; spectral-naive, spectral-dominating-axis and
        /// spectral-axis-phase name the type) or skeleton (SBCS with the rotation-spectral
        /// bone type; skeleton-axis-angle and skeleton-rotation-spectral name the type).
        #[arg(long, default_value = "auto", value_parser = clap::builder::PossibleValuesParser::new(frond_lod::METHOD_NAMES.iter().map(|(n, _)| *n)))]
        method: String,
        /// Screen heights in pixels the whole tree covers, one LOD each, nearest first.
        #[arg(long, value_delimiter = ',', default_value = "600,200,60")]
        lods: Vec<f32>,
        /// LODs by viewing distance instead (world units), with --fov and --resolution.
        #[arg(long, value_delimiter = ',', conflicts_with = "lods")]
        distances: Option<Vec<f32>>,
        /// Vertical field of view in degrees (for --distances).
        #[arg(long, default_value_t = 60.0)]
        fov: f32,
        /// Image height in pixels (for --distances and MSFT_screencoverage).
        #[arg(long, default_value_t = 1080.0)]
        resolution: f32,
        /// Screen-space error budget in pixels.
        #[arg(long, default_value_t = 1.0)]
        pixel_error: f32,
        /// Override the derived ε: a length, or a percentage of the bounding-box diagonal.
        #[arg(long)]
        epsilon: Option<Length>,
        /// skin (glTF skin and channels), vat (vertex animation textures, EXR half), vat-png16,
        /// or spectral (skinned billboards + a small float texture of each billboard's cosine
        /// terms, with reference shaders; spectral and per-bone methods).
        #[arg(long, default_value = "skin", value_parser = ["skin", "vat", "vat-png16", "spectral"])]
        animation: String,
        #[command(flatten)]
        run: RunArgs,
        #[command(flatten)]
        build: BuildArgs,
        /// Largest atlas side per LOD.
        #[arg(long, default_value_t = 4096)]
        max_atlas: u32,
        /// Dilated texels around each billboard texture: 2 covers bilinear filtering and the
        /// first mip level, which is all a LOD shown near its own size uses.
        #[arg(long, default_value_t = 2)]
        padding: u32,
        /// Add MSFT_lod (with MSFT_screencoverage) to the combined file.
        #[arg(long)]
        msft_lod: bool,
        /// Write textures as PNG files next to the GLBs instead of embedding them.
        #[arg(long)]
        external_textures: bool,
        /// Print the report (<name>_report.json) to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Compare a candidate (a LOD, any glTF) with the original: colour (coverage), colour
    /// difference, distance, orientation and animation metrics, and cost.
    Eval {
        #[command(flatten)]
        import: ImportArgs,
        /// The candidate model (.glb/.gltf); a `frond lod` LOD's `.mapping.json` beside it
        /// enables the per-triangle metrics.
        candidate: PathBuf,
        /// Ring views of the colour metric.
        #[arg(long, default_value_t = 5)]
        views: u32,
        /// Frames of the animated colour metric, uniform over the loop.
        #[arg(long, default_value_t = 5)]
        frames: u32,
        /// Image size of the colour metric (default 800x600).
        #[arg(long, conflicts_with = "screen_height")]
        size: Option<String>,
        /// Size the images for a tree seen this many pixels high (the LOD's size), 4:3.
        #[arg(long)]
        screen_height: Option<u32>,
        /// Samples over the loop for the trajectory metrics.
        #[arg(long, default_value_t = 64)]
        samples: usize,
        /// Clip (default: the original's first; the candidate plays the clip of that name).
        #[arg(long)]
        clip: Option<String>,
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Run `frond lod` over a grid of screen heights (or fixed ε) × methods × seeds, evaluate
    /// every LOD (and external candidates) with `frond eval`, and write results.csv, the
    /// stability table, failures and charts (SVG + PNG).
    Sweep {
        #[command(flatten)]
        import: ImportArgs,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
        /// Methods to compare.
        #[arg(long, value_delimiter = ',', default_value = "per-bone,static",
              value_parser = clap::builder::PossibleValuesParser::new(frond_lod::METHOD_NAMES.iter().map(|(n, _)| *n)))]
        method: Vec<String>,
        /// Screen heights (pixels), one LOD each; ε follows the screen-space rule.
        #[arg(long, value_delimiter = ',', default_value = "600,200,60")]
        lods: Vec<f32>,
        /// Fixed ε instead of screen heights: a range "A..B" (with --steps) or a list "A,B,C";
        /// each a length or a percentage of the bounding-box diagonal.
        #[arg(long)]
        epsilon: Option<String>,
        /// Values of an --epsilon range, both ends included.
        #[arg(long, default_value_t = 6)]
        steps: usize,
        /// Screen height (pixels) the fixed-ε LODs are textured and evaluated at.
        #[arg(long, default_value_t = 600.0)]
        screen_height: f32,
        /// Seeds per configuration (1..=N).
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// External candidate (any glTF) evaluated at every screen height (repeatable).
        #[arg(long = "candidate", value_name = "FILE")]
        candidates: Vec<PathBuf>,
        /// Ring views of the colour metric.
        #[arg(long, default_value_t = 5)]
        views: u32,
        /// Frames of the animated colour metric.
        #[arg(long, default_value_t = 5)]
        frames: u32,
        /// Animation samples over the loop (build and trajectory metrics).
        #[arg(long, default_value_t = 64)]
        samples: usize,
        /// Clip to sample (default: the first).
        #[arg(long)]
        clip: Option<String>,
        #[command(flatten)]
        build: BuildArgs,
        /// Seconds one run's build (or evaluation) may take before it is stopped and recorded
        /// as a timeout.
        #[arg(long, default_value_t = 900)]
        timeout: u64,
        /// Keep every run's LOD files under runs/ (default: only their reports).
        #[arg(long)]
        keep: bool,
        /// Print summary.json to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Run `frond lod` over a tree library: every .glb/.gltf below a folder, or a TOML
    /// manifest's trees with their own settings. OUTDIR/<path without extension>/ per tree,
    /// summary.json + summary.csv; up-to-date trees are skipped, failed ones recorded.
    Batch {
        /// A folder, or a .toml manifest ([defaults] and [[tree]] path = ... with method, lods,
        /// animation, foliage_material, ...; see docs/batch.md).
        input: PathBuf,
        /// Output folder (a shared volume for sharded runs).
        #[arg(short, long)]
        output: PathBuf,
        /// Trees at once (default: one per core); each gets cores/jobs threads.
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        jobs: Option<u64>,
        /// Do shard i of n (0-based), chosen by a hash of each tree's path relative to INPUT;
        /// `auto` reads JOB_COMPLETION_INDEX/JOB_COMPLETIONS (Kubernetes Indexed Job) or
        /// SLURM_ARRAY_TASK_ID/_MIN/_COUNT (Slurm array). Writes summary.shard-i-of-n.*.
        #[arg(long, value_name = "i/n|auto")]
        shard: Option<String>,
        /// Engine conventions (texture limits, external textures, MSFT_lod, VAT format,
        /// joint and influence checks; docs/engines.md).
        #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(PRESET_NAMES))]
        preset: Option<String>,
        /// Memory the running trees may use together, like 8G (default: 3/4 of what is
        /// available); a larger tree runs alone.
        #[arg(long, value_name = "SIZE")]
        max_memory: Option<String>,
        /// Also run `frond eval` on every LOD at its screen height; metrics go to the summary.
        #[arg(long)]
        eval: bool,
        /// Clustering method of every tree (default: frond lod's).
        #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(frond_lod::METHOD_NAMES.iter().map(|(n, _)| *n)))]
        method: Option<String>,
        /// Screen heights in pixels, one LOD each (default: frond lod's).
        #[arg(long, value_delimiter = ',')]
        lods: Option<Vec<f32>>,
        /// skin, vat (EXR half), vat-png16 (refused by the web preset) or spectral.
        #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(ANIMATION_NAMES))]
        animation: Option<String>,
        /// Random seed of every tree.
        #[arg(long)]
        seed: Option<u64>,
        /// Animation samples over the loop.
        #[arg(long)]
        samples: Option<usize>,
        /// Clip to sample.
        #[arg(long)]
        clip: Option<String>,
        /// Screen-space error budget in pixels.
        #[arg(long)]
        pixel_error: Option<f32>,
        /// Treat this material as foliage (repeatable).
        #[arg(long = "foliage-material", value_name = "NAME")]
        foliage_material: Vec<String>,
        /// Treat this material as wood (repeatable).
        #[arg(long = "wood-material", value_name = "NAME")]
        wood_material: Vec<String>,
        #[command(flatten)]
        limits: LimitArgs,
        #[command(flatten)]
        build: BuildArgs,
        /// Seconds one tree's `frond lod` (or one eval) may take before it is stopped and
        /// recorded as failed.
        #[arg(long, default_value_t = 3600)]
        timeout: u64,
        /// Print summary.json to stdout.
        #[arg(long)]
        json: bool,
    },
    /// Merge the summaries of a sharded batch (summary.shard-*.json in each folder) into one
    /// summary.json + summary.csv.
    BatchMerge {
        /// Output folders of the shards (often one shared folder).
        #[arg(required = true)]
        outputs: Vec<PathBuf>,
        /// Folder for the merged summary (default: the first).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print the merged summary.json to stdout.
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
        Command::Inspect {
            import,
            clip,
            samples,
            json,
        } => {
            let tree = import.load()?;
            let start = std::time::Instant::now();
            let sampled = sample(&tree, &SampleOptions { clip, samples })?;
            let summary = SamplingSummary::of(&sampled, start.elapsed().as_secs_f64());
            drop(sampled);
            let report = inspect(&tree, summary);
            if json {
                print_json(&report)?;
            } else {
                print!("{}", report.text());
            }
        }
        Command::Render {
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
        } => {
            let (width, height) = parse_size(&size)?;
            if let (Ok(o), Ok(i)) = (output.canonicalize(), import.input.canonicalize())
                && o == i
            {
                anyhow::bail!("{}: -o names the input file", output.display());
            }
            let tree = import.load()?;
            let renderer = Renderer::new()?;
            let parts = match parts.as_str() {
                "wood" => TreeParts::Wood,
                "foliage" => TreeParts::Foliage,
                _ => TreeParts::All,
            };
            let req = RenderRequest {
                clip,
                time,
                azimuth_deg: azimuth,
                elevation_deg: elevation,
                zoom,
                width,
                height,
                orthographic: ortho,
                parts,
            };
            let frame = render_tree(&renderer, &tree, &req)?;
            write_atomic(&output, &frame_png(&frame)?)?;
            if json {
                let v = serde_json::json!({
                    "output": output.display().to_string(),
                    "coverage": frame.coverage_fraction(),
                    "adapter": renderer.adapter_info(),
                });
                println!("{v}");
            }
        }
        Command::Cloud {
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
            coverage_views,
            coverage_size,
            plain,
            output,
            json,
        } => {
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
            let req = CloudRequest {
                epsilon,
                params,
                samples,
                clip,
                coverage_views,
                coverage_size: parse_size(&coverage_size)?,
            };
            let bar = Spinner::new();
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
                println!(
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
        }
        Command::Lod {
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
        } => {
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
        }
        Command::Eval {
            import,
            candidate,
            views,
            frames,
            size,
            screen_height,
            samples,
            clip,
            json,
        } => {
            let original = import.load()?;
            let cand = frond_scene::import(
                &candidate,
                &ImportOptions {
                    allow_empty: true,
                    limits: import.limits.limits(),
                    ..Default::default()
                },
            )?;
            let same_file = same_bytes(&import.input, &candidate);
            let size = match (size, screen_height) {
                (Some(s), _) => parse_size(&s)?,
                (None, Some(h)) if h > 0 => image_for_screen_height(h),
                (None, Some(_)) => anyhow::bail!("--screen-height must be at least 1"),
                (None, None) => (800, 600),
            };
            let renderer = Renderer::new()?;
            let req = EvalRequest {
                views,
                frames,
                size,
                samples,
                clip,
            };
            let bar = Spinner::new();
            bar.say(&format!("evaluating {}", candidate.display()));
            let result = evaluate(&renderer, &original, &cand, same_file, &req);
            drop(bar);
            let report = result?;
            if json {
                print_json(&report)?;
            } else {
                let show = |name: &str, m: &frond::eval_cmd::Metric| match (m.mean, m.max) {
                    (Some(a), Some(b)) => println!("{name:26} mean {a:.5}  max {b:.5}"),
                    _ => println!(
                        "{name:26} skipped: {}",
                        m.skipped_reason.as_deref().unwrap_or("-")
                    ),
                };
                show("coverage (static)", &report.coverage.static_);
                show("coverage (animated)", &report.coverage.animated);
                show("colour difference", &report.colour_difference);
                show("plane distance", &report.plane_distance);
                show("projected distance", &report.projected_distance);
                show("orientation", &report.orientation);
                show("dominating axis", &report.dominating_axis);
                show("dominating axis spectral", &report.dominating_axis_spectral);
                println!(
                    "cost: {} → {} triangles, {} → {} billboards, {} → {} texture bytes",
                    report.cost.original.triangles,
                    report.cost.candidate.triangles,
                    report.cost.original.billboards,
                    report.cost.candidate.billboards,
                    report.cost.original.texture_bytes,
                    report.cost.candidate.texture_bytes
                );
            }
        }
        Command::Sweep {
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
        } => {
            let tree = import.load()?;
            let diagonal = tree.bounds.diagonal();
            let grid = match &epsilon {
                Some(text) => {
                    if !(screen_height.is_finite() && screen_height >= 1.0) {
                        anyhow::bail!("--screen-height must be at least 1 pixel");
                    }
                    Grid::Epsilons {
                        values: parse_epsilons(text, steps, diagonal)?,
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
            let mut import_args = vec![import.input.display().to_string()];
            for m in &import.foliage_material {
                import_args.extend(["--foliage-material".to_string(), m.clone()]);
            }
            for m in &import.wood_material {
                import_args.extend(["--wood-material".to_string(), m.clone()]);
            }
            let mut lod_args = vec!["--samples".to_string(), samples.to_string()];
            if let Some(c) = &clip {
                lod_args.extend(["--clip".to_string(), c.clone()]);
            }
            lod_args.extend(build.to_args());
            let eval = EvalRequest {
                views,
                frames,
                size: (800, 600),
                samples,
                clip,
            };
            let req = SweepRequest {
                exe: std::env::current_exe().context("locating the frond executable")?,
                import_args,
                methods: method,
                grid,
                seeds: (1..=seeds).collect(),
                lod_args,
                candidates,
                timeout: std::time::Duration::from_secs(timeout.max(1)),
                keep,
                diagonal,
            };
            let renderer = Renderer::new()?;
            let bar = Progress::new();
            let result = run_sweep(&renderer, &tree, &req, &eval, &output, &|d, t, m| {
                bar.step(d, t, m)
            });
            drop(bar);
            let summary = result?;
            if json {
                print_json(&summary)?;
            } else {
                println!(
                    "{}: {} runs ({} failed); results.csv, stability.md, charts; {:.1} s",
                    output.display(),
                    summary.runs,
                    summary.failed,
                    summary.timings_s["total"].as_f64().unwrap_or(0.0)
                );
            }
            if summary.failed > 0 {
                eprintln!(
                    "{} of {} runs failed (listed in {})",
                    summary.failed,
                    summary.runs,
                    output.join("stability.md").display()
                );
            }
        }
        Command::Batch {
            input,
            output,
            jobs,
            shard,
            preset,
            max_memory,
            eval,
            method,
            lods,
            animation,
            seed,
            samples,
            clip,
            pixel_error,
            foliage_material,
            wood_material,
            limits,
            build,
            timeout,
            json,
        } => {
            let defaults = Overrides {
                method,
                lods,
                animation,
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
            let preset = preset.as_deref().and_then(EnginePreset::named);
            if let (Some(p), Some(a)) = (&preset, &defaults.animation) {
                p.lod_args(a)?;
            }
            let shard = match shard.as_deref() {
                None => None,
                Some("auto") => Some(Shard::from_env(&|k| std::env::var(k).ok())?),
                Some(s) => Some(Shard::parse(s)?),
            };
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            let jobs = jobs.map_or(cores, |j| j as usize);
            let build_args = BuildArgs {
                clouds: None,
                clusters: None,
                ..build
            }
            .to_args();
            let req = BatchRequest {
                input,
                out_dir: output.clone(),
                jobs,
                shard,
                max_memory: match &max_memory {
                    Some(m) => parse_memory(m)?,
                    None => default_max_memory(),
                },
                context: TreeContext {
                    exe: std::env::current_exe().context("locating the frond executable")?,
                    out_dir: output.clone(),
                    defaults,
                    build_args,
                    preset,
                    eval,
                    timeout: std::time::Duration::from_secs(timeout.max(1)),
                    threads: (cores / jobs).max(1),
                    limits: limits.limits(),
                },
            };
            let bar = BatchBar::new();
            let result = run_batch(&req, &bar);
            drop(bar);
            let summary = result?;
            finish_batch(&summary, &output, json)?;
        }
        Command::BatchMerge {
            outputs,
            output,
            json,
        } => {
            let mut parts = Vec::new();
            for dir in &outputs {
                for path in summaries_in(dir)? {
                    let s = read_summary(&path)?;
                    parts.push((path, s));
                }
            }
            let (summary, warnings) = merge(&parts)?;
            for w in &warnings {
                eprintln!("warning: {w}");
            }
            let dir = output.unwrap_or_else(|| outputs[0].clone());
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("{}: cannot create", dir.display()))?;
            summary.write(&dir, &BatchSummary::stem(None))?;
            finish_batch(&summary, &dir, json)?;
        }
        Command::Sample {
            preset,
            seed,
            output,
        } => {
            let preset =
                Preset::parse(&preset).with_context(|| format!("unknown preset '{preset}'"))?;
            let tree = generate(preset, seed).context("generating the sample tree")?;
            write_atomic(&output, &tree.glb)?;
            tracing::info!("wrote {} ({} bytes)", output.display(), tree.glb.len());
        }
    }
    Ok(())
}

/// A spinner with a message on a terminal (nothing otherwise); messages also go to the log.
struct Spinner(Option<indicatif::ProgressBar>);

impl Spinner {
    fn new() -> Self {
        Spinner(
            std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
                let b = indicatif::ProgressBar::new_spinner();
                b.enable_steady_tick(std::time::Duration::from_millis(120));
                b
            }),
        )
    }
    fn say(&self, msg: &str) {
        tracing::info!("{msg}");
        if let Some(b) = &self.0 {
            b.set_message(msg.to_string());
        }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

/// A progress bar over a known number of steps on a terminal; log lines otherwise.
struct Progress(Option<indicatif::ProgressBar>);

impl Progress {
    fn new() -> Self {
        Progress(
            std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
                let b = indicatif::ProgressBar::new(0);
                if let Ok(style) = indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} {elapsed_precise} (eta {eta}) {msg}",
                ) {
                    b.set_style(style);
                }
                b.enable_steady_tick(std::time::Duration::from_millis(250));
                b
            }),
        )
    }
    fn step(&self, done: usize, total: usize, msg: &str) {
        tracing::info!("[{done}/{total}] {msg}");
        if let Some(b) = &self.0 {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(msg.to_string());
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

/// The end of `frond batch` and `batch-merge`: the summary (with `--json`) and the count line,
/// an error (non-zero exit) when any tree failed.
fn finish_batch(summary: &BatchSummary, dir: &std::path::Path, json: bool) -> Result<()> {
    if json {
        print_json(summary)?;
    }
    let line = summary.counts.line();
    if summary.counts.failed > 0 {
        anyhow::bail!(
            "{line} (reasons in {})",
            dir.join(format!("{}.json", BatchSummary::stem(summary.shard)))
                .display()
        );
    }
    if !json {
        println!("{}: {line}", dir.display());
    }
    Ok(())
}

/// `frond batch` progress: an overall bar plus a spinner per running tree on a terminal, plain
/// log lines otherwise; a failed tree's error line always.
struct BatchBar {
    bars: Option<(indicatif::MultiProgress, indicatif::ProgressBar)>,
    running: std::sync::Mutex<Vec<(String, indicatif::ProgressBar)>>,
    done: std::sync::atomic::AtomicUsize,
    total: std::sync::atomic::AtomicUsize,
}

impl BatchBar {
    fn new() -> Self {
        let bars = std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
            let multi = indicatif::MultiProgress::new();
            let b = multi.add(indicatif::ProgressBar::new(0));
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} trees {elapsed_precise} (eta {eta}) {msg}",
            ) {
                b.set_style(style);
            }
            b.enable_steady_tick(std::time::Duration::from_millis(250));
            (multi, b)
        });
        BatchBar {
            bars,
            running: std::sync::Mutex::new(Vec::new()),
            done: 0.into(),
            total: 0.into(),
        }
    }

    /// Prints a line above the bars (or plainly).
    fn line(&self, text: &str) {
        match &self.bars {
            Some((multi, _)) => {
                let _ = multi.println(text);
            }
            None => eprintln!("{text}"),
        }
    }
}

impl BatchProgress for BatchBar {
    fn total(&self, trees: usize) {
        self.total.store(trees, std::sync::atomic::Ordering::SeqCst);
        if let Some((_, b)) = &self.bars {
            b.set_length(trees as u64);
        }
    }

    fn started(&self, tree: &str) {
        tracing::info!("started {tree}");
        if let Some((multi, _)) = &self.bars {
            let s = multi.add(indicatif::ProgressBar::new_spinner());
            s.enable_steady_tick(std::time::Duration::from_millis(120));
            s.set_message(tree.to_string());
            if let Ok(mut r) = self.running.lock() {
                r.push((tree.to_string(), s));
            }
        }
    }

    fn finished(&self, entry: &TreeEntry) {
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let total = self.total.load(std::sync::atomic::Ordering::SeqCst);
        if let Some((multi, b)) = &self.bars {
            b.set_position(done as u64);
            if let Ok(mut r) = self.running.lock()
                && let Some(i) = r.iter().position(|(t, _)| *t == entry.tree)
            {
                let (_, s) = r.remove(i);
                s.finish_and_clear();
                multi.remove(&s);
            }
        }
        match entry.status {
            Status::Failed => self.line(&format!(
                "error: {}: {}",
                entry.tree,
                entry.reason.as_deref().unwrap_or("failed")
            )),
            Status::Built if self.bars.is_none() => self.line(&format!(
                "[{done}/{total}] built {} ({:.1} s)",
                entry.tree, entry.wall_s
            )),
            Status::UpToDate if self.bars.is_none() => {
                self.line(&format!("[{done}/{total}] up to date {}", entry.tree))
            }
            _ => {}
        }
    }
}

impl Drop for BatchBar {
    fn drop(&mut self) {
        if let Some((_, b)) = &self.bars {
            b.finish_and_clear();
        }
    }
}

/// Prints a report as pretty JSON on stdout.
fn print_json(report: &impl serde::Serialize) -> Result<()> {
    println!(
        "{}",
        serde_json::to_string_pretty(report).context("serialising the report")?
    );
    Ok(())
}

fn main() -> ExitCode {
    // Like other Unix tools, end quietly when the reader of our output goes away
    // (`frond inspect --json big.glb | head`): Rust ignores SIGPIPE, so `println!` would panic.
    // SAFETY: setting a signal's disposition to the default before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        // Mesa's EGL probe logs a harmless DRI2 error before falling back to llvmpipe.
        .unwrap_or_else(|_| {
            tracing_subscriber::EnvFilter::new(format!("{level},wgpu_hal::gles::egl=off"))
        });
    // Colour codes only on a terminal: piped or redirected logs stay plain text.
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(ansi)
        .init();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
