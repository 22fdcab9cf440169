//! The skeleton stage: Skeleton Billboard Cloud Simplification, SBCS (spec
//! animated-billboard-clouds §6, thesis ch. 7). Bone rotations are described (axis-angle or
//! rotation spectrum), sibling bones share common rotations (CJR) until a budget of billboard
//! clouds is met, and non-terminal siblings are collapsed about a common end joint when CJR
//! alone cannot meet it. The output is a skeleton (rig nodes and a resampled clip) and the
//! foliage sets that each get one billboard cloud; `frond-billboard` builds the clouds.

pub mod cjr;
pub mod collapse;
pub mod description;
pub mod end_joint;
pub mod error;
pub mod materialize;
pub mod model;
pub mod sbcs;

pub use description::{BoneDescriptionKind, BoneDescriptionType};
pub use error::SkeletonError;
pub use model::SkeletonModel;
pub use sbcs::{CloudSet, SimplifiedSkeleton, SkeletonParams, SkeletonReport, simplify};
