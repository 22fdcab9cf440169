//! Whole glTF files: one LOD per file, or every LOD in one combined file whose LOD nodes are
//! named `<name>_LOD<k>` (the suffix convention Unity and Unreal importers use), optionally
//! with `MSFT_lod` (spec gltf-and-toolchain.md "LOD chains").

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
    /// Combined files only: add `MSFT_lod` on LOD0 with these screen coverages (one per LOD,
    /// the smallest fraction of the screen height at which that LOD is shown).
    pub msft_lod: Option<Vec<f32>>,
    /// Document extras (what produced it, the seed).
    pub extras: Option<serde_json::Value>,
}

/// A written document and the external files it references.
pub struct GltfFile {
    pub glb: Vec<u8>,
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
    if lods.is_empty() {
        return Err(ExportError::NoLod);
    }
    let mut doc = GltfBuilder::new(concat!("frond ", env!("CARGO_PKG_VERSION")));
    if let Some(e) = &opts.extras {
        doc.set_extras(e.clone());
    }
    let mut sink = TextureSink::new(opts.external_textures.clone(), opts.textures);
    let combined = lods.len() > 1;
    let mut clips: Vec<(String, Vec<ChannelDesc>)> = Vec::new();
    let mut mesh_nodes = Vec::new();
    let mut joints = Vec::new();
    for (k, lod) in lods.iter().enumerate() {
        let suffix = if combined {
            format!("_LOD{k}")
        } else {
            String::new()
        };
        let nodes = add_lod(&mut doc, lod, &suffix, &mut sink)?;
        doc.add_root(nodes.rig_root);
        joints.push(nodes.joints);
        for c in nodes.clips {
            match clips.iter_mut().find(|(n, _)| *n == c.name) {
                Some((_, ch)) => ch.extend(c.channels),
                None => clips.push((c.name, c.channels)),
            }
        }
        mesh_nodes.push(nodes.mesh_nodes);
    }
    match (&opts.msft_lod, combined) {
        (Some(coverage), true) => {
            // LOD0's first mesh node carries the chain; the lower LODs' mesh nodes are reached
            // through it only (clients without MSFT_lod show LOD0).
            doc.use_extension("MSFT_lod");
            let ids: Vec<usize> = mesh_nodes[1..]
                .iter()
                .filter_map(|n| n.first().copied())
                .collect();
            for (k, nodes) in mesh_nodes.iter().enumerate() {
                for (i, &n) in nodes.iter().enumerate() {
                    if k == 0 && i == 0 {
                        doc.set_node_extension(
                            n,
                            "MSFT_lod",
                            json!({ "ids": ids }),
                            Some(json!({ "MSFT_screencoverage": coverage })),
                        );
                        doc.add_root(n);
                    } else if k == 0 || i > 0 {
                        doc.add_root(n);
                    }
                }
            }
        }
        _ => {
            for nodes in &mesh_nodes {
                for &n in nodes {
                    doc.add_root(n);
                }
            }
        }
    }
    for (name, channels) in clips {
        let name = if opts.loop_hint {
            loop_hinted(&name)
        } else {
            name
        };
        doc.add_animation(&name, &channels);
    }
    Ok(GltfFile {
        glb: doc.to_glb(),
        external: sink.files,
        joints,
    })
}
