//! The coverage metric's CPU rasteriser ([`frond_render::render_coverage`], the default)
//! against the wgpu path it replaced ([`Rasteriser::Gpu`]) on real trees: the sample (in every
//! checkout) and two shared trees. Both draw the posed foliage from the metric's views and
//! frames; their masks must agree to within 1 % of the covered pixels and their colours to
//! within the colour metric's noise, and the CPU masks must not depend on the thread count.

use std::path::Path;
use std::sync::OnceLock;

use frond_metrics::{
    CoverageMasks, CoverageParams, Rasteriser, compare_masks, coverage_masks,
    image_for_screen_height,
};
use frond_render::{DrawScene, Renderer, TreeParts, tree_scene};
use frond_scene::{ImportOptions, Tree, import};
use glam::Vec3;

fn renderer() -> &'static Renderer {
    static RENDERER: OnceLock<Renderer> = OnceLock::new();
    RENDERER.get_or_init(|| {
        Renderer::new().unwrap_or_else(|e| panic!("no renderer (CI has Mesa llvmpipe): {e}"))
    })
}

fn load(path: &Path) -> Tree {
    import(path, &ImportOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The foliage of `tree` at `frames` times over its first clip's loop.
fn frames(tree: &Tree, frames: usize) -> Vec<DrawScene> {
    let clip = tree.clip_index(None);
    let period = clip.map_or(0.0, |c| tree.rig.clips[c].duration());
    (0..frames)
        .map(|f| {
            let t = period * f as f32 / frames as f32;
            tree_scene(tree, clip, t, TreeParts::Foliage)
        })
        .collect()
}

fn masks(tree: &Tree, scenes: &[DrawScene], params: &CoverageParams) -> CoverageMasks {
    let (lo, hi) = (Vec3::from(tree.bounds.min), Vec3::from(tree.bounds.max));
    coverage_masks(renderer(), scenes, lo, hi, params).unwrap_or_else(|e| panic!("masks: {e}"))
}

/// Renders `tree` at `screen_height` with both rasterisers and checks their agreement.
fn agree(path: &Path, screen_height: u32) {
    let tree = load(path);
    let scenes = frames(&tree, 2);
    let (width, height) = image_for_screen_height(screen_height);
    let params = CoverageParams {
        views: 3,
        frames: 2,
        width,
        height,
        ..Default::default()
    };
    let cpu = masks(&tree, &scenes, &params);
    let gpu = masks(
        &tree,
        &scenes,
        &CoverageParams {
            rasteriser: Rasteriser::Gpu,
            ..params.clone()
        },
    );
    // One rasteriser's masks scored against the other's, as the metric scores a LOD.
    let r = compare_masks(&gpu, &cpu, &[0, 1]).expect("same shapes");
    let name = path.display();
    eprintln!(
        "{name} at {screen_height} px: masks differ on {:.4} of the covered pixels, colour {:.4}",
        r.mean, r.colour_difference
    );
    assert_eq!(r.discarded, 0, "{name}");
    assert!(
        r.mean <= 0.01,
        "{name}: masks differ on {} of the pixels",
        r.mean
    );
    assert!(
        r.colour_difference <= 0.02,
        "{name}: colours differ by {}",
        r.colour_difference
    );
    // Whatever the thread count, the same masks.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool")
        .install(|| masks(&tree, &scenes, &params));
    let same = compare_masks(&cpu, &one, &[0, 1]).expect("same shapes");
    assert_eq!(same.differing_pixels.iter().sum::<u64>(), 0, "{name}");
    assert_eq!(same.colour_difference, 0.0, "{name}");
}

#[test]
fn cpu_and_gpu_masks_agree_on_the_sample() {
    agree(&frond_testdata::sample(), 600);
    agree(&frond_testdata::sample(), 60);
}

#[test]
fn cpu_and_gpu_masks_agree_on_shared_trees() {
    let trees = frond_testdata::require_trees!(["oak_medium.glb", "pine_medium_blender.glb"]);
    for tree in &trees {
        agree(tree, 200);
    }
}

/// The masks' first render gives the depth complexity the separate measure gives (view 0,
/// frame 0, same camera and textures), with and without colour; the wgpu path gives none.
#[test]
fn the_first_render_gives_the_depth_complexity() {
    let tree = load(&frond_testdata::sample());
    let scenes = frames(&tree, 2);
    let (lo, hi) = (Vec3::from(tree.bounds.min), Vec3::from(tree.bounds.max));
    for colour in [false, true] {
        let params = CoverageParams {
            views: 3,
            frames: 2,
            width: 120,
            height: 90,
            colour,
            ..Default::default()
        };
        let separate = frond_metrics::depth_complexity(&scenes[0], lo, hi, 0, &params)
            .expect("depth complexity");
        let from_masks = masks(&tree, &scenes, &params).first_depth_complexity;
        assert_eq!(from_masks, Some(separate), "colour {colour}");
        assert!(separate > 1.0, "{separate}");
    }
    let gpu = CoverageParams {
        views: 1,
        frames: 1,
        width: 40,
        height: 30,
        rasteriser: Rasteriser::Gpu,
        ..Default::default()
    };
    assert_eq!(
        masks(&tree, &scenes[..1], &gpu).first_depth_complexity,
        None
    );
}
