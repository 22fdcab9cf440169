//! The textures frond makes, as KTX2 (`--textures ktx2`, `ktx2-png`): a mip chain built
//! here, encoded to UASTC by [`frond_scene::ktx2`], for `KHR_texture_basisu`.
//!
//! Engines build a plain mip chain for a PNG, and plain averaging thins alpha-tested foliage
//! out until it vanishes with distance. A KTX2 file carries its own chain, so colour maps get
//! the chain frond's renderer draws with (`frond_render::mip_chain`): colour averaged in linear
//! light weighted by alpha, alpha rescaled per level so that as many texels pass the 0.5 test
//! as at full size. Linear data (normal, occlusion, roughness maps) gets a plain 2×2 box chain.
//! `KHR_texture_basisu` wants level 0 a multiple of 4 a side; a map that is not is resampled
//! up to the next multiple (UVs are normalized, so nothing else changes).

use frond_scene::ktx2::encode_uastc;
use image::RgbaImage;
use image::imageops::{FilterType, resize};

use crate::error::ExportError;

/// How the textures frond makes are stored (the input's own images in LOD0 are always
/// passed through as they were).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TextureFormat {
    /// PNG; the engine builds the mips.
    #[default]
    Png,
    /// KTX2 (UASTC, Zstandard) with its mip chain; `KHR_texture_basisu` required.
    Ktx2,
    /// KTX2 plus the PNG as the texture's core source, for clients without the extension.
    Ktx2Png,
}

/// What a map holds, which decides its mip chain and transfer function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// sRGB colour with alpha (base colour, emissive); mips keep an alpha test's coverage.
    Colour,
    /// sRGB colour whose alpha is each texel's covered fraction, drawn blended (a far LOD's
    /// billboard atlas, glTF `BLEND`): mips are plain area averages, alpha not rescaled.
    Covered,
    /// Linear data (normals, occlusion, metal/roughness).
    Linear,
}

impl MapKind {
    /// The kind of the texture behind material key `key` (`baseColorTexture`, ...).
    pub fn of_key(key: &str) -> MapKind {
        match key {
            "baseColorTexture" | "emissiveTexture" => MapKind::Colour,
            _ => MapKind::Linear,
        }
    }
}

/// A KTX2 file of an RGBA8 image with its mip chain.
pub fn ktx2_bytes(
    name: &str,
    width: u32,
    height: u32,
    rgba: &[u8],
    kind: MapKind,
) -> Result<Vec<u8>, ExportError> {
    let (w4, h4) = (
        width.max(1).next_multiple_of(4),
        height.max(1).next_multiple_of(4),
    );
    let base = if (w4, h4) == (width, height) {
        rgba.to_vec()
    } else {
        let image = RgbaImage::from_raw(width, height, rgba.to_vec()).ok_or_else(|| {
            ExportError::Ktx2(format!(
                "{name}: {width}×{height} with {} bytes",
                rgba.len()
            ))
        })?;
        resize(&image, w4, h4, FilterType::Triangle).into_raw()
    };
    let levels = match kind {
        MapKind::Colour => frond_render::mip_chain(w4, h4, &base),
        MapKind::Covered => frond_render::blend_mip_chain(w4, h4, &base),
        MapKind::Linear => frond_render::linear_mip_chain(w4, h4, base),
    };
    let colour = kind != MapKind::Linear;
    encode_uastc(&levels, colour, colour).map_err(|e| ExportError::Ktx2(format!("{name}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps_keep_alpha_coverage_per_level_and_odd_sizes_grow_to_multiples_of_4() {
        // 62×58: leaves of soft-edged discs (alpha falling off over 3 texels) covering about a
        // quarter of the image.
        let (w, h) = (62u32, 58u32);
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let (cx, cy) = (
                    (x / 15.5).floor() * 15.5 + 7.75,
                    (y / 14.5).floor() * 14.5 + 7.25,
                );
                let d = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
                let a = ((4.5 - d) / 3.0 * 255.0 + 127.5).clamp(0.0, 255.0) as u8;
                [40, 160, 30, a]
            })
            .collect();
        let file = ktx2_bytes("leaves", w, h, &rgba, MapKind::Colour).expect("encodes");
        let info = frond_scene::ktx2::read_info(&file).expect("reads");
        assert_eq!((info.width, info.height, info.levels), (64, 60, 7));
        assert!(info.srgb && info.alpha);
        let levels = frond_scene::ktx2::decode_levels(&file, usize::MAX).expect("decodes");
        let coverage = |l: &frond_scene::ktx2::Level| {
            l.2.chunks(4).filter(|p| p[3] >= 128).count() as f64 / f64::from(l.0 * l.1)
        };
        let c0 = coverage(&levels[0]);
        assert!(c0 > 0.15 && c0 < 0.4, "{c0}");
        for l in &levels[1..4] {
            let c = coverage(l);
            assert!((c - c0).abs() < 0.05, "level {}×{}: {c} vs {c0}", l.0, l.1);
        }
    }

    #[test]
    fn linear_maps_are_box_filtered() {
        let chain = frond_render::linear_mip_chain(
            2,
            2,
            vec![
                0, 0, 0, 0, 100, 100, 100, 100, 0, 0, 0, 0, 200, 200, 200, 200,
            ],
        );
        assert_eq!(chain.len(), 2);
        assert_eq!(chain[1], (1, 1, vec![75, 75, 75, 75]));
        let file = ktx2_bytes("n", 8, 8, &[128u8; 256], MapKind::Linear).expect("encodes");
        let info = frond_scene::ktx2::read_info(&file).expect("reads");
        assert!(!info.srgb && !info.alpha);
        assert_eq!(info.levels, 4);
    }
}
