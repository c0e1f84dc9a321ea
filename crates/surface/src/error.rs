//! Typed errors: bad configuration or input ([`SurfaceError`]) and broken model
//! invariants ([`InvariantViolation`]).

use crate::segment::SegmentId;
use geom::Real;
use thiserror::Error;

/// Why a call was refused. Refused calls leave the model unchanged.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SurfaceError {
    /// A configuration field is out of range.
    #[error("surface config: `{field}` = {value} is not {expected}")]
    Config {
        /// The field's name.
        field: &'static str,
        /// Its value.
        value: Real,
        /// What was expected.
        expected: &'static str,
    },
    /// A sensor set is malformed.
    #[error("sensor set: {field}: {message}")]
    SensorSet {
        /// The offending field, with an index where there is one (`points[3]`).
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A sensor set holds more points than [`SurfaceConfig::max_set_points`](crate::SurfaceConfig::max_set_points).
    #[error(
        "sensor set: points: {points} points, more than max_set_points = {limit} (an update's time grows with the set; split it into smaller sets or raise the limit)"
    )]
    SetTooLarge {
        /// Points in the set.
        points: usize,
        /// The limit.
        limit: usize,
    },
    /// An initial segment is malformed.
    #[error("initial segment: {message}")]
    InitialSegment {
        /// What is wrong with it.
        message: String,
    },
    /// An initial segment overlaps an initial segment already in the model
    /// on the same surface (see
    /// [`SurfaceModel::add_initial_segment`](crate::SurfaceModel::add_initial_segment)).
    #[error(
        "initial segment: overlaps initial segment {} over {area_m2:.3e} m² of the same surface (facing the same way, within λ of it); initial segments never merge, so that surface would be modelled twice",
        other.0
    )]
    InitialOverlap {
        /// The segment it overlaps.
        other: SegmentId,
        /// The common area, m².
        area_m2: Real,
    },
    /// A file could not be parsed.
    #[error("{source_name}:{line}: {field}: {message}")]
    Parse {
        /// Name of the input (usually its path).
        source_name: String,
        /// 1-based line number (1 for whole-document JSON errors without a line).
        line: usize,
        /// The offending field (`points`, `axes[2]`, `segments[0][1]`, or `json`).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The model has used up its id space (about 4·10⁹ segments, edges, pairs
    /// or corners over its lifetime).
    #[error("the surface model's id space is exhausted")]
    Capacity,
    /// Reading the input failed.
    #[error("{source_name}: {message}")]
    Io {
        /// Name of the input.
        source_name: String,
        /// The I/O error.
        message: String,
    },
}

/// A broken invariant of the surface model (SPEC §3.4), found by
/// [`SurfaceModel::check_invariants`](crate::SurfaceModel::check_invariants).
#[derive(Debug, Error, Clone, PartialEq, Eq)]
#[error("surface model invariant `{rule}` broken{}: {detail}", segment.map(|s| format!(" at segment {}", s.0)).unwrap_or_default())]
pub struct InvariantViolation {
    /// The segment where it was found, if any.
    pub segment: Option<SegmentId>,
    /// Short name of the rule (e.g. `simple-perimeter`, `local-ordering`).
    pub rule: &'static str,
    /// Details: indices, distances.
    pub detail: String,
}

impl InvariantViolation {
    pub(crate) fn new(segment: Option<SegmentId>, rule: &'static str, detail: String) -> Self {
        Self {
            segment,
            rule,
            detail,
        }
    }
}
