//! `cards`: the input's own leaf cards, thinned (issue 17 item 6, the *card LOD*; SpeedTree's
//! leaf reduction and ez-tree's LODs do the same): a seeded random subset of the cards is
//! kept within the LOD's triangle budget and each survivor is scaled about its centre so that
//! the cards together keep the input's leaf area, and so roughly its coverage. The cards stay
//! skinned as in the input and share its leaf material and texture: no bake, no atlas.

use std::collections::HashMap;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use frond_scene::wood::WoodMesh;
use frond_scene::{Part, Rig, Tree};
use glam::Vec3;

use crate::chain::part_mesh;
use crate::error::LodError;
use crate::method::{BuildContext, ClusteringMethod, Foliage, MethodName, MethodOutput};

/// The `cards` method; it has no options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cards;

/// Thinned leaf cards, ready to be skinned like the input's.
#[derive(Clone, Debug)]
pub struct CardFoliage {
    /// The kept cards, scaled, bones as rig node indices, the input's foliage materials.
    pub mesh: WoodMesh,
    /// The skeleton the cards follow: the tree's, until the chain's budget prunes it.
    pub rig: Rig,
    pub report: CardReport,
}

/// What thinning did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CardReport {
    /// Cards of the input (connected pieces of foliage triangles).
    pub cards: usize,
    pub kept: usize,
    /// Linear scale of every kept card about its centre.
    pub scale: f32,
}

impl ClusteringMethod for Cards {
    fn name(&self) -> MethodName {
        MethodName::Cards
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let foliage = part_mesh(ctx.tree, Part::Foliage);
        if foliage.triangles() == 0 {
            return Err(LodError::NoFoliage(ctx.tree.source.display().to_string()));
        }
        let max_triangles = ctx.max_foliage_triangles.unwrap_or(usize::MAX);
        let mut cards = thin_cards(&foliage, max_triangles, ctx.seed);
        cards.rig = ctx.tree.rig.clone();
        Ok(MethodOutput {
            foliage: Foliage::Cards(cards),
            timings: Default::default(),
            report: Default::default(),
        })
    }
}

/// The connected pieces of `mesh`'s triangles (over shared vertex indices), as lists of
/// (primitive, triangle) in order of first triangle.
fn pieces(mesh: &WoodMesh) -> Vec<Vec<(usize, usize)>> {
    let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    for p in &mesh.primitives {
        for t in p.indices.chunks_exact(3) {
            let a = find(&mut parent, t[0] as usize);
            for &v in &t[1..] {
                let b = find(&mut parent, v as usize);
                if a != b {
                    parent[b] = a;
                }
            }
        }
    }
    let mut index: HashMap<usize, usize> = HashMap::new();
    let mut out: Vec<Vec<(usize, usize)>> = Vec::new();
    for (pi, p) in mesh.primitives.iter().enumerate() {
        for (ti, t) in p.indices.chunks_exact(3).enumerate() {
            let root = find(&mut parent, t[0] as usize);
            let k = *index.entry(root).or_insert_with(|| {
                out.push(Vec::new());
                out.len() - 1
            });
            out[k].push((pi, ti));
        }
    }
    out
}

/// Triangles a foliage piece may have and still count as one card: a quad (2), or a quad cut
/// into a few strips as some exporters do.
pub const CARD_TRIANGLES: usize = 4;

/// Whether `tree`'s foliage is made of single leaf cards (most pieces at most
/// [`CARD_TRIANGLES`] triangles): thinning such cards keeps the look of the leaves, where
/// thinning a mesh of leaf clusters would punch holes in them.
pub fn is_card_foliage(tree: &Tree) -> bool {
    let mesh = WoodMesh::from_tree_part(tree, Part::Foliage);
    let pieces = pieces(&mesh);
    if pieces.is_empty() {
        return false;
    }
    let cards = pieces.iter().filter(|p| p.len() <= CARD_TRIANGLES).count();
    10 * cards >= 9 * pieces.len()
}

/// Area of triangle `t` of primitive `p`.
fn triangle_area(mesh: &WoodMesh, p: usize, t: usize) -> f32 {
    let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
    let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[i[k] as usize]);
    0.5 * (b - a).cross(c - a).length()
}

/// Keeps a seeded random subset of `foliage`'s cards with at most `max_triangles` triangles
/// (at least one card), each scaled about its centre by `√(all cards' area / kept area)`.
pub fn thin_cards(foliage: &WoodMesh, max_triangles: usize, seed: u64) -> CardFoliage {
    let cards = pieces(foliage);
    let area: Vec<f32> = cards
        .iter()
        .map(|c| c.iter().map(|&(p, t)| triangle_area(foliage, p, t)).sum())
        .collect();
    let mut order: Vec<usize> = (0..cards.len()).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let mut keep = vec![false; cards.len()];
    let mut triangles = 0;
    let mut kept = 0;
    for &c in &order {
        if kept > 0 && triangles + cards[c].len() > max_triangles {
            continue;
        }
        keep[c] = true;
        triangles += cards[c].len();
        kept += 1;
    }
    let total: f32 = area.iter().sum();
    let kept_area: f32 = area
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(a, _)| a)
        .sum();
    let scale = if kept_area > 0.0 {
        (total / kept_area).sqrt()
    } else {
        1.0
    };
    let mut mesh = foliage.clone();
    for p in &mut mesh.primitives {
        p.indices.clear();
    }
    for (_, tris) in cards.iter().enumerate().filter(|(c, _)| keep[*c]) {
        let mut verts: Vec<u32> = tris
            .iter()
            .flat_map(|&(p, t)| foliage.primitives[p].indices[3 * t..3 * t + 3].to_vec())
            .collect();
        verts.sort_unstable();
        verts.dedup();
        let centre: Vec3 = verts
            .iter()
            .map(|&v| foliage.positions[v as usize])
            .sum::<Vec3>()
            / verts.len() as f32;
        for &v in &verts {
            let p = &mut mesh.positions[v as usize];
            *p = centre + (*p - centre) * scale;
        }
        for &(p, t) in tris {
            mesh.primitives[p]
                .indices
                .extend_from_slice(&foliage.primitives[p].indices[3 * t..3 * t + 3]);
        }
    }
    mesh.primitives.retain(|p| !p.indices.is_empty());
    CardFoliage {
        mesh: mesh.compacted(),
        rig: Rig::default(),
        report: CardReport {
            cards: cards.len(),
            kept,
            scale,
        },
    }
}
