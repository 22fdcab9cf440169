//! Rendering a shared tree: frames are plausible and the wind visibly moves the foliage.

mod common;

use common::*;
use frond::render_cmd::{RenderRequest, render_tree};
use frond_render::{Renderer, TreeParts};
use frond_scene::{ImportOptions, import};

fn request(time: f32) -> RenderRequest {
    RenderRequest {
        clip: None,
        time,
        azimuth_deg: 0.0,
        elevation_deg: 10.0,
        zoom: 1.0,
        width: 256,
        height: 256,
        orthographic: false,
        parts: TreeParts::All,
    }
}

#[test]
fn frames_at_zero_and_quarter_period_are_plausible_and_differ() {
    let tree = import(&shared_tree("oak_medium.glb"), &ImportOptions::default()).expect("imports");
    let period = tree.clips[0].duration();
    let renderer = Renderer::new().expect("a graphics adapter (Mesa llvmpipe on CI)");
    let a = render_tree(&renderer, &tree, &request(0.0)).expect("renders");
    let b = render_tree(&renderer, &tree, &request(period / 4.0)).expect("renders");
    // A framed tree covers a real part of the image but not all of it.
    for f in [&a, &b] {
        let c = f.coverage_fraction();
        assert!((0.05..0.6).contains(&c), "coverage {c}");
    }
    // Leaves swing by up to ~2.5 units in a 65-unit tree (MANIFEST bpyCheck), i.e. several
    // pixels at 256 px, so thousands of leaf pixels change between the two times.
    let changed = a
        .coverage
        .iter()
        .zip(&b.coverage)
        .filter(|(x, y)| x != y)
        .count();
    assert!(changed > 500, "only {changed} pixels changed coverage");
    // The same time twice is the same image: the difference is the animation, not noise.
    let a2 = render_tree(&renderer, &tree, &request(0.0)).expect("renders");
    assert_eq!(a.coverage, a2.coverage);
}

#[test]
fn render_cli_writes_a_png_and_reports_coverage() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("bush.png");
    let run = frond(&[
        "render",
        shared_tree("bush_1.glb").to_str().expect("utf-8"),
        "--time",
        "1.0",
        "--azimuth",
        "-45",
        "--size",
        "96x64",
        "--json",
        "-o",
        out.to_str().expect("utf-8"),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let img = image::open(&out).expect("a PNG").to_rgba8();
    assert_eq!((img.width(), img.height()), (96, 64));
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    let c = report["coverage"].as_f64().expect("coverage");
    assert!(c > 0.05 && c < 0.9, "{c}");
    let opaque = img.pixels().filter(|p| p[3] == 255).count() as f64 / (96.0 * 64.0);
    assert!(
        (opaque - c).abs() < 1e-9,
        "alpha channel is the coverage mask"
    );
}
