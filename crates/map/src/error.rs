//! Errors of the map crate.

use crate::key::VoxelKey;
use std::path::PathBuf;

/// What can go wrong configuring a map or feeding it data. Every variant names
/// the field, file, row or voxel at fault. A call that fails leaves the map as
/// it was: inputs are checked before anything is written.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// A configuration field is out of its valid range.
    #[error("map config `{field}`: expected {expected}, got {got}")]
    Config {
        /// The field, dotted from the config root (`occupancy.voxel_m`).
        field: &'static str,
        /// What is accepted.
        expected: &'static str,
        /// What was given.
        got: String,
    },
    /// Input data (a sweep, a point list, a scan file) is unusable.
    #[error("{what}: {message}")]
    Input {
        /// The input at fault: a file path, `origins`, `points`, `sweep`.
        what: String,
        /// What is wrong, with the row and field when there is one.
        message: String,
    },
    /// A voxel key lies outside the occupancy grid (region A3).
    #[error("voxel {key} lies outside the occupancy grid")]
    OutsideGrid {
        /// The key.
        key: VoxelKey,
    },
    /// A C-space interference probability outside `[0, 1]` (A eq. 4.13).
    #[error("voxel {key}: C-space probability must be in [0, 1], got {value}")]
    Probability {
        /// The voxel.
        key: VoxelKey,
        /// The value given.
        value: f64,
    },
    /// Reading a scan file or writing the mesh failed.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
}

impl MapError {
    /// An [`MapError::Input`] about `what`.
    pub fn input(what: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Input {
            what: what.into(),
            message: message.into(),
        }
    }

    /// A [`MapError::Config`] error. Takes `got` by value so call sites can
    /// pass numbers and strings alike.
    #[allow(clippy::needless_pass_by_value)]
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
