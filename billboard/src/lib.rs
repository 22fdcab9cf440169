//! The billboard stage: stochastic billboard clouds (spec animated-billboard-clouds §2.4,
//! improved-billboard-cloud §2 and §4): plane search, minimal rectangles, baked alpha-tested
//! textures packed into one atlas. This is the static cloud only: how a cloud moves is the LOD
//! layer's business (`frond-lod`), so this crate knows no clustering method.

pub mod atlas;
pub mod bake;
pub mod cloud;
pub mod plane;
pub mod plane_search;
pub mod quad;
pub mod quad_split;
pub mod rectangle;
pub mod soup;
pub mod source_copy;
pub mod view_coverage;

pub use atlas::{Packing, pack};
pub use bake::{Atlas, BakeError, BakeParams, BakeRasteriser, BakedCloud, Cell, bake_cloud};
pub use plane::Plane;
pub use quad::Quad;
pub use soup::TriangleSoup;
pub use source_copy::{SourceCopy, source_copy};
