//! Plane-search speed: oak_dense.glb (116,160 leaf triangles, average pose) at ε = 5 % and 1 % of
//! the bounding-box diagonal with S = 500 (targets ≤ 0.5 s and ≤ 0.9 s on 2 cores), oak_medium
//! (~10k) and generated trees of ~20k, ~200k and ~1M leaf triangles. `FROND_BENCH_PLAIN=1` also times the plain
//! O(planes·S·triangles) scan; `FROND_BENCH_SEEDS=N` averages billboard counts over N seeds.
//! oak_dense and oak_medium are shared trees (`FROND_TEST_TREES`); each absent one is skipped
//! with one line.

use std::path::{Path, PathBuf};
use std::time::Instant;

use frond_billboard::TriangleSoup;
use frond_billboard::plane_search::{SearchParams, search_planes};
use frond_scene::generator::{Preset, generate};
use frond_scene::{ImportOptions, SampleOptions, Tree, import, import_bytes, sample};
use glam::Vec3;

fn soup(tree: &Tree) -> (TriangleSoup, f32) {
    let s = sample(tree, &SampleOptions::default()).expect("samples");
    let b = tree.bounds;
    (
        TriangleSoup::from_tree(tree, &s.average, &s.foliage),
        (Vec3::from(b.max) - Vec3::from(b.min)).length(),
    )
}

fn run(name: &str, soup: &TriangleSoup, diag: f32, frac: f32, accelerated: bool, seeds: u64) {
    let mut times = Vec::new();
    let mut counts = Vec::new();
    for seed in 1..=seeds {
        let p = SearchParams {
            epsilon: frac * diag,
            candidates: 500,
            seed,
            accelerated,
            ..Default::default()
        };
        let t0 = Instant::now();
        let r = search_planes(soup, &p, diag);
        times.push(t0.elapsed().as_secs_f64());
        counts.push(r.clusters.len() as f64);
    }
    times.sort_by(f64::total_cmp);
    let mean = counts.iter().sum::<f64>() / counts.len() as f64;
    println!(
        "{name}: {} triangles, eps {:.0}% S=500 {}: {:.3} s (median of {}), {:.1} billboards (mean)",
        soup.len(),
        frac * 100.0,
        if accelerated { "accelerated" } else { "plain" },
        times[times.len() / 2],
        seeds,
        mean
    );
}

/// The shared tree `name`, or `None` after one `skipped:` line.
fn shared(name: &str) -> Option<PathBuf> {
    let path = frond_testdata::tree(name);
    if path.is_none() {
        frond_testdata::report_skip(&format!("plane_search {name}"), &[name.to_string()]);
    }
    path
}

fn main() {
    let seeds: u64 = std::env::var("FROND_BENCH_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let plain = std::env::var("FROND_BENCH_PLAIN").is_ok();
    if let Some(dense) = shared("oak_dense.glb") {
        let tree = import(&dense, &ImportOptions::default()).expect("oak_dense imports");
        let (s, diag) = soup(&tree);
        for frac in [0.05, 0.01] {
            run("oak_dense", &s, diag, frac, true, seeds);
            if plain {
                run("oak_dense", &s, diag, frac, false, 1);
            }
        }
    }
    if std::env::var("FROND_BENCH_DENSE_ONLY").is_ok() {
        return;
    }
    if let Some(medium) = shared("oak_medium.glb") {
        let tree = import(&medium, &ImportOptions::default()).expect("oak_medium imports");
        let (s, diag) = soup(&tree);
        for frac in [0.05, 0.01] {
            run("oak_medium", &s, diag, frac, true, 1);
        }
    }
    for preset in [Preset::Medium, Preset::Large, Preset::Xlarge] {
        let g = generate(preset, 1).expect("generates");
        let tree =
            import_bytes(Path::new("gen.glb"), &g.glb, &ImportOptions::default()).expect("imports");
        let (s, diag) = soup(&tree);
        for frac in [0.05, 0.01] {
            run(&format!("{preset:?}"), &s, diag, frac, true, 1);
        }
    }
}
