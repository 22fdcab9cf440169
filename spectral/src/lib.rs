//! Spectral descriptions of leaf motion (spec animated-billboard-clouds §4): the DFT conventions
//! every later stage shares, the dominating movement axis, and frequency bins. The clustering
//! methods and the animation metrics build on these.

pub mod dominating_axis;
pub mod frequency_bins;
pub mod spectrum;

pub use dominating_axis::{DominatingAxis, dominating_axis};
pub use frequency_bins::{FrequencyBins, amplitude_distance, frequency_bins};
pub use spectrum::Spectrum;
