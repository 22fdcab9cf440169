//! Billboards that need no bake: a quad that its own triangles, projected onto its plane, tile
//! exactly under one material and one affine texture mapping shows what a bake of them would
//! (a single leaf card, typically), so it can keep their texture coordinates on the input's own
//! texture instead of a baked copy in the atlas (the hybrid billboard cloud: only planes that
//! merge several cards are baked). The copy is exact at every size: no
//! resampling, no atlas texels, no bake time. A card within ε of a plane it does not lie on is
//! projected onto it, as the bake would project it.

use glam::{Vec2, Vec3};

use crate::quad::Quad;
use crate::soup::TriangleSoup;

/// How a quad shows its source texture: the material, and each corner (in [`Quad::corners`]
/// order) as barycentric weights of the corners of one member triangle, so any per-vertex
/// attribute of that triangle (every texture coordinate set) extends affinely to the quad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SourceCopy {
    /// The members' material (index into the caller's material list).
    pub material: u32,
    /// The member triangle (index into the soup) the weights refer to.
    pub triangle: usize,
    /// Per quad corner: weights of the triangle's three corners (they sum to 1; outside the
    /// triangle some are negative).
    pub weights: [[f32; 3]; 4],
    /// The quad's front faces the same way as the triangle's (counter-clockwise corners seen
    /// from the triangle's front); false when a copy must be wound the other way to keep the
    /// source's facing (single-sided materials).
    pub same_facing: bool,
}

/// Relative tolerance (of the quad's diagonal for lengths, of its area for areas, of the UV
/// extent for texture coordinates) within which `members` count as tiling the quad: a card
/// posed by a skin and averaged over the loop in f32 (the cloud's reference pose) strays from
/// its plane by a small fraction of this; a mapping that is not affine, or a triangle that
/// leaves part of its quad bare, misses by far more.
const TOLERANCE: f32 = 1e-3;

/// Float noise of positions relative to their distance from the origin (f32 has 24 bits; the
/// reference pose adds a few matrix products): lengths are compared within this too.
const POSITION_NOISE: f32 = 1e-5;

/// The exact source copy of `quad` when its `members` (soup indices), projected onto its plane,
/// tile it: one material, every quad corner a member vertex, member areas summing to the
/// quad's area, and one affine map from the plane to the UVs. None otherwise.
pub fn source_copy(soup: &TriangleSoup, quad: &Quad, members: &[usize]) -> Option<SourceCopy> {
    let &first = members.first()?;
    let material = *soup.material.get(first)?;
    let diagonal = 2.0 * quad.half_size.length();
    let area = quad.area();
    if !(diagonal > 0.0 && area > 0.0 && diagonal.is_finite()) {
        return None;
    }
    let tol = TOLERANCE * diagonal + POSITION_NOISE * quad.center.length();
    // Members in plane coordinates (origin at the quad's centre).
    let to_plane = |p: Vec3| {
        let d = p - quad.center;
        Vec2::new(d.dot(quad.axis_u), d.dot(quad.axis_v))
    };
    let tri_area = |[a, b, c]: [Vec2; 3]| 0.5 * (b - a).perp_dot(c - a).abs();
    // The members' area first, without keeping them: most billboards hold many leaves and
    // fail this test, and are not gathered.
    let mut member_area = 0.0f32;
    for &t in members {
        if soup.material.get(t) != Some(&material) {
            return None;
        }
        let corners = soup.positions.get(t)?;
        if corners.iter().any(|p| !p.is_finite()) {
            return None;
        }
        member_area += tri_area(corners.map(to_plane));
    }
    if (member_area - area).abs() > TOLERANCE * area * members.len() as f32 {
        return None;
    }
    let flat: Vec<[Vec2; 3]> = members
        .iter()
        .map(|&t| soup.positions[t].map(to_plane))
        .collect();
    let quad_corners = quad.corners().map(to_plane);
    let on_member = |c: Vec2| flat.iter().any(|t| t.iter().any(|p| p.distance(c) <= tol));
    if !quad_corners.iter().all(|c| on_member(*c)) {
        return None;
    }
    // The reference triangle: the member with the largest projected area (best conditioned).
    let k = (0..flat.len()).max_by(|&a, &b| tri_area(flat[a]).total_cmp(&tri_area(flat[b])))?;
    let triangle = members[k];
    let [a, b, c] = flat[k];
    let det = (b - a).perp_dot(c - a);
    if det.abs() <= f32::EPSILON * diagonal * diagonal {
        return None;
    }
    let weights_of = |p: Vec2| {
        let wb = (p - a).perp_dot(c - a) / det;
        let wc = (b - a).perp_dot(p - a) / det;
        [1.0 - wb - wc, wb, wc]
    };
    let uv = soup.uvs.get(triangle)?;
    let uv_at = |w: [f32; 3]| uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
    let (lo, hi) = uv
        .iter()
        .fold((uv[0], uv[0]), |(lo, hi), u| (lo.min(*u), hi.max(*u)));
    let uv_tol = TOLERANCE * (hi - lo).max_element().max(f32::EPSILON);
    // One affine map: every member vertex's UV is the reference triangle's map at it.
    for (&t, corners) in members.iter().zip(&flat) {
        for (p, u) in corners.iter().zip(&soup.uvs[t]) {
            if uv_at(weights_of(*p)).distance(*u) > uv_tol {
                return None;
            }
        }
    }
    Some(SourceCopy {
        material,
        triangle,
        weights: quad_corners.map(weights_of),
        // Quad corners run counter-clockwise about the plane normal; the triangle's about its
        // own normal.
        same_facing: soup.normal(triangle).dot(quad.plane.normal) >= 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::fit_quad;
    use crate::plane::Plane;

    /// A card of two triangles in the plane z = 1, its UVs a sub-rectangle of the texture.
    fn card() -> TriangleSoup {
        let p = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(2.0, 1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ];
        let uv = [
            Vec2::new(0.25, 0.5),
            Vec2::new(0.75, 0.5),
            Vec2::new(0.75, 0.0),
            Vec2::new(0.25, 0.0),
        ];
        TriangleSoup {
            positions: vec![[p[0], p[1], p[2]], [p[0], p[2], p[3]]],
            uvs: vec![[uv[0], uv[1], uv[2]], [uv[0], uv[2], uv[3]]],
            material: vec![3, 3],
        }
    }

    fn plane() -> Plane {
        Plane {
            normal: Vec3::Z,
            offset: 1.0,
        }
    }

    #[test]
    fn a_card_is_copied_with_its_own_uvs() {
        let soup = card();
        let quad = fit_quad(&soup, &plane(), &[0, 1]);
        let copy = source_copy(&soup, &quad, &[0, 1]).expect("a card tiles its quad");
        assert_eq!(copy.material, 3);
        assert!(copy.same_facing);
        let uv = soup.uvs[copy.triangle];
        // Each quad corner gets the UV of the card corner it lies on.
        for (corner, w) in quad.corners().iter().zip(copy.weights) {
            let got = uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
            let k = soup.positions[0]
                .iter()
                .chain(&soup.positions[1])
                .position(|p| p.distance(*corner) < 1e-5)
                .expect("corner on the card");
            let want = [soup.uvs[0], soup.uvs[1]].concat()[k];
            assert!(got.distance(want) < 1e-5, "{got} vs {want}");
        }
    }

    #[test]
    fn half_a_card_or_two_textures_or_a_bent_mapping_is_baked() {
        let soup = card();
        let quad = fit_quad(&soup, &plane(), &[0, 1]);
        // One triangle covers half its quad.
        let half = fit_quad(&soup, &plane(), &[0]);
        assert!(source_copy(&soup, &half, &[0]).is_none());
        // Two materials.
        let mut two = soup.clone();
        two.material[1] = 4;
        assert!(source_copy(&two, &quad, &[0, 1]).is_none());
        // A UV layout that is not one affine map (the second triangle mirrored).
        let mut bent = soup.clone();
        bent.uvs[1][2] = Vec2::new(0.9, 0.9);
        assert!(source_copy(&bent, &quad, &[0, 1]).is_none());
    }

    #[test]
    fn a_card_off_its_plane_is_copied_as_projected() {
        // One corner lifted off the plane (a card within ε of it): projected, it still tiles
        // the quad, with the same UVs at the corners.
        let mut lifted = card();
        lifted.positions[1][2].z += 0.1;
        let quad = fit_quad(&card(), &plane(), &[0, 1]);
        let copy = source_copy(&lifted, &quad, &[0, 1]).expect("projected, a card");
        let exact = source_copy(&card(), &quad, &[0, 1]).expect("a card");
        let uv = |s: &TriangleSoup, c: &SourceCopy| {
            let t = s.uvs[c.triangle];
            c.weights.map(|w| t[0] * w[0] + t[1] * w[1] + t[2] * w[2])
        };
        for (a, b) in uv(&lifted, &copy).iter().zip(uv(&card(), &exact)) {
            assert!(a.distance(b) < 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn a_card_facing_away_from_its_quad_says_so() {
        let mut soup = card();
        for t in &mut soup.positions {
            t.swap(1, 2);
        }
        for t in &mut soup.uvs {
            t.swap(1, 2);
        }
        let quad = fit_quad(&soup, &plane(), &[0, 1]);
        let copy = source_copy(&soup, &quad, &[0, 1]).expect("still a card");
        assert!(!copy.same_facing);
    }
}
