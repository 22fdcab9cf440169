//! `frond inspect`: what a tree file holds and how frond reads it. The JSON keys are a stable
//! interface (documented in the README).

use frond_scene::sampling::clip_motion;
use frond_scene::{Bounds, Classification, Part, Tree};
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
    pub warnings: Vec<String>,
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

/// Builds the report for an imported tree.
pub fn inspect(tree: &Tree) -> InspectReport {
    let clips = (0..tree.clips.len())
        .map(|c| {
            let m = clip_motion(tree, c, MOTION_SAMPLES);
            let clip = &tree.clips[c];
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
