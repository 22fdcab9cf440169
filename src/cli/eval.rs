//! Compare a candidate (a LOD, any glTF) with the original: coverage, colour
//! difference, distance, orientation and animation metrics, and cost.

use std::path::PathBuf;

use anyhow::Result;

use crate::cli::args::ImportArgs;
use crate::cli::progress::{Spinner, print_json};
use crate::cli::values::LightingArg;
use frond_app::eval_cmd::{Costs, EvalSettings, run_eval};
use frond_scene::input_file::human_bytes;

/// `frond eval`.
#[derive(clap::Args, Clone, Debug)]
pub struct EvalArgs {
    /// The input tree and how it is read.
    #[command(flatten)]
    pub import: ImportArgs,
    /// The candidate model (.glb/.gltf); a `frond lod` LOD's `.mapping.json` beside it
    /// enables the per-triangle metrics.
    pub candidate: PathBuf,
    /// Views per ring of the coverage metrics (two rings: 0° and 30°).
    #[arg(long, default_value_t = frond_metrics::DEFAULT_VIEWS)]
    pub views: u32,
    /// Frames of the animated coverage metrics, uniform over the loop.
    #[arg(long, default_value_t = frond_metrics::DEFAULT_FRAMES)]
    pub frames: u32,
    /// Judge the candidate with the tree seen this many pixels high (its rest height on
    /// screen, as `frond lod` sizes LODs): a LOD at its own size.
    #[arg(long, default_value_t = 600.0)]
    pub screen_height: f32,
    /// Vertical field of view of the screen, degrees (as `frond lod --fov`).
    #[arg(long, default_value_t = 60.0)]
    pub fov: f32,
    /// Height of the screen, pixels (as `frond lod --resolution`).
    #[arg(long, default_value_t = 1080.0)]
    pub resolution: f32,
    /// Samples over the loop for the trajectory metrics.
    #[arg(long, default_value_t = 64)]
    pub samples: usize,
    /// Clip (default: the original's first; the candidate plays the clip of that name).
    #[arg(long)]
    pub clip: Option<String>,
    /// Draw the coverage renders' surfaces white (alpha kept): colour_difference then measures
    /// the lighting alone, how closely the candidate's normals and normal maps light it like
    /// the original under the metric's directional light.
    #[arg(long)]
    pub white_albedo: bool,
    /// How the coverage renders light surfaces: two-sided (0.6 + 0.4·|n·L|, the default) or
    /// lambert (0.3 + 0.7·max(0, n·L) on the side facing the viewer, as engines light
    /// double-sided foliage).
    #[arg(long, value_enum, default_value_t = LightingArg::TwoSided)]
    pub lighting: LightingArg,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

impl EvalArgs {
    /// The settings the application takes.
    pub fn settings(&self) -> Result<EvalSettings> {
        Ok(EvalSettings {
            input: self.import.input.clone(),
            candidate: self.candidate.clone(),
            read: self.import.read(),
            views: self.views,
            frames: self.frames,
            screen_height: self.screen_height,
            fov: self.fov,
            resolution: self.resolution,
            samples: self.samples,
            clip: self.clip.clone(),
            white_albedo: self.white_albedo,
            lighting: self.lighting.into(),
        })
    }

    /// Runs the command.
    pub fn run(self) -> Result<()> {
        run_settings(&self.settings()?, self.json)
    }
}

/// Runs `frond eval` with `settings` and prints the report (as JSON with `json`): the command's
/// own run, and a `frond batch` child's.
pub fn run_settings(settings: &EvalSettings, json: bool) -> Result<()> {
    let bar = Spinner::start();
    let result = run_eval(settings, &|m| bar.say(m));
    drop(bar);
    let report = result?;
    if json {
        return print_json(&report);
    }
    crate::say!(
        "at {} px ({} views on rings at {:?}°, {} frames, {}x{} samples a pixel):",
        report.screen_height,
        report.views,
        report.elevations_deg,
        report.frames,
        report.samples_per_side,
        report.samples_per_side
    );
    crate::say!(
        "{:36} {:.5}  (the candidate's covered area over the original's)",
        "coverage ratio",
        report.coverage.ratio
    );
    for id in frond_metrics::metric_id::MetricId::ALL {
        let m = report.metric(id);
        let name = id.label();
        match (m.mean, m.max) {
            (Some(a), Some(b)) => crate::say!("{name:36} mean {a:.5}  max {b:.5}"),
            _ => crate::say!(
                "{name:36} skipped: {}",
                m.skipped_reason.as_deref().unwrap_or("-")
            ),
        }
    }
    print!("{}", super::terminal::safe(&cost_lines(&report.cost)));
    Ok(())
}

fn cost_lines(c: &Costs) -> String {
    let (o, k) = (&c.original, &c.candidate);
    let (of, kf) = (&o.file, &k.file);
    let ratio = if of.alpha_tested_area > 0.0 {
        format!("{:.3}", kf.alpha_tested_area / of.alpha_tested_area)
    } else {
        "-".to_string()
    };
    let mut out = String::from("cost (original → candidate):\n");
    let mut line = |what: &str, a: String, b: String| {
        out.push_str(&format!("  {what:24} {a} → {b}\n"));
    };
    line(
        "triangles",
        of.triangles.to_string(),
        kf.triangles.to_string(),
    );
    line(
        "billboards",
        o.billboards.to_string(),
        k.billboards.to_string(),
    );
    line(
        "joints",
        of.joints_total.to_string(),
        kf.joints_total.to_string(),
    );
    line(
        "animated channels",
        of.animated_channels.to_string(),
        kf.animated_channels.to_string(),
    );
    line(
        "texture decoded/encoded",
        format!(
            "{}/{}",
            human_bytes(of.texture_decoded_bytes),
            human_bytes(of.texture_encoded_bytes)
        ),
        format!(
            "{}/{}",
            human_bytes(kf.texture_decoded_bytes),
            human_bytes(kf.texture_encoded_bytes)
        ),
    );
    line(
        "file bytes",
        human_bytes(of.file_bytes),
        human_bytes(kf.file_bytes),
    );
    line(
        "alpha-tested area",
        format!("{:.4}", of.alpha_tested_area),
        format!("{:.4} (ratio {ratio})", kf.alpha_tested_area),
    );
    out
}
