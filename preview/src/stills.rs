//! The pictures of a preview, all from frond's own renderer: a LOD at its screen height beside
//! LOD0 from the same camera, the difference of the two, the wind loop as an animated PNG, and
//! the LOD's atlas. Stills and differences take the coverage metric's `K × K` samples a pixel
//! (spec animated-billboard-clouds §5.4): a pixel is as opaque as the fraction of it covered, and
//! the difference counts the fractions the metric counts.

use frond_metrics::{CoverageParams, framing, samples_per_side};
use frond_render::{
    Camera, CoverageImage, DrawScene, Frame, Lighting, RenderError, SoftwareTextures,
    render_coverage,
};
use frond_scene::Tree;
use glam::Vec3;
use rayon::prelude::*;

use crate::error::PreviewError;

/// Elevation of the preview camera in degrees: a little above the tree, as a player stands.
const ELEVATION_DEG: f32 = 8.0;

/// The camera and image size a chain's stills at `screen_height` are seen with: the coverage
/// metric's framing ([`frond_metrics::framing()`]) of the input's rest bounds at that size on the
/// switch values' screen (`fov_deg`, `resolution`), one view raised by 8°, so the tree stands
/// `screen_height` pixels tall as the engine shows it and LOD0 and every LOD line up pixel for
/// pixel.
pub fn preview_view(
    input: &Tree,
    screen_height: f32,
    fov_deg: f32,
    resolution: f32,
) -> Result<(Camera, (u32, u32)), PreviewError> {
    let params = CoverageParams {
        views: 1,
        elevations_deg: vec![ELEVATION_DEG],
        screen_height: screen_height.max(1.0),
        fov_y_deg: fov_deg,
        resolution,
        ..Default::default()
    };
    let f = framing(
        Vec3::from(input.bounds.min),
        Vec3::from(input.bounds.max),
        &params,
    )
    .map_err(|source| PreviewError::Camera {
        file: input.source.display().to_string(),
        source,
    })?;
    Ok((f.cameras[0], (f.width, f.height)))
}

/// Largest side, in samples, of a filtered still ([`supersampling`]): four million samples at
/// most, which bounds a still's cost (the stills' colour has its own bound,
/// [`STILL_COLOUR_SAMPLES`]). The metric's `K` is 2 from 256 px up, which fits any still up to
/// 1024 px a side.
pub const MAX_SUPERSAMPLED_SIDE: u32 = 2048;

/// Samples per pixel side a still of `size` pixels of a tree `screen_height` pixels tall is
/// drawn with: the coverage metric's `K` ([`samples_per_side`]), lowered where `K` times the
/// still's larger side would pass `max_side` pixels (the renderer's limit) or
/// [`MAX_SUPERSAMPLED_SIDE`]; at least 1.
pub fn supersampling(screen_height: f32, size: (u32, u32), max_side: u32) -> u32 {
    let fit = max_side.min(MAX_SUPERSAMPLED_SIDE) / size.0.max(size.1).max(1);
    samples_per_side(screen_height).min(fit).max(1)
}

/// A still as the coverage metric sees it: each pixel `K × K` samples, the fraction of them
/// covered its coverage α (as MSAA, alpha-to-coverage or a distant eye show a leaf), and its
/// picture as a player sees it: the covered samples' mean colour, alpha the covered fraction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FilteredStill {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel side, `K`.
    pub samples_per_side: u32,
    /// Covered samples of each pixel, row-major, top row first (at most `K²`; blended layers
    /// count their alpha, so a sample may be partly covered).
    pub covered: Vec<f32>,
    /// `width * height * 4` bytes of sRGB RGBA8, straight alpha: per pixel the mean colour of
    /// its covered samples (averaged in linear light), alpha the covered fraction.
    pub rgba: Vec<u8>,
}

impl FilteredStill {
    /// The covered fraction α of pixel `i` (0 outside the image).
    pub fn fraction(&self, i: usize) -> f64 {
        let n = f64::from(self.samples_per_side * self.samples_per_side);
        self.covered
            .get(i)
            .map_or(0.0, |&c| if n > 0.0 { f64::from(c) / n } else { 0.0 })
    }

    /// The still of a coverage `image` of `size` pixels at `k × k` samples drawn with colour.
    fn of_image(image: &CoverageImage, size: (u32, u32), k: u32) -> FilteredStill {
        let n = f64::from(k * k);
        let covered: Vec<f32> = (0..image.samples.len())
            .map(|i| image.covered_samples(i))
            .collect();
        let mut rgba = vec![0u8; 4 * covered.len()];
        for ((px, &c), rgb) in rgba.chunks_exact_mut(4).zip(&covered).zip(&image.colour) {
            if c > 0.0 {
                for (o, v) in px.iter_mut().zip(rgb) {
                    *o = frond_render::linear_to_srgb(*v);
                }
                px[3] = (255.0 * f64::from(c) / n).round() as u8;
            }
        }
        FilteredStill {
            width: size.0,
            height: size.1,
            samples_per_side: k,
            covered,
            rgba,
        }
    }

    /// The smallest rectangle holding every pixel `self` or `other` (same size) covers at
    /// all, grown by `pad` pixels within the image ([`covered_rect`]).
    pub fn covered_box(&self, other: Option<&FilteredStill>, pad: u32) -> [u32; 4] {
        covered_rect(self.width, self.height, pad, |i| {
            self.covered[i] > 0.0
                || other.is_some_and(|o| o.covered.get(i).is_some_and(|&c| c > 0.0))
        })
    }
}

/// Draws one tree's pictures with the coverage metric's CPU rasteriser, its textures (their
/// coverage-preserving mip chains, colour included) prepared once for every still and frame:
/// a model's frames differ in positions only. Deterministic on every machine, and the
/// preview's cost: the wgpu path uploads and mip-maps every texture again for each picture.
pub struct Drawer<'a> {
    tree: &'a Tree,
    /// Prepared for colour (flip-book frames, a still's colour).
    textures: SoftwareTextures,
    /// Prepared for coverage alone (a still's `K × K` samples).
    coverage_only: SoftwareTextures,
}

impl<'a> Drawer<'a> {
    /// The drawer of `tree`, whose posed scenes all look like `scene` (same materials and
    /// textures).
    pub fn new(tree: &'a Tree, scene: &DrawScene) -> Result<Drawer<'a>, PreviewError> {
        let failed = render_error(tree, "pictures");
        let (textures, coverage_only) = rayon::join(
            || SoftwareTextures::new(scene, true),
            || SoftwareTextures::new(scene, false),
        );
        Ok(Drawer {
            tree,
            textures: textures.map_err(&failed)?.with_lighting(Lighting::TwoSided),
            coverage_only: coverage_only.map_err(&failed)?,
        })
    }

    /// `scene` through `camera` at `size` pixels of `k × k` samples: each pixel's covered
    /// samples and the mean colour of them, as the coverage metric draws it.
    fn coverage(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        (size, k, colour): ((u32, u32), u32, bool),
        what: &'static str,
    ) -> Result<CoverageImage, PreviewError> {
        let aspect = size.0 as f32 / size.1.max(1) as f32;
        let view_proj = match scene.bounds() {
            Some((min, max)) => camera.view_proj_for_bounds(aspect, min, max),
            None => camera.view_proj(aspect),
        };
        let textures = if colour {
            &self.textures
        } else {
            &self.coverage_only
        };
        render_coverage(scene, textures, view_proj, size.0, size.1, k.max(1))
            .map_err(render_error(self.tree, what))
    }

    /// A still: [`FilteredStill`] of `scene` at `size` pixels, each pixel's covered samples
    /// counted over `k × k` (as the coverage metric counts them), its colour from one sample
    /// a pixel ([`Drawer::frame`]), a pixel that sample misses taking the mean colour of its
    /// neighbours that have one. Colour at every sample would cost the still `k²` times over
    /// and hardly change a covered pixel's colour.
    pub fn still(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        size: (u32, u32),
        k: u32,
        what: &'static str,
    ) -> Result<FilteredStill, PreviewError> {
        let k = k.max(1);
        let kc = samples_within(size, k, STILL_COLOUR_SAMPLES);
        if kc == k {
            // Colour at every sample costs no second pass.
            let image = self.coverage(scene, camera, (size, k, true), what)?;
            return Ok(FilteredStill::of_image(&image, size, k));
        }
        let (coverage, colour) = rayon::join(
            || self.coverage(scene, camera, (size, k, false), what),
            || self.frame(scene, camera, size, kc, what),
        );
        let (coverage, colour) = (coverage?, colour?);
        let n = f64::from(k * k);
        let (w, h) = (size.0 as usize, size.1 as usize);
        let covered: Vec<f32> = (0..coverage.samples.len())
            .map(|i| coverage.covered_samples(i))
            .collect();
        let mut rgba = vec![0u8; 4 * covered.len()];
        rgba.par_chunks_mut(4 * w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, px) in row.chunks_exact_mut(4).enumerate() {
                    let c = covered[y * w + x];
                    if c <= 0.0 {
                        continue;
                    }
                    if let Some(rgb) = pixel_colour(&colour, x, y, (w, h)) {
                        px[..3].copy_from_slice(&rgb);
                    }
                    px[3] = (255.0 * f64::from(c) / n).round() as u8;
                }
            });
        Ok(FilteredStill {
            width: size.0,
            height: size.1,
            samples_per_side: k,
            covered,
            rgba,
        })
    }

    /// A flip-book frame: `scene` at `size` pixels of `k × k` samples, each pixel as opaque as
    /// the fraction of it covered and coloured by the mean of its covered samples.
    pub fn frame(
        &self,
        scene: &DrawScene,
        camera: &Camera,
        size: (u32, u32),
        k: u32,
        what: &'static str,
    ) -> Result<Frame, PreviewError> {
        let k = k.max(1);
        let image = self.coverage(scene, camera, (size, k, true), what)?;
        let still = FilteredStill::of_image(&image, size, k);
        let n = (k * k) as f32;
        Ok(Frame {
            width: size.0,
            height: size.1,
            coverage: still.covered.iter().map(|&c| c > 0.0).collect(),
            coverage_alpha: (still.covered.iter())
                .map(|&c| (c / n * 255.0).round().clamp(0.0, 255.0) as u8)
                .collect(),
            rgba: still.rgba,
        })
    }
}

/// Samples a still's colour is drawn with at most (its coverage takes the metric's `K × K`
/// whatever the size): a covered pixel's colour hardly changes with more, and colour at every
/// sample would cost the still `K²` times over.
pub const STILL_COLOUR_SAMPLES: u64 = 1 << 16;

/// Samples a flip-book frame is drawn with at most: far LODs' leaves, smaller than a pixel,
/// keep their coverage, and a near LOD's dozen frames stay cheap.
pub const FLIP_SAMPLES: u64 = 1 << 16;

/// The largest samples per pixel side, at most `k` and at least 1, at which an image of `size`
/// pixels takes at most `budget` samples.
pub fn samples_within(size: (u32, u32), k: u32, budget: u64) -> u32 {
    let pixels = u64::from(size.0) * u64::from(size.1);
    (1..=k.max(1))
        .rev()
        .find(|&s| pixels * u64::from(s * s) <= budget)
        .unwrap_or(1)
}

/// The colour of pixel `(x, y)` of `frame` (`w × h`): its own where covered, else the mean (in
/// linear light) of its covered 8-neighbours'; None when none is.
fn pixel_colour(frame: &Frame, x: usize, y: usize, (w, h): (usize, usize)) -> Option<[u8; 3]> {
    let at = |x: usize, y: usize| {
        let i = y * w + x;
        frame.coverage.get(i).copied().unwrap_or(false).then(|| {
            let p = &frame.rgba[4 * i..4 * i + 3];
            [p[0], p[1], p[2]]
        })
    };
    if let Some(c) = at(x, y) {
        return Some(c);
    }
    let linear = &*frond_render::SRGB_LINEAR;
    let (mut sum, mut n) = ([0.0f32; 3], 0u32);
    for ny in y.saturating_sub(1)..(y + 2).min(h) {
        for nx in x.saturating_sub(1)..(x + 2).min(w) {
            if let Some(c) = at(nx, ny) {
                for (s, v) in sum.iter_mut().zip(c) {
                    *s += linear[usize::from(v)];
                }
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum.map(|v| frond_render::linear_to_srgb(v / n as f32)))
}

/// The error of drawing `what` of `tree`.
fn render_error(tree: &Tree, what: &'static str) -> impl Fn(RenderError) -> PreviewError {
    let file = tree.source.display().to_string();
    move |source| PreviewError::Render {
        file: file.clone(),
        what,
        source,
    }
}

/// What a LOD misses and adds against LOD0 at the same size, in pixels, each pixel counted by
/// its covered fraction α as the coverage metric counts it.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PixelDifference {
    /// LOD0's covered area, `Σ α_LOD0`.
    pub reference: f64,
    /// The area LOD0 covers and the LOD does not, `Σ max(α_LOD0 − α_LOD, 0)`.
    pub missing: f64,
    /// The area the LOD covers and LOD0 does not, `Σ max(α_LOD − α_LOD0, 0)`.
    pub extra: f64,
}

impl PixelDifference {
    /// Missing plus extra area over LOD0's covered area: the coverage metric's score of this
    /// one view and frame (`Σ|α_LOD0 − α_LOD| / Σα_LOD0`); 0 when LOD0 covers nothing.
    pub fn error(&self) -> f64 {
        if self.reference > 0.0 {
            (self.missing + self.extra) / self.reference
        } else {
            0.0
        }
    }
}

/// Colour of the area LOD0 covers and the LOD misses.
pub const MISSING: [u8; 4] = [230, 40, 40, 255];
/// Colour of the area the LOD covers and LOD0 does not.
pub const EXTRA: [u8; 4] = [30, 120, 255, 255];

/// The difference image of `lod` against `reference` (same size), each pixel split as its
/// samples are: the part both cover in the LOD's colour faded to grey, the part LOD0 covers
/// beyond the LOD in [`MISSING`] (or the part the LOD covers beyond LOD0 in [`EXTRA`]), the
/// pixel's colour their area-weighted mean and its alpha the area either covers,
/// `max(α_LOD0, α_LOD)`: a pixel LOD0 fully covers and the LOD not at all is opaque red, one
/// it covers a quarter of and the LOD not at all red at a quarter opacity.
pub fn difference(reference: &FilteredStill, lod: &FilteredStill) -> (Vec<u8>, PixelDifference) {
    let mut out = vec![0u8; lod.rgba.len()];
    let mut d = PixelDifference::default();
    for (i, px) in out.chunks_exact_mut(4).enumerate() {
        let (r, l) = (reference.fraction(i), lod.fraction(i));
        d.reference += r;
        let both = r.min(l);
        let (part, colour) = if r > l {
            d.missing += r - l;
            (r - l, MISSING)
        } else {
            d.extra += l - r;
            (l - r, EXTRA)
        };
        let area = both + part;
        if area <= 0.0 {
            continue;
        }
        let faded = faded(&lod.rgba[4 * i..4 * i + 3]);
        for (c, o) in px[..3].iter_mut().enumerate() {
            let v = (both * f64::from(faded[c]) + part * f64::from(colour[c])) / area;
            *o = v.round() as u8;
        }
        px[3] = (255.0 * area).round() as u8;
    }
    (out, d)
}

/// An sRGB colour faded towards a light grey: where both cover, the LOD's shape is seen
/// without drawing the eye from the missing and extra parts.
fn faded(c: &[u8]) -> [u8; 3] {
    let grey = (u32::from(c[0]) + u32::from(c[1]) + u32::from(c[2])) / 3;
    std::array::from_fn(|i| ((u32::from(c[i]) + 3 * grey) / 4 / 2 + 100) as u8)
}

/// The smallest rectangle `[x, y, width, height]` holding every covered pixel of `frames` (all
/// of one size), grown by `pad` pixels within the image: the flip-books are cropped to it.
/// The whole image when nothing is covered.
pub fn covered_box(frames: &[&Frame], pad: u32) -> [u32; 4] {
    let Some(first) = frames.first() else {
        return [0, 0, 0, 0];
    };
    covered_rect(first.width, first.height, pad, |i| {
        frames
            .iter()
            .any(|f| f.coverage.get(i).copied().unwrap_or(false))
    })
}

/// The smallest rectangle `[x, y, width, height]` of a `width × height` image holding every
/// pixel `i` (row-major) that `covered(i)`, grown by `pad` pixels within the image: the stills
/// of LOD0 and a LOD are cropped to the same one, so they still line up. The whole image when
/// nothing is covered.
pub fn covered_rect(
    width: u32,
    height: u32,
    pad: u32,
    covered: impl Fn(usize) -> bool,
) -> [u32; 4] {
    let (w, h) = (width, height);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for i in (0..w as usize * h as usize).filter(|&i| covered(i)) {
        let (x, y) = (i as u32 % w, i as u32 / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
    }
    if x1 <= x0 || y1 <= y0 {
        return [0, 0, w, h];
    }
    let (x0, y0) = (x0.saturating_sub(pad), y0.saturating_sub(pad));
    let (x1, y1) = ((x1 + pad).min(w), (y1 + pad).min(h));
    [x0, y0, x1 - x0, y1 - y0]
}

/// The pixels of `rect` (`[x, y, width, height]`) of an RGBA8 image `width` pixels wide.
pub fn crop(rgba: &[u8], width: u32, rect: [u32; 4]) -> Vec<u8> {
    let [x, y, w, h] = rect.map(|v| v as usize);
    let row = 4 * width as usize;
    (y..y + h)
        .flat_map(|r| &rgba[r * row + 4 * x..r * row + 4 * (x + w)])
        .copied()
        .collect()
}

/// An encoded picture and its size in pixels.
pub struct Picture {
    /// The PNG file.
    pub png: Vec<u8>,
    /// Width and height in pixels.
    pub size: [u32; 2],
}

/// RGBA8 pixels as PNG bytes.
pub fn png(width: u32, height: u32, rgba: &[u8], what: &str) -> Result<Vec<u8>, PreviewError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut w = enc.write_header().map_err(encode(what))?;
        w.write_image_data(rgba).map_err(encode(what))?;
        w.finish().map_err(encode(what))?;
    }
    Ok(out)
}

/// Frames of one size as an animated PNG that loops forever, `delay_ms` per frame: a flip-book
/// every browser plays without script. Cropped to what any frame covers; returns the bytes and
/// the picture's size.
pub fn apng(frames: &[Frame], delay_ms: u16, what: &str) -> Result<Picture, PreviewError> {
    if frames.is_empty() {
        return Err(PreviewError::Encode {
            what: what.to_string(),
            reason: "no frames".into(),
        });
    };
    let mut out = Vec::new();
    let size;
    {
        let rect = covered_box(&frames.iter().collect::<Vec<_>>(), 2);
        let mut enc = png::Encoder::new(&mut out, rect[2], rect[3]);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        enc.set_animated(frames.len() as u32, 0)
            .map_err(encode(what))?;
        enc.set_frame_delay(delay_ms.max(1), 1000)
            .map_err(encode(what))?;
        let mut w = enc.write_header().map_err(encode(what))?;
        let rect = covered_box(&frames.iter().collect::<Vec<_>>(), 2);
        for f in frames {
            w.write_image_data(&crop(&f.rgba, f.width, rect))
                .map_err(encode(what))?;
        }
        w.finish().map_err(encode(what))?;
        size = [rect[2], rect[3]];
    }
    Ok(Picture { png: out, size })
}

fn encode(what: &str) -> impl Fn(png::EncodingError) -> PreviewError + '_ {
    move |e| PreviewError::Encode {
        what: what.to_string(),
        reason: e.to_string(),
    }
}

/// The LOD's baked atlas (the texture of `atlas`'s size), scaled to at most `max_side` pixels
/// a side, as PNG; None when the LOD has no such texture (card LODs keep the input's).
pub fn atlas_png(
    lod: &Tree,
    atlas: [u32; 2],
    max_side: u32,
) -> Result<Option<Picture>, PreviewError> {
    let Some(tex) = lod.textures.iter().find(|t| {
        [t.width, t.height] == atlas && t.rgba.len() == (t.width * t.height * 4) as usize
    }) else {
        return Ok(None);
    };
    let scale = (max_side as f32 / tex.width.max(tex.height) as f32).min(1.0);
    let (w, h) = (
        ((tex.width as f32 * scale).round() as u32).max(1),
        ((tex.height as f32 * scale).round() as u32).max(1),
    );
    let Some(img) = image::RgbaImage::from_raw(tex.width, tex.height, tex.rgba.clone()) else {
        return Ok(None);
    };
    let small = if (w, h) == (tex.width, tex.height) {
        img
    } else {
        image::imageops::resize(&img, w, h, image::imageops::FilterType::Triangle)
    };
    Ok(Some(Picture {
        png: png(w, h, small.as_raw(), "the atlas")?,
        size: [w, h],
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(coverage: &[bool]) -> Frame {
        Frame {
            width: coverage.len() as u32,
            height: 1,
            rgba: coverage
                .iter()
                .flat_map(|&c| if c { [90, 120, 60, 255] } else { [0; 4] })
                .collect(),
            coverage: coverage.to_vec(),
            coverage_alpha: coverage.iter().map(|&c| if c { 255 } else { 0 }).collect(),
        }
    }

    /// A one-row still of `K = 2` (4 samples a pixel) covering `covered[i]` samples of pixel
    /// `i`, in one green.
    fn still(covered: &[u32]) -> FilteredStill {
        FilteredStill {
            width: covered.len() as u32,
            height: 1,
            samples_per_side: 2,
            covered: covered.iter().map(|&c| c as f32).collect(),
            rgba: covered
                .iter()
                .flat_map(|&c| {
                    if c > 0 {
                        [90, 120, 60, (255 * c / 4) as u8]
                    } else {
                        [0; 4]
                    }
                })
                .collect(),
        }
    }

    #[test]
    fn difference_sums_covered_fractions_as_the_metric_does() {
        // Pixel by pixel (of 4 samples): both full; LOD0 full, the LOD a quarter (¾ missing);
        // LOD0 none, the LOD half (½ extra); neither; LOD0 a quarter, the LOD none.
        let reference = still(&[4, 4, 0, 0, 1]);
        let lod = still(&[4, 1, 2, 0, 0]);
        let (rgba, d) = difference(&reference, &lod);
        assert_eq!(
            d,
            PixelDifference {
                reference: 2.25,
                missing: 1.0,
                extra: 0.5
            }
        );
        assert!((d.error() - 1.5 / 2.25).abs() < 1e-12);
        let px = |i: usize| &rgba[4 * i..4 * i + 4];
        assert_eq!(px(0)[3], 255, "both cover all of it: opaque");
        assert_eq!(px(3)[3], 0, "neither covers: transparent");
        // Only missing or only extra: the pure colour, as opaque as the fraction.
        assert_eq!(
            px(2),
            &[EXTRA[0], EXTRA[1], EXTRA[2], 128][..],
            "half extra"
        );
        assert_eq!(
            px(4),
            &[MISSING[0], MISSING[1], MISSING[2], 64][..],
            "a quarter missing"
        );
        // Three quarters missing beside a quarter both cover: opaque, mostly red.
        let faded = faded(&[90, 120, 60]);
        let mix = |c: usize| (0.25 * f64::from(faded[c]) + 0.75 * f64::from(MISSING[c])).round();
        assert_eq!(px(1), &[mix(0) as u8, mix(1) as u8, mix(2) as u8, 255][..]);

        // A LOD against itself: nothing missing, nothing extra.
        let (same, d) = difference(&reference, &reference);
        assert_eq!((d.missing, d.extra, d.error()), (0.0, 0.0, 0.0));
        assert_eq!(d.reference, 2.25);
        assert!(
            same.chunks_exact(4)
                .all(|p| p[..3] != MISSING[..3] && p[..3] != EXTRA[..3]),
            "no red or blue: {same:?}"
        );
    }

    #[test]
    fn a_still_counts_samples_and_shows_their_mean_colour_in_srgb() {
        // A 2×1 coverage image at K = 2: pixel 0 has 3 of its 4 samples covered, their mean
        // linear colour two thirds white; pixel 1 none.
        let image = CoverageImage {
            width: 2,
            height: 1,
            samples_per_pixel: 4,
            samples: vec![3, 0],
            blended: vec![],
            colour: vec![[2.0 / 3.0; 3], [0.0; 3]],
        };
        let s = FilteredStill::of_image(&image, (2, 1), 2);
        assert_eq!((s.width, s.height, s.samples_per_side), (2, 1, 2));
        assert_eq!(s.covered, vec![3.0, 0.0]);
        assert_eq!(s.fraction(0), 0.75);
        // Two thirds of white in linear light is sRGB 213, not the byte mean 170.
        let grey = frond_render::linear_to_srgb(2.0 / 3.0);
        assert_eq!(grey, 213);
        assert_eq!(&s.rgba[..4], &[grey, grey, grey, 191]);
        assert_eq!(&s.rgba[4..], &[0; 4]);
        assert_eq!(s.covered_box(None, 0), [0, 0, 1, 1]);
    }

    #[test]
    fn supersampling_is_the_metrics_within_the_side_limit() {
        assert_eq!(
            supersampling(100.0, (120, 130), 16384),
            samples_per_side(100.0)
        );
        // K × 130 px is within 2048 for K up to 15.
        assert_eq!(samples_per_side(30.0), 18);
        assert_eq!(supersampling(30.0, (60, 130), 16384), 15);
        assert_eq!(supersampling(30.0, (60, 30), 16384), 18);
        // A tree 8 px tall on a 1000 px wide image: 2 samples a side fit 2048.
        assert_eq!(supersampling(8.0, (1000, 10), 16384), 2);
        assert_eq!(
            supersampling(8.0, (1000, 10), 1024),
            1,
            "the device's limit"
        );
        assert_eq!(
            supersampling(8.0, (9000, 10), 16384),
            1,
            "at least one sample"
        );
    }

    #[test]
    fn crop_box_holds_every_covered_pixel_of_every_frame() {
        let mut a = frame(&[false; 12]);
        (a.width, a.height) = (4, 3);
        let mut b = a.clone();
        a.coverage[4 + 1] = true; // (1, 1)
        b.coverage[4 * 2 + 2] = true; // (2, 2)
        assert_eq!(covered_box(&[&a, &b], 0), [1, 1, 2, 2]);
        assert_eq!(
            covered_box(&[&a, &b], 5),
            [0, 0, 4, 3],
            "padding stays in the image"
        );
        let empty = frame(&[false; 2]);
        assert_eq!(covered_box(&[&empty], 1), [0, 0, 2, 1]);
        let rgba: Vec<u8> = (0..48).collect();
        assert_eq!(crop(&rgba, 4, [1, 1, 2, 1]), (20..28).collect::<Vec<u8>>());
    }

    #[test]
    fn flip_book_is_an_animated_png_with_every_frame() {
        let frames = vec![
            frame(&[true, false]),
            frame(&[false, true]),
            frame(&[true, true]),
        ];
        let bytes = apng(&frames, 80, "test").expect("encodes").png;
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().expect("reads");
        let control = reader.info().animation_control.expect("an APNG");
        assert_eq!(control.num_frames, 3);
        assert_eq!(control.num_plays, 0, "loops forever");
    }
}
