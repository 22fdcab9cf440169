//! The animation metrics of spec animated-billboard-clouds §5.5 on one pair of trajectories
//! (an original triangle's centre and where its billboard carries it), with the frequency-bin
//! improvement (§4.10) and the product erratum of §4.8 fixed.

use frond_spectral::{Spectrum, amplitude_distance, dominating_axis};
use glam::Vec3;

use crate::normalise::{ne, nep};

/// Both dominating-axis metrics of one trajectory pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisMetrics {
    /// `NEP(1 − a_t·a_b, amplitudeDistance)`: the erratum-fixed dominating-axis metric (0 only
    /// when both the axes and the spectra agree; the thesis' product was 0 when either did).
    pub dominating_axis: f32,
    /// `NE(amplitudeDistance)`: 0 for congruent motions, whatever their axes.
    pub dominating_axis_spectral: f32,
}

/// The metrics of `original` vs `simplified` (same number of uniform samples over one loop);
/// `bins` frequency bins for the amplitude distance (e.g. the skeleton depth).
pub fn axis_metrics(original: &[Vec3], simplified: &[Vec3], bins: usize) -> AxisMetrics {
    let t = dominating_axis(original);
    let b = dominating_axis(simplified);
    let mut dot = t.axis.dot(b.axis);
    // Flip one axis when they point apart (and its motion with it: amplitudes do not care).
    if dot < 0.0 {
        dot = -dot;
    }
    let xt = Spectrum::of(&t.motion);
    let xb = Spectrum::of(&b.motion);
    let distance = amplitude_distance(&xt.amplitudes, &xb.amplitudes, bins);
    // A still trajectory has no axis: both still is perfect, one still compares spectra only.
    let axis_error = if t.axis == Vec3::ZERO || b.axis == Vec3::ZERO {
        0.0
    } else {
        (1.0 - dot).max(0.0)
    };
    AxisMetrics {
        dominating_axis: nep(axis_error, distance),
        dominating_axis_spectral: ne(distance),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use std::f32::consts::TAU;

    fn sway(n: usize, offset: f32, dir: Vec3) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let t = TAU * i as f32 / n as f32 + offset;
                Vec3::new(1.0, 2.0, 3.0) + dir * (2.0 * t.sin() + 0.5 * (3.0 * t).sin())
            })
            .collect()
    }

    #[test]
    fn time_offset_equal_trajectories_score_zero() {
        let a = sway(64, 0.0, Vec3::X);
        let b = sway(64, 1.3, Vec3::X);
        let m = axis_metrics(&a, &b, 4);
        assert!(m.dominating_axis_spectral < 1e-4, "{m:?}");
        assert!(m.dominating_axis < 1e-4, "{m:?}");
    }

    #[test]
    fn rotation_is_seen_by_the_axis_metric_only() {
        let a = sway(64, 0.0, Vec3::X);
        let dir = Quat::from_rotation_z(1.0) * Vec3::X;
        let b = sway(64, 0.0, dir);
        let m = axis_metrics(&a, &b, 4);
        assert!(m.dominating_axis_spectral < 1e-4);
        // 1 − cos 1 with equal spectra: NEP(1 − cos 1, 0) = NE(1 − cos 1).
        let want = ne(1.0 - 1f32.cos());
        assert!((m.dominating_axis - want).abs() < 1e-3, "{m:?} vs {want}");
    }

    #[test]
    fn different_amplitude_is_seen_by_both() {
        let a = sway(64, 0.0, Vec3::Y);
        let b: Vec<Vec3> = sway(64, 0.0, Vec3::Y).iter().map(|p| *p * 1.0).collect();
        let c = sway(64, 0.0, Vec3::Y * 2.0);
        assert!(axis_metrics(&a, &b, 4).dominating_axis_spectral < 1e-4);
        let m = axis_metrics(&a, &c, 4);
        assert!(
            m.dominating_axis_spectral > 0.5 && m.dominating_axis > 0.5,
            "{m:?}"
        );
        let still = vec![Vec3::ONE; 64];
        assert_eq!(axis_metrics(&still, &still, 4).dominating_axis, 0.0);
    }
}
