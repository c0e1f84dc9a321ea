//! The follow crate's one error type.

use geom::{Point3, Real, Vector3};
use thiserror::Error;

/// What can go wrong when following.
#[derive(Debug, Error)]
pub enum FollowError {
    /// A configuration value is out of range.
    #[error("follow config: {field}: expected {expected}, got {got}")]
    Config {
        /// The field, as named in the `[follow]` table.
        field: &'static str,
        /// What the field accepts.
        expected: &'static str,
        /// The value given.
        got: String,
    },
    /// The robot has no range finder at its control point, so it cannot
    /// follow a surface.
    #[error(
        "robot '{robot}' has no range finder at its control point (on link {link} within δ = {within_m} m of the tool point)"
    )]
    NoControlPointSensor {
        /// The robot's name.
        robot: String,
        /// Index of its tool link.
        link: usize,
        /// How far from the tool point a range finder was looked for (δ),
        /// metres.
        within_m: Real,
    },
    /// A step was given a number of range readings other than one per range
    /// finder.
    #[error("expected {expected} readings (one per range finder), got {got}")]
    Readings {
        /// The robot's range finders.
        expected: usize,
        /// The readings given.
        got: usize,
    },
    /// No start guess places the control point at the target with the tool
    /// axis as asked.
    #[error(
        "robot '{robot}' cannot place its control point at ({:.3}, {:.3}, {:.3}) with the tool axis along ({:.2}, {:.2}, {:.2}) from any of {guesses} start guesses",
        target.x, target.y, target.z, axis.x, axis.y, axis.z
    )]
    Unplaceable {
        /// The robot's name.
        robot: String,
        /// Where the control point was to stand.
        target: Point3,
        /// The direction the tool axis was to point in.
        axis: Vector3,
        /// How many start guesses were tried.
        guesses: usize,
    },
    /// Kinematics failed (a wrong joint vector, a link out of range).
    #[error(transparent)]
    Kinematics(#[from] robot::RobotError),
    /// A judge could not check a pose or motion (the judge's own error).
    #[error(transparent)]
    Judge(Box<dyn std::error::Error + Send + Sync>),
    /// The surface model refused an update.
    #[error(transparent)]
    Surface(#[from] surface::SurfaceError),
}
