//! `frond eval ORIGINAL CANDIDATE`: how well a candidate (a `frond lod` LOD, a decimated tree,
//! an artist's LOD) reproduces an animated tree, by the metrics of spec
//! animated-billboard-clouds §5 and App. A, each with its definition in the report.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use frond_export::mapping::Mapping;
use frond_metrics::animation::{AxisMetrics, axis_metrics};
use frond_metrics::cost::{Cost, cost};
use frond_metrics::triangle_metrics::{TriangleMetrics, image_trajectory, triangle_metrics};
use frond_metrics::{CoverageMasks, CoverageParams, CoverageReport, compare_masks, coverage_masks};
use frond_render::{DrawScene, Renderer, TreeParts, tree_scene};
use frond_scene::sampling::pose_at;
use frond_scene::surface_distance::SurfaceBvh;
use frond_scene::{Part, SampleOptions, Sampled, Tree, sample};
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

/// What `frond eval` was asked for.
#[derive(Clone, Debug)]
pub struct EvalRequest {
    /// Ring views of the colour metric (odd, thesis §8.3.1).
    pub views: u32,
    /// Frames of the animated colour metric.
    pub frames: u32,
    /// Image size of the colour metric.
    pub size: (u32, u32),
    /// Samples over the loop for the trajectory metrics.
    pub samples: usize,
    /// Clip (default: the original's first); the candidate plays the clip of the same name.
    pub clip: Option<String>,
}

/// Whether two files hold the same bytes (the candidate is the original itself): sizes first,
/// so a sweep does not read both files whole for every run.
pub fn same_bytes(a: &Path, b: &Path) -> bool {
    let len = |p: &Path| std::fs::metadata(p).map(|m| m.len()).ok();
    match (len(a), len(b)) {
        (Some(x), Some(y)) if x == y => std::fs::read(a).ok() == std::fs::read(b).ok(),
        _ => false,
    }
}

/// The colour metric's image for a tree seen `screen_height` pixels high: that height, 4:3.
pub fn image_for_screen_height(screen_height: u32) -> (u32, u32) {
    (screen_height.saturating_mul(4).div_ceil(3), screen_height)
}

/// One metric: mean and max, or why it was not computed.
#[derive(Clone, Debug, Serialize)]
pub struct Metric {
    pub mean: Option<f64>,
    pub max: Option<f64>,
    pub skipped_reason: Option<String>,
    pub definition: &'static str,
}

impl Metric {
    fn value(mean: f64, max: f64, definition: &'static str) -> Metric {
        Metric {
            mean: Some(mean),
            max: Some(max),
            skipped_reason: None,
            definition,
        }
    }
    fn skipped(reason: &str, definition: &'static str) -> Metric {
        Metric {
            mean: None,
            max: None,
            skipped_reason: Some(reason.to_string()),
            definition,
        }
    }
}

/// The static and animated colour (coverage) metric.
#[derive(Clone, Debug, Serialize)]
pub struct CoverageMetrics {
    #[serde(rename = "static")]
    pub static_: Metric,
    pub animated: Metric,
    /// (view, frame) pairs of the animated metric discarded because they scored above 1 (the
    /// thesis: no fidelity from that view) or the original covered no pixel.
    pub discarded_pairs: usize,
    /// (view, frame) pairs of the animated metric.
    pub pairs: usize,
}

/// Both models' cost.
#[derive(Clone, Debug, Serialize)]
pub struct Costs {
    pub original: Cost,
    pub candidate: Cost,
}

/// The report (`--json`).
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    pub original: String,
    pub candidate: String,
    pub clip: Option<String>,
    pub samples: usize,
    pub views: u32,
    pub frames: u32,
    pub size: [u32; 2],
    /// Distances below are in world units; this is the original's height for scale.
    pub tree_height: f32,
    pub coverage: CoverageMetrics,
    pub colour_difference: Metric,
    pub plane_distance: Metric,
    pub projected_distance: Metric,
    pub euclidean_distance: Metric,
    pub orientation: Metric,
    pub dominating_axis: Metric,
    pub dominating_axis_spectral: Metric,
    /// How each original foliage triangle was matched to the candidate.
    pub matching: String,
    pub cost: Costs,
    pub timings_s: serde_json::Value,
}

const COVERAGE_DEF: &str = "spec §5.4: Σ|o−s|/P_f over binary foliage masks per (view, frame), \
    views on a ring at elevation 0, pairs above 1 discarded; mean over pairs, max = worst pair";
const COLOUR_DEF: &str = "mean |Δ linear RGB| over pixels both foliage renders cover, per \
    (view, frame) of the animated colour metric; max = worst pair";
const PLANE_DEF: &str = "spec §5.2: distance of each foliage triangle's centroid to its \
    billboard's plane over the loop (world units); mean of per-triangle means, max of maxes";
const PROJECTED_DEF: &str = "spec §5.2: distance of the centroid's projection to its fixed \
    point on the billboard (least-squares over the loop), world units";
const EUCLID_DEF: &str = "spec §5.2: sqrt(D_plane² + D_projected²), world units";
const ORIENT_DEF: &str = "spec §5.3: 1 − (n·n_s + 1)(d·d_s + 1)/4 per sample, d = centroid → \
    vertex 0, billboard normal signed toward the triangle (double-sided)";
const AXIS_DEF: &str = "spec §5.5 with the §4.8 erratum fixed: NEP(1 − |a_t·a_b|, \
    amplitudeDistance) of the centroid's and its image's trajectories (image: the fixed point on \
    its billboard, or for candidates without a mapping the nearest candidate foliage point in \
    the rest pose), frequency bins = skeleton depth; mean and max over triangles";
const AXIS_SPEC_DEF: &str = "spec §5.5: NE(amplitudeDistance) of the dominating-axis spectra, \
    frequency bins = skeleton depth";

/// The candidate's clip to play at the original's clip `name`: the one of the same name, else
/// its first.
fn candidate_clip(candidate: &Tree, name: Option<&str>) -> Option<usize> {
    name.and_then(|n| candidate.clip_index(Some(n)))
        .or_else(|| candidate.clip_index(None))
}

fn coverage_metric(r: &CoverageReport) -> Metric {
    let worst = r
        .differing_pixels
        .iter()
        .zip(&r.original_pixels)
        .filter(|(_, o)| **o > 0)
        .map(|(d, o)| *d as f64 / *o as f64)
        .filter(|s| *s <= 1.0)
        .fold(f64::NAN, f64::max);
    if r.mean.is_nan() {
        return Metric::skipped(
            "every (view, frame) pair was discarded (no original foliage, or error above 1)",
            COVERAGE_DEF,
        );
    }
    Metric::value(r.mean, worst, COVERAGE_DEF)
}

/// The original's half of an evaluation, computed once and reused for every candidate: its
/// sampled loop, the frame times, and its coverage masks per image size (a sweep scores many
/// candidates against one original).
pub struct EvalContext<'a> {
    renderer: &'a Renderer,
    original: &'a Tree,
    sampled: Sampled,
    frame_times: Vec<f32>,
    masks: std::collections::HashMap<(u32, u32), CoverageMasks>,
    views: u32,
}

impl<'a> EvalContext<'a> {
    /// Samples `original`'s loop for `req` (views, frames, samples, clip; the size is per
    /// evaluation).
    pub fn new(renderer: &'a Renderer, original: &'a Tree, req: &EvalRequest) -> Result<Self> {
        let sampled = sample(
            original,
            &SampleOptions {
                clip: req.clip.clone(),
                samples: req.samples,
            },
        )?;
        let start = sampled.times.first().copied().unwrap_or(0.0);
        let frames = req.frames.max(1);
        let frame_times: Vec<f32> = (0..frames)
            .map(|f| start + sampled.period * f as f32 / frames as f32)
            .collect();
        Ok(EvalContext {
            renderer,
            original,
            sampled,
            frame_times,
            masks: Default::default(),
            views: req.views,
        })
    }

    /// The original's file.
    pub fn original_path(&self) -> &Path {
        &self.original.source
    }

    fn params(&self, size: (u32, u32)) -> CoverageParams {
        CoverageParams {
            views: self.views,
            frames: self.frame_times.len() as u32,
            width: size.0,
            height: size.1,
            ..Default::default()
        }
    }

    fn scenes(&self, tree: &Tree, clip: Option<usize>) -> Vec<DrawScene> {
        self.frame_times
            .iter()
            .map(|&t| tree_scene(tree, clip, t, TreeParts::Foliage))
            .collect()
    }

    fn bounds(&self) -> (Vec3, Vec3) {
        (
            Vec3::from(self.original.bounds.min),
            Vec3::from(self.original.bounds.max),
        )
    }

    /// The original's coverage masks at `size`, rendered on first use.
    fn original_masks(&mut self, size: (u32, u32)) -> Result<&CoverageMasks> {
        if !self.masks.contains_key(&size) {
            let oc = self.original.clip_index(self.sampled.clip.as_deref());
            let (lo, hi) = self.bounds();
            let m = coverage_masks(
                self.renderer,
                &self.scenes(self.original, oc),
                lo,
                hi,
                &self.params(size),
            )
            .with_context(|| format!("{}: colour metric", self.original.source.display()))?;
            self.masks.insert(size, m);
        }
        Ok(&self.masks[&size])
    }

    /// Evaluates `candidate` with images of `size`; `same_file` (the two files have the same
    /// bytes) matches every triangle to itself.
    pub fn evaluate(
        &mut self,
        candidate: &Tree,
        same_file: bool,
        size: (u32, u32),
    ) -> Result<EvalReport> {
        let t0 = Instant::now();
        let path = self.original.source.display().to_string();
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        let (lo, hi) = self.bounds();
        let cand_masks = coverage_masks(
            self.renderer,
            &self.scenes(candidate, cc),
            lo,
            hi,
            &self.params(size),
        )
        .with_context(|| format!("{}: colour metric", candidate.source.display()))?;
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let orig_masks = self.original_masks(size)?;
        // The static metric (F = 1) is the animated one's first frame: the same renders.
        let stat = compare_masks(orig_masks, &cand_masks, &[0])
            .with_context(|| format!("{path}: static colour metric"))?;
        let anim = compare_masks(orig_masks, &cand_masks, &all)
            .with_context(|| format!("{path}: animated colour metric"))?;
        drop(cand_masks);
        let t1 = Instant::now();
        let mut report = score(
            self.original,
            candidate,
            same_file,
            &self.sampled,
            cc,
            &stat,
            &anim,
        );
        report.views = self.views;
        report.frames = self.frame_times.len() as u32;
        report.size = [size.0, size.1];
        report.timings_s["colour"] = serde_json::json!((t1 - t0).as_secs_f64());
        report.timings_s["total"] = serde_json::json!(t0.elapsed().as_secs_f64());
        Ok(report)
    }
}

/// Evaluates `candidate` against `original`; `same_file` (the two files have the same bytes)
/// matches every triangle to itself.
pub fn evaluate(
    renderer: &Renderer,
    original: &Tree,
    candidate: &Tree,
    same_file: bool,
    req: &EvalRequest,
) -> Result<EvalReport> {
    EvalContext::new(renderer, original, req)?.evaluate(candidate, same_file, req.size)
}

/// Everything of a report but the colour renders: the per-triangle and animation metrics and
/// the cost, given the two colour reports.
fn score(
    original: &Tree,
    candidate: &Tree,
    same_file: bool,
    sampled: &Sampled,
    cc: Option<usize>,
    stat: &CoverageReport,
    anim: &CoverageReport,
) -> EvalReport {
    let path = original.source.display().to_string();
    let t1 = Instant::now();
    let colour = if anim.colour_difference.is_nan() {
        Metric::skipped("the two renders share no foliage pixel", COLOUR_DEF)
    } else {
        let worst = anim
            .colour_per_pair
            .iter()
            .copied()
            .filter(|c| c.is_finite())
            .fold(0.0, f64::max);
        Metric::value(anim.colour_difference, worst, COLOUR_DEF)
    };

    let (matching, per_triangle) = match_triangles(original, candidate, same_file, sampled, cc);
    let t2 = Instant::now();
    let bins = original.skeleton_depth().max(1) as usize;
    let metrics: Vec<_> = per_triangle
        .par_iter()
        .map(|(tri, board)| {
            let m = triangle_metrics(tri, board);
            let centres: Vec<Vec3> = tri.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
            let a = axis_metrics(&centres, &image_trajectory(tri, board), bins);
            (m, a)
        })
        .collect();
    // Foreign candidates: each original leaf matched to the nearest candidate foliage surface
    // point in the rest pose; that point follows its triangle's skinning.
    let foreign: Option<Result<Vec<AxisMetrics>, String>> = matching
        .is_err()
        .then(|| foreign_axis_metrics(original, candidate, sampled, cc, bins));
    let agg = |f: &dyn Fn(&TriangleScores) -> (f32, f32), def: &'static str| -> Metric {
        match &matching {
            Err(reason) => Metric::skipped(reason, def),
            Ok(_) if metrics.is_empty() => Metric::skipped("no foliage triangle to compare", def),
            Ok(_) => {
                let (mut sum, mut max) = (0.0f64, 0.0f64);
                for m in &metrics {
                    let (mean, mx) = f(m);
                    sum += f64::from(mean);
                    max = max.max(f64::from(mx));
                }
                Metric::value(sum / metrics.len() as f64, max, def)
            }
        }
    };
    EvalReport {
        original: path,
        candidate: candidate.source.display().to_string(),
        clip: sampled.clip.clone(),
        samples: sampled.samples(),
        // Set by the caller, which knows the colour metric's setup.
        views: 0,
        frames: 0,
        size: [0, 0],
        tree_height: frond_lod::tree_height(original),
        coverage: CoverageMetrics {
            static_: coverage_metric(stat),
            animated: coverage_metric(anim),
            discarded_pairs: anim.discarded,
            pairs: anim.original_pixels.len(),
        },
        colour_difference: colour,
        plane_distance: agg(
            &|m| (m.0.plane_distance.mean, m.0.plane_distance.max),
            PLANE_DEF,
        ),
        projected_distance: agg(
            &|m| (m.0.projected_distance.mean, m.0.projected_distance.max),
            PROJECTED_DEF,
        ),
        euclidean_distance: agg(
            &|m| (m.0.euclidean_distance.mean, m.0.euclidean_distance.max),
            EUCLID_DEF,
        ),
        orientation: agg(&|m| (m.0.orientation.mean, m.0.orientation.max), ORIENT_DEF),
        dominating_axis: match &foreign {
            Some(f) => axis_aggregate(f, |a| a.dominating_axis, AXIS_DEF),
            None => agg(&|m| (m.1.dominating_axis, m.1.dominating_axis), AXIS_DEF),
        },
        dominating_axis_spectral: match &foreign {
            Some(f) => axis_aggregate(f, |a| a.dominating_axis_spectral, AXIS_SPEC_DEF),
            None => agg(
                &|m| (m.1.dominating_axis_spectral, m.1.dominating_axis_spectral),
                AXIS_SPEC_DEF,
            ),
        },
        matching: match &matching {
            Ok(how) => how.clone(),
            Err(reason) => reason.clone(),
        },
        cost: Costs {
            original: cost(original, file_size(&original.source)),
            candidate: cost(candidate, file_size(&candidate.source)),
        },
        timings_s: serde_json::json!({
            "matching": (t2 - t1).as_secs_f64(),
            "trajectories": t2.elapsed().as_secs_f64(),
        }),
    }
}

/// One triangle's distance/orientation metrics and animation metrics.
type TriangleScores = (TriangleMetrics, AxisMetrics);

/// Mean and max of one animation metric over matched leaves.
fn axis_aggregate(
    found: &Result<Vec<AxisMetrics>, String>,
    f: impl Fn(&AxisMetrics) -> f32,
    def: &'static str,
) -> Metric {
    match found {
        Err(reason) => Metric::skipped(reason, def),
        Ok(v) if v.is_empty() => Metric::skipped("no foliage triangle to compare", def),
        Ok(v) => {
            let sum: f64 = v.iter().map(|a| f64::from(f(a))).sum();
            let max = v.iter().map(|a| f64::from(f(a))).fold(0.0, f64::max);
            Metric::value(sum / v.len() as f64, max, def)
        }
    }
}

/// The animation metrics of a candidate without a mapping: every original foliage triangle's
/// rest centroid is matched to the nearest point of the candidate's foliage in its rest pose
/// (spec §5.5 for foreign candidates); that point, as barycentric coordinates of its triangle,
/// moves with the candidate's skinning.
fn foreign_axis_metrics(
    original: &Tree,
    candidate: &Tree,
    sampled: &Sampled,
    cc: Option<usize>,
    bins: usize,
) -> Result<Vec<AxisMetrics>, String> {
    let cand_tris: Vec<usize> = candidate.foliage();
    if cand_tris.is_empty() {
        return Err("the candidate has no foliage to match leaves to".into());
    }
    let rest_c = pose_at(candidate, None, 0.0);
    let rest_o = pose_at(original, None, 0.0);
    let corners = |pos: &[Vec3], t: usize| candidate.triangles[t].v.map(|i| pos[i as usize]);
    let bvh = SurfaceBvh::new(cand_tris.iter().map(|&t| corners(&rest_c, t)).collect());
    let poses: Vec<Vec<Vec3>> = sampled
        .times
        .par_iter()
        .map(|&t| pose_at(candidate, cc, t))
        .collect();
    Ok(sampled
        .foliage
        .par_iter()
        .enumerate()
        .filter_map(|(k, &t)| {
            let v = original.triangles[t].v;
            let c = (rest_o[v[0] as usize] + rest_o[v[1] as usize] + rest_o[v[2] as usize]) / 3.0;
            let (i, q, _) = bvh.nearest(c)?;
            let tri = cand_tris[i];
            let w = barycentric(q, corners(&rest_c, tri));
            let image: Vec<Vec3> = poses
                .iter()
                .map(|p| {
                    let [a, b, d] = corners(p, tri);
                    a * w.x + b * w.y + d * w.z
                })
                .collect();
            Some(axis_metrics(sampled.trajectory(k), &image, bins))
        })
        .collect())
}

/// Barycentric coordinates of `p` (on or near the triangle) with respect to `t`.
fn barycentric(p: Vec3, t: [Vec3; 3]) -> Vec3 {
    let (v0, v1, v2) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= f32::EPSILON * d00 * d11 {
        return Vec3::new(1.0, 0.0, 0.0);
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    Vec3::new(1.0 - v - w, v, w)
}

fn file_size(p: &Path) -> u64 {
    std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)
}

/// Per original foliage triangle: its vertices and the corners of what replaces it, at every
/// sample; or why no matching exists.
type Matched = (
    Result<String, String>,
    Vec<(Vec<[Vec3; 3]>, Vec<[Vec3; 4]>)>,
);

fn match_triangles(
    original: &Tree,
    candidate: &Tree,
    same_file: bool,
    sampled: &Sampled,
    cc: Option<usize>,
) -> Matched {
    let nv = sampled.vertices;
    let n = sampled.samples();
    let tri_track = |t: usize| -> Vec<[Vec3; 3]> {
        let v = original.triangles[t].v;
        (0..n)
            .map(|s| v.map(|i| sampled.positions[s * nv + i as usize]))
            .collect()
    };
    if same_file {
        let tracks = sampled
            .foliage
            .par_iter()
            .map(|&t| {
                let tri = tri_track(t);
                let board = tri.iter().map(|v| [v[0], v[1], v[2], v[2]]).collect();
                (tri, board)
            })
            .collect();
        return (
            Ok("identity (the candidate is the original file)".into()),
            tracks,
        );
    }
    let sidecar = candidate.source.with_extension("mapping.json");
    let mapping: Mapping = match std::fs::read(&sidecar)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
    {
        Some(m) => m,
        None => {
            return (
                Err(format!(
                    "no triangle → billboard mapping ({} missing or unreadable): the \
                     per-billboard metrics need one",
                    sidecar.display()
                )),
                Vec::new(),
            );
        }
    };
    // The billboard primitive: triangles of the material `frond lod` names "<lod>_billboards",
    // 4 vertices per billboard in mapping order.
    let mut board_vertices: Vec<u32> = candidate
        .triangles
        .iter()
        .filter(|t| {
            t.part == Part::Foliage
                && candidate
                    .materials
                    .get(t.material as usize)
                    .is_some_and(|m| m.name.ends_with("_billboards"))
        })
        .flat_map(|t| t.v)
        .collect();
    board_vertices.sort_unstable();
    board_vertices.dedup();
    let count = mapping.billboards.len();
    let base = board_vertices.first().copied().unwrap_or(0) as usize;
    if board_vertices.len() != 4 * count
        || board_vertices
            .last()
            .is_some_and(|&l| l as usize != base + 4 * count - 1)
    {
        return (
            Err(format!(
                "{} lists {count} billboards but the candidate's billboard mesh has {} vertices",
                sidecar.display(),
                board_vertices.len()
            )),
            Vec::new(),
        );
    }
    let poses: Vec<Vec<Vec3>> = sampled
        .times
        .par_iter()
        .map(|&t| pose_at(candidate, cc, t))
        .collect();
    let foliage: std::collections::HashSet<usize> = sampled.foliage.iter().copied().collect();
    let mut pairs = Vec::new();
    for (k, b) in mapping.billboards.iter().enumerate() {
        for &t in &b.triangles {
            if foliage.contains(&t) {
                pairs.push((k, t));
            }
        }
    }
    let tracks = pairs
        .par_iter()
        .map(|&(k, t)| {
            let board = poses
                .iter()
                .map(|p| [0, 1, 2, 3].map(|c| p[base + 4 * k + c]))
                .collect();
            (tri_track(t), board)
        })
        .collect();
    (
        Ok(format!(
            "{}: {} triangles on {count} billboards ({} unmapped)",
            sidecar.display(),
            pairs.len(),
            mapping.unmapped_triangles.len()
        )),
        tracks,
    )
}
