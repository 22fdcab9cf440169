//! A CPU rasteriser for coverage renders: the alpha-tested, mip-mapped triangles of a
//! [`DrawScene`] drawn into a supersampled image and resolved to one binary coverage flag per
//! pixel (covered when at least half of its samples are) and, on request, the mean linear
//! colour of each pixel's covered samples.
//!
//! Why not the wgpu path: the coverage metric (spec animated-billboard-clouds §5.4) renders
//! every model from 5 views over 5 frames at 4× supersampling, 3200×2400 samples at a 600 px
//! screen height. On llvmpipe, the only adapter most machines running frond have, those renders
//! were 80 % of `frond lod`'s wall time on oak_dense (33 of 41 s): a screen rasteriser shades
//! colour, tests depth and reads the image back for a metric that needs one bit per sample.
//! Here a coverage-only render tests each sample once (a covered sample is skipped: coverage
//! does not depend on which surface is in front), reads one alpha channel per fragment, and
//! keeps only a band of the supersampled image in memory at a time. Bands are rasterised in
//! parallel and independently, so the image is the same whatever the thread count, and the
//! same from machine to machine (no driver in the loop). Where the machine has AVX2, coverage
//! renders test eight samples of a row at once ([`crate::sample_lanes`]) with the same
//! operations in the same order: the same bits.
//!
//! It follows the wgpu path's conventions (see the crate docs): wgpu clip space (z in [0, 1]),
//! counter-clockwise front faces, back faces culled unless the material is double-sided,
//! depth test `Less`, samples at pixel centres, the same coverage-preserving mip chains
//! ([`crate::mip_chain`]) filtered trilinearly, alpha test `alpha < cutoff` discarded, and the
//! same lighting. One simplification: the mip level is chosen once per triangle, from the
//! texture-coordinate derivatives at its centroid, where a GPU chooses it per 2×2 block of
//! pixels; the triangles of trees span a few texels of change in level at most.

use frond_scene::Wrap;
use glam::{Mat4, Vec3, Vec4};
use rayon::prelude::*;

use crate::error::RenderError;
use crate::pipeline::{LIGHT_DIRECTION, alpha_mip_chain, linear_mip_chain, mip_chain};
use crate::sample_lanes::{self, LaneFilter, LaneLevel, LaneTest, TriangleLanes};
use crate::scene::{DrawMaterial, DrawMesh, DrawScene, DrawTexture};
use crate::srgb::SRGB_LINEAR;
use crate::uv_hull::{HullLevels, TriangleHull, narrowed};

/// Most samples per side of the supersampled image (coordinates stay exact in `f32`).
pub(crate) const MAX_SIDE: u64 = 1 << 15;

/// Pixel rows per band: the unit of parallel work and of memory (one band's samples per
/// thread).
pub(crate) const BAND_PIXELS: usize = 16;

/// Largest texture side accepted (as the wgpu path's limit on common adapters).
pub(crate) const MAX_TEXTURE_SIDE: u32 = 16384;

/// A coverage render resolved to pixels, top row first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverageImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` flags: at least half of the pixel's samples passed the alpha test.
    pub covered: Vec<bool>,
    /// `width · height` mean linear RGB of the pixel's covered samples (zero where none is);
    /// empty unless colour was asked for ([`SoftwareTextures::new`]).
    pub colour: Vec<[f32; 3]>,
}

/// How lit surfaces are shaded in a colour render.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lighting {
    /// `0.6 + 0.4 · |n · L|`, the wgpu path's: both sides of a surface lit alike, whatever
    /// the light's side (the colour metric's default).
    #[default]
    TwoSided,
    /// What an engine shows of lit, double-sided foliage: `0.3 + 0.7 · max(0, n · L)` with `n`
    /// the normal of the side facing the viewer (flipped on back faces, as glTF asks of
    /// double-sided materials). The side of a leaf or billboard turned from the light is
    /// darker, so a LOD whose normals differ from its leaves' reads lighter or darker.
    Lambert,
}

impl Lighting {
    /// The shade of a unit normal `n` (already facing the viewer) under light `l`.
    #[inline]
    fn shade(self, n: Vec3, l: Vec3) -> f32 {
        match self {
            Lighting::TwoSided => 0.6 + 0.4 * n.dot(l).abs(),
            Lighting::Lambert => 0.3 + 0.7 * n.dot(l).max(0.0),
        }
    }
}

/// A scene's textures prepared for [`render_coverage`]: their coverage-preserving mip chains,
/// computed once for the many renders of one scene's frames and views.
#[derive(Clone, Debug)]
pub struct SoftwareTextures {
    pub(crate) textures: Vec<Levels>,
    /// Per texture and level, the alpha bounds of every bilinear footprint
    /// ([`AlphaBounds`]): of the alpha-only levels when colour is not drawn (coverage renders),
    /// of the RGBA levels' alpha when prepared for the bake ([`SoftwareTextures::for_bake`],
    /// footprints only); empty otherwise.
    alpha_bounds: Vec<Vec<AlphaBounds>>,
    /// Per texture, its levels' alpha channel alone when prepared for the bake
    /// ([`SoftwareTextures::for_bake`]: what [`SoftwareTextures::bake_lanes`] filters); empty
    /// otherwise.
    bake_alpha: Vec<Levels>,
    /// Per texture and level of `bake_alpha`, each bilinear footprint's four alphas (top
    /// left, top right, bottom left, bottom right, a byte each from the lowest) at its top
    /// left texel, for the footprints within the level (0 on its last row and column): what
    /// the eight-sample test gathers, one read a sample ([`LaneTest::Quads`]).
    bake_quads: Vec<Vec<Vec<u32>>>,
    /// Per texture and level, when prepared for the bake, its colour decoded to linear light
    /// on first use where the level holds at most [`MAX_LINEAR_TEXELS`] texels: what
    /// [`SoftwareTextures::bake_rgb`] filters; empty otherwise.
    bake_linear: Vec<Vec<std::sync::OnceLock<Option<LinearLevel>>>>,
    /// Per texture, its linear box chain when a drawn material uses it as a normal map and
    /// colour is drawn (lighting needs the normals); empty otherwise.
    normal_maps: Vec<Levels>,
    pub(crate) colour: bool,
    lighting: Lighting,
}

/// One texture's mip chain, level 0 first: `(width, height, texels)`, one alpha byte a texel,
/// or RGBA (sRGB colour, linear alpha) when colour is drawn.
#[derive(Clone, Debug)]
pub(crate) struct Levels(Vec<(u32, u32, Vec<u8>)>);

impl Levels {
    /// Every level, the first the texture itself: `(width, height, texels)`.
    pub(crate) fn levels(&self) -> &[(u32, u32, Vec<u8>)] {
        &self.0
    }
}

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
    scale: f32,
    cutoff: f32,
    /// Per byte `b`: `b/255 · scale ≥ cutoff` (a footprint whose least alpha is `b` passes).
    pass: [bool; 256],
    /// Per byte `b`: `b/255 · scale < cutoff` (a footprint whose greatest alpha is `b` fails).
    fail: [bool; 256],
    /// The two tables as thresholds ([`AlphaCutoff::thresholds`]).
    thresholds: Option<(u16, u16)>,
    /// The least filtered alpha (in bytes' units) that passes ([`AlphaCutoff::least_passing`]).
    least_passing: Option<f32>,
}

impl AlphaCutoff {
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
    fn decided(&self, [lo, hi]: [u8; 2]) -> Option<bool> {
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

    /// Each material's test of `scene` (its base colour's alpha the scale), `None` for a
    /// material without one.
    pub(crate) fn of_materials(scene: &DrawScene) -> Vec<Option<AlphaCutoff>> {
        scene
            .materials
            .iter()
            .map(|m| m.alpha_cutoff.map(|c| AlphaCutoff::new(m.base_color[3], c)))
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
struct AlphaBounds {
    footprint: Vec<[u8; 2]>,
    trilinear: Vec<[u8; 2]>,
}

/// An alpha level's bilinear footprints as four bytes each ([`SoftwareTextures::bake_quads`]):
/// `[top left, top right, bottom left, bottom right]` at the top left texel's index, for
/// the footprints within the level; 0 on its last row and column, where footprints wrap.
fn footprint_quads(level: &(u32, u32, Vec<u8>)) -> Vec<u32> {
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
    fn new(level: &(u32, u32, Vec<u8>), next: Option<&(u32, u32, Vec<u8>)>) -> AlphaBounds {
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
    fn cell((w, h, _): &(u32, u32, Vec<u8>), uv: [f32; 2]) -> Option<usize> {
        let x0 = floor_i64(uv[0] * *w as f32 - 0.5);
        let y0 = floor_i64(uv[1] * *h as f32 - 0.5);
        ((0..i64::from(*w)).contains(&x0) && (0..i64::from(*h)).contains(&y0))
            .then(|| y0 as usize * *w as usize + x0 as usize)
    }

    /// Every level's bounds of a chain.
    fn chain(levels: &Levels) -> Vec<AlphaBounds> {
        (0..levels.0.len())
            .map(|k| AlphaBounds::new(&levels.0[k], levels.0.get(k + 1)))
            .collect()
    }
}

impl SoftwareTextures {
    /// Prepares the textures of `scene` that its drawn meshes' materials sample; `colour`:
    /// also draw colour, which needs the RGB of every level and a depth test per sample.
    pub fn new(scene: &DrawScene, colour: bool) -> Result<SoftwareTextures, RenderError> {
        let mut used = vec![false; scene.textures.len()];
        let mut normal_map = vec![false; scene.textures.len()];
        for mesh in scene.meshes.iter().filter(|m| !m.indices.is_empty()) {
            let material = scene.materials.get(mesh.material);
            if let Some(t) = material.and_then(|m| m.texture)
                && let Some(u) = used.get_mut(t)
            {
                *u = true;
            }
            if colour
                && mesh.tangents.is_some()
                && let Some(t) = material.and_then(|m| m.normal_texture)
                && let Some(u) = normal_map.get_mut(t)
            {
                *u = true;
            }
        }
        Self::prepare(&scene.textures, used, normal_map, colour)
    }

    /// Every one of `textures` prepared for colour renders without normal maps, as the
    /// billboard bake ([`crate::render_bake`]) draws them: one preparation serves all the
    /// atlas's tiles, whichever meshes each tile holds.
    pub fn for_bake(textures: &[DrawTexture]) -> Result<SoftwareTextures, RenderError> {
        Self::for_bake_of(textures, &vec![true; textures.len()])
    }

    /// [`SoftwareTextures::for_bake`] of the textures `used` marks alone (every texture is
    /// still checked): a tree's bark maps are not drawn on its leaves' billboards. A bake
    /// render of a material whose texture was left out is an error.
    pub fn for_bake_of(
        textures: &[DrawTexture],
        used: &[bool],
    ) -> Result<SoftwareTextures, RenderError> {
        let n = textures.len();
        let used = (0..n)
            .map(|i| used.get(i).copied().unwrap_or(false))
            .collect();
        let mut prepared = Self::prepare(textures, used, vec![false; n], true)?;
        // The bake's alpha test reads one level's alpha channel: kept alone (the eight-sample
        // test gathers it a byte a texel), with its footprints' bounds.
        prepared.bake_alpha = prepared
            .textures
            .par_iter()
            .map(|levels| {
                Levels(
                    (levels.0.iter())
                        .map(|(w, h, rgba)| (*w, *h, rgba.chunks_exact(4).map(|p| p[3]).collect()))
                        .collect(),
                )
            })
            .collect();
        prepared.bake_quads = (prepared.bake_alpha.iter())
            .map(|levels| levels.0.par_iter().map(footprint_quads).collect())
            .collect();
        prepared.bake_linear = (prepared.textures.iter())
            .map(|levels| {
                levels
                    .0
                    .iter()
                    .map(|_| std::sync::OnceLock::new())
                    .collect()
            })
            .collect();
        prepared.alpha_bounds = (prepared.bake_alpha.iter())
            .map(|levels| {
                (levels.0.iter())
                    .map(|level| AlphaBounds::new(level, None))
                    .collect()
            })
            .collect();
        Ok(prepared)
    }

    /// Whether texture `texture` was prepared (has levels).
    pub(crate) fn prepared(&self, texture: usize) -> bool {
        self.textures.get(texture).is_some_and(|l| !l.0.is_empty())
    }

    /// The bake's alpha test at `uv` of `texture`'s level nearer `lod`
    /// ([`Levels::alpha_nearest_level`]): `alpha · scale ≥ cutoff`, decided from the
    /// footprint's bounds where they settle it (prepared by [`SoftwareTextures::for_bake`]).
    #[inline]
    pub(crate) fn bake_alpha_test(
        &self,
        texture: usize,
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        cutoff: &AlphaCutoff,
    ) -> bool {
        let levels = &self.textures[texture];
        let level = lod.nearest();
        if let Some(bounds) = self.alpha_bounds.get(texture)
            && let Some(cell) = AlphaBounds::cell(&levels.0[level], uv)
            && let Some(pass) = cutoff.decided(bounds[level].footprint[cell])
        {
            return pass;
        }
        let (o, fx, fy) = footprint(&levels.0[level], uv, wrap, 4);
        let data = &levels.0[level].2;
        let alpha = bilerp(o.map(|k| f32::from(data[k + 3])), fx, fy) / 255.0;
        cutoff.passes(alpha)
    }

    /// The bake's colour of `texture` at `uv`: [`Levels::rgb`] (`linear` decoding sRGB), the
    /// same bits, from its levels decoded beforehand where it has them.
    #[inline]
    pub(crate) fn bake_rgb(
        &self,
        texture: usize,
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        linear: &[f32; 256],
    ) -> Vec3 {
        let at = |l: usize| match self.bake_linear_level(texture, l) {
            Some(level) => level.bilinear(uv, wrap),
            None => bilinear_rgb(&self.textures[texture].0[l], uv, wrap, linear),
        };
        let va = at(lod.a as usize);
        if lod.f > 0.0 {
            va + (at(lod.b as usize) - va) * lod.f
        } else {
            va
        }
    }

    /// Level `level` of `texture` decoded to linear light for the bake (decoded on first use),
    /// `None` when it is not (not prepared for the bake, or over [`MAX_LINEAR_TEXELS`]).
    pub(crate) fn bake_linear_level(&self, texture: usize, level: usize) -> Option<&LinearLevel> {
        let decode = || LinearLevel::new(&self.textures[texture].0[level], &SRGB_LINEAR);
        (self.bake_linear.get(texture)?.get(level)?)
            .get_or_init(decode)
            .as_ref()
    }

    /// The bake's eight-sample test of triangle `t` of a material with `texture` sampled with
    /// `wrap` and the alpha test `cutoff` ([`SoftwareTextures::bake_alpha_test`], in lanes):
    /// the bounds table and the bilinear filter of the level nearer `t.lod`. `None` where the
    /// lanes cannot decide as the scalar test does (not prepared for the bake, or a test
    /// without thresholds).
    pub(crate) fn bake_lanes(
        &self,
        t: &Setup,
        texture: usize,
        wrap: [Wrap; 2],
        cutoff: &AlphaCutoff,
    ) -> Option<TriangleLanes<'_>> {
        let level = t.lod.nearest();
        let quads = self.bake_quads.get(texture)?.get(level)?;
        let (width, height, texels) = self.bake_alpha.get(texture)?.0.get(level)?;
        Some(TriangleLanes {
            q: t.q,
            uq: t.uq,
            affine: t.affine_corners(),
            test: LaneTest::Quads {
                quads,
                least_passing: cutoff.least_passing,
                filter: LaneFilter {
                    a: LaneLevel {
                        texels,
                        width: *width,
                        height: *height,
                        wrap,
                    },
                    b: None,
                    f: 0.0,
                    scale: cutoff.scale,
                    cutoff: cutoff.cutoff,
                },
            },
        })
    }

    /// The mip chains of the `used` textures (colour or alpha alone) and of the `normal_map`
    /// ones (linear).
    fn prepare(
        source: &[DrawTexture],
        used: Vec<bool>,
        normal_map: Vec<bool>,
        colour: bool,
    ) -> Result<SoftwareTextures, RenderError> {
        // In parallel: a 1024² colour chain is tens of milliseconds.
        let textures: Vec<Levels> = source
            .par_iter()
            .zip(used)
            .enumerate()
            .map(|(i, (t, used))| {
                let texels = t.width as usize * t.height as usize;
                if t.width == 0
                    || t.height == 0
                    || t.width > MAX_TEXTURE_SIDE
                    || t.height > MAX_TEXTURE_SIDE
                    || t.rgba.len() != texels * 4
                {
                    return Err(RenderError::InvalidTexture {
                        texture: i,
                        reason: format!(
                            "{}x{} with {} bytes (sides 1 to {MAX_TEXTURE_SIDE}, 4 bytes a texel)",
                            t.width,
                            t.height,
                            t.rgba.len()
                        ),
                    });
                }
                Ok(Levels(if !used {
                    Vec::new()
                } else if colour {
                    mip_chain(t.width, t.height, &t.rgba)
                } else {
                    let alpha: Vec<u8> = t.rgba.chunks_exact(4).map(|p| p[3]).collect();
                    alpha_mip_chain(t.width, t.height, &alpha)
                }))
            })
            .collect::<Result<_, _>>()?;
        let normal_maps = source
            .iter()
            .zip(normal_map)
            .map(|(t, used)| {
                Levels(if used {
                    linear_mip_chain(t.width, t.height, t.rgba.clone())
                } else {
                    Vec::new()
                })
            })
            .collect();
        let alpha_bounds = if colour {
            Vec::new()
        } else {
            textures.iter().map(AlphaBounds::chain).collect()
        };
        Ok(SoftwareTextures {
            textures,
            alpha_bounds,
            bake_alpha: Vec::new(),
            bake_quads: Vec::new(),
            bake_linear: Vec::new(),
            normal_maps,
            colour,
            lighting: Lighting::TwoSided,
        })
    }

    /// The same textures, colour shaded with `lighting`.
    pub fn with_lighting(mut self, lighting: Lighting) -> SoftwareTextures {
        self.lighting = lighting;
        self
    }
}

/// One triangle ready to rasterise: sample-space vertices, attributes divided by `w`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup {
    pub(crate) x: [f32; 3],
    pub(crate) y: [f32; 3],
    /// Depth (NDC z), interpolated linearly on screen.
    pub(crate) z: [f32; 3],
    /// `1 / w`.
    pub(crate) q: [f32; 3],
    /// Texture coordinates divided by `w`.
    pub(crate) uq: [[f32; 2]; 3],
    /// `1 / (twice the signed area)`, positive (vertices ordered so that it is).
    pub(crate) inv_area: f32,
    pub(crate) material: u32,
    pub(crate) lit: bool,
    /// A back face (drawn double-sided): its normal is flipped to face the viewer.
    pub(crate) back: bool,
    /// The material texture's two mip levels and the second's weight, chosen at the centroid.
    pub(crate) lod: Trilinear,
    /// Inclusive sample bounds.
    pub(crate) min: [i32; 2],
    pub(crate) max: [i32; 2],
}

/// A triangle's shading attributes, beside its [`Setup`] in renders that shade (colour, or a
/// bake's normals): a coverage render reads none of them, and leaving them out halves what it
/// writes and reads back per triangle.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Shading {
    /// Normals divided by `w` (zero for unlit meshes).
    pub(crate) nq: [Vec3; 3],
    /// Tangents (xyz divided by `w`, w the bitangent's sign) when the normal map applies.
    pub(crate) tq: Option<[Vec4; 3]>,
    /// The normal map's two mip levels and the second's weight, chosen at the centroid.
    pub(crate) normal_lod: Trilinear,
}

/// A vertex in clip space with its attributes, for near/far clipping.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    clip: Vec4,
    uv: [f32; 2],
    normal: Vec3,
    tangent: Vec4,
}

impl ClipVertex {
    fn lerp(a: &ClipVertex, b: &ClipVertex, t: f32) -> ClipVertex {
        ClipVertex {
            clip: a.clip + (b.clip - a.clip) * t,
            uv: [
                a.uv[0] + (b.uv[0] - a.uv[0]) * t,
                a.uv[1] + (b.uv[1] - a.uv[1]) * t,
            ],
            normal: a.normal + (b.normal - a.normal) * t,
            tangent: a.tangent + (b.tangent - a.tangent) * t,
        }
    }
}

/// Renders `scene` through `view_proj` (wgpu clip space, as [`crate::Renderer::render_view`])
/// at `width`×`height` pixels of `supersample`² samples each, with `textures` prepared from
/// `scene.textures`, and resolves the samples to pixels (see [`CoverageImage`]).
pub fn render_coverage(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<CoverageImage, RenderError> {
    rasterise(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        Shortcuts::ALL,
    )
    .map(|r| r.0)
}

/// The depth complexity of `scene` seen through `view_proj` at `width`×`height` pixels of
/// `supersample`² samples: fragments rasterised (every sample inside a drawn triangle, before
/// the alpha test discards any: each one runs the fragment shader, since alpha-tested surfaces
/// defeat early depth rejection) per covered sample; 0 when nothing is covered. The overdraw an
/// engine pays for alpha-tested foliage, whatever the draw order. The fragments are counted as
/// the drawn triangles' area in samples (after depth clipping and culling; a part outside the
/// image's sides counts too), which the samples inside them match up to their edges: counting
/// them one by one, without skipping covered samples, cost 2.3 s of oak_dense's run.
pub fn depth_complexity(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<f64, RenderError> {
    render_coverage_with_depth(scene, textures, view_proj, width, height, supersample).map(|r| r.1)
}

/// [`render_coverage`] and [`depth_complexity`] of the same render at once: the same mask, and
/// the same depth complexity (its pixels are not saturated, so the covered samples are
/// counted exactly). The metric's first (view, frame) pair gives both, one render fewer.
pub fn render_coverage_with_depth(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<(CoverageImage, f64), RenderError> {
    let (image, fragments, covered) = rasterise(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        Shortcuts {
            saturate: false,
            ..Shortcuts::ALL
        },
    )?;
    let depth = if covered == 0 {
        0.0
    } else {
        fragments / covered as f64
    };
    Ok((image, depth))
}

/// The shortcuts a coverage render takes, each giving the same image (tests compare them):
/// see [`Raster::saturate`], [`Raster::lanes`], [`Raster::hulls`] and
/// [`Raster::covered_rows`].
#[derive(Clone, Copy, Debug)]
struct Shortcuts {
    saturate: bool,
    lanes: bool,
    hulls: bool,
    covered_rows: bool,
}

impl Shortcuts {
    const ALL: Shortcuts = Shortcuts {
        saturate: true,
        lanes: true,
        hulls: true,
        covered_rows: true,
    };
}

/// [`render_coverage`], the drawn triangles' area in samples, and the samples covered (all
/// of a decided pixel's when `shortcuts.saturate`, see [`Raster::saturate`]).
fn rasterise(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    [width, height, supersample]: [u32; 3],
    shortcuts: Shortcuts,
) -> Result<(CoverageImage, f64, u64), RenderError> {
    let (sw, sh) = checked_target(scene, textures, view_proj, [width, height, supersample])?;
    let ss = supersample.max(1);
    let bands = Bands::new(scene, textures, view_proj, [sw, sh], ss as usize);
    let raster = Raster::new(scene, textures, &bands, sw, ss as usize, shortcuts);
    let band_rows = bands.rows;
    let resolved: Vec<Band> = (bands.bins.par_iter())
        .enumerate()
        .map(|(b, bin)| raster.band(b * band_rows, ((b + 1) * band_rows).min(sh), bin))
        .collect();
    let mut image = CoverageImage {
        width,
        height,
        covered: Vec::with_capacity(width as usize * height as usize),
        colour: Vec::new(),
    };
    let mut covered_samples = 0;
    for band in resolved {
        image.covered.extend(band.mask);
        image.colour.extend(band.colour);
        covered_samples += band.covered_samples;
    }
    let area: f64 = (bands.triangles.iter())
        .map(|t| 0.5 / f64::from(t.inv_area))
        .sum();
    Ok((image, area, covered_samples))
}

/// The supersampled target's sides in samples, once the request is checked: both sides at
/// least a pixel and at most [`MAX_SIDE`] samples, a finite matrix, a valid scene and
/// textures prepared for it.
pub(crate) fn checked_target(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    [width, height, supersample]: [u32; 3],
) -> Result<(usize, usize), RenderError> {
    let ss = supersample.max(1);
    let (sw, sh) = (
        u64::from(width) * u64::from(ss),
        u64::from(height) * u64::from(ss),
    );
    if width == 0 || height == 0 || sw > MAX_SIDE || sh > MAX_SIDE {
        return Err(RenderError::InvalidSize {
            width,
            height,
            reason: format!(
                "both sides must be at least 1 pixel and at most {MAX_SIDE} samples \
                 ({supersample}x supersampled)"
            ),
        });
    }
    if !view_proj.is_finite() {
        return Err(RenderError::InvalidCamera(
            "the view-projection matrix has a non-finite entry".into(),
        ));
    }
    scene.validate(MAX_TEXTURE_SIDE)?;
    if textures.textures.len() != scene.textures.len() {
        return Err(RenderError::InvalidTexture {
            texture: textures.textures.len().min(scene.textures.len()),
            reason: format!(
                "{} textures prepared for a scene of {}",
                textures.textures.len(),
                scene.textures.len()
            ),
        });
    }
    Ok((sw as usize, sh as usize))
}

/// A render's triangles set up, and binned into bands of [`BAND_PIXELS`] pixel rows: the
/// unit of parallel work of both CPU rasterisers.
pub(crate) struct Bands {
    pub(crate) triangles: Vec<Setup>,
    /// Per triangle, its shading attributes when the textures were prepared with colour
    /// (empty otherwise).
    pub(crate) shading: Vec<Shading>,
    /// Per band, the triangles whose bounds reach it, in draw order.
    pub(crate) bins: Vec<Vec<u32>>,
    /// Sample rows per band.
    pub(crate) rows: usize,
}

impl Bands {
    /// Sets up `scene`'s triangles for a target of `sw`×`sh` samples, `ss` per pixel side,
    /// and bins them.
    pub(crate) fn new(
        scene: &DrawScene,
        textures: &SoftwareTextures,
        view_proj: Mat4,
        [sw, sh]: [usize; 2],
        ss: usize,
    ) -> Bands {
        let (triangles, shading) = setup(scene, textures, view_proj, sw as f32, sh as f32);
        let rows = BAND_PIXELS * ss;
        let mut bins: Vec<Vec<u32>> = vec![Vec::new(); sh.div_ceil(rows)];
        for (i, t) in triangles.iter().enumerate() {
            let first = (t.min[1].max(0) as usize) / rows;
            let last = (t.max[1].max(0) as usize).min(sh - 1) / rows;
            for bin in &mut bins[first..=last] {
                bin.push(i as u32);
            }
        }
        Bands {
            triangles,
            shading,
            bins,
            rows,
        }
    }
}

/// One band of the image, resolved: its pixels' coverage and colour, and its covered samples.
struct Band {
    mask: Vec<bool>,
    colour: Vec<[f32; 3]>,
    covered_samples: u64,
}

/// Transforms, clips (near and far planes), culls and sets up every triangle of `scene`, in
/// draw order, for a target of `sw`×`sh` samples, with their shading when the textures were
/// prepared with colour.
pub(crate) fn setup(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    sw: f32,
    sh: f32,
) -> (Vec<Setup>, Vec<Shading>) {
    let mut set_up = SetUpMeshes::default();
    set_up.set_up(
        &scene.meshes,
        &scene.materials,
        textures,
        view_proj,
        [sw, sh],
    );
    (set_up.triangles, set_up.shading)
}

/// Triangles set up by [`SetUpMeshes::set_up`], its buffers reused from call to call.
#[derive(Debug, Default)]
pub(crate) struct SetUpMeshes {
    pub(crate) triangles: Vec<Setup>,
    /// Per triangle, its shading (when the textures were prepared with colour).
    pub(crate) shading: Vec<Shading>,
    /// A mesh's positions in clip space.
    clip: Vec<Vec4>,
}

impl SetUpMeshes {
    /// [`setup`] of `meshes` (of `materials`) alone, replacing what was set up before.
    pub(crate) fn set_up(
        &mut self,
        meshes: &[DrawMesh],
        materials: &[DrawMaterial],
        textures: &SoftwareTextures,
        view_proj: Mat4,
        size: [f32; 2],
    ) {
        // Reserved up front: growing it (tens of megabytes for a large tree) was a tenth of a
        // small render's time.
        let count = meshes.iter().map(|m| m.indices.len() / 3).sum();
        self.triangles.clear();
        self.triangles.reserve(count);
        self.shading.clear();
        self.shading
            .reserve(if textures.colour { count } else { 0 });
        for mesh in meshes {
            self.set_up_mesh(mesh, &materials[mesh.material], textures, view_proj, size);
        }
    }

    /// One mesh of [`SetUpMeshes::set_up`], drawn with `material`: its triangles and their
    /// shading appended.
    fn set_up_mesh(
        &mut self,
        mesh: &DrawMesh,
        material: &DrawMaterial,
        textures: &SoftwareTextures,
        view_proj: Mat4,
        [sw, sh]: [f32; 2],
    ) {
        let SetUpMeshes {
            triangles: out,
            shading,
            clip,
        } = self;
        let shade = textures.colour;
        clip.clear();
        clip.extend((mesh.positions.iter()).map(|p| view_proj * Vec3::from(*p).extend(1.0)));
        let texture = material.texture.map(|t| &textures.textures[t]);
        let lit = mesh.normals.is_some();
        // The normal map applies to lit meshes with tangents when it was prepared (colour).
        let normal_map = match (lit, &mesh.tangents, material.normal_texture) {
            (true, Some(_), Some(t)) => Some(&textures.normal_maps[t]).filter(|l| !l.0.is_empty()),
            _ => None,
        };
        for tri in mesh.indices.chunks_exact(3) {
            let vertex = |k: usize| {
                let i = tri[k] as usize;
                ClipVertex {
                    clip: clip[i],
                    uv: mesh.uvs.as_ref().map_or([0.0; 2], |u| u[i]),
                    normal: mesh
                        .normals
                        .as_ref()
                        .map_or(Vec3::ZERO, |n| Vec3::from(n[i])),
                    tangent: mesh
                        .tangents
                        .as_ref()
                        .map_or(Vec4::ZERO, |t| Vec4::from(t[i])),
                }
            };
            let corners = [vertex(0), vertex(1), vertex(2)];
            let inside = |v: &ClipVertex| v.clip.z >= 0.0 && v.clip.z <= v.clip.w;
            let mut push = |c: [&ClipVertex; 3]| {
                if let Some((mut s, sh)) =
                    setup_triangle(c, material, [texture, normal_map], [lit, shade], sw, sh)
                {
                    s.material = mesh.material as u32;
                    out.push(s);
                    if shade {
                        shading.push(sh);
                    }
                }
            };
            if corners.iter().all(inside) {
                push([&corners[0], &corners[1], &corners[2]]);
                continue;
            }
            let polygon = clip_polygon(corners.to_vec());
            for k in 1..polygon.len().saturating_sub(1) {
                push([&polygon[0], &polygon[k], &polygon[k + 1]]);
            }
        }
    }
}

/// `polygon` clipped to `0 ≤ z ≤ w` (wgpu's depth range), Sutherland–Hodgman.
fn clip_polygon(polygon: Vec<ClipVertex>) -> Vec<ClipVertex> {
    let near = |v: &ClipVertex| v.clip.z;
    let far = |v: &ClipVertex| v.clip.w - v.clip.z;
    let mut p = polygon;
    for plane in [&near as &dyn Fn(&ClipVertex) -> f32, &far] {
        if p.iter().all(|v| plane(v) >= 0.0) {
            continue;
        }
        let mut next = Vec::with_capacity(p.len() + 1);
        for i in 0..p.len() {
            let (a, b) = (&p[i], &p[(i + 1) % p.len()]);
            let (da, db) = (plane(a), plane(b));
            if da >= 0.0 {
                next.push(*a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                next.push(ClipVertex::lerp(a, b, da / (da - db)));
            }
        }
        p = next;
    }
    p
}

/// One clipped triangle in sample space, or `None` when it is culled, degenerate or off the
/// image.
fn setup_triangle(
    corners: [&ClipVertex; 3],
    material: &DrawMaterial,
    [texture, normal_map]: [Option<&Levels>; 2],
    [lit, shade]: [bool; 2],
    sw: f32,
    sh: f32,
) -> Option<(Setup, Shading)> {
    let mut v = corners.map(|c| {
        let q = 1.0 / c.clip.w;
        (
            (c.clip.x * q * 0.5 + 0.5) * sw,
            (0.5 - c.clip.y * q * 0.5) * sh,
            c.clip.z * q,
            q,
            [c.uv[0] * q, c.uv[1] * q],
            c,
        )
    });
    if v.iter()
        .any(|c| !(c.0.is_finite() && c.1.is_finite() && c.3 > 0.0))
    {
        return None;
    }
    // Twice the signed area in sample space (y down): negative for counter-clockwise (front)
    // faces of wgpu's y-up clip space.
    let area = (v[1].0 - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (v[1].1 - v[0].1);
    if area == 0.0 || !area.is_finite() || (area > 0.0 && !material.double_sided) {
        return None;
    }
    // Positive: clockwise on screen, a back face (kept only when double-sided).
    let back = area > 0.0;
    if area < 0.0 {
        v.swap(1, 2);
    }
    let area = area.abs();
    let min_x = v.iter().map(|c| c.0).fold(f32::INFINITY, f32::min);
    let max_x = v.iter().map(|c| c.0).fold(f32::NEG_INFINITY, f32::max);
    let min_y = v.iter().map(|c| c.1).fold(f32::INFINITY, f32::min);
    let max_y = v.iter().map(|c| c.1).fold(f32::NEG_INFINITY, f32::max);
    // Samples at centres: sample i is at i + 0.5.
    let min = [(min_x - 0.5).ceil().max(0.0), (min_y - 0.5).ceil().max(0.0)];
    let max = [
        (max_x - 0.5).floor().min(sw - 1.0),
        (max_y - 0.5).floor().min(sh - 1.0),
    ];
    if min[0] > max[0] || min[1] > max[1] {
        return None;
    }
    let mut s = Setup {
        x: v.map(|c| c.0),
        y: v.map(|c| c.1),
        z: v.map(|c| c.2),
        q: v.map(|c| c.3),
        uq: v.map(|c| c.4),
        inv_area: 1.0 / area,
        material: 0,
        lit,
        back,
        lod: Trilinear::default(),
        min: [min[0] as i32, min[1] as i32],
        max: [max[0] as i32, max[1] as i32],
    };
    // Colour renders' (and the bake's) levels now; a coverage render's when a band first
    // tests a sample of the triangle ([`Raster::with_lod`]): inside a crown most triangles
    // are drawn over samples covered already, and never need it.
    if shade && let Some(levels) = texture {
        s.lod = levels.pair(centroid_lod(&s, levels));
    }
    let mut shading = Shading::default();
    if shade {
        // In the vertices' final order (swapped to make the area positive).
        shading.nq = v.map(|c| c.5.normal * c.3);
        shading.tq = normal_map.map(|_| {
            v.map(|c| {
                c.5.tangent.truncate().extend(0.0) * c.3 + Vec4::new(0.0, 0.0, 0.0, c.5.tangent.w)
            })
        });
        if let Some(levels) = normal_map {
            shading.normal_lod = levels.pair(centroid_lod(&s, levels));
        }
    }
    Some((s, shading))
}

impl Setup {
    /// Screen-space barycentric weights of point `(px, py)`.
    pub(crate) fn weights(&self, px: f32, py: f32) -> [f32; 3] {
        let e = |a: usize, b: usize| {
            (self.x[b] - self.x[a]) * (py - self.y[a]) - (self.y[b] - self.y[a]) * (px - self.x[a])
        };
        [
            e(1, 2) * self.inv_area,
            e(2, 0) * self.inv_area,
            e(0, 1) * self.inv_area,
        ]
    }

    /// Perspective-correct texture coordinates at weights `b`, and `Σ b·q`.
    pub(crate) fn uv(&self, b: [f32; 3]) -> ([f32; 2], f32) {
        let q = b[0] * self.q[0] + b[1] * self.q[1] + b[2] * self.q[2];
        let u = b[0] * self.uq[0][0] + b[1] * self.uq[1][0] + b[2] * self.uq[2][0];
        let v = b[0] * self.uq[0][1] + b[1] * self.uq[1][1] + b[2] * self.uq[2][1];
        ([u / q, v / q], q)
    }

    /// The texture coordinates at the corners where `1/w` is the same at all three (an affine
    /// triangle, as every one an orthographic view draws): then the coordinates at weights `b`
    /// are `Σ b·uv` ([`affine_uv`]), with no division per sample.
    #[inline]
    pub(crate) fn affine_corners(&self) -> Option<[[f32; 2]; 3]> {
        let q = self.q;
        (q[0] == q[1] && q[1] == q[2]).then(|| self.uq.map(|c| [c[0] / q[0], c[1] / q[0]]))
    }
}

/// The texture coordinates at weights `b` of an affine triangle whose corners have `uv`
/// ([`Setup::affine_corners`]): `Σ b·uv` left to right, as the eight-sample lanes sum them.
#[inline]
pub(crate) fn affine_uv(uv: &[[f32; 2]; 3], b: [f32; 3]) -> [f32; 2] {
    [0, 1].map(|k| b[0] * uv[0][k] + b[1] * uv[1][k] + b[2] * uv[2][k])
}

/// The mip level of `levels` at `s`'s centroid: log2 of the longer of the texture
/// coordinates' screen derivatives along x and y, in level-0 texels (as a GPU's trilinear
/// filter), at least 0.
fn centroid_lod(s: &Setup, levels: &Levels) -> f32 {
    let (w, h) = (levels.0[0].0 as f32, levels.0[0].1 as f32);
    let cx = (s.x[0] + s.x[1] + s.x[2]) / 3.0;
    let cy = (s.y[0] + s.y[1] + s.y[2]) / 3.0;
    let (uv, _) = s.uv(s.weights(cx, cy));
    let (ux, _) = s.uv(s.weights(cx + 1.0, cy));
    let (uy, _) = s.uv(s.weights(cx, cy + 1.0));
    let dx = hypot((ux[0] - uv[0]) * w, (ux[1] - uv[1]) * h);
    let dy = hypot((uy[0] - uv[0]) * w, (uy[1] - uv[1]) * h);
    let rho = dx.max(dy);
    if rho.is_finite() && rho > 1.0 {
        rho.log2()
    } else {
        0.0
    }
}

/// `√(x² + y²)` as glibc's `hypotf` computes it (the squares exact in `f64`, their sum and
/// its root rounded there, then to `f32`; infinite when either argument is, even beside a
/// NaN): the same bits, without the library call (a third of the mip level's time, which
/// every triangle of every render needs), and the same on every platform, whatever its C
/// library.
#[inline]
fn hypot(x: f32, y: f32) -> f32 {
    if x.is_infinite() || y.is_infinite() {
        return f32::INFINITY;
    }
    let (x, y) = (f64::from(x), f64::from(y));
    (x * x + y * y).sqrt() as f32
}

/// `x.floor()` as an integer, without the library call `f32::floor` becomes on baseline
/// x86-64 (a tenth of the rasteriser's time). Saturates at the ends of `i64` (a file's
/// texture coordinate of ±3e38), as `as` does.
#[inline]
fn floor_i64(x: f32) -> i64 {
    let i = x as i64;
    // Without a branch: which way it goes is a coin toss for texel coordinates.
    i.saturating_sub(i64::from((i as f32) > x))
}

/// Texel index `i` of a side of `n` texels under `wrap`.
#[inline]
pub(crate) fn wrap_index(i: i64, n: u32, wrap: Wrap) -> usize {
    let n = i64::from(n.max(1));
    if (0..n).contains(&i) {
        return i as usize;
    }
    // The common cases without a division: a footprint one texel over either edge.
    match (wrap, i == -1, i == n) {
        (Wrap::Repeat, true, _) | (Wrap::ClampToEdge, false, true) => return (n - 1) as usize,
        (Wrap::Repeat, _, true) | (Wrap::ClampToEdge, true, _) => return 0,
        (Wrap::MirroredRepeat, true, _) => return 0,
        (Wrap::MirroredRepeat, _, true) => return (n - 1) as usize,
        _ => {}
    }
    (match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    }) as usize
}

/// A trilinear fetch's two mip levels and the weight of the second (0: the first alone).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Trilinear {
    // Level indices as `u32`: a `Setup` is stored per triangle and rendered many times over.
    pub(crate) a: u32,
    pub(crate) b: u32,
    pub(crate) f: f32,
}

impl Trilinear {
    /// The level of the two nearer the fetch's (what `LINEAR_MIPMAP_NEAREST` reads).
    #[inline]
    pub(crate) fn nearest(self) -> usize {
        (if self.f < 0.5 { self.a } else { self.b }) as usize
    }
}

/// Bilinear filter of channel `channel` (of `stride`-byte texels) of one level at `(u, v)`,
/// each texel `decode`d first (its byte as is for alpha, to linear light for sRGB colour, as
/// GPUs filter sRGB textures); the four texels wrap under `wrap` only when the footprint
/// leaves the level.
#[inline]
fn bilinear(
    level: &(u32, u32, Vec<u8>),
    uv: [f32; 2],
    wrap: [Wrap; 2],
    stride: usize,
    channel: usize,
    decode: impl Fn(u8) -> f32,
) -> f32 {
    let (o, fx, fy) = footprint(level, uv, wrap, stride);
    let data = &level.2;
    bilerp([0, 1, 2, 3].map(|k| decode(data[o[k] + channel])), fx, fy)
}

/// The bilinear blend of a footprint's four values (top-left, top-right, bottom-left,
/// bottom-right) with the weights of the right and bottom ones.
#[inline]
fn bilerp<T>([a, b, c, d]: [T; 4], fx: f32, fy: f32) -> T
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    let top = a + (b - a) * fx;
    let bottom = c + (d - c) * fx;
    top + (bottom - top) * fy
}

/// The most texels a level decoded to linear light holds (16 MiB): a bake reads the small
/// levels of leaf textures; a larger level is decoded texel by texel as it is read.
const MAX_LINEAR_TEXELS: usize = 1 << 20;

/// An RGBA level's colour decoded to linear light, `[r, g, b, 0]` a texel: a bilinear fetch
/// reads four vectors where [`bilinear_rgb`] reads and decodes twelve bytes (the bake shades
/// every covered sample, a third of its time on oak_dense).
#[derive(Clone, Debug)]
pub(crate) struct LinearLevel {
    pub(crate) width: u32,
    pub(crate) height: u32,
    texels: Vec<Vec4>,
}

impl LinearLevel {
    /// `level` decoded by `linear`, `None` over [`MAX_LINEAR_TEXELS`].
    fn new((width, height, rgba): &(u32, u32, Vec<u8>), linear: &[f32; 256]) -> Option<Self> {
        (rgba.len() / 4 <= MAX_LINEAR_TEXELS).then(|| LinearLevel {
            width: *width,
            height: *height,
            texels: (rgba.chunks_exact(4))
                .map(|p| {
                    let [r, g, b] = [0, 1, 2].map(|k| linear[usize::from(p[k])]);
                    Vec4::new(r, g, b, 0.0)
                })
                .collect(),
        })
    }

    /// [`bilinear_rgb`] of the level it was decoded from: the same footprint, and the same
    /// operations on each channel (a vector's lanes round as scalars do), so the same bits.
    #[inline]
    pub(crate) fn bilinear(&self, uv: [f32; 2], wrap: [Wrap; 2]) -> Vec3 {
        let (o, fx, fy) = footprint_of([self.width, self.height], uv, wrap, 1);
        bilerp(o.map(|k| self.texels[k]), fx, fy).truncate()
    }

    /// [`LinearLevel::bilinear`] of a footprint that does not wrap, found beforehand: texel
    /// `first` (top left) and the weights `fx`, `fy` (`crate::bake_lanes`).
    #[inline]
    pub(crate) fn bilinear_at(&self, first: usize, fx: f32, fy: f32) -> Vec3 {
        let w = self.width as usize;
        // One bounds check for the four texels (the footprint's rows are `w` apart).
        let t = &self.texels[first..first + w + 2];
        bilerp([t[0], t[1], t[w], t[w + 1]], fx, fy).truncate()
    }
}

/// [`bilinear`] of the three colour channels of an RGBA level at once, each texel decoded to
/// linear light by `linear`: the footprint is found once for the three.
#[inline]
fn bilinear_rgb(
    level: &(u32, u32, Vec<u8>),
    uv: [f32; 2],
    wrap: [Wrap; 2],
    linear: &[f32; 256],
) -> Vec3 {
    let (o, fx, fy) = footprint(level, uv, wrap, 4);
    let data = &level.2;
    let at = |k: usize| {
        let t = &data[o[k]..o[k] + 3];
        Vec3::new(
            linear[t[0] as usize],
            linear[t[1] as usize],
            linear[t[2] as usize],
        )
    };
    bilerp([0, 1, 2, 3].map(at), fx, fy)
}

/// The byte offsets of the four texels (of `stride` bytes) a bilinear fetch of `level` at
/// `uv` reads — top-left, top-right, bottom-left, bottom-right — and the horizontal and
/// vertical weights of the second of each pair; they wrap under `wrap` only when the
/// footprint leaves the level.
#[inline(always)]
fn footprint(
    level: &(u32, u32, Vec<u8>),
    uv: [f32; 2],
    wrap: [Wrap; 2],
    stride: usize,
) -> ([usize; 4], f32, f32) {
    footprint_of([level.0, level.1], uv, wrap, stride)
}

/// [`footprint`] on a level of `w`×`h` texels.
#[inline(always)]
fn footprint_of(
    [w, h]: [u32; 2],
    uv: [f32; 2],
    wrap: [Wrap; 2],
    stride: usize,
) -> ([usize; 4], f32, f32) {
    let x = uv[0] * w as f32 - 0.5;
    let y = uv[1] * h as f32 - 0.5;
    let (x0, y0) = (floor_i64(x), floor_i64(y));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let (wi, hi) = (i64::from(w), i64::from(h));
    // A texture coordinate far outside the texture (a file's 3e38) floors to i64::MAX: the
    // tests and the `+ 1` below never overflow on it.
    let (xa, xb, ya, yb) = if x0 >= 0 && x0 < wi - 1 && y0 >= 0 && y0 < hi - 1 {
        (x0 as usize, x0 as usize + 1, y0 as usize, y0 as usize + 1)
    } else {
        (
            wrap_index(x0, w, wrap[0]),
            wrap_index(x0.saturating_add(1), w, wrap[0]),
            wrap_index(y0, h, wrap[1]),
            wrap_index(y0.saturating_add(1), h, wrap[1]),
        )
    };
    let row = w as usize * stride;
    (
        [
            ya * row + xa * stride,
            ya * row + xb * stride,
            yb * row + xa * stride,
            yb * row + xb * stride,
        ],
        fx,
        fy,
    )
}

impl Levels {
    /// The two levels of a trilinear fetch at `lod`.
    fn pair(&self, lod: f32) -> Trilinear {
        let last = self.0.len() - 1;
        let a = (floor_i64(lod).max(0) as usize).min(last);
        let f = if a < last { lod - a as f32 } else { 0.0 };
        Trilinear {
            a: a as u32,
            b: (a + 1).min(last) as u32,
            f,
        }
    }

    /// Trilinear alpha (0..1) at `(u, v)`; `stride`: bytes a texel (1: alpha only, 4: RGBA).
    #[inline]
    pub(crate) fn alpha(
        &self,
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        stride: usize,
    ) -> f32 {
        let a = bilinear(
            &self.0[lod.a as usize],
            uv,
            wrap,
            stride,
            stride - 1,
            f32::from,
        );
        let a = if lod.f > 0.0 {
            a + (bilinear(
                &self.0[lod.b as usize],
                uv,
                wrap,
                stride,
                stride - 1,
                f32::from,
            ) - a)
                * lod.f
        } else {
            a
        };
        a / 255.0
    }

    /// The alpha test of a coverage render, `alpha(uv) · scale ≥ cutoff` with the trilinear
    /// alpha of [`Levels::alpha`] (alpha-only levels, `bounds` theirs): the same answer,
    /// filtering only when the footprints' [`AlphaBounds`] leave it open.
    #[inline]
    fn alpha_test(
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

    /// Bilinear alpha (0..1) at `(u, v)` of the one level nearer `lod` (a GPU's
    /// `LINEAR_MIPMAP_NEAREST`): half the fetches of [`Levels::alpha`]. The bake tests alpha so
    /// ([`SoftwareTextures::bake_alpha_test`]); kept as the test's reference.
    #[cfg(test)]
    pub(crate) fn alpha_nearest_level(
        &self,
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        stride: usize,
    ) -> f32 {
        let level = if lod.f < 0.5 { lod.a } else { lod.b } as usize;
        bilinear(&self.0[level], uv, wrap, stride, stride - 1, f32::from) / 255.0
    }

    /// Trilinear tangent-space normal at `(u, v)` of a normal map's linear chain: each channel
    /// from 0..255 to −1..1 (not normalised; the frame's result is).
    fn normal(&self, uv: [f32; 2], lod: Trilinear, wrap: [Wrap; 2]) -> Vec3 {
        let at = |l: usize| {
            let c = |channel| bilinear(&self.0[l], uv, wrap, 4, channel, f32::from);
            Vec3::new(c(0), c(1), c(2))
        };
        let va = at(lod.a as usize);
        let v = if lod.f > 0.0 {
            va + (at(lod.b as usize) - va) * lod.f
        } else {
            va
        };
        v * (2.0 / 255.0) - Vec3::ONE
    }

    /// Trilinear linear RGB at `(u, v)` of an RGBA chain (sRGB decoded before filtering).
    pub(crate) fn rgb(
        &self,
        uv: [f32; 2],
        lod: Trilinear,
        wrap: [Wrap; 2],
        linear: &[f32; 256],
    ) -> Vec3 {
        let at = |l: usize| bilinear_rgb(&self.0[l], uv, wrap, linear);
        let va = at(lod.a as usize);
        if lod.f > 0.0 {
            va + (at(lod.b as usize) - va) * lod.f
        } else {
            va
        }
    }
}

/// The normal a tangent-space normal map gives (glTF `normalTexture`): `map` (components in
/// −1..1) in the frame of the interpolated `normal`, `tangent` (xyz; w ignored) made
/// orthogonal to it, and the bitangent `sign · N × T`. The interpolated normal alone where
/// the frame is degenerate.
#[inline]
fn mapped_normal(normal: Vec3, tangent: Vec4, sign: f32, map: Vec3) -> Vec3 {
    let n = normal.normalize_or_zero();
    let t = (tangent.truncate() - n * n.dot(tangent.truncate())).normalize_or_zero();
    if n == Vec3::ZERO || t == Vec3::ZERO {
        return normal;
    }
    let b = n.cross(t) * if sign < 0.0 { -1.0 } else { 1.0 };
    t * map.x + b * map.y + n * map.z
}

/// The samples `first..=last` (offsets from the row's first, at most `len`) of a row whose
/// weights start at `start` and change by `step` per sample that can be inside the triangle:
/// each weight's zero crossing (`−start · inv`, `inv` the step's reciprocal, 0 where the step
/// is too small to invert safely, which leaves that edge out) bounds the span, widened by
/// [`SPAN_SLACK`] samples against rounding (the samples are still tested one by one, so any
/// span holding the inside ones gives the same image). `None` when no sample can be.
#[inline]
fn row_span(start: [f32; 3], step: [f32; 3], inv: [f32; 3], len: usize) -> Option<(usize, usize)> {
    let (mut lo, mut hi) = (0.0f32, len as f32);
    for k in 0..3 {
        if inv[k] > 0.0 {
            lo = lo.max(-start[k] * inv[k] - SPAN_SLACK);
        } else if inv[k] < 0.0 {
            hi = hi.min(-start[k] * inv[k] + SPAN_SLACK);
        } else if step[k] == 0.0 && start[k] < 0.0 {
            return None;
        }
    }
    // The first sample at or after `lo` (a ceiling: `lo` is at least 0 here). Converted
    // through `i64`: one instruction, where a float's conversion to `usize` is a sequence
    // (x86-64 has no unsigned one before AVX-512); both are at least 0 where used.
    let first = lo as i64 as usize + usize::from((lo as i64 as f32) < lo);
    (lo <= hi && hi >= 0.0).then(|| (first, (hi as i64 as usize).min(len)))
}

/// How far a row's span reaches past its edges' computed zero crossings, in samples. The
/// crossing's rounding error is a few units in the last place of its offset (under 10⁻³
/// samples across the largest target) and a weight's own rounding moves the sample it turns
/// negative at by as little: a quarter sample is hundreds of times that.
const SPAN_SLACK: f32 = 0.25;

/// One sample row of a triangle: the samples `first..=last` it may cover (see [`row_span`])
/// and the weights along the row.
pub(crate) struct RowSpan {
    /// The sample row.
    pub(crate) y: usize,
    pub(crate) first: usize,
    pub(crate) last: usize,
    /// The sample the weights `start` are at.
    pub(crate) x0: usize,
    pub(crate) start: [f32; 3],
    /// The weights' change per sample along the row.
    pub(crate) step: [f32; 3],
}

impl RowSpan {
    /// The screen-space barycentric weights of sample `x` of the row.
    #[inline]
    pub(crate) fn weights_at(&self, x: usize) -> [f32; 3] {
        let k = (x - self.x0) as f32;
        [
            self.start[0] + self.step[0] * k,
            self.start[1] + self.step[1] * k,
            self.start[2] + self.step[2] * k,
        ]
    }
}

/// What every row of one triangle's walk shares: its weights' change per sample along a row
/// and their reciprocals.
pub(crate) struct RowWalk {
    step: [f32; 3],
    inv: [f32; 3],
}

impl Setup {
    /// The sample rows of `y0..y1` the triangle may cover, each with its span of samples.
    pub(crate) fn row_spans(&self, y0: usize, y1: usize) -> impl Iterator<Item = RowSpan> + '_ {
        let walk = self.row_walk();
        self.rows(y0, y1)
            .filter_map(move |y| self.row_span(&walk, y))
    }

    /// The sample rows of `y0..y1` within the triangle's bounds.
    #[inline]
    pub(crate) fn rows(&self, y0: usize, y1: usize) -> std::ops::Range<usize> {
        (self.min[1] as usize).max(y0)..(self.max[1] as usize + 1).min(y1)
    }

    /// What [`Setup::row_span`] needs of the triangle for every row.
    #[inline]
    pub(crate) fn row_walk(&self) -> RowWalk {
        let step = [
            -(self.y[2] - self.y[1]) * self.inv_area,
            -(self.y[0] - self.y[2]) * self.inv_area,
            -(self.y[1] - self.y[0]) * self.inv_area,
        ];
        // Reciprocals once a triangle rather than a division per edge and row; steps this small
        // bound nothing within an image.
        let inv = step.map(|s| if s.abs() >= 1e-30 { 1.0 / s } else { 0.0 });
        RowWalk { step, inv }
    }

    /// Sample row `y`'s span, `None` when the triangle covers no sample of it.
    #[inline(always)]
    pub(crate) fn row_span(&self, walk: &RowWalk, y: usize) -> Option<RowSpan> {
        let x0 = self.min[0] as usize;
        let start = self.weights(x0 as f32 + 0.5, y as f32 + 0.5);
        let (first, last) = row_span(start, walk.step, walk.inv, self.max[0] as usize - x0)?;
        Some(RowSpan {
            y,
            first: x0 + first,
            last: x0 + last,
            x0,
            start,
            step: walk.step,
        })
    }
}

/// What every band of one render shares.
struct Raster<'a> {
    scene: &'a DrawScene,
    textures: &'a SoftwareTextures,
    /// Per material, its alpha test.
    cutoffs: Vec<Option<AlphaCutoff>>,
    /// Coverage renders test eight samples at once ([`sample_lanes`]) where the machine can.
    lanes: bool,
    /// Per material, the octagons of its texture's levels where its alpha test can pass
    /// (coverage renders of alpha-tested textured materials): a triangle's rows are walked
    /// only where its texture coordinates lie within its levels' octagon.
    hulls: Vec<Option<HullLevels<'a>>>,
    /// Coverage renders skip a triangle's row where the samples within its bounds are all
    /// covered, before finding the row's span (most rows of the leaf cards inside a crown).
    covered_rows: bool,
    triangles: &'a [Setup],
    /// Per triangle, its shading (colour renders; empty otherwise).
    shading: &'a [Shading],
    /// Samples per row.
    width: usize,
    ss: usize,
    /// Coverage without colour, the mask alone wanted: once half of a pixel's samples are
    /// covered the pixel is (the resolve's rule) and its other samples are marked covered too,
    /// so the leaf cards drawn over it later skip them instead of alpha-testing each (the
    /// same mask; the covered-sample count is then not the true one).
    saturate: bool,
}

impl<'a> Raster<'a> {
    /// The raster of `bands` (set up from `scene` for a target `width` samples wide, `ss` a
    /// pixel side), with the `shortcuts` asked for: `saturate` when the mask alone is wanted
    /// (see [`Raster::saturate`]), `lanes` to test eight samples at once where the machine
    /// can, `hulls` to walk only the parts of triangles where the alpha test can pass,
    /// `covered_rows` to skip rows covered already.
    fn new(
        scene: &'a DrawScene,
        textures: &'a SoftwareTextures,
        bands: &'a Bands,
        width: usize,
        ss: usize,
        Shortcuts {
            saturate,
            lanes,
            hulls,
            covered_rows,
        }: Shortcuts,
    ) -> Raster<'a> {
        let cutoffs = AlphaCutoff::of_materials(scene);
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
            hulls,
            covered_rows: covered_rows && !textures.colour,
            lanes: lanes && sample_lanes::available(),
            triangles: &bands.triangles,
            shading: &bands.shading,
            width,
            ss,
            saturate: saturate && !textures.colour,
        }
    }

    /// Sample rows `y0..y1` (whole pixel rows) drawn with the triangles `bin`, resolved to
    /// pixels: coverage, and colour when the textures were prepared with it.
    fn band(&self, y0: usize, y1: usize, bin: &[u32]) -> Band {
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

    /// [`Raster::band`]'s work, for each instruction set it is compiled for.
    #[inline(always)]
    fn band_body(&self, y0: usize, y1: usize, bin: &[u32]) -> Band {
        let colour = self.textures.colour;
        let rows = y1 - y0;
        let n = rows * self.width;
        // Coverage as one bit a sample, 64 to a word: runs of covered samples are skipped a
        // word at a time (the crown's inside is covered many times over).
        let words = self.width.div_ceil(64);
        let mut covered = vec![0u64; rows * words];
        let mut depth = if colour {
            vec![f32::INFINITY; n]
        } else {
            Vec::new()
        };
        let mut rgb = if colour {
            vec![Vec3::ZERO; n]
        } else {
            Vec::new()
        };
        // Per pixel of the band, its covered samples (when saturating).
        let mut pixel_count = if self.saturate {
            vec![0u32; (rows / self.ss) * (self.width / self.ss)]
        } else {
            Vec::new()
        };
        let linear = &*SRGB_LINEAR;
        let light = Vec3::from(LIGHT_DIRECTION);
        let stride = if colour { 4 } else { 1 };
        for &ti in bin {
            let t = &self.triangles[ti as usize];
            // The words of a row that the triangle's bounds reach, when they are one or two:
            // a row whose bounds are covered already is skipped before its span is found, and
            // a triangle with no other row is not drawn (nor its mip level found).
            let (bx0, bx1) = (t.min[0] as usize, t.max[0] as usize);
            let bounds_words = (self.covered_rows && bx1 / 64 - bx0 / 64 <= 1).then(|| {
                let (w0, w1) = (bx0 / 64, bx1 / 64);
                let (m0, m1) = (u64::MAX << (bx0 % 64), u64::MAX >> (63 - bx1 % 64));
                if w0 == w1 {
                    [(w0, m0 & m1), (w1, m0 & m1)]
                } else {
                    [(w0, m0), (w1, m1)]
                }
            });
            let row_covered = |covered: &[u64], sy: usize| {
                let row_word = (sy - y0) * words;
                bounds_words
                    .as_ref()
                    .is_some_and(|bw| bw.iter().all(|&(w, m)| covered[row_word + w] & m == m))
            };
            let rows = t.rows(y0, y1);
            let Some(first_row) = rows.clone().find(|&sy| !row_covered(&covered, sy)) else {
                continue;
            };
            let t = &if colour { *t } else { self.with_lod(t) };
            // Colour renders' triangles have their shading; coverage renders read none.
            let shading = self.shading.get(ti as usize);
            let material = &self.scene.materials[t.material as usize];
            let cutoff = self.cutoffs[t.material as usize].as_ref();
            let texture = material.texture.map(|i| &self.textures.textures[i]);
            let bounds = material
                .texture
                // A colour render's levels are RGBA: the alpha-only tables are not theirs.
                .filter(|_| !colour)
                .and_then(|i| self.textures.alpha_bounds.get(i))
                .map(Vec::as_slice);
            let normal_map = material
                .normal_texture
                .filter(|_| shading.is_some_and(|s| s.tq.is_some()))
                .map(|i| &self.textures.normal_maps[i]);
            let lanes = if self.lanes && !colour {
                self.triangle_lanes(t)
            } else {
                None
            };
            let hull = match self.triangle_hull(t) {
                TriangleHull::Empty => continue,
                TriangleHull::Rows(rows) => Some(rows),
                TriangleHull::Unbounded => None,
            };
            let walk = t.row_walk();
            for sy in first_row..rows.end {
                let row = (sy - y0) * self.width;
                let row_word = (sy - y0) * words;
                if row_covered(&covered, sy) {
                    continue;
                }
                let Some(span) = t.row_span(&walk, sy) else {
                    continue;
                };
                let Some((first, last)) = narrowed(hull.as_ref(), sy, span.first, span.last) else {
                    continue;
                };
                if let Some(lanes) = &lanes {
                    // Eight samples at a time from the span's first: their coverage bits are
                    // read across the word boundary where they straddle one.
                    let mut x = first;
                    while x <= last {
                        let (word, shift) = (x / 64, x % 64);
                        let mut bits = covered[row_word + word] >> shift;
                        if shift > 56 && word + 1 < words {
                            bits |= covered[row_word + word + 1] << (64 - shift);
                        }
                        let mut todo = !bits as u32 & 0xff;
                        if last < x + 7 {
                            todo &= 0xff >> (x + 7 - last);
                        }
                        if todo != 0 {
                            let k0 = x as i32 - span.x0 as i32;
                            // SAFETY: `self.lanes` holds only where `sample_lanes::available`,
                            // and a table test's table is an `AlphaBounds` one (padded).
                            let r = unsafe { lanes.test(k0, span.start, span.step) };
                            let mut hits = r.passing(todo, |uv| {
                                let (Some(l), Some(bounds), Some(cutoff)) =
                                    (texture, bounds, cutoff)
                                else {
                                    return false;
                                };
                                l.alpha_test(bounds, uv, t.lod, material.wrap, cutoff)
                            });
                            while hits != 0 {
                                let i = hits.trailing_zeros() as usize;
                                hits &= hits - 1;
                                self.cover(&mut covered, &mut pixel_count, sy - y0, x + i);
                            }
                        }
                        x += 8;
                    }
                    continue;
                }
                let (mut sx, end) = (first, last);
                while sx <= end {
                    let word = sx / 64;
                    let run_end = end.min(word * 64 + 63);
                    let bits = run_end - sx + 1;
                    let run = if bits == 64 {
                        u64::MAX
                    } else {
                        ((1u64 << bits) - 1) << (sx % 64)
                    };
                    // Covered samples are skipped unless colour is drawn (then depth decides).
                    let mut todo = if colour {
                        run
                    } else {
                        run & !covered[row_word + word]
                    };
                    while todo != 0 {
                        let bit = todo.trailing_zeros() as usize;
                        todo &= todo - 1;
                        // A pixel decided since `todo` was read (saturation) needs no test.
                        if self.saturate && covered[row_word + word] >> bit & 1 == 1 {
                            continue;
                        }
                        let x = word * 64 + bit;
                        let b = span.weights_at(x);
                        if b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0 {
                            continue;
                        }
                        let s = row + x;
                        let z = b[0] * t.z[0] + b[1] * t.z[1] + b[2] * t.z[2];
                        // Depth test `Less` (z is finite: the triangle was clipped to 0..1).
                        if colour && z >= depth[s] {
                            continue;
                        }
                        let (uv, q) = t.uv(b);
                        if let Some(cutoff) = cutoff {
                            let pass = match (texture, bounds) {
                                (Some(l), Some(bounds)) => {
                                    l.alpha_test(bounds, uv, t.lod, material.wrap, cutoff)
                                }
                                _ => cutoff
                                    .passes(texture.map_or(1.0, |l| {
                                        l.alpha(uv, t.lod, material.wrap, stride)
                                    })),
                            };
                            if !pass {
                                continue;
                            }
                        }
                        self.cover(&mut covered, &mut pixel_count, sy - y0, x);
                        if colour {
                            depth[s] = z;
                            let base = Vec3::new(
                                material.base_color[0],
                                material.base_color[1],
                                material.base_color[2],
                            );
                            let texel = texture
                                .map_or(Vec3::ONE, |l| l.rgb(uv, t.lod, material.wrap, linear));
                            let mut shade = 1.0;
                            if let Some(sh) = shading.filter(|_| t.lit) {
                                let mut normal =
                                    (b[0] * sh.nq[0] + b[1] * sh.nq[1] + b[2] * sh.nq[2]) / q;
                                if let (Some(tq), Some(map)) = (sh.tq, normal_map) {
                                    normal = mapped_normal(
                                        normal,
                                        (b[0] * tq[0] + b[1] * tq[1] + b[2] * tq[2]) / q,
                                        tq[0].w,
                                        map.normal(uv, sh.normal_lod, material.wrap),
                                    );
                                }
                                if normal.length_squared() > 1e-12 {
                                    let n = normal.normalize();
                                    let n = if t.back { -n } else { n };
                                    shade = self.textures.lighting.shade(n, light);
                                }
                            }
                            rgb[s] = (texel * base * shade).clamp(Vec3::ZERO, Vec3::ONE);
                        }
                    }
                    sx = run_end + 1;
                }
            }
        }
        let (mask, colour) = self.resolve(rows, &covered, &rgb);
        Band {
            mask,
            colour,
            covered_samples: covered.iter().map(|w| u64::from(w.count_ones())).sum(),
        }
    }

    /// Marks sample `x` of the band's sample row `row` covered (`covered`: the band's bits, 64
    /// to a word) and, when saturating, counts it for its pixel (`pixel_count`, the band's),
    /// marking the pixel's other samples once half of them are.
    #[inline(always)]
    fn cover(&self, covered: &mut [u64], pixel_count: &mut [u32], row: usize, x: usize) {
        let words = self.width.div_ceil(64);
        covered[row * words + x / 64] |= 1 << (x % 64);
        if self.saturate {
            let ss = self.ss;
            let (py, px) = (row / ss, x / ss);
            let count = &mut pixel_count[py * (self.width / ss) + px];
            *count += 1;
            // `2·count ≥ ss²`, the resolve's rule, first holds at this count.
            if *count as usize == (ss * ss).div_ceil(2) {
                for r in py * ss..(py + 1) * ss {
                    for c in px * ss..(px + 1) * ss {
                        covered[r * words + c / 64] |= 1 << (c % 64);
                    }
                }
            }
        }
    }

    /// What the octagon of coverage render triangle `t`'s levels (`t` with its mip levels,
    /// [`Raster::with_lod`]) does to it: a trilinear test passes only where one of its two
    /// levels' can.
    fn triangle_hull(&self, t: &Setup) -> TriangleHull {
        let Some(levels) = &self.hulls[t.material as usize] else {
            return TriangleHull::Unbounded;
        };
        let (a, b) = (t.lod.a as usize, t.lod.b as usize);
        let octagon = if t.lod.f > 0.0 {
            levels.level(a).union(levels.level(b))
        } else {
            levels.level(a)
        };
        octagon.rows(t)
    }

    /// Coverage render triangle `t` with its texture's mip levels (set up without them:
    /// [`setup_triangle`]).
    #[inline]
    fn with_lod(&self, t: &Setup) -> Setup {
        let mut t = *t;
        let material = &self.scene.materials[t.material as usize];
        if let Some(levels) = material.texture.map(|i| &self.textures.textures[i]) {
            t.lod = levels.pair(centroid_lod(&t, levels));
        }
        t
    }

    /// A coverage render's eight-sample test of triangle `t`, when its material's alpha test
    /// is one the lanes decide as the scalar path does: none, or a bounds table (the one
    /// [`Levels::alpha_test`] reads first for the triangle's levels) and the filter behind it.
    /// `None` sends the triangle to the scalar loop.
    fn triangle_lanes(&self, t: &Setup) -> Option<TriangleLanes<'_>> {
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

    /// Pixels of a band of `rows` sample rows (`covered`: bits, 64 to a word, rows padded to
    /// whole words): covered when at least half of their samples are, colour the mean of the
    /// covered samples'.
    fn resolve(&self, rows: usize, covered: &[u64], rgb: &[Vec3]) -> (Vec<bool>, Vec<[f32; 3]>) {
        let ss = self.ss;
        let words = self.width.div_ceil(64);
        let (w, h) = (self.width / ss, rows / ss);
        let mut mask = Vec::with_capacity(w * h);
        let mut colour = Vec::with_capacity(if rgb.is_empty() { 0 } else { w * h });
        for py in 0..h {
            for px in 0..w {
                let (mut count, mut sum) = (0usize, Vec3::ZERO);
                for dy in 0..ss {
                    let y = py * ss + dy;
                    for x in px * ss..(px + 1) * ss {
                        if covered[y * words + x / 64] >> (x % 64) & 1 == 1 {
                            count += 1;
                            if !rgb.is_empty() {
                                sum += rgb[y * self.width + x];
                            }
                        }
                    }
                }
                mask.push(2 * count >= ss * ss);
                if !rgb.is_empty() {
                    let mean = if count > 0 {
                        sum / count as f32
                    } else {
                        Vec3::ZERO
                    };
                    colour.push(mean.to_array());
                }
            }
        }
        (mask, colour)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};
    use crate::scene::DrawMesh;

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

    /// A quad over NDC `[x0, x1] × [-1, 1]` at depth `z`, counter-clockwise (front) unless
    /// `flip`, with texture coordinates over the whole texture.
    fn quad(x0: f32, x1: f32, z: f32, flip: bool, material: usize) -> DrawMesh {
        let indices = if flip {
            vec![0, 2, 1, 0, 3, 2]
        } else {
            vec![0, 1, 2, 0, 2, 3]
        };
        DrawMesh {
            positions: vec![[x0, -1.0, z], [x1, -1.0, z], [x1, 1.0, z], [x0, 1.0, z]],
            normals: None,
            tangents: None,
            uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
            indices,
            material,
        }
    }

    fn render(scene: &DrawScene, colour: bool, ss: u32) -> CoverageImage {
        let textures = SoftwareTextures::new(scene, colour).expect("textures");
        render_coverage(scene, &textures, Mat4::IDENTITY, 40, 30, ss).expect("render")
    }

    fn count(image: &CoverageImage) -> usize {
        image.covered.iter().filter(|c| **c).count()
    }

    #[test]
    fn a_full_screen_quad_covers_every_pixel_and_a_half_one_half() {
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])],
            textures: vec![],
        };
        let full = render(&scene, true, 2);
        assert_eq!((full.width, full.height, count(&full)), (40, 30, 1200));
        assert!(full.colour.iter().all(|c| *c == [1.0, 0.0, 0.0]));
        scene.meshes = vec![quad(-1.0, 0.0, 0.5, false, 0)];
        let half = render(&scene, false, 4);
        assert_eq!(count(&half), 600);
        assert!(half.colour.is_empty(), "no colour asked for");
        // The left half, row by row.
        assert!((0..30).all(|y| (0..40).all(|x| half.covered[y * 40 + x] == (x < 20))));
    }

    #[test]
    fn a_normal_map_turns_the_shading_normal_in_the_tangent_frame() {
        // A white quad facing +z (normal +z, tangent +x, bitangent +y), its map tilting the
        // normal by 37° towards +y: shaded with the tilted normal, and with the tangent's w
        // negative (bitangent −y) tilted the other way.
        let tilted = Vec3::new(0.0, 0.6, 0.8);
        let texel = [
            128u8,
            (255.0 * (0.6 + 1.0) / 2.0) as u8,
            (255.0 * 1.8 / 2.0) as u8,
            255,
        ];
        let light = Vec3::from(LIGHT_DIRECTION);
        let shade_of = |sign: Option<f32>| {
            let mut mesh = quad(-1.0, 1.0, 0.5, false, 0);
            mesh.normals = Some(vec![[0.0, 0.0, 1.0]; 4]);
            mesh.tangents = sign.map(|w| vec![[1.0, 0.0, 0.0, w]; 4]);
            let scene = DrawScene {
                meshes: vec![mesh],
                materials: vec![DrawMaterial {
                    normal_texture: Some(0),
                    ..DrawMaterial::opaque([1.0; 4])
                }],
                textures: vec![DrawTexture {
                    width: 4,
                    height: 4,
                    rgba: texel.repeat(16),
                }],
            };
            render(&scene, true, 1).colour[600][0]
        };
        let expect = |n: Vec3| 0.6 + 0.4 * n.normalize().dot(light).abs();
        let decoded = Vec3::new(
            f32::from(texel[0]),
            f32::from(texel[1]),
            f32::from(texel[2]),
        ) * (2.0 / 255.0)
            - Vec3::ONE;
        assert!((decoded - tilted).length() < 0.01);
        assert!((shade_of(Some(1.0)) - expect(decoded)).abs() < 1e-4);
        let mirrored = Vec3::new(decoded.x, -decoded.y, decoded.z);
        assert!((shade_of(Some(-1.0)) - expect(mirrored)).abs() < 1e-4);
        // Without tangents the map does not apply: the vertex normal's shade, visibly other.
        assert!((shade_of(None) - expect(Vec3::Z)).abs() < 1e-4);
        assert!((expect(decoded) - expect(Vec3::Z)).abs() > 0.1);
    }

    #[test]
    fn lambert_lights_the_side_facing_the_viewer() {
        // A double-sided quad: Lambert lights the normal of the side drawn (a back face's
        // normal flipped, as GPUs do for double-sided materials), two-sided lighting ignores
        // the normal's sign.
        let light = Vec3::from(LIGHT_DIRECTION);
        let shade = |flip: bool, normal: [f32; 3], lighting: Lighting| {
            let mut mesh = quad(-1.0, 1.0, 0.5, flip, 0);
            mesh.normals = Some(vec![normal; 4]);
            let scene = DrawScene {
                meshes: vec![mesh],
                materials: vec![DrawMaterial {
                    double_sided: true,
                    ..DrawMaterial::opaque([1.0; 4])
                }],
                textures: vec![],
            };
            let textures = SoftwareTextures::new(&scene, true)
                .expect("textures")
                .with_lighting(lighting);
            render_coverage(&scene, &textures, Mat4::IDENTITY, 40, 30, 1)
                .expect("render")
                .colour[600][0]
        };
        let lit = 0.3 + 0.7 * light.z.max(0.0);
        // Front face with its normal towards the light's side, and a back face whose stored
        // normal points away: both show the lit side.
        assert!((shade(false, [0.0, 0.0, 1.0], Lighting::Lambert) - lit).abs() < 1e-4);
        assert!((shade(true, [0.0, 0.0, -1.0], Lighting::Lambert) - lit).abs() < 1e-4);
        // A front face whose normal points away from the viewer and the light: ambient only.
        assert!((shade(false, [0.0, 0.0, -1.0], Lighting::Lambert) - 0.3).abs() < 1e-4);
        let two_sided = 0.6 + 0.4 * light.z.abs();
        assert!((shade(false, [0.0, 0.0, -1.0], Lighting::TwoSided) - two_sided).abs() < 1e-4);
    }

    #[test]
    fn depth_complexity_counts_every_layer_drawn() {
        // Three full-screen layers, and a half-screen fourth: 3.5 fragments per covered sample.
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.2, false, 0),
                quad(-1.0, 1.0, 0.4, false, 0),
                quad(-1.0, 1.0, 0.6, false, 0),
                quad(-1.0, 0.0, 0.8, false, 0),
            ],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        let d = depth_complexity(&scene, &textures, Mat4::IDENTITY, 40, 30, 2).expect("count");
        assert!((d - 3.5).abs() < 1e-6, "{d}");
        let empty = DrawScene {
            meshes: vec![],
            ..scene.clone()
        };
        let d = depth_complexity(&empty, &textures, Mat4::IDENTITY, 40, 30, 2).expect("count");
        assert_eq!(d, 0.0);
    }

    #[test]
    fn back_faces_are_culled_unless_double_sided() {
        let mut scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, true, 0)],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        assert_eq!(count(&render(&scene, false, 1)), 0);
        scene.materials[0].double_sided = true;
        assert_eq!(count(&render(&scene, false, 1)), 1200);
    }

    #[test]
    fn the_alpha_test_keeps_the_opaque_texels_and_depth_picks_the_nearest_colour() {
        // A 64×2 texture, opaque on its right half; mip-mapped, as the GPU path draws it.
        let rgba: Vec<u8> = (0..2)
            .flat_map(|_| (0..64).flat_map(|x| [0, 255, 0, if x >= 32 { 255 } else { 0 }]))
            .collect();
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.5, false, 0),
                quad(-1.0, 1.0, 0.7, false, 1),
            ],
            materials: vec![
                DrawMaterial {
                    texture: Some(0),
                    alpha_cutoff: Some(0.5),
                    ..DrawMaterial::opaque([1.0; 4])
                },
                DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0]),
            ],
            textures: vec![DrawTexture {
                width: 64,
                height: 2,
                rgba,
            }],
        };
        let leaf_only = DrawScene {
            meshes: scene.meshes[..1].to_vec(),
            ..scene.clone()
        };
        assert_eq!(count(&render(&leaf_only, false, 4)), 600);
        // Behind the leaf, a blue wall: green where the leaf is opaque, blue elsewhere.
        let both = render(&scene, true, 1);
        assert_eq!(count(&both), 1200);
        assert_eq!(both.colour[5], [0.0, 0.0, 1.0]);
        assert_eq!(both.colour[35], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn geometry_behind_the_near_plane_is_clipped() {
        // Half of the quad's depth range is in front of the near plane (z ≥ 0).
        let mut mesh = quad(-1.0, 1.0, 0.5, false, 0);
        mesh.positions = vec![
            [-1.0, -1.0, -0.5],
            [1.0, -1.0, -0.5],
            [1.0, 1.0, 0.5],
            [-1.0, 1.0, 0.5],
        ];
        let scene = DrawScene {
            meshes: vec![mesh],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        // z crosses 0 at y = 0: the upper half stays.
        let image = render(&scene, false, 2);
        assert_eq!(count(&image), 600);
        assert!(image.covered[0] && !image.covered[1199]);
    }

    #[test]
    fn bad_sizes_and_unprepared_textures_are_errors() {
        let scene = DrawScene {
            meshes: vec![quad(-1.0, 1.0, 0.5, false, 0)],
            materials: vec![DrawMaterial::opaque([1.0; 4])],
            textures: vec![],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        assert!(render_coverage(&scene, &textures, Mat4::IDENTITY, 0, 10, 1).is_err());
        assert!(render_coverage(&scene, &textures, Mat4::IDENTITY, 40_000, 10, 1).is_err());
        assert!(render_coverage(&scene, &textures, Mat4::NAN, 10, 10, 1).is_err());
        let mut textured = scene.clone();
        textured.textures.push(DrawTexture {
            width: 1,
            height: 1,
            rgba: vec![255; 4],
        });
        assert!(render_coverage(&textured, &textures, Mat4::IDENTITY, 10, 10, 1).is_err());
        textured.textures[0].rgba.pop();
        assert!(SoftwareTextures::new(&textured, false).is_err());
    }

    /// A perspective view of `cards` random leaf cards (random sizes, so that many mip levels
    /// and trilinear blends are drawn; texture coordinates reaching past the edges under each
    /// wrap mode; alpha tests with several cutoffs and scales, and an opaque material).
    fn random_cards(cards: usize, seed: u64) -> (DrawScene, Mat4) {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (w, h, alpha) = leaf_alpha();
        let rgba = alpha.iter().flat_map(|&a| [40, 160, 30, a]).collect();
        let wraps = [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat];
        let mut materials: Vec<DrawMaterial> = (0..9)
            .map(|m| DrawMaterial {
                texture: Some(0),
                alpha_cutoff: Some([0.3, 0.5, 0.8][m % 3]),
                base_color: [1.0, 1.0, 1.0, [1.0, 0.7, 1.3][m / 3]],
                double_sided: true,
                wrap: [wraps[m % 3], wraps[m / 3]],
                ..DrawMaterial::opaque([1.0; 4])
            })
            .collect();
        materials.push(DrawMaterial::opaque([1.0; 4]));
        let meshes = (0..cards)
            .map(|i| {
                let centre = Vec3::new(next() * 8.0 - 4.0, next() * 6.0 - 3.0, next() * 9.0);
                let size = 0.02 + next() * next() * 2.0;
                let (a, b) = (next() * 6.3, next() * 6.3);
                let right = Vec3::new(a.cos(), a.sin() * b.cos(), a.sin() * b.sin()) * size;
                let up = right.any_orthonormal_vector() * size;
                let corners = [-right - up, right - up, right + up, -right + up]
                    .map(|c| (centre + c).to_array());
                // Mostly the unit square, sometimes shifted or scaled past it.
                let (off, span) = if i % 4 == 0 {
                    (next() * 2.0 - 1.0, 0.5 + next() * 2.0)
                } else {
                    (0.0, 1.0)
                };
                DrawMesh {
                    positions: corners.to_vec(),
                    normals: None,
                    tangents: None,
                    uvs: Some(
                        [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
                            .map(|[u, v]| [off + u * span, off + v * span])
                            .to_vec(),
                    ),
                    indices: vec![0, 1, 2, 0, 2, 3],
                    material: i % materials.len(),
                }
            })
            .collect();
        let scene = DrawScene {
            meshes,
            materials,
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba,
            }],
        };
        let (min, max) = scene.bounds().expect("cards");
        let camera = Camera::framing(
            min,
            max,
            20.0,
            10.0,
            Projection::Perspective { fov_y_deg: 50.0 },
        );
        let view_proj = camera.view_proj_for_bounds(4.0 / 3.0, min, max);
        (scene, view_proj)
    }

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
                        hulled[match raster.triangle_hull(&raster.with_lod(t)) {
                            TriangleHull::Unbounded => 0,
                            TriangleHull::Rows(_) => 1,
                            TriangleHull::Empty => 2,
                        }] += 1;
                    }
                }
                for saturate in [true, false] {
                    let draw = |lanes, hulls| {
                        let shortcuts = Shortcuts {
                            saturate,
                            lanes,
                            hulls,
                            covered_rows: lanes || hulls,
                        };
                        rasterise(&scene, &textures, view_proj, [w, h, ss], shortcuts)
                            .expect("render")
                    };
                    let plain = draw(false, false);
                    let what = format!("{cards} cards, {w}x{h}, {ss}x, saturate {saturate}");
                    assert!(count(&plain.0) > 0, "{what}: nothing drawn");
                    for (lanes, hulls) in [(false, true), (true, false), (true, true)] {
                        if lanes && !lanes_available {
                            continue;
                        }
                        let other = draw(lanes, hulls);
                        let what = format!("{what}, lanes {lanes}, octagons {hulls}");
                        let differ = (plain.0.covered.iter())
                            .zip(&other.0.covered)
                            .filter(|(a, b)| a != b)
                            .count();
                        assert_eq!(differ, 0, "{what}: pixels that differ");
                        assert_eq!(plain.1, other.1, "{what}: area");
                        assert_eq!(plain.2, other.2, "{what}: covered samples");
                    }
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

    /// A 37×20 alpha: a disc of opaque texels with a soft rim, and noise — every kind of
    /// footprint (a leaf's hard and soft edges).
    fn leaf_alpha() -> (u32, u32, Vec<u8>) {
        let (w, h) = (37u32, 20u32);
        let alpha = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - 18.0, (i / w) as f32 - 10.0);
                let r = (x * x + y * y).sqrt();
                let noise = (i.wrapping_mul(2_654_435_761) >> 27) as f32;
                (255.0 - (r - 6.0).max(0.0) * 40.0 + noise).clamp(0.0, 255.0) as u8
            })
            .collect();
        (w, h, alpha)
    }

    /// Asserts that `test` (uv, level pair, wrap, `[scale, cutoff]`) answers as the `filtered`
    /// alpha does, at level pairs of `levels` from `lods`, inside and across the edges under
    /// each wrap, at cutoffs and scales around the alphas, many of them soft (between the
    /// extremes: not only footprints the bounds settle outright).
    fn assert_alpha_tests_match(
        levels: &Levels,
        lods: [f32; 6],
        filtered: impl Fn([f32; 2], Trilinear, Wrap) -> f32,
        test: impl Fn([f32; 2], Trilinear, Wrap, [f32; 2]) -> bool,
    ) {
        let mut soft = 0;
        let mut tests = 0;
        for wrap in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
            for lod in lods {
                let pair = levels.pair(lod);
                for k in 0..4000u32 {
                    let uv = [(k % 80) as f32 / 53.0 - 0.3, (k / 80) as f32 / 37.0 - 0.2];
                    let alpha = filtered(uv, pair, wrap);
                    for (scale, cutoff) in
                        [(1.0, 0.5), (0.8, 0.3), (1.0, 1.0), (1.0, 0.0), (-0.5, -0.2)]
                    {
                        let expected = passes_cutoff(alpha * scale, cutoff);
                        let got = test(uv, pair, wrap, [scale, cutoff]);
                        assert_eq!(got, expected, "{wrap:?} lod {lod} uv {uv:?} {cutoff}");
                        tests += 1;
                        soft += usize::from(alpha > 0.0 && alpha < 1.0);
                    }
                }
            }
        }
        assert!(soft > tests / 20, "{soft} of {tests}");
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

    /// An affine triangle's texture coordinates summed without a division are the divided
    /// ones but for rounding; a perspective triangle has no affine corners.
    #[test]
    fn affine_texture_coordinates_are_the_divided_ones() {
        let setup = |q: [f32; 3]| Setup {
            x: [1.0, 9.0, 3.0],
            y: [2.0, 4.0, 11.0],
            z: [0.0; 3],
            q,
            uq: [[0.1, 0.9], [0.7, 0.2], [0.4, 0.5]].map(|[u, v]| [u * q[0], v * q[0]]),
            inv_area: 1.0 / 68.0,
            material: 0,
            lit: false,
            back: false,
            lod: Trilinear::default(),
            min: [1, 2],
            max: [8, 10],
        };
        let t = setup([0.5; 3]);
        let corners = t.affine_corners().expect("affine");
        assert_eq!(corners[1], [0.7, 0.2]);
        for (px, py) in [(2.5, 3.5), (4.5, 6.5), (3.0, 9.0), (7.5, 4.5)] {
            let b = t.weights(px, py);
            let (divided, _) = t.uv(b);
            let summed = affine_uv(&corners, b);
            for k in 0..2 {
                assert!(
                    (divided[k] - summed[k]).abs() < 1e-6,
                    "{divided:?} {summed:?}"
                );
            }
        }
        assert!(setup([0.5, 0.25, 0.5]).affine_corners().is_none());
    }

    /// A row's span holds every sample the weights put inside the triangle, and at most one
    /// more at either end, for triangles of every shape and size (slivers, nearly flat rows,
    /// far outside the target).
    #[test]
    fn row_spans_hold_every_inside_sample() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |range: f32| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 * range
        };
        let (sw, sh) = (96.0f32, 64.0f32);
        let (mut inside, mut tight) = (0, 0);
        for k in 0..3000 {
            let scale = [2.0, 30.0, 400.0][k % 3];
            let mut x = [0.0f32; 3].map(|_| next(scale) - scale / 2.0 + 48.0);
            let mut y = [0.0f32; 3].map(|_| next(scale) - scale / 2.0 + 32.0);
            if k % 7 == 0 {
                y[1] = y[0] + 1e-3; // a nearly flat edge
            }
            let area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
            if area.abs() < 1e-6 {
                continue;
            }
            if area < 0.0 {
                x.swap(1, 2);
                y.swap(1, 2);
            }
            let min = [
                ((x.iter().copied().fold(f32::INFINITY, f32::min) - 0.5).ceil()).max(0.0),
                ((y.iter().copied().fold(f32::INFINITY, f32::min) - 0.5).ceil()).max(0.0),
            ];
            let max = [
                ((x.iter().copied().fold(f32::NEG_INFINITY, f32::max) - 0.5).floor()).min(sw - 1.0),
                ((y.iter().copied().fold(f32::NEG_INFINITY, f32::max) - 0.5).floor()).min(sh - 1.0),
            ];
            if min[0] > max[0] || min[1] > max[1] {
                continue;
            }
            let t = Setup {
                x,
                y,
                z: [0.0; 3],
                q: [1.0; 3],
                uq: [[0.0; 2]; 3],
                inv_area: 1.0 / area.abs(),
                material: 0,
                lit: false,
                back: false,
                lod: Trilinear::default(),
                min: [min[0] as i32, min[1] as i32],
                max: [max[0] as i32, max[1] as i32],
            };
            let spans: Vec<RowSpan> = t.row_spans(0, sh as usize).collect();
            for sy in min[1] as usize..=max[1] as usize {
                let span = spans.iter().find(|s| s.y == sy);
                let mut held = None::<(usize, usize)>;
                for sx in min[0] as usize..=max[0] as usize {
                    // Inside by the weights from scratch, or as a span steps them along the
                    // row (which the renderers test).
                    let b = t.weights(sx as f32 + 0.5, sy as f32 + 0.5);
                    let stepped = span.map(|s| {
                        let k = sx as f32 - s.x0 as f32;
                        [0, 1, 2].map(|e| s.start[e] + s.step[e] * k)
                    });
                    let all = |b: [f32; 3]| b.iter().all(|&w| w >= 0.0);
                    if all(b) || stepped.is_some_and(all) {
                        inside += 1;
                        assert!(
                            span.is_some_and(|s| (s.first..=s.last).contains(&sx)),
                            "triangle {x:?} {y:?}: sample ({sx}, {sy}) outside its row's span"
                        );
                        held = Some(held.map_or((sx, sx), |(a, _)| (a, sx)));
                    }
                }
                // Tight: at most a sample past the inside ones at either end.
                if let (Some(s), Some((a, b))) = (span, held) {
                    assert!(
                        s.first + 1 >= a && s.last <= b + 1,
                        "triangle {x:?} {y:?}: row {sy} spans {}..={} for {a}..={b}",
                        s.first,
                        s.last
                    );
                    tight += 1;
                }
            }
        }
        assert!(inside > 100_000, "{inside} inside samples");
        assert!(tight > 10_000, "{tight} rows");
    }

    /// The bake's alpha test decided from the footprints' bounds answers as filtering the
    /// nearer level does.
    #[test]
    fn bake_alpha_test_matches_the_nearer_levels_filter() {
        let (w, h, alpha) = leaf_alpha();
        let rgba = alpha.iter().flat_map(|&a| [30, 200, 90, a]).collect();
        let prepared = SoftwareTextures::for_bake(&[DrawTexture {
            width: w,
            height: h,
            rgba,
        }])
        .expect("textures");
        let levels = &prepared.textures[0];
        assert_alpha_tests_match(
            levels,
            [0.0, 0.3, 0.7, 1.7, 2.5, 9.0],
            |uv, pair, wrap| levels.alpha_nearest_level(uv, pair, [wrap; 2], 4),
            |uv, pair, wrap, [scale, cutoff]| {
                prepared.bake_alpha_test(0, uv, pair, [wrap; 2], &AlphaCutoff::new(scale, cutoff))
            },
        );
    }

    /// The bake's colour from levels decoded beforehand is the decoding filter's to the bit,
    /// inside and across the edges under each wrap, at single levels and blends; a level over
    /// the decoded size limit is filtered from its bytes.
    #[test]
    fn bake_colour_from_decoded_levels_is_the_filters() {
        let (w, h, alpha) = leaf_alpha();
        let rgba: Vec<u8> = (alpha.iter().enumerate())
            .flat_map(|(i, &a)| {
                let n = (i as u32).wrapping_mul(2_654_435_761);
                [(n >> 24) as u8, (n >> 16) as u8, (n >> 8) as u8, a]
            })
            .collect();
        let texture = DrawTexture {
            width: w,
            height: h,
            rgba,
        };
        let prepared = SoftwareTextures::for_bake(std::slice::from_ref(&texture)).expect("tex");
        let levels = &prepared.textures[0];
        // Decoded on first use.
        assert!(prepared.bake_linear[0].iter().all(|l| l.get().is_none()));
        let linear = *SRGB_LINEAR;
        let mut undecoded = prepared.clone();
        undecoded.bake_linear[0][0] = std::sync::OnceLock::from(None);
        let mut compared = 0;
        for wrap in [Wrap::Repeat, Wrap::ClampToEdge, Wrap::MirroredRepeat] {
            for lod in [0.0, 0.3, 0.7, 1.7, 2.5, 9.0] {
                let pair = levels.pair(lod);
                for k in 0..4000u32 {
                    let uv = [(k % 80) as f32 / 53.0 - 0.3, (k / 80) as f32 / 37.0 - 0.2];
                    let expected = levels.rgb(uv, pair, [wrap; 2], &linear);
                    for p in [&prepared, &undecoded] {
                        let got = p.bake_rgb(0, uv, pair, [wrap; 2], &linear);
                        assert_eq!(
                            got.to_array().map(f32::to_bits),
                            expected.to_array().map(f32::to_bits)
                        );
                    }
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 3 * 6 * 4000);
        let decoded =
            |l: &std::sync::OnceLock<Option<LinearLevel>>| l.get().is_some_and(Option::is_some);
        assert!(prepared.bake_linear[0][..4].iter().all(decoded));
        let big = DrawTexture {
            width: 1025,
            height: 1024,
            rgba: vec![128; 1025 * 1024 * 4],
        };
        let prepared = SoftwareTextures::for_bake(&[big]).expect("big");
        let wrap = [Wrap::Repeat; 2];
        for lod in [0.0, 1.0] {
            let pair = prepared.textures[0].pair(lod);
            let got = prepared.bake_rgb(0, [0.3, 0.6], pair, wrap, &linear);
            assert_eq!(got, Vec3::splat(linear[128]));
        }
        assert!(
            prepared.bake_linear[0][0]
                .get()
                .is_some_and(Option::is_none)
        );
        assert!(
            prepared.bake_linear[0][1]
                .get()
                .is_some_and(Option::is_some)
        );
    }

    /// Textures prepared for the bake (RGBA levels with their alpha's bounds) draw a colour
    /// render exactly as the colour preparation does: the coverage renders' alpha-only bounds
    /// never apply to RGBA levels.
    #[test]
    fn bake_prepared_textures_draw_colour_renders_unchanged() {
        let (w, h, alpha) = leaf_alpha();
        let scene = DrawScene {
            meshes: vec![quad(-0.9, 0.8, 0.4, false, 0)],
            materials: vec![DrawMaterial {
                texture: Some(0),
                alpha_cutoff: Some(0.5),
                ..DrawMaterial::opaque([1.0; 4])
            }],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba: alpha.iter().flat_map(|&a| [40, 180, 70, a]).collect(),
            }],
        };
        let colour = SoftwareTextures::new(&scene, true).expect("textures");
        let bake = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let draw = |t: &SoftwareTextures| {
            render_coverage(&scene, t, Mat4::IDENTITY, 60, 40, 2).expect("render")
        };
        let image = draw(&colour);
        let covered = image.covered.iter().filter(|c| **c).count();
        assert!(
            covered > 100 && covered < 60 * 40,
            "{covered} pixels covered"
        );
        assert_eq!(draw(&bake), image);
    }

    /// The mip level's `hypot` gives glibc's `hypotf` bits (what the renders read before it
    /// replaced the call): random magnitudes of texel steps and random bit patterns.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn hypot_gives_the_c_librarys_bits() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..1_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let (x, y) = if i % 2 == 0 {
                (
                    f32::from_bits(state as u32),
                    f32::from_bits((state >> 32) as u32),
                )
            } else {
                let unit = |b: u64| (b & 0xff_ffff) as f32 / (1 << 24) as f32 - 0.5;
                (unit(state) * 4096.0, unit(state >> 24) * 4096.0)
            };
            let (ours, libm) = (hypot(x, y), x.hypot(y));
            if libm.is_nan() {
                assert!(ours.is_nan(), "hypot({x:e}, {y:e})");
            } else {
                assert_eq!(ours.to_bits(), libm.to_bits(), "hypot({x:e}, {y:e})");
            }
        }
        for (x, y) in [(f32::INFINITY, f32::NAN), (f32::NAN, f32::NEG_INFINITY)] {
            assert_eq!(hypot(x, y), x.hypot(y), "hypot({x:e}, {y:e})");
        }
    }

    /// Marking a decided pixel's samples covered changes no mask: many overlapping
    /// alpha-tested quads (a noisy alpha, offset and sloped) at several supersamplings.
    #[test]
    fn saturated_pixels_give_the_same_mask() {
        let (w, h) = (23u32, 17u32);
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let a = (i.wrapping_mul(2_654_435_761) >> 24) as u8;
                [90, 160, 40, a]
            })
            .collect();
        let meshes: Vec<DrawMesh> = (0..12)
            .map(|k| {
                let x0 = -1.0 + 0.13 * k as f32;
                let mut m = quad(x0, x0 + 0.9, 0.2 + 0.05 * k as f32, k % 3 == 0, 0);
                m.positions[2][1] -= 0.1 * k as f32;
                m
            })
            .collect();
        let scene = DrawScene {
            meshes,
            materials: vec![DrawMaterial {
                texture: Some(0),
                alpha_cutoff: Some(0.5),
                double_sided: true,
                ..DrawMaterial::opaque([1.0; 4])
            }],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba,
            }],
        };
        let textures = SoftwareTextures::new(&scene, false).expect("textures");
        for ss in [1, 2, 3, 4] {
            let size = [61, 47, ss];
            let saturated =
                rasterise(&scene, &textures, Mat4::IDENTITY, size, Shortcuts::ALL).expect("r");
            let shortcuts = Shortcuts {
                saturate: false,
                ..Shortcuts::ALL
            };
            let exact = rasterise(&scene, &textures, Mat4::IDENTITY, size, shortcuts).expect("r");
            assert_eq!(saturated.0.covered, exact.0.covered, "{ss}x");
            let covered = exact.0.covered.iter().filter(|&&c| c).count();
            assert!(covered > 100 && covered < 61 * 47, "{ss}x: {covered}");
            // Only the count of covered samples grows (the decided pixels' other samples).
            if ss > 1 {
                assert!(saturated.2 > exact.2, "{ss}x: saturation never acted");
            } else {
                assert_eq!(saturated.2, exact.2);
            }
        }
    }
}
