//! The dominating movement axis of a trajectory (spec animated-billboard-clouds §4.8, §5.1.4):
//! the line through the two samples farthest apart (brute force over all pairs, as the thesis
//! does), and the 1-D motion along it, centred on its mean.

use glam::Vec3;

/// A trajectory reduced to its dominating axis.
#[derive(Clone, Debug, PartialEq)]
pub struct DominatingAxis {
    /// Unit axis (zero for a trajectory that does not move). Its sign is fixed so that the
    /// first component of largest magnitude is positive, so equal lines give equal axes.
    pub axis: Vec3,
    /// Position of each sample along the axis, relative to the mean.
    pub motion: Vec<f32>,
}

/// The dominating axis of `samples` (one loop, uniform samples).
pub fn dominating_axis(samples: &[Vec3]) -> DominatingAxis {
    let mut best = (0.0f32, Vec3::ZERO);
    for (i, a) in samples.iter().enumerate() {
        for b in &samples[i + 1..] {
            let d = *b - *a;
            let l = d.length_squared();
            if l > best.0 {
                best = (l, d);
            }
        }
    }
    let mut axis = best.1.normalize_or_zero();
    // The first component of largest magnitude decides the sign.
    let mut largest = 0.0f32;
    for c in axis.to_array() {
        if c.abs() > largest.abs() {
            largest = c;
        }
    }
    if largest < 0.0 {
        axis = -axis;
    }
    let along: Vec<f32> = samples.iter().map(|p| p.dot(axis)).collect();
    let mean = if along.is_empty() {
        0.0
    } else {
        along.iter().sum::<f32>() / along.len() as f32
    };
    DominatingAxis {
        axis,
        motion: along.iter().map(|x| x - mean).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::TAU;

    #[test]
    fn a_line_motion_gives_its_direction_and_centred_sine() {
        let dir = Vec3::new(1.0, 2.0, -2.0).normalize();
        let samples: Vec<Vec3> = (0..32)
            .map(|i| Vec3::new(5.0, 1.0, 0.0) + dir * 3.0 * (TAU * i as f32 / 32.0).sin())
            .collect();
        let d = dominating_axis(&samples);
        assert!(d.axis.abs_diff_eq(-dir, 1e-5) || d.axis.abs_diff_eq(dir, 1e-5));
        assert!(
            d.axis.abs_diff_eq(dir, 1e-5),
            "sign rule: first largest component positive"
        );
        let max = d.motion.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        assert!((max - 3.0).abs() < 1e-3);
        assert!(d.motion.iter().sum::<f32>().abs() < 1e-3);
    }

    #[test]
    fn still_and_empty() {
        let d = dominating_axis(&[Vec3::ONE; 4]);
        assert_eq!(d.axis, Vec3::ZERO);
        assert!(d.motion.iter().all(|x| *x == 0.0));
        assert!(dominating_axis(&[]).motion.is_empty());
    }
}
