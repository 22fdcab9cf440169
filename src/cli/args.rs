//! Arguments several commands share: how a tree is read (input, materials, limits), seed and
//! loop sampling, and the plane search, bake and method options of `frond lod`.

use std::path::PathBuf;

use anyhow::Result;

use crate::cli::values::BakeRasteriserArg;
use frond_app::batch::parse_memory;
use frond_app::lod_settings::{BuildSettings, ReadSettings, Sampling};
use frond_scene::Length;

/// Materials the user names as foliage or wood, over the classification heuristics.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct MaterialArgs {
    /// Treat this material as foliage (repeatable).
    #[arg(long = "foliage-material", value_name = "NAME")]
    pub foliage_material: Vec<String>,
    /// Treat this material as wood (repeatable).
    #[arg(long = "wood-material", value_name = "NAME")]
    pub wood_material: Vec<String>,
}

/// How a tree is read: the input, material overrides, what reading it may cost.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct ImportArgs {
    /// Input tree (.glb or .gltf).
    pub input: PathBuf,
    /// Materials named as foliage or wood.
    #[command(flatten)]
    pub materials: MaterialArgs,
    /// What reading the input may cost.
    #[command(flatten)]
    pub limits: LimitArgs,
}

impl ImportArgs {
    /// How the tree is read, as the application takes it.
    pub fn read(&self) -> ReadSettings {
        ReadSettings {
            foliage_materials: self.materials.foliage_material.clone(),
            wood_materials: self.materials.wood_material.clone(),
            limits: self.limits.limits(),
        }
    }

    /// Reads the tree.
    pub fn load(&self) -> Result<frond_scene::Tree> {
        self.read().load(&self.input)
    }
}

/// What reading one input may cost (every command that reads a tree; `frond batch` passes
/// them to each tree's run).
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct LimitArgs {
    /// Refuse an input whose file plus external buffers exceed this size (K, M, G: binary
    /// units; 1G = 1 GiB).
    #[arg(long, value_name = "SIZE", default_value = "1G", value_parser = parse_size_arg)]
    pub max_input_size: u64,
    /// Refuse an input whose material maps (every slot, each image once) decode to more than
    /// this, at 4 bytes a texel (384M = six 4096² maps); checked from the image headers before
    /// decoding.
    #[arg(long, value_name = "SIZE", default_value = "384M", value_parser = parse_size_arg)]
    pub max_texture_memory: u64,
    /// Refuse an input whose mesh instances add up to more vertices than this (counted from
    /// the accessors before decoding; 8000000 is four times the xlarge sample).
    #[arg(long, value_name = "N", default_value_t = frond_scene::input_file::DEFAULT_MAX_VERTICES)]
    pub max_vertices: u64,
    /// Refuse an input whose animations add up to more keys than this (each channel of each
    /// clip counts its keys, at least 64; counted from the accessors before reading).
    #[arg(long, value_name = "N", default_value_t = frond_scene::input_file::DEFAULT_MAX_ANIMATION_KEYS)]
    pub max_animation_keys: u64,
}

impl LimitArgs {
    /// The limits as the application takes them.
    pub fn limits(&self) -> frond_scene::InputLimits {
        frond_scene::InputLimits {
            max_input_bytes: self.max_input_size,
            max_texture_bytes: self.max_texture_memory,
            max_vertices: self.max_vertices,
            max_animation_keys: self.max_animation_keys,
        }
    }
}

/// A size option's value (`parse_memory`'s units), for clap.
pub fn parse_size_arg(text: &str) -> std::result::Result<u64, String> {
    parse_memory(text).map_err(|e| format!("{e:#}"))
}

/// Plane search and bake options of `frond lod`, which `frond sweep` passes to every build.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct BuildArgs {
    /// Candidate planes per iteration of the plane search.
    #[arg(long, default_value_t = 100)]
    pub planes: usize,
    /// Favour billboards seen from this elevation in degrees (0 = vertical billboards).
    #[arg(long, value_name = "DEG")]
    pub view_penalty: Option<f32>,
    /// Bake every triangle valid for a plane, not only its own.
    #[arg(long)]
    pub increased_density: bool,
    /// Supersamples per texel side when baking (1-16; 4 = 4×4, 2 is ~2.5× faster).
    #[arg(long, default_value_t = 4)]
    pub supersample: u32,
    /// Rasteriser of the billboard atlases: cpu (the same atlas on every machine) or wgpu
    /// (a GPU's, when there is one).
    #[arg(long, value_enum, default_value_t = BakeRasteriserArg::Cpu)]
    pub bake_rasteriser: BakeRasteriserArg,
    /// Spectral methods: animation clusters per LOD (default: one per 10 pixels of screen
    /// height, at least 1; at 32 px or less the joint budget less one, each cluster moving as
    /// one joint).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    pub clusters: Option<u64>,
    /// Spectral methods: animation zone size, a length or % of the diagonal (default: 2% or
    /// the LOD's ε, the larger; 0: a zone per triangle, triangles with one centre sharing one).
    #[arg(long, value_name = "SIZE")]
    pub zone_size: Option<Length>,
    /// Spectral methods: no shared-bone binding; billboards translate in world space only.
    #[arg(long)]
    pub no_shared_bone: bool,
    /// Skeleton methods: billboard clouds per LOD (default: as few as merges that cannot be
    /// seen at the LOD's size allow; a budget CJR cannot reach collapses sibling bones).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub clouds: Option<u64>,
    /// Skeleton methods: merged bones keep their own animation and only their foliage turns
    /// by the common rotation (thesis §7.1.2; the foliage then drifts off its branch).
    #[arg(long)]
    pub average_bone: bool,
}

impl BuildArgs {
    /// The options as the application takes them.
    pub fn settings(&self) -> BuildSettings {
        BuildSettings {
            planes: self.planes,
            view_penalty: self.view_penalty,
            increased_density: self.increased_density,
            supersample: self.supersample,
            bake_rasteriser: self.bake_rasteriser.into(),
            clusters: self.clusters,
            zone_size: self.zone_size,
            shared_bone: !self.no_shared_bone,
            clouds: self.clouds,
            average_bone: self.average_bone,
        }
    }
}

impl RunArgs {
    /// The options as the application takes them.
    pub fn sampling(&self) -> Sampling {
        Sampling {
            seed: self.seed,
            samples: self.samples,
            clip: self.clip.clone(),
        }
    }
}

/// Seed and loop sampling, shared by the commands that build billboards.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct RunArgs {
    /// Random seed: same input and seed, same files.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Animation samples over the loop.
    #[arg(long, default_value_t = 64)]
    pub samples: usize,
    /// Clip to sample (default: the first); billboards' own motion plays only this one.
    #[arg(long)]
    pub clip: Option<String>,
}
