//! Where a point on a link can be at all: a bound on its reachable positions
//! from the joint limits and the chain's lengths alone, with no search.
//!
//! The first actuated joint moves the axis of the second along a circle (a
//! line for a prismatic joint); from the second joint on, whatever the
//! joints do, the point stays within the summed lengths of the chain from
//! that joint's origin (rotations keep lengths: a revolute joint keeps the
//! point's distance from its axis, and a point on the axis not at all, as a
//! spherical wrist's centre). So every position of the
//! point lies within [`ReachBound::radius`] of one of the second joint's
//! origins at sampled values of the first ([`Robot::reach_bound`]). A test
//! that a point *cannot* be placed somewhere (a blast nozzle out of reach of
//! a disc) then costs a few hundred distances instead of an IK search.

use crate::model::{JointKind, LinkId, Robot};
use geom::{Isometry3, Point3, Real};

/// Every position a point on a link takes over the joint limits lies within
/// `radius` of one of `centres` (base frame).
#[derive(Clone, Debug, PartialEq)]
pub struct ReachBound {
    /// Origins of the second actuated joint's frame at evenly spaced values
    /// of the first (one centre when the chain has fewer than two joints
    /// before the link), base frame.
    pub centres: Vec<Point3>,
    /// The chain's summed offsets beyond the centres plus the largest gap
    /// between consecutive centres, metres.
    pub radius: Real,
}

impl ReachBound {
    /// `true` when the point can be within `distance` of somewhere for
    /// which `gap(centre)` is the distance from `centre` to the nearest such
    /// place: when some centre has `gap(centre) ≤ radius + distance`. A
    /// `false` is a proof that no configuration within the limits brings the
    /// point there.
    pub fn may_reach(&self, distance: Real, mut gap: impl FnMut(&Point3) -> Real) -> bool {
        let within = self.radius + distance;
        self.centres.iter().any(|c| gap(c) <= within)
    }
}

impl Robot {
    /// A bound on where the point at `link_from_point` on `link` can be over
    /// the joint limits ([`ReachBound`]), with the first actuated joint
    /// sampled at `samples + 1` values across its range (at least 2).
    ///
    /// `None` when the bound is unbounded: a prismatic joint on the chain
    /// without limits, or a first joint without limits that is not revolute.
    /// An unlimited revolute first joint is sampled over a full turn.
    pub fn reach_bound(
        &self,
        link: LinkId,
        link_from_point: &Isometry3,
        samples: usize,
    ) -> Option<ReachBound> {
        let chain = self.joints.get(..link.index())?;
        let actuated: Vec<usize> = (0..chain.len())
            .filter(|&i| chain[i].is_actuated())
            .collect();
        // How far a prismatic joint's motion can carry what follows it from
        // where the configuration of zeros puts it (the zeros apply the
        // offset, so that much more).
        let slide = |j: &crate::model::Joint| -> Option<Real> {
            let l = j.limits?;
            Some(j.offset.abs() + (l.min + j.offset).abs().max((l.max + j.offset).abs()))
        };
        let q0 = vec![0.0; self.dof()];
        let frames = self.forward_kinematics(&q0).ok()?;
        let Some(&first) = actuated.first() else {
            // Nothing moves the point.
            return Some(ReachBound {
                centres: vec![Point3::from(
                    (frames[link.index()] * link_from_point).translation.vector,
                )],
                radius: 0.0,
            });
        };
        // The chain's lengths beyond the pivot: the second actuated joint,
        // whose origin the first moves; with one actuated joint, that joint,
        // whose origin stands still. From the point back to the pivot, each
        // revolute joint's axis is fixed to the links before it, and its
        // motion keeps the distance from the point (and whatever the later
        // joints leave of it) to the axis: that distance is one length of
        // the chain, and the foot of the perpendicular, a point fixed to the
        // links before the joint, is where the next one is measured from. A
        // point on the axis costs nothing (a spherical wrist's centre). A
        // prismatic joint adds the distance to its origin and its slide.
        let pivot = actuated.get(1).copied().unwrap_or(first);
        let joint_frame = |m: usize| frames[m] * chain[m].origin;
        let mut at = Point3::from((frames[link.index()] * link_from_point).translation.vector);
        let mut radius = 0.0;
        for m in (pivot + 1..chain.len()).rev() {
            let j = &chain[m];
            let frame = joint_frame(m);
            let origin = Point3::from(frame.translation.vector);
            match j.kind {
                JointKind::Fixed => {}
                JointKind::Revolute => {
                    let axis = frame.rotation * j.axis.into_inner();
                    let foot = origin + axis * (at - origin).dot(&axis);
                    radius += (at - foot).norm();
                    at = foot;
                }
                JointKind::Prismatic => {
                    radius += (at - origin).norm() + slide(j)?;
                    at = origin;
                }
            }
        }
        // The pivot's origin is on its own axis: the distance to it is kept
        // by a rotation, grown by a slide.
        let centre = Point3::from(joint_frame(pivot).translation.vector);
        radius += (at - centre).norm();
        if chain[pivot].kind == JointKind::Prismatic {
            radius += slide(&chain[pivot])?;
        }
        let origin_at = |q: &[Real]| -> Option<Point3> {
            let frames = self.forward_kinematics(q).ok()?;
            Some(Point3::from(
                (frames[pivot] * chain[pivot].origin).translation.vector,
            ))
        };
        if pivot == first {
            return Some(ReachBound {
                centres: vec![origin_at(&q0)?],
                radius,
            });
        }
        let joint = &chain[first];
        let (lo, hi) = match (joint.limits, joint.kind) {
            (Some(l), _) => (l.min, l.max),
            (None, JointKind::Revolute) => (-std::f64::consts::PI, std::f64::consts::PI),
            _ => return None,
        };
        // Steps of at most half a turn, so that every point of an arc between
        // two samples is within its chord of the nearer one.
        let n = samples
            .max(2)
            .max(((hi - lo) / std::f64::consts::PI).ceil() as usize);
        let mut q = q0;
        let mut centres = Vec::with_capacity(n + 1);
        for s in 0..=n {
            q[0] = lo + (hi - lo) * s as Real / n as Real;
            centres.push(origin_at(&q)?);
        }
        // A value between two samples puts the centre on the arc (or line)
        // between theirs, within one chord of the nearer.
        radius += centres
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .fold(0.0, Real::max);
        Some(ReachBound { centres, radius })
    }

    /// The link nearest the base whose frame origin stays put in `link`'s
    /// frame whatever the joints between them do: on the axis of each, all
    /// revolute (within [`ON_AXIS_M`]). For a spherical wrist the wrist
    /// centre's link; `link` itself when no earlier one qualifies. Its
    /// origin's place in `link`'s frame is then one fixed offset, so where
    /// the tool can point from a place is bounded by where that origin can
    /// be ([`Robot::reach_bound`] of it).
    pub fn fixed_point_link(&self, link: LinkId) -> Option<LinkId> {
        let chain = self.joints.get(..link.index())?;
        let frames = self.forward_kinematics(&vec![0.0; self.dof()]).ok()?;
        let stays = |j: usize| {
            let p = Point3::from(frames[j].translation.vector);
            chain[j..]
                .iter()
                .enumerate()
                .all(|(k, joint)| match joint.kind {
                    JointKind::Fixed => true,
                    JointKind::Prismatic => false,
                    JointKind::Revolute => {
                        let frame = frames[j + k] * joint.origin;
                        let origin = Point3::from(frame.translation.vector);
                        let axis = frame.rotation * joint.axis.into_inner();
                        let v = p - origin;
                        (v - axis * v.dot(&axis)).norm() <= ON_AXIS_M
                    }
                })
        };
        (0..=link.index()).find(|&j| stays(j)).map(LinkId)
    }
}

/// How near a joint's axis a point counts as on it for
/// [`Robot::fixed_point_link`], metres: rounding, not geometry (the joint's
/// motion moves it twice as far).
pub const ON_AXIS_M: Real = 1e-9;
