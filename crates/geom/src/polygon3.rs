//! Planar polygons in 3-D: a plane with its own 2-D coordinates.
//!
//! A [`PlaneFrame`] has axes `(u, v, n)` forming a right-handed frame, so a
//! polygon that runs anticlockwise in `(u, v)` runs anticlockwise about `n` in 3-D
//! — the convention of Pudney's perimeters (P§2.2).

use crate::math::{Point2, Point3, Real, UnitVector3, Vector3, any_perpendicular, unit};
use crate::plane::Plane;

/// Orthonormal 2-D coordinates on a plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneFrame {
    /// Origin of the 2-D coordinates (a point on the plane).
    pub origin: Point3,
    /// First in-plane axis.
    pub u: UnitVector3,
    /// Second in-plane axis, `n × u`.
    pub v: UnitVector3,
    /// Plane normal.
    pub normal: UnitVector3,
}

impl PlaneFrame {
    /// A frame on the plane through `origin` with normal `normal`.
    pub fn new(origin: Point3, normal: UnitVector3) -> Self {
        let u = any_perpendicular(&normal);
        let v = UnitVector3::new_unchecked(normal.cross(&u));
        Self {
            origin,
            u,
            v,
            normal,
        }
    }

    /// A frame whose first axis is `u` projected onto the plane (falls back to any
    /// in-plane axis when `u` is along the normal).
    pub fn with_u_axis(origin: Point3, normal: UnitVector3, u: &Vector3) -> Self {
        let u_in = u - normal.into_inner() * normal.dot(u);
        let u = unit(u_in).unwrap_or_else(|| any_perpendicular(&normal));
        let v = UnitVector3::new_unchecked(normal.cross(&u));
        Self {
            origin,
            u,
            v,
            normal,
        }
    }

    /// The frame's plane.
    pub fn plane(&self) -> Plane {
        Plane::from_point_normal(&self.origin, self.normal)
    }

    /// 2-D coordinates of the orthogonal projection of `p`.
    #[inline]
    pub fn to_2d(&self, p: &Point3) -> Point2 {
        let d = p - self.origin;
        Point2::new(d.dot(&self.u), d.dot(&self.v))
    }

    /// The 3-D point with 2-D coordinates `q` (on the plane).
    #[inline]
    pub fn to_3d(&self, q: &Point2) -> Point3 {
        self.origin + self.u.into_inner() * q.x + self.v.into_inner() * q.y
    }

    /// Signed distance of `p` from the plane.
    #[inline]
    pub fn height(&self, p: &Point3) -> Real {
        (p - self.origin).dot(&self.normal)
    }
}

/// Newell's normal of a closed 3-D polygon: its direction is the normal about which
/// the vertices run anticlockwise, its length twice the projected area. Zero for
/// degenerate input.
pub fn newell_normal(poly: &[Point3]) -> Vector3 {
    let n = poly.len();
    let mut acc = Vector3::zeros();
    for i in 0..n {
        let a = &poly[i];
        let b = &poly[(i + 1) % n];
        acc.x += (a.y - b.y) * (a.z + b.z);
        acc.y += (a.z - b.z) * (a.x + b.x);
        acc.z += (a.x - b.x) * (a.y + b.y);
    }
    acc
}

/// Area of a planar 3-D polygon (from [`newell_normal`]).
pub fn polygon_area(poly: &[Point3]) -> Real {
    0.5 * newell_normal(poly).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polygon2;

    #[test]
    fn frame_round_trip_and_handedness() {
        let n = unit(Vector3::new(0.3, -0.4, 0.8)).unwrap();
        let f = PlaneFrame::new(Point3::new(1.0, 2.0, 3.0), n);
        assert!((f.u.cross(&f.v) - n.into_inner()).norm() < 1e-12);
        let q = Point2::new(0.7, -1.2);
        let p = f.to_3d(&q);
        assert!((f.to_2d(&p) - q).norm() < 1e-12);
        assert!(f.height(&p).abs() < 1e-12);
        // A square anticlockwise about n in 3-D is anticlockwise in 2-D.
        let sq2 = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(0.0, 1.0),
        ];
        let sq3: Vec<Point3> = sq2.iter().map(|q| f.to_3d(q)).collect();
        let nn = newell_normal(&sq3);
        assert!(nn.dot(&n) > 0.0);
        assert!((polygon_area(&sq3) - 1.0).abs() < 1e-12);
        assert!(polygon2::is_anticlockwise(&sq2));
    }
}
