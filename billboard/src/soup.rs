//! The input of a billboard cloud: a triangle soup with texture coordinates and materials.

use glam::{Vec2, Vec3};

/// Triangles to simplify (one cluster), each with its own corners, UVs and material index.
#[derive(Clone, Debug, Default)]
pub struct TriangleSoup {
    /// Each triangle's corners, world units.
    pub positions: Vec<[Vec3; 3]>,
    /// Each corner's texture coordinates in its material's base colour texture.
    pub uvs: Vec<[Vec2; 3]>,
    /// Index into the caller's material list (as in `frond_scene::Tree::materials`).
    pub material: Vec<u32>,
}

impl TriangleSoup {
    /// The given triangles of `tree` at vertex positions `positions` (a sampled or average pose).
    pub fn from_tree(
        tree: &frond_scene::Tree,
        positions: &[Vec3],
        triangles: &[usize],
    ) -> TriangleSoup {
        let mut soup = TriangleSoup::default();
        for &t in triangles {
            let tri = &tree.triangles[t];
            soup.positions.push(tri.v.map(|v| positions[v as usize]));
            soup.uvs.push(tri.v.map(|v| tree.vertices.uv[v as usize]));
            soup.material.push(tri.material);
        }
        soup
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
    /// Unit normal of triangle `i` (zero for a degenerate one).
    pub fn normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.positions[i];
        (b - a).cross(c - a).normalize_or_zero()
    }
    /// Area of triangle `i`.
    pub fn area(&self, i: usize) -> f32 {
        let [a, b, c] = self.positions[i];
        0.5 * (b - a).cross(c - a).length()
    }
}
