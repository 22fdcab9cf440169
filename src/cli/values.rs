//! The command line's closed sets of names as `clap::ValueEnum`s: clustering methods, animation
//! modes, drawn parts, sample sizes and engine presets. Each maps to the library's own type.

use clap::ValueEnum;
use clap::builder::PossibleValue;
use frond_app::eval_cmd::Lighting;
use frond_app::lod_settings::{
    Animation, BakeRasteriser, Engine, FarAlpha, MethodChoice, Normals, Textures, VatSpace,
};
use frond_render::TreeParts;
use frond_scene::generator::Preset;

/// A `--method` value: one of the application's [`MethodChoice`]s (kept as written, so that
/// `spectral` and `spectral-axis-phase` stay distinct values that name the same method).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MethodArg(pub MethodChoice);

/// Every `--method` value, in the library's order.
static METHOD_ARGS: std::sync::LazyLock<Vec<MethodArg>> =
    std::sync::LazyLock::new(|| MethodChoice::all().map(MethodArg).collect());

impl ValueEnum for MethodArg {
    fn value_variants<'a>() -> &'a [Self] {
        &METHOD_ARGS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.text()))
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

impl From<AnimationArg> for Animation {
    fn from(a: AnimationArg) -> Animation {
        match a {
            AnimationArg::Skin => Animation::Skin,
            AnimationArg::Vat => Animation::Vat,
            AnimationArg::VatPng16 => Animation::VatPng16,
            AnimationArg::Spectral => Animation::Spectral,
        }
    }
}

/// A `--textures` value: how the textures frond makes are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
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

impl From<TexturesArg> for Textures {
    fn from(t: TexturesArg) -> Textures {
        match t {
            TexturesArg::Png => Textures::Png,
            TexturesArg::Ktx2 => Textures::Ktx2,
            TexturesArg::Ktx2Png => Textures::Ktx2Png,
        }
    }
}

/// A `--far-alpha` value: how the far end draws its billboards' alpha.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum FarAlphaArg {
    /// Alpha-tested (glTF MASK), coverage kept by threshold: for engines that draw it with
    /// alpha-to-coverage.
    #[default]
    Mask,
    /// Each texel's alpha the fraction of it covered, drawn blended (glTF BLEND).
    Blend,
}

impl From<FarAlphaArg> for FarAlpha {
    fn from(a: FarAlphaArg) -> FarAlpha {
        match a {
            FarAlphaArg::Mask => FarAlpha::Mask,
            FarAlphaArg::Blend => FarAlpha::Blend,
        }
    }
}

impl From<FarAlpha> for FarAlphaArg {
    fn from(a: FarAlpha) -> FarAlphaArg {
        match a {
            FarAlpha::Mask => FarAlphaArg::Mask,
            FarAlpha::Blend => FarAlphaArg::Blend,
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

impl From<NormalsArg> for Normals {
    fn from(n: NormalsArg) -> Normals {
        match n {
            NormalsArg::Baked => Normals::Baked,
            NormalsArg::Crown => Normals::Crown,
            NormalsArg::Flat => Normals::Flat,
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

impl From<LightingArg> for Lighting {
    fn from(l: LightingArg) -> Lighting {
        match l {
            LightingArg::TwoSided => Lighting::TwoSided,
            LightingArg::Lambert => Lighting::Lambert,
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

impl From<BakeRasteriserArg> for BakeRasteriser {
    fn from(b: BakeRasteriserArg) -> BakeRasteriser {
        match b {
            BakeRasteriserArg::Cpu => BakeRasteriser::Cpu,
            BakeRasteriserArg::Wgpu => BakeRasteriser::Wgpu,
        }
    }
}

/// A `--vat-space` value of `frond lod`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
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

impl From<VatSpaceArg> for VatSpace {
    fn from(v: VatSpaceArg) -> VatSpace {
        match v {
            VatSpaceArg::Gltf => VatSpace::Gltf,
            VatSpaceArg::Unity => VatSpace::Unity,
            VatSpaceArg::Unreal => VatSpace::Unreal,
        }
    }
}

/// A `--parts` value of `frond render`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PartsArg {
    /// Wood and foliage.
    All,
    /// The wood alone.
    Wood,
    /// The foliage alone.
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
    /// ~6k, large leaves round a trunk under a pixel wide at 60 px.
    Slender,
}

impl From<SampleSize> for Preset {
    fn from(s: SampleSize) -> Preset {
        match s {
            SampleSize::Small => Preset::Small,
            SampleSize::Medium => Preset::Medium,
            SampleSize::Large => Preset::Large,
            SampleSize::Xlarge => Preset::Xlarge,
            SampleSize::Slender => Preset::Slender,
        }
    }
}

/// A `--preset` value of `frond batch` (docs/engines.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum EngineArg {
    /// Unity (glTFast, UnityGLTF).
    Unity,
    /// Unreal Engine 5 (Interchange).
    Unreal,
    /// Godot.
    Godot,
    /// three.js and the web.
    Web,
}

impl From<EngineArg> for Engine {
    fn from(e: EngineArg) -> Engine {
        match e {
            EngineArg::Unity => Engine::Unity,
            EngineArg::Unreal => Engine::Unreal,
            EngineArg::Godot => Engine::Godot,
            EngineArg::Web => Engine::Web,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_app::lod_settings::Named;

    /// Every value the command line takes names the application's value of the same text.
    fn same_names<A: ValueEnum + Into<B> + Copy, B: Named>() {
        for a in A::value_variants() {
            let name = a
                .to_possible_value()
                .expect("a value")
                .get_name()
                .to_string();
            assert_eq!((*a).into().text(), name);
        }
        assert_eq!(A::value_variants().len(), B::ALL.len());
    }

    #[test]
    fn every_value_names_what_the_application_knows() {
        same_names::<AnimationArg, Animation>();
        same_names::<TexturesArg, Textures>();
        same_names::<NormalsArg, Normals>();
        same_names::<LightingArg, Lighting>();
        same_names::<BakeRasteriserArg, BakeRasteriser>();
        same_names::<VatSpaceArg, VatSpace>();
        same_names::<EngineArg, Engine>();
        let methods: Vec<&str> = MethodArg::value_variants()
            .iter()
            .map(|m| m.0.text())
            .collect();
        assert_eq!(
            methods,
            MethodChoice::all().map(|m| m.text()).collect::<Vec<_>>()
        );
    }
}
