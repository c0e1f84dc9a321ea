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
    /// The hardware refused or failed.
    #[error(transparent)]
    Hw(#[from] hw::HwError),
    /// A run-folder file could not be written or read (the checkpoint).
    #[error(transparent)]
    Record(#[from] record::RecordError),
    /// The mapped surface could not be made a world to predict sweeps in.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// The material classifier could not be trained.
    #[error("material classifier: {0}")]
    Classifier(String),
    /// A run cannot be resumed from its checkpoint (another run's, or
    /// inconsistent).
    #[error("{what}: {message}")]
    Resume {
        /// The checkpoint, or what is inconsistent.
        what: String,
        /// Why.
        message: String,
    },
    /// A judge failed to judge.
    #[error("judge: {0}")]
    Judge(String),
}
