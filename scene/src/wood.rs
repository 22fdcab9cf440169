//! The wood mesh of a LOD: welded rest-pose geometry with skin weights, simplified to an error budget.
//!
//! [`WoodMesh::from_tree`] takes the tree's wood triangles (non-degenerate `Part::Wood`), skins
//! them into rest-pose world space and welds each tree vertex once per material. Skin influences
//! are re-expressed as indices into [`Tree::bones`], so a consumer animates the mesh with the
//! per-bone palette `world(bone.node, t) · rest_world(bone.node)⁻¹` (identity for [`NO_BONE`]):
//! at `t` = rest that palette is the identity, and for trees whose rest pose is their bind pose
//! it reproduces the tree's own linear-blend skinning.
//!
//! [`WoodMesh::simplify`] runs meshoptimizer's attribute-aware edge collapse per connected piece
//! (all materials at once, so material borders stay watertight), with the skin weights, normals
//! and UVs as vertex attributes, and checks the result with true point-to-surface distances,
//! because meshoptimizer's quadric estimate is far too optimistic on thin curved tubes.

use std::collections::{BTreeMap, HashMap, HashSet};

use glam::{Mat3, Vec2, Vec3};
use meshopt::{SimplifyOptions, SimplifyVertex};
use rayon::prelude::*;

use crate::binding::bone_of_node;
use crate::model::{Binding, Part, Tree};
use crate::sampling::world_at;
use crate::skinning::palettes;
use crate::surface_distance::SurfaceBvh;

/// No bone: the vertex stays where it is in the rest pose (its binding node is not under any bone).
pub const NO_BONE: u32 = u32::MAX;

/// Dimensions of the skin-weight embedding handed to the simplifier: every bone gets a fixed
/// pseudo-random unit vector in this space and a vertex's attribute is the weighted sum of its
/// bones' vectors, so blending weights linearly blends the attribute (what the attribute quadrics
/// assume) and two different skins land far apart.
const SKIN_DIMS: usize = 8;

/// Simplifier weight of the skin embedding. meshoptimizer adds attribute error to the
/// position error without normalising it by area (positions are scaled to a unit cube; attribute
/// error is area × weight² × deviation²), so this weighs most where the wood is big (trunk,
/// main limbs) and little on twigs; interpolated skin fields (weights blended across a joint)
/// cost nothing while they stay linear. The result depends on this weight only a little; the
/// distance checks, not this weight, bound the error.
const SKIN_WEIGHT: f32 = 0.5;
/// Simplifier weight of the (unit) normals: shading, secondary to position.
const NORMAL_WEIGHT: f32 = 0.05;
/// Simplifier weight of the UVs (texture space units; bark tiles so drift inside a chart is
/// cheap; seams between charts are kept by meshoptimizer's wedge handling regardless).
const UV_WEIGHT: f32 = 0.01;
/// Vertices locked on every border loop (a branch tube's end rings): 3 keeps a thin branch a
/// triangular prism, visible from every side (2 would allow flat ribbons, with fewer
/// triangles, that vanish edge-on).
const LOOP_LOCKS: usize = 3;

const ATTRS: usize = SKIN_DIMS + 3 + 2;

/// Float slack of the distance check, × the mesh extent.
const DISTANCE_TOLERANCE: f32 = 1e-6;
/// Rounds of "lock the vertices that strayed and simplify again" for a piece that failed.
const LOCK_ROUNDS: usize = 3;
/// Locking is tried only while at most 1/this of the piece's vertices strayed (beyond that the
/// triangle-target search does better).
const STRAY_FRACTION: usize = 20;
/// Barycentric points of a simplified triangle checked against the original surface.
const SURFACE_SAMPLES: [(f32, f32, f32); 13] = [
    (0.5, 0.5, 0.0),
    (0.0, 0.5, 0.5),
    (0.5, 0.0, 0.5),
    (0.25, 0.75, 0.0),
    (0.75, 0.25, 0.0),
    (0.0, 0.25, 0.75),
    (0.0, 0.75, 0.25),
    (0.25, 0.0, 0.75),
    (0.75, 0.0, 0.25),
    (1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0),
    (2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
    (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
    (1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0),
];

/// The wood of a tree as one welded, skinned mesh in rest-pose world space.
#[derive(Clone, Debug, Default)]
pub struct WoodMesh {
    /// Rest-pose world positions (skinned with the rest world matrices).
    pub positions: Vec<Vec3>,
    /// Rest-pose world normals (unit).
    pub normals: Vec<Vec3>,
    /// The base-colour map's coordinates ([`crate::Vertices::uv`]: transform applied).
    pub uvs: Vec<Vec2>,
    /// The input's own texture coordinate sets ([`crate::Vertices::texcoords`], untransformed):
    /// `texcoords[n]` is `TEXCOORD_n`, one entry per vertex, what the tree's materials are
    /// written back with. Empty for a tree that carries none (then `uvs` is `TEXCOORD_0`).
    pub texcoords: Vec<Vec<Vec2>>,
    /// Up to 4 influences per vertex as indices into `Tree::bones` ([`NO_BONE`] only when the
    /// weights are `[1, 0, 0, 0]` and the vertex has no bone), sorted by decreasing weight (ties:
    /// lower bone first); unused slots: bone of slot 0 and weight 0.
    pub bones: Vec<[u32; 4]>,
    /// Skin weights, sum 1.
    pub weights: Vec<[f32; 4]>,
    /// The triangles, one primitive per material.
    pub primitives: Vec<WoodPrimitive>,
}

/// A wood mesh split at a thickness ([`WoodMesh::split_thin_pieces`]).
#[derive(Clone, Debug)]
pub struct ThinSplit {
    /// The pieces at least as thick as the split's thickness.
    pub kept: WoodMesh,
    /// The thinner pieces.
    pub thin: WoodMesh,
    /// How many pieces are in `thin`.
    pub thin_pieces: usize,
}

/// The triangles of one material.
#[derive(Clone, Debug)]
pub struct WoodPrimitive {
    /// Index into `Tree::materials`.
    pub material: usize,
    /// Triangle list into the mesh's vertex arrays.
    pub indices: Vec<u32>,
}

impl WoodMesh {
    /// The wood (Part::Wood, non-degenerate triangles) of `tree` at rest, one primitive per
    /// material (ascending material index), vertices deduplicated: a tree vertex used by several
    /// wood triangles of one material is one vertex; distinct tree vertices are never merged
    /// (UV seams stay). Vertices are numbered in order of first use over the wood triangles in
    /// file order. Triangles naming vertices out of range are skipped.
    pub fn from_tree(tree: &Tree) -> WoodMesh {
        Self::from_tree_part(tree, Part::Wood)
    }

    /// [`WoodMesh::from_tree`] for either part: the foliage the same way gives LOD0's leaves
    /// as one welded, skinned mesh.
    pub fn from_tree_part(tree: &Tree, part: Part) -> WoodMesh {
        Self::from_tree_part_mapped(tree, part).0
    }

    /// [`WoodMesh::from_tree`], plus the tree vertex (index into `Tree::vertices`) each mesh
    /// vertex came from.
    pub fn from_tree_mapped(tree: &Tree) -> (WoodMesh, Vec<u32>) {
        Self::from_tree_part_mapped(tree, Part::Wood)
    }

    /// [`WoodMesh::from_tree_part`] plus the tree vertex each mesh vertex came from.
    pub fn from_tree_part_mapped(tree: &Tree, part: Part) -> (WoodMesh, Vec<u32>) {
        let v = &tree.vertices;
        let nv = v.len();
        let vertex_ok = |i: u32| {
            let i = i as usize;
            i < nv
                && i < v.binding.len()
                && i < v.joints.len()
                && i < v.weights.len()
                && v.position[i].is_finite()
        };
        // Wood triangles per material, in file order.
        let mut by_material: BTreeMap<usize, Vec<[u32; 3]>> = BTreeMap::new();
        let mut order: Vec<(usize, [u32; 3])> = Vec::new();
        for t in &tree.triangles {
            if t.part != part || t.degenerate || !t.v.iter().all(|&i| vertex_ok(i)) {
                continue;
            }
            let m = t.material as usize;
            by_material.entry(m).or_default().push(t.v);
            order.push((m, t.v));
        }
        if order.is_empty() {
            return (WoodMesh::default(), Vec::new());
        }
        // Output vertex per (material, tree vertex), numbered by first use in file order.
        let mut slot: HashMap<(usize, u32), u32> = HashMap::new();
        let mut source: Vec<u32> = Vec::new();
        for (m, tri) in &order {
            for &i in tri {
                slot.entry((*m, i)).or_insert_with(|| {
                    source.push(i);
                    (source.len() - 1) as u32
                });
            }
        }
        let primitives: Vec<WoodPrimitive> = by_material
            .into_iter()
            .map(|(material, tris)| WoodPrimitive {
                material,
                indices: tris
                    .iter()
                    .flat_map(|tri| tri.map(|i| slot[&(material, i)]))
                    .collect(),
            })
            .collect();

        let world = world_at(tree, None, 0.0);
        let pal = palettes(tree, &world);
        // Tree bone of every palette entry of every binding.
        let palette_bones: Vec<Vec<u32>> = tree
            .bindings
            .iter()
            .map(|b| match b {
                Binding::Skin { joints, .. } => joints
                    .iter()
                    .map(|&j| {
                        if j < tree.bones.len() {
                            j as u32
                        } else {
                            NO_BONE
                        }
                    })
                    .collect(),
                Binding::Node(n) => vec![
                    (*n < tree.rig.nodes.len())
                        .then(|| bone_of_node(tree, *n))
                        .flatten()
                        .map_or(NO_BONE, |b| b as u32),
                ],
            })
            .collect();

        let n_out = source.len();
        let mut mesh = WoodMesh {
            positions: Vec::with_capacity(n_out),
            normals: Vec::with_capacity(n_out),
            uvs: Vec::with_capacity(n_out),
            texcoords: v
                .texcoords
                .iter()
                .map(|set| {
                    source
                        .iter()
                        .map(|&i| set.get(i as usize).copied().unwrap_or(Vec2::ZERO))
                        .collect()
                })
                .collect(),
            bones: Vec::with_capacity(n_out),
            weights: Vec::with_capacity(n_out),
            primitives,
        };
        for &i in &source {
            let i = i as usize;
            let palette = pal
                .get(v.binding[i] as usize)
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            let pbones = palette_bones
                .get(v.binding[i] as usize)
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            let (j, w) = (v.joints[i], v.weights[i]);
            let p = v.position[i];
            // Exactly skinning::skin_into's arithmetic, so positions equal `skin_positions`.
            let pos = if w[0] >= 1.0 {
                palette
                    .get(j[0] as usize)
                    .map_or(p, |m| m.transform_point3(p))
            } else {
                let mut acc = Vec3::ZERO;
                for s in 0..4 {
                    if w[s] > 0.0
                        && let Some(m) = palette.get(j[s] as usize)
                    {
                        acc += m.transform_point3(p) * w[s];
                    }
                }
                acc
            };
            // Normal: inverse transpose of the blended linear part.
            let mut blend = Mat3::ZERO;
            for s in 0..4 {
                if w[s] > 0.0
                    && let Some(m) = palette.get(j[s] as usize)
                {
                    blend += Mat3::from_mat4(*m) * w[s];
                }
            }
            let n = v.normal.get(i).copied().unwrap_or(Vec3::ZERO);
            let det = blend.determinant();
            let normal = if det.is_finite() && det.abs() > 1e-12 {
                blend.inverse().transpose() * n
            } else {
                blend * n
            };
            let (bones, weights) = influences(j, w, pbones);
            mesh.positions.push(pos);
            mesh.normals.push(normal.normalize_or_zero());
            mesh.uvs.push(v.uv.get(i).copied().unwrap_or(Vec2::ZERO));
            mesh.bones.push(bones);
            mesh.weights.push(weights);
        }
        mesh.fill_missing_normals();
        (mesh, source)
    }

    /// The mesh without the vertices no triangle uses, vertices in order of first use
    /// (primitive by primitive), everything else unchanged.
    pub fn compacted(&self) -> WoodMesh {
        self.with_primitives(self.primitives.iter().cloned())
    }

    /// A mesh of `primitives` (indices into this mesh's vertices) holding only the vertices
    /// they use, in order of first use; a missing texture coordinate is zero.
    fn with_primitives(&self, primitives: impl Iterator<Item = WoodPrimitive>) -> WoodMesh {
        let mut remap = vec![u32::MAX; self.positions.len()];
        let mut out = WoodMesh {
            texcoords: vec![Vec::new(); self.texcoords.len()],
            ..WoodMesh::default()
        };
        for p in primitives {
            let indices = p
                .indices
                .iter()
                .map(|&i| {
                    let r = &mut remap[i as usize];
                    if *r == u32::MAX {
                        *r = out.positions.len() as u32;
                        let i = i as usize;
                        out.positions.push(self.positions[i]);
                        out.normals.push(self.normals[i]);
                        out.uvs.push(self.uvs[i]);
                        for (o, set) in out.texcoords.iter_mut().zip(&self.texcoords) {
                            o.push(set.get(i).copied().unwrap_or(Vec2::ZERO));
                        }
                        out.bones.push(self.bones[i]);
                        out.weights.push(self.weights[i]);
                    }
                    *r
                })
                .collect();
            out.primitives.push(WoodPrimitive {
                material: p.material,
                indices,
            });
        }
        out
    }

    /// Appends `other`'s vertices and primitives (its indices shifted past this mesh's
    /// vertices): one mesh, several materials.
    pub fn append(&mut self, other: &WoodMesh) {
        let base = self.positions.len() as u32;
        // Texture coordinate sets: as many as either has; a set one mesh lacks is zero there.
        let sets = self.texcoords.len().max(other.texcoords.len());
        self.texcoords.resize(sets, Vec::new());
        for (k, set) in self.texcoords.iter_mut().enumerate() {
            set.resize(self.positions.len(), Vec2::ZERO);
            match other.texcoords.get(k) {
                Some(o) if o.len() == other.positions.len() => set.extend_from_slice(o),
                _ => set.resize(self.positions.len() + other.positions.len(), Vec2::ZERO),
            }
        }
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.bones.extend_from_slice(&other.bones);
        self.weights.extend_from_slice(&other.weights);
        for p in &other.primitives {
            self.primitives.push(WoodPrimitive {
                material: p.material,
                indices: p.indices.iter().map(|&i| i + base).collect(),
            });
        }
    }

    /// The connected pieces of the mesh's triangles (over shared vertex indices: a leaf card,
    /// a branch tube), each as `(primitive, triangle)` pairs, in order of first triangle.
    pub fn pieces(&self) -> Vec<Vec<(usize, usize)>> {
        let mut parent: Vec<usize> = (0..self.positions.len()).collect();
        fn find(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        let n = parent.len();
        let valid = |t: &[u32]| t.iter().all(|&v| (v as usize) < n);
        for p in &self.primitives {
            for t in p.indices.chunks_exact(3).filter(|t| valid(t)) {
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
        for (pi, p) in self.primitives.iter().enumerate() {
            for (ti, t) in p
                .indices
                .chunks_exact(3)
                .enumerate()
                .filter(|(_, t)| valid(t))
            {
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

    /// The mesh without its pieces ([`WoodMesh::pieces`]) thinner than `min_thickness`, and how
    /// many were dropped. A piece's thickness is estimated as a tube's diameter,
    /// `area / (π · length)`, its length the diagonal of its bounds: exact for a straight tube,
    /// larger (so kept) for a curved one or a piece that is not a tube (a whole connected
    /// tree). A far LOD drops branches narrower than a pixel this way: simplification cannot
    /// collapse a closed tube, and a sub-pixel branch only aliases.
    pub fn without_thin_pieces(&self, min_thickness: f32) -> (WoodMesh, usize) {
        let (kept, _, thin_pieces) = self.partition_by_thickness(min_thickness);
        (self.mesh_of(kept), thin_pieces)
    }

    /// The mesh split at `min_thickness` as [`WoodMesh::without_thin_pieces`] splits it: the
    /// pieces kept, and the thin ones as a mesh of their own (what a far LOD bakes into its
    /// billboards instead of dropping).
    pub fn split_thin_pieces(&self, min_thickness: f32) -> ThinSplit {
        let (kept, thin, thin_pieces) = self.partition_by_thickness(min_thickness);
        ThinSplit {
            kept: self.mesh_of(kept),
            thin: self.mesh_of(thin),
            thin_pieces,
        }
    }

    /// The thickness of `piece` (one of [`WoodMesh::pieces`]) as a tube's diameter,
    /// `area / (π · length)`, its length the diagonal of its bounds
    /// ([`WoodMesh::without_thin_pieces`] drops pieces by it).
    pub fn piece_thickness(&self, piece: &[(usize, usize)]) -> f32 {
        let corners = |&(p, t): &(usize, usize)| {
            let i = &self.primitives[p].indices[3 * t..3 * t + 3];
            [0, 1, 2].map(|k| self.positions[i[k] as usize])
        };
        let area: f32 = piece
            .iter()
            .map(|pt| {
                let [a, b, c] = corners(pt);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        let length = crate::model::Bounds::of(piece.iter().flat_map(corners)).diagonal();
        if length > 0.0 {
            area / (std::f32::consts::PI * length)
        } else {
            0.0
        }
    }

    /// The triangles of the pieces at least `min_thickness` thick and of the thinner ones, per
    /// primitive, and how many pieces are thinner ([`WoodMesh::without_thin_pieces`] says how
    /// thickness is estimated).
    fn partition_by_thickness(
        &self,
        min_thickness: f32,
    ) -> (Vec<WoodPrimitive>, Vec<WoodPrimitive>, usize) {
        let empty = || -> Vec<WoodPrimitive> {
            (self.primitives.iter())
                .map(|p| WoodPrimitive {
                    material: p.material,
                    indices: Vec::new(),
                })
                .collect()
        };
        let (mut kept, mut thin) = (empty(), empty());
        let mut thin_pieces = 0;
        for piece in &self.pieces() {
            let to = if self.piece_thickness(piece) < min_thickness {
                thin_pieces += 1;
                &mut thin
            } else {
                &mut kept
            };
            for &(p, t) in piece {
                to[p]
                    .indices
                    .extend_from_slice(&self.primitives[p].indices[3 * t..3 * t + 3]);
            }
        }
        (kept, thin, thin_pieces)
    }

    /// A mesh of `primitives` (triangles of this mesh), its vertices compacted.
    fn mesh_of(&self, mut primitives: Vec<WoodPrimitive>) -> WoodMesh {
        primitives.retain(|p| !p.indices.is_empty());
        self.with_primitives(primitives.into_iter())
    }

    /// Number of triangles over all primitives.
    pub fn triangles(&self) -> usize {
        self.primitives.iter().map(|p| p.indices.len() / 3).sum()
    }

    /// Every triangle's corners at rest, primitive by primitive (what a surface-distance BVH
    /// is built from).
    pub fn triangle_corners(&self) -> Vec<[Vec3; 3]> {
        self.primitives
            .iter()
            .flat_map(|p| p.indices.chunks_exact(3))
            .map(|t| [0, 1, 2].map(|k| self.positions[t[k] as usize]))
            .collect()
    }

    /// Bones (Tree::bones indices) with non-zero weight on some vertex that some triangle uses,
    /// ascending.
    pub fn used_bones(&self) -> Vec<u32> {
        let mut used = vec![false; self.bones.len()];
        for p in &self.primitives {
            for &i in &p.indices {
                if let Some(u) = used.get_mut(i as usize) {
                    *u = true;
                }
            }
        }
        let mut out: Vec<u32> = Vec::new();
        for (i, _) in used.iter().enumerate().filter(|(_, u)| **u) {
            let w = self.weights.get(i).copied().unwrap_or([0.0; 4]);
            for (s, &b) in self.bones[i].iter().enumerate() {
                if w[s] > 0.0 && b != NO_BONE {
                    out.push(b);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Simplified so that no surface point moves more than `max_error` world units (checked,
    /// see below), returning the achieved error too.
    ///
    /// How: the mesh is split into its connected pieces (per position-welded topology; a tree's
    /// branches are usually one piece each) and each piece is simplified on its own, in
    /// parallel, by meshoptimizer's attribute-aware edge collapse
    /// (`simplify_with_attributes_and_locks`, absolute error, first with no triangle target). All
    /// primitives of a piece go in together, a vertex shared by several primitives split per
    /// primitive, so material borders are attribute seams that stay watertight and in place. The
    /// attributes are the skin weights (embedded, see `SKIN_WEIGHT`), normals and UVs; their
    /// error counts against the same budget, so vertices whose skins differ are not merged
    /// unless that is nearly free. Three vertices of every border loop are locked, so open tubes
    /// (branches) keep their end rings and never collapse into lines.
    ///
    /// meshoptimizer's error is a quadric estimate (an area-weighted mean of squared plane
    /// distances) that thin curved tubes fool: it can report a small error for a piece whose
    /// vertices end up many times farther away. So every piece is then checked with true distances:
    /// each of its vertices, triangle centroids and edge midpoints must lie within `max_error`
    /// of the simplified piece, and points spread over each simplified triangle (edge midpoints
    /// and quarter points, centroid, three interior points) within `max_error` of the original
    /// piece. A piece that fails in a few places gets those vertices locked and is simplified
    /// again (up to 3 rounds); otherwise the fewest triangles that pass are found by binary
    /// search on meshoptimizer's triangle target (the whole piece always passes).
    ///
    /// Guarantees: the result's vertices are a subset of this mesh's vertices with unchanged
    /// position, normal, UVs (every texture coordinate set) and skin (so its used bones are a
    /// subset of these); every triangle keeps its primitive's material; collapsed (repeated-vertex or zero-area) triangles are
    /// dropped, empty primitives removed, unused vertices removed and indices compacted
    /// (vertices in order of first use); the distance checks above hold (within 1e-6 × the
    /// mesh extent for rounding); the returned error is the largest of meshoptimizer's
    /// estimates and the measured distances, never more than `max_error` (a negative or
    /// non-finite `max_error` counts as 0). Same input, same output. An empty mesh (or one
    /// whose triangles all name missing vertices) gives an empty mesh and error 0.
    pub fn simplify(&self, max_error: f32) -> (WoodMesh, f32) {
        let max_error = if max_error.is_finite() {
            max_error.max(0.0)
        } else {
            0.0
        };
        let nv = self.positions.len();
        let vertex_ok = |i: u32| {
            let i = i as usize;
            i < nv
                && i < self.normals.len()
                && i < self.uvs.len()
                && i < self.bones.len()
                && i < self.weights.len()
                && self.positions[i].is_finite()
        };
        // Internal vertices: one per (primitive, mesh vertex).
        let mut slot: HashMap<(usize, u32), u32> = HashMap::new();
        let mut internal: Vec<(usize, u32)> = Vec::new();
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        for (pi, p) in self.primitives.iter().enumerate() {
            for tri in p.indices.chunks_exact(3) {
                if !tri.iter().all(|&i| vertex_ok(i))
                    || tri[0] == tri[1]
                    || tri[1] == tri[2]
                    || tri[0] == tri[2]
                {
                    continue;
                }
                triangles.push([0, 1, 2].map(|c| {
                    *slot.entry((pi, tri[c])).or_insert_with(|| {
                        internal.push((pi, tri[c]));
                        (internal.len() - 1) as u32
                    })
                }));
            }
        }
        if triangles.is_empty() {
            return (WoodMesh::default(), 0.0);
        }
        let extent = crate::model::Bounds::of(self.positions.iter().copied()).size();
        let limit = max_error + extent * DISTANCE_TOLERANCE;

        // Connected pieces over position-welded vertices, numbered by first triangle.
        let welded = weld_positions(internal.iter().map(|&(_, i)| self.positions[i as usize]));
        let mut parent: Vec<u32> = (0..welded.count as u32).collect();
        for t in &triangles {
            let [a, b, c] = t.map(|k| welded.id[k as usize]);
            union(&mut parent, a, b);
            union(&mut parent, a, c);
        }
        let mut piece_of_root: HashMap<u32, usize> = HashMap::new();
        let mut pieces: Vec<Vec<[u32; 3]>> = Vec::new();
        for t in &triangles {
            let root = find(&mut parent, welded.id[t[0] as usize]);
            let p = *piece_of_root.entry(root).or_insert_with(|| {
                pieces.push(Vec::new());
                pieces.len() - 1
            });
            pieces[p].push(*t);
        }

        let simplified: Vec<(Vec<[u32; 3]>, f32)> = pieces
            .par_iter()
            .map(|piece| self.simplify_piece(&internal, piece, max_error, limit))
            .collect();

        let mut per_prim: Vec<Vec<u32>> = vec![Vec::new(); self.primitives.len()];
        let mut error = 0.0f32;
        for (tris, e) in simplified {
            error = error.max(e);
            for t in tris {
                per_prim[internal[t[0] as usize].0].extend(t.map(|k| internal[k as usize].1));
            }
        }
        // Compact: vertices in order of first use.
        let out = self.with_primitives(
            per_prim
                .into_iter()
                .enumerate()
                .filter(|(_, idx)| !idx.is_empty())
                .map(|(pi, indices)| WoodPrimitive {
                    material: self.primitives[pi].material,
                    indices,
                }),
        );
        (out, error.min(max_error))
    }

    /// Simplifies one connected piece (triangles over internal vertices), returning its
    /// triangles (internal vertices) and error; see [`WoodMesh::simplify`].
    ///
    /// First as far as the error bound allows, locking a few stray vertices and trying again
    /// ([`LOCK_ROUNDS`] times at most); failing that, the fewest triangles that pass.
    fn simplify_piece(
        &self,
        internal: &[(usize, u32)],
        piece: &[[u32; 3]],
        max_error: f32,
        limit: f32,
    ) -> (Vec<[u32; 3]>, f32) {
        let problem = PieceProblem::new(self, internal, piece, max_error, limit);
        let mut locks = border_locks(&problem.positions, &problem.indices);
        let n = piece.len();
        // As far as the error bound allows; a few stray vertices get locked and the piece is
        // simplified again.
        let (tris, error, mut stray) = problem.attempt(0, &locks);
        if let Some(e) = error {
            return (problem.back(tris), e);
        }
        for _ in 0..LOCK_ROUNDS {
            if stray.len() > problem.global.len() / STRAY_FRACTION {
                break;
            }
            stray.sort_unstable();
            stray.dedup();
            for &k in &stray {
                locks[k as usize] = SimplifyVertex::Lock;
            }
            let (tris, error, s) = problem.attempt(0, &locks);
            if let Some(e) = error {
                return (problem.back(tris), e);
            }
            stray = s;
        }
        // Otherwise the fewest triangles that pass (binary search on meshoptimizer's triangle
        // target; the whole piece always passes).
        let locks = border_locks(&problem.positions, &problem.indices);
        let (mut lo, mut hi) = (0usize, n);
        let mut best: Option<(Vec<[u32; 3]>, f32)> = None;
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            match problem.attempt(mid, &locks) {
                (tris, Some(e), _) => {
                    hi = mid;
                    best = Some((tris, e));
                }
                _ => lo = mid,
            }
        }
        match best {
            Some((tris, e)) => (problem.back(tris), e),
            None => (piece.to_vec(), 0.0),
        }
    }

    /// Replaces zero normals (no normal in the file, or a singular skin) by the area-weighted
    /// normal of the vertex's triangles (+Y when that is zero too).
    fn fill_missing_normals(&mut self) {
        if self.normals.iter().all(|n| *n != Vec3::ZERO) {
            return;
        }
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for p in &self.primitives {
            for t in p.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize]);
                let n = (b - a).cross(c - a);
                for &i in t {
                    acc[i as usize] += n;
                }
            }
        }
        for (n, a) in self.normals.iter_mut().zip(acc) {
            if *n == Vec3::ZERO {
                *n = a.try_normalize().unwrap_or(Vec3::Y);
            }
        }
    }
}

/// One connected piece as meshoptimizer simplifies it (vertices numbered locally), with what
/// every simplification of it is checked against (see [`WoodMesh::simplify`]).
struct PieceProblem<'a> {
    /// Per internal vertex: (primitive, mesh vertex).
    internal: &'a [(usize, u32)],
    /// The internal vertex of each local vertex, in order of first use.
    global: Vec<u32>,
    /// The piece's triangles over local vertices, 3 indices each.
    indices: Vec<u32>,
    /// Local vertices' positions.
    positions: Vec<[f32; 3]>,
    /// Local vertices' attributes, [`ATTRS`] each: skin embedding, normal, uv.
    attributes: Vec<f32>,
    /// Weight of each attribute in meshoptimizer's error.
    attribute_weights: [f32; ATTRS],
    /// The original piece's surface.
    original_bvh: SurfaceBvh,
    /// Points that must stay near the simplified piece: every vertex, and every triangle's
    /// centroid and edge midpoints, each with the local vertices it belongs to (3, repeated as
    /// needed), which are locked when it strays.
    checks: Vec<(Vec3, [u32; 3])>,
    /// The original triangles as sorted vertex sets: a simplified triangle among them lies on
    /// the original surface.
    original_sets: HashSet<[u32; 3]>,
    /// The error bound meshoptimizer is given.
    max_error: f32,
    /// The largest distance a check point may lie from the simplified piece.
    limit: f32,
}

impl<'a> PieceProblem<'a> {
    /// Numbers the piece's vertices locally and gathers their positions and attributes from
    /// `mesh`, then the check points and original triangle sets.
    fn new(
        mesh: &WoodMesh,
        internal: &'a [(usize, u32)],
        piece: &[[u32; 3]],
        max_error: f32,
        limit: f32,
    ) -> Self {
        // Local numbering.
        let mut local: HashMap<u32, u32> = HashMap::new();
        let mut global: Vec<u32> = Vec::new();
        let indices: Vec<u32> = piece
            .iter()
            .flatten()
            .map(|&k| {
                *local.entry(k).or_insert_with(|| {
                    global.push(k);
                    (global.len() - 1) as u32
                })
            })
            .collect();
        let mesh_vertex = |k: u32| internal[global[k as usize] as usize].1 as usize;
        let positions: Vec<[f32; 3]> = (0..global.len() as u32)
            .map(|k| mesh.positions[mesh_vertex(k)].to_array())
            .collect();
        let point = |k: u32| Vec3::from(positions[k as usize]);
        let mut attributes: Vec<f32> = Vec::with_capacity(global.len() * ATTRS);
        for k in 0..global.len() as u32 {
            let i = mesh_vertex(k);
            let mut skin = [0.0f32; SKIN_DIMS];
            for s in 0..4 {
                let w = mesh.weights[i][s];
                if w > 0.0 {
                    let e = bone_embedding(mesh.bones[i][s]);
                    for d in 0..SKIN_DIMS {
                        skin[d] += w * e[d];
                    }
                }
            }
            attributes.extend_from_slice(&skin);
            attributes.extend_from_slice(&mesh.normals[i].to_array());
            attributes.extend_from_slice(&mesh.uvs[i].to_array());
        }
        let mut attribute_weights = [0.0f32; ATTRS];
        attribute_weights[..SKIN_DIMS].fill(SKIN_WEIGHT);
        attribute_weights[SKIN_DIMS..SKIN_DIMS + 3].fill(NORMAL_WEIGHT);
        attribute_weights[SKIN_DIMS + 3..].fill(UV_WEIGHT);

        // The original piece and the points that must stay near the simplified one: vertices
        // (with the triangles they belong to, for locking), centroids and edge midpoints.
        let original: Vec<[Vec3; 3]> = indices
            .chunks_exact(3)
            .map(|t| [point(t[0]), point(t[1]), point(t[2])])
            .collect();
        let original_bvh = SurfaceBvh::new(original.clone());
        let mut checks: Vec<(Vec3, [u32; 3])> = (0..global.len() as u32)
            .map(|k| (point(k), [k; 3]))
            .collect();
        for (t, p) in indices.chunks_exact(3).zip(&original) {
            let tri = [t[0], t[1], t[2]];
            checks.push(((p[0] + p[1] + p[2]) / 3.0, tri));
            for c in 0..3 {
                checks.push((
                    (p[c] + p[(c + 1) % 3]) * 0.5,
                    [tri[c], tri[(c + 1) % 3], tri[c]],
                ));
            }
        }
        // The original triangles as vertex sets: a simplified triangle among them lies on the
        // original surface.
        let original_sets: HashSet<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| sorted3([t[0], t[1], t[2]]))
            .collect();
        PieceProblem {
            internal,
            global,
            indices,
            positions,
            attributes,
            attribute_weights,
            original_bvh,
            checks,
            original_sets,
            max_error,
            limit,
        }
    }

    /// The mesh vertex of local vertex `k`.
    fn mesh_vertex(&self, k: u32) -> usize {
        self.internal[self.global[k as usize] as usize].1 as usize
    }

    /// The position of local vertex `k`.
    fn point(&self, k: u32) -> Vec3 {
        Vec3::from(self.positions[k as usize])
    }

    /// Triangles over local vertices renumbered to internal vertices.
    fn back(&self, tris: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
        tris.into_iter()
            .map(|t| t.map(|k| self.global[k as usize]))
            .collect()
    }

    /// One meshoptimizer run for a triangle target, then the distance checks: the surviving
    /// triangles, the error (estimate and measured) when they pass, and the stray vertices.
    fn attempt(
        &self,
        target_triangles: usize,
        locks: &[SimplifyVertex],
    ) -> (Vec<[u32; 3]>, Option<f32>, Vec<u32>) {
        let mut estimate = 0.0f32;
        let (max_error, limit) = (self.max_error, self.limit);
        let global = &self.global;
        let mesh_vertex = |k: u32| self.mesh_vertex(k);
        let point = |k: u32| self.point(k);
        let result = meshopt::simplify_with_attributes_and_locks_decoder(
            &self.indices,
            &self.positions,
            &self.attributes,
            &self.attribute_weights,
            ATTRS * std::mem::size_of::<f32>(),
            locks,
            target_triangles * 3,
            max_error,
            SimplifyOptions::ErrorAbsolute,
            Some(&mut estimate),
        );
        let tris: Vec<[u32; 3]> = result
            .chunks_exact(3)
            .filter_map(|t| {
                let t = [t[0], t[1], t[2]];
                if t.iter().any(|&k| k as usize >= global.len()) {
                    return None;
                }
                let v = t.map(mesh_vertex);
                if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                    return None;
                }
                let [a, b, c] = t.map(point);
                ((b - a).cross(c - a).length_squared() > 0.0).then_some(t)
            })
            .collect();
        let simplified: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(point)).collect();
        let bvh = SurfaceBvh::new(simplified.clone());
        let mut measured = estimate;
        let mut stray: Vec<u32> = Vec::new();
        // What the simplified piece keeps of the original: a check point on a kept vertex,
        // edge or triangle lies on it (distance 0, or float noise), which changes neither
        // the maximum nor the strays: it needs no query (at near LODs most are kept).
        let kept = Kept::of(&tris, global.len());
        // Each distance matters only over the running maximum (and the limit): the
        // bounded query gives the same maximum and the same strays.
        for (p, owners) in &self.checks {
            if kept.holds(*owners) {
                continue;
            }
            let d = bvh.distance_beyond(*p, measured.min(limit));
            if d > limit {
                stray.extend_from_slice(owners);
            } else {
                measured = measured.max(d);
            }
        }
        let mut inward = true;
        'outer: for (s, t) in simplified.iter().zip(&tris) {
            if self.original_sets.contains(&sorted3(*t)) {
                continue;
            }
            for (wa, wb, wc) in SURFACE_SAMPLES {
                let d = self
                    .original_bvh
                    .distance_beyond(s[0] * wa + s[1] * wb + s[2] * wc, measured.min(limit));
                if d > limit {
                    inward = false;
                    break 'outer;
                }
                measured = measured.max(d);
            }
        }
        let pass = stray.is_empty() && inward;
        (tris, pass.then_some(measured), stray)
    }
}

/// A triangle's vertex indices in ascending order: the triangle as a set, whatever its winding.
fn sorted3(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// The vertices, edges and triangles a simplified piece keeps of the original (local vertex
/// indices), for the check points on them ([`WoodMesh::simplify`]'s distance checks).
struct Kept {
    vertices: Vec<bool>,
    edges: HashSet<[u32; 2]>,
    triangles: HashSet<[u32; 3]>,
}

impl Kept {
    fn of(tris: &[[u32; 3]], vertices: usize) -> Kept {
        let mut kept = Kept {
            vertices: vec![false; vertices],
            edges: HashSet::with_capacity(tris.len() * 3),
            triangles: HashSet::with_capacity(tris.len()),
        };
        for t in tris {
            for c in 0..3 {
                kept.vertices[t[c] as usize] = true;
                let (a, b) = (t[c], t[(c + 1) % 3]);
                kept.edges.insert([a.min(b), a.max(b)]);
            }
            kept.triangles.insert(sorted3(*t));
        }
        kept
    }

    /// Whether the check point of `owners` lies on what is kept: a vertex (`[k, k, k]`), an
    /// edge's midpoint (`[a, b, a]`) or a triangle's centroid (`[a, b, c]`).
    fn holds(&self, owners: [u32; 3]) -> bool {
        let [a, b, c] = owners;
        if a == b {
            self.vertices[a as usize]
        } else if a == c {
            self.edges.contains(&[a.min(b), a.max(b)])
        } else {
            self.triangles.contains(&sorted3(owners))
        }
    }
}

/// A vertex's influences as Tree bone indices: duplicates merged, zero weights dropped, sorted
/// by decreasing weight (ties: lower bone), renormalised; unused slots repeat slot 0's bone
/// with weight 0. Palette entries without a bone are dropped unless nothing else is left.
fn influences(joints: [u16; 4], weights: [f32; 4], palette_bones: &[u32]) -> ([u32; 4], [f32; 4]) {
    let mut list: Vec<(u32, f32)> = Vec::with_capacity(4);
    for s in 0..4 {
        let w = weights[s];
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        let b = palette_bones
            .get(joints[s] as usize)
            .copied()
            .unwrap_or(NO_BONE);
        if b == NO_BONE {
            continue;
        }
        match list.iter_mut().find(|e| e.0 == b) {
            Some(e) => e.1 += w,
            None => list.push((b, w)),
        }
    }
    list.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let total: f32 = list.iter().map(|e| e.1).sum();
    if list.is_empty() || total <= 0.0 || !total.is_finite() {
        // No bone at all: rigid at rest, or the first palette entry's bone if it has one.
        let b = palette_bones
            .get(joints[0] as usize)
            .copied()
            .unwrap_or(NO_BONE);
        return ([b; 4], [1.0, 0.0, 0.0, 0.0]);
    }
    let mut bones = [list[0].0; 4];
    let mut out = [0.0f32; 4];
    for (s, (b, w)) in list.iter().enumerate() {
        bones[s] = *b;
        out[s] = w / total;
    }
    (bones, out)
}

/// A fixed pseudo-random unit vector per bone (SplitMix64 of the bone index).
fn bone_embedding(bone: u32) -> [f32; SKIN_DIMS] {
    let mut state = u64::from(bone).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    let mut e = [0.0f32; SKIN_DIMS];
    let mut len2 = 0.0f32;
    for x in &mut e {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        *x = (z >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0;
        len2 += *x * *x;
    }
    let len = len2.sqrt().max(1e-6);
    e.map(|x| x / len)
}

/// Vertices numbered by bit-identical position (as meshoptimizer welds them).
struct Welded {
    id: Vec<u32>,
    count: usize,
}

fn weld_positions(positions: impl Iterator<Item = Vec3>) -> Welded {
    let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
    let id = positions
        .map(|p| {
            let next = ids.len() as u32;
            *ids.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    Welded {
        id,
        count: ids.len(),
    }
}

fn find(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let up = parent[parent[x as usize] as usize];
        parent[x as usize] = up;
        x = up;
    }
    x
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// Locks that keep every open tube open: on every border loop of the position-welded mesh (what
/// meshoptimizer sees), [`LOOP_LOCKS`] vertices spread evenly around the loop, so a thin branch
/// can shrink to a prism between its end rings but never collapse into a line (whose triangles
/// would be dropped, and the branch with them). Border vertices that are not on a simple loop
/// are locked outright.
fn border_locks(positions: &[[f32; 3]], indices: &[u32]) -> Vec<SimplifyVertex> {
    let Welded {
        id: welded,
        count: nw,
    } = weld_positions(positions.iter().map(|p| Vec3::from(*p)));
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in indices.chunks_exact(3) {
        for c in 0..3 {
            let (a, b) = (welded[t[c] as usize], welded[t[(c + 1) % 3] as usize]);
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    let mut border: Vec<(u32, u32)> = edges
        .into_iter()
        .filter(|(_, n)| *n == 1)
        .map(|(e, _)| e)
        .collect();
    border.sort_unstable();
    let mut adjacent: Vec<Vec<u32>> = vec![Vec::new(); nw];
    for &(a, b) in &border {
        adjacent[a as usize].push(b);
        adjacent[b as usize].push(a);
    }
    let mut lock = vec![false; nw];
    let mut seen = vec![false; nw];
    for start in 0..nw {
        let degree = adjacent[start].len();
        if degree == 0 || seen[start] {
            continue;
        }
        if degree != 2 {
            lock[start] = true;
            seen[start] = true;
            continue;
        }
        // Walk the loop from its smallest vertex towards its smaller neighbour.
        let mut walk = vec![start as u32];
        seen[start] = true;
        let (mut prev, mut cur) = (start as u32, adjacent[start][0].min(adjacent[start][1]));
        let mut simple = true;
        while cur as usize != start {
            let c = cur as usize;
            if adjacent[c].len() != 2 || seen[c] {
                simple = false;
                break;
            }
            seen[c] = true;
            walk.push(cur);
            let next = if adjacent[c][0] == prev {
                adjacent[c][1]
            } else {
                adjacent[c][0]
            };
            (prev, cur) = (cur, next);
        }
        if simple {
            let n = walk.len();
            for k in 0..LOOP_LOCKS.min(n) {
                lock[walk[k * n / LOOP_LOCKS] as usize] = true;
            }
        } else {
            for &w in &walk {
                lock[w as usize] = true;
            }
        }
    }
    welded
        .iter()
        .map(|&w| {
            if lock[w as usize] {
                SimplifyVertex::Lock
            } else {
                SimplifyVertex::None
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tube of `rings` rings of `radial` sides (plus a UV seam column) around `axis(t)`,
    /// t ∈ [0, 1], radius `r`; all on bone 0, open at both ends.
    fn tube(rings: usize, radial: usize, r: f32, axis: impl Fn(f32) -> Vec3) -> WoodMesh {
        let mut m = WoodMesh::default();
        for i in 0..rings {
            let t = i as f32 / (rings - 1) as f32;
            let c = axis(t);
            let tangent = (axis((t + 1e-3).min(1.0)) - axis((t - 1e-3).max(0.0))).normalize();
            let u = tangent.any_orthonormal_vector();
            let v = tangent.cross(u);
            for s in 0..=radial {
                let a = std::f32::consts::TAU * s as f32 / radial as f32;
                let n = u * a.cos() + v * a.sin();
                // The seam column repeats the first one's position bit for bit.
                let n = if s == radial { u } else { n };
                m.positions.push(c + n * r);
                m.normals.push(n);
                m.uvs.push(Vec2::new(s as f32 / radial as f32, t));
                m.bones.push([0; 4]);
                m.weights.push([1.0, 0.0, 0.0, 0.0]);
            }
        }
        let row = (radial + 1) as u32;
        let mut indices = Vec::new();
        for i in 0..rings as u32 - 1 {
            for s in 0..radial as u32 {
                let (a, b) = (i * row + s, i * row + s + 1);
                let (c, d) = (a + row, b + row);
                indices.extend_from_slice(&[a, b, d, a, d, c]);
            }
        }
        m.primitives.push(WoodPrimitive {
            material: 0,
            indices,
        });
        m
    }

    #[test]
    fn thin_pieces_are_dropped_and_thick_ones_kept() {
        // A trunk of diameter 0.4 and a twig of diameter 0.02, both 2 long, apart.
        let mut m = tube(8, 12, 0.2, |t| Vec3::new(0.0, 2.0 * t, 0.0));
        let twig = tube(8, 6, 0.01, |t| Vec3::new(1.0, 1.0, 2.0 * t));
        m.append(&twig);
        assert_eq!(m.pieces().len(), 2);
        let (kept, dropped) = m.without_thin_pieces(0.1);
        assert_eq!(dropped, 1);
        assert_eq!(kept.triangles(), 7 * 12 * 2, "the trunk's triangles");
        assert!(kept.positions.iter().all(|p| p.x.abs() <= 0.2 + 1e-6));
        // The estimate is a straight tube's diameter, a little under it for a polygon.
        let (_, none) = m.without_thin_pieces(0.015);
        assert_eq!(none, 0);
        let (empty, both) = m.without_thin_pieces(0.5);
        assert_eq!((empty.triangles(), both), (0, 2));
        // Split, the thin pieces are a mesh of their own: the twig, whole.
        let split = m.split_thin_pieces(0.1);
        assert_eq!(split.thin_pieces, 1);
        assert_eq!(split.kept.triangles(), kept.triangles());
        assert_eq!(split.thin.triangles(), 7 * 6 * 2, "the twig's triangles");
        assert!(
            split
                .thin
                .positions
                .iter()
                .all(|p| (p.x - 1.0).abs() <= 0.01 + 1e-6)
        );
        assert_eq!(
            split.kept.triangles() + split.thin.triangles(),
            m.triangles()
        );
    }

    /// Largest distance from the original's vertices to the simplified surface.
    fn forward(original: &WoodMesh, simplified: &WoodMesh) -> f32 {
        let bvh = SurfaceBvh::new(simplified.triangle_corners());
        original
            .positions
            .iter()
            .map(|p| bvh.distance(*p))
            .fold(0.0, f32::max)
    }

    #[test]
    fn influences_merge_sort_and_normalise() {
        let (b, w) = influences([0, 1, 0, 2], [0.25; 4], &[5, 3, 7]);
        assert_eq!(b, [5, 3, 7, 5]);
        assert_eq!(w, [0.5, 0.25, 0.25, 0.0]);
        // Unnormalised input is renormalised; zero weights dropped.
        let (b, w) = influences([2, 0, 1, 0], [0.2, 0.6, 0.0, 0.0], &[4, 9, 1]);
        assert_eq!(b, [4, 1, 4, 4]);
        assert!((w[0] - 0.75).abs() < 1e-6 && (w[1] - 0.25).abs() < 1e-6);
        assert_eq!(&w[2..], &[0.0, 0.0]);
        // No bone anywhere: rigid at rest.
        assert_eq!(
            influences([0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0], &[NO_BONE]),
            ([NO_BONE; 4], [1.0, 0.0, 0.0, 0.0])
        );
        // A bone-less entry among real ones is dropped; out-of-range palette entries too.
        let (b, w) = influences([0, 1, 9, 0], [0.5, 0.25, 0.25, 0.0], &[NO_BONE, 6]);
        assert_eq!((b, w), ([6; 4], [1.0, 0.0, 0.0, 0.0]));
        // All weights zero: the first entry's bone, weight 1.
        assert_eq!(
            influences([1, 0, 0, 0], [0.0; 4], &[2, 8]),
            ([8; 4], [1.0, 0.0, 0.0, 0.0])
        );
    }

    #[test]
    fn bone_embedding_is_fixed_unit_and_spread() {
        for b in [0u32, 1, 17, 4000, NO_BONE] {
            let e = bone_embedding(b);
            assert_eq!(e, bone_embedding(b));
            let len: f32 = e.iter().map(|x| x * x).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-5);
        }
        // Neighbouring bones land apart.
        for b in 0..200u32 {
            let (x, y) = (bone_embedding(b), bone_embedding(b + 1));
            let d: f32 = x
                .iter()
                .zip(&y)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f32>()
                .sqrt();
            assert!(d > 0.2, "bones {b} and {} too close: {d}", b + 1);
        }
    }

    #[test]
    fn a_straight_tube_shrinks_to_a_prism_but_not_to_nothing() {
        let m = tube(12, 8, 0.01, |t| Vec3::new(0.0, t, 0.0));
        let (s, err) = m.simplify(0.05);
        assert!(err <= 0.05);
        assert!(
            (6..=12).contains(&s.triangles()),
            "{} triangles",
            s.triangles()
        );
        assert!(forward(&m, &s) <= 0.05 + 1e-6);
        // Thick: the rings must stay round.
        let m = tube(12, 8, 1.0, |t| Vec3::new(0.0, 10.0 * t, 0.0));
        let (s, _) = m.simplify(0.05);
        assert!(s.triangles() >= 16, "{} triangles", s.triangles());
        assert!(forward(&m, &s) <= 0.05 + 1e-5);
    }

    #[test]
    fn a_curved_thin_tube_keeps_its_curve() {
        // Quarter circle of radius 1: a straight prism between the ends would be 0.29 off.
        let axis = |t: f32| {
            let a = t * std::f32::consts::FRAC_PI_2;
            Vec3::new(1.0 - a.cos(), a.sin(), 0.0)
        };
        let m = tube(33, 6, 0.01, axis);
        for e in [0.005, 0.02, 0.1] {
            let (s, err) = m.simplify(e);
            assert!(err <= e);
            let d = forward(&m, &s);
            assert!(d <= e + 1e-5, "e = {e}: {d}");
            assert!(s.triangles() < m.triangles());
        }
    }

    #[test]
    fn a_flat_sheet_collapses() {
        let mut m = WoodMesh::default();
        let n = 10u32;
        for y in 0..=n {
            for x in 0..=n {
                m.positions.push(Vec3::new(x as f32, y as f32, 0.0));
                m.normals.push(Vec3::Z);
                m.uvs.push(Vec2::new(x as f32, y as f32) / n as f32);
                m.bones.push([0; 4]);
                m.weights.push([1.0, 0.0, 0.0, 0.0]);
            }
        }
        let mut indices = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let a = y * (n + 1) + x;
                indices.extend_from_slice(&[a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]);
            }
        }
        m.primitives.push(WoodPrimitive {
            material: 3,
            indices,
        });
        let (s, err) = m.simplify(0.01);
        assert!(err <= 0.01);
        assert!(s.triangles() < 40, "{} triangles", s.triangles());
        assert_eq!(s.primitives[0].material, 3);
        assert!(forward(&m, &s) <= 0.01 + 1e-5);
    }

    #[test]
    fn skins_that_differ_are_not_merged_on_a_big_surface() {
        // A long thick tube whose two halves follow different bones with a hard switch: the
        // switch ring must survive (its vertices carry bone 1 on one side, bone 0 on the other).
        let mut m = tube(21, 8, 2.0, |t| Vec3::new(0.0, 40.0 * t, 0.0));
        for (i, p) in m.positions.iter().enumerate() {
            if p.y > 20.0 {
                m.bones[i] = [1; 4];
            }
        }
        let (s, _) = m.simplify(0.05);
        // Triangles spanning the switch exist only between y = 18 and 22 (the rings next to it).
        for t in s.primitives[0].indices.chunks_exact(3) {
            let bones: Vec<u32> = t.iter().map(|&i| s.bones[i as usize][0]).collect();
            if bones.contains(&0) && bones.contains(&1) {
                for &i in t {
                    let y = s.positions[i as usize].y;
                    assert!(
                        (17.9..=22.1).contains(&y),
                        "a triangle spans the switch from y = {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn kept_checks_are_the_ones_on_the_simplified_surface() {
        // Two triangles of a fan, the simplified piece keeping the first.
        let p = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.3, 1.0, 0.1),
            Vec3::new(-0.8, 0.6, 0.4),
        ];
        let kept = Kept::of(&[[0, 1, 2]], 4);
        let surface = crate::surface_distance::SurfaceBvh::new(vec![[p[0], p[1], p[2]]]);
        let checks: [([u32; 3], Vec3, bool); 8] = [
            ([1, 1, 1], p[1], true),
            ([3, 3, 3], p[3], false),
            ([2, 0, 2], (p[2] + p[0]) * 0.5, true),
            ([0, 2, 0], (p[0] + p[2]) * 0.5, true),
            ([2, 3, 2], (p[2] + p[3]) * 0.5, false),
            ([2, 0, 1], (p[0] + p[1] + p[2]) / 3.0, true),
            ([0, 2, 3], (p[0] + p[2] + p[3]) / 3.0, false),
            ([3, 3, 3], p[3], false),
        ];
        for (owners, point, on) in checks {
            assert_eq!(kept.holds(owners), on, "{owners:?}");
            // What is held lies on the kept surface: its query could not raise the error.
            if on {
                assert!(surface.distance(point) < 1e-6, "{owners:?}");
            } else {
                assert!(surface.distance(point) > 0.1, "{owners:?}");
            }
        }
    }

    #[test]
    fn bad_indices_and_positions_are_skipped() {
        let mut m = tube(4, 4, 0.5, |t| Vec3::new(0.0, t, 0.0));
        let n = m.positions.len() as u32;
        m.primitives[0]
            .indices
            .extend_from_slice(&[0, 1, n + 5, 2, 2, 3]);
        m.positions[0] = Vec3::NAN;
        m.primitives.push(WoodPrimitive {
            material: 1,
            indices: vec![1, 2],
        });
        let (s, err) = m.simplify(0.01);
        assert!(err <= 0.01);
        assert!(s.positions.iter().all(|p| p.is_finite()));
        assert!(s.triangles() > 0);
        let mut short = m.clone();
        short.weights.truncate(3);
        let _ = short.simplify(0.1);
    }
}
