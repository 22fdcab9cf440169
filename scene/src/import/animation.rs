//! Animations: every glTF animation read into a [`Clip`] whose channels' key times are what
//! glTF requires, under the animation key budget.

use glam::Vec4;
use gltf::json;
use gltf::json::validation::Checked;

use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::input_file::{MIN_CHANNEL_KEYS, MIN_CLIP_KEYS};
use crate::rig::{Channel, Clip, Interpolation, Property};

/// Latest key time accepted in an animation, in seconds (one hour). Wind loops last seconds;
/// a clip that runs for hours (or 4e30 s, as a corrupted time accessor gives) cannot be
/// sampled meaningfully into a loop of a few dozen poses, so it is refused rather than guessed at.
pub const MAX_ANIMATION_SECONDS: f32 = 3600.0;

/// Removes keys whose time equals the next key's time, keeping the last key of every run of
/// equal times; `per_key` values go with each key (3 for CUBICSPLINE: in-tangent, value,
/// out-tangent). Returns the times, the values and how many keys were dropped.
fn drop_repeated_keys(
    times: Vec<f32>,
    values: Vec<Vec4>,
    per_key: usize,
) -> (Vec<f32>, Vec<Vec4>, usize) {
    if times.windows(2).all(|w| w[0] < w[1]) {
        return (times, values, 0);
    }
    let mut kept_times = Vec::with_capacity(times.len());
    let mut kept_values = Vec::with_capacity(values.len());
    for (k, &t) in times.iter().enumerate() {
        if times.get(k + 1) == Some(&t) {
            continue;
        }
        kept_times.push(t);
        kept_values.extend_from_slice(&values[k * per_key..(k + 1) * per_key]);
    }
    let dropped = times.len() - kept_times.len();
    (kept_times, kept_values, dropped)
}

/// An animation's name, or `animation<i>`.
fn clip_name(anim: &json::Animation, i: usize) -> String {
    anim.name.clone().unwrap_or_else(|| format!("animation{i}"))
}

/// Per animation, the channels read: all but those whose target (node and property) an earlier
/// channel of the same animation already drives. glTF forbids two channels with one target
/// (the validator's ANIMATION_DUPLICATE_TARGETS) and players keep one; frond keeps the first,
/// with a warning naming the animation and how many were dropped.
fn kept_channels(src: &GltfSource, warnings: &mut Vec<String>) -> Vec<Vec<usize>> {
    src.root
        .animations
        .iter()
        .enumerate()
        .map(|(ai, anim)| {
            let mut seen = std::collections::HashSet::new();
            let kept: Vec<usize> = (0..anim.channels.len())
                .filter(|&ci| {
                    let t = &anim.channels[ci].target;
                    seen.insert((t.node.value(), format!("{:?}", t.path)))
                })
                .collect();
            let dropped = anim.channels.len() - kept.len();
            if dropped > 0 {
                warnings.push(format!(
                    "animation '{}': {dropped} channel{} drive a target (node and property) an earlier channel already drives; the first channel of each target kept (glTF allows one)",
                    clip_name(anim, ai),
                    if dropped == 1 { "" } else { "s" }
                ));
            }
            kept
        })
        .collect()
}

/// Refuses animations whose keys, counted from the time accessors' declared counts before any
/// is read, exceed [`InputLimits::max_animation_keys`](crate::InputLimits::max_animation_keys) (see there for how channels and clips
/// count), naming the clip with the most.
fn check_animation_budget(src: &GltfSource, kept: &[Vec<usize>]) -> Result<()> {
    let per_clip: Vec<(u64, usize)> = src
        .root
        .animations
        .iter()
        .zip(kept)
        .map(|(anim, kept)| {
            let keys = kept
                .iter()
                .map(|&ci| {
                    let declared = anim
                        .samplers
                        .get(anim.channels[ci].sampler.value())
                        .and_then(|s| src.root.accessors.get(s.input.value()))
                        .map_or(0, |a| a.count.0);
                    declared.max(MIN_CHANNEL_KEYS)
                })
                .fold(0u64, u64::saturating_add);
            (keys.max(MIN_CLIP_KEYS), kept.len())
        })
        .collect();
    let total = per_clip.iter().map(|c| c.0).fold(0u64, u64::saturating_add);
    let limit = src.limits.max_animation_keys;
    if total <= limit {
        return Ok(());
    }
    // The first of the largest.
    let (largest, &(keys, channels)) = per_clip
        .iter()
        .enumerate()
        .rev()
        .max_by_key(|(_, c)| c.0)
        .unwrap_or((0, &(0, 0)));
    let name = src
        .root
        .animations
        .get(largest)
        .map(|a| clip_name(a, largest))
        .unwrap_or_default();
    Err(src.invalid(format!(
        "its {} animations add up to {total} keys (largest: animation '{name}', {keys} keys in {channels} channels), over the animation limit of {limit} keys (raise the animation key limit to read it)",
        per_clip.len()
    )))
}

/// Reads every animation into a [`Clip`], so that each channel's key times are finite,
/// non-negative, strictly increasing and at most [`MAX_ANIMATION_SECONDS`] — what glTF
/// requires of a sampler input, and so what frond writes back validates.
///
/// Broken key times are handled per case:
/// - non-finite, negative, or decreasing (a key before the one preceding it): an error naming
///   the animation, channel, key and time. No repair is right there: shifting negative times
///   would move this channel against the others, and reordering keys guesses the intent.
/// - a key at the same time as the key before it (a run of equal times, as some exporters
///   write for a jump): repaired by keeping only the last key of the run, the value the
///   channel holds from that time on (and what frond sampled at that time before), with a
///   warning naming the channel and how many keys were dropped. For CUBICSPLINE the dropped
///   key's in-tangent, value and out-tangent go together.
/// - a key after [`MAX_ANIMATION_SECONDS`]: an error naming the channel and the time, since a
///   clip that long (a corrupted accessor gives 4e30 s) cannot be sampled into a loop.
pub(super) fn read_clips(
    src: &GltfSource,
    node_count: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<Clip>> {
    let kept = kept_channels(src, warnings);
    check_animation_budget(src, &kept)?;
    let mut clips = Vec::new();
    for (ai, anim) in src.root.animations.iter().enumerate() {
        let name = clip_name(anim, ai);
        let mut channels = Vec::new();
        let (mut start, mut end) = (f32::INFINITY, f32::NEG_INFINITY);
        for &ci in &kept[ai] {
            let ch = &anim.channels[ci];
            let what = format!("animation '{name}' channel {ci}");
            let node = ch.target.node.value();
            if node >= node_count {
                return Err(src.invalid(format!("{what}: target node {node} does not exist")));
            }
            let property = match ch.target.path {
                Checked::Valid(json::animation::Property::Translation) => Property::Translation,
                Checked::Valid(json::animation::Property::Rotation) => Property::Rotation,
                Checked::Valid(json::animation::Property::Scale) => Property::Scale,
                Checked::Valid(json::animation::Property::MorphTargetWeights) => {
                    warnings.push(format!(
                        "{what}: morph-target weights are not supported; ignored"
                    ));
                    continue;
                }
                Checked::Invalid => return Err(src.invalid(format!("{what}: invalid target path"))),
            };
            let sampler = anim.samplers.get(ch.sampler.value()).ok_or_else(|| {
                src.invalid(format!(
                    "{what}: sampler {} does not exist",
                    ch.sampler.value()
                ))
            })?;
            let interpolation = match sampler.interpolation {
                Checked::Valid(json::animation::Interpolation::Linear) => Interpolation::Linear,
                Checked::Valid(json::animation::Interpolation::Step) => Interpolation::Step,
                Checked::Valid(json::animation::Interpolation::CubicSpline) => {
                    Interpolation::CubicSpline
                }
                Checked::Invalid => {
                    return Err(src.invalid(format!("{what}: invalid interpolation")));
                }
            };
            let times = src.read_floats(sampler.input.value(), &format!("{what} input"))?;
            if times.width != 1 {
                return Err(src.invalid(format!("{what}: input must be SCALAR")));
            }
            // `+ 0.0` turns -0 into +0, so no written time reads as negative.
            let times: Vec<f32> = times.values.iter().map(|t| t + 0.0).collect();
            if let Some((k, t)) = times.iter().enumerate().find(|(_, t)| !t.is_finite()) {
                return Err(src.invalid(format!("{what}: key time {t:?} at key {k} is not finite")));
            }
            if let Some((k, t)) = times.iter().enumerate().find(|(_, t)| **t < 0.0) {
                return Err(src.invalid(format!(
                    "{what}: key time {t:?} at key {k} is negative (glTF requires times ≥ 0)"
                )));
            }
            if let Some(k) = (1..times.len()).find(|&k| times[k] < times[k - 1]) {
                return Err(src.invalid(format!(
                    "{what}: key time {:?} at key {k} is before key {}'s {:?} (glTF requires increasing times)",
                    times[k],
                    k - 1,
                    times[k - 1]
                )));
            }
            if let Some((k, t)) = times
                .iter()
                .enumerate()
                .find(|(_, t)| **t > MAX_ANIMATION_SECONDS)
            {
                return Err(src.invalid(format!(
                    "{what}: key time {t:?} s at key {k} is past frond's limit of {MAX_ANIMATION_SECONDS} s (1 hour) for an animation; sampling a clip that long is meaningless"
                )));
            }
            let out = src.read_floats(sampler.output.value(), &format!("{what} output"))?;
            let want_width = if property == Property::Rotation { 4 } else { 3 };
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            if out.width != want_width || out.count() != times.len() * per_key {
                return Err(src.invalid(format!(
                    "{what}: output has {} elements of width {}, expected {} of width {want_width}",
                    out.count(),
                    out.width,
                    times.len() * per_key
                )));
            }
            if out.values.iter().any(|v| !v.is_finite()) {
                return Err(src.invalid(format!("{what}: output contains NaN or Inf")));
            }
            if times.is_empty() {
                return Err(src.invalid(format!("{what}: sampler has no keys")));
            }
            if property == Property::Rotation
                && interpolation != Interpolation::CubicSpline
                && out
                    .values
                    .chunks_exact(4)
                    .any(|q| q.iter().map(|c| c * c).sum::<f32>() < 1e-6)
            {
                return Err(src.invalid(format!("{what}: a rotation key is not a unit quaternion")));
            }
            let values: Vec<Vec4> = (0..out.count())
                .map(|k| {
                    let v = out.get::<4>(k);
                    Vec4::from(v)
                })
                .collect();
            let (times, values, dropped) = drop_repeated_keys(times, values, per_key);
            if dropped > 0 {
                warnings.push(format!(
                    "{what}: {dropped} key{} at the same time as the key before dropped, keeping the last key at each repeated time (glTF requires strictly increasing times)",
                    if dropped == 1 { "" } else { "s" }
                ));
            }
            if let (Some(&a), Some(&b)) = (times.first(), times.last()) {
                start = start.min(a);
                end = end.max(b);
            }
            channels.push(Channel {
                node,
                property,
                interpolation,
                times,
                values,
            });
        }
        if !start.is_finite() {
            start = 0.0;
            end = 0.0;
        }
        clips.push(Clip {
            name,
            start,
            end,
            channels,
        });
    }
    Ok(clips)
}
