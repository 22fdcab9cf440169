//! The report of `frond eval` (`--json`): every metric of spec animated-billboard-clouds §5
//! with its definition, or why it was skipped, and both models' cost (§5.7). The field order is
//! the JSON key order, which sweeps and batch summaries read back: keep it.

use serde::Serialize;

use crate::cost::Cost;
use crate::metric_id::MetricId;

/// One metric: mean and max, or why it was not computed.
#[derive(Clone, Debug, Serialize)]
pub struct Metric {
    /// Mean over (view, frame) pairs or matched triangles; None when skipped.
    pub mean: Option<f64>,
    /// The worst pair or triangle; None when skipped.
    pub max: Option<f64>,
    /// Why the metric has no value (no mapping, no foliage, every pair discarded), or None.
    pub skipped_reason: Option<String>,
    /// How the metric is computed ([`MetricId::definition`]).
    pub definition: &'static str,
}

impl Metric {
    /// A computed metric.
    pub(crate) fn value(id: MetricId, mean: f64, max: f64) -> Metric {
        Metric {
            mean: Some(mean),
            max: Some(max),
            skipped_reason: None,
            definition: id.definition(),
        }
    }

    /// A metric that could not be computed, and why.
    pub(crate) fn skipped(id: MetricId, reason: &str) -> Metric {
        Metric {
            mean: None,
            max: None,
            skipped_reason: Some(reason.to_string()),
            definition: id.definition(),
        }
    }
}

/// The static and animated colour (coverage) metric (§5.4).
#[derive(Clone, Debug, Serialize)]
pub struct CoverageMetrics {
    /// The first frame only ([`MetricId::CoverageStatic`]).
    #[serde(rename = "static")]
    pub static_: Metric,
    /// Every frame ([`MetricId::CoverageAnimated`]).
    pub animated: Metric,
    /// (view, frame) pairs of the animated metric discarded because they scored above 1 (the
    /// thesis: no fidelity from that view) or the original covered no pixel.
    pub discarded_pairs: usize,
    /// (view, frame) pairs of the animated metric.
    pub pairs: usize,
}

/// Both models' cost (§5.7): the billboard pair from the imported trees, the rest read from the
/// two files ([`Cost`]).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Costs {
    /// The original's.
    pub original: Cost,
    /// The candidate's.
    pub candidate: Cost,
}

/// The report (`frond eval --json`).
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    /// The original's file.
    pub original: String,
    /// The candidate's file.
    pub candidate: String,
    /// The clip played (the original's; the candidate plays the one of the same name).
    pub clip: Option<String>,
    /// Samples over the loop of the trajectory metrics.
    pub samples: usize,
    /// Ring views of the colour metric.
    pub views: u32,
    /// Frames of the animated colour metric.
    pub frames: u32,
    /// Image size of the colour metric.
    pub size: [u32; 2],
    /// Distances below are in world units; this is the original's height for scale.
    pub tree_height: f32,
    /// [`MetricId::CoverageStatic`] and [`MetricId::CoverageAnimated`].
    pub coverage: CoverageMetrics,
    /// [`MetricId::ColourDifference`].
    pub colour_difference: Metric,
    /// The animated colour metric's shift of the mean colour over shared pixels
    /// ([`crate::coverage::CoverageReport::colour_shift`]); NaN when none is shared.
    pub colour_shift: f64,
    /// [`MetricId::PlaneDistance`].
    pub plane_distance: Metric,
    /// [`MetricId::ProjectedDistance`].
    pub projected_distance: Metric,
    /// [`MetricId::EuclideanDistance`].
    pub euclidean_distance: Metric,
    /// [`MetricId::Orientation`].
    pub orientation: Metric,
    /// [`MetricId::DominatingAxis`].
    pub dominating_axis: Metric,
    /// [`MetricId::DominatingAxisSpectral`].
    pub dominating_axis_spectral: Metric,
    /// How each original foliage triangle was matched to the candidate.
    pub matching: String,
    /// Both models' cost.
    pub cost: Costs,
    /// Seconds per stage (`colour`, `matching`, `trajectories`, `total`).
    pub timings_s: serde_json::Value,
}

impl EvalReport {
    /// The metric `id` (at [`MetricId::json_path`] in the JSON).
    pub fn metric(&self, id: MetricId) -> &Metric {
        match id {
            MetricId::CoverageStatic => &self.coverage.static_,
            MetricId::CoverageAnimated => &self.coverage.animated,
            MetricId::ColourDifference => &self.colour_difference,
            MetricId::PlaneDistance => &self.plane_distance,
            MetricId::ProjectedDistance => &self.projected_distance,
            MetricId::EuclideanDistance => &self.euclidean_distance,
            MetricId::Orientation => &self.orientation,
            MetricId::DominatingAxis => &self.dominating_axis,
            MetricId::DominatingAxisSpectral => &self.dominating_axis_spectral,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A report whose every metric carries its id's column as skip reason.
    fn report() -> EvalReport {
        let m = |id: MetricId| Metric::skipped(id, id.column());
        EvalReport {
            original: "a.glb".into(),
            candidate: "b.glb".into(),
            clip: None,
            samples: 4,
            views: 5,
            frames: 5,
            size: [8, 6],
            tree_height: 1.0,
            colour_shift: 0.0,
            coverage: CoverageMetrics {
                static_: m(MetricId::CoverageStatic),
                animated: m(MetricId::CoverageAnimated),
                discarded_pairs: 0,
                pairs: 25,
            },
            colour_difference: m(MetricId::ColourDifference),
            plane_distance: m(MetricId::PlaneDistance),
            projected_distance: m(MetricId::ProjectedDistance),
            euclidean_distance: m(MetricId::EuclideanDistance),
            orientation: m(MetricId::Orientation),
            dominating_axis: m(MetricId::DominatingAxis),
            dominating_axis_spectral: m(MetricId::DominatingAxisSpectral),
            matching: String::new(),
            cost: Costs::default(),
            timings_s: serde_json::json!({}),
        }
    }

    #[test]
    fn every_metric_id_is_found_at_its_json_path() {
        let r = report();
        let json = serde_json::to_value(&r).unwrap();
        for id in MetricId::ALL {
            assert_eq!(r.metric(id).skipped_reason.as_deref(), Some(id.column()));
            let at = id.json_path().iter().fold(&json, |v, k| &v[k]);
            assert_eq!(at["skipped_reason"], id.column(), "{id:?}");
            assert_eq!(at["definition"], id.definition(), "{id:?}");
        }
    }
}
