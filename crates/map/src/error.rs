//! The error type of the map crate.
//!
//! One type, [`MapError`], serves every module: configuration, input data,
//! the occupancy grid, Scale-Like Discs, segmentation, the material belief
//! and their files. A message names the stage (`map`, `SLD`, `segment`,
//! `material`), the field, file, line, row or voxel at fault and what was
//! expected.

use crate::key::VoxelKey;
use geom::Real;
use std::fmt;
use std::path::PathBuf;

/// What a failed file operation was doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IoOp {
    /// Reading the file.
    Read,
    /// Creating or writing the file (or its directory).
    Write,
}

impl fmt::Display for IoOp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Read => "cannot read",
            Self::Write => "cannot write",
        })
    }
}

/// What can go wrong configuring a map, an SLD run, a segmentation or a
/// material belief, or feeding them data. Every variant names the field,
/// file, row or voxel at fault. A call that fails leaves its map as it was:
/// inputs are checked before anything is written.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// A configuration field is out of its valid range.
    #[error("{stage} config `{field}`: expected {expected}, got {got}")]
    Config {
        /// The configuration: `map` ([`crate::MapConfig`] and its parts),
        /// `SLD` ([`crate::SldConfig`]), `segment` ([`crate::SegmentConfig`])
        /// or `material` ([`crate::MaterialConfig`]).
        stage: &'static str,
        /// The field, dotted from that configuration's root
        /// (`occupancy.voxel_m`, `radius_m`).
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
    /// An input value (a point, sensor origin, reference normal, viewpoint,
    /// disc or pose) is not finite.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// `point`, `sensor origin`, `reference normal`, `viewpoint`, `disc`
        /// or `pose`.
        what: &'static str,
        /// Its index.
        index: usize,
    },
    /// A point is too far from the origin for the SLD voxel hash (±2²⁰
    /// voxels).
    #[error("point {index} is too far from the origin for voxels of {radius_m} m")]
    OutOfRange {
        /// The point.
        index: usize,
        /// The voxel size.
        radius_m: Real,
    },
    /// A point is not finite or too far from the origin for a [`VoxelKey`]
    /// (material belief).
    #[error("point ({x}, {y}, {z}) has no voxel key")]
    BadPoint {
        /// x.
        x: Real,
        /// y.
        y: Real,
        /// z.
        z: Real,
    },
    /// A per-point slice has the wrong length.
    #[error("{what}: expected {expected} entries (one per point), got {got}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Number of points.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// The poses do not match the discs one to one (segmentation).
    #[error("{poses} poses for {discs} discs: give one pose per disc")]
    PoseCount {
        /// Number of poses.
        poses: usize,
        /// Number of discs.
        discs: usize,
    },
    /// A material observation has the wrong number of entries.
    #[error("observation has {got} probabilities, expected one per material ({expected})")]
    ObservationLength {
        /// `n_t`.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// A material observation entry is negative or not finite.
    #[error("observation entry {index} is {value}: expected a finite probability ≥ 0")]
    ObservationValue {
        /// The entry.
        index: usize,
        /// Its value.
        value: Real,
    },
    /// The observation gives every material (with non-zero belief) zero
    /// likelihood: Bayes' rule is undefined. The belief is left unchanged.
    #[error("observation has zero evidence P(z) for voxel {key}")]
    NoEvidence {
        /// The voxel.
        key: VoxelKey,
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
    /// A file (or its directory) could not be read or written.
    #[error("{path}: {op}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Reading or writing.
        op: IoOp,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A file (disc CSV, poses CSV, segments JSON, point cloud) is malformed.
    #[error("{source_name}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file (or a label for in-memory text).
        source_name: String,
        /// 1-based line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
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

    /// A [`MapError::Config`] error of the map configuration
    /// ([`crate::MapConfig`]). Takes `got` by value so call sites can pass
    /// numbers and strings alike.
    pub(crate) fn config(
        field: &'static str,
        expected: &'static str,
        got: impl fmt::Display,
    ) -> Self {
        Self::stage_config("map", field, expected, got)
    }

    /// A [`MapError::Config`] error of the configuration `stage`.
    #[allow(clippy::needless_pass_by_value)]
    pub(crate) fn stage_config(
        stage: &'static str,
        field: &'static str,
        expected: &'static str,
        got: impl fmt::Display,
    ) -> Self {
        Self::Config {
            stage,
            field,
            expected,
            got: got.to_string(),
        }
    }

    /// A [`MapError::Io`] error reading `path`.
    pub(crate) fn read(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            op: IoOp::Read,
            source,
        }
    }

    /// A [`MapError::Io`] error writing `path`.
    pub(crate) fn write(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            op: IoOp::Write,
            source,
        }
    }

    /// A [`MapError::Parse`] error of `source_name` at `line`.
    pub(crate) fn parse(
        source_name: impl Into<String>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        Self::Parse {
            source_name: source_name.into(),
            line,
            message: message.into(),
        }
    }
}
