//! Import features on hand-built files with known answers: loop and motion detection, STEP
//! keys, classification rules, KHR_texture_transform, KHR_mesh_quantization, matrices, strips.

use std::path::Path;

use frond_scene::gltf_writer::*;
use frond_scene::{ImportOptions, Part, SampleOptions, Tree, Wrap, import_bytes, sample};
use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};

fn load(bytes: &[u8]) -> Tree {
    import_bytes(Path::new("case.glb"), bytes, &ImportOptions::default()).expect("imports")
}

/// Two bones in a chain, a 1×1 card on the second one, and a rotation clip on the first.
fn two_bone_card(keys: &[(f32, Quat)], step: bool) -> Vec<u8> {
    let mut doc = GltfBuilder::new("test");
    let leaf = doc.add_material(&MaterialDesc {
        name: "plain".into(),
        base_color: [0.2, 0.8, 0.2, 1.0],
        base_color_texture: None,
        normal_texture: None,
        alpha: WriteAlpha::Mask(0.5),
        double_sided: true,
        metallic: 0.0,
        roughness: 1.0,
    });
    let card = PrimitiveDesc {
        positions: vec![
            [0.0, 2.0, 0.0],
            [1.0, 2.0, 0.0],
            [1.0, 3.0, 0.0],
            [0.0, 3.0, 0.0],
        ],
        joints: Some(vec![[1, 0, 0, 0]; 4]),
        weights: Some(vec![[1.0, 0.0, 0.0, 0.0]; 4]),
        indices: vec![0, 1, 2, 0, 2, 3],
        material: Some(leaf),
        ..Default::default()
    };
    let mesh = doc.add_mesh("panel", &[card]);
    let b0 = doc.add_node(NodeDesc {
        name: "root".into(),
        ..Default::default()
    });
    let b1 = doc.add_node(NodeDesc {
        name: "tip".into(),
        translation: Some([0.0, 2.0, 0.0]),
        ..Default::default()
    });
    doc.add_child(b0, b1);
    doc.add_root(b0);
    let skin = doc.add_skin(
        "s",
        &[b0, b1],
        &[
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(0.0, -2.0, 0.0)),
        ],
        Some(b0),
    );
    let n = doc.add_node(NodeDesc {
        name: "panel".into(),
        mesh: Some(mesh),
        skin: Some(skin),
        ..Default::default()
    });
    doc.add_root(n);
    doc.add_animation(
        "Sway",
        &[ChannelDesc {
            node: b0,
            path: ChannelPath::Rotation,
            times: keys.iter().map(|k| k.0).collect(),
            values: keys.iter().flat_map(|k| k.1.to_array()).collect(),
            interpolation: if step {
                WriteInterpolation::Step
            } else {
                WriteInterpolation::Linear
            },
        }],
    );
    doc.to_glb()
}

#[test]
fn a_clip_that_does_not_return_is_reported_as_not_looping() {
    let tree = load(&two_bone_card(
        &[(0.0, Quat::IDENTITY), (1.0, Quat::from_rotation_z(0.5))],
        false,
    ));
    let s = sample(
        &tree,
        &SampleOptions {
            clip: None,
            samples: 8,
        },
    )
    .expect("samples");
    assert!(!s.motion.loops);
    assert!(s.motion.moves);
    assert_eq!(tree.bones.len(), 2);
    assert_eq!(tree.skeleton_depth(), 2);
    // The card is bound to the tip bone and rotates about the origin: at t = 0.5 the rotation
    // is exactly half way (slerp), so the centre of the first triangle is rotated by 0.25 rad.
    let c0 = Vec3::new(2.0 / 3.0, 7.0 / 3.0, 0.0);
    let k = s
        .times
        .iter()
        .position(|&t| (t - 0.5).abs() < 1e-6)
        .expect("t=0.5 is sampled");
    let want = Quat::from_rotation_z(0.25) * c0;
    assert!(
        s.trajectory(0)[k].distance(want) < 1e-5,
        "{} vs {want}",
        s.trajectory(0)[k]
    );
    assert_eq!(tree.triangles[0].bone, Some(1));
}

#[test]
fn a_constant_clip_has_no_motion_and_loops() {
    let q = Quat::from_rotation_x(0.3);
    let tree = load(&two_bone_card(&[(0.0, q), (2.0, q)], false));
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    assert!(s.motion.loops);
    assert!(!s.motion.moves);
}

#[test]
fn step_keys_hold_until_the_next_key() {
    let tree = load(&two_bone_card(
        &[
            (0.0, Quat::IDENTITY),
            (1.0, Quat::from_rotation_z(1.0)),
            (2.0, Quat::IDENTITY),
        ],
        true,
    ));
    let s = sample(
        &tree,
        &SampleOptions {
            clip: Some("Sway".into()),
            samples: 4,
        },
    )
    .expect("samples");
    // Samples at 0, 0.5, 1.0, 1.5: the first two hold key 0, the last two hold key 1.
    let tr = s.trajectory(0);
    assert!(tr[0].distance(tr[1]) < 1e-6);
    assert!(tr[2].distance(tr[3]) < 1e-6);
    assert!(tr[1].distance(tr[2]) > 0.5);
    assert!(
        sample(
            &tree,
            &SampleOptions {
                clip: Some("Nope".into()),
                samples: 4
            }
        )
        .is_err()
    );
}

#[test]
fn static_trees_are_a_one_frame_loop_with_a_warning() {
    let mut doc = GltfBuilder::new("test");
    let mesh = doc.add_mesh(
        "leaves",
        &[PrimitiveDesc {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            indices: vec![0, 1, 2],
            ..Default::default()
        }],
    );
    let n = doc.add_node(NodeDesc {
        name: "tree".into(),
        mesh: Some(mesh),
        ..Default::default()
    });
    doc.add_root(n);
    let tree = load(&doc.to_glb());
    assert!(tree.warnings.iter().any(|w| w.contains("static tree")));
    assert_eq!(
        tree.count(Part::Foliage),
        1,
        "mesh name 'leaves' marks foliage"
    );
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    assert_eq!(s.samples(), 1);
    assert!(s.motion.loops && !s.motion.moves);
}

/// Many small opaque cards plus one big connected sheet, all with neutral names.
fn cards_and_sheet() -> Vec<u8> {
    let mut doc = GltfBuilder::new("test");
    let mut cards = PrimitiveDesc::default();
    for i in 0..40 {
        let o = Vec3::new((i % 8) as f32 * 3.0, 10.0 + (i / 8) as f32 * 3.0, 0.0);
        let b = cards.positions.len() as u32;
        for c in [Vec3::ZERO, Vec3::X, Vec3::X + Vec3::Y, Vec3::Y] {
            cards.positions.push((o + c * 0.5).to_array());
        }
        cards
            .indices
            .extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    }
    let mut sheet = PrimitiveDesc::default();
    let n = 10;
    for y in 0..=n {
        for x in 0..=n {
            sheet.positions.push([x as f32 * 2.0, y as f32, 1.0]);
        }
    }
    for y in 0..n {
        for x in 0..n {
            let a = y * (n + 1) + x;
            sheet
                .indices
                .extend_from_slice(&[a, a + 1, a + n + 1, a + 1, a + n + 2, a + n + 1]);
        }
    }
    let m1 = doc.add_mesh("mesh_a", &[cards]);
    let m2 = doc.add_mesh("mesh_b", &[sheet]);
    for m in [m1, m2] {
        let node = doc.add_node(NodeDesc {
            name: format!("n{m}"),
            mesh: Some(m),
            ..Default::default()
        });
        doc.add_root(node);
    }
    doc.to_glb()
}

#[test]
fn small_disconnected_cards_are_foliage_and_connected_geometry_is_wood() {
    let tree = load(&cards_and_sheet());
    assert_eq!(tree.count(Part::Foliage), 80);
    assert_eq!(tree.count(Part::Wood), 200);
    assert!(
        tree.classification[0].reason.contains("disconnected cards"),
        "{:?}",
        tree.classification
    );
    assert!(tree.classification[1].reason.contains("default"));
}

#[test]
fn alpha_mask_marks_foliage_when_names_say_nothing() {
    let tree = load(&two_bone_card(
        &[(0.0, Quat::IDENTITY), (1.0, Quat::IDENTITY)],
        false,
    ));
    assert_eq!(tree.count(Part::Foliage), 2);
    assert!(tree.classification[0].reason.contains("alpha-masked"));
}

/// A raw glTF JSON document with its bin chunk, as a GLB.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    glb_container(&serde_json::to_vec(json).expect("json"), bin)
}

#[test]
fn quantized_positions_texture_transform_matrix_nodes_and_strips() {
    // POSITION: normalized i16 (KHR_mesh_quantization) scaled back by the node matrix;
    // TEXCOORD_0: normalized u8 with a KHR_texture_transform; a 4-vertex triangle strip.
    let pos: [i16; 12] = [0, 0, 0, 32767, 0, 0, 0, 32767, 0, 32767, 32767, 0];
    let uv: [u8; 8] = [0, 0, 255, 0, 0, 255, 255, 255];
    let mut bin: Vec<u8> = pos.iter().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend_from_slice(&uv);
    let png = encode_png(2, 2, &[255u8; 16]).expect("png");
    let png_offset = bin.len();
    bin.extend_from_slice(&png);
    let scale = 4.0f32;
    let matrix = Mat4::from_scale_rotation_translation(
        Vec3::splat(scale),
        Quat::IDENTITY,
        Vec3::new(1.0, 0.0, 0.0),
    );
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_mesh_quantization", "KHR_texture_transform"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "name": "q", "mesh": 0, "matrix": matrix.to_cols_array() }],
        "meshes": [{ "name": "leaf", "primitives": [{
            "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "mode": 5, "material": 0 }] }],
        "materials": [{ "name": "leaves", "pbrMetallicRoughness": { "baseColorTexture": {
            "index": 0,
            "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.25], "scale": [0.5, 0.5] } } } } }],
        "textures": [{ "source": 0 }],
        "images": [{ "bufferView": 2, "mimeType": "image/png" }],
        "accessors": [
            { "bufferView": 0, "componentType": 5122, "normalized": true, "count": 4, "type": "VEC3",
              "min": [0, 0, 0], "max": [32767, 32767, 0] },
            { "bufferView": 1, "componentType": 5121, "normalized": true, "count": 4, "type": "VEC2" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 24 },
            { "buffer": 0, "byteOffset": 24, "byteLength": 8 },
            { "buffer": 0, "byteOffset": png_offset, "byteLength": png.len() }
        ],
        "buffers": [{ "byteLength": bin.len() }]
    });
    let tree = load(&glb(&doc, &bin));
    assert_eq!(tree.triangles.len(), 2, "a 4-vertex strip is 2 triangles");
    let b = tree.bounds;
    assert!(
        (Vec3::from(b.min) - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-4,
        "{b:?}"
    );
    assert!(
        (Vec3::from(b.max) - Vec3::new(5.0, 4.0, 0.0)).length() < 1e-4,
        "{b:?}"
    );
    // uv' = offset + scale · uv.
    let uv = &tree.vertices.uv;
    assert!((uv[0] - glam::Vec2::new(0.5, 0.25)).length() < 1e-6);
    assert!((uv[3] - glam::Vec2::new(1.0, 0.75)).length() < 1e-6);
    assert_eq!(tree.textures.len(), 1);
    assert_eq!(tree.materials[0].base_color_texture, Some(0));
}

/// The base-colour map's sampler wrap modes are read (the sample's bark repeats, its leaf
/// texture is clamped), and [`Wrap::texel`] maps coordinates outside the texture as glTF does.
#[test]
fn base_colour_wrap_modes_are_read_and_applied() {
    let tree =
        frond_scene::import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
    let wraps: Vec<(String, [Wrap; 2])> = tree
        .materials
        .iter()
        .map(|m| (m.name.clone(), m.base_color_wrap))
        .collect();
    assert!(
        wraps.contains(&("bark".into(), [Wrap::Repeat; 2])),
        "{wraps:?}"
    );
    assert!(
        wraps.contains(&("leaves".into(), [Wrap::ClampToEdge; 2])),
        "{wraps:?}"
    );
    // Texels of a 4-texel axis.
    let at = |w: Wrap| [-1.5, 0.5, 3.5, 4.5, 6.2].map(|x| w.texel(x, 4));
    assert_eq!(at(Wrap::Repeat), [2, 0, 3, 0, 2]);
    assert_eq!(at(Wrap::ClampToEdge), [0, 0, 3, 3, 3]);
    assert_eq!(at(Wrap::MirroredRepeat), [1, 0, 3, 3, 1]);
}
