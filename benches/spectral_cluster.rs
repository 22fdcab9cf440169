//! Descriptions + clustering of every foliage triangle of `oak_dense.glb` (116k triangles, 64
//! samples; issue 6 target ≤ 2 s on 2 cores): describe with each type, then k-means (k = 20,
//! skeleton start + 2 k-means++ restarts) with the dominating-axis type over one shared
//! frequency partition. Prints seconds per stage. Without animation zones, every triangle is
//! clustered on its own.

use std::path::Path;
use std::time::Instant;

use frond_scene::{ImportOptions, SampleOptions, import, sample};
use frond_spectral::description::{AxisPhase, Bins, DescriptionType, DominatingAxisType, Naive};
use frond_spectral::kmeans::cluster_descriptions;
use rayon::prelude::*;

fn describe_all<T: DescriptionType>(ty: &T, s: &frond_scene::Sampled) -> (Vec<T::Desc>, f64) {
    let t0 = Instant::now();
    let d: Vec<T::Desc> = (0..s.foliage.len())
        .into_par_iter()
        .map(|k| ty.describe(s.trajectory(k)))
        .collect();
    (d, t0.elapsed().as_secs_f64())
}

fn main() {
    let dense = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/trees/oak_dense.glb");
    let tree = import(&dense, &ImportOptions::default()).expect("imports");
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    let bins = tree.skeleton_depth().max(1) as usize;
    println!(
        "oak_dense: {} foliage triangles, {} samples, {bins} bins, {} threads",
        s.foliage.len(),
        s.samples(),
        rayon::current_num_threads()
    );
    let (_, t) = describe_all(
        &Naive {
            bins: Bins::PerPair(bins),
        },
        &s,
    );
    println!("describe naive: {t:.3} s");
    let (_, t) = describe_all(
        &AxisPhase {
            bins: Bins::PerPair(bins),
        },
        &s,
    );
    println!("describe axis-phase: {t:.3} s");
    let (descs, t) = describe_all(
        &DominatingAxisType {
            bins: Bins::PerPair(bins),
        },
        &s,
    );
    println!("describe dominating axis: {t:.3} s");
    // One frequency partition for every comparison (per-pair binning costs ~3 µs a deviation).
    let t0 = Instant::now();
    let spectra: Vec<&[f32]> = descs.iter().map(|d| d.amplitudes.as_slice()).collect();
    let ty = DominatingAxisType {
        bins: Bins::shared(&spectra, bins),
    };
    println!("shared frequency bins: {:.3} s", t0.elapsed().as_secs_f64());
    let bone: Vec<usize> = s
        .foliage
        .iter()
        .map(|&f| tree.triangles[f].bone.map_or(0, |b| b as usize))
        .collect();
    let dist: Vec<f32> = s
        .foliage
        .iter()
        .enumerate()
        .map(|(k, &f)| {
            let b = tree.triangles[f].bone.map_or(0, |b| b as usize);
            let joint = tree.bones[b].rest_world.w_axis.truncate();
            s.trajectory(k)[0].distance(joint)
        })
        .collect();
    let w = vec![1.0f32; descs.len()];
    let t0 = Instant::now();
    let c = cluster_descriptions(&ty, &descs, &w, 20, Some((&bone, &dist)), 2, 1, 20);
    println!(
        "k-means (k = 20, skeleton + 2 restarts, ≤ 20 rounds): {:.3} s, error {:.1}, start {}, {} rounds",
        t0.elapsed().as_secs_f64(),
        c.error,
        c.start,
        c.iterations
    );
}
