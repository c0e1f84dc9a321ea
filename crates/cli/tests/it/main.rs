//! The cli crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

mod architecture;
mod bad_input;
mod campaign;
mod commands;
mod follow;
mod plan_blast;
#[path = "../support/mod.rs"]
mod support;
