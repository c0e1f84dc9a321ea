//! Stage One's parameters (A Table 6.1 where the thesis gives them).

use crate::ExploreError;
use crate::gain::GainKind;
use geom::Real;
use plan::PlanConfig;
use sensor::SweepConfig;
use serde::{Deserialize, Serialize};

/// How a candidate's sweep is predicted (A§4.2, Fig. 4.3): a subset of the
/// sweep's rays is cast through the planning grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PredictionConfig {
    /// Angle between predicted rays in a scan, degrees (the scanner's own
    /// step is 0.36°; 2° puts about one ray per 0.05 m voxel at 1.4 m).
    pub ray_step_deg: Real,
    /// Tilt between predicted scans, degrees (the sweep's own step is 0.4°).
    pub tilt_step_deg: Real,
    /// Scanner poses predicted along the straight joint motion from the
    /// current pose to a candidate, evenly spaced, when Stage One scans while
    /// moving ([`ExploreConfig::motion_scan_step_deg`] > 0); 0 predicts the
    /// sweep alone, as Paul did. The path the planner finds may bend
    /// through roadmap nodes: the straight motion is the prediction.
    pub motion_poses: usize,
}

impl Default for PredictionConfig {
    fn default() -> Self {
        Self {
            ray_step_deg: 2.0,
            tilt_step_deg: 2.0,
            motion_poses: 8,
        }
    }
}

/// Most scanner poses predicted along a motion.
pub const MAX_MOTION_POSES: usize = 1000;

/// How Stage One chooses among its safe candidates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// The largest gain ([`ExploreConfig::gain`]; by default the most
    /// information predicted, `ΔH1/H1₀ + ΔH2/H2₀`: geometric and C-space
    /// information revealed, each over its value before the first sweep),
    /// ties to the lower index. Our choice: Paul's
    /// rank sum favours the front's small moves (f3) and safest poses (f4),
    /// and on the bridge scenes the arm then turned its wrist for ten
    /// viewpoints before its shoulder moved (see the crate README).
    #[default]
    Information,
    /// A§3.2.2, eq. 3.7–3.8: the Pareto front of (f1, f2, f3, f4), the
    /// lowest rank sum, f1 breaking ties.
    RankSum,
    /// A baseline: a candidate drawn uniformly among the clear candidates
    /// whose sweep is safe, roadmap nodes and local poses alike (after the
    /// first sweep on bridge1 no roadmap node is safe), seeded by the plan
    /// seed and the number of sweeps; one without a safe path is dropped
    /// and another drawn.
    Random,
    /// A baseline after Yamauchi (1997): the nearest candidate (the
    /// roadmap's weighted joint distance) whose predicted rays cross the
    /// frontier, from a free voxel into an unknown one, into at least
    /// [`crate::stage_one::FRONTIER_MIN_VOXELS`] unknown voxels.
    Frontier,
}

/// How the arm moves while the scanner scans (a transit that scans, a
/// sweep).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    /// Stop and go: the arm steps, settles, and the scanner scans
    /// standing; a transit scans after every `motion_scan_step_deg`, a
    /// sweep after every tilt step. Paul's system scanned so (A§5.1).
    #[default]
    StopAndGo,
    /// Continuous ([`hw::motion`]): a transit's every straight segment and
    /// a sweep's tilt are each one timed motion with the scanner scanning
    /// all along (a scan every `scan_time`), each beam placed at the pose
    /// of its moment. A transit moves at most `motion_scan_step_deg` per
    /// scan on its largest joint (and within the joints' limits), a
    /// sweep its tilt step per scan. Hardware that cannot scan while
    /// moving is refused.
    Continuous,
}

/// How Stage Two chooses its next viewpoint.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StageTwoChoice {
    /// The most material information predicted: LM poses (g1–g6) are found
    /// for up to `stage_two_candidates` of the discs with the most `H3`
    /// left, each pose's sweep is predicted on Stage One's mesh, and the
    /// pose whose predicted sweep gives the LRC a usable observation of the
    /// most `H3` over *every* disc it sees, per second of the robot's time
    /// (the way there and the sweep), is taken among those a safe path
    /// reaches (when none is, the next discs of the ranking: see
    /// `stage_two_target_windows`). A disc a chosen sweep was predicted to
    /// identify and did not is not counted again. Our choice:
    /// Paul's one disc a viewpoint identified 50–100 of bridge1's 8866 discs
    /// in A2 per viewpoint (the crate README measures both).
    #[default]
    Information,
    /// A§3.3, §6.3.2: the disc with the most `H3` left that a valid,
    /// reachable LM pose targets.
    Thesis,
}

/// The map products made after Stage One (A§5.2–5.3, Table 6.1's
/// "Mapping" row): Scale-Like Discs of the TSDF mesh (μ = 0.04 m, n_min = 8)
/// and their segmentation (τq, τd, τp, τθ).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MappingConfig {
    /// Disc generation.
    pub sld: map::SldConfig,
    /// Segmentation thresholds.
    pub segment: map::SegmentConfig,
}

/// Largest [`ExploreConfig::local_reach_m`], metres.
pub const MAX_LOCAL_REACH_M: Real = 10.0;
/// Most [`ExploreConfig::local_candidates`].
pub const MAX_LOCAL_CANDIDATES: usize = 10_000;
/// Most viewpoints of either stage.
pub const MAX_VIEWPOINTS: usize = 1000;
/// Most plan attempts per decision, and Stage Two targets tried.
pub const MAX_ATTEMPTS: usize = 10_000;
/// Most nodes a motion's ends are joined to.
pub const MAX_LINK_K: usize = 100;

/// Parameters of Stage One (A§3.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExploreConfig {
    /// The C-space model and motion checks (n_Q = 1571, Table 6.1).
    pub plan: PlanConfig,
    /// Voxel size of the planning grid (occupancy, H1, H2, dist(Q)), metres.
    /// Paul's grid held n_v = 41 070 voxels (Table 6.1); 0.1 m over the
    /// bridge scenes' A3 gives 74 088 (at 0.05 m the ellipsoids' margin over
    /// the voxel centres is too thin to move: see the README).
    pub planning_voxel_m: Real,
    /// The tilt sweep taken at every viewpoint (α = 60°, Table 6.1). Not read
    /// from an `[explore]` table: a scenario's runner sets it from the
    /// scanner's `[scanner.sweep]`, the one place a sweep is configured.
    #[serde(skip)]
    pub sweep: SweepConfig,
    /// Region weights `{c_w1, c_w2, c_w3}` of eq. 4.11 (Table 6.1).
    #[serde(deserialize_with = "geom::exact::array")]
    pub weights: [Real; 3],
    /// Ray subsampling of the information prediction.
    pub prediction: PredictionConfig,
    /// Stage One stops when both `ΔH1` and `ΔH2` of the last viewpoint fall
    /// below this fraction of their initial values (A§3.2.4: 1 %).
    pub stop_fraction: Real,
    /// Stage One ends after this many viewpoints at the latest (the first,
    /// from the start pose, included).
    pub max_viewpoints: usize,
    /// Candidates sampled around the current pose at each decision, besides
    /// the roadmap's `n_Q` nodes (see [`ExploreConfig::local_reach_m`]).
    pub local_candidates: usize,
    /// Local candidates move each joint by up to `local_reach_m / wᵢ` (`wᵢ`
    /// the joint weight, metres of envelope travel per radian), so none moves
    /// any point of the arm's envelope much more than this (to first order).
    pub local_reach_m: Real,
    /// Nodes each end of a motion is joined to when planning through the
    /// roadmap.
    pub link_k: usize,
    /// Chosen candidates tried before a decision gives up (a candidate with
    /// no safe path is dropped and the choice made again without it).
    pub max_plan_attempts: usize,
    /// Stage Two's pose selection (A§3.3, Table 6.1: φ_max 42°, d ∈ [0.25,
    /// 0.8] m, ρ_min 15 mm, LM {50, 1e−4}).
    pub pose: plan::PoseConfig,
    /// Stage Two ends after this many viewpoints at the latest.
    pub stage_two_max_viewpoints: usize,
    /// A disc is worth targeting while its `H3` is above this fraction of
    /// its uniform-prior value (`ln n_t` per voxel).
    pub significant_h3: Real,
    /// Discs tried (in order of `H3`) per Stage Two viewpoint before Stage
    /// Two ends: a disc whose pose is invalid, whose sweep is unsafe or which
    /// no safe path reaches is passed over for good.
    pub stage_two_target_attempts: usize,
    /// With [`StageTwoChoice::Information`], windows of
    /// `stage_two_target_attempts` discs of the ranking a decision aims in
    /// before Stage Two ends: the next window only when no pose aimed at in
    /// this one is reachable. One window ended channel4's Stage Two (seed 0,
    /// continuous motion) before its first viewpoint, when the arm stood
    /// where none of the 5 valid poses of the first 16 discs had a safe
    /// path and discs further down the ranking had.
    pub stage_two_target_windows: usize,
    /// How Stage Two chooses (`"information"` or Paul's `"thesis"`).
    pub stage_two: StageTwoChoice,
    /// With [`StageTwoChoice::Information`], LM poses scored per decision
    /// (each for a disc at least `stage_two_spread_m` from the others).
    pub stage_two_candidates: usize,
    /// The discs a decision aims at are at least this far apart, metres.
    pub stage_two_spread_m: Real,
    /// Stage Two keeps the robot's collision capsules at least this far from
    /// the surface Stage One mapped (its TSDF mesh), along the path to a
    /// viewpoint and through its sweep, metres. `dist(Q)` is measured to
    /// voxel centres of the planning grid (0.1 m), so on its own it lets a
    /// link pass within a few millimetres of a seen surface; Stage Two, which
    /// aims the scanner at surfaces from 0.25–0.8 m, comes that close.
    pub stage_two_clearance_m: Real,
    /// The discs and segments made of Stage One's map.
    pub mapping: MappingConfig,
    /// Stage One scans while the arm moves to the next viewpoint, a scan
    /// each time the joints have moved this far (the largest joint change,
    /// degrees), as well as at the viewpoint; 0 scans only at viewpoints,
    /// as Paul did (A§3.2). Our addition: a line scanner keeps scanning
    /// while the arm moves (the Hokuyo of A§5.1 gives a scan every 100 ms:
    /// the default 1° is the arm at 10°/s).
    pub motion_scan_step_deg: Real,
    /// Stage Two scans while the arm moves to its next viewpoint, a scan
    /// each time the joints have moved this far (degrees, as
    /// `motion_scan_step_deg`), and the LRC classifies those scans as it
    /// does a viewpoint's sweep (A§4.4: every ray updates the material
    /// belief of the voxel it hits); 0 scans at viewpoints only, as Paul.
    pub stage_two_scan_step_deg: Real,
    /// How the arm moves while the scanner scans.
    pub motion: Motion,
    /// How the next viewpoint is chosen among the safe candidates (also
    /// read as `strategy`).
    #[serde(alias = "strategy")]
    pub selection: Selection,
    /// How `selection = "information"` scores a candidate's predicted sweep
    /// ([`crate::gain`]: ours, Paul's f1, or one of Delmerico et al.'s
    /// volumetric gains).
    pub gain: GainKind,
    /// Stage One keeps the robot's collision capsules at least this far
    /// from every point the scanner has measured, along the path to a
    /// viewpoint and through its sweep, metres (0: `dist(Q) > 1` alone, as
    /// Paul). `dist(Q)` is measured to the planning grid's voxel centres: on
    /// its own it let links pass within 13 mm of the true beams once the
    /// arm reached into the channel.
    pub stage_one_clearance_m: Real,
}

impl Default for ExploreConfig {
    fn default() -> Self {
        Self {
            plan: PlanConfig::default(),
            planning_voxel_m: 0.1,
            sweep: SweepConfig::default(),
            weights: [0.6, 0.35, 0.05],
            prediction: PredictionConfig::default(),
            stop_fraction: 0.01,
            max_viewpoints: 20,
            local_candidates: 600,
            local_reach_m: 0.6,
            link_k: 10,
            max_plan_attempts: 400,
            pose: plan::PoseConfig::default(),
            stage_two_max_viewpoints: 20,
            significant_h3: 0.5,
            stage_two_target_attempts: 60,
            stage_two_target_windows: 4,
            stage_two: StageTwoChoice::Information,
            stage_two_candidates: 16,
            stage_two_spread_m: 0.3,
            stage_two_clearance_m: 0.05,
            mapping: MappingConfig::default(),
            motion_scan_step_deg: 1.0,
            stage_two_scan_step_deg: 0.0,
            motion: Motion::StopAndGo,
            selection: Selection::Information,
            gain: GainKind::Information,
            stage_one_clearance_m: 0.05,
        }
    }
}

impl ExploreConfig {
    /// Paul's Stage One (A§3.2): the rank sum on the Pareto front, scans
    /// only at viewpoints, the sweep alone predicted, `dist(Q) > 1` the only
    /// safety rule, and 200 local candidates within 0.3 m (what this
    /// configuration had before ours); every other parameter as `self`'s.
    pub fn thesis_stage_one(mut self) -> Self {
        self.selection = Selection::RankSum;
        self.motion_scan_step_deg = 0.0;
        self.motion = Motion::StopAndGo;
        self.prediction.motion_poses = 0;
        self.stage_one_clearance_m = 0.0;
        self.local_candidates = 200;
        self.local_reach_m = 0.3;
        self
    }
}

impl ExploreConfig {
    /// Check every field.
    pub fn validate(&self) -> Result<(), ExploreError> {
        let bad = |field: &'static str, expected: &'static str, got: String| ExploreError::Config {
            field,
            expected,
            got,
        };
        if !(self.planning_voxel_m.is_finite() && self.planning_voxel_m > 0.0) {
            return Err(bad(
                "explore.planning_voxel_m",
                "a positive length",
                self.planning_voxel_m.to_string(),
            ));
        }
        self.sweep.validate()?;
        if self.weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(bad(
                "explore.weights",
                "three finite, non-negative weights",
                format!("{:?}", self.weights),
            ));
        }
        self.plan.validate(0).or_else(|e| match e {
            // The joint count is checked against the robot later.
            plan::PlanError::Config {
                field: "plan.joint_weights",
                ..
            } => Ok(()),
            e => Err(ExploreError::Plan(e)),
        })?;
        self.validate_angles()?;
        if self.prediction.motion_poses > MAX_MOTION_POSES {
            return Err(bad(
                "explore.prediction.motion_poses",
                "at most 1000 poses",
                self.prediction.motion_poses.to_string(),
            ));
        }
        if !(self.stop_fraction.is_finite() && (0.0..1.0).contains(&self.stop_fraction)) {
            return Err(bad(
                "explore.stop_fraction",
                "a fraction in [0, 1)",
                self.stop_fraction.to_string(),
            ));
        }
        if !(self.local_reach_m.is_finite()
            && (0.0..=MAX_LOCAL_REACH_M).contains(&self.local_reach_m))
        {
            return Err(bad(
                "explore.local_reach_m",
                "a length from 0 to 10 metres",
                self.local_reach_m.to_string(),
            ));
        }
        if self.local_candidates > MAX_LOCAL_CANDIDATES {
            return Err(bad(
                "explore.local_candidates",
                "at most 10000 (each is scored like a roadmap node)",
                self.local_candidates.to_string(),
            ));
        }
        if !(self.significant_h3.is_finite() && (0.0..=1.0).contains(&self.significant_h3)) {
            return Err(bad(
                "explore.significant_h3",
                "a fraction in [0, 1]",
                self.significant_h3.to_string(),
            ));
        }
        for (field, v) in [
            ("explore.max_viewpoints", self.max_viewpoints),
            (
                "explore.stage_two_max_viewpoints",
                self.stage_two_max_viewpoints,
            ),
        ] {
            if v > MAX_VIEWPOINTS {
                return Err(bad(field, "at most 1000 viewpoints", v.to_string()));
            }
        }
        for (field, v) in [
            ("explore.max_plan_attempts", self.max_plan_attempts),
            (
                "explore.stage_two_target_attempts",
                self.stage_two_target_attempts,
            ),
            ("explore.stage_two_candidates", self.stage_two_candidates),
        ] {
            if v > MAX_ATTEMPTS {
                return Err(bad(field, "at most 10000", v.to_string()));
            }
        }
        let w = self.stage_two_target_windows;
        if !(1..=MAX_ATTEMPTS).contains(&w) {
            return Err(bad(
                "explore.stage_two_target_windows",
                "from 1 to 10000 windows",
                w.to_string(),
            ));
        }
        if self.link_k > MAX_LINK_K {
            return Err(bad(
                "explore.link_k",
                "at most 100",
                self.link_k.to_string(),
            ));
        }
        for (field, v) in [
            ("explore.stage_one_clearance_m", self.stage_one_clearance_m),
            ("explore.stage_two_clearance_m", self.stage_two_clearance_m),
            ("explore.stage_two_spread_m", self.stage_two_spread_m),
        ] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return Err(bad(field, "a length from 0 to 1 metre", v.to_string()));
            }
        }
        if self.max_viewpoints == 0 {
            return Err(bad("explore.max_viewpoints", "at least 1", "0".into()));
        }
        self.pose.validate().map_err(ExploreError::Plan)?;
        self.mapping.sld.validate()?;
        self.mapping.segment.validate()?;
        if self.link_k == 0 || self.max_plan_attempts == 0 {
            return Err(bad(
                "explore.link_k / explore.max_plan_attempts",
                "at least 1",
                "0".into(),
            ));
        }
        Ok(())
    }

    /// Check the angle steps: the prediction's, and the transits' scans.
    fn validate_angles(&self) -> Result<(), ExploreError> {
        let bad = |field: &'static str, expected: &'static str, got: String| ExploreError::Config {
            field,
            expected,
            got,
        };
        for (field, v) in [
            (
                "explore.prediction.ray_step_deg",
                self.prediction.ray_step_deg,
            ),
            (
                "explore.prediction.tilt_step_deg",
                self.prediction.tilt_step_deg,
            ),
        ] {
            // The scanner's own steps are 0.36° and 0.4°: a finer prediction
            // casts rays the scanner never has.
            if !(v.is_finite() && (0.1..=90.0).contains(&v)) {
                return Err(bad(field, "an angle from 0.1 to 90 degrees", v.to_string()));
            }
        }
        for (field, m) in [
            ("explore.motion_scan_step_deg", self.motion_scan_step_deg),
            (
                "explore.stage_two_scan_step_deg",
                self.stage_two_scan_step_deg,
            ),
        ] {
            if !(m.is_finite() && (m == 0.0 || (0.1..=90.0).contains(&m))) {
                return Err(bad(
                    field,
                    "0 (no scans while moving) or an angle from 0.1 to 90 degrees",
                    m.to_string(),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stage Two's transit scans and decision windows are checked like the
    /// other steps and counts: the field is named, the value stated.
    #[test]
    fn stage_two_transit_and_window_settings_are_checked() {
        assert!(ExploreConfig::default().validate().is_ok());
        for step in [0.05, -1.0, Real::NAN, 91.0] {
            let c = ExploreConfig {
                stage_two_scan_step_deg: step,
                ..ExploreConfig::default()
            };
            let e = c.validate().unwrap_err().to_string();
            assert!(e.contains("explore.stage_two_scan_step_deg"), "{e}");
        }
        for step in [0.0, 0.1, 3.0, 90.0] {
            let c = ExploreConfig {
                stage_two_scan_step_deg: step,
                ..ExploreConfig::default()
            };
            assert!(c.validate().is_ok(), "{step}");
        }
        for windows in [0, MAX_ATTEMPTS + 1] {
            let c = ExploreConfig {
                stage_two_target_windows: windows,
                ..ExploreConfig::default()
            };
            let e = c.validate().unwrap_err().to_string();
            assert!(e.contains("explore.stage_two_target_windows"), "{e}");
        }
    }
}
