//! The cli crate's long tests (run in release by `.ci/run`), one binary so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod explore;
mod over_ros2;
#[path = "../support/mod.rs"]
mod support;
