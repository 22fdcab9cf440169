//! k-means over descriptions (spec §4.11, App. C.1): separable motions separate, k above the
//! number of descriptions is capped, the skeleton start keeps, merges and splits bone clusters,
//! and a seed gives one result.

use std::f32::consts::TAU;

use frond_spectral::description::{Bins, DescriptionType, DominatingAxisType};
use frond_spectral::kmeans::{cluster_descriptions, skeleton_start};
use glam::Vec3;

const N: usize = 32;

fn motion(axis: Vec3, freq: f32, amp: f32, phase: f32) -> Vec<Vec3> {
    (0..N)
        .map(|i| axis * amp * (freq * TAU * i as f32 / N as f32 + phase).sin())
        .collect()
}

/// 12 leaves: 6 swinging slowly along x, 6 fast along y, each with its own phase and a little
/// amplitude spread.
fn two_groups() -> Vec<Vec<Vec3>> {
    (0..12)
        .map(|i| {
            let f = i as f32;
            if i % 2 == 0 {
                motion(Vec3::X, 1.0, 1.0 + 0.02 * f, 0.3 * f)
            } else {
                motion(Vec3::Y, 4.0, 0.5 + 0.02 * f, 0.7 * f)
            }
        })
        .collect()
}

#[test]
fn separable_motions_separate_and_seeds_repeat() {
    let ty = DominatingAxisType {
        bins: Bins::PerPair(4),
    };
    let descs: Vec<_> = two_groups().iter().map(|t| ty.describe(t)).collect();
    let w = vec![1.0; descs.len()];
    let c = cluster_descriptions(&ty, &descs, &w, 2, None, 4, 7, 50);
    assert_eq!(c.centroids.len(), 2);
    for i in 0..descs.len() {
        // Same group ⇔ same cluster.
        assert_eq!(
            c.assignment[i] == c.assignment[0],
            i % 2 == 0,
            "{:?}",
            c.assignment
        );
    }
    let one = cluster_descriptions(&ty, &descs, &w, 1, None, 1, 7, 50);
    assert!(
        c.error < 0.1 && c.error < 0.1 * one.error,
        "{} vs {}",
        c.error,
        one.error
    );
    let again = cluster_descriptions(&ty, &descs, &w, 2, None, 4, 7, 50);
    assert_eq!(again.assignment, c.assignment);
    assert_eq!(again.error, c.error);
    // k above the number of descriptions: one each, no error.
    let many = cluster_descriptions(&ty, &descs, &w, 50, None, 2, 1, 50);
    assert_eq!(many.centroids.len(), descs.len());
    assert!(many.error < 1e-9);
}

#[test]
fn skeleton_start_keeps_merges_and_splits_bone_clusters() {
    let ty = DominatingAxisType {
        bins: Bins::PerPair(4),
    };
    // Bones 0 and 1 move alike (x, slow); bone 2 differs (y, fast). Two leaves per bone, one
    // near the bone's start joint and one far.
    let tracks = [
        motion(Vec3::X, 1.0, 1.0, 0.0),
        motion(Vec3::X, 1.0, 1.1, 0.5),
        motion(Vec3::X, 1.0, 1.0, 1.0),
        motion(Vec3::X, 1.0, 1.05, 1.5),
        motion(Vec3::Y, 4.0, 0.5, 0.0),
        motion(Vec3::Y, 4.0, 0.9, 0.2),
    ];
    let descs: Vec<_> = tracks.iter().map(|t| ty.describe(t)).collect();
    let w = vec![1.0; 6];
    let bone = [0, 0, 1, 1, 2, 2];
    let dist = [0.1, 0.9, 0.1, 0.9, 0.1, 0.9];
    let keep = skeleton_start(&ty, &descs, &w, &bone, &dist, 3);
    assert_eq!(keep, vec![0, 0, 1, 1, 2, 2]);
    // Two clusters: the alike bones 0 and 1 merge, bone 2 stays apart.
    let merged = skeleton_start(&ty, &descs, &w, &bone, &dist, 2);
    assert_eq!(merged[0], merged[2]);
    assert_ne!(merged[0], merged[4]);
    // Four: the most varied cluster (bone 2, amplitudes 0.5 and 0.9) splits near / far.
    let split = skeleton_start(&ty, &descs, &w, &bone, &dist, 4);
    assert_ne!(split[4], split[5]);
    assert_eq!(split[0], split[1]);
    let c = cluster_descriptions(&ty, &descs, &w, 2, Some((&bone, &dist)), 0, 1, 50);
    assert_eq!(c.start, "skeleton");
    assert_eq!(c.assignment[0], c.assignment[3]);
}
