//! How `frond eval` pairs the original's foliage triangles with what replaces them in a
//! candidate (spec animated-billboard-clouds §5.2–5.5): through the `frond lod` mapping
//! sidecar (each triangle and the corners of its billboard over the loop), by identity when the
//! candidate is the original file, or, for foreign candidates without a mapping, each leaf to
//! the nearest candidate foliage point in the rest pose (§5.5), which then follows the
//! candidate's skinning.

use std::path::Path;

use frond_export::mapping::Mapping;
use frond_scene::sampling::pose_at;
use frond_scene::surface_distance::SurfaceBvh;
use frond_scene::{Part, Sampled, Tree};
use glam::Vec3;
use rayon::prelude::*;

/// One original foliage triangle's vertices at every sample, and the four corners of what
/// replaces it at the same samples.
pub type TrianglePair = (Vec<[Vec3; 3]>, Vec<[Vec3; 4]>);

/// How the triangles were matched (or why they could not be), and the matched pairs.
pub type Matched = (Result<String, String>, Vec<TrianglePair>);

/// Matches every foliage triangle of `sampled` (the original's loop) to the candidate:
/// itself when `same_file`, else its billboard in the candidate's mapping sidecar
/// (`<candidate>.mapping.json`), posed with the candidate's clip `cc` at the same times. Without
/// a readable, consistent sidecar the result is the reason and no pair.
pub fn match_triangles(
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
    let Some(mapping) = read_mapping(&sidecar) else {
        return (
            Err(format!(
                "no triangle → billboard mapping ({} missing or unreadable): the \
                 per-billboard metrics need one",
                sidecar.display()
            )),
            Vec::new(),
        );
    };
    let count = mapping.billboards.len();
    let Some(base) = billboard_base(candidate, count) else {
        return (
            Err(format!(
                "{} lists {count} billboards but the candidate's billboard mesh has {} vertices",
                sidecar.display(),
                billboard_vertices(candidate).len()
            )),
            Vec::new(),
        );
    };
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

/// The mapping sidecar at `path`, or None when it is missing or not a mapping.
fn read_mapping(path: &Path) -> Option<Mapping> {
    std::fs::read(path)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
}

/// The vertices of the candidate's billboard primitives, sorted: those of its foliage
/// triangles. A LOD with a mapping draws its foliage as billboards only: baked ones with the
/// material `frond lod` names "<lod>_billboards", then those that copy an input card with the
/// input's leaf material, in mapping order.
fn billboard_vertices(candidate: &Tree) -> Vec<u32> {
    let mut v: Vec<u32> = candidate
        .triangles
        .iter()
        .filter(|t| t.part == Part::Foliage)
        .flat_map(|t| t.v)
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The first vertex of the billboard primitive when it holds exactly `count` billboards as
/// consecutive runs of 4 vertices in mapping order; None when it does not.
fn billboard_base(candidate: &Tree, count: usize) -> Option<usize> {
    let v = billboard_vertices(candidate);
    let base = v.first().copied().unwrap_or(0) as usize;
    let consistent =
        v.len() == 4 * count && v.last().is_none_or(|&l| l as usize == base + 4 * count - 1);
    consistent.then_some(base)
}

/// For a candidate without a mapping (§5.5, foreign candidates): every original foliage
/// triangle's rest centroid is matched to the nearest point of the candidate's foliage in its
/// rest pose; that point, as barycentric coordinates of its triangle, moves with the
/// candidate's skinning (clip `cc`, at `sampled`'s times). Returns `score(the original
/// centroid's trajectory, the point's trajectory)` per matched leaf, in `sampled.foliage`
/// order, or why no leaf can be matched.
pub fn match_foreign<T: Send>(
    original: &Tree,
    candidate: &Tree,
    sampled: &Sampled,
    cc: Option<usize>,
    score: impl Fn(&[Vec3], &[Vec3]) -> T + Sync,
) -> Result<Vec<T>, String> {
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
            Some(score(sampled.trajectory(k), &image))
        })
        .collect())
}

/// Barycentric coordinates of `p` (on or near the triangle) with respect to `t`; a degenerate
/// triangle gives its first corner.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_coordinates_rebuild_the_point() {
        let t = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(0.0, 3.0, 0.0),
        ];
        let p = t[0] * 0.2 + t[1] * 0.5 + t[2] * 0.3;
        let w = barycentric(p, t);
        assert!(
            (w - Vec3::new(0.2, 0.5, 0.3)).abs().max_element() < 1e-5,
            "{w}"
        );
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(barycentric(Vec3::X, flat), Vec3::X);
    }
}
