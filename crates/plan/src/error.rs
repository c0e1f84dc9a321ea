//! The plan crate's one error type.

use std::path::PathBuf;
use thiserror::Error;

/// What can go wrong when building, loading or using the C-space model, or
/// selecting a Stage Two pose.
#[derive(Debug, Error)]
pub enum PlanError {
    /// A configuration value is out of range: the field, what was expected and
    /// what was given.
    #[error("plan config: {field} must be {expected}, got {got}")]
    Config {
        /// The field (dotted path as in a scenario file).
        field: &'static str,
        /// What the field accepts.
        expected: &'static str,
        /// The value given.
        got: String,
    },
    /// The robot cannot be planned for (a joint without finite limits, no
    /// bounding ellipsoid, ...).
    #[error("robot {robot}: {message}")]
    Robot {
        /// The robot's name.
        robot: String,
        /// What is wrong.
        message: String,
    },
    /// A joint vector of the wrong length or with non-finite values.
    #[error(transparent)]
    Kinematics(#[from] robot::RobotError),
    /// The map refused a value.
    #[error(transparent)]
    Map(#[from] map::MapError),
    /// A Stage Two pose-selection target (a disc's centre and normal) that
    /// cannot be aimed at: the field, what was expected and what was given.
    #[error("pose target: {field} must be {expected}, got {got}")]
    Target {
        /// `centre` or `normal`.
        field: &'static str,
        /// What the field accepts.
        expected: &'static str,
        /// The value given.
        got: String,
    },
    /// An argument of a library call is invalid.
    #[error("{what}: {message}")]
    InvalidArgument {
        /// The argument.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// The cache file could not be read or written.
    #[error("C-space cache {path}: {message}")]
    Cache {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl PlanError {
    pub(crate) fn config(
        field: &'static str,
        expected: &'static str,
        got: impl std::fmt::Display,
    ) -> Self {
        Self::Config {
            field,
            expected,
            got: got.to_string(),
        }
    }
}
