//! Where the coverage metric's cameras stand and how large its images are: a tree seen at
//! screen height `H` (spec animated-billboard-clouds §5.4, §8.2; docs/metrics.md, "The
//! coverage error").
//!
//! # What a size means
//!
//! A LOD built for `H` pixels is shown by an engine when the tree's height spans `H` pixels of
//! the screen the switch values assume (`frond_lod::switching`): a perspective view of
//! vertical field of view `φ` on a screen `R` pixels high. The metric sees the tree exactly so:
//! the focal length in pixels is `f = R / (2 tan(φ/2))`, and each camera stands at
//! `d = h · f / H` from the centre of the tree's rest bounds (`h` their height), looking at it,
//! so the tree's rest height at that distance spans `H` pixels. Its image is the part of that
//! screen around the tree: centred on the bounds' centre, just large enough to hold, from
//! every view, the rest bounds grown by [`SWAY_MARGIN`] of the tree's height on each side (the
//! wind moves the crown; a LOD that bloats must still be seen).
//!
//! A camera nearer than [`MIN_DISTANCE_RADII`] bounding radii (a tree filling more than about
//! a third of the screen) would see the crown's near side many times larger than its far side
//! and need an image several times the tree's size (at 2,000 px, tens of millions of pixels);
//! its screen is then taken larger, the same field of view, so that the camera stands there.
//! The tree's height still spans `H` pixels; only the perspective is that of a farther view.
//! On the default screen (1,080 px, 60°) this applies above about 400 px.
//!
//! # Views
//!
//! `D` views evenly spread over a full turn ([`ring_azimuth_deg`]: azimuth 0 is on +Z, 90 on
//! +X, the [`Camera`] convention), on each ring of elevations: a player on the ground
//! (0°) and one looking down on the tree (30° by default).
//!
//! # Samples
//!
//! Each pixel is `K × K` point samples, the fraction of them covered being the pixel's
//! coverage α. `K` is [`samples_per_side`]: at least 512 samples over the tree's height, so
//! that a leaf spans several samples even when the tree is a few pixels tall.

use frond_render::{Camera, MAX_SUPERSAMPLE, Projection};
use glam::{DVec3, Vec3};

use crate::coverage::{CoverageParams, MetricError};

/// Margin around the rest bounds that every image holds, a fraction of the tree's height on
/// each side: the wind's sway.
pub const SWAY_MARGIN: f32 = 0.1;

/// The nearest a camera stands to the tree's centre, in radii of its rest bounds' sphere.
pub const MIN_DISTANCE_RADII: f32 = 3.0;

/// Samples over the tree's height the metric takes at least ([`samples_per_side`]): a leaf a
/// hundredth of the tree's height spans five samples across at any size, which resolves its
/// covered area to a few percent; the renders' cost grows with the square of this.
pub const SAMPLES_OVER_HEIGHT: f32 = 512.0;

/// Fewest samples per pixel side: a pixel's coverage takes at least 4 values besides 0 and 1
/// even for a tree hundreds of pixels tall.
pub const MIN_SAMPLES_PER_SIDE: u32 = 2;

/// Most samples per pixel side: [`SAMPLES_OVER_HEIGHT`] over the tree down to a tree 4 pixels
/// tall; below that, fewer, the counts of a pixel's samples fitting 16 bits.
pub const MAX_SAMPLES_PER_SIDE: u32 = 128;

/// `K`, the samples per pixel side of a tree `screen_height` pixels tall:
/// `⌈512 / H⌉` within [[`MIN_SAMPLES_PER_SIDE`], [`MAX_SAMPLES_PER_SIDE`]].
pub fn samples_per_side(screen_height: f32) -> u32 {
    let k = (SAMPLES_OVER_HEIGHT / screen_height.max(1e-3)).ceil();
    (k.min(MAX_SAMPLES_PER_SIDE as f32) as u32).clamp(MIN_SAMPLES_PER_SIDE, MAX_SAMPLES_PER_SIDE)
}

/// Azimuth in degrees of view `view` of a ring of `views`: `360 · view / views`, so view 0 is
/// at azimuth 0 (spec §8.2: views evenly spread over a full rotation).
pub fn ring_azimuth_deg(view: u32, views: u32) -> f32 {
    if views == 0 {
        return 0.0;
    }
    (360.0 * f64::from(view) / f64::from(views)) as f32
}

/// The metric's cameras and image for one screen height (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Framing {
    /// Every view, ring by ring (the rings in [`CoverageParams::elevations_deg`]'s order),
    /// each ring's views by azimuth.
    pub cameras: Vec<Camera>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel side, `K`.
    pub supersample: u32,
    /// Camera distance from the bounds' centre, world units.
    pub distance: f32,
    /// Focal length in pixels: the tree's rest height spans `height_world · focal / distance`
    /// pixels (the screen height asked for).
    pub focal: f32,
}

impl Framing {
    /// The aspect ratio of the images.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }
}

/// The framing of the rest bounds `bounds_min..bounds_max` at `params.screen_height` (see the
/// module docs). Errors name what is wrong with the bounds or the parameters.
pub fn framing(
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &CoverageParams,
) -> Result<Framing, MetricError> {
    validate_camera_params(params)?;
    let invalid = |reason: &str| MetricError::InvalidBounds {
        min: bounds_min,
        max: bounds_max,
        reason: reason.to_string(),
    };
    if !bounds_min.is_finite() || !bounds_max.is_finite() {
        return Err(invalid("not finite"));
    }
    if bounds_min.cmpgt(bounds_max).any() {
        return Err(invalid("min exceeds max"));
    }
    let (lo, hi) = (bounds_min.as_dvec3(), bounds_max.as_dvec3());
    let tree_height = hi.y - lo.y;
    let radius = (hi - lo).length() * 0.5;
    if tree_height.is_nan() || tree_height <= 1e-6 * radius.max(1e-30) {
        return Err(invalid("no height: a tree's size on screen is its height"));
    }
    let tan_half = (f64::from(params.fov_y_deg) * 0.5).to_radians().tan();
    let screen_height = f64::from(params.screen_height);
    // The screen's focal length, then the distance putting the tree's height at H pixels; a
    // screen made larger where that would be too near.
    let focal = f64::from(params.resolution) / (2.0 * tan_half);
    let distance =
        (tree_height * focal / screen_height).max(f64::from(MIN_DISTANCE_RADII) * radius);
    let focal = distance * screen_height / tree_height;
    let target = ((lo + hi) * 0.5).as_vec3();
    let cameras: Vec<Camera> = (params.elevations_deg.iter())
        .flat_map(|&elevation_deg| {
            (0..params.views).map(move |view| Camera {
                target,
                azimuth_deg: ring_azimuth_deg(view, params.views),
                elevation_deg,
                distance: distance as f32,
                // Set below, once the image's height is known.
                projection: Projection::Perspective { fov_y_deg: 1.0 },
            })
        })
        .collect();
    let margin = f64::from(SWAY_MARGIN) * tree_height;
    let (grown_lo, grown_hi) = (lo - DVec3::splat(margin), hi + DVec3::splat(margin));
    let (mut half_w, mut half_h) = (0.0f64, 0.0f64);
    for camera in &cameras {
        let view = camera.view().as_dmat4();
        for k in 0..8 {
            let corner = DVec3::new(
                if k & 1 == 0 { grown_lo.x } else { grown_hi.x },
                if k & 2 == 0 { grown_lo.y } else { grown_hi.y },
                if k & 4 == 0 { grown_lo.z } else { grown_hi.z },
            );
            let v = view.transform_point3(corner);
            // In front of the eye: the distance is at least 3 radii, the margin under 0.5.
            let depth = (-v.z).max(1e-3 * distance);
            half_w = half_w.max(v.x.abs() * focal / depth);
            half_h = half_h.max(v.y.abs() * focal / depth);
        }
    }
    // Whole pixels either side of the centre, and one more.
    let side = |half: f64| 2 * (half.ceil() as u32 + 1);
    let (width, height) = (side(half_w), side(half_h));
    let fov_y_deg = (2.0 * (f64::from(height) * 0.5 / focal).atan()).to_degrees() as f32;
    let cameras = cameras
        .into_iter()
        .map(|c| Camera {
            projection: Projection::Perspective { fov_y_deg },
            ..c
        })
        .collect();
    let supersample = params
        .samples_per_side
        .unwrap_or_else(|| samples_per_side(params.screen_height));
    Ok(Framing {
        cameras,
        width,
        height,
        supersample,
        distance: distance as f32,
        focal: focal as f32,
    })
}

/// Checks the views, screen and field of view of `params`.
pub(crate) fn validate_camera_params(params: &CoverageParams) -> Result<(), MetricError> {
    if params.views == 0 || params.elevations_deg.is_empty() {
        return Err(MetricError::NoViews);
    }
    let fov = params.fov_y_deg;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(MetricError::InvalidParams(format!(
            "the field of view {fov}° must be in (0, 180)"
        )));
    }
    if let Some(&e) = (params.elevations_deg.iter()).find(|e| !(-90.0..=90.0).contains(*e)) {
        return Err(MetricError::InvalidParams(format!(
            "the elevation {e}° must be in [-90, 90]"
        )));
    }
    let (h, r) = (params.screen_height, params.resolution);
    if !(1.0..=100_000.0).contains(&h) {
        return Err(MetricError::InvalidParams(format!(
            "the screen height {h} px must be 1 to 100000 pixels"
        )));
    }
    if !(1.0..=100_000.0).contains(&r) {
        return Err(MetricError::InvalidParams(format!(
            "the screen resolution {r} px must be 1 to 100000 pixels"
        )));
    }
    if let Some(k) = params.samples_per_side
        && !(1..=MAX_SUPERSAMPLE).contains(&k)
    {
        return Err(MetricError::InvalidParams(format!(
            "{k} samples per pixel side: 1 to {MAX_SUPERSAMPLE}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(screen_height: f32) -> CoverageParams {
        CoverageParams {
            screen_height,
            ..CoverageParams::default()
        }
    }

    /// Projects `p` with `camera` into the image of `framing`: pixels from the top left.
    fn pixel(framing: &Framing, camera: &Camera, p: Vec3) -> (f32, f32) {
        let m = camera.view_proj(framing.aspect());
        let c = m * p.extend(1.0);
        let (x, y) = (c.x / c.w, c.y / c.w);
        (
            (x + 1.0) * 0.5 * framing.width as f32,
            (1.0 - y) * 0.5 * framing.height as f32,
        )
    }

    #[test]
    fn the_rest_height_spans_the_screen_height_at_the_target() {
        // A tall box; from the ground ring, a vertical segment through the centre, of the
        // tree's height, spans H pixels.
        let (lo, hi) = (Vec3::new(-2.0, 0.0, -1.5), Vec3::new(2.0, 10.0, 1.5));
        for h in [8.0f32, 20.0, 60.0, 200.0, 600.0] {
            let f = framing(lo, hi, &params(h)).expect("framing");
            let centre = (lo + hi) * 0.5;
            for camera in f.cameras.iter().filter(|c| c.elevation_deg == 0.0) {
                let top = pixel(&f, camera, Vec3::new(centre.x, hi.y, centre.z));
                let bottom = pixel(&f, camera, Vec3::new(centre.x, lo.y, centre.z));
                let spanned = bottom.1 - top.1;
                assert!((spanned - h).abs() < 1e-3 * h, "{h}: {spanned}");
                // The centre is the image's centre.
                let mid = pixel(&f, camera, centre);
                assert!((mid.0 - f.width as f32 / 2.0).abs() < 1e-2, "{mid:?}");
            }
            // The switch values' distance, d = h / (2 (H/R) tan(φ/2)), from 3 radii on.
            let d = 10.0 / (2.0 * (h / 1080.0) * 30f32.to_radians().tan());
            let d = d.max(3.0 * (hi - lo).length() * 0.5);
            assert!(
                (f.distance - d).abs() < 1e-4 * d,
                "{h}: {} vs {d}",
                f.distance
            );
            assert_eq!(f.cameras.len(), 10);
            assert_eq!(f.supersample, samples_per_side(h));
        }
    }

    #[test]
    fn every_view_holds_the_grown_bounds() {
        let (lo, hi) = (Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 5.0, 3.0));
        for h in [20.0f32, 600.0, 2000.0] {
            let f = framing(lo, hi, &params(h)).expect("framing");
            let m = SWAY_MARGIN * 5.0;
            for camera in &f.cameras {
                for k in 0..8 {
                    let p = Vec3::new(
                        if k & 1 == 0 { lo.x - m } else { hi.x + m },
                        if k & 2 == 0 { lo.y - m } else { hi.y + m },
                        if k & 4 == 0 { lo.z - m } else { hi.z + m },
                    );
                    let (x, y) = pixel(&f, camera, p);
                    assert!(x >= 0.0 && x <= f.width as f32, "{h}: x {x} of {}", f.width);
                    assert!(
                        y >= 0.0 && y <= f.height as f32,
                        "{h}: y {y} of {}",
                        f.height
                    );
                }
            }
        }
        // A tree taller than a third of the screen is seen from 3 radii.
        let f = framing(lo, hi, &params(2000.0)).expect("framing");
        let radius = (hi - lo).length() * 0.5;
        assert!((f.distance - 3.0 * radius).abs() < 1e-4 * radius);
    }

    #[test]
    fn samples_per_side_keep_512_over_the_tree() {
        assert_eq!(samples_per_side(8.0), 64);
        assert_eq!(samples_per_side(20.0), 26);
        assert_eq!(samples_per_side(60.0), 9);
        assert_eq!(samples_per_side(200.0), 3);
        assert_eq!(samples_per_side(600.0), 2);
        assert_eq!(samples_per_side(2000.0), 2);
        assert_eq!(samples_per_side(1.0), MAX_SAMPLES_PER_SIDE);
        for h in [4.0f32, 8.0, 13.0, 60.0, 333.0, 511.0] {
            assert!(samples_per_side(h) as f32 * h >= 512.0, "{h}");
        }
    }

    #[test]
    fn ring_is_even() {
        assert_eq!(ring_azimuth_deg(0, 5), 0.0);
        assert_eq!(ring_azimuth_deg(1, 5), 72.0);
        assert_eq!(ring_azimuth_deg(4, 5), 288.0);
        assert_eq!(ring_azimuth_deg(0, 0), 0.0);
    }

    #[test]
    fn bad_bounds_and_parameters_are_named() {
        let ok = params(60.0);
        let flat = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        assert!(matches!(
            framing(flat.0, flat.1, &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
        assert!(matches!(
            framing(Vec3::ONE, Vec3::ZERO, &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
        assert!(matches!(
            framing(Vec3::ZERO, Vec3::splat(f32::NAN), &ok),
            Err(MetricError::InvalidBounds { .. })
        ));
        let bad = [
            CoverageParams {
                fov_y_deg: 180.0,
                ..ok.clone()
            },
            CoverageParams {
                elevations_deg: vec![0.0, 91.0],
                ..ok.clone()
            },
            CoverageParams {
                screen_height: 0.5,
                ..ok.clone()
            },
            CoverageParams {
                resolution: f32::NAN,
                ..ok.clone()
            },
            CoverageParams {
                samples_per_side: Some(0),
                ..ok.clone()
            },
        ];
        for p in bad {
            assert!(
                matches!(
                    validate_camera_params(&p),
                    Err(MetricError::InvalidParams(_))
                ),
                "{p:?}"
            );
        }
        let none = CoverageParams {
            elevations_deg: vec![],
            ..ok
        };
        assert!(matches!(
            validate_camera_params(&none),
            Err(MetricError::NoViews)
        ));
    }
}
