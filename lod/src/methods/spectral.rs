//! Spectral clustering of foliage, SCA (spec animated-billboard-clouds §4.11–4.14): animation
//! zones → one description per zone → k-means over the descriptions → a stochastic billboard
//! cloud per cluster in the average pose → each billboard moves by the inverse DFT of the
//! average description of its triangles, as a pure translation. With the shared-bone
//! improvement (§4.12) a billboard whose triangles share ancestor bones follows the deepest
//! one and carries only the motion relative to it.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

use frond_scene::{Sampled, Tree};
use frond_spectral::description::{
    AxisPhase, Bins, DescriptionType, DominatingAxisType, Naive, SpectralKind,
};
use frond_spectral::kmeans::cluster_descriptions;
use frond_spectral::zones::{animation_zones, mean_trajectory};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloud_build::{Driver, FoliageCluster, build_animated_cloud, sampled_worlds};
use crate::contract::{AnimatedBillboardCloud, RigidMotion, SpectralMotion};
use crate::cost_budget::{IMPOSTOR_JOINTS, is_impostor_class};
use crate::error::LodError;
use crate::method_api::{
    BuildContext, BuildTimings, ClusteringMethod, Foliage, MethodError, MethodName, MethodOutput,
    MethodPlugin, MethodSection, OptionUse, SpectralOptions,
};
use frond_billboard::Quad;
use frond_billboard::cloud::CloudError;
use frond_scene::rigid_fit::rigid_fit;

/// The name of spectral clustering with description type `kind`.
pub const fn name_of(kind: SpectralKind) -> MethodName {
    match kind {
        SpectralKind::Naive => MethodName::new("spectral-naive"),
        SpectralKind::DominatingAxis => MethodName::new("spectral-dominating-axis"),
        SpectralKind::AxisPhase => MethodName::new("spectral-axis-phase"),
    }
}

/// The description types, as the names list them.
const KINDS: [SpectralKind; 3] = [
    SpectralKind::Naive,
    SpectralKind::DominatingAxis,
    SpectralKind::AxisPhase,
];

/// The key of the LOD report entry that [`SpectralReport`] is written under.
pub const SECTION: &str = "spectral";

/// Spectral clustering as the registry lists it: `spectral` alone names the default
/// description type ([`crate::DEFAULT_SPECTRAL`]).
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[
        ("spectral", name_of(crate::DEFAULT_SPECTRAL)),
        ("spectral-naive", name_of(SpectralKind::Naive)),
        (
            "spectral-dominating-axis",
            name_of(SpectralKind::DominatingAxis),
        ),
        ("spectral-axis-phase", name_of(SpectralKind::AxisPhase)),
    ],
    configure: |name, options, _| {
        let kind = KINDS
            .into_iter()
            .find(|&k| name_of(k) == name)
            .ok_or_else(|| MethodError::Unknown(name.to_string()))?;
        Ok(Arc::new(SpectralOptions {
            kind,
            ..options.spectral.clone()
        }))
    },
    uses: |_| OptionUse {
        spectral: true,
        skeleton: false,
    },
};

/// What SCA is asked for.
#[derive(Clone, Debug)]
pub struct SpectralParams {
    /// Description type (§4.4–4.8).
    pub kind: SpectralKind,
    /// Animation clusters k (capped at the number of zones).
    pub clusters: usize,
    /// Animation zone size ε_z in world units (App. C.2); 0 describes every triangle.
    pub zone_size: f32,
    /// Frequency bins (§4.10); the skeleton depth by default, capped at N/2.
    pub bins: usize,
    /// k-means++ restarts beside the skeleton start (App. C.1).
    pub restarts: usize,
    /// Seed of the k-means++ restarts.
    pub seed: u64,
    /// Most k-means iterations of a run.
    pub max_iterations: usize,
    /// Bind billboards to their triangles' deepest shared bone (§4.12).
    pub shared_bone: bool,
    /// Give every billboard of a cluster the cluster's one motion (the average description
    /// of its zones) rather than the average of its own triangles': the far end, where each
    /// cluster is to be one joint.
    pub one_motion_per_cluster: bool,
}

/// What SCA did: the `spectral` section of a spectral LOD's report entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SpectralReport {
    /// Description type (`naive`, `dominating-axis`, `axis-phase`).
    pub kind: String,
    /// Clusters k after capping.
    pub clusters: usize,
    /// Animation zones described.
    pub zones: usize,
    /// Frequency bins shared by the descriptions.
    pub bins: usize,
    /// k-means iterations of the kept run.
    pub iterations: usize,
    /// k-means error Σ w·deviation² of the kept run.
    pub error: f64,
    /// Which start won ("skeleton" or "random i").
    pub start: String,
    /// Weighted RMS distance (world units) of the zones' motion from their cluster's applied
    /// average, over every sample.
    pub residual: f32,
    /// Weighted RMS distance of the zones from their mean positions (the residual of no motion).
    pub motion_rms: f32,
    /// False when the clip's last pose differs from its first: the DFT treats the sampled
    /// window as one period, so the jump at the seam leaks into every frequency (the kept
    /// bins still hold the bulk of the motion; the billboards' motion loops, the clip did not).
    pub loops: bool,
    /// Billboards bound to a shared bone.
    pub shared_bone_billboards: usize,
    /// Cosine terms over all billboards and axes, before the screen budget prunes them.
    pub terms: usize,
    /// Seconds making the zones and their descriptions.
    pub t_describe: f64,
    /// Seconds of the k-means.
    pub t_cluster: f64,
    /// Every billboard of a cluster moves with the cluster's one motion (the far end).
    #[serde(default)]
    pub one_motion_per_cluster: bool,
}

/// The bone node each foliage triangle follows.
fn bone_nodes(tree: &Tree, sampled: &Sampled) -> Vec<Option<usize>> {
    sampled
        .foliage
        .iter()
        .map(|&t| tree.triangles[t].bone.map(|b| tree.bones[b as usize].node))
        .collect()
}

/// The deepest rig node that is each of `nodes` or an ancestor of it, or None when a
/// node is None or they share none.
pub fn deepest_shared(rig_nodes: &[frond_scene::Node], nodes: &[Option<usize>]) -> Option<usize> {
    let first = (*nodes.first()?)?;
    let mut chain = Vec::new();
    let mut cur = Some(first);
    while let Some(c) = cur {
        chain.push(c);
        cur = rig_nodes.get(c).and_then(|n| n.parent);
    }
    let mut deepest = 0usize; // index into chain: 0 = first itself
    for n in &nodes[1..] {
        let mut cur = Some((*n)?);
        let mut found = None;
        while let Some(c) = cur {
            if let Some(p) = chain.iter().position(|&x| x == c) {
                found = Some(p);
                break;
            }
            cur = rig_nodes.get(c).and_then(|n| n.parent);
        }
        deepest = deepest.max(found?);
    }
    chain.get(deepest).copied()
}

impl SpectralOptions {
    /// What SCA is asked for at the LOD of `ctx`: k from the options or the LOD's screen
    /// height, the zone size from the options or [`crate::DEFAULT_ZONE_FRACTION`] of the
    /// diagonal (the LOD's ε when larger), the skeleton depth as frequency bins.
    ///
    /// At an impostor-class LOD ([`is_impostor_class`]) every cluster gets one motion, and k
    /// defaults to the LOD's joint budget less the one that carries the wood: each cluster
    /// is then one joint (the far end's design; a shared bone would add joints).
    pub fn params(&self, ctx: &BuildContext) -> SpectralParams {
        let impostor = is_impostor_class(ctx.level.screen_height);
        let default_k = if impostor {
            ctx.max_joints
                .unwrap_or(IMPOSTOR_JOINTS)
                .saturating_sub(1)
                .max(1)
        } else {
            crate::spectral_k(ctx.level.screen_height)
        };
        SpectralParams {
            kind: self.kind,
            clusters: self.clusters.unwrap_or(default_k),
            zone_size: match self.zone_size {
                Some(z) => z.resolve(ctx.scale),
                None => ctx
                    .level
                    .epsilon
                    .max(crate::DEFAULT_ZONE_FRACTION * ctx.scale),
            },
            bins: ctx.tree.skeleton_depth().max(1) as usize,
            restarts: 2,
            seed: ctx.seed,
            max_iterations: 20,
            shared_bone: self.shared_bone && !impostor,
            one_motion_per_cluster: impostor,
        }
    }
}

impl ClusteringMethod for SpectralOptions {
    fn name(&self) -> MethodName {
        name_of(self.kind)
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let (cloud, timings, report) = build_spectral_cloud(ctx, &self.params(ctx))?;
        Ok(MethodOutput {
            foliage: Foliage::Cloud(cloud),
            timings,
            section: Some(MethodSection::new(SECTION, &report)?),
        })
    }
}

/// Builds the spectral animated cloud of the foliage (SCA) for the LOD of `ctx`.
pub fn build_spectral_cloud(
    ctx: &BuildContext,
    sp: &SpectralParams,
) -> Result<(AnimatedBillboardCloud, BuildTimings, SpectralReport), CloudError> {
    let run = Run { ctx, sp };
    match sp.kind {
        SpectralKind::Naive => run.go::<Naive>(),
        SpectralKind::DominatingAxis => run.go::<DominatingAxisType>(),
        SpectralKind::AxisPhase => run.go::<AxisPhase>(),
    }
}

/// Zones, their trajectories and descriptions, and the k-means over them.
pub struct ZoneClustering<T: DescriptionType> {
    /// The description type, with the frequency bins the zones share.
    pub ty: T,
    /// The animation zones (§4.11, App. C.2).
    pub zones: Vec<frond_spectral::zones::Zone>,
    /// Each zone's mean trajectory over the loop's samples.
    pub trajectories: Vec<Vec<Vec3>>,
    /// Each zone's description.
    pub descriptions: Vec<T::Desc>,
    /// Each zone's weight in the k-means: its triangle count.
    pub weights: Vec<f32>,
    /// Cluster of each zone.
    pub assignment: Vec<usize>,
    /// What the clustering did so far (the build adds the billboards' part).
    pub report: SpectralReport,
}

/// SCA step 1 on animation zones (§4.11, App. C.1–C.2): describe every zone, cluster the
/// descriptions with k-means (skeleton start + restarts).
pub fn cluster_zones<T: DescriptionType>(
    tree: &Tree,
    sampled: &Sampled,
    rest: &[Mat4],
    sp: &SpectralParams,
) -> ZoneClustering<T> {
    let t0 = Instant::now();
    let n = sampled.samples();
    let bones = bone_nodes(tree, sampled);
    let first: Vec<Vec3> = (0..sampled.foliage.len())
        .map(|k| sampled.trajectory(k).first().copied().unwrap_or(Vec3::ZERO))
        .collect();
    let zones = animation_zones(&bones, &first, sp.zone_size);
    let trajectories: Vec<Vec<Vec3>> = zones
        .par_iter()
        .map(|z| mean_trajectory(z.members.iter().map(|&k| sampled.trajectory(k))))
        .collect();
    let weights: Vec<f32> = zones.iter().map(|z| z.members.len() as f32).collect();
    let bins = sp.bins.clamp(1, (n / 2).max(1));
    let probe = T::with_bins(Bins::PerPair(bins));
    let descriptions: Vec<T::Desc> = trajectories.par_iter().map(|t| probe.describe(t)).collect();
    let spectra: Vec<&[f32]> = descriptions
        .iter()
        .flat_map(|d| probe.amplitude_spectra(d))
        .collect();
    let shared = Bins::shared(&spectra, bins);
    let bin_count = shared.count();
    let ty = T::with_bins(shared);
    let t1 = Instant::now();
    let label: Vec<usize> = zones.iter().map(|z| z.bone.unwrap_or(usize::MAX)).collect();
    let dist: Vec<f32> = zones
        .iter()
        .zip(&trajectories)
        .map(|(z, t)| match (z.bone, t.first()) {
            (Some(b), Some(p)) => rest.get(b).map_or(0.0, |m| p.distance(m.w_axis.truncate())),
            _ => 0.0,
        })
        .collect();
    let c = cluster_descriptions(
        &ty,
        &descriptions,
        &weights,
        sp.clusters,
        Some((&label, &dist)),
        sp.restarts,
        sp.seed,
        sp.max_iterations,
    );
    let res = residual(&ty, &c, &trajectories, &weights);
    let report = SpectralReport {
        kind: sp.kind.name().into(),
        clusters: c.centroids.len(),
        zones: zones.len(),
        bins: bin_count,
        iterations: c.iterations,
        error: c.error,
        start: c.start.clone(),
        residual: res,
        motion_rms: motion_rms(&trajectories, &weights),
        loops: sampled.motion.loops || !sampled.motion.moves,
        t_describe: (t1 - t0).as_secs_f64(),
        t_cluster: t1.elapsed().as_secs_f64(),
        ..Default::default()
    };
    ZoneClustering {
        ty,
        zones,
        trajectories,
        descriptions,
        weights,
        assignment: c.assignment,
        report,
    }
}

/// Weighted RMS over zones and samples of the distance from the mean position.
fn motion_rms(trajectories: &[Vec<Vec3>], weights: &[f32]) -> f32 {
    let (mut sum, mut total) = (0.0f64, 0.0f64);
    for (t, &w) in trajectories.iter().zip(weights) {
        let n = t.len().max(1) as f32;
        let mean = t.iter().copied().sum::<Vec3>() / n;
        let sq: f32 = t.iter().map(|p| (*p - mean).length_squared()).sum();
        sum += f64::from(w * sq / n);
        total += f64::from(w);
    }
    if total > 0.0 {
        (sum / total).sqrt() as f32
    } else {
        0.0
    }
}

/// Weighted RMS over zones and samples of `|own motion − applied centroid|` (world units).
pub fn residual<T: DescriptionType>(
    ty: &T,
    c: &frond_spectral::kmeans::Clustering<T::Desc>,
    trajectories: &[Vec<Vec3>],
    weights: &[f32],
) -> f32 {
    let applied: Vec<Vec<Vec3>> = c
        .centroids
        .par_iter()
        .map(|d| ty.apply(d, trajectories.first().map_or(0, |t| t.len())))
        .collect();
    // Per zone in parallel, summed in order: the same value whatever the threads.
    let parts: Vec<(f64, f64)> = trajectories
        .par_iter()
        .zip(&c.assignment)
        .zip(weights)
        .map(|((t, &k), &w)| {
            let n = t.len().max(1) as f32;
            let mean = t.iter().copied().sum::<Vec3>() / n;
            let sq: f32 = t
                .iter()
                .zip(&applied[k])
                .map(|(p, a)| (*p - mean - *a).length_squared())
                .sum();
            (f64::from(w * sq / n), f64::from(w))
        })
        .collect();
    let (sum, total) = parts.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    if total > 0.0 {
        (sum / total).sqrt() as f32
    } else {
        0.0
    }
}

struct Run<'a> {
    ctx: &'a BuildContext<'a>,
    sp: &'a SpectralParams,
}

impl Run<'_> {
    fn go<T: DescriptionType>(
        &self,
    ) -> Result<(AnimatedBillboardCloud, BuildTimings, SpectralReport), CloudError> {
        let (tree, sampled, sp) = (self.ctx.tree, self.ctx.sampled, self.sp);
        let rest = tree.rig.rest_world();
        let zc = cluster_zones::<T>(tree, sampled, &rest, sp);
        if !zc.report.loops {
            tracing::warn!(
                "{}: clip does not loop (gap {:.4}): spectral motion treats the sampled window \
                 as one period, its seam jump leaks into every frequency",
                tree.source.display(),
                sampled.motion.loop_gap
            );
        }
        let k = zc.report.clusters;
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); k];
        for (z, &c) in zc.zones.iter().zip(&zc.assignment) {
            members[c].extend(&z.members);
        }
        let clusters: Vec<FoliageCluster> = members
            .into_iter()
            .filter(|m| !m.is_empty())
            .map(|mut m| {
                m.sort_unstable();
                FoliageCluster {
                    members: m,
                    driver: Driver::Assigned,
                }
            })
            .collect();
        let (mut cloud, mut timings) = build_animated_cloud(
            self.ctx,
            tree.rig.clone(),
            false,
            &clusters,
            &format!("spectral-{}", sp.kind.name()),
        )?;
        let t0 = Instant::now();
        let mut report = zc.report.clone();
        if sp.one_motion_per_cluster {
            assign_cluster_motions(&mut cloud, sampled, &zc);
            report.one_motion_per_cluster = true;
        } else {
            report.shared_bone_billboards = assign_motions(&mut cloud, tree, sampled, &zc, sp);
        }
        report.terms = cloud
            .billboards
            .iter()
            .map(|b| match &b.motion {
                Some(RigidMotion::Spectral(m)) => m.terms(),
                _ => 0,
            })
            .sum();
        cloud.update_playable_clips();
        timings.motion_fit = t0.elapsed().as_secs_f64();
        Ok((cloud, timings, report))
    }
}

/// The index into `Sampled::foliage` of each foliage triangle, and the zone of each entry.
fn foliage_zones<T: DescriptionType>(
    sampled: &Sampled,
    zc: &ZoneClustering<T>,
) -> (HashMap<usize, usize>, Vec<usize>) {
    let foliage_index: HashMap<usize, usize> = (sampled.foliage.iter().enumerate())
        .map(|(k, &t)| (t, k))
        .collect();
    let mut zone_of = vec![0usize; sampled.foliage.len()];
    for (z, zone) in zc.zones.iter().enumerate() {
        for &k in &zone.members {
            zone_of[k] = z;
        }
    }
    (foliage_index, zone_of)
}

/// A spectral motion of description `d`, or None when it has no term.
fn spectral_motion<T: DescriptionType>(ty: &T, d: &T::Desc) -> Option<RigidMotion> {
    let axes = ty.components(d);
    axes.iter().any(|a| !a.amplitudes.is_empty()).then(|| {
        RigidMotion::Spectral(SpectralMotion {
            axes,
            samples: ty.samples(d).max(1),
        })
    })
}

/// The far end's SCA step 4: one motion per cluster. Each cluster's motion is the average
/// description of its zones (each weighted by its triangles), and every billboard built from
/// the cluster's triangles (each billboard holds one cluster's) moves with it, in world
/// space: identical motions share one joint when written ([`crate::joint_budget`]).
fn assign_cluster_motions<T: DescriptionType>(
    cloud: &mut AnimatedBillboardCloud,
    sampled: &Sampled,
    zc: &ZoneClustering<T>,
) {
    let k = zc.assignment.iter().max().map_or(0, |&m| m + 1);
    let motions: Vec<Option<RigidMotion>> = (0..k)
        .into_par_iter()
        .map(|c| {
            let zones: Vec<usize> = (0..zc.zones.len())
                .filter(|&z| zc.assignment[z] == c)
                .collect();
            let refs: Vec<&T::Desc> = zones.iter().map(|&z| &zc.descriptions[z]).collect();
            let weights: Vec<f32> = zones.iter().map(|&z| zc.weights[z]).collect();
            if refs.is_empty() {
                None
            } else {
                spectral_motion(&zc.ty, &zc.ty.average(&refs, &weights))
            }
        })
        .collect();
    let (foliage_index, zone_of) = foliage_zones(sampled, zc);
    for b in &mut cloud.billboards {
        let cluster = (b.triangles.iter())
            .find_map(|t| foliage_index.get(t))
            .map(|&k| zc.assignment[zone_of[k]]);
        b.follows = None;
        b.motion = cluster.and_then(|c| motions[c].clone());
    }
}

/// SCA step 4 (and §4.12): every billboard's motion from the average description of its
/// triangles (each zone weighted by its triangles on the billboard). Returns how many
/// billboards follow a shared bone.
fn assign_motions<T: DescriptionType>(
    cloud: &mut AnimatedBillboardCloud,
    tree: &Tree,
    sampled: &Sampled,
    zc: &ZoneClustering<T>,
    sp: &SpectralParams,
) -> usize {
    let n = sampled.samples();
    let nv = sampled.vertices;
    let (foliage_index, zone_of) = foliage_zones(sampled, zc);
    let bones = bone_nodes(tree, sampled);
    let worlds = if sp.shared_bone {
        sampled_worlds(&cloud.rig, &cloud.clock)
    } else {
        Vec::new()
    };
    let rest = cloud.rig.rest_world();
    let nodes = cloud.rig.nodes.clone();
    let ty = &zc.ty;
    let results: Vec<(Option<usize>, Option<Quad>, Option<RigidMotion>)> = cloud
        .billboards
        .par_iter()
        .map(|b| {
            let ks: Vec<usize> = b
                .triangles
                .iter()
                .filter_map(|t| foliage_index.get(t).copied())
                .collect();
            let mut counts: BTreeMap<usize, f32> = BTreeMap::new();
            for &k in &ks {
                *counts.entry(zone_of[k]).or_default() += 1.0;
            }
            let weights: Vec<f32> = counts.values().copied().collect();
            let shared = if sp.shared_bone && !worlds.is_empty() {
                let bs: Vec<Option<usize>> = ks.iter().map(|&k| bones[k]).collect();
                deepest_shared(&nodes, &bs)
            } else {
                None
            };
            let (follows, quad, desc) = match shared {
                Some(bone) => {
                    // The motion in the shared bone's rest frame: Rest_b · W_b(s)⁻¹ · p(s).
                    let to_rest: Vec<Mat4> = worlds
                        .iter()
                        .map(|w| rest[bone] * w[bone].inverse())
                        .collect();
                    let local = |s: usize, p: Vec3| to_rest[s % to_rest.len()].transform_point3(p);
                    let descs: Vec<T::Desc> = counts
                        .keys()
                        .map(|&z| {
                            let r: Vec<Vec3> = zc.trajectories[z]
                                .iter()
                                .enumerate()
                                .map(|(s, &p)| local(s, p))
                                .collect();
                            ty.describe(&r)
                        })
                        .collect();
                    let refs: Vec<&T::Desc> = descs.iter().collect();
                    let d = ty.average(&refs, &weights);
                    // The quad was built in the average world pose: carry it rigidly to the
                    // mean pose of its triangles in the bone's rest frame.
                    let (mut from, mut to) = (Vec::new(), Vec::new());
                    for &k in &ks {
                        for &v in &tree.triangles[sampled.foliage[k]].v {
                            from.push(sampled.average[v as usize]);
                            let sum: Vec3 = (0..n)
                                .map(|s| local(s, sampled.positions[s * nv + v as usize]))
                                .sum();
                            to.push(sum / n.max(1) as f32);
                        }
                    }
                    let fit = rigid_fit(&from, &to);
                    (Some(bone), Some(b.quad.transformed(fit)), d)
                }
                None => {
                    let refs: Vec<&T::Desc> = counts.keys().map(|&z| &zc.descriptions[z]).collect();
                    (None, None, ty.average(&refs, &weights))
                }
            };
            (follows, quad, spectral_motion(ty, &desc))
        })
        .collect();
    let mut shared = 0;
    for (b, (follows, quad, motion)) in cloud.billboards.iter_mut().zip(results) {
        if follows.is_some() {
            shared += 1;
        }
        b.follows = follows;
        if let Some(q) = quad {
            b.quad = q;
        }
        b.motion = motion;
    }
    shared
}
