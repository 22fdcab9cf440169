//! Bakes the textures of a billboard cloud: each quad's member triangles rendered
//! orthographically onto the quad, supersampled, downsampled in linear light, dilated into
//! their padding and packed into one colour atlas and one normal atlas.
//!
//! Spec: improved-billboard-cloud §4 (texture size from a uniform texel density, orthographic
//! projection focused on the rectangle with near/far from the members' depth range, 4x4
//! supersampling with filters that average only covered samples, one atlas with padding,
//! alpha test at 0.5 and background dilation, normal maps) and animated-billboard-clouds §2.4
//! "Texturing details" (camera aligned with the quad edges, view window = the quad, ambient
//! only, \[ENG\] texel density clamped per side, one atlas per cloud).
//!
//! How it is rendered: quads are first packed (see [`crate::atlas`]); every member triangle is
//! then transformed on the CPU into the supersampled atlas (the quad's rectangle maps onto its
//! texture's cell, depth runs from the quad's far to near member), clipped to its cell, and the
//! whole supersampled atlas is drawn with identity-matrix renders. By default the CPU bake
//! rasteriser ([`frond_render::BakeTarget`]) frames strips of whole atlas rows, a few
//! targets in all, and draws each cell's part of a strip alone from its own triangles, set
//! up as it is drawn, in parallel, colour and normals in one pass (the same atlas on every
//! machine);
//! [`BakeRasteriser::Wgpu`] draws square tiles through the wgpu renderer, a colour and a
//! normal pass each.

mod baked;
mod coverage;
mod cpu_raster;
mod finish;
mod job;
mod layout;
mod params;
mod placement;
mod texels;
mod wgpu_raster;

use frond_render::{DrawMaterial, DrawTexture, Renderer};
use rayon::prelude::*;

use crate::quad::Quad;
use crate::soup::TriangleSoup;

pub use baked::{Atlas, BakeError, BakedCloud, Cell};
pub use params::{BakeParams, BakeRasteriser, MAX_ATLAS_SIDE, MAX_SUPERSAMPLE};

use coverage::covered_fractions;
use coverage::preserve_coverage;
pub use coverage::{MAX_FORESHORTENING, foreshortening};
use cpu_raster::{BakeTextures, bake_textures, render_atlas_cpu};
use finish::finish_cells;
use job::{AtlasJob, two_sided};
use layout::{layout, uv_rect};
use params::validate_params;
use placement::{PlacedTriangle, quad_triangles};
use texels::{Downsampled, cutoff_samples};
use wgpu_raster::render_atlas_wgpu;

/// Bakes the cloud's textures: `members[q]` lists the `soup` triangles drawn on `quads[q]`,
/// with `materials` / `textures` indexed by [`TriangleSoup::material`].
///
/// Each quad gets `clamp(ceil(side * density), min_side, max_side)` texels per side (a quad
/// whose longest side would exceed `max_side` is scaled down as a whole, keeping its aspect
/// ratio); the density is lowered (x0.8 steps) until all textures fit one `max_atlas`² atlas,
/// never dropping a quad. Members are drawn double-sided, unlit, with their material's texture and
/// alpha test; colours are averaged over covered supersamples in linear light, normals
/// averaged and renormalised, then every uncovered texel of a quad's padded cell takes the
/// colour and normal of the nearest covered one. The output is deterministic.
/// Improved-billboard-cloud §4, animated-billboard-clouds §2.4.
pub fn bake_cloud(
    renderer: &Renderer,
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    quads: &[Quad],
    members: &[Vec<usize>],
    params: &BakeParams,
) -> Result<BakedCloud, BakeError> {
    let start = std::time::Instant::now();
    validate_params(params)?;
    validate_input(soup, materials, quads, members)?;
    let ss = params.supersample;
    // The CPU rasteriser's textures are prepared while the atlas is laid out (one texture's
    // mip chain is mostly one thread's work).
    let (placing, prepared) = rayon::join(
        || -> Result<_, BakeError> {
            let layout = layout(quads, params)?;
            let packed = start.elapsed();
            let cells: Vec<Cell> = (layout.sizes.iter().zip(&layout.packing.origins))
                .map(|(&(width, height), &(x, y))| Cell {
                    x,
                    y,
                    width,
                    height,
                })
                .collect();
            let placed_triangles: Vec<Vec<PlacedTriangle>> = quads
                .par_iter()
                .zip(members.par_iter())
                .zip(cells.par_iter())
                .map(|((quad, tris), cell)| quad_triangles(soup, quad, tris, cell, ss))
                .collect();
            Ok((layout, packed, cells, placed_triangles))
        },
        || match params.rasteriser {
            BakeRasteriser::Cpu => bake_textures(soup, materials, textures, members).map(Some),
            BakeRasteriser::Wgpu => Ok(None),
        },
    );
    let (layout, packed, cells, placed_triangles) = placing?;
    let prepared = prepared?;
    let packing = &layout.packing;
    let (width, height) = (packing.width, packing.height);
    let mut samples = Downsampled::new(width, height);
    let placed = start.elapsed();
    render_atlas(
        renderer,
        materials,
        textures,
        prepared.as_ref(),
        &placed_triangles,
        &cells,
        params,
        &mut samples,
    )?;
    let rendered = start.elapsed();
    let mut grown = Vec::new();
    if params.covered_fraction {
        let scales: Vec<f64> = quads
            .iter()
            .zip(members)
            .map(|(q, tris)| foreshortening(soup, q, tris) * params.coverage_gain)
            .collect();
        grown = covered_fractions(&mut samples, &cells, &scales, ss * ss);
    } else if params.preserve_coverage {
        let scales: Vec<f64> = quads
            .iter()
            .zip(members)
            .map(|(q, tris)| foreshortening(soup, q, tris) * params.coverage_gain)
            .collect();
        grown = preserve_coverage(
            &mut samples,
            &cells,
            &scales,
            ss * ss,
            cutoff_samples(params),
        )
        .into_iter()
        .map(|i| (i, 255))
        .collect();
    }

    let mut atlas = finish_cells(samples, &cells, quads, params.padding);
    atlas.blended = params.covered_fraction;
    // Grown texels cover what their cell lacks with the colour and normal dilation gave them.
    for (i, alpha) in grown {
        atlas.color[4 * i + 3] = alpha;
        atlas.normal[4 * i + 3] = alpha;
    }
    let uv_rects = cells.iter().map(|c| uv_rect(c, width, height)).collect();
    let texture_bytes = atlas.color.len() + atlas.normal.len();
    tracing::debug!(
        quads = quads.len(),
        width,
        height,
        density = layout.texels_per_unit,
        "baked: packing {:.3} s, placing {:.3} s, rendering {:.3} s, dilation {:.3} s",
        packed.as_secs_f64(),
        (placed - packed).as_secs_f64(),
        (rendered - placed).as_secs_f64(),
        (start.elapsed() - rendered).as_secs_f64(),
    );
    Ok(BakedCloud {
        atlas,
        uv_rects,
        cells,
        texels_per_unit: layout.texels_per_unit,
        density_reduced: layout.density_reduced,
        texture_bytes,
    })
}

fn validate_input(
    soup: &TriangleSoup,
    materials: &[DrawMaterial],
    quads: &[Quad],
    members: &[Vec<usize>],
) -> Result<(), BakeError> {
    let bad = |m: String| Err(BakeError::InvalidInput(m));
    let n = soup.positions.len();
    if soup.uvs.len() != n || soup.material.len() != n {
        return bad(format!(
            "soup has {n} triangles but {} uv triples and {} materials",
            soup.uvs.len(),
            soup.material.len()
        ));
    }
    if members.len() != quads.len() {
        return bad(format!(
            "{} member lists for {} quads",
            members.len(),
            quads.len()
        ));
    }
    for (q, quad) in quads.iter().enumerate() {
        let finite = quad.center.is_finite()
            && quad.axis_u.is_finite()
            && quad.axis_v.is_finite()
            && quad.half_size.is_finite();
        if !finite || quad.half_size.min_element() < 0.0 {
            return bad(format!("quad {q} is not finite or has a negative size"));
        }
    }
    for (q, list) in members.iter().enumerate() {
        for &t in list {
            if t >= n {
                return bad(format!(
                    "quad {q}: triangle {t} out of range ({n} triangles)"
                ));
            }
            let m = soup.material[t] as usize;
            if m >= materials.len() {
                return bad(format!(
                    "triangle {t}: material {m} out of range ({} materials)",
                    materials.len()
                ));
            }
            let finite = soup.positions[t].iter().all(|p| p.is_finite())
                && soup.uvs[t].iter().all(|uv| uv.is_finite());
            if !finite {
                return bad(format!("triangle {t} has a non-finite position or uv"));
            }
        }
    }
    Ok(())
}

/// Renders the supersampled atlas and downsamples it: with the CPU bake rasteriser where its
/// textures are `prepared` (`params` names it), through the wgpu renderer otherwise.
#[expect(
    clippy::too_many_arguments,
    reason = "the job's parts, kept apart from the rasteriser's"
)]
fn render_atlas(
    renderer: &Renderer,
    materials: &[DrawMaterial],
    textures: &[DrawTexture],
    prepared: Option<&BakeTextures>,
    placed_triangles: &[Vec<PlacedTriangle>],
    cells: &[Cell],
    params: &BakeParams,
    out: &mut Downsampled,
) -> Result<(), BakeError> {
    let job = AtlasJob {
        materials: materials.iter().map(two_sided).collect(),
        textures,
        placed_triangles,
        cells,
        params,
    };
    match prepared {
        Some(textures) => render_atlas_cpu(&job, textures, out),
        None => render_atlas_wgpu(renderer, &job, out),
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec2, Vec3};

    use super::finish::{
        STEP, TangentSpace, UNREACHED, chessboard_passes, chessboard_passes_in, mean_color,
        padded_rect,
    };
    use super::layout::texture_size;
    use super::placement::{ClipVertex, clip_to_unit_square};
    use super::texels::{coverage_alpha, round_byte};
    use super::*;

    /// A quad in the plane z = 0 facing +z, centred on the origin, `half_size` along x and y.
    fn flat_quad(half_size: Vec2) -> Quad {
        Quad {
            plane: crate::plane::Plane {
                normal: Vec3::Z,
                offset: 0.0,
            },
            center: Vec3::ZERO,
            axis_u: Vec3::X,
            axis_v: Vec3::Y,
            half_size,
        }
    }

    #[test]
    fn foreshortening_is_the_leaves_area_over_their_projection_onto_the_quad() {
        let quad = flat_quad(Vec2::splat(2.0));
        let tilted = |deg: f32| {
            let (s, c) = deg.to_radians().sin_cos();
            [Vec3::ZERO, Vec3::X, Vec3::new(0.0, c, s)]
        };
        let soup = TriangleSoup {
            positions: vec![tilted(0.0), tilted(60.0), tilted(89.9), tilted(180.0)],
            uvs: vec![[Vec2::ZERO; 3]; 4],
            material: vec![0; 4],
        };
        let f = |tris: &[usize]| foreshortening(&soup, &quad, tris);
        assert!(
            (f(&[0]) - 1.0).abs() < 1e-6,
            "a leaf in the plane keeps its coverage"
        );
        assert!((f(&[3]) - 1.0).abs() < 1e-6, "facing away counts alike");
        assert!(
            (f(&[1]) - 2.0).abs() < 1e-4,
            "60° off the plane: half its area projected"
        );
        assert!(
            (f(&[0, 1]) - 4.0 / 3.0).abs() < 1e-4,
            "area-weighted over the leaves"
        );
        assert_eq!(f(&[2]), coverage::MAX_FORESHORTENING, "edge-on: capped");
        assert_eq!(f(&[]), 1.0);
    }

    #[test]
    fn covered_fractions_keep_each_cells_scaled_coverage() {
        // A 8x8 cell whose texels are covered 4, 8 and 16 of 16 samples in turn (every third
        // texel uncovered): alpha is the covered fraction at scale 1; at scale 1.5 the full
        // texels saturate and the others grow until the cell's alpha sums to 1.5 times its
        // coverage; at scale 4 every covered texel is opaque and the rest grows beside them.
        let cells = [Cell {
            x: 0,
            y: 0,
            width: 8,
            height: 8,
        }];
        let fill = || {
            let mut d = Downsampled::new(8, 8);
            for (i, n) in d.samples.iter_mut().enumerate() {
                *n = [4, 8, 16, 0][i % 4];
            }
            d
        };
        let alpha_sum = |d: &Downsampled, grown: &[(usize, u8)]| -> f64 {
            let own: f64 = (d.color.chunks_exact(4)).map(|p| f64::from(p[3])).sum();
            (own + grown.iter().map(|&(_, a)| f64::from(a)).sum::<f64>()) / 255.0
        };
        let coverage: f64 = fill().samples.iter().map(|&n| f64::from(n) / 16.0).sum();
        for scale in [1.0, 1.5, 4.0] {
            let mut d = fill();
            let grown = covered_fractions(&mut d, &cells, &[scale], 16);
            let want = (scale * coverage).min(64.0);
            let got = alpha_sum(&d, &grown);
            assert!(
                (got - want).abs() <= 0.02 * want,
                "scale {scale}: {got} of {want}"
            );
            assert_eq!(grown.is_empty(), scale < 4.0, "scale {scale}");
            for (i, &n) in d.samples.iter().enumerate() {
                let a = d.color[i * 4 + 3];
                assert_eq!(a == 0, n == 0, "texel {i}");
                if scale == 1.0 {
                    assert_eq!(a, (f64::from(n) / 16.0 * 255.0).round() as u8);
                }
            }
        }
    }

    #[test]
    fn scaled_coverage_grows_beside_the_covered_texels() {
        // A 12x12 cell with a 4x4 block of fully covered texels in its middle: asked for twice
        // its coverage, it keeps the 16 and grows 16 more, each next to the block.
        let mut d = Downsampled::new(12, 12);
        let cells = [Cell {
            x: 0,
            y: 0,
            width: 12,
            height: 12,
        }];
        let covered = |x: usize, y: usize| (4..8).contains(&x) && (4..8).contains(&y);
        for y in 0..12usize {
            for x in 0..12usize {
                let i = y * 12 + x;
                if covered(x, y) {
                    d.samples[i] = 16;
                    d.color[i * 4 + 3] = 255;
                    d.normal[i * 4 + 3] = 255;
                }
            }
        }
        let grown = preserve_coverage(&mut d, &cells, &[2.0], 16, 8);
        assert_eq!(grown.len(), 16);
        for &i in &grown {
            let (x, y) = (i % 12, i / 12);
            assert!(!covered(x, y));
            assert!(
                (2..10).contains(&x) && (2..10).contains(&y),
                "({x}, {y}) beside the block"
            );
        }
        let mut again = Downsampled::new(12, 12);
        again.samples.clone_from(&d.samples);
        assert_eq!(
            preserve_coverage(&mut again, &cells, &[2.0], 16, 8),
            grown,
            "the same texels every time"
        );
        // At its own coverage nothing grows.
        assert!(preserve_coverage(&mut d, &cells, &[1.0], 16, 8).is_empty());
    }

    #[test]
    fn preserved_coverage_passes_as_many_texels_as_are_covered() {
        // A 10x10 cell of texels each a quarter covered (4 of 16 samples), plus a 4x4 cell
        // fully covered: the 0.5 test keeps none of the first; preserving coverage keeps 25.
        let mut d = Downsampled::new(16, 12);
        let cells = [
            Cell {
                x: 0,
                y: 0,
                width: 10,
                height: 10,
            },
            Cell {
                x: 12,
                y: 0,
                width: 4,
                height: 4,
            },
        ];
        for y in 0..12usize {
            for x in 0..16usize {
                let i = y * 16 + x;
                let n: u16 = if x < 10 && y < 10 {
                    // Slightly different counts so the threshold falls between texels.
                    4 + ((x + y) % 2) as u16
                } else if x >= 12 && y < 4 {
                    16
                } else {
                    0
                };
                d.samples[i] = n;
                let a = coverage_alpha(u32::from(n), 16, 8);
                d.color[i * 4 + 3] = a;
                d.normal[i * 4 + 3] = a;
            }
        }
        let passing = |d: &Downsampled, c: &Cell| {
            (c.y..c.y + c.height)
                .flat_map(|y| (c.x..c.x + c.width).map(move |x| (y * 16 + x) as usize))
                .filter(|&i| d.color[i * 4 + 3] >= 128)
                .count()
        };
        assert_eq!(passing(&d, &cells[0]), 0);
        preserve_coverage(&mut d, &cells, &vec![1.0; cells.len()], 16, 8);
        // Σ n / 16 = (50·4 + 50·5) / 16 = 28.1 → 28 texels; ties at 5 samples: 50 have 5.
        // The threshold is the 28th largest count (5), so all 50 five-sample texels pass:
        // the closest achievable count with per-texel thresholds.
        let kept = passing(&d, &cells[0]);
        assert!((28..=50).contains(&kept), "{kept}");
        assert_eq!(passing(&d, &cells[1]), 16, "full cells stay full");
        for i in 0..d.samples.len() {
            let a = d.color[i * 4 + 3];
            assert_eq!(a, d.normal[i * 4 + 3]);
            assert!(a == 0 || a == 255, "binary alpha, got {a}");
            if d.samples[i] == 0 {
                assert_eq!(a, 0);
            }
        }
    }

    #[test]
    fn dilation_copies_a_nearest_covered_texel_of_the_cell() {
        // Three cells side by side and one below (two bands of rows), padding 2, a few
        // scattered covered texels each with its own colour; the third cell has none.
        let (w, h) = (40, 30);
        let cells = [(2, 2, 8, 9), (14, 2, 9, 6), (27, 2, 6, 6), (2, 17, 12, 10)].map(
            |(x, y, width, height)| Cell {
                x,
                y,
                width,
                height,
            },
        );
        let quad = flat_quad(Vec2::ONE);
        let mut d = Downsampled::new(w, h);
        let covered = [
            (3, 4),
            (8, 10),
            (5, 5),
            (20, 3),
            (14, 7),
            (2, 26),
            (13, 17),
            (7, 21),
        ];
        for (k, &(x, y)) in covered.iter().enumerate() {
            let i = (y * w + x) as usize;
            d.samples[i] = 16;
            d.color[i * 4..i * 4 + 4].copy_from_slice(&[10 + k as u8 * 20, 7, 9, 255]);
            d.normal[i * 4..i * 4 + 4].copy_from_slice(&[128, 128, 255, 255]);
        }
        let counts = d.samples.clone();
        let atlas = finish_cells(d, &cells, &[quad; 4], 2);
        for (c, cell) in cells.iter().enumerate() {
            let [x0, x1, y0, y1] = padded_rect(cell, 2, w, h);
            let own: Vec<(usize, usize)> = (covered.iter())
                .map(|&(x, y)| (x as usize, y as usize))
                .filter(|&(x, y)| (x0..x1).contains(&x) && (y0..y1).contains(&y))
                .collect();
            for y in y0..y1 {
                for x in x0..x1 {
                    let i = y * w as usize + x;
                    let texel = &atlas.color[i * 4..i * 4 + 4];
                    if own.is_empty() {
                        // No covered texel: the mean covered colour, the quad's own normal,
                        // alpha 0.
                        let mean = mean_color(&atlas.color, &counts);
                        assert_eq!(texel, &[mean[0], mean[1], mean[2], 0], "cell {c} ({x},{y})");
                        assert_eq!(&atlas.normal[i * 4..i * 4 + 3], &[128, 128, 255]);
                        continue;
                    }
                    let distance = |&(sx, sy): &(usize, usize)| sx.abs_diff(x).max(sy.abs_diff(y));
                    let nearest = own.iter().map(distance).min().expect("own texels");
                    let source = (own.iter())
                        .find(|&&(sx, sy)| atlas.color[(sy * w as usize + sx) * 4] == texel[0]);
                    let source = source.unwrap_or_else(|| panic!("cell {c} ({x},{y}) {texel:?}"));
                    assert_eq!(distance(source), nearest, "cell {c} ({x},{y})");
                    assert_eq!(&atlas.normal[i * 4..i * 4 + 3], &[128, 128, 255]);
                }
            }
        }
    }

    #[test]
    fn chessboard_passes_find_the_nearest_source_first_in_row_order() {
        // Random grids (a ring of unreached entries around each), a few sources each, some
        // sharing distances: every entry is the least (distance, source) of a brute-force
        // search, through the dispatched passes and the plain ones alike.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        for _ in 0..40 {
            let (w, h) = (1 + next(19) as usize, 1 + next(13) as usize);
            let gw = w + 2;
            let mut grid = vec![UNREACHED; gw * (h + 2)];
            let sources: Vec<(usize, usize)> = (0..1 + next(4))
                .map(|_| (next(w as u64) as usize, next(h as u64) as usize))
                .collect();
            for &(x, y) in &sources {
                grid[(y + 1) * gw + x + 1] = (y * w + x) as u64;
            }
            let mut plain = grid.clone();
            chessboard_passes(&mut grid, gw);
            chessboard_passes_in(&mut plain, gw);
            assert_eq!(grid, plain);
            for y in 0..h {
                for x in 0..w {
                    let want = (sources.iter())
                        .map(|&(sx, sy)| {
                            let d = sx.abs_diff(x).max(sy.abs_diff(y)) as u64;
                            d * STEP + (sy * w + sx) as u64
                        })
                        .min();
                    assert_eq!(Some(grid[(y + 1) * gw + x + 1]), want, "({x},{y}) {w}×{h}");
                }
            }
        }
    }

    #[test]
    fn byte_rounding_matches_the_library_round() {
        let mut values = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.0, 1e-30];
        for k in -4..=520 {
            let half = k as f32 * 0.5;
            values.extend([half, half.next_down(), half.next_up()]);
        }
        values.extend((0..100_000).map(|k| k as f32 * 0.002_7 - 3.0));
        for v in values {
            let want = v.round().clamp(0.0, 255.0) as u8;
            assert_eq!(round_byte(v), want, "{v:?}");
        }
    }

    #[test]
    fn remembered_conversions_are_the_fresh_ones() {
        // More normals than slots, in an order that revisits them: each conversion equals a
        // fresh frame's.
        let quad = Quad {
            axis_u: Vec3::new(0.6, 0.0, 0.8),
            axis_v: Vec3::Y,
            ..flat_quad(Vec2::ONE)
        };
        let mut remembered = TangentSpace::of(&quad);
        for k in 0..2000u32 {
            let j = k * 7919 % 97;
            let n = [
                (j * 37 % 256) as u8,
                (j * 11 % 256) as u8,
                (j * 5 % 256) as u8,
            ];
            let n = if j == 3 { [0, 0, 0] } else { n };
            assert_eq!(
                remembered.convert(n),
                TangentSpace::of(&quad).convert(n),
                "{n:?}"
            );
        }
    }

    #[test]
    fn resolved_cells_keep_their_graded_alpha() {
        // An 8×8 cell of sparse foliage, every texel 4 to 7 of 16 covered: the plain test
        // passes none of the 22 texels of coverage; re-thresholded, the cell keeps about them
        // (ties at the threshold pass together: the 7s and 6s, 32), with binary alpha.
        let cell = Cell {
            x: 0,
            y: 0,
            width: 8,
            height: 8,
        };
        let fill = |count: &dyn Fn(usize, usize) -> u16| {
            let mut d = Downsampled::new(8, 8);
            for y in 0..8 {
                for x in 0..8 {
                    let i = y * 8 + x;
                    let n = count(x, y);
                    d.samples[i] = n;
                    let a = coverage_alpha(u32::from(n), 16, 8);
                    d.color[i * 4 + 3] = a;
                    d.normal[i * 4 + 3] = a;
                }
            }
            d
        };
        let passing = |d: &Downsampled| (0..64).filter(|&i| d.color[i * 4 + 3] >= 128).count();
        let sparse = |x: usize, y: usize| 4 + ((x + 8 * y) % 4) as u16;
        let mut d = fill(&sparse);
        assert_eq!(passing(&d), 0);
        preserve_coverage(&mut d, std::slice::from_ref(&cell), &[1.0], 16, 8);
        assert_eq!(passing(&d), 32);
        assert!(d.color.chunks(4).all(|p| p[3] == 0 || p[3] == 255));
        // A leaf over three full columns and an edge column at 15/16: 32 texels pass for a
        // coverage of 31.5 (1.6 % off): the leaf is resolved, and the cell is left exactly as
        // baked, graded alpha and all.
        let leaf = |x: usize, _: usize| match x {
            0..=2 => 16,
            3 => 15,
            _ => 0,
        };
        let mut d = fill(&leaf);
        preserve_coverage(&mut d, std::slice::from_ref(&cell), &[1.0], 16, 8);
        assert_eq!(d.color, fill(&leaf).color);
        assert!(d.color.chunks(4).any(|p| p[3] > 128 && p[3] < 255));
    }

    #[test]
    fn preserved_coverage_carries_remainders_across_cells() {
        // 40 one-texel cells each 5/16 covered: rounding each alone keeps none; carrying the
        // remainder keeps round(40 · 5/16) = 12 or 13 of them.
        let mut d = Downsampled::new(40, 1);
        let cells: Vec<Cell> = (0..40)
            .map(|x| Cell {
                x,
                y: 0,
                width: 1,
                height: 1,
            })
            .collect();
        for i in 0..40 {
            d.samples[i] = 5;
        }
        preserve_coverage(&mut d, &cells, &vec![1.0; cells.len()], 16, 8);
        let kept = (0..40).filter(|&i| d.color[i * 4 + 3] >= 128).count();
        assert!((12..=13).contains(&kept), "{kept}");
    }

    #[test]
    fn alpha_is_128_exactly_at_the_cutoff() {
        for total in [1u32, 4, 9, 16, 25, 256] {
            for cutoff in [0.25f64, 0.5, 0.75, 1.0] {
                let needed = (0..=total)
                    .find(|&n| f64::from(n) >= cutoff * f64::from(total))
                    .unwrap_or(total);
                let mut last = 0;
                for n in 0..=total {
                    let a = coverage_alpha(n, total, needed);
                    assert_eq!(a >= 128, f64::from(n) >= cutoff * f64::from(total));
                    assert_eq!(a == 0, n == 0);
                    assert!(a >= last);
                    last = a;
                }
                assert_eq!(coverage_alpha(total, total, needed), 255);
            }
        }
    }

    #[test]
    fn clipping_keeps_the_part_inside_the_square() {
        let mut poly: Vec<ClipVertex> = vec![
            [-1.0, 0.5, 0.0, 0.0, 0.0],
            [2.0, 0.5, 3.0, 1.0, 0.0],
            [0.5, 2.0, 0.0, 0.0, 1.0],
        ];
        let mut scratch = Vec::new();
        clip_to_unit_square(&mut poly, &mut scratch);
        assert!(poly.len() >= 3);
        for p in &poly {
            assert!(
                (0.0..=1.0).contains(&p[0]) && (0.0..=1.0).contains(&p[1]),
                "{p:?}"
            );
            // Attributes stay affine: d = s + 1 - ... along the bottom edge (t = 0.5).
        }
        // Signed area keeps its (counter-clockwise) sign.
        let area: f32 = (0..poly.len())
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        assert!(area > 0.0);
    }

    #[test]
    fn texture_sizes_follow_density_and_clamps() {
        let quad = flat_quad(Vec2::new(1.0, 0.25));
        let p = BakeParams::default();
        assert_eq!(texture_size(&quad, 10.0, &p), (20, 5));
        assert_eq!(texture_size(&quad, 1.0, &p), (4, 4));
        assert_eq!(texture_size(&quad, 1000.0, &p), (1024, 256));
    }
}
