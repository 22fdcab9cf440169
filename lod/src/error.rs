//! Why a LOD chain could not be built.

use frond_billboard::cloud::CloudError;
use frond_skeleton::SkeletonError;

use crate::screen_budget::SizingError;
use crate::section_value::SectionError;

/// Why a LOD chain could not be built.
#[derive(Debug, thiserror::Error)]
pub enum LodError {
    /// The static cloud (plane search, bake) failed.
    #[error(transparent)]
    Cloud(#[from] CloudError),
    /// Skeleton simplification failed.
    #[error(transparent)]
    Skeleton(#[from] SkeletonError),
    /// The LODs cannot be sized (screen heights, pixel error).
    #[error(transparent)]
    Sizing(#[from] SizingError),
    /// Sampling the loop failed.
    #[error(transparent)]
    Scene(#[from] frond_scene::SceneError),
    /// A method's report section could not be kept.
    #[error(transparent)]
    Section(#[from] SectionError),
    /// The tree has nothing to turn into billboards.
    #[error("{0}: the tree has no foliage to turn into billboards")]
    NoFoliage(String),
}
