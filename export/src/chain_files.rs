//! A LOD chain as files: one GLB per LOD, the combined GLB, each billboard LOD's mapping
//! sidecar and animation textures (VAT or spectral) with their sidecars and the reference
//! shaders. Works from the chain alone: which method built a LOD does not matter here.

use std::time::Instant;

use rayon::prelude::*;

use frond_lod::{Chain, ChainLod, LodEntry};
use frond_scene::Tree;

use crate::ExportError;
use crate::LodInput;
use crate::cloud_motion::{spectral_textures, vat_textures};
use crate::downscale::Downscaler;
use crate::lod_file::{FileOptions, write_glb, write_named_glb};
use crate::mapping::Mapping;
use crate::spectral::SpectralTextures;
use crate::vat::{VatFormat, VatSpace, VatTextures};

/// How billboards are animated in the files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimationMode {
    /// Standard glTF skin and channels.
    Skin,
    /// Vertex animation textures (Houdini VAT 3.0 rigid layout) plus a skinned wood.
    Vat(VatFormat),
    /// Skinned billboards plus each one's own motion as a few cosines in a float texture
    /// (spectral methods, spec §4.11 "runtime"); per-bone LODs need no texture.
    Spectral,
}

impl AnimationMode {
    /// The name the report writes (`skin`, `vat-exr`, `vat-png`, `spectral`).
    pub fn report_name(self) -> String {
        match self {
            AnimationMode::Skin => "skin".into(),
            AnimationMode::Vat(f) => format!("vat-{}", f.extension()),
            AnimationMode::Spectral => "spectral".into(),
        }
    }
}

/// How a chain is written.
#[derive(Clone, Debug)]
pub struct ChainFileOptions {
    /// The tree's name in file names (`<name>_LOD1.glb`).
    pub name: String,
    /// How billboards are animated: skinned, vertex animation textures or spectral textures.
    pub animation: AnimationMode,
    /// Textures as files next to the GLBs instead of embedded.
    pub external_textures: bool,
    /// How the textures frond makes are stored (PNG, KTX2).
    pub textures: crate::TextureFormat,
    /// Clip names carry Godot's loop hint ([`crate::lod_file::loop_hinted`]).
    pub loop_hint: bool,
    /// The space VAT data is baked in (an engine's, for Houdini's stock materials).
    pub vat_space: VatSpace,
    /// Compressed geometry (`EXT_meshopt_compression`, `KHR_mesh_quantization`).
    pub compress: bool,
    /// How baked billboards are lit.
    pub billboard_normals: crate::lod_scene::BillboardNormals,
    /// `MSFT_lod` screen coverages of the combined file's LODs (None: no `MSFT_lod`).
    pub msft_lod: Option<Vec<f32>>,
    /// The asset `extras` of every file (generator, seed, source).
    pub extras: serde_json::Value,
}

/// The files of a chain, relative to the output folder, and the report lines with the files
/// filled in.
pub struct ChainFiles {
    /// Every file to write (name relative to the output folder, bytes): each LOD's GLB and
    /// sidecars, the combined file, the shaders.
    pub files: Vec<(String, Vec<u8>)>,
    /// The chain's report lines, one per LOD, with their files and export time filled in.
    pub entries: Vec<LodEntry>,
    /// The combined file's name.
    pub combined: String,
}

/// One LOD's animation textures.
struct Motion {
    vat: Option<VatTextures>,
    spectral: Option<SpectralTextures>,
}

/// Encodes LOD `k`'s billboard motion as `mode` asks, and records its size in `entry`.
fn lod_motion(
    lod: &ChainLod,
    tree: &Tree,
    mode: AnimationMode,
    vat_space: VatSpace,
    prefix: &str,
    entry: &mut LodEntry,
) -> Result<Motion, ExportError> {
    let Some(cloud) = lod.cloud() else {
        return Ok(Motion {
            vat: None,
            spectral: None,
        });
    };
    let vat = match mode {
        AnimationMode::Vat(format) => Some(vat_textures(
            cloud,
            format,
            &format!("{prefix}_vat"),
            vat_space,
        )?),
        _ => None,
    };
    let spectral = match mode {
        AnimationMode::Spectral => {
            spectral_textures(cloud, tree, &format!("{prefix}_spectral.exr"))?
        }
        _ => None,
    };
    entry.animation_bytes = vat
        .as_ref()
        .map(|v| v.position.bytes.len() + v.rotation.bytes.len())
        .or(spectral.as_ref().map(|t| t.image.bytes.len()))
        .unwrap_or(0);
    // For comparison only: a LOD VAT cannot hold (too large) just has no figure.
    entry.vat_equivalent_bytes = match &spectral {
        Some(_) => vat_textures(cloud, VatFormat::ExrHalf, "vat", VatSpace::Gltf)
            .ok()
            .map(|v| v.position.bytes.len() + v.rotation.bytes.len()),
        None => None,
    };
    Ok(Motion { vat, spectral })
}

/// The sidecars of LOD `k` (mapping, animation textures): appended to `files`, named in `entry`.
fn sidecars(
    lod: &ChainLod,
    motion: &Motion,
    chain: &Chain,
    k: usize,
    prefix: &str,
    files: &mut Vec<(String, Vec<u8>)>,
    entry: &mut LodEntry,
) -> Result<(), ExportError> {
    if let Some(cloud) = lod.cloud() {
        let mapping = Mapping::of(cloud, k, &entry.file, &chain.sampled.foliage);
        let name = format!("{prefix}.mapping.json");
        files.push((name.clone(), json(&mapping)?));
        entry.mapping = Some(name);
    }
    if let Some(v) = &motion.vat {
        let pos = v.sidecar.textures.position.clone();
        let rot = v.sidecar.textures.rotation.clone();
        let name = format!("{prefix}_vat.json");
        files.push((pos.clone(), v.position.bytes.clone()));
        files.push((rot.clone(), v.rotation.bytes.clone()));
        let mut listed = vec![pos, rot];
        if let Some(pivot) = &v.sidecar.textures.pivot {
            files.push((pivot.clone(), v.pivot.bytes.clone()));
            listed.push(pivot.clone());
        }
        files.push((name.clone(), json(&v.sidecar)?));
        listed.push(name);
        entry.vat = Some(listed);
    }
    if let Some(t) = &motion.spectral {
        let name = format!("{prefix}_spectral.json");
        files.push((t.sidecar.texture.clone(), t.image.bytes.clone()));
        files.push((name.clone(), json(&t.sidecar)?));
        entry.spectral_files = Some(vec![t.sidecar.texture.clone(), name]);
    }
    Ok(())
}

/// Pretty JSON of a sidecar.
fn json<T: serde::Serialize>(value: &T) -> Result<Vec<u8>, ExportError> {
    serde_json::to_vec_pretty(value).map_err(|e| ExportError::Json(e.to_string()))
}

/// Writes `chain` of `tree` in memory: every LOD's GLB and sidecars, then the combined file
/// and the shaders the animation mode needs. Errors name the LOD.
pub fn chain_files(
    tree: &Tree,
    chain: &Chain,
    options: &ChainFileOptions,
) -> Result<ChainFiles, (String, ExportError)> {
    let name = &options.name;
    let prefix = |k: usize| format!("{name}_LOD{k}");
    let mut entries: Vec<LodEntry> = chain.lods.iter().map(|l| l.entry.clone()).collect();
    let mut motions = Vec::with_capacity(chain.lods.len());
    for (k, lod) in chain.lods.iter().enumerate() {
        let m = lod_motion(
            lod,
            tree,
            options.animation,
            options.vat_space,
            &prefix(k),
            &mut entries[k],
        )
        .map_err(|e| (format!("building LOD{k}"), e))?;
        motions.push(m);
    }
    // Every writer's downscaled maps come from one place: each made once, one decode at a time.
    let images = Downscaler::new(tree);
    let inputs: Vec<LodInput> = chain
        .lods
        .iter()
        .zip(&motions)
        .enumerate()
        .map(|(k, (lod, m))| lod_input(&images, lod, m, prefix(k), options.billboard_normals))
        .collect();
    // Every LOD's file and the combined one are written at once: each is its own bytes.
    let write_lod = |k: usize, input: &LodInput, entry: &mut LodEntry| {
        let t0 = Instant::now();
        let at = |e| (format!("writing LOD{k}"), e);
        let file = write_glb(
            std::slice::from_ref(input),
            &FileOptions {
                external_textures: options.external_textures.then(|| format!("{}_", prefix(k))),
                textures: options.textures,
                loop_hint: options.loop_hint,
                compress: options.compress,
                msft_lod: None,
                extras: Some(options.extras.clone()),
            },
        )
        .map_err(at)?;
        entry.file = format!("{}.glb", prefix(k));
        entry.bones = file.joints.first().copied().unwrap_or(0);
        let mut files = vec![(entry.file.clone(), file.glb)];
        files.extend(file.external);
        sidecars(
            &chain.lods[k],
            &motions[k],
            chain,
            k,
            &prefix(k),
            &mut files,
            entry,
        )
        .map_err(at)?;
        entry.timings_s.export = t0.elapsed().as_secs_f64();
        Ok(files)
    };
    let (lod_files, combined) = rayon::join(
        || {
            inputs
                .par_iter()
                .zip(entries.par_iter_mut())
                .enumerate()
                .map(|(k, (input, entry))| write_lod(k, input, entry))
                .collect::<Vec<Result<_, (String, ExportError)>>>()
        },
        || {
            write_named_glb(
                &inputs,
                &FileOptions {
                    external_textures: options.external_textures.then(|| format!("{name}_lods_")),
                    textures: options.textures,
                    loop_hint: options.loop_hint,
                    compress: options.compress,
                    msft_lod: options.msft_lod.clone(),
                    extras: Some(options.extras.clone()),
                },
                name,
            )
        },
    );
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    // The error of the first LOD in order that failed, whichever order they finished in.
    for lod in lod_files {
        files.extend(lod?);
    }
    let combined = combined.map_err(|e| ("writing the combined file".to_string(), e))?;
    let combined_name = format!("{name}_lods.glb");
    files.push((combined_name.clone(), combined.glb));
    files.extend(combined.external);
    let spectral_written = motions.iter().any(|m| m.spectral.is_some());
    let blended = (chain.lods.iter()).any(|l| l.cloud().is_some_and(|c| c.atlas.blended));
    files.extend(shader_files(options.animation, spectral_written, blended));
    Ok(ChainFiles {
        files,
        entries,
        combined: combined_name,
    })
}

/// What export needs of one LOD.
fn lod_input<'a>(
    images: &'a Downscaler<'a>,
    lod: &'a ChainLod,
    m: &Motion,
    name: String,
    billboard_normals: crate::lod_scene::BillboardNormals,
) -> LodInput<'a> {
    LodInput {
        name,
        tree: images.tree(),
        images,
        rig: lod.rig(),
        parts: lod.parts.iter().collect(),
        cloud: lod.cloud(),
        clips: lod.clips.clone(),
        image_sizes: &lod.image_sizes,
        vat_uvs: m.vat.as_ref().map(|v| {
            vec![
                v.piece_uv.clone(),
                v.pivot_uv.iter().map(|p| p[0]).collect(),
                v.pivot_uv.iter().map(|p| p[1]).collect(),
            ]
        }),
        spectral_uvs: m.spectral.as_ref().map(|t| t.row_uv.clone()),
        byte_weights: !matches!(lod.content, frond_lod::chain::LodContent::Input(_)),
        billboard_normals,
    }
}

/// The shaders shipped under `shaders/`: the VAT set next to VAT output, the spectral set next
/// to spectral textures (when a LOD wrote one), the LOD cross-fade alone otherwise; with the
/// blended variants of the set's Godot materials when a LOD is drawn blended.
fn shader_files(
    mode: AnimationMode,
    spectral_written: bool,
    blended: bool,
) -> Vec<(String, Vec<u8>)> {
    let set = match mode {
        AnimationMode::Vat(_) => crate::shaders::SHADERS,
        AnimationMode::Spectral if spectral_written => crate::shaders::SPECTRAL_SHADERS,
        // Every chain can cross-fade its LODs: the dither ships with skinned chains too.
        _ => crate::shaders::LOD_FADE_SHADERS,
    };
    let variants = if blended {
        crate::shaders::blended_variants(set)
    } else {
        Vec::new()
    };
    let shipped = set
        .iter()
        .map(|&(file, text)| (file.to_string(), text.to_string()));
    (shipped.chain(variants))
        .map(|(file, text)| (format!("shaders/{file}"), text.into_bytes()))
        .collect()
}

/// `MSFT_lod` screen coverages for LODs built at `screen_heights` (pixels) on an image
/// `resolution` pixels high ([`frond_lod::switching::min_screen_fractions`]): LOD k is shown
/// down to the size the next LOD was built for; the last one to a quarter of its own.
pub fn msft_coverages(screen_heights: &[f32], resolution: f32) -> Vec<f32> {
    frond_lod::switching::min_screen_fractions(screen_heights, resolution)
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};
    use serde::Serialize;
    use serde::de::DeserializeOwned;

    use super::*;
    use crate::mapping::BillboardMapping;
    use crate::spectral::{SpectralTerm, encode_spectral};
    use crate::vat::{RigidFrame, RigidPiece, VatFormat, VatOptions, encode_rigid_with};

    /// `value` written as its sidecar is, read back: equal, and written again to the same bytes.
    fn round_trip<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(value: &T) {
        let bytes = json(value).expect("written");
        let back: T = serde_json::from_slice(&bytes).expect("read back");
        assert_eq!(&back, value);
        assert_eq!(json(&back).expect("written again"), bytes);
    }

    #[test]
    fn mapping_sidecars_read_back() {
        round_trip(&Mapping {
            lod: 2,
            file: "oak_LOD2.glb".into(),
            method: "per-bone".into(),
            unmapped_triangles: vec![7, 9],
            billboards: vec![
                BillboardMapping {
                    billboard: 0,
                    triangles: vec![0, 1, 4],
                    follows: Some("branch3_L1_0".into()),
                    own_motion: true,
                },
                BillboardMapping {
                    billboard: 1,
                    triangles: vec![2],
                    follows: None,
                    own_motion: false,
                },
            ],
        });
    }

    #[test]
    fn vat_sidecars_read_back() {
        let frame = |x: f32, angle: f32| RigidFrame {
            position: Vec3::new(x, 1.5, -0.25),
            rotation: Quat::from_rotation_y(angle),
        };
        let pieces = vec![
            RigidPiece {
                pivot: Vec3::new(0.0, 1.5, -0.25),
                frames: vec![frame(0.0, 0.0), frame(0.1, 0.2), frame(0.05, 0.1)],
            },
            RigidPiece {
                pivot: Vec3::new(-2.0, 3.0, 1.0),
                frames: vec![frame(-2.0, 0.3), frame(-2.1, 0.1), frame(-1.9, 0.0)],
            },
        ];
        for format in [VatFormat::ExrHalf, VatFormat::Png16] {
            for space in [VatSpace::Gltf, VatSpace::Unity, VatSpace::Unreal] {
                let options = VatOptions {
                    file_stem: "oak_LOD1_vat".into(),
                    space,
                    clip: Some("Wind".into()),
                    start_s: 0.5,
                    ..VatOptions::default()
                };
                let vat = encode_rigid_with(&pieces, 24.0, format, &options).expect("encoded");
                round_trip(&vat.sidecar);
            }
        }
    }

    #[test]
    fn spectral_sidecars_read_back() {
        let term = |frequency: f32| SpectralTerm {
            frequency,
            amplitude: [0.1, 0.02, -0.05],
            phase: [0.5, -1.0, 2.0],
        };
        let terms = vec![vec![term(1.0), term(3.0)], Vec::new(), vec![term(2.0)]];
        let textures =
            encode_spectral(&terms, 4.0, 0.25, Some("Wind".into()), "oak_LOD1").expect("encoded");
        round_trip(&textures.sidecar);
    }
}
