//! Skeleton clustering of foliage, SBCS (spec animated-billboard-clouds §6): the skeleton is
//! simplified to a budget of billboard clouds by `frond-skeleton` (common joint rotation, and
//! sibling collapse when CJR alone cannot reach it), then one stochastic billboard cloud is
//! built per common-rotation set in its bone's rest frame and skinned to that bone, exactly
//! as `per-bone` does for single bones. No billboard has motion of its own: the rig carries it.

use frond_render::Renderer;
use frond_scene::{Sampled, Tree};
use frond_skeleton::{SkeletonParams, SkeletonReport, simplify};

use crate::animated::{AnimatedBillboardCloud, LoopClock, Rig};
use crate::animated_build::{BuildTimings, Driver, FoliageCluster, build_animated_cloud};
use crate::cloud::{CloudError, CloudParams};

/// Builds the skeleton-simplified animated cloud of the foliage. `scale` sizes the plane
/// search's tolerances, as in [`build_animated_cloud`].
pub fn build_skeleton_cloud(
    renderer: &Renderer,
    tree: &Tree,
    sampled: &Sampled,
    clock: LoopClock,
    params: &CloudParams,
    sk: &SkeletonParams,
    scale: f32,
) -> Result<(AnimatedBillboardCloud, BuildTimings, SkeletonReport), CloudError> {
    let simplified = simplify(tree, sampled, clock.clip, sk)?;
    let changed = simplified.report.bones_changed > 0;
    let rig = Rig {
        nodes: simplified.rig.nodes,
        order: simplified.rig.order,
        clips: simplified.rig.clips,
        resampled: changed,
    };
    let clusters: Vec<FoliageCluster> = simplified
        .sets
        .into_iter()
        .filter(|s| !s.members.is_empty())
        .map(|s| FoliageCluster {
            members: s.members,
            driver: s.node.map_or(Driver::RigidFit, Driver::Node),
        })
        .collect();
    let (cloud, timings) = build_animated_cloud(
        renderer, tree, sampled, rig, clock, &clusters, params, scale, "skeleton",
    )?;
    Ok((cloud, timings, simplified.report))
}
