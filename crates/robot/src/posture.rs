//! A robot held at joint values: the joints and the link frames they give,
//! kept in step. What a simulated arm is between two motions (the
//! simulator's rig, Stage Two's map probe).

use crate::error::RobotError;
use crate::model::Robot;
use geom::{Isometry3, Real};

/// Joint values and `base_from_link` of every link at them.
#[derive(Clone, Debug, PartialEq)]
pub struct Posture {
    q: Vec<Real>,
    base_from_link: Vec<Isometry3>,
}

impl Posture {
    /// `robot` at `q`; the joint limits are not checked (a start pose is
    /// the caller's to judge). An error when `q` is not one value a joint.
    pub fn new(robot: &Robot, q: &[Real]) -> Result<Self, RobotError> {
        Ok(Self {
            q: q.to_vec(),
            base_from_link: robot.forward_kinematics(q)?,
        })
    }

    /// Move to `q`, which must lie within the joint limits; on error the
    /// posture is unchanged.
    pub fn move_to(&mut self, robot: &Robot, q: &[Real]) -> Result<(), RobotError> {
        robot.check_within_limits(q)?;
        robot.fk_into(q, &mut self.base_from_link)?;
        self.q.clear();
        self.q.extend_from_slice(q);
        Ok(())
    }

    /// The joint values.
    pub fn joints(&self) -> &[Real] {
        &self.q
    }

    /// `base_from_link` of every link.
    pub fn base_from_link(&self) -> &[Isometry3] {
        &self.base_from_link
    }

    /// `base_from_scanner`, or `None` when `robot` carries no scanner.
    pub fn base_from_scanner(&self, robot: &Robot) -> Option<Isometry3> {
        let mount = robot.scanner.as_ref()?;
        Some(self.base_from_link[mount.link.0] * mount.link_from_scanner)
    }
}
