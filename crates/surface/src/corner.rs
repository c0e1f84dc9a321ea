//! Forming corner vertices (P§2.7, Fig. 23–24).
//!
//! For a segment S with successive shared edges `e₁`, `e₂` (the next shared edge
//! after `e₁` anticlockwise) shared with different neighbours and no corner
//! vertex between them, the perimeter section `P` from `v₁` (end of `e₁`) to `v₂`
//! (start of `e₂`) is replaced by a corner vertex at the corner point, the
//! intersection of the lines `l₁` of `e₁` and `l₂` of `e₂`. Conditions per segment:
//! every point of `P` within λ of `l₁` or `l₂`; the lines not parallel; a point of
//! `P` within λ of the corner point; moving `v₁, v₂` to it keeps the anticlockwise
//! directions of `e₁, e₂`; and it sights `v₁` and `v₂` relative to the perimeter
//! without `P`. The same must hold around the whole neighbour cycle
//! `S₀ = S, S₁, …, Sₙ` (the neighbour across `e₂`, its next shared edge, …, back to
//! S across `e₁`): then a corner vertex is formed in every segment of the cycle at
//! the intersection of its own two lines — the corners need not coincide
//! (Fig. 23). Cycles are limited to [`MAX_CORNER_CYCLE`] segments.

use crate::invariants::MAX_CORNER_CYCLE;
use crate::model::SurfaceModel;
use crate::perimeter::Poly2;
use crate::segment::{EdgeKey, SegmentId};
use geom::{Line3, Point2, Point3, Real};
use std::collections::BTreeSet;

/// One member of a corner cycle: the segment and the keys of its `e₁`, `e₂`.
#[derive(Clone, Copy, Debug)]
struct Member {
    seg: SegmentId,
    e1: EdgeKey,
    e2: EdgeKey,
}

impl SurfaceModel {
    /// P§2.3 step 5 for `s`: attempt corner vertices between its successive
    /// shared edges. Returns the number of corner cycles formed.
    pub(crate) fn form_corners(&mut self, s: SegmentId) -> usize {
        let mut tried: BTreeSet<(EdgeKey, EdgeKey)> = BTreeSet::new();
        let mut formed = 0;
        // Each iteration either forms a cycle or marks a candidate tried; both
        // are bounded by the number of shared edges of s.
        for _ in 0..64 {
            let Some((e1, e2)) = self.next_corner_candidate(s, &tried) else {
                break;
            };
            tried.insert((e1, e2));
            if self.attempt(|m| m.form_corner_cycle(s, e1, e2)).is_some() {
                formed += 1;
            }
        }
        formed
    }

    /// Successive shared edges of `s` with different neighbours and no corner
    /// vertex between them.
    fn next_corner_candidate(
        &self,
        s: SegmentId,
        tried: &BTreeSet<(EdgeKey, EdgeKey)>,
    ) -> Option<(EdgeKey, EdgeKey)> {
        let p = self.poly(s)?;
        let n = p.nodes.len();
        let shared: Vec<usize> = (0..n)
            .filter(|&i| p.nodes[i].edge.share.is_some())
            .collect();
        if shared.len() < 2 {
            return None;
        }
        for (k, &i) in shared.iter().enumerate() {
            let j = shared[(k + 1) % shared.len()];
            let (Some(a), Some(b)) = (p.nodes[i].edge.share, p.nodes[j].edge.share) else {
                continue;
            };
            if a.neighbour == b.neighbour {
                continue;
            }
            if j == (i + 1) % n && p.nodes[j].corner.is_some() {
                continue; // already a corner between them
            }
            let keys = (p.nodes[i].edge.key, p.nodes[j].edge.key);
            if !tried.contains(&keys) {
                return Some(keys);
            }
        }
        None
    }

    /// The next shared edge after edge `i` of `s`, anticlockwise.
    fn next_shared(&self, s: SegmentId, i: usize) -> Option<usize> {
        let p = self.poly(s)?;
        let n = p.nodes.len();
        (1..n)
            .map(|k| (i + k) % n)
            .find(|&j| p.nodes[j].edge.share.is_some())
    }

    /// Form the corner vertices of the cycle through `s` between its edges `e1`
    /// and `e2` (inside the caller's transaction).
    fn form_corner_cycle(&mut self, s: SegmentId, e1: EdgeKey, e2: EdgeKey) -> Option<()> {
        // Walk the cycle.
        let mut members = vec![Member { seg: s, e1, e2 }];
        let mut cur = members[0];
        loop {
            let p = self.poly(cur.seg)?;
            let i2 = p.edge_index(cur.e2)?;
            let sh = p.nodes[i2].edge.share?;
            let nb = sh.neighbour;
            let f1 = self.pair_edge(nb, sh.pair)?;
            let q = self.poly(nb)?;
            let f1_key = q.nodes[f1].edge.key;
            if nb == s {
                if f1_key != e1 {
                    return None;
                }
                break;
            }
            if members.iter().any(|m| m.seg == nb) || members.len() >= MAX_CORNER_CYCLE {
                return None;
            }
            let f2 = self.next_shared(nb, f1)?;
            let f2_share = q.nodes[f2].edge.share?;
            if f2_share.neighbour == cur.seg || f2 == f1 {
                return None;
            }
            let n = q.nodes.len();
            if f2 == (f1 + 1) % n && q.nodes[f2].corner.is_some() {
                return None; // inconsistent: a corner already there
            }
            cur = Member {
                seg: nb,
                e1: f1_key,
                e2: q.nodes[f2].edge.key,
            };
            members.push(cur);
        }
        if members.len() < 3 {
            return None;
        }
        // Check every member, then form.
        let mut plans = Vec::with_capacity(members.len());
        for m in &members {
            plans.push(self.corner_check(m).ok()?);
        }
        let cid = self.new_corner();
        for (m, c) in members.iter().zip(plans) {
            let p = self.poly_mut(m.seg)?;
            let i1 = p.edge_index(m.e1)?;
            let i2 = p.edge_index(m.e2)?;
            let n = p.nodes.len();
            let v1 = (i1 + 1) % n;
            let out_edge = p.nodes[i2].edge;
            // Remove the vertices after v₁ up to and including v₂ (= i2).
            let mut remove = Vec::new();
            let mut k = v1;
            while k != i2 {
                k = (k + 1) % n;
                remove.push(k);
            }
            p.nodes[v1].position = c;
            p.nodes[v1].corner = Some(cid);
            p.nodes[v1].edge = out_edge;
            remove.sort_unstable();
            for idx in remove.into_iter().rev() {
                p.nodes.remove(idx);
            }
        }
        Some(())
    }

    /// Check the conditions of P§2.7 for one member: the corner point, or the
    /// condition that failed.
    fn corner_check(&self, m: &Member) -> Result<Point3, &'static str> {
        let tol = self.tol;
        let p = self.poly(m.seg).ok_or("seg")?;
        let n = p.nodes.len();
        let i1 = p.edge_index(m.e1).ok_or("e1")?;
        let i2 = p.edge_index(m.e2).ok_or("e2")?;
        let a = p.nodes[i1].edge.share.ok_or("sa")?.neighbour;
        let b = p.nodes[i2].edge.share.ok_or("sb")?.neighbour;
        let l1 = self.line_between(m.seg, a).ok_or("l1")?;
        let l2 = self.line_between(m.seg, b).ok_or("l2")?;
        let c = self.corner_point(a, m.seg, b).ok_or("parallel")?;
        let v1 = (i1 + 1) % n;
        if v1 != i2 && p.nodes[v1].corner.is_some() {
            return Err("v1corner");
        }
        // P: v₁ … v₂ (vertex indices v1 ..= i2).
        let mut section = vec![v1];
        let mut k = v1;
        while k != i2 {
            k = (k + 1) % n;
            section.push(k);
        }
        let pts: Vec<Point3> = section.iter().map(|&k| p.nodes[k].position).collect();
        // Every point of P within λ of l₁ or l₂.
        for w in pts.windows(2) {
            if !covered(&w[0], &w[1], &l1, &l2, tol.lambda) {
                return Err("cover");
            }
        }
        if pts.len() == 1
            && l1
                .distance_to_point(&pts[0])
                .min(l2.distance_to_point(&pts[0]))
                >= tol.lambda
        {
            return Err("cover1");
        }
        // A point of P within λ of the corner point.
        let near = if pts.len() == 1 {
            (pts[0] - c).norm()
        } else {
            pts.windows(2)
                .map(|w| geom::Segment3::new(w[0], w[1]).distance_to_point(&c))
                .fold(Real::INFINITY, Real::min)
        };
        if near >= tol.lambda {
            return Err("near");
        }
        // Directions of e₁ and e₂ preserved.
        let s1 = p.nodes[i1].position;
        let e1_dir = p.nodes[v1].position - s1;
        let e2_end = p.nodes[(i2 + 1) % n].position;
        let e2_dir = e2_end - p.nodes[i2].position;
        if (c - s1).dot(&e1_dir) <= tol.eps * e1_dir.norm()
            || (e2_end - c).dot(&e2_dir) <= tol.eps * e2_dir.norm()
        {
            return Err("direction");
        }
        // The corner point sights v₁ and v₂ relative to the perimeter without P.
        let frame = p.frame();
        let poly = Poly2::from_polygon(p, &frame);
        // Edges e₁ and e₂ lie along the sight lines themselves; they do not block.
        let mut removed: BTreeSet<usize> = section[..section.len() - 1].iter().copied().collect();
        removed.insert(i1);
        removed.insert(i2);
        let cc: Point2 = frame.to_2d(&c);
        let skip = |e: usize| removed.contains(&e);
        if !poly.sight(&cc, &poly.pt(v1), tol.eps, skip)
            || !poly.sight(&cc, &poly.pt(i2), tol.eps, skip)
        {
            return Err("sight");
        }
        Ok(c)
    }
}

/// `true` when every point of segment `a b` lies within `r` of line `l1` or `l2`.
fn covered(a: &Point3, b: &Point3, l1: &Line3, l2: &Line3, r: Real) -> bool {
    // Squared distance to a line is quadratic in the segment parameter; sample
    // the exact intervals by solving it for each line.
    let interval = |l: &Line3| -> (Real, Real) {
        let pa = a - l.point;
        let d = b - a;
        let pa_perp = pa - l.dir.into_inner() * pa.dot(&l.dir);
        let d_perp = d - l.dir.into_inner() * d.dot(&l.dir);
        let qa = d_perp.norm_squared();
        let qb = 2.0 * pa_perp.dot(&d_perp);
        let qc = pa_perp.norm_squared() - r * r;
        if qa <= 1e-300 {
            return if qc < 0.0 { (0.0, 1.0) } else { (1.0, 0.0) };
        }
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return (1.0, 0.0);
        }
        let sq = disc.sqrt();
        (
            ((-qb - sq) / (2.0 * qa)).max(0.0),
            ((-qb + sq) / (2.0 * qa)).min(1.0),
        )
    };
    let (a0, a1) = interval(l1);
    let (b0, b1) = interval(l2);
    let mut ivs: Vec<(Real, Real)> = [(a0, a1), (b0, b1)]
        .into_iter()
        .filter(|(x, y)| y > x)
        .collect();
    ivs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut reach = 0.0;
    for (x, y) in ivs {
        if x > reach + 1e-12 {
            return false;
        }
        reach = Real::max(reach, y);
    }
    reach >= 1.0 - 1e-12
}
