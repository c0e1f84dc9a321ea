//! Surface following of a scenario or a scene file on any hardware (the
//! simulator's `SimRig`, a ROS 2 robot, a user's driver): the setup from a
//! scenario or a scene file ([`FollowSetup`]: robot, base, start joints,
//! initial segments, the true faces the robot cannot reach given a priori
//! ([`super::reach::unreachable_faces`]), the robot clock's figures), the
//! loop of `follow` ([`follow::run_episode`]) on the hardware, timed on the
//! robot clock and recorded in `run.mcap` ([`FollowSetup::run_episode`]),
//! and the run folder ([`FollowRun::write`], [`follow_with`]).
//! [`HardwareFollow`] is the job on hardware nobody judges; the simulator's
//! job, with its ground-truth judge and the model's scores, is `sim`'s.
//!
//! Determinism: the follower is deterministic, so the same readings give
//! the same `steps.csv` and `surface_model.json` byte for byte, except for
//! the wall-clock timing columns of `steps.csv` and the step times of
//! `run.json`; with [`FollowRunOptions::timings`] off those columns are
//! written empty and those times are 0, so every file repeats.

use super::reach::{AprioriFace, unreachable_faces};
use super::{JobError, bag_event, check_stands_at};
use crate::{LoadedScenario, RobotChoice, is_urdf_name};
use follow::{Episode, EpisodeOptions, FollowConfig, FollowError, Follower, RunEnd, Termination};
use geom::{Aabb, Isometry3, Point3, Real, Vector3};
use hw::script::{Event, Tap};
use hw::{Arm, RangeSensors};
use plan::contact::robot_contacts;
use record::follow::{FollowSummary, StepTimeStats};
use record::snapshots::ModelSnapshots;
use record::{Collision, StepRow, StepTimes};
use robot::Robot;
use scene::faces::not_resting_on;
use scene::{PointCloud, PointCloudWorld, Scene, SceneError, World};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use surface::{SurfaceConfig, SurfaceError, SurfaceModel};

/// Where `arm4` stands when a built-in surface-following scene (cube, block1,
/// block2, cylinder) or a scenario written for another robot is run with it:
/// 1.6 m to the −x side of the origin, so the top faces (centred near the
/// origin, 0.6–1.0 m high) lie within reach of its three 1 m links from the
/// 1 m post, and no object stands between the post and the scene.
pub const ARM4_BASE_XYZ: [Real; 3] = [-1.6, 0.0, 0.0];

/// Start guess of [`follow::place_tool`] for `arm4` (radians): the arm
/// reaching forward and down.
pub const ARM4_SEED: [Real; 6] = [0.0, 0.8, 0.0, 1.0, 0.0, 1.0];

/// Default budget of sensor sets of one run.
pub const DEFAULT_MAX_SETS: u64 = 20_000;

/// How the robot starts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StartPose {
    /// The control point here (world frame), the tool axis pointing down
    /// (solved with [`follow::place_tool`] for arms).
    ControlPoint([Real; 3]),
    /// These joint values.
    Joints(Vec<Real>),
}

/// The parameters of following and of the surface model (the `--config` file
/// of `surveyor follow`: tables `[follow]` and `[surface]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FollowRunConfig {
    /// Surface following (P ch. 3).
    pub follow: FollowConfig,
    /// The surface model (P ch. 2).
    pub surface: SurfaceConfig,
}

impl FollowRunConfig {
    /// A scenario's own parameters: its `[follow]` and `[surface]` tables,
    /// each table's defaults where it has none.
    pub fn of_scenario(s: &crate::Scenario) -> Self {
        Self {
            follow: s.follow.unwrap_or_default(),
            surface: s.surface.unwrap_or_default(),
        }
    }
}

/// Options of a run; fields left out take their defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FollowRunOptions {
    /// Seed of the range noise.
    pub seed: u64,
    /// Most sensor sets to take (one per step); the run then ends with
    /// termination `max_sets`.
    pub max_sets: u64,
    /// Range noise σ, metres, instead of the scenario's.
    pub noise_sigma_m: Option<Real>,
    /// Another robot than the scenario's: `point3`, `arm4` or a URDF file
    /// (path ending in `.urdf`).
    pub robot: Option<String>,
    /// Another start than the scenario's.
    pub start: Option<StartPose>,
    /// Initial segments (world frame) instead of the scenario's.
    pub initial_segments: Option<Vec<Vec<[Real; 3]>>>,
    /// Record wall-clock step times in `steps.csv` and `run.json` (off: those
    /// columns are empty and those times 0, so the files are the same byte
    /// for byte for the same inputs).
    pub timings: bool,
    /// Parameters of following and of the model.
    pub config: FollowRunConfig,
}

impl Default for FollowRunOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            max_sets: DEFAULT_MAX_SETS,
            noise_sigma_m: None,
            robot: None,
            start: None,
            initial_segments: None,
            timings: true,
            config: FollowRunConfig::default(),
        }
    }
}

/// What can go wrong setting up or running an episode.
#[derive(Debug, thiserror::Error)]
pub enum FollowRunError {
    /// The scenario, world, robot, hardware or run folder (the
    /// simulator's rig included).
    #[error(transparent)]
    Job(Box<JobError>),
    /// The follower (configuration, robot without control-point sensors, a
    /// refused step).
    #[error(transparent)]
    Follow(#[from] FollowError),
    /// The surface model (configuration, an initial segment).
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// An option is invalid.
    #[error("{what}: {message}")]
    Option {
        /// The option.
        what: String,
        /// What is wrong.
        message: String,
    },
}

fn bad(what: &str, message: impl Into<String>) -> FollowRunError {
    FollowRunError::Option {
        what: what.to_owned(),
        message: message.into(),
    }
}

impl FollowRunOptions {
    /// Check the values that need no robot or world: finite start and initial
    /// segments, noise σ finite ≥ 0, `max_sets` ≥ 1, and both configurations.
    pub fn validate(&self) -> Result<(), FollowRunError> {
        if self.max_sets == 0 {
            return Err(bad("max_sets", "expected at least 1 sensor set"));
        }
        if let Some(s) = self.noise_sigma_m
            && !(s.is_finite() && (0.0..=crate::range_sensors::MAX_NOISE_SIGMA_M).contains(&s))
        {
            return Err(bad(
                "noise_sigma_m",
                format!("expected a standard deviation from 0 to 1 metre, got {s}"),
            ));
        }
        match &self.start {
            Some(StartPose::ControlPoint(p))
                if !p
                    .iter()
                    .all(|c| c.is_finite() && c.abs() <= scene::MAX_COORDINATE_M) =>
            {
                return Err(bad(
                    "start",
                    format!(
                        "expected a finite control point within ±{:e} m, got {p:?}",
                        scene::MAX_COORDINATE_M
                    ),
                ));
            }
            Some(StartPose::Joints(q)) => {
                if let Some(i) = q.iter().position(|v| !v.is_finite()) {
                    return Err(bad(
                        "joints",
                        format!("joint {} is {}: expected a finite value", i + 1, q[i]),
                    ));
                }
            }
            _ => {}
        }
        if let Some(segs) = &self.initial_segments {
            for (s, verts) in segs.iter().enumerate() {
                if let Some(v) = verts.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
                    return Err(bad(
                        &format!("initial_segments[{s}][{v}]"),
                        "expected finite coordinates",
                    ));
                }
            }
        }
        self.config.follow.validate()?;
        self.config.surface.validate()?;
        Ok(())
    }
}

/// A run ready to start on any hardware: the robot, where it stands and
/// starts, the initial segments and everything the follower needs.
#[derive(Clone, Debug)]
pub struct FollowSetup {
    /// The scenario name, or the scene file.
    pub source: String,
    /// The robot, its range finders around the control point.
    pub robot: Robot,
    /// Where its base stands.
    pub world_from_base: Isometry3,
    /// The world the scenario or scene file describes: what the setup
    /// knows before the run (the start's clearance, the faces the robot
    /// cannot reach), and the simulator's ground truth.
    pub world: Arc<World>,
    /// Start joints.
    pub start_joints: Vec<Real>,
    /// A-priori segments of the model (world frame).
    pub initial_segments: Vec<Vec<Point3>>,
    /// Height of the support the objects stand on: true faces facing down at
    /// this height are not scored ([`not_resting_on`]).
    pub support_z: Real,
    /// True faces (of [`scene::faces::true_faces`]) the robot cannot
    /// reach, given a priori among the initial segments and not scored
    /// ([`unreachable_faces`]).
    pub a_priori_faces: Vec<AprioriFace>,
    /// Range noise σ of every reading, metres (the option's, else the
    /// scenario's; 0 for a scene file): what the simulator adds, and how
    /// far past their range the bag lets range finders report.
    pub noise_sigma_m: Real,
    /// The options.
    pub options: FollowRunOptions,
    /// The robot clock's figures (`[robot.timing]` of the scenario's own
    /// robot; another robot's, or a scene file's, are the robot's own).
    pub timing: hw::clock::RobotTiming,
}

/// The robot clock's figures of `robot` without a scenario's: its own
/// limits, the range finders' default period.
fn own_timing(robot: &Robot) -> hw::clock::RobotTiming {
    hw::clock::RobotTiming::of(
        robot,
        sensor::ScannerConfig::default().scan_time_s,
        hw::clock::DEFAULT_READING_PERIOD_S,
    )
}

/// The robots `follow` runs: `point3`, `arm4` (the built-ins with range
/// finders around a control point) or a URDF file.
fn follow_robot_choice(name: &str) -> Result<RobotChoice, FollowRunError> {
    let choice = RobotChoice::parse(name, None).map_err(JobError::from)?;
    match choice.builtin_name() {
        Some("point3" | "arm4") | None => Ok(choice),
        Some(other) => Err(bad(
            "robot",
            format!("unknown robot `{other}`: expected point3, arm4 or a URDF file (FILE.urdf)"),
        )),
    }
}

/// The override robot, with the scenario's `[range_sensors]` applied.
fn override_robot(name: &str, loaded: Option<&LoadedScenario>) -> Result<Robot, FollowRunError> {
    let mut robot = follow_robot_choice(name)?.build().map_err(JobError::from)?;
    if let Some(l) = loaded {
        l.scenario
            .range_sensors
            .apply(&mut robot)
            .map_err(|message| JobError::Scenario {
                source_name: l.scenario.name.clone(),
                message,
            })?;
    }
    Ok(robot)
}

/// Joints putting `robot`'s control point at `target` (world frame) with the
/// tool axis down: direct for `point3`-like robots (three prismatic joints
/// along the base axes), [`follow::place_tool`] otherwise.
fn joints_for(
    robot: &Robot,
    world_from_base: &Isometry3,
    target: &Point3,
    extra_seed: Option<&[Real]>,
) -> Result<Vec<Real>, FollowRunError> {
    if robot.name == "point3" {
        let p = world_from_base.inverse_transform_point(target);
        return Ok(vec![p.x, p.y, p.z]);
    }
    let dof = robot.dof();
    let mut seeds: Vec<Vec<Real>> = Vec::new();
    if let Some(s) = extra_seed
        && s.len() == dof
    {
        seeds.push(s.to_vec());
    }
    if dof == ARM4_SEED.len() {
        seeds.push(ARM4_SEED.to_vec());
    }
    seeds.push(vec![0.0; dof]);
    Ok(follow::place_tool(
        robot,
        world_from_base,
        target,
        &-Vector3::z_axis(),
        &seeds,
    )?)
}

/// The option a start pose came from, for errors.
fn start_what(start: Option<&StartPose>) -> &'static str {
    match start {
        Some(StartPose::Joints(_)) => "joints",
        _ => "start",
    }
}

/// The start must be within the joint limits and, on a mesh scene, clear of
/// it (a run from inside an object only counts collisions), and every
/// initial segment must face it ([`check_initial_facing`]).
fn check_start(
    robot: &Robot,
    q: &[Real],
    what: &str,
    (world, world_from_base): (&World, &Isometry3),
    initial_segments: &[Vec<Point3>],
) -> Result<(), FollowRunError> {
    robot
        .check_within_limits(q)
        .map_err(|e| bad(what, e.to_string()))?;
    if let Some(scene) = world.as_scene() {
        let frames = robot
            .forward_kinematics(q)
            .map_err(|e| bad(what, e.to_string()))?;
        if let Some(c) = robot_contacts(robot, &frames, world_from_base, scene).first() {
            return Err(bad(
                what,
                format!(
                    "the start puts link {} ({}) into the scene (object {}); start clear of it",
                    c.link.index(),
                    robot.links[c.link.index()].name,
                    scene.object(c.object).map_or("?", |o| o.name.as_str())
                ),
            ));
        }
        // A point robot has no link shapes: its control point itself must be
        // outside every closed object.
        let tool = robot.tool_pose(q).map_err(|e| bad(what, e.to_string()))?;
        let control = world_from_base * Point3::from(tool.translation.vector);
        if scene.is_inside_closed_object(&control, None) {
            let object = scene
                .closest_point(&control, Real::INFINITY)
                .and_then(|(_, face, _)| scene.object(scene.triangle_object(face)))
                .map_or("?", |o| o.name.as_str());
            return Err(bad(
                what,
                format!(
                    "the start puts the control point ({:.3}, {:.3}, {:.3}) inside object {object}; start outside it",
                    control.x, control.y, control.z
                ),
            ));
        }
    }
    check_initial_facing(initial_segments, robot, q, world_from_base)
}

impl FollowSetup {
    /// A run of a scenario (built-in or file). The scenario's robot, base,
    /// start joints, range sensors, noise and initial segments apply unless the
    /// options override them. A robot override stands at the scenario's base
    /// when the scenario was written for that robot; otherwise `point3` at the
    /// origin and `arm4` at [`ARM4_BASE_XYZ`] (a URDF robot at the scenario's
    /// base). Without a start override such a robot starts with its control
    /// point where the scenario robot's is at its start joints (δ above the top
    /// face's centre for the built-ins), the tool pointing down.
    pub fn from_scenario(
        loaded: &LoadedScenario,
        options: &FollowRunOptions,
    ) -> Result<Self, FollowRunError> {
        options.validate()?;
        let s = &loaded.scenario;
        let world = Arc::new(loaded.build_world()?);
        let own = loaded.build_robot()?;
        let same_robot = match options.robot.as_deref() {
            None => true,
            Some(name) if is_urdf_name(name) => s
                .robot
                .urdf
                .as_deref()
                .is_some_and(|u| loaded.base_dir.join(u) == Path::new(name)),
            Some(name) => s.robot.preset.as_deref() == Some(name),
        };
        let timing = if same_robot {
            loaded.robot_timing(&own)?
        } else {
            own_timing(&override_robot(
                options.robot.as_deref().unwrap_or_default(),
                Some(loaded),
            )?)
        };
        let (robot, world_from_base) = if same_robot {
            (own.clone(), s.world_from_base())
        } else {
            let name = options.robot.as_deref().unwrap_or_default();
            let robot = override_robot(name, Some(loaded))?;
            let base = match name {
                "point3" => Isometry3::identity(),
                "arm4" => {
                    Isometry3::translation(ARM4_BASE_XYZ[0], ARM4_BASE_XYZ[1], ARM4_BASE_XYZ[2])
                }
                _ => s.world_from_base(),
            };
            (robot, base)
        };
        let start_joints = match &options.start {
            Some(StartPose::Joints(q)) => q.clone(),
            Some(StartPose::ControlPoint(p)) => joints_for(
                &robot,
                &world_from_base,
                &Point3::new(p[0], p[1], p[2]),
                same_robot.then_some(s.robot.start_joints.as_slice()),
            )?,
            None if same_robot => s.robot.start_joints.clone(),
            None => {
                let tool = own
                    .tool_pose(&s.robot.start_joints)
                    .map_err(JobError::from)?;
                let target = s.world_from_base() * Point3::from(tool.translation.vector);
                joints_for(&robot, &world_from_base, &target, None)?
            }
        };
        let mut initial_segments = match &options.initial_segments {
            Some(v) => to_points(v),
            None => to_points(&s.initial_segments),
        };
        check_start(
            &robot,
            &start_joints,
            start_what(options.start.as_ref()),
            (&world, &world_from_base),
            &initial_segments,
        )?;
        // arm4 on its post beside a scene written for another robot: the
        // faces it cannot reach are given a priori, as Pudney gave his
        // objects' occluded faces (P§4.3).
        let mut a_priori_faces = Vec::new();
        if !same_robot
            && options.robot.as_deref() == Some("arm4")
            && options.initial_segments.is_none()
            && let Some(scene) = world.as_scene()
        {
            a_priori_faces = unreachable_faces(
                scene,
                &robot,
                &world_from_base,
                &[ARM4_SEED.to_vec()],
                not_resting_on(0.0),
            );
            // Outlines of the true faces, anticlockwise about their outward
            // normals, so not checked to face the robot: a far face never does.
            initial_segments.extend(a_priori_faces.iter().map(|f| f.outline.clone()));
        }
        let setup = Self {
            source: s.name.clone(),
            robot,
            world_from_base,
            world,
            start_joints,
            initial_segments,
            support_z: 0.0,
            a_priori_faces,
            noise_sigma_m: options
                .noise_sigma_m
                .unwrap_or(s.range_sensors.noise_sigma_m),
            options: options.clone(),
            timing,
        };
        // The initial segments are checked now, not when the run starts.
        setup.follower()?;
        Ok(setup)
    }

    /// A run over a scene file placed as-is in the world frame: a mesh (OBJ,
    /// STL, PLY) or a point cloud (PCD, PLY, text), scaled by `scale`. The
    /// robot is `point3` at the origin unless overridden (`arm4` then stands
    /// [`ARM4_BASE_XYZ`] from the bounding box's bottom centre, a URDF robot at
    /// the origin). It starts with the control point δ above the centre of the
    /// bounding box's top, tool down. Without initial segments in the options
    /// the model starts with a table: the square at the bounding box's bottom
    /// reaching one box size (at least 0.5 m) beyond it on every side.
    pub fn from_scene_file(
        path: &Path,
        scale: Real,
        options: &FollowRunOptions,
    ) -> Result<Self, FollowRunError> {
        options.validate()?;
        if !(scale.is_finite() && scale > 0.0) {
            return Err(bad(
                "scale",
                format!("expected a finite factor > 0, got {scale}"),
            ));
        }
        let world = scene_world(path, scale)?;
        let bounds = match &world {
            World::Mesh(s) => s.bounding_box(),
            World::Cloud(c) => c.cloud().bounding_box(),
        };
        let name = options.robot.as_deref().unwrap_or("point3");
        let robot = override_robot(name, None)?;
        let bottom_centre = Point3::new(
            0.5 * (bounds.min.x + bounds.max.x),
            0.5 * (bounds.min.y + bounds.max.y),
            bounds.min.z,
        );
        let world_from_base = if name == "arm4" {
            Isometry3::translation(
                bottom_centre.x + ARM4_BASE_XYZ[0],
                bottom_centre.y + ARM4_BASE_XYZ[1],
                bottom_centre.z + ARM4_BASE_XYZ[2],
            )
        } else {
            Isometry3::identity()
        };
        let delta = options.config.follow.desired_distance_m;
        let start_joints = match &options.start {
            Some(StartPose::Joints(q)) => q.clone(),
            Some(StartPose::ControlPoint(p)) => joints_for(
                &robot,
                &world_from_base,
                &Point3::new(p[0], p[1], p[2]),
                None,
            )?,
            None => joints_for(
                &robot,
                &world_from_base,
                &Point3::new(bottom_centre.x, bottom_centre.y, bounds.max.z + delta),
                None,
            )?,
        };
        let initial_segments = match &options.initial_segments {
            Some(v) => to_points(v),
            None => vec![table_under(&bounds)],
        };
        check_start(
            &robot,
            &start_joints,
            start_what(options.start.as_ref()),
            (&world, &world_from_base),
            &initial_segments,
        )?;
        let timing = own_timing(&robot);
        let setup = Self {
            source: path.display().to_string(),
            robot,
            world_from_base,
            world: Arc::new(world),
            noise_sigma_m: options.noise_sigma_m.unwrap_or(0.0),
            start_joints,
            initial_segments,
            support_z: bounds.min.z,
            a_priori_faces: Vec::new(),
            options: options.clone(),
            timing,
        };
        setup.follower()?;
        Ok(setup)
    }

    /// The follower for this run: a new model with the initial segments.
    pub fn follower(&self) -> Result<Follower, FollowRunError> {
        let mut model = SurfaceModel::new(self.options.config.surface)?;
        // The a-priori faces come last (`initial_segments` ends with them).
        let first_face = self
            .initial_segments
            .len()
            .saturating_sub(self.a_priori_faces.len());
        let mut faces = Vec::new();
        let mut ids = Vec::with_capacity(self.initial_segments.len());
        for (i, seg) in self.initial_segments.iter().enumerate() {
            let id = model.add_initial_segment(seg).map_err(|e| match e {
                SurfaceError::InitialSegment { message } => {
                    bad("initial segments", format!("segment {i}: {message}"))
                }
                SurfaceError::InitialOverlap { other, area_m2 } => bad(
                    "initial segments",
                    format!(
                        "segment {i} overlaps segment {} over {area_m2:.3e} m² of the same surface (facing the same way, within λ of it); initial segments never merge, so that surface would be modelled twice",
                        ids.iter().position(|id| *id == other).unwrap_or(other.0 as usize)
                    ),
                ),
                e => e.into(),
            })?;
            ids.push(id);
            if i >= first_face {
                faces.push(id);
            }
        }
        let mut follower = Follower::new(
            self.robot.clone(),
            self.world_from_base,
            model,
            self.options.config.follow,
        )?;
        follower.mark_object_faces(&faces);
        Ok(follower)
    }

    /// The bag of a run from the start ([`record::bag::RunBag`]): no
    /// scanner, and range finders that report up to their range plus 10σ
    /// of the range noise (a simulated reading can lie that far past it).
    pub fn run_bag(&self) -> Result<record::bag::RunBag, JobError> {
        let config = record::bag::BagConfig {
            finder_range_slack_m: 10.0 * self.noise_sigma_m,
            ..record::bag::BagConfig::default()
        };
        Ok(record::bag::RunBag::new(
            &self.robot,
            &self.world_from_base,
            &self.start_joints,
            &[],
            config,
        )?)
    }

    /// The episode (see [`follow::run_episode`]) on `hw`, which stands at
    /// the start joints, timed by the robot clock and tapped into `bag`
    /// ([`run_bag`](Self::run_bag)), with `judge` seeing every pose and
    /// motion. `progress` is called after every step; raising `stop` ends
    /// the run after the current step. The run it gives holds no judgement
    /// and no scores: a judge's owner adds them.
    pub fn run_episode<H: Arm + RangeSensors, S, M>(
        self,
        hw: H,
        mut bag: record::bag::RunBag,
        judge: &mut dyn follow::Judge,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&StepRow, &Follower),
    ) -> Result<FollowRun<S, M>, FollowRunError> {
        let mut follower = self.follower()?;
        let mut snapshots = ModelSnapshots::new();
        let clock = hw::clock::RobotClock::default();
        let timed = hw::clock::Timed::new(hw, self.timing.clone(), clock.clone());
        let mut tapped = Tap::with_sink(timed, |e: &Event| bag_event(&mut bag, &clock, e));
        let episode = follow::run_episode(
            &mut tapped,
            &mut follower,
            judge,
            &EpisodeOptions {
                max_sets: self.options.max_sets,
                timings: self.options.timings,
                clock: clock.clone(),
            },
            stop,
            &mut |row, f| {
                snapshots.observe(row.step + 1, f.model());
                progress(row, f);
            },
        )?;
        snapshots.finish(episode.rows.len() as u64, follower.model());
        let end = clock.now_ns();
        let robot_time = clock.spent();
        let model_markers =
            record::bag::markers::surface_model(end, &follower.model().to_model_json());
        bag.write(record::bag::topics::SURFACE_MODEL, end, &model_markers)
            .map_err(JobError::from)?;
        let bag = bag.finish().map_err(JobError::from)?;
        let robot = follower.robot().name.clone();
        let end_control_point = follower.control_point(&episode.end_joints)?;
        Ok(FollowRun {
            source: self.source,
            robot,
            start_joints: self.start_joints,
            end_control_point,
            options: self.options,
            episode,
            judgement: Judgement::default(),
            model: follower.into_model(),
            snapshots,
            score: None,
            scan_score: None,
            a_priori_faces: self.a_priori_faces,
            robot_time,
            bag,
        })
    }
}

/// A scenario's or a scene file's surface following on hardware the
/// simulator does not own (a ROS 2 robot): the setup, the hardware at its
/// start pose, and no ground truth (no contact or clearance checks, no
/// score; everything else as in the simulator).
#[derive(Debug)]
pub struct HardwareFollow<H> {
    setup: FollowSetup,
    hw: H,
}

impl<H: Arm + RangeSensors> HardwareFollow<H> {
    /// The run of `setup` on `hw`, which must stand at the start joints
    /// (within `start_tolerance` radians) and carry the setup robot's range
    /// finders.
    pub fn new(setup: FollowSetup, hw: H, start_tolerance: Real) -> Result<Self, FollowRunError> {
        check_stands_at(&hw.joints(), &setup.start_joints, start_tolerance)
            .map_err(|message| bad("the robot", message))?;
        Ok(Self { setup, hw })
    }

    /// Run the episode ([`FollowSetup::run_episode`]), judged by nobody.
    pub fn run(
        self,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&StepRow, &Follower),
    ) -> Result<FollowRun, FollowRunError> {
        let bag = self.setup.run_bag()?;
        self.setup
            .run_episode(self.hw, bag, &mut follow::NoJudge, stop, progress)
    }
}

/// Each initial segment must face the robot: its vertices anticlockwise
/// about the normal pointing to the start's control point (the model's
/// convention: the robot is on the positive side of every segment).
fn check_initial_facing(
    segments: &[Vec<Point3>],
    robot: &Robot,
    q: &[Real],
    world_from_base: &Isometry3,
) -> Result<(), FollowRunError> {
    let tool = robot
        .tool_pose(q)
        .map_err(|e| bad("start", e.to_string()))?;
    let control = world_from_base * Point3::from(tool.translation.vector);
    for (i, seg) in segments.iter().enumerate() {
        let n = geom::polygon3::newell_normal(seg);
        if seg.is_empty() || n.norm() == 0.0 {
            continue; // the model reports degenerate segments itself
        }
        let centroid = seg.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / seg.len() as Real;
        if (control.coords - centroid).dot(&n) < 0.0 {
            return Err(bad(
                "initial segments",
                format!(
                    "segment {i} faces away from the robot: its vertices are clockwise seen from \
                     the start's control point ({:.3}, {:.3}, {:.3}); list them anticlockwise",
                    control.x, control.y, control.z
                ),
            ));
        }
    }
    Ok(())
}

fn to_points(v: &[Vec<[Real; 3]>]) -> Vec<Vec<Point3>> {
    v.iter()
        .map(|s| s.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect())
        .collect()
}

/// The table initial segment under `bounds` (anticlockwise about +z).
fn table_under(bounds: &Aabb) -> Vec<Point3> {
    let e = bounds.extents();
    let margin = e.x.max(e.y).max(0.5);
    let (x0, x1) = (bounds.min.x - margin, bounds.max.x + margin);
    let (y0, y1) = (bounds.min.y - margin, bounds.max.y + margin);
    let z = bounds.min.z;
    vec![
        Point3::new(x0, y0, z),
        Point3::new(x1, y0, z),
        Point3::new(x1, y1, z),
        Point3::new(x0, y1, z),
    ]
}

/// A scene file as a world, scaled: meshes by extension (a PLY without faces
/// is read as a cloud), everything else as a point cloud.
fn scene_world(path: &Path, scale: Real) -> Result<World, FollowRunError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let as_mesh = |m| -> Result<World, FollowRunError> {
        Ok(World::Mesh(Scene::from_mesh(
            &path.display().to_string(),
            m,
            scene::default_materials(),
            scene::MaterialId(0),
        )?))
    };
    let as_cloud = || -> Result<World, FollowRunError> {
        let cloud = scene::io::load_cloud(path)?;
        let points = cloud.points.iter().map(|p| p * scale).collect();
        Ok(World::Cloud(PointCloudWorld::new(
            PointCloud::from_points(points),
            None,
            None,
        )?))
    };
    match ext.as_str() {
        "obj" | "stl" => as_mesh(scene::io::load_mesh(path, scale)?),
        "ply" => match scene::io::load_mesh(path, scale) {
            Ok(m) => as_mesh(m),
            Err(SceneError::Invalid { .. }) => as_cloud(),
            Err(e) => Err(JobError::from(e).into()),
        },
        _ => as_cloud(),
    }
}

// Boxed: a job's error is large, and every setup step returns this type.
impl From<JobError> for FollowRunError {
    fn from(e: JobError) -> Self {
        Self::Job(Box::new(e))
    }
}

impl From<crate::ScenarioError> for FollowRunError {
    fn from(e: crate::ScenarioError) -> Self {
        Self::from(JobError::from(e))
    }
}

impl From<SceneError> for FollowRunError {
    fn from(e: SceneError) -> Self {
        Self::from(JobError::from(e))
    }
}

/// What a judge of a run against the ground truth found (the simulator's
/// `sim::follow_job::FollowJudge`); a run nobody judges has the default,
/// nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Judgement {
    /// Ground-truth contacts (empty without a ground truth).
    pub collisions: Vec<Collision>,
    /// Smallest ground-truth clearance of the links from the scene over the
    /// poses visited (searched within the judge's radius); `None` without
    /// a ground truth.
    pub min_clearance_m: Option<Real>,
    /// Configurations checked along the motions.
    pub motion_checks: usize,
    /// Smallest distance of the link capsules (links ≥ 1) from the scan points
    /// over the poses visited; `None` without a scan or without link
    /// capsules.
    pub min_scan_clearance_m: Option<Real>,
    /// Poses (the start included) at which a link capsule came closer than
    /// δ/2 (half the follower's desired distance) to a scan point; `None`
    /// without a scan or without link capsules.
    pub scan_close_poses: Option<usize>,
}

/// What `run.json` reads of a model's score against a true scene.
pub trait SurfaceFigures {
    /// The true surface area modelled, m².
    fn modelled_m2(&self) -> Real;
}

/// What `run.json` reads of a model's distances to a scan.
pub trait ScanFigures {
    /// The largest distance from a non-initial model polygon to the
    /// nearest scan point, metres (`None` without such polygons).
    fn max_m(&self) -> Option<Real>;
    /// The area fraction of the non-initial model polygons within λ of a
    /// scan point.
    fn within_lambda_fraction(&self) -> Real;
    /// The area of the non-initial model polygons within λ of a scan point,
    /// m²: what a scanned run counts as modelled (a scan has no true area).
    fn modelled_m2(&self) -> Real;
}

/// The score of a run nobody scores: it has none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum NoScore {}

impl SurfaceFigures for NoScore {
    fn modelled_m2(&self) -> Real {
        match *self {}
    }
}

impl ScanFigures for NoScore {
    fn max_m(&self) -> Option<Real> {
        match *self {}
    }

    fn within_lambda_fraction(&self) -> Real {
        match *self {}
    }

    fn modelled_m2(&self) -> Real {
        match *self {}
    }
}

/// A finished run: the episode, its judgement, the model and its scores,
/// `S` against a true scene and `M` against a scan (the simulator's types;
/// a run nobody scores has [`NoScore`]).
#[derive(Clone, Debug)]
pub struct FollowRun<S = NoScore, M = NoScore> {
    /// The scenario name, or the scene file.
    pub source: String,
    /// The robot's name.
    pub robot: String,
    /// Start joints.
    pub start_joints: Vec<Real>,
    /// The control point at the end.
    pub end_control_point: Point3,
    /// The options of the run.
    pub options: FollowRunOptions,
    /// What happened.
    pub episode: Episode,
    /// What the judge found.
    pub judgement: Judgement,
    /// The surface model built.
    pub model: SurfaceModel,
    /// The model's evolution: copies at evenly spaced set counts and at the
    /// end ([`ModelSnapshots`]).
    pub snapshots: ModelSnapshots,
    /// The model scored against the true scene (`None` for point-cloud worlds).
    pub score: Option<S>,
    /// The model's polygons against the scan points (point-cloud worlds only).
    pub scan_score: Option<M>,
    /// True faces the robot cannot reach, given a priori and not scored.
    pub a_priori_faces: Vec<AprioriFace>,
    /// `run.mcap`: the joint states, frames and range readings of every
    /// step, and the surface model's markers ([`record::bag::RunBag`]).
    pub bag: Vec<u8>,
    /// The robot time of the run, per activity of the robot clock.
    pub robot_time: hw::clock::RobotTime,
}

impl<S: SurfaceFigures + Serialize + Clone, M: ScanFigures + Serialize + Clone> FollowRun<S, M> {
    /// Whether the follower reported the current surface complete.
    pub fn completed(&self) -> bool {
        self.episode.end == RunEnd::Follower(Termination::SurfaceComplete)
    }

    /// Total wall time of each step, µs (0 for steps whose times were not
    /// recorded).
    pub fn step_micros(&self) -> Vec<Real> {
        self.episode
            .rows
            .iter()
            .map(|r| r.times.map_or(0.0, |t| t.total_us()))
            .collect()
    }

    /// The content of `run.json`.
    pub fn summary(&self) -> FollowSummary<FollowRunOptions, S, M> {
        let rows = &self.episode.rows;
        let mut modes = BTreeMap::new();
        let mut parts = StepTimes::default();
        for r in rows {
            *modes.entry(r.mode.clone()).or_insert(0) += 1;
            if let Some(t) = r.times {
                parts.update_us += t.update_us;
                parts.direction_us += t.direction_us;
                parts.kinematics_us += t.kinematics_us;
            }
        }
        let n = rows.len().max(1) as Real;
        parts.update_us /= n;
        parts.direction_us /= n;
        parts.kinematics_us /= n;
        let j = &self.judgement;
        // Against the true scene where there is one, else against the scan.
        let modelled_m2 = self
            .score
            .as_ref()
            .map(SurfaceFigures::modelled_m2)
            .or_else(|| self.scan_score.as_ref().map(ScanFigures::modelled_m2));
        FollowSummary {
            format_version: record::FORMAT_VERSION,
            scenario: self.source.clone(),
            robot: self.robot.clone(),
            seed: self.options.seed,
            sets: rows.len(),
            empty_sets: rows.iter().filter(|r| r.set_size == 0).count(),
            steps: rows.len(),
            completed: self.completed(),
            termination: self.episode.end.name().to_owned(),
            error: match &self.episode.end {
                RunEnd::Error(e) => Some(e.clone()),
                _ => None,
            },
            collisions: j.min_clearance_m.map(|_| {
                let mut steps: Vec<Option<u64>> = j.collisions.iter().map(|c| c.step).collect();
                steps.dedup();
                steps.len()
            }),
            collision_list: j.collisions.clone(),
            min_clearance_m: j.min_clearance_m,
            min_scan_clearance_m: j.min_scan_clearance_m,
            scan_close_poses: j.scan_close_poses,
            model_to_scan_max_m: self.scan_score.as_ref().and_then(ScanFigures::max_m),
            model_to_scan_within_lambda: self
                .scan_score
                .as_ref()
                .map(ScanFigures::within_lambda_fraction),
            motion_checks: j.motion_checks,
            a_priori_faces: self.a_priori_faces.iter().map(|f| f.normal).collect(),
            guard: self.episode.guard,
            modelled_m2,
            sets_per_m2: modelled_m2
                .filter(|m2| *m2 > 0.0)
                .map(|m2| rows.len() as Real / m2),
            step_us: StepTimeStats::from_micros(&self.step_micros()),
            robot_time_s: record::follow::FollowRobotTime::of(&self.robot_time),
            part_mean_us: parts,
            modes,
            start_joints: self.start_joints.clone(),
            end_joints: self.episode.end_joints.clone(),
            model: self.model.stats(),
            score: self.score.clone(),
            model_to_scan: self.scan_score.clone(),
            options: self.options.clone(),
        }
    }

    /// The run folder's files by name: `surface_model.json`,
    /// `surface_model.obj`, `steps.csv`, `path.ply`, `run.json` and
    /// `model_snapshots.json`.
    pub fn outputs(&self) -> Result<[(&'static str, String); 6], FollowRunError> {
        use record::follow::{PATH_PLY, STEPS_CSV, SURFACE_MODEL_JSON, SURFACE_MODEL_OBJ};
        Ok([
            (SURFACE_MODEL_JSON, pretty(&self.model.to_model_json())?),
            (SURFACE_MODEL_OBJ, self.model.to_obj()),
            (
                STEPS_CSV,
                record::follow::steps_csv(&self.episode.rows, self.start_joints.len()),
            ),
            (
                PATH_PLY,
                record::follow::path_ply(&self.episode.rows, &self.end_control_point),
            ),
            (
                record::explore::RUN_JSON,
                self.summary().to_json().map_err(JobError::from)?,
            ),
            (
                record::snapshots::MODEL_SNAPSHOTS_JSON,
                pretty(&self.snapshots)?,
            ),
        ])
    }

    /// Stage the run folder's files ([`outputs`](Self::outputs) and
    /// `run.mcap`).
    pub fn write(&self, staging: &record::Staging) -> Result<(), FollowRunError> {
        for (name, text) in self.outputs()? {
            staging.write(name, text).map_err(JobError::from)?;
        }
        staging
            .write(record::folder::RUN_MCAP, &self.bag)
            .map_err(JobError::from)?;
        Ok(())
    }
}

/// Pretty JSON with a final newline.
fn pretty<T: Serialize>(v: &T) -> Result<String, FollowRunError> {
    let mut s = serde_json::to_string_pretty(v)
        .map_err(|e| bad("output", format!("formatting JSON: {e}")))?;
    s.push('\n');
    Ok(s)
}

/// Files that mark another command's run folder.
const EXPLORE_FILES: [&str; 3] = [
    record::viewpoints::VIEWPOINTS_CSV,
    record::checkpoint::CHECKPOINT_JSON,
    record::blast::BLAST_INPUTS_JSON,
];

/// The whole `surveyor follow` job with the episode `run` gives (a
/// [`HardwareFollow`] on a ROS 2 robot, the simulator's
/// `sim::follow_job::SimFollow`): check the output folder (not a file, not
/// a `surveyor explore` run), run the episode, stage the run folder with
/// `scenario_toml` (the scenario as given, for the report's ground truth;
/// none for a scene file), let `finish` add files (the report), and move
/// everything into place, `run.json` last.
pub fn follow_with<S, M>(
    scenario_toml: Option<String>,
    out: &Path,
    run: impl FnOnce(
        &AtomicBool,
        &mut dyn FnMut(&StepRow, &Follower),
    ) -> Result<FollowRun<S, M>, FollowRunError>,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&StepRow, &Follower),
    finish: &mut dyn FnMut(&record::Staging) -> Result<(), String>,
) -> Result<FollowRun<S, M>, FollowRunError>
where
    S: SurfaceFigures + Serialize + Clone,
    M: ScanFigures + Serialize + Clone,
{
    check_follow_out(out)?;
    let run = run(stop, progress)?;
    let staging = record::Staging::new(out).map_err(JobError::from)?;
    run.write(&staging)?;
    if let Some(text) = scenario_toml {
        staging
            .write(record::folder::SCENARIO_TOML, text)
            .map_err(JobError::from)?;
    }
    finish(&staging).map_err(|message| bad(&out.display().to_string(), message))?;
    staging.commit().map_err(JobError::from)?;
    Ok(run)
}

/// An error unless `out` can take a follow run: a folder or nothing, not
/// holding a `surveyor explore` run (its files would be a mix the report
/// cannot read).
pub fn check_follow_out(out: &Path) -> Result<(), FollowRunError> {
    record::output::check_out_dir(out).map_err(JobError::from)?;
    for foreign in EXPLORE_FILES {
        if out.join(foreign).exists() {
            return Err(bad(
                &out.display().to_string(),
                format!("holds a `surveyor explore` run ({foreign}); give another --out"),
            ));
        }
    }
    Ok(())
}
