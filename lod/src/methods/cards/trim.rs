//! Leaf cards trimmed to one triangle: quads trimmed to what they show. A leaf card is a quad
//! of two triangles whose texture is mostly transparent: a sprig drawn on a quarter of its
//! texels. The smallest triangle that holds every texel the alpha test can pass, and whose
//! part outside the card reads only transparent texels under the texture's wrap modes, draws
//! exactly the card's pixels with one triangle instead of two: half the triangles and less
//! overdraw at no coverage cost. A card LOD then keeps twice the cards per triangle.
//!
//! The triangle is searched in the card's texture frame (the parallelogram its corners span in
//! texture coordinates, `[0, 1]²`): each side is a supporting line of the opaque texels' hull
//! in one of 64 directions, every triple of directions that closes a triangle is a
//! candidate, and the smallest whose outside part is clear wins. Cards sharing their texture
//! region (every card of a tree with one leaf texture) share the search. Written here: the
//! constrained minimal triangle is a few lines over support functions, which no geometry crate
//! offers with the wrap-mode constraint.

use std::collections::{HashMap, HashSet};

use glam::{Mat4, Vec2, Vec3};

use frond_scene::sampling::world_at;
use frond_scene::wood::{NO_BONE, WoodMesh};
use frond_scene::{AlphaMode, Tree};

use super::coverage::card_vertices;
use crate::simplex_fit::{fit_on_simplices, objective, project_to_simplex};

/// Directions of the triangle's sides searched: every 360/64 = 5.6°.
const DIRECTIONS: usize = 64;

/// Texels around an opaque one that a point outside the card must keep clear of, per 128
/// texels of the texture's side (at least 2): the renderer's coarser mip levels blur the
/// texture's edge rows and columns outwards (8 texels of a 1024² texture is level 3).
const CLEAR_PER_128: f32 = 1.0;

/// Area (fraction of the card) of the trimmed triangle's outside part that may lie near
/// passing texels: where a side crosses the card's edge beside a leaf touching it, a sliver a
/// few texels wide reads the edge's texels. Far below a pixel at any size the card is drawn.
const SPILL: f32 = 0.002;

/// Grid points per side of the search window `[-1, 2]²` of the card's frame, at most: whether
/// a candidate's outside part is clear is read off this grid.
const GRID: usize = 384;

/// The foliage with its cards trimmed, and what trimming did.
pub struct Trimmed {
    /// The foliage, each trimmed card one triangle.
    pub mesh: WoodMesh,
    /// Cards replaced by one triangle.
    pub cards: usize,
    /// Blended cards left as quads because they bend more than one triangle can follow and the
    /// budget had room for their second triangle.
    pub kept_as_quads: usize,
    /// Total area of the cards trimmed, before trimming (world units²).
    pub area_before: f64,
    /// Total area of their triangles after trimming (world units²).
    pub area_after: f64,
}

/// One card's trimmed triangle: its corners' texture coordinates, rest positions and skins,
/// and how far the triangle's skinning misses the card's own (world units, root mean square
/// over the leaf's texels and the fit's frames; 0 for a card on one skin).
struct CardTrim {
    card: CardFrame,
    uv: [Vec2; 3],
    rest: [Vec3; 3],
    skins: [Skin; 3],
    miss: f32,
}

/// The foliage `mesh` of `tree` with every leaf card that can be trimmed replaced by its
/// trimmed triangle ([`trimmed_triangle`]); other pieces unchanged. New vertices are affine
/// combinations of the card's corners in every attribute (positions, normals, texture
/// coordinates); a card bound to one skin keeps it, a blended card's new vertices get weights
/// fitted to the card's motion. The triangle faces the card's way.
///
/// A blended card bends when posed (its corners follow different bones) and a flat triangle
/// cannot: when the trimmed foliage leaves room within `max_triangles`, the cards whose fit
/// misses most (miss × the card's size: the pixels it moves) stay quads, one more triangle
/// each.
pub fn trim_cards(tree: &Tree, mesh: &WoodMesh, max_triangles: usize) -> Trimmed {
    let pieces = mesh.pieces();
    let motion = BoneMotion::of(tree);
    // Per material (its texture, cutoff and wrap modes) and texture region.
    let mut regions: HashMap<(usize, RegionKey), Option<Region>> = HashMap::new();
    let trims: Vec<Option<CardTrim>> = pieces
        .iter()
        .map(|piece| {
            let card = CardFrame::of(tree, mesh, piece)?;
            let material = mesh.primitives[piece[0].0].material;
            let region = regions
                .entry((material, card.key()))
                .or_insert_with(|| Region::of(tree, &tree.materials[material], &card.uv))
                .as_ref()?;
            let rest = region.triangle.map(|uv| card.point(&mesh.positions, uv));
            let (skins, miss) = match card.single_skin(mesh) {
                Some(skin) => ([skin; 3], 0.0),
                None => fit_skins(mesh, piece, &card, region, rest, &motion)
                    .unwrap_or_else(|| ([card.corner_skin(mesh); 3], 0.0)),
            };
            Some(CardTrim {
                card,
                uv: region.triangle,
                rest,
                skins,
                miss,
            })
        })
        .collect();
    let trimmable = trims.iter().flatten().count();
    let room = max_triangles.saturating_sub(mesh.triangles() - trimmable);
    // The cards that stay quads: the worst-fitting blended ones, as many as the room allows.
    let mut bending: Vec<(f32, usize)> = trims
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            t.as_ref()
                .filter(|t| t.miss > 0.0)
                .map(|t| (t.miss * t.card.facing.length().sqrt(), i))
        })
        .collect();
    bending.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let quads: HashSet<usize> = bending.iter().take(room).map(|&(_, i)| i).collect();
    let mut out = mesh.clone();
    // The second triangles of trimmed cards (the first is overwritten with the trimmed one).
    let mut dropped: HashSet<(usize, usize)> = HashSet::new();
    let (mut cards, mut area_before, mut area_after) = (0, 0.0, 0.0);
    for (i, (piece, trim)) in pieces.iter().zip(&trims).enumerate() {
        let Some(trim) = trim.as_ref().filter(|_| !quads.contains(&i)) else {
            continue;
        };
        let card = &trim.card;
        let base = out.positions.len() as u32;
        for ((uv, position), skin) in trim.uv.into_iter().zip(trim.rest).zip(trim.skins) {
            card.push_vertex(mesh, &mut out, uv, position, skin);
        }
        let p = |k: u32| out.positions[(base + k) as usize];
        let facing = (p(1) - p(0)).cross(p(2) - p(0));
        let mut tri = [base, base + 1, base + 2];
        if facing.dot(card.facing) < 0.0 {
            tri.swap(1, 2);
        }
        area_before += f64::from(card.facing.length());
        area_after += f64::from(0.5 * facing.length());
        cards += 1;
        dropped.insert(piece[1]);
        out.primitives[piece[0].0].indices[3 * piece[0].1..3 * piece[0].1 + 3]
            .copy_from_slice(&tri);
    }
    for (pi, p) in out.primitives.iter_mut().enumerate() {
        let old = std::mem::take(&mut p.indices);
        for (ti, t) in old.chunks_exact(3).enumerate() {
            if !dropped.contains(&(pi, ti)) {
                p.indices.extend_from_slice(t);
            }
        }
    }
    Trimmed {
        mesh: out.compacted(),
        cards,
        kept_as_quads: quads.len(),
        area_before,
        area_after,
    }
}

/// Quantised texture region of a card: its four texture corners (1e-5 steps), sorted.
type RegionKey = [(i64, i64); 4];

/// Points of a card's texture region per side of the grid the skin fit samples.
const FIT_SAMPLES: usize = 16;

/// What the cards sharing a material and texture region share.
struct Region {
    /// Their trimmed triangle ([`trimmed_triangle`]).
    triangle: [Vec2; 3],
    /// The points of a [`FIT_SAMPLES`]² grid over the region whose texel the alpha test
    /// passes: where the leaf is, which the skin fit of a blended card follows.
    samples: Vec<Vec2>,
}

impl Region {
    fn of(tree: &Tree, material: &frond_scene::Material, region: &[Vec2; 3]) -> Option<Region> {
        let (opaque, w, h) = passing_texels(tree, material)?;
        let triangle = triangle_over(&opaque, w, h, material, region)?;
        let [o, e1, e2] = *region;
        let samples = (0..FIT_SAMPLES * FIT_SAMPLES)
            .map(|k| {
                let f = Vec2::new(
                    (k % FIT_SAMPLES) as f32 + 0.5,
                    (k / FIT_SAMPLES) as f32 + 0.5,
                ) / FIT_SAMPLES as f32;
                o + e1 * f.x + e2 * f.y
            })
            .filter(|uv| {
                let x = material.base_color_wrap[0].texel(uv.x * w as f32, w as u32) as usize;
                let y = material.base_color_wrap[1].texel(uv.y * h as f32, h as u32) as usize;
                opaque[y * w + x]
            })
            .collect();
        Some(Region { triangle, samples })
    }
}

/// A two-triangle card whose texture coordinates map affinely onto its positions.
struct CardFrame {
    /// The card's four vertices.
    vertices: [u32; 4],
    /// Three of them, every attribute of a point of the card an affine
    /// combination of theirs.
    corners: [u32; 3],
    /// Their base-colour texture coordinates.
    corner_uv: [Vec2; 3],
    /// The card's texture region: origin and the two edges from it.
    uv: [Vec2; 3],
    /// The card's area-weighted normal (length: the card's area).
    facing: Vec3,
}

impl CardFrame {
    /// The card `piece` of `mesh` when it is one (two triangles of one alpha-tested, textured
    /// material over four vertices, a parallelogram both in space and in texture space, mapped
    /// affinely), else `None`.
    fn of(tree: &Tree, mesh: &WoodMesh, piece: &[(usize, usize)]) -> Option<CardFrame> {
        let [(p0, _), (p1, _)] = piece else {
            return None;
        };
        let material = tree.materials.get(mesh.primitives[*p0].material)?;
        if *p0 != *p1
            || material.alpha_mode != AlphaMode::Mask
            || material.base_color_texture.is_none()
        {
            return None;
        }
        let verts = card_vertices(mesh, piece);
        let &[a, b, c, d] = verts.as_slice() else {
            return None;
        };
        let uv = |v: u32| mesh.uvs.get(v as usize).copied();
        let (ua, ub, uc, ud) = (uv(a)?, uv(b)?, uv(c)?, uv(d)?);
        // Three corners spanning the texture region; the fourth must follow affinely.
        let mut best = None;
        for (three, fourth) in [
            ([a, b, c], d),
            ([a, b, d], c),
            ([a, c, d], b),
            ([b, c, d], a),
        ] {
            let u = three.map(|v| mesh.uvs[v as usize]);
            let area = (u[1] - u[0]).perp_dot(u[2] - u[0]).abs();
            if best.is_none_or(|(_, _, ar)| area > ar) {
                best = Some((three, fourth, area));
            }
        }
        let (corners, fourth, area) = best?;
        if area <= 1e-12 {
            return None;
        }
        let corner_uv = corners.map(|v| mesh.uvs[v as usize]);
        let w = barycentric(&corner_uv, mesh.uvs[fourth as usize])?;
        let at =
            |f: &dyn Fn(u32) -> Vec3| corners.iter().zip(w).map(|(&v, k)| f(v) * k).sum::<Vec3>();
        let pos = |v: u32| mesh.positions[v as usize];
        let size = (pos(a) - pos(c)).length().max((pos(b) - pos(d)).length());
        if (at(&pos) - pos(fourth)).length() > 1e-3 * size.max(f32::MIN_POSITIVE) {
            return None;
        }
        for set in &mesh.texcoords {
            let t = |v: u32| {
                set.get(v as usize)
                    .copied()
                    .unwrap_or(Vec2::ZERO)
                    .extend(0.0)
            };
            if (at(&t) - t(fourth)).length() > 1e-4 {
                return None;
            }
        }
        // The region: the parallelogram of the four texture corners, from its
        // lexicographically first corner, edges counter-clockwise.
        let mut all = [ua, ub, uc, ud];
        all.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
        let o = all[0];
        // The corner opposite `o` is the one the other two sum to, with `o`.
        let opposite = (1..4).min_by(|&i, &j| {
            let miss = |k: usize| {
                let rest: Vec2 = (1..4).filter(|&r| r != k).map(|r| all[r]).sum();
                (rest - o - all[k]).length()
            };
            miss(i).total_cmp(&miss(j))
        })?;
        let edges: Vec<Vec2> = (1..4)
            .filter(|&r| r != opposite)
            .map(|r| all[r] - o)
            .collect();
        let (mut e1, mut e2) = (edges[0], edges[1]);
        if e1.perp_dot(e2) < 0.0 {
            std::mem::swap(&mut e1, &mut e2);
        }
        if (o + e1 + e2 - all[opposite]).length() > 1e-4 * (e1.length() + e2.length()) {
            return None;
        }
        let facing = piece
            .iter()
            .map(|&(p, t)| {
                let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
                let [x, y, z] = [0, 1, 2].map(|k| mesh.positions[i[k] as usize]);
                0.5 * (y - x).cross(z - x)
            })
            .sum();
        Some(CardFrame {
            vertices: [a, b, c, d],
            corners,
            corner_uv,
            uv: [o, e1, e2],
            facing,
        })
    }

    fn key(&self) -> RegionKey {
        let [o, e1, e2] = self.uv;
        let q = |p: Vec2| ((p.x * 1e5).round() as i64, (p.y * 1e5).round() as i64);
        let mut k = [q(o), q(o + e1), q(o + e2), q(o + e1 + e2)];
        k.sort_unstable();
        k
    }

    /// Barycentric coordinates of base-colour coordinates `uv` over the card's corners.
    fn weights(&self, uv: Vec2) -> [f32; 3] {
        barycentric(&self.corner_uv, uv).unwrap_or([1.0, 0.0, 0.0])
    }

    /// The card's rest position at base-colour coordinates `uv` (outside the card too: the
    /// card's plane, extended).
    fn point(&self, positions: &[Vec3], uv: Vec2) -> Vec3 {
        self.corners
            .iter()
            .zip(self.weights(uv))
            .map(|(&v, k)| positions[v as usize] * k)
            .sum()
    }

    /// The skin every vertex of the card shares, if they share one.
    fn single_skin(&self, mesh: &WoodMesh) -> Option<Skin> {
        let skin = |v: u32| (mesh.bones[v as usize], mesh.weights[v as usize]);
        let first = skin(self.vertices[0]);
        self.vertices
            .iter()
            .all(|&v| skin(v) == first)
            .then_some(first)
    }

    /// The first corner's skin: what a blended card's new vertex falls back to.
    fn corner_skin(&self, mesh: &WoodMesh) -> Skin {
        let v = self.corners[0] as usize;
        (mesh.bones[v], mesh.weights[v])
    }

    /// Appends to `out` the card's point at base-colour coordinates `uv` (rest position
    /// `position`), every other attribute combined from the card's corners in `mesh`, with
    /// `skin`.
    fn push_vertex(
        &self,
        mesh: &WoodMesh,
        out: &mut WoodMesh,
        uv: Vec2,
        position: Vec3,
        (bones, weights): Skin,
    ) {
        let w = self.weights(uv);
        let mix3 = |a: &[Vec3]| {
            self.corners
                .iter()
                .zip(w)
                .map(|(&v, k)| a[v as usize] * k)
                .sum::<Vec3>()
        };
        let mix2 = |a: &[Vec2]| {
            self.corners
                .iter()
                .zip(w)
                .map(|(&v, k)| a.get(v as usize).copied().unwrap_or(Vec2::ZERO) * k)
                .sum::<Vec2>()
        };
        out.positions.push(position);
        out.normals
            .push(mix3(&mesh.normals).try_normalize().unwrap_or(Vec3::Y));
        out.uvs.push(uv);
        for (o, set) in out.texcoords.iter_mut().zip(&mesh.texcoords) {
            // Sets are per vertex; pad a short one so the new vertex lands at its index.
            o.resize(out.positions.len() - 1, Vec2::ZERO);
            o.push(mix2(set));
        }
        out.bones.push(bones);
        out.weights.push(weights);
    }
}

/// Barycentric coordinates of `p` in triangle `t` (any point of the plane: they may be
/// negative); `None` for a degenerate triangle.
fn barycentric(t: &[Vec2; 3], p: Vec2) -> Option<[f32; 3]> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let det = e1.perp_dot(e2);
    if det.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let d = p - t[0];
    let b = d.perp_dot(e2) / det;
    let c = e1.perp_dot(d) / det;
    Some([1.0 - b - c, b, c])
}

/// Frames of the clip a blended card's new vertices are fitted over.
const FIT_FRAMES: usize = 16;

/// Accelerated projected-gradient iterations of the skin fit.
const FIT_ITERATIONS: usize = 300;

/// Each bone's deformation (its world matrix times its rest world's inverse: rest-pose world
/// positions in, posed ones out) at [`FIT_FRAMES`] times over the tree's first clip.
struct BoneMotion {
    frames: Vec<Vec<Mat4>>,
}

impl BoneMotion {
    fn of(tree: &Tree) -> BoneMotion {
        let Some(clip) = tree.rig.clips.first() else {
            return BoneMotion { frames: Vec::new() };
        };
        let rest_inverse: Vec<Mat4> = tree.bones.iter().map(|b| b.rest_world.inverse()).collect();
        let frames = (0..FIT_FRAMES)
            .map(|f| {
                let t = clip.start + clip.duration() * f as f32 / FIT_FRAMES as f32;
                let world = world_at(tree, Some(0), t);
                tree.bones
                    .iter()
                    .zip(&rest_inverse)
                    .map(|(b, inv)| world.get(b.node).copied().unwrap_or(Mat4::IDENTITY) * *inv)
                    .collect()
            })
            .collect();
        BoneMotion { frames }
    }

    /// Where bone `b` moves rest position `p` in frame `f`.
    fn moved(&self, f: usize, b: u32, p: Vec3) -> Vec3 {
        self.frames[f]
            .get(b as usize)
            .map_or(p, |m| m.transform_point3(p))
    }
}

/// A vertex's skin: four joints and their weights.
type Skin = ([u32; 4], [f32; 4]);

/// The skins of a blended card's trimmed triangle (rest positions `rest`, texture
/// coordinates `region.triangle`): the non-negative weights, each vertex's summing to 1, over
/// the bones the card's vertices use, that move the triangle's points closest to where the
/// card's own skin moves them, over `motion`'s frames and at `region.samples` (the texels the
/// leaf shows, so the fit spends nothing on the transparent part). A card blended over bones
/// whose weights vary across it bends when posed (its two triangles no longer coplanar), which
/// one flat triangle cannot follow; fitting all three vertices together over the leaf's texels
/// leaves less error than fitting each vertex to the card's plane extended
/// (docs/experiments.md §13). `None` when
/// there is nothing to fit (one bone, no clip, no samples).
///
/// The least-squares problem is solved by accelerated projected gradient (FISTA) on the
/// product of simplices, in differences from one reference bone: the positions themselves
/// would make the normal equations' scale that of the tree and the step useless.
fn fit_skins(
    mesh: &WoodMesh,
    piece: &[(usize, usize)],
    card: &CardFrame,
    region: &Region,
    rest: [Vec3; 3],
    motion: &BoneMotion,
) -> Option<([Skin; 3], f32)> {
    let mut bones: Vec<u32> = card
        .vertices
        .iter()
        .flat_map(|&v| {
            let (b, x) = (mesh.bones[v as usize], mesh.weights[v as usize]);
            (0..4)
                .filter(move |&k| x[k] > 0.0 && b[k] != NO_BONE)
                .map(move |k| b[k])
        })
        .collect();
    bones.sort_unstable();
    bones.dedup();
    let nb = bones.len();
    if nb < 2 || motion.frames.is_empty() || region.samples.is_empty() {
        return None;
    }
    // Each sample: its barycentric coordinates in the trimmed triangle, and the card's point
    // there as a combination of the card's own triangle's vertices.
    let card_triangles: Vec<[u32; 3]> = piece
        .iter()
        .map(|&(p, t)| {
            let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
            [i[0], i[1], i[2]]
        })
        .collect();
    let samples: Vec<([f32; 3], [u32; 3], [f32; 3])> = region
        .samples
        .iter()
        .filter_map(|&uv| {
            let beta = barycentric(&region.triangle, uv)?;
            // The card triangle holding the point (the least outside one, for points on
            // the shared edge).
            let (t, gamma) = card_triangles
                .iter()
                .filter_map(|t| Some((*t, barycentric(&t.map(|v| mesh.uvs[v as usize]), uv)?)))
                .max_by(|a, b| {
                    let low = |g: &[f32; 3]| g.iter().copied().fold(f32::INFINITY, f32::min);
                    low(&a.1).total_cmp(&low(&b.1))
                })?;
            Some((beta, t, gamma))
        })
        .collect();
    if samples.is_empty() {
        return None;
    }
    let skinned = |f: usize, v: u32| -> Vec3 {
        let (b, x) = (mesh.bones[v as usize], mesh.weights[v as usize]);
        let p = mesh.positions[v as usize];
        (0..4).map(|j| motion.moved(f, b[j], p) * x[j]).sum()
    };
    // Normal equations of Σ_f Σ_s |Σ_i β_si Σ_b x_ib d_ib(f) − t_s(f)|², with d_ib(f) the
    // vertex i moved by bone b less moved by the reference bone, t_s(f) the card's point less
    // the triangle's point moved by the reference bone.
    let n = 3 * nb;
    let mut gram = [[0.0f64; 3]; 3];
    for (beta, _, _) in &samples {
        for i in 0..3 {
            for j in 0..3 {
                gram[i][j] += f64::from(beta[i] * beta[j]);
            }
        }
    }
    let mut h = vec![0.0f64; n * n];
    let mut c = vec![0.0f64; n];
    // Σ_f Σ_s |t_s(f)|²: the objective's constant, for the residual.
    let mut targets = 0.0f64;
    for f in 0..motion.frames.len() {
        let reference = rest.map(|q| motion.moved(f, bones[0], q));
        let d: Vec<Vec3> = (0..n)
            .map(|k| motion.moved(f, bones[k % nb], rest[k / nb]) - reference[k / nb])
            .collect();
        // Σ_s β_si t_s(f), per vertex i.
        let mut pulled = [Vec3::ZERO; 3];
        for (beta, t, gamma) in &samples {
            let card_point: Vec3 = t.iter().zip(gamma).map(|(&v, &g)| skinned(f, v) * g).sum();
            let base: Vec3 = reference.iter().zip(beta).map(|(&r, &b)| r * b).sum();
            targets += f64::from((card_point - base).length_squared());
            for i in 0..3 {
                pulled[i] += (card_point - base) * beta[i];
            }
        }
        for a in 0..n {
            c[a] += f64::from(d[a].dot(pulled[a / nb]));
            for b in 0..n {
                h[a * n + b] += gram[a / nb][b / nb] * f64::from(d[a].dot(d[b]));
            }
        }
    }
    let mut x = combined_corner_weights(mesh, card, &region.triangle, &bones);
    fit_on_simplices(&h, &c, &mut x, nb, FIT_ITERATIONS);
    let quadratic = objective(&h, &c, &x);
    let count = (samples.len() * motion.frames.len()) as f64;
    let miss = ((quadratic + targets).max(0.0) / count).sqrt() as f32;
    Some((
        [0, 1, 2].map(|i| strongest_four(&bones, &x[i * nb..(i + 1) * nb])),
        miss,
    ))
}

/// The corners' weights over `bones` combined at each vertex of `triangle` as its texture
/// coordinates combine the corners, projected on the simplex (combined alone they are negative
/// outside the card): where [`fit_skins`] starts. Three blocks of `bones.len()`.
fn combined_corner_weights(
    mesh: &WoodMesh,
    card: &CardFrame,
    triangle: &[Vec2; 3],
    bones: &[u32],
) -> Vec<f64> {
    let nb = bones.len();
    let mut x = vec![0.0f64; 3 * nb];
    for (i, uv) in triangle.iter().enumerate() {
        for (&v, k) in card.corners.iter().zip(card.weights(*uv)) {
            let (bs, xs) = (mesh.bones[v as usize], mesh.weights[v as usize]);
            for j in 0..4 {
                if let Ok(b) = bones.binary_search(&bs[j]) {
                    x[i * nb + b] += f64::from(xs[j] * k);
                }
            }
        }
        project_to_simplex(&mut x[i * nb..(i + 1) * nb]);
    }
    x
}

/// The four largest of `weights` (over `bones`), renormalised: a glTF vertex's skin.
fn strongest_four(bones: &[u32], weights: &[f64]) -> Skin {
    let mut fitted: Vec<(u32, f32)> = bones
        .iter()
        .zip(weights)
        .map(|(&b, &v)| (b, v as f32))
        .filter(|(_, v)| *v > 0.0)
        .collect();
    fitted.sort_by(|p, q| q.1.total_cmp(&p.1).then(p.0.cmp(&q.0)));
    fitted.truncate(4);
    let total: f32 = fitted.iter().map(|(_, v)| v).sum();
    let Some(&(first, _)) = fitted.first().filter(|_| total > 0.0) else {
        return ([bones[0]; 4], [1.0, 0.0, 0.0, 0.0]);
    };
    let mut out = ([first; 4], [0.0; 4]);
    for (k, (b, v)) in fitted.iter().enumerate() {
        out.0[k] = *b;
        out.1[k] = v / total;
    }
    out
}

/// The smallest triangle (texture coordinates) holding every texel of `material`'s base-colour
/// texture inside the region `[o, e1, e2]` (origin and edges) that its alpha test can pass,
/// whose part outside the region reads transparent texels under the texture's wrap modes, no
/// larger than the region; `None` when there is none or the region shows nothing.
pub fn trimmed_triangle(
    tree: &Tree,
    material: &frond_scene::Material,
    region: &[Vec2; 3],
) -> Option<[Vec2; 3]> {
    let (opaque, w, h) = passing_texels(tree, material)?;
    triangle_over(&opaque, w, h, material, region)
}

/// [`trimmed_triangle`] over the texture's passing texels `opaque` (`w` × `h`).
fn triangle_over(
    opaque: &[bool],
    w: usize,
    h: usize,
    material: &frond_scene::Material,
    region: &[Vec2; 3],
) -> Option<[Vec2; 3]> {
    let frame = RegionFrame::new(region, w, h);
    if frame.e1.perp_dot(frame.e2).abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let points = hull_points(opaque, w, h, &frame);
    if points.is_empty() {
        return None;
    }
    let grid = BlockedGrid::new(opaque, w, h, material, &frame);
    let [a, b, c] = hull_triangles(&points)
        .into_iter()
        .map(|(_, t)| t)
        .find(|t| grid.clear_of_blocked(t))?;
    Some([a, b, c].map(|f| frame.o + frame.e1 * f.x + frame.e2 * f.y))
}

/// A region of a texture (origin `o` and edges `e1`, `e2` in texture coordinates) as a frame
/// `(s, t)` over `[0, 1]²`, and the texture's size in texels.
struct RegionFrame {
    o: Vec2,
    e1: Vec2,
    e2: Vec2,
    size: Vec2,
}

impl RegionFrame {
    /// The frame of `region` over a `w` × `h` texture.
    fn new(region: &[Vec2; 3], w: usize, h: usize) -> RegionFrame {
        let [o, e1, e2] = *region;
        RegionFrame {
            o,
            e1,
            e2,
            size: Vec2::new(w as f32, h as f32),
        }
    }

    /// Texel space to the region's frame.
    fn to_frame(&self, x: Vec2) -> Vec2 {
        let d = x / self.size - self.o;
        let det = self.e1.perp_dot(self.e2);
        Vec2::new(d.perp_dot(self.e2) / det, self.e1.perp_dot(d) / det)
    }

    /// The region's frame to texel space.
    fn to_texel(&self, f: Vec2) -> Vec2 {
        (self.o + self.e1 * f.x + self.e2 * f.y) * self.size
    }
}

/// The hull's support points: per texel row, the outermost passing texels whose centres lie
/// in the region, each grown to the square bilinear filtering reaches (a texel either side of
/// its centre), clipped to the region; in the region's frame.
fn hull_points(opaque: &[bool], w: usize, h: usize, frame: &RegionFrame) -> Vec<Vec2> {
    let mut points: Vec<Vec2> = Vec::new();
    for y in 0..h {
        let row = &opaque[y * w..(y + 1) * w];
        let inside = |x: usize| {
            let f = frame.to_frame(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            (0.0..=1.0).contains(&f.x) && (0.0..=1.0).contains(&f.y)
        };
        let first = (0..w).find(|&x| row[x] && inside(x));
        let last = (0..w).rev().find(|&x| row[x] && inside(x));
        for x in first.into_iter().chain(last) {
            let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            for d in [
                Vec2::new(-1.0, -1.0),
                Vec2::new(1.0, -1.0),
                Vec2::new(-1.0, 1.0),
                Vec2::ONE,
            ] {
                points.push(frame.to_frame(c + d).clamp(Vec2::ZERO, Vec2::ONE));
            }
        }
    }
    points
}

/// Where a point outside the region may not go: its wrapped texel is within `clear` texels of
/// a passing one. Read on an `n` × `n` grid over `[-1, 2]²` of the frame, as per-row prefix
/// counts of blocked grid points.
struct BlockedGrid {
    /// Grid points per side.
    n: usize,
    /// Grid spacing in the frame.
    step: f32,
    /// Per row `j`, `prefix[j·(n+1) + i]` blocked points before column `i`.
    prefix: Vec<u32>,
    /// Blocked grid points a candidate may cover: their cells' area within [`SPILL`] of the
    /// card.
    allowed: u32,
}

impl BlockedGrid {
    /// The grid of `frame` over the passing texels `opaque` (`w` × `h`) of `material`'s
    /// base-colour texture, wrapped as the material wraps it.
    fn new(
        opaque: &[bool],
        w: usize,
        h: usize,
        material: &frond_scene::Material,
        frame: &RegionFrame,
    ) -> BlockedGrid {
        let clear = (CLEAR_PER_128 * w.max(h) as f32 / 128.0).max(2.0).ceil() as usize;
        let near = dilate(opaque, w, h, clear);
        let side = (frame.to_texel(Vec2::X) - frame.to_texel(Vec2::ZERO))
            .length()
            .max((frame.to_texel(Vec2::Y) - frame.to_texel(Vec2::ZERO)).length());
        let n = ((3.0 * side / clear as f32).ceil() as usize).clamp(16, GRID);
        let step = 3.0 / n as f32;
        let mut grid = BlockedGrid {
            n,
            step,
            prefix: vec![0u32; n * (n + 1)],
            allowed: (SPILL / (step * step)).floor() as u32,
        };
        for j in 0..n {
            for i in 0..n {
                let f = Vec2::new(grid.grid_point(i), grid.grid_point(j));
                let outside = !((0.0..=1.0).contains(&f.x) && (0.0..=1.0).contains(&f.y));
                let blocked = outside && {
                    let t = frame.to_texel(f);
                    let x = material.base_color_wrap[0].texel(t.x, w as u32) as usize;
                    let y = material.base_color_wrap[1].texel(t.y, h as u32) as usize;
                    near[y * w + x]
                };
                grid.prefix[j * (n + 1) + i + 1] =
                    grid.prefix[j * (n + 1) + i] + u32::from(blocked);
            }
        }
        grid
    }

    /// The frame coordinate of grid line `i`.
    fn grid_point(&self, i: usize) -> f32 {
        -1.0 + (i as f32 + 0.5) * self.step
    }

    /// Whether triangle `tri` (in the frame) stays within the grid and covers no more blocked
    /// points than allowed.
    fn clear_of_blocked(&self, tri: &[Vec2; 3]) -> bool {
        let (n, step) = (self.n, self.step);
        if tri
            .iter()
            .any(|v| v.min_element() < -1.0 || v.max_element() > 2.0)
        {
            return false;
        }
        let mut blocked = 0u32;
        let lo = tri.iter().map(|v| v.y).fold(f32::INFINITY, f32::min);
        let hi = tri.iter().map(|v| v.y).fold(f32::NEG_INFINITY, f32::max);
        let j0 = (((lo + 1.0) / step - 0.5).ceil().max(0.0)) as usize;
        let j1 = (((hi + 1.0) / step - 0.5).floor() as usize).min(n - 1);
        for j in j0..=j1 {
            let y = self.grid_point(j);
            // The triangle's span on this row.
            let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in 0..3 {
                let (p, q) = (tri[k], tri[(k + 1) % 3]);
                if (p.y - y) * (q.y - y) <= 0.0 && p.y != q.y {
                    let x = p.x + (q.x - p.x) * (y - p.y) / (q.y - p.y);
                    a = a.min(x);
                    b = b.max(x);
                }
            }
            if a > b {
                continue;
            }
            let i0 = (((a + 1.0) / step - 0.5).ceil().max(0.0)) as usize;
            let i1 = ((b + 1.0) / step - 0.5).floor();
            if i1 < 0.0 {
                continue;
            }
            let i1 = (i1 as usize).min(n - 1);
            if i0 <= i1 {
                blocked += self.prefix[j * (n + 1) + i1 + 1] - self.prefix[j * (n + 1) + i0];
                if blocked > self.allowed {
                    return false;
                }
            }
        }
        true
    }
}

/// Triangles closed by three supporting lines of `points`' hull (of [`DIRECTIONS`] normals),
/// smaller than the card itself, with their areas, smallest first.
fn hull_triangles(points: &[Vec2]) -> Vec<(f32, [Vec2; 3])> {
    let normals: Vec<Vec2> = (0..DIRECTIONS)
        .map(|k| Vec2::from_angle(k as f32 * std::f32::consts::TAU / DIRECTIONS as f32))
        .collect();
    let support: Vec<f32> = normals
        .iter()
        .map(|nrm| {
            points
                .iter()
                .map(|p| nrm.dot(*p))
                .fold(f32::NEG_INFINITY, f32::max)
        })
        .collect();
    let meet = |i: usize, j: usize| -> Option<Vec2> {
        let (a, b) = (normals[i], normals[j]);
        let det = a.perp_dot(b);
        (det.abs() > 1e-6).then(|| {
            Vec2::new(
                support[i] * b.y - support[j] * a.y,
                a.x * support[j] - b.x * support[i],
            ) / det
        })
    };
    let half = DIRECTIONS / 2;
    let mut candidates: Vec<(f32, [Vec2; 3])> = Vec::new();
    for i in 0..DIRECTIONS {
        for j in i + 1..DIRECTIONS {
            for k in j + 1..DIRECTIONS {
                // Closed when no gap between consecutive normals reaches half a turn.
                if j - i >= half || k - j >= half || DIRECTIONS - (k - i) >= half {
                    continue;
                }
                let (Some(a), Some(b), Some(c)) = (meet(i, j), meet(j, k), meet(k, i)) else {
                    continue;
                };
                let area = 0.5 * (b - a).perp_dot(c - a).abs();
                // Never larger than the card itself.
                if area < 1.0 {
                    candidates.push((area, [a, b, c]));
                }
            }
        }
    }
    candidates.sort_by(|p, q| p.0.total_cmp(&q.0));
    candidates
}

/// Which texels of `material`'s base-colour texture its alpha test passes (alpha times the
/// base colour's alpha factor at least the cutoff), with the texture's width and height;
/// `None` without a usable texture or when nothing can pass.
fn passing_texels(
    tree: &Tree,
    material: &frond_scene::Material,
) -> Option<(Vec<bool>, usize, usize)> {
    let texture = tree.textures.get(material.base_color_texture?)?;
    let (w, h) = (texture.width as usize, texture.height as usize);
    if w == 0 || h == 0 || texture.rgba.len() < w * h * 4 {
        return None;
    }
    let factor = material.base_color[3];
    if factor <= 0.0 {
        return None;
    }
    let cutoff = (material.alpha_cutoff / factor * 255.0)
        .ceil()
        .clamp(0.0, 256.0) as u16;
    let opaque = texture
        .rgba
        .chunks_exact(4)
        .map(|p| u16::from(p[3]) >= cutoff)
        .collect();
    Some((opaque, w, h))
}

/// `mask` grown by `r` texels (a square window), separably.
fn dilate(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let pass = |src: &[bool], len: usize, stride: usize, lines: usize, line_stride: usize| {
        let mut out = vec![false; src.len()];
        for l in 0..lines {
            let at = |i: usize| l * line_stride + i * stride;
            // Running count of set entries in the window [i - r, i + r].
            let mut count = 0usize;
            for i in 0..len.min(r) {
                count += usize::from(src[at(i)]);
            }
            for i in 0..len {
                if i + r < len {
                    count += usize::from(src[at(i + r)]);
                }
                if i > r {
                    count -= usize::from(src[at(i - r - 1)]);
                }
                out[at(i)] = count > 0;
            }
        }
        out
    };
    let rows = pass(mask, w, 1, h, w);
    pass(&rows, h, w, w, 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::{ImportOptions, Part, import};

    #[test]
    fn dilation_grows_by_the_radius() {
        let (w, h) = (7, 5);
        let mut m = vec![false; w * h];
        m[2 * w + 3] = true;
        let d = dilate(&m, w, h, 1);
        let set: Vec<(usize, usize)> = (0..w * h)
            .filter(|&i| d[i])
            .map(|i| (i % w, i / w))
            .collect();
        assert_eq!(set.len(), 9);
        assert!(
            set.iter()
                .all(|&(x, y)| (2..=4).contains(&x) && (1..=3).contains(&y))
        );
    }

    fn sample() -> (Tree, WoodMesh) {
        let tree = import(&frond_testdata::sample(), &ImportOptions::default()).expect("sample");
        let foliage = WoodMesh::from_tree_part(&tree, Part::Foliage);
        (tree, foliage)
    }

    /// The sample's leaf texture with its alpha replaced by a disc of radius 0.3 in the middle:
    /// a leaf drawn on a quarter of its card, clear of the card's edges (the shared trees'
    /// sprigs cover 16–26 %).
    fn disc_leaves(tree: &mut Tree, foliage: &WoodMesh) {
        let m = &tree.materials[foliage.primitives[0].material];
        let t = &mut tree.textures[m.base_color_texture.expect("leaf texture")];
        let (w, h) = (t.width as usize, t.height as usize);
        for y in 0..h {
            for x in 0..w {
                let p = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                t.rgba[(y * w + x) * 4 + 3] = if p.distance(Vec2::splat(0.5)) < 0.3 {
                    255
                } else {
                    0
                };
            }
        }
    }

    /// How far (root mean square over the fit's frames and leaf samples: what the fit
    /// minimises) the leaf texels of `piece` land from where the card itself carries them, with
    /// the trimmed triangle skinned by `skins`; in units of the card's size.
    fn leaf_error(
        mesh: &WoodMesh,
        piece: &[(usize, usize)],
        region: &Region,
        rest: [Vec3; 3],
        skins: [Skin; 3],
        motion: &BoneMotion,
    ) -> f32 {
        let skinned = |f: usize, p: Vec3, (b, x): Skin| -> Vec3 {
            (0..4).map(|j| motion.moved(f, b[j], p) * x[j]).sum()
        };
        let verts = card_vertices(mesh, piece);
        let pos = |v: u32| mesh.positions[v as usize];
        let size = (pos(verts[0]) - pos(verts[3])).length();
        let (mut squares, mut count) = (0.0f32, 0);
        for f in 0..FIT_FRAMES {
            for &uv in &region.samples {
                let beta = barycentric(&region.triangle, uv).expect("triangle");
                let got: Vec3 = (0..3)
                    .map(|i| skinned(f, rest[i], skins[i]) * beta[i])
                    .sum();
                let want = piece
                    .iter()
                    .filter_map(|&(p, t)| {
                        let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
                        let tri = [i[0], i[1], i[2]];
                        let g = barycentric(&tri.map(|v| mesh.uvs[v as usize]), uv)?;
                        g.iter().all(|&k| k >= -1e-4).then(|| {
                            tri.iter()
                                .zip(g)
                                .map(|(&v, k)| {
                                    let skin = (mesh.bones[v as usize], mesh.weights[v as usize]);
                                    skinned(f, pos(v), skin) * k
                                })
                                .sum::<Vec3>()
                        })
                    })
                    .next()
                    .expect("a sample lies on the card");
                squares += (got - want).length_squared() / (size * size);
                count += 1;
            }
        }
        (squares / count as f32).sqrt()
    }

    /// Cards blended over two bones whose weights vary across them bend when posed; the fitted
    /// skins follow the leaf closer than the corners' weights combined, on every card, and
    /// by over a fifth on the whole (29 % here).
    #[test]
    fn blended_cards_skins_follow_the_leaf() {
        let (mut tree, mut foliage) = sample();
        disc_leaves(&mut tree, &foliage);
        // Half of each card on its own bone, the other half shared with the parent bone.
        let mut blended = 0;
        for piece in foliage.pieces() {
            let verts = card_vertices(&foliage, &piece);
            let own = foliage.bones[verts[0] as usize][0];
            let Some(parent) = tree.bones.get(own as usize).and_then(|b| b.parent) else {
                continue;
            };
            for &v in &verts[2..] {
                foliage.bones[v as usize] = [own, parent as u32, own, own];
                foliage.weights[v as usize] = [0.5, 0.5, 0.0, 0.0];
            }
            blended += 1;
        }
        assert!(blended > 100, "{blended}");
        let motion = BoneMotion::of(&tree);
        let m = &tree.materials[foliage.primitives[0].material];
        let (mut fitted_sum, mut combined_sum, mut fitted_cards) = (0.0, 0.0, 0);
        let mut misses = Vec::new();
        for piece in foliage.pieces() {
            let card = CardFrame::of(&tree, &foliage, &piece).expect("a card");
            if card.single_skin(&foliage).is_some() {
                continue;
            }
            let region = Region::of(&tree, m, &card.uv).expect("trimmed");
            let rest = region.triangle.map(|uv| card.point(&foliage.positions, uv));
            let (skins, miss) =
                fit_skins(&foliage, &piece, &card, &region, rest, &motion).expect("fit");
            let mut bones: Vec<u32> = card
                .vertices
                .iter()
                .flat_map(|&v| foliage.bones[v as usize][..2].to_vec())
                .collect();
            bones.sort_unstable();
            bones.dedup();
            let x = combined_corner_weights(&foliage, &card, &region.triangle, &bones);
            let nb = bones.len();
            let combined = [0, 1, 2].map(|i| strongest_four(&bones, &x[i * nb..(i + 1) * nb]));
            let e_fit = leaf_error(&foliage, &piece, &region, rest, skins, &motion);
            let e_combined = leaf_error(&foliage, &piece, &region, rest, combined, &motion);
            assert!(e_fit <= e_combined * 1.001 + 1e-5, "{e_fit} > {e_combined}");
            // The fit's own residual is `leaf_error`'s, in world units.
            let verts = card_vertices(&foliage, &piece);
            let size = (foliage.positions[verts[0] as usize]
                - foliage.positions[verts[3] as usize])
                .length();
            assert!(
                (miss - e_fit * size).abs() <= 0.05 * miss + 1e-6,
                "{miss} against {}",
                e_fit * size
            );
            misses.push(miss);
            for (b, w) in skins {
                assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
                assert!(w.iter().all(|&k| k >= 0.0));
                assert!(b.iter().all(|b| bones.contains(b)));
            }
            fitted_sum += e_fit;
            combined_sum += e_combined;
            fitted_cards += 1;
        }
        assert_eq!(fitted_cards, blended);
        assert!(
            fitted_sum < 0.8 * combined_sum,
            "fitted {fitted_sum} against combined {combined_sum}"
        );
        // Room in the budget keeps the worst-fitting blended cards as quads, one triangle each.
        let all = trim_cards(&tree, &foliage, 0);
        assert_eq!(all.kept_as_quads, 0);
        let some = trim_cards(&tree, &foliage, all.mesh.triangles() + 10);
        assert_eq!(some.kept_as_quads, 10);
        assert_eq!(some.cards, all.cards - 10);
        assert_eq!(some.mesh.triangles(), all.mesh.triangles() + 10);
        let every = trim_cards(&tree, &foliage, foliage.triangles());
        assert_eq!(every.kept_as_quads, blended);
        assert_eq!(every.mesh.triangles(), all.mesh.triangles() + blended);
    }

    #[test]
    fn a_leaf_filling_its_card_keeps_its_quad() {
        // Every texel passing: any triangle holding the card is twice its area.
        let (mut tree, foliage) = sample();
        let m = &tree.materials[foliage.primitives[0].material];
        let t = &mut tree.textures[m.base_color_texture.expect("leaf texture")];
        t.rgba.chunks_exact_mut(4).for_each(|p| p[3] = 255);
        let trimmed = trim_cards(&tree, &foliage, 0);
        assert_eq!(trimmed.cards, 0);
        assert_eq!(trimmed.mesh.triangles(), foliage.triangles());
    }

    #[test]
    fn trimmed_cards_are_one_triangle_each_drawing_the_same_texels() {
        let (mut tree, foliage) = sample();
        disc_leaves(&mut tree, &foliage);
        let pieces = foliage.pieces();
        let trimmed = trim_cards(&tree, &foliage, 0);
        assert_eq!(trimmed.cards, pieces.len(), "every card is trimmed");
        assert_eq!(trimmed.mesh.triangles(), pieces.len());
        // A disc of area 0.28 needs a triangle of at least 3√3·0.3² = 0.47 of the card.
        let ratio = trimmed.area_after / trimmed.area_before;
        assert!((0.45..0.6).contains(&ratio), "area ratio {ratio}");

        // Where the card drew a passing texel the triangle draws it, and the triangle draws
        // nothing more (clamped texels outside the card are transparent), over a grid of the
        // card's texture region and around it.
        let m = &tree.materials[foliage.primitives[0].material];
        let texture = &tree.textures[m.base_color_texture.expect("leaf texture")];
        let region = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let tri = trimmed_triangle(&tree, m, &region).expect("a triangle");
        let (w, h) = (texture.width, texture.height);
        let passes = |uv: Vec2| {
            let x = m.base_color_wrap[0].texel(uv.x * w as f32, w) as usize;
            let y = m.base_color_wrap[1].texel(uv.y * h as f32, h) as usize;
            f32::from(texture.rgba[(y * w as usize + x) * 4 + 3]) / 255.0 >= m.alpha_cutoff
        };
        let n = 300;
        let mut drawn = 0;
        for j in 0..n {
            for i in 0..n {
                let uv = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * 3.0 / n as f32 - Vec2::ONE;
                let in_card = uv.min_element() >= 0.0 && uv.max_element() <= 1.0;
                let b = barycentric(&tri, uv).expect("triangle");
                let in_triangle = b.iter().all(|&k| k >= 0.0);
                let card = in_card && passes(uv);
                assert_eq!(card, in_triangle && passes(uv), "at {uv}");
                drawn += usize::from(card);
            }
        }
        assert!(drawn > n * n / 40, "{drawn}");

        // Each trimmed card faces its card's way and keeps its skin.
        for (piece, new) in pieces.iter().zip(trimmed.mesh.pieces()) {
            let normal = |mesh: &WoodMesh, tris: &[(usize, usize)]| -> Vec3 {
                tris.iter()
                    .map(|&(p, t)| {
                        let i = &mesh.primitives[p].indices[3 * t..3 * t + 3];
                        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[i[k] as usize]);
                        (b - a).cross(c - a)
                    })
                    .sum()
            };
            let (before, after) = (normal(&foliage, piece), normal(&trimmed.mesh, &new));
            assert!(before.normalize().dot(after.normalize()) > 0.999);
            let v0 = card_vertices(&foliage, piece)[0] as usize;
            for v in card_vertices(&trimmed.mesh, &new) {
                assert_eq!(trimmed.mesh.bones[v as usize], foliage.bones[v0]);
                assert_eq!(trimmed.mesh.weights[v as usize], foliage.weights[v0]);
            }
        }
    }

    /// The shared trees' sprig textures: every card trimmed, to 59–80 % of its area.
    #[test]
    fn the_shared_trees_cards_are_trimmed() {
        let paths = frond_testdata::require_trees!([
            "oak_medium.glb",
            "oak_medium_blendedleaves.glb",
            "pine_medium_blender.glb",
            "bush_1.glb"
        ]);
        for path in paths {
            let tree = import(&path, &ImportOptions::default()).expect("tree");
            let foliage = WoodMesh::from_tree_part(&tree, Part::Foliage);
            let cards = foliage.pieces().iter().filter(|p| p.len() == 2).count();
            let trimmed = trim_cards(&tree, &foliage, 0);
            let ratio = trimmed.area_after / trimmed.area_before;
            let name = path.display();
            assert!(
                trimmed.cards == cards,
                "{name}: {} of {cards}",
                trimmed.cards
            );
            assert!((0.5..0.82).contains(&ratio), "{name}: area ratio {ratio}");
            assert_eq!(
                trimmed.mesh.triangles(),
                foliage.triangles() - trimmed.cards
            );
        }
    }
}
