//! The one list of `frond eval`'s metrics (spec animated-billboard-clouds §5.2–5.5): each
//! metric's key in the eval report, its `results.csv` columns, its chart label, its definition
//! (the text every report carries) and its unit. The eval report, the sweep's CSV, stability
//! table and charts and the batch summary all name metrics through [`MetricId`], so a metric
//! is added or renamed in one place.

/// One metric of `frond eval` (spec animated-billboard-clouds §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum MetricId {
    /// The coverage error (§5.4 with covered fractions) on the first frame only (F = 1).
    CoverageStatic,
    /// The coverage error (§5.4 with covered fractions) over every frame of the loop.
    CoverageAnimated,
    /// The thesis' binary coverage error of §5.4 over every frame, on the same renders.
    CoverageBinary,
    /// The coverage error of the foliage alone over every frame.
    CoverageFoliage,
    /// Mean colour difference over the foliage pixels both renders cover.
    ColourDifference,
    /// `D_plane` of §5.2.
    PlaneDistance,
    /// `D_projected` of §5.2.
    ProjectedDistance,
    /// `D_euclidean` of §5.2, from the two above.
    EuclideanDistance,
    /// The orientation metric of §5.3.
    Orientation,
    /// The dominating-axis animation metric of §5.5 (with the §4.8 erratum fixed).
    DominatingAxis,
    /// The spectral part of the dominating-axis metric of §5.5.
    DominatingAxisSpectral,
}

const COVERAGE_DEF: &str = "spec §5.4 filtered: Σ|α_o−α_s|/Σα_o per (view, frame), α = covered \
    fraction of each pixel's K×K samples (wood and foliage), the tree's height H pixels; views \
    on rings at 0° and 30°; mean over every pair, max = worst pair";
const BINARY_DEF: &str = "spec §5.4 as the thesis defines it, on the same renders: a pixel \
    covered when α ≥ ½, Σ|o−s|/P_f per (view, frame), pairs above 1 or with P_f = 0 discarded; \
    mean over the rest, max = worst kept pair";
const FOLIAGE_DEF: &str = "spec §5.4 filtered, as coverage_animated but with the foliage \
    alone drawn";
const COLOUR_DEF: &str = "mean |Δ linear RGB| over the pixels both renders cover, each \
    weighted by the coverage both share, min(α_o, α_s), per (view, frame) of the animated \
    coverage error; max = worst pair";
const PLANE_DEF: &str = "spec §5.2: distance of each foliage triangle's centroid to its \
    billboard's plane over the loop (world units); mean of per-triangle means, max of maxes";
const PROJECTED_DEF: &str = "spec §5.2: distance of the centroid's projection to its fixed \
    point on the billboard (least-squares over the loop), world units";
const EUCLID_DEF: &str = "spec §5.2: sqrt(D_plane² + D_projected²), world units";
const ORIENT_DEF: &str = "spec §5.3: 1 − (n·n_s + 1)(d·d_s + 1)/4 per sample, d = centroid → \
    vertex 0, billboard normal signed toward the triangle (double-sided)";
const AXIS_DEF: &str = "spec §5.5 with the §4.8 erratum fixed: NEP(1 − |a_t·a_b|, \
    amplitudeDistance) of the centroid's and its image's trajectories (image: the fixed point on \
    its billboard, or for candidates without a mapping the nearest candidate foliage point in \
    the rest pose), frequency bins = skeleton depth; mean and max over triangles";
const AXIS_SPEC_DEF: &str = "spec §5.5: NE(amplitudeDistance) of the dominating-axis spectra, \
    frequency bins = skeleton depth";

impl MetricId {
    /// Every metric, in the eval report's order.
    pub const ALL: [MetricId; 11] = [
        MetricId::CoverageStatic,
        MetricId::CoverageAnimated,
        MetricId::CoverageBinary,
        MetricId::CoverageFoliage,
        MetricId::ColourDifference,
        MetricId::PlaneDistance,
        MetricId::ProjectedDistance,
        MetricId::EuclideanDistance,
        MetricId::Orientation,
        MetricId::DominatingAxis,
        MetricId::DominatingAxisSpectral,
    ];

    /// The `results.csv` column of the metric's mean (also its key in sweep rows and the
    /// stability table).
    pub fn column(self) -> &'static str {
        match self {
            MetricId::CoverageStatic => "coverage_static",
            MetricId::CoverageAnimated => "coverage_animated",
            MetricId::CoverageBinary => "coverage_binary",
            MetricId::CoverageFoliage => "coverage_foliage",
            MetricId::ColourDifference => "colour_difference",
            MetricId::PlaneDistance => "plane_distance",
            MetricId::ProjectedDistance => "projected_distance",
            MetricId::EuclideanDistance => "euclidean_distance",
            MetricId::Orientation => "orientation",
            MetricId::DominatingAxis => "dominating_axis",
            MetricId::DominatingAxisSpectral => "dominating_axis_spectral",
        }
    }

    /// The `results.csv` column of the metric's maximum: [`column`](Self::column) + `_max`.
    pub fn max_column(self) -> &'static str {
        match self {
            MetricId::CoverageStatic => "coverage_static_max",
            MetricId::CoverageAnimated => "coverage_animated_max",
            MetricId::CoverageBinary => "coverage_binary_max",
            MetricId::CoverageFoliage => "coverage_foliage_max",
            MetricId::ColourDifference => "colour_difference_max",
            MetricId::PlaneDistance => "plane_distance_max",
            MetricId::ProjectedDistance => "projected_distance_max",
            MetricId::EuclideanDistance => "euclidean_distance_max",
            MetricId::Orientation => "orientation_max",
            MetricId::DominatingAxis => "dominating_axis_max",
            MetricId::DominatingAxisSpectral => "dominating_axis_spectral_max",
        }
    }

    /// Where the metric sits in `frond eval --json`: the coverage metrics under `coverage`,
    /// the others at the top level under their column name.
    pub fn json_path(self) -> &'static [&'static str] {
        match self {
            MetricId::CoverageStatic => &["coverage", "static"],
            MetricId::CoverageAnimated => &["coverage", "animated"],
            MetricId::CoverageBinary => &["coverage", "binary"],
            MetricId::CoverageFoliage => &["coverage", "foliage"],
            MetricId::ColourDifference => &["colour_difference"],
            MetricId::PlaneDistance => &["plane_distance"],
            MetricId::ProjectedDistance => &["projected_distance"],
            MetricId::EuclideanDistance => &["euclidean_distance"],
            MetricId::Orientation => &["orientation"],
            MetricId::DominatingAxis => &["dominating_axis"],
            MetricId::DominatingAxisSpectral => &["dominating_axis_spectral"],
        }
    }

    /// The metric in words, as chart axes name it.
    pub fn label(self) -> &'static str {
        match self {
            MetricId::CoverageStatic => "static coverage error",
            MetricId::CoverageAnimated => "animated coverage error",
            MetricId::CoverageBinary => "binary coverage error (thesis)",
            MetricId::CoverageFoliage => "foliage coverage error",
            MetricId::ColourDifference => "foreground colour difference",
            MetricId::PlaneDistance => "plane distance (world)",
            MetricId::ProjectedDistance => "projected distance (world)",
            MetricId::EuclideanDistance => "Euclidean distance (world)",
            MetricId::Orientation => "orientation metric",
            MetricId::DominatingAxis => "dominating-axis metric",
            MetricId::DominatingAxisSpectral => "dominating-axis spectral metric",
        }
    }

    /// A short heading for table columns (the sweep's `stability.md`).
    pub fn short_label(self) -> &'static str {
        match self {
            MetricId::CoverageStatic => "static coverage",
            MetricId::CoverageAnimated => "animated coverage",
            MetricId::CoverageBinary => "binary coverage",
            MetricId::CoverageFoliage => "foliage coverage",
            MetricId::ColourDifference => "colour diff",
            MetricId::PlaneDistance => "plane dist.",
            MetricId::ProjectedDistance => "projected dist.",
            MetricId::EuclideanDistance => "Euclidean dist.",
            MetricId::Orientation => "orientation",
            MetricId::DominatingAxis => "dom. axis",
            MetricId::DominatingAxisSpectral => "dom. axis spectral",
        }
    }

    /// How the metric is computed, with its spec section: the `definition` every eval report
    /// carries next to the value.
    pub fn definition(self) -> &'static str {
        match self {
            MetricId::CoverageStatic | MetricId::CoverageAnimated => COVERAGE_DEF,
            MetricId::CoverageBinary => BINARY_DEF,
            MetricId::CoverageFoliage => FOLIAGE_DEF,
            MetricId::ColourDifference => COLOUR_DEF,
            MetricId::PlaneDistance => PLANE_DEF,
            MetricId::ProjectedDistance => PROJECTED_DEF,
            MetricId::EuclideanDistance => EUCLID_DEF,
            MetricId::Orientation => ORIENT_DEF,
            MetricId::DominatingAxis => AXIS_DEF,
            MetricId::DominatingAxisSpectral => AXIS_SPEC_DEF,
        }
    }

    /// The metric's unit or range (every metric: lower is better, 0 is a perfect match).
    pub fn unit(self) -> &'static str {
        match self {
            MetricId::CoverageStatic | MetricId::CoverageAnimated | MetricId::CoverageFoliage => {
                "covered area missing or extra per area the original covers, 0 up"
            }
            MetricId::CoverageBinary => "differing pixels per original covered pixel, 0–1",
            MetricId::ColourDifference => "linear RGB, 0–1",
            MetricId::PlaneDistance | MetricId::ProjectedDistance | MetricId::EuclideanDistance => {
                "world units"
            }
            MetricId::Orientation => "0–1",
            MetricId::DominatingAxis | MetricId::DominatingAxisSpectral => {
                "0–1 (App. A normalisation)"
            }
        }
    }

    /// Whether the metric follows from others (§5.2: the Euclidean distance from the plane
    /// and projected distances). It is in the report and `results.csv`, but neither charted
    /// nor in the stability table, which would only repeat its parts.
    pub fn is_derived(self) -> bool {
        self == MetricId::EuclideanDistance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn every_id_has_unique_columns_and_some_words() {
        let mut columns = HashSet::new();
        for id in MetricId::ALL {
            assert!(columns.insert(id.column()), "{id:?}: column used twice");
            assert!(
                columns.insert(id.max_column()),
                "{id:?}: max column used twice"
            );
            assert_eq!(id.max_column(), format!("{}_max", id.column()), "{id:?}");
            for (what, text) in [
                ("label", id.label()),
                ("short label", id.short_label()),
                ("definition", id.definition()),
                ("unit", id.unit()),
            ] {
                assert!(!text.trim().is_empty(), "{id:?}: empty {what}");
            }
            assert!(id.definition().contains('§') || id == MetricId::ColourDifference);
            assert_eq!(
                id.json_path().last().copied(),
                Some(match id {
                    MetricId::CoverageStatic => "static",
                    MetricId::CoverageAnimated => "animated",
                    MetricId::CoverageBinary => "binary",
                    MetricId::CoverageFoliage => "foliage",
                    _ => id.column(),
                })
            );
        }
        let labels: HashSet<&str> = MetricId::ALL.iter().map(|id| id.label()).collect();
        assert_eq!(labels.len(), MetricId::ALL.len(), "labels must differ");
        let sorted = {
            let mut v = MetricId::ALL;
            v.sort();
            v
        };
        assert_eq!(
            sorted,
            MetricId::ALL,
            "ALL lists every id once, in declaration order"
        );
    }
}
