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

/// The intersection line of two planes, directed along `n_a × n_b`; `None`
/// when the planes are within `sin_min` of parallel (`|n_a × n_b| < sin_min`).
pub fn line_of_planes(a: &Plane, b: &Plane, sin_min: Real) -> Option<Line3> {
    if a.normal.cross(&b.normal).norm() < sin_min {
        return None;
    }
    a.intersect_plane(b)
}

/// The point where three planes meet; `None` when the lines of `b` with `a`
/// and with `c` are within `sin_min` of parallel (the corner is ill-defined),
/// or the result is not finite.
pub fn corner_of_planes(a: &Plane, b: &Plane, c: &Plane, sin_min: Real) -> Option<Point3> {
    let na = a.normal.into_inner();
    let nb = b.normal.into_inner();
    let nc = c.normal.into_inner();
    let l1 = unit(nb.cross(&na))?;
    let l2 = unit(nb.cross(&nc))?;
    if l1.cross(&l2).norm() < sin_min {
        return None;
    }
    let det = na.dot(&nb.cross(&nc));
    if det.abs() < 1e-300 {
        return None;
    }
    let p = (nb.cross(&nc) * a.offset + nc.cross(&na) * b.offset + na.cross(&nb) * c.offset) / det;
    let p = Point3::from(p);
    crate::math::is_finite_point(&p).then_some(p)
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
    fn corner_of_three_planes_by_hand() {
        // x = 1, y = 2, x + y + z = 6 (normalised) meet at (1, 2, 3).
        let a = Plane::from_point_normal(&Point3::new(1.0, 0.0, 0.0), Vector3::x_axis());
        let b = Plane::from_point_normal(&Point3::new(0.0, 2.0, 0.0), Vector3::y_axis());
        let c = Plane::from_point_normal(
            &Point3::new(6.0, 0.0, 0.0),
            unit(Vector3::new(1.0, 1.0, 1.0)).unwrap(),
        );
        let p = corner_of_planes(&a, &b, &c, 0.1).unwrap();
        assert!((p - Point3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
        // Two planes 2° apart: their line with the third is ill-defined at 0.1.
        let tilt = unit(Vector3::new(1.0, 0.0, 2f64.to_radians().tan())).unwrap();
        let a2 = Plane::from_point_normal(&Point3::new(1.0, 0.0, 0.0), tilt);
        assert!(corner_of_planes(&a, &b, &a2, 0.1).is_none());
        assert!(corner_of_planes(&a, &b, &a2, 0.01).is_some());
        // The line of two planes lies on both; near-parallel planes have none.
        let l = line_of_planes(&a, &b, 0.1).unwrap();
        assert!((l.dir.into_inner() - Vector3::z()).norm() < 1e-12);
        assert!(line_of_planes(&a, &a2, 0.1).is_none());
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
