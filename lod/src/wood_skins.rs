//! The skins of a LOD's wood and cards once the joint budget has removed joints (spec
//! view-dependent-hierarchies-gpu §2.4): each vertex that followed a removed joint gets weights
//! over the kept joints near it, fitted to the path it had in the input ([`SkinFit`]).
//!
//! The joint budget's rigid rule moves what a removed joint carried to its placement in one
//! kept joint (where it sits relative to that joint over the loop); the fit starts from there.
//! A fit at the input's own rest position can do better still (a point halfway between two
//! swaying joints is their blend exactly where it was modelled), so a branch tries both rest
//! positions, one for the whole connected piece: mixing them would tear it at rest. A card
//! stays a card: its corners may not bend more than [`MAX_CARD_BEND`] of its diagonal away
//! from its best rigid motion, and one blend for all its corners (an affine motion: flat),
//! fitted at either rest position, is the fallback.

use frond_scene::Bounds;
use frond_scene::wood::{NO_BONE, WoodMesh};
use glam::Vec3;
use rayon::prelude::*;

use crate::methods::cards::CARD_TRIANGLES;
use crate::skin_fit::{Point, Skin, SkinFit};

/// How far a card's corners may stray from the card's best rigid motion over the loop, as a
/// fraction of its diagonal: a card that bends more no longer reads as the flat leaf it is.
pub const MAX_CARD_BEND: f32 = 0.1;

/// The wood as it was before the joint budget's merges: what each vertex's input path is
/// read from, and where a piece fitted at its input rest position goes back to.
pub struct InputSkins {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    bones: Vec<[u32; 4]>,
    weights: Vec<[f32; 4]>,
}

impl InputSkins {
    /// `wood`'s positions, normals and skins now.
    pub fn of(wood: &WoodMesh) -> InputSkins {
        InputSkins {
            positions: wood.positions.clone(),
            normals: wood.normals.clone(),
            bones: wood.bones.clone(),
            weights: wood.weights.clone(),
        }
    }

    fn skin(&self, v: usize) -> Skin {
        (self.bones[v], self.weights[v])
    }
}

/// The joints the budget kept, as the fit sees them.
pub struct KeptJoints {
    /// Per rig node, the kept joints (`NO_BONE`: the world) a vertex that followed it may be
    /// fitted over.
    pub pools: Vec<Vec<u32>>,
    /// Per rig node, whether the budget removed it.
    pub removed: Vec<bool>,
}

impl KeptJoints {
    /// Whether `skin` follows a removed joint.
    fn touches(&self, skin: &Skin) -> bool {
        (0..4).any(|j| {
            skin.1[j] > 0.0
                && skin.0[j] != NO_BONE
                && self
                    .removed
                    .get(skin.0[j] as usize)
                    .copied()
                    .unwrap_or(false)
        })
    }

    /// The kept joints the vertices of `skins` may be fitted over, without repeats.
    fn candidates(&self, skins: &[Skin]) -> Vec<u32> {
        let mut out: Vec<u32> = Vec::new();
        for (b, w) in skins {
            for j in (0..4).filter(|&j| w[j] > 0.0) {
                for c in self.pools.get(b[j] as usize).into_iter().flatten() {
                    if !out.contains(c) {
                        out.push(*c);
                    }
                }
            }
        }
        out
    }
}

/// Refits the skins of `wood` (after the joint budget's rigid rule: vertices at their
/// placements, joints resolved to kept ones) piece by piece, by the rule the module states;
/// `input` is the wood before the merges.
pub fn refit_skins(fit: &SkinFit, kept: &KeptJoints, wood: &mut WoodMesh, input: &InputSkins) {
    let used = used_vertices(wood);
    let nv = wood.positions.len().min(input.positions.len());
    let pieces: Vec<(Vec<usize>, usize)> = piece_vertices(wood)
        .into_iter()
        .filter(|(vs, _)| {
            vs.iter()
                .any(|&v| v < nv && used[v] && kept.touches(&input.skin(v)))
        })
        .collect();
    let chosen: Vec<(Vec<usize>, PieceSkins)> = pieces
        .into_par_iter()
        .map(|(vs, triangles)| {
            let skins = piece_skins(fit, kept, wood, input, (&vs, triangles));
            (vs, skins)
        })
        .collect();
    for (vs, skins) in chosen {
        for (k, &v) in vs.iter().enumerate() {
            wood.bones[v] = skins.skins[k].0;
            wood.weights[v] = skins.skins[k].1;
            if skins.input_rest {
                wood.positions[v] = input.positions[v];
                if let (Some(n), Some(n0)) = (wood.normals.get_mut(v), input.normals.get(v)) {
                    *n = *n0;
                }
            }
        }
    }
}

/// A piece's chosen skins, one per vertex, and whether they are at the input's rest positions
/// (else at the rigid rule's placements).
struct PieceSkins {
    skins: Vec<Skin>,
    input_rest: bool,
}

/// One way to skin a piece, with its summed miss over the loop.
struct Choice {
    skins: PieceSkins,
    miss: f64,
}

/// The skins of piece `vs` (of `triangles` triangles) of `wood`. A branch: of the rigid rule's
/// skins, each vertex's own fit at the placed rest positions and each vertex's own fit at the
/// input's, the one that follows the input most closely. A card (at most
/// [`CARD_TRIANGLES`]): of the rigid rule's skins and its corners' own fits at the placed rest,
/// the closest that bends at most [`MAX_CARD_BEND`] of its diagonal; failing both, one blend
/// fitted for all its corners at either rest; failing all, the least bent. Each vertex's fit
/// starts from the rigid rule's skin, so a branch never follows the input less closely than
/// the rigid rule does.
fn piece_skins(
    fit: &SkinFit,
    kept: &KeptJoints,
    wood: &WoodMesh,
    input: &InputSkins,
    (vs, triangles): (&[usize], usize),
) -> PieceSkins {
    let targets: Vec<Vec<Vec3>> = vs
        .iter()
        .map(|&v| fit.path(input.positions[v], &input.skin(v)))
        .collect();
    let rigid: Vec<Skin> = vs
        .iter()
        .map(|&v| (wood.bones[v], wood.weights[v]))
        .collect();
    let placed: Vec<Vec3> = vs.iter().map(|&v| wood.positions[v]).collect();
    let modelled: Vec<Vec3> = vs.iter().map(|&v| input.positions[v]).collect();
    let inputs: Vec<Skin> = vs.iter().map(|&v| input.skin(v)).collect();
    let option = |skins: Vec<Skin>, input_rest: bool| -> Choice {
        let rest = if input_rest { &modelled } else { &placed };
        let miss = rest
            .iter()
            .zip(&skins)
            .zip(&targets)
            .map(|((p, s), t)| fit.miss(*p, s, t))
            .sum();
        Choice {
            skins: PieceSkins { skins, input_rest },
            miss,
        }
    };
    let own = |input_rest: bool| -> Vec<Skin> {
        let rest = if input_rest { &modelled } else { &placed };
        (0..vs.len())
            .into_par_iter()
            .map(|k| match kept.touches(&inputs[k]) {
                true => {
                    let mine = kept.candidates(&inputs[k..=k]);
                    fit.fit(rest[k], &targets[k], &mine, &rigid[k]).0
                }
                false => rigid[k],
            })
            .collect()
    };
    let card = triangles <= CARD_TRIANGLES;
    // A card's corners fitted at the input's rest lose to the placed ones on most cards, and
    // the shared blend below covers the rest: half the fitting.
    let mut options = vec![option(rigid.clone(), false), option(own(false), false)];
    if !card {
        options.push(option(own(true), true));
    }
    options.sort_by(|a, b| a.miss.total_cmp(&b.miss));
    if !card {
        return options.swap_remove(0).skins;
    }
    // A card: the closest that stays flat; one blend for all its corners only when no skin
    // of its corners' own does.
    let limit = MAX_CARD_BEND * Bounds::of(placed.iter().copied()).diagonal();
    let bend = |c: &Choice| {
        let rest = if c.skins.input_rest {
            &modelled
        } else {
            &placed
        };
        fit.bend(rest, &c.skins.skins, limit)
    };
    let mut bends: Vec<f32> = Vec::with_capacity(5);
    for o in &options {
        bends.push(bend(o));
        if bends[bends.len() - 1] <= limit {
            return options.swap_remove(bends.len() - 1).skins;
        }
    }
    let candidates = kept.candidates(&inputs);
    let mut shared: Vec<Choice> = [false, true]
        .into_iter()
        .map(|input_rest| {
            let rest = if input_rest { &modelled } else { &placed };
            let points: Vec<Point> = rest
                .iter()
                .zip(&targets)
                .map(|(p, t)| (*p, t.as_slice()))
                .collect();
            let one = fit.fit_points(&points, &candidates, &rigid[0]).0;
            option(vec![one; vs.len()], input_rest)
        })
        .collect();
    shared.sort_by(|a, b| a.miss.total_cmp(&b.miss));
    for o in shared {
        bends.push(bend(&o));
        if bends[bends.len() - 1] <= limit {
            return o.skins;
        }
        options.push(o);
    }
    let least = (0..options.len())
        .min_by(|&a, &b| bends[a].total_cmp(&bends[b]))
        .unwrap_or(0);
    options.swap_remove(least).skins
}

/// The vertices of each connected piece of `wood` (shared vertex indices), each piece's in
/// first-use order, with its triangle count.
fn piece_vertices(wood: &WoodMesh) -> Vec<(Vec<usize>, usize)> {
    let mut seen = vec![false; wood.positions.len()];
    wood.pieces()
        .into_iter()
        .map(|p| {
            let mut vs: Vec<usize> = Vec::new();
            for &(pi, t) in &p {
                for &v in &wood.primitives[pi].indices[3 * t..3 * t + 3] {
                    if !std::mem::replace(&mut seen[v as usize], true) {
                        vs.push(v as usize);
                    }
                }
            }
            (vs, p.len())
        })
        .collect()
}

/// Whether each vertex of `wood` is drawn (used by a primitive).
pub fn used_vertices(wood: &WoodMesh) -> Vec<bool> {
    let mut used = vec![false; wood.positions.len()];
    for p in &wood.primitives {
        for &i in &p.indices {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
    }
    used
}
