//! Distances from points to a triangle surface.
//!
//! The closest-point arithmetic runs in f64: in f32 it loses ~1e-4 on the slivers a tree's branch
//! tips are full of (a triangle's own centroid measured off it), which is more than the error
//! budgets the distances are checked against. Inputs and results stay f32, like the meshes.
//!
//! [`triangle_distance`] measures one triangle; [`SurfaceBvh`] answers nearest-surface distance
//! queries over many, exactly (it prunes by bounding boxes, it never approximates).

use glam::{DVec3, Vec3};

/// Distance from `p` to the triangle `t` (its interior, edges and vertices), computed in f64.
/// A degenerate triangle (a segment or a point) measures as that segment or point.
pub fn triangle_distance(p: Vec3, t: &[Vec3; 3]) -> f32 {
    let p = p.as_dvec3();
    p.distance(closest_on_triangle(
        p,
        t[0].as_dvec3(),
        t[1].as_dvec3(),
        t[2].as_dvec3(),
    )) as f32
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection §5.1.5): the
/// Voronoi regions of the vertices, then of the edges, then the interior's barycentric projection.
pub fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// A bounding-volume hierarchy over a triangle soup, for exact point-to-surface distances.
///
/// Built once with [`SurfaceBvh::new`] (median splits on the widest centroid axis, up to four
/// triangles a leaf), then queried with [`SurfaceBvh::distance`], which equals the minimum of
/// [`triangle_distance`] over all triangles. Immutable and `Sync`: queries may run in parallel.
pub struct SurfaceBvh {
    triangles: Vec<[Vec3; 3]>,
    /// Index in the input of each triangle, in the hierarchy's order.
    ids: Vec<u32>,
    nodes: Vec<Node>,
}

struct Node {
    lo: Vec3,
    hi: Vec3,
    first: usize,
    /// Triangles of a leaf; 0 for an inner node, whose left child is the next node.
    count: usize,
    right: usize,
}

/// Most triangles a leaf holds.
const LEAF: usize = 4;

impl SurfaceBvh {
    /// The hierarchy over `triangles` (reordered, kept). No triangle makes an empty surface.
    pub fn new(triangles: Vec<[Vec3; 3]>) -> SurfaceBvh {
        let mut items: Vec<([Vec3; 3], u32)> = triangles
            .into_iter()
            .enumerate()
            .map(|(i, t)| (t, i as u32))
            .collect();
        let mut nodes = Vec::with_capacity(items.len() / 2 + 1);
        if !items.is_empty() {
            let n = items.len();
            Self::build(&mut items, 0, n, &mut nodes);
        }
        let (triangles, ids) = items.into_iter().unzip();
        SurfaceBvh {
            triangles,
            ids,
            nodes,
        }
    }

    /// The nearest surface point to `p`: the input index of its triangle, the point and its
    /// distance; None when there is no triangle.
    pub fn nearest(&self, p: Vec3) -> Option<(usize, Vec3, f32)> {
        let mut best: Option<(usize, Vec3, f32)> = None;
        let mut stack = if self.nodes.is_empty() {
            Vec::new()
        } else {
            vec![0usize]
        };
        let pd = p.as_dvec3();
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            let d = (node.lo - p).max(p - node.hi).max(Vec3::ZERO).length();
            if best.is_some_and(|b| d >= b.2) {
                continue;
            }
            if node.count > 0 {
                for k in node.first..node.first + node.count {
                    let [a, b, c] = self.triangles[k];
                    let q = closest_on_triangle(pd, a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
                    let dist = pd.distance(q) as f32;
                    let id = self.ids[k] as usize;
                    // Ties go to the lower input index, so the answer is deterministic.
                    if best.is_none_or(|b| dist < b.2 || (dist == b.2 && id < b.0)) {
                        best = Some((id, q.as_vec3(), dist));
                    }
                }
            } else {
                stack.push(node.right);
                stack.push(n + 1);
            }
        }
        best
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the surface has no triangle (every distance is then infinite).
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The triangles, in the hierarchy's order (not the order given to [`SurfaceBvh::new`]).
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// Distance from `p` to the nearest triangle; infinity when there is none.
    pub fn distance(&self, p: Vec3) -> f32 {
        self.distance_beyond(p, f32::NEG_INFINITY)
    }

    /// [`SurfaceBvh::distance`] when it is over `floor`; otherwise some distance at most
    /// `floor` (the first triangle found that near ends the search). For a maximum of
    /// distances, or a test against a limit, that is all a query needs: most points lie on or
    /// near the surface, and proving their exact minimum was most of the queries' time.
    pub fn distance_beyond(&self, p: Vec3, floor: f32) -> f32 {
        let mut best = f32::INFINITY;
        if self.nodes.is_empty() {
            return best;
        }
        let box_distance = |n: usize| {
            let node = &self.nodes[n];
            (node.lo - p).max(p - node.hi).max(Vec3::ZERO).length()
        };
        // The nearer child first: the leaves it reaches bound the farther one, which is then
        // mostly pruned (a third of `frond lod`'s time on oak_dense went to these queries when
        // the left child always came first). The minimum does not depend on the order.
        let mut stack: Vec<(usize, f32)> = Vec::with_capacity(64);
        stack.push((0, box_distance(0)));
        while let Some((n, d)) = stack.pop() {
            if d >= best {
                continue;
            }
            let node = &self.nodes[n];
            if node.count > 0 {
                for t in &self.triangles[node.first..node.first + node.count] {
                    best = best.min(triangle_distance(p, t));
                }
                if best <= floor {
                    return best;
                }
            } else {
                let (left, right) = (
                    (n + 1, box_distance(n + 1)),
                    (node.right, box_distance(node.right)),
                );
                let (near, far) = if left.1 <= right.1 {
                    (left, right)
                } else {
                    (right, left)
                };
                stack.push(far);
                stack.push(near);
            }
        }
        best
    }

    /// Builds the node over `tris[first..first + count]` and its subtree; returns its index.
    fn build(
        tris: &mut [([Vec3; 3], u32)],
        first: usize,
        count: usize,
        nodes: &mut Vec<Node>,
    ) -> usize {
        let span = &mut tris[first..first + count];
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        // Centroids times 3: only their order matters.
        let (mut clo, mut chi) = (lo, hi);
        for (t, _) in span.iter() {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            let c = t[0] + t[1] + t[2];
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let me = nodes.len();
        nodes.push(Node {
            lo,
            hi,
            first,
            count,
            right: 0,
        });
        if count <= LEAF {
            return me;
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let key = |t: &([Vec3; 3], u32)| (t.0[0] + t.0[1] + t.0[2])[axis];
        let half = count / 2;
        span.select_nth_unstable_by(half, |a, b| key(a).total_cmp(&key(b)).then(a.1.cmp(&b.1)));
        nodes[me].count = 0;
        Self::build(tris, first, half, nodes);
        let right = Self::build(tris, first + half, count - half, nodes);
        nodes[me].right = right;
        me
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: [Vec3; 3] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() <= 1e-6 * (1.0 + b.abs())
    }

    #[test]
    fn above_the_interior_is_the_perpendicular_distance() {
        let p = Vec3::new(0.25, 0.25, 2.0);
        assert!(close(triangle_distance(p, &T), 2.0));
        assert!(close(triangle_distance(Vec3::new(0.2, 0.3, -0.5), &T), 0.5));
        let q = closest_on_triangle(p.as_dvec3(), T[0].into(), T[1].into(), T[2].into());
        assert!(q.distance(DVec3::new(0.25, 0.25, 0.0)) < 1e-12);
        // On the surface: zero, also in the plane of a tilted triangle.
        assert_eq!(triangle_distance(Vec3::new(0.1, 0.1, 0.0), &T), 0.0);
        let tilted = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ];
        let centroid = (tilted[0] + tilted[1] + tilted[2]) / 3.0;
        assert!(triangle_distance(centroid, &tilted) < 1e-7);
        // Along the normal (1, 1, -1)/√3 from the centroid.
        let n = Vec3::new(1.0, 1.0, -1.0).normalize();
        assert!(close(triangle_distance(centroid + 0.3 * n, &tilted), 0.3));
    }

    #[test]
    fn beyond_a_vertex_is_the_distance_to_it() {
        assert!(close(
            triangle_distance(Vec3::new(-3.0, -4.0, 0.0), &T),
            5.0
        ));
        assert!(close(triangle_distance(Vec3::new(3.0, -2.0, 1.0), &T), 3.0));
        let q = closest_on_triangle(
            DVec3::new(-1.0, 3.0, 1.0),
            T[0].into(),
            T[1].into(),
            T[2].into(),
        );
        assert_eq!(q, DVec3::new(0.0, 1.0, 0.0));
    }

    #[test]
    fn beside_an_edge_is_the_distance_to_the_edge() {
        // Below edge ab, lifted off the plane: √(0.5² + 0.5²).
        let p = Vec3::new(0.5, -0.5, 0.5);
        assert!(close(triangle_distance(p, &T), 0.5f32.sqrt()));
        // Beyond the hypotenuse bc: its midpoint is closest.
        let p = Vec3::new(1.0, 1.0, 0.0);
        assert!(close(triangle_distance(p, &T), 0.5f32.sqrt()));
        let q = closest_on_triangle(p.as_dvec3(), T[0].into(), T[1].into(), T[2].into());
        assert!(q.distance(DVec3::new(0.5, 0.5, 0.0)) < 1e-12);
        // Left of edge ca.
        assert!(close(triangle_distance(Vec3::new(-2.0, 0.5, 0.0), &T), 2.0));
    }

    #[test]
    fn degenerate_and_sliver_triangles() {
        // Collinear: the segment from (0,0,0) to (2,0,0).
        let line = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        assert!(close(
            triangle_distance(Vec3::new(1.5, 3.0, 0.0), &line),
            3.0
        ));
        assert!(close(
            triangle_distance(Vec3::new(3.0, 0.0, 0.0), &line),
            1.0
        ));
        // A point.
        let point = [Vec3::ONE; 3];
        assert!(close(
            triangle_distance(Vec3::new(1.0, 1.0, 3.0), &point),
            2.0
        ));
        // A sliver far from the origin, like a branch tip: its own centroid (rounded to f32, a few
        // 1e-6 off at this magnitude) measures on it.
        let o = Vec3::new(12.345, 67.89, -3.21);
        let sliver = [
            o,
            o + Vec3::new(1e-2, 1e-5, 0.0),
            o + Vec3::new(2e-2, 0.0, 1e-5),
        ];
        let centroid = (sliver[0] + sliver[1] + sliver[2]) / 3.0;
        assert!(triangle_distance(centroid, &sliver) < 1e-5);
        for t in [sliver, line, point] {
            let d = triangle_distance(Vec3::new(0.3, -0.7, 0.9), &t);
            assert!(d.is_finite() && d >= 0.0);
        }
    }

    /// Deterministic points in [-1, 1)³ (SplitMix64).
    fn points(seed: u64, n: usize) -> Vec<Vec3> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        };
        (0..n).map(|_| Vec3::new(next(), next(), next())).collect()
    }

    #[test]
    fn bvh_distance_equals_brute_force() {
        // Small triangles scattered around, some slivers, plus queries inside and well outside.
        let corners = points(1, 3 * 300);
        let triangles: Vec<[Vec3; 3]> = corners
            .chunks_exact(3)
            .enumerate()
            .map(|(i, c)| {
                let s = if i % 7 == 0 { 1e-4 } else { 0.1 };
                [c[0], c[0] + c[1] * s, c[0] + c[2] * 0.1]
            })
            .collect();
        let bvh = SurfaceBvh::new(triangles.clone());
        assert_eq!(bvh.len(), triangles.len());
        assert!(!bvh.is_empty());
        let mut queries = points(2, 400);
        queries.extend(points(3, 100).into_iter().map(|p| p * 5.0));
        queries.extend(
            triangles
                .iter()
                .take(50)
                .map(|t| (t[0] + t[1] + t[2]) / 3.0),
        );
        for p in queries {
            let brute = triangles
                .iter()
                .map(|t| triangle_distance(p, t))
                .fold(f32::INFINITY, f32::min);
            assert_eq!(bvh.distance(p), brute, "at {p}");
            // Bounded: exact above the floor, at most the floor otherwise.
            for floor in [brute * 0.5, brute, brute * 2.0] {
                let d = bvh.distance_beyond(p, floor);
                if brute > floor {
                    assert_eq!(d, brute, "at {p}, floor {floor}");
                } else {
                    assert!(d <= floor && d >= brute, "at {p}, floor {floor}: {d}");
                }
            }
            // The nearest triangle's input index and point agree with the brute force.
            let (id, q, d) = bvh.nearest(p).expect("non-empty");
            assert_eq!(d, brute, "at {p}");
            assert_eq!(
                triangle_distance(p, &triangles[id]),
                brute,
                "index of the nearest"
            );
            assert!(
                (q.distance(p) - d).abs() <= 1e-5 * (1.0 + d),
                "point at the distance"
            );
        }
        assert!(SurfaceBvh::new(Vec::new()).nearest(Vec3::ZERO).is_none());
        // The same triangles, reordered.
        let mut a: Vec<[u32; 9]> = triangles.iter().map(key).collect();
        let mut b: Vec<[u32; 9]> = bvh.triangles().iter().map(key).collect();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
    }

    fn key(t: &[Vec3; 3]) -> [u32; 9] {
        let f = |k: usize| t[k / 3][k % 3].to_bits();
        std::array::from_fn(f)
    }

    #[test]
    fn small_and_empty_surfaces() {
        let empty = SurfaceBvh::new(Vec::new());
        assert!(empty.is_empty());
        assert_eq!(empty.len(), 0);
        assert_eq!(empty.distance(Vec3::ZERO), f32::INFINITY);
        let one = SurfaceBvh::new(vec![T]);
        assert!(close(one.distance(Vec3::new(0.25, 0.25, 2.0)), 2.0));
    }
}
