//! Animation clips and their evaluation as glTF specifies (LINEAR with shortest-path slerp for
//! rotations, STEP, CUBICSPLINE Hermite), plus world transforms of every node at a time.

use glam::{Mat4, Quat, Vec3, Vec4};

use crate::model::{Node, Trs};

/// Which node property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

/// glTF sampler interpolation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Linear,
    Step,
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    /// Key times, strictly increasing.
    pub times: Vec<f32>,
    /// Key values as Vec4 (xyz for T/S, xyzw for rotation); CUBICSPLINE stores
    /// in-tangent, value, out-tangent per key.
    pub values: Vec<Vec4>,
}

/// A named animation clip.
#[derive(Clone, Debug)]
pub struct Clip {
    pub name: String,
    pub start: f32,
    pub end: f32,
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

/// Rest translation helper used by generators and tests.
pub fn trs(translation: Vec3, rotation: Quat) -> Trs {
    Trs {
        translation,
        rotation,
        scale: Vec3::ONE,
    }
}
