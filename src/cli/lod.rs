//! Animated billboard LOD chain: LOD0 (the input) and one LOD per screen height, skinned
//! or vertex-animated, with a combined file, mapping sidecars and `<name>_report.json`.

use std::path::PathBuf;

use anyhow::Result;

use crate::cli::args::{BuildArgs, ImportArgs, RunArgs};
use crate::cli::progress::{Spinner, print_json};
use crate::cli::values::{
    AnimationArg, EngineArg, FarAlphaArg, MethodArg, NormalsArg, TexturesArg, VatSpaceArg,
};
use frond_app::lod_cmd::run_lod;
use frond_app::lod_settings::{
    DEFAULT_FAR_ALPHA, DEFAULT_LODS_TEXT, DEFAULT_MAX_ERROR, LodSettings, MethodChoice,
};
use frond_render::Renderer;
use frond_scene::Length;

/// `frond lod`.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct LodArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// How each LOD's foliage is built: auto (cards for a tree of single leaf cards, else
    /// skeleton then static; see the README's rule), cards (the input's own leaf cards,
    /// thinned to the triangle budget), per-bone, static, spectral (SCA with the axis-phase
    /// type; spectral-naive, spectral-dominating-axis and spectral-axis-phase name the type)
    /// or skeleton (SBCS with the axis-angle bone type; skeleton-axis-angle and
    /// skeleton-rotation-spectral name the type).
    #[arg(long, value_enum, default_value_t = MethodArg(MethodChoice::AUTO))]
    pub method: MethodArg,
    /// Screen heights in pixels the whole tree covers, one LOD each, nearest first.
    #[arg(long, value_delimiter = ',', default_value = DEFAULT_LODS_TEXT)]
    pub lods: Vec<f32>,
    /// LODs by viewing distance instead (world units), with --fov and --resolution.
    #[arg(long, value_delimiter = ',', conflicts_with = "lods")]
    pub distances: Option<Vec<f32>>,
    /// Vertical field of view in degrees (for --distances).
    #[arg(long, default_value_t = 60.0)]
    pub fov: f32,
    /// Image height in pixels (for --distances, MSFT_screencoverage and the report's switch
    /// values; --fov too).
    #[arg(long, default_value_t = 1080.0)]
    pub resolution: f32,
    /// Screen-space error budget in pixels.
    #[arg(long, default_value_t = 1.0)]
    pub pixel_error: f32,
    /// Override the derived ε: a length, or a percentage of the bounding-box diagonal.
    #[arg(long)]
    pub epsilon: Option<Length>,
    /// Most triangles each LOD keeps of the one before it (0.5: at most half). The plane
    /// search widens ε and the wood is simplified further until a LOD fits.
    #[arg(long, default_value_t = 0.5, value_parser = parse_ratio)]
    pub triangle_ratio: f32,
    /// Skin joints every LOD may keep, 1–256 (default: one per 2 pixels of its screen height).
    /// Never more than the LOD before it or the input has, nor 8 at the far end; for
    /// experiments with the joint budget.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=256))]
    pub max_joints: Option<u16>,
    /// Coverage error each LOD should stay within, seen at its own screen height (frond eval's
    /// `coverage.animated.mean` at `--screen-height H`): the covered area it misses or adds
    /// over the input's, each pixel counted by the fraction of it covered. Measured on the
    /// written files and reported per LOD; a LOD over it is still written, at its budget, with
    /// a warning (budgets come first).
    #[arg(long, default_value_t = DEFAULT_MAX_ERROR, value_parser = parse_ratio)]
    pub max_error: f32,
    /// Skip measuring each LOD's error after writing it (the measurement renders the input and
    /// every LOD from five views on each of two rings, 0° and 30°, over three frames at the
    /// LOD's size).
    #[arg(long)]
    pub no_measure: bool,
    /// Skip `<name>_preview.html`, the page showing each LOD at its screen size beside LOD0,
    /// its difference, wind flip-book, atlas and costs, with a live three.js view of the
    /// combined file (open it with `frond view OUTDIR`).
    #[arg(long)]
    pub no_preview: bool,
    /// The preview page's viewer scripts are at this path relative to the output folder (and
    /// not written with the set): `frond batch` keeps one copy for all its trees.
    #[arg(long, value_name = "PATH")]
    pub preview_viewer: Option<String>,
    /// Build each LOD at its screen size's ε and texel density alone, without the cost budgets
    /// (for experiments: such LODs may cost more than the input). The hard limits (at most 256
    /// joints per skin, no more than the input's) still hold.
    #[arg(long)]
    pub no_cost_budgets: bool,
    /// skin (glTF skin and channels), vat (vertex animation textures, EXR half), vat-png16,
    /// or spectral (skinned billboards + a small float texture of each billboard's cosine
    /// terms, with reference shaders; spectral and per-bone methods).
    #[arg(long, value_enum, default_value = "skin")]
    pub animation: AnimationArg,
    /// Seed and loop sampling.
    #[command(flatten)]
    pub run: RunArgs,
    /// Plane search, bake and method options.
    #[command(flatten)]
    pub build: BuildArgs,
    /// Largest atlas side per LOD.
    #[arg(long, default_value_t = 4096)]
    pub max_atlas: u32,
    /// Dilated texels around each billboard texture: 2 covers bilinear filtering and the
    /// first mip level, which is all a LOD shown near its own size uses.
    #[arg(long, default_value_t = 2)]
    pub padding: u32,
    /// How the far end (LODs of 32 px or less) draws its billboards' alpha: mask
    /// (alpha-tested, coverage kept by threshold) or blend (each texel's alpha the fraction of
    /// it covered, glTF BLEND).
    #[arg(long, value_enum, default_value_t = FarAlphaArg::from(DEFAULT_FAR_ALPHA))]
    pub far_alpha: FarAlphaArg,
    /// Add MSFT_lod (with MSFT_screencoverage) to the combined file.
    #[arg(long)]
    pub msft_lod: bool,
    /// Write textures as files next to the GLBs instead of embedding them: the atlases as PNG,
    /// the input's own images with their original bytes and type (`.jpg`, `.png`, ...).
    #[arg(long)]
    pub external_textures: bool,
    /// How the textures frond makes (atlases, downscaled maps) are stored; the input's own
    /// images in LOD0 pass through untouched.
    #[arg(long, value_enum, default_value_t = TexturesArg::Png)]
    pub textures: TexturesArg,
    /// How baked billboards are lit: baked (the normal atlas as their normalTexture, so a LOD
    /// lights like its leaves), crown (normals away from the crown's centre, no normal map) or
    /// flat (the quad's own normal).
    #[arg(long, value_enum, default_value_t = NormalsArg::Baked)]
    pub billboard_normals: NormalsArg,
    /// Name clips with Godot's loop import hint (`<clip>-loop`): glTF has no loop flag and
    /// Godot's importer loops only clips so named.
    #[arg(long)]
    pub loop_hint: bool,
    /// Compress the geometry: meshoptimizer-encoded vertex, index and animation data
    /// (EXT_meshopt_compression) with byte normals and short texture coordinates
    /// (KHR_mesh_quantization). Smaller files for clients with a meshopt decoder (three.js
    /// with setMeshoptDecoder, Babylon.js, gltfpack's readers); Godot 3 and Blender's importer
    /// cannot read them.
    #[arg(long)]
    pub compress: bool,
    /// The space `--animation vat`/`vat-png16` data is baked in: gltf (frond's shaders), or an
    /// engine's (unity, unreal) so Houdini VAT 3.0's stock materials play it unedited; the
    /// unity and unreal presets set it.
    #[arg(long, value_enum, default_value_t = VatSpaceArg::Gltf)]
    pub vat_space: VatSpaceArg,
    /// Engine conventions (texture format and limits, external textures, MSFT_lod, loop hint,
    /// VAT format checks; docs/engines.md); options given too are kept where the preset only
    /// turns something on.
    #[arg(long, value_enum)]
    pub preset: Option<EngineArg>,
    /// Print the report (`<name>_report.json`) to stdout.
    #[arg(long)]
    pub json: bool,
}

impl LodArgs {
    /// The settings the application takes.
    pub fn settings(&self) -> LodSettings {
        LodSettings {
            input: self.import.input.clone(),
            output: self.output.clone(),
            read: self.import.read(),
            method: self.method.0,
            lods: self.lods.clone(),
            distances: self.distances.clone(),
            fov: self.fov,
            resolution: self.resolution,
            pixel_error: self.pixel_error,
            epsilon: self.epsilon,
            triangle_ratio: self.triangle_ratio,
            max_joints: self.max_joints.map(usize::from),
            max_error: self.max_error,
            measure: !self.no_measure,
            preview: !self.no_preview,
            preview_viewer: self.preview_viewer.clone(),
            cost_budgets: !self.no_cost_budgets,
            animation: self.animation.into(),
            sampling: self.run.sampling(),
            build: self.build.settings(),
            max_atlas: self.max_atlas,
            padding: self.padding,
            far_alpha: self.far_alpha.into(),
            msft_lod: self.msft_lod,
            external_textures: self.external_textures,
            textures: self.textures.into(),
            billboard_normals: self.billboard_normals.into(),
            loop_hint: self.loop_hint,
            compress: self.compress,
            vat_space: self.vat_space.into(),
            preset: self.preset.map(Into::into),
        }
    }

    /// Parses a `frond lod` command line (the subcommand name first).
    pub fn parse_from<I, T>(args: I) -> Result<LodArgs, clap::Error>
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        #[derive(clap::Parser)]
        struct One {
            #[command(flatten)]
            lod: LodArgs,
        }
        <One as clap::Parser>::try_parse_from(args).map(|one| one.lod)
    }

    /// Runs the command.
    pub fn run(self) -> Result<()> {
        run_settings(self.settings(), self.json)
    }
}

/// Runs `frond lod` with `settings` and prints what it wrote (the report as JSON with `json`):
/// the command's own run, and a `frond batch` or `frond sweep` child's.
pub fn run_settings(settings: LodSettings, json: bool) -> Result<()> {
    let settings = frond_app::engine_preset::with_preset(settings)?;
    let tree = settings.load()?;
    let renderer = Renderer::new()?;
    let req = settings.request(&tree)?;
    let bar = Spinner::start();
    let result = run_lod(&renderer, &tree, &req, &settings.output, &|m: &str| {
        bar.say(m)
    });
    drop(bar);
    let report = result?;
    if json {
        return print_json(&report);
    }
    for l in &report.lods {
        crate::say!(
            "{}: {} triangles, {} billboards, {} bones, {} texture bytes ({})",
            l.file,
            l.triangles,
            l.billboards,
            l.bones,
            l.texture_bytes,
            l.method
        );
    }
    crate::say!(
        "{}: {} LODs combined; {}; {:.2} s",
        report.combined,
        report.lods.len(),
        frond_lod::report::report_name(&report.name),
        report.timings_s.total
    );
    if let Some(page) = report
        .files
        .iter()
        .find(|f| *f == &frond_preview::preview_name(&report.name))
    {
        crate::say!(
            "{page}: the preview ({:.2} s); its live view: frond view {}",
            report.timings_s.preview.unwrap_or(0.0),
            settings.output.display()
        );
    }
    Ok(())
}

/// A ratio in (0, 1].
fn parse_ratio(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("expected a number in (0, 1], got '{s}'"))?;
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("expected a number in (0, 1], got {v}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn parse(args: &[&str]) -> LodArgs {
        LodArgs::parse_from(args).expect("parses")
    }

    #[test]
    fn the_flags_default_to_the_applications_settings() {
        let d = parse(&["lod", "t.glb", "-o", "o"]).settings();
        assert_eq!(d, LodSettings::defaults(Path::new("t.glb"), Path::new("o")));
    }

    #[test]
    fn every_flag_reaches_its_setting() {
        let line = "lod t.glb -o out --method spectral --lods 300,75 --epsilon 2% --zone-size 0.5 \
                    --clusters 4 --no-shared-bone --animation vat-png16 --seed 7 --clip Wind \
                    --samples 32 --msft-lod --external-textures --json --foliage-material Leaf \
                    --max-vertices 100 --view-penalty 15 --increased-density --preset web";
        let s = parse(&line.split_whitespace().collect::<Vec<_>>()).settings();
        assert_eq!(s.method.text(), "spectral");
        assert_eq!(s.lods, [300.0, 75.0]);
        assert_eq!(s.epsilon, Some(Length::Percent(2.0)));
        assert_eq!(s.build.zone_size, Some(Length::World(0.5)));
        assert_eq!((s.build.clusters, s.build.shared_bone), (Some(4), false));
        assert_eq!(s.animation, frond_app::lod_settings::Animation::VatPng16);
        assert_eq!((s.sampling.seed, s.sampling.samples), (7, 32));
        assert_eq!(s.sampling.clip.as_deref(), Some("Wind"));
        assert!(s.msft_lod && s.external_textures && s.build.increased_density);
        assert_eq!(s.read.foliage_materials, ["Leaf"]);
        assert_eq!(s.read.limits.max_vertices, 100);
        assert_eq!(s.build.view_penalty, Some(15.0));
        assert_eq!(s.preset, Some(frond_app::lod_settings::Engine::Web));
    }
}
