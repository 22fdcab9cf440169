//! The export stage: animated billboard clouds as glTF LOD chains engines load as they are
//! (skinned billboards or vertex animation textures), plus the sidecars the metrics read.

pub mod chain_files;
pub mod cloud_motion;
pub mod downscale;
pub mod error;
pub mod ktx2_texture;
pub mod lod_file;
pub mod lod_scene;
pub mod mapping;
pub mod shaders;
pub mod spectral;
pub mod textures;
pub mod vat;

pub use chain_files::{AnimationMode, ChainFileOptions, ChainFiles, chain_files, msft_coverages};
pub use error::ExportError;
pub use ktx2_texture::TextureFormat;
pub use lod_file::{FileOptions, GltfFile, write_glb};
pub use lod_scene::{BillboardNormals, LodInput};
