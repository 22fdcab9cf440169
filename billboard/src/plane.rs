//! A plane `n·x = offset` with unit normal `n` (spec animated-billboard-clouds §2.1).

use glam::Vec3;

/// An oriented plane: the points x with `normal · x = offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal: the side the plane faces.
    pub normal: Vec3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: f32,
}

impl Plane {
    /// The plane through three points, or None when they are (nearly) collinear.
    pub fn through(a: Vec3, b: Vec3, c: Vec3) -> Option<Plane> {
        let n = (b - a).cross(c - a);
        let len = n.length();
        if !len.is_finite() || len <= 1e-20 {
            return None;
        }
        let normal = n / len;
        Some(Plane {
            normal,
            offset: normal.dot((a + b + c) / 3.0),
        })
    }
    /// Signed distance of `p` from the plane.
    pub fn distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }
    /// Orthogonal projection of `p` onto the plane.
    pub fn project(&self, p: Vec3) -> Vec3 {
        p - self.normal * self.distance(p)
    }
    /// A right-handed orthonormal frame (u, v) spanning the plane, u × v = normal.
    pub fn frame(&self) -> (Vec3, Vec3) {
        let n = self.normal;
        let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let u = a.cross(n).normalize();
        let v = n.cross(u);
        (u, v)
    }
}
