//! Member triangles placed in the supersampled atlas: each quad's members projected
//! orthographically onto it, clipped to its cell, with depth from their range in front of it
//! (animated-billboard-clouds §2.4 steps 3–4, improved-billboard-cloud §4 item 3).

use glam::Vec3;

use crate::bake::baked::Cell;
use crate::quad::Quad;
use crate::soup::TriangleSoup;

/// The quad's front normal, `axis_u × axis_v` (the side its texture shows).
pub(super) fn front_normal(quad: &Quad) -> Vec3 {
    quad.axis_u.cross(quad.axis_v).normalize_or_zero()
}

/// A member triangle placed in the supersampled atlas: x right and y down in supersampled
/// texels, z the wgpu depth (0 = nearest the quad's front), the source uv, the triangle's
/// world-space face normal and its material.
#[derive(Clone, Copy, Debug)]
pub(super) struct PlacedTriangle {
    pub(super) pos: [[f32; 3]; 3],
    pub(super) uv: [[f32; 2]; 3],
    pub(super) normal: [f32; 3],
    pub(super) material: u32,
}

/// A polygon vertex while clipping: quad coordinates s, t (0..1 across the quad), signed
/// distance from the quad's plane, uv.
pub(super) type ClipVertex = [f32; 5];

/// Clips the convex polygon to `s, t ∈ [0, 1]` (Sutherland–Hodgman, orientation kept).
pub(super) fn clip_to_unit_square(poly: &mut Vec<ClipVertex>, scratch: &mut Vec<ClipVertex>) {
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
pub(super) fn quad_triangles(
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
