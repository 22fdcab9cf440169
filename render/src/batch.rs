//! Packs validated meshes into GPU-sized vertex/index buffer batches.
//!
//! Meshes are appended into shared buffers (indices rebased on the CPU, so no
//! base-vertex support is needed on GL), and a mesh too big for one buffer is split
//! into triangle chunks with their own compact vertex lists. For normal output, meshes
//! without normals are expanded to three vertices per triangle carrying the face normal.

use bytemuck::{Pod, Zeroable};

use crate::scene::DrawScene;

/// Interleaved vertex as the shader reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(crate) struct Vertex {
    pub position: [f32; 3],
    /// xyz: normal; w: 1 when the mesh has normals (lit), 0 when unlit.
    pub normal: [f32; 4],
    pub uv: [f32; 2],
}

/// A contiguous index range drawn with one material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct DrawRange {
    pub material: usize,
    pub first_index: u32,
    pub index_count: u32,
}

/// Vertices and indices that fit one vertex buffer and one index buffer.
#[derive(Debug, Default)]
pub(crate) struct Batch {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub draws: Vec<DrawRange>,
}

impl Batch {
    fn push_draw(&mut self, material: usize, first_index: usize) {
        let end = self.indices.len() as u32;
        let first = first_index as u32;
        if first == end {
            return;
        }
        match self.draws.last_mut() {
            Some(last)
                if last.material == material && last.first_index + last.index_count == first =>
            {
                last.index_count = end - last.first_index;
            }
            _ => self.draws.push(DrawRange {
                material,
                first_index: first,
                index_count: end - first,
            }),
        }
    }
}

fn vertex(mesh: &crate::DrawMesh, i: usize) -> Vertex {
    let normal = match &mesh.normals {
        Some(n) => [n[i][0], n[i][1], n[i][2], 1.0],
        None => [0.0; 4],
    };
    Vertex {
        position: mesh.positions[i],
        normal,
        uv: mesh.uvs.as_ref().map_or([0.0; 2], |uv| uv[i]),
    }
}

/// Unit normal of the counter-clockwise triangle (a, b, c), zero when degenerate.
fn face_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> [f32; 3] {
    let [a, b, c] = [a, b, c].map(glam::Vec3::from);
    (b - a).cross(c - a).normalize_or_zero().to_array()
}

/// Splits the scene into batches whose vertex and index buffers are at most
/// `max_buffer_bytes` each. The scene must already be validated.
///
/// With `face_normals`, meshes without normals get per-triangle face normals (their
/// triangles no longer share vertices); other meshes are unchanged.
pub(crate) fn build_batches(
    scene: &DrawScene,
    max_buffer_bytes: u64,
    face_normals: bool,
) -> Vec<Batch> {
    let max_vertices =
        (max_buffer_bytes / size_of::<Vertex>() as u64).clamp(3, u32::MAX as u64) as usize;
    let max_indices = ((max_buffer_bytes / 4).clamp(3, u32::MAX as u64) as usize) / 3 * 3;

    let mut batches = Vec::new();
    let mut current = Batch::default();
    // Chunk-local vertex numbers of a split mesh; u32::MAX = not yet in the chunk.
    let mut remap: Vec<u32> = Vec::new();

    for mesh in scene.meshes.iter().filter(|m| !m.indices.is_empty()) {
        if face_normals && mesh.normals.is_none() {
            let mut first = current.indices.len();
            for tri in mesh.indices.chunks_exact(3) {
                if current.vertices.len() + 3 > max_vertices
                    || current.indices.len() + 3 > max_indices
                {
                    current.push_draw(mesh.material, first);
                    batches.push(std::mem::take(&mut current));
                    first = 0;
                }
                let corners = [0, 1, 2].map(|k| vertex(mesh, tri[k] as usize));
                let [nx, ny, nz] = face_normal(
                    corners[0].position,
                    corners[1].position,
                    corners[2].position,
                );
                for mut v in corners {
                    v.normal = [nx, ny, nz, 1.0];
                    current.indices.push(current.vertices.len() as u32);
                    current.vertices.push(v);
                }
            }
            current.push_draw(mesh.material, first);
            continue;
        }

        let (nv, ni) = (mesh.positions.len(), mesh.indices.len());
        if nv <= max_vertices && ni <= max_indices {
            if current.vertices.len() + nv > max_vertices
                || current.indices.len() + ni > max_indices
            {
                batches.push(std::mem::take(&mut current));
            }
            let base = current.vertices.len() as u32;
            let first = current.indices.len();
            current.vertices.extend((0..nv).map(|i| vertex(mesh, i)));
            current
                .indices
                .extend(mesh.indices.iter().map(|&i| i + base));
            current.push_draw(mesh.material, first);
            continue;
        }

        // Too big for one buffer: emit triangles chunk by chunk, remapping vertices.
        remap.clear();
        remap.resize(nv, u32::MAX);
        let mut touched: Vec<u32> = Vec::new();
        let mut first = current.indices.len();
        for tri in mesh.indices.chunks_exact(3) {
            if current.vertices.len() + 3 > max_vertices || current.indices.len() + 3 > max_indices
            {
                current.push_draw(mesh.material, first);
                batches.push(std::mem::take(&mut current));
                for &v in &touched {
                    remap[v as usize] = u32::MAX;
                }
                touched.clear();
                first = 0;
            }
            for &v in tri {
                let slot = &mut remap[v as usize];
                if *slot == u32::MAX {
                    *slot = current.vertices.len() as u32;
                    current.vertices.push(vertex(mesh, v as usize));
                    touched.push(v);
                }
                current.indices.push(*slot);
            }
        }
        current.push_draw(mesh.material, first);
        // The next mesh's vertices must not reuse this mesh's remapping.
        batches.push(std::mem::take(&mut current));
    }
    if !current.indices.is_empty() {
        batches.push(current);
    }
    batches
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DrawMaterial, DrawMesh};

    /// A strip of `n` quads (2n triangles) along x.
    fn strip(n: u32, material: usize) -> DrawMesh {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..=n {
            positions.push([i as f32, 0.0, 0.0]);
            positions.push([i as f32, 1.0, 0.0]);
        }
        for i in 0..n {
            let a = 2 * i;
            indices.extend([a, a + 2, a + 1, a + 1, a + 2, a + 3]);
        }
        DrawMesh {
            positions,
            indices,
            material,
            ..Default::default()
        }
    }

    /// All triangles of all batches, as position triples with material, in order.
    fn triangles(batches: &[Batch]) -> Vec<(usize, [[f32; 3]; 3])> {
        let mut out = Vec::new();
        for b in batches {
            for d in &b.draws {
                let range = d.first_index as usize..(d.first_index + d.index_count) as usize;
                for t in b.indices[range].chunks_exact(3) {
                    out.push((
                        d.material,
                        [0, 1, 2].map(|k| b.vertices[t[k] as usize].position),
                    ));
                }
            }
        }
        out
    }

    fn scene_triangles(scene: &DrawScene) -> Vec<(usize, [[f32; 3]; 3])> {
        let mut out = Vec::new();
        for m in &scene.meshes {
            for t in m.indices.chunks_exact(3) {
                out.push((m.material, [0, 1, 2].map(|k| m.positions[t[k] as usize])));
            }
        }
        out
    }

    #[test]
    fn small_meshes_share_one_batch() {
        let scene = DrawScene {
            meshes: vec![strip(3, 0), DrawMesh::default(), strip(2, 0), strip(1, 1)],
            materials: vec![DrawMaterial::default(); 2],
            textures: vec![],
        };
        let batches = build_batches(&scene, 1 << 20, false);
        assert_eq!(batches.len(), 1);
        // Same-material neighbours merge into one draw.
        assert_eq!(batches[0].draws.len(), 2);
        assert_eq!(triangles(&batches), scene_triangles(&scene));
    }

    #[test]
    fn big_meshes_are_split_losslessly() {
        let scene = DrawScene {
            meshes: vec![strip(50, 0), strip(3, 1), strip(40, 1)],
            materials: vec![DrawMaterial::default(); 2],
            textures: vec![],
        };
        // Room for 20 vertices / 72 indices per buffer.
        let cap = 20 * size_of::<Vertex>() as u64;
        let batches = build_batches(&scene, cap, false);
        assert!(batches.len() > 5);
        for b in &batches {
            assert!(b.vertices.len() <= 20, "{} vertices", b.vertices.len());
            assert!(b.indices.len() * 4 <= cap as usize);
            assert!(b.indices.iter().all(|&i| (i as usize) < b.vertices.len()));
        }
        assert_eq!(triangles(&batches), scene_triangles(&scene));
    }

    #[test]
    fn face_normals_expand_meshes_without_normals() {
        let mut with_normals = strip(2, 0);
        with_normals.normals = Some(vec![[0.0, 1.0, 0.0]; with_normals.positions.len()]);
        let scene = DrawScene {
            meshes: vec![strip(30, 0), with_normals.clone(), strip(1, 1)],
            materials: vec![DrawMaterial::default(); 2],
            textures: vec![],
        };
        let cap = 20 * size_of::<Vertex>() as u64;
        let batches = build_batches(&scene, cap, true);
        assert_eq!(triangles(&batches), scene_triangles(&scene));
        for b in &batches {
            assert!(b.vertices.len() <= 20);
            assert!(b.indices.iter().all(|&i| (i as usize) < b.vertices.len()));
        }
        // Strips lie in z = 0 and wind counter-clockwise seen from +Z.
        let normals: Vec<[f32; 4]> = batches
            .iter()
            .flat_map(|b| b.vertices.iter().map(|v| v.normal))
            .collect();
        let z_up = normals
            .iter()
            .filter(|n| **n == [0.0, 0.0, 1.0, 1.0])
            .count();
        let given = normals
            .iter()
            .filter(|n| **n == [0.0, 1.0, 0.0, 1.0])
            .count();
        assert_eq!(z_up, 3 * 2 * 31);
        assert_eq!(given, with_normals.positions.len());
    }
}
