//! The joint budget of a LOD: at most `joints` skin joints and `channels` animated channels,
//! reached by merging motion where it shows least (spec view-dependent-hierarchies-gpu
//! §2.3–2.4: error measured in pixels at the LOD's size).
//!
//! A LOD's joints are the rig nodes its wood vertices and billboards follow, one joint per
//! distinct own motion of a billboard, and one static joint for what follows nothing (what
//! `frond-export` writes, counted by [`count`]). Two merges lower that count:
//! - **collapse** a rig node: everything it carried (wood vertices, billboards) becomes rigid
//!   with a surviving node, its nearest surviving ancestor or, when all it carries is rigid
//!   with it (no billboard with an own motion relative to its frame, in any animation mode),
//!   whichever of the surviving joints nearest it moves most like it. The points are
//!   placed where they sit relative to that node over the loop (the rigid placement that best
//!   fits their motion, least squares over the loop's samples), not where they sit at rest: a
//!   bough that leans with the wind all loop keeps its lean, and a twig whose sibling sways as
//!   it does follows the sibling rather than the branch both grow from. The rig keeps its
//!   hierarchy; only what the node carried moves;
//! - **attach** a group of billboards sharing one own motion to the surviving node whose motion
//!   fits theirs best (a rigid re-fit of the quad in that node's frame): the skeleton's motions
//!   are the shared motions own motions cluster onto, and need no channel of their own.
//!
//! Each merge has an error: the farthest any carried point (corners of the carried points'
//! bounding box, which bound an affine map's displacement) moves over the loop's samples,
//! in world units. Merges are applied smallest error first (a lazy priority queue: errors only
//! grow as nodes absorb others), every merge under half a pixel regardless of the budget (motion
//! nobody can see is not worth a joint), then more until the budget holds. The order does not
//! depend on the budget, so a smaller budget merges a superset of what a larger one does.
//!
//! Last, each wood vertex and card corner that followed a removed node gets skin weights
//! fitted over the kept joints near it ([`crate::wood_skins`]), where they follow its input
//! path more closely than the rigid placement does.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use frond_scene::rigid_fit::rigid_fit;
use frond_scene::wood::{NO_BONE, WoodMesh};
use frond_scene::{Rig, Tree};
use glam::{Affine3A, Mat4, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Deserializer, Serialize};

use crate::contract::{AnimatedBillboardCloud, RigidMotion};
use crate::skin_fit::SkinFit;
use crate::wood_skins::{InputSkins, KeptJoints, refit_skins, used_vertices};

/// What a LOD may spend on animation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct JointCap {
    /// Skin joints (rig joints, motion joints and the static joint together).
    pub joints: usize,
    /// Animated channels written over all clips.
    pub channels: usize,
}

/// How the billboards' motion is written, which decides what joints they need.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BillboardAnimation {
    /// Skinned; each distinct own motion is a joint of its own (with a translation and a
    /// rotation channel), motionless billboards use the joint of the node they follow.
    Joints,
    /// Skinned to the node each follows; own motion comes from a coefficient texture.
    Spectral,
    /// Off the skin: vertex animation textures play them.
    Vat,
}

/// What the joint budget merged.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JointMerges {
    /// Rig nodes collapsed into an ancestor because their motion moved nothing half a pixel.
    pub nodes_collapsed_unseen: usize,
    /// Rig nodes collapsed to meet the budget.
    pub nodes_collapsed_for_budget: usize,
    /// Own motions replaced by following a rig node (each group of billboards sharing one).
    pub motions_attached: usize,
    /// Largest error of a merge (world units): how far a carried point strays from where its
    /// own motion put it; infinite (written `null`) when the budget forced a merge no node
    /// could carry.
    #[serde(deserialize_with = "null_as_infinite")]
    pub max_error: f32,
}

/// Reads an error written `null` (JSON has no infinity) as infinite.
fn null_as_infinite<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    Ok(Option::<f32>::deserialize(d)?.unwrap_or(f32::INFINITY))
}

/// The skin joints and animated channels a LOD would be written with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct AnimationCount {
    /// Skin joints: rig joints, motion joints and the static joint together.
    pub joints: usize,
    /// Animated channels over every clip written.
    pub channels: usize,
}

/// Key of an own motion: its exact bits (what export groups joints by).
fn motion_key(m: &RigidMotion) -> Vec<u32> {
    match m {
        RigidMotion::Sampled(frames) => frames
            .iter()
            .flat_map(|a| a.to_cols_array())
            .map(f32::to_bits)
            .collect(),
        RigidMotion::Spectral(s) => {
            let mut k = vec![s.samples as u32];
            for a in &s.axes {
                k.push(a.amplitudes.len() as u32);
                k.extend(a.frequencies.iter().map(|&f| f as u32));
                k.extend(a.amplitudes.iter().map(|f| f.to_bits()));
                k.extend(a.phases.iter().map(|f| f.to_bits()));
            }
            k
        }
    }
}

/// Groups of billboards sharing one own motion (and the node it is relative to), in order of
/// their first billboard.
fn motion_groups(cloud: &AnimatedBillboardCloud) -> Vec<Vec<usize>> {
    let mut index: HashMap<(Option<usize>, Vec<u32>), usize> = HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, b) in cloud.billboards.iter().enumerate() {
        if let Some(m) = &b.motion {
            let g = *index.entry((b.follows, motion_key(m))).or_insert_with(|| {
                groups.push(Vec::new());
                groups.len() - 1
            });
            groups[g].push(i);
        }
    }
    groups
}

/// Joints and channels of `cloud` with `wood` as `frond-export` writes them, billboards written
/// as `mode` says.
pub fn count(
    cloud: &AnimatedBillboardCloud,
    wood: &WoodMesh,
    mode: BillboardAnimation,
) -> AnimationCount {
    let n = cloud.rig.nodes.len();
    let mut joint = vec![false; n];
    let mut hierarchy = vec![false; n];
    let mut static_joint = false;
    for b in wood.used_bones() {
        match (b as usize) < n && b != NO_BONE {
            true => joint[b as usize] = true,
            false => static_joint = true,
        }
    }
    let groups = match mode {
        BillboardAnimation::Joints => motion_groups(cloud),
        _ => Vec::new(),
    };
    for b in cloud
        .billboards
        .iter()
        .filter(|_| mode != BillboardAnimation::Vat)
    {
        match (
            b.follows,
            mode == BillboardAnimation::Joints && b.motion.is_some(),
        ) {
            (Some(f), false) => joint[f] = true,
            (None, false) => static_joint = true,
            (Some(f), true) => hierarchy[f] = true,
            (None, true) => {}
        }
    }
    let joints = joint.iter().filter(|&&j| j).count() + groups.len() + usize::from(static_joint);
    let kept = cloud.rig.with_ancestors(|i| joint[i] || hierarchy[i]);
    let clips: Vec<usize> = if !groups.is_empty() || cloud.rig_resampled {
        cloud.clock.clip.into_iter().collect()
    } else {
        (0..cloud.rig.clips.len()).collect()
    };
    let rig_channels: usize = clips
        .iter()
        .filter_map(|&c| cloud.rig.clips.get(c))
        .map(|c| c.channels.iter().filter(|ch| kept[ch.node]).count())
        .sum();
    AnimationCount {
        joints,
        channels: rig_channels + 2 * groups.len(),
    }
}

/// The rig's motion at the loop's samples: `carry(n, s)` takes rest-pose points following
/// node `n` (None: the world) to sample `s`.
pub struct RigFrames<'a> {
    /// World matrix of every rig node at every sample (`worlds[s][n]`).
    pub worlds: &'a [Vec<Mat4>],
    /// Inverse rest-pose world matrix of every rig node.
    pub rest_inv: &'a [Mat4],
}

impl RigFrames<'_> {
    /// `W_n(s) · Rest_n⁻¹`, or the identity for the world.
    pub fn carry(&self, node: Option<usize>, s: usize) -> Mat4 {
        match node {
            Some(b) => self.worlds[s][b] * self.rest_inv[b],
            None => Mat4::IDENTITY,
        }
    }
}

/// How well following `node` reproduces an own motion: the rigid placement `Q` (in the node's
/// rest frame) that best fits `corners` carried by `target(s)`, and the farthest a corner then
/// strays over the samples (world units).
pub fn fit_to_node(
    rig: &RigFrames,
    node: Option<usize>,
    corners: &[Vec3],
    target: &dyn Fn(usize, Vec3) -> Vec3,
) -> (f32, Affine3A) {
    let ns = rig.worlds.len();
    let mut from = Vec::with_capacity(corners.len() * ns);
    let mut to = Vec::with_capacity(corners.len() * ns);
    for s in 0..ns {
        let back = rig.carry(node, s).inverse();
        for c in corners {
            from.push(*c);
            to.push(back.transform_point3(target(s, *c)));
        }
    }
    let q = rigid_fit(&from, &to);
    let mut worst = 0.0f32;
    for s in 0..ns {
        let a = rig.carry(node, s);
        for c in corners {
            let p = a.transform_point3(q.transform_point3(*c));
            worst = worst.max(p.distance(target(s, *c)));
        }
    }
    (worst, q)
}

/// How many surviving joints, nearest first, a collapsing node's points may move to besides
/// its surviving parent.
const NEAREST_JOINTS: usize = 16;

/// Axis-aligned box of carried points (empty: nothing carried).
#[derive(Clone, Copy, Debug)]
struct Box3 {
    lo: Vec3,
    hi: Vec3,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        lo: Vec3::splat(f32::INFINITY),
        hi: Vec3::splat(f32::NEG_INFINITY),
    };
    fn add(&mut self, p: Vec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }
    fn union(&mut self, o: &Box3) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }
    fn is_empty(&self) -> bool {
        self.lo.x > self.hi.x
    }
    fn centre(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }
    /// The box around this one's corners moved by `t` (empty stays empty).
    fn placed(&self, t: Affine3A) -> Box3 {
        let mut b = Box3::EMPTY;
        if !self.is_empty() {
            for c in self.corners() {
                b.add(t.transform_point3(c));
            }
        }
        b
    }
    fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|k| {
            Vec3::new(
                if k & 1 == 0 { self.lo.x } else { self.hi.x },
                if k & 2 == 0 { self.lo.y } else { self.hi.y },
                if k & 4 == 0 { self.lo.z } else { self.hi.z },
            )
        })
    }
}

/// A merge waiting in the queue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Merge {
    Collapse(usize),
    Attach(usize),
}

/// State of the merging.
struct Merger<'a> {
    rig: &'a Rig,
    frames: &'a RigFrames<'a>,
    tree: &'a Tree,
    /// Surviving node of each rig node (itself while it survives; None: the world).
    target: Vec<Option<usize>>,
    /// Points each surviving node carries.
    carried: Vec<Box3>,
    /// Whether each node is a joint (carries something directly).
    joint: Vec<bool>,
    /// Whether everything each node carries is rigid with it (no billboard with an own motion
    /// relative to it), so that a collapse may re-place it.
    rigid: Vec<bool>,
    /// Placement each collapsed node's points took in its target's rest frame (identity while
    /// it survives).
    placement: Vec<Affine3A>,
    groups: Vec<Vec<usize>>,
    attached: Vec<Option<(Option<usize>, Affine3A)>>,
    /// Something follows the world (the static joint is written).
    static_used: bool,
    /// Channels of each node in each clip.
    channels: Vec<Vec<usize>>,
}

impl Merger<'_> {
    /// The node `n` resolves to after collapses.
    fn resolve(&self, mut n: Option<usize>) -> Option<usize> {
        while let Some(c) = n {
            if self.target[c] == Some(c) {
                return Some(c);
            }
            n = self.target[c];
        }
        None
    }

    /// Nearest surviving strict ancestor of `n` in the rig (None: the world).
    fn surviving_parent(&self, n: usize) -> Option<usize> {
        let mut p = self.rig.nodes[n].parent;
        while let Some(c) = p {
            if self.target[c] == Some(c) {
                return Some(c);
            }
            p = self.rig.nodes[c].parent;
        }
        None
    }

    /// Error of collapsing surviving node `n`, and where its points go: into its surviving
    /// parent as they are, or, when everything it carries is rigid with it, into the surviving
    /// joint (its parent or any other) whose motion, at the rigid placement that fits best,
    /// strays least from theirs.
    fn collapse_error(&self, n: usize) -> (f32, Attachment) {
        let p = self.surviving_parent(n);
        let b = &self.carried[n];
        if b.is_empty() {
            return (0.0, (p, Affine3A::IDENTITY));
        }
        let pts = b.corners();
        let mut worst = 0.0f32;
        for s in 0..self.frames.worlds.len() {
            let (a, c) = (self.frames.carry(Some(n), s), self.frames.carry(p, s));
            for x in &pts {
                worst = worst.max(a.transform_point3(*x).distance(c.transform_point3(*x)));
            }
        }
        let mut best = (worst, (p, Affine3A::IDENTITY));
        if !self.rigid[n] {
            return best;
        }
        let target = |s: usize, x: Vec3| self.frames.carry(Some(n), s).transform_point3(x);
        let mut candidates = self.nearest_joints(n);
        candidates.push(p);
        let fits: Vec<(f32, Attachment)> = candidates
            .into_par_iter()
            .map(|c| {
                let (e, q) = fit_to_node(self.frames, c, &pts, &target);
                (e, (c, q))
            })
            .collect();
        for f in fits {
            if f.0 < best.0 || (f.0 == best.0 && f.1.0 < best.1.0) {
                best = f;
            }
        }
        best
    }

    /// The surviving joints other than `n` whose carried points lie nearest `n`'s (box
    /// centres at rest), at most [`NEAREST_JOINTS`]: the nodes whose motion can fit `n`'s,
    /// since a tree's motion varies smoothly through its crown.
    fn nearest_joints(&self, n: usize) -> Vec<Option<usize>> {
        self.joints_nearest(self.carried[n].centre(), n)
    }

    /// The surviving joints other than `except` whose carried points lie nearest `centre`
    /// (box centres at rest), at most [`NEAREST_JOINTS`].
    fn joints_nearest(&self, centre: Vec3, except: usize) -> Vec<Option<usize>> {
        let mut near: Vec<(f32, usize)> = (0..self.target.len())
            .filter(|&c| c != except && self.joint[c] && self.target[c] == Some(c))
            .filter(|&c| !self.carried[c].is_empty())
            .map(|c| (self.carried[c].centre().distance_squared(centre), c))
            .collect();
        let k = NEAREST_JOINTS.min(near.len());
        if k < near.len() {
            near.select_nth_unstable_by(k, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            near.truncate(k);
        }
        near.into_iter().map(|(_, c)| Some(c)).collect()
    }

    /// The kept joints a vertex of rig node `b` may be fitted over once `b` is collapsed: the
    /// joint `b` resolves to, the surviving joints nearest `b`'s points, `b`'s surviving
    /// ancestors that are joints, and the world while something follows it. Only joints the
    /// merges kept: fitting adds no joint.
    fn candidate_pool(&self, b: usize) -> Vec<u32> {
        let survivor = |c: usize| self.joint[c] && self.target[c] == Some(c);
        let mut pool: Vec<Option<usize>> = Vec::new();
        let resolved = self.resolve(Some(b));
        pool.extend(resolved.map(Some));
        let centre = match (self.carried[b].is_empty(), resolved) {
            (false, _) => Some(self.carried[b].centre()),
            (true, Some(r)) if !self.carried[r].is_empty() => Some(self.carried[r].centre()),
            _ => None,
        };
        if let Some(centre) = centre {
            pool.extend(self.joints_nearest(centre, resolved.unwrap_or(b)));
        }
        let mut a = self.rig.nodes[b].parent;
        while let Some(c) = a {
            if survivor(c) {
                pool.push(Some(c));
            }
            a = self.rig.nodes[c].parent;
        }
        if self.static_used {
            pool.push(None);
        }
        let mut out: Vec<u32> = Vec::with_capacity(pool.len());
        for c in pool {
            let c = c.map_or(NO_BONE, |c| c as u32);
            if !out.contains(&c) {
                out.push(c);
            }
        }
        out
    }

    /// Where a point carried by rig node `n` at rest goes with the collapses made: the
    /// placements met on the way to the node it resolves to, composed.
    fn placement_of(&self, mut n: Option<usize>) -> Affine3A {
        let mut t = Affine3A::IDENTITY;
        while let Some(c) = n {
            if self.target[c] == Some(c) {
                break;
            }
            t = self.placement[c] * t;
            n = self.target[c];
        }
        t
    }

    /// The joints and channels with the merges so far (see [`count`]).
    fn count(&self, cloud: &AnimatedBillboardCloud) -> AnimationCount {
        let n = self.target.len();
        let survivor = |i: usize| self.joint[i] && self.target[i] == Some(i);
        let mut hierarchy = vec![false; n];
        let mut groups_left = 0;
        for (g, members) in self.groups.iter().enumerate() {
            if self.attached[g].is_none() {
                groups_left += 1;
                if let Some(f) = self.resolve(cloud.billboards[members[0]].follows) {
                    hierarchy[f] = true;
                }
            }
        }
        let joints =
            (0..n).filter(|&i| survivor(i)).count() + groups_left + usize::from(self.static_used);
        let kept = self.rig.with_ancestors(|i| survivor(i) || hierarchy[i]);
        let clips: Vec<usize> = if groups_left > 0 || cloud.rig_resampled {
            cloud.clock.clip.into_iter().collect()
        } else {
            (0..self.channels.len()).collect()
        };
        let rig_channels: usize = clips
            .iter()
            .filter_map(|&c| self.channels.get(c))
            .map(|per_node| {
                (0..n)
                    .filter(|&i| kept[i])
                    .map(|i| per_node[i])
                    .sum::<usize>()
            })
            .sum();
        AnimationCount {
            joints,
            channels: rig_channels + 2 * groups_left,
        }
    }

    /// Best surviving node for motion group `g` to follow, with the error and placement.
    fn attach_choice(
        &self,
        cloud: &AnimatedBillboardCloud,
        g: usize,
    ) -> (f32, Option<usize>, Affine3A) {
        let members = &self.groups[g];
        let first = &cloud.billboards[members[0]];
        let follows = self.resolve(first.follows);
        let Some(m) = &first.motion else {
            return (0.0, follows, Affine3A::IDENTITY);
        };
        let mut corners: Vec<Vec3> = Vec::new();
        let mut candidates: Vec<Option<usize>> = vec![follows];
        for &i in members {
            let b = &cloud.billboards[i];
            corners.extend(b.quad.corners());
            for &t in &b.triangles {
                let Some(bone) = self.tree.triangles.get(t).and_then(|t| t.bone) else {
                    continue;
                };
                let node = self.tree.bones.get(bone as usize).map(|b| b.node);
                let mut cur = self.resolve(node.filter(|&x| x < self.target.len()));
                while let Some(c) = cur {
                    if candidates.contains(&Some(c)) {
                        break;
                    }
                    candidates.push(Some(c));
                    cur = self.surviving_parent(c);
                }
            }
        }
        let base = first.follows;
        let ns = self.frames.worlds.len();
        // The group's motion and its node's, once per sample: every candidate's fit reads them
        // at each corner, and a spectral motion is a cosine series to evaluate.
        let own = m.samples(ns);
        let carried: Vec<Mat4> = (0..ns).map(|s| self.frames.carry(base, s)).collect();
        let target = |s: usize, x: Vec3| carried[s].transform_point3(own[s].transform_point3(x));
        candidates.sort_unstable();
        candidates
            .into_iter()
            .map(|c| {
                let (e, q) = fit_to_node(self.frames, c, &corners, &target);
                (e, c, q)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .unwrap_or((f32::INFINITY, follows, Affine3A::IDENTITY))
    }
}

/// Merges motion in `cloud` (billboards and rig with the tree's node indices, as after the
/// motion budget's steps) and `wood` (bones as rig node indices) until the LOD has at most
/// `cap` joints and channels, applying every merge under `unseen` world units on the way (the
/// motion no viewer sees, [`crate::motion_budget::ScreenBudget::unseen_motion`]). `frames` is
/// the cloud rig's motion at the loop's samples; `mode` says how the billboards are written
/// (own motions are attached to nodes only when they are joints). Returns what it merged.
pub fn apply_joint_budget(
    cloud: &mut AnimatedBillboardCloud,
    wood: &mut WoodMesh,
    tree: &Tree,
    frames: &RigFrames,
    cap: JointCap,
    unseen: f32,
    mode: BillboardAnimation,
) -> JointMerges {
    let n = cloud.rig.nodes.len();
    let mut carrying = Carrying::of_wood(wood, n);
    carrying.add_billboards(cloud, mode);
    let groups = if mode == BillboardAnimation::Joints {
        motion_groups(cloud)
    } else {
        Vec::new()
    };
    let channels = clip_channels(&cloud.rig, n);
    // The merger reads the rig while the billboards change: its own copy.
    let rig = cloud.rig.clone();
    let mut merger = Merger {
        rig: &rig,
        frames,
        tree,
        target: (0..n).map(Some).collect(),
        carried: carrying.carried,
        joint: carrying.joint,
        rigid: carrying.rigid,
        placement: vec![Affine3A::IDENTITY; n],
        attached: vec![None; groups.len()],
        groups,
        static_used: carrying.static_used,
        channels,
    };
    let merges = merger.merge_within(cloud, cap, unseen);
    apply(&merger, cloud, wood);
    merges
}

/// What each rig node carries before any merge, and which nodes are joints.
struct Carrying {
    /// Points each node carries.
    carried: Vec<Box3>,
    /// Whether each node is a joint (carries something directly).
    joint: Vec<bool>,
    /// Whether each node carries only what is rigid with it.
    rigid: Vec<bool>,
    /// Something follows the world (the static joint is written).
    static_used: bool,
}

impl Carrying {
    /// What the wood's drawn vertices put on the `n` rig nodes: every vertex weighted to a
    /// node makes it a joint that carries the vertex; weights to no node use the static joint.
    fn of_wood(wood: &WoodMesh, n: usize) -> Carrying {
        let mut carried = vec![Box3::EMPTY; n];
        let mut joint = vec![false; n];
        let mut static_used = false;
        let used = used_vertices(wood);
        for (v, (bones, w)) in wood.bones.iter().zip(&wood.weights).enumerate() {
            if !used.get(v).copied().unwrap_or(false) {
                continue;
            }
            for (b, w) in bones.iter().zip(w) {
                if *w <= 0.0 {
                    continue;
                }
                if *b != NO_BONE && (*b as usize) < n {
                    carried[*b as usize].add(wood.positions[v]);
                    joint[*b as usize] = true;
                } else {
                    static_used = true;
                }
            }
        }
        Carrying {
            carried,
            joint,
            rigid: vec![true; n],
            static_used,
        }
    }

    /// Adds the billboards that follow a node (or the world) as `mode` writes them: a
    /// billboard with its own motion written as a joint of its own carries nothing here, and
    /// VAT billboards are off the skin (they carry points but need no joint).
    fn add_billboards(&mut self, cloud: &AnimatedBillboardCloud, mode: BillboardAnimation) {
        let per_motion = mode == BillboardAnimation::Joints;
        for b in &cloud.billboards {
            if per_motion && b.motion.is_some() {
                // The billboard is its own joint, parented on its base node; its motion is
                // relative to that node's frame, which only the node's ancestors share.
                if let Some(f) = b.follows {
                    self.rigid[f] = false;
                }
                continue;
            }
            match b.follows {
                Some(f) => {
                    for c in b.quad.corners() {
                        self.carried[f].add(c);
                    }
                    self.joint[f] |= mode != BillboardAnimation::Vat;
                    self.rigid[f] &= b.motion.is_none();
                }
                None => self.static_used |= mode != BillboardAnimation::Vat,
            }
        }
    }
}

/// Channels of each of the `n` rig nodes in each of `rig`'s clips.
fn clip_channels(rig: &Rig, n: usize) -> Vec<Vec<usize>> {
    rig.clips
        .iter()
        .map(|clip| {
            let mut per_node = vec![0; n];
            for ch in &clip.channels {
                if let Some(c) = per_node.get_mut(ch.node) {
                    *c += 1;
                }
            }
            per_node
        })
        .collect()
}

/// Merges by error (the key orders errors as their bits do: non-negative floats sort so).
type MergeQueue = BinaryHeap<Reverse<(u32, Merge)>>;

/// The queue key of an error: its bits, non-finite errors last.
fn error_key(e: f32) -> u32 {
    if e.is_finite() {
        e.max(0.0).to_bits()
    } else {
        f32::INFINITY.to_bits()
    }
}

/// Where a merge puts the points it moves: the node they follow (None: the world) and their
/// placement in that node's rest frame.
type Attachment = (Option<usize>, Affine3A);

impl Merger<'_> {
    /// Applies merges smallest error first: every one under `unseen`, then more while the count
    /// is over `cap`. Returns what was merged.
    fn merge_within(
        &mut self,
        cloud: &AnimatedBillboardCloud,
        cap: JointCap,
        unseen: f32,
    ) -> JointMerges {
        let mut merges = JointMerges::default();
        let mut heap = self.initial_queue(cloud);
        let mut current = self.count(cloud);
        while let Some(Reverse((k, m))) = heap.pop() {
            let over = current.joints > cap.joints || current.channels > cap.channels;
            if !over && f32::from_bits(k) >= unseen {
                break;
            }
            // Recompute: earlier merges may have grown this one's error.
            let Some((e, choice)) = self.current_error(cloud, m) else {
                continue;
            };
            if error_key(e) > k {
                heap.push(Reverse((error_key(e), m)));
                continue;
            }
            if !over && e >= unseen {
                break;
            }
            match m {
                Merge::Collapse(i) => {
                    self.collapse(i, choice, e < unseen, &mut heap, &mut merges);
                }
                Merge::Attach(g) => {
                    self.attach(cloud, g, choice, &mut heap);
                    merges.motions_attached += 1;
                }
            }
            merges.max_error = merges.max_error.max(e);
            current = self.count(cloud);
        }
        merges
    }

    /// Every possible merge with its error: each joint's collapse, each motion group's
    /// attachment.
    fn initial_queue(&self, cloud: &AnimatedBillboardCloud) -> MergeQueue {
        let mut heap = MergeQueue::new();
        for i in 0..self.target.len() {
            if self.joint[i] {
                heap.push(Reverse((
                    error_key(self.collapse_error(i).0),
                    Merge::Collapse(i),
                )));
            }
        }
        for g in 0..self.groups.len() {
            let (e, _, _) = self.attach_choice(cloud, g);
            heap.push(Reverse((error_key(e), Merge::Attach(g))));
        }
        heap
    }

    /// The error of merge `m` now, with where it would put what it moves; None when the merge
    /// no longer applies (its node was collapsed or is no joint, its group already attached).
    fn current_error(&self, cloud: &AnimatedBillboardCloud, m: Merge) -> Option<(f32, Attachment)> {
        match m {
            Merge::Collapse(i) => {
                if self.target[i] != Some(i) || !self.joint[i] {
                    return None;
                }
                Some(self.collapse_error(i))
            }
            Merge::Attach(g) => {
                if self.attached[g].is_some() {
                    return None;
                }
                let (e, c, q) = self.attach_choice(cloud, g);
                Some((e, (c, q)))
            }
        }
    }

    /// Makes node `n` a joint if it was not, queueing its own collapse.
    fn make_joint(&mut self, n: usize, heap: &mut MergeQueue) {
        if !self.joint[n] {
            self.joint[n] = true;
            heap.push(Reverse((
                error_key(self.collapse_error(n).0),
                Merge::Collapse(n),
            )));
        }
    }

    /// Collapses node `i` into the node of `to` (the world when none), which takes over what
    /// it carried at `to`'s placement; `unseen` when the error is under the motion no viewer
    /// sees.
    fn collapse(
        &mut self,
        i: usize,
        to: Attachment,
        unseen: bool,
        heap: &mut MergeQueue,
        merges: &mut JointMerges,
    ) {
        let (p, placement) = to;
        self.target[i] = p;
        self.placement[i] = placement;
        let b = self.carried[i].placed(placement);
        if p.is_none() && !b.is_empty() {
            self.static_used = true;
        }
        if let Some(p) = p {
            self.carried[p].union(&b);
            self.rigid[p] &= self.rigid[i];
            self.make_joint(p, heap);
        }
        self.joint[i] = false;
        if unseen {
            merges.nodes_collapsed_unseen += 1;
        } else {
            merges.nodes_collapsed_for_budget += 1;
        }
    }

    /// Attaches motion group `g` to the node (or the world) of `to`, which then carries the
    /// group's corners at their new placement.
    fn attach(
        &mut self,
        cloud: &AnimatedBillboardCloud,
        g: usize,
        to: Attachment,
        heap: &mut MergeQueue,
    ) {
        let (c, q) = to;
        self.attached[g] = Some((c, q));
        if c.is_none() {
            self.static_used = true;
        }
        if let Some(c) = c {
            let mut b = Box3::EMPTY;
            for &i in &self.groups[g] {
                for x in cloud.billboards[i].quad.corners() {
                    b.add(q.transform_point3(x));
                }
            }
            self.carried[c].union(&b);
            self.make_joint(c, heap);
        }
    }
}

/// Writes the merges into the billboards and the wood's skin: what follows a collapsed node
/// is moved to its placement in the node it resolves to and follows that node.
fn apply(merger: &Merger, cloud: &mut AnimatedBillboardCloud, wood: &mut WoodMesh) {
    for (g, members) in merger.groups.iter().enumerate() {
        if let Some((c, q)) = merger.attached[g] {
            for &i in members {
                let b = &mut cloud.billboards[i];
                b.quad = b.quad.transformed(q);
                b.follows = c;
                b.motion = None;
            }
        }
    }
    for b in &mut cloud.billboards {
        if b.motion.is_none() {
            b.quad = b.quad.transformed(merger.placement_of(b.follows));
        }
        b.follows = merger.resolve(b.follows);
    }
    let removed = (0..merger.target.len()).any(|b| merger.target[b] != Some(b));
    let before = removed.then(|| InputSkins::of(wood));
    place_wood(merger, wood);
    for (bones, weights) in wood.bones.iter_mut().zip(wood.weights.iter_mut()) {
        let mut merged: Vec<(u32, f32)> = Vec::with_capacity(4);
        for (b, w) in bones.iter().zip(weights.iter()) {
            if *w <= 0.0 {
                continue;
            }
            let nb = if *b == NO_BONE || (*b as usize) >= merger.target.len() {
                NO_BONE
            } else {
                merger
                    .resolve(Some(*b as usize))
                    .map_or(NO_BONE, |x| x as u32)
            };
            match merged.iter_mut().find(|(x, _)| *x == nb) {
                Some(slot) => slot.1 += *w,
                None => merged.push((nb, *w)),
            }
        }
        merged.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let first = merged.first().map_or(NO_BONE, |m| m.0);
        for k in 0..4 {
            let (b, w) = merged.get(k).copied().unwrap_or((first, 0.0));
            bones[k] = b;
            weights[k] = w;
        }
    }
    if let Some(before) = before {
        fit_wood_skins(merger, wood, &before);
    }
}

/// Refits the skins of the wood's vertices (and cards' corners) whose joints the merges
/// removed, over the joints they kept ([`crate::wood_skins`]). `before` is the wood as it was
/// before the merges.
fn fit_wood_skins(merger: &Merger, wood: &mut WoodMesh, before: &InputSkins) {
    let n = merger.target.len();
    let kept = KeptJoints {
        pools: (0..n).map(|b| merger.candidate_pool(b)).collect(),
        removed: (0..n).map(|b| merger.target[b] != Some(b)).collect(),
    };
    refit_skins(&SkinFit::new(merger.frames), &kept, wood, before);
}

/// Moves each wood vertex (and card corner) to the blend of its bones' placements by weight,
/// as linear blend skinning blends their motions, so a vertex shared by a collapsed node and a
/// surviving one stays between the two (no crack where a bough meets its branch).
fn place_wood(merger: &Merger, wood: &mut WoodMesh) {
    let n = merger.target.len();
    let placements: Vec<Affine3A> = (0..n).map(|i| merger.placement_of(Some(i))).collect();
    let moved = |b: u32| {
        placements
            .get(b as usize)
            .filter(|_| b != NO_BONE)
            .copied()
            .unwrap_or(Affine3A::IDENTITY)
    };
    for (v, (bones, weights)) in wood.bones.iter().zip(&wood.weights).enumerate() {
        if bones.iter().all(|&b| moved(b) == Affine3A::IDENTITY) {
            continue;
        }
        let (mut p, mut nrm) = (Vec3::ZERO, Vec3::ZERO);
        for (b, w) in bones.iter().zip(weights) {
            let t = moved(*b);
            p += *w * t.transform_point3(wood.positions[v]);
            if let Some(n0) = wood.normals.get(v) {
                nrm += *w * t.transform_vector3(*n0);
            }
        }
        wood.positions[v] = p;
        if let Some(n0) = wood.normals.get_mut(v) {
            *n0 = nrm.try_normalize().unwrap_or(*n0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::{AnimatedBillboard, BillboardTexture, LoopClock};
    use frond_billboard::{Plane, Quad};
    use frond_scene::rig::{Channel, Clip, Interpolation, Node, Property, Trs};
    use frond_scene::wood::WoodPrimitive;
    use frond_scene::{Bounds, Vertices};
    use glam::{Quat, Vec4};

    /// A static root with `children` at (0, 1, 0), each turning about z through `angles`
    /// (radians) at times 0, ½ and 1 of a one-second clip.
    fn rig(children: &[[f32; 3]]) -> Rig {
        let node = |name: &str, parent: Option<usize>, children: Vec<usize>, at: Vec3| Node {
            name: name.into(),
            parent,
            children,
            rest: Trs {
                translation: at,
                ..Trs::IDENTITY
            },
            bone: None,
            extras: None,
        };
        let mut nodes = vec![node(
            "root",
            None,
            (1..=children.len()).collect(),
            Vec3::ZERO,
        )];
        let mut channels = Vec::new();
        for (i, angles) in children.iter().enumerate() {
            nodes.push(node(&format!("c{i}"), Some(0), Vec::new(), Vec3::Y));
            channels.push(Channel {
                node: i + 1,
                property: Property::Rotation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 0.5, 1.0],
                values: angles
                    .iter()
                    .map(|&a| Vec4::from(Quat::from_rotation_z(a)))
                    .collect(),
            });
        }
        Rig {
            order: (0..nodes.len()).collect(),
            nodes,
            clips: vec![Clip {
                name: "wind".into(),
                start: 0.0,
                end: 1.0,
                channels,
            }],
        }
    }

    /// A small triangle near `at` for each `(node, at)`, skinned wholly to that node.
    fn wood(pieces: &[(u32, Vec3)]) -> WoodMesh {
        let mut w = WoodMesh::default();
        for (k, &(node, at)) in pieces.iter().enumerate() {
            for d in [Vec3::ZERO, 0.1 * Vec3::X, 0.1 * Vec3::Y] {
                w.positions.push(at + d);
                w.normals.push(Vec3::Z);
                w.uvs.push(glam::Vec2::ZERO);
                w.bones.push([node; 4]);
                w.weights.push([1.0, 0.0, 0.0, 0.0]);
            }
            let base = 3 * k as u32;
            w.primitives.push(WoodPrimitive {
                material: 0,
                indices: vec![base, base + 1, base + 2],
            });
        }
        w
    }

    /// Runs the joint budget on `wood` over `rig` with `joints`, half a pixel being `half`.
    fn budget(rig: Rig, wood: &mut WoodMesh, joints: usize, half: f32) -> JointMerges {
        budget_with(rig, wood, Vec::new(), joints, half).0
    }

    /// [`budget`] with `billboards` in the cloud (each billboard its own joint, `Joints`
    /// mode); also the cloud as the budget left it.
    fn budget_with(
        rig: Rig,
        wood: &mut WoodMesh,
        billboards: Vec<AnimatedBillboard>,
        joints: usize,
        half: f32,
    ) -> (JointMerges, AnimatedBillboardCloud) {
        let clock = LoopClock {
            clip: Some(0),
            start: 0.0,
            period: 1.0,
            samples: 8,
        };
        let tree = Tree {
            source: "test.glb".into(),
            rig: rig.clone(),
            bones: Vec::new(),
            bindings: Vec::new(),
            vertices: Vertices::default(),
            triangles: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            source_textures: Vec::new(),
            images: Vec::new(),
            classification: Vec::new(),
            foliage_reassigned: 0,
            warnings: Vec::new(),
            bounds: Bounds::of([]),
        };
        let mut cloud = AnimatedBillboardCloud {
            method: "cards".into(),
            epsilon: half,
            billboards,
            atlas: Default::default(),
            texels_per_unit: 0.0,
            density_reduced: false,
            rig,
            rig_resampled: false,
            clock: clock.clone(),
            playable_clips: vec![0],
        };
        let worlds = crate::cloud_build::sampled_worlds(&cloud.rig, &clock);
        let rest_inv: Vec<Mat4> = cloud.rig.rest_world().iter().map(|m| m.inverse()).collect();
        let frames = RigFrames {
            worlds: &worlds,
            rest_inv: &rest_inv,
        };
        let cap = JointCap {
            joints,
            channels: usize::MAX,
        };
        let merges = apply_joint_budget(
            &mut cloud,
            wood,
            &tree,
            &frames,
            cap,
            half,
            BillboardAnimation::Joints,
        );
        (merges, cloud)
    }

    #[test]
    fn a_collapsed_node_keeps_the_lean_it_holds_all_loop() {
        // The child leans 0.5 rad all loop: following the static root at rest would misplace
        // its wood by about half a unit in every frame; placed where it leans, by nothing.
        let lean = [0.5, 0.5, 0.5];
        let at = Vec3::new(0.0, 2.0, 0.0);
        let mut w = wood(&[(1, at)]);
        let merges = budget(rig(&[lean]), &mut w, usize::MAX, 0.01);
        assert_eq!(merges.nodes_collapsed_unseen, 2, "{merges:?}");
        assert!(merges.max_error < 1e-4, "{merges:?}");
        let leaned = Vec3::Y + Quat::from_rotation_z(0.5) * (at - Vec3::Y);
        assert!(
            w.positions[0].distance(leaned) < 1e-4,
            "{:?}",
            w.positions[0]
        );
        let normal = Quat::from_rotation_z(0.5) * Vec3::Z;
        assert!(w.normals[0].distance(normal) < 1e-4);
        assert_eq!(w.bones[0][0], NO_BONE, "static after the collapse");
    }

    #[test]
    fn a_collapsed_node_follows_the_joint_that_moves_like_it() {
        // Two twigs on one pivot sway alike; one joint is allowed. The root does not move, so
        // following it would put the collapsed twig's wood off by its sway; the other twig
        // carries it exactly.
        let sway = [0.0, 0.4, 0.0];
        let mut w = wood(&[(1, Vec3::new(0.0, 2.0, 0.0)), (2, Vec3::new(0.3, 2.0, 0.0))]);
        let before = w.positions.clone();
        let merges = budget(rig(&[sway, sway]), &mut w, 1, 0.01);
        assert_eq!(merges.nodes_collapsed_unseen, 1, "{merges:?}");
        assert!(merges.max_error < 1e-4, "{merges:?}");
        let followed: Vec<u32> = w.bones.iter().map(|b| b[0]).collect();
        assert!(followed.iter().all(|&b| b == followed[0] && b != NO_BONE));
        for (p, q) in w.positions.iter().zip(&before) {
            assert!(p.distance(*q) < 1e-4, "{p} moved from {q}");
        }
    }

    #[test]
    fn the_base_of_a_billboard_group_with_its_own_motion_stays_where_the_motion_is_relative_to() {
        // Two twigs sway alike, so either could carry the other's wood exactly. Twig 2 is also
        // the base of a billboard whose own motion is relative to twig 2's frame: were twig 2
        // collapsed sideways into twig 1, the billboard would ride twig 1's frame with no
        // placement. Twig 1 collapses into twig 2 instead, and the billboard keeps its base.
        let sway = [0.0, 0.4, 0.0];
        let mut w = wood(&[(1, Vec3::new(0.0, 2.0, 0.0)), (2, Vec3::new(0.3, 2.0, 0.0))]);
        let plane = Plane {
            normal: Vec3::Z,
            offset: 0.0,
        };
        let shake = (0..8)
            .map(|s| Affine3A::from_translation(Vec3::X * 0.5 * (s as f32 * 0.8).sin()))
            .collect();
        let billboard = AnimatedBillboard {
            quad: Quad {
                plane,
                center: Vec3::new(0.1, 2.2, 0.0),
                axis_u: Vec3::X,
                axis_v: Vec3::Y,
                half_size: glam::Vec2::splat(0.1),
            },
            uv: [glam::Vec2::ZERO; 4],
            texture: BillboardTexture::Atlas,
            follows: Some(2),
            motion: Some(RigidMotion::Sampled(shake)),
            triangles: Vec::new(),
        };
        let (merges, cloud) = budget_with(
            rig(&[sway, sway]),
            &mut w,
            vec![billboard],
            usize::MAX,
            0.01,
        );
        assert_eq!(merges.nodes_collapsed_unseen, 1, "{merges:?}");
        assert!(w.bones.iter().all(|b| b[0] == 2), "{:?}", w.bones);
        assert_eq!(cloud.billboards[0].follows, Some(2));
        assert!(cloud.billboards[0].motion.is_some());
    }

    /// A static root with children each translating over a one-second clip: child `i` by
    /// `moves[i]` at times 0, ½ and 1 (back where it started).
    fn translating(moves: &[Vec3]) -> Rig {
        let mut r = rig(&vec![[0.0; 3]; moves.len()]);
        for (ch, m) in r.clips[0].channels.iter_mut().zip(moves) {
            ch.property = Property::Translation;
            ch.values = vec![Vec4::ZERO, m.extend(0.0), Vec4::ZERO];
        }
        for n in &mut r.nodes[1..] {
            n.rest.translation = Vec3::ZERO;
        }
        r
    }

    #[test]
    fn a_collapsed_nodes_vertices_blend_the_kept_joints_that_bracket_its_motion() {
        // Child 3 moves halfway between children 1 and 2, close to the still root; with three
        // joints allowed it goes, its motion being the smallest to lose, and its branch (a
        // strip of six triangles), fitted over the kept joints, follows ½·1 + ½·2 exactly
        // where the rigid rule would leave it on the root, still.
        let (a, b) = (Vec3::X, Vec3::new(-1.0, 0.2, 0.0));
        let mut w = wood(&[
            (1, Vec3::ZERO),
            (2, Vec3::ZERO),
            (0, Vec3::new(0.0, -1.0, 0.0)),
        ]);
        let branch = w.positions.len();
        for k in 0..8 {
            w.positions.push(Vec3::new(
                0.1 * (k / 2) as f32,
                1.0 + 0.1 * (k % 2) as f32,
                0.0,
            ));
            w.normals.push(Vec3::Z);
            w.uvs.push(glam::Vec2::ZERO);
            w.bones.push([3; 4]);
            w.weights.push([1.0, 0.0, 0.0, 0.0]);
        }
        let strip: Vec<u32> = (0..6u32)
            .flat_map(|t| [t, t + 1, t + 2].map(|i| branch as u32 + i))
            .collect();
        w.primitives.push(WoodPrimitive {
            material: 0,
            indices: strip,
        });
        let merges = budget(translating(&[a, b, 0.5 * (a + b)]), &mut w, 3, 0.001);
        assert_eq!(merges.nodes_collapsed_for_budget, 1, "{merges:?}");
        for v in branch..branch + 8 {
            let (bones, weights) = (w.bones[v], w.weights[v]);
            let on = |j: u32| {
                (0..4)
                    .filter(|&k| bones[k] == j)
                    .map(|k| weights[k])
                    .sum::<f32>()
            };
            assert!(
                (on(1) - 0.5).abs() < 0.01 && (on(2) - 0.5).abs() < 0.01,
                "{bones:?} {weights:?}"
            );
        }
        for v in 0..6 {
            assert_eq!(w.weights[v], [1.0, 0.0, 0.0, 0.0]);
            assert_eq!(w.bones[v][0], [1, 2][v / 3]);
        }
    }
}
