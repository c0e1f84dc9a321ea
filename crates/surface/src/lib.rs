#![doc = include_str!("../README.md")]

pub mod changelog;
pub mod config;
pub mod corner;
pub mod error;
pub mod export;
pub mod fissure;
pub mod index;
pub mod input;
pub mod invariants;
pub mod merge;
pub mod model;
pub mod overlay;
pub mod perimeter;
pub mod relations;
pub mod replay;
pub mod reposition;
pub mod segment;
pub mod share;
#[doc(hidden)]
pub mod testing;
pub mod update;

pub use changelog::{ChangeLog, Merger};
pub use config::{DEFAULT_MAX_SET_POINTS, MAX_LAMBDA_M, MIN_LAMBDA_M, MergeOrder, SurfaceConfig};
pub use error::{InvariantViolation, SurfaceError};
pub use export::{EdgeJson, ModelJson, ModelStats, SegmentJson, StatsJson, UpdateTimes};
pub use fissure::FissureType;
pub use input::{
    InitialSegments, SensorSet, read_initial_segments_json, read_initial_segments_located,
    read_sets_jsonl, read_sets_jsonl_limited,
};
pub use merge::MergeFailure;
pub use model::SurfaceModel;
pub use overlay::CombineError;
pub use replay::{Replay, ReplayError, ReplayOptions, replay};
pub use segment::{
    CornerId, Edge, EdgeKey, Node, PairId, PointSegment, Polygon, Segment, SegmentId, SegmentKind,
    Share,
};
pub use share::Concavity;
