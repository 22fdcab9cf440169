//! The pictures of a preview, all from frond's own renderer: a LOD at its screen height beside
//! LOD0 from the same camera, the difference of the two, the wind loop as an animated PNG, and
//! the LOD's atlas.

use frond_metrics::{CoverageParams, framing};
use frond_render::{Camera, DrawScene, Frame, Renderer};
use frond_scene::Tree;
use glam::Vec3;

use crate::error::PreviewError;

/// Elevation of the preview camera in degrees: a little above the tree, as a player stands.
const ELEVATION_DEG: f32 = 8.0;

/// The camera and image size a chain's stills at `screen_height` are seen with: the coverage
/// metric's framing ([`frond_metrics::framing`]) of the input's rest bounds at that size on the
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

/// A posed tree's scene (`tree` names it in errors), mip-mapped as engines sample textures, on
/// a transparent background.
pub fn render_pose(
    renderer: &Renderer,
    tree: &Tree,
    scene: &DrawScene,
    camera: &Camera,
    size: (u32, u32),
    what: &'static str,
) -> Result<Frame, PreviewError> {
    renderer
        .render_mipmapped(scene, camera, size.0, size.1, [0.0; 4])
        .map_err(|source| PreviewError::Render {
            file: tree.source.display().to_string(),
            what,
            source,
        })
}

/// What a LOD misses and adds against LOD0 at the same size, in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PixelDifference {
    /// Pixels LOD0 covers.
    pub reference: u64,
    /// Pixels LOD0 covers and the LOD does not.
    pub missing: u64,
    /// Pixels the LOD covers and LOD0 does not.
    pub extra: u64,
}

impl PixelDifference {
    /// Missing plus extra pixels over LOD0's covered ones (the coverage metric's score of this
    /// one view and frame).
    pub fn error(&self) -> f64 {
        if self.reference == 0 {
            0.0
        } else {
            (self.missing + self.extra) as f64 / self.reference as f64
        }
    }
}

/// Colour of a pixel LOD0 covers and the LOD misses.
pub const MISSING: [u8; 4] = [230, 40, 40, 255];
/// Colour of a pixel the LOD covers and LOD0 does not.
pub const EXTRA: [u8; 4] = [30, 120, 255, 255];

/// The difference image of `lod` against `reference` (same size): [`MISSING`] and [`EXTRA`]
/// pixels in colour, pixels both cover in the LOD's colour faded to grey, the rest transparent.
pub fn difference(reference: &Frame, lod: &Frame) -> (Vec<u8>, PixelDifference) {
    let mut out = vec![0u8; lod.rgba.len()];
    let mut d = PixelDifference::default();
    for (i, (&r, &l)) in reference.coverage.iter().zip(&lod.coverage).enumerate() {
        let px = &mut out[4 * i..4 * i + 4];
        d.reference += u64::from(r);
        match (r, l) {
            (true, false) => {
                d.missing += 1;
                px.copy_from_slice(&MISSING);
            }
            (false, true) => {
                d.extra += 1;
                px.copy_from_slice(&EXTRA);
            }
            (true, true) => {
                let c = &lod.rgba[4 * i..4 * i + 3];
                let grey = (u32::from(c[0]) + u32::from(c[1]) + u32::from(c[2])) / 3;
                for (o, &v) in px.iter_mut().zip(c) {
                    *o = ((u32::from(v) + 3 * grey) / 4 / 2 + 100) as u8;
                }
                px[3] = 255;
            }
            (false, false) => {}
        }
    }
    (out, d)
}

/// The smallest rectangle `[x, y, width, height]` holding every covered pixel of `frames` (all
/// of one size), grown by `pad` pixels within the image: the stills are cropped to it, the same
/// for LOD0 and the LOD so they still line up. The whole image when nothing is covered.
pub fn covered_box(frames: &[&Frame], pad: u32) -> [u32; 4] {
    let Some(first) = frames.first() else {
        return [0, 0, 0, 0];
    };
    let (w, h) = (first.width, first.height);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for f in frames {
        for (i, _) in f.coverage.iter().enumerate().filter(|(_, c)| **c) {
            let (x, y) = (i as u32 % w, i as u32 / w);
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
        }
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
        }
    }

    #[test]
    fn difference_counts_and_colours_missing_and_extra_pixels() {
        let reference = frame(&[true, true, false, false, true]);
        let lod = frame(&[true, false, true, false, true]);
        let (rgba, d) = difference(&reference, &lod);
        assert_eq!(
            d,
            PixelDifference {
                reference: 3,
                missing: 1,
                extra: 1
            }
        );
        assert!((d.error() - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(&rgba[4..8], &MISSING);
        assert_eq!(&rgba[8..12], &EXTRA);
        assert_eq!(rgba[12 + 3], 0, "neither covers: transparent");
        assert_eq!(rgba[3], 255, "both cover: opaque");
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
