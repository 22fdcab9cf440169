//! `--animation spectral`: every billboard's own motion as the few cosines SCA kept (spec
//! animated-billboard-clouds §4.11 "runtime"), in one small float texture and a sidecar, played
//! by one shared vertex program (`shaders/frond_spectral.{wgsl,glsl,hlsl}`) that evaluates the
//! inverse DFT and translates the quad, before skinning to the bone it follows.
//!
//! Layout (EXR, RGBA half floats, row 0 on top): billboard `i` owns a block of `2·terms` texels
//! at row `i / per_row`, starting at column `2·terms·(i % per_row)` (`per_row` blocks fill a row
//! of at most 8192 texels, so any number of billboards fits); its term `j` takes two texels,
//! `(base + 2j) = (f, a_x, a_y, a_z)` and `(base + 2j + 1) = (φ_x, φ_y, φ_z, 0)`, and adds
//! `a_c · cos(2π f u + φ_c)` to coordinate `c`, `u = (t − start) / period` the loop fraction.
//! Unused terms are zero. The billboard's index is in `TEXCOORD_1.x` as `i + 0.5` (the u
//! channel, which engines that flip v on import leave alone).

use serde::{Deserialize, Serialize};

use crate::vat::{VatError, VatImage, write_exr_half};

/// The `layout` field of the sidecar.
pub const SPECTRAL_LAYOUT: &str = "frond-spectral-2: billboard i at row i / per_row, texels from \
2 terms (i % per_row); texel 2j = (f, ax, ay, az), texel 2j+1 = (phx, phy, phz, 0); \
offset_c = sum_j a_c cos(2 pi f u + ph_c), u = loop fraction";

/// One cosine term of a billboard's translation: the same frequency on all three axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralTerm {
    /// Cycles per loop.
    pub frequency: f32,
    /// Amplitude per axis (x, y, z), world units.
    pub amplitude: [f32; 3],
    /// Phase per axis (x, y, z), radians.
    pub phase: [f32; 3],
}

/// The sidecar written beside the texture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpectralSidecar {
    /// Always [`SPECTRAL_LAYOUT`].
    pub layout: String,
    /// The texture's file name, relative to the sidecar.
    pub texture: String,
    /// Texture width in texels.
    pub width: u32,
    /// Texture height in texels (rows of billboard blocks).
    pub height: u32,
    /// Billboards the texture holds a block for (the LOD's billboards, in order).
    pub billboards: u32,
    /// Terms per billboard the texture has room for.
    pub terms: u32,
    /// Billboard blocks (2·terms texels each) per texture row.
    pub per_row: u32,
    /// Non-zero terms over all billboards.
    pub terms_used: u32,
    /// Loop length, seconds, of the clip the motion was sampled from.
    pub period_s: f32,
    /// Clip time, seconds, where the loop starts (`u = 0`).
    pub start_s: f32,
    /// The clip's name (None for a tree without clips).
    pub clip: Option<String>,
    /// Always "TEXCOORD_1.x = billboard index + 0.5".
    pub row_channel: String,
    /// Always "added to the vertex position before skinning (the followed bone's rest frame)".
    pub space: String,
    /// Size of the texture file in bytes.
    pub bytes: usize,
}

/// The encoded texture and its sidecar.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralTextures {
    /// The coefficient texture (EXR, RGBA half floats).
    pub image: VatImage,
    /// What is written beside it as JSON.
    pub sidecar: SpectralSidecar,
    /// Per billboard: the value of `TEXCOORD_1` on its four corners (`[i + 0.5, 0]`).
    pub row_uv: Vec<[f32; 2]>,
}

/// Encodes `billboards[i]`'s terms into block `i` (an empty list: a billboard without own
/// motion).
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
    let max = crate::vat::MAX_TEXTURE_SIZE as usize;
    let block = 2 * terms;
    let per_row = (max / block).min(billboards.len()).max(1);
    let rows = billboards.len().div_ceil(per_row);
    if block > max || rows > max {
        return Err(VatError::TooLarge {
            pieces: billboards.len(),
            frames: terms,
            width: (block * per_row) as u64,
            height: rows as u64,
            max: crate::vat::MAX_TEXTURE_SIZE,
        });
    }
    let (width, height) = ((block * per_row) as u32, rows as u32);
    let mut texels = vec![[0.0f32; 4]; width as usize * height as usize];
    for (i, list) in billboards.iter().enumerate() {
        let start = (i / per_row) * width as usize + block * (i % per_row);
        for (j, t) in list.iter().enumerate() {
            if t.frequency > 2048.0 {
                return Err(VatError::FrequencyTooHigh {
                    piece: i,
                    frequency: t.frequency,
                });
            }
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
                    piece: i,
                    frame: j,
                    value: *v,
                });
            }
            texels[start + 2 * j] = [t.frequency, t.amplitude[0], t.amplitude[1], t.amplitude[2]];
            texels[start + 2 * j + 1] = [t.phase[0], t.phase[1], t.phase[2], 0.0];
        }
    }
    let bytes = write_exr_half(width, height, &texels);
    let row_uv = (0..billboards.len())
        .map(|i| [i as f32 + 0.5, 0.0])
        .collect();
    Ok(SpectralTextures {
        sidecar: SpectralSidecar {
            layout: SPECTRAL_LAYOUT.into(),
            texture: file.into(),
            width,
            height,
            billboards: billboards.len() as u32,
            terms: terms as u32,
            per_row: per_row as u32,
            terms_used: billboards.iter().map(|b| b.len() as u32).sum(),
            period_s,
            start_s,
            clip,
            row_channel: "TEXCOORD_1.x = billboard index + 0.5".into(),
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
