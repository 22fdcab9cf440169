//! The CPU bake rasteriser (the default) and the wgpu path bake the same atlas: on
//! the same quads and members, every quad's coverage (its cell's summed alpha) agrees within
//! 1 % of the cell, and its mean colour within 2 of 255 per channel. Measured on the bundled
//! sample and two shared trees, each at a 5 % and a 1 % ε (large and small billboards).

use crate::common;

use std::path::Path;

use common::*;
use frond_billboard::cloud::{CloudParams, build_cloud};
use frond_billboard::{BakeParams, BakeRasteriser, BakedCloud, TriangleSoup, bake_cloud};
use frond_render::{Renderer, TreeParts, scene_from_positions};
use frond_scene::{ImportOptions, import};

/// Most difference in a quad's coverage, as a fraction of its cell.
const COVERAGE_TOLERANCE: f64 = 0.01;
/// Most difference in a quad's mean colour, per channel (sRGB bytes).
const COLOUR_TOLERANCE: f64 = 2.0;

/// Per quad: summed alpha / (255 · cell texels), and the alpha-weighted mean colour.
fn quad_stats(baked: &BakedCloud) -> Vec<(f64, [f64; 3])> {
    let w = baked.atlas.width as usize;
    baked
        .cells
        .iter()
        .map(|c| {
            let (mut alpha, mut colour) = (0.0, [0.0; 3]);
            for y in c.y..c.y + c.height {
                for x in c.x..c.x + c.width {
                    let i = (y as usize * w + x as usize) * 4;
                    let p = &baked.atlas.color[i..i + 4];
                    let a = f64::from(p[3]);
                    alpha += a;
                    for k in 0..3 {
                        colour[k] += a * f64::from(p[k]);
                    }
                }
            }
            let area = f64::from(c.width * c.height) * 255.0;
            let mean = if alpha > 0.0 {
                colour.map(|v| v / alpha)
            } else {
                [0.0; 3]
            };
            (alpha / area, mean)
        })
        .collect()
}

/// Bakes `path`'s foliage cloud at `epsilon` (fraction of the diagonal) with both rasterisers
/// and compares them quad by quad.
fn compare(renderer: &Renderer, path: &Path, epsilon: f32) {
    let name = path.display();
    let tree = import(path, &ImportOptions::default()).expect("imports");
    let sampled = frond_lod::chain::sample_foliage(&tree, None, 16).expect("samples");
    let soup = TriangleSoup::from_tree(&tree, &sampled.average, &sampled.foliage);
    let scene = scene_from_positions(&tree, &sampled.average, None, TreeParts::Foliage);
    let diagonal = tree.bounds.diagonal();
    let mut params = CloudParams::default();
    params.search.epsilon = epsilon * diagonal;
    params.bake.texels_per_unit = 512.0 / diagonal;
    let cloud = build_cloud(
        renderer,
        &soup,
        &scene.materials,
        &scene.textures,
        &params,
        diagonal,
    )
    .expect("cloud");
    assert_eq!(params.bake.rasteriser, BakeRasteriser::Cpu, "the default");
    let members: Vec<Vec<usize>> = cloud
        .search
        .clusters
        .iter()
        .map(|c| c.triangles.clone())
        .collect();
    let wgpu = bake_cloud(
        renderer,
        &soup,
        &scene.materials,
        &scene.textures,
        &cloud.quads,
        &members,
        &BakeParams {
            rasteriser: BakeRasteriser::Wgpu,
            ..params.bake.clone()
        },
    )
    .expect("wgpu bake");
    let cpu = &cloud.baked;
    assert_eq!(
        (cpu.cells.clone(), cpu.uv_rects.clone()),
        (wgpu.cells.clone(), wgpu.uv_rects.clone())
    );
    let (a, b) = (quad_stats(cpu), quad_stats(&wgpu));
    let (mut worst_coverage, mut worst_colour) = (0.0f64, 0.0f64);
    let (mut total_a, mut total_b) = (0.0, 0.0);
    for (q, ((ca, ma), (cb, mb))) in a.iter().zip(&b).enumerate() {
        let cell = cpu.cells[q];
        let area = f64::from(cell.width * cell.height);
        total_a += ca * area;
        total_b += cb * area;
        worst_coverage = worst_coverage.max((ca - cb).abs());
        // Colour compared where both show at least a texel of foliage.
        if ca.min(*cb) * area >= 1.0 {
            for k in 0..3 {
                worst_colour = worst_colour.max((ma[k] - mb[k]).abs());
            }
        }
    }
    eprintln!(
        "{name} ε {epsilon}: {} quads, atlas {}x{}; coverage cpu {total_a:.0} wgpu {total_b:.0} \
         texels; worst quad coverage difference {worst_coverage:.4}, colour {worst_colour:.2}",
        cpu.cells.len(),
        cpu.atlas.width,
        cpu.atlas.height
    );
    assert!(
        worst_coverage <= COVERAGE_TOLERANCE,
        "{name}: a quad's coverage differs by {worst_coverage}"
    );
    assert!(
        worst_colour <= COLOUR_TOLERANCE,
        "{name}: a quad's mean colour differs by {worst_colour}"
    );
}

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("no renderer (CI has Mesa llvmpipe): {e}"))
}

#[test]
fn cpu_and_wgpu_bakes_agree_on_the_sample() {
    let r = renderer();
    for epsilon in [0.05, 0.01] {
        compare(&r, &root().join("samples/sapling.glb"), epsilon);
    }
}

#[test]
fn cpu_and_wgpu_bakes_agree_on_two_shared_trees() {
    let names = ["oak_medium.glb", "pine_medium_blender.glb"];
    frond_testdata::require_trees!(names);
    let r = renderer();
    for name in names {
        for epsilon in [0.05, 0.01] {
            compare(&r, &shared_tree(name), epsilon);
        }
    }
}
