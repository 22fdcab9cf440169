//! Turns a simplified skeleton back into glTF-shaped rig nodes and a clip (spec
//! animated-billboard-clouds §6.4 step 5): without collapses the simplified skeleton replaces
//! the input's in place (its changed bones get resampled channels, new bones are appended), so
//! one skeleton drives trunk and foliage; after a collapse the input's skeleton is kept whole
//! for the trunk and the foliage gets its own copies of every bone that changed or hangs
//! below one (§7.4: the trunk stays on the original skeleton).

use frond_scene::rig::{Channel, Interpolation, Property};
use frond_scene::{Node, Rig, Tree};
use glam::{Quat, Vec4};

use crate::model::SkeletonModel;

/// The simplified skeleton as a glTF-shaped rig.
#[derive(Clone, Debug)]
pub struct MaterializedRig {
    /// The simplified nodes, their rest transforms and the resampled clip.
    pub rig: Rig,
    /// Rig node of every model node (None for nodes the foliage no longer needs).
    pub map: Vec<Option<usize>>,
}

/// Key times of the resampled channels: the loop's samples, then the loop's end repeating the
/// first sample so LINEAR playback wraps smoothly.
fn key_times(times: &[f32], period: f32) -> Vec<f32> {
    let mut t = times.to_vec();
    if period > 0.0
        && let Some(&first) = times.first()
    {
        t.push(first + period);
    }
    t
}

/// Channels replaying model node `i`'s sampled track on rig node `node`: rotation always,
/// translation and scale only where they move.
fn channels(model: &SkeletonModel, i: usize, node: usize, times: &[f32]) -> Vec<Channel> {
    let track = &model.nodes[i].track;
    let n = times.len();
    let at = |k: usize| &track[k % track.len()];
    let mut rotations: Vec<Vec4> = Vec::with_capacity(n);
    let mut prev = Quat::IDENTITY;
    for k in 0..n {
        let mut q = at(k).rotation.normalize();
        if k > 0 && q.dot(prev) < 0.0 {
            q = -q;
        }
        prev = q;
        rotations.push(Vec4::from(q));
    }
    let mut out = vec![Channel {
        node,
        property: Property::Rotation,
        interpolation: Interpolation::Linear,
        times: times.to_vec(),
        values: rotations,
    }];
    let moves = |f: &dyn Fn(&frond_scene::Trs) -> glam::Vec3| {
        let first = f(at(0));
        track.iter().any(|t| f(t).distance(first) > 1e-7)
    };
    if moves(&|t| t.translation) || at(0).translation != model.nodes[i].rest.translation {
        out.push(Channel {
            node,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: times.to_vec(),
            values: (0..n).map(|k| at(k).translation.extend(0.0)).collect(),
        });
    }
    if moves(&|t| t.scale) || at(0).scale != model.nodes[i].rest.scale {
        out.push(Channel {
            node,
            property: Property::Scale,
            interpolation: Interpolation::Linear,
            times: times.to_vec(),
            values: (0..n).map(|k| at(k).scale.extend(0.0)).collect(),
        });
    }
    out
}

/// The rig of a simplified `model` of `tree`, its clip `clip` resampled at `times` over
/// `period`. `split`: keep the input skeleton for the trunk and give the foliage copies.
pub fn materialize(
    tree: &Tree,
    model: &SkeletonModel,
    clip: Option<usize>,
    times: &[f32],
    period: f32,
    split: bool,
) -> MaterializedRig {
    let mut nodes = tree.rig.nodes.clone();
    let mut order = tree.rig.order.clone();
    let mut clips = tree.rig.clips.clone();
    let counts = model.animated_counts();
    let keys = key_times(times, period);
    let mut map: Vec<Option<usize>> = vec![None; model.nodes.len()];
    let mut copied = vec![false; model.nodes.len()];
    let mut new_channels: Vec<Channel> = Vec::new();
    let mut replaced: Vec<usize> = Vec::new();
    for i in model.order() {
        let m = &model.nodes[i];
        let parent_copied = m.parent.is_some_and(|p| copied[p]);
        let in_place = match m.source {
            Some(_) => !split || (!m.changed && !parent_copied),
            None => false,
        };
        if in_place {
            let s = m.source.unwrap_or(i);
            map[i] = Some(s);
            if m.changed {
                nodes[s].rest = m.rest;
                replaced.push(s);
                new_channels.extend(channels(model, i, s, &keys));
            }
            continue;
        }
        if split && counts[i] == 0 {
            continue;
        }
        let idx = nodes.len();
        let parent = m.parent.and_then(|p| map[p]);
        nodes.push(Node {
            name: if m.source.is_some() {
                format!("{}_sbcs", m.name)
            } else {
                m.name.clone()
            },
            parent,
            children: Vec::new(),
            rest: m.rest,
            bone: None,
            extras: None,
        });
        if let Some(p) = parent {
            nodes[p].children.push(idx);
        }
        order.push(idx);
        map[i] = Some(idx);
        copied[i] = true;
        new_channels.extend(channels(model, i, idx, &keys));
    }
    if let Some(c) = clip.and_then(|c| clips.get_mut(c)) {
        c.channels.retain(|ch| !replaced.contains(&ch.node));
        c.channels.extend(new_channels);
    }
    MaterializedRig {
        rig: Rig {
            nodes,
            order,
            clips,
        },
        map,
    }
}
