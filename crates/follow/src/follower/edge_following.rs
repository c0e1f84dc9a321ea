//! Current edge following (P§3.4.3, Fig. 31–34): the slice line, slices of
//! width λ/2, the current point, the retention rules and the
//! little-unexposed-surface test.

use super::{Directive, Flow, Follower, Mode, SliceLine};
use crate::config::{SliceLineRule, SliceRule};
use crate::query::{EdgeRef, Feature, ModelPoint, closest_on_segment, edge_by_key};
use geom::{Point3, Real, Segment3, Vector3, unit};
use std::collections::BTreeSet;

/// Slice numbers through edge `e` (inclusive range).
fn slice_range(line: &SliceLine, e: &EdgeRef) -> (i64, i64) {
    let width = line.width;
    let (ta, tb) = (line.param(&e.a), line.param(&e.b));
    let lo = (ta.min(tb) / width).floor() as i64;
    let hi = ((ta.max(tb) / width).ceil() as i64 - 1).max(lo);
    (lo, hi)
}

/// Whether `e` runs at less than 45° to the slice line, anticlockwise
/// (P§3.4.3, Fig. 33(b)).
fn aligned(line: &SliceLine, e: &EdgeRef) -> bool {
    unit(e.b - e.a).is_some_and(|d| d.dot(&line.dir) > std::f64::consts::FRAC_PI_4.cos())
}

/// The retention test of [`SliceLineRule::Outward`] (our addition to
/// P§3.4.3), for a new current edge `e` on the segment whose slice line
/// `line` is and whose outward normal is `normal`: `e` runs at less than
/// 45° to the line and neither vertex lies more than λ inside it, where
/// "outside" is `line.dir × normal`, the side P§3.4.3's outside-edge test
/// (Fig. 32) calls away from the edge. The thesis' test also asks the
/// vertices to lie within λ of the line on either side and a used slice to
/// pass through `e`; this one keeps the line however far the edge moved
/// outward, used slice or not, since a model that grew past the line has
/// left the used slices used and the rest still to cover.
fn outward_retained(line: &SliceLine, e: &EdgeRef, normal: &Vector3, lambda: Real) -> bool {
    let out = line.dir.cross(normal);
    let outside = |p: &Point3| (p - line.point).dot(&out) > -lambda;
    aligned(line, e) && outside(&e.a) && outside(&e.b)
}

/// Widest slice considered by [`lattice_slice_width`], in quarters of λ.
const MAX_SLICE_QUARTERS: u32 = 16;

/// The slice width of [`SliceRule::Lattice`] (our addition to P§3.4.3).
///
/// `offsets` are where the control point's range finders land on the
/// current segment's plane, measured along the slice line from the foot of
/// the control point held δ off the plane. One pass along a slice leaves a
/// strip of sensor points at each offset; passes `w` apart leave strips at
/// every `k·w + offset`, which repeat with period `w`, so the gaps between
/// them are the gaps between the offsets taken modulo `w` (the gap across
/// the period's end included). Pudney's slices, λ/2 wide, leave strips at
/// most λ/2 apart whatever the sensors; this is the widest multiple of λ/4
/// up to 4λ whose strips are no more than λ/2 apart either (λ/2 itself
/// always is). With no offset it is λ/2.
pub(super) fn lattice_slice_width(offsets: &[Real], lambda: Real) -> Real {
    let half = 0.5 * lambda;
    let tol = 1e-9 * lambda.max(1.0);
    let max_gap = |w: Real| {
        let mut r: Vec<Real> = offsets.iter().map(|o| o.rem_euclid(w)).collect();
        r.sort_by(Real::total_cmp);
        let wrap = r.first().zip(r.last()).map_or(w, |(a, b)| a + w - b);
        r.windows(2).map(|p| p[1] - p[0]).fold(wrap, Real::max)
    };
    if offsets.is_empty() || offsets.iter().any(|o| !o.is_finite()) {
        return half;
    }
    (2..=MAX_SLICE_QUARTERS)
        .rev()
        .map(|q| 0.25 * lambda * Real::from(q))
        .find(|&w| max_gap(w) <= half + tol)
        .unwrap_or(half)
}

impl Follower {
    /// Choose `e` as the current edge, testing whether the slice line can be
    /// kept (P§3.4.3, Fig. 33).
    pub(super) fn set_current_edge(&mut self, e: &EdgeRef) {
        let lambda = self.model.config().lambda;
        let same_segment = self.state.edge_segment == Some(e.segment);
        let retained = self.state.slices.as_ref().is_some_and(|line| {
            let near =
                (e.a - line.foot(&e.a)).norm() < lambda && (e.b - line.foot(&e.b)).norm() < lambda;
            let aligned = aligned(line, e);
            let (ka, kb) = slice_range(line, e);
            let any_used = (ka..=kb).any(|k| line.used.contains(&k));
            same_segment && near && aligned && any_used
        });
        // Our addition (`slice_line = "outward"`): the edge only moved
        // outward, so the line, its used slices and the current slice stay.
        let outward = !retained
            && same_segment
            && self.config.slice_line == SliceLineRule::Outward
            && self.state.slices.as_ref().is_some_and(|line| {
                self.model
                    .polygon(e.segment)
                    .is_some_and(|p| outward_retained(line, e, &p.normal().into_inner(), lambda))
            });
        let keep_slice = self.config.slice_line == SliceLineRule::Outward
            && (retained || outward)
            && self.state.slices.as_ref().is_some_and(|line| {
                let (ka, kb) = slice_range(line, e);
                self.state
                    .slice
                    .is_some_and(|k| (ka..=kb).contains(&k) && !line.used.contains(&k))
            });
        if !retained && !outward {
            let dir = unit(e.b - e.a).unwrap_or_else(Vector3::x_axis);
            let width = match self.config.slices {
                SliceRule::Thesis => 0.5 * lambda,
                SliceRule::Lattice => {
                    lattice_slice_width(&self.lattice_offsets(e, &dir.into_inner()), lambda)
                }
            };
            self.state.slices = Some(SliceLine {
                point: e.a,
                dir,
                width,
                used: BTreeSet::new(),
            });
            self.state.any_edge = true;
        }
        self.state.edge = Some(e.key);
        self.state.edge_segment = Some(e.segment);
        if !keep_slice {
            self.state.slice = None;
        }
    }

    /// Where the control point's range finders, at their present
    /// orientation, land on the plane of `e`'s segment with the control point
    /// held δ off it: their offsets along `dir` from the control point's
    /// foot (for [`lattice_slice_width`]). Empty when `e`'s segment is not a
    /// polygon or the sensor frames are not known yet.
    fn lattice_offsets(&self, e: &EdgeRef, dir: &Vector3) -> Vec<Real> {
        let Some(poly) = self.model.polygon(e.segment) else {
            return Vec::new();
        };
        let n = poly.normal().into_inner();
        let (tool_link, tool) = self.robot.tool;
        let Some(tool_frame) = self.frames.get(tool_link.0) else {
            return Vec::new();
        };
        let cp = tool_frame * Point3::from(tool.translation.vector);
        let delta = self.config.desired_distance_m;
        self.cp_sensors
            .iter()
            .filter_map(|&i| {
                let m = self.robot.range_finders.get(i)?;
                let frame = self.frames.get(m.link.0)?;
                let origin = frame * m.origin - cp;
                let axis = (frame.rotation * m.axis).into_inner();
                let height = delta + origin.dot(&n);
                let down = -axis.dot(&n);
                if down <= 1e-9 || height <= 0.0 {
                    return None;
                }
                let t = height / down;
                (t <= m.max_range_m).then(|| (origin + axis * t).dot(dir))
            })
            .collect()
    }

    pub(super) fn slice_used(&mut self) {
        if let (Some(line), Some(k)) = (self.state.slices.as_mut(), self.state.slice.take()) {
            line.used.insert(k);
        }
        self.state.any_edge = false;
    }

    /// Current edge following (P§3.4.3).
    pub(super) fn edge_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let Some(key) = self.state.edge else {
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let Some(e) = edge_by_key(&self.model, key, self.state.segment) else {
            self.state.edge = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        if self.edge_complete(&e) {
            self.state.edge = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        }
        let lambda = self.model.config().lambda;
        let rho = self.config.stray_m;
        for _ in 0..64 {
            let Some(line) = self.state.slices.clone() else {
                self.set_current_edge(&e);
                continue;
            };
            let (ka, kb) = slice_range(&line, &e);
            let width = line.width;
            if self
                .state
                .slice
                .is_none_or(|k| line.used.contains(&k) || k < ka || k > kb)
            {
                // Choose the current slice: unused, through the edge, next to
                // a used one when there is one (used slices grow as a block).
                let unused: Vec<i64> = (ka..=kb).filter(|k| !line.used.contains(k)).collect();
                if unused.is_empty() {
                    self.marks.unclosable_edges.insert(key);
                    self.state.edge = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
                let adjacent: Vec<i64> = unused
                    .iter()
                    .copied()
                    .filter(|k| line.used.contains(&(k - 1)) || line.used.contains(&(k + 1)))
                    .collect();
                let pool = if adjacent.is_empty() {
                    &unused
                } else {
                    &adjacent
                };
                let at = (line.param(cp) / width).floor() as i64;
                let k = pool
                    .iter()
                    .copied()
                    .min_by_key(|k| ((k - at).abs(), *k))
                    .unwrap_or(ka);
                self.state.slice = Some(k);
                self.state.approaching = true;
                self.reset_progress();
            }
            let Some(k) = self.state.slice else {
                continue;
            };
            let current_point = Self::current_point(&line, &e, k, width);
            if self.little_unexposed(&e, &line, &current_point, lambda) {
                self.slice_used();
                continue;
            }
            let d = (cp - current_point).norm();
            if d > rho {
                if self.state.approaching {
                    return Flow::Go(Directive {
                        dir: current_point - cp,
                        step_limit: None,
                    });
                }
                self.slice_used();
                continue;
            }
            self.state.approaching = false;
            let t = line.param(cp);
            let (lo, hi) = (k as Real * width, (k + 1) as Real * width);
            if t >= lo && t < hi {
                if self.outside_edge(closest, &e, &line) {
                    self.start_gap(Mode::Edge, &current_point, closest, lambda);
                    return Flow::Again;
                }
                let u = cp - line.foot(cp);
                return Flow::Go(Directive {
                    dir: line.dir.cross(&u),
                    step_limit: None,
                });
            }
            let centre = 0.5 * (lo + hi);
            let off = centre - t;
            return Flow::Go(Directive {
                dir: line.dir.into_inner() * off.signum(),
                step_limit: (off.abs() < self.config.max_step_m).then_some(off.abs()),
            });
        }
        self.state.mode = Mode::Segment;
        Flow::Again
    }

    /// The current edge point nearest the centre of slice `k`.
    pub(super) fn current_point(line: &SliceLine, e: &EdgeRef, k: i64, width: Real) -> Point3 {
        let centre = (k as Real + 0.5) * width;
        let (ta, tb) = (line.param(&e.a), line.param(&e.b));
        if (tb - ta).abs() < 1e-12 {
            return Point3::from((e.a.coords + e.b.coords) * 0.5);
        }
        let s = ((centre - ta) / (tb - ta)).clamp(0.0, 1.0);
        e.segment3().point_at(s)
    }

    /// Whether model point `c` lies outside the current edge (P§3.4.3, Fig. 32).
    pub(super) fn outside_edge(&self, c: &ModelPoint, e: &EdgeRef, line: &SliceLine) -> bool {
        if c.segment != e.segment {
            return true;
        }
        let Some(poly) = self.model.polygon(e.segment) else {
            return true;
        };
        let (ta, tb) = (line.param(&e.a), line.param(&e.b));
        let t = line.param(&c.point);
        if !(t > ta.min(tb) && t < ta.max(tb)) {
            return false;
        }
        let dir = e.b - e.a;
        let q = c.point - e.segment3().closest_point(&c.point);
        dir.cross(&poly.normal()).dot(&q) > 1e-12
    }

    /// The slice holds little unexposed surface: part of the model outside
    /// the current edge within λ/2 of the current point (P§3.4.3).
    pub(super) fn little_unexposed(
        &self,
        e: &EdgeRef,
        line: &SliceLine,
        current_point: &Point3,
        lambda: Real,
    ) -> bool {
        let radius = 0.5 * lambda;
        let mut ids = self.model.segments_near(current_point, radius);
        ids.sort_unstable();
        for id in ids {
            if id == e.segment {
                // Other perimeter parts of the current segment that lie
                // outside the current edge.
                let Some(poly) = self.model.polygon(id) else {
                    continue;
                };
                for i in 0..poly.len() {
                    if i == e.index {
                        continue;
                    }
                    if let Some((a, b)) = poly.edge_points(i) {
                        let q = Segment3::new(a, b).closest_point(current_point);
                        if (q - current_point).norm() < radius {
                            let c = ModelPoint {
                                segment: id,
                                point: q,
                                distance: 0.0,
                                feature: Feature::Edge(i),
                            };
                            if self.outside_edge(&c, e, line) {
                                return true;
                            }
                        }
                    }
                }
            } else if let Some(c) = closest_on_segment(&self.model, id, current_point)
                && c.distance < radius
            {
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query::EdgeRef;
    use surface::EdgeKey;

    const LAMBDA: Real = 0.05;

    /// point3's lattice δ = 0.1 over a face, along an edge parallel to a
    /// lattice axis, lands at −0.1, 0 and 0.1 (2λ apart). By hand, modulo
    /// w = 1.5λ = 0.075 these are 0.05, 0 and 0.025: strips λ/2 apart, so
    /// 1.5λ passes. Every wider multiple of λ/4 leaves a wider gap: 0.1
    /// puts all three on one residue (gap 0.1); 0.0875 gives 0.075, 0 and
    /// 0.0125 (gap 0.0625); 0.1125 gives 0.0125, 0 and 0.1 (gap 0.0875).
    #[test]
    fn point3s_lattice_gives_slices_one_and_a_half_lambda_wide() {
        let w = lattice_slice_width(&[-0.1, 0.0, 0.1], LAMBDA);
        assert!((w - 0.075).abs() < 1e-12, "{w}");
    }

    /// One strip per pass (or none) is the thesis' case: λ/2.
    #[test]
    fn one_sensor_or_none_gives_the_thesis_width() {
        assert!((lattice_slice_width(&[0.03], LAMBDA) - 0.025).abs() < 1e-12);
        assert!((lattice_slice_width(&[], LAMBDA) - 0.025).abs() < 1e-12);
        assert!((lattice_slice_width(&[Real::NAN, 0.0], LAMBDA) - 0.025).abs() < 1e-12);
    }

    /// Five strips λ·2 apart (−0.2 … 0.2) reach 2.5λ: modulo 0.125 they are
    /// 0.05, 0.025, 0, 0.1, 0.075, every λ/2.
    #[test]
    fn a_wider_lattice_gives_wider_slices() {
        let w = lattice_slice_width(&[-0.2, -0.1, 0.0, 0.1, 0.2], LAMBDA);
        assert!((w - 0.125).abs() < 1e-12, "{w}");
    }

    /// The offsets point3 itself reports over the floor z = 0, for an edge
    /// along x: its nine downward range finders land at x = −0.1, 0, 0.1
    /// (three each); the horizontal and upward ones miss the plane.
    #[test]
    fn point3_over_the_floor_reports_its_lattice() {
        let (f, poly) = super::super::tests::floor_follower();
        let e = EdgeRef {
            key: EdgeKey(0),
            segment: poly,
            index: 0,
            a: Point3::new(0.0, 0.0, 0.0),
            b: Point3::new(1.0, 0.0, 0.0),
            shared_with: None,
        };
        let mut offsets = f.lattice_offsets(&e, &Vector3::x());
        offsets.sort_by(Real::total_cmp);
        assert_eq!(offsets.len(), 9, "{offsets:?}");
        for (i, o) in offsets.iter().enumerate() {
            let want = [-0.1, 0.0, 0.1][i / 3];
            assert!((o - want).abs() < 1e-9, "{offsets:?}");
        }
        let w = lattice_slice_width(&offsets, LAMBDA);
        assert!((w - 0.075).abs() < 1e-12, "{w}");
    }

    fn edge_at(a: Point3, b: Point3) -> EdgeRef {
        EdgeRef {
            key: EdgeKey(9),
            segment: surface::SegmentId(3),
            index: 0,
            a,
            b,
            shared_with: None,
        }
    }

    /// The outward test by hand: a slice line along +x through the origin
    /// on a face with normal +z, so outside is x × z = −y. An edge 4λ
    /// outside (y = −0.2) keeps the line, which the thesis' "within λ"
    /// would not; one 0.04 inside (less than λ) keeps it; one 0.06 inside
    /// (more than λ) does not, nor one at 60° to the line, nor the same
    /// edge run clockwise (180°).
    #[test]
    fn the_outward_rule_keeps_the_line_for_an_edge_that_moved_outward() {
        let line = SliceLine {
            point: Point3::origin(),
            dir: Vector3::x_axis(),
            width: 0.5 * LAMBDA,
            used: BTreeSet::from([0, 1]),
        };
        let n = Vector3::z();
        let keeps = |a: [Real; 2], b: [Real; 2]| {
            let e = edge_at(Point3::new(a[0], a[1], 0.0), Point3::new(b[0], b[1], 0.0));
            outward_retained(&line, &e, &n, LAMBDA)
        };
        assert!(keeps([0.0, -0.2], [1.0, -0.2]));
        assert!(keeps([0.0, 0.04], [1.0, 0.04]));
        assert!(!keeps([0.0, 0.06], [1.0, 0.06]));
        assert!(!keeps([0.0, -0.2], [0.5, -0.2 + 0.5 * 3.0_f64.sqrt()]));
        assert!(!keeps([1.0, -0.2], [0.0, -0.2]));
        // The same edge 4λ out fails the thesis' nearness (P§3.4.3, Fig. 33(a)).
        let e = edge_at(Point3::new(0.0, -0.2, 0.0), Point3::new(1.0, -0.2, 0.0));
        assert!((e.a - line.foot(&e.a)).norm() > LAMBDA);
    }

    /// The follower over the floor: a slice line with slices 0 and 1 used
    /// and slice 2 current, and a new current edge on the same polygon
    /// parallel to the line 4λ outside it. The thesis rule defines a new
    /// line (no used slices, no current slice); the outward rule keeps the
    /// line, its used slices and slice 2, which the new edge passes through
    /// (0 ≤ x ≤ 1 spans slices 0 to 39).
    #[test]
    fn a_changed_edge_keeps_the_slices_only_under_the_outward_rule() {
        for rule in [SliceLineRule::Thesis, SliceLineRule::Outward] {
            let (mut f, poly) = super::super::tests::floor_follower();
            f.config.slice_line = rule;
            let n = f.model.polygon(poly).expect("a polygon").normal();
            // Anticlockwise about the normal: +x with n = +z, −x with −z.
            let dir = unit(Vector3::x() * n.z.signum()).expect("a direction");
            let out = dir.cross(&n);
            let line = SliceLine {
                point: Point3::origin(),
                dir,
                width: 0.5 * LAMBDA,
                used: BTreeSet::from([0, 1]),
            };
            f.state.slices = Some(line.clone());
            f.state.edge_segment = Some(poly);
            f.state.slice = Some(2);
            let a = Point3::origin() + out * (4.0 * LAMBDA);
            let e = EdgeRef {
                segment: poly,
                ..edge_at(a, a + dir.into_inner())
            };
            f.set_current_edge(&e);
            let kept = f.state.slices.clone().expect("a slice line");
            match rule {
                SliceLineRule::Thesis => {
                    assert!(kept.used.is_empty(), "{kept:?}");
                    assert!((kept.point - e.a).norm() < 1e-12);
                    assert_eq!(f.state.slice, None);
                }
                SliceLineRule::Outward => {
                    assert_eq!(kept, line);
                    assert_eq!(f.state.slice, Some(2));
                }
            }
            assert_eq!(f.state.edge, Some(e.key));
        }
    }
}
