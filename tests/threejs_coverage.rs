//! Engines draw the far end as frond measures it: three.js (GLTFLoader, the file as written,
//! blending on: headless Chromium through `tools/three_coverage.mjs`) renders the blended far LOD
//! at 8× its screen height from an orthographic camera; its covered fraction per pixel (the
//! framebuffer's alpha, cleared to 0), box-filtered 8 × 8 to the LOD's size, is compared with
//! frond's own coverage render (the metric's CPU rasteriser, 8 × 8 samples a pixel) of the file
//! as frond reads it back, at the same camera and clip time: Σ|Δα| / Σα ≤ 0.03 over every view.
//!
//! Both sides count a blended layer by its alpha and compose layers as 1 − Π(1 − αᵢ) (three.js's
//! NormalBlending writes α + dst·(1 − α) to the alpha channel), an opaque or alpha-tested surface
//! as whole; what may differ is only where each samples the texture (three.js at 8× reads finer
//! mips of the same box-filtered chain) and the rasterisers' edge rules. The chain's `shaders/`
//! holds the Godot materials' blended variants beside such a far end.
//!
//! Skips (one `skipped:` line) when Chromium, Node or the packages in `tools/node_modules` are
//! not installed; `.ci/run` installs them.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::*;
use frond_render::{
    Camera, DrawAlpha, Projection, SoftwareTextures, TreeParts, render_coverage, tree_scene,
};
use frond_scene::{ImportOptions, Tree, import};
use glam::Vec3;
use serde::Serialize;

/// three.js's image is this many times the LOD's size, each axis.
const ENLARGED: u32 = 8;

/// The agreement the far end must reach: Σ|Δα| / Σα over every view's pixels.
const MAX_DISAGREEMENT: f64 = 0.03;

/// One view as `three_coverage.mjs` takes it.
#[derive(Serialize)]
struct ThreeView {
    eye: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    half_width: f32,
    half_height: f32,
    near: f32,
    far: f32,
    width: u32,
    height: u32,
    time: f32,
}

/// A view of the far LOD: the camera, the image size at the LOD's screen height and the clip
/// time.
struct View {
    camera: Camera,
    width: u32,
    height: u32,
    time: f32,
}

/// Orthographic views framing `tree`'s rest bounds from three azimuths, the tree's height
/// `screen_height` pixels, at the start, a third and two thirds of the way through its first
/// clip (times on the clip's keys, which three.js plays from 0 as the file says).
fn views(tree: &Tree, screen_height: f32) -> Vec<View> {
    let (lo, hi) = (Vec3::from(tree.bounds.min), Vec3::from(tree.bounds.max));
    let (start, duration) = tree
        .rig
        .clips
        .first()
        .map_or((0.0, 0.0), |c| (c.start, c.duration()));
    let mut views = Vec::new();
    for (k, azimuth) in [0.0f32, 60.0, 150.0].into_iter().enumerate() {
        let camera = Camera::framing(
            lo,
            hi,
            azimuth,
            10.0,
            Projection::Orthographic { half_height: 1.0 },
        );
        let Projection::Orthographic { half_height } = camera.projection else {
            unreachable!("framed orthographic");
        };
        // The framing sphere's diameter is this many tree heights.
        let side = (screen_height * 2.0 * half_height / (hi.y - lo.y)).ceil() as u32;
        views.push(View {
            camera,
            width: side,
            height: side,
            time: start + duration * k as f32 / 3.0,
        });
    }
    views
}

/// frond's covered fraction of each pixel of `view`, rows from the top.
fn frond_fractions(tree: &Tree, view: &View) -> Vec<f64> {
    let scene = tree_scene(tree, tree.clip_index(None), view.time, TreeParts::All);
    let textures = SoftwareTextures::new(&scene, false).expect("textures");
    let (lo, hi) = scene.bounds().expect("something drawn");
    let aspect = view.width as f32 / view.height as f32;
    let view_proj = view.camera.view_proj_for_bounds(aspect, lo, hi);
    let image = render_coverage(&scene, &textures, view_proj, view.width, view.height, 8)
        .expect("frond renders");
    (0..(view.width * view.height) as usize)
        .map(|i| f64::from(image.covered_fraction(i)))
        .collect()
}

/// `view` as three.js's orthographic camera, 8× larger, its depth range around `tree`'s
/// posed bounds.
fn three_view(tree: &Tree, view: &View) -> ThreeView {
    let scene = tree_scene(tree, tree.clip_index(None), view.time, TreeParts::All);
    let (lo, hi) = scene.bounds().expect("something drawn");
    let (near, far) = view.camera.depth_range(lo, hi);
    let Projection::Orthographic { half_height } = view.camera.projection else {
        unreachable!("framed orthographic");
    };
    ThreeView {
        eye: view.camera.eye().into(),
        target: view.camera.target.into(),
        up: view.camera.up().into(),
        half_width: half_height * view.width as f32 / view.height as f32,
        half_height,
        near,
        far,
        width: view.width * ENLARGED,
        height: view.height * ENLARGED,
        time: view.time,
    }
}

/// three.js's covered fraction of each pixel of every view, box-filtered to the views' sizes.
fn three_fractions(
    tools: &Path,
    chromium: &str,
    glb: &Path,
    tree: &Tree,
    views: &[View],
) -> Vec<Vec<f64>> {
    let tmp = tempfile::tempdir().expect("tmp");
    let cameras = tmp.path().join("cameras.json");
    let raw = tmp.path().join("alpha.raw");
    let specs: Vec<ThreeView> = views.iter().map(|v| three_view(tree, v)).collect();
    std::fs::write(&cameras, serde_json::to_vec(&specs).expect("json")).expect("cameras");
    let run = Command::new("node")
        .arg(tools.join("three_coverage.mjs"))
        .arg(glb)
        .arg(&cameras)
        .arg(&raw)
        .arg(chromium)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&run.stdout);
    let result: serde_json::Value = serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "three_coverage.mjs printed no JSON ({e}): {text} {}",
            String::from_utf8_lossy(&run.stderr)
        )
    });
    assert_eq!(result["ok"], true, "three.js did not render: {result}");
    let alpha = std::fs::read(&raw).expect("three's alpha");
    let mut offset = 0;
    views
        .iter()
        .map(|v| {
            let (w, h) = (v.width as usize, v.height as usize);
            let big = &alpha[offset..offset + w * h * (ENLARGED * ENLARGED) as usize];
            offset += big.len();
            box_filter(big, w, h)
        })
        .collect()
}

/// The mean alpha of each `ENLARGED`² block of `big` (rows from the top), 0..1.
fn box_filter(big: &[u8], width: usize, height: usize) -> Vec<f64> {
    let n = ENLARGED as usize;
    let row = width * n;
    let mut out = vec![0.0; width * height];
    for (y, line) in big.chunks_exact(row).enumerate() {
        for (x, &a) in line.iter().enumerate() {
            out[(y / n) * width + x / n] += f64::from(a) / 255.0;
        }
    }
    out.iter_mut().for_each(|v| *v /= (n * n) as f64);
    out
}

/// Builds `input`'s chain ending at a blended far LOD of `screen_height` px (the Godot materials'
/// blended variants written beside it), renders it in three.js and in frond, and asserts they
/// agree within [`MAX_DISAGREEMENT`].
fn far_end_agrees(input: &Path, screen_height: f32) {
    let tmp = tempfile::tempdir().expect("tmp");
    let lods = format!("{screen_height}");
    let report = frond_lod(
        input,
        tmp.path(),
        &["--lods", &lods, "--far-alpha", "blend"],
    );
    let far = report.lods.last().expect("the far LOD");
    assert!(far.billboards > 0, "{} has billboards", far.file);
    let glb = tmp.path().join(&far.file);
    let tree = import(&glb, &ImportOptions::default()).expect("the far LOD reads back");
    let scene = tree_scene(&tree, tree.clip_index(None), 0.0, TreeParts::All);
    assert!(
        scene.materials.iter().any(|m| m.alpha == DrawAlpha::Blend),
        "{} is drawn blended",
        far.file
    );
    for material in [
        "frond_lod_fade_blend.gdshader",
        "frond_lod_fade_blend_godot3.shader",
    ] {
        let text = std::fs::read_to_string(tmp.path().join("shaders").join(material))
            .unwrap_or_else(|e| panic!("{material} written beside a blended far end: {e}"));
        assert!(text.contains("ALPHA = albedo.a;"), "{material}");
    }

    let Some((chromium, tools)) = chromium_and_node_tools() else {
        return;
    };

    let views = views(&tree, screen_height);
    let three = three_fractions(&tools, &chromium, &glb, &tree, &views);
    let (mut diff, mut total) = (0.0, 0.0);
    for (view, three) in views.iter().zip(&three) {
        let frond = frond_fractions(&tree, view);
        diff += frond
            .iter()
            .zip(three)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>();
        total += frond.iter().sum::<f64>();
    }
    let disagreement = diff / total;
    eprintln!(
        "{}: three.js against frond at {screen_height} px: Σ|Δα|/Σα = {disagreement:.4} (Σα {total:.1})",
        far.file
    );
    assert!(total > 10.0, "the far LOD covers pixels: Σα = {total}");
    assert!(
        disagreement <= MAX_DISAGREEMENT,
        "{}: three.js and frond disagree on the covered fraction: Σ|Δα|/Σα = {disagreement:.4} > {MAX_DISAGREEMENT}",
        far.file
    );
}

#[test]
fn threejs_draws_the_samples_blended_far_end_as_frond_measures_it() {
    far_end_agrees(&root().join("samples/sapling.glb"), 20.0);
}

#[test]
fn threejs_draws_a_shared_trees_blended_far_end_as_frond_measures_it() {
    frond_testdata::require_tree!("oak_medium.glb");
    far_end_agrees(&shared_tree("oak_medium.glb"), 20.0);
}
