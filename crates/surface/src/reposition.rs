//! Repositioning shared edges and corner vertices after a merger (P§2.4.4,
//! Fig. 14).
//!
//! The merged segment S's plane differs from the planes of the merged segments,
//! so for every neighbour N:
//! 1. the intersection line `I(S, N)` is computed; when the planes are within
//!    μ/2 of parallel or antiparallel (the thesis' 180° case, and its near-0°
//!    twin) the relation is dissolved;
//! 2. corner vertices of S, and of S's neighbours where S is one of the corner's
//!    planes, move to the intersection of their two lines (the three planes);
//!    when the lines are parallel the corner becomes a non-corner vertex (P§2.8);
//! 3. non-corner vertices of shared edges are projected onto their line;
//! 4. corresponding edges that no longer overlap are unshared; a non-corner end
//!    outside the overlap moves to its end, onto the corresponding vertex;
//! 5. for each repositioned shared edge `v₂v₃` between `v₁` and `v₄`, the pairs
//!    `v₁v₂`, `v₂v₃`, `v₃v₄` must sight each other and the edge must keep its
//!    anticlockwise direction; otherwise the edge is unshared and `v₂, v₃` return
//!    to their original positions.
//!
//! The result is validated; if a perimeter still crosses itself the relation
//! with the offending neighbour is dissolved and repositioning runs again. The
//! loop ends because every retry dissolves a relation of S.

use crate::model::{Flag, SurfaceModel};
use crate::perimeter::Poly2;
use crate::segment::{PairId, SegmentId};
use geom::Point3;
use geom::Real;
use std::collections::{BTreeMap, BTreeSet};

impl SurfaceModel {
    /// Reposition the shared edges of `s` and of its neighbours (P§2.4.4).
    pub(crate) fn reposition(&mut self, s: SegmentId) {
        let neighbours = self.poly(s).map_or(0, |p| p.neighbours().len());
        for _ in 0..=neighbours + 1 {
            self.begin();
            self.set_flag(Flag::Pending, s, false);
            let ok = self.reposition_inner(s);
            let verdict = if ok { self.validate_touched() } else { Ok(()) };
            match verdict {
                Ok(()) if ok => {
                    self.commit();
                    return;
                }
                other => {
                    self.rollback();
                    // Dissolve the relation with the segment that broke, or the first.
                    let culprit = other
                        .err()
                        .and_then(|v| v.segment)
                        .filter(|t| *t != s && self.are_neighbours(s, *t));
                    let Some(nb) = culprit
                        .or_else(|| self.poly(s).and_then(|p| p.neighbours().into_iter().next()))
                    else {
                        self.set_flag(Flag::Pending, s, false);
                        return;
                    };
                    self.run(|m| m.dissolve(s, nb));
                }
            }
        }
        // Every relation has been tried; what is left has no shared edges of s.
        self.run(|m| m.dissolve_all(s));
        self.set_flag(Flag::Pending, s, false);
    }

    #[allow(
        clippy::too_many_lines,
        reason = "the repositioning of P§2.8 step by step, each step reading and changing the same perimeter and relations"
    )]
    fn reposition_inner(&mut self, s: SegmentId) -> bool {
        let tol = self.tol;
        let Some(poly) = self.poly(s) else {
            return false;
        };
        // 1. Lines; dissolve (anti)parallel neighbours.
        for nb in poly.neighbours() {
            if self.line_between(s, nb).is_none() {
                self.dissolve(s, nb);
            }
        }
        let Some(poly) = self.poly(s) else {
            return false;
        };
        let neighbours = poly.neighbours();
        let mut group: Vec<SegmentId> = vec![s];
        group.extend(neighbours.iter().copied());
        // 2a. Corners whose lines became parallel become non-corner vertices.
        for _ in 0..256 {
            let Some((t, v)) =
                self.find_corner(&group, s, |m, a, t, b| m.corner_point(a, t, b).is_none())
            else {
                break;
            };
            self.dissolve_corner(t, v);
        }
        // Positions before repositioning, for restoring.
        let mut original: BTreeMap<SegmentId, Vec<Point3>> = BTreeMap::new();
        for &t in &group {
            if let Some(p) = self.poly(t) {
                original.insert(t, p.vertices().collect());
            }
        }
        let Some(poly) = self.poly(s) else {
            return false;
        };
        let neighbours = poly.neighbours();
        // 2b. Corner vertices.
        let mut moves: BTreeMap<(SegmentId, usize), Point3> = BTreeMap::new();
        for &t in &group {
            let Some(p) = self.poly(t) else { continue };
            let n = p.nodes.len();
            for v in 0..n {
                if p.nodes[v].corner.is_none() {
                    continue;
                }
                let (Some(a), Some(b)) =
                    (p.nodes[(v + n - 1) % n].edge.share, p.nodes[v].edge.share)
                else {
                    continue;
                };
                if t != s && a.neighbour != s && b.neighbour != s {
                    continue;
                }
                if let Some(c) = self.corner_point(a.neighbour, t, b.neighbour) {
                    moves.insert((t, v), c);
                }
            }
        }
        // 3. Non-corner vertices of shared edges onto their lines.
        let mut pairs: Vec<(SegmentId, usize, SegmentId, usize, PairId)> = Vec::new();
        for &nb in &neighbours {
            let Some(line) = self.line_between(s, nb) else {
                continue;
            };
            for (t, other) in [(s, nb), (nb, s)] {
                let Some(p) = self.poly(t) else { continue };
                let n = p.nodes.len();
                for i in 0..n {
                    let Some(sh) = p.nodes[i].edge.share.filter(|x| x.neighbour == other) else {
                        continue;
                    };
                    for v in [i, (i + 1) % n] {
                        if p.nodes[v].corner.is_none() {
                            moves.insert((t, v), line.project(&p.nodes[v].position));
                        }
                    }
                    if t == s
                        && let Some(j) = self.pair_edge(nb, sh.pair)
                    {
                        pairs.push((s, i, nb, j, sh.pair));
                    }
                }
            }
        }
        for (&(t, v), pos) in &moves {
            if let Some(p) = self.poly_mut_moving(t) {
                p.nodes[v].position = *pos;
            }
        }
        // 4. Overlap of corresponding edges; clamp non-corner ends into it.
        let mut unshare: BTreeSet<(SegmentId, PairId)> = BTreeSet::new();
        for &(a, i, b, j, pair) in &pairs {
            let Some(line) = self.line_between(a, b) else {
                continue;
            };
            let (Some(pa), Some(pb)) = (self.poly(a), self.poly(b)) else {
                continue;
            };
            let (na, nb) = (pa.nodes.len(), pb.nodes.len());
            let t = |p: &Point3| line.project_param(p);
            let (a0, a1) = (
                t(&pa.nodes[i].position),
                t(&pa.nodes[(i + 1) % na].position),
            );
            let (b0, b1) = (
                t(&pb.nodes[j].position),
                t(&pb.nodes[(j + 1) % nb].position),
            );
            let lo = a0.min(a1).max(b0.min(b1));
            let hi = a0.max(a1).min(b0.max(b1));
            if hi - lo < tol.eps {
                unshare.insert((a, pair));
                continue;
            }
            for (seg, e, len) in [(a, i, na), (b, j, nb)] {
                for v in [e, (e + 1) % len] {
                    let Some(p) = self.poly(seg) else { continue };
                    if p.nodes[v].corner.is_some() {
                        continue;
                    }
                    let tv = t(&p.nodes[v].position);
                    let clamped = tv.clamp(lo, hi);
                    if clamped != tv
                        && let Some(pm) = self.poly_mut_moving(seg)
                    {
                        pm.nodes[v].position = line.point_at(clamped);
                    }
                }
            }
        }
        // 5. Sight and direction of every repositioned shared edge.
        let mut restore: BTreeSet<(SegmentId, usize)> = BTreeSet::new();
        for &(a, i, b, j, pair) in &pairs {
            if unshare.contains(&(a, pair)) {
                continue;
            }
            let mut bad = false;
            for (seg, e) in [(a, i), (b, j)] {
                let Some(p) = self.poly(seg) else { continue };
                let Some(orig) = original.get(&seg) else {
                    continue;
                };
                let Some(other) = p.nodes[e].edge.share.map(|x| x.neighbour) else {
                    continue;
                };
                let Some(line) = self.line_between(seg, other) else {
                    bad = true;
                    continue;
                };
                let n = p.nodes.len();
                let (Some(o0), Some(o1)) = (orig.get(e), orig.get((e + 1) % n)) else {
                    bad = true;
                    continue;
                };
                let before = line.dir.dot(&(o1 - o0));
                let after = line
                    .dir
                    .dot(&(p.nodes[(e + 1) % n].position - p.nodes[e].position));
                if before * after <= 0.0 || after.abs() <= tol.eps {
                    bad = true;
                    continue;
                }
                let frame = p.frame();
                let p2 = Poly2::from_polygon(p, &frame);
                let (v1, v2, v3, v4) = (p2.pt(e + n - 1), p2.pt(e), p2.pt(e + 1), p2.pt(e + 2));
                if !(p2.sight(&v1, &v2, tol.eps, |_| false)
                    && p2.sight(&v2, &v3, tol.eps, |_| false)
                    && p2.sight(&v3, &v4, tol.eps, |_| false))
                {
                    bad = true;
                }
            }
            if bad {
                unshare.insert((a, pair));
                restore.insert((a, i));
                restore.insert((a, i + 1));
                restore.insert((b, j));
                restore.insert((b, j + 1));
            }
        }
        for (seg, v) in restore {
            let Some(orig) = original.get(&seg).cloned() else {
                continue;
            };
            if let Some(p) = self.poly_mut_moving(seg) {
                let n = p.nodes.len();
                if let Some(o) = orig.get(v % n) {
                    p.nodes[v % n].position = *o;
                }
            }
        }
        for (seg, pair) in unshare {
            self.unshare_pair(seg, pair);
        }
        true
    }

    /// A corner vertex of one of `group` that involves `s`, for which `pred` holds.
    fn find_corner(
        &self,
        group: &[SegmentId],
        s: SegmentId,
        pred: impl Fn(&Self, SegmentId, SegmentId, SegmentId) -> bool,
    ) -> Option<(SegmentId, usize)> {
        for &t in group {
            let Some(p) = self.poly(t) else { continue };
            let n = p.nodes.len();
            for v in 0..n {
                if p.nodes[v].corner.is_none() {
                    continue;
                }
                let (Some(a), Some(b)) =
                    (p.nodes[(v + n - 1) % n].edge.share, p.nodes[v].edge.share)
                else {
                    continue;
                };
                if t != s && a.neighbour != s && b.neighbour != s {
                    continue;
                }
                if pred(self, a.neighbour, t, b.neighbour) {
                    return Some((t, v));
                }
            }
        }
        None
    }
}

/// The largest distance of a shared-edge vertex of `s` from its line (for the
/// figure tests, [`crate::testing`]).
pub(crate) fn max_line_offset(model: &SurfaceModel, s: SegmentId) -> Real {
    let Some(p) = model.poly(s) else { return 0.0 };
    let n = p.nodes.len();
    let mut worst: Real = 0.0;
    for i in 0..n {
        if let Some(sh) = p.nodes[i].edge.share
            && let Some(line) = model.line_between(s, sh.neighbour)
        {
            worst = worst
                .max(line.distance_to_point(&p.nodes[i].position))
                .max(line.distance_to_point(&p.nodes[(i + 1) % n].position));
        }
    }
    worst
}
