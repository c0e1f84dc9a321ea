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
    /// A value in a file is not what was expected.
    #[error("{file}, line {line}, `{field}`: {message}")]
    Field {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// The column or key.
        field: String,
        /// What was expected.
        message: String,
    },
    /// The folder is not a run folder this crate knows.
    #[error("{dir}: {message}")]
    NotARun {
        /// The folder.
        dir: String,
        /// What is missing.
        message: String,
    },
    /// Rebuilding the run's scenario (robot, scene) failed.
    #[error(transparent)]
    Sim(#[from] sim::SimError),
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
