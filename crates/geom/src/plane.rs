//! Planes `n · x = d` with a unit normal.

use crate::line::Line3;
use crate::math::{Point3, Real, UnitVector3, Vector3, unit};
use serde::{Deserialize, Serialize};

/// The plane of points `x` with `normal · x = offset`. The normal is oriented:
/// [`Plane::signed_distance`] is positive on the side it points to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    /// Unit normal.
    pub normal: UnitVector3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: Real,
}

impl Plane {
    /// The plane through `point` with unit normal `normal`.
    pub fn from_point_normal(point: &Point3, normal: UnitVector3) -> Self {
        Self {
            normal,
            offset: normal.dot(&point.coords),
        }
    }

    /// The plane through three points, normal by the right-hand rule a→b→c;
    /// `None` when they are collinear.
    pub fn from_points(a: &Point3, b: &Point3, c: &Point3) -> Option<Self> {
        let n = unit((b - a).cross(&(c - a)))?;
        Some(Self::from_point_normal(a, n))
    }

    /// Signed distance of `p` (positive on the normal's side).
    #[inline]
    pub fn signed_distance(&self, p: &Point3) -> Real {
        self.normal.dot(&p.coords) - self.offset
    }

    /// Orthogonal projection of `p` onto the plane.
    #[inline]
    pub fn project(&self, p: &Point3) -> Point3 {
        p - self.normal.into_inner() * self.signed_distance(p)
    }

    /// Some point of the plane (the one closest to the origin).
    pub fn point(&self) -> Point3 {
        Point3::from(self.normal.into_inner() * self.offset)
    }

    /// The same plane with the opposite orientation.
    pub fn flipped(&self) -> Self {
        Self {
            normal: -self.normal,
            offset: -self.offset,
        }
    }

    /// Parameter `t` where the line `p + t·dir` meets the plane, or `None` when the
    /// line is parallel to it (|n·dir| below `1e-12`).
    pub fn intersect_line_param(&self, p: &Point3, dir: &Vector3) -> Option<Real> {
        let denom = self.normal.dot(dir);
        if denom.abs() < 1e-12 {
            return None;
        }
        Some(-self.signed_distance(p) / denom)
    }

    /// The line where two planes meet, or `None` when they are parallel
    /// (normals within `1e-9` rad of each other).
    pub fn intersect_plane(&self, other: &Self) -> Option<Line3> {
        let dir = self.normal.cross(&other.normal);
        let dir_norm2 = dir.norm_squared();
        if dir_norm2 < 1e-18 {
            return None;
        }
        // Point on both planes closest to the origin:
        // p = ((d1 n2 - d2 n1) × (n1 × n2)) / |n1 × n2|², written with d's.
        let n1 = self.normal.into_inner();
        let n2 = other.normal.into_inner();
        let p = (n2.cross(&dir) * self.offset + dir.cross(&n1) * other.offset) / dir_norm2;
        let dir = unit(dir)?;
        Some(Line3::new(Point3::from(p), dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_projection() {
        let p = Plane::from_point_normal(&Point3::new(0.0, 0.0, 2.0), Vector3::z_axis());
        assert_eq!(p.signed_distance(&Point3::new(5.0, 1.0, 3.0)), 1.0);
        assert_eq!(
            p.project(&Point3::new(5.0, 1.0, 3.0)),
            Point3::new(5.0, 1.0, 2.0)
        );
        assert_eq!(p.flipped().signed_distance(&Point3::origin()), 2.0);
        let t = p
            .intersect_line_param(&Point3::origin(), &Vector3::new(0.0, 0.0, 4.0))
            .unwrap();
        assert!((t - 0.5).abs() < 1e-15);
    }

    #[test]
    fn two_plane_line_lies_on_both() {
        let a = Plane::from_point_normal(
            &Point3::new(1.0, 2.0, 3.0),
            unit(Vector3::new(1.0, 1.0, 0.0)).unwrap(),
        );
        let b = Plane::from_point_normal(
            &Point3::new(-1.0, 0.5, 2.0),
            unit(Vector3::new(0.0, 1.0, 1.0)).unwrap(),
        );
        let l = a.intersect_plane(&b).unwrap();
        for t in [-3.0, 0.0, 2.5] {
            let q = l.point_at(t);
            assert!(a.signed_distance(&q).abs() < 1e-12);
            assert!(b.signed_distance(&q).abs() < 1e-12);
        }
        assert!(a.intersect_plane(&a.flipped()).is_none());
    }

    #[test]
    fn from_points_orientation() {
        let p = Plane::from_points(
            &Point3::origin(),
            &Point3::new(1.0, 0.0, 0.0),
            &Point3::new(0.0, 1.0, 0.0),
        )
        .unwrap();
        assert!((p.normal.z - 1.0).abs() < 1e-15);
        assert!(
            Plane::from_points(
                &Point3::origin(),
                &Point3::new(1.0, 0.0, 0.0),
                &Point3::new(2.0, 0.0, 0.0)
            )
            .is_none()
        );
    }
}
