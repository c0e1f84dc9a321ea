//! Combining two projected perimeters in one plane (P§2.4.3, Fig. 10–13).
//!
//! * **Overlapping** polygons (Fig. 12–13): the perimeters are split at their
//!   crossing points (collinear stretches count as one crossing), the pieces of
//!   each perimeter that lie outside the other polygon are kept, and the kept
//!   pieces are linked into cycles. The one anticlockwise cycle is the outermost
//!   perimeter; clockwise cycles are holes, which must collapse by filling
//!   fissures without restrictions (P§2.5) or the merger fails. A polygon wholly
//!   inside the other leaves the other unchanged.
//! * **Non-overlapping** polygons (Fig. 10–11): a perimeter section `P` of one
//!   (from vertex `p₁` to vertex `p₂`) is extended to a section `Q` of the other
//!   (from `q₁`, the point closest to `p₂`, to `q₂`, the point closest to `p₁`),
//!   subject to the rules of P§2.4.3: `|p₁q₂|, |p₂q₁| < λ`, every edge of `P` within
//!   λ of `Q` and vice versa, the closest points of the two perimeters on `P` and
//!   `Q`, `p₁` sights `q₂` and `p₂` sights `q₁`, and `P` as long as possible.
//!
//! Both return the list of shared edges (pair ids) that lie on discarded
//! perimeter sections, whole or in part: the merger unshares them (P§2.8) and
//! recombines, until nothing shared is discarded.

use crate::fissure::collapse_hole;
use crate::perimeter::{Node2, PerimPoint, Poly2, param_on_segment, turn};
use crate::segment::{Edge, EdgeKey, PairId};
use geom::polygon2::{self, Containment, SegmentIntersection};
use geom::{Point2, Real};
use std::collections::BTreeSet;

/// Result of combining two perimeters.
#[derive(Clone, Debug)]
pub(crate) struct Combined {
    /// The combined perimeter.
    pub poly: Poly2,
    /// Shared edges lying (partly) on discarded sections.
    pub dropped: BTreeSet<PairId>,
    /// Holes that collapsed (P§2.4.3, Fig. 13b); read by the figure tests.
    #[cfg_attr(not(test), allow(dead_code))]
    pub holes_collapsed: usize,
    /// `true` when the polygons overlapped (union), `false` when bridged; read
    /// by the figure tests.
    #[cfg_attr(not(test), allow(dead_code))]
    pub overlapped: bool,
}

/// Why two perimeters could not be combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CombineError {
    /// A hole's perimeter did not collapse.
    HoleRemains,
    /// Non-overlapping, and no valid bridge exists.
    NoBridge,
    /// The overlay could not be traced (degenerate input).
    Degenerate,
}

/// Combine two anticlockwise perimeters (see the [module docs](self)).
pub(crate) fn combine(
    a: &Poly2,
    b: &Poly2,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Result<Combined, CombineError> {
    match overlay(a, b, eps) {
        Overlay::Union { outer, holes } => {
            let mut collapsed = 0;
            for h in &holes {
                if collapse_hole(h, lambda, eps) {
                    collapsed += 1;
                } else {
                    return Err(CombineError::HoleRemains);
                }
            }
            let polys = [a, b];
            let mut nodes = Vec::with_capacity(outer.len());
            let mut kept: BTreeSet<(usize, usize)> = BTreeSet::new();
            for (k, piece) in outer.iter().enumerate() {
                let src = polys[piece.poly];
                let prev = &outer[(k + outer.len() - 1) % outer.len()];
                let edge = if piece.whole {
                    kept.insert((piece.poly, piece.edge));
                    src.edge(piece.edge)
                } else {
                    Edge {
                        key: fresh(),
                        share: None,
                    }
                };
                // A corner survives when the vertex is the original vertex with both
                // of its original edges kept whole.
                let corner = if piece.whole
                    && prev.whole
                    && prev.poly == piece.poly
                    && (prev.edge + 1) % src.len().max(1) == piece.edge
                {
                    src.nodes[piece.edge].corner
                } else {
                    None
                };
                nodes.push(Node2 {
                    p: piece.start,
                    corner,
                    edge,
                });
            }
            let mut dropped = BTreeSet::new();
            for (pi, src) in polys.iter().enumerate() {
                for (ei, node) in src.nodes.iter().enumerate() {
                    if let Some(s) = node.edge.share
                        && !kept.contains(&(pi, ei))
                    {
                        dropped.insert(s.pair);
                    }
                }
            }
            Ok(Combined {
                poly: Poly2 { nodes },
                dropped,
                holes_collapsed: collapsed,
                overlapped: true,
            })
        }
        Overlay::Disjoint => {
            let mut plans: Vec<Bridge> = Vec::new();
            plans.extend(bridge_plans(a, b, lambda, eps));
            plans.extend(bridge_plans(b, a, lambda, eps).into_iter().map(|mut p| {
                p.swapped = true;
                p
            }));
            plans.sort_by(|x, y| y.length.total_cmp(&x.length));
            for plan in plans.iter().take(8) {
                let (x, y) = if plan.swapped { (b, a) } else { (a, b) };
                if let Some(c) = build_bridge(x, y, plan, eps, fresh) {
                    return Ok(c);
                }
            }
            Err(CombineError::NoBridge)
        }
        Overlay::Failed => Err(CombineError::Degenerate),
    }
}

/// One piece of the outer perimeter: its start point and the original edge it
/// lies on.
#[derive(Clone, Copy, Debug)]
struct Piece {
    start: Point2,
    poly: usize,
    edge: usize,
    whole: bool,
}

enum Overlay {
    Union {
        outer: Vec<Piece>,
        holes: Vec<Vec<Point2>>,
    },
    Disjoint,
    Failed,
}

#[derive(Clone, Copy, Debug)]
struct SubEdge {
    from: usize,
    to: usize,
    poly: usize,
    edge: usize,
    t0: Real,
    t1: Real,
}

/// Overlay two perimeters and trace the boundary of their union.
#[allow(
    clippy::too_many_lines,
    reason = "one boundary-tracing algorithm (split the edges, classify the pieces, trace the union, collect the holes) over shared working arrays"
)]
fn overlay(a: &Poly2, b: &Poly2, eps: Real) -> Overlay {
    let polys = [a, b];
    let pts = [a.points(), b.points()];
    // Split parameters per edge.
    let mut splits: [Vec<Vec<Real>>; 2] = [
        (0..a.len()).map(|_| vec![0.0, 1.0]).collect(),
        (0..b.len()).map(|_| vec![0.0, 1.0]).collect(),
    ];
    let mut any_contact = false;
    for i in 0..a.len() {
        let (p0, p1) = a.seg(i);
        let (ax0, ax1) = (p0.x.min(p1.x) - eps, p0.x.max(p1.x) + eps);
        let (ay0, ay1) = (p0.y.min(p1.y) - eps, p0.y.max(p1.y) + eps);
        for j in 0..b.len() {
            let (q0, q1) = b.seg(j);
            if q0.x.max(q1.x) < ax0
                || q0.x.min(q1.x) > ax1
                || q0.y.max(q1.y) < ay0
                || q0.y.min(q1.y) > ay1
            {
                continue;
            }
            match polygon2::intersect_segments(&p0, &p1, &q0, &q1, eps) {
                SegmentIntersection::None => {}
                SegmentIntersection::Point { s, t } => {
                    any_contact = true;
                    splits[0][i].push(s);
                    splits[1][j].push(t);
                }
                SegmentIntersection::Overlap { s0, s1 } => {
                    any_contact = true;
                    splits[0][i].push(s0);
                    splits[0][i].push(s1);
                    for s in [s0, s1] {
                        let p = p0 + (p1 - p0) * s;
                        splits[1][j].push(param_on_segment(&p, &q0, &q1));
                    }
                }
            }
        }
    }
    if !any_contact {
        // No crossing: one inside the other, or apart.
        let a_in_b = polygon2::locate_point(&pts[1], &pts[0][0], 0.0) == Containment::Inside;
        let b_in_a = polygon2::locate_point(&pts[0], &pts[1][0], 0.0) == Containment::Inside;
        if a_in_b || b_in_a {
            let outer_poly = usize::from(a_in_b);
            let src = polys[outer_poly];
            let outer = (0..src.len())
                .map(|k| Piece {
                    start: src.pt(k),
                    poly: outer_poly,
                    edge: k,
                    whole: true,
                })
                .collect();
            return Overlay::Union {
                outer,
                holes: Vec::new(),
            };
        }
        return Overlay::Disjoint;
    }
    // Nodes (clustered within eps) and sub-edges.
    let mut nodes: Vec<Point2> = Vec::new();
    let node_of = |p: Point2, nodes: &mut Vec<Point2>| -> usize {
        if let Some(k) = nodes.iter().position(|q| (q - p).norm() <= eps) {
            return k;
        }
        nodes.push(p);
        nodes.len() - 1
    };
    let mut subs: Vec<SubEdge> = Vec::new();
    for (pi, poly) in polys.iter().enumerate() {
        for (ei, ts) in splits[pi].iter_mut().enumerate() {
            let (p0, p1) = poly.seg(ei);
            let len = (p1 - p0).norm().max(Real::MIN_POSITIVE);
            for t in ts.iter_mut() {
                *t = t.clamp(0.0, 1.0);
                if *t * len <= eps {
                    *t = 0.0;
                } else if (1.0 - *t) * len <= eps {
                    *t = 1.0;
                }
            }
            ts.sort_by(Real::total_cmp);
            ts.dedup_by(|x, y| (*x - *y) * len <= eps);
            if let Some(last) = ts.last_mut() {
                *last = 1.0;
            }
            let ids: Vec<usize> = ts
                .iter()
                .map(|t| node_of(p0 + (p1 - p0) * *t, &mut nodes))
                .collect();
            for k in 0..ts.len().saturating_sub(1) {
                if ids[k] != ids[k + 1] {
                    subs.push(SubEdge {
                        from: ids[k],
                        to: ids[k + 1],
                        poly: pi,
                        edge: ei,
                        t0: ts[k],
                        t1: ts[k + 1],
                    });
                }
            }
        }
    }
    // Keep the pieces whose right side lies outside the other polygon.
    let mut keep: Vec<SubEdge> = Vec::new();
    for s in &subs {
        let (p, q) = (nodes[s.from], nodes[s.to]);
        let d = q - p;
        let len = d.norm();
        if len <= 0.0 {
            continue;
        }
        let right = geom::Vector2::new(d.y, -d.x) / len;
        let probe = p + d * 0.5 + right * (10.0 * eps).min(0.25 * len);
        let other = &pts[1 - s.poly];
        if polygon2::locate_point(other, &probe, 0.0) == Containment::Inside {
            continue;
        }
        if keep.iter().any(|k| k.from == s.from && k.to == s.to) {
            continue;
        }
        keep.push(*s);
    }
    // Trace cycles, turning as far left as possible at every node.
    let mut used = vec![false; keep.len()];
    let mut cycles: Vec<Vec<usize>> = Vec::new();
    for start in 0..keep.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut cycle = vec![start];
        let mut cur = start;
        let mut closed = false;
        for _ in 0..=keep.len() {
            let at = keep[cur].to;
            let din = nodes[keep[cur].to] - nodes[keep[cur].from];
            let mut best: Option<(Real, usize)> = None;
            for (k, e) in keep.iter().enumerate() {
                if e.from != at || (used[k] && k != start) {
                    continue;
                }
                let dout = nodes[e.to] - nodes[e.from];
                let t = if e.to == keep[cur].from {
                    -4.0
                } else {
                    turn(&din, &dout)
                };
                if best.is_none_or(|(bt, _)| t > bt) {
                    best = Some((t, k));
                }
            }
            let Some((_, k)) = best else { break };
            if k == start {
                closed = true;
                break;
            }
            used[k] = true;
            cycle.push(k);
            cur = k;
        }
        if !closed {
            return Overlay::Failed;
        }
        cycles.push(cycle);
    }
    let mut outers = Vec::new();
    let mut holes = Vec::new();
    for c in cycles {
        let ring: Vec<Point2> = c.iter().map(|&k| nodes[keep[k].from]).collect();
        let area = polygon2::signed_area(&ring);
        if area > eps * eps {
            outers.push(c);
        } else if area < -eps * eps {
            holes.push(ring);
        }
    }
    match outers.len() {
        0 => Overlay::Failed,
        1 => {
            let c = &outers[0];
            // Merge consecutive pieces of the same original edge.
            let mut pieces: Vec<(SubEdge, Real, Real)> = Vec::new();
            for &k in c {
                let s = keep[k];
                if let Some(last) = pieces.last_mut()
                    && last.0.poly == s.poly
                    && last.0.edge == s.edge
                    && (last.2 - s.t0).abs() < 1e-12
                {
                    last.2 = s.t1;
                    continue;
                }
                pieces.push((s, s.t0, s.t1));
            }
            if pieces.len() > 1
                && let (Some(first), Some(last)) = (pieces.first().copied(), pieces.last().copied())
                && first.0.poly == last.0.poly
                && first.0.edge == last.0.edge
                && (last.2 - first.1).abs() < 1e-12
            {
                pieces.pop();
                if let Some(f) = pieces.first_mut() {
                    f.0.from = last.0.from;
                    f.1 = last.1;
                }
            }
            let outer = pieces
                .iter()
                .map(|(s, t0, t1)| Piece {
                    start: nodes[s.from],
                    poly: s.poly,
                    edge: s.edge,
                    whole: *t0 == 0.0 && *t1 == 1.0,
                })
                .collect();
            Overlay::Union { outer, holes }
        }
        _ => Overlay::Disjoint,
    }
}

/// A candidate bridge: `P` from vertex `p1` to vertex `p2` of `x`, `Q` from `q1`
/// to `q2` of `y`.
#[derive(Clone, Copy, Debug)]
struct Bridge {
    p1: usize,
    p2: usize,
    q1: PerimPoint,
    q2: PerimPoint,
    length: Real,
    swapped: bool,
}

/// Distance between two closed 2-D segments and the parameters of the closest
/// points.
fn closest_segments(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> (Real, Real, Real) {
    if let SegmentIntersection::Point { s, t } = polygon2::intersect_segments(a, b, c, d, 0.0) {
        return (0.0, s, t);
    }
    let mut best = (Real::INFINITY, 0.0, 0.0);
    for (s, p) in [(0.0, a), (1.0, b)] {
        let t = param_on_segment(p, c, d);
        let dist = (p - (c + (d - c) * t)).norm();
        if dist < best.0 {
            best = (dist, s, t);
        }
    }
    for (t, p) in [(0.0, c), (1.0, d)] {
        let s = param_on_segment(p, a, b);
        let dist = (p - (a + (b - a) * s)).norm();
        if dist < best.0 {
            best = (dist, s, t);
        }
    }
    best
}

/// The closest pair of perimeter points of `x` and `y`.
fn closest_pair(x: &Poly2, y: &Poly2) -> (PerimPoint, PerimPoint, Real) {
    let mut best = (PerimPoint::vertex(0), PerimPoint::vertex(0), Real::INFINITY);
    for i in 0..x.len() {
        let (a, b) = x.seg(i);
        for j in 0..y.len() {
            let (c, d) = y.seg(j);
            let (dist, s, t) = closest_segments(&a, &b, &c, &d);
            if dist < best.2 {
                best = (
                    PerimPoint { edge: i, t: s },
                    PerimPoint { edge: j, t },
                    dist,
                );
            }
        }
    }
    best
}

/// Distance from segment `a b` to the polyline of `poly`'s section from `from`
/// to `to`.
fn distance_to_section(
    a: &Point2,
    b: &Point2,
    poly: &Poly2,
    from: PerimPoint,
    to: PerimPoint,
) -> Real {
    let mut best = Real::INFINITY;
    for e in poly.section_edges(from, to) {
        let (mut c, mut d) = poly.seg(e);
        if e == from.edge % poly.len() {
            c = poly.point_at(from);
        }
        if e == to.edge % poly.len() && to.t > 0.0 && !(from.edge == to.edge && to.t < from.t) {
            d = poly.point_at(to);
        }
        best = best.min(closest_segments(a, b, &c, &d).0);
    }
    best
}

/// `true` when perimeter point `p` lies on the section from `from` to `to`.
fn on_section(poly: &Poly2, p: PerimPoint, from: PerimPoint, to: PerimPoint, eps: Real) -> bool {
    poly.arc_len(from, p) <= poly.arc_len(from, to) + eps || poly.arc_len(p, from) <= eps
}

/// Candidate bridges from vertices of `x` to `y` (P§2.4.3 rules).
fn bridge_plans(x: &Poly2, y: &Poly2, lambda: Real, eps: Real) -> Vec<Bridge> {
    let (cx, cy, dmin) = closest_pair(x, y);
    if dmin >= lambda {
        return Vec::new();
    }
    let cx = x.snap(cx, eps);
    let cy = y.snap(cy, eps);
    let near: Vec<usize> = (0..x.len())
        .filter(|&i| y.closest(&x.pt(i)).1 < lambda)
        .collect();
    let mut plans = Vec::new();
    for &p1 in &near {
        for &p2 in &near {
            if p1 == p2 {
                continue;
            }
            let (pp1, pp2) = (PerimPoint::vertex(p1), PerimPoint::vertex(p2));
            if !on_section(x, cx, pp1, pp2, eps) {
                continue;
            }
            let (q2, d2) = y.closest(&x.pt(p1));
            let (q1, d1) = y.closest(&x.pt(p2));
            if d1 >= lambda || d2 >= lambda {
                continue;
            }
            let (q1, q2) = (y.snap(q1, eps), y.snap(q2, eps));
            if (y.point_at(q1) - y.point_at(q2)).norm() <= eps {
                continue;
            }
            if !on_section(y, cy, q1, q2, eps) {
                continue;
            }
            // Every edge of P within λ of Q, every piece of Q within λ of P.
            let p_ok = x.section_edges(pp1, pp2).iter().all(|&e| {
                let (a, b) = x.seg(e);
                distance_to_section(&a, &b, y, q1, q2) < lambda
            });
            if !p_ok {
                continue;
            }
            let q_ok = y.section_edges(q1, q2).iter().all(|&e| {
                let (mut a, mut b) = y.seg(e);
                if e == q1.edge % y.len() {
                    a = y.point_at(q1);
                }
                if e == q2.edge % y.len() && q2.t > 0.0 {
                    b = y.point_at(q2);
                }
                distance_to_section(&a, &b, x, pp1, pp2) < lambda
            });
            if !q_ok {
                continue;
            }
            // Sight, relative to both perimeters.
            let (xp1, xp2, yq1, yq2) = (x.pt(p1), x.pt(p2), y.point_at(q1), y.point_at(q2));
            let sees = |u: &Point2, v: &Point2| {
                x.sight(u, v, eps, |_| false) && y.sight(u, v, eps, |_| false)
            };
            if !sees(&xp1, &yq2) || !sees(&xp2, &yq1) {
                continue;
            }
            plans.push(Bridge {
                p1,
                p2,
                q1,
                q2,
                length: x.arc_len(pp1, pp2),
                swapped: false,
            });
        }
    }
    plans
}

/// Nodes of the section of `poly` from `from` to `to` (both included); the last
/// node's edge is left to the caller. Edges cut at `from` or `to` get fresh keys.
fn kept_section(
    poly: &Poly2,
    from: PerimPoint,
    to: PerimPoint,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Vec<Node2> {
    let n = poly.len();
    let mut out = Vec::new();
    if from.t == 0.0 {
        out.push(poly.nodes[from.edge % n]);
    } else {
        out.push(Node2::plain(poly.point_at(from), fresh()));
    }
    let mut k = from.edge % n;
    let stop = to.edge % n;
    let same_edge_forward = from.edge % n == stop && to.t > from.t;
    if same_edge_forward {
        if let Some(first) = out.first_mut() {
            first.edge = Edge {
                key: fresh(),
                share: None,
            };
        }
        out.push(Node2::plain(poly.point_at(to), fresh()));
    } else {
        for _ in 0..n {
            k = (k + 1) % n;
            if k == stop {
                break;
            }
            out.push(poly.nodes[k]);
        }
        if to.t > 0.0 {
            // The piece from vertex `stop` to `to` is a cut edge.
            out.push(poly.nodes[stop]);
            if let Some(last) = out.last_mut() {
                last.edge = Edge {
                    key: fresh(),
                    share: None,
                };
            }
            out.push(Node2::plain(poly.point_at(to), fresh()));
        } else {
            out.push(poly.nodes[stop]);
        }
    }
    out
}

fn build_bridge(
    x: &Poly2,
    y: &Poly2,
    plan: &Bridge,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Option<Combined> {
    let (pp1, pp2) = (PerimPoint::vertex(plan.p1), PerimPoint::vertex(plan.p2));
    let mut nodes = kept_section(x, pp2, pp1, fresh);
    if let Some(last) = nodes.last_mut() {
        last.edge = Edge {
            key: fresh(),
            share: None,
        };
    }
    let mut ys = kept_section(y, plan.q2, plan.q1, fresh);
    if let Some(last) = ys.last_mut() {
        last.edge = Edge {
            key: fresh(),
            share: None,
        };
    }
    nodes.extend(ys);
    let poly = Poly2 { nodes };
    if !poly.is_valid(eps) {
        return None;
    }
    let mut dropped = BTreeSet::new();
    for e in x.section_edges(pp1, pp2) {
        if let Some(s) = x.edge(e).share {
            dropped.insert(s.pair);
        }
    }
    for e in y.section_edges(plan.q1, plan.q2) {
        if let Some(s) = y.edge(e).share {
            dropped.insert(s.pair);
        }
    }
    Some(Combined {
        poly,
        dropped,
        holes_collapsed: 0,
        overlapped: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(pts: &[(Real, Real)], key0: u32) -> Poly2 {
        Poly2 {
            nodes: pts
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| Node2::plain(Point2::new(x, y), EdgeKey(key0 + i as u32)))
                .collect(),
        }
    }

    fn run(a: &Poly2, b: &Poly2) -> Result<Combined, CombineError> {
        let mut k = 10_000;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        combine(a, b, 0.05, 1e-6, &mut fresh)
    }

    /// P Fig. 13(a): overlapping polygons, no hole: the union.
    #[test]
    fn fig13a_union_without_hole() {
        let a = poly(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], 0);
        let b = poly(&[(0.5, 0.5), (1.5, 0.5), (1.5, 1.5), (0.5, 1.5)], 100);
        let c = run(&a, &b).unwrap();
        assert!(c.overlapped);
        assert!(c.poly.is_valid(1e-9));
        assert!((c.poly.area() - 1.75).abs() < 1e-9);
        assert_eq!(c.poly.len(), 8);
        // Edges kept whole keep their keys; cut ones get new keys.
        assert!(c.poly.nodes.iter().any(|n| n.edge.key == EdgeKey(0)));
        assert!(!c.poly.nodes.iter().any(|n| n.edge.key == EdgeKey(1)));
    }

    /// P Fig. 12–13(b): overlapping polygons forming a thin hole, which collapses.
    #[test]
    fn fig13b_hole_collapses() {
        // A "C" shape and a bar closing its mouth leave a hole 0.02 wide.
        let c_shape = poly(
            &[
                (0.0, 0.0),
                (1.0, 0.0),
                (1.0, 0.2),
                (0.2, 0.2),
                (0.2, 0.22),
                (1.0, 0.22),
                (1.0, 0.5),
                (0.0, 0.5),
            ],
            0,
        );
        let bar = poly(&[(0.9, -0.1), (1.2, -0.1), (1.2, 0.6), (0.9, 0.6)], 100);
        let c = run(&c_shape, &bar).unwrap();
        assert_eq!(c.holes_collapsed, 1);
        assert!(c.poly.is_valid(1e-9));
        // The hole is discarded: the outer perimeter is the union's outline.
        assert!(
            (c.poly.area() - (1.2 * 0.5 + 0.3 * 0.2 - 0.0)).abs() < 0.02,
            "{}",
            c.poly.area()
        );
        // A wide hole does not collapse: the merger fails.
        let wide = poly(
            &[
                (0.0, 0.0),
                (1.0, 0.0),
                (1.0, 0.1),
                (0.2, 0.1),
                (0.2, 0.4),
                (1.0, 0.4),
                (1.0, 0.5),
                (0.0, 0.5),
            ],
            0,
        );
        assert_eq!(run(&wide, &bar).unwrap_err(), CombineError::HoleRemains);
    }

    /// P Fig. 10–11: non-overlapping polygons closer than λ are bridged.
    #[test]
    fn fig11_bridge() {
        let a = poly(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], 0);
        let b = poly(&[(1.03, 0.2), (2.0, 0.2), (2.0, 0.8), (1.03, 0.8)], 100);
        let c = run(&a, &b).unwrap();
        assert!(!c.overlapped);
        assert!(c.poly.is_valid(1e-9));
        let expected = 1.0 + 0.97 * 0.6 + 0.03 * 0.6;
        assert!((c.poly.area() - expected).abs() < 1e-6, "{}", c.poly.area());
        // Farther apart than λ: no bridge.
        let far = poly(&[(1.2, 0.2), (2.0, 0.2), (2.0, 0.8), (1.2, 0.8)], 100);
        assert_eq!(run(&a, &far).unwrap_err(), CombineError::NoBridge);
    }

    #[test]
    fn containment_and_shared_sides() {
        let a = poly(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], 0);
        let inner = poly(&[(0.2, 0.2), (0.4, 0.2), (0.4, 0.4)], 100);
        let c = run(&a, &inner).unwrap();
        assert_eq!(c.poly.len(), 4);
        assert!((c.poly.area() - 1.0).abs() < 1e-12);
        // Two squares sharing a side: one rectangle (collinear vertices remain).
        let b = poly(&[(1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0)], 100);
        let c = run(&a, &b).unwrap();
        assert!(c.poly.is_valid(1e-9));
        assert!((c.poly.area() - 2.0).abs() < 1e-9);
    }
}
