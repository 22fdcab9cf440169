//! Orbit camera: a target point seen from an azimuth/elevation at a distance.

use glam::camera::rh::{proj::directx, view};
use glam::{Mat4, Vec3};

use crate::error::RenderError;

/// How the camera projects the view onto the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Perspective with the given vertical field of view in degrees (0..180).
    Perspective {
        /// Vertical field of view in degrees.
        fov_y_deg: f32,
    },
    /// Orthographic, showing `2 * half_height` world units vertically.
    Orthographic {
        /// Half of the visible world height.
        half_height: f32,
    },
}

/// An orbit camera in a Y-up world (glTF).
///
/// Azimuth 0 puts the camera on +Z looking toward -Z; azimuth grows counter-clockwise
/// seen from above (90 puts it on +X). Positive elevation is above the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The point the camera looks at (image centre).
    pub target: Vec3,
    /// Horizontal angle in degrees, see the type docs.
    pub azimuth_deg: f32,
    /// Vertical angle in degrees, -90..90.
    pub elevation_deg: f32,
    /// Distance from the target to the eye (must be > 0).
    pub distance: f32,
    /// Perspective or orthographic projection.
    pub projection: Projection,
}

impl Camera {
    /// A camera looking at the centre of the box whose bounding sphere fills the view.
    ///
    /// Perspective: the distance makes the sphere fit the vertical field of view (and
    /// the horizontal one for images at least as wide as tall). Orthographic: the given
    /// `half_height` is replaced by the sphere radius and the distance is twice the
    /// radius (any distance gives the same orthographic image).
    pub fn framing(
        bounds_min: Vec3,
        bounds_max: Vec3,
        azimuth_deg: f32,
        elevation_deg: f32,
        projection: Projection,
    ) -> Camera {
        let target = (bounds_min + bounds_max) * 0.5;
        // A degenerate box still needs a positive extent to frame.
        let radius = ((bounds_max - bounds_min).length() * 0.5).max(1e-3);
        let (distance, projection) = match projection {
            Projection::Perspective { fov_y_deg } => {
                let half = (fov_y_deg.clamp(1.0, 179.0) * 0.5).to_radians();
                (radius / half.sin(), projection)
            }
            Projection::Orthographic { .. } => (
                radius * 2.0,
                Projection::Orthographic {
                    half_height: radius,
                },
            ),
        };
        Camera {
            target,
            azimuth_deg,
            elevation_deg,
            distance,
            projection,
        }
    }

    /// Unit vector from the target toward the eye.
    pub fn direction(&self) -> Vec3 {
        let (sa, ca) = self.azimuth_deg.to_radians().sin_cos();
        let (se, ce) = self.elevation_deg.to_radians().sin_cos();
        Vec3::new(ce * sa, se, ce * ca)
    }

    /// World position of the eye.
    pub fn eye(&self) -> Vec3 {
        self.target + self.direction() * self.distance
    }

    /// Screen "up" in world space; well defined even when looking straight down.
    pub fn up(&self) -> Vec3 {
        let (sa, ca) = self.azimuth_deg.to_radians().sin_cos();
        let (se, ce) = self.elevation_deg.to_radians().sin_cos();
        Vec3::new(-se * sa, ce, -se * ca)
    }

    /// World-to-view matrix (right-handed, looking down -Z).
    pub fn view(&self) -> Mat4 {
        view::look_to_mat4(self.eye(), -self.direction(), self.up())
    }

    /// View-projection matrix with depth planes from the camera distance alone:
    /// geometry within `1000 * distance` of the eye is kept. Prefer
    /// [`Camera::view_proj_for_bounds`] when the scene extent is known.
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let (near, far) = match self.projection {
            Projection::Perspective { .. } => (self.distance * 1e-3, self.distance * 1e3),
            Projection::Orthographic { .. } => (-self.distance * 1e3, self.distance * 1e3),
        };
        self.view_proj_with_depth(aspect, near, far)
    }

    /// View-projection matrix whose near and far planes enclose the given box, so
    /// nothing inside it is clipped in depth and depth precision stays high.
    pub fn view_proj_for_bounds(&self, aspect: f32, bounds_min: Vec3, bounds_max: Vec3) -> Mat4 {
        let (near, far) = self.depth_range(bounds_min, bounds_max);
        self.view_proj_with_depth(aspect, near, far)
    }

    /// Near and far plane distances that enclose the bounding sphere of the box.
    pub fn depth_range(&self, bounds_min: Vec3, bounds_max: Vec3) -> (f32, f32) {
        let centre = (bounds_min + bounds_max) * 0.5;
        let radius = (bounds_max - bounds_min).length() * 0.5;
        // Depth of the sphere centre along the viewing direction.
        let depth = (centre - self.eye()).dot(-self.direction());
        let margin = 0.01 * radius + 1e-4 * self.distance.max(1e-3);
        let far = depth + radius + margin;
        let near = depth - radius - margin;
        match self.projection {
            Projection::Perspective { .. } => {
                let far = far.max(self.distance * 1e-3);
                (near.max(far * 1e-5), far)
            }
            Projection::Orthographic { .. } => (near, far),
        }
    }

    /// View-projection matrix with explicit near/far plane distances (wgpu depth 0..1).
    pub fn view_proj_with_depth(&self, aspect: f32, near: f32, far: f32) -> Mat4 {
        let proj = match self.projection {
            Projection::Perspective { fov_y_deg } => {
                directx::perspective(fov_y_deg.to_radians(), aspect, near, far)
            }
            Projection::Orthographic { half_height } => {
                let half_width = half_height * aspect;
                directx::orthographic(
                    -half_width,
                    half_width,
                    -half_height,
                    half_height,
                    near,
                    far,
                )
            }
        };
        proj * self.view()
    }

    /// Rejects cameras that cannot produce a finite projection.
    pub fn validate(&self) -> Result<(), RenderError> {
        let invalid = |reason: String| Err(RenderError::InvalidCamera(reason));
        if !self.target.is_finite()
            || !self.azimuth_deg.is_finite()
            || !self.elevation_deg.is_finite()
        {
            return invalid(format!("non-finite target or angles in {self:?}"));
        }
        if !(self.distance.is_finite() && self.distance > 0.0) {
            return invalid(format!("distance {} must be finite and > 0", self.distance));
        }
        match self.projection {
            Projection::Perspective { fov_y_deg } if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) => {
                invalid(format!("fov_y_deg {fov_y_deg} must be in (0, 180)"))
            }
            Projection::Orthographic { half_height }
                if !(half_height.is_finite() && half_height > 0.0) =>
            {
                invalid(format!("half_height {half_height} must be finite and > 0"))
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn project(m: Mat4, p: Vec3) -> Vec3 {
        m.project_point3(p)
    }

    #[test]
    fn azimuth_convention() {
        let mut cam = Camera {
            target: Vec3::ZERO,
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            distance: 10.0,
            projection: Projection::Perspective { fov_y_deg: 60.0 },
        };
        assert!(cam.eye().abs_diff_eq(Vec3::new(0.0, 0.0, 10.0), 1e-4));
        cam.azimuth_deg = 90.0;
        assert!(cam.eye().abs_diff_eq(Vec3::new(10.0, 0.0, 0.0), 1e-4));
        cam.elevation_deg = 90.0;
        assert!(cam.eye().abs_diff_eq(Vec3::new(0.0, 10.0, 0.0), 1e-4));
        // Looking straight down still yields a usable matrix.
        assert!(cam.view_proj(1.0).is_finite());
    }

    #[test]
    fn image_axes() {
        // From +Z, +X is to the right and +Y is up in NDC.
        let cam = Camera {
            target: Vec3::ZERO,
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            distance: 10.0,
            projection: Projection::Orthographic { half_height: 2.0 },
        };
        let m = cam.view_proj(1.0);
        let right = project(m, Vec3::X);
        let up = project(m, Vec3::Y);
        assert!((right.x - 0.5).abs() < 1e-5 && right.y.abs() < 1e-5);
        assert!((up.y - 0.5).abs() < 1e-5 && up.x.abs() < 1e-5);
    }

    #[test]
    fn bounds_depth_range_contains_box() {
        for projection in [
            Projection::Perspective { fov_y_deg: 40.0 },
            Projection::Orthographic { half_height: 1.0 },
        ] {
            let (min, max) = (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(3.0, 5.0, 1.0));
            let cam = Camera::framing(min, max, 33.0, 20.0, projection);
            let m = cam.view_proj_for_bounds(1.0, min, max);
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let p = project(m, corner);
                assert!(
                    p.z > 0.0 && p.z < 1.0,
                    "{projection:?} corner {corner} depth {}",
                    p.z
                );
                assert!(
                    p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                    "{projection:?} corner {corner} at {p}"
                );
            }
        }
    }

    #[test]
    fn invalid_cameras_are_rejected() {
        let good = Camera::framing(
            Vec3::ZERO,
            Vec3::ONE,
            0.0,
            0.0,
            Projection::Perspective { fov_y_deg: 45.0 },
        );
        assert!(good.validate().is_ok());
        assert!(
            Camera {
                distance: 0.0,
                ..good
            }
            .validate()
            .is_err()
        );
        assert!(
            Camera {
                projection: Projection::Perspective { fov_y_deg: 180.0 },
                ..good
            }
            .validate()
            .is_err()
        );
        assert!(
            Camera {
                projection: Projection::Orthographic {
                    half_height: f32::NAN
                },
                ..good
            }
            .validate()
            .is_err()
        );
    }
}
