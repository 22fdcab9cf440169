//! What a bake gives: the atlases, each quad's cell in them, the whole result, and why a bake
//! can fail.

use frond_render::RenderError;
use glam::Vec2;
use thiserror::Error;

/// The two baked atlases of a cloud, same size, rows top to bottom (glTF image convention).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Atlas {
    /// Width in texels (a multiple of 4).
    pub width: u32,
    /// Height in texels (a multiple of 4).
    pub height: u32,
    /// `width * height * 4` bytes: sRGB colour with straight alpha. Alpha grows with the
    /// covered fraction of the texel and is >= 128 exactly when that fraction reaches
    /// [`BakeParams::alpha_cutoff`](crate::BakeParams::alpha_cutoff) (or, [`Atlas::blended`], is that fraction);
    /// uncovered texels have alpha 0 and the colour of the
    /// nearest covered texel of their quad (dilation, improved-billboard-cloud §4 item 6).
    pub color: Vec<u8>,
    /// `width * height * 4` bytes, linear: a tangent-space normal map in glTF's
    /// `normalTexture` convention, `rgb = n * 0.5 + 0.5` of the unit normal facing the quad's
    /// front in its own frame (+X along `axis_u`, the image's right; +Y along `axis_v`, the
    /// image's up; +Z the quad's front normal), so an engine lights each billboard with its
    /// leaves' normals wherever the billboard turns; alpha as in `color` (dilated the same
    /// way).
    pub normal: Vec<u8>,
    /// Each texel's alpha is the fraction of it covered ([`BakeParams::covered_fraction`](crate::BakeParams::covered_fraction)):
    /// drawn blended (glTF `BLEND`), its mips plain area averages. Otherwise alpha-tested at ½.
    pub blended: bool,
}

/// Where one quad's texture lies in the atlas, in texels (its padding ring surrounds it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cell {
    /// Left column of the texture.
    pub x: u32,
    /// Top row of the texture.
    pub y: u32,
    /// Width in texels (along the quad's `axis_u`).
    pub width: u32,
    /// Height in texels (along the quad's `axis_v`).
    pub height: u32,
}

/// The result of [`bake_cloud`](crate::bake_cloud): atlases plus per-quad texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct BakedCloud {
    /// Colour and normal atlases.
    pub atlas: Atlas,
    /// Per quad: atlas UV (glTF convention, (0, 0) = top-left of the image) of its corners
    /// in [`Quad::corners`](crate::Quad::corners) order. The image shows the quad seen from its front
    /// (`axis_u × axis_v` toward the viewer): corner 3 (-u, +v) is the cell's top-left.
    pub uv_rects: Vec<[Vec2; 4]>,
    /// Per quad: its texture's texel rectangle in the atlas.
    pub cells: Vec<Cell>,
    /// The texel density actually used (texels per world unit).
    pub texels_per_unit: f32,
    /// True when the density had to be lowered below the requested one to fit `max_atlas`.
    pub density_reduced: bool,
    /// Uncompressed bytes of both atlases.
    pub texture_bytes: usize,
}

/// Why a cloud could not be baked.
#[derive(Debug, Error)]
pub enum BakeError {
    /// A [`BakeParams`](crate::BakeParams) value is out of range.
    #[error("invalid bake parameter: {0}")]
    InvalidParams(String),
    /// The soup, quads, members or materials are inconsistent or not finite.
    #[error("invalid bake input: {0}")]
    InvalidInput(String),
    /// Even the smallest textures (min_side per quad, plus padding) do not fit the atlas.
    #[error(
        "{quads} quads do not fit a {max_atlas}x{max_atlas} atlas even at {min_side} texels per \
         side with {padding} texels of padding"
    )]
    AtlasTooSmall {
        /// Number of quads.
        quads: usize,
        /// The atlas limit.
        max_atlas: u32,
        /// The smallest texture side.
        min_side: u32,
        /// Padding per texture.
        padding: u32,
    },
    /// The renderer failed.
    #[error(transparent)]
    Render(#[from] RenderError),
}
