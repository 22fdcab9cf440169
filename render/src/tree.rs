//! Draws a tree from the scene stage: its skinned pose at a time as a [`DrawScene`], one mesh
//! per material, alpha-tested cut-outs for masked and blended materials.

use frond_scene::sampling::world_at;
use frond_scene::skinning::{palettes, skin_into, skin_normals, skin_tangents};
use frond_scene::{AlphaMode, Part, Tree};
use glam::{Vec3, Vec4};

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
    let tangents = skin_tangents(tree, &pal);
    let tangents = (!tangents.is_empty()).then_some(tangents.as_slice());
    posed_scene(tree, &positions, Some(&normals), tangents, parts)
}

/// A draw scene of `tree`'s triangles at the given vertex positions (e.g. a sampled pose or
/// the average pose).
pub fn scene_from_positions(
    tree: &Tree,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    parts: TreeParts,
) -> DrawScene {
    posed_scene(tree, positions, normals, None, parts)
}

/// [`scene_from_positions`] with the tangents too (one per vertex, zero where the input gave
/// none), which let the materials' normal maps apply ([`DrawMaterial::normal_texture`]).
fn posed_scene(
    tree: &Tree,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    tangents: Option<&[Vec4]>,
    parts: TreeParts,
) -> DrawScene {
    // Normal maps need a normal and a tangent frame on every vertex of their mesh.
    let framed = |m: usize| -> bool {
        normals.is_some()
            && tangents.is_some_and(|t| {
                tree.triangles
                    .iter()
                    .filter(|tri| tri.material as usize == m)
                    .all(|tri| tri.v.iter().all(|&v| t[v as usize] != Vec4::ZERO))
            })
    };
    let mut mapped = vec![false; tree.materials.len()];
    let mut meshes: Vec<DrawMesh> = Vec::new();
    let mut remap: Vec<u32> = vec![u32::MAX; positions.len()];
    for (m, _) in tree.materials.iter().enumerate() {
        let mut mesh = DrawMesh {
            material: m,
            ..Default::default()
        };
        let mut pos = Vec::new();
        let mut nrm = Vec::new();
        let mut tan = Vec::new();
        let mut uvs = Vec::new();
        let with_tangents = tree.materials[m].normal_texture.is_some() && framed(m);
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
                    if let (true, Some(t)) = (with_tangents, tangents) {
                        tan.push(t[v].to_array());
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
        if with_tangents {
            mesh.tangents = Some(tan);
            mapped[m] = true;
        }
        mesh.uvs = Some(uvs);
        meshes.push(mesh);
    }
    let materials = tree
        .materials
        .iter()
        .zip(&mapped)
        .map(|(m, &mapped)| DrawMaterial {
            wrap: m.base_color_wrap,
            base_color: m.base_color,
            texture: m.base_color_texture,
            normal_texture: m.normal_texture.filter(|_| mapped),
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
