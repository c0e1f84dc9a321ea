//! The record crate's one error type.

use std::path::Path;

/// What can go wrong writing or reading a run folder.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A file could not be written, read or renamed.
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
    /// The folder was written in another format version.
    #[error(
        "{dir}: a run folder of format version {found}; this surveyor reads version {expected}{hint}"
    )]
    Version {
        /// The folder.
        dir: String,
        /// The version found.
        found: u32,
        /// The version read.
        expected: u32,
        /// What to do about it.
        hint: &'static str,
    },
    /// The folder is not a run folder.
    #[error("{dir}: {message}")]
    NotARun {
        /// The folder.
        dir: String,
        /// What is missing.
        message: String,
    },
    /// A PLY file could not be read or written.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// `run.mcap` could not be written, or a bag read.
    #[error(transparent)]
    Bag(#[from] crate::bag::BagError),
    /// A value cannot be written (an extra column of the wrong length, a
    /// name with a comma).
    #[error("{what}: {message}")]
    Invalid {
        /// What.
        what: String,
        /// What is wrong.
        message: String,
    },
}

impl RecordError {
    /// A file error from anything displayable.
    pub fn file(path: &Path, e: impl std::fmt::Display) -> Self {
        Self::File {
            file: path.display().to_string(),
            message: e.to_string(),
        }
    }

    /// A file error naming the file by text.
    pub fn named(file: &str, e: impl std::fmt::Display) -> Self {
        Self::File {
            file: file.to_owned(),
            message: e.to_string(),
        }
    }
}
