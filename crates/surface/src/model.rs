//! The model: an arena of segments keyed by [`SegmentId`], the spatial index,
//! id counters, and a copy-on-write journal that makes every operation atomic.
//!
//! Every operation of P§2.4–2.9 runs as a transaction: the first mutable access
//! to a segment saves its old version; at the end the touched segments are
//! validated against the invariants and the operation is committed, or rolled
//! back so that the model is exactly as before (the attempted merger "fails",
//! the shared edges are "not formed", ...). This is what keeps the model valid on
//! real, noisy data without special-casing every degenerate configuration.

use crate::changelog::ChangeLog;
use crate::config::{SurfaceConfig, Tolerances};
use crate::error::SurfaceError;
use crate::index::Grid;
use crate::segment::{
    CornerId, Edge, EdgeKey, Node, PairId, Polygon, Segment, SegmentId, SegmentKind,
};
use geom::plane::{corner_of_planes, line_of_planes};
use geom::polygon3::newell_normal;
use geom::{Line3, Moments, Plane, PlaneFrame, Point3, Real, Vector3, polygon2, unit};
use std::collections::{BTreeMap, BTreeSet};

/// Id counters; ids are never reused.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Counters {
    pub segment: u32,
    pub edge: u32,
    pub pair: u32,
    pub corner: u32,
}

/// Saved state of one transaction.
#[derive(Clone, Debug, Default)]
pub(crate) struct Journal {
    /// Old versions (`None`: the segment did not exist).
    pub saved: BTreeMap<SegmentId, Option<Segment>>,
    pub mergers_len: usize,
    pub deleted_len: usize,
    pub points_deleted: u64,
    /// Membership of `ctx.modified` / `ctx.pending` before the transaction
    /// first changed it, per segment (an undo log: cloning the sets at every
    /// `begin` made one update quadratic in the size of its sensor set).
    pub flags_before: BTreeMap<(Flag, SegmentId), bool>,
    /// Shared edges re-pointed at a merger result: (segment, pair, old neighbour).
    pub relinks: Vec<(SegmentId, PairId, SegmentId)>,
    /// What validation checks at the end of the transaction.
    pub scope: Scope,
}

/// The two per-update marks a segment can carry, kept in [`UpdateCtx`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Flag {
    /// [`UpdateCtx::modified`].
    Modified,
    /// [`UpdateCtx::pending`].
    Pending,
}

/// Bookkeeping of the update in progress.
#[derive(Clone, Debug, Default)]
pub(crate) struct UpdateCtx {
    /// First segment id created by this update.
    pub first_new: u32,
    /// Edge keys of pre-existing segments as they were before the update.
    pub orig_keys: BTreeMap<SegmentId, Vec<EdgeKey>>,
    /// The change log being built.
    pub log: ChangeLog,
    /// Segments marked modified (P§2.3).
    pub modified: BTreeSet<SegmentId>,
    /// Merger results whose shared edges await repositioning (P§2.3 step 2b);
    /// shared-edge geometry involving them is not validated until then.
    pub pending: BTreeSet<SegmentId>,
    /// Pairs for which no further shared edges are attempted in this update
    /// (P§2.6: ordering failure; P§2.6.1: undecided concavity).
    pub blocked: BTreeSet<(SegmentId, SegmentId)>,
}

/// Pudney's incremental surface model (P ch. 2). See the [crate docs](crate).
#[derive(Clone, Debug)]
pub struct SurfaceModel {
    pub(crate) config: SurfaceConfig,
    pub(crate) tol: Tolerances,
    pub(crate) segments: BTreeMap<SegmentId, Segment>,
    pub(crate) grid: Grid,
    pub(crate) ids: Counters,
    pub(crate) points_fed: u64,
    pub(crate) points_deleted: u64,
    pub(crate) updates: u64,
    pub(crate) journal: Option<Journal>,
    pub(crate) ctx: UpdateCtx,
    /// The segments the last update deleted as redundant (P§2.9), as they
    /// were when deleted.
    pub(crate) last_deleted: Vec<Segment>,
}

impl SurfaceModel {
    /// An empty model.
    pub fn new(config: SurfaceConfig) -> Result<Self, SurfaceError> {
        config.validate()?;
        let tol = Tolerances::new(&config);
        Ok(Self {
            config,
            tol,
            segments: BTreeMap::new(),
            grid: Grid::new(2.0 * config.lambda),
            ids: Counters::default(),
            points_fed: 0,
            points_deleted: 0,
            updates: 0,
            journal: None,
            ctx: UpdateCtx::default(),
            last_deleted: Vec::new(),
        })
    }

    /// The segments the last [`update`](Self::update) deleted as redundant
    /// (P§2.9), as they were when deleted, in the order of
    /// [`ChangeLog::deleted`]. Their points are no longer represented in the
    /// model, but the surface they stood for is still there: a surface
    /// follower's safety guard keeps them.
    pub fn deleted_by_last_update(&self) -> &[Segment] {
        &self.last_deleted
    }

    /// The parameters.
    pub fn config(&self) -> &SurfaceConfig {
        &self.config
    }

    /// All segments in id order.
    pub fn segments(&self) -> impl Iterator<Item = &Segment> {
        self.segments.values()
    }

    /// The segment with id `id`, if it exists.
    pub fn segment(&self, id: SegmentId) -> Option<&Segment> {
        self.segments.get(&id)
    }

    /// The polygon of segment `id`, if it is a planar polygon segment.
    pub fn polygon(&self, id: SegmentId) -> Option<&Polygon> {
        self.segments.get(&id).and_then(Segment::as_polygon)
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// `true` when the model has no segment.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Number of updates performed.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// Sensor points fed so far.
    pub fn points_fed(&self) -> u64 {
        self.points_fed
    }

    /// Sensor points no longer represented because their segment was deleted as
    /// redundant (P§2.9).
    pub fn points_deleted(&self) -> u64 {
        self.points_deleted
    }

    /// The segment and index of the edge with key `key` (see [`EdgeKey`]).
    pub fn locate_edge(&self, key: EdgeKey) -> Option<(SegmentId, usize)> {
        self.segments.values().find_map(|s| {
            s.as_polygon()
                .and_then(|p| p.edge_index(key))
                .map(|i| (s.id, i))
        })
    }

    /// Segments whose bounding boxes come within `distance` of `p` (a spatial
    /// index query; callers refine with exact distances).
    pub fn segments_near(&self, p: &Point3, distance: Real) -> Vec<SegmentId> {
        self.grid
            .query(&geom::Aabb::new(*p, *p).loosened(distance.max(0.0)))
    }

    /// Surfaces (P§2.2): the connected components of the neighbour relation, each
    /// sorted by id, listed by their smallest id. Every segment is in exactly one
    /// surface; a segment without neighbours (every point segment) is a surface on
    /// its own.
    pub fn surfaces(&self) -> Vec<Vec<SegmentId>> {
        let mut seen = BTreeSet::new();
        let mut out = Vec::new();
        for &id in self.segments.keys() {
            if !seen.insert(id) {
                continue;
            }
            let mut comp = vec![id];
            let mut stack = vec![id];
            while let Some(s) = stack.pop() {
                if let Some(p) = self.polygon(s) {
                    for n in p.neighbours() {
                        if self.segments.contains_key(&n) && seen.insert(n) {
                            comp.push(n);
                            stack.push(n);
                        }
                    }
                }
            }
            comp.sort_unstable();
            out.push(comp);
        }
        out
    }

    /// Add an initial (a priori) segment (P§4.3): a planar polygon that
    /// represents no points, never merges and is never marked modified, but with
    /// which shared edges and corner vertices can be formed. `vertices` run
    /// anticlockwise about the outward normal and must be coplanar (within
    /// `λ·10⁻⁵`), simple and of non-zero area.
    ///
    /// It must not overlap an initial segment already in the model on the same
    /// surface: facing the same way (normals within μ/2), the two planes within
    /// λ of each other at the centroid of the common part, and that part of more
    /// than `λ²·10⁻⁴` in area ([`SurfaceError::InitialOverlap`]). Polygons
    /// that overlap so represent one surface twice; ordinary segments would be
    /// merged (P§2.4.3), initial ones never are, so the model would keep both.
    /// Initial segments may touch along edges (a table in tiles), face each
    /// other (both sides of a sheet) or lie apart (parallel shelves).
    pub fn add_initial_segment(&mut self, vertices: &[Point3]) -> Result<SegmentId, SurfaceError> {
        let bad = |message: String| Err(SurfaceError::InitialSegment { message });
        if vertices.len() < 3 {
            return bad(format!("{} vertices (at least 3 needed)", vertices.len()));
        }
        if let Some(i) = vertices
            .iter()
            .position(|p| !geom::math::is_finite_point(p))
        {
            return bad(format!("vertex {i} is not finite"));
        }
        let Some(normal) = unit(newell_normal(vertices)) else {
            return bad("the vertices enclose no area".into());
        };
        let centroid = Point3::from(
            vertices.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / vertices.len() as Real,
        );
        let frame = PlaneFrame::new(centroid, normal);
        let scale = vertices
            .iter()
            .map(|p| (p - centroid).norm())
            .fold(0.0, Real::max);
        let plane_tol = self.tol.place.max(scale * 1e-9);
        if let Some((i, h)) = vertices
            .iter()
            .map(|p| frame.height(p))
            .enumerate()
            .find(|(_, h)| h.abs() > plane_tol)
        {
            return bad(format!(
                "vertex {i} is {h:.3e} m off the plane of the others"
            ));
        }
        let pts: Vec<_> = vertices.iter().map(|p| frame.to_2d(p)).collect();
        if !polygon2::is_simple(&pts, self.tol.eps) || polygon2::signed_area(&pts) <= 0.0 {
            return bad("the perimeter crosses itself or has edges shorter than λ·10⁻⁴".into());
        }
        if let Some((other, area_m2)) = self.overlapped_initial(vertices, &frame, &pts) {
            return Err(SurfaceError::InitialOverlap { other, area_m2 });
        }
        self.check_id_space()?;
        let id = self.new_segment_id();
        let nodes = pts
            .iter()
            .map(|q| Node {
                position: frame.to_3d(q),
                corner: None,
                edge: Edge {
                    key: self.fresh_key(),
                    share: None,
                },
            })
            .collect();
        let poly = Polygon {
            initial: true,
            centroid,
            normal,
            initial_plane: Plane::from_point_normal(&centroid, normal),
            nodes,
            rev: crate::segment::Revisions::fresh(),
        };
        let seg = Segment {
            id,
            moments: Moments::default(),
            kind: SegmentKind::Polygon(poly),
        };
        self.grid.insert(id, seg.bounds());
        self.segments.insert(id, seg);
        Ok(id)
    }

    /// The first initial segment (by id) that a new initial polygon overlaps
    /// on the same surface (see [`Self::add_initial_segment`]), with the
    /// common area: `vertices`, and `pts` the same in 2-D in `frame`
    /// (anticlockwise).
    fn overlapped_initial(
        &self,
        vertices: &[Point3],
        frame: &PlaneFrame,
        pts: &[geom::Point2],
    ) -> Option<(SegmentId, Real)> {
        let lambda = self.tol.lambda;
        let cos_half_mu = (1.0 - self.tol.sin_parallel * self.tol.sin_parallel).sqrt();
        let bounds = geom::Aabb::from_points(vertices).loosened(lambda);
        let mut near = self.grid.query(&bounds);
        near.sort_unstable();
        near.into_iter().find_map(|id| {
            let other = self.polygon(id).filter(|p| p.is_initial())?;
            if other.normal().dot(&frame.normal.into_inner()) <= cos_half_mu {
                return None;
            }
            // Projected along the new plane's normal: the other polygon stays
            // simple and anticlockwise (the normals are within μ/2).
            let theirs: Vec<geom::Point2> = other.vertices().map(|v| frame.to_2d(&v)).collect();
            let common = polygon2::overlap(pts, &theirs, self.tol.eps);
            let centroid = frame.to_3d(&common.centroid?);
            let apart = (centroid - other.centroid())
                .dot(&other.normal().into_inner())
                .abs();
            (common.area > lambda * lambda * 1e-4 && apart <= lambda).then_some((id, common.area))
        })
    }

    // ----- ids -------------------------------------------------------------

    pub(crate) fn check_id_space(&self) -> Result<(), SurfaceError> {
        const HEADROOM: u32 = 1 << 24;
        let c = self.ids;
        if [c.segment, c.edge, c.pair, c.corner]
            .iter()
            .any(|&v| v > u32::MAX - HEADROOM)
        {
            return Err(SurfaceError::Capacity);
        }
        Ok(())
    }

    pub(crate) fn new_segment_id(&mut self) -> SegmentId {
        self.ids.segment += 1;
        SegmentId(self.ids.segment)
    }

    pub(crate) fn fresh_key(&mut self) -> EdgeKey {
        self.ids.edge += 1;
        EdgeKey(self.ids.edge)
    }

    pub(crate) fn new_pair(&mut self) -> PairId {
        self.ids.pair += 1;
        PairId(self.ids.pair)
    }

    pub(crate) fn new_corner(&mut self) -> CornerId {
        self.ids.corner += 1;
        CornerId(self.ids.corner)
    }

    /// A key allocator usable while another borrow of `self` is live.
    pub(crate) fn key_source(counter: &mut u32) -> impl FnMut() -> EdgeKey + '_ {
        move || {
            *counter += 1;
            EdgeKey(*counter)
        }
    }

    // ----- journaled access ------------------------------------------------

    fn save(&mut self, id: SegmentId) {
        if let Some(j) = self.journal.as_mut()
            && !j.saved.contains_key(&id)
        {
            j.saved.insert(id, self.segments.get(&id).cloned());
        }
        if id.0 < self.ctx.first_new
            && !self.ctx.orig_keys.contains_key(&id)
            && let Some(p) = self.segments.get(&id).and_then(Segment::as_polygon)
        {
            let keys = p.nodes.iter().map(|n| n.edge.key).collect();
            self.ctx.orig_keys.insert(id, keys);
        }
    }

    pub(crate) fn get(&self, id: SegmentId) -> Option<&Segment> {
        self.segments.get(&id)
    }

    pub(crate) fn poly(&self, id: SegmentId) -> Option<&Polygon> {
        self.segments.get(&id).and_then(Segment::as_polygon)
    }

    pub(crate) fn poly_mut(&mut self, id: SegmentId) -> Option<&mut Polygon> {
        self.save(id);
        let p = self
            .segments
            .get_mut(&id)
            .and_then(Segment::as_polygon_mut)?;
        p.rev.shape += 1;
        Some(p)
    }

    /// [`Self::poly_mut`] for moving vertices along their lines (repositioning,
    /// P§2.4.4), which does not change the perimeter's revision.
    pub(crate) fn poly_mut_moving(&mut self, id: SegmentId) -> Option<&mut Polygon> {
        self.save(id);
        self.segments.get_mut(&id).and_then(Segment::as_polygon_mut)
    }

    /// Bookkeeping access to a polygon's revisions (not journaled: a stale
    /// revision only makes a step run again).
    pub(crate) fn revisions_mut(
        &mut self,
        id: SegmentId,
    ) -> Option<&mut crate::segment::Revisions> {
        self.segments
            .get_mut(&id)
            .and_then(Segment::as_polygon_mut)
            .map(|p| &mut p.rev)
    }

    /// Re-point the shared edge of `id` in `pair` at `neighbour` (a merger
    /// result replacing the old neighbour). Journaled as an undo record rather
    /// than a copy of the segment; the pair is validated from the merger
    /// result's side.
    pub(crate) fn relink(&mut self, id: SegmentId, pair: PairId, neighbour: SegmentId) {
        let Some(j) = self.pair_edge(id, pair) else {
            return;
        };
        let Some(share) = self
            .segments
            .get_mut(&id)
            .and_then(Segment::as_polygon_mut)
            .and_then(|p| p.nodes.get_mut(j))
            .and_then(|n| n.edge.share.as_mut())
        else {
            return;
        };
        let old = share.neighbour;
        share.neighbour = neighbour;
        if let Some(journal) = self.journal.as_mut() {
            journal.relinks.push((id, pair, old));
        }
    }

    pub(crate) fn insert_segment(&mut self, seg: Segment) {
        let id = seg.id;
        self.save(id);
        if self.journal.is_none() {
            self.grid.insert(id, seg.bounds());
        }
        self.segments.insert(id, seg);
    }

    pub(crate) fn remove_segment(&mut self, id: SegmentId) -> Option<Segment> {
        self.save(id);
        if self.journal.is_none() {
            self.grid.remove(id);
        }
        self.segments.remove(&id)
    }

    // ----- transactions ----------------------------------------------------

    pub(crate) fn begin(&mut self) {
        debug_assert!(self.journal.is_none(), "transactions do not nest");
        self.journal = Some(Journal {
            saved: BTreeMap::new(),
            mergers_len: self.ctx.log.mergers.len(),
            deleted_len: self.ctx.log.deleted.len(),
            points_deleted: self.points_deleted,
            flags_before: BTreeMap::new(),
            relinks: Vec::new(),
            scope: Scope::Full,
        });
    }

    pub(crate) fn commit(&mut self) {
        if let Some(j) = self.journal.take() {
            // A merger result takes over the grid slot of the merged segment with
            // the larger footprint (see `index`).
            for m in &self.ctx.log.mergers[j.mergers_len..] {
                let [a, b] = m.from;
                let keep = if self.grid.cells_of(a) >= self.grid.cells_of(b) {
                    a
                } else {
                    b
                };
                self.grid.rename(keep, m.into);
            }
            for id in j.saved.keys() {
                match self.segments.get(id) {
                    Some(s) => self.grid.insert(*id, s.bounds()),
                    None => self.grid.remove(*id),
                }
            }
        }
    }

    pub(crate) fn rollback(&mut self) {
        if let Some(j) = self.journal.take() {
            for (id, old) in j.saved {
                match old {
                    Some(seg) => {
                        self.segments.insert(id, seg);
                    }
                    None => {
                        self.segments.remove(&id);
                    }
                }
            }
            for (id, pair, old) in j.relinks.into_iter().rev() {
                if let Some(k) = self.pair_edge(id, pair)
                    && let Some(share) = self
                        .segments
                        .get_mut(&id)
                        .and_then(Segment::as_polygon_mut)
                        .and_then(|p| p.nodes.get_mut(k))
                        .and_then(|n| n.edge.share.as_mut())
                {
                    share.neighbour = old;
                }
            }
            self.ctx.log.mergers.truncate(j.mergers_len);
            self.ctx.log.deleted.truncate(j.deleted_len);
            self.last_deleted.truncate(j.deleted_len);
            self.points_deleted = j.points_deleted;
            for ((flag, id), was_set) in j.flags_before {
                let set = match flag {
                    Flag::Modified => &mut self.ctx.modified,
                    Flag::Pending => &mut self.ctx.pending,
                };
                if was_set {
                    set.insert(id);
                } else {
                    set.remove(&id);
                }
            }
        }
    }

    /// Set or clear `flag` on `id`, journalled so a rollback restores it.
    /// Returns whether the flag was set before.
    pub(crate) fn set_flag(&mut self, flag: Flag, id: SegmentId, on: bool) -> bool {
        let set = match flag {
            Flag::Modified => &mut self.ctx.modified,
            Flag::Pending => &mut self.ctx.pending,
        };
        let was_set = if on { !set.insert(id) } else { set.remove(&id) };
        if was_set != on
            && let Some(j) = self.journal.as_mut()
        {
            j.flags_before.entry((flag, id)).or_insert(was_set);
        }
        was_set
    }

    /// Run `f` as a transaction that always commits (for operations the
    /// procedure performs unconditionally, such as dissolving neighbours before a
    /// merger).
    pub(crate) fn run<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        if self.journal.is_some() {
            return f(self);
        }
        self.begin();
        let out = f(self);
        self.commit();
        out
    }

    /// Ids touched by the open transaction.
    pub(crate) fn touched(&self) -> Vec<SegmentId> {
        self.journal
            .as_ref()
            .map(|j| j.saved.keys().copied().collect())
            .unwrap_or_default()
    }

    /// Run `f` as a transaction: commit when it returns `Some` and the touched
    /// segments pass [`Self::validate_touched`], otherwise roll back.
    pub(crate) fn attempt<T>(&mut self, f: impl FnOnce(&mut Self) -> Option<T>) -> Option<T> {
        if self.journal.is_some() {
            // Already inside a transaction: the outer one validates.
            return f(self);
        }
        self.begin();
        let out = f(self);
        if out.is_some() && self.validate_touched().is_ok() {
            self.commit();
            out
        } else {
            self.rollback();
            None
        }
    }

    /// Validate the touched segments (and the pairs and corners they are part
    /// of), skipping shared-edge geometry of segments awaiting repositioning.
    pub(crate) fn validate_touched(&self) -> Result<(), crate::error::InvariantViolation> {
        let scope = self.journal.as_ref().map(|j| j.scope).unwrap_or_default();
        for id in self.touched() {
            if self.segments.contains_key(&id) {
                self.check_segment_scoped(id, true, scope)?;
            }
        }
        Ok(())
    }

    /// Limit the open transaction's validation (see [`Scope`]).
    pub(crate) fn set_scope(&mut self, scope: Scope) {
        if let Some(j) = self.journal.as_mut() {
            j.scope = scope;
        }
    }

    // ----- geometry of pairs ----------------------------------------------

    /// The intersection line of the planes of `a` and `b`, directed along
    /// `n_a × n_b`; `None` when the planes are within μ/2 of parallel or
    /// antiparallel (see [`Tolerances::sin_parallel`]).
    pub(crate) fn line_between(&self, a: SegmentId, b: SegmentId) -> Option<Line3> {
        let pa = self.poly(a)?;
        let pb = self.poly(b)?;
        line_of_planes(&pa.plane(), &pb.plane(), self.tol.sin_parallel)
    }

    /// The corner point of segment `s` between its neighbours `prev` and `next`:
    /// the intersection of the three planes (P§2.7).
    pub(crate) fn corner_point(
        &self,
        prev: SegmentId,
        s: SegmentId,
        next: SegmentId,
    ) -> Option<Point3> {
        let a = self.poly(prev)?.plane();
        let b = self.poly(s)?.plane();
        let c = self.poly(next)?.plane();
        corner_of_planes(&a, &b, &c, self.tol.sin_corner)
    }

    /// Index of the edge of `seg` that belongs to `pair`.
    pub(crate) fn pair_edge(&self, seg: SegmentId, pair: PairId) -> Option<usize> {
        self.poly(seg)?
            .nodes
            .iter()
            .position(|n| n.edge.share.is_some_and(|s| s.pair == pair))
    }

    /// `true` when `a` and `b` are neighbours.
    pub(crate) fn are_neighbours(&self, a: SegmentId, b: SegmentId) -> bool {
        self.poly(a).is_some_and(|p| {
            p.nodes
                .iter()
                .any(|n| n.edge.share.is_some_and(|s| s.neighbour == b))
        })
    }
}

/// How much of a segment [`SurfaceModel::check_segment`] checks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Scope {
    /// Everything.
    #[default]
    Full,
    /// Moments, plane, perimeter simplicity and orientation only: for operations
    /// that cannot change shared edges, corners or their order (a merger
    /// involving a point segment extends a section without shared edges and
    /// keeps every other record).
    Geometry,
}
