//! Infinite lines and segments in 3-D, and the closest points between them.

use crate::math::{Point3, Real, UnitVector3};
use serde::{Deserialize, Serialize};

/// The infinite line `point + t * dir`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Line3 {
    /// A point on the line.
    pub point: Point3,
    /// Unit direction.
    pub dir: UnitVector3,
}

impl Line3 {
    /// The line through `point` along `dir`.
    pub fn new(point: Point3, dir: UnitVector3) -> Self {
        Self { point, dir }
    }

    /// The point at parameter `t` (a signed distance from [`Line3::point`]).
    pub fn point_at(&self, t: Real) -> Point3 {
        self.point + self.dir.into_inner() * t
    }

    /// Parameter of the orthogonal projection of `p`.
    pub fn project_param(&self, p: &Point3) -> Real {
        (p - self.point).dot(&self.dir)
    }

    /// Orthogonal projection of `p` onto the line.
    pub fn project(&self, p: &Point3) -> Point3 {
        self.point_at(self.project_param(p))
    }

    /// Distance from `p` to the line.
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        (p - self.project(p)).norm()
    }
}

/// The segment from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment3 {
    /// Start point.
    pub a: Point3,
    /// End point.
    pub b: Point3,
}

impl Segment3 {
    /// The segment from `a` to `b`.
    pub fn new(a: Point3, b: Point3) -> Self {
        Self { a, b }
    }

    /// Length.
    pub fn length(&self) -> Real {
        (self.b - self.a).norm()
    }

    /// The point at parameter `s ∈ [0, 1]`.
    pub fn point_at(&self, s: Real) -> Point3 {
        self.a + (self.b - self.a) * s
    }

    /// Parameter in `[0, 1]` of the closest point to `p`.
    pub fn closest_param(&self, p: &Point3) -> Real {
        let d = self.b - self.a;
        let len2 = d.norm_squared();
        if len2 <= 0.0 {
            return 0.0;
        }
        ((p - self.a).dot(&d) / len2).clamp(0.0, 1.0)
    }

    /// The closest point of the segment to `p`.
    pub fn closest_point(&self, p: &Point3) -> Point3 {
        self.point_at(self.closest_param(p))
    }

    /// Distance from `p` to the segment.
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        (p - self.closest_point(p)).norm()
    }
}

/// Closest points between two segments: returns `(s, t, distance)` with the
/// points `p.point_at(s)` and `q.point_at(t)`. Degenerate (zero-length) segments
/// are handled as points. (Ericson, *Real-Time Collision Detection*, §5.1.9.)
pub fn closest_segment_segment(p: &Segment3, q: &Segment3) -> (Real, Real, Real) {
    let d1 = p.b - p.a;
    let d2 = q.b - q.a;
    let r = p.a - q.a;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let eps = 1e-24;
    let (s, t);
    if a <= eps && e <= eps {
        s = 0.0;
        t = 0.0;
    } else if a <= eps {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > eps * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    let dist = (p.point_at(s) - q.point_at(t)).norm();
    (s, t, dist)
}

/// `true` when the boxes of segments `p` and `q` lie more than `d` apart
/// along some axis (plus a margin), so that the distance of
/// [`closest_segment_segment`] is certainly greater than `d`: a cheap reject
/// for searches of the closest pair, which skip pairs that cannot beat the
/// best so far.
///
/// Why it is exact: the closest points `a + (b − a)·s` (`s, t ∈ [0, 1]`) lie
/// within a few units of rounding (about 10⁻¹⁶ relative) of their segments'
/// boxes, and the computed norm of their difference is at least its largest
/// component times `1 − 10⁻¹⁵`. The margin, 10⁻⁹ of `d` plus the coordinates'
/// magnitudes, exceeds those errors by millions. An infinite or NaN `d`
/// never rejects.
#[inline]
pub fn segments_apart(p: &Segment3, q: &Segment3, d: Real) -> bool {
    (0..3).any(|k| {
        let (pa, pb, qa, qb) = (p.a[k], p.b[k], q.a[k], q.b[k]);
        let m = d + 1e-9 * (d + pa.abs() + pb.abs() + qa.abs() + qb.abs());
        qa.min(qb) - pa.max(pb) > m || pa.min(pb) - qa.max(qb) > m
    })
}

/// Distance between two segments.
pub fn distance_segment_segment(p: &Segment3, q: &Segment3) -> Real {
    closest_segment_segment(p, q).2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector3;
    use proptest::prelude::*;

    fn seg(a: [f64; 3], b: [f64; 3]) -> Segment3 {
        Segment3::new(Point3::from(a), Point3::from(b))
    }

    /// Wherever the box reject holds, the segments are farther apart than
    /// the bound: random segments at several scales, with bounds just under,
    /// at and over their distances.
    #[test]
    fn apart_implies_farther() {
        // A small deterministic generator (xorshift).
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut unit = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as Real / (1u64 << 53) as Real
        };
        let mut rejected = 0;
        for k in 0..100_000 {
            let scale = [1e-3, 1.0, 1e3][k % 3];
            let mut pt = || {
                Point3::new(
                    (unit() - 0.5) * scale,
                    (unit() - 0.5) * scale,
                    (unit() - 0.5) * scale,
                )
            };
            let p = Segment3::new(pt(), pt());
            let q = if k % 5 == 0 {
                Segment3::new(p.b, pt())
            } else {
                Segment3::new(pt(), pt())
            };
            let dist = closest_segment_segment(&p, &q).2;
            // The largest axis gap between the boxes: the bound that rejects.
            let gap = (0..3)
                .map(|i| {
                    let (p0, p1) = (p.a[i].min(p.b[i]), p.a[i].max(p.b[i]));
                    let (q0, q1) = (q.a[i].min(q.b[i]), q.a[i].max(q.b[i]));
                    (q0 - p1).max(p0 - q1)
                })
                .fold(Real::NEG_INFINITY, Real::max);
            let bounds = [
                dist,
                dist * (1.0 - 1e-12),
                gap,
                gap * (1.0 - 1e-12),
                gap * (1.0 - 1e-8),
                0.0,
            ];
            for d in bounds {
                if d >= 0.0 && segments_apart(&p, &q, d) {
                    rejected += 1;
                    assert!(dist > d, "{p:?} {q:?} {d} {dist}");
                }
            }
        }
        assert!(rejected > 10_000);
        let p = seg([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let q = seg([0.0, 5.0, 0.0], [1.0, 5.0, 0.0]);
        assert!(segments_apart(&p, &q, 4.9));
        assert!(!segments_apart(&p, &q, 5.0));
        assert!(!segments_apart(&p, &q, Real::INFINITY));
        assert!(!segments_apart(&p, &q, Real::NAN));
    }

    #[test]
    fn hand_cases() {
        // Skew perpendicular segments one unit apart.
        let p = seg([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        let q = seg([0.0, -1.0, 1.0], [0.0, 1.0, 1.0]);
        let (s, t, d) = closest_segment_segment(&p, &q);
        assert!((d - 1.0).abs() < 1e-12 && (s - 0.5).abs() < 1e-12 && (t - 0.5).abs() < 1e-12);
        // Parallel, overlapping: distance between the supporting lines.
        let q2 = seg([0.5, 2.0, 0.0], [3.0, 2.0, 0.0]);
        assert!((distance_segment_segment(&p, &q2) - 2.0).abs() < 1e-12);
        // Collinear, disjoint: gap between the nearest endpoints.
        let q3 = seg([3.0, 0.0, 0.0], [4.0, 0.0, 0.0]);
        assert!((distance_segment_segment(&p, &q3) - 2.0).abs() < 1e-12);
        // Degenerate point segment.
        let pt = seg([0.0, 3.0, 0.0], [0.0, 3.0, 0.0]);
        assert!((distance_segment_segment(&p, &pt) - 3.0).abs() < 1e-12);
        let l = Line3::new(Point3::origin(), Vector3::x_axis());
        assert!((l.distance_to_point(&Point3::new(5.0, 3.0, 4.0)) - 5.0).abs() < 1e-12);
    }

    fn brute_force(p: &Segment3, q: &Segment3) -> f64 {
        let n = 400;
        let mut best = f64::INFINITY;
        for i in 0..=n {
            let a = p.point_at(i as f64 / n as f64);
            best = best.min(q.distance_to_point(&a));
        }
        for j in 0..=n {
            let b = q.point_at(j as f64 / n as f64);
            best = best.min(p.distance_to_point(&b));
        }
        best
    }

    proptest! {
        #[test]
        fn matches_sampled_oracle(c in proptest::collection::vec(-2.0f64..2.0, 12)) {
            let p = seg([c[0], c[1], c[2]], [c[3], c[4], c[5]]);
            let q = seg([c[6], c[7], c[8]], [c[9], c[10], c[11]]);
            let d = distance_segment_segment(&p, &q);
            let oracle = brute_force(&p, &q);
            // The sampled oracle over-estimates by at most half a sample step.
            prop_assert!(d <= oracle + 1e-9);
            prop_assert!(oracle - d <= 0.03);
        }
    }
}
