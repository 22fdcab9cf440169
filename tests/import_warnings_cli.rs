//! The importer's warnings reach `frond inspect --json` (under `warnings[]`, one line each,
//! naming what they are about), and its refusals reach the command line as one-line errors.

use crate::common;

use std::path::Path;

use common::*;
use frond_app::inspect::InspectReport;
use frond_scene::gltf_writer::glb_container;
use serde_json::{Value, json};

/// A two-quad leaf mesh with several silently-accepted flaws: a `"scene"` index past the
/// scene list, a zero byteStride, 7 indices in TRIANGLES mode and a morph target.
fn flawed() -> (Value, Vec<u8>) {
    let positions: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let mut bin: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(
        [0u16, 1, 2, 0, 2, 3, 1, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes()),
    );
    let doc = json!({
        "asset": { "version": "2.0" },
        "scene": 3,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "name": "tree", "mesh": 0 }],
        "meshes": [{ "name": "leaves", "primitives": [{
            "attributes": { "POSITION": 0 }, "indices": 1, "targets": [{ "POSITION": 0 }] }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5123, "count": 7, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48, "byteStride": 0 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 16 }
        ],
        "buffers": [{ "byteLength": bin.len() }]
    });
    (doc, bin)
}

fn write(dir: &Path, name: &str, doc: &Value, bin: &[u8]) -> String {
    let path = dir.join(name);
    let bytes = glb_container(&serde_json::to_vec(doc).expect("json"), bin);
    std::fs::write(&path, bytes).expect("write");
    path.to_str().expect("utf-8").to_string()
}

#[test]
fn inspect_json_lists_the_import_warnings() {
    let dir = tempfile::tempdir().expect("tmp");
    let (doc, bin) = flawed();
    let path = write(dir.path(), "flawed.glb", &doc, &bin);
    let out = frond_ok(&["inspect", "--json", "--samples", "2", &path]);
    let r: InspectReport = parse_json(&out.stdout);
    let warnings: Vec<&str> = r.warnings.iter().map(String::as_str).collect();
    for want in [
        "\"scene\" is 3, but the file has 1 scenes; frond reads every node regardless",
        "bufferView 0: byteStride 0 is invalid (glTF allows 4 to 252); accessor 0 read it as tightly packed",
        "mesh 'leaves' primitive 0: 7 indices is not a multiple of 3 for TRIANGLES; the last 1 dropped",
        "mesh 'leaves' primitive 0: 1 morph target ignored (frond reads the base shape only)",
    ] {
        assert!(
            warnings.contains(&want),
            "no warning '{want}' in {warnings:#?}"
        );
    }
    assert!(warnings.iter().all(|w| !w.contains('\n')), "{warnings:#?}");
    assert_eq!(r.triangles.total, 2);
}

#[test]
fn inspect_refuses_a_negative_key_time_in_one_line() {
    let dir = tempfile::tempdir().expect("tmp");
    let (mut doc, mut bin) = flawed();
    let at = bin.len();
    bin.extend([-0.5f32, 1.0].iter().flat_map(|v| v.to_le_bytes()));
    bin.extend(
        [0.0f32, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes()),
    );
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    doc["bufferViews"].as_array_mut().expect("views").extend([
        json!({ "buffer": 0, "byteOffset": at, "byteLength": 8 }),
        json!({ "buffer": 0, "byteOffset": at + 8, "byteLength": 24 }),
    ]);
    doc["accessors"].as_array_mut().expect("accessors").extend([
        json!({ "bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR",
                "min": [-0.5], "max": [1.0] }),
        json!({ "bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3" }),
    ]);
    doc["animations"] = json!([{ "name": "wind",
        "samplers": [{ "input": 2, "output": 3 }],
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }] }]);
    let path = write(dir.path(), "negative.glb", &doc, &bin);
    let out = frond(&["inspect", "--json", &path]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(&format!(
            "{path}: animation 'wind' channel 0: key time -0.5 at key 0 is negative (glTF requires times ≥ 0)"
        )),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// `frond lod`'s report carries the import's warnings too (`warnings[]`).
#[test]
fn lod_reports_the_import_warnings() {
    let dir = tempfile::tempdir().expect("tmp");
    let bytes = std::fs::read(root().join("samples/sapling.glb")).expect("sample");
    let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
    let mut doc: Value = serde_json::from_slice(&glb.json).expect("json");
    doc["scene"] = json!(7);
    let bin = glb.bin.expect("bin");
    let tree = dir.path().join("warned.glb");
    std::fs::write(
        &tree,
        glb_container(&serde_json::to_vec(&doc).expect("json"), &bin),
    )
    .expect("write");
    let out = dir.path().join("out");
    let report = frond_lod(&tree, &out, &["--lods", "60"]);
    let warnings = &report.warnings;
    assert!(
        warnings.iter().any(|w| w.contains("\"scene\" is 7")),
        "{warnings:?}"
    );
}
