//! `frond inspect --json` on every shared tree agrees with MANIFEST.json (skipped, with one line,
//! where the shared trees are absent); the text report and material overrides on fixtures.

use crate::common;

use common::*;
use frond_app::inspect::InspectReport;

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
        // Every stable key is present: the typed read requires `triangles.degenerate`,
        // `foliage_reassigned`, `bones`, `skeleton_depth` (whole numbers) and three-number
        // `bounds.min` and `bounds.max`.
        let r: InspectReport = parse_json(&out.stdout);
        // MANIFEST.json is the shared trees' own description (not frond's schema): read by key.
        let t = &entry["triangles"];
        let count = |n: usize| Some(n as u64);
        assert_eq!(
            count(r.triangles.total),
            t["total"].as_u64(),
            "{name}: total triangles"
        );
        assert_eq!(
            count(r.triangles.wood),
            t["wood"].as_u64(),
            "{name}: wood triangles"
        );
        assert_eq!(
            count(r.triangles.foliage),
            t["foliage"].as_u64(),
            "{name}: foliage triangles"
        );
        assert_eq!(count(r.bones), entry["bones"].as_u64(), "{name}: bones");
        assert_eq!(
            Some(u64::from(r.skeleton_depth)),
            entry["skeletonDepth"]["maxBoneChainDepth"].as_u64(),
            "{name}: skeleton depth"
        );
        let clip = r.clips.first().expect("a clip");
        assert_eq!(
            Some(clip.name.as_str()),
            entry["animation"]["name"].as_str(),
            "{name}: clip name"
        );
        assert_eq!(
            Some(written_f64(clip.duration_s)),
            entry["animation"]["durationS"].as_f64(),
            "{name}: period"
        );
        assert_eq!(
            Some(clip.loops),
            entry["animation"]["loops"].as_bool(),
            "{name}: loops"
        );
        assert!(clip.moves, "{name}: the wind moves the tree");
        let sm = &r.sampling;
        assert_eq!(sm.samples, 64, "{name}: default sample count");
        assert_eq!(
            sm.clip.as_deref(),
            entry["animation"]["name"].as_str(),
            "{name}: first clip sampled"
        );
        assert_eq!(
            count(sm.trajectories),
            t["foliage"].as_u64(),
            "{name}: one trajectory per foliage triangle"
        );
        // MANIFEST's Blender check saw leaves move by up to ~2.5 units between frames 0 and 1.
        let max = written_f64(sm.max_leaf_excursion);
        let height = written_f64(r.bounds.max[1]) - written_f64(r.bounds.min[1]);
        assert!(
            max > 1e-3 * height && max < 0.2 * height,
            "{name}: leaf excursion {max} of height {height}"
        );
        let rigid = entry["leafBinding"]["multiBonePieces"] == 0;
        if rigid {
            assert_eq!(
                r.foliage_reassigned, 0,
                "{name}: rigid leaves need no reassignment"
            );
        } else {
            assert_eq!(
                count(r.foliage_reassigned),
                t["foliage"].as_u64(),
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
    let r: InspectReport = parse_json(&out.stdout);
    assert_eq!(r.triangles.foliage, 13872);
    assert_eq!(r.triangles.wood, 0);
    let reason = r.classification.first().map_or("", |c| c.reason.as_str());
    assert!(reason.contains("named as foliage"), "{reason}");
}
