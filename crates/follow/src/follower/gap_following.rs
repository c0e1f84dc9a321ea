//! Gap following (P§3.4.5, Fig. 35–36): the gap point, target points every
//! λ/2 and the controlled sensor.

use super::{Directive, Flow, Follower, Gap, Mode};
use crate::config::GapTargetRule;
use crate::query::ModelPoint;
use geom::{Point3, Real, Segment3, polygon2};
use std::collections::HashMap;

/// A cube of [`SensedPoints`]' grid, by its integer coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Cell([i64; 3]);

/// Every sensor point the run has sensed, in a grid of cubes `radius`
/// wide, for [`GapTargetRule::Sensed`] (our addition to P§3.4.5): whether a
/// gap-following target lies within `radius` (λ/2) of a point an earlier set
/// sensed. Lookups only, so hash order never shows.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct SensedPoints {
    radius: Real,
    cells: HashMap<Cell, Vec<Point3>>,
}

impl SensedPoints {
    pub(super) fn new(radius: Real) -> Self {
        Self {
            radius,
            cells: HashMap::new(),
        }
    }

    fn cell(&self, p: &Point3) -> Cell {
        let k = |v: Real| (v / self.radius).floor() as i64;
        Cell([k(p.x), k(p.y), k(p.z)])
    }

    pub(super) fn insert(&mut self, points: &[Point3]) {
        for p in points
            .iter()
            .filter(|p| p.coords.iter().all(|v| v.is_finite()))
        {
            let c = self.cell(p);
            self.cells.entry(c).or_default().push(*p);
        }
    }

    /// Whether some point lies closer than the radius to `target`.
    pub(super) fn any_near(&self, target: &Point3) -> bool {
        let Cell([x, y, z]) = self.cell(target);
        (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dz| {
                    self.cells
                        .get(&Cell([x + dx, y + dy, z + dz]))
                        .is_some_and(|ps| ps.iter().any(|p| (p - target).norm() < self.radius))
                })
            })
        })
    }
}

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
            // Our addition (`gap_targets = "sensed"`): a target the sensors
            // already landed near, in this set or an earlier one, is not
            // visited again. Only for gaps of current edge following: point
            // following's targets run to the point segment, sensed already,
            // and it waits for that segment to become a polygon.
            let detected = detected
                || (gap.from == Mode::Edge
                    && self.config.gap_targets == GapTargetRule::Sensed
                    && self.sensed.as_ref().is_some_and(|s| s.any_near(&target)));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand, radius λ/2 = 0.025 (cells 0.025 wide): points at the origin
    /// and at (0.1, 0, 0). (0.02, 0.01, 0) is √0.0005 ≈ 0.0224 from the
    /// origin; (0.076, 0, 0) is 0.024 from (0.1, 0, 0), in the cell before
    /// its own along x; (−0.001, 0, 0) is 0.001 from the origin across the
    /// cell border at 0. (0.05, 0, 0) is 0.05 from both and (0.0, 0.0,
    /// 0.026) 0.026 from the origin: not near.
    #[test]
    fn sensed_points_are_found_across_cell_borders() {
        let mut s = SensedPoints::new(0.025);
        assert!(!s.any_near(&Point3::origin()));
        s.insert(&[Point3::origin(), Point3::new(0.1, 0.0, 0.0)]);
        for near in [[0.02, 0.01, 0.0], [0.076, 0.0, 0.0], [-0.001, 0.0, 0.0]] {
            assert!(s.any_near(&Point3::from(near)), "{near:?}");
        }
        for far in [[0.05, 0.0, 0.0], [0.0, 0.0, 0.026]] {
            assert!(!s.any_near(&Point3::from(far)), "{far:?}");
        }
    }
}
