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
    TriangleScores, axis_aggregate, binary_coverage_metric, colour_difference_metric,
    coverage_metric, triangle_aggregate,
};
use crate::cost::cost;
use crate::coverage::{
    CoverageImages, CoverageParams, CoverageReport, DEFAULT_ELEVATIONS_DEG, MAX_HELD_IMAGE_BYTES,
    MetricError, compare_images, coverage_error, coverage_images, image_bytes,
};
use crate::dominating_axis::{AxisMetrics, axis_metrics};
use crate::framing::{framing, samples_per_side};
use crate::matching::{match_foreign, match_triangles};
use crate::metric_id::MetricId;
use crate::report::{Costs, CoverageMetrics, EVAL_SCHEMA_VERSION, EvalReport, EvalTimings, Metric};
use crate::triangle_metrics::{image_trajectory, triangle_metrics};

/// What `frond eval` was asked for.
#[derive(Clone, Debug)]
pub struct EvalRequest {
    /// Views per ring of the coverage metrics (odd, thesis §8.3.1).
    pub views: u32,
    /// Frames of the animated coverage metrics.
    pub frames: u32,
    /// The screen height the candidate is judged at: the tree's rest height spans this many
    /// pixels ([`crate::framing`](mod@crate::framing)).
    pub screen_height: f32,
    /// The screen's vertical field of view, degrees (the switch values').
    pub fov_deg: f32,
    /// The screen's height in pixels (the switch values').
    pub resolution: f32,
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
    /// The original's images per screen height (its bits), parts drawn and colour.
    images: HashMap<ImagesKey, CoverageImages>,
    views: u32,
    fov_deg: f32,
    resolution: f32,
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
            images: Default::default(),
            views: req.views,
            fov_deg: req.fov_deg,
            resolution: req.resolution,
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

    /// Renders the original's coverage images (without colour, as [`EvalContext::coverage`]
    /// draws them) at each of `screen_heights` now rather than on first use: `frond lod` draws
    /// them while it builds the LODs they are compared with.
    pub fn prepare_coverage(&mut self, screen_heights: &[f32]) -> Result<(), EvalError> {
        for &h in screen_heights {
            self.original_images(h, TreeParts::All, false)?;
        }
        Ok(())
    }

    /// The coverage metric's parameters at `screen_height`.
    pub fn params(&self, screen_height: f32, colour: bool) -> CoverageParams {
        CoverageParams {
            views: self.views,
            elevations_deg: DEFAULT_ELEVATIONS_DEG.to_vec(),
            frames: self.frame_times.len() as u32,
            screen_height,
            fov_y_deg: self.fov_deg,
            resolution: self.resolution,
            colour,
            lighting: self.lighting,
            ..Default::default()
        }
    }

    fn scenes(&self, tree: &Tree, clip: Option<usize>, parts: TreeParts) -> Vec<DrawScene> {
        self.frame_times
            .iter()
            .map(|&t| {
                let mut scene = tree_scene(tree, clip, t, parts);
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

    /// The original's coverage images at `screen_height` (of `parts`, with colour or not),
    /// rendered on first use.
    fn original_images(
        &mut self,
        screen_height: f32,
        parts: TreeParts,
        colour: bool,
    ) -> Result<&CoverageImages, EvalError> {
        let key = (screen_height.to_bits(), parts, colour);
        if !self.images.contains_key(&key) {
            let oc = self.original.clip_index(self.sampled.clip.as_deref());
            let m = self.images_of(self.original, oc, screen_height, parts, colour)?;
            self.images.insert(key, m);
        }
        Ok(&self.images[&key])
    }

    /// `tree`'s coverage images at `screen_height`, playing its clip `clip`.
    fn images_of(
        &self,
        tree: &Tree,
        clip: Option<usize>,
        screen_height: f32,
        parts: TreeParts,
        colour: bool,
    ) -> Result<CoverageImages, EvalError> {
        let (lo, hi) = self.bounds();
        coverage_images(
            self.renderer,
            &self.scenes(tree, clip, parts),
            lo,
            hi,
            &self.params(screen_height, colour),
        )
        .map_err(EvalError::colour(&tree.source, "coverage metric"))
    }

    /// `candidate`'s coverage images at `screen_height` as [`EvalContext::coverage`] draws
    /// them (the whole tree, without colour), playing the clip the original plays.
    pub fn images(
        &self,
        candidate: &Tree,
        screen_height: f32,
    ) -> Result<CoverageImages, EvalError> {
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        self.images_of(candidate, cc, screen_height, TreeParts::All, false)
    }

    /// The animated coverage error of `candidate` at `screen_height` (spec
    /// animated-billboard-clouds §5.4 filtered, [`crate::coverage`]): the coverage metrics
    /// [`EvalContext::evaluate`] reports, alone — no per-triangle metrics, no file cost.
    pub fn coverage(
        &mut self,
        candidate: &Tree,
        screen_height: f32,
    ) -> Result<CoverageReport, EvalError> {
        self.measure(candidate, screen_height).map(|m| m.report)
    }

    /// [`EvalContext::coverage`], with the candidate's images (for comparing it with other
    /// models at the same size, [`EvalContext::compare`]) and the depth complexities of the
    /// candidate and of the original read off the metric's own first render of each.
    pub fn measure(&mut self, candidate: &Tree, screen_height: f32) -> Result<Measured, EvalError> {
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let (mut reports, images) = self
            .reports(
                candidate,
                cc,
                screen_height,
                (TreeParts::All, false),
                &[&all],
            )
            .map_err(EvalError::colour(
                &candidate.source,
                "animated coverage metric",
            ))?;
        let original_depth = match &images {
            Some(_) => {
                self.original_images(screen_height, TreeParts::All, false)?
                    .first_depth_complexity
            }
            None => None,
        };
        let original_tree = self.original;
        let depth = |images_depth: Option<f64>, tree: &Tree| match images_depth {
            Some(d) => Ok(d),
            None => self.depth_complexity(tree, screen_height),
        };
        let candidate_depth = images.as_ref().and_then(|i| i.first_depth_complexity);
        Ok(Measured {
            report: reports.remove(0),
            depth_complexity: depth(candidate_depth, candidate)?,
            original_depth_complexity: depth(original_depth, original_tree)?,
            images,
        })
    }

    /// The metric's framing at `screen_height`: its cameras and image size.
    pub fn framing(&self, screen_height: f32) -> Result<crate::framing::Framing, EvalError> {
        let (lo, hi) = self.bounds();
        framing(lo, hi, &self.params(screen_height, false))
            .map_err(EvalError::colour(&self.original.source, "coverage metric"))
    }

    /// Whether one model's images at `screen_height` (with colour or not) are kept whole: within
    /// [`MAX_HELD_IMAGE_BYTES`]. Larger ones are rendered and compared a few pairs at a time.
    fn held(&self, screen_height: f32, colour: bool) -> Result<bool, MetricError> {
        let (lo, hi) = self.bounds();
        let f = framing(lo, hi, &self.params(screen_height, colour))?;
        let pairs = f.cameras.len() * self.frame_times.len();
        Ok(image_bytes(&f, pairs, colour) <= MAX_HELD_IMAGE_BYTES)
    }

    /// `candidate` (playing clip `cc`) against the original at `screen_height`, drawing
    /// `parts` with colour or not, over each of `frame_sets`: from the original's images kept
    /// and the candidate's (returned) where they are held ([`EvalContext::held`]), else pair by
    /// pair ([`coverage_error`]).
    fn reports(
        &mut self,
        candidate: &Tree,
        cc: Option<usize>,
        screen_height: f32,
        (parts, colour): (TreeParts, bool),
        frame_sets: &[&[usize]],
    ) -> Result<(Vec<CoverageReport>, Option<CoverageImages>), MetricError> {
        let unpack = |e: EvalError| match e {
            EvalError::Colour { source, .. } => source,
            other => MetricError::InvalidParams(other.to_string()),
        };
        if self.held(screen_height, colour)? {
            let images = self
                .images_of(candidate, cc, screen_height, parts, colour)
                .map_err(unpack)?;
            let original = self
                .original_images(screen_height, parts, colour)
                .map_err(unpack)?;
            let reports = (frame_sets.iter())
                .map(|set| compare_images(original, &images, set))
                .collect::<Result<_, _>>()?;
            return Ok((reports, Some(images)));
        }
        let (lo, hi) = self.bounds();
        let oc = self.original.clip_index(self.sampled.clip.as_deref());
        let (o, c) = (
            self.scenes(self.original, oc, parts),
            self.scenes(candidate, cc, parts),
        );
        let reports = (frame_sets.iter())
            .map(|set| {
                let pick = |scenes: &[DrawScene]| -> Vec<DrawScene> {
                    set.iter().map(|&f| scenes[f].clone()).collect()
                };
                let params = CoverageParams {
                    frames: set.len() as u32,
                    ..self.params(screen_height, colour)
                };
                coverage_error(self.renderer, &pick(&o), &pick(&c), lo, hi, &params)
            })
            .collect::<Result<_, _>>()?;
        Ok((reports, None))
    }

    /// The animated coverage error of `candidate` against `reference` (the original when None)
    /// at `screen_height`, both drawn whole and compared pair by pair: the switch pop where
    /// the images are too large to keep ([`Measured::images`] is None).
    pub fn compare_trees(
        &self,
        reference: Option<&Tree>,
        candidate: &Tree,
        screen_height: f32,
    ) -> Result<CoverageReport, EvalError> {
        let reference = reference.unwrap_or(self.original);
        let clip = |t: &Tree| candidate_clip(t, self.sampled.clip.as_deref());
        let (lo, hi) = self.bounds();
        coverage_error(
            self.renderer,
            &self.scenes(reference, clip(reference), TreeParts::All),
            &self.scenes(candidate, clip(candidate), TreeParts::All),
            lo,
            hi,
            &self.params(screen_height, false),
        )
        .map_err(EvalError::colour(
            &candidate.source,
            "animated coverage metric",
        ))
    }

    /// The animated coverage error of the images `candidate` against those of `reference`
    /// (both from [`EvalContext::images`] or [`EvalContext::measure`] at `screen_height`), the
    /// original's when `reference` is None: what a player sees change when an engine swaps
    /// one model for the other at that size.
    pub fn compare(
        &mut self,
        reference: Option<&CoverageImages>,
        candidate: &CoverageImages,
        screen_height: f32,
        file: &Path,
    ) -> Result<CoverageReport, EvalError> {
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let reference = match reference {
            Some(r) => r,
            None => self.original_images(screen_height, TreeParts::All, false)?,
        };
        compare_images(reference, candidate, &all)
            .map_err(EvalError::colour(file, "animated coverage metric"))
    }

    /// The depth complexity of `candidate`'s foliage at `screen_height`, from the metric's
    /// first view at its first frame ([`crate::coverage::depth_complexity`]).
    pub fn depth_complexity(&self, candidate: &Tree, screen_height: f32) -> Result<f64, EvalError> {
        let clip = candidate_clip(candidate, self.sampled.clip.as_deref());
        let t = self.frame_times.first().copied().unwrap_or(0.0);
        let scene = tree_scene(candidate, clip, t, TreeParts::Foliage);
        let (lo, hi) = self.bounds();
        crate::coverage::depth_complexity(&scene, lo, hi, 0, &self.params(screen_height, false))
            .map_err(EvalError::colour(&candidate.source, "depth complexity"))
    }

    /// Evaluates `candidate` at `screen_height`; `same_file` (the two files have the same
    /// bytes) matches every triangle to itself.
    pub fn evaluate(
        &mut self,
        candidate: &Tree,
        same_file: bool,
        screen_height: f32,
    ) -> Result<EvalReport, EvalError> {
        let t0 = Instant::now();
        let candidate_file = file_cost(&candidate.source, &self.limits).map_err(EvalError::Cost)?;
        let cc = candidate_clip(candidate, self.sampled.clip.as_deref());
        let all: Vec<usize> = (0..self.frame_times.len()).collect();
        let original: &'a Tree = self.original;
        let colour_error = EvalError::colour(&original.source, "animated coverage metric");
        // The foliage alone, without colour; a tree without foliage has no such error.
        let foliage = self.reports(
            candidate,
            cc,
            screen_height,
            (TreeParts::Foliage, false),
            &[&all],
        );
        let foliage = match foliage {
            Ok((r, _)) => coverage_metric(MetricId::CoverageFoliage, &r[0]),
            Err(MetricError::NothingCovered { .. }) => Metric::skipped(
                MetricId::CoverageFoliage,
                "the original has no foliage to cover any pixel",
            ),
            Err(e) => return Err(colour_error(e)),
        };
        // The static metric (F = 1) is the animated one's first frame: the same renders.
        let (mut reports, _) = self
            .reports(
                candidate,
                cc,
                screen_height,
                (TreeParts::All, true),
                &[&[0], &all],
            )
            .map_err(colour_error)?;
        let (anim, stat) = (reports.remove(1), reports.remove(0));
        let (lo, hi) = self.bounds();
        let f = framing(lo, hi, &self.params(screen_height, true))
            .map_err(EvalError::colour(&original.source, "coverage metric"))?;
        let framing = (f.width, f.height);
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
        report.coverage.foliage = foliage;
        report.views = self.views;
        report.elevations_deg = DEFAULT_ELEVATIONS_DEG.to_vec();
        report.frames = self.frame_times.len() as u32;
        report.screen_height = screen_height;
        report.fov_deg = self.fov_deg;
        report.resolution = self.resolution;
        report.size = [framing.0, framing.1];
        report.samples_per_side = samples_per_side(screen_height);
        report.cost = Costs {
            original: cost(self.original, self.original_file.clone()),
            candidate: cost(candidate, candidate_file),
        };
        report.timings_s.colour = (t1 - t0).as_secs_f64();
        report.timings_s.total = t0.elapsed().as_secs_f64();
        Ok(report)
    }
}

/// What [`EvalContext::measure`] finds of one candidate.
pub struct Measured {
    /// The coverage metrics against the original.
    pub report: CoverageReport,
    /// The candidate's images, to compare it with other models at the same size; None when
    /// too large to keep ([`EvalContext::compare_trees`] compares the models then).
    pub images: Option<CoverageImages>,
    /// The candidate's depth complexity ([`crate::coverage::depth_complexity`]).
    pub depth_complexity: f64,
    /// The original's, drawn alike.
    pub original_depth_complexity: f64,
}

/// The key of the original's cached images: screen height (bits), parts drawn, colour.
type ImagesKey = (u32, TreeParts, bool);

/// Evaluates `candidate` against `original`; `same_file` (the two files have the same bytes)
/// matches every triangle to itself.
pub fn evaluate(
    renderer: &Renderer,
    original: &Tree,
    candidate: &Tree,
    same_file: bool,
    req: &EvalRequest,
) -> Result<EvalReport, EvalError> {
    EvalContext::new(renderer, original, req)?.evaluate(candidate, same_file, req.screen_height)
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
        schema_version: EVAL_SCHEMA_VERSION,
        colour_shift: anim.colour_shift,
        original: original.source.display().to_string(),
        candidate: candidate.source.display().to_string(),
        clip: sampled.clip.clone(),
        samples: sampled.samples(),
        // Set by the caller, which knows the coverage metrics' setup.
        views: 0,
        elevations_deg: Vec::new(),
        frames: 0,
        screen_height: 0.0,
        fov_deg: 0.0,
        resolution: 0.0,
        size: [0, 0],
        samples_per_side: 0,
        tree_height: original.height(),
        coverage: CoverageMetrics {
            static_: coverage_metric(MetricId::CoverageStatic, stat),
            animated: coverage_metric(MetricId::CoverageAnimated, anim),
            binary: binary_coverage_metric(anim),
            // Set by the caller, which draws the foliage alone.
            foliage: Metric::skipped(MetricId::CoverageFoliage, "not measured"),
            ratio: anim.ratio,
            loop_change: anim.loop_change_original,
            loop_change_ratio: anim.loop_change_ratio(),
            discarded_pairs: anim.binary.discarded,
            pairs: anim.per_pair.len(),
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
