//! Builds an [`AnimatedBillboardCloud`] from clusters of foliage triangles: one stochastic
//! billboard cloud per cluster, all baked into one atlas, each billboard moving with the
//! cluster's driver (spec animated-billboard-clouds §1.4, §2.4, §6 "Bone Clustering"; thesis
//! §5.2.2 for the rigid fit of a static cloud).

use std::time::Instant;

use frond_render::materials_scene;
use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;

use frond_billboard::bake::{BakeError, MAX_ATLAS_SIDE};
use frond_billboard::cloud::{CloudError, fit_quad};
use frond_billboard::plane_search::{PlaneSearch, search_planes, valid_for_plane};
use frond_billboard::quad_split::{QuadGroup, split_quads};
use frond_billboard::view_coverage::{CoverageViews, bake_keeping_view_coverage};
use frond_billboard::{BakeParams, BakedCloud};
use frond_billboard::{Plane, Quad, TriangleSoup, source_copy};
use frond_scene::Rig;
use frond_scene::rigid_fit::rigid_fit;
use frond_scene::wood::WoodMesh;

use crate::contract::{
    AnimatedBillboard, AnimatedBillboardCloud, BillboardTexture, LoopClock, RigidMotion,
    input_textured_mesh,
};
use crate::cost_budget::is_impostor_class;
use crate::error::LodError;
pub use crate::method_api::BuildTimings;
use crate::method_api::{BuildContext, Foliage, MethodName, MethodOutput};
use crate::texture_budget::{atlas_bytes, atlas_side_for_bytes};
use crate::texture_budget::{lod_image_sizes, parts_image_bytes};

/// How a cluster's billboards move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Driver {
    /// Rigidly with a rig node: the cloud is built in that node's rest frame (exact for
    /// triangles bound to it alone).
    Node(usize),
    /// Each billboard gets the best rigid fit of its triangles' sampled motion; the cloud is
    /// built in the average pose.
    RigidFit,
    /// Built in the average pose with no motion yet: the caller gives each billboard its
    /// own (spectral clustering, [`crate::methods::spectral`]).
    Assigned,
}

/// A set of foliage triangles that share one billboard cloud.
#[derive(Clone, Debug)]
pub struct FoliageCluster {
    /// Indices into `Sampled::foliage` (and so into its trajectories).
    pub members: Vec<usize>,
    /// How the cluster's billboards move.
    pub driver: Driver,
}

/// One billboard of a cluster: its quad, the triangles it replaces and those drawn on it.
type ClusterQuad = (Quad, Vec<usize>, Vec<usize>);

/// Every cluster's billboards in one list, in cluster order: each quad, the triangles it
/// replaces, those drawn on it and its cluster's driver.
struct QuadLists {
    quads: Vec<Quad>,
    owns: Vec<Vec<usize>>,
    drawn: Vec<Vec<usize>>,
    drivers: Vec<Driver>,
}

impl QuadLists {
    fn of(clusters: &[FoliageCluster], per_cluster: Vec<Vec<ClusterQuad>>) -> QuadLists {
        let mut lists = QuadLists {
            quads: Vec::new(),
            owns: Vec::new(),
            drawn: Vec::new(),
            drivers: Vec::new(),
        };
        for (cluster, list) in clusters.iter().zip(per_cluster) {
            for (q, own, d) in list {
                lists.quads.push(q);
                lists.owns.push(own);
                lists.drawn.push(d);
                lists.drivers.push(cluster.driver);
            }
        }
        lists
    }
}

/// The rig's world matrices at every sample of `clock`.
pub fn sampled_worlds(rig: &Rig, clock: &LoopClock) -> Vec<Vec<Mat4>> {
    (0..clock.samples.max(1))
        .into_par_iter()
        .map(|s| rig.world_at(clock.clip, clock.time(s)))
        .collect()
}

/// The LOD of a method that only groups the foliage: `clusters` built over the tree's own rig
/// (per-bone, static), with nothing else to report.
pub fn clustered_foliage(
    ctx: &BuildContext,
    clusters: &[FoliageCluster],
    method: MethodName,
) -> Result<MethodOutput, LodError> {
    let (cloud, timings) =
        build_animated_cloud(ctx, ctx.tree.rig.clone(), false, clusters, method.name())?;
    Ok(MethodOutput {
        foliage: Foliage::Cloud(cloud),
        timings,
        section: None,
    })
}

/// Builds the animated cloud of `clusters` for the LOD of `ctx`: one stochastic billboard
/// cloud per cluster, all baked into one atlas. `rig` is the LOD's skeleton (the tree's own,
/// or a simplified one whose node indices extend the tree's: `rig_resampled` when some of its
/// channels were resampled from the clock's clip), `method` the name the report writes.
pub fn build_animated_cloud(
    ctx: &BuildContext,
    rig: Rig,
    rig_resampled: bool,
    clusters: &[FoliageCluster],
    method: &str,
) -> Result<(AnimatedBillboardCloud, BuildTimings), CloudError> {
    let (tree, params) = (ctx.tree, ctx.cloud);
    let clock = ctx.clock.clone();
    let mut timings = BuildTimings::default();
    let t0 = Instant::now();
    let mut soup = reference_soup(ctx, &rig, &clock, clusters);
    let t1 = Instant::now();
    timings.reference_pose = (t1 - t0).as_secs_f64();

    let (per_cluster, epsilon) = cluster_quads(ctx, &soup, clusters);
    let t2 = Instant::now();
    timings.plane_search = (t2 - t1).as_secs_f64();

    let QuadLists {
        mut quads,
        owns,
        mut drawn,
        drivers,
    } = QuadLists::of(clusters, per_cluster);
    if quads.is_empty() {
        return Err(CloudError::Empty);
    }
    if let Some(wood) = ctx.baked_wood {
        draw_wood_on_nearest_quads(
            &mut soup,
            wood,
            &mut quads,
            &mut drawn,
            ctx.max_alpha_tested_area,
        );
    }
    // A billboard that its own triangles tile (one leaf card) keeps the card's texture; only
    // the others are baked (the hybrid cloud).
    let mut copies = source_copies(ctx, &soup, &mut quads, &owns);
    let mut bake_params = params.bake.clone();
    let copied_bytes = {
        let mesh = input_textured_mesh(
            quads
                .iter()
                .zip(&copies)
                .filter_map(|(q, c)| c.as_ref().map(|(uv, t)| (q, uv, t))),
        );
        let parts = std::slice::from_ref(&mesh);
        parts_image_bytes(
            tree,
            parts,
            &lod_image_sizes(tree, parts, None, ctx.level.texels_per_unit),
        )
    };
    // The atlas's bytes at its largest side, normal atlas included: what the LOD's texture
    // budget gave the foliage.
    let budget_bytes = atlas_bytes(bake_params.max_atlas);
    if copied_bytes > budget_bytes / 2 || is_impostor_class(ctx.level.screen_height) {
        // The input's textures would take most of the budget (a far LOD whose quads are single
        // cards), or an impostor-class LOD would draw them besides its atlas (its budget is two
        // draw calls, wood and foliage): every quad is baked instead, at the atlas's density.
        copies.iter_mut().for_each(|c| *c = None);
    } else if copied_bytes > 0 {
        // The copies' textures come out of the atlas's share of the texture budget.
        bake_params.max_atlas = bake_params
            .max_atlas
            .min(atlas_side_for_bytes(budget_bytes - copied_bytes));
    }
    let bake: Vec<usize> = (0..quads.len()).filter(|&i| copies[i].is_none()).collect();
    let baked = if bake.is_empty() {
        None
    } else {
        let bake_quads: Vec<Quad> = bake.iter().map(|&i| quads[i]).collect();
        let bake_drawn: Vec<Vec<usize>> = (bake.iter())
            .map(|&i| std::mem::take(&mut drawn[i]))
            .collect();
        Some(bake_growing_atlas(
            ctx,
            &soup,
            &bake_quads,
            &bake_drawn,
            &mut bake_params,
        )?)
    };
    let t3 = Instant::now();
    timings.bake = (t3 - t2).as_secs_f64();

    let mut baked_uvs = baked.iter().flat_map(|b| b.uv_rects.iter().copied());
    let textures: Vec<([Vec2; 4], BillboardTexture)> = copies
        .into_iter()
        .map(|c| {
            c.unwrap_or_else(|| {
                (
                    baked_uvs.next().unwrap_or_default(),
                    BillboardTexture::Atlas,
                )
            })
        })
        .collect();
    let mut billboards = animated_billboards(ctx, &soup, &quads, &owns, &drivers, textures);
    // Baked billboards first, then the copies by material: the order export writes them in
    // (one primitive per texture), so the mapping sidecar's billboard k is the file's quad k.
    billboards.sort_by_key(|b| match b.texture {
        BillboardTexture::Atlas => 0,
        BillboardTexture::Input { material, .. } => 1 + material,
    });
    timings.motion_fit = t3.elapsed().as_secs_f64();
    let (atlas, texels_per_unit, density_reduced) = match baked {
        Some(b) => (b.atlas, b.texels_per_unit, b.density_reduced),
        None => (Default::default(), params.bake.texels_per_unit, false),
    };
    let mut cloud = AnimatedBillboardCloud {
        method: method.to_string(),
        epsilon,
        billboards,
        atlas,
        texels_per_unit,
        density_reduced,
        rig,
        rig_resampled,
        clock,
        playable_clips: Vec::new(),
    };
    cloud.update_playable_clips();
    Ok((cloud, timings))
}

/// Bakes `quads`, each with the triangles of `soup` `drawn` on it, into one atlas: only the
/// soup's materials drawn, an impostor-class LOD's bake keeping its leaves' view coverage
/// ([`view_coverage_views`]). The atlas budget holds as many billboards as the chain allowed
/// for it; one that a method could not fit (too few texels even at the smallest texture per
/// quad) doubles until it fits, and the report shows it over its texture budget.
fn bake_growing_atlas(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    quads: &[Quad],
    drawn: &[Vec<usize>],
    params: &mut BakeParams,
) -> Result<BakedCloud, CloudError> {
    let mut used = vec![false; ctx.tree.materials.len()];
    for &m in &soup.material {
        if let Some(f) = used.get_mut(m as usize) {
            *f = true;
        }
    }
    let draw = materials_scene(ctx.tree, &used);
    let views = view_coverage_views(ctx);
    loop {
        let baked = bake_keeping_view_coverage(
            ctx.renderer,
            soup,
            &draw.materials,
            &draw.textures,
            quads,
            drawn,
            params,
            views.as_ref(),
        );
        match baked {
            Ok((baked, ratio)) => {
                if let Some(ratio) = ratio {
                    tracing::debug!(
                        "LOD{}: view coverage {ratio:.3} of the leaves'",
                        ctx.index + 1
                    );
                }
                return Ok(baked);
            }
            Err(BakeError::AtlasTooSmall { .. }) if params.max_atlas < MAX_ATLAS_SIDE => {
                params.max_atlas = (params.max_atlas * 2).min(MAX_ATLAS_SIDE);
            }
            Err(e) => return Err(e.into()),
        }
    }
}

/// Adds `wood`'s triangles (rest pose) to `soup` and each to the `drawn` list of the quad that
/// shows it best: the far end's branches too thin to keep as triangles, baked with the leaves
/// as the covered fraction they add. A triangle goes to the quad nearest it, the distance
/// divided by how squarely the quad faces it (at least [`WOOD_MIN_FACING`]), so a branch is not
/// flattened onto a quad seen edge-on from where the branch shows; the quad grows to hold the
/// triangle's projection, so no branch is cut at a quad's edge (a trunk below the crown
/// extends the lowest quads), while the quads' area stays within `max_area` (the LOD's drawn
/// area; the largest triangles grow their quads first, a triangle past it is drawn cut). The
/// wood joins no cluster and replaces nothing: the planes, the
/// clusters' motion and the billboards' count are the leaves' alone; each branch moves with
/// the billboard it is drawn on.
fn draw_wood_on_nearest_quads(
    soup: &mut TriangleSoup,
    wood: &WoodMesh,
    quads: &mut [Quad],
    drawn: &mut [Vec<usize>],
    max_area: Option<f64>,
) {
    let triangles: Vec<(usize, [Vec3; 3], [Vec2; 3])> = (wood.primitives.iter())
        .flat_map(|p| {
            (p.indices.chunks_exact(3)).map(move |t| {
                let corners = [t[0], t[1], t[2]].map(|i| wood.positions[i as usize]);
                let uvs = [t[0], t[1], t[2]].map(|i| wood.uvs[i as usize]);
                (p.material, corners, uvs)
            })
        })
        .collect();
    let shown_on = |corners: &[Vec3; 3]| -> usize {
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let score = |q: &Quad| {
            let facing = q.plane.normal.dot(normal).abs().max(WOOD_MIN_FACING);
            q.distance_to(centroid) / facing
        };
        (0..quads.len())
            .min_by(|&a, &b| score(&quads[a]).total_cmp(&score(&quads[b])))
            .unwrap_or(0)
    };
    let chosen: Vec<usize> = triangles.par_iter().map(|(_, c, _)| shown_on(c)).collect();
    // Growth within the drawn-area budget, the largest triangles (the trunk's) first.
    let mut area: f64 = quads.iter().map(|q| f64::from(q.area())).sum();
    let size: Vec<f32> = (triangles.iter())
        .map(|(_, [a, b, c], _)| 0.5 * (*b - *a).cross(*c - *a).length())
        .collect();
    let mut by_size: Vec<usize> = (0..triangles.len()).collect();
    by_size.sort_by(|&a, &b| size[b].total_cmp(&size[a]).then(a.cmp(&b)));
    for t in by_size {
        let q = chosen[t];
        let grown = grown_to_hold(&quads[q], &triangles[t].1);
        let after = area + f64::from(grown.area() - quads[q].area());
        if max_area.is_none_or(|max| after <= max) {
            area = after;
            quads[q] = grown;
        }
    }
    for ((material, corners, uvs), q) in triangles.into_iter().zip(chosen) {
        drawn[q].push(soup.len());
        soup.positions.push(corners);
        soup.uvs.push(uvs);
        soup.material.push(material as u32);
    }
}

/// How squarely a quad must face a wood triangle at least, in [`draw_wood_on_nearest_quads`]'s
/// choice: a quad seen edge-on from the triangle's normal counts as five times as far.
const WOOD_MIN_FACING: f32 = 0.2;

/// `quad` grown in its plane to hold the projection of `points`.
fn grown_to_hold(quad: &Quad, points: &[Vec3]) -> Quad {
    let (mut lo, mut hi) = (-quad.half_size, quad.half_size);
    for p in points {
        let d = *p - quad.center;
        let uv = Vec2::new(d.dot(quad.axis_u), d.dot(quad.axis_v));
        lo = lo.min(uv);
        hi = hi.max(uv);
    }
    let mid = 0.5 * (lo + hi);
    Quad {
        center: quad.center + quad.axis_u * mid.x + quad.axis_v * mid.y,
        half_size: 0.5 * (hi - lo),
        ..*quad
    }
}

/// Views on the measure's rings (5 a ring at 0° and 30°, spec animated-billboard-clouds §5.4)
/// at which an impostor-class LOD's bake keeps its leaves' covered area
/// ([`bake_keeping_view_coverage`]): there a crown is a few hundred pixels and every billboard
/// averages many leaves, so what their planes lose seen from the side shows as a thinner
/// tree. Nearer LODs keep each billboard's own rule (their billboards hold few leaves each).
fn view_coverage_views(ctx: &BuildContext) -> Option<CoverageViews> {
    is_impostor_class(ctx.level.screen_height).then(|| CoverageViews {
        views_per_ring: 5,
        elevations_deg: vec![0.0, 30.0],
        pixel: ctx.level.pixel,
        // At least 512 samples over the tree's height, as the measure draws it.
        samples_per_side: (512.0 / ctx.level.screen_height.max(1.0))
            .ceil()
            .clamp(2.0, 64.0) as u32,
    })
}

/// Every foliage triangle in its cluster's reference frame: the average pose for rigid-fit and
/// assigned clusters, the loop's average in the node's rest frame for node-driven ones.
fn reference_soup(
    ctx: &BuildContext,
    rig: &Rig,
    clock: &LoopClock,
    clusters: &[FoliageCluster],
) -> TriangleSoup {
    let (tree, sampled) = (ctx.tree, ctx.sampled);
    let worlds = sampled_worlds(rig, clock);
    let rest = rig.rest_world();
    let n = sampled.samples();
    let nv = sampled.vertices;
    // Reference positions of every foliage triangle, in its cluster's frame.
    let mut reference: Vec<[Vec3; 3]> = vec![[Vec3::ZERO; 3]; sampled.foliage.len()];
    for cluster in clusters {
        match cluster.driver {
            Driver::RigidFit | Driver::Assigned => {
                for &k in &cluster.members {
                    let tri = &tree.triangles[sampled.foliage[k]];
                    reference[k] = tri.v.map(|v| sampled.average[v as usize]);
                }
            }
            Driver::Node(node) => {
                // Rest_b · W_b(s)⁻¹ · p_s, averaged over the loop.
                let to_rest: Vec<Mat4> = worlds
                    .iter()
                    .map(|w| rest[node] * w[node].inverse())
                    .collect();
                let refs: Vec<(usize, [Vec3; 3])> = cluster
                    .members
                    .par_iter()
                    .map(|&k| {
                        let tri = &tree.triangles[sampled.foliage[k]];
                        let corners = tri.v.map(|v| {
                            let sum: Vec3 = (0..n)
                                .map(|s| {
                                    to_rest[s.min(to_rest.len() - 1)]
                                        .transform_point3(sampled.positions[s * nv + v as usize])
                                })
                                .sum();
                            sum / n as f32
                        });
                        (k, corners)
                    })
                    .collect();
                for (k, c) in refs {
                    reference[k] = c;
                }
            }
        }
    }
    TriangleSoup {
        positions: reference,
        uvs: sampled
            .foliage
            .iter()
            .map(|&t| tree.triangles[t].v.map(|v| tree.vertices.uv[v as usize]))
            .collect(),
        material: sampled
            .foliage
            .iter()
            .map(|&t| tree.triangles[t].material)
            .collect(),
    }
}

/// One plane search per cluster, each with its own seed derived from the cluster's index:
/// every cluster's quads with the triangles they replace and those drawn on them.
/// Searches the planes of every cluster at `epsilon` (in parallel).
fn search_clusters(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    clusters: &[FoliageCluster],
    epsilon: f32,
    max_planes: &(dyn Fn(usize) -> Option<usize> + Sync),
) -> Vec<(TriangleSoup, PlaneSearch)> {
    clusters
        .par_iter()
        .enumerate()
        .map(|(ci, cluster)| {
            let sub = TriangleSoup {
                positions: cluster.members.iter().map(|&k| soup.positions[k]).collect(),
                uvs: cluster.members.iter().map(|&k| soup.uvs[k]).collect(),
                material: cluster.members.iter().map(|&k| soup.material[k]).collect(),
            };
            let mut sp = ctx.cloud.search.clone();
            sp.epsilon = epsilon;
            sp.max_planes = max_planes(ci);
            sp.seed = sp
                .seed
                .wrapping_add((ci as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let search = search_planes(&sub, &sp, ctx.scale);
            (sub, search)
        })
        .collect()
}

/// Plane searches tried to fit the billboard budget before the plane count is capped outright.
const EPSILON_TRIES: usize = 6;

/// The most [`budgeted_search`] widens ε for the atlas's sake, as a multiple of the LOD's ε
/// (one pixel by default): a leaf up to two pixels off its place is the price of texels enough
/// to keep the crown's coverage at far LODs; near LODs, whose atlases hold far fewer texels
/// than pixels anyway, would pay more in parallax than they gained.
const MAX_AREA_WIDENING: f32 = 2.0;

/// Share of the atlas's texels the quads' own texels take once packed (the rest is padding
/// and packing gaps): what [`budgeted_search`] counts on when it sizes the quads' area.
const ATLAS_FILL: f32 = 0.6;

/// The planes of every cluster within the LOD's billboard budget
/// ([`BuildContext::max_billboards`]) and its atlas: searched at the LOD's ε; while there are
/// too many planes, or their quads cover more area than the atlas holds at the LOD's texel
/// density (about one texel per pixel, spec view-dependent-hierarchies-gpu §2.4), ε grows:
/// by `(planes / budget)^1.5` (the plane count falls roughly as ε^-⅔ on the shared trees) or
/// `(area / atlas area)^0.7` (the area falls about as ε^-1.5), until they fit; then ε is
/// bisected (geometrically) between the last ε that did not fit and the smallest that does,
/// for [`EPSILON_TRIES`] searches in all: the smallest ε found that fits wins. Widening ε
/// rather than dropping leaves: a wider slab of leaves on each plane, every leaf still on one.
/// If none fits, each cluster keeps its share of the billboard budget (largest remainders, at
/// least one plane) and joins its leftovers to its nearest plane. Returns the searches and the
/// ε they used.
fn budgeted_search(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    clusters: &[FoliageCluster],
) -> (Vec<(TriangleSoup, PlaneSearch)>, f32) {
    let epsilon = ctx.cloud.search.epsilon;
    let planes =
        |r: &[(TriangleSoup, PlaneSearch)]| r.iter().map(|(_, s)| s.clusters.len()).sum::<usize>();
    let first = search_clusters(ctx, soup, clusters, epsilon, &|_| None);
    let Some(budget) = ctx.max_billboards else {
        return (first, epsilon);
    };
    let budget = budget.max(clusters.len());
    let density = ctx.level.texels_per_unit;
    let atlas_area = if density > 0.0 {
        ATLAS_FILL * (ctx.cloud.bake.max_atlas as f32).powi(2) / (density * density)
    } else {
        f32::INFINITY
    };
    // How far over its budgets a search at `e` is: 1 or less when it fits. The atlas widens ε
    // to at most MAX_AREA_WIDENING times the LOD's: beyond it, parallax costs more than texels.
    let area_cap = MAX_AREA_WIDENING * epsilon;
    let over_by = |r: &[(TriangleSoup, PlaneSearch)], e: f32| -> f32 {
        let by_planes = (planes(r) as f32 / budget as f32).powf(1.5);
        let by_area = if e < area_cap {
            (quad_area(r) / atlas_area).powf(0.7)
        } else {
            0.0
        };
        by_planes.max(by_area)
    };
    let mut over = (epsilon, over_by(&first, epsilon));
    if over.1 <= 1.0 {
        return (first, epsilon);
    }
    let mut fits: Option<(f32, Vec<(TriangleSoup, PlaneSearch)>)> = None;
    let mut last = first;
    let widest = if is_impostor_class(ctx.level.screen_height) {
        IMPOSTOR_MAX_WIDENING * epsilon
    } else {
        ctx.scale
    };
    for _ in 1..EPSILON_TRIES {
        let next = match &fits {
            None => (over.0.max(1e-6 * ctx.scale) * over.1.max(1.05)).min(widest),
            Some((hi, _)) => (over.0 * hi).sqrt(),
        };
        if next <= over.0 {
            // At the widest ε allowed and still over: the planes are capped below.
            break;
        }
        let result = search_clusters(ctx, soup, clusters, next, &|_| None);
        let by = over_by(&result, next);
        tracing::debug!(
            "LOD{}: ε {next:.4}: {} planes of {budget}, {:.2} over its budgets",
            ctx.index + 1,
            planes(&result),
            by
        );
        if by <= 1.0 {
            fits = Some((next, result));
        } else {
            over = (next, by);
            last = result;
        }
    }
    if let Some((e, result)) = fits {
        return (result, e);
    }
    if planes(&last) <= budget {
        // Within the billboard budget but over the atlas: the widest ε tried, and the bake
        // lowers its density.
        return (last, over.0);
    }
    let counts: Vec<usize> = last.iter().map(|(_, s)| s.clusters.len()).collect();
    let shares = proportional_shares(&counts, budget);
    let e = over.0;
    (
        search_clusters(ctx, soup, clusters, e, &|ci| Some(shares[ci])),
        e,
    )
}

/// Most an impostor-class LOD's ε is widened to fit its billboard budget, in its own ε (one
/// pixel): a crown a few dozen pixels wide is then still a few slabs deep, each billboard's
/// leaves within a few pixels of it; past it the plane count is capped and the leftover
/// leaves join their nearest plane (spec stochastic-billboard-clouds: no leaf is dropped).
/// A nearer LOD widens as far as its budget asks.
const IMPOSTOR_MAX_WIDENING: f32 = 4.0;

/// Total area (world units²) of the minimal quads of every plane of `searches`.
fn quad_area(searches: &[(TriangleSoup, PlaneSearch)]) -> f32 {
    searches
        .par_iter()
        .map(|(sub, search)| {
            (search.clusters.iter())
                .map(|c| fit_quad(sub, &c.plane, &c.triangles).area())
                .sum::<f32>()
        })
        .sum()
}

/// Splits `budget` over clusters in proportion to `counts` (largest remainders), each at least
/// one and at most its count.
fn proportional_shares(counts: &[usize], budget: usize) -> Vec<usize> {
    let total: usize = counts.iter().sum();
    let spare = budget.saturating_sub(counts.len());
    let exact: Vec<f64> = counts
        .iter()
        .map(|&c| {
            (c.saturating_sub(1)) as f64 * spare as f64
                / total.saturating_sub(counts.len()).max(1) as f64
        })
        .collect();
    let mut share: Vec<usize> = exact.iter().map(|e| 1 + e.floor() as usize).collect();
    let mut left = budget.saturating_sub(share.iter().sum());
    let mut order: Vec<usize> = (0..counts.len()).collect();
    order.sort_by(|&a, &b| {
        (exact[b] - exact[b].floor())
            .total_cmp(&(exact[a] - exact[a].floor()))
            .then(a.cmp(&b))
    });
    for i in order {
        if left == 0 {
            break;
        }
        if share[i] < counts[i] {
            share[i] += 1;
            left -= 1;
        }
    }
    share
        .iter()
        .zip(counts)
        .map(|(&s, &c)| s.min(c.max(1)))
        .collect()
}

/// The quads of every cluster within the billboard budget, each with the triangles it
/// replaces and those it bakes; and the ε the planes were searched with.
fn cluster_quads(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    clusters: &[FoliageCluster],
) -> (Vec<Vec<ClusterQuad>>, f32) {
    let (searches, epsilon) = budgeted_search(ctx, soup, clusters);
    let increased_density = ctx.cloud.increased_density;
    // Every plane's group in the soup's own indices, cluster by cluster.
    let per_cluster: Vec<Vec<QuadGroup>> = clusters
        .par_iter()
        .zip(searches.par_iter())
        .map(|(cluster, (sub, search))| {
            search
                .clusters
                .iter()
                .map(|c| {
                    let own: Vec<usize> = c.triangles.iter().map(|&t| cluster.members[t]).collect();
                    let drawn = if increased_density {
                        let mut m: Vec<usize> = valid_for_plane(sub, &c.plane, epsilon)
                            .into_iter()
                            .map(|t| cluster.members[t])
                            .collect();
                        m.extend(&own);
                        m.sort_unstable();
                        m.dedup();
                        m
                    } else {
                        own.clone()
                    };
                    QuadGroup::new(soup, c.plane, own, drawn, 0)
                })
                .collect()
        })
        .collect();
    let cluster_of: Vec<usize> = (per_cluster.iter().enumerate())
        .flat_map(|(ci, g)| std::iter::repeat_n(ci, g.len()))
        .collect();
    let groups: Vec<QuadGroup> = (per_cluster.into_iter().flatten().enumerate())
        .map(|(i, g)| QuadGroup { source: i, ..g })
        .collect();
    // What the billboard budget leaves after the planes goes to compact quads.
    let groups = match ctx.max_billboards {
        Some(max) => split_quads(soup, groups, max),
        None => groups,
    };
    let mut quads: Vec<Vec<ClusterQuad>> = vec![Vec::new(); clusters.len()];
    for g in groups {
        quads[cluster_of[g.source]].push((g.quad, g.own, g.drawn));
    }
    (quads, epsilon)
}

/// Per quad, the input card it copies, if any ([`source_copy`]): its UVs and texture. A copy
/// whose card faces away from its quad turns the quad round (its texture is the card's front).
/// None everywhere when the tree's materials use a second texture coordinate set (the
/// animation's own sets take `TEXCOORD_1` on).
fn source_copies(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    quads: &mut [Quad],
    owns: &[Vec<usize>],
) -> Vec<Option<([Vec2; 4], BillboardTexture)>> {
    let (tree, sampled) = (ctx.tree, ctx.sampled);
    if tree.vertices.texcoords.len() > 1 {
        return vec![None; quads.len()];
    }
    quads
        .par_iter_mut()
        .zip(owns.par_iter())
        .map(|(quad, own)| {
            let copy = source_copy(soup, quad, own)?;
            let mut weights = copy.weights;
            if !copy.same_facing {
                // Negating axis_v flips the normal and reverses the corner order.
                quad.axis_v = -quad.axis_v;
                quad.plane = Plane {
                    normal: -quad.plane.normal,
                    offset: -quad.plane.offset,
                };
                weights.reverse();
            }
            let at = |values: [Vec2; 3]| {
                weights.map(|w| values[0] * w[0] + values[1] * w[1] + values[2] * w[2])
            };
            let v = tree.triangles[sampled.foliage[copy.triangle]]
                .v
                .map(|v| v as usize);
            let texcoords = tree
                .vertices
                .texcoords
                .iter()
                .map(|set| at(v.map(|i| set.get(i).copied().unwrap_or_default())))
                .collect();
            Some((
                at(soup.uvs[copy.triangle]),
                BillboardTexture::Input {
                    material: copy.material as usize,
                    texcoords,
                },
            ))
        })
        .collect()
}

/// The billboards of `quads`: each follows its cluster's driver (a node, or the rigid fit of
/// its own triangles' sampled motion) and shows `textures` (its UVs and what they index).
fn animated_billboards(
    ctx: &BuildContext,
    soup: &TriangleSoup,
    quads: &[Quad],
    owns: &[Vec<usize>],
    drivers: &[Driver],
    textures: Vec<([Vec2; 4], BillboardTexture)>,
) -> Vec<AnimatedBillboard> {
    let (tree, sampled) = (ctx.tree, ctx.sampled);
    let n = sampled.samples();
    let nv = sampled.vertices;
    quads
        .par_iter()
        .zip(owns.par_iter())
        .zip(drivers.par_iter())
        .zip(textures.into_par_iter())
        .map(|(((quad, own), driver), (uv, texture))| {
            let (follows, motion) = match *driver {
                Driver::Node(node) => (Some(node), None),
                Driver::Assigned => (None, None),
                Driver::RigidFit => {
                    let from: Vec<Vec3> = own.iter().flat_map(|&k| soup.positions[k]).collect();
                    let frames = (0..n)
                        .map(|s| {
                            let to: Vec<Vec3> = own
                                .iter()
                                .flat_map(|&k| {
                                    tree.triangles[sampled.foliage[k]]
                                        .v
                                        .map(|v| sampled.positions[s * nv + v as usize])
                                })
                                .collect();
                            rigid_fit(&from, &to)
                        })
                        .collect();
                    (None, Some(RigidMotion::Sampled(frames)))
                }
            };
            AnimatedBillboard {
                quad: *quad,
                uv,
                texture,
                follows,
                motion,
                triangles: own.iter().map(|&k| sampled.foliage[k]).collect(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::wood::WoodPrimitive;

    /// A unit square quad centred at `center`, facing +Z.
    fn quad_at(center: Vec3) -> Quad {
        Quad::facing_z(center, Vec2::splat(0.5))
    }

    #[test]
    fn thin_wood_is_drawn_on_the_nearest_billboard_and_replaces_nothing() {
        let mut quads = [quad_at(Vec3::ZERO), quad_at(Vec3::new(3.0, 0.0, 0.0))];
        // One leaf on each quad.
        let leaf = |x: f32| {
            [
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.1, 0.0, 0.0),
                Vec3::new(x, 0.1, 0.0),
            ]
        };
        let mut soup = TriangleSoup {
            positions: vec![leaf(0.0), leaf(3.0)],
            uvs: vec![[Vec2::ZERO; 3]; 2],
            material: vec![0, 0],
        };
        let mut drawn = vec![vec![0], vec![1]];
        // Two twig triangles: one behind the second quad, one just past the first's edge.
        let wood = WoodMesh {
            positions: vec![
                Vec3::new(2.9, 0.1, -0.4),
                Vec3::new(3.1, 0.1, -0.4),
                Vec3::new(3.0, 0.3, -0.4),
                Vec3::new(0.6, 0.0, 0.1),
                Vec3::new(0.7, 0.0, 0.1),
                Vec3::new(0.6, 0.1, 0.1),
            ],
            uvs: (0..6).map(|i| Vec2::new(i as f32, 0.0)).collect(),
            primitives: vec![WoodPrimitive {
                material: 7,
                indices: vec![0, 1, 2, 3, 4, 5],
            }],
            ..WoodMesh::default()
        };
        draw_wood_on_nearest_quads(&mut soup, &wood, &mut quads, &mut drawn, None);
        assert_eq!(soup.len(), 4);
        assert_eq!(drawn, [vec![0, 3], vec![1, 2]]);
        assert_eq!(soup.material[2..], [7, 7]);
        assert_eq!(soup.positions[2][0], wood.positions[0]);
        assert_eq!(soup.uvs[3], [3.0, 4.0, 5.0].map(|u| Vec2::new(u, 0.0)));
        // The first quad grew to hold the twig past its edge; the second held its own already.
        assert!((quads[0].center.x - 0.1).abs() < 1e-6, "{:?}", quads[0]);
        assert!(
            (quads[0].half_size - Vec2::new(0.6, 0.5))
                .abs()
                .max_element()
                < 1e-6
        );
        assert_eq!(quads[1], quad_at(Vec3::new(3.0, 0.0, 0.0)));
        // With no drawn area to spare, the twig is drawn (cut at the edge) and nothing grows.
        let mut tight = [quad_at(Vec3::ZERO), quad_at(Vec3::new(3.0, 0.0, 0.0))];
        let (mut soup, mut drawn) = (TriangleSoup::default(), vec![Vec::new(), Vec::new()]);
        draw_wood_on_nearest_quads(&mut soup, &wood, &mut tight, &mut drawn, Some(2.0));
        assert_eq!(drawn, [vec![1], vec![0]]);
        assert_eq!(tight[0], quad_at(Vec3::ZERO));
    }

    #[test]
    fn a_branch_goes_to_the_quad_that_faces_it_not_the_one_seen_edge_on() {
        // A quad facing +Z at the origin and one facing +X a little further away.
        let mut facing_x = quad_at(Vec3::new(0.0, 0.0, -0.6));
        facing_x.plane = Plane {
            normal: Vec3::X,
            offset: 0.0,
        };
        facing_x.axis_u = -Vec3::Z;
        let mut quads = [quad_at(Vec3::ZERO), facing_x];
        let mut soup = TriangleSoup::default();
        let mut drawn = vec![Vec::new(), Vec::new()];
        // A triangle facing +X, 0.1 in front of the first quad (seen edge-on from +X) and 0.2
        // beside the second's edge (facing it).
        let wood = WoodMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.2),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.0, 0.2, 0.1),
            ],
            uvs: vec![Vec2::ZERO; 3],
            primitives: vec![WoodPrimitive {
                material: 1,
                indices: vec![0, 1, 2],
            }],
            ..WoodMesh::default()
        };
        draw_wood_on_nearest_quads(&mut soup, &wood, &mut quads, &mut drawn, None);
        assert_eq!(drawn, [vec![], vec![0]]);
    }
}
