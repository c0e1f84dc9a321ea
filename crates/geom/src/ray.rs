//! Rays: an origin and a unit direction.

use crate::math::{Point3, Real, UnitVector3, Vector3};

/// A half-line `origin + t * dir`, `t ≥ 0`, with `dir` of unit length so `t` is a
/// distance in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (the sensor).
    pub origin: Point3,
    /// Unit direction.
    pub dir: UnitVector3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub fn new(origin: Point3, dir: UnitVector3) -> Self {
        Self { origin, dir }
    }

    /// The point at distance `t` along the ray.
    #[inline]
    pub fn point_at(&self, t: Real) -> Point3 {
        self.origin + self.dir.into_inner() * t
    }

    /// Component-wise reciprocal of the direction (infinite where a component is 0).
    #[inline]
    pub fn inv_dir(&self) -> Vector3 {
        self.dir.map(|v| 1.0 / v)
    }

    /// Distance along the ray of the foot of the perpendicular from `p`
    /// (may be negative).
    #[inline]
    pub fn project_param(&self, p: &Point3) -> Real {
        (p - self.origin).dot(&self.dir)
    }

    /// Squared distance from `p` to the ray's supporting line.
    #[inline]
    pub fn line_distance_squared(&self, p: &Point3) -> Real {
        let v = p - self.origin;
        let t = v.dot(&self.dir);
        (v.norm_squared() - t * t).max(0.0)
    }
}
