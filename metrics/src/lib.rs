//! Fidelity metrics (spec animated-billboard-clouds §5).
//!
//! The coverage ("colour") metric of §5.4, with the thesis' experiment setup of §8.2
//! and the checklist rules of §11 item 7, in [`coverage`]; App. A's normalisation in
//! [`normalise`]; the dominating-axis animation metrics of §5.5 in [`animation`]; plane, projected,
//! Euclidean distance and orientation metrics of §5.2–5.3 in [`triangle_metrics`]; the
//! cost of a model (§5.7) in [`cost`]; run statistics (§5.8) and Pareto fronts in
//! [`statistics`].

#![warn(missing_docs)]

pub mod animation;
pub mod cost;
pub mod coverage;
/// App. A's normalisation, shared with the spectral descriptions (which sit upstream).
pub use frond_spectral::normalise;
pub mod statistics;
pub mod triangle_metrics;

pub use coverage::{
    CoverageMasks, CoverageParams, CoverageReport, MetricError, compare_masks, coverage_error,
    coverage_masks, ring_azimuth_deg, view_camera,
};
