//! A CPU rasteriser for billboard baking: the alpha-tested, mip-mapped triangles of a
//! [`DrawScene`] drawn into a supersampled image, each sample keeping the nearest surface
//! (depth test `Less`), resolved per pixel to the number of covered samples, their mean
//! unlit colour in linear light and the sum of their normals facing the viewer.
//!
//! Why not the wgpu path ([`crate::Renderer::render_view`] with [`crate::Output::Color`]
//! then [`crate::Output::Normal`]): a billboard atlas is thousands of tiny orthographic views
//! of a few triangles each, and a screen rasteriser draws it twice (colour, then normals),
//! shades every fragment that passes the depth test, writes 8-bit samples and reads whole
//! tiles back. On llvmpipe, the adapter most machines running frond have, that was a large
//! share of `frond lod`'s wall time. Here one pass tests each fragment's depth and
//! alpha, keeps the winning triangle per sample, and shades only the winners once every
//! triangle is drawn (deferred): one texture fetch per fragment for the alpha test (from the
//! nearer mip level, as `LINEAR_MIPMAP_NEAREST`), and one trilinear colour fetch per covered
//! sample. A triangle's rows are walked only within the octagon of texture coordinates where
//! its alpha test can pass ([`crate::uv_hull`]): the samples left out would fail it. Where the
//! machine has AVX2, eight samples of a row are tested at once ([`crate::sample_lanes`], as
//! coverage renders do: one gather of each footprint's four alphas), their depths too, and
//! the arithmetic of eight samples won by one triangle is done at once
//! ([`crate::bake_lanes`]); the colour is filtered from levels decoded to linear light
//! beforehand. Each gives the same bits (docs/performance.md has what each step and the
//! regions below saved). A [`BakeTarget`] holds a render's frame, materials and textures; its regions
//! are drawn one by one, each from its own meshes (set up as it is drawn) into buffers of its
//! own size, and resolved alone: the billboard bake draws each atlas cell so, in parallel
//! ([`render_bake`] draws bands of rows, each setting every mesh up). Regions are
//! independent, so the image is the same whatever the thread count, and from machine to
//! machine.
//!
//! It follows [`crate::render_coverage`]'s conventions (samples at pixel centres, wgpu clip
//! space, back faces culled unless double-sided, the coverage-preserving mip chains filtered
//! trilinearly with the level chosen per triangle) and the wgpu path's bake shaders: colour is
//! the texel times the material's base colour, unlit; the normal is the interpolated vertex
//! normal, flipped on back faces so it faces the viewer (improved-billboard-cloud §4 items 4
//! and 7), found once for a triangle whose corners share one normal and one depth (every
//! billboard member is a flat face seen orthographically: the same normal but for its last
//! bits). Likewise an affine triangle's texture coordinates (`1/w` the same at its corners)
//! are summed from its corners' with no perspective division per sample, by the eight-sample
//! lanes and the scalar path alike (a few samples at the alpha test's edge change side).

use frond_scene::Wrap;
use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::bake_lanes::{self, LaneShading, ShadeLanes};
use crate::error::RenderError;
use crate::sample_lanes::{self, LaneTest, TriangleLanes};
use crate::scene::{DrawAlpha, DrawMesh, DrawScene, validate_mesh};
use crate::software::alpha::AlphaCutoff;
use crate::software::bands::{BAND_PIXELS, MAX_SIDE, checked_target};
use crate::software::sampling::LinearLevel;
use crate::software::setup::{SetUpMeshes, Setup, affine_uv};
use crate::software::shading::Shading;
use crate::software::textures::SoftwareTextures;
use crate::srgb::SRGB_LINEAR;
use crate::uv_hull::{BAKE_MIN_AREA, HullLevels, TriangleHull, narrowed};

/// A bake render resolved to pixels, top row first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` counts of the pixel's samples that a triangle covers (after the
    /// alpha test).
    pub samples: Vec<u16>,
    /// `width · height` mean linear RGB of the covered samples (zero where none is): texel
    /// times base colour, unlit, each sample clamped to 0..1 as a colour target stores it.
    pub colour: Vec<[f32; 3]>,
    /// `width · height` sums of the covered samples' unit normals facing the viewer (a sample
    /// of a mesh without normals, or with a degenerate one, adds nothing).
    pub normal: Vec<[f32; 3]>,
}

/// A pixel of a bake render that a sample of it is covered in ([`BakeTarget::render_covered`]):
/// its entries of a [`BakeImage`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoveredPixel {
    /// Its covered samples (at least one).
    pub samples: u16,
    /// Their mean linear RGB.
    pub colour: [f32; 3],
    /// The sum of their unit normals facing the viewer.
    pub normal: [f32; 3],
}

/// Renders `scene` through `view_proj` at `width`×`height` pixels of `supersample`² samples
/// for baking (see the module docs), with `textures` prepared from `scene.textures` with
/// colour ([`SoftwareTextures::for_bake`]): bands of rows drawn in parallel.
pub fn render_bake(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    width: u32,
    height: u32,
    supersample: u32,
) -> Result<BakeImage, RenderError> {
    bake_with(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        BakeShortcuts::ALL,
    )
}

/// The shortcuts a bake render takes, each giving the same image (a test compares them).
#[derive(Clone, Copy, Debug)]
struct BakeShortcuts {
    /// Only the parts of triangles where their alpha test can pass are drawn
    /// ([`crate::uv_hull`]).
    hulls: bool,
    /// Eight samples of a row are tested at once where the machine can ([`sample_lanes`]).
    lanes: bool,
    /// A flat triangle's normal is found once, not at each sample (see
    /// [`BakeTarget::shader`]): the same normals but for their last bits.
    flat: bool,
}

impl BakeShortcuts {
    const ALL: BakeShortcuts = BakeShortcuts {
        hulls: true,
        lanes: true,
        flat: true,
    };
}

/// [`render_bake`] with the given `shortcuts` (all of them but in the test that compares
/// them).
fn bake_with(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    [width, height, supersample]: [u32; 3],
    shortcuts: BakeShortcuts,
) -> Result<BakeImage, RenderError> {
    let target = BakeTarget::with(
        scene,
        textures,
        view_proj,
        [width, height, supersample],
        shortcuts,
    )?;
    let bands: Vec<BakeImage> = (0..height.div_ceil(BAND_PIXELS as u32))
        .into_par_iter()
        .map_init(BakeScratch::default, |scratch, b| {
            let y = b * BAND_PIXELS as u32;
            let rows = (BAND_PIXELS as u32).min(height - y);
            target.render([0, y, width, rows], &scene.meshes, scratch)
        })
        .collect::<Result<_, _>>()?;
    let pixels = width as usize * height as usize;
    let mut image = BakeImage {
        width,
        height,
        samples: Vec::with_capacity(pixels),
        colour: Vec::with_capacity(pixels),
        normal: Vec::with_capacity(pixels),
    };
    for band in bands {
        image.samples.extend(band.samples);
        image.colour.extend(band.colour);
        image.normal.extend(band.normal);
    }
    Ok(image)
}

/// No triangle at this sample.
const EMPTY: u32 = u32::MAX;

/// One thread's buffers, reused from region to region: the region's triangles set up, and
/// per sample the nearest depth so far and the triangle there.
#[derive(Debug, Default)]
pub struct BakeScratch {
    set_up: SetUpMeshes,
    depth: Vec<f32>,
    winner: Vec<u32>,
    /// Per sample row, a bit per eight samples (from the region's left) that a triangle
    /// took one of: the resolve reads those alone (most of a cell is clear).
    touched: Vec<u64>,
}

/// A bake render's target, materials and textures, for its regions to be drawn one by one
/// ([`BakeTarget::render`]), each from its own meshes, set up as it is drawn: a billboard
/// atlas is thousands of small cells whose triangles lie within them, and a cell drawn alone
/// keeps its triangles and samples in the core's cache and resolves no empty texel around
/// it. Every sample is the one [`render_bake`] draws when a region's meshes hold every
/// triangle reaching into it, in the scene's order.
pub struct BakeTarget<'a> {
    scene: &'a DrawScene,
    textures: &'a SoftwareTextures,
    view_proj: Mat4,
    /// Per material, its alpha test.
    cutoffs: Vec<Option<AlphaCutoff>>,
    /// Per material with a textured alpha test, where its test can pass: a triangle's rows
    /// are walked only within the octagon of the level its samples are tested at (the bake's
    /// alpha test reads one, [`SoftwareTextures::bake_alpha_test`]).
    hulls: Vec<Option<HullLevels<'a>>>,
    /// The target's size in samples.
    size: [usize; 2],
    ss: usize,
    /// Eight samples of a row tested at once ([`sample_lanes`]) where the machine can: the
    /// same image.
    lanes: bool,
    /// Flat triangles' normals found once ([`BakeTarget::shader`]).
    flat: bool,
}

impl<'a> BakeTarget<'a> {
    /// Most samples per side of a target (its pixels times the supersampling): a larger
    /// image is drawn as several targets.
    pub const MAX_SIDE_SAMPLES: u32 = MAX_SIDE as u32;

    /// A target of `width`×`height` pixels of `supersample`² samples seen through
    /// `view_proj`, drawing with the materials and textures of `scene` (its meshes are
    /// checked but not drawn: each region names its own), `textures` prepared from
    /// `scene.textures` with colour ([`SoftwareTextures::for_bake`]).
    pub fn new(
        scene: &'a DrawScene,
        textures: &'a SoftwareTextures,
        view_proj: Mat4,
        width: u32,
        height: u32,
        supersample: u32,
    ) -> Result<Self, RenderError> {
        Self::with(
            scene,
            textures,
            view_proj,
            [width, height, supersample],
            BakeShortcuts::ALL,
        )
    }

    /// [`BakeTarget::new`] taking the given shortcuts.
    fn with(
        scene: &'a DrawScene,
        textures: &'a SoftwareTextures,
        view_proj: Mat4,
        [width, height, supersample]: [u32; 3],
        shortcuts: BakeShortcuts,
    ) -> Result<Self, RenderError> {
        let (sw, sh) = checked_target(scene, textures, view_proj, [width, height, supersample])?;
        if !textures.colour {
            return Err(RenderError::InvalidTexture {
                texture: 0,
                reason: "a bake render needs textures prepared with colour".into(),
            });
        }
        let cutoffs = AlphaCutoff::of_materials(scene, DrawAlpha::test_cutoff);
        let hulls = if shortcuts.hulls {
            HullLevels::of_materials(scene, textures, &cutoffs)
        } else {
            scene.materials.iter().map(|_| None).collect()
        };
        Ok(BakeTarget {
            scene,
            textures,
            view_proj,
            cutoffs,
            hulls,
            size: [sw, sh],
            ss: supersample.max(1) as usize,
            lanes: shortcuts.lanes && sample_lanes::available(),
            flat: shortcuts.flat,
        })
    }

    /// The pixels `[x, y, w, h]` (clamped to the target) drawn with the triangles of
    /// `meshes` (of the target's materials) alone and resolved, `scratch` holding the
    /// triangles and samples meanwhile. A mesh that is not valid for the scene is an error.
    pub fn render(
        &self,
        rect: [u32; 4],
        meshes: &[DrawMesh],
        scratch: &mut BakeScratch,
    ) -> Result<BakeImage, RenderError> {
        let region = self.region(rect);
        let (width, height) = (region.x1 - region.x0, region.y1 - region.y0);
        let pixels = (width / self.ss) * (height / self.ss);
        let mut image = BakeImage {
            width: (width / self.ss) as u32,
            height: (height / self.ss) as u32,
            samples: vec![0; pixels],
            colour: vec![[0.0; 3]; pixels],
            normal: vec![[0.0; 3]; pixels],
        };
        self.render_covered(rect, meshes, scratch, |i, pixel| {
            image.samples[i] = pixel.samples;
            image.colour[i] = pixel.colour;
            image.normal[i] = pixel.normal;
        })?;
        Ok(image)
    }

    /// The samples of the pixels `[x, y, w, h]`, clamped to the target.
    fn region(&self, [x, y, w, h]: [u32; 4]) -> Region {
        let ss = self.ss;
        let clamp = |v: u32, side: usize| (v as usize * ss).min(side);
        let (x0, y0) = (clamp(x, self.size[0]), clamp(y, self.size[1]));
        let x1 = clamp(x.saturating_add(w), self.size[0]).max(x0);
        let y1 = clamp(y.saturating_add(h), self.size[1]).max(y0);
        Region { x0, x1, y0, y1 }
    }

    /// [`BakeTarget::render`] handing each pixel that a sample of it is covered in to
    /// `covered`, with its index in the region's pixels (rows of `w`, top first), in that
    /// order: no image of the region's size is made (most of an atlas cell is clear).
    pub fn render_covered(
        &self,
        rect: [u32; 4],
        meshes: &[DrawMesh],
        scratch: &mut BakeScratch,
        covered: impl FnMut(usize, CoveredPixel),
    ) -> Result<(), RenderError> {
        for (i, mesh) in meshes.iter().enumerate() {
            validate_mesh(i, mesh, self.scene.materials.len())?;
            if let Some(t) = self.scene.materials[mesh.material].texture
                && !self.textures.prepared(t)
            {
                return Err(RenderError::InvalidTexture {
                    texture: t,
                    reason: format!("mesh {i} is drawn with it but it was not prepared"),
                });
            }
        }
        let region = self.region(rect);
        let BakeScratch {
            set_up,
            depth,
            winner,
            touched,
        } = scratch;
        let size = self.size.map(|s| s as f32);
        (set_up).set_up(
            meshes,
            &self.scene.materials,
            self.textures,
            self.view_proj,
            size,
        );
        let drawn = Drawn {
            triangles: &set_up.triangles,
            shading: &set_up.shading,
        };
        // Eight samples more: the depth test reads and writes a row's samples eight at a time.
        depth.clear();
        depth.resize(region.samples() + 8, f32::INFINITY);
        winner.clear();
        winner.resize(region.samples() + 8, EMPTY);
        touched.clear();
        touched.resize((region.y1 - region.y0) * region.touched_words(), 0);
        let mut samples = Samples {
            depth,
            winner,
            touched,
        };
        for ti in 0..drawn.triangles.len() as u32 {
            self.draw(&drawn, ti, &region, &mut samples);
        }
        self.resolve(&drawn, &region, winner, touched, covered);
        Ok(())
    }

    /// Draws triangle `ti` into the samples of `region`: each sample it covers nearer than
    /// the depth there, where its alpha test passes, takes it.
    fn draw(&self, drawn: &Drawn, ti: u32, region: &Region, samples: &mut Samples) {
        let t = &drawn.triangles[ti as usize];
        let words = region.touched_words();
        let Samples {
            depth,
            winner,
            touched,
        } = samples;
        if (t.max[0].max(0) as usize) < region.x0
            || t.min[0].max(0) as usize >= region.x1
            || (t.max[1].max(0) as usize) < region.y0
            || t.min[1].max(0) as usize >= region.y1
        {
            return;
        }
        let material = &self.scene.materials[t.material as usize];
        let cutoff = self.cutoffs[t.material as usize].as_ref();
        let hull = match &self.hulls[t.material as usize] {
            Some(levels) => match levels.level(t.lod.nearest()).rows_from(t, BAKE_MIN_AREA) {
                TriangleHull::Empty => return,
                TriangleHull::Rows(rows) => Some(rows),
                TriangleHull::Unbounded => None,
            },
            None => None,
        };
        let lanes = match (cutoff, material.texture) {
            _ if !self.lanes => None,
            (None, _) => Some(TriangleLanes {
                q: t.q,
                uq: t.uq,
                affine: None,
                test: LaneTest::Opaque,
            }),
            (Some(cutoff), Some(i)) => self.textures.bake_lanes(t, i, material.wrap, cutoff),
            (Some(_), None) => None,
        };
        // An affine triangle's texture coordinates are summed without a division (the
        // lanes' test does the same: the same samples pass).
        let affine = t.affine_corners();
        let width = region.x1 - region.x0;
        for span in t.row_spans(region.y0, region.y1) {
            let row = (span.y - region.y0) * width;
            let touched = &mut touched[(span.y - region.y0) * words..][..words];
            let mut touch = |x: usize| touched[x / 512] |= 1 << (x / 8 % 64);
            let (first, last) = (span.first.max(region.x0), span.last.min(region.x1 - 1));
            if first > last {
                continue;
            }
            let Some((first, last)) = narrowed(hull.as_ref(), span.y, first, last) else {
                continue;
            };
            if let Some(lanes) = &lanes {
                let mut x = first;
                while x <= last {
                    let k0 = x as i32 - span.x0 as i32;
                    // SAFETY: `self.lanes` holds only where `sample_lanes::available`, and a
                    // table test's table is an `AlphaBounds` one (padded).
                    let r = unsafe { lanes.test(k0, span.start, span.step) };
                    let todo = if last < x + 7 {
                        0xff >> (x + 7 - last)
                    } else {
                        0xff
                    };
                    let hits = r.passing(todo, |uv| {
                        let (Some(cutoff), Some(texture)) = (cutoff, material.texture) else {
                            return false;
                        };
                        (self.textures).bake_alpha_test(texture, uv, t.lod, material.wrap, cutoff)
                    });
                    if hits != 0 {
                        let s = row + x - region.x0;
                        touch(x - region.x0 + hits.trailing_zeros() as usize);
                        touch(x - region.x0 + 31 - hits.leading_zeros() as usize);
                        let (depth, winner) = (&mut depth[s..s + 8], &mut winner[s..s + 8]);
                        // SAFETY: as above; the buffers hold eight samples past the last.
                        unsafe {
                            bake_lanes::depth_test(
                                k0, span.start, span.step, t.z, hits, ti, depth, winner,
                            )
                        };
                    }
                    x += 8;
                }
                continue;
            }
            for x in first..=last {
                let b = span.weights_at(x);
                if b[0] < 0.0 || b[1] < 0.0 || b[2] < 0.0 {
                    continue;
                }
                let s = row + x - region.x0;
                let z = b[0] * t.z[0] + b[1] * t.z[1] + b[2] * t.z[2];
                if z >= depth[s] {
                    continue;
                }
                if let Some(cutoff) = cutoff {
                    let uv = match &affine {
                        Some(corners) => affine_uv(corners, b),
                        None => t.uv(b).0,
                    };
                    let pass = match material.texture {
                        Some(i) => {
                            self.textures
                                .bake_alpha_test(i, uv, t.lod, material.wrap, cutoff)
                        }
                        None => cutoff.passes(1.0),
                    };
                    if !pass {
                        continue;
                    }
                }
                depth[s] = z;
                winner[s] = ti;
                touch(x - region.x0);
            }
        }
    }

    /// Shades each covered sample of `region` once (its winning triangle's colour and
    /// normal) and sums them per pixel, in the order of its samples (rows, then columns).
    /// Where the machine can, the arithmetic of eight samples of a row won by one triangle is
    /// done at once ([`crate::bake_lanes`]: the same bits).
    fn resolve(
        &self,
        drawn: &Drawn,
        region: &Region,
        winner: &[u32],
        touched: &[u64],
        mut covered: impl FnMut(usize, CoveredPixel),
    ) {
        let linear = &*SRGB_LINEAR;
        let ss = self.ss;
        let width = region.x1 - region.x0;
        let (w, h) = (width / ss, (region.y1 - region.y0) / ss);
        // Per pixel of the row: its covered samples, their colours' and normals' sums.
        let mut sums = vec![(0u16, Vec3::ZERO, Vec3::ZERO); w];
        // Each triangle's shading, looked up when it first wins a sample.
        let mut shaders: Vec<Option<Shader>> = Vec::new();
        shaders.resize_with(drawn.triangles.len(), || None);
        for py in 0..h {
            sums.fill((0, Vec3::ZERO, Vec3::ZERO));
            for dy in 0..ss {
                let y = py * ss + dy;
                let row = &winner[y * width..(y + 1) * width];
                let at = [region.x0, region.y0 + y];
                let words = region.touched_words();
                let groups = &touched[y * words..(y + 1) * words];
                self.shade_row(drawn, row, groups, at, &mut shaders, linear, |x, (c, n)| {
                    let (count, colour, normal) = &mut sums[x / ss];
                    *colour += c;
                    if let Some(n) = n {
                        *normal += n;
                    }
                    *count += 1;
                });
            }
            for (px, &(count, colour, normal)) in sums.iter().enumerate() {
                if count > 0 {
                    let pixel = CoveredPixel {
                        samples: count,
                        colour: (colour / f32::from(count)).to_array(),
                        normal: normal.to_array(),
                    };
                    covered(py * w + px, pixel);
                }
            }
        }
    }

    /// Shades the covered samples of one row of a region (`row`, its winners, from sample
    /// `[x0, y]`) and hands each to `add` with its column in the row, in column order: eight
    /// at a time where one triangle won several of them and the machine can, one by one
    /// otherwise. `shaders` holds each triangle's shading once looked up.
    #[expect(
        clippy::too_many_arguments,
        reason = "a row, where to find it, and its sink"
    )]
    fn shade_row<'s>(
        &'s self,
        drawn: &Drawn<'s>,
        row: &[u32],
        groups: &[u64],
        [x0, y]: [usize; 2],
        shaders: &mut [Option<Shader<'s>>],
        linear: &[f32; 256],
        mut add: impl FnMut(usize, (Vec3, Option<Vec3>)),
    ) {
        let mut out = [(Vec3::ZERO, None); 8];
        let touched = (groups.iter().enumerate()).flat_map(|(k, &word)| {
            let mut word = word;
            std::iter::from_fn(move || {
                (word != 0).then(|| {
                    let g = word.trailing_zeros() as usize;
                    word &= word - 1;
                    (k * 64 + g) * 8
                })
            })
        });
        for x in touched {
            let group = &row[x..(x + 8).min(row.len())];
            let covered = lanes_where(group, |ti| ti != EMPTY);
            let mut pending = covered;
            while pending != 0 {
                let ti = group[pending.trailing_zeros() as usize];
                let s = &*shaders[ti as usize].get_or_insert_with(|| self.shader(drawn, ti));
                let mut same = lanes_where(group, |t| t == ti);
                pending &= !same;
                if let Some(lanes) = s.lanes.filter(|_| self.lanes && same.count_ones() > 1) {
                    // SAFETY: `self.lanes` holds only where `sample_lanes::available`.
                    let r = unsafe { lanes.shade(x0 + x, y, same) };
                    let mut done = r.done;
                    same &= !done;
                    while done != 0 {
                        let i = done.trailing_zeros() as usize;
                        done &= done - 1;
                        out[i] = s.lane(&r, i);
                    }
                }
                while same != 0 {
                    let i = same.trailing_zeros() as usize;
                    same &= same - 1;
                    out[i] = self.shade(s, [x0 + x + i, y], linear);
                }
            }
            let mut covered = covered;
            while covered != 0 {
                let i = covered.trailing_zeros() as usize;
                covered &= covered - 1;
                add(x + i, out[i]);
            }
        }
    }

    /// Sample `[x, y]` shaded by the triangle of `s`: its colour and its unit normal facing
    /// the viewer, `None` when too short to normalise.
    fn shade(&self, s: &Shader, [x, y]: [usize; 2], linear: &[f32; 256]) -> (Vec3, Option<Vec3>) {
        let t = s.triangle;
        let b = t.weights(x as f32 + 0.5, y as f32 + 0.5);
        let (uv, q) = match &s.affine {
            Some(corners) => (affine_uv(corners, b), t.q[0]),
            None => t.uv(b),
        };
        let texel = match s.texels {
            Texels::White => Vec3::ONE,
            Texels::Decoded(a, b) => {
                let va = a.bilinear(uv, s.wrap);
                // `Levels::rgb`'s blend.
                b.map_or(va, |b| va + (b.bilinear(uv, s.wrap) - va) * t.lod.f)
            }
            Texels::Bytes(i) => self.textures.bake_rgb(i, uv, t.lod, s.wrap, linear),
        };
        let normal = s.flat.unwrap_or_else(|| {
            let nq = &s.nq;
            facing((b[0] * nq[0] + b[1] * nq[1] + b[2] * nq[2]) / q, t.back)
        });
        (s.colour(texel), normal)
    }
}

/// The unit normal of `n` facing the viewer (turned on a `back` face), `None` when too short
/// to normalise.
#[inline]
fn facing(n: Vec3, back: bool) -> Option<Vec3> {
    (n.length_squared() > 1e-12).then(|| {
        let n = n.normalize();
        if back { -n } else { n }
    })
}

impl BakeTarget<'_> {
    /// What shading a sample of triangle `ti` reads, looked up once.
    fn shader<'s>(&'s self, drawn: &Drawn<'s>, ti: u32) -> Shader<'s> {
        let triangle = &drawn.triangles[ti as usize];
        let material = &self.scene.materials[triangle.material as usize];
        let lod = triangle.lod;
        let texels = match material.texture {
            None => Texels::White,
            Some(i) => {
                let level = |l: u32| self.textures.bake_linear_level(i, l as usize);
                match (level(lod.a), lod.f > 0.0) {
                    (Some(a), false) => Texels::Decoded(a, None),
                    (Some(a), true) => {
                        level(lod.b).map_or(Texels::Bytes(i), |b| Texels::Decoded(a, Some(b)))
                    }
                    (None, _) => Texels::Bytes(i),
                }
            }
        };
        let [r, g, b, _] = material.base_color;
        let nq = drawn.shading[ti as usize].nq;
        let size = |level: &LinearLevel| [level.width, level.height];
        let levels = match texels {
            Texels::White => Some([None; 2]),
            Texels::Decoded(a, b) => Some([Some(size(a)), b.map(size)]),
            Texels::Bytes(_) => None,
        };
        // One normal at every sample where the corners' normals and depths are the same (a
        // flat face seen orthographically, as each billboard member is).
        let q = triangle.q;
        let flat = (self.flat && nq[0] == nq[1] && nq[1] == nq[2] && q[0] == q[1] && q[1] == q[2])
            .then(|| facing(nq[0] / q[0], triangle.back));
        let affine = triangle.affine_corners();
        Shader {
            triangle,
            base: Vec3::new(r, g, b),
            nq,
            flat,
            affine,
            wrap: material.wrap,
            texels,
            lanes: levels.map(|levels| ShadeLanes {
                x: triangle.x,
                y: triangle.y,
                inv_area: triangle.inv_area,
                q: triangle.q,
                uq: triangle.uq,
                nq: nq.map(|n| n.to_array()),
                affine,
                flat: flat.is_some(),
                back: triangle.back,
                levels,
            }),
        }
    }
}

/// The triangles of a region set up ([`BakeTarget::render`]), and their shading.
struct Drawn<'a> {
    triangles: &'a [Setup],
    shading: &'a [Shading],
}

/// What the shading of a triangle's samples reads ([`BakeTarget::shader`]).
struct Shader<'a> {
    triangle: &'a Setup,
    base: Vec3,
    nq: [Vec3; 3],
    /// The normal of every sample where the triangle is flat (see [`BakeTarget::shader`]).
    flat: Option<Option<Vec3>>,
    /// The texture coordinates at the corners of an affine triangle
    /// ([`Setup::affine_corners`]).
    affine: Option<[[f32; 2]; 3]>,
    wrap: [Wrap; 2],
    texels: Texels<'a>,
    /// Its eight-sample arithmetic, where its texels are not read from bytes.
    lanes: Option<ShadeLanes>,
}

impl Shader<'_> {
    /// A sample's colour from its texel: times the base colour, clamped as a colour target
    /// stores it.
    #[inline]
    fn colour(&self, texel: Vec3) -> Vec3 {
        (texel * self.base).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// Lane `i` of eight samples whose arithmetic `r` did ([`ShadeLanes::shade`]): its texels
    /// read and filtered as [`BakeTarget::shade`] filters them, its colour and normal.
    #[inline]
    fn lane(&self, r: &LaneShading, i: usize) -> (Vec3, Option<Vec3>) {
        let texel = match self.texels {
            Texels::Decoded(a, b) => {
                let at = |level: &LinearLevel, k: usize| {
                    level.bilinear_at(r.first[k][i] as usize, r.fx[k][i], r.fy[k][i])
                };
                let va = at(a, 0);
                // `Levels::rgb`'s blend.
                b.map_or(va, |b| va + (at(b, 1) - va) * self.triangle.lod.f)
            }
            _ => Vec3::ONE,
        };
        let normal = self.flat.unwrap_or_else(|| {
            (r.with_normal >> i & 1 == 1)
                .then(|| Vec3::new(r.normal[0][i], r.normal[1][i], r.normal[2][i]))
        });
        (self.colour(texel), normal)
    }
}

/// Where a triangle's colour texels come from: the same bits each way.
enum Texels<'a> {
    /// No texture: white.
    White,
    /// The trilinear pair's levels decoded to linear light (the second when blended in).
    Decoded(&'a LinearLevel, Option<&'a LinearLevel>),
    /// Texture `i`'s bytes, decoded as read ([`SoftwareTextures::bake_rgb`]).
    Bytes(usize),
}

/// The lanes (bits) of the winners `group` that `f` holds for.
#[inline]
fn lanes_where(group: &[u32], f: impl Fn(u32) -> bool) -> u32 {
    (group.iter().enumerate())
        .filter(|&(_, &ti)| f(ti))
        .fold(0, |m, (i, _)| m | 1 << i)
}

/// A region's per-sample buffers as triangles are drawn into it ([`BakeScratch`]).
struct Samples<'a> {
    depth: &'a mut [f32],
    winner: &'a mut [u32],
    touched: &'a mut [u64],
}

/// The samples `x0..x1` × `y0..y1` of a region being drawn (whole pixels).
struct Region {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl Region {
    /// Words of a row's bits of eight samples.
    fn touched_words(&self) -> usize {
        (self.x1 - self.x0).div_ceil(8).div_ceil(64)
    }

    fn samples(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{DrawMaterial, DrawMesh, DrawTexture};
    use crate::software::bands::Bands;

    /// A triangle pair over NDC `[x0, x1] × [-1, 1]` at depth `z` with normal `n`, counter-
    /// clockwise (front) unless `flip`.
    fn quad(x0: f32, x1: f32, z: f32, flip: bool, material: usize, n: [f32; 3]) -> DrawMesh {
        DrawMesh {
            positions: vec![[x0, -1.0, z], [x1, -1.0, z], [x1, 1.0, z], [x0, 1.0, z]],
            normals: Some(vec![n; 4]),
            tangents: None,
            uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
            indices: if flip {
                vec![0, 2, 1, 0, 3, 2]
            } else {
                vec![0, 1, 2, 0, 2, 3]
            },
            material,
        }
    }

    fn bake(scene: &DrawScene, ss: u32) -> BakeImage {
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        render_bake(scene, &textures, Mat4::IDENTITY, 8, 4, ss).expect("render")
    }

    #[test]
    fn the_nearest_surface_wins_each_sample_and_back_faces_turn_their_normal() {
        let red = DrawMaterial {
            double_sided: true,
            ..DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0])
        };
        let green = DrawMaterial {
            double_sided: true,
            ..DrawMaterial::opaque([0.0, 1.0, 0.0, 1.0])
        };
        // Green (far) everywhere; red (near, a back face) over the left half.
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.8, false, 1, [0.0, 0.0, 1.0]),
                quad(-1.0, 0.0, 0.2, true, 0, [0.0, 0.0, 1.0]),
            ],
            materials: vec![red, green],
            textures: vec![],
        };
        let image = bake(&scene, 2);
        assert_eq!((image.width, image.height), (8, 4));
        assert!(image.samples.iter().all(|&n| n == 4));
        for y in 0..4 {
            for x in 0..8 {
                let i = y * 8 + x;
                let (colour, normal) = if x < 4 {
                    ([1.0, 0.0, 0.0], [0.0, 0.0, -4.0])
                } else {
                    ([0.0, 1.0, 0.0], [0.0, 0.0, 4.0])
                };
                assert_eq!(image.colour[i], colour, "pixel {x},{y}");
                assert_eq!(image.normal[i], normal, "pixel {x},{y}");
            }
        }
    }

    #[test]
    fn a_flat_face_s_one_normal_is_each_sample_s_within_rounding() {
        // A tilted normal, the same at every corner: found once or at each sample, with and
        // without eight-sample lanes, the normals agree but for their last bits.
        let n = Vec3::new(0.3, -0.5, 0.8).normalize().to_array();
        let scene = DrawScene {
            meshes: vec![quad(-0.9, 0.7, 0.4, true, 0, n)],
            materials: vec![DrawMaterial {
                double_sided: true,
                ..DrawMaterial::opaque([0.5, 0.6, 0.7, 1.0])
            }],
            textures: vec![],
        };
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let bake = |lanes, flat| {
            let shortcuts = BakeShortcuts {
                hulls: true,
                lanes,
                flat,
            };
            bake_with(&scene, &textures, Mat4::IDENTITY, [16, 8, 4], shortcuts).expect("bake")
        };
        let once = bake(true, true);
        assert_eq!(once, bake(false, true));
        for lanes in [false, true] {
            let each = bake(lanes, false);
            assert_eq!((&each.samples, &each.colour), (&once.samples, &once.colour));
            for (i, (a, b)) in each.normal.iter().zip(&once.normal).enumerate() {
                let d = Vec3::from(*a).distance(Vec3::from(*b));
                assert!(d <= 1e-5, "pixel {i}: {a:?} {b:?}");
            }
        }
        // A back face (the quad is wound clockwise): each covered sample's normal is `-n`.
        let i = 4 * 16 + 4;
        assert_eq!(once.samples[i], 16);
        let mean = Vec3::from(once.normal[i]) / 16.0;
        assert!(mean.distance(-Vec3::from(n)) < 1e-6, "{mean}");
    }

    #[test]
    fn covered_pixels_are_the_image_s_covered_ones_in_order() {
        // A quad over the left half of an 8×4 target, drawn into a region that clips it.
        let scene = DrawScene {
            meshes: vec![quad(-1.0, 0.1, 0.5, false, 0, [0.0, 0.6, 0.8])],
            materials: vec![DrawMaterial::opaque([0.2, 0.4, 0.6, 1.0])],
            textures: vec![],
        };
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let target = BakeTarget::new(&scene, &textures, Mat4::IDENTITY, 8, 4, 2).expect("target");
        let mut scratch = BakeScratch::default();
        let rect = [1, 1, 6, 3];
        let image = (target.render(rect, &scene.meshes, &mut scratch)).expect("render");
        assert_eq!((image.width, image.height), (6, 3));
        let mut covered = Vec::new();
        (target.render_covered(rect, &scene.meshes, &mut scratch, |i, p| {
            covered.push((i, p))
        }))
        .expect("render");
        let want: Vec<(usize, CoveredPixel)> = (0..image.samples.len())
            .filter(|&i| image.samples[i] > 0)
            .map(|i| {
                let pixel = CoveredPixel {
                    samples: image.samples[i],
                    colour: image.colour[i],
                    normal: image.normal[i],
                };
                (i, pixel)
            })
            .collect();
        // Pixel columns 1..=4 of the target are wholly or partly covered (the quad's right
        // edge at x = 4.4 pixels).
        assert_eq!(want.len(), 4 * 3);
        assert_eq!(covered, want);
        assert!(
            image
                .samples
                .iter()
                .enumerate()
                .all(|(i, &n)| n > 0 || image.colour[i] == [0.0; 3])
        );
    }

    #[test]
    fn alpha_tested_texels_leave_their_samples_to_the_surface_behind() {
        // A 2×1 texture, clamped at its edges: left texel opaque white, right texel clear.
        // The near quad shows the far one through its clear half.
        let cut = DrawMaterial {
            alpha: DrawAlpha::Mask(0.5),
            texture: Some(0),
            double_sided: true,
            wrap: [frond_scene::Wrap::ClampToEdge; 2],
            ..DrawMaterial::opaque([1.0; 4])
        };
        let blue = DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0]);
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, 1.0, 0.2, false, 0, [0.0, 0.0, 1.0]),
                quad(-1.0, 1.0, 0.8, false, 1, [0.0, 0.0, 1.0]),
            ],
            materials: vec![cut, blue],
            textures: vec![DrawTexture {
                width: 2,
                height: 1,
                rgba: vec![255, 255, 255, 255, 255, 255, 255, 0],
            }],
        };
        let image = bake(&scene, 4);
        // Leftmost and rightmost columns lie well inside one texel each.
        for y in 0..4 {
            assert_eq!(image.colour[y * 8], [1.0, 1.0, 1.0]);
            assert_eq!(image.colour[y * 8 + 7], [0.0, 0.0, 1.0]);
            assert_eq!(image.samples[y * 8 + 7], 16);
        }
    }

    #[test]
    fn textures_left_out_of_the_preparation_are_an_error_where_drawn() {
        let textured = DrawMaterial {
            texture: Some(1),
            ..DrawMaterial::opaque([1.0; 4])
        };
        let texture = |v: u8| DrawTexture {
            width: 2,
            height: 2,
            rgba: vec![v; 16],
        };
        let scene = DrawScene {
            meshes: Vec::new(),
            materials: vec![DrawMaterial::opaque([0.0, 0.0, 1.0, 1.0]), textured],
            textures: vec![texture(10), texture(200)],
        };
        let only_first =
            SoftwareTextures::for_bake_of(&scene.textures, &[true, false]).expect("textures");
        assert!(only_first.prepared(0) && !only_first.prepared(1));
        let target = BakeTarget::new(&scene, &only_first, Mat4::IDENTITY, 8, 4, 2).expect("target");
        let mut scratch = BakeScratch::default();
        let plain = [quad(-1.0, 1.0, 0.5, false, 0, [0.0, 0.0, 1.0])];
        let image = target
            .render([0, 0, 8, 4], &plain, &mut scratch)
            .expect("render");
        assert!(image.samples.iter().all(|&n| n == 4));
        let drawn = [quad(-1.0, 1.0, 0.5, false, 1, [0.0, 0.0, 1.0])];
        let err = target.render([0, 0, 8, 4], &drawn, &mut scratch);
        assert!(
            matches!(err, Err(RenderError::InvalidTexture { texture: 1, .. })),
            "{err:?}"
        );
        // Prepared, the same mesh draws its texture.
        let all = SoftwareTextures::for_bake_of(&scene.textures, &[true, true]).expect("all");
        let target = BakeTarget::new(&scene, &all, Mat4::IDENTITY, 8, 4, 2).expect("target");
        let image = target
            .render([0, 0, 8, 4], &drawn, &mut scratch)
            .expect("render");
        assert!(image.samples.iter().all(|&n| n == 4));
    }

    /// The shortcuts change nothing, alone or together: walking only the parts of triangles
    /// where the alpha test can pass, and testing and shading eight samples at once. Random
    /// leaf cards (an opaque rectangle with hard edges on a clear square, most of the cards
    /// large enough to be bounded; a third untextured and opaque) at random depths, baked
    /// every way. One material's cutoff is nearly zero, so
    /// that samples pass within a small fraction of a texel of the octagon's edges.
    #[test]
    fn shortcuts_leave_the_bake_unchanged() {
        let (w, h) = (32u32, 32u32);
        let rgba = (0..w * h)
            .flat_map(|i| {
                let opaque = (8..24).contains(&(i % w)) && (5..27).contains(&(i / w));
                // Colour varying texel to texel, so that a filter's weights show.
                [
                    (i * 37 % 256) as u8,
                    (i * 11 % 256) as u8,
                    40,
                    if opaque { 255 } else { 0 },
                ]
            })
            .collect();
        let mut state = 5u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let meshes = (0..80)
            .map(|i| {
                let (cx, cy, size) = (next() * 1.6 - 0.8, next() * 1.6 - 0.8, 0.1 + next() * 0.4);
                let (a, z) = (next() * 6.3, 0.1 + next() * 0.8);
                let (c, s) = (a.cos() * size, a.sin() * size);
                DrawMesh {
                    positions: vec![
                        [cx - c + s, cy - s - c, z],
                        [cx + c + s, cy + s - c, z],
                        [cx + c - s, cy + s + c, z],
                        [cx - c - s, cy - s + c, z],
                    ],
                    normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
                    tangents: None,
                    uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
                    indices: vec![0, 1, 2, 0, 2, 3],
                    material: i % 3,
                }
            })
            .collect();
        let material = |cutoff, wrap| DrawMaterial {
            alpha: DrawAlpha::Mask(cutoff),
            texture: Some(0),
            double_sided: true,
            wrap: [wrap; 2],
            ..DrawMaterial::opaque([1.0; 4])
        };
        let scene = DrawScene {
            meshes,
            materials: vec![
                material(0.02, frond_scene::Wrap::ClampToEdge),
                material(0.5, frond_scene::Wrap::Repeat),
                DrawMaterial {
                    double_sided: true,
                    ..DrawMaterial::opaque([0.3, 0.9, 0.5, 1.0])
                },
            ],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba,
            }],
        };
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        for (width, height, ss) in [(64, 48, 2), (200, 150, 4)] {
            let size = [width, height, ss];
            let bake_all = |hulls, lanes, flat| {
                let shortcuts = BakeShortcuts { hulls, lanes, flat };
                bake_with(&scene, &textures, Mat4::IDENTITY, size, shortcuts).expect("bake")
            };
            let bake = |hulls, lanes| bake_all(hulls, lanes, true);
            let plain = bake(false, false);
            // A flat card's one normal is each sample's but for rounding, both ways.
            for lanes in [false, true] {
                let each = bake_all(false, lanes, false);
                assert_eq!(
                    (&each.samples, &each.colour),
                    (&plain.samples, &plain.colour)
                );
                for (a, b) in each.normal.iter().zip(&plain.normal) {
                    let d = Vec3::from(*a).distance(Vec3::from(*b));
                    assert!(d <= 1e-5, "{a:?} {b:?}");
                }
            }
            for (hulls, lanes) in [(true, false), (false, true), (true, true)] {
                let with = bake(hulls, lanes);
                let differ = (0..with.samples.len())
                    .filter(|&i| {
                        (with.samples[i], with.colour[i], with.normal[i])
                            != (plain.samples[i], plain.colour[i], plain.normal[i])
                    })
                    .count();
                let what = format!("{width}x{height}, {ss}x, octagons {hulls}, lanes {lanes}");
                assert_eq!(differ, 0, "{what}: pixels that differ");
                assert_eq!(with, plain, "{what}");
            }
            let covered = plain.samples.iter().filter(|&&n| n > 0).count();
            assert!(
                covered * 4 > (width * height) as usize,
                "{covered} pixels covered"
            );
        }
        // The octagons bound most textured cards at the larger size.
        let (sw, sh) = (800, 600);
        let bands = Bands::new(&scene, &textures, Mat4::IDENTITY, [sw, sh], 4);
        let cutoffs = AlphaCutoff::of_materials(&scene, DrawAlpha::test_cutoff);
        let hulls = HullLevels::of_materials(&scene, &textures, &cutoffs);
        let textured: Vec<_> = (bands.triangles.iter())
            .filter_map(|t| Some((t, hulls[t.material as usize].as_ref()?)))
            .collect();
        let bounded = (textured.iter())
            .filter(|(t, levels)| {
                matches!(
                    levels.level(t.lod.nearest()).rows(t),
                    TriangleHull::Rows(_) | TriangleHull::Empty
                )
            })
            .count();
        assert!(
            bounded > textured.len() / 2,
            "{bounded} of {} bounded",
            textured.len()
        );
    }

    /// Regions drawn alone from their own meshes are the whole render's pixels: three
    /// columns of cards, one textured and alpha-tested, the last drawn in two pieces of rows;
    /// a region reaching past the target is cut at its edge.
    #[test]
    fn regions_drawn_alone_are_the_whole_renders_pixels() {
        let (w, h) = (8u32, 8u32);
        let rgba = (0..w * h)
            .flat_map(|i| {
                [
                    (i * 3) as u8,
                    90,
                    (i * 7) as u8,
                    if (i % w + i / w) % 3 == 0 { 0 } else { 255 },
                ]
            })
            .collect();
        let cut = DrawMaterial {
            alpha: DrawAlpha::Mask(0.5),
            texture: Some(0),
            double_sided: true,
            ..DrawMaterial::opaque([0.9, 0.8, 1.0, 1.0])
        };
        let scene = DrawScene {
            meshes: vec![
                quad(-1.0, -0.5, 0.3, false, 1, [0.0, 0.6, 0.8]),
                quad(-0.5, 0.25, 0.6, true, 0, [0.0, 0.0, 1.0]),
                quad(0.25, 1.0, 0.4, false, 0, [0.6, 0.0, 0.8]),
            ],
            materials: vec![cut, DrawMaterial::opaque([0.2, 0.7, 0.1, 1.0])],
            textures: vec![DrawTexture {
                width: w,
                height: h,
                rgba,
            }],
        };
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let whole = render_bake(&scene, &textures, Mat4::IDENTITY, 16, 8, 4).expect("render");
        let target = BakeTarget::new(&scene, &textures, Mat4::IDENTITY, 16, 8, 4).expect("target");
        let mut scratch = BakeScratch::default();
        let regions = [
            ([0, 0, 4, 8], 0..1),
            ([4, 0, 6, 8], 1..2),
            ([10, 0, 6, 3], 2..3),
            ([10, 3, 9, 9], 2..3),
        ];
        let mut compared = 0;
        for (rect, meshes) in regions {
            let image = (target.render(rect, &scene.meshes[meshes], &mut scratch)).expect("render");
            let [x, y, _, _] = rect.map(|v| v as usize);
            let (rw, rh) = (image.width as usize, image.height as usize);
            assert_eq!(
                (rw, rh),
                (
                    (16 - x).min(rect[2] as usize),
                    (8 - y).min(rect[3] as usize)
                )
            );
            for j in 0..rh {
                for i in 0..rw {
                    let (a, b) = (j * rw + i, (y + j) * 16 + x + i);
                    assert_eq!(
                        (image.samples[a], image.colour[a], image.normal[a]),
                        (whole.samples[b], whole.colour[b], whole.normal[b]),
                        "pixel {},{}",
                        x + i,
                        y + j
                    );
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 16 * 8);
        let partly = whole.samples.iter().filter(|&&n| n > 0 && n < 16).count();
        let full = whole.samples.iter().filter(|&&n| n == 16).count();
        assert!(
            partly > 4 && full > 40,
            "{partly} pixels partly covered, {full} fully"
        );
    }

    #[test]
    fn the_image_does_not_depend_on_the_thread_count() {
        let scene = DrawScene {
            meshes: vec![DrawMesh {
                positions: vec![[-0.9, -0.7, 0.5], [0.8, -0.95, 0.3], [0.1, 0.9, 0.6]],
                normals: Some(vec![[0.0, 0.6, 0.8]; 3]),
                tangents: None,
                uvs: None,
                indices: vec![0, 1, 2],
                material: 0,
            }],
            materials: vec![DrawMaterial::opaque([0.3, 0.6, 0.2, 1.0])],
            textures: vec![],
        };
        let textures = SoftwareTextures::for_bake(&scene.textures).expect("textures");
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| render_bake(&scene, &textures, Mat4::IDENTITY, 200, 150, 4))
                .expect("render")
        };
        let one = run(1);
        assert_eq!(one, run(3));
        let covered = one.samples.iter().filter(|&&n| n > 0).count();
        assert!(covered > 5_000, "{covered} pixels covered");
    }
}
