//! Bone animation description types (spec animated-billboard-clouds §6.2, thesis §7.2): what a
//! bone's looping rotation is reduced to, how far two are apart, their weighted average (the
//! common rotation of a set of siblings) and the rotation track an average gives back.
//!
//! A bone's animation here is its delta rotation in its parent's frame, `d(s) = R(s)·R_rest⁻¹`
//! (see [`crate::model`]), so siblings with different rest orientations compare by how they
//! turn, not by how they sit.

use frond_spectral::description::{Bins, DescriptionType, Naive, NaiveDesc};
use frond_spectral::normalise::{angle_average, angle_difference, nep};
use glam::{Mat3, Quat, Vec3};
use serde::Serialize;

/// Which bone description type to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoneDescriptionKind {
    /// Axis and angle per sample (thesis §7.2), with the spec's errata.
    AxisAngle,
    /// The spectrum of the rotation vector over the loop (thesis §7.2.6, "advanced approach").
    RotationSpectral,
}

impl BoneDescriptionKind {
    /// The kind's name in command lines and reports (what [`Self::parse`] reads).
    pub fn name(self) -> &'static str {
        match self {
            BoneDescriptionKind::AxisAngle => "axis-angle",
            BoneDescriptionKind::RotationSpectral => "rotation-spectral",
        }
    }
    /// Parses [`Self::name`].
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "axis-angle" => Some(BoneDescriptionKind::AxisAngle),
            "rotation-spectral" => Some(BoneDescriptionKind::RotationSpectral),
            _ => None,
        }
    }
}

/// The interface of spec §4.1 for bone rotations.
pub trait BoneDescriptionType: Sync {
    /// One bone's description of a loop of rotations.
    type Desc: Clone + Send + Sync;
    /// The description of one loop of delta rotations (uniform samples).
    fn describe(&self, deltas: &[Quat]) -> Self::Desc;
    /// Dissimilarity ≥ 0; 0 for identical tracks.
    fn deviation(&self, a: &Self::Desc, b: &Self::Desc) -> f32;
    /// Weighted average (weights: the triangles each bone animates, thesis §7.2).
    fn average(&self, ds: &[&Self::Desc], weights: &[f32]) -> Self::Desc;
    /// The delta rotations the description stands for, at its own samples (lossless for a
    /// single bone's description, spec §6.2 "apply").
    fn apply(&self, d: &Self::Desc) -> Vec<Quat>;
}

/// Axis (unit) and angle in [0, π] of a rotation; the x axis for no rotation.
fn axis_angle(q: Quat) -> (Vec3, f32) {
    let q = if q.w < 0.0 { -q } else { q };
    let (axis, angle) = q.to_axis_angle();
    if angle.abs() < 1e-9 || !axis.is_finite() {
        (Vec3::X, 0.0)
    } else {
        (axis.normalize(), angle)
    }
}

/// The axis-angle type of thesis §7.2 with the spec's errata: samples at `(i/N)·c_t`,
/// `d_axis = 1 − |a₁·a₂|`, the cyclic angle difference, combined by `NEP` rather than the
/// product (which is 0 whenever either term is). Axes are lines: where they point opposite
/// ways one angle is negated before the angles are compared, so opposite rotations differ.
/// The axis term of a sample weighs by the smaller of the two angles: the axis of a rotation of
/// almost nothing is rounding noise, and the angle term already says both barely turn.
#[derive(Clone, Debug, Default)]
pub struct AxisAngle;

/// Per sample: unit axis and angle (the rotation taken with w ≥ 0).
#[derive(Clone, Debug, PartialEq)]
pub struct AxisAngleDesc {
    /// Per sample, the unit rotation axis (x for no rotation).
    pub axes: Vec<Vec3>,
    /// Per sample, the rotation angle about that axis, radians in [0, π].
    pub angles: Vec<f32>,
}

impl BoneDescriptionType for AxisAngle {
    type Desc = AxisAngleDesc;

    fn describe(&self, deltas: &[Quat]) -> AxisAngleDesc {
        let (axes, angles) = deltas.iter().map(|&q| axis_angle(q)).unzip();
        AxisAngleDesc { axes, angles }
    }

    fn deviation(&self, a: &AxisAngleDesc, b: &AxisAngleDesc) -> f32 {
        let n = a.axes.len().min(b.axes.len());
        if n == 0 {
            return 0.0;
        }
        let (mut axis, mut axis_w, mut phi) = (0.0f32, 0.0f32, 0.0f32);
        for s in 0..n {
            let dot = a.axes[s].dot(b.axes[s]);
            let other = if dot < 0.0 { -b.angles[s] } else { b.angles[s] };
            let w = a.angles[s].abs().min(b.angles[s].abs());
            axis += w * (1.0 - dot.abs()).max(0.0);
            axis_w += w;
            phi += angle_difference(a.angles[s], other) / std::f32::consts::PI;
        }
        let d_axis = if axis_w > 0.0 { axis / axis_w } else { 0.0 };
        nep(d_axis, phi / n as f32)
    }

    fn average(&self, ds: &[&AxisAngleDesc], weights: &[f32]) -> AxisAngleDesc {
        let n = ds.iter().map(|d| d.axes.len()).min().unwrap_or(0);
        let mut out = AxisAngleDesc {
            axes: Vec::with_capacity(n),
            angles: Vec::with_capacity(n),
        };
        for s in 0..n {
            // Best-fit line of the axes, each weighted by its bone's weight and angle.
            let mut m = Mat3::ZERO;
            for (d, &w) in ds.iter().zip(weights) {
                let a = d.axes[s];
                let k = w * d.angles[s].abs();
                m += Mat3::from_cols(a * a.x * k, a * a.y * k, a * a.z * k);
            }
            let line = frond_spectral::description::principal_axis(m);
            if line == Vec3::ZERO {
                out.axes.push(Vec3::X);
                out.angles.push(0.0);
                continue;
            }
            let signed: Vec<f32> = ds
                .iter()
                .map(|d| {
                    if d.axes[s].dot(line) < 0.0 {
                        -d.angles[s]
                    } else {
                        d.angles[s]
                    }
                })
                .collect();
            let mean = angle_average(&signed, weights).unwrap_or(0.0);
            let mean = if mean > std::f32::consts::PI {
                mean - std::f32::consts::TAU
            } else {
                mean
            };
            out.axes.push(line);
            out.angles.push(mean);
        }
        out
    }

    fn apply(&self, d: &AxisAngleDesc) -> Vec<Quat> {
        d.axes
            .iter()
            .zip(&d.angles)
            .map(|(&a, &phi)| Quat::from_axis_angle(a, phi))
            .collect()
    }
}

/// The "advanced approach" of thesis §7.2.6, engineered: the DFT of the rotation *vector*
/// (axis × angle, the logarithm of the delta rotation) per axis, compared and averaged as the
/// spectral description of spec §4.7 does (amplitude and absolute phase per axis and frequency,
/// with frequency bins, §4.10). The thesis's spherical angles of the axis need unwrapping and
/// give spurious amplitudes near the poles; the rotation vector is continuous for rotations
/// under a half turn (any wind) and has no poles. Absolute phases, not the axis-phase type's
/// relative ones: siblings' time offsets are real differences here, and relative phases have
/// no reference on a bone that does not turn about x at all. The mean (the DC term, a constant
/// bend) is kept apart and compared in radians.
#[derive(Clone, Debug)]
pub struct RotationSpectral {
    /// The spectral type comparing and averaging the rotation vector's motion.
    pub motion: Naive,
}

impl RotationSpectral {
    /// With `bins` frequency bins per comparison (spec §4.10).
    pub fn new(bins: usize) -> Self {
        RotationSpectral {
            motion: Naive::with_bins(Bins::PerPair(bins.max(1))),
        }
    }
}

/// Mean rotation vector and the naive spectral description of its zero-mean motion.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationSpectralDesc {
    /// The rotation vector's mean over the loop (a constant bend), radians.
    pub mean: Vec3,
    /// The naive spectral description of the zero-mean motion around it.
    pub motion: NaiveDesc,
}

impl BoneDescriptionType for RotationSpectral {
    type Desc = RotationSpectralDesc;

    fn describe(&self, deltas: &[Quat]) -> RotationSpectralDesc {
        let vectors: Vec<Vec3> = deltas
            .iter()
            .map(|&q| {
                let (axis, angle) = axis_angle(q);
                axis * angle
            })
            .collect();
        let mean = vectors.iter().sum::<Vec3>() / vectors.len().max(1) as f32;
        RotationSpectralDesc {
            mean,
            motion: self.motion.describe(&vectors),
        }
    }

    fn deviation(&self, a: &RotationSpectralDesc, b: &RotationSpectralDesc) -> f32 {
        nep(
            self.motion.deviation(&a.motion, &b.motion),
            a.mean.distance(b.mean) / std::f32::consts::PI,
        )
    }

    fn average(&self, ds: &[&RotationSpectralDesc], weights: &[f32]) -> RotationSpectralDesc {
        let total: f32 = weights.iter().sum();
        let mean = if total > 0.0 {
            ds.iter()
                .zip(weights)
                .map(|(d, &w)| d.mean * w)
                .sum::<Vec3>()
                / total
        } else {
            Vec3::ZERO
        };
        let motions: Vec<&NaiveDesc> = ds.iter().map(|d| &d.motion).collect();
        RotationSpectralDesc {
            mean,
            motion: self.motion.average(&motions, weights),
        }
    }

    fn apply(&self, d: &RotationSpectralDesc) -> Vec<Quat> {
        let n = self.motion.samples(&d.motion);
        self.motion
            .apply(&d.motion, n)
            .into_iter()
            .map(|v| Quat::from_scaled_axis(d.mean + v))
            .collect()
    }
}
