//! Skin weights fitted over the joints a LOD keeps (spec view-dependent-hierarchies-gpu §2.4;
//! the weight step of Le & Deng 2012, "Smooth Skinning Decomposition with Rigid Bones", §3.2).
//!
//! When the joint budget removes a vertex's joint, linear blend skinning can still follow the
//! motion the vertex had: a point between two kept joints moves as a blend of both. Given the
//! kept joints' animation at the loop's samples, a vertex's weights over a few candidate joints
//! are the non-negative ones, summing to one, that bring its skinned path closest (least
//! squares over the samples) to its path in the input; at most four are kept, as glTF's
//! `JOINTS_0`/`WEIGHTS_0` carry. The fit is solved by [`crate::simplex_fit`].

use frond_scene::rigid_fit::rigid_fit;
use frond_scene::wood::NO_BONE;
use glam::{Mat4, Vec3};

use crate::joint_budget::RigFrames;
use crate::simplex_fit::{project_to_simplex, solve_on_simplex};

/// A vertex's skin over the rig's nodes (`NO_BONE`: the world, which does not move): four
/// joints and their weights.
pub type Skin = ([u32; 4], [f32; 4]);

/// Loop samples a fit reads at most, evenly spread over the loop: enough to see a sway's
/// shape, few enough that fitting every vertex of a LOD stays cheap.
pub const FIT_SAMPLES: usize = 16;

/// Candidate joints a vertex's weights are fitted over, at most: those whose own motion
/// carries it closest.
pub const MAX_CANDIDATES: usize = 8;

/// Weights a vertex keeps: glTF's `JOINTS_0` holds four.
pub const MAX_INFLUENCES: usize = 4;

/// The rig's deformations at the samples a fit reads: `carry[k][n]` takes a rest-pose point
/// following node `n` to fit sample `k`.
pub struct SkinFit {
    carry: Vec<Vec<Mat4>>,
}

impl SkinFit {
    /// The deformations of every node of `frames` at up to [`FIT_SAMPLES`] of its samples.
    pub fn new(frames: &RigFrames) -> SkinFit {
        let ns = frames.worlds.len();
        let step = ns.div_ceil(FIT_SAMPLES).max(1);
        let carry = (0..ns)
            .step_by(step)
            .map(|s| {
                (0..frames.rest_inv.len())
                    .map(|n| frames.carry(Some(n), s))
                    .collect()
            })
            .collect();
        SkinFit { carry }
    }

    /// Samples each path has.
    pub fn samples(&self) -> usize {
        self.carry.len()
    }

    /// Where joint `bone` (`NO_BONE` or a node out of range: the world) moves rest position
    /// `p` at fit sample `k`.
    fn moved(&self, k: usize, bone: u32, p: Vec3) -> Vec3 {
        match self.carry[k].get(bone as usize) {
            Some(m) if bone != NO_BONE => m.transform_point3(p),
            _ => p,
        }
    }

    /// The path of rest position `p` skinned by `skin`, at every fit sample.
    pub fn path(&self, p: Vec3, skin: &Skin) -> Vec<Vec3> {
        (0..self.samples())
            .map(|k| {
                (0..4)
                    .filter(|&j| skin.1[j] > 0.0)
                    .map(|j| self.moved(k, skin.0[j], p) * skin.1[j])
                    .sum()
            })
            .collect()
    }

    /// Sum over the fit samples of the squared distance from `p` skinned by `skin` to
    /// `target`.
    pub fn miss(&self, p: Vec3, skin: &Skin, target: &[Vec3]) -> f64 {
        self.path(p, skin)
            .iter()
            .zip(target)
            .map(|(a, b)| f64::from(a.distance_squared(*b)))
            .sum()
    }

    /// The skin of rest position `p` over at most [`MAX_INFLUENCES`] of `candidates` whose
    /// path comes closest to `target`, with its [`Self::miss`]; `start` (whose joints are
    /// tried whatever their rank) is where the fit begins, and is returned when nothing fits
    /// better. Of the candidates, the [`MAX_CANDIDATES`] that alone carry `p` closest are
    /// fitted over; the four strongest weights are then fitted again alone.
    pub fn fit(&self, p: Vec3, target: &[Vec3], candidates: &[u32], start: &Skin) -> (Skin, f64) {
        self.fit_points(&[(p, target)], candidates, start)
    }

    /// One skin for every point of `points` (rest position, target path), fitted as
    /// [`Self::fit`] fits one, with the misses summed: a card whose corners share it stays
    /// flat (one blend of its joints' motions is one affine map).
    pub fn fit_points(&self, points: &[Point], candidates: &[u32], start: &Skin) -> (Skin, f64) {
        let start_miss = self.points_miss(points, start);
        let chosen = self.closest_candidates(points, candidates, start);
        if chosen.len() < 2 {
            return (*start, start_miss);
        }
        let mut x = start_weights(&chosen, start);
        self.solve(points, &chosen, &mut x);
        let (bones, mut x) = strongest(&chosen, &x, MAX_INFLUENCES);
        if bones.len() < chosen.len() && bones.len() > 1 {
            self.solve(points, &bones, &mut x);
        }
        let skin = as_skin(&bones, &x);
        let miss = self.points_miss(points, &skin);
        if miss < start_miss {
            (skin, miss)
        } else {
            (*start, start_miss)
        }
    }

    /// [`Self::miss`] summed over `points`, all skinned by `skin`.
    fn points_miss(&self, points: &[Point], skin: &Skin) -> f64 {
        points.iter().map(|(p, t)| self.miss(*p, skin, t)).sum()
    }

    /// How far points at rest positions `rest`, each skinned by its own of `skins`, stray at
    /// most from their best common rigid motion over the fit samples: how much a card whose
    /// corners follow different blends bends (or stretches) when posed. Stops at the first
    /// sample past `enough` (returning what it found there): past it, by how much is moot.
    pub fn bend(&self, rest: &[Vec3], skins: &[Skin], enough: f32) -> f32 {
        let paths: Vec<Vec<Vec3>> = rest
            .iter()
            .zip(skins)
            .map(|(p, s)| self.path(*p, s))
            .collect();
        let mut worst = 0.0f32;
        let mut posed = vec![Vec3::ZERO; rest.len()];
        for k in 0..self.samples() {
            for (q, path) in posed.iter_mut().zip(&paths) {
                *q = path[k];
            }
            let m = rigid_fit(rest, &posed);
            for (p, q) in rest.iter().zip(&posed) {
                worst = worst.max(m.transform_point3(*p).distance(*q));
            }
            if worst > enough {
                break;
            }
        }
        worst
    }

    /// `start`'s joints, then the other candidates by how closely each alone carries
    /// `points` along their targets, at most [`MAX_CANDIDATES`] in all, without repeats.
    fn closest_candidates(&self, points: &[Point], candidates: &[u32], start: &Skin) -> Vec<u32> {
        let mut chosen: Vec<u32> = Vec::with_capacity(MAX_CANDIDATES);
        for j in 0..4 {
            if start.1[j] > 0.0 && !chosen.contains(&start.0[j]) {
                chosen.push(start.0[j]);
            }
        }
        let mut ranked: Vec<(f64, u32)> = candidates
            .iter()
            .filter(|c| !chosen.contains(c))
            .map(|&c| (self.points_miss(points, &([c; 4], [1.0, 0.0, 0.0, 0.0])), c))
            .collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        ranked.dedup_by_key(|r| r.1);
        for (_, c) in ranked {
            if chosen.len() >= MAX_CANDIDATES {
                break;
            }
            chosen.push(c);
        }
        chosen
    }

    /// Fits the weights `x` of `bones` for `points` together: the normal equations in
    /// differences from the first bone's path (the positions themselves would give the
    /// equations the tree's scale and the step no use), solved on the simplex.
    fn solve(&self, points: &[Point], bones: &[u32], x: &mut [f64]) {
        let n = bones.len();
        let mut h = vec![0.0f64; n * n];
        let mut c = vec![0.0f64; n];
        let mut d = vec![Vec3::ZERO; n];
        for (p, target) in points {
            for (k, t) in target.iter().enumerate() {
                let reference = self.moved(k, bones[0], *p);
                for (a, &b) in bones.iter().enumerate() {
                    d[a] = self.moved(k, b, *p) - reference;
                }
                let t = *t - reference;
                for a in 0..n {
                    c[a] += f64::from(d[a].dot(t));
                    for b in 0..n {
                        h[a * n + b] += f64::from(d[a].dot(d[b]));
                    }
                }
            }
        }
        solve_on_simplex(&h, &c, x);
    }
}

/// A point to fit: its rest position and the path it should follow at the fit samples.
pub type Point<'a> = (Vec3, &'a [Vec3]);

/// `start`'s weights over `bones` (zero for the others), on the simplex.
fn start_weights(bones: &[u32], start: &Skin) -> Vec<f64> {
    let mut x = vec![0.0f64; bones.len()];
    for j in 0..4 {
        if let Some(a) = bones.iter().position(|&b| b == start.0[j]) {
            x[a] += f64::from(start.1[j].max(0.0));
        }
    }
    project_to_simplex(&mut x);
    x
}

/// The `most` largest weights of `x` over `bones` (ties: the lower joint), renormalised.
fn strongest(bones: &[u32], x: &[f64], most: usize) -> (Vec<u32>, Vec<f64>) {
    let mut order: Vec<usize> = (0..bones.len()).filter(|&a| x[a] > 0.0).collect();
    order.sort_by(|&a, &b| x[b].total_cmp(&x[a]).then(bones[a].cmp(&bones[b])));
    order.truncate(most);
    if order.is_empty() {
        return (vec![bones[0]], vec![1.0]);
    }
    let total: f64 = order.iter().map(|&a| x[a]).sum();
    (
        order.iter().map(|&a| bones[a]).collect(),
        order.iter().map(|&a| x[a] / total).collect(),
    )
}

/// `x` over `bones` as a written skin: joints by falling weight, zero weights dropped, the
/// weights renormalised in `f32` to sum to one, unused slots repeating the first joint.
fn as_skin(bones: &[u32], x: &[f64]) -> Skin {
    let (bones, x) = strongest(bones, x, MAX_INFLUENCES);
    let total: f32 = x.iter().map(|&v| v as f32).sum();
    let mut skin = ([bones[0]; 4], [0.0f32; 4]);
    for (k, (&b, &v)) in bones.iter().zip(&x).enumerate() {
        skin.0[k] = b;
        skin.1[k] = v as f32 / total;
    }
    skin
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three joints translating over 16 samples: `a` along x, `b` along y, and `c` halfway
    /// between them (the blend ½ a + ½ b of their motions).
    fn swaying() -> SkinFit {
        let worlds: Vec<Vec<Mat4>> = (0..16)
            .map(|s| {
                let a = (s as f32 * 0.4).sin();
                let x = Vec3::X * a;
                let y = Vec3::Y * (0.7 * a + 0.3);
                [x, y, 0.5 * (x + y)].map(Mat4::from_translation).to_vec()
            })
            .collect();
        let rest_inv = vec![Mat4::IDENTITY; 3];
        SkinFit::new(&RigFrames {
            worlds: &worlds,
            rest_inv: &rest_inv,
        })
    }

    fn on(joint: u32) -> Skin {
        ([joint; 4], [1.0, 0.0, 0.0, 0.0])
    }

    #[test]
    fn a_vertex_halfway_between_two_swaying_joints_follows_their_blend() {
        let fit = swaying();
        let p = Vec3::new(0.3, 1.0, -0.2);
        let target = fit.path(p, &on(2));
        let (skin, miss) = fit.fit(p, &target, &[0, 1], &on(0));
        let w = |j: u32| {
            (0..4)
                .filter(|&k| skin.0[k] == j)
                .map(|k| skin.1[k])
                .sum::<f32>()
        };
        assert!(
            (w(0) - 0.5).abs() < 1e-3 && (w(1) - 0.5).abs() < 1e-3,
            "{skin:?}"
        );
        assert!((skin.1.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!(miss < 1e-6, "{miss}");
        assert!(miss < fit.miss(p, &on(0), &target));
    }

    #[test]
    fn a_vertex_on_a_kept_joint_stays_on_it() {
        let fit = swaying();
        let p = Vec3::new(-1.0, 0.5, 0.0);
        let target = fit.path(p, &on(1));
        let (skin, miss) = fit.fit(p, &target, &[0, 1, NO_BONE], &on(1));
        assert_eq!(skin, on(1));
        assert_eq!(miss, 0.0);
    }

    #[test]
    fn the_fit_never_does_worse_than_where_it_starts() {
        // Targets no blend reaches: the fit keeps the start or does better.
        let fit = swaying();
        for k in 0..20 {
            let p = Vec3::new(k as f32 * 0.1, 1.0 - k as f32 * 0.05, 0.3);
            let target: Vec<Vec3> = (0..fit.samples())
                .map(|s| p + Vec3::Z * ((s * (k + 1)) as f32).cos())
                .collect();
            for start in [on(0), on(1), on(NO_BONE)] {
                let (skin, miss) = fit.fit(p, &target, &[0, 1, 2, NO_BONE], &start);
                assert!(miss <= fit.miss(p, &start, &target), "{k}: {skin:?}");
                assert!((miss - fit.miss(p, &skin, &target)).abs() < 1e-9);
                assert!(skin.1.iter().all(|&w| w >= 0.0));
                assert!((skin.1.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn one_shared_blend_keeps_a_card_rigid_where_its_corners_blend_apart() {
        // Corners of a card on the x-moving and y-moving joints bend it; one blend for all
        // four moves it as one piece.
        let fit = swaying();
        let rest = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let apart = [on(0), on(0), on(1), on(1)];
        assert!(fit.bend(&rest, &apart, f32::INFINITY) > 0.1);
        let targets: Vec<Vec<Vec3>> = rest.iter().map(|&p| fit.path(p, &on(2))).collect();
        let points: Vec<Point> = rest
            .iter()
            .zip(&targets)
            .map(|(p, t)| (*p, t.as_slice()))
            .collect();
        let (shared, _) = fit.fit_points(&points, &[0, 1], &on(0));
        assert!(fit.bend(&rest, &[shared; 4], f32::INFINITY) < 1e-4);
    }
}
