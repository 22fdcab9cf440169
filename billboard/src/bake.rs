//! Bakes the textures of a billboard cloud: each quad's member triangles rendered
//! orthographically onto the quad, supersampled, downsampled in linear light, dilated into
//! their padding and packed into one colour atlas and one normal atlas.
//!
//! Spec: improved-billboard-cloud §4 (texture size from a uniform texel density, orthographic
//! projection focused on the rectangle with near/far from the members' depth range, 4x4
//! supersampling with filters that average only covered samples, one atlas with padding,
//! alpha test at 0.5 and background dilation, normal maps) and animated-billboard-clouds §2.4
//! "Texturing details" (camera aligned with the quad edges, view window = the quad, ambient
//! only, \[ENG\] texel density clamped per side, one atlas per cloud).
//!
//! How it is rendered: quads are first packed (see [`crate::atlas`]); every member triangle is
//! then transformed on the CPU into the supersampled atlas (the quad's rectangle maps onto its
//! texture's cell, depth runs from the quad's far to near member), clipped to its cell, and the
//! whole supersampled atlas is drawn with identity-matrix renders. By default the CPU bake
//! rasteriser ([`frond_render::BakeTarget`]) frames strips of whole atlas rows, a few
//! targets in all, and draws each cell's part of a strip alone from its own triangles, set
//! up as it is drawn, in parallel, colour and normals in one pass (the same atlas on every
//! machine);
//! [`BakeRasteriser::Wgpu`] draws square tiles through the wgpu renderer, a colour and a
//! normal pass each.

use std::ops::Range;

use frond_render::{
    BakeScratch, BakeTarget, DrawMaterial, DrawMesh, DrawScene, DrawTexture, Output, RenderError,
    Renderer, SRGB_LINEAR, SoftwareTextures, linear_to_srgb,
};
use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;
use thiserror::Error;

use crate::atlas::{self, Packing};
use crate::quad::Quad;
use crate::soup::TriangleSoup;

/// Largest supported atlas side: keeps both RGBA8 atlases under 2 GiB together.
pub const MAX_ATLAS_SIDE: u32 = 16384;
/// Largest supported supersampling factor per axis.
pub const MAX_SUPERSAMPLE: u32 = 16;
/// Side of the square render tiles (in supersampled texels) the atlas is drawn in on GPUs,
/// before clamping to the device limit: 16 MiB per RGBA8 readback.
const RENDER_TILE_GPU: u32 = 2048;
/// The same on CPU rasterisers: llvmpipe measured fastest at 1024 (about 2x faster than
/// 2048 or 512 for whole bakes).
const RENDER_TILE_CPU: u32 = 1024;
/// Factor applied to the texel density each time the textures do not fit the atlas.
const DENSITY_STEP: f32 = 0.8;

/// Settings of [`bake_cloud`].
#[derive(Clone, Debug, PartialEq)]
pub struct BakeParams {
    /// Texels per world unit along both quad axes (uniform density, improved-billboard-cloud
    /// §4 item 1); lowered automatically when the atlas would exceed `max_atlas`.
    pub texels_per_unit: f32,
    /// Supersampling factor per axis (4 gives the spec's 4x4, §4 item 4), 1..=16.
    pub supersample: u32,
    /// Texels of dilated padding around each quad's texture inside the atlas (§4 item 5: 4 is
    /// "probably a suitable general choice").
    pub padding: u32,
    /// Largest atlas width and height in texels, 4..=[`MAX_ATLAS_SIDE`].
    pub max_atlas: u32,
    /// Fraction of a texel's supersamples that must be covered for it to pass the billboard's
    /// alpha test at 0.5 (stored alpha >= 128 exactly then; §4 item 6), in (0, 1].
    pub alpha_cutoff: f32,
    /// Smallest texture side per quad, in texels.
    pub min_side: u32,
    /// Largest texture side per quad, in texels (a longer side scales the quad's texture
    /// down, keeping its aspect ratio).
    pub max_side: u32,
    /// Per quad, move the alpha-test threshold so that as many texels pass as the quad's
    /// summed coverage (in texels): sparse foliage baked at low resolution keeps its density
    /// instead of vanishing where no texel is half covered (the coverage-preserving rule the
    /// renderer's mip chains use). Off: a texel passes when `alpha_cutoff` of it is covered.
    pub preserve_coverage: bool,
    /// Which rasteriser draws the atlas: the CPU bake rasteriser (default: the same atlas on
    /// every machine) or the wgpu renderer (a GPU, when there is one).
    pub rasteriser: BakeRasteriser,
}

/// The rasteriser that draws a cloud's atlas ([`BakeParams::rasteriser`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BakeRasteriser {
    /// [`frond_render::BakeTarget`]: one pass over the atlas, cells in parallel, colour and
    /// normals together; byte-identical output whatever the machine or thread count.
    #[default]
    Cpu,
    /// [`Renderer::render_view`] in tiles, a colour then a normal pass: fast on a GPU, and
    /// what the adapter's rasteriser makes of the samples.
    Wgpu,
}

impl Default for BakeParams {
    /// 64 texels per unit, 4x4 supersampling, 4 texels of padding, atlases up to 4096²,
    /// majority coverage, texture sides 4..=1024 (animated-billboard-clouds §2.4 \[ENG\]).
    fn default() -> Self {
        Self {
            texels_per_unit: 64.0,
            supersample: 4,
            padding: 4,
            max_atlas: 4096,
            alpha_cutoff: 0.5,
            min_side: 4,
            max_side: 1024,
            preserve_coverage: false,
            rasteriser: BakeRasteriser::Cpu,
        }
    }
}

/// The two baked atlases of a cloud, same size, rows top to bottom (glTF image convention).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Atlas {
    /// Width in texels (a multiple of 4).
    pub width: u32,
    /// Height in texels (a multiple of 4).
    pub height: u32,
    /// `width * height * 4` bytes: sRGB colour with straight alpha. Alpha grows with the
    /// covered fraction of the texel and is >= 128 exactly when that fraction reaches
    /// [`BakeParams::alpha_cutoff`]; uncovered texels have alpha 0 and the colour of the
    /// nearest covered texel of their quad (dilation, improved-billboard-cloud §4 item 6).
    pub color: Vec<u8>,
    /// `width * height * 4` bytes, linear: a tangent-space normal map in glTF's
    /// `normalTexture` convention, `rgb = n * 0.5 + 0.5` of the unit normal facing the quad's
    /// front in its own frame (+X along `axis_u`, the image's right; +Y along `axis_v`, the
    /// image's up; +Z the quad's front normal), so an engine lights each billboard with its
    /// leaves' normals wherever the billboard turns; alpha as in `color` (dilated the same
    /// way).
    pub normal: Vec<u8>,
}

/// Where one quad's texture lies in the atlas, in texels (its padding ring surrounds it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cell {
    /// Left column of the texture.
    pub x: u32,
    /// Top row of the texture.
    pub y: u32,
    /// Width in texels (along the quad's `axis_u`).
    pub width: u32,
    /// Height in texels (along the quad's `axis_v`).
    pub height: u32,
}

/// The result of [`bake_cloud`]: atlases plus per-quad texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedCloud {
    /// Colour and normal atlases.
    pub atlas: Atlas,
    /// Per quad: atlas UV (glTF convention, (0, 0) = top-left of the image) of its corners
    /// in [`Quad::corners`] order. The image shows the quad seen from its front
    /// (`axis_u × axis_v` toward the viewer): corner 3 (-u, +v) is the cell's top-left.
    pub uv_rects: Vec<[Vec2; 4]>,
    /// Per quad: its texture's texel rectangle in the atlas.
    pub cells: Vec<Cell>,
    /// The texel density actually used (texels per world unit).
    pub texels_per_unit: f32,
    /// True when the density had to be lowered below the requested one to fit `max_atlas`.
    pub density_reduced: bool,
    /// Uncompressed bytes of both atlases.
    pub texture_bytes: usize,
}

/// Why a cloud could not be baked.
#[derive(Debug, Error)]
pub enum BakeError {
    /// A [`BakeParams`] value is out of range.
    #[error("invalid bake parameter: {0}")]
    InvalidParams(String),
    /// The soup, quads, members or materials are inconsistent or not finite.
    #[error("invalid bake input: {0}")]
    InvalidInput(String),
    /// Even the smallest textures (min_side per quad, plus padding) do not fit the atlas.
    #[error(
        "{quads} quads do not fit a {max_atlas}x{max_atlas} atlas even at {min_side} texels per \
         side with {padding} texels of padding"
    )]
    AtlasTooSmall {
        /// Number of quads.
        quads: usize,
        /// The atlas limit.
        max_atlas: u32,
        /// The smallest texture side.
        min_side: u32,
        /// Padding per texture.
        padding: u32,
    },
    /// The renderer failed.
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// Bakes the cloud's textures: `members[q]` lists the `soup` triangles drawn on `quads[q]`,
/// with `materials` / `textures` indexed by [`TriangleSoup::material`].
///
/// Each quad gets `clamp(ceil(side * density), min_side, max_side)` texels per side (a quad
/// whose longest side would exceed `max_side` is scaled down as a whole, keeping its aspect
/// ratio); the density is lowered (x0.8 steps) until all textures fit one `max_atlas`² atlas,
/// never dropping a quad. Members are drawn double-sided, unlit, with their material's texture and
/// alpha test; colours are averaged over covered supersamples in linear light, normals
/// averaged and renormalised, then every uncovered texel of a quad's padded cell takes the
/// colour and normal of the nearest covered one. The output is deterministic.
/// Improved-billboard-cloud §4, animated-billboard-clouds §2.4.
pub fn bake_cloud(
    renderer: &Renderer,
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    quads: &[Quad],
    members: &[Vec<usize>],
    params: &BakeParams,
) -> Result<BakedCloud, BakeError> {
    let start = std::time::Instant::now();
    validate_params(params)?;
    validate_input(soup, materials, quads, members)?;
    let ss = params.supersample;
    // The CPU rasteriser's textures are prepared while the atlas is laid out (one texture's
    // mip chain is mostly one thread's work).
    let (placing, prepared) = rayon::join(
        || -> Result<_, BakeError> {
            let layout = layout(quads, params)?;
            let packed = start.elapsed();
            let cells: Vec<Cell> = (layout.sizes.iter().zip(&layout.packing.origins))
                .map(|(&(width, height), &(x, y))| Cell {
                    x,
                    y,
                    width,
                    height,
                })
                .collect();
            let placed_triangles: Vec<Vec<PlacedTriangle>> = quads
                .par_iter()
                .zip(members.par_iter())
                .zip(cells.par_iter())
                .map(|((quad, tris), cell)| quad_triangles(soup, quad, tris, cell, ss))
                .collect();
            Ok((layout, packed, cells, placed_triangles))
        },
        || match params.rasteriser {
            BakeRasteriser::Cpu => bake_textures(soup, materials, textures, members).map(Some),
            BakeRasteriser::Wgpu => Ok(None),
        },
    );
    let (layout, packed, cells, placed_triangles) = placing?;
    let prepared = prepared?;
    let packing = &layout.packing;
    let (width, height) = (packing.width, packing.height);
    let mut samples = Downsampled::new(width, height);
    let placed = start.elapsed();
    render_atlas(
        renderer,
        materials,
        textures,
        prepared.as_ref(),
        &placed_triangles,
        &cells,
        params,
        &mut samples,
    )?;
    let rendered = start.elapsed();
    if params.preserve_coverage {
        preserve_coverage(&mut samples, &cells, ss * ss, cutoff_samples(params));
    }

    let atlas = finish_cells(samples, &cells, quads, params.padding);
    let uv_rects = cells.iter().map(|c| uv_rect(c, width, height)).collect();
    let texture_bytes = atlas.color.len() + atlas.normal.len();
    tracing::debug!(
        quads = quads.len(),
        width,
        height,
        density = layout.texels_per_unit,
        "baked: packing {:.3} s, placing {:.3} s, rendering {:.3} s, dilation {:.3} s",
        packed.as_secs_f64(),
        (placed - packed).as_secs_f64(),
        (rendered - placed).as_secs_f64(),
        (start.elapsed() - rendered).as_secs_f64(),
    );
    Ok(BakedCloud {
        atlas,
        uv_rects,
        cells,
        texels_per_unit: layout.texels_per_unit,
        density_reduced: layout.density_reduced,
        texture_bytes,
    })
}

fn validate_params(p: &BakeParams) -> Result<(), BakeError> {
    let bad = |m: String| Err(BakeError::InvalidParams(m));
    if !(p.texels_per_unit.is_finite() && p.texels_per_unit > 0.0) {
        return bad(format!(
            "texels_per_unit must be finite and positive, got {}",
            p.texels_per_unit
        ));
    }
    if !(1..=MAX_SUPERSAMPLE).contains(&p.supersample) {
        return bad(format!(
            "supersample must be in 1..={MAX_SUPERSAMPLE}, got {}",
            p.supersample
        ));
    }
    if !(4..=MAX_ATLAS_SIDE).contains(&p.max_atlas) {
        return bad(format!(
            "max_atlas must be in 4..={MAX_ATLAS_SIDE}, got {}",
            p.max_atlas
        ));
    }
    if p.padding > p.max_atlas {
        return bad(format!(
            "padding {} exceeds max_atlas {}",
            p.padding, p.max_atlas
        ));
    }
    if p.min_side == 0 || p.max_side < p.min_side {
        return bad(format!(
            "need 1 <= min_side <= max_side, got {}..{}",
            p.min_side, p.max_side
        ));
    }
    if !(p.alpha_cutoff > 0.0 && p.alpha_cutoff <= 1.0) {
        return bad(format!(
            "alpha_cutoff must be in (0, 1], got {}",
            p.alpha_cutoff
        ));
    }
    Ok(())
}

fn validate_input(
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    quads: &[Quad],
    members: &[Vec<usize>],
) -> Result<(), BakeError> {
    let bad = |m: String| Err(BakeError::InvalidInput(m));
    let n = soup.positions.len();
    if soup.uvs.len() != n || soup.material.len() != n {
        return bad(format!(
            "soup has {n} triangles but {} uv triples and {} materials",
            soup.uvs.len(),
            soup.material.len()
        ));
    }
    if members.len() != quads.len() {
        return bad(format!(
            "{} member lists for {} quads",
            members.len(),
            quads.len()
        ));
    }
    for (q, quad) in quads.iter().enumerate() {
        let finite = quad.center.is_finite()
            && quad.axis_u.is_finite()
            && quad.axis_v.is_finite()
            && quad.half_size.is_finite();
        if !finite || quad.half_size.min_element() < 0.0 {
            return bad(format!("quad {q} is not finite or has a negative size"));
        }
    }
    for (q, list) in members.iter().enumerate() {
        for &t in list {
            if t >= n {
                return bad(format!(
                    "quad {q}: triangle {t} out of range ({n} triangles)"
                ));
            }
            let m = soup.material[t] as usize;
            if m >= materials.len() {
                return bad(format!(
                    "triangle {t}: material {m} out of range ({} materials)",
                    materials.len()
                ));
            }
            let finite = soup.positions[t].iter().all(|p| p.is_finite())
                && soup.uvs[t].iter().all(|uv| uv.is_finite());
            if !finite {
                return bad(format!("triangle {t} has a non-finite position or uv"));
            }
        }
    }
    Ok(())
}

/// Texture sizes and their packing at the density finally used.
struct Layout {
    sizes: Vec<(u32, u32)>,
    packing: Packing,
    texels_per_unit: f32,
    density_reduced: bool,
}

/// Texels along each quad axis at `density`: the quad's aspect ratio, the longest side at
/// most `max_side`, each side clamped to `min_side..=max_side`.
fn texture_size(quad: &Quad, density: f32, p: &BakeParams) -> (u32, u32) {
    let raw = (quad.size().as_dvec2()) * f64::from(density);
    let longest = raw.max_element();
    let max = f64::from(p.max_side);
    let scale = if longest > max { max / longest } else { 1.0 };
    let side = |x: f64| ((x * scale).ceil().min(max) as u32).clamp(p.min_side, p.max_side);
    (side(raw.x), side(raw.y))
}

/// Finds the highest density, at most the requested one, whose textures pack into the atlas.
fn layout(quads: &[Quad], p: &BakeParams) -> Result<Layout, BakeError> {
    let too_small = || BakeError::AtlasTooSmall {
        quads: quads.len(),
        max_atlas: p.max_atlas,
        min_side: p.min_side,
        padding: p.padding,
    };
    let sizes_at = |density: f32| -> Vec<(u32, u32)> {
        quads.iter().map(|q| texture_size(q, density, p)).collect()
    };
    let mut density = p.texels_per_unit;
    let mut reduced = false;
    // Jump close to a fitting density when the request is far too high: the padded area
    // grows at most quadratically with the density.
    let capacity = f64::from(p.max_atlas).powi(2);
    let area = |sizes: &[(u32, u32)]| -> f64 {
        let pad = 2.0 * f64::from(p.padding);
        sizes
            .iter()
            .map(|&(w, h)| (f64::from(w) + pad) * (f64::from(h) + pad))
            .sum()
    };
    let first = area(&sizes_at(density));
    if first > 4.0 * capacity {
        density = (f64::from(density) * (capacity / first).sqrt()) as f32;
        reduced = true;
    }
    let mut previous: Option<Vec<(u32, u32)>> = None;
    loop {
        let sizes = sizes_at(density);
        if previous.as_ref() != Some(&sizes)
            && let Some(packing) = atlas::pack(&sizes, p.padding, p.max_atlas)
        {
            return Ok(Layout {
                sizes,
                packing,
                texels_per_unit: density,
                density_reduced: reduced,
            });
        }
        let at_minimum = sizes
            .iter()
            .all(|&(w, h)| w == p.min_side && h == p.min_side);
        if at_minimum || density <= f32::MIN_POSITIVE {
            return Err(too_small());
        }
        previous = Some(sizes);
        density *= DENSITY_STEP;
        reduced = true;
    }
}

/// The quad's front normal, `axis_u × axis_v` (the side its texture shows).
fn front_normal(quad: &Quad) -> Vec3 {
    quad.axis_u.cross(quad.axis_v).normalize_or_zero()
}

/// Atlas UVs of the quad's corners (see [`BakedCloud::uv_rects`]).
fn uv_rect(c: &Cell, width: u32, height: u32) -> [Vec2; 4] {
    let (w, h) = (width as f32, height as f32);
    let (x0, x1) = (c.x as f32 / w, (c.x + c.width) as f32 / w);
    let (y0, y1) = (c.y as f32 / h, (c.y + c.height) as f32 / h);
    [
        Vec2::new(x0, y1),
        Vec2::new(x1, y1),
        Vec2::new(x1, y0),
        Vec2::new(x0, y0),
    ]
}

/// A member triangle placed in the supersampled atlas: x right and y down in supersampled
/// texels, z the wgpu depth (0 = nearest the quad's front), the source uv, the triangle's
/// world-space face normal and its material.
#[derive(Clone, Copy, Debug)]
struct PlacedTriangle {
    pos: [[f32; 3]; 3],
    uv: [[f32; 2]; 3],
    normal: [f32; 3],
    material: u32,
}

/// A polygon vertex while clipping: quad coordinates s, t (0..1 across the quad), signed
/// distance from the quad's plane, uv.
type ClipVertex = [f32; 5];

/// Clips the convex polygon to `s, t ∈ [0, 1]` (Sutherland–Hodgman, orientation kept).
fn clip_to_unit_square(poly: &mut Vec<ClipVertex>, scratch: &mut Vec<ClipVertex>) {
    for (axis, keep_above, bound) in [
        (0, true, 0.0),
        (0, false, 1.0),
        (1, true, 0.0),
        (1, false, 1.0),
    ] {
        scratch.clear();
        let inside = |v: &ClipVertex| {
            if keep_above {
                v[axis] >= bound
            } else {
                v[axis] <= bound
            }
        };
        for i in 0..poly.len() {
            let a = poly[i];
            let b = poly[(i + 1) % poly.len()];
            let (ia, ib) = (inside(&a), inside(&b));
            if ia {
                scratch.push(a);
            }
            if ia != ib {
                let f = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut v = [0.0; 5];
                for k in 0..5 {
                    v[k] = a[k] + (b[k] - a[k]) * f;
                }
                v[axis] = bound; // exact, so the clipped edge lies on the cell border
                scratch.push(v);
            }
        }
        std::mem::swap(poly, scratch);
        if poly.is_empty() {
            return;
        }
    }
}

/// The quad's member triangles transformed into its cell of the supersampled atlas and
/// clipped to it (animated-billboard-clouds §2.4 steps 3–4: view window = the quad; improved
/// §4 item 3: near/far from the members' depth range).
fn quad_triangles(
    soup: &TriangleSoup,
    quad: &Quad,
    members: &[usize],
    cell: &Cell,
    ss: u32,
) -> Vec<PlacedTriangle> {
    let size = quad.size();
    let n = front_normal(quad);
    if size.min_element() <= 0.0 || !size.recip().is_finite() || n == Vec3::ZERO {
        return Vec::new(); // a degenerate quad shows nothing
    }
    let (u, v) = (quad.axis_u.normalize(), quad.axis_v.normalize());
    let local = |p: Vec3| -> [f32; 3] {
        let d = p - quad.center;
        [d.dot(u) / size.x + 0.5, d.dot(v) / size.y + 0.5, d.dot(n)]
    };

    let mut polys: Vec<(Vec<ClipVertex>, [f32; 3], u32)> = Vec::with_capacity(members.len());
    let mut scratch = Vec::new();
    let (mut dmin, mut dmax) = (f32::INFINITY, f32::NEG_INFINITY);
    for &t in members {
        let corners = soup.positions[t];
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let mut poly: Vec<ClipVertex> = (0..3)
            .map(|k| {
                let [s, tt, d] = local(corners[k]);
                let uv = soup.uvs[t][k];
                [s, tt, d, uv.x, uv.y]
            })
            .collect();
        let outside = poly
            .iter()
            .any(|p| !(0.0..=1.0).contains(&p[0]) || !(0.0..=1.0).contains(&p[1]));
        if outside {
            clip_to_unit_square(&mut poly, &mut scratch);
        }
        if poly.len() < 3 {
            continue;
        }
        for p in &poly {
            dmin = dmin.min(p[2]);
            dmax = dmax.max(p[2]);
        }
        polys.push((poly, normal.to_array(), soup.material[t]));
    }
    if polys.is_empty() {
        return Vec::new();
    }
    // Depth: nearest member (largest distance toward the front) -> small z, with margins.
    let scale = size.max_element().max(dmax.abs()).max(dmin.abs());
    let margin = (0.01 * (dmax - dmin)).max(1e-6 * scale).max(1e-30);
    let (near, far) = (dmax + margin, dmin - margin);
    let ssf = ss as f32;
    let (x0, y0) = (cell.x as f32 * ssf, cell.y as f32 * ssf);
    let (w, h) = (cell.width as f32 * ssf, cell.height as f32 * ssf);
    let place = |p: &ClipVertex| -> [f32; 3] {
        [
            x0 + p[0] * w,
            y0 + (1.0 - p[1]) * h,
            ((near - p[2]) / (near - far)).clamp(0.0, 1.0),
        ]
    };
    let mut out = Vec::with_capacity(polys.len());
    for (poly, normal, material) in &polys {
        for i in 1..poly.len() - 1 {
            let fan = [&poly[0], &poly[i], &poly[i + 1]];
            out.push(PlacedTriangle {
                pos: fan.map(place),
                uv: fan.map(|p| [p[3], p[4]]),
                normal: *normal,
                material: *material,
            });
        }
    }
    out
}

/// Per-texel results of downsampling, before dilation.
struct Downsampled {
    width: u32,
    height: u32,
    color: Vec<u8>,
    normal: Vec<u8>,
    /// Covered supersamples per texel.
    samples: Vec<u16>,
}

impl Downsampled {
    fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            color: vec![0; n * 4],
            normal: vec![0; n * 4],
            samples: vec![0; n],
        }
    }
}

/// Alpha byte of a texel with `n` of `total` supersamples covered: 0 when none, 255 when all,
/// monotonic, and >= 128 exactly when `n >= needed` (the alpha-cutoff sample count).
fn coverage_alpha(n: u32, total: u32, needed: u32) -> u8 {
    if n == 0 {
        0
    } else if n < needed {
        ((n * 127 + needed / 2) / needed).clamp(1, 127) as u8
    } else if needed == total {
        255
    } else {
        let extra = total - needed;
        (128 + ((n - needed) * 127 + extra / 2) / extra).min(255) as u8
    }
}

/// Re-thresholds the alpha of each cell whose foliage the plain alpha test would thin out or
/// thicken, so that the number of texels passing the 0.5 test equals the cell's summed
/// coverage in texels, rounded with the remainder carried to the next such cell
/// ([`BakeParams::preserve_coverage`]). A cell where the test at the cutoff (`needed` covered
/// samples of `total`) already passes its coverage within [`COVERAGE_TOLERANCE`] keeps its
/// graded alpha: its leaves are resolved at this density, and a billboard seen at its design
/// size should reproduce their outline, not a re-thresholded (speckled) one.
fn preserve_coverage(out: &mut Downsampled, cells: &[Cell], total: u32, needed: u32) {
    let thresholds = coverage_thresholds(out, cells, total, needed);
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, 0, out.width, out.height))
        .collect();
    let bands = row_bands(&rects);
    (band_parts(out, &bands).into_par_iter()).for_each(|(mut band, members)| {
        for &c in members {
            if let Some(threshold) = thresholds[c] {
                band.threshold(rects[c], threshold);
            }
        }
    });
}

/// Per cell, the covered samples from which its texels pass after [`preserve_coverage`]
/// (`total + 1`: none), `None` where it keeps its graded alpha. The cells' counts are
/// gathered in parallel, the remainders then carried from cell to cell in quad order.
fn coverage_thresholds(
    out: &Downsampled,
    cells: &[Cell],
    total: u32,
    needed: u32,
) -> Vec<Option<u32>> {
    let w = out.width as usize;
    // Per cell with covered texels: its summed covered samples, its texels passing at the
    // cutoff, and how many texels have each count of covered samples (0 left out).
    let counts: Vec<Option<(u64, usize, Vec<usize>)>> = cells
        .par_iter()
        .map(|c| {
            let mut histogram = vec![0usize; total as usize + 1];
            for y in c.y as usize..(c.y + c.height) as usize {
                let row = &out.samples[y * w + c.x as usize..][..c.width as usize];
                for &n in row {
                    histogram[usize::from(n).min(total as usize)] += 1;
                }
            }
            histogram[0] = 0;
            let covered: usize = histogram.iter().sum();
            (covered > 0).then(|| {
                let sum = (histogram.iter().enumerate())
                    .map(|(n, &k)| n as u64 * k as u64)
                    .sum();
                let passing = histogram[needed as usize..].iter().sum();
                (sum, passing, histogram)
            })
        })
        .collect();
    // Rounding remainders carry over to the next cell (in quad order), so the whole atlas
    // keeps its coverage even when most cells hold less than one texel of it.
    let mut carry = 0.0f64;
    (counts.into_iter())
        .map(|counts| {
            let (sum, passing, histogram) = counts?;
            let own = sum as f64 / f64::from(total);
            let passing = passing as f64;
            if own >= 1.0 && (passing - own).abs() <= COVERAGE_TOLERANCE * own {
                return None;
            }
            let covered: usize = histogram.iter().sum();
            let want = own + carry;
            let keep = (want.round().max(0.0) as usize).min(covered);
            carry = want - keep as f64;
            // The `keep`-th largest count: texels with at least it pass; none when keep == 0.
            let mut seen = 0;
            Some(if keep == 0 {
                total + 1
            } else {
                (0..=total)
                    .rev()
                    .find(|&n| {
                        seen += histogram[n as usize];
                        seen >= keep
                    })
                    .unwrap_or(0)
            })
        })
        .collect()
}

/// Relative difference between a cell's coverage (in texels) and the texels the plain alpha
/// test passes under which [`preserve_coverage`] leaves the cell alone. Chosen by measurement
/// (oak_medium and pine_medium_blender, default chain, `frond eval --screen-height H`): see
/// the measurements in the commit that introduced it.
const COVERAGE_TOLERANCE: f64 = 0.1;

/// Covered supersamples (of `supersample²`) a texel needs to pass the alpha cutoff.
fn cutoff_samples(params: &BakeParams) -> u32 {
    let total = params.supersample * params.supersample;
    (0..=total)
        .find(|&n| f64::from(n) >= f64::from(params.alpha_cutoff) * f64::from(total))
        .unwrap_or(total)
}

/// The textures of the CPU bake: those the materials of `members`' triangles read, which
/// alone are prepared.
struct BakeTextures {
    prepared: SoftwareTextures,
    used: Vec<bool>,
}

/// `textures` prepared for the CPU bake ([`SoftwareTextures::for_bake_of`]).
fn bake_textures(
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

/// Renders the supersampled atlas and downsamples it: with the CPU bake rasteriser where its
/// textures are `prepared` (`params` names it), through the wgpu renderer otherwise.
#[expect(
    clippy::too_many_arguments,
    reason = "the job's parts, kept apart from the rasteriser's"
)]
fn render_atlas(
    renderer: &Renderer,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    prepared: Option<&BakeTextures>,
    placed_triangles: &[Vec<PlacedTriangle>],
    cells: &[Cell],
    params: &BakeParams,
    out: &mut Downsampled,
) -> Result<(), BakeError> {
    let job = AtlasJob {
        materials: materials.iter().map(two_sided).collect(),
        textures,
        placed_triangles,
        cells,
        params,
    };
    match prepared {
        Some(textures) => render_atlas_cpu(&job, textures, out),
        None => render_atlas_wgpu(renderer, &job, out),
    }
}

/// What either rasteriser draws: the members placed in the supersampled atlas, with their
/// materials (two-sided) and textures.
struct AtlasJob<'a> {
    materials: Vec<DrawMaterial>,
    textures: &'a [DrawTexture],
    placed_triangles: &'a [Vec<PlacedTriangle>],
    cells: &'a [Cell],
    params: &'a BakeParams,
}

impl AtlasJob<'_> {
    /// A scene of the job's materials and textures, without meshes yet.
    fn scene(&self) -> DrawScene {
        self.scene_of(&vec![true; self.textures.len()])
    }

    /// [`AtlasJob::scene`] with only the textures `used` copied, each other one a
    /// [`DrawTexture::placeholder`] (a bake reads only its foliage's).
    fn scene_of(&self, used: &[bool]) -> DrawScene {
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

    /// [`tile_meshes`] of the supersampled rectangle `rect`.
    fn meshes(&self, rect: [u32; 4]) -> (Vec<DrawMesh>, Vec<Vec<[f32; 3]>>) {
        tile_meshes(
            self.placed_triangles,
            self.cells,
            self.params.supersample,
            rect,
            self.materials.len(),
        )
    }
}

/// Members are drawn from both sides (a billboard is seen from both) with their texture and
/// alpha test.
fn two_sided(m: &DrawMaterial) -> DrawMaterial {
    DrawMaterial {
        double_sided: true,
        ..m.clone()
    }
}

/// Texel rows of the atlas in one frame of supersampled coordinates (every sample's weights
/// follow its rounding): the atlas is cut into strips of so many rows, each cell's part of a
/// strip drawn in the strip's frame.
const CPU_STRIP_TEXELS: u32 = 256;

/// Texel columns of a frame of an atlas `width` texels wide at `ss`² supersampling: the whole
/// width where a target can hold it, else as many as one can
/// ([`BakeTarget::MAX_SIDE_SAMPLES`]: a 16×-supersampled bake of an atlas wider than 2048).
fn cpu_frame_columns(width: u32, ss: u32) -> u32 {
    let most = BakeTarget::MAX_SIDE_SAMPLES / ss.max(1);
    width.min(most.max(1))
}

/// The CPU path: every cell's part of every frame of the atlas drawn alone by [`BakeTarget`]
/// from its own triangles (colour and normals in one pass), in parallel, and stored texel by
/// texel. A frame is a strip of [`CPU_STRIP_TEXELS`] rows, cut into columns where the atlas
/// is wider than a target ([`cpu_frame_columns`]); frames of one size share one target, the
/// shorter last strip and narrower last column have their own.
fn render_atlas_cpu(
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
struct CellRegion {
    /// The frame's texels `[x, y, w, h]` in the atlas.
    frame: [u32; 4],
    /// The cell's texels `[x, y, w, h]` in the frame.
    rect: [u32; 4],
    /// The cell.
    cell: usize,
}

/// The regions of the cells with triangles in the frames `group` (texels of the atlas,
/// strip by strip), frame by frame.
fn cell_regions(job: &AtlasJob, group: &[[u32; 4]]) -> Vec<CellRegion> {
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
fn store_texels(out: &mut Downsampled, regions: &[CellRegion], texels: &[Vec<CoveredTexel>]) {
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
type CoveredTexel = (usize, u16, [u8; 4], [u8; 4]);

/// One cell's triangles `tris` (supersampled atlas coordinates) in NDC of the supersampled
/// rectangle `rect` (as [`tile_meshes`] places them, with their normals) written into
/// `meshes` (its buffers reused): one mesh per material with triangles, in material order
/// (the order [`tile_meshes`] draws a cell's triangles in).
fn cell_meshes(
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

/// Appends triangle `t` (supersampled atlas coordinates) to `mesh` in NDC of the
/// supersampled rectangle `rect`, and its world-space face normal per vertex to `normals`.
fn push_triangle(
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

/// The wgpu path: the supersampled atlas rendered tile by tile (colour, then normals) and
/// downsampled.
fn render_atlas_wgpu(
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

/// Whether the quad's supersampled cell overlaps the render tile `[x, y, w, h]`.
fn cell_in_tile(c: &Cell, ss: u32, r: [u32; 4]) -> bool {
    let (x0, y0) = (c.x * ss, c.y * ss);
    let (x1, y1) = (x0 + c.width * ss, y0 + c.height * ss);
    x0 < r[0] + r[2] && r[0] < x1 && y0 < r[1] + r[3] && r[1] < y1
}

/// Tile triangles of the quads overlapping the render tile, one mesh per material, in NDC
/// of that tile (drawn with an identity matrix), without normals (unlit), plus per mesh the
/// world-space face normal of each vertex's triangle for the normal pass (the tile positions
/// no longer define world normals).
fn tile_meshes(
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
fn downsample(
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

/// One covered texel's colour and normal bytes: `alpha` its coverage's
/// ([`coverage_alpha`]), `mean` its covered samples' linear colour, `normal_sum` the sum of
/// their normals (rgb 0 when it has no direction: "no normal", which no unit vector encodes to and
/// dilation replaces with the quad's normal).
fn texel_bytes(alpha: u8, mean: [f32; 3], normal_sum: Vec3) -> ([u8; 4], [u8; 4]) {
    let [r, g, b] = mean.map(linear_to_srgb);
    let unit = normal_sum.normalize_or_zero();
    let normal = if unit == Vec3::ZERO {
        [0, 0, 0, alpha]
    } else {
        encode_normal(unit, alpha)
    };
    ([r, g, b, alpha], normal)
}

/// `rgb = n * 0.5 + 0.5` as bytes, with the given alpha.
fn encode_normal(n: Vec3, alpha: u8) -> [u8; 4] {
    let e = |x: f32| round_byte((x * 0.5 + 0.5) * 255.0);
    [e(n.x), e(n.y), e(n.z), alpha]
}

/// `v.round().clamp(0.0, 255.0) as u8` (0 for a NaN), without a call to the C library's
/// `roundf` (the baseline x86-64 has no rounding instruction): `v` clamped first, which
/// changes nothing, then its integer part plus one where the rest is at least one half (the
/// rest is exact below 256), as `round` does.
#[inline]
fn round_byte(v: f32) -> u8 {
    let c = v.clamp(0.0, 255.0);
    let whole = c as u32;
    (whole + u32::from(c - whole as f32 >= 0.5)) as u8
}

/// A quad's padded cell in the atlas: texel columns `x0..x1`, rows `y0..y1`. Padded cells
/// are disjoint.
fn padded_rect(cell: &Cell, padding: u32, width: u32, height: u32) -> [usize; 4] {
    [
        cell.x.saturating_sub(padding) as usize,
        ((cell.x + cell.width + padding).min(width)) as usize,
        cell.y.saturating_sub(padding) as usize,
        ((cell.y + cell.height + padding).min(height)) as usize,
    ]
}

/// Finishes each quad's padded cell in place, the cells in parallel (bands of atlas rows
/// that no padded cell straddles, [`row_bands`]), each texel written once more at most:
/// - dilation: every texel no sample covered takes the colour and normal of a nearest
///   covered texel of that quad (chessboard distance, 8-neighbours: [`dilate`]), alpha
///   staying 0; a quad with nothing covered gets the mean covered colour of the atlas and its
///   own front normal (improved-billboard-cloud §4 item 6);
/// - tangent space: the normal, baked and dilated in world space, is rewritten in the quad's
///   tangent frame (`axis_u`, `axis_v`, front normal): what glTF's `normalTexture` holds, the
///   tangents engines derive from the billboard's UVs running along the same axes.
fn finish_cells(mut d: Downsampled, cells: &[Cell], quads: &[Quad], padding: u32) -> Atlas {
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, padding, d.width, d.height))
        .collect();
    let bands = row_bands(&rects);
    // The cells without any covered texel, band by band.
    let empty: Vec<usize> = (band_parts(&mut d, &bands).into_par_iter())
        .map_init(Vec::new, |grid, (mut band, members)| {
            (members.iter().copied())
                .filter(|&c| !band.finish(rects[c], &quads[c], grid))
                .collect::<Vec<usize>>()
        })
        .flatten()
        .collect();
    if !empty.is_empty() {
        let fallback = mean_color(&d.color, &d.samples);
        let mut all = CellTexels {
            color: &mut d.color,
            normal: &mut d.normal,
            samples: &d.samples,
            width: d.width as usize,
            y0: 0,
        };
        for c in empty {
            all.fill(rects[c], &quads[c], fallback);
        }
    }
    Atlas {
        width: d.width,
        height: d.height,
        color: d.color,
        normal: d.normal,
    }
}

/// `d`'s rows cut along `bands` ([`row_bands`]): per band, its rows of both atlases and of
/// the covered samples, and its cells.
fn band_parts<'a>(
    d: &'a mut Downsampled,
    bands: &'a [(Range<usize>, Vec<usize>)],
) -> Vec<(CellTexels<'a>, &'a [usize])> {
    let width = d.width as usize;
    let mut parts = Vec::with_capacity(bands.len());
    let (mut color, mut normal) = (&mut d.color[..], &mut d.normal[..]);
    let mut done = 0;
    for (rows, members) in bands {
        let skip = (rows.start - done) * width * 4;
        let len = rows.len() * width * 4;
        let (c, n);
        (c, color) = std::mem::take(&mut color)[skip..].split_at_mut(len);
        (n, normal) = std::mem::take(&mut normal)[skip..].split_at_mut(len);
        done = rows.end;
        let band = CellTexels {
            color: c,
            normal: n,
            samples: &d.samples[rows.start * width..rows.end * width],
            width,
            y0: rows.start,
        };
        parts.push((band, &members[..]));
    }
    parts
}

/// The padded cells' rectangles `rects` (`[x0, x1, y0, y1]`, disjoint) gathered into bands of
/// whole atlas rows, in row order: each cell's rows lie within one band, each band's cells
/// (by index) are the ones whose rows it holds. A shelf packing gives a band a shelf.
fn row_bands(rects: &[[usize; 4]]) -> Vec<(Range<usize>, Vec<usize>)> {
    let mut order: Vec<usize> = (0..rects.len())
        .filter(|&c| rects[c][2] < rects[c][3])
        .collect();
    order.sort_by_key(|&c| (rects[c][2], c));
    let mut bands: Vec<(Range<usize>, Vec<usize>)> = Vec::new();
    for c in order {
        let [_, _, y0, y1] = rects[c];
        match bands.last_mut() {
            Some((rows, members)) if y0 < rows.end => {
                rows.end = rows.end.max(y1);
                members.push(c);
            }
            _ => bands.push((y0..y1, vec![c])),
        }
    }
    bands
}

/// One step of distance in a dilation grid's entry ([`CellTexels::finish`]).
const STEP: u64 = 1 << 32;
/// A dilation grid's entry no covered texel has reached (nor can, in the two passes: a step
/// more is still above every reached entry).
const UNREACHED: u64 = u64::MAX >> 1;

/// The two raster passes of Rosenfeld and Pfaltz over 8-neighbours on a dilation `grid` (rows
/// of `gw` entries, a ring of [`UNREACHED`] around them, see [`CellTexels::finish`]): each
/// entry becomes the least of itself and its four neighbours behind it, one [`STEP`] further,
/// which is exact for the chessboard distance (on a tie of distance, the source first in row
/// order wins: the entries' low halves). Each row takes the row behind it first, four
/// entries at a time where the machine has AVX2 (the same integers either way), then its
/// neighbour behind it in the row, one by one.
fn chessboard_passes(grid: &mut [u64], gw: usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the machine has AVX2, checked just above.
        return unsafe { chessboard_passes_avx2(grid, gw) };
    }
    chessboard_passes_in(grid, gw);
}

/// [`chessboard_passes`] compiled for AVX2 (the compiler vectorises the rows' first step).
///
/// # Safety
/// The machine must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn chessboard_passes_avx2(grid: &mut [u64], gw: usize) {
    chessboard_passes_in(grid, gw);
}

/// [`chessboard_passes`]' work, inlined into each caller's target features.
#[inline(always)]
fn chessboard_passes_in(grid: &mut [u64], gw: usize) {
    let rows = grid.len() / gw;
    // Each entry of `row` (but the ring's) the least of itself and the three of `behind`
    // around it, a step further.
    let from_row = |row: &mut [u64], behind: &[u64]| {
        let around = behind.windows(3);
        for (entry, w) in row[1..gw - 1].iter_mut().zip(around) {
            *entry = (*entry).min(w[0].min(w[1]).min(w[2]) + STEP);
        }
    };
    for y in 1..rows - 1 {
        let (done, rest) = grid.split_at_mut(y * gw);
        let row = &mut rest[..gw];
        from_row(row, &done[(y - 1) * gw..]);
        for x in 1..gw - 1 {
            row[x] = row[x].min(row[x - 1] + STEP);
        }
    }
    for y in (1..rows - 1).rev() {
        let (rest, done) = grid.split_at_mut((y + 1) * gw);
        let row = &mut rest[y * gw..];
        from_row(row, &done[..gw]);
        for x in (1..gw - 1).rev() {
            row[x] = row[x].min(row[x + 1] + STEP);
        }
    }
}

/// Rows of both atlases from row `y0` (as many as `color` holds), and their texels' covered
/// samples.
struct CellTexels<'a> {
    color: &'a mut [u8],
    normal: &'a mut [u8],
    samples: &'a [u16],
    width: usize,
    y0: usize,
}

impl CellTexels<'_> {
    /// The atlas texel `[x, y]`'s index in these rows.
    #[inline]
    fn at(&self, x: usize, y: usize) -> usize {
        (y - self.y0) * self.width + x
    }

    /// Finishes the padded cell `[x0, x1, y0, y1]` of `quad` (see [`finish_cells`]): its
    /// covered texels' normals rewritten in tangent space, then [`CellTexels::dilate`]d into
    /// the others. False, leaving it as it is, when no texel of it is covered. `grid` is
    /// scratch.
    fn finish(&mut self, rect: [usize; 4], quad: &Quad, grid: &mut Vec<u64>) -> bool {
        let [x0, x1, y0, y1] = rect;
        let mut tangent = TangentSpace::of(quad);
        // The cell with a ring of unreachable texels around it, each entry its distance
        // (high half) and source (low half, the texel's index in these rows).
        let gw = x1 - x0 + 2;
        grid.clear();
        grid.resize(gw * (y1 - y0 + 2), UNREACHED);
        let mut any = false;
        let (normal, _) = self.normal.as_chunks_mut::<4>();
        for y in y0..y1 {
            let at = (y - self.y0) * self.width + x0;
            let samples = &self.samples[at..at + x1 - x0];
            let entries = &mut grid[(y - y0 + 1) * gw + 1..][..x1 - x0];
            for (k, (&n, entry)) in samples.iter().zip(entries).enumerate() {
                if n > 0 {
                    any = true;
                    *entry = (at + k) as u64;
                    let [r, g, b, a] = normal[at + k];
                    let [r, g, b] = tangent.convert([r, g, b]);
                    normal[at + k] = [r, g, b, a];
                }
            }
        }
        if any {
            self.dilate(rect, grid);
        }
        any
    }

    /// Gives each uncovered texel of the cell `[x0, x1, y0, y1]` the colour and normal of a
    /// covered texel nearest it in chessboard distance (`grid`, see [`CellTexels::finish`]:
    /// each covered texel itself at distance 0, found by [`chessboard_passes`]), its alpha
    /// staying 0. The cell has a covered texel, so the passes reach every texel, and a covered
    /// texel is its own source: each texel's colour and normal are copied from its source
    /// with no test.
    fn dilate(&mut self, [x0, x1, y0, y1]: [usize; 4], grid: &mut [u64]) {
        let gw = x1 - x0 + 2;
        chessboard_passes(grid, gw);
        let (color, _) = self.color.as_chunks_mut::<4>();
        let (normal, _) = self.normal.as_chunks_mut::<4>();
        for y in y0..y1 {
            let at = (y - self.y0) * self.width + x0;
            let entries = &grid[(y - y0 + 1) * gw + 1..][..x1 - x0];
            for (to, &entry) in (at..).zip(entries) {
                let from = (entry & u64::from(u32::MAX)) as usize;
                let ([r, g, b, _], [nr, ng, nb, _]) = (color[from], normal[from]);
                color[to] = [r, g, b, color[to][3]];
                normal[to] = [nr, ng, nb, normal[to][3]];
            }
        }
    }

    /// Sets the alpha of the covered texels of the cell `[x0, x1, y0, y1]`: opaque from
    /// `threshold` covered samples, clear below ([`preserve_coverage`]: binary, so that
    /// bilinear magnification keeps an isolated passing texel, 61 % of its area, instead of
    /// eroding one that barely passes to nothing).
    fn threshold(&mut self, [x0, x1, y0, y1]: [usize; 4], threshold: u32) {
        for y in y0..y1 {
            for x in x0..x1 {
                let i = self.at(x, y);
                let n = u32::from(self.samples[i]);
                if n > 0 {
                    let alpha = if n >= threshold { 255 } else { 0 };
                    self.color[i * 4 + 3] = alpha;
                    self.normal[i * 4 + 3] = alpha;
                }
            }
        }
    }

    /// Fills the padded cell `[x0, x1, y0, y1]` of `quad`, none of it covered, with the colour
    /// `fallback` and the quad's own front normal (alpha staying 0).
    fn fill(&mut self, [x0, x1, y0, y1]: [usize; 4], quad: &Quad, fallback: [u8; 3]) {
        let front = TangentSpace::of(quad).front();
        for y in y0..y1 {
            for x in x0..x1 {
                let i = self.at(x, y);
                self.color[i * 4..i * 4 + 3].copy_from_slice(&fallback);
                self.normal[i * 4..i * 4 + 3].copy_from_slice(&front);
            }
        }
    }
}

/// A quad's tangent frame (`axis_u`, `axis_v`, front normal), rewriting atlas normal bytes
/// (world space, `[0, 0, 0]` for "no normal": the quad's own) as tangent-space ones.
struct TangentSpace {
    u: Vec3,
    v: Vec3,
    front: Vec3,
    /// Bytes converted and what they became, by a hash of the bytes (the bytes and a bit
    /// set above them, 0 for a free slot): a cell's texels mostly share a few normals (flat
    /// cards), seen again after other cards' (a fifth of a cell's covered texels have a normal
    /// of their own on oak_dense, where remembering the last one only left a third to do).
    seen: [(u32, [u8; 3]); CONVERTED_SLOTS],
}

/// Slots of [`TangentSpace`]'s conversions remembered.
const CONVERTED_SLOTS: usize = 32;

impl TangentSpace {
    fn of(quad: &Quad) -> Self {
        TangentSpace {
            u: quad.axis_u.normalize_or_zero(),
            v: quad.axis_v.normalize_or_zero(),
            front: front_normal(quad),
            seen: [(0, [0; 3]); CONVERTED_SLOTS],
        }
    }

    /// The quad's own front normal in its tangent frame, as bytes.
    fn front(&mut self) -> [u8; 3] {
        self.convert([0, 0, 0])
    }

    /// World-space normal bytes `n` in the tangent frame, as bytes.
    fn convert(&mut self, n: [u8; 3]) -> [u8; 3] {
        let key = u32::from_le_bytes([n[0], n[1], n[2], 1]);
        // Fibonacci hashing: the product's top bits.
        let slot = (key.wrapping_mul(0x9e37_79b9) >> (32 - CONVERTED_SLOTS.ilog2())) as usize;
        if self.seen[slot].0 == key {
            return self.seen[slot].1;
        }
        let decode = |v: u8| f32::from(v) / 255.0 * 2.0 - 1.0;
        let world = if n == [0, 0, 0] {
            let [x, y, z, _] = encode_normal(self.front, 0);
            [x, y, z]
        } else {
            n
        };
        let m = Vec3::new(decode(world[0]), decode(world[1]), decode(world[2]))
            .normalize_or(self.front);
        let t = Vec3::new(m.dot(self.u), m.dot(self.v), m.dot(self.front)).normalize_or(Vec3::Z);
        let [r, g, b, _] = encode_normal(t, 0);
        self.seen[slot] = (key, [r, g, b]);
        [r, g, b]
    }
}

/// Mean colour (in linear light) of all covered texels, mid grey when there are none.
fn mean_color(color: &[u8], samples: &[u16]) -> [u8; 3] {
    let lut = &*SRGB_LINEAR;
    let mut sum = [0.0f64; 3];
    let mut n = 0u64;
    for (i, _) in samples.iter().enumerate().filter(|(_, n)| **n > 0) {
        for k in 0..3 {
            sum[k] += f64::from(lut[color[i * 4 + k] as usize]);
        }
        n += 1;
    }
    if n == 0 {
        return [128; 3];
    }
    sum.map(|s| linear_to_srgb((s / n as f64) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in the plane z = 0 facing +z, centred on the origin, `half_size` along x and y.
    fn flat_quad(half_size: Vec2) -> Quad {
        Quad {
            plane: crate::plane::Plane {
                normal: Vec3::Z,
                offset: 0.0,
            },
            center: Vec3::ZERO,
            axis_u: Vec3::X,
            axis_v: Vec3::Y,
            half_size,
        }
    }

    #[test]
    fn preserved_coverage_passes_as_many_texels_as_are_covered() {
        // A 10x10 cell of texels each a quarter covered (4 of 16 samples), plus a 4x4 cell
        // fully covered: the 0.5 test keeps none of the first; preserving coverage keeps 25.
        let mut d = Downsampled::new(16, 12);
        let cells = [
            Cell {
                x: 0,
                y: 0,
                width: 10,
                height: 10,
            },
            Cell {
                x: 12,
                y: 0,
                width: 4,
                height: 4,
            },
        ];
        for y in 0..12usize {
            for x in 0..16usize {
                let i = y * 16 + x;
                let n: u16 = if x < 10 && y < 10 {
                    // Slightly different counts so the threshold falls between texels.
                    4 + ((x + y) % 2) as u16
                } else if x >= 12 && y < 4 {
                    16
                } else {
                    0
                };
                d.samples[i] = n;
                let a = coverage_alpha(u32::from(n), 16, 8);
                d.color[i * 4 + 3] = a;
                d.normal[i * 4 + 3] = a;
            }
        }
        let passing = |d: &Downsampled, c: &Cell| {
            (c.y..c.y + c.height)
                .flat_map(|y| (c.x..c.x + c.width).map(move |x| (y * 16 + x) as usize))
                .filter(|&i| d.color[i * 4 + 3] >= 128)
                .count()
        };
        assert_eq!(passing(&d, &cells[0]), 0);
        preserve_coverage(&mut d, &cells, 16, 8);
        // Σ n / 16 = (50·4 + 50·5) / 16 = 28.1 → 28 texels; ties at 5 samples: 50 have 5.
        // The threshold is the 28th largest count (5), so all 50 five-sample texels pass:
        // the closest achievable count with per-texel thresholds.
        let kept = passing(&d, &cells[0]);
        assert!((28..=50).contains(&kept), "{kept}");
        assert_eq!(passing(&d, &cells[1]), 16, "full cells stay full");
        for i in 0..d.samples.len() {
            let a = d.color[i * 4 + 3];
            assert_eq!(a, d.normal[i * 4 + 3]);
            assert!(a == 0 || a == 255, "binary alpha, got {a}");
            if d.samples[i] == 0 {
                assert_eq!(a, 0);
            }
        }
    }

    #[test]
    fn dilation_copies_a_nearest_covered_texel_of_the_cell() {
        // Three cells side by side and one below (two bands of rows), padding 2, a few
        // scattered covered texels each with its own colour; the third cell has none.
        let (w, h) = (40, 30);
        let cells = [(2, 2, 8, 9), (14, 2, 9, 6), (27, 2, 6, 6), (2, 17, 12, 10)].map(
            |(x, y, width, height)| Cell {
                x,
                y,
                width,
                height,
            },
        );
        let quad = flat_quad(Vec2::ONE);
        let mut d = Downsampled::new(w, h);
        let covered = [
            (3, 4),
            (8, 10),
            (5, 5),
            (20, 3),
            (14, 7),
            (2, 26),
            (13, 17),
            (7, 21),
        ];
        for (k, &(x, y)) in covered.iter().enumerate() {
            let i = (y * w + x) as usize;
            d.samples[i] = 16;
            d.color[i * 4..i * 4 + 4].copy_from_slice(&[10 + k as u8 * 20, 7, 9, 255]);
            d.normal[i * 4..i * 4 + 4].copy_from_slice(&[128, 128, 255, 255]);
        }
        let counts = d.samples.clone();
        let atlas = finish_cells(d, &cells, &[quad; 4], 2);
        for (c, cell) in cells.iter().enumerate() {
            let [x0, x1, y0, y1] = padded_rect(cell, 2, w, h);
            let own: Vec<(usize, usize)> = (covered.iter())
                .map(|&(x, y)| (x as usize, y as usize))
                .filter(|&(x, y)| (x0..x1).contains(&x) && (y0..y1).contains(&y))
                .collect();
            for y in y0..y1 {
                for x in x0..x1 {
                    let i = y * w as usize + x;
                    let texel = &atlas.color[i * 4..i * 4 + 4];
                    if own.is_empty() {
                        // No covered texel: the mean covered colour, the quad's own normal,
                        // alpha 0.
                        let mean = mean_color(&atlas.color, &counts);
                        assert_eq!(texel, &[mean[0], mean[1], mean[2], 0], "cell {c} ({x},{y})");
                        assert_eq!(&atlas.normal[i * 4..i * 4 + 3], &[128, 128, 255]);
                        continue;
                    }
                    let distance = |&(sx, sy): &(usize, usize)| sx.abs_diff(x).max(sy.abs_diff(y));
                    let nearest = own.iter().map(distance).min().expect("own texels");
                    let source = (own.iter())
                        .find(|&&(sx, sy)| atlas.color[(sy * w as usize + sx) * 4] == texel[0]);
                    let source = source.unwrap_or_else(|| panic!("cell {c} ({x},{y}) {texel:?}"));
                    assert_eq!(distance(source), nearest, "cell {c} ({x},{y})");
                    assert_eq!(&atlas.normal[i * 4..i * 4 + 3], &[128, 128, 255]);
                }
            }
        }
    }

    #[test]
    fn chessboard_passes_find_the_nearest_source_first_in_row_order() {
        // Random grids (a ring of unreached entries around each), a few sources each, some
        // sharing distances: every entry is the least (distance, source) of a brute-force
        // search, through the dispatched passes and the plain ones alike.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        for _ in 0..40 {
            let (w, h) = (1 + next(19) as usize, 1 + next(13) as usize);
            let gw = w + 2;
            let mut grid = vec![UNREACHED; gw * (h + 2)];
            let sources: Vec<(usize, usize)> = (0..1 + next(4))
                .map(|_| (next(w as u64) as usize, next(h as u64) as usize))
                .collect();
            for &(x, y) in &sources {
                grid[(y + 1) * gw + x + 1] = (y * w + x) as u64;
            }
            let mut plain = grid.clone();
            chessboard_passes(&mut grid, gw);
            chessboard_passes_in(&mut plain, gw);
            assert_eq!(grid, plain);
            for y in 0..h {
                for x in 0..w {
                    let want = (sources.iter())
                        .map(|&(sx, sy)| {
                            let d = sx.abs_diff(x).max(sy.abs_diff(y)) as u64;
                            d * STEP + (sy * w + sx) as u64
                        })
                        .min();
                    assert_eq!(Some(grid[(y + 1) * gw + x + 1]), want, "({x},{y}) {w}×{h}");
                }
            }
        }
    }

    #[test]
    fn byte_rounding_matches_the_library_round() {
        let mut values = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.0, 1e-30];
        for k in -4..=520 {
            let half = k as f32 * 0.5;
            values.extend([half, half.next_down(), half.next_up()]);
        }
        values.extend((0..100_000).map(|k| k as f32 * 0.002_7 - 3.0));
        for v in values {
            let want = v.round().clamp(0.0, 255.0) as u8;
            assert_eq!(round_byte(v), want, "{v:?}");
        }
    }

    #[test]
    fn remembered_conversions_are_the_fresh_ones() {
        // More normals than slots, in an order that revisits them: each conversion equals a
        // fresh frame's.
        let quad = Quad {
            axis_u: Vec3::new(0.6, 0.0, 0.8),
            axis_v: Vec3::Y,
            ..flat_quad(Vec2::ONE)
        };
        let mut remembered = TangentSpace::of(&quad);
        for k in 0..2000u32 {
            let j = k * 7919 % 97;
            let n = [
                (j * 37 % 256) as u8,
                (j * 11 % 256) as u8,
                (j * 5 % 256) as u8,
            ];
            let n = if j == 3 { [0, 0, 0] } else { n };
            assert_eq!(
                remembered.convert(n),
                TangentSpace::of(&quad).convert(n),
                "{n:?}"
            );
        }
    }

    #[test]
    fn resolved_cells_keep_their_graded_alpha() {
        // An 8×8 cell of sparse foliage, every texel 4 to 7 of 16 covered: the plain test
        // passes none of the 22 texels of coverage; re-thresholded, the cell keeps about them
        // (ties at the threshold pass together: the 7s and 6s, 32), with binary alpha.
        let cell = Cell {
            x: 0,
            y: 0,
            width: 8,
            height: 8,
        };
        let fill = |count: &dyn Fn(usize, usize) -> u16| {
            let mut d = Downsampled::new(8, 8);
            for y in 0..8 {
                for x in 0..8 {
                    let i = y * 8 + x;
                    let n = count(x, y);
                    d.samples[i] = n;
                    let a = coverage_alpha(u32::from(n), 16, 8);
                    d.color[i * 4 + 3] = a;
                    d.normal[i * 4 + 3] = a;
                }
            }
            d
        };
        let passing = |d: &Downsampled| (0..64).filter(|&i| d.color[i * 4 + 3] >= 128).count();
        let sparse = |x: usize, y: usize| 4 + ((x + 8 * y) % 4) as u16;
        let mut d = fill(&sparse);
        assert_eq!(passing(&d), 0);
        preserve_coverage(&mut d, std::slice::from_ref(&cell), 16, 8);
        assert_eq!(passing(&d), 32);
        assert!(d.color.chunks(4).all(|p| p[3] == 0 || p[3] == 255));
        // A leaf over three full columns and an edge column at 15/16: 32 texels pass for a
        // coverage of 31.5 (1.6 % off): the leaf is resolved, and the cell is left exactly as
        // baked, graded alpha and all.
        let leaf = |x: usize, _: usize| match x {
            0..=2 => 16,
            3 => 15,
            _ => 0,
        };
        let mut d = fill(&leaf);
        preserve_coverage(&mut d, std::slice::from_ref(&cell), 16, 8);
        assert_eq!(d.color, fill(&leaf).color);
        assert!(d.color.chunks(4).any(|p| p[3] > 128 && p[3] < 255));
    }

    #[test]
    fn preserved_coverage_carries_remainders_across_cells() {
        // 40 one-texel cells each 5/16 covered: rounding each alone keeps none; carrying the
        // remainder keeps round(40 · 5/16) = 12 or 13 of them.
        let mut d = Downsampled::new(40, 1);
        let cells: Vec<Cell> = (0..40)
            .map(|x| Cell {
                x,
                y: 0,
                width: 1,
                height: 1,
            })
            .collect();
        for i in 0..40 {
            d.samples[i] = 5;
        }
        preserve_coverage(&mut d, &cells, 16, 8);
        let kept = (0..40).filter(|&i| d.color[i * 4 + 3] >= 128).count();
        assert!((12..=13).contains(&kept), "{kept}");
    }

    #[test]
    fn alpha_is_128_exactly_at_the_cutoff() {
        for total in [1u32, 4, 9, 16, 25, 256] {
            for cutoff in [0.25f64, 0.5, 0.75, 1.0] {
                let needed = (0..=total)
                    .find(|&n| f64::from(n) >= cutoff * f64::from(total))
                    .unwrap_or(total);
                let mut last = 0;
                for n in 0..=total {
                    let a = coverage_alpha(n, total, needed);
                    assert_eq!(a >= 128, f64::from(n) >= cutoff * f64::from(total));
                    assert_eq!(a == 0, n == 0);
                    assert!(a >= last);
                    last = a;
                }
                assert_eq!(coverage_alpha(total, total, needed), 255);
            }
        }
    }

    #[test]
    fn clipping_keeps_the_part_inside_the_square() {
        let mut poly: Vec<ClipVertex> = vec![
            [-1.0, 0.5, 0.0, 0.0, 0.0],
            [2.0, 0.5, 3.0, 1.0, 0.0],
            [0.5, 2.0, 0.0, 0.0, 1.0],
        ];
        let mut scratch = Vec::new();
        clip_to_unit_square(&mut poly, &mut scratch);
        assert!(poly.len() >= 3);
        for p in &poly {
            assert!(
                (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]),
                "{p:?}"
            );
            // Attributes stay affine: d = s + 1 - ... along the bottom edge (t = 0.5).
        }
        // Signed area keeps its (counter-clockwise) sign.
        let area: f32 = (0..poly.len())
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        assert!(area > 0.0);
    }

    #[test]
    fn texture_sizes_follow_density_and_clamps() {
        let quad = flat_quad(Vec2::new(1.0, 0.25));
        let p = BakeParams::default();
        assert_eq!(texture_size(&quad, 10.0, &p), (20, 5));
        assert_eq!(texture_size(&quad, 1.0, &p), (4, 4));
        assert_eq!(texture_size(&quad, 1000.0, &p), (1024, 256));
    }
}
