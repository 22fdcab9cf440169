//! The animated LOD layer (spec animated-billboard-clouds §1.4, §3–§6; view-dependent
//! hierarchies §2.3–2.4): the contract between clustering and export (an animated billboard
//! cloud), the clustering methods behind one trait, the screen and motion budgets, and the
//! chain builder that turns a tree into LODs in memory. Export writes a chain without knowing
//! which method built it; the static cloud (plane search, bake, atlas) is `frond-billboard`'s.

pub mod chain;
pub mod cloud_build;
pub mod contract;
pub mod cost_budget;
pub mod error;
pub mod joint_budget;
pub mod method;
pub mod method_api;
pub mod methods;
pub mod motion_budget;
mod part_mesh;
pub mod report;
pub mod screen_budget;
pub mod section_value;
pub mod simplex_fit;
pub mod skin_fit;
pub mod switching;
pub mod texture_budget;
pub mod wood_skins;

use frond_skeleton::BoneDescriptionKind;
use frond_spectral::description::SpectralKind;

pub use chain::{Chain, ChainLod, ChainRequest, CloudOptions, LodContent, build_chain};
pub use contract::{
    AnimatedBillboard, AnimatedBillboardCloud, BillboardTexture, LoopClock, RigidMotion,
};
pub use error::LodError;
pub use method::{auto_method, ignored_options};
pub use method_api::{
    BuildContext, ClusteringMethod, Foliage, IgnoredOptions, Method, MethodChoice, MethodError,
    MethodName, MethodOptions, MethodOutput, MethodPlugin, MethodSection, PickContext, Registry,
    SkeletonOptions, SpectralOptions,
};
pub use methods::{METHOD_NAMES, REGISTRY};
pub use report::{
    DroppedReport, LOD_REPORT_SCHEMA_VERSION, LodEntry, LodReport, LodTimings, ReportTimings,
    TextureMemory,
};
pub use screen_budget::{LodLevel, lod_levels, screen_height_at};

/// The description type `--method spectral` uses.
pub const DEFAULT_SPECTRAL: SpectralKind = SpectralKind::AxisPhase;

/// The bone description type `--method skeleton` uses: axis-angle reached fewer clouds at the
/// same screen tolerance with less foliage error than rotation-spectral on oak_medium and
/// oak_dense (docs/experiments.md §8).
pub const DEFAULT_SKELETON: BoneDescriptionKind = BoneDescriptionKind::AxisAngle;

/// Default animation zone size as a fraction of the bounding-box diagonal (or the LOD's ε when
/// larger): a large tree's foliage becomes a few thousand zones, few enough for k-means.
pub const DEFAULT_ZONE_FRACTION: f32 = 0.02;

/// The spectral k rule: one animation cluster per 10 pixels of tree height (6 at 60 px, 20 at
/// 200 px), at least 1.
pub fn spectral_k(screen_height: f32) -> usize {
    ((screen_height / 10.0).round() as usize).max(1)
}
