//! A render's target and per-frame data, shared by both CPU rasterisers: the request
//! checked ([`checked_target`]), and the scene's triangles set up and binned into bands of
//! pixel rows ([`Bands`]), the unit of parallel work.

use glam::Mat4;

use super::setup::{Setup, setup};
use super::shading::Shading;
use super::textures::{MAX_TEXTURE_SIDE, SoftwareTextures};
use crate::error::RenderError;
use crate::scene::DrawScene;

/// Most samples per side of the supersampled image (coordinates stay exact in `f32`).
pub(crate) const MAX_SIDE: u64 = 1 << 15;

/// Most samples per pixel side: a pixel's covered samples are counted in 16 bits.
pub const MAX_SUPERSAMPLE: u32 = 255;

/// Pixel rows per band: the unit of parallel work and of memory (one band's samples per
/// thread).
pub(crate) const BAND_PIXELS: usize = 16;

/// The supersampled target's sides in samples, once the request is checked: both sides at
/// least a pixel and at most [`MAX_SIDE`] samples, a finite matrix, a valid scene and
/// textures prepared for it.
pub(crate) fn checked_target(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    [width, height, supersample]: [u32; 3],
) -> Result<(usize, usize), RenderError> {
    let ss = supersample.max(1);
    let (sw, sh) = (
        u64::from(width) * u64::from(ss),
        u64::from(height) * u64::from(ss),
    );
    if width == 0 || height == 0 || sw > MAX_SIDE || sh > MAX_SIDE || ss > MAX_SUPERSAMPLE {
        return Err(RenderError::InvalidSize {
            width,
            height,
            reason: format!(
                "both sides must be at least 1 pixel and at most {MAX_SIDE} samples \
                 ({supersample}x supersampled, at most {MAX_SUPERSAMPLE}x)"
            ),
        });
    }
    if !view_proj.is_finite() {
        return Err(RenderError::InvalidCamera(
            "the view-projection matrix has a non-finite entry".into(),
        ));
    }
    scene.validate(MAX_TEXTURE_SIDE)?;
    if textures.textures.len() != scene.textures.len() {
        return Err(RenderError::InvalidTexture {
            texture: textures.textures.len().min(scene.textures.len()),
            reason: format!(
                "{} textures prepared for a scene of {}",
                textures.textures.len(),
                scene.textures.len()
            ),
        });
    }
    Ok((sw as usize, sh as usize))
}

/// A render's triangles set up, and binned into bands of [`BAND_PIXELS`] pixel rows: the
/// unit of parallel work of both CPU rasterisers.
pub(crate) struct Bands {
    /// The scene's triangles set up, in draw order.
    pub(crate) triangles: Vec<Setup>,
    /// Per triangle, its shading attributes when the textures were prepared with colour
    /// (empty otherwise).
    pub(crate) shading: Vec<Shading>,
    /// Per band, the triangles whose bounds reach it, in draw order.
    pub(crate) bins: Vec<Vec<u32>>,
    /// Sample rows per band.
    pub(crate) rows: usize,
}

impl Bands {
    /// Sets up `scene`'s triangles for a target of `sw`×`sh` samples, `ss` per pixel side,
    /// and bins them.
    pub(crate) fn new(
        scene: &DrawScene,
        textures: &SoftwareTextures,
        view_proj: Mat4,
        [sw, sh]: [usize; 2],
        ss: usize,
    ) -> Bands {
        let (triangles, shading) = setup(scene, textures, view_proj, sw as f32, sh as f32);
        let rows = BAND_PIXELS * ss;
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); sh.div_ceil(rows)];
        for (i, t) in triangles.iter().enumerate() {
            let first = (t.min[1].max(0) as usize) / rows;
            let last = (t.max[1].max(0) as usize).min(sh - 1) / rows;
            for bin in &mut bins[first..=last] {
                bin.push(i as u32);
            }
        }
        Bands {
            triangles,
            shading,
            bins,
            rows,
        }
    }
}
