//! SCA (spec animated-billboard-clouds §4.11–4.14) on the bundled sapling: billboards that move
//! like their leaves, the shared-bone binding, and its failure modes (one bone, a
//! clip that does not loop, no motion, k larger than the zones).

use std::path::Path;

use frond_billboard::cloud::CloudParams;
use frond_lod::cloud_build::{BuildTimings, sampled_worlds};
use frond_lod::contract::SpectralMotion;
use frond_lod::methods::spectral::{
    SpectralParams, SpectralReport, build_spectral_cloud, cluster_zones, deepest_shared,
};
use frond_lod::{AnimatedBillboardCloud, BuildContext, LodLevel, LoopClock, RigidMotion};
use frond_render::Renderer;
use frond_scene::{ImportOptions, SampleOptions, Sampled, Tree, import, sample};
use frond_spectral::description::{AxisPhase, Components, SpectralKind};
use glam::Vec3;

fn sapling() -> Tree {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/sapling.glb");
    import(&p, &ImportOptions::default()).expect("sapling imports")
}

fn sampled(tree: &Tree) -> Sampled {
    sample(
        tree,
        &SampleOptions {
            clip: None,
            samples: 32,
        },
    )
    .expect("samples")
}

fn params(kind: SpectralKind, clusters: usize, tree: &Tree) -> SpectralParams {
    SpectralParams {
        kind,
        clusters,
        zone_size: 0.0,
        bins: tree.skeleton_depth().max(1) as usize,
        restarts: 2,
        seed: 3,
        max_iterations: 20,
        shared_bone: true,
        one_motion_per_cluster: false,
    }
}

fn cloud_params(tree: &Tree) -> CloudParams {
    let mut p = CloudParams::default();
    let pixel = tree.bounds.height() / 150.0;
    p.search.epsilon = pixel;
    p.search.candidates = 40;
    p.bake.texels_per_unit = 1.0 / pixel;
    p
}

/// SCA at a LOD 150 pixels high (the sizes of [`cloud_params`]).
fn build(
    renderer: &Renderer,
    tree: &Tree,
    s: &Sampled,
    sp: &SpectralParams,
    scale: f32,
) -> (AnimatedBillboardCloud, BuildTimings, SpectralReport) {
    let cloud = cloud_params(tree);
    let pixel = tree.bounds.height() / 150.0;
    let level = LodLevel {
        screen_height: 150.0,
        pixel,
        epsilon: pixel,
        texels_per_unit: 1.0 / pixel,
        wood_error: pixel,
    };
    let clock = LoopClock::of(tree, s);
    let ctx = BuildContext {
        renderer,
        tree,
        sampled: s,
        clock: &clock,
        level: &level,
        index: 0,
        cloud: &cloud,
        scale,
        seed: sp.seed,
        max_billboards: None,
        max_foliage_triangles: None,
        max_alpha_tested_area: None,
        max_joints: None,
        baked_wood: None,
    };
    build_spectral_cloud(&ctx, sp).expect("spectral cloud")
}

/// The far end's SCA: every billboard of a cluster moves with the cluster's one motion, in
/// world space (no shared bone), so the cloud has no more distinct motions than clusters.
#[test]
fn one_motion_per_cluster_gives_each_cluster_one_motion() {
    let tree = sapling();
    let s = sampled(&tree);
    let renderer = Renderer::new().expect("renderer");
    let sp = SpectralParams {
        one_motion_per_cluster: true,
        ..params(SpectralKind::AxisPhase, 4, &tree)
    };
    let (cloud, _, report) = build(&renderer, &tree, &s, &sp, tree.bounds.size());
    assert!(report.one_motion_per_cluster);
    assert_eq!(report.clusters, 4);
    assert_eq!(report.shared_bone_billboards, 0);
    let mut motions: Vec<&SpectralMotion> = Vec::new();
    for b in &cloud.billboards {
        assert_eq!(b.follows, None, "world-space motion");
        let Some(RigidMotion::Spectral(m)) = &b.motion else {
            panic!("every cluster of a swaying tree moves: {:?}", b.motion);
        };
        if !motions.contains(&m) {
            motions.push(m);
        }
    }
    assert!(
        (2..=4).contains(&motions.len()),
        "{} distinct motions for 4 clusters over {} billboards",
        motions.len(),
        cloud.billboards.len()
    );
    assert!(cloud.billboards.len() > motions.len());
}

#[test]
fn sca_billboards_move_like_their_leaves() {
    let tree = sapling();
    let s = sampled(&tree);
    let renderer = Renderer::new().expect("renderer");
    let sp = params(SpectralKind::AxisPhase, 6, &tree);
    let (cloud, _, report) = build(&renderer, &tree, &s, &sp, tree.bounds.size());
    assert_eq!(cloud.method, "spectral-axis-phase");
    assert_eq!(report.clusters, 6);
    assert!(report.loops);
    assert!(report.residual < report.motion_rms, "{report:?}");
    let worlds = sampled_worlds(&cloud.rig, &cloud.clock);
    let rest_inv = cloud.rest_inverse();
    let n = worlds.len();
    let k_of: std::collections::HashMap<usize, usize> =
        s.foliage.iter().enumerate().map(|(k, &t)| (t, k)).collect();
    let (mut err_moving, mut err_still, mut shared) = (0.0f64, 0.0f64, 0);
    for (i, b) in cloud.billboards.iter().enumerate() {
        assert!(
            matches!(b.motion, None | Some(RigidMotion::Spectral(_))),
            "SCA motion is spectral"
        );
        if let Some(node) = b.follows {
            shared += 1;
            // The followed node is every triangle's bone or one of its ancestors.
            for t in &b.triangles {
                let bone = tree.triangles[*t].bone.expect("bound") as usize;
                let mut cur = Some(tree.bones[bone].node);
                let mut found = false;
                while let Some(c) = cur {
                    found |= c == node;
                    cur = cloud.rig.nodes[c].parent;
                }
                assert!(found, "billboard {i} follows a shared ancestor");
            }
        }
        // The billboard's centre against the mean centre of its leaves, per sample.
        let ks: Vec<usize> = b.triangles.iter().map(|t| k_of[t]).collect();
        let still = cloud.corners_at(i, &worlds[0], &rest_inv, 0, n);
        let c_still = still.iter().copied().sum::<Vec3>() / 4.0;
        let mean_of =
            |s_: usize| ks.iter().map(|&k| s.trajectory(k)[s_]).sum::<Vec3>() / ks.len() as f32;
        let mean_leaf: Vec3 = (0..n).map(mean_of).sum::<Vec3>() / n as f32;
        for (si, world) in worlds.iter().enumerate() {
            let c = cloud.corners_at(i, world, &rest_inv, si, n);
            for q in &c {
                assert!(q.is_finite());
            }
            let centre = c.iter().copied().sum::<Vec3>() / 4.0;
            let leaf = mean_of(si);
            // Motion of the billboard vs motion of its leaves (offsets from their means).
            err_moving += f64::from((centre - c_still - (leaf - mean_of(0))).length_squared());
            err_still += f64::from((leaf - mean_leaf).length_squared());
        }
    }
    assert!(shared > 0, "some billboards follow a shared bone");
    assert!(
        err_moving < 0.5 * err_still,
        "billboards follow their leaves' motion: {err_moving} vs standing still {err_still}"
    );
}

#[test]
fn k_larger_than_the_zones_is_capped() {
    let tree = sapling();
    let s = sampled(&tree);
    let rest = tree.rig.rest_world();
    let mut sp = params(SpectralKind::AxisPhase, 1_000_000, &tree);
    sp.zone_size = 0.2 * tree.bounds.size();
    let zc = cluster_zones::<AxisPhase>(&tree, &s, &rest, &sp);
    assert_eq!(zc.report.clusters, zc.zones.len());
    let mut used = zc.assignment.clone();
    used.sort_unstable();
    used.dedup();
    assert_eq!(used.len(), zc.zones.len(), "every zone its own cluster");
    // Each zone keeps its own description: only the frequency binning is lost.
    assert!(
        zc.report.residual <= 0.2 * zc.report.motion_rms,
        "{:?}",
        zc.report
    );
    // Zones hold every triangle once, each within the zone size of the others.
    let total: usize = zc.zones.iter().map(|z| z.members.len()).sum();
    assert_eq!(total, s.foliage.len());
}

#[test]
fn one_bone_splits_by_distance_from_the_joint() {
    let mut tree = sapling();
    let s = sampled(&tree);
    for t in &mut tree.triangles {
        if t.bone.is_some() {
            t.bone = Some(0);
        }
    }
    let rest = tree.rig.rest_world();
    let zc =
        cluster_zones::<AxisPhase>(&tree, &s, &rest, &params(SpectralKind::AxisPhase, 4, &tree));
    assert_eq!(zc.report.clusters, 4);
    assert!(zc.report.error.is_finite() && zc.report.residual.is_finite());
    assert!(zc.report.residual < zc.report.motion_rms);
}

#[test]
fn a_clip_that_does_not_loop_is_described_as_one_period() {
    let mut tree = sapling();
    let c = &mut tree.rig.clips[0];
    c.end = c.start + 0.55 * (c.end - c.start);
    let s = sampled(&tree);
    assert!(!s.motion.loops, "the cut clip does not loop");
    let rest = tree.rig.rest_world();
    let zc =
        cluster_zones::<AxisPhase>(&tree, &s, &rest, &params(SpectralKind::AxisPhase, 3, &tree));
    assert!(!zc.report.loops);
    // Leakage spreads the seam's jump over the bins, but the motion stays finite and within
    // the range the leaves covered.
    for (d, t) in zc.descriptions.iter().zip(&zc.trajectories) {
        let m = frond_spectral::description::DescriptionType::apply(&zc.ty, d, t.len());
        let mean = t.iter().copied().sum::<Vec3>() / t.len() as f32;
        let reach = t.iter().map(|p| p.distance(mean)).fold(0.0f32, f32::max);
        for p in m {
            assert!(p.is_finite());
            assert!(
                p.length() <= 2.0 * reach + 1e-4,
                "{} vs {reach}",
                p.length()
            );
        }
    }
}

#[test]
fn no_motion_gives_still_billboards() {
    let mut tree = sapling();
    tree.rig.clips.clear();
    let s = sampled(&tree);
    let renderer = Renderer::new().expect("renderer");
    let sp = params(SpectralKind::DominatingAxis, 3, &tree);
    let (cloud, _, report) = build(&renderer, &tree, &s, &sp, tree.bounds.size());
    assert_eq!(report.motion_rms, 0.0);
    assert!(!cloud.billboards.is_empty());
    assert!(cloud.billboards.iter().all(|b| b.motion.is_none()));
}

#[test]
fn deepest_shared_bone_and_pruning() {
    let tree = sapling();
    let nodes = &tree.rig.nodes;
    // A node and its parent share the parent; a node alone is its own.
    let child = (0..nodes.len())
        .find(|&i| nodes[i].parent.is_some())
        .expect("a child");
    let parent = nodes[child].parent;
    assert_eq!(deepest_shared(nodes, &[Some(child), parent]), parent);
    assert_eq!(deepest_shared(nodes, &[Some(child)]), Some(child));
    assert_eq!(deepest_shared(nodes, &[Some(child), None]), None);
    assert_eq!(deepest_shared(nodes, &[]), None);
    // Two siblings share their parent, which is neither of them; with a grandchild of one of
    // them, still that parent.
    let parent = (0..nodes.len())
        .find(|&i| nodes[i].children.len() >= 2)
        .expect("a node with two children");
    let (a, b) = (nodes[parent].children[0], nodes[parent].children[1]);
    assert_eq!(deepest_shared(nodes, &[Some(a), Some(b)]), Some(parent));
    if let Some(&g) = nodes[a].children.first() {
        assert_eq!(deepest_shared(nodes, &[Some(g), Some(b)]), Some(parent));
        assert_eq!(deepest_shared(nodes, &[Some(g), Some(a)]), Some(a));
    }

    let axis = |f: Vec<usize>, a: Vec<f32>| Components {
        phases: vec![0.0; f.len()],
        frequencies: f,
        amplitudes: a,
    };
    let mut m = SpectralMotion {
        axes: [
            axis(vec![1, 2], vec![1.0, 0.01]),
            axis(vec![3], vec![0.02]),
            axis(vec![], vec![]),
        ],
        samples: 16,
    };
    let full: Vec<Vec3> = (0..16).map(|s| m.offset(s as f32)).collect();
    // 0.01 + 0.02 < 0.05: both weak terms go, the strong one stays.
    assert_eq!(m.prune(0.05), 2);
    assert_eq!(m.terms(), 1);
    for (s, f) in full.iter().enumerate() {
        assert!(m.offset(s as f32).distance(*f) <= 0.03 + 1e-6);
    }
    assert_eq!(m.prune(0.5), 0, "1.0 is above the tolerance");
    // The motion at a sample is that translation.
    let t = RigidMotion::Spectral(m.clone()).at(4, 16);
    assert!(t.translation.distance(m.offset(4.0).into()) < 1e-6);
}
