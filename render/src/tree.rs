//! Draws a tree from the scene stage: its skinned pose at a time as a [`DrawScene`], one mesh
//! per material, alpha-tested cut-outs for masked and blended materials.

use frond_scene::sampling::world_at;
use frond_scene::skinning::{palettes, skin_into, skin_normals, skin_tangents};
use frond_scene::{AlphaMode, Part, Tree};
use glam::{Vec3, Vec4};

use crate::scene::{DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture};

/// Which triangles of the tree to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TreeParts {
    /// Every triangle: wood and foliage.
    All,
    /// The wood alone (trunk and branches), as the scene stage classifies it.
    Wood,
    /// The foliage alone (leaves and other cards), as the scene stage classifies it.
    Foliage,
}

/// The tree posed at time `t` of clip `clip` (rest pose when None).
pub fn tree_scene(tree: &Tree, clip: Option<usize>, t: f32, parts: TreeParts) -> DrawScene {
    PosedTree::new(tree, clip, t, parts).scene
}

/// A tree's draw scene built once and posed many times (a flip-book, the frames of a metric):
/// the meshes' vertex order, the materials and the textures stay; [`PosedTree::pose`] rewrites
/// positions, normals and tangents only, instead of rebuilding the scene and copying every
/// texture per frame.
pub struct PosedTree<'a> {
    tree: &'a Tree,
    scene: DrawScene,
    /// Per mesh of `scene`, the tree vertex of each of its vertices.
    sources: Vec<Vec<u32>>,
}

/// A pose of a tree: skinned positions, normals and tangents (empty when the tree has none).
struct Pose {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    tangents: Vec<Vec4>,
}

fn pose_at(tree: &Tree, clip: Option<usize>, t: f32) -> Pose {
    let world = world_at(tree, clip, t);
    let pal = palettes(tree, &world);
    let mut positions = vec![Vec3::ZERO; tree.vertices.len()];
    skin_into(tree, &pal, &mut positions);
    Pose {
        positions,
        normals: skin_normals(tree, &pal),
        tangents: skin_tangents(tree, &pal),
    }
}

impl<'a> PosedTree<'a> {
    /// `tree`'s `parts` posed at time `t` of clip `clip` (rest pose when None).
    pub fn new(tree: &'a Tree, clip: Option<usize>, t: f32, parts: TreeParts) -> PosedTree<'a> {
        let p = pose_at(tree, clip, t);
        let tangents = (!p.tangents.is_empty()).then_some(p.tangents.as_slice());
        let (scene, sources) = build_scene(tree, &p.positions, Some(&p.normals), tangents, parts);
        PosedTree {
            tree,
            scene,
            sources,
        }
    }

    /// The scene posed at time `t` of clip `clip`: the same meshes as [`PosedTree::new`]
    /// built, with this pose's vertices (what [`tree_scene`] would return).
    pub fn pose(&mut self, clip: Option<usize>, t: f32) -> &DrawScene {
        let p = pose_at(self.tree, clip, t);
        for (mesh, src) in self.scene.meshes.iter_mut().zip(&self.sources) {
            for (out, &v) in mesh.positions.iter_mut().zip(src) {
                *out = p.positions[v as usize].to_array();
            }
            if let Some(n) = &mut mesh.normals {
                for (out, &v) in n.iter_mut().zip(src) {
                    *out = p.normals[v as usize].to_array();
                }
            }
            if let Some(tan) = &mut mesh.tangents {
                for (out, &v) in tan.iter_mut().zip(src) {
                    *out = p
                        .tangents
                        .get(v as usize)
                        .map_or([0.0; 4], |t| t.to_array());
                }
            }
        }
        &self.scene
    }

    /// The scene as last posed.
    pub fn scene(&self) -> &DrawScene {
        &self.scene
    }
}

/// A draw scene of `tree`'s triangles at the given vertex positions (e.g. a sampled pose or
/// the average pose).
pub fn scene_from_positions(
    tree: &Tree,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    parts: TreeParts,
) -> DrawScene {
    build_scene(tree, positions, normals, None, parts).0
}

/// [`scene_from_positions`] with the tangents too (one per vertex, zero where the input gave
/// none), which let the materials' normal maps apply ([`DrawMaterial::normal_texture`]); with,
/// per mesh, the tree vertex of each mesh vertex ([`PosedTree`] reposes through it).
fn build_scene(
    tree: &Tree,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    tangents: Option<&[Vec4]>,
    parts: TreeParts,
) -> (DrawScene, Vec<Vec<u32>>) {
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
    let mut sources: Vec<Vec<u32>> = Vec::new();
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
        let mut src = Vec::new();
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
                    src.push(v as u32);
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
        sources.push(src);
    }
    let (materials, textures) = materials_and_textures(tree, &mapped, |_| true);
    (
        DrawScene {
            meshes,
            materials,
            textures,
        },
        sources,
    )
}

/// A draw scene of `tree`'s materials and textures, without meshes (and without normal
/// maps, as [`scene_from_positions`] has them): what a render of meshes made elsewhere, such
/// as the billboard bake's, draws with. Only the textures of the materials flagged in `drawn`
/// are copied; each other one is a [`DrawTexture::placeholder`].
pub fn materials_scene(tree: &Tree, drawn: &[bool]) -> DrawScene {
    let mut read = vec![false; tree.textures.len()];
    for (m, _) in (tree.materials.iter().zip(drawn)).filter(|(_, d)| **d) {
        if let Some(r) = m.base_color_texture.and_then(|t| read.get_mut(t)) {
            *r = true;
        }
    }
    let unmapped = vec![false; tree.materials.len()];
    let (materials, textures) = materials_and_textures(tree, &unmapped, |t| read[t]);
    DrawScene {
        meshes: Vec::new(),
        materials,
        textures,
    }
}

/// `tree`'s materials as drawn, with their normal maps where `mapped`, and its textures (those
/// not `copied` a [`DrawTexture::placeholder`]).
fn materials_and_textures(
    tree: &Tree,
    mapped: &[bool],
    copied: impl Fn(usize) -> bool,
) -> (Vec<DrawMaterial>, Vec<DrawTexture>) {
    let materials = tree
        .materials
        .iter()
        .zip(mapped)
        .map(|(m, &mapped)| DrawMaterial {
            wrap: m.base_color_wrap,
            base_color: m.base_color,
            texture: m.base_color_texture,
            normal_texture: m.normal_texture.filter(|_| mapped),
            alpha: match m.alpha_mode {
                AlphaMode::Opaque => DrawAlpha::Opaque,
                AlphaMode::Mask => DrawAlpha::Mask(m.alpha_cutoff),
                AlphaMode::Blend => DrawAlpha::Blend,
            },
            double_sided: m.double_sided,
        })
        .collect();
    let textures = (tree.textures.iter().enumerate())
        .map(|(i, t)| match copied(i) {
            true => DrawTexture {
                width: t.width,
                height: t.height,
                rgba: t.rgba.clone(),
            },
            false => DrawTexture::placeholder(),
        })
        .collect();
    (materials, textures)
}
