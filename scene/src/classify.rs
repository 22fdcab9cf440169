//! Foliage vs wood: decides per primitive, from user overrides, names, alpha mode, or the shape
//! of its connected pieces (many small disconnected cards), and records why.

use std::collections::HashMap;

use glam::Vec3;

use crate::model::{AlphaMode, Classification, Material, Part, Tree, Triangle};

/// Name fragments that mark foliage.
pub const FOLIAGE_WORDS: &[&str] = &["leaf", "leaves", "foliage", "needle", "frond", "card"];
/// Name fragments that mark wood.
pub const WOOD_WORDS: &[&str] = &["bark", "trunk", "branch", "wood", "stem", "twig"];

/// One imported primitive before classification.
pub struct PrimitiveInfo {
    /// Name of its mesh (for reports and name heuristics).
    pub mesh: String,
    /// The node that instances it.
    pub node: usize,
    /// Index of the primitive in its mesh.
    pub primitive: usize,
    /// Its material's index, if it has one.
    pub material: Option<usize>,
    /// Its triangles, as indices into the tree's flattened vertices.
    pub triangles: Vec<[u32; 3]>,
}

/// Statistics of a primitive's connected pieces (vertices welded by position).
struct Pieces {
    count: usize,
    median_triangles: usize,
    median_extent: f32,
}

fn pieces(tris: &[[u32; 3]], pos: &[Vec3]) -> Pieces {
    // Weld by quantised position so split vertices (Blender export) stay connected.
    let mut key_of: HashMap<[i64; 3], usize> = HashMap::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut vert_key = HashMap::new();
    let q = |p: Vec3| [(p.x * 1e5) as i64, (p.y * 1e5) as i64, (p.z * 1e5) as i64];
    for t in tris {
        for &v in t {
            vert_key.entry(v).or_insert_with(|| {
                let k = q(pos[v as usize]);
                *key_of.entry(k).or_insert_with(|| {
                    parent.push(parent.len());
                    parent.len() - 1
                })
            });
        }
    }
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in tris {
        let a = find(&mut parent, vert_key[&t[0]]);
        for &v in &t[1..] {
            let b = find(&mut parent, vert_key[&v]);
            if a != b {
                parent[b] = a;
            }
        }
    }
    let mut stats: HashMap<usize, (usize, Vec3, Vec3)> = HashMap::new();
    for t in tris {
        let r = find(&mut parent, vert_key[&t[0]]);
        let e = stats.entry(r).or_insert((
            0,
            Vec3::splat(f32::INFINITY),
            Vec3::splat(f32::NEG_INFINITY),
        ));
        e.0 += 1;
        for &v in t {
            e.1 = e.1.min(pos[v as usize]);
            e.2 = e.2.max(pos[v as usize]);
        }
    }
    let mut counts: Vec<usize> = stats.values().map(|s| s.0).collect();
    let mut extents: Vec<f32> = stats.values().map(|s| (s.2 - s.1).max_element()).collect();
    counts.sort_unstable();
    extents.sort_by(f32::total_cmp);
    Pieces {
        count: counts.len(),
        median_triangles: counts.get(counts.len() / 2).copied().unwrap_or(0),
        median_extent: extents.get(extents.len() / 2).copied().unwrap_or(0.0),
    }
}

fn has_word(name: &str, words: &[&str]) -> Option<String> {
    let lower = name.to_lowercase();
    words
        .iter()
        .find(|w| lower.contains(*w))
        .map(|w| w.to_string())
}

/// Materials the user named as foliage or as wood ([`ImportOptions::foliage_materials`](crate::ImportOptions::foliage_materials),
/// [`ImportOptions::wood_materials`](crate::ImportOptions::wood_materials)): they win over
/// every heuristic.
#[derive(Clone, Copy, Debug)]
pub struct MaterialOverrides<'a> {
    /// Names of materials whose primitives are foliage.
    pub foliage: &'a [String],
    /// Names of materials whose primitives are wood.
    pub wood: &'a [String],
}

/// Classifies every primitive and flattens them into triangles. Primitives without a material
/// get a default one appended to `tree.materials` by the caller's materials list.
pub fn classify_primitives(
    tree: &Tree,
    prims: &[PrimitiveInfo],
    rest: &[Vec3],
    overrides: MaterialOverrides,
) -> (Vec<Triangle>, Vec<Classification>) {
    let tree_size = crate::model::Bounds::of(
        prims
            .iter()
            .flat_map(|p| p.triangles.iter().flatten().map(|&v| rest[v as usize])),
    )
    .size();
    let default_material = tree.materials.len() as u32;
    let mut tris = Vec::new();
    let mut report = Vec::new();
    for p in prims {
        let mat: Option<&Material> = p.material.map(|m| &tree.materials[m]);
        let mat_name = mat
            .map(|m| m.name.clone())
            .unwrap_or_else(|| "(none)".into());
        let node_name = &tree.rig.nodes[p.node].name;
        let (part, reason) = if overrides.foliage.contains(&mat_name) {
            (
                Part::Foliage,
                format!("material '{mat_name}' named as foliage"),
            )
        } else if overrides.wood.contains(&mat_name) {
            (Part::Wood, format!("material '{mat_name}' named as wood"))
        } else if let Some(w) = has_word(&mat_name, FOLIAGE_WORDS) {
            (Part::Foliage, format!("material name contains '{w}'"))
        } else if let Some(w) = has_word(&mat_name, WOOD_WORDS) {
            (Part::Wood, format!("material name contains '{w}'"))
        } else if let Some(w) =
            has_word(&p.mesh, FOLIAGE_WORDS).or_else(|| has_word(node_name, FOLIAGE_WORDS))
        {
            (Part::Foliage, format!("mesh or node name contains '{w}'"))
        } else if let Some(w) =
            has_word(&p.mesh, WOOD_WORDS).or_else(|| has_word(node_name, WOOD_WORDS))
        {
            (Part::Wood, format!("mesh or node name contains '{w}'"))
        } else if let Some(m) = mat.filter(|m| m.alpha_mode != AlphaMode::Opaque) {
            (
                Part::Foliage,
                format!(
                    "alpha-{} material",
                    if m.alpha_mode == AlphaMode::Mask {
                        "masked"
                    } else {
                        "blended"
                    }
                ),
            )
        } else {
            let pc = pieces(&p.triangles, rest);
            if pc.count >= 8 && pc.median_triangles <= 12 && pc.median_extent <= 0.1 * tree_size {
                (
                    Part::Foliage,
                    format!(
                        "{} small disconnected cards (median {} triangles, {:.3} wide)",
                        pc.count, pc.median_triangles, pc.median_extent
                    ),
                )
            } else {
                (
                    Part::Wood,
                    "opaque, connected geometry (default)".to_string(),
                )
            }
        };
        let material = p.material.map(|m| m as u32).unwrap_or(default_material);
        report.push(Classification {
            mesh: p.mesh.clone(),
            primitive: p.primitive,
            material: mat_name,
            part,
            reason,
            triangles: p.triangles.len(),
        });
        tris.extend(p.triangles.iter().map(|&v| Triangle {
            v,
            material,
            part,
            degenerate: false,
            bone: None,
        }));
    }
    (tris, report)
}
