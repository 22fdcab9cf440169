//! Bake speed: oak_dense.glb's foliage (116,160 leaf triangles, average pose) cut
//! into billboards at ε = 1 % and 5 % of the diagonal, then baked by the CPU bake rasteriser
//! (the default) and by the wgpu renderer (on llvmpipe where there is no GPU), 4×4
//! supersampled, at two texel densities: 1024 texels across the diagonal (as `frond cloud`)
//! and the 600 px LOD's density (`frond lod --method per-bone --lods 600`: 2.4 texels per
//! screen pixel at 600 px, 4 across the diagonal's unit). Medians of 3. oak_dense is a shared
//! tree (`FROND_TEST_TREES`); without it the bench says so and ends.

use std::time::Instant;

use frond_billboard::plane_search::{SearchParams, search_planes};
use frond_billboard::{BakeParams, BakeRasteriser, TriangleSoup, bake_cloud};
use frond_render::{Renderer, TreeParts, scene_from_positions};
use frond_scene::{ImportOptions, SampleOptions, import, sample};

fn main() {
    let Some(path) = frond_testdata::tree("oak_dense.glb") else {
        frond_testdata::report_skip("bake oak_dense", &["oak_dense.glb".to_string()]);
        return;
    };
    let renderer = Renderer::new().expect("a renderer (Mesa llvmpipe at least)");
    let tree = import(&path, &ImportOptions::default()).expect("oak_dense imports");
    let s = sample(&tree, &SampleOptions::default()).expect("samples");
    let soup = TriangleSoup::from_tree(&tree, &s.average, &s.foliage);
    let scene = scene_from_positions(&tree, &s.average, None, TreeParts::Foliage);
    let diag = tree.bounds.diagonal();
    for frac in [0.05, 0.01] {
        let search = search_planes(
            &soup,
            &SearchParams {
                epsilon: frac * diag,
                candidates: 500,
                seed: 1,
                ..Default::default()
            },
            diag,
        );
        let quads: Vec<_> = search
            .clusters
            .iter()
            .map(|c| frond_billboard::cloud::fit_quad(&soup, &c.plane, &c.triangles))
            .collect();
        let members: Vec<Vec<usize>> = search
            .clusters
            .iter()
            .map(|c| c.triangles.clone())
            .collect();
        for (label, density) in [("1024/diagonal", 1024.0 / diag), ("600 px LOD", 4.0)] {
            for rasteriser in [BakeRasteriser::Cpu, BakeRasteriser::Wgpu] {
                let params = BakeParams {
                    texels_per_unit: density,
                    rasteriser,
                    ..Default::default()
                };
                let mut times = Vec::new();
                let mut atlas = (0, 0);
                for _ in 0..3 {
                    let t0 = Instant::now();
                    let baked = bake_cloud(
                        &renderer,
                        &soup,
                        &scene.materials,
                        &scene.textures,
                        &quads,
                        &members,
                        &params,
                    )
                    .expect("bakes");
                    times.push(t0.elapsed().as_secs_f64());
                    atlas = (baked.atlas.width, baked.atlas.height);
                }
                times.sort_by(f64::total_cmp);
                println!(
                    "oak_dense eps {:.0}%, {} quads, {label} ({}x{} atlas), {rasteriser:?}: {:.3} s",
                    frac * 100.0,
                    quads.len(),
                    atlas.0,
                    atlas.1,
                    times[1]
                );
            }
        }
    }
}
