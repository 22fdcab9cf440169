//! `frond lod` writes the input's materials back unchanged: LOD0's
//! materials, and the wood of the billboard LODs, carry every map, factor, extension and extra
//! of the input's, their textures keep the input's samplers, and their images are the input's
//! bytes with the input's MIME type (a JPEG stays the same JPEG), embedded or external alike.
//!
//! The input is the generated `Small` tree with its bark material made rich: a JPEG base colour
//! with a `KHR_texture_transform`, normal, occlusion (on `TEXCOORD_1`, which the test adds),
//! metallic-roughness and emissive maps with non-default factors, a MIRRORED_REPEAT sampler,
//! `KHR_materials_emissive_strength` and extras. Everything is read back from the written files.

use crate::common;

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use common::*;
use frond_scene::generator::{Preset, generate};
use frond_scene::gltf_writer::{encode_png, glb_container};
use serde_json::{Value, json};

/// A JPEG of a smooth gradient.
fn jpeg(width: u32, height: u32) -> Vec<u8> {
    let img = image::RgbImage::from_fn(width, height, |x, y| {
        image::Rgb([(x * 4) as u8, (y * 4) as u8, 90])
    });
    let mut out = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 85)
        .encode_image(&img)
        .expect("encode jpeg");
    assert!(out.starts_with(&[0xFF, 0xD8, 0xFF]), "a JPEG");
    out
}

/// A small PNG of constant colour.
fn png(rgba: [u8; 4]) -> Vec<u8> {
    let pixels: Vec<u8> = std::iter::repeat_n(rgba, 16 * 16).flatten().collect();
    encode_png(16, 16, &pixels).expect("encode png")
}

/// The images the rich bark material uses: (name, bytes, MIME type, file name when external).
fn rich_images() -> Vec<(&'static str, Vec<u8>, &'static str, &'static str)> {
    vec![
        ("bark_colour", jpeg(64, 64), "image/jpeg", "bark_colour.jpg"),
        (
            "bark_normal",
            png([128, 128, 255, 255]),
            "image/png",
            "bark_normal.png",
        ),
        (
            "bark_occlusion",
            png([200, 0, 0, 255]),
            "image/png",
            "bark_ao.png",
        ),
        (
            "bark_mr",
            png([0, 150, 30, 255]),
            "image/png",
            "bark_mr.png",
        ),
        (
            "bark_emissive",
            png([10, 20, 30, 255]),
            "image/png",
            "bark_emissive.png",
        ),
    ]
}

/// TEXCOORD_1 of a vertex from its TEXCOORD_0: distinct from it, so swapped sets show.
fn second_set(uv: [f32; 2]) -> [f32; 2] {
    [uv[0] * 0.5 + 0.25, 1.0 - uv[1]]
}

/// Appends `bytes` to `bin` (4-byte aligned) as a new buffer view of `doc`; returns its index.
fn push_view(doc: &mut Value, bin: &mut Vec<u8>, bytes: &[u8]) -> usize {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let views = doc["bufferViews"].as_array_mut().expect("bufferViews");
    views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len() }));
    bin.extend_from_slice(bytes);
    views.len() - 1
}

/// The generated tree with the rich bark material, written into `dir`: a `.glb` with embedded
/// images, or (`external`) a `.gltf` with its buffer and images in files beside it.
fn rich_input(dir: &Path, external: bool) -> PathBuf {
    let generated = generate(Preset::Small, 7).expect("generate");
    let glb = gltf::binary::Glb::from_slice(&generated.glb).expect("glb");
    let mut doc: Value = serde_json::from_slice(&glb.json).expect("json");
    let mut bin = glb.bin.expect("bin").into_owned();

    // TEXCOORD_1 on every primitive of the bark material (which the occlusion map uses).
    let bark = doc["materials"]
        .as_array()
        .expect("materials")
        .iter()
        .position(|m| m["name"] == "bark")
        .expect("a bark material");
    let meshes = doc["meshes"].as_array().expect("meshes").len();
    for m in 0..meshes {
        let prims = doc["meshes"][m]["primitives"]
            .as_array()
            .expect("prims")
            .len();
        for p in 0..prims {
            if doc["meshes"][m]["primitives"][p]["material"] != json!(bark) {
                continue;
            }
            let acc = doc["meshes"][m]["primitives"][p]["attributes"]["TEXCOORD_0"]
                .as_u64()
                .expect("TEXCOORD_0") as usize;
            let a = doc["accessors"][acc].clone();
            assert_eq!(a["componentType"], 5126, "float UVs");
            let view = &doc["bufferViews"][a["bufferView"].as_u64().expect("view") as usize];
            let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
                + a["byteOffset"].as_u64().unwrap_or(0) as usize;
            let count = a["count"].as_u64().expect("count") as usize;
            let uv1: Vec<u8> = bin[start..start + count * 8]
                .chunks_exact(8)
                .flat_map(|c| {
                    let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
                    second_set([f(0), f(4)])
                })
                .flat_map(f32::to_le_bytes)
                .collect();
            let v = push_view(&mut doc, &mut bin, &uv1);
            let accessors = doc["accessors"].as_array_mut().expect("accessors");
            accessors.push(json!({
                "bufferView": v, "componentType": 5126, "count": count, "type": "VEC2"
            }));
            let id = accessors.len() - 1;
            doc["meshes"][m]["primitives"][p]["attributes"]["TEXCOORD_1"] = json!(id);
        }
    }

    // Images, one sampler, textures.
    let first_image = doc["images"].as_array().expect("images").len();
    for (name, bytes, mime, file) in rich_images() {
        let image = if external {
            std::fs::write(dir.join(file), &bytes).expect("write image");
            json!({ "name": name, "uri": file })
        } else {
            let v = push_view(&mut doc, &mut bin, &bytes);
            json!({ "name": name, "mimeType": mime, "bufferView": v })
        };
        doc["images"].as_array_mut().expect("images").push(image);
    }
    let samplers = doc["samplers"].as_array_mut().expect("samplers");
    samplers.push(json!({
        "name": "mirror", "magFilter": 9728, "minFilter": 9984, "wrapS": 33648, "wrapT": 33071
    }));
    let sampler = samplers.len() - 1;
    let first_texture = doc["textures"].as_array().expect("textures").len();
    for k in 0..rich_images().len() {
        let mut t = json!({ "source": first_image + k, "sampler": sampler });
        if k == 0 {
            t["name"] = json!("bark_colour_texture");
            t["extras"] = json!({ "origin": "scan" });
        }
        doc["textures"].as_array_mut().expect("textures").push(t);
    }
    let t = |k: usize| first_texture + k;
    doc["materials"][bark] = json!({
        "name": "bark",
        "pbrMetallicRoughness": {
            "baseColorFactor": [0.9, 0.8, 0.7, 1.0],
            "baseColorTexture": {
                "index": t(0),
                "extensions": { "KHR_texture_transform": { "scale": [2.0, 1.0], "offset": [0.1, 0.0] } }
            },
            "metallicFactor": 0.25,
            "roughnessFactor": 0.75,
            "metallicRoughnessTexture": { "index": t(3) }
        },
        "normalTexture": { "index": t(1), "scale": 0.6 },
        "occlusionTexture": { "index": t(2), "strength": 0.8, "texCoord": 1 },
        "emissiveTexture": { "index": t(4) },
        "emissiveFactor": [0.2, 0.1, 0.05],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 2.0 } },
        "extras": { "shader": "bark_v2" }
    });
    let mut used = doc["extensionsUsed"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    for e in ["KHR_texture_transform", "KHR_materials_emissive_strength"] {
        if !used.contains(&json!(e)) {
            used.push(json!(e));
        }
    }
    doc["extensionsUsed"] = json!(used);

    if external {
        std::fs::write(dir.join("rich.bin"), &bin).expect("write bin");
        doc["buffers"] = json!([{ "uri": "rich.bin", "byteLength": bin.len() }]);
        let path = dir.join("rich.gltf");
        std::fs::write(&path, serde_json::to_vec(&doc).expect("json")).expect("write gltf");
        path
    } else {
        doc["buffers"] = json!([{ "byteLength": bin.len() }]);
        let path = dir.join("rich.glb");
        let json_bytes = serde_json::to_vec(&doc).expect("json");
        std::fs::write(&path, glb_container(&json_bytes, &bin)).expect("write glb");
        path
    }
}

/// A glTF file read back: its JSON, its binary chunk or buffer, and its folder.
struct Doc {
    json: Value,
    bin: Vec<u8>,
    dir: PathBuf,
}

impl Doc {
    fn read(path: &Path) -> Doc {
        let bytes = std::fs::read(path).expect("read");
        let dir = path.parent().expect("dir").to_path_buf();
        if bytes.starts_with(b"glTF") {
            let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
            Doc {
                json: serde_json::from_slice(&glb.json).expect("json"),
                bin: glb.bin.map(|b| b.into_owned()).unwrap_or_default(),
                dir,
            }
        } else {
            let json: Value = serde_json::from_slice(&bytes).expect("json");
            let uri = json["buffers"][0]["uri"].as_str().expect("buffer uri");
            let bin = std::fs::read(dir.join(uri)).expect("buffer");
            Doc { json, bin, dir }
        }
    }

    /// Image `i`'s bytes, its MIME type (None when the file gives none) and its uri, if any.
    fn image(&self, i: usize) -> (Vec<u8>, Option<String>, Option<String>) {
        let img = &self.json["images"][i];
        let mime = img["mimeType"].as_str().map(str::to_string);
        match img["uri"].as_str() {
            Some(uri) => (
                std::fs::read(self.dir.join(uri)).expect("image file"),
                mime,
                Some(uri.to_string()),
            ),
            None => {
                let v =
                    &self.json["bufferViews"][img["bufferView"].as_u64().expect("view") as usize];
                let start = v["byteOffset"].as_u64().unwrap_or(0) as usize;
                let len = v["byteLength"].as_u64().expect("len") as usize;
                (self.bin[start..start + len].to_vec(), mime, None)
            }
        }
    }

    /// Material `name` with every texture map's `index` replaced by what it names: the
    /// texture's other members, its sampler's JSON and a hash of its image's bytes with the
    /// image's name and MIME type (the file's extension when it gives none), so materials of
    /// two files compare equal exactly when they look the same.
    fn resolved_material(&self, name: &str) -> Value {
        let mut m = self.json["materials"]
            .as_array()
            .expect("materials")
            .iter()
            .find(|m| m["name"] == name)
            .unwrap_or_else(|| panic!("material {name}"))
            .clone();
        resolve(&mut m, self);
        m
    }

    /// Every TEXCOORD_0 → TEXCOORD_1 pair of primitives with material `name`.
    fn uv_pairs(&self, name: &str) -> Vec<([f32; 2], [f32; 2])> {
        let mats = self.json["materials"].as_array().expect("materials");
        let mut pairs = Vec::new();
        for mesh in self.json["meshes"].as_array().expect("meshes") {
            for p in mesh["primitives"].as_array().expect("prims") {
                let Some(m) = p["material"].as_u64() else {
                    continue;
                };
                if mats[m as usize]["name"] != name {
                    continue;
                }
                let a = |k: &str| self.floats(p["attributes"][k].as_u64().expect(k) as usize);
                let (uv0, uv1) = (a("TEXCOORD_0"), a("TEXCOORD_1"));
                assert_eq!(uv0.len(), uv1.len());
                for (u0, u1) in uv0.chunks_exact(2).zip(uv1.chunks_exact(2)) {
                    pairs.push(([u0[0], u0[1]], [u1[0], u1[1]]));
                }
            }
        }
        pairs
    }

    fn floats(&self, accessor: usize) -> Vec<f32> {
        let a = &self.json["accessors"][accessor];
        assert_eq!(a["componentType"], 5126);
        let v = &self.json["bufferViews"][a["bufferView"].as_u64().expect("view") as usize];
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
            + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        let n = a["count"].as_u64().expect("count") as usize * 2;
        self.bin[start..start + n * 4]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }
}

fn resolve(v: &mut Value, doc: &Doc) {
    let Value::Object(map) = v else { return };
    for (key, val) in map.iter_mut() {
        if key.ends_with("Texture")
            && let Some(t) = val.get("index").and_then(Value::as_u64)
        {
            let mut texture = doc.json["textures"][t as usize].clone();
            let source = texture["source"].as_u64().expect("source") as usize;
            let sampler = texture["sampler"]
                .as_u64()
                .map(|s| doc.json["samplers"][s as usize].clone());
            let obj = texture.as_object_mut().expect("texture");
            obj.remove("source");
            obj.remove("sampler");
            let (bytes, mime, uri) = doc.image(source);
            let mime =
                mime.unwrap_or_else(|| match uri.as_deref().and_then(|u| u.rsplit('.').next()) {
                    Some("jpg" | "jpeg") => "image/jpeg".into(),
                    Some("png") => "image/png".into(),
                    other => panic!("image without mimeType and known extension: {other:?}"),
                });
            let mut h = DefaultHasher::new();
            bytes.hash(&mut h);
            val["index"] = json!({
                "texture": texture,
                "sampler": sampler,
                "image": {
                    "name": doc.json["images"][source]["name"],
                    "mime": mime,
                    "bytes": h.finish().to_string(),
                    "len": bytes.len(),
                }
            });
        } else {
            resolve(val, doc);
        }
    }
}

/// A resolved material with each image reduced to the name it was downscaled from (a `_WxH`
/// suffix dropped), after checking that a downscaled one is a PNG.
fn downscaled_as_input(m: &serde_json::Value) -> serde_json::Value {
    let mut m = m.clone();
    fn walk(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(map) => {
                if let Some(image) = map.get_mut("image") {
                    let name = image["name"].as_str().unwrap_or_default().to_string();
                    let base = match name.rsplit_once('_') {
                        Some((b, size)) if size.split('x').all(|n| n.parse::<u32>().is_ok()) => {
                            assert_eq!(image["mime"], "image/png", "{name}: a downscaled PNG");
                            b.to_string()
                        }
                        _ => name,
                    };
                    *image = serde_json::json!({ "name": base });
                }
                for (_, x) in map.iter_mut() {
                    walk(x);
                }
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(walk),
            _ => {}
        }
    }
    walk(&mut m);
    m
}

/// Runs `frond lod` on the rich input and checks LOD0 and LOD1 against it.
fn check(external_input: bool, external_output: bool) {
    let dir = tempfile::tempdir().expect("tmp");
    let input = rich_input(dir.path(), external_input);
    let out = dir.path().join("out");
    let mut extra = vec!["--lods", "120", "--method", "static"];
    if external_output {
        extra.push("--external-textures");
    }
    frond_lod(&input, &out, &extra);
    let source = Doc::read(&input);
    let bark = source.resolved_material("bark");
    let leaves = source.resolved_material("leaves");
    // Sanity of the comparison itself: the JPEG, the sampler and every map are in it.
    let text = bark.to_string();
    for needle in [
        "image/jpeg",
        "33648",
        "normalTexture",
        "occlusionTexture",
        "metallicRoughnessTexture",
        "emissiveTexture",
        "KHR_texture_transform",
        "bark_v2",
        "scan",
    ] {
        assert!(text.contains(needle), "{needle} in {text}");
    }
    let images = rich_images();
    for lod in ["LOD0", "LOD1"] {
        let path = out.join(format!("rich_{lod}.glb"));
        let doc = Doc::read(&path);
        if lod == "LOD1" {
            // A farther LOD draws its maps at its texel density: the same material, maps,
            // factors and samplers, each image a PNG named `<name>_<w>x<h>` no larger than
            // the input's (the wood's images are 4² to 8² here; 120 px needs less).
            assert_eq!(
                downscaled_as_input(&doc.resolved_material("bark")),
                downscaled_as_input(&bark),
                "{lod}: bark material"
            );
            continue;
        }
        assert_eq!(doc.resolved_material("bark"), bark, "{lod}: bark material");
        if lod == "LOD0" {
            assert_eq!(
                doc.resolved_material("leaves"),
                leaves,
                "{lod}: leaf material"
            );
        }
        // Byte-identical images with their MIME type, embedded or as files with the right
        // extension.
        for (name, bytes, mime, _) in &images {
            let i = doc.json["images"]
                .as_array()
                .expect("images")
                .iter()
                .position(|im| im["name"] == *name)
                .unwrap_or_else(|| panic!("{lod}: image {name}"));
            let (written, written_mime, uri) = doc.image(i);
            assert!(
                written == *bytes,
                "{lod}: image {name} is the input's bytes"
            );
            assert_eq!(written_mime.as_deref(), Some(*mime), "{lod}: {name}");
            match uri {
                Some(uri) => {
                    assert!(external_output, "{lod}: {name} external only when asked");
                    let ext = if *mime == "image/jpeg" {
                        ".jpg"
                    } else {
                        ".png"
                    };
                    assert!(uri.ends_with(ext), "{lod}: {uri} ends with {ext}");
                }
                None => assert!(!external_output, "{lod}: {name} embedded unless asked"),
            }
        }
        let used = doc.json["extensionsUsed"].to_string();
        for e in ["KHR_texture_transform", "KHR_materials_emissive_strength"] {
            assert!(used.contains(e), "{lod}: {e} in extensionsUsed {used}");
        }
        // TEXCOORD_1 carried through (welding and simplification keep each vertex's pair).
        let pairs = doc.uv_pairs("bark");
        assert!(!pairs.is_empty(), "{lod}: bark triangles");
        for (uv0, uv1) in pairs {
            let want = second_set(uv0);
            assert!(
                (uv1[0] - want[0]).abs() < 1e-6 && (uv1[1] - want[1]).abs() < 1e-6,
                "{lod}: TEXCOORD_1 {uv1:?} for TEXCOORD_0 {uv0:?}, want {want:?}"
            );
        }
    }
}

#[test]
fn lod0_and_lod1_wood_keep_the_input_materials_images_and_samplers() {
    check(false, false);
}

#[test]
fn external_textures_are_the_input_bytes_with_their_extension() {
    check(false, true);
}

#[test]
fn external_input_images_pass_through_too() {
    check(true, false);
}
