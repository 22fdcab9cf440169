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
use frond_scene::{Bounds, Length, Part, Rig, SampleOptions, Sampled, Tree, sample};

use crate::contract::{AnimatedBillboardCloud, CardFoliage, LoopClock};

pub use crate::cost_budget::{
    ATLAS_TEXELS_PER_SQUARED_PIXEL, IMPOSTOR_HEIGHT, IMPOSTOR_JOINTS, IMPOSTOR_MAX_ERROR,
    IMPOSTOR_TEXTURE_BYTES, LodBudget, MAX_JOINTS, TRIANGLES_PER_SQUARED_PIXEL, impostor_triangles,
    is_impostor_class, joints_for_screen,
};
use crate::error::LodError;
use crate::joint_budget::{AnimationCount, BillboardAnimation, JointCap, count};
use crate::method_api::{
    BuildContext, BuildTimings, Foliage, Method, MethodName, MethodSection, PickContext,
};
use crate::methods::cards::is_card_foliage;
use crate::motion_budget::{ScreenBudget, apply_budget};
use crate::part_mesh::{part_mesh, triangle_area};
use crate::report::LodEntry;
use crate::screen_budget::{LodLevel, lod_levels};
use crate::texture_budget::{ImageSizes, atlas_side_for_bytes, lod_image_sizes, parts_image_bytes};

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
    /// The rasteriser that draws the atlases.
    pub rasteriser: frond_billboard::BakeRasteriser,
    /// Impostor-class LODs (the far end) bake each texel's covered fraction as its alpha and
    /// are drawn blended (glTF `BLEND`, [`frond_billboard::BakeParams::covered_fraction`]);
    /// false: alpha-tested, their bake keeping coverage by threshold.
    pub far_blend: bool,
}

/// What a chain is built for.
#[derive(Clone, Debug)]
pub struct ChainRequest {
    /// The method that builds each LOD's foliage (or the rule that picks one per LOD).
    pub method: Method,
    /// Screen heights (pixels) of LOD1, LOD2, ..., nearest first.
    pub screen_heights: Vec<f32>,
    /// Pixel-error budget.
    pub pixel_error: f32,
    /// ε override for experiments (default: the pixel budget in world units).
    pub epsilon: Option<Length>,
    /// How the files animate billboards (spectral coefficients: the auto rule picks spectral
    /// motion for farther LODs; own motions cost joints only as skin joints).
    pub animation: BillboardAnimation,
    /// Seed of the plane searches and every random choice (each LOD adds its index).
    pub seed: u64,
    /// Most triangles a LOD keeps of the one before it (0.5: half).
    pub triangle_ratio: f32,
    /// Skin joints every LOD may keep, in place of one per 2 pixels of its height (still
    /// within the hard limits and the monotone rule); for experiments.
    pub max_joints: Option<usize>,
    /// Hold every LOD to the cost budgets (the monotone rule and the screen-size budgets);
    /// false builds each at its screen size's ε and texel density alone, for experiments,
    /// within the hard limits only.
    pub cost_budgets: bool,
    /// Samples over the loop.
    pub samples: usize,
    /// Clip to sample (None: the first).
    pub clip: Option<String>,
    /// How every LOD's static clouds are searched and baked.
    pub cloud: CloudOptions,
}

/// What a LOD draws: LOD0 the input's rig, a billboard LOD its foliage (whose rig the
/// budget pruned).
#[derive(Clone, Debug)]
pub enum LodContent {
    /// LOD0: the input's own rig, every clip (its meshes are the LOD's parts).
    Input(Rig),
    /// A built LOD's foliage, over the rig it carries.
    Foliage(Foliage),
}

/// One LOD of a chain, ready to write.
#[derive(Clone, Debug)]
pub struct ChainLod {
    /// What the LOD draws besides its parts.
    pub content: LodContent,
    /// Skinned meshes with the tree's materials, bones as rig node indices: LOD0's wood and
    /// foliage, a billboard LOD's simplified wood.
    pub parts: Vec<WoodMesh>,
    /// Rig clips to write.
    pub clips: Vec<usize>,
    /// Sizes the parts' images are written at, where smaller than the input's.
    pub image_sizes: ImageSizes,
    /// The report line; export fills in the files.
    pub entry: LodEntry,
}

impl ChainLod {
    /// The billboards, if the LOD has any.
    pub fn cloud(&self) -> Option<&AnimatedBillboardCloud> {
        match &self.content {
            LodContent::Foliage(Foliage::Cloud(c)) => Some(c),
            LodContent::Input(_) | LodContent::Foliage(Foliage::Cards(_)) => None,
        }
    }
    /// The skeleton the LOD's parts and billboards refer to.
    pub fn rig(&self) -> &Rig {
        match &self.content {
            LodContent::Input(rig) => rig,
            LodContent::Foliage(Foliage::Cloud(c)) => &c.rig,
            LodContent::Foliage(Foliage::Cards(c)) => &c.rig,
        }
    }
}

/// A built chain: LOD0 and one LOD per screen height.
pub struct Chain {
    /// The loop the chain was built from, without its poses ([`Sampled::into_loop`]).
    pub sampled: Sampled,
    /// LOD0 (the input) first, then one LOD per screen height, nearest first.
    pub lods: Vec<ChainLod>,
    /// Seconds spent sampling the loop.
    pub t_sample: f64,
    /// Seconds spent building the LODs.
    pub t_build: f64,
}

/// Samples the loop of `tree` for billboards; an error when the tree has no foliage.
pub fn sample_foliage(
    tree: &Tree,
    clip: Option<&str>,
    samples: usize,
) -> Result<Sampled, LodError> {
    sample_foliage_with(tree, clip, samples, true)
}

/// [`sample_foliage`], with the poses only when `poses` ([`frond_scene::sample_loop`]).
fn sample_foliage_with(
    tree: &Tree,
    clip: Option<&str>,
    samples: usize,
    poses: bool,
) -> Result<Sampled, LodError> {
    let options = SampleOptions {
        clip: clip.map(str::to_string),
        samples,
    };
    let sampled = if poses {
        sample(tree, &options)?
    } else {
        frond_scene::sample_loop(tree, &options)?
    };
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
    let card_foliage = is_card_foliage(tree);
    let spectral = req.animation == BillboardAnimation::Spectral;
    // The poses only when a LOD's method reads them (card chains do not: 2.4 GB on the 1M
    // preset).
    let poses = (levels.iter().enumerate()).any(|(k, level)| {
        let lod = PickContext {
            index: k,
            spectral_animation: spectral,
            card_foliage,
            screen_height: level.screen_height,
        };
        req.method.pick(&lod).0.needs_poses()
    });
    let sampled = sample_foliage_with(tree, req.clip.as_deref(), req.samples, poses)
        .map_err(|e| (None, e))?;
    let t_sampled = Instant::now();
    let clock = LoopClock::of(tree, &sampled);
    let wood = part_mesh(tree, Part::Wood);
    let lod0 = lod0(tree, &wood);
    let mut spent = Spent::of_lod0(tree, &lod0);
    let mut lods = vec![lod0];
    for (k, level) in levels.iter().enumerate() {
        progress(&format!(
            "LOD{}: {} px, ε = {:.4}",
            k + 1,
            level.screen_height,
            level.epsilon
        ));
        let budget = if req.cost_budgets {
            spent.budget_for(level, req.triangle_ratio, req.max_joints)
        } else {
            let joints = spent
                .animation
                .joints
                .min(req.max_joints.unwrap_or(usize::MAX));
            LodBudget::hard_limits_only(joints.max(1))
        };
        let lod = billboard_lod(
            renderer,
            tree,
            &sampled,
            &clock,
            &wood,
            req,
            level,
            k,
            &budget,
            card_foliage,
        )
        .map_err(|e| (Some(k + 1), e))?;
        spent = spent.after(&lod, req.animation);
        lods.push(lod);
    }
    let t_built = Instant::now();
    Ok(Chain {
        // Measuring, writing and previewing the chain need the loop alone.
        sampled: sampled.into_loop(),
        lods,
        t_sample: (t_sampled - t_start).as_secs_f64(),
        t_build: (t_built - t_sampled).as_secs_f64(),
    })
}

/// What the previous LOD cost: no later LOD may cost more in what each drawn instance pays
/// (the monotone rule); and what the input spent on what all instances of a species share,
/// texture and drawn area, which bounds every LOD's own budget.
#[derive(Clone, Copy, Debug)]
struct Spent {
    /// LOD0's share of wood in its triangles: each LOD's triangle budget is split so.
    wood_share: f64,
    /// The input's triangles: an impostor-class LOD's budget is a share of them.
    input_triangles: usize,
    triangles: usize,
    /// Decoded bytes of every texture the input draws with: no LOD's images exceed them.
    input_texture_bytes: usize,
    /// The input's alpha-tested or blended area (world units²): no LOD draws more.
    input_drawn_area: f64,
    animation: AnimationCount,
}

impl Spent {
    fn of_lod0(tree: &Tree, lod0: &ChainLod) -> Spent {
        let mut animation = meshes_count(lod0);
        // Hard limit: no engine we target skins more than 256 joints (Unreal's 8-bit indices).
        animation.joints = animation.joints.min(MAX_JOINTS);
        Spent {
            wood_share: lod0.entry.wood_triangles as f64 / lod0.entry.triangles.max(1) as f64,
            input_triangles: lod0.entry.triangles,
            triangles: lod0.entry.triangles,
            input_texture_bytes: parts_image_bytes(tree, &lod0.parts, &lod0.image_sizes),
            input_drawn_area: alpha_tested_area(tree, lod0),
            animation,
        }
    }

    /// The budget of the next LOD at `level`; `ratio` is the most triangles it may keep of
    /// this one's, `joints` the most joints in place of [`joints_for_screen`]'s.
    fn budget_for(&self, level: &LodLevel, ratio: f32, joints: Option<usize>) -> LodBudget {
        let h = level.screen_height;
        let triangles = (((self.triangles as f64) * f64::from(ratio.clamp(0.0, 1.0))).floor()
            as usize)
            .min((TRIANGLES_PER_SQUARED_PIXEL * h * h) as usize);
        let texels = (ATLAS_TEXELS_PER_SQUARED_PIXEL * h * h) as usize;
        let mut budget = LodBudget {
            triangles,
            wood_triangles: (triangles as f64 * self.wood_share).floor() as usize,
            joints: self
                .animation
                .joints
                .min(joints.unwrap_or_else(|| joints_for_screen(h))),
            channels: self.animation.channels,
            texture_bytes: self.input_texture_bytes.min(4 * texels),
            alpha_tested_area: self.input_drawn_area,
        };
        if is_impostor_class(h) {
            budget.triangles = budget
                .triangles
                .min(impostor_triangles(self.input_triangles));
            budget.wood_triangles = (budget.triangles as f64 * self.wood_share).floor() as usize;
            budget.joints = budget.joints.min(IMPOSTOR_JOINTS);
            // The far end's own texture budget: its texels hold covered fractions at two a
            // pixel, more than 16 per H² would give.
            budget.texture_bytes = self.input_texture_bytes.min(IMPOSTOR_TEXTURE_BYTES);
        }
        budget
    }

    /// What has been spent once `lod` is built.
    fn after(&self, lod: &ChainLod, animation: BillboardAnimation) -> Spent {
        let mut next = Spent {
            wood_share: self.wood_share,
            input_triangles: self.input_triangles,
            triangles: lod.entry.triangles,
            input_texture_bytes: self.input_texture_bytes,
            input_drawn_area: self.input_drawn_area,
            animation: self.animation,
        };
        let n = match (lod.cloud(), lod.parts.first()) {
            (Some(c), Some(wood)) => count(c, wood, animation),
            _ => meshes_count(lod),
        };
        next.animation = AnimationCount {
            joints: self.animation.joints.min(n.joints),
            channels: self.animation.channels.min(n.channels),
        };
        next
    }
}

/// A LOD's alpha-tested area (world units², rest pose): its parts' triangles whose material
/// is alpha-tested or blended, and its billboards' quads (always alpha-tested), as
/// `frond_scene::file_cost` counts the written file's.
fn alpha_tested_area(tree: &Tree, lod: &ChainLod) -> f64 {
    let parts: f64 = lod
        .parts
        .iter()
        .flat_map(|m| m.primitives.iter().enumerate().map(move |(i, p)| (m, i, p)))
        .filter(|(_, _, p)| {
            tree.materials
                .get(p.material)
                .is_some_and(|m| m.alpha_mode != frond_scene::AlphaMode::Opaque)
        })
        .flat_map(|(m, i, p)| {
            (0..p.indices.len() / 3).map(move |t| f64::from(triangle_area(m, i, t)))
        })
        .sum();
    let quads: f64 = lod.cloud().map_or(0.0, |c| {
        c.billboards.iter().map(|b| f64::from(b.quad.area())).sum()
    });
    parts + quads
}

/// Joints and channels of a LOD drawn with meshes alone (LOD0, a card LOD): one joint per rig
/// node a vertex follows (and the static joint when a vertex follows none), every clip's
/// channels on the nodes kept.
fn meshes_count(lod0: &ChainLod) -> AnimationCount {
    let rig = lod0.rig();
    let mut joint = vec![false; rig.nodes.len()];
    let mut static_joint = false;
    for p in &lod0.parts {
        for b in p.used_bones() {
            match joint.get_mut(b as usize) {
                Some(j) if b != NO_BONE => *j = true,
                _ => static_joint = true,
            }
        }
    }
    AnimationCount {
        joints: joint.iter().filter(|&&j| j).count() + usize::from(static_joint),
        channels: rig.clips.iter().map(|c| c.channels.len()).sum(),
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
    let mut e = LodEntry::new(MethodName::INPUT, "LOD0 is the input tree, rewritten");
    e.triangles = wood.triangles() + foliage.triangles();
    e.wood_triangles = wood.triangles();
    let parts = vec![wood, foliage];
    e.texture_bytes = parts_image_bytes(tree, &parts, &ImageSizes::new());
    e.clips = rig.clips.iter().map(|c| c.name.clone()).collect();
    ChainLod {
        clips: (0..rig.clips.len()).collect(),
        content: LodContent::Input(rig),
        parts,
        image_sizes: ImageSizes::new(),
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
    // Far LODs bake sparse foliage into few texels: keep its coverage (see BakeParams), as
    // covered fractions drawn blended at the far end where asked.
    params.bake.preserve_coverage = true;
    params.bake.covered_fraction = o.far_blend && is_impostor_class(level.screen_height);
    params.bake.supersample = o.supersample;
    params.bake.padding = o.padding;
    params.bake.rasteriser = o.rasteriser;
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

/// Atlas texels a billboard needs at least: an 8×8 texture with 2 texels of padding around
/// it (144) less what packing shares (the rule keeps a far LOD's atlas from being nothing but
/// padding).
const TEXELS_PER_BILLBOARD: usize = 128;

/// Padding (texels) around an impostor-class LOD's billboard textures: its billboards are a
/// few pixels across, read at the atlas's top level, where one texel keeps bilinear filtering
/// inside each texture.
const IMPOSTOR_PADDING: u32 = 1;

/// Atlas texels an impostor-class billboard needs at least: a 4×4 texture (a billboard a few
/// pixels across at that size) with [`IMPOSTOR_PADDING`] around it. The far end's texture
/// budget is a few thousand texels, which a larger floor would spend on padding.
const IMPOSTOR_TEXELS_PER_BILLBOARD: usize = 36;

/// Steps of a doubling wood error tried before the wood is left over its share.
const WOOD_TRIES: usize = 16;

/// `wood` simplified within `max_error`, then with a doubling error while it has more than
/// `max_triangles`. Returns the mesh and the error it was simplified with.
fn simplify_wood(wood: &WoodMesh, max_error: f32, max_triangles: usize) -> (WoodMesh, f32) {
    let mut error = max_error;
    let (mut mesh, _) = wood.simplify(error);
    let diagonal = Bounds::of(wood.positions.iter().copied()).diagonal();
    for _ in 0..WOOD_TRIES {
        if mesh.triangles() <= max_triangles || diagonal.is_nan() || diagonal <= 0.0 {
            break;
        }
        error = (error.max(1e-4 * diagonal) * 2.0).min(diagonal);
        mesh = wood.simplify(error).0;
    }
    (mesh, error)
}

/// Times [`wood_within`] doubles the thickness under which branches go.
const THIN_TRIES: usize = 4;

/// A LOD's wood: the mesh, the error it was simplified with, how many branches were dropped,
/// and the width under which they were.
struct WoodLod {
    mesh: WoodMesh,
    error: f32,
    thin_pieces: usize,
    min_width: f32,
}

/// The wood within `max_triangles`: branches narrower than `min_width` (half a pixel, where
/// narrower a branch covers under half the pixels it crosses) dropped and the rest simplified
/// within `error` to fit ([`simplify_wood`]); where simplifying cannot reach the budget (every
/// branch keeps a few triangles however coarse), the thinnest branches go next, the width
/// doubled up to [`THIN_TRIES`] times: a LOD keeps its trunk and limbs and its foliage keeps
/// its cards or billboards (taking triangles from them for thin branches cost more coverage
/// than it kept: docs/experiments.md).
fn wood_within(wood: &WoodMesh, min_width: f32, error: f32, max_triangles: usize) -> WoodLod {
    let mut thickness = min_width;
    let mut doublings = 0;
    loop {
        let (kept, thin) = wood.without_thin_pieces(thickness);
        let (mesh, e) = simplify_wood(&kept, error, max_triangles);
        let fits = mesh.triangles() <= max_triangles;
        if doublings == THIN_TRIES || fits || kept.triangles() == 0 {
            return WoodLod {
                mesh,
                error: e,
                thin_pieces: thin,
                min_width: thickness,
            };
        }
        thickness *= 2.0;
        doublings += 1;
    }
}

/// How much finer than one pixel the wood may be refined into triangles the foliage left.
const WOOD_REFINE_FLOOR: f32 = 8.0;

/// Bisection steps of [`refine_wood`]'s error.
const WOOD_REFINE_STEPS: usize = 6;

/// `wood` at the finest error between `floor` and `current`'s that fits in `max_triangles`,
/// found by bisection of the error's logarithm; branches narrower than the error are
/// re-admitted (unless `keep_width`: a far end whose billboards hold its thin branches
/// already), and none wider than `current`'s width goes (a far LOD's half-pixel trunk stays,
/// though it is narrower than the wood's error). A near LOD whose cards need fewer triangles
/// than it may draw spends them on its branches.
fn refine_wood(
    wood: &WoodMesh,
    current: WoodLod,
    floor: f32,
    max_triangles: usize,
    keep_width: bool,
) -> WoodLod {
    let mut best = current;
    if best.mesh.triangles() > max_triangles || !(floor > 0.0 && best.error > floor) {
        return best;
    }
    let min_width = best.min_width;
    let at = |error: f32| {
        let width = if keep_width {
            min_width
        } else {
            error.min(min_width)
        };
        let (kept, thin) = wood.without_thin_pieces(width);
        WoodLod {
            mesh: kept.simplify(error).0,
            error,
            thin_pieces: thin,
            min_width: width,
        }
    };
    // The floor first: often everything fits.
    let finest = at(floor);
    if finest.mesh.triangles() <= max_triangles {
        return finest;
    }
    let (mut lo, mut hi) = (floor.ln(), best.error.ln());
    for _ in 0..WOOD_REFINE_STEPS {
        let tried = at((0.5 * (lo + hi)).exp());
        if tried.mesh.triangles() <= max_triangles {
            hi = tried.error.ln();
            best = tried;
        } else {
            lo = tried.error.ln();
        }
    }
    best
}

/// Billboard LOD `k + 1`: the wood simplified to its share of the budget, the method's
/// foliage within the rest, the motion budget applied within its joints and channels.
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
    lod_budget: &LodBudget,
    card_foliage: bool,
) -> Result<ChainLod, LodError> {
    let (method, reason) = req.method.pick(&PickContext {
        index: k,
        spectral_animation: req.animation == BillboardAnimation::Spectral,
        card_foliage,
        screen_height: level.screen_height,
    });
    let t0 = Instant::now();
    // Branches too thin to see go first; what is left is simplified to its share. Triangles the
    // wood does not need go to the foliage. A branch half a pixel wide still covers half the
    // pixels it crosses: every branch stays while at least half a pixel wide (the trunk of a
    // slender tree is no wider than a pixel or two at 60 px).
    let impostor = is_impostor_class(level.screen_height);
    let min_width = 0.5 * level.pixel;
    let wood_lod = wood_within(wood, min_width, level.wood_error, lod_budget.wood_triangles);
    let t1 = Instant::now();
    let wood_sizes = lod_image_sizes(
        tree,
        std::slice::from_ref(&wood_lod.mesh),
        Some(wood),
        level.texels_per_unit,
    );
    let wood_texture_bytes =
        parts_image_bytes(tree, std::slice::from_ref(&wood_lod.mesh), &wood_sizes);
    let mut params = cloud_params(req, level, k);
    let atlas_bytes = lod_budget.texture_bytes.saturating_sub(wood_texture_bytes);
    params.bake.max_atlas = params.bake.max_atlas.min(atlas_side_for_bytes(atlas_bytes));
    let texels_per_billboard = if impostor {
        params.bake.padding = params.bake.padding.min(IMPOSTOR_PADDING);
        IMPOSTOR_TEXELS_PER_BILLBOARD
    } else {
        TEXELS_PER_BILLBOARD
    };
    // Two triangles per billboard, and room in the atlas for each (a small texture, padded).
    let foliage_room = lod_budget
        .triangles
        .saturating_sub(wood_lod.mesh.triangles());
    let max_billboards = (foliage_room / 2).min(atlas_bytes / 4 / texels_per_billboard);
    tracing::debug!(
        "LOD{}: wood {} triangles ({} B of texture), at most {max_billboards} billboards",
        k + 1,
        wood_lod.mesh.triangles(),
        wood_texture_bytes
    );
    // The far end's branches under half a pixel (or past the wood's share): baked into its
    // billboards as the covered fraction they add, so none vanishes and none turns solid.
    let baked_wood = impostor
        .then(|| wood.split_thin_pieces(wood_lod.min_width).thin)
        .filter(|thin| thin.triangles() > 0);
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
        max_billboards: Some(max_billboards.max(1)),
        max_foliage_triangles: Some(foliage_room),
        max_alpha_tested_area: Some(lod_budget.alpha_tested_area),
        max_joints: Some(lod_budget.joints),
        baked_wood: baked_wood.as_ref(),
    };
    let built = method.build(&ctx)?;
    // Only a billboard cloud draws the thin wood; cards leave it dropped.
    let wood_baked = ctx.baked_wood.is_some() && matches!(built.foliage, Foliage::Cloud(_));
    // Triangles the foliage left unused go back to the wood, as a finer wood error.
    let foliage_triangles = match &built.foliage {
        Foliage::Cards(cards) => cards.mesh.triangles(),
        Foliage::Cloud(cloud) => 2 * cloud.billboards.len(),
    };
    let room = lod_budget.triangles.saturating_sub(foliage_triangles);
    let t2 = Instant::now();
    let WoodLod {
        mesh: wood_lod,
        error: wood_error,
        thin_pieces,
        ..
    } = refine_wood(
        wood,
        wood_lod,
        level.wood_error / WOOD_REFINE_FLOOR,
        room,
        wood_baked,
    );
    let mut e = LodEntry::new(method.name(), reason);
    e.screen_height = Some(level.screen_height);
    e.pixel = Some(level.pixel);
    e.epsilon = Some(level.epsilon);
    e.budget = Some(*lod_budget);
    // Simplifying the wood, and refining it into the room the foliage left.
    e.timings_s.wood = (t1 - t0 + t2.elapsed()).as_secs_f64();
    e.dropped.wood_triangles = wood.triangles() - wood_lod.triangles().min(wood.triangles());
    e.dropped.wood_error = wood_error;
    if wood_baked {
        e.dropped.wood_pieces_baked = thin_pieces;
    } else {
        e.dropped.wood_pieces = thin_pieces;
    }
    let budget = ScreenBudget {
        pixel: level.pixel,
        epsilon: level.epsilon,
        joints: JointCap {
            joints: lod_budget.joints,
            channels: lod_budget.channels,
        },
        keep_sub_pixel_motion: impostor,
    };
    let shared = LodShared {
        tree,
        wood,
        level,
        sampled,
        clock,
        animation: req.animation,
    };
    match built.foliage {
        Foliage::Cloud(cloud) => Ok(cloud_lod(
            &shared,
            cloud,
            wood_lod,
            budget,
            built.timings,
            built.section,
            e,
        )),
        Foliage::Cards(cards) => Ok(card_lod(
            &shared,
            cards,
            wood_lod,
            (&budget, lod_budget.texture_bytes),
            built.section,
            e,
        )),
    }
}

/// What every LOD of a chain shares.
struct LodShared<'a> {
    tree: &'a Tree,
    /// The input's wood, whose bark density sizes every LOD's bark maps.
    wood: &'a WoodMesh,
    level: &'a LodLevel,
    sampled: &'a Sampled,
    clock: &'a LoopClock,
    animation: BillboardAnimation,
}

/// Halvings of a card LOD's texel density [`card_images_within`] tries.
const CARD_DENSITY_HALVINGS: usize = 8;

/// The sizes of `mesh`'s images at the LOD's texel density, halved while they decode to more
/// than `max_bytes` (the LOD's texture budget), and the bytes they decode to.
fn card_images_within(
    shared: &LodShared,
    mesh: &WoodMesh,
    max_bytes: usize,
) -> (ImageSizes, usize) {
    let parts = std::slice::from_ref(mesh);
    let mut density = shared.level.texels_per_unit;
    let mut sizes = lod_image_sizes(shared.tree, parts, Some(shared.wood), density);
    let mut bytes = parts_image_bytes(shared.tree, parts, &sizes);
    for _ in 0..CARD_DENSITY_HALVINGS {
        if bytes <= max_bytes {
            break;
        }
        density *= 0.5;
        sizes = lod_image_sizes(shared.tree, parts, Some(shared.wood), density);
        bytes = parts_image_bytes(shared.tree, parts, &sizes);
    }
    (sizes, bytes)
}

/// A card LOD: the thinned cards and the wood in one skinned mesh, the joint budget applied.
fn card_lod(
    shared: &LodShared,
    mut cards: CardFoliage,
    wood_lod: WoodMesh,
    (budget, texture_bytes): (&ScreenBudget, usize),
    section: Option<MethodSection>,
    mut e: LodEntry,
) -> ChainLod {
    let t0 = Instant::now();
    let wood_triangles = wood_lod.triangles();
    let mut mesh = wood_lod;
    mesh.append(&cards.mesh);
    // The budget works on a cloud: one without billboards carries the rig and the clock.
    let mut carrier = AnimatedBillboardCloud {
        method: "cards".into(),
        epsilon: budget.epsilon,
        billboards: Vec::new(),
        atlas: Default::default(),
        texels_per_unit: 0.0,
        density_reduced: false,
        rig: std::mem::take(&mut cards.rig),
        rig_resampled: false,
        clock: shared.clock.clone(),
        playable_clips: Vec::new(),
    };
    carrier.update_playable_clips();
    let dropped = apply_budget(
        &mut carrier,
        &mut mesh,
        shared.tree,
        shared.sampled,
        budget,
        shared.animation,
    );
    cards.rig = carrier.rig;
    let clips = carrier.playable_clips;
    e.triangles = mesh.triangles();
    e.wood_triangles = wood_triangles;
    let (image_sizes, bytes) = card_images_within(shared, &mesh, texture_bytes);
    e.texture_bytes = bytes;
    e.clips = clips
        .iter()
        .map(|&c| cards.rig.clips[c].name.clone())
        .collect();
    e.dropped.budget = dropped;
    e.sections.extend(section);
    e.timings_s.budget = t0.elapsed().as_secs_f64();
    ChainLod {
        content: LodContent::Foliage(Foliage::Cards(cards)),
        parts: vec![mesh],
        clips,
        image_sizes,
        entry: e,
    }
}

/// A billboard LOD: the method's cloud with the motion budget applied, and the wood.
fn cloud_lod(
    shared: &LodShared,
    mut cloud: AnimatedBillboardCloud,
    mut wood_lod: WoodMesh,
    mut budget: ScreenBudget,
    timings: BuildTimings,
    section: Option<MethodSection>,
    mut e: LodEntry,
) -> ChainLod {
    let (tree, sampled) = (shared.tree, shared.sampled);
    let t2 = Instant::now();
    budget.epsilon = cloud.epsilon;
    let dropped = apply_budget(
        &mut cloud,
        &mut wood_lod,
        tree,
        sampled,
        &budget,
        shared.animation,
    );
    let t3 = Instant::now();
    let clips = cloud.playable_clips.clone();
    // The wood and the billboards that copy input cards draw with the input's images.
    let input_textured = [wood_lod.clone(), cloud.input_textured_mesh()];
    let image_sizes = lod_image_sizes(
        tree,
        &input_textured,
        Some(shared.wood),
        shared.level.texels_per_unit,
    );
    e.epsilon = Some(cloud.epsilon);
    e.triangles = wood_lod.triangles() + 2 * cloud.billboards.len();
    e.wood_triangles = wood_lod.triangles();
    e.billboards = cloud.billboards.len();
    e.input_textured_billboards = cloud.input_textured();
    e.texture_bytes =
        cloud.atlas.color.len() + parts_image_bytes(tree, &input_textured, &image_sizes);
    e.atlas = (cloud.atlas.width > 0).then_some([cloud.atlas.width, cloud.atlas.height]);
    e.texels_per_unit = Some(cloud.texels_per_unit);
    e.density_reduced = cloud.density_reduced;
    e.clips = clips
        .iter()
        .map(|&c| cloud.rig.clips[c].name.clone())
        .collect();
    e.dropped.budget = dropped;
    e.dropped.clips = (0..cloud.rig.clips.len())
        .filter(|c| !clips.contains(c))
        .map(|c| dropped_clip_reason(&cloud, tree, c))
        .collect();
    e.sections.extend(section);
    e.timings_s.build = timings;
    e.timings_s.budget = (t3 - t2).as_secs_f64();
    ChainLod {
        content: LodContent::Foliage(Foliage::Cloud(cloud)),
        parts: vec![wood_lod],
        clips,
        image_sizes,
        entry: e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::{ImportOptions, import};

    #[test]
    fn the_wood_is_refined_into_the_room_left_and_no_further() {
        let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
        let wood = WoodMesh::from_tree(&tree);
        let coarse = 0.01 * tree.height();
        let (kept, thin) = wood.without_thin_pieces(coarse);
        let (mesh, _) = kept.simplify(coarse);
        let start = mesh.triangles();
        assert!(start < wood.triangles());
        // Room for half again as many triangles: a finer error, within the room.
        let room = start + start / 2;
        let at_coarse = |mesh: WoodMesh| WoodLod {
            mesh,
            error: coarse,
            thin_pieces: thin,
            min_width: coarse,
        };
        let refined = refine_wood(&wood, at_coarse(mesh.clone()), coarse / 64.0, room, false);
        assert!(refined.error < coarse, "{}", refined.error);
        assert!(refined.mesh.triangles() > start && refined.mesh.triangles() <= room);
        // No room: unchanged.
        let same = refine_wood(&wood, at_coarse(mesh), coarse / 64.0, start, false);
        assert_eq!((same.mesh.triangles(), same.error), (start, coarse));
        // Room for everything: the floor.
        let finest = refine_wood(
            &wood,
            at_coarse(kept.simplify(coarse).0),
            coarse / 64.0,
            usize::MAX,
            false,
        )
        .error;
        assert_eq!(finest, coarse / 64.0);
    }

    #[test]
    fn refining_keeps_the_branches_a_far_lod_kept() {
        // The sample seen 20 px tall: branches half a pixel wide stay, though the wood's error
        // is a pixel; refining into a little room must not trade them for nothing.
        let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
        let wood = WoodMesh::from_tree(&tree);
        let pixel = tree.height() / 20.0;
        let far = wood_within(&wood, 0.5 * pixel, pixel, 64);
        let kept = far.mesh.pieces().len();
        assert!(kept > 0 && far.mesh.triangles() <= 64, "{kept} pieces");
        let thinner_than_error = wood.without_thin_pieces(pixel).0.pieces().len();
        assert!(
            kept > thinner_than_error,
            "{kept} pieces, {thinner_than_error} a pixel wide"
        );
        for room in [
            far.mesh.triangles(),
            far.mesh.triangles() + 8,
            4 * far.mesh.triangles(),
        ] {
            let start = WoodLod {
                mesh: far.mesh.clone(),
                ..far
            };
            let refined = refine_wood(&wood, start, pixel / WOOD_REFINE_FLOOR, room, false);
            assert!(refined.mesh.triangles() <= room.max(far.mesh.triangles()));
            assert!(
                refined.mesh.pieces().len() >= kept,
                "room {room}: {} pieces of {kept}",
                refined.mesh.pieces().len()
            );
        }
    }
}
