//! glTF import: turns any valid skinned (or static) tree into a [`Tree`]
//! (spec animated-billboard-clouds §1, §1.3; gltf-and-toolchain.md for the crate traps).
//!
//! Malformed input is either refused with a one-line error naming the cause (the node, skin,
//! primitive or animation channel, and the offending value), or accepted with a one-line
//! warning in [`Tree::warnings`] saying what was read instead; nothing is repaired silently.
//! The choice per case is documented on the function that reads that part.
//!
//! The reading is split by what it reads, one file each: `hierarchy` (nodes and scenes),
//! `buffers` (bufferView layout), `skins` (joints and inverse bind matrices), `materials`
//! (materials and their texture maps), `textures` (images: bytes, size budget, decoding),
//! `meshes` (vertices and triangles, with `influences` for skin weights) and `animation`
//! (clips and their channels). This module runs them in order and assembles the [`Tree`].

mod animation;
mod attributes;
mod buffers;
pub(crate) mod hierarchy;
mod influences;
pub(crate) mod materials;
pub(crate) mod meshes;
mod skins;
mod textures;

use std::path::Path;

use crate::binding::assign_foliage_bones;
use crate::classify::{MaterialOverrides, classify_primitives};
use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::input_file::InputLimits;
use crate::model::*;
use crate::rig::{Rig, Trs, world_matrices};
use crate::skinning::skin_positions;

pub use animation::MAX_ANIMATION_SECONDS;
pub use hierarchy::MAX_NODE_DEPTH;
pub use materials::texture_image;
pub use meshes::MAX_COORDINATE;
pub use textures::KTX2_MIME;

use animation::read_clips;
use buffers::check_buffer_views;
use hierarchy::{check_scenes, read_nodes};
use materials::read_materials;
use meshes::{check_rest_positions, mark_degenerate, read_meshes};
use skins::{check_inverse_binds, read_skins};
use textures::{check_texture_budget, read_source_textures, read_textures};

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

/// Reads the whole tree from an opened file: nodes, skins, materials and meshes, then clips,
/// then images, then the rest pose, classification and foliage bones, collecting every
/// warning into [`Tree::warnings`].
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
