//! SBCS(TreeModel, BC) (spec animated-billboard-clouds §6.4, thesis §7.5): collapse
//! non-terminal siblings only while common joint rotation alone cannot reach the budget of
//! billboard clouds, then CJR, then one cloud per common-rotation set. Policy (§6.4): as much
//! CJR as possible, collapses only when needed, because a collapse costs the foliage its
//! connection to the trunk.

use std::collections::BTreeSet;
use std::time::Instant;

use frond_scene::{Sampled, Tree};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cjr::{Merge, apply_common_rotations, common_rotation_sets};
use crate::collapse::{CollapseRecord, EndJointCache, collapse_candidates, collapse_pair};
use crate::description::{AxisAngle, BoneDescriptionKind, BoneDescriptionType, RotationSpectral};
use crate::error::SkeletonError;
use crate::materialize::{MaterializedRig, materialize};
use crate::model::SkeletonModel;

/// What SBCS is asked for.
#[derive(Clone, Debug)]
pub struct SkeletonParams {
    /// How bone rotations are described and compared.
    pub kind: BoneDescriptionKind,
    /// The budget BC: billboard clouds wanted. None: as few as merges that cannot be seen
    /// allow (see `attach_tolerance` and `displacement_tolerance`), with no collapse.
    pub clouds: Option<usize>,
    /// The average-animation-bone improvement (§6.1, thesis §7.1.2): merged bones keep their
    /// own animation and only their foliage moves by the average.
    pub average_bone: bool,
    /// Frequency bins of the rotation-spectral type (§4.10).
    pub bins: usize,
    /// How far (world units) a merge may move foliage off its own bone while trunk and
    /// foliage share one skeleton (the LOD's half pixel: attached as far as the eye can
    /// tell). Ignored with `average_bone`, which gives attachment up.
    pub attach_tolerance: f32,
    /// With no budget: the largest RMS foliage displacement (world units) a merge may cause.
    pub displacement_tolerance: f32,
}

/// One billboard cloud to build: foliage triangles and the rig node they follow.
#[derive(Clone, Debug)]
pub struct CloudSet {
    /// Rig node (None: foliage bound to no bone, given a rigid fit).
    pub node: Option<usize>,
    /// Indices into `Sampled::foliage`.
    pub members: Vec<usize>,
}

/// What SBCS did, for `report.json`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SkeletonReport {
    /// Name of the bone description type used.
    pub description: String,
    /// The budget BC (None: merges that cannot be seen, `displacement_tolerance`).
    pub budget: Option<usize>,
    /// The displacement tolerance used (world units).
    pub displacement_tolerance: f32,
    /// Clouds made (common-rotation sets, plus one for unbound foliage).
    pub clouds: usize,
    /// Bones with foliage bound directly, before simplification.
    pub foliage_bones: usize,
    /// The fewest clouds CJR alone could reach on the input skeleton (one per sibling group).
    pub cjr_floor: usize,
    /// Merges CJR made.
    pub merges: usize,
    /// Largest description deviation of a merge CJR made.
    pub max_merge_deviation: f32,
    /// Largest RMS foliage displacement (world units) of a merge CJR made.
    pub max_merge_displacement: f32,
    /// Collapses made, in order.
    pub collapses: Vec<CollapseRecord>,
    /// Why the budget was not met, naming the skeleton level that stops it (§7.6.2); None
    /// when it was.
    pub stopped_by: Option<String>,
    /// True after a collapse, or when CJR had to move foliage off its branches by more than
    /// `attach_tolerance` to reach the budget: the wood follows the input's skeleton and the
    /// foliage its own.
    pub trunk_on_original_skeleton: bool,
    /// The attachment tolerance used (world units).
    pub attach_tolerance: f32,
    /// Whether the average-animation-bone improvement was on.
    pub average_bone: bool,
    /// Bones whose animation changed (plus new ones).
    pub bones_changed: usize,
    /// Weighted RMS and largest distance (world units) between where a leaf is in the input
    /// and where the simplified skeleton carries it, over the loop (leaves carried rigidly by
    /// the node their cloud follows, as the billboards are).
    pub foliage_error_rms: f32,
    /// The largest of those distances (world units).
    pub foliage_error_max: f32,
    /// Largest movement (world units) of a leaf relative to the bone whose wood it grew from,
    /// over the loop, in the LOD's rig: 0 when foliage stays attached to its branch.
    pub detachment_max: f32,
    /// Weighted RMS of that movement (world units).
    pub detachment_rms: f32,
    /// Seconds.
    pub t_simplify: f64,
}

/// The simplified skeleton and the clouds to build on it.
#[derive(Clone, Debug)]
pub struct SimplifiedSkeleton {
    /// The simplified skeleton as a rig.
    pub rig: MaterializedRig,
    /// The billboard clouds to build: their foliage and the rig node each follows.
    pub sets: Vec<CloudSet>,
    /// What SBCS did.
    pub report: SkeletonReport,
}

/// Sibling groups of foliage bones: the fewest clouds CJR alone can reach.
fn cjr_floor(model: &SkeletonModel) -> usize {
    model
        .foliage_nodes()
        .iter()
        .map(|&i| model.nodes[i].parent)
        .collect::<BTreeSet<_>>()
        .len()
}

/// Runs SBCS on `tree`'s skeleton, sampled as `sampled` (clip `clip` of the tree).
pub fn simplify(
    tree: &Tree,
    sampled: &Sampled,
    clip: Option<usize>,
    params: &SkeletonParams,
) -> Result<SimplifiedSkeleton, SkeletonError> {
    if params.clouds == Some(0) {
        return Err(SkeletonError::ZeroBudget);
    }
    match params.kind {
        BoneDescriptionKind::AxisAngle => run(&AxisAngle, tree, sampled, clip, params),
        BoneDescriptionKind::RotationSpectral => run(
            &RotationSpectral::new(params.bins),
            tree,
            sampled,
            clip,
            params,
        ),
    }
}

fn run<T: BoneDescriptionType>(
    ty: &T,
    tree: &Tree,
    sampled: &Sampled,
    clip: Option<usize>,
    params: &SkeletonParams,
) -> Result<SimplifiedSkeleton, SkeletonError> {
    let t0 = Instant::now();
    let mut model = SkeletonModel::from_tree(tree, sampled, clip)?;
    let extra = usize::from(!model.unbound.is_empty());
    let mut report = SkeletonReport {
        description: params.kind.name().into(),
        budget: params.clouds,
        displacement_tolerance: params.displacement_tolerance,
        foliage_bones: model.foliage_nodes().len(),
        cjr_floor: cjr_floor(&model) + extra,
        average_bone: params.average_bone,
        ..Default::default()
    };
    // 1. CJR alone, keeping every cloud on its branch (one skeleton for trunk and foliage).
    let attach = (!params.average_bone).then_some(params.attach_tolerance);
    let (budget, max_disp) = match params.clouds {
        Some(n) => (n, None),
        None => (1, Some(params.displacement_tolerance)),
    };
    let mut cjr = common_rotation_sets(
        ty,
        &model,
        budget,
        extra,
        params.average_bone,
        attach,
        max_disp,
    );
    let mut split = false;
    if params.clouds.is_some() && cjr.sets.len() + extra > budget {
        // 2. Collapses, only while CJR cannot reach the budget, then CJR on what is left;
        //    the trunk keeps the input's skeleton (§7.4).
        let mut cache = EndJointCache::default();
        while cjr_floor(&model) + extra > budget {
            let candidates = collapse_candidates(&model, &mut cache);
            let Some(&(a, b, j, e)) = candidates.first() else {
                break;
            };
            let (c, record) = collapse_pair(ty, &mut model, a, b, j, e, report.collapses.len());
            cache.invalidate_subtree(&model, c);
            report.collapses.push(record);
        }
        split = attach.is_some() || !report.collapses.is_empty();
        cjr = common_rotation_sets(ty, &model, budget, extra, params.average_bone, None, None);
    }
    report.merges = cjr.merges.len();
    report.max_merge_deviation = cjr
        .merges
        .iter()
        .map(|m: &Merge| m.deviation)
        .fold(0.0, f32::max);
    report.max_merge_displacement = cjr
        .merges
        .iter()
        .map(|m| m.displacement)
        .fold(0.0, f32::max);
    let follow = apply_common_rotations(&mut model, &cjr, params.average_bone);
    report.clouds = cjr.sets.len() + extra;
    if let Some(n) = params.clouds
        && report.clouds > n
    {
        report.stopped_by = Some(stop_reason(&model, report.clouds, n));
    }
    report.trunk_on_original_skeleton = split;
    report.attach_tolerance = params.attach_tolerance;
    report.bones_changed = model.nodes.iter().filter(|n| n.alive && n.changed).count();
    let rig = materialize(tree, &model, clip, &sampled.times, sampled.period, split);
    let mut sets: Vec<CloudSet> = follow
        .iter()
        .map(|&f| CloudSet {
            node: rig.map[f],
            members: model.nodes[f].foliage.clone(),
        })
        .collect();
    if extra > 0 {
        sets.push(CloudSet {
            node: None,
            members: model.unbound.clone(),
        });
    }
    measure(&model, &follow, split, &mut report);
    report.t_simplify = t0.elapsed().as_secs_f64();
    Ok(SimplifiedSkeleton { rig, sets, report })
}

/// The budget could not be met: name the sibling groups left and their skeleton levels.
fn stop_reason(model: &SkeletonModel, clouds: usize, budget: usize) -> String {
    let levels: BTreeSet<usize> = model
        .foliage_nodes()
        .iter()
        .map(|&i| model.depth(i))
        .collect();
    let deepest = levels.iter().next_back().copied().unwrap_or(0);
    format!(
        "budget {budget} clouds not reachable: {clouds} remain, one per sibling group of \
         foliage bones, and no two non-terminal siblings are left to collapse; foliage sits on \
         {} skeleton level(s) (deepest {deepest}), and without parent/child collapse every \
         level keeps at least one cloud (spec §6.6)",
        levels.len()
    )
}

/// Foliage error and detachment of the simplified skeleton, measured on the representatives.
fn measure(model: &SkeletonModel, follow: &[usize], split: bool, report: &mut SkeletonReport) {
    let worlds = model.worlds();
    let rest = model.rest_world();
    let n = model.samples;
    let reps: Vec<(usize, &crate::model::Representative)> = follow
        .iter()
        .flat_map(|&f| {
            model
                .node_representatives(f)
                .into_iter()
                .map(move |r| (f, r))
        })
        .collect();
    let per: Vec<(f32, f32, f32, f32)> = reps
        .par_iter()
        .map(|&(f, r)| {
            let to_rest: Vec<Mat4> = (0..n).map(|s| rest[f] * worlds[s][f].inverse()).collect();
            let reference = r
                .trajectory
                .iter()
                .zip(&to_rest)
                .map(|(p, m)| m.transform_point3(*p))
                .sum::<Vec3>()
                / n as f32;
            let rest_inv = rest[f].inverse();
            let carried: Vec<Vec3> = (0..n)
                .map(|s| (worlds[s][f] * rest_inv).transform_point3(reference))
                .collect();
            let (mut e2, mut emax) = (0.0f32, 0.0f32);
            for (c, p) in carried.iter().zip(&r.trajectory) {
                let d = c.distance(*p);
                e2 += d * d;
                emax = emax.max(d);
            }
            // The wood of the leaf's input bone: the input skeleton after a collapse, the
            // simplified one (same node) otherwise.
            let wood = |s: usize| {
                if split || !model.nodes[r.node].alive {
                    model.input_world[s][r.node]
                } else {
                    worlds[s][r.node]
                }
            };
            let local: Vec<Vec3> = (0..n)
                .map(|s| wood(s).inverse().transform_point3(carried[s]))
                .collect();
            let mean = local.iter().sum::<Vec3>() / n as f32;
            let (mut d2, mut dmax) = (0.0f32, 0.0f32);
            for l in &local {
                let d = l.distance(mean);
                d2 += d * d;
                dmax = dmax.max(d);
            }
            (
                e2 / n as f32 * r.weight,
                emax,
                d2 / n as f32 * r.weight,
                dmax,
            )
        })
        .collect();
    let total: f32 = reps.iter().map(|(_, r)| r.weight).sum::<f32>().max(1e-12);
    report.foliage_error_rms = (per.iter().map(|p| p.0).sum::<f32>() / total).sqrt();
    report.foliage_error_max = per.iter().map(|p| p.1).fold(0.0, f32::max);
    report.detachment_rms = (per.iter().map(|p| p.2).sum::<f32>() / total).sqrt();
    report.detachment_max = per.iter().map(|p| p.3).fold(0.0, f32::max);
}
