//! Where on a texture an alpha test can pass, as an octagon in texture coordinates, and the
//! sample span of each row of a triangle that octagon leaves.
//!
//! A leaf card's texture is transparent over much of its square (the margins either side of
//! the branch, and the corners), and a coverage render alpha-tests every sample of every card
//! that no other card has covered yet: many of the eight-sample groups it tests lie wholly
//! where no footprint of the triangle's mip levels holds a texel that can pass. Bounding the
//! texture's possibly passing footprints by eight half-planes `d·uv ≤ s` (the axes and the
//! diagonals) turns each into a linear function on the triangle's screen (perspective divides
//! out: `s·q − d·(u·q, v·q)` is linear in the screen-space weights and has the sign of
//! `s − d·uv`), so each sample row gets a narrower span in a few operations, and a triangle
//! that lies wholly outside one is not drawn at all. The samples left out are ones whose test
//! fails whatever the filter: a filtered alpha never exceeds its footprint's greatest texel,
//! nor a trilinear blend the greater of its two levels' (every step a lerp between bytes).
//! Spans are bounds: every sample left in is still tested exactly, so the image is the same
//! bit for bit.
//!
//! The billboard bake ([`crate::render_bake`]) walks its triangles' rows the same way, with
//! the octagon of the one level its alpha test reads.
//!
//! The octagon is the tightest polygon whose edges take these eight fixed directions: any
//! convex polygon would do; fixed directions cost one pass over each level to fit, and a row
//! evaluates each bound with a multiply and an add. Small triangles are drawn without it
//! ([`MIN_AREA`]): on them the bounds cost more than the samples they save.

use std::sync::OnceLock;

use frond_scene::Wrap;

use crate::scene::DrawScene;
use crate::software::alpha::AlphaCutoff;
use crate::software::sampling::wrap_index;
use crate::software::setup::Setup;
use crate::software::textures::SoftwareTextures;

/// The half-planes' directions `d` in `(u, v)`, those that cut most first (a triangle keeps
/// four of each kind of bound, see [`HullRows`]).
const DIRECTIONS: [[f32; 2]; 8] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [1.0, 1.0],
    [-1.0, -1.0],
    [1.0, -1.0],
    [-1.0, 1.0],
    [0.0, 1.0],
    [0.0, -1.0],
];

/// How far the octagon reaches past the footprints it bounds, in texture coordinates: the
/// half-planes are evaluated on screen by another sequence of operations than a sample's
/// texture coordinates, whose rounding differs by a few units in the last place (around
/// 10⁻⁷); this is thousands of times that.
const MARGIN: f32 = 1.0 / 1024.0;

/// How far a row's span reaches past a half-plane's computed crossing, in samples (as the
/// triangle's own edges, `SPAN_SLACK`).
const ROW_SLACK: f32 = 0.25;

/// The least area, in samples, of a triangle whose rows a coverage render bounds: on smaller
/// ones the bounds cost more than the samples they save.
const MIN_AREA: f32 = 256.0;

/// [`MIN_AREA`] of the bake, whose alpha test costs more a sample: the bounds pay off on
/// smaller triangles there.
pub(crate) const BAKE_MIN_AREA: f32 = 64.0;

/// How far off the target's origin, in samples, a bounded triangle's corners may lie (twice
/// the largest target's side): a crossing's rounding grows with the coordinates it is computed
/// from, a few hundredths of a sample here against the quarter sample of [`ROW_SLACK`].
const MAX_CORNER: f32 = 65536.0;

/// Texture coordinates a triangle's corners may have for its samples' to lie within the
/// footprints an octagon was fitted to (they reach half a texel of the level past each edge):
/// the unit square, give or take rounding.
const SQUARE_SLACK: f32 = 1e-5;

/// The region of one texture level's texture coordinates where a bilinear alpha test can pass
/// (under one wrap mode and one test's failing threshold), as the octagon
/// `dₖ·uv ≤ support[k]` over [`DIRECTIONS`]: every point of `[0, 1]²` whose footprint holds
/// a texel that does not fail lies within it. All supports are −∞ where nothing can pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct UvHull {
    support: [f32; 8],
}

impl UvHull {
    /// The octagon of the footprints of `level` (`stride` bytes a texel, alpha the last) that
    /// hold a texel of at least `fail_below` (below it, a test fails), their texels wrapped as
    /// `wrap` has them: every footprint a texture coordinate in `[0, 1]²` can have (their
    /// origins run from one texel before the level's first to its last).
    pub(crate) fn of_level(
        (w, h, texels): &(u32, u32, Vec<u8>),
        stride: usize,
        wrap: [Wrap; 2],
        fail_below: u16,
    ) -> UvHull {
        let mut support = [f32::NEG_INFINITY; 8];
        let (wf, hf) = (*w as f32, *h as f32);
        // Footprint `k` of a row has its origin at texel `k − 1`.
        let columns: Vec<[usize; 2]> = (-1..i64::from(*w))
            .map(|x| [wrap_index(x, *w, wrap[0]), wrap_index(x + 1, *w, wrap[0])])
            .collect();
        for y in -1..i64::from(*h) {
            let rows = [wrap_index(y, *h, wrap[1]), wrap_index(y + 1, *h, wrap[1])];
            let open = |k: &usize| {
                rows.iter().any(|r| {
                    let row = &texels[r * *w as usize * stride + stride - 1..];
                    columns[*k]
                        .iter()
                        .any(|&c| u16::from(row[c * stride]) >= fail_below)
                })
            };
            // The row's extreme footprints bound it for every direction.
            let Some(first) = (0..columns.len()).find(open) else {
                continue;
            };
            let last = (first..columns.len()).rev().find(open).unwrap_or(first);
            let (u0, u1) = ((first as f32 - 0.5) / wf, (last as f32 + 0.5) / wf);
            let (v0, v1) = ((y as f32 + 0.5) / hf, (y as f32 + 1.5) / hf);
            for (s, [du, dv]) in support.iter_mut().zip(DIRECTIONS) {
                for (u, v) in [(u0, v0), (u0, v1), (u1, v0), (u1, v1)] {
                    *s = s.max(du * u + dv * v + MARGIN);
                }
            }
        }
        UvHull { support }
    }

    /// Both regions in one octagon (a trilinear test passes only where one of its levels'
    /// can).
    pub(crate) fn union(self, other: UvHull) -> UvHull {
        UvHull {
            support: std::array::from_fn(|k| self.support[k].max(other.support[k])),
        }
    }

    /// Triangle `t`'s rows as this octagon bounds them, `t` textured with the level(s) it was
    /// fitted to, unless its area is below [`MIN_AREA`].
    pub(crate) fn rows(&self, t: &Setup) -> TriangleHull {
        self.rows_from(t, MIN_AREA)
    }

    /// [`UvHull::rows`] of triangles of `min_area` samples or more.
    pub(crate) fn rows_from(&self, t: &Setup, min_area: f32) -> TriangleHull {
        if t.inv_area * min_area > 0.5 {
            return TriangleHull::Unbounded;
        }
        let square = (-SQUARE_SLACK)..=(1.0 + SQUARE_SLACK);
        let in_square = (0..3).all(|i| {
            square.contains(&(t.uq[i][0] / t.q[i])) && square.contains(&(t.uq[i][1] / t.q[i]))
        });
        // The bounds' rounding stays far below the margin while `q` varies little over the
        // triangle, the triangle is not a sliver (its edge functions' gradients then stay in
        // proportion to its size) and its corners are not far off the target (the crossings
        // are computed from them): its whole extent counts, not the part on the target.
        // Anywhere else the triangle is drawn without them.
        let (q_min, q_max) = (
            t.q.iter().copied().fold(f32::INFINITY, f32::min),
            t.q.iter().copied().fold(0.0, f32::max),
        );
        let span = |c: &[f32; 3]| {
            c.iter().copied().fold(f32::NEG_INFINITY, f32::max)
                - c.iter().copied().fold(f32::INFINITY, f32::min)
        };
        let extent = span(&t.x).max(span(&t.y)) + 1.0;
        let far = t.x.iter().chain(&t.y).any(|c| c.abs() > MAX_CORNER);
        if !in_square || far || q_max > 16.0 * q_min || extent * extent * t.inv_area > 64.0 {
            return TriangleHull::Unbounded;
        }
        // Nothing passes anywhere (after the checks above: texture coordinates off the square,
        // a NaN among them, can give a NaN alpha, which passes).
        if self.support[0] == f32::NEG_INFINITY {
            return TriangleHull::Empty;
        }
        // Screen-space derivatives of the weights (as `Setup::weights` has them).
        let dx = [
            -(t.y[2] - t.y[1]) * t.inv_area,
            -(t.y[0] - t.y[2]) * t.inv_area,
            -(t.y[1] - t.y[0]) * t.inv_area,
        ];
        let dy = [
            (t.x[2] - t.x[1]) * t.inv_area,
            (t.x[0] - t.x[2]) * t.inv_area,
            (t.x[1] - t.x[0]) * t.inv_area,
        ];
        let top = t.min[1] as f32;
        let mut rows = HullRows {
            top,
            lo: [[f32::NEG_INFINITY, 0.0]; 4],
            hi: [[f32::INFINITY, 0.0]; 4],
        };
        let (mut lows, mut highs) = (0, 0);
        for (s, [du, dv]) in self.support.iter().zip(DIRECTIONS) {
            // `s·q − d·(u·q, v·q)` at the corners: the half-plane's function, linear on screen.
            let g: [f32; 3] =
                std::array::from_fn(|i| s * t.q[i] - (du * t.uq[i][0] + dv * t.uq[i][1]));
            if g.iter().all(|&v| v < 0.0) {
                return TriangleHull::Empty;
            }
            if g.iter().all(|&v| v >= 0.0) {
                continue;
            }
            // Its gradient on screen and its value at sample (0, 0)'s centre (from corner 0).
            let a = g[0] * dx[0] + g[1] * dx[1] + g[2] * dx[2];
            let b = g[0] * dy[0] + g[1] * dy[1] + g[2] * dy[2];
            let scale = g.iter().fold(0.0f32, |m, v| m.max(v.abs()));
            if a.abs() * extent < 0.1 * scale {
                // Nearly level on screen: its crossings along a row would be ill-conditioned.
                continue;
            }
            // Its crossing along the sample row `top + r` (centres at `x + 0.5`):
            // `x = x₀ − 0.5 − (g₀ + b·(top + r + 0.5 − y₀)) / a`, with `r` within the
            // triangle's height (so that nothing large cancels).
            let c = t.x[0] - 0.5 - (g[0] + b * (top + 0.5 - t.y[0])) / a;
            let d = -b / a;
            if a > 0.0 && lows < 4 {
                rows.lo[lows] = [c - ROW_SLACK, d];
                lows += 1;
            } else if a < 0.0 && highs < 4 {
                rows.hi[highs] = [c + ROW_SLACK, d];
                highs += 1;
            }
        }
        if lows + highs == 0 {
            TriangleHull::Unbounded
        } else {
            TriangleHull::Rows(rows)
        }
    }
}

/// One material's texture levels and the octagon of each where its alpha test can pass, each
/// fitted when a triangle first reads it (a render reads a few of a chain's levels).
pub(crate) struct HullLevels<'a> {
    levels: &'a [(u32, u32, Vec<u8>)],
    /// Bytes a texel: 1 for a coverage render's alpha-only levels, 4 for RGBA.
    stride: usize,
    wrap: [Wrap; 2],
    fail_below: u16,
    hulls: Vec<OnceLock<UvHull>>,
}

impl<'a> HullLevels<'a> {
    /// Per material of `scene`, its texture's levels in `textures` when it has a textured
    /// alpha test (`cutoffs`, the materials' tests) whose failing threshold is known.
    pub(crate) fn of_materials(
        scene: &DrawScene,
        textures: &'a SoftwareTextures,
        cutoffs: &[Option<AlphaCutoff>],
    ) -> Vec<Option<HullLevels<'a>>> {
        let stride = if textures.colour { 4 } else { 1 };
        (scene.materials.iter().zip(cutoffs))
            .map(|(material, cutoff)| {
                let fail_below = cutoff.as_ref()?.fail_below()?;
                let levels = textures.textures.get(material.texture?)?.levels();
                (!levels.is_empty()).then(|| HullLevels {
                    levels,
                    stride,
                    wrap: material.wrap,
                    fail_below,
                    hulls: levels.iter().map(|_| OnceLock::new()).collect(),
                })
            })
            .collect()
    }

    /// The octagon of level `k`.
    pub(crate) fn level(&self, k: usize) -> UvHull {
        *self.hulls[k].get_or_init(|| {
            UvHull::of_level(&self.levels[k], self.stride, self.wrap, self.fail_below)
        })
    }
}

/// What an octagon does to one triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) enum TriangleHull {
    /// No bound: every half-plane holds the whole triangle (or its bounds would not be safe).
    Unbounded,
    /// The triangle lies outside a half-plane: none of its samples can pass.
    Empty,
    /// Its rows' spans narrowed by the half-planes that cross it.
    Rows(HullRows),
}

/// Up to four lower and four upper bounds on a triangle's samples along each row: the bound
/// on row `top + r` is `c + d·r` (`[c, d]`; unused ones −∞ and +∞).
#[derive(Clone, Copy, Debug)]
pub(crate) struct HullRows {
    /// The triangle's first sample row.
    top: f32,
    lo: [[f32; 2]; 4],
    hi: [[f32; 2]; 4],
}

/// Row `y`'s span `first..=last` narrowed by a triangle's `bounds` where it has them, `None`
/// when they leave no sample.
#[inline]
pub(crate) fn narrowed(
    bounds: Option<&HullRows>,
    y: usize,
    first: usize,
    last: usize,
) -> Option<(usize, usize)> {
    match bounds {
        Some(rows) => rows.narrow(y, first, last),
        None => Some((first, last)),
    }
}

impl HullRows {
    /// Row `y`'s span `first..=last` narrowed to the samples the half-planes leave, `None`
    /// when they leave none.
    #[inline]
    pub(crate) fn narrow(&self, y: usize, first: usize, last: usize) -> Option<(usize, usize)> {
        let r = y as f32 - self.top;
        let mut lo = first as f32;
        let mut hi = last as f32;
        for k in 0..4 {
            lo = lo.max(self.lo[k][0] + self.lo[k][1] * r);
            hi = hi.min(self.hi[k][0] + self.hi[k][1] * r);
        }
        // Never NaN: `max` and `min` keep the finite operand.
        if lo > hi {
            return None;
        }
        // Both within `first..=last` here: the first sample at or after `lo` (a ceiling), the
        // last at or before `hi`, converted through `i64` (see `row_span`).
        let from = lo as i64 as usize + usize::from((lo as i64 as f32) < lo);
        let to = hi as i64 as usize;
        (from <= to).then_some((from, to))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16-texel-wide level transparent but for texels `(5..=9, 3..=12)`.
    fn level() -> (u32, u32, Vec<u8>) {
        let alpha = (0..16 * 16)
            .map(|i| {
                let (x, y) = (i % 16, i / 16);
                if (5..=9).contains(&x) && (3..=12).contains(&y) {
                    255
                } else {
                    0
                }
            })
            .collect();
        (16, 16, alpha)
    }

    #[test]
    fn the_octagon_holds_every_footprint_that_can_pass_and_no_more_than_it_must() {
        let hull = UvHull::of_level(&level(), 1, [Wrap::ClampToEdge; 2], 128);
        // Footprints reach half a texel either side of a texel's centre and another beyond
        // its neighbour's: opaque texels 5..=9 are read for `u·16 − 0.5` within (4, 10).
        let expect = |k: usize, value: f32| {
            assert!(
                (hull.support[k] - value - MARGIN).abs() < 1e-6,
                "{k}: {} against {value}",
                hull.support[k]
            );
        };
        expect(0, 10.5 / 16.0);
        expect(1, -4.5 / 16.0);
        expect(6, 13.5 / 16.0);
        expect(7, -2.5 / 16.0);
        // The same octagon from RGBA texels (alpha the last byte), as the bake reads them.
        let (w, h, alpha) = level();
        let rgba = alpha.iter().flat_map(|&a| [7, 7, 7, a]).collect();
        assert_eq!(
            UvHull::of_level(&(w, h, rgba), 4, [Wrap::ClampToEdge; 2], 128),
            hull
        );
        // Nothing passes a test no byte passes.
        assert!(
            UvHull::of_level(&level(), 1, [Wrap::ClampToEdge; 2], 256)
                .support
                .iter()
                .all(|s| *s == f32::NEG_INFINITY)
        );
    }

    /// A triangle whose texture coordinates leave the unit square (or are NaN, whose filtered
    /// alpha passes) is drawn whole, even where no texel of the square passes.
    #[test]
    fn triangles_off_the_square_are_drawn_whole_even_where_nothing_passes() {
        let nothing = UvHull::of_level(&level(), 1, [Wrap::ClampToEdge; 2], 256);
        let mut t = Setup {
            x: [0.0, 100.0, 0.0],
            y: [0.0, 0.0, 100.0],
            z: [0.5; 3],
            q: [1.0; 3],
            uq: [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            inv_area: 1.0 / 10_000.0,
            material: 0,
            lit: false,
            back: false,
            lod: Default::default(),
            min: [0, 0],
            max: [99, 99],
        };
        assert!(matches!(nothing.rows(&t), TriangleHull::Empty));
        for off in [[f32::NAN, 0.0], [1.5, 0.0], [0.0, -0.25]] {
            t.uq[1] = off;
            assert!(
                matches!(nothing.rows(&t), TriangleHull::Unbounded),
                "{off:?}"
            );
        }
    }

    #[test]
    fn wrapped_footprints_reach_across_the_edges() {
        // Opaque at the last column alone: a repeating texture reads it from the first
        // footprint too, a clamped one does not.
        let mut alpha = vec![0u8; 8 * 8];
        for y in 0..8 {
            alpha[y * 8 + 7] = 255;
        }
        let level = (8, 8, alpha);
        let repeat = UvHull::of_level(&level, 1, [Wrap::Repeat; 2], 128);
        let clamp = UvHull::of_level(&level, 1, [Wrap::ClampToEdge; 2], 128);
        // `−u ≤ support[1]`: the repeating one reaches u = −0.5/8 (footprint origin −1).
        assert!(repeat.support[1] >= 0.5 / 8.0);
        assert!((clamp.support[1] - (-6.5 / 8.0 + MARGIN)).abs() < 1e-6);
    }
}
