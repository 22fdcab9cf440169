//! Animated billboard LOD chain: LOD0 (the input) and one LOD per screen height, skinned
//! or vertex-animated, with a combined file, mapping sidecars and `<name>_report.json`.

use std::path::PathBuf;

use anyhow::Result;

use crate::batch::preset::EnginePreset;
use crate::cli::args::{BuildArgs, ImportArgs, RunArgs};
use crate::cli::progress::{Spinner, print_json};
use crate::cli::values::{
    AnimationArg, EngineArg, MethodArg, NormalsArg, TexturesArg, VatSpaceArg,
};
use crate::lod_cmd::{LodRequest, run_lod};
use frond_lod::method::ignored_options;
use frond_lod::{
    ChainRequest, CloudOptions, Method, SkeletonOptions, SpectralOptions, screen_height_at,
};
use frond_render::Renderer;
use frond_scene::Length;

/// `--max-error`'s default.
pub const DEFAULT_MAX_ERROR: f32 = 0.15;

/// `frond lod`.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct LodArgs {
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
    #[arg(long, value_enum, default_value = "auto")]
    pub method: MethodArg,
    /// Screen heights in pixels the whole tree covers, one LOD each, nearest first.
    #[arg(long, value_delimiter = ',', default_value = "600,200,60")]
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
    /// Coverage error each LOD should stay within, seen at its own screen height (frond eval's
    /// `coverage.animated.mean` at `--screen-height H`). Measured on the written files and
    /// reported per LOD; a LOD over it is still written, at its budget, with a warning (budgets
    /// come first). The default is the worst the default card LODs reach at 200 px on the
    /// shared trees (0.14).
    #[arg(long, default_value_t = DEFAULT_MAX_ERROR, value_parser = parse_ratio)]
    pub max_error: f32,
    /// Skip measuring each LOD's error after writing it (the measurement renders the input and
    /// every LOD from five views over five frames at the LOD's size).
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
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub build: BuildArgs,
    /// Largest atlas side per LOD.
    #[arg(long, default_value_t = 4096)]
    pub max_atlas: u32,
    /// Dilated texels around each billboard texture: 2 covers bilinear filtering and the
    /// first mip level, which is all a LOD shown near its own size uses.
    #[arg(long, default_value_t = 2)]
    pub padding: u32,
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
    /// What the arguments ask of the library for `tree`: screen heights from `--lods` or from
    /// `--distances`, the method with its options. Warns about options the method ignores.
    pub fn request(&self, tree: &frond_scene::Tree) -> Result<LodRequest> {
        let screen_heights = match &self.distances {
            Some(d) => {
                let h = tree.height();
                d.iter()
                    .map(|&z| {
                        if !(z.is_finite() && z > 0.0) {
                            anyhow::bail!("--distances: {z} is not a positive distance");
                        }
                        Ok(screen_height_at(h, z, self.fov, self.resolution))
                    })
                    .collect::<Result<Vec<_>>>()?
            }
            None => self.lods.clone(),
        };
        let spectral_animation = self.animation == AnimationArg::Spectral;
        let name = self.method.method();
        let (spectral, skeleton) = self.build.method_options();
        for w in ignored_options(
            name,
            spectral != SpectralOptions::default(),
            skeleton != SkeletonOptions::default(),
            spectral_animation,
        ) {
            tracing::warn!("{w}");
        }
        let build = &self.build;
        Ok(LodRequest {
            chain: ChainRequest {
                method: Method::new(name, spectral, skeleton)?,
                screen_heights,
                pixel_error: self.pixel_error,
                epsilon: self.epsilon,
                animation: self.animation.billboards(),
                seed: self.run.seed,
                triangle_ratio: self.triangle_ratio,
                cost_budgets: !self.no_cost_budgets,
                samples: self.run.samples,
                clip: self.run.clip.clone(),
                cloud: CloudOptions {
                    planes: build.planes,
                    view_penalty: build.view_penalty.map(f32::to_radians),
                    increased_density: build.increased_density,
                    max_atlas: self.max_atlas,
                    supersample: build.supersample,
                    padding: self.padding,
                    rasteriser: build.bake_rasteriser.rasteriser(),
                },
            },
            animation: self.animation.mode(),
            measure: (!self.no_measure).then_some(f64::from(self.max_error)),
            preview: !self.no_preview,
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

    /// The arguments again, as a `frond lod` command line parses them (the subcommand name
    /// first): child runs of `frond sweep` and `frond batch` are built as a [`LodArgs`] and
    /// written with this, so every option has one spelling.
    pub fn to_args(&self) -> Vec<String> {
        let mut a = vec![
            "lod".to_string(),
            self.import.input.display().to_string(),
            "-o".into(),
            self.output.display().to_string(),
        ];
        a.extend(self.option_args());
        a
    }

    /// The options alone (input and output aside), as [`Self::to_args`] writes them.
    pub fn option_args(&self) -> Vec<String> {
        let list = |v: &[f32]| v.iter().map(f32::to_string).collect::<Vec<_>>().join(",");
        let mut a = self.import.option_args();
        a.extend(["--method".into(), self.method.text().into()]);
        match &self.distances {
            Some(d) => a.extend(["--distances".into(), list(d)]),
            None => a.extend(["--lods".into(), list(&self.lods)]),
        }
        a.extend(["--fov".into(), self.fov.to_string()]);
        a.extend(["--resolution".into(), self.resolution.to_string()]);
        a.extend(["--pixel-error".into(), self.pixel_error.to_string()]);
        if let Some(e) = self.epsilon {
            a.extend(["--epsilon".into(), e.to_string()]);
        }
        if let Some(v) = &self.preview_viewer {
            a.extend(["--preview-viewer".into(), v.clone()]);
        }
        a.extend(["--triangle-ratio".into(), self.triangle_ratio.to_string()]);
        a.extend(["--max-error".into(), self.max_error.to_string()]);
        for (flag, on) in [
            ("--no-measure", self.no_measure),
            ("--no-cost-budgets", self.no_cost_budgets),
            ("--no-preview", self.no_preview),
        ] {
            if on {
                a.push(flag.into());
            }
        }
        a.extend(["--animation".into(), self.animation.text().into()]);
        a.extend(self.run.to_args());
        a.extend(self.build.to_args());
        a.extend(["--max-atlas".into(), self.max_atlas.to_string()]);
        a.extend(["--padding".into(), self.padding.to_string()]);
        a.extend(["--textures".into(), self.textures.text().into()]);
        a.extend(["--vat-space".into(), self.vat_space.text().into()]);
        a.extend([
            "--billboard-normals".into(),
            self.billboard_normals.text().into(),
        ]);
        if let Some(p) = self.preset {
            a.extend(["--preset".into(), p.text().into()]);
        }
        for (flag, on) in [
            ("--msft-lod", self.msft_lod),
            ("--loop-hint", self.loop_hint),
            ("--compress", self.compress),
            ("--external-textures", self.external_textures),
            ("--json", self.json),
        ] {
            if on {
                a.push(flag.into());
            }
        }
        a
    }

    /// Parses a `frond lod` command line (the subcommand name first), as [`Self::to_args`]
    /// writes it.
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

    /// `frond lod`'s arguments for `input` into `output`, every option at its default.
    pub fn defaults(input: &std::path::Path, output: &std::path::Path) -> LodArgs {
        let line = [
            std::ffi::OsStr::new("lod"),
            input.as_os_str(),
            std::ffi::OsStr::new("-o"),
            output.as_os_str(),
        ];
        match LodArgs::parse_from(line) {
            Ok(args) => args,
            // Only a required argument could be missing, and both are given.
            Err(e) => unreachable!("frond lod's defaults do not parse: {e}"),
        }
    }

    /// Runs the command.
    pub fn run(mut self) -> Result<()> {
        if let Some(p) = self.preset.and_then(|p| EnginePreset::named(p.text())) {
            p.apply(&mut self)?;
        }
        let tree = self.import.load()?;
        let renderer = Renderer::new()?;
        let req = self.request(&tree)?;
        let bar = Spinner::start();
        let result = run_lod(&renderer, &tree, &req, &self.output, &|m: &str| bar.say(m));
        drop(bar);
        let report = result?;
        if self.json {
            print_json(&report)?;
        } else {
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
                    self.output.display()
                );
            }
        }
        Ok(())
    }
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

    fn parse(args: &[&str]) -> LodArgs {
        LodArgs::parse_from(args).expect("parses")
    }

    #[test]
    fn arguments_round_trip() {
        for line in [
            "lod t.glb -o out",
            "lod t.glb -o out --method spectral --lods 300,75 --epsilon 2% --zone-size 0.5 \
             --clusters 4 --no-shared-bone --animation vat-png16 --seed 7 --clip Wind \
             --samples 32 --msft-lod --external-textures --json --foliage-material Leaf \
             --max-vertices 100 --view-penalty 15 --increased-density",
            "lod t.glb -o out --method skeleton-rotation-spectral --distances 5,20 --fov 45 \
             --clouds 3 --average-bone --max-atlas 2048 --padding 4 --supersample 2 --planes 50",
        ] {
            let line: Vec<&str> = line.split_whitespace().collect();
            let a = parse(&line);
            let again = a.to_args();
            let b = parse(&again.iter().map(String::as_str).collect::<Vec<_>>());
            assert_eq!(a, b, "{line:?} -> {again:?}");
        }
        let d = LodArgs::defaults(std::path::Path::new("t.glb"), std::path::Path::new("o"));
        assert_eq!(d, parse(&["lod", "t.glb", "-o", "o"]));
        assert_eq!(d.method, MethodArg::AUTO);
    }
}
