//! The skeleton being simplified (spec animated-billboard-clouds §6, §1.2): the tree's node
//! hierarchy with every node's local transform sampled over the loop, the foliage bound
//! directly to each node, and a few representative foliage points per node for the geometric
//! steps (end joints, joint animation, error measures).
//!
//! glTF skeletons are node hierarchies: a node's *pivot* is its rest translation in its
//! parent's frame, and its *animation* is the delta rotation `d(s) = R(s)·R_rest⁻¹` it turns
//! about that pivot, in the parent's frame. Siblings are nodes with the same parent.

use frond_scene::rig::local_pose;
use frond_scene::{Sampled, Tree, Trs};
use glam::{Mat4, Quat, Vec3};
use rayon::prelude::*;

use crate::error::SkeletonError;

/// Representative foliage points kept per node: a bone's triangles move rigidly with it, so a
/// few spread over its foliage stand for all of them in sums over positions.
pub const REPRESENTATIVES: usize = 24;

/// One node of the skeleton being simplified.
#[derive(Clone, Debug)]
pub struct SkNode {
    /// The node's name, as in the input or made for a new (collapsed) node.
    pub name: String,
    /// Index of its parent node; None for a root.
    pub parent: Option<usize>,
    /// Indices of its child nodes.
    pub children: Vec<usize>,
    /// Rest local transform.
    pub rest: Trs,
    /// Local transform at each loop sample.
    pub track: Vec<Trs>,
    /// The tree node it started as (None for nodes the simplification made).
    pub source: Option<usize>,
    /// Its rest, parent or track differ from the tree node's.
    pub changed: bool,
    /// False once collapsed into another node.
    pub alive: bool,
    /// Foliage bound directly (indices into `Sampled::foliage`).
    pub foliage: Vec<usize>,
}

impl SkNode {
    /// A new node under `parent` with its pivot at `pivot` (parent frame), no rest rotation,
    /// turning by `deltas` (one per sample; identity past their end) and carrying `foliage`.
    pub fn turning(
        name: String,
        parent: Option<usize>,
        pivot: Vec3,
        deltas: &[Quat],
        samples: usize,
        foliage: Vec<usize>,
    ) -> SkNode {
        let rest = Trs {
            translation: pivot,
            ..Trs::IDENTITY
        };
        SkNode {
            name,
            parent,
            children: Vec::new(),
            rest,
            track: (0..samples)
                .map(|s| Trs {
                    rotation: deltas.get(s).copied().unwrap_or(Quat::IDENTITY),
                    ..rest
                })
                .collect(),
            source: None,
            changed: true,
            alive: true,
            foliage,
        }
    }

    /// The delta rotation at every sample, `R(s)·R_rest⁻¹` (parent frame, about the pivot).
    pub fn deltas(&self) -> Vec<Quat> {
        let inv = self.rest.rotation.inverse();
        self.track
            .iter()
            .map(|t| {
                let d = (t.rotation * inv).normalize();
                if d.w < 0.0 { -d } else { d }
            })
            .collect()
    }
}

/// A foliage point standing for `weight` triangles of one node.
#[derive(Clone, Debug)]
pub struct Representative {
    /// Index into `Sampled::foliage`.
    pub foliage: usize,
    /// How many foliage triangles it stands for (its share of the node's foliage).
    pub weight: f32,
    /// World trajectory in the input's animation.
    pub trajectory: Vec<Vec3>,
    /// Where it sits at rest, carried rigidly by the node it was bound to in the input.
    pub rest: Vec3,
    /// The input's node it is bound to.
    pub node: usize,
}

/// The skeleton with its sampled animation and foliage.
#[derive(Clone, Debug)]
pub struct SkeletonModel {
    /// The nodes: the input's hierarchy, later simplified.
    pub nodes: Vec<SkNode>,
    /// Loop samples of every track.
    pub samples: usize,
    /// Representatives of every node's direct foliage, by the input node they are bound to.
    pub representatives: Vec<Vec<Representative>>,
    /// Foliage bound to no bone (static trees).
    pub unbound: Vec<usize>,
    /// World matrices of the input's nodes at every sample, and at rest.
    pub input_world: Vec<Vec<Mat4>>,
    /// World matrices of the input's nodes at rest.
    pub input_rest: Vec<Mat4>,
}

impl SkeletonModel {
    /// The tree's nodes, sampled at `sampled`'s loop times of clip `clip`.
    pub fn from_tree(
        tree: &Tree,
        sampled: &Sampled,
        clip: Option<usize>,
    ) -> Result<SkeletonModel, SkeletonError> {
        if tree.bones.is_empty() {
            return Err(SkeletonError::NoBones);
        }
        let times = &sampled.times;
        let n = times.len().max(1);
        let clip_ref = clip.and_then(|c| tree.rig.clips.get(c));
        let poses: Vec<Vec<Trs>> = (0..n)
            .into_par_iter()
            .map(|s| {
                local_pose(
                    &tree.rig.nodes,
                    clip_ref,
                    times.get(s).copied().unwrap_or(0.0),
                )
            })
            .collect();
        let mut nodes: Vec<SkNode> = tree
            .rig
            .nodes
            .iter()
            .enumerate()
            .map(|(i, node)| SkNode {
                name: node.name.clone(),
                parent: node.parent,
                children: node.children.clone(),
                rest: node.rest,
                track: poses.iter().map(|p| p[i]).collect(),
                source: Some(i),
                changed: false,
                alive: true,
                foliage: Vec::new(),
            })
            .collect();
        let mut unbound = Vec::new();
        for (k, &t) in sampled.foliage.iter().enumerate() {
            match tree.triangles[t].bone {
                Some(b) => nodes[tree.bones[b as usize].node].foliage.push(k),
                None => unbound.push(k),
            }
        }
        let mut model = SkeletonModel {
            nodes,
            samples: n,
            representatives: Vec::new(),
            unbound,
            input_world: Vec::new(),
            input_rest: Vec::new(),
        };
        model.input_world = (0..n).into_par_iter().map(|s| model.world(s)).collect();
        model.input_rest = model.rest_world();
        let ns = sampled.samples();
        model.representatives = model
            .nodes
            .par_iter()
            .enumerate()
            .map(|(i, node)| {
                let m = node.foliage.len();
                if m == 0 {
                    return Vec::new();
                }
                let picks = m.min(REPRESENTATIVES);
                let weight = m as f32 / picks as f32;
                (0..picks)
                    .map(|r| {
                        let k = node.foliage[r * m / picks];
                        let trajectory: Vec<Vec3> = (0..n)
                            .map(|s| sampled.centres[k * ns + s.min(ns.saturating_sub(1))])
                            .collect();
                        let rest = trajectory
                            .iter()
                            .enumerate()
                            .map(|(s, p)| {
                                (model.input_rest[i] * model.input_world[s][i].inverse())
                                    .transform_point3(*p)
                            })
                            .sum::<Vec3>()
                            / n as f32;
                        Representative {
                            foliage: k,
                            weight,
                            trajectory,
                            rest,
                            node: i,
                        }
                    })
                    .collect()
            })
            .collect();
        Ok(model)
    }

    /// A model from hand-made nodes (tracks filled, `samples` each) and leaves given as
    /// (node, rest world position), each carried rigidly by its node: for tests and tools.
    pub fn from_nodes(nodes: Vec<SkNode>, leaves: &[(usize, Vec3)]) -> SkeletonModel {
        let samples = nodes.first().map_or(1, |n| n.track.len().max(1));
        let mut model = SkeletonModel {
            nodes,
            samples,
            representatives: Vec::new(),
            unbound: Vec::new(),
            input_world: Vec::new(),
            input_rest: Vec::new(),
        };
        model.input_world = (0..samples).map(|s| model.world(s)).collect();
        model.input_rest = model.rest_world();
        model.representatives = vec![Vec::new(); model.nodes.len()];
        for (k, &(node, rest)) in leaves.iter().enumerate() {
            model.nodes[node].foliage.push(k);
            let carry = |s: usize| model.input_world[s][node] * model.input_rest[node].inverse();
            let trajectory = (0..samples)
                .map(|s| carry(s).transform_point3(rest))
                .collect();
            model.representatives[node].push(Representative {
                foliage: k,
                weight: 1.0,
                trajectory,
                rest,
                node,
            });
        }
        model
    }

    /// Alive nodes, parents first (children in index order).
    pub fn order(&self) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.nodes.len());
        let mut stack: Vec<usize> = (0..self.nodes.len())
            .rev()
            .filter(|&i| self.nodes[i].alive && self.nodes[i].parent.is_none())
            .collect();
        while let Some(i) = stack.pop() {
            out.push(i);
            for &c in self.nodes[i].children.iter().rev() {
                if self.nodes[c].alive {
                    stack.push(c);
                }
            }
        }
        out
    }

    /// World matrices of every node at sample `s` (dead nodes: identity).
    pub fn world(&self, s: usize) -> Vec<Mat4> {
        self.world_with(|node| node.track[s.min(node.track.len() - 1)].matrix())
    }

    /// World matrices of every node at rest.
    pub fn rest_world(&self) -> Vec<Mat4> {
        self.world_with(|node| node.rest.matrix())
    }

    fn world_with(&self, local: impl Fn(&SkNode) -> Mat4) -> Vec<Mat4> {
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        for i in self.order() {
            let node = &self.nodes[i];
            world[i] = match node.parent {
                Some(p) => world[p] * local(node),
                None => local(node),
            };
        }
        world
    }

    /// World matrices at every sample.
    pub fn worlds(&self) -> Vec<Vec<Mat4>> {
        (0..self.samples)
            .into_par_iter()
            .map(|s| self.world(s))
            .collect()
    }

    /// Foliage triangles each node animates: its own plus all its descendants' (thesis §7.2
    /// "average" weights).
    pub fn animated_counts(&self) -> Vec<usize> {
        let mut count: Vec<usize> = self.nodes.iter().map(|n| n.foliage.len()).collect();
        for &i in self.order().iter().rev() {
            if let Some(p) = self.nodes[i].parent {
                count[p] += count[i];
            }
        }
        count
    }

    /// Alive nodes with foliage bound directly.
    pub fn foliage_nodes(&self) -> Vec<usize> {
        (0..self.nodes.len())
            .filter(|&i| self.nodes[i].alive && !self.nodes[i].foliage.is_empty())
            .collect()
    }

    /// A node is non-terminal when a child of it animates foliage (spec §6.3: only those
    /// carry an end joint worth collapsing).
    pub fn non_terminal(&self, i: usize, counts: &[usize]) -> bool {
        self.nodes[i]
            .children
            .iter()
            .any(|&c| self.nodes[c].alive && counts[c] > 0)
    }

    /// The representatives of every foliage triangle now bound directly to node `i`.
    pub fn node_representatives(&self, i: usize) -> Vec<&Representative> {
        let mut out = Vec::new();
        self.collect_direct(i, &mut out);
        out
    }

    fn collect_direct<'a>(&'a self, i: usize, out: &mut Vec<&'a Representative>) {
        let node = &self.nodes[i];
        if node.foliage.is_empty() {
            return;
        }
        // Foliage moves between nodes by whole input nodes; find which input nodes' foliage
        // it holds by looking at its first triangle of each.
        for reps in &self.representatives {
            if let Some(first) = reps.first()
                && node.foliage.binary_search(&first.foliage).is_ok()
            {
                out.extend(reps.iter());
            }
        }
    }

    /// The representatives of node `i`'s whole subtree (its own and its descendants').
    pub fn subtree_representatives(&self, i: usize) -> Vec<&Representative> {
        let mut out = Vec::new();
        let mut stack = vec![i];
        while let Some(c) = stack.pop() {
            self.collect_direct(c, &mut out);
            for &k in &self.nodes[c].children {
                if self.nodes[k].alive {
                    stack.push(k);
                }
            }
        }
        out
    }

    /// Depth of a node (1 for a root).
    pub fn depth(&self, i: usize) -> usize {
        let mut d = 1;
        let mut cur = self.nodes[i].parent;
        while let Some(p) = cur {
            d += 1;
            cur = self.nodes[p].parent;
        }
        d
    }

    /// Appends a node and links it under its parent.
    pub fn push(&mut self, node: SkNode) -> usize {
        let i = self.nodes.len();
        if let Some(p) = node.parent {
            self.nodes[p].children.push(i);
        }
        self.nodes.push(node);
        i
    }
}
