//! Animation zones (spec animated-billboard-clouds §4.14, App. C.2): the triangles of one bone
//! that lie close together move alike, so SCA describes and clusters one centroid trajectory
//! per zone instead of every triangle. The thesis leaves the clustering open: here a uniform
//! grid per bone whose cells have a diagonal of `size`, so no two members of a zone are farther
//! apart than `size` (the error-based bound of App. C.2).

use std::collections::BTreeMap;

use glam::Vec3;

/// One animation zone.
#[derive(Clone, Debug, PartialEq)]
pub struct Zone {
    /// The bone (any id the caller uses) its triangles follow; None for unbound triangles.
    pub bone: Option<usize>,
    /// Indices of its triangles, ascending.
    pub members: Vec<usize>,
}

/// Zones of triangles with bones `bones[i]` and first-frame centres `first[i]`, no member
/// farther than `size` from another; `size ≤ 0` (or not finite) gives one zone per triangle.
/// Zones come ordered by bone, then cell, so the result does not depend on threads.
pub fn animation_zones(bones: &[Option<usize>], first: &[Vec3], size: f32) -> Vec<Zone> {
    let n = bones.len().min(first.len());
    if !(size > 0.0 && size.is_finite()) {
        return (0..n)
            .map(|i| Zone {
                bone: bones[i],
                members: vec![i],
            })
            .collect();
    }
    let cell = size / 3f32.sqrt();
    let mut grid: BTreeMap<(Option<usize>, [i64; 3]), Vec<usize>> = BTreeMap::new();
    for i in 0..n {
        let c = (first[i] / cell).floor();
        let key = [c.x as i64, c.y as i64, c.z as i64];
        grid.entry((bones[i], key)).or_default().push(i);
    }
    grid.into_iter()
        .map(|((bone, _), members)| Zone { bone, members })
        .collect()
}

/// The mean trajectory of `members` (the zone centroid's motion): all trajectories have the
/// same length.
pub fn mean_trajectory<'a>(members: impl IntoIterator<Item = &'a [Vec3]>) -> Vec<Vec3> {
    let mut sum: Vec<Vec3> = Vec::new();
    let mut count = 0usize;
    for t in members {
        if sum.is_empty() {
            sum = vec![Vec3::ZERO; t.len()];
        }
        for (s, p) in sum.iter_mut().zip(t) {
            *s += *p;
        }
        count += 1;
    }
    if count > 0 {
        for s in &mut sum {
            *s /= count as f32;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zones_split_by_bone_and_distance() {
        let bones = [Some(0), Some(0), Some(1), Some(0), None];
        let first = [
            Vec3::ZERO,
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::new(0.05, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::ZERO,
        ];
        let z = animation_zones(&bones, &first, 1.0);
        // Bone None first, then bone 0's two cells, then bone 1.
        assert_eq!(z.len(), 4);
        let all: Vec<usize> = z.iter().flat_map(|z| z.members.clone()).collect();
        let mut sorted = all.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 1, 2, 3, 4]);
        for zone in &z {
            for &a in &zone.members {
                assert_eq!(bones[a], zone.bone);
                for &b in &zone.members {
                    assert!(first[a].distance(first[b]) <= 1.0);
                }
            }
        }
        assert!(z.iter().any(|z| z.members == vec![0, 1]));
        assert_eq!(animation_zones(&bones, &first, 0.0).len(), 5);
    }

    #[test]
    fn mean_trajectory_is_the_centroid_motion() {
        let a = [Vec3::ZERO, Vec3::X];
        let b = [Vec3::Y, Vec3::Y + Vec3::X];
        let m = mean_trajectory([&a[..], &b[..]]);
        assert_eq!(m, vec![Vec3::Y * 0.5, Vec3::X + Vec3::Y * 0.5]);
        assert!(mean_trajectory(std::iter::empty()).is_empty());
    }
}
