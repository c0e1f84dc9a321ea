//! Merging model segments (P§2.4): two segments' moment sums are added, the
//! result's type and description follow from the eigen-decomposition, and the
//! merger fails (leaving both unchanged) when a condition of the thesis is not
//! met.
//!
//! | pair | thesis | conditions | description of S₃ |
//! |---|---|---|---|
//! | point + point | P§2.4.1, Fig. 5–6 | sensing axes within 90°; `s²_pt < λ²` (point) or `s²_pp < λ²` (polygon); for a polygon, the summed axes more than μ out of the plane (the outside must be decidable) | centroid with summed axes, or the diamond `c ± √u₁v₁, c ± √u₂v₂` on the plane of best fit, outward normal against the summed axes |
//! | point + polygon | P§2.4.2, Fig. 7–9 | axis and outward normal more than 90° apart; planar result; `s²_pp < λ²`; initial plane of the polygon within μ (normal) and λ (centroid) of the new plane | the projected perimeter, extended to the projected point by the five rules; unchanged when the point is inside or the closest perimeter point is on a shared edge (Fig. 9b–c) |
//! | polygon + polygon | P§2.4.3, Fig. 10–13 | neighbours dissolved first; planar result; `s²_pp < λ²`; both planes within μ (normal) and λ (centroid) of the new plane | the union of the projections (holes collapsed by fissures), or a bridge between them; retained shared edges are checked for local and global ordering; with no bridge, a polygon of fewer than ψ points without shared edges is absorbed by extending the other's perimeter to its vertices (our addition, see `absorb`) |
//!
//! Type (P§2.2): Pudney's `s²_pt < s²_pp` test can never hold (`s²_pt` is the
//! covariance trace, `s²_pp` its smallest eigenvalue), so the type is decided by
//! his collinearity rule: points are collinear — and a point segment represents
//! them — when the middle eigenvalue `u₂` is below `(collinear_fraction·λ)²` or
//! below `4u₁` (no well-defined plane). The drift check of the polygon + polygon
//! row extends the thesis' initial-plane check of P§2.4.2 to both merged planes,
//! and the initial plane of S₃ is then its own plane, as in P§2.4.3.

use crate::config::Tolerances;
use crate::model::{Flag, SurfaceModel};
use crate::overlay::{CombineError, combine};
use crate::perimeter::{Node2, PerimPoint, Poly2};
use crate::relations::OrderingFix;
use crate::segment::{Edge, EdgeKey, Node, PointSegment, Polygon, Segment, SegmentId, SegmentKind};
use geom::polygon2::{self, Containment};
use geom::{Moments, Pca, Plane, PlaneFrame, Point2, Point3, Real, UnitVector3, Vector3};

/// Why a merger failed (the rule of P§2.4 that was not met).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeFailure {
    /// A segment is missing, or is an initial segment (P§4.3).
    NotMergeable,
    /// The moments have no eigen-decomposition.
    Degenerate,
    /// P§2.4.1: the sensing axes are more than 90° apart.
    AxesOppose,
    /// P§2.4.1: `s²_pt ≥ λ²` for a point result.
    PointVariance,
    /// `s²_pp ≥ λ²` for a polygon result.
    PlaneVariance,
    /// P§2.4.1: the summed sensing axes lie within μ of the plane (the outside
    /// cannot be told).
    EdgeOn,
    /// P§2.4.2: the point's sensing axis is less than 90° from the outward normal.
    AxisAlongNormal,
    /// P§2.4.2–2.4.3: the result would have to be a point segment.
    NotPlanar,
    /// P§2.4.2 (Fig. 7) / P§2.4.3: the new plane drifted more than μ or λ.
    Drift,
    /// A projected perimeter is not simple (planes too far apart).
    Projection,
    /// P§2.4.2: no valid perimeter points `p₁, p₂`.
    NoExtension,
    /// P§2.4.3: the perimeters could not be combined.
    Combine(crate::overlay::CombineError),
}

/// Outcome of extending a perimeter to a projected point (P§2.4.2).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Extension {
    /// The point is inside the polygon (Fig. 9c) or the closest perimeter point
    /// is on a shared edge (Fig. 9b): the perimeter is unchanged.
    Unchanged,
    /// The perimeter section `P` was extended to the point (Fig. 8, 9a).
    Extended(Poly2),
    /// No valid pair of perimeter points: the merger fails.
    Failed,
}

impl SurfaceModel {
    /// `true` when the points are collinear in the sense of the [module docs](self).
    pub(crate) fn is_collinear(&self, pca: &Pca) -> bool {
        collinear(&self.tol, pca)
    }

    /// Attempt to merge `s1` and `s2` (P§2.4). Neighbours are dissolved first, and
    /// stay dissolved when the merger fails (P§2.4.3). Returns the new segment.
    pub(crate) fn try_merge(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
    ) -> Result<SegmentId, MergeFailure> {
        if self.are_neighbours(s1, s2) {
            self.run(|m| m.dissolve(s1, s2));
        }
        let a = self.get(s1).ok_or(MergeFailure::NotMergeable)?;
        let b = self.get(s2).ok_or(MergeFailure::NotMergeable)?;
        if a.is_initial() || b.is_initial() {
            return Err(MergeFailure::NotMergeable);
        }
        if matches!(
            (&a.kind, &b.kind),
            (SegmentKind::Polygon(_), SegmentKind::Polygon(_))
        ) {
            let mut failure = MergeFailure::NotMergeable;
            let out = self.attempt(|m| match m.merge_two_polygons(s1, s2) {
                Ok(id) => Some(id),
                Err(e) => {
                    failure = e;
                    None
                }
            });
            return out.ok_or(failure);
        }
        // A merger with a point segment computes the result without touching the
        // model; only then is the model changed.
        let (moments, kind, verified) = self.merge_with_point(s1, s2)?;
        if verified && self.journal.is_none() {
            // The result's perimeter was checked where it was built (or is a
            // projection through less than 10⁻³ rad of a valid one), and shared
            // edges, corners and orderings are carried over unchanged: nothing
            // can fail, so no transaction is needed.
            return Ok(self.replace_by(s1, s2, moments, kind, false));
        }
        let id = self.attempt(|m| {
            m.set_scope(crate::model::Scope::Geometry);
            Some(m.replace_by(s1, s2, moments, kind, false))
        });
        id.ok_or(MergeFailure::Projection)
    }

    /// P§2.4.1–2.4.2: a merger involving a point segment, computed without
    /// changing the model: the moments, the description, and whether the
    /// description's perimeter is known to be simple.
    fn merge_with_point(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
    ) -> Result<(Moments, SegmentKind, bool), MergeFailure> {
        let tol = self.tol;
        let a = self.segments.get(&s1).ok_or(MergeFailure::NotMergeable)?;
        let b = self.segments.get(&s2).ok_or(MergeFailure::NotMergeable)?;
        let moments = a.moments.merged(&b.moments);
        let pca = moments.pca().ok_or(MergeFailure::Degenerate)?;
        let keys = &mut self.ids.edge;
        match (&a.kind, &b.kind) {
            (SegmentKind::Point(p), SegmentKind::Point(q)) => {
                let mut kind = merge_points(&tol, p, q, &moments, &pca)?;
                if let SegmentKind::Polygon(g) = &mut kind {
                    for node in &mut g.nodes {
                        *keys += 1;
                        node.edge.key = EdgeKey(*keys);
                    }
                }
                Ok((moments, kind, true))
            }
            (SegmentKind::Point(p), SegmentKind::Polygon(g))
            | (SegmentKind::Polygon(g), SegmentKind::Point(p)) => {
                let mut fresh = move || {
                    *keys += 1;
                    EdgeKey(*keys)
                };
                let (poly, verified) =
                    merge_point_polygon(&tol, p, g, &pca, moments.m, &mut fresh)?;
                Ok((moments, SegmentKind::Polygon(poly), verified))
            }
            (SegmentKind::Polygon(_), SegmentKind::Polygon(_)) => Err(MergeFailure::NotMergeable),
        }
    }

    /// P§2.4.3 inside a transaction.
    fn merge_two_polygons(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
    ) -> Result<SegmentId, MergeFailure> {
        let a = self.get(s1).ok_or(MergeFailure::NotMergeable)?;
        let b = self.get(s2).ok_or(MergeFailure::NotMergeable)?;
        let moments = a.moments.merged(&b.moments);
        let pca = moments.pca().ok_or(MergeFailure::Degenerate)?;
        let poly = self.merge_polygons(s1, s2, &pca)?;
        Ok(self.replace_by(s1, s2, moments, SegmentKind::Polygon(poly), true))
    }

    /// P§2.4.3: two planar polygon segments.
    fn merge_polygons(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
        pca: &Pca,
    ) -> Result<Polygon, MergeFailure> {
        let tol = self.tol;
        if self.is_collinear(pca) {
            return Err(MergeFailure::NotPlanar);
        }
        if pca.eigenvalues[0] >= tol.lambda * tol.lambda {
            return Err(MergeFailure::PlaneVariance);
        }
        let missing = MergeFailure::NotMergeable;
        let (n1, c1) = {
            let g = self.poly(s1).ok_or(missing)?;
            (g.normal, g.centroid)
        };
        let (n2, c2) = {
            let g = self.poly(s2).ok_or(missing)?;
            (g.normal, g.centroid)
        };
        let normal = orient(pca.axes[0], &n1).ok_or(MergeFailure::Drift)?;
        let plane = Plane::from_point_normal(&pca.centroid, normal);
        if normal.dot(&n1) < tol.cos_mu
            || normal.dot(&n2) < tol.cos_mu
            || plane.signed_distance(&c1).abs() > tol.lambda
            || plane.signed_distance(&c2).abs() > tol.lambda
        {
            return Err(MergeFailure::Drift);
        }
        let frame = PlaneFrame::new(pca.centroid, normal);
        // Combine; unshare the shared edges on discarded sections and combine
        // again, until nothing shared is discarded. Every round unshares at least
        // one pair, so the rounds are bounded by the pairs of S₁ and S₂.
        let (ma, mb) = (
            self.get(s1).ok_or(missing)?.moments.m,
            self.get(s2).ok_or(missing)?.moments.m,
        );
        let rounds = 2
            + self.poly(s1).ok_or(missing)?.shared_edge_count()
            + self.poly(s2).ok_or(missing)?.shared_edge_count();
        for _ in 0..rounds {
            let a = Poly2::from_polygon(self.poly(s1).ok_or(missing)?, &frame);
            let b = Poly2::from_polygon(self.poly(s2).ok_or(missing)?, &frame);
            if !a.is_valid(tol.eps) || !b.is_valid(tol.eps) {
                return Err(MergeFailure::Projection);
            }
            let combined = {
                let mut fresh = Self::key_source(&mut self.ids.edge);
                match combine(&a, &b, tol.lambda, tol.eps, &mut fresh) {
                    Ok(c) => c,
                    Err(CombineError::NoBridge) => {
                        // A young polygon without shared edges beside the other:
                        // its vertices are merged as points (see `absorb`).
                        let (big, small, m_small) =
                            if ma >= mb { (&a, &b, mb) } else { (&b, &a, ma) };
                        let young = (m_small as Real) < tol.psi
                            && small.nodes.iter().all(|n| n.edge.share.is_none());
                        let absorbed = if young {
                            absorb(big, small, tol.lambda, tol.eps, &mut fresh)
                        } else {
                            None
                        };
                        let poly = absorbed.ok_or(MergeFailure::Combine(CombineError::NoBridge))?;
                        return Ok(Polygon {
                            initial: false,
                            centroid: pca.centroid,
                            normal,
                            initial_plane: plane,
                            nodes: poly.to_nodes(&frame),
                            rev: crate::segment::Revisions::fresh(),
                        });
                    }
                    Err(e) => return Err(MergeFailure::Combine(e)),
                }
            };
            if combined.dropped.is_empty() {
                if !combined.poly.is_valid(tol.eps) {
                    return Err(MergeFailure::Projection);
                }
                return Ok(Polygon {
                    initial: false,
                    centroid: pca.centroid,
                    normal,
                    initial_plane: plane,
                    nodes: combined.poly.to_nodes(&frame),
                    rev: crate::segment::Revisions::fresh(),
                });
            }
            for pair in combined.dropped {
                let owner = if self.pair_edge(s1, pair).is_some() {
                    s1
                } else {
                    s2
                };
                self.unshare_pair(owner, pair);
            }
        }
        Err(MergeFailure::Combine(
            crate::overlay::CombineError::Degenerate,
        ))
    }

    /// Replace `s1` and `s2` by a new segment (P§2.4): the neighbours of retained
    /// shared edges now share them with the new segment, whose shared edges await
    /// repositioning (P§2.4.4).
    fn replace_by(
        &mut self,
        s1: SegmentId,
        s2: SegmentId,
        moments: Moments,
        kind: SegmentKind,
        structural: bool,
    ) -> SegmentId {
        let id = self.new_segment_id();
        let was_pending =
            self.set_flag(Flag::Pending, s1, false) | self.set_flag(Flag::Pending, s2, false);
        if self.journal.is_none() {
            // Outside a transaction the index is updated at once; the result takes
            // over the larger footprint's slot (see `index`).
            let keep = if self.grid.cells_of(s1) >= self.grid.cells_of(s2) {
                s1
            } else {
                s2
            };
            self.grid.rename(keep, id);
        }
        self.remove_segment(s1);
        self.remove_segment(s2);
        let shares: Vec<_> = match &kind {
            SegmentKind::Polygon(p) => p.nodes.iter().filter_map(|n| n.edge.share).collect(),
            SegmentKind::Point(_) => Vec::new(),
        };
        self.insert_segment(Segment { id, moments, kind });
        for share in &shares {
            self.relink(share.neighbour, share.pair, id);
        }
        self.ctx.log.mergers.push(crate::changelog::Merger {
            from: [s1, s2],
            into: id,
        });
        self.set_flag(Flag::Modified, s1, false);
        self.set_flag(Flag::Modified, s2, false);
        self.set_flag(Flag::Modified, id, true);
        if !shares.is_empty() || was_pending {
            self.set_flag(Flag::Pending, id, true);
        }
        if structural && !shares.is_empty() {
            // Corner vertices inherited from both S₁ and S₂ of one cycle cannot stay.
            self.dissolve_duplicate_corners(id);
            self.enforce_ordering(id, OrderingFix::Merger);
            self.repair_junctions(id);
        }
        id
    }

    fn dissolve_duplicate_corners(&mut self, id: SegmentId) {
        for _ in 0..64 {
            let Some(p) = self.poly(id) else { return };
            let mut seen = std::collections::BTreeSet::new();
            let dup = p
                .nodes
                .iter()
                .position(|n| n.corner.is_some_and(|c| !seen.insert(c)));
            match dup {
                Some(v) => self.dissolve_corner(id, v),
                None => return,
            }
        }
    }
}

/// `true` when the points are collinear in the sense of the [module docs](self).
pub(crate) fn collinear(tol: &Tolerances, pca: &Pca) -> bool {
    let [u1, u2, _] = pca.eigenvalues;
    u2 < tol.min_spread_sq || u2 < 4.0 * u1
}

/// P§2.4.1: two point segments.
fn merge_points(
    tol: &Tolerances,
    p: &PointSegment,
    q: &PointSegment,
    moments: &Moments,
    pca: &Pca,
) -> Result<SegmentKind, MergeFailure> {
    let lambda_sq = tol.lambda * tol.lambda;
    if p.axis_sum.dot(&q.axis_sum) < 0.0 {
        return Err(MergeFailure::AxesOppose);
    }
    let axis_sum = p.axis_sum + q.axis_sum;
    if collinear(tol, pca) {
        if moments.point_variance().ok_or(MergeFailure::Degenerate)? >= lambda_sq {
            return Err(MergeFailure::PointVariance);
        }
        return Ok(SegmentKind::Point(PointSegment {
            centroid: pca.centroid,
            axis_sum,
        }));
    }
    if pca.eigenvalues[0] >= lambda_sq {
        return Err(MergeFailure::PlaneVariance);
    }
    // The outside is where the summed sensing axes point away from: it cannot
    // be told when they lie (within μ) in the plane — a plane seen edge-on,
    // which is what collinear points spread by noise along their sensing
    // axis look like.
    let axis = geom::unit(axis_sum).ok_or(MergeFailure::EdgeOn)?;
    if axis.dot(&pca.axes[0]).abs() < tol.sin_mu {
        return Err(MergeFailure::EdgeOn);
    }
    let normal = orient(pca.axes[0], &-axis_sum).ok_or(MergeFailure::EdgeOn)?;
    Ok(SegmentKind::Polygon(diamond(pca, normal)))
}

/// P§2.4.2: a point segment and a planar polygon segment. Also returns whether
/// the perimeter is known to be simple: built and checked by the extension, or
/// projected through less than 10⁻³ rad (lengths change by a factor of at least
/// `cos θ > 1 − 5·10⁻⁷`).
pub(crate) fn merge_point_polygon(
    tol: &Tolerances,
    p: &PointSegment,
    g: &Polygon,
    pca: &Pca,
    points: u64,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Result<(Polygon, bool), MergeFailure> {
    if p.axis_sum.dot(&g.normal) > 0.0 {
        return Err(MergeFailure::AxisAlongNormal);
    }
    if collinear(tol, pca) {
        return Err(MergeFailure::NotPlanar);
    }
    if pca.eigenvalues[0] >= tol.lambda * tol.lambda {
        return Err(MergeFailure::PlaneVariance);
    }
    let normal = orient(pca.axes[0], &g.normal).ok_or(MergeFailure::Drift)?;
    let init = g.initial_plane;
    if normal.dot(&init.normal) < tol.cos_mu
        || init.signed_distance(&pca.centroid).abs() > tol.lambda
    {
        return Err(MergeFailure::Drift); // drifted from the initial plane (Fig. 7)
    }
    // Orthogonal projection between planes less than 2μ apart is an
    // orientation-preserving affine map: the projected perimeter stays simple
    // (the transaction's validation checks the result otherwise).
    // The initial plane stays fixed (P§2.4.2) once the polygon represents ψ
    // points. Before that it follows the plane of best fit: under range noise
    // the diamond of the first few points (P§2.4.1) can be tilted by more than
    // μ, and a fixed tilted initial plane then refuses the points of the very
    // surface it came from, which pile up in small stray polygons beside it.
    // ψ is the thesis' own count for a segment that has not yet "had a chance
    // to develop" (P§2.9). The drift check above still compares each merger
    // with the plane before it, so no single point can tilt a young polygon
    // by more than μ (Fig. 7).
    let initial_plane = if (points as Real) < tol.psi {
        Plane::from_point_normal(&pca.centroid, normal)
    } else {
        init
    };
    let frame = PlaneFrame::new(pca.centroid, normal);
    let proj = Poly2::from_polygon(g, &frame);
    let q = frame.to_2d(&p.centroid);
    let (perimeter, verified, rev) = match extend_to_point(&proj, q, tol.lambda, tol.eps, fresh) {
        Extension::Unchanged => (proj, normal.dot(&g.normal) > 1.0 - 5e-7, g.rev),
        Extension::Extended(e) => (e, true, crate::segment::Revisions::fresh()),
        Extension::Failed => return Err(MergeFailure::NoExtension),
    };
    Ok((
        Polygon {
            initial: false,
            centroid: pca.centroid,
            normal,
            initial_plane,
            nodes: perimeter.to_nodes(&frame),
            rev,
        },
        verified,
    ))
}

/// `axis` or its opposite, whichever has a positive dot product with `towards`;
/// `None` when they are perpendicular.
pub(crate) fn orient(axis: UnitVector3, towards: &Vector3) -> Option<UnitVector3> {
    let d = axis.dot(towards);
    if d > 0.0 {
        Some(axis)
    } else if d < 0.0 {
        Some(-axis)
    } else {
        None
    }
}

/// The diamond of P§2.4.1 (Fig. 5): vertices at `c ± √u₁v₁` and `c ± √u₂v₂` for the
/// two largest eigenvalues, anticlockwise about `normal`; the initial plane is
/// the plane of best fit.
pub(crate) fn diamond(pca: &Pca, normal: UnitVector3) -> Polygon {
    let c = pca.centroid;
    let a1 = pca.axes[2].into_inner() * pca.eigenvalues[2].sqrt();
    let mut a2 = pca.axes[1].into_inner() * pca.eigenvalues[1].sqrt();
    if a1.cross(&a2).dot(&normal) < 0.0 {
        a2 = -a2;
    }
    let positions = [c + a1, c + a2, c - a1, c - a2];
    let nodes = positions
        .iter()
        .map(|p| Node {
            position: *p,
            corner: None,
            edge: Edge {
                key: EdgeKey(0),
                share: None,
            },
        })
        .collect();
    Polygon {
        initial: false,
        centroid: c,
        normal,
        initial_plane: Plane::from_point_normal(&c, normal),
        nodes,
        rev: crate::segment::Revisions::fresh(),
    }
}

/// Extend the perimeter to the projected point `q` (P§2.4.2, Fig. 8–9).
pub(crate) fn extend_to_point(
    poly: &Poly2,
    q: Point2,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Extension {
    let pts = poly.points();
    if polygon2::locate_point(&pts, &q, eps) != Containment::Outside {
        return Extension::Unchanged; // Fig. 9(c)
    }
    let n = poly.len();
    let (c, dist) = poly.closest(&q);
    let c = poly.snap(c, eps);
    if dist >= lambda {
        return Extension::Failed;
    }
    let on_shared = if c.t > 0.0 {
        poly.is_shared(c.edge)
    } else {
        poly.is_shared(c.edge) && poly.is_shared(poly.prev(c.edge))
    };
    if on_shared {
        return Extension::Unchanged; // Fig. 9(b)
    }
    let inside = |p: &Point2| (p - q).norm() < lambda;
    // Candidate p₁ walking backwards from c, p₂ forwards; vertices and the ends of
    // the perimeter run within λ of q, never crossing a shared edge.
    let mut back: Vec<PerimPoint> = Vec::new();
    let mut fwd: Vec<PerimPoint> = Vec::new();
    if c.t == 0.0 {
        back.push(c);
        fwd.push(c);
    }
    // Backwards.
    {
        let (mut e, mut t_hi) = if c.t > 0.0 {
            (c.edge, c.t)
        } else {
            (poly.prev(c.edge), 1.0)
        };
        for _ in 0..n {
            if poly.is_shared(e) {
                break;
            }
            let (a, b) = poly.seg(e);
            let (lo, _) = circle_params(&a, &b, &q, lambda);
            if lo > 0.0 && lo < t_hi {
                // Just inside the circle; a point within `eps` of a vertex is
                // that vertex (a perimeter point there would leave a
                // zero-length edge, and the merger failed).
                let t = lo + (t_hi - lo) * 1e-6;
                back.push(poly.snap(PerimPoint { edge: e, t }, eps));
                break;
            }
            if !inside(&a) {
                break;
            }
            back.push(PerimPoint::vertex(e));
            e = poly.prev(e);
            t_hi = 1.0;
        }
    }
    // Forwards.
    {
        let (mut e, mut t_lo) = (c.edge, c.t);
        for _ in 0..n {
            if poly.is_shared(e) {
                break;
            }
            let (a, b) = poly.seg(e);
            let (_, hi) = circle_params(&a, &b, &q, lambda);
            if hi < 1.0 && hi > t_lo {
                let t = hi - (hi - t_lo) * 1e-6;
                fwd.push(poly.snap(PerimPoint { edge: e, t }, eps));
                break;
            }
            if !inside(&b) {
                break;
            }
            e = poly.next(e);
            fwd.push(PerimPoint::vertex(e));
            t_lo = 0.0;
        }
    }
    let sees = |p: &PerimPoint| poly.sight(&poly.point_at(*p), &q, eps, |_| false);
    back.retain(sees);
    fwd.retain(sees);
    let mut combos: Vec<(Real, PerimPoint, PerimPoint)> = Vec::new();
    for p1 in &back {
        for p2 in &fwd {
            if (poly.point_at(*p1) - poly.point_at(*p2)).norm() <= eps {
                continue;
            }
            combos.push((poly.arc_len(*p1, c) + poly.arc_len(c, *p2), *p1, *p2));
        }
    }
    combos.sort_by(|a, b| b.0.total_cmp(&a.0));
    let area = poly.area();
    for (_, p1, p2) in combos.into_iter().take(16) {
        let edge = Edge {
            key: fresh(),
            share: None,
        };
        let apex = [Node2::plain(q, fresh())];
        if let Ok(next) = poly.replace_section(p1, p2, edge, &apex, fresh)
            && next.is_valid(eps)
            && next.area() > area
        {
            return Extension::Extended(next);
        }
    }
    Extension::Failed
}

/// Absorb a small polygon `small` lying beside `big` (not overlapping it, no
/// bridge of P§2.4.3 found): `big`'s perimeter is extended (P§2.4.2) to each
/// vertex of `small` in turn, nearest first, as if its points had been merged
/// one by one. `None` unless every extension succeeds and the result contains
/// `small` (every vertex inside, no edge of `small` crossing the perimeter).
///
/// Our addition to P§2.4.3. The bridge considers only vertices as `p₁, p₂`
/// and only their closest points as `q₁, q₂` (the thesis' economy, "at the
/// expense of the possibility of missing valid perimeter points"): a diamond
/// of a few points (P§2.4.1) beside a polygon offers one vertex within λ, and
/// the bridge is never found. Had those points arrived after the polygon had
/// grown next to them, each would have merged by P§2.4.2. Without this, such
/// diamonds stay beside the face as separate segments, notching its model, and
/// every point near them merges into them instead of the face. Only polygons
/// of fewer than ψ points without shared edges (the segments that have not
/// "had a chance to develop", P§2.9) are absorbed this way.
pub(crate) fn absorb(
    big: &Poly2,
    small: &Poly2,
    lambda: Real,
    eps: Real,
    fresh: &mut dyn FnMut() -> EdgeKey,
) -> Option<Poly2> {
    let mut current = big.clone();
    let mut left: Vec<Point2> = small.points();
    while !left.is_empty() {
        let pts = current.points();
        left.retain(|v| polygon2::locate_point(&pts, v, eps) == Containment::Outside);
        let Some((k, _)) = left
            .iter()
            .enumerate()
            .map(|(k, v)| (k, current.closest(v).1))
            .min_by(|x, y| x.1.total_cmp(&y.1))
        else {
            break;
        };
        let v = left.swap_remove(k);
        match extend_to_point(&current, v, lambda, eps, fresh) {
            Extension::Extended(next) => current = next,
            Extension::Unchanged | Extension::Failed => return None,
        }
    }
    let pts = current.points();
    let n = small.len();
    let contained = (0..n).all(|i| {
        let (a, b) = small.seg(i);
        polygon2::locate_point(&pts, &a, eps) != Containment::Outside
            && current.sight(&a, &b, eps, |_| false)
    });
    (contained && current.is_valid(eps)).then_some(current)
}

/// Parameters `(lo, hi)` along segment `a b` between which it lies within `r` of
/// `q` (`lo > hi` when it never does).
fn circle_params(a: &Point2, b: &Point2, q: &Point2, r: Real) -> (Real, Real) {
    let d = b - a;
    let f = a - q;
    let aa = d.norm_squared();
    if aa <= 0.0 {
        return if f.norm() < r {
            (Real::NEG_INFINITY, Real::INFINITY)
        } else {
            (1.0, 0.0)
        };
    }
    let bb = 2.0 * f.dot(&d);
    let cc = f.norm_squared() - r * r;
    let disc = bb * bb - 4.0 * aa * cc;
    if disc < 0.0 {
        return (1.0, 0.0);
    }
    let sq = disc.sqrt();
    ((-bb - sq) / (2.0 * aa), (-bb + sq) / (2.0 * aa))
}

/// Distance between two planar polygons in 3-D (0 when they meet).
pub(crate) fn polygon_distance(a: &Polygon, b: &Polygon) -> Real {
    let mut best = Real::INFINITY;
    let (na, nb) = (a.nodes.len(), b.nodes.len());
    for i in 0..na {
        let sa = geom::Segment3::new(a.nodes[i].position, a.nodes[(i + 1) % na].position);
        for j in 0..nb {
            let sb = geom::Segment3::new(b.nodes[j].position, b.nodes[(j + 1) % nb].position);
            // A pair whose boxes are farther apart than the best cannot lower it.
            if geom::line::segments_apart(&sa, &sb, best) {
                continue;
            }
            best = best.min(geom::line::distance_segment_segment(&sa, &sb));
        }
    }
    for (x, y) in [(a, b), (b, a)] {
        let frame = y.frame();
        let pts = y.points_2d(&frame);
        let n = x.nodes.len();
        for i in 0..n {
            let p = x.nodes[i].position;
            if polygon2::contains_point(&pts, &frame.to_2d(&p), 0.0) {
                best = best.min(frame.height(&p).abs());
            }
            // An edge piercing the other polygon.
            let q = x.nodes[(i + 1) % n].position;
            let (hp, hq) = (frame.height(&p), frame.height(&q));
            if hp * hq < 0.0 {
                let s = hp / (hp - hq);
                let x3: Point3 = p + (q - p) * s;
                if polygon2::contains_point(&pts, &frame.to_2d(&x3), 0.0) {
                    return 0.0;
                }
            }
        }
    }
    best
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

    fn ext(poly: &Poly2, q: Point2) -> Extension {
        let mut k = 100;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        extend_to_point(poly, q, 0.05, 1e-6, &mut fresh)
    }

    /// P Fig. 8 / 9(a): the section within λ of the point is extended to it.
    #[test]
    fn fig9a_extension() {
        let sq = square();
        let Extension::Extended(p) = ext(&sq, Point2::new(0.5, 1.03)) else {
            panic!("expected an extension");
        };
        assert!(p.is_valid(1e-9));
        // The apex is a vertex and the removed section lay within λ of it.
        assert!(
            p.points()
                .iter()
                .any(|v| (v - Point2::new(0.5, 1.03)).norm() < 1e-12)
        );
        let area_gain = p.area() - 1.0;
        // Triangle over the chord of the λ-circle at distance 0.03: base 2·0.04.
        assert!((area_gain - 0.5 * 0.08 * 0.03).abs() < 1e-6, "{area_gain}");
        // Near a corner the section runs around it (vertices within λ included).
        let Extension::Extended(p) = ext(&sq, Point2::new(1.02, 1.02)) else {
            panic!("expected an extension");
        };
        assert!(p.is_valid(1e-9));
        assert!(p.len() >= 5);
    }

    /// P Fig. 9(b): the closest perimeter point is on a shared edge.
    #[test]
    fn fig9b_shared_edge_keeps_perimeter() {
        let mut sq = square();
        sq.nodes[2].edge.share = Some(crate::segment::Share {
            neighbour: SegmentId(7),
            pair: crate::segment::PairId(1),
        });
        assert_eq!(ext(&sq, Point2::new(0.5, 1.03)), Extension::Unchanged);
    }

    /// P Fig. 9(c): the point is inside.
    #[test]
    fn fig9c_contained_point() {
        assert_eq!(ext(&square(), Point2::new(0.5, 0.5)), Extension::Unchanged);
        assert_eq!(ext(&square(), Point2::new(0.5, 1.2)), Extension::Failed);
    }

    /// P§2.4.2 with the λ-circle leaving an edge a hair before its end vertex
    /// (the vertex lies 10⁻¹⁰ beyond λ of the point): the extension takes the
    /// vertex as `p₂` instead of a perimeter point within `eps` of it (whose
    /// perimeter would not be simple), and the area gained is the triangle over
    /// the circle's chord.
    #[test]
    fn circle_exit_next_to_a_vertex() {
        let lambda: Real = 0.05;
        let (h, half) = (0.03, 0.04); // half-chord of the λ-circle at height 0.03
        let pts = [
            (0.0, 0.0),
            (0.5 + half + 1e-10, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
        ];
        let sq = Poly2 {
            nodes: pts
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| Node2::plain(Point2::new(x, y), EdgeKey(i as u32)))
                .collect(),
        };
        let q = Point2::new(0.5, -h);
        assert!((sq.pt(1) - q).norm() > lambda);
        let Extension::Extended(p) = ext(&sq, q) else {
            panic!("expected an extension");
        };
        assert!(p.is_valid(1e-9));
        let gain = p.area() - 1.0;
        assert!((gain - 0.5 * (2.0 * half) * h).abs() < 1e-9, "{gain}");
    }

    fn poly2(pts: &[(Real, Real)]) -> Poly2 {
        Poly2 {
            nodes: pts
                .iter()
                .enumerate()
                .map(|(i, &(x, y))| Node2::plain(Point2::new(x, y), EdgeKey(i as u32)))
                .collect(),
        }
    }

    /// A diamond of a few points beside a face (P§2.4.1): the bridge of
    /// P§2.4.3 finds one vertex within λ and fails; absorbing it by successive
    /// extensions gives a valid perimeter containing both, within λ of them.
    #[test]
    fn diamond_beside_a_face_is_absorbed() {
        let face = poly2(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        // Tip 3 cm right of the face's right edge, 4 cm across.
        let diamond = poly2(&[(1.03, 0.5), (1.05, 0.48), (1.07, 0.5), (1.05, 0.52)]);
        let mut k = 100;
        let mut fresh = || {
            k += 1;
            EdgeKey(k)
        };
        assert_eq!(
            crate::overlay::combine(&face, &diamond, 0.05, 1e-6, &mut fresh).unwrap_err(),
            CombineError::NoBridge
        );
        let out = absorb(&face, &diamond, 0.05, 1e-6, &mut fresh).expect("absorbed");
        assert!(out.is_valid(1e-6));
        let pts = out.points();
        for v in face.points().iter().chain(diamond.points().iter()) {
            assert_ne!(polygon2::locate_point(&pts, v, 1e-9), Containment::Outside);
        }
        // Oracle: the new region lies within λ of the diamond (x ≤ 1.07) and
        // the result is no larger than the face plus a λ-wide band beside it.
        assert!(pts.iter().all(|v| v.x <= 1.07 + 1e-12));
        assert!(out.area() > 1.0 + 0.5 * 0.04 * 0.04);
        assert!(out.area() < 1.0 + 0.07 * 0.1);
        // Too far (6 cm): nothing to extend to.
        let far = poly2(&[(1.06, 0.5), (1.08, 0.48), (1.10, 0.5), (1.08, 0.52)]);
        assert!(absorb(&face, &far, 0.05, 1e-6, &mut fresh).is_none());
    }
}
