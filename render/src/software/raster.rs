//! The span rasteriser: a band of the supersampled image drawn triangle by triangle, each
//! triangle's sample rows walked as spans (narrowed by the octagon where its alpha test can
//! pass), the spans' samples tested eight at once or one by one, and the band resolved to
//! pixels.

use glam::Vec3;

use super::alpha::AlphaCutoff;
use super::bands::Bands;
use super::setup::{Setup, centroid_lod};
use super::shading::{Shading, Surface};
use super::spans::RowSpan;
use super::textures::SoftwareTextures;
use crate::pipeline::LIGHT_DIRECTION;
use crate::sample_lanes::{self, LaneFilter, LaneLevel, LaneTest, TriangleLanes};
use crate::scene::{DrawAlpha, DrawScene};
use crate::srgb::SRGB_LINEAR;
use crate::uv_hull::{HullLevels, TriangleHull, narrowed};

/// The shortcuts a coverage render takes, each giving the same image (tests compare them):
/// see [`Raster::lanes`], [`Raster::hulls`] and [`Raster::covered_rows`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Shortcuts {
    /// Test eight samples at once where the machine can ([`Raster::lanes`]).
    pub(super) lanes: bool,
    /// Walk only where the alpha test can pass ([`Raster::hulls`]).
    pub(super) hulls: bool,
    /// Skip rows covered already ([`Raster::covered_rows`]).
    pub(super) covered_rows: bool,
}

impl Shortcuts {
    /// Every shortcut: what the renders take.
    pub(super) const ALL: Shortcuts = Shortcuts {
        lanes: true,
        hulls: true,
        covered_rows: true,
    };
}

/// One band of the image, resolved: its pixels' coverage and colour, and its covered samples.
pub(super) struct Band {
    /// Per pixel of the band, top row first: how many of its samples are covered.
    pub(super) samples: Vec<u16>,
    /// Per pixel, the coverage blended surfaces add to its samples that nothing covers
    /// (scenes with a blended material; empty otherwise): `Σ 1 − Π(1 − αᵢ)` over them.
    pub(super) blended: Vec<f32>,
    /// Per pixel, the mean colour of its covered samples (colour renders; empty otherwise).
    pub(super) colour: Vec<[f32; 3]>,
    /// The band's covered samples.
    pub(super) covered_samples: u64,
}

/// What every band of one render shares.
pub(super) struct Raster<'a> {
    /// The scene drawn.
    scene: &'a DrawScene,
    /// Its textures, prepared.
    textures: &'a SoftwareTextures,
    /// Per material, its alpha test (MASK materials).
    cutoffs: Vec<Option<AlphaCutoff>>,
    /// Per material, whether it is blended ([`DrawAlpha::Blend`]): its samples are drawn
    /// by [`Raster::blend_triangle`].
    blended: Vec<bool>,
    /// Whether any material is blended: the bands keep each sample's transmittance.
    any_blended: bool,
    /// Coverage renders test eight samples at once ([`sample_lanes`]) where the machine can.
    lanes: bool,
    /// Per material, the octagons of its texture's levels where its alpha test can pass
    /// (coverage renders of alpha-tested textured materials): a triangle's rows are walked
    /// only where its texture coordinates lie within its levels' octagon.
    pub(super) hulls: Vec<Option<HullLevels<'a>>>,
    /// Coverage renders skip a triangle's row where the samples within its bounds are all
    /// covered, before finding the row's span (most rows of the leaf cards inside a crown).
    covered_rows: bool,
    /// The render's triangles set up.
    triangles: &'a [Setup],
    /// Per triangle, its shading (colour renders; empty otherwise).
    shading: &'a [Shading],
    /// Samples per row.
    width: usize,
    /// Samples per pixel side.
    ss: usize,
}

impl<'a> Raster<'a> {
    /// The raster of `bands` (set up from `scene` for a target `width` samples wide, `ss` a
    /// pixel side), with the `shortcuts` asked for: `lanes` to test eight samples at once where the machine
    /// can, `hulls` to walk only the parts of triangles where the alpha test can pass,
    /// `covered_rows` to skip rows covered already.
    pub(super) fn new(
        scene: &'a DrawScene,
        textures: &'a SoftwareTextures,
        bands: &'a Bands,
        width: usize,
        ss: usize,
        Shortcuts {
            lanes,
            hulls,
            covered_rows,
        }: Shortcuts,
    ) -> Raster<'a> {
        let cutoffs = AlphaCutoff::of_materials(scene, DrawAlpha::mask_cutoff);
        let blended: Vec<bool> = (scene.materials.iter())
            .map(|m| m.alpha == DrawAlpha::Blend)
            .collect();
        // The octagons are fitted to alpha-only levels: coverage renders'.
        let hulls = if hulls && !textures.colour {
            HullLevels::of_materials(scene, textures, &cutoffs)
        } else {
            scene.materials.iter().map(|_| None).collect()
        };
        Raster {
            scene,
            textures,
            cutoffs,
            any_blended: blended.contains(&true),
            blended,
            hulls,
            covered_rows: covered_rows && !textures.colour,
            lanes: lanes && sample_lanes::available(),
            triangles: &bands.triangles,
            shading: &bands.shading,
            width,
            ss,
        }
    }

    /// Sample rows `y0..y1` (whole pixel rows) drawn with the triangles `bin`, resolved to
    /// pixels: coverage, and colour when the textures were prepared with it.
    pub(super) fn band(&self, y0: usize, y1: usize, bin: &[u32]) -> Band {
        #[cfg(target_arch = "x86_64")]
        if self.lanes {
            // SAFETY: `self.lanes` holds only where `sample_lanes::available` (AVX2).
            return unsafe { self.band_avx2(y0, y1, bin) };
        }
        self.band_body(y0, y1, bin)
    }

    /// [`Raster::band`] compiled for AVX2, so that the eight-sample test inlines into it. The
    /// compiler fuses no multiply with an add (that needs FMA, which this does not enable,
    /// and Rust never contracts): every operation rounds as in the scalar build.
    ///
    /// # Safety
    /// The machine must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn band_avx2(&self, y0: usize, y1: usize, bin: &[u32]) -> Band {
        self.band_body(y0, y1, bin)
    }

    /// [`Raster::band`]'s work, for each instruction set it is compiled for: the band's
    /// buffers made, its triangles drawn in draw order, and its samples resolved to pixels.
    #[inline(always)]
    fn band_body(&self, y0: usize, y1: usize, bin: &[u32]) -> Band {
        let mut band = BandBuffers::new(self, y0, y1);
        for &ti in bin {
            self.draw_triangle(&mut band, ti);
        }
        let (samples, blended, colour) = self.resolve(y1 - y0, &band);
        Band {
            samples,
            blended,
            colour,
            covered_samples: band.covered.iter().map(|w| u64::from(w.count_ones())).sum(),
        }
    }

    /// Triangle `ti` drawn into `band`: its rows that are not covered already walked as spans
    /// (narrowed by its octagon), each span's samples tested eight at a time where the
    /// triangle has lanes, one by one otherwise.
    #[inline(always)]
    fn draw_triangle(&self, band: &mut BandBuffers, ti: u32) {
        let t = &self.triangles[ti as usize];
        if self.any_blended && self.blended[t.material as usize] {
            self.blend_triangle(band, ti);
            return;
        }
        // A row whose bounds are covered already is skipped before its span is found, and a
        // triangle with no other row is not drawn (nor its mip level found).
        let bounds_words = self.bounds_words(t);
        let rows = t.rows(band.y0, band.y1);
        let Some(first_row) = (rows.clone()).find(|&sy| !band.row_covered(bounds_words, sy)) else {
            return;
        };
        let colour = self.textures.colour;
        let t = &if colour { *t } else { self.with_lod(t) };
        let surface = self.surface(ti, t);
        let lanes = if self.lanes && !colour {
            self.triangle_lanes(t)
        } else {
            None
        };
        let hull = match self.triangle_hull(*t) {
            TriangleHull::Empty => return,
            TriangleHull::Rows(rows) => Some(rows),
            TriangleHull::Unbounded => None,
        };
        let walk = t.row_walk();
        for sy in first_row..rows.end {
            if band.row_covered(bounds_words, sy) {
                continue;
            }
            let Some(span) = t.row_span(&walk, sy) else {
                continue;
            };
            let Some((first, last)) = narrowed(hull.as_ref(), sy, span.first, span.last) else {
                continue;
            };
            if let Some(lanes) = &lanes {
                self.lanes_span(band, &surface, lanes, &span, [first, last]);
            } else {
                self.scalar_span(band, t, &surface, &span, [first, last]);
            }
        }
    }

    /// Blended triangle `ti` drawn into `band`: each sample inside it that nothing opaque or
    /// alpha-tested covers keeps `1 − α` of what still showed through it (`trans`), α the
    /// filtered alpha of its texture (box-filtered levels) times the base colour's; in colour
    /// renders its colour adds to the sample's weighted by what it shows, `α · trans` before
    /// it. Coverage does not depend on the order (`1 − Π(1 − αᵢ)`); colour does, and is
    /// mixed in draw order. Not inlined: the alpha-tested loop does not carry it.
    #[inline(never)]
    fn blend_triangle(&self, band: &mut BandBuffers, ti: u32) {
        let t = &self.triangles[ti as usize];
        let colour = self.textures.colour;
        let t = &if colour { *t } else { self.with_lod(t) };
        let surface = self.surface(ti, t);
        let (stride, scale) = (if colour { 4 } else { 1 }, surface.material.base_color[3]);
        let walk = t.row_walk();
        for sy in t.rows(band.y0, band.y1) {
            let Some(span) = t.row_span(&walk, sy) else {
                continue;
            };
            let row = sy - band.y0;
            for x in span.first..=span.last {
                if band.covered[row * band.words + x / 64] >> (x % 64) & 1 == 1 {
                    continue;
                }
                let b = span.weights_at(x);
                if b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0 {
                    continue;
                }
                let (uv, q) = t.uv(b);
                let wrap = surface.material.wrap;
                let texel =
                    (surface.texture).map_or(1.0, |l| l.alpha(uv, surface.lod, wrap, stride));
                // A NaN alpha covers nothing.
                let alpha = match texel * scale {
                    a if a > 0.0 => a.min(1.0),
                    _ => continue,
                };
                let s = row * self.width + x;
                if colour {
                    let lighting = self.textures.lighting;
                    let c = surface.colour(b, q, uv, lighting, band.light, band.linear);
                    band.blend_rgb[s] += c * (alpha * band.trans[s]);
                }
                band.trans[s] *= 1.0 - alpha;
            }
        }
    }

    /// The words of a sample row that triangle `t`'s bounds reach, each with the mask of the
    /// bounds' samples in it, when they are one or two words (the same one twice when one)
    /// and rows covered already are skipped ([`Raster::covered_rows`]).
    #[inline(always)]
    fn bounds_words(&self, t: &Setup) -> Option<[(usize, u64); 2]> {
        let (bx0, bx1) = (t.min[0] as usize, t.max[0] as usize);
        (self.covered_rows && bx1 / 64 - bx0 / 64 <= 1).then(|| {
            let (w0, w1) = (bx0 / 64, bx1 / 64);
            let (m0, m1) = (u64::MAX << (bx0 % 64), u64::MAX >> (63 - bx1 % 64));
            if w0 == w1 {
                [(w0, m0 & m1), (w1, m0 & m1)]
            } else {
                [(w0, m0), (w1, m1)]
            }
        })
    }

    /// What the samples of triangle `ti` (`t`, with its mip levels) read to be alpha-tested
    /// and coloured: its material and alpha test, its texture's levels and their alpha
    /// bounds (coverage renders), its normal map and shading attributes (colour renders).
    #[inline(always)]
    fn surface(&self, ti: u32, t: &Setup) -> Surface<'_> {
        let colour = self.textures.colour;
        // Colour renders' triangles have their shading; coverage renders read none.
        let shading = self.shading.get(ti as usize);
        let material = &self.scene.materials[t.material as usize];
        Surface {
            material,
            cutoff: self.cutoffs[t.material as usize].as_ref(),
            texture: material.texture.map(|i| &self.textures.textures[i]),
            bounds: material
                .texture
                // A colour render's levels are RGBA: the alpha-only tables are not theirs.
                .filter(|_| !colour)
                .and_then(|i| self.textures.alpha_bounds.get(i))
                .map(Vec::as_slice),
            normal_map: material
                .normal_texture
                .filter(|_| shading.is_some_and(|s| s.tq.is_some()))
                .map(|i| &self.textures.normal_maps[i]),
            shading,
            lod: t.lod,
            lit: t.lit,
            back: t.back,
        }
    }

    /// The samples `first..=last` of `span` tested eight at a time from the first (coverage
    /// renders, where the machine has AVX2): their coverage bits are read across the word
    /// boundary where they straddle one, and the covered ones are not tested.
    #[inline(always)]
    fn lanes_span(
        &self,
        band: &mut BandBuffers,
        surface: &Surface<'_>,
        lanes: &TriangleLanes<'_>,
        span: &RowSpan,
        [first, last]: [usize; 2],
    ) {
        let (row, words) = (span.y - band.y0, band.words);
        let row_word = row * words;
        let mut x = first;
        while x <= last {
            let (word, shift) = (x / 64, x % 64);
            let mut bits = band.covered[row_word + word] >> shift;
            if shift > 56 && word + 1 < words {
                bits |= band.covered[row_word + word + 1] << (64 - shift);
            }
            let mut todo = !bits as u32 & 0xff;
            if last < x + 7 {
                todo &= 0xff >> (x + 7 - last);
            }
            if todo != 0 {
                let k0 = x as i32 - span.x0 as i32;
                // SAFETY: `self.lanes` holds only where `sample_lanes::available`, and a table
                // test's table is an `AlphaBounds` one (padded).
                let r = unsafe { lanes.test(k0, span.start, span.step) };
                let mut hits = r.passing(todo, |uv| surface.bounded_alpha_test(uv));
                while hits != 0 {
                    let i = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    self.cover(&mut band.covered, row, x + i);
                }
            }
            x += 8;
        }
    }

    /// The samples `first..=last` of `span` tested one by one, a word of coverage bits at a
    /// time: covered samples are skipped unless colour is drawn (then depth decides).
    #[inline(always)]
    fn scalar_span(
        &self,
        band: &mut BandBuffers,
        t: &Setup,
        surface: &Surface<'_>,
        span: &RowSpan,
        [first, end]: [usize; 2],
    ) {
        let row_word = (span.y - band.y0) * band.words;
        let mut sx = first;
        while sx <= end {
            let word = sx / 64;
            let run_end = end.min(word * 64 + 63);
            let bits = run_end - sx + 1;
            let run = if bits == 64 {
                u64::MAX
            } else {
                ((1u64 << bits) - 1) << (sx % 64)
            };
            let mut todo = if band.colour {
                run
            } else {
                run & !band.covered[row_word + word]
            };
            while todo != 0 {
                let bit = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                self.draw_sample(band, t, surface, span, word * 64 + bit);
            }
            sx = run_end + 1;
        }
    }

    /// Sample `x` of `span`'s row drawn when it is inside the triangle, nearer than what was
    /// drawn there (colour renders) and passes the alpha test: covered, and in colour renders
    /// its depth and colour written.
    #[inline(always)]
    fn draw_sample(
        &self,
        band: &mut BandBuffers,
        t: &Setup,
        surface: &Surface<'_>,
        span: &RowSpan,
        x: usize,
    ) {
        let b = span.weights_at(x);
        if b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0 {
            return;
        }
        let row = span.y - band.y0;
        let s = row * self.width + x;
        let z = b[0] * t.z[0] + b[1] * t.z[1] + b[2] * t.z[2];
        // Depth test `Less` (z is finite: the triangle was clipped to 0..1).
        if band.colour && z >= band.depth[s] {
            return;
        }
        let (uv, q) = t.uv(b);
        let stride = if band.colour { 4 } else { 1 };
        if let Some(cutoff) = surface.cutoff
            && !surface.passes_alpha(cutoff, uv, stride)
        {
            return;
        }
        self.cover(&mut band.covered, row, x);
        if band.colour {
            band.depth[s] = z;
            let lighting = self.textures.lighting;
            band.rgb[s] = surface.colour(b, q, uv, lighting, band.light, band.linear);
        }
    }

    /// Marks sample `x` of the band's sample row `row` covered (`covered`: the band's bits, 64
    /// to a word).
    #[inline(always)]
    fn cover(&self, covered: &mut [u64], row: usize, x: usize) {
        let words = self.width.div_ceil(64);
        covered[row * words + x / 64] |= 1 << (x % 64);
    }

    /// What the octagon of coverage render triangle `t`'s levels (`t` with its mip levels,
    /// [`Raster::with_lod`]) does to it: a trilinear test passes only where one of its two
    /// levels' can. `t` is a copy: the octagon's code (in another file) sees its address, not
    /// the address of the triangle the rows are walked with, so the compiler can keep that
    /// one's corners in registers through the rows (calls in the walk it cannot see into
    /// could otherwise change them).
    pub(super) fn triangle_hull(&self, t: Setup) -> TriangleHull {
        let Some(levels) = &self.hulls[t.material as usize] else {
            return TriangleHull::Unbounded;
        };
        let (a, b) = (t.lod.a as usize, t.lod.b as usize);
        let octagon = if t.lod.f > 0.0 {
            levels.level(a).union(levels.level(b))
        } else {
            levels.level(a)
        };
        octagon.rows(&t)
    }

    /// Coverage render triangle `t` with its texture's mip levels (set up without them:
    /// [`setup`](super::setup)'s `setup_triangle`).
    #[inline(always)]
    pub(super) fn with_lod(&self, t: &Setup) -> Setup {
        let mut with = *t;
        let material = &self.scene.materials[t.material as usize];
        if let Some(levels) = material.texture.map(|i| &self.textures.textures[i]) {
            // The level from `t` (the same corners): the copy's address stays here, which
            // lets the compiler keep its fields in registers through the triangle's rows.
            with.lod = levels.pair(centroid_lod(t, levels));
        }
        with
    }

    /// A coverage render's eight-sample test of triangle `t`, when its material's alpha test
    /// is one the lanes decide as the scalar path does: none, or a bounds table (the one
    /// [`Levels::alpha_test`](super::sampling::Levels::alpha_test) reads first for the triangle's levels) and the filter behind it.
    /// `None` sends the triangle to the scalar loop.
    pub(super) fn triangle_lanes(&self, t: &Setup) -> Option<TriangleLanes<'_>> {
        let material = &self.scene.materials[t.material as usize];
        let test = match &self.cutoffs[t.material as usize] {
            None => LaneTest::Opaque,
            Some(cutoff) => {
                let texture = material.texture?;
                let levels = &self.textures.textures[texture];
                let bounds = self.textures.alpha_bounds.get(texture)?;
                let (pass_from, fail_below) = cutoff.thresholds?;
                let (a, b) = (t.lod.a as usize, t.lod.b as usize);
                let trilinear = t.lod.f > 0.0;
                let table = &bounds[a];
                let entries = if !trilinear {
                    &table.footprint
                } else if b == a + 1 && !table.trilinear.is_empty() {
                    &table.trilinear
                } else {
                    return None;
                };
                let level = |k: usize| {
                    let (width, height, texels) = &levels.0[k];
                    LaneLevel {
                        texels,
                        width: *width,
                        height: *height,
                        wrap: material.wrap,
                    }
                };
                LaneTest::Table {
                    table: entries,
                    pass_from,
                    fail_below,
                    filter: LaneFilter {
                        a: level(a),
                        b: trilinear.then(|| level(b)),
                        f: t.lod.f,
                        scale: cutoff.scale,
                        cutoff: cutoff.cutoff,
                    },
                }
            }
        };
        Some(TriangleLanes {
            q: t.q,
            uq: t.uq,
            affine: None,
            test,
        })
    }

    /// Pixels of a band of `rows` sample rows: how many of their samples are covered, the
    /// coverage blended surfaces add (scenes with one), and the mean colour of what covers
    /// them (each sample weighted by its coverage).
    fn resolve(&self, rows: usize, band: &BandBuffers) -> (Vec<u16>, Vec<f32>, Vec<[f32; 3]>) {
        let (covered, rgb) = (&band.covered, &band.rgb);
        let ss = self.ss;
        let words = self.width.div_ceil(64);
        let (w, h) = (self.width / ss, rows / ss);
        let mut samples = vec![0u16; w * h];
        for y in 0..rows {
            let row = &covered[y * words..(y + 1) * words];
            let counts = &mut samples[(y / ss) * w..(y / ss + 1) * w];
            for (px, count) in counts.iter_mut().enumerate() {
                // At most 255² samples a pixel ([`checked_target`](super::bands::checked_target)).
                *count += bits_set(row, px * ss, ss) as u16;
            }
        }
        let is_covered = |x: usize, y: usize| covered[y * words + x / 64] >> (x % 64) & 1 == 1;
        let blended = if band.trans.is_empty() {
            Vec::new()
        } else {
            let mut blended = vec![0f32; w * h];
            for (p, value) in blended.iter_mut().enumerate() {
                let (px, py) = (p % w, p / w);
                for y in py * ss..(py + 1) * ss {
                    for x in (px * ss..(px + 1) * ss).filter(|&x| !is_covered(x, y)) {
                        *value += 1.0 - band.trans[y * self.width + x];
                    }
                }
            }
            blended
        };
        if rgb.is_empty() {
            return (samples, blended, Vec::new());
        }
        let mut colour = Vec::with_capacity(w * h);
        for py in 0..h {
            for px in 0..w {
                let mut sum = Vec3::ZERO;
                for y in py * ss..(py + 1) * ss {
                    for x in px * ss..(px + 1) * ss {
                        if is_covered(x, y) {
                            sum += rgb[y * self.width + x];
                        } else if !band.blend_rgb.is_empty() {
                            sum += band.blend_rgb[y * self.width + x];
                        }
                    }
                }
                let p = py * w + px;
                let weight = f32::from(samples[p]) + blended.get(p).copied().unwrap_or(0.0);
                let mean = if weight > 0.0 {
                    sum / weight
                } else {
                    Vec3::ZERO
                };
                colour.push(mean.to_array());
            }
        }
        (samples, blended, colour)
    }
}

/// The set bits of `row` (64 to a word, lowest first) among the `len` from bit `start`.
#[inline]
fn bits_set(row: &[u64], start: usize, len: usize) -> u32 {
    let (mut x, end, mut n) = (start, start + len, 0);
    while x < end {
        let (word, shift) = (x / 64, x % 64);
        let take = (64 - shift).min(end - x);
        let mask = if take == 64 {
            u64::MAX
        } else {
            ((1u64 << take) - 1) << shift
        };
        n += (row[word] & mask).count_ones();
        x += take;
    }
    n
}

/// One band being drawn: its sample buffers, and what every sample's shading reads.
struct BandBuffers {
    /// The band's first sample row.
    y0: usize,
    /// The sample row after its last.
    y1: usize,
    /// Words a sample row of `covered`.
    words: usize,
    /// Coverage as one bit a sample, 64 to a word: runs of covered samples are skipped a word
    /// at a time (the crown's inside is covered many times over).
    covered: Vec<u64>,
    /// Colour is drawn: a sample's depth decides, and it is shaded.
    colour: bool,
    /// Per sample, the depth drawn there (colour renders; empty otherwise).
    depth: Vec<f32>,
    /// Per sample, the colour drawn there (colour renders; empty otherwise).
    rgb: Vec<Vec3>,
    /// Per sample, the fraction of it that blended surfaces leave showing, `Π(1 − αᵢ)`
    /// (scenes with a blended material; empty otherwise).
    trans: Vec<f32>,
    /// Per sample, the blended surfaces' colour, each weighted by what it shows (colour
    /// renders of scenes with a blended material; empty otherwise).
    blend_rgb: Vec<Vec3>,
    /// sRGB to linear light, a byte's value.
    linear: &'static [f32; 256],
    /// The light's direction ([`LIGHT_DIRECTION`]).
    light: Vec3,
}

impl BandBuffers {
    /// The empty buffers of the sample rows `y0..y1` of `raster`'s image.
    #[inline(always)]
    fn new(raster: &Raster<'_>, y0: usize, y1: usize) -> BandBuffers {
        let colour = raster.textures.colour;
        let rows = y1 - y0;
        let n = rows * raster.width;
        let words = raster.width.div_ceil(64);
        BandBuffers {
            y0,
            y1,
            words,
            covered: vec![0u64; rows * words],
            colour,
            depth: if colour {
                vec![f32::INFINITY; n]
            } else {
                Vec::new()
            },
            rgb: if colour {
                vec![Vec3::ZERO; n]
            } else {
                Vec::new()
            },
            trans: if raster.any_blended {
                vec![1.0; n]
            } else {
                Vec::new()
            },
            blend_rgb: if colour && raster.any_blended {
                vec![Vec3::ZERO; n]
            } else {
                Vec::new()
            },
            linear: &SRGB_LINEAR,
            light: Vec3::from(LIGHT_DIRECTION),
        }
    }

    /// Whether the samples of sample row `sy` within a triangle's bounds (`bounds_words`,
    /// [`Raster::bounds_words`]) are all covered; false without bounds.
    #[inline(always)]
    fn row_covered(&self, bounds_words: Option<[(usize, u64); 2]>, sy: usize) -> bool {
        let row_word = (sy - self.y0) * self.words;
        bounds_words.is_some_and(|bw| bw.iter().all(|&(w, m)| self.covered[row_word + w] & m == m))
    }
}

#[cfg(test)]
mod tests {
    use glam::Mat4;

    use super::*;
    use crate::scene::DrawMaterial;
    use crate::software::coverage::rasterise;
    use crate::software::test_scenes::{count, quad, random_cards};

    /// The eight-sample lanes, the octagons where alpha tests can pass and the skipped covered
    /// rows change nothing: the shortcuts draw the plain rasteriser's masks, areas and covered
    /// samples, on random cards at many sizes.
    #[test]
    fn shortcuts_draw_what_the_plain_rasteriser_draws() {
        let lanes_available = sample_lanes::available();
        if !lanes_available {
            eprintln!("this machine has no AVX2: the lanes are never used, and not compared");
        }
        // Triangles drawn opaque, bilinear, trilinear by the lanes, and by the scalar loop.
        let mut drawn = [0usize; 4];
        // Triangles the octagons leave whole, narrow, and leave out.
        let mut hulled = [0usize; 3];
        for (cards, seed) in [(60, 1), (400, 2), (2000, 3)] {
            let (scene, view_proj) = random_cards(cards, seed);
            let textures = SoftwareTextures::new(&scene, false).expect("textures");
            for (w, h, ss) in [(40, 30, 1), (120, 90, 4), (400, 300, 2), (800, 600, 4)] {
                let [sw, sh] = [w * ss, h * ss].map(|n| n as usize);
                let bands = Bands::new(&scene, &textures, view_proj, [sw, sh], ss as usize);
                let raster =
                    Raster::new(&scene, &textures, &bands, sw, ss as usize, Shortcuts::ALL);
                for t in &bands.triangles {
                    if raster.hulls[t.material as usize].is_some() {
                        hulled[match raster.triangle_hull(raster.with_lod(t)) {
                            TriangleHull::Unbounded => 0,
                            TriangleHull::Rows(_) => 1,
                            TriangleHull::Empty => 2,
                        }] += 1;
                    }
                }
                let draw = |lanes, hulls| {
                    let shortcuts = Shortcuts {
                        lanes,
                        hulls,
                        covered_rows: lanes || hulls,
                    };
                    rasterise(&scene, &textures, view_proj, [w, h, ss], shortcuts).expect("render")
                };
                let plain = draw(false, false);
                let what = format!("{cards} cards, {w}x{h}, {ss}x");
                assert!(count(&plain.0) > 0, "{what}: nothing drawn");
                for (lanes, hulls) in [(false, true), (true, false), (true, true)] {
                    if lanes && !lanes_available {
                        continue;
                    }
                    let other = draw(lanes, hulls);
                    let what = format!("{what}, lanes {lanes}, octagons {hulls}");
                    assert!(plain.0.samples == other.0.samples, "{what}: pixels differ");
                    assert_eq!(plain.1, other.1, "{what}: area");
                    assert_eq!(plain.2, other.2, "{what}: covered samples");
                }
                if !lanes_available {
                    continue;
                }
                // The lanes draw most triangles, of every kind (not only the scalar loop).
                let kinds = bands.triangles.iter().map(|t| {
                    raster
                        .triangle_lanes(&raster.with_lod(t))
                        .map(|l| match l.test {
                            LaneTest::Opaque => 0,
                            LaneTest::Table { filter, .. } => 1 + usize::from(filter.b.is_some()),
                            LaneTest::Quads { .. } => unreachable!("coverage tests by bounds"),
                        })
                });
                let mut counts = [0usize; 4];
                for kind in kinds {
                    counts[kind.unwrap_or(3)] += 1;
                }
                assert!(
                    counts[3] < bands.triangles.len() / 4,
                    "{cards} cards, {w}x{h}: {counts:?} (opaque, bilinear, trilinear, scalar)"
                );
                for (all, n) in drawn.iter_mut().zip(counts) {
                    *all += n;
                }
            }
        }
        assert!(
            !lanes_available || drawn[..3].iter().all(|&n| n > 0),
            "{drawn:?}"
        );
        // The octagons act: most cards' triangles lie on the unit square, whose texture is
        // transparent around a disc (the smallest triangles are left whole, and every
        // triangle of a material no byte passes is left out).
        let total: usize = hulled.iter().sum();
        assert!(
            hulled[1] > total / 8 && hulled[2] > 0,
            "{hulled:?} (whole, narrowed, left out)"
        );
    }

    /// Each pixel counts its covered samples: a quad's edge covers the pixel it crosses by
    /// the fraction of its sample columns left of the edge, at
    /// supersamplings from 1 to 128 (a pixel of more than one word of samples).
    #[test]
    fn pixels_count_their_covered_samples() {
        let scene = DrawScene {
            meshes: vec![quad(-1.0, 0.08, 0.5, false, 0)],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        for ss in [1u32, 2, 5, 64, 100, 128] {
            let (image, _, covered) = rasterise(
                &scene,
                &textures,
                Mat4::IDENTITY,
                [10, 3, ss],
                Shortcuts::ALL,
            )
            .expect("render");
            assert_eq!(image.samples_per_pixel, ss * ss);
            // x = 0.08 in clip space is 5.4 pixels from the left: pixel 5's sample columns at
            // (j + ½)/ss are covered while left of 0.4.
            let left = (0..ss)
                .filter(|&j| (j as f32 + 0.5) / (ss as f32) < 0.4)
                .count();
            let row: Vec<f32> = (0..10).map(|x| image.covered_fraction(x)).collect();
            for (x, f) in row.iter().enumerate() {
                let expected = match x {
                    0..5 => 1.0,
                    5 => (left as u32 * ss) as f32 / (ss * ss) as f32,
                    _ => 0.0,
                };
                assert_eq!(*f, expected, "{ss}x, pixel {x}: {row:?}");
            }
            let per_row: u64 = image.samples[..10].iter().map(|&n| u64::from(n)).sum();
            assert_eq!(covered, 3 * per_row, "{ss}x");
        }
    }
}
