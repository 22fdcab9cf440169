//! `frond lod`: an animated tree in, a chain of animated LODs out, written as one output set.
//! The chain is built by `frond-lod` and written by `frond-export`; this file only names the
//! files, assembles `<name>_report.json` and installs the set.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use frond_export::textures::sanitize;
use frond_export::{AnimationMode, ChainFileOptions, chain_files, msft_coverages};
use frond_lod::chain::{Chain, IMPOSTOR_MAX_ERROR, chain_levels, is_impostor_class};
use frond_lod::report::MeasuredError;
use frond_lod::report::report_name;
use frond_lod::{ChainRequest, LOD_REPORT_SCHEMA_VERSION, LodReport, ReportTimings, build_chain};
use frond_metrics::{
    CoverageImages, DEFAULT_ELEVATIONS_DEG, EvalContext, EvalRequest, samples_per_side,
};
use frond_render::Renderer;
use frond_scene::{ImportOptions, Tree};

use crate::output_set::OutputSet;

/// What `frond lod` was asked for: the chain, and how to write it.
#[derive(Clone, Debug)]
pub struct LodRequest {
    /// The chain to build: method, screen sizes, budgets, seed, sampling.
    pub chain: ChainRequest,
    /// How billboards are animated in the files.
    pub animation: AnimationMode,
    /// Measure each LOD's coverage error on its written file against this target (None: skip).
    pub measure: Option<f64>,
    /// Add MSFT_lod to the combined file, with coverages for an image `resolution` high.
    pub msft_lod: bool,
    /// The view the report's switch values assume: image height and vertical field of view.
    pub resolution: f32,
    /// Vertical field of view in degrees, for the switch values.
    pub fov: f32,
    /// Textures as files beside the GLBs rather than embedded.
    pub external_textures: bool,
    /// How the textures frond makes are stored.
    pub textures: frond_export::TextureFormat,
    /// Clip names carry Godot's `-loop` import hint.
    pub loop_hint: bool,
    /// The space VAT data is baked in.
    pub vat_space: frond_export::vat::VatSpace,
    /// Geometry compressed with `EXT_meshopt_compression` and `KHR_mesh_quantization`.
    pub compress: bool,
    /// How baked billboards are lit.
    pub billboard_normals: frond_export::BillboardNormals,
    /// Write `<name>_preview.html` and its pictures (`--no-preview` turns it off).
    pub preview: bool,
    /// The preview's viewer scripts are elsewhere, at this path relative to the output folder.
    pub preview_viewer: Option<String>,
}

/// Input-name stem used for the files.
pub fn lod_name(tree: &Tree) -> String {
    name_of(&tree.source)
}

/// The name a tree read from `input` gets in file names: its file stem, made file-name safe.
pub fn name_of(input: &Path) -> String {
    let stem = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "tree".into());
    sanitize(&stem)
}

/// Builds the chain in memory, then writes the LOD files, the combined file, the sidecars and
/// `<name>_report.json` into `out_dir` as one [`OutputSet`]: the folder is checked (and a staging
/// folder made in it) before the build, and the set is installed whole at the end, replacing the
/// previous set of the same tree. Nothing is written unless everything was built.
pub fn run_lod(
    renderer: &Renderer,
    tree: &Tree,
    req: &LodRequest,
    out_dir: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<LodReport> {
    let path = tree.source.display().to_string();
    let t_start = Instant::now();
    let name = lod_name(tree);
    let levels =
        chain_levels(tree, &req.chain).with_context(|| format!("{path}: sizing the LODs"))?;
    let mut set = OutputSet::prepare(out_dir, &name, &report_name(&name), &[&tree.source])?;
    let mut expected: Vec<String> = (0..=levels.len())
        .map(|k| format!("{name}_LOD{k}.glb"))
        .collect();
    expected.push(format!("{name}_lods.glb"));
    set.check_names(&expected)?;
    // The input's renders the measure compares the LODs with need nothing the build makes:
    // they are drawn while the LODs are built, on the cores the build leaves idle.
    let mut measure = req
        .measure
        .map(|_| measure_context(renderer, tree, req, req.chain.clip.clone()))
        .transpose()?;
    let sizes: Vec<f32> = levels.iter().map(|l| l.screen_height).collect();
    let (chain, (prepared, t_prepare)) = rayon::join(
        || build_chain(renderer, tree, &req.chain, &levels, progress),
        || {
            let t = Instant::now();
            let prepared = measure
                .as_mut()
                .map_or(Ok(()), |ctx| ctx.prepare_coverage(&sizes));
            (prepared, t.elapsed().as_secs_f64())
        },
    );
    let t_joined = Instant::now();
    let chain = chain.map_err(|(lod, e)| {
        let e = anyhow::Error::new(e);
        match lod {
            Some(k) => e.context(format!("{path}: building LOD{k}")),
            None => e,
        }
    })?;
    prepared.with_context(|| format!("{path}: rendering the input to measure the LODs"))?;
    progress("writing files");
    // LOD0's preview pictures need nothing the files give: drawn while the files are written
    // and read back, on the core that leaves idle.
    let lod0_request = frond_preview::Lod0Request {
        input: tree,
        name: &name,
        clip: chain.sampled.clip.as_deref(),
        period: chain.sampled.period,
        screen_heights: std::iter::once(None)
            .chain(levels.iter().map(|l| Some(l.screen_height)))
            .collect(),
        fov_deg: req.fov,
        resolution: req.resolution,
        flip_frames: PREVIEW_FLIP_FRAMES,
    };
    let (files, lod0_pictures) = rayon::join(
        || {
            let times = (t_start, t_joined, measure.is_some().then_some(t_prepare));
            write_and_read_back(tree, req, &chain, &name, &mut set, times)
        },
        || {
            req.preview.then(|| {
                frond_preview::lod0_pictures(renderer, &lod0_request)
                    .with_context(|| format!("{path}: rendering the preview page"))
            })
        },
    );
    let (written_files, mut report, read_back) = files?;
    let lod0_pictures = lod0_pictures.transpose()?;
    // LOD0 is the input itself (its file passes the input through): not read again.
    let lods: Vec<&Tree> = std::iter::once(tree).chain(&read_back).collect();
    // The preview's pictures do not depend on the measured errors (its page's text does):
    // they are rendered while the LODs are measured, from the report as it stands.
    let snapshot = req.preview.then(|| report.clone());
    let combined = written_files
        .iter()
        .find(|(rel, _)| *rel == report.combined)
        .map(|(_, bytes)| bytes.as_slice())
        .with_context(|| format!("{}: not among the files written", report.combined))?;
    let preview_request = |report| frond_preview::LodPreviewRequest {
        report,
        lods: &lods,
        combined,
        resolution: req.resolution,
        flip_frames: PREVIEW_FLIP_FRAMES,
        viewer: req.preview_viewer.as_deref(),
    };
    match (req.measure, req.preview) {
        (Some(_), true) => progress("measuring each LOD's error and rendering the preview page"),
        (Some(_), false) => progress("measuring each LOD's error"),
        (None, true) => progress("rendering the preview page"),
        (None, false) => {}
    }
    let pictures = measure_and_draw(
        renderer,
        tree,
        req,
        &mut measure,
        &lods,
        &mut report,
        snapshot.as_ref().zip(lod0_pictures),
        &preview_request,
    )?;
    if let Some(pictures) = pictures {
        let preview = frond_preview::lod_page(&preview_request(&report), pictures?)
            .with_context(|| format!("{}: writing the preview page", tree.source.display()))?;
        for (rel, bytes) in &preview.files {
            set.stage(rel, bytes)?;
            report.files.insert(report.files.len() - 1, rel.clone());
        }
        report.timings_s.preview = Some(preview.seconds);
    }
    // Everything up to the report, measuring and the preview included.
    report.timings_s.wall = t_start.elapsed().as_secs_f64();
    let json = serde_json::to_vec_pretty(&report).context("serialising the report")?;
    set.commit(&json)?;
    Ok(report)
}

/// The chain's files as written (relative path, bytes), the report as far as they give it and
/// the LODs read back ([`write_and_read_back`]).
type WrittenChain = (Vec<(String, Vec<u8>)>, LodReport, Vec<Tree>);

/// Writes the chain's files into `set` and reads them back: the files, the report as far as
/// they give it (their costs, the switch values) and the LODs read back (when the measure or
/// the preview needs them). `times`: the run's start, the build's end and the seconds of the
/// input's renders for the measure (when measured).
fn write_and_read_back(
    tree: &Tree,
    req: &LodRequest,
    chain: &Chain,
    name: &str,
    set: &mut OutputSet,
    (t_start, t_joined, t_prepare): (Instant, Instant, Option<f64>),
) -> Result<WrittenChain> {
    let path = tree.source.display().to_string();
    let written = chain_files(tree, chain, &file_options(tree, req, name))
        .map_err(|(what, e)| anyhow::Error::new(e).context(format!("{path}: {what}")))?;
    let t_written = Instant::now();
    let total = (t_written - t_start).as_secs_f64();
    let mut report = LodReport {
        schema_version: LOD_REPORT_SCHEMA_VERSION,
        input: path,
        name: name.to_string(),
        clip: chain.sampled.clip.clone(),
        period: chain.sampled.period,
        samples: chain.sampled.samples(),
        seed: req.chain.seed,
        pixel_error: req.chain.pixel_error,
        animation: req.animation.report_name(),
        tree_height: tree.height(),
        switching: None,
        lods: written.entries,
        texture_memory: None,
        combined: written.combined,
        files: written.files.iter().map(|(p, _)| p.clone()).collect(),
        warnings: tree.warnings.clone(),
        timings_s: ReportTimings {
            sample: chain.t_sample,
            build: chain.t_build,
            // From the build's end and the input's renders' (the later), to the files.
            export: (t_written - t_joined).as_secs_f64(),
            total,
            ..Default::default()
        },
    };
    // Seconds drawing the input's renders for the measure, alongside the build.
    report.timings_s.measure_input = t_prepare;
    report.files.push(report_name(name));
    fill_switching(tree, req, &mut report);
    for (rel, bytes) in &written.files {
        set.stage(rel, bytes)?;
    }
    read_back_costs(set, &mut report)?;
    let read_back = if req.measure.is_some() || req.preview {
        read_back_lods(set, &report)?
    } else {
        Vec::new()
    };
    Ok((written.files, report, read_back))
}

/// How the chain's files are written, as the request asks.
fn file_options(tree: &Tree, req: &LodRequest, name: &str) -> ChainFileOptions {
    ChainFileOptions {
        name: name.to_string(),
        animation: req.animation,
        external_textures: req.external_textures,
        textures: req.textures,
        loop_hint: req.loop_hint,
        vat_space: req.vat_space,
        compress: req.compress,
        billboard_normals: req.billboard_normals,
        msft_lod: req
            .msft_lod
            .then(|| msft_coverages(&req.chain.screen_heights, req.resolution)),
        extras: serde_json::json!({
            "generator": concat!("frond ", env!("CARGO_PKG_VERSION")),
            "seed": req.chain.seed,
            "source": tree.source.file_name().map(|f| f.to_string_lossy().into_owned()),
        }),
    }
}

/// Measures each LOD's error into `report` (when asked) while the preview's pictures are drawn
/// from `snapshot`, the report as it stood (they do not depend on the errors): both at once,
/// on the cores each leaves idle. Returns the pictures, when the preview was asked for.
#[expect(
    clippy::too_many_arguments,
    reason = "the run's renderer, tree and request, the measure's context, the LODs read back, \
              the report it fills and the preview's inputs"
)]
fn measure_and_draw<'a, 'r>(
    renderer: &'r Renderer,
    tree: &'r Tree,
    req: &LodRequest,
    measure: &mut Option<EvalContext<'r>>,
    lods: &[&Tree],
    report: &mut LodReport,
    snapshot: Option<(&'a LodReport, frond_preview::Lod0Pictures)>,
    preview_request: &(dyn Fn(&'a LodReport) -> frond_preview::LodPreviewRequest<'a> + Sync),
) -> Result<Option<Result<frond_preview::lod_page::LodPreviewPictures>>> {
    let input_path = tree.source.display().to_string();
    let (measured, pictures) = rayon::join(
        || -> Result<()> {
            if let Some(max_error) = req.measure {
                let t = Instant::now();
                // Sampled with the request's clip: the chain's, unless it resolved otherwise.
                let ctx = match measure.as_mut() {
                    Some(ctx) if ctx.clip() == report.clip.as_deref() => ctx,
                    _ => measure.insert(measure_context(renderer, tree, req, report.clip.clone())?),
                };
                measure_errors(ctx, lods, report, max_error)?;
                report.timings_s.measure = Some(t.elapsed().as_secs_f64());
            }
            Ok(())
        },
        || {
            snapshot.map(|(snapshot, lod0)| {
                frond_preview::lod_pictures_after(renderer, &preview_request(snapshot), lod0)
                    .with_context(|| format!("{input_path}: rendering the preview page"))
            })
        },
    );
    measured?;
    Ok(pictures)
}

/// Each LOD's switch values for the request's view ([`frond_lod::switching`]).
fn fill_switching(tree: &Tree, req: &LodRequest, report: &mut LodReport) {
    let b = &tree.bounds;
    let view = frond_lod::switching::SwitchView {
        fov_deg: req.fov,
        resolution: req.resolution,
        tree_height: tree.height(),
        bounds_size: b.size(),
        sphere_radius: 0.5 * b.diagonal(),
    };
    let values = frond_lod::switching::switch_values(&req.chain.screen_heights, &view);
    for (entry, v) in report.lods.iter_mut().zip(values) {
        entry.switch = Some(v);
    }
    report.switching = Some(view);
}

/// Views and frames of the measured error: `frond eval`'s defaults, so the report's number is
/// the one `frond eval INPUT LOD --screen-height H` prints.
const MEASURE_VIEWS: u32 = frond_metrics::DEFAULT_VIEWS;
const MEASURE_FRAMES: u32 = frond_metrics::DEFAULT_FRAMES;

/// Every LOD after LOD0 read back from its staged file as `frond eval` reads a candidate, in
/// the report's order.
fn read_back_lods(set: &OutputSet, report: &LodReport) -> Result<Vec<Tree>> {
    let unlimited = unlimited();
    let mut lods = Vec::with_capacity(report.lods.len());
    for entry in report.lods.iter().skip(1) {
        let staged = set
            .staged_path(&entry.file)
            .with_context(|| format!("{}: not among the files written", entry.file))?;
        let lod = frond_scene::import(
            &staged,
            &ImportOptions {
                allow_empty: true,
                limits: unlimited,
                ..Default::default()
            },
        )
        .with_context(|| format!("{}: reading back what was written", entry.file))?;
        lods.push(lod);
    }
    Ok(lods)
}

/// Frames of each LOD's wind flip-book on the preview page.
const PREVIEW_FLIP_FRAMES: u32 = 6;

/// Fills each billboard or card LOD's `error` with its coverage error at its own screen
/// height, on its written file read back (`lods`, the report's order), and its switch pop
/// against the LOD before it at that size; warns (in the log and the report) about every LOD
/// over its target (`max_error`, or at the far end [`IMPOSTOR_MAX_ERROR`]).
fn measure_errors(
    ctx: &mut EvalContext,
    lods: &[&Tree],
    report: &mut LodReport,
    max_error: f64,
) -> Result<()> {
    for k in 1..report.lods.len().min(lods.len()) {
        let entry = &report.lods[k];
        let Some(h) = entry.screen_height else {
            continue;
        };
        let file = entry.file.clone();
        let lod = lods[k];
        // The depth complexities come from the metric's first renders of both.
        let measured = ctx
            .measure(lod, h)
            .with_context(|| format!("{file}: measuring its error"))?;
        let coverage = &measured.report;
        let framing = ctx
            .framing(h)
            .with_context(|| format!("{file}: framing its measure"))?;
        let switch_pop = switch_pop(ctx, lods, k, measured.images.as_ref(), h)
            .with_context(|| format!("{file}: measuring its switch pop"))?;
        // The far end has a target of its own; the others are held to `--max-error`.
        let (target, which) = if is_impostor_class(h) {
            (IMPOSTOR_MAX_ERROR, "the far end's")
        } else {
            (max_error, "--max-error")
        };
        let within_target = coverage.mean <= target;
        if !within_target {
            let w = format!(
                "{file}: coverage error {:.3} at {h} px is over the target {} ({which}): \
                 written at its budget",
                coverage.mean, target as f32
            );
            tracing::warn!("{w}");
            report.warnings.push(w);
        }
        let binary = coverage.binary.mean;
        report.lods[k].error = Some(MeasuredError {
            coverage: coverage.mean,
            coverage_ratio: coverage.ratio,
            coverage_binary: (!binary.is_nan()).then_some(binary),
            switch_pop,
            loop_change_input: coverage.loop_change_original,
            loop_change_ratio: coverage.loop_change_ratio(),
            max_error: target,
            within_target,
            image: [framing.width, framing.height],
            samples_per_side: samples_per_side(h),
            views: MEASURE_VIEWS,
            elevations_deg: DEFAULT_ELEVATIONS_DEG.to_vec(),
            frames: MEASURE_FRAMES,
            depth_complexity: measured.depth_complexity,
            input_depth_complexity: measured.original_depth_complexity,
        });
    }
    Ok(())
}

/// The coverage error of LOD `k` (its `images` at `screen_height`, its size, when kept)
/// against LOD `k − 1` drawn alike: what changes on screen when the engine swaps them. LOD1's
/// is against the input, whose images the measure has already.
fn switch_pop(
    ctx: &mut EvalContext,
    lods: &[&Tree],
    k: usize,
    images: Option<&CoverageImages>,
    screen_height: f32,
) -> Result<f64> {
    let previous = (k > 1).then(|| lods[k - 1]);
    let Some(images) = images else {
        return Ok(ctx.compare_trees(previous, lods[k], screen_height)?.mean);
    };
    let previous: Option<CoverageImages> = match previous {
        None => None,
        Some(tree) => Some(ctx.images(tree, screen_height)?),
    };
    let pop = ctx.compare(previous.as_ref(), images, screen_height, &lods[k].source)?;
    Ok(pop.mean)
}

/// The context `frond lod` measures its LODs in: the input's loop sampled for `clip`, with the
/// views and frames of [`MEASURE_VIEWS`] and [`MEASURE_FRAMES`], on the request's screen.
fn measure_context<'a>(
    renderer: &'a Renderer,
    tree: &'a Tree,
    req: &LodRequest,
    clip: Option<String>,
) -> Result<EvalContext<'a>> {
    let eval = EvalRequest {
        views: MEASURE_VIEWS,
        frames: MEASURE_FRAMES,
        // Unused here: each LOD is measured at its own size (`EvalContext::measure`).
        screen_height: 0.0,
        fov_deg: req.fov,
        resolution: req.resolution,
        // Only the loop's start and period are used: the frames' times.
        samples: 2,
        clip,
        limits: unlimited(),
        white_albedo: false,
        lighting: Default::default(),
    };
    EvalContext::new(renderer, tree, &eval).with_context(|| {
        format!(
            "{}: sampling the input to measure the LODs",
            tree.source.display()
        )
    })
}

/// Limits for reading frond's own files: none is a safety matter (the input passed its own).
fn unlimited() -> frond_scene::InputLimits {
    frond_scene::InputLimits {
        max_input_bytes: u64::MAX,
        max_texture_bytes: u64::MAX,
        max_vertices: u64::MAX,
        max_animation_keys: u64::MAX,
    }
}

/// Fills each LOD's cost from its written file (staged, with its external textures), as an
/// engine would count it (`frond_scene::file_cost`), and its alpha-tested area relative to
/// LOD0's (the input's leaf cards): the overdraw its foliage asks for.
fn read_back_costs(set: &OutputSet, report: &mut LodReport) -> Result<()> {
    let limits = unlimited();
    for entry in &mut report.lods {
        let path = set
            .staged_path(&entry.file)
            .with_context(|| format!("{}: not among the files written", entry.file))?;
        let cost = frond_scene::file_cost(&path, &limits)
            .with_context(|| format!("{}: reading back what was written", entry.file))?;
        entry.cost = Some(cost);
    }
    let leaf_area = report
        .lods
        .first()
        .and_then(|l| l.cost.as_ref())
        .map_or(0.0, |c| c.alpha_tested_area);
    for entry in &mut report.lods {
        entry.alpha_tested_area_ratio = entry
            .cost
            .as_ref()
            .filter(|_| leaf_area > 0.0)
            .map(|c| c.alpha_tested_area / leaf_area);
    }
    report.texture_memory = Some(frond_lod::TextureMemory::of(
        report.lods.iter().filter_map(|l| l.cost.as_ref()),
    ));
    for w in report
        .cost_increases()
        .into_iter()
        .chain(report.budget_excesses())
    {
        tracing::warn!("{w}");
        report.warnings.push(w);
    }
    Ok(())
}
