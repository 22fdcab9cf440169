//! Cost of a model (spec animated-billboard-clouds §5.7) as `frond eval` reports it: the
//! thesis' hardware-independent pair ⟨billboard count, total billboard area⟩ plus what an
//! engine pays for.
//!
//! Two sources, one notion: the pair needs frond's foliage classification, so it is counted on
//! the imported [`Tree`]; everything an engine pays for (triangles, draw calls, joints, keys,
//! texture bytes, file bytes, alpha-tested area) is [`FileCost`], read from the written file by
//! [`frond_scene::file_cost()`], so a frond LOD, the input tree and a foreign file are measured
//! by the same rules. There is no second triangle or texture count here.

use frond_scene::{FileCost, Part, Tree};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// What a model costs (in the JSON, the file's fields sit beside the billboard pair).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Foliage cards: the imported tree's non-degenerate foliage triangles / 2. For a
    /// `frond lod` LOD these are exactly its billboards; for any other model, its leaf cards
    /// counted the same way.
    pub billboards: usize,
    /// Summed rest-pose area of those foliage triangles (world units²), the thesis'
    /// resolution-independent measure of texture memory.
    pub billboard_area: f64,
    /// What the file costs an engine ([`FileCost`]).
    #[serde(flatten)]
    pub file: FileCost,
}

/// The cost of `tree` (as imported) whose file costs `file`.
pub fn cost(tree: &Tree, file: FileCost) -> Cost {
    let p = &tree.vertices.position;
    let mut foliage = 0;
    let mut area = 0.0f64;
    for t in tree
        .triangles
        .iter()
        .filter(|t| !t.degenerate && t.part == Part::Foliage)
    {
        foliage += 1;
        let [a, b, c] =
            t.v.map(|i| p.get(i as usize).copied().unwrap_or(Vec3::ZERO));
        area += f64::from(0.5 * (b - a).cross(c - a).length());
    }
    Cost {
        billboards: foliage / 2,
        billboard_area: area,
        file,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::generator::{Preset, generate};
    use frond_scene::{ImportOptions, InputLimits, file_cost_bytes, import_bytes};

    #[test]
    fn cost_of_a_generated_tree_matches_its_construction() {
        let g = generate(Preset::Small, 3).expect("generate");
        let path = std::path::Path::new("small.glb");
        let tree = import_bytes(path, &g.glb, &ImportOptions::default()).expect("import");
        let file = file_cost_bytes(path, &g.glb, &InputLimits::default()).expect("file cost");
        let c = cost(&tree, file.clone());
        assert_eq!(c.billboards, g.leaf_corners.len());
        assert_eq!(c.file, file);
        // The leaf cards are the billboards: their summed area.
        let want = g.leaf_card_area();
        assert!(
            (c.billboard_area - want).abs() < 1e-3 * want,
            "{} vs {want}",
            c.billboard_area
        );
        // The leaves are the file's only alpha-tested triangles: both areas agree.
        assert!((c.billboard_area - c.file.alpha_tested_area).abs() < 1e-3 * want);
        // The JSON puts the file's fields beside the pair.
        let json = serde_json::to_value(&c).expect("JSON");
        assert_eq!(json["billboards"], g.leaf_corners.len());
        assert_eq!(json["triangles"], file.triangles);
        assert_eq!(json["texture_decoded_bytes"], (64 * 64 + 128 * 128) * 4);
    }
}
