//! SCA step 1 on `oak_dense.glb` (116k foliage triangles, 64 samples; target ≤ 2 s on
//! 2 cores): animation zones, a description per zone, shared frequency bins and k-means, for
//! each description type, as `frond lod --method spectral-*` runs them. Prints seconds, zone
//! count and the RMS motion residual of the clustering.
//!
//! `FROND_TREE` (a path), `FROND_ZONE` (% of the diagonal, default 2) and `FROND_K` (default
//! 16) change the case. `oak_dense.glb` is a shared tree (`FROND_TEST_TREES`); without it and
//! without `FROND_TREE` the bench is skipped with one line.

use std::path::PathBuf;
use std::time::Instant;

use frond_lod::methods::spectral::{SpectralParams, cluster_zones};
use frond_scene::{ImportOptions, SampleOptions, import, sample};
use frond_spectral::description::{
    AxisPhase, DescriptionType, DominatingAxisType, Naive, SpectralKind,
};

fn env_f32(name: &str, default: f32) -> f32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn run<T: DescriptionType>(
    tree: &frond_scene::Tree,
    s: &frond_scene::Sampled,
    rest: &[glam::Mat4],
    sp: &SpectralParams,
) {
    let t0 = Instant::now();
    let zc = cluster_zones::<T>(tree, s, rest, sp);
    let r = &zc.report;
    println!(
        "{:>16}: {:.3} s (zones + describe {:.3} s, k-means {:.3} s): {} zones, k = {}, {} bins, {} rounds, start {}, RMS residual {:.4} (no motion: {:.4})",
        r.kind,
        t0.elapsed().as_secs_f64(),
        r.t_describe,
        r.t_cluster,
        r.zones,
        r.clusters,
        r.bins,
        r.iterations,
        r.start,
        r.residual,
        r.motion_rms
    );
}

fn main() {
    let path = match std::env::var("FROND_TREE") {
        Ok(path) => PathBuf::from(path),
        Err(_) => match frond_testdata::tree("oak_dense.glb") {
            Some(path) => path,
            None => {
                frond_testdata::report_skip("spectral_cluster", &["oak_dense.glb".into()]);
                return;
            }
        },
    };
    let tree = import(&path, &ImportOptions::default()).expect("imports");
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    let b = tree.bounds;
    let diag = (glam::Vec3::from(b.max) - glam::Vec3::from(b.min)).length();
    let zone = env_f32("FROND_ZONE", 2.0) / 100.0 * diag;
    let k = env_f32("FROND_K", 16.0) as usize;
    println!(
        "{}: {} foliage triangles, {} samples, zone {zone:.3} ({}% of the diagonal), {} threads",
        path.display(),
        s.foliage.len(),
        s.samples(),
        env_f32("FROND_ZONE", 2.0),
        rayon::current_num_threads()
    );
    let rest = tree.rig.rest_world();
    for kind in SpectralKind::ALL {
        let sp = SpectralParams {
            kind,
            clusters: k,
            zone_size: zone,
            bins: tree.skeleton_depth().max(1) as usize,
            restarts: 2,
            seed: 1,
            max_iterations: 20,
            shared_bone: true,
            one_motion_per_cluster: false,
        };
        match kind {
            SpectralKind::Naive => run::<Naive>(&tree, &s, &rest, &sp),
            SpectralKind::DominatingAxis => run::<DominatingAxisType>(&tree, &s, &rest, &sp),
            SpectralKind::AxisPhase => run::<AxisPhase>(&tree, &s, &rest, &sp),
        }
    }
}
