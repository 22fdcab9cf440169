//! Whole glTF files: one LOD per file, or every LOD in one combined file whose LOD nodes are
//! named `<name>_LOD<k>` (the suffix convention Unity and Unreal importers use), optionally
//! with `MSFT_lod` (spec gltf-and-toolchain.md "LOD chains"). In the combined file each LOD's
//! skinned mesh node is named `LOD_<name>_LOD<k>`: a scene root whose name starts with `LOD`
//! (UnityGLTF's name-based LOD import makes a LODGroup of such roots) and ends in `_LOD<k>`
//! after a base all LODs share (the suffix convention); the LOD's other mesh node (VAT
//! billboards, not skinned) is its child, so one node shows or hides a LOD (Godot shows every
//! root at once). Skinned mesh nodes stay scene roots (glTF: parents do not move them).

use frond_scene::gltf_writer::{ChannelDesc, GltfBuilder};
use serde_json::json;

use crate::error::ExportError;
use crate::lod_scene::{LodInput, add_lod};
use crate::textures::TextureSink;

/// How files are written.
#[derive(Clone, Debug, Default)]
pub struct FileOptions {
    /// Write textures as files next to the glTF, named with this prefix.
    pub external_textures: Option<String>,
    /// How the textures frond makes are stored (PNG, KTX2).
    pub textures: crate::TextureFormat,
    /// Name clips with Godot's loop import hint (a `-loop` suffix): glTF has no loop flag,
    /// and Godot's importer loops clips whose names end in `-loop` or `_loop`.
    pub loop_hint: bool,
    /// Compressed geometry: `EXT_meshopt_compression` and `KHR_mesh_quantization`
    /// ([`GltfBuilder::set_compression`]).
    pub compress: bool,
    /// Combined files only: add `MSFT_lod` on LOD0 with these screen coverages (one per LOD,
    /// the smallest fraction of the screen height at which that LOD is shown).
    pub msft_lod: Option<Vec<f32>>,
    /// Document extras (what produced it, the seed).
    pub extras: Option<serde_json::Value>,
}

/// A written document and the external files it references.
pub struct GltfFile {
    /// The binary glTF.
    pub glb: Vec<u8>,
    /// Texture files the GLB references by URI (name relative to the GLB, bytes); empty
    /// unless textures are written as files.
    pub external: Vec<(String, Vec<u8>)>,
    /// Joints in the skin of each LOD.
    pub joints: Vec<usize>,
}

/// `name` with Godot's loop import hint: `-loop` appended unless it ends in `-loop` or
/// `_loop` already.
pub fn loop_hinted(name: &str) -> String {
    if name.ends_with("-loop") || name.ends_with("_loop") {
        name.to_string()
    } else {
        format!("{name}-loop")
    }
}

/// Writes `lods` into one GLB. With more than one LOD every node but the LOD mesh nodes gets
/// the suffix `_LOD<k>` so names stay unique; animations are merged by clip name so one clip
/// plays every LOD in phase.
pub fn write_glb(lods: &[LodInput], opts: &FileOptions) -> Result<GltfFile, ExportError> {
    write_named_glb(lods, opts, "")
}

/// The name of LOD `k`'s mesh node in a combined file of the tree `name` (see the module
/// docs).
pub fn lod_group_name(name: &str, k: usize) -> String {
    format!("LOD_{name}_LOD{k}")
}

/// [`write_glb`]; a combined file's LOD mesh nodes are named after the tree `name`.
pub fn write_named_glb(
    lods: &[LodInput],
    opts: &FileOptions,
    name: &str,
) -> Result<GltfFile, ExportError> {
    if lods.is_empty() {
        return Err(ExportError::NoLod);
    }
    let mut doc = GltfBuilder::new(concat!("frond ", env!("CARGO_PKG_VERSION")));
    if let Some(e) = &opts.extras {
        doc.set_extras(e.clone());
    }
    doc.set_compression(opts.compress);
    let mut sink = TextureSink::new(opts.external_textures.clone(), opts.textures);
    let combined = lods.len() > 1;
    let mut clips: Vec<(String, Vec<ChannelDesc>)> = Vec::new();
    let mut groups = Vec::new();
    let mut joints = Vec::new();
    for (k, lod) in lods.iter().enumerate() {
        let suffix = if combined {
            format!("_LOD{k}")
        } else {
            String::new()
        };
        let nodes = add_lod(&mut doc, lod, &suffix, &mut sink)?;
        doc.add_root(nodes.rig_root);
        match nodes.mesh_nodes.split_first() {
            Some((&first, rest)) if combined => {
                doc.set_node_name(first, &lod_group_name(name, k));
                for &n in rest {
                    doc.add_child(first, n);
                }
                groups.push(Some(first));
            }
            _ => {
                for &n in &nodes.mesh_nodes {
                    doc.add_root(n);
                }
                groups.push(None);
            }
        }
        joints.push(nodes.joints);
        for c in nodes.clips {
            match clips.iter_mut().find(|(n, _)| *n == c.name) {
                Some((_, ch)) => ch.extend(c.channels),
                None => clips.push((c.name, c.channels)),
            }
        }
    }
    let groups: Vec<usize> = groups.into_iter().flatten().collect();
    match (&opts.msft_lod, groups.split_first()) {
        (Some(coverage), Some((&first, lower))) if combined => {
            // LOD0's mesh node carries the chain; the lower LODs' mesh nodes are reached
            // through it only (clients without MSFT_lod show LOD0).
            doc.use_extension("MSFT_lod");
            doc.set_node_extension(
                first,
                "MSFT_lod",
                json!({ "ids": lower }),
                Some(json!({ "MSFT_screencoverage": coverage })),
            );
            doc.add_root(first);
        }
        _ => {
            for &g in &groups {
                doc.add_root(g);
            }
        }
    }
    for (clip, channels) in clips {
        let clip = if opts.loop_hint {
            loop_hinted(&clip)
        } else {
            clip
        };
        doc.add_animation(&clip, &channels);
    }
    Ok(GltfFile {
        glb: doc.to_glb(),
        external: sink.files,
        joints,
    })
}
