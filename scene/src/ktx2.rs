//! KTX2 textures in Basis Universal UASTC, Zstandard-supercompressed: what glTF's
//! `KHR_texture_basisu` carries (`gltf-and-toolchain.md`, "Textures"). Written for the textures
//! frond makes (atlases, downscaled maps), read so that frond can measure and import files
//! that carry them.
//!
//! The blocks come from Binomial's encoder and transcoder (`basis-universal`); the container
//! is written here and read with the `ktx2` crate. Why not the encoder's own KTX2 writer: the
//! crate exposes only `.basis` output, so each level's UASTC blocks are taken from that file
//! (the transcoder's level table gives where they are) and packed as KTX2 levels. Why a direct
//! call into the low-level transcoder: the crate's safe wrapper sizes its output buffer in
//! blocks for uncompressed targets (RGBA32), so decoding a UASTC level to texels writes past
//! it; [`decode_levels`] passes a buffer of the right size and its row pitch in pixels.
//!
//! Why UASTC rather than ETC1S (docs/experiments.md §15 has the measurements): on a leaf map,
//! UASTC's colour error over the alpha-passing texels and its share of flipped alpha-test
//! decisions are well below ETC1S's; both transcode to the same GPU formats (BC7 / ASTC 4×4,
//! one byte a texel), and ETC1S's files are several times smaller. For foliage drawn
//! alpha-tested, the cut-out is the picture, so quality wins.

use basis_universal::sys;
use basis_universal::{
    BasisTextureFormat, ColorSpace, Compressor, CompressorParams, Transcoder, UASTC_QUALITY_MIN,
};
use rayon::prelude::*;

/// KTX2 file identifier (KTX 2.0 spec §3.1).
const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];
/// `supercompressionScheme` Zstandard.
const ZSTD: u32 = 2;
/// Data format descriptor colour model of UASTC (`KHR_DF_MODEL_UASTC`).
const MODEL_UASTC: u8 = 166;
/// UASTC channel ids (`KHR_DF_CHANNEL_UASTC_RGB`, `_RGBA`).
const CHANNEL_RGB: u8 = 0;
const CHANNEL_RGBA: u8 = 3;
/// Zstandard level: the levels' blocks are written once and read many times.
const ZSTD_LEVEL: i32 = 18;
/// Bytes of one 4×4 UASTC block, and of the BC7 / ASTC 4×4 block it transcodes to.
pub const BLOCK_BYTES: u64 = 16;

/// What went wrong encoding or reading a KTX2 texture.
#[derive(Debug, thiserror::Error)]
pub enum Ktx2Error {
    /// The bytes are not a KTX2 file of a kind this reader takes (the reason says why).
    #[error("not a KTX2 file this reader takes: {0}")]
    Format(String),
    /// The UASTC encoder refused the image.
    #[error("UASTC encoding failed: {0}")]
    Encode(String),
    /// A level's UASTC blocks could not be transcoded to RGBA8.
    #[error("UASTC level {level} does not transcode")]
    Transcode {
        /// The level that failed (0 is the full-size image).
        level: usize,
    },
}

/// One mip level: width, height, RGBA8 texels.
pub type Level = (u32, u32, Vec<u8>);

/// What a KTX2 file holds, from its header.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ktx2Info {
    /// Width of level 0, texels.
    pub width: u32,
    /// Height of level 0, texels.
    pub height: u32,
    /// Mip levels stored (at least 1).
    pub levels: u32,
    /// sRGB transfer (colour), or linear (normals).
    pub srgb: bool,
    /// Whether the data format says the texels carry alpha.
    pub alpha: bool,
}

/// Bytes a `width`×`height` texture with `levels` mip levels takes on the GPU in a 4×4-block
/// format of 16 bytes a block (BC7, ASTC 4×4: what UASTC transcodes to), one block at least a
/// level.
pub fn gpu_bytes(width: u32, height: u32, levels: u32) -> u64 {
    (0..levels)
        .map(|l| {
            let (w, h) = ((width >> l).max(1), (height >> l).max(1));
            u64::from(w.div_ceil(4)) * u64::from(h.div_ceil(4)) * BLOCK_BYTES
        })
        .sum()
}

/// Encodes a mip chain (level 0 first, each level half the one before, rounded down, at
/// least 1) as a UASTC KTX2 file, levels Zstandard-supercompressed. `srgb`: colour data (sRGB
/// transfer, perceptual encoding); otherwise linear (normal maps). `alpha`: the texels carry
/// alpha (an RGBA channel layout), else RGB.
///
/// Deterministic: UASTC blocks are encoded one by one, whatever the thread count.
pub fn encode_uastc(levels: &[Level], srgb: bool, alpha: bool) -> Result<Vec<u8>, Ktx2Error> {
    let blocks = uastc_blocks(levels, srgb)?;
    Ok(uastc_container(
        levels[0].0,
        levels[0].1,
        &blocks,
        srgb,
        alpha,
    ))
}

/// The UASTC blocks of each level of `levels` (see [`encode_uastc`]), 16 bytes a 4×4 block,
/// rows of blocks top to bottom.
///
/// Each level is encoded in strips of `STRIP_ROWS` texel rows, the strips in parallel, each
/// by an encoder of its own on the calling thread (`image_blocks`): UASTC encodes every
/// block on its own, so a strip of whole block rows gives the level's blocks for those rows,
/// and the strips' blocks, concatenated, are the level's.
pub fn uastc_blocks(levels: &[Level], srgb: bool) -> Result<Vec<Vec<u8>>, Ktx2Error> {
    let Some((w0, h0, _)) = levels.first() else {
        return Err(Ktx2Error::Encode("no levels".into()));
    };
    for (l, (w, h, rgba)) in levels.iter().enumerate() {
        let expect = ((w0 >> l).max(1), (h0 >> l).max(1));
        if (*w, *h) != expect || rgba.len() != (*w as usize) * (*h as usize) * 4 {
            return Err(Ktx2Error::Encode(format!(
                "level {l} is {w}×{h} with {} bytes; a chain from {w0}×{h0} wants {}×{} RGBA8",
                rgba.len(),
                expect.0,
                expect.1
            )));
        }
    }
    let strips: Vec<(usize, u32, u32)> = levels
        .iter()
        .enumerate()
        .flat_map(|(l, (_, h, _))| {
            (0..h.div_ceil(STRIP_ROWS))
                .map(move |s| (l, s * STRIP_ROWS, (h - s * STRIP_ROWS).min(STRIP_ROWS)))
        })
        .collect();
    let encoded: Vec<(usize, Vec<u8>)> = strips
        .into_par_iter()
        .map(|(l, y0, rows)| {
            let (w, _, rgba) = &levels[l];
            let row_bytes = *w as usize * 4;
            let texels = &rgba[y0 as usize * row_bytes..(y0 + rows) as usize * row_bytes];
            image_blocks(*w, rows, texels, srgb).map(|b| (l, b))
        })
        .collect::<Result<_, _>>()?;
    let mut blocks = vec![Vec::new(); levels.len()];
    for (l, b) in encoded {
        blocks[l].extend_from_slice(&b);
    }
    Ok(blocks)
}

/// Texel rows of the strips a level is encoded in ([`uastc_blocks`]): whole rows of 4×4
/// blocks, enough texels a strip that an encoder's set-up is a small part of its time.
const STRIP_ROWS: u32 = 64;

/// The UASTC blocks of one `w`×`h` RGBA8 image, by an encoder that runs on the calling
/// thread alone. Why not the encoder's own threads: its job pool's destructor raises its stop
/// flag without the lock its workers wait under, so a worker can miss the wake-up and the
/// destructor wait for it forever (`basisu::job_pool::~job_pool`, basis_universal 1.16 as
/// `basis-universal-sys` 0.3.1 vendors it); the caller's strips run in parallel instead.
fn image_blocks(w: u32, h: u32, rgba: &[u8], srgb: bool) -> Result<Vec<u8>, Ktx2Error> {
    let mut params = CompressorParams::new();
    params.set_basis_format(BasisTextureFormat::UASTC4x4);
    params.set_uastc_quality_level(UASTC_QUALITY_MIN);
    params.set_color_space(if srgb {
        ColorSpace::Srgb
    } else {
        ColorSpace::Linear
    });
    params.set_generate_mipmaps(false);
    params.set_print_status_to_stdout(false);
    params.source_image_mut(0).init(rgba, w, h, 4);
    // One thread: no job pool thread is started (see above).
    let mut compressor = Compressor::new(1);
    // SAFETY: one source image of `w`×`h` RGBA8 texels (the caller's strip of a checked level).
    unsafe {
        if !compressor.init(&params) {
            return Err(Ktx2Error::Encode(
                "the encoder refused its parameters".into(),
            ));
        }
        compressor
            .process()
            .map_err(|e| Ktx2Error::Encode(format!("{e:?}")))?;
    }
    let basis = compressor.basis_file();
    let transcoder = Transcoder::new();
    let info = transcoder
        .image_level_info(basis, 0, 0)
        .ok_or_else(|| Ktx2Error::Encode(format!("a {w}×{h} image's level missing")))?;
    let start = info.m_rgb_file_ofs as usize;
    let end = start + info.m_rgb_file_len as usize;
    let data = basis
        .get(start..end)
        .ok_or_else(|| Ktx2Error::Encode("level out of the encoder's file".into()))?;
    let expected = w.div_ceil(4) as usize * h.div_ceil(4) as usize * BLOCK_BYTES as usize;
    if data.len() != expected {
        return Err(Ktx2Error::Encode(format!(
            "{} bytes of blocks for a {w}×{h} image, {expected} expected",
            data.len()
        )));
    }
    Ok(data.to_vec())
}

/// Packs UASTC levels (level 0 first) as a KTX2 file (KTX 2.0 spec §3): header, level index,
/// a basic data format descriptor for UASTC, the writer's name, the levels Zstandard
/// supercompressed and stored smallest first. `blocks[l]` holds level `l`'s UASTC blocks
/// ([`uastc_blocks`]); `width`×`height` is level 0's size.
pub fn uastc_container(
    width: u32,
    height: u32,
    blocks: &[Vec<u8>],
    srgb: bool,
    alpha: bool,
) -> Vec<u8> {
    let n = blocks.len();
    let compressed: Vec<Vec<u8>> = blocks
        .iter()
        .map(|b| zstd::bulk::compress(b, ZSTD_LEVEL).unwrap_or_else(|_| b.clone()))
        .collect();
    // Data format descriptor: total size, then one basic block of 24 bytes + one 16-byte sample.
    let mut dfd = Vec::with_capacity(44);
    dfd.extend_from_slice(&44u32.to_le_bytes());
    dfd.extend_from_slice(&0u32.to_le_bytes()); // vendor Khronos, descriptor type basic
    dfd.extend_from_slice(&2u16.to_le_bytes()); // version 2
    dfd.extend_from_slice(&40u16.to_le_bytes()); // block size
    dfd.extend_from_slice(&[MODEL_UASTC, 1, if srgb { 2 } else { 1 }, 0]); // BT.709, sRGB/linear, straight alpha
    dfd.extend_from_slice(&[3, 3, 0, 0]); // 4×4×1×1 blocks
    dfd.extend_from_slice(&[16, 0, 0, 0, 0, 0, 0, 0]); // bytes per plane
    dfd.extend_from_slice(&0u16.to_le_bytes()); // bit offset
    dfd.push(127); // bit length − 1
    dfd.push(if alpha { CHANNEL_RGBA } else { CHANNEL_RGB });
    dfd.extend_from_slice(&[0, 0, 0, 0]); // sample position
    dfd.extend_from_slice(&0u32.to_le_bytes()); // sample lower
    dfd.extend_from_slice(&u32::MAX.to_le_bytes()); // sample upper
    // Key/value data: the writer.
    let mut kvd = Vec::new();
    let entry = format!("KTXwriter\0frond {}\0", env!("CARGO_PKG_VERSION"));
    kvd.extend_from_slice(&(entry.len() as u32).to_le_bytes());
    kvd.extend_from_slice(entry.as_bytes());
    while kvd.len() % 4 != 0 {
        kvd.push(0);
    }
    let dfd_offset = 80 + 24 * n;
    let kvd_offset = dfd_offset + dfd.len();
    let mut data_offset = kvd_offset + kvd.len();
    // Levels are stored smallest first; the index lists them largest first.
    let mut offsets = vec![0usize; n];
    for l in (0..n).rev() {
        offsets[l] = data_offset;
        data_offset += compressed[l].len();
    }
    let mut out = Vec::with_capacity(data_offset);
    out.extend_from_slice(&IDENTIFIER);
    for v in [
        0, // VK_FORMAT_UNDEFINED
        1, // type size
        width, height, 0, // depth
        0, // layers
        1, // faces
        n as u32, ZSTD,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [dfd_offset, dfd.len(), kvd_offset, kvd.len()] {
        out.extend_from_slice(&(v as u32).to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // no supercompression global data
    out.extend_from_slice(&0u64.to_le_bytes());
    for l in 0..n {
        for v in [offsets[l], compressed[l].len(), blocks[l].len()] {
            out.extend_from_slice(&(v as u64).to_le_bytes());
        }
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    for c in compressed.iter().rev() {
        out.extend_from_slice(c);
    }
    out
}

/// Largest side of a KTX2 image frond decodes: what GPUs sample (16384 on desktop APIs). A
/// larger one is refused before its blocks are decompressed (a header may declare 2³¹
/// texels a side in a few bytes).
pub const MAX_SIDE: u32 = 16_384;

/// Width and height a KTX2 file's header declares, whatever its format (a height of 0, a 1D
/// texture, reads as 1).
pub fn declared_size(bytes: &[u8]) -> Result<(u32, u32), Ktx2Error> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| Ktx2Error::Format(format!("{e}")))?;
    let header = reader.header();
    Ok((header.pixel_width, header.pixel_height.max(1)))
}

/// Reads a KTX2 file's header and data format descriptor, refusing what [`decode_levels`]
/// cannot read (anything but 2D UASTC, supercompressed with Zstandard or not at all, at most
/// [`MAX_SIDE`] a side).
pub fn read_info(bytes: &[u8]) -> Result<Ktx2Info, Ktx2Error> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| Ktx2Error::Format(format!("{e}")))?;
    let header = reader.header();
    if header.pixel_width > MAX_SIDE || header.pixel_height > MAX_SIDE {
        return Err(Ktx2Error::Format(format!(
            "{}×{} texels, over the {MAX_SIDE} a side frond decodes",
            header.pixel_width, header.pixel_height
        )));
    }
    let dfd = reader
        .basic_dfd()
        .ok_or_else(|| Ktx2Error::Format("no basic data format descriptor".into()))?;
    if reader.color_model() != Some(ktx2::ColorModel::UASTC) {
        return Err(Ktx2Error::Format(format!(
            "colour model {:?}, not UASTC (ETC1S/BasisLZ and plain formats are not read)",
            reader.color_model()
        )));
    }
    match header.supercompression_scheme {
        None | Some(ktx2::SupercompressionScheme::Zstandard) => {}
        Some(s) => {
            return Err(Ktx2Error::Format(format!(
                "supercompression {s:?} (only Zstandard or none)"
            )));
        }
    }
    if header.pixel_depth > 1 || header.layer_count > 1 || header.face_count != 1 {
        return Err(Ktx2Error::Format(
            "not a plain 2D texture (depth, layers or cube faces)".into(),
        ));
    }
    if header.pixel_width == 0 || header.pixel_height == 0 {
        return Err(Ktx2Error::Format("zero width or height".into()));
    }
    let alpha = dfd
        .sample_information
        .first()
        .is_some_and(|s| s.channel_type == CHANNEL_RGBA);
    Ok(Ktx2Info {
        width: header.pixel_width,
        height: header.pixel_height,
        levels: header.level_count.max(1),
        srgb: reader.transfer_function() == Some(ktx2::TransferFunction::SRGB),
        alpha,
    })
}

/// Decodes the first `max_levels` mip levels of a UASTC KTX2 file to RGBA8 (level 0 first),
/// through Binomial's transcoder: what a loader's transcode shows, before the GPU's own block
/// decoding.
pub fn decode_levels(bytes: &[u8], max_levels: usize) -> Result<Vec<Level>, Ktx2Error> {
    let info = read_info(bytes)?;
    let reader = ktx2::Reader::new(bytes).map_err(|e| Ktx2Error::Format(format!("{e}")))?;
    let zstd = reader.header().supercompression_scheme.is_some();
    let mut out = Vec::new();
    for (l, level) in reader.levels().enumerate().take(max_levels) {
        let (w, h) = ((info.width >> l).max(1), (info.height >> l).max(1));
        let (bx, by) = (w.div_ceil(4), h.div_ceil(4));
        let expect = bx as usize * by as usize * BLOCK_BYTES as usize;
        let blocks = if zstd {
            zstd::bulk::decompress(level.data, expect)
                .map_err(|e| Ktx2Error::Format(format!("level {l}: {e}")))?
        } else {
            level.data.to_vec()
        };
        if blocks.len() != expect {
            return Err(Ktx2Error::Format(format!(
                "level {l}: {} bytes of blocks, a {w}×{h} level has {expect}",
                blocks.len()
            )));
        }
        out.push((w, h, transcode_rgba(&blocks, w, h, info.alpha, l)?));
    }
    Ok(out)
}

/// One UASTC level's blocks to RGBA8 texels (see the module doc for why the call is direct).
fn transcode_rgba(
    blocks: &[u8],
    width: u32,
    height: u32,
    alpha: bool,
    level: usize,
) -> Result<Vec<u8>, Ktx2Error> {
    let mut rgba = vec![0u8; width as usize * height as usize * 4];
    // SAFETY: `blocks` holds exactly ⌈w/4⌉·⌈h/4⌉ UASTC blocks (checked by the caller) and
    // `rgba` w·h texels of 4 bytes, the output the transcoder writes for RGBA32 with a row
    // pitch of `width` pixels over `height` rows; the transcoder is created and freed here.
    let ok = unsafe {
        sys::basisu_transcoder_init();
        let transcoder = sys::low_level_uastc_transcoder_new();
        let ok = sys::low_level_uastc_transcoder_transcode_slice(
            transcoder,
            rgba.as_mut_ptr().cast(),
            width.div_ceil(4),
            height.div_ceil(4),
            blocks.as_ptr(),
            blocks.len() as u32,
            sys::basist_block_format_cRGBA32,
            4,
            false,
            alpha,
            width,
            height,
            width,
            std::ptr::null_mut(),
            height,
            0,
            3,
            0,
        );
        sys::low_level_uastc_transcoder_delete(transcoder);
        ok
    };
    if ok {
        Ok(rgba)
    } else {
        Err(Ktx2Error::Transcode { level })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16×8 chain: opaque red disc on transparent, plain halving.
    fn chain() -> Vec<Level> {
        let (w, h) = (16u32, 8u32);
        let mut levels = Vec::new();
        let (mut lw, mut lh) = (w, h);
        loop {
            let mut rgba = Vec::new();
            for y in 0..lh {
                for x in 0..lw {
                    let (u, v) = ((x as f32 + 0.5) / lw as f32, (y as f32 + 0.5) / lh as f32);
                    let inside = (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.1;
                    rgba.extend_from_slice(if inside {
                        &[200, 30, 20, 255]
                    } else {
                        &[0, 0, 0, 0]
                    });
                }
            }
            levels.push((lw, lh, rgba));
            if lw == 1 && lh == 1 {
                break;
            }
            (lw, lh) = ((lw / 2).max(1), (lh / 2).max(1));
        }
        levels
    }

    #[test]
    fn round_trip_keeps_sizes_levels_and_texels() {
        let levels = chain();
        let file = encode_uastc(&levels, true, true).expect("encodes");
        let info = read_info(&file).expect("reads");
        assert_eq!(
            info,
            Ktx2Info {
                width: 16,
                height: 8,
                levels: 5,
                srgb: true,
                alpha: true
            }
        );
        let decoded = decode_levels(&file, usize::MAX).expect("decodes");
        assert_eq!(decoded.len(), 5);
        for ((w, h, a), (dw, dh, b)) in levels.iter().zip(&decoded) {
            assert_eq!((w, h), (dw, dh));
            for (p, q) in a.chunks(4).zip(b.chunks(4)) {
                assert_eq!(p[3] >= 128, q[3] >= 128, "alpha test kept");
                if p[3] == 255 {
                    for k in 0..3 {
                        assert!((p[k] as i32 - q[k] as i32).abs() <= 8, "{p:?} vs {q:?}");
                    }
                }
            }
        }
        // The same input gives the same bytes.
        assert_eq!(file, encode_uastc(&levels, true, true).expect("encodes"));
    }

    #[test]
    fn strips_encode_to_the_blocks_of_the_whole_image() {
        // Over three strips, a last block row cut short (150 rows), texels that vary in every
        // channel, alpha included: the strips' blocks, concatenated, are the image's.
        let (w, h) = (40u32, 2 * STRIP_ROWS + 22);
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                [
                    (x * 6) as u8,
                    (y * 3) as u8,
                    ((x * y) % 251) as u8,
                    if (x + y) % 7 < 3 { 0 } else { 255 },
                ]
            })
            .collect();
        let whole = image_blocks(w, h, &rgba, true).expect("encodes");
        let strips = uastc_blocks(&[(w, h, rgba.clone())], true).expect("encodes");
        assert_eq!(strips.len(), 1);
        assert_eq!(whole.len(), 10 * h.div_ceil(4) as usize * 16);
        assert!(
            strips[0] == whole,
            "strip blocks differ from the whole image's"
        );
        // A chain's levels each come out whole too.
        let chain = chain();
        let blocks = uastc_blocks(&chain, true).expect("encodes");
        for ((lw, lh, texels), b) in chain.iter().zip(&blocks) {
            assert!(*b == image_blocks(*lw, *lh, texels, true).expect("encodes"));
        }
    }

    #[test]
    fn gpu_bytes_count_blocks_of_every_level() {
        // 16×8: 8 + 2 + 1 + 1 + 1 blocks.
        assert_eq!(gpu_bytes(16, 8, 5), 13 * 16);
        assert_eq!(gpu_bytes(512, 512, 10), {
            let mut s = 0;
            for l in 0..10 {
                let side = (512u64 >> l).max(1).div_ceil(4);
                s += side * side * 16;
            }
            s
        });
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        assert!(matches!(read_info(b"not ktx"), Err(Ktx2Error::Format(_))));
        let mut file = encode_uastc(&chain(), true, true).expect("encodes");
        file.truncate(100);
        assert!(decode_levels(&file, 1).is_err());
        assert!(encode_uastc(&[], true, true).is_err());
        assert!(encode_uastc(&[(4, 4, vec![0; 3])], true, true).is_err());
    }
}
