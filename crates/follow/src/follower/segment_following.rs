//! Current segment following (P§3.4.2, Fig. 30): the current edge and the
//! direction along the perimeter.

use super::{Flow, Follower, Mode};
use crate::query::EdgeRef;
use geom::{Point3, Real};
use surface::EdgeKey;

/// Lengths of the anticlockwise and clockwise routes along a perimeter of
/// `n` edges from edge `from` to edge `to` (the edges passed on the way and
/// `to` itself).
pub(super) fn routes(from: usize, to: usize, n: usize, edges: &[EdgeRef]) -> (Real, Real) {
    let mut ccw = 0.0;
    let mut k = from;
    while k != to {
        k = (k + 1) % n;
        ccw += edges[k].length();
    }
    let mut cw = 0.0;
    let mut k = from;
    while k != to {
        k = (k + n - 1) % n;
        cw += edges[k].length();
    }
    (ccw, cw)
}

/// Cumulative edge lengths of a perimeter, for route lengths in O(1).
pub(super) struct Perimeter {
    /// `cum[k]`: total length of edges `0..k`.
    cum: Vec<Real>,
}

impl Perimeter {
    pub(super) fn new(edges: &[EdgeRef]) -> Self {
        let mut cum = Vec::with_capacity(edges.len() + 1);
        let mut total = 0.0;
        cum.push(0.0);
        for e in edges {
            total += e.length();
            cum.push(total);
        }
        Self { cum }
    }

    /// Distance from edge `from` to edge `to` via the perimeter, the shorter
    /// way (as [`routes`] counts it: the edges passed and `to` itself).
    pub(super) fn distance(&self, from: usize, to: usize) -> Real {
        let total = self.cum[self.cum.len() - 1];
        // Anticlockwise: edges from+1 ..= to (wrapping).
        let ccw = if to >= from {
            self.cum[to + 1] - self.cum[from + 1]
        } else {
            total - self.cum[from + 1] + self.cum[to + 1]
        };
        // Clockwise: edges to ..= from-1 (wrapping).
        let cw = if from >= to {
            self.cum[from] - self.cum[to]
        } else {
            total - self.cum[to] + self.cum[from]
        };
        ccw.min(cw)
    }
}

/// Whether the anticlockwise route from edge `from` to edge `to` is the
/// shorter (by length) of the two.
fn shorter_anticlockwise(from: usize, to: usize, n: usize, edges: &[EdgeRef]) -> bool {
    let (ccw, cw) = routes(from, to, n, edges);
    ccw <= cw
}

impl Follower {
    /// Current segment following (P§3.4.2).
    pub(super) fn segment_following(&mut self, cp: &Point3) -> Flow {
        let Some(seg) = self.state.segment else {
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        let Some(segment) = self.model.segment(seg) else {
            self.state.segment = None;
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        if segment.as_point().is_some() {
            return self.reach_segment(seg);
        }
        let edges = self.edges_of(seg);
        if edges.is_empty() || self.segment_complete(seg) {
            self.state.mode = Mode::Surface;
            self.state.path = None;
            return Flow::Again;
        }
        let n = edges.len();
        let position = |key: EdgeKey| edges.iter().position(|e| e.key == key);
        let current = self.state.edge.and_then(position);
        let current_ok = current.is_some_and(|i| !self.edge_complete(&edges[i]));
        let nearest = (0..n)
            .min_by(|&i, &j| {
                edges[i]
                    .distance_to(cp)
                    .total_cmp(&edges[j].distance_to(cp))
                    .then(i.cmp(&j))
            })
            .unwrap_or(0);
        let mut ce = match current {
            Some(i) if current_ok => i,
            _ => {
                // The incomplete edge closest to f via the perimeter.
                let perimeter = Perimeter::new(&edges);
                let pick = (0..n)
                    .filter(|&i| !self.edge_complete(&edges[i]))
                    .map(|i| (perimeter.distance(nearest, i), i))
                    .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                    .map(|(_, i)| i);
                let Some(i) = pick else {
                    self.state.mode = Mode::Surface;
                    self.state.path = None;
                    return Flow::Again;
                };
                if edges[i].length() <= 1e-9 {
                    // Zero-length edges are marked unclosable (P§3.4.2).
                    self.marks.unclosable_edges.insert(edges[i].key);
                    return Flow::Again;
                }
                self.set_current_edge(&edges[i]);
                self.state.follow = Some(edges[nearest].key);
                self.state.anticlockwise = shorter_anticlockwise(nearest, i, n, &edges);
                self.reset_progress();
                i
            }
        };
        let mut follow = if let Some(f) = self.state.follow.and_then(position) {
            f
        } else {
            self.state.follow = Some(edges[nearest].key);
            self.state.anticlockwise = shorter_anticlockwise(nearest, ce, n, &edges);
            self.reset_progress();
            nearest
        };
        // Advance the follow edge towards the current edge in the current
        // direction: the furthest within ρ.
        let rho = self.config.stray_m;
        let mut k = follow;
        let mut best = follow;
        for _ in 0..n {
            if edges[k].distance_to(cp) < rho {
                best = k;
            }
            if k == ce {
                break;
            }
            k = if self.state.anticlockwise {
                (k + 1) % n
            } else {
                (k + n - 1) % n
            };
        }
        if best != follow {
            follow = best;
            self.state.follow = Some(edges[follow].key);
            self.reset_progress();
        }
        if self.state.any_edge && follow != ce && !self.edge_complete(&edges[follow]) {
            self.set_current_edge(&edges[follow]);
            ce = follow;
        }
        if follow == ce {
            self.state.mode = Mode::Edge;
            return Flow::Again;
        }
        let e = edges[follow];
        let along = if self.state.anticlockwise {
            e.b - e.a
        } else {
            e.a - e.b
        };
        Flow::Go(self.towards_and_along(cp, &e, &along, &[seg]))
    }
}
