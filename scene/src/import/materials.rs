//! Materials: what billboards need of each (base colour, alpha, sides), the input's own JSON
//! with its texture maps renumbered, and which images the base colour and normal maps show.

use glam::Vec2;
use gltf::json;
use gltf::json::validation::Checked;

use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::model::{
    AlphaMode, MAX_TEXCOORD_SETS, Material, MaterialSource, Wrap, visit_texture_infos,
};

/// A material's base colour map: (input image index, texture coordinate set, uv transform from
/// `KHR_texture_transform`).
pub(super) type BaseColorMap = (usize, u32, glam::Affine2);

/// What [`read_materials`] found.
pub(super) struct MaterialInfo {
    /// The materials in input order, their texture fields still unset (the importer sets them
    /// once the textures are decoded).
    pub(super) materials: Vec<Material>,
    /// Per material: (input image index, texcoord set, uv transform) of its base colour.
    pub(super) base: Vec<Option<BaseColorMap>>,
    /// Per material: the input image of its normal map, when that samples the base colour's
    /// coordinates (see [`Material::normal_texture`]).
    pub(super) normal: Vec<Option<usize>>,
    /// The input texture index of every [`Tree::source_textures`](crate::Tree::source_textures) entry, in that order.
    pub(super) textures: Vec<usize>,
    /// How many texture coordinate sets the maps use (1 ..= [`MAX_TEXCOORD_SETS`]).
    pub(super) texcoord_sets: usize,
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
pub(super) fn read_materials(src: &GltfSource, warnings: &mut Vec<String>) -> Result<MaterialInfo> {
    let mut mats = Vec::new();
    let mut texinfo = Vec::new();
    let mut normals = Vec::new();
    let mut slots = MapSlots {
        textures: Vec::new(),
        texcoord_sets: 1,
    };
    for (i, m) in src.root.materials.iter().enumerate() {
        let pbr = &m.pbr_metallic_roughness;
        let (tex, base_color_wrap) = base_color_map(src, i, pbr)?;
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
        slots.renumber_maps(src, i, m, &mut json, warnings)?;
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
        let normal = applied_normal_map(src, i, m, tex);
        texinfo.push(tex);
        normals.push(normal);
    }
    Ok(MaterialInfo {
        materials: mats,
        base: texinfo,
        normal: normals,
        textures: slots.textures,
        texcoord_sets: slots.texcoord_sets,
    })
}

/// Material `i`'s base colour map, if it has one: (input image, texture coordinate set, uv
/// transform from `KHR_texture_transform`), with the wrap modes of its sampler (repeat
/// without one).
///
/// Refused: a map naming a texture that does not exist, or whose texture names no image.
fn base_color_map(
    src: &GltfSource,
    i: usize,
    pbr: &json::material::PbrMetallicRoughness,
) -> Result<(Option<BaseColorMap>, [Wrap; 2])> {
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
    Ok((tex, base_color_wrap))
}

/// The input textures the materials' maps name, in the order
/// [`Tree::source_textures`](crate::Tree::source_textures) lists them, and the texture
/// coordinate sets the maps use.
struct MapSlots {
    /// The input texture index of each slot, in first-use order.
    textures: Vec<usize>,
    /// How many texture coordinate sets the maps use (at least 1).
    texcoord_sets: usize,
}

impl MapSlots {
    /// Renumbers every texture map of material `i` (`m`; its JSON `json`) to its texture's slot,
    /// giving a texture its slot on first use, and counts the coordinate set each map samples.
    /// A map sampling a set past what frond carries is rewritten to sample `TEXCOORD_0`, with
    /// a warning.
    ///
    /// Refused: a map without a valid texture index, naming a texture that does not exist, or
    /// whose texture names a missing image or sampler.
    fn renumber_maps(
        &mut self,
        src: &GltfSource,
        i: usize,
        m: &json::Material,
        json: &mut serde_json::Value,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        let textures = &mut self.textures;
        let texcoord_sets = &mut self.texcoord_sets;
        visit_texture_infos(json, &mut |key, info| {
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
                *texcoord_sets = (*texcoord_sets).max(set as usize + 1);
            }
            Ok(())
        })
    }
}

/// Material `i`'s normal map (`m`'s input image), when it samples what
/// [`Vertices::uv`](crate::Vertices::uv) holds: the base colour map `tex`'s coordinate set,
/// untransformed on both. Otherwise the two maps' coordinates differ and the normal map is not
/// applied.
fn applied_normal_map(
    src: &GltfSource,
    i: usize,
    m: &json::Material,
    tex: Option<BaseColorMap>,
) -> Option<usize> {
    m.normal_texture.as_ref().and_then(|n| {
        let same_set = tex.map_or(0, |t| t.1) == n.tex_coord;
        let untransformed = tex.is_none_or(|t| t.2 == glam::Affine2::IDENTITY)
            && src.raw.materials.get(i).is_none_or(|j| {
                j.pointer("/normalTexture/extensions/KHR_texture_transform")
                    .is_none()
            });
        let image = texture_image(src, n.index.value(), false);
        (same_set && untransformed && image < src.root.images.len()).then_some(image)
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
