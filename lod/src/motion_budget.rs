//! "Model no more than a scene needs" for the animation of a cloud: at a LOD's pixel size,
//! motion that stays under half a pixel is dropped, billboards are moved to the highest
//! ancestor bone that still carries them within budget, billboards that cover less than half
//! a pixel are removed, and rig nodes that then drive nothing are pruned (spec
//! view-dependent-hierarchies-gpu §2.3–2.4: one pixel at the LOD's viewing distance).

use frond_scene::{Sampled, Tree};
use glam::{Affine3A, Mat4, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloud_build::sampled_worlds;
use crate::contract::{AnimatedBillboardCloud, BillboardTexture, RigidMotion};
use crate::joint_budget::{
    BillboardAnimation, JointCap, JointMerges, RigFrames, apply_joint_budget, fit_to_node,
};
use frond_scene::wood::{NO_BONE, WoodMesh};

/// What one LOD can show.
#[derive(Clone, Copy, Debug)]
pub struct ScreenBudget {
    /// World units covered by one screen pixel at the LOD's viewing distance.
    pub pixel: f32,
    /// Plane tolerance ε of the LOD (world units): a triangle's centre must stay within it of
    /// its billboard's plane in every sample.
    pub epsilon: f32,
    /// Joints and channels the LOD may have.
    pub joints: JointCap,
    /// Keep motion under half a pixel: an impostor-class LOD, a tree a few dozen pixels high
    /// whose clusters sway by fractions of a pixel, which the covered fraction of its edge
    /// pixels shows (spec §5.4, filtered). Steps 1b and 2 are skipped, and motion counts as
    /// unseen, for every later merge, only under [`SUB_PIXEL_MOTION_SHOWN`] of a pixel; its
    /// joint budget bounds what the motion costs either way.
    pub keep_sub_pixel_motion: bool,
}

/// The smallest motion, in pixels, that an impostor-class LOD keeps: an edge pixel's covered
/// fraction changes by about the fraction of a pixel its edge moves, and a sixteenth is about
/// what 8-bit alpha-to-coverage and 4×4 supersampling resolve.
pub const SUB_PIXEL_MOTION_SHOWN: f32 = 1.0 / 16.0;

impl ScreenBudget {
    /// The motion no viewer sees at this LOD (world units): half a pixel, or
    /// [`SUB_PIXEL_MOTION_SHOWN`] of one where sub-pixel motion is kept. Merges of motion
    /// under it are made whatever the joint budget.
    pub fn unseen_motion(&self) -> f32 {
        if self.keep_sub_pixel_motion {
            SUB_PIXEL_MOTION_SHOWN * self.pixel
        } else {
            0.5 * self.pixel
        }
    }
}

/// What was removed, and why (reported per LOD).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Dropped {
    /// Billboards whose own motion never moves a corner half a pixel: made static.
    pub motion_under_half_pixel: usize,
    /// Billboards whose own motion is within half a pixel of a bone's (one their triangles
    /// follow, or an ancestor): they follow that bone instead and need no joint of their own.
    pub attached_to_bone: usize,
    /// Billboards whose own motion is within half a pixel of an earlier billboard's: they
    /// share that billboard's motion (and so its joint or VAT track).
    pub motion_shared: usize,
    /// Billboards moved to an ancestor bone whose motion differs from their own bone's by less
    /// than half a pixel (and keeps their triangles within ε of the plane).
    pub rebound_to_ancestor: usize,
    /// Billboards whose bone's whole motion stays under half a pixel: they no longer follow one.
    pub made_static: usize,
    /// Billboards removed because all of them together cover under half a pixel.
    pub billboards_under_half_pixel: usize,
    /// Rig nodes (bones or their parents) removed because nothing they move is left.
    pub nodes_pruned: usize,
    /// Cosine terms of spectral motions whose amplitudes sum to under a quarter pixel per
    /// billboard (applied first, so with the half-pixel rules no corner strays a pixel).
    pub frequencies_under_quarter_pixel: usize,
    /// Rig nodes collapsed and own motions attached to rig nodes by the joint budget.
    pub joints: JointMerges,
}

/// Covered fraction of a billboard's texture (texels passing the alpha test); 1 for one that
/// copies an input card (an upper bound: such a billboard is only ever kept for it).
fn covered_fraction(cloud: &AnimatedBillboardCloud, i: usize) -> f32 {
    if cloud.billboards[i].texture != BillboardTexture::Atlas {
        return 1.0;
    }
    let atlas = &cloud.atlas;
    let uv = &cloud.billboards[i].uv;
    let (w, h) = (atlas.width as f32, atlas.height as f32);
    let (mut lo, mut hi) = (uv[0], uv[0]);
    for p in uv {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let x0 = (lo.x * w).round().max(0.0) as u32;
    let x1 = ((hi.x * w).round() as u32).min(atlas.width);
    let y0 = (lo.y * h).round().max(0.0) as u32;
    let y1 = ((hi.y * h).round() as u32).min(atlas.height);
    if x1 <= x0 || y1 <= y0 {
        return 0.0;
    }
    let mut covered = 0usize;
    for y in y0..y1 {
        for x in x0..x1 {
            if atlas.color[((y * atlas.width + x) * 4 + 3) as usize] >= 128 {
                covered += 1;
            }
        }
    }
    covered as f32 / ((x1 - x0) * (y1 - y0)) as f32
}

/// Applies `budget` to `cloud` (built from `tree`, whose loop `sampled` is; the rig's node
/// indices still those of the tree) and to `wood` (the LOD's simplified wood, bones as rig
/// nodes), in the order of the steps below: what is not seen goes first, then motion that a
/// bone (or an earlier billboard) already gives, then the joint budget
/// ([`apply_joint_budget`]); finally the rig is pruned to what is still used and `wood`'s
/// bones re-mapped to it. `animation` says how the billboards' motion is written.
pub fn apply_budget(
    cloud: &mut AnimatedBillboardCloud,
    wood: &mut WoodMesh,
    tree: &Tree,
    sampled: &Sampled,
    budget: &ScreenBudget,
    animation: BillboardAnimation,
) -> Dropped {
    let mut dropped = Dropped::default();
    let half = 0.5 * budget.pixel;
    drop_unseen_billboards(cloud, budget, &mut dropped);
    if !budget.keep_sub_pixel_motion {
        drop_unseen_motion(cloud, half, &mut dropped);
    }
    let worlds = sampled_worlds(&cloud.rig, &cloud.clock);
    let rest_inv: Vec<Mat4> = cloud.rig.rest_world().iter().map(|m| m.inverse()).collect();
    let rig = RigFrames {
        worlds: &worlds,
        rest_inv: &rest_inv,
    };
    let unseen = budget.unseen_motion();
    attach_to_bones(cloud, tree, &rig, unseen, &mut dropped);
    share_motions(cloud, unseen, &mut dropped);
    rebind_to_ancestors(cloud, sampled, &rig, budget, &mut dropped);
    dropped.joints = apply_joint_budget(cloud, wood, tree, &rig, budget.joints, unseen, animation);
    let keep: Vec<usize> = wood
        .used_bones()
        .into_iter()
        .filter(|&b| b != NO_BONE)
        .map(|b| b as usize)
        .collect();
    let map = prune_rig(cloud, &keep, &mut dropped);
    for b in wood.bones.iter_mut().flatten() {
        if *b != NO_BONE {
            *b = map
                .get(*b as usize)
                .copied()
                .flatten()
                .map_or(NO_BONE, |n| n as u32);
        }
    }
    dropped
}

/// Step 1: billboards too small to see.
fn drop_unseen_billboards(
    cloud: &mut AnimatedBillboardCloud,
    budget: &ScreenBudget,
    dropped: &mut Dropped,
) {
    // 1. Billboards too small to see: smallest covered area first, as long as everything
    //    dropped together covers under half a pixel (alpha-tested quads smaller than a pixel
    //    still cover one now and then: dropping many would thin the foliage).
    let pixel_area = budget.pixel * budget.pixel;
    let covered: Vec<f32> = (0..cloud.billboards.len())
        .into_par_iter()
        .map(|i| cloud.billboards[i].quad.area() * covered_fraction(cloud, i) / pixel_area)
        .collect();
    let mut order: Vec<usize> = (0..covered.len()).collect();
    order.sort_by(|&a, &b| covered[a].total_cmp(&covered[b]).then(a.cmp(&b)));
    let mut keep = vec![true; covered.len()];
    let mut dropped_area = 0.0f32;
    for i in order {
        if dropped_area + covered[i] >= 0.5 {
            break;
        }
        dropped_area += covered[i];
        keep[i] = false;
    }
    let before = cloud.billboards.len();
    let mut it = keep.iter();
    cloud.billboards.retain(|_| *it.next().unwrap_or(&true));
    dropped.billboards_under_half_pixel = before - cloud.billboards.len();
}

/// Steps 1b and 2: spectral terms, then whole motions, too small to see.
fn drop_unseen_motion(cloud: &mut AnimatedBillboardCloud, half: f32, dropped: &mut Dropped) {
    // 1b. Spectral terms too small to see.
    for b in &mut cloud.billboards {
        if let Some(RigidMotion::Spectral(m)) = &mut b.motion {
            dropped.frequencies_under_quarter_pixel += m.prune(0.5 * half);
            if m.terms() == 0 {
                b.motion = None;
                dropped.motion_under_half_pixel += 1;
            }
        }
    }

    // 2. Own motion under half a pixel.
    for b in &mut cloud.billboards {
        if let Some(m) = &b.motion {
            let corners = b.quad.corners();
            let n = m.len();
            let moves = (0..n).any(|s| {
                let t = m.at(s, n);
                corners
                    .iter()
                    .any(|c| t.transform_point3(*c).distance(*c) >= half)
            });
            if !moves {
                b.motion = None;
                dropped.motion_under_half_pixel += 1;
            }
        }
    }
}

/// Step 2a: own motion within half a pixel of a bone's becomes following that bone.
fn attach_to_bones(
    cloud: &mut AnimatedBillboardCloud,
    tree: &Tree,
    rig: &RigFrames,
    unseen: f32,
    dropped: &mut Dropped,
) {
    let worlds = rig.worlds;
    // 2a. Own motion within `unseen` (half a pixel; the far end: a sixteenth) of a bone's:
    //     follow the bone.
    let nodes = &cloud.rig.nodes;
    let attach: Vec<Option<(usize, Affine3A)>> = cloud
        .billboards
        .par_iter()
        .map(|b| {
            let m = b.motion.as_ref()?;
            if b.follows.is_some() {
                return None;
            }
            let mut candidates: Vec<usize> = Vec::new();
            for &t in &b.triangles {
                let Some(bone) = tree.triangles.get(t).and_then(|t| t.bone) else {
                    continue;
                };
                let mut cur = tree.bones.get(bone as usize).map(|b| b.node);
                while let Some(c) = cur {
                    if c >= nodes.len() || candidates.contains(&c) {
                        break;
                    }
                    candidates.push(c);
                    cur = nodes[c].parent;
                }
            }
            candidates.sort_unstable();
            let corners = b.quad.corners();
            let ns = worlds.len();
            // Following `node` puts the quad at Q·corners in the node's rest frame, Q the rigid
            // fit of Rest·W(s)⁻¹·M(s) over the loop; the deviation is what that costs on screen.
            let own = m.samples(ns);
            let target = |s: usize, c: Vec3| own[s].transform_point3(c);
            let fit = |node: usize| fit_to_node(rig, Some(node), &corners, &target);
            candidates
                .into_iter()
                .map(|c| (fit(c), c))
                .filter(|((d, _), _)| *d < unseen)
                .min_by(|a, b| a.0.0.total_cmp(&b.0.0).then(a.1.cmp(&b.1)))
                .map(|((_, q), c)| (c, q))
        })
        .collect();
    for (b, a) in cloud.billboards.iter_mut().zip(attach) {
        if let Some((node, q)) = a {
            b.quad = b.quad.transformed(q);
            b.follows = Some(node);
            b.motion = None;
            dropped.attached_to_bone += 1;
        }
    }
}

/// Step 2b: motions within half a pixel of an earlier billboard's are shared.
fn share_motions(cloud: &mut AnimatedBillboardCloud, unseen: f32, dropped: &mut Dropped) {
    // 2b. Motions within `unseen` of an earlier one are shared (greedy, in billboard
    //     order, so the result does not depend on threads).
    // Each motion at its own samples, once: every later billboard compares against them.
    let sampled: Vec<Option<Vec<Affine3A>>> = (cloud.billboards.par_iter())
        .map(|b| b.motion.as_ref().map(|m| m.samples(m.len())))
        .collect();
    let mut reps: Vec<usize> = Vec::new();
    for i in 0..cloud.billboards.len() {
        let Some(own) = &sampled[i] else {
            continue;
        };
        let corners = cloud.billboards[i].quad.corners();
        let follows = cloud.billboards[i].follows;
        let close = reps.iter().copied().find(|&r| {
            cloud.billboards[r].follows == follows
                && sampled[r].as_ref().is_some_and(|m| {
                    m.len() == own.len()
                        && own.iter().zip(m).all(|(a, b)| {
                            corners.iter().all(|c| {
                                a.transform_point3(*c).distance(b.transform_point3(*c)) < unseen
                            })
                        })
                })
        });
        match close {
            Some(r) => {
                cloud.billboards[i].motion = cloud.billboards[r].motion.clone();
                dropped.motion_shared += 1;
            }
            None => reps.push(i),
        }
    }
}

/// Step 3: bone-bound billboards move up to the highest ancestor that carries them unseen.
fn rebind_to_ancestors(
    cloud: &mut AnimatedBillboardCloud,
    sampled: &Sampled,
    rig: &RigFrames,
    budget: &ScreenBudget,
    dropped: &mut Dropped,
) {
    let worlds = rig.worlds;
    let unseen = budget.unseen_motion();
    // 3. Bone-bound billboards move to the highest ancestor (or the world) that carries them
    //    within half a pixel (the far end: a sixteenth) and keeps their triangles' centres
    //    within ε of the plane.
    let centre_of: std::collections::HashMap<usize, usize> = sampled
        .foliage
        .iter()
        .enumerate()
        .map(|(k, &t)| (t, k))
        .collect();
    let ns = worlds.len();
    let nodes = &cloud.rig.nodes;
    let targets: Vec<Option<Option<usize>>> = cloud
        .billboards
        .par_iter()
        .map(|b| {
            let own = b.follows?;
            if b.motion.is_some() {
                return None;
            }
            let corners = b.quad.corners();
            let normal = b.quad.plane.normal;
            let centre = b.quad.center;
            let fits = |cand: Option<usize>| {
                (0..ns).all(|s| {
                    let a = rig.carry(Some(own), s);
                    let c = rig.carry(cand, s);
                    if corners
                        .iter()
                        .any(|p| a.transform_point3(*p).distance(c.transform_point3(*p)) >= unseen)
                    {
                        return false;
                    }
                    let n = c.transform_vector3(normal).normalize_or_zero();
                    let o = c.transform_point3(centre);
                    b.triangles.iter().all(|t| {
                        centre_of.get(t).is_none_or(|&k| {
                            let traj = sampled.trajectory(k);
                            let p: Vec3 = traj[s.min(traj.len() - 1)];
                            (p - o).dot(n).abs() <= budget.epsilon
                        })
                    })
                })
            };
            let mut best = None;
            let mut cur = nodes[own].parent;
            loop {
                if !fits(cur) {
                    break;
                }
                best = Some(cur);
                match cur {
                    Some(p) => cur = nodes[p].parent,
                    None => break,
                }
            }
            best
        })
        .collect();
    for (b, t) in cloud.billboards.iter_mut().zip(targets) {
        if let Some(target) = t {
            match target {
                Some(_) => dropped.rebound_to_ancestor += 1,
                None => dropped.made_static += 1,
            }
            b.follows = target;
        }
    }
}

/// Step 4: rig nodes nothing follows (and the caller's meshes do not need) are removed.
fn prune_rig(
    cloud: &mut AnimatedBillboardCloud,
    keep_nodes: &[usize],
    dropped: &mut Dropped,
) -> Vec<Option<usize>> {
    // 4. Prune rig nodes nothing needs.
    let mut needed = vec![false; cloud.rig.nodes.len()];
    for b in &cloud.billboards {
        if let Some(f) = b.follows {
            needed[f] = true;
        }
    }
    for &k in keep_nodes {
        if k < needed.len() {
            needed[k] = true;
        }
    }
    let before_nodes = cloud.rig.nodes.len();
    let map = cloud.rig.retain(&needed);
    dropped.nodes_pruned = before_nodes - cloud.rig.nodes.len();
    for b in &mut cloud.billboards {
        b.follows = b.follows.and_then(|f| map[f]);
    }
    cloud.clock.clip = cloud.clock.clip.filter(|&c| c < cloud.rig.clips.len());
    cloud.update_playable_clips();
    map
}
