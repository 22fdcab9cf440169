//! What a glTF/GLB file costs an engine that draws it, read from the file itself: triangles,
//! vertices, draw calls, materials, skinning, animation keys, textures (encoded and decoded),
//! bytes on disk and the alpha-tested (overdraw) area.
//!
//! The same function costs frond's LODs, the input tree and any foreign file (gltfpack output,
//! an artist's LOD), so it reads the file and nothing frond builds in memory. The file is opened
//! by [`GltfSource`] (the importer's reader, under [`InputLimits`] and the external-file rules
//! of [`crate::input_file`]).
//!
//! What counts as drawn: every mesh instance of the default scene (`scene`, else scene 0; a
//! file without scenes, or whose `scene` names none, has every root node drawn, as the
//! importer reads it). A mesh used by n nodes is drawn n times and counts n times.

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use gltf::json;
use gltf::json::validation::Checked;
use serde::{Deserialize, Serialize};

use crate::accessor::{component_size, type_width};
use crate::error::{Result, SceneError};
use crate::gltf_source::GltfSource;
use crate::import::hierarchy::read_nodes;
use crate::import::meshes::triangulate;
use crate::input_file::{InputLimits, resolve_uri};
use crate::rig::world_matrices;

/// The cost of one file (see the module doc for what is drawn).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FileCost {
    /// Triangles drawn: TRIANGLES primitives give ⌊indices/3⌋ (⌊vertices/3⌋ without indices),
    /// strips and fans n − 2; points and lines give none. Degenerate triangles count.
    pub triangles: u64,
    /// Vertices drawn: the POSITION accessor's count of every drawn primitive.
    pub vertices: u64,
    /// Draw calls: one per primitive per mesh instance (points and lines included).
    pub draw_calls: u64,
    /// Distinct materials of the drawn primitives (a primitive without one uses glTF's default
    /// material, which counts as one more).
    pub materials: u64,
    /// Skins of the drawn mesh instances.
    pub skins: u64,
    /// Joints of the largest of those skins.
    pub joints_per_skin_max: u64,
    /// Distinct joint nodes over those skins.
    pub joints_total: u64,
    /// Most non-zero skin weights of any vertex of a drawn skinned primitive, over all its
    /// `WEIGHTS_n` sets (each set holds up to 4; 0 when nothing drawn is skinned).
    pub max_influences: u32,
    /// Animation channels over every animation of the file.
    pub animated_channels: u64,
    /// Keyframes: the key count (sampler input) of every channel, summed over channels.
    pub keyframes: u64,
    /// Bytes of the animation samplers' input and output accessors (count × element size,
    /// each accessor counted once however many samplers share it).
    pub keyframe_bytes: u64,
    /// Every image of the file, used or not.
    pub images: Vec<ImageCost>,
    /// Decoded bytes (RGBA8, no mips) of the images the drawn primitives' materials use.
    pub texture_decoded_bytes: u64,
    /// Encoded bytes of the same images, as stored.
    pub texture_encoded_bytes: u64,
    /// GPU-resident bytes of the same images, mips included ([`ImageCost::gpu_bytes`]).
    #[serde(default)]
    pub texture_gpu_bytes: u64,
    /// Bytes on disk: the file plus every external buffer and image it references (each
    /// distinct file once; `data:` URIs are inside the file already).
    pub file_bytes: u64,
    /// Summed rest-pose area (world units²) of the drawn triangles whose material's alphaMode
    /// is MASK or BLEND: the cards a renderer blends or alpha-tests, the overdraw measure
    /// (divide by the input tree's to get relative overdraw). Unskinned meshes are placed by
    /// their node's world matrix; skinned ones are taken as stored, which is their bind pose
    /// in practice (glTF ignores a skinned mesh node's own transform, and exporters write
    /// skinned positions in the space the inverse bind matrices expect).
    pub alpha_tested_area: f64,
    /// The same area for OPAQUE triangles (world units²).
    pub opaque_area: f64,
}

/// One image of a file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ImageCost {
    /// Index in the file's `images`.
    pub index: usize,
    /// Its `name`, if any.
    pub name: Option<String>,
    /// Its `mimeType`, or the format its bytes show (`image/png`, `image/jpeg`), if known.
    pub mime_type: Option<String>,
    /// Width in pixels from the image header; 0 for a format frond does not read (KTX2,
    /// WebP, ...).
    pub width: u32,
    /// Height in pixels from the image header; 0 likewise.
    pub height: u32,
    /// Bytes of the image as stored (buffer view, data URI payload or external file).
    pub encoded_bytes: u64,
    /// width × height × 4: the image decoded as RGBA8, without mips.
    pub decoded_bytes: u64,
    /// Mip levels stored in the file (KTX2); 1 for PNG and JPEG, whose mips the engine makes.
    #[serde(default)]
    pub levels: u32,
    /// Bytes it takes on the GPU, mips included: a KTX2 (UASTC) image transcoded to BC7 or
    /// ASTC 4×4 (16 bytes a 4×4 block, every stored level); PNG or JPEG decoded to RGBA8 with
    /// the full mip chain engines build (4/3 of level 0).
    #[serde(default)]
    pub gpu_bytes: u64,
    /// Whether a material of a drawn primitive uses it (only those count in the totals).
    pub used: bool,
    /// SHA-256 of its stored bytes, hex: images identical in bytes (a LOD's leaf map in every
    /// file of a chain) are one image to an engine that shares them. Empty in costs written
    /// before it.
    #[serde(default)]
    pub sha256: String,
}

/// The cost of the file at `path`, read within `limits`.
pub fn file_cost(path: &Path, limits: &InputLimits) -> Result<FileCost> {
    let src = GltfSource::open(path, limits)?;
    let own = std::fs::metadata(path)
        .map(|m| m.len())
        .map_err(|error| SceneError::Io {
            path: path.to_path_buf(),
            error,
        })?;
    cost_of(&src, own)
}

/// The cost of `bytes` as if read from `path` (which locates external files); `file_bytes`
/// counts `bytes.len()` for the file itself.
pub fn file_cost_bytes(path: &Path, bytes: &[u8], limits: &InputLimits) -> Result<FileCost> {
    let src = GltfSource::from_bytes(path, bytes, limits)?;
    cost_of(&src, bytes.len() as u64)
}

/// One drawn mesh instance: the mesh, the node's world matrix, its skin.
struct Instance {
    mesh: usize,
    world: Mat4,
    skin: Option<usize>,
}

fn cost_of(src: &GltfSource, own_bytes: u64) -> Result<FileCost> {
    let root = &src.root;
    let instances = drawn_instances(src)?;
    let mut cost = FileCost::default();
    let mut materials: BTreeSet<Option<usize>> = BTreeSet::new();
    let mut skins: BTreeSet<usize> = BTreeSet::new();
    // Vertices are checked against the limit from the declared counts first, as the importer
    // does: instancing multiplies the work.
    for inst in &instances {
        for (pi, p) in mesh_of(src, inst.mesh)?.primitives.iter().enumerate() {
            if let Some(acc) = position_accessor(p) {
                let count = accessor(src, acc, &prim_what(inst.mesh, pi))?.count.0;
                cost.vertices = cost.vertices.saturating_add(count);
            }
        }
    }
    if cost.vertices > src.limits.max_vertices {
        return Err(src.invalid(format!(
            "its drawn meshes have {} vertices, over the vertex limit of {} (raise the vertex limit to read it)",
            cost.vertices, src.limits.max_vertices
        )));
    }
    // Per primitive (mesh, index): its triangles (in local space) and largest influence count,
    // read once however often the mesh is instanced.
    let mut read: HashMap<(usize, usize), PrimitiveData> = HashMap::new();
    for inst in &instances {
        if let Some(s) = inst.skin {
            skins.insert(s);
        }
        for (pi, p) in mesh_of(src, inst.mesh)?.primitives.iter().enumerate() {
            let what = prim_what(inst.mesh, pi);
            let Some(pos_acc) = position_accessor(p) else {
                // glTF: a primitive without positions is not rendered.
                continue;
            };
            cost.draw_calls += 1;
            let material = p.material.map(|m| m.value());
            if let Some(m) = material
                && m >= root.materials.len()
            {
                return Err(src.invalid(format!("{what}: material {m} does not exist")));
            }
            materials.insert(material);
            let data = match read.entry((inst.mesh, pi)) {
                std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(read_primitive(src, p, pos_acc, &what)?)
                }
            };
            cost.triangles += data.triangles.len() as u64;
            if inst.skin.is_some() {
                cost.max_influences = cost.max_influences.max(data.influences);
            }
            let area = match inst.skin {
                Some(_) => data.area(&Mat4::IDENTITY),
                None => data.area(&inst.world),
            };
            if material.is_some_and(|m| alpha_tested(&root.materials[m])) {
                cost.alpha_tested_area += area;
            } else {
                cost.opaque_area += area;
            }
        }
    }
    cost.materials = materials.len() as u64;
    // Skins.
    let mut joints: HashSet<usize> = HashSet::new();
    for &s in &skins {
        let skin = root
            .skins
            .get(s)
            .ok_or_else(|| src.invalid(format!("skin {s} does not exist")))?;
        cost.joints_per_skin_max = cost.joints_per_skin_max.max(skin.joints.len() as u64);
        joints.extend(skin.joints.iter().map(|j| j.value()));
    }
    cost.skins = skins.len() as u64;
    cost.joints_total = joints.len() as u64;
    animation_cost(src, &mut cost)?;
    // Images: every one listed, those of the drawn materials counted.
    let used = used_images(src, materials.iter().flatten().copied())?;
    cost.images = (0..root.images.len())
        .map(|i| image_cost(src, i, used.contains(&i)))
        .collect::<Result<_>>()?;
    for img in cost.images.iter().filter(|i| i.used) {
        cost.texture_decoded_bytes += img.decoded_bytes;
        cost.texture_encoded_bytes += img.encoded_bytes;
        cost.texture_gpu_bytes += img.gpu_bytes;
    }
    cost.file_bytes = own_bytes.saturating_add(external_bytes(src)?);
    Ok(cost)
}

/// Names a primitive in errors.
fn prim_what(mesh: usize, primitive: usize) -> String {
    format!("mesh {mesh} primitive {primitive}")
}

fn mesh_of(src: &GltfSource, mesh: usize) -> Result<&json::Mesh> {
    src.root
        .meshes
        .get(mesh)
        .ok_or_else(|| src.invalid(format!("mesh {mesh} does not exist")))
}

fn accessor<'a>(src: &'a GltfSource, index: usize, what: &str) -> Result<&'a json::Accessor> {
    src.root
        .accessors
        .get(index)
        .ok_or_else(|| src.invalid(format!("{what}: accessor {index} does not exist")))
}

fn position_accessor(p: &json::mesh::Primitive) -> Option<usize> {
    p.attributes
        .get(&Checked::Valid(json::mesh::Semantic::Positions))
        .map(|a| a.value())
}

fn alpha_tested(m: &json::Material) -> bool {
    matches!(
        m.alpha_mode,
        Checked::Valid(json::material::AlphaMode::Mask | json::material::AlphaMode::Blend)
    )
}

/// The mesh instances of the default scene (see the module doc), with world matrices.
fn drawn_instances(src: &GltfSource) -> Result<Vec<Instance>> {
    let root = &src.root;
    // The importer's node reading: refuses cycles, multiple parents and absurd depths.
    let (nodes, order) = read_nodes(src)?;
    let rest: Vec<_> = nodes.iter().map(|n| n.rest).collect();
    let world = world_matrices(&nodes, &order, &rest);
    let scene = match root.scene.map(|s| s.value()) {
        Some(s) => root.scenes.get(s),
        None => root.scenes.first(),
    };
    let mut stack: Vec<usize> = match scene {
        Some(s) => s.nodes.iter().rev().map(|n| n.value()).collect(),
        None => (0..nodes.len())
            .rev()
            .filter(|&i| nodes[i].parent.is_none())
            .collect(),
    };
    let mut seen = vec![false; nodes.len()];
    let mut out = Vec::new();
    while let Some(i) = stack.pop() {
        // A scene root that does not exist, or one listed twice (or under another root), is
        // drawn once.
        if i >= nodes.len() || seen[i] {
            continue;
        }
        seen[i] = true;
        let jn = &root.nodes[i];
        if let Some(m) = jn.mesh {
            out.push(Instance {
                mesh: m.value(),
                world: world[i],
                skin: jn.skin.map(|s| s.value()),
            });
        }
        stack.extend(nodes[i].children.iter().rev().copied());
    }
    Ok(out)
}

/// What a primitive holds, read once: its triangles in its own space, and its vertices' largest
/// count of non-zero skin weights.
struct PrimitiveData {
    triangles: Vec<[Vec3; 3]>,
    influences: u32,
}

impl PrimitiveData {
    /// Summed area of the triangles placed by `m` (world units²).
    fn area(&self, m: &Mat4) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|p| m.transform_point3(p));
                f64::from(0.5 * (b - a).cross(c - a).length())
            })
            .sum()
    }
}

fn read_primitive(
    src: &GltfSource,
    p: &json::mesh::Primitive,
    pos_acc: usize,
    what: &str,
) -> Result<PrimitiveData> {
    use json::mesh::Mode;
    let mode = match p.mode {
        Checked::Valid(m) => m,
        Checked::Invalid => return Err(src.invalid(format!("{what}: invalid mode"))),
    };
    let pos = src.read_floats(pos_acc, &format!("{what} POSITION"))?;
    if pos.width != 3 {
        return Err(src.invalid(format!("{what}: POSITION must be VEC3")));
    }
    let n = pos.count();
    let mut triangles = Vec::new();
    if matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        let indices: Vec<u32> = match p.indices {
            Some(a) => {
                let (w, v) = src.read_ints(a.value(), &format!("{what} indices"))?;
                if w != 1 {
                    return Err(src.invalid(format!("{what}: indices must be SCALAR")));
                }
                v
            }
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(src.invalid(format!(
                "{what}: index {bad} is out of range ({n} vertices)"
            )));
        }
        triangles = triangulate(&indices, mode)
            .into_iter()
            .map(|t| t.map(|i| Vec3::from(pos.get::<3>(i as usize))))
            .collect();
    }
    // Non-zero weights per vertex over every WEIGHTS_n set.
    let mut nonzero = vec![0u32; n];
    for (sem, acc) in &p.attributes {
        let Checked::Valid(json::mesh::Semantic::Weights(set)) = sem else {
            continue;
        };
        let w = src.read_floats(acc.value(), &format!("{what} WEIGHTS_{set}"))?;
        if w.count() != n {
            return Err(src.invalid(format!(
                "{what}: WEIGHTS_{set} has {} elements, POSITION has {n}",
                w.count()
            )));
        }
        for (v, row) in nonzero
            .iter_mut()
            .zip(w.values.chunks_exact(w.width.max(1)))
        {
            *v += row.iter().filter(|x| **x != 0.0).count() as u32;
        }
    }
    Ok(PrimitiveData {
        triangles,
        influences: nonzero.into_iter().max().unwrap_or(0),
    })
}

/// Channels, keyframes and keyframe bytes of every animation.
fn animation_cost(src: &GltfSource, cost: &mut FileCost) -> Result<()> {
    let mut counted: HashSet<usize> = HashSet::new();
    for (ai, anim) in src.root.animations.iter().enumerate() {
        for (ci, ch) in anim.channels.iter().enumerate() {
            let what = format!("animation {ai} channel {ci}");
            let s = ch.sampler.value();
            let sampler = anim
                .samplers
                .get(s)
                .ok_or_else(|| src.invalid(format!("{what}: sampler {s} does not exist")))?;
            let input = sampler.input.value();
            cost.animated_channels += 1;
            cost.keyframes += accessor(src, input, &what)?.count.0;
        }
        for (si, sampler) in anim.samplers.iter().enumerate() {
            let what = format!("animation {ai} sampler {si}");
            for acc in [sampler.input.value(), sampler.output.value()] {
                if counted.insert(acc) {
                    cost.keyframe_bytes += accessor_bytes(src, acc, &what)?;
                }
            }
        }
    }
    Ok(())
}

/// count × element size of accessor `index` (tightly packed: strides are layout, not data).
fn accessor_bytes(src: &GltfSource, index: usize, what: &str) -> Result<u64> {
    let acc = accessor(src, index, what)?;
    let (Checked::Valid(comp), Checked::Valid(ty)) = (acc.component_type, acc.type_) else {
        return Err(src.invalid(format!(
            "{what}: accessor {index} has an invalid componentType or type"
        )));
    };
    let elem = (component_size(comp.0) * type_width(ty)) as u64;
    Ok(acc.count.0.saturating_mul(elem))
}

/// Images of the textures that materials `used` reference (base colour, metallic-roughness,
/// normal, occlusion, emissive; textures named only by material extensions are not followed).
fn used_images(src: &GltfSource, used: impl Iterator<Item = usize>) -> Result<BTreeSet<usize>> {
    let root = &src.root;
    let mut out = BTreeSet::new();
    for m in used {
        let mat = &root.materials[m];
        let pbr = &mat.pbr_metallic_roughness;
        let textures = [
            pbr.base_color_texture.as_ref().map(|t| t.index.value()),
            pbr.metallic_roughness_texture
                .as_ref()
                .map(|t| t.index.value()),
            mat.normal_texture.as_ref().map(|t| t.index.value()),
            mat.occlusion_texture.as_ref().map(|t| t.index.value()),
            mat.emissive_texture.as_ref().map(|t| t.index.value()),
        ];
        for t in textures.into_iter().flatten() {
            if t >= root.textures.len() {
                return Err(src.invalid(format!("material {m}: texture {t} does not exist")));
            }
            let img = crate::import::materials::texture_image(src, t, true);
            if img >= root.images.len() {
                return Err(src.invalid(format!("texture {t}: image {img} does not exist")));
            }
            out.insert(img);
        }
    }
    Ok(out)
}

/// Image `index`: its stored bytes and, for PNG and JPEG, its header's size.
fn image_cost(src: &GltfSource, index: usize, used: bool) -> Result<ImageCost> {
    let image = &src.root.images[index];
    let bytes = src.image_bytes(index)?;
    let guessed = image::guess_format(&bytes).ok();
    let (width, height) = match guessed {
        Some(format @ (image::ImageFormat::Png | image::ImageFormat::Jpeg)) => {
            image::ImageReader::with_format(std::io::Cursor::new(&bytes), format)
                .into_dimensions()
                .map_err(|e| src.invalid(format!("image {index}: cannot read its header ({e})")))?
        }
        _ => (0, 0),
    };
    let ktx2 = crate::ktx2::read_info(&bytes).ok();
    let (width, height, levels) = match ktx2 {
        Some(k) => (k.width, k.height, k.levels),
        None => (width, height, 1),
    };
    let gpu_bytes = match ktx2 {
        Some(k) => crate::ktx2::gpu_bytes(k.width, k.height, k.levels),
        None => rgba8_mip_bytes(width, height),
    };
    let mime_type = image
        .mime_type
        .as_ref()
        .map(|m| m.0.clone())
        .or_else(|| guessed.map(|f| f.to_mime_type().to_string()));
    Ok(ImageCost {
        index,
        name: image.name.clone(),
        mime_type,
        width,
        height,
        encoded_bytes: bytes.len() as u64,
        decoded_bytes: u64::from(width)
            .saturating_mul(u64::from(height))
            .saturating_mul(4),
        levels,
        gpu_bytes,
        used,
        sha256: sha256_hex(&bytes),
    })
}

/// The SHA-256 of `bytes` in lowercase hex.
fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    use std::fmt::Write;
    let digest = Sha256::digest(bytes);
    let mut hex = String::with_capacity(2 * digest.len());
    for b in digest {
        // Writing to a String cannot fail.
        let _ = write!(hex, "{b:02x}");
    }
    hex
}

/// RGBA8 bytes of a `width`×`height` image with its full mip chain.
fn rgba8_mip_bytes(width: u32, height: u32) -> u64 {
    if width == 0 || height == 0 {
        return 0;
    }
    let levels = 32 - width.max(height).leading_zeros();
    // Saturating: a header may declare 2³² - 1 texels a side.
    (0..levels)
        .map(|l| {
            u64::from((width >> l).max(1))
                .saturating_mul(u64::from((height >> l).max(1)))
                .saturating_mul(4)
        })
        .fold(0u64, u64::saturating_add)
}

/// Bytes of the distinct external files (buffers and images) the document references.
fn external_bytes(src: &GltfSource) -> Result<u64> {
    let root = &src.root;
    let mut files: HashMap<PathBuf, u64> = HashMap::new();
    let buffer_uris = root
        .buffers
        .iter()
        .enumerate()
        .filter_map(|(i, b)| b.uri.as_deref().map(|u| (format!("buffer {i}"), u)));
    let image_uris = root
        .images
        .iter()
        .enumerate()
        .filter(|(_, im)| im.buffer_view.is_none())
        .filter_map(|(i, im)| im.uri.as_deref().map(|u| (format!("image {i}"), u)));
    for (what, uri) in buffer_uris.chain(image_uris) {
        if uri.starts_with("data:") {
            continue;
        }
        let full = resolve_uri(&src.dir, uri)
            .map_err(|why| src.invalid(format!("{what}: external URI '{uri}' {why}")))?;
        if files.contains_key(&full) {
            continue;
        }
        let len = std::fs::metadata(&full).map(|m| m.len()).map_err(|e| {
            src.invalid(format!("{what}: '{}' cannot be read ({e})", full.display()))
        })?;
        files.insert(full, len);
    }
    Ok(files.values().sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generator::{Preset, generate};
    use crate::gltf_writer::*;
    use serde_json::{Value, json};

    fn cost(glb: &[u8]) -> FileCost {
        file_cost_bytes(Path::new("case.glb"), glb, &InputLimits::default()).expect("costs")
    }

    /// `glb` with its JSON edited by `edit`.
    fn edit_json(glb: &[u8], edit: impl FnOnce(&mut Value)) -> Vec<u8> {
        let g = gltf::binary::Glb::from_slice(glb).expect("GLB");
        let mut v: Value = serde_json::from_slice(&g.json).expect("JSON");
        edit(&mut v);
        let bin = g.bin.map(|b| b.into_owned()).unwrap_or_default();
        glb_container(&serde_json::to_vec(&v).expect("JSON"), &bin)
    }

    fn material(doc: &mut GltfBuilder, alpha: WriteAlpha, texture: Option<usize>) -> usize {
        doc.add_material(&MaterialDesc {
            name: "m".into(),
            base_color: [1.0; 4],
            base_color_texture: texture,
            normal_texture: None,
            alpha,
            double_sided: false,
            metallic: 0.0,
            roughness: 1.0,
        })
    }

    /// A 1×1 square in the xy plane as two triangles.
    fn square(material: Option<usize>) -> PrimitiveDesc {
        PrimitiveDesc {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            material,
            ..Default::default()
        }
    }

    fn node(doc: &mut GltfBuilder, mesh: Option<usize>, skin: Option<usize>) -> usize {
        doc.add_node(NodeDesc {
            name: "n".into(),
            mesh,
            skin,
            ..Default::default()
        })
    }

    #[test]
    fn the_generated_tree_costs_what_it_was_built_with() {
        let g = generate(Preset::Small, 3).expect("generate");
        let c = cost(&g.glb);
        let leaves = g.leaf_corners.len() as u64;
        assert_eq!(c.triangles, g.wood_triangles as u64 + 2 * leaves);
        // Read back by the importer: one instance per mesh, so its vertices are the file's.
        let tree = crate::import_bytes(
            Path::new("small.glb"),
            &g.glb,
            &crate::ImportOptions::default(),
        )
        .expect("import");
        assert_eq!(c.vertices, tree.vertices.position.len() as u64);
        // Two primitives (wood, leaves), two materials (bark, leaves).
        assert_eq!((c.draw_calls, c.materials), (2, 2));
        // One skin over every bone; wood vertices between two rings blend two bones.
        let bones = g.bones.len() as u64;
        assert_eq!(
            (c.skins, c.joints_per_skin_max, c.joints_total),
            (1, bones, bones)
        );
        assert_eq!(c.max_influences, 2);
        // One rotation channel per bone, all sharing one key-time accessor.
        let keys = g.key_times.len() as u64;
        assert_eq!(c.animated_channels, bones);
        assert_eq!(c.keyframes, bones * keys);
        assert_eq!(c.keyframe_bytes, keys * 4 + bones * keys * 16);
        // Bark 64², leaf 128², both used.
        let sizes: Vec<_> = c
            .images
            .iter()
            .map(|i| (i.width, i.height, i.used))
            .collect();
        assert_eq!(sizes, [(64, 64, true), (128, 128, true)]);
        assert_eq!(c.texture_decoded_bytes, (64 * 64 + 128 * 128) * 4);
        assert_eq!(
            c.images[0].mime_type.as_deref(),
            Some("image/png"),
            "{:?}",
            c.images[0]
        );
        let encoded: u64 = c.images.iter().map(|i| i.encoded_bytes).sum();
        assert_eq!(c.texture_encoded_bytes, encoded);
        // PNGs are a few hundred bytes to a few KB, inside the GLB.
        assert!(encoded > 100 && encoded < g.glb.len() as u64, "{encoded}");
        assert_eq!(c.file_bytes, g.glb.len() as u64);
        // The leaves (MASK) are the generator's rectangles; the wood is opaque.
        let want = g.leaf_card_area();
        assert!(
            (c.alpha_tested_area - want).abs() < 1e-3 * want,
            "{} vs {want}",
            c.alpha_tested_area
        );
        assert!(c.opaque_area > 0.0);
        // The JSON form reads back equal (areas to the last bit or so: serde_json's float
        // parsing is not exactly round-trip).
        let text = serde_json::to_string(&c).expect("serialise");
        assert!(text.contains("\"texture_decoded_bytes\""), "{text}");
        let back: FileCost = serde_json::from_str(&text).expect("read back");
        assert!((back.alpha_tested_area - c.alpha_tested_area).abs() < 1e-9 * want);
        let back = FileCost {
            alpha_tested_area: c.alpha_tested_area,
            opaque_area: c.opaque_area,
            ..back
        };
        assert_eq!(back, c);
    }

    #[test]
    fn instances_count_once_per_node_of_the_scene_and_are_placed_by_their_node() {
        let mut doc = GltfBuilder::new("test");
        let m = material(&mut doc, WriteAlpha::Opaque, None);
        let mesh = doc.add_mesh("square", &[square(Some(m))]);
        let a = node(&mut doc, Some(mesh), None);
        let parent = doc.add_node(NodeDesc {
            name: "parent".into(),
            scale: Some([2.0, 1.0, 1.0]),
            ..Default::default()
        });
        let b = doc.add_node(NodeDesc {
            name: "b".into(),
            mesh: Some(mesh),
            scale: Some([1.0, 3.0, 1.0]),
            ..Default::default()
        });
        doc.add_child(parent, b);
        doc.add_root(a);
        doc.add_root(parent);
        // A third instance outside the scene is not drawn.
        node(&mut doc, Some(mesh), None);
        let c = cost(&doc.to_glb());
        assert_eq!((c.triangles, c.vertices, c.draw_calls), (4, 8, 2));
        assert_eq!(c.materials, 1);
        // 1 + (2 × 3) world units².
        assert!((c.opaque_area - 7.0).abs() < 1e-6, "{}", c.opaque_area);
        assert_eq!(c.alpha_tested_area, 0.0);
        assert_eq!((c.skins, c.max_influences, c.animated_channels), (0, 0, 0));
    }

    #[test]
    fn strips_and_fans_are_triangulated_and_points_draw_no_triangle() {
        let mut doc = GltfBuilder::new("test");
        let m = material(&mut doc, WriteAlpha::Blend, None);
        let zigzag = PrimitiveDesc {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
            ],
            indices: vec![0, 1, 2, 3],
            material: Some(m),
            ..Default::default()
        };
        let fan = PrimitiveDesc {
            indices: vec![0, 1, 2, 3],
            ..square(Some(m))
        };
        let points = PrimitiveDesc {
            indices: vec![0, 1, 2, 3],
            ..square(None)
        };
        let mesh = doc.add_mesh("modes", &[zigzag, fan, points]);
        let n = node(&mut doc, Some(mesh), None);
        doc.add_root(n);
        let glb = edit_json(&doc.to_glb(), |v| {
            let prims = &mut v["meshes"][0]["primitives"];
            prims[0]["mode"] = json!(5);
            prims[1]["mode"] = json!(6);
            prims[2]["mode"] = json!(0);
        });
        let c = cost(&glb);
        // Strip of 4: 2 triangles; fan of 4: 2; points: 0. Three draws, 12 vertices.
        assert_eq!((c.triangles, c.draw_calls, c.vertices), (4, 3, 12));
        // Blended: both unit squares are alpha-tested area; the default material is one more.
        assert!(
            (c.alpha_tested_area - 2.0).abs() < 1e-6,
            "{}",
            c.alpha_tested_area
        );
        assert_eq!(c.opaque_area, 0.0);
        assert_eq!(c.materials, 2);
    }

    #[test]
    fn skins_count_joints_once_and_influences_that_are_not_zero() {
        let mut doc = GltfBuilder::new("test");
        let joints: Vec<usize> = (0..4).map(|_| node(&mut doc, None, None)).collect();
        for &j in &joints {
            doc.add_root(j);
        }
        let skin_a = doc.add_skin("a", &joints[..2], &[Mat4::IDENTITY; 2], None);
        let skin_b = doc.add_skin("b", &joints[1..], &[Mat4::IDENTITY; 3], None);
        // A third skin no drawn node uses.
        doc.add_skin("unused", &joints[..1], &[Mat4::IDENTITY], None);
        let prim = PrimitiveDesc {
            joints: Some(vec![[0, 1, 0, 0], [0, 0, 0, 0], [0, 1, 2, 0], [0, 0, 0, 0]]),
            weights: Some(vec![
                [0.5, 0.5, 0.0, 0.0],
                [1.0, 0.0, 0.0, 0.0],
                [0.2, 0.3, 0.5, 0.0],
                [1.0, 0.0, 0.0, 0.0],
            ]),
            ..square(None)
        };
        let mesh = doc.add_mesh("skinned", &[prim]);
        for skin in [skin_a, skin_b] {
            let n = doc.add_node(NodeDesc {
                name: "skinned".into(),
                mesh: Some(mesh),
                skin: Some(skin),
                // Ignored for skinned meshes: their positions are the bind pose.
                scale: Some([5.0; 3]),
                ..Default::default()
            });
            doc.add_root(n);
        }
        let glb = doc.to_glb();
        let c = cost(&glb);
        assert_eq!((c.skins, c.joints_per_skin_max, c.joints_total), (2, 3, 4));
        assert_eq!(c.max_influences, 3);
        assert!((c.opaque_area - 2.0).abs() < 1e-6, "{}", c.opaque_area);
        // A second influence set (here the first one again) adds its non-zero weights.
        let glb = edit_json(&glb, |v| {
            let attrs = &mut v["meshes"][0]["primitives"][0]["attributes"];
            attrs["JOINTS_1"] = attrs["JOINTS_0"].clone();
            attrs["WEIGHTS_1"] = attrs["WEIGHTS_0"].clone();
        });
        assert_eq!(cost(&glb).max_influences, 6);
    }

    #[test]
    fn keyframe_bytes_count_each_accessor_once() {
        let mut doc = GltfBuilder::new("test");
        let mesh = doc.add_mesh("square", &[square(None)]);
        let n = node(&mut doc, Some(mesh), None);
        doc.add_root(n);
        let times = vec![0.0, 0.5, 1.0];
        let channel = |path, values: Vec<f32>, times: &Vec<f32>| ChannelDesc {
            node: n,
            path,
            times: times.clone(),
            values,
            interpolation: WriteInterpolation::Linear,
        };
        // Rotation and translation share the time accessor: 3·4 + 3·16 + 3·12 bytes.
        doc.add_animation(
            "sway",
            &[
                channel(
                    ChannelPath::Rotation,
                    [0.0, 0.0, 0.0, 1.0].repeat(3),
                    &times,
                ),
                channel(ChannelPath::Translation, vec![0.0; 9], &times),
            ],
        );
        // A second clip of two scale keys: 2·4 + 2·12 bytes.
        doc.add_animation(
            "grow",
            &[channel(ChannelPath::Scale, vec![1.0; 6], &vec![0.0, 2.0])],
        );
        let c = cost(&doc.to_glb());
        assert_eq!(c.animated_channels, 3);
        assert_eq!(c.keyframes, 3 + 3 + 2);
        assert_eq!(c.keyframe_bytes, 12 + 48 + 36 + 8 + 24);
    }

    #[test]
    fn external_buffers_and_images_count_in_file_bytes_once_each() {
        let dir = tempfile::tempdir().expect("tmp");
        let png = encode_png(8, 4, &[200u8; 8 * 4 * 4]).expect("png");
        std::fs::write(dir.path().join("leaf.png"), &png).expect("write");
        let ktx = vec![0xABu8; 300];
        std::fs::write(dir.path().join("bark.ktx2"), &ktx).expect("write");
        let mut doc = GltfBuilder::new("test");
        let leaf = doc.add_texture_uri("leaf", "leaf.png", true);
        // The same file again, as a texture no drawn material uses.
        doc.add_texture_uri("leaf again", "./leaf.png", true);
        doc.add_texture_uri("bark", "bark.ktx2", false);
        let m = material(&mut doc, WriteAlpha::Mask(0.5), Some(leaf));
        let mesh = doc.add_mesh("card", &[square(Some(m))]);
        let n = node(&mut doc, Some(mesh), None);
        doc.add_root(n);
        // Split the GLB into a .gltf, its .bin and the images beside it.
        let glb = doc.to_glb();
        let g = gltf::binary::Glb::from_slice(&glb).expect("GLB");
        let bin = g.bin.expect("binary chunk").into_owned();
        let mut v: Value = serde_json::from_slice(&g.json).expect("JSON");
        v["buffers"][0]["uri"] = json!("card.bin");
        v["images"][2]["mimeType"] = json!("image/ktx2");
        let text = serde_json::to_vec(&v).expect("JSON");
        std::fs::write(dir.path().join("card.bin"), &bin).expect("write");
        let path = dir.path().join("card.gltf");
        std::fs::write(&path, &text).expect("write");
        let c = file_cost(&path, &InputLimits::default()).expect("costs");
        assert_eq!(
            c.file_bytes,
            (text.len() + bin.len() + png.len() + ktx.len()) as u64
        );
        let got: Vec<_> = c
            .images
            .iter()
            .map(|i| (i.width, i.height, i.encoded_bytes, i.used))
            .collect();
        let p = png.len() as u64;
        assert_eq!(got, [(8, 4, p, true), (8, 4, p, false), (0, 0, 300, false)]);
        assert_eq!(c.images[2].mime_type.as_deref(), Some("image/ktx2"));
        assert_eq!(c.texture_decoded_bytes, 8 * 4 * 4);
        assert_eq!(c.texture_encoded_bytes, p);
        assert!((c.alpha_tested_area - 1.0).abs() < 1e-6);
        // A missing image is an error naming the file and the image.
        std::fs::remove_file(dir.path().join("bark.ktx2")).expect("remove");
        let err = file_cost(&path, &InputLimits::default())
            .expect_err("missing image")
            .to_string();
        assert!(
            err.contains("card.gltf") && err.contains("image 2") && err.contains("bark.ktx2"),
            "{err}"
        );
    }

    #[test]
    fn a_file_that_is_not_gltf_is_refused_by_name() {
        let err = file_cost_bytes(Path::new("notes.glb"), b"hello", &InputLimits::default())
            .expect_err("not glTF")
            .to_string();
        assert!(err.starts_with("notes.glb: not a glTF file"), "{err}");
    }
}
