//! LOD sizes from a screen-space error budget (spec view-dependent-hierarchies-gpu §2.3–2.4,
//! Holst & Schumann eq. 3 and 9): a LOD is the screen height in pixels the whole tree covers;
//! one pixel there is `tree height / screen height` world units, the plane tolerance ε is the
//! pixel budget in those units, and textures get about one texel per screen pixel.

use serde::Serialize;

use crate::cost_budget::{IMPOSTOR_TEXELS_PER_PIXEL, is_impostor_class};

/// Why the LODs cannot be sized; each variant names the value to change.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SizingError {
    /// The tree is flat or empty: pixels per world unit cannot be derived.
    #[error("the tree has no height to size LODs by")]
    NoHeight,
    /// The pixel-error budget is not a positive number.
    #[error("the pixel error must be a positive number of pixels")]
    PixelError,
    /// The screen heights do not go from near (largest) to far (smallest).
    #[error(
        "screen heights {}: they go from the nearest LOD (largest) to the farthest \
         (smallest), each smaller than the one before, but {before} is followed by {after} \
         (did you mean {}?)",
        list(.given),
        list(.sorted)
    )]
    NotNearToFar {
        /// The screen heights given, pixels.
        given: Vec<f32>,
        /// The first height not followed by a smaller one.
        before: f32,
        /// The height that follows it.
        after: f32,
        /// The given heights largest first, without repeats: what was likely meant.
        sorted: Vec<f32>,
    },
    /// A screen height under one pixel.
    #[error("LOD screen height {0} must be at least 1 pixel")]
    TooSmall(f32),
}

/// Screen heights as a comma-separated list.
fn list(heights: &[f32]) -> String {
    heights
        .iter()
        .map(|h| h.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// What one LOD may spend.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct LodLevel {
    /// Pixels the tree's height covers on screen.
    pub screen_height: f32,
    /// World units per screen pixel at that size.
    pub pixel: f32,
    /// Plane tolerance (world units).
    pub epsilon: f32,
    /// Texels per world unit of the billboards' textures.
    pub texels_per_unit: f32,
    /// Geometric error allowed to the wood simplification (world units).
    pub wood_error: f32,
}

/// Screen height (pixels) of an object of height `height` at `distance` with a vertical field
/// of view `fov_deg` and `resolution` pixels of image height: Holst eq. 3,
/// `s = l / z · (res / 2) · cot(fov / 2)`.
pub fn screen_height_at(height: f32, distance: f32, fov_deg: f32, resolution: f32) -> f32 {
    let pc = 0.5 * resolution / (0.5 * fov_deg.to_radians()).tan();
    height / distance * pc
}

/// Billboard texels per screen pixel (each axis) of a LOD `screen_height` pixels high: one,
/// and at the far end ([`is_impostor_class`]) [`IMPOSTOR_TEXELS_PER_PIXEL`], where almost
/// every pixel of a crown is partly covered and a texel's covered fraction needs finer
/// texels than the pixel to follow the leaves' outline when the billboard is resampled at a
/// random offset (spec animated-billboard-clouds §2.4; docs/experiments.md, "The far end
/// under its budget").
pub fn texels_per_pixel(screen_height: f32) -> f32 {
    if is_impostor_class(screen_height) {
        IMPOSTOR_TEXELS_PER_PIXEL
    } else {
        1.0
    }
}

/// The LOD levels for `screen_heights` (pixels) of a tree `tree_height` high, with an error
/// budget of `budget_px` pixels; `epsilon` overrides the derived ε.
pub fn lod_levels(
    tree_height: f32,
    screen_heights: &[f32],
    budget_px: f32,
    epsilon: Option<f32>,
) -> Result<Vec<LodLevel>, SizingError> {
    if !(tree_height.is_finite() && tree_height > 0.0) {
        return Err(SizingError::NoHeight);
    }
    if !(budget_px.is_finite() && budget_px > 0.0) {
        return Err(SizingError::PixelError);
    }
    // LOD1 is the nearest: each LOD must be built for a smaller screen size than the one before
    // it, or the chain would get coarser and then finer again.
    if let Some(w) = screen_heights
        .windows(2)
        .find(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Less))
    {
        let mut sorted: Vec<f32> = screen_heights.to_vec();
        sorted.sort_by(|a, b| b.total_cmp(a));
        sorted.dedup();
        return Err(SizingError::NotNearToFar {
            given: screen_heights.to_vec(),
            before: w[0],
            after: w[1],
            sorted,
        });
    }
    screen_heights
        .iter()
        .map(|&h| {
            if !(h.is_finite() && h >= 1.0) {
                return Err(SizingError::TooSmall(h));
            }
            let pixel = tree_height / h;
            let eps = epsilon.unwrap_or(budget_px * pixel);
            Ok(LodLevel {
                screen_height: h,
                pixel,
                epsilon: eps,
                texels_per_unit: texels_per_pixel(h) / pixel,
                wood_error: budget_px * pixel,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screen_heights_go_near_to_far() {
        let err = lod_levels(30.0, &[60.0, 600.0], 1.0, None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("did you mean 600,60?"), "{err}");
        assert!(!err.contains("--"), "{err}");
        let err = lod_levels(30.0, &[600.0, 600.0], 1.0, None).unwrap_err();
        assert!(err.to_string().contains("followed by 600"), "{err}");
        assert_eq!(
            err,
            SizingError::NotNearToFar {
                given: vec![600.0, 600.0],
                before: 600.0,
                after: 600.0,
                sorted: vec![600.0],
            }
        );
        assert_eq!(
            lod_levels(30.0, &[60.0], 0.0, None),
            Err(SizingError::PixelError)
        );
        assert_eq!(
            lod_levels(30.0, &[600.0, 200.0, 60.0], 1.0, None)
                .unwrap()
                .len(),
            3
        );
    }

    #[test]
    fn one_pixel_of_a_600_pixel_tree() {
        let l = lod_levels(30.0, &[600.0, 60.0], 1.0, None).unwrap();
        assert!((l[0].pixel - 0.05).abs() < 1e-6);
        assert!((l[0].epsilon - 0.05).abs() < 1e-6);
        assert!((l[0].texels_per_unit - 20.0).abs() < 1e-4);
        assert!((l[1].epsilon - 0.5).abs() < 1e-6);
        let o = lod_levels(30.0, &[600.0], 2.0, Some(0.01)).unwrap();
        assert_eq!(o[0].epsilon, 0.01);
        assert!((o[0].wood_error - 0.1).abs() < 1e-6);
        assert!(lod_levels(30.0, &[0.5], 1.0, None).is_err());
        assert!(lod_levels(0.0, &[60.0], 1.0, None).is_err());
    }

    #[test]
    fn distance_to_screen_height() {
        // 90° fov: cot(45°) = 1, so a 10-unit tree at distance 10 covers res/2 pixels.
        let h = screen_height_at(10.0, 10.0, 90.0, 1080.0);
        assert!((h - 540.0).abs() < 1e-3);
    }
}
