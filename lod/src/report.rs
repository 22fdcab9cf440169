//! What `<name>_report.json` says about a chain and each of its LODs. The chain builder fills
//! what it knows (sizes, method, budgets, what was dropped); export fills the files it wrote
//! (names, joints, animation textures).

use serde::Serialize;

use crate::cloud_build::BuildTimings;
use crate::methods::spectral::SpectralReport;
use crate::motion_budget::Dropped;
use frond_skeleton::SkeletonReport;

/// One LOD's line of `<name>_report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LodEntry {
    pub file: String,
    pub mapping: Option<String>,
    /// Pixels the tree covers (None for LOD0, the input itself).
    pub screen_height: Option<f32>,
    pub pixel: Option<f32>,
    pub epsilon: Option<f32>,
    pub method: String,
    pub method_reason: String,
    /// Triangles drawn (wood plus two per billboard).
    pub triangles: usize,
    pub wood_triangles: usize,
    pub billboards: usize,
    /// Billboards that copy one input card with its own texture instead of a baked one (the
    /// hybrid cloud: only planes that merge several cards are baked).
    pub input_textured_billboards: usize,
    /// Joints of the LOD's skin.
    pub bones: usize,
    pub texture_bytes: usize,
    pub atlas: Option<[u32; 2]>,
    pub texels_per_unit: Option<f32>,
    pub density_reduced: bool,
    /// What the written file costs an engine (read back from it; see `frond_scene::file_cost`).
    pub cost: Option<frond_scene::FileCost>,
    /// When engines should show this LOD (filled by `frond lod` for its `--fov` and
    /// `--resolution`; see [`crate::switching`]).
    #[serde(default)]
    pub switch: Option<crate::switching::SwitchValues>,
    /// Alpha-tested (leaf card or billboard) area relative to LOD0's: the overdraw the foliage
    /// asks for.
    pub alpha_tested_area_ratio: Option<f64>,
    /// What the LOD was allowed to spend (None for LOD0).
    pub budget: Option<crate::cost_budget::LodBudget>,
    /// The LOD's coverage error at its own screen height, measured on the written file (None
    /// for LOD0, or when `frond lod --no-measure` skipped it).
    pub error: Option<MeasuredError>,
    pub clips: Vec<String>,
    pub dropped: DroppedReport,
    pub vat: Option<Vec<String>>,
    /// `--animation spectral`: the coefficient texture and its sidecar.
    pub spectral_files: Option<Vec<String>>,
    /// Bytes of the coefficient texture (`--animation spectral`), or of the VAT textures.
    pub animation_bytes: usize,
    /// `--animation spectral`: what EXR VAT textures of the same LOD would take (encoded, not
    /// written), for comparison.
    pub vat_equivalent_bytes: Option<usize>,
    /// What spectral clustering did (spectral LODs only).
    pub spectral: Option<SpectralReport>,
    /// What skeleton simplification did (skeleton LODs only).
    pub skeleton: Option<SkeletonReport>,
    /// What thinning did (card LODs only).
    pub cards: Option<crate::methods::cards::CardReport>,
    pub timings_s: LodTimings,
}

/// A LOD's animated coverage error (spec animated-billboard-clouds §5.4) at its own screen
/// height: the same number `frond eval INPUT LOD --screen-height H` prints as
/// `coverage.animated.mean` (same views, frames and image size).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasuredError {
    /// Mean over views and frames of (pixels covered by exactly one of the two) / (pixels
    /// the input covers); 0 is perfect.
    pub coverage: f64,
    /// The target it was measured against (`--max-error`).
    pub max_error: f64,
    /// Whether `coverage ≤ max_error`; a LOD over its target is still written, at its budget,
    /// with a warning (issue 17: budgets take precedence over the error target).
    pub within_target: bool,
    /// Image size of the metric: the screen height, 4:3.
    pub image: [u32; 2],
    pub views: u32,
    pub frames: u32,
    /// The foliage's depth complexity at this size (the metric's first view and frame, 4×
    /// supersampled): fragments rasterised per covered sample, each one a fragment-shader run
    /// since alpha-tested surfaces defeat early depth rejection. Overdraw as the GPU pays it.
    pub depth_complexity: f64,
    /// The input's, drawn alike.
    pub input_depth_complexity: f64,
}

/// What a LOD left out, and why.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DroppedReport {
    #[serde(flatten)]
    pub budget: Dropped,
    /// Wood triangles removed, by simplification within `wood_error` world units and with
    /// the pieces dropped.
    pub wood_triangles: usize,
    /// Wood pieces (branch tubes) dropped for being narrower than `wood_error`.
    pub wood_pieces: usize,
    pub wood_error: f32,
    /// Input clips not written, with the reason.
    pub clips: Vec<String>,
}

/// Per-stage wall times of one LOD.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LodTimings {
    #[serde(flatten)]
    pub build: BuildTimings,
    pub budget: f64,
    pub wood: f64,
    pub export: f64,
}

/// `<name>_report.json`.
#[derive(Clone, Debug, Serialize)]
pub struct LodReport {
    pub input: String,
    pub name: String,
    pub clip: Option<String>,
    pub period: f32,
    pub samples: usize,
    pub seed: u64,
    pub pixel_error: f32,
    pub animation: String,
    pub tree_height: f32,
    /// The view the LODs' `switch` values assume (`--fov`, `--resolution`, the tree's bounds).
    pub switching: Option<crate::switching::SwitchView>,
    pub lods: Vec<LodEntry>,
    pub combined: String,
    /// Every file of the set, relative to the output folder, this report last.
    pub files: Vec<String>,
    /// What the import accepted with a warning (silently repaired or ignored input).
    pub warnings: Vec<String>,
    pub timings_s: serde_json::Value,
}

/// Reads one cost off a written file's.
type CostOf = fn(&frond_scene::FileCost) -> f64;

/// The costs the monotone rule compares between consecutive LODs (issue 17 item 3), each with
/// its name in the warnings: what an engine pays, read back from the written files.
const MONOTONE_COSTS: [(&str, CostOf); 9] = [
    ("triangles", |c| c.triangles as f64),
    ("joints per skin", |c| c.joints_per_skin_max as f64),
    ("animated channels", |c| c.animated_channels as f64),
    ("draw calls", |c| c.draw_calls as f64),
    ("materials", |c| c.materials as f64),
    ("decoded texture bytes", |c| c.texture_decoded_bytes as f64),
    ("GPU texture bytes", |c| c.texture_gpu_bytes as f64),
    ("file bytes", |c| c.file_bytes as f64),
    ("alpha-tested area (overdraw)", |c| c.alpha_tested_area),
];

impl LodReport {
    /// One line per cost in which a LOD's written file costs more than the LOD before it (LOD0,
    /// the input, for the first): the chain should never write one, and a method that cannot
    /// keep within a rule (a static cloud's large, mostly transparent quads) is named rather
    /// than hidden. Areas compare within a part in a million (float sums).
    pub fn cost_increases(&self) -> Vec<String> {
        let mut out = Vec::new();
        for pair in self.lods.windows(2) {
            let (Some(before), Some(after)) = (&pair[0].cost, &pair[1].cost) else {
                continue;
            };
            for (name, get) in MONOTONE_COSTS {
                let (b, a) = (get(before), get(after));
                if a > b * (1.0 + 1e-6) {
                    out.push(format!(
                        "{} costs more than {} in {name}: {a} against {b} (the chain's monotone \
                         rule)",
                        pair[1].file, pair[0].file
                    ));
                }
            }
        }
        out
    }
}

/// The report's file name: `<name>_report.json`, so that several trees can share one output
/// folder without their reports colliding.
pub fn report_name(name: &str) -> String {
    format!("{name}_report.json")
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_scene::FileCost;

    fn lod(file: &str, cost: FileCost) -> LodEntry {
        let mut e = crate::chain::entry("cards".into(), String::new());
        e.file = file.into();
        e.cost = Some(cost);
        e
    }

    #[test]
    fn a_lod_costing_more_than_the_one_before_is_named_per_cost() {
        let input = FileCost {
            triangles: 100,
            file_bytes: 1000,
            alpha_tested_area: 2.0,
            ..Default::default()
        };
        let cheaper = FileCost {
            triangles: 50,
            file_bytes: 900,
            alpha_tested_area: 2.0,
            ..Default::default()
        };
        // More quad area and bytes than the LOD before it, though fewer triangles.
        let worse = FileCost {
            triangles: 25,
            file_bytes: 950,
            alpha_tested_area: 3.0,
            ..Default::default()
        };
        let mut report = LodReport {
            input: String::new(),
            name: "t".into(),
            clip: None,
            period: 0.0,
            samples: 0,
            seed: 0,
            pixel_error: 1.0,
            animation: "skin".into(),
            tree_height: 1.0,
            switching: None,
            lods: vec![lod("t_LOD0.glb", input), lod("t_LOD1.glb", cheaper)],
            combined: String::new(),
            files: Vec::new(),
            warnings: Vec::new(),
            timings_s: serde_json::Value::Null,
        };
        assert!(
            report.cost_increases().is_empty(),
            "equal area is no increase"
        );
        report.lods.push(lod("t_LOD2.glb", worse));
        let lines = report.cost_increases();
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(lines[0].starts_with("t_LOD2.glb costs more than t_LOD1.glb in file bytes: 950"));
        assert!(lines[1].contains("alpha-tested area (overdraw): 3 against 2"));
    }
}
