//! Skeleton clustering of foliage, SBCS (spec animated-billboard-clouds §6): the skeleton is
//! simplified to a budget of billboard clouds by `frond-skeleton` (common joint rotation, and
//! sibling collapse when CJR alone cannot reach it), then one stochastic billboard cloud is
//! built per common-rotation set in its bone's rest frame and skinned to that bone, exactly
//! as `per-bone` does for single bones. No billboard has motion of its own: the rig carries it.

use std::sync::Arc;

use frond_skeleton::{BoneDescriptionKind, SkeletonParams, SkeletonReport, simplify};

use crate::cloud_build::{Driver, FoliageCluster, build_animated_cloud};
use crate::contract::AnimatedBillboardCloud;
use crate::error::LodError;
use crate::method_api::{
    BuildContext, BuildTimings, ClusteringMethod, Foliage, MethodError, MethodName, MethodOutput,
    MethodPlugin, MethodSection, OptionUse, SkeletonOptions,
};

/// The name of skeleton simplification with bone description type `kind`.
pub const fn name_of(kind: BoneDescriptionKind) -> MethodName {
    match kind {
        BoneDescriptionKind::AxisAngle => MethodName::new("skeleton-axis-angle"),
        BoneDescriptionKind::RotationSpectral => MethodName::new("skeleton-rotation-spectral"),
    }
}

/// The bone description types, as the names list them.
const KINDS: [BoneDescriptionKind; 2] = [
    BoneDescriptionKind::AxisAngle,
    BoneDescriptionKind::RotationSpectral,
];

/// The key of the LOD report entry that [`SkeletonReport`] is written under.
pub const SECTION: &str = "skeleton";

/// Skeleton simplification as the registry lists it: `skeleton` alone names the default
/// description type ([`crate::DEFAULT_SKELETON`]).
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[
        ("skeleton", name_of(crate::DEFAULT_SKELETON)),
        (
            "skeleton-axis-angle",
            name_of(BoneDescriptionKind::AxisAngle),
        ),
        (
            "skeleton-rotation-spectral",
            name_of(BoneDescriptionKind::RotationSpectral),
        ),
    ],
    configure: |name, options, _| {
        let kind = KINDS
            .into_iter()
            .find(|&k| name_of(k) == name)
            .ok_or_else(|| MethodError::Unknown(name.to_string()))?;
        Ok(Arc::new(SkeletonOptions {
            kind,
            ..options.skeleton.clone()
        }))
    },
    uses: |_| OptionUse {
        spectral: false,
        skeleton: true,
    },
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
        name_of(self.kind)
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let (cloud, timings, report) = build_skeleton_cloud(ctx, &self.params(ctx))?;
        Ok(MethodOutput {
            foliage: Foliage::Cloud(cloud),
            timings,
            section: Some(MethodSection::new(SECTION, &report)?),
        })
    }
}

/// Builds the skeleton-simplified animated cloud of the foliage (SBCS) for the LOD of `ctx`.
pub fn build_skeleton_cloud(
    ctx: &BuildContext,
    sk: &SkeletonParams,
) -> Result<(AnimatedBillboardCloud, BuildTimings, SkeletonReport), LodError> {
    let mut simplified = simplify(ctx.tree, ctx.sampled, ctx.clock.clip, sk)?;
    // Every cloud takes a billboard at least: more clouds than the LOD's billboard budget
    // (a far LOD's few triangles) are simplified again to that many.
    if let Some(max) = ctx.max_billboards
        && sk.clouds.is_none()
        && simplified.report.clouds > max
    {
        let capped = SkeletonParams {
            clouds: Some(max.max(1)),
            ..sk.clone()
        };
        simplified = simplify(ctx.tree, ctx.sampled, ctx.clock.clip, &capped)?;
    }
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
