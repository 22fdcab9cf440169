//! Lacewell's stochastic plane search (spec animated-billboard-clouds §2.4, with the D_max reset
//! fixed) plus the options of improved-billboard-cloud §2.4/§2.7/§2.8: view penalty, distance
//! falloff, least-squares refit, a plane budget. Exact accelerations only: a bounding-volume
//! hierarchy prunes triangles that cannot be within ε of a candidate plane (centroid boxes for
//! rejection, vertex boxes for whole-node acceptance), all candidates of an iteration walk it
//! together in one batch per thread, and the per-triangle test and contribution do the plain
//! scan's operations in its order (within a leaf, eight triangles at a time, compiled for AVX2
//! where the machine has it), so the accelerated search scores every candidate to the bit as
//! the plain one does and picks exactly its planes for the same seed.

use glam::{Vec3, Vec3A};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::plane::Plane;
use crate::soup::TriangleSoup;

/// Parameters of the search.
#[derive(Clone, Debug)]
pub struct SearchParams {
    /// Largest allowed vertex distance from a triangle's plane (absolute world units).
    pub epsilon: f32,
    /// Candidate planes per iteration (the thesis's S or N).
    pub candidates: usize,
    /// Seed of the candidate draws: the same seed gives the same planes.
    pub seed: u64,
    /// View-penalty angle φ_v in radians (0 favours vertical billboards), or None for off.
    pub view_penalty: Option<f32>,
    /// Weight each triangle's contribution by 1/(d/ε + 1), d its mean vertex distance.
    pub falloff: bool,
    /// Least-squares refit of each chosen plane, kept only when its triangles stay within ε.
    pub refit: bool,
    /// Stop after this many planes and join the leftovers to the nearest plane.
    pub max_planes: Option<usize>,
    /// Use the hierarchy and parallel scoring (false: the plain O(planes·S·triangles) scan).
    pub accelerated: bool,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            epsilon: 0.0,
            candidates: 500,
            seed: 1,
            view_penalty: None,
            falloff: false,
            refit: false,
            max_planes: None,
            accelerated: true,
        }
    }
}

/// One chosen plane and the triangles it simplifies.
#[derive(Clone, Debug)]
pub struct Cluster {
    /// The plane, fitted or as drawn.
    pub plane: Plane,
    /// Indices of its soup triangles, ascending.
    pub triangles: Vec<usize>,
}

/// The search result.
#[derive(Clone, Debug)]
pub struct PlaneSearch {
    /// The chosen planes with their triangles, in the order they were chosen.
    pub clusters: Vec<Cluster>,
    /// Cluster of every soup triangle.
    pub assignment: Vec<u32>,
    /// Triangles that were joined to the nearest plane (plane budget or zero area), not chosen
    /// by validity; their vertices may lie farther than ε from it.
    pub joined: usize,
    /// Largest vertex distance of any triangle from its cluster's plane.
    pub max_distance: f32,
    /// Candidate planes scored.
    pub candidates_scored: usize,
}

/// Per-triangle data in the order the hierarchy stores them.
struct Tris {
    /// Original soup index.
    id: Vec<u32>,
    v: Vec<[Vec3A; 3]>,
    centroid: Vec<Vec3A>,
    /// area × unit normal.
    area_normal: Vec<Vec3A>,
    alive: Vec<bool>,
}

/// A node of the bounding-volume hierarchy over triangle centroids.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Bounds of all vertices below (centre and half extents).
    center: Vec3A,
    half: Vec3A,
    /// Bounds of the triangle centroids below: a valid triangle's centroid is within ε of the
    /// plane, so this tighter box decides rejection.
    ccenter: Vec3A,
    chalf: Vec3A,
    start: u32,
    end: u32,
    /// Child indices; 0 for a leaf (the root is never a child).
    left: u32,
    right: u32,
    parent: u32,
    alive: u32,
    /// A leaf's alive triangles as bits (bit `k`: stored triangle `start + k`), so a leaf's
    /// test loop visits only the alive triangles near a candidate's plane.
    alive_bits: u32,
    /// A leaf's entry in [`Bvh::leaves`].
    slot: u32,
}

/// A leaf's triangle centroids, coordinate by coordinate, radii (largest vertex distance
/// from the centroid), vertices and area normals in fixed-size arrays (entries past the leaf's
/// triangles are zero, and their `alive_bits` clear): a candidate's distances, masks, exact
/// tests and contributions over the leaf are loops of constant length, which the compiler
/// turns into vector code.
#[derive(Clone, Debug)]
struct LeafBlock {
    cx: [f32; LEAF_SIZE],
    cy: [f32; LEAF_SIZE],
    cz: [f32; LEAF_SIZE],
    radius: [f32; LEAF_SIZE],
    /// `vertex[j][axis][k]`: coordinate `axis` of vertex `j` of triangle `k`.
    vertex: [[[f32; LEAF_SIZE]; 3]; 3],
    /// `area_normal[axis][k]`.
    area_normal: [[f32; LEAF_SIZE]; 3],
}

impl LeafBlock {
    /// The block of stored triangles `a..b` of `t`.
    fn new(t: &Tris, a: usize, b: usize) -> LeafBlock {
        let block = |f: &dyn Fn(usize) -> f32| {
            let mut out = [0.0f32; LEAF_SIZE];
            for (k, o) in out.iter_mut().take(b - a).enumerate() {
                *o = f(a + k);
            }
            out
        };
        LeafBlock {
            cx: block(&|i| t.centroid[i].x),
            cy: block(&|i| t.centroid[i].y),
            cz: block(&|i| t.centroid[i].z),
            radius: block(&|i| {
                t.v[i]
                    .iter()
                    .map(|p| p.distance(t.centroid[i]))
                    .fold(0.0, f32::max)
            }),
            vertex: std::array::from_fn(|j| {
                std::array::from_fn(|axis| block(&|i| t.v[i][j][axis]))
            }),
            area_normal: std::array::from_fn(|axis| block(&|i| t.area_normal[i][axis])),
        }
    }

    /// Distance of centroid `k` from the plane `n·x = rho`.
    #[inline(always)]
    fn distance(&self, k: usize, n: Vec3A, rho: f32) -> f32 {
        (n.x * self.cx[k] + n.y * self.cy[k] + n.z * self.cz[k] - rho).abs()
    }
}

const LEAF_SIZE: usize = 32;
// A leaf's alive triangles fit one `u32` of bits ([`Node::alive_bits`]).
const _: () = assert!(LEAF_SIZE <= 32);

struct Bvh {
    nodes: Vec<Node>,
    /// Per leaf ([`Node::slot`]), its triangles' centroids and radii.
    leaves: Vec<LeafBlock>,
    /// Leaf node of each stored triangle.
    leaf_of: Vec<u32>,
}

impl Bvh {
    fn build(t: &mut Tris) -> Bvh {
        let n = t.id.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 2);
        let mut leaf_of = vec![0u32; n];
        build_node(t, &mut order, 0, n, u32::MAX, &mut nodes, &mut leaf_of);
        // Reorder triangle arrays into hierarchy order.
        let reorder = |o: &[u32]| -> Tris {
            Tris {
                id: o.iter().map(|&i| t.id[i as usize]).collect(),
                v: o.iter().map(|&i| t.v[i as usize]).collect(),
                centroid: o.iter().map(|&i| t.centroid[i as usize]).collect(),
                area_normal: o.iter().map(|&i| t.area_normal[i as usize]).collect(),
                alive: o.iter().map(|&i| t.alive[i as usize]).collect(),
            }
        };
        let mut leaf_sorted = vec![0u32; n];
        for (pos, &i) in order.iter().enumerate() {
            leaf_sorted[pos] = leaf_of[i as usize];
        }
        *t = reorder(&order);
        let mut leaves = Vec::new();
        for node in nodes.iter_mut().filter(|n| n.left == 0) {
            node.slot = leaves.len() as u32;
            leaves.push(LeafBlock::new(t, node.start as usize, node.end as usize));
        }
        Bvh {
            nodes,
            leaves,
            leaf_of: leaf_sorted,
        }
    }

    /// Marks stored triangle `i` dead and updates alive counts up to the root.
    fn kill(&mut self, t: &mut Tris, i: usize) {
        if !t.alive[i] {
            return;
        }
        t.alive[i] = false;
        let leaf = &mut self.nodes[self.leaf_of[i] as usize];
        leaf.alive_bits &= !(1u32 << (i - leaf.start as usize));
        let mut n = self.leaf_of[i];
        while n != u32::MAX {
            let node = &mut self.nodes[n as usize];
            node.alive -= 1;
            n = node.parent;
        }
    }
}

fn build_node(
    t: &Tris,
    order: &mut [u32],
    start: usize,
    end: usize,
    parent: u32,
    nodes: &mut Vec<Node>,
    leaf_of: &mut [u32],
) -> u32 {
    let idx = nodes.len() as u32;
    let (mut lo, mut hi) = (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for &i in &order[start..end] {
        for v in t.v[i as usize] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        clo = clo.min(t.centroid[i as usize]);
        chi = chi.max(t.centroid[i as usize]);
    }
    nodes.push(Node {
        center: (lo + hi) * 0.5,
        half: (hi - lo) * 0.5,
        ccenter: (clo + chi) * 0.5,
        chalf: (chi - clo) * 0.5,
        start: start as u32,
        end: end as u32,
        left: 0,
        right: 0,
        parent,
        alive: (end - start) as u32,
        alive_bits: if end - start <= LEAF_SIZE {
            u32::MAX >> (32 - (end - start))
        } else {
            0
        },
        slot: 0,
    });
    if end - start <= LEAF_SIZE {
        for &i in &order[start..end] {
            leaf_of[i as usize] = idx;
        }
        return idx;
    }
    let ext = chi - clo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = (start + end) / 2;
    order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
        t.centroid[a as usize][axis]
            .total_cmp(&t.centroid[b as usize][axis])
            .then(a.cmp(&b))
    });
    let l = build_node(t, order, start, mid, idx, nodes, leaf_of);
    let r = build_node(t, order, mid, end, idx, nodes, leaf_of);
    nodes[idx as usize].left = l;
    nodes[idx as usize].right = r;
    idx
}

/// The shared exact validity predicate: all three vertices within ε of the plane.
#[inline]
fn valid_exact(v: &[Vec3A; 3], n: Vec3A, rho: f32, eps: f32) -> bool {
    v.iter().all(|p| (n.dot(*p) - rho).abs() <= eps)
}

/// Contribution of a valid triangle: projected area, optionally with distance falloff.
#[inline]
fn contribution(
    v: &[Vec3A; 3],
    area_normal: Vec3A,
    n: Vec3A,
    rho: f32,
    eps: f32,
    falloff: bool,
) -> f64 {
    let c = area_normal.dot(n).abs();
    if falloff {
        let spread = v.iter().map(|p| (n.dot(*p) - rho).abs()).sum::<f32>();
        falloff_contribution(c, spread, eps)
    } else {
        c as f64
    }
}

/// A contribution `c` with distance falloff, `spread` the sum of the triangle's three vertex
/// distances from the plane.
#[inline(always)]
fn falloff_contribution(c: f32, spread: f32, eps: f32) -> f64 {
    c as f64 / (spread / 3.0 / eps.max(f32::MIN_POSITIVE) + 1.0) as f64
}

/// The search state shared by the plain and the accelerated scoring.
struct Search<'a> {
    t: Tris,
    bvh: Bvh,
    eps: f32,
    /// Safety margin for the conservative tests (float noise), never for the exact one.
    margin: f32,
    params: &'a SearchParams,
}

impl<'a> Search<'a> {
    /// The search state of `soup` (every triangle alive) for `params`, `scale` the soup's
    /// size (its diagonal), which sets the margin of the conservative tests.
    fn new(soup: &TriangleSoup, params: &'a SearchParams, scale: f32) -> Search<'a> {
        let n = soup.len();
        let eps = params.epsilon.max(0.0);
        let mut t = Tris {
            id: (0..n as u32).collect(),
            v: soup.positions.iter().map(|v| v.map(Vec3A::from)).collect(),
            centroid: soup
                .positions
                .iter()
                .map(|v| Vec3A::from((v[0] + v[1] + v[2]) / 3.0))
                .collect(),
            area_normal: soup
                .positions
                .iter()
                .map(|v| Vec3A::from(0.5 * (v[1] - v[0]).cross(v[2] - v[0])))
                .collect(),
            alive: vec![true; n],
        };
        let bvh = Bvh::build(&mut t);
        Search {
            t,
            bvh,
            eps,
            margin: 1e-5 * scale.max(eps) + 1e-4 * eps,
            params,
        }
    }
}

impl Search<'_> {
    /// Density of a candidate plane over alive triangles (and the valid ones when `collect`).
    fn score(&self, n: Vec3A, rho: f32, collect: Option<&mut Vec<usize>>) -> f64 {
        if self.params.accelerated {
            self.score_tree(n, rho, collect)
        } else {
            self.score_plain(n, rho, collect)
        }
    }

    fn score_plain(&self, n: Vec3A, rho: f32, mut collect: Option<&mut Vec<usize>>) -> f64 {
        let t = &self.t;
        let mut d = 0.0;
        for i in 0..t.id.len() {
            if t.alive[i] && valid_exact(&t.v[i], n, rho, self.eps) {
                d += contribution(
                    &t.v[i],
                    t.area_normal[i],
                    n,
                    rho,
                    self.eps,
                    self.params.falloff,
                );
                if let Some(c) = collect.as_deref_mut() {
                    c.push(i);
                }
            }
        }
        d
    }

    /// Densities of many candidates in one traversal: each node and each leaf's triangles are
    /// loaded once for every candidate whose ε-slab reaches them, instead of once per candidate
    /// (the per-candidate walks were memory-bound). Same predicate and summation order per
    /// candidate as [`Self::score_tree`], so the same densities.
    fn score_batch(&self, cands: &[(Vec3A, f32)]) -> Vec<f64> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the machine has AVX2, just checked.
            return unsafe { self.score_batch_avx2(cands) };
        }
        self.score_batch_body(cands)
    }

    /// [`Self::score_batch`] compiled for AVX2: a leaf's 32 distances eight at a time. No
    /// fused multiply-add is enabled (and Rust never contracts), so every operation rounds as
    /// in the baseline build: the same densities.
    ///
    /// # Safety
    /// The machine must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn score_batch_avx2(&self, cands: &[(Vec3A, f32)]) -> Vec<f64> {
        self.score_batch_body(cands)
    }

    /// [`Self::score_batch`]'s work, for each instruction set it is compiled for.
    #[inline(always)]
    fn score_batch_body(&self, cands: &[(Vec3A, f32)]) -> Vec<f64> {
        let t = &self.t;
        let (eps, m, falloff) = (self.eps, self.margin, self.params.falloff);
        let normals_abs: Vec<Vec3A> = cands.iter().map(|c| c.0.abs()).collect();
        let mut d = vec![0.0f64; cands.len()];
        // Stack of (node, start, end) ranges into `lists`, which holds active candidate ids.
        let mut lists: Vec<u16> = (0..cands.len() as u16).collect();
        let mut stack: Vec<(u32, usize, usize)> = vec![(0, 0, lists.len())];
        let mut partial: Vec<u16> = Vec::with_capacity(cands.len());
        let mut inside: Vec<u16> = Vec::with_capacity(cands.len());
        let (near, far) = (eps + m, eps - m);
        while let Some((ni, a, b)) = stack.pop() {
            let node = &self.bvh.nodes[ni as usize];
            if node.alive == 0 {
                lists.truncate(a);
                continue;
            }
            partial.clear();
            inside.clear();
            for &c in &lists[a..b] {
                let (n, rho) = cands[c as usize];
                let na = normals_abs[c as usize];
                if (n.dot(node.ccenter) - rho).abs() - na.dot(node.chalf) > eps + m {
                    continue;
                }
                if (n.dot(node.center) - rho).abs() + na.dot(node.half) < eps - m {
                    inside.push(c);
                } else {
                    partial.push(c);
                }
            }
            lists.truncate(a);
            let (s0, e0) = (node.start as usize, node.end as usize);
            // Candidates whose slab holds this whole node: every alive triangle counts.
            if !inside.is_empty() {
                for i in s0..e0 {
                    if !t.alive[i] {
                        continue;
                    }
                    for &c in &inside {
                        let (n, rho) = cands[c as usize];
                        d[c as usize] +=
                            contribution(&t.v[i], t.area_normal[i], n, rho, eps, falloff);
                    }
                }
            }
            if partial.is_empty() {
                continue;
            }
            if node.left != 0 {
                // Both children get the partial set; right is pushed first so left runs first.
                let ra = lists.len();
                lists.extend_from_slice(&partial);
                let rb = lists.len();
                lists.extend_from_slice(&partial);
                let lb = lists.len();
                stack.push((node.right, ra, rb));
                stack.push((node.left, rb, lb));
                continue;
            }
            let leaf = &self.bvh.leaves[node.slot as usize];
            for &c in &partial {
                let (n, rho) = cands[c as usize];
                // Bit masks of the leaf's triangles whose centroid is near enough to be valid
                // (`maybe`) and of those valid by their bounding sphere alone (`sure`); the
                // exact test runs only on the rest. Bits are visited in storage order, so the
                // sum is the one `score_tree` makes.
                let (mut maybe, mut sure) = (0u32, 0u32);
                for k in 0..LEAF_SIZE {
                    let dc = leaf.distance(k, n, rho);
                    maybe |= u32::from(dc <= near) << k;
                    sure |= u32::from(dc + leaf.radius[k] < far) << k;
                }
                let bits = maybe & node.alive_bits;
                // The exact test and the contributions, eight triangles at a time in each group
                // where one needs the test (near, but not valid by its bounding sphere alone):
                // `valid_exact` and `contribution`'s operations in their order (a dot product is
                // `(x·x' + y·y') + z·z'`, as glam's), so the same bits, summed group after group
                // in storage order.
                let acc = &mut d[c as usize];
                for g in 0..LEAF_SIZE / 8 {
                    let mut wanted = (bits >> (8 * g)) & 0xff;
                    if wanted == 0 {
                        continue;
                    }
                    let base = 8 * g;
                    if (wanted & !(sure >> base)) == 0 {
                        // Valid by their spheres alone.
                        while wanted != 0 {
                            let i = s0 + base + wanted.trailing_zeros() as usize;
                            wanted &= wanted - 1;
                            *acc += contribution(&t.v[i], t.area_normal[i], n, rho, eps, falloff);
                        }
                        continue;
                    }
                    let mut valid = (sure >> base) & 0xff;
                    let (mut value, mut spread) = ([0.0f32; 8], [0.0f32; 8]);
                    for l in 0..8 {
                        let k = base + l;
                        let v = &leaf.vertex;
                        let at = |j: usize| {
                            (n.x * v[j][0][k] + n.y * v[j][1][k] + n.z * v[j][2][k] - rho).abs()
                        };
                        let (d0, d1, d2) = (at(0), at(1), at(2));
                        valid |= u32::from((d0 <= eps) & (d1 <= eps) & (d2 <= eps)) << l;
                        let a = &leaf.area_normal;
                        value[l] = (a[0][k] * n.x + a[1][k] * n.y + a[2][k] * n.z).abs();
                        spread[l] = d0 + d1 + d2;
                    }
                    wanted &= valid;
                    while wanted != 0 {
                        let l = wanted.trailing_zeros() as usize;
                        wanted &= wanted - 1;
                        *acc += if falloff {
                            falloff_contribution(value[l], spread[l], eps)
                        } else {
                            f64::from(value[l])
                        };
                    }
                }
            }
        }
        d
    }

    /// Density of one candidate by hierarchy traversal (and its valid triangles when `collect`).
    fn score_tree(&self, n: Vec3A, rho: f32, mut collect: Option<&mut Vec<usize>>) -> f64 {
        let t = &self.t;
        let (eps, m, falloff) = (self.eps, self.margin, self.params.falloff);
        let na = n.abs();
        let mut d = 0.0;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let node = &self.bvh.nodes[ni as usize];
            if node.alive == 0 {
                continue;
            }
            if (n.dot(node.ccenter) - rho).abs() - na.dot(node.chalf) > eps + m {
                continue; // every centroid below is farther than ε: no triangle can be valid
            }
            let inside = (n.dot(node.center) - rho).abs() + na.dot(node.half) < eps - m; // every vertex below is within ε
            if !inside && node.left != 0 {
                stack.push(node.right);
                stack.push(node.left);
                continue;
            }
            let (a, b) = (node.start as usize, node.end as usize);
            // Not inside: a leaf (an inner node was split above).
            let leaf = (!inside).then(|| &self.bvh.leaves[node.slot as usize]);
            for i in a..b {
                if !t.alive[i] {
                    continue;
                }
                let ok = match leaf {
                    None => true,
                    Some(leaf) => {
                        let dc = leaf.distance(i - a, n, rho);
                        if dc > eps + m {
                            false
                        } else if dc + leaf.radius[i - a] < eps - m {
                            true
                        } else {
                            valid_exact(&t.v[i], n, rho, eps)
                        }
                    }
                };
                if ok {
                    d += contribution(&t.v[i], t.area_normal[i], n, rho, eps, falloff);
                    if let Some(c) = collect.as_deref_mut() {
                        c.push(i);
                    }
                }
            }
        }
        d
    }

    /// View-penalty factor `1 − |φ_v − φ_n|/(π/2)` (the thesis's printed factor inverted, erratum §11).
    fn penalty(&self, n: Vec3A) -> f64 {
        match self.params.view_penalty {
            Some(phi_v) => {
                let phi_n = n.y.abs().min(1.0).asin();
                (1.0 - (phi_v - phi_n).abs() / std::f32::consts::FRAC_PI_2).max(0.0) as f64
            }
            None => 1.0,
        }
    }
}

// Index loops mirror the Jacobi rotation formulas; iterator forms would obscure them.
/// Least-squares plane through points: normal = eigenvector of the smallest eigenvalue of the
/// covariance (Jacobi iteration on the symmetric 3×3 matrix).
#[expect(
    clippy::needless_range_loop,
    reason = "Jacobi rotations index rows and columns of the same matrices by one index"
)]
fn fit_plane(points: impl Iterator<Item = Vec3A> + Clone) -> Option<Plane> {
    let mut count = 0.0f64;
    let mut mean = [0.0f64; 3];
    for p in points.clone() {
        count += 1.0;
        for k in 0..3 {
            mean[k] += p[k] as f64;
        }
    }
    if count < 3.0 {
        return None;
    }
    for m in &mut mean {
        *m /= count;
    }
    let mut a = [[0.0f64; 3]; 3];
    for p in points {
        let d = [
            p.x as f64 - mean[0],
            p.y as f64 - mean[1],
            p.z as f64 - mean[2],
        ];
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] += d[r] * d[c];
            }
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0f64]];
    for _ in 0..32 {
        let (mut p, mut q, mut big) = (0, 1, 0.0);
        for r in 0..3 {
            for c in r + 1..3 {
                if a[r][c].abs() > big {
                    big = a[r][c].abs();
                    p = r;
                    q = c;
                }
            }
        }
        if big < 1e-30 {
            break;
        }
        let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
        let t = if theta == 0.0 { 1.0 } else { t };
        let c = 1.0 / (t * t + 1.0).sqrt();
        let s = t * c;
        for k in 0..3 {
            let (akp, akq) = (a[k][p], a[k][q]);
            a[k][p] = c * akp - s * akq;
            a[k][q] = s * akp + c * akq;
        }
        for k in 0..3 {
            let (apk, aqk) = (a[p][k], a[q][k]);
            a[p][k] = c * apk - s * aqk;
            a[q][k] = s * apk + c * aqk;
        }
        for row in &mut v {
            let (vp, vq) = (row[p], row[q]);
            row[p] = c * vp - s * vq;
            row[q] = s * vp + c * vq;
        }
    }
    let k = (0..3).min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))?;
    let n = Vec3::new(v[0][k] as f32, v[1][k] as f32, v[2][k] as f32).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    let centre = Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32);
    Some(Plane {
        normal: n,
        offset: n.dot(centre),
    })
}

/// Runs the search on `soup`. `scale` is the size used for float-noise margins (e.g. the tree's
/// bounding-box diagonal).
pub fn search_planes(soup: &TriangleSoup, params: &SearchParams, scale: f32) -> PlaneSearch {
    let n = soup.len();
    let min_area = (scale * scale * 1e-12).max(f32::MIN_POSITIVE);
    let mut s = Search::new(soup, params, scale);
    let mut seeds = Seeds::new(&s.t, min_area);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut clusters: Vec<Cluster> = Vec::new();
    let mut assignment = vec![u32::MAX; n];
    let mut scored = 0usize;
    let budget = params.max_planes.unwrap_or(usize::MAX).max(1);
    while !seeds.seedable.is_empty() && clusters.len() < budget {
        // Draw every candidate first (sequential RNG), then score them in parallel.
        let cands = s.draw_candidates(&seeds.seedable, &mut rng);
        scored += cands.len();
        let scores = s.score_candidates(&cands);
        let Some(b) = best_candidate(&scores) else {
            // Every candidate was degenerate: retire one seed so the loop always progresses.
            let seed = seeds.seedable[rng.random_range(0..seeds.seedable.len())];
            seeds.remove(seed);
            continue;
        };
        let cluster = clusters.len() as u32;
        clusters.push(s.take_cluster(cands[b], cluster, &mut assignment, &mut seeds));
    }
    let joined = s.join_leftovers(&mut clusters, &mut assignment);
    for c in &mut clusters {
        c.triangles.sort_unstable();
    }
    let max_distance = clusters
        .iter()
        .flat_map(|c| {
            c.triangles.iter().map(move |&i| {
                soup.positions[i]
                    .iter()
                    .map(|p| c.plane.distance(*p).abs())
                    .fold(0.0, f32::max)
            })
        })
        .fold(0.0, f32::max);
    PlaneSearch {
        clusters,
        assignment,
        joined,
        max_distance,
        candidates_scored: scored,
    }
}

/// A candidate plane: its unit normal, its offset, and the stored triangle that seeded it.
type Candidate = (Vec3A, f32, u32);

/// The triangles that may still seed a plane: stored indices, drawn from in soup order (so
/// the hierarchy's layout never changes which are drawn), with each one's position in that
/// list for removal.
struct Seeds {
    /// Stored indices of the seedable triangles.
    seedable: Vec<u32>,
    /// Per stored triangle, its position in `seedable` (`u32::MAX`: not seedable).
    seed_pos: Vec<u32>,
}

impl Seeds {
    /// The alive triangles with a usable area (more than `min_area`), in soup order.
    /// Zero-area ones never seed (they would stop the search early) and are joined to the
    /// nearest plane at the end.
    fn new(t: &Tris, min_area: f32) -> Seeds {
        let n = t.id.len();
        let mut stored_of = vec![0u32; n];
        for (pos, &id) in t.id.iter().enumerate() {
            stored_of[id as usize] = pos as u32;
        }
        let seedable: Vec<u32> = (0..n as u32)
            .map(|id| stored_of[id as usize])
            .filter(|&i| t.area_normal[i as usize].length() > min_area)
            .collect();
        let mut seed_pos: Vec<u32> = vec![u32::MAX; n];
        for (k, &i) in seedable.iter().enumerate() {
            seed_pos[i as usize] = k as u32;
        }
        Seeds { seedable, seed_pos }
    }

    /// Removes stored triangle `i` from the seeds (see [`remove_seed`]).
    fn remove(&mut self, i: u32) {
        remove_seed(&mut self.seedable, &mut self.seed_pos, i);
    }
}

/// The first candidate of the highest score, None when there are none. D_max starts at 0
/// once per iteration (the thesis reset it inside the loop: erratum).
fn best_candidate(scores: &[f64]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (k, &d) in scores.iter().enumerate() {
        if best.is_none_or(|b| d > scores[b]) {
            best = Some(k);
        }
    }
    best
}

impl Search<'_> {
    /// Draws one iteration's candidate planes from `rng`, in order: each through a random seed
    /// triangle's vertices, each moved along its normal by up to ε (the thesis's jitter).
    /// Degenerate draws are left out.
    fn draw_candidates(&self, seedable: &[u32], rng: &mut ChaCha8Rng) -> Vec<Candidate> {
        let eps = self.eps;
        (0..self.params.candidates.max(1))
            .filter_map(|_| {
                let seed = seedable[rng.random_range(0..seedable.len())] as usize;
                let v = self.t.v[seed];
                let nt = self.t.area_normal[seed].normalize_or_zero();
                let mut off = [0.0f32; 3];
                for o in &mut off {
                    *o = if eps > 0.0 {
                        rng.random_range(-eps..=eps)
                    } else {
                        0.0
                    };
                }
                let p = Plane::through(
                    Vec3::from(v[0] + nt * off[0]),
                    Vec3::from(v[1] + nt * off[1]),
                    Vec3::from(v[2] + nt * off[2]),
                )?;
                Some((Vec3A::from(p.normal), p.offset, seed as u32))
            })
            .collect()
    }

    /// Each candidate's score (density times view penalty), in candidate order: in parallel
    /// batches over the hierarchy when accelerated, else by the plain scan.
    fn score_candidates(&self, cands: &[Candidate]) -> Vec<f64> {
        if self.params.accelerated {
            // One batched traversal per worker (bigger batches share more cache); the order
            // of `scores` is the order of `cands`, whatever the thread count.
            let batch = cands
                .len()
                .div_ceil(rayon::current_num_threads().max(1))
                .max(1);
            let planes: Vec<(Vec3A, f32)> = cands.iter().map(|c| (c.0, c.1)).collect();
            planes
                .par_chunks(batch)
                .flat_map_iter(|chunk| {
                    self.score_batch(chunk)
                        .into_iter()
                        .zip(chunk)
                        .map(|(d, c)| d * self.penalty(c.0))
                        .collect::<Vec<_>>()
                })
                .collect()
        } else {
            cands
                .iter()
                .map(|&(nn, rho, _)| self.score(nn, rho, None) * self.penalty(nn))
                .collect()
        }
    }

    /// Makes the chosen candidate cluster number `cluster`: its valid triangles (at least its
    /// seed) with its plane, least-squares refitted when asked and the fit keeps them all
    /// valid. The members are assigned to it, killed in the hierarchy and retired from the
    /// seeds, in soup order.
    fn take_cluster(
        &mut self,
        (nn, rho, seed): Candidate,
        cluster: u32,
        assignment: &mut [u32],
        seeds: &mut Seeds,
    ) -> Cluster {
        let eps = self.eps;
        let mut members = Vec::new();
        self.score(nn, rho, Some(&mut members));
        if members.is_empty() {
            members.push(seed as usize); // float noise at ε = 0: the seed always belongs
        }
        let mut plane = Plane {
            normal: Vec3::from(nn),
            offset: rho,
        };
        if self.params.refit
            && let Some(fit) = fit_plane(members.iter().flat_map(|&i| self.t.v[i]))
        {
            let fa = Vec3A::from(fit.normal);
            if members
                .iter()
                .all(|&i| valid_exact(&self.t.v[i], fa, fit.offset, eps))
            {
                plane = fit;
            }
        }
        let mut tris = Vec::with_capacity(members.len());
        // Retire members in soup order, so the seed list (and every later draw) does not depend
        // on the hierarchy's layout.
        members.sort_unstable_by_key(|&i| self.t.id[i]);
        for &i in &members {
            let id = self.t.id[i];
            assignment[id as usize] = cluster;
            tris.push(id as usize);
            self.bvh.kill(&mut self.t, i);
            if seeds.seed_pos[i] != u32::MAX {
                seeds.remove(i as u32);
            }
        }
        tris.sort_unstable();
        Cluster {
            plane,
            triangles: tris,
        }
    }

    /// Joins every triangle still alive (plane budget reached, or zero area) to the nearest
    /// plane (by its farthest vertex; a plane of its own when there is none yet). Returns how
    /// many were joined.
    fn join_leftovers(&self, clusters: &mut Vec<Cluster>, assignment: &mut [u32]) -> usize {
        // Leftovers (plane budget reached, or zero-area triangles): join the nearest plane.
        let mut joined = 0;
        for i in 0..self.t.alive.len() {
            if !self.t.alive[i] {
                continue;
            }
            let id = self.t.id[i] as usize;
            let v = self.t.v[i];
            let nearest = clusters
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let na = Vec3A::from(c.plane.normal);
                    (
                        k,
                        v.iter()
                            .map(|p| (na.dot(*p) - c.plane.offset).abs())
                            .fold(0.0, f32::max),
                    )
                })
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            let k = match nearest {
                Some((k, _)) => k,
                None => {
                    let p = fit_plane(v.into_iter()).or_else(|| {
                        Plane::through(Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]))
                    });
                    clusters.push(Cluster {
                        plane: p.unwrap_or(Plane {
                            normal: Vec3::Y,
                            offset: v[0].y,
                        }),
                        triangles: Vec::new(),
                    });
                    clusters.len() - 1
                }
            };
            clusters[k].triangles.push(id);
            assignment[id] = k as u32;
            joined += 1;
        }
        joined
    }
}

/// Removes stored triangle `i` from `seedable` in constant time (the last seed takes its
/// place), keeping `seed_pos` up to date.
fn remove_seed(seedable: &mut Vec<u32>, seed_pos: &mut [u32], i: u32) {
    let k = seed_pos[i as usize] as usize;
    let last = *seedable.last().unwrap_or(&i);
    seedable.swap_remove(k);
    if last != i {
        seed_pos[last as usize] = k as u32;
    }
    seed_pos[i as usize] = u32::MAX;
}

/// Soup triangles (all of them, assigned or not) with every vertex within ε of `plane`:
/// the extra triangles "increased foliage density" bakes onto a billboard (spec §2.4).
pub fn valid_for_plane(soup: &TriangleSoup, plane: &Plane, epsilon: f32) -> Vec<usize> {
    let n = Vec3A::from(plane.normal);
    (0..soup.len())
        .filter(|&i| {
            valid_exact(
                &soup.positions[i].map(Vec3A::from),
                n,
                plane.offset,
                epsilon,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// `count` small triangles (a hundredth to a thirtieth of the box) at random places and
    /// orientations in the unit box.
    fn random_soup(count: usize, seed: u64) -> TriangleSoup {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut next = move || rng.random_range(0.0f32..1.0);
        let positions = (0..count)
            .map(|_| {
                let centre = Vec3::new(next(), next(), next());
                let size = 0.01 + next() * 0.02;
                let mut corner =
                    || centre + Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.0 * size;
                [corner(), corner(), corner()]
            })
            .collect();
        TriangleSoup {
            positions,
            uvs: vec![[Vec2::ZERO; 3]; count],
            material: vec![0; count],
        }
    }

    /// The batched traversal (the exact test and the contributions eight triangles at a time)
    /// gives every candidate the plain scan's density to the bit, with and without distance
    /// falloff, some triangles dead.
    #[test]
    fn batched_densities_are_the_plain_scans_to_the_bit() {
        let soup = random_soup(4000, 3);
        let diag = 3.0f32.sqrt();
        let mut nonzero = 0;
        for (frac, falloff) in [(0.01, false), (0.01, true), (0.05, false), (0.05, true)] {
            let params = SearchParams {
                epsilon: frac * diag,
                falloff,
                ..Default::default()
            };
            let mut s = Search::new(&soup, &params, diag);
            for i in (0..soup.len()).step_by(3) {
                s.bvh.kill(&mut s.t, i);
            }
            // Planes through random triangles, their corners moved along the normal within ε
            // (as the search draws its candidates).
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            let mut pick = move |n: usize| rng.random_range(0..n);
            let cands: Vec<(Vec3A, f32)> = (0..300)
                .filter_map(|_| {
                    let v = s.t.v[pick(soup.len())];
                    let nt = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
                    let off: [Vec3A; 3] = std::array::from_fn(|_| {
                        nt * params.epsilon * (pick(201) as f32 / 100.0 - 1.0)
                    });
                    let p = Plane::through(
                        Vec3::from(v[0] + off[0]),
                        Vec3::from(v[1] + off[1]),
                        Vec3::from(v[2] + off[2]),
                    )?;
                    Some((Vec3A::from(p.normal), p.offset))
                })
                .collect();
            for (c, batched) in cands.iter().zip(s.score_batch(&cands)) {
                let plain = s.score_plain(c.0, c.1, None);
                assert_eq!(
                    batched.to_bits(),
                    plain.to_bits(),
                    "ε {frac}, falloff {falloff}: {batched} against {plain}"
                );
                nonzero += usize::from(plain > 0.0);
            }
        }
        assert!(nonzero > 600, "{nonzero} candidates with valid triangles");
    }
}
