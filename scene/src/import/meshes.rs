//! Meshes: every mesh instance's primitives flattened into [`Vertices`] and per-primitive
//! triangle lists, with the coordinate checks on the way in and after the rest pose.

use std::collections::HashMap;

use glam::{Vec2, Vec3};
use gltf::json;
use gltf::json::validation::Checked;

use crate::classify::PrimitiveInfo;
use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::import::materials::MaterialInfo;
use crate::input_file::MAX_VERTICES_OPTION;
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
    let mut verts = Vertices::default();
    let mut prims = Vec::new();
    let mut node_binding: HashMap<usize, u32> = HashMap::new();
    let skin_count = src.root.skins.len();
    for &ni in order {
        let jn = &src.root.nodes[ni];
        let Some(mesh_index) = jn.mesh.map(|m| m.value()) else {
            continue;
        };
        let mesh = src.root.meshes.get(mesh_index).ok_or_else(|| {
            src.invalid(format!(
                "node {ni} references mesh {mesh_index}, which does not exist"
            ))
        })?;
        let skin = jn.skin.map(|s| s.value());
        if let Some(s) = skin
            && s >= skin_count
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
        for (pi, p) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh '{mesh_name}' primitive {pi}");
            let mode = match p.mode {
                Checked::Valid(m) => m,
                Checked::Invalid => return Err(src.invalid(format!("{what}: invalid mode"))),
            };
            use json::mesh::Mode;
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                warnings.push(format!(
                    "{what}: {mode:?} primitives are not triangles; skipped"
                ));
                continue;
            }
            let attr = |sem: json::mesh::Semantic| {
                p.attributes.get(&Checked::Valid(sem)).map(|a| a.value())
            };
            let pos_acc = attr(json::mesh::Semantic::Positions)
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
            if verts.len().saturating_add(declared) as u64 > limit {
                return Err(src.invalid(format!(
                    "{what} (node {ni}) brings the meshes to {} vertices, over the vertex limit of {limit} (raise it with {MAX_VERTICES_OPTION})",
                    verts.len().saturating_add(declared)
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
            if let Some(w) = integer_position_warning(src, pos_acc, quantization) {
                warnings.push(format!("{what}: {w}"));
            }
            if let Some(targets) = p.targets.as_ref().filter(|t| !t.is_empty()) {
                warnings.push(format!(
                    "{what}: {} morph target{} ignored (frond reads the base shape only)",
                    targets.len(),
                    if targets.len() == 1 { "" } else { "s" }
                ));
            }
            let n = pos.count();
            let check_count = |d: &crate::accessor::Decoded, name: &str| -> Result<()> {
                if d.count() != n {
                    return Err(src.invalid(format!(
                        "{what}: {name} has {} elements, POSITION has {n}",
                        d.count()
                    )));
                }
                Ok(())
            };
            let normals = match attr(json::mesh::Semantic::Normals) {
                Some(a) => {
                    let d = src.read_floats(a, &format!("{what} NORMAL"))?;
                    check_count(&d, "NORMAL")?;
                    Some(d)
                }
                None => None,
            };
            let tangents = match attr(json::mesh::Semantic::Tangents) {
                Some(a) => {
                    let d = src.read_floats(a, &format!("{what} TANGENT"))?;
                    check_count(&d, "TANGENT")?;
                    (d.width == 4).then_some(d)
                }
                None => None,
            };
            let material = p.material.map(|m| m.value());
            if let Some(m) = material
                && m >= materials.materials.len()
            {
                return Err(src.invalid(format!("{what}: material {m} does not exist")));
            }
            let tex = material.and_then(|m| materials.base[m]);
            let uv_set = tex.map(|t| t.1).unwrap_or(0);
            let read_set = |set: u32| -> Result<Option<crate::accessor::Decoded>> {
                match attr(json::mesh::Semantic::TexCoords(set)) {
                    Some(a) => {
                        let d = src.read_floats(a, &format!("{what} TEXCOORD_{set}"))?;
                        check_count(&d, &format!("TEXCOORD_{set}"))?;
                        Ok(Some(d))
                    }
                    None => Ok(None),
                }
            };
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
            if verts.texcoords.len() < materials.texcoord_sets {
                verts.texcoords.resize(materials.texcoord_sets, Vec::new());
            }
            // Influence sets JOINTS_n/WEIGHTS_n for n = 0, 1, ... while both are present:
            // (joint ids, weights), 4 per vertex each.
            let mut influence_sets: Vec<(Vec<u32>, Vec<f32>)> = Vec::new();
            if skin.is_some() {
                use json::mesh::Semantic;
                while let (Some(j), Some(w)) = (
                    attr(Semantic::Joints(influence_sets.len() as u32)),
                    attr(Semantic::Weights(influence_sets.len() as u32)),
                ) {
                    let set = influence_sets.len();
                    let (jw, jv) = src.read_ints(j, &format!("{what} JOINTS_{set}"))?;
                    let wd = src.read_floats(w, &format!("{what} WEIGHTS_{set}"))?;
                    check_count(&wd, &format!("WEIGHTS_{set}"))?;
                    if jw != 4 || wd.width != 4 || jv.len() != n * 4 {
                        return Err(src.invalid(format!(
                            "{what}: JOINTS_{set}/WEIGHTS_{set} must be VEC4 with one per vertex"
                        )));
                    }
                    influence_sets.push((jv, wd.values));
                }
                if influence_sets.is_empty() {
                    warnings.push(format!(
                        "{what}: skinned node without JOINTS_0/WEIGHTS_0; bound to joint 0"
                    ));
                }
                let mut unpaired: Vec<String> = p
                    .attributes
                    .keys()
                    .filter_map(|k| match k {
                        Checked::Valid(sem @ (Semantic::Joints(s) | Semantic::Weights(s)))
                            if *s as usize >= influence_sets.len().max(1) =>
                        {
                            Some(sem.to_string())
                        }
                        _ => None,
                    })
                    .collect();
                unpaired.sort();
                if !unpaired.is_empty() {
                    warnings.push(format!(
                        "{what}: {} ignored (influence sets are read as JOINTS_n/WEIGHTS_n pairs numbered from 0)",
                        unpaired.join(", ")
                    ));
                }
            }
            let mut influences: Vec<(usize, f32)> = Vec::new();
            let (mut zero_weight, mut folded, mut max_dropped) = (0usize, 0usize, 0.0f32);
            let base = verts.len() as u32;
            if tangents.is_some() && verts.tangent.len() < verts.len() {
                verts.tangent.resize(verts.len(), glam::Vec4::ZERO);
            }
            for i in 0..n {
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
                let (joints, weights) = if influence_sets.is_empty() {
                    ([0; 4], [1.0, 0.0, 0.0, 0.0])
                } else {
                    let check = |jj: usize, w: f32| -> Result<()> {
                        if w != 0.0 && jj >= palette {
                            return Err(src.invalid(format!(
                                "{what}: vertex {i} names joint {jj}, but the skin has {palette} joints"
                            )));
                        }
                        if !w.is_finite() || w < 0.0 {
                            return Err(src.invalid(format!(
                                "{what}: vertex {i} has a negative or non-finite weight"
                            )));
                        }
                        Ok(())
                    };
                    let mut j = [0u16; 4];
                    let mut w = [0.0f32; 4];
                    if let [(jv, wv)] = influence_sets.as_slice() {
                        // One set: slots kept as written (zero-weight slots name joint 0).
                        for k in 0..4 {
                            let (jj, wk) = (jv[i * 4 + k] as usize, wv[i * 4 + k]);
                            check(jj, wk)?;
                            j[k] = if wk == 0.0 { 0 } else { jj as u16 };
                            w[k] = wk;
                        }
                    } else {
                        // Several sets: merge per joint, keep the 4 largest.
                        influences.clear();
                        for (jv, wv) in &influence_sets {
                            for k in i * 4..i * 4 + 4 {
                                let (jj, wk) = (jv[k] as usize, wv[k]);
                                check(jj, wk)?;
                                if wk > 0.0 {
                                    match influences.iter_mut().find(|e| e.0 == jj) {
                                        Some(e) => e.1 += wk,
                                        None => influences.push((jj, wk)),
                                    }
                                }
                            }
                        }
                        if influences.len() > 4 {
                            influences.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                            let total: f32 = influences.iter().map(|e| e.1).sum();
                            let dropped: f32 = influences[4..].iter().map(|e| e.1).sum();
                            folded += 1;
                            max_dropped = max_dropped.max(dropped / total);
                            influences.truncate(4);
                        }
                        for (k, &(jj, wk)) in influences.iter().enumerate() {
                            j[k] = jj as u16;
                            w[k] = wk;
                        }
                    }
                    let sum: f32 = w.iter().sum();
                    if !sum.is_finite() {
                        // Each weight is finite, but e.g. 4 × 1e38 is not: normalising would
                        // silently zero them all.
                        return Err(src.invalid(format!(
                            "{what}: vertex {i} has skin weights whose sum overflows ({:?})",
                            w
                        )));
                    }
                    if sum > 0.0 {
                        for x in &mut w {
                            *x /= sum;
                        }
                    } else {
                        zero_weight += 1;
                        j = [0; 4];
                        w = [1.0, 0.0, 0.0, 0.0];
                    }
                    (j, w)
                };
                verts.joints.push(joints);
                verts.weights.push(weights);
            }
            if zero_weight > 0
                && let Binding::Skin { joints, .. } = &bindings[binding as usize]
                && let Some(first) = joints.first().map(|&b| &bones[b])
            {
                warnings.push(format!(
                    "{what}: {zero_weight} of {n} vertices {} all-zero skin weights; bound rigidly to the skin's first joint (joint 0, node {} '{}')",
                    if zero_weight == 1 { "has" } else { "have" },
                    first.node,
                    first.name
                ));
            }
            if influence_sets.len() > 1 {
                let extra: Vec<String> = (1..influence_sets.len())
                    .map(|s| format!("JOINTS_{s}/WEIGHTS_{s}"))
                    .collect();
                let outcome = if folded == 0 {
                    "no vertex has more than 4, so nothing is lost".to_string()
                } else {
                    format!(
                        "{folded} {} more than 4 and {} the 4 largest, renormalised (dropping at most {:.1}% of a vertex's weight)",
                        if folded == 1 {
                            "vertex has"
                        } else {
                            "vertices have"
                        },
                        if folded == 1 { "keeps" } else { "keep" },
                        max_dropped * 100.0
                    )
                };
                warnings.push(format!(
                    "{what}: {} present; frond keeps 4 influences per vertex and merged the sets: {outcome}",
                    extra.join(", ")
                ));
            }
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
            if mode == json::mesh::Mode::Triangles && leftover != 0 {
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
            let tris = triangulate(&raw_indices, mode);
            prims.push(PrimitiveInfo {
                mesh: mesh_name.clone(),
                node: ni,
                primitive: pi,
                material,
                triangles: tris.into_iter().map(|t| t.map(|i| i + base)).collect(),
            });
        }
    }
    Ok((verts, prims))
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
