//! 2-D polygon and segment queries.
//!
//! A polygon is a slice of vertices; edge `i` joins `v[i]` to `v[(i + 1) % n]`.
//! Anticlockwise polygons have positive [`signed_area`]. These are the primitives
//! Pudney's surface model builds on (P§2.2–2.7): simplicity of perimeters, point
//! containment, and *sight* — "a point can sight another if the straight line that
//! lies between them does not cross the perimeter" (P§2.4.2).

use crate::math::{Point2, Real};

/// Twice the signed area of triangle `a b c`: positive when anticlockwise.
#[inline]
pub fn orient2d(a: &Point2, b: &Point2, c: &Point2) -> Real {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// Signed area (positive when the vertices run anticlockwise).
pub fn signed_area(poly: &[Point2]) -> Real {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..n {
        let a = &poly[i];
        let b = &poly[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    0.5 * s
}

/// `true` when the polygon runs anticlockwise (positive area).
pub fn is_anticlockwise(poly: &[Point2]) -> bool {
    signed_area(poly) > 0.0
}

/// Length of the perimeter.
pub fn perimeter_length(poly: &[Point2]) -> Real {
    let n = poly.len();
    (0..n).map(|i| (poly[(i + 1) % n] - poly[i]).norm()).sum()
}

/// Distance from `p` to the segment `a b`.
pub fn distance_point_segment(p: &Point2, a: &Point2, b: &Point2) -> Real {
    let d = b - a;
    let len2 = d.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&d) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

/// `true` when `p` lies outside the box of segment `a b` grown by `tol` and a
/// margin, so far that [`distance_point_segment`] is certainly greater than
/// `tol`: a cheap reject before that test's division and square root.
///
/// Why it is exact: the computed closest point `a + (b − a)·t` (`t ∈ [0, 1]`)
/// lies within a few units of rounding (about 10⁻¹⁶ relative) of the box of
/// `a b`, and the computed norm of `p − c` is at least `|p.x − c.x|·(1 − 10⁻¹⁵)`
/// (likewise in y). The margin, 10⁻⁹ of `tol` plus the coordinates' magnitudes,
/// exceeds those errors by millions. With NaN or infinite input the reject
/// may hold or not; where it holds the distance is greater or NaN, so
/// `distance_point_segment(p, a, b) <= tol` is false either way.
#[inline]
pub fn beyond_segment_box(p: &Point2, a: &Point2, b: &Point2, tol: Real) -> bool {
    let mx = tol + 1e-9 * (tol + p.x.abs() + a.x.abs() + b.x.abs());
    let my = tol + 1e-9 * (tol + p.y.abs() + a.y.abs() + b.y.abs());
    p.x < a.x.min(b.x) - mx
        || p.x > a.x.max(b.x) + mx
        || p.y < a.y.min(b.y) - my
        || p.y > a.y.max(b.y) + my
}

/// How two closed segments meet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentIntersection {
    /// No common point.
    None,
    /// One common point, at parameter `s` on the first segment and `t` on the second.
    Point {
        /// Parameter on the first segment, in `[0, 1]`.
        s: Real,
        /// Parameter on the second segment, in `[0, 1]`.
        t: Real,
    },
    /// Collinear with a common stretch `[s0, s1]` (parameters on the first segment).
    Overlap {
        /// Start of the common stretch on the first segment.
        s0: Real,
        /// End of the common stretch on the first segment.
        s1: Real,
    },
}

/// Intersection of closed segments `a b` and `c d`. `tol` is a length: points
/// closer than `tol` to a line count as on it, so touching and collinear cases are
/// decided consistently.
pub fn intersect_segments(
    a: &Point2,
    b: &Point2,
    c: &Point2,
    d: &Point2,
    tol: Real,
) -> SegmentIntersection {
    let r = b - a;
    let s = d - c;
    let len_r = r.norm();
    let len_s = s.norm();
    let denom = r.x * s.y - r.y * s.x; // |r||s| sin(angle)
    let qp = c - a;
    // Distances of c and d from line ab, and of a and b from line cd.
    let dist_c = if len_r > 0.0 {
        (r.x * qp.y - r.y * qp.x) / len_r
    } else {
        qp.norm()
    };
    let dist_d = if len_r > 0.0 {
        (r.x * (d.y - a.y) - r.y * (d.x - a.x)) / len_r
    } else {
        (d - a).norm()
    };
    let parallel = denom.abs() <= tol * (len_r.max(len_s)).max(Real::MIN_POSITIVE) * 1e-6
        || len_r == 0.0
        || len_s == 0.0;
    if parallel || (dist_c.abs() <= tol && dist_d.abs() <= tol) {
        if dist_c.abs() > tol || dist_d.abs() > tol {
            return SegmentIntersection::None;
        }
        // Collinear (within tol): overlap of the parameter ranges along ab.
        if len_r == 0.0 {
            // ab is a point: on cd?
            return if distance_point_segment(a, c, d) <= tol {
                SegmentIntersection::Point {
                    s: 0.0,
                    t: if len_s > 0.0 {
                        ((a - c).dot(&s) / (len_s * len_s)).clamp(0.0, 1.0)
                    } else {
                        0.0
                    },
                }
            } else {
                SegmentIntersection::None
            };
        }
        let tc = (c - a).dot(&r) / (len_r * len_r);
        let td = (d - a).dot(&r) / (len_r * len_r);
        let (lo, hi) = if tc <= td { (tc, td) } else { (td, tc) };
        let eps = tol / len_r;
        let s0 = lo.max(0.0);
        let s1 = hi.min(1.0);
        if s0 > s1 + eps {
            return SegmentIntersection::None;
        }
        if s1 - s0 <= eps {
            let sm = (0.5 * (s0 + s1)).clamp(0.0, 1.0);
            let p = a + r * sm;
            let t = if len_s > 0.0 {
                ((p - c).dot(&s) / (len_s * len_s)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return SegmentIntersection::Point { s: sm, t };
        }
        return SegmentIntersection::Overlap { s0, s1 };
    }
    let t_ab = (qp.x * s.y - qp.y * s.x) / denom;
    let t_cd = (qp.x * r.y - qp.y * r.x) / denom;
    let eps_ab = tol / len_r;
    let eps_cd = tol / len_s;
    if t_ab < -eps_ab || t_ab > 1.0 + eps_ab || t_cd < -eps_cd || t_cd > 1.0 + eps_cd {
        return SegmentIntersection::None;
    }
    SegmentIntersection::Point {
        s: t_ab.clamp(0.0, 1.0),
        t: t_cd.clamp(0.0, 1.0),
    }
}

/// Distance between segments `a b` and `c d` (0 when they meet).
pub fn distance_segment_segment(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> Real {
    if !matches!(
        intersect_segments(a, b, c, d, 0.0),
        SegmentIntersection::None
    ) {
        return 0.0;
    }
    distance_point_segment(a, c, d)
        .min(distance_point_segment(b, c, d))
        .min(distance_point_segment(c, a, b))
        .min(distance_point_segment(d, a, b))
}

/// How two edges of a polygon adjoin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeAdjacency {
    /// They share no vertex.
    Apart,
    /// The second edge follows the first: first's end is second's start.
    Next,
    /// The second edge is the closing edge before the first: second's end is
    /// first's start.
    Prev,
}

impl EdgeAdjacency {
    /// Of edge `i` and edge `j > i` of a polygon with `n ≥ 3` vertices.
    pub fn of(i: usize, j: usize, n: usize) -> Self {
        if j == i + 1 {
            Self::Next
        } else if i == 0 && j + 1 == n {
            Self::Prev
        } else {
            Self::Apart
        }
    }
}

/// `true` when polygon edges `a b` and `c d` meet where the edges of a simple
/// polygon may not: anywhere when they are apart, anywhere but their shared
/// vertex when they adjoin (`tol` as in [`intersect_segments`]). The
/// edge-pair test of [`is_simple`].
pub fn edges_meet_improperly(
    a: &Point2,
    b: &Point2,
    c: &Point2,
    d: &Point2,
    adjacency: EdgeAdjacency,
    tol: Real,
) -> bool {
    match intersect_segments(a, b, c, d, tol) {
        SegmentIntersection::None => false,
        SegmentIntersection::Overlap { .. } => true,
        SegmentIntersection::Point { s, t } => {
            let at_shared = match adjacency {
                EdgeAdjacency::Apart => false,
                EdgeAdjacency::Next => s >= 1.0 - tol / (b - a).norm() && t <= tol / (d - c).norm(),
                EdgeAdjacency::Prev => s <= tol / (b - a).norm() && t >= 1.0 - tol / (d - c).norm(),
            };
            !at_shared
        }
    }
}

/// `true` when the polygon is simple: at least three vertices, non-zero area, no
/// repeated vertex, adjacent edges meet only at their shared vertex and
/// non-adjacent edges do not meet at all (`tol` as in [`intersect_segments`]).
pub fn is_simple(poly: &[Point2], tol: Real) -> bool {
    let n = poly.len();
    if n < 3 || signed_area(poly).abs() <= tol * tol {
        return false;
    }
    for i in 0..n {
        let a = &poly[i];
        let b = &poly[(i + 1) % n];
        if (b - a).norm() <= tol {
            return false;
        }
        for j in (i + 1)..n {
            let c = &poly[j];
            let d = &poly[(j + 1) % n];
            if edges_meet_improperly(a, b, c, d, EdgeAdjacency::of(i, j, n), tol) {
                return false;
            }
        }
    }
    true
}

/// Where a point lies relative to a polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    /// Strictly inside.
    Inside,
    /// Within `tol` of the perimeter.
    Boundary,
    /// Strictly outside.
    Outside,
}

/// Locate `p` relative to the polygon (any orientation), with a boundary band of
/// width `tol`.
pub fn locate_point(poly: &[Point2], p: &Point2, tol: Real) -> Containment {
    let n = poly.len();
    if n == 0 {
        return Containment::Outside;
    }
    for i in 0..n {
        let (a, b) = (&poly[i], &poly[(i + 1) % n]);
        if !beyond_segment_box(p, a, b, tol) && distance_point_segment(p, a, b) <= tol {
            return Containment::Boundary;
        }
    }
    // Crossing number with the half-open rule on y.
    let mut inside = false;
    for i in 0..n {
        let a = &poly[i];
        let b = &poly[(i + 1) % n];
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if x > p.x {
                inside = !inside;
            }
        }
    }
    if inside {
        Containment::Inside
    } else {
        Containment::Outside
    }
}

/// `true` when `p` is inside the polygon or on its boundary (within `tol`).
pub fn contains_point(poly: &[Point2], p: &Point2, tol: Real) -> bool {
    locate_point(poly, p, tol) != Containment::Outside
}

/// Sight test (P§2.4.2): `true` when the segment `a b` does not cross any of the
/// given edges. Contact at `a` or `b` themselves (within `tol`) is not a crossing,
/// so perimeter points can sight along their own perimeter; an edge equal to
/// `a b` is ignored.
pub fn can_sight<'a>(
    a: &Point2,
    b: &Point2,
    edges: impl IntoIterator<Item = (&'a Point2, &'a Point2)>,
    tol: Real,
) -> bool {
    let len = (b - a).norm();
    if len <= tol {
        return true;
    }
    let near = tol / len; // parameter band around a and b that does not count
    for (c, d) in edges {
        if blocks_sight(a, b, c, d, tol, near) {
            return false;
        }
    }
    true
}

/// One edge's part of [`can_sight`]: `true` when edge `c d` crosses the sight
/// line `a b` (longer than `tol`) outside the parameter band `near = tol / |ab|`
/// at its ends. For callers that scan their edges themselves.
#[inline]
pub fn blocks_sight(a: &Point2, b: &Point2, c: &Point2, d: &Point2, tol: Real, near: Real) -> bool {
    let same = ((c - a).norm() <= tol && (d - b).norm() <= tol)
        || ((c - b).norm() <= tol && (d - a).norm() <= tol);
    if same {
        return false;
    }
    match intersect_segments(a, b, c, d, tol) {
        SegmentIntersection::None => false,
        SegmentIntersection::Point { s, .. } => s > near && s < 1.0 - near,
        SegmentIntersection::Overlap { s0, s1 } => s1 > near && s0 < 1.0 - near,
    }
}

/// Sight test relative to a closed perimeter (all of its edges).
pub fn can_sight_in_polygon(a: &Point2, b: &Point2, poly: &[Point2], tol: Real) -> bool {
    let n = poly.len();
    can_sight(a, b, (0..n).map(|i| (&poly[i], &poly[(i + 1) % n])), tol)
}

/// The common part of two polygons ([`overlap`]): its area and centroid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// Area of the intersection (0 when the polygons only touch).
    pub area: Real,
    /// Centroid of the intersection (`None` when its area is 0).
    pub centroid: Option<Point2>,
}

/// Area and centroid of the intersection of two simple anticlockwise
/// polygons, by Green's theorem over its boundary: the pieces of each
/// perimeter that lie inside the other polygon, and the stretches along which
/// both perimeters run the same way, counted once. Perimeters that run along
/// each other in opposite directions bound the polygons from either side, so
/// polygons that only touch along an edge or at a vertex overlap by 0.
/// `tol` as in [`intersect_segments`]: a piece within `tol` of the other
/// perimeter lies on it. Cost: O(n·m) segment tests.
///
/// ```
/// use geom::Point2;
/// use geom::polygon2::overlap;
/// let square = |x: f64, y: f64| {
///     vec![Point2::new(x, y), Point2::new(x + 1.0, y), Point2::new(x + 1.0, y + 1.0), Point2::new(x, y + 1.0)]
/// };
/// let half = overlap(&square(0.0, 0.0), &square(0.5, 0.0), 1e-9);
/// assert!((half.area - 0.5).abs() < 1e-12);
/// assert!((half.centroid.unwrap() - Point2::new(0.75, 0.5)).norm() < 1e-12);
/// assert_eq!(overlap(&square(0.0, 0.0), &square(1.0, 0.0), 1e-9).area, 0.0);
/// ```
pub fn overlap(p: &[Point2], q: &[Point2], tol: Real) -> Overlap {
    let mut sums = [0.0; 3];
    boundary_within(p, q, tol, true, &mut sums);
    boundary_within(q, p, tol, false, &mut sums);
    let area = 0.5 * sums[0];
    // Rounding can leave touching polygons a few ulps of signed area.
    if area <= 0.0 {
        return Overlap {
            area: 0.0,
            centroid: None,
        };
    }
    Overlap {
        area,
        centroid: Some(Point2::new(sums[1] / (6.0 * area), sums[2] / (6.0 * area))),
    }
}

/// Adds to `sums` (twice the area, six times the area's first moments in x
/// and y) the Green's-theorem terms of the pieces of `p`'s perimeter inside
/// `q`, and with `shared` those along `q`'s perimeter in the same direction.
fn boundary_within(p: &[Point2], q: &[Point2], tol: Real, shared: bool, sums: &mut [Real; 3]) {
    let (n, m) = (p.len(), q.len());
    let mut cuts = Vec::new();
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        cuts.clear();
        cuts.extend([0.0, 1.0]);
        for j in 0..m {
            match intersect_segments(&a, &b, &q[j], &q[(j + 1) % m], tol) {
                SegmentIntersection::None => {}
                SegmentIntersection::Point { s, .. } => cuts.push(s),
                SegmentIntersection::Overlap { s0, s1 } => cuts.extend([s0, s1]),
            }
        }
        cuts.sort_by(Real::total_cmp);
        for w in cuts.windows(2) {
            if w[1] <= w[0] {
                continue;
            }
            let (u, v) = (a + (b - a) * w[0], a + (b - a) * w[1]);
            let mid = Point2::from((u.coords + v.coords) * 0.5);
            let counts = match locate_point(q, &mid, tol) {
                Containment::Inside => true,
                Containment::Outside => false,
                Containment::Boundary => {
                    shared
                        && (0..m).any(|j| {
                            let (c, d) = (&q[j], &q[(j + 1) % m]);
                            distance_point_segment(&mid, c, d) <= tol && (d - c).dot(&(v - u)) > 0.0
                        })
                }
            };
            if counts {
                let cross = u.x * v.y - v.x * u.y;
                sums[0] += cross;
                sums[1] += (u.x + v.x) * cross;
                sums[2] += (u.y + v.y) * cross;
            }
        }
    }
}

/// Convex hull (Andrew's monotone chain), anticlockwise from the lowest-x
/// (then lowest-y) point, without collinear vertices or a repeated first
/// vertex. Fewer than three distinct points come back sorted.
pub fn convex_hull(mut pts: Vec<Point2>) -> Vec<Point2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let mut hull: Vec<Point2> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point2>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for p in iter {
            while hull.len() >= start + 2
                && orient2d(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(*p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point2 {
        Point2::new(x, y)
    }

    fn square() -> Vec<Point2> {
        vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]
    }

    /// Wherever the box reject holds, the distance exceeds the tolerance:
    /// points scattered around segments of several scales, most of them near
    /// the grown box's sides (where rounding could matter).
    #[test]
    fn box_reject_implies_far() {
        // A small deterministic generator (xorshift) keeps the test free of
        // dependencies.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut unit = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as Real / (1u64 << 53) as Real
        };
        let mut rejected = 0;
        for k in 0..200_000 {
            let scale = [1e-3, 1.0, 1e3][k % 3];
            let tol = [0.0, 1e-9, 1e-6, 0.05][k % 4];
            let a = p((unit() - 0.5) * scale, (unit() - 0.5) * scale);
            let b = if k % 7 == 0 {
                a
            } else {
                p((unit() - 0.5) * scale, (unit() - 0.5) * scale)
            };
            // A point just beyond a side of the grown box, or anywhere near.
            let side = (unit() - 0.5) * 4e-15 * scale;
            let q = match k % 5 {
                0 => p(a.x.max(b.x) + tol + side, (unit() - 0.5) * scale),
                1 => p(a.x.min(b.x) - tol + side, (unit() - 0.5) * scale),
                2 => p((unit() - 0.5) * scale, a.y.max(b.y) + tol + side),
                3 => p((unit() - 0.5) * scale, a.y.min(b.y) - tol + side),
                _ => p((unit() - 0.5) * 2.0 * scale, (unit() - 0.5) * 2.0 * scale),
            };
            if beyond_segment_box(&q, &a, &b, tol) {
                rejected += 1;
                assert!(
                    distance_point_segment(&q, &a, &b).partial_cmp(&tol)
                        == Some(std::cmp::Ordering::Greater),
                    "{q} {a} {b} {tol}"
                );
            }
        }
        assert!(rejected > 10_000);
        // Non-finite input: a reject only where the distance test fails too.
        let (o, e) = (p(0.0, 0.0), p(1.0, 0.0));
        for q in [
            p(Real::NAN, 5.0),
            p(Real::NAN, 0.0),
            p(Real::INFINITY, 0.0),
            p(0.5, Real::NEG_INFINITY),
        ] {
            if beyond_segment_box(&q, &o, &e, 0.1) {
                let d = distance_point_segment(&q, &o, &e);
                assert!(d > 0.1 || d.is_nan());
            }
        }
    }

    #[test]
    fn area_and_orientation() {
        let sq = square();
        assert!((signed_area(&sq) - 1.0).abs() < 1e-15);
        assert!(is_anticlockwise(&sq));
        let mut cw = sq.clone();
        cw.reverse();
        assert!((signed_area(&cw) + 1.0).abs() < 1e-15);
        assert!((perimeter_length(&sq) - 4.0).abs() < 1e-15);
    }

    #[test]
    fn simplicity() {
        assert!(is_simple(&square(), 1e-9));
        // Bow tie.
        let bow = vec![p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 1.0)];
        assert!(!is_simple(&bow, 1e-9));
        // Vertex touching a non-adjacent edge.
        let touch = vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 2.0),
            p(1.0, 0.0),
            p(0.0, 2.0),
        ];
        assert!(!is_simple(&touch, 1e-9));
        // Fold-back spike (adjacent edges overlap).
        let spike = vec![p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)];
        assert!(!is_simple(&spike, 1e-9));
        // Concave L is simple.
        let l = vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 1.0),
            p(1.0, 2.0),
            p(0.0, 2.0),
        ];
        assert!(is_simple(&l, 1e-9));
        assert!(!is_simple(&[p(0.0, 0.0), p(1.0, 0.0)], 1e-9));
    }

    #[test]
    fn containment() {
        let l = vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 1.0),
            p(1.0, 2.0),
            p(0.0, 2.0),
        ];
        assert_eq!(locate_point(&l, &p(0.5, 0.5), 1e-9), Containment::Inside);
        assert_eq!(locate_point(&l, &p(1.5, 1.5), 1e-9), Containment::Outside);
        assert_eq!(locate_point(&l, &p(1.0, 1.5), 1e-9), Containment::Boundary);
        assert_eq!(locate_point(&l, &p(1.5, 0.5), 1e-9), Containment::Inside);
        assert!(contains_point(&l, &p(2.0, 0.0), 1e-9));
    }

    #[test]
    fn segment_intersections() {
        let r = intersect_segments(
            &p(0.0, 0.0),
            &p(2.0, 0.0),
            &p(1.0, -1.0),
            &p(1.0, 1.0),
            1e-12,
        );
        assert_eq!(r, SegmentIntersection::Point { s: 0.5, t: 0.5 });
        let r = intersect_segments(
            &p(0.0, 0.0),
            &p(2.0, 0.0),
            &p(1.0, 0.0),
            &p(3.0, 0.0),
            1e-12,
        );
        assert_eq!(r, SegmentIntersection::Overlap { s0: 0.5, s1: 1.0 });
        let r = intersect_segments(
            &p(0.0, 0.0),
            &p(2.0, 0.0),
            &p(3.0, 0.0),
            &p(4.0, 0.0),
            1e-12,
        );
        assert_eq!(r, SegmentIntersection::None);
        let r = intersect_segments(
            &p(0.0, 0.0),
            &p(2.0, 0.0),
            &p(0.0, 1.0),
            &p(2.0, 1.0),
            1e-12,
        );
        assert_eq!(r, SegmentIntersection::None);
        assert!(
            (distance_segment_segment(&p(0.0, 0.0), &p(2.0, 0.0), &p(3.0, 1.0), &p(3.0, 2.0))
                - 2f64.sqrt())
            .abs()
                < 1e-12
        );
        assert_eq!(
            distance_segment_segment(&p(0.0, 0.0), &p(2.0, 2.0), &p(0.0, 2.0), &p(2.0, 0.0)),
            0.0
        );
    }

    #[test]
    fn sight() {
        // L-shape: the re-entrant corner blocks sight across the notch.
        let l = vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 1.0),
            p(1.0, 2.0),
            p(0.0, 2.0),
        ];
        // (2,1)→(1,2) passes outside through the notch but touches no edge except at
        // its ends: visible *relative to the perimeter* (no crossing).
        assert!(can_sight_in_polygon(&p(2.0, 1.0), &p(1.0, 2.0), &l, 1e-9));
        // (2,0.5)→(0.5,2) crosses edges (2,1)-(1,1) and (1,1)-(1,2).
        assert!(!can_sight_in_polygon(&p(2.0, 0.5), &p(0.5, 2.0), &l, 1e-9));
        // Consecutive vertices always sight each other.
        for i in 0..l.len() {
            assert!(can_sight_in_polygon(&l[i], &l[(i + 1) % l.len()], &l, 1e-9));
        }
        // A segment lying along an edge but beyond its ends crosses (overlap).
        assert!(!can_sight_in_polygon(&p(-1.0, 0.0), &p(0.5, 0.0), &l, 1e-9));
    }

    #[test]
    fn convex_hull_of_a_square_with_inner_and_edge_points() {
        let pts = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
            (0.2, 0.7),
            (1.0, 0.5),
        ]
        .map(|(x, y)| Point2::new(x, y));
        let h = super::convex_hull(pts.to_vec());
        let want = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| Point2::new(x, y));
        assert_eq!(h, want.to_vec());
        assert!(super::is_anticlockwise(&h));
    }

    /// A deterministic generator (xorshift) in [0, 1).
    fn xorshift(seed: u64) -> impl FnMut() -> Real {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as Real / (1u64 << 53) as Real
        }
    }

    /// A random simple polygon, star-shaped about `(cx, cy)`: `k ≥ 3`
    /// vertices at increasing angles (each in its own `1/k` of the turn,
    /// jittered by 0.4 of it, so no gap reaches half a turn) and radii in
    /// [0.3, 1], anticlockwise.
    fn star(unit: &mut impl FnMut() -> Real, cx: Real, cy: Real, k: usize) -> Vec<Point2> {
        (0..k)
            .map(|i| {
                let a = (i as Real + 0.4 * unit()) / k as Real * std::f64::consts::TAU;
                let r = 0.3 + 0.7 * unit();
                p(cx + r * a.cos(), cy + r * a.sin())
            })
            .collect()
    }

    /// The oracle for a convex `clip`: Sutherland–Hodgman clipping of
    /// `subject` (any simple polygon; a non-convex one may leave zero-width
    /// bridges, which add no area), then the shoelace area and centroid.
    fn clipped_area_and_centroid(subject: &[Point2], clip: &[Point2]) -> (Real, Point2) {
        let mut out = subject.to_vec();
        for j in 0..clip.len() {
            let (c, d) = (clip[j], clip[(j + 1) % clip.len()]);
            let inside = |x: &Point2| orient2d(&c, &d, x) >= 0.0;
            let input = std::mem::take(&mut out);
            for i in 0..input.len() {
                let (a, b) = (input[i], input[(i + 1) % input.len()]);
                let cut = |a: &Point2, b: &Point2| {
                    let (fa, fb) = (orient2d(&c, &d, a), orient2d(&c, &d, b));
                    a + (b - a) * (fa / (fa - fb))
                };
                match (inside(&a), inside(&b)) {
                    (true, true) => out.push(b),
                    (true, false) => out.push(cut(&a, &b)),
                    (false, true) => {
                        out.push(cut(&a, &b));
                        out.push(b);
                    }
                    (false, false) => {}
                }
            }
        }
        let area = signed_area(&out);
        let (mut cx, mut cy) = (0.0, 0.0);
        for i in 0..out.len() {
            let (a, b) = (out[i], out[(i + 1) % out.len()]);
            let cross = a.x * b.y - b.x * a.y;
            cx += (a.x + b.x) * cross;
            cy += (a.y + b.y) * cross;
        }
        (area, p(cx / (6.0 * area), cy / (6.0 * area)))
    }

    #[test]
    fn overlap_of_squares_touching_sharing_and_containing() {
        let rect = |x0: Real, y0: Real, x1: Real, y1: Real| {
            vec![p(x0, y0), p(x1, y0), p(x1, y1), p(x0, y1)]
        };
        let sq = square();
        let cases = [
            // Side by side, along a corner, apart: no area.
            (rect(1.0, 0.0, 2.0, 1.0), 0.0, None),
            (rect(1.0, 1.0, 2.0, 2.0), 0.0, None),
            (rect(1.5, 0.0, 2.0, 1.0), 0.0, None),
            // The same square; one inside another sharing three sides; a
            // half sharing two; a small one strictly inside.
            (square(), 1.0, Some(p(0.5, 0.5))),
            (rect(0.0, 0.0, 1.0, 2.0), 1.0, Some(p(0.5, 0.5))),
            (rect(0.0, 0.5, 1.0, 1.5), 0.5, Some(p(0.5, 0.75))),
            (rect(0.25, 0.25, 0.5, 0.5), 0.0625, Some(p(0.375, 0.375))),
            // Crossing in a plus sign.
            (rect(0.25, -1.0, 0.75, 2.0), 0.5, Some(p(0.5, 0.5))),
        ];
        for (q, area, centroid) in cases {
            for (a, b) in [(&sq, &q), (&q, &sq)] {
                let o = overlap(a, b, 1e-9);
                assert!((o.area - area).abs() < 1e-12, "{q:?}: {o:?}");
                match (o.centroid, centroid) {
                    (None, None) => {}
                    (Some(c), Some(want)) => assert!((c - want).norm() < 1e-12, "{q:?}: {o:?}"),
                    _ => panic!("{q:?}: {o:?}"),
                }
            }
        }
        // An L beside a square in its notch touches it along two edges.
        let l = vec![
            p(0.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 1.0),
            p(1.0, 1.0),
            p(1.0, 2.0),
            p(0.0, 2.0),
        ];
        assert_eq!(overlap(&l, &rect(1.0, 1.0, 2.0, 2.0), 1e-9).area, 0.0);
        assert!((overlap(&l, &rect(0.5, 0.5, 1.5, 1.5), 1e-9).area - 0.75).abs() < 1e-12);
    }

    /// Random star polygons against random convex ones (the clipping
    /// oracle), both ways round, at several scales.
    #[test]
    fn overlap_matches_clipping_by_a_convex_polygon() {
        let mut unit = xorshift(0x2545_f491_4f6c_dd1d);
        let mut overlapping = 0;
        for k in 0..2000 {
            let scale = [1e-2, 1.0, 1e2][k % 3];
            let subject: Vec<Point2> = star(&mut unit, 0.0, 0.0, 3 + k % 9)
                .iter()
                .map(|v| Point2::from(v.coords * scale))
                .collect();
            let (cx, cy) = ((unit() - 0.5) * 2.5 * scale, (unit() - 0.5) * 2.5 * scale);
            let clip = convex_hull(
                (0..3 + k % 6)
                    .map(|_| p(cx + unit() * scale, cy + unit() * scale))
                    .collect(),
            );
            if clip.len() < 3 {
                continue;
            }
            let (area, centroid) = clipped_area_and_centroid(&subject, &clip);
            for o in [
                overlap(&subject, &clip, 1e-12 * scale),
                overlap(&clip, &subject, 1e-12 * scale),
            ] {
                let tol = 1e-9 * scale * scale;
                assert!(
                    (o.area - area).abs() < tol,
                    "case {k}: {} against {area}",
                    o.area
                );
                if area > 1e-6 * scale * scale {
                    let c = o.centroid.unwrap();
                    assert!(
                        (c - centroid).norm() < 1e-6 * scale,
                        "case {k}: {c} against {centroid}"
                    );
                }
            }
            overlapping += usize::from(area > 0.0);
        }
        assert!(overlapping > 500, "{overlapping}");
    }

    /// Two random star polygons (neither convex): the area against a count
    /// of grid cell centres inside both, to the grid's resolution.
    #[test]
    fn overlap_of_two_non_convex_polygons_matches_a_grid_count() {
        let mut unit = xorshift(0x9e37_79b9_7f4a_7c15);
        for k in 0..20 {
            let a = star(&mut unit, 0.0, 0.0, 12);
            let (cx, cy) = (0.5 * (unit() - 0.5), 0.5 * (unit() - 0.5));
            let b = star(&mut unit, cx, cy, 12);
            let n = 400;
            let cell = 4.0 / Real::from(n);
            let mut inside = 0u32;
            for i in 0..n {
                for j in 0..n {
                    let c = p(
                        -2.0 + (Real::from(i) + 0.5) * cell,
                        -2.0 + (Real::from(j) + 0.5) * cell,
                    );
                    if locate_point(&a, &c, 0.0) == Containment::Inside
                        && locate_point(&b, &c, 0.0) == Containment::Inside
                    {
                        inside += 1;
                    }
                }
            }
            let counted = Real::from(inside) * cell * cell;
            let o = overlap(&a, &b, 1e-12);
            // The cells the two perimeters (each under 2π·2 long) cross.
            let bound = 2.0 * 4.0 * std::f64::consts::TAU * cell;
            assert!(
                (o.area - counted).abs() < bound,
                "case {k}: {} against {counted}",
                o.area
            );
            assert!(counted > 0.05, "case {k}: the stars meet");
        }
    }
}
