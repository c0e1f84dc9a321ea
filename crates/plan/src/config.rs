//! The planning parameters (A§3.2.3, §4.3; Table 6.1's n_Q).

use crate::PlanError;
use geom::Real;
use serde::{Deserialize, Serialize};

/// Most roadmap nodes `n_Q` (Paul's 1571 is a thirteenth of it).
pub const MAX_N_Q: usize = 20_000;
/// Most neighbours a node is joined to.
pub const MAX_NEIGHBOURS: usize = 100;
/// Smallest step at which motions are checked, metres.
pub const MIN_CHECK_STEP_M: Real = 0.001;
/// Largest step at which motions are checked, metres.
pub const MAX_CHECK_STEP_M: Real = 1.0;

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
        // The likelihoods L(cᵢ) plan a path between every pair of nodes:
        // n_Q² paths, the model's cost.
        if !(2..=MAX_N_Q).contains(&self.n_q) {
            return Err(PlanError::config("plan.n_q", "2 to 20000", self.n_q));
        }
        if !(1..=MAX_NEIGHBOURS).contains(&self.neighbours) {
            return Err(PlanError::config(
                "plan.neighbours",
                "1 to 100",
                self.neighbours,
            ));
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
        // A motion is checked every check_step_m of weighted distance: the
        // floor bounds the configurations one motion costs.
        if !(self.check_step_m.is_finite()
            && (MIN_CHECK_STEP_M..=MAX_CHECK_STEP_M).contains(&self.check_step_m))
        {
            return Err(PlanError::config(
                "plan.check_step_m",
                "a length from 0.001 to 1 metres",
                self.check_step_m,
            ));
        }
        if !(self.safety_cap.is_finite() && self.safety_cap > 1.0 && self.safety_cap <= 100.0) {
            return Err(PlanError::config(
                "plan.safety_cap",
                "a value in (1, 100]",
                self.safety_cap,
            ));
        }
        Ok(())
    }
}
