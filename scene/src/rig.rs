//! The rig: the node hierarchy with rest transforms and the animation clips that drive it,
//! one type for the imported tree, the simplified skeleton of a LOD and the written files
//! (spec animated-billboard-clouds §1.1). Clips are evaluated as glTF specifies (LINEAR with
//! shortest-path slerp for rotations, STEP, CUBICSPLINE Hermite).

use glam::{Mat4, Quat, Vec3, Vec4};

/// A node's local transform as translation, rotation, scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation, in the parent's units.
    pub translation: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Scale per axis.
    pub scale: Vec3,
}

impl Trs {
    /// The identity transform.
    pub const IDENTITY: Trs = Trs {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };
    /// As a column-major matrix (T · R · S).
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// One node of the glTF hierarchy.
#[derive(Clone, Debug)]
pub struct Node {
    /// The node's name (`node<i>` when the file gives none).
    pub name: String,
    /// Index of the parent node; None for a root.
    pub parent: Option<usize>,
    /// Indices of the child nodes, in the file's order.
    pub children: Vec<usize>,
    /// Rest (un-animated) local transform.
    pub rest: Trs,
    /// The bone this node is, if it is a skin joint.
    pub bone: Option<usize>,
    /// The node's `extras`, verbatim JSON (empty when absent).
    pub extras: Option<serde_json::Value>,
}

/// Which node property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    /// The node's translation (glTF `translation`).
    Translation,
    /// The node's rotation (glTF `rotation`).
    Rotation,
    /// The node's scale (glTF `scale`).
    Scale,
}

/// glTF sampler interpolation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Linear between keys (shortest-path slerp for rotations).
    Linear,
    /// Each key's value held until the next.
    Step,
    /// Cubic Hermite through the keys with their in- and out-tangents.
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    /// Index of the node it drives.
    pub node: usize,
    /// The property it drives.
    pub property: Property,
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// Key times in seconds: finite, ≥ 0 and strictly increasing (the importer refuses or
    /// repairs anything else, see `import::animation::read_clips`), as glTF requires of what frond writes.
    pub times: Vec<f32>,
    /// Key values as Vec4 (xyz for T/S, xyzw for rotation); CUBICSPLINE stores
    /// in-tangent, value, out-tangent per key.
    pub values: Vec<Vec4>,
}

/// A named animation clip.
#[derive(Clone, Debug)]
pub struct Clip {
    /// The animation's name (`animation<i>` when the file gives none).
    pub name: String,
    /// Earliest key time over its channels, seconds (0 without keys).
    pub start: f32,
    /// Latest key time over its channels, seconds (0 without keys).
    pub end: f32,
    /// The animated properties.
    pub channels: Vec<Channel>,
}

impl Clip {
    /// Length of the clip in seconds (the loop period).
    pub fn duration(&self) -> f32 {
        (self.end - self.start).max(0.0)
    }
}

impl Channel {
    /// The channel's value at time `t` (clamped to the key range).
    pub fn sample(&self, t: f32) -> Vec4 {
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| {
            if cubic {
                self.values[3 * k + 1]
            } else {
                self.values[k]
            }
        };
        if n == 0 {
            return Vec4::ZERO;
        }
        if n == 1 || t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        // Last key with time <= t.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let u = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => {
                let (a, b) = (value(k), value(k + 1));
                if self.property == Property::Rotation {
                    let qa = Quat::from_vec4(a).normalize();
                    let qb = Quat::from_vec4(b).normalize();
                    Vec4::from(qa.slerp(qb, u))
                } else {
                    a.lerp(b, u)
                }
            }
            Interpolation::CubicSpline => {
                let p0 = self.values[3 * k + 1];
                let m0 = self.values[3 * k + 2] * dt;
                let p1 = self.values[3 * (k + 1) + 1];
                let m1 = self.values[3 * (k + 1)] * dt;
                let u2 = u * u;
                let u3 = u2 * u;
                let v = p0 * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + m0 * (u3 - 2.0 * u2 + u)
                    + p1 * (-2.0 * u3 + 3.0 * u2)
                    + m1 * (u3 - u2);
                if self.property == Property::Rotation {
                    Vec4::from(Quat::from_vec4(v).normalize())
                } else {
                    v
                }
            }
        }
    }
}

/// Local transforms of every node at time `t` of `clip` (rest pose where no channel drives).
pub fn local_pose(nodes: &[Node], clip: Option<&Clip>, t: f32) -> Vec<Trs> {
    let mut pose: Vec<Trs> = nodes.iter().map(|n| n.rest).collect();
    if let Some(clip) = clip {
        for ch in &clip.channels {
            let v = ch.sample(t);
            let trs = &mut pose[ch.node];
            match ch.property {
                Property::Translation => trs.translation = v.truncate(),
                Property::Scale => trs.scale = v.truncate(),
                Property::Rotation => trs.rotation = Quat::from_vec4(v).normalize(),
            }
        }
    }
    pose
}

/// World matrices of every node for a local pose; `order` lists parents before children.
pub fn world_matrices(nodes: &[Node], order: &[usize], pose: &[Trs]) -> Vec<Mat4> {
    let mut world = vec![Mat4::IDENTITY; nodes.len()];
    for &i in order {
        let local = pose[i].matrix();
        world[i] = match nodes[i].parent {
            Some(p) => world[p] * local,
            None => local,
        };
    }
    world
}

/// A node hierarchy with rest transforms and the clips that drive it. Node and channel indices
/// are the rig's own: the imported tree's rig holds every glTF node, a LOD's rig may be pruned
/// ([`Rig::retain`]) or rebuilt (skeleton simplification).
#[derive(Clone, Debug, Default)]
pub struct Rig {
    /// Nodes; `parent`/`children` index this list.
    pub nodes: Vec<Node>,
    /// Nodes ordered parents first (for world transforms).
    pub order: Vec<usize>,
    /// Clips over these nodes; each keeps the input's name, start and end.
    pub clips: Vec<Clip>,
}

impl Rig {
    /// World matrices of every node at time `t` of clip `clip` (rest pose when None).
    pub fn world_at(&self, clip: Option<usize>, t: f32) -> Vec<Mat4> {
        let local = local_pose(&self.nodes, clip.and_then(|c| self.clips.get(c)), t);
        world_matrices(&self.nodes, &self.order, &local)
    }

    /// Rest world matrices of every node.
    pub fn rest_world(&self) -> Vec<Mat4> {
        self.world_at(None, 0.0)
    }

    /// Index of the clip named `name`.
    pub fn clip_named(&self, name: &str) -> Option<usize> {
        self.clips.iter().position(|c| c.name == name)
    }

    /// The nodes `wanted` selects and all their ancestors, as a flag per node.
    pub fn with_ancestors(&self, wanted: impl Fn(usize) -> bool) -> Vec<bool> {
        let mut kept = vec![false; self.nodes.len()];
        for i in (0..self.nodes.len()).filter(|&i| wanted(i)) {
            let mut cur = Some(i);
            while let Some(c) = cur {
                if kept[c] {
                    break;
                }
                kept[c] = true;
                cur = self.nodes[c].parent;
            }
        }
        kept
    }

    /// Keeps only `keep` (and their ancestors), remapping indices; returns old → new index.
    /// Channels of removed nodes are dropped; clips are kept (names and lengths), even when
    /// left without channels. Kept nodes lose their `bone` (a LOD's skin is its own).
    pub fn retain(&mut self, keep: &[bool]) -> Vec<Option<usize>> {
        let n = self.nodes.len();
        let kept = self.with_ancestors(|i| keep.get(i).copied().unwrap_or(false));
        let mut map = vec![None; n];
        let mut next = 0;
        for (i, k) in kept.iter().enumerate() {
            if *k {
                map[i] = Some(next);
                next += 1;
            }
        }
        let mut nodes = Vec::with_capacity(next);
        for (i, node) in self.nodes.iter().enumerate() {
            if !kept[i] {
                continue;
            }
            let mut node = node.clone();
            node.parent = node.parent.and_then(|p| map[p]);
            node.children = node.children.iter().filter_map(|&c| map[c]).collect();
            node.bone = None;
            nodes.push(node);
        }
        self.order = self.order.iter().filter_map(|&i| map[i]).collect();
        self.nodes = nodes;
        for clip in &mut self.clips {
            clip.channels.retain(|c| map[c.node].is_some());
            for c in &mut clip.channels {
                c.node = map[c.node].unwrap_or(0);
            }
        }
        map
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(
        interpolation: Interpolation,
        property: Property,
        times: &[f32],
        values: &[Vec4],
    ) -> Channel {
        Channel {
            node: 0,
            property,
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
        }
    }

    #[test]
    fn cubic_spline_is_hermite_with_tangents_scaled_by_the_key_interval() {
        // p0 = 0, p1 = 1, out-tangent of key 0 = 2, in-tangent of key 1 = 0, interval 2 s:
        // p(u) = (2u³ - 3u² + 1)·0 + (u³ - 2u² + u)·(2·2) + (-2u³ + 3u²)·1 + (u³ - u²)·0.
        let v = |x: f32| Vec4::new(x, 0.0, 0.0, 0.0);
        let c = channel(
            Interpolation::CubicSpline,
            Property::Translation,
            &[0.0, 2.0],
            &[v(9.0), v(0.0), v(2.0), v(0.0), v(1.0), v(9.0)],
        );
        for u in [0.0f32, 0.25, 0.5, 0.9, 1.0] {
            let want = (u * u * u - 2.0 * u * u + u) * 4.0 + (-2.0 * u * u * u + 3.0 * u * u);
            assert!((c.sample(2.0 * u).x - want).abs() < 1e-5, "u={u}");
        }
        // Outside the key range the end values hold.
        assert_eq!(c.sample(-1.0).x, 0.0);
        assert_eq!(c.sample(5.0).x, 1.0);
    }

    #[test]
    fn linear_rotation_takes_the_shortest_path() {
        let a = Quat::from_rotation_y(0.2);
        let b = -Quat::from_rotation_y(0.6); // same rotation, opposite hemisphere
        let c = channel(
            Interpolation::Linear,
            Property::Rotation,
            &[0.0, 1.0],
            &[Vec4::from(a), Vec4::from(b)],
        );
        let mid = Quat::from_vec4(c.sample(0.5));
        assert!(mid.angle_between(Quat::from_rotation_y(0.4)) < 1e-5);
    }

    #[test]
    fn linear_translation_interpolates_and_step_holds() {
        let keys = [Vec4::ZERO, Vec4::new(2.0, 4.0, 6.0, 0.0)];
        let lin = channel(
            Interpolation::Linear,
            Property::Translation,
            &[1.0, 3.0],
            &keys,
        );
        assert!((lin.sample(2.5) - Vec4::new(1.5, 3.0, 4.5, 0.0)).length() < 1e-6);
        let step = channel(
            Interpolation::Step,
            Property::Translation,
            &[1.0, 3.0],
            &keys,
        );
        assert_eq!(step.sample(2.99), Vec4::ZERO);
        assert_eq!(step.sample(3.0), keys[1]);
    }
}
