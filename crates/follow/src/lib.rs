#![doc = include_str!("../README.md")]

pub mod actuator;
mod body;
pub mod config;
pub mod episode;
pub mod error;
pub mod follower;
pub mod guard;
pub mod motion;
pub mod path;
pub mod query;
pub mod reach;

pub use config::{FollowConfig, GapTargetRule, MAX_STEP_M, Objective, SliceLineRule, SliceRule};
pub use episode::{Episode, EpisodeOptions, Judge, NoJudge, RunEnd, run_episode};
pub use error::FollowError;
pub use follower::{Follower, Mode, ModeCounts, Step, StepTimes, Termination};
pub use guard::{GuardAction, GuardCounts};
pub use motion::control_point_motion;
pub use reach::place_tool;
