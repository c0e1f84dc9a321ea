//! The follow crate's one error type.

use thiserror::Error;

/// What can go wrong when following.
#[derive(Debug, Error)]
pub enum FollowError {
    /// A configuration value is out of range (names the field).
    #[error("follow config: {0}")]
    Config(String),
    /// The robot cannot be followed with (no range finder at the control point,
    /// wrong joint vector, ...).
    #[error("robot: {0}")]
    Robot(String),
    /// Kinematics failed (a wrong joint vector, a link out of range).
    #[error(transparent)]
    Kinematics(#[from] robot::RobotError),
    /// A judge could not check a pose or motion.
    #[error("{0}")]
    Judge(String),
    /// The surface model refused an update.
    #[error(transparent)]
    Surface(#[from] surface::SurfaceError),
}
