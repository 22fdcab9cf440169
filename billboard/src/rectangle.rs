//! Minimum-area bounding rectangles of 2-D point sets (spec animated-billboard-clouds §2.4
//! step 2 and §11 item 3; improved-billboard-cloud §4 item 2): a convex hull by Andrew's
//! monotone chain, then rotating calipers over the hull edges.
//!
//! The optimal rectangle has one side collinear with a hull edge (Freeman & Shapira 1975), so
//! trying every hull edge direction is exact. The calipers track the three other extreme
//! points while the edge advances, which makes the search O(h) after the O(n log n) hull.
//! Geometry is evaluated in `f64` relative to the first hull point, and the winning edge's
//! extents are recomputed over the whole hull, so every input point lies in the result up
//! to `f32` rounding.

use glam::{DVec2, Vec2};

/// An oriented rectangle in the plane: the output of [`min_area_rect`], the 2-D footprint of
/// one billboard quad (spec animated-billboard-clouds §2.4 step 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect2 {
    /// Centre of the rectangle.
    pub center: Vec2,
    /// Unit direction of the rectangle's first side (the hull edge it is flush with).
    pub axis: Vec2,
    /// Half extents along `axis` and along [`Rect2::perp`] = `(-axis.y, axis.x)`; either may
    /// be zero for degenerate inputs (one point, collinear points).
    pub half_size: Vec2,
}

impl Rect2 {
    /// The unit second side direction, `axis` turned 90° counter-clockwise.
    pub fn perp(&self) -> Vec2 {
        self.axis.perp()
    }

    /// Area (`4 · half_size.x · half_size.y`), the cost the calipers minimise.
    pub fn area(&self) -> f32 {
        4.0 * self.half_size.x * self.half_size.y
    }

    /// Corners counter-clockwise: (−a,−p), (+a,−p), (+a,+p), (−a,+p) in the rectangle's own
    /// frame (a = `axis`, p = [`Rect2::perp`]), as needed to build a quad.
    pub fn corners(&self) -> [Vec2; 4] {
        let a = self.axis * self.half_size.x;
        let p = self.perp() * self.half_size.y;
        [
            self.center - a - p,
            self.center + a - p,
            self.center + a + p,
            self.center - a + p,
        ]
    }

    /// Coordinates of `p` in the rectangle's frame: (along `axis`, along `perp`) from the
    /// centre; `p` is inside when both magnitudes are within `half_size`.
    pub fn to_local(&self, p: Vec2) -> Vec2 {
        let d = p - self.center;
        Vec2::new(d.dot(self.axis), d.dot(self.perp()))
    }

    /// Whether `p` lies inside the rectangle grown by `tolerance` on every side.
    pub fn contains(&self, p: Vec2, tolerance: f32) -> bool {
        let l = self.to_local(p).abs();
        l.x <= self.half_size.x + tolerance && l.y <= self.half_size.y + tolerance
    }
}

/// Convex hull of `points`, counter-clockwise, starting at the lowest-x (then lowest-y) point,
/// without duplicate or collinear vertices (Andrew's monotone chain; spec
/// animated-billboard-clouds §11 item 3).
///
/// Non-finite points are ignored. One distinct point gives a one-point hull, collinear points
/// give their two extreme points, and no finite point gives an empty hull.
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    // Adding 0.0 turns -0.0 into 0.0, so `total_cmp` sorts equal points next to each other.
    let mut pts: Vec<Vec2> = points
        .iter()
        .filter(|p| p.is_finite())
        .map(|p| *p + Vec2::ZERO)
        .collect();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }

    // Pops while the last turn is not strictly counter-clockwise, dropping collinear points.
    fn push(chain: &mut Vec<Vec2>, p: Vec2, floor: usize) {
        while chain.len() >= floor + 2 {
            let (a, b) = (chain[chain.len() - 2], chain[chain.len() - 1]);
            if cross(a.as_dvec2(), b.as_dvec2(), p.as_dvec2()) > 0.0 {
                break;
            }
            chain.pop();
        }
        chain.push(p);
    }

    let mut hull: Vec<Vec2> = Vec::with_capacity(pts.len() + 1);
    for &p in &pts {
        push(&mut hull, p, 0);
    }
    let lower_len = hull.len();
    for &p in pts.iter().rev().skip(1) {
        push(&mut hull, p, lower_len - 1);
    }
    // The upper chain ends where the lower one started.
    hull.pop();
    hull
}

/// Minimum-area rectangle enclosing every finite point of `points`, by rotating calipers over
/// the convex hull's edges (spec animated-billboard-clouds §2.4 step 2, improved-billboard-cloud
/// §4 item 2).
///
/// Returns `None` when there is no finite point. One point gives a zero-size rectangle with
/// `axis = +X`; collinear points give a zero-width rectangle along their line. Ties between
/// equally small rectangles go to the first hull edge in [`convex_hull`] order, so the result
/// is deterministic.
pub fn min_area_rect(points: &[Vec2]) -> Option<Rect2> {
    let hull = convex_hull(points);
    let origin = hull.first()?.as_dvec2();
    // Relative coordinates keep the f64 products small and precise.
    let q: Vec<DVec2> = hull.iter().map(|p| p.as_dvec2() - origin).collect();
    match q.len() {
        1 => Some(Rect2 {
            center: hull[0],
            axis: Vec2::X,
            half_size: Vec2::ZERO,
        }),
        // Collinear input: the segment between the extremes, with an exactly zero width.
        2 => {
            let length = q[1].length();
            Some(Rect2 {
                center: (origin + q[1] * 0.5).as_vec2(),
                axis: (q[1] / length).as_vec2(),
                half_size: Vec2::new((length * 0.5) as f32, 0.0),
            })
        }
        _ => Some(enclosing_rect(&q, best_edge_direction(&q), origin)),
    }
}

/// Twice the signed area of triangle (a, b, c): positive for a counter-clockwise turn.
fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// The unit direction of the hull edge whose flush rectangle has the least area.
///
/// `q` is a strictly convex counter-clockwise polygon with at least three vertices. Indices
/// grow without wrapping (taken modulo `h` on access) so each caliper only moves forward.
fn best_edge_direction(q: &[DVec2]) -> DVec2 {
    let h = q.len();
    let at = |i: usize| q[i % h];
    let (mut right, mut top, mut left) = (1usize, 1usize, 1usize);
    let mut best: Option<(f64, DVec2)> = None;
    for i in 0..h {
        let Some(u) = (at(i + 1) - at(i)).try_normalize() else {
            continue;
        };
        let v = u.perp();
        // The extreme along +u, +v and -u; each walk is bounded by one full turn.
        right = right.max(i + 1);
        while right < i + 1 + h && (at(right + 1) - at(right)).dot(u) > 0.0 {
            right += 1;
        }
        top = top.max(right);
        while top < right + h && (at(top + 1) - at(top)).dot(v) > 0.0 {
            top += 1;
        }
        left = left.max(top);
        while left < top + h && (at(left + 1) - at(left)).dot(u) < 0.0 {
            left += 1;
        }
        let width = (at(right) - at(left)).dot(u);
        let height = (at(top) - at(i)).dot(v);
        let area = width * height;
        if best.is_none_or(|(a, _)| area < a) {
            best = Some((area, u));
        }
    }
    best.map_or(DVec2::X, |(_, u)| u)
}

/// The rectangle with first side along unit `u` that encloses all of `q` (shifted by
/// `origin`), from a full scan so rounding in the calipers cannot leave a point outside.
fn enclosing_rect(q: &[DVec2], u: DVec2, origin: DVec2) -> Rect2 {
    let v = u.perp();
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for p in q {
        let l = DVec2::new(p.dot(u), p.dot(v));
        lo = lo.min(l);
        hi = hi.max(l);
    }
    let mid = (lo + hi) * 0.5;
    Rect2 {
        center: (origin + u * mid.x + v * mid.y).as_vec2(),
        axis: u.as_vec2(),
        half_size: ((hi - lo) * 0.5).as_vec2(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Exhaustive O(h²) reference: every hull edge direction, full extents each time.
    fn brute_force_area(points: &[Vec2]) -> f64 {
        let hull = convex_hull(points);
        let q: Vec<DVec2> = hull.iter().map(|p| p.as_dvec2()).collect();
        let mut best = f64::INFINITY;
        for i in 0..q.len() {
            let Some(u) = (q[(i + 1) % q.len()] - q[i]).try_normalize() else {
                continue;
            };
            let v = u.perp();
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for p in &q {
                let l = DVec2::new(p.dot(u), p.dot(v));
                lo = lo.min(l);
                hi = hi.max(l);
            }
            best = best.min((hi.x - lo.x) * (hi.y - lo.y));
        }
        best
    }

    fn rect(points: &[Vec2]) -> Rect2 {
        min_area_rect(points).unwrap_or_else(|| panic!("no rectangle for {points:?}"))
    }

    fn assert_contains_all(r: &Rect2, points: &[Vec2], tol: f32) {
        for p in points {
            assert!(
                r.contains(*p, tol),
                "{p} outside {r:?} (local {})",
                r.to_local(*p)
            );
        }
    }

    /// Twice the signed area of a polygon (positive when counter-clockwise).
    fn signed_area2(poly: &[Vec2]) -> f64 {
        (0..poly.len())
            .map(|i| {
                let (a, b) = (poly[i].as_dvec2(), poly[(i + 1) % poly.len()].as_dvec2());
                a.perp_dot(b)
            })
            .sum()
    }

    #[test]
    fn hull_of_square_with_interior_duplicate_and_collinear_points() {
        let mut pts = vec![
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(1.0, 0.0), // on an edge
            Vec2::new(2.0, 1.0), // on an edge
            Vec2::new(0.0, 0.0), // duplicate
            Vec2::new(2.0, 2.0), // duplicate
            Vec2::new(0.5, 1.5),
        ];
        pts.push(Vec2::new(f32::NAN, 0.0));
        pts.push(Vec2::new(f32::INFINITY, 1.0));
        let hull = convex_hull(&pts);
        assert_eq!(
            hull,
            vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(2.0, 0.0),
                Vec2::new(2.0, 2.0),
                Vec2::new(0.0, 2.0)
            ]
        );
    }

    #[test]
    fn hull_degenerate_inputs() {
        assert!(convex_hull(&[]).is_empty());
        assert!(convex_hull(&[Vec2::NAN]).is_empty());
        let p = Vec2::new(3.0, -1.0);
        assert_eq!(convex_hull(&[p, p, p]), vec![p]);
        let line: Vec<Vec2> = (0..10)
            .map(|i| Vec2::new(i as f32, 2.0 * i as f32))
            .rev()
            .collect();
        assert_eq!(convex_hull(&line), vec![Vec2::ZERO, Vec2::new(9.0, 18.0)]);
        // -0.0 and 0.0 are the same point.
        assert_eq!(
            convex_hull(&[Vec2::new(-0.0, 0.0), Vec2::new(0.0, -0.0)]).len(),
            1
        );
    }

    #[test]
    fn hull_is_strictly_convex_ccw_and_contains_random_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..50 {
            let n = rng.random_range(3..300);
            // Coarse grid coordinates produce many duplicates and collinear triples.
            let pts: Vec<Vec2> = (0..n)
                .map(|_| {
                    Vec2::new(
                        rng.random_range(0..12) as f32,
                        rng.random_range(0..9) as f32,
                    )
                })
                .collect();
            let hull = convex_hull(&pts);
            let h = hull.len();
            if h < 3 {
                continue;
            }
            for i in 0..h {
                let (a, b, c) = (hull[i], hull[(i + 1) % h], hull[(i + 2) % h]);
                assert!(
                    cross(a.as_dvec2(), b.as_dvec2(), c.as_dvec2()) > 0.0,
                    "not strictly convex: {hull:?}"
                );
            }
            for p in &pts {
                for i in 0..h {
                    let (a, b) = (hull[i].as_dvec2(), hull[(i + 1) % h].as_dvec2());
                    assert!(
                        cross(a, b, p.as_dvec2()) >= 0.0,
                        "{p} outside hull {hull:?}"
                    );
                }
            }
            assert!(signed_area2(&hull) > 0.0);
        }
    }

    #[test]
    fn axis_aligned_square_is_exact() {
        let mut pts = Vec::new();
        for i in 0..=4 {
            for j in 0..=4 {
                pts.push(Vec2::new(i as f32 * 0.5 - 1.0, j as f32 * 0.5 + 3.0));
            }
        }
        let r = rect(&pts);
        assert_eq!(r.area(), 4.0);
        assert_eq!(r.center, Vec2::new(0.0, 4.0));
        assert_eq!(r.axis, Vec2::X);
        assert_eq!(r.half_size, Vec2::ONE);
    }

    #[test]
    fn rotated_rectangle_is_recovered() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for k in 0..24 {
            let angle = k as f32 * 0.261_799_4 + 0.05; // about 15° steps, never axis-aligned
            let (axis, perp) = (Vec2::from_angle(angle), Vec2::from_angle(angle).perp());
            let (center, half) = (Vec2::new(5.0, -2.0), Vec2::new(3.0, 1.25));
            let mut pts: Vec<Vec2> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|&(a, b)| center + axis * half.x * a + perp * half.y * b)
                .collect();
            for _ in 0..40 {
                let (a, b) = (
                    rng.random_range(-1.0f32..1.0),
                    rng.random_range(-1.0f32..1.0),
                );
                pts.push(center + axis * half.x * a + perp * half.y * b);
            }
            let r = rect(&pts);
            assert!(
                (r.area() - 15.0).abs() < 1e-4,
                "angle {angle}: area {}",
                r.area()
            );
            assert!(r.center.abs_diff_eq(center, 1e-4), "angle {angle}: {r:?}");
            // Up to sign and swap, the sides match.
            let (long, long_axis) = if r.half_size.x >= r.half_size.y {
                (r.half_size, r.axis)
            } else {
                (Vec2::new(r.half_size.y, r.half_size.x), r.perp())
            };
            assert!(long.abs_diff_eq(half, 1e-4), "angle {angle}: {r:?}");
            assert!(
                long_axis.dot(axis).abs() > 1.0 - 1e-6,
                "angle {angle}: {r:?}"
            );
            assert!((r.axis.length() - 1.0).abs() < 1e-6);
            assert_contains_all(&r, &pts, 1e-4);
        }
    }

    #[test]
    fn right_triangle_gives_twice_its_area() {
        // Legs 3 and 4 along the axes: flush with a leg the rectangle is 3·4 = 12, flush with
        // the hypotenuse 5 · 12/5 = 12; either way twice the triangle's area.
        let pts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 0.0),
            Vec2::new(0.0, 4.0),
        ];
        let r = rect(&pts);
        assert!((r.area() - 12.0).abs() < 1e-5, "{r:?}");
        assert_contains_all(&r, &pts, 1e-5);
    }

    #[test]
    fn obtuse_triangle_uses_longest_side() {
        // Base (0,0)-(10,0), apex (2,1): the rectangle on the base has area 10·1 = 10; flush
        // with the other sides it is 80/√65 · 10/√65 ≈ 12.3 and 20/√5 · 10/√5 = 40.
        let pts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(10.0, 0.0),
            Vec2::new(2.0, 1.0),
        ];
        let r = rect(&pts);
        assert!((r.area() - 10.0).abs() < 1e-5, "{r:?}");
        assert_eq!(r.axis, Vec2::X);
        assert!(r.center.abs_diff_eq(Vec2::new(5.0, 0.5), 1e-6));
    }

    #[test]
    fn regular_octagon_has_known_area() {
        // A regular octagon of circumradius 1: its minimum rectangle is the square on two
        // opposite sides, side = 2·cos(22.5°), area 4·cos²(22.5°) = 2 + √2.
        let pts: Vec<Vec2> = (0..8)
            .map(|i| Vec2::from_angle(std::f32::consts::FRAC_PI_4 * i as f32 + 0.3))
            .collect();
        let r = rect(&pts);
        assert!(
            (r.area() - (2.0 + std::f32::consts::SQRT_2)).abs() < 1e-5,
            "{r:?}"
        );
        assert_contains_all(&r, &pts, 1e-5);
    }

    #[test]
    fn random_clouds_match_brute_force_and_contain_all_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(2024);
        for round in 0..200 {
            let n = rng.random_range(1..400);
            let offset = Vec2::new(
                rng.random_range(-10.0f32..10.0),
                rng.random_range(-10.0f32..10.0),
            );
            let stretch = Vec2::new(
                rng.random_range(0.1f32..10.0),
                rng.random_range(0.1f32..10.0),
            );
            let turn = Vec2::from_angle(rng.random_range(0.0f32..6.3));
            let pts: Vec<Vec2> = (0..n)
                .map(|_| {
                    let p = Vec2::new(
                        rng.random_range(-1.0f32..1.0),
                        rng.random_range(-1.0f32..1.0),
                    );
                    offset + turn.rotate(p * stretch)
                })
                .collect();
            let r = rect(&pts);
            assert_contains_all(&r, &pts, 1e-4);
            let (min, max) = pts
                .iter()
                .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
            let aabb = f64::from((max - min).x) * f64::from((max - min).y);
            let area = f64::from(r.area());
            assert!(
                area <= aabb * (1.0 + 1e-5) + 1e-6,
                "round {round}: area {area} > aabb {aabb}"
            );
            let reference = brute_force_area(&pts);
            assert!(
                (area - reference).abs() <= 1e-4 * reference.max(1.0),
                "round {round}: calipers {area} vs brute force {reference}"
            );
        }
    }

    #[test]
    fn far_from_origin_keeps_its_area() {
        // The same cloud near the origin and 10⁴ units away: f64 maths relative to the first
        // hull point keeps the area; containment holds to f32 rounding at that magnitude.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let pts: Vec<Vec2> = (0..200)
            .map(|_| {
                Vec2::new(
                    rng.random_range(-3.0f32..3.0),
                    rng.random_range(-1.0f32..1.0),
                )
            })
            .collect();
        let far_offset = Vec2::new(1.0e4, -2.5e4);
        let far: Vec<Vec2> = pts.iter().map(|p| *p + far_offset).collect();
        let (near_r, far_r) = (rect(&pts), rect(&far));
        assert!(
            (near_r.area() - far_r.area()).abs() < 1e-2 * near_r.area(),
            "{near_r:?} vs {far_r:?}"
        );
        assert_contains_all(&far_r, &far, 1e-2);
    }

    #[test]
    fn degenerate_inputs_give_zero_width() {
        assert_eq!(min_area_rect(&[]), None);
        assert_eq!(
            min_area_rect(&[Vec2::NAN, Vec2::new(1.0, f32::NEG_INFINITY)]),
            None
        );

        let p = Vec2::new(2.0, 7.0);
        let r = rect(&[p, p]);
        assert_eq!(
            r,
            Rect2 {
                center: p,
                axis: Vec2::X,
                half_size: Vec2::ZERO
            }
        );

        let line: Vec<Vec2> = (0..7)
            .map(|i| Vec2::new(1.0 + 3.0 * i as f32, 2.0 + 4.0 * i as f32))
            .collect();
        let r = rect(&line);
        assert_eq!(r.area(), 0.0);
        assert!(
            (r.half_size.x - 15.0).abs() < 1e-5 && r.half_size.y == 0.0,
            "{r:?}"
        );
        assert!(r.axis.abs_diff_eq(Vec2::new(0.6, 0.8), 1e-6));
        assert!(r.center.abs_diff_eq(Vec2::new(10.0, 14.0), 1e-5));
        assert_contains_all(&r, &line, 1e-5);

        // A NaN among good points is ignored, not propagated.
        let r = rect(&[
            Vec2::ZERO,
            Vec2::new(f32::NAN, 1.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(0.0, 1.0),
        ]);
        assert!((r.area() - 2.0).abs() < 1e-6 && r.center.is_finite());
    }

    #[test]
    fn corners_are_counter_clockwise_and_enclose() {
        let pts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(4.0, 1.0),
            Vec2::new(3.0, 3.0),
            Vec2::new(-1.0, 2.0),
        ];
        let r = rect(&pts);
        let c = r.corners();
        assert!(signed_area2(&c) > 0.0);
        assert!((signed_area2(&c) as f32 * 0.5 - r.area()).abs() < 1e-4);
        assert_contains_all(&r, &pts, 1e-5);
        for corner in c {
            assert!(r.contains(corner, 1e-5));
        }
    }

    #[test]
    fn deterministic() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pts: Vec<Vec2> = (0..500)
            .map(|_| {
                Vec2::new(
                    rng.random_range(-5.0f32..5.0),
                    rng.random_range(-2.0f32..2.0),
                )
            })
            .collect();
        let mut reversed = pts.clone();
        reversed.reverse();
        assert_eq!(min_area_rect(&pts), min_area_rect(&pts));
        // The hull sorts its input, so the order of the points does not matter.
        assert_eq!(min_area_rect(&pts), min_area_rect(&reversed));
    }
}
