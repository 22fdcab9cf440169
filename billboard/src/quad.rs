//! A billboard quad: a rectangle lying in its plane.

use glam::{Vec2, Vec3};

use crate::plane::Plane;

/// A rectangle in 3-D: centre, two unit in-plane axes and half extents along them.
/// `axis_u × axis_v = plane.normal`, so the corners run counter-clockwise seen from the front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// The plane it lies in.
    pub plane: Plane,
    /// Centre of the rectangle, world units.
    pub center: Vec3,
    /// Unit direction of its first side (the texture's right).
    pub axis_u: Vec3,
    /// Unit direction of its second side (the texture's up).
    pub axis_v: Vec3,
    /// Half extents along `axis_u` and `axis_v`, world units.
    pub half_size: Vec2,
}

impl Quad {
    /// The rectangle facing +Z at `center` (its sides along X and Y), `half_size` its half
    /// extents: the quad of a test scene or of a front-facing impostor.
    pub fn facing_z(center: Vec3, half_size: Vec2) -> Quad {
        Quad {
            plane: Plane {
                normal: Vec3::Z,
                offset: center.z,
            },
            center,
            axis_u: Vec3::X,
            axis_v: Vec3::Y,
            half_size,
        }
    }

    /// Corners in order (-u,-v), (+u,-v), (+u,+v), (-u,+v).
    pub fn corners(&self) -> [Vec3; 4] {
        let (u, v) = (
            self.axis_u * self.half_size.x,
            self.axis_v * self.half_size.y,
        );
        [
            self.center - u - v,
            self.center + u - v,
            self.center + u + v,
            self.center - u + v,
        ]
    }
    /// The quad moved by a rigid transform (its size and texture stay).
    pub fn transformed(&self, t: glam::Affine3A) -> Quad {
        let center = t.transform_point3(self.center);
        let normal = t.transform_vector3(self.plane.normal).normalize_or_zero();
        Quad {
            plane: Plane {
                normal,
                offset: normal.dot(center),
            },
            center,
            axis_u: t.transform_vector3(self.axis_u).normalize_or_zero(),
            axis_v: t.transform_vector3(self.axis_v).normalize_or_zero(),
            half_size: self.half_size,
        }
    }
    /// Width and height in world units.
    pub fn size(&self) -> Vec2 {
        self.half_size * 2.0
    }
    /// Area in world units².
    pub fn area(&self) -> f32 {
        4.0 * self.half_size.x * self.half_size.y
    }
    /// Distance from `p` to the nearest point of the rectangle (world units).
    pub fn distance_to(&self, p: Vec3) -> f32 {
        let d = p - self.center;
        let (u, v) = (d.dot(self.axis_u), d.dot(self.axis_v));
        let nearest = self.center
            + self.axis_u * u.clamp(-self.half_size.x, self.half_size.x)
            + self.axis_v * v.clamp(-self.half_size.y, self.half_size.y);
        p.distance(nearest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_to_the_rectangle_is_to_its_nearest_point() {
        let q = Quad::facing_z(Vec3::ZERO, Vec2::new(1.0, 0.5));
        // In front of the rectangle: the distance to the plane.
        assert!((q.distance_to(Vec3::new(0.5, 0.2, 2.0)) - 2.0).abs() < 1e-6);
        // Beside it in its plane: to the edge.
        assert!((q.distance_to(Vec3::new(3.0, 0.0, 0.0)) - 2.0).abs() < 1e-6);
        // Off a corner, out of the plane.
        let d = q.distance_to(Vec3::new(2.0, 1.5, 1.0));
        assert!((d - 3f32.sqrt()).abs() < 1e-6, "{d}");
    }
}
