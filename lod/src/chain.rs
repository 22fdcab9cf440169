//! The chain builder: a tree in, its LODs in memory out (spec animated-billboard-clouds §1.4;
//! view-dependent hierarchies §2.3–2.4 for the sizes). LOD0 is the input's own meshes over its
//! bones; every further LOD is the foliage as a method built it for the LOD's screen size, the
//! wood simplified to the LOD's error budget, and the rig pruned to what is still seen to move
//! (the motion budget). Nothing here writes a file: `frond-export` does.

use std::time::Instant;

use frond_billboard::cloud::CloudParams;
use frond_billboard::plane_search::SearchParams;
use frond_render::Renderer;
use frond_scene::wood::{NO_BONE, WoodMesh};
use frond_scene::{Length, Part, Rig, SampleOptions, Sampled, Tree, sample};

use crate::contract::{AnimatedBillboardCloud, LoopClock};
use crate::error::LodError;
use crate::method::{BuildContext, Foliage, Method, MethodReport};
use crate::motion_budget::{ScreenBudget, apply_budget};
use crate::report::{DroppedReport, LodEntry, LodTimings};
use crate::screen_budget::{LodLevel, lod_levels};

/// How the static clouds of every LOD are searched and baked (improved-billboard-cloud §2–4).
#[derive(Clone, Debug, PartialEq)]
pub struct CloudOptions {
    /// Candidate planes per iteration of the plane search.
    pub planes: usize,
    /// Lacewell's view penalty (radians of the favoured elevation), thesis §8.4.1.
    pub view_penalty: Option<f32>,
    /// Bake every triangle valid for a plane, not only its own (thesis §8.4.1).
    pub increased_density: bool,
    /// Largest atlas side.
    pub max_atlas: u32,
    /// Supersamples per texel side when baking (4 = the spec's 4×4; 2 bakes ~2.5× faster).
    pub supersample: u32,
    /// Dilated texels around each billboard's texture in the atlas.
    pub padding: u32,
}

/// What a chain is built for.
#[derive(Clone, Debug)]
pub struct ChainRequest {
    pub method: Method,
    /// Screen heights (pixels) of LOD1, LOD2, ..., nearest first.
    pub screen_heights: Vec<f32>,
    /// Pixel-error budget.
    pub pixel_error: f32,
    /// ε override for experiments (default: the pixel budget in world units).
    pub epsilon: Option<Length>,
    /// The files animate billboards with spectral coefficients (the auto rule picks spectral
    /// motion for farther LODs then).
    pub spectral_animation: bool,
    pub seed: u64,
    /// Samples over the loop.
    pub samples: usize,
    /// Clip to sample (None: the first).
    pub clip: Option<String>,
    pub cloud: CloudOptions,
}

/// What a LOD draws: LOD0 the input's rig, a billboard LOD its foliage (whose rig the
/// budget pruned).
#[derive(Clone, Debug)]
pub enum LodContent {
    Input(Rig),
    Foliage(Foliage),
}

/// One LOD of a chain, ready to write.
#[derive(Clone, Debug)]
pub struct ChainLod {
    pub content: LodContent,
    /// Skinned meshes with the tree's materials, bones as rig node indices: LOD0's wood and
    /// foliage, a billboard LOD's simplified wood.
    pub parts: Vec<WoodMesh>,
    /// Rig clips to write.
    pub clips: Vec<usize>,
    /// The report line; export fills in the files.
    pub entry: LodEntry,
}

impl ChainLod {
    /// The billboards, if the LOD has any.
    pub fn cloud(&self) -> Option<&AnimatedBillboardCloud> {
        match &self.content {
            LodContent::Foliage(Foliage::Cloud(c)) => Some(c),
            LodContent::Input(_) => None,
        }
    }
    /// The skeleton the LOD's parts and billboards refer to.
    pub fn rig(&self) -> &Rig {
        match &self.content {
            LodContent::Input(rig) => rig,
            LodContent::Foliage(Foliage::Cloud(c)) => &c.rig,
        }
    }
}

/// A built chain: LOD0 and one LOD per screen height.
pub struct Chain {
    pub sampled: Sampled,
    pub lods: Vec<ChainLod>,
    /// Seconds spent sampling the loop and building the LODs.
    pub t_sample: f64,
    pub t_build: f64,
}

/// Samples the loop of `tree` for billboards; an error when the tree has no foliage.
pub fn sample_foliage(
    tree: &Tree,
    clip: Option<&str>,
    samples: usize,
) -> Result<Sampled, LodError> {
    let sampled = sample(
        tree,
        &SampleOptions {
            clip: clip.map(str::to_string),
            samples,
        },
    )?;
    if sampled.foliage.is_empty() {
        return Err(LodError::NoFoliage(tree.source.display().to_string()));
    }
    Ok(sampled)
}

/// The LOD levels `req` asks for, sized for `tree`.
pub fn chain_levels(tree: &Tree, req: &ChainRequest) -> Result<Vec<LodLevel>, LodError> {
    let eps = req.epsilon.map(|e| e.resolve(tree.bounds.diagonal()));
    Ok(lod_levels(
        tree.height(),
        &req.screen_heights,
        req.pixel_error,
        eps,
    )?)
}

/// Builds the chain of `tree` in memory at `levels` (from [`chain_levels`], which the caller
/// needs first to name the files); `progress` hears each step. Errors name the LOD (None: the
/// loop's sampling).
pub fn build_chain(
    renderer: &Renderer,
    tree: &Tree,
    req: &ChainRequest,
    levels: &[LodLevel],
    progress: &dyn Fn(&str),
) -> Result<Chain, (Option<usize>, LodError)> {
    let t_start = Instant::now();
    progress("sampling the animation");
    let sampled = sample_foliage(tree, req.clip.as_deref(), req.samples).map_err(|e| (None, e))?;
    let t_sampled = Instant::now();
    let clock = LoopClock::of(tree, &sampled);
    let wood = part_mesh(tree, Part::Wood);
    let mut lods = vec![lod0(tree, &wood)];
    for (k, level) in levels.iter().enumerate() {
        progress(&format!(
            "LOD{}: {} px, ε = {:.4}",
            k + 1,
            level.screen_height,
            level.epsilon
        ));
        let lod = billboard_lod(renderer, tree, &sampled, &clock, &wood, req, level, k)
            .map_err(|e| (Some(k + 1), e))?;
        lods.push(lod);
    }
    let t_built = Instant::now();
    Ok(Chain {
        sampled,
        lods,
        t_sample: (t_sampled - t_start).as_secs_f64(),
        t_build: (t_built - t_sampled).as_secs_f64(),
    })
}

/// The tree's wood or foliage with bones as rig node indices.
fn part_mesh(tree: &Tree, part: Part) -> WoodMesh {
    let mut m = WoodMesh::from_tree_part(tree, part);
    for b in m.bones.iter_mut().flatten() {
        if *b != NO_BONE {
            *b = tree.bones[*b as usize].node as u32;
        }
    }
    m
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

/// An empty report line for a LOD.
fn entry(method: String, method_reason: String) -> LodEntry {
    LodEntry {
        file: String::new(),
        mapping: None,
        screen_height: None,
        pixel: None,
        epsilon: None,
        method,
        method_reason,
        triangles: 0,
        wood_triangles: 0,
        billboards: 0,
        bones: 0,
        texture_bytes: 0,
        atlas: None,
        texels_per_unit: None,
        density_reduced: false,
        clips: Vec::new(),
        dropped: DroppedReport::default(),
        vat: None,
        spectral_files: None,
        animation_bytes: 0,
        vat_equivalent_bytes: None,
        spectral: None,
        skeleton: None,
        timings_s: LodTimings::default(),
    }
}

/// LOD0: the input's wood (`wood`, bones as tree nodes) and foliage as one skinned mesh over its bones, every clip.
fn lod0(tree: &Tree, wood: &WoodMesh) -> ChainLod {
    let mut rig = tree.rig.clone();
    let mut wood = wood.clone();
    let mut foliage = part_mesh(tree, Part::Foliage);
    let mut keep = vec![false; rig.nodes.len()];
    for b in &tree.bones {
        keep[b.node] = true;
    }
    let map = rig.retain(&keep);
    remap(&mut wood, &map);
    remap(&mut foliage, &map);
    let mut e = entry("input".into(), "LOD0 is the input tree, rewritten".into());
    e.triangles = wood.triangles() + foliage.triangles();
    e.wood_triangles = wood.triangles();
    e.texture_bytes = tree.textures.iter().map(|t| t.rgba.len()).sum::<usize>();
    e.clips = rig.clips.iter().map(|c| c.name.clone()).collect();
    ChainLod {
        clips: (0..rig.clips.len()).collect(),
        content: LodContent::Input(rig),
        parts: vec![wood, foliage],
        entry: e,
    }
}

/// The static cloud parameters of LOD `k` at `level`.
fn cloud_params(req: &ChainRequest, level: &LodLevel, k: usize) -> CloudParams {
    let o = &req.cloud;
    let mut params = CloudParams {
        search: SearchParams {
            epsilon: level.epsilon,
            candidates: o.planes,
            seed: req.seed.wrapping_add(k as u64),
            view_penalty: o.view_penalty,
            ..Default::default()
        },
        increased_density: o.increased_density,
        ..Default::default()
    };
    params.bake.texels_per_unit = level.texels_per_unit;
    params.bake.max_atlas = o.max_atlas;
    // Far LODs bake sparse foliage into few texels: keep its coverage (see BakeParams).
    params.bake.preserve_coverage = true;
    params.bake.supersample = o.supersample;
    params.bake.padding = o.padding;
    params
}

/// Why a clip of a billboard LOD is not written.
fn dropped_clip_reason(cloud: &AnimatedBillboardCloud, tree: &Tree, c: usize) -> String {
    let from = cloud
        .clock
        .clip
        .map(|i| tree.rig.clips[i].name.as_str())
        .unwrap_or("-");
    let what = if cloud.rig_resampled {
        "the simplified skeleton was resampled"
    } else {
        "billboards have their own motion sampled"
    };
    format!(
        "{}: {what} from clip '{from}' only",
        cloud.rig.clips[c].name
    )
}

/// Billboard LOD `k + 1`: the method's foliage, the wood simplified, the motion budget applied.
#[expect(
    clippy::too_many_arguments,
    reason = "the chain's shared state (tree, its loop, clock, wood) and the LOD's own"
)]
fn billboard_lod(
    renderer: &Renderer,
    tree: &Tree,
    sampled: &Sampled,
    clock: &LoopClock,
    wood: &WoodMesh,
    req: &ChainRequest,
    level: &LodLevel,
    k: usize,
) -> Result<ChainLod, LodError> {
    let (method, reason) = req.method.pick(k, req.spectral_animation);
    let params = cloud_params(req, level, k);
    let ctx = BuildContext {
        renderer,
        tree,
        sampled,
        clock,
        level,
        index: k,
        cloud: &params,
        scale: tree.bounds.diagonal(),
        seed: req.seed.wrapping_add(k as u64),
    };
    let built = method.build(&ctx)?;
    let Foliage::Cloud(mut cloud) = built.foliage;
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
    let mut e = entry(method.name().name().into(), reason.into());
    e.screen_height = Some(level.screen_height);
    e.pixel = Some(level.pixel);
    e.epsilon = Some(level.epsilon);
    e.triangles = wood_lod.triangles() + 2 * cloud.billboards.len();
    e.wood_triangles = wood_lod.triangles();
    e.billboards = cloud.billboards.len();
    e.texture_bytes = cloud.atlas.color.len();
    e.atlas = Some([cloud.atlas.width, cloud.atlas.height]);
    e.texels_per_unit = Some(cloud.texels_per_unit);
    e.density_reduced = cloud.density_reduced;
    e.clips = clips
        .iter()
        .map(|&c| cloud.rig.clips[c].name.clone())
        .collect();
    e.dropped = DroppedReport {
        budget: dropped,
        wood_triangles: wood.triangles() - wood_lod.triangles().min(wood.triangles()),
        wood_error: level.wood_error,
        clips: (0..cloud.rig.clips.len())
            .filter(|c| !clips.contains(c))
            .map(|c| dropped_clip_reason(&cloud, tree, c))
            .collect(),
    };
    match built.report {
        MethodReport::None => {}
        MethodReport::Spectral(r) => e.spectral = Some(r),
        MethodReport::Skeleton(r) => e.skeleton = Some(r),
    }
    e.timings_s = LodTimings {
        build: built.timings,
        budget: (t2 - t1).as_secs_f64(),
        wood: (t1 - t0).as_secs_f64(),
        export: 0.0,
    };
    Ok(ChainLod {
        content: LodContent::Foliage(Foliage::Cloud(cloud)),
        parts: vec![wood_lod],
        clips,
        entry: e,
    })
}
