//! Engine presets of `frond batch`: the `frond lod` settings each engine's glTF importer needs,
//! and the checks of each tree's output against the engine's limits (docs/engines.md has the
//! sources and how to import).

use anyhow::{Result, bail};

use crate::lod_settings::LodSettings;
use crate::lod_settings::{Animation, Named, Textures, VatSpace};
use serde::Serialize;

/// One engine's conventions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EnginePreset {
    /// The preset's name (`unity`, `unreal`, `godot`, `web`): what settings and summaries
    /// record.
    pub name: &'static str,
    /// Largest atlas side written (`--max-atlas`).
    pub max_atlas: u32,
    /// Textures as files beside the GLBs (`--external-textures`) rather than embedded (atlases
    /// as PNG, the input's images as they were).
    pub external_textures: bool,
    /// `MSFT_lod` + `MSFT_screencoverage` on the combined file (`--msft-lod`).
    pub msft_lod: bool,
    /// Bone influences per vertex the importer keeps (frond writes at most 4, `JOINTS_0`).
    pub max_influences: u32,
    /// Joints one skin may have before the engine needs a setting changed (None: no limit
    /// documented).
    pub max_joints: Option<usize>,
    /// Whether 16-bit PNG VAT textures reach the shader at 16 bits (`vat`, EXR half, works
    /// everywhere).
    pub png16_vat: bool,
    /// How frond's own textures are stored (`--textures`): KTX2 where the importer transcodes
    /// it.
    pub textures: Textures,
    /// Clip names with the `-loop` import hint (`--loop-hint`): Godot loops only clips so
    /// named.
    pub loop_hint: bool,
    /// Compressed geometry (`--compress`): the importer decodes `EXT_meshopt_compression`.
    pub compress: bool,
    /// The space VAT data is baked in (`--vat-space`): the engine's, for Houdini VAT 3.0's
    /// stock materials.
    pub vat_space: VatSpace,
}

/// What every engine shares: 4 influences, no joint limit known, 16-bit PNG VATs usable.
const COMMON: EnginePreset = EnginePreset {
    name: "",
    max_atlas: 4096,
    external_textures: false,
    msft_lod: false,
    max_influences: 4,
    max_joints: None,
    png16_vat: true,
    textures: Textures::Png,
    loop_hint: false,
    compress: false,
    vat_space: VatSpace::Gltf,
};

/// Every preset, by `--preset` name.
pub const PRESETS: &[EnginePreset] = &[
    // Unity (glTFast, UnityGLTF): external PNGs get Unity's own texture importer (Mip Maps
    // Preserve Coverage, Max Size); UnityGLTF builds the LODGroup from MSFT_lod and keeps 4
    // weights.
    EnginePreset {
        name: "unity",
        external_textures: true,
        msft_lod: true,
        vat_space: VatSpace::Unity,
        ..COMMON
    },
    // Unreal Engine 5 (Interchange): 8192 is the documented texture limit without .ini
    // changes; 8-bit bone indices hold 256 joints per section unless "Support 16-bit Bone
    // Index" is on.
    EnginePreset {
        name: "unreal",
        max_atlas: 8192,
        external_textures: true,
        max_joints: Some(256),
        vat_space: VatSpace::Unreal,
        ..COMMON
    },
    // Godot 4: embedded images are extracted on import; up to 16384 px; generates its own
    // mesh LODs (turn off for billboard LODs), no name convention, no MSFT_lod; clips loop on
    // import only when named `-loop` (Godot 3 and 4 importers).
    EnginePreset {
        name: "godot",
        loop_hint: true,
        ..COMMON
    },
    // three.js / the web: one GLB a LOD (one request), 4096 px (~99 % of WebGL devices), 4
    // weights (JOINTS_0 only); browsers decode 16-bit PNG to 8 bits, so VAT is EXR
    // (EXRLoader, half float).
    // three.js reads KTX2 through KTX2Loader (UASTC transcodes to BC7/ASTC/ETC2): a quarter of
    // RGBA8's GPU memory, and the file's coverage-preserving mips. Geometry meshopt-compressed
    // (GLTFLoader.setMeshoptDecoder, as gltfpack -cc output is read).
    EnginePreset {
        name: "web",
        png16_vat: false,
        textures: Textures::Ktx2,
        compress: true,
        ..COMMON
    },
];

/// `settings` with its engine preset's conventions applied ([`EnginePreset::apply`]);
/// unchanged without a preset.
pub fn with_preset(mut settings: LodSettings) -> Result<LodSettings> {
    if let Some(p) = settings.preset.and_then(|e| EnginePreset::named(e.text())) {
        p.apply(&mut settings)?;
    }
    Ok(settings)
}

/// Every `--preset` name.
pub const PRESET_NAMES: &[&str] = &["unity", "unreal", "godot", "web"];

impl EnginePreset {
    /// The preset called `name`.
    pub fn named(name: &str) -> Option<EnginePreset> {
        PRESETS.iter().copied().find(|p| p.name == name)
    }

    /// Refuses an animation mode this engine cannot play (16-bit PNG VAT in a browser).
    pub fn check_animation(&self, animation: Animation) -> Result<()> {
        if animation == Animation::VatPng16 && !self.png16_vat {
            bail!(
                "preset {}: browsers decode 16-bit PNG textures to 8 bits; use the animation mode vat \
                 (EXR, three.js EXRLoader)",
                self.name
            );
        }
        Ok(())
    }

    /// Sets this preset's `frond lod` options on `args` (atlas size, external textures,
    /// `MSFT_lod`), refusing an animation mode the engine cannot play.
    pub fn apply(&self, args: &mut LodSettings) -> Result<()> {
        self.check_animation(args.animation)?;
        args.max_atlas = self.max_atlas;
        args.external_textures |= self.external_textures;
        args.msft_lod |= self.msft_lod;
        args.loop_hint |= self.loop_hint;
        args.compress |= self.compress;
        if args.vat_space == VatSpace::Gltf {
            args.vat_space = self.vat_space;
        }
        if args.textures == Textures::Png {
            args.textures = self.textures;
        }
        Ok(())
    }

    /// What in a written glTF document breaks this engine's limits: the largest skin's joints,
    /// the influences per vertex its `JOINTS_n` sets give (4 each).
    pub fn check_file(&self, file: &str, doc: &gltf::json::Root) -> Vec<String> {
        use gltf::json::mesh::Semantic;
        use gltf::json::validation::Checked;
        let mut warnings = Vec::new();
        let joints = doc.skins.iter().map(|s| s.joints.len()).max().unwrap_or(0);
        if let Some(max) = self.max_joints
            && joints > max
        {
            warnings.push(format!(
                "{file}: {joints} joints in one skin, over {}'s {max} (enable 16-bit bone \
                 indices, or use --method skeleton with --clouds to merge bones)",
                self.name
            ));
        }
        let sets = doc
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .flat_map(|p| p.attributes.keys())
            .filter_map(|k| match k {
                Checked::Valid(Semantic::Joints(n)) => Some(*n + 1),
                _ => None,
            })
            .max()
            .unwrap_or(0);
        let influences = 4 * sets;
        if influences > self.max_influences {
            warnings.push(format!(
                "{file}: {influences} influences per vertex, over {}'s {}",
                self.name, self.max_influences
            ));
        }
        warnings
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn names_args_and_checks() {
        assert_eq!(
            PRESET_NAMES,
            PRESETS.iter().map(|p| p.name).collect::<Vec<_>>()
        );
        let web = EnginePreset::named("web").unwrap();
        let mut args = LodSettings::defaults(Path::new("t.glb"), Path::new("o"));
        args.max_atlas = 8192;
        args.animation = Animation::VatPng16;
        assert!(web.apply(&mut args.clone()).is_err());
        args.animation = Animation::Skin;
        let mut on_web = args.clone();
        web.apply(&mut on_web).unwrap();
        assert_eq!(
            (on_web.max_atlas, on_web.external_textures, on_web.msft_lod),
            (4096, false, false)
        );
        assert_eq!(on_web.textures, Textures::Ktx2);
        let mut on_godot = args.clone();
        EnginePreset::named("godot")
            .unwrap()
            .apply(&mut on_godot)
            .unwrap();
        assert!(on_godot.loop_hint && on_godot.textures == Textures::Png);
        // A format asked for on the command line stays.
        let mut own = args.clone();
        own.textures = Textures::Ktx2Png;
        web.apply(&mut own).unwrap();
        assert_eq!(own.textures, Textures::Ktx2Png);
        let unity = EnginePreset::named("unity").unwrap();
        args.animation = Animation::Vat;
        unity.apply(&mut args).unwrap();
        assert_eq!(
            (args.max_atlas, args.external_textures, args.msft_lod),
            (4096, true, true)
        );
        let unreal = EnginePreset::named("unreal").unwrap();
        let doc = |joints: usize, sets: &[&str]| {
            let attributes: Vec<String> = sets.iter().map(|s| format!("\"{s}\": 0")).collect();
            let text = format!(
                r#"{{"asset": {{"version": "2.0"}},
                    "skins": [{{"joints": [{}]}}, {{"joints": [0]}}],
                    "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, {}}}}}]}}]}}"#,
                vec!["0"; joints].join(","),
                attributes.join(",")
            );
            gltf::json::Root::from_str(&text).unwrap()
        };
        assert!(
            unreal
                .check_file("a.glb", &doc(256, &["JOINTS_0"]))
                .is_empty()
        );
        let w = unreal.check_file("a.glb", &doc(300, &["JOINTS_0", "JOINTS_1"]));
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("300 joints"), "{w:?}");
        assert!(w[1].contains("8 influences"), "{w:?}");
        // No joint limit known for Godot; influences still checked.
        let godot = EnginePreset::named("godot").unwrap();
        assert!(
            godot
                .check_file("a.glb", &doc(300, &["JOINTS_0"]))
                .is_empty()
        );
    }
}
