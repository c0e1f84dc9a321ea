//! The sim crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod bag;
mod bounds;
mod bridge_scan;
mod continuous;
mod follow_reach;
mod follow_rig;
mod follow_run;
mod fuzz;
mod mosd_follow;
mod mosd_scenario;
mod real_data;
mod replay;
mod scan_check;
mod surface_score;
mod ur5_cube;
