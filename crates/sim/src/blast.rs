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
    let poses = blast_poses(robot, world_from_base, config)?;
    let d = &run.discs;
    let scope = in_region(run, a2);
    let found: Vec<Option<BlastTarget>> = scope
        .par_iter()
        .map(|&i| -> Result<Option<BlastTarget>, SimError> {
            let Some((q, m)) = disc_pose(&poses, &run.grid, run, i)? else {
                return Ok(None);
            };
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

/// The discs of `run` in `a2` that a nozzle pose reaches when everything is
/// known: the same pose selection as [`plan_blast`], against a grid of
/// `run.grid`'s geometry made from the ground truth (a voxel is occupied
/// when the true surface passes within its half-diagonal of its centre,
/// free otherwise). The denominator of "poses for ≥ 95 % of the discs
/// reachable by the tool" (issue 11).
pub fn reachable_discs(
    run: &ExploreRun,
    robot: &Robot,
    world_from_base: Isometry3,
    a2: &RegionBox,
    scene: &scene::Scene,
    config: &BlastConfig,
) -> Result<Vec<usize>, SimError> {
    use rayon::prelude::*;
    let truth = ground_truth_grid(&run.grid, scene)?;
    let poses = blast_poses(robot, world_from_base, config)?;
    let found: Vec<Option<usize>> = in_region(run, a2)
        .into_par_iter()
        .map(|i| Ok(disc_pose(&poses, &truth, run, i)?.map(|_| i)))
        .collect::<Result<_, SimError>>()?;
    Ok(found.into_iter().flatten().collect())
}

/// The pose selection of `config` for `robot` at `world_from_base`.
fn blast_poses(
    robot: &Robot,
    world_from_base: Isometry3,
    config: &BlastConfig,
) -> Result<BlastPoses, SimError> {
    Ok(BlastPoses::new(
        robot,
        world_from_base,
        &PlanConfig::default(),
        vec![1.0; robot.dof()],
        &config.pose,
        config.tool,
    )?)
}

/// The discs of `run` whose centres are in `region`.
fn in_region(run: &ExploreRun, region: &RegionBox) -> Vec<usize> {
    let d = &run.discs.discs;
    (0..d.len())
        .filter(|&i| region.contains(&d[i].centre))
        .collect()
}

/// A valid blast pose for disc `i` of `run` against `grid` (the LM starting
/// from the joints of the viewpoint that saw the disc), re-measured.
fn disc_pose(
    poses: &BlastPoses,
    grid: &map::OccupancyGrid,
    run: &ExploreRun,
    i: usize,
) -> Result<Option<(Vec<Real>, plan::BlastMeasure)>, SimError> {
    let d = &run.discs;
    let target = Target::from_disc(&d.discs[i]);
    let start = &run.viewpoints[d.viewpoint[i]].joints;
    let solution = poses.select(grid, &target, start)?;
    if !solution.valid() {
        return Ok(None);
    }
    let q = solution.joints().to_vec();
    let m = poses.measure(grid, &target, &q)?;
    Ok(m.valid.then_some((q, m)))
}

/// A grid of `like`'s geometry with the ground truth's occupancy: occupied
/// where `scene`'s surface passes within a voxel's half-diagonal of its
/// centre, free elsewhere.
fn ground_truth_grid(
    like: &map::OccupancyGrid,
    scene: &scene::Scene,
) -> Result<map::OccupancyGrid, SimError> {
    let mut grid = map::OccupancyGrid::new(*like.config())?;
    let g = *grid.geometry();
    let v = g.voxel_m();
    let reach = 0.5 * v * 3f64.sqrt();
    let k0 = g.key_min().coords();
    let [nx, ny, nz] = g.dims();
    let (mut origins, mut points) = (Vec::new(), Vec::new());
    for z in 0..nz as i32 {
        for y in 0..ny as i32 {
            for x in 0..nx as i32 {
                let key = map::VoxelKey::new(k0[0] + x, k0[1] + y, k0[2] + z);
                let c = key.center(v);
                grid.mark_free(key)?;
                if scene.closest_point(&c, reach).is_some() {
                    // A return at the centre from inside the voxel: a hit.
                    origins.push(c + Vector3::new(0.1 * v, 0.0, 0.0));
                    points.push(c);
                }
            }
        }
    }
    grid.integrate_points(&origins, &points)?;
    Ok(grid)
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
