//! What one `frond lod` run is asked: the input and how it is read, the screen sizes, the
//! method and its options, and how the files are written. Clap-free and serialisable: the
//! command line fills it from its flags, and `frond batch` and `frond sweep` write one for each
//! child run, which reads it back (a child never has its options rebuilt as flags).
//!
//! [`LodSettings::defaults`] is the one place the defaults live; the command line's flags take
//! their defaults from it.

use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::{Deserialize, Serialize};

use crate::lod_cmd::LodRequest;
use frond_export::AnimationMode;
use frond_export::vat::VatFormat;
use frond_lod::method::ignored_options;
use frond_lod::{
    ChainRequest, CloudOptions, METHOD_NAMES, Method, MethodName, SkeletonOptions, SpectralOptions,
    screen_height_at,
};
use frond_scene::{ImportOptions, InputLimits, Length, Tree, import};

/// A closed set of names as settings, manifests and the command line write them.
pub trait Named: Copy + Sized + 'static {
    /// Every value, in the order help texts list them.
    const ALL: &'static [Self];
    /// The value as written.
    fn text(self) -> &'static str;
    /// The value written `text`, if any.
    fn parse(text: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.text() == text)
    }
    /// Every value as written, comma-separated (for messages).
    fn list() -> String {
        Self::ALL
            .iter()
            .map(|v| v.text())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Declares a [`Named`] enum serialised as its text.
macro_rules! named_enum {
    ($(#[$meta:meta])* $name:ident { $($(#[$vmeta:meta])* $variant:ident = $text:literal),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
        pub enum $name {
            $($(#[$vmeta])* #[serde(rename = $text)] $variant),+
        }
        impl $crate::lod_settings::Named for $name {
            const ALL: &'static [Self] = &[$($name::$variant),+];
            fn text(self) -> &'static str {
                match self {
                    $($name::$variant => $text),+
                }
            }
        }
    };
}
pub(crate) use named_enum;

named_enum! {
    /// How billboards are animated in the written files.
    Animation {
        /// glTF skin and channels.
        Skin = "skin",
        /// Vertex animation textures, EXR half floats.
        Vat = "vat",
        /// Vertex animation textures, 16-bit PNG.
        VatPng16 = "vat-png16",
        /// Skinned billboards plus a small float texture of each billboard's cosine terms.
        Spectral = "spectral",
    }
}

named_enum! {
    /// How the textures frond makes (atlases, downscaled maps) are stored.
    Textures {
        /// PNG; engines build plain mip chains.
        Png = "png",
        /// KTX2 (Basis Universal UASTC, Zstandard) with alpha-coverage-preserving mips.
        Ktx2 = "ktx2",
        /// KTX2 plus the PNG as fallback for clients without KHR_texture_basisu.
        Ktx2Png = "ktx2-png",
    }
}

named_enum! {
    /// How baked billboards are lit.
    Normals {
        /// The baked normal atlas as the billboards' normalTexture: lit like the leaves.
        Baked = "baked",
        /// Vertex normals pointing away from the crown's centre, no normal map.
        Crown = "crown",
        /// One flat normal per quad.
        Flat = "flat",
    }
}

named_enum! {
    /// How the far end (impostor-class LODs) draws its billboards' alpha.
    FarAlpha {
        /// Alpha-tested (glTF MASK): the bake keeps the leaves' coverage by threshold, for an
        /// engine that draws it with alpha-to-coverage.
        Mask = "mask",
        /// Each texel's alpha is the fraction of it covered, drawn blended (glTF BLEND).
        Blend = "blend",
    }
}

named_enum! {
    /// Which rasteriser bakes the billboard atlases.
    BakeRasteriser {
        /// frond's CPU bake rasteriser: the same atlas on every machine.
        Cpu = "cpu",
        /// The wgpu renderer (the atlas is then the adapter's).
        Wgpu = "wgpu",
    }
}

named_enum! {
    /// The space vertex-animation data is baked in.
    VatSpace {
        /// The glTF file's space (right-handed, +Y up, metres): frond's own shaders.
        Gltf = "gltf",
        /// Unity's, as glTFast and UnityGLTF import the mesh (x mirrored, v flipped).
        Unity = "unity",
        /// Unreal's (Z up, left-handed, centimetres).
        Unreal = "unreal",
    }
}

named_enum! {
    /// An engine preset (docs/engines.md; [`crate::engine_preset::PRESETS`]).
    Engine {
        /// Unity (glTFast, UnityGLTF).
        Unity = "unity",
        /// Unreal Engine 5 (Interchange).
        Unreal = "unreal",
        /// Godot.
        Godot = "godot",
        /// three.js and the web.
        Web = "web",
    }
}

impl Animation {
    /// How the chain builder counts the billboards' joints.
    pub fn billboards(self) -> frond_lod::joint_budget::BillboardAnimation {
        use frond_lod::joint_budget::BillboardAnimation as B;
        match self {
            Animation::Skin => B::Joints,
            Animation::Vat | Animation::VatPng16 => B::Vat,
            Animation::Spectral => B::Spectral,
        }
    }

    /// How the files animate billboards.
    pub fn mode(self) -> AnimationMode {
        match self {
            Animation::Skin => AnimationMode::Skin,
            Animation::Vat => AnimationMode::Vat(VatFormat::ExrHalf),
            Animation::VatPng16 => AnimationMode::Vat(VatFormat::Png16),
            Animation::Spectral => AnimationMode::Spectral,
        }
    }
}

impl Textures {
    /// The export stage's setting.
    pub fn format(self) -> frond_export::TextureFormat {
        match self {
            Textures::Png => frond_export::TextureFormat::Png,
            Textures::Ktx2 => frond_export::TextureFormat::Ktx2,
            Textures::Ktx2Png => frond_export::TextureFormat::Ktx2Png,
        }
    }
}

impl Normals {
    /// The export stage's setting.
    pub fn normals(self) -> frond_export::BillboardNormals {
        match self {
            Normals::Baked => frond_export::BillboardNormals::Baked,
            Normals::Crown => frond_export::BillboardNormals::Crown,
            Normals::Flat => frond_export::BillboardNormals::Flat,
        }
    }
}

impl BakeRasteriser {
    /// The bake's setting.
    pub fn rasteriser(self) -> frond_billboard::BakeRasteriser {
        match self {
            BakeRasteriser::Cpu => frond_billboard::BakeRasteriser::Cpu,
            BakeRasteriser::Wgpu => frond_billboard::BakeRasteriser::Wgpu,
        }
    }
}

impl VatSpace {
    /// The export stage's setting.
    pub fn space(self) -> frond_export::vat::VatSpace {
        match self {
            VatSpace::Gltf => frond_export::vat::VatSpace::Gltf,
            VatSpace::Unity => frond_export::vat::VatSpace::Unity,
            VatSpace::Unreal => frond_export::vat::VatSpace::Unreal,
        }
    }
}

/// A clustering method as written (`spectral`, `per-bone`, ...): one entry of
/// [`METHOD_NAMES`], kept as written so that `spectral` and `spectral-axis-phase` stay distinct
/// values that name the same method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodChoice(usize);

impl MethodChoice {
    /// `auto`.
    pub const AUTO: MethodChoice = MethodChoice(0);

    /// Every value, in [`METHOD_NAMES`] order.
    pub fn all() -> impl Iterator<Item = MethodChoice> {
        (0..METHOD_NAMES.len()).map(MethodChoice)
    }

    /// The value as written.
    pub fn text(self) -> &'static str {
        METHOD_NAMES[self.0].0
    }

    /// The method it names.
    pub fn method(self) -> MethodName {
        METHOD_NAMES[self.0].1
    }

    /// The value that names `method` in full (`spectral-axis-phase`, not `spectral`).
    pub fn named(method: MethodName) -> MethodChoice {
        METHOD_NAMES
            .iter()
            .position(|(n, _)| *n == method.name())
            .map_or(MethodChoice::AUTO, MethodChoice)
    }

    /// The value written `text`, if any.
    pub fn parse(text: &str) -> Option<MethodChoice> {
        METHOD_NAMES
            .iter()
            .position(|(n, _)| *n == text)
            .map(MethodChoice)
    }

    /// Every value as written, comma-separated (for messages).
    pub fn list() -> String {
        Self::all().map(|m| m.text()).collect::<Vec<_>>().join(", ")
    }
}

impl Serialize for MethodChoice {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.text())
    }
}

impl<'de> Deserialize<'de> for MethodChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<MethodChoice, D::Error> {
        let text = String::deserialize(d)?;
        MethodChoice::parse(&text).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown method '{text}' (one of {})",
                MethodChoice::list()
            ))
        })
    }
}

/// A [`Length`] as its text (`0.5`, `2%`).
mod length_text {
    use super::Length;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &Option<Length>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(l) => s.serialize_some(&l.to_string()),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Length>, D::Error> {
        Option::<String>::deserialize(d)?
            .map(|t| t.parse().map_err(serde::de::Error::custom))
            .transpose()
    }
}

/// How a tree is read: materials named as foliage or wood over the classification heuristics,
/// and what reading it may cost.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReadSettings {
    /// Materials treated as foliage.
    pub foliage_materials: Vec<String>,
    /// Materials treated as wood.
    pub wood_materials: Vec<String>,
    /// What reading one input may cost.
    pub limits: InputLimits,
}

impl ReadSettings {
    /// Reads the tree at `input`.
    pub fn load(&self, input: &Path) -> Result<Tree> {
        let options = ImportOptions {
            foliage_materials: self.foliage_materials.clone(),
            wood_materials: self.wood_materials.clone(),
            limits: self.limits,
            ..Default::default()
        };
        Ok(import(input, &options)?)
    }
}

/// Seed and loop sampling, shared by the commands that build billboards.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sampling {
    /// Random seed: same input and seed, same files.
    pub seed: u64,
    /// Animation samples over the loop.
    pub samples: usize,
    /// Clip to sample (None: the first).
    pub clip: Option<String>,
}

impl Default for Sampling {
    fn default() -> Sampling {
        Sampling {
            seed: 1,
            samples: 64,
            clip: None,
        }
    }
}

/// Plane search, bake and method options of a build.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildSettings {
    /// Candidate planes per iteration of the plane search.
    pub planes: usize,
    /// Favour billboards seen from this elevation in degrees.
    pub view_penalty: Option<f32>,
    /// Bake every triangle valid for a plane, not only its own.
    pub increased_density: bool,
    /// Supersamples per texel side when baking.
    pub supersample: u32,
    /// Rasteriser of the billboard atlases.
    pub bake_rasteriser: BakeRasteriser,
    /// Spectral methods: animation clusters per LOD (None: one per 10 pixels of height).
    pub clusters: Option<u64>,
    /// Spectral methods: animation zone size.
    #[serde(with = "length_text")]
    pub zone_size: Option<Length>,
    /// Spectral methods: bind billboards to a shared bone.
    pub shared_bone: bool,
    /// Skeleton methods: billboard clouds per LOD.
    pub clouds: Option<u64>,
    /// Skeleton methods: merged bones keep their own animation.
    pub average_bone: bool,
}

impl Default for BuildSettings {
    fn default() -> BuildSettings {
        BuildSettings {
            planes: 100,
            view_penalty: None,
            increased_density: false,
            supersample: 4,
            bake_rasteriser: BakeRasteriser::Cpu,
            clusters: None,
            zone_size: None,
            shared_bone: true,
            clouds: None,
            average_bone: false,
        }
    }
}

impl BuildSettings {
    /// The spectral and skeleton methods' options (description types at their defaults: the
    /// method name sets them).
    pub fn method_options(&self) -> (SpectralOptions, SkeletonOptions) {
        (
            SpectralOptions {
                clusters: self.clusters.map(|k| k as usize),
                zone_size: self.zone_size,
                shared_bone: self.shared_bone,
                ..Default::default()
            },
            SkeletonOptions {
                clouds: self.clouds.map(|c| c as usize),
                average_bone: self.average_bone,
                ..Default::default()
            },
        )
    }
}

/// The coverage error each LOD should stay within by default (see [`LodSettings::max_error`]):
/// a tenth of the covered area missing or extra at the LOD's own size, the far end's target.
pub const DEFAULT_MAX_ERROR: f32 = 0.10;

/// The screen heights (pixels) of the LODs `frond lod` and `frond sweep` build by default, one
/// each, nearest first: 600 px (a tree close by), 200 and 60 px. The far end (32 px or less)
/// is asked for with `--lods`, until its error meets the far end's target on every tree.
pub const DEFAULT_LODS: [f32; 3] = [600.0, 200.0, 60.0];

/// [`DEFAULT_LODS`] as `--lods` is written (the command line's default; a test holds the two
/// equal).
pub const DEFAULT_LODS_TEXT: &str = "600,200,60";

/// Everything one `frond lod` run is asked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodSettings {
    /// The input tree (.glb or .gltf).
    pub input: PathBuf,
    /// The output folder.
    pub output: PathBuf,
    /// How the tree is read.
    pub read: ReadSettings,
    /// How each LOD's foliage is built.
    pub method: MethodChoice,
    /// Screen heights in pixels the whole tree covers, one LOD each, nearest first.
    pub lods: Vec<f32>,
    /// LODs by viewing distance instead (world units), with `fov` and `resolution`.
    pub distances: Option<Vec<f32>>,
    /// Vertical field of view in degrees.
    pub fov: f32,
    /// Image height in pixels (distances, MSFT_screencoverage, switch values).
    pub resolution: f32,
    /// Screen-space error budget in pixels.
    pub pixel_error: f32,
    /// An ε given instead of derived.
    #[serde(with = "length_text")]
    pub epsilon: Option<Length>,
    /// Most triangles each LOD keeps of the one before it.
    pub triangle_ratio: f32,
    /// Skin joints every LOD may keep (None: one per 2 pixels of its height).
    #[serde(default)]
    pub max_joints: Option<usize>,
    /// Coverage error each LOD should stay within at its own screen height.
    pub max_error: f32,
    /// Measure each LOD's error after writing it.
    pub measure: bool,
    /// Write the preview page.
    pub preview: bool,
    /// The preview's viewer scripts' path relative to the output folder (None: written with
    /// the set).
    pub preview_viewer: Option<String>,
    /// Keep each LOD within the cost budgets (off only for experiments).
    pub cost_budgets: bool,
    /// How billboards are animated.
    pub animation: Animation,
    /// Seed and loop sampling.
    pub sampling: Sampling,
    /// Plane search, bake and method options.
    pub build: BuildSettings,
    /// Largest atlas side per LOD.
    pub max_atlas: u32,
    /// Dilated texels around each billboard texture.
    pub padding: u32,
    /// How the far end draws its billboards' alpha.
    #[serde(default = "default_far_alpha")]
    pub far_alpha: FarAlpha,
    /// Add MSFT_lod (with MSFT_screencoverage) to the combined file.
    pub msft_lod: bool,
    /// Write textures as files next to the GLBs.
    pub external_textures: bool,
    /// How frond's own textures are stored.
    pub textures: Textures,
    /// How baked billboards are lit.
    pub billboard_normals: Normals,
    /// Name clips with Godot's loop import hint.
    pub loop_hint: bool,
    /// Compress the geometry (EXT_meshopt_compression, KHR_mesh_quantization).
    pub compress: bool,
    /// The space vertex-animation data is baked in.
    pub vat_space: VatSpace,
    /// An engine's conventions, applied by [`crate::engine_preset::with_preset`].
    pub preset: Option<Engine>,
}

/// The far end's alpha by default: alpha-tested. Blended covered fractions score a lower
/// coverage error at the far end, but their coverage changes less over the loop than the
/// alpha-tested bake's, below the far end's target on most trees, so the default waits on
/// the far end's motion (docs/experiments.md, "Covered fractions at the far end").
pub const DEFAULT_FAR_ALPHA: FarAlpha = FarAlpha::Mask;

/// The far end's alpha of settings written before it was a setting: alpha-tested, as they
/// were built (whatever [`DEFAULT_FAR_ALPHA`] is now).
fn default_far_alpha() -> FarAlpha {
    FarAlpha::Mask
}

impl LodSettings {
    /// A run of `input` into `output`, every option at its default.
    pub fn defaults(input: &Path, output: &Path) -> LodSettings {
        LodSettings {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            read: ReadSettings::default(),
            method: MethodChoice::AUTO,
            lods: DEFAULT_LODS.to_vec(),
            distances: None,
            fov: 60.0,
            resolution: 1080.0,
            pixel_error: 1.0,
            epsilon: None,
            triangle_ratio: 0.5,
            max_joints: None,
            max_error: DEFAULT_MAX_ERROR,
            measure: true,
            preview: true,
            preview_viewer: None,
            cost_budgets: true,
            animation: Animation::Skin,
            sampling: Sampling::default(),
            build: BuildSettings::default(),
            max_atlas: 4096,
            padding: 2,
            far_alpha: DEFAULT_FAR_ALPHA,
            msft_lod: false,
            external_textures: false,
            textures: Textures::Png,
            billboard_normals: Normals::Baked,
            loop_hint: false,
            compress: false,
            vat_space: VatSpace::Gltf,
            preset: None,
        }
    }

    /// Reads the input tree.
    pub fn load(&self) -> Result<Tree> {
        self.read.load(&self.input)
    }

    /// What the settings ask of the library for `tree`: screen heights from `lods` or from
    /// `distances`, the method with its options. Warns about options the method ignores.
    pub fn request(&self, tree: &Tree) -> Result<LodRequest> {
        let screen_heights = match &self.distances {
            Some(d) => {
                let h = tree.height();
                d.iter()
                    .map(|&z| {
                        if !(z.is_finite() && z > 0.0) {
                            anyhow::bail!("the distances: {z} is not a positive distance");
                        }
                        Ok(screen_height_at(h, z, self.fov, self.resolution))
                    })
                    .collect::<Result<Vec<_>>>()?
            }
            None => self.lods.clone(),
        };
        let name = self.method.method();
        let (spectral, skeleton) = self.build.method_options();
        for w in ignored_options(
            name,
            spectral != SpectralOptions::default(),
            skeleton != SkeletonOptions::default(),
            self.animation == Animation::Spectral,
        ) {
            tracing::warn!("{w}");
        }
        Ok(LodRequest {
            chain: self.chain_request(name, spectral, skeleton, screen_heights)?,
            animation: self.animation.mode(),
            measure: self.measure.then_some(f64::from(self.max_error)),
            preview: self.preview,
            preview_viewer: self.preview_viewer.clone(),
            msft_lod: self.msft_lod,
            resolution: self.resolution,
            fov: self.fov,
            external_textures: self.external_textures,
            textures: self.textures.format(),
            loop_hint: self.loop_hint,
            compress: self.compress,
            vat_space: self.vat_space.space(),
            billboard_normals: self.billboard_normals.normals(),
        })
    }

    /// The chain builder's part of the request.
    fn chain_request(
        &self,
        name: MethodName,
        spectral: SpectralOptions,
        skeleton: SkeletonOptions,
        screen_heights: Vec<f32>,
    ) -> Result<ChainRequest> {
        let build = &self.build;
        Ok(ChainRequest {
            method: Method::new(name, spectral, skeleton)?,
            screen_heights,
            pixel_error: self.pixel_error,
            epsilon: self.epsilon,
            animation: self.animation.billboards(),
            seed: self.sampling.seed,
            triangle_ratio: self.triangle_ratio,
            max_joints: self.max_joints,
            cost_budgets: self.cost_budgets,
            samples: self.sampling.samples,
            clip: self.sampling.clip.clone(),
            cloud: CloudOptions {
                planes: build.planes,
                view_penalty: build.view_penalty.map(f32::to_radians),
                increased_density: build.increased_density,
                max_atlas: self.max_atlas,
                supersample: build.supersample,
                padding: self.padding,
                rasteriser: build.bake_rasteriser.rasteriser(),
                far_blend: self.far_alpha == FarAlpha::Blend,
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_lods_text_is_the_default_lods() {
        let parsed: Vec<f32> = (DEFAULT_LODS_TEXT.split(','))
            .map(|h| h.parse().expect("a number"))
            .collect();
        assert_eq!(parsed, DEFAULT_LODS);
    }

    #[test]
    fn settings_round_trip_through_their_request_file() {
        let mut s = LodSettings::defaults(Path::new("t.glb"), Path::new("out"));
        s.method = MethodChoice::parse("spectral").expect("a method");
        s.epsilon = Some(Length::Percent(2.0));
        s.build.zone_size = Some(Length::World(0.5));
        s.animation = Animation::VatPng16;
        s.preset = Some(Engine::Web);
        s.read.foliage_materials = vec!["Leaf \"1\"".into()];
        let text = serde_json::to_string(&s).expect("writes");
        let back: LodSettings = serde_json::from_str(&text).expect("reads back");
        assert_eq!(back, s);
        assert_eq!(back.method.text(), "spectral", "kept as written");
    }

    #[test]
    fn every_name_parses_back() {
        for m in MethodChoice::all() {
            assert_eq!(MethodChoice::parse(m.text()), Some(m));
            assert_eq!(MethodName::parse(m.text()), Some(m.method()));
            assert_eq!(MethodChoice::named(m.method()).method(), m.method());
        }
        for a in Animation::ALL {
            assert_eq!(Animation::parse(a.text()), Some(*a));
        }
        let engines: Vec<&str> = Engine::ALL.iter().map(|e| e.text()).collect();
        assert_eq!(engines, crate::engine_preset::PRESET_NAMES);
        for e in Engine::ALL {
            assert!(crate::engine_preset::EnginePreset::named(e.text()).is_some());
        }
    }
}
