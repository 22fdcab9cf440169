//! What `<name>_report.json` says about a chain and each of its LODs. The chain builder fills
//! what it knows (sizes, method, budgets, what was dropped); export fills the files it wrote
//! (names, joints, animation textures); `frond lod` the costs, errors and timings it measures.
//! Every type here reads back what it writes: a report read and written again is the same text.

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::cost_budget::LodBudget;
use crate::method_api::{BuildTimings, MethodName, MethodSection};
use crate::motion_budget::Dropped;
use crate::section_value::{SectionError, SectionValue};
use crate::switching::{SwitchValues, SwitchView};

/// One LOD's line of `<name>_report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodEntry {
    /// The LOD's file, relative to the output folder (filled by export).
    pub file: String,
    /// The file mapping the LOD's billboards to the input's triangles (billboard LODs).
    pub mapping: Option<String>,
    /// Pixels the tree covers (None for LOD0, the input itself).
    pub screen_height: Option<f32>,
    /// World units per screen pixel at that size.
    pub pixel: Option<f32>,
    /// Plane tolerance the billboards were searched with (world units).
    pub epsilon: Option<f32>,
    /// The method that built the LOD (`input` for LOD0).
    pub method: MethodName,
    /// Why that method: given by the run, or what `auto`'s rule says.
    pub method_reason: String,
    /// Triangles drawn (wood plus two per billboard).
    pub triangles: usize,
    /// Triangles of the wood among them.
    pub wood_triangles: usize,
    /// Billboards drawn.
    pub billboards: usize,
    /// Billboards that copy one input card with its own texture instead of a baked one (the
    /// hybrid cloud: only planes that merge several cards are baked).
    pub input_textured_billboards: usize,
    /// Joints of the LOD's skin.
    pub bones: usize,
    /// Decoded bytes of the textures the LOD draws with (atlas and the input's images at
    /// the LOD's sizes).
    pub texture_bytes: usize,
    /// Width and height of the billboard atlas, when there is one.
    pub atlas: Option<[u32; 2]>,
    /// Atlas texels per world unit.
    pub texels_per_unit: Option<f32>,
    /// The atlas was baked at a lower density than asked to fit its largest side.
    pub density_reduced: bool,
    /// What the written file costs an engine (read back from it; see `frond_scene::file_cost`).
    pub cost: Option<frond_scene::FileCost>,
    /// When engines should show this LOD (filled by `frond lod` for its `--fov` and
    /// `--resolution`; see [`crate::switching`]).
    #[serde(default)]
    pub switch: Option<SwitchValues>,
    /// Alpha-tested (leaf card or billboard) area relative to LOD0's: the overdraw the foliage
    /// asks for.
    pub alpha_tested_area_ratio: Option<f64>,
    /// What the LOD was allowed to spend (None for LOD0).
    pub budget: Option<LodBudget>,
    /// The LOD's coverage error at its own screen height, measured on the written file (None
    /// for LOD0, or when `frond lod --no-measure` skipped it).
    pub error: Option<MeasuredError>,
    /// Clips the LOD's file plays.
    pub clips: Vec<String>,
    /// What the LOD left out, and why.
    pub dropped: DroppedReport,
    /// `--animation vat`: the vertex animation textures and their sidecar.
    pub vat: Option<Vec<String>>,
    /// `--animation spectral`: the coefficient texture and its sidecar.
    pub spectral_files: Option<Vec<String>>,
    /// Bytes of the coefficient texture (`--animation spectral`), or of the VAT textures.
    pub animation_bytes: usize,
    /// `--animation spectral`: what EXR VAT textures of the same LOD would take (encoded, not
    /// written), for comparison.
    pub vat_equivalent_bytes: Option<usize>,
    /// What the LOD's method reports of its own, one entry key per section (`spectral`,
    /// `skeleton`, `cards`, ...): see [`MethodSections`].
    #[serde(flatten)]
    pub sections: MethodSections,
    /// Seconds per stage of the LOD's build.
    pub timings_s: LodTimings,
}

impl LodEntry {
    /// An empty report line for a LOD built by `method`, for `method_reason`.
    pub fn new(method: MethodName, method_reason: &str) -> LodEntry {
        LodEntry {
            file: String::new(),
            mapping: None,
            screen_height: None,
            pixel: None,
            epsilon: None,
            method,
            method_reason: method_reason.to_string(),
            triangles: 0,
            wood_triangles: 0,
            billboards: 0,
            input_textured_billboards: 0,
            bones: 0,
            texture_bytes: 0,
            atlas: None,
            texels_per_unit: None,
            density_reduced: false,
            cost: None,
            switch: None,
            alpha_tested_area_ratio: None,
            error: None,
            budget: None,
            clips: Vec::new(),
            dropped: DroppedReport::default(),
            vat: None,
            spectral_files: None,
            animation_bytes: 0,
            vat_equivalent_bytes: None,
            sections: MethodSections::default(),
            timings_s: LodTimings::default(),
        }
    }
}

/// The sections every LOD entry writes, `null` where its method reports none: the sections of
/// the methods the report format began with (spectral clustering, skeleton simplification,
/// card thinning), in the order the format has them. Other methods' sections follow them,
/// written only where present.
pub const ALWAYS_WRITTEN_SECTIONS: [&str; 3] = ["spectral", "skeleton", "cards"];

/// The method sections of a LOD entry, written into the entry itself (one key each): the
/// report holds any method's section without naming its type.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MethodSections(Vec<MethodSection>);

impl MethodSections {
    /// Adds a section (one a method returned).
    pub fn push(&mut self, section: MethodSection) {
        self.0.push(section);
    }

    /// The section written under `key`, if any.
    pub fn get(&self, key: &str) -> Option<&SectionValue> {
        self.0.iter().find(|s| s.key == key).map(|s| &s.value)
    }

    /// The section under `key` read as a `T` (`methods::spectral::SpectralReport` for
    /// `spectral`, ...); None when the entry has none.
    pub fn typed<T: serde::de::DeserializeOwned>(
        &self,
        key: &str,
    ) -> Option<Result<T, SectionError>> {
        self.get(key).map(SectionValue::to_typed)
    }

    /// Every section, in the order they were added.
    pub fn iter(&self) -> impl Iterator<Item = &MethodSection> {
        self.0.iter()
    }
}

impl Extend<MethodSection> for MethodSections {
    fn extend<I: IntoIterator<Item = MethodSection>>(&mut self, sections: I) {
        self.0.extend(sections);
    }
}

impl Serialize for MethodSections {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        for key in ALWAYS_WRITTEN_SECTIONS {
            map.serialize_entry(key, &self.get(key))?;
        }
        for section in &self.0 {
            if !ALWAYS_WRITTEN_SECTIONS.contains(&section.key.as_str()) {
                map.serialize_entry(&section.key, &section.value)?;
            }
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for MethodSections {
    /// Reads the entry's keys no field took: each is a section, `null` none.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<MethodSections, D::Error> {
        d.deserialize_map(SectionsVisitor)
    }
}

/// Reads [`MethodSections`] from the keys of an entry.
struct SectionsVisitor;

impl<'de> Visitor<'de> for SectionsVisitor {
    type Value = MethodSections;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("method sections")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<MethodSections, A::Error> {
        let mut sections = MethodSections::default();
        while let Some((key, value)) = map.next_entry::<String, SectionValue>()? {
            if value != SectionValue::Null {
                sections.push(MethodSection { key, value });
            }
        }
        Ok(sections)
    }
}

/// A LOD's animated coverage error (spec animated-billboard-clouds §5.4) at its own screen
/// height: the same number `frond eval INPUT LOD --screen-height H` prints as
/// `coverage.animated.mean` (same views, frames and image size).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeasuredError {
    /// The coverage error at the LOD's own size: per view and frame, the covered area the
    /// LOD misses or adds over the input's covered area (`Σ|α_input − α_LOD| / Σα_input`, α
    /// the covered fraction of each pixel, wood and foliage), then the mean; 0 is perfect
    /// (`frond eval`'s `coverage.animated`).
    pub coverage: f64,
    /// Per view and frame the LOD's covered area over the input's, then the mean: below 1 the
    /// LOD thins out, above 1 it bloats.
    pub coverage_ratio: f64,
    /// The thesis' binary error on the same renders (a pixel covered when at least half of
    /// its samples are, pairs above 1 discarded); None when every pair was discarded.
    pub coverage_binary: Option<f64>,
    /// The switch pop: the coverage error of this LOD against the LOD before it, at this
    /// LOD's size, where the engine swaps them: what a player sees change.
    pub switch_pop: f64,
    /// How much the input's coverage changes over the loop at this size: per view, each
    /// measured frame against the next, the samples that change over those covered, then the
    /// mean (`frond_metrics::coverage::CoverageReport::loop_change_original`); None with one
    /// frame.
    #[serde(default)]
    pub loop_change_input: Option<f64>,
    /// This LOD's change of coverage over the loop over the input's: 1 moves as much as the
    /// tree, 0 stands still; None with one frame or an input that does not move.
    #[serde(default)]
    pub loop_change_ratio: Option<f64>,
    /// The target it was measured against: `--max-error`, or at the far end (an
    /// impostor-class LOD, 32 px or less) the far end's own ([`crate::chain::IMPOSTOR_MAX_ERROR`]).
    pub max_error: f64,
    /// Whether `coverage ≤ max_error`; a LOD over its target is still written, at its budget,
    /// with a warning: budgets take precedence over the error target.
    pub within_target: bool,
    /// Image size of the metric, pixels: the tree's rest height spans the LOD's screen height
    /// in it, seen on the switch values' screen.
    pub image: [u32; 2],
    /// Samples per pixel side of the metric's renders.
    pub samples_per_side: u32,
    /// Views of the metric per ring.
    pub views: u32,
    /// The rings' elevations, degrees (around the tree, and from above).
    pub elevations_deg: Vec<f32>,
    /// Frames of the loop measured per view.
    pub frames: u32,
    /// The foliage's depth complexity at this size (the metric's first view and frame):
    /// fragments rasterised per covered sample, each one a fragment-shader run since
    /// alpha-tested surfaces defeat early depth rejection. Overdraw as the GPU pays it.
    pub depth_complexity: f64,
    /// The input's, drawn alike.
    pub input_depth_complexity: f64,
}

/// The schema version of a report written before versions were.
fn first_version() -> u32 {
    1
}

/// What a LOD left out, and why.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DroppedReport {
    /// What the motion and joint budgets removed or merged.
    #[serde(flatten)]
    pub budget: Dropped,
    /// Wood triangles removed, by simplification within `wood_error` world units and with
    /// the pieces dropped.
    pub wood_triangles: usize,
    /// Wood pieces (branch tubes) dropped for being narrower than `wood_error`.
    pub wood_pieces: usize,
    /// Wood pieces the far end took out of its triangles for being narrower than half a
    /// pixel and baked into its billboards instead (their triangles count in
    /// `wood_triangles`, but they are drawn).
    #[serde(default)]
    pub wood_pieces_baked: usize,
    /// The wood's simplification error (world units).
    pub wood_error: f32,
    /// Input clips not written, with the reason.
    pub clips: Vec<String>,
}

/// Per-stage wall times of one LOD, seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LodTimings {
    /// The method's build.
    #[serde(flatten)]
    pub build: BuildTimings,
    /// Applying the motion and joint budgets.
    pub budget: f64,
    /// Simplifying the wood, and refining it into the room the foliage left.
    pub wood: f64,
    /// Writing the LOD's files.
    pub export: f64,
}

/// Wall times of a whole `frond lod` run, seconds; a stage that did not run is not written.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReportTimings {
    /// Building the LODs in memory (after sampling).
    pub build: f64,
    /// From the build's end (and the input's renders', the later) to the files.
    pub export: f64,
    /// Measuring each LOD's coverage error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measure: Option<f64>,
    /// Drawing the input's renders for the measure, alongside the build.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measure_input: Option<f64>,
    /// Rendering the preview page.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preview: Option<f64>,
    /// Sampling the loop.
    pub sample: f64,
    /// From the start to the files written.
    pub total: f64,
    /// Everything up to the report, measuring and the preview included (set last).
    pub wall: f64,
}

/// The version of `<name>_report.json`'s layout: raised whenever a field changes meaning.
pub const LOD_REPORT_SCHEMA_VERSION: u32 = 3;

/// What a chain's images cost all the instances of a species together: every image a drawn
/// primitive of some LOD's file uses (LOD0 included, the combined file left out), images
/// identical in bytes counted once. Texture memory is shared, so it is judged for the chain
/// as a whole and each LOD against its own budget, not against the LOD before it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TextureMemory {
    /// Distinct images.
    pub images: usize,
    /// Their bytes decoded as RGBA8, without mips.
    pub decoded_bytes: u64,
    /// Their bytes on the GPU, mips included ([`frond_scene::ImageCost::gpu_bytes`]).
    pub gpu_bytes: u64,
}

impl TextureMemory {
    /// The texture memory of `costs` (each LOD file's, read back).
    pub fn of<'a>(costs: impl IntoIterator<Item = &'a frond_scene::FileCost>) -> TextureMemory {
        let mut seen = std::collections::BTreeSet::new();
        let mut memory = TextureMemory::default();
        for image in costs.into_iter().flat_map(|c| &c.images) {
            if image.used && seen.insert(image.sha256.as_str()) {
                memory.images += 1;
                memory.decoded_bytes += image.decoded_bytes;
                memory.gpu_bytes += image.gpu_bytes;
            }
        }
        memory
    }
}

/// `<name>_report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodReport {
    /// The layout's version ([`LOD_REPORT_SCHEMA_VERSION`]; 1 for reports written before it).
    #[serde(default = "first_version")]
    pub schema_version: u32,
    /// The input file.
    pub input: String,
    /// The name the files are prefixed with.
    pub name: String,
    /// The clip the loop was sampled from (None: a tree without clips).
    pub clip: Option<String>,
    /// Loop length in seconds.
    pub period: f32,
    /// Samples over the loop.
    pub samples: usize,
    /// The run's seed.
    pub seed: u64,
    /// The pixel-error budget the LODs were sized with.
    pub pixel_error: f32,
    /// How the files animate billboards.
    pub animation: String,
    /// The tree's height (world units).
    pub tree_height: f32,
    /// The view the LODs' `switch` values assume (`--fov`, `--resolution`, the tree's bounds).
    pub switching: Option<SwitchView>,
    /// LOD0 (the input) first, then each LOD nearest first.
    pub lods: Vec<LodEntry>,
    /// The chain's texture memory over every LOD's file, each image once
    /// ([`TextureMemory`]); absent before the files are read back.
    #[serde(default)]
    pub texture_memory: Option<TextureMemory>,
    /// The file holding every LOD.
    pub combined: String,
    /// Every file of the set, relative to the output folder, this report last.
    pub files: Vec<String>,
    /// What the import accepted with a warning (silently repaired or ignored input).
    pub warnings: Vec<String>,
    /// Seconds per stage of the run.
    pub timings_s: ReportTimings,
}

/// Reads one cost off a written file's.
type CostOf = fn(&frond_scene::FileCost) -> f64;

/// The costs the monotone rule compares between consecutive LODs, each with its name in the
/// warnings: what each drawn instance pays, read back from the written files. Texture and
/// drawn area, which every instance of a species shares, are held to each LOD's own budget
/// instead ([`LodReport::budget_excesses`]).
const MONOTONE_COSTS: [(&str, CostOf); 8] = [
    ("triangles", |c| c.triangles as f64),
    ("vertices", |c| c.vertices as f64),
    ("joints per skin", |c| c.joints_per_skin_max as f64),
    ("animated channels", |c| c.animated_channels as f64),
    ("keyframe bytes", |c| c.keyframe_bytes as f64),
    ("draw calls", |c| c.draw_calls as f64),
    ("materials", |c| c.materials as f64),
    ("file bytes without images", |c| {
        file_bytes_without_images(c) as f64
    }),
];

/// A written file's bytes less its images' (the geometry, skin and animation each drawn
/// instance loads; the images every instance shares are counted by the texture budget).
pub fn file_bytes_without_images(c: &frond_scene::FileCost) -> u64 {
    let images: u64 = c.images.iter().map(|i| i.encoded_bytes).sum();
    c.file_bytes.saturating_sub(images)
}

impl LodReport {
    /// One line per LOD whose written file exceeds its own budget in what all instances of a
    /// species share: its images' decoded bytes over the LOD's texture budget, or its drawn
    /// (alpha-tested or blended) area over the input's. Areas compare within a part in a
    /// million (float sums).
    pub fn budget_excesses(&self) -> Vec<String> {
        let input_area = self.lods.first().and_then(|l| l.cost.as_ref());
        let input_area = input_area.map_or(f64::INFINITY, |c| c.alpha_tested_area);
        let mut out = Vec::new();
        for lod in self.lods.iter().skip(1) {
            let (Some(cost), Some(budget)) = (&lod.cost, &lod.budget) else {
                continue;
            };
            if cost.texture_decoded_bytes > budget.texture_bytes as u64 {
                out.push(format!(
                    "{} decodes {} bytes of texture, over its budget of {}",
                    lod.file, cost.texture_decoded_bytes, budget.texture_bytes
                ));
            }
            if cost.alpha_tested_area > input_area * (1.0 + 1e-6) {
                out.push(format!(
                    "{} draws {} units² alpha-tested or blended, more than the input's {} \
                     (overdraw)",
                    lod.file, cost.alpha_tested_area, input_area
                ));
            }
        }
        out
    }

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
        let mut e = LodEntry::new(MethodName::new("cards"), "");
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
            schema_version: LOD_REPORT_SCHEMA_VERSION,
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
            texture_memory: None,
            combined: String::new(),
            files: Vec::new(),
            warnings: Vec::new(),
            timings_s: ReportTimings::default(),
        };
        assert!(
            report.cost_increases().is_empty(),
            "equal area is no increase"
        );
        report.lods.push(lod("t_LOD2.glb", worse));
        let lines = report.cost_increases();
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(lines[0].starts_with(
            "t_LOD2.glb costs more than t_LOD1.glb in file bytes without images: 950"
        ));
        // More quad area than the LOD before is no increase of what an instance pays; more
        // than the input's is over the LOD's own budget, as are images over its texture budget.
        assert!(report.budget_excesses().is_empty(), "no budgets given");
        for l in &mut report.lods[1..] {
            l.budget = Some(LodBudget {
                texture_bytes: 100,
                ..LodBudget::hard_limits_only(30)
            });
        }
        report.lods[1]
            .cost
            .as_mut()
            .expect("a cost")
            .texture_decoded_bytes = 101;
        let lines = report.budget_excesses();
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].contains("t_LOD1.glb decodes 101 bytes of texture, over its budget of 100")
        );
        assert!(lines[1].contains("t_LOD2.glb draws 3 units²"), "{lines:?}");
    }

    #[test]
    fn texture_memory_counts_each_used_image_once() {
        let image = |sha: &str, bytes: u64, used: bool| frond_scene::ImageCost {
            decoded_bytes: bytes,
            gpu_bytes: bytes * 4 / 3,
            used,
            sha256: sha.into(),
            ..Default::default()
        };
        let lod0 = FileCost {
            images: vec![image("bark", 300, true), image("leaves", 600, true)],
            ..Default::default()
        };
        // The same bark in the next file, an atlas of its own, and an image nothing draws.
        let lod1 = FileCost {
            images: vec![
                image("bark", 300, true),
                image("atlas", 90, true),
                image("unused", 5000, false),
            ],
            ..Default::default()
        };
        assert_eq!(
            TextureMemory::of([&lod0, &lod1]),
            TextureMemory {
                images: 3,
                decoded_bytes: 990,
                gpu_bytes: 400 + 800 + 120,
            }
        );
    }

    #[test]
    fn file_bytes_without_images_leave_out_every_image() {
        let cost = FileCost {
            file_bytes: 1000,
            images: vec![
                frond_scene::ImageCost {
                    encoded_bytes: 300,
                    ..Default::default()
                },
                frond_scene::ImageCost {
                    encoded_bytes: 200,
                    used: false,
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        assert_eq!(file_bytes_without_images(&cost), 500);
    }

    /// A report with every kind of field filled: sections of the three methods and of one
    /// the crate does not know, timings with and without the optional stages, an unbounded
    /// budget (written `null`).
    fn full_report() -> LodReport {
        let mut lod0 = LodEntry::new(MethodName::INPUT, "LOD0 is the input tree, rewritten");
        lod0.file = "t_LOD0.glb".into();
        lod0.cost = Some(FileCost {
            triangles: 100,
            alpha_tested_area: 2.5,
            ..Default::default()
        });
        let mut spectral = LodEntry::new(MethodName::new("spectral-axis-phase"), "given");
        spectral.screen_height = Some(200.0);
        spectral.pixel = Some(0.1);
        spectral.epsilon = Some(0.030000001);
        spectral.atlas = Some([256, 128]);
        spectral.budget = Some(LodBudget::hard_limits_only(30));
        spectral.error = Some(MeasuredError {
            coverage: 0.123456789,
            coverage_ratio: 0.97,
            coverage_binary: None,
            switch_pop: 0.0625,
            loop_change_input: Some(0.05),
            loop_change_ratio: Some(0.875),
            max_error: 0.25,
            within_target: true,
            image: [267, 200],
            samples_per_side: 5,
            views: 8,
            elevations_deg: vec![0.0, 30.0],
            frames: 4,
            depth_complexity: 3.5,
            input_depth_complexity: 7.25,
        });
        spectral.switch = Some(SwitchValues {
            min_screen_fraction: 0.5,
            unity_transition_height: 0.5,
            unreal_screen_size: 0.6,
            begin_distance: 0.0,
            end_distance: 12.5,
        });
        spectral.dropped.wood_error = 0.2;
        spectral.dropped.clips = vec!["sway: only the first".into()];
        spectral.timings_s.build.bake = 0.7;
        spectral.timings_s.wood = 0.01;
        let section = crate::methods::spectral::SpectralReport {
            kind: "axis-phase".into(),
            clusters: 6,
            residual: 0.1,
            error: 0.30000000000000004,
            loops: true,
            ..Default::default()
        };
        spectral
            .sections
            .push(MethodSection::new("spectral", &section).unwrap());
        let mut cards = LodEntry::new(MethodName::new("cards"), "auto: cards");
        let thinned = crate::methods::cards::CardReport {
            cards: 10,
            trimmed: 4,
            kept_as_quads: 1,
            kept: 5,
            scale: 1.2,
        };
        cards
            .sections
            .push(MethodSection::new("cards", &thinned).unwrap());
        let mut other = LodEntry::new(MethodName::new("test-flat"), "given");
        other
            .sections
            .push(MethodSection::new("flat", &[("planes", 1.5f32)]).unwrap());
        LodReport {
            schema_version: LOD_REPORT_SCHEMA_VERSION,
            input: "t.glb".into(),
            name: "t".into(),
            clip: Some("sway".into()),
            period: 2.0,
            samples: 32,
            seed: 7,
            pixel_error: 1.0,
            animation: "skin".into(),
            tree_height: 3.3,
            switching: Some(SwitchView {
                fov_deg: 60.0,
                resolution: 1080.0,
                tree_height: 3.3,
                bounds_size: 3.4,
                sphere_radius: 1.7,
            }),
            lods: vec![lod0, spectral, cards, other],
            texture_memory: Some(TextureMemory {
                images: 2,
                decoded_bytes: 4096,
                gpu_bytes: 5460,
            }),
            combined: "t_lods.glb".into(),
            files: vec!["t_LOD0.glb".into(), "t_report.json".into()],
            warnings: vec!["a warning".into()],
            timings_s: ReportTimings {
                build: 1.25,
                export: 0.5,
                measure: Some(2.0),
                measure_input: None,
                preview: Some(0.75),
                sample: 0.125,
                total: 1.875,
                wall: 4.5,
            },
        }
    }

    #[test]
    fn a_report_read_back_writes_the_same_text() {
        let report = full_report();
        let text = serde_json::to_string_pretty(&report).unwrap();
        let back: LodReport = serde_json::from_str(&text).unwrap();
        assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
        // Every entry has the three sections, null where its method has none, in order; the
        // spectral section reads back as its type.
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        for lod in value["lods"].as_array().unwrap() {
            for key in ALWAYS_WRITTEN_SECTIONS {
                assert!(lod.get(key).is_some(), "{key}");
            }
        }
        assert!(value["lods"][0]["spectral"].is_null());
        assert_eq!(value["lods"][2]["cards"]["kept"], 5);
        assert!(value["lods"][3]["flat"].is_array());
        assert!(value["timings_s"].get("measure_input").is_none());
        let spectral: crate::methods::spectral::SpectralReport =
            back.lods[1].sections.typed("spectral").unwrap().unwrap();
        assert_eq!(spectral.clusters, 6);
        assert_eq!(
            back.lods[1].budget.unwrap().alpha_tested_area,
            f64::INFINITY
        );
        assert_eq!(back.lods[0].method, MethodName::INPUT);
    }

    #[test]
    fn the_timings_keep_their_keys_in_order() {
        let t = serde_json::to_string(&full_report().timings_s).unwrap();
        assert_eq!(
            t,
            r#"{"build":1.25,"export":0.5,"measure":2.0,"preview":0.75,"sample":0.125,"total":1.875,"wall":4.5}"#
        );
    }
}
