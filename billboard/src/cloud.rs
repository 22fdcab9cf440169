//! A billboard cloud for one set of triangles: plane search, one minimal rectangle per plane,
//! baked textures in one atlas (spec animated-billboard-clouds §2.4, improved-billboard-cloud §4).

use std::time::Instant;

use frond_render::{DrawAlpha, DrawMaterial, DrawTexture, Renderer};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bake::{BakeError, BakeParams, BakedCloud, bake_cloud};
use crate::plane_search::{PlaneSearch, SearchParams, search_planes, valid_for_plane};
use crate::quad::Quad;
use crate::rectangle::min_area_rect;
use crate::soup::TriangleSoup;

/// Everything that shapes a cloud.
#[derive(Clone, Debug, Default)]
pub struct CloudParams {
    /// How the billboard planes are found (spec §2.4).
    pub search: SearchParams,
    /// Bake every triangle valid for a plane, not only its own cluster (spec §2.4, §3.6.2).
    pub increased_density: bool,
    /// How the planes' textures are baked into the atlas.
    pub bake: BakeParams,
}

/// Wall times of the stages, seconds.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct CloudTimings {
    /// Seconds finding the planes.
    pub plane_search: f64,
    /// Seconds fitting each plane's rectangle and gathering its members.
    pub rectangles: f64,
    /// Seconds baking the atlas.
    pub bake: f64,
    /// Seconds for the whole cloud.
    pub total: f64,
}

/// Size and error facts of a cloud.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct CloudStats {
    /// Triangles of the soup.
    pub triangles: usize,
    /// Billboards (quads) in the cloud.
    pub billboards: usize,
    /// Sum of quad areas (world units²): the thesis's cost measure next to the count.
    pub total_area: f64,
    /// Uncompressed bytes of the colour and normal atlases.
    pub texture_bytes: usize,
    /// Atlas width, texels.
    pub atlas_width: u32,
    /// Atlas height, texels.
    pub atlas_height: u32,
    /// Texel density used, texels per world unit.
    pub texels_per_unit: f32,
    /// Whether that density is below the requested one (lowered to fit the atlas).
    pub density_reduced: bool,
    /// Largest vertex distance of a triangle from its billboard plane.
    pub max_distance: f32,
    /// Triangles joined to the nearest plane (plane budget or zero area), not placed by validity.
    pub joined: usize,
    /// Candidate planes the search scored.
    pub candidates_scored: usize,
    /// Wall times of the stages.
    pub timings_s: CloudTimings,
}

/// A finished cloud.
pub struct BillboardCloud {
    /// One billboard per plane, in the search's cluster order.
    pub quads: Vec<Quad>,
    /// The plane search that chose them.
    pub search: PlaneSearch,
    /// Their atlas and texture coordinates.
    pub baked: BakedCloud,
    /// Size and error facts.
    pub stats: CloudStats,
}

/// Why a cloud could not be built.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    /// The soup has no triangles.
    #[error("no triangles to simplify")]
    Empty,
    /// Baking the atlas failed.
    #[error(transparent)]
    Bake(#[from] BakeError),
}

/// The minimum-area rectangle of `triangles` projected onto the cluster's plane.
pub fn fit_quad(soup: &TriangleSoup, plane: &crate::Plane, triangles: &[usize]) -> Quad {
    let (u, v) = plane.frame();
    let origin = plane.normal * plane.offset;
    let pts: Vec<Vec2> = triangles
        .iter()
        .flat_map(|&t| soup.positions[t])
        .map(|p| {
            let d = p - origin;
            Vec2::new(d.dot(u), d.dot(v))
        })
        .collect();
    let rect = min_area_rect(&pts);
    let (center, axis, half) = match rect {
        Some(r) => (r.center, r.axis, r.half_size),
        None => (Vec2::ZERO, Vec2::X, Vec2::ZERO),
    };
    let axis_u = (u * axis.x + v * axis.y).normalize_or(u);
    let axis_v = plane.normal.cross(axis_u);
    Quad {
        plane: *plane,
        center: origin + u * center.x + v * center.y,
        axis_u,
        axis_v,
        half_size: half,
    }
}

/// Builds the cloud of `soup`. `scale` (e.g. the tree's bounding-box diagonal) sizes the float
/// tolerances of the search.
pub fn build_cloud(
    renderer: &Renderer,
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    params: &CloudParams,
    scale: f32,
) -> Result<BillboardCloud, CloudError> {
    if soup.is_empty() {
        return Err(CloudError::Empty);
    }
    let t0 = Instant::now();
    let search = search_planes(soup, &params.search, scale);
    let t1 = Instant::now();
    let quads: Vec<Quad> = search
        .clusters
        .par_iter()
        .map(|c| fit_quad(soup, &c.plane, &c.triangles))
        .collect();
    let members: Vec<Vec<usize>> = if params.increased_density {
        search
            .clusters
            .par_iter()
            .map(|c| {
                let mut m = valid_for_plane(soup, &c.plane, params.search.epsilon);
                m.extend(&c.triangles);
                m.sort_unstable();
                m.dedup();
                m
            })
            .collect()
    } else {
        search
            .clusters
            .iter()
            .map(|c| c.triangles.clone())
            .collect()
    };
    let t2 = Instant::now();
    let baked = bake_cloud(
        renderer,
        soup,
        materials,
        textures,
        &quads,
        &members,
        &params.bake,
    )?;
    let t3 = Instant::now();
    let stats = CloudStats {
        triangles: soup.len(),
        billboards: quads.len(),
        total_area: quads.iter().map(|q| q.area() as f64).sum(),
        texture_bytes: baked.texture_bytes,
        atlas_width: baked.atlas.width,
        atlas_height: baked.atlas.height,
        texels_per_unit: baked.texels_per_unit,
        density_reduced: baked.density_reduced,
        max_distance: search.max_distance,
        joined: search.joined,
        candidates_scored: search.candidates_scored,
        timings_s: CloudTimings {
            plane_search: (t1 - t0).as_secs_f64(),
            rectangles: (t2 - t1).as_secs_f64(),
            bake: (t3 - t2).as_secs_f64(),
            total: (t3 - t0).as_secs_f64(),
        },
    };
    Ok(BillboardCloud {
        quads,
        search,
        baked,
        stats,
    })
}

/// The cloud's quads as one indexed mesh: 4 corners each (in [`Quad::corners`] order), the
/// plane normal, atlas UVs, two triangles.
#[derive(Clone, Debug, Default)]
pub struct QuadMesh {
    /// Corner positions, world units, 4 per quad.
    pub positions: Vec<[f32; 3]>,
    /// The quad's plane normal at each corner.
    pub normals: Vec<[f32; 3]>,
    /// Atlas UV of each corner (glTF convention, (0, 0) top-left).
    pub uvs: Vec<[f32; 2]>,
    /// Two triangles per quad, counter-clockwise seen from its front.
    pub indices: Vec<u32>,
}

impl BillboardCloud {
    /// The quads as one mesh, for drawing and for export.
    pub fn quad_mesh(&self) -> QuadMesh {
        let mut m = QuadMesh::default();
        for (q, uv) in self.quads.iter().zip(&self.baked.uv_rects) {
            let base = m.positions.len() as u32;
            for (c, t) in q.corners().iter().zip(uv) {
                m.positions.push(c.to_array());
                m.normals.push(q.plane.normal.to_array());
                m.uvs.push(t.to_array());
            }
            m.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
        m
    }

    /// The cloud as drawable quads (two triangles each) textured with the colour atlas,
    /// alpha-tested at 0.5 and double-sided.
    pub fn draw_scene(&self) -> frond_render::DrawScene {
        let q = self.quad_mesh();
        let mesh = frond_render::DrawMesh {
            positions: q.positions,
            normals: None,
            tangents: None,
            uvs: Some(q.uvs),
            indices: q.indices,
            material: 0,
        };
        let atlas = &self.baked.atlas;
        frond_render::DrawScene {
            meshes: vec![mesh],
            materials: vec![DrawMaterial {
                wrap: Default::default(),
                base_color: [1.0; 4],
                texture: Some(0),
                normal_texture: None,
                alpha: DrawAlpha::Mask(0.5),
                double_sided: true,
            }],
            textures: vec![DrawTexture {
                width: atlas.width,
                height: atlas.height,
                rgba: atlas.color.clone(),
            }],
        }
    }
}

/// Bounding-box diagonal of points.
pub fn diagonal(points: impl Iterator<Item = Vec3>) -> f32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.x > hi.x { 0.0 } else { (hi - lo).length() }
}
