//! A cloud's billboard motion as textures: vertex animation textures of every billboard's rigid
//! transform over the loop (Houdini VAT 3.0 rigid layout, [`crate::vat`]), or each billboard's
//! own spectral motion as a few cosine terms ([`crate::spectral`], spec animated-billboard-clouds
//! §4.11 "runtime").

use std::collections::BTreeMap;

use frond_lod::cloud_build::sampled_worlds;
use frond_lod::contract::SpectralMotion;
use frond_lod::{AnimatedBillboardCloud, RigidMotion};
use frond_scene::Tree;

use crate::ExportError;
use crate::spectral::{SpectralTerm, SpectralTextures, encode_spectral};
use crate::vat::{
    RigidFrame, RigidPiece, VatFormat, VatOptions, VatSpace, VatTextures, encode_rigid_with,
};

/// Vertex animation textures of every billboard over the clock's samples, baked in `space`;
/// textures are named `<stem>_pos.<ext>` and `<stem>_rot.<ext>`.
pub fn vat_textures(
    cloud: &AnimatedBillboardCloud,
    format: VatFormat,
    stem: &str,
    space: VatSpace,
) -> Result<VatTextures, ExportError> {
    let worlds = sampled_worlds(&cloud.rig, &cloud.clock);
    let rest_inv = cloud.rest_inverse();
    let n = worlds.len();
    let pieces: Vec<RigidPiece> = cloud
        .billboards
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let pivot = b.quad.center;
            let frames = (0..n)
                .map(|s| {
                    let carry = cloud.transform_at(i, &worlds[s], &rest_inv, s, n);
                    let (_, r, _) = carry.to_scale_rotation_translation();
                    RigidFrame {
                        position: carry.transform_point3(pivot),
                        rotation: r.normalize(),
                    }
                })
                .collect();
            RigidPiece { pivot, frames }
        })
        .collect();
    let fps = if cloud.clock.period > 0.0 {
        n as f32 / cloud.clock.period
    } else {
        1.0
    };
    Ok(encode_rigid_with(
        &pieces,
        fps,
        format,
        &VatOptions {
            file_stem: stem.to_string(),
            space,
            clip: cloud
                .clock
                .clip
                .and_then(|c| cloud.rig.clips.get(c))
                .map(|c| c.name.clone()),
            start_s: cloud.clock.start,
            ..Default::default()
        },
    )?)
}

/// The spectral coefficient texture of a cloud (None when no billboard has own motion); an
/// error when a billboard's motion is sampled rather than spectral (the `static` method).
pub fn spectral_textures(
    cloud: &AnimatedBillboardCloud,
    tree: &Tree,
    file: &str,
) -> Result<Option<SpectralTextures>, ExportError> {
    let mut rows = Vec::with_capacity(cloud.billboards.len());
    for b in &cloud.billboards {
        rows.push(match &b.motion {
            None => Vec::new(),
            Some(RigidMotion::Spectral(m)) => spectral_terms(m),
            Some(RigidMotion::Sampled(_)) => {
                return Err(ExportError::NoSpectralForm(cloud.method.clone()));
            }
        });
    }
    if rows.iter().all(Vec::is_empty) {
        return Ok(None);
    }
    let clip = cloud.clock.clip.map(|c| tree.rig.clips[c].name.clone());
    Ok(Some(encode_spectral(
        &rows,
        cloud.clock.period,
        cloud.clock.start,
        clip,
        file,
    )?))
}

/// A spectral motion's terms merged by frequency over the three axes (phases in loop
/// fractions: `cos(2π f s/N + φ)` at sample `s` is `cos(2π f u + φ)` at `u = s/N`).
pub fn spectral_terms(m: &SpectralMotion) -> Vec<SpectralTerm> {
    let mut by_freq: BTreeMap<usize, SpectralTerm> = Default::default();
    for (c, axis) in m.axes.iter().enumerate() {
        for ((&f, &a), &p) in axis
            .frequencies
            .iter()
            .zip(&axis.amplitudes)
            .zip(&axis.phases)
        {
            let t = by_freq.entry(f).or_insert(SpectralTerm {
                frequency: f as f32,
                amplitude: [0.0; 3],
                phase: [0.0; 3],
            });
            // Two terms of one frequency on one axis add as phasors.
            let (x, y) = (
                t.amplitude[c] * t.phase[c].cos() + a * p.cos(),
                t.amplitude[c] * t.phase[c].sin() + a * p.sin(),
            );
            t.amplitude[c] = x.hypot(y);
            t.phase[c] = y.atan2(x);
        }
    }
    by_freq.into_values().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_spectral::description::Components;

    #[test]
    fn spectral_terms_evaluate_like_the_motion() {
        let axis = |f: Vec<usize>, a: Vec<f32>, p: Vec<f32>| Components {
            frequencies: f,
            amplitudes: a,
            phases: p,
        };
        // Two terms of frequency 2 on x (they add as phasors), one shared with y, one z only.
        let m = SpectralMotion {
            axes: [
                axis(vec![2, 2, 5], vec![0.3, 0.2, 0.1], vec![0.5, -1.0, 2.0]),
                axis(vec![5], vec![0.4], vec![-2.5]),
                axis(vec![1], vec![0.7], vec![0.0]),
            ],
            samples: 24,
        };
        let terms = spectral_terms(&m);
        let freqs: Vec<f32> = terms.iter().map(|t| t.frequency).collect();
        assert_eq!(freqs, vec![1.0, 2.0, 5.0]);
        for s in 0..24 {
            let want = m.offset(s as f32);
            let got = crate::spectral::evaluate(&terms, s as f32 / 24.0);
            for c in 0..3 {
                assert!((want[c] - got[c]).abs() < 1e-5, "sample {s} axis {c}");
            }
        }
    }
}
