//! Best rigid motion between two point sets (least squares), by Horn's closed-form quaternion
//! method: the rotation is the eigenvector of the largest eigenvalue of a symmetric 4×4 matrix.
//! Used to give a billboard the rigid motion of the triangles it replaces (thesis §5.2.2,
//! spec animated-billboard-clouds §1.4: billboards move rigidly). Written here rather than
//! pulling in a linear-algebra crate for one 4×4 eigenproblem.

use glam::{Affine3A, DQuat, DVec3, Quat, Vec3};

/// The rotation and translation that move `from` onto `to` with the least summed squared
/// distance. Returns the identity for empty input; collinear input gives one of the optimal
/// rotations.
pub fn rigid_fit(from: &[Vec3], to: &[Vec3]) -> Affine3A {
    let n = from.len().min(to.len());
    if n == 0 {
        return Affine3A::IDENTITY;
    }
    let inv = 1.0 / n as f64;
    let ca = from[..n].iter().map(|p| p.as_dvec3()).sum::<DVec3>() * inv;
    let cb = to[..n].iter().map(|p| p.as_dvec3()).sum::<DVec3>() * inv;
    let s = cross_covariance(
        from[..n]
            .iter()
            .zip(&to[..n])
            .map(|(a, b)| (a.as_dvec3() - ca, b.as_dvec3() - cb, 1.0)),
    );
    let rot = horn_rotation(s);
    let t = cb - rot * ca;
    Affine3A::from_rotation_translation(rot.as_quat(), t.as_vec3())
}

/// The rotation `R` about the fixed point `pivot` that moves `from` onto `to` with the least
/// weighted summed squared distance, `Σ w |pivot + R(a − pivot) − b|²`: Horn's method without
/// the centroid step (a joint turning about its pivot, spec animated-billboard-clouds §6.3
/// "joint animation"). Identity for empty or all-zero-weight input.
pub fn pivot_rotation_fit(pivot: Vec3, from: &[Vec3], to: &[Vec3], weights: &[f32]) -> Quat {
    let p = pivot.as_dvec3();
    let s = cross_covariance(
        from.iter()
            .zip(to)
            .zip(weights)
            .map(|((a, b), &w)| (a.as_dvec3() - p, b.as_dvec3() - p, f64::from(w))),
    );
    horn_rotation(s).as_quat()
}

/// `Σ w a bᵀ` over centred pairs.
fn cross_covariance(pairs: impl Iterator<Item = (DVec3, DVec3, f64)>) -> [[f64; 3]; 3] {
    let mut s = [[0.0f64; 3]; 3];
    for (a, b, w) in pairs {
        let (a, b) = ((a * w).to_array(), b.to_array());
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] += a[i] * b[j];
            }
        }
    }
    s
}

/// The rotation maximising `Σ b·R a` from the cross-covariance (Horn's symmetric 4×4 matrix).
fn horn_rotation(s: [[f64; 3]; 3]) -> DQuat {
    let [[sxx, sxy, sxz], [syx, syy, syz], [szx, szy, szz]] = s;
    let m = [
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ];
    let q = largest_eigenvector(m);
    let rot = DQuat::from_xyzw(q[1], q[2], q[3], q[0]).normalize();
    if rot.is_finite() {
        rot
    } else {
        DQuat::IDENTITY
    }
}

/// Eigenvector of the largest eigenvalue of a symmetric 4×4 matrix (cyclic Jacobi rotations).
fn largest_eigenvector(mut a: [[f64; 4]; 4]) -> [f64; 4] {
    let mut v = [[0.0f64; 4]; 4];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        let scale: f64 = (0..4).map(|i| a[i][i] * a[i][i]).sum::<f64>() + off;
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (rp, rq) = (a[p], a[q]);
                for k in 0..4 {
                    a[p][k] = c * rp[k] - s * rq[k];
                    a[q][k] = s * rp[k] + c * rq[k];
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let best = (0..4)
        .max_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(0);
    [v[0][best], v[1][best], v[2][best], v[3][best]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn cloud() -> Vec<Vec3> {
        (0..20)
            .map(|i| {
                let f = i as f32;
                Vec3::new((f * 1.3).sin() * 2.0, (f * 0.7).cos(), f * 0.1 - 1.0)
            })
            .collect()
    }

    #[test]
    fn recovers_a_known_motion() {
        let from = cloud();
        let truth = Affine3A::from_rotation_translation(
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 2.1),
            Vec3::new(3.0, -1.0, 0.5),
        );
        let to: Vec<Vec3> = from.iter().map(|p| truth.transform_point3(*p)).collect();
        let fit = rigid_fit(&from, &to);
        for (a, b) in from.iter().zip(&to) {
            assert!(fit.transform_point3(*a).distance(*b) < 1e-5);
        }
    }

    #[test]
    fn planar_triangle_and_half_turn() {
        // Three points (one leaf card) rotated by π about z: the hardest case for quaternion
        // eigen-solvers (two equal eigenvalues appear for some inputs).
        let from = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let truth = Affine3A::from_rotation_translation(
            Quat::from_rotation_z(std::f32::consts::PI),
            Vec3::new(0.0, 0.0, 1.0),
        );
        let to: Vec<Vec3> = from.iter().map(|p| truth.transform_point3(*p)).collect();
        let fit = rigid_fit(&from, &to);
        for (a, b) in from.iter().zip(&to) {
            assert!(fit.transform_point3(*a).distance(*b) < 1e-5, "{a} -> {b}");
        }
    }

    #[test]
    fn identity_and_empty() {
        let p = cloud();
        let fit = rigid_fit(&p, &p);
        assert!(fit.abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        assert_eq!(rigid_fit(&[], &[]), Affine3A::IDENTITY);
    }

    #[test]
    fn least_squares_on_noisy_points() {
        // A rigid motion plus zero-mean noise: the fit stays within the noise of the truth.
        let from = cloud();
        let truth = Affine3A::from_rotation_translation(Quat::from_rotation_y(0.4), Vec3::ONE);
        let to: Vec<Vec3> = from
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let noise = if i % 2 == 0 { 0.01 } else { -0.01 };
                truth.transform_point3(*p) + Vec3::splat(noise)
            })
            .collect();
        let fit = rigid_fit(&from, &to);
        for a in &from {
            assert!(
                fit.transform_point3(*a)
                    .distance(truth.transform_point3(*a))
                    < 0.03
            );
        }
    }
}
