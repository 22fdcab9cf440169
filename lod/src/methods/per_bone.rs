//! `per-bone`: one billboard cloud per rig node that foliage follows, each billboard skinned
//! rigidly to that node (spec animated-billboard-clouds §6 "Bone Clustering", without
//! reduction); foliage without a bone gets one cloud whose billboards follow the rigid fit of
//! their triangles' motion.

use std::sync::Arc;

use frond_scene::{Sampled, Tree};

use crate::cloud_build::{Driver, FoliageCluster, clustered_foliage};
use crate::error::LodError;
use crate::method_api::{
    BuildContext, ClusteringMethod, MethodName, MethodOutput, MethodPlugin, uses_no_options,
};

/// `per-bone`'s name.
pub const NAME: MethodName = MethodName::new("per-bone");

/// `per-bone` as the registry lists it.
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[("per-bone", NAME)],
    configure: |_, _, _| Ok(Arc::new(PerBone)),
    uses: uses_no_options,
};

/// The `per-bone` method; it has no options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PerBone;

impl ClusteringMethod for PerBone {
    fn name(&self) -> MethodName {
        NAME
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        clustered_foliage(ctx, &per_bone_clusters(ctx.tree, ctx.sampled), self.name())
    }
}

/// `per-bone` clusters: one per rig node that foliage follows; foliage without a bone gets one
/// rigid-fit cluster.
pub fn per_bone_clusters(tree: &Tree, sampled: &Sampled) -> Vec<FoliageCluster> {
    let mut by_node: std::collections::BTreeMap<Option<usize>, Vec<usize>> = Default::default();
    for (k, &t) in sampled.foliage.iter().enumerate() {
        let node = tree.triangles[t].bone.map(|b| tree.bones[b as usize].node);
        by_node.entry(node).or_default().push(k);
    }
    by_node
        .into_iter()
        .map(|(node, members)| FoliageCluster {
            members,
            driver: node.map_or(Driver::RigidFit, Driver::Node),
        })
        .collect()
}
