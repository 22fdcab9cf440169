//! The clustering methods, one file each (see [`crate::method`]).

pub mod card_coverage;
pub mod card_trim;
pub mod cards;
pub mod per_bone;
pub mod skeleton;
pub mod spectral;
pub mod static_cloud;
