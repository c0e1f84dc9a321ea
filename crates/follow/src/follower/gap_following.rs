//! Gap following (P§3.4.5, Fig. 35–36): the gap point, target points every
//! λ/2 and the controlled sensor.

use super::{Directive, Flow, Follower, Gap, Mode};
use crate::query::ModelPoint;
use geom::{Point3, Real, Segment3, polygon2};

/// Gap following deems the controlled sensor aimed at its target when its
/// sensing axis passes within this fraction of λ of it (λ/20 = 2.5 mm at
/// Pudney's λ; the detection radius is λ/2).
const AIM_FRACTION: Real = 0.05;

impl Follower {
    /// Switch from mode `from` to gap following (P§3.4.5), towards the
    /// current point `current_point` ([`Follower::gap_targets`]).
    pub(super) fn start_gap(
        &mut self,
        from: Mode,
        current_point: &Point3,
        closest: &ModelPoint,
        lambda: Real,
    ) {
        let targets = self.gap_targets(current_point, closest, lambda);
        self.state.gap = Some(Gap {
            from,
            targets,
            next: 0,
            sensor: None,
            steps_on_target: 0,
        });
        self.state.mode = Mode::Gap;
    }

    /// Target points of gap following (P§3.4.5, Fig. 35–36), from the gap
    /// point towards the current point every λ/2.
    pub(super) fn gap_targets(
        &self,
        current_point: &Point3,
        closest: &ModelPoint,
        lambda: Real,
    ) -> Vec<Point3> {
        let gap_point = match self.model.polygon(closest.segment) {
            None => closest.point,
            Some(poly) => {
                let projected = poly.plane().project(current_point);
                let frame = poly.frame();
                let pts = poly.points_2d(&frame);
                let (p2, c2) = (frame.to_2d(&projected), frame.to_2d(&closest.point));
                let n = pts.len();
                let mut best: Option<(Real, Point3)> = None;
                for i in 0..n {
                    let hit = match polygon2::intersect_segments(
                        &p2,
                        &c2,
                        &pts[i],
                        &pts[(i + 1) % n],
                        1e-12,
                    ) {
                        polygon2::SegmentIntersection::Point { s, .. } => Some(s),
                        polygon2::SegmentIntersection::Overlap { s0, .. } => Some(s0),
                        polygon2::SegmentIntersection::None => None,
                    };
                    if let Some(s) = hit {
                        let x = frame.to_3d(&(p2 + (c2 - p2) * s));
                        let d = (x - projected).norm();
                        if best.is_none_or(|b| d < b.0) {
                            best = Some((d, x));
                        }
                    }
                }
                best.map_or(closest.point, |b| b.1)
            }
        };
        let span = current_point - gap_point;
        let len = span.norm();
        let spacing = 0.5 * lambda;
        let count = (len / spacing).floor() as usize + 1;
        (0..count.min(1000))
            .map(|i| {
                if len > 0.0 {
                    gap_point + span * ((i as Real * spacing) / len)
                } else {
                    gap_point
                }
            })
            .collect()
    }

    /// Gap following (P§3.4.5).
    pub(super) fn gap_following(&mut self, cp: &Point3) -> Flow {
        let Some(gap) = self.state.gap.clone() else {
            self.state.mode = Mode::Segment;
            return Flow::Again;
        };
        let lambda = self.model.config().lambda;
        match gap.from {
            Mode::Point => {
                let still_point = self
                    .state
                    .segment
                    .and_then(|s| self.model.segment(s))
                    .is_some_and(|s| s.as_point().is_some());
                if !still_point {
                    self.state.gap = None;
                    self.state.edge = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
            }
            _ => {
                if self.state.edge.is_none() {
                    self.state.gap = None;
                    self.state.mode = Mode::Segment;
                    return Flow::Again;
                }
            }
        }
        let mut gap = gap;
        loop {
            let Some(&target) = gap.targets.get(gap.next) else {
                // All targets used: the gap was not closed.
                self.state.gap = None;
                if gap.from == Mode::Point {
                    if let Some(p) = self.state.point.as_mut()
                        && let Some(k) = p.current.take()
                    {
                        p.used[k] = true;
                    }
                    self.state.mode = Mode::Point;
                } else {
                    self.slice_used();
                    self.state.follow = None;
                    self.state.mode = Mode::Segment;
                }
                return Flow::Again;
            };
            // Detection counts from the sets taken after the target was
            // chosen: the set in hand was taken before the sensor was aimed
            // (and the gap point itself is a model point, sensed already).
            let detected = gap.steps_on_target > 0
                && self
                    .last_points
                    .iter()
                    .any(|p| (p - target).norm() < 0.5 * lambda);
            let patience = self.config.target_patience_steps;
            if detected || (patience > 0 && gap.steps_on_target >= patience) {
                gap.next += 1;
                gap.sensor = None;
                gap.steps_on_target = 0;
                continue;
            }
            if gap.sensor.is_none() {
                gap.sensor = self.controlled_sensor(&target);
                self.reset_progress();
            }
            let Some(sensor) = gap.sensor else {
                gap.next += 1;
                continue;
            };
            let Some(axis_point) = self.axis_point(sensor, &target) else {
                gap.next += 1;
                gap.sensor = None;
                continue;
            };
            let dir = target - axis_point;
            let d = dir.norm();
            // A gap we fill (P§3.4.5 gives up a target "after some time"):
            // once the controlled sensor's axis passes within `AIM` of the
            // target at the pose the set in hand was taken from, that set is
            // what aiming at the target yields, and with the sensor on target
            // the robot stands still (σ ≤ d), so later sets repeat it. No
            // point near the target in it: give the target up now rather
            // than idle until the progress check (P§3.4.7) or the patience.
            if d < AIM_FRACTION * lambda {
                gap.next += 1;
                gap.sensor = None;
                gap.steps_on_target = 0;
                continue;
            }
            gap.steps_on_target += 1;
            self.state.gap = Some(gap);
            let _ = cp;
            return Flow::Go(Directive {
                dir,
                step_limit: (d < self.config.max_step_m).then_some(d),
            });
        }
    }

    /// The control-point sensor whose sensing axis is closest to `target`.
    pub(super) fn controlled_sensor(&self, target: &Point3) -> Option<usize> {
        self.cp_sensors
            .iter()
            .filter_map(|&i| self.axis_point(i, target).map(|p| ((p - target).norm(), i)))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, i)| i)
    }

    /// The point of sensor `i`'s sensing axis (origin to range) closest to
    /// `target`, at the current pose.
    pub(super) fn axis_point(&self, i: usize, target: &Point3) -> Option<Point3> {
        let m = self.robot.range_finders.get(i)?;
        let frame = self.frames.get(m.link.0)?;
        let o = frame * m.origin;
        let a = frame.rotation * m.axis;
        Some(Segment3::new(o, o + a.into_inner() * m.max_range_m).closest_point(target))
    }
}
