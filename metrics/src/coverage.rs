//! The coverage ("colour") metric (spec animated-billboard-clouds §5.4, §8.2, §11 item 7).
//!
//! The original foliage and its simplification are rendered as binary coverage masks from `D`
//! views on a ring around the tree and for `F` frames. Each (view, frame) pair scores
//! `Σ_p |o_p − s_p| / P_f`, the number of pixels where exactly one of the two renders has
//! foliage divided by the number of foliage pixels `P_f` of the original. Pairs scoring above 1
//! (the simplification is judged to have no fidelity there) or with `P_f = 0` are discarded;
//! the metric is the mean of the rest. The static metric is the case `F = 1`.
//!
//! # Camera rule
//!
//! View `d` of `D` looks at the centre `c` of the caller's bounds from azimuth `360°·d/D`
//! (the [`frond_render::Camera`] convention: azimuth 0 is on +Z, 90 on +X) and elevation
//! [`CoverageParams::elevation_deg`], with a perspective projection of vertical field of view
//! `φ` = [`CoverageParams::fov_y_deg`]. The distance is the smallest one that keeps all eight
//! corners of the bounds inside the vertical field of view:
//!
//! ```text
//! distance = max over corners k of ( |r_k · up| / tan(φ/2) + r_k · dir ),   r_k = corner_k − c
//! ```
//!
//! where `up` is the camera's screen-up and `dir` its target-to-eye unit vector. The corner
//! attaining the maximum lies exactly on the top or bottom image edge, so the bounds' projected
//! vertical extent spans the image height (at elevation 0 the box is symmetric about the
//! view's horizontal plane and touches both edges). The image width plays no part: bounds wider
//! on screen than `width / height` times their projected height are cropped at the sides.
//! (A guard keeps every corner at least 0.1% of the bounds' half-diagonal in front of the eye;
//! it only acts for boxes that are almost flat as seen from the view.)
//!
//! Both renders of a pair use this one camera, computed from the bounds the caller passes (the
//! whole tree's rest bounds), never from either scene.

use frond_render::{
    Camera, DrawScene, Lighting, Projection, RenderError, Renderer, SoftwareTextures,
    render_coverage, render_coverage_with_depth,
};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Background colour of the metric renders; coverage does not depend on it.
const BACKGROUND: [f32; 4] = [0.0; 4];

/// Settings of the coverage metric; the defaults are the thesis' experiment setup (spec
/// animated-billboard-clouds §8.2): 5 views at ground level, 800×600 pixels, one frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageParams {
    /// Number of views `D`, evenly spread over a full turn. Odd counts are recommended (§8.2):
    /// opposite views of an even ring are near mirror images and add little information.
    pub views: u32,
    /// Number of frames `F`; the caller supplies one scene per frame for both models. 1 gives
    /// the static metric (§5.4); the thesis used 5 for animated comparisons (§8.2).
    pub frames: u32,
    /// Image width in pixels (800 in §8.2).
    pub width: u32,
    /// Image height in pixels (600 in §8.2); the tree's bounds span exactly this height.
    pub height: u32,
    /// Elevation of the view ring in degrees, within [-90, 90]; 0 is the thesis' ground-level
    /// viewer (§8.2).
    pub elevation_deg: f32,
    /// Vertical field of view of the perspective camera in degrees, within (0, 180).
    pub fov_y_deg: f32,
    /// Each image is rendered at `supersample`× its size and a pixel counts as covered when at
    /// least half of its samples are. Without it both masks carry the alpha-test aliasing of
    /// minified leaf textures, which alone gives an error even to a LOD whose billboards lie
    /// exactly on the leaves (ε = 0).
    pub supersample: u32,
    /// Which rasteriser draws the masks: the CPU one by default (fast, and the same numbers on
    /// every machine), the wgpu one on request (a GPU's own filtering and rasterisation rules).
    #[serde(default)]
    pub rasteriser: Rasteriser,
    /// Also compute the covered pixels' colour ([`CoverageReport::colour_difference`]); the
    /// coverage alone needs neither a depth test nor the textures' colour.
    #[serde(default = "yes")]
    pub colour: bool,
    /// How the colour renders are lit (the CPU rasteriser's; the wgpu one is two-sided).
    #[serde(default)]
    pub lighting: Lighting,
}

fn yes() -> bool {
    true
}

/// The rasteriser of the metric's renders.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Rasteriser {
    /// [`frond_render::render_coverage`]: the CPU rasteriser built for coverage renders.
    #[default]
    Software,
    /// [`Renderer::render_mipmapped`] on the renderer's adapter.
    Gpu,
}

impl Default for CoverageParams {
    /// 5 views, 1 frame, 800×600, elevation 0°, 40° vertical field of view (spec §8.2; the
    /// field of view is not given in the thesis).
    fn default() -> Self {
        Self {
            views: 5,
            frames: 1,
            width: 800,
            height: 600,
            elevation_deg: 0.0,
            fov_y_deg: 40.0,
            supersample: 4,
            rasteriser: Rasteriser::Software,
            colour: true,
            lighting: Lighting::TwoSided,
        }
    }
}

/// Result of [`coverage_error`] (spec animated-billboard-clouds §5.4). Per-pair vectors are
/// view-major: the entry of view `d`, frame `f` is at index `d · frames + f`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageReport {
    /// For each view, the mean score of its kept frames; NaN when all its frames were
    /// discarded.
    pub per_view: Vec<f64>,
    /// The metric: mean score over all kept (view, frame) pairs, 0 being perfect; NaN when
    /// every pair was discarded.
    pub mean: f64,
    /// Number of (view, frame) pairs discarded because they scored above 1 or the original
    /// covered no pixel (`P_f = 0`).
    pub discarded: usize,
    /// `P_f` per (view, frame): the original's covered pixels.
    pub original_pixels: Vec<u64>,
    /// `Σ_p |o_p − s_p|` per (view, frame): pixels covered by exactly one of the two renders.
    pub differing_pixels: Vec<u64>,
    /// Foreground colour error (the thesis' metric ignores colour): over the pixels covered in
    /// both renders, the mean absolute difference of linear RGB (mean of the three channels,
    /// 0..1), averaged over the (view, frame) pairs that share any pixel; NaN when none do.
    pub colour_difference: f64,
    /// That difference per (view, frame) pair; NaN for a pair sharing no pixel.
    pub colour_per_pair: Vec<f64>,
    /// The shift of the mean colour over the same pixels: per pair `|mean(o − s)|` (signed
    /// per pixel, mean of the three channels), averaged like `colour_difference`. What reads as
    /// one LOD being lighter or darker than the other (the pop at a switch), without the
    /// per-pixel differences that average out at a distance; NaN when no pair shares a pixel.
    #[serde(default)]
    pub colour_shift: f64,
}

/// Why the coverage metric could not be computed.
#[derive(Debug, Error)]
pub enum MetricError {
    /// [`CoverageParams::views`] is zero.
    #[error("the coverage metric needs at least one view")]
    NoViews,
    /// [`CoverageParams::frames`] is zero.
    #[error("the coverage metric needs at least one frame")]
    NoFrames,
    /// The image width or height is zero.
    #[error("invalid image size {width}x{height}: both sides must be at least 1 pixel")]
    InvalidSize {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
    },
    /// The number of scenes given differs from [`CoverageParams::frames`].
    #[error(
        "expected {expected} frame scene(s) per model, got {original} original and {simplified} simplified"
    )]
    FrameCountMismatch {
        /// [`CoverageParams::frames`].
        expected: u32,
        /// Number of original scenes given.
        original: usize,
        /// Number of simplified scenes given.
        simplified: usize,
    },
    /// A camera setting is out of range.
    #[error("invalid camera parameter: {0}")]
    InvalidParams(String),
    /// The bounds are not finite, inverted, or have no vertical extent from some view, so no
    /// camera can make them fill the image height.
    #[error("cannot frame bounds {min}..{max}: {reason}")]
    InvalidBounds {
        /// Minimum corner given.
        min: Vec3,
        /// Maximum corner given.
        max: Vec3,
        /// What is wrong with them.
        reason: String,
    },
    /// Rendering failed (bad scene data, no adapter, GPU error).
    #[error(transparent)]
    Render(#[from] RenderError),
    /// The renderer returned a coverage mask of the wrong size.
    #[error("coverage mask has {len} entries, expected {expected}")]
    MaskSize {
        /// Entries received.
        len: usize,
        /// `width · height`.
        expected: usize,
    },
}

/// Azimuth in degrees of view `view` of a ring of `views`: `360 · view / views`, so view 0 is
/// at azimuth 0 (spec §8.2: views evenly spread over a full rotation).
pub fn ring_azimuth_deg(view: u32, views: u32) -> f32 {
    if views == 0 {
        return 0.0;
    }
    (360.0 * f64::from(view) / f64::from(views)) as f32
}

/// The camera of view `view` (see the module docs for the rule): on the ring at
/// [`ring_azimuth_deg`], looking at the bounds' centre from the distance at which the bounds'
/// vertical extent spans the image height exactly. Exposed so callers can render the very
/// images the metric compares.
pub fn view_camera(
    bounds_min: Vec3,
    bounds_max: Vec3,
    view: u32,
    params: &CoverageParams,
) -> Result<Camera, MetricError> {
    validate_camera_params(params)?;
    let invalid = |reason: &str| MetricError::InvalidBounds {
        min: bounds_min,
        max: bounds_max,
        reason: reason.to_string(),
    };
    if !bounds_min.is_finite() || !bounds_max.is_finite() {
        return Err(invalid("not finite"));
    }
    if bounds_min.cmpgt(bounds_max).any() {
        return Err(invalid("min exceeds max"));
    }
    let target = (bounds_min + bounds_max) * 0.5;
    let mut camera = Camera {
        target,
        azimuth_deg: ring_azimuth_deg(view, params.views),
        elevation_deg: params.elevation_deg,
        // Placeholder; only the direction vectors are used until the distance is known.
        distance: 1.0,
        projection: Projection::Perspective {
            fov_y_deg: params.fov_y_deg,
        },
    };
    let (dir, up) = (camera.direction().as_dvec3(), camera.up().as_dvec3());
    let half = (bounds_max.as_dvec3() - bounds_min.as_dvec3()) * 0.5;
    let radius = half.length();
    let tan_half = (f64::from(params.fov_y_deg) * 0.5).to_radians().tan();
    let (mut fit, mut nearest, mut vertical) = (f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0f64);
    for k in 0..8 {
        let r = DVec3::new(
            if k & 1 == 0 { -half.x } else { half.x },
            if k & 2 == 0 { -half.y } else { half.y },
            if k & 4 == 0 { -half.z } else { half.z },
        );
        let (y, depth) = (r.dot(up).abs(), r.dot(dir));
        fit = fit.max(y / tan_half + depth);
        nearest = nearest.max(depth);
        vertical = vertical.max(y);
    }
    // The bounds were checked finite above, so neither value is NaN.
    if radius <= 0.0 || vertical <= 1e-6 * radius {
        return Err(invalid("no vertical extent seen from this view"));
    }
    let distance = fit.max(nearest + 1e-3 * radius) as f32;
    if !(distance.is_finite() && distance > 0.0) {
        return Err(invalid("no finite camera distance frames them"));
    }
    camera.distance = distance;
    Ok(camera)
}

/// The coverage metric of `simplified` against `original` (spec animated-billboard-clouds
/// §5.4, §11 item 7): binary coverage masks from `params.views` ring views and
/// `params.frames` frames, scored `Σ_p |o_p − s_p| / P_f` per (view, frame); pairs above 1 or
/// with `P_f = 0` are discarded and counted, the rest averaged.
///
/// `original[f]` and `simplified[f]` are the posed scenes of frame `f`. `bounds_min` and
/// `bounds_max` frame every view (see the module docs); pass the whole tree's rest bounds so
/// the camera is the same for both models and all frames. Renders run one after another in a
/// fixed order and pixel counts are integers, so the result is deterministic for a given
/// adapter.
pub fn coverage_error(
    renderer: &Renderer,
    original: &[DrawScene],
    simplified: &[DrawScene],
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &CoverageParams,
) -> Result<CoverageReport, MetricError> {
    validate(original.len(), simplified.len(), params)?;
    let o = coverage_masks(renderer, original, bounds_min, bounds_max, params)?;
    let s = coverage_masks(renderer, simplified, bounds_min, bounds_max, params)?;
    let frames: Vec<usize> = (0..original.len()).collect();
    compare_masks(&o, &s, &frames)
}

/// One model's binary coverage masks and covered colours for every (view, frame) pair of the
/// metric, so one model's renders can be compared with many others (a sweep renders the
/// original once).
#[derive(Clone, Debug)]
pub struct CoverageMasks {
    /// Pixels per mask.
    pub pixels: usize,
    /// Views of the ring.
    pub views: usize,
    /// Frames per view.
    pub frames: usize,
    /// View-major (`d · frames + f`): whether each pixel is covered.
    covered: Vec<Vec<bool>>,
    /// The same pairs: mean linear RGB of each pixel's covered samples (empty vectors when
    /// drawn without colour, [`CoverageParams::colour`]).
    colour: Vec<Vec<[f32; 3]>>,
    /// The depth complexity of the first view's first frame ([`depth_complexity`]), from its
    /// render; None from the wgpu rasteriser.
    pub first_depth_complexity: Option<f64>,
}

/// Renders the masks of `scenes` (one per frame) from every view of `params` (see
/// [`coverage_error`]).
pub fn coverage_masks(
    renderer: &Renderer,
    scenes: &[DrawScene],
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &CoverageParams,
) -> Result<CoverageMasks, MetricError> {
    validate(scenes.len(), scenes.len(), params)?;
    // Every camera is checked before the first (slow) render.
    let cameras = (0..params.views)
        .map(|d| view_camera(bounds_min, bounds_max, d, params))
        .collect::<Result<Vec<_>, _>>()?;
    let expected = params.width as usize * params.height as usize;
    let mut first_depth_complexity = None;
    let rendered: Vec<(Vec<bool>, Vec<[f32; 3]>)> = match params.rasteriser {
        Rasteriser::Gpu => cameras
            .iter()
            .flat_map(|camera| scenes.iter().map(move |scene| (camera, scene)))
            .map(|(camera, scene)| coverage_mask(renderer, scene, camera, params))
            .collect::<Result<_, _>>()?,
        Rasteriser::Software => {
            // Mip chains prepared once for the frames that share them (a model's frames do),
            // then every (view, frame) render at once: each is deterministic, and they are
            // collected in order.
            let mut prepared: Vec<SoftwareTextures> = Vec::new();
            let mut of_frame: Vec<usize> = Vec::with_capacity(scenes.len());
            for (f, scene) in scenes.iter().enumerate() {
                match (0..f).find(|&g| same_textures(&scenes[g], scene)) {
                    Some(g) => of_frame.push(of_frame[g]),
                    None => {
                        of_frame.push(prepared.len());
                        prepared.push(
                            SoftwareTextures::new(scene, params.colour)?
                                .with_lighting(params.lighting),
                        );
                    }
                }
            }
            let pairs: Vec<(usize, usize)> = (0..cameras.len())
                .flat_map(|d| (0..scenes.len()).map(move |f| (d, f)))
                .collect();
            let masks: Vec<SoftwareMask> = pairs
                .par_iter()
                .map(|&(d, f)| {
                    let first = (d, f) == (0, 0);
                    software_mask(
                        &scenes[f],
                        &prepared[of_frame[f]],
                        &cameras[d],
                        params,
                        first,
                    )
                })
                .collect::<Result<_, _>>()?;
            masks
                .into_iter()
                .map(|(m, rgb, depth)| {
                    first_depth_complexity = first_depth_complexity.or(depth);
                    (m, rgb)
                })
                .collect()
        }
    };
    let (mut covered, mut colour) = (Vec::new(), Vec::new());
    for (m, rgb) in rendered {
        if m.len() != expected {
            return Err(MetricError::MaskSize {
                len: m.len(),
                expected,
            });
        }
        covered.push(m);
        colour.push(rgb);
    }
    Ok(CoverageMasks {
        pixels: expected,
        views: cameras.len(),
        frames: scenes.len(),
        covered,
        colour,
        first_depth_complexity,
    })
}

/// Scores `simplified` against `original` over the frames `frames` of each view (all of them
/// for the animated metric, `[0]` for the static one); the report's per-pair vectors hold
/// `views · frames.len()` entries, view-major.
pub fn compare_masks(
    original: &CoverageMasks,
    simplified: &CoverageMasks,
    frames: &[usize],
) -> Result<CoverageReport, MetricError> {
    if (original.views, original.frames, original.pixels)
        != (simplified.views, simplified.frames, simplified.pixels)
        || frames.iter().any(|&f| f >= original.frames)
    {
        return Err(MetricError::FrameCountMismatch {
            expected: original.frames as u32,
            original: original.frames,
            simplified: simplified.frames,
        });
    }
    let pairs = original.views * frames.len();
    let mut original_pixels = Vec::with_capacity(pairs);
    let mut differing_pixels = Vec::with_capacity(pairs);
    let mut per_view = Vec::with_capacity(original.views);
    let (mut total, mut kept_total, mut discarded) = (0.0f64, 0usize, 0usize);
    let (mut colour_sum, mut colour_pairs, mut shift_sum) = (0.0f64, 0usize, 0.0f64);
    let mut colour_per_pair = Vec::with_capacity(pairs);
    for d in 0..original.views {
        let (mut view_sum, mut view_kept) = (0.0f64, 0usize);
        for &f in frames {
            let i = d * original.frames + f;
            let (o, s) = (&original.covered[i], &simplified.covered[i]);
            let (o_rgb, s_rgb) = (&original.colour[i], &simplified.colour[i]);
            let (mut diff, mut signed, mut shared) = (0.0f64, 0.0f64, 0usize);
            // Masks drawn without colour have none to compare.
            let with_colour = o_rgb.len() == o.len() && s_rgb.len() == s.len();
            for p in (0..o.len().min(s.len())).filter(|_| with_colour) {
                if o[p] && s[p] {
                    let d: f32 = (0..3).map(|c| (o_rgb[p][c] - s_rgb[p][c]).abs()).sum();
                    diff += f64::from(d) / 3.0;
                    let sd: f32 = (0..3).map(|c| o_rgb[p][c] - s_rgb[p][c]).sum();
                    signed += f64::from(sd) / 3.0;
                    shared += 1;
                }
            }
            if shared > 0 {
                colour_sum += diff / shared as f64;
                shift_sum += (signed / shared as f64).abs();
                colour_pairs += 1;
                colour_per_pair.push(diff / shared as f64);
            } else {
                colour_per_pair.push(f64::NAN);
            }
            let covered = o.iter().filter(|&&c| c).count() as u64;
            let differing = o.iter().zip(s).filter(|(a, b)| a != b).count() as u64;
            original_pixels.push(covered);
            differing_pixels.push(differing);
            match pair_score(differing, covered) {
                Some(score) => {
                    view_sum += score;
                    view_kept += 1;
                    total += score;
                    kept_total += 1;
                }
                None => discarded += 1,
            }
        }
        per_view.push(mean_or_nan(view_sum, view_kept));
    }
    Ok(CoverageReport {
        per_view,
        mean: mean_or_nan(total, kept_total),
        discarded,
        original_pixels,
        differing_pixels,
        colour_difference: mean_or_nan(colour_sum, colour_pairs),
        colour_per_pair,
        colour_shift: mean_or_nan(shift_sum, colour_pairs),
    })
}

/// `differing / covered`, or `None` when the pair is discarded (score above 1, or nothing
/// covered in the original) per spec §5.4.
fn pair_score(differing: u64, covered: u64) -> Option<f64> {
    if covered == 0 {
        return None;
    }
    let score = differing as f64 / covered as f64;
    (score <= 1.0).then_some(score)
}

fn mean_or_nan(sum: f64, count: usize) -> f64 {
    if count == 0 {
        f64::NAN
    } else {
        sum / count as f64
    }
}

/// The depth complexity of `scene` from view `view` of `params`' ring, framed by the bounds
/// (see the module docs), at the metric's size and supersampling: fragments rasterised per
/// covered sample ([`frond_render::depth_complexity`]), drawn by the CPU rasteriser whatever
/// `params.rasteriser` says.
pub fn depth_complexity(
    scene: &DrawScene,
    bounds_min: Vec3,
    bounds_max: Vec3,
    view: u32,
    params: &CoverageParams,
) -> Result<f64, MetricError> {
    let camera = view_camera(bounds_min, bounds_max, view, params)?;
    let textures = SoftwareTextures::new(scene, false)?;
    Ok(frond_render::depth_complexity(
        scene,
        &textures,
        projection(scene, &camera, params)?,
        params.width,
        params.height,
        params.supersample,
    )?)
}

/// The wgpu path's projection for `camera` at the metric's size: depth planes around the
/// scene's own bounds.
fn projection(
    scene: &DrawScene,
    camera: &Camera,
    params: &CoverageParams,
) -> Result<glam::Mat4, MetricError> {
    camera.validate()?;
    let aspect = params.width as f32 / params.height as f32;
    Ok(match scene.bounds() {
        Some((min, max)) => camera.view_proj_for_bounds(aspect, min, max),
        None => camera.view_proj(aspect),
    })
}

/// Whether two frames' scenes draw the same textures with the same materials (a model's
/// frames do: only the positions move), so one preparation serves both.
fn same_textures(a: &DrawScene, b: &DrawScene) -> bool {
    a.materials == b.materials
        && a.textures == b.textures
        && a.meshes
            .iter()
            .map(|m| (m.material, m.indices.is_empty()))
            .eq(b.meshes.iter().map(|m| (m.material, m.indices.is_empty())))
}

/// A mask, its covered pixels' colour and, for the first pair, its render's depth complexity.
type SoftwareMask = (Vec<bool>, Vec<[f32; 3]>, Option<f64>);

/// The binary coverage mask of `scene` at the metric's size drawn by the CPU rasteriser, the
/// covered pixels' colour when `params.colour` (else an empty vector), and the render's depth
/// complexity when `with_depth`.
fn software_mask(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    camera: &Camera,
    params: &CoverageParams,
    with_depth: bool,
) -> Result<SoftwareMask, MetricError> {
    let view_proj = projection(scene, camera, params)?;
    let (w, h, ss) = (params.width, params.height, params.supersample);
    let (image, depth) = if with_depth {
        let (image, depth) = render_coverage_with_depth(scene, textures, view_proj, w, h, ss)?;
        (image, Some(depth))
    } else {
        (render_coverage(scene, textures, view_proj, w, h, ss)?, None)
    };
    Ok((image.covered, image.colour, depth))
}

/// The binary coverage mask of `scene` at the metric's size: rendered `supersample`× larger,
/// a pixel covered when at least half of its samples are.
fn coverage_mask(
    renderer: &Renderer,
    scene: &DrawScene,
    camera: &Camera,
    params: &CoverageParams,
) -> Result<(Vec<bool>, Vec<[f32; 3]>), MetricError> {
    let ss = params.supersample.max(1) as usize;
    let (w, h) = (params.width as usize, params.height as usize);
    let frame = renderer.render_mipmapped(
        scene,
        camera,
        params.width * ss as u32,
        params.height * ss as u32,
        BACKGROUND,
    )?;
    let big_w = w * ss;
    let linear = &*frond_render::SRGB_LINEAR;
    let mut mask = vec![false; w * h];
    let mut colour = vec![[0.0f32; 3]; w * h];
    // Rows are independent: downsample them in parallel (each pixel's sum is in a fixed order).
    mask.par_chunks_mut(w)
        .zip(colour.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (mask_row, colour_row))| {
            for x in 0..w {
                let (mut covered, mut sum) = (0usize, [0.0f32; 3]);
                for dy in 0..ss {
                    let row = (y * ss + dy) * big_w + x * ss;
                    for i in row..row + ss {
                        if frame.coverage.get(i).copied().unwrap_or(false) {
                            covered += 1;
                            for (c, v) in sum.iter_mut().enumerate() {
                                *v += linear
                                    [usize::from(frame.rgba.get(i * 4 + c).copied().unwrap_or(0))];
                            }
                        }
                    }
                }
                mask_row[x] = 2 * covered >= ss * ss;
                if covered > 0 {
                    colour_row[x] = sum.map(|v| v / covered as f32);
                }
            }
        });
    Ok((mask, colour))
}

fn validate(
    original: usize,
    simplified: usize,
    params: &CoverageParams,
) -> Result<(), MetricError> {
    if params.views == 0 {
        return Err(MetricError::NoViews);
    }
    if params.frames == 0 {
        return Err(MetricError::NoFrames);
    }
    if params.width == 0 || params.height == 0 {
        return Err(MetricError::InvalidSize {
            width: params.width,
            height: params.height,
        });
    }
    let frames = params.frames as usize;
    if original != frames || simplified != frames {
        return Err(MetricError::FrameCountMismatch {
            expected: params.frames,
            original,
            simplified,
        });
    }
    validate_camera_params(params)
}

fn validate_camera_params(params: &CoverageParams) -> Result<(), MetricError> {
    if params.views == 0 {
        return Err(MetricError::NoViews);
    }
    let fov = params.fov_y_deg;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(MetricError::InvalidParams(format!(
            "fov_y_deg {fov} must be in (0, 180)"
        )));
    }
    let elevation = params.elevation_deg;
    if !(-90.0..=90.0).contains(&elevation) {
        return Err(MetricError::InvalidParams(format!(
            "elevation_deg {elevation} must be in [-90, 90]"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners(min: Vec3, max: Vec3) -> [Vec3; 8] {
        std::array::from_fn(|k| {
            Vec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            )
        })
    }

    #[test]
    fn bounds_span_the_image_height_exactly() {
        let boxes = [
            (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(3.0, 5.0, 1.0)),
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, 1.0, 1.0)),
            (Vec3::new(10.0, 0.0, 10.0), Vec3::new(10.5, 8.0, 10.5)),
            // A flat vertical card facing +Z.
            (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0)),
        ];
        for (min, max) in boxes {
            for elevation_deg in [0.0f32, 15.0, -30.0, 60.0] {
                let params = CoverageParams {
                    views: 7,
                    elevation_deg,
                    fov_y_deg: 35.0,
                    ..CoverageParams::default()
                };
                for view in 0..params.views {
                    let cam = view_camera(min, max, view, &params).expect("camera");
                    let m = cam.view_proj_for_bounds(4.0 / 3.0, min, max);
                    let ys: Vec<f32> = corners(min, max)
                        .iter()
                        .map(|&c| {
                            let clip = m * c.extend(1.0);
                            assert!(clip.w > 0.0, "corner {c} behind the eye");
                            clip.y / clip.w
                        })
                        .collect();
                    let top = ys.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                    let bottom = ys.iter().copied().fold(f32::INFINITY, f32::min);
                    let reach = top.max(-bottom);
                    assert!(
                        (reach - 1.0).abs() < 1e-4,
                        "{min}..{max} elevation {elevation_deg} view {view}: ys {ys:?}"
                    );
                    if elevation_deg == 0.0 {
                        assert!((top - 1.0).abs() < 1e-4 && (bottom + 1.0).abs() < 1e-4);
                    }
                }
            }
        }
    }

    #[test]
    fn card_distance_is_analytic() {
        // A card of height 2 at the centre plane: distance = 1 / tan(φ/2).
        let params = CoverageParams {
            views: 1,
            fov_y_deg: 40.0,
            ..CoverageParams::default()
        };
        let cam = view_camera(
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            0,
            &params,
        )
        .expect("camera");
        let expected = 1.0 / 20.0f32.to_radians().tan();
        assert!((cam.distance - expected).abs() < 1e-5 * expected);
        assert_eq!(cam.azimuth_deg, 0.0);
        assert_eq!(cam.target, Vec3::ZERO);
    }

    #[test]
    fn ring_is_even() {
        assert_eq!(ring_azimuth_deg(0, 5), 0.0);
        assert_eq!(ring_azimuth_deg(1, 5), 72.0);
        assert_eq!(ring_azimuth_deg(4, 5), 288.0);
        assert_eq!(ring_azimuth_deg(2, 3), 240.0);
        assert_eq!(ring_azimuth_deg(0, 0), 0.0);
    }

    #[test]
    fn pair_scores_and_discards() {
        assert_eq!(pair_score(0, 10), Some(0.0));
        assert_eq!(pair_score(10, 10), Some(1.0));
        assert_eq!(pair_score(11, 10), None);
        assert_eq!(pair_score(0, 0), None);
        assert!(mean_or_nan(0.0, 0).is_nan());
    }

    #[test]
    fn bad_inputs_are_rejected() {
        let ok = CoverageParams::default();
        assert!(validate(1, 1, &ok).is_ok());
        assert!(matches!(
            validate(1, 2, &ok),
            Err(MetricError::FrameCountMismatch { .. })
        ));
        let p = CoverageParams {
            views: 0,
            ..ok.clone()
        };
        assert!(matches!(validate(1, 1, &p), Err(MetricError::NoViews)));
        let p = CoverageParams {
            frames: 0,
            ..ok.clone()
        };
        assert!(matches!(validate(0, 0, &p), Err(MetricError::NoFrames)));
        let p = CoverageParams {
            width: 0,
            ..ok.clone()
        };
        assert!(matches!(
            validate(1, 1, &p),
            Err(MetricError::InvalidSize { .. })
        ));
        for fov_y_deg in [0.0, 180.0, f32::NAN] {
            let p = CoverageParams {
                fov_y_deg,
                ..ok.clone()
            };
            assert!(matches!(
                validate(1, 1, &p),
                Err(MetricError::InvalidParams(_))
            ));
        }
        let p = CoverageParams {
            elevation_deg: 91.0,
            ..ok.clone()
        };
        assert!(matches!(
            validate(1, 1, &p),
            Err(MetricError::InvalidParams(_))
        ));

        let flat = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        assert!(matches!(
            view_camera(flat.0, flat.1, 0, &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
        assert!(matches!(
            view_camera(Vec3::ONE, Vec3::ZERO, 0, &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
        assert!(matches!(
            view_camera(Vec3::ZERO, Vec3::splat(f32::NAN), 0, &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
    }
}
