//! Which leaf cards a LOD can spare, judged by what they cover on screen (the card LOD).
//! Every card is rasterised, alpha-tested with its own texture, into a ring of orthographic
//! views at the LOD's pixel size; a card whose pixels other cards also cover adds
//! nothing to the tree's silhouette, so thinning drops, one at a time, the card that covers the
//! fewest pixels no other card covers ([`CardCoverage::thin`]). The survivors are then grown by
//! the smallest scale at which they cover as much of these views as all the cards did
//! ([`CardCoverage::coverage_keeping_scale`]): a thinned LOD keeps the crown's coverage. The
//! scale closest to the input's sample by sample in these rest-pose views stays near 1, which
//! leaves far LODs thinner than the input and worse by the coverage metric, whose moving
//! leaves never sit where the rest pose put them (docs/experiments.md, card scale).
//!
//! The rasteriser is written here: the greedy needs, per sample, how many cards cover it and
//! which one when only one does (a count and an XOR of card indices), which no rasteriser crate
//! keeps; a card is a few triangles a few samples wide.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use frond_scene::wood::WoodMesh;
use frond_scene::{AlphaMode, Bounds, Tree, Wrap};

/// Views of the ring at eye level (the coverage metric's viewers, spec §8.2) …
const RING_VIEWS: usize = 8;
/// … and from above at [`ELEVATED_DEG`], between them: trees are also seen from hills and
/// cameras above the ground.
const ELEVATED_VIEWS: usize = 4;
const ELEVATED_DEG: f32 = 40.0;
/// Samples per pixel side: cards smaller than a pixel still cover part of one, which sampling
/// pixel centres alone would miss (the coverage metric counts many samples a pixel for the
/// same reason).
const SUPERSAMPLE: f32 = 4.0;
/// Samples over the tree's height of the coverage metric's renders, at least
/// (`frond_metrics::framing::SAMPLES_OVER_HEIGHT`, downstream of this crate).
const METRIC_SAMPLES: f32 = 512.0;
/// At most this many samples across the tree's height per view: bounds memory and time at
/// near sizes, where leaves span several pixels and a coarser grid still resolves them.
const MAX_SAMPLES_ACROSS: f32 = 512.0;
/// Samples across a typical (median) card are enough at this many: cards much larger than a
/// pixel are sampled coarser than the screen, which decides the same cards at a fraction of
/// the work (the sample tree's leaves span 40 pixels at 600 px).
const CARD_SAMPLES_ACROSS: f32 = 8.0;
/// At most this many samples along any side of a view (the bounds' diagonal): a tree is
/// about as wide as it is tall, so [`MAX_SAMPLES_ACROSS`] decides, but a file whose bounds
/// are far wider than its height (one stray vertex) would otherwise ask for a grid of
/// gigabytes.
const MAX_VIEW_SIDE: f32 = 2048.0;

/// What [`CardCoverage::raster`] tells about a card's covered samples.
trait Sink {
    /// Whether sample `s` still needs testing: a mask skips the samples it already holds.
    fn wants(&self, s: usize) -> bool;
    /// Sample `s` is covered by the card.
    fn hit(&mut self, s: usize);
}

/// Every covered sample, to a closure (the cover counts of thinning).
struct Every<F>(F);

impl<F: FnMut(usize)> Sink for Every<F> {
    #[inline]
    fn wants(&self, _: usize) -> bool {
        true
    }

    #[inline]
    fn hit(&mut self, s: usize) {
        (self.0)(s);
    }
}

/// A coverage mask: a sample already covered is not tested again (most of a dense crown's are,
/// many times over), which sets the same samples.
struct Mask<'a>(&'a mut [bool]);

impl Sink for Mask<'_> {
    #[inline]
    fn wants(&self, s: usize) -> bool {
        !self.0[s]
    }

    #[inline]
    fn hit(&mut self, s: usize) {
        self.0[s] = true;
    }
}

/// The samples `x0..x1` of the row at height `sy` (sample centres at `x + 0.5`, within
/// `lo..hi`) that can lie inside a triangle of `edges` (counter-clockwise): each edge function
/// is linear along the row, and its zero bounds the span, widened by a sample against rounding
/// (every sample is still tested exactly). `None` when the row misses the triangle.
#[inline]
fn row_span(edges: &[(Vec2, Vec2); 3], sy: f32, lo: f32, hi: f32) -> Option<(usize, usize)> {
    let (mut a, mut b) = (lo, hi);
    for (p, q) in edges {
        let d = *q - *p;
        // w(x) = d.x·(sy − p.y) − d.y·(x + 0.5 − p.x) ≥ 0.
        let at = d.x * (sy - p.y);
        if d.y < 0.0 {
            a = a.max((p.x + at / d.y - 0.5).floor() - 1.0);
        } else if d.y > 0.0 {
            b = b.min((p.x + at / d.y - 0.5).ceil() + 2.0);
        } else if at < 0.0 {
            return None;
        }
    }
    (a < b).then(|| (a.max(lo) as usize, b.min(hi) as usize))
}

/// One view's cover by the cards ([`CardCoverage::cover`]).
struct Cover {
    count: Vec<u32>,
    xor: Vec<u32>,
    cards: CardSamples,
}

/// One view's covered samples of every card, card by card: card `c`'s are
/// `samples[start[c]..start[c + 1]]`.
struct CardSamples {
    start: Vec<usize>,
    samples: Vec<u32>,
}

impl CardSamples {
    fn of(&self, card: usize) -> &[u32] {
        &self.samples[self.start[card]..self.start[card + 1]]
    }
}

/// One view: an orthographic projection onto `right`/`up`, sample `(0, 0)` at `origin`.
struct View {
    right: Vec3,
    up: Vec3,
    origin: Vec2,
    width: usize,
    height: usize,
}

/// A card's triangles at rest: positions, base-colour coordinates, and how its texture is
/// alpha-tested.
struct Card {
    triangles: Vec<[(Vec3, Vec2); 3]>,
    centre: Vec3,
    /// Texture index into the tree's textures, the alpha a sample needs and how the texture
    /// wraps; `None`: opaque.
    alpha: Option<(usize, f32, [Wrap; 2])>,
}

/// Largest side of the alpha maps the rasteriser samples: the renderer's mip levels from the
/// first this small stay in cache (on full-size maps every lookup is a cache miss), and a card
/// is a few samples wide.
const ALPHA_MAP_SIDE: u32 = 256;

/// A texture's alpha as the renderer samples it: its coverage-preserving mip levels
/// ([`frond_render::alpha_mip_chain`]) from the first no larger than [`ALPHA_MAP_SIDE`] a side. At a
/// far LOD a leaf card is a few samples wide and the renderer reads a small, coarse level (a
/// blob that keeps the card's covered fraction), not the full map's thin outline: thinning and
/// the scale search judge the same shapes the coverage metric will see.
struct AlphaMap {
    /// The full texture's size in texels (what mip levels are counted from).
    size: Vec2,
    /// Level of the full texture that `levels[0]` is.
    first: usize,
    /// `(width, height, alpha)` per level.
    levels: Vec<(usize, usize, Vec<u8>)>,
}

impl AlphaMap {
    fn of(t: &frond_scene::Texture) -> AlphaMap {
        let alpha: Vec<u8> = t.rgba.chunks_exact(4).map(|p| p[3]).collect();
        let chain = frond_render::alpha_mip_chain(t.width, t.height, &alpha);
        let first = chain
            .iter()
            .position(|(w, h, _)| (*w).max(*h) <= ALPHA_MAP_SIDE)
            .unwrap_or(chain.len().saturating_sub(1));
        let levels = chain
            .into_iter()
            .skip(first)
            .map(|(w, h, alpha)| (w as usize, h as usize, alpha))
            .collect();
        AlphaMap {
            size: Vec2::new(t.width as f32, t.height as f32),
            first,
            levels,
        }
    }

    /// The level pair mip level `lod` of the full texture reads: the first kept level at or
    /// below it and the weight of the next (0 at the last level).
    fn level(&self, lod: f32) -> (usize, f32) {
        let l = (lod - self.first as f32).max(0.0);
        let last = self.levels.len().saturating_sub(1);
        let k = (l as usize).min(last);
        (k, if k == last { 0.0 } else { l - k as f32 })
    }

    /// Alpha (0..1) at `uv` (outside [0, 1] as `wrap` says) at the level pair `(k, frac)`
    /// ([`AlphaMap::level`]): nearest texel of the two levels, blended linearly between them
    /// (the renderer's trilinear filter, point-sampled within a level).
    #[inline(always)]
    fn at(&self, uv: Vec2, (k, frac): (usize, f32), wrap: [Wrap; 2]) -> f32 {
        // Inside the texture (nearly always) without the wrap's remainder: a libm call in
        // this hot loop.
        let index = |x: f32, n: usize, w: Wrap| {
            let t = x * n as f32;
            if (0.0..n as f32).contains(&t) {
                // Through `i32` (`t` is below the side): one instruction where a conversion
                // to `usize` is a sequence.
                t as i32 as usize
            } else {
                w.texel(t, n as u32) as usize
            }
        };
        let texel = |level: &(usize, usize, Vec<u8>)| {
            let (w, h, a) = level;
            if *w == 0 || *h == 0 {
                return 1.0;
            }
            let x = index(uv.x, *w, wrap[0]);
            let y = index(uv.y, *h, wrap[1]);
            f32::from(a[y * w + x]) / 255.0
        };
        let Some(a) = self.levels.get(k) else {
            return 1.0;
        };
        match self.levels.get(k + 1) {
            Some(b) if frac > 0.0 => texel(a) * (1.0 - frac) + texel(b) * frac,
            _ => texel(a),
        }
    }
}

/// Halvings of [`CardCoverage::coverage_keeping_scale`]'s bracket: the scale to within 1/32 of
/// its range.
const COVERAGE_BISECTIONS: usize = 5;

/// Samples a view's mask covers.
fn covered(mask: &[bool]) -> usize {
    mask.iter().filter(|c| **c).count()
}

/// The input's cards seen from the views, with the samples' cover counts.
pub struct CardCoverage {
    /// Per texture of the tree, its alpha map when some card samples it.
    alpha_maps: Vec<Option<AlphaMap>>,
    /// Every view's coverage by all cards, unscaled: what thinning is judged against. Read off
    /// [`CardCoverage::thin`]'s cover counts when it ran, else rasterised on first use.
    original: OnceLock<Vec<Vec<bool>>>,
    views: Vec<View>,
    /// World units per sample.
    spacing: f32,
    /// World units per sample of the coverage metric's render at this LOD's size, whose
    /// sample footprint sets the mip level it reads: at least [`METRIC_SAMPLES`] samples over
    /// the tree's height and 2 per pixel side (`frond_metrics::framing`'s rule).
    render_spacing: f32,
    /// Samples per pixel side, when the samples are finer than pixels: coverage is compared
    /// per pixel, as the metric does.
    per_pixel: usize,
    cards: Vec<Card>,
}

impl CardCoverage {
    /// The cards `pieces` of `foliage` (as `(primitive, triangle)` lists) seen at `pixel` world
    /// units per pixel; `bounds` frames every view.
    pub fn new(
        tree: &Tree,
        foliage: &WoodMesh,
        pieces: &[Vec<(usize, usize)>],
        bounds: &Bounds,
        pixel: f32,
    ) -> Self {
        let height = tree.height().max(f32::MIN_POSITIVE);
        let cards: Vec<Card> = pieces
            .iter()
            .map(|tris| card(tree, foliage, tris))
            .collect();
        let mut sides: Vec<f32> = cards.iter().map(Card::side).collect();
        sides.sort_unstable_by(f32::total_cmp);
        let typical = sides.get(sides.len() / 2).copied().unwrap_or(0.0);
        let spacing = (pixel / SUPERSAMPLE)
            .max(height / MAX_SAMPLES_ACROSS)
            .max(typical / CARD_SAMPLES_ACROSS)
            .max(bounds.diagonal() / MAX_VIEW_SIDE);
        let views = views(bounds, spacing);
        let mut alpha_maps: Vec<Option<AlphaMap>> =
            (0..tree.textures.len()).map(|_| None).collect();
        for c in &cards {
            if let Some((t, _, _)) = c.alpha
                && alpha_maps[t].is_none()
            {
                alpha_maps[t] = Some(AlphaMap::of(&tree.textures[t]));
            }
        }
        CardCoverage {
            alpha_maps,
            original: OnceLock::new(),
            views,
            spacing,
            render_spacing: (pixel / 2.0).min(height / METRIC_SAMPLES),
            per_pixel: ((pixel / spacing).round() as usize).max(1),
            cards,
        }
    }

    /// Calls `f` once with every sample of `view` that `card`, scaled by `scale` about its
    /// centre, covers. A sample on an edge belongs to the triangle on the edge's left or top
    /// side only (the usual fill rule), so the two triangles of a quad never both claim the
    /// samples on their shared diagonal.
    fn raster(&self, view: &View, card: usize, scale: f32, sink: &mut impl Sink) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the machine has AVX2, just checked.
            return unsafe { self.raster_avx2(view, card, scale, sink) };
        }
        self.raster_body(view, card, scale, sink);
    }

    /// [`CardCoverage::raster`] compiled for AVX2 (rounding and conversions are single
    /// instructions there, library calls or sequences on baseline x86-64): the same
    /// operations, rounded the same (no fused multiply-add is enabled), so the same samples.
    ///
    /// # Safety
    /// The machine must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn raster_avx2(&self, view: &View, card: usize, scale: f32, sink: &mut impl Sink) {
        self.raster_body(view, card, scale, sink);
    }

    /// [`CardCoverage::raster`]'s work, for each instruction set it is compiled for.
    #[inline(always)]
    fn raster_body(&self, view: &View, card: usize, scale: f32, sink: &mut impl Sink) {
        let c = &self.cards[card];
        for tri in &c.triangles {
            let mut p = tri.map(|(pos, _)| {
                let w = c.centre + (pos - c.centre) * scale;
                Vec2::new(w.dot(view.right), w.dot(view.up)) / self.spacing - view.origin
            });
            let mut uv = tri.map(|(_, t)| t);
            let mut area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
            if area.abs() <= f32::EPSILON {
                continue;
            }
            if area < 0.0 {
                p.swap(1, 2);
                uv.swap(1, 2);
                area = -area;
            }
            // The texture, its cutoff and the mip level the renderer reads on this triangle.
            let alpha = c.alpha.and_then(|(texture, cutoff, wrap)| {
                let map = self.alpha_maps.get(texture)?.as_ref()?;
                Some((
                    map,
                    cutoff,
                    wrap,
                    map.level(self.mip_level(&p, &uv, map.size)),
                ))
            });
            let lo = p[0].min(p[1]).min(p[2]).floor().max(Vec2::ZERO);
            let hi = p[0].max(p[1]).max(p[2]).ceil();
            let hi = hi.min(Vec2::new(view.width as f32, view.height as f32));
            if lo.x >= hi.x || lo.y >= hi.y {
                continue;
            }
            // Edge k is the one opposite vertex k; counter-clockwise, a sample is inside when
            // every edge function is positive, or zero on a top or left edge.
            let edges = [(p[1], p[2]), (p[2], p[0]), (p[0], p[1])];
            let owns_zero = edges.map(|(a, b)| {
                let d = b - a;
                d.y < 0.0 || (d.y == 0.0 && d.x > 0.0)
            });
            for y in lo.y as usize..hi.y as usize {
                let sy = y as f32 + 0.5;
                let Some((x0, x1)) = row_span(&edges, sy, lo.x, hi.x) else {
                    continue;
                };
                for x in x0..x1 {
                    let i = y * view.width + x;
                    if !sink.wants(i) {
                        continue;
                    }
                    let s = Vec2::new(x as f32 + 0.5, sy);
                    let w = [0, 1, 2].map(|k| (edges[k].1 - edges[k].0).perp_dot(s - edges[k].0));
                    if (0..3).any(|k| w[k] < 0.0 || (w[k] == 0.0 && !owns_zero[k])) {
                        continue;
                    }
                    if let Some((map, cutoff, wrap, level)) = alpha {
                        let t = (uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2]) / area;
                        if map.at(t, level, wrap) < cutoff {
                            continue;
                        }
                    }
                    sink.hit(i);
                }
            }
        }
    }

    /// The mip level the renderer samples a triangle at, corners `p` in samples and `uv` in
    /// texture coordinates of a `size` texture: log₂ of the larger texel step per sample of the
    /// coverage metric's render (the GPU's rule; an orthographic view maps a triangle
    /// affinely, so it is one level).
    fn mip_level(&self, p: &[Vec2; 3], uv: &[Vec2; 3], size: Vec2) -> f32 {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (t1, t2) = ((uv[1] - uv[0]) * size, (uv[2] - uv[0]) * size);
        let det = e1.perp_dot(e2);
        if det.abs() <= f32::EPSILON {
            return 0.0;
        }
        // J = [t1 t2] · [e1 e2]⁻¹: its columns are the texel steps along x and y.
        let dx = (t1 * e2.y - t2 * e1.y) / det;
        let dy = (t2 * e1.x - t1 * e2.x) / det;
        let step = dx.length().max(dy.length()) * self.render_spacing / self.spacing;
        step.max(1.0).log2()
    }

    /// Every card's cover of `view`, rasterised once: per sample how many cards cover it and
    /// the XOR of their indices (the one card, when one does), and each card's covered samples,
    /// so that thinning replays a dropped card's instead of rasterising it again.
    fn cover(&self, view: &View) -> Cover {
        let n = self.cards.len();
        let mut count = vec![0u32; view.width * view.height];
        let mut xor = vec![0u32; view.width * view.height];
        let mut cards = CardSamples {
            start: Vec::with_capacity(n + 1),
            samples: Vec::new(),
        };
        for c in 0..n {
            cards.start.push(cards.samples.len());
            self.raster(
                view,
                c,
                1.0,
                &mut Every(|s: usize| {
                    count[s] += 1;
                    xor[s] ^= c as u32;
                    cards.samples.push(s as u32);
                }),
            );
        }
        cards.start.push(cards.samples.len());
        Cover { count, xor, cards }
    }

    /// Chooses the cards to keep: at most `max_triangles` triangles of them (at least one
    /// card), dropping first the card with the fewest samples no other card covers, per
    /// triangle it frees. `tie` orders cards that free the same (a seeded shuffle, so equal
    /// cards are not dropped in file order, which is often spatial).
    pub fn thin(&self, triangles: &[usize], max_triangles: usize, tie: &[u32]) -> Vec<bool> {
        let n = self.cards.len();
        let mut keep = vec![true; n];
        let mut total: usize = triangles.iter().sum();
        if total <= max_triangles || n <= 1 {
            return keep;
        }
        let mut buffers: Vec<Cover> = self.views.par_iter().map(|v| self.cover(v)).collect();
        let _ = self.original.set(
            buffers
                .iter()
                .map(|cover| cover.count.iter().map(|&k| k > 0).collect())
                .collect(),
        );
        let mut unique = vec![0u64; n];
        for Cover { count, xor, .. } in &buffers {
            for (s, &k) in count.iter().enumerate() {
                if k == 1 {
                    unique[xor[s] as usize] += 1;
                }
            }
        }
        // Lazy min-heap on samples lost per triangle freed; a card's own count only grows as
        // others go, so an entry is current when it matches.
        let key = |u: u64, c: usize| (u * 1024 / triangles[c].max(1) as u64, tie[c], c);
        let mut heap: BinaryHeap<Reverse<(u64, u32, usize)>> =
            (0..n).map(|c| Reverse(key(unique[c], c))).collect();
        let mut kept = n;
        while total > max_triangles && kept > 1 {
            let Some(Reverse((k, _, c))) = heap.pop() else {
                break;
            };
            if !keep[c] {
                continue;
            }
            let current = key(unique[c], c);
            if current.0 != k {
                heap.push(Reverse(current));
                continue;
            }
            keep[c] = false;
            kept -= 1;
            total -= triangles[c];
            for Cover { count, xor, cards } in &mut buffers {
                for &s in cards.of(c) {
                    let s = s as usize;
                    count[s] -= 1;
                    xor[s] ^= c as u32;
                    if count[s] == 1 {
                        unique[xor[s] as usize] += 1;
                    }
                }
            }
        }
        keep
    }

    /// The smallest scale in `1..=most` at which the cards `keep` marks, each scaled about its
    /// centre, cover as many samples of the views as all the cards do: thinning keeps the
    /// crown's coverage. Found by bisection (`COVERAGE_BISECTIONS` halvings; the covered
    /// count grows with the scale); `most` when even that covers less.
    pub fn coverage_keeping_scale(&self, keep: &[bool], most: f32) -> f32 {
        let original = self
            .original
            .get_or_init(|| self.masks(&vec![true; self.cards.len()], 1.0));
        let target: usize = original.iter().map(|m| covered(m)).sum();
        let covers = |scale: f32| {
            self.masks(keep, scale)
                .iter()
                .map(|m| covered(m))
                .sum::<usize>()
        };
        if most.is_nan() || most <= 1.0 || covers(1.0) >= target {
            return 1.0;
        }
        // `hi` stays `most` unless a smaller scale covers the target.
        let (mut lo, mut hi) = (1.0f32, most);
        for _ in 0..COVERAGE_BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if covers(mid) >= target {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Every view's coverage by the cards `keep` marks, scaled by `scale`.
    pub fn masks(&self, keep: &[bool], scale: f32) -> Vec<Vec<bool>> {
        let cards: Vec<usize> = (0..self.cards.len()).filter(|&c| keep[c]).collect();
        self.views
            .par_iter()
            .map(|v| self.mask(v, &cards, scale))
            .collect()
    }

    /// Over all views, the coverage by the cards `keep` marks, scaled by `scale`, that differs
    /// from `original` ([`CardCoverage::masks`]): per pixel the difference of the two covered
    /// sample counts, summed — the coverage error's numerator (spec animated-billboard-clouds
    /// §5.4 on covered fractions, `frond_metrics::coverage`) on these views, in samples.
    pub fn differing(&self, original: &[Vec<bool>], keep: &[bool], scale: f32) -> u64 {
        self.masks(keep, scale)
            .iter()
            .zip(original)
            .zip(&self.views)
            .map(|((m, o), v)| {
                let (a, b) = (self.pixels(v, o), self.pixels(v, m));
                a.iter()
                    .zip(&b)
                    .map(|(x, y)| u64::from(x.abs_diff(*y)))
                    .sum::<u64>()
            })
            .sum()
    }

    /// A view's sample mask as pixels of [`Self::per_pixel`]² samples: how many of each
    /// pixel's samples are covered (the coverage metric's covered fraction, in samples).
    fn pixels(&self, view: &View, mask: &[bool]) -> Vec<u32> {
        let k = self.per_pixel;
        if k <= 1 {
            return mask.iter().map(|&c| u32::from(c)).collect();
        }
        let (w, h) = (view.width.div_ceil(k), view.height.div_ceil(k));
        let mut count = vec![0u32; w * h];
        for (s, _) in mask.iter().enumerate().filter(|(_, c)| **c) {
            let (x, y) = (s % view.width, s / view.width);
            count[(y / k) * w + x / k] += 1;
        }
        count
    }

    fn mask(&self, view: &View, cards: &[usize], scale: f32) -> Vec<bool> {
        let mut m = vec![false; view.width * view.height];
        for &c in cards {
            self.raster(view, c, scale, &mut Mask(&mut m));
        }
        m
    }
}

impl Card {
    /// The side of a square of the card's area.
    fn side(&self) -> f32 {
        self.triangles
            .iter()
            .map(|[a, b, c]| 0.5 * (b.0 - a.0).cross(c.0 - a.0).length())
            .sum::<f32>()
            .sqrt()
    }
}

/// The ring of [`RING_VIEWS`] eye-level and [`ELEVATED_VIEWS`] elevated views around `bounds`,
/// sampled every `spacing` world units.
fn views(bounds: &Bounds, spacing: f32) -> Vec<View> {
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 {
                    bounds.min[0]
                } else {
                    bounds.max[0]
                },
                if i & 2 == 0 {
                    bounds.min[1]
                } else {
                    bounds.max[1]
                },
                if i & 4 == 0 {
                    bounds.min[2]
                } else {
                    bounds.max[2]
                },
            )
        })
        .collect();
    let ring = (0..RING_VIEWS).map(|k| (k as f32 / RING_VIEWS as f32, 0.0));
    let elevated =
        (0..ELEVATED_VIEWS).map(|k| ((k as f32 + 0.5) / ELEVATED_VIEWS as f32, ELEVATED_DEG));
    ring.chain(elevated)
        .map(|(turn, elevation)| {
            let (az, el) = (turn * std::f32::consts::TAU, elevation.to_radians());
            let forward = Vec3::new(az.sin() * el.cos(), -el.sin(), az.cos() * el.cos());
            let right = Vec3::Y.cross(forward).normalize_or(Vec3::X);
            let up = forward.cross(right).normalize_or(Vec3::Y);
            let projected: Vec<Vec2> = corners
                .iter()
                .map(|c| Vec2::new(c.dot(right), c.dot(up)) / spacing)
                .collect();
            let lo = projected
                .iter()
                .fold(Vec2::splat(f32::INFINITY), |a, p| a.min(*p));
            let hi = projected
                .iter()
                .fold(Vec2::splat(f32::NEG_INFINITY), |a, p| a.max(*p));
            let size = (hi - lo).ceil().max(Vec2::ONE);
            View {
                right,
                up,
                origin: lo.floor(),
                width: size.x as usize + 1,
                height: size.y as usize + 1,
            }
        })
        .collect()
}

/// Card of triangles `tris` of `foliage`.
fn card(tree: &Tree, foliage: &WoodMesh, tris: &[(usize, usize)]) -> Card {
    let triangles: Vec<[(Vec3, Vec2); 3]> = tris
        .iter()
        .map(|&(p, t)| {
            let i = &foliage.primitives[p].indices[3 * t..3 * t + 3];
            [0, 1, 2].map(|k| {
                let v = i[k] as usize;
                (
                    foliage.positions[v],
                    foliage.uvs.get(v).copied().unwrap_or(Vec2::ZERO),
                )
            })
        })
        .collect();
    let centre = card_centre(foliage, tris);
    let alpha = tris.first().and_then(|&(p, _)| {
        let m = tree.materials.get(foliage.primitives[p].material)?;
        let cutoff = match m.alpha_mode {
            AlphaMode::Opaque => return None,
            AlphaMode::Mask => m.alpha_cutoff,
            AlphaMode::Blend => 0.5,
        };
        // The factor scales the texture's alpha: the texel needs cutoff / factor.
        let factor = m.base_color[3];
        let wrap = m.base_color_wrap;
        if factor <= 0.0 {
            return Some((m.base_color_texture?, f32::INFINITY, wrap));
        }
        Some((m.base_color_texture?, cutoff / factor, wrap))
    });
    Card {
        triangles,
        centre,
        alpha,
    }
}

/// The distinct vertices (ascending) of card `tris` of `foliage`.
pub fn card_vertices(foliage: &WoodMesh, tris: &[(usize, usize)]) -> Vec<u32> {
    let mut verts: Vec<u32> = tris
        .iter()
        .flat_map(|&(p, t)| foliage.primitives[p].indices[3 * t..3 * t + 3].to_vec())
        .collect();
    verts.sort_unstable();
    verts.dedup();
    verts
}

/// The mean of the distinct vertices of card `tris` of `foliage`: what a card is scaled about.
pub fn card_centre(foliage: &WoodMesh, tris: &[(usize, usize)]) -> Vec3 {
    let verts = card_vertices(foliage, tris);
    verts
        .iter()
        .map(|&v| foliage.positions[v as usize])
        .sum::<Vec3>()
        / verts.len().max(1) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::{ImportOptions, Part, import};
    use rand::seq::SliceRandom;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn sample() -> (Tree, WoodMesh, Vec<Vec<(usize, usize)>>) {
        let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
        let foliage = WoodMesh::from_tree_part(&tree, Part::Foliage);
        let pieces = foliage.pieces();
        (tree, foliage, pieces)
    }

    #[test]
    fn row_spans_hold_every_sample_inside_the_triangle() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..500 {
            let mut p: [Vec2; 3] = std::array::from_fn(|_| {
                Vec2::new(rng.random_range(-5.0..45.0), rng.random_range(-5.0..45.0))
            });
            if (p[1] - p[0]).perp_dot(p[2] - p[0]) < 0.0 {
                p.swap(1, 2);
            }
            let edges = [(p[1], p[2]), (p[2], p[0]), (p[0], p[1])];
            for y in 0..40 {
                let sy = y as f32 + 0.5;
                let span = row_span(&edges, sy, 0.0, 40.0);
                for x in 0..40usize {
                    let s = Vec2::new(x as f32 + 0.5, sy);
                    let inside = edges.iter().all(|(a, b)| (*b - *a).perp_dot(s - *a) >= 0.0);
                    if inside {
                        let (x0, x1) = span.expect("a row with an inside sample has a span");
                        assert!(
                            (x0..x1).contains(&x),
                            "{p:?} row {y}: {x} outside {x0}..{x1}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_cover_records_what_each_card_rasterises_and_masks_their_union() {
        let (tree, foliage, pieces) = sample();
        let coverage = CardCoverage::new(
            &tree,
            &foliage,
            &pieces,
            &tree.bounds,
            tree.height() / 200.0,
        );
        let view = &coverage.views[1];
        let cover = coverage.cover(view);
        let mut union = vec![false; view.width * view.height];
        let mut count = vec![0u32; union.len()];
        for c in 0..coverage.cards.len() {
            let mut samples = Vec::new();
            coverage.raster(view, c, 1.0, &mut Every(|s: usize| samples.push(s as u32)));
            assert_eq!(cover.cards.of(c), samples.as_slice(), "card {c}");
            for &s in &samples {
                union[s as usize] = true;
                count[s as usize] += 1;
            }
        }
        assert_eq!(cover.count, count);
        assert!(union.iter().filter(|c| **c).count() > 1000);
        // The mask skips samples it holds: the same union.
        let all: Vec<usize> = (0..coverage.cards.len()).collect();
        assert_eq!(coverage.mask(view, &all, 1.0), union);
    }

    #[test]
    fn thinning_by_coverage_loses_less_than_a_random_choice() {
        let (tree, foliage, pieces) = sample();
        let pixel = tree.height() / 200.0;
        let coverage = CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, pixel);
        let n = pieces.len();
        let triangles: Vec<usize> = pieces.iter().map(Vec::len).collect();
        let total: usize = triangles.iter().sum();
        let tie: Vec<u32> = (0..n as u32).collect();
        assert!(coverage.thin(&triangles, total, &tie).iter().all(|k| *k));

        let keep = coverage.thin(&triangles, total / 2, &tie);
        let kept_triangles: usize = (0..n).filter(|&c| keep[c]).map(|c| triangles[c]).sum();
        assert!(
            kept_triangles <= total / 2,
            "{kept_triangles} > {}",
            total / 2
        );
        let kept = keep.iter().filter(|k| **k).count();
        let mut order: Vec<usize> = (0..n).collect();
        order.shuffle(&mut ChaCha8Rng::seed_from_u64(7));
        let mut random = vec![false; n];
        order[..kept].iter().for_each(|&c| random[c] = true);

        let original = coverage.masks(&vec![true; n], 1.0);
        // Thinning read the same coverage off its cover counts.
        assert_eq!(coverage.original.get(), Some(&original));
        assert_eq!(coverage.differing(&original, &vec![true; n], 1.0), 0);
        let greedy = coverage.differing(&original, &keep, 1.0);
        let random = coverage.differing(&original, &random, 1.0);
        let covered: u64 = original.iter().flatten().filter(|c| **c).count() as u64;
        assert!(covered > 0);
        assert!(
            2 * greedy < random,
            "greedy thinning lost {greedy} samples of {covered}, a random one {random}"
        );
    }

    /// A 512² leaf texture whose alpha is a fine grid of thin opaque lines: a quarter of its
    /// texels pass the test, none of them next to a passing neighbour's 2×2 block average.
    fn thin_lines() -> frond_scene::Texture {
        let side = 512u32;
        let rgba = (0..side * side)
            .flat_map(|i| {
                let (x, y) = (i % side, i / side);
                let a = if x % 2 == 0 && y % 2 == 0 { 255 } else { 0 };
                [40, 120, 30, a]
            })
            .collect();
        frond_scene::Texture {
            name: "lines".into(),
            width: side,
            height: side,
            rgba,
            image: None,
        }
    }

    const REPEAT: [Wrap; 2] = [Wrap::Repeat; 2];

    #[test]
    fn far_cards_read_the_renderers_coarse_coverage_preserving_levels() {
        let texture = thin_lines();
        let chain = frond_render::mip_chain(texture.width, texture.height, &texture.rgba);
        let map = AlphaMap::of(&texture);
        // 512² is one level above the 256² cap.
        assert_eq!(map.first, 1);
        assert_eq!(map.levels.len(), chain.len() - 1);
        // At each whole level, every texel centre reads the renderer's alpha of that level;
        // below the first kept level, the first; halfway, the mean of the two around.
        let alpha = |k: usize, x: u32, y: u32| {
            let (w, _, rgba) = &chain[k];
            f32::from(rgba[((y * w + x) * 4 + 3) as usize]) / 255.0
        };
        for (k, &(w, h, _)) in chain.iter().enumerate().skip(1) {
            for (x, y) in [(0, 0), (w / 3, h / 2), (w - 1, h - 1)] {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                assert_eq!(
                    map.at(uv, map.level(k as f32), REPEAT),
                    alpha(k, x, y),
                    "level {k} at {x},{y}"
                );
                if k == 1 {
                    assert_eq!(map.at(uv, map.level(0.0), REPEAT), alpha(1, x, y));
                }
            }
        }
        let uv = Vec2::splat(0.3);
        let (a, b) = (
            map.at(uv, map.level(3.0), REPEAT),
            map.at(uv, map.level(4.0), REPEAT),
        );
        assert!((map.at(uv, map.level(3.5), REPEAT) - 0.5 * (a + b)).abs() < 1e-6);

        // The level follows the texel step per metric sample: the whole 512² texture over a
        // triangle 8 samples wide is 64 texels a sample, and a metric sample is `grid` of them.
        let (tree, foliage, pieces) = sample();
        let coverage =
            CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, tree.height() / 60.0);
        let p = [Vec2::ZERO, Vec2::new(8.0, 0.0), Vec2::new(0.0, 8.0)];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let grid = coverage.render_spacing / coverage.spacing;
        let level = coverage.mip_level(&p, &uv, Vec2::splat(512.0));
        assert!((level - (64.0 * grid).log2()).abs() < 1e-4, "{level}");
    }

    #[test]
    fn fine_samples_are_counted_per_pixel_as_the_metric_counts_them() {
        let (tree, foliage, pieces) = sample();
        let coverage =
            CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, tree.height() / 15.0);
        // At 15 px the sample's leaves are far below a pixel: the grid is the metric's 4×4 per
        // pixel.
        let k = coverage.per_pixel;
        assert_eq!(k, 4);
        let view = &coverage.views[0];
        let mut mask = vec![false; view.width * view.height];
        // Half of the first pixel's samples covered, one fewer of the second's: each pixel
        // counts its own.
        let half = (k * k).div_ceil(2);
        for i in 0..half {
            mask[(i / k) * view.width + i % k] = true;
        }
        for i in 0..half - 1 {
            mask[(i / k) * view.width + k + i % k] = true;
        }
        let pixels = coverage.pixels(view, &mask);
        assert_eq!(
            pixels.len(),
            view.width.div_ceil(k) * view.height.div_ceil(k)
        );
        assert_eq!(pixels[..2], [half as u32, half as u32 - 1]);
        assert_eq!(pixels.iter().sum::<u32>() as usize, 2 * half - 1);
    }

    #[test]
    fn all_cards_kept_need_no_scale() {
        let (tree, foliage, pieces) = sample();
        let coverage =
            CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, tree.height() / 60.0);
        let keep = vec![true; pieces.len()];
        assert_eq!(coverage.coverage_keeping_scale(&keep, 1.5), 1.0);
        // Growing every card covers samples the input leaves open.
        let original = coverage.masks(&keep, 1.0);
        assert!(coverage.differing(&original, &keep, 1.5) > 0);
    }

    #[test]
    fn thinned_cards_grow_until_they_cover_what_all_covered() {
        let (tree, foliage, pieces) = sample();
        let coverage =
            CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, tree.height() / 60.0);
        let covers = |keep: &[bool], scale: f32| -> usize {
            coverage.masks(keep, scale).iter().map(|m| covered(m)).sum()
        };
        let all = covers(&vec![true; pieces.len()], 1.0);
        // Every other card kept: the crown thins at scale 1.
        let keep: Vec<bool> = (0..pieces.len()).map(|c| c % 2 == 0).collect();
        assert!(covers(&keep, 1.0) < all);
        // Room to double every side: more than keeping the leaf area (√2) takes, where the
        // kept cards overlap.
        let most = 2.0;
        let scale = coverage.coverage_keeping_scale(&keep, most);
        assert!(scale > 1.0 && scale <= most, "{scale}");
        // It covers what all the cards covered, and is the smallest that does (to the
        // bisection's step).
        assert!(covers(&keep, scale) >= all);
        let step = (most - 1.0) / (1 << COVERAGE_BISECTIONS) as f32;
        assert!(covers(&keep, scale - step) < all, "{scale}");
        // Held to the overdraw budget: no more than `most`.
        let tight = 1.0 + 0.25 * (scale - 1.0);
        assert_eq!(coverage.coverage_keeping_scale(&keep, tight), tight);
    }
}
