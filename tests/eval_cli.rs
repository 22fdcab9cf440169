//! `frond eval` end to end: known answers (a file against itself scores 0 everywhere), a
//! per-bone LOD stays within its ε, foreign candidates get the image metrics and a reason for
//! the rest, bad input fails cleanly.

mod common;

use std::path::Path;

use common::*;
use frond_app::inspect::InspectReport;
use frond_metrics::{EvalReport, Metric, MetricId};

fn eval(original: &Path, candidate: &Path, extra: &[&str]) -> EvalReport {
    let mut args = vec!["--samples", "16", "--views", "3", "--frames", "3"];
    args.extend_from_slice(extra);
    frond_eval(original, candidate, &args)
}

/// The metrics beside the coverage pair: every metric after the first two.
const METRICS: &[MetricId] = MetricId::ALL.split_at(2).1;

/// The report's static and animated coverage metrics, with their keys.
fn coverage(r: &EvalReport) -> [(&'static str, &Metric); 2] {
    [
        ("static", &r.coverage.static_),
        ("animated", &r.coverage.animated),
    ]
}

#[test]
fn a_file_against_itself_scores_zero_everywhere() {
    let sapling = root().join("samples/sapling.glb");
    let r = eval(&sapling, &sapling, &["--size", "160x120"]);
    for (key, m) in coverage(&r) {
        assert_eq!(m.mean, Some(0.0), "coverage.{key}");
        assert!(!m.definition.is_empty());
    }
    // Distances are in world units (float noise scales with the tree), the rest in [0, 1].
    let h = written_f64(r.tree_height);
    for &id in METRICS {
        let tol = if matches!(
            id,
            MetricId::PlaneDistance | MetricId::ProjectedDistance | MetricId::EuclideanDistance
        ) {
            1e-6 * h
        } else {
            1e-5
        };
        let m = r.metric(id);
        for (agg, v) in [("mean", m.mean), ("max", m.max)] {
            let v = v.unwrap_or(f64::NAN);
            assert!(v.abs() <= tol, "{id:?}.{agg} = {v}");
        }
    }
    assert_eq!(r.cost.original, r.cost.candidate);
    assert!(r.matching.starts_with("identity"));
}

#[test]
fn the_cost_is_read_from_the_files_and_agrees_with_inspect() {
    let sapling = root().join("samples/sapling.glb");
    let r = eval(&sapling, &sapling, &["--size", "80x60"]);
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
        "--size",
        "80x60",
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
    let cov = r.coverage.animated.mean.expect("coverage");
    assert!(cov > 0.0 && cov < 0.2, "coverage {cov}");
    assert_eq!(
        r.cost.candidate.billboards, lods.lods[1].billboards,
        "cost counts the LOD's billboards"
    );
    assert_eq!(r.size, [160, 120]);
    // The same file without its sidecar: image metrics only, a reason for the rest.
    let foreign = dir.path().join("foreign.glb");
    std::fs::copy(&lod1, &foreign).expect("copy");
    let r = eval(&sapling, &foreign, &["--size", "160x120"]);
    assert!(r.coverage.static_.mean.is_some());
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
    let r = eval(&sapling, &packed, &["--size", "160x120"]);
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
    let r = eval(&sapling, &empty, &["--size", "160x120"]);
    for (key, m) in coverage(&r) {
        assert_eq!(m.mean, Some(1.0), "coverage.{key}");
    }
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
