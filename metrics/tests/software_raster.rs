//! The coverage metric's CPU rasteriser ([`frond_render::render_coverage`], the default)
//! against the wgpu path ([`Rasteriser::Gpu`]: its own rasterisation and texture filtering,
//! `K × K` pixels of a render `K` times the image's size counted per pixel) at the same
//! cameras, on real trees: the sample (in every checkout) and every shared tree, at 600, 200,
//! 60 and 20 pixels. Both draw the whole tree posed at two frames from the metric's default
//! views (5 on each of two rings). At each size:
//!
//! - one rasteriser's images scored against the other's, as the metric scores a LOD, differ by
//!   at most [`BOUND`];
//! - the metric's value for a simplified candidate (the tree with every second foliage card
//!   removed) computed with either rasteriser agrees to within [`BOUND`].
//!
//! The CPU images must not depend on the thread count, and their first render gives the depth
//! complexity.

mod common;

use std::sync::OnceLock;

use common::{load, without_every_second_card};
use frond_metrics::{
    CoverageImages, CoverageParams, Rasteriser, compare_images, coverage_images, depth_complexity,
};
use frond_render::{DrawScene, Renderer, TreeParts, tree_scene};
use frond_scene::Tree;
use glam::Vec3;

/// The largest difference allowed between the two rasterisers, in units of the coverage error.
const BOUND: f64 = 0.02;

/// The screen heights of a default LOD chain, and the smallest the metric judges.
const SIZES: [f32; 4] = [600.0, 200.0, 60.0, 20.0];

fn renderer() -> &'static Renderer {
    static RENDERER: OnceLock<Renderer> = OnceLock::new();
    RENDERER.get_or_init(|| {
        Renderer::new().unwrap_or_else(|e| panic!("no renderer (CI has Mesa llvmpipe): {e}"))
    })
}

/// `tree`'s `parts` at `frames` times over its first clip's loop.
fn frames(tree: &Tree, frames: usize, parts: TreeParts) -> Vec<DrawScene> {
    let clip = tree.clip_index(None);
    let period = clip.map_or(0.0, |c| tree.rig.clips[c].duration());
    (0..frames)
        .map(|f| {
            let t = period * f as f32 / frames as f32;
            tree_scene(tree, clip, t, parts)
        })
        .collect()
}

/// The metric's images of `scenes`, framed by `bounds_of`'s rest bounds.
fn images(bounds_of: &Tree, scenes: &[DrawScene], params: &CoverageParams) -> CoverageImages {
    let (lo, hi) = (
        Vec3::from(bounds_of.bounds.min),
        Vec3::from(bounds_of.bounds.max),
    );
    coverage_images(renderer(), scenes, lo, hi, params).unwrap_or_else(|e| panic!("images: {e}"))
}

/// What the two rasterisers give for one tree at one size.
struct Agreement {
    /// The thinned candidate's coverage error, CPU images.
    cpu: f64,
    /// The same, wgpu images.
    gpu: f64,
    /// The CPU images of the whole tree scored against the wgpu ones.
    images: f64,
    /// Their colour difference.
    colour: f64,
}

/// Renders `tree` and its thinned candidate at `screen_height` with both rasterisers (`views`
/// a ring on the metric's two rings, `frames` frames, colour) and scores them.
fn measure(
    tree: &Tree,
    thinned: &Tree,
    screen_height: f32,
    (views, frames): (u32, usize),
) -> Agreement {
    let params = CoverageParams {
        views,
        frames: frames as u32,
        screen_height,
        ..Default::default()
    };
    let gpu_params = CoverageParams {
        rasteriser: Rasteriser::Gpu,
        ..params.clone()
    };
    let (original, candidate) = (
        self::frames(tree, frames, TreeParts::All),
        self::frames(thinned, frames, TreeParts::All),
    );
    let all: Vec<usize> = (0..frames).collect();
    let both = |p: &CoverageParams| (images(tree, &original, p), images(tree, &candidate, p));
    let (cpu_o, cpu_s) = both(&params);
    let (gpu_o, gpu_s) = both(&gpu_params);
    let score = |o: &CoverageImages, s: &CoverageImages| {
        compare_images(o, s, &all).unwrap_or_else(|e| panic!("compare: {e}"))
    };
    let images = score(&gpu_o, &cpu_o);
    Agreement {
        cpu: score(&cpu_o, &cpu_s).mean,
        gpu: score(&gpu_o, &gpu_s).mean,
        images: images.mean,
        colour: images.colour_difference,
    }
}

/// Checks the agreement of the two rasterisers on `path` at every size of [`SIZES`] (`setup`:
/// views a ring and frames), after printing every size's numbers (so one failure shows them
/// all).
fn agree(name: &str, tree: &Tree, setup: (u32, usize)) {
    let (thinned, cards) = without_every_second_card(tree);
    assert!(cards >= 2, "{name}: {cards} foliage cards");
    let results: Vec<(f32, Agreement)> = SIZES
        .iter()
        .map(|&h| {
            let a = measure(tree, &thinned, h, setup);
            eprintln!(
                "{name} at {h} px: CPU {:.4}, GPU {:.4}, CPU-vs-GPU images {:.4} (colour {:.4})",
                a.cpu, a.gpu, a.images, a.colour
            );
            (h, a)
        })
        .collect();
    for (h, a) in &results {
        assert!(
            a.images <= BOUND,
            "{name} at {h} px: the CPU images differ from the GPU's by {}",
            a.images
        );
        assert!(
            (a.cpu - a.gpu).abs() <= BOUND,
            "{name} at {h} px: the candidate scores {} on the CPU, {} on the GPU",
            a.cpu,
            a.gpu
        );
        // A thinned tree misses coverage: a real error, not the noise of the comparison.
        assert!(a.cpu > 2.0 * BOUND, "{name} at {h} px: {}", a.cpu);
        assert!(
            a.colour <= BOUND,
            "{name} at {h} px: colours differ by {}",
            a.colour
        );
    }
}

#[test]
fn cpu_and_gpu_agree_on_the_sample() {
    // The metric's default views, two frames.
    agree("sapling", &load(&frond_testdata::sample()), (5, 2));
}

/// Every shared tree present; one skip line for each absent one.
#[test]
fn heavy_cpu_and_gpu_agree_on_shared_trees() {
    if !frond_testdata::heavy(env!("CARGO_CRATE_NAME")) {
        return;
    }
    // Three views a ring and one frame: the wgpu path on llvmpipe is slow.
    frond_testdata::each_shared_tree("heavy_cpu_and_gpu_agree_on_shared_trees", |name, path| {
        agree(name, &load(&path), (3, 1))
    });
}

/// Whatever the thread count, the CPU rasteriser gives the same sample counts and colours.
#[test]
fn cpu_images_do_not_depend_on_the_thread_count() {
    let tree = load(&frond_testdata::sample());
    let scenes = frames(&tree, 2, TreeParts::All);
    let params = CoverageParams {
        views: 3,
        frames: 2,
        screen_height: 60.0,
        ..Default::default()
    };
    let many = images(&tree, &scenes, &params);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| images(&tree, &scenes, &params));
    for pair in 0..many.views * many.frames {
        assert_eq!(many.fractions(pair), one.fractions(pair), "pair {pair}");
    }
    let same = compare_images(&many, &one, &[0, 1]).expect("same shapes");
    assert_eq!(same.mean, 0.0);
    assert_eq!(same.colour_difference, 0.0);
    assert_eq!(many.first_depth_complexity, one.first_depth_complexity);
}

/// The images' first render gives the depth complexity the separate measure gives (view 0,
/// frame 0, same camera and textures), with and without colour; the wgpu path gives none.
#[test]
fn the_first_render_gives_the_depth_complexity() {
    let tree = load(&frond_testdata::sample());
    let scenes = frames(&tree, 2, TreeParts::Foliage);
    let (lo, hi) = (Vec3::from(tree.bounds.min), Vec3::from(tree.bounds.max));
    for colour in [false, true] {
        let params = CoverageParams {
            views: 3,
            frames: 2,
            screen_height: 60.0,
            colour,
            ..Default::default()
        };
        let separate = depth_complexity(&scenes[0], lo, hi, 0, &params).expect("depth complexity");
        let from_images = images(&tree, &scenes, &params).first_depth_complexity;
        assert_eq!(from_images, Some(separate), "colour {colour}");
        assert!(separate > 1.0, "{separate}");
    }
    let gpu = CoverageParams {
        views: 1,
        elevations_deg: vec![0.0],
        frames: 1,
        screen_height: 20.0,
        samples_per_side: Some(4),
        rasteriser: Rasteriser::Gpu,
        ..Default::default()
    };
    assert_eq!(
        images(&tree, &scenes[..1], &gpu).first_depth_complexity,
        None
    );
}
