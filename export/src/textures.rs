//! Where written textures go: embedded in the GLB, or PNG files next to it
//! (`--external-textures`), and the tree's materials written once per document.

use std::collections::HashMap;

use frond_scene::gltf_writer::{GltfBuilder, MaterialDesc, WriteAlpha, encode_png};
use frond_scene::{AlphaMode, Tree};

use crate::error::ExportError;

/// Collects textures and materials of one document.
pub struct TextureSink {
    /// File-name prefix of external PNGs (None: embed).
    external: Option<String>,
    /// External PNG files to write next to the glTF: (file name, bytes).
    pub files: Vec<(String, Vec<u8>)>,
    tree_textures: HashMap<usize, usize>,
    tree_materials: HashMap<usize, usize>,
}

impl TextureSink {
    /// Embedded textures, or external ones named `<prefix><texture>.png` when `external`.
    pub fn new(external: Option<String>) -> Self {
        TextureSink {
            external,
            files: Vec::new(),
            tree_textures: HashMap::new(),
            tree_materials: HashMap::new(),
        }
    }

    /// Adds an RGBA8 image as a texture (clamped when `clamp`).
    pub fn add_rgba(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        width: u32,
        height: u32,
        rgba: &[u8],
        clamp: bool,
    ) -> Result<usize, ExportError> {
        let png = encode_png(width, height, rgba).map_err(|source| ExportError::Image {
            name: name.to_string(),
            source,
        })?;
        Ok(match &self.external {
            None => doc.add_texture(name, &png, clamp),
            Some(prefix) => {
                // Same name, other pixels: number the file.
                let mut file = format!("{prefix}{}.png", sanitize(name));
                let mut k = 1;
                while self.files.iter().any(|(f, b)| *f == file && *b != png) {
                    file = format!("{prefix}{}_{k}.png", sanitize(name));
                    k += 1;
                }
                let id = doc.add_texture_uri(name, &file, clamp);
                if !self.files.iter().any(|(f, _)| *f == file) {
                    self.files.push((file, png));
                }
                id
            }
        })
    }

    /// The billboards' material: the colour atlas, alpha-tested at 0.5, double-sided, rough.
    pub fn billboard_material(
        &mut self,
        doc: &mut GltfBuilder,
        name: &str,
        atlas: &frond_billboard::Atlas,
    ) -> Result<usize, ExportError> {
        let tex = self.add_rgba(
            doc,
            &format!("{name}_atlas"),
            atlas.width,
            atlas.height,
            &atlas.color,
            true,
        )?;
        Ok(doc.add_material(&MaterialDesc {
            name: format!("{name}_billboards"),
            base_color: [1.0; 4],
            base_color_texture: Some(tex),
            alpha: WriteAlpha::Mask(0.5),
            double_sided: true,
            metallic: 0.0,
            roughness: 1.0,
        }))
    }

    /// The document material for tree material `m` (written once, with its texture).
    pub fn tree_material(
        &mut self,
        doc: &mut GltfBuilder,
        tree: &Tree,
        m: usize,
    ) -> Result<usize, ExportError> {
        if let Some(&id) = self.tree_materials.get(&m) {
            return Ok(id);
        }
        let material = tree.materials.get(m).ok_or(ExportError::NoMaterial(m))?;
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
            alpha: match material.alpha_mode {
                AlphaMode::Opaque => WriteAlpha::Opaque,
                AlphaMode::Mask => WriteAlpha::Mask(material.alpha_cutoff),
                AlphaMode::Blend => WriteAlpha::Blend,
            },
            double_sided: material.double_sided,
            metallic: 0.0,
            roughness: 1.0,
        });
        self.tree_materials.insert(m, id);
        Ok(id)
    }
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
