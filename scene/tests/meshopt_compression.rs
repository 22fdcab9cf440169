//! `GltfBuilder::set_compression`: what it writes reads back as what was put in (positions,
//! indices and key times exactly, rotations, normals, tangents and texture coordinates within their
//! quantization step), with both extensions required, and smaller.

use std::path::Path;

use frond_scene::gltf_writer::*;
use frond_scene::{ImportOptions, Tree, import_bytes};
use glam::{Mat4, Quat, Vec3};
use serde_json::Value;

/// A skinned grid of `n`×`n` tilted cards with normals, tangents and texture coordinates in
/// 0..1, and a rotation clip.
fn cards(n: usize, compress: bool) -> Vec<u8> {
    let mut doc = GltfBuilder::new("test");
    doc.set_compression(compress);
    let leaf = doc.add_material(&MaterialDesc {
        name: "leaf".into(),
        base_color: [0.2, 0.8, 0.2, 1.0],
        base_color_texture: None,
        normal_texture: None,
        alpha: WriteAlpha::Mask(0.5),
        double_sided: true,
        metallic: 0.0,
        roughness: 1.0,
    });
    let mut p = PrimitiveDesc {
        byte_weights: true,
        material: Some(leaf),
        ..Default::default()
    };
    let (mut normals, mut tangents, mut uvs, mut joints, mut weights) =
        (vec![], vec![], vec![], vec![], vec![]);
    for i in 0..n * n {
        let (x, z) = ((i % n) as f32 * 0.3, (i / n) as f32 * 0.3);
        let tilt = Quat::from_rotation_x(i as f32 * 0.37) * Quat::from_rotation_y(i as f32 * 0.11);
        let base = p.positions.len() as u32;
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            let q = Vec3::new(x, 1.0, z) + tilt * Vec3::new(u * 0.2, v * 0.2, 0.0);
            p.positions.push(q.to_array());
            normals.push((tilt * Vec3::Z).to_array());
            let t = tilt * Vec3::X;
            tangents.push([t.x, t.y, t.z, if i % 2 == 0 { 1.0 } else { -1.0 }]);
            uvs.push([0.1 + 0.8 * u * (i as f32 / (n * n) as f32), 0.9 - 0.7 * v]);
            joints.push([1, 0, 0, 0]);
            weights.push([0.7, 0.3, 0.0, 0.0]);
        }
        p.indices
            .extend([0, 1, 2, 0, 2, 3].iter().map(|k| base + k));
    }
    p.normals = Some(normals);
    p.tangents = Some(tangents);
    p.uvs = Some(uvs);
    p.joints = Some(joints);
    p.weights = Some(weights);
    let mesh = doc.add_mesh("cards", &[p]);
    let b0 = doc.add_node(NodeDesc {
        name: "root".into(),
        ..Default::default()
    });
    let b1 = doc.add_node(NodeDesc {
        name: "tip".into(),
        translation: Some([0.0, 1.0, 0.0]),
        ..Default::default()
    });
    doc.add_child(b0, b1);
    doc.add_root(b0);
    let skin = doc.add_skin(
        "s",
        &[b0, b1],
        &[
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0)),
        ],
        Some(b0),
    );
    let node = doc.add_node(NodeDesc {
        name: "cards".into(),
        mesh: Some(mesh),
        skin: Some(skin),
        ..Default::default()
    });
    doc.add_root(node);
    let times: Vec<f32> = (0..=30).map(|k| k as f32 / 30.0).collect();
    doc.add_animation(
        "Wind",
        &[ChannelDesc {
            node: b1,
            path: ChannelPath::Rotation,
            values: times
                .iter()
                .flat_map(|t| {
                    Quat::from_rotation_z((t * std::f32::consts::TAU).sin() * 0.2).to_array()
                })
                .collect(),
            times,
            interpolation: WriteInterpolation::Linear,
        }],
    );
    doc.to_glb()
}

fn load(bytes: &[u8]) -> Tree {
    import_bytes(Path::new("cards.glb"), bytes, &ImportOptions::default()).expect("imports")
}

fn json_of(glb: &[u8]) -> Value {
    let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    serde_json::from_slice(&glb[20..20 + len]).expect("json chunk")
}

#[test]
fn compressed_geometry_reads_back_within_its_quantization() {
    let (plain, packed) = (cards(40, false), cards(40, true));
    let (a, b) = (load(&plain), load(&packed));
    assert_eq!(
        a.vertices.position, b.vertices.position,
        "positions stay floats"
    );
    let tris = |t: &Tree| t.triangles.iter().map(|t| t.v).collect::<Vec<_>>();
    assert_eq!(tris(&a), tris(&b));
    let worst = |x: &[Vec3], y: &[Vec3]| {
        x.iter()
            .zip(y)
            .map(|(p, q)| (*p - *q).abs().max_element())
            .fold(0.0f32, f32::max)
    };
    // A normalized byte is within half a step (1/254) of the value, renormalised on import.
    assert!(worst(&a.vertices.normal, &b.vertices.normal) < 0.01);
    assert_eq!(a.vertices.tangent.len(), b.vertices.tangent.len());
    let t3 = |t: &Tree| -> Vec<Vec3> { t.vertices.tangent.iter().map(|t| t.truncate()).collect() };
    assert!(worst(&t3(&a), &t3(&b)) < 0.01);
    assert!(
        a.vertices
            .tangent
            .iter()
            .zip(&b.vertices.tangent)
            .all(|(p, q)| p.w == q.w)
    );
    let uv_error = a
        .vertices
        .uv
        .iter()
        .zip(&b.vertices.uv)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(uv_error <= 0.5 / 65535.0 + 1e-7, "uv error {uv_error}");
    assert_eq!(a.vertices.weights, b.vertices.weights);
    // Key times exactly; rotation keys as normalized shorts, within half a step a component.
    let (ca, cb) = (&a.rig.clips[0], &b.rig.clips[0]);
    assert_eq!(ca.channels.len(), cb.channels.len());
    let mut worst = 0.0f32;
    for (x, y) in ca.channels.iter().zip(&cb.channels) {
        assert_eq!(x.times, y.times);
        for (p, q) in x.values.iter().zip(&y.values) {
            worst = worst.max((*p - *q).abs().max_element());
        }
    }
    // Renormalised on import: up to a step a component.
    assert!(worst <= 1.0 / 32767.0, "rotation keys off by {worst}");
    assert!(worst > 0.0, "rotations are quantized");

    let j = json_of(&packed);
    for e in ["EXT_meshopt_compression", "KHR_mesh_quantization"] {
        assert!(
            j["extensionsRequired"]
                .as_array()
                .is_some_and(|r| r.iter().any(|x| x == e)),
            "{e} required"
        );
    }
    let buffers = j["buffers"].as_array().expect("buffers");
    assert_eq!(buffers.len(), 2);
    assert_eq!(
        buffers[1]["extensions"]["EXT_meshopt_compression"]["fallback"],
        true
    );
    let modes: Vec<&str> = j["bufferViews"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|v| {
            v.pointer("/extensions/EXT_meshopt_compression/mode")?
                .as_str()
        })
        .collect();
    assert!(modes.contains(&"ATTRIBUTES") && modes.contains(&"TRIANGLES"));
    assert!(
        packed.len() * 2 < plain.len(),
        "{} bytes compressed, {} plain",
        packed.len(),
        plain.len()
    );
}

#[test]
fn compression_is_deterministic() {
    assert_eq!(cards(8, true), cards(8, true));
}
