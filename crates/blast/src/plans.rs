//! Blast plans over an exploration's map (Paul App. A): a pose for every disc
//! in A2 that a nozzle on the flange can blast within its limits
//! ([`BlastPoses`], App. A.1), then, segment by segment, the order of
//! the targets by the GA of App. A.2, reported with the nearest-neighbour
//! order and its 2-opt improvement on the same cost ([`crate::sequence`]).
//!
//! Discs without a valid pose are listed, not dropped. One disc per patch of
//! a segment (its seed) is solved from the joints of the viewpoint that saw
//! it, the patch's other discs first from the seed's pose, and a disc
//! without a pose then from its neighbours' poses (`select_poses`).
//! Deterministic for a seed.

use crate::BlastError;
use crate::poses::{BlastMeasure, BlastPoses, BlastTool};
use crate::sequence::{GaConfig, Targets, Weights, genetic, nearest_neighbour, two_opt};
use geom::{Isometry3, Real, Vector3};
use map::RegionBox;
use plan::{PlanConfig, PoseConfig, Target};
use record::blast::{BlastTarget, GridFile, PathWeights, SegmentPlan, Tri};
use robot::Robot;
use serde::{Deserialize, Serialize};

/// A blast plan: the record of `record::blast` with this crate's tool.
pub type BlastPlan = record::blast::BlastPlan<BlastTool>;

/// How a blast plan is made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlastConfig {
    /// The nozzle and its limits.
    pub tool: BlastTool,
    /// The GA (its seed is mixed with each segment's index).
    pub ga: GaConfig,
    /// LM settings of the pose selection (its limits and aim scale come
    /// from `tool`). Its `starts` are the LM runs of each disc's first
    /// try, from its viewpoint's joints ([`BLAST_STARTS`] by default).
    pub pose: PoseConfig,
}

/// LM runs of a disc's first try, from the best-ranked of its ten
/// candidate starts (Stage Two's 5 elsewhere). Ours: on bridge1's run the
/// third to fifth runs found a pose for 109 of the 8866 discs while every
/// disc without a pose paid for all five (most of the plan's time); with
/// two, the neighbours' retries find most of those 109, and the plan
/// (with the 10 mm aim scale) has poses for 5896 discs in 10 s against
/// 5899 in 12 s with three.
pub const BLAST_STARTS: usize = 2;

/// [`PoseConfig::give_up_scales`] of the blast plan: a run whose aim has
/// strayed ten aim scales (10 cm with the default tool) is given up. Ours:
/// on bridge1's run a third of the LM iterations were spent by runs that
/// had strayed that far and never came back (see
/// [`plan::PoseTermination::GaveUp`]).
pub const BLAST_GIVE_UP_SCALES: Real = 10.0;

impl Default for BlastConfig {
    fn default() -> Self {
        Self {
            tool: BlastTool::default(),
            ga: GaConfig::default(),
            pose: PoseConfig {
                starts: BLAST_STARTS,
                give_up_scales: BLAST_GIVE_UP_SCALES,
                aim_backtracking: true,
                ..PoseConfig::default()
            },
        }
    }
}

/// What a blast plan is made from: an exploration's discs with their
/// segments, where each disc's LM starts, and the planning grid every pose
/// must be safe on. [`BlastInputs::to_file`] / [`BlastInputs::from_file`]
/// convert them to and from the run folder's `blast_inputs.json`
/// ([`record::blast::BlastInputsFile`]), so `surveyor plan-blast` plans
/// from the folder exactly what `surveyor explore` planned at the end of
/// the run.
#[derive(Clone, Debug)]
pub struct BlastInputs {
    /// The discs.
    pub discs: Vec<map::Disc>,
    /// Per disc: the joints its pose selection starts from (those of the
    /// viewpoint that saw it).
    pub start_joints: Vec<Vec<Real>>,
    /// The segments: disc indices.
    pub segments: Vec<Vec<map::DiscId>>,
    /// The planning grid (occupied and unknown voxels are obstacles).
    pub grid: map::OccupancyGrid,
}

impl BlastInputs {
    /// Inputs from their parts, checked ([`check`](Self::check)); `source`
    /// names them in errors.
    pub fn new(
        discs: Vec<map::Disc>,
        start_joints: Vec<Vec<Real>>,
        segments: Vec<Vec<map::DiscId>>,
        grid: map::OccupancyGrid,
        source: &str,
    ) -> Result<Self, BlastError> {
        let inputs = Self {
            discs,
            start_joints,
            segments,
            grid,
        };
        inputs.check(source)?;
        Ok(inputs)
    }

    /// Check that the parts agree: one start per disc, and the segments a
    /// partition of the discs (each disc in exactly one). `source` names
    /// them in the error.
    pub fn check(&self, source: &str) -> Result<(), BlastError> {
        let fail = |message: String| BlastError::Invalid {
            what: source.to_owned(),
            message,
        };
        if self.start_joints.len() != self.discs.len() {
            return Err(fail(format!(
                "{} discs but {} start joint vectors",
                self.discs.len(),
                self.start_joints.len()
            )));
        }
        // The segments partition the discs (as segmentation makes them).
        let mut segment_of: Vec<Option<usize>> = vec![None; self.discs.len()];
        for (s, members) in self.segments.iter().enumerate() {
            for m in members {
                let Some(slot) = segment_of.get_mut(m.0) else {
                    return Err(fail(format!(
                        "segment {s} names disc {}, but there are {} discs",
                        m.0,
                        self.discs.len()
                    )));
                };
                if let Some(first) = slot.replace(s) {
                    return Err(fail(format!(
                        "disc {} is in segments {first} and {s}; each disc is in one segment",
                        m.0
                    )));
                }
            }
        }
        if let Some(d) = segment_of.iter().position(Option::is_none) {
            return Err(fail(format!(
                "disc {d} is in no segment; the segments must hold every disc"
            )));
        }
        Ok(())
    }
}

/// The stored form of [`BlastInputs`].
pub type BlastInputsFile = record::blast::BlastInputsFile<map::Disc, map::OccupancyConfig>;

impl BlastInputs {
    /// The inputs as `blast_inputs.json` holds them: the grid's states run-length
    /// encoded in [`map::GridGeometry::keys`] order.
    pub fn to_file(&self) -> BlastInputsFile {
        let grid = &self.grid;
        let states: Vec<Tri> = grid
            .geometry()
            .keys()
            .map(|key| match grid.state(key) {
                map::VoxelState::Unknown => Tri::Unknown,
                map::VoxelState::Free => Tri::Free,
                map::VoxelState::Occupied => Tri::Occupied,
            })
            .collect();
        BlastInputsFile {
            format: record::blast::BLAST_INPUTS_FORMAT.into(),
            version: record::blast::BLAST_INPUTS_VERSION,
            discs: self.discs.clone(),
            start_joints: self.start_joints.clone(),
            segments: self
                .segments
                .iter()
                .map(|s| s.iter().map(|d| d.0).collect())
                .collect(),
            grid: GridFile {
                config: *grid.config(),
                states: record::blast::encode_states(&states),
            },
        }
    }

    /// The inputs of a stored file, checked; `source` names it in errors.
    pub fn from_file(file: BlastInputsFile, source: &str) -> Result<Self, BlastError> {
        let fail = |message: String| BlastError::Invalid {
            what: source.to_owned(),
            message,
        };
        file.grid
            .config
            .validate()
            .map_err(|e| fail(format!("grid.config: {e}")))?;
        let like = map::OccupancyGrid::new(file.grid.config)?;
        let states =
            record::blast::decode_states(&file.grid.states, like.geometry().voxel_count(), source)?;
        let grid = map::OccupancyGrid::from_states(file.grid.config, |k, _| match states[k] {
            Tri::Unknown => map::VoxelState::Unknown,
            Tri::Free => map::VoxelState::Free,
            Tri::Occupied => map::VoxelState::Occupied,
        })?;
        let segments = file
            .segments
            .into_iter()
            .map(|s| s.into_iter().map(map::DiscId).collect())
            .collect();
        Self::new(file.discs, file.start_joints, segments, grid, source)
    }
}

/// The blast plan of `inputs`' discs in `a2`, for `robot` at
/// `world_from_base`, checked against `inputs`' grid.
pub fn plan_blast(
    inputs: &BlastInputs,
    robot: &Robot,
    world_from_base: Isometry3,
    a2: &RegionBox,
    config: &BlastConfig,
) -> Result<BlastPlan, BlastError> {
    use rayon::prelude::*;
    inputs.check("blast inputs")?;
    let poses = blast_poses(robot, world_from_base, config)?;
    let scope = in_region(&inputs.discs, a2);
    let found: Vec<Option<BlastTarget>> = select_poses(&poses, &inputs.grid, inputs, &scope)?
        .into_par_iter()
        .zip(scope.par_iter())
        .map(|(found, &i)| -> Result<Option<BlastTarget>, BlastError> {
            let Some((q, m)) = found else {
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
    let discs = &inputs.discs;
    let mut by_disc: Vec<Option<BlastTarget>> = vec![None; discs.len()];
    let mut in_scope = vec![false; discs.len()];
    for (&i, t) in scope.iter().zip(found) {
        in_scope[i] = true;
        by_disc[i] = t;
    }
    let with_pose = by_disc.iter().filter(|t| t.is_some()).count();
    // Each segment's order on its own (the GA seeded by its index), in
    // parallel, collected in segment order.
    let segments: Vec<Option<SegmentPlan>> = inputs
        .segments
        .par_iter()
        .enumerate()
        .map(|(s, members)| -> Result<Option<SegmentPlan>, BlastError> {
            let members: Vec<usize> = members
                .iter()
                .map(|id| id.0)
                .filter(|&i| in_scope[i])
                .collect();
            if members.is_empty() {
                return Ok(None);
            }
            let no_pose: Vec<usize> = members
                .iter()
                .copied()
                .filter(|&i| by_disc[i].is_none())
                .collect();
            let targets: Vec<BlastTarget> =
                members.iter().filter_map(|&i| by_disc[i].clone()).collect();
            let centres: Vec<geom::Point3> = targets.iter().map(|t| discs[t.disc].centre).collect();
            let joints: Vec<Vec<Real>> = targets.iter().map(|t| t.joints.clone()).collect();
            let table = Targets::new(&centres, &joints).ok_or_else(|| BlastError::Invalid {
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
            Ok(Some(SegmentPlan {
                segment: s,
                targets: ga.order.iter().map(|&k| targets[k].clone()).collect(),
                no_pose,
                weights: PathWeights {
                    alpha: weights.alpha,
                    beta: weights.beta,
                },
                cost_nearest_neighbour: table.cost(&nn, weights),
                cost_two_opt: table.cost(&opt, weights),
                cost_ga: ga.cost,
            }))
        })
        .collect::<Result<_, _>>()?;
    let segments = segments.into_iter().flatten().collect();
    Ok(BlastPlan {
        tool: config.tool,
        discs_in_scope: scope.len(),
        discs_with_pose: with_pose,
        segments,
    })
}

/// The discs of `inputs` in `a2` for which a valid nozzle pose exists on
/// `grid` (any grid of `inputs.grid`'s configuration: the same pose
/// selection as [`plan_blast`], on another map, such as one made from a
/// ground truth).
pub fn discs_with_pose(
    inputs: &BlastInputs,
    robot: &Robot,
    world_from_base: Isometry3,
    a2: &RegionBox,
    grid: &map::OccupancyGrid,
    config: &BlastConfig,
) -> Result<Vec<usize>, BlastError> {
    inputs.check("blast inputs")?;
    let poses = blast_poses(robot, world_from_base, config)?;
    let scope = in_region(&inputs.discs, a2);
    let found = select_poses(&poses, grid, inputs, &scope)?;
    Ok(scope
        .into_iter()
        .zip(found)
        .filter_map(|(i, f)| f.map(|_| i))
        .collect())
}

/// Rounds of retries from neighbours' poses (`select_poses`). Ours, as are
/// [`NEIGHBOUR_STARTS`] and the single LM run per neighbour: on the bridge1
/// run of `surveyor explore` (20 Stage Two viewpoints) they raise the discs
/// in A2 with a pose from 91.7 % to 94.0 % of those reachable with
/// everything known, and the plan's time from 17 s to 71 s (two cores,
/// loaded), spent on the discs that have no pose at all. A neighbour's pose
/// that failed a disc is not tried on it again in a later round (LM is
/// deterministic: same plan, 21 s → 15 s for `plan-blast` on that run).
const NEIGHBOUR_ROUNDS: usize = 3;

/// Solved discs whose poses a failed disc's retry starts from, nearest
/// first (ours, see [`NEIGHBOUR_ROUNDS`]).
const NEIGHBOUR_STARTS: usize = 5;

/// A disc's pose and its re-measurement.
type Found = (Vec<Real>, BlastMeasure);

/// A valid, re-measured pose for each disc of `scope` (indices into
/// `inputs`' discs) against `grid`, or `None`.
///
/// Discs that [`BlastPoses::may_reach`] proves out of the nozzle's reach
/// get `None` without a run. The others are grouped in patches (a
/// segment's discs in one [`SEED_CELL_M`] cell, [`patch_seeds`]): each
/// patch's seed, its first disc, starts LM from its own start joints (the
/// viewpoint that saw it; App. A.1 leaves the start open), and every other
/// disc of the patch first from the seed's pose (one run), then, when that
/// fails, from its own start joints as the seed did. Then, in up to
/// [`NEIGHBOUR_ROUNDS`] rounds, each disc still without a pose is tried
/// again from the poses of the [`NEIGHBOUR_STARTS`] nearest discs (by
/// centre distance, ties by index) that have one, one LM run from each (no
/// aimed starts: the neighbour's pose is the educated guess), until one is
/// valid. Neighbouring discs on one surface are blasted
/// from neighbouring poses, so a neighbour's pose starts LM in the right
/// arm configuration, clear of the unknown voxels that block the aimed
/// starts from the viewpoint's joints (on bridge1 most discs without a first
/// pose are those). The rules a pose must meet are unchanged. Each round
/// reads only the previous rounds' poses, so the result does not depend on
/// the order the discs are solved in.
fn select_poses(
    poses: &BlastPoses,
    grid: &map::OccupancyGrid,
    inputs: &BlastInputs,
    scope: &[usize],
) -> Result<Vec<Option<Found>>, BlastError> {
    use rayon::prelude::*;
    // Discs out of the nozzle's reach have no pose on any map: they take no
    // LM runs (on bridge1's run, 2561 of the 2987 discs without a pose; 1181
    // before the wrist's bound and the chain's lengths measured between
    // axes; those took most of the planning time in up to twenty runs each).
    let open: Vec<bool> = scope
        .par_iter()
        .map(|&i| {
            let target = Target::from_disc(&inputs.discs[i]);
            target.check()?;
            Ok(poses.may_reach(&target))
        })
        .collect::<Result<_, BlastError>>()?;
    let seeds = patch_seeds(&inputs.discs, &inputs.segments, scope, &open);
    let mut found: Vec<Option<Found>> = scope
        .par_iter()
        .enumerate()
        .map(|(k, &i)| {
            if open[k] && seeds[k] == k {
                disc_pose(poses, grid, inputs, i, &inputs.start_joints[i])
            } else {
                Ok(None)
            }
        })
        .collect::<Result<_, _>>()?;
    let retry = poses.with_starts(1)?;
    // The neighbours each disc has been tried from: LM is deterministic, so a
    // start that failed once fails again and later rounds skip it (same
    // result, without repeating the failed runs).
    let mut tried: Vec<Vec<usize>> = vec![Vec::new(); scope.len()];
    // The patches' other discs: from the seed's pose, else as a seed is.
    let rest: Vec<(usize, Option<Found>, bool)> = (0..scope.len())
        .into_par_iter()
        .filter(|&k| open[k] && seeds[k] != k)
        .map(|k| -> Result<_, BlastError> {
            let i = scope[k];
            let from_seed = found[seeds[k]].as_ref().map(|(q, _)| q);
            if let Some(q) = from_seed
                && let Some(p) = disc_pose(&retry, grid, inputs, i, q)?
            {
                return Ok((k, Some(p), true));
            }
            let own = disc_pose(poses, grid, inputs, i, &inputs.start_joints[i])?;
            Ok((k, own, from_seed.is_some()))
        })
        .collect::<Result<_, _>>()?;
    for (k, p, seeded) in rest {
        found[k] = p;
        if seeded {
            tried[k].push(scope[seeds[k]]);
        }
    }
    for _ in 0..NEIGHBOUR_ROUNDS {
        let solved: Vec<(usize, &[Real])> = scope
            .iter()
            .zip(&found)
            .filter_map(|(&i, f)| f.as_ref().map(|(q, _)| (i, q.as_slice())))
            .collect();
        let failed: Vec<usize> = (0..scope.len())
            .filter(|&k| open[k] && found[k].is_none())
            .collect();
        if solved.is_empty() || failed.is_empty() {
            break;
        }
        let again: Vec<(Option<Found>, Vec<usize>)> = failed
            .par_iter()
            .map(|&k| {
                let centre = inputs.discs[scope[k]].centre;
                let mut near: Vec<(Real, usize)> = solved
                    .iter()
                    .enumerate()
                    .map(|(n, (j, _))| ((inputs.discs[*j].centre - centre).norm(), n))
                    .collect();
                let take = NEIGHBOUR_STARTS.min(near.len());
                if take < near.len() {
                    near.select_nth_unstable_by(take, |a, b| {
                        a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
                    });
                    near.truncate(take);
                }
                near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                let mut now = Vec::new();
                for (_, n) in near {
                    let j = solved[n].0;
                    if tried[k].contains(&j) {
                        continue;
                    }
                    now.push(j);
                    if let Some(p) = disc_pose(&retry, grid, inputs, scope[k], solved[n].1)? {
                        return Ok((Some(p), now));
                    }
                }
                Ok((None, now))
            })
            .collect::<Result<_, BlastError>>()?;
        let mut any = false;
        for (k, (p, now)) in failed.into_iter().zip(again) {
            any |= p.is_some();
            found[k] = p;
            tried[k].extend(now);
        }
        if !any {
            break;
        }
    }
    Ok(found)
}

/// Side of the cubes (world axes) that cut a segment into patches for
/// the plan's first poses, metres. Ours: two and a half times the largest disc's
/// radius (Paul's discs are 1–4 cm), so a patch is a few discs of one
/// surface, blasted from nearly one pose. On bridge1's run (5462 of the
/// 7685 discs in reach are seeds) the plan has poses for 5893 discs instead
/// of 5896 and a GA path cost (eq. A.9) of 1032 instead of 1073, the poses
/// of a patch being alike, in about 5 % less time: a disc that starts from
/// its seed's pose needs neither the ten ranked starts nor, mostly, a
/// second run.
pub const SEED_CELL_M: Real = 0.1;

/// For each disc of `scope` (indices into `discs`) that is `open`, the
/// position in `scope` of its patch's seed (itself for a seed): the first
/// open disc, in `scope`'s order, of its segment (of `segments`) in its
/// [`SEED_CELL_M`] cell. Closed discs map to themselves.
fn patch_seeds(
    discs: &[map::Disc],
    segments: &[Vec<map::DiscId>],
    scope: &[usize],
    open: &[bool],
) -> Vec<usize> {
    let mut segment_of = vec![0usize; discs.len()];
    for (s, members) in segments.iter().enumerate() {
        for d in members {
            if let Some(slot) = segment_of.get_mut(d.0) {
                *slot = s;
            }
        }
    }
    let mut first: std::collections::HashMap<(usize, [i64; 3]), usize> =
        std::collections::HashMap::new();
    (0..scope.len())
        .map(|k| {
            if !open[k] {
                return k;
            }
            let c = discs[scope[k]].centre;
            let cell = [c.x, c.y, c.z].map(|v| (v / SEED_CELL_M).floor() as i64);
            *first.entry((segment_of[scope[k]], cell)).or_insert(k)
        })
        .collect()
}

/// The pose selection of `config` for `robot` at `world_from_base`.
fn blast_poses(
    robot: &Robot,
    world_from_base: Isometry3,
    config: &BlastConfig,
) -> Result<BlastPoses, BlastError> {
    Ok(BlastPoses::new(
        robot,
        world_from_base,
        &PlanConfig::default(),
        vec![1.0; robot.dof()],
        &config.pose,
        config.tool,
    )?)
}

/// The discs whose centres are in `region`.
fn in_region(d: &[map::Disc], region: &RegionBox) -> Vec<usize> {
    (0..d.len())
        .filter(|&i| region.contains(&d[i].centre))
        .collect()
}

/// A valid blast pose for disc `i` of `inputs` against `grid`, the LM
/// starting from `start`, re-measured.
fn disc_pose(
    poses: &BlastPoses,
    grid: &map::OccupancyGrid,
    inputs: &BlastInputs,
    i: usize,
    start: &[Real],
) -> Result<Option<(Vec<Real>, BlastMeasure)>, BlastError> {
    let target = Target::from_disc(&inputs.discs[i]);
    let solution = poses.select(grid, &target, start)?;
    if !solution.valid() {
        return Ok(None);
    }
    let q = solution.joints().to_vec();
    let m = poses.measure(grid, &target, &q)?;
    Ok(m.valid.then_some((q, m)))
}

/// The nozzle's pose in the world at `q`.
fn robot_nozzle(
    poses: &BlastPoses,
    world_from_base: &Isometry3,
    q: &[Real],
) -> Result<Isometry3, BlastError> {
    poses
        .robot()
        .scanner_pose(q)?
        .map(|p| world_from_base * p)
        .ok_or(BlastError::NoNozzle)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// Patches by hand: a segment's discs in one 10 cm cell share the first
    /// open one as seed; another segment in the same cell, the next cell,
    /// and a closed disc each stand alone.
    #[test]
    fn patch_seeds_by_hand() {
        let disc = |x: Real, y: Real| map::Disc {
            centre: geom::Point3::new(x, y, 0.05),
            normal: geom::UnitVector3::new_normalize(Vector3::z()),
            radius_m: 0.02,
            points: 10,
        };
        // Cell [0, 0, 0]: discs 0, 1, 2 (2 in segment 1); cell [1, 0, 0]:
        // disc 3; disc 4 closed in cell [0, 0, 0]; disc 5 in cell [0, 0, 0]
        // of segment 0.
        let discs = vec![
            disc(0.01, 0.01),
            disc(0.05, 0.09),
            disc(0.02, 0.02),
            disc(0.11, 0.01),
            disc(0.03, 0.03),
            disc(0.09, 0.01),
        ];
        let id = map::DiscId;
        let segments = vec![vec![id(0), id(1), id(3), id(4), id(5)], vec![id(2)]];
        // Scope in another order than the indices: the seed is the first in
        // scope order.
        let scope = [1, 0, 2, 3, 4, 5];
        let open = [true, true, true, true, false, true];
        assert_eq!(
            patch_seeds(&discs, &segments, &scope, &open),
            vec![0, 0, 2, 3, 4, 0]
        );
    }
}
