//! Which leaf cards a LOD can spare, judged by what they cover on screen (issue 17 item 6, the
//! card LOD). Every card is rasterised, alpha-tested with its own texture, into a ring of
//! orthographic views at the LOD's pixel size; a card whose pixels other cards also cover adds
//! nothing to the tree's silhouette, so thinning drops, one at a time, the card that covers the
//! fewest pixels no other card covers ([`CardCoverage::thin`]). The survivors are then grown by
//! the one scale that makes their coverage closest to the input's ([`CardCoverage::best_scale`]):
//! the same measure as the coverage metric (pixels covered by exactly one of the two),
//! over these views.
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
use frond_scene::{AlphaMode, Bounds, Tree};

/// Views of the ring at eye level (the coverage metric's viewers, spec §8.2) …
const RING_VIEWS: usize = 8;
/// … and from above at [`ELEVATED_DEG`], between them: trees are also seen from hills and
/// cameras above the ground.
const ELEVATED_VIEWS: usize = 4;
const ELEVATED_DEG: f32 = 40.0;
/// Samples per pixel side: cards smaller than a pixel still cover part of one, which sampling
/// pixel centres alone would miss (the coverage metric renders 4× supersampled for the same
/// reason).
const SUPERSAMPLE: f32 = 4.0;
/// At most this many samples across the tree's height per view: bounds memory and time at
/// near sizes, where leaves span several pixels and a coarser grid still resolves them.
const MAX_SAMPLES_ACROSS: f32 = 512.0;
/// Samples across a typical (median) card are enough at this many: cards much larger than a
/// pixel are sampled coarser than the screen, which decides the same cards at a fraction of
/// the work (the sample tree's leaves span 40 pixels at 600 px).
const CARD_SAMPLES_ACROSS: f32 = 8.0;

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
    /// Texture index into the tree's textures and the alpha a sample needs; `None`: opaque.
    alpha: Option<(usize, f32)>,
}

/// Largest side of the alpha maps the rasteriser samples: a point-sampled copy of each leaf
/// texture's alpha this small stays in cache (the full 1024² maps made thinning oak_dense
/// three times slower, every lookup a cache miss), and a card is a few samples wide.
const ALPHA_MAP_SIDE: u32 = 256;

/// A texture's alpha, point-sampled down to at most [`ALPHA_MAP_SIDE`] a side.
struct AlphaMap {
    width: usize,
    height: usize,
    alpha: Vec<u8>,
}

impl AlphaMap {
    fn of(t: &frond_scene::Texture) -> AlphaMap {
        let (w, h) = (t.width.min(ALPHA_MAP_SIDE), t.height.min(ALPHA_MAP_SIDE));
        let alpha = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| {
                let sx = (x as u64 * u64::from(t.width) / u64::from(w.max(1))) as usize;
                let sy = (y as u64 * u64::from(t.height) / u64::from(h.max(1))) as usize;
                t.rgba
                    .get(4 * (sy * t.width as usize + sx) + 3)
                    .copied()
                    .unwrap_or(255)
            })
            .collect();
        AlphaMap {
            width: w as usize,
            height: h as usize,
            alpha,
        }
    }
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
            .max(typical / CARD_SAMPLES_ACROSS);
        let views = views(bounds, spacing);
        let mut alpha_maps: Vec<Option<AlphaMap>> =
            (0..tree.textures.len()).map(|_| None).collect();
        for c in &cards {
            if let Some((t, _)) = c.alpha
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
            cards,
        }
    }

    /// Calls `f` once with every sample of `view` that `card`, scaled by `scale` about its
    /// centre, covers. A sample on an edge belongs to the triangle on the edge's left or top
    /// side only (the usual fill rule), so the two triangles of a quad never both claim the
    /// samples on their shared diagonal.
    fn raster(&self, view: &View, card: usize, scale: f32, f: &mut impl FnMut(usize)) {
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
                for x in lo.x as usize..hi.x as usize {
                    let s = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let w = [0, 1, 2].map(|k| (edges[k].1 - edges[k].0).perp_dot(s - edges[k].0));
                    if (0..3).any(|k| w[k] < 0.0 || (w[k] == 0.0 && !owns_zero[k])) {
                        continue;
                    }
                    if let Some((texture, cutoff)) = c.alpha {
                        let t = (uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2]) / area;
                        if self.alpha(texture, t) < cutoff {
                            continue;
                        }
                    }
                    f(y * view.width + x);
                }
            }
        }
    }

    /// The texture's alpha (0..1) nearest `uv` in its alpha map, repeating outside [0, 1].
    fn alpha(&self, texture: usize, uv: Vec2) -> f32 {
        let Some(Some(t)) = self.alpha_maps.get(texture) else {
            return 1.0;
        };
        if t.width == 0 || t.height == 0 {
            return 1.0;
        }
        // `v − ⌊v⌋` repeats like `rem_euclid(1.0)`, without its slow `fmod`.
        let x = (((uv.x - uv.x.floor()) * t.width as f32) as usize).min(t.width - 1);
        let y = (((uv.y - uv.y.floor()) * t.height as f32) as usize).min(t.height - 1);
        f32::from(t.alpha[y * t.width + x]) / 255.0
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
        // Per view and sample: how many cards cover it, and the XOR of their indices (the one
        // card, when one does).
        let mut buffers: Vec<(Vec<u32>, Vec<u32>)> = self
            .views
            .par_iter()
            .map(|v| {
                let mut count = vec![0u32; v.width * v.height];
                let mut xor = vec![0u32; v.width * v.height];
                for c in 0..n {
                    self.raster(v, c, 1.0, &mut |s| {
                        count[s] += 1;
                        xor[s] ^= c as u32;
                    });
                }
                (count, xor)
            })
            .collect();
        let _ = self.original.set(
            buffers
                .iter()
                .map(|(count, _)| count.iter().map(|&k| k > 0).collect())
                .collect(),
        );
        let mut unique = vec![0u64; n];
        for (count, xor) in &buffers {
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
            for (v, (count, xor)) in self.views.iter().zip(buffers.iter_mut()) {
                self.raster(v, c, 1.0, &mut |s| {
                    count[s] -= 1;
                    xor[s] ^= c as u32;
                    if count[s] == 1 {
                        unique[xor[s] as usize] += 1;
                    }
                });
            }
        }
        keep
    }

    /// Of `candidates` scales (ascending), the one whose kept cards, each scaled about its
    /// centre, cover samples closest to all cards' coverage ([`CardCoverage::differing`]),
    /// searched upwards until the count rises; ties go to the earlier scale.
    pub fn best_scale(&self, keep: &[bool], candidates: &[f32]) -> f32 {
        let original = self
            .original
            .get_or_init(|| self.masks(&vec![true; self.cards.len()], 1.0));
        let mut best = (u64::MAX, 1.0);
        for &s in candidates {
            let differing = self.differing(original, keep, s);
            if differing >= best.0 {
                // Growing the cards first fills the holes thinning left, then covers what the
                // input left open: the count falls, then rises, so the first rise ends it.
                break;
            }
            best = (differing, s);
        }
        best.1
    }

    /// Every view's coverage by the cards `keep` marks, scaled by `scale`.
    pub fn masks(&self, keep: &[bool], scale: f32) -> Vec<Vec<bool>> {
        let cards: Vec<usize> = (0..self.cards.len()).filter(|&c| keep[c]).collect();
        self.views
            .par_iter()
            .map(|v| self.mask(v, &cards, scale))
            .collect()
    }

    /// Samples, over all views, covered by exactly one of `original` ([`CardCoverage::masks`])
    /// and the cards `keep` marks scaled by `scale`: the coverage metric's numerator (spec
    /// animated-billboard-clouds §5.4) on these views.
    pub fn differing(&self, original: &[Vec<bool>], keep: &[bool], scale: f32) -> u64 {
        self.masks(keep, scale)
            .iter()
            .zip(original)
            .map(|(m, o)| o.iter().zip(m).filter(|(a, b)| a != b).count() as u64)
            .sum()
    }

    fn mask(&self, view: &View, cards: &[usize], scale: f32) -> Vec<bool> {
        let mut m = vec![false; view.width * view.height];
        for &c in cards {
            self.raster(view, c, scale, &mut |s| m[s] = true);
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
        if factor <= 0.0 {
            return Some((m.base_color_texture?, f32::INFINITY));
        }
        Some((m.base_color_texture?, cutoff / factor))
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
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    use rand_chacha::ChaCha8Rng;

    fn sample() -> (Tree, WoodMesh, Vec<Vec<(usize, usize)>>) {
        let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
        let foliage = WoodMesh::from_tree_part(&tree, Part::Foliage);
        let pieces = foliage.pieces();
        (tree, foliage, pieces)
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

    #[test]
    fn all_cards_kept_need_no_scale() {
        let (tree, foliage, pieces) = sample();
        let coverage =
            CardCoverage::new(&tree, &foliage, &pieces, &tree.bounds, tree.height() / 60.0);
        let keep = vec![true; pieces.len()];
        assert_eq!(coverage.best_scale(&keep, &[1.0, 1.2, 1.5]), 1.0);
        // Growing every card covers samples the input leaves open.
        let original = coverage.masks(&keep, 1.0);
        assert!(coverage.differing(&original, &keep, 1.5) > 0);
    }
}
