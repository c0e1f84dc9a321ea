//! Distance queries against the surface model: the model point closest to a
//! point (the corrective motion of P§3.2, the closest model segment of
//! P§3.4.5) and the closest points between a link and the model (the `lᵢ`, `sᵢ`
//! of eq. 4).

use geom::line::{Segment3, closest_segment_segment, segments_apart};
use geom::{Point3, Real, polygon2};
use surface::{EdgeKey, Polygon, SegmentId, SegmentKind, SurfaceModel};

/// Where on a segment a closest point lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// A point segment's centroid.
    Point,
    /// Inside a polygon's perimeter.
    Interior,
    /// On perimeter edge `i` (its vertices included).
    Edge(usize),
}

/// A surface-model point closest to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelPoint {
    /// The segment it lies on.
    pub segment: SegmentId,
    /// The point.
    pub point: Point3,
    /// Its distance from the query.
    pub distance: Real,
    /// Where on the segment.
    pub feature: Feature,
}

/// The closest point of polygon `poly` (the region bounded by its perimeter) to
/// `p`, and where it lies.
pub fn closest_on_polygon(poly: &Polygon, p: &Point3) -> (Point3, Feature) {
    let frame = poly.frame();
    let pts = poly.points_2d(&frame);
    if polygon2::contains_point(&pts, &frame.to_2d(p), 0.0) {
        return (poly.plane().project(p), Feature::Interior);
    }
    closest_on_perimeter(poly, p)
}

/// The closest point of `poly`'s perimeter to `p` and the edge it lies on.
pub fn closest_on_perimeter(poly: &Polygon, p: &Point3) -> (Point3, Feature) {
    let mut best = (Real::INFINITY, Point3::origin(), Feature::Interior);
    for i in 0..poly.len() {
        if let Some((a, b)) = poly.edge_points(i) {
            let q = Segment3::new(a, b).closest_point(p);
            let d = (q - p).norm_squared();
            if d < best.0 {
                best = (d, q, Feature::Edge(i));
            }
        }
    }
    (best.1, best.2)
}

/// The closest point of segment `id` to `p`.
pub fn closest_on_segment(model: &SurfaceModel, id: SegmentId, p: &Point3) -> Option<ModelPoint> {
    let seg = model.segment(id)?;
    let (point, feature) = match seg.kind() {
        SegmentKind::Point(s) => (s.centroid(), Feature::Point),
        SegmentKind::Polygon(g) => closest_on_polygon(g, p),
    };
    Some(ModelPoint {
        segment: id,
        point,
        distance: (point - p).norm(),
        feature,
    })
}

/// The surface-model point closest to `p` within `max_distance`, ties broken
/// by the lower segment id (deterministic).
pub fn closest_model_point(
    model: &SurfaceModel,
    p: &Point3,
    max_distance: Real,
) -> Option<ModelPoint> {
    let mut best: Option<ModelPoint> = None;
    let mut ids = model.segments_near(p, max_distance);
    ids.sort_unstable();
    for id in ids {
        let Some(c) = closest_on_segment(model, id, p) else {
            continue;
        };
        if c.distance <= max_distance && best.is_none_or(|b| c.distance < b.distance) {
            best = Some(c);
        }
    }
    best
}

/// The closest model point to `p` within `max_distance` that satisfies `keep`.
pub fn closest_model_point_where(
    model: &SurfaceModel,
    p: &Point3,
    max_distance: Real,
    keep: impl Fn(&ModelPoint) -> bool,
) -> Option<ModelPoint> {
    let mut best: Option<ModelPoint> = None;
    let mut ids = model.segments_near(p, max_distance);
    ids.sort_unstable();
    for id in ids {
        let Some(c) = closest_on_segment(model, id, p) else {
            continue;
        };
        if c.distance <= max_distance && keep(&c) && best.is_none_or(|b| c.distance < b.distance) {
            best = Some(c);
        }
    }
    best
}

/// Closest points between segment `s` and polygon `poly`:
/// `(distance, point on s, point on poly)`.
pub fn closest_segment_polygon(s: &Segment3, poly: &Polygon) -> (Real, Point3, Point3) {
    let plane = poly.plane();
    let frame = poly.frame();
    let pts = poly.points_2d(&frame);
    let inside = |p: &Point3| polygon2::contains_point(&pts, &frame.to_2d(p), 0.0);
    let (ha, hb) = (plane.signed_distance(&s.a), plane.signed_distance(&s.b));
    if ha * hb <= 0.0 && (ha - hb).abs() > 0.0 {
        let t = ha / (ha - hb);
        let x = s.point_at(t);
        if inside(&x) {
            return (0.0, x, x);
        }
    }
    let mut best = (Real::INFINITY, s.a, s.a);
    for e in [s.a, s.b] {
        let q = plane.project(&e);
        if inside(&q) {
            let d = (e - q).norm();
            if d < best.0 {
                best = (d, e, q);
            }
        }
    }
    for i in 0..poly.len() {
        if let Some((a, b)) = poly.edge_points(i) {
            let edge = Segment3::new(a, b);
            // An edge whose box is farther off than the best cannot beat it.
            if segments_apart(s, &edge, best.0) {
                continue;
            }
            let (ts, te, d) = closest_segment_segment(s, &edge);
            if d < best.0 {
                best = (d, s.point_at(ts), edge.point_at(te));
            }
        }
    }
    best
}

/// Closest points between segment `s` and the model, looking no farther than
/// `max_distance`: `(distance, point on s, model point, segment)`.
pub fn closest_segment_model(
    model: &SurfaceModel,
    s: &Segment3,
    max_distance: Real,
) -> Option<(Real, Point3, Point3, SegmentId)> {
    let mid = Point3::from((s.a.coords + s.b.coords) * 0.5);
    let reach = s.length() * 0.5 + max_distance;
    let mut ids = model.segments_near(&mid, reach);
    ids.sort_unstable();
    let mut best: Option<(Real, Point3, Point3, SegmentId)> = None;
    for id in ids {
        let Some(seg) = model.segment(id) else {
            continue;
        };
        let (d, on_s, on_m) = match seg.kind() {
            SegmentKind::Point(pt) => {
                let c = pt.centroid();
                let q = s.closest_point(&c);
                ((q - c).norm(), q, c)
            }
            SegmentKind::Polygon(g) => closest_segment_polygon(s, g),
        };
        if d <= max_distance && best.is_none_or(|b| d < b.0) {
            best = Some((d, on_s, on_m, id));
        }
    }
    best
}

/// The end points of the edge with key `key`, with its segment and index,
/// looking in segment `hint` first (where it usually is) and then everywhere.
pub fn edge_by_key(model: &SurfaceModel, key: EdgeKey, hint: Option<SegmentId>) -> Option<EdgeRef> {
    let (segment, index) = hint
        .and_then(|h| {
            model
                .polygon(h)
                .and_then(|p| p.edge_index(key))
                .map(|i| (h, i))
        })
        .or_else(|| model.locate_edge(key))?;
    let poly = model.polygon(segment)?;
    let (a, b) = poly.edge_points(index)?;
    let shared = poly.edge(index)?.share.map(|s| s.neighbour);
    Some(EdgeRef {
        key,
        segment,
        index,
        a,
        b,
        shared_with: shared,
    })
}

/// A located perimeter edge: from `a` to `b`, anticlockwise about its
/// polygon's outward normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeRef {
    /// Its key.
    pub key: EdgeKey,
    /// The polygon it belongs to.
    pub segment: SegmentId,
    /// Its index in the polygon's perimeter.
    pub index: usize,
    /// Start vertex.
    pub a: Point3,
    /// End vertex.
    pub b: Point3,
    /// The neighbour it is shared with, if shared.
    pub shared_with: Option<SegmentId>,
}

impl EdgeRef {
    /// The edge as a segment.
    pub fn segment3(&self) -> Segment3 {
        Segment3::new(self.a, self.b)
    }

    /// Its length.
    pub fn length(&self) -> Real {
        (self.b - self.a).norm()
    }

    /// Distance from `p` to the edge.
    pub fn distance_to(&self, p: &Point3) -> Real {
        self.segment3().distance_to_point(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surface::SurfaceConfig;

    fn square_model(z: Real) -> (SurfaceModel, SegmentId) {
        let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
        let id = m
            .add_initial_segment(&[
                Point3::new(0.0, 0.0, z),
                Point3::new(1.0, 0.0, z),
                Point3::new(1.0, 1.0, z),
                Point3::new(0.0, 1.0, z),
            ])
            .unwrap();
        (m, id)
    }

    #[test]
    fn closest_point_above_inside_and_outside_by_hand() {
        let (m, id) = square_model(0.5);
        let c = closest_model_point(&m, &Point3::new(0.3, 0.4, 0.6), 1.0).unwrap();
        assert_eq!(c.segment, id);
        assert_eq!(c.feature, Feature::Interior);
        assert!((c.point - Point3::new(0.3, 0.4, 0.5)).norm() < 1e-12);
        assert!((c.distance - 0.1).abs() < 1e-12);
        // Beyond the edge y = 0 (edge 0, from (0,0) to (1,0)).
        let c = closest_model_point(&m, &Point3::new(0.3, -0.3, 0.9), 1.0).unwrap();
        assert_eq!(c.feature, Feature::Edge(0));
        assert!((c.point - Point3::new(0.3, 0.0, 0.5)).norm() < 1e-12);
        assert!((c.distance - 0.5).abs() < 1e-12);
        assert!(closest_model_point(&m, &Point3::new(0.3, -0.3, 0.9), 0.4).is_none());
    }

    #[test]
    fn segment_polygon_crossing_above_and_beside_by_hand() {
        let (m, _) = square_model(0.0);
        let g = m.segments().next().unwrap().as_polygon().unwrap();
        // Crossing the plane inside: distance 0 at the crossing.
        let s = Segment3::new(Point3::new(0.5, 0.5, -1.0), Point3::new(0.5, 0.5, 1.0));
        let (d, a, b) = closest_segment_polygon(&s, g);
        assert!(d.abs() < 1e-12 && (a - Point3::new(0.5, 0.5, 0.0)).norm() < 1e-12 && a == b);
        // Parallel above: an end point's projection.
        let s = Segment3::new(Point3::new(0.2, 0.2, 0.3), Point3::new(0.8, 0.2, 0.4));
        let (d, a, _) = closest_segment_polygon(&s, g);
        assert!((d - 0.3).abs() < 1e-12 && (a - s.a).norm() < 1e-12);
        // Beside the edge x = 1, level with the plane: segment–edge distance.
        let s = Segment3::new(Point3::new(1.5, -1.0, 0.0), Point3::new(1.5, 2.0, 0.0));
        let (d, _, b) = closest_segment_polygon(&s, g);
        assert!((d - 0.5).abs() < 1e-12 && (b.x - 1.0).abs() < 1e-12);
        // Crossing the plane outside the polygon.
        let s = Segment3::new(Point3::new(2.0, 0.5, -1.0), Point3::new(2.0, 0.5, 1.0));
        let (d, _, _) = closest_segment_polygon(&s, g);
        assert!((d - 1.0).abs() < 1e-12);
    }
}
