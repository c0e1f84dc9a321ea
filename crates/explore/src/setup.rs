//! What an exploration starts from ([`Setup`]): the robot with its scanner
//! and where it stands, the parameters, the regions of interest, the
//! material table the classifier is trained on, the C-space model (built,
//! or loaded from its cache) and Stage One's planning state at the start
//! pose. Nothing here knows the scene.

use crate::{ExploreConfig, ExploreError, StageOne};
use geom::{Isometry3, Real};
use hw::clock::RobotTiming;
use plan::{CacheOutcome, CspaceModel};
use robot::Robot;
use sensor::{Scanner, ScannerConfig, SweepConfig};
use std::path::PathBuf;

/// Misses free space this much short of the scanner's range, metres (three
/// σ of the URG-04LX's 1 % noise at 4 m, rounded up).
pub const MISS_MARGIN_M: Real = 0.15;

/// What [`Setup::new`] is made from.
#[derive(Clone, Debug)]
pub struct SetupInputs {
    /// The robot, its scanner mounted.
    pub robot: Robot,
    /// Where its base stands.
    pub world_from_base: Isometry3,
    /// The scanner model.
    pub scanner: ScannerConfig,
    /// The sweep taken at every viewpoint (it replaces `config.sweep`).
    pub sweep: SweepConfig,
    /// The parameters.
    pub config: ExploreConfig,
    /// The regions of interest A1 ⊂ A2 ⊂ A3.
    pub regions: map::RegionsConfig,
    /// The start pose (assumed safe, A§6.1).
    pub start: Vec<Real>,
    /// The materials the classifier tells apart (empty: no material
    /// identification, and no Stage Two).
    pub materials: Vec<scene::Material>,
    /// Where the C-space model is cached (`None`: built every run).
    pub cspace_cache: Option<PathBuf>,
    /// Where the trained LRC is cached (`None`: trained every run).
    pub lrc_cache: Option<PathBuf>,
    /// The robot's joint limits and the scanner's scan time: how fast a
    /// continuous motion runs and how long a motion takes.
    pub timing: RobotTiming,
}

/// Everything a run starts from.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The robot (scanner mounted).
    pub robot: Robot,
    /// Where the robot's base stands.
    pub world_from_base: Isometry3,
    /// The parameters (the sweep set from [`SetupInputs::sweep`]).
    pub config: ExploreConfig,
    /// The regions of interest.
    pub regions: map::RegionsConfig,
    /// The scanner model.
    pub scanner: ScannerConfig,
    /// How far misses free space and predictions cast, metres.
    pub reach_m: Real,
    /// The start pose.
    pub start: Vec<Real>,
    /// The materials the classifier tells apart.
    pub materials: Vec<scene::Material>,
    /// The planning state before the first sweep.
    pub stage: StageOne,
    /// How the C-space model was obtained.
    pub cspace: String,
    /// Where the trained LRC is cached (`None`: trained every run).
    pub lrc_cache: Option<PathBuf>,
    /// The robot's joint limits and the scanner's scan time.
    pub timing: RobotTiming,
}

impl Setup {
    /// The same setup with Stage One's predicted sweeps scored by `gain`
    /// (a user's own [`crate::Gain`]; `[explore] gain` names the built-in
    /// ones). It is used when `selection = "information"`.
    pub fn with_gain(mut self, gain: std::sync::Arc<dyn crate::Gain>) -> Self {
        self.stage.set_gain(gain);
        self
    }

    /// The setup of `inputs`: the start within the joint limits, the
    /// C-space model built or loaded, the planning grid at the start pose.
    pub fn new(inputs: SetupInputs) -> Result<Self, ExploreError> {
        let SetupInputs {
            robot,
            world_from_base,
            scanner,
            sweep,
            mut config,
            regions,
            start,
            materials,
            cspace_cache,
            lrc_cache,
            timing,
        } = inputs;
        timing
            .check(robot.dof())
            .map_err(|message| ExploreError::Robot {
                robot: robot.name.clone(),
                message: format!("timing: {message}"),
            })?;
        config.sweep = sweep;
        // Rays without a return free space up to a little short of the range
        // (map's perfect-detection reading), and predictions cast as far.
        let reach_m = (scanner.max_range_m - MISS_MARGIN_M).max(scanner.min_range_m);
        let occupancy = map::OccupancyConfig {
            regions,
            free_misses_m: Some(reach_m),
            ..map::OccupancyConfig::default()
        };
        robot.check_within_limits(&start)?;
        let voxel = config.planning_voxel_m;
        let (model, outcome) = match &cspace_cache {
            Some(path) => {
                CspaceModel::load_or_build(path, &robot, &world_from_base, voxel, &config.plan)?
            }
            None => (
                CspaceModel::build(&robot, &world_from_base, voxel, &config.plan)?,
                CacheOutcome::Built("no cache file".into()),
            ),
        };
        let cspace = match outcome {
            CacheOutcome::Loaded => "loaded from cache".to_owned(),
            CacheOutcome::Built(why) => format!("built ({why})"),
        };
        let bearings = Scanner::new(scanner)?.bearings_rad().to_vec();
        let stage = StageOne::new(
            model,
            &occupancy,
            &bearings,
            reach_m,
            config.clone(),
            &start,
        )?;
        Ok(Self {
            robot,
            world_from_base,
            config,
            regions,
            scanner,
            reach_m,
            start,
            materials,
            stage,
            cspace,
            lrc_cache,
            timing,
        })
    }
}
