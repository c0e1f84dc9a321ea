//! A scenario's exploration on any hardware (the simulator's `SimRig`, a
//! ROS 2 robot, a user's driver): its setup from the scenario
//! ([`explore_setup`]), the loop of `explore` on the hardware, timed on the
//! robot clock and recorded in `run.mcap` ([`run_loop`]), and the run
//! folder with its blast plan (Paul App. A), written whole or not at all
//! ([`explore_with`]). [`HardwareExplore`] is the job on hardware nobody
//! judges; the simulator's job, with its ground-truth judge, is `sim`'s.

use super::{JobError, bag_event};
use crate::LoadedScenario;
use blast::{BlastConfig, BlastInputs, BlastPlan};
use explore::{ExploreConfig, ExploreRun, Judge, Setup, SetupInputs};
use geom::Real;
use hw::script::{Event, Tap};
use hw::{Arm, LineScanner};
use map::TsdfConfig;
use plan::contact::robot_contacts;
use record::CoverageReport;
use record::Staging;
use record::bag::RunBag;
use record::bag::msg::MarkerArray;
use record::explore::{
    CoverageOracle, ExploreCoverage, ExploreSummary, MaterialIdentification, OracleComparison,
};
use scene::World;
use sensor::Scanner;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct ExploreOptions {
    /// Seed of the scanner noise.
    pub seed: u64,
    /// Override of the Stage One viewpoint budget.
    pub max_viewpoints: Option<usize>,
    /// Where the C-space model is cached (`None`: built every run).
    pub cspace_cache: Option<PathBuf>,
    /// Where the trained LRC is cached (`None`: trained every run).
    pub lrc_cache: Option<PathBuf>,
    /// Stage One parameters instead of the scenario's `[explore]` table
    /// (`None`: the scenario's, or the defaults).
    pub config: Option<ExploreConfig>,
    /// TSDF of the output mesh.
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
    /// Whether the outcome holds the coverage oracle
    /// (`sim::oracle::run_oracle`; mesh worlds only; the simulator's alone), and its cache;
    /// with Stage Two in a scene with materials, the material oracle too
    /// (`sim::material_oracle`), cached beside it
    /// (`sim::material_oracle::cache_beside`).
    pub oracle: OracleOption,
}

/// Whether a run computes the coverage oracle.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum OracleOption {
    /// No oracle.
    #[default]
    Off,
    /// The oracle, cached in the file when one is given (else computed).
    On(Option<PathBuf>),
}

impl ExploreOptions {
    /// The default C-space cache of a scenario's robot: one file per robot
    /// (a URDF by its file name) in the system's temporary folder, so runs
    /// that alternate robots do not rebuild each other's model.
    pub fn default_cspace_cache(loaded: &LoadedScenario) -> Result<PathBuf, JobError> {
        let name = loaded.robot_choice()?.short_name();
        Ok(std::env::temp_dir().join(format!("surveyor-cspace-{name}.json")))
    }

    /// The default oracle cache of a scenario: one file per scenario name
    /// (a file's by its name) in the system's temporary folder; a file made
    /// for other inputs is made again.
    pub fn default_oracle_cache(loaded: &LoadedScenario) -> PathBuf {
        let stem: String = loaded
            .scenario
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        std::env::temp_dir().join(format!("surveyor-oracle-{stem}.json"))
    }

    /// The Stage One parameters of a choice rule: `"information"` (the
    /// scenario's own, `None`) or `"thesis"` (Paul's rank sum on the Pareto
    /// front, viewpoint scans only: [`explore::ExploreConfig::thesis_stage_one`]
    /// of the scenario's); `None` for another name.
    pub fn stage_one_config(loaded: &LoadedScenario, rule: &str) -> Option<Option<ExploreConfig>> {
        match rule {
            "information" => Some(None),
            "thesis" => Some(Some(
                loaded
                    .scenario
                    .explore
                    .clone()
                    .unwrap_or_default()
                    .thesis_stage_one(),
            )),
            _ => None,
        }
    }

    /// The default LRC cache of a run seed (the training's seed): one file
    /// per seed in the system's temporary folder, so runs that alternate
    /// seeds do not retrain each other's model.
    pub fn default_lrc_cache(seed: u64) -> PathBuf {
        std::env::temp_dir().join(format!("surveyor-lrc-seed{seed}.json"))
    }
}

/// What a scenario's exploration starts from, and its ground truth: the
/// scenario's robot, scanner, parameters (with `options`' overrides) and
/// regions, the scene's materials, the C-space model (built or loaded from
/// `options.cspace_cache`). The start pose must be within the joint limits
/// and clear of the scene (exploration assumes only that the start is
/// safe, A§6.1).
pub fn explore_setup(
    loaded: &LoadedScenario,
    options: &ExploreOptions,
) -> Result<(Setup, Arc<World>), JobError> {
    let s = &loaded.scenario;
    let scenario_error = |message: String| JobError::Scenario {
        source_name: s.name.clone(),
        message,
    };
    let robot = loaded.build_robot()?;
    let world = Arc::new(loaded.build_world()?);
    let world_from_base = s.world_from_base();
    let spec = s.scanner.clone().unwrap_or_default();
    let mut config = options
        .config
        .clone()
        .or_else(|| s.explore.clone())
        .unwrap_or_default();
    if let Some(n) = options.max_viewpoints {
        config.max_viewpoints = n;
    }
    let regions = s.regions.ok_or_else(|| {
        scenario_error("exploration needs regions of interest ([regions] a1, a2, a3)".into())
    })?;
    let start = s.robot.start_joints.clone();
    robot
        .check_within_limits(&start)
        .map_err(|e| scenario_error(format!("robot.start_joints: {e}")))?;
    if let Some(scene) = world.as_scene() {
        let frames = robot.forward_kinematics(&start)?;
        if let Some(c) = robot_contacts(&robot, &frames, &world_from_base, scene).first() {
            return Err(scenario_error(format!(
                "robot.start_joints: the start pose puts link {} ({}) into the scene (object {}); exploration starts from a safe pose",
                c.link.index(),
                robot.links[c.link.index()].name,
                scene.object(c.object).map_or("?", |o| o.name.as_str())
            )));
        }
    }
    let materials = world
        .as_scene()
        .map(|scene| scene.materials().to_vec())
        .unwrap_or_default();
    let timing = loaded.robot_timing(&robot)?;
    let setup = Setup::new(SetupInputs {
        timing,
        robot,
        world_from_base,
        scanner: spec.config,
        sweep: spec.sweep,
        config,
        regions,
        start,
        materials,
        cspace_cache: options.cspace_cache.clone(),
        lrc_cache: options.lrc_cache.clone(),
    })?;
    Ok((setup, world))
}

/// How the loop runs `loaded` under `options`.
pub fn run_options(
    loaded: &LoadedScenario,
    options: &ExploreOptions,
) -> Result<explore::RunOptions, JobError> {
    Ok(explore::RunOptions {
        seed: options.seed,
        tsdf: options.tsdf,
        timings: options.timings,
        checkpoint: options.checkpoint.clone(),
        resume: options.resume,
        stage_two: options.stage_two,
        identity: explore::RunIdentity {
            scenario: loaded.scenario.name.clone(),
            scenario_toml: loaded.standalone().to_toml()?,
        },
        clock: hw::clock::RobotClock::default(),
    })
}

/// The loop of `setup` on `hw`, timed by `loaded`'s robot clock figures
/// on `run_options.clock` and tapped into `bag`, under `judge`: the run
/// and its finished bag.
pub fn run_loop<H: Arm + LineScanner>(
    loaded: &LoadedScenario,
    setup: Setup,
    hw: H,
    judge: &mut dyn Judge,
    mut bag: RunBag,
    run_options: &explore::RunOptions,
    progress: &mut dyn FnMut(&record::ViewpointRecord),
) -> Result<(ExploreRun, Vec<u8>), JobError> {
    let robot = setup.robot.clone();
    let world_from_base = setup.world_from_base;
    let timing = loaded.robot_timing(&robot)?;
    // When each viewpoint's record came: its sweep cloud's stamp.
    let clock = run_options.clock.clone();
    let mut stamps = Vec::new();
    let mut progress = |v: &record::ViewpointRecord| {
        stamps.push(clock.now_ns());
        progress(v);
    };
    let timed = hw::clock::Timed::new(hw, timing, clock.clone());
    let mut tapped = Tap::with_sink(timed, |e: &Event| bag_event(&mut bag, &clock, e));
    let run = explore::run(setup, &mut tapped, judge, run_options, &mut progress)?;
    let end = clock.now_ns();
    let bag = finish_bag(bag, end, &run, &robot, &world_from_base, &stamps)?;
    Ok((run, bag))
}

/// A scenario's exploration on hardware the simulator does not own (a
/// ROS 2 robot): the setup from the scenario, the hardware at its start
/// pose, and no ground truth (no coverage, no contact or clearance tally,
/// no true materials; everything else as in the simulator).
pub struct HardwareExplore<H> {
    loaded: LoadedScenario,
    setup: Setup,
    hw: H,
    run_options: explore::RunOptions,
    judge: Box<dyn Judge>,
}

impl<H: std::fmt::Debug> std::fmt::Debug for HardwareExplore<H> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HardwareExplore")
            .field("setup", &self.setup)
            .field("hw", &self.hw)
            .finish_non_exhaustive()
    }
}

impl<H: Arm + LineScanner> HardwareExplore<H> {
    /// The exploration of `loaded` under `options` (seed, budget,
    /// parameters, cache; no oracle) on `hw`, which must stand at the
    /// scenario's start joints (within `start_tolerance` radians) and scan
    /// with the scenario's scanner's bearings.
    pub fn new(
        loaded: &LoadedScenario,
        options: &ExploreOptions,
        hw: H,
        start_tolerance: Real,
    ) -> Result<Self, JobError> {
        let (setup, _) = explore_setup(loaded, options)?;
        let hardware = |message: String| JobError::InvalidArgument {
            what: "the robot".into(),
            message,
        };
        super::check_stands_at(&hw.joints(), &setup.start, start_tolerance).map_err(hardware)?;
        let bearings = Scanner::new(setup.scanner)?.bearings_rad().to_vec();
        if hw.bearings_rad() != bearings.as_slice() {
            return Err(hardware(format!(
                "its scanner has {} bearings, not the scenario scanner's {}",
                hw.bearings_rad().len(),
                bearings.len()
            )));
        }
        let run_options = run_options(loaded, options)?;
        Ok(Self {
            loaded: loaded.clone(),
            setup,
            hw,
            run_options,
            judge: Box::new(explore::NoJudge),
        })
    }

    /// Let `judge` see every motion and sweep as the loop makes them: a
    /// live view, or whatever knows the truth about the robot's world (by
    /// default nothing does: [`explore::NoJudge`]).
    #[must_use]
    pub fn judged_by(mut self, judge: Box<dyn Judge>) -> Self {
        self.judge = judge;
        self
    }

    /// Run it; `progress` sees each viewpoint's record as it completes.
    pub fn run(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<ExploreOutcome, JobError> {
        let Self {
            loaded,
            setup,
            hw,
            run_options,
            mut judge,
        } = self;
        let defaults = record::bag::BagConfig::default();
        let bag = RunBag::new(
            &setup.robot,
            &setup.world_from_base,
            &hw.joints(),
            hw.bearings_rad(),
            record::bag::BagConfig {
                scan_range_m: (setup.scanner.min_range_m, setup.scanner.max_range_m),
                ..defaults
            },
        )?;
        let (run, bag) = run_loop(
            &loaded,
            setup,
            hw,
            judge.as_mut(),
            bag,
            &run_options,
            progress,
        )?;
        Ok(ExploreOutcome {
            bag,
            coverage: None,
            observable: Vec::new(),
            oracle: None,
            material_identification: None,
            run,
            loaded,
        })
    }
}

/// A finished simulated exploration and its judgement.
#[derive(Clone, Debug)]
pub struct ExploreOutcome {
    /// The scenario run.
    pub loaded: LoadedScenario,
    /// What the loop did.
    pub run: ExploreRun,
    /// Coverage of the true surfaces in A1, A2, A3 (mesh worlds).
    pub coverage: Option<[CoverageReport; 3]>,
    /// Per region: observable samples and the covered ones among them.
    pub observable: Vec<(usize, usize)>,
    /// The coverage oracle (when asked for, mesh worlds).
    pub oracle: Option<CoverageOracle>,
    /// The run's material identification beside the material oracle (when
    /// the oracle was asked for and Stage Two ran in a scene with
    /// materials).
    pub material_identification: Option<MaterialIdentification>,
    /// `run.mcap`: what the hardware did, the sweeps, viewpoints and discs
    /// as ROS 2 messages ([`RunBag`]).
    pub bag: Vec<u8>,
}

/// Finish the bag of `run`: each viewpoint's points as one sweep cloud at
/// the time its record came (`stamps`, in viewpoint order), then marker
/// arrays of the viewpoints' scanner poses and of the discs by material.
fn finish_bag(
    mut recorder: RunBag,
    end: u64,
    run: &ExploreRun,
    robot: &robot::Robot,
    world_from_base: &geom::Isometry3,
    stamps: &[u64],
) -> Result<Vec<u8>, JobError> {
    let mut per_viewpoint: Vec<Vec<&sensor::SweepPoint>> = vec![Vec::new(); run.viewpoints.len()];
    for (p, &k) in run.cloud.iter().zip(&run.cloud_viewpoint) {
        if let Some(points) = per_viewpoint.get_mut(k) {
            points.push(p);
        }
    }
    for (k, points) in per_viewpoint.into_iter().enumerate() {
        recorder.sweep(stamps.get(k).copied().unwrap_or(end), points)?;
    }
    let (viewpoints, discs) = explore_markers(end, run, robot, world_from_base)?;
    recorder.write(record::bag::topics::VIEWPOINTS, end, &viewpoints)?;
    recorder.write(record::bag::topics::DISCS, end, &discs)?;
    Ok(recorder.finish()?)
}

/// The markers of a run stamped `stamp_ns`: its viewpoints' scanner poses
/// (`/surveyor/viewpoints`) and its discs by most probable material
/// (`/surveyor/discs`).
pub fn explore_markers(
    stamp_ns: u64,
    run: &ExploreRun,
    robot: &robot::Robot,
    world_from_base: &geom::Isometry3,
) -> Result<(MarkerArray, MarkerArray), JobError> {
    let mut poses = Vec::with_capacity(run.viewpoints.len());
    for v in &run.viewpoints {
        if let Some(pose) = robot.scanner_pose(&v.joints)? {
            poses.push(world_from_base * pose);
        }
    }
    let d = &run.discs;
    let discs: Vec<record::bag::markers::DiscMark> = d
        .discs
        .iter()
        .enumerate()
        .map(|(k, disc)| record::bag::markers::DiscMark {
            centre: disc.centre,
            normal: disc.normal,
            radius: disc.radius_m,
            material: material_of(d, k),
        })
        .collect();
    Ok((
        record::bag::markers::viewpoints(stamp_ns, &poses),
        record::bag::markers::discs(stamp_ns, &discs),
    ))
}

/// The most likely material of disc `k` once an observation updated it.
fn material_of(d: &explore::DiscMap, k: usize) -> Option<usize> {
    if d.observations.get(k).copied().unwrap_or(0) == 0 {
        return None;
    }
    d.posterior.get(k).and_then(|p| {
        p.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(m, _)| m)
    })
}

impl ExploreOutcome {
    /// The coverage as `run.json` holds it.
    pub fn coverage_summary(&self) -> Option<ExploreCoverage> {
        self.coverage.as_ref().map(|c| {
            let mut summary = ExploreCoverage::new(c, &self.observable);
            summary.oracle = self.oracle.clone().map(|o| {
                let stage_one: Vec<Real> = self
                    .run
                    .viewpoints
                    .iter()
                    .filter(|v| v.stage == 1)
                    .map(|v| v.coverage_a1.unwrap_or(0.0))
                    .collect();
                OracleComparison::new(o, &stage_one)
            });
            summary
        })
    }

    /// `run.json`.
    pub fn summary(&self) -> ExploreSummary {
        ExploreSummary {
            material_identification: self.material_identification.clone(),
            ..self.run.summary(self.coverage_summary())
        }
    }

    /// What a blast plan over this run is made from: its discs and segments,
    /// each disc's start the joints of the viewpoint that saw it, and its
    /// planning grid.
    pub fn blast_inputs(&self) -> Result<BlastInputs, JobError> {
        let run = &self.run;
        Ok(BlastInputs::new(
            run.discs.discs.clone(),
            run.disc_start_joints()?,
            run.discs.segments.clone(),
            run.grid.clone(),
            "the run",
        )?)
    }

    /// The blast plan of the run's discs in A2 (none without discs or
    /// regions), for the scenario's robot where it stands.
    pub fn blast_plan(&self, config: &BlastConfig) -> Result<Option<BlastPlan>, JobError> {
        let s = &self.loaded.scenario;
        match (s.regions, self.run.discs.discs.is_empty()) {
            (Some(regions), false) => Ok(Some(blast::plan_blast(
                &self.blast_inputs()?,
                &self.loaded.build_robot()?,
                s.world_from_base(),
                &regions.a2,
                config,
            )?)),
            _ => Ok(None),
        }
    }
}

/// Stage the run folder of `outcome`: the run's files
/// ([`ExploreRun::write`]), `scenario.toml` (the scenario as run, its file
/// paths made absolute so they resolve from the folder:
/// [`LoadedScenario::standalone`]), `blast_inputs.json` (what
/// `surveyor plan-blast` reads) and the blast plan (`blast_plan.json`,
/// `blast_plan.csv`) when the run made discs. Returns the plan.
pub fn write_run(
    outcome: &ExploreOutcome,
    staging: &Staging,
) -> Result<Option<BlastPlan>, JobError> {
    // The maintenance plan over the map (Paul App. A): a nozzle pose for
    // every disc in A2 that has one, each segment's targets ordered by the GA.
    let plan = outcome.blast_plan(&BlastConfig::default())?;
    stage_files(outcome, plan.as_ref(), staging)?;
    Ok(plan)
}

/// [`write_run`] with the blast plan made already.
fn stage_files(
    outcome: &ExploreOutcome,
    plan: Option<&BlastPlan>,
    staging: &Staging,
) -> Result<(), JobError> {
    outcome.run.write(staging, &outcome.summary())?;
    staging.write(record::folder::RUN_MCAP, &outcome.bag)?;
    staging.write(
        record::folder::SCENARIO_TOML,
        outcome.loaded.standalone().to_toml()?,
    )?;
    staging.write(
        record::blast::BLAST_INPUTS_JSON,
        outcome.blast_inputs()?.to_file().to_json()?,
    )?;
    if let Some(plan) = plan {
        staging.write(record::blast::BLAST_PLAN_JSON, plan.to_json()?)?;
        staging.write(record::blast::BLAST_PLAN_CSV, plan.csv())?;
    }
    Ok(())
}

/// Files that mark another command's run folder.
const FOLLOW_FILES: [&str; 2] = [
    record::follow::STEPS_CSV,
    record::follow::SURFACE_MODEL_JSON,
];

/// What adds files to a staged explore run folder (the report), in two
/// steps: the first, timed as the job's `report` phase, sees the folder
/// with `run.json` as it stands before that phase; the step it returns
/// sees the final `run.json`, whose timings include the first step (so a
/// report's figures can be the run's final ones).
pub type Finish<'a> = dyn FnMut(&Staging) -> Result<Complete, String> + 'a;

/// The second step of a [`Finish`].
pub type Complete = Box<dyn FnOnce(&Staging) -> Result<(), String>>;

/// A [`Finish`] that adds nothing.
pub fn no_files(_: &Staging) -> Result<Complete, String> {
    Ok(Box::new(|_| Ok(())))
}

/// An exploration ready to run, in the simulator (`sim::explore_job::SimExplore`) or on
/// other hardware ([`HardwareExplore`]).
pub trait ExploreJob {
    /// Run it; `progress` sees each viewpoint's record as it completes.
    fn run_job(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<ExploreOutcome, JobError>;
}

impl<H: Arm + LineScanner> ExploreJob for HardwareExplore<H> {
    fn run_job(
        self,
        progress: &mut dyn FnMut(&record::ViewpointRecord),
    ) -> Result<ExploreOutcome, JobError> {
        self.run(progress)
    }
}

/// The whole `surveyor explore` job with the exploration `make` gives for
/// the options (a [`HardwareExplore`] on a ROS 2 robot, the simulator's
/// `sim::explore_job::SimExplore`): check the output folder (not a file, not
/// a `surveyor follow` run, holding a checkpoint when resuming), run it with
/// its checkpoint in `out`, stage the run folder with the blast plan, let
/// `finish` add files to the staged folder (the report, see [`Finish`]), and
/// move everything into place, `run.json` last.
pub fn explore_with<J: ExploreJob>(
    options: &ExploreOptions,
    out: &Path,
    make: impl FnOnce(&ExploreOptions) -> Result<J, JobError>,
    progress: &mut dyn FnMut(&record::ViewpointRecord),
    finish: &mut Finish<'_>,
) -> Result<(ExploreOutcome, Option<BlastPlan>), JobError> {
    let bad_out = |message: String| JobError::InvalidArgument {
        what: out.display().to_string(),
        message,
    };
    record::output::check_out_dir(out)?;
    for foreign in FOLLOW_FILES {
        if out.join(foreign).exists() {
            return Err(bad_out(format!(
                "holds a `surveyor follow` run ({foreign}); give another --out"
            )));
        }
    }
    let checkpoint = out.join(record::checkpoint::CHECKPOINT_JSON);
    if options.resume && !checkpoint.is_file() {
        return Err(bad_out(
            "holds no checkpoint.json (no run to continue there; run without --resume)".into(),
        ));
    }
    let options = ExploreOptions {
        checkpoint: Some(checkpoint),
        ..options.clone()
    };
    let t_job = Instant::now();
    let mut clock = Instant::now();
    // Seconds since the last lap.
    let mut lap = || {
        let s = clock.elapsed().as_secs_f64();
        clock = Instant::now();
        s
    };
    let job = make(&options)?;
    record::output::create_out_dir(out)?;
    let setup_s = lap();
    let mut outcome = job.run_job(progress)?;
    lap();
    let plan = outcome.blast_plan(&BlastConfig::default())?;
    let blast_planning_s = lap();
    if let Some(t) = &mut outcome.run.timings {
        t.setup_s = setup_s;
        t.blast_planning_s = blast_planning_s;
    }
    let staging = Staging::new(out)?;
    stage_files(&outcome, plan.as_ref(), &staging)?;
    let write_s = lap();
    let failed = |message: String| JobError::InvalidArgument {
        what: out.display().to_string(),
        message,
    };
    let complete = finish(&staging).map_err(failed)?;
    let report_s = lap();
    if let Some(t) = &mut outcome.run.timings {
        t.write_s = write_s;
        t.report_s = report_s;
        t.total_s = t_job.elapsed().as_secs_f64();
        // run.json again, with the whole job's times.
        staging.write(record::explore::RUN_JSON, outcome.summary().to_json()?)?;
    }
    complete(&staging).map_err(failed)?;
    staging.commit()?;
    Ok((outcome, plan))
}

/// The blast plan of the `surveyor explore` run folder `dir` under `config`
/// (what `surveyor plan-blast` makes): the robot, its placement and A2 from
/// the folder's `scenario.toml`, the discs, segments, start joints and
/// planning grid from its `blast_inputs.json`, both read through
/// [`record::RunFolder`].
pub fn plan_blast_run(dir: &Path, config: &BlastConfig) -> Result<BlastPlan, JobError> {
    let needed = [
        record::folder::SCENARIO_TOML,
        record::blast::BLAST_INPUTS_JSON,
    ];
    if needed.iter().any(|n| !dir.join(n).is_file()) {
        return Err(JobError::InvalidArgument {
            what: dir.display().to_string(),
            message: format!(
                "expected {} and {} (with the rest of a run folder), as `surveyor explore --out DIR` writes them",
                needed[0], needed[1]
            ),
        });
    }
    let folder = record::RunFolder::open(dir)?;
    if folder.kind() != record::RunKind::Explore {
        return Err(JobError::InvalidArgument {
            what: dir.display().to_string(),
            message: "not a `surveyor explore` run folder (it holds a `surveyor follow` run)"
                .into(),
        });
    }
    let scenario_path = folder.path(record::folder::SCENARIO_TOML);
    let source = scenario_path.display().to_string();
    let text = folder.scenario_toml()?.unwrap_or_default();
    let loaded = LoadedScenario {
        scenario: crate::Scenario::from_toml(&text, &source)?,
        base_dir: dir.to_owned(),
    };
    let Some(regions) = loaded.scenario.regions else {
        return Err(JobError::InvalidArgument {
            what: source,
            message: "the scenario has no regions (A2 is where discs are blasted)".into(),
        });
    };
    if loaded.scenario.name != folder.scenario() {
        return Err(JobError::InvalidArgument {
            what: source,
            message: format!(
                "the scenario is `{}`, but the run folder's run.json names `{}`: scenario.toml \
                 belongs to another run",
                loaded.scenario.name,
                folder.scenario()
            ),
        });
    }
    let robot = loaded.build_robot()?;
    let file = folder.blast_inputs::<map::Disc, map::OccupancyConfig>()?;
    let inputs_path = folder.path(record::blast::BLAST_INPUTS_JSON);
    let mismatch = |message: String| JobError::InvalidArgument {
        what: inputs_path.display().to_string(),
        message,
    };
    if file.grid.config.regions != regions {
        return Err(mismatch(format!(
            "its planning grid covers other regions than {source}'s: the two files belong to \
             different runs"
        )));
    }
    if let Some(q) = file.start_joints.iter().find(|q| q.len() != robot.dof()) {
        return Err(mismatch(format!(
            "a start pose of {} joints for {source}'s robot `{}` of {}: the two files belong \
             to different runs",
            q.len(),
            robot.name,
            robot.dof()
        )));
    }
    let inputs = BlastInputs::from_file(
        file,
        &folder
            .path(record::blast::BLAST_INPUTS_JSON)
            .display()
            .to_string(),
    )?;
    Ok(blast::plan_blast(
        &inputs,
        &robot,
        loaded.scenario.world_from_base(),
        &regions.a2,
        config,
    )?)
}
