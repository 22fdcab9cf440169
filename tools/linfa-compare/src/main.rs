//! linfa's k-means where an exact Euclidean embedding exists, against frond's own k-means over
//! the spectral description types. None of the three types has one: their deviations
//! are NEP-normalised sums of binned amplitude distances, cyclic phase differences and
//! `1 − |a·b|` axis terms, none a Euclidean distance. The motion itself has one: a zone's
//! zero-mean sampled trajectory as a 3N-vector, whose squared Euclidean distance to a centroid
//! is N times the mean squared motion residual (by Parseval, the same as the full complex DFT
//! with phases). So linfa clusters that "Euclidean analysis" (spec §4.4, the thesis's rejected
//! approach: time-offset leaves count as different), and both are scored by the RMS motion
//! residual SCA reports (world units), on the same zones.

use std::path::PathBuf;
use std::time::Instant;

use frond_billboard::animated::Rig;
use frond_billboard::spectral_build::{SpectralParams, cluster_zones};
use frond_scene::{ImportOptions, SampleOptions, import, sample};
use frond_spectral::description::{
    AxisPhase, DominatingAxisType, Naive, SpectralKind,
};
use glam::Vec3;
use linfa::prelude::*;
use linfa_clustering::KMeans;
use ndarray::Array2;
use rand_xoshiro::Xoshiro256Plus;
use rand_xoshiro::rand_core::SeedableRng;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/trees/oak_dense.glb")
    });
    let k: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(16);
    let tree = import(&path, &ImportOptions::default()).expect("imports");
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    let b = tree.bounds;
    let diag = (Vec3::from(b.max) - Vec3::from(b.min)).length();
    let rest = Rig::from_tree(&tree).rest_world();
    let params = |kind| SpectralParams {
        kind,
        clusters: k,
        zone_size: 0.02 * diag,
        bins: tree.skeleton_depth().max(1) as usize,
        restarts: 2,
        seed: 1,
        max_iterations: 20,
        shared_bone: true,
        one_motion_per_cluster: false,
    };
    println!(
        "{}: {} foliage triangles, {} samples, k = {k}, zones 2% of the diagonal",
        path.display(),
        s.foliage.len(),
        s.samples()
    );
    println!("| clustering | seconds | RMS motion residual | no motion |");
    println!("|---|---|---|---|");
    let mut zones = None;
    for kind in SpectralKind::ALL {
        let t0 = Instant::now();
        let report = match kind {
            SpectralKind::Naive => cluster_zones::<Naive>(&tree, &s, &rest, &params(kind)).report,
            SpectralKind::DominatingAxis => {
                let zc = cluster_zones::<DominatingAxisType>(&tree, &s, &rest, &params(kind));
                zones = Some((zc.trajectories.clone(), zc.weights.clone()));
                zc.report
            }
            SpectralKind::AxisPhase => {
                cluster_zones::<AxisPhase>(&tree, &s, &rest, &params(kind)).report
            }
        };
        println!(
            "| frond k-means, {} | {:.3} | {:.4} | {:.4} |",
            kind.name(),
            t0.elapsed().as_secs_f64(),
            report.residual,
            report.motion_rms
        );
    }
    let (trajectories, weights) = zones.expect("zones");
    // The Euclidean embedding: zero-mean motion, 3 coordinates per sample.
    let n = trajectories.first().map_or(0, |t| t.len());
    let t0 = Instant::now();
    let mut data = Array2::<f64>::zeros((trajectories.len(), 3 * n));
    for (i, t) in trajectories.iter().enumerate() {
        let mean = t.iter().copied().sum::<Vec3>() / n as f32;
        for (j, p) in t.iter().enumerate() {
            let d = *p - mean;
            for c in 0..3 {
                data[[i, 3 * j + c]] = f64::from(d[c]);
            }
        }
    }
    // linfa weighs every zone alike; the residual below weighs by triangles, as SCA does.
    let dataset = DatasetBase::from(data.clone());
    let model = KMeans::params_with_rng(k, Xoshiro256Plus::seed_from_u64(1))
        .n_runs(3)
        .max_n_iterations(20)
        .tolerance(1e-6)
        .fit(&dataset)
        .expect("k-means fits");
    let labels = model.predict(&data);
    let secs = t0.elapsed().as_secs_f64();
    // Weighted cluster means and the weighted RMS residual.
    let mut sums = vec![vec![0.0f64; 3 * n]; k];
    let mut mass = vec![0.0f64; k];
    for (i, &l) in labels.iter().enumerate() {
        let w = f64::from(weights[i]);
        mass[l] += w;
        for (acc, v) in sums[l].iter_mut().zip(data.row(i)) {
            *acc += w * v;
        }
    }
    let (mut sq, mut total) = (0.0f64, 0.0f64);
    for (i, &l) in labels.iter().enumerate() {
        let w = f64::from(weights[i]);
        let m = mass[l].max(f64::MIN_POSITIVE);
        let d: f64 = data
            .row(i)
            .iter()
            .zip(&sums[l])
            .map(|(v, s)| (v - s / m).powi(2))
            .sum();
        sq += w * d / n as f64;
        total += w;
    }
    println!(
        "| linfa k-means, Euclidean motion (3N = {}) | {secs:.3} | {:.4} | |",
        3 * n,
        (sq / total).sqrt()
    );
}
