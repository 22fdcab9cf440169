//! Meshes: every mesh instance's primitives flattened into [`Vertices`] and per-primitive
//! triangle lists, with the coordinate checks on the way in and after the rest pose.

use std::collections::HashMap;

use glam::{Vec2, Vec3};
use gltf::json;
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use crate::accessor::Decoded;
use crate::classify::PrimitiveInfo;
use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::import::attributes::{PrimitiveAttributes, attribute};
use crate::import::influences::Influences;
use crate::import::materials::{BaseColorMap, MaterialInfo};
use crate::model::{Binding, Bone, Triangle, Vertices};
use crate::rig::Node;

/// Largest coordinate magnitude accepted for a vertex, in the file's units, both in a POSITION
/// accessor and after the rest-pose transforms. No tree is ten thousand kilometres (or, in
/// millimetres, ten kilometres) across, f32 cannot resolve a leaf out there, and sizes computed
/// from such values overflow: refusing names the cause instead of a later "no height" or
/// "no foliage".
pub const MAX_COORDINATE: f32 = 1e7;

/// Refuses a primitive whose vertices land at absurd or non-finite coordinates in the rest
/// pose (beyond ±[`MAX_COORDINATE`]): sane POSITION values can still be scaled there by node or
/// skin transforms, and the tree's size then overflows.
pub(super) fn check_rest_positions(
    src: &GltfSource,
    nodes: &[Node],
    prims: &[PrimitiveInfo],
    rest: &[Vec3],
) -> Result<()> {
    for p in prims {
        let bad = p
            .triangles
            .iter()
            .flatten()
            .map(|&v| rest[v as usize])
            .find(|q| !q.is_finite() || q.abs().max_element() > MAX_COORDINATE);
        if let Some(q) = bad {
            return Err(src.invalid(format!(
                "mesh '{}' primitive {} (node {} '{}'): a vertex lies at {:?} in the rest pose, beyond ±{MAX_COORDINATE:e} (its node or skin transforms scale it absurdly)",
                p.mesh,
                p.primitive,
                p.node,
                nodes[p.node].name,
                q.to_array()
            )));
        }
    }
    Ok(())
}

/// Reads every mesh instance (in parents-first node order) into the flattened vertex arrays and
/// returns where each primitive's triangles live.
///
/// Refused: a POSITION beyond ±[`MAX_COORDINATE`] (naming the primitive, vertex and value).
/// Accepted with a one-line warning naming the mesh and primitive: integer POSITION without
/// `KHR_mesh_quantization` (read as stored), morph targets (the base shape is read), a
/// TRIANGLES index count that is not a multiple of 3 (the leftover indices are dropped),
/// vertices whose skin weights are all zero (bound rigidly to the skin's first joint), and
/// extra influence sets `JOINTS_1`/`WEIGHTS_1`, ... (folded: all sets are merged per vertex and
/// the 4 largest influences kept, renormalised, since frond's vertices carry 4).
pub(super) fn read_meshes(
    src: &GltfSource,
    order: &[usize],
    bindings: &mut Vec<Binding>,
    bones: &[Bone],
    materials: &MaterialInfo,
    warnings: &mut Vec<String>,
) -> Result<(Vertices, Vec<PrimitiveInfo>)> {
    let quantization = src
        .root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_mesh_quantization");
    let mut reader = MeshReader {
        src,
        bones,
        materials,
        quantization,
        verts: Vertices::default(),
        prims: Vec::new(),
        warnings,
    };
    let mut node_binding: HashMap<usize, u32> = HashMap::new();
    for &ni in order {
        let Some(instance) = mesh_instance(src, ni, bindings, &mut node_binding)? else {
            continue;
        };
        for (pi, p) in instance.mesh.primitives.iter().enumerate() {
            reader.read_primitive(&instance, &bindings[instance.binding as usize], pi, p)?;
        }
    }
    Ok((reader.verts, reader.prims))
}

/// A node that shows a mesh, with the binding its vertices take.
struct MeshInstance<'a> {
    /// The node's index.
    node: usize,
    /// The mesh it shows.
    mesh: &'a json::Mesh,
    /// The mesh's name, or `mesh<i>`.
    mesh_name: String,
    /// The node's skin, if it has one.
    skin: Option<usize>,
    /// Index into the bindings: the skin's, or the node's own rigid binding.
    binding: u32,
    /// Joints in that binding (1 for a rigid one): what joint ids may name.
    palette: usize,
}

/// Node `ni`'s mesh instance, or None when it shows no mesh. An unskinned node gets its own
/// [`Binding::Node`] (added to `bindings` the first time, remembered in `node_binding`).
///
/// Refused: a node naming a mesh or skin that does not exist.
fn mesh_instance<'a>(
    src: &'a GltfSource,
    ni: usize,
    bindings: &mut Vec<Binding>,
    node_binding: &mut HashMap<usize, u32>,
) -> Result<Option<MeshInstance<'a>>> {
    let jn = &src.root.nodes[ni];
    let Some(mesh_index) = jn.mesh.map(|m| m.value()) else {
        return Ok(None);
    };
    let mesh = src.root.meshes.get(mesh_index).ok_or_else(|| {
        src.invalid(format!(
            "node {ni} references mesh {mesh_index}, which does not exist"
        ))
    })?;
    let skin = jn.skin.map(|s| s.value());
    if let Some(s) = skin
        && s >= src.root.skins.len()
    {
        return Err(src.invalid(format!(
            "node {ni} references skin {s}, which does not exist"
        )));
    }
    let binding = match skin {
        Some(s) => s as u32,
        None => *node_binding.entry(ni).or_insert_with(|| {
            bindings.push(Binding::Node(ni));
            (bindings.len() - 1) as u32
        }),
    };
    let palette = match &bindings[binding as usize] {
        Binding::Skin { joints, .. } => joints.len(),
        Binding::Node(_) => 1,
    };
    let mesh_name = mesh
        .name
        .clone()
        .unwrap_or_else(|| format!("mesh{mesh_index}"));
    Ok(Some(MeshInstance {
        node: ni,
        mesh,
        mesh_name,
        skin,
        binding,
        palette,
    }))
}

/// What the primitives are read into, and the file-wide facts reading each one needs.
struct MeshReader<'a> {
    /// The file.
    src: &'a GltfSource,
    /// The skins' bones (to name a skin's first joint in warnings).
    bones: &'a [Bone],
    /// The materials read (base colour maps and the texture coordinate sets they use).
    materials: &'a MaterialInfo,
    /// Whether the file declares `KHR_mesh_quantization` (integer POSITION allowed).
    quantization: bool,
    /// Every primitive's vertices so far, flattened.
    verts: Vertices,
    /// Every primitive read so far, its triangles indexing `verts`.
    prims: Vec<PrimitiveInfo>,
    /// Where warnings go.
    warnings: &'a mut Vec<String>,
}

/// The per-vertex attributes of one primitive, read and checked, before they are appended.
struct PrimitiveData {
    /// POSITION (VEC3, finite, within ±[`MAX_COORDINATE`]).
    positions: Decoded,
    /// NORMAL, if present.
    normals: Option<Decoded>,
    /// TANGENT, if present as VEC4.
    tangents: Option<Decoded>,
    /// The base colour map's (input image, texcoord set, uv transform), if the material has one.
    map: Option<BaseColorMap>,
    /// The set that map samples (0 without one).
    uv_set: u32,
    /// That set's coordinates, if the primitive has them.
    uvs: Option<Decoded>,
    /// Per set the materials' maps use: its coordinates, except at `uv_set` (that one is
    /// `uvs`), for writing the input's materials back unchanged.
    raw_sets: Vec<Option<Decoded>>,
}

impl MeshReader<'_> {
    /// Reads primitive `pi` (`p`) of a mesh instance whose vertices take `binding`: its
    /// attributes into the vertex arrays, its triangles into a [`PrimitiveInfo`]. A primitive of
    /// points or lines is skipped with a warning.
    fn read_primitive(
        &mut self,
        instance: &MeshInstance,
        binding: &Binding,
        pi: usize,
        p: &json::mesh::Primitive,
    ) -> Result<()> {
        let src = self.src;
        let what = format!("mesh '{}' primitive {pi}", instance.mesh_name);
        let Some(mode) = self.triangle_mode(p, &what)? else {
            return Ok(());
        };
        let positions = self.read_positions(p, &what, instance.node)?;
        let attrs = PrimitiveAttributes {
            src,
            primitive: p,
            what: &what,
            n: positions.count(),
        };
        let normals = attrs.optional(Semantic::Normals, "NORMAL")?;
        let tangents = attrs
            .optional(Semantic::Tangents, "TANGENT")?
            .and_then(|d| (d.width == 4).then_some(d));
        let material = p.material.map(|m| m.value());
        if let Some(m) = material
            && m >= self.materials.materials.len()
        {
            return Err(src.invalid(format!("{what}: material {m} does not exist")));
        }
        let data = self.read_texcoords(&attrs, material, positions, normals, tangents)?;
        let mut influences = Influences::read(
            &attrs,
            instance.skin.is_some(),
            instance.palette,
            self.warnings,
        )?;
        let base = self.verts.len() as u32;
        self.push_vertices(&attrs, instance.binding, &data, &mut influences)?;
        influences.warn(&attrs, binding, self.bones, self.warnings);
        let tris = triangles(&attrs, mode, self.warnings)?;
        self.prims.push(PrimitiveInfo {
            mesh: instance.mesh_name.clone(),
            node: instance.node,
            primitive: pi,
            material,
            triangles: tris.into_iter().map(|t| t.map(|i| i + base)).collect(),
        });
        Ok(())
    }

    /// The primitive's mode when it draws triangles; None (with a warning) for points and lines.
    fn triangle_mode(&mut self, p: &json::mesh::Primitive, what: &str) -> Result<Option<Mode>> {
        let mode = match p.mode {
            Checked::Valid(m) => m,
            Checked::Invalid => return Err(self.src.invalid(format!("{what}: invalid mode"))),
        };
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.warnings.push(format!(
                "{what}: {mode:?} primitives are not triangles; skipped"
            ));
            return Ok(None);
        }
        Ok(Some(mode))
    }

    /// Reads the POSITION of primitive `p` (on node `ni`), first checking from the accessor's
    /// declared count that it keeps the meshes within
    /// [`InputLimits::max_vertices`](crate::InputLimits::max_vertices).
    ///
    /// Refused: no POSITION, one past the vertex limit, not VEC3, NaN or Inf, or a coordinate
    /// beyond ±[`MAX_COORDINATE`]. Warned: integer POSITION the glTF rules do not allow, and
    /// morph targets (ignored).
    fn read_positions(
        &mut self,
        p: &json::mesh::Primitive,
        what: &str,
        ni: usize,
    ) -> Result<Decoded> {
        let src = self.src;
        let pos_acc = attribute(p, Semantic::Positions)
            .ok_or_else(|| src.invalid(format!("{what}: has no POSITION attribute")))?;
        // Checked from the declared count before anything is decoded: a mesh instanced
        // on many nodes, or an accessor without a bufferView (zeros of any count), would
        // otherwise let a tiny file take gigabytes.
        let declared = src
            .root
            .accessors
            .get(pos_acc)
            .map_or(0, |a| a.count.0 as usize);
        let limit = src.limits.max_vertices;
        if self.verts.len().saturating_add(declared) as u64 > limit {
            return Err(src.invalid(format!(
                "{what} (node {ni}) brings the meshes to {} vertices, over the vertex limit of {limit} (raise the vertex limit to read it)",
                self.verts.len().saturating_add(declared)
            )));
        }
        let pos = src.read_floats(pos_acc, &format!("{what} POSITION"))?;
        if pos.width != 3 {
            return Err(src.invalid(format!("{what}: POSITION must be VEC3")));
        }
        if pos.values.iter().any(|v| !v.is_finite()) {
            return Err(src.invalid(format!("{what}: POSITION contains NaN or Inf")));
        }
        if let Some(k) = pos.values.iter().position(|v| v.abs() > MAX_COORDINATE) {
            return Err(src.invalid(format!(
                "{what}: POSITION of vertex {} is {:?}, beyond ±{MAX_COORDINATE:e} (absurd for a tree in any unit)",
                k / 3,
                pos.get::<3>(k / 3)
            )));
        }
        if let Some(w) = integer_position_warning(src, pos_acc, self.quantization) {
            self.warnings.push(format!("{what}: {w}"));
        }
        if let Some(targets) = p.targets.as_ref().filter(|t| !t.is_empty()) {
            self.warnings.push(format!(
                "{what}: {} morph target{} ignored (frond reads the base shape only)",
                targets.len(),
                if targets.len() == 1 { "" } else { "s" }
            ));
        }
        Ok(pos)
    }

    /// Reads the texture coordinates the primitive's vertices take (the set its `material`'s
    /// base colour map samples, and the input's own sets) and gathers them with the other
    /// attributes. The vertex arrays get a coordinate list per set the maps use.
    fn read_texcoords(
        &mut self,
        attrs: &PrimitiveAttributes,
        material: Option<usize>,
        positions: Decoded,
        normals: Option<Decoded>,
        tangents: Option<Decoded>,
    ) -> Result<PrimitiveData> {
        let materials = self.materials;
        let tex = material.and_then(|m| materials.base[m]);
        let uv_set = tex.map(|t| t.1).unwrap_or(0);
        let read_set =
            |set: u32| attrs.optional(Semantic::TexCoords(set), &format!("TEXCOORD_{set}"));
        let uvs = read_set(uv_set)?;
        // The input's own sets, untransformed, for writing its materials back unchanged.
        let raw_sets = (0..materials.texcoord_sets as u32)
            .map(|set| {
                if set == uv_set {
                    Ok(None)
                } else {
                    read_set(set)
                }
            })
            .collect::<Result<Vec<_>>>()?;
        if self.verts.texcoords.len() < materials.texcoord_sets {
            self.verts
                .texcoords
                .resize(materials.texcoord_sets, Vec::new());
        }
        Ok(PrimitiveData {
            positions,
            normals,
            tangents,
            map: tex,
            uv_set,
            uvs,
            raw_sets,
        })
    }

    /// Appends the primitive's vertices to the vertex arrays, all bound to `binding`: tangents
    /// normalised (zero where the file gives none or a degenerate one), normals normalised,
    /// the base colour map's coordinates transformed, the input's sets as they are, and each
    /// vertex's joints and weights from `influences`.
    fn push_vertices(
        &mut self,
        attrs: &PrimitiveAttributes,
        binding: u32,
        data: &PrimitiveData,
        influences: &mut Influences,
    ) -> Result<()> {
        let verts = &mut self.verts;
        let PrimitiveData {
            positions: pos,
            normals,
            tangents,
            map: tex,
            uv_set,
            uvs,
            raw_sets,
        } = data;
        let (tex, uv_set) = (*tex, *uv_set);
        if tangents.is_some() && verts.tangent.len() < verts.len() {
            verts.tangent.resize(verts.len(), glam::Vec4::ZERO);
        }
        for i in 0..attrs.n {
            if let Some(t) = &tangents {
                let t = glam::Vec4::from(t.get::<4>(i));
                let xyz = t.truncate().normalize_or_zero();
                verts.tangent.push(if t.is_finite() && xyz != Vec3::ZERO {
                    xyz.extend(if t.w < 0.0 { -1.0 } else { 1.0 })
                } else {
                    glam::Vec4::ZERO
                });
            } else if !verts.tangent.is_empty() {
                verts.tangent.push(glam::Vec4::ZERO);
            }
            verts.position.push(Vec3::from(pos.get::<3>(i)));
            verts.normal.push(
                normals
                    .as_ref()
                    .map(|d| Vec3::from(d.get::<3>(i)).normalize_or_zero())
                    .unwrap_or(Vec3::ZERO),
            );
            let uv = uvs
                .as_ref()
                .map(|d| Vec2::from(d.get::<2>(i)))
                .unwrap_or(Vec2::ZERO);
            verts
                .uv
                .push(tex.map(|t| t.2.transform_point2(uv)).unwrap_or(uv));
            for (set, raw) in raw_sets.iter().enumerate() {
                let d = if set as u32 == uv_set {
                    uvs.as_ref()
                } else {
                    raw.as_ref()
                };
                verts.texcoords[set]
                    .push(d.map(|d| Vec2::from(d.get::<2>(i))).unwrap_or(Vec2::ZERO));
            }
            verts.binding.push(binding);
            let (joints, weights) = influences.vertex(attrs, i)?;
            verts.joints.push(joints);
            verts.weights.push(weights);
        }
        Ok(())
    }
}

/// The primitive's triangles (vertex indices local to it) in drawing `mode`: its index
/// accessor, or its vertices in order without one.
///
/// Refused: indices that are not SCALAR or name a vertex past the primitive's. Warned: a
/// TRIANGLES count that is not a multiple of 3 (the leftover dropped).
fn triangles(
    attrs: &PrimitiveAttributes,
    mode: Mode,
    warnings: &mut Vec<String>,
) -> Result<Vec<[u32; 3]>> {
    let (src, what, n, p) = (attrs.src, attrs.what, attrs.n, attrs.primitive);
    let raw_indices: Vec<u32> = match p.indices {
        Some(a) => {
            let (w, v) = src.read_ints(a.value(), &format!("{what} indices"))?;
            if w != 1 {
                return Err(src.invalid(format!("{what}: indices must be SCALAR")));
            }
            v
        }
        None => (0..n as u32).collect(),
    };
    if let Some(&bad) = raw_indices.iter().find(|&&i| i as usize >= n) {
        return Err(src.invalid(format!(
            "{what}: index {bad} is out of range ({n} vertices)"
        )));
    }
    let leftover = raw_indices.len() % 3;
    if mode == Mode::Triangles && leftover != 0 {
        let counted = if p.indices.is_some() {
            "indices"
        } else {
            "vertices (no indices)"
        };
        warnings.push(format!(
            "{what}: {} {counted} is not a multiple of 3 for TRIANGLES; the last {leftover} dropped",
            raw_indices.len()
        ));
    }
    Ok(triangulate(&raw_indices, mode))
}

/// Why an integer POSITION accessor breaks the glTF rules, if it does: core glTF allows only
/// floats, `KHR_mesh_quantization` adds (normalized or not) bytes and shorts, and nothing
/// allows unsigned ints. frond reads such values anyway (as stored, or scaled to [0, 1] /
/// [-1, 1] when `normalized`), so this is a warning saying how.
fn integer_position_warning(src: &GltfSource, index: usize, quantization: bool) -> Option<String> {
    use json::accessor::ComponentType;
    let acc = src.root.accessors.get(index)?;
    let Checked::Valid(c) = acc.component_type else {
        return None;
    };
    let (name, range) = match c.0 {
        ComponentType::F32 => return None,
        ComponentType::I8 => ("BYTE", "[-1, 1]"),
        ComponentType::U8 => ("UNSIGNED_BYTE", "[0, 1]"),
        ComponentType::I16 => ("SHORT", "[-1, 1]"),
        ComponentType::U16 => ("UNSIGNED_SHORT", "[0, 1]"),
        ComponentType::U32 => ("UNSIGNED_INT", "[0, 1]"),
    };
    // accessor.rs scales normalized bytes and shorts only (glTF has no normalized u32).
    let how = if acc.normalized && c.0 != ComponentType::U32 {
        format!("read as normalized values in {range}")
    } else {
        "read as integer coordinates".to_string()
    };
    if c.0 == ComponentType::U32 {
        Some(format!(
            "POSITION accessor {index} is {name}, which glTF never allows (not even with KHR_mesh_quantization); {how}"
        ))
    } else if !quantization {
        Some(format!(
            "POSITION accessor {index} is {name}, which glTF allows only with KHR_mesh_quantization (not in extensionsUsed); {how}"
        ))
    } else {
        None
    }
}

/// Triangle list from TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN indices.
pub(crate) fn triangulate(idx: &[u32], mode: json::mesh::Mode) -> Vec<[u32; 3]> {
    use json::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i - 2], idx[i - 1], idx[i]]
                } else {
                    [idx[i - 1], idx[i - 2], idx[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..idx.len())
            .map(|i| [idx[0], idx[i - 1], idx[i]])
            .collect(),
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// Marks the triangles whose rest-pose area (the cross product's length) is negligible against
/// the tree's `size`: later stages skip them when they need a normal or an area.
pub(super) fn mark_degenerate(tris: &mut [Triangle], pos: &[Vec3], size: f32) {
    let eps = (size * size * 1e-12).max(f32::MIN_POSITIVE);
    for t in tris {
        let [a, b, c] = t.v.map(|i| pos[i as usize]);
        t.degenerate = (b - a).cross(c - a).length() <= eps;
    }
}
