//! Blast plans over an exploration's map (Paul App. A): a pose for every disc
//! in A2 that a nozzle on the flange can blast within its limits
//! ([`plan::BlastPoses`], App. A.1), then, segment by segment, the order of
//! the targets by the GA of App. A.2, reported with the nearest-neighbour
//! order and its 2-opt improvement on the same cost ([`plan::sequence`]).
//!
//! Discs without a valid pose are listed, not dropped. Each pose's LM starts
//! from the joints of the viewpoint that saw its disc. Deterministic for a
//! seed.

use crate::SimError;
use crate::explore_run::ExploreRun;
use geom::{Isometry3, Real, Vector3};
use map::RegionBox;
use plan::sequence::{GaConfig, Targets, Weights, genetic, nearest_neighbour, two_opt};
use plan::{BlastPoses, BlastTool, PlanConfig, PoseConfig, Target};
use robot::Robot;
use serde::{Deserialize, Serialize};

/// How a blast plan is made.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlastConfig {
    /// The nozzle and its limits.
    pub tool: BlastTool,
    /// The GA (its seed is mixed with each segment's index).
    pub ga: GaConfig,
    /// LM settings of the pose selection (its limits come from `tool`).
    pub pose: PoseConfig,
}

/// One target of a plan: a disc and the pose that blasts it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlastTarget {
    /// The disc (index into the run's discs).
    pub disc: usize,
    /// The joints.
    pub joints: Vec<Real>,
    /// Nozzle tip, world frame.
    pub nozzle: [Real; 3],
    /// Stream direction, world frame.
    pub direction: [Real; 3],
    /// Angle between the stream and the disc normal, degrees.
    pub phi_deg: Real,
    /// Stream length to the disc's plane, metres.
    pub d_m: Real,
    /// Distance from where the stream meets the plane to the disc centre, m.
    pub aim_error_m: Real,
    /// `dist(Q)` against the run's occupied and unknown voxels.
    pub dist: Real,
}

/// The plan of one segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentPlan {
    /// The segment (index into the run's segments).
    pub segment: usize,
    /// The targets, in the GA's order.
    pub targets: Vec<BlastTarget>,
    /// Discs of the segment in A2 without a valid pose.
    pub no_pose: Vec<usize>,
    /// The comparison weights (eq. A.10 on the nearest-neighbour order).
    pub weights: Weights,
    /// Cost (eq. A.9) of the nearest-neighbour order.
    pub cost_nearest_neighbour: Real,
    /// Cost of its 2-opt improvement.
    pub cost_two_opt: Real,
    /// Cost of the GA's order.
    pub cost_ga: Real,
}

/// A blast plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlastPlan {
    /// The nozzle and its limits.
    pub tool: BlastTool,
    /// Discs in A2 (the ones a plan is sought for).
    pub discs_in_scope: usize,
    /// Of those, the ones with a valid pose.
    pub discs_with_pose: usize,
    /// Segments with at least one disc in A2, in segment order.
    pub segments: Vec<SegmentPlan>,
}

/// The blast plan of `run`'s discs in `a2`, for `robot` at
/// `world_from_base` (the run's robot and placement), checked against the
/// run's planning grid.
pub fn plan_blast(
    run: &ExploreRun,
    robot: &Robot,
    world_from_base: Isometry3,
    a2: &RegionBox,
    config: &BlastConfig,
) -> Result<BlastPlan, SimError> {
    use rayon::prelude::*;
    let poses = BlastPoses::new(
        robot,
        world_from_base,
        &PlanConfig::default(),
        vec![1.0; robot.dof()],
        &config.pose,
        config.tool,
    )?;
    let d = &run.discs;
    let scope: Vec<usize> = (0..d.discs.len())
        .filter(|&i| a2.contains(&d.discs[i].centre))
        .collect();
    let found: Vec<Option<BlastTarget>> = scope
        .par_iter()
        .map(|&i| -> Result<Option<BlastTarget>, SimError> {
            let disc = &d.discs[i];
            let target = Target::from_disc(disc);
            let start = &run.viewpoints[d.viewpoint[i]].joints;
            let solution = poses.select(&run.grid, &target, start)?;
            if !solution.valid() {
                return Ok(None);
            }
            let q = solution.joints().to_vec();
            let m = poses.measure(&run.grid, &target, &q)?;
            if !m.valid {
                return Ok(None);
            }
            let nozzle = robot_nozzle(&poses, &world_from_base, &q)?;
            let dir = nozzle.rotation * Vector3::z();
            let tip = nozzle.translation.vector;
            Ok(Some(BlastTarget {
                disc: i,
                joints: q,
                nozzle: [tip.x, tip.y, tip.z],
                direction: [dir.x, dir.y, dir.z],
                phi_deg: m.phi_deg,
                d_m: m.d_m,
                aim_error_m: m.aim_error_m,
                dist: m.dist,
            }))
        })
        .collect::<Result<_, _>>()?;
    let mut by_disc: Vec<Option<BlastTarget>> = vec![None; d.discs.len()];
    let mut in_scope = vec![false; d.discs.len()];
    for (&i, t) in scope.iter().zip(found) {
        in_scope[i] = true;
        by_disc[i] = t;
    }
    let with_pose = by_disc.iter().filter(|t| t.is_some()).count();
    let mut segments = Vec::new();
    for (s, members) in d.segments.iter().enumerate() {
        let members: Vec<usize> = members
            .iter()
            .map(|id| id.0)
            .filter(|&i| in_scope[i])
            .collect();
        if members.is_empty() {
            continue;
        }
        let no_pose: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&i| by_disc[i].is_none())
            .collect();
        let targets: Vec<BlastTarget> =
            members.iter().filter_map(|&i| by_disc[i].clone()).collect();
        let centres: Vec<geom::Point3> = targets.iter().map(|t| d.discs[t.disc].centre).collect();
        let joints: Vec<Vec<Real>> = targets.iter().map(|t| t.joints.clone()).collect();
        let table = Targets::new(&centres, &joints).ok_or_else(|| SimError::InvalidArgument {
            what: "blast plan".into(),
            message: "targets and poses disagree".into(),
        })?;
        let nn0 = nearest_neighbour(&table, 0, Weights::normalising(1.0, 1.0));
        let weights = Weights::of_population(&table, std::slice::from_ref(&nn0));
        let nn = nearest_neighbour(&table, 0, weights);
        let opt = two_opt(&table, &nn, weights);
        let ga = genetic(
            &table,
            &opt,
            weights,
            &GaConfig {
                seed: config.ga.seed ^ (s as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                ..config.ga
            },
        );
        segments.push(SegmentPlan {
            segment: s,
            targets: ga.order.iter().map(|&k| targets[k].clone()).collect(),
            no_pose,
            weights,
            cost_nearest_neighbour: table.cost(&nn, weights),
            cost_two_opt: table.cost(&opt, weights),
            cost_ga: ga.cost,
        });
    }
    Ok(BlastPlan {
        tool: config.tool,
        discs_in_scope: scope.len(),
        discs_with_pose: with_pose,
        segments,
    })
}

/// The nozzle's pose in the world at `q`.
fn robot_nozzle(
    poses: &BlastPoses,
    world_from_base: &Isometry3,
    q: &[Real],
) -> Result<Isometry3, SimError> {
    poses
        .robot()
        .scanner_pose(q)?
        .map(|p| world_from_base * p)
        .ok_or(SimError::NoScanner)
}

impl BlastPlan {
    /// `blast_plan.csv`: one row per target, segments in order and the
    /// targets of each in the GA's order.
    pub fn csv(&self) -> String {
        use std::fmt::Write as _;
        let mut out = String::from(
            "segment,order,disc,q1,q2,q3,q4,q5,q6,nozzle_x,nozzle_y,nozzle_z,dir_x,dir_y,dir_z,phi_deg,d_m,aim_error_m,dist\n",
        );
        for s in &self.segments {
            for (k, t) in s.targets.iter().enumerate() {
                let _ = write!(out, "{},{k},{}", s.segment, t.disc);
                for v in t.joints.iter().chain(&t.nozzle).chain(&t.direction).chain([
                    &t.phi_deg,
                    &t.d_m,
                    &t.aim_error_m,
                    &t.dist,
                ]) {
                    let _ = write!(out, ",{v}");
                }
                out.push('\n');
            }
        }
        out
    }

    /// Write `blast_plan.json` and `blast_plan.csv` into `dir`.
    pub fn write(&self, dir: &std::path::Path) -> Result<(), SimError> {
        let err = |e: &dyn std::fmt::Display| SimError::InvalidArgument {
            what: dir.display().to_string(),
            message: format!("cannot write the blast plan: {e}"),
        };
        let json = serde_json::to_string_pretty(self).map_err(|e| err(&e))?;
        std::fs::write(dir.join("blast_plan.json"), json).map_err(|e| err(&e))?;
        std::fs::write(dir.join("blast_plan.csv"), self.csv()).map_err(|e| err(&e))
    }
}
