//! `frond eval` end to end: known answers (a file against itself scores 0 everywhere, at every
//! screen height down to a few pixels; an empty candidate scores 1), a per-bone LOD stays
//! within its ε and has a coverage error at every screen height, foreign candidates get the
//! image metrics and a reason for the rest, bad input fails cleanly.

use crate::common;

use std::path::Path;

use common::*;
use frond_app::inspect::InspectReport;
use frond_metrics::report::EVAL_SCHEMA_VERSION;
use frond_metrics::{EvalReport, Metric, MetricId, samples_per_side};

/// `frond eval` with small settings (16 samples, 3 views a ring, 3 frames) but for the
/// options `extra` sets itself.
fn eval(original: &Path, candidate: &Path, extra: &[&str]) -> EvalReport {
    let mut args = Vec::new();
    for pair in ["--samples", "16", "--views", "3", "--frames", "3"].chunks(2) {
        if !extra.contains(&pair[0]) {
            args.extend_from_slice(pair);
        }
    }
    args.extend_from_slice(extra);
    frond_eval(original, candidate, &args)
}

/// The coverage metrics: the whole tree's on the first frame and over the loop, the thesis'
/// binary error on the same renders, the foliage's.
const COVERAGE: [MetricId; 4] = [
    MetricId::CoverageStatic,
    MetricId::CoverageAnimated,
    MetricId::CoverageBinary,
    MetricId::CoverageFoliage,
];

/// The metrics beside the coverage ones: every metric after them.
const METRICS: &[MetricId] = MetricId::ALL.split_at(COVERAGE.len()).1;

/// The report's coverage metrics, with their keys.
fn coverage(r: &EvalReport) -> [(&'static str, &Metric); 4] {
    [
        ("static", &r.coverage.static_),
        ("animated", &r.coverage.animated),
        ("binary", &r.coverage.binary),
        ("foliage", &r.coverage.foliage),
    ]
}

/// Screen heights the coverage error is checked at: trees 8 and 20 pixels high (the most samples
/// a pixel, `K` = 125 and 50), a far LOD's 60 px and a near LOD's 600 px (the fewest, `K` = 2).
const HEIGHTS: [&str; 4] = ["8", "20", "60", "600"];

#[test]
fn a_file_against_itself_scores_zero_everywhere() {
    let sapling = root().join("samples/sapling.glb");
    assert_eq!(
        MetricId::ALL[..COVERAGE.len()],
        COVERAGE,
        "the coverage metrics lead"
    );
    for h in HEIGHTS {
        // Two views a ring and two frames: the known answer holds in every pair.
        let r = eval(
            &sapling,
            &sapling,
            &["--screen-height", h, "--views", "2", "--frames", "2"],
        );
        let height: f32 = h.parse().expect("a height");
        assert_eq!(r.schema_version, EVAL_SCHEMA_VERSION);
        assert_eq!(r.screen_height, height);
        assert_eq!(r.samples_per_side, samples_per_side(height), "{h} px");
        assert_eq!(r.elevations_deg, [0.0, 30.0]);
        let pairs = 2 * r.elevations_deg.len() * 2;
        assert_eq!(r.coverage.pairs, pairs, "{h} px");
        // Exactly 0, a number even where the tree is 8 pixels high: nothing is discarded.
        for (key, m) in coverage(&r) {
            assert_eq!(
                (m.mean, m.max),
                (Some(0.0), Some(0.0)),
                "coverage.{key} at {h} px"
            );
            assert!(!m.definition.is_empty());
        }
        assert_eq!(r.coverage.ratio, 1.0, "{h} px");
        assert_eq!(r.coverage.discarded_pairs, 0, "{h} px");
        // Distances are in world units (float noise scales with the tree), the rest in [0, 1].
        let tree = written_f64(r.tree_height);
        for &id in METRICS {
            let tol = if matches!(
                id,
                MetricId::PlaneDistance | MetricId::ProjectedDistance | MetricId::EuclideanDistance
            ) {
                1e-6 * tree
            } else {
                1e-5
            };
            let m = r.metric(id);
            for (agg, v) in [("mean", m.mean), ("max", m.max)] {
                let v = v.unwrap_or(f64::NAN);
                assert!(v.abs() <= tol, "{id:?}.{agg} = {v} at {h} px");
            }
        }
        assert_eq!(r.cost.original, r.cost.candidate);
        assert!(r.matching.starts_with("identity"));
    }
}

#[test]
fn the_cost_is_read_from_the_files_and_agrees_with_inspect() {
    let sapling = root().join("samples/sapling.glb");
    let r = eval(&sapling, &sapling, &["--screen-height", "60"]);
    let (o, c) = (&r.cost.original, &r.cost.candidate);
    assert_eq!(o, c, "a file against itself costs the same");
    let path = sapling.to_str().expect("utf-8");
    let out = frond_ok(&["inspect", "--json", "--samples", "2", path]);
    let inspect: InspectReport = parse_json(&out.stdout);
    // The importer reads every mesh instance once; the file cost counts the same triangles.
    assert_eq!(c.file.triangles, inspect.triangles.total as u64);
    assert_eq!(c.file.vertices, inspect.vertices as u64);
    assert_eq!(c.file.joints_total, inspect.bones as u64);
    let file_bytes = std::fs::metadata(&sapling).expect("sapling").len();
    assert_eq!(
        c.file.file_bytes, file_bytes,
        "a GLB without external files"
    );
    // Its leaves are alpha-tested, and the card area is the billboard area.
    let area = c.file.alpha_tested_area;
    let cards = c.billboard_area;
    assert!(
        area > 0.0 && (area - cards).abs() <= 1e-3 * cards,
        "{area} vs {cards}"
    );
    // The text report prints the ratio candidate/original of that area: 1 here.
    let text = frond_ok(&[
        "eval",
        path,
        path,
        "--screen-height",
        "60",
        "--views",
        "1",
        "--frames",
        "1",
        "--samples",
        "8",
    ]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("(ratio 1.000)"), "{text}");
}

/// The highest animated coverage error at 120 px of the sample's per-bone LOD built for 300 px:
/// every card its own billboard on its own bone, so what differs is the bake's texels, a few
/// percent of the tree's covered area.
const MAX_PER_BONE_ERROR: f64 = 0.05;

/// The coverage metric's image at `screen_height` with `views` a ring for the original `tree`:
/// its rest bounds framed from every view on the default screen ([`frond_metrics::framing()`]).
fn image_size(tree: &Path, screen_height: f32, views: u32) -> [u32; 2] {
    let t = frond_scene::import(tree, &Default::default()).expect("the tree reads");
    let f = frond_metrics::framing(
        glam::Vec3::from(t.bounds.min),
        glam::Vec3::from(t.bounds.max),
        &frond_metrics::CoverageParams {
            screen_height,
            views,
            ..Default::default()
        },
    )
    .expect("a framing");
    [f.width, f.height]
}

#[test]
fn a_per_bone_lod_stays_within_its_epsilon_and_a_foreign_copy_is_skipped_with_a_reason() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("lods");
    let sapling = root().join("samples/sapling.glb");
    let lods = frond_lod(
        &sapling,
        &out,
        &["--lods", "300", "--method", "per-bone", "--no-cost-budgets"],
    );
    let lod1 = out.join("sapling_LOD1.glb");
    let r = eval(&sapling, &lod1, &["--screen-height", "120"]);
    let eps = written_f64(lods.lods[1].epsilon.expect("epsilon"));
    let plane_max = r.plane_distance.max.expect("plane max");
    assert!(plane_max <= eps * 1.001, "{plane_max} > ε {eps}");
    // Billboards follow their bones exactly: the images do not drift.
    assert!(r.projected_distance.max.expect("projected") < 1e-3 * eps.max(1.0));
    // One billboard a card, on its bone: what is left is the bake at the LOD's texel density,
    // a few percent of the tree's area at most, and the same area, neither thinned nor bloated.
    let cov = r.coverage.animated.mean.expect("coverage");
    assert!(cov > 0.0 && cov < MAX_PER_BONE_ERROR, "coverage {cov}");
    assert!(
        (r.coverage.ratio - 1.0).abs() < 0.01,
        "ratio {}",
        r.coverage.ratio
    );
    assert_eq!(
        r.cost.candidate.billboards, lods.lods[1].billboards,
        "cost counts the LOD's billboards"
    );
    // The image is framed as the metric frames the original at 120 px.
    assert_eq!(r.size, image_size(&sapling, 120.0, 3));
    // A number at every screen height, the tree down to 8 pixels high (one view a ring and one
    // frame, to be quick).
    for h in HEIGHTS {
        let r = eval(
            &sapling,
            &lod1,
            &["--screen-height", h, "--views", "1", "--frames", "1"],
        );
        let height: f32 = h.parse().expect("a height");
        // The filtered errors see the bake's texels however small the tree; the binary one
        // may round them away (a pixel covered when half its samples are).
        for (key, m) in coverage(&r) {
            let v = m.mean.unwrap_or(f64::NAN);
            let low = if key == "binary" {
                0.0
            } else {
                f64::MIN_POSITIVE
            };
            assert!(
                v.is_finite() && v >= low && v < 1.0,
                "coverage.{key} at {h} px: {v}"
            );
        }
        let ratio = r.coverage.ratio;
        assert!(ratio.is_finite() && ratio > 0.0, "ratio at {h} px: {ratio}");
        assert_eq!(r.size, image_size(&sapling, height, 1), "{h} px");
    }
    // The same file without its sidecar: image metrics only (the same as the LOD's), a reason
    // for the rest.
    let foreign = dir.path().join("foreign.glb");
    std::fs::copy(&lod1, &foreign).expect("copy");
    let r = eval(&sapling, &foreign, &["--screen-height", "120"]);
    assert_eq!(r.coverage.animated.mean, Some(cov));
    assert!(r.plane_distance.mean.is_none());
    assert!(
        r.plane_distance
            .skipped_reason
            .as_deref()
            .expect("reason")
            .contains("mapping")
    );
    // The animation metrics match leaves to the nearest candidate surface instead.
    let axis = r.dominating_axis.mean.expect("axis metric");
    assert!((0.0..1.0).contains(&axis), "{axis}");
}

#[test]
fn a_gltfpack_simplified_tree_is_evaluated_like_any_candidate() {
    let Some(tools) = node_tools() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tmp");
    let sapling = root().join("samples/sapling.glb");
    let packed = dir.path().join("sapling_si01.glb");
    let status = std::process::Command::new("node")
        .arg(tools.join("node_modules/gltfpack/cli.js"))
        .args(["-si", "0.1", "-sa", "-i"])
        .arg(&sapling)
        .arg("-o")
        .arg(&packed)
        .status()
        .expect("node runs gltfpack");
    assert!(status.success(), "gltfpack failed");
    let r = eval(&sapling, &packed, &["--screen-height", "120"]);
    let cov = r.coverage.animated.mean.expect("coverage");
    assert!(cov > 0.0 && cov <= 1.0, "{cov}");
    assert!(r.dominating_axis_spectral.mean.is_some());
    assert!(r.plane_distance.mean.is_none());
    let (o, c) = (&r.cost.original, &r.cost.candidate);
    assert!(
        c.file.triangles < o.file.triangles,
        "gltfpack simplified it"
    );
}

#[test]
fn a_missing_candidate_fails_naming_it() {
    let sapling = root().join("samples/sapling.glb");
    let r = frond(&["eval", sapling.to_str().expect("utf-8"), "no/such/lod.glb"]);
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("no/such/lod.glb") && !err.contains("panicked"),
        "{err}"
    );
}

#[test]
fn an_empty_candidate_has_coverage_error_one() {
    let dir = tempfile::tempdir().expect("tmp");
    let empty = dir.path().join("empty.gltf");
    std::fs::write(
        &empty,
        r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[]}]}"#,
    )
    .expect("write");
    let sapling = root().join("samples/sapling.glb");
    let r = eval(&sapling, &empty, &["--screen-height", "120"]);
    // Every covered sample of the original missed, none added: 1 in every pair.
    for (key, m) in coverage(&r) {
        assert_eq!((m.mean, m.max), (Some(1.0), Some(1.0)), "coverage.{key}");
    }
    assert_eq!(r.coverage.ratio, 0.0);
    assert_eq!(
        r.coverage.discarded_pairs, 0,
        "1 is kept by the binary rule"
    );
    assert!(r.colour_difference.mean.is_none());
    assert!(r.dominating_axis.skipped_reason.is_some());
    assert_eq!(r.cost.candidate.file.triangles, 0);
    // Every other command still refuses an empty file.
    let out = dir.path().join("o");
    let refused = frond(&[
        "lod",
        empty.to_str().expect("utf-8"),
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("no mesh"));
}
