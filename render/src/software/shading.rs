//! Shading a sample: a triangle's shading attributes, the lighting of a colour render and
//! normal mapping, and what one triangle's samples read to be alpha-tested and coloured
//! ([`Surface`]).

use frond_scene::Wrap;
use glam::{Vec3, Vec4};

use super::alpha::{AlphaBounds, AlphaCutoff};
use super::sampling::{Levels, Trilinear};
use crate::scene::DrawMaterial;

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
    pub(super) fn shade(self, n: Vec3, l: Vec3) -> f32 {
        match self {
            Lighting::TwoSided => 0.6 + 0.4 * n.dot(l).abs(),
            Lighting::Lambert => 0.3 + 0.7 * n.dot(l).max(0.0),
        }
    }
}

/// A triangle's shading attributes, beside its [`Setup`](super::setup::Setup) in renders that shade (colour, or a
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

/// The normal a tangent-space normal map gives (glTF `normalTexture`): `map` (components in
/// −1..1) in the frame of the interpolated `normal`, `tangent` (xyz; w ignored) made
/// orthogonal to it, and the bitangent `sign · N × T`. The interpolated normal alone where
/// the frame is degenerate.
#[inline]
pub(super) fn mapped_normal(normal: Vec3, tangent: Vec4, sign: f32, map: Vec3) -> Vec3 {
    let n = normal.normalize_or_zero();
    let t = (tangent.truncate() - n * n.dot(tangent.truncate())).normalize_or_zero();
    if n == Vec3::ZERO || t == Vec3::ZERO {
        return normal;
    }
    let b = n.cross(t) * if sign < 0.0 { -1.0 } else { 1.0 };
    t * map.x + b * map.y + n * map.z
}

impl Shading {
    /// The normal at weights `b` (`q`: `Σ b·q` there): the corners' normals interpolated
    /// perspective-correctly and, where the triangle has tangents and a `normal_map`, turned
    /// by the map at `uv` ([`mapped_normal`]). Not normalised.
    #[inline(always)]
    pub(super) fn normal_at(
        &self,
        b: [f32; 3],
        q: f32,
        uv: [f32; 2],
        normal_map: Option<&Levels>,
        wrap: [Wrap; 2],
    ) -> Vec3 {
        let normal = (b[0] * self.nq[0] + b[1] * self.nq[1] + b[2] * self.nq[2]) / q;
        if let (Some(tq), Some(map)) = (self.tq, normal_map) {
            mapped_normal(
                normal,
                (b[0] * tq[0] + b[1] * tq[1] + b[2] * tq[2]) / q,
                tq[0].w,
                map.normal(uv, self.normal_lod, wrap),
            )
        } else {
            normal
        }
    }
}

/// What the samples of one triangle read to be alpha-tested and coloured: its material, its
/// texture's levels and their alpha bounds, its normal map and shading attributes, and the
/// mip levels chosen for it.
pub(crate) struct Surface<'r> {
    /// The triangle's material.
    pub(super) material: &'r DrawMaterial,
    /// The material's alpha test, if it has one.
    pub(super) cutoff: Option<&'r AlphaCutoff>,
    /// The material's texture, prepared.
    pub(super) texture: Option<&'r Levels>,
    /// The texture's alpha bounds per level (alpha-only levels: coverage renders).
    pub(super) bounds: Option<&'r [AlphaBounds]>,
    /// The material's normal map, when it applies (colour renders of meshes with tangents).
    pub(super) normal_map: Option<&'r Levels>,
    /// The triangle's shading attributes (colour renders).
    pub(super) shading: Option<&'r Shading>,
    /// The texture's two mip levels and the second's weight.
    pub(super) lod: Trilinear,
    /// The mesh has normals: the colour is lit.
    pub(super) lit: bool,
    /// A back face: its normal is flipped to face the viewer.
    pub(super) back: bool,
}

impl Surface<'_> {
    /// The alpha test at `uv` from the footprints' bounds ([`Levels::alpha_test`]) of a
    /// textured alpha test with bounds; false for any other surface. What the eight-sample
    /// test asks of the samples its lanes leave open.
    #[inline(always)]
    pub(super) fn bounded_alpha_test(&self, uv: [f32; 2]) -> bool {
        let (Some(l), Some(bounds), Some(cutoff)) = (self.texture, self.bounds, self.cutoff) else {
            return false;
        };
        l.alpha_test(bounds, uv, self.lod, self.material.wrap, cutoff)
    }

    /// `cutoff` tested at `uv`: from the footprints' bounds where the texture has them,
    /// otherwise on the filtered alpha of `stride`-byte texels (1 untextured).
    #[inline(always)]
    pub(super) fn passes_alpha(&self, cutoff: &AlphaCutoff, uv: [f32; 2], stride: usize) -> bool {
        let wrap = self.material.wrap;
        match (self.texture, self.bounds) {
            (Some(l), Some(bounds)) => l.alpha_test(bounds, uv, self.lod, wrap, cutoff),
            _ => cutoff.passes((self.texture).map_or(1.0, |l| l.alpha(uv, self.lod, wrap, stride))),
        }
    }

    /// The linear colour of the sample at weights `b` (`q`: `Σ b·q` there; `uv`: its texture
    /// coordinates): the base colour times the texel (decoded by `linear`), shaded under
    /// `lighting` from `light` where the mesh is lit, clamped to 0..1.
    #[inline(always)]
    pub(super) fn colour(
        &self,
        b: [f32; 3],
        q: f32,
        uv: [f32; 2],
        lighting: Lighting,
        light: Vec3,
        linear: &[f32; 256],
    ) -> Vec3 {
        let material = self.material;
        let base = Vec3::new(
            material.base_color[0],
            material.base_color[1],
            material.base_color[2],
        );
        let texel =
            (self.texture).map_or(Vec3::ONE, |l| l.rgb(uv, self.lod, material.wrap, linear));
        let mut shade = 1.0;
        if let Some(sh) = self.shading.filter(|_| self.lit) {
            let normal = sh.normal_at(b, q, uv, self.normal_map, material.wrap);
            if normal.length_squared() > 1e-12 {
                let n = normal.normalize();
                let n = if self.back { -n } else { n };
                shade = lighting.shade(n, light);
            }
        }
        (texel * base * shade).clamp(Vec3::ZERO, Vec3::ONE)
    }
}
