//! Crate internals for the thesis-figure tests (`tests/figures.rs`).
//!
//! **Not a stable API.** This module exists only so that the focused figure
//! reproductions of P ch. 2 can drive single operations (forming shared edges
//! between two given polygons, one merger, one corner cycle, ...) from an
//! integration test. It is hidden from the documentation, may change or vanish
//! in any release, and nothing outside this crate's tests should use it. The
//! internals it reaches stay `pub(crate)`: [`ModelInternals`] only delegates.
//!
//! The operations run outside an update, so their bookkeeping (the update's
//! modified flags, deleted list, pending repositioning) is exposed through a
//! few small methods instead of the update context itself.

use crate::merge::MergeFailure;
use crate::model::SurfaceModel;
use crate::segment::{
    Edge, EdgeKey, Node, PairId, PointSegment, Polygon, Segment, SegmentId, SegmentKind,
};
use crate::share::Concavity;
use geom::polygon3::newell_normal;
use geom::{Line3, Moments, Pca, Plane, PlaneFrame, Point3, Real, Vector3, unit};

/// What an attempt to form shared edges between two polygons did (a copy of
/// the crate's internal outcome, for the figure tests).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShareOutcome {
    /// Nothing attempted (no non-shared edges near the line, or no line).
    Skipped,
    /// Concavity undecided (P§2.6.1).
    Undecided,
    /// Attempted; `n` pairs of shared edges formed.
    Formed(usize),
}

impl From<crate::share::ShareOutcome> for ShareOutcome {
    fn from(o: crate::share::ShareOutcome) -> Self {
        match o {
            crate::share::ShareOutcome::Skipped => Self::Skipped,
            crate::share::ShareOutcome::Undecided => Self::Undecided,
            crate::share::ShareOutcome::Formed(n) => Self::Formed(n),
        }
    }
}

/// Single operations of the model's update procedure, for the figure tests
/// (see the [module docs](self): not a stable API). Each method delegates to
/// the crate-internal operation of the same name.
pub trait ModelInternals {
    /// Insert an ordinary polygon segment with the given vertices (anticlockwise
    /// about its outward normal), representing `m` points spread over its
    /// vertices.
    fn insert_test_polygon(&mut self, vertices: &[Point3], m: u64) -> SegmentId;
    /// The polygon of `id`.
    fn poly(&self, id: SegmentId) -> Option<&Polygon>;
    /// The segment `id`.
    fn get(&self, id: SegmentId) -> Option<&Segment>;
    /// P§2.6: attempt to form shared edges between `s1` and `s2`.
    fn form_shared_edges(&mut self, s1: SegmentId, s2: SegmentId) -> ShareOutcome;
    /// The intersection line of the planes of `a` and `b` (directed `n_a × n_b`).
    fn line_between(&self, a: SegmentId, b: SegmentId) -> Option<Line3>;
    /// P§2.6.1: the concavity between `s1` and `s2` along `line`.
    fn concavity(&self, s1: SegmentId, s2: SegmentId, line: &Line3) -> Concavity;
    /// `true` when `a` and `b` share an edge.
    fn are_neighbours(&self, a: SegmentId, b: SegmentId) -> bool;
    /// P§2.4: attempt to merge `s1` and `s2`.
    fn try_merge(&mut self, s1: SegmentId, s2: SegmentId) -> Result<SegmentId, MergeFailure>;
    /// P§2.3 step 4 for one polygon (with the redundancy test of P§2.9).
    fn shared_edges_of(&mut self, s1: SegmentId);
    /// P§2.3 step 5 for one polygon; returns the corner cycles formed.
    fn form_corners(&mut self, s: SegmentId) -> usize;
    /// Open a transaction.
    fn begin(&mut self);
    /// Commit the open transaction.
    fn commit(&mut self);
    /// P§2.8: unshare `pair` starting from `s`, as a committed transaction.
    fn unshare_pair_committed(&mut self, s: SegmentId, pair: PairId);
    /// P§2.7: the corner point of `s` between its neighbours `prev` and `next`.
    fn corner_point(&self, prev: SegmentId, s: SegmentId, next: SegmentId) -> Option<Point3>;
    /// The largest distance of a shared-edge vertex of `s` from its line.
    fn max_line_offset(&self, s: SegmentId) -> Real;
    /// P§2.6.1: the (convex, concave) overlap registers of `s1` and `s2`.
    fn registers_between(&self, s1: SegmentId, s2: SegmentId) -> Option<(Real, Real)>;
    /// Treat every segment as pre-existing (no segment counts as created by the
    /// update in progress).
    fn treat_all_as_old(&mut self);
    /// Mark `id` modified (P§2.3).
    fn mark_modified(&mut self, id: SegmentId);
    /// Segments deleted since the last update began.
    fn deleted_in_update(&self) -> &[SegmentId];
    /// Forget pending repositioning (P§2.3 step 2b).
    fn clear_pending(&mut self);
    /// Keep only the perimeter nodes of `id` for which `keep` holds (a direct
    /// edit; the caller keeps the perimeter valid).
    fn retain_nodes(&mut self, id: SegmentId, keep: &mut dyn FnMut(&Node) -> bool);
}

impl ModelInternals for SurfaceModel {
    fn insert_test_polygon(&mut self, vertices: &[Point3], m: u64) -> SegmentId {
        let normal = unit(newell_normal(vertices)).unwrap_or_else(Vector3::z_axis);
        let count = vertices.len().max(1);
        let mut moments = Moments::default();
        // Exactly m points, cycling over the vertices.
        for k in 0..m {
            if let Some(v) = vertices.get(usize::try_from(k).unwrap_or(0) % count) {
                moments.add(v);
            }
        }
        let centroid = moments
            .centroid()
            .or_else(|| vertices.first().copied())
            .unwrap_or_else(Point3::origin);
        let frame = PlaneFrame::new(centroid, normal);
        let id = self.new_segment_id();
        let nodes = vertices
            .iter()
            .map(|p| Node {
                position: frame.to_3d(&frame.to_2d(p)),
                corner: None,
                edge: Edge {
                    key: self.fresh_key(),
                    share: None,
                },
            })
            .collect();
        let seg = Segment {
            id,
            moments,
            kind: SegmentKind::Polygon(Polygon {
                initial: false,
                centroid,
                normal,
                initial_plane: Plane::from_point_normal(&centroid, normal),
                nodes,
                rev: crate::segment::Revisions::fresh(),
            }),
        };
        self.points_fed += moments.m;
        self.grid.insert(id, seg.bounds());
        self.segments.insert(id, seg);
        id
    }

    fn poly(&self, id: SegmentId) -> Option<&Polygon> {
        SurfaceModel::poly(self, id)
    }

    fn get(&self, id: SegmentId) -> Option<&Segment> {
        SurfaceModel::get(self, id)
    }

    fn form_shared_edges(&mut self, s1: SegmentId, s2: SegmentId) -> ShareOutcome {
        SurfaceModel::form_shared_edges(self, s1, s2).into()
    }

    fn line_between(&self, a: SegmentId, b: SegmentId) -> Option<Line3> {
        SurfaceModel::line_between(self, a, b)
    }

    fn concavity(&self, s1: SegmentId, s2: SegmentId, line: &Line3) -> Concavity {
        SurfaceModel::concavity(self, s1, s2, line)
    }

    fn are_neighbours(&self, a: SegmentId, b: SegmentId) -> bool {
        SurfaceModel::are_neighbours(self, a, b)
    }

    fn try_merge(&mut self, s1: SegmentId, s2: SegmentId) -> Result<SegmentId, MergeFailure> {
        SurfaceModel::try_merge(self, s1, s2)
    }

    fn shared_edges_of(&mut self, s1: SegmentId) {
        SurfaceModel::shared_edges_of(self, s1);
    }

    fn form_corners(&mut self, s: SegmentId) -> usize {
        SurfaceModel::form_corners(self, s)
    }

    fn begin(&mut self) {
        SurfaceModel::begin(self);
    }

    fn commit(&mut self) {
        SurfaceModel::commit(self);
    }

    fn unshare_pair_committed(&mut self, s: SegmentId, pair: PairId) {
        self.run(|m| m.unshare_pair(s, pair));
    }

    fn corner_point(&self, prev: SegmentId, s: SegmentId, next: SegmentId) -> Option<Point3> {
        SurfaceModel::corner_point(self, prev, s, next)
    }

    fn max_line_offset(&self, s: SegmentId) -> Real {
        crate::reposition::max_line_offset(self, s)
    }

    fn registers_between(&self, s1: SegmentId, s2: SegmentId) -> Option<(Real, Real)> {
        crate::share::registers_between(self, s1, s2)
    }

    fn treat_all_as_old(&mut self) {
        self.ctx.first_new = u32::MAX;
    }

    fn mark_modified(&mut self, id: SegmentId) {
        self.ctx.modified.insert(id);
    }

    fn deleted_in_update(&self) -> &[SegmentId] {
        &self.ctx.log.deleted
    }

    fn clear_pending(&mut self) {
        self.ctx.pending.clear();
    }

    fn retain_nodes(&mut self, id: SegmentId, keep: &mut dyn FnMut(&Node) -> bool) {
        if let Some(g) = self.poly_mut(id) {
            g.nodes.retain(|n| keep(n));
        }
    }
}

/// P§2.4.2 on its own: merge a point segment (`centroid`, summed sensing axes
/// `axis_sum`) into polygon `g`, where `pca` is the decomposition of the merged
/// moments of `points` points; `fresh` allocates edge keys. Returns the new polygon and whether its
/// perimeter is known to be simple.
pub fn merge_point_polygon(
    model: &SurfaceModel,
    centroid: Point3,
    axis_sum: Vector3,
    g: &Polygon,
    pca: &Pca,
    points: u64,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Result<(Polygon, bool), MergeFailure> {
    let p = PointSegment { centroid, axis_sum };
    crate::merge::merge_point_polygon(&model.tol, &p, g, pca, points, fresh)
}
