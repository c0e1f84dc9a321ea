//! Capsules (swept spheres): the default link collision shape.

use crate::aabb::Aabb;
use crate::line::{Segment3, distance_segment_segment};
use crate::math::{Isometry3, Point3, Real, Vector3};
use crate::triangle::Triangle;
use serde::{Deserialize, Serialize};

/// The set of points within `radius` of the segment `a b`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Capsule {
    /// Axis segment.
    pub segment: Segment3,
    /// Radius (> 0).
    pub radius: Real,
}

impl Capsule {
    /// The capsule around `a b` with `radius`.
    pub fn new(a: Point3, b: Point3, radius: Real) -> Self {
        Self {
            segment: Segment3::new(a, b),
            radius,
        }
    }

    /// The capsule moved by `frame_from_here`.
    pub fn transformed(&self, frame_from_here: &Isometry3) -> Self {
        Self::new(
            frame_from_here * self.segment.a,
            frame_from_here * self.segment.b,
            self.radius,
        )
    }

    /// Signed distance from `p` to the surface (negative inside).
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        self.segment.distance_to_point(p) - self.radius
    }

    /// Signed distance between two capsules (negative when they overlap).
    pub fn distance_to_capsule(&self, other: &Self) -> Real {
        distance_segment_segment(&self.segment, &other.segment) - self.radius - other.radius
    }

    /// Signed distance to a triangle (negative when they overlap).
    pub fn distance_to_triangle(&self, tri: &Triangle) -> Real {
        tri.distance_to_segment(&self.segment) - self.radius
    }

    /// The bounding box.
    pub fn bounding_box(&self) -> Aabb {
        Aabb::new(self.segment.a, self.segment.b).loosened(self.radius)
    }

    /// Volume.
    pub fn volume(&self) -> Real {
        let r = self.radius;
        std::f64::consts::PI * r * r * (self.segment.length() + 4.0 / 3.0 * r)
    }

    /// Direction of the axis (zero for a sphere).
    pub fn axis(&self) -> Vector3 {
        self.segment.b - self.segment.a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_by_hand() {
        let c = Capsule::new(Point3::new(0.0, 0.0, 0.0), Point3::new(0.0, 0.0, 1.0), 0.1);
        assert!((c.distance_to_point(&Point3::new(0.5, 0.0, 0.5)) - 0.4).abs() < 1e-15);
        assert!((c.distance_to_point(&Point3::new(0.0, 0.0, 1.5)) - 0.4).abs() < 1e-15);
        assert!(c.distance_to_point(&Point3::new(0.05, 0.0, 0.5)) < 0.0);
        let d = Capsule::new(Point3::new(1.0, -1.0, 0.5), Point3::new(1.0, 1.0, 0.5), 0.2);
        assert!((c.distance_to_capsule(&d) - 0.7).abs() < 1e-15);
        let wall = Triangle::new(
            Point3::new(0.3, -5.0, -5.0),
            Point3::new(0.3, 5.0, -5.0),
            Point3::new(0.3, 0.0, 5.0),
        );
        assert!((c.distance_to_triangle(&wall) - 0.2).abs() < 1e-12);
        let bb = c.bounding_box();
        assert!((bb.min.z + 0.1).abs() < 1e-15 && (bb.max.x - 0.1).abs() < 1e-15);
    }
}
