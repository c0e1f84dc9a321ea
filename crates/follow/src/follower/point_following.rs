//! Point following (P§3.4.4): four slices through a point segment.

use super::{Directive, Flow, Follower, Mode, PointSlices};
use crate::query::ModelPoint;
use geom::{Point3, Vector3, unit};

impl Follower {
    /// Point following (P§3.4.4).
    pub(super) fn point_following(&mut self, cp: &Point3, closest: &ModelPoint) -> Flow {
        let Some(seg) = self.state.segment else {
            self.state.mode = Mode::Surface;
            return Flow::Again;
        };
        let Some(point) = self.model.segment(seg).and_then(|s| s.as_point().copied()) else {
            // It became a planar polygon: on to its edges; the slice line is
            // not retained.
            self.state.point = None;
            self.state.edge = None;
            self.state.slices = None;
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let c = point.centroid();
        if self.state.point.as_ref().is_none_or(|p| p.centre != c) {
            let towards = cp - c;
            let n = unit(towards).unwrap_or_else(Vector3::z_axis);
            let helper = if n.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let v1 = unit(n.cross(&helper)).unwrap_or_else(Vector3::x_axis);
            let v3 = unit(n.cross(&v1)).unwrap_or_else(Vector3::y_axis);
            let used = self.state.point.as_ref().map_or([false; 4], |p| p.used);
            self.state.point = Some(PointSlices {
                centre: c,
                dirs: [v1, -v1, v3, -v3],
                used,
                current: None,
            });
        }
        let Some(ps) = self.state.point.as_mut() else {
            return Flow::Again;
        };
        if ps.current.is_none() {
            if let Some(k) = (0..4).find(|&k| !ps.used[k]) {
                ps.current = Some(k);
                self.reset_progress();
            } else {
                self.marks.unclosable_points.insert(seg);
                self.state.point = None;
                self.state.mode = Mode::Surface;
                return Flow::Again;
            }
        }
        let Some(ps) = self.state.point.clone() else {
            return Flow::Again;
        };
        let Some(k) = ps.current else {
            return Flow::Again;
        };
        // A departure made explicit: Pudney puts no limit on the distance
        // along a point-following slice; we deem it used beyond ρ, as in
        // current edge following, so a point that never grows cannot hold the
        // robot forever.
        if (cp - c).norm() > self.config.stray_m {
            if let Some(p) = self.state.point.as_mut() {
                p.used[k] = true;
                p.current = None;
            }
            return Flow::Again;
        }
        if closest.segment != seg {
            let lambda = self.model.config().lambda;
            self.start_gap(Mode::Point, &c, closest, lambda);
            return Flow::Again;
        }
        let v = ps.dirs[k];
        let foot = c + v.into_inner() * (cp - c).dot(&v);
        let u = cp - foot;
        Flow::Go(Directive {
            dir: v.cross(&u),
            step_limit: None,
        })
    }
}
