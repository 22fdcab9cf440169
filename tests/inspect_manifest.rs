//! `frond inspect --json` on every shared tree agrees with MANIFEST.json (skipped, with one line,
//! where the shared trees are absent); the text report and material overrides on fixtures.

mod common;

use common::*;

#[test]
fn inspect_json_matches_manifest_for_every_shared_tree() {
    frond_testdata::require_tree!("MANIFEST.json");
    let manifest = manifest();
    let files = manifest["files"].as_array().expect("files[]");
    assert!(files.len() >= 7, "the manifest lists the shared trees");
    let names = files.iter().map(|e| e["file"].as_str().expect("file name"));
    let paths = frond_testdata::require_trees!(names);
    for (entry, path) in files.iter().zip(&paths) {
        let name = entry["file"].as_str().expect("file name");
        let out = frond(&["inspect", "--json", path.to_str().expect("utf-8 path")]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: serde_json::Value =
            serde_json::from_slice(&out.stdout).expect("inspect prints JSON");
        let t = &entry["triangles"];
        assert_eq!(
            r["triangles"]["total"], t["total"],
            "{name}: total triangles"
        );
        assert_eq!(r["triangles"]["wood"], t["wood"], "{name}: wood triangles");
        assert_eq!(
            r["triangles"]["foliage"], t["foliage"],
            "{name}: foliage triangles"
        );
        assert_eq!(r["bones"], entry["bones"], "{name}: bones");
        assert_eq!(
            r["skeleton_depth"], entry["skeletonDepth"]["maxBoneChainDepth"],
            "{name}: skeleton depth"
        );
        let clip = &r["clips"][0];
        assert_eq!(
            clip["name"], entry["animation"]["name"],
            "{name}: clip name"
        );
        assert_eq!(
            clip["duration_s"].as_f64(),
            entry["animation"]["durationS"].as_f64(),
            "{name}: period"
        );
        assert_eq!(clip["loops"], entry["animation"]["loops"], "{name}: loops");
        assert_eq!(clip["moves"], true, "{name}: the wind moves the tree");
        // Every stable key is present.
        assert!(
            r["triangles"]["degenerate"].is_u64(),
            "{name}: triangles.degenerate"
        );
        for key in ["foliage_reassigned", "bones", "skeleton_depth"] {
            assert!(r[key].is_u64(), "{name}: {key}");
        }
        assert_eq!(r["bounds"]["min"].as_array().map(Vec::len), Some(3));
        assert_eq!(r["bounds"]["max"].as_array().map(Vec::len), Some(3));
        let sm = &r["sampling"];
        assert_eq!(sm["samples"], 64, "{name}: default sample count");
        assert_eq!(
            sm["clip"], entry["animation"]["name"],
            "{name}: first clip sampled"
        );
        assert_eq!(
            sm["trajectories"], t["foliage"],
            "{name}: one trajectory per foliage triangle"
        );
        // MANIFEST's Blender check saw leaves move by up to ~2.5 units between frames 0 and 1.
        let max = sm["max_leaf_excursion"].as_f64().unwrap_or(0.0);
        let height = r["bounds"]["max"][1].as_f64().unwrap_or(0.0)
            - r["bounds"]["min"][1].as_f64().unwrap_or(0.0);
        assert!(
            max > 1e-3 * height && max < 0.2 * height,
            "{name}: leaf excursion {max} of height {height}"
        );
        let rigid = entry["leafBinding"]["multiBonePieces"] == 0;
        if rigid {
            assert_eq!(
                r["foliage_reassigned"], 0,
                "{name}: rigid leaves need no reassignment"
            );
        } else {
            assert_eq!(
                r["foliage_reassigned"], t["foliage"],
                "{name}: every blended leaf triangle was reassigned"
            );
        }
    }
}

#[test]
fn inspect_text_names_classification_reasons() {
    // Blender's round trip of the sapling keeps the material names ("leaves").
    let out = frond(&[
        "inspect",
        fixture("sapling_blender.glb").to_str().expect("utf-8"),
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("Foliage") && text.contains("material name contains 'leaves'"),
        "{text}"
    );
    assert!(text.contains("loops"), "{text}");
}

#[test]
fn material_overrides_change_the_split() {
    // Calling the wood material foliage moves all of its triangles.
    let path = fixture("bush_1.glb");
    let out = frond(&[
        "inspect",
        "--json",
        "--foliage-material",
        "branches",
        path.to_str().expect("utf-8"),
    ]);
    assert!(out.status.success());
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(r["triangles"]["foliage"], 13872);
    assert_eq!(r["triangles"]["wood"], 0);
    let reason = r["classification"][0]["reason"].as_str().unwrap_or("");
    assert!(reason.contains("named as foliage"), "{reason}");
}
