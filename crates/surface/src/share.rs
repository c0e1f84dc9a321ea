//! Forming shared edges (P§2.6, Fig. 17–19) and determining concavity
//! (P§2.6.1, Fig. 20–22).
//!
//! Between planar polygon segments S₁ and S₂ whose normals differ by more than μ,
//! a section `P` of S₁'s perimeter (from `p₁` to `p₂`) and a section `Q` of S₂'s
//! (from `q₁` to `q₂`) are both extended to a section `L = [l₁, l₂]` of the planes'
//! intersection line, where they become a pair of corresponding shared edges.
//! With the line directed along `d = n₁ × n₂` and parameter `t`, S₁'s new edge
//! runs `l₁ → l₂` along `σd` and S₂'s `l₂ → l₁`, where `σ = +1` for a convex and
//! `-1` for a concave pair (P§2.2, Fig. 2). The rules of P§2.6:
//!
//! * `p₁, p₂, q₁, q₂` and the vertices of `P` and `Q` lie within λ of the line and
//!   project into `L`; `p₁` and `q₂` project to `l₁`, `p₂` and `q₁` to `l₂`; at
//!   least one of `p₁, q₂` and one of `p₂, q₁` is a vertex (the candidate `t`
//!   values are the projections of vertices within λ of the line);
//! * corresponding corner vertices on the line may stand for `l₁` (or `l₂`) in
//!   their own segment, though they do not coincide;
//! * `l₁ ≠ l₂`, with the direction of the concavity;
//! * `p₁` sights `l₁`, `p₂` sights `l₂` (in S₁), `q₁` sights `l₂`, `q₂` sights `l₁`
//!   (in S₂), and `l₁` sights `l₂`, all relative to what remains of both
//!   perimeters (P§2.6 states the first four relative to the whole perimeter;
//!   see `check_and_build` for why);
//! * the only shared edges on `P` and `Q` are shared between S₁ and S₂, and each
//!   one's corresponding edge lies on the other section; some non-shared edge lies
//!   on `P` or `Q`;
//! * `P` and `Q` as long as possible: candidates are tried longest `L` first;
//! * (our addition) `L` is longer than the S₁–S₂ shared edges it replaces by
//!   [`MIN_GAIN_FRACTION`]`·λ`, so that a formation always makes progress instead
//!   of rebuilding the same edge;
//! * (our addition, `SurfaceConfig::snap_near_line_ends`, off by default)
//!   when no section pair passes between segments that share no edge yet,
//!   the pairs refused only because the perimeter they would leave is not
//!   valid are tried again with a section end vertex within `split`
//!   (λ·10⁻²) of its point on the line moved onto it (see `extend_to_line`).
//!
//! A vertex at `p₁` that already lies on the line (the end of an edge S₁ shares
//! with S₂, or a corner vertex) becomes the new edge's end itself (step 4).
//! Attempts repeat until no valid perimeter points are found (at most
//! [`MAX_FORM_ROUNDS`] rounds; each round converts a non-shared edge, so this is
//! only a backstop). Afterwards local and global ordering are checked (P§2.6).
//!
//! Concavity (P§2.6.1): neighbours keep the concavity of their shared edges.
//! Otherwise every pair of edges `(e₁, e₂)` whose parts within λ of the line
//! project onto overlapping intervals with opposite directions adds the overlap
//! length to the convex register when `e₁` runs along `d` and to the concave
//! register otherwise; the larger register decides, and equal registers leave it
//! undecided (no attempt in this update; redundancy check, P§2.9).

use crate::model::SurfaceModel;
use crate::perimeter::{Node2, PerimPoint, Poly2, SightGrid, cross2};
use crate::relations::OrderingFix;
use crate::segment::{Edge, EdgeKey, Node, SegmentId, Share};
use geom::{Line3, PlaneFrame, Point2, Real, Vector2};

/// Backstop on formation rounds per pair and update.
pub const MAX_FORM_ROUNDS: usize = 8;

/// Candidate section pairs examined per formation round (a backstop on the
/// quadratic search near apexes, where many vertices lie within λ of the line).
pub const MAX_PLAN_TRIES: usize = 512;

/// A formation must lengthen the shared edges between the pair by this
/// fraction of λ.
pub const MIN_GAIN_FRACTION: Real = 0.1;

/// Section pairs kept for the retry with vertices moved onto the line (see
/// the [module docs](self)), longest first.
pub const MAX_SNAP_RETRIES: usize = 16;

/// The concavity decision of P§2.6.1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Concavity {
    /// Each segment's centroid inside the other's plane (outside angle > 180°).
    Convex,
    /// Outside angle < 180°.
    Concave,
    /// Equal registers.
    Undecided,
}

/// What an attempt to form shared edges did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ShareOutcome {
    /// Nothing attempted (no non-shared edges near the line, or no line).
    Skipped,
    /// Concavity undecided.
    Undecided,
    /// Attempted; `n` pairs of shared edges formed.
    Formed(usize),
}

/// One polygon's view of the line: 2-D coordinates, line origin and direction.
struct View {
    frame: PlaneFrame,
    poly: Poly2,
    origin: Point2,
    dir: Vector2,
    /// Sight index of `poly`, built on first use (the perimeter does not
    /// change while a view lives).
    grid: std::cell::OnceCell<SightGrid>,
    /// `t` and `h` of every vertex, computed on first use.
    vth: std::cell::OnceCell<(Vec<Real>, Vec<Real>)>,
}

impl View {
    fn new(model: &SurfaceModel, id: SegmentId, line: &Line3) -> Option<Self> {
        let p = model.poly(id)?;
        let frame = p.frame();
        let poly = Poly2::from_polygon(p, &frame);
        let origin = frame.to_2d(&line.point);
        let d = Vector2::new(line.dir.dot(&frame.u), line.dir.dot(&frame.v));
        let len = d.norm();
        if len < 0.5 {
            return None;
        }
        Some(Self {
            frame,
            poly,
            origin,
            dir: d / len,
            grid: std::cell::OnceCell::new(),
            vth: std::cell::OnceCell::new(),
        })
    }

    /// `(t, h)` of each vertex: the same values as `t(&p)` and `h(&p)`.
    fn vertex_th(&self) -> (&[Real], &[Real]) {
        let (t, h) = self.vth.get_or_init(|| {
            let ps = &self.poly.nodes;
            (
                ps.iter().map(|n| self.t(&n.p)).collect(),
                ps.iter().map(|n| self.h(&n.p)).collect(),
            )
        });
        (t, h)
    }

    /// [`Poly2::sight`] through the view's sight index.
    fn sight(&self, a: &Point2, b: &Point2, eps: Real, skip: impl Fn(usize) -> bool) -> bool {
        self.grid
            .get_or_init(|| SightGrid::new(&self.poly))
            .sight(&self.poly, a, b, eps, skip)
    }

    fn t(&self, p: &Point2) -> Real {
        (p - self.origin).dot(&self.dir)
    }

    fn h(&self, p: &Point2) -> Real {
        cross2(&self.dir, &(p - self.origin))
    }

    fn at(&self, t: Real) -> Point2 {
        self.origin + self.dir * t
    }

    /// The part of edge `e` within `lambda` of the line, as parameters along it.
    fn strip_part(&self, e: usize, lambda: Real) -> Option<(Real, Real)> {
        let (a, b) = self.poly.seg(e);
        let (ha, hb) = (self.h(&a), self.h(&b));
        let (mut lo, mut hi): (Real, Real) = (0.0, 1.0);
        let dh = hb - ha;
        if dh.abs() < 1e-300 {
            if ha.abs() >= lambda {
                return None;
            }
        } else {
            let s1 = (lambda - ha) / dh;
            let s2 = (-lambda - ha) / dh;
            lo = lo.max(s1.min(s2));
            hi = hi.min(s1.max(s2));
        }
        (hi > lo).then_some((lo, hi))
    }
}

/// A section found on one perimeter.
#[derive(Clone, Copy, Debug)]
struct Section {
    start: PerimPoint,
    end: PerimPoint,
    length: Real,
}

/// The perimeter points of `view.poly` where `t = t_start`, within λ of the
/// line: where the sections of [`sections`] from `t_start` begin. They depend
/// on `t_start` only, so a search over many ends computes them once.
fn starts_at(view: &View, t_start: Real, lambda: Real, eps: Real) -> Vec<PerimPoint> {
    let poly = &view.poly;
    let in_strip = |p: &Point2| view.h(p).abs() < lambda;
    let (vt, vh) = view.vertex_th();
    let n = poly.len();
    let mut starts = Vec::new();
    for e in 0..n {
        let (ta, tb) = (vt[e], vt[(e + 1) % n]);
        if (ta - t_start).abs() <= eps {
            if vh[e].abs() < lambda {
                starts.push(PerimPoint::vertex(e));
            }
        } else if (ta - t_start) * (tb - t_start) < 0.0 && (tb - t_start).abs() > eps {
            let (a, b) = poly.seg(e);
            let u = (t_start - ta) / (tb - ta);
            let x = a + (b - a) * u;
            if in_strip(&x) {
                starts.push(PerimPoint { edge: e, t: u });
            }
        }
    }
    starts
}

/// Sections of `view.poly` starting at `starts` (those of [`starts_at`] for
/// `t_start`) and ending where `t = t_end`, lying within λ of the line and
/// projecting into the range.
/// Written into `out` (cleared first): the search computes them for every
/// candidate, and reuses two lists.
fn sections(
    view: &View,
    starts: &[PerimPoint],
    t_start: Real,
    t_end: Real,
    lambda: Real,
    eps: Real,
    out: &mut Vec<Section>,
) {
    out.clear();
    let poly = &view.poly;
    let n = poly.len();
    let lo = t_start.min(t_end) - eps;
    let hi = t_start.max(t_end) + eps;
    // `t` and `h` of each point are computed once (vertices: from the view's
    // table, which holds the same values).
    let (vt, vh) = view.vertex_th();
    for &start in starts {
        let (mut e, mut u0) = (start.edge, start.t);
        for step in 0..=n {
            if step > 0 && e == start.edge && u0 <= start.t {
                break; // back at the start
            }
            let (a, b) = poly.seg(e);
            let pa = a + (b - a) * u0;
            let (tpa, hpa) = (view.t(&pa), view.h(&pa));
            // In the strip and in the range (false for NaN, as before).
            let inside = hpa.abs() < lambda && tpa >= lo && tpa <= hi;
            if !inside {
                break;
            }
            if step > 0 && (tpa - t_end).abs() <= eps {
                out.push(Section {
                    start,
                    end: PerimPoint::vertex(e),
                    length: poly.arc_len(start, PerimPoint::vertex(e)),
                });
            }
            // Largest u1 such that [u0, u1] stays in the strip and range.
            let mut u1: Real = 1.0;
            let (ha, hb) = (hpa, vh[(e + 1) % n]);
            if hb.abs() >= lambda {
                let target = lambda.copysign(hb);
                let f = (target - ha) / (hb - ha);
                u1 = u1.min(u0 + (1.0 - u0) * f * (1.0 - 1e-9));
            }
            let (ta, tb) = (tpa, vt[(e + 1) % n]);
            if tb > hi || tb < lo {
                let bound = if tb > hi { hi } else { lo };
                let f = (bound - ta) / (tb - ta);
                u1 = u1.min(u0 + (1.0 - u0) * f);
            }
            // Ends on this piece (skip the start itself).
            let dt = tb - ta;
            if dt.abs() > 0.0 {
                let f = (t_end - ta) / dt;
                let u = u0 + (1.0 - u0) * f;
                if f > 0.0 && u <= u1 + 1e-12 && u < 1.0 && (ta - t_end).abs() > eps {
                    let end = poly.snap(PerimPoint { edge: e, t: u }, eps);
                    if !(end.edge == start.edge && (end.t - start.t).abs() < 1e-12) {
                        out.push(Section {
                            start,
                            end,
                            length: poly.arc_len(start, end),
                        });
                    }
                }
            }
            if u1 < 1.0 {
                break;
            }
            e = (e + 1) % n;
            u0 = 0.0;
        }
    }
    out.sort_by(|x, y| y.length.total_cmp(&x.length));
}

/// The union of the t-ranges of the parts of `view`'s edges within λ of the
/// line, as sorted disjoint intervals, each piece widened by `eps`. A section
/// of [`sections`] is a connected path through such parts from `t ≈ t_start`
/// to `t ≈ t_end` (each within `eps`), so its t-values fill the range between
/// them: no section exists unless one interval holds that range (see
/// [`covers`]). This only decides which candidates are searched, never what
/// a search finds.
fn strip_cover(view: &View, lambda: Real, eps: Real) -> Vec<(Real, Real)> {
    let mut pieces: Vec<(Real, Real)> = (0..view.poly.len())
        .filter_map(|e| {
            let (lo, hi) = view.strip_part(e, lambda)?;
            let (a, b) = view.poly.seg(e);
            let (ta, tb) = (view.t(&(a + (b - a) * lo)), view.t(&(a + (b - a) * hi)));
            Some((ta.min(tb) - eps, ta.max(tb) + eps))
        })
        .collect();
    pieces.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: Vec<(Real, Real)> = Vec::with_capacity(pieces.len());
    for (lo, hi) in pieces {
        match out.last_mut() {
            Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
            _ => out.push((lo, hi)),
        }
    }
    out
}

/// `true` when one interval of `cover` holds `[min(t0, t1) + eps, max(t0, t1) − eps]`.
fn covers(cover: &[(Real, Real)], t0: Real, t1: Real, eps: Real) -> bool {
    let (lo, hi) = (t0.min(t1) + eps, t0.max(t1) - eps);
    if hi <= lo {
        return true;
    }
    cover.iter().any(|&(a, b)| a <= lo && hi <= b)
}

/// A candidate endpoint value of `L`: the parameter in each segment's view.
#[derive(Clone, Copy, Debug)]
struct Anchor {
    t1: Real,
    t2: Real,
}

/// Why [`SurfaceModel::check_and_build`] found no formation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refusal {
    /// A rule on the sections themselves (vertices, progress, shared edges):
    /// moving `L`'s ends cannot change it.
    Sections,
    /// A sight test.
    Sight,
    /// The perimeter the formation would leave is not valid.
    Build,
}

/// The buffers of [`SurfaceModel::check_and_build`], kept over one search:
/// the edges of `P` and `Q` and their membership masks.
#[derive(Default)]
struct CheckScratch {
    edges1: Vec<usize>,
    edges2: Vec<usize>,
    on1: Vec<bool>,
    on2: Vec<bool>,
}

/// What one formation changes.
struct Plan {
    nodes1: Vec<Node>,
    nodes2: Vec<Node>,
}

impl SurfaceModel {
    /// The concavity between `s1` and `s2` along `line` (directed `n₁ × n₂`),
    /// from their shared edges when neighbours, else from the overlap registers.
    pub(crate) fn concavity(&self, s1: SegmentId, s2: SegmentId, line: &Line3) -> Concavity {
        if let Some(p) = self.poly(s1) {
            let n = p.nodes.len();
            for i in 0..n {
                if p.nodes[i].edge.share.is_some_and(|sh| sh.neighbour == s2) {
                    let d = p.nodes[(i + 1) % n].position - p.nodes[i].position;
                    return if d.dot(&line.dir) > 0.0 {
                        Concavity::Convex
                    } else {
                        Concavity::Concave
                    };
                }
            }
        }
        let (Some(v1), Some(v2)) = (View::new(self, s1, line), View::new(self, s2, line)) else {
            return Concavity::Undecided;
        };
        let (convex, concave) = registers(&v1, &v2, self.tol.lambda);
        if convex > concave {
            Concavity::Convex
        } else if concave > convex {
            Concavity::Concave
        } else {
            Concavity::Undecided
        }
    }

    /// P§2.3 step 4 for one pair: attempt to form shared edges between `s1` and `s2`.
    pub(crate) fn form_shared_edges(&mut self, s1: SegmentId, s2: SegmentId) -> ShareOutcome {
        let tol = self.tol;
        let Some(line) = self.line_between(s1, s2) else {
            return ShareOutcome::Skipped;
        };
        if !self.near_line(s1, &line) || !self.near_line(s2, &line) {
            return ShareOutcome::Skipped;
        }
        let sigma = match self.concavity(s1, s2, &line) {
            Concavity::Convex => 1.0,
            Concavity::Concave => -1.0,
            Concavity::Undecided => return ShareOutcome::Undecided,
        };
        if !self.room_for_shared_edge(s1, s2, &line) {
            return ShareOutcome::Formed(0);
        }
        let mut formed = 0;
        for _ in 0..MAX_FORM_ROUNDS {
            let Some(line) = self.line_between(s1, s2) else {
                break;
            };
            let ok = self.attempt(|m| {
                let plan = m.plan_shared_edge(s1, s2, &line, sigma)?;
                if let Some(p) = m.poly_mut(s1) {
                    p.nodes = plan.nodes1;
                }
                if let Some(p) = m.poly_mut(s2) {
                    p.nodes = plan.nodes2;
                }
                m.validate_touched().ok()?;
                Some(())
            });
            if ok.is_none() {
                break;
            }
            formed += 1;
            // Ordering (P§2.6): dissolve what breaks it and stop for this update.
            let broke = self.run(|m| {
                let a = m.enforce_ordering(s1, OrderingFix::Forming { with: s2 });
                let b = m.enforce_ordering(s2, OrderingFix::Forming { with: s1 });
                a || b
            });
            if broke {
                self.ctx.blocked.insert((s1.min(s2), s1.max(s2)));
                break;
            }
            if !self.near_line(s1, &line) || !self.near_line(s2, &line) {
                break;
            }
        }
        let _ = tol;
        ShareOutcome::Formed(formed)
    }

    /// A necessary condition for a new pair of shared edges: along the line,
    /// the stretch where both perimeters come within λ of it, minus the stretch
    /// already covered by their shared edges, is at least `MIN_GAIN_FRACTION·λ`
    /// long (every `L` lies where both perimeters project, and must add that much).
    /// Skips the full search of [`Self::plan_shared_edge`] between neighbours
    /// whose shared edges are complete.
    fn room_for_shared_edge(&self, s1: SegmentId, s2: SegmentId, line: &Line3) -> bool {
        let lambda = self.tol.lambda;
        let (Some(v1), Some(v2)) = (View::new(self, s1, line), View::new(self, s2, line)) else {
            return false;
        };
        // Edges shared with a third segment can be on no section (P§2.6: the
        // only shared edges on P and Q are shared between S₁ and S₂).
        let strip = |v: &View, shared_only: bool| -> Vec<(Real, Real)> {
            let mut iv: Vec<(Real, Real)> = (0..v.poly.len())
                .filter(|&e| match v.poly.edge(e).share {
                    Some(sh) => sh.neighbour == s1 || sh.neighbour == s2,
                    None => !shared_only,
                })
                .filter_map(|e| {
                    let (u0, u1) = v.strip_part(e, lambda)?;
                    let (a, b) = v.poly.seg(e);
                    let (ta, tb) = (v.t(&(a + (b - a) * u0)), v.t(&(a + (b - a) * u1)));
                    Some((ta.min(tb), ta.max(tb)))
                })
                .collect();
            iv.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut merged: Vec<(Real, Real)> = Vec::new();
            for (a, b) in iv {
                match merged.last_mut() {
                    Some(last) if a <= last.1 => last.1 = last.1.max(b),
                    _ => merged.push((a, b)),
                }
            }
            merged
        };
        let (c1, c2) = (strip(&v1, false), strip(&v2, false));
        let shared = strip(&v1, true);
        let mut free = 0.0;
        for &(a0, a1) in &c1 {
            for &(b0, b1) in &c2 {
                let (lo, hi) = (a0.max(b0), a1.min(b1));
                if hi <= lo {
                    continue;
                }
                let covered: Real = shared
                    .iter()
                    .map(|&(s0, s1)| (hi.min(s1) - lo.max(s0)).max(0.0))
                    .sum();
                free += (hi - lo) - covered;
            }
        }
        free >= MIN_GAIN_FRACTION * lambda
    }

    /// `true` when `s` has a non-shared edge within λ of `line` (P§2.3 step 4).
    pub(crate) fn near_line(&self, s: SegmentId, line: &Line3) -> bool {
        let Some(p) = self.poly(s) else { return false };
        let n = p.nodes.len();
        let lambda = self.tol.lambda;
        (0..n).any(|i| {
            if p.nodes[i].edge.share.is_some() {
                return false;
            }
            let a = p.nodes[i].position;
            let b = p.nodes[(i + 1) % n].position;
            let seg = geom::Segment3::new(a, b);
            let far = geom::Segment3::new(line.point_at(-1e6), line.point_at(1e6));
            geom::line::distance_segment_segment(&seg, &far) < lambda
        })
    }

    /// Find the best valid formation (rules in the [module docs](self)).
    fn plan_shared_edge(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
        line: &Line3,
        sigma: Real,
    ) -> Option<Plan> {
        let tol = self.tol;
        let v1 = View::new(self, s1, line)?;
        let v2 = View::new(self, s2, line)?;
        // Anchors: vertices within λ of the line; corresponding corner pairs on it.
        let mut anchors: Vec<Anchor> = Vec::new();
        for v in [&v1, &v2] {
            for node in &v.poly.nodes {
                if v.h(&node.p).abs() < tol.lambda {
                    let t = v.t(&node.p);
                    anchors.push(Anchor { t1: t, t2: t });
                }
            }
        }
        for a in &v1.poly.nodes {
            let Some(cid) = a.corner else { continue };
            if let Some(b) = v2.poly.nodes.iter().find(|b| b.corner == Some(cid)) {
                anchors.push(Anchor {
                    t1: v1.t(&a.p),
                    t2: v2.t(&b.p),
                });
            }
        }
        anchors.sort_by(|a, b| a.t1.total_cmp(&b.t1).then(a.t2.total_cmp(&b.t2)));
        anchors.dedup_by(|a, b| (a.t1 - b.t1).abs() <= tol.eps && (a.t2 - b.t2).abs() <= tol.eps);
        // A candidate can only have sections where each perimeter's pieces in
        // the strip cover its t-range (see `strip_cover`): the others are
        // dropped before the O(n) section search.
        let (cover1, cover2) = (
            strip_cover(&v1, tol.lambda, tol.eps),
            strip_cover(&v2, tol.lambda, tol.eps),
        );
        let mut candidates: Vec<(Real, usize, usize)> = Vec::new();
        for (i, a) in anchors.iter().enumerate() {
            for (j, b) in anchors.iter().enumerate() {
                if sigma * (b.t1 - a.t1) > tol.eps
                    && sigma * (b.t2 - a.t2) > tol.eps
                    && covers(&cover1, a.t1, b.t1, tol.eps)
                    && covers(&cover2, b.t2, a.t2, tol.eps)
                {
                    candidates.push(((b.t1 - a.t1).abs(), i, j));
                }
            }
        }
        // Longest first; ties in push order, i.e. by (i, j) (as a stable sort).
        candidates
            .sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        // Section starts per anchor (P from a's t₁, Q from b's t₂), found once.
        let mut starts1: Vec<Option<Vec<PerimPoint>>> = vec![None; anchors.len()];
        let mut starts2: Vec<Option<Vec<PerimPoint>>> = vec![None; anchors.len()];
        let mut tries = 0;
        let mut scratch = CheckScratch::default();
        let (mut secs1, mut secs2) = (Vec::new(), Vec::new());
        let mut retry: Vec<(Section, Section, Anchor, Anchor)> = Vec::new();
        let keep = self.config().snap_near_line_ends && !self.are_neighbours(s1, s2);
        'search: for (_, i, j) in candidates {
            let (a, b) = (anchors[i], anchors[j]);
            let from1 = starts1[i].get_or_insert_with(|| starts_at(&v1, a.t1, tol.lambda, tol.eps));
            sections(&v1, from1, a.t1, b.t1, tol.lambda, tol.eps, &mut secs1);
            if secs1.is_empty() {
                continue;
            }
            let from2 = starts2[j].get_or_insert_with(|| starts_at(&v2, b.t2, tol.lambda, tol.eps));
            sections(&v2, from2, b.t2, a.t2, tol.lambda, tol.eps, &mut secs2);
            for sec1 in secs1.iter().take(4) {
                for sec2 in secs2.iter().take(4) {
                    tries += 1;
                    if tries > MAX_PLAN_TRIES {
                        break 'search;
                    }
                    let (ends, sections) = ((a, b), (*sec1, *sec2));
                    match self.check_and_build(
                        s1,
                        s2,
                        (&v1, &v2),
                        line,
                        sections,
                        ends,
                        false,
                        &mut scratch,
                    ) {
                        Ok(plan) => return Some(plan),
                        Err(Refusal::Build) if keep && retry.len() < MAX_SNAP_RETRIES => {
                            retry.push((*sec1, *sec2, a, b));
                        }
                        Err(_) => {}
                    }
                }
            }
        }
        // Our addition (`SurfaceConfig::snap_near_line_ends`, issue 45): the
        // pairs refused only because the perimeter they leave is not valid
        // are tried again with a section end vertex within `split` of its
        // point on the line moved onto it (`extend_to_line`). Tried only when
        // nothing else formed, so every formation the rules above allow is
        // unchanged, and only between segments that share no edge yet (the
        // case of a relation dissolved and never formed again; pulling the
        // ends of an existing shared edge along the line, tried before, left
        // point3's block2 run with shared edges along 91.5 % instead of
        // 95.2 %).
        for (sec1, sec2, a, b) in retry {
            let sections = (sec1, sec2);
            if let Ok(plan) = self.check_and_build(
                s1,
                s2,
                (&v1, &v2),
                line,
                sections,
                (a, b),
                true,
                &mut scratch,
            ) {
                return Some(plan);
            }
        }
        None
    }

    /// The rules of the [module docs](self) on one pair of sections with `L`
    /// from anchor `a` to anchor `b`, and the formation they allow.
    #[allow(clippy::too_many_arguments)]
    fn check_and_build(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
        (v1, v2): (&View, &View),
        line: &Line3,
        (sec1, sec2): (Section, Section),
        (a, b): (Anchor, Anchor),
        may_snap: bool,
        scratch: &mut CheckScratch,
    ) -> Result<Plan, Refusal> {
        let tol = self.tol;
        let (p1, p2) = (sec1.start, sec1.end);
        let (q1, q2) = (sec2.start, sec2.end);
        // At least one of p₁, q₂ and one of p₂, q₁ is a vertex.
        if !(p1.is_vertex() || q2.is_vertex()) || !(p2.is_vertex() || q1.is_vertex()) {
            return Err(Refusal::Sections);
        }
        // The rules below only reject (without side effects), so their order
        // does not change the outcome: the progress rule, which needs P's
        // edges only, comes before the masks and the shared-edge walk. Most
        // sections fail one of them, so their lists live in `scratch`.
        let CheckScratch {
            edges1,
            edges2,
            on1,
            on2,
        } = scratch;
        v1.poly.section_edges_into(p1, p2, edges1);
        // Progress: the new shared edge must be longer than the S₁–S₂ shared edges
        // it replaces by at least λ/10 (otherwise a formation could rebuild the
        // same edge with the same connecting edges round after round).
        let replaced: Real = edges1
            .iter()
            .filter(|&&e| v1.poly.is_shared(e))
            .map(|&e| v1.poly.edge_len(e))
            .sum();
        if (b.t1 - a.t1).abs() < replaced + MIN_GAIN_FRACTION * tol.lambda {
            return Err(Refusal::Sections);
        }
        // Shared edges on P and Q: only with each other, whole, corresponding.
        v2.poly.section_edges_into(q1, q2, edges2);
        // Membership of P's and Q's edges, by edge index.
        let mask = |n: usize, edges: &[usize], m: &mut Vec<bool>| {
            m.clear();
            m.resize(n, false);
            for &e in edges {
                m[e % n.max(1)] = true;
            }
        };
        mask(v1.poly.len(), edges1, on1);
        mask(v2.poly.len(), edges2, on2);
        let (edges1, edges2, on1, on2) = (&edges1[..], &edges2[..], &on1[..], &on2[..]);
        let mut plain = false;
        for (view, edges, from, to, other, other_on, other_view) in [
            (v1, edges1, p1, p2, s2, on2, v2),
            (v2, edges2, q1, q2, s1, on1, v1),
        ] {
            for &e in edges {
                match view.poly.edge(e).share {
                    None => plain = true,
                    Some(sh) => {
                        if sh.neighbour != other {
                            return Err(Refusal::Sections);
                        }
                        let cut = (e == from.edge % view.poly.len() && from.t > 0.0)
                            || (e == to.edge % view.poly.len() && to.t > 0.0);
                        if cut {
                            return Err(Refusal::Sections);
                        }
                        let partner = other_view
                            .poly
                            .nodes
                            .iter()
                            .position(|x| x.edge.share.is_some_and(|s| s.pair == sh.pair))
                            .ok_or(Refusal::Sections)?;
                        if !other_on[partner] {
                            return Err(Refusal::Sections);
                        }
                    }
                }
            }
        }
        if !plain {
            return Err(Refusal::Sections);
        }
        // Points of L in each view.
        let (l1a, l2a) = (v1.at(a.t1), v1.at(b.t1));
        let (l1b, l2b) = (v2.at(a.t2), v2.at(b.t2));
        let (xp1, xp2) = (v1.poly.point_at(p1), v1.poly.point_at(p2));
        let (xq1, xq2) = (v2.poly.point_at(q1), v2.poly.point_at(q2));
        // Sight of the new connecting edges, relative to what remains of each
        // perimeter once P and Q are removed. P§2.6 says "relative to the
        // perimeter", for the purpose that "the new edges formed will not cross
        // the resulting perimeters"; edges of P and Q are not part of those.
        // Against the whole perimeter, a vertex a fraction of a millimetre off
        // the line (range noise) whose next edge runs along the line fails
        // sight of its own projection, and a shared edge once unshared there
        // can never be formed again. The result is validated in any case.
        let sees1 = |x: &Point2, y: &Point2| v1.sight(x, y, tol.eps, |e| on1[e]);
        let sees2 = |x: &Point2, y: &Point2| v2.sight(x, y, tol.eps, |e| on2[e]);
        if !sees1(&xp1, &l1a) || !sees1(&xp2, &l2a) || !sees2(&xq1, &l2b) || !sees2(&xq2, &l1b) {
            return Err(Refusal::Sight);
        }
        // l₁ sights l₂ relative to what remains of each perimeter.
        if !sees1(&l1a, &l2a) || !sees2(&l1b, &l2b) {
            return Err(Refusal::Sight);
        }
        let (t_l1a, t_l2a) = (a.t1, b.t1);
        let (t_l1b, t_l2b) = (a.t2, b.t2);
        let tols = (tol.eps, tol.split);
        // With vertices moved onto the line (`may_snap`), the edits are
        // tried first with throwaway keys, so that a refusal takes no id
        // from the model.
        if may_snap
            && !(snaps_onto_line(v1, (p1, p2), (t_l1a, l1a), (t_l2a, l2a), s2, line, tols)
                && snaps_onto_line(v2, (q1, q2), (t_l2b, l2b), (t_l1b, l1b), s1, line, tols))
        {
            return Err(Refusal::Build);
        }
        // Build.
        let pair = self.new_pair();
        let key1 = self.fresh_key();
        let key2 = self.fresh_key();
        let shared1 = Edge {
            key: key1,
            share: Some(Share {
                neighbour: s2,
                pair,
            }),
        };
        let shared2 = Edge {
            key: key2,
            share: Some(Share {
                neighbour: s1,
                pair,
            }),
        };
        let nodes1 = {
            let mut fresh = Self::key_source(&mut self.ids.edge);
            extend_to_line(
                v1,
                p1,
                p2,
                (t_l1a, l1a),
                (t_l2a, l2a),
                shared1,
                line,
                tols,
                may_snap,
                &mut fresh,
            )
            .ok_or(Refusal::Build)?
        };
        let nodes2 = {
            let mut fresh = Self::key_source(&mut self.ids.edge);
            extend_to_line(
                v2,
                q1,
                q2,
                (t_l2b, l2b),
                (t_l1b, l1b),
                shared2,
                line,
                tols,
                may_snap,
                &mut fresh,
            )
            .ok_or(Refusal::Build)?
        };
        Ok(Plan { nodes1, nodes2 })
    }
}

/// `true` when [`extend_to_line`] with `may_snap` succeeds, tried with
/// throwaway keys and pair id (a shared edge with `neighbour`).
fn snaps_onto_line(
    view: &View,
    (from, to): (PerimPoint, PerimPoint),
    l_from: (Real, Point2),
    l_to: (Real, Point2),
    neighbour: SegmentId,
    line: &Line3,
    tols: (Real, Real),
) -> bool {
    let mut k = u32::MAX;
    let mut throwaway = || {
        k -= 1;
        EdgeKey(k)
    };
    let shared = Edge {
        key: EdgeKey(u32::MAX),
        share: Some(Share {
            neighbour,
            pair: crate::segment::PairId(u32::MAX),
        }),
    };
    extend_to_line(
        view,
        from,
        to,
        l_from,
        l_to,
        shared,
        line,
        tols,
        true,
        &mut throwaway,
    )
    .is_some()
}

/// Replace the section `from → to` of `view.poly` by `from → l_from → l_to → to`
/// with `l_from → l_to` the shared edge; vertices already on the line (within
/// eps) are used instead of new ones. Returns 3-D nodes with the line points
/// placed exactly on `line`.
///
/// (Our addition, issue 45, with `may_snap`: see
/// `SurfaceConfig::snap_near_line_ends`.) When that perimeter is not valid
/// and an end of the section is a vertex off its line point by more than
/// `eps` but no more than `split` (λ·10⁻²), the vertex itself is moved onto
/// the line and becomes the shared edge's end (first the `from` end, then
/// `to`, then both), unless its edge outside the section is shared. A vertex
/// that close to its own projection would otherwise be joined to it by an
/// edge a few `eps` long, and the perimeter fails validity (edges closer than
/// `eps`): on the scripted noisy cube, seed 3, the −x and −y faces' shared
/// edge was dissolved, and every later formation between the two was refused
/// this way, with end vertices 5.8 and 6.7 µm (ε = 5 µm) from their points on
/// the line. Formations that are valid without the move are unchanged.
#[allow(clippy::too_many_arguments)]
fn extend_to_line(
    view: &View,
    from: PerimPoint,
    to: PerimPoint,
    l_from: (Real, Point2),
    l_to: (Real, Point2),
    shared: Edge,
    line: &Line3,
    (eps, split): (Real, Real),
    may_snap: bool,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Option<Vec<Node>> {
    let ends = (from, to, l_from, l_to);
    let tols = (eps, split);
    if let Some(nodes) = build_to_line(view, ends, shared, line, tols, (false, false), fresh) {
        return Some(nodes);
    }
    if !may_snap {
        return None;
    }
    // Only a vertex whose edge outside the section is not shared moves (a
    // shared edge's ends stay where its partner's are).
    let poly = &view.poly;
    let near = |p: PerimPoint, l: Point2, outside: usize| {
        let d = (poly.point_at(p) - l).norm();
        p.is_vertex() && d > eps && d <= split && poly.edge(outside).share.is_none()
    };
    let snap_from = near(from, l_from.1, poly.prev(from.edge));
    let snap_to = near(to, l_to.1, to.edge);
    // The moves are tried with throwaway edge keys, so that a refusal takes
    // no key from the model (its keys stay those of a model without this
    // fallback); the valid one is built again with `fresh`.
    let mut scratch_key = u32::MAX;
    let mut throwaway = || {
        scratch_key -= 1;
        EdgeKey(scratch_key)
    };
    let snap = [(true, false), (false, true), (true, true)]
        .into_iter()
        .filter(|&(f, t)| (!f || snap_from) && (!t || snap_to))
        .find(|&snap| {
            build_to_line(view, ends, shared, line, tols, snap, &mut throwaway).is_some()
        })?;
    build_to_line(view, ends, shared, line, tols, snap, fresh)
}

/// [`extend_to_line`] with the `from` and `to` vertices moved onto the line
/// where `snap` says so.
#[allow(clippy::type_complexity)]
fn build_to_line(
    view: &View,
    (from, to, (t_from, l_from), (t_to, l_to)): (
        PerimPoint,
        PerimPoint,
        (Real, Point2),
        (Real, Point2),
    ),
    shared: Edge,
    line: &Line3,
    (eps, split): (Real, Real),
    (snap_from, snap_to): (bool, bool),
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Option<Vec<Node>> {
    let moved;
    let poly = if snap_from || snap_to {
        let mut p = view.poly.clone();
        let n = p.len();
        for (snap, at, l) in [(snap_from, from, l_from), (snap_to, to, l_to)] {
            let node = &mut p.nodes[at.edge % n];
            if snap && node.corner.is_none() {
                node.p = l;
            }
        }
        moved = p;
        &moved
    } else {
        &view.poly
    };
    let mut from_on = snap_from || (poly.point_at(from) - l_from).norm() <= eps;
    let mut to_on = snap_to || (poly.point_at(to) - l_to).norm() <= eps;
    // A vertex on the line that ends an edge shared with another neighbour cannot
    // start this shared edge without a corner (P§2.7 forms those later): the new
    // edge starts a short step δ along the line instead, joined by a short edge.
    let other = shared.share.map(|s| s.neighbour);
    let foreign = |sh: Option<Share>| sh.is_some_and(|s| Some(s.neighbour) != other);
    let (mut t_from, mut l_from, mut t_to, mut l_to) = (t_from, l_from, t_to, l_to);
    let step = split.min(0.25 * (t_to - t_from).abs());
    let dir = (t_to - t_from).signum();
    if from_on
        && from.is_vertex()
        && poly.nodes[from.edge % poly.len()].corner.is_none()
        && foreign(poly.edge(poly.prev(from.edge)).share)
    {
        from_on = false;
        t_from += dir * step;
        l_from = view.at(t_from);
    }
    if to_on
        && to.is_vertex()
        && poly.nodes[to.edge % poly.len()].corner.is_none()
        && foreign(poly.edge(to.edge).share)
    {
        to_on = false;
        t_to -= dir * step;
        l_to = view.at(t_to);
    }
    let mut inserted = Vec::new();
    let from_edge;
    if from_on {
        from_edge = shared;
    } else {
        from_edge = Edge {
            key: fresh(),
            share: None,
        };
        inserted.push(Node2 {
            p: l_from,
            corner: None,
            edge: shared,
        });
    }
    if !to_on {
        inserted.push(Node2::plain(l_to, fresh()));
    }
    let next = poly
        .replace_section(from, to, from_edge, &inserted, fresh)
        .ok()?;
    if !next.is_valid(eps) {
        return None;
    }
    let m = next.len();
    let from_idx = m - inserted.len() - 1;
    let mut nodes = next.to_nodes(&view.frame);
    // Exact positions on the line: the shared edge's two ends.
    let l_from_idx = if from_on { from_idx } else { from_idx + 1 };
    let l_to_idx = if to_on { 0 } else { (l_from_idx + 1) % m };
    let keep_corner = |n: &Node| n.corner.is_some();
    if !(from_on && keep_corner(&nodes[l_from_idx])) {
        nodes[l_from_idx].position = line.point_at(t_from);
    }
    if !(to_on && keep_corner(&nodes[l_to_idx])) {
        nodes[l_to_idx].position = line.point_at(t_to);
    }
    Some(nodes)
}

/// The overlap registers of P§2.6.1: (convex, concave).
fn registers(v1: &View, v2: &View, lambda: Real) -> (Real, Real) {
    let parts = |v: &View| -> Vec<(Real, Real, Real)> {
        (0..v.poly.len())
            .filter_map(|e| {
                let (s0, s1) = v.strip_part(e, lambda)?;
                let (a, b) = v.poly.seg(e);
                let (ta, tb) = (v.t(&(a + (b - a) * s0)), v.t(&(a + (b - a) * s1)));
                let dir = (tb - ta).signum();
                (dir != 0.0 && (tb - ta).abs() > 0.0).then_some((ta.min(tb), ta.max(tb), dir))
            })
            .collect()
    };
    let (p1, p2) = (parts(v1), parts(v2));
    let (mut convex, mut concave) = (0.0, 0.0);
    for &(a0, a1, da) in &p1 {
        for &(b0, b1, db) in &p2 {
            if da == db {
                continue;
            }
            let overlap = a1.min(b1) - a0.max(b0);
            if overlap > 0.0 {
                if da > 0.0 {
                    convex += overlap;
                } else {
                    concave += overlap;
                }
            }
        }
    }
    (convex, concave)
}

/// The registers of two segments (figure reproductions, [`crate::testing`]).
pub(crate) fn registers_between(
    model: &SurfaceModel,
    s1: SegmentId,
    s2: SegmentId,
) -> Option<(Real, Real)> {
    let line = model.line_between(s1, s2)?;
    let v1 = View::new(model, s1, &line)?;
    let v2 = View::new(model, s2, &line)?;
    Some(registers(&v1, &v2, model.tol.lambda))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perimeter::Node2;
    use geom::{Point3, Vector3};
    use rand::{RngExt, SeedableRng};

    /// A ragged star-shaped polygon around the origin and a line near it.
    fn random_view(rng: &mut rand_chacha::ChaCha8Rng) -> View {
        let n = rng.random_range(5..60);
        let mut angles: Vec<Real> = (0..n)
            .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
            .collect();
        angles.sort_by(Real::total_cmp);
        angles.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
        let nodes = angles
            .iter()
            .enumerate()
            .map(|(i, &a)| {
                let r = rng.random_range(0.05..0.3);
                Node2::plain(Point2::new(r * a.cos(), r * a.sin()), EdgeKey(i as u32))
            })
            .collect();
        let dir_angle: Real = rng.random_range(0.0..std::f64::consts::TAU);
        View {
            frame: PlaneFrame::new(Point3::origin(), Vector3::z_axis()),
            poly: Poly2 { nodes },
            origin: Point2::new(rng.random_range(-0.2..0.2), rng.random_range(-0.2..0.2)),
            dir: Vector2::new(dir_angle.cos(), dir_angle.sin()),
            grid: std::cell::OnceCell::new(),
            vth: std::cell::OnceCell::new(),
        }
    }

    /// The candidate pre-filter of `plan_shared_edge` is sound: whenever
    /// `covers` rejects a range, the section search finds nothing there (so
    /// filtering changes no plan). Ranges between the parameters of vertices
    /// in the strip (the anchors) and random ones, on ragged perimeters.
    #[test]
    fn strip_cover_rejects_only_ranges_without_sections() {
        let (lambda, eps) = (0.05, 5e-6);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut rejected, mut found) = (0, 0);
        for _ in 0..400 {
            let view = random_view(&mut rng);
            if !view.poly.is_valid(eps) {
                continue;
            }
            let cover = strip_cover(&view, lambda, eps);
            let mut ts: Vec<Real> = view
                .poly
                .points()
                .iter()
                .filter(|p| view.h(p).abs() < lambda)
                .map(|p| view.t(p))
                .collect();
            for _ in 0..6 {
                ts.push(rng.random_range(-0.35..0.35));
            }
            for &t0 in &ts {
                for &t1 in &ts {
                    let starts = starts_at(&view, t0, lambda, eps);
                    let mut secs = Vec::new();
                    sections(&view, &starts, t0, t1, lambda, eps, &mut secs);
                    if covers(&cover, t0, t1, eps) {
                        found += usize::from(!secs.is_empty());
                    } else {
                        rejected += 1;
                        assert!(secs.is_empty(), "rejected [{t0}, {t1}] has {secs:?}");
                    }
                }
            }
        }
        assert!(
            rejected > 1000 && found > 1000,
            "{rejected} rejected, {found} found"
        );
    }
}
