//! Builds an [`AnimatedBillboardCloud`] from clusters of foliage triangles: one stochastic
//! billboard cloud per cluster, all baked into one atlas, each billboard moving with the
//! cluster's driver (spec animated-billboard-clouds §1.4, §2.4, §6 "Bone Clustering"; thesis
//! §5.2.2 for the rigid fit of a static cloud).

use std::time::Instant;

use frond_render::{TreeParts, scene_from_positions};
use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use frond_billboard::bake::bake_cloud;
use frond_billboard::cloud::{CloudError, fit_quad};
use frond_billboard::plane_search::{search_planes, valid_for_plane};
use frond_billboard::{Quad, TriangleSoup};
use frond_scene::Rig;
use frond_scene::rigid_fit::rigid_fit;

use crate::contract::{AnimatedBillboard, AnimatedBillboardCloud, LoopClock, RigidMotion};
use crate::error::LodError;
use crate::method::{BuildContext, Foliage, MethodName, MethodOutput};

/// How a cluster's billboards move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Driver {
    /// Rigidly with a rig node: the cloud is built in that node's rest frame (exact for
    /// triangles bound to it alone).
    Node(usize),
    /// Each billboard gets the best rigid fit of its triangles' sampled motion; the cloud is
    /// built in the average pose.
    RigidFit,
    /// Built in the average pose with no motion yet: the caller gives each billboard its
    /// own (spectral clustering, [`crate::methods::spectral`]).
    Assigned,
}

/// A set of foliage triangles that share one billboard cloud.
#[derive(Clone, Debug)]
pub struct FoliageCluster {
    /// Indices into `Sampled::foliage` (and so into its trajectories).
    pub members: Vec<usize>,
    pub driver: Driver,
}

/// One billboard of a cluster: its quad, the triangles it replaces and those drawn on it.
type ClusterQuad = (Quad, Vec<usize>, Vec<usize>);

/// Wall times of the build, seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BuildTimings {
    pub reference_pose: f64,
    pub plane_search: f64,
    pub bake: f64,
    pub motion_fit: f64,
}

/// The rig's world matrices at every sample of `clock`.
pub fn sampled_worlds(rig: &Rig, clock: &LoopClock) -> Vec<Vec<Mat4>> {
    (0..clock.samples.max(1))
        .into_par_iter()
        .map(|s| rig.world_at(clock.clip, clock.time(s)))
        .collect()
}

/// The LOD of a method that only groups the foliage: `clusters` built over the tree's own rig
/// (per-bone, static), with nothing else to report.
pub fn clustered_foliage(
    ctx: &BuildContext,
    clusters: &[FoliageCluster],
    method: MethodName,
) -> Result<MethodOutput, LodError> {
    let (cloud, timings) =
        build_animated_cloud(ctx, ctx.tree.rig.clone(), false, clusters, method.name())?;
    Ok(MethodOutput {
        foliage: Foliage::Cloud(cloud),
        timings,
        report: Default::default(),
    })
}

/// Builds the animated cloud of `clusters` for the LOD of `ctx`: one stochastic billboard
/// cloud per cluster, all baked into one atlas. `rig` is the LOD's skeleton (the tree's own,
/// or a simplified one whose node indices extend the tree's: `rig_resampled` when some of its
/// channels were resampled from the clock's clip), `method` the name the report writes.
pub fn build_animated_cloud(
    ctx: &BuildContext,
    rig: Rig,
    rig_resampled: bool,
    clusters: &[FoliageCluster],
    method: &str,
) -> Result<(AnimatedBillboardCloud, BuildTimings), CloudError> {
    let (renderer, tree, sampled, params) = (ctx.renderer, ctx.tree, ctx.sampled, ctx.cloud);
    let clock = ctx.clock.clone();
    let mut timings = BuildTimings::default();
    let t0 = Instant::now();
    let soup = reference_soup(ctx, &rig, &clock, clusters);
    let t1 = Instant::now();
    timings.reference_pose = (t1 - t0).as_secs_f64();

    let per_cluster = cluster_quads(ctx, &soup, clusters);
    let t2 = Instant::now();
    timings.plane_search = (t2 - t1).as_secs_f64();

    let mut quads = Vec::new();
    let mut owns = Vec::new();
    let mut drawn = Vec::new();
    let mut drivers = Vec::new();
    for (cluster, list) in clusters.iter().zip(per_cluster) {
        for (q, own, d) in list {
            quads.push(q);
            owns.push(own);
            drawn.push(d);
            drivers.push(cluster.driver);
        }
    }
    if quads.is_empty() {
        return Err(CloudError::Empty);
    }
    let draw = scene_from_positions(tree, &sampled.average, None, TreeParts::Foliage);
    let baked = bake_cloud(
        renderer,
        &soup,
        &draw.materials,
        &draw.textures,
        &quads,
        &drawn,
        &params.bake,
    )?;
    let t3 = Instant::now();
    timings.bake = (t3 - t2).as_secs_f64();

    let billboards = animated_billboards(ctx, &soup, &quads, &owns, &drivers, &baked.uv_rects);
    timings.motion_fit = t3.elapsed().as_secs_f64();
    let mut cloud = AnimatedBillboardCloud {
        method: method.to_string(),
        billboards,
        atlas: baked.atlas,
        texels_per_unit: baked.texels_per_unit,
        density_reduced: baked.density_reduced,
        rig,
        rig_resampled,
        clock,
        playable_clips: Vec::new(),
    };
    cloud.update_playable_clips();
    Ok((cloud, timings))
}

/// Every foliage triangle in its cluster's reference frame: the average pose for rigid-fit and
/// assigned clusters, the loop's average in the node's rest frame for node-driven ones.
fn reference_soup(
    ctx: &BuildContext,
    rig: &Rig,
    clock: &LoopClock,
    clusters: &[FoliageCluster],
) -> TriangleSoup {
    let (tree, sampled) = (ctx.tree, ctx.sampled);
    let worlds = sampled_worlds(rig, clock);
    let rest = rig.rest_world();
    let n = sampled.samples();
    let nv = sampled.vertices;
    // Reference positions of every foliage triangle, in its cluster's frame.
    let mut reference: Vec<[Vec3; 3]> = vec![[Vec3::ZERO; 3]; sampled.foliage.len()];
    for cluster in clusters {
        match cluster.driver {
            Driver::RigidFit | Driver::Assigned => {
                for &k in &cluster.members {
                    let tri = &tree.triangles[sampled.foliage[k]];
                    reference[k] = tri.v.map(|v| sampled.average[v as usize]);
                }
            }
            Driver::Node(node) => {
                // Rest_b · W_b(s)⁻¹ · p_s, averaged over the loop.
                let to_rest: Vec<Mat4> = worlds
                    .iter()
                    .map(|w| rest[node] * w[node].inverse())
                    .collect();
                let refs: Vec<(usize, [Vec3; 3])> = cluster
                    .members
                    .par_iter()
                    .map(|&k| {
                        let tri = &tree.triangles[sampled.foliage[k]];
                        let corners = tri.v.map(|v| {
                            let sum: Vec3 = (0..n)
                                .map(|s| {
                                    to_rest[s.min(to_rest.len() - 1)]
                                        .transform_point3(sampled.positions[s * nv + v as usize])
                                })
                                .sum();
                            sum / n as f32
                        });
                        (k, corners)
                    })
                    .collect();
                for (k, c) in refs {
                    reference[k] = c;
                }
            }
        }
    }
    TriangleSoup {
        positions: reference,
        uvs: sampled
            .foliage
            .iter()
            .map(|&t| tree.triangles[t].v.map(|v| tree.vertices.uv[v as usize]))
            .collect(),
        material: sampled
            .foliage
            .iter()
            .map(|&t| tree.triangles[t].material)
            .collect(),
    }
}

/// One plane search per cluster, each with its own seed derived from the cluster's index:
/// every cluster's quads with the triangles they replace and those drawn on them.
fn cluster_quads(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    clusters: &[FoliageCluster],
) -> Vec<Vec<ClusterQuad>> {
    let (params, scale) = (ctx.cloud, ctx.scale);
    clusters
        .par_iter()
        .enumerate()
        .map(|(ci, cluster)| {
            let sub = TriangleSoup {
                positions: cluster.members.iter().map(|&k| soup.positions[k]).collect(),
                uvs: cluster.members.iter().map(|&k| soup.uvs[k]).collect(),
                material: cluster.members.iter().map(|&k| soup.material[k]).collect(),
            };
            let mut sp = params.search.clone();
            sp.seed = sp
                .seed
                .wrapping_add((ci as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let search = search_planes(&sub, &sp, scale);
            search
                .clusters
                .iter()
                .map(|c| {
                    let quad = fit_quad(&sub, &c.plane, &c.triangles);
                    let own: Vec<usize> = c.triangles.iter().map(|&t| cluster.members[t]).collect();
                    let drawn = if params.increased_density {
                        let mut m: Vec<usize> = valid_for_plane(&sub, &c.plane, sp.epsilon)
                            .into_iter()
                            .map(|t| cluster.members[t])
                            .collect();
                        m.extend(&own);
                        m.sort_unstable();
                        m.dedup();
                        m
                    } else {
                        own.clone()
                    };
                    (quad, own, drawn)
                })
                .collect()
        })
        .collect()
}

/// The billboards of `quads`: each follows its cluster's driver (a node, or the rigid fit of
/// its own triangles' sampled motion) and samples the atlas at `uv_rects`.
fn animated_billboards(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    quads: &[Quad],
    owns: &[Vec<usize>],
    drivers: &[Driver],
    uv_rects: &[[Vec2; 4]],
) -> Vec<AnimatedBillboard> {
    let (tree, sampled) = (ctx.tree, ctx.sampled);
    let n = sampled.samples();
    let nv = sampled.vertices;
    quads
        .par_iter()
        .zip(owns.par_iter())
        .zip(drivers.par_iter())
        .zip(uv_rects.par_iter())
        .map(|(((quad, own), driver), uv)| {
            let (follows, motion) = match *driver {
                Driver::Node(node) => (Some(node), None),
                Driver::Assigned => (None, None),
                Driver::RigidFit => {
                    let from: Vec<Vec3> = own.iter().flat_map(|&k| soup.positions[k]).collect();
                    let frames = (0..n)
                        .map(|s| {
                            let to: Vec<Vec3> = own
                                .iter()
                                .flat_map(|&k| {
                                    tree.triangles[sampled.foliage[k]]
                                        .v
                                        .map(|v| sampled.positions[s * nv + v as usize])
                                })
                                .collect();
                            rigid_fit(&from, &to)
                        })
                        .collect();
                    (None, Some(RigidMotion::Sampled(frames)))
                }
            };
            AnimatedBillboard {
                quad: *quad,
                uv: *uv,
                follows,
                motion,
                triangles: own.iter().map(|&k| sampled.foliage[k]).collect(),
            }
        })
        .collect()
}
