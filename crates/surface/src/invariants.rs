//! The invariant checker (SPEC §3.4). Tests run it after every update; every
//! operation also runs it on the segments it touched before committing.
//!
//! Checked, per segment:
//! * moments: `m ≥ 1` for point and ordinary polygon segments, `m = 0` for
//!   initial segments; the centroid is the moments' centroid;
//! * polygons: at least three vertices, all on the plane (within the placement
//!   tolerance), a simple perimeter (no two non-adjacent edges closer than
//!   `λ·10⁻⁴`, no edge shorter) running anticlockwise about the unit outward
//!   normal; edge keys unique;
//! * shared edges: the neighbour exists and is another polygon; it has exactly one
//!   edge with the same pair id, shared back (corresponding, reciprocal); the
//!   planes are not within μ/2 of parallel; both edges lie on the planes'
//!   intersection line, run in opposite directions, overlap along it, and have the
//!   anticlockwise direction of the pair's one concavity (P§2.2, Fig. 2);
//! * vertices: a corner vertex joins two edges shared with different neighbours,
//!   and its corresponding corner vertices form a closed cycle of distinct
//!   segments with the same corner id (P§2.7); a non-corner vertex never joins
//!   edges shared with two different neighbours (P§2.8);
//! * local ordering and global ordering of shared edges (P§2.2, Fig. 3);
//!
//! and for the whole model: moment totals equal the points fed minus the points
//! of deleted segments, edge keys are unique, and the spatial index holds every
//! segment with its current bounds.

use crate::error::InvariantViolation;
use crate::model::{Scope, SurfaceModel};
use crate::perimeter::{Poly2, valid_points};
use crate::segment::{EdgeKey, PairId, SegmentId, SegmentKind};
use geom::Real;
use geom::plane::line_of_planes;
use std::collections::{BTreeMap, BTreeSet};

/// Longest neighbour cycle around a corner (P§2.7); walks stop here.
pub const MAX_CORNER_CYCLE: usize = 16;

impl SurfaceModel {
    /// Check every invariant of SPEC §3.4 (listed in the [module docs](crate::invariants)).
    pub fn check_invariants(&self) -> Result<(), InvariantViolation> {
        let v = |rule, detail: String| Err(InvariantViolation::new(None, rule, detail));
        if self.journal.is_some() {
            return v("no-open-transaction", "a transaction is still open".into());
        }
        let mut total: u64 = 0;
        let mut keys: BTreeSet<EdgeKey> = BTreeSet::new();
        for (id, seg) in &self.segments {
            if *id != seg.id {
                return v(
                    "arena-id",
                    format!("segment stored under {} has id {}", id.0, seg.id.0),
                );
            }
            self.check_segment(*id, false)?;
            total += seg.moments.m;
            if let Some(p) = seg.as_polygon() {
                for n in &p.nodes {
                    if !keys.insert(n.edge.key) {
                        return v(
                            "unique-edge-keys",
                            format!("edge key {} appears twice", n.edge.key.0),
                        );
                    }
                }
            }
            match self.grid.stored(*id) {
                Some(b) if b == seg.bounds() => {}
                _ => {
                    return v(
                        "spatial-index",
                        format!("segment {} is not indexed with its bounds", id.0),
                    );
                }
            }
        }
        if self.grid.len() != self.segments.len() {
            return v(
                "spatial-index",
                format!(
                    "{} indexed entries for {} segments",
                    self.grid.len(),
                    self.segments.len()
                ),
            );
        }
        if total + self.points_deleted != self.points_fed {
            return v(
                "moment-totals",
                format!(
                    "segments represent {total} points, {} were deleted, {} were fed",
                    self.points_deleted, self.points_fed
                ),
            );
        }
        Ok(())
    }

    /// Check one segment, its shared-edge pairs, corners and orderings. With
    /// `skip_pending`, shared-edge geometry involving a segment that awaits
    /// repositioning is not checked.
    pub(crate) fn check_segment(
        &self,
        id: SegmentId,
        skip_pending: bool,
    ) -> Result<(), InvariantViolation> {
        self.check_segment_scoped(id, skip_pending, Scope::Full)
    }

    /// [`Self::check_segment`] limited to `scope`.
    #[allow(
        clippy::too_many_lines,
        reason = "one checker listing a segment's invariants in the order P§2 states them; each check is a few lines and none is reused"
    )]
    pub(crate) fn check_segment_scoped(
        &self,
        id: SegmentId,
        skip_pending: bool,
        scope: Scope,
    ) -> Result<(), InvariantViolation> {
        let fail = |rule, detail: String| Err(InvariantViolation::new(Some(id), rule, detail));
        let Some(seg) = self.segments.get(&id) else {
            return fail("exists", "no such segment".into());
        };
        let tol = &self.tol;
        let poly = match &seg.kind {
            SegmentKind::Point(p) => {
                if seg.moments.m == 0 {
                    return fail("moments", "a point segment represents no point".into());
                }
                let c = seg.moments.centroid().unwrap_or(p.centroid);
                if (c - p.centroid).norm() > tol.place * (1.0 + c.coords.norm()) {
                    return fail(
                        "centroid",
                        "point is not the centroid of its moments".into(),
                    );
                }
                if !(p.axis_sum.iter().all(|x| x.is_finite()) && p.axis_sum.norm() > 0.0) {
                    return fail("sensing-axis", "no sensing axis".into());
                }
                return Ok(());
            }
            SegmentKind::Polygon(p) => p,
        };
        if poly.initial != (seg.moments.m == 0) {
            return fail(
                "moments",
                format!("initial = {} but m = {}", poly.initial, seg.moments.m),
            );
        }
        if let Some(c) = seg.moments.centroid()
            && (c - poly.centroid).norm() > tol.place * (1.0 + c.coords.norm())
        {
            return fail(
                "centroid",
                "plane point is not the centroid of the moments".into(),
            );
        }
        if (poly.normal.norm() - 1.0).abs() > 1e-9 {
            return fail("unit-normal", format!("|n| = {}", poly.normal.norm()));
        }
        let n = poly.nodes.len();
        if n < 3 {
            return fail("simple-perimeter", format!("{n} vertices"));
        }
        let frame = poly.frame();
        let scale = 1.0 + poly.centroid.coords.norm();
        for (i, node) in poly.nodes.iter().enumerate() {
            if !geom::math::is_finite_point(&node.position) {
                return fail("finite", format!("vertex {i} is not finite"));
            }
            let h = frame.height(&node.position);
            if h.abs() > tol.place * scale {
                return fail(
                    "vertex-on-plane",
                    format!("vertex {i} is {h:.3e} off the plane"),
                );
            }
        }
        // `Poly2::from_polygon(poly, &frame).is_valid(eps)` without building
        // the perimeter (built only for the message).
        if !valid_points(poly.nodes.iter().map(|x| frame.to_2d(&x.position)), tol.eps) {
            let p2 = Poly2::from_polygon(poly, &frame);
            return fail(
                "simple-perimeter",
                format!(
                    "perimeter of {n} vertices is not simple and anticlockwise (area {:.3e})",
                    p2.area()
                ),
            );
        }
        if scope == Scope::Geometry {
            return Ok(());
        }
        // Sorted, a repeated key sits next to its twin (a sorted list costs
        // less than a tree set; every operation runs this check).
        let mut own_keys: Vec<EdgeKey> = poly.nodes.iter().map(|x| x.edge.key).collect();
        own_keys.sort_unstable();
        if own_keys.windows(2).any(|w| w[0] == w[1]) {
            return fail("unique-edge-keys", "an edge key repeats".into());
        }
        // Shared edges.
        let mut concavity: BTreeMap<SegmentId, Real> = BTreeMap::new();
        let mut pairs_seen: BTreeSet<PairId> = BTreeSet::new();
        for i in 0..n {
            let Some(share) = poly.nodes[i].edge.share else {
                continue;
            };
            let nb = share.neighbour;
            if nb == id {
                return fail(
                    "shared-edge",
                    format!("edge {i} is shared with its own segment"),
                );
            }
            if !pairs_seen.insert(share.pair) {
                return fail(
                    "shared-edge",
                    format!("pair {} appears twice", share.pair.0),
                );
            }
            let Some(other) = self.poly(nb) else {
                return fail(
                    "shared-edge",
                    format!("edge {i} is shared with missing/point segment {}", nb.0),
                );
            };
            let matches: Vec<usize> = other
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, x)| x.edge.share.is_some_and(|s| s.pair == share.pair))
                .map(|(j, _)| j)
                .collect();
            let [j] = matches[..] else {
                return fail(
                    "corresponding-edges",
                    format!(
                        "edge {i}: neighbour {} has {} edges of pair {}",
                        nb.0,
                        matches.len(),
                        share.pair.0
                    ),
                );
            };
            if other.nodes[j].edge.share.map(|s| s.neighbour) != Some(id) {
                return fail(
                    "corresponding-edges",
                    format!("edge {i}: the corresponding edge is not shared back"),
                );
            }
            if skip_pending && (self.ctx.pending.contains(&id) || self.ctx.pending.contains(&nb)) {
                continue;
            }
            let Some(line) = line_of_planes(&poly.plane(), &other.plane(), tol.sin_parallel) else {
                return fail(
                    "neighbour-planes",
                    format!("planes of {} and {} are (anti)parallel", id.0, nb.0),
                );
            };
            let (a, b) = (poly.nodes[i].position, poly.nodes[(i + 1) % n].position);
            let m = other.nodes.len();
            let (c, d) = (other.nodes[j].position, other.nodes[(j + 1) % m].position);
            let line_tol = tol.place * (scale + 1.0 + other.centroid.coords.norm());
            for (name, p) in [
                ("start", a),
                ("end", b),
                ("partner start", c),
                ("partner end", d),
            ] {
                let dist = line.distance_to_point(&p);
                if dist > line_tol {
                    return fail(
                        "shared-edge-on-line",
                        format!(
                            "edge {i} ({name}) is {dist:.3e} off the intersection line with {}",
                            nb.0
                        ),
                    );
                }
            }
            let (ta, tb) = (line.project_param(&a), line.project_param(&b));
            let (tc, td) = (line.project_param(&c), line.project_param(&d));
            if tb - ta <= tol.eps && ta - tb <= tol.eps {
                return fail("shared-edge", format!("edge {i} is shorter than λ·10⁻⁴"));
            }
            if (tb - ta).signum() == (td - tc).signum() {
                return fail(
                    "corresponding-edges",
                    format!("edge {i} runs the same way as its corresponding edge"),
                );
            }
            let overlap = ta.max(tb).min(tc.max(td)) - ta.min(tb).max(tc.min(td));
            if overlap < tol.eps {
                return fail(
                    "corresponding-edges",
                    format!("edge {i} and its corresponding edge overlap by {overlap:.3e}"),
                );
            }
            let sign = (tb - ta).signum();
            if let Some(prev) = concavity.insert(nb, sign)
                && prev != sign
            {
                return fail(
                    "one-concavity",
                    format!("edges shared with {} have both concavities", nb.0),
                );
            }
        }
        // Vertices.
        for i in 0..n {
            let node = &poly.nodes[i];
            let sin = poly.nodes[(i + n - 1) % n].edge.share;
            let sout = node.edge.share;
            match node.corner {
                Some(cid) => {
                    let (Some(si), Some(so)) = (sin, sout) else {
                        return fail(
                            "corner-vertex",
                            format!("corner vertex {i} does not join two shared edges"),
                        );
                    };
                    if si.neighbour == so.neighbour {
                        return fail(
                            "corner-vertex",
                            format!("corner vertex {i} joins edges shared with one neighbour"),
                        );
                    }
                    let members = self.corner_cycle(id, i).map_err(|e| {
                        InvariantViolation::new(
                            Some(id),
                            "corner-cycle",
                            format!("vertex {i}: {e}"),
                        )
                    })?;
                    let distinct: BTreeSet<SegmentId> = members.iter().map(|m| m.0).collect();
                    if distinct.len() != members.len() || members.len() < 3 {
                        return fail(
                            "corner-cycle",
                            format!(
                                "vertex {i} (corner {}): cycle of {} is not of ≥3 distinct segments",
                                cid.0,
                                members.len()
                            ),
                        );
                    }
                }
                None => {
                    if let (Some(si), Some(so)) = (sin, sout)
                        && si.neighbour != so.neighbour
                    {
                        return fail(
                            "corner-vertex",
                            format!(
                                "non-corner vertex {i} joins edges shared with {} and {}",
                                si.neighbour.0, so.neighbour.0
                            ),
                        );
                    }
                }
            }
        }
        // Local ordering (P§2.2, Fig. 3a).
        let labels: Vec<(SegmentId, PairId)> = poly
            .nodes
            .iter()
            .filter_map(|x| x.edge.share.map(|s| (s.neighbour, s.pair)))
            .collect();
        let neighbours: BTreeSet<SegmentId> = labels.iter().map(|l| l.0).collect();
        for &nb in &neighbours {
            let mine: Vec<PairId> = labels.iter().filter(|l| l.0 == nb).map(|l| l.1).collect();
            let Some(other) = self.poly(nb) else { continue };
            let mut theirs: Vec<PairId> = other
                .nodes
                .iter()
                .filter_map(|x| x.edge.share.filter(|s| s.neighbour == id).map(|s| s.pair))
                .collect();
            theirs.reverse();
            if !cyclic_equal(&mine, &theirs) {
                return fail(
                    "local-ordering",
                    format!("edges shared with {} are disordered", nb.0),
                );
            }
        }
        // Global ordering (P§2.2, Fig. 3b).
        if let Some((a, b)) =
            global_order_violation(&labels.iter().map(|l| l.0).collect::<Vec<_>>())
        {
            return fail(
                "global-ordering",
                format!("edges shared with {} and {} interleave", a.0, b.0),
            );
        }
        Ok(())
    }

    /// The corner cycle through vertex `vertex` of `start` (P§2.7): walking from
    /// a corner vertex along its outgoing shared edge to the corresponding edge's
    /// end vertex in the neighbour, and so on, must return to the start within
    /// [`MAX_CORNER_CYCLE`] steps with the same corner id at every vertex.
    pub(crate) fn corner_cycle(
        &self,
        start: SegmentId,
        vertex: usize,
    ) -> Result<Vec<(SegmentId, usize)>, String> {
        let cid = self
            .poly(start)
            .and_then(|p| p.nodes.get(vertex))
            .and_then(|x| x.corner)
            .ok_or("not a corner vertex")?;
        let mut members = vec![(start, vertex)];
        let mut cur = (start, vertex);
        for _ in 0..MAX_CORNER_CYCLE {
            let p = self.poly(cur.0).ok_or("missing segment")?;
            let share = p
                .nodes
                .get(cur.1)
                .and_then(|x| x.edge.share)
                .ok_or("corner without outgoing shared edge")?;
            let j = self
                .pair_edge(share.neighbour, share.pair)
                .ok_or("broken pair")?;
            let q = self.poly(share.neighbour).ok_or("missing neighbour")?;
            let v = (j + 1) % q.nodes.len().max(1);
            if (share.neighbour, v) == (start, vertex) {
                return Ok(members);
            }
            if q.nodes.get(v).and_then(|x| x.corner) != Some(cid) {
                return Err(format!(
                    "segment {} has no corresponding corner vertex",
                    share.neighbour.0
                ));
            }
            cur = (share.neighbour, v);
            members.push(cur);
        }
        Err("the cycle does not close".into())
    }
}

/// `true` when `a` is a rotation of `b`.
pub(crate) fn cyclic_equal<T: PartialEq>(a: &[T], b: &[T]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    if a.is_empty() {
        return true;
    }
    (0..b.len()).any(|r| (0..a.len()).all(|i| a[i] == b[(i + r) % b.len()]))
}

/// A pair of neighbour labels whose shared edges interleave (`a … b … a … b`
/// cyclically), if any.
pub(crate) fn global_order_violation(labels: &[SegmentId]) -> Option<(SegmentId, SegmentId)> {
    let distinct: BTreeSet<SegmentId> = labels.iter().copied().collect();
    let distinct: Vec<SegmentId> = distinct.into_iter().collect();
    for (k, &a) in distinct.iter().enumerate() {
        for &b in &distinct[k + 1..] {
            let seq: Vec<SegmentId> = labels
                .iter()
                .copied()
                .filter(|l| *l == a || *l == b)
                .collect();
            let changes = (0..seq.len())
                .filter(|&i| seq[i] != seq[(i + 1) % seq.len()])
                .count();
            if changes > 2 {
                return Some((a, b));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orderings() {
        let s = |i| SegmentId(i);
        assert!(cyclic_equal(&[1, 2, 3], &[3, 1, 2]));
        assert!(!cyclic_equal(&[1, 2, 3], &[3, 2, 1]));
        assert!(global_order_violation(&[s(1), s(1), s(2), s(1)]).is_none());
        assert!(global_order_violation(&[s(1), s(2), s(3), s(2), s(1)]).is_none());
        assert_eq!(
            global_order_violation(&[s(1), s(2), s(1), s(2)]),
            Some((s(1), s(2)))
        );
    }
}
