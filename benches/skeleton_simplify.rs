//! SBCS on `oak_dense.glb` (264 bones, 116k foliage triangles, 64 samples; target ≤ 1 s
//! on 2 cores): the skeleton simplified to 20 billboard clouds with each bone description type,
//! as `frond lod --method skeleton-* --clouds 20` runs it (collapses, CJR, the resampled rig,
//! the error measures). Prints seconds, clouds, merges, collapses and the foliage error.
//!
//! `FROND_TREE` (a path) and `FROND_CLOUDS` (default 20) change the case. `oak_dense.glb` is a
//! shared tree (`FROND_TEST_TREES`); without it and without `FROND_TREE` the bench is skipped
//! with one line.

use std::path::PathBuf;
use std::time::Instant;

use frond_scene::{ImportOptions, SampleOptions, import, sample};
use frond_skeleton::{BoneDescriptionKind, SkeletonParams, simplify};

fn main() {
    let path = match std::env::var("FROND_TREE") {
        Ok(path) => PathBuf::from(path),
        Err(_) => match frond_testdata::tree("oak_dense.glb") {
            Some(path) => path,
            None => {
                frond_testdata::report_skip("skeleton_simplify", &["oak_dense.glb".into()]);
                return;
            }
        },
    };
    let clouds = std::env::var("FROND_CLOUDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    let tree = import(&path, &ImportOptions::default()).expect("imports");
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    let pixel = tree.bounds.height() / 60.0;
    println!(
        "{}: {} bones, {} foliage triangles, {} samples, budget {clouds} clouds",
        path.display(),
        tree.bones.len(),
        s.foliage.len(),
        s.samples()
    );
    for kind in [
        BoneDescriptionKind::AxisAngle,
        BoneDescriptionKind::RotationSpectral,
    ] {
        let params = SkeletonParams {
            kind,
            clouds: Some(clouds),
            average_bone: false,
            bins: tree.skeleton_depth().max(1) as usize,
            attach_tolerance: 0.5 * pixel,
            displacement_tolerance: pixel,
        };
        let t0 = Instant::now();
        let out = simplify(&tree, &s, tree.clip_index(None), &params).expect("simplifies");
        let r = &out.report;
        println!(
            "{:>18}: {:.3} s: {} clouds ({} foliage bones, CJR floor {}), {} merges, {} collapses, foliage error RMS {:.3} max {:.3}, detachment max {:.3}{}",
            kind.name(),
            t0.elapsed().as_secs_f64(),
            r.clouds,
            r.foliage_bones,
            r.cjr_floor,
            r.merges,
            r.collapses.len(),
            r.foliage_error_rms,
            r.foliage_error_max,
            r.detachment_max,
            r.stopped_by
                .as_ref()
                .map(|w| format!(" [{w}]"))
                .unwrap_or_default()
        );
    }
}
