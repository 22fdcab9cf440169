//! Texture sizes of a LOD: every image the LOD's meshes draw with (wood maps,
//! a card LOD's leaf texture) is written no larger than the LOD's texel density asks for: one
//! texel per screen pixel at the LOD's screen height (spec view-dependent-hierarchies-gpu
//! §2.4, Holst's texture budget), where the density a map has on the mesh is measured from the
//! mesh's UVs; alpha-tested maps keep [`ALPHA_TESTED_TEXELS_PER_PIXEL`] texels per pixel.
//! Sizes stay powers of two when the input's were, and never grow.

use std::collections::BTreeMap;

use frond_scene::wood::WoodMesh;
use frond_scene::{AlphaMode, Tree, visit_texture_infos};

/// Size each image (index into `Tree::images`) is written at in a LOD, where smaller than the
/// input's; images not listed are written as the input had them.
pub type ImageSizes = BTreeMap<usize, [u32; 2]>;

/// Texels per screen pixel an alpha-tested (`MASK`) material's maps keep: the alpha test turns
/// the texture's outline into the leaf's, and at one texel per pixel filtering moves that
/// outline by a pixel. Sixteen is four texels per sample of the coverage metric's 4×
/// supersampled render: the density at which a near card LOD's coverage error stops falling
/// (docs/experiments.md has the measurements), still a small fraction of the input's texture
/// bytes.
pub const ALPHA_TESTED_TEXELS_PER_PIXEL: f32 = 16.0;

/// Smallest side a downscaled image keeps.
pub const MIN_IMAGE_SIDE: u32 = 4;

/// Images (indices into `Tree::images`) material `m` draws with: every map of its source
/// description, or the image of its decoded base colour.
pub fn material_images(tree: &Tree, m: usize) -> Vec<usize> {
    let Some(material) = tree.materials.get(m) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    match &material.source {
        Some(source) => {
            let mut json = source.json.clone();
            let _ = visit_texture_infos(&mut json, &mut |_, info| {
                if let Some(t) = info
                    .get("index")
                    .and_then(serde_json::Value::as_u64)
                    .and_then(|t| tree.source_textures.get(t as usize))
                {
                    out.push(t.image);
                }
                Ok::<(), ()>(())
            });
        }
        None => {
            if let Some(j) = material
                .base_color_texture
                .and_then(|t| tree.textures.get(t))
                .and_then(|t| t.image)
            {
                out.push(j);
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Width and height of image `j` as the input stored it (from its header: PNG, JPEG or KTX2).
pub fn image_dimensions(tree: &Tree, j: usize) -> Option<[u32; 2]> {
    if let Some(t) = tree.textures.iter().find(|t| t.image == Some(j)) {
        return Some([t.width, t.height]);
    }
    let img = tree.images.get(j)?;
    if img.mime_type == frond_scene::import::KTX2_MIME {
        return frond_scene::ktx2::read_info(&img.bytes)
            .ok()
            .map(|k| [k.width, k.height]);
    }
    image::ImageReader::new(std::io::Cursor::new(&img.bytes))
        .with_guessed_format()
        .ok()?
        .into_dimensions()
        .ok()
        .map(|(w, h)| [w, h])
}

/// Texels per world unit a `width`×`height` texture has on the triangles `indices` of `mesh`
/// (through its base-colour UVs): the area-weighted 90th percentile over triangles, so that
/// nine tenths of the surface get at least the density asked for. None without area.
fn texel_density(mesh: &WoodMesh, indices: &[u32], width: u32, height: u32) -> Option<f32> {
    let mut samples: Vec<(f32, f32)> = Vec::new();
    let texels = (width as f32) * (height as f32);
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| t[k] as usize);
        let (Some(pa), Some(pb), Some(pc)) = (
            mesh.positions.get(a),
            mesh.positions.get(b),
            mesh.positions.get(c),
        ) else {
            continue;
        };
        let (Some(ua), Some(ub), Some(uc)) = (mesh.uvs.get(a), mesh.uvs.get(b), mesh.uvs.get(c))
        else {
            continue;
        };
        let world = 0.5 * (*pb - *pa).cross(*pc - *pa).length();
        let uv = 0.5 * (*ub - *ua).perp_dot(*uc - *ua).abs();
        if world > 0.0 && uv > 0.0 && world.is_finite() && uv.is_finite() {
            samples.push(((uv * texels / world).sqrt(), world));
        }
    }
    if samples.is_empty() {
        return None;
    }
    samples.sort_by(|x, y| x.0.total_cmp(&y.0));
    let total: f32 = samples.iter().map(|s| s.1).sum();
    let mut acc = 0.0;
    for (d, w) in &samples {
        acc += w;
        if acc >= 0.9 * total {
            return Some(*d);
        }
    }
    samples.last().map(|s| s.0)
}

/// `side` scaled by `s` (≤ 1), at least [`MIN_IMAGE_SIDE`], a power of two when `side` was.
fn shrink(side: u32, s: f32) -> u32 {
    let want = ((side as f32) * s).ceil().max(MIN_IMAGE_SIDE as f32) as u32;
    let want = if side.is_power_of_two() {
        want.next_power_of_two()
    } else {
        want
    };
    want.min(side)
}

/// The image sizes of a LOD drawing `parts` at `texels_per_unit` (see the module docs;
/// [`ALPHA_TESTED_TEXELS_PER_PIXEL`] times that for alpha-tested materials): per primitive, the
/// base-colour map's density on its triangles gives a scale ≤ 1 that every map of its material
/// takes (they share the UV layout in practice); an image several primitives use gets the
/// largest size any asks for. A material that `reference` (the input's wood, of which the
/// parts' wood is a simplification) draws takes its density there: a far LOD's few wood
/// triangles stretch or collapse the bark's UVs, and their density says nothing of the map's.
pub fn lod_image_sizes(
    tree: &Tree,
    parts: &[WoodMesh],
    reference: Option<&WoodMesh>,
    texels_per_unit: f32,
) -> ImageSizes {
    let base_of = |material: usize| {
        (tree.materials.get(material))
            .and_then(|m| m.base_color_texture)
            .and_then(|t| tree.textures.get(t))
    };
    let reference_density: BTreeMap<usize, Option<f32>> = reference
        .into_iter()
        .flat_map(|mesh| mesh.primitives.iter().map(move |p| (mesh, p)))
        .map(|(mesh, p)| {
            let d = base_of(p.material)
                .and_then(|t| texel_density(mesh, &p.indices, t.width, t.height));
            (p.material, d)
        })
        .collect();
    let mut scale: BTreeMap<usize, f32> = BTreeMap::new();
    for mesh in parts {
        for p in &mesh.primitives {
            let Some(material) = tree.materials.get(p.material) else {
                continue;
            };
            let wanted = match material.alpha_mode {
                AlphaMode::Mask => ALPHA_TESTED_TEXELS_PER_PIXEL * texels_per_unit,
                AlphaMode::Opaque | AlphaMode::Blend => texels_per_unit,
            };
            let density = match reference_density.get(&p.material) {
                Some(&d) => d,
                None => base_of(p.material)
                    .and_then(|t| texel_density(mesh, &p.indices, t.width, t.height)),
            };
            let s = density.map_or(1.0, |d| (wanted / d).min(1.0));
            for j in material_images(tree, p.material) {
                let e = scale.entry(j).or_insert(0.0);
                *e = e.max(s);
            }
        }
    }
    scale
        .into_iter()
        .filter_map(|(j, s)| {
            let [w, h] = image_dimensions(tree, j)?;
            let size = [shrink(w, s), shrink(h, s)];
            (size != [w, h]).then_some((j, size))
        })
        .collect()
}

/// Decoded bytes (RGBA8, 4 a texel) of every image `parts` draw with, at `sizes`.
pub fn parts_image_bytes(tree: &Tree, parts: &[WoodMesh], sizes: &ImageSizes) -> usize {
    let mut images: Vec<usize> = parts
        .iter()
        .flat_map(|m| &m.primitives)
        .flat_map(|p| material_images(tree, p.material))
        .collect();
    images.sort_unstable();
    images.dedup();
    images
        .iter()
        .filter_map(|j| sizes.get(j).copied().or_else(|| image_dimensions(tree, *j)))
        .map(|[w, h]| 4 * w as usize * h as usize)
        .sum()
}

/// The side of a square atlas of at most `texels` texels (a multiple of 4, at least 64).
/// Decoded bytes (RGBA8) of a colour atlas `side` texels square and its normal atlas, half its
/// side rounded up to a multiple of 4, as export writes it.
pub(crate) fn atlas_bytes(side: u32) -> usize {
    let half = (side / 2).max(1).next_multiple_of(4) as usize;
    4 * ((side as usize).pow(2) + half * half)
}

/// The largest atlas side whose colour atlas and normal atlas (half its side, rounded up to a
/// multiple of 4, as export writes it) decode to at most `bytes` (RGBA8), and at least 64.
pub(crate) fn atlas_side_for_bytes(bytes: usize) -> u32 {
    let mut side = atlas_side(bytes / 5);
    while side > 64 && atlas_bytes(side) > bytes {
        side -= 4;
    }
    side
}

pub(crate) fn atlas_side(texels: usize) -> u32 {
    let side = (texels as f64).sqrt().floor() as u32;
    (side / 4 * 4).clamp(64, frond_billboard::bake::MAX_ATLAS_SIDE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_atlas_and_its_normal_atlas_fit_their_bytes() {
        for bytes in [81_920usize, 77_824, 49_152, 25_600, 1 << 20, 20 << 20] {
            let side = atlas_side_for_bytes(bytes) as usize;
            let half = (side / 2).next_multiple_of(4);
            assert!(
                4 * (side * side + half * half) <= bytes,
                "{bytes}: side {side}"
            );
            let more = side + 4;
            let half = (more / 2).next_multiple_of(4);
            assert!(
                4 * (more * more + half * half) > bytes,
                "{bytes}: {side} is not the largest"
            );
        }
        assert_eq!(atlas_side_for_bytes(100), 64, "never under 64");
    }

    #[test]
    fn sides_shrink_to_powers_of_two_and_never_grow() {
        assert_eq!(shrink(1024, 1.0), 1024);
        assert_eq!(shrink(1024, 0.3), 512);
        assert_eq!(shrink(1024, 0.01), 16);
        assert_eq!(shrink(1024, 0.0), MIN_IMAGE_SIDE);
        assert_eq!(shrink(300, 0.5), 150);
        assert_eq!(shrink(2, 0.1), 2);
    }
}
