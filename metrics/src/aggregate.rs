//! From per-pair and per-triangle values to the report's [`Metric`]s (spec
//! animated-billboard-clouds §5.2–5.5): the colour metrics' mean and worst (view, frame) pair,
//! and the mean and max over matched triangles of the distance, orientation and dominating-axis
//! metrics.

use crate::coverage::CoverageReport;
use crate::dominating_axis::AxisMetrics;
use crate::metric_id::MetricId;
use crate::report::Metric;
use crate::triangle_metrics::TriangleMetrics;

/// One matched triangle's distance/orientation metrics (§5.2–5.3) and animation metrics (§5.5).
pub type TriangleScores = (TriangleMetrics, AxisMetrics);

/// A coverage error (§5.4 filtered, `id` static, animated or foliage) from its report: the
/// mean over the (view, frame) pairs and the worst pair.
pub fn coverage_metric(id: MetricId, r: &CoverageReport) -> Metric {
    let worst = r.per_pair.iter().copied().fold(f64::NAN, f64::max);
    Metric::value(id, r.mean, worst)
}

/// The thesis' binary coverage error ([`MetricId::CoverageBinary`]) of a report: the mean
/// over the kept pairs and the worst kept pair; skipped when every pair was discarded.
pub fn binary_coverage_metric(r: &CoverageReport) -> Metric {
    let id = MetricId::CoverageBinary;
    let b = &r.binary;
    if b.mean.is_nan() {
        return Metric::skipped(
            id,
            "every (view, frame) pair was discarded (no pixel at least half covered in the \
             original, or error above 1)",
        );
    }
    let worst = (b.differing_pixels.iter())
        .zip(&b.original_pixels)
        .filter(|(_, o)| **o > 0)
        .map(|(d, o)| *d as f64 / *o as f64)
        .filter(|s| *s <= 1.0)
        .fold(f64::NAN, f64::max);
    Metric::value(id, b.mean, worst)
}

/// The foreground colour difference ([`MetricId::ColourDifference`]) of the animated colour
/// report: its mean and the worst finite pair; skipped when the renders share no foliage pixel.
pub fn colour_difference_metric(anim: &CoverageReport) -> Metric {
    let id = MetricId::ColourDifference;
    if anim.colour_difference.is_nan() {
        return Metric::skipped(id, "the two renders share no covered pixel");
    }
    let worst = anim
        .colour_per_pair
        .iter()
        .copied()
        .filter(|c| c.is_finite())
        .fold(0.0, f64::max);
    Metric::value(id, anim.colour_difference, worst)
}

/// Mean of the per-triangle means and max of the per-triangle maxima that `f` picks from each
/// matched triangle's scores; skipped with the matching's reason when there is no matching, or
/// when no triangle was matched.
pub fn triangle_aggregate(
    matching: &Result<String, String>,
    scores: &[TriangleScores],
    id: MetricId,
    f: impl Fn(&TriangleScores) -> (f32, f32),
) -> Metric {
    match matching {
        Err(reason) => Metric::skipped(id, reason),
        Ok(_) if scores.is_empty() => Metric::skipped(id, "no foliage triangle to compare"),
        Ok(_) => {
            let (mut sum, mut max) = (0.0f64, 0.0f64);
            for m in scores {
                let (mean, mx) = f(m);
                sum += f64::from(mean);
                max = max.max(f64::from(mx));
            }
            Metric::value(id, sum / scores.len() as f64, max)
        }
    }
}

/// Mean and max of one animation metric over the leaves matched to a foreign candidate
/// ([`crate::matching::match_foreign`]); skipped with the reason when no leaf could be
/// matched.
pub fn axis_aggregate(
    found: &Result<Vec<AxisMetrics>, String>,
    id: MetricId,
    f: impl Fn(&AxisMetrics) -> f32,
) -> Metric {
    match found {
        Err(reason) => Metric::skipped(id, reason),
        Ok(v) if v.is_empty() => Metric::skipped(id, "no foliage triangle to compare"),
        Ok(v) => {
            let sum: f64 = v.iter().map(|a| f64::from(f(a))).sum();
            let max = v.iter().map(|a| f64::from(f(a))).fold(0.0, f64::max);
            Metric::value(id, sum / v.len() as f64, max)
        }
    }
}
