//! The coverage metric's renders of `oak_dense.glb` (a shared tree, `FROND_TEST_TREES`;
//! skipped when absent) as `frond lod` measures its default chain: the input's images, 5 views
//! on each of 2 rings × 3 frames, at each LOD's size (600, 200 and 60 px, and 20 px), drawn
//! by the CPU rasteriser (eight samples at once where the machine has AVX2); then one
//! candidate measured against them at 60 and 20 px (its renders and the comparison, the
//! original's excluded): the LOD file `FROND_BENCH_CANDIDATE` names (the 60 px LOD of a
//! default `frond lod oak_dense.glb` run, `oak_dense_LOD3.glb`), else the input itself (no LOD
//! of it draws more). `RAYON_NUM_THREADS=1` gives their CPU time.
//!
//! `cargo bench -p frond-metrics --bench coverage_renders` (`FROND_BENCH_RUNS`, default 2).

use std::time::Instant;

use frond_metrics::eval::{EvalContext, EvalRequest};
use frond_metrics::framing::samples_per_side;
use frond_render::Renderer;
use frond_scene::{ImportOptions, InputLimits, import};

fn main() {
    let Some(path) = frond_testdata::tree("oak_dense.glb") else {
        frond_testdata::report_skip("coverage_renders", &["oak_dense.glb".to_string()]);
        return;
    };
    let runs: usize = std::env::var("FROND_BENCH_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2);
    let tree = import(&path, &ImportOptions::default()).expect("oak_dense imports");
    let renderer = Renderer::new().expect("a renderer");
    let req = EvalRequest {
        views: frond_metrics::DEFAULT_VIEWS,
        frames: frond_metrics::DEFAULT_FRAMES,
        screen_height: 600.0,
        fov_deg: frond_metrics::DEFAULT_FOV_DEG,
        resolution: frond_metrics::DEFAULT_RESOLUTION,
        samples: 2,
        clip: None,
        limits: InputLimits {
            max_input_bytes: u64::MAX,
            max_texture_bytes: u64::MAX,
            max_vertices: u64::MAX,
            max_animation_keys: u64::MAX,
        },
        white_albedo: false,
        lighting: Default::default(),
    };
    println!(
        "coverage_renders oak_dense: 5 views x 2 rings x 3 frames, {} threads",
        rayon::current_num_threads()
    );
    let mut ctx = EvalContext::new(&renderer, &tree, &req).expect("sampled");
    for h in [600.0f32, 200.0, 60.0, 20.0] {
        let seconds: Vec<f64> = (0..runs)
            .map(|_| {
                // A fresh context a run: each keeps the images it rendered.
                let mut ctx = EvalContext::new(&renderer, &tree, &req).expect("sampled");
                let t = Instant::now();
                ctx.prepare_coverage(&[h]).expect("rendered");
                t.elapsed().as_secs_f64()
            })
            .collect();
        let best = seconds.iter().copied().fold(f64::INFINITY, f64::min);
        let k = samples_per_side(h);
        println!(
            "  input's images at {h:>3} px ({k}x{k} samples a pixel): best {best:.3} s of {runs} \
             ({:.1} ms a render)",
            best / 30.0 * 1000.0
        );
    }
    let candidate = std::env::var_os("FROND_BENCH_CANDIDATE").map(|p| {
        let options = ImportOptions {
            allow_empty: true,
            ..Default::default()
        };
        import(std::path::Path::new(&p), &options).expect("the candidate imports")
    });
    let same = candidate.is_none();
    let candidate = candidate.as_ref().unwrap_or(&tree);
    for h in [60.0f32, 20.0] {
        ctx.prepare_coverage(&[h]).expect("rendered");
        let seconds: Vec<f64> = (0..runs)
            .map(|_| {
                let t = Instant::now();
                let m = ctx.measure(candidate, h).expect("measured");
                assert!(!same || m.report.mean == 0.0, "the input against itself");
                t.elapsed().as_secs_f64()
            })
            .collect();
        let best = seconds.iter().copied().fold(f64::INFINITY, f64::min);
        let name = candidate.source.display();
        println!("  {name} measured at {h:>3} px: best {best:.3} s of {runs}");
    }
}
