#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`roadmap`] | [`Roadmap`], [`NodeId`], [`Path`], [`MotionChecker`], [`MemoChecker`] |
//! | [`safety`] | [`Safety`]: `dist(Q)` (eq. 3.5), interpolated motion checks |
//! | [`interference`] | voxel–node interference (eq. 4.13) |
//! | [`pose`] | [`PoseSelector`], [`Target`], [`view_geometry`]: Stage Two's LM (eq. 3.14–3.20) |
//! | [`contact`] | robot shapes against a triangle scene: contacts, clearance |
//! | (root) | [`CspaceModel`], [`PlanConfig`], [`PlanError`] |

pub mod clearance;
mod config;
pub mod contact;
mod error;
pub mod interference;
mod model;
pub mod pose;
pub mod roadmap;
pub mod safety;

pub use clearance::{ClearanceChecker, PointClearance};
pub use config::{MAX_CHECK_STEP_M, MAX_N_Q, MAX_NEIGHBOURS, MIN_CHECK_STEP_M, PlanConfig};
pub use error::PlanError;
pub use interference::{Interference, interfering_voxels};
pub use model::{CacheOutcome, CspaceModel, MAX_INTERFERENCE_PAIRS};
pub use pose::{
    Constraints, MAX_LM_ITERATIONS, MAX_STARTS, PlaneHit, PoseConfig, PoseEvaluation, PoseRun,
    PoseSelector, PoseSolution, PoseTermination, Target, ViewGeometry, view_geometry,
};
pub use roadmap::{
    Edge, MemoChecker, MotionChecker, NodeId, Path, Roadmap, RoadmapParts, weighted_distance,
};
pub use safety::{Safety, SafetyChecker};
