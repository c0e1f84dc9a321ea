//! The surface crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod api;
mod figures;
mod follower_sets;
mod fuzz;
mod merge_order;
mod proptests;
mod real_data;
#[path = "../support/mod.rs"]
mod support;
mod sweeps;
