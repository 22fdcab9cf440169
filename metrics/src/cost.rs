//! Cost of a model (spec animated-billboard-clouds §5.7): the thesis' hardware-independent
//! pair ⟨billboard count, total billboard area⟩ plus what an engine pays for: triangles,
//! texture bytes, bones, draw calls and file size.

use frond_scene::{Part, Tree};
use glam::Vec3;
use serde::Serialize;

/// What a model costs.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Cost {
    /// Triangles drawn (non-degenerate, wood and foliage).
    pub triangles: usize,
    /// Foliage cards: foliage triangles / 2. For a `frond lod` LOD these are exactly its
    /// billboards; for any other model, its leaf cards counted the same way.
    pub billboards: usize,
    /// Summed rest-pose area of the foliage triangles (world units²), the thesis' resolution-
    /// independent measure of texture memory.
    pub billboard_area: f64,
    /// Decoded bytes of every texture (RGBA8).
    pub texture_bytes: usize,
    /// Skin joints.
    pub bones: usize,
    /// Draw calls: one per primitive (mesh × material).
    pub draw_calls: usize,
    /// Size of the file on disk (0 when unknown).
    pub file_bytes: u64,
}

/// The cost of `tree` (as imported), with `file_bytes` the size of its file.
pub fn cost(tree: &Tree, file_bytes: u64) -> Cost {
    let p = &tree.vertices.position;
    let mut triangles = 0;
    let mut foliage = 0;
    let mut area = 0.0f64;
    for t in tree.triangles.iter().filter(|t| !t.degenerate) {
        triangles += 1;
        if t.part == Part::Foliage {
            foliage += 1;
            let [a, b, c] =
                t.v.map(|i| p.get(i as usize).copied().unwrap_or(Vec3::ZERO));
            area += f64::from(0.5 * (b - a).cross(c - a).length());
        }
    }
    Cost {
        triangles,
        billboards: foliage / 2,
        billboard_area: area,
        texture_bytes: tree.textures.iter().map(|t| t.rgba.len()).sum(),
        bones: tree.bones.len(),
        draw_calls: tree.classification.len(),
        file_bytes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::generator::{Preset, generate};
    use frond_scene::{ImportOptions, import_bytes};

    #[test]
    fn cost_of_a_generated_tree_matches_its_construction() {
        let g = generate(Preset::Small, 3).expect("generate");
        let tree = import_bytes(
            std::path::Path::new("small.glb"),
            &g.glb,
            &ImportOptions::default(),
        )
        .expect("import");
        let c = cost(&tree, g.glb.len() as u64);
        assert_eq!(c.billboards, tree.count(Part::Foliage) / 2);
        assert_eq!(
            c.triangles,
            tree.triangles.iter().filter(|t| !t.degenerate).count()
        );
        assert_eq!(c.bones, tree.bones.len());
        assert_eq!(c.file_bytes, g.glb.len() as u64);
        // Two textures (bark and leaf) decoded as RGBA8, two primitives (wood, leaves).
        assert_eq!(c.texture_bytes, 64 * 64 * 4 + 128 * 128 * 4);
        assert_eq!(c.draw_calls, 2);
        // Every leaf card of the generator is a rectangle: area = Σ |corner₁ − corner₀|·|corner₃ − corner₀|.
        let want: f64 = g
            .leaf_corners
            .iter()
            .map(|q| f64::from((q[1] - q[0]).length() * (q[3] - q[0]).length()))
            .sum();
        assert!(
            (c.billboard_area - want).abs() < 1e-3 * want,
            "{} vs {want}",
            c.billboard_area
        );
    }
}
