//! The coverage oracle: what Stage One's viewpoint choice could cover if it
//! knew the true scene. From the start pose and the C-space model's roadmap
//! nodes (the pool Stage One chooses from, less its local candidates), each
//! next tilt sweep is the one whose simulated points cover the most A1
//! samples not yet covered (SPEC §6's samples and 10 mm rule, the scanner's
//! noise, seeded by the pose's index as a run's is by the viewpoint).
//!
//! A pose is in the pool when it and every configuration of its sweep obey
//! a safety rule against the true scene:
//! - [`OracleRule::Run`], the run's: `dist(Q) > 1` (eq. 3.5) against the
//!   planning voxels a true surface passes through, every other voxel free
//!   (the planner with a perfect map), and the links' capsules at least
//!   Stage One's clearance (`stage_one_clearance_m`) from the true surface;
//! - [`OracleRule::Contact`]: the links' collision shapes touch no true
//!   surface.
//!
//! [`run_oracle`] is what `surveyor explore` puts in `run.json`
//! (`coverage.oracle`), cached in a file like the C-space model;
//! `cargo run --release -p sim --example coverage_oracle` prints both rules
//! and how much a denser pool adds.

use crate::SimError;
use crate::metrics::CoverageTracker;
use explore::Setup;
use geom::{Isometry3, Real};
use map::VoxelKey;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use record::explore::CoverageOracle;
use robot::Robot;
use scenario::{LoadedScenario, MetricsConfig};
use scene::World;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::Path;
use std::sync::Arc;

/// Tilt step at which a sweep's configurations are checked, degrees.
const CHECK_TILT_DEG: Real = 2.0;

/// Density of the true-surface points that mark planning voxels occupied.
const VOXEL_MARK_PER_M2: Real = 10_000.0;

/// Most sweeps the oracle's greedy choice takes (it stops sooner when no
/// sweep adds a sample).
pub const ORACLE_MAX_SWEEPS: usize = 40;

/// Format of the cache file; a file of another format is made again.
const CACHE_FORMAT: u32 = 1;

/// The safety rule a pose of the pool obeys.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OracleRule {
    /// The run's: `dist(Q) > 1` with a perfect map and Stage One's
    /// clearance from the true surface.
    Run,
    /// No contact of the links with the true surface.
    Contact,
}

impl OracleRule {
    /// Its name in `run.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Run => "dist(Q) > 1 on the true scene's voxels and Stage One's clearance",
            Self::Contact => "no contact",
        }
    }
}

/// Every pose of the pool with what its sweep covers.
#[derive(Debug)]
pub struct OraclePool {
    samples: usize,
    poses: usize,
    /// Per pose: clear by the run's rule, by the contact rule, and the bits
    /// of the A1 samples its sweep covers (in the tracker's storage order,
    /// [`CoverageTracker::stored_bits_of`]: only counted and united).
    per_pose: Vec<(bool, bool, Vec<u64>)>,
}

/// The run's safety rule against the true scene ([`OracleRule::Run`] with a
/// clearance of the caller's): the planning voxels a true surface passes
/// through (in A3) stand for a perfect map, against which a configuration
/// needs `dist(Q) > 1`, and the links' capsules keep the clearance from the
/// true surface. The coverage oracle holds Stage One's clearance, the
/// material oracle Stage Two's.
pub(crate) struct TruthRule<'a> {
    pub(crate) setup: &'a Setup,
    pub(crate) scene: &'a scene::Scene,
    occupied: HashSet<VoxelKey>,
}

impl<'a> TruthRule<'a> {
    /// The rule of `setup` in `world` (a scene: the rule needs true
    /// surfaces); `metrics` gives the sampling that marks the voxels (its
    /// seed; the region and density are the rule's). `what` names the
    /// caller in an error.
    pub(crate) fn new(
        setup: &'a Setup,
        world: &'a World,
        metrics: &MetricsConfig,
        what: &str,
    ) -> Result<Self, SimError> {
        let scene = world.as_scene().ok_or_else(|| SimError::InvalidArgument {
            what: what.into(),
            message: "needs a scene with true surfaces, not a point cloud".into(),
        })?;
        let voxel = setup.config.planning_voxel_m;
        let mut marks = metrics.sampling;
        marks.region = Some(setup.regions.a3.aabb());
        marks.samples_per_m2 = VOXEL_MARK_PER_M2;
        marks.exposed_only = false;
        let occupied: HashSet<VoxelKey> = scene::SurfaceSampler::new(scene, &marks)?
            .flatten()
            .filter_map(|s| VoxelKey::of_point(&s.point, voxel))
            .collect();
        Ok(Self {
            setup,
            scene,
            occupied,
        })
    }

    /// Whether configuration `c` (its link frames `frames`) has `dist(Q) >
    /// 1` against the marked voxels and its links' capsules at least
    /// `clearance_m` from the true surface (0: no clearance asked).
    pub(crate) fn clear_at(
        &self,
        c: &[Real],
        frames: &[Isometry3],
        clearance_m: Real,
    ) -> Result<bool, SimError> {
        let setup = self.setup;
        let safety = setup.stage.model().safety();
        Ok(
            plan::interfering_voxels(safety, c, setup.config.planning_voxel_m)
                .map_err(|e| SimError::Plan(Box::new(e)))?
                .iter()
                .all(|k| !self.occupied.contains(k))
                && (clearance_m <= 0.0
                    || plan::contact::min_clearance(
                        &setup.robot,
                        frames,
                        &setup.world_from_base,
                        self.scene,
                        clearance_m,
                    ) >= clearance_m),
        )
    }

    /// Whether `q` and every configuration of its tilt sweep
    /// ([`sweep_configurations`]) is clear ([`Self::clear_at`]).
    pub(crate) fn sweep_clear(&self, q: &[Real], clearance_m: Real) -> Result<bool, SimError> {
        for c in &sweep_configurations(self.setup, q) {
            let frames = self.setup.robot.forward_kinematics(c)?;
            if !self.clear_at(c, &frames, clearance_m)? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The perfect map: the planning grid of the setup with every marked
    /// voxel occupied and every other one free.
    pub(crate) fn perfect_map(&self) -> Result<map::OccupancyGrid, SimError> {
        let config = *self.setup.stage.grid().config();
        Ok(map::OccupancyGrid::from_states(config, |_, key| {
            if self.occupied.contains(&key) {
                map::VoxelState::Occupied
            } else {
                map::VoxelState::Free
            }
        })?)
    }
}

/// What a pose is checked and scored with: the A1 samples, the run's rule
/// against the true scene, and the scanner.
struct PoseJudge<'a> {
    rule: TruthRule<'a>,
    world: &'a Arc<World>,
    scanner: &'a sensor::ScannerConfig,
    tracker: CoverageTracker,
}

impl<'a> PoseJudge<'a> {
    fn new(
        setup: &'a Setup,
        world: &'a Arc<World>,
        scanner: &'a sensor::ScannerConfig,
        metrics: &MetricsConfig,
    ) -> Result<Self, SimError> {
        let rule = TruthRule::new(setup, world, metrics, "coverage oracle")?;
        let mut a1 = *metrics;
        a1.sampling.region = Some(setup.regions.a1.aabb());
        let tracker = CoverageTracker::new(rule.scene, &a1)?;
        Ok(Self {
            rule,
            world,
            scanner,
            tracker,
        })
    }

    /// Pose `i` (`q`): clear by the run's rule, by the contact rule, and the
    /// A1 samples its sweep (noise seeded by `noise_seed`) covers (empty
    /// when neither rule clears it, except for the start, `i == 0`, whose
    /// sweep a run always takes).
    fn judge(
        &self,
        i: usize,
        q: &[Real],
        noise_seed: u64,
    ) -> Result<(bool, bool, Vec<u64>), SimError> {
        let setup = self.rule.setup;
        let robot = &setup.robot;
        let world_from_base = setup.world_from_base;
        let clearance_m = setup.config.stage_one_clearance_m;
        let mut contact = true;
        let mut run = true;
        for c in &sweep_configurations(setup, q) {
            let frames = robot.forward_kinematics(c)?;
            contact &=
                plan::contact::robot_contacts(robot, &frames, &world_from_base, self.rule.scene)
                    .is_empty();
            if run {
                run = self.rule.clear_at(c, &frames, clearance_m)?;
            }
        }
        let bits = if i == 0 || contact || run {
            let sweep = simulated_sweep(setup, self.world, self.scanner, q, noise_seed)?;
            self.tracker.stored_bits_of(&sweep.positions())
        } else {
            Vec::new()
        };
        Ok((run, contact, bits))
    }
}

/// `n` configurations drawn uniformly within `robot`'s joint limits
/// (0 for an unlimited joint), seeded.
fn uniform_poses(robot: &Robot, n: usize, seed: u64) -> Vec<Vec<Real>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            robot
                .limits()
                .iter()
                .map(|l| l.map_or(0.0, |l| rng.random_range(l.min..=l.max)))
                .collect()
        })
        .collect()
}

impl OraclePool {
    /// The pool of `setup` in `world` (a scene: the oracle needs true
    /// surfaces) with the scanner `scanner` and the metric `metrics`:
    /// the start, the roadmap's nodes and `extra` poses drawn uniformly
    /// within the joint limits (seeded).
    pub fn new(
        setup: &Setup,
        world: &Arc<World>,
        scanner: &sensor::ScannerConfig,
        metrics: &MetricsConfig,
        extra: usize,
    ) -> Result<Self, SimError> {
        let judge = PoseJudge::new(setup, world, scanner, metrics)?;
        let mut poses: Vec<Vec<Real>> = vec![setup.start.clone()];
        poses.extend(setup.stage.model().roadmap().nodes().map(<[Real]>::to_vec));
        poses.extend(uniform_poses(&setup.robot, extra, 0));
        let per_pose = poses
            .par_iter()
            .enumerate()
            .map(|(i, q)| judge.judge(i, q, i as u64))
            .collect::<Result<_, _>>()?;
        Ok(Self {
            samples: judge.tracker.len(),
            poses: poses.len(),
            per_pose,
        })
    }

    /// A1 samples.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Poses in the pool.
    pub fn poses(&self) -> usize {
        self.poses
    }

    /// The poses clear under `rule` (the start counted when it is).
    pub fn clear(&self, rule: OracleRule) -> Vec<usize> {
        (0..self.per_pose.len())
            .filter(|&i| match rule {
                OracleRule::Run => self.per_pose[i].0,
                OracleRule::Contact => self.per_pose[i].1,
            })
            .collect()
    }

    fn share(&self, bits: &[u64]) -> Real {
        count(bits) as Real / self.samples.max(1) as Real
    }

    /// The share of A1 covered by the start's sweep and every clear pose's.
    pub fn all(&self, rule: OracleRule) -> Real {
        let mut all = self.per_pose[0].2.clone();
        for i in self.clear(rule) {
            or_into(&mut all, &self.per_pose[i].2);
        }
        self.share(&all)
    }

    /// The greedy choice: the start's sweep, then up to `sweeps - 1` more,
    /// each the clear pose that adds the most samples (ties to the lower
    /// index), stopping when none adds one. Returns the share covered after
    /// each sweep and the samples covered at the end.
    pub fn greedy(&self, rule: OracleRule, sweeps: usize) -> (Vec<Real>, Vec<u64>) {
        let clear = self.clear(rule);
        let mut have = self.per_pose[0].2.clone();
        let mut curve = vec![self.share(&have)];
        for _ in 1..sweeps {
            let Some((best, g)) = clear
                .par_iter()
                .map(|&i| (i, gain(&self.per_pose[i].2, &have)))
                .max_by_key(|&(i, g)| (g, std::cmp::Reverse(i)))
            else {
                break;
            };
            if g == 0 {
                break;
            }
            or_into(&mut have, &self.per_pose[best].2);
            curve.push(self.share(&have));
        }
        (curve, have)
    }

    /// No start sweep and `sweeps - 1` poses cover more than this share:
    /// the greedy set's samples plus the `sweeps - 1` largest gains over it
    /// (coverage is submodular), and no more than all the poses together.
    pub fn bound(&self, rule: OracleRule, sweeps: usize, greedy: &[u64]) -> Real {
        let mut gains: Vec<usize> = self
            .clear(rule)
            .iter()
            .map(|&i| gain(&self.per_pose[i].2, greedy))
            .collect();
        gains.sort_unstable_by(|a, b| b.cmp(a));
        let extra: usize = gains.iter().take(sweeps.saturating_sub(1)).sum();
        ((count(greedy) + extra) as Real / self.samples.max(1) as Real).min(self.all(rule))
    }

    /// The oracle under `rule` as `run.json` gives it.
    pub fn oracle(&self, rule: OracleRule) -> CoverageOracle {
        CoverageOracle {
            rule: rule.name().to_owned(),
            poses: self.poses,
            clear_poses: self.clear(rule).len(),
            a1_after_sweeps: self.greedy(rule, ORACLE_MAX_SWEEPS).0,
            a1_all_poses: self.all(rule),
        }
    }
}

/// Most candidates [`candidate_coverage`] draws (the planner's own ceiling
/// on `plan.n_q`).
pub const MAX_CANDIDATES: usize = 20_000;

/// Candidates judged at a time by [`candidate_coverage`] (their sample bits
/// are dropped once united).
const CANDIDATE_CHUNK: usize = 64;

/// One point of Paul's Fig. 3.2: what the sweeps of `n_q` candidate poses
/// together cover.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CandidateCoverage {
    /// Candidates drawn.
    pub n_q: usize,
    /// Of them, clear by the run's rule ([`OracleRule::Run`]).
    pub clear_run: usize,
    /// A1 share covered by the start's sweep and every run-clear
    /// candidate's.
    pub coverage_run: Real,
    /// Of them, clear by the contact rule ([`OracleRule::Contact`]).
    pub clear_contact: usize,
    /// A1 share covered by the start's sweep and every contact-clear
    /// candidate's.
    pub coverage_contact: Real,
}

/// Paul's Fig. 3.2 (§3.2.3) in simulation: the A1 coverage (SPEC §6) of the
/// combined sweeps of `n_Q` contending viewpoints drawn uniformly in C-space,
/// for each `n_Q` of `sizes`. Candidates are drawn uniformly within the
/// joint limits (seeded by `seed`), each judged as the oracle's pool is (the
/// sweep from it clear by a rule), its sweep's noise seeded as a run of seed
/// `seed` seeds viewpoint `k` (the start is 0, candidate `i` is `i`). The
/// first `n_Q` of the draw are a uniform sample of `n_Q`, so one draw of the
/// largest size answers every size. The start pose's
/// sweep is always counted (a run's map holds it before Stage One chooses),
/// so `n_Q = 0` is the start's coverage alone. One row per size, ascending.
pub fn candidate_coverage(
    setup: &Setup,
    world: &Arc<World>,
    scanner: &sensor::ScannerConfig,
    metrics: &MetricsConfig,
    sizes: &[usize],
    seed: u64,
) -> Result<Vec<CandidateCoverage>, SimError> {
    let mut sizes = sizes.to_vec();
    sizes.sort_unstable();
    sizes.dedup();
    let n = sizes.last().copied().unwrap_or(0);
    if n > MAX_CANDIDATES {
        return Err(SimError::InvalidArgument {
            what: "candidate sizes".into(),
            message: format!("{n} candidates: expected at most {MAX_CANDIDATES}"),
        });
    }
    let judge = PoseJudge::new(setup, world, scanner, metrics)?;
    let share = |bits: &[u64]| count(bits) as Real / judge.tracker.len().max(1) as Real;
    let noise = |i: usize| explore::viewpoint_seed(seed, i);
    let start = judge.judge(0, &setup.start, noise(0))?.2;
    let (mut run, mut contact) = (start.clone(), start);
    let (mut clear_run, mut clear_contact) = (0, 0);
    let mut rows = Vec::with_capacity(sizes.len());
    let mut next = sizes.iter().copied().peekable();
    let mut record = |k: usize, run: &[u64], contact: &[u64], cr: usize, cc: usize| {
        while next.peek() == Some(&k) {
            next.next();
            rows.push(CandidateCoverage {
                n_q: k,
                clear_run: cr,
                coverage_run: share(run),
                clear_contact: cc,
                coverage_contact: share(contact),
            });
        }
    };
    record(0, &run, &contact, 0, 0);
    let poses = uniform_poses(&setup.robot, n, seed);
    for (c, chunk) in poses.chunks(CANDIDATE_CHUNK).enumerate() {
        let first = 1 + c * CANDIDATE_CHUNK;
        let judged = chunk
            .par_iter()
            .enumerate()
            .map(|(k, q)| judge.judge(first + k, q, noise(first + k)))
            .collect::<Result<Vec<_>, _>>()?;
        for (k, (is_run, is_contact, bits)) in judged.into_iter().enumerate() {
            if is_run {
                clear_run += 1;
                or_into(&mut run, &bits);
            }
            if is_contact {
                clear_contact += 1;
                or_into(&mut contact, &bits);
            }
            record(first + k, &run, &contact, clear_run, clear_contact);
        }
    }
    Ok(rows)
}

/// The cache file: the inputs the oracle was made for, and the oracle.
#[derive(Serialize, Deserialize)]
struct CacheFile {
    format: u32,
    inputs: String,
    oracle: CoverageOracle,
}

/// What the oracle depends on, as text: the scenario with what does not
/// matter to it left out (names, the `[explore]` table), and the
/// parameters of the run it does depend on (the roadmap's, the planning
/// voxel, Stage One's clearance, the sweep). A scene's mesh file
/// enters by its path, not its content.
fn oracle_inputs(loaded: &LoadedScenario, setup: &Setup) -> Result<String, SimError> {
    let mut s = loaded.standalone();
    s.name.clear();
    s.description.clear();
    s.initial_segments.clear();
    s.explore = None;
    let c = &setup.config;
    Ok(format!(
        "plan = {:?}\nplanning_voxel_m = {:?}\nstage_one_clearance_m = {:?}\nsweep = {:?}\n{}",
        c.plan,
        c.planning_voxel_m,
        c.stage_one_clearance_m,
        c.sweep,
        s.to_toml()?
    ))
}

/// The run's oracle ([`OracleRule::Run`]) of the scenario `loaded` set up
/// as `setup` in `world`: read from `cache` when that file was made for the
/// same inputs, else computed (and written there). The second value says
/// whether it was loaded.
pub fn run_oracle(
    loaded: &LoadedScenario,
    setup: &Setup,
    world: &Arc<World>,
    cache: Option<&Path>,
) -> Result<(CoverageOracle, bool), SimError> {
    let inputs = oracle_inputs(loaded, setup)?;
    if let Some(oracle) = cached_oracle(cache, &inputs) {
        return Ok((oracle, true));
    }
    Ok((compute_oracle(loaded, setup, world, cache, inputs)?, false))
}

/// The run's oracle of [`run_oracle`], computed beside the caller: read at
/// once when `cache` holds it, else computed on a thread of its own (with
/// a thread pool of its own, so the caller's parallel work does not queue
/// behind it) until [`OracleJob::finish`] waits for it. The same oracle as
/// [`run_oracle`]'s, whatever the caller does meanwhile.
#[derive(Debug)]
pub struct OracleJob(OracleState);

#[derive(Debug)]
enum OracleState {
    Ready(CoverageOracle),
    Running(std::thread::JoinHandle<Result<CoverageOracle, SimError>>),
}

impl OracleJob {
    /// Read the oracle of `loaded` set up as `setup` in `world` from
    /// `cache`, or start computing it (a copy of `setup` goes to the
    /// thread). Fails when the scenario cannot be described for the cache
    /// or the thread cannot start.
    pub fn start(
        loaded: &LoadedScenario,
        setup: &Setup,
        world: &Arc<World>,
        cache: Option<&Path>,
    ) -> Result<Self, SimError> {
        let inputs = oracle_inputs(loaded, setup)?;
        if let Some(oracle) = cached_oracle(cache, &inputs) {
            return Ok(Self(OracleState::Ready(oracle)));
        }
        let (loaded, setup, world) = (loaded.clone(), setup.clone(), Arc::clone(world));
        let cache = cache.map(Path::to_path_buf);
        let threads = rayon::current_num_threads();
        let thread_error = |e: std::io::Error| SimError::InvalidArgument {
            what: "coverage oracle".into(),
            message: format!("cannot start its thread: {e}"),
        };
        let handle = std::thread::Builder::new()
            .name("oracle".into())
            .spawn(move || {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .thread_name(|i| format!("oracle-{i}"))
                    .start_handler(|_| idle_priority())
                    .build()
                    .map_err(|e| SimError::InvalidArgument {
                        what: "coverage oracle".into(),
                        message: format!("cannot start its thread pool: {e}"),
                    })?;
                pool.install(|| compute_oracle(&loaded, &setup, &world, cache.as_deref(), inputs))
            })
            .map_err(thread_error)?;
        Ok(Self(OracleState::Running(handle)))
    }

    /// The oracle, once computed (and written to the cache).
    pub fn finish(self) -> Result<CoverageOracle, SimError> {
        match self.0 {
            OracleState::Ready(oracle) => Ok(oracle),
            // A panic in the oracle is a bug: it goes on as if the oracle
            // had run on this thread.
            OracleState::Running(handle) => handle
                .join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p)),
        }
    }
}

/// Let the calling thread run only on a core nothing else wants (Linux's
/// `SCHED_IDLE`): the oracle beside a run takes the cores the run leaves
/// idle and slows it as little as it can. Where the system refuses, the
/// thread keeps its priority (the oracle is the same either way).
pub(crate) fn idle_priority() {
    #[cfg(target_os = "linux")]
    {
        use thread_priority::unix::{
            NormalThreadSchedulePolicy, ThreadSchedulePolicy, set_thread_priority_and_policy,
            thread_native_id,
        };
        let _ = set_thread_priority_and_policy(
            thread_native_id(),
            thread_priority::ThreadPriority::Min,
            ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Idle),
        );
    }
}

/// The oracle in `cache` when that file holds one made for `inputs`.
fn cached_oracle(cache: Option<&Path>, inputs: &str) -> Option<CoverageOracle> {
    let text = std::fs::read(cache?).ok()?;
    let file = serde_json::from_slice::<CacheFile>(&text).ok()?;
    (file.format == CACHE_FORMAT && file.inputs == inputs).then_some(file.oracle)
}

/// The run's oracle computed, and written to `cache` (with its `inputs`).
fn compute_oracle(
    loaded: &LoadedScenario,
    setup: &Setup,
    world: &Arc<World>,
    cache: Option<&Path>,
    inputs: String,
) -> Result<CoverageOracle, SimError> {
    let scanner = loaded.scenario.scanner.clone().unwrap_or_default().config;
    let pool = OraclePool::new(setup, world, &scanner, &loaded.scenario.metrics, 0)?;
    let oracle = pool.oracle(OracleRule::Run);
    if let Some(path) = cache {
        let file = CacheFile {
            format: CACHE_FORMAT,
            inputs,
            oracle: oracle.clone(),
        };
        let text = serde_json::to_vec(&file).map_err(|e| SimError::InvalidArgument {
            what: path.display().to_string(),
            message: format!("cannot encode the oracle: {e}"),
        })?;
        record::output::replace_file(path, &text)?;
    }
    Ok(oracle)
}

/// The configurations of the tilt sweep from `q`: every `CHECK_TILT_DEG` of
/// the sweep joint's range, ends included, and `q` itself.
pub(crate) fn sweep_configurations(setup: &Setup, q: &[Real]) -> Vec<Vec<Real>> {
    let (lo, hi) = setup.stage.sweep_range(q);
    let j = setup.config.sweep.joint - 1;
    let steps = ((hi[j] - lo[j]) / CHECK_TILT_DEG.to_radians())
        .ceil()
        .max(1.0) as usize;
    let mut out = vec![q.to_vec()];
    for s in 0..=steps {
        let mut c = lo.clone();
        c[j] = lo[j] + (hi[j] - lo[j]) * s as Real / steps as Real;
        out.push(c);
    }
    out
}

/// The sweep from `q` of `setup`'s robot and sweep in `world` with the
/// scanner `scanner`, simulated with noise seeded by `seed`.
pub(crate) fn simulated_sweep(
    setup: &Setup,
    world: &Arc<World>,
    scanner: &sensor::ScannerConfig,
    q: &[Real],
    seed: u64,
) -> Result<sensor::Sweep, SimError> {
    let robot = &setup.robot;
    let mut rig = crate::SimRig::new(
        robot.clone(),
        Arc::clone(world),
        setup.world_from_base,
        q,
        Some(sensor::Scanner::new(*scanner)?),
        seed,
    )?;
    Ok(hw::tilt_sweep(
        &mut rig,
        robot,
        &setup.world_from_base,
        &setup.config.sweep,
        &mut |_, _| {},
    )?)
}

fn count(bits: &[u64]) -> usize {
    bits.iter().map(|w| w.count_ones() as usize).sum()
}

fn gain(bits: &[u64], have: &[u64]) -> usize {
    bits.iter()
        .zip(have)
        .map(|(a, b)| (a & !b).count_ones() as usize)
        .sum()
}

fn or_into(into: &mut [u64], bits: &[u64]) {
    for (a, b) in into.iter_mut().zip(bits) {
        *a |= b;
    }
}
