//! The command line's closed sets of names as `clap::ValueEnum`s: clustering methods, animation
//! modes, drawn parts, sample sizes and engine presets. Each maps to the library's own type.

use clap::ValueEnum;
use clap::builder::PossibleValue;
use frond_export::AnimationMode;
use frond_export::vat::VatFormat;
use frond_lod::{METHOD_NAMES, MethodName};
use frond_render::TreeParts;
use frond_scene::generator::Preset;

/// A `--method` value: one entry of [`METHOD_NAMES`] (by index, so that `spectral` and
/// `spectral-axis-phase` stay distinct values that name the same method).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodArg(usize);

const METHOD_COUNT: usize = METHOD_NAMES.len();

/// Every `--method` value, in [`METHOD_NAMES`] order.
static METHOD_ARGS: [MethodArg; METHOD_COUNT] = {
    let mut all = [MethodArg(0); METHOD_COUNT];
    let mut i = 0;
    while i < METHOD_COUNT {
        all[i] = MethodArg(i);
        i += 1;
    }
    all
};

impl MethodArg {
    /// `auto`.
    pub const AUTO: MethodArg = MethodArg(0);

    /// The value as written (`spectral`, `per-bone`, ...).
    pub fn text(self) -> &'static str {
        METHOD_NAMES[self.0].0
    }
    /// The method it names.
    pub fn method(self) -> MethodName {
        METHOD_NAMES[self.0].1
    }
    /// The value that names `method` in full (`spectral-axis-phase`, not `spectral`).
    pub fn named(method: MethodName) -> MethodArg {
        METHOD_NAMES
            .iter()
            .position(|(n, _)| *n == method.name())
            .map_or(MethodArg::AUTO, MethodArg)
    }
    /// The value written `text`, if any.
    pub fn parse(text: &str) -> Option<MethodArg> {
        METHOD_NAMES
            .iter()
            .position(|(n, _)| *n == text)
            .map(MethodArg)
    }
}

impl ValueEnum for MethodArg {
    fn value_variants<'a>() -> &'a [Self] {
        &METHOD_ARGS
    }
    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.text()))
    }
}

/// An `--animation` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AnimationArg {
    /// glTF skin and channels.
    Skin,
    /// Vertex animation textures, EXR half floats.
    Vat,
    /// Vertex animation textures, 16-bit PNG.
    #[value(name = "vat-png16")]
    VatPng16,
    /// Skinned billboards plus a small float texture of each billboard's cosine terms.
    Spectral,
}

impl AnimationArg {
    /// How the chain builder counts the billboards' joints.
    pub fn billboards(self) -> frond_lod::joint_budget::BillboardAnimation {
        use frond_lod::joint_budget::BillboardAnimation as B;
        match self {
            AnimationArg::Skin => B::Joints,
            AnimationArg::Vat | AnimationArg::VatPng16 => B::Vat,
            AnimationArg::Spectral => B::Spectral,
        }
    }

    /// How the files animate billboards.
    pub fn mode(self) -> AnimationMode {
        match self {
            AnimationArg::Skin => AnimationMode::Skin,
            AnimationArg::Vat => AnimationMode::Vat(VatFormat::ExrHalf),
            AnimationArg::VatPng16 => AnimationMode::Vat(VatFormat::Png16),
            AnimationArg::Spectral => AnimationMode::Spectral,
        }
    }
    /// The value as written.
    pub fn text(self) -> &'static str {
        match self {
            AnimationArg::Skin => "skin",
            AnimationArg::Vat => "vat",
            AnimationArg::VatPng16 => "vat-png16",
            AnimationArg::Spectral => "spectral",
        }
    }
}

/// A `--textures` value: how the textures frond makes are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TexturesArg {
    /// PNG; engines build plain mip chains.
    #[default]
    Png,
    /// KTX2 (Basis Universal UASTC, Zstandard) with alpha-coverage-preserving mips, through
    /// KHR_texture_basisu (required: three.js with KTX2Loader, glTFast, Babylon.js).
    Ktx2,
    /// KTX2 plus the PNG as fallback for clients without KHR_texture_basisu (Blender, Godot).
    #[value(name = "ktx2-png")]
    Ktx2Png,
}

impl TexturesArg {
    /// The export stage's setting.
    pub fn format(self) -> frond_export::TextureFormat {
        match self {
            TexturesArg::Png => frond_export::TextureFormat::Png,
            TexturesArg::Ktx2 => frond_export::TextureFormat::Ktx2,
            TexturesArg::Ktx2Png => frond_export::TextureFormat::Ktx2Png,
        }
    }

    /// The value as written.
    pub fn text(self) -> &'static str {
        match self {
            TexturesArg::Png => "png",
            TexturesArg::Ktx2 => "ktx2",
            TexturesArg::Ktx2Png => "ktx2-png",
        }
    }
}

/// A `--billboard-normals` value: how baked billboards are lit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum NormalsArg {
    /// The baked normal atlas as the billboards' normalTexture: lit like the leaves.
    #[default]
    Baked,
    /// Vertex normals pointing away from the crown's centre, no normal map.
    Crown,
    /// One flat normal per quad.
    Flat,
}

impl NormalsArg {
    /// The export stage's setting.
    pub fn normals(self) -> frond_export::BillboardNormals {
        match self {
            NormalsArg::Baked => frond_export::BillboardNormals::Baked,
            NormalsArg::Crown => frond_export::BillboardNormals::Crown,
            NormalsArg::Flat => frond_export::BillboardNormals::Flat,
        }
    }

    /// The value as written.
    pub fn text(self) -> &'static str {
        match self {
            NormalsArg::Baked => "baked",
            NormalsArg::Crown => "crown",
            NormalsArg::Flat => "flat",
        }
    }
}

/// A `--lighting` value of `frond eval`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum LightingArg {
    /// 0.6 + 0.4·|n·L|: both sides lit alike.
    #[default]
    TwoSided,
    /// 0.3 + 0.7·max(0, n·L) on the side facing the viewer.
    Lambert,
}

impl LightingArg {
    /// The renderer's setting.
    pub fn lighting(self) -> frond_render::Lighting {
        match self {
            LightingArg::TwoSided => frond_render::Lighting::TwoSided,
            LightingArg::Lambert => frond_render::Lighting::Lambert,
        }
    }
}

/// A `--bake-rasteriser` value of `frond lod`, `frond cloud` and `frond sweep`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum BakeRasteriserArg {
    /// frond's CPU bake rasteriser: the same atlas on every machine, whatever the thread
    /// count.
    #[default]
    Cpu,
    /// The wgpu renderer: fast on a GPU (the atlas is then the adapter's).
    Wgpu,
}

impl BakeRasteriserArg {
    /// The bake's setting.
    pub fn rasteriser(self) -> frond_billboard::BakeRasteriser {
        match self {
            BakeRasteriserArg::Cpu => frond_billboard::BakeRasteriser::Cpu,
            BakeRasteriserArg::Wgpu => frond_billboard::BakeRasteriser::Wgpu,
        }
    }

    /// The value as written.
    pub fn text(self) -> &'static str {
        match self {
            BakeRasteriserArg::Cpu => "cpu",
            BakeRasteriserArg::Wgpu => "wgpu",
        }
    }
}

/// A `--vat-space` value of `frond lod`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum VatSpaceArg {
    /// The glTF file's space (right-handed, +Y up, metres): frond's own shaders.
    #[default]
    Gltf,
    /// Unity's, as glTFast and UnityGLTF import the mesh (x mirrored, v flipped): Houdini VAT
    /// 3.0's Unity materials play it unedited.
    Unity,
    /// Unreal's (Z up, left-handed, centimetres): Houdini VAT 3.0's Unreal material functions
    /// play it unedited.
    Unreal,
}

impl VatSpaceArg {
    /// The export stage's setting.
    pub fn space(self) -> frond_export::vat::VatSpace {
        match self {
            VatSpaceArg::Gltf => frond_export::vat::VatSpace::Gltf,
            VatSpaceArg::Unity => frond_export::vat::VatSpace::Unity,
            VatSpaceArg::Unreal => frond_export::vat::VatSpace::Unreal,
        }
    }

    /// The value as written.
    pub fn text(self) -> &'static str {
        match self {
            VatSpaceArg::Gltf => "gltf",
            VatSpaceArg::Unity => "unity",
            VatSpaceArg::Unreal => "unreal",
        }
    }
}

/// A `--parts` value of `frond render`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PartsArg {
    All,
    Wood,
    Foliage,
}

impl From<PartsArg> for TreeParts {
    fn from(p: PartsArg) -> TreeParts {
        match p {
            PartsArg::All => TreeParts::All,
            PartsArg::Wood => TreeParts::Wood,
            PartsArg::Foliage => TreeParts::Foliage,
        }
    }
}

/// A `--preset` value of `frond sample`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SampleSize {
    /// ~2k foliage triangles.
    Small,
    /// ~20k.
    Medium,
    /// ~200k.
    Large,
    /// ~1M.
    Xlarge,
}

impl From<SampleSize> for Preset {
    fn from(s: SampleSize) -> Preset {
        match s {
            SampleSize::Small => Preset::Small,
            SampleSize::Medium => Preset::Medium,
            SampleSize::Large => Preset::Large,
            SampleSize::Xlarge => Preset::Xlarge,
        }
    }
}

/// A `--preset` value of `frond batch` (docs/engines.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum EngineArg {
    Unity,
    Unreal,
    Godot,
    Web,
}

impl EngineArg {
    /// The preset's name in [`crate::batch::preset::PRESET_NAMES`].
    pub fn text(self) -> &'static str {
        match self {
            EngineArg::Unity => "unity",
            EngineArg::Unreal => "unreal",
            EngineArg::Godot => "godot",
            EngineArg::Web => "web",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::preset::{EnginePreset, PRESET_NAMES};

    #[test]
    fn every_value_names_what_the_library_knows() {
        assert_eq!(MethodArg::value_variants().len(), METHOD_NAMES.len());
        for m in MethodArg::value_variants() {
            assert_eq!(MethodArg::parse(m.text()), Some(*m));
            assert_eq!(MethodName::parse(m.text()), Some(m.method()));
        }
        assert_eq!(MethodArg::AUTO.method(), MethodName::AUTO);
        for (_, m) in METHOD_NAMES {
            assert_eq!(MethodArg::named(*m).method(), *m);
            assert_eq!(MethodArg::named(*m).text(), m.name());
        }
        for a in AnimationArg::value_variants() {
            let v = a.to_possible_value().expect("value");
            assert_eq!(v.get_name(), a.text());
        }
        let engines: Vec<&str> = EngineArg::value_variants()
            .iter()
            .map(|e| e.text())
            .collect();
        assert_eq!(engines, PRESET_NAMES);
        for e in EngineArg::value_variants() {
            assert!(EnginePreset::named(e.text()).is_some());
        }
    }
}
