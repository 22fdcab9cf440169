//! A CPU rasteriser for coverage renders: the alpha-tested, mip-mapped triangles of a
//! [`DrawScene`](crate::DrawScene) drawn into a supersampled image and resolved to one binary
//! coverage flag per pixel (covered when at least half of its samples are) and, on request,
//! the mean linear colour of each pixel's covered samples.
//!
//! Why not the wgpu path: the coverage metric (spec animated-billboard-clouds §5.4) renders
//! every model from 5 views over 5 frames at 4× supersampling, 3200×2400 samples at a 600 px
//! screen height. On llvmpipe, the only adapter most machines running frond have, those
//! renders were most of `frond lod`'s wall time: a screen rasteriser shades colour, tests
//! depth and reads the image back for a metric that needs one bit per sample. Here a
//! coverage-only render tests each sample once (a covered sample is skipped: coverage does
//! not depend on which surface is in front), reads one alpha channel per fragment, and
//! keeps only a band of the supersampled image in memory at a time. Bands are rasterised in
//! parallel and independently, so the image is the same whatever the thread count, and the
//! same from machine to machine (no driver in the loop). Where the machine has AVX2, coverage
//! renders test eight samples of a row at once ([`crate::sample_lanes`]) with the same
//! operations in the same order: the same bits.
//!
//! It follows the wgpu path's conventions (see the crate docs): wgpu clip space (z in [0, 1]),
//! counter-clockwise front faces, back faces culled unless the material is double-sided,
//! depth test `Less`, samples at pixel centres, the same coverage-preserving mip chains
//! ([`crate::mip_chain`]) filtered trilinearly, alpha test `alpha < cutoff` discarded, and the
//! same lighting. One simplification: the mip level is chosen once per triangle, from the
//! texture-coordinate derivatives at its centroid, where a GPU chooses it per 2×2 block of
//! pixels; the triangles of trees span a few texels of change in level at most.
//!
//! The rasteriser's parts, each a file: [`coverage`] (the public renders and their resolved
//! image), [`bands`] (a render's target checked and its triangles binned into bands),
//! [`setup`] (triangle setup: clipping, culling, edge functions, mip level), [`spans`] (each
//! sample row's span of a triangle), [`raster`] (walking a band's triangles, rows and spans),
//! [`shading`] (a sample's alpha test and colour, and the lighting), [`textures`] and
//! [`bake_textures`] (the scene's textures prepared for coverage renders and for the bake),
//! [`alpha`] (the alpha test and its footprint bounds) and [`sampling`] (texture filtering).

pub(crate) mod alpha;
pub(crate) mod bake_textures;
pub(crate) mod bands;
pub(crate) mod coverage;
pub(crate) mod raster;
pub(crate) mod sampling;
pub(crate) mod setup;
pub(crate) mod shading;
pub(crate) mod spans;
#[cfg(test)]
mod test_scenes;
pub(crate) mod textures;

pub use bands::MAX_SUPERSAMPLE;
pub use coverage::{CoverageImage, depth_complexity, render_coverage, render_coverage_with_depth};
pub use shading::Lighting;
pub use textures::SoftwareTextures;
