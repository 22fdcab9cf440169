//! The CPU bake rasteriser's path ([`BakeRasteriser::Cpu`](crate::BakeRasteriser::Cpu)):
//! strips of atlas rows, each cell's part of a strip drawn alone by
//! [`BakeTarget`] in parallel, colour and normals in one pass.

use frond_render::{
    BakeScratch, BakeTarget, DrawMaterial, DrawMesh, DrawTexture, SoftwareTextures,
};
use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::bake::baked::BakeError;
use crate::bake::job::{AtlasJob, cell_in_tile, push_triangle};
use crate::bake::placement::PlacedTriangle;
use crate::bake::texels::{Downsampled, coverage_alpha, cutoff_samples, texel_bytes};
use crate::soup::TriangleSoup;

/// The textures of the CPU bake: those the materials of `members`' triangles read, which
/// alone are prepared.
pub(super) struct BakeTextures {
    pub(super) prepared: SoftwareTextures,
    pub(super) used: Vec<bool>,
}

/// `textures` prepared for the CPU bake ([`SoftwareTextures::for_bake_of`]).
pub(super) fn bake_textures(
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    members: &[Vec<usize>],
) -> Result<BakeTextures, BakeError> {
    let mut used = vec![false; textures.len()];
    for &t in members.iter().flatten() {
        let material = materials.get(soup.material[t] as usize);
        if let Some(u) = material
            .and_then(|m| m.texture)
            .and_then(|i| used.get_mut(i))
        {
            *u = true;
        }
    }
    let prepared = SoftwareTextures::for_bake_of(textures, &used)?;
    Ok(BakeTextures { prepared, used })
}

/// Texel rows of the atlas in one frame of supersampled coordinates (every sample's weights
/// follow its rounding): the atlas is cut into strips of so many rows, each cell's part of a
/// strip drawn in the strip's frame.
pub(super) const CPU_STRIP_TEXELS: u32 = 256;

/// Texel columns of a frame of an atlas `width` texels wide at `ss`² supersampling: the whole
/// width where a target can hold it, else as many as one can
/// ([`BakeTarget::MAX_SIDE_SAMPLES`]: a 16×-supersampled bake of an atlas wider than 2048).
pub(super) fn cpu_frame_columns(width: u32, ss: u32) -> u32 {
    let most = BakeTarget::MAX_SIDE_SAMPLES / ss.max(1);
    width.min(most.max(1))
}

/// The CPU path: every cell's part of every frame of the atlas drawn alone by [`BakeTarget`]
/// from its own triangles (colour and normals in one pass), in parallel, and stored texel by
/// texel. A frame is a strip of [`CPU_STRIP_TEXELS`] rows, cut into columns where the atlas
/// is wider than a target ([`cpu_frame_columns`]); frames of one size share one target, the
/// shorter last strip and narrower last column have their own.
pub(super) fn render_atlas_cpu(
    job: &AtlasJob,
    textures: &BakeTextures,
    out: &mut Downsampled,
) -> Result<(), BakeError> {
    let ss = job.params.supersample;
    let (total, needed) = (ss * ss, cutoff_samples(job.params));
    // Per count of covered samples, its alpha.
    let alphas: Vec<u8> = (0..=total)
        .map(|n| coverage_alpha(n, total, needed))
        .collect();
    let prepared = &textures.prepared;
    let scene = job.scene_of(&textures.used);
    let columns = cpu_frame_columns(out.width, ss);
    // Frames `[x, y, w, h]` in texels, strip by strip, grouped by size.
    let mut groups: Vec<Vec<[u32; 4]>> = Vec::new();
    for ty in (0..out.height).step_by(CPU_STRIP_TEXELS as usize) {
        for tx in (0..out.width).step_by(columns as usize) {
            let size = [
                columns.min(out.width - tx),
                CPU_STRIP_TEXELS.min(out.height - ty),
            ];
            let frame = [tx, ty, size[0], size[1]];
            match groups.iter_mut().find(|g| g[0][2..] == size) {
                Some(group) => group.push(frame),
                None => groups.push(vec![frame]),
            }
        }
    }
    for group in groups {
        let [_, _, tw, th] = group[0];
        let regions = cell_regions(job, &group);
        let target = BakeTarget::new(&scene, prepared, Mat4::IDENTITY, tw, th, ss)?;
        let texels: Vec<Vec<CoveredTexel>> = regions
            .par_iter()
            .map_init(
                || (BakeScratch::default(), Vec::new(), Vec::new()),
                |(scratch, meshes, pixels), region| {
                    let tris = &job.placed_triangles[region.cell];
                    let frame = region.frame.map(|v| v * ss);
                    cell_meshes(meshes, tris, frame, job.materials.len());
                    pixels.clear();
                    target.render_covered(region.rect, meshes, scratch, |i, pixel| {
                        pixels.push((i, pixel));
                    })?;
                    Ok((pixels.iter())
                        .map(|&(i, pixel)| {
                            let n = pixel.samples;
                            let alpha = alphas[usize::from(n).min(alphas.len() - 1)];
                            let normal = Vec3::from(pixel.normal);
                            let (c, nb) = texel_bytes(alpha, pixel.colour, normal);
                            (i, n, c, nb)
                        })
                        .collect())
                },
            )
            .collect::<Result<_, BakeError>>()?;
        store_texels(out, &regions, &texels);
    }
    Ok(())
}

/// One cell's part of a frame of the atlas, for [`BakeTarget::render`].
pub(super) struct CellRegion {
    /// The frame's texels `[x, y, w, h]` in the atlas.
    pub(super) frame: [u32; 4],
    /// The cell's texels `[x, y, w, h]` in the frame.
    pub(super) rect: [u32; 4],
    /// The cell.
    pub(super) cell: usize,
}

/// The regions of the cells with triangles in the frames `group` (texels of the atlas,
/// strip by strip), frame by frame.
pub(super) fn cell_regions(job: &AtlasJob, group: &[[u32; 4]]) -> Vec<CellRegion> {
    let ss = job.params.supersample;
    (group.iter())
        .flat_map(|&frame| {
            let [tx, ty, tw, th] = frame;
            (job.cells.iter().zip(job.placed_triangles).enumerate())
                .filter(move |(_, (cell, tris))| {
                    !tris.is_empty() && cell_in_tile(cell, ss, frame.map(|v| v * ss))
                })
                .map(move |(c, (cell, _))| {
                    let (x0, x1) = (cell.x.max(tx), (cell.x + cell.width).min(tx + tw));
                    let (y0, y1) = (cell.y.max(ty), (cell.y + cell.height).min(ty + th));
                    CellRegion {
                        frame,
                        rect: [x0 - tx, y0 - ty, x1 - x0, y1 - y0],
                        cell: c,
                    }
                })
        })
        .collect()
}

/// Stores each region's covered texels in `out`, strip by strip in parallel (the regions
/// come strip by strip).
pub(super) fn store_texels(
    out: &mut Downsampled,
    regions: &[CellRegion],
    texels: &[Vec<CoveredTexel>],
) {
    let strip = CPU_STRIP_TEXELS as usize;
    let width = out.width as usize;
    // Per strip, its regions (`0..0` until its first).
    let mut per_strip = vec![0..0; (out.height as usize).div_ceil(strip)];
    for (k, region) in regions.iter().enumerate() {
        let range = &mut per_strip[region.frame[1] as usize / strip];
        *range = if range.end == 0 {
            k..k + 1
        } else {
            range.start..k + 1
        };
    }
    let rows = strip * width;
    (out.samples.par_chunks_mut(rows))
        .zip(out.color.par_chunks_mut(rows * 4))
        .zip(out.normal.par_chunks_mut(rows * 4))
        .zip(per_strip.par_iter())
        .for_each(|(((samples, color), normal), range)| {
            for k in range.clone() {
                let [x, y, w, _] = regions[k].rect.map(|v| v as usize);
                let x = x + regions[k].frame[0] as usize;
                for &(i, n, c, nb) in &texels[k] {
                    let at = (y + i / w) * width + x + i % w;
                    samples[at] = n;
                    color[at * 4..at * 4 + 4].copy_from_slice(&c);
                    normal[at * 4..at * 4 + 4].copy_from_slice(&nb);
                }
            }
        });
}

/// A covered texel of a region drawn by [`BakeTarget::render`]: its index in the region, its
/// covered samples, colour and normal bytes.
pub(super) type CoveredTexel = (usize, u16, [u8; 4], [u8; 4]);

/// One cell's triangles `tris` (supersampled atlas coordinates) in NDC of the supersampled
/// rectangle `rect` (as [`tile_meshes`] places them, with their normals) written into
/// `meshes` (its buffers reused): one mesh per material with triangles, in material order
/// (the order [`tile_meshes`] draws a cell's triangles in).
pub(super) fn cell_meshes(
    meshes: &mut Vec<DrawMesh>,
    tris: &[PlacedTriangle],
    rect: [u32; 4],
    material_count: usize,
) {
    let mut used = 0;
    for material in 0..material_count {
        let of_material = |t: &&PlacedTriangle| t.material as usize == material;
        if !tris.iter().any(|t| of_material(&t)) {
            continue;
        }
        if meshes.len() == used {
            meshes.push(DrawMesh::default());
        }
        let mesh = &mut meshes[used];
        used += 1;
        mesh.material = material;
        mesh.positions.clear();
        mesh.indices.clear();
        let mut uvs = mesh.uvs.take().unwrap_or_default();
        let mut normals = mesh.normals.take().unwrap_or_default();
        uvs.clear();
        normals.clear();
        mesh.uvs = Some(uvs);
        for t in tris.iter().filter(of_material) {
            push_triangle(mesh, &mut normals, t, rect);
        }
        mesh.normals = Some(normals);
    }
    meshes.truncate(used);
}
