//! `--animation spectral`: every billboard's own motion as the few cosines SCA kept (spec
//! animated-billboard-clouds §4.11 "runtime"), in one small float texture and a sidecar, played
//! by one shared vertex program (`shaders/frond_spectral.{wgsl,glsl,hlsl}`) that evaluates the
//! inverse DFT and translates the quad, before skinning to the bone it follows.
//!
//! Layout (EXR, RGBA half floats, row 0 on top): row `r` is billboard `r`; its term `j` takes
//! two texels, `(2j, r) = (f, a_x, a_y, a_z)` and `(2j+1, r) = (φ_x, φ_y, φ_z, 0)`, and adds
//! `a_c · cos(2π f u + φ_c)` to coordinate `c`, `u = (t − start) / period` the loop fraction.
//! Unused terms are zero. The billboard's row is in `TEXCOORD_1.x` as `(r + 0.5) / height`
//! (the u channel: engines that flip v on import leave it alone).

use serde::{Deserialize, Serialize};

use crate::vat::{VatError, VatImage, write_exr_half};

/// The `layout` field of the sidecar.
pub const SPECTRAL_LAYOUT: &str = "frond-spectral-1: row = billboard; texel 2j = (f, ax, ay, az), \
texel 2j+1 = (phx, phy, phz, 0); offset_c = sum_j a_c cos(2 pi f u + ph_c), u = loop fraction";

/// One cosine term of a billboard's translation: the same frequency on all three axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralTerm {
    /// Cycles per loop.
    pub frequency: f32,
    pub amplitude: [f32; 3],
    pub phase: [f32; 3],
}

/// The sidecar written beside the texture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectralSidecar {
    /// Always [`SPECTRAL_LAYOUT`].
    pub layout: String,
    pub texture: String,
    pub width: u32,
    pub height: u32,
    pub billboards: u32,
    /// Terms per billboard the texture has room for (width / 2).
    pub terms: u32,
    /// Non-zero terms over all billboards.
    pub terms_used: u32,
    /// Loop length and start, seconds, of the clip the motion was sampled from.
    pub period_s: f32,
    pub start_s: f32,
    pub clip: Option<String>,
    /// Always "TEXCOORD_1.x = (row + 0.5) / height".
    pub row_channel: String,
    /// Always "added to the vertex position before skinning (the followed bone's rest frame)".
    pub space: String,
    pub bytes: usize,
}

/// The encoded texture and its sidecar.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralTextures {
    pub image: VatImage,
    pub sidecar: SpectralSidecar,
    /// Per billboard: the value of `TEXCOORD_1` on its four corners.
    pub row_uv: Vec<[f32; 2]>,
}

/// Encodes `billboards[r]`'s terms into row `r` (an empty list: a billboard without own motion).
pub fn encode_spectral(
    billboards: &[Vec<SpectralTerm>],
    period_s: f32,
    start_s: f32,
    clip: Option<String>,
    file: &str,
) -> Result<SpectralTextures, VatError> {
    if billboards.is_empty() {
        return Err(VatError::NoPieces);
    }
    let terms = billboards.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let width = 2 * terms as u32;
    let height = billboards.len() as u32;
    if height > crate::vat::MAX_TEXTURE_SIZE || width > crate::vat::MAX_TEXTURE_SIZE {
        return Err(VatError::TooLarge {
            pieces: billboards.len(),
            frames: terms,
            width: u64::from(width),
            height: u64::from(height),
            max: crate::vat::MAX_TEXTURE_SIZE,
        });
    }
    let mut texels = vec![[0.0f32; 4]; (width * height) as usize];
    for (r, list) in billboards.iter().enumerate() {
        for (j, t) in list.iter().enumerate() {
            let values = [
                t.frequency,
                t.amplitude[0],
                t.amplitude[1],
                t.amplitude[2],
                t.phase[0],
                t.phase[1],
                t.phase[2],
            ];
            if let Some(v) = values.iter().find(|v| !v.is_finite() || v.abs() > 65504.0) {
                return Err(VatError::OutOfHalfRange {
                    piece: r,
                    frame: j,
                    value: *v,
                });
            }
            let base = r * width as usize + 2 * j;
            texels[base] = [t.frequency, t.amplitude[0], t.amplitude[1], t.amplitude[2]];
            texels[base + 1] = [t.phase[0], t.phase[1], t.phase[2], 0.0];
        }
    }
    let bytes = write_exr_half(width, height, &texels);
    let row_uv = (0..height)
        .map(|r| [(r as f32 + 0.5) / height as f32, 0.0])
        .collect();
    Ok(SpectralTextures {
        sidecar: SpectralSidecar {
            layout: SPECTRAL_LAYOUT.into(),
            texture: file.into(),
            width,
            height,
            billboards: height,
            terms: terms as u32,
            terms_used: billboards.iter().map(|b| b.len() as u32).sum(),
            period_s,
            start_s,
            clip,
            row_channel: "TEXCOORD_1.x = (row + 0.5) / height".into(),
            space: "added to the vertex position before skinning (the followed bone's rest frame)"
                .into(),
            bytes: bytes.len(),
        },
        image: VatImage {
            width,
            height,
            bytes,
            extension: "exr",
        },
        row_uv,
    })
}

/// The offset `terms` give at loop fraction `u` (what the reference shaders compute).
pub fn evaluate(terms: &[SpectralTerm], u: f32) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for t in terms {
        for ((o, a), p) in out.iter_mut().zip(t.amplitude).zip(t.phase) {
            *o += a * (std::f32::consts::TAU * t.frequency * u + p).cos();
        }
    }
    out
}
