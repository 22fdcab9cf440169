//! Every LOD cheaper than the one before it, judged as an engine programmer would:
//! from the written files (`frond_scene::file_cost`), not from what the pipeline meant to do.
//! The default chain of the sample, the committed fixtures and the smaller shared trees must
//! have every requested LOD, the hard limits (joints per skin ≤ min(256, the input's), ≤ 4
//! influences), the monotone rule in what each drawn instance pays (each LOD ≤ the one before
//! in triangles, at most half of them, vertices, joints, animated channels, keyframe bytes,
//! draw calls, materials and file bytes without images) and each LOD's own budget in what all
//! instances of a species share (decoded texture no more than the input's, the far end's
//! within 256 KiB counted with its mips; alpha-tested or blended area no more than the
//! input's).

use crate::common;

use std::path::Path;

use common::*;
use frond_lod::report::file_bytes_without_images;
use frond_scene::rigid_fit::rigid_fit;
use frond_scene::sampling::world_at;
use frond_scene::skinning::skin_positions;
use frond_scene::surface_distance::SurfaceBvh;
use frond_scene::wood::WoodMesh;
use frond_scene::{AlphaMode, FileCost, ImportOptions, InputLimits, Part, file_cost, import};
use glam::Vec3;

/// The files' costs of the default chain of `tree` written into `out`, LOD0 first.
fn chain_costs(tree: &Path, out: &Path, extra: &[&str]) -> Vec<(String, FileCost)> {
    let costs = written_costs(tree, out, extra);
    assert_eq!(
        costs.len(),
        4,
        "LOD0 and the three default LODs are written"
    );
    costs
}

/// The files' costs of the chain `frond lod` writes of `tree` into `out` with `extra`, LOD0
/// first, each the same as the report's.
fn written_costs(tree: &Path, out: &Path, extra: &[&str]) -> Vec<(String, FileCost)> {
    let report = frond_lod(tree, out, extra);
    let lods = &report.lods;
    lods.iter()
        .map(|l| {
            let file = l.file.clone();
            let cost = file_cost(&out.join(&file), &InputLimits::default()).expect("file cost");
            // The report carries the same cost, read back from the same file.
            let reported: &FileCost = l.cost.as_ref().expect("the report's cost");
            assert_eq!(reported.triangles, cost.triangles, "{file}");
            assert_eq!(reported.file_bytes, cost.file_bytes, "{file}");
            (file, cost)
        })
        .collect()
}

/// The hard limits and the monotone rule over `costs` (LOD0 first), against the input's
/// `input` cost.
fn assert_cheaper_each_step(input: &FileCost, costs: &[(String, FileCost)]) {
    let joint_limit = input.joints_per_skin_max.min(256);
    for (file, c) in &costs[1..] {
        assert!(
            c.joints_per_skin_max <= joint_limit,
            "{file}: {} joints",
            c.joints_per_skin_max
        );
        assert!(
            c.max_influences <= 4,
            "{file}: {} influences",
            c.max_influences
        );
    }
    for (file, c) in &costs[1..] {
        assert!(
            c.texture_decoded_bytes <= input.texture_decoded_bytes,
            "{file}: {} B of texture decoded, the input {}",
            c.texture_decoded_bytes,
            input.texture_decoded_bytes
        );
        assert!(
            c.alpha_tested_area <= input.alpha_tested_area * (1.0 + 1e-6),
            "{file}: {} units² drawn alpha-tested or blended, the input {}",
            c.alpha_tested_area,
            input.alpha_tested_area
        );
    }
    for w in costs.windows(2) {
        let ((pf, p), (f, c)) = (&w[0], &w[1]);
        let pairs: [(&str, u64, u64); 8] = [
            ("triangles", p.triangles, c.triangles),
            ("vertices", p.vertices, c.vertices),
            ("joints", p.joints_per_skin_max, c.joints_per_skin_max),
            (
                "animated channels",
                p.animated_channels,
                c.animated_channels,
            ),
            ("keyframe bytes", p.keyframe_bytes, c.keyframe_bytes),
            ("draw calls", p.draw_calls, c.draw_calls),
            ("materials", p.materials, c.materials),
            (
                "file bytes without images",
                file_bytes_without_images(p),
                file_bytes_without_images(c),
            ),
        ];
        for (what, before, after) in pairs {
            assert!(
                after <= before,
                "{f} has more {what} ({after}) than {pf} ({before})"
            );
        }
        assert!(
            c.triangles <= p.triangles / 2 + 1,
            "{f}: {} triangles, more than half of {pf}'s {}",
            c.triangles,
            p.triangles
        );
    }
}

/// Checks the default chain of `tree`: its costs, its cards' bend and its branches; returns
/// how many (LOD, branch) pairs at least half a pixel wide there are and how many were dropped.
fn check(tree: &Path, name: &str) -> (usize, usize) {
    let out = tempfile::tempdir().expect("tempdir");
    let input = file_cost(tree, &InputLimits::default()).expect("input cost");
    let costs = chain_costs(tree, out.path(), &[]);
    // LOD0 is the input rewritten: degenerate triangles (which draw nothing) are dropped.
    let lod0 = &costs[0].1;
    assert!(
        lod0.triangles <= input.triangles && 100 * lod0.triangles >= 99 * input.triangles,
        "{name}: LOD0 has {} triangles, the input {}",
        lod0.triangles,
        input.triangles
    );
    assert_cheaper_each_step(&input, &costs);
    assert_cards_bend_little(out.path(), &costs);
    let (branches, dropped) = assert_no_visible_branch_dropped(tree, out.path());
    eprintln!(
        "{name}: {branches} (LOD, branch) pairs at least half a pixel wide, {dropped} dropped \
         within the wood's share"
    );
    let counts = (branches, dropped);
    for (file, c) in &costs {
        eprintln!(
            "{file}: {} triangles, {} joints, {} channels, {} B texture, {} B file",
            c.triangles,
            c.joints_per_skin_max,
            c.animated_channels,
            c.texture_decoded_bytes,
            c.file_bytes
        );
    }
    counts
}

#[test]
fn the_sample_chain_gets_cheaper_at_every_step() {
    check(&root().join("samples/sapling.glb"), "sapling");
}

#[test]
fn the_fixtures_chains_get_cheaper_at_every_step() {
    for f in ["bush_1.glb", "sapling_blender.glb"] {
        check(&fixture(f), f);
    }
}

#[test]
fn the_smaller_shared_trees_chains_get_cheaper_at_every_step() {
    let names = ["oak_medium.glb", "pine_medium_blender.glb"];
    frond_testdata::require_trees!(names);
    for n in names {
        check(&shared_tree(n), n);
    }
}

/// An impostor-class LOD (20 px, the far end) fits the far end's budget, read back from its
/// file, whatever the method: at most 1 % of the input's triangles (at least 64, at most
/// 512), 8 joints, 2 draw calls and 256 KiB of texture counted with its mips (decoded × 4/3);
/// and it is cheaper than the LOD before it in what each instance pays.
#[test]
fn the_far_end_fits_the_impostor_budget_with_every_method() {
    for (tree, name) in [
        (root().join("samples/sapling.glb"), "sapling"),
        (fixture("bush_1.glb"), "bush_1"),
    ] {
        let input = file_cost(&tree, &InputLimits::default()).expect("input cost");
        for method in ["static", "spectral", "skeleton", "cards"] {
            let out = tempfile::tempdir().expect("tempdir");
            let costs = written_costs(
                &tree,
                out.path(),
                &["--lods", "200,60,20", "--method", method],
            );
            // The far LOD against the one before it (billboard methods' near LODs can draw
            // the input's leaf texture beside their atlas, a draw call more than LOD0).
            assert_cheaper_each_step(&input, &costs[costs.len() - 2..]);
            let (file, far) = costs.last().expect("the far LOD");
            let triangles = frond_lod::chain::impostor_triangles(costs[0].1.triangles as usize);
            eprintln!(
                "{name} {method} {file}: {} triangles of {triangles}, {} joints, {} draw calls, \
                 {} B decoded texture",
                far.triangles, far.joints_per_skin_max, far.draw_calls, far.texture_decoded_bytes
            );
            assert!(
                far.triangles as usize <= triangles,
                "{name} {method}: {}",
                far.triangles
            );
            assert!(
                far.joints_per_skin_max <= 8,
                "{name} {method}: {} joints",
                far.joints_per_skin_max
            );
            assert!(
                far.draw_calls <= 2,
                "{name} {method}: {} draw calls",
                far.draw_calls
            );
            assert!(
                far.texture_decoded_bytes * 4 / 3 <= 256 * 1024,
                "{name} {method}: {} B decoded texture",
                far.texture_decoded_bytes
            );
        }
    }
}

/// The far end of `auto` is an animated billboard cloud of FFT clusters: the impostor-class
/// LOD is built by `spectral-axis-phase` with one motion per cluster, at most the joint
/// budget's clusters less the wood's joint; the written file skins its billboards to no more
/// joints than that, and its coverage changes over the loop 0.7–1.3× as much as the tree's.
#[test]
fn the_far_end_of_auto_is_an_animated_cloud_of_fft_clusters() {
    for tree in [root().join("samples/sapling.glb"), fixture("bush_1.glb")] {
        let out = tempfile::tempdir().expect("tempdir");
        let report = frond_lod_measured(&tree, out.path(), &["--lods", "60,20", "--no-preview"]);
        let far = far_end_of_auto(&report);
        let spectral = spectral_section(far).expect("a spectral section");
        assert!(spectral.one_motion_per_cluster, "{spectral:?}");
        assert!(
            (1..=7).contains(&spectral.clusters),
            "{}",
            spectral.clusters
        );
        let cost = file_cost(&out.path().join(&far.file), &InputLimits::default()).expect("cost");
        assert!(
            cost.joints_per_skin_max <= 8,
            "{}: {} joints",
            far.file,
            cost.joints_per_skin_max
        );
        let error = far.error.as_ref().expect("measured");
        let ratio = error
            .loop_change_ratio
            .expect("three frames of a moving tree");
        assert!(
            error.loop_change_input.is_some_and(|c| c > 0.0),
            "{error:?}"
        );
        eprintln!(
            "{}: {} clusters, {} joints, error {:.3}, ratio {:.3}, loop change {ratio:.3}× LOD0's",
            far.file,
            spectral.clusters,
            cost.joints_per_skin_max,
            error.coverage,
            error.coverage_ratio
        );
        // It moves like the tree: the far end keeps its clusters' sub-pixel sway, which the
        // covered fraction of its edge pixels shows.
        assert!(
            (0.7..=1.3).contains(&ratio),
            "{}: its coverage changes {ratio:.3}× as much as LOD0's over the loop",
            far.file
        );
    }
}

/// The benchmark tree's far LODs meet their cost targets: 60 px ≤ 32 joints, ≤ 1 MB decoded
/// texture, ≤ 1 MB file, quad area ≤ 2× the input's leaf area; 200 px ≤ 128 joints. A heavy
/// case (oak_dense), in `.ci/run`'s optimised run.
#[test]
fn heavy_oak_dense_far_lods_fit_their_targets() {
    if !heavy() {
        return;
    }
    let tree = frond_testdata::require_tree!("oak_dense.glb");
    let out = tempfile::tempdir().expect("tempdir");
    let input = file_cost(&tree, &InputLimits::default()).expect("input cost");
    let costs = chain_costs(&tree, out.path(), &[]);
    assert_cheaper_each_step(&input, &costs);
    let (lod2, lod3) = (&costs[2].1, &costs[3].1);
    assert!(
        lod2.joints_per_skin_max <= 128,
        "{}",
        lod2.joints_per_skin_max
    );
    assert!(
        lod3.joints_per_skin_max <= 32,
        "{}",
        lod3.joints_per_skin_max
    );
    assert!(
        lod3.texture_decoded_bytes <= 1 << 20,
        "{}",
        lod3.texture_decoded_bytes
    );
    assert!(lod3.file_bytes <= 1 << 20, "{}", lod3.file_bytes);
    assert!(lod3.alpha_tested_area <= 2.0 * input.alpha_tested_area);
}

/// `--far-alpha blend`: the far end's billboards are written with a `BLEND` material whose
/// atlas alpha is each texel's covered fraction (the sapling's leaves span several texels, so
/// many are wholly covered, and a tenth at least partly), while `mask` writes the same LOD
/// alpha-tested; both measure a coverage ratio within 0.9–1.1 with the metric drawing each as
/// engines do, and both keep the far end's budget.
#[test]
fn the_blended_far_end_writes_covered_fractions_as_blend() {
    let tree = root().join("samples/sapling.glb");
    let input = file_cost(&tree, &InputLimits::default()).expect("input cost");
    for (mode, alpha_mode) in [("blend", AlphaMode::Blend), ("mask", AlphaMode::Mask)] {
        let out = tempfile::tempdir().expect("tempdir");
        let args = ["--lods", "60,20", "--far-alpha", mode, "--no-preview"];
        let report = frond_lod_measured(&tree, out.path(), &args);
        let far = report.lods.last().expect("the far LOD");
        let file = out.path().join(&far.file);
        let lod = import(&file, &ImportOptions::default()).expect("the far LOD imports");
        let billboards = (lod.materials.iter())
            .find(|m| m.name.ends_with("_billboards"))
            .expect("the billboards' material");
        assert_eq!(billboards.alpha_mode, alpha_mode, "{mode}");
        let atlas = &lod.textures[billboards.base_color_texture.expect("an atlas")];
        let alphas: Vec<u8> = atlas.rgba.chunks_exact(4).map(|p| p[3]).collect();
        let covered = alphas.iter().filter(|&&a| a > 0).count();
        let partial = alphas.iter().filter(|&&a| a > 0 && a < 255).count();
        eprintln!(
            "{mode}: {} of {covered} covered texels partly covered, error {:?}",
            partial, far.error
        );
        if alpha_mode == AlphaMode::Blend {
            assert!(10 * partial > covered, "{partial} of {covered}");
        }
        let error = far.error.as_ref().expect("measured");
        assert!(
            (0.9..=1.1).contains(&error.coverage_ratio),
            "{mode}: {error:?}"
        );
        // The far end is judged against its own target, the 60 px LOD against --max-error.
        assert_eq!(error.max_error, frond_lod::chain::IMPOSTOR_MAX_ERROR);
        let near = report.lods[1].error.as_ref().expect("measured");
        assert_eq!(near.max_error, f64::from(0.10f32), "{near:?}");
        let costs: Vec<(String, FileCost)> = (report.lods.iter())
            .map(|l| (l.file.clone(), l.cost.clone().expect("the report's cost")))
            .collect();
        assert_cheaper_each_step(&input, &costs);
        let far_cost = &costs.last().expect("the far LOD").1;
        assert!(far_cost.texture_decoded_bytes * 4 / 3 <= 256 * 1024);
        assert!(
            far_cost.alpha_tested_area > 0.0,
            "a blended quad counts as drawn area"
        );
    }
}

/// The far end keeps the branches at least half a pixel wide as triangles and bakes the thinner
/// ones into its billboards (none is dropped); a nearer LOD, and a far end of cards, drop their
/// thin branches as before.
#[test]
fn the_far_end_bakes_the_branches_it_cannot_keep() {
    let tree = root().join("samples/sapling.glb");
    let out = tempfile::tempdir().expect("tempdir");
    let args = ["--lods", "60,20", "--far-alpha", "blend", "--no-preview"];
    let report = frond_lod_measured(&tree, out.path(), &args);
    let (near, far) = (&report.lods[1], &report.lods[2]);
    eprintln!(
        "60 px: {} thin pieces dropped; 20 px: {} baked, {} dropped, {} wood triangles kept",
        near.dropped.wood_pieces,
        far.dropped.wood_pieces_baked,
        far.dropped.wood_pieces,
        far.wood_triangles
    );
    assert_eq!(
        near.dropped.wood_pieces_baked, 0,
        "only the far end bakes wood"
    );
    assert!(far.dropped.wood_pieces_baked > 0, "{:?}", far.dropped);
    assert_eq!(far.dropped.wood_pieces, 0, "{:?}", far.dropped);
    // The trunk, wider than half a pixel, stays as triangles.
    assert!(far.wood_triangles > 0, "{}", far.wood_triangles);
    let error = far.error.as_ref().expect("measured");
    assert!(
        (0.9..=1.1).contains(&error.coverage_ratio),
        "the baked branches neither thin nor bloat the far end: {error:?}"
    );
    // Cards draw no wood of their own: a far end of cards drops its thin branches, as said.
    let cards_out = tempfile::tempdir().expect("tempdir");
    let args = ["--lods", "20", "--method", "cards"];
    let cards = frond_lod(&tree, cards_out.path(), &args);
    let dropped = &cards.lods[1].dropped;
    assert_eq!(dropped.wood_pieces_baked, 0, "{dropped:?}");
    assert_eq!(
        dropped.wood_pieces, far.dropped.wood_pieces_baked,
        "{dropped:?}"
    );
}

/// Times over the first clip a card's bend is read at.
const BEND_TIMES: usize = 16;

/// How far the cards of `file` bend when posed: over its cards (foliage pieces of at most four
/// triangles, connected by shared vertices), the farthest a corner strays from the card's best
/// rigid motion at [`BEND_TIMES`] times of the first clip, as a fraction of the card's rest
/// diagonal; and how many cards there are. Read back from the file, as an engine skins it.
fn worst_card_bend(file: &Path) -> (f32, usize) {
    let tree = import(file, &ImportOptions::default()).expect("the LOD reads back");
    let cards = foliage_cards(&tree);
    let Some(clip) = tree.rig.clips.first() else {
        return (0.0, cards.len());
    };
    let rest = skin_positions(&tree, &world_at(&tree, None, 0.0));
    let posed: Vec<Vec<Vec3>> = (0..BEND_TIMES)
        .map(|k| {
            let t = clip.start + clip.duration() * k as f32 / BEND_TIMES as f32;
            skin_positions(&tree, &world_at(&tree, Some(0), t))
        })
        .collect();
    let mut worst = 0.0f32;
    for card in &cards {
        let from: Vec<Vec3> = card.iter().map(|&v| rest[v]).collect();
        let diagonal = frond_scene::Bounds::of(from.iter().copied()).diagonal();
        if diagonal <= 0.0 {
            continue;
        }
        for p in &posed {
            let to: Vec<Vec3> = card.iter().map(|&v| p[v]).collect();
            let m = rigid_fit(&from, &to);
            for (a, b) in from.iter().zip(&to) {
                worst = worst.max(m.transform_point3(*a).distance(*b) / diagonal);
            }
        }
    }
    (worst, cards.len())
}

/// The vertices of each card of `tree` (indices into its vertices): the pieces of its foliage
/// mesh of at most four triangles.
fn foliage_cards(tree: &frond_scene::Tree) -> Vec<Vec<usize>> {
    let (mesh, source) = WoodMesh::from_tree_part_mapped(tree, Part::Foliage);
    mesh.pieces()
        .into_iter()
        .filter(|piece| piece.len() <= 4)
        .map(|piece| {
            let mut vs: Vec<usize> = piece
                .iter()
                .flat_map(|&(p, t)| &mesh.primitives[p].indices[3 * t..3 * t + 3])
                .map(|&v| source[v as usize] as usize)
                .collect();
            vs.sort_unstable();
            vs.dedup();
            vs
        })
        .collect()
}

/// Every LOD's cards stay cards when posed: no corner strays more than a tenth of its card's
/// diagonal from the card's best rigid motion, unless the input's own cards bend that much
/// (then no more than they do).
fn assert_cards_bend_little(out: &Path, costs: &[(String, FileCost)]) {
    let (input_bend, _) = worst_card_bend(&out.join(&costs[0].0));
    let limit = input_bend.max(0.1) + 1e-3;
    for (file, _) in &costs[1..] {
        let (bend, cards) = worst_card_bend(&out.join(file));
        eprintln!(
            "{file}: {cards} cards, worst bend {bend:.3} of the diagonal (input {input_bend:.3})"
        );
        assert!(
            bend <= limit,
            "{file}: a card bends {bend:.3} of its diagonal, more than {limit:.3}"
        );
    }
}

/// Pixels a LOD's wood may lie from where an input branch was and still draw it: the wood is
/// simplified within about a pixel, and a collapsed joint's branch leans where it sways.
const BRANCH_TOLERANCE_PX: f32 = 2.0;

/// No LOD drops a branch that is at least half a pixel wide at its size unless its wood is
/// held to its triangle share: for every LOD of the chain in `out` (its report's pixel size)
/// and every branch of `input` that wide (a piece of its wood, as wide as
/// `frond_scene::wood::WoodMesh::piece_thickness` estimates), at least half the branch's
/// vertices lie within [`BRANCH_TOLERANCE_PX`] of the LOD's wood, read back from its file at
/// rest; or, where one does not, the report says branches were dropped and the LOD's wood is
/// within its share of the triangles. Returns how many (LOD, branch) pairs were checked and
/// how many of them were dropped.
fn assert_no_visible_branch_dropped(input: &Path, out: &Path) -> (usize, usize) {
    let options = ImportOptions::default();
    let tree = import(input, &options).expect("the input reads");
    let wood = WoodMesh::from_tree_part(&tree, Part::Wood);
    let pieces = wood.pieces();
    let thickness: Vec<f32> = pieces.iter().map(|p| wood.piece_thickness(p)).collect();
    let stem = input.file_stem().and_then(|s| s.to_str()).expect("a stem");
    let report = lod_report(out, stem);
    let (mut checked, mut dropped) = (0, 0);
    for lod in report.lods.iter().skip(1) {
        let pixel = lod.pixel.expect("a built LOD's pixel");
        let lod_tree = import(&out.join(&lod.file), &options).expect("the LOD reads back");
        let lod_wood = WoodMesh::from_tree_part(&lod_tree, Part::Wood);
        let bvh = SurfaceBvh::new(lod_wood.triangle_corners());
        for (piece, &width) in pieces.iter().zip(&thickness) {
            if width < 0.5 * pixel {
                continue;
            }
            checked += 1;
            let vertices: Vec<Vec3> = piece
                .iter()
                .flat_map(|&(p, t)| &wood.primitives[p].indices[3 * t..3 * t + 3])
                .map(|&v| wood.positions[v as usize])
                .collect();
            let near = vertices
                .iter()
                .filter(|&&v| bvh.distance(v) <= BRANCH_TOLERANCE_PX * pixel)
                .count();
            if 2 * near >= vertices.len() {
                continue;
            }
            dropped += 1;
            let share = lod.budget.as_ref().map_or(0, |b| b.wood_triangles);
            assert!(
                lod.dropped.wood_pieces > 0 && lod.wood_triangles <= share,
                "{}: a branch {:.2} px wide is dropped ({near} of its {} vertices near the \
                 wood) though the wood ({} triangles) is under its share ({share})",
                lod.file,
                width / pixel,
                vertices.len(),
                lod.wood_triangles
            );
        }
    }
    (checked, dropped)
}

/// A slender broadleaf (`frond sample --preset slender`: a trunk under a pixel wide at 60 px)
/// keeps every branch at least half a pixel wide at every LOD, its trunk among them, and its
/// chain keeps every rule the others do.
#[test]
fn the_slender_trunk_keeps_its_trunk_at_every_lod() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tree = dir.path().join("slender.glb");
    let path = tree.to_str().expect("utf-8");
    frond_ok(&["sample", "--preset", "slender", "--seed", "3", "-o", path]);
    let (branches, dropped) = check(&tree, "slender");
    assert!(
        branches > 0,
        "the trunk is at least half a pixel wide at 60 px"
    );
    assert_eq!(dropped, 0, "of {branches}");
}
