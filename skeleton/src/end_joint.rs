//! The common end joint of two collapsed siblings (spec animated-billboard-clouds §6.3, thesis
//! §7.3.1–7.3.2): the point `j` minimising
//! `E_T = Σ_tr Σ_n [ r_tr² − |p_n − j|² ]²` over the centre trajectories `p_n` of the foliage
//! the two bones' children animate.
//!
//! \[ENG\] erratum: the thesis fixes `r = |j − c|` (`c` the trajectory's centroid). The centroid
//! of an arc lies inside it, not on the sphere, so even leaves turning exactly about one point
//! leave a residual there and the minimiser misses the point. Here each trajectory's radius is
//! free: the optimal `r_tr²` is the mean of `|p_n − j|²`, and eliminating it leaves
//! `r² − |p_n − j|² = (mean|p|² − |p_n|²) − 2 j·(c − p_n)`, still linear in `j`: `E_T` is a
//! convex quadratic whose minimiser is exact for pure rotations about one point. Every
//! (trajectory, sample) adds a row `a = 2(c − p_n)` with target `b = mean|p|² − |p_n|²`; the
//! 3×3 normal equations are summed here (additively: a pair's sums are its two bones' sums) and
//! solved, regularised toward a guess (the children's pivots) where motion is tiny or planar.

use glam::{DMat3, DVec3, Vec3};

/// Relative regularisation toward the guess: `λ = REGULARISATION · trace(AᵀA) / 3`.
pub const REGULARISATION: f64 = 1e-6;

/// Summed normal equations of `E_T` (weights scale a trajectory's rows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndJointSums {
    /// `Σ w a aᵀ`.
    pub ata: DMat3,
    /// `Σ w a b`.
    pub atb: DVec3,
    /// `Σ w b²`.
    pub bb: f64,
    /// Trajectories' total weight.
    pub weight: f64,
}

impl Default for EndJointSums {
    /// No rows (glam's matrix default is the identity, not zero).
    fn default() -> Self {
        EndJointSums {
            ata: DMat3::ZERO,
            atb: DVec3::ZERO,
            bb: 0.0,
            weight: 0.0,
        }
    }
}

impl EndJointSums {
    /// Adds one centre trajectory (uniform samples of one loop) with `weight`.
    pub fn add_trajectory(&mut self, p: &[Vec3], weight: f64) {
        if p.is_empty() {
            return;
        }
        let c = p.iter().map(|v| v.as_dvec3()).sum::<DVec3>() / p.len() as f64;
        let c2 = p.iter().map(|v| v.as_dvec3().length_squared()).sum::<f64>() / p.len() as f64;
        for v in p {
            let v = v.as_dvec3();
            let a = 2.0 * (c - v);
            let b = c2 - v.length_squared();
            self.ata += DMat3::from_cols(a * a.x, a * a.y, a * a.z) * weight;
            self.atb += a * (b * weight);
            self.bb += b * b * weight;
        }
        self.weight += weight;
    }

    /// The sums of both.
    pub fn plus(&self, other: &EndJointSums) -> EndJointSums {
        EndJointSums {
            ata: self.ata + other.ata,
            atb: self.atb + other.atb,
            bb: self.bb + other.bb,
            weight: self.weight + other.weight,
        }
    }

    /// `E_T` at `j`: `Σb² − 2 j·Aᵀb + jᵀ AᵀA j`.
    pub fn error_at(&self, j: DVec3) -> f64 {
        (self.bb - 2.0 * j.dot(self.atb) + j.dot(self.ata * j)).max(0.0)
    }

    /// The minimiser of `E_T` (regularised toward `guess`) and `E_T` there.
    pub fn solve(&self, guess: DVec3) -> (DVec3, f64) {
        let trace = self.ata.x_axis.x + self.ata.y_axis.y + self.ata.z_axis.z;
        let lambda = REGULARISATION * trace / 3.0 + 1e-300;
        let m = self.ata + DMat3::from_diagonal(DVec3::splat(lambda));
        let det = m.determinant();
        let j = if det.is_finite() && det.abs() > 1e-300 {
            m.inverse() * (self.atb + guess * lambda)
        } else {
            guess
        };
        let j = if j.is_finite() { j } else { guess };
        (j, self.error_at(j))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// `E_T` evaluated from its definition, each trajectory's radius at its optimum (the mean
    /// of `|p_n − j|²`).
    fn direct(trajs: &[Vec<Vec3>], j: DVec3) -> f64 {
        trajs
            .iter()
            .map(|p| {
                let r2 = p
                    .iter()
                    .map(|v| (v.as_dvec3() - j).length_squared())
                    .sum::<f64>()
                    / p.len() as f64;
                p.iter()
                    .map(|v| {
                        let e = r2 - (v.as_dvec3() - j).length_squared();
                        e * e
                    })
                    .sum::<f64>()
            })
            .sum()
    }

    fn swinging(pivot: Vec3, arm: Vec3, axis: Vec3, amp: f32, phase: f32) -> Vec<Vec3> {
        (0..32)
            .map(|s| {
                let t = std::f32::consts::TAU * s as f32 / 32.0;
                pivot + Quat::from_axis_angle(axis.normalize(), amp * (t + phase).sin()) * arm
            })
            .collect()
    }

    #[test]
    fn sums_reproduce_the_definition() {
        let trajs = vec![
            swinging(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.0), Vec3::Z, 0.3, 0.0),
            swinging(Vec3::ONE, Vec3::new(0.0, 1.5, 0.5), Vec3::X, 0.2, 1.0),
        ];
        let mut sums = EndJointSums::default();
        for t in &trajs {
            sums.add_trajectory(t, 1.0);
        }
        for j in [DVec3::ZERO, DVec3::new(0.3, -1.0, 2.0)] {
            let (a, b) = (sums.error_at(j), direct(&trajs, j));
            assert!((a - b).abs() <= 1e-9 * b.max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn closed_form_matches_a_numerical_minimiser() {
        // Leaves swinging about three different pivots with different axes: no exact sphere
        // centre, a genuine least-squares optimum.
        let trajs = vec![
            swinging(
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.2),
                Vec3::Z,
                0.4,
                0.0,
            ),
            swinging(
                Vec3::new(0.2, 1.1, 0.1),
                Vec3::new(-0.5, 1.2, 0.4),
                Vec3::X,
                0.3,
                0.7,
            ),
            swinging(
                Vec3::new(-0.1, 0.9, 0.3),
                Vec3::new(0.3, 0.8, -0.9),
                Vec3::new(1.0, 0.0, 1.0),
                0.5,
                2.0,
            ),
        ];
        let mut sums = EndJointSums::default();
        for t in &trajs {
            sums.add_trajectory(t, 1.0);
        }
        let (j, e) = sums.solve(DVec3::ZERO);
        // Gradient descent with backtracking on the definition, from far away.
        let mut x = DVec3::new(3.0, -2.0, 1.0);
        let mut step = 1e-3;
        for _ in 0..20000 {
            let h = 1e-6;
            let f = direct(&trajs, x);
            let g = DVec3::new(
                direct(&trajs, x + DVec3::X * h) - f,
                direct(&trajs, x + DVec3::Y * h) - f,
                direct(&trajs, x + DVec3::Z * h) - f,
            ) / h;
            loop {
                let next = x - g * step;
                if direct(&trajs, next) < f {
                    x = next;
                    step *= 1.2;
                    break;
                }
                step *= 0.5;
                if step < 1e-15 {
                    break;
                }
            }
        }
        assert!(j.distance(x) < 1e-3, "closed form {j} vs numerical {x}");
        assert!(e <= direct(&trajs, x) * (1.0 + 1e-6) + 1e-12);
    }

    #[test]
    fn leaves_turning_about_one_point_find_it() {
        let pivot = Vec3::new(0.5, 2.0, -0.3);
        let trajs = vec![
            swinging(pivot, Vec3::new(1.0, 1.0, 0.0), Vec3::Z, 0.4, 0.0),
            swinging(pivot, Vec3::new(0.0, 1.0, 1.0), Vec3::X, 0.3, 1.0),
            swinging(pivot, Vec3::new(-1.0, 0.5, 0.5), Vec3::Y, 0.3, 2.0),
        ];
        let mut sums = EndJointSums::default();
        for t in &trajs {
            sums.add_trajectory(t, 1.0);
        }
        let (j, e) = sums.solve(DVec3::ZERO);
        // Exact with a free radius per trajectory (the thesis's r = |j − c| misses it).
        assert!(j.distance(pivot.as_dvec3()) < 1e-4, "{j}");
        assert!(e < 1e-8, "{e}");
    }

    #[test]
    fn no_motion_falls_back_to_the_guess() {
        let still = vec![Vec3::new(1.0, 2.0, 3.0); 16];
        let mut sums = EndJointSums::default();
        sums.add_trajectory(&still, 1.0);
        let guess = DVec3::new(0.5, 0.5, 0.5);
        let (j, e) = sums.solve(guess);
        assert_eq!(j, guess);
        assert_eq!(e, 0.0);
    }
}
