//! Real glTF clients agree with us: the Khronos validator accepts what we write, and a
//! gltfpack-quantized tree (KHR_mesh_quantization, KHR_texture_transform) reads back the same.

use crate::common;

use std::process::Command;

use common::*;
use frond_app::render_cmd::{RenderRequest, render_tree};
use frond_render::{Renderer, TreeParts};
use frond_scene::{ImportOptions, import};

#[test]
fn generated_trees_pass_the_khronos_validator() {
    if node_tools().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    for preset in ["small", "medium"] {
        let out = dir.path().join(format!("{preset}.glb"));
        frond_ok(&[
            "sample",
            "--preset",
            preset,
            "--seed",
            "4",
            "-o",
            out.to_str().expect("utf-8"),
        ]);
        let report = validate(&out).expect("the Node clients are installed");
        assert_eq!(report["errors"], 0, "{preset}: {report}");
        assert_eq!(report["warnings"], 0, "{preset}: {report}");
        assert_eq!(report["info"]["hasSkins"], true);
        assert_eq!(report["info"]["animationCount"], 1);
        assert_eq!(report["info"]["hasTextures"], true);
    }
}

#[test]
fn gltfpack_quantized_tree_reads_back_with_the_same_counts_and_look() {
    packed_tree_reads_back(&[], "KHR_mesh_quantization");
}

/// `gltfpack -cc` (EXT_meshopt_compression over quantized data: what assets that went through
/// gltfpack for the web carry) reads back like the original.
#[test]
fn gltfpack_meshopt_compressed_tree_reads_back_with_the_same_counts_and_look() {
    packed_tree_reads_back(&["-cc"], "EXT_meshopt_compression");
}

/// bush_1 through gltfpack with `flags`: the copy must name `marker` (else the test proves
/// nothing) and import with the original's counts, bounds and look.
fn packed_tree_reads_back(flags: &[&str], marker: &str) {
    let Some(tools) = node_tools() else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    // A real exporter's tree (ez-tree's bush_1, committed as a fixture): textured, skinned.
    let src = fixture("bush_1.glb");
    let packed = dir.path().join("bush_1_packed.glb");
    let status = Command::new("node")
        .arg(tools.join("node_modules/gltfpack/cli.js"))
        .arg("-i")
        .arg(&src)
        .arg("-o")
        .arg(&packed)
        .args(flags)
        .status()
        .expect("node runs gltfpack");
    assert!(status.success(), "gltfpack failed");
    let original = import(&src, &ImportOptions::default()).expect("original imports");
    let quantized = import(&packed, &ImportOptions::default()).expect("quantized copy imports");
    // The copy really is quantized (else this test proves nothing).
    let bytes = std::fs::read(&packed).expect("read packed");
    let text = String::from_utf8_lossy(&bytes[..4096.min(bytes.len())]).into_owned();
    assert!(
        text.contains(marker),
        "gltfpack output does not use {marker}"
    );
    assert_eq!(quantized.triangles.len(), original.triangles.len());
    assert_eq!(
        quantized.count(frond_scene::Part::Foliage),
        original.count(frond_scene::Part::Foliage)
    );
    assert_eq!(
        quantized.count(frond_scene::Part::Wood),
        original.count(frond_scene::Part::Wood)
    );
    assert_eq!(quantized.bones.len(), original.bones.len());
    assert_eq!(quantized.skeleton_depth(), original.skeleton_depth());
    // Dequantised geometry sits where the original does (quantisation step ~ 1e-4 of the size).
    for k in 0..3 {
        assert!((quantized.bounds.min[k] - original.bounds.min[k]).abs() < 0.01);
        assert!((quantized.bounds.max[k] - original.bounds.max[k]).abs() < 0.01);
    }
    // And looks the same: coverage of the same view within half a percent of the image,
    // which needs both positions and texture coordinates dequantised right.
    let renderer = Renderer::new().expect("a graphics adapter (Mesa llvmpipe on CI)");
    let req = RenderRequest {
        time: 1.0,
        azimuth_deg: 30.0,
        parts: TreeParts::Foliage,
        ..Default::default()
    };
    let a = render_tree(&renderer, &original, &req).expect("renders");
    let b = render_tree(&renderer, &quantized, &req).expect("renders");
    let (ca, cb) = (a.coverage_fraction(), b.coverage_fraction());
    assert!(ca > 0.05, "foliage is visible ({ca})");
    assert!((ca - cb).abs() < 0.005, "coverage {ca} vs {cb}");
}
