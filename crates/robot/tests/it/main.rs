//! The robot crate's integration tests, one binary (a module per topic) so a test build links few executables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may panic

#[path = "../common/mod.rs"]
mod common;
mod errors;
mod fk;
mod fuzz;
mod jacobian;
mod nullspace;
mod reach;
mod shapes;
