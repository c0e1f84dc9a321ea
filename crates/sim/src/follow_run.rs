//! The surface-following episode runner (issue 9): a [`Follower`] driven
//! through the hardware traits, checked against the ground truth, with its
//! outputs (`surface_model.json`/`.obj`, `steps.csv`, `path.ply`, `run.json`,
//! and `model_snapshots.json`, the model's evolution: [`ModelSnapshots`]).
//!
//! * [`run_episode`] is the loop itself, for any hardware that implements
//!   [`Arm`] and [`RangeSensors`] (a real driver can replace [`SimRig`]): per
//!   step it reads every range finder, calls [`Follower::step`], checks the new
//!   pose and the straight joint motion to it against the ground truth when
//!   there is one ([`GroundTruth`]), records a [`StepRow`] and moves. It stops
//!   on the follower's termination, after `max_sets` sensor sets, or when the
//!   stop flag is raised (Ctrl-C: the steps so far are kept, termination
//!   `interrupted`).
//! * [`FollowSetup`] wires a scenario or a scene file, a robot and a start pose
//!   into a rig and a follower from [`FollowRunOptions`]; [`FollowSetup::run`]
//!   runs the episode and scores the model ([`FollowRun`]).
//! * [`FollowRun::outputs`] formats the output files; the caller writes them.
//!
//! Determinism: the rig's noise is seeded and the follower is deterministic, so
//! the same inputs and seed give the same `steps.csv` and `surface_model.json`
//! byte for byte, except for the wall-clock timing columns of `steps.csv` and
//! the step times of `run.json`; with [`FollowRunOptions::timings`] off those
//! columns are written empty and those times are 0, so every file repeats.

use crate::model_snapshots::ModelSnapshots;
use crate::rig::{Arm, RangeSensors};
use crate::safety::{min_clearance, motion_contacts, robot_contacts, smallest_link_radius};
use crate::scan_check::{
    ModelScanConfig, ModelScanScore, ScanIndex, model_to_scan, scan_clearance,
};
use crate::scenario::{LoadedScenario, build_robot, scene_mesh_loader};
use crate::surface_score::{SurfaceScore, SurfaceScoreConfig, not_resting_on, score_surface_model};
use crate::{SimError, SimRig};
use follow::{FollowConfig, FollowError, Follower, Mode, StepTimes, Termination};
use geom::{Aabb, Isometry3, Point3, Real, Vector3};
use robot::Robot;
use scene::{PointCloud, PointCloudWorld, Scene, SceneError, World};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use surface::{EdgeKey, SegmentId, SurfaceConfig, SurfaceError, SurfaceModel};

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

/// Ground-truth clearance is searched no farther than this from the links, metres.
pub const CLEARANCE_SEARCH_M: Real = 1.0;

/// Step of [`motion_contacts`] for robots without link capsules, metres.
pub const MOTION_STEP_WITHOUT_CAPSULES_M: Real = 0.01;

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
    /// The scenario, world, robot or rig.
    #[error(transparent)]
    Sim(#[from] SimError),
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
            && !(s.is_finite() && s >= 0.0)
        {
            return Err(bad(
                "noise_sigma_m",
                format!("expected a finite standard deviation ≥ 0 (metres), got {s}"),
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

/// A run ready to start: the rig at its start pose and everything the
/// follower needs.
#[derive(Clone, Debug)]
pub struct FollowSetup {
    /// The scenario name, or the scene file.
    pub source: String,
    /// The simulated robot and sensors in the ground-truth world.
    pub rig: SimRig,
    /// Start joints (the rig is there).
    pub start_joints: Vec<Real>,
    /// A-priori segments of the model (world frame).
    pub initial_segments: Vec<Vec<Point3>>,
    /// Height of the support the objects stand on: true faces facing down at
    /// this height are not scored ([`not_resting_on`]).
    pub support_z: Real,
    /// The options.
    pub options: FollowRunOptions,
}

/// `true` for a robot argument naming a URDF file.
fn is_urdf(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".urdf")
}

/// The override robot, with the scenario's `[range_sensors]` applied.
fn override_robot(name: &str, loaded: Option<&LoadedScenario>) -> Result<Robot, FollowRunError> {
    let mut robot = if is_urdf(name) {
        Robot::from_urdf_file_with(Path::new(name), None, &scene_mesh_loader)
            .map_err(SimError::from)?
    } else {
        match name {
            "point3" | "arm4" => build_robot(Some(name), None, None)?,
            other => {
                return Err(bad(
                    "robot",
                    format!(
                        "unknown robot `{other}`: expected point3, arm4 or a URDF file (FILE.urdf)"
                    ),
                ));
            }
        }
    };
    if let Some(l) = loaded {
        l.scenario
            .range_sensors
            .apply(&mut robot)
            .map_err(|message| SimError::Scenario {
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
        if let Some(c) =
            crate::safety::robot_contacts(robot, &frames, world_from_base, scene).first()
        {
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
            Some(name) if is_urdf(name) => s
                .robot
                .urdf
                .as_deref()
                .is_some_and(|u| loaded.base_dir.join(u) == Path::new(name)),
            Some(name) => s.robot.preset.as_deref() == Some(name),
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
                    .map_err(SimError::from)?;
                let target = s.world_from_base() * Point3::from(tool.translation.vector);
                joints_for(&robot, &world_from_base, &target, None)?
            }
        };
        let initial_segments = match &options.initial_segments {
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
        let mut rig = SimRig::new(
            robot,
            world,
            world_from_base,
            &start_joints,
            None,
            options.seed,
        )?;
        rig.set_range_noise_sigma_m(
            options
                .noise_sigma_m
                .unwrap_or(s.range_sensors.noise_sigma_m),
        )?;
        let setup = Self {
            source: s.name.clone(),
            rig,
            start_joints,
            initial_segments,
            support_z: 0.0,
            options: options.clone(),
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
        let mut rig = SimRig::new(
            robot,
            Arc::new(world),
            world_from_base,
            &start_joints,
            None,
            options.seed,
        )?;
        rig.set_range_noise_sigma_m(options.noise_sigma_m.unwrap_or(0.0))?;
        let setup = Self {
            source: path.display().to_string(),
            rig,
            start_joints,
            initial_segments,
            support_z: bounds.min.z,
            options: options.clone(),
        };
        setup.follower()?;
        Ok(setup)
    }

    /// The follower for this run: a new model with the initial segments.
    pub fn follower(&self) -> Result<Follower, FollowRunError> {
        let mut model = SurfaceModel::new(self.options.config.surface)?;
        for (i, seg) in self.initial_segments.iter().enumerate() {
            model.add_initial_segment(seg).map_err(|e| match e {
                SurfaceError::InitialSegment { message } => {
                    bad("initial segments", format!("segment {i}: {message}"))
                }
                e => e.into(),
            })?;
        }
        Ok(Follower::new(
            self.rig.robot().clone(),
            self.rig.world_from_base(),
            model,
            self.options.config.follow,
        )?)
    }

    /// Run the episode (see [`run_episode`]) and score the model against the
    /// ground truth when the world is a mesh scene; when it is a point cloud,
    /// measure the links' clearance from the scan points at every pose and
    /// the model polygons' distances to the scan ([`model_to_scan`], with the
    /// surface model's λ). `progress` is called after every step; raising
    /// `stop` ends the run after the current step.
    pub fn run(
        mut self,
        stop: &AtomicBool,
        progress: &mut dyn FnMut(&StepRow, &Follower),
    ) -> Result<FollowRun, FollowRunError> {
        let mut follower = self.follower()?;
        let world = Arc::new(self.rig.world().clone());
        let truth = world.as_scene().map(|scene| GroundTruth {
            scene,
            world_from_base: self.rig.world_from_base(),
        });
        let scan_index = match world.as_ref() {
            World::Cloud(c) => Some(ScanIndex::new(&c.cloud().points)?),
            World::Mesh(_) => None,
        };
        let scan = scan_index.as_ref().map(|scan| ScanTruth {
            scan,
            world_from_base: self.rig.world_from_base(),
        });
        let mut snapshots = ModelSnapshots::new();
        let episode = run_episode(
            &mut self.rig,
            &mut follower,
            truth.as_ref(),
            scan.as_ref(),
            self.options.max_sets,
            stop,
            &mut |row, f| {
                snapshots.observe(row.step + 1, f.model());
                progress(row, f);
            },
        )?;
        snapshots.finish(episode.rows.len() as u64, follower.model());
        let score = match world.as_scene() {
            Some(scene) => {
                let surface = follower.model().config();
                let cfg = SurfaceScoreConfig {
                    lambda_m: surface.lambda,
                    mu_deg: surface.mu_deg,
                    ..SurfaceScoreConfig::default()
                };
                Some(score_surface_model(
                    scene,
                    follower.model(),
                    &cfg,
                    &not_resting_on(self.support_z),
                )?)
            }
            None => None,
        };
        let scan_score = match &scan_index {
            Some(index) => {
                let cfg = ModelScanConfig {
                    lambda_m: follower.model().config().lambda,
                    ..ModelScanConfig::default()
                };
                Some(model_to_scan(follower.model(), index, &cfg)?)
            }
            None => None,
        };
        let robot = follower.robot().name.clone();
        let end_control_point = follower.control_point(&episode.end_joints)?;
        Ok(FollowRun {
            source: self.source,
            robot,
            start_joints: self.start_joints,
            end_control_point,
            options: self.options,
            episode,
            model: follower.into_model(),
            snapshots,
            score,
            scan_score,
        })
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
            Err(e) => Err(SimError::from(e).into()),
        },
        _ => as_cloud(),
    }
}

impl From<SceneError> for FollowRunError {
    fn from(e: SceneError) -> Self {
        Self::Sim(SimError::from(e))
    }
}

/// The true world, for safety checks during a run.
#[derive(Clone, Copy, Debug)]
pub struct GroundTruth<'a> {
    /// The scene's surfaces.
    pub scene: &'a Scene,
    /// Where the robot's base stands.
    pub world_from_base: Isometry3,
}

/// A real scan standing in for the truth (point-cloud worlds): the robot's
/// clearance from its points is measured at every pose.
#[derive(Clone, Copy, Debug)]
pub struct ScanTruth<'a> {
    /// The scan points (world frame).
    pub scan: &'a ScanIndex,
    /// Where the robot's base stands.
    pub world_from_base: Isometry3,
}

/// One step of a run (a row of `steps.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepRow {
    /// 0-based step number.
    pub step: u64,
    /// The mode that produced the direction.
    pub mode: Mode,
    /// The control point when the set was taken (world frame).
    pub control_point: Point3,
    /// The joints when the set was taken.
    pub joints: Vec<Real>,
    /// Sensor points in the set.
    pub set_size: usize,
    /// Wall time of the step's parts.
    pub times: StepTimes,
    /// The follower's link clearance from the model (within its influence
    /// distance), metres.
    pub link_clearance_m: Option<Real>,
    /// The current segment.
    pub current_segment: Option<SegmentId>,
    /// The current edge.
    pub current_edge: Option<EdgeKey>,
}

/// A ground-truth contact during a run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Collision {
    /// The step whose motion touched the scene (`None`: the start pose).
    pub step: Option<u64>,
    /// Name of the link.
    pub link: String,
    /// Where along the step's joint motion (`0` start, `1` end).
    pub t: Real,
}

/// Why a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunEnd {
    /// The follower stopped (P§3.4).
    Follower(Termination),
    /// The budget of sensor sets was used up.
    MaxSets,
    /// The stop flag was raised.
    Interrupted,
    /// A step or a move failed after the run had started; the steps before it
    /// are kept.
    Error(String),
}

impl RunEnd {
    /// Name used in files: the follower's termination, `max_sets`,
    /// `interrupted` or `error`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Follower(t) => t.name(),
            Self::MaxSets => "max_sets",
            Self::Interrupted => "interrupted",
            Self::Error(_) => "error",
        }
    }
}

/// What [`run_episode`] recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    /// One row per step.
    pub rows: Vec<StepRow>,
    /// Why it ended.
    pub end: RunEnd,
    /// The joints at the end.
    pub end_joints: Vec<Real>,
    /// Ground-truth contacts (empty without a ground truth).
    pub collisions: Vec<Collision>,
    /// Smallest ground-truth clearance of the links from the scene over the
    /// poses visited (searched within [`CLEARANCE_SEARCH_M`]); `None` without
    /// a ground truth.
    pub min_clearance_m: Option<Real>,
    /// Configurations checked along the motions.
    pub motion_checks: usize,
    /// Smallest distance of the link capsules (links ≥ 1) from the scan points
    /// over the poses visited ([`scan_clearance`]); `None` without a scan or
    /// without link capsules.
    pub min_scan_clearance_m: Option<Real>,
    /// Poses (the start included) at which a link capsule came closer than
    /// δ/2 (half the follower's desired distance) to a scan point; `None`
    /// without a scan or without link capsules.
    pub scan_close_poses: Option<usize>,
}

/// What [`run_episode`] measures at every pose.
#[derive(Default)]
struct PoseTally {
    collisions: Vec<Collision>,
    min_clear: Option<Real>,
    min_scan: Option<Real>,
    scan_close: usize,
}

/// Drive `follower` through the hardware until it terminates, `max_sets`
/// sensor sets have been taken, or `stop` is raised (checked before every
/// step). Each step: read every range finder, [`Follower::step`], check the
/// new pose ([`robot_contacts`]) and the straight joint motion to it
/// ([`motion_contacts`], steps of half the smallest link radius, or
/// [`MOTION_STEP_WITHOUT_CAPSULES_M`]) against `truth`, record the row, move.
/// With a `scan` (a point-cloud world has no solid truth) every pose's link
/// clearance from the scan points is measured instead ([`scan_clearance`]),
/// and the poses closer than δ/2 (the follower's desired distance) counted.
///
/// Errors before the first step (reading the joints, the start pose's
/// checks) are returned; a failure once the run is under way ends it with
/// [`RunEnd::Error`], keeping the steps so far.
pub fn run_episode<H: Arm + RangeSensors>(
    hw: &mut H,
    follower: &mut Follower,
    truth: Option<&GroundTruth<'_>>,
    scan: Option<&ScanTruth<'_>>,
    max_sets: u64,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&StepRow, &Follower),
) -> Result<Episode, FollowRunError> {
    let robot = follower.robot().clone();
    let motion_step =
        smallest_link_radius(&robot).map_or(MOTION_STEP_WITHOUT_CAPSULES_M, |r| 0.5 * r);
    let mut q = hw.joints();
    robot.check_joints(&q).map_err(SimError::from)?;
    let scan_close_m = 0.5 * follower.config().desired_distance_m;
    let mut rows = Vec::new();
    let mut tally = PoseTally::default();
    let mut motion_checks = 0;
    let mut frames = Vec::with_capacity(robot.links.len());
    let mut check_pose =
        |q: &[Real], step: Option<u64>, tally: &mut PoseTally| -> Result<(), FollowRunError> {
            if truth.is_some() || scan.is_some() {
                robot.fk_into(q, &mut frames).map_err(SimError::from)?;
            }
            if let Some(s) = scan
                && let Some(d) = scan_clearance(&robot, &frames, &s.world_from_base, s.scan)
            {
                tally.min_scan = Some(tally.min_scan.map_or(d, |m: Real| m.min(d)));
                if d < scan_close_m {
                    tally.scan_close += 1;
                }
            }
            if let Some(t) = truth {
                for c in robot_contacts(&robot, &frames, &t.world_from_base, t.scene) {
                    tally.collisions.push(Collision {
                        step,
                        link: robot.links[c.link.0].name.clone(),
                        t: 1.0,
                    });
                }
                let d = min_clearance(
                    &robot,
                    &frames,
                    &t.world_from_base,
                    t.scene,
                    CLEARANCE_SEARCH_M,
                );
                tally.min_clear = Some(tally.min_clear.map_or(d, |m: Real| m.min(d)));
            }
            Ok(())
        };
    check_pose(&q, None, &mut tally)?;
    let end = loop {
        if stop.load(Ordering::Relaxed) {
            break RunEnd::Interrupted;
        }
        if rows.len() as u64 >= max_sets {
            break RunEnd::MaxSets;
        }
        let readings = match hw.read_all() {
            Ok(r) => r,
            Err(e) => break RunEnd::Error(e.to_string()),
        };
        let points: Vec<Option<Point3>> = readings.iter().map(|r| r.map(|s| s.point)).collect();
        let step = match follower.step(&q, &points) {
            Ok(s) => s,
            Err(e) => break RunEnd::Error(e.to_string()),
        };
        let n = rows.len() as u64;
        let row = StepRow {
            step: n,
            mode: step.mode,
            control_point: step.control_point,
            joints: q.clone(),
            set_size: step.set_size,
            times: step.times,
            link_clearance_m: step.link_clearance,
            current_segment: step.current_segment,
            current_edge: step.current_edge,
        };
        rows.push(row);
        if let Some(t) = step.termination {
            if let Some(r) = rows.last() {
                progress(r, follower);
            }
            break RunEnd::Follower(t);
        }
        let next: Vec<Real> = q.iter().zip(&step.dq).map(|(a, d)| a + d).collect();
        if let Some(t) = truth {
            match motion_contacts(&robot, &q, &next, &t.world_from_base, t.scene, motion_step) {
                Ok(m) => {
                    motion_checks += m.checks;
                    // Both end poses are checked with every link on their own
                    // (the start as the previous step's end); here only a
                    // contact strictly inside the motion. (`motion_contacts`
                    // stops at the first contact, so a motion that starts in
                    // contact is not searched further.)
                    if let Some(c) = m.first_contact.filter(|c| c.t > 0.0 && c.t < 1.0) {
                        tally.collisions.push(Collision {
                            step: Some(n),
                            link: robot.links[c.contact.link.0].name.clone(),
                            t: c.t,
                        });
                    }
                }
                Err(e) => break RunEnd::Error(e.to_string()),
            }
        }
        if let Err(e) = hw.move_to(&next) {
            break RunEnd::Error(format!("step {n}: moving to the next pose: {e}"));
        }
        q = hw.joints();
        if let Err(e) = check_pose(&q, Some(n), &mut tally) {
            break RunEnd::Error(e.to_string());
        }
        if let Some(r) = rows.last() {
            progress(r, follower);
        }
    };
    let measured_scan = scan.is_some() && tally.min_scan.is_some();
    Ok(Episode {
        rows,
        end,
        end_joints: q,
        collisions: tally.collisions,
        min_clearance_m: tally.min_clear,
        motion_checks,
        min_scan_clearance_m: tally.min_scan,
        scan_close_poses: measured_scan.then_some(tally.scan_close),
    })
}

/// A finished run: the episode, the model and its score.
#[derive(Clone, Debug)]
pub struct FollowRun {
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
    /// The surface model built.
    pub model: SurfaceModel,
    /// The model's evolution: copies at evenly spaced set counts and at the
    /// end ([`ModelSnapshots`]).
    pub snapshots: ModelSnapshots,
    /// The model scored against the true scene (`None` for point-cloud worlds).
    pub score: Option<SurfaceScore>,
    /// The model's polygons against the scan points (point-cloud worlds only).
    pub scan_score: Option<ModelScanScore>,
}

/// Mean, median and 95th percentile of step times, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StepTimeStats {
    /// Mean.
    pub mean: Real,
    /// Median.
    pub median: Real,
    /// 95th percentile (nearest rank).
    pub p95: Real,
}

impl StepTimeStats {
    /// Summarise samples (zeros for none).
    pub fn from_micros(samples: &[Real]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let t = surface::UpdateTimes::from_micros(samples);
        Self {
            mean: samples.iter().sum::<Real>() / samples.len() as Real,
            median: t.median,
            p95: t.p95,
        }
    }
}

/// `run.json`.
#[derive(Clone, Debug, Serialize)]
pub struct RunJson<'a> {
    /// The scenario name, or the scene file.
    pub scenario: &'a str,
    /// The robot.
    pub robot: &'a str,
    /// Seed of the range noise.
    pub seed: u64,
    /// Sensor sets taken (one per step).
    pub sets: usize,
    /// Of which sets without any point.
    pub empty_sets: usize,
    /// Follower steps (rows of `steps.csv`).
    pub steps: usize,
    /// The follower reported the current surface complete.
    pub completed: bool,
    /// Why the run ended (see [`RunEnd::name`]).
    pub termination: &'static str,
    /// The error that ended the run, when it was one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<&'a str>,
    /// Poses or motions with a ground-truth contact: the start pose, and each
    /// step whose motion or end pose touched the scene (`null` without a mesh
    /// ground truth).
    pub collisions: Option<usize>,
    /// The contacts (per link at a pose, the first along a motion).
    pub collision_list: &'a [Collision],
    /// Smallest ground-truth clearance of the links, metres.
    pub min_clearance_m: Option<Real>,
    /// Point-cloud worlds: smallest distance of the link capsules from the
    /// scan points over the poses visited, metres (`null` for mesh worlds).
    pub min_scan_clearance_m: Option<Real>,
    /// Point-cloud worlds: poses at which a link capsule came closer than
    /// δ/2 to a scan point (`null` for mesh worlds).
    pub scan_close_poses: Option<usize>,
    /// Point-cloud worlds: the largest distance from a non-initial model
    /// polygon to the nearest scan point, metres (`null` for mesh worlds or
    /// without such polygons; details in `model_to_scan`).
    pub model_to_scan_max_m: Option<Real>,
    /// Point-cloud worlds: the area fraction of the non-initial model
    /// polygons within λ of a scan point (`null` for mesh worlds).
    pub model_to_scan_within_lambda: Option<Real>,
    /// Configurations checked along the motions.
    pub motion_checks: usize,
    /// Wall time per step (update + direction + kinematics), µs.
    pub step_us: StepTimeStats,
    /// Mean time of each part of a step, µs.
    pub part_mean_us: StepTimes,
    /// Steps per mode.
    pub modes: BTreeMap<&'static str, u64>,
    /// Start joints.
    pub start_joints: &'a [Real],
    /// End joints.
    pub end_joints: &'a [Real],
    /// The model's counts.
    pub model: surface::ModelStats,
    /// The model scored against the ground truth (mesh worlds).
    pub score: Option<&'a SurfaceScore>,
    /// The model's polygons against the scan points, per polygon
    /// (point-cloud worlds).
    pub model_to_scan: Option<&'a ModelScanScore>,
    /// The options (with the configuration in effect).
    pub options: &'a FollowRunOptions,
}

impl FollowRun {
    /// Whether the follower reported the current surface complete.
    pub fn completed(&self) -> bool {
        self.episode.end == RunEnd::Follower(Termination::SurfaceComplete)
    }

    /// Total wall time of each step, µs.
    pub fn step_micros(&self) -> Vec<Real> {
        self.episode
            .rows
            .iter()
            .map(|r| r.times.update_us + r.times.direction_us + r.times.kinematics_us)
            .collect()
    }

    /// The content of `run.json`.
    pub fn run_json(&self) -> RunJson<'_> {
        let rows = &self.episode.rows;
        let mut modes = BTreeMap::new();
        let mut parts = StepTimes::default();
        for r in rows {
            *modes.entry(r.mode.name()).or_insert(0) += 1;
            parts.update_us += r.times.update_us;
            parts.direction_us += r.times.direction_us;
            parts.kinematics_us += r.times.kinematics_us;
        }
        let n = rows.len().max(1) as Real;
        parts.update_us /= n;
        parts.direction_us /= n;
        parts.kinematics_us /= n;
        // Timings off: 0, so run.json is the same byte for byte per seed.
        let micros = if self.options.timings {
            self.step_micros()
        } else {
            parts = StepTimes::default();
            vec![0.0; rows.len()]
        };
        RunJson {
            scenario: &self.source,
            robot: &self.robot,
            seed: self.options.seed,
            sets: rows.len(),
            empty_sets: rows.iter().filter(|r| r.set_size == 0).count(),
            steps: rows.len(),
            completed: self.completed(),
            termination: self.episode.end.name(),
            error: match &self.episode.end {
                RunEnd::Error(e) => Some(e),
                _ => None,
            },
            collisions: self.episode.min_clearance_m.map(|_| {
                let mut steps: Vec<Option<u64>> =
                    self.episode.collisions.iter().map(|c| c.step).collect();
                steps.dedup();
                steps.len()
            }),
            collision_list: &self.episode.collisions,
            min_clearance_m: self.episode.min_clearance_m,
            min_scan_clearance_m: self.episode.min_scan_clearance_m,
            scan_close_poses: self.episode.scan_close_poses,
            model_to_scan_max_m: self.scan_score.as_ref().and_then(|s| s.max_m),
            model_to_scan_within_lambda: self.scan_score.as_ref().map(|s| s.within_lambda_fraction),
            motion_checks: self.episode.motion_checks,
            step_us: StepTimeStats::from_micros(&micros),
            part_mean_us: parts,
            modes,
            start_joints: &self.start_joints,
            end_joints: &self.episode.end_joints,
            model: self.model.stats(),
            score: self.score.as_ref(),
            model_to_scan: self.scan_score.as_ref(),
            options: &self.options,
        }
    }

    /// `steps.csv`: `step,mode,x,y,z,q1..qn,set_size,update_us,direction_us,
    /// kinematics_us,link_clearance_m,current_segment,current_edge`; empty
    /// fields for no value, and for the times when timings are off.
    pub fn steps_csv(&self) -> String {
        let dof = self.start_joints.len();
        let mut out = String::from("step,mode,x,y,z");
        for i in 1..=dof {
            let _ = write!(out, ",q{i}");
        }
        out.push_str(
            ",set_size,update_us,direction_us,kinematics_us,link_clearance_m,current_segment,current_edge\n",
        );
        let opt = |v: Option<String>| v.unwrap_or_default();
        for r in &self.episode.rows {
            let p = r.control_point;
            let _ = write!(out, "{},{},{},{},{}", r.step, r.mode.name(), p.x, p.y, p.z);
            for q in &r.joints {
                let _ = write!(out, ",{q}");
            }
            let _ = write!(out, ",{}", r.set_size);
            if self.options.timings {
                let _ = write!(
                    out,
                    ",{:.3},{:.3},{:.3}",
                    r.times.update_us, r.times.direction_us, r.times.kinematics_us
                );
            } else {
                out.push_str(",,,");
            }
            let _ = writeln!(
                out,
                ",{},{},{}",
                opt(r.link_clearance_m.map(|v| v.to_string())),
                opt(r.current_segment.map(|s| s.0.to_string())),
                opt(r.current_edge.map(|e| e.0.to_string()))
            );
        }
        out
    }

    /// `path.ply`: the control point at every step, then where the run ended
    /// (when that differs from the last step's), as ASCII PLY vertices joined
    /// by edges in order.
    pub fn path_ply(&self) -> String {
        let mut pts: Vec<Point3> = self.episode.rows.iter().map(|r| r.control_point).collect();
        if pts.last() != Some(&self.end_control_point) {
            pts.push(self.end_control_point);
        }
        let edges = pts.len().saturating_sub(1);
        let mut out = format!(
            "ply\nformat ascii 1.0\ncomment surveyor follow: control-point path ({} steps)\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement edge {edges}\nproperty int vertex1\nproperty int vertex2\nend_header\n",
            self.episode.rows.len(),
            pts.len()
        );
        for p in &pts {
            let _ = writeln!(out, "{} {} {}", p.x, p.y, p.z);
        }
        for i in 0..edges {
            let _ = writeln!(out, "{} {}", i, i + 1);
        }
        out
    }

    /// The output files by name: `surface_model.json`, `surface_model.obj`,
    /// `steps.csv`, `path.ply`, `run.json` and `model_snapshots.json`.
    pub fn outputs(&self) -> Result<[(&'static str, String); 6], FollowRunError> {
        Ok([
            ("surface_model.json", pretty(&self.model.to_model_json())?),
            ("surface_model.obj", self.model.to_obj()),
            ("steps.csv", self.steps_csv()),
            ("path.ply", self.path_ply()),
            ("run.json", pretty(&self.run_json())?),
            ("model_snapshots.json", pretty(&self.snapshots)?),
        ])
    }
}

/// Pretty JSON with a final newline.
fn pretty<T: Serialize>(v: &T) -> Result<String, FollowRunError> {
    let mut s = serde_json::to_string_pretty(v)
        .map_err(|e| bad("output", format!("formatting JSON: {e}")))?;
    s.push('\n');
    Ok(s)
}
