//! Draws a tree from the scene stage: its skinned pose at a time as a [`DrawScene`], one mesh
//! per material, alpha-tested cut-outs for masked and blended materials.

use frond_scene::sampling::world_at;
use frond_scene::skinning::{palettes, skin_into, skin_normals};
use frond_scene::{AlphaMode, Part, Tree};
use glam::Vec3;

use crate::scene::{DrawMaterial, DrawMesh, DrawScene, DrawTexture};

/// Which triangles of the tree to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeParts {
    All,
    Wood,
    Foliage,
}

/// The tree posed at time `t` of clip `clip` (rest pose when None).
pub fn tree_scene(tree: &Tree, clip: Option<usize>, t: f32, parts: TreeParts) -> DrawScene {
    let world = world_at(tree, clip, t);
    let pal = palettes(tree, &world);
    let mut positions = vec![Vec3::ZERO; tree.vertices.len()];
    skin_into(tree, &pal, &mut positions);
    let normals = skin_normals(tree, &pal);
    scene_from_positions(tree, &positions, Some(&normals), parts)
}

/// A draw scene of `tree`'s triangles at the given vertex positions (e.g. a sampled pose or
/// the average pose).
pub fn scene_from_positions(
    tree: &Tree,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    parts: TreeParts,
) -> DrawScene {
    let mut meshes: Vec<DrawMesh> = Vec::new();
    let mut remap: Vec<u32> = vec![u32::MAX; positions.len()];
    for (m, _) in tree.materials.iter().enumerate() {
        let mut mesh = DrawMesh {
            material: m,
            ..Default::default()
        };
        let mut pos = Vec::new();
        let mut nrm = Vec::new();
        let mut uvs = Vec::new();
        for t in &tree.triangles {
            let keep = match parts {
                TreeParts::All => true,
                TreeParts::Wood => t.part == Part::Wood,
                TreeParts::Foliage => t.part == Part::Foliage,
            };
            if t.material as usize != m || t.degenerate || !keep {
                continue;
            }
            for &v in &t.v {
                let v = v as usize;
                if remap[v] == u32::MAX {
                    remap[v] = pos.len() as u32;
                    pos.push(positions[v].to_array());
                    if let Some(n) = normals {
                        nrm.push(n[v].to_array());
                    }
                    uvs.push(tree.vertices.uv[v].to_array());
                }
                mesh.indices.push(remap[v]);
            }
        }
        if mesh.indices.is_empty() {
            continue;
        }
        // Reset the remap entries this material used.
        for t in &tree.triangles {
            if t.material as usize == m {
                for &v in &t.v {
                    remap[v as usize] = u32::MAX;
                }
            }
        }
        mesh.positions = pos;
        mesh.normals = normals.map(|_| nrm);
        mesh.uvs = Some(uvs);
        meshes.push(mesh);
    }
    let materials = tree
        .materials
        .iter()
        .map(|m| DrawMaterial {
            wrap: m.base_color_wrap,
            base_color: m.base_color,
            texture: m.base_color_texture,
            alpha_cutoff: match m.alpha_mode {
                AlphaMode::Opaque => None,
                AlphaMode::Mask => Some(m.alpha_cutoff),
                AlphaMode::Blend => Some(0.5),
            },
            double_sided: m.double_sided,
        })
        .collect();
    let textures = tree
        .textures
        .iter()
        .map(|t| DrawTexture {
            width: t.width,
            height: t.height,
            rgba: t.rgba.clone(),
        })
        .collect();
    DrawScene {
        meshes,
        materials,
        textures,
    }
}
