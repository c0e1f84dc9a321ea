//! The `surveyor scan` job: one tilt sweep from a pose, written as a PLY and
//! scored against the ground truth. Split in steps so the caller can time and
//! report each.

use crate::SimError;
use crate::metrics::{AccuracyReport, CoverageReport, accuracy, coverage};
use crate::rig::SimRig;
use geom::{Aabb, Isometry3, Point3, Real};
use hw::tilt_sweep;
use plan::contact::{Contact, robot_contacts};
use robot::Robot;
use scenario::{LoadedScenario, MetricsConfig, RobotChoice, mount_scanner};
use scene::{PointCloudWorld, SceneError, World};
use sensor::{Scanner, ScannerConfig, Sweep, SweepConfig};
use std::path::Path;
use std::sync::Arc;

/// Everything a scan needs, resolved.
#[derive(Debug)]
pub struct ScanSetup {
    /// The robot (with a scanner mounted).
    pub robot: Robot,
    /// The ground truth.
    pub world: Arc<World>,
    /// Where the base stands.
    pub world_from_base: Isometry3,
    /// The pose to sweep from.
    pub joints: Vec<Real>,
    /// Scanner model.
    pub scanner: ScannerConfig,
    /// Sweep.
    pub sweep: SweepConfig,
    /// Metrics settings.
    pub metrics: MetricsConfig,
    /// Noise seed.
    pub seed: u64,
}

/// What a scan produced.
#[derive(Debug)]
pub struct ScanOutcome {
    /// The sweep.
    pub sweep: Sweep,
    /// Links touching the scene at the sweep pose (must be empty).
    pub contacts: Vec<Contact>,
}

/// Scores of a scan against a mesh ground truth.
#[derive(Debug)]
pub struct ScanScores {
    /// Coverage of the true surfaces.
    pub coverage: CoverageReport,
    /// Accuracy of the points.
    pub accuracy: AccuracyReport,
}

/// A world from a mesh or point-cloud file placed as-is: `.obj`/`.stl` are
/// meshes, `.pcd`/`.txt`/`.xyz`/`.csv`/`.pts` clouds, `.ply` a mesh when it has
/// faces and a cloud otherwise.
pub fn world_from_file(path: &Path) -> Result<World, SimError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let as_mesh = |m| -> Result<World, SimError> {
        let materials = scene::default_materials();
        Ok(World::Mesh(scene::Scene::from_mesh(
            &path.display().to_string(),
            m,
            materials,
            scene::MaterialId(0),
        )?))
    };
    let as_cloud = || -> Result<World, SimError> {
        let cloud = scene::io::load_cloud(path)?;
        Ok(World::Cloud(PointCloudWorld::new(cloud, None, None)?))
    };
    match ext.as_str() {
        "obj" | "stl" => as_mesh(scene::io::load_mesh(path, 1.0)?),
        "ply" => match scene::io::load_mesh(path, 1.0) {
            Ok(m) => as_mesh(m),
            Err(SceneError::Invalid { .. }) => as_cloud(),
            Err(e) => Err(e.into()),
        },
        _ => as_cloud(),
    }
}

impl ScanSetup {
    /// From a scenario; `joints` defaults to its start pose, `tilt_deg` to its sweep.
    pub fn from_scenario(
        loaded: &LoadedScenario,
        joints: Option<Vec<Real>>,
        tilt_deg: Option<Real>,
        seed: u64,
    ) -> Result<Self, SimError> {
        let s = &loaded.scenario;
        let robot = loaded.build_robot()?;
        let world = Arc::new(loaded.build_world()?);
        let spec = s.scanner.clone().unwrap_or_default();
        let mut robot = robot;
        mount_scanner(&mut robot, spec.mount.as_ref());
        let mut sweep = spec.sweep;
        if let Some(t) = tilt_deg {
            sweep.tilt_deg = t;
        }
        sweep.validate_with(&spec.config)?;
        let joints = joints.unwrap_or_else(|| s.robot.start_joints.clone());
        robot.check_within_limits(&joints)?;
        Ok(Self {
            robot,
            world,
            world_from_base: s.world_from_base(),
            joints,
            scanner: spec.config,
            sweep,
            metrics: s.metrics,
            seed,
        })
    }

    /// From a scene file (geometry placed as-is in the world frame) and a robot
    /// preset or URDF (with an optional tip link, see
    /// [`RobotChoice::parse`]) standing at `world_from_base`. Coverage is scored within
    /// reach of the scanner: a box of half-size max range + 1 m around the base.
    pub fn from_scene_file(
        scene_file: &Path,
        robot_name_or_urdf: &str,
        tip: Option<&str>,
        world_from_base: Isometry3,
        joints: Vec<Real>,
        tilt_deg: Option<Real>,
        seed: u64,
    ) -> Result<Self, SimError> {
        let world = Arc::new(world_from_file(scene_file)?);
        let mut robot = RobotChoice::parse(robot_name_or_urdf, tip)?.build()?;
        mount_scanner(&mut robot, None);
        robot.check_within_limits(&joints)?;
        let mut sweep = SweepConfig::default();
        if let Some(t) = tilt_deg {
            sweep.tilt_deg = t;
        }
        let scanner = ScannerConfig::default();
        sweep.validate_with(&scanner)?;
        let mut metrics = MetricsConfig::default();
        let base = Point3::from(world_from_base.translation.vector);
        metrics.sampling.region = Some(Aabb::new(base, base).loosened(scanner.max_range_m + 1.0));
        Ok(Self {
            robot,
            world,
            world_from_base,
            joints,
            scanner,
            sweep,
            metrics,
            seed,
        })
    }

    /// Sweep from the pose, and check the pose for contacts with the scene.
    pub fn run(&self, progress: &mut dyn FnMut(usize, usize)) -> Result<ScanOutcome, SimError> {
        let scanner = Scanner::new(self.scanner)?;
        let mut rig = SimRig::new(
            self.robot.clone(),
            Arc::clone(&self.world),
            self.world_from_base,
            &self.joints,
            Some(scanner),
            self.seed,
        )?;
        let sweep = tilt_sweep(
            &mut rig,
            &self.robot,
            &self.world_from_base,
            &self.sweep,
            progress,
        )?;
        let contacts = match self.world.as_scene() {
            Some(scene) => {
                let frames = self.robot.forward_kinematics(&self.joints)?;
                robot_contacts(&self.robot, &frames, &self.world_from_base, scene)
            }
            None => Vec::new(),
        };
        Ok(ScanOutcome { sweep, contacts })
    }

    /// Coverage and accuracy against a mesh ground truth (`None` for point-cloud
    /// worlds, whose true surface is unknown); an error for invalid metrics settings.
    pub fn score(&self, sweep: &Sweep) -> Result<Option<ScanScores>, SimError> {
        let Some(scene) = self.world.as_scene() else {
            return Ok(None);
        };
        let points = sweep.positions();
        Ok(Some(ScanScores {
            coverage: coverage(scene, &points, &self.metrics)?,
            accuracy: accuracy(scene, &points, 0.5),
        }))
    }
}
