//! `Renderer::render_view`: explicit view-projection matrices and normal output.
//!
//! Runs on whatever adapter the machine has (llvmpipe in CI) and fails when none exists.

use frond_render::{
    Camera, DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture, Frame, Output, Projection,
    RenderError,
};
use glam::camera::rh::{proj::directx, view};
use glam::{Mat4, Vec3};

mod common;
use common::renderer;

/// Axis-aligned rectangle facing +Z at depth `z`, counter-clockwise seen from +Z.
fn rect_z(min: [f32; 2], max: [f32; 2], z: f32) -> DrawMesh {
    common::quad_z(min, max, z, 0)
}

fn one_mesh(mesh: DrawMesh, material: DrawMaterial) -> DrawScene {
    DrawScene {
        meshes: vec![mesh],
        materials: vec![material],
        textures: vec![],
    }
}

/// Looking down -Z from the origin: x in [-2, 2] and y in [-1, 3] fill the image.
fn ortho_window() -> Mat4 {
    directx::orthographic(-2.0, 2.0, -1.0, 3.0, 0.5, 10.0)
}

/// World point (x, y) seen through [`ortho_window`] at pixel centre (px, py) of a 64x64 image.
fn world_of_pixel(px: u32, py: u32) -> (f32, f32) {
    let nx = (px as f32 + 0.5) / 64.0 * 2.0 - 1.0;
    let ny = 1.0 - (py as f32 + 0.5) / 64.0 * 2.0;
    (nx * 2.0, ny * 2.0 + 1.0)
}

#[test]
fn explicit_orthographic_matrix_covers_the_expected_pixels() {
    let r = renderer();
    let green = DrawMaterial::opaque([0.0, 1.0, 0.0, 1.0]);
    // x in [-1, 1], y in [0, 1] -> columns 16..48, rows 32..48 of a 64x64 image.
    let s = one_mesh(rect_z([-1.0, 0.0], [1.0, 1.0], -1.0), green);
    let frame = r
        .render_view(
            &s,
            ortho_window(),
            64,
            64,
            [0.0, 0.0, 1.0, 1.0],
            Output::Color,
        )
        .expect("render");
    for py in 0..64 {
        for px in 0..64 {
            let (x, y) = world_of_pixel(px, py);
            let inside = (-1.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y);
            assert_eq!(frame.covered(px, py), inside, "pixel ({px},{py})");
            let want = if inside {
                [0, 255, 0, 255]
            } else {
                [0, 0, 255, 255]
            };
            assert_eq!(frame.pixel(px, py), want, "pixel ({px},{py})");
        }
    }
    assert_eq!(frame.covered_count(), 32 * 16);

    // Depth is the caller's job: geometry beyond the far plane is clipped away.
    let far = one_mesh(
        rect_z([-1.0, 0.0], [1.0, 1.0], -20.0),
        DrawMaterial::default(),
    );
    let frame = r
        .render_view(&far, ortho_window(), 64, 64, [0.0; 4], Output::Color)
        .expect("render");
    assert_eq!(frame.covered_count(), 0);
}

#[test]
fn render_view_with_the_camera_matrix_matches_render() {
    let r = renderer();
    let mut mesh = rect_z([-1.0, -0.5], [0.7, 1.0], 0.2);
    mesh.normals = Some(vec![[0.0, 0.0, 1.0]; 4]);
    let s = DrawScene {
        meshes: vec![mesh],
        materials: vec![DrawMaterial {
            texture: Some(0),
            double_sided: true,
            ..DrawMaterial::default()
        }],
        textures: vec![DrawTexture {
            width: 2,
            height: 2,
            rgba: vec![
                255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255,
            ],
        }],
    };
    let camera = Camera {
        target: Vec3::ZERO,
        azimuth_deg: 25.0,
        elevation_deg: 15.0,
        distance: 5.0,
        projection: Projection::Perspective { fov_y_deg: 45.0 },
    };
    let (min, max) = s.bounds().expect("bounds");
    let view_proj = camera.view_proj_for_bounds(48.0 / 40.0, min, max);
    let a = r.render(&s, &camera, 48, 40, [0.1; 4]).expect("render");
    let b = r
        .render_view(&s, view_proj, 48, 40, [0.1; 4], Output::Color)
        .expect("render");
    assert!(a.covered_count() > 200);
    assert_eq!(a, b);
}

fn centre(frame: &Frame) -> [u8; 4] {
    frame.pixel(frame.width / 2, frame.height / 2)
}

fn assert_near(got: [u8; 4], want: [u8; 4], what: &str) {
    for k in 0..4 {
        assert!(got[k].abs_diff(want[k]) <= 1, "{what}: {got:?} vs {want:?}");
    }
}

#[test]
fn normal_output_encodes_the_side_facing_the_viewer() {
    let r = renderer();
    let front = ortho_window(); // looks down -Z: sees the +Z side
    let back = directx::orthographic(-2.0, 2.0, -1.0, 3.0, 0.5, 10.0)
        * view::look_at_mat4(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO, Vec3::Y); // sees the -Z side
    let double_sided = DrawMaterial {
        double_sided: true,
        ..DrawMaterial::opaque([0.3, 0.2, 0.1, 1.0])
    };
    let bg = [0.0; 4];
    // Face normals (no vertex normals) and given vertex normals behave alike.
    let face = rect_z([-2.0, -1.0], [2.0, 3.0], -1.0);
    let mut given = face.clone();
    given.normals = Some(vec![[0.0, 0.0, 1.0]; 4]);
    for mesh in [face, given] {
        let s = one_mesh(mesh, double_sided.clone());
        let seen = r
            .render_view(&s, front, 16, 16, bg, Output::Normal)
            .expect("render");
        assert_eq!(seen.covered_count(), 256);
        assert_near(centre(&seen), [128, 128, 255, 255], "front");
        assert!(
            seen.rgba
                .chunks_exact(4)
                .all(|p| p == seen.rgba[..4].to_vec())
        );

        let behind = r
            .render_view(&s, back, 16, 16, bg, Output::Normal)
            .expect("render");
        assert_eq!(behind.covered_count(), 256);
        assert_near(centre(&behind), [128, 128, 0, 255], "back face flipped");

        // Single-sided: the back is culled, nothing is written but the background.
        let culled = one_mesh(s.meshes[0].clone(), DrawMaterial::default());
        let none = r
            .render_view(&culled, back, 16, 16, [0.5, 0.25, 0.0, 0.0], Output::Normal)
            .expect("render");
        assert_eq!(none.covered_count(), 0);
        // The normal target is linear: the clear colour is stored without sRGB encoding.
        assert_near(centre(&none), [128, 64, 0, 0], "linear background");
    }

    // A tilted face normal: the triangle in the plane x + z = 0 faces (1, 0, 1)/sqrt2.
    let tilted = DrawMesh {
        positions: vec![[-1.0, -1.0, 1.0], [1.0, -1.0, -1.0], [0.0, 2.0, 0.0]],
        indices: vec![0, 1, 2],
        ..Default::default()
    };
    let s = one_mesh(tilted, DrawMaterial::default());
    let view = directx::orthographic(-2.0, 2.0, -2.0, 2.0, 0.5, 10.0)
        * view::look_at_mat4(Vec3::new(3.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y);
    let frame = r
        .render_view(&s, view, 32, 32, bg, Output::Normal)
        .expect("render");
    let h = ((std::f32::consts::FRAC_1_SQRT_2 * 0.5 + 0.5) * 255.0).round() as u8;
    assert_near(centre(&frame), [h, 128, h, 255], "tilted");
}

#[test]
fn normal_output_keeps_the_alpha_test() {
    let r = renderer();
    // Left half transparent, right half opaque.
    let mut rgba = Vec::new();
    for _ in 0..4 {
        for x in 0..8 {
            rgba.extend([10, 20, 30, if x < 4 { 0 } else { 255 }]);
        }
    }
    let s = DrawScene {
        meshes: vec![rect_z([-2.0, -1.0], [2.0, 3.0], -1.0)],
        materials: vec![DrawMaterial {
            texture: Some(0),
            alpha: DrawAlpha::Mask(0.5),
            ..DrawMaterial::default()
        }],
        textures: vec![DrawTexture {
            width: 8,
            height: 4,
            rgba,
        }],
    };
    let color = r
        .render_view(&s, ortho_window(), 32, 32, [0.0; 4], Output::Color)
        .expect("render");
    let normal = r
        .render_view(&s, ortho_window(), 32, 32, [0.0; 4], Output::Normal)
        .expect("render");
    assert_eq!(color.coverage, normal.coverage);
    assert!((color.coverage_fraction() - 0.5).abs() < 2.0 / 32.0);
    assert!(!normal.covered(4, 16) && normal.covered(28, 16));
    assert_near(normal.pixel(28, 16), [128, 128, 255, 255], "opaque half");
}

#[test]
fn render_view_rejects_bad_input() {
    let r = renderer();
    let s = one_mesh(
        rect_z([-1.0, 0.0], [1.0, 1.0], -1.0),
        DrawMaterial::default(),
    );
    let nan = Mat4::from_cols_array(&[f32::NAN; 16]);
    assert!(matches!(
        r.render_view(&s, nan, 8, 8, [0.0; 4], Output::Color),
        Err(RenderError::InvalidCamera(_))
    ));
    assert!(matches!(
        r.render_view(&s, ortho_window(), 0, 8, [0.0; 4], Output::Normal),
        Err(RenderError::InvalidSize { .. })
    ));
    let mut bad = s.clone();
    bad.meshes[0].indices = vec![0, 1, 9];
    assert!(matches!(
        r.render_view(&bad, ortho_window(), 8, 8, [0.0; 4], Output::Normal),
        Err(RenderError::IndexOutOfRange { .. })
    ));
}

/// A 512² texture: left half opaque, right half transparent, plus 1-texel transparent
/// speckles in the opaque half (10 %), so point sampling at a distance aliases.
fn half_texture() -> DrawTexture {
    let n = 512u32;
    let mut rgba = vec![0u8; (n * n * 4) as usize];
    for y in 0..n {
        for x in 0..n {
            let o = ((y * n + x) * 4) as usize;
            let speckle = (x * 7 + y * 13) % 10 == 0;
            rgba[o..o + 4].copy_from_slice(&[
                40,
                160,
                40,
                if x < n / 2 && !speckle { 255 } else { 0 },
            ]);
        }
    }
    DrawTexture {
        width: n,
        height: n,
        rgba,
    }
}

#[test]
fn mipmapped_renders_keep_coverage_when_minified_and_change_nothing_magnified() {
    let r = renderer();
    let mut scene = one_mesh(
        rect_z([-2.0, -1.0], [2.0, 3.0], -1.0),
        DrawMaterial {
            texture: Some(0),
            alpha: DrawAlpha::Mask(0.5),
            double_sided: true,
            ..DrawMaterial::default()
        },
    );
    scene.textures.push(half_texture());
    let camera = Camera::framing(
        Vec3::new(-2.0, -1.0, -1.0),
        Vec3::new(2.0, 3.0, -1.0),
        0.0,
        0.0,
        Projection::Orthographic { half_height: 2.0 },
    );
    // Minified 32×: the left half stays covered (coverage-preserving mip levels), ≈ half the quad.
    let small = r
        .render_mipmapped(&scene, &camera, 16, 16, [0.0; 4])
        .expect("renders");
    let quad_pixels = small.covered_count() as f64;
    let quad_area = {
        let full = one_mesh(
            rect_z([-2.0, -1.0], [2.0, 3.0], -1.0),
            DrawMaterial::opaque([1.0; 4]),
        );
        r.render(&full, &camera, 16, 16, [0.0; 4])
            .expect("renders")
            .covered_count() as f64
    };
    let frac = quad_pixels / quad_area;
    assert!(
        (frac - 0.5).abs() <= 2.0 / 16.0 + 1e-9,
        "minified coverage {frac}"
    );
    // Magnified, mip level 0 is used: identical to the plain render.
    let a = r
        .render(&scene, &camera, 1024, 1024, [0.0; 4])
        .expect("renders");
    let b = r
        .render_mipmapped(&scene, &camera, 1024, 1024, [0.0; 4])
        .expect("renders");
    let differ = a
        .coverage
        .iter()
        .zip(&b.coverage)
        .filter(|(x, y)| x != y)
        .count();
    assert_eq!(differ, 0, "pixels differ at 2× magnification");
}
