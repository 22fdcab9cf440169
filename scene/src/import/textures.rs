//! Images: the original bytes of every image a material map uses, the decoded-size budget
//! checked from their headers, and the decoding of the maps frond samples itself.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::import::materials::{MaterialInfo, texture_image};
use crate::input_file::human_bytes;
use crate::model::{SourceImage, SourceTexture, Texture, visit_texture_infos};

/// The MIME type of KTX2 images (`KHR_texture_basisu`).
pub const KTX2_MIME: &str = "image/ktx2";

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
/// [`InputLimits::max_input_bytes`](crate::InputLimits::max_input_bytes) together with the file and its buffers.
///
/// Returns the source textures (in [`MaterialInfo::textures`] order), the images and, per
/// input image index read, its slot in the images. A texture's own `extensions` (say
/// `EXT_texture_webp` naming another image) are dropped with a warning: the texture is written
/// with its core `source` image.
pub(super) fn read_source_textures(
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
                    "image {img}: the file, its external buffers and images add up to {}, over the input size limit of {} (raise the input size limit to read it)",
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
/// against [`InputLimits::max_texture_bytes`](crate::InputLimits::max_texture_bytes), from the images' headers, before any image is
/// decoded. frond decodes base-colour maps and applied normal maps on import and may decode any
/// other map later (a far LOD writes it downscaled), so all of them count, each image once, at
/// 4 bytes (RGBA8) per texel. A small file that declares huge images (a "texture bomb") is
/// refused naming the largest image and the map that uses it; an image whose header cannot be
/// read is refused naming it.
///
/// Returns each image slot's declared size, in the order of `images`.
pub(super) fn check_texture_budget(
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
            "its {} images decode to {} (largest: {}, {w}×{h} texels, {}), over the texture memory limit of {} (raise the texture memory limit to read it)",
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
pub(super) fn read_textures(
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
