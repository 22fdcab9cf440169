//! Clustering methods behind one trait (spec animated-billboard-clouds §3 "per-bone", §4
//! spectral clustering SCA, §6 skeleton simplification SBCS; thesis §5.2.2 for `static`).
//!
//! A method is a type carrying its own options ([`SpectralOptions`], [`SkeletonOptions`], ...)
//! that implements [`ClusteringMethod`]: given one LOD's [`BuildContext`] (the tree, its sampled
//! loop, the LOD's screen size and error budget, the static cloud's parameters) it returns the
//! LOD's foliage as a [`Foliage`] representation. [`Method`] is the closed list of methods the
//! chain builder can run, [`MethodName`] their names on the command line and in reports.
//!
//! Adding a method: a type in `methods/<name>.rs` implementing [`ClusteringMethod`], a variant
//! of [`Method`] and of [`MethodName`] with its entry in [`METHOD_NAMES`].

use frond_billboard::cloud::CloudParams;
use frond_render::Renderer;
use frond_scene::{Length, Sampled, Tree};
use frond_skeleton::{BoneDescriptionKind, SkeletonReport};
use frond_spectral::description::SpectralKind;

use crate::cloud_build::BuildTimings;
use crate::contract::{AnimatedBillboardCloud, LoopClock};
use crate::error::LodError;
use crate::methods::cards::Cards;
use crate::methods::per_bone::PerBone;
use crate::methods::static_cloud::StaticCloud;
use crate::screen_budget::LodLevel;

/// Everything one LOD's build reads, shared by every method.
pub struct BuildContext<'a> {
    /// Renders the bake.
    pub renderer: &'a Renderer,
    pub tree: &'a Tree,
    /// The tree's loop, sampled (foliage trajectories).
    pub sampled: &'a Sampled,
    /// The samples' clip, start and period.
    pub clock: &'a LoopClock,
    /// The LOD's screen height and what it may spend: pixel size, ε, texel density, wood error.
    pub level: &'a LodLevel,
    /// 0 for LOD1, the nearest billboard LOD.
    pub index: usize,
    /// Plane search and bake parameters of this LOD's static clouds (ε, texel density, seed).
    pub cloud: &'a CloudParams,
    /// The rest-pose bounding-box diagonal: sizes float tolerances and relative lengths.
    pub scale: f32,
    /// This LOD's seed (the run's seed plus the LOD index).
    pub seed: u64,
    /// Most billboards the LOD may have (its triangle budget less the wood's, halved): the
    /// plane search widens ε until its planes fit ([`crate::cloud_build`]).
    pub max_billboards: Option<usize>,
    /// Most foliage triangles the LOD may have (its triangle budget less the wood's).
    pub max_foliage_triangles: Option<usize>,
    /// Most alpha-tested area (world units²) the LOD's foliage may have: the previous LOD's
    /// (the monotone rule on overdraw). Card LODs grow their survivors within it.
    pub max_alpha_tested_area: Option<f64>,
}

/// A LOD's foliage as a method built it. Today every method bakes an animated billboard cloud;
/// representations that keep some of the input's own cards come as further variants, and
/// export writes whichever it gets.
#[derive(Clone, Debug)]
pub enum Foliage {
    /// Billboards baked into one atlas, each moving rigidly (spec §1.4).
    Cloud(AnimatedBillboardCloud),
    /// The input's own leaf cards, thinned and skinned as in the input.
    Cards(crate::methods::cards::CardFoliage),
}

/// What the method did, for the report.
#[derive(Clone, Debug, Default)]
pub enum MethodReport {
    #[default]
    None,
    Spectral(crate::methods::spectral::SpectralReport),
    Skeleton(SkeletonReport),
}

/// One method's result for one LOD.
pub struct MethodOutput {
    pub foliage: Foliage,
    pub timings: BuildTimings,
    pub report: MethodReport,
}

/// A way to cluster a tree's foliage into animated billboards for one LOD.
pub trait ClusteringMethod: Sync {
    /// The method's name in reports (with its description type: `spectral-axis-phase`).
    fn name(&self) -> MethodName;
    /// Builds the LOD's foliage within the context's budget.
    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError>;
    /// Whether [`ClusteringMethod::build`] reads the sampled poses, trajectories or average
    /// pose ([`frond_scene::Sampled::positions`]); a chain whose methods do not samples the
    /// loop without them.
    fn needs_poses(&self) -> bool {
        true
    }
}

/// Options of spectral clustering (SCA, spec §4.11–4.14).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralOptions {
    /// Description type (§4.4–4.8).
    pub kind: SpectralKind,
    /// Animation clusters per LOD (None: [`crate::spectral_k`] of the LOD's screen height).
    pub clusters: Option<usize>,
    /// Animation zone size (None: [`crate::DEFAULT_ZONE_FRACTION`] of the diagonal or the
    /// LOD's ε, the larger).
    pub zone_size: Option<Length>,
    /// Bind billboards to their triangles' deepest shared bone (§4.12).
    pub shared_bone: bool,
}

impl Default for SpectralOptions {
    fn default() -> Self {
        SpectralOptions {
            kind: crate::DEFAULT_SPECTRAL,
            clusters: None,
            zone_size: None,
            shared_bone: true,
        }
    }
}

/// Options of skeleton simplification (SBCS, spec §6).
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonOptions {
    /// Bone description type (§6.2).
    pub kind: BoneDescriptionKind,
    /// Billboard clouds per LOD (None: as few as merges no eye can see at the LOD's size
    /// allow: at most a pixel of foliage motion, half a pixel off a branch).
    pub clouds: Option<usize>,
    /// The average-animation-bone improvement (§6.1, thesis §7.1.2).
    pub average_bone: bool,
}

impl Default for SkeletonOptions {
    fn default() -> Self {
        SkeletonOptions {
            kind: crate::DEFAULT_SKELETON,
            clouds: None,
            average_bone: false,
        }
    }
}

/// The methods the chain builder runs, each with its options.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// The documented rule of [`auto_method`], with the options of the methods it may pick.
    Auto {
        spectral: SpectralOptions,
        skeleton: SkeletonOptions,
    },
    PerBone(PerBone),
    Static(StaticCloud),
    Spectral(SpectralOptions),
    Skeleton(SkeletonOptions),
    Cards(Cards),
}

impl Method {
    /// The method named `name`, with the given options for the spectral and skeleton methods
    /// (their description type comes from the name). Options of a method the name does not
    /// run are dropped; [`ignored_options`] says which, for a warning.
    pub fn new(name: MethodName, spectral: SpectralOptions, skeleton: SkeletonOptions) -> Method {
        match name {
            MethodName::Auto => Method::Auto { spectral, skeleton },
            MethodName::Spectral(kind) => Method::Spectral(SpectralOptions { kind, ..spectral }),
            MethodName::Skeleton(kind) => Method::Skeleton(SkeletonOptions { kind, ..skeleton }),
            MethodName::PerBone => Method::PerBone(PerBone),
            MethodName::Static => Method::Static(StaticCloud),
            MethodName::Cards => Method::Cards(Cards),
        }
    }

    /// The name the method was asked by (`auto` for the rule).
    pub fn name(&self) -> MethodName {
        match self {
            Method::Auto { .. } => MethodName::Auto,
            Method::PerBone(m) => m.name(),
            Method::Static(m) => m.name(),
            Method::Spectral(m) => m.name(),
            Method::Skeleton(m) => m.name(),
            Method::Cards(m) => m.name(),
        }
    }

    /// The method that builds LOD `lod_index` (0 = LOD1) and why: itself, or what the auto
    /// rule picks. `spectral_animation`: the files animate with spectral coefficients;
    /// `card_foliage`: the tree's foliage is single leaf cards
    /// ([`crate::methods::cards::is_card_foliage`]).
    pub fn pick(
        &self,
        lod_index: usize,
        spectral_animation: bool,
        card_foliage: bool,
    ) -> (&dyn ClusteringMethod, &'static str) {
        match self {
            Method::Auto { spectral, skeleton } => {
                let (name, reason) = auto_method(lod_index, spectral_animation, card_foliage);
                let m: &dyn ClusteringMethod = match name {
                    MethodName::Skeleton(_) => skeleton,
                    MethodName::Spectral(_) => spectral,
                    MethodName::Cards => &Cards,
                    _ => &StaticCloud,
                };
                (m, reason)
            }
            Method::PerBone(m) => (m, GIVEN),
            Method::Static(m) => (m, GIVEN),
            Method::Spectral(m) => (m, GIVEN),
            Method::Skeleton(m) => (m, GIVEN),
            Method::Cards(m) => (m, GIVEN),
        }
    }
}

const GIVEN: &str = "given with --method";

/// Warnings for options given to a method that does not use them: spectral options
/// (`spectral_given`) act on spectral methods, and on `auto` only when it may pick one (with
/// spectral animation); skeleton options (`skeleton_given`) act on skeleton methods (`auto`
/// uses them for its nearest LOD, but they are not what `auto` is for).
pub fn ignored_options(
    name: MethodName,
    spectral_given: bool,
    skeleton_given: bool,
    spectral_animation: bool,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let may_be_spectral =
        matches!(name, MethodName::Spectral(_)) || (name == MethodName::Auto && spectral_animation);
    if spectral_given && !may_be_spectral {
        warnings.push(format!(
            "--clusters, --zone-size and --no-shared-bone act on spectral methods only; \
             method '{}' ignores them",
            name.name()
        ));
    }
    if skeleton_given && !matches!(name, MethodName::Skeleton(_)) {
        warnings.push(format!(
            "--clouds and --average-bone act on skeleton methods only; method '{}' ignores them",
            name.name()
        ));
    }
    warnings
}

/// A method's name: what `--method` takes and the report's `method` field writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodName {
    /// The documented rule of [`auto_method`].
    Auto,
    PerBone,
    Static,
    /// The input's own cards, thinned (not a clustering: no billboards).
    Cards,
    /// Spectral clustering (SCA) with one description type.
    Spectral(SpectralKind),
    /// Skeleton simplification (SBCS) with one bone description type.
    Skeleton(BoneDescriptionKind),
}

/// Every name `--method` takes, with what it names (`spectral` and `skeleton` alone name the
/// default description types).
pub const METHOD_NAMES: &[(&str, MethodName)] = &[
    ("auto", MethodName::Auto),
    ("per-bone", MethodName::PerBone),
    ("static", MethodName::Static),
    ("cards", MethodName::Cards),
    ("spectral", MethodName::Spectral(crate::DEFAULT_SPECTRAL)),
    ("spectral-naive", MethodName::Spectral(SpectralKind::Naive)),
    (
        "spectral-dominating-axis",
        MethodName::Spectral(SpectralKind::DominatingAxis),
    ),
    (
        "spectral-axis-phase",
        MethodName::Spectral(SpectralKind::AxisPhase),
    ),
    ("skeleton", MethodName::Skeleton(crate::DEFAULT_SKELETON)),
    (
        "skeleton-axis-angle",
        MethodName::Skeleton(BoneDescriptionKind::AxisAngle),
    ),
    (
        "skeleton-rotation-spectral",
        MethodName::Skeleton(BoneDescriptionKind::RotationSpectral),
    ),
];

impl MethodName {
    /// Parses a name of [`METHOD_NAMES`].
    pub fn parse(s: &str) -> Option<MethodName> {
        METHOD_NAMES.iter().find(|(n, _)| *n == s).map(|(_, m)| *m)
    }
    /// The full name (spectral and skeleton methods with their type).
    pub fn name(self) -> &'static str {
        match self {
            MethodName::Auto => "auto",
            MethodName::PerBone => "per-bone",
            MethodName::Static => "static",
            MethodName::Cards => "cards",
            MethodName::Spectral(SpectralKind::Naive) => "spectral-naive",
            MethodName::Spectral(SpectralKind::DominatingAxis) => "spectral-dominating-axis",
            MethodName::Spectral(SpectralKind::AxisPhase) => "spectral-axis-phase",
            MethodName::Skeleton(BoneDescriptionKind::AxisAngle) => "skeleton-axis-angle",
            MethodName::Skeleton(BoneDescriptionKind::RotationSpectral) => {
                "skeleton-rotation-spectral"
            }
        }
    }
}

/// The fixed rule of `--method auto`. A tree whose foliage is single leaf cards gets `cards`
/// at every LOD (issue 17: the input's own cards, thinned to the LOD's triangle budget, on its
/// leaf texture downscaled to the LOD's texel density). Measured with the cost budgets on
/// (`frond lod TREE --method M`, `frond eval TREE LODk --screen-height H`, coverage error
/// at 600/200/60 px): sapling cards 0.15/0.24/0.29 against billboards (skeleton, static)
/// 0.27/0.23/0.83; oak_dense cards 0.15/0.23/0.45 against 0.04/0.63/0.65, the 600 px
/// billboards at 19.4 MB of texture and a file larger than the input's where the cards take
/// 0.07 MB. Other foliage (leaf clusters, where thinning would punch holes) keeps the rule of
/// the issue-5 to -7 sweeps (docs/experiments.md §6–8): the nearest LOD `skeleton`, every
/// farther one `static`, or `spectral-axis-phase` under `--animation spectral`, whose
/// coefficient texture only spectral motion has. Under `--animation spectral` or VAT cards are
/// still picked: they carry no motion of their own. Returns the method and the reason written
/// to the report.
pub fn auto_method(
    lod_index: usize,
    spectral_animation: bool,
    card_foliage: bool,
) -> (MethodName, &'static str) {
    if card_foliage {
        (
            MethodName::Cards,
            "auto: foliage of single leaf cards -> cards (the input's cards thinned to the \
             triangle budget, its leaf texture at the LOD's texel density: no atlas)",
        )
    } else if lod_index == 0 {
        (
            MethodName::Skeleton(crate::DEFAULT_SKELETON),
            "auto: nearest LOD -> skeleton (per-bone clouds; sibling bones share a rotation only \
             where no leaf would move a pixel)",
        )
    } else if spectral_animation {
        (
            MethodName::Spectral(SpectralKind::AxisPhase),
            "auto: farther LOD with --animation spectral -> spectral-axis-phase (motion as a few \
             cosines per billboard)",
        )
    } else {
        (
            MethodName::Static,
            "auto: farther LOD -> static (one cloud, fewest billboards, best colour at matched \
             billboard counts)",
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral_k;

    #[test]
    fn method_names_round_trip() {
        for (text, m) in METHOD_NAMES {
            assert_eq!(MethodName::parse(text), Some(*m));
            if *text != "spectral" && *text != "skeleton" {
                assert_eq!(m.name(), *text);
            }
        }
        assert_eq!(MethodName::parse("spectral-fourier"), None);
        assert_eq!(spectral_k(60.0), 6);
        assert_eq!(spectral_k(3.0), 1);
    }

    #[test]
    fn options_go_to_the_methods_that_use_them() {
        let spectral = SpectralOptions {
            clusters: Some(4),
            ..Default::default()
        };
        let skeleton_name = MethodName::Skeleton(BoneDescriptionKind::AxisAngle);
        let m = Method::new(skeleton_name, spectral.clone(), SkeletonOptions::default());
        assert_eq!(m, Method::Skeleton(SkeletonOptions::default()));
        let w = ignored_options(skeleton_name, true, false, false);
        assert!(w.len() == 1 && w[0].contains("--clusters"), "{w:?}");
        assert!(ignored_options(MethodName::Auto, true, false, true).is_empty());
        let m = Method::new(MethodName::Auto, spectral, SkeletonOptions::default());
        assert_eq!(m.name(), MethodName::Auto);
        let (picked, _) = m.pick(1, true, false);
        assert_eq!(picked.name(), MethodName::Spectral(SpectralKind::AxisPhase));
        let (picked, _) = m.pick(0, false, false);
        assert_eq!(picked.name(), MethodName::Skeleton(crate::DEFAULT_SKELETON));
        for k in 0..3 {
            let (picked, _) = m.pick(k, k == 1, true);
            assert_eq!(picked.name(), MethodName::Cards);
        }
    }
}
