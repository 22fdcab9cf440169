//! Evaluating a candidate (a `frond lod` LOD, a decimated tree, an artist's LOD) against the
//! animated original by every metric of spec animated-billboard-clouds §5 and App. A: the
//! colour renders (§5.4), the triangle matching, the per-triangle and animation metrics
//! (§5.2–5.5) and the cost (§5.7), into an [`EvalReport`]. The original's half is computed once
//! in an [`EvalContext`] and reused for every candidate of a sweep.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

use frond_render::{DrawScene, Lighting, Renderer, TreeParts, tree_scene};
use frond_scene::{
    FileCost, InputLimits, SampleOptions, Sampled, SceneError, Tree, file_cost, sample,
};
use glam::Vec3;
use rayon::prelude::*;

use crate::aggregate::{
    TriangleScores, axis_aggregate, colour_difference_metric, coverage_metric, triangle_aggregate,
};
use crate::cost::cost;
use crate::coverage::{
    CoverageMasks, CoverageParams, CoverageReport, MetricError, compare_masks, coverage_masks,
};
use crate::dominating_axis::{AxisMetrics, axis_metrics};
use crate::matching::{match_foreign, match_triangles};
use crate::metric_id::MetricId;
use crate::report::{Costs, CoverageMetrics, EvalReport, EvalTimings};
use crate::triangle_metrics::{image_trajectory, triangle_metrics};

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
    /// What reading a file for its cost may take (the limits the trees were imported with).
    pub limits: InputLimits,
    /// Draw every surface white (alpha and the alpha test kept) in the colour metric, so its
    /// colour difference is the lighting's alone: how closely a LOD's normals (vertex normals,
    /// normal maps) light it like the tree under the metric's directional light, without the
    /// baked textures' own differences.
    pub white_albedo: bool,
    /// How the colour metric's renders are lit.
    pub lighting: Lighting,
}

/// Why an evaluation failed.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The original's loop could not be sampled.
    #[error(transparent)]
    Sample(#[from] SceneError),
    /// A model's file could not be read for its cost (the error names the file).
    #[error(transparent)]
    Cost(SceneError),
    /// A colour-metric render or comparison failed (`what`: which one, of which `file`).
    #[error("{file}: {what}")]
    Colour {
        /// The file whose render failed, or the original's for a comparison.
        file: String,
        /// `colour metric`, `static colour metric` or `animated colour metric`.
        what: &'static str,
        /// The metric's error.
        #[source]
        source: MetricError,
    },
}

impl EvalError {
    fn colour(file: &Path, what: &'static str) -> impl FnOnce(MetricError) -> EvalError {
        let file = file.display().to_string();
        move |source| EvalError::Colour { file, what, source }
    }
}

/// The colour metric's image for a tree seen `screen_height` pixels high: that height, 4:3.
pub fn image_for_screen_height(screen_height: u32) -> (u32, u32) {
    (screen_height.saturating_mul(4).div_ceil(3), screen_height)
}

/// The candidate's clip to play at the original's clip `name`: the one of the same name, else
/// its first.
pub fn candidate_clip(candidate: &Tree, name: Option<&str>) -> Option<usize> {
    name.and_then(|n| candidate.clip_index(Some(n)))
        .or_else(|| candidate.clip_index(None))
}

/// `scene` with white base colours and textures, their alpha (and so the alpha test) kept:
/// what is left of its colour is the lighting ([`EvalRequest::white_albedo`]).
fn whiten(scene: &mut DrawScene) {
    for m in &mut scene.materials {
        m.base_color = [1.0, 1.0, 1.0, m.base_color[3]];
    }
    // Only colour textures: a normal map must keep its texels.
    let colour: Vec<usize> = scene.materials.iter().filter_map(|m| m.texture).collect();
    for (i, t) in scene.textures.iter_mut().enumerate() {
        if colour.contains(&i) {
            for texel in t.rgba.chunks_exact_mut(4) {
                texel[..3].fill(255);
            }
        }
    }
}

/// The original's half of an evaluation, computed once and reused for every candidate: its
/// sampled loop, the frame times, and its coverage masks per image size (a sweep scores many
/// candidates against one original).
pub struct EvalContext<'a> {
    renderer: &'a Renderer,
    original: &'a Tree,
    sampled: Sampled,
    frame_times: Vec<f32>,
    /// Per image size and whether drawn with colour.
    masks: HashMap<((u32, u32), bool), CoverageMasks>,
    views: u32,
    /// [`EvalRequest::white_albedo`].
    white_albedo: bool,
    lighting: Lighting,
    /// The original file's cost, read once.
    original_file: FileCost,
    limits: InputLimits,
}

impl<'a> EvalContext<'a> {
    /// The original tree the candidates are compared with.
    pub fn original(&self) -> &'a Tree {
        self.original
    }

    /// Samples `original`'s loop for `req` (views, frames, samples, clip; the size is per
    /// evaluation).
    pub fn new(
        renderer: &'a Renderer,
        original: &'a Tree,
        req: &EvalRequest,
    ) -> Result<Self, EvalError> {
        let sampled = sample(
            original,
            &SampleOptions {
                clip: req.clip.clone(),
                samples: req.samples,
            },
        )?;
        let original_file = file_cost(&original.source, &req.limits).map_err(EvalError::Cost)?;
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
            white_albedo: req.white_albedo,
            lighting: req.lighting,
            original_file,
            limits: req.limits,
        })
    }

    /// The original's file.
    pub fn original_path(&self) -> &Path {
        &self.original.source
    }

    /// The name of the clip the original plays, as its loop was sampled.
    pub fn clip(&self) -> Option<&str> {
        self.sampled.clip.as_deref()
    }

    /// Renders the original's coverage masks (without colour, as [`EvalContext::coverage`]
    /// draws them) at each of `sizes` now rather than on first use: `frond lod` draws them while
    /// it builds the LODs they are compared with.
    pub fn prepare_coverage(&mut self, sizes: &[(u32, u32)]) -> Result<(), EvalError> {
        for &size in sizes {
            self.original_masks(size, false)?;
        }
        Ok(())
    }

    fn params(&self, size: (u32, u32), colour: bool) -> CoverageParams {
        CoverageParams {
            views: self.views,
            frames: self.frame_times.len() as u32,
            width: size.0,
            height: size.1,
            colour,
            lighting: self.lighting,
            ..Default::default()
        }
    }

    fn scenes(&self, tree: &Tree, clip: Option<usize>) -> Vec<DrawScene> {
        self.frame_times
            .iter()
            .map(|&t| {
                let mut scene = tree_scene(tree, clip, t, TreeParts::Foliage);
                if self.white_albedo {
                    whiten(&mut scene);
                }
                scene
            })
            .collect()
    }

    fn bounds(&self) -> (Vec3, Vec3) {
        (
            Vec3::from(self.original.bounds.min),
            Vec3::from(self.original.bounds.max),
        )
    }

    /// The original's coverage masks at `size` (with colour or not), rendered on first use.
    fn original_masks(
        &mut self,
        size: (u32, u32),
        colour: bool,
    ) -> Result<&CoverageMasks, EvalError> {
        if !self.masks.contains_key(&(size, colour)) {
            let oc = self.original.clip_index(self.sampled.clip.as_deref());
            let (lo, hi) = self.bounds();
            let m = coverage_masks(
                self.renderer,
                &self.scenes(self.original, oc),
                lo,
                hi,
                &self.params(size, colour),
            )
            .map_err(EvalError::colour(&self.original.source, "colour metric"))?;
            self.masks.insert((size, colour), m);
        }
        Ok(&self.masks[&(size, colour)])
    }

    /// `candidate`'s coverage masks at `size`, playing its clip `clip`.
    fn candidate_masks(
        &self,
        candidate: &Tree,
        clip: Option<usize>,
        size: (u32, u32),
        colour: bool,
    ) -> Result<CoverageMasks, EvalError> {
        let (lo, hi) = self.bounds();
        coverage_masks(
            self.renderer,
            &self.scenes(candidate, clip),
            lo,
            hi,
            &self.params(size, colour),
        )
        .map_err(EvalError::colour(&candidate.source, "colour metric"))
    }

    /// The animated coverage error of `candidate` with images of `size` (spec
    /// animated-billboard-clouds §5.4): the animated colour metric [`EvalContext::evaluate`]
    /// reports, alone — no per-triangle metrics, no file cost. `frond lod` measures each LOD's
    /// error with it.
    pub fn coverage(
        &mut self,
        candidate: &Tree,
        size: (u32, u32),
    ) -> Result<CoverageReport, EvalError> {
        self.coverage_with_depth(candidate, size).map(|r| r.0)
    }

    /// [`EvalContext::coverage`], with the depth complexities of the candidate and of the
    /// original ([`EvalContext::depth_complexity`]: the same values) read off the metric's
    /// own first render of each, where it has them.
    pub fn coverage_with_depth(
        &mut self,
        candidate: &Tree,
        size: (u32, u32),
    ) -> Result<(CoverageReport, f64, f64), EvalError> {
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        // The coverage alone: drawn without colour (no depth test, alpha only).
        let cand_masks = self.candidate_masks(candidate, cc, size, false)?;
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let original = self.original_masks(size, false)?;
        let report = compare_masks(original, &cand_masks, &all).map_err(EvalError::colour(
            &candidate.source,
            "animated colour metric",
        ))?;
        let original_depth = original.first_depth_complexity;
        let original_tree = self.original;
        let depth = |masks_depth: Option<f64>, tree: &Tree| match masks_depth {
            Some(d) => Ok(d),
            None => self.depth_complexity(tree, size),
        };
        Ok((
            report,
            depth(cand_masks.first_depth_complexity, candidate)?,
            depth(original_depth, original_tree)?,
        ))
    }

    /// The depth complexity of `candidate`'s foliage at `size`, from the metric's first view
    /// at its first frame ([`crate::coverage::depth_complexity`]).
    pub fn depth_complexity(&self, candidate: &Tree, size: (u32, u32)) -> Result<f64, EvalError> {
        let clip = candidate_clip(candidate, self.sampled.clip.as_deref());
        let t = self.frame_times.first().copied().unwrap_or(0.0);
        let scene = tree_scene(candidate, clip, t, TreeParts::Foliage);
        let (lo, hi) = self.bounds();
        crate::coverage::depth_complexity(&scene, lo, hi, 0, &self.params(size, false))
            .map_err(EvalError::colour(&candidate.source, "depth complexity"))
    }

    /// Evaluates `candidate` with images of `size`; `same_file` (the two files have the same
    /// bytes) matches every triangle to itself.
    pub fn evaluate(
        &mut self,
        candidate: &Tree,
        same_file: bool,
        size: (u32, u32),
    ) -> Result<EvalReport, EvalError> {
        let t0 = Instant::now();
        let candidate_file = file_cost(&candidate.source, &self.limits).map_err(EvalError::Cost)?;
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        let cand_masks = self.candidate_masks(candidate, cc, size, true)?;
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let original: &'a Tree = self.original;
        let orig_masks = self.original_masks(size, true)?;
        // The static metric (F = 1) is the animated one's first frame: the same renders.
        let stat = compare_masks(orig_masks, &cand_masks, &[0])
            .map_err(EvalError::colour(&original.source, "static colour metric"))?;
        let anim = compare_masks(orig_masks, &cand_masks, &all).map_err(EvalError::colour(
            &original.source,
            "animated colour metric",
        ))?;
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
        report.cost = Costs {
            original: cost(self.original, self.original_file.clone()),
            candidate: cost(candidate, candidate_file),
        };
        report.timings_s.colour = (t1 - t0).as_secs_f64();
        report.timings_s.total = t0.elapsed().as_secs_f64();
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
) -> Result<EvalReport, EvalError> {
    EvalContext::new(renderer, original, req)?.evaluate(candidate, same_file, req.size)
}

/// Everything of a report but the colour renders and the cost: the per-triangle and animation
/// metrics (§5.2–5.5), given the static and animated colour reports (§5.4). The colour setup
/// (views, frames, size), the colour timings and the cost (§5.7, which reads the files) are the
/// caller's to fill in.
fn score(
    original: &Tree,
    candidate: &Tree,
    same_file: bool,
    sampled: &Sampled,
    cc: Option<usize>,
    stat: &CoverageReport,
    anim: &CoverageReport,
) -> EvalReport {
    let t1 = Instant::now();
    let colour = colour_difference_metric(anim);
    let (matching, per_triangle) = match_triangles(original, candidate, same_file, sampled, cc);
    let t2 = Instant::now();
    let bins = original.skeleton_depth().max(1) as usize;
    let scores: Vec<TriangleScores> = per_triangle
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
    let foreign: Option<Result<Vec<AxisMetrics>, String>> = matching.is_err().then(|| {
        match_foreign(original, candidate, sampled, cc, |leaf, image| {
            axis_metrics(leaf, image, bins)
        })
    });
    let agg = |id, f: &dyn Fn(&TriangleScores) -> (f32, f32)| {
        triangle_aggregate(&matching, &scores, id, f)
    };
    let axis = |id, f: fn(&AxisMetrics) -> f32| match &foreign {
        Some(found) => axis_aggregate(found, id, f),
        None => agg(id, &|m| (f(&m.1), f(&m.1))),
    };
    EvalReport {
        colour_shift: anim.colour_shift,
        original: original.source.display().to_string(),
        candidate: candidate.source.display().to_string(),
        clip: sampled.clip.clone(),
        samples: sampled.samples(),
        // Set by the caller, which knows the colour metric's setup.
        views: 0,
        frames: 0,
        size: [0, 0],
        tree_height: original.height(),
        coverage: CoverageMetrics {
            static_: coverage_metric(MetricId::CoverageStatic, stat),
            animated: coverage_metric(MetricId::CoverageAnimated, anim),
            discarded_pairs: anim.discarded,
            pairs: anim.original_pixels.len(),
        },
        colour_difference: colour,
        plane_distance: agg(MetricId::PlaneDistance, &|m| {
            (m.0.plane_distance.mean, m.0.plane_distance.max)
        }),
        projected_distance: agg(MetricId::ProjectedDistance, &|m| {
            (m.0.projected_distance.mean, m.0.projected_distance.max)
        }),
        euclidean_distance: agg(MetricId::EuclideanDistance, &|m| {
            (m.0.euclidean_distance.mean, m.0.euclidean_distance.max)
        }),
        orientation: agg(MetricId::Orientation, &|m| {
            (m.0.orientation.mean, m.0.orientation.max)
        }),
        dominating_axis: axis(MetricId::DominatingAxis, |a| a.dominating_axis),
        dominating_axis_spectral: axis(MetricId::DominatingAxisSpectral, |a| {
            a.dominating_axis_spectral
        }),
        matching: match matching {
            Ok(how) => how,
            Err(reason) => reason,
        },
        // Set by the caller, which reads the files.
        cost: Costs::default(),
        // Colour and total are the caller's, which times the renders.
        timings_s: EvalTimings {
            matching: (t2 - t1).as_secs_f64(),
            trajectories: t2.elapsed().as_secs_f64(),
            ..EvalTimings::default()
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use frond_render::{DrawMaterial, DrawTexture};

    #[test]
    fn whitening_keeps_alpha_and_normal_maps() {
        let texture = |v: u8| DrawTexture {
            width: 1,
            height: 2,
            rgba: vec![v, 10, 20, 0, v, 30, 40, 200],
        };
        let mut scene = DrawScene {
            meshes: vec![],
            materials: vec![DrawMaterial {
                base_color: [0.2, 0.4, 0.6, 0.7],
                texture: Some(0),
                normal_texture: Some(1),
                ..DrawMaterial::default()
            }],
            textures: vec![texture(5), texture(128)],
        };
        whiten(&mut scene);
        assert_eq!(scene.materials[0].base_color, [1.0, 1.0, 1.0, 0.7]);
        assert_eq!(
            scene.textures[0].rgba,
            vec![255, 255, 255, 0, 255, 255, 255, 200]
        );
        assert_eq!(
            scene.textures[1].rgba,
            texture(128).rgba,
            "the normal map as it was"
        );
    }
}
