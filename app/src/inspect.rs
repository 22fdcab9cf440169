//! `frond inspect`: what a tree file holds and how frond reads it. The JSON keys are a stable
//! interface (documented in the README).

use frond_scene::sampling::clip_motion;
use frond_scene::{Bounds, Classification, Part, Sampled, Tree};
use serde::{Deserialize, Serialize};

/// Number of poses checked per clip for motion.
const MOTION_SAMPLES: usize = 16;

/// The inspect report.
#[derive(Debug, Serialize, Deserialize)]
pub struct InspectReport {
    /// The tree file's path as it was opened.
    pub file: String,
    /// Triangles by part, as the file holds them (degenerate ones counted).
    pub triangles: TriangleCounts,
    /// Vertices of all mesh instances after import.
    pub vertices: usize,
    /// Bones (skin joints) of the rig.
    pub bones: usize,
    /// Longest chain of bones from a root bone (1 for a root alone, 0 without bones).
    pub skeleton_depth: u32,
    /// Distinct bones that carry foliage.
    pub foliage_bones: usize,
    /// Foliage triangles whose vertices were not all rigidly bound to the one bone chosen for
    /// them (spec §1.3), so that following that bone alone departs from the input's skinning.
    pub foliage_reassigned: usize,
    /// Each primitive's wood/foliage decision and the rule that made it, in file order.
    pub classification: Vec<Classification>,
    /// The file's materials, in file order.
    pub materials: Vec<MaterialSummary>,
    /// The decoded textures, in file order.
    pub textures: Vec<TextureSummary>,
    /// Every animation clip with its loop and motion check.
    pub clips: Vec<ClipSummary>,
    /// Rest-pose world bounds of all triangles (file units, metres in glTF).
    pub bounds: Bounds,
    /// The sampled loop of the chosen clip (`--clip`, `--samples`).
    pub sampling: SamplingSummary,
    /// What the import accepted with a warning (static tree, unsupported channels, …).
    pub warnings: Vec<String>,
}

/// What sampling the chosen clip produced.
#[derive(Debug, Serialize, Deserialize)]
pub struct SamplingSummary {
    /// The sampled clip's name; None for a tree without clips (its rest pose).
    pub clip: Option<String>,
    /// Uniform samples over one period (1 for a static tree or a clip of zero length).
    pub samples: usize,
    /// Loop period in seconds: the clip's duration; 0 for a tree without clips or a clip of
    /// zero length.
    pub period_s: f32,
    /// Non-degenerate foliage triangles with a centre trajectory.
    pub trajectories: usize,
    /// Largest distance of a foliage triangle centre from its mean position.
    pub max_leaf_excursion: f32,
    /// Mean of that distance over foliage triangles.
    pub mean_leaf_excursion: f32,
    /// Whether the clip's last pose matches its first within [`LOOP_TOLERANCE`](frond_scene::sampling::LOOP_TOLERANCE) × tree height,
    /// so the loop plays without a jump.
    pub loops: bool,
    /// Whether any vertex moves more than [`MOTION_TOLERANCE`](frond_scene::sampling::MOTION_TOLERANCE) × tree height over the clip.
    pub moves: bool,
    /// Wall time of the sampling (not part of the stable output).
    pub seconds: f64,
}

impl SamplingSummary {
    /// Summarises a sampled loop that took `seconds`.
    pub fn of(s: &Sampled, seconds: f64) -> Self {
        let n = s.samples();
        let excursions: Vec<f32> = (0..s.foliage.len())
            .map(|k| {
                let tr = s.trajectory(k);
                let mean = tr.iter().copied().sum::<glam::Vec3>() / n as f32;
                tr.iter().map(|p| p.distance(mean)).fold(0.0, f32::max)
            })
            .collect();
        SamplingSummary {
            clip: s.clip.clone(),
            samples: n,
            period_s: s.period,
            trajectories: s.foliage.len(),
            max_leaf_excursion: excursions.iter().copied().fold(0.0, f32::max),
            mean_leaf_excursion: if excursions.is_empty() {
                0.0
            } else {
                excursions.iter().sum::<f32>() / excursions.len() as f32
            },
            loops: s.motion.loops,
            moves: s.motion.moves,
            seconds,
        }
    }
}

/// Triangle counts as the file holds them.
#[derive(Debug, Serialize, Deserialize)]
pub struct TriangleCounts {
    /// All triangles of all primitives.
    pub total: usize,
    /// Triangles classified as wood (trunk and branches).
    pub wood: usize,
    /// Triangles classified as foliage (leaves and cards: what billboards stand for).
    pub foliage: usize,
    /// Triangles of zero area at rest: counted above but skipped by later stages.
    pub degenerate: usize,
}

/// One material.
#[derive(Debug, Serialize, Deserialize)]
pub struct MaterialSummary {
    /// The material's name in the file.
    pub name: String,
    /// glTF alpha mode: opaque, mask (alpha-tested) or blend.
    pub alpha_mode: frond_scene::AlphaMode,
    /// Alpha below which a masked material's texel is discarded (glTF `alphaCutoff`,
    /// 0.5 when the file gives none).
    pub alpha_cutoff: f32,
    /// Whether back faces are drawn too (glTF `doubleSided`).
    pub double_sided: bool,
    /// Name of its base-colour texture ([`TextureSummary::name`]), if it has one.
    pub texture: Option<String>,
}

/// One decoded texture.
#[derive(Debug, Serialize, Deserialize)]
pub struct TextureSummary {
    /// The source image's name in the file, or `image<N>` (its index) when it has none.
    pub name: String,
    /// Width in texels, as decoded.
    pub width: u32,
    /// Height in texels, as decoded.
    pub height: u32,
}

/// One animation clip.
#[derive(Debug, Serialize, Deserialize)]
pub struct ClipSummary {
    /// The clip's name in the file.
    pub name: String,
    /// Length in seconds from its first to its last key: the loop period.
    pub duration_s: f32,
    /// Animation channels (one node property each) the clip drives.
    pub channels: usize,
    /// Whether `loop_gap` is within [`LOOP_TOLERANCE`](frond_scene::sampling::LOOP_TOLERANCE) × tree height, so the clip loops
    /// without a jump.
    pub loops: bool,
    /// Whether `max_displacement` exceeds [`MOTION_TOLERANCE`](frond_scene::sampling::MOTION_TOLERANCE) × tree height.
    pub moves: bool,
    /// Largest vertex distance between the clip's first and last pose (file units).
    pub loop_gap: f32,
    /// Largest vertex distance from the first pose over poses evenly spaced through
    /// the clip (file units).
    pub max_displacement: f32,
}

/// Builds the report for an imported tree and its sampled loop.
pub fn inspect(tree: &Tree, sampling: SamplingSummary) -> InspectReport {
    let clips = (0..tree.rig.clips.len())
        .map(|c| {
            let m = clip_motion(tree, c, MOTION_SAMPLES);
            let clip = &tree.rig.clips[c];
            ClipSummary {
                name: clip.name.clone(),
                duration_s: clip.duration(),
                channels: clip.channels.len(),
                loops: m.loops,
                moves: m.moves,
                loop_gap: m.loop_gap,
                max_displacement: m.max_displacement,
            }
        })
        .collect();
    InspectReport {
        file: tree.source.display().to_string(),
        triangles: TriangleCounts {
            total: tree.triangles.len(),
            wood: tree.count(Part::Wood),
            foliage: tree.count(Part::Foliage),
            degenerate: tree.triangles.iter().filter(|t| t.degenerate).count(),
        },
        vertices: tree.vertices.len(),
        bones: tree.bones.len(),
        skeleton_depth: tree.skeleton_depth(),
        foliage_bones: tree.foliage_bones(),
        foliage_reassigned: tree.foliage_reassigned,
        classification: tree.classification.clone(),
        materials: tree
            .materials
            .iter()
            .map(|m| MaterialSummary {
                name: m.name.clone(),
                alpha_mode: m.alpha_mode,
                alpha_cutoff: m.alpha_cutoff,
                double_sided: m.double_sided,
                texture: m.base_color_texture.map(|t| tree.textures[t].name.clone()),
            })
            .collect(),
        textures: tree
            .textures
            .iter()
            .map(|t| TextureSummary {
                name: t.name.clone(),
                width: t.width,
                height: t.height,
            })
            .collect(),
        clips,
        bounds: tree.bounds,
        sampling,
        warnings: tree.warnings.clone(),
    }
}

impl InspectReport {
    /// Human-readable summary.
    pub fn text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let t = &self.triangles;
        let _ = writeln!(s, "{}", self.file);
        let _ = writeln!(
            s,
            "  triangles: {} total, {} wood, {} foliage, {} degenerate; {} vertices",
            t.total, t.wood, t.foliage, t.degenerate, self.vertices
        );
        let _ = writeln!(
            s,
            "  skeleton: {} bones, depth {}; foliage on {} bones, {} foliage triangles reassigned to one bone",
            self.bones, self.skeleton_depth, self.foliage_bones, self.foliage_reassigned
        );
        for c in &self.classification {
            let _ = writeln!(
                s,
                "  {} #{} [{}]: {:?}, {} triangles ({})",
                c.mesh, c.primitive, c.material, c.part, c.triangles, c.reason
            );
        }
        for c in &self.clips {
            let _ = writeln!(
                s,
                "  clip '{}': {:.3} s, {} channels, {}, {}",
                c.name,
                c.duration_s,
                c.channels,
                if c.loops { "loops" } else { "does NOT loop" },
                if c.moves { "moves" } else { "no motion" }
            );
        }
        let sm = &self.sampling;
        let _ = writeln!(
            s,
            "  sampled '{}': {} samples over {:.3} s, {} leaf trajectories, leaf excursion mean {:.4} / max {:.4} ({:.3} s)",
            sm.clip.as_deref().unwrap_or("(rest pose)"),
            sm.samples,
            sm.period_s,
            sm.trajectories,
            sm.mean_leaf_excursion,
            sm.max_leaf_excursion,
            sm.seconds
        );
        let _ = writeln!(
            s,
            "  bounds: {:?} .. {:?}",
            self.bounds.min, self.bounds.max
        );
        for w in &self.warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
        s
    }
}
