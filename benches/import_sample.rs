//! Import + 64-sample skinning benchmark: `oak_dense.glb` (target ≤ 1.5 s on 2 cores) and the
//! generated large preset. Prints the median of several runs per stage. `oak_dense.glb` is a
//! shared tree (`FROND_TEST_TREES`); without it that case is skipped with one line.

use std::path::Path;
use std::time::Instant;

use frond_scene::generator::{Preset, generate};
use frond_scene::{ImportOptions, SampleOptions, import, import_bytes, sample};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn bench(name: &str, runs: usize, load: &dyn Fn() -> frond_scene::Tree) {
    let (mut t_import, mut t_sample, mut t_total) = (Vec::new(), Vec::new(), Vec::new());
    let mut foliage = 0;
    for _ in 0..runs {
        let t0 = Instant::now();
        let tree = load();
        let t1 = Instant::now();
        let s = sample(&tree, &SampleOptions::default()).expect("samples");
        let t2 = Instant::now();
        foliage = s.foliage.len();
        t_import.push((t1 - t0).as_secs_f64());
        t_sample.push((t2 - t1).as_secs_f64());
        t_total.push((t2 - t0).as_secs_f64());
    }
    println!(
        "{name}: {foliage} foliage triangles, {} threads: import {:.3} s + 64-sample skinning {:.3} s = {:.3} s (median of {runs})",
        rayon::current_num_threads(),
        median(t_import),
        median(t_sample),
        median(t_total)
    );
}

fn main() {
    match frond_testdata::tree("oak_dense.glb") {
        Some(dense) => bench("oak_dense.glb", 5, &|| {
            import(&dense, &ImportOptions::default()).expect("imports")
        }),
        None => {
            frond_testdata::report_skip("import_sample oak_dense.glb", &["oak_dense.glb".into()])
        }
    }
    let large = generate(Preset::Large, 1).expect("generates").glb;
    bench("large preset", 3, &|| {
        import_bytes(Path::new("large.glb"), &large, &ImportOptions::default()).expect("imports")
    });
}
