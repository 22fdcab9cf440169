//! Per-triangle distance and orientation metrics of spec animated-billboard-clouds §5.2–5.3:
//! how far an original foliage triangle is from the billboard that replaces it, how far its
//! image on that billboard drifts from where the triangle really is, and how differently the
//! two are oriented, over one loop.
//!
//! Decisions the thesis leaves open (\[ENG\]):
//! - A triangle stands for its centroid: `D_plane` is the centroid's distance to the
//!   billboard's plane.
//! - The triangle's *simplified position* is a fixed point of the billboard (it moves with it):
//!   the mean, over the loop, of the billboard-local coordinates of the centroid's projection —
//!   the point that minimises the summed squared drift. `D_projected` is the distance from the
//!   centroid's projection to that point at each sample. A constant offset inside the plane is
//!   thus no error (the texture shows the leaf where it is); only drift is.
//! - The simplified triangle's direction `d_s` is fixed the same way (mean billboard-local
//!   direction of centroid → vertex 0, projected into the plane); its normal is the billboard's,
//!   signed to face the triangle on average (billboards are double-sided).

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Mean and maximum over the loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeanMax {
    /// Mean over the samples.
    pub mean: f32,
    /// Largest value over the samples.
    pub max: f32,
}

impl MeanMax {
    fn of(values: &[f32]) -> MeanMax {
        if values.is_empty() {
            return MeanMax::default();
        }
        MeanMax {
            mean: values.iter().sum::<f32>() / values.len() as f32,
            max: values.iter().fold(0.0f32, |m, v| m.max(*v)),
        }
    }
}

/// One triangle's metrics over the loop (distances in world units).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriangleMetrics {
    /// Centroid to billboard plane.
    pub plane_distance: MeanMax,
    /// Centroid's projection to its fixed point on the billboard.
    pub projected_distance: MeanMax,
    /// `sqrt(D_plane² + D_projected²)` per sample.
    pub euclidean_distance: MeanMax,
    /// `1 − (n·n_s + 1)(d·d_s + 1)/4` per sample, in [0, 1].
    pub orientation: MeanMax,
}

/// A billboard's frame at one sample: origin (corner 0), unit in-plane axes, unit normal.
fn frame(c: &[Vec3; 4]) -> (Vec3, Vec3, Vec3, Vec3) {
    let u = (c[1] - c[0]).normalize_or_zero();
    let v0 = c[3] - c[0];
    // Re-orthogonalise against u (quads are rectangles; this only absorbs rounding).
    let v = (v0 - u * v0.dot(u)).normalize_or_zero();
    (c[0], u, v, u.cross(v))
}

/// Where a triangle sits on its billboard, in billboard-local coordinates (see the module
/// docs): its fixed point, its fixed direction, and the sign that turns the billboard's normal
/// toward it.
struct Fixed {
    local: (f32, f32),
    dir: (f32, f32),
    sign: f32,
}

fn fixed(triangle: &[[Vec3; 3]], frames: &[(Vec3, Vec3, Vec3, Vec3)]) -> Fixed {
    let centroid = |s: usize| (triangle[s][0] + triangle[s][1] + triangle[s][2]) / 3.0;
    let (mut local, mut dir) = ((0.0f32, 0.0f32), (0.0f32, 0.0f32));
    let mut facing = 0.0f32;
    for (s, (o, u, v, nrm)) in frames.iter().enumerate() {
        let c = centroid(s) - *o;
        local.0 += c.dot(*u);
        local.1 += c.dot(*v);
        let d = (triangle[s][0] - centroid(s)).normalize_or_zero();
        dir.0 += d.dot(*u);
        dir.1 += d.dot(*v);
        let tn = (triangle[s][1] - triangle[s][0])
            .cross(triangle[s][2] - triangle[s][0])
            .normalize_or_zero();
        facing += tn.dot(*nrm);
    }
    let inv = 1.0 / frames.len().max(1) as f32;
    Fixed {
        local: (local.0 * inv, local.1 * inv),
        dir,
        sign: if facing < 0.0 { -1.0 } else { 1.0 },
    }
}

/// The trajectory of a triangle's image on its billboard: its fixed point carried by the
/// billboard, one position per sample (what the animation metrics compare with the triangle's
/// own centroid trajectory).
pub fn image_trajectory(triangle: &[[Vec3; 3]], board: &[[Vec3; 4]]) -> Vec<Vec3> {
    let n = triangle.len().min(board.len());
    let frames: Vec<(Vec3, Vec3, Vec3, Vec3)> = board[..n].iter().map(frame).collect();
    let f = fixed(&triangle[..n], &frames);
    frames
        .iter()
        .map(|(o, u, v, _)| *o + *u * f.local.0 + *v * f.local.1)
        .collect()
}

/// The metrics of one original triangle (`triangle[s]` = its three vertices at sample s) against
/// the billboard that replaces it (`board[s]` = its corners in quad order at sample s), both
/// over the same uniform samples of one loop. Empty input gives zeros.
pub fn triangle_metrics(triangle: &[[Vec3; 3]], board: &[[Vec3; 4]]) -> TriangleMetrics {
    let n = triangle.len().min(board.len());
    if n == 0 {
        return TriangleMetrics::default();
    }
    let frames: Vec<(Vec3, Vec3, Vec3, Vec3)> = board[..n].iter().map(frame).collect();
    let centroid = |s: usize| (triangle[s][0] + triangle[s][1] + triangle[s][2]) / 3.0;
    let Fixed { local, dir, sign } = fixed(triangle, &frames);
    let (mut plane, mut projected, mut euclid, mut orient) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    for (s, (o, u, v, nrm)) in frames.iter().enumerate() {
        let c = centroid(s);
        let rel = c - *o;
        let dp = rel.dot(*nrm).abs();
        let on_plane = *o + *u * rel.dot(*u) + *v * rel.dot(*v);
        let fixed = *o + *u * local.0 + *v * local.1;
        let dq = on_plane.distance(fixed);
        plane.push(dp);
        projected.push(dq);
        euclid.push((dp * dp + dq * dq).sqrt());
        let tn = (triangle[s][1] - triangle[s][0])
            .cross(triangle[s][2] - triangle[s][0])
            .normalize_or_zero();
        let d = (triangle[s][0] - c).normalize_or_zero();
        let ds = (*u * dir.0 + *v * dir.1).normalize_or_zero();
        let ns = *nrm * sign;
        orient.push((1.0 - (tn.dot(ns) + 1.0) * (d.dot(ds) + 1.0) / 4.0).clamp(0.0, 1.0));
    }
    TriangleMetrics {
        plane_distance: MeanMax::of(&plane),
        projected_distance: MeanMax::of(&projected),
        euclidean_distance: MeanMax::of(&euclid),
        orientation: MeanMax::of(&orient),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// A unit billboard in the z = 0 plane, corners in quad order, moved by `f`.
    fn board(f: impl Fn(Vec3) -> Vec3) -> [Vec3; 4] {
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ]
        .map(f)
    }

    fn leaf(f: impl Fn(Vec3) -> Vec3) -> [Vec3; 3] {
        [
            Vec3::new(0.2, 0.3, 0.0),
            Vec3::new(-0.3, -0.1, 0.0),
            Vec3::new(0.4, -0.2, 0.0),
        ]
        .map(f)
    }

    fn sway(s: usize) -> Vec3 {
        let t = std::f32::consts::TAU * s as f32 / 16.0;
        Vec3::new(0.7 * t.sin(), 0.2 * t.cos(), 0.1 * (2.0 * t).sin())
    }

    #[test]
    fn a_leaf_in_its_billboard_moving_with_it_scores_zero() {
        let rot = |s: usize| Quat::from_rotation_y(0.3 * s as f32);
        let tri: Vec<[Vec3; 3]> = (0..16).map(|s| leaf(|p| rot(s) * p + sway(s))).collect();
        let bb: Vec<[Vec3; 4]> = (0..16).map(|s| board(|p| rot(s) * p + sway(s))).collect();
        let m = triangle_metrics(&tri, &bb);
        assert!(m.plane_distance.max < 1e-5, "{m:?}");
        assert!(m.projected_distance.max < 1e-5, "{m:?}");
        assert!(m.orientation.max < 1e-5, "{m:?}");
    }

    #[test]
    fn the_image_of_a_leaf_riding_its_billboard_follows_the_leaf() {
        let rot = |s: usize| Quat::from_rotation_x(0.2 * s as f32);
        let tri: Vec<[Vec3; 3]> = (0..16).map(|s| leaf(|p| rot(s) * p + sway(s))).collect();
        let bb: Vec<[Vec3; 4]> = (0..16)
            .map(|s| board(|p| rot(s) * (p - Vec3::Z * 0.1) + sway(s)))
            .collect();
        let image = image_trajectory(&tri, &bb);
        assert_eq!(image.len(), 16);
        for (s, p) in image.iter().enumerate() {
            let c = (tri[s][0] + tri[s][1] + tri[s][2]) / 3.0;
            // The image is the centroid pushed onto the billboard 0.1 behind it.
            assert!((p.distance(c) - 0.1).abs() < 1e-5, "sample {s}");
        }
        // A leaf in its billboard's plane: the image is the centroid, and the animation
        // metrics see nothing.
        let flush: Vec<[Vec3; 4]> = (0..16).map(|s| board(|p| rot(s) * p + sway(s))).collect();
        let image = image_trajectory(&tri, &flush);
        let centres: Vec<Vec3> = tri.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        for (a, b) in image.iter().zip(&centres) {
            assert!(a.distance(*b) < 1e-5);
        }
        let m = crate::dominating_axis::axis_metrics(&centres, &image, 4);
        assert!(
            m.dominating_axis < 1e-3 && m.dominating_axis_spectral < 1e-3,
            "{m:?}"
        );
    }

    #[test]
    fn offsets_along_the_normal_and_in_plane_drift_are_measured() {
        // The billboard sits 0.25 behind the leaf: plane distance 0.25, no drift.
        let tri: Vec<[Vec3; 3]> = (0..16).map(|s| leaf(|p| p + sway(s))).collect();
        let bb: Vec<[Vec3; 4]> = (0..16)
            .map(|s| board(|p| p + sway(s) - Vec3::Z * 0.25))
            .collect();
        let m = triangle_metrics(&tri, &bb);
        assert!(
            (m.plane_distance.mean - 0.25).abs() < 1e-5
                && (m.plane_distance.max - 0.25).abs() < 1e-5
        );
        assert!(m.projected_distance.max < 1e-5);
        assert!((m.euclidean_distance.mean - 0.25).abs() < 1e-5);
        // The billboard slides ±0.4 along x half the loop each: the leaf's image drifts 0.4
        // from its fixed point at every sample.
        let bb: Vec<[Vec3; 4]> = (0..16)
            .map(|s| {
                let dx = if s < 8 { 0.4 } else { -0.4 };
                board(|p| p + sway(s) + Vec3::X * dx)
            })
            .collect();
        let m = triangle_metrics(&tri, &bb);
        assert!((m.projected_distance.mean - 0.4).abs() < 1e-4, "{m:?}");
        assert!((m.projected_distance.max - 0.4).abs() < 1e-4);
        assert!(m.plane_distance.max < 1e-5);
    }

    #[test]
    fn tilted_leaf_orientation_has_the_closed_form() {
        let theta = 0.6f32;
        // Tilt about the axis along d (centroid → vertex 0): d stays in the plane,
        // orientation = 1 − (cos θ + 1)·2/4 = (1 − cos θ)/2.
        let c = (Vec3::new(0.2, 0.3, 0.0) + Vec3::new(-0.3, -0.1, 0.0) + Vec3::new(0.4, -0.2, 0.0))
            / 3.0;
        let d = (Vec3::new(0.2, 0.3, 0.0) - c).normalize();
        let along = Quat::from_axis_angle(d, theta);
        let tri: Vec<[Vec3; 3]> = (0..8).map(|_| leaf(|p| c + along * (p - c))).collect();
        let bb: Vec<[Vec3; 4]> = (0..8).map(|_| board(|p| p)).collect();
        let m = triangle_metrics(&tri, &bb);
        let want = (1.0 - theta.cos()) / 2.0;
        assert!(
            (m.orientation.mean - want).abs() < 1e-4,
            "{} vs {want}",
            m.orientation.mean
        );
        // Tilt about the in-plane axis perpendicular to d: n·n_s = cos θ and d·d_s = cos θ,
        // orientation = 1 − (cos θ + 1)²/4.
        let perp = Vec3::Z.cross(d).normalize();
        let across = Quat::from_axis_angle(perp, theta);
        let tri: Vec<[Vec3; 3]> = (0..8).map(|_| leaf(|p| c + across * (p - c))).collect();
        let m = triangle_metrics(&tri, &bb);
        let want = 1.0 - (theta.cos() + 1.0).powi(2) / 4.0;
        assert!(
            (m.orientation.mean - want).abs() < 1e-4,
            "{} vs {want}",
            m.orientation.mean
        );
        // A flipped billboard normal is no error (double-sided).
        let flipped: Vec<[Vec3; 4]> = (0..8)
            .map(|_| {
                let b = board(|p| p);
                [b[1], b[0], b[3], b[2]]
            })
            .collect();
        let tri: Vec<[Vec3; 3]> = (0..8).map(|_| leaf(|p| p)).collect();
        assert!(triangle_metrics(&tri, &flipped).orientation.max < 1e-5);
        assert_eq!(triangle_metrics(&[], &[]), TriangleMetrics::default());
    }
}
