//! Sampled motion agrees with ground truth: the generator's own keyed transforms for generated
//! trees, and `_meta/<name>.structure.json` leaf-to-bone bindings for the shared trees
//! (`FROND_TEST_TREES`; those tests skip with one line where the shared trees are absent).

use std::path::Path;

use frond_scene::generator::{GeneratedTree, Preset, generate};
use frond_scene::{ImportOptions, Part, SampleOptions, Tree, import, import_bytes, sample};
use glam::Vec3;

/// Imports a generated tree from memory.
fn load(g: &GeneratedTree) -> Tree {
    import_bytes(
        Path::new("generated.glb"),
        &g.glb,
        &ImportOptions::default(),
    )
    .expect("generated tree imports")
}

fn check_against_generator(preset: Preset, seed: u64) {
    let g = generate(preset, seed).expect("generates");
    let tree = load(&g);
    assert_eq!(tree.count(Part::Foliage), 2 * g.leaf_corners.len());
    assert_eq!(tree.count(Part::Wood), g.wood_triangles);
    assert_eq!(tree.bones.len(), g.bones.len());
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    assert_eq!(s.samples(), 64);
    assert!((s.period - 4.0).abs() < 1e-6);
    assert!(s.motion.loops && s.motion.moves);
    let tol = 1e-4 * g.height;
    let leaf_base = s
        .foliage
        .iter()
        .map(|&ti| tree.triangles[ti].v.iter().copied().min().unwrap_or(0))
        .min()
        .unwrap_or(0);
    let mut worst = 0.0f32;
    for (k, &ti) in s.foliage.iter().enumerate() {
        let tri = tree.triangles[ti];
        let q = ((tri.v.iter().copied().min().unwrap_or(0) - leaf_base) / 4) as usize;
        let bone = g.leaf_bones[q];
        assert_eq!(
            tree.bones[tri.bone.expect("foliage has a bone") as usize].name,
            g.bones[bone].name
        );
        let local: Vec<usize> = tri
            .v
            .iter()
            .map(|&v| (v - leaf_base) as usize % 4)
            .collect();
        for (si, &t) in s.times.iter().enumerate() {
            let expect: Vec3 = local
                .iter()
                .map(|&c| g.bound_point(bone, g.leaf_corners[q][c], t))
                .sum::<Vec3>()
                / 3.0;
            worst = worst.max(expect.distance(s.trajectory(k)[si]));
        }
    }
    assert!(
        worst <= tol,
        "{preset:?}: worst trajectory error {worst} > {tol}"
    );
    // Bone world transforms agree too.
    for (b, _) in g.bones.iter().enumerate() {
        for (si, &t) in s.times.iter().enumerate().step_by(7) {
            let got = s.bone_world[si * tree.bones.len() + b].w_axis.truncate();
            let want = g.bone_world(b, t).w_axis.truncate();
            assert!(
                got.distance(want) <= tol,
                "bone {b} at {t}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn generated_small_tree_trajectories_match_generator_keys() {
    check_against_generator(Preset::Small, 3);
}

#[test]
fn generated_medium_tree_trajectories_match_generator_keys() {
    check_against_generator(Preset::Medium, 11);
}

#[test]
fn generator_is_deterministic_per_seed() {
    let a = generate(Preset::Small, 5).expect("generates");
    let b = generate(Preset::Small, 5).expect("generates");
    let c = generate(Preset::Small, 6).expect("generates");
    assert_eq!(a.glb, b.glb);
    assert_ne!(a.glb, c.glb);
}

#[test]
fn twigs_sway_faster_than_the_trunk() {
    // The thesis's observation (§1.5): each level has its own inherent frequencies.
    let g = generate(Preset::Small, 2).expect("generates");
    let zero_crossings = |b: usize| {
        let angles: Vec<f32> = g.bones[b]
            .keys
            .iter()
            .map(|q| q.to_axis_angle().1 * q.x.signum())
            .collect();
        let mean = angles.iter().sum::<f32>() / angles.len() as f32;
        angles
            .windows(2)
            .filter(|w| (w[0] - mean) * (w[1] - mean) < 0.0)
            .count()
    };
    let trunk = (0..g.bones.len())
        .filter(|&b| g.bones[b].level == 0)
        .map(zero_crossings)
        .max()
        .unwrap_or(0);
    let deepest = g.bones.iter().map(|b| b.level).max().unwrap_or(0);
    let twig = (0..g.bones.len())
        .filter(|&b| g.bones[b].level == deepest)
        .map(zero_crossings)
        .min()
        .unwrap_or(0);
    assert!(twig > trunk, "twig crossings {twig} vs trunk {trunk}");
    // Seamless: first and last key are the same rotation.
    for b in &g.bones {
        let (first, last) = (b.keys[0], b.keys[b.keys.len() - 1]);
        assert!(first.dot(last).abs() > 1.0 - 1e-6);
    }
}

#[test]
fn shared_rigid_trees_bind_leaves_as_structure_json_says() {
    let names = ["bush_1", "oak_medium", "oak_large", "pine_medium"];
    let paths = frond_testdata::require_trees!(
        names
            .iter()
            .flat_map(|n| [format!("{n}.glb"), format!("_meta/{n}.structure.json")])
    );
    for (name, pair) in names.iter().zip(paths.chunks_exact(2)) {
        let tree = import(&pair[0], &ImportOptions::default()).expect("imports");
        let text = std::fs::read_to_string(&pair[1]).expect("structure");
        let st: serde_json::Value = serde_json::from_str(&text).expect("json");
        let quad_bone = st["leafQuads"]["bone"].as_array().expect("leafQuads.bone");
        let bones = st["bones"].as_array().expect("bones");
        let foliage: Vec<_> = tree
            .triangles
            .iter()
            .filter(|t| t.part == Part::Foliage)
            .collect();
        assert_eq!(foliage.len(), 2 * quad_bone.len(), "{name}");
        let base = foliage.iter().flat_map(|t| t.v).min().unwrap_or(0);
        for t in &foliage {
            let q = ((t.v.iter().copied().min().unwrap_or(0) - base) / 4) as usize;
            let want_bone = quad_bone[q].as_u64().expect("bone index") as usize;
            let want_node = bones[want_bone]["node"].as_u64().expect("node") as usize;
            let got = tree.bones[t.bone.expect("bound") as usize].node;
            assert_eq!(got, want_node, "{name}: quad {q}");
        }
        assert_eq!(tree.foliage_reassigned, 0, "{name}");
    }
}

#[test]
fn blended_leaves_are_bound_to_a_bone_they_are_weighted_to() {
    let path = frond_testdata::require_tree!("oak_medium_blendedleaves.glb");
    let tree = import(&path, &ImportOptions::default()).expect("imports");
    let v = &tree.vertices;
    let mut checked = 0;
    for t in tree.triangles.iter().filter(|t| t.part == Part::Foliage) {
        let bone = t.bone.expect("bound") as usize;
        let weighted = t.v.iter().any(|&i| {
            let i = i as usize;
            let frond_scene::Binding::Skin { joints, .. } = &tree.bindings[v.binding[i] as usize]
            else {
                return false;
            };
            (0..4).any(|s| v.weights[i][s] > 0.0 && joints[v.joints[i][s] as usize] == bone)
        });
        assert!(
            weighted,
            "triangle bound to bone {bone} carries no weight on it"
        );
        checked += 1;
    }
    assert_eq!(checked, 10640);
    assert_eq!(
        tree.foliage_reassigned, 10640,
        "every blended triangle is reported as reassigned"
    );
}

#[test]
fn average_pose_is_the_mean_of_the_samples() {
    let g = generate(Preset::Small, 9).expect("generates");
    let tree = load(&g);
    let s = sample(
        &tree,
        &SampleOptions {
            clip: None,
            samples: 16,
        },
    )
    .expect("samples");
    for v in (0..s.vertices).step_by(97) {
        let mean = (0..16).map(|i| s.pose(i)[v]).sum::<Vec3>() / 16.0;
        assert!(mean.distance(s.average[v]) < 1e-5);
    }
}

/// The loop sampled without its poses has the full sampling's clock, foliage list and motion
/// facts, bit for bit, and holds none of the per-sample arrays; `into_loop` gives the same.
#[test]
fn loop_without_poses_keeps_the_clock_and_the_motion_facts() {
    let g = generate(Preset::Small, 4).expect("generates");
    let tree = load(&g);
    let options = SampleOptions {
        clip: None,
        samples: 24,
    };
    let full = sample(&tree, &options).expect("samples");
    let bare = frond_scene::sample_loop(&tree, &options).expect("samples the loop");
    assert!(full.has_poses() && !bare.has_poses());
    for s in [&bare, &full.clone().into_loop()] {
        assert_eq!(s.clip, full.clip);
        assert_eq!(s.period.to_bits(), full.period.to_bits());
        assert_eq!(s.times, full.times);
        assert_eq!(s.vertices, full.vertices);
        assert_eq!(s.foliage, full.foliage);
        assert_eq!(s.motion.loop_gap.to_bits(), full.motion.loop_gap.to_bits());
        assert_eq!(
            s.motion.max_displacement.to_bits(),
            full.motion.max_displacement.to_bits()
        );
        assert_eq!((s.motion.loops, s.motion.moves), (true, true));
        assert!(s.positions.is_empty() && s.centres.is_empty());
        assert!(s.bone_world.is_empty() && s.average.is_empty());
    }
    // A bad request fails the same way.
    let none = SampleOptions {
        clip: Some("no such clip".into()),
        samples: 4,
    };
    assert!(frond_scene::sample_loop(&tree, &none).is_err());
}
