//! Current edge following (P§3.4.3, Fig. 31–34): the slice line, slices of
//! width λ/2, the current point, the retention rules and the
//! little-unexposed-surface test.

use super::{Directive, Flow, Follower, Mode, SliceLine};
use crate::query::{EdgeRef, Feature, ModelPoint, closest_on_segment, edge_by_key};
use geom::{Point3, Real, Segment3, Vector3, unit};
use std::collections::BTreeSet;

/// Slice numbers through edge `e` (inclusive range).
fn slice_range(line: &SliceLine, e: &EdgeRef, width: Real) -> (i64, i64) {
    let (ta, tb) = (line.param(&e.a), line.param(&e.b));
    let lo = (ta.min(tb) / width).floor() as i64;
    let hi = ((ta.max(tb) / width).ceil() as i64 - 1).max(lo);
    (lo, hi)
}

impl Follower {
    /// Choose `e` as the current edge, testing whether the slice line can be
    /// kept (P§3.4.3, Fig. 33).
    pub(super) fn set_current_edge(&mut self, e: &EdgeRef) {
        let lambda = self.model.config().lambda;
        let width = 0.5 * lambda;
        let retained = self.state.slices.as_ref().is_some_and(|line| {
            let same_segment = self.state.edge_segment == Some(e.segment);
            let near =
                (e.a - line.foot(&e.a)).norm() < lambda && (e.b - line.foot(&e.b)).norm() < lambda;
            let dir = e.b - e.a;
            let aligned =
                unit(dir).is_some_and(|d| d.dot(&line.dir) > std::f64::consts::FRAC_PI_4.cos());
            let (ka, kb) = slice_range(line, e, width);
            let any_used = (ka..=kb).any(|k| line.used.contains(&k));
            same_segment && near && aligned && any_used
        });
        if !retained {
            let dir = unit(e.b - e.a).unwrap_or_else(Vector3::x_axis);
            self.state.slices = Some(SliceLine {
                point: e.a,
                dir,
                used: BTreeSet::new(),
            });
            self.state.any_edge = true;
        }
        self.state.edge = Some(e.key);
        self.state.edge_segment = Some(e.segment);
        self.state.slice = None;
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
        let width = 0.5 * lambda;
        let rho = self.config.stray_m;
        for _ in 0..64 {
            let Some(line) = self.state.slices.clone() else {
                self.set_current_edge(&e);
                continue;
            };
            let (ka, kb) = slice_range(&line, &e, width);
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
