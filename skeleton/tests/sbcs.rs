//! Known answers of skeleton simplification (spec animated-billboard-clouds §6): identical
//! siblings merge first at zero deviation, a collapse of siblings whose end joints coincide is
//! exact, the budget is met or the report says which level stops it.

use std::path::Path;

use frond_scene::{ImportOptions, SampleOptions, Trs, import, sample};
use frond_skeleton::cjr::common_rotation_sets;
use frond_skeleton::collapse::{EndJointCache, collapse_candidates, collapse_pair};
use frond_skeleton::description::{AxisAngle, BoneDescriptionType, RotationSpectral};
use frond_skeleton::model::{SkNode, SkeletonModel};
use frond_skeleton::{BoneDescriptionKind, SkeletonParams, simplify};
use glam::{Quat, Vec3};

const N: usize = 32;

/// A node turning by `delta(s)` about its pivot `at` (parent frame).
fn node(name: &str, parent: Option<usize>, at: Vec3, delta: impl Fn(f32) -> Quat) -> SkNode {
    let rest = Trs {
        translation: at,
        ..Trs::IDENTITY
    };
    SkNode {
        name: name.into(),
        parent,
        children: Vec::new(),
        rest,
        track: (0..N)
            .map(|s| Trs {
                rotation: delta(std::f32::consts::TAU * s as f32 / N as f32),
                ..rest
            })
            .collect(),
        source: None,
        changed: false,
        alive: true,
        foliage: Vec::new(),
    }
}

fn link(nodes: &mut [SkNode]) {
    for i in 0..nodes.len() {
        if let Some(p) = nodes[i].parent {
            nodes[p].children.push(i);
        }
    }
}

fn swing(axis: Vec3, amp: f32, phase: f32) -> impl Fn(f32) -> Quat {
    move |t| Quat::from_axis_angle(axis.normalize(), amp * (t + phase).sin())
}

/// A trunk with four terminal siblings: a and b at one pivot with the same motion, c and d
/// elsewhere with their own.
fn four_siblings() -> SkeletonModel {
    let mut nodes = vec![
        node("trunk", None, Vec3::ZERO, swing(Vec3::X, 0.05, 0.0)),
        node(
            "a",
            Some(0),
            Vec3::new(0.0, 2.0, 0.0),
            swing(Vec3::Z, 0.3, 0.0),
        ),
        node(
            "b",
            Some(0),
            Vec3::new(0.0, 2.0, 0.0),
            swing(Vec3::Z, 0.3, 0.0),
        ),
        node(
            "c",
            Some(0),
            Vec3::new(0.0, 3.0, 0.0),
            swing(Vec3::X, 0.2, 1.0),
        ),
        node(
            "d",
            Some(0),
            Vec3::new(0.0, 2.5, 0.0),
            swing(Vec3::Y, 0.25, 2.5),
        ),
    ];
    link(&mut nodes);
    let leaves = vec![
        (1, Vec3::new(1.0, 2.5, 0.0)),
        (1, Vec3::new(1.5, 2.2, 0.3)),
        (2, Vec3::new(-1.0, 2.4, 0.2)),
        (3, Vec3::new(0.0, 3.5, 1.0)),
        (4, Vec3::new(0.5, 2.7, -1.0)),
    ];
    SkeletonModel::from_nodes(nodes, &leaves)
}

fn identical_merge_first<T: BoneDescriptionType>(ty: &T) {
    let model = four_siblings();
    let cjr = common_rotation_sets(ty, &model, 3, 0, false, None, None);
    assert_eq!(cjr.merges.len(), 1);
    let m = &cjr.merges[0];
    let mut names = [m.a.clone(), m.b.clone()].concat();
    names.sort();
    assert_eq!(names, vec!["a", "b"]);
    assert!(m.deviation.abs() < 1e-6, "deviation {}", m.deviation);
    assert!(m.displacement < 1e-5, "displacement {}", m.displacement);
    assert_eq!(cjr.sets.len(), 3);
    // Down to one set: every sibling shares one rotation, and the later merges cost more.
    let all = common_rotation_sets(ty, &model, 1, 0, false, None, None);
    assert_eq!(all.sets.len(), 1);
    assert!(all.merges[1].displacement > 1e-3);
}

#[test]
fn identical_siblings_merge_first_at_zero_deviation() {
    identical_merge_first(&AxisAngle);
    identical_merge_first(&RotationSpectral::new(4));
}

#[test]
fn descriptions_are_lossless_for_one_bone_and_tell_opposites_apart() {
    let deltas: Vec<Quat> = (0..N)
        .map(|s| {
            swing(Vec3::new(1.0, 0.5, 0.2), 0.4, 0.3)(std::f32::consts::TAU * s as f32 / N as f32)
        })
        .collect();
    let opposite: Vec<Quat> = deltas.iter().map(|q| q.inverse()).collect();
    let aa = AxisAngle;
    let rs = RotationSpectral::new(4);
    for back in [
        aa.apply(&aa.describe(&deltas)),
        rs.apply(&rs.describe(&deltas)),
    ] {
        for (a, b) in back.iter().zip(&deltas) {
            assert!(1.0 - a.dot(*b).abs() < 1e-6, "{a} {b}");
        }
    }
    assert!(aa.deviation(&aa.describe(&deltas), &aa.describe(&opposite)) > 0.1);
    assert!(rs.deviation(&rs.describe(&deltas), &rs.describe(&opposite)) > 0.1);
}

#[test]
fn attachment_tolerance_keeps_far_pivots_apart() {
    let model = four_siblings();
    // c and d sit 1 and 0.5 above a/b: with a tiny tolerance only a+b (same pivot) may merge.
    let cjr = common_rotation_sets(&AxisAngle, &model, 1, 0, false, Some(1e-4), None);
    assert_eq!(cjr.sets.len(), 3);
}

#[test]
fn collapse_of_siblings_with_coinciding_end_joints_is_exact() {
    // a and b turn alike about one pivot; their children a1 and b1 both start at j* and turn
    // about it their own way; leaves on a1 and b1.
    let j_star = Vec3::new(0.3, 3.0, 0.1);
    let pivot = Vec3::new(0.0, 1.0, 0.0);
    let mut nodes = vec![
        node("trunk", None, Vec3::ZERO, swing(Vec3::X, 0.05, 0.0)),
        node("a", Some(0), pivot, swing(Vec3::Z, 0.2, 0.0)),
        node("b", Some(0), pivot, swing(Vec3::Z, 0.2, 0.0)),
        node("a1", Some(1), j_star - pivot, swing(Vec3::X, 0.3, 1.0)),
        node(
            "b1",
            Some(2),
            j_star - pivot,
            swing(Vec3::new(1.0, 0.0, 1.0), 0.25, 2.0),
        ),
        node(
            "c",
            Some(0),
            Vec3::new(0.0, 0.5, 0.0),
            swing(Vec3::Y, 0.1, 0.5),
        ),
        node(
            "c1",
            Some(5),
            Vec3::new(0.0, 1.0, 0.0),
            swing(Vec3::X, 0.1, 0.5),
        ),
    ];
    link(&mut nodes);
    let leaves = vec![
        (3, j_star + Vec3::new(1.0, 0.5, 0.0)),
        (3, j_star + Vec3::new(0.5, 1.0, 0.5)),
        (4, j_star + Vec3::new(-1.0, 0.7, 0.2)),
        (4, j_star + Vec3::new(-0.3, 1.2, -0.8)),
        (6, Vec3::new(0.5, 2.0, 0.5)),
    ];
    let mut model = SkeletonModel::from_nodes(nodes, &leaves);
    let before: Vec<_> = (0..N).map(|s| model.world(s)).collect();
    let mut cache = EndJointCache::default();
    let candidates = collapse_candidates(&model, &mut cache);
    let &(a, b, j, e) = candidates
        .iter()
        .find(|c| (c.0, c.1) == (1, 2))
        .expect("a, b pair");
    assert!(
        j.as_vec3().distance(j_star) < 1e-3,
        "end joint {j} vs {j_star}"
    );
    let (c, record) = collapse_pair(&AxisAngle, &mut model, a, b, j, e, 0);
    assert_eq!(record.depth, 2);
    assert_eq!(model.nodes[3].parent, Some(c));
    assert_eq!(model.nodes[4].parent, Some(c));
    for (s, was) in before.iter().enumerate() {
        let after = model.world(s);
        for child in [3, 4] {
            let d = (after[child] - was[child]).abs();
            let worst = d.to_cols_array().iter().fold(0.0f32, |m, v| m.max(*v));
            assert!(worst < 1e-4, "sample {s}, child {child}: {worst}");
        }
    }
}

#[test]
fn the_budget_is_met_or_the_report_names_the_level() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/sapling.glb");
    let tree = import(&p, &ImportOptions::default()).expect("sapling imports");
    let sampled = sample(
        &tree,
        &SampleOptions {
            clip: None,
            samples: 16,
        },
    )
    .expect("samples");
    let params = |clouds| SkeletonParams {
        kind: BoneDescriptionKind::AxisAngle,
        clouds: Some(clouds),
        average_bone: false,
        bins: 4,
        attach_tolerance: 0.0,
        displacement_tolerance: 0.0,
    };
    let clip = tree.clip_index(None);
    let free = simplify(&tree, &sampled, clip, &params(1000)).expect("simplifies");
    let bones = free.report.foliage_bones;
    assert_eq!(free.report.clouds, bones);
    assert_eq!(free.report.merges, 0);
    assert!(free.report.foliage_error_max < 1e-3);
    // Half the clouds: met, by CJR (and collapses where needed).
    let half = simplify(&tree, &sampled, clip, &params(bones / 2)).expect("simplifies");
    assert_eq!(half.report.clouds, bones / 2);
    assert!(half.report.stopped_by.is_none());
    // One cloud: not reachable without parent/child collapse; the report names the levels.
    let one = simplify(&tree, &sampled, clip, &params(1)).expect("simplifies");
    match &one.report.stopped_by {
        Some(why) => {
            assert!(one.report.clouds > 1);
            assert!(why.contains("skeleton level"), "{why}");
        }
        None => assert_eq!(one.report.clouds, 1),
    }
    assert!(one.report.trunk_on_original_skeleton);
    assert!(!one.report.collapses.is_empty());
    assert!(one.report.clouds < half.report.clouds);
}
