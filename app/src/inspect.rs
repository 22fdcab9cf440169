//! `frond inspect`: what a tree file holds and how frond reads it. The JSON keys are a stable
//! interface (documented in the README).

use frond_scene::sampling::clip_motion;
use frond_scene::{Bounds, Classification, Part, Sampled, Tree};
use serde::Serialize;

/// Number of poses checked per clip for motion.
const MOTION_SAMPLES: usize = 16;

/// The inspect report.
#[derive(Debug, Serialize)]
pub struct InspectReport {
    pub file: String,
    pub triangles: TriangleCounts,
    pub vertices: usize,
    pub bones: usize,
    pub skeleton_depth: u32,
    /// Distinct bones that carry foliage.
    pub foliage_bones: usize,
    pub foliage_reassigned: usize,
    pub classification: Vec<Classification>,
    pub materials: Vec<MaterialSummary>,
    pub textures: Vec<TextureSummary>,
    pub clips: Vec<ClipSummary>,
    pub bounds: Bounds,
    /// The sampled loop of the chosen clip (`--clip`, `--samples`).
    pub sampling: SamplingSummary,
    pub warnings: Vec<String>,
}

/// What sampling the chosen clip produced.
#[derive(Debug, Serialize)]
pub struct SamplingSummary {
    pub clip: Option<String>,
    pub samples: usize,
    pub period_s: f32,
    /// Non-degenerate foliage triangles with a centre trajectory.
    pub trajectories: usize,
    /// Largest distance of a foliage triangle centre from its mean position.
    pub max_leaf_excursion: f32,
    /// Mean of that distance over foliage triangles.
    pub mean_leaf_excursion: f32,
    pub loops: bool,
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
#[derive(Debug, Serialize)]
pub struct TriangleCounts {
    pub total: usize,
    pub wood: usize,
    pub foliage: usize,
    pub degenerate: usize,
}

/// One material.
#[derive(Debug, Serialize)]
pub struct MaterialSummary {
    pub name: String,
    pub alpha_mode: frond_scene::AlphaMode,
    pub alpha_cutoff: f32,
    pub double_sided: bool,
    pub texture: Option<String>,
}

/// One decoded texture.
#[derive(Debug, Serialize)]
pub struct TextureSummary {
    pub name: String,
    pub width: u32,
    pub height: u32,
}

/// One animation clip.
#[derive(Debug, Serialize)]
pub struct ClipSummary {
    pub name: String,
    pub duration_s: f32,
    pub channels: usize,
    pub loops: bool,
    pub moves: bool,
    pub loop_gap: f32,
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
