//! `cards`: the input's own leaf cards, thinned (the *card LOD*; SpeedTree's leaf reduction
//! and ez-tree's LODs do the same): the cards that add least to the tree's silhouette at the
//! LOD's pixel size are dropped until the rest fit the LOD's triangle budget ([`coverage`]),
//! and the survivors are grown about their centres by the scale that brings their coverage
//! closest to the input's. Cards are first trimmed to one triangle where their texture allows
//! ([`trim`]): half the triangles, so twice the cards within a budget. The cards stay skinned
//! as in the input and share its leaf material and texture: no bake, no atlas.

pub mod coverage;
pub mod trim;

use std::sync::Arc;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use frond_scene::wood::WoodMesh;
use frond_scene::{Part, Rig, Tree};

pub use crate::contract::CardFoliage;
use crate::error::LodError;
use crate::method_api::{
    BuildContext, ClusteringMethod, Foliage, MethodName, MethodOutput, MethodPlugin, MethodSection,
    uses_no_options,
};
use crate::part_mesh::{part_mesh, triangle_area};
use coverage::{CardCoverage, card_centre, card_vertices};
use trim::trim_cards;

/// `cards`' name.
pub const NAME: MethodName = MethodName::new("cards");

/// The key of the LOD report entry that [`CardReport`] is written under.
pub const SECTION: &str = "cards";

/// `cards` as the registry lists it.
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[("cards", NAME)],
    configure: |_, _, _| Ok(Arc::new(Cards)),
    uses: uses_no_options,
};

/// The `cards` method; it has no options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Cards;

/// What thinning did: the `cards` section of a card LOD's report entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CardReport {
    /// Cards of the input (connected pieces of foliage triangles).
    pub cards: usize,
    /// Cards drawn as one trimmed triangle ([`trim`]).
    pub trimmed: usize,
    /// Blended cards left as quads within the triangle budget: they bend when posed, which
    /// one triangle cannot follow.
    pub kept_as_quads: usize,
    /// Cards kept within the LOD's triangle budget.
    pub kept: usize,
    /// Linear scale of every kept card about its centre.
    pub scale: f32,
}

impl ClusteringMethod for Cards {
    fn name(&self) -> MethodName {
        NAME
    }

    /// Cards keep the input's own skinning: nothing of the sampled loop is read.
    fn needs_poses(&self) -> bool {
        false
    }

    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError> {
        let foliage = part_mesh(ctx.tree, Part::Foliage);
        if foliage.triangles() == 0 {
            return Err(LodError::NoFoliage(ctx.tree.source.display().to_string()));
        }
        let max_triangles = ctx.max_foliage_triangles.unwrap_or(usize::MAX);
        let budget = CardBudget {
            triangles: max_triangles,
            area: ctx.max_alpha_tested_area.unwrap_or(f64::INFINITY),
        };
        let (mut cards, report) =
            thin_cards(ctx.tree, &foliage, &budget, ctx.level.pixel, ctx.seed);
        cards.rig = ctx.tree.rig.clone();
        Ok(MethodOutput {
            foliage: Foliage::Cards(cards),
            timings: Default::default(),
            section: Some(MethodSection::new(SECTION, &report)?),
        })
    }
}

/// What a card LOD may spend on its cards.
#[derive(Clone, Copy, Debug)]
pub struct CardBudget {
    /// Most triangles.
    pub triangles: usize,
    /// Most card area (world units²): the previous LOD's alpha-tested area.
    pub area: f64,
}

/// Triangles a foliage piece may have and still count as one card: a quad (2), or a quad cut
/// into a few strips as some exporters do.
pub const CARD_TRIANGLES: usize = 4;

/// Whether `tree`'s foliage is made of single leaf cards (most pieces at most
/// [`CARD_TRIANGLES`] triangles): thinning such cards keeps the look of the leaves, where
/// thinning a mesh of leaf clusters would punch holes in them.
pub fn is_card_foliage(tree: &Tree) -> bool {
    let mesh = WoodMesh::from_tree_part(tree, Part::Foliage);
    let pieces = mesh.pieces();
    if pieces.is_empty() {
        return false;
    }
    let cards = pieces.iter().filter(|p| p.len() <= CARD_TRIANGLES).count();
    10 * cards >= 9 * pieces.len()
}

/// Keeps the cards of `foliage` that matter most to its silhouette at `pixel` world units per
/// pixel, at most `max_triangles` triangles of them (at least one card; see
/// [`CardCoverage::thin`]), each scaled about its centre by the smallest scale at which they
/// cover what all the cards covered ([`CardCoverage::coverage_keeping_scale`]), at most
/// `√(all cards' area / kept area)` (the leaf area kept) within the overdraw budget. `seed`
/// orders cards that are equally
/// redundant. Returns the cards (over no rig yet) and what thinning did.
pub fn thin_cards(
    tree: &Tree,
    foliage: &WoodMesh,
    budget: &CardBudget,
    pixel: f32,
    seed: u64,
) -> (CardFoliage, CardReport) {
    let max_triangles = budget.triangles;
    let trimmed = trim_cards(tree, foliage, max_triangles);
    let foliage = &trimmed.mesh;
    let cards = foliage.pieces();
    let area: Vec<f32> = cards
        .iter()
        .map(|c| c.iter().map(|&(p, t)| triangle_area(foliage, p, t)).sum())
        .collect();
    let mut order: Vec<u32> = (0..cards.len() as u32).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let mut tie = vec![0u32; cards.len()];
    for (rank, &c) in order.iter().enumerate() {
        tie[c as usize] = rank as u32;
    }
    let triangles: Vec<usize> = cards.iter().map(Vec::len).collect();
    let t0 = std::time::Instant::now();
    let coverage = CardCoverage::new(tree, foliage, &cards, &tree.bounds, pixel);
    let keep = coverage.thin(&triangles, max_triangles, &tie);
    let t1 = std::time::Instant::now();
    let kept = keep.iter().filter(|k| **k).count();
    let total: f32 = area.iter().sum();
    let kept_area: f32 = area
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(a, _)| a)
        .sum();
    let scale = if kept == cards.len() {
        1.0
    } else {
        let most = if kept_area > 0.0 {
            // The area-keeping scale, held to the overdraw budget (never below 1).
            (total.min(budget.area as f32) / kept_area).sqrt().max(1.0)
        } else {
            1.0
        };
        coverage.coverage_keeping_scale(&keep, most)
    };
    tracing::debug!(
        "cards: {} of {} kept in {:.2} s, scale {scale} chosen in {:.2} s",
        kept,
        cards.len(),
        (t1 - t0).as_secs_f64(),
        t1.elapsed().as_secs_f64()
    );
    let mut mesh = foliage.clone();
    for p in &mut mesh.primitives {
        p.indices.clear();
    }
    for (_, tris) in cards.iter().enumerate().filter(|(c, _)| keep[*c]) {
        let centre = card_centre(foliage, tris);
        for v in card_vertices(foliage, tris) {
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
    let foliage = CardFoliage {
        mesh: mesh.compacted(),
        rig: Rig::default(),
    };
    let report = CardReport {
        cards: cards.len(),
        trimmed: trimmed.cards,
        kept_as_quads: trimmed.kept_as_quads,
        kept,
        scale,
    };
    (foliage, report)
}
