//! Common joint rotation, CJR (spec animated-billboard-clouds §6.1, thesis §7.1): sibling bones
//! that turn alike share one rotation, so their foliage can share one billboard cloud. Sets
//! start as one per bone carrying foliage; the pair of sibling sets whose merge moves foliage
//! least is merged until the budget of clouds is met or no two sets are siblings.
//!
//! \[ENG\] merge order: the thesis merges the pair whose average descriptions deviate least.
//! Description deviations are unitless and blind to lever arms: on glTF trees, whose siblings
//! start at different points along their parent, such a merge can move leaves visibly on
//! screen. Here the pair merged first is the one whose common rotation moves
//! the foliage it affects least, in world units: each member's own foliage turns by the
//! set's average about the set's pivot instead of by its own about its own pivot, and (without
//! the average-bone improvement) its descendants' foliage turns by the average too. The
//! description's average still gives the common rotation and its deviation breaks ties and is
//! reported; the displacement comes from first and second moments of the foliage's rest
//! positions, so a pair costs O(samples), not O(leaves).

use std::collections::BTreeMap;

use glam::{Mat3, Mat4, Quat, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::description::BoneDescriptionType;
use crate::model::{SkNode, SkeletonModel};

/// One merge CJR made.
#[derive(Clone, Debug, Serialize)]
pub struct Merge {
    /// Bone names of the two sets.
    pub a: Vec<String>,
    /// Bone names of the second set (`a` holds the first's).
    pub b: Vec<String>,
    /// Deviation of the two sets' average descriptions.
    pub deviation: f32,
    /// RMS displacement (world units) of the foliage the merge affects.
    pub displacement: f32,
}

/// The sets CJR ends with.
#[derive(Clone, Debug)]
pub struct CommonRotationSets {
    /// Model nodes per set (siblings), in a deterministic order.
    pub sets: Vec<Vec<usize>>,
    /// Each set's common rotation: the delta rotations its average description applies to
    /// (empty for a single bone, which keeps its own).
    pub deltas: Vec<Vec<Quat>>,
    /// Every merge made, in order.
    pub merges: Vec<Merge>,
}

struct Set<D> {
    members: Vec<usize>,
    parent: Option<usize>,
    average: D,
}

/// First and second moments of weighted points: `Σw`, `Σw x`, `Σw x xᵀ`.
#[derive(Clone, Copy, Debug)]
struct Moments {
    w: f32,
    s1: Vec3,
    s2: Mat3,
}

impl Moments {
    /// No points (glam's matrix default is the identity, not zero).
    fn new() -> Self {
        Moments {
            w: 0.0,
            s1: Vec3::ZERO,
            s2: Mat3::ZERO,
        }
    }
    fn add(&mut self, x: Vec3, w: f32) {
        self.w += w;
        self.s1 += x * w;
        self.s2 += Mat3::from_cols(x * (x.x * w), x * (x.y * w), x * (x.z * w));
    }
    /// `Σ w |a + B x|²`.
    fn squared(&self, a: Vec3, b: Mat3) -> f32 {
        let btb = b.transpose() * b;
        let trace = (btb * self.s2).to_cols_array();
        self.w * a.length_squared() + 2.0 * a.dot(b * self.s1) + trace[0] + trace[4] + trace[8]
    }
}

/// What a foliage bone's merge moves: its pivot, its delta rotations, the moments of its own
/// foliage and of its descendants', all in its parent's rest frame.
struct Lever {
    pivot: Vec3,
    deltas: Vec<Mat3>,
    own: Moments,
    below: Moments,
}

fn levers(model: &SkeletonModel, nodes: &[usize]) -> BTreeMap<usize, Lever> {
    let rest = model.rest_world();
    nodes
        .iter()
        .map(|&i| {
            let node = &model.nodes[i];
            let to_parent = node.parent.map_or(Mat4::IDENTITY, |p| rest[p].inverse());
            let mut own = Moments::new();
            for r in model.node_representatives(i) {
                own.add(to_parent.transform_point3(r.rest), r.weight);
            }
            let mut below = Moments::new();
            for &c in &node.children {
                if model.nodes[c].alive {
                    for r in model.subtree_representatives(c) {
                        below.add(to_parent.transform_point3(r.rest), r.weight);
                    }
                }
            }
            let lever = Lever {
                pivot: node.rest.translation,
                deltas: node.deltas().into_iter().map(Mat3::from_quat).collect(),
                own,
                below,
            };
            (i, lever)
        })
        .collect()
}

/// RMS displacement of the foliage a set's common rotation `deltas` about its pivot moves, and
/// the largest distance a member's own foliage moves off the member (turning about the set's
/// pivot rather than the member's own: `|(I − D̄)(p_m − p̄)|`).
fn displacement(
    levers: &BTreeMap<usize, Lever>,
    members: &[usize],
    deltas: &[Quat],
    average_bone: bool,
) -> (f32, f32) {
    let own_w: f32 = members.iter().map(|m| levers[m].own.w).sum();
    let pivot = members
        .iter()
        .map(|m| levers[m].pivot * levers[m].own.w)
        .sum::<Vec3>()
        / own_w.max(1e-12);
    let (mut sum, mut weight, mut detach) = (0.0f32, 0.0f32, 0.0f32);
    for m in members {
        let l = &levers[m];
        for (s, d) in deltas.iter().enumerate() {
            let avg = Mat3::from_quat(*d);
            detach = detach.max((l.pivot - pivot - avg * (l.pivot - pivot)).length());
            let mine = l.deltas[s.min(l.deltas.len() - 1)];
            let b = avg - mine;
            // Own foliage: by the average about the set's pivot, not its own about its own.
            let a = pivot - avg * pivot - l.pivot + mine * l.pivot;
            sum += l.own.squared(a, b);
            if !average_bone {
                // Descendants: the member itself now turns by the average about its pivot.
                sum += l.below.squared(-(b * l.pivot), b);
            }
        }
        weight += (l.own.w + if average_bone { 0.0 } else { l.below.w }) * deltas.len() as f32;
    }
    ((sum.max(0.0) / weight.max(1e-12)).sqrt(), detach)
}

/// Merges sibling sets of the model's foliage bones, least foliage displacement first (ties:
/// least description deviation), until `budget` clouds remain (`extra` clouds are made
/// elsewhere: unbound foliage) or no sibling pair is left (every sibling group shares one
/// rotation). With `attach`, a merge is allowed only while no member's foliage would move
/// more than that (world units) off its own bone: its cloud stays on its branch; with
/// `max_displacement`, only while the foliage it affects moves less than that (RMS).
pub fn common_rotation_sets<T: BoneDescriptionType>(
    ty: &T,
    model: &SkeletonModel,
    budget: usize,
    extra: usize,
    average_bone: bool,
    attach: Option<f32>,
    max_displacement: Option<f32>,
) -> CommonRotationSets {
    let counts = model.animated_counts();
    let foliage = model.foliage_nodes();
    let descs: BTreeMap<usize, T::Desc> = foliage
        .iter()
        .map(|&i| (i, ty.describe(&model.nodes[i].deltas())))
        .collect();
    let levers = levers(model, &foliage);
    let average = |members: &[usize]| -> T::Desc {
        let ds: Vec<&T::Desc> = members.iter().map(|m| &descs[m]).collect();
        let ws: Vec<f32> = members.iter().map(|&m| counts[m] as f32).collect();
        ty.average(&ds, &ws)
    };
    let cost = |a: &Set<T::Desc>, b: &Set<T::Desc>| -> Option<(f32, f32)> {
        let mut members = a.members.clone();
        members.extend(&b.members);
        let deltas = ty.apply(&average(&members));
        let (disp, detach) = displacement(&levers, &members, &deltas, average_bone);
        if attach.is_some_and(|tol| detach > tol) || max_displacement.is_some_and(|m| disp > m) {
            return None;
        }
        Some((disp, ty.deviation(&a.average, &b.average)))
    };
    let mut sets: Vec<Option<Set<T::Desc>>> = foliage
        .iter()
        .map(|&i| {
            Some(Set {
                members: vec![i],
                parent: model.nodes[i].parent,
                average: descs[&i].clone(),
            })
        })
        .collect();
    // (displacement, deviation) of every sibling pair of sets, keyed (lower id, higher id).
    let keys: Vec<(usize, usize)> = (0..sets.len())
        .flat_map(|a| (a + 1..sets.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| match (&sets[a], &sets[b]) {
            (Some(x), Some(y)) => x.parent == y.parent,
            _ => false,
        })
        .collect();
    let costs: Vec<Option<(f32, f32)>> = keys
        .par_iter()
        .map(|&(a, b)| match (&sets[a], &sets[b]) {
            (Some(x), Some(y)) => cost(x, y),
            _ => None,
        })
        .collect();
    let mut pairs: BTreeMap<(usize, usize), (f32, f32)> = keys
        .into_iter()
        .zip(costs)
        .filter_map(|(k, c)| Some((k, c?)))
        .collect();
    let mut merges = Vec::new();
    let mut alive = sets.len();
    while alive + extra > budget {
        let Some((&(a, b), &(disp, dev))) = pairs.iter().min_by(|x, y| {
            x.1.0
                .total_cmp(&y.1.0)
                .then(x.1.1.total_cmp(&y.1.1))
                .then(x.0.cmp(y.0))
        }) else {
            break;
        };
        let (Some(sa), Some(sb)) = (sets[a].take(), sets[b].take()) else {
            break;
        };
        pairs.retain(|&(x, y), _| x != a && x != b && y != a && y != b);
        let names = |s: &Set<T::Desc>| -> Vec<String> {
            s.members
                .iter()
                .map(|&m| model.nodes[m].name.clone())
                .collect()
        };
        merges.push(Merge {
            a: names(&sa),
            b: names(&sb),
            deviation: dev,
            displacement: disp,
        });
        let mut members = sa.members;
        members.extend(sb.members);
        members.sort_unstable();
        let merged = Set {
            average: average(&members),
            members,
            parent: sa.parent,
        };
        let id = sets.len();
        let fresh: Vec<((usize, usize), (f32, f32))> = sets
            .par_iter()
            .enumerate()
            .filter_map(|(other, s)| {
                let s = s.as_ref()?;
                if s.parent != merged.parent {
                    return None;
                }
                Some(((other, id), cost(s, &merged)?))
            })
            .collect();
        pairs.extend(fresh);
        sets.push(Some(merged));
        alive -= 1;
    }
    let mut out: Vec<(Vec<usize>, Vec<Quat>)> = sets
        .into_iter()
        .flatten()
        .map(|s| {
            let deltas = if s.members.len() > 1 {
                ty.apply(&s.average)
            } else {
                Vec::new()
            };
            (s.members, deltas)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    let (sets, deltas) = out.into_iter().unzip();
    CommonRotationSets {
        sets,
        deltas,
        merges,
    }
}

/// Applies CJR's sets to the model (spec §6.1 "applying a common rotation"): each set of two
/// or more bones gets a new node under their parent, at their pivots' mean weighted by the
/// foliage bound to each, turning by the set's average rotation and carrying all of the set's
/// foliage. Without the average-animation-bone improvement (§7.1.2) the member bones turn by the
/// average too, so their branches and descendants follow it; with it they keep their own
/// animation and only the foliage moves by the average. Returns each set's node.
pub fn apply_common_rotations(
    model: &mut SkeletonModel,
    cjr: &CommonRotationSets,
    average_bone: bool,
) -> Vec<usize> {
    let mut follow = Vec::with_capacity(cjr.sets.len());
    for (k, (set, deltas)) in cjr.sets.iter().zip(&cjr.deltas).enumerate() {
        if set.len() == 1 {
            follow.push(set[0]);
            continue;
        }
        let direct: f32 = set
            .iter()
            .map(|&m| model.nodes[m].foliage.len() as f32)
            .sum();
        let pivot = set
            .iter()
            .map(|&m| model.nodes[m].rest.translation * model.nodes[m].foliage.len() as f32)
            .sum::<glam::Vec3>()
            / direct.max(1.0);
        let mut foliage: Vec<usize> = set
            .iter()
            .flat_map(|&m| std::mem::take(&mut model.nodes[m].foliage))
            .collect();
        foliage.sort_unstable();
        if !average_bone {
            for &m in set {
                let node = &mut model.nodes[m];
                let r = node.rest.rotation;
                for (t, d) in node.track.iter_mut().zip(deltas) {
                    t.rotation = (*d * r).normalize();
                }
                node.changed = true;
            }
        }
        let parent = model.nodes[set[0]].parent;
        let node = model.push(SkNode::turning(
            format!("frond_cjr_{k}"),
            parent,
            pivot,
            deltas,
            model.samples,
            foliage,
        ));
        follow.push(node);
    }
    follow
}
