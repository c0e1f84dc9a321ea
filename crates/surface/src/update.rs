//! The update procedure of P§2.3, in its order:
//!
//! 1. a point segment is created for each sensor point and marked modified;
//! 2. MERGERS — (a) for each modified segment S₁, in id order, and each segment
//!    S₂ near it: if either is a point segment and their descriptions are closer
//!    than λ, or both are polygons whose normals differ by less than μ and which
//!    are neighbours or closer than λ, a merger is attempted; on success S₁
//!    becomes the result (marked modified) and the scan continues with it;
//!    (b) the shared edges of every merger result are repositioned (P§2.4.4);
//! 3. FISSURES — fissures of every modified polygon are filled (P§2.5), and
//!    vertices lying on the straight edge between their neighbours are removed;
//! 4. SHARED EDGES — for each modified polygon S₁ and each polygon S₂ near it
//!    whose normal differs by more than μ, shared edges are attempted when both
//!    have non-shared edges within λ of the planes' intersection line (P§2.6); if
//!    they were not neighbours and none formed, or the concavity is undecided,
//!    the smaller may be deleted as redundant (P§2.9);
//! 5. CORNER VERTICES — corner vertices are attempted between the shared edges of
//!    every modified polygon (P§2.7);
//! 6. the modified flags are cleared.
//!
//! "Near" is a spatial-index query: the segment's bounding box loosened by λ.
//! Initial segments (P§4.3) never merge and are never modified.
//!
//! Termination: in step 2(a) every success removes a segment, and every failure
//! consumes a (S₁, S₂) pair of the current S₁, so the scan is finite; steps 2(b)–5
//! visit each modified segment once with bounded inner loops (documented where
//! they are).

use crate::changelog::ChangeLog;
use crate::config::MergeOrder;
use crate::error::SurfaceError;
use crate::fissure::{
    FissureMode, close_pockets, fill_fissures, remove_collinear, remove_nearly_collinear,
};
use crate::input::SensorSet;
use crate::merge::polygon_distance;
use crate::model::{SurfaceModel, UpdateCtx};
use crate::perimeter::Poly2;
use crate::segment::{EdgeKey, PointSegment, Segment, SegmentId, SegmentKind};
use crate::share::ShareOutcome;
use geom::Moments;
use std::collections::BTreeSet;

/// The rank of merger candidates tried in id order, after every ranked one
/// (above the bits of every finite distance).
const BY_ID: u64 = u64::MAX;

impl SurfaceModel {
    /// Update the model with one set of sensor points (P§2.3). Bad input (non-finite
    /// coordinates, a length mismatch, a non-unit axis, more points than
    /// [`SurfaceConfig::max_set_points`](crate::SurfaceConfig::max_set_points))
    /// is refused with an error and leaves the model unchanged.
    pub fn update(&mut self, set: &SensorSet) -> Result<ChangeLog, SurfaceError> {
        if set.len() > self.config.max_set_points {
            return Err(SurfaceError::SetTooLarge {
                points: set.len(),
                limit: self.config.max_set_points,
            });
        }
        set.validate()?;
        self.check_id_space()?;
        self.ctx = UpdateCtx {
            first_new: self.ids.segment + 1,
            ..UpdateCtx::default()
        };
        self.last_deleted.clear();
        // 1. A point segment per sensor point.
        let mut new_ids = Vec::with_capacity(set.len());
        for (p, a) in set.points.iter().zip(&set.axes) {
            let id = self.new_segment_id();
            self.insert_segment(Segment {
                id,
                moments: Moments::from_point(p),
                kind: SegmentKind::Point(PointSegment {
                    centroid: *p,
                    axis_sum: a.into_inner(),
                }),
            });
            self.ctx.modified.insert(id);
            new_ids.push(id);
        }
        self.points_fed += set.len() as u64;
        // 2(a). Mergers.
        for start in new_ids {
            self.merge_chain(start);
        }
        // 2(b). Reposition the shared edges of merger results.
        let pending: Vec<SegmentId> = self.ctx.pending.iter().copied().collect();
        for s in pending {
            if self.segments.contains_key(&s) {
                self.reposition(s);
            } else {
                self.ctx.pending.remove(&s);
            }
        }
        self.ctx.pending.clear();
        // 3. Fissures.
        for s in self.modified_polygons() {
            self.fill_fissures_of(s);
        }
        // 4. Shared edges.
        for s in self.modified_polygons() {
            self.shared_edges_of(s);
        }
        // 5. Corner vertices.
        for s in self.modified_polygons() {
            if self.segments.contains_key(&s) {
                self.form_corners(s);
            }
        }
        // 6. The change log; clear the flags.
        let log = self.finish_log();
        self.ctx = UpdateCtx::default();
        self.updates += 1;
        Ok(log)
    }

    fn modified_polygons(&self) -> Vec<SegmentId> {
        self.ctx
            .modified
            .iter()
            .copied()
            .filter(|id| {
                self.get(*id)
                    .is_some_and(|s| s.as_polygon().is_some() && !s.is_initial())
            })
            .collect()
    }

    /// Step 2(a) for one modified segment and its successors. Candidates are
    /// tried each once per chain, in id order ([`MergeOrder::Thesis`]) or, for
    /// a new point segment, the polygons nearest its plane first
    /// ([`MergeOrder::NearestPlane`], see there); after a success the new S₁
    /// also meets the candidates near the absorbed S₂, which join the queue in
    /// id order.
    fn merge_chain(&mut self, start: SegmentId) {
        if !self.segments.contains_key(&start) {
            return;
        }
        let mut s1 = start;
        let mut queue: BTreeSet<(u64, SegmentId)> = self
            .merge_candidates(s1)
            .into_iter()
            .map(|s2| (self.merge_rank(s1, s2), s2))
            .collect();
        let mut tried: BTreeSet<SegmentId> = BTreeSet::new();
        // Every iteration removes an id from the queue (ids join the queue at most
        // once, through `tried`), so the loop ends.
        while let Some((_, s2)) = queue.pop_first() {
            if !tried.insert(s2) || s2 == s1 || !self.segments.contains_key(&s2) {
                continue;
            }
            if !self.should_attempt_merge(s1, s2) {
                continue;
            }
            let Some(s2_bounds) = self.get(s2).map(Segment::bounds) else {
                continue;
            };
            if let Ok(s3) = self.try_merge(s1, s2) {
                s1 = s3;
                let near_s2 = self.grid.query(&s2_bounds.loosened(self.tol.lambda));
                queue.extend(
                    near_s2
                        .into_iter()
                        .filter(|id| !tried.contains(id) && *id != s3)
                        .map(|id| (BY_ID, id)),
                );
                if let Some(p) = self.poly(s3) {
                    queue.extend(
                        p.neighbours()
                            .into_iter()
                            .filter(|id| !tried.contains(id))
                            .map(|id| (BY_ID, id)),
                    );
                }
            }
        }
    }

    /// Where `s2` stands in `s1`'s first merger queue (smaller first, ties by
    /// id): under [`MergeOrder::NearestPlane`], a polygon's distance from a
    /// point segment `s1` to its plane (the bits of a non-negative float order
    /// as the float does); every other pair, and every pair under
    /// [`MergeOrder::Thesis`], [`BY_ID`].
    fn merge_rank(&self, s1: SegmentId, s2: SegmentId) -> u64 {
        if self.config.merge_order == MergeOrder::Thesis {
            return BY_ID;
        }
        match (self.get(s1).map(|s| &s.kind), self.get(s2).map(|s| &s.kind)) {
            (Some(SegmentKind::Point(p)), Some(SegmentKind::Polygon(g))) => {
                let d = (p.centroid - g.centroid).dot(&g.normal).abs();
                if d.is_finite() { d.to_bits() } else { BY_ID }
            }
            _ => BY_ID,
        }
    }

    /// Segments near `s` (bounding box loosened by λ) and its neighbours.
    fn merge_candidates(&self, s: SegmentId) -> Vec<SegmentId> {
        let Some(seg) = self.get(s) else {
            return Vec::new();
        };
        let mut out = self.grid.query(&seg.bounds().loosened(self.tol.lambda));
        if let Some(p) = seg.as_polygon() {
            out.extend(p.neighbours());
            out.sort_unstable();
            out.dedup();
        }
        out.retain(|id| *id != s && self.segments.contains_key(id));
        out
    }

    /// The attempt conditions of P§2.3 step 2(a).
    fn should_attempt_merge(&self, s1: SegmentId, s2: SegmentId) -> bool {
        let (Some(a), Some(b)) = (self.get(s1), self.get(s2)) else {
            return false;
        };
        if a.is_initial() || b.is_initial() {
            return false;
        }
        let lambda = self.tol.lambda;
        match (&a.kind, &b.kind) {
            (SegmentKind::Point(p), SegmentKind::Point(q)) => {
                (p.centroid - q.centroid).norm() < lambda
            }
            (SegmentKind::Point(p), SegmentKind::Polygon(g))
            | (SegmentKind::Polygon(g), SegmentKind::Point(p)) => {
                g.distance_to_point(&p.centroid) < lambda
            }
            (SegmentKind::Polygon(g), SegmentKind::Polygon(h)) => {
                g.normal.dot(&h.normal) > self.tol.cos_mu
                    && (self.are_neighbours(s1, s2) || polygon_distance(g, h) < lambda)
            }
        }
    }

    /// Step 3 for one polygon.
    pub(crate) fn fill_fissures_of(&mut self, s: SegmentId) -> usize {
        let tol = self.tol;
        // Nothing to fill on a perimeter unchanged since the last pass.
        if self
            .poly(s)
            .is_none_or(|p| p.rev.fissures_at == p.rev.shape)
        {
            return 0;
        }
        let filled = self
            .attempt(|m| {
                let p = m.poly(s)?;
                let frame = p.frame();
                let mut poly = Poly2::from_polygon(p, &frame);
                let (filled, straightened, known_valid) = {
                    let mut fresh = Self::key_source(&mut m.ids.edge);
                    let mut filled = fill_fissures(
                        &mut poly,
                        FissureMode::Restricted,
                        tol.lambda,
                        tol.eps,
                        &mut fresh,
                    )
                    .len();
                    let pockets = close_pockets(&mut poly, tol.lambda, tol.eps, &mut fresh);
                    if pockets > 0 {
                        filled += pockets
                            + fill_fissures(
                                &mut poly,
                                FissureMode::Restricted,
                                tol.lambda,
                                tol.eps,
                                &mut fresh,
                            )
                            .len();
                    }
                    let straightened = remove_collinear(&mut poly, tol.eps, &mut fresh);
                    // Shallow dents (within the collinearity length) are filled
                    // too, unless that leaves an invalid perimeter.
                    let before = poly.clone();
                    let dents =
                        remove_nearly_collinear(&mut poly, tol.collinear, tol.eps, &mut fresh);
                    if dents == 0 {
                        (filled, straightened, false)
                    } else if poly.is_valid(tol.eps) {
                        (filled, straightened + dents, true)
                    } else {
                        poly = before;
                        (filled, straightened, false)
                    }
                };
                if filled + straightened == 0 || !(known_valid || poly.is_valid(tol.eps)) {
                    return None;
                }
                m.poly_mut(s)?.nodes = poly.to_nodes(&frame);
                Some(filled)
            })
            .unwrap_or(0);
        if let Some(rev) = self.revisions_mut(s) {
            rev.fissures_at = rev.shape;
        }
        filled
    }

    /// Step 4 for one modified polygon.
    pub(crate) fn shared_edges_of(&mut self, s1: SegmentId) {
        let Some(seg) = self.get(s1) else { return };
        let Some(p) = seg.as_polygon() else { return };
        let mut candidates = self.grid.query(&seg.bounds().loosened(self.tol.lambda));
        candidates.extend(p.neighbours());
        candidates.sort_unstable();
        candidates.dedup();
        for s2 in candidates {
            if s2 == s1 {
                continue;
            }
            if self.delete_if_stray(s1, s2) {
                if self.segments.contains_key(&s1) {
                    continue;
                }
                return;
            }
            let (Some(a), Some(b)) = (self.poly(s1), self.poly(s2)) else {
                if self.segments.contains_key(&s1) {
                    continue;
                }
                return;
            };
            if a.normal.dot(&b.normal) >= self.tol.cos_mu {
                continue; // angle not greater than μ
            }
            if self.ctx.blocked.contains(&(s1.min(s2), s1.max(s2))) {
                continue;
            }
            // Both perimeters unchanged since their last attempts: the attempt
            // would repeat (only the planes moved, by a merger's re-fit).
            if a.rev.shares_at == a.rev.shape && b.rev.shares_at == b.rev.shape {
                continue;
            }
            let were_neighbours = self.are_neighbours(s1, s2);
            match self.form_shared_edges(s1, s2) {
                ShareOutcome::Skipped | ShareOutcome::Formed(1..) => {}
                ShareOutcome::Undecided => {
                    self.ctx.blocked.insert((s1.min(s2), s1.max(s2)));
                    if !were_neighbours {
                        self.check_redundant(s1, s2);
                    }
                }
                ShareOutcome::Formed(0) => {
                    if !were_neighbours {
                        self.check_redundant(s1, s2);
                    }
                }
            }
            if !self.segments.contains_key(&s1) {
                return;
            }
        }
        if let Some(rev) = self.revisions_mut(s1) {
            rev.shares_at = rev.shape;
        }
    }

    /// P§2.9: delete the smaller of `s1`, `s2` when it represents fewer than ψ
    /// points and fewer than φ times the other's.
    fn check_redundant(&mut self, s1: SegmentId, s2: SegmentId) {
        let (Some(a), Some(b)) = (self.get(s1), self.get(s2)) else {
            return;
        };
        if a.is_initial() || b.is_initial() {
            return;
        }
        let (small, n_small, n_big) = match a.moments.m.cmp(&b.moments.m) {
            std::cmp::Ordering::Less => (s1, a.moments.m, b.moments.m),
            std::cmp::Ordering::Greater => (s2, b.moments.m, a.moments.m),
            std::cmp::Ordering::Equal => return,
        };
        let (n1, n2) = (n_small as f64, n_big as f64);
        if n1 < self.config.psi && n1 / n2 < self.config.phi {
            self.run(|m| m.delete_segment(small));
        }
    }

    /// The smaller of `s1`, `s2` when it is redundant by the counts of P§2.9
    /// (`n₁ < ψ`, `n₁/n₂ < φ`) and, beyond the thesis, lies on the larger one's
    /// surface: every vertex within λ of its plane, its plane crossing that
    /// plane (vertices on both sides), and within λ of its polygon.
    ///
    /// P§2.9 tests for redundancy only after a failed attempt to share edges
    /// between non-neighbours, and the thesis notes (P ch. 5) that redundant
    /// segments escape it "because they have formed shared edges". Under range
    /// noise that is the common case: a few points beside a large face fit a
    /// plane tilted by more than μ (so no merger is attempted, P§2.3), then
    /// share edges with the face, notching it and blocking its shared edges
    /// and corners with its other neighbours. Such a polygon describes nothing
    /// the larger one does not describe to within λ. A genuine new face beside
    /// an edge lies on one side of the larger plane, so it is kept.
    fn stray_of(&self, s1: SegmentId, s2: SegmentId) -> Option<SegmentId> {
        let (a, b) = (self.get(s1)?, self.get(s2)?);
        if a.is_initial() || b.is_initial() {
            return None;
        }
        let (small, big) = match a.moments.m.cmp(&b.moments.m) {
            std::cmp::Ordering::Less => (a, b),
            std::cmp::Ordering::Greater => (b, a),
            std::cmp::Ordering::Equal => return None,
        };
        let (n1, n2) = (small.moments.m as f64, big.moments.m as f64);
        if !(n1 < self.config.psi && n1 / n2 < self.config.phi) {
            return None;
        }
        let (p, q) = (small.as_polygon()?, big.as_polygon()?);
        let plane = q.plane();
        let lambda = self.tol.lambda;
        let (mut below, mut above) = (false, false);
        for v in p.vertices() {
            let h = plane.signed_distance(&v);
            if h.abs() >= lambda {
                return None;
            }
            below |= h < 0.0;
            above |= h > 0.0;
        }
        (below && above && polygon_distance(p, q) < lambda).then_some(small.id)
    }

    /// Delete the stray of `s1`, `s2` (see [`Self::stray_of`]); `true` when
    /// one was deleted.
    fn delete_if_stray(&mut self, s1: SegmentId, s2: SegmentId) -> bool {
        let Some(stray) = self.stray_of(s1, s2) else {
            return false;
        };
        self.run(|m| m.delete_segment(stray));
        true
    }

    fn finish_log(&mut self) -> ChangeLog {
        let mut log = std::mem::take(&mut self.ctx.log);
        let first_new = self.ctx.first_new;
        log.created = self
            .segments
            .range(SegmentId(first_new)..)
            .map(|(id, _)| *id)
            .collect();
        log.modified = self
            .ctx
            .modified
            .iter()
            .copied()
            .filter(|id| self.segments.contains_key(id))
            .collect();
        // The keys still alive, as a sorted list searched by bisection: built
        // once per update from a few hundred keys, it costs a fraction of a
        // tree set's node allocations and pointer chasing.
        let mut alive: Vec<EdgeKey> = Vec::new();
        let keys_of = |seg: Option<&Segment>, alive: &mut Vec<EdgeKey>| {
            if let Some(p) = seg.and_then(Segment::as_polygon) {
                alive.extend(p.nodes.iter().map(|n| n.edge.key));
            }
        };
        for id in self.ctx.orig_keys.keys() {
            keys_of(self.segments.get(id), &mut alive);
        }
        for id in &log.created {
            keys_of(self.segments.get(id), &mut alive);
        }
        alive.sort_unstable();
        for (seg, keys) in &self.ctx.orig_keys {
            for (i, k) in keys.iter().enumerate() {
                if alive.binary_search(k).is_err() {
                    log.changed_edges.push((*seg, i));
                    log.changed_edge_keys.push(*k);
                }
            }
        }
        log
    }
}
