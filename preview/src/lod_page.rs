//! The preview page of one `frond lod` run (`<name>_preview.html`): the live view of the
//! combined file, the cost table read from the written files, and per LOD its still at its own
//! screen height beside LOD0's from the same camera, their difference, the wind loop as a
//! flip-book and its atlas, with the method, why it was chosen, and the error measured at its
//! own size.

use std::time::Instant;

use frond_lod::report::MeasuredError;
use frond_lod::switching::SwitchValues;
use frond_lod::{LodEntry, LodReport};
use frond_metrics::{DEFAULT_FOV_DEG, candidate_clip, samples_per_side};
use frond_render::{Frame, PosedTree, Renderer, TreeParts};
use frond_scene::{FileCost, Tree};

use crate::error::PreviewError;
use crate::html::{esc, figure, href, page};
use crate::stills::{
    Drawer, EXTRA, FLIP_SAMPLES, FilteredStill, MISSING, PixelDifference, apng, atlas_png, crop,
    difference, png, preview_view, samples_within, supersampling,
};
use crate::units;
use crate::viewer::{
    LIVE_VIEW_JS, VIEWER_DIR, ViewConfig, ViewLod, combined_roots, config_json, uses_extension,
    viewer_files,
};

/// What a preview of a `frond lod` run is made from.
pub struct LodPreviewRequest<'a> {
    /// The run's report, its costs and measured errors filled.
    pub report: &'a LodReport,
    /// Every LOD in the report's order: LOD0, the input (its rest bounds frame the camera), then
    /// the written LODs read back.
    pub lods: &'a [&'a Tree],
    /// The combined file's bytes (its scene roots are grouped per LOD for the live view).
    pub combined: &'a [u8],
    /// The report's switch values' image height (`--resolution`).
    pub resolution: f32,
    /// Frames of the wind flip-books.
    pub flip_frames: u32,
    /// Where the vendored viewer scripts are, relative to the output folder, when somebody
    /// else writes them (`frond batch` keeps one copy for all its trees); None: the page's own
    /// `viewer/` is written with it.
    pub viewer: Option<&'a str>,
}

/// The page and its pictures, as (path relative to the output folder, bytes).
pub struct PreviewFiles {
    /// The page, its stills and flip-books, and the viewer scripts unless written elsewhere.
    pub files: Vec<(String, Vec<u8>)>,
    /// Seconds spent rendering and encoding.
    pub seconds: f64,
}

/// The page's name for tree `name`.
pub fn preview_name(name: &str) -> String {
    format!("{name}_preview.html")
}

/// The flip-books' height: small (the loop is many frames) but never above the LOD's own size.
const FLIP_HEIGHT: f32 = 160.0;
/// LOD0's still when no LOD gives a size.
const LOD0_HEIGHT: f32 = 400.0;
/// Triangles drawn over one flip-book's frames: a frame costs about its triangles on a CPU
/// renderer (posing and setup, not pixels, at the flip-book's size), so a heavy LOD gets fewer
/// frames and the preview stays a small part of the run.
const FLIP_TRIANGLE_FRAMES: usize = 250_000;
/// The fewest frames a flip-book gets, however heavy the LOD: enough to read the sway (a
/// loop's four quarters).
const MIN_FLIP_FRAMES: u32 = 4;
/// Largest side of an atlas thumbnail.
const ATLAS_SIDE: u32 = 512;

/// The pictures of one LOD.
struct LodPictures {
    files: Vec<(String, Vec<u8>)>,
    /// The stills' size (cropped to the tree).
    still: [u32; 2],
    /// The tree's height in the stills, pixels: the LOD's screen height (LOD0's: the first
    /// LOD's).
    tree_height: f32,
    /// Samples per pixel side of the stills and their difference.
    samples_per_side: u32,
    flip: [u32; 2],
    /// Frames of its flip-book.
    flip_frames: u32,
    atlas: Option<[u32; 2]>,
    difference: PixelDifference,
}

/// Every LOD's pictures for the page of a `frond lod` run ([`lod_pictures`]), not yet placed
/// on it.
pub struct LodPreviewPictures {
    pictures: Vec<LodPictures>,
    seconds: f64,
}

/// What LOD0's pictures for the page of a `frond lod` run are drawn from: all known once the
/// chain is built, before its files are written ([`lod0_pictures`]).
pub struct Lod0Request<'a> {
    /// LOD0, the input (its rest bounds frame every picture's camera).
    pub input: &'a Tree,
    /// The run's tree name (the report's `name`): the pictures' folder is `<name>_preview`.
    pub name: &'a str,
    /// The run's clip (the report's `clip`).
    pub clip: Option<&'a str>,
    /// The loop's period in seconds (the report's `period`).
    pub period: f32,
    /// Each LOD's screen height in the report's order, LOD0's first (None where a LOD has
    /// none).
    pub screen_heights: Vec<Option<f32>>,
    /// The switch values' field of view, degrees.
    pub fov_deg: f32,
    /// The switch values' image height (`--resolution`).
    pub resolution: f32,
    /// Frames of the wind flip-books.
    pub flip_frames: u32,
}

impl<'a> Lod0Request<'a> {
    /// The request of `req`'s LOD0 pictures, from its report.
    fn of(req: &LodPreviewRequest<'a>) -> Result<Lod0Request<'a>, PreviewError> {
        let report = req.report;
        let Some(&input) = req.lods.first() else {
            return Err(PreviewError::LodCount {
                report: report.lods.len(),
                given: 0,
            });
        };
        let (fov_deg, resolution) = report
            .switching
            .map_or((DEFAULT_FOV_DEG, req.resolution), |v| {
                (v.fov_deg, v.resolution)
            });
        Ok(Lod0Request {
            input,
            name: &report.name,
            clip: report.clip.as_deref(),
            period: report.period,
            screen_heights: report.lods.iter().map(|e| e.screen_height).collect(),
            fov_deg,
            resolution,
            flip_frames: req.flip_frames,
        })
    }

    /// The height LOD `k`'s pictures are drawn at: its screen height; LOD0's, the first LOD's.
    fn height(&self, k: usize) -> f32 {
        let lod0 = (self.screen_heights.iter().find_map(|h| *h)).unwrap_or(LOD0_HEIGHT);
        self.screen_heights[k].unwrap_or(lod0)
    }

    /// Everything the pictures depend on besides the input: two requests with the same key
    /// draw the same pictures.
    fn key(&self) -> Lod0Key {
        (
            self.name.to_string(),
            self.clip.map(str::to_string),
            self.period,
            self.screen_heights.clone(),
            [self.fov_deg, self.resolution],
            self.flip_frames,
        )
    }

    /// The pictures' view of the run.
    fn view(&self) -> PageView<'a> {
        PageView {
            input: self.input,
            dir: format!("{}_preview", self.name),
            clip: self.clip.map(str::to_string),
            period: self.period,
            fov_deg: self.fov_deg,
            resolution: self.resolution,
            flip_frames: self.flip_frames,
        }
    }
}

/// [`Lod0Request::key`]: name, clip, period, screen heights, field of view and resolution,
/// flip-book frames.
type Lod0Key = (String, Option<String>, f32, Vec<Option<f32>>, [f32; 2], u32);

/// LOD0's pictures for the page of a `frond lod` run ([`lod0_pictures`]): its own still and
/// flip-book, and its still at every LOD's size, the reference each LOD is compared with.
pub struct Lod0Pictures {
    pictures: LodPictures,
    /// LOD0's still at LOD `k`'s size, for each `k` (the first: its own).
    references: Vec<FilteredStill>,
    /// What they were drawn for ([`Lod0Request::key`]).
    key: Lod0Key,
    seconds: f64,
}

/// Renders LOD0's pictures for the page of a `frond lod` run: they need nothing the chain's
/// files give, so `frond lod` draws them while it writes and reads back the files, on the
/// cores that leaves idle ([`lod_pictures_after`] draws the rest). Deterministic.
pub fn lod0_pictures(renderer: &Renderer, req: &Lod0Request) -> Result<Lod0Pictures, PreviewError> {
    let t0 = Instant::now();
    let view = req.view();
    let lod0 = req.input;
    // LOD0 at the start of its clip: the reference every LOD's still is compared with.
    let (clip0, start0) = clip_start(lod0, view.clip.as_deref());
    let mut posed = PosedTree::new(lod0, clip0, start0, TreeParts::All);
    let drawer = Drawer::new(lod0, posed.scene())?;
    let (pictures, still) = lod_pictures_of(
        renderer,
        &view,
        LodToDraw {
            tree: lod0,
            k: 0,
            h: req.height(0),
            atlas: None,
        },
        &mut posed,
        &drawer,
        None,
    )?;
    // LOD0's still at each LOD's size: the one just drawn where the size is its own (the same
    // pose, camera and size: the same picture).
    let mut references = vec![still];
    for k in 1..req.screen_heights.len() {
        let (camera, size) = preview_view(lod0, req.height(k), view.fov_deg, view.resolution)?;
        let samples = supersampling(req.height(k), size, renderer.max_dimension());
        let same = |f: &&FilteredStill| {
            (f.width, f.height, f.samples_per_side) == (size.0, size.1, samples)
        };
        let still = match references.iter().find(same) {
            Some(still) => still.clone(),
            None => {
                posed.pose(clip0, start0);
                drawer.still(posed.scene(), &camera, size, samples, "still")?
            }
        };
        references.push(still);
    }
    Ok(Lod0Pictures {
        pictures,
        references,
        key: req.key(),
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Renders the pictures of the page of a `frond lod` run: what they show does not depend on
/// the measured errors (only the page's text does), so `frond lod` renders them while it
/// measures, from a report whose errors are not filled yet, and [`lod_page`] writes the page
/// with the final report. Deterministic: the same files give the same bytes.
pub fn lod_pictures(
    renderer: &Renderer,
    req: &LodPreviewRequest,
) -> Result<LodPreviewPictures, PreviewError> {
    let lod0 = lod0_pictures(renderer, &Lod0Request::of(req)?)?;
    lod_pictures_after(renderer, req, lod0)
}

/// [`lod_pictures`] with LOD0's drawn already ([`lod0_pictures`], for the same run): the
/// other LODs' pictures, one LOD at a time (the renderer spreads each frame over the threads).
/// LOD0's are drawn again if they were drawn for another run than `req`'s report gives
/// (other sizes, clip, loop, view or flip-book frames).
pub fn lod_pictures_after(
    renderer: &Renderer,
    req: &LodPreviewRequest,
    lod0: Lod0Pictures,
) -> Result<LodPreviewPictures, PreviewError> {
    let t0 = Instant::now();
    let report = req.report;
    if req.lods.len() != report.lods.len() {
        return Err(PreviewError::LodCount {
            report: report.lods.len(),
            given: req.lods.len(),
        });
    }
    let lod0_req = Lod0Request::of(req)?;
    let lod0 = if lod0.key == lod0_req.key() {
        lod0
    } else {
        lod0_pictures(renderer, &lod0_req)?
    };
    let view = lod0_req.view();
    let Lod0Pictures {
        pictures: mut first,
        references,
        seconds,
        ..
    } = lod0;
    // LOD0 is the input, with no atlas of its own; drawn if a report ever gives it one.
    if let Some(a) = report.lods[0].atlas
        && let Some(picture) = atlas_png(req.lods[0], a, ATLAS_SIDE)?
    {
        first
            .files
            .push((format!("{}/lod0_atlas.png", view.dir), picture.png));
        first.atlas = Some(picture.size);
    }
    let mut pictures: Vec<LodPictures> = Vec::with_capacity(req.lods.len());
    pictures.push(first);
    for (k, (&tree, reference)) in req.lods.iter().zip(&references).enumerate().skip(1) {
        let (clip, start) = clip_start(tree, view.clip.as_deref());
        let mut posed = PosedTree::new(tree, clip, start, TreeParts::All);
        let drawer = Drawer::new(tree, posed.scene())?;
        let lod = LodToDraw {
            tree,
            k,
            h: lod0_req.height(k),
            atlas: report.lods[k].atlas,
        };
        let (p, _) = lod_pictures_of(renderer, &view, lod, &mut posed, &drawer, Some(reference))?;
        pictures.push(p);
    }
    Ok(LodPreviewPictures {
        pictures,
        seconds: seconds + t0.elapsed().as_secs_f64(),
    })
}

/// The page of a `frond lod` run with its `pictures` ([`lod_pictures`], for the same LODs):
/// the page's files, the pictures among them; `seconds` counts the pictures' rendering too.
pub fn lod_page(
    req: &LodPreviewRequest,
    pictures: LodPreviewPictures,
) -> Result<PreviewFiles, PreviewError> {
    let t0 = Instant::now();
    let report = req.report;
    let LodPreviewPictures { pictures, seconds } = pictures;
    if pictures.len() != report.lods.len() {
        return Err(PreviewError::LodCount {
            report: report.lods.len(),
            given: pictures.len(),
        });
    }
    let combined_error = |reason| PreviewError::Combined {
        file: report.combined.clone(),
        reason,
    };
    let groups = combined_roots(req.combined, report.lods.len()).map_err(combined_error)?;
    let ktx2 = uses_extension(req.combined, "KHR_texture_basisu").map_err(combined_error)?;
    let config = ViewConfig {
        combined: report.combined.clone(),
        clip: report.clip.clone(),
        viewer: req
            .viewer
            .unwrap_or(VIEWER_DIR)
            .trim_end_matches('/')
            .to_string(),
        ktx2,
        lods: report
            .lods
            .iter()
            .zip(groups)
            .map(|(e, nodes)| ViewLod {
                file: e.file.clone(),
                nodes,
                screen_height: e.screen_height,
                shown_down_to_px: e
                    .switch
                    .as_ref()
                    .map_or(0.0, |s| s.min_screen_fraction * req.resolution),
                triangles: e.cost.as_ref().map_or(e.triangles as u64, |c| c.triangles),
                vertex_animated: e.vat.is_some() || e.spectral_files.is_some(),
            })
            .collect(),
    };
    let body = body(report, &pictures, &config);
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    for p in pictures {
        files.extend(p.files);
    }
    if req.viewer.is_none() {
        for (path, bytes) in viewer_files(ktx2) {
            files.push((path, bytes.to_vec()));
        }
    }
    let title = format!("{} — frond LOD chain", report.name);
    files.push((preview_name(&report.name), page(&title, &body).into_bytes()));
    Ok(PreviewFiles {
        files,
        seconds: seconds + t0.elapsed().as_secs_f64(),
    })
}

/// How a run's pictures are seen: the camera's framing of LOD0 and the loop they play.
struct PageView<'a> {
    input: &'a Tree,
    /// The pictures' folder.
    dir: String,
    clip: Option<String>,
    period: f32,
    fov_deg: f32,
    resolution: f32,
    flip_frames: u32,
}

/// One LOD to draw: LOD `k`, `tree`, at `h` pixels, with its atlas's size.
struct LodToDraw<'a> {
    tree: &'a Tree,
    k: usize,
    h: f32,
    atlas: Option<[u32; 2]>,
}

/// LOD `k`'s still at `h` pixels (and LOD0's at the same size, `reference`, with the
/// difference, for k > 0), its flip-book and its atlas, drawn with `drawer` from `posed` (the
/// LOD at the start of its clip).
fn lod_pictures_of(
    renderer: &Renderer,
    view: &PageView,
    lod: LodToDraw,
    posed: &mut PosedTree,
    drawer: &Drawer,
    reference: Option<&FilteredStill>,
) -> Result<(LodPictures, FilteredStill), PreviewError> {
    let LodToDraw { tree, k, h, atlas } = lod;
    let dir = &view.dir;
    let (clip, start) = clip_start(tree, view.clip.as_deref());
    let (camera, size) = preview_view(view.input, h, view.fov_deg, view.resolution)?;
    let camera = &camera;
    // Each pixel K×K samples as the coverage metric takes them: the stills are what a player
    // sees, their difference is judged as the metric judges.
    let samples = supersampling(h, size, renderer.max_dimension());
    let still = drawer.still(posed.scene(), camera, size, samples, "still")?;
    let mut files = Vec::new();
    let mut diff = PixelDifference::default();
    let rect;
    if let Some(reference) = reference {
        rect = still.covered_box(Some(reference), 2);
        let (rgba, d) = difference(reference, &still);
        diff = d;
        files.push((
            format!("{dir}/lod{k}_lod0.png"),
            png(
                rect[2],
                rect[3],
                &crop(&reference.rgba, size.0, rect),
                "a still",
            )?,
        ));
        files.push((
            format!("{dir}/lod{k}_diff.png"),
            png(
                rect[2],
                rect[3],
                &crop(&rgba, size.0, rect),
                "a difference image",
            )?,
        ));
    } else {
        rect = still.covered_box(None, 2);
    }
    files.push((
        format!("{dir}/lod{k}.png"),
        png(
            rect[2],
            rect[3],
            &crop(&still.rgba, size.0, rect),
            "a still",
        )?,
    ));
    let (flip_camera, flip_size) = preview_view(
        view.input,
        h.min(FLIP_HEIGHT),
        view.fov_deg,
        view.resolution,
    )?;
    let n = flip_frames(view.flip_frames, tree.triangles.len());
    let flip_k = samples_within(
        flip_size,
        samples_per_side(h.min(FLIP_HEIGHT)),
        FLIP_SAMPLES,
    );
    let frames: Vec<Frame> = (0..n)
        .map(|i| {
            let t = start + view.period * i as f32 / n as f32;
            let scene = posed.pose(clip, t);
            drawer.frame(scene, &flip_camera, flip_size, flip_k, "flip-book frame")
        })
        .collect::<Result<_, _>>()?;
    let delay = (1000.0 * view.period / n as f32)
        .round()
        .clamp(10.0, 2000.0) as u16;
    let flip = apng(&frames, delay, "a flip-book")?;
    files.push((format!("{dir}/lod{k}_wind.png"), flip.png));
    let mut atlas_size = None;
    if let Some(a) = atlas
        && let Some(picture) = atlas_png(tree, a, ATLAS_SIDE)?
    {
        files.push((format!("{dir}/lod{k}_atlas.png"), picture.png));
        atlas_size = Some(picture.size);
    }
    let pictures = LodPictures {
        files,
        still: [rect[2], rect[3]],
        tree_height: h,
        samples_per_side: samples,
        flip: flip.size,
        flip_frames: n,
        atlas: atlas_size,
        difference: diff,
    };
    Ok((pictures, still))
}

/// Frames of a flip-book of a LOD of `triangles`: `asked`, fewer where they would draw more
/// than [`FLIP_TRIANGLE_FRAMES`] triangles, never under [`MIN_FLIP_FRAMES`] (or `asked`).
fn flip_frames(asked: u32, triangles: usize) -> u32 {
    let affordable = (FLIP_TRIANGLE_FRAMES / triangles.max(1)).min(u32::MAX as usize) as u32;
    asked.min(affordable.max(MIN_FLIP_FRAMES)).max(1)
}

/// The LOD's clip of the run's clip `name` (as `frond eval` picks it) and the time it starts.
fn clip_start(tree: &Tree, name: Option<&str>) -> (Option<usize>, f32) {
    let clip = candidate_clip(tree, name);
    (clip, clip.map_or(0.0, |c| tree.rig.clips[c].start))
}

/// The page's body.
fn body(report: &LodReport, pictures: &[LodPictures], config: &ViewConfig) -> String {
    let mut b = String::new();
    // No timings: the page is the same bytes for the same input and seed (they are in the
    // report).
    b.push_str(&format!(
        "<header><h1>{}</h1><p class=\"meta\">{} LODs of <code>{}</code> · clip {} ({} loop, {} samples) · \
         seed {} · frond {}</p>\n",
        esc(&report.name),
        report.lods.len() - 1,
        esc(&report.input),
        esc(report.clip.as_deref().unwrap_or("(none)")),
        units::duration(f64::from(report.period)),
        report.samples,
        report.seed,
        env!("CARGO_PKG_VERSION"),
    ));
    b.push_str("<nav><a href=\"#live\">Live view</a><a href=\"#costs\">Costs</a>");
    for (k, _) in report.lods.iter().enumerate() {
        b.push_str(&format!("<a href=\"#lod{k}\">LOD{k}</a>"));
    }
    b.push_str("</nav></header>\n");
    b.push_str(&live_view(config));
    b.push_str(&cost_table(report, pictures));
    for (k, (e, p)) in report.lods.iter().zip(pictures).enumerate() {
        b.push_str(&lod_section(report, k, e, p));
    }
    if !report.warnings.is_empty() {
        b.push_str("<h2>Warnings</h2><ul>");
        for w in &report.warnings {
            b.push_str(&format!("<li>{}</li>", esc(w)));
        }
        b.push_str("</ul>\n");
    }
    b.push_str(
        "<footer><p class=\"muted\">Stills, differences and flip-books are frond's own renders \
         (wood and foliage, textures mip-mapped as engines sample them) from one camera; the \
         stills and differences at the coverage metric's samples a pixel. KB and \
         MB are 1024 and 1024² bytes. The live view is three.js r187, vendored in \
         <code>viewer/</code>.</p></footer>\n",
    );
    b.push_str(ZOOM_JS);
    b.push_str(&format!(
        "<script type=\"application/json\" id=\"frond-config\">{}</script>\n\
         <script src=\"{}\"></script>\n<script>\n{LIVE_VIEW_JS}</script>\n",
        config_json(config),
        href(&format!("{}/frond-three.js", config.viewer)),
    ));
    b
}

/// The live view's markup (its script comes at the end of the page).
fn live_view(config: &ViewConfig) -> String {
    let last = config.lods.len().saturating_sub(1);
    format!(
        "<section id=\"live\"><h2>Live view</h2>\n<div class=\"live\">\
         <canvas id=\"live-canvas\"></canvas>\n<div class=\"controls\">\
         <label>LOD <input type=\"range\" id=\"lod-slider\" min=\"0\" max=\"{last}\" step=\"1\" value=\"0\"></label>\
         <output id=\"lod-label\">LOD0</output>\
         <label><input type=\"checkbox\" id=\"lod-auto\"> switch by screen size</label>\
         <button id=\"play\" type=\"button\">Pause</button><span id=\"live-status\">loading…</span></div>\n\
         <div id=\"file-fallback\" class=\"fallback\" hidden><p>This page was opened from disk, and \
         browsers do not let such a page read the files beside it. Run <code>frond view \
         FOLDER</code> (it serves this folder on localhost and opens the page), or pick \
         <code>{}</code> here: <input type=\"file\" id=\"file-pick\" accept=\".glb\"></p></div>\n\
         <p class=\"muted\">Drag to orbit, scroll to zoom. \"Switch by screen size\" shows the LOD \
         built for the tree's height on this canvas, at the report's switch values.</p></div></section>\n",
        esc(&config.combined)
    )
}

/// A row of the cost table: label, and per LOD the value (None: not known).
struct Row {
    label: &'static str,
    values: Vec<Option<f64>>,
    show: fn(f64) -> String,
    /// The chain's monotone rule applies: a value above the LOD before is marked.
    monotone: bool,
    /// Show each value as a share of LOD0's too.
    share: bool,
}

fn cost_row(
    label: &'static str,
    report: &LodReport,
    get: fn(&FileCost) -> f64,
    show: fn(f64) -> String,
) -> Row {
    Row {
        label,
        values: report
            .lods
            .iter()
            .map(|e| e.cost.as_ref().map(get))
            .collect(),
        show,
        monotone: true,
        share: true,
    }
}

fn count(v: f64) -> String {
    units::count(v.round() as u64)
}

fn bytes(v: f64) -> String {
    units::bytes(v)
}

/// A cost of the table read off a file's cost, and how it is written.
type FileCostRow = (&'static str, fn(&FileCost) -> f64, fn(f64) -> String);

/// The table's rows read off each file's cost (`frond_scene::file_cost`).
const FILE_COSTS: [FileCostRow; 10] = [
    ("Triangles", |c| c.triangles as f64, count),
    ("Vertices", |c| c.vertices as f64, count),
    ("Draw calls", |c| c.draw_calls as f64, count),
    ("Materials", |c| c.materials as f64, count),
    (
        "Joints (largest skin)",
        |c| c.joints_per_skin_max as f64,
        count,
    ),
    ("Animated channels", |c| c.animated_channels as f64, count),
    ("Keyframe bytes", |c| c.keyframe_bytes as f64, bytes),
    (
        "Texture memory (GPU, mips)",
        |c| c.texture_gpu_bytes as f64,
        bytes,
    ),
    (
        "Texture bytes in files",
        |c| c.texture_encoded_bytes as f64,
        bytes,
    ),
    ("File bytes", |c| c.file_bytes as f64, bytes),
];

/// The cost table: what each written file costs an engine, read back from the files.
fn cost_table(report: &LodReport, pictures: &[LodPictures]) -> String {
    let mut rows: Vec<Row> = FILE_COSTS
        .iter()
        .map(|&(label, get, show)| cost_row(label, report, get, show))
        .collect();
    rows.push(Row {
        label: "Overdraw (alpha-tested area vs LOD0)",
        values: report
            .lods
            .iter()
            .map(|e| e.alpha_tested_area_ratio)
            .collect(),
        show: |v| format!("{}×", units::significant(v)),
        monotone: true,
        share: false,
    });
    let mut t = String::from(
        "<section id=\"costs\"><h2>What each LOD costs</h2>\n<p class=\"muted\">Read back from \
         the written files as an engine counts them. A red cell costs more than the LOD before \
         it; the small figure is the share of LOD0.</p>\n<table class=\"costs\"><tr><th></th>",
    );
    for (k, e) in report.lods.iter().enumerate() {
        t.push_str(&format!(
            "<th><a href=\"#lod{k}\">LOD{k}</a><br><small>{}</small></th>",
            esc(&e.file)
        ));
    }
    t.push_str("</tr>\n");
    let lods = &report.lods;
    t.push_str(&text_row(
        "Built for",
        lods.iter().map(|e| {
            cell(
                &e.screen_height
                    .map_or("the input".into(), |h| format!("{h} px high")),
            )
        }),
    ));
    t.push_str(&text_row(
        "Method",
        lods.iter().map(|e| cell(&esc(e.method.name()))),
    ));
    for row in &rows {
        t.push_str(&format!("<tr><td>{}</td>", row.label));
        let first = row.values.first().copied().flatten();
        for (k, v) in row.values.iter().enumerate() {
            let Some(v) = *v else {
                t.push_str(NONE);
                continue;
            };
            let before = k.checked_sub(1).and_then(|j| row.values[j]);
            let up = row.monotone && before.is_some_and(|b| v > b * (1.0 + 1e-6));
            let share = match first {
                Some(f) if row.share && k > 0 && f > 0.0 => {
                    format!(" <small>{} %</small>", units::significant(100.0 * v / f))
                }
                _ => String::new(),
            };
            t.push_str(&format!(
                "<td{}>{}{share}</td>",
                if up { " class=\"up\"" } else { "" },
                (row.show)(v)
            ));
        }
        t.push_str("</tr>\n");
    }
    if let Some(view) = &report.switching {
        let switch = |label: &str, show: &dyn Fn(&SwitchValues) -> String| {
            text_row(
                label,
                lods.iter()
                    .map(|e| e.switch.as_ref().map_or(NONE.into(), |s| cell(&show(s)))),
            )
        };
        t.push_str(&switch(
            &format!(
                "Shown from (camera distance, {}° FOV, {} px screen)",
                units::significant(f64::from(view.fov_deg)),
                view.resolution
            ),
            &|s| {
                format!(
                    "{} – {}",
                    distance(s.begin_distance),
                    distance(s.end_distance)
                )
            },
        ));
        t.push_str(&switch(
            "Shown down to (tree's share of screen height)",
            &|s| {
                format!(
                    "{} % <small>{} px</small>",
                    units::significant(f64::from(100.0 * s.min_screen_fraction)),
                    units::significant(f64::from(s.min_screen_fraction * view.resolution))
                )
            },
        ));
        t.push_str(&switch(
            "Unity transition height · Unreal screen size",
            &|s| {
                format!(
                    "{} · {}",
                    units::significant(f64::from(s.unity_transition_height)),
                    units::significant(f64::from(s.unreal_screen_size))
                )
            },
        ));
    }
    t.push_str(&measured_rows(lods));
    t.push_str(&text_row(
        "Covered area missing · extra in the still (px)",
        pictures.iter().enumerate().map(|(k, p)| {
            let d = p.difference;
            if k == 0 {
                NONE.into()
            } else {
                cell(&format!(
                    "{} · {}",
                    units::significant(d.missing),
                    units::significant(d.extra)
                ))
            }
        }),
    ));
    t.push_str("</table>\n");
    t.push_str(COVERAGE_NOTE);
    t.push_str("</section>\n");
    t
}

/// What the coverage measures are, under the cost table.
const COVERAGE_NOTE: &str = "<p class=\"muted\">The coverage error is the covered area a LOD \
     misses or adds, over the area LOD0 covers, each pixel counted by the fraction of it covered \
     (as MSAA, alpha-to-coverage or a distant eye show it), at the LOD's own size: 0 is perfect, \
     red is over the target. The coverage ratio is the LOD's covered area over LOD0's: below \
     100 % it thins out, above it bloats. The switch pop is the LOD's error against the LOD \
     before it at this size, what a player sees change when the engine swaps them. The binary \
     error is the thesis' rule on the same renders (a pixel covered when half its samples are), \
     for comparison.</p>\n";

/// The table's rows of the measured errors ([`MeasuredError`]), a cell per LOD (none for a
/// LOD not measured).
fn measured_rows(lods: &[LodEntry]) -> String {
    let row = |label: &str, show: &dyn Fn(&MeasuredError) -> String| {
        text_row(
            label,
            lods.iter()
                .map(|e| e.error.as_ref().map_or(NONE.into(), show)),
        )
    };
    let mut t = row("Coverage error at its own size (target)", &|m| {
        format!(
            "<td class=\"{}\">{} <small>({})</small></td>",
            if m.within_target { "ok" } else { "over" },
            units::significant(m.coverage),
            units::significant(m.max_error)
        )
    });
    t.push_str(&row("Coverage ratio (covered area, LOD0 = 100 %)", &|m| {
        cell(&format!(
            "{} %",
            units::significant(100.0 * m.coverage_ratio)
        ))
    }));
    t.push_str(&row(
        "Switch pop (error against the LOD before, at this size)",
        &|m| cell(&units::significant(m.switch_pop)),
    ));
    t.push_str(&row(
        "<small>Binary error (thesis: covered when ≥ ½ of a pixel is)</small>",
        &|m| cell(&format!("<small>{}</small>", binary(m.coverage_binary))),
    ));
    t.push_str(&row("Measured from", &|m| {
        cell(&format!(
            "{} views a ring × {} frames <small>{}</small>",
            m.views,
            m.frames,
            esc(&rings(&m.elevations_deg))
        ))
    }));
    t.push_str(&row("Samples a pixel", &|m| {
        cell(&format!("{0}×{0}", m.samples_per_side))
    }));
    t
}

/// The thesis' binary error, `—` where every pair was discarded.
fn binary(b: Option<f64>) -> String {
    b.map_or("—".into(), units::significant)
}

/// The metric's rings: "the ring at 0°", "rings at 0° and 30°".
fn rings(elevations_deg: &[f32]) -> String {
    let deg: Vec<String> = elevations_deg
        .iter()
        .map(|&e| format!("{}°", units::significant(f64::from(e))))
        .collect();
    match deg.as_slice() {
        [] => "no rings".into(),
        [one] => format!("the ring at {one}"),
        [init @ .., last] => format!("rings at {} and {last}", init.join(", ")),
    }
}

/// A cell of the table for a LOD without the value.
const NONE: &str = "<td>–</td>";

/// A table cell holding `html`.
fn cell(html: &str) -> String {
    format!("<td>{html}</td>")
}

/// A row of the table: its label, then the cells (each a whole `<td>`).
fn text_row(label: &str, cells: impl Iterator<Item = String>) -> String {
    let mut r = format!("<tr><td>{label}</td>");
    r.extend(cells);
    r.push_str("</tr>\n");
    r
}

/// A distance in the file's units (metres for glTF).
fn distance(d: f32) -> String {
    if d.is_finite() {
        format!("{} m", units::significant(f64::from(d)))
    } else {
        "∞".into()
    }
}

/// One LOD's section.
fn lod_section(report: &LodReport, k: usize, e: &LodEntry, p: &LodPictures) -> String {
    let dir = format!("{}_preview", report.name);
    let h = units::significant(f64::from(p.tree_height));
    // Start magnified so the tree reads at about 240 px or more.
    let zoom = if p.tree_height >= 240.0 {
        1
    } else if p.tree_height >= 120.0 {
        2
    } else {
        4
    };
    let mut s = format!(
        "<section class=\"lod\" id=\"lod{k}\"><h2>LOD{k} — {}</h2>\n<p>File \
         <a href=\"{}\"><code>{}</code></a>. <b>{}</b>: {}</p>\n",
        e.screen_height.map_or("the input".into(), |h| format!(
            "{h} px high · {}",
            esc(e.method.name())
        )),
        href(&e.file),
        esc(&e.file),
        esc(e.method.name()),
        esc(&e.method_reason),
    );
    if let Some(m) = &e.error {
        s.push_str(&measured_paragraph(k, e, m));
    }
    s.push_str(&format!(
        "<div class=\"zoom\" data-zoom=\"{zoom}\">Stills: <button type=\"button\" data-z=\"1\">1×</button>\
         <button type=\"button\" data-z=\"2\">2×</button><button type=\"button\" data-z=\"4\">4×</button> \
         <span class=\"muted\">(pixels as a player sees them, the tree {h} px high; each pixel the mean of {0}×{0} \
         samples, as opaque as the fraction of them covered)</span></div>\n<div class=\"row\">",
        p.samples_per_side
    ));
    let size = p.still;
    if k == 0 {
        s.push_str(&figure(
            &format!("{dir}/lod0.png"),
            size,
            &format!("LOD0, {h} px high"),
            true,
        ));
    } else {
        s.push_str(&figure(
            &format!("{dir}/lod{k}_lod0.png"),
            size,
            &format!("LOD0, {h} px high"),
            true,
        ));
        s.push_str(&figure(
            &format!("{dir}/lod{k}.png"),
            size,
            &format!("LOD{k}, {h} px high, same camera"),
            true,
        ));
        let d = p.difference;
        s.push_str(&figure(
            &format!("{dir}/lod{k}_diff.png"),
            size,
            &format!(
                "Difference, each pixel {k2}×{k2} samples: <span class=\"legend\"><span \
                 style=\"background:rgb({},{},{})\"></span>missing {} px<span \
                 style=\"background:rgb({},{},{})\"></span>extra {} px</span> of LOD0's {} px \
                 covered: {} %, the coverage error of this one view (colour strength is the \
                 fraction of a pixel missing or extra)",
                MISSING[0],
                MISSING[1],
                MISSING[2],
                units::significant(d.missing),
                EXTRA[0],
                EXTRA[1],
                EXTRA[2],
                units::significant(d.extra),
                units::significant(d.reference),
                units::significant(100.0 * d.error()),
                k2 = p.samples_per_side,
            ),
            true,
        ));
    }
    s.push_str("</div>\n<div class=\"row\">");
    let still_note = if e.vat.is_some() || e.spectral_files.is_some() {
        " (vertex-animated: frond's renderer and the live view show it still)"
    } else {
        ""
    };
    s.push_str(&format!(
        "<figure><img class=\"flip\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"wind loop\">\
         <figcaption>Wind loop, {} frames over {}{still_note}</figcaption></figure>",
        href(&format!("{dir}/lod{k}_wind.png")),
        p.flip[0] * 2,
        p.flip[1] * 2,
        p.flip_frames,
        units::duration(f64::from(report.period)),
    ));
    if let (Some(side), Some(a)) = (p.atlas, e.atlas) {
        s.push_str(&format!(
            "<figure><img class=\"atlas\" src=\"{}\" width=\"{}\" height=\"{}\" alt=\"atlas\">\
             <figcaption>Atlas, {}×{} texels ({} billboards)</figcaption></figure>",
            href(&format!("{dir}/lod{k}_atlas.png")),
            side[0],
            side[1],
            a[0],
            a[1],
            e.billboards,
        ));
    }
    s.push_str("</div></section>\n");
    s
}

/// What LOD `k`'s measured error says, in words.
fn measured_paragraph(k: usize, e: &LodEntry, m: &MeasuredError) -> String {
    let height = e.screen_height.map_or_else(
        || m.image[1].to_string(),
        |h| units::significant(f64::from(h)),
    );
    format!(
        "<p>Coverage error at its own size, the tree {height} px high: <span class=\"{}\">{}</span> \
         (target {}): the covered area it misses or adds over the area LOD0 covers, each pixel \
         counted by the fraction of it covered. It covers {} % of LOD0's covered area ({}). \
         Switch pop {}: its error against LOD{} at this size, what a player sees change when the \
         engine swaps them. {}Measured from {} views a ring on {}, × {} frames of the loop, \
         {}×{} samples a pixel, in {}×{} px images. <small class=\"muted\">Binary error (the \
         thesis' rule, a pixel covered when half its samples are): {}.</small> Depth complexity \
         {} (the input's {} at this size).</p>\n",
        if m.within_target { "ok" } else { "over" },
        units::significant(m.coverage),
        units::significant(m.max_error),
        units::significant(100.0 * m.coverage_ratio),
        if m.coverage_ratio < 1.0 {
            "below 100 %: it thins out"
        } else if m.coverage_ratio > 1.0 {
            "above 100 %: it bloats"
        } else {
            "as much"
        },
        units::significant(m.switch_pop),
        k.saturating_sub(1),
        loop_sentence(m),
        m.views,
        esc(&rings(&m.elevations_deg)),
        m.frames,
        m.samples_per_side,
        m.samples_per_side,
        m.image[0],
        m.image[1],
        binary(m.coverage_binary),
        units::significant(m.depth_complexity),
        units::significant(m.input_depth_complexity),
    )
}

/// What the LOD's motion does to its coverage, against LOD0's, as a sentence (empty when not
/// measured).
fn loop_sentence(m: &MeasuredError) -> String {
    match (m.loop_change_ratio, m.loop_change_input) {
        (Some(r), Some(input)) => format!(
            "Over the loop its coverage changes {}× as much as LOD0's ({} % of LOD0's covered \
             area changes from frame to frame): {}. ",
            units::significant(r),
            units::significant(100.0 * input),
            if r < 0.7 {
                "it moves less than the tree"
            } else if r > 1.3 {
                "it moves more than the tree"
            } else {
                "it moves like the tree"
            }
        ),
        _ => String::new(),
    }
}

/// The zoom buttons of the stills: each section's pictures at 1×, 2× or 4× their pixels.
const ZOOM_JS: &str = r#"<script>
for (const bar of document.querySelectorAll('.zoom')) {
  const row = bar.nextElementSibling;
  const set = (z) => {
    for (const img of row.querySelectorAll('img.px')) {
      img.style.width = img.getAttribute('width') * z + 'px';
      img.style.height = 'auto';
    }
    for (const b of bar.querySelectorAll('button')) b.classList.toggle('on', b.dataset.z == z);
  };
  for (const b of bar.querySelectorAll('button')) b.addEventListener('click', () => set(+b.dataset.z));
  set(+bar.dataset.zoom);
}
</script>
"#;

#[cfg(test)]
mod tests {
    use frond_lod::method_api::MethodName;

    use super::*;

    fn measured(ratio: f64, binary: Option<f64>) -> MeasuredError {
        MeasuredError {
            coverage: 0.123,
            coverage_ratio: ratio,
            coverage_binary: binary,
            switch_pop: 0.0456,
            loop_change_input: Some(0.04),
            loop_change_ratio: Some(0.9),
            max_error: 0.1,
            within_target: false,
            image: [98, 114],
            samples_per_side: 17,
            views: 5,
            elevations_deg: vec![0.0, 30.0],
            frames: 5,
            depth_complexity: 3.0,
            input_depth_complexity: 11.0,
        }
    }

    #[test]
    fn heavy_lods_get_fewer_flip_frames_but_never_under_the_floor() {
        assert_eq!(flip_frames(12, 7_200), 12, "a light LOD: every frame asked");
        assert_eq!(flip_frames(12, 50_000), 5, "250k triangles over the frames");
        assert_eq!(flip_frames(12, 128_000), MIN_FLIP_FRAMES);
        assert_eq!(flip_frames(12, 1_000_000), MIN_FLIP_FRAMES);
        assert_eq!(flip_frames(4, 1_000_000), 4, "never more than asked");
        assert_eq!(flip_frames(0, 10), 1);
        assert_eq!(flip_frames(12, 0), 12);
    }

    #[test]
    fn measured_rows_show_error_ratio_pop_binary_rings_and_samples() {
        let lod0 = LodEntry::new(MethodName::INPUT, "the input");
        let mut lod1 = LodEntry::new(MethodName::INPUT, "thinned");
        lod1.error = Some(measured(0.97, None));
        let mut lod2 = lod1.clone();
        lod2.error = Some(measured(1.25, Some(0.111)));
        let rows = measured_rows(&[lod0, lod1.clone(), lod2]);
        assert!(
            rows.contains("<td class=\"over\">0.123 <small>(0.1)</small></td>"),
            "over its target: red: {rows}"
        );
        assert!(rows.contains("<td>97 %</td><td>125 %</td>"), "{rows}");
        assert!(rows.contains("<td>0.0456</td>"), "{rows}");
        assert!(
            rows.contains("<td><small>—</small></td><td><small>0.111</small></td>"),
            "{rows}"
        );
        assert!(rows.contains("rings at 0° and 30°"), "{rows}");
        assert!(rows.contains("<td>17×17</td>"), "{rows}");
        assert_eq!(rows.matches(NONE).count(), 6, "LOD0 is not measured");

        let p = measured_paragraph(1, &lod1, lod1.error.as_ref().expect("measured"));
        assert!(p.contains("It covers 97 % of LOD0's covered area (below 100 %: it thins out)"));
        assert!(p.contains("Switch pop 0.0456: its error against LOD0"));
        assert!(
            p.contains("changes 0.9× as much as LOD0's (4 % of LOD0's covered area"),
            "{p}"
        );
        assert!(p.contains("it moves like the tree"));
        assert!(p.contains("Binary error"));
        assert!(p.contains("—.</small>"));
    }

    #[test]
    fn rings_read_as_a_list() {
        assert_eq!(rings(&[0.0]), "the ring at 0°");
        assert_eq!(rings(&[0.0, 30.0]), "rings at 0° and 30°");
        assert_eq!(rings(&[-10.0, 0.0, 45.5]), "rings at -10°, 0° and 45.5°");
    }
}
