//! Skeleton clustering of foliage, SBCS (spec animated-billboard-clouds §6): the skeleton is
//! simplified to a budget of billboard clouds by `frond-skeleton` (common joint rotation, and
//! sibling collapse when CJR alone cannot reach it), then one stochastic billboard cloud is
//! built per common-rotation set in its bone's rest frame and skinned to that bone, exactly
//! as `per-bone` does for single bones. No billboard has motion of its own: the rig carries it.

use frond_skeleton::{SkeletonParams, SkeletonReport, simplify};

use crate::cloud_build::{BuildTimings, Driver, FoliageCluster, build_animated_cloud};
use crate::contract::AnimatedBillboardCloud;
use crate::error::LodError;
use crate::method::{
    BuildContext, ClusteringMethod, Foliage, MethodName, MethodOutput, MethodReport,
    SkeletonOptions,
};

impl SkeletonOptions {
    /// What `frond-skeleton` is asked for at the LOD of `ctx`: the options, the skeleton depth
    /// as frequency bins, and merges allowed while no leaf moves more than a pixel and none
    /// leaves its branch by half a pixel.
    pub fn params(&self, ctx: &BuildContext) -> SkeletonParams {
        SkeletonParams {
            kind: self.kind,
            clouds: self.clouds,
            average_bone: self.average_bone,
            bins: ctx.tree.skeleton_depth().max(1) as usize,
            attach_tolerance: 0.5 * ctx.level.pixel,
            displacement_tolerance: ctx.level.pixel,
        }
    }
}

impl ClusteringMethod for SkeletonOptions {
    fn name(&self) -> MethodName {
        MethodName::Skeleton(self.kind)
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let (cloud, timings, report) = build_skeleton_cloud(ctx, &self.params(ctx))?;
        Ok(MethodOutput {
            foliage: Foliage::Cloud(cloud),
            timings,
            report: MethodReport::Skeleton(report),
        })
    }
}

/// Builds the skeleton-simplified animated cloud of the foliage (SBCS) for the LOD of `ctx`.
pub fn build_skeleton_cloud(
    ctx: &BuildContext,
    sk: &SkeletonParams,
) -> Result<(AnimatedBillboardCloud, BuildTimings, SkeletonReport), LodError> {
    let simplified = simplify(ctx.tree, ctx.sampled, ctx.clock.clip, sk)?;
    if let Some(why) = &simplified.report.stopped_by {
        tracing::warn!("LOD{}: {why}", ctx.index + 1);
    }
    let changed = simplified.report.bones_changed > 0;
    let clusters: Vec<FoliageCluster> = simplified
        .sets
        .into_iter()
        .filter(|s| !s.members.is_empty())
        .map(|s| FoliageCluster {
            members: s.members,
            driver: s.node.map_or(Driver::RigidFit, Driver::Node),
        })
        .collect();
    let (cloud, timings) =
        build_animated_cloud(ctx, simplified.rig.rig, changed, &clusters, "skeleton")?;
    Ok((cloud, timings, simplified.report))
}
