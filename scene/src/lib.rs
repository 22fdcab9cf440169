//! frond's first stage: the tree model, glTF import and writing, animation sampling and the
//! sample-tree generator.

pub mod accessor;
pub mod binding;
pub mod classify;
pub mod error;
pub mod file_cost;
pub mod generator;
pub mod gltf_source;
pub mod gltf_writer;
pub mod import;
pub mod input_file;
pub mod ktx2;
pub mod length;
pub mod meshopt_views;
pub mod model;
pub mod rig;
pub mod rigid_fit;
pub mod sampling;
pub mod skinning;
pub mod surface_distance;
pub mod wood;

pub use error::{Result, SceneError};
pub use file_cost::{FileCost, ImageCost, file_cost, file_cost_bytes};
pub use import::{ImportOptions, import, import_bytes};
pub use input_file::InputLimits;
pub use length::Length;
pub use model::*;
pub use rig::{Clip, Node, Rig, Trs};
pub use sampling::{Motion, SampleOptions, Sampled, sample, sample_loop};
