//! When each LOD of a chain is shown, in the values engines take (`gltf-and-toolchain.md`,
//! "LOD chains"): the chain is built for screen heights, engines switch on their own measures.
//!
//! The rule is the one `MSFT_screencoverage` is written with: LOD k (k ≥ 1, built for `H_k`
//! pixels) is shown from the size the LOD before it was built for down to its own next LOD's
//! size; LOD0 above `H_1`; the last LOD down to a quarter of its own size, below which the
//! tree is culled. From that one fraction `c` of the screen height the tree's height covers
//! (at an image `resolution` pixels high, vertical field of view `fov`):
//!
//! - **distance** `d = tree_height / (2 c tan(fov/2))`: Godot 4's
//!   `visibility_range_begin`/`_end` and Bevy's `VisibilityRange` (start and end, no fade
//!   margin) are distances from the camera;
//! - **Unity** `LODGroup` `screenRelativeTransitionHeight`: the LOD group's size (Unity sets it
//!   to the largest extent of the bounds) over the view height at that distance, so
//!   `c · size / tree_height`;
//! - **Unreal** LOD screen size: the bounding sphere's projected diameter over the screen
//!   height (`ComputeBoundsScreenSize`), so `c · 2r / tree_height`.

use serde::{Deserialize, Serialize};

/// The view a chain's switch values assume.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwitchView {
    /// Vertical field of view in degrees.
    pub fov_deg: f32,
    /// Image height in pixels.
    pub resolution: f32,
    /// The tree's height (what screen heights measure), world units.
    pub tree_height: f32,
    /// Largest extent of the tree's bounds (Unity's LOD group size).
    pub bounds_size: f32,
    /// Radius of the sphere around the bounds (half their diagonal; Unreal's bounds).
    pub sphere_radius: f32,
}

/// Where one LOD is shown, for each engine.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwitchValues {
    /// Smallest fraction of the screen height the tree covers while this LOD is shown (its
    /// `MSFT_screencoverage` value).
    pub min_screen_fraction: f32,
    /// Unity `LODGroup` LOD `screenRelativeTransitionHeight`.
    pub unity_transition_height: f32,
    /// Unreal static/skeletal mesh LOD `ScreenSize`.
    pub unreal_screen_size: f32,
    /// Camera distance at which this LOD starts (Godot 4 `visibility_range_begin`, Bevy
    /// `VisibilityRange` start); 0 for LOD0.
    pub begin_distance: f32,
    /// Camera distance at which the next LOD takes over, or the tree is culled after the last
    /// (Godot 4 `visibility_range_end`, Bevy `VisibilityRange` end).
    pub end_distance: f32,
}

/// The smallest screen fraction each LOD is shown at, LOD0 first, for LODs built at
/// `screen_heights` (pixels, nearest first) on an image `resolution` high: LOD k down to the
/// size the next LOD was built for, the last to a quarter of its own.
pub fn min_screen_fractions(screen_heights: &[f32], resolution: f32) -> Vec<f32> {
    let mut c: Vec<f32> = screen_heights
        .iter()
        .map(|h| (h / resolution).min(1.0))
        .collect();
    let last = c.last().copied().unwrap_or(0.0) * 0.25;
    c.push(last);
    c
}

/// Every LOD's switch values (LOD0 first) for LODs built at `screen_heights`.
pub fn switch_values(screen_heights: &[f32], view: &SwitchView) -> Vec<SwitchValues> {
    let fractions = min_screen_fractions(screen_heights, view.resolution);
    let tan = (view.fov_deg.to_radians() * 0.5).tan().max(1e-6);
    let distance = |c: f32| view.tree_height / (2.0 * c.max(1e-6) * tan);
    let height = view.tree_height.max(1e-12);
    fractions
        .iter()
        .enumerate()
        .map(|(k, &c)| SwitchValues {
            min_screen_fraction: c,
            unity_transition_height: c * view.bounds_size / height,
            unreal_screen_size: c * 2.0 * view.sphere_radius / height,
            begin_distance: if k == 0 {
                0.0
            } else {
                distance(fractions[k - 1])
            },
            end_distance: distance(c),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_put_the_tree_at_the_size_each_lod_was_built_for() {
        let view = SwitchView {
            fov_deg: 60.0,
            resolution: 1080.0,
            tree_height: 10.0,
            bounds_size: 10.0,
            sphere_radius: 6.0,
        };
        let s = switch_values(&[600.0, 200.0, 60.0], &view);
        assert_eq!(s.len(), 4);
        // At LOD0's end the tree is 600 px of 1080: its height over the view height there.
        let view_height = |d: f32| 2.0 * d * (30f32).to_radians().tan();
        assert!((10.0 / view_height(s[0].end_distance) - 600.0 / 1080.0).abs() < 1e-5);
        assert!((10.0 / view_height(s[3].end_distance) - 15.0 / 1080.0).abs() < 1e-5);
        for k in 1..4 {
            assert_eq!(s[k].begin_distance, s[k - 1].end_distance);
            assert!(s[k].end_distance > s[k].begin_distance);
            assert!(s[k].unity_transition_height < s[k - 1].unity_transition_height);
        }
        assert_eq!(s[0].begin_distance, 0.0);
        // Unity and Unreal scale the same fraction by their bounds.
        assert!((s[1].unity_transition_height - 200.0 / 1080.0).abs() < 1e-6);
        assert!((s[1].unreal_screen_size - 200.0 / 1080.0 * 1.2).abs() < 1e-6);
    }
}
