//! Samples a clip's loop uniformly into skinned vertex positions, bone world transforms,
//! per-foliage-triangle centre trajectories and the average pose (spec §4.3, §4.11 step 2).

use glam::{Mat4, Vec3};
use rayon::prelude::*;

use crate::error::{Result, SceneError};
use crate::model::Tree;
use crate::rig::{local_pose, world_matrices};
use crate::skinning::{palettes, skin_into};

/// A loop whose first and last poses differ by more than this × tree height does not loop.
pub const LOOP_TOLERANCE: f32 = 1e-3;
/// A clip whose vertices never move more than this × tree height has no motion.
pub const MOTION_TOLERANCE: f32 = 1e-5;

/// What to sample.
#[derive(Clone, Debug)]
pub struct SampleOptions {
    /// Clip name; the first clip when None.
    pub clip: Option<String>,
    /// Number of uniform samples over one period.
    pub samples: usize,
}

impl Default for SampleOptions {
    fn default() -> Self {
        SampleOptions {
            clip: None,
            samples: 64,
        }
    }
}

/// The sampled loop. Arrays are flat: `positions[s * vertices + v]`,
/// `bone_world[s * bones + b]`, `centres[k * samples + s]` for foliage triangle `k`.
#[derive(Clone, Debug)]
pub struct Sampled {
    /// Name of the clip sampled; None for a tree without clips.
    pub clip: Option<String>,
    /// Length of the loop, seconds (0 for a one-frame loop).
    pub period: f32,
    /// Sample times, seconds: `start + period · s / samples`.
    pub times: Vec<f32>,
    /// Vertices per pose (the tree's).
    pub vertices: usize,
    /// Sample-major skinned positions ([`Sampled::pose`]). This, `bone_world`, `centres` and
    /// `average` are empty for a loop sampled without its poses ([`sample_loop`],
    /// [`Sampled::into_loop`]): on the largest presets they take gigabytes, and card LODs, the
    /// files and the report need only the loop's clock and its motion facts.
    pub positions: Vec<Vec3>,
    /// Sample-major world transforms of the bones.
    pub bone_world: Vec<Mat4>,
    /// Indices (into `Tree::triangles`) of the non-degenerate foliage triangles.
    pub foliage: Vec<usize>,
    /// Per foliage triangle (in [`Sampled::foliage`] order), its centre at every sample.
    pub centres: Vec<Vec3>,
    /// Every vertex at its mean position over the loop.
    pub average: Vec<Vec3>,
    /// Whether the clip loops and moves.
    pub motion: Motion,
}

/// Loop and motion facts of a clip.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Motion {
    /// Largest vertex distance between the first and the last pose.
    pub loop_gap: f32,
    /// Largest vertex distance from the first pose over the samples.
    pub max_displacement: f32,
    /// Whether the first and last poses match within [`LOOP_TOLERANCE`] × tree height.
    pub loops: bool,
    /// Whether any vertex moves more than [`MOTION_TOLERANCE`] × tree height.
    pub moves: bool,
}

impl Sampled {
    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.times.len()
    }
    /// Skinned vertex positions of sample `s`.
    pub fn pose(&self, s: usize) -> &[Vec3] {
        &self.positions[s * self.vertices..(s + 1) * self.vertices]
    }
    /// Centre trajectory of foliage triangle `k` (index into `foliage`).
    pub fn trajectory(&self, k: usize) -> &[Vec3] {
        let n = self.samples();
        &self.centres[k * n..(k + 1) * n]
    }

    /// Whether the poses, trajectories and average pose are held (see [`Sampled::positions`]).
    pub fn has_poses(&self) -> bool {
        !self.positions.is_empty() || self.vertices == 0
    }

    /// The loop alone: the same clock, foliage list and motion facts, the poses,
    /// trajectories and average pose freed (see [`Sampled::positions`]).
    pub fn into_loop(self) -> Sampled {
        Sampled {
            positions: Vec::new(),
            bone_world: Vec::new(),
            centres: Vec::new(),
            average: Vec::new(),
            ..self
        }
    }
}

/// Skinned positions of every vertex at time `t` of clip `clip` (rest pose when None).
pub fn pose_at(tree: &Tree, clip: Option<usize>, t: f32) -> Vec<Vec3> {
    let world = world_at(tree, clip, t);
    crate::skinning::skin_positions(tree, &world)
}

/// Node world matrices at time `t` of clip `clip`.
pub fn world_at(tree: &Tree, clip: Option<usize>, t: f32) -> Vec<Mat4> {
    let local = local_pose(&tree.rig.nodes, clip.map(|c| &tree.rig.clips[c]), t);
    world_matrices(&tree.rig.nodes, &tree.rig.order, &local)
}

fn max_distance(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.par_iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .reduce(|| 0.0, f32::max)
}

fn scale_of(tree: &Tree) -> f32 {
    let h = tree.bounds.height();
    if h > 0.0 {
        h
    } else {
        tree.bounds.size().max(f32::MIN_POSITIVE)
    }
}

/// Loop and motion facts of clip `clip`, checked on `samples` uniform poses.
pub fn clip_motion(tree: &Tree, clip: usize, samples: usize) -> Motion {
    let c = &tree.rig.clips[clip];
    let first = pose_at(tree, Some(clip), c.start);
    let last = pose_at(tree, Some(clip), c.end);
    let mut max_disp = max_distance(&first, &last);
    for s in 1..samples.max(1) {
        let t = c.start + c.duration() * s as f32 / samples as f32;
        max_disp = max_disp.max(max_distance(&first, &pose_at(tree, Some(clip), t)));
    }
    motion_from(tree, max_distance(&first, &last), max_disp)
}

fn motion_from(tree: &Tree, loop_gap: f32, max_displacement: f32) -> Motion {
    let h = scale_of(tree);
    Motion {
        loop_gap,
        max_displacement,
        loops: loop_gap <= LOOP_TOLERANCE * h,
        moves: max_displacement > MOTION_TOLERANCE * h,
    }
}

/// The clip `options` names (its index; None for a tree without clips), the loop's start,
/// period and sample count.
fn loop_of(tree: &Tree, options: &SampleOptions) -> Result<(Option<usize>, f32, f32, usize)> {
    if options.samples == 0 {
        return Err(SceneError::Request {
            path: tree.source.clone(),
            problem: "the number of samples must be at least 1".into(),
        });
    }
    let clip = match &options.clip {
        Some(name) => Some(
            tree.clip_index(Some(name))
                .ok_or_else(|| SceneError::Request {
                    path: tree.source.clone(),
                    problem: format!(
                        "no clip named '{name}' (clips: {})",
                        tree.rig
                            .clips
                            .iter()
                            .map(|c| c.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                })?,
        ),
        None => tree.clip_index(None),
    };
    let (start, period, n) = match clip {
        Some(c) if tree.rig.clips[c].duration() > 0.0 => (
            tree.rig.clips[c].start,
            tree.rig.clips[c].duration(),
            options.samples,
        ),
        Some(c) => (tree.rig.clips[c].start, 0.0, 1),
        None => (0.0, 0.0, 1),
    };
    Ok((clip, start, period, n))
}

/// The loop's sample times.
fn times_of(start: f32, period: f32, n: usize) -> Vec<f32> {
    (0..n)
        .map(|s| start + period * s as f32 / n as f32)
        .collect()
}

/// The largest vertex distance between the first and the last pose of the loop (0 without
/// motion), from the first pose.
fn loop_gap(tree: &Tree, clip: Option<usize>, period: f32, first: &[Vec3]) -> f32 {
    match clip {
        Some(c) if period > 0.0 => {
            max_distance(first, &pose_at(tree, Some(c), tree.rig.clips[c].end))
        }
        _ => 0.0,
    }
}

/// [`sample`] without the poses, trajectories and average pose ([`Sampled::positions`]):
/// the loop's clock, foliage list and motion facts (the same), each pose skinned, compared
/// with the first and dropped.
pub fn sample_loop(tree: &Tree, options: &SampleOptions) -> Result<Sampled> {
    let (clip, start, period, n) = loop_of(tree, options)?;
    let times = times_of(start, period, n);
    let first = pose_at(tree, clip, times[0]);
    let gap = loop_gap(tree, clip, period, &first);
    let max_disp = times[1..]
        .iter()
        .map(|&t| max_distance(&first, &pose_at(tree, clip, t)))
        .fold(gap, f32::max);
    Ok(Sampled {
        clip: clip.map(|c| tree.rig.clips[c].name.clone()),
        period,
        times,
        vertices: tree.vertices.len(),
        positions: Vec::new(),
        bone_world: Vec::new(),
        foliage: tree.foliage(),
        centres: Vec::new(),
        average: Vec::new(),
        motion: motion_from(tree, gap, max_disp),
    })
}

/// Samples the chosen clip's loop. A tree without clips is a one-frame loop.
pub fn sample(tree: &Tree, options: &SampleOptions) -> Result<Sampled> {
    let (clip, start, period, n) = loop_of(tree, options)?;
    let times = times_of(start, period, n);
    let nv = tree.vertices.len();
    let nb = tree.bones.len();
    let mut positions = vec![Vec3::ZERO; n * nv];
    let mut bone_world = vec![Mat4::IDENTITY; n * nb];
    for (s, &t) in times.iter().enumerate() {
        let world = world_at(tree, clip, t);
        for (b, bone) in tree.bones.iter().enumerate() {
            bone_world[s * nb + b] = world[bone.node];
        }
        let pal = palettes(tree, &world);
        skin_into(tree, &pal, &mut positions[s * nv..(s + 1) * nv]);
    }
    let foliage = tree.foliage();
    let mut centres = vec![Vec3::ZERO; foliage.len() * n];
    centres
        .par_chunks_mut(n)
        .zip(&foliage)
        .for_each(|(traj, &ti)| {
            let v = tree.triangles[ti].v;
            for (s, c) in traj.iter_mut().enumerate() {
                let p = &positions[s * nv..(s + 1) * nv];
                *c = (p[v[0] as usize] + p[v[1] as usize] + p[v[2] as usize]) / 3.0;
            }
        });
    let inv = 1.0 / n as f32;
    let average: Vec<Vec3> = (0..nv)
        .into_par_iter()
        .map(|v| (0..n).map(|s| positions[s * nv + v]).sum::<Vec3>() * inv)
        .collect();
    let first = &positions[..nv];
    let loop_gap = loop_gap(tree, clip, period, first);
    let max_disp = (1..n)
        .map(|s| max_distance(first, &positions[s * nv..(s + 1) * nv]))
        .fold(loop_gap, f32::max);
    Ok(Sampled {
        clip: clip.map(|c| tree.rig.clips[c].name.clone()),
        period,
        times,
        vertices: nv,
        positions,
        bone_world,
        foliage,
        centres,
        average,
        motion: motion_from(tree, loop_gap, max_disp),
    })
}
