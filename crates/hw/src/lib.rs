#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | item | what |
//! |---|---|
//! | [`Arm`] | a robot that reports its joints and moves |
//! | [`LineScanner`], [`ScanReadings`] | a 2-D laser scan at the current pose |
//! | [`RangeSensors`] | single-point range finders on the robot |
//! | [`HwError`] | what hardware can refuse or fail at |
//! | [`tilt_sweep`] | nod the scanner with one joint into a [`sensor::Sweep`] |
//! | [`motion`] | [`motion::LineMotion`], [`motion::MovingScanner`], [`motion::scan_line`]: continuous motion, the scanner scanning while the arm moves, each beam placed at the pose of its moment |
//! | [`clock`] | [`clock::RobotClock`], [`clock::Timed`]: the robot clock, what a real arm's motions, scans and readings would take, split by [`clock::Activity`] |
//! | [`script`] | [`script::Recorder`] (logs what any hardware did), [`script::Tap`] (hands each event to a sink as it happens) and [`script::Replay`] (plays a log back, checking every command) |

pub mod clock;
mod error;
pub mod motion;
pub mod script;
mod sweep;
mod traits;

pub use error::HwError;
pub use sweep::{
    ScannedMotion, StepGuard, scan_motion, tilt_joint, tilt_sweep, tilt_sweep_through,
};
pub use traits::{Arm, LineScanner, RangeSensors, ScanReadings};
