#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`range_finder`] | [`RangeFinder`], [`SensorPoint`], [`float32`] (a value as a driver's message carries it) |
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
pub use range_finder::{RangeFinder, SensorPoint, float32};
pub use reflection::ReflectionModel;
pub use scanner::{MAX_RAYS_PER_SCAN, RangeNoise, Scan, ScanReturn, Scanner, ScannerConfig};
pub use sweep::{
    GridCell, GridShape, MAX_RAYS_PER_SWEEP, MAX_SCANS_PER_SWEEP, Sweep, SweepBuilder, SweepConfig,
    SweepPoint, beam_direction,
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
    /// A field asks for more work or memory than the crate's stated budget.
    #[error(
        "sensor config `{field}` = {value} gives {count} {what}, more than the limit of {limit}"
    )]
    Budget {
        /// The field.
        field: &'static str,
        /// Its value.
        value: String,
        /// What it would cost.
        count: usize,
        /// What is counted (`rays per scan`, `scans per sweep`, ...).
        what: &'static str,
        /// The budget ([`MAX_RAYS_PER_SCAN`], [`MAX_SCANS_PER_SWEEP`], [`MAX_RAYS_PER_SWEEP`]).
        limit: usize,
    },
}
