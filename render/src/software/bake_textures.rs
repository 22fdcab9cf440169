//! The billboard bake's view of [`SoftwareTextures`]: textures prepared for it (every level's
//! alpha alone, its footprints as four bytes and their bounds, its colour decoded to linear
//! light on first use) and the bake's alpha test, colour fetch and eight-sample test.

use frond_scene::Wrap;
use glam::Vec3;
use rayon::prelude::*;

use super::alpha::{AlphaBounds, AlphaCutoff, footprint_quads};
use super::sampling::{Levels, LinearLevel, Trilinear, bilerp, bilinear_rgb, footprint};
use super::setup::Setup;
use super::textures::SoftwareTextures;
use crate::error::RenderError;
use crate::pipeline::Mips;
use crate::sample_lanes::{LaneFilter, LaneLevel, LaneTest, TriangleLanes};
use crate::scene::DrawTexture;
use crate::srgb::SRGB_LINEAR;

impl SoftwareTextures {
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
            // The bake tests every material's alpha (a blended one at ½).
            .map(|i| {
                used.get(i)
                    .copied()
                    .unwrap_or(false)
                    .then_some(Mips::Tested)
            })
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

    /// The bake's alpha test at `uv` of `texture`'s level nearer `lod`
    /// (`Levels::alpha_nearest_level`): `alpha · scale ≥ cutoff`, decided from the
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
    /// `None` when it is not (not prepared for the bake, or over [`MAX_LINEAR_TEXELS`](super::sampling::MAX_LINEAR_TEXELS)).
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::software::test_scenes::{assert_alpha_tests_match, leaf_alpha};

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
}
