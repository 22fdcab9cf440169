//! `frond eval ORIGINAL CANDIDATE`: how well a candidate (a `frond lod` LOD, a decimated tree,
//! an artist's LOD) reproduces an animated tree, by the metrics of spec
//! animated-billboard-clouds §5 and App. A, each with its definition in the report.
//!
//! The evaluation itself (matching, metrics, report) is `frond_metrics::eval`; this is the
//! command's glue: which files are the same, and the names the CLI and the sweep use.

use std::path::Path;

pub use frond_metrics::eval::{EvalContext, EvalError, EvalRequest, evaluate};
pub use frond_metrics::report::{Costs, CoverageMetrics, EvalReport, Metric};

/// Whether two files hold the same bytes (the candidate is the original itself): sizes first,
/// so a sweep does not read both files whole for every run.
pub fn same_bytes(a: &Path, b: &Path) -> bool {
    let len = |p: &Path| std::fs::metadata(p).map(|m| m.len()).ok();
    match (len(a), len(b)) {
        (Some(x), Some(y)) if x == y => std::fs::read(a).ok() == std::fs::read(b).ok(),
        _ => false,
    }
}

crate::lod_settings::named_enum! {
    /// How the colour metric's renders are lit.
    Lighting {
        /// 0.6 + 0.4·|n·L|: both sides lit alike.
        TwoSided = "two-sided",
        /// 0.3 + 0.7·max(0, n·L) on the side facing the viewer.
        Lambert = "lambert",
    }
}

impl Lighting {
    /// The renderer's setting.
    pub fn lighting(self) -> frond_render::Lighting {
        match self {
            Lighting::TwoSided => frond_render::Lighting::TwoSided,
            Lighting::Lambert => frond_render::Lighting::Lambert,
        }
    }
}

/// The screen height a candidate is judged at when none is asked, pixels.
pub const DEFAULT_SCREEN_HEIGHT: f32 = 600.0;

/// Everything one `frond eval` run is asked: the two files, how they are read, and the
/// metrics' views, frames, image size, sampling and lighting. Serialisable: `frond batch`
/// writes one for each evaluation it runs as a child.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EvalSettings {
    /// The original tree.
    pub input: std::path::PathBuf,
    /// The candidate (a LOD, any glTF).
    pub candidate: std::path::PathBuf,
    /// How the original is read (the candidate is read with the same limits).
    pub read: crate::lod_settings::ReadSettings,
    /// Ring views of the colour metric.
    pub views: u32,
    /// Frames of the animated colour metric.
    pub frames: u32,
    /// The screen height the tree is judged at: its rest height spans this many pixels
    /// ([`frond_metrics::framing()`]).
    pub screen_height: f32,
    /// The screen's vertical field of view, degrees (as `frond lod --fov`).
    pub fov: f32,
    /// The screen's height, pixels (as `frond lod --resolution`).
    pub resolution: f32,
    /// Samples over the loop for the trajectory metrics.
    pub samples: usize,
    /// Clip (None: the original's first).
    pub clip: Option<String>,
    /// Draw every surface white, so the colour difference is the lighting's alone.
    pub white_albedo: bool,
    /// How the colour metric's renders are lit.
    pub lighting: Lighting,
}

impl EvalSettings {
    /// `candidate` against `input`, every option at its default.
    pub fn defaults(input: &Path, candidate: &Path) -> EvalSettings {
        EvalSettings {
            input: input.to_path_buf(),
            candidate: candidate.to_path_buf(),
            read: crate::lod_settings::ReadSettings::default(),
            views: frond_metrics::DEFAULT_VIEWS,
            frames: frond_metrics::DEFAULT_FRAMES,
            screen_height: DEFAULT_SCREEN_HEIGHT,
            fov: frond_metrics::DEFAULT_FOV_DEG,
            resolution: frond_metrics::DEFAULT_RESOLUTION,
            samples: 64,
            clip: None,
            white_albedo: false,
            lighting: Lighting::TwoSided,
        }
    }

    /// Checks the screen: a height of at least 1 pixel.
    pub fn check(&self) -> anyhow::Result<()> {
        if !(self.screen_height.is_finite() && self.screen_height >= 1.0) {
            anyhow::bail!("the screen height must be at least 1 pixel");
        }
        Ok(())
    }
}

/// Reads both files and evaluates the candidate; `progress` hears what is being done.
pub fn run_eval(settings: &EvalSettings, progress: &dyn Fn(&str)) -> anyhow::Result<EvalReport> {
    settings.check()?;
    let original = settings.read.load(&settings.input)?;
    let limits = settings.read.limits;
    let candidate = frond_scene::import(
        &settings.candidate,
        &frond_scene::ImportOptions {
            allow_empty: true,
            limits,
            ..Default::default()
        },
    )?;
    let same_file = same_bytes(&settings.input, &settings.candidate);
    let req = EvalRequest {
        views: settings.views,
        frames: settings.frames,
        screen_height: settings.screen_height,
        fov_deg: settings.fov,
        resolution: settings.resolution,
        samples: settings.samples,
        clip: settings.clip.clone(),
        limits,
        white_albedo: settings.white_albedo,
        lighting: settings.lighting.lighting(),
    };
    let renderer = frond_render::Renderer::new()?;
    progress(&format!("evaluating {}", settings.candidate.display()));
    Ok(evaluate(&renderer, &original, &candidate, same_file, &req)?)
}
