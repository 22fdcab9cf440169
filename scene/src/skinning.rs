//! Linear-blend skinning of the tree's vertices for a set of node world matrices
//! (spec animated-billboard-clouds §7: v' = Σ w · world(joint) · inverseBind · v).

use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;

use crate::model::{Binding, Tree};

/// Per-binding matrix palettes for the given node world matrices.
pub fn palettes(tree: &Tree, world: &[Mat4]) -> Vec<Vec<Mat4>> {
    tree.bindings
        .iter()
        .map(|b| match b {
            Binding::Skin {
                joints,
                inverse_bind,
            } => joints
                .iter()
                .zip(inverse_bind)
                .map(|(&j, ibm)| world[tree.bones[j].node] * *ibm)
                .collect(),
            Binding::Node(n) => vec![world[*n]],
        })
        .collect()
}

/// Skinned positions of every vertex.
pub fn skin_positions(tree: &Tree, world: &[Mat4]) -> Vec<Vec3> {
    let pal = palettes(tree, world);
    let mut out = vec![Vec3::ZERO; tree.vertices.len()];
    skin_into(tree, &pal, &mut out);
    out
}

/// Skins every vertex into `out` (same length as the vertex arrays), in parallel.
pub fn skin_into(tree: &Tree, pal: &[Vec<Mat4>], out: &mut [Vec3]) {
    let v = &tree.vertices;
    out.par_chunks_mut(4096).enumerate().for_each(|(c, chunk)| {
        let base = c * 4096;
        for (k, o) in chunk.iter_mut().enumerate() {
            let i = base + k;
            let p = v.position[i];
            let palette = &pal[v.binding[i] as usize];
            let w = v.weights[i];
            let j = v.joints[i];
            if w[0] >= 1.0 {
                *o = palette[j[0] as usize].transform_point3(p);
                continue;
            }
            let mut acc = Vec3::ZERO;
            for s in 0..4 {
                if w[s] > 0.0 {
                    acc += palette[j[s] as usize].transform_point3(p) * w[s];
                }
            }
            *o = acc;
        }
    });
}

/// Skinned unit normals of every vertex (weight-blended palette rotation; zero stays zero).
pub fn skin_normals(tree: &Tree, pal: &[Vec<Mat4>]) -> Vec<Vec3> {
    skin_directions(tree, pal, &tree.vertices.normal)
}

/// Skinned tangents of every vertex (xyz as [`skin_normals`], w the bitangent's sign kept;
/// zero stays zero), or empty when the tree has none ([`crate::Vertices::tangent`]).
pub fn skin_tangents(tree: &Tree, pal: &[Vec<Mat4>]) -> Vec<Vec4> {
    let t = &tree.vertices.tangent;
    if t.len() != tree.vertices.len() {
        return Vec::new();
    }
    let xyz: Vec<Vec3> = t.iter().map(|t| t.truncate()).collect();
    skin_directions(tree, pal, &xyz)
        .into_iter()
        .zip(t)
        .map(|(d, t)| d.extend(t.w))
        .collect()
}

/// The unit directions `dirs` (one per vertex) skinned: the weight-blended palette rotation.
fn skin_directions(tree: &Tree, pal: &[Vec<Mat4>], dirs: &[Vec3]) -> Vec<Vec3> {
    let v = &tree.vertices;
    (0..v.len())
        .into_par_iter()
        .map(|i| {
            let palette = &pal[v.binding[i] as usize];
            let mut acc = Vec3::ZERO;
            for s in 0..4 {
                let w = v.weights[i][s];
                if w > 0.0 {
                    acc += palette[v.joints[i][s] as usize].transform_vector3(dirs[i]) * w;
                }
            }
            acc.normalize_or_zero()
        })
        .collect()
}
