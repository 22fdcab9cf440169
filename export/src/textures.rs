//! Where written textures go: embedded in the GLB, or files next to it
//! (`--external-textures`), and the tree's materials written once per document.
//!
//! The tree's own materials are written as the input described them ([`MaterialSource`]):
//! every map, factor, extension and extra, their textures' samplers, and their images' original
//! bytes and MIME type (a JPEG stays the same JPEG), so LOD0 looks like the input. Only what
//! frond makes (billboard atlases, downscaled maps) is encoded: as PNG, or as KTX2 with its
//! own mip chain ([`crate::ktx2_texture`], `--textures`).

use std::collections::HashMap;

use frond_scene::gltf_writer::{GltfBuilder, MaterialDesc, WriteAlpha, encode_png};
use frond_scene::{AlphaMode, MaterialSource, visit_texture_infos};

use frond_lod::texture_budget::{ImageSizes, material_images};

use frond_scene::import::KTX2_MIME;

use crate::downscale::Downscaler;
use crate::error::ExportError;
use crate::ktx2_texture::{MapKind, TextureFormat, ktx2_bytes};

/// A tree material as written into one LOD: its index and the sizes of those of its images
/// that LOD downscales.
type MaterialKey = (usize, Vec<(usize, [u32; 2])>);

/// A texture's document images: its core `source`, its `KHR_texture_basisu` KTX2 image, or
/// both (the PNG then the fallback).
#[derive(Clone, Copy)]
enum Images {
    Core(usize),
    Ktx2(usize),
    Both { core: usize, ktx2: usize },
}

/// Collects textures and materials of one document.
pub struct TextureSink {
    /// File-name prefix of external images (None: embed).
    external: Option<String>,
    /// How the textures frond makes are stored.
    format: TextureFormat,
    /// External image files to write next to the glTF: (file name, bytes).
    pub files: Vec<(String, Vec<u8>)>,
    /// Decoded tree texture → document texture (materials without a source).
    tree_textures: HashMap<usize, usize>,
    /// (`Tree::source_textures` entry, size written) → document texture.
    source_textures: HashMap<(usize, Option<[u32; 2]>), usize>,
    /// (`Tree::images` entry, size written) → document images (core source, KTX2).
    source_images: HashMap<(usize, Option<[u32; 2]>), Images>,
    /// (tree material, sizes of its images) → document material.
    tree_materials: HashMap<MaterialKey, usize>,
}

impl TextureSink {
    /// Embedded textures, or external files named `<prefix><texture>.<png, jpg, ...>` when
    /// `external`; the textures frond makes stored as `format` says.
    pub fn new(external: Option<String>, format: TextureFormat) -> Self {
        TextureSink {
            external,
            format,
            files: Vec::new(),
            tree_textures: HashMap::new(),
            source_textures: HashMap::new(),
            source_images: HashMap::new(),
            tree_materials: HashMap::new(),
        }
    }

    /// The file name for external image bytes `bytes` named `stem` with extension `ext`
    /// (`<prefix><stem>.<ext>`, numbered when another file took that name with other bytes),
    /// queued in [`TextureSink::files`] once.
    fn external_file(&mut self, prefix: &str, stem: &str, ext: &str, bytes: &[u8]) -> String {
        let stem = sanitize(stem);
        let mut file = format!("{prefix}{stem}.{ext}");
        let mut k = 1;
        while self.files.iter().any(|(f, b)| *f == file && b != bytes) {
            file = format!("{prefix}{stem}_{k}.{ext}");
            k += 1;
        }
        if !self.files.iter().any(|(f, _)| *f == file) {
            self.files.push((file.clone(), bytes.to_vec()));
        }
        file
    }

    /// An image of encoded `bytes`, embedded or written next to the glTF as `<stem>.<ext>`.
    fn place_image(
        &mut self,
        doc: &mut GltfBuilder,
        name: Option<&str>,
        stem: &str,
        bytes: &[u8],
        mime: &str,
        ext: &str,
    ) -> usize {
        match self.external.clone() {
            None => doc.add_image(name, bytes, mime),
            Some(prefix) => {
                // Same name, other pixels: the file is numbered.
                let file = self.external_file(&prefix, stem, ext, bytes);
                doc.add_image_uri(name, &file, mime)
            }
        }
    }

    /// The image(s) of an RGBA8 map frond made, as [`TextureFormat`] says: `(core source,
    /// KTX2 image)`, the core source None for KTX2 alone.
    fn made_images(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        image: &image::RgbaImage,
        kind: MapKind,
    ) -> Result<Images, ExportError> {
        let png = || {
            encode_png(image.width(), image.height(), image.as_raw()).map_err(|source| {
                ExportError::Image {
                    name: name.to_string(),
                    source,
                }
            })
        };
        let ktx2 = |this: &mut Self, doc: &mut GltfBuilder| {
            let bytes = ktx2_bytes(name, image.width(), image.height(), image.as_raw(), kind)?;
            Ok::<_, ExportError>(this.place_image(doc, Some(name), name, &bytes, KTX2_MIME, "ktx2"))
        };
        if self.format == TextureFormat::Ktx2 {
            return Ok(Images::Ktx2(ktx2(self, doc)?));
        }
        let bytes = png()?;
        let core = self.place_image(doc, Some(name), name, &bytes, "image/png", "png");
        Ok(match self.format {
            TextureFormat::Ktx2Png => Images::Both {
                core,
                ktx2: ktx2(self, doc)?,
            },
            _ => Images::Core(core),
        })
    }

    /// A texture of `images` with `sampler` and the further JSON members `fields`.
    fn texture_of(
        doc: &mut GltfBuilder,
        images: Images,
        sampler: Option<usize>,
        fields: serde_json::Value,
    ) -> usize {
        let (first, ktx2, keep_source) = match images {
            Images::Core(c) => (c, None, true),
            Images::Ktx2(k) => (k, Some(k), false),
            Images::Both { core, ktx2 } => (core, Some(ktx2), true),
        };
        let id = doc.add_texture_of(first, sampler, fields);
        if let Some(k) = ktx2 {
            doc.set_basisu_source(id, k, keep_source);
        }
        id
    }

    /// Adds an RGBA8 colour image frond made as a texture (clamped when `clamp`).
    pub fn add_rgba(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        width: u32,
        height: u32,
        rgba: &[u8],
        clamp: bool,
    ) -> Result<usize, ExportError> {
        self.add_map(doc, name, width, height, rgba, clamp, MapKind::Colour)
    }

    /// Adds an RGBA8 map frond made as a texture of `kind` (clamped when `clamp`).
    #[expect(
        clippy::too_many_arguments,
        reason = "an image (name, size, texels) and how it is sampled and encoded"
    )]
    fn add_map(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        width: u32,
        height: u32,
        rgba: &[u8],
        clamp: bool,
        kind: MapKind,
    ) -> Result<usize, ExportError> {
        let image = image::RgbaImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
            ExportError::Ktx2(format!(
                "{name}: {width}×{height} with {} bytes",
                rgba.len()
            ))
        })?;
        let images = self.made_images(doc, name, &image, kind)?;
        let wrap = if clamp { 33071 } else { 10497 };
        let sampler = doc.add_sampler(
            serde_json::json!({ "magFilter": 9729, "minFilter": 9987, "wrapS": wrap, "wrapT": wrap }),
        );
        Ok(Self::texture_of(
            doc,
            images,
            Some(sampler),
            serde_json::json!({ "name": name }),
        ))
    }

    /// The billboards' material: the colour atlas, alpha-tested at 0.5 (or blended, its
    /// alpha the covered fraction, where the atlas is [`blended`](frond_billboard::Atlas::blended)),
    /// double-sided, rough; with `normals`, the baked normal atlas at half its side as the
    /// `normalTexture`.
    pub fn billboard_material(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        atlas: &frond_billboard::Atlas,
        normals: bool,
    ) -> Result<usize, ExportError> {
        let tex = self.add_map(
            doc,
            &format!("{name}_atlas"),
            atlas.width,
            atlas.height,
            &atlas.color,
            true,
            if atlas.blended {
                MapKind::Covered
            } else {
                MapKind::Colour
            },
        )?;
        let normal = if normals {
            let (w, h, rgba) = half_normal_map(atlas.width, atlas.height, &atlas.normal);
            Some(self.add_map(
                doc,
                &format!("{name}_atlas_normal"),
                w,
                h,
                &rgba,
                true,
                MapKind::Linear,
            )?)
        } else {
            None
        };
        Ok(doc.add_material(&MaterialDesc {
            name: format!("{name}_billboards"),
            base_color: [1.0; 4],
            base_color_texture: Some(tex),
            normal_texture: normal,
            alpha: if atlas.blended {
                WriteAlpha::Blend
            } else {
                WriteAlpha::Mask(0.5)
            },
            double_sided: true,
            metallic: 0.0,
            roughness: 1.0,
        }))
    }

    /// The document texture for `Tree::source_textures[t]`: its original image bytes and MIME
    /// type (embedded, or a file with the type's extension), its sampler and its name/extras
    /// as the input had them. Written once per document.
    fn source_texture(
        &mut self,
        doc: &mut GltfBuilder,
        images: &Downscaler,
        t: usize,
        sizes: &ImageSizes,
        cutoff: Option<f32>,
        kind: MapKind,
    ) -> Result<usize, ExportError> {
        let tree = images.tree();
        let texture = tree
            .source_textures
            .get(t)
            .ok_or(ExportError::NoTexture(t))?;
        let size = sizes.get(&texture.image).copied();
        if let Some(&id) = self.source_textures.get(&(t, size)) {
            return Ok(id);
        }
        let ids = match self.source_images.get(&(texture.image, size)) {
            Some(&ids) => ids,
            None => {
                let img = tree
                    .images
                    .get(texture.image)
                    .ok_or(ExportError::NoTexture(t))?;
                let ids = match size {
                    // A downscaled image is frond's own: PNG or KTX2 as asked.
                    Some(s) if self.format != TextureFormat::Png => {
                        let small = images.rgba(texture.image, s, cutoff)?;
                        let stem = img
                            .name
                            .clone()
                            .unwrap_or_else(|| format!("image{}", texture.image));
                        let name = format!("{stem}_{}x{}", s[0], s[1]);
                        self.made_images(doc, &name, &small, kind)?
                    }
                    _ => {
                        // The input's image is written as it was.
                        let (bytes, mime, ext, suffix) = match size {
                            Some(s) => (
                                images.png(texture.image, s, cutoff)?,
                                "image/png".to_string(),
                                "png",
                                format!("_{}x{}", s[0], s[1]),
                            ),
                            None => (
                                img.bytes.clone(),
                                img.mime_type.clone(),
                                img.extension(),
                                String::new(),
                            ),
                        };
                        let name = img.name.as_ref().map(|n| format!("{n}{suffix}"));
                        let stem = name
                            .clone()
                            .unwrap_or_else(|| format!("image{}{suffix}", texture.image));
                        let id = self.place_image(doc, name.as_deref(), &stem, &bytes, &mime, ext);
                        // An input KTX2 image stays KTX2, through the extension.
                        if mime == KTX2_MIME {
                            Images::Ktx2(id)
                        } else {
                            Images::Core(id)
                        }
                    }
                };
                self.source_images.insert((texture.image, size), ids);
                ids
            }
        };
        let sampler = texture.sampler.clone().map(|s| doc.add_sampler(s));
        let id = Self::texture_of(doc, ids, sampler, texture.json.clone());
        self.source_textures.insert((t, size), id);
        Ok(id)
    }

    /// The input's material `source` with its maps pointing at this document's textures.
    fn source_material(
        &mut self,
        doc: &mut GltfBuilder,
        images: &Downscaler,
        name: &str,
        source: &MaterialSource,
        sizes: &ImageSizes,
        cutoff: Option<f32>,
    ) -> Result<usize, ExportError> {
        let mut json = source.json.clone();
        visit_texture_infos(&mut json, &mut |key, info| {
            let t = info
                .get("index")
                .and_then(serde_json::Value::as_u64)
                .ok_or_else(|| ExportError::NoTextureIndex(name.to_string()))?
                as usize;
            // Only the base colour carries the alpha the material tests.
            let cutoff = cutoff.filter(|_| key == "baseColorTexture");
            let id = self.source_texture(doc, images, t, sizes, cutoff, MapKind::of_key(key))?;
            info.insert("index".into(), serde_json::json!(id));
            Ok::<(), ExportError>(())
        })?;
        Ok(doc.add_material_json(json, &source.extensions))
    }

    /// The document material for tree material `m`, written once: an imported material exactly
    /// as the input described it (see the module docs), one made by frond from its fields.
    /// `images` makes the tree's images smaller where `sizes` asks.
    pub fn tree_material(
        &mut self,
        doc: &mut GltfBuilder,
        images: &Downscaler,
        m: usize,
        sizes: &ImageSizes,
    ) -> Result<usize, ExportError> {
        let tree = images.tree();
        let key = (
            m,
            material_images(tree, m)
                .into_iter()
                .filter_map(|j| sizes.get(&j).map(|s| (j, *s)))
                .collect::<Vec<_>>(),
        );
        if let Some(&id) = self.tree_materials.get(&key) {
            return Ok(id);
        }
        let material = tree.materials.get(m).ok_or(ExportError::NoMaterial(m))?;
        let cutoff = (material.alpha_mode == AlphaMode::Mask).then_some(material.alpha_cutoff);
        if let Some(source) = &material.source {
            let id = self.source_material(doc, images, &material.name, source, sizes, cutoff)?;
            self.tree_materials.insert(key, id);
            return Ok(id);
        }
        let texture = match material.base_color_texture {
            Some(ti) => match self.tree_textures.get(&ti) {
                Some(&t) => Some(t),
                None => {
                    let t = tree.textures.get(ti).ok_or(ExportError::NoMaterial(m))?;
                    let clamp = material.alpha_mode != AlphaMode::Opaque;
                    let id = self.add_rgba(doc, &t.name, t.width, t.height, &t.rgba, clamp)?;
                    self.tree_textures.insert(ti, id);
                    Some(id)
                }
            },
            None => None,
        };
        let id = doc.add_material(&MaterialDesc {
            name: material.name.clone(),
            base_color: material.base_color,
            base_color_texture: texture,
            normal_texture: None,
            alpha: match material.alpha_mode {
                AlphaMode::Opaque => WriteAlpha::Opaque,
                AlphaMode::Mask => WriteAlpha::Mask(material.alpha_cutoff),
                AlphaMode::Blend => WriteAlpha::Blend,
            },
            double_sided: material.double_sided,
            metallic: 0.0,
            roughness: 1.0,
        });
        self.tree_materials.insert(key, id);
        Ok(id)
    }
}

/// A tangent-space normal map (RGBA8, `n * 0.5 + 0.5`) at half its side, rounded up to a
/// multiple of 4 (a block-compressed format's block): each texel the renormalised mean of the
/// 2×2 texels under it (nearest, when rounding up made the map a little larger than half), alpha opaque (a normal map's alpha is unused and would only cost
/// bytes). The atlas's UVs address it as they address the colour atlas.
fn half_normal_map(width: u32, height: u32, rgba: &[u8]) -> (u32, u32, Vec<u8>) {
    let (w2, h2) = (
        (width / 2).max(1).next_multiple_of(4),
        (height / 2).max(1).next_multiple_of(4),
    );
    let decode = |v: u8| f32::from(v) / 255.0 * 2.0 - 1.0;
    let encode = |x: f32| ((x * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
    let mut out = Vec::with_capacity((w2 * h2 * 4) as usize);
    for y in 0..h2 {
        for x in 0..w2 {
            let mut n = glam::Vec3::ZERO;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                // The 2×2 source texels under this one (edges repeated).
                let sx = (x * width / w2 + dx).min(width - 1);
                let sy = (y * height / h2 + dy).min(height - 1);
                let i = ((sy * width + sx) * 4) as usize;
                // Texels no cell owns hold zeros: flat there.
                n += match &rgba[i..i + 3] {
                    [0, 0, 0] => glam::Vec3::Z,
                    t => glam::Vec3::new(decode(t[0]), decode(t[1]), decode(t[2])),
                };
            }
            let n = n.normalize_or(glam::Vec3::Z);
            out.extend_from_slice(&[encode(n.x), encode(n.y), encode(n.z), 255]);
        }
    }
    (w2, h2, out)
}

/// A file-name-safe version of `name` (letters, digits, `-`, `_`, `.`; others become `_`).
pub fn sanitize(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() { "texture".into() } else { s }
}
