//! The preview page in a real browser: headless Chromium (Debian's `chromium`, WebGL in software
//! through SwiftShader) opens the sample's `sapling_preview.html` as `frond view` serves it, and
//! `tools/preview_check.mjs` (puppeteer-core) checks from the page itself that the live view — a
//! WebGL canvas drawing the combined file with three.js — loaded every LOD, that the wind plays
//! (two screenshots at different times differ in the tree's pixels), and that the LOD slider
//! shows one LOD's meshes at a time and changes the picture. The screenshots are left in
//! `target/test-artefacts/preview_browser/` (`anim_0.png`, `anim_1.png`, `lod_<k>.png`,
//! `page.png`).
//!
//! Skips (one `skipped:` line) when Chromium, Node or puppeteer-core (in `tools/node_modules`)
//! is not installed; `.ci/run` installs them.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::*;
use serde_json::Value;

/// The page's background (`scene.background` in live_view.js).
const SKY: [u8; 3] = [0xdf, 0xe9, 0xf1];

/// Pixels of a screenshot that show the tree (not the sky), and of two screenshots the tree
/// pixels that differ.
fn tree_mask(path: &Path) -> (u32, u32, Vec<bool>, image::RgbImage) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let mask = img
        .pixels()
        .map(|p| {
            p.0.iter()
                .zip(SKY)
                .map(|(a, b)| a.abs_diff(b) as u32)
                .sum::<u32>()
                > 24
        })
        .collect();
    (img.width(), img.height(), mask, img)
}

fn changed_tree_pixels(a: &Path, b: &Path) -> (usize, usize) {
    let (wa, ha, ma, ia) = tree_mask(a);
    let (wb, hb, mb, ib) = tree_mask(b);
    assert_eq!((wa, ha), (wb, hb), "screenshots of one size");
    let tree = ma.iter().zip(&mb).filter(|(x, y)| **x || **y).count();
    let changed = ia
        .pixels()
        .zip(ib.pixels())
        .zip(ma.iter().zip(&mb))
        .filter(|((p, q), (x, y))| {
            (**x || **y)
                && p.0
                    .iter()
                    .zip(q.0)
                    .map(|(a, b)| a.abs_diff(b) as u32)
                    .sum::<u32>()
                    > 24
        })
        .count();
    (tree, changed)
}

#[test]
fn chromium_plays_the_live_view_and_switches_lods() {
    check_in_chromium(&root().join("samples/sapling.glb"), "preview_browser");
}

/// The same on oak_dense, the benchmark tree (116k leaf triangles), its screenshots in
/// `target/test-artefacts/preview_browser_oak_dense/`. A heavy case, in `.ci/run`'s
/// optimised run.
#[test]
fn heavy_chromium_plays_oak_dense() {
    if !heavy() {
        return;
    }
    frond_testdata::require_tree!("oak_dense.glb");
    check_in_chromium(&shared_tree("oak_dense.glb"), "preview_browser_oak_dense");
}

/// Builds `input`'s chain (not measured), serves it with `frond view`, and checks its page in
/// Chromium, leaving the screenshots in `target/test-artefacts/<artefacts>/`.
fn check_in_chromium(input: &Path, artefacts: &str) {
    let Some((chromium, tools)) = chromium_and_node_tools() else {
        return;
    };
    let tmp = tempfile::tempdir().expect("tmp");
    let out = tmp.path().join("out");
    let report = frond_lod_measured(input, &out, &["--no-measure"]);
    let name = input
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("utf-8 stem");
    let lods = &report.lods;

    let server = frond_view(&out);
    let url = server.url().to_string();
    assert!(url.ends_with(&format!("/{name}_preview.html")), "{url}");

    let shots = artefact_dir(artefacts);
    let run = Command::new("node")
        .arg(tools.join("preview_check.mjs"))
        .arg(&url)
        .arg(&shots)
        .arg(&chromium)
        .output()
        .expect("node runs");
    drop(server);
    let text = String::from_utf8_lossy(&run.stdout);
    let result: Value = serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "preview_check.mjs printed no JSON ({e}): {text} {}",
            String::from_utf8_lossy(&run.stderr)
        )
    });
    assert_eq!(
        result["error"],
        Value::Null,
        "the live view failed: {result}"
    );
    assert_eq!(result["ok"], true, "{result}");

    // Every LOD loaded from the combined file, with the triangles its own file has.
    let seen = result["lods"].as_array().expect("lods");
    assert_eq!(seen.len(), lods.len());
    for (k, (s, l)) in seen.iter().zip(lods).enumerate() {
        assert_eq!(s["loaded"], true, "LOD{k} loaded: {s}");
        assert_eq!(
            s["triangles"].as_u64(),
            Some(l.cost.as_ref().expect("cost").triangles),
            "LOD{k}'s triangles: {s}"
        );
    }

    // The wind plays: the clip's time advanced and the tree's pixels moved.
    let times: Vec<f64> = result["times"]
        .as_array()
        .expect("times")
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    assert!(
        times.len() == 2 && times[1] > times[0],
        "clip time advances: {times:?}"
    );
    let (tree, changed) = changed_tree_pixels(&shots.join("anim_0.png"), &shots.join("anim_1.png"));
    assert!(tree > 5000, "the tree is drawn: {tree} pixels");
    assert!(
        changed * 100 > tree,
        "the animation moves more than 1 % of the tree's pixels: {changed} of {tree}"
    );

    // The slider shows one LOD at a time, and each looks different from the one before.
    let visible = result["visible"].as_array().expect("visible");
    assert_eq!(visible.len(), lods.len());
    for (k, v) in visible.iter().enumerate() {
        let v: Vec<bool> = v
            .as_array()
            .expect("flags")
            .iter()
            .map(|b| b == true)
            .collect();
        let expected: Vec<bool> = (0..lods.len()).map(|i| i == k).collect();
        assert_eq!(
            v, expected,
            "slider at {k}: only LOD{k}'s nodes are visible"
        );
    }
    for k in 1..lods.len() {
        let (tree, changed) = changed_tree_pixels(
            &shots.join(format!("lod_{}.png", k - 1)),
            &shots.join(format!("lod_{k}.png")),
        );
        assert!(
            changed > 0 && tree > 5000,
            "LOD{} → LOD{k}: {changed} of {tree} pixels change",
            k - 1
        );
    }
    eprintln!("preview_browser: screenshots in {}", shots.display());
}
