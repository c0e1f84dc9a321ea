//! Model segments (P§2.2): point segments and planar polygon segments, with the
//! per-edge and per-vertex records that make shared edges and corner vertices.

use geom::polygon2;
use geom::{Moments, Plane, PlaneFrame, Point2, Point3, Real, UnitVector3, Vector3, unit};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// Stable identity of a model segment. Ids grow with creation and are never
/// reused within a model, so "the order in which segments are stored in memory"
/// (P§2.3) is id order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct SegmentId(pub u32);

/// Stable identity of a perimeter edge. An edge keeps its key while it is only
/// projected or repositioned (P§3.4.6: these "merely reposition edges"), also when
/// a merger carries it into the new segment; an edge that is cut, shortened by a
/// removed perimeter section, or replaced gets a new key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct EdgeKey(pub u32);

/// Identity of a pair of corresponding shared edges (P§2.2): both copies carry it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct PairId(pub u32);

/// Identity of a set of corresponding corner vertices, one per segment of a
/// neighbour cycle (P§2.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct CornerId(pub u32);

/// The shared status of an edge: the neighbour it is shared with, and the pair id
/// its corresponding edge in that neighbour carries too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Share {
    /// The neighbour.
    pub neighbour: SegmentId,
    /// The pair of corresponding shared edges this edge belongs to.
    pub pair: PairId,
}

/// A perimeter edge record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Stable key (see [`EdgeKey`]).
    pub key: EdgeKey,
    /// `Some` when this is a shared edge.
    pub share: Option<Share>,
}

/// One perimeter vertex and the edge that leaves it anticlockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// The vertex, on the segment's plane.
    pub position: Point3,
    /// `Some` when the vertex is a corner vertex (P§2.7): it then joins two edges
    /// shared with different neighbours, and its corresponding corner vertices on
    /// the other segments of the cycle carry the same id.
    pub corner: Option<CornerId>,
    /// The edge from this vertex to the next one anticlockwise.
    pub edge: Edge,
}

/// A point segment (P§2.2): the centroid of the points it represents, with the sum
/// of their sensing axes (P§2.3, P§2.4.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSegment {
    pub(crate) centroid: Point3,
    pub(crate) axis_sum: Vector3,
}

impl PointSegment {
    /// The point of best fit (centroid).
    pub fn centroid(&self) -> Point3 {
        self.centroid
    }

    /// The sensing axis: the direction of the sum of the represented points'
    /// sensing axes; it points into the surface.
    pub fn sensing_axis(&self) -> UnitVector3 {
        unit(self.axis_sum).unwrap_or_else(Vector3::z_axis)
    }

    /// The un-normalised sum of the sensing axes.
    pub fn axis_sum(&self) -> Vector3 {
        self.axis_sum
    }
}

/// Perimeter revisions, to skip repeating the fissure and shared-edge steps on a
/// perimeter that has not changed since they last ran (a merger that only
/// re-projects a perimeter keeps its revision).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Revisions {
    /// Bumped by every change of the perimeter's records or positions.
    pub shape: u64,
    /// `shape` when fissures were last filled.
    pub fissures_at: u64,
    /// `shape` when shared edges were last attempted from this polygon.
    pub shares_at: u64,
}

impl Revisions {
    /// A new perimeter: every step still has to run.
    pub fn fresh() -> Self {
        Self {
            shape: 1,
            fissures_at: 0,
            shares_at: 0,
        }
    }
}

/// A planar polygon segment (P§2.2): a perimeter on the plane of best fit, running
/// anticlockwise about the outward normal and never crossing itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    pub(crate) initial: bool,
    pub(crate) centroid: Point3,
    pub(crate) normal: UnitVector3,
    pub(crate) initial_plane: Plane,
    pub(crate) nodes: Vec<Node>,
    pub(crate) rev: Revisions,
}

impl Polygon {
    /// `true` for an initial (a priori) segment (P§4.3): it represents no points
    /// and never merges.
    pub fn is_initial(&self) -> bool {
        self.initial
    }

    /// A point of the plane: the centroid of the represented points (for an initial
    /// segment, the mean of its vertices).
    pub fn centroid(&self) -> Point3 {
        self.centroid
    }

    /// The outward facing unit normal.
    pub fn normal(&self) -> UnitVector3 {
        self.normal
    }

    /// The plane, oriented by the outward normal.
    pub fn plane(&self) -> Plane {
        Plane::from_point_normal(&self.centroid, self.normal)
    }

    /// The initial plane (P§2.4.1–2.4.2), oriented by the outward normal.
    pub fn initial_plane(&self) -> Plane {
        self.initial_plane
    }

    /// 2-D coordinates on the plane (anticlockwise in 2-D = about the normal).
    pub fn frame(&self) -> PlaneFrame {
        PlaneFrame::new(self.centroid, self.normal)
    }

    /// Number of vertices (= number of edges).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// `true` when the perimeter has no vertex (never for a model polygon).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The perimeter nodes in anticlockwise order.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The vertices in anticlockwise order.
    pub fn vertices(&self) -> impl Iterator<Item = Point3> + '_ {
        self.nodes.iter().map(|n| n.position)
    }

    /// Vertex `i` (modulo the vertex count), or `None` for an empty perimeter.
    pub fn vertex(&self, i: usize) -> Option<Point3> {
        let n = self.nodes.len();
        (n > 0).then(|| self.nodes[i % n].position)
    }

    /// Edge `i` as its two end points (start, end), modulo the edge count.
    pub fn edge_points(&self, i: usize) -> Option<(Point3, Point3)> {
        let n = self.nodes.len();
        (n > 0).then(|| (self.nodes[i % n].position, self.nodes[(i + 1) % n].position))
    }

    /// The record of edge `i` (modulo the edge count).
    pub fn edge(&self, i: usize) -> Option<&Edge> {
        let n = self.nodes.len();
        (n > 0).then(|| &self.nodes[i % n].edge)
    }

    /// Index of the edge with key `key`.
    pub fn edge_index(&self, key: EdgeKey) -> Option<usize> {
        self.nodes.iter().position(|n| n.edge.key == key)
    }

    /// The neighbours: segments this polygon shares at least one edge with.
    pub fn neighbours(&self) -> BTreeSet<SegmentId> {
        self.nodes
            .iter()
            .filter_map(|n| n.edge.share.map(|s| s.neighbour))
            .collect()
    }

    /// Number of shared edges.
    pub fn shared_edge_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.edge.share.is_some()).count()
    }

    /// Number of corner vertices.
    pub fn corner_count(&self) -> usize {
        self.nodes.iter().filter(|n| n.corner.is_some()).count()
    }

    /// The area enclosed by the perimeter.
    pub fn area(&self) -> Real {
        polygon2::signed_area(&self.points_2d(&self.frame()))
    }

    /// Vertices in the 2-D coordinates of `frame` (orthogonal projection).
    pub fn points_2d(&self, frame: &PlaneFrame) -> Vec<Point2> {
        self.nodes
            .iter()
            .map(|n| frame.to_2d(&n.position))
            .collect()
    }

    /// Distance from `p` to the polygon (the region bounded by the perimeter).
    pub fn distance_to_point(&self, p: &Point3) -> Real {
        let frame = self.frame();
        let q = frame.to_2d(p);
        let h = frame.height(p);
        let pts = self.points_2d(&frame);
        if polygon2::contains_point(&pts, &q, 0.0) {
            return h.abs();
        }
        let n = pts.len();
        let d2 = (0..n)
            .map(|i| polygon2::distance_point_segment(&q, &pts[i], &pts[(i + 1) % n]))
            .fold(Real::INFINITY, Real::min);
        d2.hypot(h)
    }
}

/// What a segment is: a point or a planar polygon.
#[derive(Clone, Debug, PartialEq)]
pub enum SegmentKind {
    /// A point segment.
    Point(PointSegment),
    /// A planar polygon segment.
    Polygon(Polygon),
}

/// A model segment (P§2.2): the moment sums of the sensor points it represents
/// (the "model segment data") and its description.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    pub(crate) id: SegmentId,
    pub(crate) moments: Moments,
    pub(crate) kind: SegmentKind,
}

impl Segment {
    /// Its id.
    pub fn id(&self) -> SegmentId {
        self.id
    }

    /// The moment sums `m, Σx … Σz²` (P§2.2).
    pub fn moments(&self) -> &Moments {
        &self.moments
    }

    /// Number of sensor points represented, `m`.
    pub fn points(&self) -> u64 {
        self.moments.m
    }

    /// The description.
    pub fn kind(&self) -> &SegmentKind {
        &self.kind
    }

    /// `true` for an initial segment (P§4.3).
    pub fn is_initial(&self) -> bool {
        matches!(&self.kind, SegmentKind::Polygon(p) if p.initial)
    }

    /// The point of best fit (point segments) or the plane's point (polygons).
    pub fn centroid(&self) -> Point3 {
        match &self.kind {
            SegmentKind::Point(p) => p.centroid,
            SegmentKind::Polygon(p) => p.centroid,
        }
    }

    /// The polygon, for planar polygon segments.
    pub fn as_polygon(&self) -> Option<&Polygon> {
        match &self.kind {
            SegmentKind::Polygon(p) => Some(p),
            SegmentKind::Point(_) => None,
        }
    }

    /// The point, for point segments.
    pub fn as_point(&self) -> Option<&PointSegment> {
        match &self.kind {
            SegmentKind::Point(p) => Some(p),
            SegmentKind::Polygon(_) => None,
        }
    }

    pub(crate) fn as_polygon_mut(&mut self) -> Option<&mut Polygon> {
        match &mut self.kind {
            SegmentKind::Polygon(p) => Some(p),
            SegmentKind::Point(_) => None,
        }
    }

    /// Axis-aligned bounds of the description.
    pub fn bounds(&self) -> geom::Aabb {
        match &self.kind {
            SegmentKind::Point(p) => geom::Aabb::new(p.centroid, p.centroid),
            SegmentKind::Polygon(p) => geom::Aabb::from_points(p.nodes.iter().map(|n| &n.position)),
        }
    }
}
