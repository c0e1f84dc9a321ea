//! Parameters of surface following, with Pudney's values (P§4.3) as defaults.

use crate::FollowError;
use geom::Real;
use serde::{Deserialize, Serialize};

/// Which objective generates the reconfiguration vector `z` of eq. 3.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Eq. 4–5 (App. A): the distance of each link from the surface model.
    #[default]
    LinkDistance,
    /// App. B: proximity switches on the links (the link range finders read as
    /// binary switches: object present when a reading is within range).
    ProximitySwitches,
}

/// How current edge following (P§3.4.3) cuts the unexposed surface near the
/// current edge into slices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SliceRule {
    /// Pudney's rule: slices λ/2 wide, whatever the sensors cover.
    #[default]
    Thesis,
    /// Our addition: the slice width is taken from where the control
    /// point's range finders land on the current segment's plane (its
    /// lattice), the widest for which the strips of passes one slice apart
    /// interleave no more than λ/2 apart, as one sensor's strips do with
    /// the thesis' slices (`follower/edge_following.rs`,
    /// `lattice_slice_width`).
    Lattice,
}

impl SliceRule {
    /// Name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Thesis => "thesis",
            Self::Lattice => "lattice",
        }
    }
}

/// When current edge following keeps its slice line, its used slices and
/// its current slice after the current edge changes (P§3.4.3, P§3.4.6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SliceLineRule {
    /// Pudney's rule (P§3.4.3, Fig. 33): the line and its used slices are
    /// kept for a new current edge on the same segment whose vertices lie
    /// within λ of the line, at less than 45° to it, with a used slice
    /// through it; the current slice is chosen anew.
    #[default]
    Thesis,
    /// Our addition: the line and its used slices are also kept when the
    /// new current edge lies on the same segment, at less than 45° to the
    /// line, and neither vertex lies more than λ inside the line (the edge
    /// only moved outward: the model grew), used slice or not; the current
    /// slice is kept too when it passes through the new edge and is not
    /// used, so a slice is followed across the unexposed surface in one
    /// pass (`follower/edge_following.rs`, `outward_retained`).
    Outward,
}

impl SliceLineRule {
    /// Name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Thesis => "thesis",
            Self::Outward => "outward",
        }
    }
}

/// Which gap-following target points (P§3.4.5) count as detected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GapTargetRule {
    /// Pudney's rule: a target is detected by a sensor point within λ/2 of
    /// it in a set taken while gap following aims at it.
    #[default]
    Thesis,
    /// Our addition: a target within λ/2 of a point any earlier set sensed
    /// (since the run began) counts as detected at once, so gap following
    /// does not send the sensors over surface they already measured
    /// (`follower/gap_following.rs`, `SensedPoints`).
    Sensed,
}

impl GapTargetRule {
    /// Name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Thesis => "thesis",
            Self::Sensed => "sensed",
        }
    }
}

/// Surface-following parameters (SPEC §3.5; values of P§4.3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FollowConfig {
    /// Desired distance δ between the control point and the surface model
    /// (P§3.2), metres.
    pub desired_distance_m: Real,
    /// Maximum step σ_max of the control point (P§3.2), metres.
    pub max_step_m: Real,
    /// ρ: how far the control point may stray from what it follows (P§3.4.1),
    /// metres; Pudney sets it to the sensing range.
    pub stray_m: Real,
    /// Ceiling γ_p on the prismatic part of each actuator change (P§3.3), metres.
    pub ceiling_prismatic_m: Real,
    /// Ceiling γ_r on the revolute part of each actuator change (P§3.3), degrees.
    pub ceiling_revolute_deg: Real,
    /// Gain α of the null-space term (eq. 3). Zero turns redundancy off.
    pub alpha: Real,
    /// Exponent g of the objective (eq. 4), a positive integer.
    pub exponent: u32,
    /// √(2 d₀): distance from the model beyond which a link has no influence
    /// (eq. 4), metres.
    pub influence_m: Real,
    /// τ: the configuration is checked for progress every τ steps (P§3.4.7).
    pub progress_steps: u32,
    /// The reconfiguration objective.
    pub objective: Objective,
    /// Gap following gives up on a target point after this many steps without a
    /// sensor point near it (P§3.4.5 "after some time"; 0 = never give up
    /// except through the progress check).
    pub target_patience_steps: u32,
    /// Damping of the pseudo-inverse near singularities (0 = plain J⁺).
    pub damping: Real,
    /// The share of the ceilings γ_r and γ_p the control-point term `J⁺ẋ`
    /// of eq. 3 is granted before the reconfiguration term (our departure
    /// from P§3.3, see [`crate::actuator::actuator_change`]); 0 scales the
    /// whole actuator change by one factor, as Pudney does.
    pub task_share: Real,
    /// Gain of the joint-limit term added to the reconfiguration vector
    /// `z` of a redundant robot (our addition to eq. 5, see
    /// [`crate::actuator::joint_limit_gradient`]); 0 (the default) turns it
    /// off.
    pub joint_limit_gain: Real,
    /// How far the joint-limit term yields to link avoidance (our addition):
    /// the term is scaled by `1 − yield·w`, `w` the largest weight eq. 5
    /// gives any link ([`crate::actuator::largest_link_weight`]: 1 at the
    /// model, 0 beyond the influence distance). 0 takes the term whole; 1
    /// (the default since issue 45's repositioning; before, 0) leaves the
    /// null space to link avoidance wherever a link touches the model (with
    /// a steady `joint_limit_gain` of 0.01 not better, crate README).
    pub joint_limit_yield: Real,
    /// Repositioning before giving up (our addition to P§3.4.7, issue 45):
    /// when the progress check would give the goal up on a robot with joints
    /// to spare (more than three) while a joint lies in the outer tenth of
    /// its range, the follower first spends this many steps with the
    /// joint-limit term at [`Self::reposition_gain`] (and no new
    /// repositioning starts until twice that many steps after it ended).
    /// 0 gives up at once, as P§3.4.7; the default is 100, and
    /// [`Self::reposition_after_give_ups`] and
    /// [`Self::reposition_joints_near_limit`] say when it starts.
    pub reposition_steps: u32,
    /// The joint-limit gain while repositioning (see
    /// [`Self::reposition_steps`]; the larger of it and
    /// [`Self::joint_limit_gain`]); default 0.05.
    pub reposition_gain: Real,
    /// How many goals in a row the progress check must give up, none of
    /// its checks in between finding the robot moved, before a
    /// repositioning (see [`Self::reposition_steps`]) may start (our
    /// addition, issue 45); 0 or 1: at the first give-up; default 10.
    /// A robot whose joints on their limits hold it gives up goal after
    /// goal without moving (arm4 on block2: rows of up to 25, one every 11
    /// steps); most give-ups of a run that moves on come one or a few at a
    /// time.
    pub reposition_after_give_ups: u32,
    /// How many joints must lie in the outer tenth of their ranges for a
    /// repositioning (see [`Self::reposition_steps`]) to start (our
    /// addition, issue 45); 0 or 1: one; default 2. arm4 stalled on
    /// block2 with its yaw and a wrist roll both on their limits.
    pub reposition_joints_near_limit: u32,
    /// The joint-limit term keeps links off (our addition, issue 45): its
    /// null-space motion `α(I − J⁺J)z_j` loses, within the null space, the
    /// part that would bring a link within the influence distance closer
    /// than its radius plus [`Self::link_margin_m`] from the model in one
    /// step, or a link already within that any closer (to first order; see
    /// [`crate::actuator::actuator_change_bounded`]). Pudney's link-distance
    /// term is taken as it is. `true` by default; `false` takes the
    /// joint-limit term whole: repositioning (`reposition_steps`) at a raised gain then
    /// pushed arm4's last link onto block2's edge between the chamfer and
    /// the +y face until the safety guard held it at its margin, where the
    /// model's chamfer ended up to 6 mm short of the true edge (14.2 mm
    /// true clearance; crate README).
    pub joint_limit_keeps_links_off: bool,
    /// A link closer to the model than its radius plus this margin may not be
    /// brought closer by the control-point motion (our addition to P§3.3,
    /// see [`crate::actuator::actuator_change`]), metres.
    pub link_margin_m: Real,
    /// The safety guard (our addition, [`crate::guard`]): every step's
    /// motion is checked against the model (with strips past its unshared
    /// edges), the segments it deleted and the raw readings of the last
    /// sets before it is taken.
    pub guard: bool,
    /// The guard's margin: no link shape is brought closer than this to
    /// known surface, metres.
    pub guard_margin_m: Real,
    /// How many of the last sensor sets the guard keeps as raw readings.
    pub guard_recent_sets: u32,
    /// The guard takes every unshared polygon edge to go on this far past
    /// the polygon, in its plane, metres (0: the polygons as they are);
    /// default λ/2 for Pudney's λ = 0.05 (see [`crate::guard`]).
    pub guard_edge_extension_m: Real,
    /// The guard takes every unshared edge of an initial segment (P§4.3: a table the
    /// objects stand on, a face given a priori) to go on this far past it,
    /// in its plane, metres: a brim that keeps the links from passing round
    /// the segment's edge to behind it (0: the segments as they are).
    pub guard_initial_extension_m: Real,
    /// The guard demands this much more clearance, metres, from every
    /// convex fold of the model: a shared edge, of a polygon that is not an
    /// initial segment, whose neighbour lies behind the polygon's plane (0,
    /// the default: no more than from the rest). Under range noise a fitted
    /// plane tilts and the model's folds lie inside the true edges, by 5–23
    /// mm on block2's vertical edges (see [`crate::guard`]). Unshared
    /// edges have their strip ([`Self::guard_edge_extension_m`]) instead.
    pub guard_convex_edge_margin_m: Real,
    /// How current edge following cuts slices (P§3.4.3): `thesis` (λ/2
    /// wide) or `lattice` (width from the control point's sensor lattice).
    pub slices: SliceRule,
    /// When a changed current edge keeps the slice line (P§3.4.3,
    /// P§3.4.6): `thesis` or `outward` (also while the edge only moves
    /// outward).
    pub slice_line: SliceLineRule,
    /// Which gap-following targets count as detected (P§3.4.5): `thesis`
    /// or `sensed` (also those an earlier set already sensed).
    pub gap_targets: GapTargetRule,
}

impl Default for FollowConfig {
    fn default() -> Self {
        Self {
            desired_distance_m: 0.1,
            max_step_m: 0.1,
            stray_m: 0.2,
            ceiling_prismatic_m: 0.05,
            ceiling_revolute_deg: 3.8,
            alpha: 7000.0,
            exponent: 6,
            influence_m: 0.2,
            progress_steps: 10,
            objective: Objective::LinkDistance,
            target_patience_steps: 20,
            damping: 1e-3,
            task_share: 0.15,
            joint_limit_gain: 0.0,
            joint_limit_yield: 1.0,
            reposition_steps: 100,
            reposition_gain: 0.05,
            reposition_after_give_ups: 10,
            reposition_joints_near_limit: 2,
            joint_limit_keeps_links_off: true,
            link_margin_m: 0.05,
            guard: true,
            guard_margin_m: 0.02,
            guard_recent_sets: 10,
            guard_edge_extension_m: 0.025,
            guard_initial_extension_m: 0.2,
            guard_convex_edge_margin_m: 0.0,
            slices: SliceRule::Thesis,
            slice_line: SliceLineRule::Thesis,
            gap_targets: GapTargetRule::Thesis,
        }
    }
}

/// Largest [`FollowConfig::max_step_m`], metres: ten times Pudney's 0.1 m,
/// far past the few centimetres the range finders see (issue 48: 1e308
/// was taken as it was).
pub const MAX_STEP_M: Real = 1.0;

impl FollowConfig {
    /// Check every field; the error names the field and what was expected.
    pub fn validate(&self) -> Result<(), FollowError> {
        let bad = |field: &'static str, expected: &'static str, got: String| {
            Err(FollowError::Config {
                field,
                expected,
                got,
            })
        };
        let positive = |field: &'static str, v: Real| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                bad(field, "a finite value > 0", v.to_string())
            }
        };
        positive("desired_distance_m", self.desired_distance_m)?;
        positive("max_step_m", self.max_step_m)?;
        if self.max_step_m > MAX_STEP_M {
            return bad(
                "max_step_m",
                "a step of at most 1 m (MAX_STEP_M)",
                format!("{:e}", self.max_step_m),
            );
        }
        positive("stray_m", self.stray_m)?;
        positive("ceiling_prismatic_m", self.ceiling_prismatic_m)?;
        positive("ceiling_revolute_deg", self.ceiling_revolute_deg)?;
        positive("influence_m", self.influence_m)?;
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return bad("alpha", "a finite gain ≥ 0", self.alpha.to_string());
        }
        if !(self.task_share.is_finite() && (0.0..=1.0).contains(&self.task_share)) {
            return bad(
                "task_share",
                "a share in 0..=1",
                self.task_share.to_string(),
            );
        }
        if !(self.joint_limit_gain.is_finite() && self.joint_limit_gain >= 0.0) {
            return bad(
                "joint_limit_gain",
                "a finite gain ≥ 0",
                self.joint_limit_gain.to_string(),
            );
        }
        if !(self.joint_limit_yield.is_finite() && (0.0..=1.0).contains(&self.joint_limit_yield)) {
            return bad(
                "joint_limit_yield",
                "a fraction in 0..=1",
                self.joint_limit_yield.to_string(),
            );
        }
        if !(self.reposition_gain.is_finite() && self.reposition_gain >= 0.0) {
            return bad(
                "reposition_gain",
                "a gain ≥ 0",
                self.reposition_gain.to_string(),
            );
        }
        if !(self.link_margin_m.is_finite() && self.link_margin_m >= 0.0) {
            return bad(
                "link_margin_m",
                "a finite distance ≥ 0",
                self.link_margin_m.to_string(),
            );
        }
        if !(self.guard_margin_m.is_finite() && self.guard_margin_m >= 0.0) {
            return bad(
                "guard_margin_m",
                "a finite distance ≥ 0",
                self.guard_margin_m.to_string(),
            );
        }
        if !(self.guard_edge_extension_m.is_finite()
            && (0.0..=1.0).contains(&self.guard_edge_extension_m))
        {
            return bad(
                "guard_edge_extension_m",
                "a distance in 0..=1",
                self.guard_edge_extension_m.to_string(),
            );
        }
        if !(self.guard_initial_extension_m.is_finite()
            && (0.0..=1.0).contains(&self.guard_initial_extension_m))
        {
            return bad(
                "guard_initial_extension_m",
                "a distance in 0..=1",
                self.guard_initial_extension_m.to_string(),
            );
        }
        if !(self.guard_convex_edge_margin_m.is_finite()
            && (0.0..=1.0).contains(&self.guard_convex_edge_margin_m))
        {
            return bad(
                "guard_convex_edge_margin_m",
                "a distance in 0..=1",
                self.guard_convex_edge_margin_m.to_string(),
            );
        }
        if self.guard_recent_sets > 1000 {
            return bad(
                "guard_recent_sets",
                "at most 1000 sets",
                self.guard_recent_sets.to_string(),
            );
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return bad("damping", "a finite value ≥ 0", self.damping.to_string());
        }
        if self.exponent == 0 || self.exponent > 64 {
            return bad(
                "exponent",
                "an integer in 1..=64",
                self.exponent.to_string(),
            );
        }
        if self.progress_steps == 0 {
            return bad("progress_steps", "at least 1", "0".into());
        }
        if self.stray_m <= self.desired_distance_m {
            return bad(
                "stray_m",
                "more than desired_distance_m (eq. 6 blends over δ < ‖v₁‖ < ρ)",
                format!(
                    "{} with desired_distance_m {}",
                    self.stray_m, self.desired_distance_m
                ),
            );
        }
        Ok(())
    }

    /// γ_r in radians.
    pub fn ceiling_revolute_rad(&self) -> Real {
        self.ceiling_revolute_deg.to_radians()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An edit of the defaults, the field it breaks and the value it gives.
    type Case = (fn(&mut FollowConfig), &'static str, &'static str);

    /// Each bad field is named in a typed error, with what it accepts and
    /// the value given.
    #[test]
    fn bad_fields_are_named() {
        let cases: [Case; 7] = [
            (|c| c.max_step_m = -1.0, "max_step_m", "-1"),
            (|c| c.max_step_m = 1e308, "max_step_m", "1e308"),
            (|c| c.alpha = Real::NAN, "alpha", "NaN"),
            (|c| c.link_margin_m = -0.5, "link_margin_m", "-0.5"),
            (|c| c.exponent = 65, "exponent", "65"),
            (|c| c.progress_steps = 0, "progress_steps", "0"),
            (
                |c| c.stray_m = 0.05,
                "stray_m",
                "0.05 with desired_distance_m 0.1",
            ),
        ];
        assert!(FollowConfig::default().validate().is_ok());
        for (edit, name, value) in cases {
            let mut c = FollowConfig::default();
            edit(&mut c);
            match c.validate() {
                Err(FollowError::Config { field, got, .. }) => {
                    assert_eq!((field, got.as_str()), (name, value));
                }
                other => panic!("{name}: {other:?}"),
            }
        }
    }
}
