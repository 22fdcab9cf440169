//! The clustering methods, one file each (see [`crate::method`]).

pub mod cards;
pub mod per_bone;
pub mod skeleton;
pub mod spectral;
pub mod static_cloud;
