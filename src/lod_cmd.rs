//! `frond lod`: an animated tree in, a chain of animated LODs out. LOD0 is the input rewritten
//! cleanly; every further LOD is an animated billboard cloud of the foliage plus the wood
//! simplified to the LOD's error budget, sized from the screen height it is seen at.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use frond_billboard::animated::{
    AnimatedBillboardCloud, LoopClock, Rig, RigidMotion, SpectralMotion,
};
use frond_billboard::animated_build::{
    BuildTimings, build_animated_cloud, per_bone_clusters, sampled_worlds, static_clusters,
};
use frond_billboard::cloud::{CloudParams, parse_epsilon};
use frond_billboard::motion_budget::{Dropped, ScreenBudget, apply_budget};
use frond_billboard::plane_search::SearchParams;
use frond_billboard::skeleton_build::build_skeleton_cloud;
use frond_billboard::spectral_build::{SpectralParams, SpectralReport, build_spectral_cloud};
use frond_export::lod_file::{FileOptions, write_glb};
use frond_export::mapping::Mapping;
use frond_export::spectral::{SpectralTerm, SpectralTextures, encode_spectral};
use frond_export::textures::sanitize;
use frond_export::vat::{RigidFrame, RigidPiece, VatFormat, VatOptions, encode_rigid_with};
use frond_export::{GltfFile, LodInput};
use frond_render::Renderer;
use frond_scene::wood::{NO_BONE, WoodMesh};
use frond_scene::{Part, Sampled, Tree};
use frond_skeleton::{BoneDescriptionKind, SkeletonParams, SkeletonReport};
use frond_spectral::description::SpectralKind;
use serde::Serialize;

use crate::cloud_cmd::{rest_diagonal, sample_foliage};
use crate::output_set::OutputSet;
use crate::screen_budget::{LodLevel, lod_levels, tree_height};

/// How the foliage of a LOD is clustered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The documented rule of [`auto_method`].
    Auto,
    PerBone,
    Static,
    /// Spectral clustering (SCA) with one description type.
    Spectral(SpectralKind),
    /// Skeleton simplification (SBCS) with one bone description type.
    Skeleton(BoneDescriptionKind),
}

/// The description type `--method spectral` uses.
pub const DEFAULT_SPECTRAL: SpectralKind = SpectralKind::AxisPhase;

/// The bone description type `--method skeleton` uses: axis-angle reached fewer clouds at the
/// same screen tolerance with less foliage error than rotation-spectral on oak_medium and
/// oak_dense (docs/experiments.md §8).
pub const DEFAULT_SKELETON: BoneDescriptionKind = BoneDescriptionKind::AxisAngle;

/// Default animation zone size as a fraction of the bounding-box diagonal (or the LOD's ε when
/// larger): oak_dense's 116k triangles become ~4,400 zones, which k-means clusters in ~1 s.
pub const DEFAULT_ZONE_FRACTION: f32 = 0.02;

/// Every name `--method` takes.
pub const METHOD_NAMES: &[&str] = &[
    "auto",
    "per-bone",
    "static",
    "spectral",
    "spectral-naive",
    "spectral-dominating-axis",
    "spectral-axis-phase",
    "skeleton",
    "skeleton-axis-angle",
    "skeleton-rotation-spectral",
];

impl Method {
    /// Parses a name of [`METHOD_NAMES`] (`spectral` alone is [`DEFAULT_SPECTRAL`]).
    pub fn parse(s: &str) -> Option<Method> {
        match s {
            "auto" => Some(Method::Auto),
            "per-bone" => Some(Method::PerBone),
            "static" => Some(Method::Static),
            "spectral" => Some(Method::Spectral(DEFAULT_SPECTRAL)),
            "skeleton" => Some(Method::Skeleton(DEFAULT_SKELETON)),
            _ => s
                .strip_prefix("spectral-")
                .and_then(SpectralKind::parse)
                .map(Method::Spectral)
                .or_else(|| {
                    s.strip_prefix("skeleton-")
                        .and_then(BoneDescriptionKind::parse)
                        .map(Method::Skeleton)
                }),
        }
    }
    /// The name `--method` takes (spectral methods with their type).
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::PerBone => "per-bone",
            Method::Static => "static",
            Method::Spectral(SpectralKind::Naive) => "spectral-naive",
            Method::Spectral(SpectralKind::DominatingAxis) => "spectral-dominating-axis",
            Method::Spectral(SpectralKind::AxisPhase) => "spectral-axis-phase",
            Method::Skeleton(BoneDescriptionKind::AxisAngle) => "skeleton-axis-angle",
            Method::Skeleton(BoneDescriptionKind::RotationSpectral) => "skeleton-rotation-spectral",
        }
    }
}

/// The fixed rule of `--method auto`, from the issue-5, -6 and -7 sweeps (docs/experiments.md
/// §6–8): the nearest LOD gets `skeleton` (per-bone clouds, sibling bones merged only where
/// no leaf moves a pixel and none leaves its branch by half a pixel: per-bone's exact-looking
/// motion with fewer clouds, and the same LOD as per-bone where nothing merges unseen);
/// every farther LOD `static` (one cloud, fewest billboards: at matched billboard counts
/// its animated colour error beat every spectral type on the shared trees), except under
/// `--animation spectral`, whose compact coefficient texture only spectral motion has: there
/// farther LODs get `spectral-axis-phase` (of the three types, the lowest colour and motion
/// errors). Returns the method and the reason written to the report.
pub fn auto_method(lod_index: usize, spectral_animation: bool) -> (Method, &'static str) {
    if lod_index == 0 {
        (
            Method::Skeleton(DEFAULT_SKELETON),
            "auto: nearest LOD -> skeleton (per-bone clouds; sibling bones share a rotation only \
             where no leaf would move a pixel)",
        )
    } else if spectral_animation {
        (
            Method::Spectral(SpectralKind::AxisPhase),
            "auto: farther LOD with --animation spectral -> spectral-axis-phase (motion as a few \
             cosines per billboard)",
        )
    } else {
        (
            Method::Static,
            "auto: farther LOD -> static (one cloud, fewest billboards, best colour at matched \
             billboard counts)",
        )
    }
}

/// The spectral k rule: one animation cluster per 10 pixels of tree height (6 at 60 px, 20 at
/// 200 px), at least 1.
pub fn spectral_k(screen_height: f32) -> usize {
    ((screen_height / 10.0).round() as usize).max(1)
}

/// How billboards are animated in the files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationMode {
    /// Standard glTF skin and channels.
    Skin,
    /// Vertex animation textures (Houdini VAT 3.0 rigid layout) plus a skinned wood.
    Vat(VatFormat),
    /// Skinned billboards plus each one's own motion as a few cosines in a float texture
    /// (spectral methods, spec §4.11 "runtime"); per-bone LODs need no texture.
    Spectral,
}

/// What `frond lod` was asked for.
#[derive(Clone, Debug)]
pub struct LodRequest {
    pub method: Method,
    /// Screen heights (pixels) of LOD1, LOD2, ...
    pub screen_heights: Vec<f32>,
    /// Pixel-error budget.
    pub pixel_error: f32,
    /// ε override as given ("0.5" or "2%"), for experiments.
    pub epsilon: Option<String>,
    pub animation: AnimationMode,
    pub seed: u64,
    pub samples: usize,
    pub clip: Option<String>,
    /// Candidate planes per iteration.
    pub planes: usize,
    /// Lacewell's view penalty (radians of the favoured elevation), thesis §8.4.1.
    pub view_penalty: Option<f32>,
    /// Bake every triangle valid for a plane, not only its own (thesis §8.4.1).
    pub increased_density: bool,
    pub max_atlas: u32,
    /// Supersamples per texel side when baking (4 = the spec's 4×4; 2 bakes ~2.5× faster).
    pub supersample: u32,
    /// Dilated texels around each billboard's texture in the atlas.
    pub padding: u32,
    /// Add MSFT_lod to the combined file, with coverages for this image height.
    pub msft_lod: bool,
    /// Spectral clusters per LOD (None: the k rule, see [`SpectralParams::clusters`]).
    pub clusters: Option<usize>,
    /// Animation zone size ("0.5" or "1%"; None: [`DEFAULT_ZONE_FRACTION`] of the diagonal or
    /// the LOD's ε, the larger).
    pub zone_size: Option<String>,
    /// Bind spectral billboards to their triangles' deepest shared bone (spec §4.12).
    pub shared_bone: bool,
    /// Skeleton billboard clouds per LOD (None: the LOD's own rule, merges no eye can see at
    /// its pixel size: at most a pixel of foliage motion, half a pixel off a branch).
    pub clouds: Option<usize>,
    /// Skeleton method: the average-animation-bone improvement (spec §6.1, thesis §7.1.2).
    pub average_bone: bool,
    pub resolution: f32,
    pub external_textures: bool,
}

/// One LOD's line of `<name>_report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LodEntry {
    pub file: String,
    pub mapping: Option<String>,
    /// Pixels the tree covers (None for LOD0, the input itself).
    pub screen_height: Option<f32>,
    pub pixel: Option<f32>,
    pub epsilon: Option<f32>,
    pub method: String,
    pub method_reason: String,
    /// Triangles drawn (wood plus two per billboard).
    pub triangles: usize,
    pub wood_triangles: usize,
    pub billboards: usize,
    /// Joints of the LOD's skin.
    pub bones: usize,
    pub texture_bytes: usize,
    pub atlas: Option<[u32; 2]>,
    pub texels_per_unit: Option<f32>,
    pub density_reduced: bool,
    pub clips: Vec<String>,
    pub dropped: DroppedReport,
    pub vat: Option<Vec<String>>,
    /// `--animation spectral`: the coefficient texture and its sidecar.
    pub spectral_files: Option<Vec<String>>,
    /// Bytes of the coefficient texture (`--animation spectral`), or of the VAT textures.
    pub animation_bytes: usize,
    /// `--animation spectral`: what EXR VAT textures of the same LOD would take (encoded, not
    /// written), for comparison.
    pub vat_equivalent_bytes: Option<usize>,
    /// What spectral clustering did (spectral LODs only).
    pub spectral: Option<SpectralReport>,
    /// What skeleton simplification did (skeleton LODs only).
    pub skeleton: Option<SkeletonReport>,
    pub timings_s: LodTimings,
}

/// What a LOD left out, and why.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DroppedReport {
    #[serde(flatten)]
    pub budget: Dropped,
    /// Wood triangles removed by simplification within `wood_error` world units.
    pub wood_triangles: usize,
    pub wood_error: f32,
    /// Input clips not written, with the reason.
    pub clips: Vec<String>,
}

/// Per-stage wall times of one LOD.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LodTimings {
    #[serde(flatten)]
    pub build: BuildTimings,
    pub budget: f64,
    pub wood: f64,
    pub export: f64,
}

/// `<name>_report.json`.
#[derive(Debug, Serialize)]
pub struct LodReport {
    pub input: String,
    pub name: String,
    pub clip: Option<String>,
    pub period: f32,
    pub samples: usize,
    pub seed: u64,
    pub pixel_error: f32,
    pub animation: String,
    pub tree_height: f32,
    pub lods: Vec<LodEntry>,
    pub combined: String,
    /// Every file of the set, relative to the output folder, this report last.
    pub files: Vec<String>,
    /// What the import accepted with a warning (silently repaired or ignored input).
    pub warnings: Vec<String>,
    pub timings_s: serde_json::Value,
}

/// The report's file name: `<name>_report.json`, so that several trees can share one output
/// folder without their reports colliding.
pub fn report_name(name: &str) -> String {
    format!("{name}_report.json")
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

/// The tree's wood and foliage with bones as rig node indices (a [`Rig::from_tree`] rig).
fn part_mesh(tree: &Tree, part: Part) -> WoodMesh {
    let mut m = WoodMesh::from_tree_part(tree, part);
    to_nodes(tree, &mut m);
    m
}

/// Re-expresses a mesh's tree-bone indices as tree node indices.
fn to_nodes(tree: &Tree, m: &mut WoodMesh) {
    for b in m.bones.iter_mut().flatten() {
        if *b != NO_BONE {
            *b = tree.bones[*b as usize].node as u32;
        }
    }
}

/// Re-maps node indices after a rig was pruned.
fn remap(m: &mut WoodMesh, map: &[Option<usize>]) {
    for b in m.bones.iter_mut().flatten() {
        if *b != NO_BONE {
            *b = map
                .get(*b as usize)
                .copied()
                .flatten()
                .map_or(NO_BONE, |n| n as u32);
        }
    }
}

/// Rig nodes a mesh needs.
fn used_nodes(m: &WoodMesh) -> Vec<usize> {
    m.used_bones()
        .into_iter()
        .filter(|&b| b != NO_BONE)
        .map(|b| b as usize)
        .collect()
}

/// What a LOD draws its skeleton from: LOD0 keeps the input's rig, a billboard LOD its
/// cloud's (which the screen budget pruned).
enum LodContent {
    Input(Rig),
    Cloud(AnimatedBillboardCloud),
}

/// A LOD ready to write.
struct BuiltLod {
    name: String,
    content: LodContent,
    parts: Vec<WoodMesh>,
    clips: Vec<usize>,
    vat: Option<frond_export::vat::VatTextures>,
    spectral: Option<SpectralTextures>,
    entry: LodEntry,
}

impl BuiltLod {
    fn cloud(&self) -> Option<&AnimatedBillboardCloud> {
        match &self.content {
            LodContent::Cloud(c) => Some(c),
            LodContent::Input(_) => None,
        }
    }
}

/// Builds everything in memory, then writes the LOD files, the combined file, the sidecars and
/// `<name>_report.json` into `out_dir` as one [`OutputSet`]: the folder is checked (and a staging
/// folder made in it) before the build, and the set is installed whole at the end, replacing the
/// previous set of the same tree. Nothing is written unless everything was built.
pub fn run_lod(
    renderer: &Renderer,
    tree: &Tree,
    req: &LodRequest,
    out_dir: &Path,
    progress: &dyn Fn(&str),
) -> Result<LodReport> {
    let path = tree.source.display().to_string();
    let t_start = Instant::now();
    let name = lod_name(tree);
    let height = tree_height(tree);
    let diag = rest_diagonal(tree);
    let eps_override = match &req.epsilon {
        Some(e) => Some(parse_epsilon(e, diag).with_context(|| {
            format!("--epsilon '{e}': expected a length or a percentage like 2%")
        })?),
        None => None,
    };
    let spectral_options = req.clusters.is_some() || req.zone_size.is_some() || !req.shared_bone;
    let may_be_spectral = matches!(req.method, Method::Spectral(_))
        || (req.method == Method::Auto && req.animation == AnimationMode::Spectral);
    if spectral_options && !may_be_spectral {
        tracing::warn!(
            "--clusters, --zone-size and --no-shared-bone act on spectral methods only; \
             method '{}' ignores them",
            req.method.name()
        );
    }
    let skeleton_options = req.clouds.is_some() || req.average_bone;
    if skeleton_options && !matches!(req.method, Method::Skeleton(_)) {
        tracing::warn!(
            "--clouds and --average-bone act on skeleton methods only; method '{}' ignores them",
            req.method.name()
        );
    }
    let levels = lod_levels(height, &req.screen_heights, req.pixel_error, eps_override)
        .with_context(|| format!("{path}: sizing the LODs"))?;
    let mut set = OutputSet::prepare(out_dir, &name, &report_name(&name), &[&tree.source])?;
    let mut expected: Vec<String> = (0..=levels.len())
        .map(|k| format!("{name}_LOD{k}.glb"))
        .collect();
    expected.push(format!("{name}_lods.glb"));
    set.check_names(&expected)?;
    progress("sampling the animation");
    let sampled = sample_foliage(tree, req.clip.as_deref(), req.samples)?;
    let t_sampled = Instant::now();
    let clock = LoopClock::of(tree, &sampled);

    let mut built = Vec::new();
    built.push(build_lod0(tree, &name));
    let wood = part_mesh(tree, Part::Wood);
    for (k, level) in levels.iter().enumerate() {
        progress(&format!(
            "LOD{}: {} px, ε = {:.4}",
            k + 1,
            level.screen_height,
            level.epsilon
        ));
        let lod = build_lod(
            renderer, tree, &sampled, &clock, &wood, req, level, k, &name,
        )
        .with_context(|| format!("{path}: building LOD{}", k + 1))?;
        built.push(lod);
    }
    let t_built = Instant::now();

    // Write everything in memory first.
    progress("writing files");
    let prefix = |k: usize| format!("{name}_LOD{k}");
    let tex_prefix = |k: Option<usize>| {
        req.external_textures.then(|| match k {
            Some(k) => format!("{name}_LOD{k}_"),
            None => format!("{name}_lods_"),
        })
    };
    let extras = serde_json::json!({
        "generator": concat!("frond ", env!("CARGO_PKG_VERSION")),
        "seed": req.seed,
        "source": tree.source.file_name().map(|f| f.to_string_lossy().into_owned()),
    });
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    let mut entries = Vec::new();
    let inputs: Vec<LodInput> = built
        .iter()
        .map(|b| LodInput {
            name: b.name.clone(),
            tree,
            rig: match &b.content {
                LodContent::Input(rig) => rig,
                LodContent::Cloud(cloud) => &cloud.rig,
            },
            parts: b.parts.iter().collect(),
            cloud: b.cloud(),
            clips: b.clips.clone(),
            vat_uvs: b.vat.as_ref().map(|v| {
                vec![
                    v.piece_uv.clone(),
                    v.pivot_uv.iter().map(|p| p[0]).collect(),
                    v.pivot_uv.iter().map(|p| p[1]).collect(),
                ]
            }),
            spectral_uvs: b.spectral.as_ref().map(|t| t.row_uv.clone()),
        })
        .collect();
    for (k, (b, input)) in built.iter().zip(&inputs).enumerate() {
        let t0 = Instant::now();
        let file: GltfFile = write_glb(
            std::slice::from_ref(input),
            &FileOptions {
                external_textures: tex_prefix(Some(k)),
                msft_lod: None,
                extras: Some(extras.clone()),
            },
        )
        .with_context(|| format!("{path}: writing LOD{k}"))?;
        let glb_name = format!("{}.glb", prefix(k));
        files.push((glb_name.clone(), file.glb));
        files.extend(file.external);
        let mut entry = LodEntry {
            file: glb_name.clone(),
            bones: file.joints.first().copied().unwrap_or(0),
            ..b.entry.clone()
        };
        if let Some(cloud) = b.cloud() {
            let mapping = Mapping::of(cloud, k, &glb_name, &sampled.foliage);
            let mapping_name = format!("{}.mapping.json", prefix(k));
            files.push((
                mapping_name.clone(),
                serde_json::to_vec_pretty(&mapping).context("serialising a mapping")?,
            ));
            entry.mapping = Some(mapping_name);
        }
        if let Some(v) = &b.vat {
            let pos = v.sidecar.textures.position.clone();
            let rot = v.sidecar.textures.rotation.clone();
            let json = format!("{}_vat.json", prefix(k));
            files.push((pos.clone(), v.position.bytes.clone()));
            files.push((rot.clone(), v.rotation.bytes.clone()));
            files.push((
                json.clone(),
                serde_json::to_vec_pretty(&v.sidecar).context("serialising a VAT sidecar")?,
            ));
            entry.vat = Some(vec![pos, rot, json]);
        }
        if let Some(t) = &b.spectral {
            let json = format!("{}_spectral.json", prefix(k));
            files.push((t.sidecar.texture.clone(), t.image.bytes.clone()));
            files.push((
                json.clone(),
                serde_json::to_vec_pretty(&t.sidecar).context("serialising a spectral sidecar")?,
            ));
            entry.spectral_files = Some(vec![t.sidecar.texture.clone(), json]);
        }
        entry.timings_s.export = t0.elapsed().as_secs_f64();
        entries.push(entry);
    }
    // The combined file.
    let coverage: Option<Vec<f32>> = req.msft_lod.then(|| {
        let mut c: Vec<f32> = req
            .screen_heights
            .iter()
            .map(|h| (h / req.resolution).min(1.0))
            .collect();
        // LOD k is shown down to the size the next LOD was built for; the last one to a
        // quarter of its own.
        let last = c.last().copied().unwrap_or(0.0) * 0.25;
        c.push(last);
        c
    });
    let combined = write_glb(
        &inputs,
        &FileOptions {
            external_textures: tex_prefix(None),
            msft_lod: coverage,
            extras: Some(extras),
        },
    )
    .with_context(|| format!("{path}: writing the combined file"))?;
    let combined_name = format!("{name}_lods.glb");
    files.push((combined_name.clone(), combined.glb));
    files.extend(combined.external);
    let spectral_written = built.iter().any(|b| b.spectral.is_some());
    files.extend(shader_files(req, spectral_written));
    let t_written = Instant::now();

    let mut report = LodReport {
        input: path,
        name: name.clone(),
        clip: sampled.clip.clone(),
        period: sampled.period,
        samples: sampled.samples(),
        seed: req.seed,
        pixel_error: req.pixel_error,
        animation: match req.animation {
            AnimationMode::Skin => "skin".into(),
            AnimationMode::Vat(f) => format!("vat-{}", f.extension()),
            AnimationMode::Spectral => "spectral".into(),
        },
        tree_height: height,
        lods: entries,
        combined: combined_name,
        files: files.iter().map(|(p, _)| p.clone()).collect(),
        warnings: tree.warnings.clone(),
        timings_s: serde_json::json!({
            "sample": (t_sampled - t_start).as_secs_f64(),
            "build": (t_built - t_sampled).as_secs_f64(),
            "export": (t_written - t_built).as_secs_f64(),
            "total": (t_written - t_start).as_secs_f64(),
        }),
    };
    report.files.push(report_name(&name));
    for (rel, bytes) in &files {
        set.stage(rel, bytes)?;
    }
    let json = serde_json::to_vec_pretty(&report).context("serialising the report")?;
    set.commit(&json)?;
    Ok(report)
}

/// The reference shaders, copied next to VAT output and next to spectral textures (when a LOD
/// wrote one).
fn shader_files(req: &LodRequest, spectral_written: bool) -> Vec<(String, Vec<u8>)> {
    let set = match req.animation {
        AnimationMode::Vat(_) => frond_export::shaders::SHADERS,
        AnimationMode::Spectral if spectral_written => frond_export::shaders::SPECTRAL_SHADERS,
        _ => return Vec::new(),
    };
    set.iter()
        .map(|(file, text)| (format!("shaders/{file}"), text.as_bytes().to_vec()))
        .collect()
}

/// LOD0: the input's wood and foliage as one skinned mesh over its bones, every clip.
fn build_lod0(tree: &Tree, name: &str) -> BuiltLod {
    let mut rig = Rig::from_tree(tree);
    let mut wood = part_mesh(tree, Part::Wood);
    let mut foliage = part_mesh(tree, Part::Foliage);
    let mut keep = vec![false; rig.nodes.len()];
    for b in &tree.bones {
        keep[b.node] = true;
    }
    let map = rig.retain(&keep);
    remap(&mut wood, &map);
    remap(&mut foliage, &map);
    let triangles = wood.triangles() + foliage.triangles();
    let texture_bytes = tree.textures.iter().map(|t| t.rgba.len()).sum::<usize>();
    let clips: Vec<usize> = (0..rig.clips.len()).collect();
    BuiltLod {
        name: format!("{name}_LOD0"),
        entry: LodEntry {
            file: String::new(),
            mapping: None,
            screen_height: None,
            pixel: None,
            epsilon: None,
            method: "input".into(),
            method_reason: "LOD0 is the input tree, rewritten".into(),
            triangles,
            wood_triangles: wood.triangles(),
            billboards: 0,
            bones: 0,
            texture_bytes,
            atlas: None,
            texels_per_unit: None,
            density_reduced: false,
            clips: rig.clips.iter().map(|c| c.name.clone()).collect(),
            dropped: DroppedReport::default(),
            vat: None,
            spectral_files: None,
            animation_bytes: 0,
            vat_equivalent_bytes: None,
            spectral: None,
            skeleton: None,
            timings_s: LodTimings::default(),
        },
        content: LodContent::Input(rig),
        parts: vec![wood, foliage],
        clips,
        vat: None,
        spectral: None,
    }
}

#[expect(
    clippy::too_many_arguments,
    reason = "the build context of one LOD; issue 16 gathers it into one type"
)]
fn build_lod(
    renderer: &Renderer,
    tree: &Tree,
    sampled: &Sampled,
    clock: &LoopClock,
    wood: &WoodMesh,
    req: &LodRequest,
    level: &LodLevel,
    k: usize,
    name: &str,
) -> Result<BuiltLod> {
    let (method, reason) = match req.method {
        Method::Auto => auto_method(k, req.animation == AnimationMode::Spectral),
        m => (m, "given with --method"),
    };
    let mut params = CloudParams {
        search: SearchParams {
            epsilon: level.epsilon,
            candidates: req.planes,
            seed: req.seed.wrapping_add(k as u64),
            view_penalty: req.view_penalty,
            ..Default::default()
        },
        increased_density: req.increased_density,
        ..Default::default()
    };
    params.bake.texels_per_unit = level.texels_per_unit;
    params.bake.max_atlas = req.max_atlas;
    // Far LODs bake sparse foliage into few texels: keep its coverage (see BakeParams).
    params.bake.preserve_coverage = true;
    params.bake.supersample = req.supersample;
    params.bake.padding = req.padding;
    let diag = rest_diagonal(tree);
    let mut spectral = None;
    let mut skeleton = None;
    let (mut cloud, build_t) = match method {
        Method::Skeleton(kind) => {
            let sk = SkeletonParams {
                kind,
                clouds: req.clouds,
                average_bone: req.average_bone,
                bins: tree.skeleton_depth().max(1) as usize,
                attach_tolerance: 0.5 * level.pixel,
                displacement_tolerance: level.pixel,
            };
            let (cloud, t, report) =
                build_skeleton_cloud(renderer, tree, sampled, clock.clone(), &params, &sk, diag)?;
            if let Some(why) = &report.stopped_by {
                tracing::warn!("LOD{}: {why}", k + 1);
            }
            skeleton = Some(report);
            (cloud, t)
        }
        Method::Spectral(kind) => {
            let zone_size = match &req.zone_size {
                Some(z) => parse_epsilon(z, diag).with_context(|| {
                    format!("--zone-size '{z}': expected a length or a percentage like 1%")
                })?,
                None => level.epsilon.max(DEFAULT_ZONE_FRACTION * diag),
            };
            let sp = SpectralParams {
                kind,
                clusters: req
                    .clusters
                    .unwrap_or_else(|| spectral_k(level.screen_height)),
                zone_size,
                bins: tree.skeleton_depth().max(1) as usize,
                restarts: 2,
                seed: req.seed.wrapping_add(k as u64),
                max_iterations: 20,
                shared_bone: req.shared_bone,
            };
            let (cloud, t, report) = build_spectral_cloud(
                renderer,
                tree,
                sampled,
                Rig::from_tree(tree),
                clock.clone(),
                &params,
                &sp,
                diag,
            )?;
            spectral = Some(report);
            (cloud, t)
        }
        _ => {
            let clusters = match method {
                Method::Static => static_clusters(sampled),
                _ => per_bone_clusters(tree, sampled),
            };
            build_animated_cloud(
                renderer,
                tree,
                sampled,
                Rig::from_tree(tree),
                clock.clone(),
                &clusters,
                &params,
                diag,
                method.name(),
            )?
        }
    };
    let t0 = Instant::now();
    let (mut wood_lod, _achieved) = wood.simplify(level.wood_error);
    let t1 = Instant::now();
    let budget = ScreenBudget {
        pixel: level.pixel,
        epsilon: level.epsilon,
    };
    let (map, dropped) = apply_budget(&mut cloud, tree, sampled, &budget, &used_nodes(&wood_lod));
    remap(&mut wood_lod, &map);
    let t2 = Instant::now();
    let clips = cloud.playable_clips.clone();
    let dropped_clips: Vec<String> = (0..cloud.rig.clips.len())
        .filter(|c| !clips.contains(c))
        .map(|c| {
            let from = clock
                .clip
                .map(|i| tree.clips[i].name.as_str())
                .unwrap_or("-");
            let what = if cloud.rig.resampled {
                "the simplified skeleton was resampled"
            } else {
                "billboards have their own motion sampled"
            };
            format!(
                "{}: {what} from clip '{from}' only",
                cloud.rig.clips[c].name
            )
        })
        .collect();
    let vat = match req.animation {
        AnimationMode::Vat(format) => Some(vat_textures(
            &cloud,
            format,
            &format!("{name}_LOD{}_vat", k + 1),
        )?),
        _ => None,
    };
    let spectral_tex = match req.animation {
        AnimationMode::Spectral => {
            spectral_textures(&cloud, tree, &format!("{name}_LOD{}_spectral.exr", k + 1))?
        }
        _ => None,
    };
    let atlas = &cloud.atlas;
    let entry = LodEntry {
        file: String::new(),
        mapping: None,
        screen_height: Some(level.screen_height),
        pixel: Some(level.pixel),
        epsilon: Some(level.epsilon),
        method: method.name().into(),
        method_reason: reason.into(),
        triangles: wood_lod.triangles() + 2 * cloud.billboards.len(),
        wood_triangles: wood_lod.triangles(),
        billboards: cloud.billboards.len(),
        bones: 0,
        texture_bytes: atlas.color.len(),
        atlas: Some([atlas.width, atlas.height]),
        texels_per_unit: Some(cloud.texels_per_unit),
        density_reduced: cloud.density_reduced,
        clips: clips
            .iter()
            .map(|&c| cloud.rig.clips[c].name.clone())
            .collect(),
        dropped: DroppedReport {
            budget: dropped,
            wood_triangles: wood.triangles() - wood_lod.triangles().min(wood.triangles()),
            wood_error: level.wood_error,
            clips: dropped_clips,
        },
        vat: None,
        spectral_files: None,
        animation_bytes: vat
            .as_ref()
            .map(|v| v.position.bytes.len() + v.rotation.bytes.len())
            .or(spectral_tex.as_ref().map(|t| t.image.bytes.len()))
            .unwrap_or(0),
        vat_equivalent_bytes: match &spectral_tex {
            // For comparison only: a LOD VAT cannot hold (too large) just has no figure.
            Some(_) => vat_textures(&cloud, VatFormat::ExrHalf, "vat")
                .ok()
                .map(|v| v.position.bytes.len() + v.rotation.bytes.len()),
            None => None,
        },
        spectral,
        skeleton,
        timings_s: LodTimings {
            build: build_t,
            budget: (t2 - t1).as_secs_f64(),
            wood: (t1 - t0).as_secs_f64(),
            export: 0.0,
        },
    };
    Ok(BuiltLod {
        name: format!("{name}_LOD{}", k + 1),
        content: LodContent::Cloud(cloud),
        parts: vec![wood_lod],
        clips,
        vat,
        spectral: spectral_tex,
        entry,
    })
}

/// The spectral coefficient texture of a cloud (None when no billboard has own motion); an
/// error when a billboard's motion is sampled rather than spectral (the `static` method).
pub fn spectral_textures(
    cloud: &AnimatedBillboardCloud,
    tree: &Tree,
    file: &str,
) -> Result<Option<SpectralTextures>> {
    let mut rows = Vec::with_capacity(cloud.billboards.len());
    for b in &cloud.billboards {
        rows.push(match &b.motion {
            None => Vec::new(),
            Some(RigidMotion::Spectral(m)) => spectral_terms(m),
            Some(RigidMotion::Sampled(_)) => anyhow::bail!(
                "--animation spectral: method '{}' gives billboards sampled rigid motion, which \
                 has no spectral form; use a spectral method (or per-bone), or --animation \
                 skin/vat",
                cloud.method
            ),
        });
    }
    if rows.iter().all(Vec::is_empty) {
        return Ok(None);
    }
    let clip = cloud.clock.clip.map(|c| tree.clips[c].name.clone());
    Ok(Some(encode_spectral(
        &rows,
        cloud.clock.period,
        cloud.clock.start,
        clip,
        file,
    )?))
}

/// A spectral motion's terms merged by frequency over the three axes (phases in loop
/// fractions: `cos(2π f s/N + φ)` at sample `s` is `cos(2π f u + φ)` at `u = s/N`).
pub fn spectral_terms(m: &SpectralMotion) -> Vec<SpectralTerm> {
    let mut by_freq: std::collections::BTreeMap<usize, SpectralTerm> = Default::default();
    for (c, axis) in m.axes.iter().enumerate() {
        for ((&f, &a), &p) in axis
            .frequencies
            .iter()
            .zip(&axis.amplitudes)
            .zip(&axis.phases)
        {
            let t = by_freq.entry(f).or_insert(SpectralTerm {
                frequency: f as f32,
                amplitude: [0.0; 3],
                phase: [0.0; 3],
            });
            // Two terms of one frequency on one axis add as phasors.
            let (x, y) = (
                t.amplitude[c] * t.phase[c].cos() + a * p.cos(),
                t.amplitude[c] * t.phase[c].sin() + a * p.sin(),
            );
            t.amplitude[c] = x.hypot(y);
            t.phase[c] = y.atan2(x);
        }
    }
    by_freq.into_values().collect()
}

/// Vertex animation textures of every billboard over the clock's samples; textures are named
/// `<stem>_pos.<ext>` and `<stem>_rot.<ext>`.
pub fn vat_textures(
    cloud: &AnimatedBillboardCloud,
    format: VatFormat,
    stem: &str,
) -> Result<frond_export::vat::VatTextures> {
    let worlds = sampled_worlds(&cloud.rig, &cloud.clock);
    let rest_inv = cloud.rest_inverse();
    let n = worlds.len();
    let pieces: Vec<RigidPiece> = cloud
        .billboards
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let pivot = b.quad.center;
            let frames = (0..n)
                .map(|s| {
                    let carry = cloud.transform_at(i, &worlds[s], &rest_inv, s, n);
                    let (_, r, _) = carry.to_scale_rotation_translation();
                    RigidFrame {
                        position: carry.transform_point3(pivot),
                        rotation: r.normalize(),
                    }
                })
                .collect();
            RigidPiece { pivot, frames }
        })
        .collect();
    let fps = if cloud.clock.period > 0.0 {
        n as f32 / cloud.clock.period
    } else {
        1.0
    };
    Ok(encode_rigid_with(
        &pieces,
        fps,
        format,
        &VatOptions {
            file_stem: stem.to_string(),
            ..Default::default()
        },
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_spectral::description::Components;

    #[test]
    fn spectral_terms_evaluate_like_the_motion() {
        let axis = |f: Vec<usize>, a: Vec<f32>, p: Vec<f32>| Components {
            frequencies: f,
            amplitudes: a,
            phases: p,
        };
        // Two terms of frequency 2 on x (they add as phasors), one shared with y, one z only.
        let m = SpectralMotion {
            axes: [
                axis(vec![2, 2, 5], vec![0.3, 0.2, 0.1], vec![0.5, -1.0, 2.0]),
                axis(vec![5], vec![0.4], vec![-2.5]),
                axis(vec![1], vec![0.7], vec![0.0]),
            ],
            samples: 24,
        };
        let terms = spectral_terms(&m);
        let freqs: Vec<f32> = terms.iter().map(|t| t.frequency).collect();
        assert_eq!(freqs, vec![1.0, 2.0, 5.0]);
        for s in 0..24 {
            let want = m.offset(s as f32);
            let got = frond_export::spectral::evaluate(&terms, s as f32 / 24.0);
            for c in 0..3 {
                assert!((want[c] - got[c]).abs() < 1e-5, "sample {s} axis {c}");
            }
        }
    }

    #[test]
    fn method_names_round_trip() {
        for name in METHOD_NAMES {
            let m = Method::parse(name).expect("parses");
            if *name != "spectral" && *name != "skeleton" {
                assert_eq!(m.name(), *name);
            }
        }
        assert_eq!(
            Method::parse("spectral"),
            Some(Method::Spectral(DEFAULT_SPECTRAL))
        );
        assert_eq!(
            Method::parse("skeleton"),
            Some(Method::Skeleton(DEFAULT_SKELETON))
        );
        assert_eq!(Method::parse("spectral-fourier"), None);
        assert_eq!(spectral_k(60.0), 6);
        assert_eq!(spectral_k(3.0), 1);
    }
}
