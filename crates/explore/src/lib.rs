#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | entry points |
//! |---|---|
//! | [`setup`] | [`Setup`], [`SetupInputs`]: the robot, parameters, regions, materials, the C-space model |
//! | [`run`](mod@run) | [`run()`], [`RunOptions`], [`ExploreRun`]: both stages, the checkpoint, the map products |
//! | [`judge`] | [`Judge`], [`NoJudge`], [`SafetyTally`] |
//! | [`stage_one`] | [`StageOne`]: the decision of A§3.2 |
//! | [`gain`] | [`Gain`], [`GainKind`], [`Trace`]: how a candidate's predicted sweep is scored |
//! | [`pareto`] | the Pareto front and rank sum (eq. 3.7–3.8) |
//! | [`discs`] | [`DiscMap`]: discs, segments, material belief |
//! | [`lrc`] | [`lrc::train_lrc`], [`lrc::PatchIndex`], [`lrc::IDENTIFIED_P`]: the run's classifier and its observations |

mod config;
pub mod discs;
mod error;
pub mod gain;
pub mod judge;
pub mod lrc;
mod materials;
mod output;
pub mod pareto;
mod probe;
pub mod run;
pub mod setup;
pub mod stage_one;

pub use config::{
    ExploreConfig, MAX_ATTEMPTS, MAX_LINK_K, MAX_LOCAL_CANDIDATES, MAX_LOCAL_REACH_M,
    MAX_MOTION_POSES, MAX_VIEWPOINTS, MappingConfig, Motion, PredictionConfig, Selection,
    StageTwoChoice,
};
pub use discs::DiscMap;
pub use error::ExploreError;
pub use gain::{Gain, GainContext, GainKind, Trace};
pub use judge::{Judge, NoJudge, SafetyTally};
pub use lrc::{IDENTIFIED_P, PatchIndex, lrc_config, patch_radius_m, train_lrc};
pub use run::{ExploreRun, RunIdentity, RunOptions, run, viewpoint_seed};
pub use setup::{Setup, SetupInputs};
pub use stage_one::{Candidate, Choice, Decision, StageOne, Termination};
