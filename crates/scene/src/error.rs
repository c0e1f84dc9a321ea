//! Errors of the scene crate.

use std::path::PathBuf;

/// What can go wrong building or loading a scene. Every variant names the file,
/// object or field at fault, so the message alone tells the user what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be opened or read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A file could not be created or written.
    #[error("{path}: cannot write: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A file's contents do not follow its format.
    #[error("{path}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line, when the format is line-oriented and the fault has one.
        line: Option<usize>,
        /// What was found and what was expected.
        message: String,
    },
    /// The file's format is not one surveyor reads.
    #[error("{path}: unsupported file type (expected {expected})")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// The formats accepted here.
        expected: &'static str,
    },
    /// One ray of a rays file ([`crate::io::rays`]) is not a finite origin
    /// with a unit direction (when reading, or before writing).
    #[error("{path}: ray {index}: {message}")]
    Ray {
        /// The file.
        path: PathBuf,
        /// 0-based index of the ray (its record starts at byte `24 × index`).
        index: usize,
        /// What is wrong, with the values found.
        message: String,
    },
    /// Geometry that parses but cannot be used (empty, non-finite, bad indices).
    #[error("{what}: {message}")]
    Invalid {
        /// The file, object or field at fault.
        what: String,
        /// What is wrong.
        message: String,
    },
}

impl SceneError {
    /// An [`SceneError::Invalid`] for `what`.
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Invalid {
            what: what.into(),
            message: message.into(),
        }
    }

    /// A [`SceneError::Parse`] error.
    pub fn parse(
        path: impl Into<PathBuf>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        Self::Parse {
            path: path.into(),
            line,
            message: message.into(),
        }
    }
}

impl From<geom::MeshError> for SceneError {
    fn from(e: geom::MeshError) -> Self {
        Self::Invalid {
            what: e.what,
            message: e.message,
        }
    }
}
