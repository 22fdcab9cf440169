//! Normalisation tools of the thesis' App. A (spec animated-billboard-clouds §5.1): map
//! unbounded errors into [0, 1) and combine them, and handle cyclic quantities (angles).

/// NE(a) = 1 − 1/(1 + a) for a ≥ 0 (A.1); negative input counts as 0.
pub fn ne(a: f32) -> f32 {
    let a = a.max(0.0);
    1.0 - 1.0 / (1.0 + a)
}

/// NEP(a, b) = 1 − 1/(1 + a) · 1/(1 + b) (A.2): large when either is large.
pub fn nep(a: f32, b: f32) -> f32 {
    wnep(a, b, 1.0, 1.0)
}

/// WNEP(a, b, w_a, w_b) = 1 − 1/(1 + a·w_a) · 1/(1 + b·w_b) (A.3).
pub fn wnep(a: f32, b: f32, wa: f32, wb: f32) -> f32 {
    1.0 - 1.0 / (1.0 + (a * wa).max(0.0)) / (1.0 + (b * wb).max(0.0))
}

/// Difference of two angles (radians) as the angle between their unit vectors, in [0, π]
/// (A.4): 0.1 and 2π − 0.1 differ by 0.2.
pub fn angle_difference(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::TAU);
    d.min(std::f32::consts::TAU - d)
}

/// Weighted average of angles as the angle of the weighted sum of their unit vectors (A.4),
/// in [0, 2π); None when the vectors cancel (no defined average).
pub fn angle_average(angles: &[f32], weights: &[f32]) -> Option<f32> {
    let (mut x, mut y, mut total) = (0.0f64, 0.0f64, 0.0f64);
    for (a, w) in angles.iter().zip(weights) {
        x += f64::from(*w) * f64::from(*a).cos();
        y += f64::from(*w) * f64::from(*a).sin();
        total += f64::from(*w).abs();
    }
    // Cancelled up to f32 angle rounding.
    if x.hypot(y) <= 1e-6 * total {
        return None;
    }
    Some((y.atan2(x) as f32).rem_euclid(std::f32::consts::TAU))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        assert_eq!(ne(0.0), 0.0);
        assert!((ne(1.0) - 0.5).abs() < 1e-7);
        assert!((nep(1.0, 1.0) - 0.75).abs() < 1e-7);
        assert_eq!(nep(0.0, 0.0), 0.0);
        assert!((wnep(1.0, 1.0, 2.0, 0.0) - (1.0 - 1.0 / 3.0)).abs() < 1e-6);
        assert!((angle_difference(0.1, std::f32::consts::TAU - 0.1) - 0.2).abs() < 1e-5);
        // 110° and 330° average to 40° (App. A.4's example).
        let avg = angle_average(&[110f32.to_radians(), 330f32.to_radians()], &[1.0, 1.0])
            .expect("defined");
        assert!(
            (avg.to_degrees() - 40.0).abs() < 1e-3,
            "{}",
            avg.to_degrees()
        );
        assert_eq!(
            angle_average(&[0.0, std::f32::consts::PI], &[1.0, 1.0]),
            None
        );
    }
}
