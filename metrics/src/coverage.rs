//! The coverage error (spec animated-billboard-clouds §5.4, §8.2, §11 item 7; docs/metrics.md,
//! "The coverage error"): how much of what a player sees of the tree a LOD misses or adds,
//! at the LOD's own screen size.
//!
//! The original and its simplification are rendered from the views of [`crate::framing`](mod@crate::framing) for
//! `F` frames, each pixel resolved to the fraction α of its `K × K` samples something drawn
//! covers: what MSAA, alpha-to-coverage, TAA or a distant eye show of it. Each (view, frame)
//! pair scores `Σ_p |α_o − α_s| / Σ_p α_o` over the image; the error is the mean over every
//! pair (none is discarded: a LOD that bloats scores above 1). Beside it:
//!
//! - the **coverage ratio**, per pair `Σ α_s / Σ α_o`, then the mean: below 1 a LOD thins,
//!   above 1 it bloats;
//! - the **binary** error of §5.4 as the thesis defines it, on the same renders: a pixel is
//!   covered when α ≥ ½, a pair scores (pixels covered by exactly one) / (pixels the original
//!   covers), pairs above 1 or with no covered pixel are discarded;
//! - the **colour difference** of the covered pixels (colour renders), each pixel weighted by
//!   the coverage both share, `min(α_o, α_s)`.
//!
//! # Why filtered
//!
//! A pixel under half covered is empty to the binary rule: a tree a few dozen pixels tall has
//! almost no covered pixel at all, so the binary error measures the noise of that threshold,
//! or nothing. The covered fraction is defined at every size, is 0 for identical renders, and
//! weighs a missing leaf by the area it covers whatever its size on screen.
//!
//! # Textures
//!
//! Alpha-tested textures are read through coverage-preserving mip chains
//! ([`frond_render::alpha_mip_chain`]: each level's alpha rescaled so as many texels pass the
//! test as at full size), at the level of a sample's footprint (at least 512 samples over the
//! tree's height): a leaf keeps the shape and covered area of its full-size texture at every
//! size. Reading the level of a pixel's footprint instead, as a GPU does for a multisampled
//! pixel, would leave a far leaf a texel or two, all covered or none: its area lost.

use frond_render::{
    Camera, CoverageImage, DrawScene, Lighting, RenderError, Renderer, SoftwareTextures,
    render_coverage, render_coverage_with_depth,
};
use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::framing::{Framing, framing, validate_camera_params};

/// One image's covered samples per pixel: those an opaque or alpha-tested surface covers,
/// and what blended layers add ([`frond_render::CoverageImage::blended`]: empty when nothing
/// blended was drawn).
#[derive(Clone, Copy)]
struct Pixels<'a> {
    samples: &'a [u16],
    blended: &'a [f32],
}

impl Pixels<'_> {
    /// Pixel `p`'s covered samples (an integer where nothing blended covers it).
    #[inline]
    fn at(&self, p: usize) -> f64 {
        let n = f64::from(self.samples[p]);
        match self.blended.get(p) {
            Some(&b) => n + f64::from(b),
            None => n,
        }
    }

    fn len(&self) -> usize {
        self.samples.len()
    }
}

/// Background colour of the metric renders; coverage does not depend on it.
const BACKGROUND: [f32; 4] = [0.0; 4];

/// Views per ring by default: odd, as the thesis recommends (§8.2).
pub const DEFAULT_VIEWS: u32 = 5;

/// Frames of the loop by default: 0, ⅓ and ⅔ of the period. With the second ring the views
/// doubled; three frames keep a LOD's measure within its budget, and on the shared trees give
/// the five-frame error to within 0.001.
pub const DEFAULT_FRAMES: u32 = 3;

/// The elevations of the metric's rings by default: a player on the ground, and one looking
/// down on the tree.
pub const DEFAULT_ELEVATIONS_DEG: [f32; 2] = [0.0, 30.0];

/// The vertical field of view the metric's sizes assume by default, degrees (the switch
/// values' default).
pub const DEFAULT_FOV_DEG: f32 = 60.0;

/// The screen height the metric's sizes assume by default, pixels (the switch values'
/// default).
pub const DEFAULT_RESOLUTION: f32 = 1080.0;

/// Settings of the coverage metric; the defaults are 5 views on each of two rings (0° and
/// 30°), one frame, a tree 600 pixels tall on a 1080-pixel screen of 60° vertical field of view.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageParams {
    /// Views `D` per ring, evenly spread over a full turn. Odd counts are recommended (§8.2):
    /// opposite views of an even ring are near mirror images and add little information.
    pub views: u32,
    /// The elevation of each ring of views, degrees within [-90, 90].
    pub elevations_deg: Vec<f32>,
    /// Number of frames `F`; the caller supplies one scene per frame for both models. 1 gives
    /// the static metric (§5.4).
    pub frames: u32,
    /// The screen height `H` the tree is seen at, pixels: its rest height spans `H` pixels
    /// ([`crate::framing`](mod@crate::framing)).
    pub screen_height: f32,
    /// Vertical field of view of the screen, degrees within (0, 180).
    pub fov_y_deg: f32,
    /// Height of the screen in pixels.
    pub resolution: f32,
    /// Samples per pixel side, `K`; None: [`crate::framing::samples_per_side`].
    pub samples_per_side: Option<u32>,
    /// Which rasteriser draws the images: the CPU one by default (fast, and the same numbers
    /// on every machine), the wgpu one on request (a GPU's own filtering and rasterisation).
    pub rasteriser: Rasteriser,
    /// Also compute the covered pixels' colour ([`CoverageReport::colour_difference`]); the
    /// coverage alone needs neither a depth test nor the textures' colour.
    pub colour: bool,
    /// How the colour renders are lit (the CPU rasteriser's; the wgpu one is two-sided).
    pub lighting: Lighting,
}

/// The rasteriser of the metric's renders.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Rasteriser {
    /// [`frond_render::render_coverage`]: the CPU rasteriser built for coverage renders.
    #[default]
    Software,
    /// [`Renderer::render_mipmapped`] on the renderer's adapter, `K` times the image's size.
    Gpu,
}

impl Default for CoverageParams {
    fn default() -> Self {
        Self {
            views: 5,
            elevations_deg: DEFAULT_ELEVATIONS_DEG.to_vec(),
            frames: 1,
            screen_height: 600.0,
            fov_y_deg: DEFAULT_FOV_DEG,
            resolution: DEFAULT_RESOLUTION,
            samples_per_side: None,
            rasteriser: Rasteriser::Software,
            colour: true,
            lighting: Lighting::TwoSided,
        }
    }
}

/// The binary error of spec §5.4 as the thesis defines it, on the metric's renders: a pixel is
/// covered when at least half of its samples are.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BinaryCoverage {
    /// Mean over the kept pairs of (pixels covered by exactly one render) / (pixels the
    /// original covers); NaN when every pair was discarded.
    pub mean: f64,
    /// Pairs discarded: scoring above 1 (no fidelity from that view, §5.4) or the original
    /// covering no pixel.
    pub discarded: usize,
    /// Per (view, frame), the pixels the original covers, `P_f`.
    pub original_pixels: Vec<u64>,
    /// Per (view, frame), the pixels covered by exactly one of the two renders.
    pub differing_pixels: Vec<u64>,
}

/// Result of comparing two models' coverage images ([`compare_images`]). Per-pair vectors
/// are view-major (views ring by ring): the entry of view `d`, frame `f` is at index
/// `d · frames + f`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoverageReport {
    /// The coverage error: the mean over every pair of `Σ|α_o − α_s| / Σα_o`; 0 is perfect.
    pub mean: f64,
    /// That score per pair.
    pub per_pair: Vec<f64>,
    /// Per view, the mean score of its frames.
    pub per_view: Vec<f64>,
    /// The coverage ratio: the mean over every pair of `Σα_s / Σα_o`.
    pub ratio: f64,
    /// That ratio per pair.
    pub ratio_per_pair: Vec<f64>,
    /// Per pair, `Σα_o`: the original's covered area, pixels.
    pub original_coverage: Vec<f64>,
    /// The thesis' binary error on the same renders.
    pub binary: BinaryCoverage,
    /// The covered pixels' colour difference: per pair, the mean absolute difference of
    /// linear RGB (mean of the three channels, 0..1), each pixel weighted by `min(α_o, α_s)`;
    /// averaged over the pairs sharing any coverage; NaN when none does or without colour.
    pub colour_difference: f64,
    /// That difference per pair; NaN for a pair sharing no coverage.
    pub colour_per_pair: Vec<f64>,
    /// The shift of the mean colour over the same pixels and weights: per pair
    /// `|mean(o − s)|` (signed per pixel, mean of the three channels), averaged like
    /// `colour_difference`. What reads as one model being lighter or darker than the other,
    /// without the per-pixel differences that average out at a distance.
    pub colour_shift: f64,
    /// How much the original's coverage changes over the loop: per view, each frame against
    /// the next (the last against the first), the samples that change over those the original
    /// covers, then the mean over views and frames; None with fewer than two frames.
    pub loop_change_original: Option<f64>,
    /// The same of the simplified model, over the original's covered area.
    pub loop_change_simplified: Option<f64>,
}

/// The change of a model's coverage over the loop: per view, each frame against the next
/// (the last against the first: the loop closes), `Σ|n_f − n_{f+1}|` over the pixels, divided
/// by the original's covered samples `Σn_o,f` of that view and frame; the mean over views and
/// frames. The animated metric's own renders measure it, so it costs nothing more. Swaying
/// leaves that uncover and cover pixels move it; a model that does not move scores 0. A LOD
/// moves like the tree when its change is close to the original's: their ratio is
/// [`CoverageReport::loop_change_ratio`].
#[derive(Clone, Copy, Debug, Default)]
struct LoopChange {
    /// `Σ` over frames of the original's changed samples over its covered samples.
    original: f64,
    /// The same of the simplified model.
    simplified: f64,
    /// Frames summed.
    frames: usize,
}

impl LoopChange {
    /// Adds one view's frames (`frames[f]` the original's and the simplified model's covered
    /// samples of frame `f`, in loop order).
    fn add_view(&mut self, frames: &[(Pixels<'_>, Pixels<'_>)]) {
        if frames.len() < 2 {
            return;
        }
        for (f, (o, s)) in frames.iter().enumerate() {
            let (o2, s2) = frames[(f + 1) % frames.len()];
            let covered: f64 = (0..o.len()).map(|p| o.at(p)).sum();
            if covered == 0.0 {
                continue;
            }
            // Sums of integers where nothing is blended: exact, in any order.
            let changed = |a: &Pixels<'_>, b: &Pixels<'_>| -> f64 {
                (0..a.len()).map(|p| (a.at(p) - b.at(p)).abs()).sum()
            };
            self.original += changed(o, &o2) / covered;
            self.simplified += changed(s, &s2) / covered;
            self.frames += 1;
        }
    }

    /// The means, None when no view had two frames.
    fn means(&self) -> (Option<f64>, Option<f64>) {
        if self.frames == 0 {
            return (None, None);
        }
        let n = self.frames as f64;
        (Some(self.original / n), Some(self.simplified / n))
    }
}

impl CoverageReport {
    /// The simplified model's change of coverage over the loop over the original's: 1 moves
    /// as much as the tree, 0 stands still; None without two frames or when the original
    /// does not move.
    pub fn loop_change_ratio(&self) -> Option<f64> {
        match (self.loop_change_original, self.loop_change_simplified) {
            (Some(o), Some(s)) if o > 0.0 => Some(s / o),
            _ => None,
        }
    }
}

/// Why the coverage metric could not be computed.
#[derive(Debug, Error)]
pub enum MetricError {
    /// [`CoverageParams::views`] is zero.
    #[error("the coverage metric needs at least one view on at least one ring")]
    NoViews,
    /// [`CoverageParams::frames`] is zero.
    #[error("the coverage metric needs at least one frame")]
    NoFrames,
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
    /// The bounds are not finite, inverted, or have no height, so no screen size can be given
    /// to them.
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
    /// The original covers nothing from some view (an empty tree): there is nothing to
    /// compare with.
    #[error(
        "the original covers no pixel from view {view}, frame {frame}: nothing to compare with"
    )]
    NothingCovered {
        /// The view (ring by ring).
        view: usize,
        /// The frame.
        frame: usize,
    },
    /// The renderer returned a coverage image of the wrong size.
    #[error("coverage image has {len} entries, expected {expected}")]
    MaskSize {
        /// Entries received.
        len: usize,
        /// `width · height`.
        expected: usize,
    },
}

/// The coverage error of `simplified` against `original` (see the module docs), from their
/// posed scenes of each frame (`original[f]`, `simplified[f]`), framed by `bounds_min` and
/// `bounds_max` (pass the whole tree's rest bounds, so both models and all frames share the
/// cameras). The pairs are rendered a few at a time and compared as they come, so the images
/// held stay within [`MAX_HELD_IMAGE_BYTES`] whatever the size. Deterministic: every render is,
/// and the sums are of integer sample counts.
pub fn coverage_error(
    renderer: &Renderer,
    original: &[DrawScene],
    simplified: &[DrawScene],
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &CoverageParams,
) -> Result<CoverageReport, MetricError> {
    validate(original.len(), simplified.len(), params)?;
    let framing = framing(bounds_min, bounds_max, params)?;
    let o = Drawing::new(renderer, original, &framing, params)?;
    let s = Drawing::new(renderer, simplified, &framing, params)?;
    let pairs: Vec<(usize, usize)> = (0..framing.cameras.len())
        .flat_map(|d| (0..original.len()).map(move |f| (d, f)))
        .collect();
    // Whole views at a time (a view's frames give the loop change), as many as fit.
    let frames = original.len();
    let per_view = image_bytes(&framing, frames, params.colour).max(1);
    let views = (MAX_HELD_IMAGE_BYTES / (2 * per_view)).clamp(1, framing.cameras.len() as u64);
    let chunk = views as usize * frames;
    let samples = framing.supersample * framing.supersample;
    let mut sums = Vec::with_capacity(pairs.len());
    let mut change = LoopChange::default();
    for chunk in pairs.chunks(chunk) {
        let (a, _) = o.render(chunk)?;
        let (b, _) = s.render(chunk)?;
        for (&(d, f), (a, b)) in chunk.iter().zip(a.iter().zip(&b)) {
            let pair = pair_sums(
                (Pixels::of(a), &a.colour),
                (Pixels::of(b), &b.colour),
                samples,
            );
            if pair.original == 0.0 {
                return Err(MetricError::NothingCovered { view: d, frame: f });
            }
            sums.push(pair);
        }
        for (a, b) in a.chunks(frames).zip(b.chunks(frames)) {
            let view: Vec<(Pixels<'_>, Pixels<'_>)> = (a.iter().zip(b))
                .map(|(a, b)| (Pixels::of(a), Pixels::of(b)))
                .collect();
            change.add_view(&view);
        }
    }
    Ok(report_of(
        &sums,
        (framing.cameras.len(), frames),
        samples,
        change,
    ))
}

/// Most bytes of images [`coverage_error`] holds at once (and [`crate::eval::EvalContext`]
/// keeps of one model at one size): beyond it, pairs are rendered and compared a few at a
/// time.
pub const MAX_HELD_IMAGE_BYTES: u64 = 384 << 20;

/// Bytes of `pairs` images of `framing` (covered samples, and colour when drawn with it).
pub fn image_bytes(framing: &Framing, pairs: usize, colour: bool) -> u64 {
    let pixel = 2 + if colour { 12 } else { 0 };
    u64::from(framing.width) * u64::from(framing.height) * pairs as u64 * pixel
}

/// One model's coverage images for every (view, frame) pair of the metric: per pixel, its
/// covered samples and their mean colour. One model's renders can be compared with many
/// others (a sweep renders the original once).
#[derive(Clone, Debug)]
pub struct CoverageImages {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Views (every ring's).
    pub views: usize,
    /// Frames per view.
    pub frames: usize,
    /// Samples per pixel, `K²`.
    pub samples_per_pixel: u32,
    /// View-major (`d · frames + f`): each pixel's covered samples.
    samples: Vec<Vec<u16>>,
    /// The same pairs: what blended layers add to each pixel's covered samples (empty
    /// vectors where nothing blended was drawn).
    blended: Vec<Vec<f32>>,
    /// The same pairs: mean linear RGB of each pixel's covered samples (empty vectors when
    /// drawn without colour, [`CoverageParams::colour`]).
    colour: Vec<Vec<[f32; 3]>>,
    /// The depth complexity of the first view's first frame ([`depth_complexity`]), from its
    /// render; None from the wgpu rasteriser.
    pub first_depth_complexity: Option<f64>,
}

impl CoverageImages {
    /// Pair `pair`'s (view-major) covered fraction of each pixel, 0..1, row by row from the top.
    pub fn fractions(&self, pair: usize) -> Vec<f32> {
        let n = f64::from(self.samples_per_pixel);
        let pixels = self.pixels(pair);
        (0..pixels.len())
            .map(|p| (pixels.at(p) / n) as f32)
            .collect()
    }

    /// Pair `pair`'s covered samples per pixel.
    fn pixels(&self, pair: usize) -> Pixels<'_> {
        Pixels {
            samples: &self.samples[pair],
            blended: &self.blended[pair],
        }
    }
}

/// Renders the coverage images of `scenes` (one per frame) from every view of `params` (see
/// [`coverage_error`]).
pub fn coverage_images(
    renderer: &Renderer,
    scenes: &[DrawScene],
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &CoverageParams,
) -> Result<CoverageImages, MetricError> {
    validate(scenes.len(), scenes.len(), params)?;
    // Every camera is checked before the first (slow) render.
    let framing = framing(bounds_min, bounds_max, params)?;
    for camera in &framing.cameras {
        camera.validate()?;
    }
    let expected = framing.width as usize * framing.height as usize;
    let pairs: Vec<(usize, usize)> = (0..framing.cameras.len())
        .flat_map(|d| (0..scenes.len()).map(move |f| (d, f)))
        .collect();
    let (rendered, first_depth_complexity) =
        Drawing::new(renderer, scenes, &framing, params)?.render(&pairs)?;
    let (mut samples, mut blended, mut colour) = (Vec::new(), Vec::new(), Vec::new());
    for image in rendered {
        if image.samples.len() != expected
            || !(image.blended.is_empty() || image.blended.len() == expected)
        {
            return Err(MetricError::MaskSize {
                len: image.samples.len().max(image.blended.len()),
                expected,
            });
        }
        samples.push(image.samples);
        blended.push(image.blended);
        colour.push(image.colour);
    }
    Ok(CoverageImages {
        width: framing.width,
        height: framing.height,
        views: framing.cameras.len(),
        frames: scenes.len(),
        samples_per_pixel: framing.supersample * framing.supersample,
        samples,
        blended,
        colour,
        first_depth_complexity,
    })
}

impl<'a> Pixels<'a> {
    /// A render's covered samples per pixel.
    fn of(image: &'a CoverageImage) -> Pixels<'a> {
        Pixels {
            samples: &image.samples,
            blended: &image.blended,
        }
    }
}

/// One model's frames ready to be drawn from the metric's views: by the CPU rasteriser with
/// their textures' mip chains prepared once (a model's frames share them), or by wgpu.
struct Drawing<'a> {
    renderer: &'a Renderer,
    scenes: &'a [DrawScene],
    framing: &'a Framing,
    rasteriser: Rasteriser,
    /// The CPU rasteriser's prepared textures, and which of them each frame draws with.
    prepared: Vec<SoftwareTextures>,
    of_frame: Vec<usize>,
}

impl<'a> Drawing<'a> {
    fn new(
        renderer: &'a Renderer,
        scenes: &'a [DrawScene],
        framing: &'a Framing,
        params: &CoverageParams,
    ) -> Result<Drawing<'a>, MetricError> {
        let (mut prepared, mut of_frame) = (Vec::new(), Vec::with_capacity(scenes.len()));
        if params.rasteriser == Rasteriser::Software {
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
        }
        Ok(Drawing {
            renderer,
            scenes,
            framing,
            rasteriser: params.rasteriser,
            prepared,
            of_frame,
        })
    }

    /// The images of the (view, frame) `pairs`, in order, and the depth complexity of the
    /// pair (0, 0) when among them and drawn by the CPU rasteriser. The CPU rasteriser draws
    /// them in parallel (each render is deterministic, and they are collected in order).
    fn render(
        &self,
        pairs: &[(usize, usize)],
    ) -> Result<(Vec<CoverageImage>, Option<f64>), MetricError> {
        let framing = self.framing;
        if self.rasteriser == Rasteriser::Gpu {
            let images = (pairs.iter())
                .map(|&(d, f)| {
                    gpu_image(self.renderer, &self.scenes[f], &framing.cameras[d], framing)
                })
                .collect::<Result<Vec<_>, _>>()?;
            return Ok((images, None));
        }
        let images: Vec<(CoverageImage, Option<f64>)> = pairs
            .par_iter()
            .map(|&(d, f)| {
                let scene = &self.scenes[f];
                let view_proj = projection(scene, &framing.cameras[d], framing)?;
                let (w, h, k) = (framing.width, framing.height, framing.supersample);
                let textures = &self.prepared[self.of_frame[f]];
                let (image, depth) = if (d, f) == (0, 0) {
                    let (image, depth) =
                        render_coverage_with_depth(scene, textures, view_proj, w, h, k)?;
                    (image, Some(depth))
                } else {
                    (render_coverage(scene, textures, view_proj, w, h, k)?, None)
                };
                Ok((image, depth))
            })
            .collect::<Result<_, MetricError>>()?;
        let first_depth = images.iter().find_map(|(_, d)| *d);
        Ok((images.into_iter().map(|(i, _)| i).collect(), first_depth))
    }
}

/// Scores `simplified` against `original` over the frames `frames` of each view (all of them
/// for the animated metric, `[0]` for the static one); the report's per-pair vectors hold
/// `views · frames.len()` entries, view-major.
pub fn compare_images(
    original: &CoverageImages,
    simplified: &CoverageImages,
    frames: &[usize],
) -> Result<CoverageReport, MetricError> {
    let shape = |m: &CoverageImages| (m.views, m.frames, m.width, m.height, m.samples_per_pixel);
    if shape(original) != shape(simplified) || frames.iter().any(|&f| f >= original.frames) {
        return Err(MetricError::FrameCountMismatch {
            expected: original.frames as u32,
            original: original.frames,
            simplified: simplified.frames,
        });
    }
    let mut pairs = Vec::with_capacity(original.views * frames.len());
    let mut change = LoopChange::default();
    for d in 0..original.views {
        for &f in frames {
            let i = d * original.frames + f;
            let pair = pair_sums(
                (original.pixels(i), &original.colour[i]),
                (simplified.pixels(i), &simplified.colour[i]),
                original.samples_per_pixel,
            );
            if pair.original == 0.0 {
                return Err(MetricError::NothingCovered { view: d, frame: f });
            }
            pairs.push(pair);
        }
        let view: Vec<(Pixels<'_>, Pixels<'_>)> = (frames.iter())
            .map(|&f| {
                let i = d * original.frames + f;
                (original.pixels(i), simplified.pixels(i))
            })
            .collect();
        change.add_view(&view);
    }
    Ok(report_of(
        &pairs,
        (original.views, frames.len()),
        original.samples_per_pixel,
        change,
    ))
}

/// The sums of one (view, frame) pair, in samples (exact integers where nothing blended is
/// drawn: sums of integers in `f64`) and weighted colour.
#[derive(Clone, Copy, Debug, Default)]
struct PairSums {
    /// `Σ n_o`: the original's covered samples.
    original: f64,
    /// `Σ n_s`.
    simplified: f64,
    /// `Σ |n_o − n_s|`.
    differing: f64,
    /// Pixels the original covers (at least half of their samples).
    original_pixels: u64,
    /// Pixels covered by exactly one of the two, by that rule.
    differing_pixels: u64,
    /// `Σ min(n_o, n_s)` over the pixels whose colour is compared.
    shared: f64,
    /// `Σ min(n_o, n_s) · |c_o − c_s|` (mean of the three channels).
    colour: f64,
    /// `Σ min(n_o, n_s) · (c_o − c_s)` (mean of the three channels).
    signed: f64,
}

/// The sums of one pair's two images (covered samples and colour per pixel, `samples` a
/// pixel).
fn pair_sums(
    (o, o_rgb): (Pixels<'_>, &[[f32; 3]]),
    (s, s_rgb): (Pixels<'_>, &[[f32; 3]]),
    samples: u32,
) -> PairSums {
    // Images drawn without colour have none to compare.
    let with_colour = o_rgb.len() == o.len() && s_rgb.len() == s.len();
    let half = f64::from(samples);
    let mut sums = PairSums::default();
    for p in 0..o.len().min(s.len()) {
        let (no, ns) = (o.at(p), s.at(p));
        sums.original += no;
        sums.simplified += ns;
        sums.differing += (no - ns).abs();
        let (bo, bs) = (2.0 * no >= half, 2.0 * ns >= half);
        sums.original_pixels += u64::from(bo);
        sums.differing_pixels += u64::from(bo != bs);
        let w = no.min(ns);
        if with_colour && w > 0.0 {
            let (a, b) = (o_rgb[p], s_rgb[p]);
            let d: f32 = (0..3).map(|c| (a[c] - b[c]).abs()).sum();
            let sd: f32 = (0..3).map(|c| a[c] - b[c]).sum();
            sums.shared += w;
            sums.colour += w * f64::from(d) / 3.0;
            sums.signed += w * f64::from(sd) / 3.0;
        }
    }
    sums
}

/// The report of the pairs' sums (`views · frames` of them, view-major) and the views' loop
/// change.
fn report_of(
    pairs: &[PairSums],
    (views, frames): (usize, usize),
    samples_per_pixel: u32,
    change: LoopChange,
) -> CoverageReport {
    let per_pair: Vec<f64> = (pairs.iter()).map(|p| p.differing / p.original).collect();
    let ratio_per_pair: Vec<f64> = (pairs.iter()).map(|p| p.simplified / p.original).collect();
    let per_view = per_pair
        .chunks(frames.max(1))
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    let colour_per_pair: Vec<f64> = (pairs.iter())
        .map(|p| {
            if p.shared > 0.0 {
                p.colour / p.shared
            } else {
                f64::NAN
            }
        })
        .collect();
    let shifts: Vec<f64> = (pairs.iter())
        .filter(|p| p.shared > 0.0)
        .map(|p| (p.signed / p.shared).abs())
        .collect();
    let coloured: Vec<f64> = colour_per_pair
        .iter()
        .copied()
        .filter(|c| !c.is_nan())
        .collect();
    let kept: Vec<f64> = (pairs.iter())
        .filter(|p| p.original_pixels > 0)
        .map(|p| p.differing_pixels as f64 / p.original_pixels as f64)
        .filter(|&score| score <= 1.0)
        .collect();
    debug_assert_eq!(pairs.len(), views * frames);
    let (loop_change_original, loop_change_simplified) = change.means();
    CoverageReport {
        mean: mean_or_nan(&per_pair),
        per_view,
        ratio: mean_or_nan(&ratio_per_pair),
        original_coverage: (pairs.iter())
            .map(|p| p.original / f64::from(samples_per_pixel))
            .collect(),
        binary: BinaryCoverage {
            mean: mean_or_nan(&kept),
            discarded: pairs.len() - kept.len(),
            original_pixels: pairs.iter().map(|p| p.original_pixels).collect(),
            differing_pixels: pairs.iter().map(|p| p.differing_pixels).collect(),
        },
        per_pair,
        ratio_per_pair,
        colour_difference: mean_or_nan(&coloured),
        colour_per_pair,
        colour_shift: mean_or_nan(&shifts),
        loop_change_original,
        loop_change_simplified,
    }
}

/// The mean of `values`, NaN when there are none.
fn mean_or_nan(values: &[f64]) -> f64 {
    if values.is_empty() {
        f64::NAN
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

/// The depth complexity of `scene` from view `view` (ring by ring) of `params`, framed by the
/// bounds (see [`crate::framing`](mod@crate::framing)), at the metric's size and samples: fragments rasterised per
/// covered sample ([`frond_render::depth_complexity`]), drawn by the CPU rasteriser whatever
/// `params.rasteriser` says.
pub fn depth_complexity(
    scene: &DrawScene,
    bounds_min: Vec3,
    bounds_max: Vec3,
    view: usize,
    params: &CoverageParams,
) -> Result<f64, MetricError> {
    let framing = framing(bounds_min, bounds_max, params)?;
    let camera = framing.cameras.get(view).ok_or(MetricError::NoViews)?;
    let textures = SoftwareTextures::new(scene, false)?;
    Ok(frond_render::depth_complexity(
        scene,
        &textures,
        projection(scene, camera, &framing)?,
        framing.width,
        framing.height,
        framing.supersample,
    )?)
}

/// The projection of `camera` for the framing's image: depth planes around the scene's own
/// bounds.
fn projection(
    scene: &DrawScene,
    camera: &Camera,
    framing: &Framing,
) -> Result<glam::Mat4, MetricError> {
    camera.validate()?;
    let aspect = framing.aspect();
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

/// The coverage image of `scene` drawn by the wgpu renderer `K` times the image's size, each
/// pixel's covered samples counted and their colour averaged.
fn gpu_image(
    renderer: &Renderer,
    scene: &DrawScene,
    camera: &Camera,
    framing: &Framing,
) -> Result<CoverageImage, MetricError> {
    let k = framing.supersample as usize;
    let (w, h) = (framing.width as usize, framing.height as usize);
    let frame = renderer.render_mipmapped(
        scene,
        camera,
        framing.width * k as u32,
        framing.height * k as u32,
        BACKGROUND,
    )?;
    let big_w = w * k;
    let linear = &*frond_render::SRGB_LINEAR;
    let mut samples = vec![0u16; w * h];
    let mut blended = vec![0.0f32; w * h];
    let mut colour = vec![[0.0f32; 3]; w * h];
    // Rows are independent: resolve them in parallel (each pixel's sum is in a fixed order).
    // A sample is covered where its coverage is 255; blended layers compose to less, which
    // counts as that fraction of a sample, its colour blended over the clear (black)
    // background: weighted by its coverage already.
    samples
        .par_chunks_mut(w)
        .zip(blended.par_chunks_mut(w))
        .zip(colour.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, ((count_row, blend_row), colour_row))| {
            for x in 0..w {
                let (mut covered, mut part, mut sum) = (0u16, 0.0f32, [0.0f32; 3]);
                for dy in 0..k {
                    let row = (y * k + dy) * big_w + x * k;
                    for i in row..row + k {
                        match frame.coverage_alpha.get(i).copied().unwrap_or(0) {
                            0 => continue,
                            255 => covered += 1,
                            a => part += f32::from(a) / 255.0,
                        }
                        for (c, v) in sum.iter_mut().enumerate() {
                            *v += linear
                                [usize::from(frame.rgba.get(i * 4 + c).copied().unwrap_or(0))];
                        }
                    }
                }
                count_row[x] = covered;
                blend_row[x] = part;
                let weight = f32::from(covered) + part;
                if weight > 0.0 {
                    colour_row[x] = sum.map(|v| v / weight);
                }
            }
        });
    // A render without blended layers keeps whole samples alone.
    if blended.iter().all(|&b| b == 0.0) {
        blended.clear();
    }
    Ok(CoverageImage {
        width: framing.width,
        height: framing.height,
        samples_per_pixel: (k * k) as u32,
        samples,
        blended,
        colour,
    })
}

fn validate(
    original: usize,
    simplified: usize,
    params: &CoverageParams,
) -> Result<(), MetricError> {
    if params.frames == 0 {
        return Err(MetricError::NoFrames);
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

#[cfg(test)]
mod tests {
    use super::*;

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
    }

    #[test]
    fn pairs_score_their_covered_fractions() {
        // Four pixels of 4 samples: the original covers 4, 2, 0, 4; the simplification 2, 2,
        // 2, 4. Σ|Δ| = 4 of Σα_o = 10 samples; ratio 10/10; binary: the original covers
        // pixels 0, 1, 3, the simplification 0, 1, 2, 3: one of three differs.
        let images = |counts: Vec<u16>| CoverageImages {
            width: 2,
            height: 2,
            views: 1,
            frames: 1,
            samples_per_pixel: 4,
            samples: vec![counts],
            blended: vec![vec![]],
            colour: vec![vec![]],
            first_depth_complexity: None,
        };
        let (o, s) = (images(vec![4, 2, 0, 4]), images(vec![2, 2, 2, 4]));
        let r = compare_images(&o, &s, &[0]).expect("compare");
        assert_eq!(r.per_pair, vec![0.4]);
        assert_eq!(r.mean, 0.4);
        assert_eq!(r.ratio, 1.0);
        assert_eq!(r.original_coverage, vec![2.5]);
        assert_eq!(r.binary.original_pixels, vec![3]);
        assert_eq!(r.binary.differing_pixels, vec![1]);
        assert!((r.binary.mean - 1.0 / 3.0).abs() < 1e-12);
        assert!(r.colour_difference.is_nan(), "no colour drawn");
        // Nothing covered in the original: an error, not a discarded pair.
        let empty = images(vec![0; 4]);
        assert!(matches!(
            compare_images(&empty, &s, &[0]),
            Err(MetricError::NothingCovered { view: 0, frame: 0 })
        ));
        // A bloated simplification scores above 1 and is kept; the binary rule discards it.
        let sparse = images(vec![1, 0, 0, 0]);
        let full = images(vec![4; 4]);
        let r = compare_images(&sparse, &full, &[0]).expect("compare");
        assert_eq!(r.mean, 15.0);
        assert_eq!(r.ratio, 16.0);
        assert_eq!(r.binary.discarded, 1);
        assert!(r.binary.mean.is_nan());
    }

    #[test]
    fn colour_is_weighted_by_the_shared_coverage() {
        let images = |counts: Vec<u16>, rgb: Vec<[f32; 3]>| CoverageImages {
            width: 2,
            height: 1,
            views: 1,
            frames: 1,
            samples_per_pixel: 4,
            samples: vec![counts],
            blended: vec![vec![]],
            colour: vec![rgb],
            first_depth_complexity: None,
        };
        // Pixel 0 shares 1 sample and differs by 0.6; pixel 1 shares 3 and differs by 0.2.
        let o = images(vec![4, 3], vec![[0.6; 3], [0.2; 3]]);
        let s = images(vec![1, 4], vec![[0.0; 3], [0.0; 3]]);
        let r = compare_images(&o, &s, &[0]).expect("compare");
        let expected = (1.0 * 0.6 + 3.0 * 0.2) / 4.0;
        assert!((r.colour_difference - expected).abs() < 1e-6, "{r:?}");
        assert!((r.colour_shift - expected).abs() < 1e-6);
    }
}
