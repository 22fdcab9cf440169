//! End-to-end renders on whatever adapter the machine has (llvmpipe in CI).
//!
//! Each test creates one `Renderer` and fails (never skips) when no adapter exists.

use frond_render::{
    Camera, DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture, Frame, Projection,
    RenderError,
};
use frond_scene::Wrap;
use glam::Vec3;

mod common;
use common::{quad_z, renderer};

const BLUE: [f32; 4] = [0.0, 0.0, 1.0, 1.0];

fn ortho(azimuth_deg: f32, half_height: f32) -> Camera {
    Camera {
        target: Vec3::ZERO,
        azimuth_deg,
        elevation_deg: 0.0,
        distance: 10.0,
        projection: Projection::Orthographic { half_height },
    }
}

fn scene(meshes: Vec<DrawMesh>, materials: Vec<DrawMaterial>) -> DrawScene {
    DrawScene {
        meshes,
        materials,
        textures: vec![],
    }
}

fn centre(frame: &Frame) -> [u8; 4] {
    frame.pixel(frame.width / 2, frame.height / 2)
}

/// Pixel centre of (x, y) in NDC.
fn ndc(frame: &Frame, x: u32, y: u32) -> (f32, f32) {
    let nx = (x as f32 + 0.5) / frame.width as f32 * 2.0 - 1.0;
    let ny = 1.0 - (y as f32 + 0.5) / frame.height as f32 * 2.0;
    (nx, ny)
}

#[test]
fn opaque_triangle_covers_exactly_its_region() {
    let r = renderer();
    let red = DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0]);
    // Lower-left half of the view: x + y < 0 in NDC.
    let triangle = DrawMesh {
        positions: vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, 1.0, 0.0]],
        indices: vec![0, 1, 2],
        ..Default::default()
    };
    let s = scene(vec![triangle], vec![red.clone()]);
    let frame = r
        .render(&s, &ortho(0.0, 1.0), 64, 64, BLUE)
        .expect("render");
    assert_eq!(frame.rgba.len(), 64 * 64 * 4);
    assert_eq!(frame.coverage.len(), 64 * 64);
    let margin = 2.0 * 2.0 / 64.0; // two pixels
    let mut checked = 0;
    for y in 0..64 {
        for x in 0..64 {
            let (nx, ny) = ndc(&frame, x, y);
            let d = nx + ny;
            if d < -margin {
                assert!(frame.covered(x, y), "({x},{y}) should be covered");
                assert_eq!(frame.pixel(x, y), [255, 0, 0, 255], "({x},{y})");
                checked += 1;
            } else if d > margin {
                assert!(!frame.covered(x, y), "({x},{y}) should not be covered");
                assert_eq!(frame.pixel(x, y), [0, 0, 255, 255], "({x},{y})");
                checked += 1;
            }
        }
    }
    assert!(checked > 3500);
    let fraction = frame.coverage_fraction();
    assert!((fraction - 0.5).abs() < 0.02, "coverage {fraction}");
    // Exactness: every covered pixel is red, every uncovered one is background.
    for (i, &c) in frame.coverage.iter().enumerate() {
        let p = &frame.rgba[i * 4..i * 4 + 4];
        assert_eq!(c, p == [255, 0, 0, 255], "pixel {i} {p:?}");
    }

    // Seen from behind, a single-sided triangle is culled; a double-sided one is not.
    let back = r
        .render(&s, &ortho(180.0, 1.0), 64, 64, BLUE)
        .expect("render");
    assert_eq!(back.covered_count(), 0);
    let two_sided = scene(
        s.meshes.clone(),
        vec![DrawMaterial {
            double_sided: true,
            ..red
        }],
    );
    let back = r
        .render(&two_sided, &ortho(180.0, 1.0), 64, 64, BLUE)
        .expect("render");
    assert!((back.coverage_fraction() - 0.5).abs() < 0.02);
}

#[test]
fn alpha_mask_cuts_out_the_transparent_half() {
    let r = renderer();
    let (w, h) = (64u32, 4u32);
    let mut rgba = Vec::new();
    for _y in 0..h {
        for x in 0..w {
            let alpha = if x < w / 2 { 0 } else { 255 };
            rgba.extend([0, 255, 0, alpha]);
        }
    }
    let masked = DrawMaterial {
        wrap: Default::default(),
        base_color: [1.0; 4],
        texture: Some(0),
        normal_texture: None,
        alpha: DrawAlpha::Mask(0.5),
        double_sided: true,
    };
    let mut s = DrawScene {
        meshes: vec![quad_z([-1.0, -1.0], [1.0, 1.0], 0.0, 0)],
        materials: vec![masked.clone()],
        textures: vec![DrawTexture {
            width: w,
            height: h,
            rgba,
        }],
    };
    let frame = r
        .render(&s, &ortho(0.0, 1.0), 64, 64, [0.0; 4])
        .expect("render");
    let fraction = frame.coverage_fraction();
    assert!((fraction - 0.5).abs() <= 2.0 / 64.0, "coverage {fraction}");
    for y in 0..64 {
        for x in (0..30).chain(34..64) {
            assert_eq!(frame.covered(x, y), x >= 34, "({x},{y})");
        }
    }
    assert_eq!(frame.pixel(48, 32), [0, 255, 0, 255]);
    assert_eq!(
        frame.pixel(16, 32),
        [0, 0, 0, 0],
        "background with alpha 0 shows through"
    );

    // The same texture on an opaque material ignores alpha.
    s.materials[0].alpha = DrawAlpha::Opaque;
    let frame = r
        .render(&s, &ortho(0.0, 1.0), 64, 64, [0.0; 4])
        .expect("render");
    assert_eq!(frame.covered_count(), 64 * 64);
}

/// The sampler's wrap modes are honoured: a texture opaque in its right half only, stretched
/// over u in [0, 2] across the view, shows twice when repeating (a quarter of the view each,
/// 2 of 4 quarters), once when clamped (the right quarter of [0, 1], and beyond 1 the opaque
/// edge column: half the view), and mirrored, [0.5, 1.5] opaque.
#[test]
fn wrap_modes_decide_what_lies_outside_the_texture() {
    let r = renderer();
    let (w, h) = (64u32, 4u32);
    let rgba: Vec<u8> = (0..w * h)
        .flat_map(|i| [0, 255, 0, if i % w < w / 2 { 0 } else { 255 }])
        .collect();
    let mut quad = quad_z([-1.0, -1.0], [1.0, 1.0], 0.0, 0);
    quad.uvs = Some(vec![[0.0, 1.0], [2.0, 1.0], [2.0, 0.0], [0.0, 0.0]]);
    let covered_columns = |wrap: [Wrap; 2]| {
        let s = DrawScene {
            meshes: vec![quad.clone()],
            materials: vec![DrawMaterial {
                base_color: [1.0; 4],
                texture: Some(0),
                normal_texture: None,
                alpha: DrawAlpha::Mask(0.5),
                double_sided: true,
                wrap,
            }],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba: rgba.clone(),
            }],
        };
        let frame = r
            .render(&s, &ortho(0.0, 1.0), 64, 64, [0.0; 4])
            .expect("render");
        (0..64).map(|x| frame.covered(x, 32)).collect::<Vec<bool>>()
    };
    // Columns well inside each quarter of the view (u in steps of 0.5).
    let quarters = |c: &[bool]| [4, 20, 36, 52].map(|x: usize| (c[x], c[x + 8]));
    let t = (true, true);
    let f = (false, false);
    assert_eq!(quarters(&covered_columns([Wrap::Repeat; 2])), [f, t, f, t]);
    assert_eq!(
        quarters(&covered_columns([Wrap::ClampToEdge, Wrap::Repeat])),
        [f, t, t, t]
    );
    assert_eq!(
        quarters(&covered_columns([Wrap::MirroredRepeat, Wrap::Repeat])),
        [f, t, t, f]
    );
}

#[test]
fn nearer_surface_wins_regardless_of_draw_order() {
    let r = renderer();
    let materials = vec![
        DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0]),
        DrawMaterial::opaque([0.0, 1.0, 0.0, 1.0]),
    ];
    let far = quad_z([-1.0, -1.0], [0.5, 0.5], -0.5, 0);
    let near = quad_z([-0.5, -0.5], [1.0, 1.0], 0.5, 1);
    let camera = Camera {
        target: Vec3::ZERO,
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        distance: 6.0,
        projection: Projection::Perspective { fov_y_deg: 40.0 },
    };
    for meshes in [
        vec![far.clone(), near.clone()],
        vec![near.clone(), far.clone()],
    ] {
        let frame = r
            .render(&scene(meshes, materials.clone()), &camera, 96, 96, BLUE)
            .expect("render");
        assert_eq!(
            centre(&frame),
            [0, 255, 0, 255],
            "overlap shows the near quad"
        );
        // Lower-left: only the far quad; upper-right: only the near one.
        assert_eq!(frame.pixel(30, 66), [255, 0, 0, 255]);
        assert_eq!(frame.pixel(66, 30), [0, 255, 0, 255]);
        assert_eq!(frame.pixel(2, 2), [0, 0, 255, 255]);
    }
}

#[test]
fn camera_angles_follow_the_documented_convention() {
    let r = renderer();
    // Quads 5 units out on +X (facing +X), on +Z (facing +Z) and on +Y (facing +Y),
    // each single-sided so they only show when seen from outside.
    let plus_x = DrawMesh {
        positions: vec![
            [5.0, -1.0, 1.0],
            [5.0, -1.0, -1.0],
            [5.0, 1.0, -1.0],
            [5.0, 1.0, 1.0],
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
        ..Default::default()
    };
    let plus_z = DrawMesh {
        material: 1,
        ..quad_z([-1.0, -1.0], [1.0, 1.0], 5.0, 1)
    };
    let plus_y = DrawMesh {
        positions: vec![
            [-1.0, 5.0, 1.0],
            [1.0, 5.0, 1.0],
            [1.0, 5.0, -1.0],
            [-1.0, 5.0, -1.0],
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 2,
        ..Default::default()
    };
    // A marker at z = +5 facing +X, to find where +Z lands when seen from +X.
    let marker = DrawMesh {
        positions: vec![
            [0.0, -0.5, 5.5],
            [0.0, -0.5, 4.5],
            [0.0, 0.5, 4.5],
            [0.0, 0.5, 5.5],
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 3,
        ..Default::default()
    };
    let s = scene(
        vec![plus_x, plus_z, plus_y, marker],
        vec![
            DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0]),
            DrawMaterial::opaque([0.0, 1.0, 0.0, 1.0]),
            DrawMaterial::opaque([1.0, 1.0, 0.0, 1.0]),
            DrawMaterial::opaque([1.0, 0.0, 1.0, 1.0]),
        ],
    );
    let view = |azimuth_deg: f32, elevation_deg: f32| Camera {
        target: Vec3::ZERO,
        azimuth_deg,
        elevation_deg,
        distance: 20.0,
        projection: Projection::Perspective { fov_y_deg: 40.0 },
    };
    let black = [0.0, 0.0, 0.0, 1.0];
    let at_90 = r
        .render(&s, &view(90.0, 0.0), 64, 64, black)
        .expect("render");
    assert!(at_90.covered(32, 32));
    assert_eq!(
        centre(&at_90),
        [255, 0, 0, 255],
        "azimuth 90 looks at +X from +X"
    );
    // From +X, +Z lies to the left: counter-clockwise seen from above.
    let magenta = [255, 0, 255, 255];
    let left = (0..32).filter(|&x| at_90.pixel(x, 32) == magenta).count();
    let right = (32..64).filter(|&x| at_90.pixel(x, 32) == magenta).count();
    assert!(
        left > 0 && right == 0,
        "+Z marker at left {left} / right {right}"
    );

    let at_0 = r
        .render(&s, &view(0.0, 0.0), 64, 64, black)
        .expect("render");
    assert_eq!(
        centre(&at_0),
        [0, 255, 0, 255],
        "azimuth 0 looks at +Z from +Z"
    );

    let above = r
        .render(&s, &view(0.0, 90.0), 64, 64, black)
        .expect("render");
    assert_eq!(
        centre(&above),
        [255, 255, 0, 255],
        "elevation 90 looks down from +Y"
    );

    let behind = r
        .render(&s, &view(270.0, 0.0), 64, 64, black)
        .expect("render");
    assert_ne!(
        centre(&behind),
        [255, 0, 0, 255],
        "+X quad is back-facing from -X"
    );

    // framing() fits the scene: everything drawn lies inside the image border.
    let (min, max) = s.bounds().expect("bounds");
    let framed = Camera::framing(
        min,
        max,
        30.0,
        20.0,
        Projection::Perspective { fov_y_deg: 40.0 },
    );
    let frame = r.render(&s, &framed, 64, 64, black).expect("render");
    assert!(frame.covered_count() > 0);
    for i in 0..64 {
        for (x, y) in [(i, 0), (i, 63), (0, i), (63, i)] {
            assert!(!frame.covered(x, y), "border pixel ({x},{y}) covered");
        }
    }
}

#[test]
fn textures_lighting_and_srgb_round_trip() {
    let r = renderer();
    // Unlit texture colour comes back unchanged (sRGB in, sRGB out).
    let s = DrawScene {
        meshes: vec![quad_z([-1.0, -1.0], [1.0, 1.0], 0.0, 0)],
        materials: vec![DrawMaterial {
            texture: Some(0),
            ..DrawMaterial::default()
        }],
        textures: vec![DrawTexture {
            width: 2,
            height: 2,
            rgba: [200, 100, 50, 255].repeat(4),
        }],
    };
    let frame = r
        .render(&s, &ortho(0.0, 2.0), 32, 32, BLUE)
        .expect("render");
    let p = centre(&frame);
    for (got, want) in p.iter().zip([200u8, 100, 50, 255]) {
        assert!(got.abs_diff(want) <= 1, "{p:?}");
    }

    // Lit: 0.6 + 0.4 * |n . light| with n = +Z.
    let mut lit = quad_z([-1.0, -1.0], [1.0, 1.0], 0.0, 0);
    lit.normals = Some(vec![[0.0, 0.0, 1.0]; 4]);
    let s = scene(vec![lit], vec![DrawMaterial::opaque([1.0, 1.0, 1.0, 1.0])]);
    let frame = r
        .render(&s, &ortho(0.0, 2.0), 32, 32, BLUE)
        .expect("render");
    let shade = 0.6 + 0.4 * frond_render::LIGHT_DIRECTION[2];
    let srgb = if shade <= 0.003_130_8 {
        shade * 12.92
    } else {
        1.055 * shade.powf(1.0 / 2.4) - 0.055
    };
    let want = (srgb * 255.0).round() as u8;
    let p = centre(&frame);
    assert!(
        p[0].abs_diff(want) <= 1 && p[0] == p[1] && p[1] == p[2],
        "{p:?} vs {want}"
    );
}

#[test]
fn empty_scenes_render_the_background() {
    let r = renderer();
    let camera = ortho(0.0, 1.0);
    let empty_mesh = DrawMesh {
        positions: vec![[0.0; 3]],
        material: 7, // not drawn, so not checked
        ..Default::default()
    };
    for s in [DrawScene::default(), scene(vec![empty_mesh], vec![])] {
        let frame = r
            .render(&s, &camera, 16, 8, [0.0, 0.0, 1.0, 0.0])
            .expect("render");
        assert_eq!((frame.width, frame.height), (16, 8));
        assert_eq!(frame.covered_count(), 0);
        assert!(frame.rgba.chunks_exact(4).all(|p| p == [0, 0, 255, 0]));
    }
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let r = renderer();
    let camera = ortho(0.0, 1.0);
    let good = scene(
        vec![quad_z([-1.0, -1.0], [1.0, 1.0], 0.0, 0)],
        vec![DrawMaterial::default()],
    );
    assert!(r.render(&good, &camera, 8, 8, BLUE).is_ok());

    let mut s = good.clone();
    s.meshes[0].indices[4] = 4;
    let err = r
        .render(&s, &camera, 8, 8, BLUE)
        .expect_err("index 4 of 4 vertices");
    assert!(
        matches!(err, RenderError::IndexOutOfRange { index: 4, .. }),
        "{err}"
    );

    let mut s = good.clone();
    s.meshes[0].material = 3;
    assert!(matches!(
        r.render(&s, &camera, 8, 8, BLUE),
        Err(RenderError::MaterialOutOfRange { .. })
    ));

    let mut s = good.clone();
    s.materials[0].texture = Some(0);
    assert!(matches!(
        r.render(&s, &camera, 8, 8, BLUE),
        Err(RenderError::TextureOutOfRange { .. })
    ));
    s.textures.push(DrawTexture {
        width: 3,
        height: 3,
        rgba: vec![0; 35],
    });
    assert!(matches!(
        r.render(&s, &camera, 8, 8, BLUE),
        Err(RenderError::InvalidTexture { .. })
    ));

    for (w, h) in [(0, 8), (8, 0), (r.max_dimension() + 1, 8)] {
        assert!(
            matches!(
                r.render(&good, &camera, w, h, BLUE),
                Err(RenderError::InvalidSize { .. })
            ),
            "{w}x{h}"
        );
    }
    let bad_camera = Camera {
        distance: -1.0,
        ..camera
    };
    assert!(matches!(
        r.render(&good, &bad_camera, 8, 8, BLUE),
        Err(RenderError::InvalidCamera(_))
    ));
    // The renderer still works after errors.
    assert!(r.render(&good, &camera, 8, 8, BLUE).is_ok());
}

#[test]
fn one_renderer_serves_several_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<frond_render::Renderer>();
    let r = renderer();
    let s = scene(
        vec![quad_z([-0.5, -0.5], [0.5, 0.5], 0.0, 0)],
        vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
    );
    // Many small renders at once: one thread's poll may run another's map
    // callbacks after that thread's own poll returned (a CI failure once).
    let frames: Vec<Frame> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..8)
            .map(|_| {
                scope.spawn(|| {
                    (0..25)
                        .map(|_| r.render(&s, &ortho(0.0, 1.0), 32, 32, BLUE))
                        .collect::<Result<Vec<_>, _>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("thread").expect("render"))
            .collect()
    });
    assert_eq!(frames.len(), 200);
    for f in &frames {
        assert_eq!(f, &frames[0]);
        assert_eq!(f.covered_count(), 16 * 16);
    }
}

/// Rough timing of a 256x256 render of ~100k triangles: a heavy case, in `.ci/run`'s
/// optimised run (`--nocapture` shows the figures).
#[test]
fn heavy_timing_100k_triangles() {
    if !heavy() {
        return;
    }
    let r = renderer();
    // A 224 x 224 grid of quads on a wavy sheet: 100,352 triangles.
    let n = 224u32;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
            positions.push([
                u * 2.0 - 1.0,
                v * 2.0 - 1.0,
                0.1 * (u * 20.0).sin() * (v * 13.0).cos(),
            ]);
            normals.push([0.0, 0.0, 1.0]);
            uvs.push([u * 4.0, v * 4.0]);
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            indices.extend([a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]);
        }
    }
    let mut rgba = Vec::new();
    for y in 0..64u32 {
        for x in 0..64u32 {
            rgba.extend([
                x as u8 * 4,
                y as u8 * 4,
                128,
                if (x / 8 + y / 8) % 2 == 0 { 255 } else { 0 },
            ]);
        }
    }
    let s = DrawScene {
        meshes: vec![DrawMesh {
            positions,
            normals: Some(normals),
            tangents: None,
            uvs: Some(uvs),
            indices,
            material: 0,
        }],
        materials: vec![DrawMaterial {
            wrap: Default::default(),
            base_color: [1.0; 4],
            texture: Some(0),
            normal_texture: None,
            alpha: DrawAlpha::Mask(0.5),
            double_sided: true,
        }],
        textures: vec![DrawTexture {
            width: 64,
            height: 64,
            rgba,
        }],
    };
    let triangles = s.meshes[0].indices.len() / 3;
    let (min, max) = s.bounds().expect("bounds");
    let camera = Camera::framing(
        min,
        max,
        20.0,
        30.0,
        Projection::Perspective { fov_y_deg: 40.0 },
    );
    let _warm = r.render(&s, &camera, 256, 256, BLUE).expect("render");
    let runs = 5;
    let start = std::time::Instant::now();
    for _ in 0..runs {
        let frame = r.render(&s, &camera, 256, 256, BLUE).expect("render");
        assert!(frame.covered_count() > 0);
    }
    let per = start.elapsed() / runs;
    eprintln!(
        "{}: {triangles} triangles at 256x256: {per:?} per render",
        r.adapter_info()
    );

    // 1M+ triangles in one mesh also render (u32 indices, buffers within limits).
    let n = 710u32;
    let mut positions = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for j in 0..=n {
        for i in 0..=n {
            positions.push([i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5, 0.0]);
        }
    }
    let mut indices = Vec::with_capacity((n * n * 6) as usize);
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            indices.extend([a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]);
        }
    }
    let big = scene(
        vec![DrawMesh {
            positions,
            indices,
            ..Default::default()
        }],
        vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
    );
    let start = std::time::Instant::now();
    let frame = r
        .render(&big, &ortho(0.0, 1.0), 256, 256, BLUE)
        .expect("render 1M triangles");
    eprintln!(
        "{} triangles at 256x256: {:?}",
        big.meshes[0].indices.len() / 3,
        start.elapsed()
    );
    assert_eq!(frame.covered_count(), 128 * 128);
}

/// A posed tree reposed at another time is the scene `tree_scene` builds at that time, vertex
/// for vertex: the flip-books and metric frames that repose one scene draw what they would
/// have drawn rebuilding it.
#[test]
fn reposing_a_tree_equals_building_its_scene_at_that_time() {
    use frond_render::{PosedTree, TreeParts, tree_scene};
    use frond_scene::generator::{Preset, generate};
    let g = generate(Preset::Small, 3).expect("generates");
    let tree = frond_scene::import_bytes(
        std::path::Path::new("small.glb"),
        &g.glb,
        &frond_scene::ImportOptions::default(),
    )
    .expect("imports");
    let clip = tree.clip_index(None);
    for parts in [TreeParts::All, TreeParts::Foliage] {
        let mut posed = PosedTree::new(&tree, clip, 0.0, parts);
        assert_eq!(posed.scene(), &tree_scene(&tree, clip, 0.0, parts));
        for t in [0.7, 1.9] {
            let expected = tree_scene(&tree, clip, t, parts);
            assert_eq!(posed.pose(clip, t), &expected, "t = {t}");
        }
        assert_ne!(
            tree_scene(&tree, clip, 0.0, parts).meshes[0].positions,
            posed.scene().meshes[0].positions,
            "the wind moves the tree"
        );
    }
}

/// Whether the heavy cases run ([`frond_testdata::heavy`]); else one skip line.
fn heavy() -> bool {
    frond_testdata::heavy(env!("CARGO_CRATE_NAME"))
}
