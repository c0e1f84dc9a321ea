//! The exploration episode (A ch. 3, Fig. 6.3): sweep from the start pose,
//! then Stage One — decide, move, sweep, integrate — until the 1 % rule or
//! the budget; the map products (discs, segments); then Stage Two — aim the
//! scanner at the disc with the most material information left, move,
//! sweep, classify — until no disc can be targeted or the budget is spent.
//!
//! [`run`] drives any hardware that implements [`hw::Arm`] and
//! [`hw::LineScanner`]; a [`Judge`] sees every executed motion and sweep
//! (a simulator's ground truth; [`crate::NoJudge`] for a real robot). Every
//! executed motion (paths and sweeps) is also checked against the map of
//! that moment at configurations no farther apart than half the planner's
//! step: `dist(Q) ≤ 1` there is an *unsafe configuration*, recorded.
//!
//! A checkpoint is written after every viewpoint; resuming replays the
//! recorded viewpoints' sweeps (the scanner's noise is reseeded per
//! viewpoint, [`hw::LineScanner::seed_noise`]) and goes on, so an
//! interrupted run ends as an uninterrupted one. The replayed records are
//! not judged again, so the checkpoint carries a checksum and the
//! scenario as run: an edited checkpoint, or one of other inputs, is
//! refused.

use crate::discs::{DiscMap, disc_map};
use crate::judge::{Judge, SafetyTally};
use crate::lrc::PatchIndex;
use crate::materials::Materials;
use crate::probe::MapProbe;
use crate::setup::Setup;
use crate::stage_one::path_via_visited;
use crate::{Choice, ExploreConfig, ExploreError, StageOne, StageTwoChoice, Termination};
use geom::{Isometry3, Real, TriMesh};
use hw::clock::{Activity, ClockMark, RobotClock, RobotTime, RobotTiming};
use hw::{Arm, LineScanner, tilt_sweep, tilt_sweep_through};
use map::{IntegrationStats, TsdfConfig, TsdfMap};
use plan::{ClearanceChecker, PlanConfig, PointClearance, Safety};
use record::checkpoint::{CHECKPOINT_FORMAT, Checkpoint};
use record::{ScoredCandidate, UnsafeConfiguration, ViewpointRecord};
use robot::Robot;
use robot::timing::MotionLimits;
use sensor::{Scanner, Sweep, SweepPoint};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// Which run this is, as a checkpoint records it: a resumed run must be of
/// the same scenario, content included.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RunIdentity {
    /// The scenario's name.
    pub scenario: String,
    /// The scenario as run (its file's text, robot included): any change
    /// refuses a resume.
    pub scenario_toml: String,
}

/// How to run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Seed of the run (the scanner's noise per viewpoint, the disc draws).
    pub seed: u64,
    /// The TSDF of the output mesh.
    pub tsdf: TsdfConfig,
    /// Record wall-clock times (off: the time columns are 0, so outputs are
    /// the same byte for byte for the same inputs).
    pub timings: bool,
    /// Write a checkpoint here after every viewpoint.
    pub checkpoint: Option<PathBuf>,
    /// Continue the run recorded in `checkpoint` (which must exist).
    pub resume: bool,
    /// Run Stage Two after Stage One.
    pub stage_two: bool,
    /// Which run this is (kept in the checkpoint).
    pub identity: RunIdentity,
    /// The robot clock the hardware runs on (`hw::clock::Timed`): the loop
    /// says what the robot is doing, counts its decisions on it, and reads
    /// each viewpoint's robot time from it.
    pub clock: RobotClock,
}

/// Robot time a decision counts when timings are off (wall time would make
/// the outputs differ run to run), seconds: the README run's decisions,
/// integration included, take 0.9 s (Stage One) and 1.5 s (Stage Two) at
/// the median on a laptop core.
pub const UNTIMED_DECISION_S: Real = 1.0;

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            tsdf: TsdfConfig::default(),
            timings: true,
            checkpoint: None,
            resume: false,
            stage_two: true,
            identity: RunIdentity::default(),
            clock: RobotClock::default(),
        }
    }
}

/// A finished run.
#[derive(Clone, Debug)]
pub struct ExploreRun {
    /// Scenario name.
    pub scenario: String,
    /// Per viewpoint.
    pub viewpoints: Vec<ViewpointRecord>,
    /// Why Stage One stopped.
    pub termination: Termination,
    /// Why Stage Two stopped (`None` when it did not run).
    pub stage_two_termination: Option<String>,
    /// Configurations with `dist(Q) ≤ 1` along executed motions.
    pub unsafe_configurations: Vec<UnsafeConfiguration>,
    /// What the judge tallied.
    pub tally: SafetyTally,
    /// `(H1 weighted, H2)` before the first sweep.
    pub initial_information: (Real, Real),
    /// How the C-space model was obtained.
    pub cspace: String,
    /// How the LRC was obtained (`None`: no materials or no discs, so no
    /// classifier).
    pub lrc: Option<String>,
    /// Every measured point.
    pub cloud: Vec<SweepPoint>,
    /// Per point of `cloud`: the index of the viewpoint whose sweep
    /// measured it (into `viewpoints`).
    pub cloud_viewpoint: Vec<usize>,
    /// The TSDF mesh.
    pub mesh: TriMesh,
    /// The map products of Stage One (A§5.2–5.3): the mesh's Scale-Like
    /// Discs and their segments, with the material belief.
    pub discs: DiscMap,
    /// The planning grid at the end of the run (occupancy at
    /// `planning_voxel_m`, with H1 and H2): what later plans, such as blast
    /// plans, must respect.
    pub grid: map::OccupancyGrid,
    /// Wall time of the whole run, seconds (0 when timings are off).
    pub wall_s: Real,
    /// Where the run's wall time went (`None` when timings are off): the
    /// phases of [`run`] (stages, discs, LRC, final mesh; `total_s` is
    /// [`Self::wall_s`]); a job around it, such as the simulator's, adds
    /// its own (setup, blast plan, files, report) and its total.
    pub timings: Option<record::explore::PhaseTimings>,
}

/// The noise seed of viewpoint `k`'s sweep in a run of seed `seed` (the
/// start pose's sweep is viewpoint 0).
pub fn viewpoint_seed(seed: u64, k: usize) -> u64 {
    seed ^ 0xa076_1d64_78bd_642f_u64.wrapping_mul(k as u64 + 1)
}

/// Salt of the noise seed of the scans taken on the way to a viewpoint.
const MOTION_NOISE_SALT: u64 = 0x5bd1_e995_0000_0001;

/// How much closer than its bound the guard of a motion lets a step come
/// before it stops the arm, metres: the guard checks the motion at other
/// configurations than the planner did (each step's own interpolation), and
/// a configuration between two the planner checked may lie a fraction of a
/// millimetre closer; a stop is for a surface the motion's own scans
/// revealed.
const GUARD_TOLERANCE_M: Real = 0.001;

/// How much less than `stage_one_clearance_m` from the measured points the
/// guard of a motion holds the arm to, metres. The nearest of many noisy
/// points lies closer than the surface they measure (on the bridge scenes
/// 20 mm closer, against 10 mm of range noise), so a guard at the planner's
/// own 0.05 m stopped motions that kept 0.08 m from the true surface, and
/// each stop is a viewpoint; 0.04 m from the points kept every link 0.059 m
/// or more from the true surface on channel4.
const GUARD_MARGIN_M: Real = 0.01;

/// Run AXBAM from `setup` on `hw`: Stage One, then Stage Two when
/// `options.stage_two` (and the setup has materials), then the map
/// products. `judge` sees every executed motion and sweep; `progress` each
/// viewpoint's record as it completes.
pub fn run<H: Arm + LineScanner + ?Sized>(
    setup: Setup,
    hw: &mut H,
    judge: &mut dyn Judge,
    options: &RunOptions,
    progress: &mut dyn FnMut(&ViewpointRecord),
) -> Result<ExploreRun, ExploreError> {
    let t_run = Instant::now();
    let mut phases = record::explore::PhaseTimings::default();
    let mut clock = Instant::now();
    // Seconds since the last lap.
    let mut lap = || {
        let s = clock.elapsed().as_secs_f64();
        clock = Instant::now();
        s
    };
    if setup.config.motion == crate::Motion::Continuous && hw.moving().is_none() {
        return Err(ExploreError::Config {
            field: "explore.motion",
            expected: "\"stop_and_go\" on hardware that cannot scan while the arm moves",
            got: "\"continuous\"".into(),
        });
    }
    let mut episode = Episode::new(setup, hw, judge, options)?;
    let restored = if options.resume {
        Some(episode.restore()?)
    } else {
        None
    };
    let (mut replay_one, replay_two, tried_before) = restored.unwrap_or_default();
    let termination = episode.stage_one(&mut replay_one, progress)?;
    phases.stage_one_s = lap();
    let mesh = episode.tsdf.extract_mesh();
    // Stage Two's map world is built beside the disc map: both only read
    // the mesh, and each is mostly serial work.
    let two = options.stage_two && !episode.setup.materials.is_empty();
    let (discs, built_world) = std::thread::scope(|s| {
        let world = two.then(|| s.spawn(|| map_world(&mesh)));
        let discs = disc_map(
            &mesh,
            (&episode.cloud, &episode.cloud_viewpoint),
            &episode.viewpoints,
            (&episode.setup.materials, &*episode.judge),
            &episode.setup.config.mapping,
            options.seed,
        );
        let world = world.map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)));
        (discs, world)
    });
    let mut discs = discs?;
    phases.discs_s = lap();
    let mut materials = Materials::new(
        &mut discs,
        &mesh,
        &episode.setup.config.pose,
        &episode.setup.materials,
        &episode.setup.scanner,
        options.seed,
        episode.setup.lrc_cache.as_deref(),
    )?;
    if let Some(m) = &mut materials {
        for sweep in &std::mem::take(&mut episode.sweeps) {
            m.observe(&mut discs, sweep)?;
        }
        // Stage One's last row holds H3 once its sweeps are classified on
        // the map Stage One built: the baseline of Stage Two's curve.
        if let Some(last) = episode.viewpoints.last_mut() {
            last.h3 = Some(m.h3_total());
            last.discs_identified = Some(m.mark_identified(&mut discs, last.k));
        }
    }
    phases.lrc_s = lap();
    // The map products between the stages are made while the arm stands.
    episode.decided(phases.discs_s + phases.lrc_s);
    let mut stage_two_termination = None;
    if let (true, Some(m)) = (options.stage_two, materials.as_mut()) {
        let map_world = match built_world {
            Some(w) => w?,
            None => map_world(&mesh)?,
        };
        let end = episode.stage_two(
            m,
            &mut discs,
            map_world,
            &tried_before,
            replay_two,
            progress,
        )?;
        stage_two_termination = Some(end.to_owned());
    }
    if let Some(m) = &materials {
        m.finish(&mut discs);
    }
    let lrc = materials.map(|m| m.obtained);
    phases.stage_two_s = lap();
    let Episode {
        setup,
        tsdf,
        viewpoints,
        cloud,
        cloud_viewpoint,
        unsafe_configurations,
        judge,
        ..
    } = episode;
    let mesh = tsdf.extract_mesh();
    phases.final_mesh_s = lap();
    let wall_s = t_run.elapsed().as_secs_f64();
    phases.total_s = wall_s;
    Ok(ExploreRun {
        scenario: options.identity.scenario.clone(),
        viewpoints,
        termination,
        stage_two_termination,
        unsafe_configurations,
        tally: judge.tally(),
        initial_information: setup.stage.initial_information(),
        cspace: setup.cspace,
        lrc,
        cloud,
        cloud_viewpoint,
        mesh,
        discs,
        grid: setup.stage.grid().clone(),
        wall_s: if options.timings { wall_s } else { 0.0 },
        timings: options.timings.then_some(phases),
    })
}

/// A Stage One choice waiting for its sweep.
struct Pending {
    choice: Choice,
    scored: Vec<ScoredCandidate>,
    front: usize,
    unreachable: usize,
    decision_ms: Real,
    plan_ms: Real,
}

/// A Stage Two choice: the disc, the path to its pose, the decision's time
/// and the discs ranked.
struct Aim {
    target: usize,
    path: plan::Path,
    decision_ms: Real,
    ranked: usize,
}

/// What a viewpoint's sweep gave.
struct Taken {
    stats: IntegrationStats,
    sweep_ms: Real,
    integrate_ms: Real,
}

/// What a checkpoint restores: the Stage One and Stage Two viewpoints to
/// replay, and the discs Stage Two has tried.
type Restored = (
    VecDeque<ViewpointRecord>,
    VecDeque<ViewpointRecord>,
    Vec<usize>,
);

/// The state of a run under way.
struct Episode<'a, H: ?Sized> {
    setup: Setup,
    hw: &'a mut H,
    judge: &'a mut dyn Judge,
    options: &'a RunOptions,
    /// Motions are checked against the map at half the planner's step.
    fine: Safety,
    tsdf: TsdfMap,
    viewpoints: Vec<ViewpointRecord>,
    cloud: Vec<SweepPoint>,
    /// Per point of `cloud`: the viewpoint that measured it.
    cloud_viewpoint: Vec<usize>,
    /// Stage One's sweeps, classified once its map is made.
    sweeps: Vec<Sweep>,
    unsafe_configurations: Vec<UnsafeConfiguration>,
    /// Where the arm is.
    q: Vec<Real>,
    /// Every point measured, for Stage One's clearance.
    points: PointClearance,
    /// The robot clock when the last viewpoint's record was made (at
    /// first, when the run began: a clock may have run before).
    recorded_at: ClockMark,
}

impl<'a, H: Arm + LineScanner + ?Sized> Episode<'a, H> {
    fn new(
        setup: Setup,
        hw: &'a mut H,
        judge: &'a mut dyn Judge,
        options: &'a RunOptions,
    ) -> Result<Self, ExploreError> {
        let config = &setup.config;
        let fine = Safety::new(
            setup.robot.clone(),
            setup.world_from_base,
            &PlanConfig {
                check_step_m: 0.5 * config.plan.check_step_m,
                ..config.plan.clone()
            },
            setup.stage.model().roadmap().weights().to_vec(),
        )?;
        let tsdf = TsdfMap::new(options.tsdf)?;
        let q = setup.start.clone();
        Ok(Self {
            setup,
            hw,
            judge,
            options,
            fine,
            tsdf,
            viewpoints: Vec::new(),
            cloud: Vec::new(),
            cloud_viewpoint: Vec::new(),
            sweeps: Vec::new(),
            unsafe_configurations: Vec::new(),
            q,
            points: PointClearance::new(),
            recorded_at: options.clock.mark(),
        })
    }

    fn stage(&self) -> &StageOne {
        &self.setup.stage
    }

    fn config(&self) -> &ExploreConfig {
        &self.setup.config
    }

    /// Milliseconds since `t`, or 0 when timings are off.
    fn timed(&self, t: Instant) -> Real {
        if self.options.timings {
            t.elapsed().as_secs_f64() * 1e3
        } else {
            0.0
        }
    }

    /// The robot stood still for `wall_s` seconds of decision (integrating
    /// and deciding): counted on the robot clock, or [`UNTIMED_DECISION_S`]
    /// when timings are off.
    fn decided(&self, wall_s: Real) {
        let s = if self.options.timings {
            wall_s
        } else {
            UNTIMED_DECISION_S
        };
        self.options.clock.stand(Activity::Deciding, s);
    }

    /// Viewpoint `record` is complete: a new one gets the robot time since
    /// the last record (a replayed one keeps its own), then it is shown
    /// to `progress` and kept.
    fn push_record(
        &mut self,
        mut record: ViewpointRecord,
        replayed: bool,
        progress: &mut dyn FnMut(&ViewpointRecord),
    ) {
        if !replayed {
            record.robot_time = self.options.clock.since(&self.recorded_at);
        }
        self.recorded_at = self.options.clock.mark();
        progress(&record);
        self.viewpoints.push(record);
    }

    /// The checkpoint of the run so far.
    fn checkpoint(&self, tried: &[usize]) -> Checkpoint<ExploreConfig> {
        let tally = self.judge.tally();
        let id = &self.options.identity;
        Checkpoint {
            format: CHECKPOINT_FORMAT,
            checksum: 0,
            scenario: id.scenario.clone(),
            scenario_toml: id.scenario_toml.clone(),
            stage_two: self.options.stage_two,
            seed: self.options.seed,
            config: self.config().clone(),
            sweep: self.config().sweep,
            viewpoints: self.viewpoints.clone(),
            collisions: tally.collisions,
            unsafe_configurations: self.unsafe_configurations.clone(),
            min_clearance_m: tally.min_clearance_m,
            stage_two_tried: tried.to_vec(),
        }
    }

    /// Write the checkpoint, when the run keeps one.
    fn save(&self, tried: &[usize]) -> Result<(), ExploreError> {
        match &self.options.checkpoint {
            Some(path) => Ok(self.checkpoint(tried).write(path)?),
            None => Ok(()),
        }
    }

    /// Read the checkpoint to resume from, refuse one of another run, and
    /// restore the tallies; the viewpoints to replay are returned.
    fn restore(&mut self) -> Result<Restored, ExploreError> {
        let path = self
            .options
            .checkpoint
            .as_ref()
            .ok_or_else(|| ExploreError::Resume {
                what: "resume".into(),
                message: "no checkpoint file given".into(),
            })?;
        let c = Checkpoint::<ExploreConfig>::read(path)?;
        let mine = self.checkpoint(&[]);
        let mut config = mine.config.clone();
        config.sweep = c.config.sweep;
        let stages = |two: bool| if two { "both" } else { "one" };
        let differs = if c.scenario != mine.scenario {
            Some(format!(
                "the scenario ({} then, {} now)",
                c.scenario, mine.scenario
            ))
        } else if c.seed != mine.seed {
            Some(format!("--seed ({} then, {} now)", c.seed, mine.seed))
        } else if c.stage_two != mine.stage_two {
            Some(format!(
                "--stages ({} then, {} now)",
                stages(c.stage_two),
                stages(mine.stage_two)
            ))
        } else if c.scenario_toml != mine.scenario_toml {
            Some(
                "the scenario's content (the file, or --robot, changed since the checkpoint)"
                    .to_owned(),
            )
        } else if c.config != config || c.sweep != mine.sweep {
            Some("the exploration parameters ([explore], --max-viewpoints)".to_owned())
        } else {
            None
        };
        if let Some(what) = differs {
            return Err(ExploreError::Resume {
                what: path.display().to_string(),
                message: format!(
                    "the checkpoint is of another run: {what} differs; resume with the same \
                     scenario, robot, --seed, --stages and parameters, or run again without --resume"
                ),
            });
        }
        self.judge.restore(SafetyTally {
            collisions: c.collisions,
            min_clearance_m: c.min_clearance_m,
        });
        self.unsafe_configurations = c.unsafe_configurations;
        let (one, two): (Vec<_>, Vec<_>) = c.viewpoints.into_iter().partition(|r| r.stage == 1);
        Ok((one.into(), two.into(), c.stage_two_tried))
    }

    /// Check the executed motion `a` → `b` (on the way to, or sweeping at,
    /// viewpoint `k`) against the map of this moment, and show it to the
    /// judge.
    fn audit(&mut self, k: usize, a: &[Real], b: &[Real]) -> Result<(), ExploreError> {
        let checked = self.fine.interpolate(a, b);
        for c in &checked {
            let d = self.fine.dist(self.setup.stage.grid(), c)?;
            if d <= 1.0 {
                self.unsafe_configurations.push(UnsafeConfiguration {
                    viewpoint: k,
                    joints: c.clone(),
                    dist: d,
                });
            }
        }
        self.judge.motion(k, a, b, &checked)
    }

    /// Move along `waypoints` to viewpoint `k`, each motion audited first.
    fn move_along(&mut self, k: usize, waypoints: &[Vec<Real>]) -> Result<(), ExploreError> {
        self.options.clock.set_activity(Activity::Moving);
        for w in waypoints.windows(2) {
            self.audit(k, &w[0], &w[1])?;
            self.hw.move_to(&w[1])?;
        }
        // Plans start where the arm was sent, not where it reports within
        // its tolerance: joints a motion does not move never drift.
        if let Some(last) = waypoints.last() {
            self.q.clone_from(last);
        }
        Ok(())
    }

    /// Move along `waypoints` to Stage One's viewpoint `k` scanning as the
    /// arm moves (`motion_scan_step_deg`; without it, as
    /// [`Episode::move_along`]), each motion audited unless `replayed`;
    /// what the scanner saw goes into the maps and the cloud as viewpoint
    /// `k`'s. Each step keeps Stage One's clearance from the points measured
    /// so far, the motion's own included: returns `false` when that stopped
    /// the arm short of the goal.
    fn move_scanning(
        &mut self,
        k: usize,
        waypoints: &[Vec<Real>],
        replayed: bool,
        transit: Transit<'_>,
    ) -> Result<bool, ExploreError> {
        let step = transit.step_deg.to_radians();
        if step <= 0.0 {
            // A replayed viewpoint's arm is put where it stood.
            if !replayed {
                self.move_along(k, waypoints)?;
            }
            return Ok(true);
        }
        self.hw
            .seed_noise(viewpoint_seed(self.options.seed, k) ^ MOTION_NOISE_SALT);
        self.options
            .clock
            .set_activity(Activity::MovingWhileScanning);
        let mut builder = sensor::SweepBuilder::new(self.hw.bearings_rad())?;
        if let Some(first) = waypoints.first()
            && replayed
        {
            self.hw.move_to(first)?;
        }
        let clearance_m = transit.clearance_m;
        // Points of `builder` already in `self.points`.
        let mut kept = 0;
        let mut completed = true;
        // The clearance every step must keep: where the arm stood when it
        // chose, it may be closer than `clearance_m` (a surface it saw
        // after arriving) and back away; the bound rises as it does, up to
        // `clearance_m`, and never falls.
        let mut bound: Option<Real> = None;
        // The last step's goal and its clearance when measured, and the
        // points kept since: a step that starts there measures the new
        // points only (the same number as measuring them all).
        let mut last: Option<(Vec<Real>, Real)> = None;
        let mut fresh = PointClearance::new();
        let search_m = clearance_m - GUARD_MARGIN_M;
        // Continuous motion: each segment one timed motion, at most `step`
        // on the largest joint per scan.
        let scan_time_s = self.setup.timing.scan_time_s;
        let line = (self.config().motion == crate::Motion::Continuous)
            .then(|| per_scan(&self.setup.timing, step));
        let mut stopped_at = self.q.clone();
        for w in waypoints.windows(2) {
            let s = &self.setup;
            let (fine, points) = (&self.fine, &mut self.points);
            // Each step keeps the bound from what the scanner has measured
            // so far, the motion's own scans included: a surface seen on
            // the way stops the arm before it comes too close.
            let mut guard = |at: &[Real], next: &[Real], b: &sensor::SweepBuilder| {
                fresh.clear();
                points.insert_noting(
                    b.points()[kept..].iter().map(|p| &p.point),
                    Some(&mut fresh),
                );
                kept = b.points().len();
                if clearance_m <= 0.0 {
                    return true;
                }
                let clearance = |q: &[Real]| points.configuration_clearance(fine, q, search_m);
                let here = match last.take() {
                    Some((q, c)) if q.as_slice() == at => {
                        c.min(fresh.configuration_clearance(fine, at, search_m))
                    }
                    _ => clearance(at),
                };
                let least = *bound.get_or_insert(here);
                let mut at_next = None;
                let ok = fine.interpolate(at, next).iter().all(|c| {
                    let v = if c.as_slice() == at {
                        here
                    } else {
                        let v = clearance(c);
                        if c.as_slice() == next {
                            at_next = Some(v);
                        }
                        v
                    };
                    v >= least - GUARD_TOLERANCE_M
                });
                if ok {
                    let there = at_next.unwrap_or_else(|| clearance(next));
                    bound = Some(least.max(there));
                    last = Some((next.to_vec(), there));
                }
                ok
            };
            // One timed motion, the guard on a receding horizon; or steps.
            let (completed_here, reached) = if let Some(limits) = &line {
                let motion = hw::motion::LineMotion::new(limits, &w[0], &w[1]);
                let done = hw::motion::scan_line(
                    &mut *self.hw,
                    &s.robot,
                    &s.world_from_base,
                    &motion,
                    scan_time_s,
                    &mut builder,
                    &mut guard,
                )?;
                (done.completed, done.reached)
            } else {
                let done = hw::scan_motion(
                    &mut *self.hw,
                    &s.robot,
                    &s.world_from_base,
                    (&w[0], &w[1]),
                    step,
                    &mut builder,
                    &mut guard,
                )?;
                let reached = if done.completed {
                    w[1].clone()
                } else {
                    self.hw.joints()
                };
                (done.completed, reached)
            };
            // The map is the one the motion started on until its scans are
            // integrated below: the audit sees what the arm did.
            if !replayed {
                self.audit(k, &w[0], &reached)?;
            }
            stopped_at = reached;
            if !completed_here {
                completed = false;
                break;
            }
        }
        // Where the arm was sent (as in `move_along`), or where the guard
        // stopped it.
        self.q = match waypoints.last() {
            Some(last) if completed => last.clone(),
            _ => stopped_at,
        };
        if builder.scan_count() > 0 {
            let t = Instant::now();
            let sweep = builder.finish()?;
            self.setup.stage.integrate_motion(&sweep);
            self.tsdf.integrate_sweep(&sweep);
            // The guard kept the points before `kept` (the sweep holds the
            // builder's points in order): the same index, without looking
            // each up again.
            self.add_points(k, &sweep, kept);
            if let Some((m, discs)) = transit.classify {
                m.observe(discs, &sweep)?;
            }
            self.decided(t.elapsed().as_secs_f64());
        }
        Ok(completed)
    }

    /// Stage One's transits: `motion_scan_step_deg`, its clearance, no
    /// classification.
    fn stage_one_transit(&self) -> Transit<'static> {
        Transit {
            step_deg: self.config().motion_scan_step_deg,
            clearance_m: self.config().stage_one_clearance_m,
            classify: None,
        }
    }

    /// Keep the points `sweep` measured for viewpoint `k` (the cloud, the
    /// clearance index from its point `kept` on: the ones before are in it
    /// already) and show them to the judge.
    fn add_points(&mut self, k: usize, sweep: &Sweep, kept: usize) {
        self.cloud.extend_from_slice(sweep.points());
        self.cloud_viewpoint.resize(self.cloud.len(), k);
        let new = sweep.points().get(kept..).unwrap_or_default();
        self.points.insert(new.iter().map(|p| &p.point));
        self.judge.sweep(sweep);
    }

    /// Take viewpoint `k`'s sweep where the arm stands and integrate it;
    /// with `classify`, the sweep also updates the material beliefs. A
    /// replayed viewpoint's sweep motion was audited before the
    /// interruption, a new one's is audited now.
    fn take_viewpoint(
        &mut self,
        k: usize,
        replayed: bool,
        classify: Option<(&mut Materials, &mut DiscMap)>,
    ) -> Result<(Sweep, Taken), ExploreError> {
        let q = self.q.clone();
        let tilts = self.safe_tilts(&q, classify.is_none())?;
        if !replayed {
            let j = self.stage().tilt_joint();
            let (mut lo, mut hi) = (q.clone(), q.clone());
            lo[j] = tilts[0];
            hi[j] = tilts[tilts.len() - 1];
            self.audit(k, &q, &lo)?;
            self.audit(k, &lo, &hi)?;
            self.audit(k, &hi, &q)?;
        }
        self.hw.seed_noise(viewpoint_seed(self.options.seed, k));
        let t = Instant::now();
        let s = &self.setup;
        self.options.clock.set_activity(Activity::StandingToSweep);
        let sweep = match (self.config().motion, tilts.first(), tilts.last()) {
            // One motion across, the scanner scanning all along at the
            // sweep's tilt step per scan.
            (crate::Motion::Continuous, Some(&lo), Some(&hi)) if tilts.len() > 1 => {
                let t = &s.timing;
                let limits = sweep_limits(t, lo, hi, tilts.len());
                hw::motion::tilt_sweep_moving(
                    &mut *self.hw,
                    &s.robot,
                    &s.world_from_base,
                    &q,
                    s.stage.tilt_joint(),
                    (lo, hi),
                    &limits,
                    t.scan_time_s,
                )?
            }
            _ => tilt_sweep_through(
                &mut *self.hw,
                &s.robot,
                &s.world_from_base,
                &q,
                s.stage.tilt_joint(),
                &tilts,
                &mut |_, _| {},
            )?,
        };
        let sweep_ms = self.timed(t);
        let t = Instant::now();
        let stats = self.setup.stage.integrate(&sweep);
        self.tsdf.integrate_sweep(&sweep);
        if let Some((m, discs)) = classify {
            m.observe(discs, &sweep)?;
        }
        let integrate_ms = self.timed(t);
        self.decided(t.elapsed().as_secs_f64());
        self.add_points(k, &sweep, 0);
        Ok((
            sweep,
            Taken {
                stats,
                sweep_ms,
                integrate_ms,
            },
        ))
    }

    /// The tilt values of a sweep at `q` that keep the arm safe on the map
    /// of this moment: the configured sweep cut to the part around the
    /// standing tilt where every configuration the audit checks has
    /// `dist(Q) > 1` and, with `keep_clear` (Stage One), the clearance from
    /// the measured points ([`ClearanceChecker`]). The scans of a motion may
    /// show, once integrated, that part of the sweep chosen before it
    /// would not be. Never empty: at worst the standing tilt alone.
    fn safe_tilts(&self, q: &[Real], keep_clear: bool) -> Result<Vec<Real>, ExploreError> {
        let stage = self.stage();
        let j = stage.tilt_joint();
        let clearance_m = if keep_clear {
            self.config().stage_one_clearance_m
        } else {
            0.0
        };
        let clear = ClearanceChecker::new((), &self.fine, &self.points, clearance_m, q);
        // The first configuration of the motion `a` → `b` (the audit's
        // interpolation) that is not safe.
        let first_unsafe = |a: &[Real], b: &[Real]| -> Result<Option<Vec<Real>>, ExploreError> {
            let from_here = a == q || b == q;
            for c in self.fine.interpolate(a, b) {
                if self.fine.dist(stage.grid(), &c)? <= 1.0 || !clear.clears(&c, from_here) {
                    return Ok(Some(c));
                }
            }
            Ok(None)
        };
        let at = |t: Real| {
            let mut c = q.to_vec();
            c[j] = t;
            c
        };
        let mut tilts = stage.sweep_tilts(q);

        // Cut the tilt values at the first unsafe configuration on the way
        // out to each end, then check the motions the audit checks (out to
        // the lowest, across to the highest, back), cutting again while
        // one fails.
        while let (Some(&lo), Some(&hi)) = (tilts.first(), tilts.last()) {
            let (lo, hi) = (at(lo), at(hi));
            let low = first_unsafe(q, &lo)?;
            let high = first_unsafe(&hi, q)?;
            let across = if low.is_none() && high.is_none() {
                first_unsafe(&lo, &hi)?
            } else {
                None
            };
            if low.is_none() && high.is_none() && across.is_none() {
                return Ok(tilts);
            }
            let len = tilts.len();
            for c in [low, high, across].into_iter().flatten() {
                let t = c[j];
                // Keep the side of the unsafe tilt the arm stands on.
                tilts.retain(|&v| if t < q[j] { v > t } else { v < t });
            }
            if tilts.len() == len {
                // An unsafe configuration at the standing tilt itself (the
                // unsafe one is the pose the arm stands at, or the cut did
                // not move): narrow from both ends.
                tilts.remove(0);
                tilts.pop();
            }
        }
        Ok(vec![q[j]])
    }

    /// The record of a viewpoint just taken at the arm's pose.
    fn record(&self, k: usize, stage: u8, taken: &Taken) -> ViewpointRecord {
        let (h1_weighted, h2) = self.stage().information();
        ViewpointRecord {
            k,
            stage,
            joints: self.q.clone(),
            f: None,
            h1: self.stage().grid().h1_unweighted(),
            h1_weighted,
            h2,
            h3: None,
            discs_identified: None,
            target_disc: None,
            predicted_h1_weighted: None,
            candidates: 0,
            front: 0,
            unreachable: 0,
            predicted_revealed: 0,
            revealed: taken.stats.newly_known,
            coverage_a1: self.judge.coverage_a1(),
            joint_travel: 0.0,
            waypoints: 0,
            path: Vec::new(),
            scored: Vec::new(),
            decision_ms: 0.0,
            plan_ms: 0.0,
            sweep_ms: taken.sweep_ms,
            integrate_ms: taken.integrate_ms,
            robot_time: RobotTime::default(),
        }
    }

    /// Stage One's record of viewpoint `k` just taken, with the choice that
    /// led there (none at the start).
    fn stage_one_record(
        &self,
        k: usize,
        taken: &Taken,
        pending: Option<Pending>,
    ) -> ViewpointRecord {
        let mut record = self.record(k, 1, taken);
        if let Some(p) = pending {
            let c = &p.choice;
            record.f = Some(c.candidate.f);
            record.predicted_h1_weighted = Some(c.candidate.f[0]);
            record.predicted_revealed = c.candidate.revealed;
            record.candidates = p.scored.len();
            record.front = p.front;
            record.unreachable = p.unreachable;
            record.joint_travel = c.path.joint_travel();
            record.waypoints = c.path.waypoints.len();
            record.path.clone_from(&c.path.waypoints);
            record.scored = p.scored;
            record.decision_ms = p.decision_ms;
            record.plan_ms = p.plan_ms;
        }
        record
    }

    /// Put the arm where a replayed viewpoint stood.
    fn stand_at(&mut self, r: &ViewpointRecord) -> Result<(), ExploreError> {
        self.hw.move_to(&r.joints)?;
        self.q.clone_from(&r.joints);
        Ok(())
    }

    /// Stage One (A§3.2): sweep, then decide, move and sweep again until
    /// the 1 % rule, the budget, or no safe candidate.
    fn stage_one(
        &mut self,
        replay: &mut VecDeque<ViewpointRecord>,
        progress: &mut dyn FnMut(&ViewpointRecord),
    ) -> Result<Termination, ExploreError> {
        let mut pending: Option<Pending> = None;
        // Whether the arm reached the viewpoint it chose last.
        let mut arrived = true;
        loop {
            let k = self.viewpoints.len();
            // A replayed viewpoint: the arm is put where it stood and its
            // sweep taken again (same seed, same points); its record and
            // audit come from the checkpoint.
            let replayed = replay.pop_front();
            if let Some(r) = &replayed {
                arrived = self.move_scanning(k, &r.path, true, self.stage_one_transit())?;
                self.stand_at(r)?;
            }
            let (sweep, taken) = self.take_viewpoint(k, replayed.is_some(), None)?;
            self.sweeps.push(sweep);
            let was_replayed = replayed.is_some();
            let record = if let Some(r) = replayed {
                r
            } else {
                self.stage_one_record(k, &taken, pending.take())
            };
            self.push_record(record, was_replayed, progress);
            if !replay.is_empty() {
                continue;
            }
            // A replayed viewpoint is in the checkpoint already (with any
            // Stage Two viewpoints after it).
            if !was_replayed {
                self.save(&[])?;
            }
            // The 1 % rule judges the viewpoints the arm chose: one where a
            // motion was stopped short does not end Stage One (the budget
            // still does).
            if let Some(t) = self.stage().termination(arrived) {
                return Ok(t);
            }
            let t = Instant::now();
            let visited: Vec<&[Real]> = self
                .viewpoints
                .iter()
                .map(|v| v.joints.as_slice())
                .collect();
            let decision = self.stage().decide(&self.q, Some(&self.points), &visited)?;
            let decision_ms = self.timed(t);
            self.decided(t.elapsed().as_secs_f64());
            let plan_ms = if self.options.timings {
                decision.plan_ms
            } else {
                0.0
            };
            let Some(choice) = decision.choice else {
                return Ok(Termination::NoSafeCandidate);
            };
            // Move along the path, auditing each motion against the map as
            // it is, and scanning as the arm moves.
            arrived = self.move_scanning(
                k + 1,
                &choice.path.waypoints,
                false,
                self.stage_one_transit(),
            )?;
            let scored = decision
                .candidates
                .iter()
                .zip(&decision.on_front)
                .map(|(c, &front)| ScoredCandidate { f: c.f, front })
                .collect();
            pending = Some(Pending {
                choice,
                scored,
                front: decision.front_size,
                unreachable: decision.unreachable,
                decision_ms,
                plan_ms,
            });
        }
    }

    /// Stage Two (A§3.3): aim the scanner at the disc with the most
    /// material information left that a valid, reachable pose can target;
    /// sweep, classify, update; until none can be targeted or the budget is
    /// spent. Returns why it stopped.
    fn stage_two(
        &mut self,
        m: &mut Materials,
        discs: &mut DiscMap,
        map_world: Arc<scene::World>,
        tried_before: &[usize],
        mut replay: VecDeque<ViewpointRecord>,
        progress: &mut dyn FnMut(&ViewpointRecord),
    ) -> Result<&'static str, ExploreError> {
        let mut tried = vec![false; discs.discs.len()];
        for &i in tried_before {
            if let Some(t) = tried.get_mut(i) {
                *t = true;
            }
        }
        let safety = self.stage().model().safety().clone();
        let mut aimer = Aimer::new(self, map_world, &safety)?;
        let information = self.config().stage_two == StageTwoChoice::Information;
        loop {
            let done = self.viewpoints.iter().filter(|r| r.stage == 2).count();
            if done >= self.config().stage_two_max_viewpoints {
                return Ok("viewpoint_budget");
            }
            let k = self.viewpoints.len();
            // A replayed viewpoint: the arm is put where it stood (its
            // record and audit come from the checkpoint).
            let replayed = replay.pop_front();
            let mut predicted = Vec::new();
            let transit = |config: &ExploreConfig, m, discs| Transit {
                step_deg: config.stage_two_scan_step_deg,
                clearance_m: config.stage_two_clearance_m,
                classify: Some((m, discs)),
            };
            let aim = if let Some(r) = &replayed {
                let t = transit(&self.setup.config, &mut *m, &mut *discs);
                self.move_scanning(k, &r.path, true, t)?;
                self.stand_at(r)?;
                None
            } else {
                let t = Instant::now();
                let found = if information {
                    aimer.choose_information(self, m, discs, &mut tried, k)?
                } else {
                    aimer
                        .choose(self, m, discs, &mut tried, k)?
                        .map(|(t, p, r)| (t, p, r, Vec::new()))
                };
                let decision_ms = self.timed(t);
                self.decided(t.elapsed().as_secs_f64());
                let Some((target, path, ranked, usable)) = found else {
                    return Ok("no_targetable_disc");
                };
                predicted = usable;
                let t = transit(&self.setup.config, &mut *m, &mut *discs);
                self.move_scanning(k, &path.waypoints, false, t)?;
                Some(Aim {
                    target,
                    path,
                    decision_ms,
                    ranked,
                })
            };
            let (_, taken) = self.take_viewpoint(k, replayed.is_some(), Some((m, discs)))?;
            let identified = m.mark_identified(discs, k);
            // A disc the sweep was predicted to observe and that is still
            // not identified is not counted on again.
            for &j in &predicted {
                if !m.identified(j) {
                    tried[j] = true;
                }
            }
            let was_replayed = replayed.is_some();
            let record = match (replayed, aim) {
                (Some(r), _) => r,
                (None, None) => {
                    return Err(ExploreError::Resume {
                        what: "stage two".into(),
                        message: "a viewpoint is neither replayed nor chosen".into(),
                    });
                }
                (None, Some(aim)) => ViewpointRecord {
                    h3: Some(m.h3_total()),
                    discs_identified: Some(identified),
                    target_disc: Some(aim.target),
                    candidates: aim.ranked,
                    joint_travel: aim.path.joint_travel(),
                    waypoints: aim.path.waypoints.len(),
                    path: aim.path.waypoints,
                    decision_ms: aim.decision_ms,
                    ..self.record(k, 2, &taken)
                },
            };
            self.push_record(record, was_replayed, progress);
            if replay.is_empty() {
                let tried: Vec<usize> = (0..tried.len()).filter(|&i| tried[i]).collect();
                self.save(&tried)?;
            }
        }
    }
}

/// How a transit scans: a scan each `step_deg` of the largest joint (0:
/// none), keeping `clearance_m` from the measured points, and the LRC
/// classifying the scans when `classify` holds the beliefs.
struct Transit<'m> {
    step_deg: Real,
    clearance_m: Real,
    classify: Option<(&'m mut Materials, &'m mut DiscMap)>,
}

/// Stage Two's choice of the next disc and pose.
struct Aimer<'s> {
    selector: plan::PoseSelector<'s>,
    /// The mapped surface (Stage One's mesh) as a world to predict sweeps in.
    map_world: Arc<scene::World>,
    probe: MapProbe,
    /// `ln n_t`, the information of a voxel under the uniform prior.
    uniform: Real,
}

/// The map as the scanner would see it: a simulated sweep of the mapped
/// surface (Stage One's mesh) from a candidate pose, with the scanner's own
/// model and noise, predicts the observation the LRC will get; a pose
/// whose predicted observation fails the LRC's geometric checks (range,
/// incidence, returns and span in the fit window, flatness) is not a
/// viewpoint for that disc.
fn map_world(mesh: &TriMesh) -> Result<Arc<scene::World>, ExploreError> {
    Ok(Arc::new(scene::World::Mesh(scene::Scene::from_mesh(
        "map",
        mesh.clone(),
        vec![scene::Material::new("map", 0.5, 0.5)],
        scene::MaterialId(0),
    )?)))
}

impl<'s> Aimer<'s> {
    /// `safety` is the C-space model's (the selector keeps it).
    /// `map_world` is Stage One's mesh as a world ([`map_world`]).
    fn new<H: Arm + LineScanner + ?Sized>(
        episode: &Episode<'_, H>,
        map_world: Arc<scene::World>,
        safety: &'s Safety,
    ) -> Result<Self, ExploreError> {
        let s = &episode.setup;
        let selector = plan::PoseSelector::new(safety, s.config.pose.clone())?;
        let probe = MapProbe::new(
            s.robot.clone(),
            Arc::clone(&map_world),
            s.world_from_base,
            &episode.q,
            Scanner::new(s.scanner)?,
        )?;
        Ok(Self {
            selector,
            map_world,
            probe,
            uniform: (s.materials.len() as Real).ln(),
        })
    }

    /// A safe path from where the arm stands to `goal` (the roadmap's, or
    /// through a pose of `visited`, checked by `checker`) whose motions and
    /// the sweep at its end keep the robot `stage_two_clearance_m` from the
    /// mapped surface; `None` when there is none.
    fn reach<H: Arm + LineScanner + ?Sized>(
        &self,
        episode: &Episode<'_, H>,
        visited: &[&[Real]],
        goal: &[Real],
        checker: &mut dyn plan::MotionChecker,
    ) -> Result<Option<plan::Path>, ExploreError> {
        let s = &episode.setup;
        let stage = &s.stage;
        let Some(path) = path_via_visited(
            stage.model().roadmap(),
            visited,
            &episode.q,
            goal,
            s.config.link_k,
            checker,
        ) else {
            return Ok(None);
        };
        let clear = clear_of_map(
            &s.robot,
            &s.world_from_base,
            &self.map_world,
            &episode.fine,
            &path.waypoints,
            stage.sweep_range(goal),
            s.config.stage_two_clearance_m,
        )?;
        Ok(clear.then_some(path))
    }

    /// The discs worth targeting, most `H3` first (ties to the lower
    /// index): not yet tried, flat within the LRC's patch, in A2, with more
    /// than `significant_h3` of their uniform-prior information left.
    fn ranked<H: Arm + LineScanner + ?Sized>(
        &self,
        episode: &Episode<'_, H>,
        m: &Materials,
        discs: &DiscMap,
        tried: &[bool],
    ) -> Vec<(usize, Real)> {
        use rayon::prelude::*;
        let a2 = episode.setup.regions.a2;
        let significant = episode.setup.config.significant_h3 * self.uniform;
        let mut ranked: Vec<(usize, Real)> = (0..discs.discs.len())
            .into_par_iter()
            .filter(|&i| !tried[i] && m.flat[i] && a2.contains(&discs.discs[i].centre))
            .map(|i| (i, m.h3(i)))
            .filter(|(i, h)| *h > significant * m.disc_voxels(*i).len() as Real)
            .collect();
        ranked.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        ranked
    }

    /// The disc to aim at next, the path to its pose and how many discs
    /// were ranked; `None` when no disc can be targeted. Every disc tried
    /// is marked in `tried` for good.
    fn choose<H: Arm + LineScanner + ?Sized>(
        &mut self,
        episode: &Episode<'_, H>,
        m: &Materials,
        discs: &DiscMap,
        tried: &mut [bool],
        k: usize,
    ) -> Result<Option<(usize, plan::Path, usize)>, ExploreError> {
        let s = &episode.setup;
        let config = &s.config;
        let stage = &s.stage;
        let ranked = self.ranked(episode, m, discs, tried);
        // One map for the whole decision: every motion checked while
        // trying one disc is known when trying the next.
        let mut checker = plan::MemoChecker::new(stage.model().safety().checker(stage.grid()));
        let q = &episode.q;
        for &(i, _) in ranked.iter().take(config.stage_two_target_attempts) {
            tried[i] = true;
            let target = plan::Target::from_disc(&discs.discs[i]);
            let solution = self.selector.select(stage.grid(), &target, q)?;
            if !solution.valid() {
                continue;
            }
            let goal = solution.joints().to_vec();
            if stage.sweep_dist(&goal)?.is_none() {
                continue;
            }
            self.probe.move_to(&goal)?;
            self.probe
                .seed_noise(viewpoint_seed(episode.options.seed, k) ^ i as u64);
            let predicted = tilt_sweep(
                &mut self.probe,
                &s.robot,
                &s.world_from_base,
                &config.sweep,
                &mut |_, _| {},
            )?;
            let check = m.lrc.check_geometry(
                &PatchIndex::new(predicted.points()).observation(
                    &discs.discs[i].centre,
                    m.patch_m,
                    None,
                ),
                &m.lrc.config,
            );
            if check.is_err() {
                continue;
            }
            let visited: Vec<&[Real]> = episode
                .viewpoints
                .iter()
                .map(|r| r.joints.as_slice())
                .collect();
            if let Some(path) = self.reach(episode, &visited, &goal, &mut checker)? {
                return Ok(Some((i, path, ranked.len())));
            }
        }
        Ok(None)
    }
}
/// Seconds of robot time a sweep through `tilts` of joint `j` from `q`
/// takes on `timing` (out to the first tilt, across, back), moving as
/// `motion` says: stop and go, a motion, its settling and a scan per tilt;
/// continuous, one motion across at the tilt step per scan
/// ([`sweep_limits`]).
pub(crate) fn sweep_seconds(
    timing: &RobotTiming,
    motion: crate::Motion,
    q: &[Real],
    j: usize,
    tilts: &[Real],
) -> Real {
    let at = |t: Real| {
        let mut c = q.to_vec();
        if let Some(v) = c.get_mut(j) {
            *v = t;
        }
        c
    };
    let (Some(&lo), Some(&hi)) = (tilts.first(), tilts.last()) else {
        return 0.0;
    };
    let ends = timing.motion_s(q, &at(lo)) + timing.motion_s(&at(hi), q);
    match motion {
        crate::Motion::Continuous if tilts.len() > 1 => {
            let limits = sweep_limits(timing, lo, hi, tilts.len());
            ends + limits.duration_s(&at(lo), &at(hi)) + timing.settle_s + timing.scan_time_s
        }
        _ => {
            let steps: Real = tilts
                .windows(2)
                .map(|w| timing.motion_s(&at(w[0]), &at(w[1])))
                .sum();
            ends + steps + tilts.len() as Real * timing.scan_time_s
        }
    }
}

/// Seconds of robot time the straight transit `from` → `to` takes on
/// `timing` when it scans every `step` radians of its largest joint (0:
/// one motion, no scans), moving as `motion` says: stop and go, a motion,
/// its settling and a scan per step; continuous, one motion at most `step`
/// per scan.
pub(crate) fn transit_seconds(
    timing: &RobotTiming,
    motion: crate::Motion,
    step: Real,
    from: &[Real],
    to: &[Real],
) -> Real {
    let span = from
        .iter()
        .zip(to)
        .map(|(a, b)| (b - a).abs())
        .fold(0.0, Real::max);
    if step <= 0.0 || span <= 0.0 {
        return timing.motion_s(from, to);
    }
    match motion {
        crate::Motion::Continuous => per_scan(timing, step).duration_s(from, to) + timing.settle_s,
        crate::Motion::StopAndGo => {
            let n = (span / step).ceil().max(1.0);
            let first: Vec<Real> = from.iter().zip(to).map(|(a, b)| a + (b - a) / n).collect();
            n * (timing.motion_s(from, &first) + timing.scan_time_s)
        }
    }
}

/// The joint limits of a continuous sweep from tilt `lo` to `hi` over `n`
/// tilt values: the tilt moves one step per scan.
pub(crate) fn sweep_limits(timing: &RobotTiming, lo: Real, hi: Real, n: usize) -> MotionLimits {
    per_scan(timing, (hi - lo).abs() / (n.max(2) - 1) as Real)
}

/// `timing`'s joint limits, no joint faster than `step` radians a scan.
fn per_scan(timing: &RobotTiming, step: Real) -> MotionLimits {
    timing.limits.capped(if timing.scan_time_s > 0.0 {
        step / timing.scan_time_s
    } else {
        Real::INFINITY
    })
}

/// A Stage Two candidate: the disc aimed at, the LM pose, and the discs its
/// predicted sweep gives a usable observation of (the target among them),
/// with the `H3` they hold per second of the robot's time to get there and
/// sweep.
struct Aimed {
    target: usize,
    goal: Vec<Real>,
    usable: Vec<usize>,
    gain: Real,
}

impl Aimer<'_> {
    /// [`StageTwoChoice::Information`]: LM poses for up to
    /// `stage_two_candidates` discs among the first
    /// `stage_two_target_attempts` of the ranking (most `H3` first, each at
    /// least `stage_two_spread_m` from the others aimed at), each kept when
    /// its sweep is safe and its predicted sweep on the map gives a usable
    /// observation of its target; the one whose predicted sweep observes the
    /// most `H3` over every disc it sees per second of the robot's time (the
    /// straight way there and the sweep) that a safe path reaches is chosen.
    /// When no pose aimed at is reachable, the same with the next
    /// `stage_two_target_attempts` discs of the ranking, up to
    /// `stage_two_target_windows` times. Returns the target, the path, the
    /// discs ranked and the discs the chosen sweep is predicted to observe.
    /// Every disc aimed at is marked in `tried` for good.
    fn choose_information<H: Arm + LineScanner + ?Sized>(
        &mut self,
        episode: &Episode<'_, H>,
        m: &Materials,
        discs: &DiscMap,
        tried: &mut [bool],
        k: usize,
    ) -> Result<Option<StageTwoChoiceMade>, ExploreError> {
        let s = &episode.setup;
        let config = &s.config;
        let stage = &s.stage;
        // The discs still worth an observation, most `H3` first.
        let ranked = self.ranked(episode, m, discs, tried);
        let open: Vec<usize> = ranked.iter().map(|&(i, _)| i).collect();
        let h3: std::collections::HashMap<usize, Real> = ranked.iter().copied().collect();
        let q = &episode.q;
        // The path keeps `stage_two_clearance_m` from the measured points
        // (as Stage One's paths do: the noisy points can lie nearer than the
        // TSDF mesh they were fused into); the mapped surface's clearance is
        // checked after.
        let mut checker = plan::MemoChecker::new(ClearanceChecker::new(
            stage.model().safety().checker(stage.grid()),
            stage.model().safety(),
            &episode.points,
            config.stage_two_clearance_m,
            q,
        ));
        let visited: Vec<&[Real]> = episode
            .viewpoints
            .iter()
            .map(|r| r.joints.as_slice())
            .collect();
        // The ranking in windows of `stage_two_target_attempts` discs: the
        // next window only when no pose aimed in this one is reachable.
        let window = config.stage_two_target_attempts.max(1);
        let spread2 = config.stage_two_spread_m * config.stage_two_spread_m;
        for from in (0..ranked.len())
            .step_by(window)
            .take(config.stage_two_target_windows)
        {
            let next = &ranked[from..(from + window).min(ranked.len())];
            // The targets: spread over the surfaces, each tried once.
            let mut targets: Vec<usize> = Vec::new();
            for &(i, _) in next {
                if targets.len() >= config.stage_two_candidates {
                    break;
                }
                let c = discs.discs[i].centre;
                if targets
                    .iter()
                    .any(|&t| (discs.discs[t].centre - c).norm_squared() < spread2)
                {
                    continue;
                }
                tried[i] = true;
                targets.push(i);
            }
            for a in self.aim(episode, m, discs, &targets, (&open, &h3), k)? {
                if let Some(path) = self.reach(episode, &visited, &a.goal, &mut checker)? {
                    return Ok(Some((a.target, path, ranked.len(), a.usable)));
                }
            }
        }
        Ok(None)
    }

    /// LM poses for `targets` from where the arm stands, each kept when its
    /// sweep is safe and its sweep predicted on the map gives a usable
    /// observation of its target, most `H3` (of `h3`, over the discs of
    /// `open` it observes) per second of the robot's time first.
    fn aim<H: Arm + LineScanner + ?Sized>(
        &self,
        episode: &Episode<'_, H>,
        m: &Materials,
        discs: &DiscMap,
        targets: &[usize],
        (open, h3): (&[usize], &std::collections::HashMap<usize, Real>),
        k: usize,
    ) -> Result<Vec<Aimed>, ExploreError> {
        use rayon::prelude::*;
        let s = &episode.setup;
        let config = &s.config;
        let stage = &s.stage;
        let q = &episode.q;
        let selector = &self.selector;
        let world = &self.map_world;
        let mut aimed: Vec<Aimed> = targets
            .par_iter()
            .map(|&i| -> Result<Option<Aimed>, ExploreError> {
                let target = plan::Target::from_disc(&discs.discs[i]);
                let solution = selector.select(stage.grid(), &target, q)?;
                if !solution.valid() {
                    return Ok(None);
                }
                let goal = solution.joints().to_vec();
                if stage.sweep_dist(&goal)?.is_none() {
                    return Ok(None);
                }
                let mut probe = MapProbe::new(
                    s.robot.clone(),
                    Arc::clone(world),
                    s.world_from_base,
                    &goal,
                    Scanner::new(s.scanner)?,
                )?;
                probe.seed_noise(viewpoint_seed(episode.options.seed, k) ^ i as u64);
                let predicted = tilt_sweep(
                    &mut probe,
                    &s.robot,
                    &s.world_from_base,
                    &config.sweep,
                    &mut |_, _| {},
                )?;
                let Some(usable) = m.usable(discs, predicted.points(), open, i) else {
                    return Ok(None);
                };
                if !usable.contains(&i) {
                    return Ok(None);
                }
                let h3_seen: Real = usable.iter().map(|j| h3[j]).sum();
                // Per second of the robot's time (its clock): the straight
                // way there (scanning as Stage Two's transits do) and the
                // sweep.
                let timing = &s.timing;
                let tilts = stage.sweep_tilts(&goal);
                let step = config.stage_two_scan_step_deg.to_radians();
                let seconds = transit_seconds(timing, config.motion, step, q, &goal)
                    + sweep_seconds(timing, config.motion, &goal, stage.tilt_joint(), &tilts);
                Ok(Some(Aimed {
                    target: i,
                    goal,
                    usable,
                    gain: h3_seen / seconds.max(timing.scan_time_s).max(1e-3),
                }))
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
        aimed.sort_by(|a, b| b.gain.total_cmp(&a.gain).then(a.target.cmp(&b.target)));
        Ok(aimed)
    }
}

/// What a Stage Two decision chose: the target disc, the path to its pose,
/// the discs ranked, and the discs its sweep is predicted to observe.
type StageTwoChoiceMade = (usize, plan::Path, usize, Vec<usize>);

/// Whether the robot's collision capsules stay `clearance_m` or more from
/// `map` (the mapped surface) at every configuration checked along
/// `waypoints` and through the tilt sweep `(lo, hi)` at its end.
fn clear_of_map(
    robot: &Robot,
    world_from_base: &Isometry3,
    map: &scene::World,
    safety: &Safety,
    waypoints: &[Vec<Real>],
    (lo, hi): (Vec<Real>, Vec<Real>),
    clearance_m: Real,
) -> Result<bool, ExploreError> {
    let (Some(map), true) = (map.as_scene(), clearance_m > 0.0) else {
        return Ok(true);
    };
    let Some(goal) = waypoints.last() else {
        return Ok(true);
    };
    let sweep = [goal.clone(), lo, hi];
    for pair in waypoints.windows(2).chain(sweep.windows(2)) {
        for c in safety.interpolate(&pair[0], &pair[1]) {
            let frames = robot.forward_kinematics(&c)?;
            if plan::contact::min_clearance(robot, &frames, world_from_base, map, clearance_m)
                < clearance_m
            {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sweep of three tilts 0.5 rad apart on joints of 1 rad/s and
    /// 2 rad/s², by hand. Stop and go: each 0.5 rad motion is a triangle
    /// of 1 s plus 0.05 s to settle; four of them (out, two steps, back)
    /// and three scans of 0.1 s: 4.5 s. Continuous: out and back as
    /// before (2.1 s), across 1 rad on one trapezoid of 1.5 s (the tilt
    /// step per scan, 5 rad/s, caps nothing), settling and the last scan:
    /// 3.75 s.
    #[test]
    fn sweep_seconds_by_hand() {
        let timing = RobotTiming {
            limits: MotionLimits::uniform(2, 1.0, 2.0),
            settle_s: 0.05,
            scan_time_s: 0.1,
            reading_period_s: 0.01,
        };
        let tilts = [-0.5, 0.0, 0.5];
        let q = [0.3, 0.0];
        let s = sweep_seconds(&timing, crate::Motion::StopAndGo, &q, 1, &tilts);
        assert!((s - 4.5).abs() < 1e-12, "{s}");
        let c = sweep_seconds(&timing, crate::Motion::Continuous, &q, 1, &tilts);
        assert!((c - 3.75).abs() < 1e-12, "{c}");
        // A finer sweep is capped by its step: 0.01 rad a scan is 0.1 rad/s.
        let fine: Vec<Real> = (0..=100).map(|k| -0.5 + 0.01 * k as Real).collect();
        let l = sweep_limits(&timing, -0.5, 0.5, fine.len());
        assert!((l.velocity[1] - 0.1).abs() < 1e-12);
        assert_eq!(
            sweep_seconds(&timing, crate::Motion::Continuous, &q, 1, &[]),
            0.0
        );
    }

    /// A scanning transit's seconds by hand (1 rad/s, 2 rad/s²: a move of
    /// `d` takes `d + 0.5` s from 0.5 rad on, `2√(d/2)` below).
    #[test]
    fn transit_seconds_by_hand() {
        let timing = RobotTiming {
            limits: MotionLimits::uniform(2, 1.0, 2.0),
            settle_s: 0.05,
            scan_time_s: 0.1,
            reading_period_s: 0.01,
        };
        let (a, b) = ([0.0, 0.0], [1.0, 0.2]);
        let t = |motion, step| transit_seconds(&timing, motion, step, &a, &b);
        // No scans: one trapezoid and its settling, 1.5 + 0.05 s.
        assert!((t(crate::Motion::StopAndGo, 0.0) - 1.55).abs() < 1e-12);
        // Stop and go every 0.25 rad: 4 × (2√0.125 + 0.05 + 0.1) s.
        let by_hand = 4.0 * (2.0 * 0.125_f64.sqrt() + 0.15);
        assert!((t(crate::Motion::StopAndGo, 0.25) - by_hand).abs() < 1e-9);
        // Continuous at 0.25 rad a scan: the joints' own 1 rad/s binds.
        assert!((t(crate::Motion::Continuous, 0.25) - 1.55).abs() < 1e-12);
        // At 0.05 rad a scan, 0.5 rad/s: 1/0.5 + 0.5/2 + 0.05 s.
        assert!((t(crate::Motion::Continuous, 0.05) - 2.3).abs() < 1e-12);
        assert_eq!(
            transit_seconds(&timing, crate::Motion::Continuous, 0.1, &a, &a),
            0.0
        );
    }
}
