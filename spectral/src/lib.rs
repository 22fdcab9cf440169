//! Spectral descriptions of leaf motion (spec animated-billboard-clouds §4): the DFT conventions
//! every later stage shares, the dominating movement axis, frequency bins, App. A's
//! normalisation, the three description types (naive, dominating-axis, axis-phase) and k-means
//! over them. The clustering methods and the animation metrics build on these.

pub mod description;
pub mod dominating_axis;
pub mod frequency_bins;
pub mod kmeans;
pub mod normalise;
pub mod spectrum;
pub mod zones;

pub use dominating_axis::{DominatingAxis, dominating_axis};
pub use frequency_bins::{FrequencyBins, amplitude_distance, frequency_bins};
pub use spectrum::Spectrum;
