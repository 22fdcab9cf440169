//! The coverage metric's renders of `oak_dense.glb` (a shared tree, `FROND_TEST_TREES`;
//! skipped when absent) as `frond lod` measures its default chain: the input's masks, 5 views ×
//! 5 frames, at each LOD's image size (600, 200 and 60 px high), drawn by the CPU rasteriser
//! (eight samples at once where the machine has AVX2). The renders are most of the default
//! run's time; `RAYON_NUM_THREADS=1` gives their CPU time.
//!
//! `cargo bench -p frond-metrics --bench coverage_renders` (`FROND_BENCH_RUNS`, default 2).

use std::time::Instant;

use frond_metrics::eval::{EvalContext, EvalRequest, image_for_screen_height};
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
        views: 5,
        frames: 5,
        size: (0, 0),
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
        "coverage_renders oak_dense: 5 views x 5 frames, {} threads",
        rayon::current_num_threads()
    );
    for h in [600, 200, 60] {
        let size = image_for_screen_height(h);
        let seconds: Vec<f64> = (0..runs)
            .map(|_| {
                // A fresh context a run: each keeps the masks it rendered.
                let mut ctx = EvalContext::new(&renderer, &tree, &req).expect("sampled");
                let t = Instant::now();
                ctx.prepare_coverage(&[size]).expect("rendered");
                t.elapsed().as_secs_f64()
            })
            .collect();
        let best = seconds.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "  {h:>3} px ({}x{}, 4x supersampled): best {best:.3} s of {runs} ({:.1} ms a render)",
            size.0,
            size.1,
            best / 25.0 * 1000.0
        );
    }
}
