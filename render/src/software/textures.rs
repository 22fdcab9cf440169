//! A scene's textures prepared for the CPU rasterisers ([`SoftwareTextures`]): their mip
//! chains, alpha bounds and normal maps, made once for the many renders of one scene.

use rayon::prelude::*;

use super::alpha::AlphaBounds;
use super::sampling::{Levels, LinearLevel};
use super::shading::Lighting;
use crate::error::RenderError;
use crate::pipeline::{Mips, linear_mip_chain};
use crate::scene::{DrawScene, DrawTexture};

/// Largest texture side accepted (as the wgpu path's limit on common adapters).
pub(crate) const MAX_TEXTURE_SIDE: u32 = 16384;

/// A scene's textures prepared for [`render_coverage`](super::render_coverage): their coverage-preserving mip chains,
/// computed once for the many renders of one scene's frames and views.
#[derive(Clone, Debug)]
pub struct SoftwareTextures {
    /// Per texture, its mip chain (empty when no drawn material samples it): RGBA when colour
    /// is drawn, alpha alone otherwise.
    pub(crate) textures: Vec<Levels>,
    /// Per texture and level, the alpha bounds of every bilinear footprint
    /// ([`AlphaBounds`]): of the alpha-only levels when colour is not drawn (coverage renders),
    /// of the RGBA levels' alpha when prepared for the bake ([`SoftwareTextures::for_bake`],
    /// footprints only); empty otherwise.
    pub(super) alpha_bounds: Vec<Vec<AlphaBounds>>,
    /// Per texture, its levels' alpha channel alone when prepared for the bake
    /// ([`SoftwareTextures::for_bake`]: what [`SoftwareTextures::bake_lanes`] filters); empty
    /// otherwise.
    pub(super) bake_alpha: Vec<Levels>,
    /// Per texture and level of `bake_alpha`, each bilinear footprint's four alphas (top
    /// left, top right, bottom left, bottom right, a byte each from the lowest) at its top
    /// left texel, for the footprints within the level (0 on its last row and column): what
    /// the eight-sample test gathers, one read a sample ([`LaneTest::Quads`](crate::sample_lanes::LaneTest::Quads)).
    pub(super) bake_quads: Vec<Vec<Vec<u32>>>,
    /// Per texture and level, when prepared for the bake, its colour decoded to linear light
    /// on first use where the level holds at most [`MAX_LINEAR_TEXELS`](super::sampling::MAX_LINEAR_TEXELS) texels: what
    /// [`SoftwareTextures::bake_rgb`] filters; empty otherwise.
    pub(super) bake_linear: Vec<Vec<std::sync::OnceLock<Option<LinearLevel>>>>,
    /// Per texture, its linear box chain when a drawn material uses it as a normal map and
    /// colour is drawn (lighting needs the normals); empty otherwise.
    pub(super) normal_maps: Vec<Levels>,
    /// Whether colour is drawn: the levels are RGBA, and a render tests depth and shades.
    pub(crate) colour: bool,
    pub(super) lighting: Lighting,
}

impl SoftwareTextures {
    /// Prepares the textures of `scene` that its drawn meshes' materials sample; `colour`:
    /// also draw colour, which needs the RGB of every level and a depth test per sample.
    pub fn new(scene: &DrawScene, colour: bool) -> Result<SoftwareTextures, RenderError> {
        let mut used: Vec<Option<Mips>> = vec![None; scene.textures.len()];
        let mut normal_map = vec![false; scene.textures.len()];
        for mesh in scene.meshes.iter().filter(|m| !m.indices.is_empty()) {
            let material = scene.materials.get(mesh.material);
            if let Some(m) = material
                && let Some(t) = m.texture
                && let Some(u) = used.get_mut(t)
            {
                *u = Some(u.map_or(Mips::of(m.alpha), |mips| mips.with(m.alpha)));
            }
            if colour
                && mesh.tangents.is_some()
                && let Some(t) = material.and_then(|m| m.normal_texture)
                && let Some(u) = normal_map.get_mut(t)
            {
                *u = true;
            }
        }
        Self::prepare(&scene.textures, used, normal_map, colour)
    }

    /// Whether texture `texture` was prepared (has levels).
    pub(crate) fn prepared(&self, texture: usize) -> bool {
        self.textures.get(texture).is_some_and(|l| !l.0.is_empty())
    }

    /// The mip chains of the `used` textures (colour or alpha alone; the chain each asks for,
    /// none where it is not drawn) and of the `normal_map` ones (linear).
    pub(super) fn prepare(
        source: &[DrawTexture],
        used: Vec<Option<Mips>>,
        normal_map: Vec<bool>,
        colour: bool,
    ) -> Result<SoftwareTextures, RenderError> {
        // In parallel: a 1024² colour chain is tens of milliseconds.
        let textures: Vec<Levels> = source
            .par_iter()
            .zip(used)
            .enumerate()
            .map(|(i, (t, used))| {
                let texels = t.width as usize * t.height as usize;
                if t.width == 0
                    || t.height == 0
                    || t.width > MAX_TEXTURE_SIDE
                    || t.height > MAX_TEXTURE_SIDE
                    || t.rgba.len() != texels * 4
                {
                    return Err(RenderError::InvalidTexture {
                        texture: i,
                        reason: format!(
                            "{}x{} with {} bytes (sides 1 to {MAX_TEXTURE_SIDE}, 4 bytes a texel)",
                            t.width,
                            t.height,
                            t.rgba.len()
                        ),
                    });
                }
                Ok(Levels(match used {
                    None => Vec::new(),
                    Some(mips) if colour => mips.rgba(t.width, t.height, &t.rgba),
                    Some(mips) => {
                        let alpha: Vec<u8> = t.rgba.chunks_exact(4).map(|p| p[3]).collect();
                        mips.alpha(t.width, t.height, &alpha)
                    }
                }))
            })
            .collect::<Result<_, _>>()?;
        let normal_maps = source
            .iter()
            .zip(normal_map)
            .map(|(t, used)| {
                Levels(if used {
                    linear_mip_chain(t.width, t.height, t.rgba.clone())
                } else {
                    Vec::new()
                })
            })
            .collect();
        let alpha_bounds = if colour {
            Vec::new()
        } else {
            textures.iter().map(AlphaBounds::chain).collect()
        };
        Ok(SoftwareTextures {
            textures,
            alpha_bounds,
            bake_alpha: Vec::new(),
            bake_quads: Vec::new(),
            bake_linear: Vec::new(),
            normal_maps,
            colour,
            lighting: Lighting::TwoSided,
        })
    }

    /// The same textures, colour shaded with `lighting`.
    pub fn with_lighting(mut self, lighting: Lighting) -> SoftwareTextures {
        self.lighting = lighting;
        self
    }
}
