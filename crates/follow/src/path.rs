//! The shortest edge path of current surface following (P§3.4.1): a
//! best-first branch-and-bound search over the current surface's edges, from
//! the edge nearest the control point to any edge of an incomplete segment.
//!
//! The search graph's nodes are perimeter vertices, merged when closer than a
//! tolerance (corresponding shared edges and corner vertices of neighbouring
//! polygons coincide, which is how the path crosses from one segment to the
//! next); its arcs are the perimeter edges, costing their length. Expanding the
//! cheapest open node first and stopping at the first goal popped is the
//! branch-and-bound search with the path length so far as its bound: every
//! open branch costing more than the goal found is pruned.

use crate::query::EdgeRef;
use geom::{Point3, Real};
use std::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap, HashMap};
use surface::{SegmentId, SurfaceModel};

/// A path along edges of the current surface.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgePath {
    /// The edges in path order.
    pub edges: Vec<EdgeRef>,
    /// For each edge, `true` when the path runs from its `a` to its `b`.
    pub forward: Vec<bool>,
    /// The incomplete segment the path leads to.
    pub target: SegmentId,
}

#[derive(Clone, Copy, PartialEq)]
struct Open {
    cost: Real,
    node: usize,
}

impl Eq for Open {}

impl Ord for Open {
    fn cmp(&self, other: &Self) -> Ordering {
        // Min-heap on cost, then on node for determinism.
        other
            .cost
            .total_cmp(&self.cost)
            .then_with(|| other.node.cmp(&self.node))
    }
}

impl PartialOrd for Open {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// All edges of the polygons in `surface`, in segment-id then perimeter order.
pub fn surface_edges(model: &SurfaceModel, surface: &[SegmentId]) -> Vec<EdgeRef> {
    let mut out = Vec::new();
    for &id in surface {
        let Some(poly) = model.polygon(id) else {
            continue;
        };
        for i in 0..poly.len() {
            if let (Some((a, b)), Some(e)) = (poly.edge_points(i), poly.edge(i)) {
                out.push(EdgeRef {
                    key: e.key,
                    segment: id,
                    index: i,
                    a,
                    b,
                    shared_with: e.share.map(|s| s.neighbour),
                });
            }
        }
    }
    out
}

/// Merge edge end points closer than `tol` into node ids: `(a node, b node)`
/// per edge, and the node count.
fn nodes_of(edges: &[EdgeRef], tol: Real) -> (Vec<(usize, usize)>, usize) {
    let cell = tol.max(1e-9);
    let key = |p: &Point3| {
        (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<usize>> = HashMap::new();
    let mut positions: Vec<Point3> = Vec::new();
    let mut node_of = |p: &Point3| -> usize {
        let (x, y, z) = key(p);
        let mut best: Option<(Real, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&(x + dx, y + dy, z + dz)) {
                        for &n in list {
                            let d = (positions[n] - p).norm();
                            if d <= tol && best.is_none_or(|b| d < b.0) {
                                best = Some((d, n));
                            }
                        }
                    }
                }
            }
        }
        if let Some((_, n)) = best {
            return n;
        }
        let n = positions.len();
        positions.push(*p);
        grid.entry((x, y, z)).or_default().push(n);
        n
    };
    let ends: Vec<(usize, usize)> = edges
        .iter()
        .map(|e| (node_of(&e.a), node_of(&e.b)))
        .collect();
    let count = positions.len();
    (ends, count)
}

/// The shortest edge path over `edges` (the current surface's edges) from the
/// edge nearest `from` to an edge of a segment for which `is_goal` holds.
/// `None` when no goal edge is connected to the start.
pub fn shortest_edge_path(
    edges: &[EdgeRef],
    from: &Point3,
    tol: Real,
    is_goal: impl Fn(SegmentId) -> bool,
) -> Option<EdgePath> {
    let start = (0..edges.len()).min_by(|&i, &j| {
        edges[i]
            .distance_to(from)
            .total_cmp(&edges[j].distance_to(from))
            .then(i.cmp(&j))
    })?;
    if is_goal(edges[start].segment) {
        let e = edges[start];
        // Head for the goal's interior side: along the edge anticlockwise.
        return Some(EdgePath {
            edges: vec![e],
            forward: vec![true],
            target: e.segment,
        });
    }
    let (ends, count) = nodes_of(edges, tol);
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); count];
    for (i, &(a, b)) in ends.iter().enumerate() {
        adjacent[a].push(i);
        if b != a {
            adjacent[b].push(i);
        }
    }
    // A node is a goal when an edge of a goal segment ends there.
    let mut goal_edge_at: BTreeMap<usize, usize> = BTreeMap::new();
    for (i, &(a, b)) in ends.iter().enumerate() {
        if is_goal(edges[i].segment) {
            goal_edge_at.entry(a).or_insert(i);
            goal_edge_at.entry(b).or_insert(i);
        }
    }
    if goal_edge_at.is_empty() {
        return None;
    }
    let mut cost = vec![Real::INFINITY; count];
    // How each node was reached: (edge, previous node).
    let mut came: Vec<Option<(usize, usize)>> = vec![None; count];
    let mut heap = BinaryHeap::new();
    let s = edges[start].segment3();
    let t = s.closest_param(from);
    let len = s.length();
    let (sa, sb) = ends[start];
    for (node, c) in [(sa, t * len), (sb, (1.0 - t) * len)] {
        if c < cost[node] {
            cost[node] = c;
            heap.push(Open { cost: c, node });
        }
    }
    let mut done = vec![false; count];
    let mut reached = None;
    while let Some(Open { cost: c, node }) = heap.pop() {
        if done[node] {
            continue;
        }
        done[node] = true;
        if goal_edge_at.contains_key(&node) {
            reached = Some(node);
            break;
        }
        for &e in &adjacent[node] {
            let (a, b) = ends[e];
            let other = if a == node { b } else { a };
            let nc = c + edges[e].length();
            if nc < cost[other] {
                cost[other] = nc;
                came[other] = Some((e, node));
                heap.push(Open {
                    cost: nc,
                    node: other,
                });
            }
        }
    }
    let end = reached?;
    let mut rev: Vec<(usize, bool)> = Vec::new();
    let mut node = end;
    while let Some((e, prev)) = came[node] {
        rev.push((e, ends[e].0 == prev));
        node = prev;
    }
    // The start edge first, run towards the node the search left it by.
    let first_forward = node == sb;
    let mut out_edges = vec![edges[start]];
    let mut forward = vec![first_forward];
    for (e, fwd) in rev.into_iter().rev() {
        if e != start {
            out_edges.push(edges[e]);
            forward.push(fwd);
        }
    }
    let goal_edge = goal_edge_at[&end];
    let target = edges[goal_edge].segment;
    if out_edges.last().is_none_or(|l| l.segment != target) {
        let (a, _) = ends[goal_edge];
        out_edges.push(edges[goal_edge]);
        forward.push(a == end);
    }
    Some(EdgePath {
        edges: out_edges,
        forward,
        target,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use surface::{EdgeKey, SegmentId};

    fn edge(k: u32, seg: u32, a: [Real; 3], b: [Real; 3]) -> EdgeRef {
        EdgeRef {
            key: EdgeKey(k),
            segment: SegmentId(seg),
            index: k as usize,
            a: Point3::from(a),
            b: Point3::from(b),
            shared_with: None,
        }
    }

    /// A ladder of unit squares along x (segments 1, 2, 3 sharing edges); the
    /// goal is segment 3. The path from near segment 1's left edge runs along
    /// a rail (length 2 + the start edge's part) — checked by hand.
    #[test]
    fn ladder_by_hand() {
        let mut edges = Vec::new();
        let mut k = 0;
        for s in 0..3u32 {
            let x = Real::from(s);
            let sq = [
                [x, 0.0, 0.0],
                [x + 1.0, 0.0, 0.0],
                [x + 1.0, 1.0, 0.0],
                [x, 1.0, 0.0],
            ];
            for i in 0..4 {
                edges.push(edge(k, s + 1, sq[i], sq[(i + 1) % 4]));
                k += 1;
            }
        }
        let path = shortest_edge_path(&edges, &Point3::new(-0.1, 0.2, 0.0), 1e-6, |s| {
            s == SegmentId(3)
        })
        .unwrap();
        assert_eq!(path.target, SegmentId(3));
        // Start at segment 1's left edge (x = 0), to (0,0), then along y = 0.
        assert_eq!(path.edges[0].segment, SegmentId(1));
        assert!((path.edges[0].a.x).abs() < 1e-12 && (path.edges[0].b.x).abs() < 1e-12);
        let total: Real = path.edges[1..].iter().map(EdgeRef::length).sum();
        // Two unit rails to reach x = 2 (a vertex of segment 3), then its edge.
        assert!((total - 3.0).abs() < 1e-9, "{total}");
        assert_eq!(path.edges.last().unwrap().segment, SegmentId(3));
        // Consecutive edges connect in the stated directions.
        for w in 0..path.edges.len() - 1 {
            let (e0, f0) = (path.edges[w], path.forward[w]);
            let (e1, f1) = (path.edges[w + 1], path.forward[w + 1]);
            let end0 = if f0 { e0.b } else { e0.a };
            let start1 = if f1 { e1.a } else { e1.b };
            assert!((end0 - start1).norm() < 1e-9, "gap at {w}");
        }
        assert!(shortest_edge_path(&edges, &Point3::origin(), 1e-6, |_| false).is_none());
    }
}
