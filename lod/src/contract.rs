//! The contract between clustering and export: a LOD's foliage, an animated billboard cloud
//! (spec animated-billboard-clouds §1.4) or the input's own leaf cards thinned. Every method
//! produces one of the two ([`Foliage`]); `frond-export` writes it without knowing the method.
//!
//! Motion of a billboard, in world space at loop time `t`:
//! `corners(t) = W_b(t) · Rest_b⁻¹ · M(t) · quad.corners()` when it follows rig node `b`, or
//! `M(t) · quad.corners()` when it follows none, where `W_b(t)` is `b`'s animated world matrix,
//! `Rest_b` its rest world matrix and `M(t)` its own rigid motion (identity when `None`).
//! Quads never deform: `M` is rotation plus translation only.

use frond_billboard::{Atlas, Quad};
use frond_scene::wood::{NO_BONE, WoodMesh, WoodPrimitive};
use frond_scene::{Rig, Tree};
use frond_spectral::description::Components;
use glam::{Affine3A, Mat4, Vec2, Vec3};

/// A LOD's foliage as a method built it: export writes whichever it gets.
#[derive(Clone, Debug)]
pub enum Foliage {
    /// Billboards baked into one atlas, each moving rigidly (spec §1.4).
    Cloud(AnimatedBillboardCloud),
    /// The input's own leaf cards, thinned and skinned as in the input.
    Cards(CardFoliage),
}

/// Thinned leaf cards, ready to be skinned like the input's.
#[derive(Clone, Debug)]
pub struct CardFoliage {
    /// The kept cards, scaled, bones as rig node indices, the input's foliage materials.
    pub mesh: WoodMesh,
    /// The skeleton the cards follow: the tree's, until the chain's budget prunes it.
    pub rig: Rig,
}

/// When a billboard's own motion is sampled: uniformly over one period of one clip.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopClock {
    /// Index into [`Rig::clips`], or None for a tree without clips.
    pub clip: Option<usize>,
    /// Time of the first sample, seconds into the clip.
    pub start: f32,
    /// Loop length in seconds (0 for a static tree).
    pub period: f32,
    /// Number of uniform samples; sample `s` is at `start + period · s / samples`.
    pub samples: usize,
}

impl LoopClock {
    /// The clock of a sampled loop of `tree` (its clip, first time, period and sample count).
    pub fn of(tree: &Tree, sampled: &frond_scene::Sampled) -> LoopClock {
        LoopClock {
            clip: sampled
                .clip
                .as_deref()
                .and_then(|c| tree.clip_index(Some(c))),
            start: sampled.times.first().copied().unwrap_or(0.0),
            period: sampled.period,
            samples: sampled.samples(),
        }
    }

    /// Time of sample `s`.
    pub fn time(&self, s: usize) -> f32 {
        if self.samples == 0 {
            return self.start;
        }
        self.start + self.period * s as f32 / self.samples as f32
    }
}

/// A billboard's own rigid motion over the loop, relative to what it follows.
#[derive(Clone, Debug, PartialEq)]
pub enum RigidMotion {
    /// One transform per [`LoopClock`] sample.
    Sampled(Vec<Affine3A>),
    /// A fixed placement followed by a translation given as a few cosines per axis (spectral
    /// clustering, spec §4.11: the inverse DFT of the billboard's average description).
    Spectral(SpectralMotion),
}

/// `M(t) = translate(Σ_j a_j cos(2π f_j t/N + φ_j) per axis)`, t in loop samples of `N`: the
/// quad never turns, as spec §4.11 \[ENG\] asks (the apply of a centre trajectory is a rigid
/// translation of all four corners).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralMotion {
    /// Cosine series of the x, y and z translation.
    pub axes: [Components; 3],
    /// Loop samples `N` the frequencies and phases refer to (also the motion's sample count).
    pub samples: usize,
}

impl SpectralMotion {
    /// The translation at fractional loop sample `t` of [`Self::samples`].
    pub fn offset(&self, t: f32) -> Vec3 {
        Vec3::new(
            self.axes[0].value_at(t, self.samples),
            self.axes[1].value_at(t, self.samples),
            self.axes[2].value_at(t, self.samples),
        )
    }

    /// Number of cosine terms over all axes.
    pub fn terms(&self) -> usize {
        self.axes.iter().map(|a| a.amplitudes.len()).sum()
    }

    /// Drops the weakest terms while their amplitudes sum to less than `tolerance` (world
    /// units): `|Σ a cos(…)| ≤ Σ a`, so no point moves more than that from where the full
    /// series puts it. Returns the number dropped.
    pub fn prune(&mut self, tolerance: f32) -> usize {
        let mut terms: Vec<(f32, usize, usize)> = Vec::new();
        for (c, axis) in self.axes.iter().enumerate() {
            for (j, &a) in axis.amplitudes.iter().enumerate() {
                terms.push((a.abs(), c, j));
            }
        }
        terms.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut budget = 0.0f32;
        let mut drop: Vec<Vec<bool>> = self
            .axes
            .iter()
            .map(|a| vec![false; a.amplitudes.len()])
            .collect();
        for (a, c, j) in terms {
            if budget + a >= tolerance {
                break;
            }
            budget += a;
            drop[c][j] = true;
        }
        let mut dropped = 0;
        for (axis, d) in self.axes.iter_mut().zip(drop) {
            let mut keep = Components::none();
            for (j, &gone) in d.iter().enumerate() {
                if gone {
                    dropped += 1;
                    continue;
                }
                keep.frequencies.push(axis.frequencies[j]);
                keep.amplitudes.push(axis.amplitudes[j]);
                keep.phases.push(axis.phases[j]);
            }
            *axis = keep;
        }
        dropped
    }
}

impl RigidMotion {
    /// The transform at sample `s` of `n` uniform samples of the loop (`n` may differ from the
    /// number the motion was made with; the loop wraps).
    pub fn at(&self, s: usize, n: usize) -> Affine3A {
        match self {
            RigidMotion::Sampled(frames) => {
                if frames.is_empty() || n == 0 {
                    return Affine3A::IDENTITY;
                }
                if n == frames.len() {
                    return frames[s % n];
                }
                let x = (s % n) as f32 * frames.len() as f32 / n as f32;
                let k = x.floor() as usize % frames.len();
                let u = x - x.floor();
                interpolate(frames[k], frames[(k + 1) % frames.len()], u)
            }
            RigidMotion::Spectral(m) => {
                let t = if n == 0 {
                    0.0
                } else {
                    (s % n) as f32 * m.samples as f32 / n as f32
                };
                Affine3A::from_translation(m.offset(t))
            }
        }
    }

    /// The transforms at every one of `n` uniform samples of the loop ([`Self::at`]), for a
    /// caller that reads them many times (a spectral motion is a cosine series to evaluate).
    pub fn samples(&self, n: usize) -> Vec<Affine3A> {
        (0..n).map(|s| self.at(s, n)).collect()
    }

    /// Number of samples it carries.
    pub fn len(&self) -> usize {
        match self {
            RigidMotion::Sampled(f) => f.len(),
            RigidMotion::Spectral(m) => m.samples,
        }
    }

    /// True when it carries no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Rigid interpolation: slerp of rotations, lerp of translations.
fn interpolate(a: Affine3A, b: Affine3A, u: f32) -> Affine3A {
    let (_, ra, ta) = a.to_scale_rotation_translation();
    let (_, rb, tb) = b.to_scale_rotation_translation();
    Affine3A::from_rotation_translation(ra.slerp(rb, u), ta.lerp(tb, u))
}

/// What a billboard's texture is.
#[derive(Clone, Debug, PartialEq)]
pub enum BillboardTexture {
    /// Baked into the cloud's atlas.
    Atlas,
    /// The input's own material (index into `Tree::materials`): the billboard is one input card,
    /// copied with its texture mapping instead of baked (the hybrid cloud,
    /// [`frond_billboard::source_copy()`]). `texcoords[n]` holds the corners' `TEXCOORD_n` as the
    /// input stores them (no transform applied; empty for a tree without texture coordinates).
    Input {
        /// The input material whose texture the billboard samples.
        material: usize,
        /// The corners' texture coordinates, one set per `TEXCOORD_n`.
        texcoords: Vec<[Vec2; 4]>,
    },
}

/// One billboard of the cloud.
#[derive(Clone, Debug)]
pub struct AnimatedBillboard {
    /// The quad in the reference pose (see the module docs).
    pub quad: Quad,
    /// UVs of the corners in [`Quad::corners`] order: in the atlas, or the input's base-colour
    /// map coordinates (its `KHR_texture_transform` applied) for a [`BillboardTexture::Input`].
    pub uv: [Vec2; 4],
    /// Where `uv` points.
    pub texture: BillboardTexture,
    /// Rig node it follows, if any.
    pub follows: Option<usize>,
    /// Its own rigid motion relative to what it follows, if any.
    pub motion: Option<RigidMotion>,
    /// The input foliage triangles it replaces (indices into `Tree::triangles`).
    pub triangles: Vec<usize>,
}

/// A billboard cloud that moves: the output of a clustering method, the input of export.
#[derive(Clone, Debug)]
pub struct AnimatedBillboardCloud {
    /// How the billboards were made (`per-bone`, `static`, ...).
    pub method: String,
    /// Plane tolerance its planes were searched with (world units): the LOD's ε, or wider
    /// when its billboard budget asked for fewer planes.
    pub epsilon: f32,
    /// The billboards, each with its quad, texture and motion.
    pub billboards: Vec<AnimatedBillboard>,
    /// Colour (and normal) atlas all billboards sample.
    pub atlas: Atlas,
    /// Atlas texels per world unit the billboards were baked at.
    pub texels_per_unit: f32,
    /// The bake lowered the texel density to fit the atlas's largest side.
    pub density_reduced: bool,
    /// The LOD's skeleton: the tree's rig, pruned or rebuilt.
    pub rig: Rig,
    /// Some nodes' channels were resampled from the loop clock's clip alone (skeleton
    /// simplification): only that clip plays correctly.
    pub rig_resampled: bool,
    /// The samples [`RigidMotion`] refers to.
    pub clock: LoopClock,
    /// Clips the cloud can play correctly (indices into `rig.clips`): every clip when no
    /// billboard has its own motion and the rig was not resampled, only the clock's clip
    /// otherwise.
    pub playable_clips: Vec<usize>,
}

impl AnimatedBillboardCloud {
    /// The transform carrying billboard `i` from its reference pose to the world at motion
    /// sample `s` of `n`, given the rig's world matrices and inverse rest world matrices (see
    /// the module docs).
    pub fn transform_at(
        &self,
        i: usize,
        world: &[Mat4],
        rest_inv: &[Mat4],
        s: usize,
        n: usize,
    ) -> Mat4 {
        let b = &self.billboards[i];
        let m = Mat4::from(b.motion.as_ref().map_or(Affine3A::IDENTITY, |m| m.at(s, n)));
        match b.follows {
            Some(node) => world[node] * rest_inv[node] * m,
            None => m,
        }
    }

    /// World corners of billboard `i` at motion sample `s` of `n` ([`Self::transform_at`]).
    pub fn corners_at(
        &self,
        i: usize,
        world: &[Mat4],
        rest_inv: &[Mat4],
        s: usize,
        n: usize,
    ) -> [Vec3; 4] {
        let t = self.transform_at(i, world, rest_inv, s, n);
        self.billboards[i]
            .quad
            .corners()
            .map(|c| t.transform_point3(c))
    }

    /// Inverse rest world matrices of the rig's nodes (for [`Self::transform_at`]).
    pub fn rest_inverse(&self) -> Vec<Mat4> {
        self.rig.rest_world().iter().map(|m| m.inverse()).collect()
    }

    /// Billboards that copy an input card with its own texture ([`BillboardTexture::Input`]).
    pub fn input_textured(&self) -> usize {
        self.billboards
            .iter()
            .filter(|b| b.texture != BillboardTexture::Atlas)
            .count()
    }

    /// The billboards that copy input cards as one unskinned mesh with the input's materials
    /// (corners in the reference pose): what their textures cost is sized and counted with it
    /// ([`crate::texture_budget`]), like the wood's.
    pub fn input_textured_mesh(&self) -> WoodMesh {
        input_textured_mesh(self.billboards.iter().map(|b| (&b.quad, &b.uv, &b.texture)))
    }

    /// Recomputes which clips are playable from the billboards' motions.
    pub fn update_playable_clips(&mut self) {
        let own_motion = self.billboards.iter().any(|b| b.motion.is_some());
        self.playable_clips = if own_motion || self.rig_resampled {
            self.clock.clip.into_iter().collect()
        } else {
            (0..self.rig.clips.len()).collect()
        };
    }
}

/// The quads of `billboards` (quad, UVs, texture) that carry an input texture, as one unskinned
/// mesh: four corners and two triangles each, one primitive per material (ascending).
pub fn input_textured_mesh<'a>(
    billboards: impl Iterator<Item = (&'a Quad, &'a [Vec2; 4], &'a BillboardTexture)>,
) -> WoodMesh {
    let mut mesh = WoodMesh::default();
    let mut by_material: std::collections::BTreeMap<usize, Vec<u32>> = Default::default();
    for (quad, uv, texture) in billboards {
        let BillboardTexture::Input {
            material,
            texcoords,
        } = texture
        else {
            continue;
        };
        let base = mesh.positions.len() as u32;
        if mesh.texcoords.len() < texcoords.len() {
            mesh.texcoords
                .resize(texcoords.len(), vec![Vec2::ZERO; mesh.positions.len()]);
        }
        for (k, set) in mesh.texcoords.iter_mut().enumerate() {
            set.extend(texcoords.get(k).map_or([Vec2::ZERO; 4], |c| *c));
        }
        mesh.positions.extend(quad.corners());
        mesh.normals.extend([quad.plane.normal; 4]);
        mesh.uvs.extend(uv);
        mesh.bones.extend([[NO_BONE, NO_BONE, NO_BONE, NO_BONE]; 4]);
        mesh.weights.extend([[1.0, 0.0, 0.0, 0.0]; 4]);
        by_material.entry(*material).or_default().extend([
            base,
            base + 1,
            base + 2,
            base,
            base + 2,
            base + 3,
        ]);
    }
    mesh.primitives = by_material
        .into_iter()
        .map(|(material, indices)| WoodPrimitive { material, indices })
        .collect();
    mesh
}
