//! The cli crate's integration tests, one binary (a module per topic) so a test build links few executables.

mod bad_input;
mod commands;
mod follow;
mod plan_blast;
#[path = "../support/mod.rs"]
mod support;
