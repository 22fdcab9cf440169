//! Rendering real exporters' trees (the `tests/fixtures/` ez-tree bush and Blender round trip;
//! the shared pines where present): frames are plausible and the wind visibly moves the foliage.

use crate::common;

use std::path::Path;

use common::*;
use frond_app::render_cmd::{RenderRequest, render_tree};
use frond_render::Renderer;
use frond_scene::{ImportOptions, import};

fn request(time: f32) -> RenderRequest {
    RenderRequest {
        time,
        ..Default::default()
    }
}

#[test]
fn frames_at_zero_and_quarter_period_are_plausible_and_differ() {
    let tree = import(&fixture("bush_1.glb"), &ImportOptions::default()).expect("imports");
    let period = tree.rig.clips[0].duration();
    let renderer = Renderer::new().expect("a graphics adapter (Mesa llvmpipe on CI)");
    let a = render_tree(&renderer, &tree, &request(0.0)).expect("renders");
    let b = render_tree(&renderer, &tree, &request(period / 4.0)).expect("renders");
    // A framed tree covers a real part of the image but not all of it.
    for f in [&a, &b] {
        let c = f.coverage_fraction();
        assert!((0.05..0.6).contains(&c), "coverage {c}");
    }
    // Leaves swing by several pixels at 256 px (oak_medium: up to ~2.5 units in a 65-unit tree,
    // MANIFEST bpyCheck), so thousands of leaf pixels change between the two times (measured:
    // ~2,700 on bush_1, as on oak_medium).
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
    let run = frond_ok(&[
        "render",
        fixture("bush_1.glb").to_str().expect("utf-8"),
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

/// A Blender round trip (`blender`) posed at the same times covers the same pixels as the
/// `native` file it was made from.
fn poses_like_the_native_file(native: &Path, blender: &Path) {
    // The round trip went through Blender's importer and exporter: armature node, skinned
    // meshes below it, TRS channels with STEP keys, split vertices. Blender resampled the 30 fps
    // keys at 24 fps, so only at times on both key grids (multiples of 1/6 s) are the poses equal.
    let native = import(native, &ImportOptions::default()).expect("imports");
    let blender = import(blender, &ImportOptions::default()).expect("imports");
    let renderer = Renderer::new().expect("a graphics adapter (Mesa llvmpipe on CI)");
    for t in [0.0, 1.0, 1.5, 2.5] {
        let a = render_tree(&renderer, &native, &request(t)).expect("renders");
        let b = render_tree(&renderer, &blender, &request(t)).expect("renders");
        let differ = a
            .coverage
            .iter()
            .zip(&b.coverage)
            .filter(|(x, y)| x != y)
            .count();
        assert!(a.coverage_fraction() > 0.03);
        assert!(differ < 40, "t={t}: {differ} pixels differ");
    }
}

#[test]
fn blender_round_trip_of_the_sapling_poses_like_the_sapling() {
    poses_like_the_native_file(
        &root().join("samples/sapling.glb"),
        &fixture("sapling_blender.glb"),
    );
}

#[test]
fn blender_round_trip_poses_like_the_native_file() {
    let native = frond_testdata::require_tree!("pine_medium.glb");
    let blender = frond_testdata::require_tree!("pine_medium_blender.glb");
    poses_like_the_native_file(&native, &blender);
}

#[test]
fn a_materials_scene_copies_only_the_drawn_materials_textures() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("samples/sapling.glb");
    let tree = import(&path, &ImportOptions::default()).expect("imports");
    let textured: Vec<usize> = (0..tree.materials.len())
        .filter(|&m| tree.materials[m].base_color_texture.is_some())
        .collect();
    assert!(!textured.is_empty(), "the sample has a textured material");
    // Only the first textured material drawn.
    let first = textured[0];
    let mut drawn = vec![false; tree.materials.len()];
    drawn[first] = true;
    let scene = frond_render::materials_scene(&tree, &drawn);
    assert_eq!(scene.materials.len(), tree.materials.len());
    assert_eq!(scene.textures.len(), tree.textures.len());
    let read = tree.materials[first].base_color_texture;
    for (i, (t, source)) in scene.textures.iter().zip(&tree.textures).enumerate() {
        if Some(i) == read {
            assert_eq!((t.width, t.height), (source.width, source.height));
            assert!(t.rgba == source.rgba, "texture {i} copied as it is");
        } else {
            assert_eq!(*t, frond_render::DrawTexture::placeholder(), "texture {i}");
        }
    }
    // Every material drawn: every texture a material reads is copied.
    let all = frond_render::materials_scene(&tree, &vec![true; tree.materials.len()]);
    for m in &tree.materials {
        if let Some(i) = m.base_color_texture {
            assert!(all.textures[i].rgba == tree.textures[i].rgba);
        }
    }
}
