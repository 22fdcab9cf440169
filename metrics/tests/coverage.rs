//! The coverage metric (spec animated-billboard-clouds §5.4) on real renders, each case with a
//! known answer. Small images (64×48) keep CPU rasterisers fast.
//!
//! All tests share one `Renderer` and fail (never skip) when no adapter exists: CI machines
//! have Mesa llvmpipe.

use std::sync::OnceLock;

use frond_metrics::{
    CoverageParams, CoverageReport, MetricError, Rasteriser, coverage_error, ring_azimuth_deg,
    view_camera,
};
use frond_render::{DrawMaterial, DrawMesh, DrawScene, Renderer};
use glam::Vec3;

const W: u32 = 64;
const H: u32 = 48;

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

fn params(views: u32, frames: u32) -> CoverageParams {
    CoverageParams {
        views,
        frames,
        width: W,
        height: H,
        elevation_deg: 0.0,
        fov_y_deg: 40.0,
        // Exact pixel counts below are for plain masks; supersampling has its own test.
        supersample: 1,
        // The default (CPU) rasteriser; `software_raster.rs` checks it against the GPU's.
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

fn run(
    original: &[DrawScene],
    simplified: &[DrawScene],
    min: Vec3,
    max: Vec3,
    p: &CoverageParams,
) -> CoverageReport {
    let report = coverage_error(renderer(), original, simplified, min, max, p)
        .unwrap_or_else(|e| panic!("coverage_error failed: {e}"));
    // Every known answer holds for the GPU's rasteriser too: the two count the same pixels
    // but for a few along the edges of each card.
    let gpu = CoverageParams {
        rasteriser: Rasteriser::Gpu,
        ..p.clone()
    };
    let other = coverage_error(renderer(), original, simplified, min, max, &gpu)
        .unwrap_or_else(|e| panic!("coverage_error (GPU) failed: {e}"));
    for (counts, gpu_counts) in [
        (&report.original_pixels, &other.original_pixels),
        (&report.differing_pixels, &other.differing_pixels),
    ] {
        for (a, b) in counts.iter().zip(gpu_counts) {
            assert!(
                a.abs_diff(*b) <= 2 + a.max(b) / 50,
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
    let r = run(one, one, min, max, &params(5, 1));
    assert_eq!(r.per_view, vec![0.0; 5]);
    assert_eq!(r.mean, 0.0);
    assert_eq!(r.discarded, 0);
    assert_eq!(r.differing_pixels, vec![0; 5]);
    assert!(r.original_pixels.iter().all(|&p| p > 50), "{r:?}");
}

#[test]
fn empty_simplification_scores_exactly_one() {
    let t = tree();
    let (min, max) = bounds(&t);
    let r = run(&[t], &[DrawScene::default()], min, max, &params(5, 1));
    assert_eq!(r.per_view, vec![1.0; 5]);
    assert_eq!(r.mean, 1.0);
    assert_eq!(r.discarded, 0);
    assert_eq!(r.differing_pixels, r.original_pixels);
}

#[test]
fn scores_above_one_are_discarded() {
    // The tree's bounds are ±4, the original a small card at the centre: it covers a small part
    // of the image while a huge quad covers all of it, so |o − s| ≫ P_f.
    let (min, max) = (Vec3::splat(-4.0), Vec3::splat(4.0));
    let small = scene(&[card(Vec3::ZERO, Vec3::X, 0.5, 0.5)], true);
    let huge = scene(&[card(Vec3::ZERO, Vec3::X, 100.0, 100.0)], true);
    let r = run(
        std::slice::from_ref(&small),
        std::slice::from_ref(&huge),
        min,
        max,
        &params(1, 1),
    );
    let p_f = r.original_pixels[0];
    assert!(p_f > 0 && p_f < u64::from(W * H) / 4, "{r:?}");
    assert_eq!(r.differing_pixels[0], u64::from(W * H) - p_f);
    assert_eq!(r.discarded, 1);
    assert!(r.per_view[0].is_nan() && r.mean.is_nan(), "{r:?}");

    // Two frames: frame 0 is perfect, frame 1 is discarded and does not pollute the mean.
    let r = run(
        &[small.clone(), small.clone()],
        &[small, huge],
        min,
        max,
        &params(1, 2),
    );
    assert_eq!(r.discarded, 1);
    assert_eq!(r.per_view, vec![0.0]);
    assert_eq!(r.mean, 0.0);
}

#[test]
fn empty_original_is_discarded() {
    let t = tree();
    let (min, max) = bounds(&t);
    let r = run(&[DrawScene::default()], &[t], min, max, &params(3, 1));
    assert_eq!(r.discarded, 3);
    assert_eq!(r.original_pixels, vec![0; 3]);
    assert!(r.per_view.iter().all(|v| v.is_nan()) && r.mean.is_nan());
}

/// A 1×2 card facing the single view fills the image height (48 rows) and 24 of its 64
/// columns. Shifting it by a fraction `k` of its width leaves `2k` of its area uncovered by the
/// other: the metric is `2k`.
#[test]
fn shifted_card_scores_analytically() {
    let original = scene(&[card(Vec3::ZERO, Vec3::X, 0.5, 1.0)], false);
    let (min, max) = bounds(&original);
    for (shift, expected) in [(0.5f32, 1.0f64), (0.25, 0.5), (0.125, 0.25)] {
        let shifted = scene(
            &[card(Vec3::new(shift, 0.0, 0.0), Vec3::X, 0.5, 1.0)],
            false,
        );
        let r = run(
            std::slice::from_ref(&original),
            &[shifted],
            min,
            max,
            &params(1, 1),
        );
        let p_f = r.original_pixels[0];
        eprintln!(
            "shift {shift}: P_f {p_f}, |o-s| {}, score {}",
            r.differing_pixels[0], r.mean
        );
        // One column of slack for rasterisation at each of the two edges.
        assert!(p_f.abs_diff(24 * 48) <= 2 * 48, "P_f {p_f}");
        let tolerance = 2.0 * 48.0 / p_f as f64;
        assert!(
            (r.mean - expected).abs() <= tolerance,
            "shift {shift}: {} vs {expected} ({r:?})",
            r.mean
        );
        assert_eq!(r.discarded, 0);
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
        &params(3, 2),
    );
    assert_eq!(r.per_view, vec![0.5; 3]);
    assert_eq!(r.mean, 0.5);
    assert_eq!(r.original_pixels.len(), 6);
    // View-major: frame 1 of every view differs everywhere the original covers.
    for d in 0..3 {
        assert_eq!(r.differing_pixels[2 * d], 0);
        assert_eq!(r.differing_pixels[2 * d + 1], r.original_pixels[2 * d + 1]);
    }
}

/// The bounds' vertical extent spans the image height: the front face of a cube's bounds
/// touches the top and bottom rows, the back face (farther away) does not.
#[test]
fn framing_fills_the_image_height() {
    let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let p = params(1, 1);
    let camera = view_camera(min, max, 0, &p).expect("camera");
    let expected = 1.0 / 20.0f32.to_radians().tan() + 1.0;
    assert!((camera.distance - expected).abs() < 1e-5 * expected);
    let rows = |z: f32| {
        let s = scene(&[card(Vec3::new(0.0, 0.0, z), Vec3::X, 1.0, 1.0)], true);
        let frame = renderer()
            .render(&s, &camera, W, H, [0.0; 4])
            .expect("render");
        (0..H)
            .filter(|&y| (0..W).any(|x| frame.covered(x, y)))
            .collect::<Vec<u32>>()
    };
    let front = rows(1.0);
    assert_eq!(front, (0..H).collect::<Vec<_>>());
    let back = rows(-1.0);
    assert!(!back.is_empty() && !back.contains(&0) && !back.contains(&(H - 1)));
}

/// A single-sided marker card facing outward at azimuth 72°·k (the ring's `k`-th azimuth) is
/// seen head-on by view k: there it differs most, by its analytic pixel count, and sits in the
/// middle columns; views k ± 1 see it obliquely and the two views behind it not at all. The
/// original (a card above the markers, never overlapping them on screen) scores exactly what
/// manual renders with `view_camera` give, so the metric uses those cameras.
#[test]
fn ring_starts_at_azimuth_zero_and_is_evenly_spaced() {
    let views = 5u32;
    // Larger than the other tests: the oblique views see the marker as a thin sliver.
    let p = CoverageParams {
        width: 128,
        height: 96,
        ..params(views, 1)
    };
    let (min, max) = (Vec3::splat(-2.0), Vec3::splat(2.0));
    let (radius, hw, hh) = (1.5f32, 0.5f32, 0.4f32);
    let top = card(Vec3::new(0.0, 1.5, 0.0), Vec3::X, 0.5, 0.4);
    let original = scene(std::slice::from_ref(&top), true);
    for (d, expected) in [0.0f32, 72.0, 144.0, 216.0, 288.0].iter().enumerate() {
        assert_eq!(ring_azimuth_deg(d as u32, views), *expected);
    }
    for k in 0..views {
        let theta = ring_azimuth_deg(k, views).to_radians();
        let normal = Vec3::new(theta.sin(), 0.0, theta.cos());
        let right = Vec3::new(theta.cos(), 0.0, -theta.sin());
        let marker = card(normal * radius - Vec3::Y * 1.5, right, hw, hh);
        // The top card stays double-sided; only the single-sided marker can differ.
        let mut simplified = scene(&[top.clone(), marker.clone()], true);
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
        let diff = &r.differing_pixels;
        let at = |offset: u32| diff[((k + offset) % views) as usize];
        assert!(
            at(0) > 3 * at(1) && at(0) > 3 * at(4) && at(1) > 0 && at(4) > 0,
            "k {k}: {diff:?}"
        );
        assert_eq!((at(2), at(3)), (0, 0), "k {k}: {diff:?}");

        // Head-on from view k: the marker's projected size at depth distance − radius.
        let camera = view_camera(min, max, k, &p).expect("camera");
        assert_eq!(camera.azimuth_deg, 72.0 * k as f32);
        let px_per_unit =
            p.height as f32 / (2.0 * (camera.distance - radius) * 20f32.to_radians().tan());
        let (w_px, h_px) = (2.0 * hw * px_per_unit, 2.0 * hh * px_per_unit);
        let expected = w_px * h_px;
        let slack = 2.0 * (w_px + h_px);
        assert!(
            (at(0) as f32 - expected).abs() <= slack,
            "k {k}: {} pixels, expected {expected} ± {slack}",
            at(0)
        );
        let alone = scene(&[marker], false);
        let frame = renderer()
            .render(&alone, &camera, p.width, p.height, [0.0; 4])
            .expect("render");
        let cols: Vec<u32> = (0..p.width)
            .filter(|&x| (0..p.height).any(|y| frame.covered(x, y)))
            .collect();
        let (first, last) = (cols[0], cols[cols.len() - 1]);
        assert!(
            (first + last + 1).abs_diff(p.width) <= 2,
            "k {k}: marker columns {first}..={last} not centred"
        );

        for d in 0..views {
            let camera = view_camera(min, max, d, &p).expect("camera");
            let frame = renderer()
                .render(&original, &camera, p.width, p.height, [0.0; 4])
                .expect("render");
            assert_eq!(
                r.original_pixels[d as usize],
                frame.covered_count() as u64,
                "view {d}"
            );
        }
    }
}

#[test]
fn bad_arguments_are_errors() {
    let t = tree();
    let (min, max) = bounds(&t);
    let one = std::slice::from_ref(&t);
    let err = |o: &[DrawScene], s: &[DrawScene], p: CoverageParams| match coverage_error(
        renderer(),
        o,
        s,
        min,
        max,
        &p,
    ) {
        Ok(r) => panic!("expected an error, got {r:?}"),
        Err(e) => e,
    };
    assert!(matches!(
        err(one, &[t.clone(), t.clone()], params(1, 1)),
        MetricError::FrameCountMismatch {
            expected: 1,
            original: 1,
            simplified: 2
        }
    ));
    assert!(matches!(
        err(one, one, params(1, 2)),
        MetricError::FrameCountMismatch { .. }
    ));
    assert!(matches!(
        err(
            one,
            one,
            CoverageParams {
                width: 0,
                ..params(1, 1)
            }
        ),
        MetricError::InvalidSize { .. }
    ));
    assert!(matches!(
        err(
            one,
            one,
            CoverageParams {
                height: 0,
                ..params(1, 1)
            }
        ),
        MetricError::InvalidSize { .. }
    ));
    assert!(matches!(err(one, one, params(0, 1)), MetricError::NoViews));
    assert!(matches!(err(&[], &[], params(1, 0)), MetricError::NoFrames));
    assert!(matches!(
        err(
            one,
            one,
            CoverageParams {
                fov_y_deg: 0.0,
                ..params(1, 1)
            }
        ),
        MetricError::InvalidParams(_)
    ));
    // Bad scene data surfaces as the renderer's error.
    let mut broken = t.clone();
    broken.meshes[0].indices.push(999);
    assert!(matches!(
        err(one, std::slice::from_ref(&broken), params(1, 1)),
        MetricError::Render(_)
    ));
}

#[test]
fn supersampled_masks_keep_analytic_answers() {
    // The half-width shift of a card is still exactly half its pixels different with 4×4
    // supersampling (edges fall on pixel boundaries at this framing), and identical scenes
    // still score 0.
    let r = renderer();
    let a = DrawScene {
        meshes: vec![DrawMesh {
            positions: card(Vec3::ZERO, Vec3::X, 1.0, 1.0),
            normals: None,
            tangents: None,
            uvs: None,
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
        }],
        materials: vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
        textures: vec![],
    };
    let p = CoverageParams {
        supersample: 4,
        ..params(1, 1)
    };
    let same = coverage_error(
        r,
        std::slice::from_ref(&a),
        std::slice::from_ref(&a),
        Vec3::splat(-1.0),
        Vec3::splat(1.0),
        &p,
    )
    .expect("metric");
    assert_eq!(same.mean, 0.0);
    let empty = DrawScene {
        meshes: vec![],
        ..a.clone()
    };
    let none = coverage_error(
        r,
        std::slice::from_ref(&a),
        &[empty],
        Vec3::splat(-1.0),
        Vec3::splat(1.0),
        &p,
    )
    .expect("metric");
    assert_eq!(none.mean, 1.0);
}

#[test]
fn colour_difference_is_zero_for_equal_renders_and_known_for_recoloured_ones() {
    let p = params(3, 1);
    let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
    let a = tree();
    let one = std::slice::from_ref(&a);
    let same = coverage_error(renderer(), one, one, lo, hi, &p).expect("metric");
    assert_eq!(same.colour_difference, 0.0);
    // Same geometry, pure red against pure blue (unlit, linear 1 vs 0 in two channels): 2/3.
    let mut red = a.clone();
    red.materials[0] = DrawMaterial {
        double_sided: true,
        ..DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])
    };
    let mut blue = a;
    blue.materials[0] = DrawMaterial {
        double_sided: true,
        ..DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0])
    };
    let r = coverage_error(renderer(), &[red.clone()], &[blue], lo, hi, &p).expect("metric");
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
    let (mut white, mut grey) = (red.clone(), red);
    white.materials[0].base_color = [1.0; 4];
    grey.materials[0].base_color = [0.5, 0.5, 0.5, 1.0];
    let g = coverage_error(renderer(), &[white], &[grey], lo, hi, &p).expect("metric");
    assert!((g.colour_shift - 0.5).abs() < 1e-3, "{}", g.colour_shift);
    assert!((g.colour_difference - 0.5).abs() < 1e-3);
}

#[test]
fn masks_rendered_once_compare_like_the_metric() {
    // Two frames: the tree, then the tree shifted right. Comparing stored masks gives the
    // metric's numbers; frame 0 alone is the static metric on frame 0's scenes.
    let (lo, hi) = (Vec3::splat(-1.5), Vec3::splat(1.5));
    let a = tree();
    let mut moved = a.clone();
    for m in &mut moved.meshes {
        for p in &mut m.positions {
            p[0] += 0.2;
        }
    }
    let cut = {
        let mut c = a.clone();
        c.meshes.truncate(6);
        c
    };
    let original = [a.clone(), moved.clone()];
    let simplified = [cut.clone(), moved];
    let p = params(3, 2);
    let full = run(&original, &simplified, lo, hi, &p);
    let o = frond_metrics::coverage_masks(renderer(), &original, lo, hi, &p).expect("masks");
    let s = frond_metrics::coverage_masks(renderer(), &simplified, lo, hi, &p).expect("masks");
    assert_eq!((o.views, o.frames, o.pixels), (3, 2, (W * H) as usize));
    let again = frond_metrics::compare_masks(&o, &s, &[0, 1]).expect("compare");
    assert_eq!(again, full);
    let stat = frond_metrics::compare_masks(&o, &s, &[0]).expect("compare");
    let direct = run(
        std::slice::from_ref(&a),
        std::slice::from_ref(&cut),
        lo,
        hi,
        &params(3, 1),
    );
    assert_eq!(stat, direct);
    assert!(stat.mean > 0.0 && stat.mean > full.mean, "frame 1 is exact");
    // A frame outside the masks is refused, not read out of bounds.
    assert!(frond_metrics::compare_masks(&o, &s, &[2]).is_err());
}
