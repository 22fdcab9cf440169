//! glTF import: turns any valid skinned (or static) tree into a [`Tree`]
//! (spec animated-billboard-clouds §1, §1.3; gltf-and-toolchain.md for the crate traps).

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::validation::Checked;
use rayon::prelude::*;

use crate::animation::{Channel, Clip, Interpolation, Property, world_matrices};
use crate::binding::assign_foliage_bones;
use crate::classify::{PrimitiveInfo, classify_primitives};
use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::model::*;
use crate::skinning::skin_positions;

/// User choices that change how a file is read.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Materials (by name) to treat as foliage regardless of the heuristics.
    pub foliage_materials: Vec<String>,
    /// Materials (by name) to treat as wood regardless of the heuristics.
    pub wood_materials: Vec<String>,
    /// Accept a file without any triangle (an empty tree) instead of refusing it: an
    /// evaluator compares such a candidate like any other.
    pub allow_empty: bool,
}

/// Reads a `.glb` or `.gltf` tree from disk.
pub fn import(path: &Path, options: &ImportOptions) -> Result<Tree> {
    let src = GltfSource::open(path)?;
    import_source(&src, options)
}

/// Reads a tree from bytes, `path` naming it (and locating external files).
pub fn import_bytes(path: &Path, bytes: &[u8], options: &ImportOptions) -> Result<Tree> {
    let src = GltfSource::from_bytes(path, bytes)?;
    import_source(&src, options)
}

fn import_source(src: &GltfSource, options: &ImportOptions) -> Result<Tree> {
    let mut warnings = Vec::new();
    let (nodes, node_order) = read_nodes(src)?;
    let (bones, skin_bindings) = read_skins(src, &nodes)?;
    let mut nodes = nodes;
    for (b, bone) in bones.iter().enumerate() {
        nodes[bone.node].bone = Some(b);
    }
    let mut bindings: Vec<Binding> = skin_bindings;
    let materials = read_materials(src)?;
    let (vertices, prims) =
        read_meshes(src, &node_order, &mut bindings, &materials, &mut warnings)?;
    if prims.is_empty() && !options.allow_empty {
        return Err(src.invalid("the file has no mesh with triangles (nothing to simplify)"));
    }
    let (textures, texture_images) = read_textures(src, &materials.1)?;
    let mut materials_out = materials.0;
    for (m, info) in materials_out.iter_mut().zip(&materials.1) {
        m.base_color_texture =
            info.and_then(|(img, _, _)| texture_images.iter().position(|&i| i == img));
    }
    let materials = materials_out;
    let clips = read_clips(src, nodes.len(), &mut warnings)?;

    // Rest pose: every node at its own TRS.
    let rest_pose: Vec<Trs> = nodes.iter().map(|n| n.rest).collect();
    let rest_world = world_matrices(&nodes, &node_order, &rest_pose);
    let mut bones = bones;
    for b in &mut bones {
        b.rest_world = rest_world[b.node];
    }
    let tmp = Tree {
        source: src.path.clone(),
        nodes,
        node_order,
        bones,
        bindings,
        vertices,
        triangles: Vec::new(),
        materials,
        textures,
        clips,
        classification: Vec::new(),
        foliage_reassigned: 0,
        warnings: Vec::new(),
        bounds: Bounds::of([]),
    };
    let rest_positions = skin_positions(&tmp, &rest_world);
    let mut tree = tmp;
    let (triangles, classification) = classify_primitives(&tree, &prims, &rest_positions, options);
    tree.triangles = triangles;
    tree.classification = classification;
    if tree
        .triangles
        .iter()
        .any(|t| t.material as usize == tree.materials.len())
    {
        tree.materials.push(Material {
            name: "default".into(),
            base_color: [1.0; 4],
            base_color_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
        });
    }
    tree.bounds = Bounds::of(
        tree.triangles
            .iter()
            .flat_map(|t| t.v.iter().map(|&i| rest_positions[i as usize])),
    );
    mark_degenerate(&mut tree.triangles, &rest_positions, tree.bounds.size());
    tree.foliage_reassigned = assign_foliage_bones(&mut tree);
    if tree.bones.is_empty() {
        warnings.push(
            "static tree: no skin, so foliage follows no bone (treated as a one-frame loop)".into(),
        );
    } else if tree.clips.is_empty() {
        warnings.push("static tree: no animation clip (treated as a one-frame loop)".into());
    }
    if tree.count(Part::Foliage) == 0 {
        warnings.push("no foliage found: later stages simplify the wood only".into());
    }
    for w in &warnings {
        tracing::warn!("{}: {w}", src.path.display());
    }
    tree.warnings = warnings;
    Ok(tree)
}

fn read_nodes(src: &GltfSource) -> Result<(Vec<Node>, Vec<usize>)> {
    let n = src.root.nodes.len();
    let mut nodes = Vec::with_capacity(n);
    for (i, jn) in src.root.nodes.iter().enumerate() {
        let rest = match jn.matrix {
            Some(m) => {
                let m = Mat4::from_cols_array(&m);
                if !m.is_finite() {
                    return Err(src.invalid(format!("node {i} matrix is not finite")));
                }
                let (s, r, t) = m.to_scale_rotation_translation();
                Trs {
                    translation: t,
                    rotation: r.normalize(),
                    scale: s,
                }
            }
            None => Trs {
                translation: jn.translation.map(Vec3::from).unwrap_or(Vec3::ZERO),
                rotation: jn
                    .rotation
                    .map(|q| Quat::from_array(q.0).normalize())
                    .unwrap_or(Quat::IDENTITY),
                scale: jn.scale.map(Vec3::from).unwrap_or(Vec3::ONE),
            },
        };
        if !(rest.translation.is_finite() && rest.rotation.is_finite() && rest.scale.is_finite()) {
            return Err(src.invalid(format!("node {i} transform is not finite")));
        }
        let extras = jn
            .extras
            .as_ref()
            .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok());
        nodes.push(Node {
            name: jn.name.clone().unwrap_or_else(|| format!("node{i}")),
            parent: None,
            children: Vec::new(),
            rest,
            bone: None,
            extras,
        });
    }
    for (i, jn) in src.root.nodes.iter().enumerate() {
        for c in jn.children.iter().flatten() {
            let c = c.value();
            if c >= n {
                return Err(src.invalid(format!(
                    "node {i} has child {c}, but there are only {n} nodes"
                )));
            }
            if c == i || nodes[c].parent.is_some() {
                return Err(src.invalid(format!(
                    "node {c} has more than one parent (the hierarchy must be a forest)"
                )));
            }
            nodes[c].parent = Some(i);
            nodes[i].children.push(c);
        }
    }
    // Parents-first order from every root; a cycle leaves nodes unreached.
    let mut order = Vec::with_capacity(n);
    let mut stack: Vec<usize> = (0..n)
        .rev()
        .filter(|&i| nodes[i].parent.is_none())
        .collect();
    while let Some(i) = stack.pop() {
        order.push(i);
        stack.extend(nodes[i].children.iter().rev().copied());
    }
    if order.len() != n {
        return Err(src.invalid("the node hierarchy contains a cycle"));
    }
    Ok((nodes, order))
}

fn read_skins(src: &GltfSource, nodes: &[Node]) -> Result<(Vec<Bone>, Vec<Binding>)> {
    let mut bone_of_node: HashMap<usize, usize> = HashMap::new();
    let mut bones: Vec<Bone> = Vec::new();
    let mut bindings = Vec::new();
    for (s, skin) in src.root.skins.iter().enumerate() {
        let what = format!("skin {s}");
        let mut joints = Vec::with_capacity(skin.joints.len());
        for j in &skin.joints {
            let node = j.value();
            if node >= nodes.len() {
                return Err(src.invalid(format!("{what}: joint node {node} does not exist")));
            }
            let b = *bone_of_node.entry(node).or_insert_with(|| {
                bones.push(Bone {
                    name: nodes[node].name.clone(),
                    node,
                    parent: None,
                    depth: 1,
                    rest_world: Mat4::IDENTITY,
                });
                bones.len() - 1
            });
            joints.push(b);
        }
        if joints.is_empty() || joints.len() > u16::MAX as usize {
            return Err(src.invalid(format!(
                "{what}: has {} joints (1 to 65535 supported)",
                joints.len()
            )));
        }
        let inverse_bind = match skin.inverse_bind_matrices {
            Some(acc) => {
                let d = src.read_floats(acc.value(), &format!("{what} inverseBindMatrices"))?;
                if d.width != 16 || d.count() < joints.len() {
                    return Err(src.invalid(format!(
                        "{what}: inverseBindMatrices must hold one MAT4 per joint ({} joints, {} matrices)",
                        joints.len(),
                        d.count()
                    )));
                }
                let mats: Vec<Mat4> = (0..joints.len())
                    .map(|k| Mat4::from_cols_array(&d.get::<16>(k)))
                    .collect();
                if mats.iter().any(|m| !m.is_finite()) {
                    return Err(
                        src.invalid(format!("{what}: inverseBindMatrices contain NaN or Inf"))
                    );
                }
                mats
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        bindings.push(Binding::Skin {
            joints,
            inverse_bind,
        });
    }
    // Bone parent: nearest ancestor node that is a bone. Depth via parents-first pass.
    for b in 0..bones.len() {
        let mut p = nodes[bones[b].node].parent;
        while let Some(n) = p {
            if let Some(&pb) = bone_of_node.get(&n) {
                bones[b].parent = Some(pb);
                break;
            }
            p = nodes[n].parent;
        }
    }
    for b in 0..bones.len() {
        let mut depth = 1;
        let mut p = bones[b].parent;
        while let Some(pb) = p {
            depth += 1;
            p = bones[pb].parent;
            if depth as usize > bones.len() {
                break;
            }
        }
        bones[b].depth = depth;
    }
    Ok((bones, bindings))
}

/// Materials plus, per material, (image index, texcoord set, uv transform) of its base colour.
type MaterialInfo = (Vec<Material>, Vec<Option<(usize, u32, glam::Affine2)>>);

fn read_materials(src: &GltfSource) -> Result<MaterialInfo> {
    let mut mats = Vec::new();
    let mut texinfo = Vec::new();
    for (i, m) in src.root.materials.iter().enumerate() {
        let pbr = &m.pbr_metallic_roughness;
        let tex = match &pbr.base_color_texture {
            Some(info) => {
                let t = src.root.textures.get(info.index.value()).ok_or_else(|| {
                    src.invalid(format!(
                        "material {i}: texture {} does not exist",
                        info.index.value()
                    ))
                })?;
                let image = t.source.value();
                if image >= src.root.images.len() {
                    return Err(src.invalid(format!(
                        "texture {}: image {image} does not exist",
                        info.index.value()
                    )));
                }
                let mut set = info.tex_coord;
                let mut xf = glam::Affine2::IDENTITY;
                if let Some(tt) = info
                    .extensions
                    .as_ref()
                    .and_then(|e| e.texture_transform.as_ref())
                {
                    let (s, c) = tt.rotation.0.sin_cos();
                    // KHR_texture_transform: uv' = T(offset) · R(rotation) · S(scale) · uv.
                    let r = glam::Mat2::from_cols(Vec2::new(c, s), Vec2::new(-s, c));
                    let sc = glam::Mat2::from_diagonal(Vec2::from(tt.scale.0));
                    xf = glam::Affine2::from_mat2_translation(r * sc, Vec2::from(tt.offset.0));
                    if let Some(tc) = tt.tex_coord {
                        set = tc;
                    }
                }
                Some((image, set, xf))
            }
            None => None,
        };
        let alpha_mode = match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Mask) => AlphaMode::Mask,
            Checked::Valid(json::material::AlphaMode::Blend) => AlphaMode::Blend,
            _ => AlphaMode::Opaque,
        };
        mats.push(Material {
            name: m.name.clone().unwrap_or_else(|| format!("material{i}")),
            base_color: pbr.base_color_factor.0,
            base_color_texture: None,
            alpha_mode,
            alpha_cutoff: m.alpha_cutoff.map(|c| c.0).unwrap_or(0.5),
            double_sided: m.double_sided,
        });
        texinfo.push(tex);
    }
    Ok((mats, texinfo))
}

/// Decodes the base-colour images materials use (in parallel) and links them to materials.
fn read_textures(
    src: &GltfSource,
    texinfo: &[Option<(usize, u32, glam::Affine2)>],
) -> Result<(Vec<Texture>, Vec<usize>)> {
    let mut images: Vec<usize> = texinfo.iter().flatten().map(|t| t.0).collect();
    images.sort_unstable();
    images.dedup();
    let textures = images
        .par_iter()
        .map(|&img| {
            let bytes = src.image_bytes(img)?;
            let decoded = image::load_from_memory(&bytes)
                .map_err(|e| src.invalid(format!("image {img}: cannot decode ({e})")))?
                .to_rgba8();
            let name = src.root.images[img]
                .name
                .clone()
                .unwrap_or_else(|| format!("image{img}"));
            Ok(Texture {
                name,
                width: decoded.width(),
                height: decoded.height(),
                rgba: decoded.into_raw(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((textures, images))
}

/// Where a primitive's triangles live in the flattened vertex/index arrays.
fn read_meshes(
    src: &GltfSource,
    order: &[usize],
    bindings: &mut Vec<Binding>,
    materials: &MaterialInfo,
    warnings: &mut Vec<String>,
) -> Result<(Vertices, Vec<PrimitiveInfo>)> {
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
            let pos = src.read_floats(pos_acc, &format!("{what} POSITION"))?;
            if pos.width != 3 {
                return Err(src.invalid(format!("{what}: POSITION must be VEC3")));
            }
            if pos.values.iter().any(|v| !v.is_finite()) {
                return Err(src.invalid(format!("{what}: POSITION contains NaN or Inf")));
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
            let material = p.material.map(|m| m.value());
            if let Some(m) = material
                && m >= materials.0.len()
            {
                return Err(src.invalid(format!("{what}: material {m} does not exist")));
            }
            let tex = material.and_then(|m| materials.1[m]);
            let uv_set = tex.map(|t| t.1).unwrap_or(0);
            let uvs = match attr(json::mesh::Semantic::TexCoords(uv_set)) {
                Some(a) => {
                    let d = src.read_floats(a, &format!("{what} TEXCOORD_{uv_set}"))?;
                    check_count(&d, "TEXCOORD")?;
                    Some(d)
                }
                None => None,
            };
            let skin_attrs = if skin.is_some() {
                match (
                    attr(json::mesh::Semantic::Joints(0)),
                    attr(json::mesh::Semantic::Weights(0)),
                ) {
                    (Some(j), Some(w)) => {
                        let (jw, jv) = src.read_ints(j, &format!("{what} JOINTS_0"))?;
                        let wd = src.read_floats(w, &format!("{what} WEIGHTS_0"))?;
                        check_count(&wd, "WEIGHTS_0")?;
                        if jw != 4 || wd.width != 4 || jv.len() != n * 4 {
                            return Err(src.invalid(format!(
                                "{what}: JOINTS_0/WEIGHTS_0 must be VEC4 with one per vertex"
                            )));
                        }
                        Some((jv, wd))
                    }
                    _ => {
                        warnings.push(format!(
                            "{what}: skinned node without JOINTS_0/WEIGHTS_0; bound to joint 0"
                        ));
                        None
                    }
                }
            } else {
                None
            };
            let base = verts.len() as u32;
            for i in 0..n {
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
                verts.binding.push(binding);
                let (joints, weights) = match &skin_attrs {
                    Some((jv, wd)) => {
                        let mut j = [0u16; 4];
                        let mut w = Vec4::from(wd.get::<4>(i));
                        for k in 0..4 {
                            let jj = jv[i * 4 + k] as usize;
                            if w[k] != 0.0 && jj >= palette {
                                return Err(src.invalid(format!(
                                    "{what}: vertex {i} names joint {jj}, but the skin has {palette} joints"
                                )));
                            }
                            if !w[k].is_finite() || w[k] < 0.0 {
                                return Err(src.invalid(format!(
                                    "{what}: vertex {i} has a negative or non-finite weight"
                                )));
                            }
                            j[k] = if w[k] == 0.0 { 0 } else { jj as u16 };
                        }
                        let sum = w.x + w.y + w.z + w.w;
                        if sum > 0.0 {
                            w /= sum;
                        } else {
                            w = Vec4::X;
                        }
                        (j, w.to_array())
                    }
                    None => ([0; 4], [1.0, 0.0, 0.0, 0.0]),
                };
                verts.joints.push(joints);
                verts.weights.push(weights);
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

/// Triangle list from TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN indices.
fn triangulate(idx: &[u32], mode: json::mesh::Mode) -> Vec<[u32; 3]> {
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

fn mark_degenerate(tris: &mut [Triangle], pos: &[Vec3], size: f32) {
    let eps = (size * size * 1e-12).max(f32::MIN_POSITIVE);
    for t in tris {
        let [a, b, c] = t.v.map(|i| pos[i as usize]);
        t.degenerate = (b - a).cross(c - a).length() <= eps;
    }
}

fn read_clips(
    src: &GltfSource,
    node_count: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<Clip>> {
    let mut clips = Vec::new();
    for (ai, anim) in src.root.animations.iter().enumerate() {
        let name = anim
            .name
            .clone()
            .unwrap_or_else(|| format!("animation{ai}"));
        let mut channels = Vec::new();
        let (mut start, mut end) = (f32::INFINITY, f32::NEG_INFINITY);
        for (ci, ch) in anim.channels.iter().enumerate() {
            let what = format!("animation '{name}' channel {ci}");
            let node = ch.target.node.value();
            if node >= node_count {
                return Err(src.invalid(format!("{what}: target node {node} does not exist")));
            }
            let property = match ch.target.path {
                Checked::Valid(json::animation::Property::Translation) => Property::Translation,
                Checked::Valid(json::animation::Property::Rotation) => Property::Rotation,
                Checked::Valid(json::animation::Property::Scale) => Property::Scale,
                Checked::Valid(json::animation::Property::MorphTargetWeights) => {
                    warnings.push(format!(
                        "{what}: morph-target weights are not supported; ignored"
                    ));
                    continue;
                }
                Checked::Invalid => return Err(src.invalid(format!("{what}: invalid target path"))),
            };
            let sampler = anim.samplers.get(ch.sampler.value()).ok_or_else(|| {
                src.invalid(format!(
                    "{what}: sampler {} does not exist",
                    ch.sampler.value()
                ))
            })?;
            let interpolation = match sampler.interpolation {
                Checked::Valid(json::animation::Interpolation::Linear) => Interpolation::Linear,
                Checked::Valid(json::animation::Interpolation::Step) => Interpolation::Step,
                Checked::Valid(json::animation::Interpolation::CubicSpline) => {
                    Interpolation::CubicSpline
                }
                Checked::Invalid => {
                    return Err(src.invalid(format!("{what}: invalid interpolation")));
                }
            };
            let times = src.read_floats(sampler.input.value(), &format!("{what} input"))?;
            if times.width != 1 {
                return Err(src.invalid(format!("{what}: input must be SCALAR")));
            }
            let times = times.values;
            if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                return Err(src.invalid(format!("{what}: key times must be finite and increasing")));
            }
            let out = src.read_floats(sampler.output.value(), &format!("{what} output"))?;
            let want_width = if property == Property::Rotation { 4 } else { 3 };
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            if out.width != want_width || out.count() != times.len() * per_key {
                return Err(src.invalid(format!(
                    "{what}: output has {} elements of width {}, expected {} of width {want_width}",
                    out.count(),
                    out.width,
                    times.len() * per_key
                )));
            }
            if out.values.iter().any(|v| !v.is_finite()) {
                return Err(src.invalid(format!("{what}: output contains NaN or Inf")));
            }
            if times.is_empty() {
                return Err(src.invalid(format!("{what}: sampler has no keys")));
            }
            if property == Property::Rotation
                && interpolation != Interpolation::CubicSpline
                && out
                    .values
                    .chunks_exact(4)
                    .any(|q| q.iter().map(|c| c * c).sum::<f32>() < 1e-6)
            {
                return Err(src.invalid(format!("{what}: a rotation key is not a unit quaternion")));
            }
            let values = (0..out.count())
                .map(|k| {
                    let v = out.get::<4>(k);
                    Vec4::from(v)
                })
                .collect();
            if let (Some(&a), Some(&b)) = (times.first(), times.last()) {
                start = start.min(a);
                end = end.max(b);
            }
            channels.push(Channel {
                node,
                property,
                interpolation,
                times,
                values,
            });
        }
        if !start.is_finite() {
            start = 0.0;
            end = 0.0;
        }
        clips.push(Clip {
            name,
            start,
            end,
            channels,
        });
    }
    Ok(clips)
}
