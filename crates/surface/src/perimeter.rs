//! Perimeters in a plane's 2-D coordinates: the working form every perimeter
//! operation uses (P§2.4–2.7 all act on "perimeter points" and "perimeter
//! sections"). A `Poly2` is converted from a [`Polygon`] through a
//! [`PlaneFrame`] (orthogonal projection) and back.

use crate::segment::{CornerId, Edge, EdgeKey, Node, Polygon};
use geom::polygon2::{self, EdgeAdjacency};
use geom::{PlaneFrame, Point2, Real, Vector2};

/// A perimeter vertex in 2-D with its records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node2 {
    pub p: Point2,
    pub corner: Option<CornerId>,
    pub edge: Edge,
}

impl Node2 {
    pub fn plain(p: Point2, key: EdgeKey) -> Self {
        Self {
            p,
            corner: None,
            edge: Edge { key, share: None },
        }
    }
}

/// A point on a perimeter: edge index and parameter `t ∈ [0, 1)` along it
/// (`t = 0` is the edge's start vertex).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PerimPoint {
    pub edge: usize,
    pub t: Real,
}

impl PerimPoint {
    pub fn vertex(i: usize) -> Self {
        Self { edge: i, t: 0.0 }
    }

    pub fn is_vertex(&self) -> bool {
        self.t == 0.0
    }
}

/// Why a perimeter edit was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EditError {
    /// The edit would cut a shared edge.
    CutsSharedEdge,
    /// The section is empty or the whole perimeter.
    Degenerate,
}

/// A closed perimeter in 2-D; edge `i` joins node `i` to node `i + 1`.
#[derive(Clone, Debug, PartialEq, Default)]
pub(crate) struct Poly2 {
    pub nodes: Vec<Node2>,
}

impl Poly2 {
    /// The polygon's perimeter projected into `frame`.
    pub fn from_polygon(poly: &Polygon, frame: &PlaneFrame) -> Self {
        Self {
            nodes: poly
                .nodes
                .iter()
                .map(|n| Node2 {
                    p: frame.to_2d(&n.position),
                    corner: n.corner,
                    edge: n.edge,
                })
                .collect(),
        }
    }

    /// Back to 3-D nodes on the frame's plane.
    pub fn to_nodes(&self, frame: &PlaneFrame) -> Vec<Node> {
        self.nodes
            .iter()
            .map(|n| Node {
                position: frame.to_3d(&n.p),
                corner: n.corner,
                edge: n.edge,
            })
            .collect()
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    #[inline]
    pub fn next(&self, i: usize) -> usize {
        let n = self.nodes.len().max(1);
        (i + 1) % n
    }

    #[inline]
    pub fn prev(&self, i: usize) -> usize {
        let n = self.nodes.len().max(1);
        (i + n - 1) % n
    }

    /// Vertex `i` (modulo the count).
    #[inline]
    pub fn pt(&self, i: usize) -> Point2 {
        let n = self.nodes.len();
        if n == 0 {
            return Point2::origin();
        }
        self.nodes[i % n].p
    }

    /// Edge `i` as (start, end).
    #[inline]
    pub fn seg(&self, i: usize) -> (Point2, Point2) {
        (self.pt(i), self.pt(i + 1))
    }

    /// The record of edge `i` (modulo the count).
    #[inline]
    pub fn edge(&self, i: usize) -> Edge {
        let n = self.nodes.len().max(1);
        self.nodes.get(i % n).map_or(
            Edge {
                key: EdgeKey(u32::MAX),
                share: None,
            },
            |n| n.edge,
        )
    }

    #[inline]
    pub fn is_shared(&self, i: usize) -> bool {
        self.edge(i).share.is_some()
    }

    pub fn points(&self) -> Vec<Point2> {
        self.nodes.iter().map(|n| n.p).collect()
    }

    pub fn edge_len(&self, i: usize) -> Real {
        let (a, b) = self.seg(i);
        (b - a).norm()
    }

    /// Signed area (positive when anticlockwise).
    pub fn area(&self) -> Real {
        // `polygon2::signed_area` on the nodes in place (same terms, same order).
        let ns = &self.nodes;
        let n = ns.len();
        if n < 3 {
            return 0.0;
        }
        let mut s = 0.0;
        for i in 0..n {
            let a = &ns[i].p;
            let b = &ns[(i + 1) % n].p;
            s += a.x * b.y - b.x * a.y;
        }
        0.5 * s
    }

    /// Simple (with coincidence tolerance `eps`) and anticlockwise.
    ///
    /// Every perimeter operation ends with this check, so its buffers are
    /// kept per thread ([`SimpleScratch`]) instead of allocated per call.
    pub fn is_valid(&self, eps: Real) -> bool {
        if self.nodes.len() < 3 {
            return false;
        }
        // `area` adds the terms of `polygon2::signed_area` in its order.
        let area = self.area();
        area > 0.0 && valid_points(self.nodes.iter().map(|n| n.p), eps)
    }

    /// The point at `pp`.
    pub fn point_at(&self, pp: PerimPoint) -> Point2 {
        let (a, b) = self.seg(pp.edge);
        a + (b - a) * pp.t
    }

    /// Snap a perimeter point to a vertex when it is within `eps` of one.
    pub fn snap(&self, pp: PerimPoint, eps: Real) -> PerimPoint {
        let n = self.len().max(1);
        let len = self.edge_len(pp.edge);
        let edge = pp.edge % n;
        if pp.t * len <= eps {
            PerimPoint::vertex(edge)
        } else if (1.0 - pp.t) * len <= eps {
            PerimPoint::vertex((edge + 1) % n)
        } else {
            PerimPoint { edge, t: pp.t }
        }
    }

    /// Perimeter distance from `a` anticlockwise to `b` (0 when equal).
    pub fn arc_len(&self, a: PerimPoint, b: PerimPoint) -> Real {
        let n = self.len();
        if n == 0 {
            return 0.0;
        }
        if a.edge == b.edge && b.t >= a.t {
            return (b.t - a.t) * self.edge_len(a.edge);
        }
        let mut total = (1.0 - a.t) * self.edge_len(a.edge);
        let mut i = self.next(a.edge);
        let mut guard = 0;
        while i != b.edge % n && guard < n {
            total += self.edge_len(i);
            i = self.next(i);
            guard += 1;
        }
        total + b.t * self.edge_len(b.edge)
    }

    /// The perimeter point closest to `q`, and its distance.
    pub fn closest(&self, q: &Point2) -> (PerimPoint, Real) {
        let mut best = (PerimPoint::vertex(0), Real::INFINITY);
        for i in 0..self.len() {
            let (a, b) = self.seg(i);
            let t = param_on_segment(q, &a, &b);
            let d = (q - (a + (b - a) * t)).norm();
            if d < best.1 {
                best = (PerimPoint { edge: i, t }, d);
            }
        }
        best
    }

    /// Edges whose index is in the anticlockwise section `from ..= to` of edge
    /// indices (inclusive, cyclic), into `out` (cleared first).
    fn edge_range_into(&self, from: usize, to: usize, out: &mut Vec<usize>) {
        out.clear();
        let n = self.len();
        if n == 0 {
            return;
        }
        let mut i = from % n;
        for _ in 0..n {
            out.push(i);
            if i == to % n {
                break;
            }
            i = self.next(i);
        }
    }

    /// Indices of the edges touched by the open section from `a` to `b`
    /// (anticlockwise): the edges of which a part of positive length lies strictly
    /// between them.
    pub fn section_edges(&self, a: PerimPoint, b: PerimPoint) -> Vec<usize> {
        let mut out = Vec::new();
        self.section_edges_into(a, b, &mut out);
        out
    }

    /// [`Poly2::section_edges`] into `out` (cleared first), for callers that
    /// test many sections.
    pub fn section_edges_into(&self, a: PerimPoint, b: PerimPoint, out: &mut Vec<usize>) {
        out.clear();
        let n = self.len();
        if n == 0 {
            return;
        }
        let last = if b.t == 0.0 {
            self.prev(b.edge)
        } else {
            b.edge % n
        };
        if a.edge == b.edge && b.t > a.t {
            out.push(a.edge % n);
            return;
        }
        self.edge_range_into(a.edge, last, out);
    }

    /// `true` when the segment `a b` crosses none of the perimeter's edges,
    /// except those for which `skip` holds (P§2.4.2 sight test).
    pub fn sight(&self, a: &Point2, b: &Point2, eps: Real, skip: impl Fn(usize) -> bool) -> bool {
        // `polygon2::can_sight` over the edges that pass the box filter below,
        // written out as one loop (edge by edge, `polygon2::blocks_sight`):
        // this scan runs in every perimeter operation.
        let len = (b - a).norm();
        if len <= eps {
            return true;
        }
        let near = eps / len;
        let n = self.len();
        // Only edges whose boxes meet the sight line's box can cross it.
        let (x0, x1) = (a.x.min(b.x) - eps, a.x.max(b.x) + eps);
        let (y0, y1) = (a.y.min(b.y) - eps, a.y.max(b.y) + eps);
        for i in 0..n {
            let (c, d) = (
                &self.nodes[i].p,
                &self.nodes[if i + 1 == n { 0 } else { i + 1 }].p,
            );
            let apart =
                c.x.max(d.x) < x0 || c.x.min(d.x) > x1 || c.y.max(d.y) < y0 || c.y.min(d.y) > y1;
            if !apart && !skip(i) && polygon2::blocks_sight(a, b, c, d, eps, near) {
                return false;
            }
        }
        true
    }

    /// Replace the section that runs anticlockwise from `from` to `to` by new
    /// vertices: the result keeps the perimeter from `to` around to `from`, gives
    /// the vertex at `from` the outgoing edge `from_edge`, then appends `inserted`
    /// (the last inserted vertex's edge runs to `to`). Vertices are formed at
    /// `from` and `to` unless they are vertices already (P§2.4.2 step 1); an edge
    /// cut by them becomes a new edge (`fresh` keys).
    pub fn replace_section(
        &self,
        from: PerimPoint,
        to: PerimPoint,
        from_edge: Edge,
        inserted: &[Node2],
        fresh: &mut dyn FnMut() -> EdgeKey,
    ) -> Result<Self, EditError> {
        let mut out = Vec::with_capacity(self.len() + inserted.len() + 2);
        self.replace_section_into(from, to, from_edge, inserted, fresh, &mut out)?;
        Ok(Self { nodes: out })
    }

    /// [`Poly2::replace_section`] into `out` (cleared first; on an error it
    /// holds a part of the result): for callers that try many edits and keep
    /// few, without an allocation each.
    pub fn replace_section_into(
        &self,
        from: PerimPoint,
        to: PerimPoint,
        from_edge: Edge,
        inserted: &[Node2],
        fresh: &mut dyn FnMut() -> EdgeKey,
        out: &mut Vec<Node2>,
    ) -> Result<(), EditError> {
        out.clear();
        let n = self.len();
        if n < 2 {
            return Err(EditError::Degenerate);
        }
        let (i, s) = (from.edge % n, from.t);
        let (j, u) = (to.edge % n, to.t);
        if i == j && s == u {
            return Err(EditError::Degenerate);
        }
        // The vertex at `to`.
        if u == 0.0 {
            out.push(self.nodes[j]);
        } else {
            if self.nodes[j].edge.share.is_some() {
                return Err(EditError::CutsSharedEdge);
            }
            out.push(Node2::plain(self.point_at(to), fresh()));
        }
        // Whole vertices after `to` up to vertex i.
        let mut count = (i + n - j) % n;
        if i == j && s < u {
            count = n;
        }
        // Nodes j + 1 ..= j + count (modulo n), copied as at most two runs.
        let first = (j + 1).min(n);
        let head = count.min(n - first);
        out.extend_from_slice(&self.nodes[first..first + head]);
        out.extend_from_slice(&self.nodes[..count - head]);
        // The vertex at `from`.
        if s == 0.0 {
            // Vertex i is the `from` vertex (it is the last pushed, or `to` itself
            // when the kept section is a single vertex).
            let Some(last) = out.last_mut() else {
                return Err(EditError::Degenerate);
            };
            last.edge = from_edge;
        } else {
            if self.nodes[i].edge.share.is_some() {
                return Err(EditError::CutsSharedEdge);
            }
            if let Some(last) = out.last_mut() {
                last.edge = Edge {
                    key: fresh(),
                    share: None,
                };
            }
            out.push(Node2 {
                p: self.point_at(from),
                corner: None,
                edge: from_edge,
            });
        }
        out.extend_from_slice(inserted);
        if out.len() < 3 {
            return Err(EditError::Degenerate);
        }
        Ok(())
    }
}

/// A uniform grid over the bounding boxes of a [`Poly2`]'s edges, for call
/// sites that run many sight tests against one unchanged perimeter. A query
/// visits the edges in the cells its box meets and applies exactly the box
/// filter of [`Poly2::sight`] to them, so it hands [`polygon2::can_sight`] the
/// same set of edges (in another order, which cannot change its answer: it is
/// `false` exactly when one of the edges crosses). Cell indices are monotone
/// in the coordinates, so two boxes that meet share a cell.
pub(crate) struct SightGrid {
    /// Edge boxes as `(x_min, x_max, y_min, y_max)`, computed as in `sight`.
    boxes: Vec<(Real, Real, Real, Real)>,
    /// First cell (x, y) of each edge's box.
    first: Vec<(u32, u32)>,
    /// Grid origin and cell size, and the cell counts.
    x0: Real,
    y0: Real,
    wx: Real,
    wy: Real,
    gx: usize,
    gy: usize,
    /// Edges per cell (CSR): `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Edges in no cell, checked by every query.
    big: Vec<u32>,
    /// `false` when the grid is not usable (non-finite coordinates): queries
    /// fall back to the plain scan.
    usable: bool,
}

impl SightGrid {
    pub fn new(poly: &Poly2) -> Self {
        let n = poly.len();
        let boxes: Vec<(Real, Real, Real, Real)> = (0..n)
            .map(|i| {
                let (c, d) = (&poly.nodes[i].p, &poly.nodes[(i + 1) % n].p);
                (c.x.min(d.x), c.x.max(d.x), c.y.min(d.y), c.y.max(d.y))
            })
            .collect();
        let mut grid = Self {
            boxes,
            first: Vec::new(),
            x0: 0.0,
            y0: 0.0,
            wx: 1.0,
            wy: 1.0,
            gx: 1,
            gy: 1,
            start: Vec::new(),
            items: Vec::new(),
            big: Vec::new(),
            usable: false,
        };
        if n < 16 {
            return grid;
        }
        let finite = grid
            .boxes
            .iter()
            .all(|b| b.0.is_finite() && b.1.is_finite() && b.2.is_finite() && b.3.is_finite());
        if !finite {
            return grid;
        }
        let (mut x0, mut x1, mut y0, mut y1) = (Real::MAX, Real::MIN, Real::MAX, Real::MIN);
        for b in &grid.boxes {
            x0 = x0.min(b.0);
            x1 = x1.max(b.1);
            y0 = y0.min(b.2);
            y1 = y1.max(b.3);
        }
        let g = ((n as Real).sqrt() as usize).clamp(1, 64);
        let (gx, gy) = (g, g);
        let (wx, wy) = ((x1 - x0) / gx as Real, (y1 - y0) / gy as Real);
        grid.x0 = x0;
        grid.y0 = y0;
        grid.gx = gx;
        grid.gy = gy;
        grid.wx = if wx > 0.0 && wx.is_finite() { wx } else { 1.0 };
        grid.wy = if wy > 0.0 && wy.is_finite() { wy } else { 1.0 };
        let ranges: Vec<(usize, usize, usize, usize)> = grid
            .boxes
            .iter()
            .map(|b| (grid.cx(b.0), grid.cx(b.1), grid.cy(b.2), grid.cy(b.3)))
            .collect();
        // Edges over more than a few cells are kept in one list that every
        // query scans (with the same box filter).
        let big = |r: &(usize, usize, usize, usize)| (r.1 - r.0 + 1) * (r.3 - r.2 + 1) > 4;
        let mut count = vec![0u32; gx * gy + 1];
        for r in &ranges {
            if big(r) {
                grid.big.push(0);
                continue;
            }
            for y in r.2..=r.3 {
                for x in r.0..=r.1 {
                    count[y * gx + x + 1] += 1;
                }
            }
        }
        for c in 1..count.len() {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[gx * gy] as usize];
        grid.big.clear();
        for (e, r) in ranges.iter().enumerate() {
            if big(r) {
                grid.big.push(e as u32);
                continue;
            }
            for y in r.2..=r.3 {
                for x in r.0..=r.1 {
                    let c = y * gx + x;
                    items[fill[c] as usize] = e as u32;
                    fill[c] += 1;
                }
            }
        }
        grid.first = ranges.iter().map(|r| (r.0 as u32, r.2 as u32)).collect();
        grid.start = count;
        grid.items = items;
        grid.usable = true;
        grid
    }

    /// Cell column of `x` (monotone non-decreasing in `x`, clamped).
    #[inline]
    fn cx(&self, x: Real) -> usize {
        // Truncation is the floor for f ≥ 0 (and avoids a libm call).
        let f = (x - self.x0) / self.wx;
        if f > 0.0 {
            (f as usize).min(self.gx - 1)
        } else {
            0
        }
    }

    #[inline]
    fn cy(&self, y: Real) -> usize {
        // Truncation is the floor for f ≥ 0 (and avoids a libm call).
        let f = (y - self.y0) / self.wy;
        if f > 0.0 {
            (f as usize).min(self.gy - 1)
        } else {
            0
        }
    }

    /// [`Poly2::sight`] on `poly`, the perimeter this grid was built from.
    pub fn sight(
        &self,
        poly: &Poly2,
        a: &Point2,
        b: &Point2,
        eps: Real,
        skip: impl Fn(usize) -> bool,
    ) -> bool {
        let n = poly.len();
        debug_assert_eq!(n, self.boxes.len());
        // `polygon2::can_sight` over the kept edges, written out as loops
        // (edge by edge, `polygon2::blocks_sight`), as in `Poly2::sight`.
        let len = (b - a).norm();
        if len <= eps {
            return true;
        }
        let near = eps / len;
        let (x0, x1) = (a.x.min(b.x) - eps, a.x.max(b.x) + eps);
        let (y0, y1) = (a.y.min(b.y) - eps, a.y.max(b.y) + eps);
        let finite = x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite();
        let blocks = |i: usize| {
            let bx = &self.boxes[i];
            let apart = bx.1 < x0 || bx.0 > x1 || bx.3 < y0 || bx.2 > y1;
            !apart && !skip(i) && {
                let (c, d) = (&poly.nodes[i].p, &poly.nodes[(i + 1) % n].p);
                polygon2::blocks_sight(a, b, c, d, eps, near)
            }
        };
        if !self.usable || !finite {
            return !(0..n).any(blocks);
        }
        if self.big.iter().any(|&e| blocks(e as usize)) {
            return false;
        }
        let (qx0, qx1, qy0, qy1) = (self.cx(x0), self.cx(x1), self.cy(y0), self.cy(y1));
        for y in qy0..=qy1 {
            for x in qx0..=qx1 {
                let c = y * self.gx + x;
                for &e in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    let e = e as usize;
                    // Report an edge only in the first cell it shares with the query.
                    let (fx, fy) = self.first[e];
                    if x == qx0.max(fx as usize) && y == qy0.max(fy as usize) && blocks(e) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// [`polygon2::is_simple`] with a bounding-box rejection in front of every
/// edge-pair test (perimeters are checked after every operation). Pairs whose
/// boxes, grown by `tol`, do not overlap cannot meet; the others, found by a
/// sweep along x (ragged noisy perimeters have many short edges), get the exact
/// test of `geom` on the two-edge sub-problem.
#[cfg(test)]
pub(crate) fn is_simple_fast(poly: &[Point2], tol: Real) -> bool {
    let mut scratch = SimpleScratch::default();
    poly.len() >= 3
        && simple_with_area(
            poly,
            tol,
            polygon2::signed_area(poly),
            &mut scratch.boxes,
            &mut scratch.order,
        )
}

/// The buffers of [`Poly2::is_valid`]: the perimeter's points, the edges'
/// boxes and the sweep order of [`simple_with_area`].
#[derive(Default)]
struct SimpleScratch {
    pts: Vec<Point2>,
    boxes: Vec<(Real, Real, Real, Real)>,
    order: Vec<(i64, u32)>,
}

thread_local! {
    static SIMPLE_SCRATCH: std::cell::RefCell<SimpleScratch> =
        std::cell::RefCell::new(SimpleScratch::default());
}

/// [`Poly2::is_valid`] of the perimeter through `points` (in order), without
/// building the perimeter: the points go straight into the per-thread buffer
/// (the invariant check projects every touched polygon's vertices).
pub(crate) fn valid_points(points: impl IntoIterator<Item = Point2>, eps: Real) -> bool {
    SIMPLE_SCRATCH.with(|cell| {
        let mut scratch = cell.borrow_mut();
        let SimpleScratch { pts, boxes, order } = &mut *scratch;
        pts.clear();
        pts.extend(points);
        if pts.len() < 3 {
            return false;
        }
        // The terms of `Poly2::area`, in its order.
        let area = polygon2::signed_area(pts);
        area > 0.0 && simple_with_area(pts, eps, area, boxes, order)
    })
}

/// [`is_simple_fast`] given the polygon's signed area (`n ≥ 3`), with
/// `boxes` and `order` as buffers (any content).
fn simple_with_area(
    poly: &[Point2],
    tol: Real,
    area: Real,
    boxes: &mut Vec<(Real, Real, Real, Real)>,
    order: &mut Vec<(i64, u32)>,
) -> bool {
    let n = poly.len();
    if n < 3 || area.abs() <= tol * tol {
        return false;
    }
    boxes.clear();
    boxes.extend((0..n).map(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        (
            a.x.min(b.x) - tol,
            a.x.max(b.x) + tol,
            a.y.min(b.y) - tol,
            a.y.max(b.y) + tol,
        )
    }));
    if (0..n).any(|i| (poly[(i + 1) % n] - poly[i]).norm() <= tol) {
        return false;
    }
    // Sweep along x: edges sorted by the left side of their boxes; each edge
    // meets only the following ones whose boxes start before its box ends.
    // Keys in the order of `f64::total_cmp` (its own bit transform), so the
    // order is the same as sorting by `total_cmp` then index, on plain integers.
    order.clear();
    order.extend(boxes.iter().enumerate().map(|(i, b)| {
        let mut key = b.0.to_bits() as i64;
        key ^= (((key >> 63) as u64) >> 1) as i64;
        (key, i as u32)
    }));
    order.sort_unstable();
    let boxes = &boxes[..];
    for (k, &(_, u)) in order.iter().enumerate() {
        let u = u as usize;
        let bu = boxes[u];
        for &(_, w) in &order[k + 1..] {
            let w = w as usize;
            let bw = boxes[w];
            if bw.0 > bu.1 {
                break;
            }
            if bu.3 < bw.2 || bw.3 < bu.2 {
                continue;
            }
            let (i, j) = (u.min(w), u.max(w));
            let a = &poly[i];
            let b = &poly[(i + 1) % n];
            let c = &poly[j];
            let d = &poly[(j + 1) % n];
            let adjacency = EdgeAdjacency::of(i, j, n);
            // Adjacent edges that do not fold back onto each other meet only at
            // their shared vertex.
            if adjacency != EdgeAdjacency::Apart {
                let (d1, d2) = if adjacency == EdgeAdjacency::Next {
                    (b - a, d - c)
                } else {
                    (d - c, b - a)
                };
                let cross = d1.x * d2.y - d1.y * d2.x;
                if d1.dot(&d2) > 0.0 || cross.abs() > tol * (d1.norm() + d2.norm()) {
                    continue;
                }
            }
            if polygon2::edges_meet_improperly(a, b, c, d, adjacency, tol) {
                return false;
            }
        }
    }
    true
}

/// Parameter in `[0, 1]` of the point of segment `a b` closest to `q`.
pub(crate) fn param_on_segment(q: &Point2, a: &Point2, b: &Point2) -> Real {
    let d = b - a;
    let len2 = d.norm_squared();
    if len2 <= 0.0 {
        return 0.0;
    }
    ((q - a).dot(&d) / len2).clamp(0.0, 1.0)
}

/// 2-D cross product.
#[inline]
pub(crate) fn cross2(a: &Vector2, b: &Vector2) -> Real {
    a.x * b.y - a.y * b.x
}

/// Signed turn from direction `a` to direction `b`, in `(-π, π]` (left positive).
pub(crate) fn turn(a: &Vector2, b: &Vector2) -> Real {
    cross2(a, b).atan2(a.dot(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Poly2 {
        let pts = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        Poly2 {
            nodes: pts
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| Node2::plain(Point2::new(x, y), EdgeKey(i as u32)))
                .collect(),
        }
    }

    #[test]
    fn replace_section_between_edge_points() {
        let sq = square();
        let mut next = 100;
        let mut fresh = || {
            next += 1;
            EdgeKey(next)
        };
        // Remove the right side between (1, 0.25) and (1, 0.75), bulge out to (1.5, 0.5).
        let from = PerimPoint { edge: 1, t: 0.25 };
        let to = PerimPoint { edge: 1, t: 0.75 };
        let bulge = [Node2::plain(Point2::new(1.5, 0.5), EdgeKey(50))];
        let out = sq
            .replace_section(
                from,
                to,
                Edge {
                    key: EdgeKey(49),
                    share: None,
                },
                &bulge,
                &mut fresh,
            )
            .unwrap();
        let pts = out.points();
        assert_eq!(pts.len(), 7);
        assert!(out.is_valid(1e-9));
        assert!((out.area() - 1.125).abs() < 1e-12);
        // Kept edges keep their keys, cut ones get fresh keys.
        assert!(out.nodes.iter().any(|n| n.edge.key == EdgeKey(2)));
        assert!(!out.nodes.iter().any(|n| n.edge.key == EdgeKey(1)));
        assert!((sq.arc_len(from, to) - 0.5).abs() < 1e-12);
        assert!((sq.arc_len(to, from) - 3.5).abs() < 1e-12);
    }

    proptest::proptest! {
        /// The fast simplicity test agrees with `geom`'s on random polygons.
        #[test]
        fn fast_simplicity_matches_geom(c in proptest::collection::vec(-1.0f64..1.0, 6..24)) {
            let pts: Vec<Point2> = c.chunks_exact(2).map(|p| Point2::new(p[0], p[1])).collect();
            proptest::prop_assert_eq!(is_simple_fast(&pts, 1e-6), polygon2::is_simple(&pts, 1e-6));
        }
    }

    proptest::proptest! {
        /// `valid_points` answers as `geom`'s tests (anticlockwise and simple)
        /// and as `Poly2::is_valid` on random polygons, and on their reversals.
        #[test]
        fn valid_points_matches_geom(c in proptest::collection::vec(-1.0f64..1.0, 0..24)) {
            let mut pts: Vec<Point2> = c.chunks_exact(2).map(|p| Point2::new(p[0], p[1])).collect();
            for _ in 0..2 {
                let oracle = pts.len() >= 3
                    && polygon2::signed_area(&pts) > 0.0
                    && polygon2::is_simple(&pts, 1e-6);
                let poly = Poly2 {
                    nodes: pts.iter().map(|p| Node2::plain(*p, EdgeKey(0))).collect(),
                };
                proptest::prop_assert_eq!(valid_points(pts.iter().copied(), 1e-6), oracle);
                proptest::prop_assert_eq!(poly.is_valid(1e-6), oracle);
                pts.reverse();
            }
        }
    }

    proptest::proptest! {
        /// The sight index answers as the plain scan on random perimeters.
        #[test]
        fn sight_grid_matches_scan(
            c in proptest::collection::vec(-1.0f64..1.0, 40..200),
            q in proptest::collection::vec(-1.2f64..1.2, 40),
        ) {
            let poly = Poly2 {
                nodes: c
                    .chunks_exact(2)
                    .enumerate()
                    .map(|(i, p)| Node2::plain(Point2::new(p[0], p[1]), EdgeKey(i as u32)))
                    .collect(),
            };
            let grid = SightGrid::new(&poly);
            for s in q.chunks_exact(4) {
                let (a, b) = (Point2::new(s[0], s[1]), Point2::new(s[2], s[3]));
                for eps in [1e-9, 0.05] {
                    proptest::prop_assert_eq!(
                        grid.sight(&poly, &a, &b, eps, |e| e % 7 == 3),
                        poly.sight(&a, &b, eps, |e| e % 7 == 3)
                    );
                }
            }
        }
    }

    #[test]
    fn replace_section_between_vertices() {
        let sq = square();
        let mut fresh = || EdgeKey(7);
        // Remove vertex 2 (section from vertex 1 to vertex 3): a triangle remains.
        let out = sq
            .replace_section(
                PerimPoint::vertex(1),
                PerimPoint::vertex(3),
                Edge {
                    key: EdgeKey(9),
                    share: None,
                },
                &[],
                &mut fresh,
            )
            .unwrap();
        assert_eq!(out.len(), 3);
        assert!((out.area() - 0.5).abs() < 1e-12);
        assert_eq!(
            sq.section_edges(PerimPoint::vertex(1), PerimPoint::vertex(3)),
            vec![1, 2]
        );
    }
}
