//! A tree's wood or foliage as one skinned mesh over rig nodes, what the chain builder and the
//! card method both start from, and the area of its triangles (card sizes, alpha-tested area).

use frond_scene::wood::{NO_BONE, WoodMesh};
use frond_scene::{Part, Tree};

/// The tree's wood or foliage with bones as rig node indices.
pub(crate) fn part_mesh(tree: &Tree, part: Part) -> WoodMesh {
    let mut m = WoodMesh::from_tree_part(tree, part);
    for b in m.bones.iter_mut().flatten() {
        if *b != NO_BONE {
            *b = tree.bones[*b as usize].node as u32;
        }
    }
    m
}

/// Area of triangle `t` of primitive `p`.
pub(crate) fn triangle_area(mesh: &WoodMesh, p: usize, t: usize) -> f32 {
    let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
    let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[i[k] as usize]);
    0.5 * (b - a).cross(c - a).length()
}
