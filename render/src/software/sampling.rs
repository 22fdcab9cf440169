//! Texture sampling for the CPU rasterisers: a texture's mip chain ([`Levels`]), the mip
//! level pair of a trilinear fetch, wrap modes, bilinear footprints and filters (alpha,
//! linear-light colour, normal maps), as a GPU's sampler reads them.

use frond_scene::Wrap;
use glam::{Vec3, Vec4};

/// One texture's mip chain, level 0 first: `(width, height, texels)`, one alpha byte a texel,
/// or RGBA (sRGB colour, linear alpha) when colour is drawn.
#[derive(Clone, Debug)]
pub(crate) struct Levels(pub(super) Vec<(u32, u32, Vec<u8>)>);

/// `x.floor()` as an integer, without the library call `f32::floor` becomes on baseline
/// x86-64 (every texel fetch floors two coordinates). Saturates at the ends of `i64` (a file's
/// texture coordinate of ±3e38), as `as` does.
#[inline]
pub(super) fn floor_i64(x: f32) -> i64 {
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
    /// The first level (the finer).
    pub(crate) a: u32,
    /// The second level: `a + 1`, or `a` at the chain's last.
    pub(crate) b: u32,
    /// The second level's weight, 0 to 1.
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
pub(super) fn bilinear(
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
pub(super) fn bilerp<T>([a, b, c, d]: [T; 4], fx: f32, fy: f32) -> T
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
pub(super) const MAX_LINEAR_TEXELS: usize = 1 << 20;

/// An RGBA level's colour decoded to linear light, `[r, g, b, 0]` a texel: a bilinear fetch
/// reads four vectors where [`bilinear_rgb`] reads and decodes twelve bytes (the bake shades
/// every covered sample).
#[derive(Clone, Debug)]
pub(crate) struct LinearLevel {
    /// Width in texels.
    pub(crate) width: u32,
    /// Height in texels.
    pub(crate) height: u32,
    /// `width · height` texels, top row first.
    texels: Vec<Vec4>,
}

impl LinearLevel {
    /// `level` decoded by `linear`, `None` over [`MAX_LINEAR_TEXELS`].
    pub(super) fn new(
        (width, height, rgba): &(u32, u32, Vec<u8>),
        linear: &[f32; 256],
    ) -> Option<Self> {
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
pub(super) fn bilinear_rgb(
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
pub(super) fn footprint(
    level: &(u32, u32, Vec<u8>),
    uv: [f32; 2],
    wrap: [Wrap; 2],
    stride: usize,
) -> ([usize; 4], f32, f32) {
    footprint_of([level.0, level.1], uv, wrap, stride)
}

/// [`footprint`] on a level of `w`×`h` texels.
#[inline(always)]
pub(super) fn footprint_of(
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
    /// Every level, the first the texture itself: `(width, height, texels)`.
    pub(crate) fn levels(&self) -> &[(u32, u32, Vec<u8>)] {
        &self.0
    }

    /// The two levels of a trilinear fetch at `lod`.
    #[inline]
    pub(super) fn pair(&self, lod: f32) -> Trilinear {
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
    #[inline]
    pub(super) fn normal(&self, uv: [f32; 2], lod: Trilinear, wrap: [Wrap; 2]) -> Vec3 {
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
    #[inline]
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
