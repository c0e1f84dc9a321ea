//! The explore crate's one error type.

use thiserror::Error;

/// What can go wrong when exploring.
#[derive(Debug, Error)]
pub enum ExploreError {
    /// A configuration value is out of range: the field, what was expected and
    /// what was given.
    #[error("explore config: {field} must be {expected}, got {got}")]
    Config {
        /// The field (dotted path as in a scenario file).
        field: &'static str,
        /// What the field accepts.
        expected: &'static str,
        /// The value given.
        got: String,
    },
    /// The robot cannot explore (no scanner, no tilt joint, ...).
    #[error("robot {robot}: {message}")]
    Robot {
        /// The robot's name.
        robot: String,
        /// What is wrong.
        message: String,
    },
    /// Kinematics failed.
    #[error(transparent)]
    Kinematics(#[from] robot::RobotError),
    /// Planning failed.
    #[error(transparent)]
    Plan(#[from] plan::PlanError),
    /// The map refused a value.
    #[error(transparent)]
    Map(#[from] map::MapError),
    /// The sensor configuration is invalid.
    #[error(transparent)]
    Sensor(#[from] sensor::SensorError),
}
