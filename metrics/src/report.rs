//! The report of `frond eval` (`--json`): every metric of spec animated-billboard-clouds §5
//! with its definition, or why it was skipped, and both models' cost (§5.7). The field order is
//! the JSON key order, which sweeps and batch summaries read back: keep it.

use std::borrow::Cow;

use serde::{Deserialize, Deserializer, Serialize};

use crate::cost::Cost;
use crate::metric_id::MetricId;

/// One metric: mean and max, or why it was not computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metric {
    /// Mean over (view, frame) pairs or matched triangles; None when skipped.
    pub mean: Option<f64>,
    /// The worst pair or triangle; None when skipped.
    pub max: Option<f64>,
    /// Why the metric has no value (no mapping, no foliage, every pair discarded), or None.
    pub skipped_reason: Option<String>,
    /// How the metric is computed ([`MetricId::definition`]; owned when read back).
    pub definition: Cow<'static, str>,
}

impl Metric {
    /// A computed metric.
    pub(crate) fn value(id: MetricId, mean: f64, max: f64) -> Metric {
        Metric {
            mean: Some(mean),
            max: Some(max),
            skipped_reason: None,
            definition: Cow::Borrowed(id.definition()),
        }
    }

    /// A metric that could not be computed, and why.
    pub(crate) fn skipped(id: MetricId, reason: &str) -> Metric {
        Metric {
            mean: None,
            max: None,
            skipped_reason: Some(reason.to_string()),
            definition: Cow::Borrowed(id.definition()),
        }
    }
}

/// The coverage metrics (§5.4; [`crate::coverage`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageMetrics {
    /// The first frame only ([`MetricId::CoverageStatic`]).
    #[serde(rename = "static")]
    pub static_: Metric,
    /// Every frame ([`MetricId::CoverageAnimated`]): the coverage error.
    pub animated: Metric,
    /// The thesis' binary error on the same renders ([`MetricId::CoverageBinary`]).
    pub binary: Metric,
    /// The foliage alone ([`MetricId::CoverageFoliage`]).
    pub foliage: Metric,
    /// The coverage ratio over every frame: per pair the candidate's covered area over the
    /// original's, then the mean (below 1 the candidate thins, above 1 it bloats).
    pub ratio: f64,
    /// How much the original's coverage changes over the loop: per view, each frame against
    /// the next (the last against the first), the samples that change over those it covers,
    /// then the mean; None with one frame.
    #[serde(default)]
    pub loop_change: Option<f64>,
    /// The candidate's change over the original's: 1 moves as much as the tree, 0 stands
    /// still; None with one frame or an original that does not move.
    #[serde(default)]
    pub loop_change_ratio: Option<f64>,
    /// (view, frame) pairs the binary error discarded because they scored above 1 (the
    /// thesis: no fidelity from that view) or the original covered no pixel.
    pub discarded_pairs: usize,
    /// (view, frame) pairs of the animated metrics.
    pub pairs: usize,
}

/// Both models' cost (§5.7): the billboard pair from the imported trees, the rest read from the
/// two files ([`Cost`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Costs {
    /// The original's.
    pub original: Cost,
    /// The candidate's.
    pub candidate: Cost,
}

/// Seconds each stage of an evaluation took (`timings_s` in the JSON). The fields are in the
/// order the JSON has always had its keys (alphabetical); every evaluation sets all four.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EvalTimings {
    /// The colour renders of the candidate (and of the original, unless already cached) and
    /// the static and animated colour metrics' comparison of them (§5.4).
    pub colour: f64,
    /// Matching the original's foliage triangles to the candidate's billboards or triangles.
    pub matching: f64,
    /// The whole evaluation: file cost, colour metrics, matching, trajectories and cost.
    pub total: f64,
    /// The per-triangle and animation metrics over the loop (§5.2–5.5), after the matching,
    /// with their aggregation into the report.
    pub trajectories: f64,
}

/// The version of the eval report's layout: raised whenever a field changes meaning.
pub const EVAL_SCHEMA_VERSION: u32 = 2;

/// The report (`frond eval --json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// The layout's version ([`EVAL_SCHEMA_VERSION`]; 1 for reports written before it).
    #[serde(default = "first_version")]
    pub schema_version: u32,
    /// The original's file.
    pub original: String,
    /// The candidate's file.
    pub candidate: String,
    /// The clip played (the original's; the candidate plays the one of the same name).
    pub clip: Option<String>,
    /// Samples over the loop of the trajectory metrics.
    pub samples: usize,
    /// Views per ring of the coverage metrics.
    pub views: u32,
    /// The rings' elevations, degrees.
    pub elevations_deg: Vec<f32>,
    /// Frames of the animated coverage metrics.
    pub frames: u32,
    /// The screen height the tree was seen at: its rest height spans this many pixels.
    pub screen_height: f32,
    /// The screen's vertical field of view, degrees.
    pub fov_deg: f32,
    /// The screen's height, pixels.
    pub resolution: f32,
    /// Image size of the coverage metrics, pixels.
    pub size: [u32; 2],
    /// Samples per pixel side, `K`.
    pub samples_per_side: u32,
    /// Distances below are in world units; this is the original's height for scale.
    pub tree_height: f32,
    /// [`MetricId::CoverageStatic`] and [`MetricId::CoverageAnimated`].
    pub coverage: CoverageMetrics,
    /// [`MetricId::ColourDifference`].
    pub colour_difference: Metric,
    /// The animated colour metric's shift of the mean colour over shared pixels
    /// ([`crate::coverage::CoverageReport::colour_shift`]); NaN when none is shared, which the
    /// JSON writes as `null` (read back as NaN, as is a report without the field).
    #[serde(default = "not_a_number", deserialize_with = "nan_if_null")]
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
    #[serde(default)]
    pub cost: Costs,
    /// Seconds per stage.
    #[serde(default)]
    pub timings_s: EvalTimings,
}

/// The schema version of a report written before versions were.
fn first_version() -> u32 {
    1
}

/// NaN: what a float field the JSON lacks reads as.
fn not_a_number() -> f64 {
    f64::NAN
}

/// A float the JSON may hold as `null` (how serde_json writes NaN and the infinities): NaN.
fn nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl EvalReport {
    /// The metric `id` (at [`MetricId::json_path`] in the JSON).
    pub fn metric(&self, id: MetricId) -> &Metric {
        match id {
            MetricId::CoverageStatic => &self.coverage.static_,
            MetricId::CoverageAnimated => &self.coverage.animated,
            MetricId::CoverageBinary => &self.coverage.binary,
            MetricId::CoverageFoliage => &self.coverage.foliage,
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
            schema_version: EVAL_SCHEMA_VERSION,
            original: "a.glb".into(),
            candidate: "b.glb".into(),
            clip: None,
            samples: 4,
            views: 5,
            elevations_deg: vec![0.0, 30.0],
            frames: 5,
            screen_height: 60.0,
            fov_deg: 60.0,
            resolution: 1080.0,
            size: [8, 6],
            samples_per_side: 17,
            tree_height: 1.0,
            colour_shift: 0.0,
            coverage: CoverageMetrics {
                static_: m(MetricId::CoverageStatic),
                animated: m(MetricId::CoverageAnimated),
                binary: m(MetricId::CoverageBinary),
                foliage: m(MetricId::CoverageFoliage),
                ratio: 1.0,
                loop_change: None,
                loop_change_ratio: None,
                discarded_pairs: 0,
                pairs: 50,
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
            timings_s: EvalTimings::default(),
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

    /// `report()` with values in every metric, the cost and the timings.
    fn filled_report() -> EvalReport {
        let mut r = report();
        r.coverage.static_ = Metric::value(MetricId::CoverageStatic, 0.25, 0.5);
        r.plane_distance = Metric::value(MetricId::PlaneDistance, 0.1, 1.25);
        r.clip = Some("Wind".into());
        r.colour_shift = 0.0025;
        r.cost.original.billboards = 12;
        r.cost.original.billboard_area = 3.5;
        r.cost.candidate.file.triangles = 24;
        r.timings_s = EvalTimings {
            colour: 13.1,
            matching: 0.003,
            total: 13.2,
            trajectories: 0.02,
        };
        r
    }

    #[test]
    fn reports_read_back_equal() {
        let r = filled_report();
        let text = serde_json::to_string_pretty(&r).unwrap();
        let back: EvalReport = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
        assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
    }

    #[test]
    fn a_nan_colour_shift_is_written_null_and_read_back_nan() {
        let mut r = filled_report();
        r.colour_shift = f64::NAN;
        let text = serde_json::to_string(&r).unwrap();
        assert!(text.contains("\"colour_shift\":null"), "{text}");
        let back: EvalReport = serde_json::from_str(&text).unwrap();
        assert!(back.colour_shift.is_nan());
        assert_eq!(serde_json::to_string(&back).unwrap(), text);
    }

    #[test]
    fn timings_are_written_as_the_untyped_map_was() {
        let t = filled_report().timings_s;
        let untyped = serde_json::json!({
            "matching": t.matching,
            "trajectories": t.trajectories,
            "colour": t.colour,
            "total": t.total,
        });
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            serde_json::to_string(&untyped).unwrap()
        );
    }
}
