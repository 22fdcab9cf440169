//! Bad input: a one-line error naming the file and the problem, exit code 1, no panic, and no
//! output file left behind.

use crate::common;

use std::path::Path;

use common::gltf_cases::*;
use common::*;
use serde_json::json;

/// Runs inspect and render on a bad file and checks the error contract.
fn expect_clean_error(path: &Path, needle: &str) {
    let p = path.to_str().expect("utf-8");
    let out = frond(&["inspect", p]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{p}: exit code; stderr: {err}");
    assert!(!err.contains("panicked"), "{p}: panicked: {err}");
    assert!(err.contains(p), "{p}: error does not name the file: {err}");
    assert!(
        err.contains(needle),
        "{p}: error does not say '{needle}': {err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{p}: one line: {err}");
    let png = path.with_extension("png");
    let out = frond(&["render", p, "-o", png.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!png.exists(), "{p}: a failed render left {png:?}");
}

#[test]
fn the_valid_base_case_imports() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = write_case(
        dir.path(),
        "good",
        &triangle_gltf(),
        &triangle_bin(GOOD, [0, 1, 2]),
    );
    let out = frond(&["inspect", "--json", path.to_str().expect("utf-8")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: frond_app::inspect::InspectReport = parse_json(&out.stdout);
    assert_eq!(r.triangles.total, 1);
    assert_eq!(r.bones, 0);
    assert!(
        r.warnings.iter().any(|w| w.contains("static tree")),
        "{r:?}"
    );
}

#[test]
fn not_gltf() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = dir.path().join("notes.glb");
    std::fs::write(&path, "these are not the trees you are looking for").expect("write");
    expect_clean_error(&path, "not a glTF file");
}

#[test]
fn truncated_glb() {
    let dir = tempfile::tempdir().expect("tmp");
    let bytes = std::fs::read(fixture("bush_1.glb")).expect("read");
    for cut in [10usize, 100, 5000, bytes.len() / 2] {
        let path = dir.path().join(format!("cut{cut}.glb"));
        std::fs::write(&path, &bytes[..cut]).expect("write");
        expect_clean_error(&path, "truncated");
    }
}

#[test]
fn index_out_of_range() {
    let dir = tempfile::tempdir().expect("tmp");
    let path = write_case(
        dir.path(),
        "index",
        &triangle_gltf(),
        &triangle_bin(GOOD, [0, 1, 5]),
    );
    expect_clean_error(&path, "index 5 is out of range");
}

#[test]
fn accessor_out_of_range() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut doc = triangle_gltf();
    doc["meshes"][0]["primitives"][0]["indices"] = json!(7);
    let path = write_case(dir.path(), "accessor", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    expect_clean_error(&path, "accessor 7 does not exist");
}

#[test]
fn accessor_count_larger_than_its_buffer() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut doc = triangle_gltf();
    doc["accessors"][0]["count"] = json!(300);
    let path = write_case(dir.path(), "count", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    expect_clean_error(&path, "needs 3600 bytes");
}

#[test]
fn nan_and_inf_positions() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut p = GOOD;
    p[4] = f32::NAN;
    let path = write_case(
        dir.path(),
        "nan",
        &triangle_gltf(),
        &triangle_bin(p, [0, 1, 2]),
    );
    expect_clean_error(&path, "NaN or Inf");
    p[4] = f32::INFINITY;
    let path = write_case(
        dir.path(),
        "inf",
        &triangle_gltf(),
        &triangle_bin(p, [0, 1, 2]),
    );
    expect_clean_error(&path, "NaN or Inf");
}

#[test]
fn unsupported_required_extension_is_named() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut doc = triangle_gltf();
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let path = write_case(dir.path(), "ext", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    expect_clean_error(
        &path,
        "requires unsupported glTF extension KHR_draco_mesh_compression",
    );
}

#[test]
fn external_uri_outside_the_input_folder() {
    let dir = tempfile::tempdir().expect("tmp");
    std::fs::write(dir.path().join("secret.bin"), triangle_bin(GOOD, [0, 1, 2])).expect("write");
    for uri in [
        "../secret.bin",
        "/etc/passwd",
        "file:///etc/passwd",
        "sub/../../secret.bin",
    ] {
        let mut doc = triangle_gltf();
        doc["buffers"][0]["uri"] = json!(uri);
        let path = write_case(dir.path(), "escape", &doc, &triangle_bin(GOOD, [0, 1, 2]));
        expect_clean_error(&path, "outside the input folder");
    }
}

#[test]
fn missing_image() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut doc = triangle_gltf();
    doc["images"] = json!([{ "uri": "leaf.png" }]);
    doc["textures"] = json!([{ "source": 0 }]);
    doc["materials"] = json!([{ "name": "leaves", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let path = write_case(dir.path(), "image", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    expect_clean_error(&path, "leaf.png' cannot be read (No such file");
}

#[test]
fn no_mesh_at_all() {
    let dir = tempfile::tempdir().expect("tmp");
    let mut doc = triangle_gltf();
    doc["nodes"] = json!([{ "name": "empty" }]);
    doc.as_object_mut().expect("object").remove("meshes");
    let path = write_case(dir.path(), "nomesh", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    expect_clean_error(&path, "no mesh");
}

#[test]
fn missing_input_file() {
    let dir = tempfile::tempdir().expect("tmp");
    expect_clean_error(&dir.path().join("nowhere.glb"), "No such file");
}
