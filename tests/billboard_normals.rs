//! `--billboard-normals`: baked billboards carry the baked normal atlas as their
//! `normalTexture` (tangent space, half the colour atlas's side), or crown-shaped vertex
//! normals, or one flat normal a quad; read back from the written files.

use crate::common;

use std::path::Path;

use common::*;
use frond_scene::gltf_source::GltfSource;
use frond_scene::input_file::InputLimits;
use glam::Vec3;
use gltf::json::mesh::Semantic;
use gltf::json::validation::Checked;

/// The written LOD1 of the sample with the per-bone method and `normals`.
fn lod1(dir: &Path, normals: &str) -> GltfSource {
    let out = dir.join(normals);
    let report = frond_lod(
        &root().join("samples/sapling.glb"),
        &out,
        &[
            "--method",
            "per-bone",
            "--lods",
            "200",
            "--billboard-normals",
            normals,
        ],
    );
    let file = out.join(&report.lods[1].file);
    // The normal map comes with the tangents it is read in (else the validator warns that
    // engines must generate them, not portably).
    if let Some(v) = validate(&file) {
        assert_eq!(
            (v["errors"].as_u64(), v["warnings"].as_u64()),
            (Some(0), Some(0)),
            "{v}"
        );
    }
    GltfSource::open(&file, &InputLimits::default()).expect("reads")
}

/// The billboard material's JSON and the billboard primitive's (positions, normals).
fn billboards(src: &GltfSource) -> (serde_json::Value, Vec<Vec3>, Vec<Vec3>) {
    let m = src
        .raw
        .materials
        .iter()
        .position(|m| {
            m["name"]
                .as_str()
                .is_some_and(|n| n.ends_with("_billboards"))
        })
        .expect("a billboard material");
    let prim = src
        .root
        .meshes
        .iter()
        .flat_map(|mesh| &mesh.primitives)
        .find(|p| p.material.map(|i| i.value()) == Some(m))
        .expect("a billboard primitive");
    let read = |semantic: Semantic| -> Vec<Vec3> {
        let acc = prim
            .attributes
            .iter()
            .find(|(s, _)| matches!(s, Checked::Valid(x) if *x == semantic))
            .map(|(_, a)| a.value())
            .expect("attribute");
        let a = &src.root.accessors[acc];
        let view = a.buffer_view.expect("view").value();
        let bytes = src.view_bytes(view, "test").expect("bytes");
        let start = a.byte_offset.map_or(0, |o| o.0 as usize);
        bytes[start..start + a.count.0 as usize * 12]
            .chunks(12)
            .map(|c| {
                let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
                Vec3::new(f(0), f(4), f(8))
            })
            .collect()
    };
    (
        src.raw.materials[m].clone(),
        read(Semantic::Positions),
        read(Semantic::Normals),
    )
}

#[test]
fn baked_normals_are_a_half_size_tangent_space_map_crown_and_flat_are_vertex_normals() {
    let dir = tempfile::tempdir().expect("temp dir");

    let baked = lod1(dir.path(), "baked");
    let (material, _, _) = billboards(&baked);
    let colour = material["pbrMetallicRoughness"]["baseColorTexture"]["index"]
        .as_u64()
        .expect("colour") as usize;
    let normal = material["normalTexture"]["index"]
        .as_u64()
        .expect("a normal map") as usize;
    let decode = |t: usize| {
        let image = baked.raw.textures[t]["source"].as_u64().expect("source") as usize;
        image::load_from_memory(&baked.image_bytes(image).expect("bytes"))
            .expect("PNG")
            .to_rgba8()
    };
    let (c, n) = (decode(colour), decode(normal));
    assert_eq!(n.width(), (c.width() / 2).next_multiple_of(4));
    assert_eq!(n.height(), (c.height() / 2).next_multiple_of(4));
    // Under the covered texels, normals face the viewer (+Z in tangent space) on the whole,
    // and are unit length.
    let (mut z, mut count) = (0.0f64, 0usize);
    for (x, y, p) in c.enumerate_pixels() {
        if p[3] < 128 {
            continue;
        }
        let q = n.get_pixel((x / 2).min(n.width() - 1), (y / 2).min(n.height() - 1));
        let v = Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / 127.5 - Vec3::ONE;
        assert!((v.length() - 1.0).abs() < 0.05, "{v}");
        z += f64::from(v.z);
        count += 1;
    }
    assert!(
        count > 100 && z / count as f64 > 0.5,
        "mean z {}",
        z / count as f64
    );

    // frond reads it back as a normal map it applies: the tangents and the decoded map, at
    // the file's size, on the billboard material.
    let tree =
        frond_scene::import(&baked.path, &frond_scene::ImportOptions::default()).expect("imports");
    assert_eq!(tree.vertices.tangent.len(), tree.vertices.len());
    let m = tree
        .materials
        .iter()
        .find(|m| m.name.ends_with("_billboards"))
        .expect("billboard material");
    let t = &tree.textures[m.normal_texture.expect("the normal map is applied")];
    assert_eq!((t.width, t.height), (n.width(), n.height()));

    let crown = lod1(dir.path(), "crown");
    let (material, positions, normals) = billboards(&crown);
    assert!(material.get("normalTexture").is_none());
    let (lo, hi) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let centre = 0.5 * (lo + hi);
    for (p, n) in positions.iter().zip(&normals) {
        assert!(n.dot(*p - centre) > 0.0, "a crown normal points inward");
        assert!((n.length() - 1.0).abs() < 1e-3);
    }

    let flat = lod1(dir.path(), "flat");
    let (material, _, normals) = billboards(&flat);
    assert!(material.get("normalTexture").is_none());
    for quad in normals.chunks(4) {
        assert!(quad.iter().all(|n| (*n - quad[0]).length() < 1e-6));
    }
}
