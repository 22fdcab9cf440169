//! The alpha test of the CPU rasterisers: a material's test with its answers for byte bounds
//! tabulated ([`AlphaCutoff`]), the alpha bounds of every bilinear footprint of a level
//! ([`AlphaBounds`]), and a coverage render's trilinear test decided from them
//! ([`Levels::alpha_test`]).

use frond_scene::Wrap;

use super::sampling::{Levels, Trilinear, bilerp, floor_i64, footprint};
use crate::scene::{DrawAlpha, DrawScene};

/// The alpha test: discarded only when `alpha < cutoff` (a NaN alpha is kept, as the renderer
/// always kept it).
#[inline]
pub(crate) fn passes_cutoff(alpha: f32, cutoff: f32) -> bool {
    alpha.partial_cmp(&cutoff) != Some(std::cmp::Ordering::Less)
}

/// A material's alpha test, `alpha · scale ≥ cutoff` ([`passes_cutoff`]), with its answers
/// for footprint bounds tabulated: the bounds are bytes, so whether a bound settles the test
/// is looked up rather than computed (a division and two conversions a sample, most of a
/// coverage render's samples being decided so).
pub(crate) struct AlphaCutoff {
    /// What alpha is multiplied by before the test (the material's base colour alpha).
    pub(super) scale: f32,
    /// Alpha below this fails.
    pub(super) cutoff: f32,
    /// Per byte `b`: `b/255 · scale ≥ cutoff` (a footprint whose least alpha is `b` passes).
    pass: [bool; 256],
    /// Per byte `b`: `b/255 · scale < cutoff` (a footprint whose greatest alpha is `b` fails).
    fail: [bool; 256],
    /// The two tables as thresholds ([`AlphaCutoff::thresholds`]).
    pub(super) thresholds: Option<(u16, u16)>,
    /// The least filtered alpha (in bytes' units) that passes ([`AlphaCutoff::least_passing`]).
    pub(super) least_passing: Option<f32>,
}

impl AlphaCutoff {
    /// The test `alpha · scale ≥ cutoff`, its tables and thresholds computed.
    pub(crate) fn new(scale: f32, cutoff: f32) -> AlphaCutoff {
        let at = |b: usize| f32::from(b as u8) / 255.0 * scale;
        // A negative (or NaN) scale reverses the test's order: bounds then settle nothing.
        let monotone = scale >= 0.0;
        let pass = std::array::from_fn(|b| monotone && at(b) >= cutoff);
        let fail = std::array::from_fn(|b| monotone && at(b) < cutoff);
        AlphaCutoff {
            scale,
            cutoff,
            pass,
            fail,
            thresholds: Self::thresholds(&pass, &fail),
            least_passing: Self::least_passing(scale, cutoff),
        }
    }

    /// The least alpha `a` (in bytes' units, 0 to 255; infinity when none) with
    /// `a / 255 · scale ≥ cutoff` as [`passes_cutoff`] computes it, found by bisecting the
    /// floats: every alpha from it on passes, every one below fails, so one comparison
    /// decides a filtered alpha (the eight-sample test's division and multiplication were on
    /// its critical path). `None` where the test is not monotone (a negative or NaN scale, a
    /// NaN cutoff).
    fn least_passing(scale: f32, cutoff: f32) -> Option<f32> {
        if scale.is_nan() || scale < 0.0 || cutoff.is_nan() {
            return None;
        }
        let passes = |a: f32| passes_cutoff(a / 255.0 * scale, cutoff);
        if passes(0.0) {
            return Some(0.0);
        }
        if !passes(255.0) {
            return Some(f32::INFINITY);
        }
        // Non-negative floats order as their bits; `lo` fails, `hi` passes.
        let (mut lo, mut hi) = (0.0f32.to_bits(), 255.0f32.to_bits());
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if passes(f32::from_bits(mid)) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(f32::from_bits(hi))
    }

    /// The test's answer for every alpha within the footprint bounds `[lo, hi]` (bytes), when
    /// they settle it: monotone in every texel, a filtered alpha lies within its footprint's
    /// bounds, and the same operations on the bounds bound the result.
    #[inline]
    pub(super) fn decided(&self, [lo, hi]: [u8; 2]) -> Option<bool> {
        if self.pass[usize::from(lo)] {
            Some(true)
        } else if self.fail[usize::from(hi)] {
            Some(false)
        } else {
            None
        }
    }

    /// The `pass` and `fail` tables as thresholds, `(pass_from, fail_below)`: a footprint whose
    /// least alpha is at least the first passes, one whose greatest is below the second fails
    /// (what [`AlphaCutoff::decided`] looks up, as two comparisons for the eight-sample test).
    /// `None` where the tables are not of that shape (they always are: the test is monotone).
    fn thresholds(pass: &[bool; 256], fail: &[bool; 256]) -> Option<(u16, u16)> {
        let pass_from = pass.iter().position(|&p| p).unwrap_or(256);
        let fail_below = fail.iter().take_while(|&&f| f).count();
        let shaped = (0..256).all(|b| pass[b] == (b >= pass_from) && fail[b] == (b < fail_below));
        shaped.then_some((pass_from as u16, fail_below as u16))
    }

    /// The byte below which a footprint's greatest alpha fails the test
    /// ([`AlphaCutoff::thresholds`]), when the test is monotone.
    pub(crate) fn fail_below(&self) -> Option<u16> {
        self.thresholds.map(|(_, fail_below)| fail_below)
    }

    /// The test of a filtered `alpha` (0..1).
    #[inline]
    pub(crate) fn passes(&self, alpha: f32) -> bool {
        passes_cutoff(alpha * self.scale, self.cutoff)
    }

    /// Each material's test of `scene` (its base colour's alpha the scale), its cutoff
    /// chosen by `cutoff`: [`DrawAlpha::test_cutoff`] where every surface is tested (the bake:
    /// a blended material at ½), [`DrawAlpha::mask_cutoff`] where blended materials are
    /// blended (coverage renders); `None` for a material without one.
    pub(crate) fn of_materials(
        scene: &DrawScene,
        cutoff: fn(DrawAlpha) -> Option<f32>,
    ) -> Vec<Option<AlphaCutoff>> {
        (scene.materials.iter())
            .map(|m| cutoff(m.alpha).map(|c| AlphaCutoff::new(m.base_color[3], c)))
            .collect()
    }
}

/// The least and greatest alpha of each interior bilinear footprint of one alpha-only level:
/// entry `y·w + x` bounds texels `(x..=x+1, y..=y+1)` (`[0, 255]`, deciding nothing, where
/// the footprint would wrap). A filtered alpha lies between its footprint's bounds, and so
/// does a trilinear blend of two levels' (every step is a monotone lerp), so most alpha tests
/// are decided without filtering: in a coverage render a sample is tested by every leaf card
/// over it until one passes, and the filtering was most of the rasteriser's time.
/// `trilinear` (with the next level, none for the last) widens each entry by every footprint
/// of the next level that a point of the same footprint cell can read, so a trilinear test is
/// decided from one footprint and one entry, the next level's footprint found only when the
/// entry leaves it open.
#[derive(Clone, Debug)]
pub(crate) struct AlphaBounds {
    /// Per footprint of the level (top left texel's index, one padding entry at the end), its
    /// least and greatest alpha.
    pub(super) footprint: Vec<[u8; 2]>,
    /// Per footprint, [`AlphaBounds::footprint`] widened by the next level's footprints a
    /// point of its cell can read (empty for the last level, or when prepared without).
    pub(super) trilinear: Vec<[u8; 2]>,
}

/// An alpha level's bilinear footprints as four bytes each ([`SoftwareTextures::bake_quads`](super::textures::SoftwareTextures::bake_quads)):
/// `[top left, top right, bottom left, bottom right]` at the top left texel's index, for
/// the footprints within the level; 0 on its last row and column, where footprints wrap.
pub(super) fn footprint_quads(level: &(u32, u32, Vec<u8>)) -> Vec<u32> {
    let mut quads = vec![0u32; level.2.len()];
    for_footprints(level, |i, q| quads[i] = u32::from_le_bytes(q));
    quads
}

/// `f(i, [top left, top right, bottom left, bottom right])` for each bilinear footprint
/// within an alpha level (its top left texel `i`, not on the last row or column).
fn for_footprints((w, h, alpha): &(u32, u32, Vec<u8>), mut f: impl FnMut(usize, [u8; 4])) {
    let (w, h) = (*w as usize, *h as usize);
    for y in 0..h.saturating_sub(1) {
        let (top, bottom) = (&alpha[y * w..(y + 1) * w], &alpha[(y + 1) * w..(y + 2) * w]);
        for x in 0..w - 1 {
            f(y * w + x, [top[x], top[x + 1], bottom[x], bottom[x + 1]]);
        }
    }
}

impl AlphaBounds {
    /// The bounds of `level`'s footprints, widened by those of `next` (the following level)
    /// for trilinear tests when given.
    pub(super) fn new(
        level: &(u32, u32, Vec<u8>),
        next: Option<&(u32, u32, Vec<u8>)>,
    ) -> AlphaBounds {
        let (w, h, alpha) = level;
        let (w, h) = (*w as usize, *h as usize);
        // One entry more than the footprints: the eight-sample test reads each entry as four
        // bytes (`crate::sample_lanes`), the last one's with this padding.
        let mut bounds = vec![[0u8, 255u8]; alpha.len() + 1];
        for_footprints(level, |i, q| {
            bounds[i] = [
                q.iter().copied().fold(u8::MAX, u8::min),
                q.iter().copied().fold(0, u8::max),
            ];
        });
        let trilinear = next.map_or_else(Vec::new, |(nw, nh, next)| {
            let (nw, nh) = (*nw as usize, *nh as usize);
            // The next level's first footprint texels a point of cell `c` (of `n` a side here,
            // `m` there) can read: `uv` within `[(c + 0.5)/n, (c + 1.5)/n)`, so
            // `uv·m − 0.5` within this range (padded against rounding); `None` when a
            // footprint there would leave the level (it wraps: not in the table).
            let reach = |c: usize, n: usize, m: usize| {
                let (n, m) = (n as f32, m as f32);
                let lo = (c as f32 + 0.5) / n * m - 0.5 - 0.01;
                let hi = (c as f32 + 1.5) / n * m - 0.5 + 0.01;
                (lo >= 0.0 && hi < m - 1.0).then(|| (lo as usize, hi as usize + 1))
            };
            let mut out = vec![[0u8, 255u8]; alpha.len() + 1];
            for y in 0..h.saturating_sub(1) {
                let Some((y0, y1)) = reach(y, h, nh) else {
                    continue;
                };
                for x in 0..w - 1 {
                    let Some((x0, x1)) = reach(x, w, nw) else {
                        continue;
                    };
                    let mut r = bounds[y * w + x];
                    for row in next[y0 * nw..(y1 + 1) * nw].chunks_exact(nw) {
                        for &a in &row[x0..=x1] {
                            r = [r[0].min(a), r[1].max(a)];
                        }
                    }
                    out[y * w + x] = r;
                }
            }
            out
        });
        AlphaBounds {
            footprint: bounds,
            trilinear,
        }
    }

    /// The entry of a level's bounds for the bilinear footprint at `uv` (the level's texels
    /// RGBA or alpha alone: only its size counts), as [`footprint`] finds it, when that lies
    /// on the level: the last row and column hold `[0, 255]` (their footprints wrap).
    #[inline(always)]
    pub(super) fn cell((w, h, _): &(u32, u32, Vec<u8>), uv: [f32; 2]) -> Option<usize> {
        let x0 = floor_i64(uv[0] * *w as f32 - 0.5);
        let y0 = floor_i64(uv[1] * *h as f32 - 0.5);
        ((0..i64::from(*w)).contains(&x0) && (0..i64::from(*h)).contains(&y0))
            .then(|| y0 as usize * *w as usize + x0 as usize)
    }

    /// Every level's bounds of a chain.
    pub(super) fn chain(levels: &Levels) -> Vec<AlphaBounds> {
        (0..levels.0.len())
            .map(|k| AlphaBounds::new(&levels.0[k], levels.0.get(k + 1)))
            .collect()
    }
}

impl Levels {
    /// The alpha test of a coverage render, `alpha(uv) · scale ≥ cutoff` with the trilinear
    /// alpha of [`Levels::alpha`] (alpha-only levels, `bounds` theirs): the same answer,
    /// filtering only when the footprints' [`AlphaBounds`] leave it open.
    #[inline]
    pub(super) fn alpha_test(
        &self,
        bounds: &[AlphaBounds],
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        cutoff: &AlphaCutoff,
    ) -> bool {
        let (a, b) = (lod.a as usize, lod.b as usize);
        let trilinear = lod.f > 0.0;
        // The first footprint's entry (a footprint off the level is filtered below).
        let table = &bounds[a];
        if let Some(cell) = AlphaBounds::cell(&self.0[a], uv) {
            let range = if !trilinear {
                table.footprint[cell]
            } else if b == a + 1 && !table.trilinear.is_empty() {
                table.trilinear[cell]
            } else {
                [0, 255]
            };
            if let Some(pass) = cutoff.decided(range) {
                return pass;
            }
        }
        let fa = footprint(&self.0[a], uv, wrap, 1);
        let fb = trilinear.then(|| footprint(&self.0[b], uv, wrap, 1));
        let filter = |(o, fx, fy): ([usize; 4], f32, f32), level: usize| {
            let data = &self.0[level].2;
            bilerp(o.map(|k| f32::from(data[k])), fx, fy)
        };
        let mut alpha = filter(fa, a);
        if let Some(fb) = fb {
            alpha += (filter(fb, b) - alpha) * lod.f;
        }
        cutoff.passes(alpha / 255.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::software::test_scenes::{assert_alpha_tests_match, leaf_alpha};

    #[test]
    fn the_least_passing_alpha_splits_the_test() {
        for (scale, cutoff) in [
            (1.0, 0.5),
            (0.8, 0.33),
            (1.0, 0.001),
            (0.37, 0.9),
            (2.0, 0.0),
        ] {
            let test = AlphaCutoff::new(scale, cutoff);
            let least = test.least_passing.expect("monotone");
            let mut alphas: Vec<f32> = (0..=255 * 64).map(|i| i as f32 / 64.0).collect();
            alphas.extend([least, least.next_down(), least.next_up(), 255.0, 0.0]);
            // Filtered alphas lie within their texels' bytes.
            for a in alphas.into_iter().filter(|a| (0.0..=255.0).contains(a)) {
                assert_eq!(a >= least, test.passes(a / 255.0), "{scale} {cutoff} {a}");
            }
        }
        assert_eq!(
            AlphaCutoff::new(0.2, 0.5).least_passing,
            Some(f32::INFINITY)
        );
        assert_eq!(AlphaCutoff::new(-1.0, 0.5).least_passing, None);
        assert_eq!(AlphaCutoff::new(1.0, f32::NAN).least_passing, None);
    }

    /// The alpha test decided from the footprints' bounds (trilinear: one footprint and the
    /// widened entry) answers as filtering does.
    #[test]
    fn bounded_alpha_test_matches_the_filtered_one() {
        let (w, h, alpha) = leaf_alpha();
        let levels = Levels(crate::pipeline::alpha_mip_chain(w, h, &alpha));
        let bounds = AlphaBounds::chain(&levels);
        assert_alpha_tests_match(
            &levels,
            [0.0, 0.3, 1.0, 1.7, 2.5, 9.0],
            |uv, pair, wrap| levels.alpha(uv, pair, [wrap; 2], 1),
            |uv, pair, wrap, [scale, cutoff]| {
                levels.alpha_test(
                    &bounds,
                    uv,
                    pair,
                    [wrap; 2],
                    &AlphaCutoff::new(scale, cutoff),
                )
            },
        );
    }
}
