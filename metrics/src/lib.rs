//! Fidelity metrics (spec animated-billboard-clouds §5) and `frond eval`'s evaluation of a
//! candidate against the animated original.
//!
//! The coverage error of §5.4 on covered fractions (the thesis' binary rule beside it), in
//! [`coverage`], with its cameras and image sizes in [`framing`](mod@framing); App. A's normalisation in
//! [`normalise`]; the dominating-axis animation metrics of §5.5 in [`dominating_axis`]; plane,
//! projected, Euclidean distance and orientation metrics of §5.2–5.3 in [`triangle_metrics`];
//! the cost of a model (§5.7) in [`cost`]; run statistics (§5.8) and Pareto fronts in
//! [`statistics`].
//!
//! The evaluation: every metric's name, columns, label and definition in [`metric_id`]; how the
//! original's foliage triangles are matched to a candidate in [`matching`]; per-triangle and
//! per-pair values to report metrics in [`aggregate`]; the report in [`report`]; the whole
//! evaluation (renders, matching, scores, cost) in [`eval`].

pub mod aggregate;
pub mod cost;
pub mod coverage;
pub mod dominating_axis;
pub mod eval;
pub mod framing;
pub mod matching;
pub mod metric_id;
/// App. A's normalisation, shared with the spectral descriptions (which sit upstream).
pub use frond_spectral::normalise;
pub mod report;
pub mod statistics;
pub mod triangle_metrics;

pub use coverage::{
    BinaryCoverage, CoverageImages, CoverageParams, CoverageReport, DEFAULT_ELEVATIONS_DEG,
    DEFAULT_FOV_DEG, DEFAULT_FRAMES, DEFAULT_RESOLUTION, DEFAULT_VIEWS, MetricError, Rasteriser,
    compare_images, coverage_error, coverage_images, depth_complexity,
};
pub use eval::{EvalContext, EvalError, EvalRequest, Measured, candidate_clip, evaluate};
pub use framing::{Framing, framing, ring_azimuth_deg, samples_per_side};
pub use metric_id::MetricId;
pub use report::{Costs, CoverageMetrics, EvalReport, EvalTimings, Metric};
