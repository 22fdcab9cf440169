//! Finishing the cells: dilation of each quad's covered texels into the rest of its padded
//! cell (improved-billboard-cloud §4 item 6) and the normals rewritten in the quad's tangent
//! frame, the cells in parallel in bands of atlas rows.

use std::ops::Range;

use frond_render::{SRGB_LINEAR, linear_to_srgb};
use glam::Vec3;
use rayon::prelude::*;

use crate::bake::baked::{Atlas, Cell};
use crate::bake::placement::front_normal;
use crate::bake::texels::{Downsampled, encode_normal};
use crate::quad::Quad;

/// A quad's padded cell in the atlas: texel columns `x0..x1`, rows `y0..y1`. Padded cells
/// are disjoint.
pub(super) fn padded_rect(cell: &Cell, padding: u32, width: u32, height: u32) -> [usize; 4] {
    [
        cell.x.saturating_sub(padding) as usize,
        ((cell.x + cell.width + padding).min(width)) as usize,
        cell.y.saturating_sub(padding) as usize,
        ((cell.y + cell.height + padding).min(height)) as usize,
    ]
}

/// Finishes each quad's padded cell in place, the cells in parallel (bands of atlas rows
/// that no padded cell straddles, [`row_bands`]), each texel written once more at most:
/// - dilation: every texel no sample covered takes the colour and normal of a nearest
///   covered texel of that quad (chessboard distance, 8-neighbours: [`dilate`]), alpha
///   staying 0; a quad with nothing covered gets the mean covered colour of the atlas and its
///   own front normal (improved-billboard-cloud §4 item 6);
/// - tangent space: the normal, baked and dilated in world space, is rewritten in the quad's
///   tangent frame (`axis_u`, `axis_v`, front normal): what glTF's `normalTexture` holds, the
///   tangents engines derive from the billboard's UVs running along the same axes.
pub(super) fn finish_cells(
    mut d: Downsampled,
    cells: &[Cell],
    quads: &[Quad],
    padding: u32,
) -> Atlas {
    let rects: Vec<[usize; 4]> = (cells.iter())
        .map(|c| padded_rect(c, padding, d.width, d.height))
        .collect();
    let bands = row_bands(&rects);
    // The cells without any covered texel, band by band.
    let empty: Vec<usize> = (band_parts(&mut d, &bands).into_par_iter())
        .map_init(Vec::new, |grid, (mut band, members)| {
            (members.iter().copied())
                .filter(|&c| !band.finish(rects[c], &quads[c], grid))
                .collect::<Vec<usize>>()
        })
        .flatten()
        .collect();
    if !empty.is_empty() {
        let fallback = mean_color(&d.color, &d.samples);
        let mut all = CellTexels {
            color: &mut d.color,
            normal: &mut d.normal,
            samples: &d.samples,
            width: d.width as usize,
            y0: 0,
        };
        for c in empty {
            all.fill(rects[c], &quads[c], fallback);
        }
    }
    Atlas {
        width: d.width,
        height: d.height,
        color: d.color,
        normal: d.normal,
        blended: false,
    }
}

/// `d`'s rows cut along `bands` ([`row_bands`]): per band, its rows of both atlases and of
/// the covered samples, and its cells.
pub(super) fn band_parts<'a>(
    d: &'a mut Downsampled,
    bands: &'a [(Range<usize>, Vec<usize>)],
) -> Vec<(CellTexels<'a>, &'a [usize])> {
    let width = d.width as usize;
    let mut parts = Vec::with_capacity(bands.len());
    let (mut color, mut normal) = (&mut d.color[..], &mut d.normal[..]);
    let mut done = 0;
    for (rows, members) in bands {
        let skip = (rows.start - done) * width * 4;
        let len = rows.len() * width * 4;
        let (c, n);
        (c, color) = std::mem::take(&mut color)[skip..].split_at_mut(len);
        (n, normal) = std::mem::take(&mut normal)[skip..].split_at_mut(len);
        done = rows.end;
        let band = CellTexels {
            color: c,
            normal: n,
            samples: &d.samples[rows.start * width..rows.end * width],
            width,
            y0: rows.start,
        };
        parts.push((band, &members[..]));
    }
    parts
}

/// The padded cells' rectangles `rects` (`[x0, x1, y0, y1]`, disjoint) gathered into bands of
/// whole atlas rows, in row order: each cell's rows lie within one band, each band's cells
/// (by index) are the ones whose rows it holds. A shelf packing gives a band a shelf.
pub(super) fn row_bands(rects: &[[usize; 4]]) -> Vec<(Range<usize>, Vec<usize>)> {
    let mut order: Vec<usize> = (0..rects.len())
        .filter(|&c| rects[c][2] < rects[c][3])
        .collect();
    order.sort_by_key(|&c| (rects[c][2], c));
    let mut bands: Vec<(Range<usize>, Vec<usize>)> = Vec::new();
    for c in order {
        let [_, _, y0, y1] = rects[c];
        match bands.last_mut() {
            Some((rows, members)) if y0 < rows.end => {
                rows.end = rows.end.max(y1);
                members.push(c);
            }
            _ => bands.push((y0..y1, vec![c])),
        }
    }
    bands
}

/// One step of distance in a dilation grid's entry ([`CellTexels::finish`]).
pub(super) const STEP: u64 = 1 << 32;
/// A dilation grid's entry no covered texel has reached (nor can, in the two passes: a step
/// more is still above every reached entry).
pub(super) const UNREACHED: u64 = u64::MAX >> 1;

/// The two raster passes of Rosenfeld and Pfaltz over 8-neighbours on a dilation `grid` (rows
/// of `gw` entries, a ring of [`UNREACHED`] around them, see [`CellTexels::finish`]): each
/// entry becomes the least of itself and its four neighbours behind it, one [`STEP`] further,
/// which is exact for the chessboard distance (on a tie of distance, the source first in row
/// order wins: the entries' low halves). Each row takes the row behind it first, four
/// entries at a time where the machine has AVX2 (the same integers either way), then its
/// neighbour behind it in the row, one by one.
pub(super) fn chessboard_passes(grid: &mut [u64], gw: usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the machine has AVX2, checked just above.
        return unsafe { chessboard_passes_avx2(grid, gw) };
    }
    chessboard_passes_in(grid, gw);
}

/// [`chessboard_passes`] compiled for AVX2 (the compiler vectorises the rows' first step).
///
/// # Safety
/// The machine must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn chessboard_passes_avx2(grid: &mut [u64], gw: usize) {
    chessboard_passes_in(grid, gw);
}

/// [`chessboard_passes`]' work, inlined into each caller's target features.
#[inline(always)]
pub(super) fn chessboard_passes_in(grid: &mut [u64], gw: usize) {
    let rows = grid.len() / gw;
    // Each entry of `row` (but the ring's) the least of itself and the three of `behind`
    // around it, a step further.
    let from_row = |row: &mut [u64], behind: &[u64]| {
        let around = behind.windows(3);
        for (entry, w) in row[1..gw - 1].iter_mut().zip(around) {
            *entry = (*entry).min(w[0].min(w[1]).min(w[2]) + STEP);
        }
    };
    for y in 1..rows - 1 {
        let (done, rest) = grid.split_at_mut(y * gw);
        let row = &mut rest[..gw];
        from_row(row, &done[(y - 1) * gw..]);
        for x in 1..gw - 1 {
            row[x] = row[x].min(row[x - 1] + STEP);
        }
    }
    for y in (1..rows - 1).rev() {
        let (rest, done) = grid.split_at_mut((y + 1) * gw);
        let row = &mut rest[y * gw..];
        from_row(row, &done[..gw]);
        for x in (1..gw - 1).rev() {
            row[x] = row[x].min(row[x + 1] + STEP);
        }
    }
}

/// Rows of both atlases from row `y0` (as many as `color` holds), and their texels' covered
/// samples.
pub(super) struct CellTexels<'a> {
    pub(super) color: &'a mut [u8],
    pub(super) normal: &'a mut [u8],
    pub(super) samples: &'a [u16],
    pub(super) width: usize,
    pub(super) y0: usize,
}

impl CellTexels<'_> {
    /// The atlas texel `[x, y]`'s index in these rows.
    #[inline]
    pub(super) fn at(&self, x: usize, y: usize) -> usize {
        (y - self.y0) * self.width + x
    }

    /// Finishes the padded cell `[x0, x1, y0, y1]` of `quad` (see [`finish_cells`]): its
    /// covered texels' normals rewritten in tangent space, then [`CellTexels::dilate`]d into
    /// the others. False, leaving it as it is, when no texel of it is covered. `grid` is
    /// scratch.
    pub(super) fn finish(&mut self, rect: [usize; 4], quad: &Quad, grid: &mut Vec<u64>) -> bool {
        let [x0, x1, y0, y1] = rect;
        let mut tangent = TangentSpace::of(quad);
        // The cell with a ring of unreachable texels around it, each entry its distance
        // (high half) and source (low half, the texel's index in these rows).
        let gw = x1 - x0 + 2;
        grid.clear();
        grid.resize(gw * (y1 - y0 + 2), UNREACHED);
        let mut any = false;
        let (normal, _) = self.normal.as_chunks_mut::<4>();
        for y in y0..y1 {
            let at = (y - self.y0) * self.width + x0;
            let samples = &self.samples[at..at + x1 - x0];
            let entries = &mut grid[(y - y0 + 1) * gw + 1..][..x1 - x0];
            for (k, (&n, entry)) in samples.iter().zip(entries).enumerate() {
                if n > 0 {
                    any = true;
                    *entry = (at + k) as u64;
                    let [r, g, b, a] = normal[at + k];
                    let [r, g, b] = tangent.convert([r, g, b]);
                    normal[at + k] = [r, g, b, a];
                }
            }
        }
        if any {
            self.dilate(rect, grid);
        }
        any
    }

    /// Gives each uncovered texel of the cell `[x0, x1, y0, y1]` the colour and normal of a
    /// covered texel nearest it in chessboard distance (`grid`, see [`CellTexels::finish`]:
    /// each covered texel itself at distance 0, found by [`chessboard_passes`]), its alpha
    /// staying 0. The cell has a covered texel, so the passes reach every texel, and a covered
    /// texel is its own source: each texel's colour and normal are copied from its source
    /// with no test.
    pub(super) fn dilate(&mut self, [x0, x1, y0, y1]: [usize; 4], grid: &mut [u64]) {
        let gw = x1 - x0 + 2;
        chessboard_passes(grid, gw);
        let (color, _) = self.color.as_chunks_mut::<4>();
        let (normal, _) = self.normal.as_chunks_mut::<4>();
        for y in y0..y1 {
            let at = (y - self.y0) * self.width + x0;
            let entries = &grid[(y - y0 + 1) * gw + 1..][..x1 - x0];
            for (to, &entry) in (at..).zip(entries) {
                let from = (entry & u64::from(u32::MAX)) as usize;
                let ([r, g, b, _], [nr, ng, nb, _]) = (color[from], normal[from]);
                color[to] = [r, g, b, color[to][3]];
                normal[to] = [nr, ng, nb, normal[to][3]];
            }
        }
    }

    /// Fills the padded cell `[x0, x1, y0, y1]` of `quad`, none of it covered, with the colour
    /// `fallback` and the quad's own front normal (alpha staying 0).
    pub(super) fn fill(&mut self, [x0, x1, y0, y1]: [usize; 4], quad: &Quad, fallback: [u8; 3]) {
        let front = TangentSpace::of(quad).front();
        for y in y0..y1 {
            for x in x0..x1 {
                let i = self.at(x, y);
                self.color[i * 4..i * 4 + 3].copy_from_slice(&fallback);
                self.normal[i * 4..i * 4 + 3].copy_from_slice(&front);
            }
        }
    }
}

/// A quad's tangent frame (`axis_u`, `axis_v`, front normal), rewriting atlas normal bytes
/// (world space, `[0, 0, 0]` for "no normal": the quad's own) as tangent-space ones.
pub(super) struct TangentSpace {
    pub(super) u: Vec3,
    pub(super) v: Vec3,
    pub(super) front: Vec3,
    /// Bytes converted and what they became, by a hash of the bytes (the bytes and a bit
    /// set above them, 0 for a free slot): a cell's texels mostly share a few normals (flat
    /// cards), seen again after other cards', which remembering only the last one would miss.
    pub(super) seen: [(u32, [u8; 3]); CONVERTED_SLOTS],
}

/// Slots of [`TangentSpace`]'s conversions remembered.
pub(super) const CONVERTED_SLOTS: usize = 32;

impl TangentSpace {
    pub(super) fn of(quad: &Quad) -> Self {
        TangentSpace {
            u: quad.axis_u.normalize_or_zero(),
            v: quad.axis_v.normalize_or_zero(),
            front: front_normal(quad),
            seen: [(0, [0; 3]); CONVERTED_SLOTS],
        }
    }

    /// The quad's own front normal in its tangent frame, as bytes.
    pub(super) fn front(&mut self) -> [u8; 3] {
        self.convert([0, 0, 0])
    }

    /// World-space normal bytes `n` in the tangent frame, as bytes.
    pub(super) fn convert(&mut self, n: [u8; 3]) -> [u8; 3] {
        let key = u32::from_le_bytes([n[0], n[1], n[2], 1]);
        // Fibonacci hashing: the product's top bits.
        let slot = (key.wrapping_mul(0x9e37_79b9) >> (32 - CONVERTED_SLOTS.ilog2())) as usize;
        if self.seen[slot].0 == key {
            return self.seen[slot].1;
        }
        let decode = |v: u8| f32::from(v) / 255.0 * 2.0 - 1.0;
        let world = if n == [0, 0, 0] {
            let [x, y, z, _] = encode_normal(self.front, 0);
            [x, y, z]
        } else {
            n
        };
        let m = Vec3::new(decode(world[0]), decode(world[1]), decode(world[2]))
            .normalize_or(self.front);
        let t = Vec3::new(m.dot(self.u), m.dot(self.v), m.dot(self.front)).normalize_or(Vec3::Z);
        let [r, g, b, _] = encode_normal(t, 0);
        self.seen[slot] = (key, [r, g, b]);
        [r, g, b]
    }
}

/// Mean colour (in linear light) of all covered texels, mid grey when there are none.
pub(super) fn mean_color(color: &[u8], samples: &[u16]) -> [u8; 3] {
    let lut = &*SRGB_LINEAR;
    let mut sum = [0.0f64; 3];
    let mut n = 0u64;
    for (i, _) in samples.iter().enumerate().filter(|(_, n)| **n > 0) {
        for k in 0..3 {
            sum[k] += f64::from(lut[color[i * 4 + k] as usize]);
        }
        n += 1;
    }
    if n == 0 {
        return [128; 3];
    }
    sum.map(|s| linear_to_srgb((s / n as f64) as f32))
}
