//! What either rasteriser draws: the placed members with their (two-sided) materials and
//! textures, and how a placed triangle goes into a draw mesh.

use frond_render::{DrawMaterial, DrawMesh, DrawScene, DrawTexture};

use crate::bake::baked::Cell;
use crate::bake::params::BakeParams;
use crate::bake::placement::PlacedTriangle;

/// What either rasteriser draws: the members placed in the supersampled atlas, with their
/// materials (two-sided) and textures.
pub(super) struct AtlasJob<'a> {
    pub(super) materials: Vec<DrawMaterial>,
    pub(super) textures: &'a [DrawTexture],
    pub(super) placed_triangles: &'a [Vec<PlacedTriangle>],
    pub(super) cells: &'a [Cell],
    pub(super) params: &'a BakeParams,
}

impl AtlasJob<'_> {
    /// A scene of the job's materials and textures, without meshes yet.
    pub(super) fn scene(&self) -> DrawScene {
        self.scene_of(&vec![true; self.textures.len()])
    }

    /// [`AtlasJob::scene`] with only the textures `used` copied, each other one a
    /// [`DrawTexture::placeholder`] (a bake reads only its foliage's).
    pub(super) fn scene_of(&self, used: &[bool]) -> DrawScene {
        DrawScene {
            meshes: Vec::new(),
            materials: self.materials.clone(),
            textures: (self.textures.iter().zip(used))
                .map(|(t, &used)| {
                    if used {
                        t.clone()
                    } else {
                        DrawTexture::placeholder()
                    }
                })
                .collect(),
        }
    }
}

/// Members are drawn from both sides (a billboard is seen from both) with their texture and
/// alpha test.
pub(super) fn two_sided(m: &DrawMaterial) -> DrawMaterial {
    DrawMaterial {
        double_sided: true,
        ..m.clone()
    }
}

/// Appends triangle `t` (supersampled atlas coordinates) to `mesh` in NDC of the
/// supersampled rectangle `rect`, and its world-space face normal per vertex to `normals`.
pub(super) fn push_triangle(
    mesh: &mut DrawMesh,
    normals: &mut Vec<[f32; 3]>,
    t: &PlacedTriangle,
    rect: [u32; 4],
) {
    let [x, y, w, h] = rect.map(|v| v as f32);
    for k in 0..3 {
        let [px, py, pz] = t.pos[k];
        mesh.indices.push(mesh.positions.len() as u32);
        mesh.positions
            .push([(px - x) / w * 2.0 - 1.0, 1.0 - (py - y) / h * 2.0, pz]);
        if let Some(uvs) = &mut mesh.uvs {
            uvs.push(t.uv[k]);
        }
        normals.push(t.normal);
    }
}

/// Whether the quad's supersampled cell overlaps the render tile `[x, y, w, h]`.
pub(super) fn cell_in_tile(c: &Cell, ss: u32, r: [u32; 4]) -> bool {
    let (x0, y0) = (c.x * ss, c.y * ss);
    let (x1, y1) = (x0 + c.width * ss, y0 + c.height * ss);
    x0 < r[0] + r[2] && r[0] < x1 && y0 < r[1] + r[3] && r[1] < y1
}
