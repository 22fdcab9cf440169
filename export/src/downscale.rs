//! Images written smaller than the input's for a far LOD (sizes from
//! `frond_lod::texture_budget`): decoded, resampled (triangle filter, premultiplied alpha), and
//! re-encoded. An alpha-tested map keeps its coverage: alpha is scaled so that as many texels
//! pass the material's cutoff as passed it in the input, in proportion (the coverage-preserving
//! rule of alpha-tested mip chains, as frond's renderer builds them), so thin foliage does not
//! vanish when its texture shrinks.
//!
//! Memory is what bounds this module: an input map may be 8192² (256 MiB decoded), and every
//! LOD file and the combined file want their downscaled copies at once. So a [`Downscaler`]
//! serves one chain's writers: each (image, size, cutoff) is made once and shared, one image is
//! decoded at a time and kept while it is asked for, and the resampling streams source rows
//! ([`resample`]). The image crate's `resize` was used before; it converts the whole map to
//! 16-byte float texels first (1 GiB for 8192²), and a resize crate with alpha support needs a
//! full premultiplied copy, where this holds a few rows.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

use frond_scene::Tree;
use frond_scene::gltf_writer::encode_png;
use image::RgbaImage;

use crate::error::ExportError;

/// What identifies one downscaled image: input image, size, and the cutoff's bits.
type Key = (usize, [u32; 2], Option<u32>);

/// Makes the downscaled images of one tree for any number of writers at once (see the module
/// doc): each once, one decode at a time.
pub struct Downscaler<'t> {
    tree: &'t Tree,
    state: Mutex<State>,
}

#[derive(Default)]
struct State {
    /// The input image decoded last (an image that `Tree::textures` does not hold decoded).
    source: Option<(usize, Arc<RgbaImage>)>,
    made: HashMap<Key, Arc<RgbaImage>>,
}

impl<'t> Downscaler<'t> {
    /// A downscaler of `tree`'s images that has made none yet.
    pub fn new(tree: &'t Tree) -> Self {
        Downscaler {
            tree,
            state: Mutex::new(State::default()),
        }
    }

    /// The tree whose images it downscales.
    pub fn tree(&self) -> &'t Tree {
        self.tree
    }

    /// PNG bytes of image `j` resampled to `size`; `cutoff`: the alpha test of the material it
    /// serves (None: alpha is not tested).
    pub fn png(
        &self,
        j: usize,
        size: [u32; 2],
        cutoff: Option<f32>,
    ) -> Result<Vec<u8>, ExportError> {
        let small = self.rgba(j, size, cutoff)?;
        encode_png(small.width(), small.height(), small.as_raw()).map_err(|source| {
            ExportError::Image {
                name: image_name(self.tree, j),
                source,
            }
        })
    }

    /// Image `j` resampled to `size` as RGBA8 (see [`Downscaler::png`]).
    pub fn rgba(
        &self,
        j: usize,
        size: [u32; 2],
        cutoff: Option<f32>,
    ) -> Result<Arc<RgbaImage>, ExportError> {
        let size = [size[0].max(1), size[1].max(1)];
        let key = (j, size, cutoff.map(f32::to_bits));
        // One at a time: the decoded source is the largest thing this module holds.
        let mut state = self.state.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(made) = state.made.get(&key) {
            return Ok(made.clone());
        }
        let small = match self.tree.textures.iter().find(|t| t.image == Some(j)) {
            Some(t) => downscale(&t.rgba, [t.width, t.height], size, cutoff),
            None => {
                let source = state.source(self.tree, j)?;
                downscale(
                    source.as_raw(),
                    [source.width(), source.height()],
                    size,
                    cutoff,
                )
            }
        }
        .ok_or(ExportError::NoTexture(j))?;
        let small = Arc::new(small);
        state.made.insert(key, small.clone());
        Ok(small)
    }
}

impl State {
    /// Input image `j` decoded (kept until another image is asked for).
    fn source(&mut self, tree: &Tree, j: usize) -> Result<Arc<RgbaImage>, ExportError> {
        if let Some((k, img)) = &self.source
            && *k == j
        {
            return Ok(img.clone());
        }
        // The previous source goes before the next is decoded.
        self.source = None;
        let img = Arc::new(decode(tree, j)?);
        self.source = Some((j, img.clone()));
        Ok(img)
    }
}

/// Input image `j` of `tree` decoded to RGBA8 (PNG, JPEG or KTX2; import checked its declared
/// size against the texture memory limit).
fn decode(tree: &Tree, j: usize) -> Result<RgbaImage, ExportError> {
    let img = tree.images.get(j).ok_or(ExportError::NoTexture(j))?;
    if img.mime_type == frond_scene::import::KTX2_MIME {
        let (w, h, rgba) = frond_scene::ktx2::decode_levels(&img.bytes, 1)
            .ok()
            .and_then(|mut l| l.pop())
            .ok_or(ExportError::NoTexture(j))?;
        return RgbaImage::from_raw(w, h, rgba).ok_or(ExportError::NoTexture(j));
    }
    Ok(image::load_from_memory(&img.bytes)
        .map_err(|source| ExportError::Image {
            name: image_name(tree, j),
            source,
        })?
        .into_rgba8())
}

/// Image `j`'s name, or `image<j>`.
fn image_name(tree: &Tree, j: usize) -> String {
    tree.images
        .get(j)
        .and_then(|i| i.name.clone())
        .unwrap_or_else(|| format!("image{j}"))
}

/// `rgba` (`from` texels) resampled to `to` with the coverage kept for `cutoff`; None when the
/// bytes do not hold `from`.
fn downscale(rgba: &[u8], from: [u32; 2], to: [u32; 2], cutoff: Option<f32>) -> Option<RgbaImage> {
    let texels = from[0] as usize * from[1] as usize;
    if texels == 0 || rgba.len() != texels * 4 {
        return None;
    }
    let mut small = resample(rgba, from, to);
    if let Some(c) = cutoff {
        keep_coverage(rgba, small.as_mut(), c);
    }
    Some(small)
}

/// One output texel's source taps along an axis: the first source index and the weights.
struct Taps {
    first: usize,
    weights: Vec<f32>,
}

/// Triangle-filter taps for resampling `from` texels to `to` along one axis: each output
/// texel's centre mapped into the source, the filter widened by the scale when shrinking,
/// weights normalised to 1.
fn taps(from: u32, to: u32) -> Vec<Taps> {
    let scale = from as f32 / to as f32;
    let radius = scale.max(1.0);
    (0..to)
        .map(|o| {
            let centre = (o as f32 + 0.5) * scale;
            let lo = ((centre - radius).floor().max(0.0)) as usize;
            let hi = ((centre + radius).ceil() as usize).min(from as usize);
            let mut weights: Vec<f32> = (lo..hi)
                .map(|i| (1.0 - ((i as f32 + 0.5 - centre) / radius).abs()).max(0.0))
                .collect();
            let sum: f32 = weights.iter().sum();
            if sum > 0.0 {
                weights.iter_mut().for_each(|w| *w /= sum);
            } else {
                // Narrower than a texel between two centres: the nearest texel.
                let nearest = (centre as usize).min(from as usize - 1);
                return Taps {
                    first: nearest,
                    weights: vec![1.0],
                };
            }
            Taps { first: lo, weights }
        })
        .collect()
}

/// `rgba` resampled from `from` to `to` texels with a triangle filter over premultiplied alpha
/// (so transparent texels' colour does not bleed into the edges), streaming. A texel left with
/// no alpha at all keeps the plain mean of the input's colour there: the colour an input
/// stores under its transparent texels (often the leaf's, bled outwards) is what an engine's
/// bilinear filter and mip chain blend into the edges, and black there would darken every
/// leaf seen from afar. Streaming: output rows in
/// order, each blending the source rows it needs, which are resampled horizontally once each
/// and kept in a window while later rows need them. Memory: the window and the output, never
/// a full-size float copy.
///
/// One thread: [`Downscaler`] runs this under its lock, and a rayon call here could run
/// another writer's job on this thread while it holds the lock (which that job would then
/// wait for for ever).
pub fn resample(rgba: &[u8], from: [u32; 2], to: [u32; 2]) -> RgbaImage {
    let (xs, ys) = (taps(from[0], to[0]), taps(from[1], to[1]));
    let (sw, ow) = (from[0] as usize, to[0] as usize);
    let mut out = vec![0u8; ow * to[1] as usize * 4];
    let mut window = RowWindow::default();
    let mut acc = vec![0f32; ow * TEXEL_SUMS];
    for (t, row_out) in ys.iter().zip(out.chunks_exact_mut(ow * 4)) {
        window.drop_before(t.first);
        acc.fill(0.0);
        for (i, &w) in t.weights.iter().enumerate() {
            let y = t.first + i;
            let row = window.row(y, || horizontal(&rgba[y * sw * 4..(y + 1) * sw * 4], &xs));
            for (a, &v) in acc.iter_mut().zip(row) {
                *a += w * v;
            }
        }
        unpremultiply(&acc, row_out);
    }
    RgbaImage::from_raw(to[0], to[1], out).unwrap_or_else(|| RgbaImage::new(to[0], to[1]))
}

/// Source rows resampled horizontally, kept while later output rows need them.
#[derive(Default)]
struct RowWindow {
    first: usize,
    rows: std::collections::VecDeque<Vec<f32>>,
}

impl RowWindow {
    /// Row `y` (made when not held; rows are asked for in increasing order, after
    /// [`RowWindow::drop_before`] the first one needed).
    fn row(&mut self, y: usize, make: impl FnOnce() -> Vec<f32>) -> &[f32] {
        if y < self.first || y > self.first + self.rows.len() {
            self.rows.clear();
            self.first = y;
        }
        let k = y - self.first;
        if k == self.rows.len() {
            self.rows.push_back(make());
        }
        &self.rows[k]
    }

    /// Forgets the rows before `y`.
    fn drop_before(&mut self, y: usize) {
        while self.first < y && !self.rows.is_empty() {
            self.rows.pop_front();
            self.first += 1;
        }
    }
}

/// Floats a resampled texel sums: premultiplied RGBA, then the plain RGB.
const TEXEL_SUMS: usize = 7;

/// One source row (RGBA8) resampled to the output's width: per texel, premultiplied RGBA and
/// plain RGB ([`TEXEL_SUMS`] floats).
fn horizontal(row: &[u8], xs: &[Taps]) -> Vec<f32> {
    let mut out = Vec::with_capacity(xs.len() * TEXEL_SUMS);
    for t in xs {
        let mut px = [0f32; TEXEL_SUMS];
        for (i, &w) in t.weights.iter().enumerate() {
            let p = &row[(t.first + i) * 4..(t.first + i) * 4 + 4];
            let a = f32::from(p[3]) / 255.0;
            for c in 0..3 {
                let v = f32::from(p[c]) / 255.0;
                px[c] += w * v * a;
                px[4 + c] += w * v;
            }
            px[3] += w * a;
        }
        out.extend_from_slice(&px);
    }
    out
}

/// Resampled texels back to straight-alpha RGBA8: the premultiplied colour over alpha, or the
/// plain colour where no alpha reached the texel.
fn unpremultiply(acc: &[f32], out: &mut [u8]) {
    for (p, q) in acc.chunks_exact(TEXEL_SUMS).zip(out.chunks_exact_mut(4)) {
        let a = p[3].clamp(0.0, 1.0);
        let c = |k: usize| {
            let v = if a > 0.0 { p[k] / a } else { p[4 + k] };
            (v.clamp(0.0, 1.0) * 255.0).round() as u8
        };
        q.copy_from_slice(&[c(0), c(1), c(2), (a * 255.0).round() as u8]);
    }
}

/// Scales the alpha of `small` (RGBA8) so that the fraction of its texels at or above
/// `cutoff` equals that of `full`.
fn keep_coverage(full: &[u8], small: &mut [u8], cutoff: f32) {
    let threshold = (cutoff.clamp(0.0, 1.0) * 255.0).round() as u8;
    let n_full = full.len() / 4;
    let n_small = small.len() / 4;
    if n_full == 0 || n_small == 0 {
        return;
    }
    let passing = full.chunks_exact(4).filter(|p| p[3] >= threshold).count();
    let want = ((passing as f64 / n_full as f64) * n_small as f64).round() as usize;
    if want == 0 {
        return;
    }
    let mut alphas: Vec<u8> = small.chunks_exact(4).map(|p| p[3]).collect();
    alphas.sort_unstable_by(|a, b| b.cmp(a));
    let at = alphas[want.min(n_small) - 1];
    if at == 0 || at == threshold {
        return;
    }
    let k = f32::from(threshold) / f32::from(at);
    for p in small.chunks_exact_mut(4) {
        p[3] = (f32::from(p[3]) * k).round().min(255.0) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transparent_texels_keep_the_colour_the_input_stores_under_them() {
        // An opaque red square in the middle of transparent texels whose colour is green (a
        // leaf's colour bled outwards, as exporters do): shrunk, the texels no alpha reaches
        // stay green, not black, and the square stays red.
        let n = 64;
        let image: Vec<u8> = (0..n * n)
            .flat_map(|i| {
                let (x, y) = (i % n, i / n);
                if (24..40).contains(&x) && (24..40).contains(&y) {
                    [255, 0, 0, 255]
                } else {
                    [40, 160, 60, 0]
                }
            })
            .collect();
        let small = resample(&image, [64, 64], [16, 16]);
        assert_eq!(small.get_pixel(0, 0).0, [40, 160, 60, 0]);
        assert_eq!(small.get_pixel(15, 15).0, [40, 160, 60, 0]);
        let centre = small.get_pixel(8, 8).0;
        assert_eq!(centre, [255, 0, 0, 255]);
        // Every texel with any alpha is the square's red.
        for p in small.pixels().filter(|p| p.0[3] > 0) {
            assert_eq!([p.0[0], p.0[1], p.0[2]], [255, 0, 0], "{:?}", p.0);
        }
    }

    #[test]
    fn resampling_keeps_flat_colour_and_averages_with_premultiplied_alpha() {
        // A flat image stays flat at any size, up or down.
        let flat: Vec<u8> = [30u8, 120, 200, 255].repeat(37 * 23);
        for to in [[5, 3], [16, 16], [37, 23], [80, 50]] {
            let small = resample(&flat, [37, 23], to);
            assert_eq!(small.dimensions(), (to[0], to[1]));
            assert!(small.pixels().all(|p| p.0 == [30, 120, 200, 255]), "{to:?}");
        }
        // Halving a 2×2 checker of opaque red and transparent green: half coverage, and no
        // green bleeds into the colour (premultiplied).
        let checker: Vec<u8> = (0..64 * 64)
            .flat_map(|i| {
                let (x, y) = (i % 64, i / 64);
                if (x + y) % 2 == 0 {
                    [255, 0, 0, 255]
                } else {
                    [0, 255, 0, 0]
                }
            })
            .collect();
        let half = resample(&checker, [64, 64], [32, 32]);
        for (x, y, p) in half.enumerate_pixels() {
            assert_eq!([p.0[0], p.0[1]], [255, 0], "{:?}", p.0);
            // Inside, exactly half; at the border the filter is cut off and renormalised.
            let border = x == 0 || y == 0 || x == 31 || y == 31;
            let tolerance = if border { 16 } else { 1 };
            assert!(
                (i32::from(p.0[3]) - 128).abs() <= tolerance,
                "{x},{y}: {:?}",
                p.0
            );
        }
    }

    #[test]
    fn each_downscaled_map_is_made_once_from_one_decode() {
        let glb = frond_scene::generator::generate(frond_scene::generator::Preset::Small, 1)
            .unwrap()
            .glb;
        let mut tree = frond_scene::import_bytes(
            std::path::Path::new("small.glb"),
            &glb,
            &frond_scene::ImportOptions::default(),
        )
        .unwrap();
        let png = encode_png(64, 64, &[90u8, 140, 200, 255].repeat(64 * 64)).unwrap();
        tree.images.push(frond_scene::SourceImage {
            name: Some("extra".into()),
            mime_type: "image/png".into(),
            bytes: png,
        });
        let j = tree.images.len() - 1;
        let d = Downscaler::new(&tree);
        let a = d.rgba(j, [16, 16], None).unwrap();
        let b = d.rgba(j, [16, 16], None).unwrap();
        assert!(Arc::ptr_eq(&a, &b), "made once");
        let c = d.rgba(j, [8, 8], Some(0.5)).unwrap();
        assert_eq!(c.dimensions(), (8, 8));
        // Opaque stays above the cutoff (the coverage rule scales alpha to it).
        assert!(
            c.pixels()
                .all(|p| p.0[..3] == [90, 140, 200] && p.0[3] >= 128)
        );
        let png = d.png(j, [8, 8], Some(0.5)).unwrap();
        assert_eq!(image::load_from_memory(&png).unwrap().into_rgba8(), *c);
    }

    #[test]
    fn alpha_scaling_keeps_the_passing_fraction() {
        // A full image with a quarter of its texels opaque (scattered), a downscaled one whose
        // alpha averaged them to 64: without scaling nothing passes 0.5.
        let full: Vec<u8> = (0..64)
            .flat_map(|i| [0, 0, 0, if i % 4 == 0 { 255 } else { 0 }])
            .collect();
        let mut small: Vec<u8> = (0..16)
            .flat_map(|i| [0, 0, 0, if i % 2 == 0 { 64 } else { 60 }])
            .collect();
        keep_coverage(&full, &mut small, 0.5);
        let pass = small.chunks_exact(4).filter(|p| p[3] >= 128).count();
        // A quarter of 16 is 4: the fourth largest alpha (64) is scaled to the cutoff, and the
        // texels tied with it pass too.
        assert_eq!(pass, 8);
    }
}
