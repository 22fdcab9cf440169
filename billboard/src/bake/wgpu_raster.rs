//! The wgpu renderer's path ([`BakeRasteriser::Wgpu`](crate::BakeRasteriser::Wgpu)): square
//! tiles of the supersampled atlas rendered (colour, then normals) and downsampled.

use frond_render::{DrawMesh, Output, Renderer, SRGB_LINEAR};
use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::bake::baked::{BakeError, Cell};
use crate::bake::job::{AtlasJob, cell_in_tile, push_triangle};
use crate::bake::placement::PlacedTriangle;
use crate::bake::texels::{Downsampled, coverage_alpha, cutoff_samples, texel_bytes};

/// Side of the square render tiles (in supersampled texels) the atlas is drawn in on GPUs,
/// before clamping to the device limit: 16 MiB per RGBA8 readback.
pub(super) const RENDER_TILE_GPU: u32 = 2048;
/// The same on CPU rasterisers (llvmpipe), where smaller tiles than on GPUs draw whole bakes
/// fastest.
pub(super) const RENDER_TILE_CPU: u32 = 1024;

/// The wgpu path: the supersampled atlas rendered tile by tile (colour, then normals) and
/// downsampled.
pub(super) fn render_atlas_wgpu(
    renderer: &Renderer,
    job: &AtlasJob,
    out: &mut Downsampled,
) -> Result<(), BakeError> {
    let ss = job.params.supersample;
    let (full_w, full_h) = (out.width * ss, out.height * ss);
    let preferred = if renderer.is_cpu() {
        RENDER_TILE_CPU
    } else {
        RENDER_TILE_GPU
    };
    let tile = (preferred.min(renderer.max_dimension()) / ss).max(1) * ss;
    let needed = cutoff_samples(job.params);
    // No normals in the colour pass, so it is unlit (§2.4: ambient only).
    let mut scene = job.scene();

    for ty in (0..full_h).step_by(tile as usize) {
        for tx in (0..full_w).step_by(tile as usize) {
            let (tw, th) = (tile.min(full_w - tx), tile.min(full_h - ty));
            let (meshes, normals) = job.meshes([tx, ty, tw, th]);
            if meshes.is_empty() {
                continue;
            }
            scene.meshes = meshes;
            let color =
                renderer.render_view(&scene, Mat4::IDENTITY, tw, th, [0.0; 4], Output::Color)?;
            for (mesh, n) in scene.meshes.iter_mut().zip(normals) {
                mesh.normals = Some(n);
            }
            let normal =
                renderer.render_view(&scene, Mat4::IDENTITY, tw, th, [0.0; 4], Output::Normal)?;
            downsample(&color, &normal, [tx / ss, ty / ss], ss, needed, out);
        }
    }
    Ok(())
}

/// Tile triangles of the quads overlapping the render tile, one mesh per material, in NDC
/// of that tile (drawn with an identity matrix), without normals (unlit), plus per mesh the
/// world-space face normal of each vertex's triangle for the normal pass (the tile positions
/// no longer define world normals).
pub(super) fn tile_meshes(
    placed_triangles: &[Vec<PlacedTriangle>],
    cells: &[Cell],
    ss: u32,
    rect: [u32; 4],
    material_count: usize,
) -> (Vec<DrawMesh>, Vec<Vec<[f32; 3]>>) {
    let mut meshes: Vec<(DrawMesh, Vec<[f32; 3]>)> = (0..material_count)
        .map(|material| {
            let mesh = DrawMesh {
                uvs: Some(Vec::new()),
                material,
                ..Default::default()
            };
            (mesh, Vec::new())
        })
        .collect();
    for (tris, cell) in placed_triangles.iter().zip(cells) {
        if !cell_in_tile(cell, ss, rect) {
            continue;
        }
        for t in tris {
            let (mesh, normals) = &mut meshes[t.material as usize];
            push_triangle(mesh, normals, t, rect);
        }
    }
    meshes.retain(|(m, _)| !m.indices.is_empty());
    meshes.into_iter().unzip()
}

/// Averages each texel's covered supersamples: colour in linear light, normals renormalised,
/// alpha from the covered fraction (improved-billboard-cloud §4 item 4).
pub(super) fn downsample(
    color: &frond_render::Frame,
    normal: &frond_render::Frame,
    origin: [u32; 2],
    ss: u32,
    needed: u32,
    out: &mut Downsampled,
) {
    let lut = &*SRGB_LINEAR;
    let (tex_w, tex_h) = ((color.width / ss) as usize, (color.height / ss) as usize);
    let frame_w = color.width as usize;
    let atlas_w = out.width as usize;
    let (ox, oy) = (origin[0] as usize, origin[1] as usize);
    let ss = ss as usize;
    let total = (ss * ss) as u32;
    let rows = out
        .color
        .par_chunks_mut(atlas_w * 4)
        .zip(out.normal.par_chunks_mut(atlas_w * 4))
        .zip(out.samples.par_chunks_mut(atlas_w))
        .skip(oy)
        .take(tex_h)
        .enumerate();
    rows.for_each(|(row, ((color_row, normal_row), samples_row))| {
        for col in 0..tex_w {
            let mut n = 0u32;
            let mut sum = [0.0f32; 3];
            let mut nn = 0u32;
            let mut nsum = Vec3::ZERO;
            for sy in 0..ss {
                let base = (row * ss + sy) * frame_w + col * ss;
                for sx in 0..ss {
                    let i = base + sx;
                    if color.coverage[i] {
                        n += 1;
                        let p = &color.rgba[i * 4..i * 4 + 3];
                        for k in 0..3 {
                            sum[k] += lut[p[k] as usize];
                        }
                    }
                    if normal.coverage[i] {
                        nn += 1;
                        let p = &normal.rgba[i * 4..i * 4 + 3];
                        nsum +=
                            Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 127.5 - Vec3::ONE;
                    }
                }
            }
            if n == 0 {
                continue;
            }
            let x = ox + col;
            let mean = sum.map(|c| c / n as f32);
            let normal = if nn > 0 { nsum } else { Vec3::ZERO };
            let (c, nb) = texel_bytes(coverage_alpha(n, total, needed), mean, normal);
            samples_row[x] = n as u16;
            color_row[x * 4..x * 4 + 4].copy_from_slice(&c);
            normal_row[x * 4..x * 4 + 4].copy_from_slice(&nb);
        }
    });
}

impl AtlasJob<'_> {
    /// [`tile_meshes`] of the supersampled rectangle `rect`.
    pub(super) fn meshes(&self, rect: [u32; 4]) -> (Vec<DrawMesh>, Vec<Vec<[f32; 3]>>) {
        tile_meshes(
            self.placed_triangles,
            self.cells,
            self.params.supersample,
            rect,
            self.materials.len(),
        )
    }
}
