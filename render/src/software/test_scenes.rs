//! Scenes and checks the CPU rasterisers' tests share: quads, leaf cards and a leaf-like
//! alpha, and the comparison of an alpha test with the filtered alpha it stands for.

use frond_scene::Wrap;
use glam::{Mat4, Vec3};

use super::alpha::passes_cutoff;
use super::coverage::CoverageImage;
use super::sampling::{Levels, Trilinear};
use crate::camera::{Camera, Projection};
use crate::scene::{DrawAlpha, DrawMaterial, DrawMesh, DrawScene, DrawTexture};

/// A quad over NDC `[x0, x1] × [-1, 1]` at depth `z`, counter-clockwise (front) unless
/// `flip`, with texture coordinates over the whole texture.
pub(super) fn quad(x0: f32, x1: f32, z: f32, flip: bool, material: usize) -> DrawMesh {
    let indices = if flip {
        vec![0, 2, 1, 0, 3, 2]
    } else {
        vec![0, 1, 2, 0, 2, 3]
    };
    DrawMesh {
        positions: vec![[x0, -1.0, z], [x1, -1.0, z], [x1, 1.0, z], [x0, 1.0, z]],
        normals: None,
        tangents: None,
        uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
        indices,
        material,
    }
}

pub(super) fn count(image: &CoverageImage) -> usize {
    (0..image.samples.len())
        .filter(|&i| image.is_covered(i))
        .count()
}

/// A 37×20 alpha: a disc of opaque texels with a soft rim, and noise — every kind of
/// footprint (a leaf's hard and soft edges).
pub(super) fn leaf_alpha() -> (u32, u32, Vec<u8>) {
    let (w, h) = (37u32, 20u32);
    let alpha = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 - 18.0, (i / w) as f32 - 10.0);
            let r = (x * x + y * y).sqrt();
            let noise = (i.wrapping_mul(2_654_435_761) >> 27) as f32;
            (255.0 - (r - 6.0).max(0.0) * 40.0 + noise).clamp(0.0, 255.0) as u8
        })
        .collect();
    (w, h, alpha)
}

/// A perspective view of `cards` random leaf cards (random sizes, so that many mip levels
/// and trilinear blends are drawn; texture coordinates reaching past the edges under each
/// wrap mode; alpha tests with several cutoffs and scales, and an opaque material).
pub(super) fn random_cards(cards: usize, seed: u64) -> (DrawScene, Mat4) {
    let mut state = seed;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let (w, h, alpha) = leaf_alpha();
    let rgba = alpha.iter().flat_map(|&a| [40, 160, 30, a]).collect();
    let wraps = [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat];
    let mut materials: Vec<DrawMaterial> = (0..9)
        .map(|m| DrawMaterial {
            texture: Some(0),
            alpha: DrawAlpha::Mask([0.3, 0.5, 0.8][m % 3]),
            base_color: [1.0, 1.0, 1.0, [1.0, 0.7, 1.3][m / 3]],
            double_sided: true,
            wrap: [wraps[m % 3], wraps[m / 3]],
            ..DrawMaterial::opaque([1.0; 4])
        })
        .collect();
    materials.push(DrawMaterial::opaque([1.0; 4]));
    let meshes = (0..cards)
        .map(|i| {
            let centre = Vec3::new(next() * 8.0 - 4.0, next() * 6.0 - 3.0, next() * 9.0);
            let size = 0.02 + next() * next() * 2.0;
            let (a, b) = (next() * 6.3, next() * 6.3);
            let right = Vec3::new(a.cos(), a.sin() * b.cos(), a.sin() * b.sin()) * size;
            let up = right.any_orthonormal_vector() * size;
            let corners =
                [-right - up, right - up, right + up, -right + up].map(|c| (centre + c).to_array());
            // Mostly the unit square, sometimes shifted or scaled past it.
            let (off, span) = if i % 4 == 0 {
                (next() * 2.0 - 1.0, 0.5 + next() * 2.0)
            } else {
                (0.0, 1.0)
            };
            DrawMesh {
                positions: corners.to_vec(),
                normals: None,
                tangents: None,
                uvs: Some(
                    [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
                        .map(|[u, v]| [off + u * span, off + v * span])
                        .to_vec(),
                ),
                indices: vec![0, 1, 2, 0, 2, 3],
                material: i % materials.len(),
            }
        })
        .collect();
    let scene = DrawScene {
        meshes,
        materials,
        textures: vec![DrawTexture {
            width: w,
            height: h,
            rgba,
        }],
    };
    let (min, max) = scene.bounds().expect("cards");
    let camera = Camera::framing(
        min,
        max,
        20.0,
        10.0,
        Projection::Perspective { fov_y_deg: 50.0 },
    );
    let view_proj = camera.view_proj_for_bounds(4.0 / 3.0, min, max);
    (scene, view_proj)
}

/// Asserts that `test` (uv, level pair, wrap, `[scale, cutoff]`) answers as the `filtered`
/// alpha does, at level pairs of `levels` from `lods`, inside and across the edges under
/// each wrap, at cutoffs and scales around the alphas, many of them soft (between the
/// extremes: not only footprints the bounds settle outright).
pub(super) fn assert_alpha_tests_match(
    levels: &Levels,
    lods: [f32; 6],
    filtered: impl Fn([f32; 2], Trilinear, Wrap) -> f32,
    test: impl Fn([f32; 2], Trilinear, Wrap, [f32; 2]) -> bool,
) {
    let mut soft = 0;
    let mut tests = 0;
    for wrap in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
        for lod in lods {
            let pair = levels.pair(lod);
            for k in 0..4000u32 {
                let uv = [(k % 80) as f32 / 53.0 - 0.3, (k / 80) as f32 / 37.0 - 0.2];
                let alpha = filtered(uv, pair, wrap);
                for (scale, cutoff) in
                    [(1.0, 0.5), (0.8, 0.3), (1.0, 1.0), (1.0, 0.0), (-0.5, -0.2)]
                {
                    let expected = passes_cutoff(alpha * scale, cutoff);
                    let got = test(uv, pair, wrap, [scale, cutoff]);
                    assert_eq!(got, expected, "{wrap:?} lod {lod} uv {uv:?} {cutoff}");
                    tests += 1;
                    soft += usize::from(alpha > 0.0 && alpha < 1.0);
                }
            }
        }
    }
    assert!(soft > tests / 20, "{soft} of {tests}");
}
