//! Skins: their joints as [`Bone`]s and [`Binding::Skin`]s, and the check that no vertex is
//! skinned through a singular inverse bind matrix.

use std::collections::HashMap;

use glam::Mat4;

use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::model::{Binding, Bone, Vertices};
use crate::rig::Node;

/// Reads every skin: each joint node becomes one [`Bone`] (a node that several skins use is one
/// bone), each skin a [`Binding::Skin`] with its joints' bones and inverse bind matrices
/// (identity when the skin gives none). A bone's parent is its nearest ancestor node that is
/// also a bone.
///
/// Refused: a joint naming a missing node, a skin with no joints or more than 65535 (vertices
/// carry joint ids as u16), and inverse bind matrices of the wrong type or count, or with NaN
/// or Inf.
pub(super) fn read_skins(src: &GltfSource, nodes: &[Node]) -> Result<(Vec<Bone>, Vec<Binding>)> {
    let mut bone_of_node: HashMap<usize, usize> = HashMap::new();
    let mut bones: Vec<Bone> = Vec::new();
    let mut bindings = Vec::new();
    for (s, skin) in src.root.skins.iter().enumerate() {
        let what = format!("skin {s}");
        let mut joints = Vec::with_capacity(skin.joints.len());
        for j in &skin.joints {
            let node = j.value();
            if node >= nodes.len() {
                return Err(src.invalid(format!("{what}: joint node {node} does not exist")));
            }
            let b = *bone_of_node.entry(node).or_insert_with(|| {
                bones.push(Bone {
                    name: nodes[node].name.clone(),
                    node,
                    parent: None,
                    depth: 1,
                    rest_world: Mat4::IDENTITY,
                });
                bones.len() - 1
            });
            joints.push(b);
        }
        if joints.is_empty() || joints.len() > u16::MAX as usize {
            return Err(src.invalid(format!(
                "{what}: has {} joints (1 to 65535 supported)",
                joints.len()
            )));
        }
        let inverse_bind = match skin.inverse_bind_matrices {
            Some(acc) => {
                let d = src.read_floats(acc.value(), &format!("{what} inverseBindMatrices"))?;
                if d.width != 16 || d.count() < joints.len() {
                    return Err(src.invalid(format!(
                        "{what}: inverseBindMatrices must hold one MAT4 per joint ({} joints, {} matrices)",
                        joints.len(),
                        d.count()
                    )));
                }
                let mats: Vec<Mat4> = (0..joints.len())
                    .map(|k| Mat4::from_cols_array(&d.get::<16>(k)))
                    .collect();
                if mats.iter().any(|m| !m.is_finite()) {
                    return Err(
                        src.invalid(format!("{what}: inverseBindMatrices contain NaN or Inf"))
                    );
                }
                mats
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        bindings.push(Binding::Skin {
            joints,
            inverse_bind,
        });
    }
    // Bone parent: nearest ancestor node that is a bone. Depth via parents-first pass.
    for b in 0..bones.len() {
        let mut p = nodes[bones[b].node].parent;
        while let Some(n) = p {
            if let Some(&pb) = bone_of_node.get(&n) {
                bones[b].parent = Some(pb);
                break;
            }
            p = nodes[n].parent;
        }
    }
    for b in 0..bones.len() {
        let mut depth = 1;
        let mut p = bones[b].parent;
        while let Some(pb) = p {
            depth += 1;
            p = bones[pb].parent;
            if depth as usize > bones.len() {
                break;
            }
        }
        bones[b].depth = depth;
    }
    Ok((bones, bindings))
}

/// How far an inverse bind matrix is from singular: |det| of its 3×3 part over the product of
/// its column lengths (Hadamard's bound), so 1 for a rotation-and-scale matrix of any scale and
/// 0 for a singular one. Computed in f64 so large but sane scales do not overflow.
fn bind_conditioning(m: &Mat4) -> f64 {
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate().as_dvec3());
    let norms = cols[0].length() * cols[1].length() * cols[2].length();
    if norms > 0.0 && norms.is_finite() {
        glam::DMat3::from_cols(cols[0], cols[1], cols[2])
            .determinant()
            .abs()
            / norms
    } else {
        0.0
    }
}

/// Inverse bind matrices closer to singular than this (see [`bind_conditioning`]) are refused:
/// skinning through them flattens every vertex weighted to that joint onto a plane, a line or
/// a point, and later stages then fail on the symptom ("the tree has no height").
const SINGULAR_BIND: f64 = 1e-6;

/// Checks every skin's inverse bind matrices for singular ones. A singular matrix on a joint
/// that some vertex is weighted to (including vertices without weights, bound to the first
/// joint) is an error naming the skin, the joint and its node; on a joint no vertex uses it is
/// harmless for frond, so only a warning.
pub(super) fn check_inverse_binds(
    src: &GltfSource,
    bones: &[Bone],
    bindings: &[Binding],
    verts: &Vertices,
    warnings: &mut Vec<String>,
) -> Result<()> {
    for (s, binding) in bindings.iter().enumerate() {
        let Binding::Skin {
            joints,
            inverse_bind,
        } = binding
        else {
            continue;
        };
        let singular: Vec<usize> = (0..inverse_bind.len())
            .filter(|&k| bind_conditioning(&inverse_bind[k]) < SINGULAR_BIND)
            .collect();
        let Some(&first) = singular.first() else {
            continue;
        };
        // Vertices weighted to each joint of this skin.
        let mut users = vec![0usize; joints.len()];
        for v in 0..verts.len() {
            if verts.binding[v] as usize != s {
                continue;
            }
            for j in 0..4 {
                if verts.weights[v][j] > 0.0
                    && let Some(u) = users.get_mut(verts.joints[v][j] as usize)
                {
                    *u += 1;
                }
            }
        }
        let skin_name = src
            .root
            .skins
            .get(s)
            .and_then(|sk| sk.name.as_deref())
            .map(|n| format!(" ('{n}')"))
            .unwrap_or_default();
        let joint = |k: usize| {
            let b = &bones[joints[k]];
            format!(
                "the inverse bind matrix of joint {k} (node {} '{}') is singular (determinant {:?})",
                b.node,
                b.name,
                inverse_bind[k].determinant()
            )
        };
        if let Some(&k) = singular.iter().find(|&&k| users[k] > 0) {
            return Err(src.invalid(format!(
                "skin {s}{skin_name}: {}; the {} vertices weighted to it would collapse",
                joint(k),
                users[k]
            )));
        }
        let more = match singular.len() {
            1 => String::new(),
            n => format!(" (and {} more joints)", n - 1),
        };
        warnings.push(format!(
            "skin {s}{skin_name}: {}{more}; harmless here, as no vertex is weighted to it",
            joint(first)
        ));
    }
    Ok(())
}
