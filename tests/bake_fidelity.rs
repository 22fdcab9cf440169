//! Bake fidelity at the design size: at ε = 0 every billboard holds one leaf
//! card, so the 600 px LOD must draw its leaves' outline as the input does: no speckle along
//! leaf edges (the coverage-preserving re-threshold only touches cells whose plain alpha test
//! would miss their coverage, `frond_billboard::bake`), and single-card billboards keep the
//! input's own texels (hybrid cloud).
//!
//! The bound: frond's renderer scores LOD0 (the input rewritten) at about 1e-5, since it draws
//! the very same data, so "twice LOD0's error" is read against the independent
//! renderer, which scored a re-encoded copy of the tree at 0.008: the ε = 0 LOD must stay below
//! 0.005, under that copy's score. Measured when written: oak_medium 0.0006,
//! pine_medium_blender 0.0017. Built with `--no-cost-budgets`: the default budgets hold a
//! 600 px LOD to half the input's triangles, which merges cards into shared planes whatever ε
//! says (0.030 and 0.077 then: merging, not baking).

use crate::common;

use common::*;

/// Highest coverage error at 600 px of the ε = 0 LOD (see the module comment).
const BOUND: f64 = 0.005;

#[test]
fn billboards_at_epsilon_zero_draw_the_leaves_outline_at_their_size() {
    let names = ["oak_medium.glb", "pine_medium_blender.glb"];
    frond_testdata::require_trees!(names);
    for name in names {
        let tree = shared_tree(name);
        let out = tempfile::tempdir().expect("tempdir");
        let report = per_bone_at_zero(&tree, out.path());
        let lods = &report.lods;
        let lod = &lods[1];
        assert_eq!(lod.method.name(), "per-bone", "{name}");
        let billboards = lod.billboards;
        let own = lod.input_textured_billboards;
        assert!(billboards > 1000, "{name}: {billboards} billboards");
        // Nearly every billboard holds one card on its own texels (99 % of both trees').
        assert!(
            own <= billboards && 10 * own >= 9 * billboards,
            "{name}: {own} of {billboards} billboards on the input's texels"
        );
        let error = lod.error.as_ref().expect("error").coverage;
        let lod0 = frond_eval(
            &tree,
            &out.path().join(&lods[0].file),
            &["--screen-height", "600"],
        )
        .coverage
        .animated
        .mean
        .expect("LOD0 error");
        assert!(lod0 < 1e-3, "{name}: LOD0 scores {lod0}");
        assert!(
            error <= BOUND,
            "{name}: the ε = 0 LOD scores {error} at 600 px (LOD0 {lod0})"
        );
    }
}
