//! Small glTF documents the bad-input tests break one thing of: a valid one-triangle `.gltf` with
//! an external `tri.bin`.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

/// A valid one-triangle glTF with an external `tri.bin`; tests then break one thing.
pub fn triangle_gltf() -> Value {
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "name": "leaf", "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 6 }
        ],
        "buffers": [{ "uri": "tri.bin", "byteLength": 42 }]
    })
}

pub fn triangle_bin(positions: [f32; 9], indices: [u16; 3]) -> Vec<u8> {
    let mut b: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    b.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
    b
}

pub const GOOD: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Writes `doc` (and `tri.bin`) into `dir/sub`, returns the .gltf path.
pub fn write_case(dir: &Path, name: &str, doc: &Value, bin: &[u8]) -> PathBuf {
    let sub = dir.join(name);
    std::fs::create_dir_all(&sub).expect("mkdir");
    std::fs::write(sub.join("tri.bin"), bin).expect("write bin");
    let path = sub.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec(doc).expect("json")).expect("write gltf");
    path
}
