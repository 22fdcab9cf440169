//! The billboard stage: stochastic billboard clouds (spec animated-billboard-clouds §2.4,
//! improved-billboard-cloud §2 and §4): plane search, minimal rectangles, baked alpha-tested
//! textures packed into one atlas.

pub mod animated;
pub mod animated_build;
pub mod atlas;
pub mod bake;
pub mod cloud;
pub mod motion_budget;
pub mod plane;
pub mod plane_search;
pub mod quad;
pub mod rectangle;
pub mod skeleton_build;
pub mod soup;
pub mod spectral_build;

pub use atlas::{Packing, pack};
pub use bake::{Atlas, BakeError, BakeParams, BakedCloud, Cell, bake_cloud};
pub use plane::Plane;
pub use quad::Quad;
pub use soup::TriangleSoup;
