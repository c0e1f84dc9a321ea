//! Axis-aligned bounding boxes.

use crate::math::{Point3, Real, Vector3};
use serde::{Deserialize, Serialize};

/// An axis-aligned box `[min, max]`. An empty box has `min > max` on every axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Lowest corner.
    pub min: Point3,
    /// Highest corner.
    pub max: Point3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::empty()
    }
}

impl Aabb {
    /// The box with these corners (taken component-wise, so order does not matter).
    pub fn new(a: Point3, b: Point3) -> Self {
        Self {
            min: a.inf(&b),
            max: a.sup(&b),
        }
    }

    /// The empty box: growing it by a point gives that point.
    pub fn empty() -> Self {
        Self {
            min: Point3::new(Real::INFINITY, Real::INFINITY, Real::INFINITY),
            max: Point3::new(-Real::INFINITY, -Real::INFINITY, -Real::INFINITY),
        }
    }

    /// The smallest box holding all `points` (empty for no points).
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Point3>) -> Self {
        let mut b = Self::empty();
        for p in points {
            b.grow(p);
        }
        b
    }

    /// `true` when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Grow to include `p`.
    #[inline]
    pub fn grow(&mut self, p: &Point3) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    /// The union of two boxes.
    #[inline]
    pub fn merged(&self, other: &Self) -> Self {
        Self {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    /// The box enlarged by `margin` on every side.
    pub fn loosened(&self, margin: Real) -> Self {
        let m = Vector3::repeat(margin);
        Self {
            min: self.min - m,
            max: self.max + m,
        }
    }

    /// Centre point.
    pub fn center(&self) -> Point3 {
        nalgebra::center(&self.min, &self.max)
    }

    /// Edge lengths.
    pub fn extents(&self) -> Vector3 {
        self.max - self.min
    }

    /// Surface area (0 for an empty box).
    pub fn surface_area(&self) -> Real {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extents();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// `true` when `p` lies inside or on the boundary.
    pub fn contains_point(&self, p: &Point3) -> bool {
        (0..3).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i])
    }

    /// `true` when the two boxes share at least one point.
    pub fn intersects(&self, other: &Self) -> bool {
        (0..3).all(|i| self.min[i] <= other.max[i] && other.min[i] <= self.max[i])
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared_to_point(&self, p: &Point3) -> Real {
        let mut d2 = 0.0;
        for i in 0..3 {
            let v = if p[i] < self.min[i] {
                self.min[i] - p[i]
            } else if p[i] > self.max[i] {
                p[i] - self.max[i]
            } else {
                0.0
            };
            d2 += v * v;
        }
        d2
    }

    /// The parameter interval `[t_enter, t_exit]` over which the ray
    /// `origin + t * dir` is inside the box, clipped to `[0, t_max]`, or `None`
    /// when it misses. `inv_dir` is the component-wise reciprocal of the direction
    /// (infinite components are fine).
    #[inline]
    pub fn ray_interval(
        &self,
        origin: &Point3,
        inv_dir: &Vector3,
        t_max: Real,
    ) -> Option<(Real, Real)> {
        let mut t0: Real = 0.0;
        let mut t1 = t_max;
        for i in 0..3 {
            let a = (self.min[i] - origin[i]) * inv_dir[i];
            let b = (self.max[i] - origin[i]) * inv_dir[i];
            // NaN (0 * inf on a face plane) compares false and leaves the bound alone.
            let (near, far) = if a <= b { (a, b) } else { (b, a) };
            if near > t0 {
                t0 = near;
            }
            if far < t1 {
                t1 = far;
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grow_and_merge() {
        let mut b = Aabb::empty();
        assert!(b.is_empty());
        b.grow(&Point3::new(1.0, 2.0, 3.0));
        b.grow(&Point3::new(-1.0, 0.0, 5.0));
        assert_eq!(b.min, Point3::new(-1.0, 0.0, 3.0));
        assert_eq!(b.max, Point3::new(1.0, 2.0, 5.0));
        assert!((b.surface_area() - 2.0 * (4.0 + 4.0 + 4.0)).abs() < 1e-12);
        let c = Aabb::new(Point3::new(2.0, 2.0, 2.0), Point3::new(3.0, 3.0, 3.0));
        assert!(!b.intersects(&c));
        assert!(b.merged(&c).contains_point(&Point3::new(2.5, 1.0, 3.0)));
    }

    #[test]
    fn ray_interval_hand_cases() {
        let b = Aabb::new(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 1.0, 1.0));
        let o = Point3::new(-1.0, 0.5, 0.5);
        let d = Vector3::new(1.0, 0.0, 0.0);
        let inv = d.map(|v| 1.0 / v);
        let (t0, t1) = b.ray_interval(&o, &inv, 10.0).unwrap();
        assert!((t0 - 1.0).abs() < 1e-12 && (t1 - 2.0).abs() < 1e-12);
        assert!(b.ray_interval(&o, &inv, 0.5).is_none());
        // Parallel ray outside the slab misses.
        let o2 = Point3::new(-1.0, 1.5, 0.5);
        assert!(b.ray_interval(&o2, &inv, 10.0).is_none());
        // Origin inside: interval starts at 0.
        let (t0, _) = b
            .ray_interval(&Point3::new(0.5, 0.5, 0.5), &inv, 10.0)
            .unwrap();
        assert_eq!(t0, 0.0);
    }
}
