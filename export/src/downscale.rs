//! Images written smaller than the input's for a far LOD (sizes from
//! `frond_lod::texture_budget`): decoded, resampled (triangle filter), and re-encoded as PNG.
//! An alpha-tested map keeps its coverage: alpha is scaled so that as many texels pass the
//! material's cutoff as passed it in the input, in proportion (the coverage-preserving rule of
//! alpha-tested mip chains, as frond's renderer builds them), so thin foliage does not vanish
//! when its texture shrinks.

use frond_scene::Tree;
use frond_scene::gltf_writer::encode_png;
use image::RgbaImage;
use image::imageops::{FilterType, resize};

use crate::error::ExportError;

/// PNG bytes of image `j` of `tree` resampled to `size`; `cutoff`: the alpha test of the
/// material it serves (None: alpha is not tested).
pub fn downscaled_png(
    tree: &Tree,
    j: usize,
    size: [u32; 2],
    cutoff: Option<f32>,
) -> Result<Vec<u8>, ExportError> {
    let small = downscaled_rgba(tree, j, size, cutoff)?;
    encode_png(small.width(), small.height(), small.as_raw()).map_err(|source| ExportError::Image {
        name: image_name(tree, j),
        source,
    })
}

/// Image `j`'s name, or `image<j>`.
fn image_name(tree: &Tree, j: usize) -> String {
    tree.images
        .get(j)
        .and_then(|i| i.name.clone())
        .unwrap_or_else(|| format!("image{j}"))
}

/// Image `j` of `tree` resampled to `size` as RGBA8 (see [`downscaled_png`]).
pub fn downscaled_rgba(
    tree: &Tree,
    j: usize,
    size: [u32; 2],
    cutoff: Option<f32>,
) -> Result<RgbaImage, ExportError> {
    let source: RgbaImage = match tree.textures.iter().find(|t| t.image == Some(j)) {
        Some(t) => RgbaImage::from_raw(t.width, t.height, t.rgba.clone())
            .ok_or_else(|| ExportError::NoTexture(j))?,
        None => {
            let img = tree.images.get(j).ok_or(ExportError::NoTexture(j))?;
            if img.mime_type == frond_scene::import::KTX2_MIME {
                let (w, h, rgba) = frond_scene::ktx2::decode_levels(&img.bytes, 1)
                    .ok()
                    .and_then(|mut l| l.pop())
                    .ok_or(ExportError::NoTexture(j))?;
                RgbaImage::from_raw(w, h, rgba).ok_or(ExportError::NoTexture(j))?
            } else {
                image::load_from_memory(&img.bytes)
                    .map_err(|source| ExportError::Image {
                        name: image_name(tree, j),
                        source,
                    })?
                    .to_rgba8()
            }
        }
    };
    let mut small = resize_premultiplied(&source, size[0].max(1), size[1].max(1));
    if let Some(c) = cutoff {
        keep_coverage(source.as_raw(), small.as_mut(), c);
    }
    Ok(small)
}

fn resize_premultiplied(image: &RgbaImage, width: u32, height: u32) -> RgbaImage {
    let (w, h) = image.dimensions();
    let mut pre = image::Rgba32FImage::new(w, h);
    for (p, q) in image.pixels().zip(pre.pixels_mut()) {
        let a = f32::from(p[3]) / 255.0;
        *q = image::Rgba([
            f32::from(p[0]) / 255.0 * a,
            f32::from(p[1]) / 255.0 * a,
            f32::from(p[2]) / 255.0 * a,
            a,
        ]);
    }
    let small = resize(&pre, width, height, FilterType::Triangle);
    let mut out = RgbaImage::new(width, height);
    for (p, q) in small.pixels().zip(out.pixels_mut()) {
        let a = p[3].clamp(0.0, 1.0);
        let c = |v: f32| {
            let v = if a > 0.0 { v / a } else { 0.0 };
            (v.clamp(0.0, 1.0) * 255.0).round() as u8
        };
        *q = image::Rgba([c(p[0]), c(p[1]), c(p[2]), (a * 255.0).round() as u8]);
    }
    out
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
