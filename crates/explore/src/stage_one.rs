//! Stage One: geometric and C-space exploration (A§3.2, §4.2–4.3).
//!
//! [`StageOne`] holds the planning grid and the C-space model. Each decision
//! scores every sampled node as a contending viewpoint: its tilt sweep must be
//! safe (`dist(Q) > 1` at every checked configuration, f4 the smallest); the
//! sweep's rays are cast through the grid, stopping at occupied voxels, and
//! the unknown voxels they pass are credited with their geometric (eq. 4.11)
//! and C-space (eq. 4.14) information: f1 and f2 are what would remain; f3 is
//! the joint travel (eq. 3.3). The Pareto front, lowest rank sum and f1
//! tie-break choose (eq. 3.8), and A* through the roadmap must find a safe
//! path there, else the next choice is tried.

use crate::gain::{self, Gain, GainContext, Trace};
use crate::pareto::{self, Sense};
use crate::{ExploreConfig, ExploreError, Selection};
use geom::{Isometry3, Point3, Real, UnitVector3};
use map::{IntegrationStats, OccupancyConfig, OccupancyGrid, VoxelKey};
use plan::{
    ClearanceChecker, CspaceModel, MotionChecker, NodeId, Path, PointClearance, Safety,
    interfering_voxels,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use robot::Robot;
use sensor::Sweep;
use std::sync::Arc;
use std::time::Instant;

/// The objectives of eq. 3.7, in order: f1, f2, f3 minimised, f4 maximised.
const SENSES: [Sense; 4] = [
    Sense::Minimise,
    Sense::Minimise,
    Sense::Minimise,
    Sense::Maximise,
];

/// Unknown voxels a candidate's predicted rays must enter from free space
/// for `selection = "frontier"` to go there: 1 m² of 0.1 m voxels. After
/// Yamauchi's smallest frontier region worth going to ("roughly the size of
/// the robot"); with any one voxel, the nearest candidate was a wrist turn
/// that revealed under 1 % and the 1 % rule ended bridge1's run at its
/// second viewpoint.
pub const FRONTIER_MIN_VOXELS: usize = 100;

/// Joint travel (Σ|Δqᵢ|, radians) under which a candidate is the current pose.
const SAME_POSE_RAD: Real = 1e-9;

/// One contending viewpoint's scores.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The roadmap node, or `None` for a candidate sampled around the
    /// current pose.
    pub node: Option<NodeId>,
    /// The pose.
    pub q: Vec<Real>,
    /// `[f1, f2, f3, f4]`: weighted geometric information predicted to remain,
    /// C-space information predicted to remain, joint travel (rad), `dist(Q)`
    /// (smallest over the sweep).
    pub f: [Real; 4],
    /// Unknown voxels the sweep is predicted to reveal.
    pub revealed: usize,
    /// The gain's score of the predicted sweep ([`crate::gain`]).
    pub gain: Real,
    /// Unknown voxels a predicted ray enters directly from a free voxel
    /// (a frontier voxel: free, beside unknown space), each once; computed
    /// only for `selection = "frontier"`, else 0.
    pub frontier: usize,
}

/// What a decision chose.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// The candidate.
    pub candidate: Candidate,
    /// Its rank sum on the Pareto front.
    pub rank_sum: usize,
    /// The safe path from the current pose to it.
    pub path: Path,
}

/// One Stage One decision.
#[derive(Clone, Debug)]
pub struct Decision {
    /// Every candidate whose sweep is safe, in node order.
    pub candidates: Vec<Candidate>,
    /// Size of the Pareto front of the first choice.
    pub front_size: usize,
    /// Per candidate: on the Pareto front of the first choice.
    pub on_front: Vec<bool>,
    /// The choice, or `None` when no safe candidate can be reached.
    pub choice: Option<Choice>,
    /// Candidates chosen but dropped for want of a safe path.
    pub unreachable: usize,
    /// Wall time scoring the candidates, ms.
    pub score_ms: Real,
    /// Wall time of the Pareto choice and path planning, ms.
    pub plan_ms: Real,
}

/// Why Stage One stops.
#[derive(Clone, Debug, PartialEq)]
pub enum Termination {
    /// A§3.2.4: both changes of the last viewpoint fell below the fraction of
    /// the initial information.
    Converged {
        /// `ΔH1` of the last viewpoint.
        dh1: Real,
        /// `ΔH2` of the last viewpoint.
        dh2: Real,
    },
    /// The viewpoint budget is spent.
    Budget,
    /// No candidate is both safe and reachable.
    NoSafeCandidate,
}

impl Termination {
    /// A short machine-readable name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Converged { .. } => "information_converged",
            Self::Budget => "viewpoint_budget",
            Self::NoSafeCandidate => "no_safe_candidate",
        }
    }
}

/// Stage One's state: the planning grid, the C-space model and the history of
/// information remaining.
#[derive(Clone, Debug)]
pub struct StageOne {
    config: ExploreConfig,
    model: CspaceModel,
    grid: OccupancyGrid,
    /// Scanner-frame directions of the predicted rays.
    dirs: Vec<UnitVector3>,
    max_range_m: Real,
    /// Index (into `q`) of the tilting joint, and the first link it moves.
    tilt_joint: usize,
    tilt_first_link: usize,
    /// `(H1 weighted, H2)` before any sweep, then after each.
    history: Vec<(Real, Real)>,
    /// How a predicted sweep is scored.
    gain: Arc<dyn Gain>,
}

impl StageOne {
    /// Stage One for the model's robot with the scanner's `bearings_rad` and
    /// `max_range_m`. The planning grid takes `occupancy`'s regions, occlusion
    /// and miss settings, with `config`'s voxel size and region weights; the model's
    /// `P(ʲx_c)` is applied to it; the space the arm's envelope takes during the
    /// start pose's sweep is marked free (the only space assumed free before
    /// the first scan, A§3.2.1.4, §6.1); `H1₀` and `H2₀` are recorded.
    pub fn new(
        model: CspaceModel,
        occupancy: &OccupancyConfig,
        bearings_rad: &[Real],
        max_range_m: Real,
        config: ExploreConfig,
        start: &[Real],
    ) -> Result<Self, ExploreError> {
        config.validate()?;
        let robot = model.safety().robot();
        if robot.scanner.is_none() {
            return Err(ExploreError::Robot {
                robot: robot.name.clone(),
                message: "no scanner is mounted".into(),
            });
        }
        let dof = robot.dof();
        robot.check_joints(start)?;
        let tilt_joint = config
            .sweep
            .joint
            .checked_sub(1)
            .filter(|j| *j < dof)
            .ok_or_else(|| ExploreError::Config {
                field: "scanner.sweep.joint",
                expected: "a joint of the robot (1-based)",
                got: format!("{} for a robot with {dof} joints", config.sweep.joint),
            })?;
        let tilt_first_link = first_link_moved_by(robot, tilt_joint);
        if (model.voxel_m() - config.planning_voxel_m).abs() > 1e-12 {
            return Err(ExploreError::Config {
                field: "explore.planning_voxel_m",
                expected: "the C-space model's voxel size",
                got: format!("{} (model: {})", config.planning_voxel_m, model.voxel_m()),
            });
        }
        let mut grid = OccupancyGrid::new(OccupancyConfig {
            voxel_m: config.planning_voxel_m,
            weights: config.weights,
            ..*occupancy
        })?;
        model.apply_to(&mut grid)?;
        let step = config.prediction.ray_step_deg.to_radians();
        let dirs = subsample(bearings_rad, step)
            .into_iter()
            .map(|b| UnitVector3::new_normalize(sensor::beam_direction(b)))
            .collect();
        let gain = config.gain.gain();
        let mut stage = Self {
            config,
            model,
            grid,
            dirs,
            max_range_m,
            tilt_joint,
            tilt_first_link,
            history: Vec::new(),
            gain,
        };
        let envelope = stage.sweep_envelope(start)?;
        for key in envelope {
            if stage.grid.geometry().contains(key) {
                stage.grid.mark_free(key)?;
            }
        }
        stage
            .history
            .push((stage.grid.h1_weighted(), stage.grid.h2()));
        Ok(stage)
    }

    /// The planning grid.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// How a candidate's predicted sweep is scored (`[explore] gain`'s
    /// built-in unless [`StageOne::set_gain`] gave another).
    pub fn gain(&self) -> &dyn Gain {
        self.gain.as_ref()
    }

    /// Score predicted sweeps with `gain` from the next decision on (one of
    /// [`gain::GainKind`] or a user's own; with `selection =
    /// "information"` the candidate of the largest score is chosen).
    pub fn set_gain(&mut self, gain: Arc<dyn Gain>) {
        self.gain = gain;
    }

    /// The C-space model.
    pub fn model(&self) -> &CspaceModel {
        &self.model
    }

    /// The configuration.
    pub fn config(&self) -> &ExploreConfig {
        &self.config
    }

    /// `(H1 weighted, H2)` before any sweep (`H1₀`, `H2₀`).
    pub fn initial_information(&self) -> (Real, Real) {
        self.history[0]
    }

    /// `(H1 weighted, H2)` now.
    pub fn information(&self) -> (Real, Real) {
        *self.history.last().unwrap_or(&(0.0, 0.0))
    }

    /// Sweeps integrated so far.
    pub fn sweeps(&self) -> usize {
        self.history.len() - 1
    }

    /// Integrate a measured sweep into the planning grid.
    pub fn integrate(&mut self, sweep: &Sweep) -> IntegrationStats {
        let stats = self.grid.integrate_sweep(sweep);
        self.history.push((self.grid.h1_weighted(), self.grid.h2()));
        stats
    }

    /// Integrate what the scanner measured while the arm moved to the next
    /// viewpoint (`motion_scan_step_deg`): the grid changes, the history of
    /// information does not until that viewpoint's sweep is integrated, so
    /// A§3.2.4's changes are per viewpoint, motion and sweep together.
    pub fn integrate_motion(&mut self, sweep: &Sweep) -> IntegrationStats {
        self.grid.integrate_sweep(sweep)
    }

    /// Why Stage One should stop now, if it should: A§3.2.4 after at least
    /// two sweeps when the arm `arrived` at the viewpoint it chose (a motion
    /// stopped short of it does not judge the choice), or the budget.
    pub fn termination(&self, arrived: bool) -> Option<Termination> {
        let n = self.history.len();
        if n >= 3 && arrived {
            let (h10, h20) = self.history[0];
            let (a1, a2) = self.history[n - 2];
            let (b1, b2) = self.history[n - 1];
            let (dh1, dh2) = (a1 - b1, a2 - b2);
            let f = self.config.stop_fraction;
            if dh1 < f * h10 && dh2 < f * h20 {
                return Some(Termination::Converged { dh1, dh2 });
            }
        }
        (self.sweeps() >= self.config.max_viewpoints).then_some(Termination::Budget)
    }

    /// The tilt values of the sweep from `q` (the sweep joint's range; other
    /// joints held).
    pub fn sweep_range(&self, q: &[Real]) -> (Vec<Real>, Vec<Real>) {
        let j = self.tilt_joint;
        let tilts = self.sweep_tilts(q);
        let mut lo = q.to_vec();
        let mut hi = q.to_vec();
        lo[j] = tilts.first().copied().unwrap_or(q[j]);
        hi[j] = tilts.last().copied().unwrap_or(q[j]);
        (lo, hi)
    }

    /// The tilt joint's values a sweep at `q` scans at, in order.
    pub fn sweep_tilts(&self, q: &[Real]) -> Vec<Real> {
        let j = self.tilt_joint;
        let limits = self.robot().limits()[j].map(|l| (l.min, l.max));
        self.config.sweep.tilt_values(q[j], limits)
    }

    /// The index of the joint that tilts the scanner.
    pub fn tilt_joint(&self) -> usize {
        self.tilt_joint
    }

    fn robot(&self) -> &Robot {
        self.model.safety().robot()
    }

    fn safety(&self) -> &Safety {
        self.model.safety()
    }

    /// Voxels inside the arm's ellipsoids at `q` and along its sweep.
    fn sweep_envelope(&self, q: &[Real]) -> Result<Vec<VoxelKey>, ExploreError> {
        let (lo, hi) = self.sweep_range(q);
        let v = self.grid.geometry().voxel_m();
        let mut keys = interfering_voxels(self.safety(), q, v)?;
        for c in self.safety().interpolate(&lo, &hi) {
            keys.extend(interfering_voxels(self.safety(), &c, v)?);
        }
        keys.sort_unstable();
        keys.dedup();
        Ok(keys)
    }

    /// `dist(Q)` of the whole sweep from `q`: the links the tilt does not move
    /// at `q`, the others at every checked tilt. `None` when some checked
    /// configuration is at or below 1.
    pub fn sweep_dist(&self, q: &[Real]) -> Result<Option<Real>, ExploreError> {
        let safety = self.safety();
        let fixed =
            safety.dist_of_links(&self.grid, q, 0..self.tilt_first_link, safety.cap(), 1.0)?;
        if fixed <= 1.0 {
            return Ok(None);
        }
        let (lo, hi) = self.sweep_range(q);
        let mut best = fixed;
        for c in safety.interpolate(&lo, &hi) {
            best = best.min(safety.dist_of_links(
                &self.grid,
                &c,
                self.tilt_first_link..usize::MAX,
                best,
                1.0,
            )?);
            if best <= 1.0 {
                return Ok(None);
            }
        }
        Ok(Some(best))
    }

    /// The predicted sweep from `q` ([`Trace`]): the sweep's predicted rays
    /// cast through the grid up to the scanner's range, stopping at occupied
    /// voxels (A§4.2, Fig. 4.3), and, when the arm scans as it moves, the
    /// rays of `prediction.motion_poses` scanner poses on the straight
    /// motion `from` the current pose.
    fn predict(
        &self,
        q: &[Real],
        from: Option<&[Real]>,
        trace: &mut Trace,
    ) -> Result<(), ExploreError> {
        let (lo, hi) = self.sweep_range(q);
        let j = self.tilt_joint;
        let span = hi[j] - lo[j];
        let steps = (span / self.config.prediction.tilt_step_deg.to_radians())
            .ceil()
            .max(0.0) as usize;
        let world_from_base = *self.safety().world_from_base();
        let mut configs: Vec<Vec<Real>> = Vec::new();
        let mut c = lo.clone();
        for s in 0..=steps {
            c[j] = if steps == 0 {
                lo[j]
            } else {
                lo[j] + span * s as Real / steps as Real
            };
            configs.push(c.clone());
        }
        // The straight motion from where the arm stands, when the arm scans
        // as it moves.
        let poses = self.config.prediction.motion_poses;
        if let (Some(from), true) = (from, self.config.motion_scan_step_deg > 0.0) {
            for s in 1..=poses {
                let t = s as Real / (poses + 1) as Real;
                configs.push(from.iter().zip(q).map(|(a, b)| a + (b - a) * t).collect());
            }
        }
        let keep_steps = self.gain.reads_steps() || self.config.selection == Selection::Frontier;
        trace.begin(self.grid.geometry().slot_count(), keep_steps);
        for c in &configs {
            let Some(pose) = self.robot().scanner_pose(c)? else {
                continue;
            };
            let pose: Isometry3 = world_from_base * pose;
            let origin = Point3::from(pose.translation.vector);
            for d in &self.dirs {
                let dir = UnitVector3::new_unchecked(pose.rotation * d.into_inner());
                trace.cast_ray(&self.grid, &origin, &dir, self.max_range_m);
            }
        }
        Ok(())
    }

    /// The contending viewpoints of a decision from `q`: the roadmap's nodes,
    /// then `local_candidates` poses sampled around `q`. Each local pose moves
    /// `m` joints (`m` uniform in 1..=dof, the joints drawn at random), each
    /// uniformly by up to `local_reach_m / wᵢ`, clamped to its limits; seeded
    /// by the plan seed and the number of sweeps so far.
    pub fn contenders(&self, q: &[Real]) -> Vec<(Option<NodeId>, Vec<Real>)> {
        let map = self.model.roadmap();
        let mut out: Vec<(Option<NodeId>, Vec<Real>)> = map
            .node_ids()
            .map(|i| (Some(i), map.node(i).to_vec()))
            .collect();
        let seed = self.config.plan.seed
            ^ 0x9e37_79b9_7f4a_7c15_u64.wrapping_mul(self.sweeps() as u64 + 1);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let limits = self.robot().limits();
        let dof = q.len();
        for _ in 0..self.config.local_candidates {
            let mut c = q.to_vec();
            let m = rng.random_range(1..=dof);
            let mut joints: Vec<usize> = (0..dof).collect();
            for k in 0..m {
                let pick = rng.random_range(k..dof);
                joints.swap(k, pick);
                let j = joints[k];
                let r = self.config.local_reach_m / map.weights()[j];
                if r > 0.0 {
                    c[j] += rng.random_range(-r..r);
                }
                if let Some(l) = limits[j] {
                    c[j] = c[j].clamp(l.min, l.max);
                }
            }
            out.push((None, c));
        }
        out
    }

    /// Score every contending viewpoint ([`StageOne::contenders`]) from the
    /// current pose `q`; those whose sweep is unsafe are left out.
    pub fn score(&self, q: &[Real]) -> Result<Vec<Candidate>, ExploreError> {
        self.robot().check_joints(q)?;
        let (h1, h2) = self.information();
        let contenders = self.contenders(q);
        let information = self.grid.information_by_slot();
        let context = GainContext::new(
            &self.grid,
            &information,
            self.information(),
            self.initial_information(),
        );
        let frontier = self.config.selection == Selection::Frontier;
        let scored: Vec<Option<Candidate>> = contenders
            .into_par_iter()
            .map_init(
                Trace::new,
                |trace, (node, c)| -> Result<Option<Candidate>, ExploreError> {
                    // The current pose itself is no new viewpoint.
                    let f3: Real = c.iter().zip(q).map(|(a, b)| (a - b).abs()).sum();
                    if f3 <= SAME_POSE_RAD {
                        return Ok(None);
                    }
                    let Some(f4) = self.sweep_dist(&c)? else {
                        return Ok(None);
                    };
                    self.predict(&c, Some(q), trace)?;
                    let (g1, g2) = gain::revealed(trace, &context);
                    let frontier = if frontier {
                        gain::frontier_crossings(trace)
                    } else {
                        0
                    };
                    Ok(Some(Candidate {
                        node,
                        q: c,
                        f: [h1 - g1, h2 - g2, f3, f4],
                        revealed: trace.distinct_unknown().len(),
                        gain: self.gain.score(trace, &context),
                        frontier,
                    }))
                },
            )
            .collect::<Result<_, _>>()?;
        Ok(scored.into_iter().flatten().collect())
    }

    /// One Stage One decision from the current pose `q` (A§3.2): score, choose
    /// on the Pareto front, plan a safe path; a choice without a safe path is
    /// dropped and the choice made again, up to `max_plan_attempts`.
    ///
    /// The choice is `selection`'s: Paul's rank sum on the Pareto front, or
    /// the most information. A candidate the roadmap cannot reach may be
    /// reached by a straight motion from a pose in `visited` (the viewpoints
    /// so far) that the roadmap reaches. With `points` (what the scanner
    /// measured), candidates must stand, and their path and sweep keep,
    /// `stage_one_clearance_m` from them ([`plan::ClearanceChecker`]); a
    /// chosen candidate whose sweep does not is dropped like one without a
    /// path.
    pub fn decide(
        &self,
        q: &[Real],
        points: Option<&PointClearance>,
        visited: &[&[Real]],
    ) -> Result<Decision, ExploreError> {
        let t0 = Instant::now();
        let candidates = self.score(q)?;
        let score_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        // Candidates standing closer to a measured point than the clearance
        // are not contenders (their paths would fail at the end).
        let clearance_m = self.config.stage_one_clearance_m;
        let robot = self.robot();
        let world_from_base = self.safety().world_from_base();
        let clear: Vec<bool> = candidates
            .par_iter()
            .map(|c| match points {
                Some(p) if clearance_m > 0.0 => robot.forward_kinematics(&c.q).is_ok_and(|f| {
                    p.robot_clearance(robot, &f, world_from_base, clearance_m) >= clearance_m
                }),
                _ => true,
            })
            .collect();
        let mut pool: Vec<usize> = (0..candidates.len()).filter(|&i| clear[i]).collect();
        let mut front_size = 0;
        let mut on_front = vec![false; candidates.len()];
        let mut unreachable = 0;
        let mut choice = None;
        // The map does not change during a decision: each attempt reuses
        // the motion checks of the ones before.
        let empty = PointClearance::new();
        let mut checker = plan::MemoChecker::new(ClearanceChecker::new(
            self.safety().checker(&self.grid),
            self.safety(),
            points.unwrap_or(&empty),
            if points.is_some() {
                self.config.stage_one_clearance_m
            } else {
                0.0
            },
            q,
        ));
        // What the choice maximises, per candidate (rank sum aside).
        let key: Vec<Real> = match self.config.selection {
            Selection::RankSum => Vec::new(),
            Selection::Information => candidates.iter().map(|c| c.gain).collect(),
            // Yamauchi: the nearest candidate that sees a frontier region.
            Selection::Frontier => candidates
                .iter()
                .map(|c| {
                    if c.frontier >= FRONTIER_MIN_VOXELS {
                        -self.model.roadmap().distance(q, &c.q)
                    } else {
                        Real::NEG_INFINITY
                    }
                })
                .collect(),
            // Uniformly among the clear candidates: independent uniform
            // keys, the largest first (a dropped one leaves the rest
            // uniform).
            Selection::Random => {
                let seed = self.config.plan.seed
                    ^ 0xd1b5_4a32_d192_ed03_u64.wrapping_mul(self.sweeps() as u64 + 1);
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                candidates.iter().map(|_| rng.random::<Real>()).collect()
            }
        };
        for attempt in 0..self.config.max_plan_attempts {
            let f: Vec<Vec<Real>> = pool.iter().map(|&i| candidates[i].f.to_vec()).collect();
            if attempt == 0 {
                let front = pareto::pareto_front(&f, &SENSES);
                front_size = front.len();
                // `front` indexes the pool (the clear candidates).
                for &i in &front {
                    on_front[pool[i]] = true;
                }
            }
            let picked = match self.config.selection {
                Selection::RankSum => pareto::choose(&f, &SENSES),
                _ => largest(pool.iter().map(|&i| key[i])),
            };
            let Some((k, rank_sum)) = picked else {
                break;
            };
            let c = &candidates[pool[k]];
            let (lo, hi) = self.sweep_range(&c.q);
            let path = path_via_visited(
                self.model.roadmap(),
                visited,
                q,
                &c.q,
                self.config.link_k,
                &mut checker,
            )
            .filter(|_| checker.motion_ok(&c.q, &lo) && checker.motion_ok(&lo, &hi));
            if let Some(path) = path {
                choice = Some(Choice {
                    candidate: c.clone(),
                    rank_sum,
                    path,
                });
                break;
            }
            unreachable += 1;
            pool.remove(k);
        }
        Ok(Decision {
            candidates,
            front_size,
            on_front,
            choice,
            unreachable,
            score_ms,
            plan_ms: t1.elapsed().as_secs_f64() * 1e3,
        })
    }
}

/// Poses the arm has stood at that are tried as the last waypoint before a
/// goal the roadmap cannot reach.
const VISITED_BRIDGES: usize = 5;

/// A safe path from `from` to `goal`: the roadmap's (a direct motion, or A*
/// through the roadmap), or else through one of the poses the arm has
/// already stood at (`visited`; the [`VISITED_BRIDGES`] nearest to the goal,
/// nearest first) from which a straight motion reaches the goal. A Stage Two
/// pose is chosen by LM anywhere in free space, often beside a viewpoint
/// the arm took but far from every roadmap node whose surroundings are known
/// free. When neither reaches the goal (the arm may stand where such a
/// bridge took it, beside a part of the roadmap cut off from the rest, and
/// the way it came is the way out), the path leaves by a straight motion to
/// the nearest visited pose one reaches and goes on from there as above.
pub(crate) fn path_via_visited(
    roadmap: &plan::Roadmap,
    visited: &[&[Real]],
    from: &[Real],
    goal: &[Real],
    link_k: usize,
    checker: &mut dyn plan::MotionChecker,
) -> Option<plan::Path> {
    if let Some(path) = path_into(roadmap, visited, from, goal, link_k, checker) {
        return Some(path);
    }
    // The way out: the nearest visited pose a straight motion reaches.
    let (d, v) = nearest_visited(roadmap, visited, from)
        .into_iter()
        .find(|&(_, v)| v != from && v != goal && checker.motion_ok(from, v))?;
    let mut path = path_into(roadmap, visited, v, goal, link_k, checker)?;
    path.waypoints.insert(0, from.to_vec());
    path.cost += d;
    Some(path)
}

/// The [`VISITED_BRIDGES`] poses of `visited` nearest `to`, nearest first,
/// with their distance.
fn nearest_visited<'v>(
    roadmap: &plan::Roadmap,
    visited: &[&'v [Real]],
    to: &[Real],
) -> Vec<(Real, &'v [Real])> {
    let mut near: Vec<(Real, &[Real])> = visited
        .iter()
        .map(|v| (roadmap.distance(v, to), *v))
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.dedup_by(|a, b| a.1 == b.1);
    near.truncate(VISITED_BRIDGES);
    near
}

/// [`path_via_visited`] without leaving `from` by a visited pose.
fn path_into(
    roadmap: &plan::Roadmap,
    visited: &[&[Real]],
    from: &[Real],
    goal: &[Real],
    link_k: usize,
    checker: &mut dyn plan::MotionChecker,
) -> Option<plan::Path> {
    if let Some(path) = roadmap.plan(from, goal, link_k, checker) {
        return Some(path);
    }
    for (d, v) in nearest_visited(roadmap, visited, goal) {
        if v == from || !checker.motion_ok(v, goal) {
            continue;
        }
        if let Some(mut path) = roadmap.plan(from, v, link_k, checker) {
            path.waypoints.push(goal.to_vec());
            path.cost += d;
            return Some(path);
        }
    }
    None
}

/// The index (and rank sum 0) of the largest finite value, ties to the
/// lower index; `None` when there is none.
fn largest(values: impl Iterator<Item = Real>) -> Option<(usize, usize)> {
    values
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
        .map(|(i, _)| (i, 0))
}

/// Bearings every `step` radians (the first, then each at least `step` past
/// the last kept, and the last).
fn subsample(bearings: &[Real], step: Real) -> Vec<Real> {
    let mut out: Vec<Real> = Vec::new();
    for &b in bearings {
        if out.last().is_none_or(|l| b - l >= step - 1e-12) {
            out.push(b);
        }
    }
    if let (Some(&last), Some(&kept)) = (bearings.last(), out.last())
        && last != kept
    {
        out.push(last);
    }
    out
}

/// The first link moved by actuated joint `a` (links before it stay put
/// when only `a` and later joints move).
fn first_link_moved_by(robot: &Robot, a: usize) -> usize {
    robot
        .joints
        .iter()
        .enumerate()
        .filter(|(_, j)| j.is_actuated())
        .nth(a)
        .map_or(usize::MAX, |(i, _)| i + 1)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::{largest, path_via_visited, subsample};
    use geom::Real;
    use plan::{Edge, MotionChecker, NodeId, Roadmap, RoadmapParts};

    /// A 2-D joint space with forbidden boxes, motions checked every 0.01.
    struct Boxes(Vec<([Real; 2], [Real; 2])>);

    impl Boxes {
        fn inside(&self, q: &[Real]) -> bool {
            self.0
                .iter()
                .any(|(lo, hi)| (0..2).all(|i| q[i] > lo[i] && q[i] < hi[i]))
        }
    }

    impl MotionChecker for Boxes {
        fn pose_ok(&mut self, q: &[Real]) -> bool {
            !self.inside(q)
        }
        fn motion_ok(&mut self, a: &[Real], b: &[Real]) -> bool {
            let len = (a[0] - b[0]).hypot(a[1] - b[1]);
            let steps = (len / 0.01).ceil().max(1.0) as usize;
            (0..=steps).all(|s| {
                let t = s as Real / steps as Real;
                !self.inside(&[a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
            })
        }
    }

    /// The arm stands at (7.5, 8.5), beside two roadmap nodes joined only to
    /// each other; the rest of the roadmap is a chain along y = 0 to the
    /// goal (2, 0.5). A box blocks the straight way to the goal, another the
    /// straight way from the one viewpoint visited, (0.5, 5), to the goal.
    /// Neither the roadmap nor a last straight motion from the viewpoint
    /// reaches the goal: the path leaves by the straight motion to the
    /// viewpoint and goes on through the chain.
    #[test]
    fn a_path_leaves_by_a_visited_pose_when_the_roadmap_is_cut_off() {
        let edge = |a: u32, b: u32, cost: Real| Edge {
            a: NodeId(a),
            b: NodeId(b),
            cost,
        };
        let roadmap = Roadmap::from_parts(RoadmapParts {
            dof: 2,
            nodes: vec![
                vec![0.0, 0.0],
                vec![1.0, 0.0],
                vec![2.0, 0.0],
                vec![8.0, 8.0],
                vec![8.0, 9.0],
            ],
            weights: vec![1.0, 1.0],
            edges: vec![edge(0, 1, 1.0), edge(1, 2, 1.0), edge(3, 4, 1.0)],
        })
        .unwrap();
        let mut checker = Boxes(vec![([2.5, 0.0], [4.5, 4.0]), ([1.0, 2.0], [1.6, 3.5])]);
        let (from, goal, visited) = ([7.5, 8.5], [2.0, 0.5], [0.5, 5.0]);
        assert!(!checker.motion_ok(&from, &goal));
        assert!(!checker.motion_ok(&visited, &goal));
        assert!(roadmap.plan(&from, &goal, 2, &mut checker).is_none());
        let path = path_via_visited(&roadmap, &[&visited], &from, &goal, 2, &mut checker).unwrap();
        assert_eq!(path.waypoints[0], from.to_vec());
        assert_eq!(path.waypoints[1], visited.to_vec());
        assert_eq!(path.waypoints.last().unwrap(), &goal.to_vec());
        for w in path.waypoints.windows(2) {
            assert!(checker.motion_ok(&w[0], &w[1]), "{w:?}");
        }
        // Without the visited pose there is no way.
        assert!(path_via_visited(&roadmap, &[], &from, &goal, 2, &mut checker).is_none());
    }

    /// The largest finite key, ties to the lower index; keys of candidates
    /// that cannot be chosen (-inf, NaN) never are.
    #[test]
    fn the_largest_key_is_chosen() {
        let inf = Real::INFINITY;
        assert_eq!(largest([0.1, 0.3, 0.3, 0.2].into_iter()), Some((1, 0)));
        assert_eq!(largest([-inf, -2.0, -1.0].into_iter()), Some((2, 0)));
        assert_eq!(largest([-inf, Real::NAN, inf].into_iter()), None);
        assert_eq!(largest(std::iter::empty()), None);
    }

    #[test]
    fn subsample_keeps_ends_and_spacing() {
        let b: Vec<f64> = (0..=10).map(|i| f64::from(i) * 0.1).collect();
        let s = subsample(&b, 0.35);
        assert_eq!(s.len(), 4);
        assert!((s[1] - 0.4).abs() < 1e-12 && (s[2] - 0.8).abs() < 1e-12);
        assert_eq!(*s.last().unwrap(), 1.0);
    }
}
