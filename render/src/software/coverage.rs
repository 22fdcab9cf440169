//! The coverage renders ([`render_coverage`], [`depth_complexity`] and both at once) and the
//! image they resolve to: a render's triangles set up and binned ([`Bands`]), its bands drawn
//! in parallel ([`Raster`]) and put together top to bottom.

use glam::Mat4;
use rayon::prelude::*;

use super::bands::{Bands, checked_target};
use super::raster::{Band, Raster, Shortcuts};
use super::textures::SoftwareTextures;
use crate::error::RenderError;
use crate::scene::DrawScene;

/// A coverage render resolved to pixels, top row first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverageImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples of each pixel (`supersample²`).
    pub samples_per_pixel: u32,
    /// `width · height` counts: how many of the pixel's samples are covered (something
    /// opaque drawn there, or passing its alpha test).
    pub samples: Vec<u16>,
    /// `width · height` sums: the coverage blended surfaces ([`DrawAlpha::Blend`](crate::DrawAlpha::Blend)) add
    /// to the pixel, in samples: over its samples that `samples` does not count,
    /// `Σ 1 − Π(1 − αᵢ)` of the blended layers over each. Empty when the scene draws no
    /// blended material.
    pub blended: Vec<f32>,
    /// `width · height` mean linear RGB of the pixel's covered samples (zero where none is);
    /// empty unless colour was asked for ([`SoftwareTextures::new`]).
    pub colour: Vec<[f32; 3]>,
}

impl CoverageImage {
    /// Pixel `i`'s covered samples: those counted, and what blended layers add.
    pub fn covered_samples(&self, i: usize) -> f32 {
        f32::from(self.samples[i]) + self.blended.get(i).copied().unwrap_or(0.0)
    }

    /// The fraction of pixel `i` covered, 0..1: what MSAA, alpha-to-coverage or a distant
    /// eye shows of it (blended layers counting their alpha).
    pub fn covered_fraction(&self, i: usize) -> f32 {
        self.covered_samples(i) / self.samples_per_pixel as f32
    }

    /// Whether at least half of pixel `i` is covered (spec animated-billboard-clouds §5.4's
    /// binary pixel).
    pub fn is_covered(&self, i: usize) -> bool {
        match self.blended.get(i) {
            None => 2 * u32::from(self.samples[i]) >= self.samples_per_pixel,
            Some(_) => 2.0 * self.covered_samples(i) >= self.samples_per_pixel as f32,
        }
    }
}

/// Renders `scene` through `view_proj` (wgpu clip space, as [`crate::Renderer::render_view`])
/// at `width`×`height` pixels of `supersample`² samples each, with `textures` prepared from
/// `scene.textures`, and resolves the samples to pixels (see [`CoverageImage`]).
pub fn render_coverage(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<CoverageImage, RenderError> {
    rasterise(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        Shortcuts::ALL,
    )
    .map(|r| r.0)
}

/// The depth complexity of `scene` seen through `view_proj` at `width`×`height` pixels of
/// `supersample`² samples: fragments rasterised (every sample inside a drawn triangle, before
/// the alpha test discards any: each one runs the fragment shader, since alpha-tested surfaces
/// defeat early depth rejection, and blended ones write no depth) per covered sample, a
/// blended layer's sample counting its coverage; 0 when nothing is covered. The overdraw an
/// engine pays for alpha-tested foliage, whatever the draw order. The fragments are counted as
/// the drawn triangles' area in samples (after depth clipping and culling; a part outside the
/// image's sides counts too), which the samples inside them match up to their edges: counting
/// them one by one would mean testing every sample, covered or not.
pub fn depth_complexity(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<f64, RenderError> {
    render_coverage_with_depth(scene, textures, view_proj, width, height, supersample).map(|r| r.1)
}

/// [`render_coverage`] and [`depth_complexity`] of the same render at once: the same mask, and
/// the same depth complexity. The metric's first (view, frame) pair gives both, one render fewer.
pub fn render_coverage_with_depth(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<(CoverageImage, f64), RenderError> {
    let (image, fragments, covered) = rasterise(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        Shortcuts::ALL,
    )?;
    // Blended layers cover their alpha of a sample (none where nothing is blended).
    let blended: f64 = image.blended.iter().map(|&b| f64::from(b)).sum();
    let covered = covered as f64 + blended;
    let depth = if covered == 0.0 {
        0.0
    } else {
        fragments / covered
    };
    Ok((image, depth))
}

/// [`render_coverage`], the drawn triangles' area in samples, and the samples covered.
pub(super) fn rasterise(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    [width, height, supersample]: [u32; 3],
    shortcuts: Shortcuts,
) -> Result<(CoverageImage, f64, u64), RenderError> {
    let (sw, sh) = checked_target(scene, textures, view_proj, [width, height, supersample])?;
    let ss = supersample.max(1);
    let bands = Bands::new(scene, textures, view_proj, [sw, sh], ss as usize);
    let raster = Raster::new(scene, textures, &bands, sw, ss as usize, shortcuts);
    let band_rows = bands.rows;
    let resolved: Vec<Band> = (bands.bins.par_iter())
        .enumerate()
        .map(|(b, bin)| raster.band(b * band_rows, ((b + 1) * band_rows).min(sh), bin))
        .collect();
    let mut image = CoverageImage {
        width,
        height,
        samples_per_pixel: ss * ss,
        samples: Vec::with_capacity(width as usize * height as usize),
        blended: Vec::new(),
        colour: Vec::new(),
    };
    let mut covered_samples = 0;
    for band in resolved {
        image.samples.extend(band.samples);
        image.blended.extend(band.blended);
        image.colour.extend(band.colour);
        covered_samples += band.covered_samples;
    }
    let area: f64 = (bands.triangles.iter())
        .map(|t| 0.5 / f64::from(t.inv_area))
        .sum();
    Ok((image, area, covered_samples))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::pipeline::LIGHT_DIRECTION;
    use crate::scene::{DrawAlpha, DrawMaterial, DrawTexture};
    use crate::software::shading::Lighting;
    use crate::software::test_scenes::{count, leaf_alpha, quad};

    fn render(scene: &DrawScene, colour: bool, ss: u32) -> CoverageImage {
        let textures = SoftwareTextures::new(scene, colour).expect("textures");
        render_coverage(scene, &textures, Mat4::IDENTITY, 40, 30, ss).expect("render")
    }

    #[test]
    fn a_full_screen_quad_covers_every_pixel_and_a_half_one_half() {
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
            textures: vec![],
        };
        let full = render(&scene, true, 2);
        assert_eq!((full.width, full.height, count(&full)), (40, 30, 1200));
        assert!(full.colour.iter().all(|c| *c == [1.0, 0.0, 0.0]));
        scene.meshes = vec![quad(-1.0, 0.0, 0.5, false, 0)];
        let half = render(&scene, false, 4);
        assert_eq!(count(&half), 600);
        assert!(half.colour.is_empty(), "no colour asked for");
        // The left half, row by row.
        assert!((0..30).all(|y| (0..40).all(|x| half.is_covered(y * 40 + x) == (x < 20))));
    }

    #[test]
    fn a_normal_map_turns_the_shading_normal_in_the_tangent_frame() {
        // A white quad facing +z (normal +z, tangent +x, bitangent +y), its map tilting the
        // normal by 37° towards +y: shaded with the tilted normal, and with the tangent's w
        // negative (bitangent −y) tilted the other way.
        let tilted = Vec3::new(0.0, 0.6, 0.8);
        let texel = [
            128u8,
            (255.0 * (0.6 + 1.0) / 2.0) as u8,
            (255.0 * 1.8 / 2.0) as u8,
            255,
        ];
        let light = Vec3::from(LIGHT_DIRECTION);
        let shade_of = |sign: Option<f32>| {
            let mut mesh = quad(-1.0, 1.0, 0.5, false, 0);
            mesh.normals = Some(vec![[0.0, 0.0, 1.0]; 4]);
            mesh.tangents = sign.map(|w| vec![[1.0, 0.0, 0.0, w]; 4]);
            let scene = DrawScene {
                meshes: vec![mesh],
                materials: vec![DrawMaterial {
                    normal_texture: Some(0),
                    ..DrawMaterial::opaque([1.0; 4])
                }],
                textures: vec![DrawTexture {
                    width: 4,
                    height: 4,
                    rgba: texel.repeat(16),
                }],
            };
            render(&scene, true, 1).colour[600][0]
        };
        let expect = |n: Vec3| 0.6 + 0.4 * n.normalize().dot(light).abs();
        let decoded = Vec3::new(
            f32::from(texel[0]),
            f32::from(texel[1]),
            f32::from(texel[2]),
        ) * (2.0 / 255.0)
            - Vec3::ONE;
        assert!((decoded - tilted).length() < 0.01);
        assert!((shade_of(Some(1.0)) - expect(decoded)).abs() < 1e-4);
        let mirrored = Vec3::new(decoded.x, -decoded.y, decoded.z);
        assert!((shade_of(Some(-1.0)) - expect(mirrored)).abs() < 1e-4);
        // Without tangents the map does not apply: the vertex normal's shade, visibly other.
        assert!((shade_of(None) - expect(Vec3::Z)).abs() < 1e-4);
        assert!((expect(decoded) - expect(Vec3::Z)).abs() > 0.1);
    }

    #[test]
    fn lambert_lights_the_side_facing_the_viewer() {
        // A double-sided quad: Lambert lights the normal of the side drawn (a back face's
        // normal flipped, as GPUs do for double-sided materials), two-sided lighting ignores
        // the normal's sign.
        let light = Vec3::from(LIGHT_DIRECTION);
        let shade = |flip: bool, normal: [f32; 3], lighting: Lighting| {
            let mut mesh = quad(-1.0, 1.0, 0.5, flip, 0);
            mesh.normals = Some(vec![normal; 4]);
            let scene = DrawScene {
                meshes: vec![mesh],
                materials: vec![DrawMaterial {
                    double_sided: true,
                    ..DrawMaterial::opaque([1.0; 4])
                }],
                textures: vec![],
            };
            let textures = SoftwareTextures::new(&scene, true)
                .expect("textures")
                .with_lighting(lighting);
            render_coverage(&scene, &textures, Mat4::IDENTITY, 40, 30, 1)
                .expect("render")
                .colour[600][0]
        };
        let lit = 0.3 + 0.7 * light.z.max(0.0);
        // Front face with its normal towards the light's side, and a back face whose stored
        // normal points away: both show the lit side.
        assert!((shade(false, [0.0, 0.0, 1.0], Lighting::Lambert) - lit).abs() < 1e-4);
        assert!((shade(true, [0.0, 0.0, -1.0], Lighting::Lambert) - lit).abs() < 1e-4);
        // A front face whose normal points away from the viewer and the light: ambient only.
        assert!((shade(false, [0.0, 0.0, -1.0], Lighting::Lambert) - 0.3).abs() < 1e-4);
        let two_sided = 0.6 + 0.4 * light.z.abs();
        assert!((shade(false, [0.0, 0.0, -1.0], Lighting::TwoSided) - two_sided).abs() < 1e-4);
    }

    #[test]
    fn depth_complexity_counts_every_layer_drawn() {
        // Three full-screen layers, and a half-screen fourth: 3.5 fragments per covered sample.
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.2, false, 0),
                quad(-1.0, 1.0, 0.4, false, 0),
                quad(-1.0, 1.0, 0.6, false, 0),
                quad(-1.0, 0.0, 0.8, false, 0),
            ],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        let d = depth_complexity(&scene, &textures, Mat4::IDENTITY, 40, 30, 2).expect("count");
        assert!((d - 3.5).abs() < 1e-6, "{d}");
        let empty = DrawScene {
            meshes: vec![],
            ..scene.clone()
        };
        let d = depth_complexity(&empty, &textures, Mat4::IDENTITY, 40, 30, 2).expect("count");
        assert_eq!(d, 0.0);
    }

    /// The mean covered fraction of `image`'s pixels.
    fn mean_fraction(image: &CoverageImage) -> f32 {
        let n = image.samples.len();
        (0..n).map(|i| image.covered_fraction(i)).sum::<f32>() / n as f32
    }

    fn blended(alpha: f32) -> DrawMaterial {
        DrawMaterial {
            alpha: DrawAlpha::Blend,
            ..DrawMaterial::opaque([1.0, 0.0, 0.0, alpha])
        }
    }

    #[test]
    fn a_blended_quad_covers_its_alpha_and_overlapping_layers_compose() {
        // One 30 % quad over the whole image: every pixel 30 % covered, none by the binary
        // rule; its colour is its own.
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![blended(0.3)],
            textures: vec![],
        };
        let one = render(&scene, true, 4);
        assert!((0..1200).all(|i| (one.covered_fraction(i) - 0.3).abs() < 0.005));
        assert_eq!((count(&one), one.samples.iter().sum::<u16>()), (0, 0));
        assert!(one.colour.iter().all(|c| *c == [1.0, 0.0, 0.0]));
        // Two 50 % quads, in either order: 1 − ½ · ½ = 75 %.
        scene.materials = vec![blended(0.5)];
        scene.meshes = vec![
            quad(-1.0, 1.0, 0.5, false, 0),
            quad(-1.0, 1.0, 0.3, false, 0),
        ];
        let two = render(&scene, false, 4);
        assert!(
            (mean_fraction(&two) - 0.75).abs() < 0.005,
            "{}",
            mean_fraction(&two)
        );
        assert_eq!(count(&two), 1200);
        // An opaque quad covers its half whatever is blended over or behind it, and the
        // blended quad alone the other half.
        scene
            .materials
            .push(DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0]));
        scene.meshes = vec![
            quad(-1.0, 1.0, 0.5, false, 0),
            quad(-1.0, 0.0, 0.7, false, 1),
        ];
        let over = render(&scene, true, 4);
        for x in [0, 19, 20, 39] {
            let expected = if x < 20 { 1.0 } else { 0.5 };
            assert!(
                (over.covered_fraction(x) - expected).abs() < 0.005,
                "pixel {x}"
            );
        }
        assert_eq!(over.colour[0], [0.0, 0.0, 1.0], "the opaque quad's colour");
    }

    #[test]
    fn a_blended_texture_is_minified_as_its_area_average() {
        // A 64×64 texture of alternating clear and opaque columns, drawn over the whole
        // image at 40×30 pixels of one sample: every sample reads a level whose texels
        // average half covered, so the quad covers half of the image. Alpha-tested, the
        // same texture keeps its coverage by the test's rule instead (every pixel or none).
        let rgba: Vec<u8> = (0..64 * 64)
            .flat_map(|i| [255, 255, 255, if i % 2 == 0 { 255 } else { 0 }])
            .collect();
        let material = |alpha| DrawMaterial {
            texture: Some(0),
            alpha,
            double_sided: true,
            ..DrawMaterial::opaque([1.0; 4])
        };
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![material(DrawAlpha::Blend)],
            textures: vec![DrawTexture {
                width: 64,
                height: 64,
                rgba,
            }],
        };
        let blend = render(&scene, false, 1);
        assert!(
            (mean_fraction(&blend) - 0.5).abs() < 0.01,
            "{}",
            mean_fraction(&blend)
        );
        scene.materials = vec![material(DrawAlpha::Mask(0.5))];
        let mask = render(&scene, false, 1);
        assert!((0..1200).all(|i| [0.0, 1.0].contains(&mask.covered_fraction(i))));
    }

    #[test]
    fn back_faces_are_culled_unless_double_sided() {
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, true, 0)],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        assert_eq!(count(&render(&scene, false, 1)), 0);
        scene.materials[0].double_sided = true;
        assert_eq!(count(&render(&scene, false, 1)), 1200);
    }

    #[test]
    fn the_alpha_test_keeps_the_opaque_texels_and_depth_picks_the_nearest_colour() {
        // A 64×2 texture, opaque on its right half; mip-mapped, as the GPU path draws it.
        let rgba: Vec<u8> = (0..2)
            .flat_map(|_| (0..64).flat_map(|x| [0, 255, 0, if x >= 32 { 255 } else { 0 }]))
            .collect();
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.5, false, 0),
                quad(-1.0, 1.0, 0.7, false, 1),
            ],
            materials: vec![
                DrawMaterial {
                    texture: Some(0),
                    alpha: DrawAlpha::Mask(0.5),
                    ..DrawMaterial::opaque([1.0; 4])
                },
                DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0]),
            ],
            textures: vec![DrawTexture {
                width: 64,
                height: 2,
                rgba,
            }],
        };
        let leaf_only = DrawScene {
            meshes: scene.meshes[..1].to_vec(),
            ..scene.clone()
        };
        assert_eq!(count(&render(&leaf_only, false, 4)), 600);
        // Behind the leaf, a blue wall: green where the leaf is opaque, blue elsewhere.
        let both = render(&scene, true, 1);
        assert_eq!(count(&both), 1200);
        assert_eq!(both.colour[5], [0.0, 0.0, 1.0]);
        assert_eq!(both.colour[35], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn geometry_behind_the_near_plane_is_clipped() {
        // Half of the quad's depth range is in front of the near plane (z ≥ 0).
        let mut mesh = quad(-1.0, 1.0, 0.5, false, 0);
        mesh.positions = vec![
            [-1.0, -1.0, -0.5],
            [1.0, -1.0, -0.5],
            [1.0, 1.0, 0.5],
            [-1.0, 1.0, 0.5],
        ];
        let scene = DrawScene {
            meshes: vec![mesh],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        // z crosses 0 at y = 0: the upper half stays.
        let image = render(&scene, false, 2);
        assert_eq!(count(&image), 600);
        assert!(image.is_covered(0) && !image.is_covered(1199));
    }

    #[test]
    fn bad_sizes_and_unprepared_textures_are_errors() {
        let scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        assert!(render_coverage(&scene, &textures, Mat4::IDENTITY, 0, 10, 1).is_err());
        assert!(render_coverage(&scene, &textures, Mat4::IDENTITY, 40_000, 10, 1).is_err());
        assert!(render_coverage(&scene, &textures, Mat4::NAN, 10, 10, 1).is_err());
        let mut textured = scene.clone();
        textured.textures.push(DrawTexture {
            width: 1,
            height: 1,
            rgba: vec![255; 4],
        });
        assert!(render_coverage(&textured, &textures, Mat4::IDENTITY, 10, 10, 1).is_err());
        textured.textures[0].rgba.pop();
        assert!(SoftwareTextures::new(&textured, false).is_err());
    }

    /// Textures prepared for the bake (RGBA levels with their alpha's bounds) draw a colour
    /// render exactly as the colour preparation does: the coverage renders' alpha-only bounds
    /// never apply to RGBA levels.
    #[test]
    fn bake_prepared_textures_draw_colour_renders_unchanged() {
        let (w, h, alpha) = leaf_alpha();
        let scene = DrawScene {
            meshes: vec![quad(-0.9, 0.8, 0.4, false, 0)],
            materials: vec![DrawMaterial {
                texture: Some(0),
                alpha: DrawAlpha::Mask(0.5),
                ..DrawMaterial::opaque([1.0; 4])
            }],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba: alpha.iter().flat_map(|&a| [40, 180, 70, a]).collect(),
            }],
        };
        let colour = SoftwareTextures::new(&scene, true).expect("textures");
        let bake = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let draw = |t: &SoftwareTextures| {
            render_coverage(&scene, t, Mat4::IDENTITY, 60, 40, 2).expect("render")
        };
        let image = draw(&colour);
        let covered = count(&image);
        assert!(
            covered > 100 && covered < 60 * 40,
            "{covered} pixels covered"
        );
        assert_eq!(draw(&bake), image);
    }
}
