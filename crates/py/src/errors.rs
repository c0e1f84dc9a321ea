//! The workspace's typed errors as Python exceptions, each carrying the Rust
//! message: a file that cannot be read is an `OSError` (`FileNotFoundError`
//! when it is missing, `PermissionError` when it may not be read), anything
//! else a `ValueError`. Nothing here panics.

use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use robot::RobotError;
use scenario::ScenarioError;
use scene::SceneError;
use std::io::ErrorKind;
use std::path::Path;

/// A `ValueError` with `message`.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// The `OSError` subclass for an operating-system error of this kind.
fn os_error_of(kind: ErrorKind, message: String) -> PyErr {
    match kind {
        ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// The `OSError` for a file that could not be read, when only the message
/// of the operating-system error was kept: the kind is asked of the file
/// system again.
fn os_error_at(path: &Path, message: String) -> PyErr {
    let kind = match std::fs::File::open(path) {
        Ok(_) => ErrorKind::Other,
        Err(e) => e.kind(),
    };
    os_error_of(kind, message)
}

/// A robot error: `OSError` when a file (the URDF, or a collision mesh it
/// names) cannot be read, `ValueError` otherwise.
pub fn robot_error(e: &RobotError) -> PyErr {
    match e {
        RobotError::Io { path, .. } => os_error_at(path, e.to_string()),
        RobotError::MeshFile { path, .. } if std::fs::File::open(path).is_err() => {
            os_error_at(path, e.to_string())
        }
        _ => value_error(e.to_string()),
    }
}

/// A scene error: `OSError` when a file cannot be read or written,
/// `ValueError` otherwise.
pub fn scene_error(e: &SceneError) -> PyErr {
    match e {
        SceneError::Io { source, .. } | SceneError::Write { source, .. } => {
            os_error_of(source.kind(), e.to_string())
        }
        _ => value_error(e.to_string()),
    }
}

/// A scenario error: its robot or scene error as above, `ValueError` otherwise.
pub fn scenario_error(e: &ScenarioError) -> PyErr {
    match e {
        ScenarioError::Robot(r) => robot_error(r),
        ScenarioError::Scene(s) => scene_error(s),
        _ => value_error(e.to_string()),
    }
}
