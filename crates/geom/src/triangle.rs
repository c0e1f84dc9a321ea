//! Triangles: ray hits, closest points, segment distance and intersection.
//!
//! # The ray–triangle convention
//!
//! One rule for every ray–triangle test of the workspace: this crate's
//! [`Triangle::ray_hit`] (double precision) and the single-precision tests behind
//! `scene`'s BVH (`Scene::first_hit_f32`, `Scene::cast_rays_f32`, `RayCast::cast_ray`
//! on a scene). A ray `o + t·d` (unit `d`) hits the triangle `a b c` where
//! `o + t·d = a + u·(b − a) + v·(c − a)` (Möller–Trumbore) with
//!
//! - **closed distance interval**: `0 ≤ t ≤ t_max` — a surface through the ray's
//!   origin (`t = 0`) and one at exactly `t_max` are hit (as in Embree, whose
//!   interval is `[tnear, tfar]`);
//! - **closed triangle**: `u ≥ 0`, `v ≥ 0`, `u + v ≤ 1` — edges and vertices belong
//!   to the triangle, so a ray through an edge shared by two triangles hits both
//!   (at the same distance), and no ray slips through a closed mesh at an edge;
//! - **either side**: front and back faces alike;
//! - **parallel rays miss**: a ray parallel to the triangle's plane, including one
//!   lying in it, misses (|determinant| below 10⁻³⁰⁰ here, 10⁻²⁰ in `f32`).
//!
//! Where several triangles are hit at the same smallest distance, which one is
//! reported is unspecified; the distance is not. `tests` here and `scene`'s
//! `tests/convention.rs` pin the rule on rays through edges, vertices, at `t = 0`
//! and at `t = t_max`.

use crate::line::{Segment3, closest_segment_segment};
use crate::math::{Point3, Real, UnitVector3, Vector3, unit};
use crate::ray::Ray;

/// A triangle `a b c`; its normal follows the right-hand rule a→b→c.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// First vertex.
    pub a: Point3,
    /// Second vertex.
    pub b: Point3,
    /// Third vertex.
    pub c: Point3,
}

impl Triangle {
    /// The triangle `a b c`.
    pub fn new(a: Point3, b: Point3, c: Point3) -> Self {
        Self { a, b, c }
    }

    /// Unit normal (right-hand rule), `None` for a degenerate triangle.
    pub fn normal(&self) -> Option<UnitVector3> {
        unit((self.b - self.a).cross(&(self.c - self.a)))
    }

    /// Area.
    pub fn area(&self) -> Real {
        0.5 * (self.b - self.a).cross(&(self.c - self.a)).norm()
    }

    /// The point with barycentric weights `(1 - u - v, u, v)`.
    pub fn point_at(&self, u: Real, v: Real) -> Point3 {
        self.a + (self.b - self.a) * u + (self.c - self.a) * v
    }

    /// The three edges as segments.
    pub fn edges(&self) -> [Segment3; 3] {
        [
            Segment3::new(self.a, self.b),
            Segment3::new(self.b, self.c),
            Segment3::new(self.c, self.a),
        ]
    }

    /// Distance along `ray` to the triangle (either side), if it is hit within
    /// `[0, t_max]`, edges and vertices included (Möller–Trumbore): the
    /// workspace's [ray–triangle convention](self#the-raytriangle-convention).
    #[inline]
    pub fn ray_hit(&self, ray: &Ray, t_max: Real) -> Option<Real> {
        let e1 = self.b - self.a;
        let e2 = self.c - self.a;
        let pvec = ray.dir.cross(&e2);
        let det = e1.dot(&pvec);
        if det.abs() < 1e-300 {
            return None;
        }
        let inv = 1.0 / det;
        let tvec = ray.origin - self.a;
        let u = tvec.dot(&pvec) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let qvec = tvec.cross(&e1);
        let v = ray.dir.dot(&qvec) * inv;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = e2.dot(&qvec) * inv;
        (0.0..=t_max).contains(&t).then_some(t)
    }

    /// The closest point of the triangle to `p` (Ericson, *Real-Time Collision
    /// Detection*, §5.1.5).
    pub fn closest_point(&self, p: &Point3) -> Point3 {
        let (a, b, c) = (self.a, self.b, self.c);
        let ab = b - a;
        let ac = c - a;
        let ap = p - a;
        let d1 = ab.dot(&ap);
        let d2 = ac.dot(&ap);
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let bp = p - b;
        let d3 = ab.dot(&bp);
        let d4 = ac.dot(&bp);
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            let v = d1 / (d1 - d3);
            return a + ab * v;
        }
        let cp = p - c;
        let d5 = ab.dot(&cp);
        let d6 = ac.dot(&cp);
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            let w = d2 / (d2 - d6);
            return a + ac * w;
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            return b + (c - b) * w;
        }
        let denom = 1.0 / (va + vb + vc);
        let v = vb * denom;
        let w = vc * denom;
        a + ab * v + ac * w
    }

    /// Distance from `p` to the triangle.
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        (p - self.closest_point(p)).norm()
    }

    /// Parameter `s ∈ [0, 1]` where segment `seg` crosses the triangle, if it does.
    pub fn segment_hit(&self, seg: &Segment3) -> Option<Real> {
        let d = seg.b - seg.a;
        let len = d.norm();
        if len <= 0.0 {
            return (self.distance_to_point(&seg.a) == 0.0).then_some(0.0);
        }
        let ray = Ray::new(seg.a, UnitVector3::new_unchecked(d / len));
        self.ray_hit(&ray, len).map(|t| t / len)
    }

    /// Distance between a segment and the triangle (0 when they meet).
    pub fn distance_to_segment(&self, seg: &Segment3) -> Real {
        if self.segment_hit(seg).is_some() {
            return 0.0;
        }
        let mut best = self
            .distance_to_point(&seg.a)
            .min(self.distance_to_point(&seg.b));
        for e in self.edges() {
            best = best.min(closest_segment_segment(seg, &e).2);
        }
        best
    }

    /// Distance between two triangles (0 when they intersect). The minimum is
    /// attained on an edge of one of them, so it is the least of the six
    /// edge-to-triangle distances.
    pub fn distance_to_triangle(&self, other: &Self) -> Real {
        let mut best = Real::INFINITY;
        for e in self.edges() {
            best = best.min(other.distance_to_segment(&e));
            if best == 0.0 {
                return 0.0;
            }
        }
        for e in other.edges() {
            best = best.min(self.distance_to_segment(&e));
            if best == 0.0 {
                return 0.0;
            }
        }
        best
    }

    /// `true` when the two triangles share a point.
    pub fn intersects_triangle(&self, other: &Self) -> bool {
        self.distance_to_triangle(other) <= 1e-12
    }

    /// The centroid.
    pub fn centroid(&self) -> Point3 {
        Point3::from((self.a.coords + self.b.coords + self.c.coords) / 3.0)
    }
}

/// A uniformly distributed point of the triangle from two uniform numbers in `[0, 1)`.
pub fn uniform_point(tri: &Triangle, r1: Real, r2: Real) -> Point3 {
    let s = r1.sqrt();
    let w: Vector3 =
        tri.a.coords * (1.0 - s) + tri.b.coords * (s * (1.0 - r2)) + tri.c.coords * (s * r2);
    Point3::from(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tri() -> Triangle {
        Triangle::new(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        )
    }

    #[test]
    fn ray_hits() {
        let t = tri();
        let down = UnitVector3::new_normalize(Vector3::new(0.0, 0.0, -1.0));
        let r = Ray::new(Point3::new(0.25, 0.25, 2.0), down);
        assert!((t.ray_hit(&r, 10.0).unwrap() - 2.0).abs() < 1e-15);
        assert!(t.ray_hit(&r, 1.0).is_none());
        let miss = Ray::new(Point3::new(0.75, 0.75, 2.0), down);
        assert!(t.ray_hit(&miss, 10.0).is_none());
        let away = Ray::new(Point3::new(0.25, 0.25, 2.0), -down);
        assert!(t.ray_hit(&away, 10.0).is_none());
    }

    /// The convention (module docs) on exact cases: every number below is a
    /// small dyadic fraction, so Möller–Trumbore computes it without rounding.
    #[test]
    fn ray_hit_convention_edges_vertices_and_interval_ends() {
        let t = tri();
        let down = UnitVector3::new_normalize(Vector3::new(0.0, 0.0, -1.0));
        let from = |x: f64, y: f64, z: f64| Ray::new(Point3::new(x, y, z), down);
        // Vertices and edge points are hit (closed triangle)...
        for (x, y) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.0, 0.5),
            (0.5, 0.5),
            (0.25, 0.75),
        ] {
            assert_eq!(t.ray_hit(&from(x, y, 2.0), 10.0), Some(2.0), "({x}, {y})");
        }
        // ...points just outside are not.
        for (x, y) in [(-0.125, 0.5), (0.5, -0.125), (0.625, 0.5), (1.0, 0.125)] {
            assert_eq!(t.ray_hit(&from(x, y, 2.0), 10.0), None, "({x}, {y})");
        }
        // Closed distance interval: t == t_max and t == 0 are hits, just short
        // of the surface is not.
        assert_eq!(t.ray_hit(&from(0.25, 0.25, 2.0), 2.0), Some(2.0));
        assert_eq!(t.ray_hit(&from(0.25, 0.25, 2.0), 1.999_999), None);
        assert_eq!(t.ray_hit(&from(0.25, 0.25, 0.0), 1.0), Some(0.0));
        // Either side.
        let up = Ray::new(Point3::new(0.25, 0.25, -0.5), -down);
        assert_eq!(t.ray_hit(&up, 1.0), Some(0.5));
        // A ray in the triangle's plane misses, even through its interior.
        let along = Ray::new(Point3::new(-1.0, 0.25, 0.0), Vector3::x_axis());
        assert_eq!(t.ray_hit(&along, 10.0), None);
    }

    #[test]
    fn closest_point_regions() {
        let t = tri();
        assert_eq!(t.closest_point(&Point3::new(-1.0, -1.0, 0.0)), t.a);
        assert_eq!(t.closest_point(&Point3::new(2.0, -0.5, 1.0)), t.b);
        let p = t.closest_point(&Point3::new(0.5, -1.0, 0.0));
        assert!((p - Point3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
        let p = t.closest_point(&Point3::new(1.0, 1.0, 0.0));
        assert!((p - Point3::new(0.5, 0.5, 0.0)).norm() < 1e-15);
        let p = t.closest_point(&Point3::new(0.2, 0.3, 5.0));
        assert!((p - Point3::new(0.2, 0.3, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn triangle_pairs() {
        let t = tri();
        let piercing = Triangle::new(
            Point3::new(0.2, 0.2, -1.0),
            Point3::new(0.2, 0.2, 1.0),
            Point3::new(0.3, 0.1, 1.0),
        );
        assert!(t.intersects_triangle(&piercing));
        let above = Triangle::new(
            Point3::new(0.0, 0.0, 0.5),
            Point3::new(1.0, 0.0, 0.5),
            Point3::new(0.0, 1.0, 0.5),
        );
        assert!((t.distance_to_triangle(&above) - 0.5).abs() < 1e-12);
        // Coplanar overlapping.
        let shifted = Triangle::new(
            Point3::new(0.1, 0.1, 0.0),
            Point3::new(2.0, 0.1, 0.0),
            Point3::new(0.1, 2.0, 0.0),
        );
        assert!(t.intersects_triangle(&shifted));
    }

    fn brute_point_distance(t: &Triangle, p: &Point3) -> f64 {
        let n = 120;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let q = t.point_at(i as f64 / n as f64, j as f64 / n as f64);
                best = best.min((q - p).norm());
            }
        }
        best
    }

    proptest! {
        #[test]
        fn closest_point_matches_sampling(c in proptest::collection::vec(-1.0f64..1.0, 12)) {
            let t = Triangle::new(
                Point3::new(c[0], c[1], c[2]),
                Point3::new(c[3], c[4], c[5]),
                Point3::new(c[6], c[7], c[8]),
            );
            prop_assume!(t.area() > 1e-3);
            let p = Point3::new(c[9] * 2.0, c[10] * 2.0, c[11] * 2.0);
            let d = t.distance_to_point(&p);
            let oracle = brute_point_distance(&t, &p);
            prop_assert!(d <= oracle + 1e-9);
            prop_assert!(oracle - d < 0.05);
        }

        #[test]
        fn uniform_points_lie_inside(r1 in 0.0f64..1.0, r2 in 0.0f64..1.0) {
            let t = tri();
            let p = uniform_point(&t, r1, r2);
            prop_assert!(t.distance_to_point(&p) < 1e-12);
        }
    }
}
