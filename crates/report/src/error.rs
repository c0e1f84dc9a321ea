//! Errors of report building.

use thiserror::Error;

/// Why a report could not be made.
#[derive(Debug, Error)]
pub enum ReportError {
    /// A file could not be read or parsed.
    #[error("{file}: {message}")]
    File {
        /// The file.
        file: String,
        /// What went wrong.
        message: String,
    },
    /// The run folder (its version, a file in it) could not be read.
    #[error(transparent)]
    Record(#[from] record::RecordError),
    /// Rebuilding the run's scenario (robot, scene) failed.
    #[error(transparent)]
    Scenario(#[from] scenario::ScenarioError),
    /// Forward kinematics failed on a recorded pose.
    #[error(transparent)]
    Robot(#[from] robot::RobotError),
    /// Reading a mesh or cloud failed.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
}

impl ReportError {
    /// A file error from anything displayable.
    pub fn file(file: &str, e: impl std::fmt::Display) -> Self {
        Self::File {
            file: file.to_owned(),
            message: e.to_string(),
        }
    }
}
