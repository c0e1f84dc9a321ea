#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`range_finder`] | [`RangeFinder`], [`SensorPoint`] |
//! | [`scanner`] | [`Scanner`], [`ScannerConfig`], [`Scan`], [`ScanReturn`], [`RangeNoise`] |
//! | [`reflection`] | [`reflection::ReflectionModel`]: intensity and range bias versus incidence |
//! | [`sweep`] | [`SweepConfig`] (the tilt angles of a 3-D sweep), [`Sweep`] (its returns on the (scan, ray) grid), [`SweepBuilder`], [`beam_direction`] |
//! | [`scan_file`] | [`Sweep::read_ply`], [`Sweep::write_ply`]: the scan PLY |
//! | [`classifier`] | [`Lrc`], [`LrcConfig`], [`Observation`]: the material classifier of A App. B |

pub mod classifier;
pub mod range_finder;
pub mod reflection;
pub mod scan_file;
pub mod scanner;
pub mod sweep;

pub use classifier::{Classification, ClassifyError, Lrc, LrcConfig, LrcError, Observation};
pub use range_finder::{RangeFinder, SensorPoint};
pub use reflection::ReflectionModel;
pub use scanner::{RangeNoise, Scan, ScanReturn, Scanner, ScannerConfig};
pub use sweep::{
    GridCell, GridShape, Sweep, SweepBuilder, SweepConfig, SweepPoint, beam_direction,
};

/// Errors of sensor configuration.
#[derive(Debug, thiserror::Error)]
pub enum SensorError {
    /// A configuration field is out of its valid range.
    #[error("sensor config `{field}`: expected {expected}, got {got}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is accepted.
        expected: &'static str,
        /// What was given.
        got: String,
    },
    /// A sweep's data break its invariants (see [`Sweep`]).
    #[error("sweep: {message}")]
    Sweep {
        /// What is wrong.
        message: String,
    },
    /// A scan file is malformed.
    #[error("{path}: {message}")]
    ScanFile {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A scan file could not be read or written.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
}
