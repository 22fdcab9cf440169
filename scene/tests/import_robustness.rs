//! Malformed input the importer must either refuse with an error naming the cause, repair with
//! a warning saying what was repaired, or accept with a warning saying what it read instead:
//! key times, scenes, integer positions, strides, index counts, skin weights, influence sets,
//! morph targets, singular inverse binds, absurd coordinates and clip lengths, deep hierarchies.

use std::path::Path;

use frond_scene::gltf_writer::glb_container;
use frond_scene::rig::Interpolation;
use frond_scene::{ImportOptions, Tree, import_bytes};
use glam::{Mat4, Quat, Vec3, Vec4};
use serde_json::{Value, json};

/// A glTF document under construction: its JSON and its binary chunk.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    /// An empty document with one scene.
    fn new() -> Doc {
        Doc {
            json: json!({
                "asset": { "version": "2.0" },
                "scene": 0,
                "scenes": [{ "nodes": [] }],
                "nodes": [],
                "meshes": [],
                "accessors": [],
                "bufferViews": [],
                "buffers": [{ "byteLength": 0 }]
            }),
            bin: Vec::new(),
        }
    }

    /// Appends `v` to the top-level array `key` (created when absent); returns its index.
    fn push(&mut self, key: &str, v: Value) -> usize {
        if self.json[key].is_null() {
            self.json[key] = json!([]);
        }
        let list = self.json[key].as_array_mut().expect("array");
        list.push(v);
        list.len() - 1
    }

    /// Adds a bufferView over `bytes` and an accessor of `count` elements reading it.
    fn accessor(&mut self, bytes: &[u8], component: u32, ty: &str, count: usize) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = self.push(
            "bufferViews",
            json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }),
        );
        self.bin.extend_from_slice(bytes);
        self.push(
            "accessors",
            json!({ "bufferView": view, "componentType": component, "count": count, "type": ty }),
        )
    }

    fn floats(&mut self, v: &[f32], ty: &str) -> usize {
        let width = match ty {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 16,
        };
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, 5126, ty, v.len() / width)
    }

    fn u16s(&mut self, v: &[u16], ty: &str, count: usize) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, 5123, ty, count)
    }

    fn node(&mut self, node: Value) -> usize {
        self.push("nodes", node)
    }

    fn root(&mut self, node: usize) {
        self.json["scenes"][0]["nodes"]
            .as_array_mut()
            .expect("array")
            .push(json!(node));
    }

    fn child(&mut self, parent: usize, child: usize) {
        let p = &mut self.json["nodes"][parent];
        if p["children"].is_null() {
            p["children"] = json!([]);
        }
        p["children"]
            .as_array_mut()
            .expect("array")
            .push(json!(child));
    }

    /// The primitive `p` of mesh `m`.
    fn prim(&mut self, m: usize, p: usize) -> &mut Value {
        &mut self.json["meshes"][m]["primitives"][p]
    }

    fn glb(&self) -> Vec<u8> {
        let mut json = self.json.clone();
        json["buffers"][0]["byteLength"] = json!(self.bin.len());
        glb_container(&serde_json::to_vec(&json).expect("json"), &self.bin)
    }

    fn import(&self) -> Result<Tree, String> {
        import_bytes(
            Path::new("case.glb"),
            &self.glb(),
            &ImportOptions::default(),
        )
        .map_err(|e| e.to_string())
    }

    fn load(&self) -> Tree {
        self.import().unwrap_or_else(|e| panic!("imports: {e}"))
    }

    fn error(&self) -> String {
        match self.import() {
            Ok(_) => panic!("expected an import error"),
            Err(e) => e,
        }
    }
}

/// Bones in the skeleton of [`skinned`]: a vertical chain, 0.5 apart.
const BONES: usize = 6;

/// A chain of [`BONES`] bones ('bone0' at the origin, each next one 0.5 above), a 1×1 leaf card
/// (mesh 'card', alpha-masked) skinned to the last bone, and an animation 'wind' whose
/// channel 0 rotates bone0 over `times`, `interpolation` ("LINEAR", "STEP", "CUBICSPLINE").
fn skinned(times: &[f32], interpolation: &str) -> Doc {
    let mut d = Doc::new();
    let mut prev = None;
    let mut joints = Vec::new();
    for b in 0..BONES {
        let n = d.node(json!({
            "name": format!("bone{b}"),
            "translation": [0.0, if b == 0 { 0.0 } else { 0.5 }, 0.0]
        }));
        match prev {
            Some(p) => d.child(p, n),
            None => d.root(n),
        }
        prev = Some(n);
        joints.push(n);
    }
    let ibm: Vec<f32> = (0..BONES)
        .flat_map(|b| Mat4::from_translation(Vec3::new(0.0, -0.5 * b as f32, 0.0)).to_cols_array())
        .collect();
    let ibm = d.floats(&ibm, "MAT4");
    d.push(
        "skins",
        json!({ "name": "s", "joints": joints, "inverseBindMatrices": ibm }),
    );
    let pos = d.floats(
        &[0.0, 2.5, 0.0, 1.0, 2.5, 0.0, 1.0, 3.5, 0.0, 0.0, 3.5, 0.0],
        "VEC3",
    );
    let tip = (BONES - 1) as u16;
    let j = d.u16s(&[tip, 0, 0, 0].repeat(4), "VEC4", 4);
    let w = d.floats(&[1.0, 0.0, 0.0, 0.0].repeat(4), "VEC4");
    let idx = d.u16s(&[0, 1, 2, 0, 2, 3], "SCALAR", 6);
    d.push(
        "materials",
        json!({ "name": "plain", "alphaMode": "MASK", "doubleSided": true }),
    );
    d.push(
        "meshes",
        json!({ "name": "card", "primitives": [{
            "attributes": { "POSITION": pos, "JOINTS_0": j, "WEIGHTS_0": w },
            "indices": idx, "material": 0, "mode": 4 }] }),
    );
    let m = d.node(json!({ "name": "card", "mesh": 0, "skin": 0 }));
    d.root(m);
    let per_key = if interpolation == "CUBICSPLINE" { 3 } else { 1 };
    let values: Vec<f32> = (0..times.len() * per_key)
        .flat_map(|k| Quat::from_rotation_z(0.1 * k as f32).to_array())
        .collect();
    let input = d.floats(times, "SCALAR");
    let output = d.floats(&values, "VEC4");
    d.push(
        "animations",
        json!({ "name": "wind",
            "samplers": [{ "input": input, "output": output, "interpolation": interpolation }],
            "channels": [{ "sampler": 0, "target": { "node": 0, "path": "rotation" } }] }),
    );
    d
}

/// A static one-mesh document: mesh 'leaves' (one primitive) on node 'tree'.
fn static_mesh(positions: &[f32], indices: Option<&[u16]>) -> Doc {
    let mut d = Doc::new();
    let pos = d.floats(positions, "VEC3");
    let mut prim = json!({ "attributes": { "POSITION": pos }, "mode": 4 });
    if let Some(i) = indices {
        prim["indices"] = json!(d.u16s(i, "SCALAR", i.len()));
    }
    d.push("meshes", json!({ "name": "leaves", "primitives": [prim] }));
    let n = d.node(json!({ "name": "tree", "mesh": 0 }));
    d.root(n);
    d
}

const QUAD: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];

/// The warning that contains `needle`, or a panic listing them all.
fn warning<'a>(tree: &'a Tree, needle: &str) -> &'a str {
    tree.warnings
        .iter()
        .find(|w| w.contains(needle))
        .unwrap_or_else(|| panic!("no warning says '{needle}': {:#?}", tree.warnings))
}

fn assert_error(e: &str, needle: &str) {
    assert!(e.contains(needle), "error does not say '{needle}': {e}");
    assert!(e.starts_with("case.glb: "), "error names the file: {e}");
    assert_eq!(e.lines().count(), 1, "one line: {e}");
}

/// Every clip channel has what glTF requires of a sampler input.
fn assert_valid_times(tree: &Tree) {
    for clip in &tree.rig.clips {
        for ch in &clip.channels {
            assert!(
                ch.times.iter().all(|t| t.is_finite() && *t >= 0.0),
                "{ch:?}"
            );
            assert!(ch.times.windows(2).all(|w| w[0] < w[1]), "{ch:?}");
            let per_key = if ch.interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            assert_eq!(ch.values.len(), ch.times.len() * per_key);
        }
    }
}

#[test]
fn the_base_documents_import_without_warnings_about_them() {
    let tree = skinned(&[0.0, 1.0, 2.0], "LINEAR").load();
    assert_eq!(tree.bones.len(), BONES);
    assert_eq!(tree.skeleton_depth(), BONES as u32);
    assert!(tree.warnings.is_empty(), "{:?}", tree.warnings);
    assert_valid_times(&tree);
    let tree = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3])).load();
    assert_eq!(tree.triangles.len(), 2);
    assert_eq!(tree.warnings.len(), 1, "{:?}", tree.warnings);
    warning(&tree, "static tree");
}

// --- 1. key times ---------------------------------------------------------------------------

#[test]
fn a_negative_key_time_is_refused_naming_animation_channel_and_key() {
    let e = skinned(&[-0.5, 1.0, 2.0], "LINEAR").error();
    assert_error(
        &e,
        "animation 'wind' channel 0: key time -0.5 at key 0 is negative (glTF requires times ≥ 0)",
    );
}

#[test]
fn decreasing_key_times_are_refused_naming_the_key() {
    let e = skinned(&[0.0, 2.0, 1.0], "LINEAR").error();
    assert_error(
        &e,
        "animation 'wind' channel 0: key time 1.0 at key 2 is before key 1's 2.0",
    );
}

#[test]
fn non_finite_key_times_are_refused() {
    let e = skinned(&[0.0, f32::NAN, 1.0], "LINEAR").error();
    assert_error(
        &e,
        "animation 'wind' channel 0: key time NaN at key 1 is not finite",
    );
}

#[test]
fn negative_zero_is_read_as_zero() {
    let tree = skinned(&[-0.0, 1.0], "LINEAR").load();
    let t0 = tree.rig.clips[0].channels[0].times[0];
    assert!(t0 == 0.0 && t0.is_sign_positive(), "{t0}");
}

#[test]
fn repeated_key_times_keep_the_last_key_with_a_warning() {
    let tree = skinned(&[0.0, 1.0, 1.0, 1.0, 2.0], "LINEAR").load();
    let w = warning(&tree, "animation 'wind' channel 0: 2 keys at the same time");
    assert!(w.contains("keeping the last key"), "{w}");
    assert_valid_times(&tree);
    let ch = &tree.rig.clips[0].channels[0];
    assert_eq!(ch.times, [0.0, 1.0, 2.0]);
    // Keys 0, 3 and 4 of the written ones remain (key k rotates by 0.1·k about z).
    for (got, k) in ch.values.iter().zip([0, 3, 4]) {
        let want = Vec4::from(Quat::from_rotation_z(0.1 * k as f32));
        assert!(got.distance(want) < 1e-6, "{got} vs key {k}");
    }
}

#[test]
fn repeated_cubic_spline_keys_drop_their_tangent_triplet() {
    let tree = skinned(&[0.0, 0.0, 1.0], "CUBICSPLINE").load();
    warning(&tree, "animation 'wind' channel 0: 1 key at the same time");
    assert_valid_times(&tree);
    let ch = &tree.rig.clips[0].channels[0];
    assert_eq!(ch.times, [0.0, 1.0]);
    // Written values 0..9 are (in, value, out) of keys 0, 1, 2; key 0's triplet (0, 1, 2) goes.
    for (got, k) in ch.values.iter().zip(3..9) {
        let want = Vec4::from(Quat::from_rotation_z(0.1 * k as f32));
        assert!(got.distance(want) < 1e-6, "{got} vs value {k}");
    }
}

#[test]
fn a_clip_longer_than_an_hour_is_refused() {
    let e = skinned(&[0.0, 4e30], "LINEAR").error();
    assert_error(
        &e,
        "animation 'wind' channel 0: key time 4e30 s at key 1 is past frond's limit of 3600 s (1 hour)",
    );
    // An hour itself is fine.
    let tree = skinned(&[0.0, 3600.0], "LINEAR").load();
    assert_eq!(tree.rig.clips[0].duration(), 3600.0);
}

// --- 2. warnings for what used to pass silently ---------------------------------------------

#[test]
fn a_scene_index_out_of_range_is_a_warning() {
    let mut d = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3]));
    d.json["scene"] = json!(5);
    let tree = d.load();
    warning(
        &tree,
        "\"scene\" is 5, but the file has 1 scenes; frond reads every node regardless",
    );
    assert_eq!(tree.triangles.len(), 2);
}

#[test]
fn a_scene_root_that_is_also_a_child_is_a_warning() {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    d.root(1);
    d.json["scenes"][0]["nodes"]
        .as_array_mut()
        .expect("array")
        .push(json!(99));
    let tree = d.load();
    warning(
        &tree,
        "scene 0 lists node 1 ('bone1') as a root, but it is a child of node 0 ('bone0'); read as that node's child",
    );
    warning(&tree, "scene 0 lists node 99 as a root, but there are only");
    assert_eq!(tree.rig.nodes[1].parent, Some(0));
}

#[test]
fn integer_positions_without_mesh_quantization_are_a_warning() {
    let mut d = Doc::new();
    let pos = d.u16s(&[0, 0, 0, 2, 0, 0, 0, 2, 0], "VEC3", 3);
    d.push(
        "meshes",
        json!({ "name": "leaves", "primitives": [{ "attributes": { "POSITION": pos } }] }),
    );
    let n = d.node(json!({ "name": "tree", "mesh": 0 }));
    d.root(n);
    let tree = d.load();
    warning(
        &tree,
        "mesh 'leaves' primitive 0: POSITION accessor 0 is UNSIGNED_SHORT, which glTF allows only with KHR_mesh_quantization (not in extensionsUsed); read as integer coordinates",
    );
    assert_eq!(tree.bounds.max, [2.0, 2.0, 0.0]);
    // Listed as used: no warning.
    d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    let tree = d.load();
    assert!(
        tree.warnings.iter().all(|w| !w.contains("POSITION")),
        "{:?}",
        tree.warnings
    );
}

#[test]
fn a_zero_byte_stride_is_a_warning_and_reads_tightly_packed() {
    let mut d = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3]));
    d.json["bufferViews"][0]["byteStride"] = json!(0);
    let tree = d.load();
    warning(
        &tree,
        "bufferView 0: byteStride 0 is invalid (glTF allows 4 to 252); accessor 0 read it as tightly packed",
    );
    assert_eq!(tree.bounds.max, [1.0, 1.0, 0.0]);
}

#[test]
fn leftover_triangle_indices_are_dropped_with_a_warning() {
    let tree = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3, 1])).load();
    warning(
        &tree,
        "mesh 'leaves' primitive 0: 7 indices is not a multiple of 3 for TRIANGLES; the last 1 dropped",
    );
    assert_eq!(tree.triangles.len(), 2);
    // Without indices the vertex count is the index count.
    let tree = static_mesh(&QUAD, None).load();
    warning(
        &tree,
        "mesh 'leaves' primitive 0: 4 vertices (no indices) is not a multiple of 3 for TRIANGLES; the last 1 dropped",
    );
    assert_eq!(tree.triangles.len(), 1);
}

#[test]
fn vertices_without_skin_weight_are_bound_to_the_first_joint_with_a_warning() {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    let w = [1.0f32, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let w: Vec<f32> = w.iter().chain(&w).copied().collect();
    let acc = d.floats(&w, "VEC4");
    d.prim(0, 0)["attributes"]["WEIGHTS_0"] = json!(acc);
    let tree = d.load();
    warning(
        &tree,
        "mesh 'card' primitive 0: 2 of 4 vertices have all-zero skin weights; bound rigidly to the skin's first joint (joint 0, node 0 'bone0')",
    );
    assert_eq!(tree.vertices.joints[1], [0; 4]);
    assert_eq!(tree.vertices.weights[1], [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(tree.vertices.joints[0], [(BONES - 1) as u16, 0, 0, 0]);
}

#[test]
fn skin_weights_whose_sum_overflows_are_refused() {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    let acc = d.floats(&[3e38, 3e38, 0.0, 0.0].repeat(4), "VEC4");
    d.prim(0, 0)["attributes"]["WEIGHTS_0"] = json!(acc);
    assert_error(
        &d.error(),
        "mesh 'card' primitive 0: vertex 0 has skin weights whose sum overflows",
    );
}

#[test]
fn morph_targets_are_ignored_with_a_warning() {
    let mut d = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3]));
    d.prim(0, 0)["targets"] = json!([{ "POSITION": 0 }, { "POSITION": 0 }]);
    let tree = d.load();
    warning(
        &tree,
        "mesh 'leaves' primitive 0: 2 morph targets ignored (frond reads the base shape only)",
    );
}

#[test]
fn extra_influence_sets_are_folded_into_the_four_largest() {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    // Vertex 0: joints 0..3 in set 0, joints 4 and 5 in set 1 (six influences summing to 1).
    let j0 = d.u16s(
        &[[0, 1, 2, 3], [5, 0, 0, 0], [5, 0, 0, 0], [5, 0, 0, 0]].concat(),
        "VEC4",
        4,
    );
    let w0 = d.floats(
        &[
            [0.1, 0.2, 0.3, 0.15],
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, 0.0],
        ]
        .concat(),
        "VEC4",
    );
    let j1 = d.u16s(&[[4, 5, 0, 0], [0; 4], [0; 4], [0; 4]].concat(), "VEC4", 4);
    let w1 = d.floats(
        &[[0.05, 0.2, 0.0, 0.0], [0.0; 4], [0.0; 4], [0.0; 4]].concat(),
        "VEC4",
    );
    let attrs = &mut d.prim(0, 0)["attributes"];
    attrs["JOINTS_0"] = json!(j0);
    attrs["WEIGHTS_0"] = json!(w0);
    attrs["JOINTS_1"] = json!(j1);
    attrs["WEIGHTS_1"] = json!(w1);
    let tree = d.load();
    warning(
        &tree,
        "mesh 'card' primitive 0: JOINTS_1/WEIGHTS_1 present; frond keeps 4 influences per vertex and merged the sets: 1 vertex has more than 4 and keeps the 4 largest, renormalised (dropping at most 15.0% of a vertex's weight)",
    );
    // Kept: joint 2 (0.3), joints 1 and 5 (0.2 each, lower joint first), joint 3 (0.15).
    assert_eq!(tree.vertices.joints[0], [2, 1, 5, 3]);
    let want = [0.3f32, 0.2, 0.2, 0.15].map(|w| w / 0.85);
    for (g, w) in tree.vertices.weights[0].iter().zip(want) {
        assert!((g - w).abs() < 1e-6, "{:?}", tree.vertices.weights[0]);
    }
    assert_eq!(tree.vertices.joints[1], [5, 0, 0, 0]);
    assert_eq!(tree.vertices.weights[1], [1.0, 0.0, 0.0, 0.0]);
}

#[test]
fn extra_influence_sets_that_fit_in_four_lose_nothing_and_a_lone_set_is_named() {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    // Set 0 and set 1 both give half of the tip bone's weight: merged into one influence.
    let w = d.floats(&[0.5, 0.0, 0.0, 0.0].repeat(4), "VEC4");
    let attrs = &mut d.prim(0, 0)["attributes"];
    attrs["WEIGHTS_0"] = json!(w);
    attrs["JOINTS_1"] = attrs["JOINTS_0"].clone();
    attrs["WEIGHTS_1"] = json!(w);
    attrs["JOINTS_2"] = attrs["JOINTS_0"].clone();
    let tree = d.load();
    warning(
        &tree,
        "JOINTS_1/WEIGHTS_1 present; frond keeps 4 influences per vertex and merged the sets: no vertex has more than 4, so nothing is lost",
    );
    warning(
        &tree,
        "mesh 'card' primitive 0: JOINTS_2 ignored (influence sets are read as JOINTS_n/WEIGHTS_n pairs numbered from 0)",
    );
    assert_eq!(tree.vertices.joints[0], [(BONES - 1) as u16, 0, 0, 0]);
    assert_eq!(tree.vertices.weights[0], [1.0, 0.0, 0.0, 0.0]);
}

// --- 3. errors that name the cause ----------------------------------------------------------

/// [`skinned`] with the inverse bind matrix of `joint` replaced by `m`.
fn with_inverse_bind(joint: usize, m: Mat4) -> Doc {
    let mut d = skinned(&[0.0, 1.0], "LINEAR");
    let acc = d.json["skins"][0]["inverseBindMatrices"]
        .as_u64()
        .expect("index") as usize;
    let view = d.json["accessors"][acc]["bufferView"]
        .as_u64()
        .expect("view") as usize;
    let at = d.json["bufferViews"][view]["byteOffset"]
        .as_u64()
        .expect("offset") as usize
        + joint * 64;
    let bytes: Vec<u8> = m
        .to_cols_array()
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    d.bin[at..at + 64].copy_from_slice(&bytes);
    d
}

#[test]
fn a_singular_inverse_bind_matrix_in_use_is_refused_naming_skin_and_joint() {
    let tip = BONES - 1;
    let e = with_inverse_bind(tip, Mat4::ZERO).error();
    assert_error(
        &e,
        &format!(
            "skin 0 ('s'): the inverse bind matrix of joint {tip} (node {tip} 'bone{tip}') is singular (determinant 0.0); the 4 vertices weighted to it would collapse"
        ),
    );
    // Flattened along one axis (scale 0 in z) is singular too, whatever the other scales.
    let flat = Mat4::from_scale(Vec3::new(1000.0, 1000.0, 0.0));
    assert_error(
        &with_inverse_bind(tip, flat).error(),
        "is singular (determinant 0.0)",
    );
    // A small but regular scale is fine (the test is scale-free).
    let small = Mat4::from_scale(Vec3::splat(1e-3));
    let tree = with_inverse_bind(tip, small).load();
    assert!(tree.warnings.is_empty(), "{:?}", tree.warnings);
}

#[test]
fn a_singular_inverse_bind_matrix_nobody_uses_is_a_warning() {
    let tree = with_inverse_bind(2, Mat4::ZERO).load();
    warning(
        &tree,
        "skin 0 ('s'): the inverse bind matrix of joint 2 (node 2 'bone2') is singular (determinant 0.0); harmless here, as no vertex is weighted to it",
    );
}

#[test]
fn absurd_coordinates_are_refused_naming_primitive_and_value() {
    let far: Vec<f32> = (0..50).flat_map(|i| [3e38, i as f32, 0.0]).collect();
    let e = static_mesh(&far, None).error();
    assert_error(
        &e,
        "mesh 'leaves' primitive 0: POSITION of vertex 0 is [3e38, 0.0, 0.0], beyond ±1e7",
    );
    // Sane positions scaled out there by a node transform.
    let mut d = static_mesh(&QUAD, Some(&[0, 1, 2, 0, 2, 3]));
    d.json["nodes"][0]["scale"] = json!([1e35, 1e35, 1e35]);
    let e = d.error();
    assert_error(
        &e,
        "mesh 'leaves' primitive 0 (node 0 'tree'): a vertex lies at [1e35, 0.0, 0.0] in the rest pose, beyond ±1e7",
    );
}

// --- 4. depth limit -------------------------------------------------------------------------

/// A chain of `depth` nodes, the last one holding a triangle.
fn chain(depth: usize) -> Doc {
    let mut d = static_mesh(&QUAD[..9], None);
    d.json["nodes"] = json!([]);
    d.json["scenes"][0]["nodes"] = json!([]);
    for i in 0..depth {
        let mut n = json!({ "name": format!("n{i}"), "translation": [0.0, 0.01, 0.0] });
        if i + 1 == depth {
            n["mesh"] = json!(0);
        }
        d.node(n);
        if i > 0 {
            d.child(i - 1, i);
        }
    }
    d.root(0);
    d
}

#[test]
fn hierarchies_deeper_than_the_limit_are_refused_naming_the_node() {
    assert_eq!(frond_scene::import::MAX_NODE_DEPTH, 256);
    let tree = chain(256).load();
    assert_eq!(tree.triangles.len(), 1);
    let e = chain(257).error();
    assert_error(
        &e,
        "node 256 ('n256') is 257 levels deep; frond refuses node hierarchies deeper than 256 levels",
    );
}

#[test]
fn a_ten_thousand_deep_chain_is_refused_without_overflowing_the_stack() {
    // Test threads have small stacks: a recursive walk over 10,000 levels would overflow here.
    let e = chain(10_000).error();
    assert_error(&e, "node 256 ('n256') is 257 levels deep");
}
