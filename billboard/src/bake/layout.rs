//! The atlas layout: each quad's texture size at a uniform texel density, lowered until all
//! of them pack into one atlas (improved-billboard-cloud §4 items 1 and 5), and the atlas UVs
//! of a cell.

use glam::Vec2;

use crate::atlas::{self, Packing};
use crate::bake::baked::{BakeError, Cell};
use crate::bake::params::BakeParams;
use crate::quad::Quad;

/// Factor applied to the texel density each time the textures do not fit the atlas.
pub(super) const DENSITY_STEP: f32 = 0.8;

/// Texture sizes and their packing at the density finally used.
pub(super) struct Layout {
    pub(super) sizes: Vec<(u32, u32)>,
    pub(super) packing: Packing,
    pub(super) texels_per_unit: f32,
    pub(super) density_reduced: bool,
}

/// Texels along each quad axis at `density`: the quad's aspect ratio, the longest side at
/// most `max_side`, each side clamped to `min_side..=max_side`.
pub(super) fn texture_size(quad: &Quad, density: f32, p: &BakeParams) -> (u32, u32) {
    let raw = (quad.size().as_dvec2()) * f64::from(density);
    let longest = raw.max_element();
    let max = f64::from(p.max_side);
    let scale = if longest > max { max / longest } else { 1.0 };
    let side = |x: f64| ((x * scale).ceil().min(max) as u32).clamp(p.min_side, p.max_side);
    (side(raw.x), side(raw.y))
}

/// Finds the highest density, at most the requested one, whose textures pack into the atlas.
pub(super) fn layout(quads: &[Quad], p: &BakeParams) -> Result<Layout, BakeError> {
    let too_small = || BakeError::AtlasTooSmall {
        quads: quads.len(),
        max_atlas: p.max_atlas,
        min_side: p.min_side,
        padding: p.padding,
    };
    let sizes_at = |density: f32| -> Vec<(u32, u32)> {
        quads.iter().map(|q| texture_size(q, density, p)).collect()
    };
    let mut density = p.texels_per_unit;
    let mut reduced = false;
    // Jump close to a fitting density when the request is far too high: the padded area
    // grows at most quadratically with the density.
    let capacity = f64::from(p.max_atlas).powi(2);
    let area = |sizes: &[(u32, u32)]| -> f64 {
        let pad = 2.0 * f64::from(p.padding);
        sizes
            .iter()
            .map(|&(w, h)| (f64::from(w) + pad) * (f64::from(h) + pad))
            .sum()
    };
    let first = area(&sizes_at(density));
    if first > 4.0 * capacity {
        density = (f64::from(density) * (capacity / first).sqrt()) as f32;
        reduced = true;
    }
    let mut previous: Option<Vec<(u32, u32)>> = None;
    loop {
        let sizes = sizes_at(density);
        if previous.as_ref() != Some(&sizes)
            && let Some(packing) = atlas::pack(&sizes, p.padding, p.max_atlas)
        {
            return Ok(Layout {
                sizes,
                packing,
                texels_per_unit: density,
                density_reduced: reduced,
            });
        }
        let at_minimum = sizes
            .iter()
            .all(|&(w, h)| w == p.min_side && h == p.min_side);
        if at_minimum || density <= f32::MIN_POSITIVE {
            return Err(too_small());
        }
        previous = Some(sizes);
        density *= DENSITY_STEP;
        reduced = true;
    }
}

/// Atlas UVs of the quad's corners (see [`BakedCloud::uv_rects`]).
pub(super) fn uv_rect(c: &Cell, width: u32, height: u32) -> [Vec2; 4] {
    let (w, h) = (width as f32, height as f32);
    let (x0, x1) = (c.x as f32 / w, (c.x + c.width) as f32 / w);
    let (y0, y1) = (c.y as f32 / h, (c.y + c.height) as f32 / h);
    [
        Vec2::new(x0, y1),
        Vec2::new(x1, y1),
        Vec2::new(x1, y0),
        Vec2::new(x0, y0),
    ]
}
