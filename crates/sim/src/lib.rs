#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`scenario`] | [`Scenario`] (TOML), [`scenario::builtin_scenario`], [`LoadedScenario`] |
//! | [`rig`] | the hardware traits [`Arm`], [`LineScanner`], [`RangeSensors`]; [`SimRig`] |
//! | [`sweep`] | [`tilt_sweep`]: nod the scanner through the hardware traits into a [`sensor::Sweep`] |
//! | [`metrics`] | [`metrics::coverage`], [`metrics::accuracy`] against the ground truth |
//! | [`safety`] | [`safety::robot_contacts`]: the robot's link shapes against the scene; [`safety::motion_contacts`] along a joint-space motion |
//! | [`range_sensors`] | [`range_sensors::RangeSensorsSpec`]: a scenario's range finders (single and rings) and range noise |
//! | [`scan_check`] | [`scan_check::ScanIndex`] (kd-tree over scan points), [`scan_check::scan_clearance`] (link capsules against a scan), [`scan_check::model_to_scan`] (model polygons against a scan) |
//! | [`surface_score`] | [`surface_score::score_surface_model`]: a surface model against the true faces, edges and corners |
//! | [`table_fit`] | [`table_fit::fit_table`]: a table plane fitted to scan points, as world frame and initial segment |
//! | [`scan_job`] | the `surveyor scan` job as library calls |
//! | [`explore_run`] | [`explore_run::run_exploration`]: AXBAM (both stages) through the hardware traits, every motion audited against the map and the ground truth; [`explore_run::ExploreRun::write`] (the `surveyor explore` files) |
//! | [`follow_run`] | [`follow_run::run_episode`]: a `follow::Follower` through the hardware traits with ground-truth safety; [`follow_run::FollowSetup`] (scenario or scene file → rig + follower), [`follow_run::FollowRun::outputs`] (the `surveyor follow` files) |

pub mod blast;
pub mod explore_run;
pub mod follow_run;
pub mod metrics;
pub mod model_snapshots;
pub mod range_sensors;
pub mod rig;
pub mod safety;
pub mod scan_check;
pub mod scan_job;
pub mod scenario;
pub mod surface_score;
pub mod sweep;
pub mod table_fit;

pub use rig::{Arm, LineScanner, RangeSensors, ScanReadings, SimRig};
pub use scenario::{LoadedScenario, Scenario};
pub use sweep::tilt_sweep;

/// What can go wrong running a scenario.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A scenario file or field is invalid.
    #[error("scenario {source_name}: {message}")]
    Scenario {
        /// The file or scenario name.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// The robot model rejected something.
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// The scene could not be built or loaded.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// An argument of a library call is invalid.
    #[error("{what}: {message}")]
    InvalidArgument {
        /// The argument.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// A sensor configuration is invalid.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
    /// Planning (the C-space model, safety) failed.
    #[error(transparent)]
    Plan(Box<plan::PlanError>),
    /// Exploration failed.
    #[error(transparent)]
    Explore(Box<explore::ExploreError>),
    /// A map refused a value.
    #[error(transparent)]
    Map(Box<map::MapError>),
    /// A scan was requested from a robot without a scanner.
    #[error("the robot carries no scanner")]
    NoScanner,
    /// The sweep's tilt joint does not exist.
    #[error("tilt joint {joint} does not exist: the robot has {dof} joints")]
    TiltJoint {
        /// 1-based joint number asked for.
        joint: usize,
        /// Joints the robot has.
        dof: usize,
    },
}

// Boxed: the planning and exploration errors are large, and `SimError` is
// returned on every path.
impl From<plan::PlanError> for SimError {
    fn from(e: plan::PlanError) -> Self {
        Self::Plan(Box::new(e))
    }
}

impl From<explore::ExploreError> for SimError {
    fn from(e: explore::ExploreError) -> Self {
        Self::Explore(Box::new(e))
    }
}

impl From<map::MapError> for SimError {
    fn from(e: map::MapError) -> Self {
        Self::Map(Box::new(e))
    }
}
