//! Unsharing edges (P§2.8), dissolving neighbour relations, the ordering rules
//! (P§2.2, Fig. 3) and deleting segments (P§2.9).
//!
//! These functions mutate inside the caller's transaction and keep every
//! invariant that does not involve a segment awaiting repositioning:
//!
//! * unsharing converts both corresponding edges to non-shared edges; a corner
//!   vertex at either end becomes a non-corner vertex together with all its
//!   corresponding corner vertices (found by walking the corner cycle both ways);
//! * a former corner vertex that still joins two edges shared with different
//!   neighbours is duplicated (P§2.8): the vertex is moved back along its incoming
//!   shared edge and the duplicate forward along its outgoing one, each by
//!   `δ = min(λ·10⁻², ¼ of either edge)`, joined by a new short non-shared edge. (The
//!   thesis puts the duplicate at the same position — a zero-length edge; we keep
//!   perimeters strictly simple instead. Both copies stay on their intersection
//!   lines.) When the short edge would be shorter than `4·λ·10⁻⁴` or cross the
//!   perimeter, the outgoing edge is unshared instead; the cascade ends because
//!   every step removes a shared edge.

use crate::invariants::{MAX_CORNER_CYCLE, cyclic_equal, global_order_violation};
use crate::model::{Flag, SurfaceModel};
use crate::segment::{CornerId, Edge, Node, PairId, SegmentId};
use geom::PlaneFrame;
use std::collections::BTreeSet;

/// Which pair of neighbour relations to dissolve on a global-ordering failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum OrderingFix {
    /// After a merger (P§2.4.3): dissolve both relations that interleave.
    Merger,
    /// After forming shared edges with `with` (P§2.6): dissolve the relation with
    /// `with` and the other interleaving one.
    Forming { with: SegmentId },
}

impl SurfaceModel {
    /// Unshare the pair of corresponding shared edges `pair` (P§2.8), starting
    /// from segment `s`.
    pub(crate) fn unshare_pair(&mut self, s: SegmentId, pair: PairId) {
        self.unshare_pairs(vec![(s, pair)]);
    }

    /// Make the corner vertex `v` of `seg` and its corresponding corner vertices
    /// non-corner vertices (P§2.8), duplicating junctions as needed.
    pub(crate) fn dissolve_corner(&mut self, seg: SegmentId, v: usize) {
        let Some(cid) = self
            .poly(seg)
            .and_then(|p| p.nodes.get(v))
            .and_then(|x| x.corner)
        else {
            return;
        };
        let members = self.corner_members(seg, v, cid);
        let mut check = BTreeSet::new();
        for (ms, mv) in members {
            if let Some(p) = self.poly_mut(ms)
                && let Some(node) = p.nodes.get_mut(mv)
                && node.corner == Some(cid)
            {
                node.corner = None;
            }
            check.insert(ms);
        }
        let mut queue = Vec::new();
        for s in check {
            self.fix_junctions(s, &mut queue);
        }
        self.unshare_pairs(queue);
    }

    /// Duplicate or unshare at every junction of `seg` (see [`Self::unshare_pair`]).
    pub(crate) fn repair_junctions(&mut self, seg: SegmentId) {
        let mut queue = Vec::new();
        self.fix_junctions(seg, &mut queue);
        self.unshare_pairs(queue);
    }

    fn unshare_pairs(&mut self, mut queue: Vec<(SegmentId, PairId)>) {
        // Each round removes at least one shared edge pair, so the number of
        // rounds is bounded by the pairs in the model; the guard is a backstop.
        let mut guard = 0usize;
        while let Some((s, pair)) = queue.pop() {
            guard += 1;
            if guard > 100_000 {
                break;
            }
            let Some(i) = self.pair_edge(s, pair) else {
                continue;
            };
            let Some(share) = self.poly(s).and_then(|p| p.nodes[i].edge.share) else {
                continue;
            };
            let nb = share.neighbour;
            let j = self.pair_edge(nb, pair);
            // Corner ids at the ends of both edges.
            let mut ends = vec![(s, i), (s, i + 1)];
            if let Some(j) = j {
                ends.push((nb, j));
                ends.push((nb, j + 1));
            }
            let mut members: Vec<(SegmentId, usize, CornerId)> = Vec::new();
            for (seg, v) in ends {
                let Some(p) = self.poly(seg) else { continue };
                let v = v % p.nodes.len().max(1);
                if let Some(cid) = p.nodes.get(v).and_then(|x| x.corner)
                    && !members.iter().any(|m| m.2 == cid)
                {
                    for (ms, mv) in self.corner_members(seg, v, cid) {
                        members.push((ms, mv, cid));
                    }
                }
            }
            // Unshare both copies.
            if let Some(p) = self.poly_mut(s) {
                p.nodes[i].edge.share = None;
            }
            if let Some(j) = j
                && let Some(p) = self.poly_mut(nb)
            {
                p.nodes[j].edge.share = None;
            }
            // Corner vertices become non-corner vertices.
            let mut check: BTreeSet<SegmentId> = [s, nb].into_iter().collect();
            for (ms, mv, cid) in members {
                if let Some(p) = self.poly_mut(ms)
                    && let Some(node) = p.nodes.get_mut(mv)
                    && node.corner == Some(cid)
                {
                    node.corner = None;
                }
                check.insert(ms);
            }
            for seg in check {
                self.fix_junctions(seg, &mut queue);
            }
        }
    }

    /// All vertices carrying corner id `cid` reachable from vertex `v` of `seg`
    /// by walking the corner cycle forwards and backwards.
    pub(crate) fn corner_members(
        &self,
        seg: SegmentId,
        v: usize,
        cid: CornerId,
    ) -> Vec<(SegmentId, usize)> {
        let mut out = vec![(seg, v)];
        // Forwards: outgoing shared edge → end vertex of its corresponding edge.
        let mut cur = (seg, v);
        for _ in 0..MAX_CORNER_CYCLE {
            let Some(share) = self
                .poly(cur.0)
                .and_then(|p| p.nodes.get(cur.1))
                .and_then(|x| x.edge.share)
            else {
                break;
            };
            let Some(j) = self.pair_edge(share.neighbour, share.pair) else {
                break;
            };
            let Some(q) = self.poly(share.neighbour) else {
                break;
            };
            let nv = (j + 1) % q.nodes.len().max(1);
            if q.nodes.get(nv).and_then(|x| x.corner) != Some(cid)
                || out.contains(&(share.neighbour, nv))
            {
                break;
            }
            cur = (share.neighbour, nv);
            out.push(cur);
        }
        // Backwards: incoming shared edge → start vertex of its corresponding edge.
        let mut cur = (seg, v);
        for _ in 0..MAX_CORNER_CYCLE {
            let Some(p) = self.poly(cur.0) else { break };
            let n = p.nodes.len().max(1);
            let Some(share) = p.nodes.get((cur.1 + n - 1) % n).and_then(|x| x.edge.share) else {
                break;
            };
            let Some(j) = self.pair_edge(share.neighbour, share.pair) else {
                break;
            };
            let Some(q) = self.poly(share.neighbour) else {
                break;
            };
            if q.nodes.get(j).and_then(|x| x.corner) != Some(cid)
                || out.contains(&(share.neighbour, j))
            {
                break;
            }
            cur = (share.neighbour, j);
            out.push(cur);
        }
        out
    }

    /// Duplicate (or unshare at) every non-corner vertex of `seg` that joins edges
    /// shared with two different neighbours (P§2.8).
    fn fix_junctions(&mut self, seg: SegmentId, queue: &mut Vec<(SegmentId, PairId)>) {
        let mut i = 0;
        loop {
            let Some(p) = self.poly(seg) else { return };
            let n = p.nodes.len();
            if i >= n {
                return;
            }
            let node = p.nodes[i];
            let sin = p.nodes[(i + n - 1) % n].edge.share;
            let junction = node.corner.is_none()
                && matches!((sin, node.edge.share), (Some(a), Some(b)) if a.neighbour != b.neighbour);
            if junction
                && !self.split_vertex(seg, i)
                && let Some(share) = node.edge.share
            {
                // Unshared by the caller's loop, which then re-checks junctions.
                queue.push((seg, share.pair));
            }
            i += 1;
        }
    }

    /// Split vertex `i` of `seg` into two, `δ` apart along its two edges (see the
    /// [module docs](self)). `false` when that would not leave a simple perimeter.
    fn split_vertex(&mut self, seg: SegmentId, i: usize) -> bool {
        let tol = self.tol;
        let Some(p) = self.poly(seg) else {
            return false;
        };
        let n = p.nodes.len();
        let a = p.nodes[(i + n - 1) % n].position;
        let v = p.nodes[i].position;
        let b = p.nodes[(i + 1) % n].position;
        let (len_in, len_out) = ((v - a).norm(), (b - v).norm());
        let delta = tol.split.min(0.25 * len_in).min(0.25 * len_out);
        if delta <= 4.0 * tol.eps {
            return false;
        }
        let v_in = v - (v - a) * (delta / len_in);
        let v_out = v + (b - v) * (delta / len_out);
        if (v_out - v_in).norm() <= 4.0 * tol.eps {
            return false;
        }
        let frame: PlaneFrame = p.frame();
        let (q_in, q_out) = (frame.to_2d(&v_in), frame.to_2d(&v_out));
        let edges: Vec<_> = (0..n)
            .filter(|&k| k != i && k != (i + n - 1) % n)
            .map(|k| {
                (
                    frame.to_2d(&p.nodes[k].position),
                    frame.to_2d(&p.nodes[(k + 1) % n].position),
                )
            })
            .collect();
        if !geom::polygon2::can_sight(&q_in, &q_out, edges.iter().map(|(c, d)| (c, d)), tol.eps) {
            return false;
        }
        let key = self.fresh_key();
        let Some(pm) = self.poly_mut(seg) else {
            return false;
        };
        let out_edge = pm.nodes[i].edge;
        pm.nodes[i].position = v_in;
        pm.nodes[i].edge = Edge { key, share: None };
        pm.nodes.insert(
            i + 1,
            Node {
                position: v_out,
                corner: None,
                edge: out_edge,
            },
        );
        true
    }

    /// Dissolve the neighbour relation of `a` and `b` by unsharing every edge
    /// they share (P§2.8).
    pub(crate) fn dissolve(&mut self, a: SegmentId, b: SegmentId) {
        // Bounded: every pass unshares at least the first pair found.
        for _ in 0..10_000 {
            let Some(pair) = self.poly(a).and_then(|p| {
                p.nodes
                    .iter()
                    .find_map(|x| x.edge.share.filter(|s| s.neighbour == b).map(|s| s.pair))
            }) else {
                return;
            };
            self.unshare_pair(a, pair);
        }
    }

    /// Dissolve every neighbour relation of `s`.
    pub(crate) fn dissolve_all(&mut self, s: SegmentId) {
        let Some(p) = self.poly(s) else { return };
        for nb in p.neighbours() {
            self.dissolve(s, nb);
        }
    }

    /// Enforce local and global ordering on `s` (P§2.4.3, P§2.6): dissolve the
    /// neighbour relations that break them. Returns `true` when something was
    /// dissolved.
    pub(crate) fn enforce_ordering(&mut self, s: SegmentId, fix: OrderingFix) -> bool {
        let mut changed = false;
        let Some(p) = self.poly(s) else { return false };
        // Local ordering.
        for nb in p.neighbours() {
            let Some(p) = self.poly(s) else {
                return changed;
            };
            let mine: Vec<PairId> = p
                .nodes
                .iter()
                .filter_map(|x| {
                    x.edge
                        .share
                        .filter(|sh| sh.neighbour == nb)
                        .map(|sh| sh.pair)
                })
                .collect();
            let mut theirs: Vec<PairId> = self
                .poly(nb)
                .map(|q| {
                    q.nodes
                        .iter()
                        .filter_map(|x| {
                            x.edge
                                .share
                                .filter(|sh| sh.neighbour == s)
                                .map(|sh| sh.pair)
                        })
                        .collect()
                })
                .unwrap_or_default();
            theirs.reverse();
            if !cyclic_equal(&mine, &theirs) {
                self.dissolve(s, nb);
                changed = true;
            }
        }
        // Global ordering; each round dissolves at least one relation.
        for _ in 0..1000 {
            let Some(p) = self.poly(s) else {
                return changed;
            };
            let labels: Vec<SegmentId> = p
                .nodes
                .iter()
                .filter_map(|x| x.edge.share.map(|sh| sh.neighbour))
                .collect();
            let Some((a, b)) = global_order_violation(&labels) else {
                return changed;
            };
            changed = true;
            match fix {
                OrderingFix::Merger => {
                    self.dissolve(s, a);
                    self.dissolve(s, b);
                }
                OrderingFix::Forming { with } => {
                    self.dissolve(s, with);
                    if a != with {
                        self.dissolve(s, a);
                    }
                    if b != with {
                        self.dissolve(s, b);
                    }
                }
            }
        }
        changed
    }

    /// Delete segment `id` (P§2.9): dissolve its neighbour relations, remove it,
    /// and record it in the change log. Its points are no longer represented.
    pub(crate) fn delete_segment(&mut self, id: SegmentId) {
        self.dissolve_all(id);
        if let Some(seg) = self.remove_segment(id) {
            self.points_deleted += seg.moments.m;
            self.ctx.log.deleted.push(id);
            self.last_deleted.push(seg);
            self.set_flag(Flag::Modified, id, false);
            self.set_flag(Flag::Pending, id, false);
        }
    }
}
