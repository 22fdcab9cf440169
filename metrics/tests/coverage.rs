//! The coverage metric (spec animated-billboard-clouds §5.4, filtered: docs/metrics.md, "The
//! coverage error") on real renders, each case with a known answer on covered fractions.
//! Small screen heights and few samples per pixel keep the renders fast.
//!
//! All tests share one `Renderer` and fail (never skip) when no adapter exists: CI machines
//! have Mesa llvmpipe. Every known answer is checked on the CPU rasteriser (the metric's
//! default) and, through [`run`], against the wgpu path's sample counts.

mod common;

use std::sync::OnceLock;

use common::{load, without_every_second_card};

use frond_metrics::eval::{EvalContext, EvalRequest};
use frond_metrics::{
    CoverageParams, CoverageReport, MetricError, Rasteriser, compare_images, coverage_error,
    coverage_images, framing, ring_azimuth_deg,
};
use frond_render::{
    DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture, Renderer, SoftwareTextures,
    render_coverage,
};
use frond_scene::{InputLimits, Part};
use glam::Vec3;

/// Samples per pixel side of most cases: enough for sub-pixel answers, few enough for the
/// wgpu path's `K`-times-larger renders to stay small.
const K: u32 = 8;

fn renderer() -> &'static Renderer {
    static RENDERER: OnceLock<Renderer> = OnceLock::new();
    RENDERER.get_or_init(|| match Renderer::new() {
        Ok(r) => {
            eprintln!("adapter: {}", r.adapter_info());
            r
        }
        Err(e) => panic!("no renderer (CI machines have Mesa llvmpipe): {e}"),
    })
}

/// `views` on the ground ring alone, `frames` frames, the tree `screen_height` pixels tall,
/// `K` samples per pixel side, drawn by the CPU rasteriser.
fn params(views: u32, frames: u32, screen_height: f32) -> CoverageParams {
    CoverageParams {
        views,
        frames,
        elevations_deg: vec![0.0],
        screen_height,
        samples_per_side: Some(K),
        ..Default::default()
    }
}

/// A rectangle centred at `center`, spanned by unit `right` (half width `hw`) and +Y (half
/// height `hh`), counter-clockwise seen from `right × Y`.
fn card(center: Vec3, right: Vec3, hw: f32, hh: f32) -> Vec<[f32; 3]> {
    let (r, u) = (right * hw, Vec3::Y * hh);
    [
        center - r - u,
        center + r - u,
        center + r + u,
        center - r + u,
    ]
    .map(|p| p.to_array())
    .to_vec()
}

/// A scene of cards (4 positions each); single-sided cards are visible only from the side
/// their counter-clockwise winding faces.
fn scene(cards: &[Vec<[f32; 3]>], double_sided: bool) -> DrawScene {
    DrawScene {
        meshes: cards
            .iter()
            .map(|positions| DrawMesh {
                positions: positions.clone(),
                indices: vec![0, 1, 2, 0, 2, 3],
                ..Default::default()
            })
            .collect(),
        materials: vec![DrawMaterial {
            double_sided,
            ..DrawMaterial::opaque([0.2, 0.6, 0.2, 1.0])
        }],
        textures: vec![],
    }
}

/// Twelve double-sided leaf cards of varied orientation, a small "tree" fitting in ±1.
fn tree() -> DrawScene {
    let cards: Vec<Vec<[f32; 3]>> = (0..12)
        .map(|i| {
            let t = i as f32;
            let center = Vec3::new(
                (t * 2.1).sin() * 0.7,
                (t * 0.37).cos() * 0.8,
                (t * 1.3).cos() * 0.7,
            );
            let right = Vec3::new((t * 0.9).cos(), 0.0, (t * 0.9).sin());
            card(center, right, 0.25, 0.15)
        })
        .collect();
    scene(&cards, true)
}

/// The CPU report of `simplified` against `original`, after checking that the wgpu path
/// (its own rasterisation, `K × K` pixels a pixel) counts nearly the same: per pair, the
/// original's covered area and the area covered by one model only agree to within a pixel
/// and 2 % (the two differ along the cards' edges only).
fn run(
    original: &[DrawScene],
    simplified: &[DrawScene],
    min: Vec3,
    max: Vec3,
    p: &CoverageParams,
) -> CoverageReport {
    let report = coverage_error(renderer(), original, simplified, min, max, p)
        .unwrap_or_else(|e| panic!("coverage_error failed: {e}"));
    let gpu = CoverageParams {
        rasteriser: Rasteriser::Gpu,
        ..p.clone()
    };
    let other = coverage_error(renderer(), original, simplified, min, max, &gpu)
        .unwrap_or_else(|e| panic!("coverage_error (GPU) failed: {e}"));
    let differing = |r: &CoverageReport| -> Vec<f64> {
        (r.per_pair.iter().zip(&r.original_coverage))
            .map(|(score, area)| score * area)
            .collect()
    };
    for (areas, gpu_areas) in [
        (
            report.original_coverage.clone(),
            other.original_coverage.clone(),
        ),
        (differing(&report), differing(&other)),
    ] {
        for (a, b) in areas.iter().zip(&gpu_areas) {
            assert!(
                (a - b).abs() <= 1.0 + 0.02 * a.max(*b),
                "CPU {a} vs GPU {b} pixels"
            );
        }
    }
    report
}

fn bounds(s: &DrawScene) -> (Vec3, Vec3) {
    s.bounds().unwrap_or_else(|| panic!("scene has no bounds"))
}

#[test]
fn identical_scenes_score_exactly_zero() {
    let t = tree();
    let (min, max) = bounds(&t);
    let one = std::slice::from_ref(&t);
    // Both rings: 5 views each.
    let p = CoverageParams {
        elevations_deg: vec![0.0, 30.0],
        ..params(5, 1, 40.0)
    };
    let r = run(one, one, min, max, &p);
    assert_eq!(r.per_view, vec![0.0; 10]);
    assert_eq!(r.mean, 0.0);
    assert_eq!(r.ratio, 1.0);
    assert_eq!(r.ratio_per_pair, vec![1.0; 10]);
    assert_eq!(r.binary.mean, 0.0);
    assert_eq!(r.binary.discarded, 0);
    assert_eq!(r.binary.differing_pixels, vec![0; 10]);
    assert!(r.original_coverage.iter().all(|&a| a > 50.0), "{r:?}");
    assert_eq!(r.colour_difference, 0.0);
}

#[test]
fn empty_simplification_scores_exactly_one() {
    let t = tree();
    let (min, max) = bounds(&t);
    let r = run(&[t], &[DrawScene::default()], min, max, &params(5, 1, 40.0));
    assert_eq!(r.per_view, vec![1.0; 5]);
    assert_eq!(r.mean, 1.0);
    assert_eq!(r.ratio, 0.0, "nothing covered by the simplification");
    // Nothing discarded, by either rule.
    assert_eq!(r.binary.discarded, 0);
    assert_eq!(r.binary.mean, 1.0);
    assert_eq!(r.binary.differing_pixels, r.binary.original_pixels);
    // No shared coverage: no colour to compare.
    assert!(r.colour_difference.is_nan() && r.colour_per_pair.iter().all(|c| c.is_nan()));
}

#[test]
fn a_bloated_simplification_scores_above_one_and_is_kept() {
    // The tree's bounds are ±4, the original a small card at the centre: a huge triangle
    // covering the whole image adds far more than the original covers. It covers every
    // sample, so `|α_o − α_s| = α_s − α_o` everywhere: the error is the ratio less 1, and the
    // ratio is the image's area over the original's.
    let (min, max) = (Vec3::splat(-4.0), Vec3::splat(4.0));
    let small = scene(&[card(Vec3::ZERO, Vec3::X, 0.5, 0.5)], true);
    let mut huge = scene(&[card(Vec3::ZERO, Vec3::X, 0.5, 0.5)], true);
    huge.meshes[0] = DrawMesh {
        positions: vec![
            [-50.0, -50.0, 0.0],
            [100.0, -50.0, 0.0],
            [-50.0, 100.0, 0.0],
        ],
        indices: vec![0, 1, 2],
        ..Default::default()
    };
    let p = params(1, 1, 40.0);
    let f = framing(min, max, &p).expect("framing");
    let image = f64::from(f.width * f.height);
    let r = run(
        std::slice::from_ref(&small),
        std::slice::from_ref(&huge),
        min,
        max,
        &p,
    );
    let area = r.original_coverage[0];
    assert!(area > 0.0 && area < image / 10.0, "{r:?}");
    assert!((r.ratio - image / area).abs() < 1e-9 * r.ratio, "{r:?}");
    assert!((r.mean - (r.ratio - 1.0)).abs() < 1e-9 * r.ratio, "{r:?}");
    assert!(r.mean > 1.0);
    // The binary rule discards it.
    assert_eq!(r.binary.discarded, 1);
    assert!(r.binary.mean.is_nan(), "{r:?}");

    // Two frames: frame 0 is perfect, frame 1 bloated; both count.
    let r2 = run(
        &[small.clone(), small.clone()],
        &[small, huge],
        min,
        max,
        &params(1, 2, 40.0),
    );
    assert_eq!(r2.per_pair[0], 0.0);
    assert_eq!(r2.per_pair[1], r.mean);
    assert_eq!(r2.per_view, vec![r.mean / 2.0]);
    assert_eq!(r2.binary.discarded, 1);
    assert_eq!(r2.binary.mean, 0.0, "frame 0 alone is kept");
}

#[test]
fn an_empty_original_covers_nothing() {
    let t = tree();
    let (min, max) = bounds(&t);
    let e = coverage_error(
        renderer(),
        &[DrawScene::default()],
        &[t],
        min,
        max,
        &params(3, 1, 40.0),
    );
    assert!(
        matches!(e, Err(MetricError::NothingCovered { view: 0, frame: 0 })),
        "{e:?}"
    );
}

/// A 1×2 card facing the single view, its height the tree's: 48 pixels tall, 24 wide. Shifting
/// it by `s` world units sideways leaves two strips of `s` pixels per unit times its height
/// covered by one card only.
#[test]
fn a_shifted_card_scores_analytically() {
    let (hw, hh) = (0.5f32, 1.0f32);
    let original = scene(&[card(Vec3::ZERO, Vec3::X, hw, hh)], false);
    // Wider than the card, so the shifted ones stay in the image; its height is the card's.
    let (min, max) = (Vec3::new(-1.5, -hh, -0.1), Vec3::new(1.5, hh, 0.1));
    let p = params(1, 1, 48.0);
    let f = framing(min, max, &p).expect("framing");
    // The card stands at the target, `distance` from the eye: `focal / distance` pixels a unit.
    let px = f64::from(f.focal / f.distance);
    let (w_px, h_px) = (2.0 * f64::from(hw) * px, 2.0 * f64::from(hh) * px);
    assert!((h_px - 48.0).abs() < 1e-3, "{h_px}");
    let k = f64::from(K);
    for shift in [0.5f32, 0.25, 0.125, 0.3] {
        let shifted = scene(&[card(Vec3::new(shift, 0.0, 0.0), Vec3::X, hw, hh)], false);
        let r = run(std::slice::from_ref(&original), &[shifted], min, max, &p);
        let s_px = f64::from(shift) * px;
        let (area, differing) = (w_px * h_px, 2.0 * s_px * h_px);
        let expected = differing / area;
        // Each edge of length L pixels is sampled on L·K rows (or columns) of samples, each
        // off by at most one sample of 1/K² pixels: L/K pixels an edge. The original has its
        // four edges; the strips the four vertical ones and the cards' shared top and bottom
        // over 2·s pixels each.
        let err_area = 2.0 * (w_px + h_px) / k;
        let err_differing = (4.0 * h_px + 4.0 * s_px) / k;
        let tolerance = (err_differing + expected * err_area) / (area - err_area);
        eprintln!(
            "shift {shift}: area {:.2} (exact {area:.2}), score {:.5} (exact {expected:.5} ± \
             {tolerance:.5})",
            r.original_coverage[0], r.mean
        );
        assert!((r.original_coverage[0] - area).abs() <= err_area, "{r:?}");
        assert!(
            (r.mean - expected).abs() <= tolerance,
            "shift {shift}: {} vs {expected} ± {tolerance}",
            r.mean
        );
        // The same area, moved: the ratio is 1 but for the edges.
        assert!((r.ratio - 1.0).abs() <= 2.0 * err_area / (area - err_area));
        assert_eq!(r.binary.discarded, 0);
    }
}

#[test]
fn frames_are_averaged_per_view() {
    let t = tree();
    let (min, max) = bounds(&t);
    let r = run(
        &[t.clone(), t.clone()],
        &[t, DrawScene::default()],
        min,
        max,
        &params(3, 2, 40.0),
    );
    assert_eq!(r.per_view, vec![0.5; 3]);
    assert_eq!(r.mean, 0.5);
    assert_eq!(r.ratio, 0.5);
    // View-major: frame 1 of every view misses everything the original covers.
    assert_eq!(r.per_pair, [0.0, 1.0].repeat(3));
    assert_eq!(r.ratio_per_pair, [1.0, 0.0].repeat(3));
    assert_eq!(r.original_coverage.len(), 6);
    for d in 0..3 {
        assert_eq!(r.binary.differing_pixels[2 * d], 0);
        assert_eq!(
            r.binary.differing_pixels[2 * d + 1],
            r.binary.original_pixels[2 * d + 1]
        );
    }
}

/// The tree's rest height spans `H` pixels: projected with the framing's cameras, the top and
/// bottom of the bounds above and below their centre are `H` rows apart, and a card as tall as
/// the bounds, at their centre, covers `H` pixels down its middle column.
#[test]
fn the_framing_puts_the_rest_height_at_h_pixels() {
    let (min, max) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 3.0, 1.0));
    let centre = (min + max) * 0.5;
    let pole = scene(&[card(centre, Vec3::X, 0.5, (max.y - min.y) / 2.0)], false);
    for h in [20.0f32, 48.0, 600.0] {
        let p = params(1, 1, h);
        let f = framing(min, max, &p).expect("framing");
        // The switch values' distance: the rest height at H pixels of a 1080-pixel screen
        // of 60°, from 3 bounding radii on.
        let d = 3.0 * 1080.0 / (2.0 * 30f32.to_radians().tan() * h);
        let d = d.max(3.0 * (max - min).length() * 0.5);
        assert!((f.distance - d).abs() < 1e-4 * d, "{h}: {}", f.distance);
        assert!(
            f.height as f32 >= 1.2 * h,
            "{h}: the image holds the sway margin"
        );
        let camera = &f.cameras[0];
        let m = camera.view_proj(f.aspect());
        let row = |p: Vec3| {
            let c = m * p.extend(1.0);
            (1.0 - c.y / c.w) * 0.5 * f.height as f32
        };
        let (top, bottom) = (row(centre.with_y(max.y)), row(centre.with_y(min.y)));
        assert!((bottom - top - h).abs() < 1e-3 * h, "{h}: {top}..{bottom}");
        assert!((top + bottom - f.height as f32).abs() < 1e-2, "centred");
        if h > 100.0 {
            // Enough of the projection; 600 pixels of K² samples is a slow render.
            continue;
        }
        let images =
            coverage_images(renderer(), std::slice::from_ref(&pole), min, max, &p).expect("images");
        let alpha = images.fractions(0);
        let (w, x) = (images.width as usize, images.width as usize / 2);
        let column: f32 = (0..images.height as usize).map(|y| alpha[y * w + x]).sum();
        // Two edges cross the column, each off by at most one sample of each of K columns.
        assert!((column - h).abs() <= 2.0 / K as f32, "{h}: {column} pixels");
    }
}

/// A single-sided marker card facing outward at azimuth 72°·k (the ring's `k`-th azimuth) is
/// seen head-on by view k of the ground ring, and from above by view k of the 30° ring: there
/// it differs most, by its analytic area on the ground ring; views k ± 1 see it obliquely and
/// the two views behind it not at all. The original (a card above the markers, never
/// overlapping them on screen) covers what the CPU rasteriser draws from the framing's
/// cameras, in the metric's order: ring by ring, azimuth 360·d/D.
#[test]
fn views_go_ring_by_ring_at_even_azimuths() {
    let views = 5u32;
    let p = CoverageParams {
        elevations_deg: vec![0.0, 30.0],
        ..params(views, 1, 48.0)
    };
    let (min, max) = (Vec3::splat(-2.0), Vec3::splat(2.0));
    let (radius, hw, hh) = (1.5f32, 0.5f32, 0.4f32);
    let top = card(Vec3::new(0.0, 1.5, 0.0), Vec3::X, 0.5, 0.4);
    let original = scene(std::slice::from_ref(&top), true);
    let f = framing(min, max, &p).expect("framing");
    assert_eq!(f.cameras.len(), 10);
    for (i, camera) in f.cameras.iter().enumerate() {
        let (ring, d) = (i / views as usize, i as u32 % views);
        assert_eq!(camera.elevation_deg, [0.0, 30.0][ring], "view {i}");
        assert_eq!(
            camera.azimuth_deg,
            360.0 * d as f32 / views as f32,
            "view {i}"
        );
        assert_eq!(camera.azimuth_deg, ring_azimuth_deg(d, views));
    }
    // The original's renders from the framing's cameras, one by one.
    let textures = SoftwareTextures::new(&original, false).expect("textures");
    let manual: Vec<f64> = (f.cameras.iter())
        .map(|camera| {
            let (lo, hi) = bounds(&original);
            let m = camera.view_proj_for_bounds(f.aspect(), lo, hi);
            let image =
                render_coverage(&original, &textures, m, f.width, f.height, K).expect("render");
            image.samples.iter().map(|&n| f64::from(n)).sum::<f64>() / f64::from(K * K)
        })
        .collect();
    for k in 0..views {
        let theta = ring_azimuth_deg(k, views).to_radians();
        let normal = Vec3::new(theta.sin(), 0.0, theta.cos());
        let right = Vec3::new(theta.cos(), 0.0, -theta.sin());
        let marker = card(normal * radius - Vec3::Y * 1.5, right, hw, hh);
        // The top card stays double-sided; only the single-sided marker can differ.
        let mut simplified = scene(&[top.clone(), marker], true);
        simplified.materials.push(DrawMaterial {
            double_sided: false,
            ..simplified.materials[0].clone()
        });
        simplified.meshes[1].material = 1;
        let r = run(
            std::slice::from_ref(&original),
            std::slice::from_ref(&simplified),
            min,
            max,
            &p,
        );
        assert_eq!(r.original_coverage, manual, "k {k}");
        let diff: Vec<f64> = (r.per_pair.iter().zip(&r.original_coverage))
            .map(|(s, a)| s * a)
            .collect();
        for ring in 0..2 {
            let at = |offset: u32| diff[ring * views as usize + ((k + offset) % views) as usize];
            assert!(
                at(0) > 3.0 * at(1) && at(0) > 3.0 * at(4) && at(1) > 0.0 && at(4) > 0.0,
                "k {k}, ring {ring}: {diff:?}"
            );
            assert_eq!((at(2), at(3)), (0.0, 0.0), "k {k}, ring {ring}: {diff:?}");
        }
        // Head-on from the ground ring: a rectangle at depth distance − radius.
        let px = f64::from(f.focal / (f.distance - radius));
        let (w_px, h_px) = (2.0 * f64::from(hw) * px, 2.0 * f64::from(hh) * px);
        let slack = 2.0 * (w_px + h_px) / f64::from(K);
        let head_on = diff[k as usize];
        assert!(
            (head_on - w_px * h_px).abs() <= slack,
            "k {k}: {head_on} pixels, expected {} ± {slack}",
            w_px * h_px
        );
    }
}

#[test]
fn bad_arguments_are_errors() {
    let t = tree();
    let (min, max) = bounds(&t);
    let one = std::slice::from_ref(&t);
    let err = |o: &[DrawScene], s: &[DrawScene], p: CoverageParams, lo: Vec3, hi: Vec3| {
        match coverage_error(renderer(), o, s, lo, hi, &p) {
            Ok(r) => panic!("expected an error, got {r:?}"),
            Err(e) => e,
        }
    };
    let p = || params(1, 1, 40.0);
    assert!(matches!(
        err(one, &[t.clone(), t.clone()], p(), min, max),
        MetricError::FrameCountMismatch {
            expected: 1,
            original: 1,
            simplified: 2
        }
    ));
    assert!(matches!(
        err(one, one, params(1, 2, 40.0), min, max),
        MetricError::FrameCountMismatch { .. }
    ));
    assert!(matches!(
        err(one, one, params(0, 1, 40.0), min, max),
        MetricError::NoViews
    ));
    let no_rings = CoverageParams {
        elevations_deg: vec![],
        ..p()
    };
    assert!(matches!(
        err(one, one, no_rings, min, max),
        MetricError::NoViews
    ));
    assert!(matches!(
        err(&[], &[], params(1, 0, 40.0), min, max),
        MetricError::NoFrames
    ));
    let invalid = [
        CoverageParams {
            fov_y_deg: 0.0,
            ..p()
        },
        CoverageParams {
            elevations_deg: vec![0.0, 95.0],
            ..p()
        },
        CoverageParams {
            screen_height: 0.0,
            ..p()
        },
        CoverageParams {
            resolution: f32::INFINITY,
            ..p()
        },
        CoverageParams {
            samples_per_side: Some(0),
            ..p()
        },
    ];
    for bad in invalid {
        let e = err(one, one, bad.clone(), min, max);
        assert!(matches!(e, MetricError::InvalidParams(_)), "{bad:?}: {e}");
    }
    // Bounds without height, inverted or not finite cannot be framed.
    for (lo, hi) in [
        (min.with_y(0.0), max.with_y(0.0)),
        (max, min),
        (min, Vec3::splat(f32::NAN)),
    ] {
        let e = err(one, one, p(), lo, hi);
        assert!(matches!(e, MetricError::InvalidBounds { .. }), "{e}");
    }
    // Bad scene data surfaces as the renderer's error.
    let mut broken = t.clone();
    broken.meshes[0].indices.push(999);
    assert!(matches!(
        err(one, std::slice::from_ref(&broken), p(), min, max),
        MetricError::Render(_)
    ));
}

/// One sample a pixel makes every pixel wholly covered or not: the filtered error is then the
/// binary one, pixel for pixel, wherever no pair is discarded.
#[test]
fn one_sample_a_pixel_is_the_binary_error() {
    let t = tree();
    let (min, max) = bounds(&t);
    let cut = DrawScene {
        meshes: t.meshes[..7].to_vec(),
        ..t.clone()
    };
    let p = CoverageParams {
        samples_per_side: Some(1),
        ..params(3, 1, 40.0)
    };
    let r = run(
        std::slice::from_ref(&t),
        std::slice::from_ref(&cut),
        min,
        max,
        &p,
    );
    assert!(r.mean > 0.0 && r.mean < 1.0, "{r:?}");
    assert_eq!(r.binary.discarded, 0);
    for (i, score) in r.per_pair.iter().enumerate() {
        let (o, d) = (r.binary.original_pixels[i], r.binary.differing_pixels[i]);
        assert_eq!(r.original_coverage[i], o as f64);
        assert_eq!(*score, d as f64 / o as f64);
    }
    assert_eq!(r.mean, r.binary.mean);
}

#[test]
fn colour_difference_is_zero_for_equal_renders_and_known_for_recoloured_ones() {
    let p = params(3, 1, 40.0);
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let a = tree();
    let one = std::slice::from_ref(&a);
    let same = coverage_error(renderer(), one, one, lo, hi, &p).expect("metric");
    assert_eq!(same.colour_difference, 0.0);
    assert_eq!(same.colour_shift, 0.0);
    // Same geometry, pure red against pure blue (unlit, linear 1 vs 0 in two channels): 2/3.
    let recolour = |s: &DrawScene, rgb: [f32; 3]| {
        let mut s = s.clone();
        s.materials[0].base_color = [rgb[0], rgb[1], rgb[2], 1.0];
        s
    };
    let (red, blue) = (recolour(&a, [1.0, 0.0, 0.0]), recolour(&a, [0.0, 0.0, 1.0]));
    let r = coverage_error(renderer(), std::slice::from_ref(&red), &[blue], lo, hi, &p)
        .expect("metric");
    assert_eq!(r.mean, 0.0, "same coverage");
    assert!(
        (r.colour_difference - 2.0 / 3.0).abs() < 1e-3,
        "{}",
        r.colour_difference
    );
    assert_eq!(r.colour_per_pair.len(), 3, "one per (view, frame)");
    for c in &r.colour_per_pair {
        assert!((c - 2.0 / 3.0).abs() < 1e-3, "{c}");
    }
    // Red against blue shifts no mean (+1 and −1 in two channels); white against mid grey
    // shifts it by the whole difference, as lighter or darker LODs do.
    assert!(r.colour_shift.abs() < 1e-3, "{}", r.colour_shift);
    let (white, grey) = (recolour(&a, [1.0; 3]), recolour(&a, [0.5; 3]));
    let g = coverage_error(renderer(), &[white], &[grey], lo, hi, &p).expect("metric");
    assert!((g.colour_shift - 0.5).abs() < 1e-3, "{}", g.colour_shift);
    assert!((g.colour_difference - 0.5).abs() < 1e-3);
    // Only the coverage both share is compared: half the blue tree, shifted, still differs
    // from the red one by 2/3 wherever they overlap.
    let mut moved = recolour(&a, [0.0, 0.0, 1.0]);
    moved.meshes.truncate(6);
    for m in &mut moved.meshes {
        for q in &mut m.positions {
            q[0] += 0.05;
        }
    }
    let r = coverage_error(renderer(), &[red], &[moved], lo, hi, &p).expect("metric");
    assert!(r.mean > 0.2, "{r:?}");
    assert!(
        (r.colour_difference - 2.0 / 3.0).abs() < 1e-3,
        "{}",
        r.colour_difference
    );
}

/// `scene` moved `dx` along x.
fn shifted(scene: &DrawScene, dx: f32) -> DrawScene {
    let mut moved = scene.clone();
    for m in &mut moved.meshes {
        for p in &mut m.positions {
            p[0] += dx;
        }
    }
    moved
}

#[test]
fn images_rendered_once_compare_like_the_metric() {
    // Two frames: the tree, then the tree shifted right. Comparing stored images gives the
    // metric's numbers; frame 0 alone is the static metric on frame 0's scenes.
    let (lo, hi) = (Vec3::splat(-1.5), Vec3::splat(1.5));
    let a = tree();
    let moved = shifted(&a, 0.2);
    let mut cut = a.clone();
    cut.meshes.truncate(6);
    let original = [a.clone(), moved.clone()];
    let simplified = [cut.clone(), moved];
    let p = params(3, 2, 40.0);
    let full = run(&original, &simplified, lo, hi, &p);
    let o = coverage_images(renderer(), &original, lo, hi, &p).expect("images");
    let s = coverage_images(renderer(), &simplified, lo, hi, &p).expect("images");
    let f = framing(lo, hi, &p).expect("framing");
    assert_eq!(
        (o.views, o.frames, o.width, o.height, o.samples_per_pixel),
        (3, 2, f.width, f.height, K * K)
    );
    let again = compare_images(&o, &s, &[0, 1]).expect("compare");
    assert_eq!(again, full);
    let stat = compare_images(&o, &s, &[0]).expect("compare");
    let direct = run(
        std::slice::from_ref(&a),
        std::slice::from_ref(&cut),
        lo,
        hi,
        &params(3, 1, 40.0),
    );
    assert_eq!(stat, direct);
    assert!(stat.mean > 0.0 && stat.mean > full.mean, "frame 1 is exact");
    // A frame outside the images is refused, not read out of bounds.
    assert!(compare_images(&o, &s, &[2]).is_err());
    // The loop change: one frame has none; both paths give the same over two.
    assert_eq!(
        (stat.loop_change_original, stat.loop_change_ratio()),
        (None, None)
    );
    assert_eq!(again.loop_change_original, full.loop_change_original);
    assert!(
        full.loop_change_original.is_some_and(|c| c > 0.0),
        "{full:?}"
    );
}

/// The change of coverage over the loop: a model that moves as the original does changes as
/// much (ratio 1), one that stands still not at all (ratio 0), and the change is that of the
/// samples each frame uncovers or covers, over the original's covered samples.
#[test]
fn the_loop_change_is_the_coverage_that_moves_from_frame_to_frame() {
    let (lo, hi) = (Vec3::splat(-1.5), Vec3::splat(1.5));
    let a = tree();
    let moved = shifted(&a, 0.2);
    let swaying = [a.clone(), moved.clone(), a.clone()];
    let p = params(2, 3, 40.0);
    let same = run(&swaying, &swaying, lo, hi, &p);
    let change = same.loop_change_original.expect("three frames");
    assert!(change > 0.05 && change < 2.0, "{change}");
    assert_eq!(same.loop_change_simplified, Some(change));
    assert_eq!(same.loop_change_ratio(), Some(1.0));
    let still = [a.clone(), a.clone(), a.clone()];
    let r = run(&swaying, &still, lo, hi, &p);
    assert_eq!(r.loop_change_original, Some(change), "the original's own");
    assert_eq!(
        r.loop_change_ratio(),
        Some(0.0),
        "a model that stands still"
    );
    // Frame 0 against 1 and 1 against 2 change; 2 against 0 does not: a third less than the
    // pairs it would be were every frame different, whatever the views.
    let per_pair = change * 3.0 / 2.0;
    let moved_twice = [a.clone(), moved.clone(), a, moved];
    let four = run(&moved_twice, &moved_twice, lo, hi, &params(2, 4, 40.0));
    let c4 = four.loop_change_original.expect("four frames");
    assert!(
        (c4 - per_pair).abs() < 0.05 * per_pair,
        "{c4} vs {per_pair}"
    );
}

/// A `size`×`size` leaf texture: an opaque disc on a clear ground, for alpha-tested cards.
fn disc_texture(size: u32) -> DrawTexture {
    let c = (size as f32 - 1.0) / 2.0;
    let rgba = (0..size * size)
        .flat_map(|i| {
            let (x, y) = ((i % size) as f32 - c, (i / size) as f32 - c);
            let inside = x * x + y * y <= (size as f32 / 2.0).powi(2);
            [40, 160, 40, if inside { 255 } else { 0 }]
        })
        .collect();
    DrawTexture {
        width: size,
        height: size,
        rgba,
    }
}

/// A blended (glTF BLEND) layer covers its alpha of each pixel, and overlapping layers
/// `1 − Π(1 − αᵢ)`: against an opaque card, the same card at 30 % alpha reads a ratio of 0.3
/// and an error of 0.7, two at 50 % a ratio of 0.75, and one over the opaque card changes
/// nothing (±0.005, on the CPU rasteriser at a far LOD's size and at a near one's, and on the wgpu
/// path at the far one's).
#[test]
fn blended_layers_count_their_alpha_and_compose() {
    // The layers lie on one another (a blended layer writes no depth, and coverage does not
    // depend on which is in front), so they overlap exactly from every view.
    let front = card(Vec3::ZERO, Vec3::X, 0.8, 0.8);
    let behind = front.clone();
    let opaque = scene(std::slice::from_ref(&front), true);
    let blended = |alpha: f32, cards: &[Vec<[f32; 3]>]| {
        let mut s = scene(cards, true);
        s.materials[0].base_color[3] = alpha;
        s.materials[0].alpha = DrawAlpha::Blend;
        s
    };
    let (min, max) = bounds(&opaque);
    for (h, rasteriser) in [
        (20.0f32, Rasteriser::Software),
        (200.0, Rasteriser::Software),
        (20.0, Rasteriser::Gpu),
    ] {
        let p = CoverageParams {
            rasteriser,
            ..params(5, 1, h)
        };
        let measure = |s: &DrawScene| {
            coverage_error(
                renderer(),
                std::slice::from_ref(&opaque),
                std::slice::from_ref(s),
                min,
                max,
                &p,
            )
            .expect("metric")
        };
        // The report's ratio and error, each within ±0.005 of its known answer.
        let reads = |r: &CoverageReport, ratio: f64, error: f64| {
            let what = format!("{h} px {rasteriser:?}: {r:?}");
            assert!((r.ratio - ratio).abs() <= 0.005, "{what}");
            assert!((r.mean - error).abs() <= 0.005, "{what}");
        };
        reads(
            &measure(&blended(0.3, std::slice::from_ref(&front))),
            0.3,
            0.7,
        );
        reads(
            &measure(&blended(0.5, &[front.clone(), behind.clone()])),
            0.75,
            0.25,
        );
        let mut over = blended(0.5, std::slice::from_ref(&behind));
        over.materials.push(DrawMaterial {
            double_sided: true,
            ..DrawMaterial::opaque([0.2, 0.6, 0.2, 1.0])
        });
        over.meshes.push(DrawMesh {
            material: 1,
            ..opaque.meshes[0].clone()
        });
        reads(&measure(&over), 1.0, 0.0);
    }
}

/// A grid of `n × n` alpha-tested, double-sided leaf cards in the plane z = 0, with gaps: no
/// two overlap on screen from any view that sees the plane.
fn leaf_grid(n: usize) -> DrawScene {
    let step = 2.0 / n as f32;
    let meshes = (0..n * n)
        .map(|i| {
            let (col, row) = ((i % n) as f32, (i / n) as f32);
            let centre = Vec3::new(-1.0 + (col + 0.5) * step, (row + 0.5) * step, 0.0);
            DrawMesh {
                positions: card(centre, Vec3::X, 0.35 * step, 0.35 * step),
                uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
                indices: vec![0, 1, 2, 0, 2, 3],
                ..Default::default()
            }
        })
        .collect();
    DrawScene {
        meshes,
        materials: vec![DrawMaterial {
            texture: Some(0),
            alpha: DrawAlpha::Mask(0.5),
            double_sided: true,
            ..DrawMaterial::opaque([1.0; 4])
        }],
        textures: vec![disc_texture(64)],
    }
}

/// Removing half of a tree's cards, none of them overlapping another on screen, halves its
/// covered area: a coverage ratio of 0.5 ± 0.05, from every view of both rings.
#[test]
fn half_the_cards_removed_read_a_ratio_of_one_half() {
    let n = 8;
    let full = leaf_grid(n);
    // Every second card, in a checkerboard: as many of the larger (nearer) ones as not.
    let mut half = full.clone();
    half.meshes = (full.meshes.iter().enumerate())
        .filter(|(i, _)| (i % n + i / n) % 2 == 0)
        .map(|(_, m)| m.clone())
        .collect();
    assert_eq!(half.meshes.len(), n * n / 2);
    // The views on the ring at azimuths 0, 72, 144, 216, 288 all see the plane.
    let (min, max) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
    for h in [20.0f32, 60.0] {
        let p = CoverageParams {
            elevations_deg: vec![0.0, 30.0],
            samples_per_side: None,
            ..params(5, 1, h)
        };
        let r = coverage_error(
            renderer(),
            std::slice::from_ref(&full),
            std::slice::from_ref(&half),
            min,
            max,
            &p,
        )
        .expect("metric");
        eprintln!(
            "{h} px: ratio {:.4} (per pair {:?}), error {:.4}",
            r.ratio, r.ratio_per_pair, r.mean
        );
        assert!((r.ratio - 0.5).abs() <= 0.05, "{h} px: {r:?}");
        for ratio in &r.ratio_per_pair {
            assert!((ratio - 0.5).abs() <= 0.05, "{h} px: {ratio}");
        }
        // Nothing added: the error is what was removed.
        assert!((r.mean - (1.0 - r.ratio)).abs() < 1e-9, "{r:?}");
    }
}

/// The sample's foliage (its wood removed), and the same with every second card removed,
/// measured through `EvalContext` as `frond lod` measures a LOD: the ratio reads the area
/// left, at most 1 and at least the half the cards leave, more where the removed cards
/// overlapped others on screen.
#[test]
fn half_the_sample_cards_removed_read_the_area_left() {
    let mut tree = load(&frond_testdata::sample());
    tree.triangles.retain(|t| t.part == Part::Foliage);
    let (thinned, cards) = without_every_second_card(&tree);
    let req = EvalRequest {
        views: 5,
        frames: 1,
        screen_height: 60.0,
        fov_deg: frond_metrics::DEFAULT_FOV_DEG,
        resolution: frond_metrics::DEFAULT_RESOLUTION,
        samples: 2,
        clip: None,
        limits: InputLimits::default(),
        white_albedo: false,
        lighting: Default::default(),
    };
    let mut ctx = EvalContext::new(renderer(), &tree, &req).expect("context");
    for h in [60.0f32, 200.0] {
        let r = ctx.coverage(&thinned, h).expect("coverage");
        eprintln!(
            "sapling foliage, {} of {} cards removed, at {h} px: ratio {:.4}, error {:.4}",
            cards / 2,
            cards,
            r.ratio,
            r.mean
        );
        assert!(r.ratio >= 0.45 && r.ratio < 1.0, "{h} px: {r:?}");
        // Nothing added: the error is what was removed.
        assert!((r.mean - (1.0 - r.ratio)).abs() < 1e-9, "{r:?}");
        let same = ctx.coverage(&tree, h).expect("coverage");
        assert_eq!((same.mean, same.ratio), (0.0, 1.0));
    }
}
