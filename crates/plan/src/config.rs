//! The planning parameters (A§3.2.3, §4.3; Table 6.1's n_Q).

use crate::PlanError;
use geom::Real;
use serde::{Deserialize, Serialize};

/// Parameters of the C-space model and of motion checks. `Default` is Paul's
/// (Table 6.1: n_Q = 1571) where the thesis gives a value; the rest are ours and
/// say why in their field docs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlanConfig {
    /// Number of sampled C-space nodes `n_Q` (A Table 6.1: 1571). They are the
    /// roadmap's nodes and Stage One's contending viewpoints (A§3.2.3).
    pub n_q: usize,
    /// Seed of the node sampling (uniform within the joint limits).
    pub seed: u64,
    /// Each node is joined to its `neighbours` nearest nodes in the
    /// joint-weighted distance; a minimum spanning tree is added so the
    /// roadmap is one connected component.
    pub neighbours: usize,
    /// Joint weights of the distance `Σ wᵢ |Δqᵢ|` (metres per radian, or per
    /// metre for prismatic joints). Empty: derived from the robot, each joint's
    /// weight being the farthest any bounding-ellipsoid point beyond it lies from
    /// its axis over the sampled nodes, so the weighted distance of a motion
    /// bounds (to first order) how far any point of the arm's envelope moves.
    pub joint_weights: Vec<Real>,
    /// Configurations along a motion are checked at least every
    /// `check_step_m` of joint-weighted distance (with derived weights: of
    /// envelope travel). A quarter of exploration's 0.1 m planning voxel.
    pub check_step_m: Real,
    /// `dist(Q)` (eq. 3.5) is resolved up to this value; larger distances
    /// report `safety_cap`. Voxels farther than `√cap` ellipsoid radii are not
    /// visited, which bounds the work per pose. 9 (three radii).
    pub safety_cap: Real,
}

impl Default for PlanConfig {
    fn default() -> Self {
        Self {
            n_q: 1571,
            seed: 0,
            neighbours: 10,
            joint_weights: Vec::new(),
            check_step_m: 0.025,
            safety_cap: 9.0,
        }
    }
}

impl PlanConfig {
    /// Check every field against a robot with `dof` joints.
    pub fn validate(&self, dof: usize) -> Result<(), PlanError> {
        if self.n_q < 2 {
            return Err(PlanError::config("plan.n_q", "at least 2", self.n_q));
        }
        if self.neighbours == 0 {
            return Err(PlanError::config("plan.neighbours", "at least 1", 0));
        }
        if !self.joint_weights.is_empty()
            && (self.joint_weights.len() != dof
                || self
                    .joint_weights
                    .iter()
                    .any(|w| !(w.is_finite() && *w > 0.0)))
        {
            return Err(PlanError::config(
                "plan.joint_weights",
                "empty, or one positive finite weight per joint",
                format!("{:?} for a robot with {dof} joints", self.joint_weights),
            ));
        }
        if !(self.check_step_m.is_finite() && self.check_step_m > 0.0) {
            return Err(PlanError::config(
                "plan.check_step_m",
                "a positive length",
                self.check_step_m,
            ));
        }
        if !(self.safety_cap.is_finite() && self.safety_cap > 1.0) {
            return Err(PlanError::config(
                "plan.safety_cap",
                "a finite value above 1",
                self.safety_cap,
            ));
        }
        Ok(())
    }
}
