#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`file`](mod@file) | [`Scenario`] (TOML), [`LoadedScenario`] (a scenario and its folder): build its robot and world |
//! | [`builtin`] | [`builtin_scenario`], [`BUILTIN_NAMES`] |
//! | [`robots`] | [`RobotChoice`]: a built-in robot or a URDF file, the one parser every command uses; [`mount_scanner`] |
//! | [`range_sensors`] | [`range_sensors::RangeSensorsSpec`]: a scenario's range finders (single and rings) and range noise |
//! | [`ros2`](mod@ros2) | [`ros2::Ros2Spec`]: the `[ros2]` table (topics, joint names, tolerances of a ROS 2 robot) |
//! | [`job`] | [`job::explore::HardwareExplore`], [`job::explore::explore_with`]: a scenario's run on any hardware and its run folder; [`job::JobError`] |
//! | [`mjcf`] | [`mjcf::model`]: the scenario as a MuJoCo model (MJCF) and the sidecar a physics robot serving it needs |
//! | [`table_fit`] | [`table_fit::fit_table`]: a table plane fitted to scan points, as world frame and initial segment |

pub mod builtin;
pub mod file;
pub mod job;
pub mod mjcf;
pub mod range_sensors;
pub mod robots;
pub mod ros2;
pub mod table_fit;

pub use builtin::{BUILTIN_NAMES, builtin_scenario};
pub use file::{LoadedScenario, MetricsConfig, RobotSpec, ScannerSpec, Scenario};
pub use range_sensors::RangeSensorsSpec;
pub use robots::{RobotChoice, is_urdf_name, mount_scanner, scene_mesh_loader};

/// What can go wrong reading a scenario or building what it describes.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
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
}
