//! Non-terminal sibling collapse (spec animated-billboard-clouds §6.3, thesis §7.3): two
//! sibling bones that both carry branches with foliage become one bone turning by their
//! average rotation; their children become siblings at a common end joint (the minimiser of
//! `E_T`, [`crate::end_joint`]) and each child gets the rotation about that joint that best
//! keeps its own frame where it was.
//!
//! \[ENG\] joint animation: the thesis maps every triangle onto its centroid rotation sphere and
//! averages the per-triangle rotations per bone, admitting the average is not guaranteed to be
//! good. Here each child's rotation at each sample is the least-squares rotation about the end
//! joint of all the foliage its frame carries (Horn's method with a fixed centre): the best
//! single rotation per bone by construction. The fit follows the child's *frame* (its foliage
//! carried rigidly by it), not the foliage's full motion, so deeper bones keep their own
//! rotations on top unchanged.

use std::collections::HashMap;

use frond_scene::Trs;
use frond_scene::rigid_fit::pivot_rotation_fit;
use glam::{DVec3, Mat3, Mat4, Quat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::description::BoneDescriptionType;
use crate::end_joint::EndJointSums;
use crate::model::{SkNode, SkeletonModel};

/// One collapse, for the report.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CollapseRecord {
    /// Name of the first of the two sibling bones collapsed.
    pub a: String,
    /// Name of the second.
    pub b: String,
    /// The new bone's name.
    pub into: String,
    /// Depth of the collapsed siblings (1 = a root).
    pub depth: usize,
    /// `E_T` at the chosen end joint.
    pub end_joint_error: f64,
    /// The common end joint, in the parent's rest frame.
    pub end_joint: [f32; 3],
}

/// `E_T` sums of the foliage node `i`'s children animate, cached until the node's frame or
/// subtree changes.
#[derive(Default)]
pub struct EndJointCache {
    sums: HashMap<usize, EndJointSums>,
}

impl EndJointCache {
    /// Forgets the sums of every node in `root`'s subtree (their frames changed).
    pub fn invalidate_subtree(&mut self, model: &SkeletonModel, root: usize) {
        let mut stack = vec![root];
        while let Some(i) = stack.pop() {
            self.sums.remove(&i);
            stack.extend(model.nodes[i].children.iter().copied());
        }
    }
}

/// The sums of node `i`'s descendants' foliage (not its own), in the frame that turns with
/// `i` (where its children's pivots stay put), in its parent's rest coordinates: the end joint
/// is fixed in the collapsed bone, which turns like both siblings on average.
fn descendant_sums(
    model: &SkeletonModel,
    worlds: &[Vec<Mat4>],
    rest: &[Mat4],
    i: usize,
) -> EndJointSums {
    let parent_rest_inv = model.nodes[i]
        .parent
        .map_or(Mat4::IDENTITY, |p| rest[p].inverse());
    let to_parent: Vec<Mat4> = (0..model.samples)
        .map(|s| parent_rest_inv * rest[i] * worlds[s][i].inverse())
        .collect();
    let mut sums = EndJointSums::default();
    for &c in &model.nodes[i].children {
        if !model.nodes[c].alive {
            continue;
        }
        for rep in model.subtree_representatives(c) {
            let q: Vec<Vec3> = rep
                .trajectory
                .iter()
                .zip(&to_parent)
                .map(|(p, m)| m.transform_point3(*p))
                .collect();
            sums.add_trajectory(&q, f64::from(rep.weight));
        }
    }
    sums
}

/// Every pair of non-terminal siblings (both with children animating foliage), with the end
/// joint and `E_T` of collapsing them; least `E_T` first (ties by node index).
pub fn collapse_candidates(
    model: &SkeletonModel,
    cache: &mut EndJointCache,
) -> Vec<(usize, usize, DVec3, f64)> {
    let counts = model.animated_counts();
    let worlds = model.worlds();
    let rest = model.rest_world();
    let order = model.order();
    let non_terminal: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&i| model.non_terminal(i, &counts))
        .collect();
    let missing: Vec<usize> = non_terminal
        .iter()
        .copied()
        .filter(|i| !cache.sums.contains_key(i))
        .collect();
    let fresh: Vec<(usize, EndJointSums)> = missing
        .par_iter()
        .map(|&i| (i, descendant_sums(model, &worlds, &rest, i)))
        .collect();
    cache.sums.extend(fresh);
    let mut out = Vec::new();
    for (x, &a) in non_terminal.iter().enumerate() {
        for &b in &non_terminal[x + 1..] {
            if model.nodes[a].parent != model.nodes[b].parent {
                continue;
            }
            let sums = cache.sums[&a].plus(&cache.sums[&b]);
            let guess = children_pivot_mean(model, &rest, &counts, &[a, b]);
            let (j, e) = sums.solve(guess);
            out.push((a.min(b), a.max(b), j, e));
        }
    }
    out.sort_by(|x, y| x.3.total_cmp(&y.3).then((x.0, x.1).cmp(&(y.0, y.1))));
    out
}

/// Mean rest position of the children's pivots of `nodes` in their parent's rest frame,
/// weighted by the foliage each child animates (the regularisation's guess for `E_T`).
fn children_pivot_mean(
    model: &SkeletonModel,
    rest: &[Mat4],
    counts: &[usize],
    nodes: &[usize],
) -> DVec3 {
    let parent_inv = model.nodes[nodes[0]]
        .parent
        .map_or(Mat4::IDENTITY, |p| rest[p].inverse());
    let (mut sum, mut w) = (DVec3::ZERO, 0.0f64);
    for &n in nodes {
        for &c in &model.nodes[n].children {
            if model.nodes[c].alive && counts[c] > 0 {
                let origin = parent_inv.transform_point3(rest[c].w_axis.truncate());
                sum += origin.as_dvec3() * counts[c] as f64;
                w += counts[c] as f64;
            }
        }
    }
    if w > 0.0 { sum / w } else { DVec3::ZERO }
}

/// Collapses siblings `a` and `b` with end joint `j` (parent's rest frame): returns the new
/// bone and the record.
pub fn collapse_pair<T: BoneDescriptionType>(
    ty: &T,
    model: &mut SkeletonModel,
    a: usize,
    b: usize,
    j: DVec3,
    end_joint_error: f64,
    serial: usize,
) -> (usize, CollapseRecord) {
    let counts = model.animated_counts();
    let worlds_before = model.worlds();
    let rest_before = model.rest_world();
    let (wa, wb) = (counts[a] as f32, counts[b] as f32);
    let da = ty.describe(&model.nodes[a].deltas());
    let db = ty.describe(&model.nodes[b].deltas());
    let deltas = ty.apply(&ty.average(&[&da, &db], &[wa, wb]));
    let total = (wa + wb).max(1.0);
    let pivot =
        (model.nodes[a].rest.translation * wa + model.nodes[b].rest.translation * wb) / total;
    let parent = model.nodes[a].parent;
    let mut foliage: Vec<usize> = model.nodes[a]
        .foliage
        .iter()
        .chain(&model.nodes[b].foliage)
        .copied()
        .collect();
    foliage.sort_unstable();
    let into = format!("frond_collapse_{serial}");
    let record = CollapseRecord {
        a: model.nodes[a].name.clone(),
        b: model.nodes[b].name.clone(),
        into: into.clone(),
        depth: model.depth(a),
        end_joint_error,
        end_joint: j.as_vec3().to_array(),
    };
    let children: Vec<usize> = model.nodes[a]
        .children
        .iter()
        .chain(&model.nodes[b].children)
        .copied()
        .filter(|&c| model.nodes[c].alive)
        .collect();
    for n in [a, b] {
        model.nodes[n].alive = false;
        model.nodes[n].foliage.clear();
        model.nodes[n].children.clear();
    }
    if let Some(p) = parent {
        model.nodes[p].children.retain(|&c| c != a && c != b);
    }
    let c_node = model.push(SkNode::turning(
        into,
        parent,
        pivot,
        &deltas,
        model.samples,
        foliage,
    ));
    let rest = model.nodes[c_node].rest;
    // World frames of the new bone.
    let parent_rest = parent.map_or(Mat4::IDENTITY, |p| rest_before[p]);
    let c_rest = parent_rest * rest.matrix();
    let c_rest_inv = c_rest.inverse();
    let c_world: Vec<Mat4> = (0..model.samples)
        .map(|s| {
            parent.map_or(Mat4::IDENTITY, |p| worlds_before[s][p])
                * model.nodes[c_node].track[s].matrix()
        })
        .collect();
    let j_local = j.as_vec3() - pivot;
    let j_world = parent_rest.transform_point3(j.as_vec3());
    for c in children {
        if counts[c] == 0 {
            // Carries no foliage: the foliage skeleton does not need it (the wood keeps the
            // input's skeleton after a collapse, spec §6.3 "loss of correspondence").
            kill_subtree(model, c);
            continue;
        }
        let old_rest = rest_before[c];
        let delta = j_world - old_rest.w_axis.truncate();
        let new_rest_world = Mat4::from_translation(delta) * old_rest;
        let local = c_rest_inv * new_rest_world;
        let (scale, rotation, translation) = local.to_scale_rotation_translation();
        // The child's frame carried rigidly: where its foliage would be, in the new bone's
        // frame, at every sample (target), and at rest (source).
        let reps: Vec<(Vec3, f32)> = model
            .subtree_representatives(c)
            .iter()
            .map(|r| (r.rest, r.weight))
            .collect();
        let from: Vec<Vec3> = reps
            .iter()
            .map(|(p, _)| c_rest_inv.transform_point3(*p))
            .collect();
        let weights: Vec<f32> = reps.iter().map(|(_, w)| *w).collect();
        let old_rest_inv = old_rest.inverse();
        let rotations: Vec<Quat> = (0..model.samples)
            .into_par_iter()
            .map(|s| {
                let carry = c_world[s].inverse() * worlds_before[s][c] * old_rest_inv;
                let to: Vec<Vec3> = reps
                    .iter()
                    .map(|(p, _)| carry.transform_point3(*p))
                    .collect();
                pivot_rotation_fit(j_local, &from, &to, &weights)
            })
            .collect();
        let linear_inv = Mat3::from_mat4(old_rest).inverse();
        let shift = -(linear_inv * delta);
        let node = &mut model.nodes[c];
        node.parent = Some(c_node);
        node.rest = Trs {
            translation,
            rotation,
            scale,
        };
        node.track = rotations
            .iter()
            .map(|r| Trs {
                translation,
                rotation: (*r * rotation).normalize(),
                scale,
            })
            .collect();
        node.changed = true;
        let grandchildren = node.children.clone();
        for g in grandchildren {
            let gn = &mut model.nodes[g];
            gn.rest.translation += shift;
            for t in &mut gn.track {
                t.translation += shift;
            }
            gn.changed = true;
        }
        model.nodes[c_node].children.push(c);
    }
    (c_node, record)
}

fn kill_subtree(model: &mut SkeletonModel, root: usize) {
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        model.nodes[i].alive = false;
        stack.extend(model.nodes[i].children.iter().copied());
    }
}
