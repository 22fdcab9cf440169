//! The methods, one module each, and the registry that lists them (the types they implement
//! are [`crate::method_api`]'s).
//!
//! Adding a method: a module here with a type implementing
//! [`ClusteringMethod`](crate::method_api::ClusteringMethod) and its
//! [`MethodPlugin`](crate::method_api::MethodPlugin) (its names, how it is configured), and the plugin's line in [`REGISTRY`].
//! Names, parsing and `auto`'s picks all come from the registry.

use crate::method_api::{MethodName, Registry};

pub mod auto;
pub mod cards;
pub mod per_bone;
pub mod skeleton;
pub mod spectral;
pub mod static_cloud;

/// The methods frond runs, in the order `--method` lists their names.
pub const REGISTRY: Registry<'static> = Registry::new(&[
    auto::PLUGIN,
    per_bone::PLUGIN,
    static_cloud::PLUGIN,
    cards::PLUGIN,
    spectral::PLUGIN,
    skeleton::PLUGIN,
]);

/// How many names [`REGISTRY`] lists.
const NAME_COUNT: usize = REGISTRY.name_count();

/// Every name `--method` takes, with the method it names, in [`REGISTRY`] order (`spectral`
/// and `skeleton` alone name the default description types).
pub const METHOD_NAMES: &[(&str, MethodName)] = &REGISTRY.names_array::<NAME_COUNT>();
