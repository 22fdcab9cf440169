//! glTF import: turns any valid skinned (or static) tree into a [`Tree`]
//! (spec animated-billboard-clouds §1, §1.3; gltf-and-toolchain.md for the crate traps).
//!
//! Malformed input is either refused with a one-line error naming the cause (the node, skin,
//! primitive or animation channel, and the offending value), or accepted with a one-line
//! warning in [`Tree::warnings`] saying what was read instead; nothing is repaired silently.
//! The choice per case is documented on the function that reads that part.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use gltf::json::validation::Checked;
use rayon::prelude::*;

use crate::binding::assign_foliage_bones;
use crate::classify::{MaterialOverrides, PrimitiveInfo, classify_primitives};
use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::input_file::{
    InputLimits, MAX_ANIMATION_OPTION, MAX_INPUT_OPTION, MAX_TEXTURE_OPTION, MAX_VERTICES_OPTION,
    MIN_CHANNEL_KEYS, MIN_CLIP_KEYS, human_bytes,
};
use crate::model::*;
use crate::rig::{Channel, Clip, Interpolation, Property, world_matrices};
use crate::rig::{Node, Rig, Trs};
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
    /// What reading the input may cost (file bytes, decoded texture memory).
    pub limits: InputLimits,
}

/// Reads a `.glb` or `.gltf` tree from disk.
pub fn import(path: &Path, options: &ImportOptions) -> Result<Tree> {
    let src = GltfSource::open(path, &options.limits)?;
    import_source(&src, options)
}

/// Reads a tree from bytes, `path` naming it (and locating external files).
pub fn import_bytes(path: &Path, bytes: &[u8], options: &ImportOptions) -> Result<Tree> {
    let src = GltfSource::from_bytes(path, bytes, &options.limits)?;
    import_source(&src, options)
}

fn import_source(src: &GltfSource, options: &ImportOptions) -> Result<Tree> {
    let mut warnings = Vec::new();
    let (nodes, node_order) = read_nodes(src)?;
    check_scenes(src, &nodes, &mut warnings);
    check_buffer_views(src, &mut warnings);
    let (bones, skin_bindings) = read_skins(src, &nodes)?;
    let mut nodes = nodes;
    for (b, bone) in bones.iter().enumerate() {
        nodes[bone.node].bone = Some(b);
    }
    let mut bindings: Vec<Binding> = skin_bindings;
    let materials = read_materials(src, &mut warnings)?;
    let (vertices, prims) = read_meshes(
        src,
        &node_order,
        &mut bindings,
        &bones,
        &materials,
        &mut warnings,
    )?;
    check_inverse_binds(src, &bones, &bindings, &vertices, &mut warnings)?;
    if prims.is_empty() && !options.allow_empty {
        return Err(src.invalid("the file has no mesh with triangles (nothing to simplify)"));
    }
    // Clips before textures: a broken animation is reported without decoding any image.
    let clips = read_clips(src, nodes.len(), &mut warnings)?;
    let (source_textures, images, slot_of_image) =
        read_source_textures(src, &materials, &mut warnings)?;
    // Normal maps are decoded only when the file gives tangent frames to apply them with.
    let normal_images: Vec<Option<usize>> = if vertices.tangent.is_empty() {
        vec![None; materials.normal.len()]
    } else {
        materials.normal.clone()
    };
    let mut decoded: Vec<usize> = materials.base.iter().flatten().map(|t| t.0).collect();
    decoded.extend(normal_images.iter().flatten());
    let sizes = check_texture_budget(src, &images, &slot_of_image)?;
    let (textures, texture_images) = read_textures(src, &decoded, &images, &sizes, &slot_of_image)?;
    let mut materials_out = materials.materials;
    for ((m, info), normal) in materials_out
        .iter_mut()
        .zip(&materials.base)
        .zip(&normal_images)
    {
        m.base_color_texture =
            info.and_then(|(img, _, _)| texture_images.iter().position(|&i| i == img));
        m.normal_texture = normal.and_then(|img| texture_images.iter().position(|&i| i == img));
    }
    let materials = materials_out;

    // Rest pose: every node at its own TRS.
    let rest_pose: Vec<Trs> = nodes.iter().map(|n| n.rest).collect();
    let rest_world = world_matrices(&nodes, &node_order, &rest_pose);
    let mut bones = bones;
    for b in &mut bones {
        b.rest_world = rest_world[b.node];
    }
    let tmp = Tree {
        source: src.path.clone(),
        rig: Rig {
            nodes,
            order: node_order,
            clips,
        },
        bones,
        bindings,
        vertices,
        triangles: Vec::new(),
        materials,
        textures,
        source_textures,
        images,
        classification: Vec::new(),
        foliage_reassigned: 0,
        warnings: Vec::new(),
        bounds: Bounds::of([]),
    };
    let rest_positions = skin_positions(&tmp, &rest_world);
    check_rest_positions(src, &tmp.rig.nodes, &prims, &rest_positions)?;
    let mut tree = tmp;
    let (triangles, classification) = classify_primitives(
        &tree,
        &prims,
        &rest_positions,
        MaterialOverrides {
            foliage: &options.foliage_materials,
            wood: &options.wood_materials,
        },
    );
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
            base_color_wrap: [Wrap::Repeat; 2],
            normal_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            source: None,
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
    } else if tree.rig.clips.is_empty() {
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

/// Deepest node hierarchy accepted, counting a root as level 1. Real tree skeletons are under
/// 30 levels (the shared trees: at most 8 bones in a chain); a chain thousands deep is a
/// malformed or hostile file, and writing it back out crashes glTF tools that walk the
/// hierarchy recursively (the Khronos validator among them). frond's own walks are iterative,
/// so the limit only keeps what frond writes readable.
pub const MAX_NODE_DEPTH: usize = 256;

/// Largest coordinate magnitude accepted for a vertex, in the file's units, both in a POSITION
/// accessor and after the rest-pose transforms. No tree is ten thousand kilometres (or, in
/// millimetres, ten kilometres) across, f32 cannot resolve a leaf out there, and sizes computed
/// from such values overflow: refusing names the cause instead of a later "no height" or
/// "no foliage".
pub const MAX_COORDINATE: f32 = 1e7;

/// Latest key time accepted in an animation, in seconds (one hour). Wind loops last seconds;
/// a clip that runs for hours (or 4e30 s, as a corrupted time accessor gives) cannot be
/// sampled meaningfully into a loop of a few dozen poses, so it is refused rather than guessed at.
pub const MAX_ANIMATION_SECONDS: f32 = 3600.0;

/// Reads the node hierarchy: rest transforms, parents and children, and a parents-first order.
///
/// Refuses a node with two parents, a cycle, and a hierarchy deeper than [`MAX_NODE_DEPTH`]
/// (naming the first node past the limit). Everything here is iterative, so no depth can
/// overflow the stack before that check.
pub(crate) fn read_nodes(src: &GltfSource) -> Result<(Vec<Node>, Vec<usize>)> {
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
    let mut depth = vec![0usize; n];
    for &i in &order {
        depth[i] = nodes[i].parent.map_or(1, |p| depth[p] + 1);
        if depth[i] > MAX_NODE_DEPTH {
            return Err(src.invalid(format!(
                "node {i} ('{}') is {} levels deep; frond refuses node hierarchies deeper than {MAX_NODE_DEPTH} levels (tree skeletons are under 30; deeper chains break glTF tools)",
                nodes[i].name, depth[i]
            )));
        }
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

/// Warns about scene data frond does not rely on but a file may get wrong: a `"scene"` index
/// past the scene list, a scene root that does not exist, and a scene root that is also
/// another node's child. frond reads every node of the hierarchy whatever the scenes say, so
/// none of these changes the import; the warning says what was read instead.
fn check_scenes(src: &GltfSource, nodes: &[Node], warnings: &mut Vec<String>) {
    let scenes = &src.root.scenes;
    if let Some(s) = src.root.scene.map(|s| s.value())
        && s >= scenes.len()
    {
        warnings.push(format!(
            "\"scene\" is {s}, but the file has {} scenes; frond reads every node regardless",
            scenes.len()
        ));
    }
    for (si, scene) in scenes.iter().enumerate() {
        for r in scene.nodes.iter().map(|r| r.value()) {
            match nodes.get(r) {
                None => warnings.push(format!(
                    "scene {si} lists node {r} as a root, but there are only {} nodes; ignored",
                    nodes.len()
                )),
                Some(node) => {
                    if let Some(p) = node.parent {
                        warnings.push(format!(
                            "scene {si} lists node {r} ('{}') as a root, but it is a child of node {p} ('{}'); read as that node's child",
                            node.name, nodes[p].name
                        ));
                    }
                }
            }
        }
    }
}

/// Warns about a bufferView whose `byteStride` is 0: glTF allows 4 to 252, and frond (like
/// most readers) takes 0 as tightly packed, which may not be what the writer meant.
fn check_buffer_views(src: &GltfSource, warnings: &mut Vec<String>) {
    for (vi, view) in src.root.buffer_views.iter().enumerate() {
        if view.byte_stride.map(|s| s.0) != Some(0) {
            continue;
        }
        let users: Vec<String> = src
            .root
            .accessors
            .iter()
            .enumerate()
            .filter(|(_, a)| a.buffer_view.map(|v| v.value()) == Some(vi))
            .map(|(a, _)| a.to_string())
            .collect();
        let readers = if users.is_empty() {
            "no accessor reads it".to_string()
        } else {
            format!(
                "accessor{} {} read it as tightly packed",
                if users.len() == 1 { "" } else { "s" },
                users.join(", ")
            )
        };
        warnings.push(format!(
            "bufferView {vi}: byteStride 0 is invalid (glTF allows 4 to 252); {readers}"
        ));
    }
}

/// How far an inverse bind matrix is from singular: |det| of its 3×3 part over the product of
/// its column lengths (Hadamard's bound), so 1 for a rotation-and-scale matrix of any scale and
/// 0 for a singular one. Computed in f64 so large but sane scales do not overflow.
fn bind_conditioning(m: &Mat4) -> f64 {
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate().as_dvec3());
    let norms = cols[0].length() * cols[1].length() * cols[2].length();
    if norms > 0.0 && norms.is_finite() {
        glam::DMat3::from_cols(cols[0], cols[1], cols[2])
            .determinant()
            .abs()
            / norms
    } else {
        0.0
    }
}

/// Inverse bind matrices closer to singular than this (see [`bind_conditioning`]) are refused:
/// skinning through them flattens every vertex weighted to that joint onto a plane, a line or
/// a point, and later stages then fail on the symptom ("the tree has no height").
const SINGULAR_BIND: f64 = 1e-6;

/// Checks every skin's inverse bind matrices for singular ones. A singular matrix on a joint
/// that some vertex is weighted to (including vertices without weights, bound to the first
/// joint) is an error naming the skin, the joint and its node; on a joint no vertex uses it is
/// harmless for frond, so only a warning.
fn check_inverse_binds(
    src: &GltfSource,
    bones: &[Bone],
    bindings: &[Binding],
    verts: &Vertices,
    warnings: &mut Vec<String>,
) -> Result<()> {
    for (s, binding) in bindings.iter().enumerate() {
        let Binding::Skin {
            joints,
            inverse_bind,
        } = binding
        else {
            continue;
        };
        let singular: Vec<usize> = (0..inverse_bind.len())
            .filter(|&k| bind_conditioning(&inverse_bind[k]) < SINGULAR_BIND)
            .collect();
        let Some(&first) = singular.first() else {
            continue;
        };
        // Vertices weighted to each joint of this skin.
        let mut users = vec![0usize; joints.len()];
        for v in 0..verts.len() {
            if verts.binding[v] as usize != s {
                continue;
            }
            for j in 0..4 {
                if verts.weights[v][j] > 0.0
                    && let Some(u) = users.get_mut(verts.joints[v][j] as usize)
                {
                    *u += 1;
                }
            }
        }
        let skin_name = src
            .root
            .skins
            .get(s)
            .and_then(|sk| sk.name.as_deref())
            .map(|n| format!(" ('{n}')"))
            .unwrap_or_default();
        let joint = |k: usize| {
            let b = &bones[joints[k]];
            format!(
                "the inverse bind matrix of joint {k} (node {} '{}') is singular (determinant {:?})",
                b.node,
                b.name,
                inverse_bind[k].determinant()
            )
        };
        if let Some(&k) = singular.iter().find(|&&k| users[k] > 0) {
            return Err(src.invalid(format!(
                "skin {s}{skin_name}: {}; the {} vertices weighted to it would collapse",
                joint(k),
                users[k]
            )));
        }
        let more = match singular.len() {
            1 => String::new(),
            n => format!(" (and {} more joints)", n - 1),
        };
        warnings.push(format!(
            "skin {s}{skin_name}: {}{more}; harmless here, as no vertex is weighted to it",
            joint(first)
        ));
    }
    Ok(())
}

/// Refuses a primitive whose vertices land at absurd or non-finite coordinates in the rest
/// pose (beyond ±[`MAX_COORDINATE`]): sane POSITION values can still be scaled there by node or
/// skin transforms, and the tree's size then overflows.
fn check_rest_positions(
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

/// What [`read_materials`] found.
struct MaterialInfo {
    materials: Vec<Material>,
    /// Per material: (input image index, texcoord set, uv transform) of its base colour.
    base: Vec<Option<(usize, u32, glam::Affine2)>>,
    /// Per material: the input image of its normal map, when that samples the base colour's
    /// coordinates (see [`Material::normal_texture`]).
    normal: Vec<Option<usize>>,
    /// The input texture index of every [`Tree::source_textures`] entry, in that order.
    textures: Vec<usize>,
    /// How many texture coordinate sets the maps use (1 ..= [`MAX_TEXCOORD_SETS`]).
    texcoord_sets: usize,
}

/// The names under every `extensions` object of `value`, at any depth (sorted, unique).
fn extension_names(value: &serde_json::Value, out: &mut Vec<String>) {
    if let serde_json::Value::Object(map) = value {
        for (key, v) in map {
            if key == "extensions"
                && let serde_json::Value::Object(ext) = v
            {
                out.extend(ext.keys().cloned());
            }
            extension_names(v, out);
        }
    }
    out.sort();
    out.dedup();
}

/// Reads the materials: what billboards need (base colour and its texture, alpha, sides) and the
/// whole input description ([`MaterialSource`]) for writing them back unchanged.
///
/// Refused: a texture map naming a texture that does not exist (or whose texture names a
/// missing image or sampler), with the material and map named. Accepted with a warning: a map
/// using a texture coordinate set past `TEXCOORD_1` (written with `texCoord` 0: frond carries
/// [`MAX_TEXCOORD_SETS`] sets).
fn read_materials(src: &GltfSource, warnings: &mut Vec<String>) -> Result<MaterialInfo> {
    let mut mats = Vec::new();
    let mut texinfo = Vec::new();
    let mut normals = Vec::new();
    let mut textures: Vec<usize> = Vec::new();
    let mut texcoord_sets = 1usize;
    for (i, m) in src.root.materials.iter().enumerate() {
        let pbr = &m.pbr_metallic_roughness;
        let mut base_color_wrap = [Wrap::Repeat; 2];
        let tex = match &pbr.base_color_texture {
            Some(info) => {
                let t = src.root.textures.get(info.index.value()).ok_or_else(|| {
                    src.invalid(format!(
                        "material {i}: texture {} does not exist",
                        info.index.value()
                    ))
                })?;
                let image = texture_image(src, info.index.value(), false);
                if image >= src.root.images.len() {
                    return Err(src.invalid(format!(
                        "texture {}: image {image} does not exist",
                        info.index.value()
                    )));
                }
                if let Some(sampler) = t.sampler.and_then(|s| src.root.samplers.get(s.value())) {
                    base_color_wrap = [&sampler.wrap_s, &sampler.wrap_t].map(wrap_of);
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
        let mut json = src
            .raw
            .materials
            .get(i)
            .cloned()
            .unwrap_or_else(|| serde_json::json!({}));
        visit_texture_infos(&mut json, &mut |key, info| {
            let index = info
                .get("index")
                .and_then(serde_json::Value::as_u64)
                .map(|t| t as usize)
                .ok_or_else(|| {
                    src.invalid(format!("material {i}: {key} has no valid texture index"))
                })?;
            let texture = src.root.textures.get(index).ok_or_else(|| {
                src.invalid(format!(
                    "material {i}: {key} names texture {index}, which does not exist"
                ))
            })?;
            let image = texture_image(src, index, false);
            if image >= src.root.images.len() {
                return Err(src.invalid(format!(
                    "texture {index} (material {i} {key}): image {image} does not exist"
                )));
            }
            if let Some(s) = texture.sampler.map(|s| s.value())
                && s >= src.raw.samplers.len()
            {
                return Err(src.invalid(format!(
                    "texture {index} (material {i} {key}): sampler {s} does not exist"
                )));
            }
            let slot = match textures.iter().position(|&t| t == index) {
                Some(slot) => slot,
                None => {
                    textures.push(index);
                    textures.len() - 1
                }
            };
            info.insert("index".into(), serde_json::json!(slot));
            // The set the map samples: its own texCoord, or KHR_texture_transform's override.
            let overridden = info
                .get("extensions")
                .and_then(|e| e.get("KHR_texture_transform"))
                .is_some_and(|t| t.get("texCoord").is_some());
            let (holder, whose) = if overridden {
                match info
                    .get_mut("extensions")
                    .and_then(|e| e.get_mut("KHR_texture_transform"))
                    .and_then(serde_json::Value::as_object_mut)
                {
                    Some(t) => (t, format!("{key}'s KHR_texture_transform")),
                    None => return Ok(()),
                }
            } else {
                (info, key.to_string())
            };
            let set = holder
                .get("texCoord")
                .and_then(serde_json::Value::as_u64)
                .unwrap_or(0);
            if set as usize >= MAX_TEXCOORD_SETS {
                warnings.push(format!(
                    "material {i} ('{}'): {whose} uses TEXCOORD_{set}; frond carries TEXCOORD_0 and TEXCOORD_1 only, so it is written with TEXCOORD_0",
                    m.name.as_deref().unwrap_or("")
                ));
                holder.insert("texCoord".into(), serde_json::json!(0));
            } else {
                texcoord_sets = texcoord_sets.max(set as usize + 1);
            }
            Ok(())
        })?;
        let mut extensions = Vec::new();
        extension_names(&json, &mut extensions);
        mats.push(Material {
            name: m.name.clone().unwrap_or_else(|| format!("material{i}")),
            base_color: pbr.base_color_factor.0,
            base_color_texture: None,
            base_color_wrap,
            normal_texture: None,
            alpha_mode,
            alpha_cutoff: m.alpha_cutoff.map(|c| c.0).unwrap_or(0.5),
            double_sided: m.double_sided,
            source: Some(MaterialSource { json, extensions }),
        });
        // The normal map, when it samples what `Vertices::uv` holds: the base colour's set,
        // untransformed on both (else the two maps' coordinates differ and it is not applied).
        let normal = m.normal_texture.as_ref().and_then(|n| {
            let same_set = tex.map_or(0, |t| t.1) == n.tex_coord;
            let untransformed = tex.is_none_or(|t| t.2 == glam::Affine2::IDENTITY)
                && src.raw.materials.get(i).is_none_or(|j| {
                    j.pointer("/normalTexture/extensions/KHR_texture_transform")
                        .is_none()
                });
            let image = texture_image(src, n.index.value(), false);
            (same_set && untransformed && image < src.root.images.len()).then_some(image)
        });
        texinfo.push(tex);
        normals.push(normal);
    }
    Ok(MaterialInfo {
        materials: mats,
        base: texinfo,
        normal: normals,
        textures,
        texcoord_sets,
    })
}

/// A glTF sampler's wrap mode as frond's (an invalid one reads as the default, repeat).
fn wrap_of(mode: &Checked<json::texture::WrappingMode>) -> Wrap {
    match mode {
        Checked::Valid(json::texture::WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
        Checked::Valid(json::texture::WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    }
}

/// The MIME type of KTX2 images (`KHR_texture_basisu`).
pub const KTX2_MIME: &str = "image/ktx2";

/// The image texture `t` shows: its core `source`, else the KTX2 image its
/// `KHR_texture_basisu` names (a texture without a fallback), else an index past the images
/// (reported as missing by the callers). With `prefer_ktx2`, the KTX2 image first (what a
/// client with the extension loads: the file's cost). `t` must exist.
pub fn texture_image(src: &GltfSource, t: usize, prefer_ktx2: bool) -> usize {
    let core = Some(src.root.textures[t].source.value()).filter(|&i| i != u32::MAX as usize);
    let ktx2 = src
        .raw
        .textures
        .get(t)
        .and_then(|j| j.pointer("/extensions/KHR_texture_basisu/source"))
        .and_then(serde_json::Value::as_u64)
        .map(|i| i as usize);
    let (first, second) = if prefer_ktx2 {
        (ktx2, core)
    } else {
        (core, ktx2)
    };
    first.or(second).unwrap_or(usize::MAX)
}

/// The MIME type of an encoded image recognised from its first bytes (PNG or JPEG).
fn sniff_mime(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some("image/jpeg")
    } else {
        None
    }
}

/// What [`read_source_textures`] read: the textures, the images, and per input image index its
/// slot in the images.
type SourceParts = (Vec<SourceTexture>, Vec<SourceImage>, HashMap<usize, usize>);

/// Reads the textures the materials' maps name and their images' original bytes (not decoded;
/// written back byte for byte). External image files count towards
/// [`InputLimits::max_input_bytes`] together with the file and its buffers.
///
/// Returns the source textures (in [`MaterialInfo::textures`] order), the images and, per
/// input image index read, its slot in the images. A texture's own `extensions` (say
/// `EXT_texture_webp` naming another image) are dropped with a warning: the texture is written
/// with its core `source` image.
fn read_source_textures(
    src: &GltfSource,
    info: &MaterialInfo,
    warnings: &mut Vec<String>,
) -> Result<SourceParts> {
    let mut images: Vec<SourceImage> = Vec::new();
    let mut slot_of_image: HashMap<usize, usize> = HashMap::new();
    let mut total = src.bytes_read;
    let mut read_image = |img: usize, images: &mut Vec<SourceImage>| -> Result<usize> {
        if let Some(&slot) = slot_of_image.get(&img) {
            return Ok(slot);
        }
        let bytes = src.image_bytes(img)?;
        let raw = src.raw.images.get(img);
        let external = src.root.images[img]
            .uri
            .as_deref()
            .is_some_and(|u| !u.starts_with("data:"))
            && src.root.images[img].buffer_view.is_none();
        if external {
            total = total.saturating_add(bytes.len() as u64);
            if total > src.limits.max_input_bytes {
                return Err(src.invalid(format!(
                    "image {img}: the file, its external buffers and images add up to {}, over the input size limit of {} (raise it with {MAX_INPUT_OPTION})",
                    human_bytes(total),
                    human_bytes(src.limits.max_input_bytes)
                )));
            }
        }
        let mime = raw
            .and_then(|r| r.get("mimeType"))
            .and_then(serde_json::Value::as_str)
            .map(str::to_string)
            .or_else(|| sniff_mime(&bytes).map(str::to_string))
            .ok_or_else(|| {
                src.invalid(format!(
                    "image {img}: neither PNG nor JPEG, and no mimeType says what it is"
                ))
            })?;
        images.push(SourceImage {
            name: src.root.images[img].name.clone(),
            mime_type: mime,
            bytes,
        });
        slot_of_image.insert(img, images.len() - 1);
        Ok(images.len() - 1)
    };
    let mut textures = Vec::with_capacity(info.textures.len());
    for &t in &info.textures {
        let texture = &src.root.textures[t];
        let image = read_image(texture_image(src, t, false), &mut images)?;
        let mut json = src
            .raw
            .textures
            .get(t)
            .cloned()
            .unwrap_or_else(|| serde_json::json!({}));
        if let serde_json::Value::Object(map) = &mut json {
            map.remove("source");
            map.remove("sampler");
            if let Some(serde_json::Value::Object(ext)) = map.remove("extensions") {
                let names: Vec<&str> = ext.keys().map(String::as_str).collect();
                warnings.push(format!(
                    "texture {t}: extensions {} not passed through; written with its core source image",
                    names.join(", ")
                ));
            }
        }
        let sampler = texture
            .sampler
            .and_then(|s| src.raw.samplers.get(s.value()).cloned());
        textures.push(SourceTexture {
            json,
            image,
            sampler,
        });
    }
    // Base-colour images are decoded from these bytes too.
    for img in info.base.iter().flatten().map(|b| b.0) {
        read_image(img, &mut images)?;
    }
    Ok((textures, images, slot_of_image))
}

/// Checks the decoded size of every image the materials use (every map slot: base colour,
/// normal, occlusion, metallic-roughness, emissive, extensions' maps; PNG, JPEG and KTX2 alike)
/// against [`InputLimits::max_texture_bytes`], from the images' headers, before any image is
/// decoded. frond decodes base-colour maps and applied normal maps on import and may decode any
/// other map later (a far LOD writes it downscaled), so all of them count, each image once, at
/// 4 bytes (RGBA8) per texel. A small file that declares huge images (a "texture bomb") is
/// refused naming the largest image and the map that uses it; an image whose header cannot be
/// read is refused naming it.
///
/// Returns each image slot's declared size, in the order of `images`.
fn check_texture_budget(
    src: &GltfSource,
    images: &[SourceImage],
    slot_of_image: &HashMap<usize, usize>,
) -> Result<Vec<(u32, u32)>> {
    let mut input_of_slot = vec![0usize; images.len()];
    for (&img, &slot) in slot_of_image {
        input_of_slot[slot] = img;
    }
    let sizes = images
        .iter()
        .enumerate()
        .map(|(slot, image)| {
            declared_size(image).map_err(|e| {
                src.invalid(format!(
                    "{}: cannot read its size ({e})",
                    image_role(src, input_of_slot[slot])
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // Saturating: a header may declare 2³¹ × 2³¹ texels.
    let bytes = |&(w, h): &(u32, u32)| u64::from(w).saturating_mul(u64::from(h)).saturating_mul(4);
    let total = sizes.iter().map(bytes).fold(0u64, u64::saturating_add);
    let budget = src.limits.max_texture_bytes;
    if total > budget {
        // The first of the largest.
        let (slot, &(w, h)) = sizes
            .iter()
            .enumerate()
            .rev()
            .max_by_key(|(_, s)| bytes(s))
            .unwrap_or((0, &(0, 0)));
        return Err(src.invalid(format!(
            "its {} images decode to {} (largest: {}, {w}×{h} texels, {}), over the texture memory limit of {} (raise it with {MAX_TEXTURE_OPTION})",
            images.len(),
            human_bytes(total),
            image_role(src, input_of_slot[slot]),
            human_bytes(bytes(&(w, h))),
            human_bytes(budget)
        )));
    }
    Ok(sizes)
}

/// An image's width and height as its header declares them (PNG, JPEG, or KTX2 of any
/// format: one frond cannot decode, such as ETC1S, is passed through but still counts).
fn declared_size(image: &SourceImage) -> std::result::Result<(u32, u32), String> {
    if image.mime_type == KTX2_MIME {
        return crate::ktx2::declared_size(&image.bytes).map_err(|e| e.to_string());
    }
    image::ImageReader::new(std::io::Cursor::new(&image.bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .into_dimensions()
        .map_err(|e| e.to_string())
}

/// Input image `img` in words for messages: its index, name, and the first material map that
/// uses it (`image 2 ('bark_n'), the normalTexture of material 0 ('bark')`).
fn image_role(src: &GltfSource, img: usize) -> String {
    let name = src
        .root
        .images
        .get(img)
        .and_then(|i| i.name.as_deref())
        .map(|n| format!(" ('{n}')"))
        .unwrap_or_default();
    let mut role = None;
    for (i, m) in src.raw.materials.iter().enumerate() {
        let mut json = m.clone();
        let _ = visit_texture_infos(&mut json, &mut |key, info| {
            let t = info.get("index").and_then(serde_json::Value::as_u64);
            let uses = t.is_some_and(|t| {
                let t = t as usize;
                t < src.root.textures.len()
                    && (texture_image(src, t, false) == img || texture_image(src, t, true) == img)
            });
            if uses && role.is_none() {
                let material = m
                    .get("name")
                    .and_then(serde_json::Value::as_str)
                    .map(|n| format!(" ('{n}')"))
                    .unwrap_or_default();
                role = Some(format!(", the {key} of material {i}{material}"));
            }
            Ok::<(), ()>(())
        });
    }
    format!("image {img}{name}{}", role.unwrap_or_default())
}

/// Decodes the images `decoded` (input image indices: the base-colour images materials use,
/// and the normal maps applied) in parallel from their bytes in `images`, whose declared
/// `sizes` [`check_texture_budget`] has checked. Each decoder is held to its image's declared
/// size, in case a header lies. Images only other maps use (and normal maps not applied) are
/// not decoded here (they are passed through).
fn read_textures(
    src: &GltfSource,
    decoded: &[usize],
    images: &[SourceImage],
    sizes: &[(u32, u32)],
    slot_of_image: &HashMap<usize, usize>,
) -> Result<(Vec<Texture>, Vec<usize>)> {
    let mut used: Vec<usize> = decoded.to_vec();
    used.sort_unstable();
    used.dedup();
    let encoded = used
        .iter()
        .map(|&img| {
            let slot = slot_of_image
                .get(&img)
                .copied()
                .ok_or_else(|| src.invalid(format!("image {img} was not read")))?;
            let (w, h) = sizes[slot];
            Ok((
                img,
                slot,
                u64::from(w).saturating_mul(u64::from(h)).saturating_mul(4),
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    let textures = encoded
        .par_iter()
        .map(|&(img, slot, size)| {
            let name = src.root.images[img]
                .name
                .clone()
                .unwrap_or_else(|| format!("image{img}"));
            if images[slot].mime_type == KTX2_MIME {
                let mut levels = crate::ktx2::decode_levels(&images[slot].bytes, 1)
                    .map_err(|e| src.invalid(format!("image {img}: {e}")))?;
                let (width, height, rgba) = levels.pop().ok_or_else(|| {
                    src.invalid(format!("image {img}: a KTX2 file without levels"))
                })?;
                return Ok(Texture {
                    name,
                    width,
                    height,
                    rgba,
                    image: Some(slot),
                });
            }
            let mut reader = image::ImageReader::new(std::io::Cursor::new(&images[slot].bytes))
                .with_guessed_format()
                .map_err(|e| src.invalid(format!("image {img}: cannot read ({e})")))?;
            let mut limits = image::Limits::default();
            // The declared size plus slack for the decoder's own buffers.
            limits.max_alloc = Some(size.saturating_mul(2).max(1 << 20));
            reader.limits(limits);
            let decoded = reader
                .decode()
                .map_err(|e| src.invalid(format!("image {img}: cannot decode ({e})")))?
                .into_rgba8();
            Ok(Texture {
                name,
                width: decoded.width(),
                height: decoded.height(),
                rgba: decoded.into_raw(),
                image: Some(slot),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((textures, used))
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
fn read_meshes(
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

/// Removes keys whose time equals the next key's time, keeping the last key of every run of
/// equal times; `per_key` values go with each key (3 for CUBICSPLINE: in-tangent, value,
/// out-tangent). Returns the times, the values and how many keys were dropped.
fn drop_repeated_keys(
    times: Vec<f32>,
    values: Vec<Vec4>,
    per_key: usize,
) -> (Vec<f32>, Vec<Vec4>, usize) {
    if times.windows(2).all(|w| w[0] < w[1]) {
        return (times, values, 0);
    }
    let mut kept_times = Vec::with_capacity(times.len());
    let mut kept_values = Vec::with_capacity(values.len());
    for (k, &t) in times.iter().enumerate() {
        if times.get(k + 1) == Some(&t) {
            continue;
        }
        kept_times.push(t);
        kept_values.extend_from_slice(&values[k * per_key..(k + 1) * per_key]);
    }
    let dropped = times.len() - kept_times.len();
    (kept_times, kept_values, dropped)
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

fn mark_degenerate(tris: &mut [Triangle], pos: &[Vec3], size: f32) {
    let eps = (size * size * 1e-12).max(f32::MIN_POSITIVE);
    for t in tris {
        let [a, b, c] = t.v.map(|i| pos[i as usize]);
        t.degenerate = (b - a).cross(c - a).length() <= eps;
    }
}

/// An animation's name, or `animation<i>`.
fn clip_name(anim: &json::Animation, i: usize) -> String {
    anim.name.clone().unwrap_or_else(|| format!("animation{i}"))
}

/// Per animation, the channels read: all but those whose target (node and property) an earlier
/// channel of the same animation already drives. glTF forbids two channels with one target
/// (the validator's ANIMATION_DUPLICATE_TARGETS) and players keep one; frond keeps the first,
/// with a warning naming the animation and how many were dropped.
fn kept_channels(src: &GltfSource, warnings: &mut Vec<String>) -> Vec<Vec<usize>> {
    src.root
        .animations
        .iter()
        .enumerate()
        .map(|(ai, anim)| {
            let mut seen = std::collections::HashSet::new();
            let kept: Vec<usize> = (0..anim.channels.len())
                .filter(|&ci| {
                    let t = &anim.channels[ci].target;
                    seen.insert((t.node.value(), format!("{:?}", t.path)))
                })
                .collect();
            let dropped = anim.channels.len() - kept.len();
            if dropped > 0 {
                warnings.push(format!(
                    "animation '{}': {dropped} channel{} drive a target (node and property) an earlier channel already drives; the first channel of each target kept (glTF allows one)",
                    clip_name(anim, ai),
                    if dropped == 1 { "" } else { "s" }
                ));
            }
            kept
        })
        .collect()
}

/// Refuses animations whose keys, counted from the time accessors' declared counts before any
/// is read, exceed [`InputLimits::max_animation_keys`] (see there for how channels and clips
/// count), naming the clip with the most.
fn check_animation_budget(src: &GltfSource, kept: &[Vec<usize>]) -> Result<()> {
    let per_clip: Vec<(u64, usize)> = src
        .root
        .animations
        .iter()
        .zip(kept)
        .map(|(anim, kept)| {
            let keys = kept
                .iter()
                .map(|&ci| {
                    let declared = anim
                        .samplers
                        .get(anim.channels[ci].sampler.value())
                        .and_then(|s| src.root.accessors.get(s.input.value()))
                        .map_or(0, |a| a.count.0);
                    declared.max(MIN_CHANNEL_KEYS)
                })
                .fold(0u64, u64::saturating_add);
            (keys.max(MIN_CLIP_KEYS), kept.len())
        })
        .collect();
    let total = per_clip.iter().map(|c| c.0).fold(0u64, u64::saturating_add);
    let limit = src.limits.max_animation_keys;
    if total <= limit {
        return Ok(());
    }
    // The first of the largest.
    let (largest, &(keys, channels)) = per_clip
        .iter()
        .enumerate()
        .rev()
        .max_by_key(|(_, c)| c.0)
        .unwrap_or((0, &(0, 0)));
    let name = src
        .root
        .animations
        .get(largest)
        .map(|a| clip_name(a, largest))
        .unwrap_or_default();
    Err(src.invalid(format!(
        "its {} animations add up to {total} keys (largest: animation '{name}', {keys} keys in {channels} channels), over the animation limit of {limit} keys (raise it with {MAX_ANIMATION_OPTION})",
        per_clip.len()
    )))
}

/// Reads every animation into a [`Clip`], so that each channel's key times are finite,
/// non-negative, strictly increasing and at most [`MAX_ANIMATION_SECONDS`] — what glTF
/// requires of a sampler input, and so what frond writes back validates.
///
/// Broken key times are handled per case:
/// - non-finite, negative, or decreasing (a key before the one preceding it): an error naming
///   the animation, channel, key and time. No repair is right there: shifting negative times
///   would move this channel against the others, and reordering keys guesses the intent.
/// - a key at the same time as the key before it (a run of equal times, as some exporters
///   write for a jump): repaired by keeping only the last key of the run, the value the
///   channel holds from that time on (and what frond sampled at that time before), with a
///   warning naming the channel and how many keys were dropped. For CUBICSPLINE the dropped
///   key's in-tangent, value and out-tangent go together.
/// - a key after [`MAX_ANIMATION_SECONDS`]: an error naming the channel and the time, since a
///   clip that long (a corrupted accessor gives 4e30 s) cannot be sampled into a loop.
fn read_clips(
    src: &GltfSource,
    node_count: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<Clip>> {
    let kept = kept_channels(src, warnings);
    check_animation_budget(src, &kept)?;
    let mut clips = Vec::new();
    for (ai, anim) in src.root.animations.iter().enumerate() {
        let name = clip_name(anim, ai);
        let mut channels = Vec::new();
        let (mut start, mut end) = (f32::INFINITY, f32::NEG_INFINITY);
        for &ci in &kept[ai] {
            let ch = &anim.channels[ci];
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
            // `+ 0.0` turns -0 into +0, so no written time reads as negative.
            let times: Vec<f32> = times.values.iter().map(|t| t + 0.0).collect();
            if let Some((k, t)) = times.iter().enumerate().find(|(_, t)| !t.is_finite()) {
                return Err(src.invalid(format!("{what}: key time {t:?} at key {k} is not finite")));
            }
            if let Some((k, t)) = times.iter().enumerate().find(|(_, t)| **t < 0.0) {
                return Err(src.invalid(format!(
                    "{what}: key time {t:?} at key {k} is negative (glTF requires times ≥ 0)"
                )));
            }
            if let Some(k) = (1..times.len()).find(|&k| times[k] < times[k - 1]) {
                return Err(src.invalid(format!(
                    "{what}: key time {:?} at key {k} is before key {}'s {:?} (glTF requires increasing times)",
                    times[k],
                    k - 1,
                    times[k - 1]
                )));
            }
            if let Some((k, t)) = times
                .iter()
                .enumerate()
                .find(|(_, t)| **t > MAX_ANIMATION_SECONDS)
            {
                return Err(src.invalid(format!(
                    "{what}: key time {t:?} s at key {k} is past frond's limit of {MAX_ANIMATION_SECONDS} s (1 hour) for an animation; sampling a clip that long is meaningless"
                )));
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
            let values: Vec<Vec4> = (0..out.count())
                .map(|k| {
                    let v = out.get::<4>(k);
                    Vec4::from(v)
                })
                .collect();
            let (times, values, dropped) = drop_repeated_keys(times, values, per_key);
            if dropped > 0 {
                warnings.push(format!(
                    "{what}: {dropped} key{} at the same time as the key before dropped, keeping the last key at each repeated time (glTF requires strictly increasing times)",
                    if dropped == 1 { "" } else { "s" }
                ));
            }
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
