//! The covered area of a baked cloud from around it, against its leaves' (spec
//! animated-billboard-clouds §5.4's filtered coverage, drawn by the CPU coverage rasteriser):
//! what a viewer's eye adds up, where the bake's per-billboard rule
//! ([`BakeParams::preserve_coverage`](crate::BakeParams::preserve_coverage)) only sees each
//! billboard from its front.
//!
//! A billboard's texels hold its leaves' area as projected onto its plane, foreshortening
//! undone; a leaf seen from elsewhere covers `area·|n_leaf·v|`, its billboard `area·|n_plane·v|`,
//! and where many of a crown's leaves face away from their planes the sum over the views
//! falls short. [`bake_keeping_view_coverage`] measures that shortfall and bakes again with
//! the billboards' coverage scaled to undo it ([`BakeParams::coverage_gain`](crate::BakeParams::coverage_gain)).

use frond_render::{
    Camera, DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture, Projection, RenderError,
    Renderer,
};
use frond_render::{SoftwareTextures, render_coverage};
use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::bake::{BakeError, BakeParams, BakedCloud, bake_cloud};
use crate::{Quad, TriangleSoup};

/// Where the covered areas are compared: views on rings around the leaves, at a pixel size.
#[derive(Clone, Debug, PartialEq)]
pub struct CoverageViews {
    /// Views per ring, evenly spaced in azimuth.
    pub views_per_ring: u32,
    /// The rings' elevations, degrees.
    pub elevations_deg: Vec<f32>,
    /// World units a pixel spans (the LOD's pixel at its switch distance).
    pub pixel: f32,
    /// Samples per pixel side.
    pub samples_per_side: u32,
}

/// Most pixels a side of a view's image: the views compare areas, which need no more.
const MAX_SIDE_PIXELS: u32 = 512;

/// Bakes tried at most by [`bake_keeping_view_coverage`] (the first included).
pub const MAX_BAKES: usize = 4;

/// The bake's covered area from the views is kept within this fraction of the leaves'.
pub const VIEW_COVERAGE_TOLERANCE: f64 = 0.02;

/// Most the billboards' coverage is scaled by, either way: a cloud that needs more is far
/// from its leaves for some other reason (planes, wood), which scaling would hide.
pub const MAX_COVERAGE_GAIN: f64 = 2.0;

/// The covered samples of `soup` (drawn with `materials` and `textures`, alpha-tested as
/// their materials say) and of the baked cloud (`quads` with `baked`'s atlas, alpha-tested at
/// 0.5 or blended as its atlas says, double-sided), summed over `views`: `(leaves, cloud)`
/// (blended layers count their alpha).
pub fn view_coverage(
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    quads: &[Quad],
    baked: &BakedCloud,
    views: &CoverageViews,
) -> Result<(f64, f64), RenderError> {
    let leaves = soup_scene(soup, materials, textures);
    let cloud = cloud_scene(quads, baked);
    let Some((lo, hi)) = leaves.bounds() else {
        return Ok((0.0, 0.0));
    };
    let cameras = cameras(lo, hi, views);
    let leaves = covered_samples(&leaves, &cameras)?;
    let cloud = covered_samples(&cloud, &cameras)?;
    Ok((leaves, cloud))
}

/// Bakes the cloud ([`bake_cloud`]); with `views`, then, while its covered area from them
/// differs from its leaves' by more than [`VIEW_COVERAGE_TOLERANCE`], again with the
/// billboards' coverage scaled by the ratio ([`BakeParams::coverage_gain`], within
/// [`MAX_COVERAGE_GAIN`]), at most [`MAX_BAKES`] times. Returns the bake whose ratio is
/// nearest 1 and that ratio (the cloud's covered samples over the leaves'); without `views`,
/// the one bake and no ratio.
#[expect(
    clippy::too_many_arguments,
    reason = "bake_cloud's inputs and the views to compare from"
)]
pub fn bake_keeping_view_coverage(
    renderer: &Renderer,
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    quads: &[Quad],
    members: &[Vec<usize>],
    params: &BakeParams,
    views: Option<&CoverageViews>,
) -> Result<(BakedCloud, Option<f64>), BakeError> {
    let bake = |p: &BakeParams| bake_cloud(renderer, soup, materials, textures, quads, members, p);
    let leaves_scene = soup_scene(soup, materials, textures);
    let (Some(views), Some((lo, hi))) = (views, leaves_scene.bounds()) else {
        return Ok((bake(params)?, None));
    };
    let cameras = cameras(lo, hi, views);
    let leaves = covered_samples(&leaves_scene, &cameras)?;
    let mut params = params.clone();
    let mut best: Option<(BakedCloud, f64)> = None;
    for _ in 0..MAX_BAKES {
        let baked = bake(&params)?;
        let cloud = covered_samples(&cloud_scene(quads, &baked), &cameras)?;
        let ratio = if leaves > 0.0 { cloud / leaves } else { 1.0 };
        let better = best
            .as_ref()
            .is_none_or(|(_, r)| (ratio.ln()).abs() < r.ln().abs());
        let done = (ratio - 1.0).abs() <= VIEW_COVERAGE_TOLERANCE || cloud == 0.0;
        if better {
            best = Some((baked, ratio));
        }
        let gain = (params.coverage_gain / ratio).clamp(1.0 / MAX_COVERAGE_GAIN, MAX_COVERAGE_GAIN);
        if done || gain == params.coverage_gain {
            break;
        }
        params.coverage_gain = gain;
    }
    let (baked, ratio) = best.unwrap_or_else(|| unreachable!("at least one bake ran"));
    Ok((baked, Some(ratio)))
}

/// The views' orthographic cameras around the box `lo..hi`, with the image size in pixels.
fn cameras(lo: Vec3, hi: Vec3, views: &CoverageViews) -> Vec<(Mat4, u32, u32)> {
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let side = ((2.0 * radius / views.pixel.max(1e-6)).ceil() as u32).clamp(1, MAX_SIDE_PIXELS);
    let n = views.views_per_ring.max(1);
    (views.elevations_deg.iter())
        .flat_map(|&elevation| {
            (0..n).map(move |i| {
                let camera = Camera::framing(
                    lo,
                    hi,
                    360.0 * i as f32 / n as f32,
                    elevation,
                    Projection::Orthographic {
                        half_height: radius,
                    },
                );
                (
                    camera.view_proj_for_bounds(1.0, lo, hi),
                    side,
                    views.samples_per_side.max(1),
                )
            })
        })
        .collect()
}

/// The covered samples of `scene` summed over `cameras` (in parallel, summed in order;
/// integers, exact, where nothing is blended).
fn covered_samples(scene: &DrawScene, cameras: &[(Mat4, u32, u32)]) -> Result<f64, RenderError> {
    let textures = SoftwareTextures::new(scene, false)?;
    let counts: Vec<f64> = cameras
        .par_iter()
        .map(|&(view_proj, side, k)| {
            let image = render_coverage(scene, &textures, view_proj, side, side, k)?;
            Ok((0..image.samples.len())
                .map(|i| f64::from(image.covered_samples(i)))
                .sum())
        })
        .collect::<Result<_, RenderError>>()?;
    Ok(counts.iter().sum())
}

/// The soup's triangles as a scene: one mesh per material.
fn soup_scene(
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
) -> DrawScene {
    let mut meshes: Vec<DrawMesh> = (0..materials.len())
        .map(|material| DrawMesh {
            material,
            ..Default::default()
        })
        .collect();
    for ((p, uv), &m) in soup.positions.iter().zip(&soup.uvs).zip(&soup.material) {
        let Some(mesh) = meshes.get_mut(m as usize) else {
            continue;
        };
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(p.iter().map(|v| v.to_array()));
        mesh.uvs
            .get_or_insert_with(Vec::new)
            .extend(uv.iter().map(|t| t.to_array()));
        mesh.indices.extend([base, base + 1, base + 2]);
    }
    meshes.retain(|m| !m.indices.is_empty());
    DrawScene {
        meshes,
        materials: materials.to_vec(),
        textures: textures.to_vec(),
    }
}

/// The baked quads as a scene: one double-sided mesh on the colour atlas, alpha-tested at
/// half coverage or blended ([`Atlas::blended`](crate::Atlas::blended)) as the written files draw it.
fn cloud_scene(quads: &[Quad], baked: &BakedCloud) -> DrawScene {
    let mut mesh = DrawMesh::default();
    let mut uvs = Vec::with_capacity(4 * quads.len());
    for (q, uv) in quads.iter().zip(&baked.uv_rects) {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(q.corners().map(|c| c.to_array()));
        uvs.extend(uv.iter().map(|t| t.to_array()));
        mesh.indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    mesh.uvs = Some(uvs);
    DrawScene {
        meshes: vec![mesh],
        materials: vec![DrawMaterial {
            texture: Some(0),
            alpha: if baked.atlas.blended {
                DrawAlpha::Blend
            } else {
                DrawAlpha::Mask(0.5)
            },
            double_sided: true,
            ..DrawMaterial::opaque([1.0; 4])
        }],
        textures: vec![DrawTexture {
            width: baked.atlas.width,
            height: baked.atlas.height,
            rgba: baked.atlas.color.clone(),
        }],
    }
}
