//! `frond-render`: a small offscreen wgpu renderer for plain triangle meshes.
//!
//! It draws already-posed meshes (the caller skins vertices on the CPU) into an
//! sRGB RGBA8 image plus an exact per-pixel coverage mask, on real GPUs and on CPU
//! adapters (Mesa llvmpipe over GL, lavapipe over Vulkan) alike. It is used for
//! baking billboard textures and for measuring how LODs differ on screen.
//! [`Renderer::render_view`] takes an explicit view-projection matrix (e.g. an
//! orthographic view of one billboard quad) and can output world-space normals
//! ([`Output::Normal`]) for normal-map baking.
//!
//! Conventions: Y-up right-handed world (as in glTF), counter-clockwise front faces,
//! depth in [0, 1] (Depth32Float), a fixed world-space light from above
//! ([`LIGHT_DIRECTION`]). Textures are sampled at full size unless a caller asks for mip
//! chains ([`Renderer::render_mipmapped`], used by the coverage metric), and those chains
//! preserve alpha-tested coverage per level, so leaves are never thinned by mip averaging.
//!
//! ```no_run
//! use frond_render::{Camera, DrawMaterial, DrawMesh, DrawScene, Projection, Renderer};
//! # fn main() -> Result<(), frond_render::RenderError> {
//! let renderer = Renderer::new()?;
//! let scene = DrawScene {
//!     meshes: vec![DrawMesh {
//!         positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
//!         normals: None,
//!         tangents: None,
//!         uvs: None,
//!         indices: vec![0, 1, 2],
//!         material: 0,
//!     }],
//!     materials: vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
//!     textures: vec![],
//! };
//! let (min, max) = scene.bounds().unwrap_or_default();
//! let camera = Camera::framing(min, max, 0.0, 0.0, Projection::Perspective { fov_y_deg: 45.0 });
//! let frame = renderer.render(&scene, &camera, 128, 128, [0.0, 0.0, 0.0, 0.0])?;
//! println!("{} of the image is covered", frame.coverage_fraction());
//! # Ok(())
//! # }
//! ```

mod adapter;
mod bake_lanes;
mod bake_raster;
mod batch;
mod camera;
mod error;
mod frame;
mod pipeline;
mod readback;
mod renderer;
mod sample_lanes;
mod scene;
mod software;
mod srgb;
mod tree;
mod uv_hull;

pub use bake_raster::{BakeImage, BakeScratch, BakeTarget, CoveredPixel, render_bake};
pub use camera::{Camera, Projection};
pub use error::RenderError;
pub use frame::Frame;
pub use pipeline::{
    LIGHT_DIRECTION, alpha_mip_chain, blend_alpha_mip_chain, blend_mip_chain, linear_mip_chain,
    mip_chain,
};
pub use renderer::{Output, Renderer};
pub use scene::{DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture};
pub use software::{
    CoverageImage, Lighting, MAX_SUPERSAMPLE, SoftwareTextures, depth_complexity, render_coverage,
    render_coverage_with_depth,
};
pub use srgb::{SRGB_LINEAR, linear_to_srgb, srgb_to_linear};
pub use tree::{PosedTree, TreeParts, materials_scene, scene_from_positions, tree_scene};
