//! `static`: all foliage in one billboard cloud built in the loop's average pose, each
//! billboard following the rigid fit of its triangles' sampled motion (thesis §5.2.2, Static
//! Co-planar Clustering).

use std::sync::Arc;

use frond_scene::Sampled;

use crate::cloud_build::{Driver, FoliageCluster, clustered_foliage};
use crate::error::LodError;
use crate::method_api::{
    BuildContext, ClusteringMethod, MethodName, MethodOutput, MethodPlugin, uses_no_options,
};

/// `static`'s name.
pub const NAME: MethodName = MethodName::new("static");

/// `static` as the registry lists it.
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[("static", NAME)],
    configure: |_, _, _| Ok(Arc::new(StaticCloud)),
    uses: uses_no_options,
};

/// The `static` method; it has no options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StaticCloud;

impl ClusteringMethod for StaticCloud {
    fn name(&self) -> MethodName {
        NAME
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        clustered_foliage(ctx, &static_clusters(ctx.sampled), self.name())
    }
}

/// `static` clusters: every foliage triangle in one rigid-fit cluster.
pub fn static_clusters(sampled: &Sampled) -> Vec<FoliageCluster> {
    vec![FoliageCluster {
        members: (0..sampled.foliage.len()).collect(),
        driver: Driver::RigidFit,
    }]
}
